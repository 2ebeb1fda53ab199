/* Seed 3.8: getEndEffectorState, getTool, putTool, activateTool,
 * deactivateTool.
 *
 * A tool change is a blocking command answered when done (LS_CALL_DEFERRED):
 * a joint move to the approach point above the tool's rack pose, a straight
 * line down to the rack pose, coupling (or uncoupling) in the control loop,
 * a straight line back up. Each step is started here when the loop reports
 * the previous one (the loop's events reach ls_core_tool_on_event first:
 * ls_core.c, on_loop_event). The tool's bits are driven in the loop as
 * well and answered when the loop reports them.
 *
 * The rack poses and tool offsets are read with the tool changer's
 * rack_pose/tool_offset from this (comms) thread: they are look-ups of
 * constant data (hal/sim); coupling and bits, which change the device, run in
 * the loop.
 *
 * State (static, one controller per process): the held tool, its bits, and
 * the tool change or bit command in progress. */
#include <math.h>
#include <string.h>

#include "cmd_drives.h"
#include "cmd_sensor.h"
#include "landscape.h"
#include "ls_control.h"
#include "ls_core_services.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_motion.h"
#include "ls_units.h"

/* A tool id the schema lets through fits the loop's command whole. */
_Static_assert(sizeof(((ls_GetToolReq *)0)->tool_id) <= LS_CTL_TOOL_ID_LEN,
               "LS_CTL_TOOL_ID_LEN must hold ls.GetToolReq.tool_id");

/* The approach point is this far from the rack pose, back along the flange's
 * z axis (the tool points into the rack). */
#define APPROACH_M 0.10
/* Speed of the straight lines into and out of the rack. */
#define RACK_SPEED_M_S 0.05

enum { STEP_APPROACH = 1, STEP_IN, STEP_COUPLE, STEP_OUT };

/* ------------------------------------------------------------- helpers */

static bool have_changer(const ls_core_t *core)
{
    return core->tool != NULL && core->tool->ops != NULL && core->tool->ops->rack_pose != NULL;
}

static int32_t no_changer(ls_call_t *call, const char *what)
{
    return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "%s: no tool changer is composed in this controller", what);
}

static int32_t unknown_tool(ls_core_t *core, ls_call_t *call, const char *what, const char *id)
{
    char list[96] = "";
    size_t n = 0;
    const char *name = NULL;
    for (int i = 0; core->tool->ops->name != NULL && n < sizeof list &&
                    (name = core->tool->ops->name(core->tool->self, i)) != NULL;
         i++) {
        n += (size_t)ls_fmt_print(list + n, sizeof list - n, "%s%s", n ? ", " : "", name);
    }
    return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: unknown tool '%s'; the rack holds %s", what, id,
                    n > 0 ? list : "tools whose names this firmware cannot list");
}

static bool post_tool(ls_core_t *core, ls_ctl_kind_t kind, uint32_t ref_seq, const char *id, bool attach, uint32_t on,
                      uint32_t off)
{
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.ref_seq = ref_seq;
    c.tool.dev = core->tool;
    ls_fmt_print(c.tool.id, sizeof c.tool.id, "%s", id);
    c.tool.attach = attach;
    c.tool.on = on;
    c.tool.off = off;
    return ls_control_post(core->ctl, &c);
}

static void rest(ls_core_t *core)
{
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    }
}

/* End the tool change with an answer. */
static void op_end(ls_core_t *core, int32_t code, const char *msg, bool to_rest)
{
    if (!core->tool_cmds.op.active) {
        return;
    }
    core->tool_cmds.op.active = false;
    if (to_rest) {
        rest(core);
    }
    ls_core_finish_deferred(core, core->tool_cmds.op.sup, code, msg);
}

static const char *op_name(const ls_core_t *core)
{
    return core->tool_cmds.op.attach ? "getTool" : "putTool";
}

/* Plan the next motion step into the plan slot and start it. LS_OK, or with
 * why: LS_EAGAIN (the loop has not taken the previous plan, or its queue is
 * full), LS_EUNREACHABLE (the approach point), the planner's status. */
