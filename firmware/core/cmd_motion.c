/* Seed 3.4-3.6: single moves, path queues, stop/resume/abort, getTagId, and
 * the comms-thread side of the motion executor's events.
 *
 * Handlers run in the comms thread. They convert the user's units to SI,
 * plan into the control loop's plan slot (the planners sample and check the
 * whole motion before anything moves) and hand the plan over; the executor
 * reports back through ls_core_on_motion_event.
 *
 * State kept here (static, one controller per process): the path queues
 * (LS_PATH_MAX names x LS_PATH_MAX_POINTS points) and the program of the path
 * being run. The motion being run is core->run (ls_run.h), shared with
 * moveReact and comply: its one final notice goes through ls_run_finish. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_control.h"
#include "ls_core.h"
#include "ls_core_events.h"
#include "ls_kin.h"
#include "ls_motion.h"
#include "ls_units.h"


#define PI 3.14159265358979323846

/* The motion library keeps names and tags in LS_MOTION_NAME_LEN bytes and
 * auxiliary commands in LS_MOTION_AUX_LEN: whatever the schema lets through
 * (protocol/landscape.options) must fit, never be cut. */
#define FITS(msg, field, len) _Static_assert(sizeof(((msg *)0)->field) <= (len), #msg "." #field " exceeds " #len)
FITS(ls_TagPoint, tag_name, LS_MOTION_NAME_LEN);
FITS(ls_PathLoadReq, path_name, LS_MOTION_NAME_LEN);
FITS(ls_PathMoveReq, path_name, LS_MOTION_NAME_LEN);
FITS(ls_PathClearPathReq, path_name, LS_MOTION_NAME_LEN);
FITS(ls_MoveAbsoluteReq, point_name, LS_MOTION_NAME_LEN);
FITS(ls_MoveRelativeReq, point_name, LS_MOTION_NAME_LEN);
FITS(ls_MoveArcReq, point_name, LS_MOTION_NAME_LEN);
FITS(ls_TagPoint, aux_commands[0], LS_MOTION_AUX_LEN);
_Static_assert(sizeof(((ls_GetTagIdRes *)0)->path_name) >= LS_MOTION_NAME_LEN, "getTagId must hold a path name");
_Static_assert(sizeof(((ls_GetTagIdRes *)0)->tag_id) >= LS_MOTION_NAME_LEN, "getTagId must hold a tag");


/* ------------------------------------------------------------- units */

/* The factors of the seed's units (3.2.1 setUnits), from ls_units. */
static double lin_si(ls_LinearUnit u)
{
    return ls_units_to_si_linear(u, 1.0);
}

static double ang_si(ls_AngularUnit u)
{
    return ls_units_to_si_angular(u, 1.0);
}

static const char *lin_name(ls_LinearUnit u)
{
    switch (u) {
    case ls_LinearUnit_MILLIMETERS: return "mm";
    case ls_LinearUnit_CENTIMETERS: return "cm";
    case ls_LinearUnit_INCHES: return "in";
    case ls_LinearUnit_FEET: return "ft";
    case ls_LinearUnit_METERS:
    default: return "m";
    }
}

static const char *ang_name(ls_AngularUnit u)
{
    return u == ls_AngularUnit_DEGREES ? "deg" : "rad";
}

/* x y z (linear units) roll pitch yaw (angular units) -> SI */
static void pose6_si(ls_units_t un, const double in[6], double out[6])
{
    ls_units_pose_to_si(un.linear, un.angular, in, out);
}

/* ------------------------------------------------------------- state */

typedef struct {
    bool used;
    ls_ReferenceFrame frame;
    bool straight; /* STRAIGHT_MOTION (Cartesian points only) */
    bool relative;
    double v[LS_N_JOINTS]; /* SI: joints (rad), or x y z (m) roll pitch yaw (rad) */
    char tag[LS_MOTION_NAME_LEN];
    int32_t tag_index;
    double delay_s, blend_pct, speed_pct, accel_pct;
    uint8_t n_aux;
    char aux[LS_MOTION_AUX_PER_POINT][LS_MOTION_AUX_LEN];
} path_point_t;

typedef struct {
    bool used;
    char name[LS_MOTION_NAME_LEN];
    uint16_t n;
    path_point_t pt[LS_PATH_MAX_POINTS];
} path_t;


static path_t g_paths[LS_PATH_MAX];
static ls_motion_program_t g_prog;
static char g_tag_path[LS_MOTION_NAME_LEN];
static char g_tag_last[LS_MOTION_NAME_LEN];
static uint64_t g_now_us;
static ls_ctl_snapshot_t g_snap; /* scratch */

/* ------------------------------------------------------------- helpers */

static int32_t plan_refused(ls_call_t *call, int status, const char *what, const char *why)
{
    int32_t code = status == LS_MOTION_ERANGE ? ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR : ls_RetCode_CMD_PARAM_ERR;
    return ls_reply(call, code, "%s refused, nothing moved: %s", what, why);
}

static bool snapshot(ls_core_t *core, ls_ctl_snapshot_t *snap)
{
    if (core->ctl == NULL) {
        return false;
    }
    ls_control_snapshot(core->ctl, snap);
    return true;
}

static void tool_pose(const ls_core_t *core, double T[16])
{
    ls_pose_from_xyzrpy(core->settings.tool_offset, T);
}

static void world_pose(const ls_core_t *core, double T[16])
{
    ls_pose_from_xyzrpy(core->settings.world_frame, T);
}

static void cart_limits(const ls_core_t *core, double speed_pct, ls_motion_cart_limits_t *lim)
{
    const ls_robot_model_t *m = core->model;
    const ls_settings_t *st = &core->settings;
    lim->v_lin_m_s = speed_pct > 0.0 ? m->max_linear_speed_m_s * speed_pct / 100.0 : st->linear_speed_m_s;
    lim->v_ang_rad_s = speed_pct > 0.0 ? m->max_angular_speed_rad_s * speed_pct / 100.0 : st->angular_speed_rad_s;
    lim->v_lin_m_s = fmin(lim->v_lin_m_s, m->max_linear_speed_m_s);
    lim->v_ang_rad_s = fmin(lim->v_ang_rad_s, m->max_angular_speed_rad_s);
    lim->a_lin_m_s2 = fmin(st->linear_accel_m_s2, m->max_linear_accel_m_s2);
    lim->a_ang_rad_s2 = fmin(st->angular_accel_rad_s2, m->max_angular_accel_rad_s2);
    /* Jerk follows the acceleration setting's share of the maximum. */
    lim->j_lin_m_s3 = m->max_linear_jerk_m_s3 * lim->a_lin_m_s2 / m->max_linear_accel_m_s2;
    lim->j_ang_rad_s3 = m->max_angular_jerk_rad_s3 * lim->a_ang_rad_s2 / m->max_angular_accel_rad_s2;
    lim->joint_speed_frac = 1.0;
}

