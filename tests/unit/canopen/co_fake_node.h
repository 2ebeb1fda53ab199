/* A scripted CANopen server for the master's tests: a tiny object
 * dictionary answering expedited SDO (what configuration scripts use), NMT
 * with boot-up, a heartbeat producer at the period written to its 0x1017,
 * and the CiA 301 rules of PDO remapping, strictly: a mapping entry may be
 * written only while the PDO is invalid (COB-ID bit 31) and its mapping
 * count (sub-index 0) is 0; the count only while the PDO is invalid, and
 * every counted entry must be a mappable object that fits in 64 bits; a
 * valid PDO's COB-ID may only be invalidated. Written from CiA 301, not from
 * the master's code. Header-only (static inline). */
#ifndef CO_FAKE_NODE_H
#define CO_FAKE_NODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "co_test_bus.h"

#define FAKE_OD_CAP 64u
#define FAKE_LOG_CAP 128u
#define FAKE_OUT_CAP 16u

enum { OD_RO = 1, OD_MAP = 2 };

typedef struct {
    uint16_t index;
    uint8_t sub;
    uint8_t size; /* bytes */
    uint8_t flags;
    uint32_t value;
} fake_obj_t;

typedef struct {
    uint16_t index;
    uint8_t sub;
    uint32_t value;
} fake_write_t;

typedef struct {
    uint8_t id;
    bool dead;          /* answers nothing */
    bool hb_muted;      /* sends no heartbeat (but answers SDO and boots) */
    bool ignores_start; /* stays PRE-OPERATIONAL after NMT start */
    uint8_t state;      /* LS_CO_NMT_* */
    fake_obj_t od[FAKE_OD_CAP];
    fake_obj_t stored[FAKE_OD_CAP]; /* what reset communication restores */
    size_t n_od;
    uint16_t refuse_index; /* abort writes (and reads) to this object ... */
    uint8_t refuse_sub;
    uint32_t refuse_code; /* ... with this code (0: none) */
    fake_write_t log[FAKE_LOG_CAP];
    size_t n_log;
    size_t sdo_requests;
    uint64_t hb_next_us;
    hal_can_frame_t out[FAKE_OUT_CAP]; /* frames it sent, for the test to deliver */
    size_t n_out;
} fake_t;

static inline void fake_emit(fake_t *k, hal_can_frame_t f)
{
    if (k->n_out < FAKE_OUT_CAP) {
        k->out[k->n_out++] = f;
    }
}

static inline void fake_add(fake_t *k, uint16_t index, uint8_t sub, uint8_t size, uint8_t flags, uint32_t value)
{
    fake_obj_t o = { index, sub, size, flags, value };
    k->od[k->n_od] = o;
    k->stored[k->n_od] = o;
    k->n_od++;
}

static inline fake_obj_t *fake_obj(fake_t *k, uint16_t index, uint8_t sub)
{
    for (size_t i = 0; i < k->n_od; i++) {
        if (k->od[i].index == index && k->od[i].sub == sub) {
            return &k->od[i];
        }
    }
    return NULL;
}

static inline uint32_t fake_get(fake_t *k, uint16_t index, uint8_t sub)
{
    fake_obj_t *o = fake_obj(k, index, sub);
    return o == NULL ? 0xDEADBEEFu : o->value;
}

/* A CiA 402 drive's communication and drive objects: RPDO1 and TPDO1 with
 * a default mapping, identity, the objects a CSP axis maps. */
