/* The arm of CiA 402 drives (ls_drives.h). */
#include "ls_drives.h"

#include <stdarg.h>
#include <string.h>

#include "ls_canopen.h"
#include "ls_fmt.h"

/* ---- configuration scripts ---------------------------------------------- */

static const char k_eds[] = "the EDS";

/* Append one step; false when the script is full (init refuses then). */
static bool add(ls_co_step_t *script, size_t *n, ls_co_step_t step)
{
    if (*n >= LS_DRIVES_SCRIPT_MAX) {
        return false;
    }
    script[(*n)++] = step;
    return true;
}

#define ADD(step) ok = ok && add(script, &n, (ls_co_step_t)step)

/* Map one PDO in the order CiA 301 asks: the COB-ID invalid first (the
 * drive refuses mapping writes on a valid PDO), the transmission type,
 * sub 0 = 0, the entries, sub 0 = N, then the COB-ID valid. */
static bool map_pdo(ls_co_step_t *script, size_t *np, const ls_drive_joint_t *jc, uint16_t comm, uint16_t map,
                    uint32_t cob, const uint32_t *entries, uint8_t n_entries, bool tpdo)
{
    size_t n = *np;
    bool ok = true;
    ADD(LS_CO_WRITE(comm, LS_CO_PDO_SUB_COB_ID, 4, cob | LS_CO_COBID_INVALID));
    if (jc->write_pdo_type) {
        ADD(LS_CO_WRITE(comm, LS_CO_PDO_SUB_TYPE, 1, LS_CO_PDO_TYPE_SYNC_MIN));
    }
    if (tpdo && jc->write_tpdo_inhibit) {
        ADD(LS_CO_WRITE(comm, LS_CO_PDO_SUB_INHIBIT, 2, 0));
    }
    ADD(LS_CO_WRITE(map, 0, 1, 0));
    for (uint8_t i = 0; i < n_entries; i++) {
        ADD(LS_CO_WRITE(map, (uint8_t)(i + 1u), 4, entries[i]));
    }
    ADD(LS_CO_WRITE(map, 0, 1, n_entries));
    ADD(LS_CO_WRITE(comm, LS_CO_PDO_SUB_COB_ID, 4, cob));
    *np = n;
    return ok;
}

/* The interpolation period 0x60C2 as value x 10^index s: the drive cycle
 * in whole ms when it is one, else in 100 us or 10 us steps. */
static void interp_period(uint32_t cycle_us, uint8_t *value, int8_t *index)
{
    uint32_t v = cycle_us;
    int8_t e = -6;
    while (v % 10u == 0u && e < -3) {
        v /= 10u;
        e++;
    }
    while (v > 255u) {
        v /= 10u;
        e++;
    }
    *value = (uint8_t)v;
    *index = e;
}

/* ---- the PDO layout ----------------------------------------------------- */

static const ls_drive_obj_t *ro_obj(const ls_drive_joint_t *jc, ls_drive_ro_t ro)
{
    switch (ro) {
    case LS_DRIVE_RO_BRAKE: return &jc->brake;
    case LS_DRIVE_RO_STO: return &jc->sto;
    case LS_DRIVE_RO_TORQUE: return &jc->torque;
    case LS_DRIVE_RO_TEMPERATURE: return &jc->temperature;
    case LS_DRIVE_RO_VELOCITY: return &jc->velocity;
    case LS_DRIVE_RO_COUNT: break;
    }
    return &jc->brake;
}

const char *ls_drives_ro_name(ls_drive_ro_t ro)
{
    switch (ro) {
    case LS_DRIVE_RO_BRAKE: return "brake";
    case LS_DRIVE_RO_STO: return "safe torque off";
    case LS_DRIVE_RO_TORQUE: return "torque actual";
    case LS_DRIVE_RO_TEMPERATURE: return "temperature";
    case LS_DRIVE_RO_VELOCITY: return "velocity actual";
    case LS_DRIVE_RO_COUNT: break;
    }
    return "?";
}

static void place(ls_drive_layout_t *l, uint8_t slot, uint16_t index, uint8_t sub, uint8_t bytes)
{
    l->map[slot][l->n_map[slot]++] = LS_CO_PDO_MAP_ENTRY(index, sub, 8u * bytes);
    l->tpdo_bytes[slot] = (uint8_t)(l->tpdo_bytes[slot] + bytes);
    if (slot + 1u > l->n_tpdo) {
        l->n_tpdo = (uint8_t)(slot + 1u);
    }
}

void ls_drives_layout(const ls_drive_joint_t *jc, ls_drive_layout_t *out)
{
    memset(out, 0, sizeof *out);
    out->rpdo1_bytes = jc->map_mode ? 7u : 6u;
    place(out, 0, LS_CO_OBJ_STATUSWORD, 0, 2);
    place(out, 0, LS_CO_OBJ_POSITION_ACTUAL, 0, 4);
    if (jc->map_mode) {
        place(out, 0, LS_CO_OBJ_MODES_DISPLAY, 0, 1);
    }
    for (unsigned r = 0; r < LS_DRIVE_RO_COUNT; r++) {
        const ls_drive_obj_t *o = ro_obj(jc, (ls_drive_ro_t)r);
        if (!o->map || o->bytes == 0u || o->bytes > 4u) {
            continue;
        }
        bool placed = false;
        for (uint8_t slot = 0; slot < LS_DRIVES_TPDOS && !placed; slot++) {
            if (out->tpdo_bytes[slot] + o->bytes <= 8u && out->n_map[slot] < jc->tpdo_room[slot] &&
                out->n_map[slot] < LS_DRIVES_MAP_MAX) {
                out->ro[r].mapped = true;
                out->ro[r].slot = slot;
                out->ro[r].offset = out->tpdo_bytes[slot];
                place(out, slot, o->index, o->sub, o->bytes);
                placed = true;
            }
        }
        if (!placed) {
            out->left_out |= 1u << r;
        }
    }
}