static int plan_step(ls_core_t *core, const double q0[LS_N_JOINTS], char *why, size_t whylen)
{
    ls_motion_plan_t *slot = ls_control_plan_slot(core->ctl);
    if (slot == NULL) {
        ls_fmt_print(why, whylen, "the control loop has not taken the previous motion");
        return LS_EAGAIN;
    }
    const ls_robot_model_t *m = core->model;
    char w[LS_MOTION_WHY_LEN] = "";
    int st;
    if (core->tool_cmds.op.step == STEP_APPROACH) {
        double q1[LS_N_JOINTS];
        if (ls_kin_ik_nearest(m, core->tool_cmds.op.approach, q0, q1) != LS_OK) {
            ls_fmt_print(why, whylen, "the approach point above the rack is out of reach");
            return LS_EUNREACHABLE;
        }
        const ls_settings_t *set = &core->settings;
        st = ls_motion_plan_joint(slot, m, q0, q1, set->speed_pct / 100.0, set->accel_pct / 100.0, w, sizeof w);
    } else {
        ls_motion_cart_limits_t lim = {
            .v_lin_m_s = RACK_SPEED_M_S,
            .a_lin_m_s2 = fmin(core->settings.linear_accel_m_s2, m->max_linear_accel_m_s2),
            .j_lin_m_s3 = m->max_linear_jerk_m_s3 * 0.25,
            .v_ang_rad_s = 0.5,
            .a_ang_rad_s2 = fmin(core->settings.angular_accel_rad_s2, m->max_angular_accel_rad_s2),
            .j_ang_rad_s3 = m->max_angular_jerk_rad_s3 * 0.25,
            .joint_speed_frac = 1.0,
        };
        double flange_tool[16];
        const double zero[6] = { 0 };
        ls_pose_from_xyzrpy(zero, flange_tool);
        const double *goal = core->tool_cmds.op.step == STEP_IN ? core->tool_cmds.op.rack : core->tool_cmds.op.approach;
        st = ls_motion_plan_line(slot, m, q0, flange_tool, goal, &lim, w, sizeof w);
    }
    if (st < 0) {
        ls_fmt_print(why, whylen, "%s", w);
        return st;
    }
    slot->ref_seq = core->tool_cmds.op.ref_seq;
    ls_fmt_print(slot->name, sizeof slot->name, "%s", core->tool_cmds.op.id);
    if (!ls_control_start_plan(core->ctl, core->tool_cmds.op.ref_seq)) {
        ls_fmt_print(why, whylen, "the control loop's command queue is full");
        return LS_EAGAIN;
    }
    return LS_OK;
}

static void step_failed(ls_core_t *core, const char *why)
{
    char msg[LS_MOTION_WHY_LEN + 128]; /* why (a planner's text) whole, with a 63-byte tool id */
    ls_fmt_print(msg, sizeof msg, "%s %s stopped at step %d: %s; the arm holds where it is", op_name(core),
                 core->tool_cmds.op.id, core->tool_cmds.op.step, why);
    op_end(core, ls_RetCode_CMD_ERR, msg, true);
}

/* ------------------------------------------------------------- getTool, putTool */

static int32_t change(ls_core_t *core, ls_call_t *call, const char *id, bool attach)
{
    const char *what = attach ? "getTool" : "putTool";
    if (core->ctl == NULL || core->model == NULL) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "%s: no arm is composed in this controller", what);
    }
    if (!have_changer(core)) {
        return no_changer(call, what);
    }
    if (ls_control_manual_on(core->ctl)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: manualControl is on: send manualControl off first", what);
    }
    double rack6[6];
    if (strcmp(id, "none") == 0 || core->tool->ops->rack_pose(core->tool->self, id, rack6) != LS_OK) {
        return unknown_tool(core, call, what, id);
    }
    bool holding = strcmp(core->tool_cmds.held, "none") != 0;
    if (attach && holding) {
        return ls_reply(call, ls_RetCode_CMD_ERR, "getTool %s: holding %s: put back %s first (putTool %s)", id,
                        core->tool_cmds.held, core->tool_cmds.held, core->tool_cmds.held);
    }
    if (!attach && !holding) {
        return ls_reply(call, ls_RetCode_CMD_ERR, "putTool %s: no tool is held, nothing to put back", id);
    }
    if (!attach && strcmp(core->tool_cmds.held, id) != 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "putTool %s: the held tool is %s: putTool %s", id,
                        core->tool_cmds.held, core->tool_cmds.held);
    }
    if (core->tool_cmds.op.active) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: a tool change is in progress", what);
    }
    int32_t code = 0;
    if (ls_drv_refuse_unhomed(core, call, what, &code)) {
        return code;
    }
    ls_tool_op_t op;
    memset(&op, 0, sizeof op);
    op.attach = attach;
    op.sup = call->sup;
    op.ref_seq = call->req->seq;
    op.step = STEP_APPROACH;
    ls_fmt_print(op.id, sizeof op.id, "%s", id);
    ls_pose_from_xyzrpy(rack6, op.rack);
    memcpy(op.approach, op.rack, sizeof op.approach);
    for (int i = 0; i < 3; i++) {
        op.approach[12 + i] -= APPROACH_M * op.rack[8 + i]; /* back along the flange z axis */
    }
    if (attach && (core->tool->ops->tool_offset == NULL ||
                   core->tool->ops->tool_offset(core->tool->self, id, op.offset) != LS_OK)) {
        return ls_reply(call, ls_RetCode_CMD_ERR, "getTool %s: the tool changer does not know its offset", id);
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    core->tool_cmds.op = op;
    char why[LS_MOTION_WHY_LEN];
    if (plan_step(core, snap.q_cmd_rad, why, sizeof why) != LS_OK) {
        core->tool_cmds.op.active = false;
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s %s refused, nothing moved: %s", what, id, why);
    }
    core->tool_cmds.op.active = true;
    core->state = ls_State_MOVING;
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_CHANGING_TOOL_CHOICE);
    return LS_CALL_DEFERRED;
}

