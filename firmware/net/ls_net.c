#include "ls_net.h" /* with cantools' landscape.h: protocol/landscape.dbc */

#include <string.h>

#include "ls_fmt.h"

/* Every downlink is one ISO-TP message: the largest the schema allows must fit
 * (protocol/landscape.options bounds it; describe is the largest answer). */
_Static_assert(LS_DOWNLINK_MAX <= LS_ISOTP_MAX_PAYLOAD, "ls.Downlink can exceed one ISO-TP message");
/* The ISO-TP module's defaults are the protocol's parameters, whose home is
 * the schema (enum IsotpParam; the host configures can-isotp from it). */
#define SAME_AS_SCHEMA(ours, param) _Static_assert((ours) == (unsigned)(param), #ours " differs from ls." #param)
SAME_AS_SCHEMA(LS_ISOTP_MAX_PAYLOAD, ls_IsotpParam_ISOTP_MAX_MESSAGE_BYTES);
SAME_AS_SCHEMA(LS_ISOTP_DEFAULT_BS, ls_IsotpParam_ISOTP_BLOCK_SIZE);
SAME_AS_SCHEMA(LS_ISOTP_DEFAULT_ST_MIN, ls_IsotpParam_ISOTP_ST_MIN);
SAME_AS_SCHEMA(LS_ISOTP_DEFAULT_PADDING_BYTE, ls_IsotpParam_ISOTP_PADDING_BYTE);
SAME_AS_SCHEMA(LS_ISOTP_DEFAULT_N_TIMEOUT_US, ls_IsotpParam_ISOTP_N_TIMEOUT_MS * 1000u);
/* Every session keeps its link and sources without one still find some. */
_Static_assert(LS_NET_MAX_PEERS >= LS_MAX_SUPERVISORS + 2, "too few ISO-TP links for the sessions");
_Static_assert(LS_NET_MAX_LINKS <= 127, "ls_net_peer_t.link is an int8_t");

bool ls_net_bucket_take(ls_net_bucket_t *b, uint32_t rate_per_s, uint32_t burst, uint64_t now_us)
{
    const uint64_t full = (uint64_t)burst * 1000u;
    if (!b->primed) {
        b->primed = true;
        b->milli = full;
        b->last_us = now_us;
    } else if (now_us > b->last_us) {
        /* rate tokens per 1e6 us = rate thousandths per 1e3 us; the last
         * stamp only moves when something was added, so slow rates still
         * refill when polled often */
        const uint64_t dt_us = now_us - b->last_us;
        const uint64_t add = dt_us > full * 1000u ? full : dt_us * rate_per_s / 1000u;
        if (add > 0) {
            b->milli = b->milli + add > full ? full : b->milli + add;
            b->last_us = now_us;
        }
    }
    if (b->milli < 1000u) {
        return false;
    }
    b->milli -= 1000u;
    return true;
}

static int isotp_send_frame(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len)
{
    ls_net_t *net = ctx;
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = can_id;
    f.flags = HAL_CAN_F_EXT;
    f.len = len;
    memcpy(f.data, data, len);
    return ls_net_send_frame(net, &f);
}

void ls_net_init(ls_net_t *net, uint8_t node, ls_core_t *core)
{
    memset(net, 0, sizeof *net);
    net->node = node;
    net->core = core;
    ls_isotp_default_config(&net->isotp_cfg);
}

int ls_net_add_link(ls_net_t *net, const hal_can_link_t *link)
{
    if (net->n_links >= LS_NET_MAX_LINKS) {
        return LS_ENOSPC;
    }
    net->links[net->n_links++] = *link;
    return LS_OK;
}

int ls_net_send_frame(ls_net_t *net, const hal_can_frame_t *frame)
{
    int ok = 0;
    for (size_t i = 0; i < net->n_links; i++) {
        if (hal_can_send(&net->links[i], frame) >= 0) {
            ok++;
        } else {
            net->tx_full++;
        }
    }
    if (ok > 0 || net->n_links == 0) {
        net->frames_out++;
        return LS_OK;
    }
    net->tx_blocked = true;
    return LS_EAGAIN;
}

static ls_net_peer_t *find_peer(ls_net_t *net, uint8_t addr)
{
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        if (net->peers[i].used && net->peers[i].addr == addr) {
            return &net->peers[i];
        }
    }
    return NULL;
}

