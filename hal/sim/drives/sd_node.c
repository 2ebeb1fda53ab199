/* The CiA 301 side of a simulated drive (sd_node.h): NMT slave, heartbeat
 * producer and consumer, EMCY producer, PDOs and the SDO access rules of
 * the communication profile. The SDO protocol is in sd_sdo.c, the drive
 * profile in sd_drive.c. */
#include "sd_node.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "ls_err.h"

#define MS_US 1000u
#define INHIBIT_UNIT_US 100u /* 0x1800:03 counts 100 us */

/* ---- the entries the node needs ---- */

typedef struct {
    uint16_t index;
    uint8_t sub;
    bool required;
    size_t off;
} need_t;

#define NEED(field, index, sub, required)                                                                              \
    {                                                                                                                  \
        index, sub, required, offsetof(sd_entries_t, field)                                                            \
    }

static const need_t k_needs[] = {
    NEED(cw, LS_CO_OBJ_CONTROLWORD, 0, true),
    NEED(sw, LS_CO_OBJ_STATUSWORD, 0, true),
    NEED(modes, LS_CO_OBJ_MODES, 0, true),
    NEED(modes_display, LS_CO_OBJ_MODES_DISPLAY, 0, true),
    NEED(pos_actual, LS_CO_OBJ_POSITION_ACTUAL, 0, true),
    NEED(target, LS_CO_OBJ_TARGET_POSITION, 0, true),
    NEED(error_code, LS_CO_OBJ_ERROR_CODE, 0, true),
    NEED(error_register, LS_CO_OBJ_ERROR_REGISTER, 0, true),
    NEED(supported_modes, LS_CO_OBJ_SUPPORTED_MODES, 0, true),
    NEED(sync_cobid, LS_CO_OBJ_COB_ID_SYNC, 0, true),
    NEED(emcy_cobid, LS_CO_OBJ_COB_ID_EMCY, 0, true),
    NEED(producer_hb, LS_CO_OBJ_PRODUCER_HB, 0, true),
    NEED(interp_value, LS_CO_OBJ_INTERP_PERIOD, 1, true),
    NEED(interp_index, LS_CO_OBJ_INTERP_PERIOD, 2, true),
    NEED(vendor, LS_CO_OBJ_IDENTITY, 1, true),
    NEED(product, LS_CO_OBJ_IDENTITY, 2, true),
    NEED(abort_option, LS_CO_OBJ_ABORT_CONNECTION, 0, true),
    NEED(qs_option, LS_CO_OBJ_QUICK_STOP_OPTION, 0, true),
    NEED(qs_decel, LS_CO_OBJ_QUICK_STOP_DECEL, 0, true),
    NEED(fe_window, LS_CO_OBJ_FOLLOWING_WINDOW, 0, true),
    NEED(fe_timeout, LS_CO_OBJ_FOLLOWING_TIMEOUT, 0, true),
    NEED(vel_actual, LS_CO_OBJ_VELOCITY_ACTUAL, 0, false),
    NEED(torque_actual, LS_CO_OBJ_TORQUE_ACTUAL, 0, false),
    NEED(vel_offset, LS_CO_OBJ_VELOCITY_OFFSET, 0, false),
    NEED(fe_actual, LS_CO_OBJ_FOLLOWING_ACTUAL, 0, false),
    NEED(home_offset, LS_CO_OBJ_HOME_OFFSET, 0, false),
    NEED(homing_method, LS_CO_OBJ_HOMING_METHOD, 0, false),
    NEED(sw_min, LS_CO_OBJ_SW_POSITION_LIMIT, 1, false),
    NEED(sw_max, LS_CO_OBJ_SW_POSITION_LIMIT, 2, false),
    NEED(error_behaviour, LS_CO_OBJ_ERROR_BEHAVIOUR, 1, false),
    NEED(brake, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED, false),
    NEED(sto, SD_OBJ_BRAKE_STO, SD_SUB_STO_ACTIVE, false),
    NEED(temperature, SD_OBJ_BRAKE_STO, SD_SUB_TEMPERATURE, false),
    NEED(hb_count, LS_CO_OBJ_CONSUMER_HB, 0, false),
};

static void resolve(sd_entries_t *e)
{
    for (size_t i = 0; i < sizeof k_needs / sizeof k_needs[0]; i++) {
        *(int *)((char *)e + k_needs[i].off) = sd_od_lookup(k_needs[i].index, k_needs[i].sub);
    }
}

/* The PDO objects: communication (0x1400 / 0x1800 + k) and mapping (0x1600 /
 * 0x1A00 + k) parameters, looked up by sub-index. */
static uint16_t comm_index(bool rx, unsigned k)
{
    return (uint16_t)((rx ? LS_CO_OBJ_RPDO_COMM : LS_CO_OBJ_TPDO_COMM) + k);
}

