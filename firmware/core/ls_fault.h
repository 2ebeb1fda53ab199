/* The fault latch: a fault (a loop fault, a failed auxiliary command, an
 * EMERGENCY frame) is recorded, raised as an alarm to every session and
 * stops whatever moves (docs/state-machine.md "Faults").
 *
 * Services layer of firmware/core (docs/architecture.md "Core layers"): the
 * highest service, above ls_run (the stop), ls_log and ls_send. Comms
 * thread only; no allocation.*/
#ifndef LS_FAULT_H
#define LS_FAULT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_types.h"

/* Latch a fault: record it, raise the alarm `fault` to everyone, stop a
 * motion along its path at the model's maximum deceleration, then drives off
 * (ACTIVE -> LOCKED once they are off; the motion's final notice then). */
void ls_core_fault(ls_core_t *core, const char *text, uint64_t now_us);

/* The same for an EMERGENCY frame on the bus (reason=emergency). Repeats of
 * the alarm within LS_ALARM_WINDOW_MS are counted, not sent; the stop is
 * never delayed. */
void ls_core_emergency(ls_core_t *core, uint64_t now_us);

#endif