static bool peer_idle(const ls_net_peer_t *c)
{
    return !ls_isotp_tx_busy(&c->isotp) && c->isotp.rx_state == LS_ISOTP_RX_IDLE && c->q_count == 0 && c->tx_tries == 0;
}

/* Pick the better victim of `a` and `b` (either may be NULL): the one made
 * progress least recently. */
static ls_net_peer_t *older(ls_net_peer_t *a, ls_net_peer_t *b)
{
    if (a == NULL) {
        return b;
    }
    return b != NULL && b->last_used_us < a->last_used_us ? b : a;
}

/* A peer for `addr`: an existing one, a free slot, or one of a source
 * without a session (ls_net.h LS_NET_MAX_PEERS): the least recently used
 * idle one (a supervisor that went away without a word), else the busy one
 * that made progress least recently, answers before receptions. */
static ls_net_peer_t *get_peer(ls_net_t *net, uint8_t addr)
{
    ls_net_peer_t *p = find_peer(net, addr);
    if (p != NULL) {
        return p;
    }
    ls_net_peer_t *victim = NULL, *idle = NULL, *sending = NULL, *receiving = NULL;
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        ls_net_peer_t *c = &net->peers[i];
        if (!c->used) {
            victim = c;
            break;
        }
        if (ls_core_session_of(net->core, c->addr) >= 0) {
            continue; /* reserved: a live session's link */
        }
        if (peer_idle(c)) {
            idle = older(idle, c);
        } else if (c->isotp.rx_state == LS_ISOTP_RX_IDLE) {
            sending = older(sending, c);
        } else {
            receiving = older(receiving, c);
        }
    }
    if (victim == NULL) {
        victim = idle != NULL ? idle : sending != NULL ? sending : receiving;
        if (victim == NULL) {
            return NULL; /* every link belongs to a session */
        }
        if (victim != idle) {
            net->peers_preempted++;
        }
    }
    if (victim->used) {
        net->peers_evicted++;
        for (int r = 0; r < LS_ISOTP_N_RESULT_COUNT; r++) {
            net->rx_results_gone[r] += victim->isotp.rx_results[r];
            net->tx_results_gone[r] += victim->isotp.tx_results[r];
        }
    }
    memset(victim, 0, sizeof *victim);
    victim->used = true;
    victim->addr = addr;
    victim->link = -1;
    victim->last_used_us = net->now_us;
    uint32_t tx_id = LS_ID_ISOTP_PHYS | ((uint32_t)addr << 8) | net->node;
    uint32_t rx_id = LS_ID_ISOTP_PHYS | ((uint32_t)net->node << 8) | addr;
    (void)ls_isotp_init(&victim->isotp, &net->isotp_cfg, tx_id, rx_id, isotp_send_frame, net);
    return victim;
}

/* The same bytes to the same peer are already waiting or in flight. A
 * retransmitted request is answered from the session's cache, byte for byte
 * the answer already on its way; a second copy would only queue behind the
 * first (and, when the link loses frames, hold up the answers after it). */
static bool already_pending(const ls_net_peer_t *p, const uint8_t *buf, size_t len)
{
    if (p->tx_tries > 0 && p->isotp.tx_len == len && memcmp(p->isotp.tx_buf, buf, len) == 0) {
        return true;
    }
    for (uint8_t i = 0; i < p->q_count; i++) {
        const ls_net_msg_t *m = &p->q[(p->q_head + i) % LS_NET_OUTQ];
        if (m->len == len && memcmp(m->buf, buf, len) == 0) {
            return true;
        }
    }
    return false;
}

int ls_net_send_downlink(void *ctx, uint8_t addr, const uint8_t *buf, size_t len)
{
    ls_net_t *net = ctx;
    if (len == 0 || len > LS_DOWNLINK_MAX) {
        return LS_ELEN; /* ISO-TP carries 1..LS_ISOTP_MAX_PAYLOAD bytes: it would stay queued */
    }
    ls_net_peer_t *p = get_peer(net, addr);
    if (p == NULL) {
        return LS_ENOSPC;
    }
    if (already_pending(p, buf, len)) {
        net->tx_deduplicated++;
        /* The answer to a retransmitted request, while that answer is in
         * flight: the supervisor did not get it (a lost consecutive frame
         * leaves our transfer waiting N_Bs for a flow control that will not
         * come), so ls_net_poll restarts a waiting transfer at once. */
        if (p->tx_tries > 0 && p->isotp.tx_len == len && memcmp(p->isotp.tx_buf, buf, len) == 0) {
            p->tx_asked_again = true;
        }
        return LS_OK;
    }
    if (p->q_count >= LS_NET_OUTQ) {
        p->q_dropped++;
        return LS_EAGAIN;
    }
    ls_net_msg_t *m = &p->q[(p->q_head + p->q_count) % LS_NET_OUTQ];
    memcpy(m->buf, buf, len);
    m->len = (uint16_t)len;
    p->q_count++;
    p->last_used_us = net->now_us;
    return LS_OK;
}

