/* Seed 3.4-3.5: single moves (moveAbsolute, moveRelative, moveArc),
 * stopMotion, resumeMotion, abortMotion and getTagId.
 *
 * Handlers run in the comms thread. They convert the user's units to SI,
 * plan into the control loop's plan slot (the planners sample and check the
 * whole motion before anything moves) and hand the plan over; the executor
 * reports back through ls_core_on_motion_event (cmd_motion_events.c). The
 * motion being run is core->run (ls_run.h), shared with moveReact and
 * comply: its one final notice goes through ls_run_finish. */
#include <math.h>
#include <string.h>

#include "cmd_motion.h"
#include "landscape.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

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
        return ls_mcmd_no_arm(call, what);
    }
    int32_t code = ls_mcmd_check_speed_pct(call, speed_pct);
    if (code == 0) {
        code = ls_mcmd_check_name(call, what, "point_name", point);
    }
    if (code != 0) {
        return code;
    }
    if (!ls_mcmd_all_finite(values, n_values)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: values must be finite numbers", what);
    }
    ls_ctl_snapshot_t snap;
    (void)ls_mcmd_snapshot(core, &snap);
    const double *q0 = snap.q_cmd_rad;
    ls_motion_plan_t *slot = ls_mcmd_take_slot(core, call, what, &code);
    if (slot == NULL) {
        return code;
    }
    char why[LS_MOTION_WHY_LEN];
    int st;
    const ls_settings_t *set = &core->settings;
    const ls_units_t un = ls_core_units(core, call->sup);
    if (frame == ls_ReferenceFrame_JOINT_FRAME) {
        if (n_values != LS_N_JOINTS) {
            return count_error(call, what, "values", n_values, LS_N_JOINTS);
        }
        double q1[LS_N_JOINTS];
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q1[j] = values[j] * ls_units_to_si_angular(un.angular, 1.0) + (relative ? q0[j] : 0.0);
        }
        if (ls_mcmd_joints_within(core, un, q1, why, sizeof why) != LS_OK) {
            return ls_mcmd_refused(call, LS_ERANGE, what, why);
        }
        const double sf = (speed_pct > 0.0 ? speed_pct : set->speed_pct) / 100.0;
        st = ls_motion_plan_joint(slot, core->model, q0, q1, sf, set->accel_pct / 100.0, why, sizeof why);
    } else if (frame == ls_ReferenceFrame_BASE_CARTESIAN_FRAME || frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME ||
               (frame == ls_ReferenceFrame_TOOL_FRAME && relative)) {
        if (n_values != 6) {
            return count_error(call, what, "values", n_values, 6);
        }
        code = ls_mcmd_check_pose(core, call, what, "values", values, un, relative);
        if (code != 0) {
            return code;
        }
        double d[6], P0[16], P1[16], W[16], T[16];
        ls_units_pose_to_si(un.linear, un.angular, values, d);
        ls_mcmd_tip_of(core, q0, P0);
        ls_mcmd_world_pose(core, W);
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
            ls_mcmd_offset_in_frame(frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME ? W : I, P0, d, P1);
        }
        if (ls_mcmd_tip_within(core, un, &P1[12], why, sizeof why) != LS_OK) {
            return ls_mcmd_refused(call, LS_ERANGE, what, why);
        }
        ls_motion_cart_limits_t lim;
        ls_mcmd_cart_limits(core, speed_pct, 0.0, &lim);
        double tool[16];
        ls_mcmd_tool_pose(core, tool);
        st = ls_motion_plan_line(slot, core->model, q0, tool, P1, &lim, why, sizeof why);
    } else {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: frame %d is not valid here (JOINT_FRAME, BASE_CARTESIAN_FRAME, WORLD_CARTESIAN_FRAME%s)",
                        what, (int)frame, relative ? ", TOOL_FRAME" : "");
    }
    if (st < 0) {
        return ls_mcmd_refused(call, st, what, why);
    }
    ls_motion_slowdown_t slow;
    const bool slowed =
        ls_motion_seg_slowdown(&slot->one, &slow) && ls_motion_slowdown_text(&slow, why, sizeof why) >= 0;
    return ls_mcmd_start_plan(core, call, slot, what, point, LS_PATH_NONE, slowed ? why : NULL);
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
        return ls_mcmd_no_arm(call, "moveArc");
    }
    if (r->frame != ls_ReferenceFrame_BASE_CARTESIAN_FRAME && r->frame != ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "moveArc: an arc is Cartesian: use BASE_CARTESIAN_FRAME or WORLD_CARTESIAN_FRAME");
    }
    int32_t named = ls_mcmd_check_name(call, "moveArc", "point_name", r->point_name);
    if (named != 0) {
        return named;
    }
    if (r->arc_value_count != 6 || r->goal_value_count != 6) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "moveArc: arc_value and goal_value need 6 values each (x y z roll pitch yaw), got %u and %u",
                        (unsigned)r->arc_value_count, (unsigned)r->goal_value_count);
    }
    if (!ls_mcmd_all_finite(r->arc_value, 6) || !ls_mcmd_all_finite(r->goal_value, 6)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "moveArc: values must be finite numbers");
    }
    const ls_units_t un = ls_core_units(core, call->sup);
    named = ls_mcmd_check_pose(core, call, "moveArc", "arc_value", r->arc_value, un, true);
    if (named == 0) {
        named = ls_mcmd_check_pose(core, call, "moveArc", "goal_value", r->goal_value, un, true);
    }
    if (named != 0) {
        return named;
    }
    ls_ctl_snapshot_t snap;
    (void)ls_mcmd_snapshot(core, &snap);
    const double *q0 = snap.q_cmd_rad;
    int32_t code = 0;
    ls_motion_plan_t *slot = ls_mcmd_take_slot(core, call, "moveArc", &code);
    if (slot == NULL) {
        return code;
    }
    double P0[16], W[16], F[16], via[16], goal[16];
    ls_mcmd_tip_of(core, q0, P0);
    ls_mcmd_world_pose(core, W);
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
        ls_units_pose_to_si(un.linear, un.angular, src[k], d);
        if (r->offset_type == ls_OffsetType_RELATIVE_DATA) {
            ls_mcmd_offset_in_frame(F, P0, d, dst[k]);
        } else {
            ls_pose_from_xyzrpy(d, T);
            ls_pose_mul(F, T, dst[k]);
        }
    }
    ls_motion_cart_limits_t lim;
    ls_mcmd_cart_limits(core, 0.0, 0.0, &lim);
    double tool[16];
    ls_mcmd_tool_pose(core, tool);
    char why[LS_MOTION_WHY_LEN];
    int st = ls_motion_plan_arc(slot, core->model, q0, tool, via, goal, &lim, why, sizeof why);
    if (st < 0) {
        return ls_mcmd_refused(call, st, "moveArc", why);
    }
    ls_motion_slowdown_t slow;
    const bool slowed =
        ls_motion_seg_slowdown(&slot->one, &slow) && ls_motion_slowdown_text(&slow, why, sizeof why) >= 0;
    return ls_mcmd_start_plan(core, call, slot, "moveArc", r->point_name, LS_PATH_NONE, slowed ? why : NULL);
}

