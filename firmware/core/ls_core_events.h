/* The handlers' side of the control loop's events and of time: what the
 * core's one route of the loop's events (ls_core.c, on_loop_event) and its
 * tick call. Motion events: firmware/core/cmd_motion_events.c; a path's
 * auxiliary commands: cmd_aux.c; DIO changes: cmd_dio.c; the sensor-guided
 * moves and jogs: cmd_sensor.c; tool changes: cmd_tool.c; the drives'
 * enable: cmd_session.c; their homing: cmd_drives.c. Handlers layer
 * (docs/architecture.md "Core layers"): only the layer above calls these.
 * Comms thread only. */
#ifndef LS_CORE_EVENTS_H
#define LS_CORE_EVENTS_H

#include <stdbool.h>
#include <stdint.h>

#include "ls_control.h"
#include "ls_core_services.h"
#include "ls_motion.h"

void ls_core_on_motion_event(ls_core_t *core, const ls_motion_event_t *ev);
/* Polls the DIO inputs of a path's `wait` auxiliary command: every comms loop turn. */
void ls_core_motion_tick(ls_core_t *core, uint64_t now_us);
/* The loop could not carry out the motion `ref_seq` (LS_CEV_CMD_FAILED), or
 * faulted (LS_CEV_FAULT, ref_seq 0 = whatever runs): send the motion's one
 * final notice (an alarm) and leave MOVING/PAUSED. */
void ls_core_motion_failed(ls_core_t *core, uint32_t ref_seq, const char *text);
void ls_core_on_dio_event(ls_core_t *core, uint16_t unit, uint32_t levels, uint32_t changed, uint64_t now_us);
/* Polling time-outs and cycle times of signalDigitalIO watches. */
void ls_dio_tick(ls_core_t *core, uint64_t now_us);
/* The part of ls_core_next_deadline_us that ls_dio_tick serves. */
uint64_t ls_dio_next_deadline_us(const ls_core_t *core, uint64_t now_us);

/* An event of the control loop; true when it was one of a guarded or
 * compliant move or a jog cmd_sensor.c started (consumed), false to pass it
 * on. */
bool ls_core_sensor_on_event(ls_core_t *core, const ls_ctl_event_t *ev);

/* cmd_tool.c: an event of the loop; true when it was the tool code's own
 * (consumed), false to pass it on (it may still have acted on it: a fault
 * ends a tool change in progress). */
bool ls_core_tool_on_event(ls_core_t *core, const ls_ctl_event_t *ev);

/* The control loop's answer to the drives' enable (LS_CEV_ENABLED with
 * `failure` NULL, LS_CEV_ENABLE_FAILED with its text): finishes the
 * deferred activate of core->activating (RESTING, or refused naming the
 * joint and what its drive said); drives that came on for a session that
 * ended or lost the lock are switched off again. Comms thread. */
void ls_core_on_enable_result(ls_core_t *core, const char *failure, uint64_t now_us);

/* cmd_drives.c: the homing's end (LS_CEV_HOMED with `failure` NULL,
 * LS_CEV_HOME_FAILED with its line): the deferred answer of sendCommand
 * home to core->homing. Comms thread. */
void ls_drv_on_home_result(ls_core_t *core, const char *failure, uint64_t now_us);

#endif