static bool build_script(ls_drives_t *d, int j, size_t *len)
{
    const ls_drive_joint_t *jc = &d->cfg.joint[j];
    ls_drive_axis_t *a = &d->axis[j];
    ls_co_step_t *script = d->script[j];
    const uint8_t node = jc->node_id;
    size_t n = 0;
    bool ok = true;
    ADD(LS_CO_EXPECT(LS_CO_OBJ_DEVICE_TYPE, 0, LS_CO_PROFILE_DRIVE, LS_CO_DEVICE_PROFILE_MASK,
                     "device profile (bits 0-15)", "a CiA 402 drive"));
    if (jc->has_vendor) {
        ADD(LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 1, jc->vendor_id, 0, "vendor id", k_eds));
    }
    if (jc->has_product) {
        ADD(LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 2, jc->product_code, 0, "product code", k_eds));
    }
    if (jc->has_revision) {
        ls_co_step_t s = LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 3, jc->revision, 0, "revision number", k_eds);
        s.optional = true; /* firmware updates change it; the vendor and product say what the drive is */
        ok = ok && add(script, &n, s);
    }
    if (jc->write_consumer_hb) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_CONSUMER_HB, 1, 4,
                        ((uint32_t)d->cfg.master_node << 16) | (uint32_t)d->cfg.heartbeat_timeout_ms));
    }
    if (jc->write_abort_option) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_ABORT_CONNECTION, 0, 2, (uint16_t)d->cfg.abort_option));
    }
    /* Every PDO the drive has goes off first: a drive's power-on PDOs (all
     * valid on some) would otherwise add their frames to every SYNC. */
    for (uint8_t p = 0; p < LS_DRIVES_PDO_SETS; p++) {
        if (jc->rpdo_present[p]) {
            ADD(LS_CO_WRITE(LS_CO_OBJ_RPDO_COMM + p, LS_CO_PDO_SUB_COB_ID, 4,
                            LS_CO_COB_RPDO(p + 1u, node) | LS_CO_COBID_INVALID));
        }
        if (jc->tpdo_present[p]) {
            ADD(LS_CO_WRITE(LS_CO_OBJ_TPDO_COMM + p, LS_CO_PDO_SUB_COB_ID, 4,
                            LS_CO_COB_TPDO(p + 1u, node) | LS_CO_COBID_INVALID));
        }
    }
    const ls_drive_layout_t *l = &d->layout[j];
    const uint32_t rpdo1[] = { LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_CONTROLWORD, 0, 16),
                               LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32),
                               LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_MODES, 0, 8) };
    ok = ok && map_pdo(script, &n, jc, LS_CO_OBJ_RPDO_COMM, LS_CO_OBJ_RPDO_MAP, LS_CO_COB_RPDO(1, node), rpdo1,
                       jc->map_mode ? 3u : 2u, false);
    if (jc->feedforward) {
        const uint32_t rpdo2[] = { LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_VELOCITY_OFFSET, 0, 32) };
        ok = ok && map_pdo(script, &n, jc, LS_CO_OBJ_RPDO_COMM + 1u, LS_CO_OBJ_RPDO_MAP + 1u, LS_CO_COB_RPDO(2, node),
                           rpdo2, 1, false);
    }
    for (uint8_t t = 0; t < l->n_tpdo; t++) {
        ok = ok && map_pdo(script, &n, jc, (uint16_t)(LS_CO_OBJ_TPDO_COMM + t), (uint16_t)(LS_CO_OBJ_TPDO_MAP + t),
                           LS_CO_COB_TPDO(t + 1u, node), l->map[t], l->n_map[t], true);
    }
    if (jc->write_interp_period) {
        uint8_t value;
        int8_t index;
        interp_period(d->cfg.control_period_us * d->cfg.cycle_ticks, &value, &index);
        ADD(LS_CO_WRITE(LS_CO_OBJ_INTERP_PERIOD, 1, 1, value));
        ADD(LS_CO_WRITE(LS_CO_OBJ_INTERP_PERIOD, 2, 1, (uint8_t)index));
    }
    /* What the configuration sets of the drive's own supervision and
     * homing (only where the EDS lets it be written: ls_drive_setup). */
    if (jc->write_fe_window) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_FOLLOWING_WINDOW, 0, 4, jc->fe_window_counts));
    }
    if (jc->write_fe_timeout) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_FOLLOWING_TIMEOUT, 0, 2, jc->fe_timeout_ms));
    }
    if (jc->write_quick_stop) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_QUICK_STOP_OPTION, 0, 2, (uint16_t)jc->quick_stop_option));
    }
    if (jc->write_home_method) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_HOMING_METHOD, 0, 1, (uint8_t)jc->home_method));
    }
    if (jc->write_home_offset) {
        ADD(LS_CO_WRITE(LS_CO_OBJ_HOME_OFFSET, 0, 4, (uint32_t)jc->home_offset_counts));
    }
    if (jc->read_limits) {
        ADD(LS_CO_READ_INTO(LS_CO_OBJ_SW_POSITION_LIMIT, 1, &a->lim0[0]));
        ADD(LS_CO_READ_INTO(LS_CO_OBJ_SW_POSITION_LIMIT, 2, &a->lim0[1]));
    }
    /* CSP, confirmed in the display before anything enables the drive. */
    ADD(LS_CO_WRITE(LS_CO_OBJ_MODES, 0, 1, (uint8_t)LS_CO_MODE_CSP));
    ADD(LS_CO_EXPECT(LS_CO_OBJ_MODES_DISPLAY, 0, (uint32_t)LS_CO_MODE_CSP, 0xFFu, "modes of operation display",
                     "0x6060 = 8 (cyclic synchronous position)"));
    ADD(LS_CO_READ_INTO(LS_CO_OBJ_POSITION_ACTUAL, 0, &a->pos0));
    ADD(LS_CO_READ_INTO(LS_CO_OBJ_STATUSWORD, 0, &a->sw0));
    *len = n;
    return ok;
}

#undef ADD

/* ---- init and boot -------------------------------------------------------- */

static int link_send(void *ctx, const hal_can_frame_t *frame)
{
    const int r = hal_can_send((hal_can_link_t *)ctx, frame);
    return r == LS_OK ? LS_OK : LS_EAGAIN;
}

static int refuse(ls_drives_t *d, const char *text)
{
    ls_fmt_print(d->text, sizeof d->text, "%s", text);
    return LS_EINVAL;
}

int ls_drives_init(ls_drives_t *d, const ls_drives_config_t *cfg)
{
    if (d == NULL) {
        return LS_EINVAL;
    }
    memset(d, 0, sizeof *d);
    if (cfg == NULL || cfg->link == NULL) {
        return refuse(d, "drives: no configuration or no drive bus");
    }
    d->cfg = *cfg;
    if (cfg->n_joints == 0u || cfg->n_joints > HAL_ARM_MAX_JOINTS || cfg->n_joints > LS_CO_MAX_NODES) {
        return refuse(d, "drives: the number of joints is outside 1..the master's node count");
    }
    if (cfg->cycle_ticks == 0u || cfg->control_period_us == 0u || cfg->heartbeat_ms == 0u ||
        cfg->heartbeat_timeout_ms <= cfg->heartbeat_ms) {
        return refuse(d, "drives: a drive cycle, control period or heartbeat of 0, or a heartbeat time-out not "
                         "above the heartbeat");
    }
    if (d->cfg.stale_cycles == 0u) {
        d->cfg.stale_cycles = LS_DRIVES_STALE_CYCLES;
    }
    ls_co_master_config_t mc;
    memset(&mc, 0, sizeof mc);
    mc.node_id = cfg->master_node;
    mc.heartbeat_ms = cfg->heartbeat_ms;
    mc.node_count = cfg->n_joints;
    /* An enable must end within the control loop's time-out (and the host's
     * for activate): a step not followed within LS_DRIVES_STEP_TIMEOUT_MS,
     * LS_DRIVES_RESET_EDGES fault resets. */
    ls_402_config_t ac;
    ls_402_default_config(&ac, cfg->control_period_us * cfg->cycle_ticks);
    ac.step_timeout_cycles = (LS_DRIVES_STEP_TIMEOUT_MS * 1000u + cfg->control_period_us * cfg->cycle_ticks - 1u) /
                             (cfg->control_period_us * cfg->cycle_ticks);
    ac.fault_reset_edges = LS_DRIVES_RESET_EDGES;
    for (uint8_t j = 0; j < cfg->n_joints; j++) {
        const ls_drive_joint_t *jc = &cfg->joint[j];
        ls_drive_axis_t *a = &d->axis[j];
        ls_402_scale_t s;
        if (ls_402_scale_init(&s, jc->scale.counts_per_rad, jc->scale.sign, jc->scale.zero_offset_rad,
                              jc->scale.vel_counts_per_rad) != LS_OK) {
            ls_fmt_print(d->text, sizeof d->text, "joint %u: its scaling is invalid (counts_per_rad > 0, sign 1 or -1)",
                         (unsigned)j + 1u);
            return LS_EINVAL;
        }
        d->cfg.joint[j].scale = s;
        ls_drives_layout(jc, &d->layout[j]);
        (void)ls_402_init(&a->ax, &ac);
        ls_402_unwrap_reset(&a->unwrap);
        size_t len = 0;
        if (!build_script(d, (int)j, &len)) {
            ls_fmt_print(d->text, sizeof d->text, "joint %u: its configuration needs more than %u SDO steps",
                         (unsigned)j + 1u, (unsigned)LS_DRIVES_SCRIPT_MAX);
            return LS_EINVAL;
        }
        ls_co_node_config_t *nc = &mc.nodes[j];
        nc->node_id = jc->node_id;
        nc->boot_timeout_ms = cfg->boot_timeout_ms;
        nc->heartbeat_ms = cfg->heartbeat_ms;
        nc->heartbeat_timeout_ms = cfg->heartbeat_timeout_ms;
        nc->script = d->script[j];
        nc->script_len = len;
        const ls_drive_layout_t *l = &d->layout[j];
        nc->rpdo[0] = (ls_co_pdo_t){ .cob_id = (uint16_t)LS_CO_COB_RPDO(1, jc->node_id), .len = l->rpdo1_bytes };
        if (jc->feedforward) {
            nc->rpdo[1] = (ls_co_pdo_t){ .cob_id = (uint16_t)LS_CO_COB_RPDO(2, jc->node_id), .len = 4 };
        }
        for (uint8_t t = 0; t < l->n_tpdo; t++) {
            nc->tpdo[t] =
                (ls_co_pdo_t){ .cob_id = (uint16_t)LS_CO_COB_TPDO(t + 1u, jc->node_id), .len = l->tpdo_bytes[t] };
        }
    }
    if (ls_co_master_init(&d->master, &mc, link_send, cfg->link) != LS_OK) {
        ls_fmt_print(d->text, sizeof d->text, "drives: %s", ls_co_master_text(&d->master));
        return LS_EINVAL;
    }
    return LS_OK;
}