int32_t ls_h_stop_motion(struct ls_core *core, struct ls_call *call)
{
    if (core->ctl == NULL) {
        return ls_mcmd_no_arm(call, "stopMotion");
    }
    if (!ls_mcmd_post(core, LS_CTL_STOP, call->req->seq)) {
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
        return ls_mcmd_no_arm(call, "resumeMotion");
    }
    if (!ls_mcmd_post(core, LS_CTL_RESUME, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "resumeMotion: the control loop's command queue is full; try again");
    }
    core->state = ls_State_MOVING;
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_RUNNING_TRAJECTORY_CHOICE);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "resumed along the planned path");
}

int32_t ls_h_abort_motion(struct ls_core *core, struct ls_call *call)
{
    if (core->ctl != NULL && !ls_mcmd_post(core, LS_CTL_ABORT, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "abortMotion: the control loop's command queue is full; try again");
    }
    bool had = core->run.active;
    if (had) {
        const int path = core->run.path;
        ls_run_finish(core, LS_RUN_END_ABORT, NULL, 0);
        ls_path_delete(core, path);
    }
    if (core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_COMMAND_CHOICE);
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s",
                    had ? "motion dropped and its path queue cleared" : "nothing to abort: no motion was held");
}

int32_t ls_h_get_tag_id(struct ls_core *core, struct ls_call *call)
{
    ls_GetTagIdRes *r = &call->res->result.get_tag_id;
    ls_fmt_print(r->path_name, sizeof r->path_name, "%s", core->motion.tag_path);
    ls_fmt_print(r->tag_id, sizeof r->tag_id, "%s", core->motion.tag_last);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s",
                    core->motion.tag_last[0] != '\0' ? "last tag reached" : "no tag reached yet");
}
