/* What the comms thread calls when the control loop reports something.
 * Motion events: firmware/core/cmd_motion_events.c; a path's auxiliary
 * commands: cmd_aux.c. DIO changes: firmware/core/cmd_dio.c. */
#ifndef LS_CORE_EVENTS_H
#define LS_CORE_EVENTS_H

#include <stdint.h>

#include "ls_core.h"
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

#endif