static int32_t check_speed_pct(ls_call_t *call, double pct)
{
    if (!isfinite(pct) || (pct != 0.0 && pct < LS_RATE_MIN_PCT) || pct > 100.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "speed %.4g %% is out of range: give 0 (the current setSpeed) or a value in [%g, 100]", pct,
                        LS_RATE_MIN_PCT);
    }
    return 0;
}

/* Names of points and paths are not empty (docs/protocol.md "Limits"). */
static int32_t check_name(ls_call_t *call, const char *what, const char *field, const char *name)
{
    if (name[0] == '\0') {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: %s is empty: give the %s a name", what, field,
                        field[0] == 'p' && field[1] == 'a' ? "path" : "point");
    }
    return 0;
}

static bool all_finite(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(v[i])) {
            return false;
        }
    }
    return true;
}

/* Tool-tip pose (base frame) of the commanded joints. */
static void tip_of(const ls_core_t *core, const double q[LS_N_JOINTS], double P[16])
{
    double F[16], T[16];
    ls_kin_fk(core->model, q, F);
    tool_pose(core, T);
    ls_pose_mul(F, T, P);
}

/* Rotation part of R (3x3 of a pose) applied to a vector. */
static void rot_apply(const double T[16], const double v[3], double out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = T[i] * v[0] + T[4 + i] * v[1] + T[8 + i] * v[2];
    }
}

/* A relative Cartesian offset d (x y z roll pitch yaw, SI) applied to the tip
 * pose P, expressed in the axes of frame F (base: identity, world: the world
 * frame): the position moves by d's translation along F's axes and the
 * orientation turns by d's rotation about F's axes (at the tip). */
static void offset_in_frame(const double F[16], const double P[16], const double d[6], double out[16])
{
    double D[16], Fr[16], Fri[16], tmp[16], Rd[16];
    memcpy(Fr, F, sizeof Fr);
    Fr[12] = Fr[13] = Fr[14] = 0.0;
    ls_pose_inv(Fr, Fri);
    double rpy[6] = { 0, 0, 0, d[3], d[4], d[5] };
    ls_pose_from_xyzrpy(rpy, D);
    ls_pose_mul(Fr, D, tmp);
    ls_pose_mul(tmp, Fri, Rd); /* rotation about F's axes */
    double Pr[16];
    memcpy(Pr, P, sizeof Pr);
    Pr[12] = Pr[13] = Pr[14] = 0.0;
    ls_pose_mul(Rd, Pr, out);
    double dt[3];
    rot_apply(Fr, d, dt);
    for (int i = 0; i < 3; i++) {
        out[12 + i] = P[12 + i] + dt[i];
    }
}

/* Hand the plan in the slot over and enter MOVING. */
static int32_t start_plan(ls_core_t *core, ls_call_t *call, ls_motion_plan_t *slot, const char *seed_name,
                          const char *point, int path)
{
    slot->ref_seq = call->req->seq;
    snprintf(slot->name, sizeof slot->name, "%s", point);
    if (!ls_control_start_plan(core->ctl, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: the control loop's command queue is full; try again",
                        seed_name);
    }
    ls_run_begin(core, call, false, seed_name, point, path);
    return ls_reply(call, ls_RetCode_CMD_STARTED_OK, "%s started: expect %sComplete or an alarm", seed_name, seed_name);
}

static int32_t no_arm(ls_call_t *call, const char *what)
{
    return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                    "%s: no arm is composed in this controller (start landscaped with an arm backend)", what);
}

/* The plan slot, or NULL after answering CMD_BUSY_ERR in *code. */
static ls_motion_plan_t *take_slot(ls_core_t *core, ls_call_t *call, const char *what, int32_t *code)
{
    ls_motion_plan_t *slot = ls_control_plan_slot(core->ctl);
    if (slot == NULL && ls_control_manual_on(core->ctl)) {
        *code = ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: manualControl is on: send manualControl off first", what);
    } else if (slot == NULL) {
        *code = ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                         "%s: the control loop has not taken the previous motion yet; try again", what);
    }
    return slot;
}

/* ------------------------------------------------------------- single moves */

static int32_t count_error(ls_call_t *call, const char *what, const char *field, size_t got, size_t want)
{
    return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: %s has %zu values, %s needs %zu", what, field, got,
                    "this frame", want);
}

/* moveAbsolute / moveRelative. */
static int32_t do_move(ls_core_t *core, ls_call_t *call, bool relative)
{
    const char *what = relative ? "moveRelative" : "moveAbsolute";
    const char *point;
    ls_ReferenceFrame frame;
    const double *values;
    size_t n_values;
    double speed_pct;
    if (relative) {
        const ls_MoveRelativeReq *r = &call->req->cmd.move_relative;
        point = r->point_name, frame = r->frame, values = r->values, n_values = r->values_count;
        speed_pct = r->speed_pct;
    } else {
        const ls_MoveAbsoluteReq *r = &call->req->cmd.move_absolute;
        point = r->point_name, frame = r->frame, values = r->values, n_values = r->values_count;
        speed_pct = r->speed_pct;
    }
    if (core->ctl == NULL || core->model == NULL) {
        return no_arm(call, what);
    }
    int32_t code = check_speed_pct(call, speed_pct);
    if (code == 0) {
        code = check_name(call, what, "point_name", point);
    }
    if (code != 0) {
        return code;
    }
    if (!all_finite(values, n_values)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: values must be finite numbers", what);
    }
    ls_ctl_snapshot_t snap;
    (void)snapshot(core, &snap);
    const double *q0 = snap.q_cmd_rad;
    ls_motion_plan_t *slot = take_slot(core, call, what, &code);
    if (slot == NULL) {
        return code;
    }
    char why[128];
    int st;
    const ls_settings_t *set = &core->settings;
    const ls_units_t un = ls_core_units(core, call->sup);
    if (frame == ls_ReferenceFrame_JOINT_FRAME) {
        if (n_values != LS_N_JOINTS) {
            return count_error(call, what, "values", n_values, LS_N_JOINTS);
        }
        double q1[LS_N_JOINTS];
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q1[j] = values[j] * ang_si(un.angular) + (relative ? q0[j] : 0.0);
        }
        const double sf = (speed_pct > 0.0 ? speed_pct : set->speed_pct) / 100.0;
        st = ls_motion_plan_joint(slot, core->model, q0, q1, sf, set->accel_pct / 100.0, why, sizeof why);
    } else if (frame == ls_ReferenceFrame_BASE_CARTESIAN_FRAME || frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME ||
               (frame == ls_ReferenceFrame_TOOL_FRAME && relative)) {
        if (n_values != 6) {
            return count_error(call, what, "values", n_values, 6);
        }
        double d[6], P0[16], P1[16], W[16], T[16];
        pose6_si(un, values, d);
        tip_of(core, q0, P0);
        world_pose(core, W);
        if (!relative) {
            ls_pose_from_xyzrpy(d, T);
            if (frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
                ls_pose_mul(W, T, P1);
            } else {
                memcpy(P1, T, sizeof P1);
            }
        } else if (frame == ls_ReferenceFrame_TOOL_FRAME) {
            ls_pose_from_xyzrpy(d, T);
            ls_pose_mul(P0, T, P1);
        } else {
            double I[16];
            const double zero[6] = { 0 };
            ls_pose_from_xyzrpy(zero, I);
            offset_in_frame(frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME ? W : I, P0, d, P1);
        }
        ls_motion_cart_limits_t lim;
        cart_limits(core, speed_pct, &lim);
        double tool[16];
        tool_pose(core, tool);
        st = ls_motion_plan_line(slot, core->model, q0, tool, P1, &lim, why, sizeof why);
    } else {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: frame %d is not valid here (JOINT_FRAME, BASE_CARTESIAN_FRAME, WORLD_CARTESIAN_FRAME%s)",
                        what, (int)frame, relative ? ", TOOL_FRAME" : "");
    }
    if (st < 0) {
        return plan_refused(call, st, what, why);
    }
    return start_plan(core, call, slot, what, point, -1);
}