static uint16_t map_index(bool rx, unsigned k)
{
    return (uint16_t)((rx ? LS_CO_OBJ_RPDO_MAP : LS_CO_OBJ_TPDO_MAP) + k);
}

static unsigned count_pdos(bool rx)
{
    unsigned k = 0;
    while (k < LS_CO_PDO_MAX_PDOS && sd_od_lookup(comm_index(rx, k), LS_CO_PDO_SUB_COB_ID) >= 0) {
        k++;
    }
    return k;
}

int sd_node_check_od(char *msg, size_t msglen)
{
    for (size_t i = 0; i < sizeof k_needs / sizeof k_needs[0]; i++) {
        if (k_needs[i].required && sd_od_lookup(k_needs[i].index, k_needs[i].sub) < 0) {
            snprintf(msg, msglen, "the drive's EDS lacks object 0x%04X:%02X, which the simulated drive needs",
                     (unsigned)k_needs[i].index, (unsigned)k_needs[i].sub);
            return LS_EINVAL;
        }
    }
    for (int rx = 0; rx < 2; rx++) {
        unsigned n = count_pdos(rx != 0);
        if (n > SD_MAX_PDOS) {
            snprintf(msg, msglen, "the drive's EDS has %u %s; the simulated drive carries at most %u", n,
                     rx ? "RPDOs" : "TPDOs", SD_MAX_PDOS);
            return LS_EINVAL;
        }
        for (unsigned k = 0; k < n; k++) {
            if (sd_od_lookup(comm_index(rx != 0, k), LS_CO_PDO_SUB_TYPE) < 0 ||
                sd_od_lookup(map_index(rx != 0, k), 0) < 0) {
                snprintf(msg, msglen, "the drive's EDS has PDO communication object 0x%04X without its type or mapping",
                         (unsigned)comm_index(rx != 0, k));
                return LS_EINVAL;
            }
        }
    }
    int hb = sd_od_lookup(LS_CO_OBJ_CONSUMER_HB, 0);
    if (hb >= 0 && sd_od_table[hb].def > (int64_t)SD_MAX_HB_CONSUMERS) {
        snprintf(msg, msglen, "the drive's EDS has %lld consumer heartbeat entries; at most %u",
                 (long long)sd_od_table[hb].def, SD_MAX_HB_CONSUMERS);
        return LS_EINVAL;
    }
    return LS_OK;
}

/* ---- small helpers ---- */

static int64_t V(const sd_node_t *n, int entry)
{
    return entry >= 0 ? n->od.val[entry] : 0;
}

static bool can_talk(const sd_node_t *n)
{
    return n->nmt == LS_CO_NMT_PREOPERATIONAL || n->nmt == LS_CO_NMT_OPERATIONAL;
}

void sd_node_send(sd_node_t *n, uint32_t id, const uint8_t *data, uint8_t len)
{
    if (n->mis.silent || n->nmt == SD_NMT_DEAD) {
        return;
    }
    hal_can_frame_t f = { .id = id, .flags = 0, .len = len };
    if (len > 0) {
        memcpy(f.data, data, len);
    }
    n->cfg.tx(n->cfg.tx_ctx, n, &f);
}

/* ---- errors: the error register and EMCY ---- */

uint8_t sd_node_error_register(const sd_node_t *n)
{
    uint8_t r = 0u;
    r |= ls_co_error_register_bits(n->fault_code);
    if (n->hb_error || n->pdo_len_error) {
        r |= (uint8_t)(LS_CO_ERR_REG_GENERIC | LS_CO_ERR_REG_COMMUNICATION);
    }
    return r;
}

/* EMCY producer: error code, error register, five manufacturer bytes (the
 * drive's CiA 402 state, for a reader of a bus log). Sent in
 * PRE-OPERATIONAL and OPERATIONAL only, as CiA 301 allows. */
void sd_node_emcy(sd_node_t *n, uint16_t code)
{
    uint32_t cob = (uint32_t)V(n, n->e.emcy_cobid);
    if (!can_talk(n) || (cob & LS_CO_COBID_INVALID) != 0u) {
        return;
    }
    uint8_t d[LS_CO_EMCY_LEN] = {
        (uint8_t)code, (uint8_t)(code >> 8), sd_node_error_register(n), (uint8_t)n->drv.state, 0, 0, 0, 0
    };
    sd_node_send(n, cob & LS_CO_COB_MASK, d, LS_CO_EMCY_LEN);
}

/* After an error went away: "error reset" once none is left. */
void sd_node_error_cleared(sd_node_t *n)
{
    if (sd_node_error_register(n) == 0u) {
        sd_node_emcy(n, LS_CO_EMCY_NO_ERROR);
    }
}

/* ---- PDO mapping ---- */

static bool pdo_valid(const sd_node_t *n, bool rx, unsigned k, uint32_t *cob)
{
    uint32_t v = (uint32_t)V(n, sd_od_lookup(comm_index(rx, k), LS_CO_PDO_SUB_COB_ID));
    if (cob != NULL) {
        *cob = v & LS_CO_COB_MASK;
    }
    return (v & LS_CO_COBID_INVALID) == 0u;
}

