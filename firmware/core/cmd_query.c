/* Seed 3.3 state queries that need nothing but the core. */
#include "ls_core_services.h"

#include <string.h>

#include "landscape.h"
#include "landscape_choices.h"
#include "ls_fmt.h"

int32_t ls_h_get_motion_control_state(struct ls_core *core, struct ls_call *call)
{
    ls_GetMotionControlStateRes *r = &call->res->result.get_motion_control_state;
    ls_fmt_print(r->motion_control_state, sizeof r->motion_control_state, "%s", ls_core_motion_state_name(core));
    bool active = core->state == ls_State_RESTING || core->state == ls_State_MOVING || core->state == ls_State_PAUSED;
    uint32_t mode = core->fault[0] != '\0' ? LANDSCAPE_STATUS_ST_CONTROL_MODE_CONTROLLER_ERROR_CHOICE
                    : active               ? LANDSCAPE_STATUS_ST_CONTROL_MODE_POWER_ON_CHOICE
                                           : LANDSCAPE_STATUS_ST_CONTROL_MODE_POWER_OFF_CHOICE;
    ls_fmt_print(r->control_mode, sizeof r->control_mode, "%s", landscape_status_st_control_mode_choice_name(mode));
    r->state = core->state;
    ls_fmt_print(r->fault, sizeof r->fault, "%s", core->fault);
    r->owner = core->owner == call->sup;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s", ls_State_name(core->state));
}
