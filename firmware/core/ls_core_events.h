/* What the comms thread calls when the control loop reports something.
 * Motion events: firmware/core/cmd_motion.c. DIO changes: firmware/core/cmd_dio.c. */
#ifndef LS_CORE_EVENTS_H
#define LS_CORE_EVENTS_H

#include <stdint.h>

#include "ls_core.h"
#include "ls_motion.h"

void ls_core_on_motion_event(ls_core_t *core, const ls_motion_event_t *ev);
void ls_core_on_dio_event(ls_core_t *core, uint16_t unit, uint32_t levels, uint32_t changed, uint64_t now_us);
/* Polling time-outs and cycle times of signalDigitalIO watches. */
void ls_dio_tick(ls_core_t *core, uint64_t now_us);

#endif