int ls_drives_boot(ls_drives_t *d, uint64_t now_us)
{
    if (d == NULL) {
        return LS_EINVAL;
    }
    d->booted = false;
    d->text[0] = '\0';
    return ls_co_master_boot(&d->master, now_us);
}

const char *ls_drives_text(const ls_drives_t *d)
{
    return d != NULL ? d->text : "";
}

static int32_t le32(const uint8_t *b)
{
    return (int32_t)((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24);
}

static void put_le16(uint8_t *b, uint16_t v)
{
    b[0] = (uint8_t)(v & 0xFFu);
    b[1] = (uint8_t)(v >> 8);
}

static void put_le32(uint8_t *b, int32_t v)
{
    const uint32_t u = (uint32_t)v;
    b[0] = (uint8_t)(u & 0xFFu);
    b[1] = (uint8_t)((u >> 8) & 0xFFu);
    b[2] = (uint8_t)((u >> 16) & 0xFFu);
    b[3] = (uint8_t)(u >> 24);
}

/* Every drive READY for the first time: take what the scripts read. */
/* A drive READY after its boot (or a reboot): take what its script read. */
static void axis_ready(ls_drives_t *d, uint8_t j)
{
    ls_drive_axis_t *a = &d->axis[j];
    a->statusword = (uint16_t)a->sw0;
    a->pos_raw = (int32_t)a->pos0;
    a->hold_raw = a->pos_raw;
    ls_402_unwrap_reset(&a->unwrap);
    a->q = ls_402_pos_rad(&d->cfg.joint[j].scale, ls_402_unwrap(&a->unwrap, a->pos_raw));
    a->qd = 0.0;
    a->fresh_seen = false;
    a->last_age = 0;
    a->ready_sync = d->master.sync_count;
    a->rebooting = false;
    /* A drive that booted starts its CiA 402 state machine anew: what the
     * stepper latched of it before (a step a dead drive did not follow)
     * would otherwise fail the enable that configured it again. */
    (void)ls_402_init(&a->ax, &a->ax.cfg);
    memset(&a->out, 0, sizeof a->out);
    /* The script confirmed CSP; a drive that booted has forgotten its homing. */
    a->mode_shown = LS_CO_MODE_CSP;
    a->mode_known = true;
    a->mode_cmd = LS_CO_MODE_CSP;
    a->home = HAL_HOME_NOT_HOMED;
    a->hm_phase = 0u;
    a->hm_sdo = 0u;
    a->hm_text[0] = '\0';
    memset(a->ro_seen, 0, sizeof a->ro_seen);
}

/* Every drive READY for the first time. */
static void booted(ls_drives_t *d)
{
    d->booted = true;
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        axis_ready(d, j);
    }
}

/* The link failed: every drive is lost until an enable finds the bus back. */
static int link_failed(ls_drives_t *d, const char *why)
{
    if (!d->link_failed) {
        /* The text goes out as a notice's datum (95 bytes, "fault=" first):
         * a by-id path would not fit, its end names the device. */
        char link[36];
        ls_fmt_name_tail(link, sizeof link, d->cfg.link->name);
        ls_fmt_print(d->text, sizeof d->text, "the drive bus %s %s: every drive is lost", link, why);
    }
    d->link_failed = true;
    ls_co_master_drop_unsent(&d->master);
    return LS_EIO;
}

int ls_drives_service(ls_drives_t *d, uint64_t now_us)
{
    if (d->link_failed) {
        return LS_EIO;
    }
    for (unsigned i = 0; i < LS_DRIVES_RX_PER_CYCLE; i++) {
        hal_can_frame_t f;
        const int r = hal_can_recv(d->cfg.link, &f);
        if (r == 1) {
            ls_co_master_on_frame(&d->master, &f, now_us);
        } else if (r == LS_EAGAIN) {
            break;
        } else {
            char why[48];
            ls_fmt_print(why, sizeof why, "failed (%s)", ls_err_name(r));
            return link_failed(d, why);
        }
    }
    /* Bus-off is a state of the controller, not an error of a call: looked
     * at now and then (hal_can_status may read sysfs). */
    if ((++d->status_tick % LS_DRIVES_BUS_CHECK_CYCLES) == 0u) {
        hal_can_status_t st;
        if (hal_can_status(d->cfg.link, &st) == LS_OK && st.state == HAL_CAN_STATE_BUS_OFF) {
            return link_failed(d, "is bus-off");
        }
    }
    ls_co_master_poll(&d->master, now_us);
    if (d->booted) {
        return 1;
    }
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        const uint8_t node = d->cfg.joint[j].node_id;
        if (ls_co_master_node_phase(&d->master, node) == LS_CO_PHASE_FAILED) {
            ls_fmt_print(d->text, sizeof d->text, "joint %u: %s", (unsigned)j + 1u,
                         ls_co_master_node_text(&d->master, node));
            return LS_EIO;
        }
    }
    if (!ls_co_master_all_ready(&d->master)) {
        return 0;
    }
    booted(d);
    return 1;
}

/* ---- the drive cycle ------------------------------------------------------- */

/* Little-endian, `bytes` (1..4) of `b`, zero-extended. */
static uint32_t get_le(const uint8_t *b, uint8_t bytes)
{
    uint32_t v = 0;
    for (uint8_t i = 0; i < bytes && i < 4u; i++) {
        v |= (uint32_t)b[i] << (8u * i);
    }
    return v;
}

