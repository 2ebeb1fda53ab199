/* The drive arm's composition and checks (ls_drive_setup.h). */
#include "ls_drive_setup.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stdarg.h>
#include <string.h>
#include <time.h>

#include "ls_canopen.h"
#include "ls_drive_budget.h"
#include "ls_eds.h"
#include "ls_link_open.h"

/* One EDS at a time: the tables are large (ls_eds.h), and the facts the
 * drive arm needs are taken out of each file as it is read. */
static ls_eds_t g_eds;
static char g_eds_path[sizeof(((ls_config_joint_t *)0)->eds)];
static ls_drives_t g_drives;
static hal_can_link_t g_link;
static bool g_composed;

static uint64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static int fail(char *msg, size_t msglen, int code, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static int fail(char *msg, size_t msglen, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(msg, msglen, fmt, ap);
    va_end(ap);
    return code;
}

static void warn(ls_drive_plan_t *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn(ls_drive_plan_t *p, const char *fmt, ...)
{
    if (p->n_warnings >= LS_DRIVE_SETUP_MAX_WARNINGS) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(p->warnings[p->n_warnings++], LS_DRIVE_SETUP_LINE, fmt, ap);
    va_end(ap);
}

/* ---- what cyclic synchronous position needs of a drive's EDS -------------- */

typedef enum { NEED_READ, NEED_WRITE, NEED_MAP } need_t;

typedef struct {
    uint16_t index;
    uint8_t sub;
    need_t need;
    const char *what;
} need_def_t;

static const need_def_t k_csp_needs[] = {
    { LS_CO_OBJ_DEVICE_TYPE, 0, NEED_READ, "0x1000 device type, readable" },
    { LS_CO_OBJ_PRODUCER_HB, 0, NEED_WRITE, "0x1017 producer heartbeat time, writable" },
    { LS_CO_OBJ_CONTROLWORD, 0, NEED_MAP, "0x6040 controlword, mappable into an RPDO" },
    { LS_CO_OBJ_TARGET_POSITION, 0, NEED_MAP, "0x607A target position, mappable into an RPDO" },
    { LS_CO_OBJ_STATUSWORD, 0, NEED_MAP, "0x6041 statusword, mappable into a TPDO" },
    { LS_CO_OBJ_POSITION_ACTUAL, 0, NEED_MAP, "0x6064 position actual value, mappable into a TPDO" },
    { LS_CO_OBJ_MODES, 0, NEED_WRITE, "0x6060 modes of operation, writable" },
    { LS_CO_OBJ_MODES_DISPLAY, 0, NEED_READ, "0x6061 modes of operation display, readable" },
    { LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_COB_ID, NEED_WRITE, "0x1400:01 RPDO1 COB-ID, writable" },
    { LS_CO_OBJ_RPDO_MAP, 0, NEED_WRITE, "0x1600:00 RPDO1 mapping count, writable" },
    { LS_CO_OBJ_RPDO_MAP, 1, NEED_WRITE, "0x1600:01 RPDO1 mapping entry 1, writable" },
    { LS_CO_OBJ_RPDO_MAP, 2, NEED_WRITE, "0x1600:02 RPDO1 mapping entry 2, writable" },
    { LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_COB_ID, NEED_WRITE, "0x1800:01 TPDO1 COB-ID, writable" },
    { LS_CO_OBJ_TPDO_MAP, 0, NEED_WRITE, "0x1A00:00 TPDO1 mapping count, writable" },
    { LS_CO_OBJ_TPDO_MAP, 1, NEED_WRITE, "0x1A00:01 TPDO1 mapping entry 1, writable" },
    { LS_CO_OBJ_TPDO_MAP, 2, NEED_WRITE, "0x1A00:02 TPDO1 mapping entry 2, writable" },
};

static bool meets(const ls_eds_entry_t *e, need_t need)
{
    switch (need) {
    case NEED_READ: return ls_eds_readable(e);
    case NEED_WRITE: return ls_eds_writable(e);
    case NEED_MAP: return ls_eds_mappable(e);
    }
    return false;
}

static bool writable(uint16_t index, uint8_t sub)
{
    return ls_eds_writable(ls_eds_find(&g_eds, index, sub));
}

/* The value a drive built from the EDS powers on with, as an unsigned
 * number; false when the file gives none. */
static bool power_on_value(uint16_t index, uint8_t sub, uint8_t node, uint64_t *out)
{
    const ls_eds_entry_t *e = ls_eds_find(&g_eds, index, sub);
    ls_eds_value_t v;
    if (e == NULL || ls_eds_value(&g_eds, e, node, &v) != LS_OK) {
        return false;
    }
    if (v.kind == LS_EDS_VALUE_UINT) {
        *out = v.u;
        return true;
    }
    if (v.kind == LS_EDS_VALUE_INT) {
        *out = (uint64_t)v.i;
        return true;
    }
    return false;
}

/* A PDO whose transmission type cannot be written must already be synchronous. */
static int pdo_type_ok(int j, const char *eds, uint16_t comm, uint8_t node, char *msg, size_t msglen)
{
    if (writable(comm, LS_CO_PDO_SUB_TYPE)) {
        return LS_OK;
    }
    uint64_t t = 0;
    if (power_on_value(comm, LS_CO_PDO_SUB_TYPE, node, &t) && t >= LS_CO_PDO_TYPE_SYNC_MIN &&
        t <= LS_CO_PDO_TYPE_SYNC_MAX) {
        return LS_OK;
    }
    return fail(msg, msglen, LS_EINVAL,
                "[joint.%d] eds %s: 0x%04X:02 (the PDO's transmission type) is not writable and not synchronous: "
                "cyclic synchronous position needs PDOs sent and applied at each SYNC",
                j + 1, eds, (unsigned)comm);
}

static int load_eds(int j, const char *path, char *msg, size_t msglen)
{
    if (strcmp(g_eds_path, path) == 0) {
        return LS_OK; /* the joint before used the same file */
    }
    char m[LS_EDS_MSG_MAX];
    g_eds_path[0] = '\0';
    const int r = ls_eds_load(&g_eds, path, m, sizeof m);
    if (r != LS_OK) {
        return fail(msg, msglen, r, "[joint.%d] eds: %s", j + 1, m);
    }
    (void)snprintf(g_eds_path, sizeof g_eds_path, "%s", path);
    return LS_OK;
}

static bool readable(uint16_t index, uint8_t sub)
{
    return ls_eds_readable(ls_eds_find(&g_eds, index, sub));
}

/* How many mapping entries of a PDO mapping object the EDS lets the master
 * write (its sub 0 and entries 1..n, each writable): 0 when none. */
static uint8_t map_room(uint16_t map)
{
    if (!writable(map, 0)) {
        return 0;
    }
    uint8_t n = 0;
    while (n < LS_DRIVES_MAP_MAX && writable(map, (uint8_t)(n + 1u))) {
        n++;
    }
    return n;
}

/* A readout object of the configuration (brake, STO, temperature) or the
 * profile's (velocity, torque actual): mapped when the EDS lets it be;
 * refused when the EDS has no such object (a typo in the configuration). */
static int plan_readout(ls_drive_plan_t *p, int j, const char *eds, const char *key, const ls_config_obj_t *want,
                        ls_drive_obj_t *o, char *msg, size_t msglen)
{
    const ls_eds_entry_t *e = ls_eds_find(&g_eds, want->index, want->sub);
    memset(o, 0, sizeof *o);
    if (e == NULL) {
        return fail(msg, msglen, LS_EINVAL, "[joint.%d] %s = 0x%04X:%02X: the drive's EDS %s has no such object", j + 1,
                    key, (unsigned)want->index, (unsigned)want->sub, eds);
    }
    const unsigned bytes = ls_eds_size(e);
    if (bytes != 1u && bytes != 2u && bytes != 4u) {
        return fail(msg, msglen, LS_EINVAL,
                    "[joint.%d] %s = 0x%04X:%02X: %s says it is %u bytes long; a readout is 1, 2 or 4 bytes", j + 1,
                    key, (unsigned)want->index, (unsigned)want->sub, eds, bytes);
    }
    if (want->bit >= 8u * bytes) {
        return fail(msg, msglen, LS_EINVAL, "[joint.%d] %s = 0x%04X:%02X/%u: the object has %u bits", j + 1, key,
                    (unsigned)want->index, (unsigned)want->sub, (unsigned)want->bit, 8u * bytes);
    }
    o->index = want->index;
    o->sub = want->sub;
    o->bytes = (uint8_t)bytes;
    o->bit = want->bit;
    o->inverted = want->inverted;
    o->is_signed = e->data_type == LS_CO_TYPE_INTEGER8 || e->data_type == LS_CO_TYPE_INTEGER16 ||
                   e->data_type == LS_CO_TYPE_INTEGER32;
    o->map = ls_eds_mappable(e);
    if (!o->map) {
        warn(p, "joint %d (node 0x%02X): its EDS does not let 0x%04X:%02X be mapped into a TPDO: its %s is not shown",
             j + 1, (unsigned)p->drives.joint[j].node_id, (unsigned)want->index, (unsigned)want->sub, key);
    }
    return LS_OK;
}

/* A configured value for an object the drive's EDS may not let be written. */
static bool settable(ls_drive_plan_t *p, int j, bool given, uint16_t index, const char *key)
{
    if (!given) {
        return false;
    }
    if (!writable(index, 0)) {
        warn(p, "joint %d (node 0x%02X): its EDS has no writable 0x%04X: %s is left as the drive has it", j + 1,
             (unsigned)p->drives.joint[j].node_id, (unsigned)index, key);
        return false;
    }
    return true;
}

/* Homing: whether the drive can, whether it changes modes in its PDOs, the
 * method and offset it is given. */
static int plan_homing(const ls_config_t *cfg, int j, ls_drive_plan_t *p, char *msg, size_t msglen)
{
    const ls_config_joint_t *jc = &cfg->joint[j];
    ls_drive_joint_t *dj = &p->drives.joint[j];
    const uint8_t node = jc->node;
    uint64_t modes = 0;
    dj->can_home =
        !power_on_value(LS_CO_OBJ_SUPPORTED_MODES, 0, node, &modes) || (modes & (1u << (LS_CO_MODE_HM - 1))) != 0u;
    dj->home_required = jc->home_required;
    if (jc->home_required && !dj->can_home) {
        return fail(msg, msglen, LS_EINVAL,
                    "[joint.%d] home_required = true, but the drive's EDS %s says it has no homing mode (0x6502 = "
                    "0x%08llX, bit 5 clear): it could never move; set home_required = false (an absolute encoder)",
                    j + 1, jc->eds, (unsigned long long)modes);
    }
    /* The mode rides in the PDOs of a joint configured for homing (a byte
     * each way, every cycle: counted in the budget); another joint homed on
     * request changes its mode over SDO, at rest. */
    const bool homes = jc->home_required || jc->has_home_method || jc->has_home_offset;
    dj->map_mode = homes && dj->can_home && ls_eds_mappable(ls_eds_find(&g_eds, LS_CO_OBJ_MODES, 0)) &&
                   ls_eds_mappable(ls_eds_find(&g_eds, LS_CO_OBJ_MODES_DISPLAY, 0)) &&
                   map_room(LS_CO_OBJ_RPDO_MAP) >= 3u && dj->tpdo_room[0] >= 3u;
    if (homes && dj->can_home && !dj->map_mode) {
        warn(p,
             "joint %d (node 0x%02X): its EDS does not let 0x6060 and 0x6061 be mapped into RPDO1 and TPDO1: a "
             "homing switches the drive's mode over SDO, with the arm at rest",
             j + 1, (unsigned)node);
    }
    dj->write_home_method = settable(p, j, jc->has_home_method, LS_CO_OBJ_HOMING_METHOD, "home_method");
    dj->home_method = (int8_t)jc->home_method;
    dj->write_home_offset = settable(p, j, jc->has_home_offset, LS_CO_OBJ_HOME_OFFSET, "home_offset_rad");
    const double home_counts = (jc->home_offset_rad - jc->offset_rad) * (double)jc->sign * jc->counts_per_rad;
    if (dj->write_home_offset && !(fabs(home_counts) < 2147483647.0)) {
        return fail(msg, msglen, LS_EINVAL,
                    "[joint.%d] home_offset_rad = %g is %.0f counts from the drive's zero: beyond 0x607C's int32",
                    j + 1, jc->home_offset_rad, home_counts);
    }
    dj->home_offset_counts = dj->write_home_offset ? (int32_t)lround(home_counts) : 0;
    return LS_OK;
}

/* The drive's own supervision: following error, quick stop, limits. */
static int plan_supervision(const ls_config_t *cfg, int j, ls_drive_plan_t *p, char *msg, size_t msglen)
{
    const ls_config_joint_t *jc = &cfg->joint[j];
    ls_drive_joint_t *dj = &p->drives.joint[j];
    dj->write_fe_window = settable(p, j, jc->has_following_window, LS_CO_OBJ_FOLLOWING_WINDOW, "following_window_rad");
    const double window = jc->following_window_rad * jc->counts_per_rad;
    if (dj->write_fe_window && !(window >= 1.0 && window < 4294967295.0)) {
        return fail(msg, msglen, LS_EINVAL,
                    "[joint.%d] following_window_rad = %g is %.0f counts: 0x6065 takes 1..4294967294 (0xFFFFFFFF "
                    "switches the drive's check off)",
                    j + 1, jc->following_window_rad, window);
    }
    dj->fe_window_counts = dj->write_fe_window ? (uint32_t)lround(window) : 0u;
    dj->write_fe_timeout =
        settable(p, j, jc->has_following_timeout, LS_CO_OBJ_FOLLOWING_TIMEOUT, "following_timeout_ms");
    dj->fe_timeout_ms = (uint16_t)jc->following_timeout_ms;
    dj->write_quick_stop =
        settable(p, j, cfg->drives_has_quick_stop, LS_CO_OBJ_QUICK_STOP_OPTION, "[drives] quick_stop_option");
    dj->quick_stop_option = (int16_t)cfg->drives_quick_stop;
    dj->read_limits = readable(LS_CO_OBJ_SW_POSITION_LIMIT, 1) && readable(LS_CO_OBJ_SW_POSITION_LIMIT, 2);
    if (!dj->read_limits) {
        warn(p,
             "joint %d (node 0x%02X): its EDS has no readable 0x607D: the drive's software position limits are not "
             "checked against the robot model's",
             j + 1, (unsigned)jc->node);
    }
    return LS_OK;
}

/* The readouts: brake, STO and temperature as configured, velocity and
 * torque actual as [drives] readouts asks; what finds no room is named. */
static int plan_readouts(const ls_config_t *cfg, int j, ls_drive_plan_t *p, char *msg, size_t msglen)
{
    const ls_config_joint_t *jc = &cfg->joint[j];
    ls_drive_joint_t *dj = &p->drives.joint[j];
    const ls_config_obj_t velocity = { .given = (cfg->drives_readouts & LS_CONFIG_READOUT_VELOCITY) != 0u,
                                       .index = LS_CO_OBJ_VELOCITY_ACTUAL };
    const ls_config_obj_t torque = { .given = (cfg->drives_readouts & LS_CONFIG_READOUT_TORQUE) != 0u,
                                     .index = LS_CO_OBJ_TORQUE_ACTUAL };
    const struct {
        const char *key;
        const ls_config_obj_t *want;
        ls_drive_obj_t *o;
    } k[] = { { "brake", &jc->brake, &dj->brake },
              { "sto", &jc->sto, &dj->sto },
              { "temperature", &jc->temperature, &dj->temperature },
              { "velocity", &velocity, &dj->velocity },
              { "torque", &torque, &dj->torque } };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        const int r = k[i].want->given ? plan_readout(p, j, jc->eds, k[i].key, k[i].want, k[i].o, msg, msglen) : LS_OK;
        if (r != LS_OK) {
            return r;
        }
    }
    dj->temperature_scale = jc->temperature_scale;
    ls_drive_layout_t l;
    ls_drives_layout(dj, &l);
    for (unsigned r = 0; r < LS_DRIVE_RO_COUNT; r++) {
        if ((l.left_out & (1u << r)) != 0u) {
            warn(p,
                 "joint %d (node 0x%02X): no room for its %s in two TPDOs (8 bytes each, as many entries as the "
                 "EDS lets be mapped): not shown",
                 j + 1, (unsigned)jc->node, ls_drives_ro_name((ls_drive_ro_t)r));
        }
    }
    return LS_OK;
}

/* What the configuration asks of homing, supervision and readouts. */
static int plan_ops(const ls_config_t *cfg, int j, ls_drive_plan_t *p, char *msg, size_t msglen)
{
    ls_drive_joint_t *dj = &p->drives.joint[j];
    dj->tpdo_room[0] = map_room(LS_CO_OBJ_TPDO_MAP);
    dj->tpdo_room[1] = dj->tpdo_present[1] ? map_room(LS_CO_OBJ_TPDO_MAP + 1u) : 0u;
    int r = plan_homing(cfg, j, p, msg, msglen);
    if (r == LS_OK) {
        r = plan_supervision(cfg, j, p, msg, msglen);
    }
    return r == LS_OK ? plan_readouts(cfg, j, p, msg, msglen) : r;
}

/* One joint: its EDS checked and its drive's configuration derived. */
static int plan_joint(const ls_config_t *cfg, int j, ls_drive_plan_t *p, char *msg, size_t msglen)
{
    const ls_config_joint_t *jc = &cfg->joint[j];
    ls_drive_joint_t *dj = &p->drives.joint[j];
    int r = load_eds(j, jc->eds, msg, msglen);
    if (r != LS_OK) {
        return r;
    }
    for (size_t k = 0; k < sizeof k_csp_needs / sizeof k_csp_needs[0]; k++) {
        const need_def_t *n = &k_csp_needs[k];
        if (!meets(ls_eds_find(&g_eds, n->index, n->sub), n->need)) {
            return fail(msg, msglen, LS_EINVAL,
                        "[joint.%d] eds %s: the drive lacks %s, which cyclic synchronous position needs (is this "
                        "the EDS of a CiA 402 drive?)",
                        j + 1, jc->eds, n->what);
        }
    }
    const uint8_t node = jc->node;
    uint64_t modes = 0;
    if (power_on_value(LS_CO_OBJ_SUPPORTED_MODES, 0, node, &modes) && (modes & (1u << (LS_CO_MODE_CSP - 1))) == 0u) {
        return fail(msg, msglen, LS_EINVAL,
                    "[joint.%d] eds %s: 0x6502 supported drive modes = 0x%08llX does not list cyclic synchronous "
                    "position (bit 7): this drive cannot be driven by landscaped",
                    j + 1, jc->eds, (unsigned long long)modes);
    }
    if ((r = pdo_type_ok(j, jc->eds, LS_CO_OBJ_RPDO_COMM, node, msg, msglen)) != LS_OK ||
        (r = pdo_type_ok(j, jc->eds, LS_CO_OBJ_TPDO_COMM, node, msg, msglen)) != LS_OK) {
        return r;
    }
    ls_eds_device_t dev;
    (void)ls_eds_device(&g_eds, &dev);
    dj->node_id = node;
    dj->scale.counts_per_rad = jc->counts_per_rad;
    dj->scale.vel_counts_per_rad = jc->vel_counts_per_rad_s;
    dj->scale.zero_offset_rad = jc->offset_rad;
    dj->scale.sign = jc->sign;
    dj->has_vendor = dev.has_vendor_number;
    dj->vendor_id = dev.vendor_number;
    dj->has_product = dev.has_product_number;
    dj->product_code = dev.product_number;
    dj->has_revision = dev.has_revision_number;
    dj->revision = dev.revision_number;
    dj->write_pdo_type =
        writable(LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_TYPE) && writable(LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_TYPE);
    dj->write_tpdo_inhibit = writable(LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_INHIBIT);
    dj->write_consumer_hb = writable(LS_CO_OBJ_CONSUMER_HB, 1);
    dj->write_abort_option = writable(LS_CO_OBJ_ABORT_CONNECTION, 0);
    dj->write_interp_period = writable(LS_CO_OBJ_INTERP_PERIOD, 1) && writable(LS_CO_OBJ_INTERP_PERIOD, 2);
    for (uint16_t k = 0; k < LS_DRIVES_PDO_SETS; k++) {
        dj->rpdo_present[k] = writable((uint16_t)(LS_CO_OBJ_RPDO_COMM + k), LS_CO_PDO_SUB_COB_ID);
        dj->tpdo_present[k] = writable((uint16_t)(LS_CO_OBJ_TPDO_COMM + k), LS_CO_PDO_SUB_COB_ID);
    }
    const bool ff_possible = ls_eds_mappable(ls_eds_find(&g_eds, LS_CO_OBJ_VELOCITY_OFFSET, 0)) &&
                             writable(LS_CO_OBJ_RPDO_COMM + 1u, LS_CO_PDO_SUB_COB_ID) &&
                             writable(LS_CO_OBJ_RPDO_MAP + 1u, 0) && writable(LS_CO_OBJ_RPDO_MAP + 1u, 1);
    dj->feedforward = cfg->drives_feedforward && ff_possible;
    if (cfg->drives_feedforward && !ff_possible) {
        warn(p, "joint %d (node 0x%02X): no velocity feed-forward: its EDS has no mappable 0x60B1 or no free RPDO2",
             j + 1, (unsigned)node);
    }
    if (!dj->write_consumer_hb) {
        warn(p,
             "joint %d (node 0x%02X): its EDS has no writable 0x1016: the drive cannot watch the controller's "
             "heartbeat and keeps its last set-point if landscaped dies",
             j + 1, (unsigned)node);
    }
    if (!dj->write_abort_option) {
        warn(p,
             "joint %d (node 0x%02X): its EDS has no writable 0x6007: what the drive does when the controller's "
             "heartbeat stops is the drive's own setting",
             j + 1, (unsigned)node);
    }
    if (!dj->write_interp_period) {
        warn(p,
             "joint %d (node 0x%02X): its EDS has no writable 0x60C2: the drive interpolates over its own period, "
             "not the drive cycle",
             j + 1, (unsigned)node);
    }
    return plan_ops(cfg, j, p, msg, msglen);
}

int ls_drive_plan(const ls_config_t *cfg, ls_drive_plan_t *p, char *msg, size_t msglen)
{
    memset(p, 0, sizeof *p);
    g_eds_path[0] = '\0';
    ls_drives_config_t *dc = &p->drives;
    dc->n_joints = LS_N_JOINTS;
    dc->control_period_us = 1000000u / cfg->rate_hz;
    dc->cycle_ticks = (uint16_t)cfg->drives_cycle;
    dc->master_node = cfg->drives_master_node;
    dc->heartbeat_ms = (uint16_t)cfg->drives_heartbeat_ms;
    dc->heartbeat_timeout_ms = (uint16_t)cfg->drives_heartbeat_timeout_ms;
    dc->boot_timeout_ms = (uint16_t)cfg->drives_boot_timeout_ms;
    dc->abort_option = (int16_t)cfg->drives_abort;
    dc->stale_cycles = (uint8_t)cfg->drives_stale_cycles;
    ls_drive_budget_axis_t axes[LS_N_JOINTS];
    memset(axes, 0, sizeof axes);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const int r = plan_joint(cfg, j, p, msg, msglen);
        if (r != LS_OK) {
            return r;
        }
        ls_drive_layout_t l;
        ls_drives_layout(&dc->joint[j], &l);
        axes[j].n_rpdo = dc->joint[j].feedforward ? 2u : 1u;
        axes[j].rpdo_bytes[0] = l.rpdo1_bytes;
        axes[j].rpdo_bytes[1] = 4;
        axes[j].n_tpdo = l.n_tpdo;
        for (uint8_t t = 0; t < l.n_tpdo; t++) {
            axes[j].tpdo_bytes[t] = l.tpdo_bytes[t];
        }
        axes[j].heartbeat_ms = cfg->drives_heartbeat_ms;
    }
    const ls_drive_budget_in_t in = { .control_period_us = dc->control_period_us,
                                      .cycle_us = dc->control_period_us * cfg->drives_cycle,
                                      .bitrate = cfg->drives_bitrate,
                                      .master_heartbeat_ms = cfg->drives_heartbeat_ms,
                                      .ceiling_pct = (double)cfg->drives_budget_pct,
                                      .axes = axes,
                                      .n_axes = LS_N_JOINTS };
    ls_drive_budget_t b;
    if (ls_drive_budget_compute(&in, &b) != LS_OK) {
        return fail(msg, msglen, LS_EINVAL, "drive bus: the budget could not be computed for this configuration");
    }
    (void)ls_drive_budget_format(&in, &b, p->budget, sizeof p->budget);
    p->budget_fits = b.fits;
    return LS_OK;
}

