/* The life of a started motion: see ls_run.h. */
#include "ls_run.h"

#include <math.h>
#include <string.h>

#include "landscape.h"
#include "ls_cmd_table.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_log.h"
#include "ls_send.h"

/* "At rest": every measured joint speed below this. */
#define REST_SPEED_RAD_S 1e-3
/* Drives off and the arm still coasting: wait at most this long for rest. */
#define COAST_MAX_US 500000u

const char *ls_run_end_name(ls_run_end_t why)
{
    return ls_motion_end_text((ls_MotionEnd)why);
}

const char *ls_run_end_suffix(ls_run_end_t why)
{
    return ls_motion_end_suffix((ls_MotionEnd)why);
}

void ls_run_begin(ls_core_t *core, const ls_call_t *call, bool react, const char *point, int path)
{
    const ls_cmd_desc_t *cmd = ls_cmd_find(call->req->which_cmd);
    ls_run_t *r = &core->run;
    const ls_session_t *s = &core->sessions[call->sup];
    memset(r, 0, sizeof *r);
    r->active = true;
    r->react = react;
    r->sup = call->sup;
    r->addr = s->addr;
    r->epoch = s->epoch;
    r->ref_seq = call->req->seq;
    r->path = path;
    r->stop_sup = LS_NO_SESSION;
    r->finals = cmd != NULL ? cmd->finals : NULL;
    ls_fmt_print(r->point, sizeof r->point, "%s", point);
    core->state = ls_State_MOVING;
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_RUNNING_TRAJECTORY_CHOICE);
}

void ls_run_finish(ls_core_t *core, ls_run_end_t why, const char *const *extra, size_t n_extra)
{
    ls_run_t *r = &core->run;
    if (!r->active) {
        return;
    }
    char d_point[8 + LS_MOTION_NAME_LEN], d_reason[32];
    ls_fmt_print(d_point, sizeof d_point, "point=%s", r->point);
    ls_fmt_print(d_reason, sizeof d_reason, "reason=%s", ls_run_end_name(why));
    const char *data[9] = { d_point, d_reason };
    size_t n = 2;
    for (size_t k = 0; k < n_extra && n < sizeof data / sizeof data[0] - 1u; k++) {
        data[n++] = extra[k];
    }
    if (r->dry_run) {
        data[n++] = "dry_run=true";
    }
    const ls_EventId id = ls_motion_end_final(r->finals, (ls_MotionEnd)why);
    r->active = false;
    r->wait_active = false;
    ls_core_notify_to(core, r->addr, r->epoch, why == LS_RUN_END_COMPLETE ? ls_NoticeKind_EVENT : ls_NoticeKind_ALARM,
                      id, r->ref_seq, true, data, n);
    if (r->stop_pending) {
        r->stop_pending = false;
        char msg[120];
        ls_fmt_print(msg, sizeof msg, "the motion ended (%s) before it paused", ls_run_end_name(why));
        ls_core_finish_deferred(core, r->stop_sup,
                                why == LS_RUN_END_COMPLETE ? ls_RetCode_CMD_EXEC_OK : ls_RetCode_CMD_ERR,
                                why == LS_RUN_END_COMPLETE ? "the motion completed before it could stop" : msg);
    }
}

void ls_core_manual_off(ls_core_t *core)
{
    if (core->sensor.sup < 0 && strcmp(core->sensor.mode, "off") == 0) {
        return;
    }
    if (core->ctl != NULL) {
        (void)ls_control_set_manual(core->ctl, NULL, NULL, NULL, 0);
    }
    ls_fmt_print(core->sensor.mode, sizeof core->sensor.mode, "off");
    core->sensor.sup = LS_NO_SESSION;
    core->sensor.kind = -1;
    if (ls_core_motion_is_manual(core)) {
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    }
}

static void post_stop(ls_core_t *core, bool fast)
{
    if (fast && core->act.halt != NULL) {
        core->act.halt(core->act.ctx);
    } else if (core->act.enable_drives != NULL) {
        /* The loop stops a running motion along its path first (LS_CTL_DISABLE). */
        (void)core->act.enable_drives(core->act.ctx, false);
    }
}

static bool is_fault(ls_run_end_t why)
{
    return why == LS_RUN_END_FAULT || why == LS_RUN_END_EMERGENCY;
}

/* What every halt does as it begins, after its fields are set: note the loop
 * cycle it starts at, end a program's wait and manual control, and report
 * robot_stopping. */
static void halt_enter(ls_core_t *core)
{
    ls_halt_t *h = &core->halt;
    if (core->ctl != NULL) {
        ls_ctl_snapshot_t snap;
        ls_control_snapshot(core->ctl, &snap);
        h->start_cycle = snap.cycle;
    }
    core->run.wait_active = false;
    ls_core_manual_off(core);
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPING_CHOICE);
}