/* The readouts TPDO `slot` carries, as received. */
static void take_readouts(ls_drives_t *d, uint8_t j, uint8_t slot, const uint8_t *b, size_t len)
{
    ls_drive_axis_t *a = &d->axis[j];
    const ls_drive_layout_t *l = &d->layout[j];
    for (unsigned r = 0; r < LS_DRIVE_RO_COUNT; r++) {
        const uint8_t bytes = ro_obj(&d->cfg.joint[j], (ls_drive_ro_t)r)->bytes;
        if (l->ro[r].mapped && l->ro[r].slot == slot && (size_t)l->ro[r].offset + bytes <= len) {
            a->ro_raw[r] = get_le(&b[l->ro[r].offset], bytes);
            a->ro_seen[r] = true;
        }
    }
}

/* TPDO2 (readouts only), when this SYNC's has come. */
static void take_second(ls_drives_t *d, uint8_t j)
{
    ls_drive_axis_t *a = &d->axis[j];
    uint8_t b[8];
    size_t len = 0;
    uint32_t age = 0;
    if (d->layout[j].n_tpdo < 2u ||
        ls_co_master_tpdo_get(&d->master, d->cfg.joint[j].node_id, 1, b, &len, &age) != LS_OK || age != 0u ||
        a->taken_sync2 == d->master.sync_count) {
        return;
    }
    a->taken_sync2 = d->master.sync_count;
    take_readouts(d, j, 1, b, len);
}

/* The drive's answer to the latest SYNC, taken in the control cycle it
 * arrives in (not at the next drive cycle: a drive cycle sooner). Its age
 * in SYNC periods says how stale the feedback is when it does not come. */
static void take_feedback(ls_drives_t *d, uint8_t j)
{
    ls_drive_axis_t *a = &d->axis[j];
    const uint8_t node = d->cfg.joint[j].node_id;
    uint8_t b[8];
    size_t len = 0;
    uint32_t age = 0;
    const uint32_t syncs = d->master.sync_count;
    if (ls_co_master_tpdo_get(&d->master, node, 0, b, &len, &age) != LS_OK) {
        a->last_age = syncs - a->ready_sync; /* none since the drive became READY */
        return;
    }
    a->last_age = age;
    if (age != 0u || len < 6u || (a->fresh_seen && a->taken_sync == syncs)) {
        return; /* the answer to the latest SYNC is not there yet, or already taken */
    }
    const double q_old = a->q;
    const uint32_t periods = a->fresh_seen && syncs > a->taken_sync ? syncs - a->taken_sync : 1u;
    a->statusword = (uint16_t)((uint16_t)b[0] | (uint16_t)((uint16_t)b[1] << 8));
    a->pos_raw = le32(&b[2]);
    take_readouts(d, j, 0, b, len);
    if (d->cfg.joint[j].map_mode && len >= 7u) {
        a->mode_shown = (int8_t)(b[6] < 0x80u ? (int)b[6] : (int)b[6] - 0x100);
        a->mode_known = true;
    }
    a->q = ls_402_pos_rad(&d->cfg.joint[j].scale, ls_402_unwrap(&a->unwrap, a->pos_raw));
    const double dt = (double)d->cfg.control_period_us * 1e-6 * (double)d->cfg.cycle_ticks * (double)periods;
    a->qd = a->fresh_seen ? (a->q - q_old) / dt : 0.0;
    a->fresh_seen = true;
    a->taken_sync = syncs;
    a->feedback_age = 0;
}

/* The axis's statusword was sampled after the first controlword of the
 * latest enable() took effect: one sent before a disable may still show
 * OPERATION ENABLED for a drive it has since switched off. */
static bool settled_since(uint32_t taken_sync, uint32_t since_sync)
{
    const uint32_t n = taken_sync - since_sync; /* modulo 2^32: a TPDO taken before `since` is "negative" */
    return n >= LS_DRIVES_SETTLE_SYNCS && n < 0x80000000u;
}

static bool settled_since_enable(const ls_drives_t *d, const ls_drive_axis_t *a)
{
    return settled_since(a->taken_sync, d->enable_sync);
}

/* ---- homing -------------------------------------------------------------- */

/* The phases of a homing (ls_drive_axis_t.hm_phase). */
enum {
    HM_IDLE = 0,
    HM_TO_HOMING, /* mode 6 asked, awaited in 0x6061 */
    HM_START,     /* the rising edge of controlword bit 4 goes out */
    HM_RUNNING,   /* bit 4 held; statusword bits 12 / 13 awaited */
    HM_TO_CSP,    /* homed: mode 8 asked, the target at the new actual position */
    HM_RESTORE,   /* failed: mode 8 again over SDO (without map_mode) */
};


/* A mode change over SDO (a drive whose EDS does not let 0x6060 and 0x6061
 * be mapped): write 0x6060, then read 0x6061 until it shows the mode. 1
 * when confirmed, 0 while under way, LS_EIO when the drive refused (the
 * node's text says why). One step per drive cycle, at rest. */
static int mode_by_sdo(ls_drives_t *d, uint8_t j, int8_t mode, uint64_t now_us)
{
    ls_drive_axis_t *a = &d->axis[j];
    const uint8_t node = d->cfg.joint[j].node_id;
    if (a->reading) {
        return 0; /* the error code's read has the node's SDO client */
    }
    if (a->hm_sdo == 0u) {
        const uint8_t v = (uint8_t)mode;
        if (ls_co_master_sdo_write(&d->master, node, LS_CO_OBJ_MODES, 0, &v, 1, now_us) == LS_OK) {
            a->hm_sdo = 1u;
        }
        return 0;
    }
    uint8_t b[8];
    size_t len = 0;
    const int r = ls_co_master_sdo_result(&d->master, node, b, sizeof b, &len);
    if (r == LS_EBUSY) {
        return 0;
    }
    if (r != LS_OK) {
        a->hm_sdo = 0u;
        return LS_EIO;
    }
    if (a->hm_sdo == 2u && len >= 1u) {
        a->mode_shown = (int8_t)(b[0] < 0x80u ? (int)b[0] : (int)b[0] - 0x100);
        a->mode_known = true;
        if (a->mode_shown == mode) {
            a->hm_sdo = 0u;
            return 1;
        }
    }
    a->hm_sdo = ls_co_master_sdo_read(&d->master, node, LS_CO_OBJ_MODES_DISPLAY, 0, now_us) == LS_OK ? 2u : 1u;
    return 0;
}