static uint8_t pdo_type(const sd_node_t *n, bool rx, unsigned k)
{
    return (uint8_t)V(n, sd_od_lookup(comm_index(rx, k), LS_CO_PDO_SUB_TYPE));
}

/* Can `value` (index << 16 | sub << 8 | bits) be mapped into an RPDO (rx)
 * or a TPDO? 0 or the abort code; *entry = the object's entry. */
static uint32_t check_map_entry(bool rx, uint32_t value, int *entry)
{
    uint32_t abort = 0;
    int e = sd_od_find((uint16_t)(value >> 16), (uint8_t)(value >> 8), &abort);
    if (e < 0) {
        return abort;
    }
    const sd_od_entry_t *o = &sd_od_table[e];
    bool dir_ok = rx ? (o->access == SD_OD_ACCESS_RW || o->access == SD_OD_ACCESS_RWW || o->access == SD_OD_ACCESS_WO)
                     : (o->access != SD_OD_ACCESS_WO && o->access != SD_OD_ACCESS_RWW);
    if ((o->flags & SD_OD_F_PDO) == 0u || !dir_ok || (value & 0xFFu) != sd_od_bits(e)) {
        return LS_CO_ABORT_NO_MAP;
    }
    if (entry != NULL) {
        *entry = e;
    }
    return 0;
}

/* Check entries 1..count of a mapping; fill the cache when `p` is given. */
static uint32_t check_mapping(const sd_node_t *n, bool rx, unsigned k, unsigned count, sd_pdo_t *p)
{
    unsigned bits = 0;
    for (unsigned s = 1; s <= count; s++) {
        int me = sd_od_lookup(map_index(rx, k), (uint8_t)s);
        if (me < 0) {
            return LS_CO_ABORT_VALUE_HIGH; /* more entries than the object has */
        }
        int e = -1;
        uint32_t abort = check_map_entry(rx, (uint32_t)V(n, me), &e);
        if (abort != 0u) {
            return abort;
        }
        bits += sd_od_bits(e);
        if (bits > 64u) {
            return LS_CO_ABORT_MAP_LEN;
        }
        if (p != NULL) {
            p->entry[s - 1u] = (int16_t)e;
            p->bytes[s - 1u] = (uint8_t)(sd_od_bits(e) / 8u);
        }
    }
    if (p != NULL) {
        p->n = (uint8_t)count;
        p->len = (uint8_t)(bits / 8u);
    }
    return 0;
}

/* Rebuild a PDO's cache from its mapping (at reset and after sub 0 is
 * written). A mapping the EDS defaults make invalid maps nothing. */
static void rebuild_pdo(sd_node_t *n, bool rx, unsigned k)
{
    sd_pdo_t *p = rx ? &n->rpdo[k] : &n->tpdo[k];
    memset(p, 0, sizeof *p);
    unsigned count = (unsigned)V(n, sd_od_lookup(map_index(rx, k), 0));
    if (check_mapping(n, rx, k, count, p) != 0u) {
        p->n = 0;
        p->len = 0;
    }
}

static void pack_tpdo(sd_node_t *n, const sd_pdo_t *p, uint8_t out[8])
{
    memset(out, 0, 8);
    size_t off = 0;
    for (unsigned i = 0; i < p->n; i++) {
        sd_od_pack(n->od.val[p->entry[i]], out + off, p->bytes[i]);
        off += p->bytes[i];
    }
}

static void send_tpdo(sd_node_t *n, unsigned k, const uint8_t data[8], uint64_t now_us)
{
    sd_pdo_t *p = &n->tpdo[k];
    uint32_t cob = 0;
    (void)pdo_valid(n, false, k, &cob);
    memcpy(p->last, data, 8);
    p->sent_once = true;
    p->inhibit_until_us =
        now_us + INHIBIT_UNIT_US * (uint64_t)V(n, sd_od_lookup(comm_index(false, k), LS_CO_PDO_SUB_INHIBIT));
    uint64_t timer_ms = (uint64_t)V(n, sd_od_lookup(comm_index(false, k), LS_CO_PDO_SUB_EVENT_TIMER));
    p->event_due_us = timer_ms > 0u ? now_us + timer_ms * MS_US : UINT64_MAX;
    if (!n->mis.tpdo_frozen) {
        sd_node_send(n, cob, data, p->len);
    }
}

/* Write one mapped value as an RPDO carries it: the drive's checks, then
 * the side effects of a write. A value the drive refuses is skipped. */
static void apply_value(sd_node_t *n, int e, int64_t v, uint64_t now_us);