/* ---- start and shutdown ------------------------------------------------------ */

/* Wait up to 1 ms for the drive link (or just sleep when it has no fd). */
static void wait_link(hal_can_link_t *link)
{
    const int fd = hal_can_poll_fd(link);
    if (fd >= 0) {
        struct pollfd pf = { .fd = fd, .events = POLLIN, .revents = 0 };
        (void)poll(&pf, 1, 1);
    } else {
        const struct timespec ts = { 0, 1000000L };
        (void)nanosleep(&ts, NULL);
    }
}

static int open_drive_link(const ls_config_t *cfg, char *msg, size_t msglen)
{
    char m[256];
    const int r = ls_link_open(cfg->drives_link, cfg->drives_bitrate, true, &g_link, m, sizeof m);
    if (r != LS_OK) {
        return fail(msg, msglen, r, "[drives] link %s: %s", cfg->drives_link, m);
    }
    return LS_OK;
}

/* Every drive's communication reset (they stop their PDOs and forget the
 * controller's heartbeat, which would otherwise fault them once it is
 * gone), then the link closed. */
static void reset_and_close(void)
{
    (void)ls_co_master_nmt(&g_drives.master, LS_CO_NMT_ALL_NODES, LS_CO_NMT_RESET_COMM, mono_us());
    for (int i = 0; i < 20; i++) {
        ls_co_master_poll(&g_drives.master, mono_us());
        wait_link(&g_link);
    }
    hal_can_close(&g_link);
}

