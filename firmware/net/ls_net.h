/* The network layer: CAN links (bus segments), routing of frames by id,
 * one ISO-TP link per supervisor, per-supervisor downlink queues, and
 * bridging between links (a frame received on one link is forwarded to the
 * others, so several pty links form one bus).
 *
 * Identifiers (docs/protocol.md): ISO-TP normal fixed 29-bit addressing
 * 0x18DA<target><source> (physical) and 0x18DB<target><source> (functional,
 * target 0xFF = every device); broadcasts of protocol/landscape.dbc with the
 * sender's address in the low byte.
 *
 * Comms thread only. All storage is inside ls_net_t. */
#ifndef LS_NET_H
#define LS_NET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "ls_core.h"
#include "ls_isotp.h"
#include "landscape.h" /* cantools: the DBC's frame ids */

/* The limits below are per profile (CMakeLists.txt LS_PROFILE): linux, or
 * mcu for a 256 KiB-RAM Cortex-M4F, where each peer costs 2 x
 * LS_ISOTP_MAX_PAYLOAD plus LS_NET_OUTQ x LS_DOWNLINK_MAX (about 20 KB
 * with 3 queued downlinks). */
#if LS_PROFILE_MCU
#define LS_NET_MAX_LINKS 2
#else
#define LS_NET_MAX_LINKS 4
#endif
/* ISO-TP links, one per source address, so a source holds at most one
 * reception (of at most LS_ISOTP_MAX_PAYLOAD bytes, its time capped by
 * LS_ISOTP_RX_CAP_BLOCK). The link of an address with a live session is
 * reserved: never evicted nor preempted. A source without one takes a free
 * link, else the least recently used idle link of another such source,
 * else it preempts the busy one of another such source that made progress
 * least recently (answers to session-less sources before receptions), so a
 * flood from changing addresses churns among itself and a new supervisor
 * can still connect (docs/protocol.md "Budgets under floods"). */
#if LS_PROFILE_MCU
#define LS_NET_MAX_PEERS 4 /* LS_MAX_SUPERVISORS + 2 */
#define LS_NET_OUTQ 3      /* an answer and two notices waiting per peer; more are dropped and counted */
#else
#define LS_NET_MAX_PEERS 6
#define LS_NET_OUTQ 8
#endif
/* Bridged frames (a frame received on one link, copied to the others): a
 * token bucket per output link, LS_NET_FWD_RATE_FPS frames/s with bursts of
 * LS_NET_FWD_BURST; EMERGENCY frames have a bucket of their own so a flood
 * of other frames cannot keep a stop from the other segments. Frames over
 * the budget are dropped and counted (fwd_dropped, fwd_emergency_dropped). */
#define LS_NET_FWD_RATE_FPS 1000u
#define LS_NET_FWD_BURST 128u
#define LS_NET_FWD_EMERGENCY_RATE_FPS 20u
#define LS_NET_FWD_EMERGENCY_BURST 4u
/* Transfers of one downlink before it is given up: a transfer that fails
 * (no flow control within N_Bs, ...) is sent again from its first frame,
 * so a supervisor that was slow for a moment still gets its answer or
 * notice (docs/protocol.md, "ISO-TP parameters"). */
#define LS_NET_TX_TRIES 3
/* While no link takes our frames (every hal_can_send refused them), ISO-TP
 * timers already due wait for the link's room: the caller's poll wakes
 * when a link polls writable (hal_can_tx_pending), and at the latest this
 * long after the refusal (a backend whose fd cannot tell). */
#define LS_NET_TX_RETRY_US 1000u

/* The schema declares them (protocol/landscape.proto IsotpId, NodeAddress). */
#define LS_ID_ISOTP_PHYS ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE)
#define LS_ID_ISOTP_FUNC ((uint32_t)ls_IsotpId_ISOTP_FUNCTIONAL_BASE)
#define LS_ID_MASK_PF 0x1FFF0000u
#define LS_ID_MASK_SRC 0x1FFFFF00u
/* Broadcast ids come from protocol/landscape.dbc (cantools' header), whose ids
 * carry the default device address in their low byte: mask it off. */
#define LS_ID_OF_DBC(frame_id) ((uint32_t)(frame_id)&LS_ID_MASK_SRC)
#define LS_ID_EMERGENCY LS_ID_OF_DBC(LANDSCAPE_EMERGENCY_FRAME_ID)
#define LS_ID_HEARTBEAT LS_ID_OF_DBC(LANDSCAPE_HEARTBEAT_FRAME_ID)
#define LS_ADDR_ALL ((uint32_t)ls_NodeAddress_FUNCTIONAL_ALL_DEVICES)

typedef struct {
    uint16_t len;
    uint8_t buf[LS_DOWNLINK_MAX];
} ls_net_msg_t;

/* A token bucket: starts full (`burst` tokens), refills at `rate` per second. */
typedef struct {
    bool primed;
    uint64_t last_us;
    uint64_t milli; /* thousandths of a token */
} ls_net_bucket_t;

