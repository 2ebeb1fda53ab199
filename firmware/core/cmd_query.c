/* Seed 3.3 state queries that need nothing but the core. */
#include "ls_core.h"

#include <string.h>

#include "ls_fmt.h"

int32_t ls_h_get_motion_control_state(struct ls_core *core, struct ls_call *call)
{
    ls_GetMotionControlStateRes *r = &call->res->result.get_motion_control_state;
    ls_fmt_print(r->motion_control_state, sizeof r->motion_control_state, "%s", core->motion_state);
    bool active = core->state == ls_State_RESTING || core->state == ls_State_MOVING || core->state == ls_State_PAUSED;
    ls_fmt_print(r->control_mode, sizeof r->control_mode, "%s",
                 core->fault[0] != '\0' ? "controller_error" : (active ? "power_on" : "power_off"));
    r->state = core->state;
    ls_fmt_print(r->fault, sizeof r->fault, "%s", core->fault);
    r->owner = core->owner == call->sup;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s", ls_State_name(core->state));
}
