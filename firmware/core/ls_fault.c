/* The fault latch. See ls_fault.h. */
#include "ls_fault.h"

#include "landscape.h"
#include "ls_fmt.h"
#include "ls_log.h"
#include "ls_run.h"
#include "ls_send.h"

static void fault_as(ls_core_t *core, ls_run_end_t why, const char *text, uint64_t now_us)
{
    ls_fmt_print(core->fault, sizeof core->fault, "%s", text);
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED || core->halt.active) {
        /* Stop along the path at the model's maximum deceleration, then drives
         * off; ls_run_tick changes the state and sends the motion's notice. */
        ls_run_halt(core, why, text, true, LS_NO_SESSION, now_us);
    } else {
        if (core->state == ls_State_RESTING) {
            if (core->act.enable_drives != NULL) {
                (void)core->act.enable_drives(core->act.ctx, false);
            }
            core->state = ls_State_LOCKED;
        }
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_ERROR_CHOICE);
    }
    if (ls_log_alarm_repeat(core, text, now_us)) {
        return; /* latched and stopping; counted, reported at the window's end */
    }
    ls_core_log_fault(core, now_us, "%s", text);
    char d[80];
    ls_fmt_print(d, sizeof d, "fault=%s", text);
    const char *data[] = { d };
    ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_fault, 0, false, data, 1);
}

void ls_core_fault(ls_core_t *core, const char *text, uint64_t now_us)
{
    fault_as(core, LS_RUN_END_FAULT, text, now_us);
}

void ls_core_emergency(ls_core_t *core, uint64_t now_us)
{
    core->emergency_frames++;
    fault_as(core, LS_RUN_END_EMERGENCY, "emergency stop frame on the bus", now_us);
}
