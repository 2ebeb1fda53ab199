/* SLCAN serial adapter backend of the CAN link contract (hal/hal_can.h):
 * a USB-serial CAN adapter speaking the Lawicel ASCII protocol (CANable,
 * USBtin, CANtact and the like, /dev/ttyACM0), or any serial device that
 * speaks it as an adapter does, such as the pseudo-terminal of
 * `ls-simdrives --link slcan:pty:PATH`. This side is the host: it opens the
 * channel (`C`, `Sn`, `O` at open, `C` at close), sends frames as lines and
 * reads the adapter's lines; the adapter's acknowledgements (CR, BEL, `z`,
 * `Z`) are read and dropped. The other side of hal/sim/slcan_pty.
 *
 * Storage: a static pool of HAL_LINUX_SLCAN_TTY_MAX_LINKS entries (no heap);
 * lines the device cannot take at once wait in the entry's own buffer
 * (tx_pending), frames read but not yet returned in its read buffer
 * (next_due_us: at once).
 *
 * Threading: open and close at init/shutdown; send, recv, poll_fd, status,
 * tx_pending and next_due_us from the one thread that owns the link (the
 * control thread, for a drive bus). send and recv make at most one write and
 * one read system call each and never block. */
#ifndef HAL_LINUX_SLCAN_TTY_H
#define HAL_LINUX_SLCAN_TTY_H

#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"

#define HAL_LINUX_SLCAN_TTY_MAX_LINKS 2

/* Open the serial device at `path` and open its CAN channel at `bitrate`
 * (one of 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k, 1M bit/s: the Sn
 * indices of the protocol). A tty is put in raw mode; a device that is no
 * tty (a FIFO in tests) is used as it is. Errors, with `msg` naming the
 * cause and the fix:
 *   LS_EINVAL   a NULL argument, an empty path, a bitrate without an Sn
 *               index, or the pool is full;
 *   LS_ENODEV   no such file;
 *   LS_EPERM    no permission (the service user needs the dialout group);
 *   LS_EIO      another open or write failure (the message has strerror).
 * On success out->name is "slcan:tty:PATH". Init-time only. */
int hal_linux_slcan_tty_open(hal_can_link_t *out, const char *path, uint32_t bitrate, char *msg, size_t msglen);

/* The protocol's bitrate index for `bitrate` ('0'..'8'), or 0 when there is none. */
char hal_linux_slcan_bitrate_index(uint32_t bitrate);

#endif