static void apply_rpdo(sd_node_t *n, sd_pdo_t *p, uint64_t now_us)
{
    size_t off = 0;
    for (unsigned i = 0; i < p->n; i++) {
        int e = p->entry[i];
        int64_t v = sd_od_unpack(e, p->data + off);
        off += p->bytes[i];
        if (v >= sd_od_table[e].low && v <= sd_od_table[e].high && sd_drive_check(n, e, v) == 0u) {
            apply_value(n, e, v, now_us);
        }
    }
    p->pending = false;
}

static void rx_rpdo(sd_node_t *n, unsigned k, const hal_can_frame_t *f, uint64_t now_us)
{
    sd_pdo_t *p = &n->rpdo[k];
    if (f->len < p->len) {
        if (!n->pdo_len_error) {
            n->pdo_len_error = true;
            sd_node_emcy(n, LS_CO_EMCY_PDO_LENGTH);
        }
        return;
    }
    if (n->pdo_len_error) {
        n->pdo_len_error = false;
        sd_node_error_cleared(n);
    }
    memcpy(p->data, f->data, f->len);
    p->pending = true;
    uint8_t type = pdo_type(n, true, k);
    if (type > LS_CO_PDO_TYPE_SYNC_MAX) {
        apply_rpdo(n, p, now_us); /* event-driven: at once */
    }
}

/* ---- heartbeat consumer ---- */

static void load_consumers(sd_node_t *n)
{
    n->n_consumers = (uint8_t)V(n, n->e.hb_count);
    memset(n->cons, 0, sizeof n->cons);
    for (unsigned i = 0; i < n->n_consumers; i++) {
        uint32_t v = (uint32_t)V(n, sd_od_lookup(LS_CO_OBJ_CONSUMER_HB, (uint8_t)(i + 1u)));
        n->cons[i].node = (uint8_t)((v & LS_CO_HB_CONSUMER_NODE_MASK) >> LS_CO_HB_CONSUMER_NODE_SHIFT);
        n->cons[i].time_ms = v & LS_CO_HB_CONSUMER_TIME_MASK;
    }
}

static void rx_heartbeat(sd_node_t *n, uint8_t from, uint64_t now_us)
{
    for (unsigned i = 0; i < n->n_consumers; i++) {
        sd_hb_consumer_t *c = &n->cons[i];
        if (c->node != from || c->time_ms == 0u) {
            continue;
        }
        c->monitoring = true;
        c->last_us = now_us;
        if (c->timed_out) {
            c->timed_out = false;
            bool any = false;
            for (unsigned j = 0; j < n->n_consumers; j++) {
                any = any || n->cons[j].timed_out;
            }
            if (!any && n->hb_error) {
                n->hb_error = false;
                sd_node_error_cleared(n);
            }
        }
    }
}

static void set_nmt(sd_node_t *n, uint8_t state, uint64_t now_us);

/* A monitored heartbeat stopped: EMCY 0x8130, the drive's 0x6007 reaction,
 * then the NMT state 0x1029:01 asks for. Monitoring resumes with the next
 * heartbeat of that node. */
static void heartbeat_lost(sd_node_t *n, sd_hb_consumer_t *c, uint64_t now_us)
{
    c->timed_out = true;
    c->monitoring = false;
    n->hb_error = true;
    sd_drive_abort_connection(n, LS_CO_EMCY_HEARTBEAT, now_us);
    if (n->fault_code != LS_CO_EMCY_HEARTBEAT) {
        sd_node_emcy(n, LS_CO_EMCY_HEARTBEAT); /* the fault reaction sent it otherwise */
    }
    int64_t behaviour = n->e.error_behaviour >= 0 ? V(n, n->e.error_behaviour) : LS_CO_ERR_BEHAVIOUR_PREOP;
    if (behaviour == LS_CO_ERR_BEHAVIOUR_PREOP && n->nmt == LS_CO_NMT_OPERATIONAL) {
        set_nmt(n, LS_CO_NMT_PREOPERATIONAL, now_us);
    } else if (behaviour == LS_CO_ERR_BEHAVIOUR_STOPPED) {
        set_nmt(n, LS_CO_NMT_STOPPED, now_us);
    }
}

/* ---- NMT ---- */

static void set_nmt(sd_node_t *n, uint8_t state, uint64_t now_us)
{
    if (state == n->nmt) {
        return;
    }
    uint8_t was = n->nmt;
    n->nmt = state;
    for (unsigned k = 0; k < n->n_rpdo; k++) {
        n->rpdo[k].pending = false;
    }
    if (state == LS_CO_NMT_OPERATIONAL) {
        for (unsigned k = 0; k < n->n_tpdo; k++) {
            n->tpdo[k].sync_count = 0;
            n->tpdo[k].sent_once = false; /* event-driven TPDOs go out once on entry */
        }
    }
    if (state == LS_CO_NMT_STOPPED) {
        sd_sdo_reset(n);
        if (was == LS_CO_NMT_OPERATIONAL || was == LS_CO_NMT_PREOPERATIONAL) {
            sd_drive_abort_connection(n, LS_CO_EMCY_COMMUNICATION, now_us);
        }
    }
}

