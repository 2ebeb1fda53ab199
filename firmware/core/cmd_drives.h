/* Private to the core: the drives' own operations through the seed's
 * vendor hook (4.1 sendCommand; docs/protocol.md "Drives"), and the one
 * refusal every motion command shares while a joint that must be homed is
 * not. Handlers layer (docs/architecture.md "Core layers"); the homing's
 * end comes through ls_core_events.h. Comms thread only; every answer is
 * one line naming what to do. */
#ifndef LS_CMD_DRIVES_H
#define LS_CMD_DRIVES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_services.h"

/* sendCommand home [JOINT...]: the drives' own homing of the joints named
 * (1..LS_N_JOINTS, separated by blanks or commas), or of every joint that
 * must be homed when none is named. The owner's, in RESTING (drives on, at
 * rest); answered when the homing ends (LS_CALL_DEFERRED), or refused at
 * once naming what is wrong. `args` is what follows "home". */
int32_t ls_drv_home(ls_core_t *core, ls_call_t *call, const char *args);

/* sendCommand drives [JOINT | bus]: per joint one line of the drive's
 * readouts, one joint's in full, or the drive bus master's counters, into
 * `out` (cap bytes). CMD_EXEC_OK, or a refusal answered in *call (no arm
 * with drives, a bad argument). */
int32_t ls_drv_readouts(ls_core_t *core, ls_call_t *call, const char *args, char *out, size_t cap);

/* sendCommand status's lines of the drives ("drive j1 node=0x21 ..."),
 * appended at out[*len] (cap bytes in all); nothing on an arm without
 * drives. */
void ls_drv_status_lines(ls_core_t *core, char *out, size_t cap, size_t *len);

/* Before any motion (moves, paths, sensor-guided moves, jogging, tool
 * changes): true when a joint that must be homed is not, or a homing runs,
 * after answering CMD_WRONG_STATE_ERR in *code naming the joints and
 * sendCommand home. */
bool ls_drv_refuse_unhomed(ls_core_t *core, ls_call_t *call, const char *what, int32_t *code);

#endif
