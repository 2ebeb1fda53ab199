/* The drives' own operations through the vendor hook (cmd_drives.h). */
#include "cmd_drives.h"

#include <string.h>

#include "ls_control.h"
#include "ls_core_events.h"
#include "ls_fmt.h"

typedef struct {
    char *buf;
    size_t cap, len;
} text_t;

#define put(t, ...) ls_fmt_append((t)->buf, (t)->cap, &(t)->len, __VA_ARGS__)

/* "joints 2, 3" / "joint 2" of a mask (bit j: joint j + 1). */
static void joint_list(uint32_t mask, char *out, size_t cap)
{
    text_t t = { out, cap, 0 };
    out[0] = '\0';
    const char *sep = (mask & (mask - 1u)) != 0u ? "joints " : "joint ";
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if ((mask & (1u << j)) != 0u) {
            put(&t, "%s%d", sep, j + 1);
            sep = ", ";
        }
    }
}

/* ---- homing ---------------------------------------------------------------- */

/* "2 3", "2,3": the joints; false with `bad` at the first word that is none. */
static bool parse_joints(const char *args, uint32_t *mask, const char **bad)
{
    *mask = 0u;
    const char *p = args;
    for (;;) {
        while (*p == ' ' || *p == ',' || *p == '\t') {
            p++;
        }
        if (*p == '\0') {
            return true;
        }
        const size_t n = strcspn(p, " ,\t");
        if (n != 1u || p[0] < '1' || p[0] > (char)('0' + LS_N_JOINTS)) {
            *bad = p;
            return false;
        }
        *mask |= 1u << (unsigned)(p[0] - '1');
        p += n;
    }
}

int32_t ls_drv_home(ls_core_t *core, ls_call_t *call, const char *args)
{
    if (core->ctl == NULL) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "sendCommand home: no arm is composed");
    }
    uint32_t mask = 0u;
    const char *bad = NULL;
    if (!parse_joints(args, &mask, &bad)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "sendCommand home: '%.*s' is no joint: name joints 1..%d, or none for every joint that must "
                        "be homed",
                        (int)strcspn(bad, " ,\t"), bad, LS_N_JOINTS);
    }
    if (core->owner != call->sup) {
        return ls_reply(call, ls_RetCode_CMD_NOT_OWNER_ERR, "sendCommand home needs the owner: lock the device first");
    }
    if (core->state != ls_State_RESTING) {
        return ls_reply(call, ls_RetCode_CMD_WRONG_STATE_ERR,
                        "sendCommand home is valid in RESTING (drives on, at rest), the device is %s: %s",
                        ls_State_name(core->state),
                        core->state == ls_State_LOCKED ? "activate first" : "wait until the arm is at rest");
    }
    if (core->homing != LS_NO_SESSION) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "sendCommand home: a homing runs already");
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (snap.home_timeout_ms == 0u) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                        "sendCommand home: this arm has no homing: its joints' positions are absolute");
    }
    if (mask == 0u) {
        mask = snap.home_required;
        if (mask == 0u) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "sendCommand home: no joint must be homed here ([joint.N] home_required): name the "
                            "joints to home, e.g. 'home 2'");
        }
    }
    ls_ctl_cmd_t cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.kind = LS_CTL_HOME;
    cmd.ref_seq = call->req->seq;
    cmd.home.joints = mask;
    if (!ls_control_post(core->ctl, &cmd)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "sendCommand home: the control loop's queue is full; try again");
    }
    core->homing = call->sup;
    core->homing_joints = mask;
    return LS_CALL_DEFERRED;
}

void ls_drv_on_home_result(ls_core_t *core, const char *failure, uint64_t now_us)
{
    const int sup = core->homing;
    char joints[48];
    joint_list(core->homing_joints, joints, sizeof joints);
    core->homing = LS_NO_SESSION;
    char msg[sizeof core->down.msg.response.ret_msg];
    if (failure != NULL) {
        ls_core_log_event(core, now_us, "sendCommand home %s: %s", joints, failure);
        ls_fmt_print(msg, sizeof msg, "sendCommand home failed: %s", failure);
        ls_core_finish_deferred(core, sup, ls_RetCode_CMD_ERR, msg);
        return;
    }
    ls_core_log_event(core, now_us, "sendCommand home: %s homed", joints);
    ls_fmt_print(msg, sizeof msg, "homed: %s", joints);
    ls_core_finish_deferred(core, sup, ls_RetCode_CMD_EXEC_OK, msg);
}

bool ls_drv_refuse_unhomed(ls_core_t *core, ls_call_t *call, const char *what, int32_t *code)
{
    if (core->ctl == NULL) {
        return false;
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (snap.homing || core->homing != LS_NO_SESSION) {
        *code = ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: the drives are homing: wait for sendCommand home's answer",
                         what);
        return true;
    }
    if (snap.unhomed == 0u) {
        return false;
    }
    char joints[48];
    joint_list(snap.unhomed, joints, sizeof joints);
    *code = ls_reply(call, ls_RetCode_CMD_WRONG_STATE_ERR,
                     "%s refused, nothing moved: %s must be homed first (an incremental encoder): send "
                     "sendCommand home",
                     what, joints);
    return true;
}