static void home_failed(ls_drives_t *d, uint8_t j, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void home_failed(ls_drives_t *d, uint8_t j, const char *fmt, ...)
{
    ls_drive_axis_t *a = &d->axis[j];
    char why[HAL_JOINT_TEXT_LEN];
    va_list ap;
    va_start(ap, fmt);
    (void)ls_fmt_vprint(why, sizeof why, fmt, ap);
    va_end(ap);
    ls_fmt_print(a->hm_text, sizeof a->hm_text, "homing failed: %s", why);
    a->home = HAL_HOME_FAILED;
    a->mode_cmd = LS_CO_MODE_CSP;
    a->hm_sdo = 0u;
    /* With the mode in the PDOs, RPDO1 carries CSP again from now on. */
    a->hm_phase = d->cfg.joint[j].map_mode ? HM_IDLE : HM_RESTORE;
}

/* Homed: CSP again at the new actual position. The drive's counter has a
 * new zero: the unwrapping starts over from it, and the joint holds where
 * it reads now until the loop's next set-point (which starts there). */
static void home_done(ls_drives_t *d, uint8_t j)
{
    ls_drive_axis_t *a = &d->axis[j];
    ls_402_unwrap_reset(&a->unwrap);
    a->q = ls_402_pos_rad(&d->cfg.joint[j].scale, ls_402_unwrap(&a->unwrap, a->pos_raw));
    a->qd = 0.0;
    a->hold_raw = a->pos_raw;
    a->cmd_valid = false;
    a->home = HAL_HOME_HOMED;
    a->hm_phase = HM_IDLE;
}

/* One drive cycle of a joint's homing, after its 402 step: the mode it
 * asks for (mode_cmd) and the phase. */
static void home_cycle(ls_drives_t *d, uint8_t j, uint64_t now_us)
{
    ls_drive_axis_t *a = &d->axis[j];
    const ls_drive_joint_t *jc = &d->cfg.joint[j];
    const uint8_t ph = a->hm_phase;
    if (ph == HM_IDLE) {
        return;
    }
    if (ph == HM_RESTORE) {
        const int r = mode_by_sdo(d, j, LS_CO_MODE_CSP, now_us);
        a->hm_phase = r == 0 ? HM_RESTORE : HM_IDLE; /* a refusal: the next enable finds the mode wrong and says so */
        return;
    }
    if (!d->want_enabled) {
        home_failed(d, j, "interrupted: the drives were switched off");
        return;
    }
    if (!a->out.enabled) {
        home_failed(d, j, "interrupted: the drive left OPERATION ENABLED (%s)", ls_402_state_name(a->out.state));
        return;
    }
    if (now_us > a->hm_deadline_us) {
        home_failed(d, j, "the drive did not end its homing within %u ms (statusword 0x%04X)",
                    (unsigned)LS_DRIVES_HOME_TIMEOUT_MS, (unsigned)a->statusword);
        return;
    }
    const bool settled = settled_since(a->taken_sync, a->hm_sync);
    switch (ph) {
    case HM_TO_HOMING:
        a->mode_cmd = LS_CO_MODE_HM;
        if (jc->map_mode) {
            if (a->mode_known && a->mode_shown == LS_CO_MODE_HM && settled) {
                a->hm_phase = HM_START;
            }
        } else {
            const int r = mode_by_sdo(d, j, LS_CO_MODE_HM, now_us);
            if (r < 0) {
                home_failed(d, j, "homing mode (0x6060 = 6) refused: %s",
                            ls_co_master_node_text(&d->master, jc->node_id));
            } else if (r == 1) {
                a->hm_phase = HM_START;
            }
        }
        break;
    case HM_START:
        a->hm_phase = HM_RUNNING; /* this cycle's controlword carries the edge */
        a->hm_sync = d->master.sync_count;
        break;
    case HM_RUNNING:
        if (!settled) {
            break;
        }
        if ((a->statusword & LS_CO_SW_OMS13) != 0u) {
            home_failed(d, j, "the drive reports a homing error (statusword 0x%04X, bit 13)", (unsigned)a->statusword);
        } else if ((a->statusword & (LS_CO_SW_OMS12 | LS_CO_SW_TARGET_REACHED)) ==
                   (LS_CO_SW_OMS12 | LS_CO_SW_TARGET_REACHED)) {
            a->hm_phase = HM_TO_CSP;
            a->mode_cmd = LS_CO_MODE_CSP;
            a->hm_sync = d->master.sync_count;
        }
        break;
    case HM_TO_CSP:
        if (jc->map_mode) {
            if (a->mode_known && a->mode_shown == LS_CO_MODE_CSP && settled) {
                home_done(d, j);
            }
        } else {
            const int r = mode_by_sdo(d, j, LS_CO_MODE_CSP, now_us);
            if (r < 0) {
                home_failed(d, j, "cyclic synchronous position (0x6060 = 8) refused after the homing: %s",
                            ls_co_master_node_text(&d->master, jc->node_id));
            } else if (r == 1) {
                home_done(d, j);
            }
        }
        break;
    default: break;
    }
}

/* The RPDO1 bytes of a joint: controlword, target position and, with
 * map_mode, the mode of operation. */
static size_t rpdo1(const ls_drives_t *d, uint8_t j, int32_t target, uint8_t *b)
{
    const ls_drive_axis_t *a = &d->axis[j];
    uint16_t cw = a->out.controlword;
    if ((a->hm_phase == HM_RUNNING) && a->out.state == LS_402_OPERATION_ENABLED) {
        cw |= LS_CO_CW_HOMING_START;
    }
    put_le16(b, cw);
    put_le32(&b[2], target);
    b[6] = (uint8_t)a->mode_cmd;
    return d->layout[j].rpdo1_bytes;
}

static void publish_readouts(ls_drives_t *d, uint64_t now_us);

static void drive_cycle(ls_drives_t *d, uint64_t now_us)
{
    const ls_402_want_t want = d->want_enabled ? LS_402_WANT_ENABLED : LS_402_WANT_DISABLED;
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        ls_drive_axis_t *a = &d->axis[j];
        const ls_drive_joint_t *jc = &d->cfg.joint[j];
        if (ls_co_master_node_phase(&d->master, jc->node_id) != LS_CO_PHASE_READY) {
            continue;
        }
        /* An enable steps on statuswords the drive sampled after it: an
         * older one may still show the state a disable since left (the
         * controlword of the disable goes on meanwhile). A disable steps at
         * once: set-points stop being followed at once. */
        if (want != LS_402_WANT_ENABLED || settled_since_enable(d, a)) {
            (void)ls_402_step(&a->ax, a->statusword, want, d->reset_allowed, &a->out);
            a->step_epoch = d->enable_epoch;
        }
        home_cycle(d, j, now_us);
        /* Target = actual until the drive is under control, then held
         * there until the loop gives set-points: no axis jumps. Disabled
         * (or being disabled) it is the actual position again, so the next
         * enable holds where the joint is then, not where an earlier enable
         * found it. While it homes the drive ignores the target; it stays at
         * the actual position, so CSP takes over from there. */
        int32_t target = a->pos_raw;
        if (a->hm_phase != HM_IDLE) {
            a->hold_raw = a->pos_raw;
        } else if (d->want_enabled && a->out.state == LS_402_OPERATION_ENABLED) {
            target = a->hold_raw;
            int32_t raw;
            if (a->cmd_valid && ls_402_target_raw(&jc->scale, &a->unwrap, a->q_cmd, &raw) == LS_OK) {
                target = raw;
            }
        } else {
            a->hold_raw = a->pos_raw;
        }
        uint8_t b[8];
        (void)ls_co_master_rpdo_set(&d->master, jc->node_id, 0, b, rpdo1(d, j, target, b));
        if (jc->feedforward) {
            int32_t v = 0;
            if (!(a->cmd_valid && a->hm_phase == HM_IDLE && a->out.state == LS_402_OPERATION_ENABLED &&
                  ls_402_vel_raw(&jc->scale, a->qd_cmd, &v) == LS_OK)) {
                v = 0;
            }
            uint8_t f[4];
            put_le32(f, v);
            (void)ls_co_master_rpdo_set(&d->master, jc->node_id, 1, f, sizeof f);
        }
    }
    /* Fault resets belong to the enable that asked for them: once every
     * drive is under control, a drive that faults stays in FAULT until the
     * next enable (nothing resumes by itself). */
    bool all_enabled = d->want_enabled;
    for (uint8_t j = 0; j < d->cfg.n_joints && all_enabled; j++) {
        all_enabled =
            d->axis[j].out.enabled && d->axis[j].step_epoch == d->enable_epoch && settled_since_enable(d, &d->axis[j]);
    }
    if (all_enabled) {
        d->reset_allowed = false;
    }
    (void)ls_co_master_sync(&d->master, now_us);
    publish_readouts(d, now_us);
}