int32_t ls_h_move_absolute(struct ls_core *core, struct ls_call *call)
{
    return do_move(core, call, false);
}

int32_t ls_h_move_relative(struct ls_core *core, struct ls_call *call)
{
    return do_move(core, call, true);
}

int32_t ls_h_move_arc(struct ls_core *core, struct ls_call *call)
{
    const ls_MoveArcReq *r = &call->req->cmd.move_arc;
    if (core->ctl == NULL || core->model == NULL) {
        return no_arm(call, "moveArc");
    }
    if (r->frame != ls_ReferenceFrame_BASE_CARTESIAN_FRAME && r->frame != ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "moveArc: an arc is Cartesian: use BASE_CARTESIAN_FRAME or WORLD_CARTESIAN_FRAME");
    }
    int32_t named = check_name(call, "moveArc", "point_name", r->point_name);
    if (named != 0) {
        return named;
    }
    if (r->arc_value_count != 6 || r->goal_value_count != 6) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "moveArc: arc_value and goal_value need 6 values each (x y z roll pitch yaw), got %u and %u",
                        (unsigned)r->arc_value_count, (unsigned)r->goal_value_count);
    }
    if (!all_finite(r->arc_value, 6) || !all_finite(r->goal_value, 6)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "moveArc: values must be finite numbers");
    }
    ls_ctl_snapshot_t snap;
    (void)snapshot(core, &snap);
    const double *q0 = snap.q_cmd_rad;
    int32_t code = 0;
    ls_motion_plan_t *slot = take_slot(core, call, "moveArc", &code);
    if (slot == NULL) {
        return code;
    }
    double P0[16], W[16], F[16], via[16], goal[16];
    tip_of(core, q0, P0);
    world_pose(core, W);
    const double zero[6] = { 0 };
    if (r->frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        memcpy(F, W, sizeof F);
    } else {
        ls_pose_from_xyzrpy(zero, F);
    }
    const double *src[2] = { r->arc_value, r->goal_value };
    double *dst[2] = { via, goal };
    for (int k = 0; k < 2; k++) {
        double d[6], T[16];
        pose6_si(ls_core_units(core, call->sup), src[k], d);
        if (r->offset_type == ls_OffsetType_RELATIVE_DATA) {
            offset_in_frame(F, P0, d, dst[k]);
        } else {
            ls_pose_from_xyzrpy(d, T);
            ls_pose_mul(F, T, dst[k]);
        }
    }
    ls_motion_cart_limits_t lim;
    cart_limits(core, 0.0, &lim);
    double tool[16];
    tool_pose(core, tool);
    char why[128];
    int st = ls_motion_plan_arc(slot, core->model, q0, tool, via, goal, &lim, why, sizeof why);
    if (st < 0) {
        return plan_refused(call, st, "moveArc", why);
    }
    return start_plan(core, call, slot, "moveArc", r->point_name, -1);
}

/* ------------------------------------------------------------- stop, resume, abort */

static bool post(ls_core_t *core, ls_ctl_kind_t kind, uint32_t ref_seq)
{
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.ref_seq = ref_seq;
    return ls_control_post(core->ctl, &c);
}

int32_t ls_h_stop_motion(struct ls_core *core, struct ls_call *call)
{
    if (core->ctl == NULL) {
        return no_arm(call, "stopMotion");
    }
    if (!post(core, LS_CTL_STOP, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "stopMotion: the control loop's command queue is full; try again");
    }
    core->run.stop_pending = true;
    core->run.stop_sup = call->sup;
    return LS_CALL_DEFERRED;
}

int32_t ls_h_resume_motion(struct ls_core *core, struct ls_call *call)
{
    if (core->ctl == NULL) {
        return no_arm(call, "resumeMotion");
    }
    if (!post(core, LS_CTL_RESUME, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "resumeMotion: the control loop's command queue is full; try again");
    }
    core->state = ls_State_MOVING;
    snprintf(core->motion_state, sizeof core->motion_state, "running_trajectory");
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "resumed along the planned path");
}

static void path_delete(int i)
{
    if (i >= 0 && i < LS_PATH_MAX) {
        g_paths[i].used = false;
        g_paths[i].n = 0;
        g_paths[i].name[0] = '\0';
    }
}

int32_t ls_h_abort_motion(struct ls_core *core, struct ls_call *call)
{
    if (core->ctl != NULL && !post(core, LS_CTL_ABORT, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "abortMotion: the control loop's command queue is full; try again");
    }
    bool had = core->run.active;
    if (had) {
        const int path = core->run.path;
        ls_run_finish(core, LS_RUN_END_ABORT, NULL, 0);
        path_delete(path);
    }
    if (core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        snprintf(core->motion_state, sizeof core->motion_state, "robot_stopped_on_command");
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s",
                    had ? "motion dropped and its path queue cleared" : "nothing to abort: no motion was held");
}

/* ------------------------------------------------------------- getTagId */

int32_t ls_h_get_tag_id(struct ls_core *core, struct ls_call *call)
{
    (void)core;
    ls_GetTagIdRes *r = &call->res->result.get_tag_id;
    snprintf(r->path_name, sizeof r->path_name, "%s", g_tag_path);
    snprintf(r->tag_id, sizeof r->tag_id, "%s", g_tag_last);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s",
                    g_tag_last[0] != '\0' ? "last tag reached" : "no tag reached yet");
}

/* ------------------------------------------------------------- auxiliary commands */

typedef enum { AUX_DIO = 1, AUX_WAIT, AUX_EVENT, AUX_RSVP } aux_kind_t;

