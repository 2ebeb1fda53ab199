/* libFuzzer target for the CANopen master (firmware/canopen): arbitrary
 * frames and time steps into a master with four nodes whose scripts use
 * every step kind (numbers, a segmented byte string, expect, read-into,
 * optional), so that nodes pass through every phase.
 *
 * The input is a sequence of records, each starting with an op byte:
 *   op & 7 == 0  a frame: node byte (& 7: 0..3 our nodes, else 0x40), kind
 *                byte (SDO answer, heartbeat, EMCY, TPDO1, TPDO2, NMT,
 *                SYNC, or any 11-bit id from the next two bytes), a length
 *                byte (0..15: lengths above 8 must be ignored), the data
 *   op & 7 == 1  time: two bytes x 37 us (up to 2.4 s), then poll
 *   op & 7 == 2  one drive cycle: RPDOs set from the next byte, tpdo_get,
 *                sync
 *   op & 7 == 3  the nodes answer as a compliant server would: boot-up
 *                after a reset, the pending SDO request answered (values
 *                from the next byte), a heartbeat with their state
 *   op & 7 == 4  an NMT command of the caller: node byte, command byte
 *   op & 7 == 5  reboot a node, or a caller SDO read or write: two bytes
 *   op & 7 == 6  the CAN queue: full, room for the next byte's count, open
 *   op & 7 == 7  drain EMCY, read texts, phases and counters
 *
 * Invariants (abort on violation): every frame sent has an 11-bit id, no
 * flags and at most 8 bytes; phases are known values, texts are
 * NUL-terminated within LS_CO_TEXT_LEN; SDO buffers within bounds; EMCY
 * rings within their size; an RPDO goes out only inside a sync cycle and
 * never after its SYNC; no SDO request reaches a READY node unless the
 * caller started one on it (the master starts none by itself). */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../unit/canopen/co_test_bus.h"
#include "ls_canopen.h"
#include "ls_co_master.h"

#define N_NODES 4u
#define BASE_ID 0x21u

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct {
    bool need_bootup;
    uint8_t state;
    bool has_request; /* an SDO request awaits its answer */
    hal_can_frame_t request;
    bool caller_sdo; /* the harness started an SDO on it since its last boot */
} fz_node_t;

static ls_co_master_t m;
static fz_node_t nodes[N_NODES];
static bool q_full;
static bool q_limited;
static unsigned q_room;
static uint32_t accepted;

static uint32_t position;
static uint32_t vendor;
static const uint8_t k_name[] = "LandScape axis";
static const ls_co_step_t k_script[] = {
    LS_CO_EXPECT(LS_CO_OBJ_DEVICE_TYPE, 0, LS_CO_PROFILE_DRIVE, LS_CO_DEVICE_PROFILE_MASK, "device type", "the EDS"),
    LS_CO_READ_INTO(LS_CO_OBJ_IDENTITY, 1, &vendor),
    LS_CO_WRITE(LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_COB_ID, 4, LS_CO_COBID_INVALID),
    LS_CO_WRITE(LS_CO_OBJ_RPDO_MAP, 0, 1, 0),
    { .kind = LS_CO_STEP_WRITE, .index = 0x2008, .sub = 0, .bytes = k_name, .bytes_len = sizeof(k_name) - 1u },
    { .kind = LS_CO_STEP_WRITE, .index = LS_CO_OBJ_VELOCITY_OFFSET, .sub = 0, .size = 4, .optional = true },
    LS_CO_READ_INTO(LS_CO_OBJ_POSITION_ACTUAL, 0, &position),
    LS_CO_WRITE(LS_CO_OBJ_INTERP_PERIOD, 1, 1, 4),
};

static size_t node_index(uint32_t id)
{
    return id >= BASE_ID && id < BASE_ID + N_NODES ? id - BASE_ID : N_NODES;
}