/* The downlink in the peer's ISO-TP link has finished its transfer: done
 * when it succeeded, else sent again up to LS_NET_TX_TRIES transfers. */
static void settle_tx(ls_net_t *net, ls_net_peer_t *p, uint64_t now_us)
{
    if (p->tx_tries == 0) {
        return;
    }
    if (p->isotp.tx_results[LS_ISOTP_N_OK] != p->tx_ok_mark) {
        p->tx_tries = 0;
        return;
    }
    if (p->tx_tries < LS_NET_TX_TRIES && ls_isotp_resend(&p->isotp, now_us) == LS_OK) {
        p->tx_tries++;
        net->tx_retried++;
        return;
    }
    p->tx_tries = 0;
    net->tx_given_up++;
}

static void route(ls_net_t *net, const hal_can_frame_t *f, size_t from)
{
    if ((f->flags & HAL_CAN_F_EXT) == 0u || (f->flags & HAL_CAN_F_RTR) != 0u) {
        return; /* everything of ours is a 29-bit data frame */
    }
    uint32_t pf = f->id & LS_ID_MASK_PF;
    uint8_t target = (uint8_t)((f->id >> 8) & 0xFFu);
    uint8_t source = (uint8_t)(f->id & 0xFFu);
    if (pf == LS_ID_ISOTP_PHYS && target == net->node) {
        ls_net_peer_t *p = get_peer(net, source);
        if (p != NULL) {
            p->last_used_us = net->now_us;
            p->link = (int8_t)from;
            ls_isotp_on_frame(&p->isotp, f->data, f->len, net->now_us);
            /* Take a completed message at once: the next frame of this
             * batch may already be the sender's next request. */
            size_t n = ls_isotp_take_rx(&p->isotp, net->rxbuf, sizeof net->rxbuf);
            if (n > 0) {
                ls_core_on_uplink(net->core, p->addr, (int)from, net->rxbuf, n, net->now_us);
            }
        }
    } else if (pf == LS_ID_ISOTP_FUNC && (target == LS_ADDR_ALL || target == net->node)) {
        uint8_t payload[8];
        size_t n = ls_isotp_decode_single(f->data, f->len, payload, sizeof payload);
        if (n > 0) {
            ls_core_on_functional(net->core, source, (int)from, payload, n, net->now_us);
        }
    } else if ((f->id & LS_ID_MASK_SRC) == LS_ID_HEARTBEAT) {
        /* The DBC's HEARTBEAT, multiplexed by hb_role: a supervisor's (1)
         * keeps its session when it carries the session's token (or MAC). */
        struct landscape_heartbeat_t hb;
        if (f->len == LANDSCAPE_HEARTBEAT_LENGTH && landscape_heartbeat_unpack(&hb, f->data, f->len) == 0 &&
            hb.hb_role == LANDSCAPE_HEARTBEAT_HB_ROLE_SUPERVISOR_CHOICE) {
            ls_core_on_heartbeat(net->core, source, hb.hb_counter, hb.hb_period_ms, hb.hb_token, net->now_us);
        }
    } else if ((f->id & LS_ID_MASK_SRC) == LS_ID_EMERGENCY && source != net->node) {
        ls_core_emergency(net->core, net->now_us);
    }
}

/* A frame no node on link `from` may send: one carrying the device's own
 * address as its source, or the address of a session bound to another link
 * segment (docs/protocol.md "Security": "Sessions bound to their link"). It
 * is neither routed nor bridged. */
static bool foreign(const ls_net_t *net, const hal_can_frame_t *f, size_t from)
{
    if ((f->flags & HAL_CAN_F_EXT) == 0u) {
        return false; /* 11-bit frames carry no source address of ours */
    }
    const uint8_t source = (uint8_t)(f->id & 0xFFu);
    if (source == net->node) {
        return true;
    }
    const int link = ls_core_session_link(net->core, source);
    return link >= 0 && (size_t)link != from;
}

