/* What the motion handlers share (cmd_move.c, cmd_path.c,
 * cmd_path_program.c, cmd_aux.c, cmd_motion_events.c, and the sensor-guided
 * moves of cmd_sensor.c): pose maths of the tool and the world frame, the
 * Cartesian limits of the settings, parameter checks, and handing a plan to
 * the control loop. Comms thread only. */
#include <math.h>
#include <string.h>

#include "cmd_drives.h"
#include "cmd_motion.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

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
/* A path point keeps every auxiliary command the schema lets through, and
 * its storage is the motion library's (cmd_path_program.c copies it whole):
 * the two counts must agree, or a larger max_count would overflow pt->aux. */
_Static_assert(pb_arraysize(ls_TagPoint, aux_commands) == LS_MOTION_AUX_PER_POINT,
               "ls.TagPoint.aux_commands max_count (protocol/landscape.options) must equal "
               "LS_MOTION_AUX_PER_POINT (firmware/motion/ls_motion.h)");
_Static_assert(sizeof(((ls_GetTagIdRes *)0)->path_name) >= LS_MOTION_NAME_LEN, "getTagId must hold a path name");
_Static_assert(sizeof(((ls_GetTagIdRes *)0)->tag_id) >= LS_MOTION_NAME_LEN, "getTagId must hold a tag");

/* A planner's refusal reaches the user whole (docs/protocol.md "Limits"):
 * the answer holds the longest command name, "refused, nothing moved: ",
 * the path builder's point prefix and the planner's text. */
#define REFUSED_PREFIX_LEN (sizeof "moveRelative refused, nothing moved: " - 1)
_Static_assert(sizeof(((ls_Response *)0)->ret_msg) >= REFUSED_PREFIX_LEN + LS_MCMD_WHY_LEN,
               "landscape.options: ls.Response.ret_msg must hold a planner's refusal whole");

int32_t ls_mcmd_refused(ls_call_t *call, int status, const char *what, const char *why)
{
    /* what is one of the motion commands' names, none longer than moveRelative */
    int32_t code = status == LS_ERANGE ? ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR : ls_RetCode_CMD_PARAM_ERR;
    return ls_reply(call, code, "%s refused, nothing moved: %s", what, why);
}

int ls_mcmd_joints_within(const ls_core_t *core, ls_units_t un, const double q_rad[LS_N_JOINTS], char *why,
                          size_t whylen)
{
    const double per = ls_units_to_si_angular(un.angular, 1.0);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const double lo = core->model->q_min_rad[j], hi = core->model->q_max_rad[j];
        if (q_rad[j] < lo || q_rad[j] > hi) {
            const char *sym = ls_units_angular_symbol(un.angular);
            ls_fmt_print(why, whylen, "joint %d: %.4g %s beyond its limit %.4g %s", j + 1, q_rad[j] / per, sym,
                         (q_rad[j] < lo ? lo : hi) / per, sym);
            return LS_ERANGE;
        }
    }
    return LS_OK;
}

int ls_mcmd_tip_within(const ls_core_t *core, ls_units_t un, const double p_m[3], char *why, size_t whylen)
{
    static const char *const ax[3] = { "x", "y", "z" };
    const double per = ls_units_to_si_linear(un.linear, 1.0);
    for (int i = 0; i < 3; i++) {
        const double lo = core->model->workspace_min_m[i], hi = core->model->workspace_max_m[i];
        if (p_m[i] < lo || p_m[i] > hi) {
            const char *sym = ls_units_linear_symbol(un.linear);
            ls_fmt_print(why, whylen, "axis %s: %.4g %s beyond the workspace limit %.4g %s (base frame, tool tip)",
                         ax[i], p_m[i] / per, sym, (p_m[i] < lo ? lo : hi) / per, sym);
            return LS_ERANGE;
        }
    }
    return LS_OK;
}

bool ls_mcmd_snapshot(ls_core_t *core, ls_ctl_snapshot_t *snap)
{
    if (core->ctl == NULL) {
        return false;
    }
    ls_control_snapshot(core->ctl, snap);
    return true;
}

void ls_mcmd_tool_pose(const ls_core_t *core, double T[16])
{
    ls_pose_from_xyzrpy(core->settings.tool_offset, T);
}

void ls_mcmd_world_pose(const ls_core_t *core, double T[16])
{
    ls_pose_from_xyzrpy(core->settings.world_frame, T);
}