typedef struct {
    aux_kind_t kind;
    uint16_t unit;
    uint32_t on, off; /* dio: bits to set, bits to clear; wait: on = mask */
    double timeout_s;
    char name[LS_MOTION_NAME_LEN];
} aux_t;

static bool parse_u32(const char *tok, int base, uint32_t *out)
{
    if (tok == NULL || *tok == '\0' || *tok == '-') {
        return false;
    }
    char *end = NULL;
    unsigned long v = strtoul(tok, &end, base);
    if (*end != '\0' || v > 0xFFFFFFFFul) {
        return false;
    }
    *out = (uint32_t)v;
    return true;
}

static bool parse_timeout(const char *tok, double *out)
{
    if (tok == NULL) {
        return false;
    }
    char *end = NULL;
    double v = strtod(tok, &end);
    if (*end != '\0' || !isfinite(v) || v <= 0.0 || v > 3600.0) {
        return false;
    }
    *out = v;
    return true;
}

/* Syntax (docs/protocol.md "Auxiliary commands"):
 *   dio UNIT ON OFF          ON/OFF hex masks (0x optional)
 *   wait UNIT MASK TIMEOUT_S MASK hex, TIMEOUT_S in (0, 3600]
 *   event NAME
 *   rsvp NAME TIMEOUT_S */
static int parse_aux(const char *text, aux_t *a, char *why, size_t whylen)
{
    char buf[LS_MOTION_AUX_LEN];
    snprintf(buf, sizeof buf, "%s", text);
    char *tok[5] = { 0 };
    int n = 0;
    for (char *c = buf; *c != '\0';) {
        while (*c == ' ' || *c == '\t') {
            *c++ = '\0';
        }
        if (*c == '\0') {
            break;
        }
        if (n == 5) {
            n = 6; /* too many words */
            break;
        }
        tok[n++] = c;
        while (*c != '\0' && *c != ' ' && *c != '\t') {
            c++;
        }
    }
    memset(a, 0, sizeof *a);
    uint32_t unit = 0;
    if (n == 4 && strcmp(tok[0], "dio") == 0) {
        a->kind = AUX_DIO;
        if (parse_u32(tok[1], 10, &unit) && unit < LS_CTL_MAX_DIO_UNITS && parse_u32(tok[2], 16, &a->on) &&
            parse_u32(tok[3], 16, &a->off)) {
            a->unit = (uint16_t)unit;
            return 0;
        }
        snprintf(why, whylen, "expected 'dio UNIT ON OFF' with UNIT 0..%d and hex masks", LS_CTL_MAX_DIO_UNITS - 1);
        return -1;
    }
    if (n == 4 && strcmp(tok[0], "wait") == 0) {
        a->kind = AUX_WAIT;
        if (parse_u32(tok[1], 10, &unit) && unit < LS_CTL_MAX_DIO_UNITS && parse_u32(tok[2], 16, &a->on) &&
            a->on != 0 && parse_timeout(tok[3], &a->timeout_s)) {
            a->unit = (uint16_t)unit;
            return 0;
        }
        snprintf(why, whylen, "expected 'wait UNIT MASK TIMEOUT_S', MASK hex != 0, TIMEOUT_S in (0, 3600]");
        return -1;
    }
    if (n == 2 && strcmp(tok[0], "event") == 0) {
        a->kind = AUX_EVENT;
        snprintf(a->name, sizeof a->name, "%s", tok[1]);
        return 0;
    }
    if (n == 3 && strcmp(tok[0], "rsvp") == 0) {
        a->kind = AUX_RSVP;
        snprintf(a->name, sizeof a->name, "%s", tok[1]);
        if (parse_timeout(tok[2], &a->timeout_s)) {
            return 0;
        }
        snprintf(why, whylen, "expected 'rsvp NAME TIMEOUT_S', TIMEOUT_S in (0, 3600]");
        return -1;
    }
    snprintf(why, whylen, "unknown auxiliary command: use dio, wait, event or rsvp");
    return -1;
}

/* The I/O an auxiliary command names exists on this controller: a `dio`
 * unit with those output bits, a `wait` unit with those input bits. */
static int check_aux_io(const ls_core_t *core, const aux_t *a, char *why, size_t whylen)
{
    if (a->kind != AUX_DIO && a->kind != AUX_WAIT) {
        return 0;
    }
    if (a->unit >= core->dio_units) {
        if (core->dio_units == 0) {
            snprintf(why, whylen, "this controller has no DIO units (start landscaped with a DIO backend)");
        } else {
            snprintf(why, whylen, "DIO unit %u does not exist: units 0..%u", (unsigned)a->unit,
                     (unsigned)core->dio_units - 1u);
        }
        return -1;
    }
    const hal_dio_unit_info_t *u = &core->dio_info[a->unit];
    if (a->kind == AUX_DIO) {
        const uint32_t bad = (a->on | a->off) & ~u->output_mask;
        if (bad != 0u) {
            snprintf(why, whylen, "bits 0x%X of unit %u are not outputs (outputs: 0x%X)", (unsigned)bad,
                     (unsigned)a->unit, (unsigned)u->output_mask);
            return -1;
        }
        if ((a->on & a->off) != 0u) {
            snprintf(why, whylen, "bits 0x%X are both set and cleared", (unsigned)(a->on & a->off));
            return -1;
        }
        return 0;
    }
    const uint32_t bad = a->on & ~u->input_mask;
    if (bad != 0u) {
        snprintf(why, whylen, "bits 0x%X of unit %u are not inputs (inputs: 0x%X)", (unsigned)bad, (unsigned)a->unit,
                 (unsigned)u->input_mask);
        return -1;
    }
    return 0;
}

static void aux_done(ls_core_t *core)
{
    if (core->ctl == NULL || !post(core, LS_CTL_AUX_DONE, core->run.ref_seq)) {
        /* The loop's queue is full: the path would wait for ever, so fail loudly. */
        ls_core_fault(core, "auxiliary command finished but the control loop's queue was full", g_now_us);
    }
}

/* The path ended at a point because an auxiliary command failed: the arm is
 * at rest there (the executor waits for the command), so the path is
 * dropped and the device stays RESTING, ready for the next motion. */
static void aux_failed(ls_core_t *core, int point, const char *text)
{
    if (!core->run.active) {
        return;
    }
    (void)post(core, LS_CTL_ABORT, core->run.ref_seq);
    char d1[24], d2[72];
    snprintf(d1, sizeof d1, "at_point=%d", point);
    snprintf(d2, sizeof d2, "fault=%s", text);
    const char *extra[] = { d1, d2 };
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        snprintf(core->motion_state, sizeof core->motion_state, "robot_stopped_on_error");
    }
    ls_run_finish(core, LS_RUN_END_AUX_FAILED, extra, 2);
}

/* A path's `rsvp` (docs/protocol.md "RSVP"): accept continues the path,
 * decline drops it (the arm is at rest at the point), no answer continues. */