/* ---- readouts -------------------------------------------------------------- */

static const char *brake_name(hal_tri_t t)
{
    return t == HAL_TRI_ON ? "engaged" : "released";
}

static const char *sto_name(hal_tri_t t)
{
    return t == HAL_TRI_ON ? "active" : "off";
}

/* "OPERATION ENABLED" as one word for a key=value line. */
static void state_word(const char *state, char *out, size_t cap)
{
    ls_fmt_print(out, cap, "%s", state != NULL ? state : "?");
    for (char *p = out; *p != '\0'; p++) {
        *p = *p == ' ' ? '_' : *p;
    }
}

/* One joint's line: the same in sendCommand drives and status. */
static void joint_line(text_t *t, int j, const hal_drive_readout_t *o)
{
    char state[32];
    state_word(o->state, state, sizeof state);
    put(t, "drive j%d node=0x%02X state=%s mode=%d home=%s%s", j + 1, (unsigned)o->node, state, (int)o->mode,
        hal_home_name(o->home), o->home_required ? "(required)" : "");
    if (o->brake != HAL_TRI_UNKNOWN) {
        put(t, " brake=%s", brake_name(o->brake));
    }
    if (o->sto != HAL_TRI_UNKNOWN) {
        put(t, " sto=%s", sto_name(o->sto));
    }
    put(t, " error=0x%04X\n", (unsigned)o->last_error);
}

/* One joint in full: every readout on its own line. */
static void joint_full(text_t *t, int j, const hal_drive_readout_t *o)
{
    put(t, "joint=%d\nnode=0x%02X\nstate=%s\nstatusword=0x%04X\nmode=%d\nhome=%s\nhome_required=%s\n", j + 1,
        (unsigned)o->node, o->state != NULL ? o->state : "?", (unsigned)o->statusword, (int)o->mode,
        hal_home_name(o->home), o->home_required ? "yes" : "no");
    put(t, "error=0x%04X\nerror_name=%s\nposition_rad=%.5f\n", (unsigned)o->last_error,
        o->error_name != NULL ? o->error_name : "", o->position_rad);
    if (o->has_velocity) {
        put(t, "velocity_rad_s=%.4f\n", o->velocity_rad_s);
    }
    if (o->has_torque) {
        put(t, "torque_permille=%d\n", (int)o->torque_permille);
    }
    if (o->has_temperature) {
        put(t, "temperature_c=%.1f\n", o->temperature_c);
    }
    if (o->brake != HAL_TRI_UNKNOWN) {
        put(t, "brake=%s\n", brake_name(o->brake));
    }
    if (o->sto != HAL_TRI_UNKNOWN) {
        put(t, "sto=%s\n", sto_name(o->sto));
    }
    put(t, "feedback_age_cycles=%u\n", (unsigned)o->feedback_age);
}

static int read_drives(ls_core_t *core, hal_arm_readout_t *r)
{
    if (core->ctl == NULL) {
        return LS_EUNSUPPORTED;
    }
    const int rc = ls_control_readout(core->ctl, r);
    if (rc != LS_OK && rc != LS_EAGAIN) {
        return rc;
    }
    return r->t_us != 0u ? LS_OK : LS_EAGAIN; /* a copy overlapped by a publish is the one before */
}

int32_t ls_drv_readouts(ls_core_t *core, ls_call_t *call, const char *args, char *out, size_t cap)
{
    static hal_arm_readout_t r; /* comms thread only; large for its stack */
    const int rc = read_drives(core, &r);
    if (rc != LS_OK) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                        rc == LS_EAGAIN ? "sendCommand drives: the drives have published nothing yet; try again"
                                        : "sendCommand drives: this arm has no drives to read (docs/deploy.md "
                                          "\"Drives\")");
    }
    text_t t = { out, cap, 0 };
    out[0] = '\0';
    while (*args == ' ') {
        args++;
    }
    if (args[0] == '\0') {
        for (int j = 0; j < r.n_joints && j < LS_N_JOINTS; j++) {
            joint_line(&t, j, &r.joint[j]);
        }
    } else if (strcmp(args, "bus") == 0) {
        for (uint8_t k = 0; k < r.n_counters && k < HAL_READOUT_COUNTERS; k++) {
            put(&t, "%s=%u\n", r.counter[k].name, (unsigned)r.counter[k].value);
        }
    } else if (args[1] == '\0' && args[0] >= '1' && args[0] < (char)('1' + r.n_joints)) {
        joint_full(&t, args[0] - '1', &r.joint[args[0] - '1']);
    } else {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "sendCommand drives '%.20s': give nothing (every joint), a joint 1..%u, or bus", args,
                        (unsigned)r.n_joints);
    }
    return ls_RetCode_CMD_EXEC_OK;
}

void ls_drv_status_lines(ls_core_t *core, char *out, size_t cap, size_t *len)
{
    static hal_arm_readout_t r;
    if (read_drives(core, &r) != LS_OK) {
        return;
    }
    text_t t = { out, cap, *len };
    for (int j = 0; j < r.n_joints && j < LS_N_JOINTS; j++) {
        joint_line(&t, j, &r.joint[j]);
    }
    *len = t.len;
}