int32_t ls_h_get_tool(struct ls_core *core, struct ls_call *call)
{
    return change(core, call, call->req->cmd.get_tool.tool_id, true);
}

int32_t ls_h_put_tool(struct ls_core *core, struct ls_call *call)
{
    return change(core, call, call->req->cmd.put_tool.tool_id, false);
}

/* ------------------------------------------------------------- bits */

static int32_t bits(ls_core_t *core, ls_call_t *call, const char *id, uint32_t field, bool on)
{
    const char *what = on ? "activateTool" : "deactivateTool";
    if (core->ctl == NULL || !have_changer(core)) {
        return no_changer(call, what);
    }
    if (strcmp(core->tool_cmds.held, id) != 0 || strcmp(id, "none") == 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s %s: the held tool is %s%s", what, id, core->tool_cmds.held,
                        strcmp(core->tool_cmds.held, "none") == 0 ? " (getTool first)" : "");
    }
    if (field == 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s %s: bit_field is 0: name the bits to %s", what, id,
                        on ? "set" : "clear");
    }
    if (core->tool_cmds.bits_op.active) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: the previous tool bit command is still running", what);
    }
    if (!post_tool(core, LS_CTL_TOOL_BITS, call->req->seq, id, false, on ? field : 0u, on ? 0u : field)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: the control loop's command queue is full; try again", what);
    }
    core->tool_cmds.bits_op =
        (ls_bits_op_t){ .active = true, .on = on, .sup = call->sup, .ref_seq = call->req->seq, .bits = field };
    return LS_CALL_DEFERRED;
}

int32_t ls_h_activate_tool(struct ls_core *core, struct ls_call *call)
{
    const ls_ActivateToolReq *r = &call->req->cmd.activate_tool;
    return bits(core, call, r->tool_id, r->bit_field, true);
}

int32_t ls_h_deactivate_tool(struct ls_core *core, struct ls_call *call)
{
    const ls_DeactivateToolReq *r = &call->req->cmd.deactivate_tool;
    return bits(core, call, r->tool_id, r->bit_field, false);
}

int32_t ls_h_get_end_effector_state(struct ls_core *core, struct ls_call *call)
{
    ls_GetEndEffectorStateRes *r = &call->res->result.get_end_effector_state;
    ls_fmt_print(r->current_ee, sizeof r->current_ee, "%s", core->tool_cmds.held);
    if (strcmp(core->tool_cmds.held, "none") == 0) {
        ls_fmt_print(r->ee_state, sizeof r->ee_state, "flange (no tool)");
    } else {
        ls_fmt_print(r->ee_state, sizeof r->ee_state, "bits=0x%X", (unsigned)core->tool_cmds.bits);
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s%s", have_changer(core) ? "" : "no tool changer: ",
                    strcmp(core->tool_cmds.held, "none") == 0 ? "no tool held" : "tool held");
}

/* ------------------------------------------------------------- loop events */

static void bits_event(ls_core_t *core, const ls_ctl_event_t *ev)
{
    core->tool_cmds.bits_op.active = false;
    core->tool_cmds.bits = ev->dio.on;
    char msg[160];
    int st = ev->motion.index;
    if (st < 0) {
        ls_fmt_print(msg, sizeof msg, "%s: bits 0x%X refused by %.31s (HAL status %d): the tool has no such bits",
                     core->tool_cmds.bits_op.on ? "activateTool" : "deactivateTool",
                     (unsigned)core->tool_cmds.bits_op.bits, core->tool_cmds.held, st);
        ls_core_finish_deferred(core, core->tool_cmds.bits_op.sup,
                                st == LS_EINVAL ? ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR : ls_RetCode_CMD_ERR, msg);
        return;
    }
    ls_fmt_print(msg, sizeof msg, "%s bits now 0x%X", core->tool_cmds.held, (unsigned)core->tool_cmds.bits);
    ls_core_finish_deferred(core, core->tool_cmds.bits_op.sup, ls_RetCode_CMD_EXEC_OK, msg);
}

