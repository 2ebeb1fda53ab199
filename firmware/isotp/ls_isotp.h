/* ISO 15765-2 (ISO-TP) transport for classic CAN, one link = one pair of CAN
 * ids (one peer). Static buffers, no heap, no clock reads: time is passed in.
 *
 * Names follow the standard: N_Bs (sender waits for a flow control), N_Cr
 * (receiver waits for a consecutive frame), BS (block size), STmin.
 *
 * Usage (comms thread only; a link is not thread-safe):
 *   ls_isotp_init(&l, &cfg, tx_id, rx_id, send_fn, ctx);
 *   on every CAN frame with id == rx_id:  ls_isotp_on_frame(&l, data, len, now_us);
 *   to send a message:                    ls_isotp_send(&l, buf, len, now_us);
 *   often (each loop turn, <= 1 ms):      ls_isotp_poll(&l, now_us);
 *   a complete message arrived when:      ls_isotp_take_rx(&l, out, cap) > 0
 *
 * Costs: every function is O(frame) except ls_isotp_send/take_rx, which copy
 * the payload once (O(len)). */
#ifndef LS_ISOTP_H
#define LS_ISOTP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_err.h"

#define LS_ISOTP_MAX_PAYLOAD 4095u /* classic ISO-TP without the 32-bit escape */
/* ls_isotp_default_config's protocol parameters. The module knows no schema:
 * these are the protocol's (protocol/landscape.proto enum IsotpParam), and
 * firmware/net/ls_net.c asserts at compile time that they agree. */
#define LS_ISOTP_DEFAULT_BS 8u
#define LS_ISOTP_DEFAULT_ST_MIN 0u
#define LS_ISOTP_DEFAULT_PADDING_BYTE 0xCCu
#define LS_ISOTP_DEFAULT_N_TIMEOUT_US 1000000u /* N_Bs and N_Cr */
/* A reception's whole time is bounded by its announced length: at most
 * N_Cr x (1 + its blocks of consecutive frames), a block being the BS we ask
 * for (LS_ISOTP_RX_CAP_BLOCK when we ask BS 0). N_Cr alone restarts at every
 * consecutive frame, so a sender trickling one frame per N_Cr could hold a
 * 4095-byte reception for 585 N_Cr; with the cap it is 1 + 74 N_Cr at most.
 * Past the cap the reception ends as N_TIMEOUT_CR. */
#define LS_ISOTP_RX_CAP_BLOCK 8u

/* Result of a transfer (N_Result of the standard), also the error counters' index. */
typedef enum {
    LS_ISOTP_N_OK = 0,
    LS_ISOTP_N_TIMEOUT_BS,   /* sender: no flow control within N_Bs */
    LS_ISOTP_N_TIMEOUT_CR,   /* receiver: no consecutive frame within N_Cr */
    LS_ISOTP_N_WRONG_SN,     /* receiver: consecutive frame out of sequence */
    LS_ISOTP_N_INVALID_FS,   /* sender: flow status not CTS/WAIT/OVFLW */
    LS_ISOTP_N_UNEXP_PDU,    /* a frame that does not fit the current state */
    LS_ISOTP_N_WFT_OVRN,     /* sender: more FC.WAIT frames than wft_max */
    LS_ISOTP_N_BUFFER_OVFLW, /* receiver: message longer than the buffer (FC.OVFLW sent);
                                sender: the peer answered FC.OVFLW */
    LS_ISOTP_N_MALFORMED,    /* frame too short, bad length field, unknown PCI type */
    LS_ISOTP_N_RESULT_COUNT
} ls_isotp_result_t;

/* Return codes of the API functions (ls_err.h): LS_OK; LS_EBUSY (a
 * transmission is already in progress), LS_ELEN (length 0 or >
 * LS_ISOTP_MAX_PAYLOAD), LS_EINVAL (NULL pointer or bad configuration). */

/* Transmit one CAN frame. Returns 0 when queued, negative when the link's
 * queue is full (the ISO-TP layer then retries the same frame on the next
 * ls_isotp_poll). `len` is 1..8. */
typedef int (*ls_isotp_send_fn)(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len);