int ls_drive_compose(const ls_config_t *cfg, const ls_robot_model_t *model, hal_arm_t *arm, FILE *log, char *msg,
                     size_t msglen)
{
    static ls_drive_plan_t plan; /* large: not on the stack */
    int r = ls_drive_plan(cfg, &plan, msg, msglen);
    if (r != LS_OK) {
        return r;
    }
    if (!plan.budget_fits) {
        return fail(msg, msglen, LS_EINVAL, "%s", plan.budget);
    }
    if (log != NULL) {
        for (size_t i = 0; i < plan.n_warnings; i++) {
            fprintf(log, "<4>landscaped: warning: drives: %s\n", plan.warnings[i]);
        }
        fprintf(log, "<6>landscaped: info: %s\n", plan.budget);
    }
    if ((r = open_drive_link(cfg, msg, msglen)) != LS_OK) {
        return r;
    }
    plan.drives.link = &g_link;
    if (ls_drives_init(&g_drives, &plan.drives) != LS_OK) {
        hal_can_close(&g_link);
        return fail(msg, msglen, LS_EINVAL, "%s", ls_drives_text(&g_drives));
    }
    uint64_t now = mono_us();
    /* The master's own deadlines end each node's boot and each SDO step;
     * this one only guards the loop. */
    const uint64_t deadline = now + 3u * (uint64_t)cfg->drives_boot_timeout_ms * 1000u + 2000000u;
    (void)ls_drives_boot(&g_drives, now);
    for (;;) {
        now = mono_us();
        r = ls_drives_service(&g_drives, now);
        if (r == 1) {
            break;
        }
        if (r < 0 || now > deadline) {
            if (r >= 0) {
                (void)snprintf(msg, msglen, "drives: not every drive was ready within %u ms",
                               (unsigned)(deadline - now) / 1000u);
            } else {
                (void)snprintf(msg, msglen, "drives: %s", ls_drives_text(&g_drives));
            }
            hal_can_close(&g_link);
            return r < 0 ? r : LS_ETIMEDOUT;
        }
        wait_link(&g_link);
    }
    char lim[LS_DRIVE_SETUP_LINE];
    if (ls_drives_check_limits(&g_drives, model->q_min_rad, model->q_max_rad, lim, sizeof lim) != LS_OK) {
        (void)snprintf(msg, msglen, "drives: %s", lim);
        reset_and_close();
        return LS_ERANGE;
    }
    ls_drives_arm(&g_drives, arm);
    g_composed = true;
    return LS_OK;
}