static void coupled(ls_core_t *core, const ls_ctl_event_t *ev)
{
    int st = ev->motion.index;
    if (st < 0) {
        char why[100];
        ls_fmt_print(why, sizeof why, "the tool changer refused to %.20s (HAL status %d)", ev->motion.text, st);
        step_failed(core, why);
        return;
    }
    if (core->tool_cmds.op.attach) {
        ls_fmt_print(core->tool_cmds.held, sizeof core->tool_cmds.held, "%s", core->tool_cmds.op.id);
        memcpy(core->settings.tool_offset, core->tool_cmds.op.offset, sizeof core->settings.tool_offset);
    } else {
        ls_fmt_print(core->tool_cmds.held, sizeof core->tool_cmds.held, "none");
        memset(core->settings.tool_offset, 0, sizeof core->settings.tool_offset);
    }
    core->tool_cmds.bits = ev->dio.on;
    core->tool_cmds.op.step = STEP_OUT;
    char why[LS_MOTION_WHY_LEN];
    if (plan_step(core, core->tool_cmds.q_hold, why, sizeof why) != LS_OK) {
        step_failed(core, why);
    }
}

bool ls_core_tool_on_event(ls_core_t *core, const ls_ctl_event_t *ev)
{
    if (ev->kind == LS_CEV_MOTION && ev->motion.kind == LS_MEV_TOOL) {
        if (core->tool_cmds.bits_op.active && ev->ref_seq == core->tool_cmds.bits_op.ref_seq) {
            bits_event(core, ev);
        } else if (core->tool_cmds.op.active && ev->ref_seq == core->tool_cmds.op.ref_seq) {
            coupled(core, ev);
        }
        return true;
    }
    if (ev->kind == LS_CEV_FAULT) {
        char msg[192];
        ls_fmt_print(msg, sizeof msg, "%s %s stopped by a fault: %.60s", op_name(core), core->tool_cmds.op.id,
                     ev->text);
        op_end(core, ls_RetCode_CMD_FAULT_ERR, msg, false);
        return false;
    }
    if (!core->tool_cmds.op.active || ev->ref_seq != core->tool_cmds.op.ref_seq) {
        return false;
    }
    if (ev->kind == LS_CEV_CMD_FAILED) {
        step_failed(core, ev->text);
        return true;
    }
    if (ev->kind != LS_CEV_MOTION) {
        return false;
    }
    switch (ev->motion.kind) {
    case LS_MEV_DONE: {
        char why[LS_MOTION_WHY_LEN];
        memcpy(core->tool_cmds.q_hold, ev->motion.q_rad, sizeof core->tool_cmds.q_hold);
        if (core->tool_cmds.op.step == STEP_APPROACH) {
            core->tool_cmds.op.step = STEP_IN;
            if (plan_step(core, core->tool_cmds.q_hold, why, sizeof why) != LS_OK) {
                step_failed(core, why);
            }
        } else if (core->tool_cmds.op.step == STEP_IN) {
            core->tool_cmds.op.step = STEP_COUPLE;
            if (!post_tool(core, LS_CTL_TOOL_COUPLE, core->tool_cmds.op.ref_seq, core->tool_cmds.op.id,
                           core->tool_cmds.op.attach, 0, 0)) {
                step_failed(core, "the control loop's command queue is full");
            }
        } else {
            char msg[160];
            char off[64];
            double o[6];
            const ls_units_t un = ls_core_units(core, core->tool_cmds.op.sup); /* the answer's session */
            ls_units_pose_from_si(un.linear, un.angular, core->settings.tool_offset, o);
            ls_fmt_print(off, sizeof off, "%.4g %.4g %.4g", o[0], o[1], o[2]);
            ls_fmt_print(msg, sizeof msg, "%s: %s; tool offset now %s %s", op_name(core),
                         core->tool_cmds.op.attach ? core->tool_cmds.op.id : "flange (no tool)", off,
                         ls_units_linear_name(un.linear));
            op_end(core, ls_RetCode_CMD_EXEC_OK, msg, true);
        }
        return true;
    }
    case LS_MEV_PAUSED:
        /* stopMotion: its handler answers and pauses; the change ends here. */
        op_end(core, ls_RetCode_CMD_ERR, "tool change interrupted by stopMotion: abortMotion, then retry", false);
        return false;
    case LS_MEV_FAULT: {
        char msg[160];
        ls_fmt_print(msg, sizeof msg, "%s %.31s stopped by a fault: %.60s", op_name(core), core->tool_cmds.op.id,
                     ev->motion.text);
        op_end(core, ls_RetCode_CMD_FAULT_ERR, msg, false);
        return false;
    }
    case LS_MEV_TAG:
    case LS_MEV_AUX:
    case LS_MEV_REACT_END:
    case LS_MEV_JOG:
    case LS_MEV_TOOL:
    case LS_MEV_SLOW: return true;
    }
    return false;
}