typedef struct {
    uint8_t block_size;       /* BS we ask of a sender (0: no flow control after the first) */
    uint8_t st_min;           /* STmin we ask of a sender, raw ISO byte (0x00-0x7F ms, 0xF1-0xF9 100-900 us) */
    bool tx_padding;          /* pad our frames to 8 bytes with `padding_byte` */
    uint8_t padding_byte;     /* 0xCC is customary */
    uint32_t n_bs_timeout_us; /* default 1000000 */
    uint32_t n_cr_timeout_us; /* default 1000000 */
    uint8_t wft_max;          /* FC.WAIT frames tolerated in a row; default 10 */
} ls_isotp_config_t;

/* Fills `cfg` with the defaults above (LS_ISOTP_DEFAULT_*: BS 8, STmin 0,
 * padding on with 0xCC, N_Bs and N_Cr 1 s) and wft_max 10. */
void ls_isotp_default_config(ls_isotp_config_t *cfg);

typedef enum { LS_ISOTP_RX_IDLE = 0, LS_ISOTP_RX_RECEIVING, LS_ISOTP_RX_DONE } ls_isotp_rx_state_t;
typedef enum { LS_ISOTP_TX_IDLE = 0, LS_ISOTP_TX_WAIT_FC, LS_ISOTP_TX_SENDING } ls_isotp_tx_state_t;

typedef struct {
    ls_isotp_config_t cfg;
    uint32_t tx_id, rx_id;
    ls_isotp_send_fn send;
    void *send_ctx;

    /* receiver */
    ls_isotp_rx_state_t rx_state;
    uint8_t rx_buf[LS_ISOTP_MAX_PAYLOAD];
    uint16_t rx_len, rx_got;
    uint8_t rx_sn, rx_bs_left;
    uint64_t rx_deadline_us; /* N_Cr: the next consecutive frame */
    uint64_t rx_end_us;      /* the whole reception (LS_ISOTP_RX_CAP_BLOCK) */
    bool rx_fc_pending;      /* a flow control frame waits for room in the CAN queue */
    uint8_t rx_fc_status;

    /* sender */
    ls_isotp_tx_state_t tx_state;
    uint8_t tx_buf[LS_ISOTP_MAX_PAYLOAD];
    uint16_t tx_len, tx_off;
    uint8_t tx_sn, tx_bs, tx_bs_left, tx_wft;
    uint32_t tx_stmin_us;
    uint64_t tx_next_us, tx_deadline_us;

    /* outcome counters, indexed by ls_isotp_result_t (N_OK counts successes) */
    uint32_t rx_results[LS_ISOTP_N_RESULT_COUNT];
    uint32_t tx_results[LS_ISOTP_N_RESULT_COUNT];
    ls_isotp_result_t last_error;
} ls_isotp_link_t;

/* Prepare a link (init time; clears counters). `cfg` NULL means the defaults.
 * Returns LS_EINVAL on a NULL link or send function, a reserved st_min or
 * a zero timeout. */
int ls_isotp_init(ls_isotp_link_t *l, const ls_isotp_config_t *cfg, uint32_t tx_id, uint32_t rx_id,
                  ls_isotp_send_fn send, void *send_ctx);

/* Feed one received CAN frame of this link (can_id == rx_id; the caller routes).
 * Handles SF/FF/CF for the receiver and FC for the sender. Malformed frames are
 * counted and dropped, never crash. Expires N_Bs/N_Cr first, like poll.
 *
 * Receiver policy (counters in rx_results unless said otherwise):
 *  - Padded and unpadded frames are accepted (len >= the bytes the PCI needs);
 *    len 0 or > 8, a too-short frame, an unknown PCI type, SF length 0 or > 7
 *    and FF length 1..7 count N_MALFORMED and are dropped; a too-short CF does
 *    not abort the reception (N_Cr still runs).
 *  - A FF with length 0 (32-bit escape, unsupported) or > LS_ISOTP_MAX_PAYLOAD
 *    is answered with FC.OVFLW and counts N_BUFFER_OVFLW.
 *  - A new SF/FF during a reception aborts it (N_UNEXP_PDU) and starts anew.
 *  - While a completed message waits for ls_isotp_take_rx (RX_DONE), an
 *    incoming SF or FF is dropped and counts N_BUFFER_OVFLW; a FF is also
 *    answered with FC.OVFLW so that its sender aborts at once instead of
 *    waiting out N_Bs. Take messages every loop turn to avoid this.
 *  - A CF while not receiving counts N_UNEXP_PDU; a CF with the wrong SN
 *    aborts the reception (N_WRONG_SN).
 *  - A reception ends with N_TIMEOUT_CR when no CF came within N_Cr, and also
 *    when it is not complete within its cap (LS_ISOTP_RX_CAP_BLOCK): a
 *    trickle of frames does not keep it alive.
 * Sender policy (tx_results): an FC while not waiting for one counts
 * N_UNEXP_PDU and is ignored; an FC.CTS sends the CFs that are due at once. */