#define LS_PATH_RSVP_ACCEPT "continue"
#define LS_PATH_RSVP_DECLINE "abort"
#define LS_PATH_RSVP_DEFAULT LS_PATH_RSVP_ACCEPT
static const char *rsvp_done(struct ls_core *core, void *ctx, int32_t ret_code, bool timed_out, uint64_t now_us)
{
    (void)ctx;
    (void)now_us;
    if (!core->run.active) {
        return "none"; /* the path ended meanwhile */
    }
    if (!timed_out && ret_code < 0) {
        /* The supervisor declined: drop the path (it asked us not to go on);
         * the arm is at rest at the point. */
        (void)post(core, LS_CTL_ABORT, core->run.ref_seq);
        char d1[32];
        snprintf(d1, sizeof d1, "answer=%d", (int)ret_code);
        const char *extra[] = { d1 };
        if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
            core->state = ls_State_RESTING;
            snprintf(core->motion_state, sizeof core->motion_state, "robot_stopped_on_command");
        }
        ls_run_finish(core, LS_RUN_END_RSVP_DECLINED, extra, 1);
        return LS_PATH_RSVP_DECLINE;
    }
    aux_done(core); /* answered, or timed out: the default action is to continue */
    return timed_out ? LS_PATH_RSVP_DEFAULT : LS_PATH_RSVP_ACCEPT;
}

static void run_aux(ls_core_t *core, const ls_motion_event_t *ev)
{
    aux_t a;
    char why[96];
    if (parse_aux(ev->text, &a, why, sizeof why) != 0) {
        /* pathLoad checked it: only a corrupted program gets here. */
        char t[96];
        snprintf(t, sizeof t, "bad auxiliary command '%.40s'", ev->text);
        aux_failed(core, (int)ev->index, t);
        return;
    }
    char d1[8 + LS_MOTION_NAME_LEN], d2[24];
    snprintf(d1, sizeof d1, "path=%s", core->run.point);
    snprintf(d2, sizeof d2, "point=%d", (int)ev->index);
    const char *data[] = { d1, d2 };
    switch (a.kind) {
    case AUX_DIO: {
        ls_ctl_cmd_t c;
        memset(&c, 0, sizeof c);
        c.kind = LS_CTL_DIO_WRITE;
        c.ref_seq = core->run.ref_seq;
        c.dio.unit = a.unit;
        c.dio.on = a.on;
        c.dio.off = a.off;
        if (!ls_control_post(core->ctl, &c)) {
            aux_failed(core, (int)ev->index, "dio: the control loop's queue was full");
            return;
        }
        /* Go on only once the loop has carried the write out (ls_core_motion_tick);
         * a refusal comes back as LS_CEV_CMD_FAILED (ls_core_motion_failed). */
        core->run.dio_pending = true;
        core->run.dio_point = (int)ev->index;
        core->run.dio_cycle = snapshot(core, &g_snap) ? g_snap.cycle : 0;
        core->run.dio_seen = false;
        return;
    }
    case AUX_WAIT:
        core->run.wait_active = true;
        core->run.wait_unit = a.unit;
        core->run.wait_mask = a.on;
        core->run.wait_deadline_us = g_now_us + (uint64_t)(a.timeout_s * 1e6);
        core->run.wait_point = (int)ev->index;
        snprintf(core->run.wait_text, sizeof core->run.wait_text, "%.*s", (int)sizeof core->run.wait_text - 1,
                 ev->text);
        ls_core_motion_tick(core, g_now_us);
        return;
    case AUX_EVENT:
        ls_core_notify_to(core, core->run.addr, core->run.epoch, ls_NoticeKind_EVENT, a.name, core->run.ref_seq, false,
                          data, 2);
        aux_done(core);
        return;
    case AUX_RSVP:
        if (ls_core_rsvp(core, core->run.sup, core->run.ref_seq, ls_NoticeKind_EVENT_RSVP, a.name, data, 2,
                         (uint32_t)(a.timeout_s * 1000.0), LS_PATH_RSVP_DEFAULT, rsvp_done, NULL, g_now_us) < 0) {
            aux_done(core); /* nobody to ask (or the table is full): take the default */
        }
        return;
    default: return;
    }
}

void ls_core_motion_tick(ls_core_t *core, uint64_t now_us)
{
    g_now_us = now_us;
    if (!core->run.active || core->run.react || core->ctl == NULL) {
        return;
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (core->run.dio_pending) {
        /* The loop took the write two cycles ago: a refusal was pushed before
         * that snapshot, so it has been drained by the next turn. */
        if (core->run.dio_seen) {
            core->run.dio_pending = false;
            aux_done(core);
        } else if (snap.cycle >= core->run.dio_cycle + 2u) {
            core->run.dio_seen = true;
        }
        return;
    }
    if (!core->run.wait_active) {
        return;
    }
    if ((snap.dio[core->run.wait_unit] & core->run.wait_mask) == core->run.wait_mask) {
        core->run.wait_active = false;
        aux_done(core);
    } else if (now_us >= core->run.wait_deadline_us) {
        core->run.wait_active = false;
        char t[64];
        snprintf(t, sizeof t, "wait: inputs 0x%X of unit %u not all set in time", (unsigned)core->run.wait_mask,
                 (unsigned)core->run.wait_unit);
        aux_failed(core, core->run.wait_point, t);
    }
}

void ls_core_motion_failed(ls_core_t *core, uint32_t ref_seq, const char *text)
{
    if (!core->run.active || core->run.react || ref_seq == 0 || ref_seq != core->run.ref_seq) {
        return;
    }
    if (core->run.dio_pending) {
        core->run.dio_pending = false;
        aux_failed(core, core->run.dio_point, text);
        return;
    }
    if (core->halt.active) {
        return; /* the halt ends it */
    }
    /* The loop could not start it (drives off, manual control, a motion
     * still held): nothing moved. */
    char d[80];
    snprintf(d, sizeof d, "fault=%s", text);
    const char *extra[] = { d };
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        snprintf(core->motion_state, sizeof core->motion_state, "robot_stopped_on_error");
    }
    ls_run_finish(core, LS_RUN_END_FAULT, extra, 1);
}

/* ------------------------------------------------------------- executor events */

static void joints_text(const ls_core_t *core, const double q[LS_N_JOINTS], char *out, size_t cap)
{
    /* Fit the notice's 64 characters: fewer digits when needed. */
    for (int prec = 6; prec >= 3; prec--) {
        size_t len = (size_t)snprintf(out, cap, "joints=");
        for (int j = 0; j < LS_N_JOINTS && len < cap; j++) {
            len += (size_t)snprintf(out + len, cap - len, "%s%.*g", j ? "," : "", prec,
                                    q[j] / ang_si(ls_core_run_units(core).angular));
        }
        if (len < cap) {
            return;
        }
    }
}