void ls_drive_shutdown(void)
{
    if (!g_composed) {
        return;
    }
    g_composed = false;
    /* The control thread has stopped: this thread owns the drives now. A
     * few drive cycles carry the disable (shutdown controlword) to every
     * drive, then reset communication ends their PDOs and their watch of
     * our heartbeat, which would otherwise fault them once we are gone. */
    hal_arm_t arm;
    ls_drives_arm(&g_drives, &arm);
    (void)hal_arm_enable(&arm, false);
    const uint64_t end = mono_us() + 3u * (uint64_t)g_drives.cfg.cycle_ticks * g_drives.cfg.control_period_us + 20000u;
    uint64_t next = mono_us();
    while (mono_us() < end) {
        if (mono_us() >= next) {
            (void)hal_arm_update(&arm, mono_us());
            next += g_drives.cfg.control_period_us;
        }
        wait_link(&g_link);
    }
    reset_and_close();
}

/* ---- --check ---------------------------------------------------------------- */

static int check_send(void *ctx, const hal_can_frame_t *frame)
{
    return hal_can_send((hal_can_link_t *)ctx, frame) == LS_OK ? LS_OK : LS_EAGAIN;
}

static int probe_read(ls_co_master_t *m, uint8_t node, uint16_t index, uint8_t sub, uint32_t *out, char *why,
                      size_t whylen)
{
    uint64_t now = mono_us();
    int r = ls_co_master_sdo_read(m, node, index, sub, now);
    if (r != LS_OK) {
        (void)snprintf(why, whylen, "SDO read 0x%04X:%02X not started (%s)", (unsigned)index, (unsigned)sub,
                       ls_err_name(r));
        return r;
    }
    for (;;) {
        hal_can_frame_t f;
        while ((r = hal_can_recv(&g_link, &f)) == 1) {
            ls_co_master_on_frame(m, &f, mono_us());
        }
        if (r != LS_EAGAIN) {
            (void)snprintf(why, whylen, "the drive bus failed (%s)", ls_err_name(r));
            return LS_EIO;
        }
        ls_co_master_poll(m, mono_us());
        uint8_t b[8];
        size_t len = 0;
        r = ls_co_master_sdo_result(m, node, b, sizeof b, &len);
        if (r != LS_EBUSY) {
            if (r != LS_OK) {
                (void)snprintf(why, whylen, "%s", ls_co_master_node_text(m, node));
                return r;
            }
            uint32_t v = 0;
            for (size_t i = 0; i < len && i < 4u; i++) {
                v |= (uint32_t)b[i] << (8u * i);
            }
            *out = v;
            return LS_OK;
        }
        wait_link(&g_link);
    }
}