static inline void fake_init(fake_t *k, uint8_t id)
{
    memset(k, 0, sizeof(*k));
    k->id = id;
    k->state = LS_CO_NMT_PREOPERATIONAL;
    fake_add(k, LS_CO_OBJ_DEVICE_TYPE, 0, 4, OD_RO, 0x00020192u);
    fake_add(k, LS_CO_OBJ_PRODUCER_HB, 0, 2, 0, 0);
    fake_add(k, LS_CO_OBJ_CONSUMER_HB, 1, 4, 0, 0);
    fake_add(k, LS_CO_OBJ_IDENTITY, 1, 4, OD_RO, 0x000000FCu);
    fake_add(k, LS_CO_OBJ_IDENTITY, 2, 4, OD_RO, 0x00030001u);
    for (uint16_t n = 0; n < 2; n++) {
        fake_add(k, (uint16_t)(LS_CO_OBJ_RPDO_COMM + n), LS_CO_PDO_SUB_COB_ID, 4, 0,
                 n == 0 ? LS_CO_COB_RPDO(1, id) : LS_CO_COBID_INVALID | LS_CO_COB_RPDO(2, id));
        fake_add(k, (uint16_t)(LS_CO_OBJ_RPDO_COMM + n), LS_CO_PDO_SUB_TYPE, 1, 0, LS_CO_PDO_TYPE_EVENT);
        fake_add(k, (uint16_t)(LS_CO_OBJ_TPDO_COMM + n), LS_CO_PDO_SUB_COB_ID, 4, 0,
                 n == 0 ? LS_CO_COB_TPDO(1, id) : LS_CO_COBID_INVALID | LS_CO_COB_TPDO(2, id));
        fake_add(k, (uint16_t)(LS_CO_OBJ_TPDO_COMM + n), LS_CO_PDO_SUB_TYPE, 1, 0, LS_CO_PDO_TYPE_EVENT);
    }
    fake_add(k, LS_CO_OBJ_RPDO_MAP, 0, 1, 0, 1);
    fake_add(k, LS_CO_OBJ_TPDO_MAP, 0, 1, 0, 1);
    for (uint8_t s = 1; s <= 4; s++) {
        fake_add(k, LS_CO_OBJ_RPDO_MAP, s, 4, 0, s == 1 ? LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_CONTROLWORD, 0, 16) : 0);
        fake_add(k, LS_CO_OBJ_TPDO_MAP, s, 4, 0, s == 1 ? LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_STATUSWORD, 0, 16) : 0);
    }
    fake_add(k, LS_CO_OBJ_CONTROLWORD, 0, 2, OD_MAP, 0);
    fake_add(k, LS_CO_OBJ_STATUSWORD, 0, 2, OD_RO | OD_MAP, 0x0250u);
    fake_add(k, LS_CO_OBJ_MODES, 0, 1, OD_MAP, 0);
    fake_add(k, LS_CO_OBJ_POSITION_ACTUAL, 0, 4, OD_RO | OD_MAP, 123456u);
    fake_add(k, LS_CO_OBJ_TARGET_POSITION, 0, 4, OD_MAP, 0);
    fake_add(k, LS_CO_OBJ_INTERP_PERIOD, 1, 1, 0, 1);
    fake_add(k, LS_CO_OBJ_INTERP_PERIOD, 2, 1, 0, 0xFDu);
    fake_add(k, 0x2000u, 0, 4, 0, 0); /* a vendor object that cannot be mapped */
}

/* The abort a write breaks the remapping rules with, 0 when it is allowed. */
static inline uint32_t fake_pdo_rule(fake_t *k, uint16_t index, uint8_t sub, uint32_t value)
{
    bool rx_map = index >= LS_CO_OBJ_RPDO_MAP && index < LS_CO_OBJ_RPDO_MAP + 2u;
    bool tx_map = index >= LS_CO_OBJ_TPDO_MAP && index < LS_CO_OBJ_TPDO_MAP + 2u;
    bool rx_comm = index >= LS_CO_OBJ_RPDO_COMM && index < LS_CO_OBJ_RPDO_COMM + 2u;
    bool tx_comm = index >= LS_CO_OBJ_TPDO_COMM && index < LS_CO_OBJ_TPDO_COMM + 2u;
    if (rx_comm || tx_comm) {
        if (sub != LS_CO_PDO_SUB_COB_ID) {
            return 0;
        }
        uint32_t now = fake_get(k, index, sub);
        bool valid_now = (now & LS_CO_COBID_INVALID) == 0u;
        bool stays_valid = (value & LS_CO_COBID_INVALID) == 0u;
        return valid_now && stays_valid && value != now ? LS_CO_ABORT_VALUE : 0u;
    }
    if (!rx_map && !tx_map) {
        return 0;
    }
    uint16_t comm = (uint16_t)(index - (rx_map ? LS_CO_OBJ_RPDO_MAP : LS_CO_OBJ_TPDO_MAP) +
                               (rx_map ? LS_CO_OBJ_RPDO_COMM : LS_CO_OBJ_TPDO_COMM));
    if ((fake_get(k, comm, LS_CO_PDO_SUB_COB_ID) & LS_CO_COBID_INVALID) == 0u) {
        return LS_CO_ABORT_ACCESS; /* the PDO is valid: its mapping is frozen */
    }
    if (sub != 0u) {
        if (fake_get(k, index, 0) != 0u) {
            return LS_CO_ABORT_ACCESS; /* entries only while the count is 0 */
        }
        fake_obj_t *o = fake_obj(k, (uint16_t)(value >> 16), (uint8_t)(value >> 8));
        return o == NULL || (o->flags & OD_MAP) == 0u || (value & 0xFFu) != 8u * o->size ? LS_CO_ABORT_NO_MAP : 0u;
    }
    if (value > 4u) {
        return LS_CO_ABORT_MAP_LEN;
    }
    uint32_t bits = 0;
    for (uint8_t s = 1; s <= value; s++) {
        bits += fake_get(k, index, s) & 0xFFu;
    }
    return bits > 64u ? LS_CO_ABORT_MAP_LEN : 0u;
}

static inline void fake_abort(fake_t *k, uint16_t index, uint8_t sub, uint32_t code)
{
    uint8_t c[4];
    le32(c, code);
    fake_emit(k, sdo_mux(LS_CO_COB_SDO_TX + k->id, LS_CO_SDO_CS_ABORT, index, sub, c));
}

