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

LS_NOT_IMPLEMENTED(set_speed, "setSpeed")
LS_NOT_IMPLEMENTED(set_acceleration, "setAcceleration")
LS_NOT_IMPLEMENTED(set_tool_offset, "setToolOffset")
LS_NOT_IMPLEMENTED(set_world_cartesian_frame, "setWorldCartesianFrame")
LS_NOT_IMPLEMENTED(set_units, "setUnits")
LS_NOT_IMPLEMENTED(get_units, "getUnits")
LS_NOT_IMPLEMENTED(get_velocities, "getVelocities")
LS_NOT_IMPLEMENTED(get_accelerations, "getAccelerations")
LS_NOT_IMPLEMENTED(get_max_velocities, "getMaxVelocities")
LS_NOT_IMPLEMENTED(get_max_accelerations, "getMaxAccelerations")
LS_NOT_IMPLEMENTED(get_tool_offsets, "getToolOffsets")
LS_NOT_IMPLEMENTED(get_robot_position, "getRobotPosition")
LS_NOT_IMPLEMENTED(get_sensor_reading, "getSensorReading")
LS_NOT_IMPLEMENTED(move_react, "moveReact")
LS_NOT_IMPLEMENTED(comply, "comply")
LS_NOT_IMPLEMENTED(manual_control, "manualControl")
LS_NOT_IMPLEMENTED(get_end_effector_state, "getEndEffectorState")
LS_NOT_IMPLEMENTED(get_tool, "getTool")
LS_NOT_IMPLEMENTED(put_tool, "putTool")
LS_NOT_IMPLEMENTED(activate_tool, "activateTool")
LS_NOT_IMPLEMENTED(deactivate_tool, "deactivateTool")
LS_NOT_IMPLEMENTED(set_digital_io, "setDigitalIO")
LS_NOT_IMPLEMENTED(get_digital_io, "getDigitalIO")
LS_NOT_IMPLEMENTED(signal_digital_io, "signalDigitalIO")
