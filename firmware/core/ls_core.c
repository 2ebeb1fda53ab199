/* The core's start and its time: init, the one route of the control loop's
 * events into the core, and the tick with its next deadline. Top layer of
 * firmware/core (docs/architecture.md "Core layers"), beside the sessions
 * (ls_session.c) and the dispatcher (ls_dispatch.c). */
#include "ls_core.h"

#include <string.h>

#include "landscape.h"
#include "ls_control.h"
#include "ls_core_events.h"
#include "ls_fmt.h"
#include "ls_session.h"

void ls_core_init(ls_core_t *core, const ls_core_config_t *cfg, const ls_core_io_t *io, const ls_core_actions_t *act)
{
    memset(core, 0, sizeof *core);
    core->cfg = *cfg;
    core->io = *io;
    if (act != NULL) {
        core->act = *act;
    }
    core->state = ls_State_IDLE;
    core->owner = LS_NO_SESSION;
    core->activating = LS_NO_SESSION;
    core->homing = LS_NO_SESSION;
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    core->settings.speed_pct = 25.0;
    core->settings.accel_pct = 50.0;
    core->settings.linear_speed_m_s = 0.25;
    core->settings.angular_speed_rad_s = 1.0;
    core->settings.linear_accel_m_s2 = 1.0;
    core->settings.angular_accel_rad_s2 = 4.0;
    core->rsvp_next_id = 1;
    core->epoch_next = 1;
    core->run.path = LS_PATH_NONE;
    core->halt.answer_sup = LS_NO_SESSION;
    ls_fmt_print(core->sensor.mode, sizeof core->sensor.mode, "off");
    core->sensor.sup = LS_NO_SESSION;
    core->sensor.kind = -1;
    ls_fmt_print(core->tool_cmds.held, sizeof core->tool_cmds.held, "none");
}

/* What a joint's drive reported (an EMCY, its error code read back): in
 * the fault log, and to every supervisor (docs/protocol.md "Drives"). */
static void on_arm_event(ls_core_t *core, const hal_arm_event_t *e, uint64_t now_us)
{
    ls_core_log_fault(core, now_us, "joint %u (node 0x%02X): %s", (unsigned)e->joint + 1u, (unsigned)e->node, e->text);
    char joint[16], node[16], code[16], meaning[72], reg[16], vendor[24];
    ls_fmt_print(joint, sizeof joint, "joint=%u", (unsigned)e->joint + 1u);
    ls_fmt_print(node, sizeof node, "node=0x%02X", (unsigned)e->node);
    ls_fmt_print(code, sizeof code, "code=0x%04X", (unsigned)e->code);
    ls_fmt_print(meaning, sizeof meaning, "meaning=%s", e->meaning);
    if (e->is_emcy) {
        ls_fmt_print(reg, sizeof reg, "register=0x%02X", (unsigned)e->reg);
        ls_fmt_print(vendor, sizeof vendor, "vendor=%02X%02X%02X%02X%02X", (unsigned)e->vendor[0],
                     (unsigned)e->vendor[1], (unsigned)e->vendor[2], (unsigned)e->vendor[3], (unsigned)e->vendor[4]);
        const char *data[] = { joint, node, code, meaning, reg, vendor };
        ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_driveEmcy, 0, false, data, 6);
    } else {
        const char *data[] = { joint, node, code, meaning };
        ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_EVENT, ls_EventId_driveErrorCode, 0, false, data, 4);
    }
}

/* The one route of the control loop's events into the core. The moves,
 * jogs and tool changes that cmd_sensor.c and cmd_tool.c started take
 * their own events first; the rest go to the motion executor's side
 * (cmd_motion_events.c), the fault latch and the DIO watches. */
static void on_loop_event(ls_core_t *core, const ls_ctl_event_t *ev, uint64_t now_us)
{
    if (ls_core_tool_on_event(core, ev) || ls_core_sensor_on_event(core, ev)) {
        return;
    }
    switch (ev->kind) {
    case LS_CEV_MOTION: ls_core_on_motion_event(core, &ev->motion); break;
    case LS_CEV_FAULT: ls_core_fault(core, ev->text, now_us); break; /* its halt ends the motion */
    case LS_CEV_DIO_CHANGED: ls_core_on_dio_event(core, ev->dio.unit, ev->dio.on, ev->dio.off, now_us); break;
    case LS_CEV_ARM_EVENT: on_arm_event(core, &ev->arm, now_us); break;
    case LS_CEV_ENABLED: ls_core_on_enable_result(core, NULL, now_us); break;
    case LS_CEV_ENABLE_FAILED: ls_core_on_enable_result(core, ev->text, now_us); break;
    case LS_CEV_HOMED: ls_drv_on_home_result(core, NULL, now_us); break;
    case LS_CEV_HOME_FAILED: ls_drv_on_home_result(core, ev->text, now_us); break;
    case LS_CEV_MANUAL: break; /* cmd_sensor.c takes them all */
    case LS_CEV_CMD_FAILED: {
        char d[80];
        ls_fmt_print(d, sizeof d, "reason=%s", ev->text);
        const char *data[] = { d };
        ls_core_notify(core, core->owner, ls_NoticeKind_ALARM, ls_EventId_commandFailed, ev->ref_seq, false, data, 1);
        ls_core_motion_failed(core, ev->ref_seq, ev->text);
        if (core->act.log_warn != NULL) {
            char line[112];
            ls_fmt_print(line, sizeof line, "control loop: %s", ev->text);
            core->act.log_warn(core->act.ctx, line);
        }
        break;
    }
    }
}

void ls_core_take_loop_events(ls_core_t *core, uint64_t now_us)
{
    if (core->ctl != NULL) {
        ls_ctl_event_t ev;
        while (ls_control_next_event(core->ctl, &ev)) {
            on_loop_event(core, &ev, now_us);
        }
    }
}

void ls_core_tick(ls_core_t *core, uint64_t now_us)
{
    ls_core_take_loop_events(core, now_us);
    ls_rsvp_tick(core, now_us);
    ls_log_alarm_tick(core, now_us);
    ls_session_tick(core, now_us);
    ls_run_tick(core, now_us);
    ls_dio_tick(core, now_us);
    ls_core_motion_tick(core, now_us);
}

uint64_t ls_core_next_deadline_us(const ls_core_t *core, uint64_t now_us)
{
    uint64_t t = ls_dio_next_deadline_us(core, now_us);
    const uint64_t sample = now_us + LS_CORE_SAMPLE_US;
    if (core->halt.active) {
        t = sample < t ? sample : t; /* ls_run_tick: at rest yet? */
    }
    if (core->run.active && !core->run.react && core->ctl != NULL && (core->run.dio_pending || core->run.wait_active)) {
        t = sample < t ? sample : t; /* ls_core_motion_tick: the DIO of a path's aux command */
    }
    for (int i = 0; i < LS_MAX_RSVP; i++) {
        if (core->rsvp[i].used && core->rsvp[i].deadline_us < t) {
            t = core->rsvp[i].deadline_us;
        }
    }
    if (core->alarm_window.open) {
        const uint64_t end = core->alarm_window.since_us + (uint64_t)LS_ALARM_WINDOW_MS * 1000u;
        t = end < t ? end : t;
    }
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        const ls_session_t *s = &core->sessions[i];
        if (s->connected) {
            /* ls_core_tick drops it once more than the time-out has passed */
            const uint64_t lost = s->last_heard_us + (uint64_t)s->heartbeat_timeout_ms * 1000u + 1u;
            t = lost < t ? lost : t;
        }
    }
    return t;
}