/* Take one token at `now_us`: true when there was one. O(1), no clock read. */
bool ls_net_bucket_take(ls_net_bucket_t *b, uint32_t rate_per_s, uint32_t burst, uint64_t now_us);

typedef struct {
    bool used;
    uint8_t addr;
    int8_t link;           /* the link its last frame came from, -1: none yet */
    uint64_t last_used_us; /* its last frame, or the last downlink queued for it */
    ls_isotp_link_t isotp;
    ls_net_msg_t q[LS_NET_OUTQ];
    uint8_t q_head, q_count;
    uint32_t q_dropped;
    uint8_t tx_tries;    /* > 0: transfers so far of the downlink in the ISO-TP link */
    bool tx_asked_again; /* the same downlink was queued again while in flight */
    uint32_t tx_ok_mark; /* isotp.tx_results[N_OK] before its first transfer */
} ls_net_peer_t;

typedef struct ls_net {
    uint8_t node;
    ls_core_t *core;
    hal_can_link_t links[LS_NET_MAX_LINKS];
    size_t n_links;
    ls_net_peer_t peers[LS_NET_MAX_PEERS];
    ls_isotp_config_t isotp_cfg;
    uint64_t now_us;
    uint32_t frames_in, frames_out, frames_bridged, tx_full, peers_evicted;
    uint32_t peers_preempted;                    /* busy links of session-less sources taken for another */
    uint32_t fwd_dropped, fwd_emergency_dropped; /* bridged frames over a link's forward budget */
    uint32_t frames_foreign; /* frames from the device's own address, or a session's on another link: dropped */
    ls_net_bucket_t fwd[LS_NET_MAX_LINKS]; /* forward budget per output link */
    ls_net_bucket_t fwd_emergency[LS_NET_MAX_LINKS];
    bool link_held[LS_NET_MAX_LINKS]; /* told the link: sessions live on it (hal_can_hold_open) */
    uint32_t tx_retried, tx_given_up; /* downlink transfers sent again; downlinks given up */
    uint32_t tx_deduplicated;         /* downlinks identical to one still pending: not queued twice */
    uint32_t tx_restarted;            /* of those, in flight and waiting for a flow control: restarted at once */
    bool tx_blocked;                  /* this poll, a frame was refused by every link */
    uint32_t rx_results_gone[LS_ISOTP_N_RESULT_COUNT]; /* counters of evicted peers */
    uint32_t tx_results_gone[LS_ISOTP_N_RESULT_COUNT];
    uint8_t rxbuf[LS_ISOTP_MAX_PAYLOAD];
} ls_net_t;

void ls_net_init(ls_net_t *net, uint8_t node, ls_core_t *core);
/* Add an opened link (copied). Returns LS_OK, or LS_ENOSPC when the table is full. */
int ls_net_add_link(ls_net_t *net, const hal_can_link_t *link);
/* Receive and route every pending frame, run ISO-TP timers, deliver complete
 * messages to the core and start queued transmissions. A frame whose source
 * is the device's own address, or the address of a session bound to another
 * link (ls_core_session_link), is dropped before it is routed or bridged
 * (frames_foreign). Tells each link
 * whether sessions live on it (hal_can_hold_open: a peer whose last frame
 * came on it has a session in the core, or downlinks still to send). */
void ls_net_poll(ls_net_t *net, uint64_t now_us);
/* Send one frame on every link (broadcasts). Returns LS_OK when at least one
 * link took it (or there is none), else LS_EAGAIN. */
int ls_net_send_frame(ls_net_t *net, const hal_can_frame_t *frame);
/* The ls_core_io_t.send_downlink implementation: LS_OK (queued, or the same
 * message is already pending), LS_ELEN (empty or longer than a downlink),
 * LS_ENOSPC (no ISO-TP peer is free for `addr`), LS_EAGAIN (its queue is
 * full: the message is dropped and counted). */
int ls_net_send_downlink(void *net, uint8_t addr, const uint8_t *buf, size_t len);
/* When ls_net_poll next has work, for an event-driven caller's sleep
 * (frames arriving wake it otherwise): the earliest ISO-TP timer (STmin
 * pacing, N_Bs, N_Cr, a flow control to send), 0 (at once) while a queued
 * downlink or a restart waits to be started (downlinks queued since the
 * last poll, by ls_core_tick or a handler), UINT64_MAX when nothing waits.
 * While the links refuse our frames (the last poll's tx_blocked) a timer
 * already due is put off to LS_NET_TX_RETRY_US after that poll. O(peers),
 * no clock read. */
uint64_t ls_net_next_deadline_us(const ls_net_t *net);
void ls_net_close(ls_net_t *net);
/* Transport counters as key=value lines (the ls_core_io_t.describe hook). */
void ls_net_describe(void *net, char *buf, size_t cap);

#endif