/* ---- events -------------------------------------------------------------- */

static hal_arm_event_t *push_event(ls_drives_t *d, uint8_t j)
{
    if (d->ev_count >= LS_DRIVES_EVENTS) {
        d->events_lost++; /* the first ones name the cause: keep them */
        return NULL;
    }
    hal_arm_event_t *e = &d->events[(d->ev_head + d->ev_count++) % LS_DRIVES_EVENTS];
    memset(e, 0, sizeof *e);
    e->joint = j;
    e->node = d->cfg.joint[j].node_id;
    return e;
}

static void take_emcys(ls_drives_t *d, uint8_t j)
{
    ls_drive_axis_t *a = &d->axis[j];
    ls_co_emcy_t em;
    while (ls_co_master_next_emcy(&d->master, d->cfg.joint[j].node_id, &em) == 1) {
        a->emcy_code = em.code;
        a->emcy_name = em.name;
        a->read_error_code = a->read_error_code || em.code != LS_CO_EMCY_NO_ERROR;
        hal_arm_event_t *e = push_event(d, j);
        if (e == NULL) {
            continue;
        }
        e->is_emcy = true;
        e->code = em.code;
        ls_fmt_print(e->meaning, sizeof e->meaning, "%s", em.name);
        e->reg = em.reg;
        memcpy(e->vendor, em.vendor, sizeof e->vendor);
        ls_fmt_print(e->text, sizeof e->text, "EMCY 0x%04X %s (error register 0x%02X, vendor %02X %02X %02X %02X %02X)",
                     (unsigned)em.code, em.name, (unsigned)em.reg, (unsigned)em.vendor[0], (unsigned)em.vendor[1],
                     (unsigned)em.vendor[2], (unsigned)em.vendor[3], (unsigned)em.vendor[4]);
    }
}

/* After an EMCY, once every drive is off (no SDO while they are in
 * operation): the drive's own error code, 0x603F, one node at a time. */
static void read_error_codes(ls_drives_t *d, uint64_t now_us)
{
    if (d->want_enabled) {
        return;
    }
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        ls_drive_axis_t *a = &d->axis[j];
        const uint8_t node = d->cfg.joint[j].node_id;
        if (a->reading) {
            uint8_t b[8];
            size_t len = 0;
            const int r = ls_co_master_sdo_result(&d->master, node, b, sizeof b, &len);
            if (r == LS_EBUSY) {
                return;
            }
            a->reading = false;
            hal_arm_event_t *e = push_event(d, j);
            if (e != NULL && r == LS_OK && len >= 2u) {
                e->code = (uint16_t)(b[0] | (uint16_t)(b[1] << 8));
                ls_fmt_print(e->meaning, sizeof e->meaning, "%s", ls_co_emcy_name(e->code));
                ls_fmt_print(e->text, sizeof e->text, "its error code 0x603F reads 0x%04X %s", (unsigned)e->code,
                             ls_co_emcy_name(e->code));
            } else if (e != NULL) {
                ls_fmt_print(e->text, sizeof e->text, "its error code 0x603F could not be read (%s)",
                             ls_co_master_node_text(&d->master, node));
            }
            continue;
        }
        if (a->read_error_code && a->hm_sdo == 0u && ls_co_master_node_phase(&d->master, node) == LS_CO_PHASE_READY) {
            a->read_error_code = false;
            if (ls_co_master_sdo_read(&d->master, node, LS_CO_OBJ_ERROR_CODE, 0, now_us) == LS_OK) {
                a->reading = true;
                return; /* one at a time */
            }
        }
    }
}

/* ---- the HAL arm operations ------------------------------------------------ */

static int drives_info(void *self, hal_arm_info_t *out)
{
    const ls_drives_t *d = self;
    memset(out, 0, sizeof *out);
    out->n_joints = d->cfg.n_joints;
    /* A set-point waits up to a drive cycle for its RPDO, takes effect at
     * that SYNC and is interpolated over the next drive cycle; the position
     * is sampled at the SYNC after, taken in the control cycle its TPDO
     * arrives in, and stands for a whole drive cycle until the next one:
     * three drive cycles, and two control cycles for the frames' way. */
    out->feedback_lag_cycles = (uint16_t)(3u * d->cfg.cycle_ticks + 2u);
    out->home_timeout_ms = LS_DRIVES_HOME_TIMEOUT_MS;
    return LS_OK;
}

static int drives_enable(void *self, bool on)
{
    ls_drives_t *d = self;
    /* After a failed link an enable looks again: every drive is booted anew
     * below, as the master cannot know what each did meanwhile. */
    const bool relink = on && d->link_failed;
    d->link_failed = d->link_failed && !on;
    d->want_enabled = on;
    d->reset_allowed = on;
    d->enable_epoch++; /* what the axes said before this call no longer answers it */
    d->enable_sync = d->master.sync_count;
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        ls_drive_axis_t *a = &d->axis[j];
        a->cmd_valid = false;
        /* Held from now on where the joint is now, whatever an earlier
         * enable found (an enable right after a disable may reach a drive
         * that never saw the disable, with no set-point in between). */
        a->hold_raw = a->pos_raw;
        /* A lost drive is configured again only when an enable asks for it:
         * nothing comes back by itself. Any phase but READY starts over (a
         * boot an earlier enable began may have reset the drive unheard). */
        const uint8_t node = d->cfg.joint[j].node_id;
        const ls_co_phase_t phase = ls_co_master_node_phase(&d->master, node);
        /* One reset per node: a second would boot it twice, and the answer
         * to the first boot's configuration would meet the second's. */
        if (on && (relink || phase != LS_CO_PHASE_READY) &&
            ls_co_master_reboot_node(&d->master, node, d->now_us) == LS_OK) {
            a->rebooting = true;
        }
    }
    return LS_OK;
}

static int drives_command(void *self, const double *q_rad, const double *qd_rad_s)
{
    ls_drives_t *d = self;
    if (!d->want_enabled) {
        return LS_OK; /* disabled drives take no set-points */
    }
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        d->axis[j].q_cmd = q_rad[j];
        d->axis[j].qd_cmd = qd_rad_s != NULL ? qd_rad_s[j] : 0.0;
        d->axis[j].cmd_valid = true;
    }
    return LS_OK;
}

static int drives_read(void *self, double *q_rad, double *qd_rad_s)
{
    const ls_drives_t *d = self;
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        q_rad[j] = d->axis[j].q;
        qd_rad_s[j] = d->axis[j].qd;
    }
    return LS_OK;
}

static int drives_update(void *self, uint64_t now_us)
{
    ls_drives_t *d = self;
    d->now_us = now_us;
    const int r = ls_drives_service(d, now_us);
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        ls_drive_axis_t *a = &d->axis[j];
        take_emcys(d, j);
        if (a->feedback_age < UINT32_MAX) {
            a->feedback_age++;
        }
        if (r >= 0 && ls_co_master_node_phase(&d->master, d->cfg.joint[j].node_id) == LS_CO_PHASE_READY) {
            if (a->rebooting) {
                axis_ready(d, j); /* configured again: its position read anew */
            }
            take_feedback(d, j);
            take_second(d, j);
        }
    }
    if (r < 0) {
        return r;
    }
    read_error_codes(d, now_us);
    if (++d->tick >= d->cfg.cycle_ticks) {
        d->tick = 0;
        drive_cycle(d, now_us);
    }
    return LS_OK;
}