/* Copy a frame received on link `from` to every other link, within each
 * output link's forward budget (ls_net.h LS_NET_FWD_RATE_FPS). */
static void forward(ls_net_t *net, const hal_can_frame_t *f, size_t from)
{
    const bool emergency = (f->flags & HAL_CAN_F_EXT) != 0u && (f->id & LS_ID_MASK_SRC) == LS_ID_EMERGENCY;
    for (size_t i = 0; i < net->n_links; i++) {
        if (i == from) {
            continue;
        }
        const bool ok = emergency
                            ? ls_net_bucket_take(&net->fwd_emergency[i], LS_NET_FWD_EMERGENCY_RATE_FPS,
                                                 LS_NET_FWD_EMERGENCY_BURST, net->now_us)
                            : ls_net_bucket_take(&net->fwd[i], LS_NET_FWD_RATE_FPS, LS_NET_FWD_BURST, net->now_us);
        if (!ok) {
            if (emergency) {
                net->fwd_emergency_dropped++;
            } else {
                net->fwd_dropped++;
            }
            continue;
        }
        if (hal_can_send(&net->links[i], f) >= 0) {
            net->frames_bridged++;
        } else {
            net->tx_full++;
        }
    }
}

/* A link is held open while a peer whose frames came on it has a live
 * session or downlinks still to send (hal_can_hold_open). */
static void hold_links(ls_net_t *net)
{
    bool held[LS_NET_MAX_LINKS] = { false };
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        const ls_net_peer_t *p = &net->peers[i];
        if (p->used && p->link >= 0 && (size_t)p->link < net->n_links &&
            (!peer_idle(p) || ls_core_session_of(net->core, p->addr) >= 0)) {
            held[p->link] = true;
        }
    }
    for (size_t i = 0; i < net->n_links; i++) {
        if (held[i] != net->link_held[i]) {
            net->link_held[i] = held[i];
            (void)hal_can_hold_open(&net->links[i], held[i]);
        }
    }
}

void ls_net_poll(ls_net_t *net, uint64_t now_us)
{
    net->now_us = now_us;
    net->tx_blocked = false;
    for (size_t i = 0; i < net->n_links; i++) {
        hal_can_frame_t f;
        /* Bounded per turn so one busy link cannot starve the others. */
        for (int k = 0; k < 256 && hal_can_recv(&net->links[i], &f) == 1; k++) {
            net->frames_in++;
            if (foreign(net, &f, i)) {
                net->frames_foreign++;
                continue;
            }
            if (net->n_links > 1) {
                forward(net, &f, i);
            }
            route(net, &f, i);
        }
    }
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        ls_net_peer_t *p = &net->peers[i];
        if (!p->used) {
            continue;
        }
        ls_isotp_poll(&p->isotp, now_us);
        size_t n = ls_isotp_take_rx(&p->isotp, net->rxbuf, sizeof net->rxbuf);
        if (n > 0) {
            ls_core_on_uplink(net->core, p->addr, p->link, net->rxbuf, n, now_us);
        }
        if (p->tx_asked_again) {
            p->tx_asked_again = false;
            if (p->tx_tries > 0 && ls_isotp_restart_waiting(&p->isotp, now_us) == LS_OK) {
                net->tx_restarted++;
            }
        }
        /* Settle the finished transfer, start the next downlink; again while
         * one finishes at once (a single frame the link took), so nothing
         * is left for a later turn: an event-driven caller would sleep on
         * it (ls_net_next_deadline_us). Bounded by LS_NET_OUTQ starts and
         * LS_NET_TX_TRIES transfers each. */
        for (;;) {
            if (!ls_isotp_tx_busy(&p->isotp)) {
                settle_tx(net, p, now_us);
            }
            if (p->q_count == 0 || p->tx_tries != 0 || ls_isotp_tx_busy(&p->isotp)) {
                break;
            }
            ls_net_msg_t *m = &p->q[p->q_head];
            uint32_t ok_mark = p->isotp.tx_results[LS_ISOTP_N_OK];
            if (ls_isotp_send(&p->isotp, m->buf, m->len, now_us) != LS_OK) {
                break;
            }
            p->q_head = (uint8_t)((p->q_head + 1u) % LS_NET_OUTQ);
            p->q_count--;
            p->tx_tries = 1;
            p->tx_ok_mark = ok_mark;
        }
    }
    hold_links(net);
}

