/* Open a CAN link from its configuration spelling, the one place that maps
 * a spec to a backend (landscaped's supervisor links and its drive bus):
 *
 *   socketcan:IFNAME   a SocketCAN interface (hal/linux)
 *   slcan:pty:PATH     SLCAN on a new pseudo-terminal, PATH its symlink:
 *                      this side is the adapter (hal/sim)
 *   slcan:tty:PATH     a serial SLCAN adapter (or a pty that plays one):
 *                      this side is the host (hal/linux)
 *
 * Init-time only. */
#ifndef LS_LINK_OPEN_H
#define LS_LINK_OPEN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"

/* Open `spec`. `bitrate` is what a serial adapter's channel is opened at
 * (slcan:tty only). `allow_tty` false refuses slcan:tty (the supervisor
 * links are the adapter's side of their lines). Returns LS_OK, or a
 * negative status with `msg` naming the cause and the fix (the backend's
 * message, or "unknown link kind; expected ..."). */
int ls_link_open(const char *spec, uint32_t bitrate, bool allow_tty, hal_can_link_t *out, char *msg, size_t msglen);

#endif