static hal_tri_t ro_tri(const ls_drives_t *d, uint8_t j, ls_drive_ro_t ro);

static int drives_status(void *self, hal_joint_status_t *out)
{
    const ls_drives_t *d = self;
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        const ls_drive_axis_t *a = &d->axis[j];
        const uint8_t node = d->cfg.joint[j].node_id;
        hal_joint_status_t *s = &out[j];
        memset(s, 0, sizeof *s);
        s->node = node;
        s->feedback_age = a->feedback_age;
        const ls_co_phase_t phase = ls_co_master_node_phase(&d->master, node);
        if (d->link_failed) {
            s->state = HAL_JOINT_LOST;
            ls_fmt_print(s->text, sizeof s->text, "%s", d->text);
        } else if (phase != LS_CO_PHASE_READY && a->rebooting && d->want_enabled && phase != LS_CO_PHASE_FAILED) {
            s->state = HAL_JOINT_ENABLING;
            ls_fmt_print(s->text, sizeof s->text, "the drive is configured again (%s)", ls_co_phase_name(phase));
        } else if (phase != LS_CO_PHASE_READY) {
            s->state = HAL_JOINT_LOST;
            const char *why = ls_co_master_node_text(&d->master, node);
            if (why[0] != '\0') {
                ls_fmt_print(s->text, sizeof s->text, "%s", why);
            } else {
                ls_fmt_print(s->text, sizeof s->text, "the drive is %s, not operational", ls_co_phase_name(phase));
            }
        } else if (a->last_age > d->cfg.stale_cycles) {
            s->state = HAL_JOINT_LOST;
            ls_fmt_print(s->text, sizeof s->text, "no feedback (TPDO1) for %u drive cycles", (unsigned)a->last_age);
        } else if (d->want_enabled && ro_tri(d, j, LS_DRIVE_RO_STO) == HAL_TRI_ON && !a->out.fault) {
            /* The drive cannot switch on while it lasts: say so at once,
             * not as a step not followed. */
            const ls_drive_obj_t *o = &d->cfg.joint[j].sto;
            s->state = HAL_JOINT_FAULT;
            ls_fmt_print(s->text, sizeof s->text, "safe torque off is active (0x%04X:%02X bit %u%s, statusword 0x%04X)",
                         (unsigned)o->index, (unsigned)o->sub, (unsigned)o->bit, o->inverted ? " clear" : "",
                         (unsigned)a->statusword);
        } else if (a->out.fault || a->out.error != LS_402_OK) {
            /* While an enable asked for it, a FAULT is being reset (the
             * stepper's edges) until it stays: only then is it one. */
            const bool resetting = d->want_enabled && d->reset_allowed && a->out.error == LS_402_OK;
            s->state = resetting ? HAL_JOINT_ENABLING : HAL_JOINT_FAULT;
            s->code = a->emcy_code;
            char fault[64] = "", why[LS_CO_TEXT_LEN] = "";
            if (a->emcy_code != 0u) {
                ls_fmt_print(fault, sizeof fault, "FAULT, EMCY 0x%04X %s", (unsigned)a->emcy_code,
                             a->emcy_name != NULL ? a->emcy_name : ls_co_emcy_name(a->emcy_code));
            } else if (a->out.fault) {
                ls_fmt_print(fault, sizeof fault, "FAULT (statusword 0x%04X)", (unsigned)a->statusword);
            }
            if (a->out.error != LS_402_OK) {
                (void)ls_402_describe(&a->out, why, sizeof why);
            }
            ls_fmt_print(s->text, sizeof s->text, "%s%s%s%s", resetting ? "resetting its " : "", fault,
                         fault[0] != '\0' && why[0] != '\0' ? ": " : "", why);
        } else if (d->want_enabled) {
            /* In CSP the drive confirms it follows (bit 12) in the mode it
             * shows; while it homes, bit 12 means attained instead. */
            const bool homing = a->hm_phase != HM_IDLE && a->hm_phase != HM_RESTORE;
            const bool csp = !a->mode_known || a->mode_shown == LS_CO_MODE_CSP;
            const bool confirmed = a->step_epoch == d->enable_epoch && settled_since_enable(d, a) && a->out.enabled &&
                                   (homing || (csp && a->hm_phase == HM_IDLE && !a->out.target_ignored));
            s->state = confirmed ? HAL_JOINT_ENABLED : HAL_JOINT_ENABLING;
            if (s->state == HAL_JOINT_ENABLING && a->out.enabled && (!csp || a->hm_phase == HM_RESTORE)) {
                ls_fmt_print(s->text, sizeof s->text,
                             "its mode of operation (0x6061) is %d, not 8 (cyclic synchronous "
                             "position) yet",
                             (int)a->mode_shown);
            } else if (s->state == HAL_JOINT_ENABLING) {
                (void)ls_402_describe(&a->out, s->text, sizeof s->text);
            }
        } else {
            s->state = HAL_JOINT_OFF;
        }
        s->home = a->home;
        s->home_required = d->cfg.joint[j].home_required;
        if (a->home == HAL_HOME_FAILED && s->text[0] == '\0') {
            ls_fmt_print(s->text, sizeof s->text, "%s", a->hm_text);
        }
    }
    return LS_OK;
}

static int drives_home(void *self, uint32_t joint_mask)
{
    ls_drives_t *d = self;
    if (joint_mask == 0u || (joint_mask >> d->cfg.n_joints) != 0u) {
        return LS_EINVAL;
    }
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        const ls_drive_axis_t *a = &d->axis[j];
        if ((joint_mask & (1u << j)) == 0u) {
            continue;
        }
        if (!d->want_enabled || !a->out.enabled || a->step_epoch != d->enable_epoch || a->hm_phase != HM_IDLE ||
            ls_co_master_node_phase(&d->master, d->cfg.joint[j].node_id) != LS_CO_PHASE_READY) {
            return LS_EBUSY;
        }
    }
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        ls_drive_axis_t *a = &d->axis[j];
        if ((joint_mask & (1u << j)) == 0u) {
            continue;
        }
        a->hm_text[0] = '\0';
        if (!d->cfg.joint[j].can_home) {
            home_failed(d, j, "the drive offers no homing mode (0x6502 bit 5 clear)");
            a->hm_phase = HM_IDLE;
            continue;
        }
        a->home = HAL_HOME_HOMING;
        a->hm_phase = HM_TO_HOMING;
        a->hm_sdo = 0u;
        a->hm_sync = d->master.sync_count;
        a->hm_deadline_us = d->now_us + (uint64_t)LS_DRIVES_HOME_TIMEOUT_MS * 1000u;
    }
    return LS_OK;
}

/* ---- readouts ------------------------------------------------------------- */

static hal_tri_t ro_tri(const ls_drives_t *d, uint8_t j, ls_drive_ro_t ro)
{
    const ls_drive_axis_t *a = &d->axis[j];
    const ls_drive_obj_t *o = ro_obj(&d->cfg.joint[j], ro);
    if (!d->layout[j].ro[ro].mapped || !a->ro_seen[ro]) {
        return HAL_TRI_UNKNOWN;
    }
    const bool set = ((a->ro_raw[ro] >> o->bit) & 1u) != 0u;
    return set != o->inverted ? HAL_TRI_ON : HAL_TRI_OFF;
}