bool ls_drive_check(const ls_config_t *cfg, ls_drive_say_fn say, void *ctx)
{
    static ls_drive_plan_t plan;
    static ls_co_master_t master;
    char line[LS_DRIVE_SETUP_LINE + 128]; /* a finding: a line of the plan, or one with an EDS path (255) in it */
    const int pr = ls_drive_plan(cfg, &plan, line, sizeof line);
    if (pr != LS_OK) {
        say(ctx, 2, "drives", line);
        return pr == LS_EIO; /* a file this machine lacks fails the check; a refused one the configuration */
    }
    (void)snprintf(line, sizeof line, "%d joints on %s: every EDS has what cyclic synchronous position needs",
                   LS_N_JOINTS, cfg->drives_link);
    say(ctx, 0, "drives", line);
    for (size_t i = 0; i < plan.n_warnings; i++) {
        say(ctx, 1, "drives", plan.warnings[i]);
    }
    say(ctx, plan.budget_fits ? 0 : 2, "drive bus budget", plan.budget);
    if (open_drive_link(cfg, line, sizeof line) != LS_OK) {
        say(ctx, 2, "drive bus", line);
        return plan.budget_fits;
    }
    ls_co_master_config_t mc;
    memset(&mc, 0, sizeof mc);
    mc.node_count = LS_N_JOINTS;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        mc.nodes[j].node_id = cfg->joint[j].node;
        mc.nodes[j].heartbeat_ms = (uint16_t)cfg->drives_heartbeat_ms;
        mc.nodes[j].heartbeat_timeout_ms = (uint16_t)cfg->drives_heartbeat_timeout_ms;
    }
    if (ls_co_master_init(&master, &mc, check_send, &g_link) != LS_OK) {
        say(ctx, 2, "drive bus", ls_co_master_text(&master));
        hal_can_close(&g_link);
        return plan.budget_fits;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const ls_drive_joint_t *dj = &plan.drives.joint[j];
        char what[48], why[LS_CO_TEXT_LEN];
        (void)snprintf(what, sizeof what, "drive of joint %d (node 0x%02X)", j + 1, (unsigned)dj->node_id);
        uint32_t type = 0, vendor = 0, product = 0;
        if (probe_read(&master, dj->node_id, LS_CO_OBJ_DEVICE_TYPE, 0, &type, why, sizeof why) != LS_OK) {
            (void)snprintf(line, sizeof line,
                           "does not answer (%s): is it powered, on %s, at this node id and %u bit/s?", why,
                           cfg->drives_link, (unsigned)cfg->drives_bitrate);
            say(ctx, 2, what, line);
            continue;
        }
        const bool ids = probe_read(&master, dj->node_id, LS_CO_OBJ_IDENTITY, 1, &vendor, why, sizeof why) == LS_OK &&
                         probe_read(&master, dj->node_id, LS_CO_OBJ_IDENTITY, 2, &product, why, sizeof why) == LS_OK;
        if ((type & LS_CO_DEVICE_PROFILE_MASK) != LS_CO_PROFILE_DRIVE) {
            (void)snprintf(line, sizeof line, "answers, but 0x1000 = 0x%08X is no CiA 402 drive (profile %u)",
                           (unsigned)type, (unsigned)(type & LS_CO_DEVICE_PROFILE_MASK));
            say(ctx, 2, what, line);
        } else if (!ids) {
            (void)snprintf(line, sizeof line, "its identity 0x1018 could not be read (%s)", why);
            say(ctx, 2, what, line);
        } else if ((dj->has_vendor && vendor != dj->vendor_id) || (dj->has_product && product != dj->product_code)) {
            (void)snprintf(line, sizeof line,
                           "identity vendor 0x%08X product 0x%08X, but its EDS %s says vendor 0x%08X product 0x%08X: "
                           "another drive at this node id, or the wrong EDS",
                           (unsigned)vendor, (unsigned)product, cfg->joint[j].eds, (unsigned)dj->vendor_id,
                           (unsigned)dj->product_code);
            say(ctx, 2, what, line);
        } else {
            (void)snprintf(line, sizeof line, "answers: a CiA 402 drive, vendor 0x%08X product 0x%08X as its EDS",
                           (unsigned)vendor, (unsigned)product);
            say(ctx, 0, what, line);
        }
    }
    hal_can_close(&g_link);
    return plan.budget_fits;
}