void ls_run_halt(ls_core_t *core, ls_run_end_t why, const char *text, bool fast, int answer_sup, uint64_t now_us)
{
    ls_halt_t *h = &core->halt;
    if (h->active) {
        /* Already stopping: a fault takes over the reason and the speed of the stop. */
        if (is_fault(why) && !is_fault(h->why)) {
            h->why = why;
            ls_fmt_text(h->text, sizeof h->text, "%s", text != NULL ? text : "");
        }
        if (answer_sup >= 0) {
            h->answer_sup = answer_sup;
        }
        if (fast && !h->fast) {
            h->keep_drives = false; /* a fault turns the drives off after all */
            h->fast = true;
            post_stop(core, true);
        }
        return;
    }
    memset(h, 0, sizeof *h);
    h->active = true;
    h->why = why;
    h->answer_sup = answer_sup;
    h->since_us = now_us;
    h->fast = fast;
    ls_fmt_text(h->text, sizeof h->text, "%s", text != NULL ? text : "");
    halt_enter(core);
    post_stop(core, fast);
}

void ls_run_halt_owner_lost(ls_core_t *core, ls_run_end_t why, bool keep_drives, uint64_t now_us)
{
    if (core->halt.active || !keep_drives || core->act.stop_motion == NULL) {
        ls_run_halt(core, why, "", false, LS_NO_SESSION, now_us);
        return;
    }
    ls_halt_t *h = &core->halt;
    memset(h, 0, sizeof *h);
    h->active = true;
    h->why = why;
    h->answer_sup = LS_NO_SESSION;
    h->since_us = now_us;
    h->keep_drives = true;
    halt_enter(core);
    core->act.stop_motion(core->act.ctx); /* along the path at the configured deceleration, then paused */
}

/* The arm is at rest with the drives off (or there is no loop to ask); with
 * keep_drives, at rest with the motion paused or done. */
static bool halted(ls_core_t *core, uint64_t now_us)
{
    ls_halt_t *h = &core->halt;
    if (core->ctl == NULL) {
        return true;
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (now_us - h->since_us > LS_RUN_HALT_MAX_US) {
        return true;
    }
    /* two cycles: the one that took the command and one that published after it */
    const bool stopped = h->keep_drives ? (snap.phase == LS_MOTION_IDLE || snap.phase == LS_MOTION_PAUSED)
                                        : (!snap.enabled && snap.phase == LS_MOTION_IDLE && !snap.react_active);
    if (snap.cycle < h->start_cycle + 2u || !stopped) {
        h->off_since_us = 0;
        return false;
    }
    if (h->off_since_us == 0) {
        h->off_since_us = now_us;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (fabs(snap.qd_rad_s[j]) > REST_SPEED_RAD_S && now_us - h->off_since_us < COAST_MAX_US) {
            return false;
        }
    }
    return true;
}

void ls_run_tick(ls_core_t *core, uint64_t now_us)
{
    ls_halt_t *h = &core->halt;
    if (!h->active || !halted(core, now_us)) {
        return;
    }
    h->active = false;
    const bool fault = is_fault(h->why) || h->why == LS_RUN_END_AUX_FAILED;
    char d_fault[sizeof(((ls_Notice *)0)->data[0])]; /* one notice datum: its whole room */
    const char *extra[1] = { d_fault };
    size_t n_extra = 0;
    if (h->text[0] != '\0') {
        ls_fmt_text(d_fault, sizeof d_fault, "fault=%s", h->text);
        n_extra = 1;
    }
    if (h->keep_drives && core->ctl != NULL) {
        /* Drop the paused motion: the executor holds nothing, the drives stay on. */
        ls_ctl_cmd_t c;
        memset(&c, 0, sizeof c);
        c.kind = LS_CTL_ABORT;
        c.ref_seq = core->run.ref_seq;
        (void)ls_control_post(core->ctl, &c);
    }
    /* The state first: a supervisor reacting to the notice sees the arm's state. */
    if (h->keep_drives) {
        if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
            core->state = ls_State_RESTING;
        }
    } else if (h->release) {
        core->state = ls_State_UNLOCKED;
        for (int i = 0; i < LS_MAX_SUPERVISORS && core->state == ls_State_UNLOCKED; i++) {
            if (core->sessions[i].connected) {
                break;
            }
            if (i == LS_MAX_SUPERVISORS - 1) {
                core->state = ls_State_IDLE;
            }
        }
    } else if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED || core->state == ls_State_RESTING) {
        core->state = ls_State_LOCKED;
    }
    ls_core_set_motion_state(core, fault || h->why == LS_RUN_END_OWNER_LOST
                                       ? LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_ERROR_CHOICE
                                       : LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_COMMAND_CHOICE);
    ls_run_finish(core, h->why, extra, n_extra);
    if (h->owner_lost) {
        ls_core_owner_lost_alarm(core, h->lost_addr, h->lost_why, h->lost_action, now_us);
    }
    bool anyone = false;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        anyone = anyone || core->sessions[i].connected;
    }
    if (!anyone && !core->held && core->state == ls_State_UNLOCKED) {
        core->state = ls_State_IDLE;
    }
    if (h->answer_sup >= 0) {
        ls_core_finish_deferred(core, h->answer_sup, ls_RetCode_CMD_EXEC_OK,
                                fault ? "inactive: a fault stopped the motion first, drives disabled"
                                      : "inactive: stopped along the planned path, drives disabled");
    }
}

bool ls_run_shutdown(ls_core_t *core, uint64_t now_us)
{
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED || core->halt.active) {
        ls_run_halt(core, LS_RUN_END_SHUTDOWN, "", true, LS_NO_SESSION, now_us);
    }
    return core->halt.active;
}
