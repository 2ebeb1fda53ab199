/* Seed 3.1: lock, release, activate, deactivate. The dispatcher has already
 * checked the state and the owner. */
#include "landscape.h"
#include "ls_core_services.h"
#include "ls_fmt.h"

int32_t ls_h_lock(struct ls_core *core, struct ls_call *call)
{
    core->owner = call->sup;
    core->state = ls_State_LOCKED;
    /* How the last motion ended was the previous owner's news: a new lock
     * starts at rest unless a fault is still latched (docs/state-machine.md
     * "motion_control_state"). */
    if (core->fault[0] == '\0') {
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "locked by 0x%02X", core->sessions[call->sup].addr);
}

int32_t ls_h_release(struct ls_core *core, struct ls_call *call)
{
    ls_core_manual_off(core);
    core->owner = LS_NO_SESSION;
    core->state = ls_State_UNLOCKED;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "released: the device is under local control");
}

int32_t ls_h_activate(struct ls_core *core, struct ls_call *call)
{
    if (core->fault[0] != '\0') {
        /* Activation acknowledges the latched fault: the supervisor saw it
         * (alarm, getMotionControlState) and decides to go on. */
        core->fault[0] = '\0';
    }
    bool have_drives = core->act.enable_drives != NULL;
    if (have_drives) {
        int r = core->act.enable_drives(core->act.ctx, true);
        if (r < 0) {
            return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                            "the drives could not be enabled (%s): check the arm backend (--arm)", ls_err_name(r));
        }
        if (r > 0) {
            /* Real drives enable in steps: answered when every joint has
             * confirmed, or one could not (ls_core_on_enable_result). */
            core->activating = call->sup;
            return LS_CALL_DEFERRED;
        }
    }
    core->state = ls_State_RESTING;
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s",
                    have_drives ? "active: drives enabled" : "active: no arm backend is composed, nothing can move");
}

int32_t ls_h_deactivate(struct ls_core *core, struct ls_call *call)
{
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        /* A controlled stop along the planned path at the configured
         * deceleration, then drives off; the answer (and the motion's final
         * notice, reason=deactivate) when the arm is at rest with the drives
         * off (ls_run_tick). */
        ls_run_halt(core, LS_RUN_END_DEACTIVATE, "", false, call->sup, call->now_us);
        return LS_CALL_DEFERRED;
    }
    if (core->act.enable_drives != NULL) {
        (void)core->act.enable_drives(core->act.ctx, false);
    }
    core->state = ls_State_LOCKED;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "inactive: drives disabled");
}

void ls_core_on_enable_result(ls_core_t *core, const char *failure, uint64_t now_us)
{
    const int sup = core->activating;
    core->activating = LS_NO_SESSION;
    if (failure != NULL) {
        ls_core_log_fault(core, now_us, "activate: the drives are off: %s", failure);
        if (sup >= 0) {
            char msg[sizeof core->down.msg.response.ret_msg];
            ls_fmt_print(msg, sizeof msg, "activate failed, the drives are off: %s", failure);
            ls_core_finish_deferred(core, sup, ls_RetCode_CMD_ERR, msg);
        }
        return;
    }
    /* Every joint confirmed. The drives stay on only for the session that
     * asked, while it still owns the device and no fault came meanwhile (an
     * emergency frame, an owner loss); else they go off again at once. */
    const bool asked = sup >= 0 && core->sessions[sup].connected && core->owner == sup;
    if (!asked || core->state != ls_State_LOCKED || core->fault[0] != '\0') {
        if (core->state == ls_State_LOCKED || core->state == ls_State_UNLOCKED) {
            if (core->act.enable_drives != NULL) {
                (void)core->act.enable_drives(core->act.ctx, false);
            }
            ls_core_log_event(core, now_us, "the drives came on after their activate ended: switched off again");
        }
        if (sup >= 0) {
            char msg[sizeof core->down.msg.response.ret_msg];
            ls_fmt_print(msg, sizeof msg, "activate failed, the drives are off again: %s",
                         core->fault[0] != '\0' ? core->fault : "the device changed state while they enabled");
            ls_core_finish_deferred(core, sup, ls_RetCode_CMD_FAULT_ERR, msg);
        }
        return;
    }
    core->state = ls_State_RESTING;
    ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    ls_core_finish_deferred(core, sup, ls_RetCode_CMD_EXEC_OK, "active: drives enabled");
}
