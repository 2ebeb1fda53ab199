/* Commands that are in the schema but not built yet. Each answers
 * CMD_NOT_IMPLEMENTED_ERR with its name; docs/conformance.md lists them.
 * A handler moves out of this file when its feature lands. */
#include "ls_core.h"

#define LS_NOT_IMPLEMENTED(field, seed_name)                                                              \
    int32_t ls_h_##field(struct ls_core *core, struct ls_call *call)                                     \
    {                                                                                                     \
        (void)core;                                                                                       \
        return ls_reply(call, ls_RetCode_CMD_NOT_IMPLEMENTED_ERR,                                        \
                        seed_name " is not implemented in this firmware yet (see docs/conformance.md)"); \
    }

LS_NOT_IMPLEMENTED(move_react, "moveReact")
LS_NOT_IMPLEMENTED(comply, "comply")
LS_NOT_IMPLEMENTED(manual_control, "manualControl")
LS_NOT_IMPLEMENTED(get_end_effector_state, "getEndEffectorState")
LS_NOT_IMPLEMENTED(get_tool, "getTool")
LS_NOT_IMPLEMENTED(put_tool, "putTool")
LS_NOT_IMPLEMENTED(activate_tool, "activateTool")
LS_NOT_IMPLEMENTED(deactivate_tool, "deactivateTool")