void ls_mcmd_cart_limits(const ls_core_t *core, double speed_pct, double accel_pct, ls_motion_cart_limits_t *lim)
{
    const ls_robot_model_t *m = core->model;
    const ls_settings_t *st = &core->settings;
    /* A percent of the move or point wins; else the kind of the most recent
     * setSpeed / setAcceleration call: PERCENT_* scales the model's
     * Cartesian maxima (seed 3.2.1: "globally to both joint and Cartesian
     * moves"), LINEAR_* / ANGULAR_* give the values themselves. */
    const double sp = speed_pct > 0.0 ? speed_pct : (st->cart_speed_from_pct ? st->speed_pct : 0.0);
    const double ap = accel_pct > 0.0 ? accel_pct : (st->cart_accel_from_pct ? st->accel_pct : 0.0);
    lim->v_lin_m_s = sp > 0.0 ? m->max_linear_speed_m_s * sp / 100.0 : st->linear_speed_m_s;
    lim->v_ang_rad_s = sp > 0.0 ? m->max_angular_speed_rad_s * sp / 100.0 : st->angular_speed_rad_s;
    lim->a_lin_m_s2 = ap > 0.0 ? m->max_linear_accel_m_s2 * ap / 100.0 : st->linear_accel_m_s2;
    lim->a_ang_rad_s2 = ap > 0.0 ? m->max_angular_accel_rad_s2 * ap / 100.0 : st->angular_accel_rad_s2;
    lim->v_lin_m_s = fmin(lim->v_lin_m_s, m->max_linear_speed_m_s);
    lim->v_ang_rad_s = fmin(lim->v_ang_rad_s, m->max_angular_speed_rad_s);
    lim->a_lin_m_s2 = fmin(lim->a_lin_m_s2, m->max_linear_accel_m_s2);
    lim->a_ang_rad_s2 = fmin(lim->a_ang_rad_s2, m->max_angular_accel_rad_s2);
    /* Jerk follows the acceleration's share of the maximum. */
    lim->j_lin_m_s3 = ls_robot_model_linear_jerk(m, lim->a_lin_m_s2);
    lim->j_ang_rad_s3 = ls_robot_model_angular_jerk(m, lim->a_ang_rad_s2);
    lim->joint_speed_frac = 1.0;
}

int32_t ls_mcmd_check_speed_pct(ls_call_t *call, double pct)
{
    if (!isfinite(pct) || (pct != 0.0 && pct < LS_RATE_MIN_PCT) || pct > 100.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "speed %.4g %% is out of range: give 0 (the current setSpeed) or a value in [%g, 100]", pct,
                        LS_RATE_MIN_PCT);
    }
    return 0;
}

/* Names of points and paths are not empty (docs/protocol.md "Limits"). */
int32_t ls_mcmd_check_name(ls_call_t *call, const char *what, const char *field, const char *name)
{
    if (name[0] == '\0') {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: %s is empty: give the %s a name", what, field,
                        field[0] == 'p' && field[1] == 'a' ? "path" : "point");
    }
    return 0;
}

bool ls_mcmd_all_finite(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(v[i])) {
            return false;
        }
    }
    return true;
}

int32_t ls_mcmd_check_pose(const ls_core_t *core, ls_call_t *call, const char *what, const char *field, const double *v,
                           ls_units_t un, bool translations)
{
    static const char *const names[6] = { "x", "y", "z", "roll", "pitch", "yaw" };
    const double reach_m = LS_POSE_REACH_FACTOR * ls_robot_model_reach_m(core->model);
    for (int i = translations ? 0 : 3; i < 6; i++) {
        const bool angle = i >= 3;
        const double si = angle ? ls_units_to_si_angular(un.angular, v[i]) : ls_units_to_si_linear(un.linear, v[i]);
        const double max_si = angle ? LS_FRAME_ANGLE_MAX_RAD : reach_m;
        if (fabs(si) > max_si) {
            const double max =
                angle ? ls_units_from_si_angular(un.angular, max_si) : ls_units_from_si_linear(un.linear, max_si);
            const char *unit = angle ? ls_units_angular_name(un.angular) : ls_units_linear_name(un.linear);
            return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                            "%s: %s %s %g %s is out of range: allowed [-%g, %g] %s (docs/protocol.md \"Limits\")", what,
                            field, names[i], v[i], unit, max, max, unit);
        }
    }
    return 0;
}

/* Tool-tip pose (base frame) of the commanded joints. */
void ls_mcmd_tip_of(const ls_core_t *core, const double q[LS_N_JOINTS], double P[16])
{
    double F[16], T[16];
    ls_kin_fk(core->model, q, F);
    ls_mcmd_tool_pose(core, T);
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
void ls_mcmd_offset_in_frame(const double F[16], const double P[16], const double d[6], double out[16])
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
int32_t ls_mcmd_start_plan(ls_core_t *core, ls_call_t *call, ls_motion_plan_t *slot, const char *seed_name,
                           const char *point, int path, const char *note)
{
    slot->ref_seq = call->req->seq;
    ls_fmt_print(slot->name, sizeof slot->name, "%s", point);
    if (!ls_control_start_plan(core->ctl, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: the control loop's command queue is full; try again",
                        seed_name);
    }
    ls_run_begin(core, call, false, point, path);
    return ls_reply(call, ls_RetCode_CMD_STARTED_OK, "%s started: expect %sComplete or an alarm%s%s", seed_name,
                    seed_name, note != NULL ? "; " : "", note != NULL ? note : "");
}

int32_t ls_mcmd_no_arm(ls_call_t *call, const char *what)
{
    return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                    "%s: no arm is composed in this controller (start landscaped with an arm backend)", what);
}

/* The plan slot, or NULL after answering CMD_BUSY_ERR in *code. */
ls_motion_plan_t *ls_mcmd_take_slot(ls_core_t *core, ls_call_t *call, const char *what, int32_t *code)
{
    if (ls_drv_refuse_unhomed(core, call, what, code)) {
        return NULL;
    }
    ls_motion_plan_t *slot = ls_control_plan_slot(core->ctl);
    if (slot == NULL && ls_control_manual_on(core->ctl)) {
        *code = ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: manualControl is on: send manualControl off first", what);
    } else if (slot == NULL) {
        *code = ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                         "%s: the control loop has not taken the previous motion yet; try again", what);
    }
    return slot;
}

bool ls_mcmd_post(ls_core_t *core, ls_ctl_kind_t kind, uint32_t ref_seq)
{
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.ref_seq = ref_seq;
    return ls_control_post(core->ctl, &c);
}
