/* SLCAN link on a pseudo-terminal: the simulated controller's CAN bus on a
 * machine without SocketCAN. landscaped owns the pty master; PATH becomes a
 * symlink to the slave, which a supervisor opens as python-can's `slcan`
 * channel. The symlink is removed by close(). */
#ifndef HAL_SIM_SLCAN_PTY_H
#define HAL_SIM_SLCAN_PTY_H

#include <stddef.h>

#include "hal/hal_can.h"

#define HAL_SLCAN_PTY_MAX_LINKS 4

/* Create the pty and the symlink at `path` (an existing symlink is replaced;
 * any other existing file is an error). Init-time only. Returns HAL_OK, or a
 * negative status with `msg` naming the cause and the fix. */
int hal_sim_slcan_pty_open(hal_can_link_t *out, const char *path, char *msg, size_t msglen);

#endif