static int fz_send(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    if (f == NULL || f->len > 8u || f->flags != 0u || f->id > LS_CO_COB_MASK) {
        abort();
    }
    if (q_full || (q_limited && q_room == 0u)) {
        return LS_EAGAIN;
    }
    if (q_limited) {
        q_room--;
    }
    accepted++;
    uint32_t fn = f->id & ~0x7Fu;
    size_t k = node_index(f->id & 0x7Fu);
    if (f->id == LS_CO_COB_NMT && f->len == 2u) {
        for (size_t i = 0; i < N_NODES; i++) {
            if (f->data[1] != LS_CO_NMT_ALL_NODES && f->data[1] != BASE_ID + i) {
                continue;
            }
            if (f->data[0] == LS_CO_NMT_RESET_COMM || f->data[0] == LS_CO_NMT_RESET_NODE) {
                nodes[i].need_bootup = true;
                nodes[i].state = LS_CO_NMT_PREOPERATIONAL;
                nodes[i].has_request = false;
            } else if (f->data[0] == LS_CO_NMT_START) {
                nodes[i].state = LS_CO_NMT_OPERATIONAL;
            } else if (f->data[0] == LS_CO_NMT_STOP) {
                nodes[i].state = LS_CO_NMT_STOPPED;
            } else if (f->data[0] == LS_CO_NMT_ENTER_PREOP) {
                nodes[i].state = LS_CO_NMT_PREOPERATIONAL;
            }
        }
    } else if (f->id == LS_CO_COB_SYNC) {
        if (!m.cycle_pending) {
            abort(); /* a SYNC outside a cycle */
        }
    } else if (fn == LS_CO_COB_SDO_RX && k < N_NODES) {
        /* The master starts no SDO on a READY node by itself. */
        if (ls_co_master_node_phase(&m, (uint8_t)f->id & 0x7Fu) == LS_CO_PHASE_READY && !nodes[k].caller_sdo) {
            abort();
        }
        nodes[k].has_request = (f->data[0] & LS_CO_SDO_CS_MASK) != LS_CO_SDO_CS_ABORT;
        nodes[k].request = *f;
    } else if (f->id >= LS_CO_PDO_COB_MIN && f->id <= LS_CO_PDO_COB_MAX) {
        if (!m.cycle_pending) {
            abort(); /* an RPDO after its SYNC or outside a cycle */
        }
    }
    return LS_OK;
}

static void check(void)
{
    if (ls_co_master_text(&m)[0] != '\0') {
        abort();
    }
    for (size_t i = 0; i < N_NODES; i++) {
        const ls_co_node_t *n = &m.nodes[i];
        if (n->phase > LS_CO_PHASE_LOST || n->emcy_count > LS_CO_EMCY_RING || n->emcy_head >= LS_CO_EMCY_RING ||
            n->sdo.len > LS_CO_SDO_BUF_LEN || n->sdo.off > n->sdo.len ||
            memchr(n->text, '\0', LS_CO_TEXT_LEN) == NULL || memchr(n->sdo.text, '\0', LS_CO_TEXT_LEN) == NULL ||
            n->step > n->cfg.script_len + 1u) {
            abort();
        }
        if (n->phase == LS_CO_PHASE_FAILED || n->phase == LS_CO_PHASE_LOST) {
            if (n->text[0] == '\0') {
                abort(); /* every failure leaves a line */
            }
        }
    }
    if (m.cycle_node > m.node_count || m.cycle_pdo > LS_CO_NODE_PDOS) {
        abort();
    }
}

static void feed(const hal_can_frame_t *f, uint64_t now_us)
{
    ls_co_master_on_frame(&m, f, now_us);
    check();
}