/* Reset communication: the communication objects to their defaults, the
 * services restarted, then boot-up (unless the node is told not to boot). */
static void reset_communication(sd_node_t *n, uint64_t now_us)
{
    sd_od_reset(&n->od, n->cfg.node_id, LS_CO_OBJ_COMM_FIRST, LS_CO_OBJ_COMM_LAST);
    sd_sdo_reset(n);
    n->n_rpdo = (uint8_t)count_pdos(true);
    n->n_tpdo = (uint8_t)count_pdos(false);
    for (unsigned k = 0; k < n->n_rpdo; k++) {
        rebuild_pdo(n, true, k);
    }
    for (unsigned k = 0; k < n->n_tpdo; k++) {
        rebuild_pdo(n, false, k);
    }
    load_consumers(n);
    n->hb_error = false;
    n->pdo_len_error = false;
    if (n->mis.no_boot) {
        n->nmt = SD_NMT_DEAD;
        return;
    }
    n->nmt = LS_CO_NMT_PREOPERATIONAL;
    uint8_t boot = LS_CO_NMT_BOOTUP;
    sd_node_send(n, LS_CO_COB_HEARTBEAT + n->cfg.node_id, &boot, 1);
    uint64_t period_ms = (uint64_t)V(n, n->e.producer_hb);
    n->hb_next_us = now_us + period_ms * MS_US;
}

/* Reset node (application): every object to its default, the drive off,
 * its faults and homing forgotten; then reset communication. */
static void reset_node(sd_node_t *n, uint64_t now_us)
{
    sd_od_reset(&n->od, n->cfg.node_id, 0u, UINT16_MAX);
    n->fault_code = LS_CO_EMCY_NO_ERROR;
    sd_drive_reset(n);
    reset_communication(n, now_us);
}

static void rx_nmt(sd_node_t *n, const hal_can_frame_t *f, uint64_t now_us)
{
    if (f->len != 2u || (f->data[1] != LS_CO_NMT_ALL_NODES && f->data[1] != n->cfg.node_id)) {
        return;
    }
    switch (f->data[0]) {
    case LS_CO_NMT_START: set_nmt(n, LS_CO_NMT_OPERATIONAL, now_us); break;
    case LS_CO_NMT_STOP: set_nmt(n, LS_CO_NMT_STOPPED, now_us); break;
    case LS_CO_NMT_ENTER_PREOP: set_nmt(n, LS_CO_NMT_PREOPERATIONAL, now_us); break;
    case LS_CO_NMT_RESET_NODE: reset_node(n, now_us); break;
    case LS_CO_NMT_RESET_COMM:
        sd_drive_abort_connection(n, LS_CO_EMCY_COMMUNICATION, now_us);
        reset_communication(n, now_us);
        break;
    default: break; /* not a command: ignored, as CiA 301 says */
    }
}

/* ---- the node ---- */

void sd_node_init(sd_node_t *n, const sd_node_config_t *cfg, const sd_joint_fb_t *fb, uint64_t now_us)
{
    memset(n, 0, sizeof *n);
    n->cfg = *cfg;
    resolve(&n->e);
    n->drv.fb = *fb;
    reset_node(n, now_us);
}

void sd_node_rx(sd_node_t *n, const hal_can_frame_t *f, uint64_t now_us)
{
    if (n->nmt == SD_NMT_DEAD || (f->flags & (HAL_CAN_F_EXT | HAL_CAN_F_RTR)) != 0u) {
        return;
    }
    if (f->id == LS_CO_COB_NMT) {
        rx_nmt(n, f, now_us);
        return;
    }
    if (f->id > LS_CO_COB_HEARTBEAT && f->id <= LS_CO_COB_HEARTBEAT + LS_CO_NODE_MAX && f->len >= 1u) {
        rx_heartbeat(n, (uint8_t)(f->id - LS_CO_COB_HEARTBEAT), now_us);
        return;
    }
    if (f->id == LS_CO_COB_SDO_RX + n->cfg.node_id) {
        if (can_talk(n)) {
            sd_sdo_rx(n, f, now_us);
        }
        return;
    }
    if (n->nmt != LS_CO_NMT_OPERATIONAL) {
        return;
    }
    for (unsigned k = 0; k < n->n_rpdo; k++) {
        uint32_t cob = 0;
        if (pdo_valid(n, true, k, &cob) && cob == f->id) {
            rx_rpdo(n, k, f, now_us);
        }
    }
}

bool sd_node_is_sync(const sd_node_t *n, const hal_can_frame_t *f)
{
    uint32_t cob = (uint32_t)V(n, n->e.sync_cobid);
    return can_talk(n) && (f->flags & (HAL_CAN_F_EXT | HAL_CAN_F_RTR)) == 0u && (cob & LS_CO_COB_MASK) == f->id;
}

