/* CiA 301 SDO client for one server (one node): expedited and segmented
 * download (write) and upload (read), one transfer at a time, as a
 * non-blocking state machine. Static buffers, no heap, no clock reads: time
 * is passed in. Block transfer is not implemented (CiA 301 makes it
 * optional; the objects a drive master reads and writes fit in segments).
 *
 * Usage (one thread, the one that owns the master; a client is not
 * thread-safe):
 *   ls_co_sdo_init(&s, node_id, timeout_us, send_fn, ctx);
 *   ls_co_sdo_write(&s, index, sub, data, len, now_us);    or ls_co_sdo_read
 *   every frame with id LS_CO_COB_SDO_TX + node_id:        ls_co_sdo_on_frame
 *   often (each control cycle):                            ls_co_sdo_poll
 *   when ls_co_sdo_status() is no longer LS_EBUSY:         the outcome, the
 *                                                          bytes (ls_co_sdo_data)
 *                                                          and ls_co_sdo_text
 *
 * Protocol policy:
 *  - The time-out runs per request: each initiate or segment request must be
 *    answered within timeout_us (CiA 301 leaves the value to the
 *    application; 500 ms is the customary default). On expiry the client
 *    sends abort LS_CO_ABORT_TIMEOUT, unless the request itself never got
 *    onto the bus (the send function kept refusing it): then the server
 *    knows nothing of the transfer and no abort is sent.
 *  - A server response that does not fit the transfer (another command
 *    specifier, another index or sub-index in an initiate response, a frame
 *    shorter than 8 bytes) ends it: the client sends abort LS_CO_ABORT_CS;
 *    a segment with the wrong toggle bit sends LS_CO_ABORT_TOGGLE; a
 *    segmented upload whose length differs from the size the server
 *    indicated sends LS_CO_ABORT_TYPE_LEN. An abort from the server ends the
 *    transfer whatever its multiplexer says (servers that abort before
 *    parsing the request put zeros there).
 *  - A frame while no transfer runs is a stray (a late answer to a transfer
 *    that timed out): counted in `stray`, never answered.
 *  - Uploads keep at most LS_CO_SDO_BUF_LEN bytes: a longer object is read
 *    up to that length and the transfer is aborted with
 *    LS_CO_ABORT_NO_MEMORY; the status is LS_ELEN and the first
 *    LS_CO_SDO_BUF_LEN bytes stay readable (a long 0x1008 name, truncated).
 *  - An expedited upload without size indication (e = 1, s = 0) yields its
 *    four data bytes.
 *
 * Sending: every frame goes through `send` (LS_OK, or LS_EAGAIN when the CAN
 * queue is full). A refused frame is kept and offered again by every
 * ls_co_sdo_poll until taken; nothing blocks. */
#ifndef LS_CO_SDO_H
#define LS_CO_SDO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "ls_err.h"

#define LS_CO_SDO_BUF_LEN 64u                /* bytes of one transfer (0x1008 names fit) */
#define LS_CO_SDO_TIMEOUT_US_DEFAULT 500000u /* per request, when init is given 0 */
#define LS_CO_TEXT_LEN 160u                  /* one line of text, NUL included */

/* Queue one CAN frame for transmission; never blocks. LS_OK when taken,
 * LS_EAGAIN (or any other negative) when refused: the caller keeps the
 * frame and offers it again later. */
typedef int (*ls_co_send_fn)(void *ctx, const hal_can_frame_t *frame);

typedef enum {
    LS_CO_SDO_IDLE = 0, /* no transfer: the last outcome is readable */
    LS_CO_SDO_DL_INIT,  /* download initiate sent, its response awaited */
    LS_CO_SDO_DL_SEG,   /* download segment sent */
    LS_CO_SDO_UL_INIT,  /* upload initiate sent */
    LS_CO_SDO_UL_SEG,   /* upload segment request sent */
} ls_co_sdo_phase_t;

typedef struct {
    uint32_t transfers;       /* transfers started */
    uint32_t aborts_sent;     /* aborts this client sent (time-outs included) */
    uint32_t aborts_received; /* aborts from the server */
    uint32_t timeouts;        /* transfers that ended with LS_ETIMEDOUT */
    uint32_t stray;           /* frames while no transfer ran */
} ls_co_sdo_counters_t;

