/* SocketCAN backend of the CAN link contract (hal/hal_can.h).
 *
 * One CAN_RAW socket per link, non-blocking, bound to one interface (can0,
 * vcan0, slcan0, ...). Error frames (bus-off, controller state changes,
 * restarts) are subscribed with CAN_RAW_ERR_FILTER: they update the link's
 * status and are never returned as data frames. Kernel receive-queue drops
 * (SO_RXQ_OVFL) are reported as rx_dropped.
 *
 * Storage: links live in a static pool of HAL_LINUX_SOCKETCAN_MAX_LINKS
 * entries; open and close take and give back a pool entry (no heap at all).
 * The caller owns the hal_can_link_t it passes in; after a failed open it
 * holds no ops (hal_can_close on it is a no-op). close is idempotent until
 * another open reuses the pool entry: drop the hal_can_link_t after closing.
 *
 * Threading: open, probe and close at init/shutdown (they take a mutex and
 * make a few syscalls); send, recv, poll_fd and status from the one comms
 * thread that owns the link. send and recv are one syscall each, never block
 * and never allocate. status reads /sys/class/net/<if>/operstate (three
 * syscalls): call it at a low rate, not every control cycle. */
#ifndef HAL_LINUX_SOCKETCAN_H
#define HAL_LINUX_SOCKETCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <linux/can.h>

#include "hal/hal_can.h"

#define HAL_LINUX_SOCKETCAN_MAX_LINKS 4

/* Open a link on interface `ifname` (e.g. "can0"). On error `out` holds no
 * ops and `msg` (if not NULL) names the cause and the fix:
 *   LS_EINVAL    out or ifname NULL, ifname empty or longer than IFNAMSIZ-1,
 *                 or all pool entries in use;
 *   LS_ENOAFCAN  the kernel has no AF_CAN or no CAN_RAW (modprobe can can-raw);
 *   LS_ENODEV    no interface of that name, or it is not a CAN interface;
 *   LS_EIO       the interface exists but is administratively down, or
 *                 another socket call failed (message has strerror);
 *   LS_EPERM     the kernel refused the socket.
 * On success out->name is "socketcan:<ifname>", the bitrate and controller
 * state are read once over rtnetlink (best effort: bitrate 0 when unknown). */
int hal_linux_socketcan_open(hal_can_link_t *out, const char *ifname, char *msg, size_t msglen);

/* Self-check for `landscaped --check`: opens and closes a link on `ifname`
 * without keeping a pool entry. LS_OK with a one-line summary in `msg`
 * ("socketcan:can0 ok: bitrate 500000 bit/s, state active"), or the status
 * and message open would give. Init-time only. */
int hal_linux_socketcan_probe(const char *ifname, char *msg, size_t msglen);

/* Adopt an already bound CAN_RAW socket `fd` (e.g. inherited from a
 * supervisor). The link takes ownership of fd (closes it on close, and on
 * failure). fd is made non-blocking. Any datagram socket that carries
 * struct can_frame records works, which is how the unit tests exercise the
 * link logic on a kernel without AF_CAN. Errors: LS_EINVAL (bad argument,
 * pool full), LS_EIO (fcntl failed). */
int hal_linux_socketcan_adopt_fd(hal_can_link_t *out, int fd, const char *ifname, char *msg, size_t msglen);

/* Frame conversion, exposed so tests can check it without a CAN kernel.
 * encode: LS_EINVAL for an id wider than its format, len > 8 or unknown
 * flags; LS_OK otherwise. */
int hal_linux_socketcan_encode(const hal_can_frame_t *in, struct can_frame *out);

/* decode: a data or remote frame is written to `out` (returns 1); an error
 * frame (CAN_ERR_FLAG) updates `st` (state, error_frames) and returns 0;
 * a frame with can_dlc > 8 returns LS_EINVAL and counts in st->rx_dropped. */
int hal_linux_socketcan_decode(const struct can_frame *in, hal_can_frame_t *out, hal_can_status_t *st);

/* What rtnetlink says about a CAN interface. */
typedef struct {
    uint32_t bitrate; /* bit/s; 0 when not reported (vcan, slcan) */
    bool have_state;  /* the kernel reported a controller state */
    hal_can_state_t state;
} hal_linux_socketcan_link_info_t;

/* Parse an RTM_NEWLINK answer (one or more netlink messages, `len` bytes):
 * IFLA_LINKINFO of kind "can" -> IFLA_CAN_BITTIMING.bitrate and
 * IFLA_CAN_STATE (stopped and sleeping count as bus-off). Returns 1 when CAN
 * data was found, 0 when not (another link kind), LS_EINVAL for NULL
 * arguments. Malformed lengths end the walk; never reads outside buf.
 * Exposed for tests and fuzzing; open uses it. */
int hal_linux_socketcan_parse_link(const void *buf, size_t len, hal_linux_socketcan_link_info_t *info);

#endif