void sd_node_sync(sd_node_t *n, uint64_t now_us)
{
    if (n->nmt == LS_CO_NMT_OPERATIONAL) {
        /* Inputs are sampled at the SYNC, before this period's set-points
         * take effect: the TPDO reports the joint as the SYNC found it. */
        sd_drive_refresh(n);
        for (unsigned k = 0; k < n->n_tpdo; k++) {
            uint8_t type = pdo_type(n, false, k);
            if (!pdo_valid(n, false, k, NULL) || type > LS_CO_PDO_TYPE_SYNC_MAX) {
                continue;
            }
            sd_pdo_t *p = &n->tpdo[k];
            uint8_t data[8];
            pack_tpdo(n, p, data);
            if (type == 0u) { /* acyclic synchronous: at the SYNC after a change */
                if (!p->sent_once || memcmp(data, p->last, 8) != 0) {
                    send_tpdo(n, k, data, now_us);
                }
                continue;
            }
            if (++p->sync_count >= type) {
                p->sync_count = 0;
                send_tpdo(n, k, data, now_us);
            }
        }
        for (unsigned k = 0; k < n->n_rpdo; k++) {
            if (n->rpdo[k].pending && pdo_valid(n, true, k, NULL) && pdo_type(n, true, k) <= LS_CO_PDO_TYPE_SYNC_MAX) {
                apply_rpdo(n, &n->rpdo[k], now_us);
            }
        }
    }
    sd_drive_sync(n);
}

double sd_node_period_s(const sd_node_t *n)
{
    double t = (double)V(n, n->e.interp_value);
    for (int64_t i = V(n, n->e.interp_index); i < 0; i++) {
        t /= 10.0;
    }
    for (int64_t i = V(n, n->e.interp_index); i > 0; i--) {
        t *= 10.0;
    }
    return t > 0.1 ? 0.1 : (t > 0.0 ? t : 0.001);
}

void sd_node_substep(sd_node_t *n, double dt_s, sd_joint_cmd_t *cmd)
{
    sd_drive_substep(n, dt_s, cmd);
}

void sd_node_feedback(sd_node_t *n, const sd_joint_fb_t *fb, double dt_s, uint64_t now_us)
{
    sd_drive_feedback(n, fb, dt_s, now_us);
}

void sd_node_tick(sd_node_t *n, uint64_t now_us)
{
    if (n->nmt == SD_NMT_DEAD) {
        return;
    }
    uint64_t period_ms = (uint64_t)V(n, n->e.producer_hb);
    if (period_ms > 0u && now_us >= n->hb_next_us) {
        uint8_t state = n->nmt;
        sd_node_send(n, LS_CO_COB_HEARTBEAT + n->cfg.node_id, &state, 1);
        n->hb_next_us += period_ms * MS_US;
        if (n->hb_next_us <= now_us) {
            n->hb_next_us = now_us + period_ms * MS_US; /* fell behind (a stall): no burst */
        }
    }
    for (unsigned i = 0; i < n->n_consumers; i++) {
        sd_hb_consumer_t *c = &n->cons[i];
        if (c->monitoring && c->time_ms > 0u && now_us - c->last_us > (uint64_t)c->time_ms * MS_US) {
            heartbeat_lost(n, c, now_us);
        }
    }
    sd_sdo_tick(n, now_us);
    sd_drive_tick(n, now_us);
    if (n->nmt != LS_CO_NMT_OPERATIONAL) {
        return;
    }
    bool refreshed = false;
    for (unsigned k = 0; k < n->n_tpdo; k++) {
        if (!pdo_valid(n, false, k, NULL) || pdo_type(n, false, k) < LS_CO_PDO_TYPE_EVENT_MFR) {
            continue;
        }
        if (!refreshed) {
            sd_drive_refresh(n);
            refreshed = true;
        }
        sd_pdo_t *p = &n->tpdo[k];
        uint8_t data[8];
        pack_tpdo(n, p, data);
        bool changed = !p->sent_once || memcmp(data, p->last, 8) != 0;
        if ((changed && now_us >= p->inhibit_until_us) || now_us >= p->event_due_us) {
            send_tpdo(n, k, data, now_us);
        }
    }
}

