/* SLCAN link on a pseudo-terminal: the simulated controller's CAN bus on a
 * machine without SocketCAN. landscaped owns the pty master; PATH becomes a
 * symlink to the slave, which a supervisor opens as python-can's `slcan`
 * channel. The symlink is removed by close(). */
#ifndef HAL_SIM_SLCAN_PTY_H
#define HAL_SIM_SLCAN_PTY_H

#include <stddef.h>

#include "hal/hal_can.h"

#define HAL_SLCAN_PTY_MAX_LINKS 4

/* Create the pty and the symlink at `path`. A live path is never taken
 * over: `path`.lock is held with flock(2) for the link's life and holds the
 * owner's PID; while another process holds it the open fails (LS_EIO)
 * with `msg` naming that PID. A lock left by a dead process is free (the
 * kernel drops it), so a stale symlink is replaced; any other existing file
 * is an error. close() removes the symlink and the lock file. Init-time
 * only. Returns LS_OK, or a negative status with `msg` naming the cause and
 * the fix. */
int hal_sim_slcan_pty_open(hal_can_link_t *out, const char *path, char *msg, size_t msglen);

#endif