/* All fields are private to ls_co_sdo.c; read them through the functions. */
typedef struct {
    uint8_t node_id;
    uint32_t timeout_us;
    ls_co_send_fn send;
    void *send_ctx;

    ls_co_sdo_phase_t phase;
    bool upload;
    uint16_t index;
    uint8_t sub;
    uint8_t buf[LS_CO_SDO_BUF_LEN];
    uint8_t len;     /* download: bytes to send; upload: bytes kept */
    uint8_t off;     /* download: bytes sent and acknowledged or in flight */
    uint32_t size;   /* upload: size the server indicated */
    bool size_known; /* upload: it indicated one */
    uint8_t toggle;  /* LS_CO_SDO_TOGGLE or 0: the next segment's */
    uint64_t deadline_us;

    hal_can_frame_t tx; /* a frame the send function refused */
    bool tx_pending;
    bool tx_is_request; /* it is the request the current phase waits on */

    int status; /* LS_EBUSY while a transfer runs, then its outcome */
    uint32_t abort_code;
    char text[LS_CO_TEXT_LEN];
    ls_co_sdo_counters_t counters;
} ls_co_sdo_t;

/* Prepare a client for server `node_id` (init time; clears counters).
 * timeout_us 0 means LS_CO_SDO_TIMEOUT_US_DEFAULT. O(1).
 * Returns LS_OK, or LS_EINVAL (s or send NULL, node_id outside 1..127);
 * *s is untouched on error. */
int ls_co_sdo_init(ls_co_sdo_t *s, uint8_t node_id, uint32_t timeout_us, ls_co_send_fn send, void *send_ctx);

/* Start writing `len` bytes (copied) to index:sub: expedited for 1..4
 * bytes, segmented for 5..LS_CO_SDO_BUF_LEN. Sends the initiate request at
 * once when the queue takes it. O(len).
 * Returns LS_OK; LS_EINVAL (s or data NULL); LS_ELEN (len 0 or more than
 * LS_CO_SDO_BUF_LEN); LS_EBUSY (a transfer runs or an abort waits to be
 * sent: ls_co_sdo_busy). Nothing changes on error. */
int ls_co_sdo_write(ls_co_sdo_t *s, uint16_t index, uint8_t sub, const uint8_t *data, size_t len, uint64_t now_us);

/* Start reading index:sub. O(1). Returns LS_OK, LS_EINVAL (s NULL) or
 * LS_EBUSY; nothing changes on error. */
int ls_co_sdo_read(ls_co_sdo_t *s, uint16_t index, uint8_t sub, uint64_t now_us);

/* Feed one frame the server sent (id LS_CO_COB_SDO_TX + node_id; the caller
 * routes). Advances the transfer and sends its next request at once. Never
 * fails: a frame that does not fit ends the transfer as the policy above
 * says. Expires the time-out first, like poll. O(frame). */
void ls_co_sdo_on_frame(ls_co_sdo_t *s, const hal_can_frame_t *frame, uint64_t now_us);

/* Offer a refused frame again and expire the time-out. O(1). Call every
 * control cycle (at least as often as the time-out's resolution needs). */
void ls_co_sdo_poll(ls_co_sdo_t *s, uint64_t now_us);

/* Drop the transfer and any frame waiting to be sent, without an abort:
 * the server reset or is gone, so it has no transfer to abort. A running
 * transfer ends with LS_EIO and `why` (NULL: "cancelled") as its text
 * after the node prefix. O(text). */
void ls_co_sdo_cancel(ls_co_sdo_t *s, const char *why);

/* True while a transfer runs or a frame of this client waits to be sent
 * (then a new transfer is refused with LS_EBUSY). O(1). */
bool ls_co_sdo_busy(const ls_co_sdo_t *s);

/* LS_EBUSY while a transfer runs; then the outcome of the last one:
 * LS_OK; LS_EABORTED (the server aborted: ls_co_sdo_abort_code);
 * LS_ETIMEDOUT (no answer within the time-out); LS_EPROTO (the server broke
 * the protocol; the abort this client sent is ls_co_sdo_abort_code);
 * LS_ELEN (an upload longer than LS_CO_SDO_BUF_LEN, truncated); LS_EIO
 * (cancelled). LS_OK before the first transfer. O(1). */
int ls_co_sdo_status(const ls_co_sdo_t *s);

/* The abort code of the last failed transfer (received or sent), 0 when
 * none was exchanged. O(1). */
uint32_t ls_co_sdo_abort_code(const ls_co_sdo_t *s);

/* The bytes of the last upload (or of the last download) and their count;
 * valid until the next transfer starts. Never NULL. O(1). */
const uint8_t *ls_co_sdo_data(const ls_co_sdo_t *s, size_t *len);

/* The last upload's first bytes (at most four) as a little-endian number;
 * *len (may be NULL) gets how many bytes there were. O(1). */
uint32_t ls_co_sdo_value(const ls_co_sdo_t *s, size_t *len);

/* One line on the last failure: node, operation, object and cause, e.g.
 * "node 0x23: SDO write 0x1600:01 aborted 0x06040041 (object cannot be
 * mapped to the PDO)". "" when the last transfer succeeded. Never NULL. */
const char *ls_co_sdo_text(const ls_co_sdo_t *s);

#endif