uint64_t sd_node_next_due_us(const sd_node_t *n, uint64_t now_us)
{
    if (n->nmt == SD_NMT_DEAD) {
        return UINT64_MAX;
    }
    uint64_t due = UINT64_MAX;
    if (V(n, n->e.producer_hb) > 0) {
        due = n->hb_next_us;
    }
    for (unsigned i = 0; i < n->n_consumers; i++) {
        const sd_hb_consumer_t *c = &n->cons[i];
        if (c->monitoring && c->time_ms > 0u) {
            uint64_t t = c->last_us + (uint64_t)c->time_ms * MS_US + 1u;
            due = t < due ? t : due;
        }
    }
    if (n->sdo.state != 0u && n->sdo.deadline_us < due) {
        due = n->sdo.deadline_us;
    }
    if (n->drv.state == SD_DS_FAULT_REACTION) {
        due = now_us;
    }
    if (n->nmt == LS_CO_NMT_OPERATIONAL) {
        for (unsigned k = 0; k < n->n_tpdo; k++) {
            const sd_pdo_t *p = &n->tpdo[k];
            if (pdo_valid(n, false, k, NULL) && pdo_type(n, false, k) >= LS_CO_PDO_TYPE_EVENT_MFR) {
                /* Values change only with an event (a frame, a SYNC, a
                 * command), after which the caller ticks anyway: what is
                 * due without one is the end of an inhibit time (a change
                 * may wait for it) and the event timer. */
                uint64_t t = p->inhibit_until_us > now_us ? p->inhibit_until_us : UINT64_MAX;
                t = p->event_due_us < t ? p->event_due_us : t;
                due = t < due ? t : due;
            }
        }
    }
    return due;
}

/* ---- SDO access with the profiles' rules ---- */

uint32_t sd_node_read(sd_node_t *n, int entry, uint8_t *buf, size_t cap, size_t *len, uint64_t now_us)
{
    (void)now_us;
    if (!sd_od_readable(entry)) {
        return LS_CO_ABORT_WRITE_ONLY;
    }
    sd_drive_refresh(n);
    if (n->mis.identity && (entry == n->e.vendor || entry == n->e.product)) {
        sd_od_pack((int64_t)(entry == n->e.vendor ? n->mis.vendor : n->mis.product), buf, 4);
        *len = 4;
        return 0;
    }
    return sd_od_get_bytes(&n->od, entry, buf, cap, len);
}

/* Which PDO parameter an entry is: *rx, *k and *map (mapping or
 * communication); false for any other object. */
static bool pdo_param(int entry, bool *rx, unsigned *k, bool *map)
{
    uint16_t index = sd_od_table[entry].index;
    static const struct {
        uint16_t base;
        bool rx, map;
    } k_kinds[] = {
        { LS_CO_OBJ_RPDO_COMM, true, false },
        { LS_CO_OBJ_RPDO_MAP, true, true },
        { LS_CO_OBJ_TPDO_COMM, false, false },
        { LS_CO_OBJ_TPDO_MAP, false, true },
    };
    for (size_t i = 0; i < sizeof k_kinds / sizeof k_kinds[0]; i++) {
        if (index >= k_kinds[i].base && index < k_kinds[i].base + LS_CO_PDO_MAX_PDOS) {
            *rx = k_kinds[i].rx;
            *map = k_kinds[i].map;
            *k = (unsigned)(index - k_kinds[i].base);
            return true;
        }
    }
    return false;
}

/* CiA 301's rules for PDO parameters: a valid PDO (COB-ID bit 31 clear)
 * keeps its COB-ID, type, inhibit time and mapping; a mapping is changed
 * with sub 0 = 0, then the entries, then sub 0 = N, which checks them all. */
static uint32_t check_pdo_write(const sd_node_t *n, int entry, int64_t v, bool rx, unsigned k, bool map)
{
    uint8_t sub = sd_od_table[entry].sub;
    uint32_t cur_cob = 0;
    bool valid = pdo_valid(n, rx, k, &cur_cob);
    if (map) {
        if (valid) {
            return LS_CO_ABORT_VALUE;
        }
        if (sub == 0u) {
            return check_mapping(n, rx, k, (unsigned)v, NULL);
        }
        if (V(n, sd_od_lookup(map_index(rx, k), 0)) != 0) {
            return LS_CO_ABORT_VALUE; /* sub 0 = 0 first */
        }
        if (v == 0) {
            return 0;
        }
        uint32_t abort = check_map_entry(rx, (uint32_t)v, NULL);
        if (abort == 0u && ((uint32_t)v & 0xFFu) > 64u) {
            return LS_CO_ABORT_MAP_LEN;
        }
        return abort;
    }
    uint32_t u = (uint32_t)v;
    switch (sub) {
    case LS_CO_PDO_SUB_COB_ID: {
        bool new_valid = (u & LS_CO_COBID_INVALID) == 0u;
        uint32_t id = u & LS_CO_COB_MASK;
        if ((u & (LS_CO_COBID_RESERVED | LS_CO_COBID_FRAME)) != 0u) {
            return LS_CO_ABORT_VALUE;
        }
        if (new_valid && ((valid && id != cur_cob) || id == 0u || (rx ? n->rpdo[k].n : n->tpdo[k].n) == 0u)) {
            return LS_CO_ABORT_VALUE;
        }
        return 0;
    }
    case LS_CO_PDO_SUB_TYPE:
        if (valid || (u > LS_CO_PDO_TYPE_SYNC_MAX && u < LS_CO_PDO_TYPE_EVENT_MFR)) {
            return LS_CO_ABORT_VALUE;
        }
        return 0;
    case LS_CO_PDO_SUB_INHIBIT: return valid ? LS_CO_ABORT_VALUE : 0u;
    default: return 0;
    }
}