void ls_isotp_on_frame(ls_isotp_link_t *l, const uint8_t *data, uint8_t len, uint64_t now_us);

/* Start sending `len` bytes (copied). Sends the SF or FF at once when the CAN
 * queue has room, else on the next poll (a refused frame is retried by every
 * poll until the queue takes it). Returns LS_OK, LS_EINVAL (NULL),
 * LS_ELEN or LS_EBUSY. */
int ls_isotp_send(ls_isotp_link_t *l, const uint8_t *payload, size_t len, uint64_t now_us);

/* Send the last message again from its first frame (its bytes are still in
 * the link), after its transfer failed: no flow control within N_Bs, too many
 * FC.WAIT, an invalid flow status. The caller tells failure from success by
 * tx_results[LS_ISOTP_N_OK]. Returns LS_OK, LS_EINVAL (NULL, or
 * nothing was ever sent) or LS_EBUSY (a transfer is under way). */
int ls_isotp_resend(ls_isotp_link_t *l, uint64_t now_us);

/* The receiver asked for the message again (a retransmitted request): a
 * transfer that waits for a flow control is restarted from its first frame
 * now, not after N_Bs (a receiver that lost a consecutive frame sends no
 * flow control). Returns LS_OK when it restarted, LS_EBUSY while frames are
 * being sent (it finishes), LS_EINVAL when no transfer is under way. */
int ls_isotp_restart_waiting(ls_isotp_link_t *l, uint64_t now_us);

/* Send due consecutive frames (honouring STmin and BS), pending flow controls,
 * and expire N_Bs / N_Cr. */
void ls_isotp_poll(ls_isotp_link_t *l, uint64_t now_us);

/* When a whole message was received: copy it to `out` (cap >= its length),
 * return its length and free the receiver. Else return 0. A message longer
 * than `cap` is dropped and counted as N_BUFFER_OVFLW; returns 0. A NULL `out`
 * returns 0 and leaves the message in place. Never writes past out[cap-1]. */
size_t ls_isotp_take_rx(ls_isotp_link_t *l, uint8_t *out, size_t cap);

bool ls_isotp_tx_busy(const ls_isotp_link_t *l);

/* The earliest time at which ls_isotp_poll has work (a CF due, a timeout), or
 * UINT64_MAX when idle. Lets the caller sleep exactly as long as allowed. A
 * value <= now (0 for a pending flow control) means: poll now. */
uint64_t ls_isotp_next_deadline_us(const ls_isotp_link_t *l);

/* Decode a single frame outside of any link (functional addressing carries
 * single frames only). Returns the payload length (1..7) and copies it to
 * `out` (cap >= 7), or 0 when the frame is not a valid single frame. */
size_t ls_isotp_decode_single(const uint8_t *data, uint8_t len, uint8_t *out, size_t cap);

/* Encode a single frame for a payload of 1..7 bytes into `frame` (8 bytes).
 * Returns the CAN data length to send (padded to 8 if `pad`), 0 on bad length. */
uint8_t ls_isotp_encode_single(const uint8_t *payload, size_t len, bool pad, uint8_t pad_byte, uint8_t frame[8]);

/* The cap of a reception of `msg_len` bytes under `cfg` (LS_ISOTP_RX_CAP_BLOCK),
 * in microseconds. */
uint64_t ls_isotp_rx_cap_us(const ls_isotp_config_t *cfg, uint16_t msg_len);

/* Convert an STmin byte to microseconds per ISO 15765-2 (reserved values mean 127 ms). */
uint32_t ls_isotp_stmin_to_us(uint8_t st_min);

const char *ls_isotp_result_name(ls_isotp_result_t r);

#endif
