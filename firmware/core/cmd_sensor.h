/* Seed 3.7.2-3.8: what the sensor-guided moves and manual control
 * (firmware/core/cmd_sensor.c) share with the other handlers. Private to the
 * core, handlers layer (docs/architecture.md "Core layers"); their loop
 * events are in ls_core_events.h. Comms thread. */
#ifndef LS_CMD_SENSOR_H
#define LS_CMD_SENSOR_H

#include <stdbool.h>

#include "ls_control.h"
#include "ls_core_services.h"

/* A sensor-guided move's final notice for its ending, from its command's
 * finals `f` (ls_cmd_table: <command>Complete, ...Envelope, ...Timeout,
 * ...PanicStop, ...Aborted or ...Failed; docs/protocol.md "Motion
 * lifecycle"). EVENT_ID_NONE for f NULL. */
ls_EventId ls_core_sensor_final(const ls_cmd_finals_t *f, ls_react_end_t end);

/* The name of value `k` of sensor `s` ("Fx", ..., "distance") and its SI unit
 * in *unit_si ("N", "Nm", "m"), or NULL past its last value (describe). */
const char *ls_core_sensor_component(const hal_sensor_t *s, size_t k, const char **unit_si);

#endif