/* 0x1016:n: node id 1..127 in bits 16-23, time in 0-15, no node watched twice. */
static uint32_t check_consumer_write(const sd_node_t *n, int entry, uint32_t v)
{
    uint32_t node = (v & LS_CO_HB_CONSUMER_NODE_MASK) >> LS_CO_HB_CONSUMER_NODE_SHIFT;
    uint32_t ms = v & LS_CO_HB_CONSUMER_TIME_MASK;
    if ((v & LS_CO_HB_CONSUMER_RESERVED) != 0u || (ms != 0u && (node < LS_CO_NODE_MIN || node > LS_CO_NODE_MAX))) {
        return LS_CO_ABORT_VALUE;
    }
    unsigned self = sd_od_table[entry].sub;
    for (unsigned i = 0; i < n->n_consumers; i++) {
        if (i + 1u != self && ms != 0u && n->cons[i].time_ms != 0u && n->cons[i].node == node) {
            return LS_CO_ABORT_PARAM_INCOMPAT;
        }
    }
    return 0;
}

static void apply_value(sd_node_t *n, int e, int64_t v, uint64_t now_us)
{
    sd_od_set(&n->od, e, v);
    if (e == n->e.cw) {
        sd_drive_controlword(n, (uint16_t)v, now_us);
    } else if (e == n->e.modes) {
        sd_drive_mode(n, (int8_t)v);
    }
}

uint32_t sd_node_write(sd_node_t *n, int entry, const uint8_t *buf, size_t len, uint64_t now_us)
{
    if (!sd_od_writable(entry)) {
        return LS_CO_ABORT_READ_ONLY;
    }
    int64_t v = 0;
    uint32_t abort = sd_od_decode(entry, buf, len, &v);
    if (abort != 0u) {
        return abort;
    }
    if (!sd_od_is_number(entry)) {
        sd_od_set_string(&n->od, entry, buf, len);
        return 0;
    }
    const sd_od_entry_t *o = &sd_od_table[entry];
    bool rx = false, map = false;
    unsigned k = 0;
    if (pdo_param(entry, &rx, &k, &map)) {
        abort = check_pdo_write(n, entry, v, rx, k, map);
    } else if (entry == n->e.sync_cobid) {
        abort = ((uint32_t)v & (LS_CO_COBID_SYNC_GEN | LS_CO_COBID_FRAME | LS_CO_COBID_RESERVED)) != 0u
                    ? LS_CO_ABORT_VALUE
                    : 0u;
    } else if (o->index == LS_CO_OBJ_CONSUMER_HB && o->sub > 0u) {
        abort = check_consumer_write(n, entry, (uint32_t)v);
    } else {
        abort = sd_drive_check(n, entry, v);
    }
    if (abort != 0u) {
        return abort;
    }
    apply_value(n, entry, v, now_us);
    if (pdo_param(entry, &rx, &k, &map)) {
        if (map && o->sub == 0u) {
            rebuild_pdo(n, rx, k);
        } else if (!map && o->sub == LS_CO_PDO_SUB_COB_ID) {
            sd_pdo_t *p = rx ? &n->rpdo[k] : &n->tpdo[k];
            p->pending = false;
            p->sent_once = false;
            p->sync_count = 0;
        }
    } else if (entry == n->e.producer_hb) {
        n->hb_next_us = now_us + (uint64_t)v * MS_US;
    } else if (o->index == LS_CO_OBJ_CONSUMER_HB && o->sub > 0u) {
        load_consumers(n);
    }
    return 0;
}

/* ---- inputs from the control socket and the link ---- */

void sd_node_inject_emcy(sd_node_t *n, uint16_t code, uint64_t now_us)
{
    sd_drive_fault(n, code, now_us);
}

void sd_node_set_sto(sd_node_t *n, bool active, uint64_t now_us)
{
    sd_drive_set_sto(n, active, now_us);
}

void sd_node_bus_off(sd_node_t *n, uint64_t now_us)
{
    if (n->nmt != SD_NMT_DEAD) {
        sd_drive_abort_connection(n, LS_CO_EMCY_BUS_OFF_RECOVERED, now_us);
    }
}

/* The EMCY that could not go out while the bus was off (the fault's, when
 * 0x6007 made one of it). */
void sd_node_bus_recovered(sd_node_t *n, uint64_t now_us)
{
    (void)now_us;
    sd_node_emcy(n, LS_CO_EMCY_BUS_OFF_RECOVERED);
}

void sd_node_behave(sd_node_t *n, uint64_t now_us)
{
    memset(&n->mis, 0, sizeof n->mis);
    if (n->nmt == SD_NMT_DEAD) {
        reset_communication(n, now_us);
    }
}