void ls_core_on_motion_event(ls_core_t *core, const ls_motion_event_t *ev)
{
    if (ev == NULL) {
        return;
    }
    switch (ev->kind) {
    case LS_MEV_DONE: {
        if (!core->run.active || core->run.react || ev->ref_seq != core->run.ref_seq) {
            return; /* a motion we already gave up (abort) */
        }
        char d2[64];
        joints_text(core, ev->q_rad, d2, sizeof d2);
        const char *extra[] = { d2 };
        if (!core->halt.active && (core->state == ls_State_MOVING || core->state == ls_State_PAUSED)) {
            core->state = ls_State_RESTING;
            snprintf(core->motion_state, sizeof core->motion_state, "robot_at_rest");
        }
        /* It completed, even when a halt was already stopping it. */
        ls_run_finish(core, LS_RUN_END_COMPLETE, extra, 1);
        return;
    }
    case LS_MEV_PAUSED:
        if (core->halt.active) {
            return; /* a halt's stop: the drives go off next */
        }
        if (core->state == ls_State_MOVING) {
            core->state = ls_State_PAUSED;
            snprintf(core->motion_state, sizeof core->motion_state, "robot_paused");
        }
        if (core->run.stop_pending) {
            core->run.stop_pending = false;
            ls_core_finish_deferred(core, core->run.stop_sup, ls_RetCode_CMD_EXEC_OK,
                                    "paused on the planned path: resumeMotion continues, abortMotion drops it");
        }
        return;
    case LS_MEV_FAULT: {
        char t[80];
        snprintf(t, sizeof t, "%s", ev->text);
        if (core->ctl != NULL) {
            ls_ctl_snapshot_t snap;
            ls_control_snapshot(core->ctl, &snap);
            if (snap.t_us > g_now_us) {
                g_now_us = snap.t_us;
            }
        }
        ls_core_fault(core, t, g_now_us); /* ends the run once the drives are off */
        return;
    }
    case LS_MEV_TAG: {
        snprintf(g_tag_path, sizeof g_tag_path, "%.*s", (int)sizeof g_tag_path - 1, ev->text);
        snprintf(g_tag_last, sizeof g_tag_last, "%s", ev->name);
        if (!core->run.active || core->run.react) {
            return;
        }
        char d1[8 + LS_MOTION_NAME_LEN], d2[24], d3[24], d4[8 + sizeof ev->text];
        snprintf(d1, sizeof d1, "tag=%s", ev->name);
        snprintf(d2, sizeof d2, "index=%d", (int)ev->index);
        snprintf(d3, sizeof d3, "cycle=%d", (int)ev->cycle);
        snprintf(d4, sizeof d4, "path=%s", ev->text);
        const char *data[] = { d1, d2, d3, d4, "dry_run=true" };
        ls_core_notify_to(core, core->run.addr, core->run.epoch, ls_NoticeKind_EVENT, "tag", core->run.ref_seq, false,
                          data, core->run.dry_run ? 5u : 4u);
        return;
    }
    case LS_MEV_AUX:
        if (core->run.active && !core->run.react && !core->halt.active) {
            run_aux(core, ev);
        }
        return;
    default: return;
    }
}

/* ------------------------------------------------------------- path queues */

static int path_find(const char *name)
{
    for (int i = 0; i < LS_PATH_MAX; i++) {
        if (g_paths[i].used && strcmp(g_paths[i].name, name) == 0) {
            return i;
        }
    }
    return -1;
}

static bool path_running(const ls_core_t *core, int i)
{
    return core->run.active && core->run.path == i;
}

static int32_t check_pct(ls_call_t *call, int k, const char *field, double v)
{
    if (!isfinite(v) || (v != 0.0 && v < LS_RATE_MIN_PCT) || v > 100.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "pathLoad point %d: %s %.4g is out of range: 0 (the current setting) or [%g, 100] %%", k, field,
                        v, LS_RATE_MIN_PCT);
    }
    return 0;
}

/* Validate point k of the message and convert it to SI. */
static int32_t load_point(ls_core_t *core, ls_call_t *call, const ls_PathLoadReq *r, int k, path_point_t *pt)
{
    const ls_TagPoint *tp = &r->tags[k];
    const ls_units_t un = ls_core_units(core, call->sup);
    memset(pt, 0, sizeof *pt);
    pt->used = true;
    pt->frame = r->frame;
    pt->straight = r->motion_type == ls_MotionType_STRAIGHT_MOTION;
    pt->relative = r->offset_type == ls_OffsetType_RELATIVE_DATA;
    if (r->frame == ls_ReferenceFrame_JOINT_FRAME) {
        if (tp->joints_count != LS_N_JOINTS || !all_finite(tp->joints, LS_N_JOINTS)) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "pathLoad point %d: JOINT_FRAME needs %d finite joint values in `joints`, got %u", k,
                            LS_N_JOINTS, (unsigned)tp->joints_count);
        }
        for (int j = 0; j < LS_N_JOINTS; j++) {
            pt->v[j] = tp->joints[j] * ang_si(un.angular);
            if (!pt->relative && (pt->v[j] < core->model->q_min_rad[j] || pt->v[j] > core->model->q_max_rad[j])) {
                const double lim =
                    pt->v[j] < core->model->q_min_rad[j] ? core->model->q_min_rad[j] : core->model->q_max_rad[j];
                return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                                "pathLoad point %d: joint %d: %.4g %s beyond its limit %.4g %s", k, j + 1,
                                tp->joints[j], ang_name(un.angular), lim / ang_si(un.angular), ang_name(un.angular));
            }
        }
    } else {
        if (tp->pose_count != 6 || !all_finite(tp->pose, 6)) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "pathLoad point %d: a Cartesian frame needs 6 finite values in `pose` (x y z roll pitch "
                            "yaw), got %u",
                            k, (unsigned)tp->pose_count);
        }
        pose6_si(un, tp->pose, pt->v);
        if (!pt->relative) {
            double T[16], W[16], P[16];
            ls_pose_from_xyzrpy(pt->v, T);
            if (r->frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
                world_pose(core, W);
                ls_pose_mul(W, T, P);
            } else {
                memcpy(P, T, sizeof P);
            }
            for (int i = 0; i < 3; i++) {
                const double lo = core->model->workspace_min_m[i], hi = core->model->workspace_max_m[i];
                if (P[12 + i] < lo || P[12 + i] > hi) {
                    static const char *const ax[3] = { "x", "y", "z" };
                    return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                                    "pathLoad point %d: axis %s: %.4g %s beyond the workspace limit %.4g %s (base "
                                    "frame)",
                                    k, ax[i], P[12 + i] / lin_si(un.linear), lin_name(un.linear),
                                    (P[12 + i] < lo ? lo : hi) / lin_si(un.linear), lin_name(un.linear));
                }
            }
        }
    }
    int32_t code;
    if ((code = check_pct(call, k, "transition_speed_pct", tp->transition_speed_pct)) != 0 ||
        (code = check_pct(call, k, "speed_pct", tp->speed_pct)) != 0 ||
        (code = check_pct(call, k, "accel_pct", tp->accel_pct)) != 0) {
        return code;
    }
    if (!isfinite(tp->time_delay_s) || tp->time_delay_s < 0.0 || tp->time_delay_s > 3600.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "pathLoad point %d: time_delay_s %.4g is out of range [0, 3600] s", k, tp->time_delay_s);
    }
    snprintf(pt->tag, sizeof pt->tag, "%s", tp->tag_name);
    pt->tag_index = tp->tag_index;
    pt->delay_s = tp->time_delay_s;
    pt->blend_pct = tp->transition_speed_pct;
    pt->speed_pct = tp->speed_pct;
    pt->accel_pct = tp->accel_pct;
    pt->n_aux = (uint8_t)tp->aux_commands_count;
    for (int a = 0; a < pt->n_aux; a++) {
        aux_t ax;
        char why[96];
        if (parse_aux(tp->aux_commands[a], &ax, why, sizeof why) != 0 ||
            check_aux_io(core, &ax, why, sizeof why) != 0) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathLoad point %d: aux command '%s': %s", k,
                            tp->aux_commands[a], why);
        }
        snprintf(pt->aux[a], sizeof pt->aux[a], "%s", tp->aux_commands[a]);
    }
    return 0;
}