/* The answer a compliant server gives to the node's pending request. */
static void answer(size_t i, uint8_t v, uint64_t now_us)
{
    fz_node_t *z = &nodes[i];
    if (!z->has_request) {
        return;
    }
    z->has_request = false;
    const uint8_t *q = z->request.data;
    hal_can_frame_t f = can_frame(LS_CO_COB_SDO_TX + BASE_ID + (uint32_t)i, 8, NULL);
    memcpy(&f.data[1], &q[1], 3); /* the multiplexer */
    switch (q[0] & LS_CO_SDO_CS_MASK) {
    case LS_CO_SDO_CCS_DOWNLOAD_INITIATE: f.data[0] = LS_CO_SDO_SCS_DOWNLOAD_INITIATE; break;
    case LS_CO_SDO_CCS_DOWNLOAD_SEGMENT:
        memset(&f.data[1], 0, 3);
        f.data[0] = (uint8_t)(LS_CO_SDO_SCS_DOWNLOAD_SEGMENT | (q[0] & LS_CO_SDO_TOGGLE));
        break;
    case LS_CO_SDO_CCS_UPLOAD_INITIATE:
        if ((v & 0x80u) != 0u) { /* segmented, size indicated or not */
            f.data[0] = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_INITIATE | (v & LS_CO_SDO_SIZE));
            f.data[4] = (uint8_t)(v & 0x7Fu);
        } else {
            f.data[0] = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE |
                                  ((v & 3u) << LS_CO_SDO_EXP_N_SHIFT));
            f.data[4] = (uint8_t)(v == 0u ? LS_CO_PROFILE_DRIVE & 0xFFu : v);
            f.data[5] = (uint8_t)(v == 0u ? LS_CO_PROFILE_DRIVE >> 8 : 0u);
        }
        break;
    case LS_CO_SDO_CCS_UPLOAD_SEGMENT:
        memset(&f.data[1], v, 7);
        f.data[0] = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_SEGMENT | (q[0] & LS_CO_SDO_TOGGLE) | (v & 0x0Fu & ~0x01u) |
                              ((v & 0x40u) != 0u ? LS_CO_SDO_LAST : 0u));
        break;
    default: return;
    }
    feed(&f, now_us);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ls_co_master_config_t cfg;
    memset(&cfg, 0, sizeof(cfg));
    cfg.node_id = 0x7F;
    cfg.heartbeat_ms = 100;
    cfg.node_count = N_NODES;
    for (size_t i = 0; i < N_NODES; i++) {
        ls_co_node_config_t *nc = &cfg.nodes[i];
        /* scripts of 0, 8, 6 and 4 steps */
        co_test_node(nc, (uint8_t)(BASE_ID + i), k_script,
                     i == 0u ? 0u : sizeof(k_script) / sizeof(k_script[0]) - (i - 1u) * 2u);
        nc->boot_timeout_ms = 500;
        nc->rpdo[1].cob_id = (uint16_t)LS_CO_COB_RPDO(2, nc->node_id);
        nc->rpdo[1].len = 4;
        nc->tpdo[1].cob_id = (uint16_t)LS_CO_COB_TPDO(2, nc->node_id);
        nc->tpdo[1].len = 8;
    }
    memset(nodes, 0, sizeof(nodes));
    q_full = false;
    q_limited = false;
    accepted = 0;
    if (ls_co_master_init(&m, &cfg, fz_send, NULL) != LS_OK) {
        abort();
    }
    uint64_t now_us = 1000;
    if (ls_co_master_boot(&m, now_us) != LS_OK) {
        abort();
    }
    check();

    size_t p = 0;
    while (p < size) {
        uint8_t op = data[p++];
        switch (op & 7u) {
        case 0: {
            if (p + 3 > size) {
                return 0;
            }
            uint8_t who = data[p] & 7u;
            uint32_t id = who < N_NODES ? BASE_ID + who : 0x40u;
            uint8_t kind = data[p + 1] & 7u;
            uint8_t len = data[p + 2] & 0x0Fu;
            p += 3;
            static const uint32_t k_fn[] = { LS_CO_COB_SDO_TX, LS_CO_COB_HEARTBEAT, LS_CO_COB_EMCY, LS_CO_COB_TPDO1,
                                             LS_CO_COB_TPDO1 + 0x100u };
            hal_can_frame_t f = can_frame(0, len, NULL);
            if (kind < 5u) {
                f.id = k_fn[kind] + id;
            } else if (kind == 5u) {
                f.id = LS_CO_COB_NMT;
            } else if (kind == 6u) {
                f.id = LS_CO_COB_SYNC;
            } else {
                if (p + 2 > size) {
                    return 0;
                }
                f.id = ((uint32_t)data[p] << 8 | data[p + 1]) & 0x1FFFu; /* some beyond 11 bits */
                f.flags = (uint8_t)(data[p] >> 5) & (HAL_CAN_F_EXT | HAL_CAN_F_RTR);
                p += 2;
            }
            size_t n = len < 8u ? len : 8u;
            if (p + n > size) {
                n = size - p;
            }
            memcpy(f.data, data + p, n);
            p += n;
            feed(&f, now_us);
            break;
        }
        case 1: {
            if (p + 2 > size) {
                return 0;
            }
            now_us += ((uint64_t)data[p] << 8 | data[p + 1]) * 37u;
            p += 2;
            ls_co_master_poll(&m, now_us);
            check();
            break;
        }
        case 2: {
            uint8_t v = p < size ? data[p++] : 0u;
            for (size_t i = 0; i < N_NODES; i++) {
                uint8_t d[8] = { v, (uint8_t)i, v, v, v, v, v, v };
                uint8_t id = (uint8_t)(BASE_ID + i);
                if (ls_co_master_rpdo_set(&m, id, 0, d, 6) != LS_OK ||
                    ls_co_master_rpdo_set(&m, id, 1, d, 4) != LS_OK ||
                    ls_co_master_rpdo_set(&m, id, 0, d, 5) != LS_ELEN) {
                    abort();
                }
                uint8_t out[8];
                size_t len = 99;
                uint32_t age = 0;
                int rc = ls_co_master_tpdo_get(&m, id, (size_t)(v & 1u), out, &len, &age);
                if ((rc != LS_OK && rc != LS_EAGAIN) || (rc == LS_OK && len != ((v & 1u) ? 8u : 6u)) ||
                    (rc == LS_OK && age > m.sync_count)) {
                    abort();
                }
            }
            int rc = ls_co_master_sync(&m, now_us);
            if ((rc == LS_OK) == m.cycle_pending) {
                abort();
            }
            check();
            break;
        }
        case 3: {
            uint8_t v = p < size ? data[p++] : 0u;
            for (size_t i = 0; i < N_NODES; i++) {
                hal_can_frame_t hb = can_frame(LS_CO_COB_HEARTBEAT + BASE_ID + (uint32_t)i, 1, NULL);
                if (nodes[i].need_bootup) {
                    nodes[i].need_bootup = false;
                    hb.data[0] = LS_CO_NMT_BOOTUP;
                    feed(&hb, now_us);
                }
                answer(i, v, now_us);
                hb.data[0] = nodes[i].state;
                feed(&hb, now_us);
            }
            break;
        }
        case 4: {
            if (p + 2 > size) {
                return 0;
            }
            uint8_t who = data[p] & 7u;
            uint8_t id = who < N_NODES ? (uint8_t)(BASE_ID + who) : who == 7u ? LS_CO_NMT_ALL_NODES : 0x40u;
            uint8_t cmd = data[p + 1];
            p += 2;
            int rc = ls_co_master_nmt(&m, id, cmd, now_us);
            bool valid_cmd = cmd == LS_CO_NMT_START || cmd == LS_CO_NMT_STOP || cmd == LS_CO_NMT_ENTER_PREOP ||
                             cmd == LS_CO_NMT_RESET_NODE || cmd == LS_CO_NMT_RESET_COMM;
            if ((rc == LS_OK) != (valid_cmd && id != 0x40u)) {
                abort();
            }
            check();
            break;
        }
        case 5: {
            if (p + 2 > size) {
                return 0;
            }
            size_t i = data[p] & 3u;
            uint8_t id = (uint8_t)(BASE_ID + i);
            uint8_t what = data[p + 1];
            p += 2;
            if ((what & 3u) == 0u) {
                if (ls_co_master_reboot_node(&m, id, now_us) != LS_OK) {
                    abort();
                }
                nodes[i].caller_sdo = false;
            } else {
                uint8_t bytes[LS_CO_SDO_BUF_LEN + 1u];
                memset(bytes, what, sizeof(bytes));
                size_t len = (size_t)(what >> 2) + 1u; /* 1..64: expedited and segmented */
                ls_co_phase_t ph = ls_co_master_node_phase(&m, id);
                bool was = nodes[i].caller_sdo;
                nodes[i].caller_sdo = true; /* its request goes out inside the call */
                int rc = (what & 3u) == 1u
                             ? ls_co_master_sdo_read(&m, id, 0x1008, 0, now_us)
                             : ls_co_master_sdo_write(&m, id, 0x2000, (uint8_t)(what & 7u), bytes, len, now_us);
                if (rc == LS_OK) {
                    if (ph == LS_CO_PHASE_BOOTING || ph == LS_CO_PHASE_CONFIGURING) {
                        abort();
                    }
                } else if (rc == LS_EBUSY) {
                    nodes[i].caller_sdo = was;
                } else {
                    abort();
                }
                uint8_t out[LS_CO_SDO_BUF_LEN];
                size_t got = 0;
                rc = ls_co_master_sdo_result(&m, id, out, sizeof(out), &got);
                if (got > sizeof(out) || rc > 0) {
                    abort();
                }
            }
            check();
            break;
        }
        case 6: {
            uint8_t v = p < size ? data[p++] : 0u;
            q_full = (v & 3u) == 0u;
            q_limited = (v & 3u) == 1u;
            q_room = v >> 2;
            break;
        }
        default: {
            for (size_t i = 0; i < N_NODES; i++) {
                uint8_t id = (uint8_t)(BASE_ID + i);
                ls_co_emcy_t e;
                int rc;
                while ((rc = ls_co_master_next_emcy(&m, id, &e)) == 1) {
                    if (e.name == NULL) {
                        abort();
                    }
                }
                if (rc != 0 || ls_co_phase_name(ls_co_master_node_phase(&m, id)) == NULL) {
                    abort();
                }
            }
            ls_co_counters_t c;
            if (ls_co_master_counters(&m, &c) != LS_OK || c.frames_out != accepted || c.emcy_lost > c.emcy_received) {
                abort();
            }
            (void)ls_co_master_all_ready(&m);
            break;
        }
        }
    }
    return 0;
}