/* A readout's raw bytes as a signed or unsigned number. */
static double ro_value(const ls_drives_t *d, uint8_t j, ls_drive_ro_t ro)
{
    const ls_drive_obj_t *o = ro_obj(&d->cfg.joint[j], ro);
    const uint32_t raw = d->axis[j].ro_raw[ro];
    if (!o->is_signed || o->bytes == 0u || o->bytes > 4u) {
        return (double)raw;
    }
    const uint32_t sign = 1u << (8u * o->bytes - 1u);
    const uint32_t mask = o->bytes == 4u ? UINT32_MAX : (sign << 1) - 1u;
    const uint32_t v = raw & mask;
    return (v & sign) != 0u ? -(double)((~v & mask) + 1u) : (double)v;
}

static void publish_readouts(ls_drives_t *d, uint64_t now_us)
{
    hal_arm_readout_t *r = &d->ro_build;
    memset(r, 0, sizeof *r); /* padding too: the seqlock copies raw words */
    r->t_us = now_us != 0u ? now_us : 1u;
    r->n_joints = d->cfg.n_joints;
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        const ls_drive_axis_t *a = &d->axis[j];
        const ls_drive_joint_t *jc = &d->cfg.joint[j];
        const ls_drive_layout_t *l = &d->layout[j];
        hal_drive_readout_t *o = &r->joint[j];
        o->node = jc->node_id;
        o->statusword = a->statusword;
        o->state = ls_402_state_name(ls_402_state(a->statusword));
        o->mode = a->mode_known ? a->mode_shown : 0;
        o->last_error = a->emcy_code;
        o->error_name = a->emcy_code == 0u ? "" : a->emcy_name != NULL ? a->emcy_name : ls_co_emcy_name(a->emcy_code);
        o->position_rad = a->q;
        o->has_velocity = l->ro[LS_DRIVE_RO_VELOCITY].mapped && a->ro_seen[LS_DRIVE_RO_VELOCITY];
        if (o->has_velocity) {
            o->velocity_rad_s = ls_402_vel_rad_s(&jc->scale, (int32_t)ro_value(d, j, LS_DRIVE_RO_VELOCITY));
        }
        o->has_torque = l->ro[LS_DRIVE_RO_TORQUE].mapped && a->ro_seen[LS_DRIVE_RO_TORQUE];
        if (o->has_torque) {
            o->torque_permille = (int16_t)ro_value(d, j, LS_DRIVE_RO_TORQUE);
        }
        o->has_temperature = l->ro[LS_DRIVE_RO_TEMPERATURE].mapped && a->ro_seen[LS_DRIVE_RO_TEMPERATURE];
        if (o->has_temperature) {
            o->temperature_c = ro_value(d, j, LS_DRIVE_RO_TEMPERATURE) * jc->temperature_scale;
        }
        o->brake = ro_tri(d, j, LS_DRIVE_RO_BRAKE);
        o->sto = ro_tri(d, j, LS_DRIVE_RO_STO);
        o->home = a->home;
        o->home_required = jc->home_required;
        o->feedback_age = a->feedback_age;
    }
    ls_co_counters_t c;
    (void)ls_co_master_counters(&d->master, &c);
    const struct {
        const char *name;
        uint32_t value;
    } k[] = {
        { "frames_in", c.frames_in },
        { "frames_out", c.frames_out },
        { "sync_sent", c.sync_sent },
        { "sync_deferred", c.sync_deferred },
        { "sync_overruns", c.sync_overruns },
        { "sends_refused", c.sends_refused },
        { "emcy_received", c.emcy_received },
        { "emcy_lost", c.emcy_lost },
        { "heartbeats_lost", c.heartbeats_lost },
        { "sdo_timeouts", c.sdo_timeouts },
        { "sdo_aborts_sent", c.sdo_aborts_sent },
        { "sdo_aborts_received", c.sdo_aborts_received },
        { "unexpected", c.unexpected },
        { "optional_failures", c.optional_failures },
        { "events_lost", d->events_lost },
    };
    _Static_assert(sizeof k / sizeof k[0] <= HAL_READOUT_COUNTERS, "hal_arm_readout_t holds every counter");
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        r->counter[i].name = k[i].name;
        r->counter[i].value = k[i].value;
    }
    r->n_counters = (uint8_t)(sizeof k / sizeof k[0]);
    ls_seqlock_write(&d->ro_seq, d->ro_words, LS_SEQLOCK_WORDS(sizeof *r), r, sizeof *r);
}

static int drives_readout(void *self, hal_arm_readout_t *out)
{
    ls_drives_t *d = self;
    hal_arm_readout_t r;
    if (ls_seqlock_read(&d->ro_seq, d->ro_words, LS_SEQLOCK_WORDS(sizeof r), &r, sizeof r, LS_DRIVES_READOUT_TRIES)) {
        d->ro_last = r;
        *out = r;
        return LS_OK;
    }
    *out = d->ro_last;
    return LS_EAGAIN;
}

int ls_drives_check_limits(const ls_drives_t *d, const double *q_min_rad, const double *q_max_rad, char *msg,
                           size_t msglen)
{
    if (d == NULL || q_min_rad == NULL || q_max_rad == NULL || msg == NULL) {
        return LS_EINVAL;
    }
    msg[0] = '\0';
    for (uint8_t j = 0; j < d->cfg.n_joints; j++) {
        const ls_drive_joint_t *jc = &d->cfg.joint[j];
        const int32_t lo = (int32_t)d->axis[j].lim0[0], hi = (int32_t)d->axis[j].lim0[1];
        if (!jc->read_limits || lo >= hi) {
            continue; /* the drive enforces none */
        }
        double a = ls_402_pos_rad(&jc->scale, lo), b = ls_402_pos_rad(&jc->scale, hi);
        if (a > b) {
            const double t = a;
            a = b;
            b = t;
        }
        const double count_rad = 1.0 / jc->scale.counts_per_rad;
        if (a > q_min_rad[j] + count_rad || b < q_max_rad[j] - count_rad) {
            ls_fmt_print(msg, msglen,
                         "joint %u (node 0x%02X): the drive's software position limits 0x607D = %ld..%ld counts "
                         "(%.4f..%.4f rad) do not contain the robot model's %.4f..%.4f rad: widen the drive's "
                         "limits, or check counts_per_rad, sign and offset_rad",
                         (unsigned)j + 1u, (unsigned)jc->node_id, (long)lo, (long)hi, a, b, q_min_rad[j], q_max_rad[j]);
            return LS_ERANGE;
        }
    }
    return LS_OK;
}

static int drives_next_event(void *self, hal_arm_event_t *out)
{
    ls_drives_t *d = self;
    if (d->ev_count == 0u) {
        return 0;
    }
    *out = d->events[d->ev_head];
    d->ev_head = (d->ev_head + 1u) % LS_DRIVES_EVENTS;
    d->ev_count--;
    return 1;
}

static void drives_close(void *self)
{
    (void)self; /* the link is the caller's */
}

static const hal_arm_ops_t k_ops = {
    .info = drives_info,
    .enable = drives_enable,
    .command = drives_command,
    .read = drives_read,
    .close = drives_close,
    .status = drives_status,
    .update = drives_update,
    .next_event = drives_next_event,
    .home = drives_home,
    .readout = drives_readout,
};

void ls_drives_arm(ls_drives_t *d, hal_arm_t *out)
{
    memset(out, 0, sizeof *out);
    out->ops = &k_ops;
    out->self = d;
    ls_fmt_print(out->name, sizeof out->name, "cia402:%s", d->cfg.link != NULL ? d->cfg.link->name : "?");
}