int32_t ls_h_path_load(struct ls_core *core, struct ls_call *call)
{
    const ls_PathLoadReq *r = &call->req->cmd.path_load;
    if (core->model == NULL) {
        return no_arm(call, "pathLoad");
    }
    int32_t named = check_name(call, "pathLoad", "path_name", r->path_name);
    if (named != 0) {
        return named;
    }
    if (r->number_of_points < 1 || (pb_size_t)r->number_of_points != r->tags_count) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: number_of_points %d must equal the number of points sent (%u) and be >= 1",
                        (int)r->number_of_points, (unsigned)r->tags_count);
    }
    if (r->frame != ls_ReferenceFrame_JOINT_FRAME && r->frame != ls_ReferenceFrame_BASE_CARTESIAN_FRAME &&
        r->frame != ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: frame must be JOINT_FRAME, BASE_CARTESIAN_FRAME or WORLD_CARTESIAN_FRAME");
    }
    if (r->motion_type != ls_MotionType_JOINT_MOTION && r->motion_type != ls_MotionType_STRAIGHT_MOTION) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: motion_type must be JOINT_MOTION or STRAIGHT_MOTION");
    }
    if (r->motion_type == ls_MotionType_STRAIGHT_MOTION && r->frame == ls_ReferenceFrame_JOINT_FRAME) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: STRAIGHT_MOTION needs Cartesian points (BASE_ or WORLD_CARTESIAN_FRAME)");
    }
    int i = path_find(r->path_name);
    if (i >= 0 && path_running(core, i)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "pathLoad: path '%s' belongs to a stopped motion: abortMotion first", r->path_name);
    }
    if (i < 0) {
        for (int k = 0; k < LS_PATH_MAX; k++) {
            if (!g_paths[k].used) {
                i = k;
                break;
            }
        }
        if (i < 0) {
            return ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                            "pathLoad: all %d path queues are in use: pathClearPath one first", LS_PATH_MAX);
        }
    }
    path_t *p = &g_paths[i];
    const uint16_t have = p->used ? p->n : 0;
    if ((size_t)have + r->tags_count > LS_PATH_MAX_POINTS) {
        return ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                        "pathLoad: path '%s' holds %u points, %u more exceed its %d", r->path_name, (unsigned)have,
                        (unsigned)r->tags_count, LS_PATH_MAX_POINTS);
    }
    /* Validate every point into the free tail first: the path changes only
     * when all of them are good. */
    for (int k = 0; k < (int)r->tags_count; k++) {
        int32_t code = load_point(core, call, r, k, &p->pt[have + k]);
        if (code != 0) {
            return code;
        }
    }
    if (!p->used) {
        p->used = true;
        snprintf(p->name, sizeof p->name, "%s", r->path_name);
    }
    p->n = (uint16_t)(have + r->tags_count);
    call->res->result.path_load.points_in_path = p->n;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "path '%s' holds %u points", p->name, (unsigned)p->n);
}

int32_t ls_h_path_clear_path(struct ls_core *core, struct ls_call *call)
{
    (void)core;
    const char *name = call->req->cmd.path_clear_path.path_name;
    int i = path_find(name);
    if (i < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathClearPath: there is no path named '%s'", name);
    }
    if (path_running(core, i)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "pathClearPath: path '%s' belongs to a stopped motion: abortMotion clears it", name);
    }
    path_delete(i);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "path '%s' deleted", name);
}

/* Resolve point k against the previous position (q_prev, tip pose P_prev)
 * and plan its segment into s. *straight_out and the target are kept for
 * the segment that closes a cycle. */
static int plan_point(ls_core_t *core, const path_point_t *pt, const double q_prev[LS_N_JOINTS],
                      const double P_prev[16], ls_motion_seg_t *s, double q_target[LS_N_JOINTS], double P_target[16],
                      char *why, unsigned whylen)
{
    const ls_settings_t *set = &core->settings;
    const double sf = (pt->speed_pct > 0.0 ? pt->speed_pct : set->speed_pct) / 100.0;
    const double af = (pt->accel_pct > 0.0 ? pt->accel_pct : set->accel_pct) / 100.0;
    double tool[16];
    tool_pose(core, tool);
    if (pt->frame == ls_ReferenceFrame_JOINT_FRAME) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q_target[j] = pt->v[j] + (pt->relative ? q_prev[j] : 0.0);
        }
        tip_of(core, q_target, P_target);
        return ls_motion_seg_joint(s, core->model, q_prev, q_target, sf, af, why, whylen);
    }
    double F[16], T[16];
    const double zero[6] = { 0 };
    if (pt->frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        world_pose(core, F);
    } else {
        ls_pose_from_xyzrpy(zero, F);
    }
    if (pt->relative) {
        offset_in_frame(F, P_prev, pt->v, P_target);
    } else {
        ls_pose_from_xyzrpy(pt->v, T);
        ls_pose_mul(F, T, P_target);
    }
    if (pt->straight) {
        ls_motion_cart_limits_t lim;
        cart_limits(core, pt->speed_pct, &lim);
        int st = ls_motion_seg_line(s, core->model, q_prev, tool, P_target, &lim, why, whylen);
        memcpy(q_target, s->q1, LS_N_JOINTS * sizeof(double));
        return st;
    }
    double tinv[16], Fl[16];
    ls_pose_inv(tool, tinv);
    ls_pose_mul(P_target, tinv, Fl);
    int ks = ls_kin_ik_nearest(core->model, Fl, q_prev, q_target);
    if (ks != LS_KIN_OK) {
        snprintf(why, whylen, "no joint solution for tip (%.4g, %.4g, %.4g) m (%s)", P_target[12], P_target[13],
                 P_target[14],
                 ks == LS_KIN_ELIMITS ? "beyond the joint limits"
                                      : (ks == LS_KIN_ESINGULAR ? "shoulder singularity" : "out of reach"));
        return LS_MOTION_ERANGE;
    }
    return ls_motion_seg_joint(s, core->model, q_prev, q_target, sf, af, why, whylen);
}

