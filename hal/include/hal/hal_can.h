/* CAN link contract: one bus segment carrying classic CAN 2.0 frames.
 * Backends: hal/sim (SLCAN on a pseudo-terminal), hal/linux (SocketCAN).
 * Nothing above this contract knows which backend carries the frames.
 *
 * Threading: a link is used from one thread (the comms thread). */
#ifndef HAL_CAN_H
#define HAL_CAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_status.h"

#define HAL_CAN_F_EXT 0x01u /* 29-bit identifier */
#define HAL_CAN_F_RTR 0x02u /* remote frame */

#define HAL_CAN_NAME_LEN 136 /* hal_can_link_t.name with its NUL: a kind ("slcan:tty:") and a path of 120 */

typedef struct {
    uint32_t id;   /* 11 or 29 bits, without flag bits */
    uint8_t flags; /* HAL_CAN_F_* */
    uint8_t len;   /* 0..8 */
    uint8_t data[8];
} hal_can_frame_t;

typedef enum {
    HAL_CAN_STATE_ACTIVE = 0,
    HAL_CAN_STATE_WARNING,
    HAL_CAN_STATE_PASSIVE,
    HAL_CAN_STATE_BUS_OFF,
} hal_can_state_t;

typedef struct {
    hal_can_state_t state;
    uint32_t rx_frames, tx_frames;
    uint32_t rx_dropped; /* frames the backend could not parse or had no room for */
    uint32_t tx_dropped;
    uint32_t error_frames; /* error frames / error reports seen */
    uint32_t bitrate;      /* bit/s, 0 when unknown */
    uint32_t close_held;   /* requests of the far side to close the channel deferred by hal_can_hold_open */
} hal_can_status_t;

typedef struct {
    /* Queue one frame for transmission. Never blocks. LS_EAGAIN when the
     * backend's queue is full (the caller keeps the frame and retries). */
    int (*send)(void *self, const hal_can_frame_t *frame);
    /* Take one received frame. Never blocks. 1: a frame was written;
     * LS_EAGAIN: none pending; other negatives: link failed. */
    int (*recv)(void *self, hal_can_frame_t *frame);
    /* A file descriptor that polls readable when recv may have a frame, or -1. */
    int (*poll_fd)(void *self);
    /* Bus state and counters. */
    int (*status)(void *self, hal_can_status_t *out);
    /* Release everything the link holds (fds, symlinks). Idempotent. */
    void (*close)(void *self);
    /* Optional. `hold` true: sessions live on this link, so a request of
     * one client on the far side to close the channel (SLCAN `C`, which
     * python-can sends at every shutdown) must not mute it for the others:
     * it is acknowledged and deferred (counted in close_held), and an open
     * request (`O`) does not discard output in flight. `hold` false carries
     * out a deferred close. NULL: the backend has no such request
     * (SocketCAN). */
    int (*hold_open)(void *self, bool hold);
    /* Optional. True while output the backend took waits in its own
     * buffer for room in the medium: the caller polls poll_fd writable too
     * and calls recv or send when it is, which write it out. It must turn
     * false once the fd has room (no spinning on a writable fd). NULL: the
     * backend buffers nothing (SocketCAN: the kernel queues, and a frame it
     * refuses stays with the caller, who retries; a CAN socket's POLLOUT
     * does not tell when the device queue has room). */
    bool (*tx_pending)(void *self);
    /* Optional. When the backend has work of its own to do in recv/send
     * although poll_fd may not poll readable: received bytes it has read
     * but not yet parsed, frames it holds until a time (fault injection).
     * 0: at once; UINT64_MAX: nothing; else a CLOCK_MONOTONIC time in us.
     * NULL: never. An event-driven caller sleeps no longer than this. */
    uint64_t (*next_due_us)(void *self);
} hal_can_ops_t;

typedef struct {
    const hal_can_ops_t *ops;
    void *self;
    /* e.g. "slcan:pty:/tmp/ls0" or "socketcan:vcan0", for logs: as long as
     * the longest link a configuration names, so that a device's by-id path
     * is whole (texts with less room shorten it: ls_fmt_name_tail). */
    char name[HAL_CAN_NAME_LEN];
} hal_can_link_t;

int hal_can_send(hal_can_link_t *link, const hal_can_frame_t *frame);
int hal_can_recv(hal_can_link_t *link, hal_can_frame_t *frame);
int hal_can_poll_fd(hal_can_link_t *link);
int hal_can_status(hal_can_link_t *link, hal_can_status_t *out);
void hal_can_close(hal_can_link_t *link);
int hal_can_hold_open(hal_can_link_t *link, bool hold);
/* The optional operations above; a backend without them: false, UINT64_MAX. */
bool hal_can_tx_pending(hal_can_link_t *link);
uint64_t hal_can_next_due_us(hal_can_link_t *link);

#endif
