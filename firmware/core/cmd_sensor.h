/* Seed 3.7.2-3.8: the comms-thread side of sensor-guided motion, manual
 * control (firmware/core/cmd_sensor.c) and the end effector
 * (firmware/core/cmd_tool.c). Private to the core.
 *
 * Their completions come back from the control loop as events: ls_core_tick
 * hands every event to ls_core_sensor_on_event first, so the events of the
 * moves, jogs and tool changes they started reach them before the other
 * handlers. Everything here runs in the comms thread. */
#ifndef LS_CMD_SENSOR_H
#define LS_CMD_SENSOR_H

#include <stdbool.h>

#include "ls_control.h"
#include "ls_core.h"

/* An event of the control loop; true when it was one of a move, jog or tool
 * change these handlers started (consumed), false to pass it on. */
bool ls_core_sensor_on_event(ls_core_t *core, const ls_ctl_event_t *ev);

/* The suffix of a sensor-guided move's final event id for its ending:
 * "Complete", "Envelope", "Timeout", "PanicStop", "Aborted" or "Failed"
 * (docs/protocol.md "Motion lifecycle"; ls_run_end_event makes the id). */
const char *ls_core_sensor_end_suffix(ls_react_end_t end);

/* cmd_tool.c: an event of the loop; true when it was the tool code's own
 * (consumed), false to pass it on (it may still have acted on it: a fault
 * ends a tool change in progress). */
bool ls_core_tool_on_event(ls_core_t *core, const ls_ctl_event_t *ev);

/* Manual control ends with the owner's control of the device (release, or
 * the owner lost): the next owner must switch it on itself. */
void ls_core_manual_off(ls_core_t *core);

/* The name of value `k` of sensor `s` ("Fx", ..., "distance") and its SI unit
 * in *unit_si ("N", "Nm", "m"), or NULL past its last value (describe). */
const char *ls_core_sensor_component(const hal_sensor_t *s, size_t k, const char **unit_si);

#endif