static void copy_point_attrs(ls_motion_seg_t *s, const path_point_t *pt, int k)
{
    memcpy(s->tag, pt->tag, sizeof s->tag);
    s->tag_index = pt->tag_index;
    s->point = k;
    s->delay_s = pt->delay_s;
    s->n_aux = pt->n_aux;
    memcpy(s->aux, pt->aux, sizeof s->aux);
    s->overlap_s = 0.0;
}

/* Plan every segment of path `p` from q_start into g_prog. Returns 0 or the
 * planner status with `why` naming the point. */
static int build_program(ls_core_t *core, const path_t *p, const double q_start[LS_N_JOINTS], int32_t cycles, char *why,
                         unsigned whylen)
{
    double q_prev[LS_N_JOINTS], P_prev[16], q_first[LS_N_JOINTS], P_first[16];
    memcpy(q_prev, q_start, sizeof q_prev);
    tip_of(core, q_prev, P_prev);
    char w[112];
    for (int k = 0; k < p->n; k++) {
        ls_motion_seg_t *s = &g_prog.seg[k];
        copy_point_attrs(s, &p->pt[k], k);
        double q_t[LS_N_JOINTS], P_t[16];
        int st = plan_point(core, &p->pt[k], q_prev, P_prev, s, q_t, P_t, w, sizeof w);
        if (st < 0) {
            snprintf(why, whylen, "point %d: %s", k, w);
            return st;
        }
        if (k == 0) {
            memcpy(q_first, s->q1, sizeof q_first);
            memcpy(P_first, P_t, sizeof P_first);
        }
        memcpy(q_prev, s->q1, sizeof q_prev);
        memcpy(P_prev, P_t, sizeof P_prev);
    }
    g_prog.n = p->n;
    if (cycles > 1) {
        /* Close the cycle: from the last point back to point 0's position
         * (relative points were resolved once, against the start). */
        ls_motion_seg_t *s = &g_prog.seg[p->n];
        const path_point_t *pt0 = &p->pt[0];
        copy_point_attrs(s, pt0, 0);
        int st;
        if (pt0->frame != ls_ReferenceFrame_JOINT_FRAME && pt0->straight) {
            ls_motion_cart_limits_t lim;
            cart_limits(core, pt0->speed_pct, &lim);
            double tool[16];
            tool_pose(core, tool);
            st = ls_motion_seg_line(s, core->model, q_prev, tool, P_first, &lim, w, sizeof w);
            if (st == 0) {
                for (int j = 0; j < LS_N_JOINTS; j++) {
                    if (fabs(s->q1[j] - q_first[j]) > 1e-6) {
                        snprintf(w, sizeof w, "the line back to it ends in another arm configuration (joint %d)",
                                 j + 1);
                        st = LS_MOTION_ERANGE;
                        break;
                    }
                }
            }
        } else {
            const double sf = (pt0->speed_pct > 0.0 ? pt0->speed_pct : core->settings.speed_pct) / 100.0;
            const double af = (pt0->accel_pct > 0.0 ? pt0->accel_pct : core->settings.accel_pct) / 100.0;
            st = ls_motion_seg_joint(s, core->model, q_prev, q_first, sf, af, w, sizeof w);
        }
        if (st < 0) {
            snprintf(why, whylen, "point 0 (start of cycle 2): %s", w);
            return st;
        }
    }
    /* Blends: each point with the segment that follows it. */
    for (int k = 0; k < p->n; k++) {
        const ls_motion_seg_t *nx = k + 1 < p->n ? &g_prog.seg[k + 1] : (cycles > 1 ? &g_prog.seg[p->n] : NULL);
        ls_motion_seg_blend(&g_prog.seg[k], nx, p->pt[k].blend_pct / 100.0);
    }
    if (cycles > 1) {
        const ls_motion_seg_t *nx = p->n > 1 ? &g_prog.seg[1] : &g_prog.seg[p->n];
        ls_motion_seg_blend(&g_prog.seg[p->n], nx, p->pt[0].blend_pct / 100.0);
    }
    return 0;
}

int32_t ls_h_path_move(struct ls_core *core, struct ls_call *call)
{
    const ls_PathMoveReq *r = &call->req->cmd.path_move;
    if (core->ctl == NULL || core->model == NULL) {
        return no_arm(call, "pathMove");
    }
    int i = path_find(r->path_name);
    if (i < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathMove: there is no path named '%s': pathLoad it first",
                        r->path_name);
    }
    /* An absent number_of_cycles is 1 by now (seed 3.5.2; the schema's
     * (ls.absent_means), applied by the dispatcher): only an explicit 0 is
     * a dry run. */
    if (r->number_of_cycles < 0 || r->number_of_cycles > LS_PATH_MAX_CYCLES) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "pathMove: number_of_cycles %d is out of range [0, %d] (0: dry run)", (int)r->number_of_cycles,
                        LS_PATH_MAX_CYCLES);
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (snap.phase != LS_MOTION_IDLE) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "pathMove: the executor still holds a motion; try again");
    }
    int32_t code = 0;
    ls_motion_plan_t *slot = take_slot(core, call, "pathMove", &code);
    if (slot == NULL) {
        return code;
    }
    const bool dry = r->number_of_cycles == 0;
    const int32_t cycles = dry ? 1 : r->number_of_cycles;
    char why[160];
    int st = build_program(core, &g_paths[i], snap.q_cmd_rad, cycles, why, sizeof why);
    if (st < 0) {
        return plan_refused(call, st, "pathMove", why);
    }
    (void)ls_motion_plan_path(slot, &g_prog, cycles, dry, r->path_name);
    snprintf(g_tag_path, sizeof g_tag_path, "%s", r->path_name);
    g_tag_last[0] = '\0';
    int32_t started = start_plan(core, call, slot, "pathMove", r->path_name, i);
    if (started == ls_RetCode_CMD_STARTED_OK && dry) {
        /* Every notice of a dry run says so (its tag events and its final notice). */
        core->run.dry_run = true;
        return ls_reply(call, ls_RetCode_CMD_STARTED_OK,
                        "pathMove started as a dry run (number_of_cycles 0): one cycle without auxiliary "
                        "commands; expect pathMoveComplete with dry_run=true, or an alarm");
    }
    return started;
}
