/* The comms-thread side of the motion executor's events: a motion done,
 * paused, faulted, a tag or an auxiliary command reached. Each becomes the
 * state change and the notice of docs/state-machine.md, to the session that
 * started the motion. */
#include <math.h>
#include <string.h>

#include "cmd_motion.h"
#include "landscape.h"
#include "ls_core_events.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

#define LS_JOINT_TEXT_ZERO 1e-9

static void joints_text(const ls_core_t *core, const double q[LS_N_JOINTS], char *out, size_t cap)
{
    /* Fit the notice's 64 characters: fewer digits when needed. A value
     * below LS_JOINT_TEXT_ZERO (far below any encoder's resolution, e.g. a
     * joint the simulation holds at 2.6e-20 rad) is written 0. */
    const double per_unit = ls_units_to_si_angular(ls_core_run_units(core).angular, 1.0);
    for (int prec = 6; prec >= 3; prec--) {
        size_t len = (size_t)ls_fmt_print(out, cap, "joints=");
        for (int j = 0; j < LS_N_JOINTS && len < cap; j++) {
            const double v = q[j] / per_unit;
            len += (size_t)ls_fmt_print(out + len, cap - len, "%s%.*g", j ? "," : "", prec,
                                        fabs(v) < LS_JOINT_TEXT_ZERO ? 0.0 : v);
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
            ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
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
            ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_PAUSED_CHOICE);
        }
        if (core->run.stop_pending) {
            core->run.stop_pending = false;
            char msg[128];
            ls_fmt_print(msg, sizeof msg,
                         "paused on the planned path (%s): resumeMotion continues, abortMotion drops it",
                         ev->text[0] != '\0' ? ev->text : "between two points");
            ls_core_finish_deferred(core, core->run.stop_sup, ls_RetCode_CMD_EXEC_OK, msg);
        }
        return;
    case LS_MEV_FAULT: {
        char t[80];
        ls_fmt_print(t, sizeof t, "%s", ev->text);
        if (core->ctl != NULL) {
            ls_ctl_snapshot_t snap;
            ls_control_snapshot(core->ctl, &snap);
            if (snap.t_us > core->motion.now_us) {
                core->motion.now_us = snap.t_us;
            }
        }
        ls_core_fault(core, t, core->motion.now_us); /* ends the run once the drives are off */
        return;
    }
    case LS_MEV_TAG: {
        ls_fmt_print(core->motion.tag_path, sizeof core->motion.tag_path, "%.*s", (int)sizeof core->motion.tag_path - 1,
                     ev->text);
        ls_fmt_print(core->motion.tag_last, sizeof core->motion.tag_last, "%s", ev->name);
        if (!core->run.active || core->run.react) {
            return;
        }
        char d1[8 + LS_MOTION_NAME_LEN], d2[24], d3[24], d4[8 + sizeof ev->text];
        ls_fmt_print(d1, sizeof d1, "tag=%s", ev->name);
        ls_fmt_print(d2, sizeof d2, "index=%d", (int)ev->index);
        ls_fmt_print(d3, sizeof d3, "cycle=%d", (int)ev->cycle);
        ls_fmt_print(d4, sizeof d4, "path=%s", ev->text);
        const char *data[] = { d1, d2, d3, d4, "dry_run=true" };
        ls_core_notify_to(core, core->run.addr, core->run.epoch, ls_NoticeKind_EVENT, ls_EventId_tag, core->run.ref_seq,
                          false, data, core->run.dry_run ? 5u : 4u);
        return;
    }
    case LS_MEV_SLOW: {
        /* The program is the core's and unchanged while it runs. */
        ls_motion_slowdown_t d;
        if (!core->run.active || core->run.react || ev->ref_seq != core->run.ref_seq || ev->index < 0 ||
            ev->index >= LS_MOTION_MAX_SEGS || !ls_motion_seg_slowdown(&core->motion.prog.seg[ev->index], &d)) {
            return;
        }
        char d1[8 + LS_MOTION_NAME_LEN], d2[24], d3[32], d4[32], d5[32], d6[16], d7[24], d8[32], d9[32];
        ls_fmt_print(d1, sizeof d1, "path=%s", ev->name);
        ls_fmt_print(d2, sizeof d2, "point=%d", (int)core->motion.prog.seg[ev->index].point);
        ls_fmt_print(d3, sizeof d3, "speed_pct=%.3g", 100.0 * d.speed_frac);
        ls_fmt_print(d4, sizeof d4, "from_pct=%.3g", 100.0 * d.from);
        ls_fmt_print(d5, sizeof d5, "to_pct=%.3g", 100.0 * d.to);
        ls_fmt_print(d6, sizeof d6, "joint=%d", d.joint);
        ls_fmt_print(d7, sizeof d7, "limit=%s", d.velocity ? "velocity" : "acceleration");
        ls_fmt_print(d8, sizeof d8, "duration_s=%.4g", d.duration_s);
        ls_fmt_print(d9, sizeof d9, "requested_s=%.4g", d.requested_s);
        const char *data[] = { d1, d2, d3, d4, d5, d6, d7, d8, d9 };
        ls_core_notify_to(core, core->run.addr, core->run.epoch, ls_NoticeKind_EVENT, ls_EventId_slowedDown,
                          core->run.ref_seq, false, data, sizeof data / sizeof data[0]);
        return;
    }
    case LS_MEV_AUX:
        if (core->run.active && !core->run.react && !core->halt.active) {
            ls_aux_run(core, ev);
        }
        return;
    default: return;
    }
}