uint64_t ls_net_next_deadline_us(const ls_net_t *net)
{
    uint64_t t = UINT64_MAX;
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        const ls_net_peer_t *p = &net->peers[i];
        if (!p->used) {
            continue;
        }
        const bool tx_busy = ls_isotp_tx_busy(&p->isotp);
        if (p->tx_asked_again || (!tx_busy && (p->tx_tries > 0 || p->q_count > 0))) {
            return 0; /* a transfer to settle, start or restart (ls_net_poll's peer pass) */
        }
        uint64_t d = ls_isotp_next_deadline_us(&p->isotp);
        t = d < t ? d : t;
    }
    if (net->tx_blocked && t <= net->now_us) {
        t = net->now_us + LS_NET_TX_RETRY_US;
    }
    return t;
}

void ls_net_close(ls_net_t *net)
{
    for (size_t i = 0; i < net->n_links; i++) {
        hal_can_close(&net->links[i]);
    }
    net->n_links = 0;
}

void ls_net_describe(void *ctx, char *buf, size_t cap)
{
    ls_net_t *net = ctx;
    uint32_t rx[LS_ISOTP_N_RESULT_COUNT], tx[LS_ISOTP_N_RESULT_COUNT];
    for (int r = 0; r < LS_ISOTP_N_RESULT_COUNT; r++) {
        rx[r] = net->rx_results_gone[r];
        tx[r] = net->tx_results_gone[r];
    }
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        if (net->peers[i].used) {
            for (int r = 0; r < LS_ISOTP_N_RESULT_COUNT; r++) {
                rx[r] += net->peers[i].isotp.rx_results[r];
                tx[r] += net->peers[i].isotp.tx_results[r];
            }
        }
    }
    uint32_t link_rx_dropped = 0, link_tx_dropped = 0, link_close_held = 0;
    for (size_t i = 0; i < net->n_links; i++) {
        hal_can_status_t st;
        memset(&st, 0, sizeof st);
        if (hal_can_status(&net->links[i], &st) >= 0) {
            link_rx_dropped += st.rx_dropped;
            link_tx_dropped += st.tx_dropped;
            link_close_held += st.close_held;
        }
    }
    size_t n = 0;
    int w = ls_fmt_print(
        buf, cap,
        "frames_in=%u\nframes_out=%u\ntx_full=%u\nlink_rx_dropped=%u\nlink_tx_dropped=%u\n"
        "peers_evicted=%u\npeers_preempted=%u\ntx_retried=%u\ntx_given_up=%u\ntx_deduplicated=%u\ntx_restarted=%u\n"
        "frames_bridged=%u\nfwd_dropped=%u\nfwd_emergency_dropped=%u\nlink_close_held=%u\nframes_foreign=%u\n",
        (unsigned)net->frames_in, (unsigned)net->frames_out, (unsigned)net->tx_full, (unsigned)link_rx_dropped,
        (unsigned)link_tx_dropped, (unsigned)net->peers_evicted, (unsigned)net->peers_preempted,
        (unsigned)net->tx_retried, (unsigned)net->tx_given_up, (unsigned)net->tx_deduplicated,
        (unsigned)net->tx_restarted, (unsigned)net->frames_bridged, (unsigned)net->fwd_dropped,
        (unsigned)net->fwd_emergency_dropped, (unsigned)link_close_held, (unsigned)net->frames_foreign);
    n = w > 0 ? (size_t)w : 0u;
    for (int r = 0; r < LS_ISOTP_N_RESULT_COUNT && n < cap; r++) {
        /* e.g. isotp_unexp_pdu=1: receive and send outcomes together, by ISO name */
        const char *name = ls_isotp_result_name((ls_isotp_result_t)r);
        char lower[32];
        size_t k = 0;
        for (; name[k] != '\0' && k + 1 < sizeof lower; k++) {
            char ch = name[k];
            lower[k] = (char)(ch >= 'A' && ch <= 'Z' ? ch - 'A' + 'a' : ch);
        }
        lower[k] = '\0';
        const char *suffix = strncmp(lower, "n_", 2) == 0 ? lower + 2 : lower;
        w = ls_fmt_print(buf + n, cap - n, "isotp_%s=%u\n", suffix, (unsigned)(rx[r] + tx[r]));
        n += w > 0 ? (size_t)w : 0u;
    }
}