static inline void fake_sdo(fake_t *k, const hal_can_frame_t *f, uint64_t now_us)
{
    k->sdo_requests++;
    uint8_t cmd = f->data[0];
    uint16_t index = (uint16_t)(f->data[1] | (f->data[2] << 8));
    uint8_t sub = f->data[3];
    fake_obj_t *o = fake_obj(k, index, sub);
    uint8_t cs = cmd & LS_CO_SDO_CS_MASK;
    if (k->refuse_code != 0u && index == k->refuse_index && sub == k->refuse_sub) {
        fake_abort(k, index, sub, k->refuse_code);
        return;
    }
    if (cs == LS_CO_SDO_CCS_UPLOAD_INITIATE) {
        if (o == NULL) {
            fake_abort(k, index, sub, LS_CO_ABORT_NO_OBJECT);
            return;
        }
        uint8_t d4[4];
        le32(d4, o->value);
        uint8_t rsp = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_INITIATE | ((4u - o->size) << LS_CO_SDO_EXP_N_SHIFT) |
                                LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE);
        fake_emit(k, sdo_mux(LS_CO_COB_SDO_TX + k->id, rsp, index, sub, d4));
        return;
    }
    if (cs != LS_CO_SDO_CCS_DOWNLOAD_INITIATE || (cmd & LS_CO_SDO_EXPEDITED) == 0u) {
        fake_abort(k, index, sub, LS_CO_ABORT_CS); /* this fake speaks expedited only */
        return;
    }
    if (o == NULL) {
        fake_abort(k, index, sub, LS_CO_ABORT_NO_OBJECT);
        return;
    }
    if ((o->flags & OD_RO) != 0u) {
        fake_abort(k, index, sub, LS_CO_ABORT_READ_ONLY);
        return;
    }
    uint8_t len = (cmd & LS_CO_SDO_SIZE) != 0u ? (uint8_t)(4u - ((cmd >> LS_CO_SDO_EXP_N_SHIFT) & 3u)) : 4u;
    if (len != o->size) {
        fake_abort(k, index, sub, len > o->size ? LS_CO_ABORT_TYPE_LEN_HIGH : LS_CO_ABORT_TYPE_LEN_LOW);
        return;
    }
    uint32_t value = 0;
    for (uint8_t i = 0; i < len; i++) {
        value |= (uint32_t)f->data[4 + i] << (8u * i);
    }
    uint32_t rule = fake_pdo_rule(k, index, sub, value);
    if (rule != 0u) {
        fake_abort(k, index, sub, rule);
        return;
    }
    o->value = value;
    if (k->n_log < FAKE_LOG_CAP) {
        fake_write_t w = { index, sub, value };
        k->log[k->n_log++] = w;
    }
    if (index == LS_CO_OBJ_PRODUCER_HB) {
        k->hb_next_us = now_us + (uint64_t)value * 1000u;
    }
    fake_emit(k, sdo_mux(LS_CO_COB_SDO_TX + k->id, LS_CO_SDO_SCS_DOWNLOAD_INITIATE, index, sub, NULL));
}

static inline void fake_boot(fake_t *k)
{
    memcpy(k->od, k->stored, sizeof(k->od)); /* communication and application alike: simple */
    k->state = LS_CO_NMT_PREOPERATIONAL;
    k->hb_next_us = 0;
    uint8_t b = LS_CO_NMT_BOOTUP;
    fake_emit(k, can_frame(LS_CO_COB_HEARTBEAT + k->id, 1, &b));
}

/* One frame on the bus, as this node sees it. */
static inline void fake_hear(fake_t *k, const hal_can_frame_t *f, uint64_t now_us)
{
    if (k->dead) {
        return;
    }
    if (f->id == LS_CO_COB_NMT && f->len == 2u && (f->data[1] == k->id || f->data[1] == LS_CO_NMT_ALL_NODES)) {
        switch (f->data[0]) {
        case LS_CO_NMT_RESET_COMM:
        case LS_CO_NMT_RESET_NODE: fake_boot(k); break;
        case LS_CO_NMT_START:
            if (!k->ignores_start) {
                k->state = LS_CO_NMT_OPERATIONAL;
            }
            break;
        case LS_CO_NMT_STOP: k->state = LS_CO_NMT_STOPPED; break;
        case LS_CO_NMT_ENTER_PREOP: k->state = LS_CO_NMT_PREOPERATIONAL; break;
        default: break;
        }
        return;
    }
    if (f->id == LS_CO_COB_SDO_RX + k->id && f->len == 8u && k->state != LS_CO_NMT_STOPPED) {
        fake_sdo(k, f, now_us);
    }
}

/* Its heartbeat when due. */
static inline void fake_tick(fake_t *k, uint64_t now_us)
{
    uint32_t period_ms = fake_get(k, LS_CO_OBJ_PRODUCER_HB, 0);
    if (k->dead || k->hb_muted || period_ms == 0u || k->hb_next_us == 0u || now_us < k->hb_next_us) {
        return;
    }
    k->hb_next_us += (uint64_t)period_ms * 1000u;
    fake_emit(k, can_frame(LS_CO_COB_HEARTBEAT + k->id, 1, &k->state));
}

#endif
