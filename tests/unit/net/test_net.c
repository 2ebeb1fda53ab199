/* ls_net, black box: CAN frames in on fake hal_can links, calls into the
 * core and frames out.
 *
 * The core is a test double: the entry points the network layer calls
 * (ls_core_on_uplink, ls_core_on_functional, ls_core_on_heartbeat,
 * ls_core_emergency, and the lookups ls_core_session_of, ls_core_session_link) are
 * redirected here at link time (-Wl,--wrap, as tests/unit/core does for the
 * control loop), so a test sees exactly which messages reached the core, from
 * which address, without encoding protobuf requests; the real core's
 * answers are covered by tests/unit/core and the integration tier. When
 * asked, the double answers an uplink through ls_net_send_downlink as the
 * core does, to drive the downlink path.
 *
 * The supervisors on the far side are real ls_isotp links (tests/unit/isotp
 * covers the transport itself) whose frames the test queues on a fake link.
 * The peer table is looked at directly only to tell which peer an eviction
 * chose. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_net.h"

/* A STATUS broadcast of node 0x42 (the DBC's id with that sender). */
#define STATUS_OF_42 (LS_ID_OF_DBC(LANDSCAPE_STATUS_FRAME_ID) | 0x42u)

#define NODE 0x01u
#define SUP_A 0x21u
#define SUP_B 0x22u

/* ---------------------------------------------------------------- fake links */

#define LINK_Q 512

typedef struct {
    hal_can_frame_t rx[LINK_Q];
    size_t rx_head, rx_count;
    hal_can_frame_t tx[LINK_Q];
    size_t n_tx;
    int refuse_send; /* send returns LS_EAGAIN */
    int closed;
    int held;       /* the last hal_can_hold_open */
    int hold_calls; /* how often it changed */
} fake_link_t;

static int link_send(void *self, const hal_can_frame_t *frame)
{
    fake_link_t *l = self;
    if (l->refuse_send || l->n_tx >= LINK_Q) {
        return LS_EAGAIN;
    }
    l->tx[l->n_tx++] = *frame;
    return LS_OK;
}

static int link_recv(void *self, hal_can_frame_t *frame)
{
    fake_link_t *l = self;
    if (l->rx_count == 0) {
        return LS_EAGAIN;
    }
    *frame = l->rx[l->rx_head];
    l->rx_head = (l->rx_head + 1u) % LINK_Q;
    l->rx_count--;
    return 1;
}

static uint32_t g_status_count = 2; /* what every fake link's status counts */

static int link_status(void *self, hal_can_status_t *out)
{
    (void)self;
    memset(out, 0, sizeof *out);
    out->rx_dropped = g_status_count;
    out->tx_dropped = g_status_count == 2 ? 0 : g_status_count;
    out->close_held = g_status_count == 2 ? 0 : g_status_count;
    return LS_OK;
}

static void link_close(void *self)
{
    ((fake_link_t *)self)->closed++;
}

static int link_hold_open(void *self, bool hold)
{
    fake_link_t *l = self;
    l->held = hold ? 1 : 0;
    l->hold_calls++;
    return LS_OK;
}

static const hal_can_ops_t LINK_OPS = {
    .send = link_send, .recv = link_recv, .status = link_status, .close = link_close, .hold_open = link_hold_open
};

static void link_put(fake_link_t *l, uint32_t id, uint8_t flags, const uint8_t *data, uint8_t len)
{
    assert_true(l->rx_count < LINK_Q);
    hal_can_frame_t *f = &l->rx[(l->rx_head + l->rx_count) % LINK_Q];
    memset(f, 0, sizeof *f);
    f->id = id;
    f->flags = flags;
    f->len = len;
    memcpy(f->data, data, len);
    l->rx_count++;
}

/* ---------------------------------------------------------------- core double */

#define MAX_CALLS 64

typedef enum { CALL_UPLINK = 1, CALL_FUNCTIONAL, CALL_HEARTBEAT, CALL_EMERGENCY } call_kind_t;

typedef struct {
    call_kind_t kind;
    uint8_t addr;
    uint8_t buf[LS_ISOTP_MAX_PAYLOAD];
    size_t len;
    char text[64];
    uint32_t token; /* a heartbeat's hb_token */
    int link;       /* the link an uplink came on */
    uint64_t now_us;
} call_t;

static call_t g_calls[MAX_CALLS];
static size_t g_ncalls;
static ls_net_t g_net;
static ls_core_t *const CORE = (ls_core_t *)&g_calls; /* an address the double checks, never dereferenced */
static size_t g_echo_len;                             /* > 0: answer each uplink with this many bytes */

void __wrap_ls_core_on_uplink(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len, uint64_t now_us);
void __wrap_ls_core_on_functional(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len,
                                  uint64_t now_us);
void __wrap_ls_core_on_heartbeat(ls_core_t *core, uint8_t addr, uint8_t counter, uint16_t period_ms, uint32_t token,
                                 uint64_t now_us);
void __wrap_ls_core_emergency(ls_core_t *core, uint64_t now_us);
int __wrap_ls_core_session_of(const ls_core_t *core, uint8_t addr);
int __wrap_ls_core_session_link(const ls_core_t *core, uint8_t addr);

/* Addresses the double says have a live session, and the link each is bound
 * to (-1: none; the session's link only counts where g_session is set). */
static bool g_session[256];
static int g_session_link[256];

static call_t *record(ls_core_t *core, call_kind_t kind, uint8_t addr, uint64_t now_us)
{
    assert_ptr_equal(core, CORE);
    assert_true(g_ncalls < MAX_CALLS);
    call_t *c = &g_calls[g_ncalls++];
    memset(c, 0, sizeof *c);
    c->kind = kind;
    c->addr = addr;
    c->now_us = now_us;
    return c;
}

void __wrap_ls_core_on_uplink(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len, uint64_t now_us)
{
    call_t *c = record(core, CALL_UPLINK, addr, now_us);
    assert_true(len <= sizeof c->buf);
    memcpy(c->buf, buf, len);
    c->len = len;
    c->link = link;
    if (g_echo_len > 0) {
        static uint8_t answer[LS_DOWNLINK_MAX];
        for (size_t i = 0; i < g_echo_len; i++) {
            answer[i] = (uint8_t)(buf[0] + i);
        }
        assert_int_equal(ls_net_send_downlink(&g_net, addr, answer, g_echo_len), 0);
    }
}

void __wrap_ls_core_on_functional(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len,
                                  uint64_t now_us)
{
    call_t *c = record(core, CALL_FUNCTIONAL, addr, now_us);
    assert_true(len <= sizeof c->buf);
    memcpy(c->buf, buf, len);
    c->len = len;
    c->link = link;
}

void __wrap_ls_core_on_heartbeat(ls_core_t *core, uint8_t addr, uint8_t counter, uint16_t period_ms, uint32_t token,
                                 uint64_t now_us)
{
    (void)counter;
    (void)period_ms;
    record(core, CALL_HEARTBEAT, addr, now_us)->token = token;
}

void __wrap_ls_core_emergency(ls_core_t *core, uint64_t now_us)
{
    (void)record(core, CALL_EMERGENCY, 0, now_us);
}

int __wrap_ls_core_session_of(const ls_core_t *core, uint8_t addr)
{
    assert_ptr_equal(core, CORE);
    return g_session[addr] ? 0 : -1;
}

int __wrap_ls_core_session_link(const ls_core_t *core, uint8_t addr)
{
    assert_ptr_equal(core, CORE);
    return g_session[addr] ? g_session_link[addr] : -1;
}

/* ---------------------------------------------------------------- fixture */

static fake_link_t g_link[3];

static void setup_net(size_t n_links)
{
    memset(g_link, 0, sizeof g_link);
    memset(g_calls, 0, sizeof g_calls);
    memset(g_session, 0, sizeof g_session);
    memset(g_session_link, 0, sizeof g_session_link);
    g_ncalls = 0;
    g_echo_len = 0;
    ls_net_init(&g_net, NODE, CORE);
    for (size_t i = 0; i < n_links; i++) {
        hal_can_link_t l = { .ops = &LINK_OPS, .self = &g_link[i] };
        snprintf(l.name, sizeof l.name, "fake%zu", i);
        assert_int_equal(ls_net_add_link(&g_net, &l), 0);
    }
}

/* A supervisor: a real ISO-TP link whose frames go into one fake link. */
typedef struct {
    uint8_t addr;
    fake_link_t *via;
    ls_isotp_link_t tp;
} sup_t;

static int sup_send(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len)
{
    sup_t *s = ctx;
    link_put(s->via, can_id, HAL_CAN_F_EXT, data, len);
    return 0;
}

static void sup_init(sup_t *s, uint8_t addr, fake_link_t *via)
{
    s->addr = addr;
    s->via = via;
    uint32_t tx = LS_ID_ISOTP_PHYS | (NODE << 8) | addr;
    uint32_t rx = LS_ID_ISOTP_PHYS | ((uint32_t)addr << 8) | NODE;
    assert_int_equal(ls_isotp_init(&s->tp, NULL, tx, rx, sup_send, s), LS_OK);
}

/* Feed the supervisor every frame the node sent to it on `link` since index *seen. */
static void sup_hear(sup_t *s, const fake_link_t *link, size_t *seen, uint64_t now_us)
{
    for (; *seen < link->n_tx; (*seen)++) {
        const hal_can_frame_t *f = &link->tx[*seen];
        if (f->id == s->tp.rx_id) {
            ls_isotp_on_frame(&s->tp, f->data, f->len, now_us);
        }
    }
}

static void put_sf(fake_link_t *l, uint32_t id, const uint8_t *payload, uint8_t n)
{
    uint8_t d[8];
    uint8_t len = ls_isotp_encode_single(payload, n, true, 0xCC, d);
    assert_true(len > 0);
    link_put(l, id, HAL_CAN_F_EXT, d, len);
}

static uint32_t phys(uint8_t target, uint8_t source)
{
    return LS_ID_ISOTP_PHYS | ((uint32_t)target << 8) | source;
}

static uint32_t func(uint8_t target, uint8_t source)
{
    return LS_ID_ISOTP_FUNC | ((uint32_t)target << 8) | source;
}

static bool peer_used(uint8_t addr)
{
    for (size_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        if (g_net.peers[i].used && g_net.peers[i].addr == addr) {
            return true;
        }
    }
    return false;
}

static unsigned describe_value(const char *key)
{
    char buf[1024];
    ls_net_describe(&g_net, buf, sizeof buf);
    char pat[64];
    snprintf(pat, sizeof pat, "%s=", key);
    const char *p = strstr(buf, pat);
    if (p == NULL) {
        fail_msg("no %s in the description:\n%s", key, buf);
        return 0;
    }
    return (unsigned)strtoul(p + strlen(pat), NULL, 10);
}

/* ---------------------------------------------------------------- routing by id */

static void test_physical_single_frame_reaches_the_core(void **state)
{
    (void)state;
    setup_net(1);
    const uint8_t req[] = { 0x0A, 0x03, 0x08, 0x01 };
    put_sf(&g_link[0], phys(NODE, SUP_A), req, sizeof req);
    put_sf(&g_link[0], phys(0x05, SUP_A), req, sizeof req); /* another device's */
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_ncalls, 1);
    assert_int_equal(g_calls[0].kind, CALL_UPLINK);
    assert_int_equal(g_calls[0].addr, SUP_A);
    assert_int_equal(g_calls[0].len, sizeof req);
    assert_memory_equal(g_calls[0].buf, req, sizeof req);
    assert_int_equal(g_calls[0].now_us, 1000);
    assert_int_equal(describe_value("frames_in"), 2);
    assert_true(peer_used(SUP_A));
    assert_false(peer_used(0x05));
}

static void test_frames_that_are_not_ours_are_ignored(void **state)
{
    (void)state;
    setup_net(1);
    const uint8_t d[8] = { 0x02, 0x0A, 0x00 };
    /* Our id with an 11-bit identifier, and as a remote frame. */
    link_put(&g_link[0], phys(NODE, SUP_A) & 0x7FFu, 0, d, 8);
    link_put(&g_link[0], phys(NODE, SUP_A), HAL_CAN_F_EXT | HAL_CAN_F_RTR, d, 0);
    /* An unrelated 29-bit id. */
    link_put(&g_link[0], (LS_ID_OF_DBC(LANDSCAPE_STATUS_FRAME_ID) | 0x21u), HAL_CAN_F_EXT, d, 8);
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_ncalls, 0);
    assert_false(peer_used(SUP_A));
    assert_int_equal(describe_value("frames_in"), 3);
}

static void test_functional_single_frames(void **state)
{
    (void)state;
    setup_net(1);
    const uint8_t req[] = { 0x11, 0x22 };
    put_sf(&g_link[0], func(LS_ADDR_ALL, SUP_A), req, sizeof req); /* every device */
    put_sf(&g_link[0], func(NODE, SUP_B), req, sizeof req);        /* this device */
    put_sf(&g_link[0], func(0x07, SUP_A), req, sizeof req);        /* another device */
    /* A first frame on the functional id: functional addressing is single frames only. */
    const uint8_t ff[8] = { 0x10, 0x20, 1, 2, 3, 4, 5, 6 };
    link_put(&g_link[0], func(LS_ADDR_ALL, SUP_A), HAL_CAN_F_EXT, ff, 8);
    ls_net_poll(&g_net, 2000);
    assert_int_equal(g_ncalls, 2);
    assert_int_equal(g_calls[0].kind, CALL_FUNCTIONAL);
    assert_int_equal(g_calls[0].addr, SUP_A);
    assert_int_equal(g_calls[1].addr, SUP_B);
    assert_int_equal(g_calls[1].len, 2);
    assert_memory_equal(g_calls[1].buf, req, 2);
    /* Functional requests need no ISO-TP link: no peer taken. */
    assert_false(peer_used(SUP_A));
    assert_false(peer_used(SUP_B));
}

static void test_heartbeats(void **state)
{
    (void)state;
    setup_net(1);
    uint8_t hb[8] = { 0 };
    hb[2] = 1;    /* role: supervisor */
    hb[5] = 0x56; /* hb_token, 24 bits little-endian in bytes 5..7 (protocol/landscape.dbc) */
    hb[6] = 0x34;
    hb[7] = 0x12;
    link_put(&g_link[0], LS_ID_HEARTBEAT | SUP_A, HAL_CAN_F_EXT, hb, 8);
    hb[2] = 0; /* a controller's heartbeat (another device) */
    link_put(&g_link[0], LS_ID_HEARTBEAT | 0x02u, HAL_CAN_F_EXT, hb, 8);
    hb[2] = 1;
    link_put(&g_link[0], LS_ID_HEARTBEAT | SUP_B, HAL_CAN_F_EXT, hb, 2); /* too short for a role */
    ls_net_poll(&g_net, 3000);
    assert_int_equal(g_ncalls, 1);
    assert_int_equal(g_calls[0].kind, CALL_HEARTBEAT);
    assert_int_equal(g_calls[0].addr, SUP_A);
    assert_int_equal(g_calls[0].token, 0x123456);
    assert_int_equal(g_calls[0].now_us, 3000);
}

static void test_emergency_frames(void **state)
{
    (void)state;
    setup_net(1);
    const uint8_t d[8] = { 0 };
    link_put(&g_link[0], LS_ID_EMERGENCY | NODE, HAL_CAN_F_EXT, d, 8);  /* our own, echoed: ignored */
    link_put(&g_link[0], LS_ID_EMERGENCY | SUP_A, HAL_CAN_F_EXT, d, 8); /* a supervisor's */
    ls_net_poll(&g_net, 4000);
    assert_int_equal(g_ncalls, 1);
    assert_int_equal(g_calls[0].kind, CALL_EMERGENCY);
    assert_int_equal(g_calls[0].now_us, 4000);
}

/* Physical frames go to the sender's own ISO-TP link: two supervisors'
 * multi-frame requests interleave frame by frame and both arrive whole. */
static void test_interleaved_multi_frame_requests_stay_apart(void **state)
{
    (void)state;
    setup_net(1);
    static sup_t a, b;
    sup_init(&a, SUP_A, &g_link[0]);
    sup_init(&b, SUP_B, &g_link[0]);
    static uint8_t ma[300], mb[200];
    for (size_t i = 0; i < sizeof ma; i++) {
        ma[i] = (uint8_t)i;
    }
    for (size_t i = 0; i < sizeof mb; i++) {
        mb[i] = (uint8_t)(0xFF - i);
    }
    uint64_t t = 10000;
    assert_int_equal(ls_isotp_send(&a.tp, ma, sizeof ma, t), LS_OK);
    assert_int_equal(ls_isotp_send(&b.tp, mb, sizeof mb, t), LS_OK);
    size_t seen_a = 0, seen_b = 0;
    for (int turn = 0; turn < 200 && g_ncalls < 2; turn++) {
        t += 100;
        ls_net_poll(&g_net, t); /* the node answers each first frame with a flow control */
        sup_hear(&a, &g_link[0], &seen_a, t);
        sup_hear(&b, &g_link[0], &seen_b, t);
        ls_isotp_poll(&a.tp, t); /* one block of CFs each, alternately */
        ls_isotp_poll(&b.tp, t);
    }
    assert_int_equal(g_ncalls, 2);
    const call_t *ca = g_calls[0].addr == SUP_A ? &g_calls[0] : &g_calls[1];
    const call_t *cb = g_calls[0].addr == SUP_A ? &g_calls[1] : &g_calls[0];
    assert_int_equal(ca->addr, SUP_A);
    assert_int_equal(cb->addr, SUP_B);
    assert_int_equal(ca->len, sizeof ma);
    assert_memory_equal(ca->buf, ma, sizeof ma);
    assert_int_equal(cb->len, sizeof mb);
    assert_memory_equal(cb->buf, mb, sizeof mb);
    assert_int_equal(describe_value("isotp_ok"), 2);
}

/* The answer goes back on the sender's link as ISO-TP 0x18DA<sup><node>. */
static void test_answer_is_sent_to_the_sender(void **state)
{
    (void)state;
    setup_net(1);
    static sup_t a;
    sup_init(&a, SUP_A, &g_link[0]);
    g_echo_len = 100; /* multi-frame answer */
    const uint8_t req[] = { 0x40 };
    assert_int_equal(ls_isotp_send(&a.tp, req, sizeof req, 0), LS_OK);
    size_t seen = 0;
    uint8_t got[LS_ISOTP_MAX_PAYLOAD];
    size_t n = 0;
    uint64_t t = 0;
    for (int turn = 0; turn < 100 && n == 0; turn++) {
        t += 100;
        ls_net_poll(&g_net, t);
        sup_hear(&a, &g_link[0], &seen, t);
        ls_isotp_poll(&a.tp, t);
        n = ls_isotp_take_rx(&a.tp, got, sizeof got);
    }
    assert_int_equal(n, 100);
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(got[i], (uint8_t)(0x40 + i));
    }
    assert_int_equal(g_link[0].tx[0].id, phys(SUP_A, NODE));
    assert_int_equal(g_link[0].tx[0].flags, HAL_CAN_F_EXT);
    assert_int_equal(g_link[0].tx[0].data[0] & 0xF0, 0x10); /* first frame */
}

static void test_downlink_queue_is_bounded(void **state)
{
    (void)state;
    setup_net(1);
    uint8_t msg[20] = { 1 };
    /* While the first message waits for its flow control, LS_NET_OUTQ queue behind it. */
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, msg, sizeof msg), 0);
    ls_net_poll(&g_net, 100);
    assert_int_equal(g_link[0].n_tx, 1); /* the first frame */
    for (int i = 0; i < LS_NET_OUTQ; i++) {
        msg[1] = (uint8_t)(i + 1); /* distinct messages (identical ones are not queued twice) */
        assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, msg, sizeof msg), 0);
    }
    msg[1] = 0xEE;
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, msg, sizeof msg), LS_EAGAIN);
    /* Too long for a downlink: refused. */
    static uint8_t big[LS_DOWNLINK_MAX + 1];
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_B, big, sizeof big), LS_ELEN);
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_B, big, 0), LS_ELEN); /* empty: ISO-TP carries none */
    /* Waiting for a flow control: the poll deadline is N_Bs away. */
    uint64_t d = ls_net_next_deadline_us(&g_net);
    assert_true(d > 100 && d <= 100 + 1000000u);
}

/* ------------------------------------------------ the comms thread's sleep */

/* ls_net_next_deadline_us says when ls_net_poll next has work: the comms
 * thread sleeps until then unless a frame arrives. */
static void test_next_deadline_says_when_the_poll_has_work(void **state)
{
    (void)state;
    setup_net(1);
    assert_true(ls_net_next_deadline_us(&g_net) == UINT64_MAX); /* nothing at all */
    /* A single-frame downlink queued (by a handler, by ls_core_tick): at once. */
    const uint8_t sf[5] = { 1, 2, 3, 4, 5 };
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, sf, sizeof sf), 0);
    assert_true(ls_net_next_deadline_us(&g_net) == 0);
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_link[0].n_tx, 1);
    assert_true(ls_net_next_deadline_us(&g_net) == UINT64_MAX); /* sent and settled in the same poll */
    /* Two more: both go out in one poll, nothing is left for a later turn. */
    const uint8_t sf2[3] = { 7, 8, 9 };
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, sf, sizeof sf), 0);
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, sf2, sizeof sf2), 0);
    ls_net_poll(&g_net, 1500);
    assert_int_equal(g_link[0].n_tx, 3);
    assert_true(ls_net_next_deadline_us(&g_net) == UINT64_MAX);
    /* A multi-frame one: its first frame, then N_Bs for the flow control. */
    uint8_t mf[20];
    memset(mf, 0x5A, sizeof mf);
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, mf, sizeof mf), 0);
    ls_net_poll(&g_net, 2000);
    assert_int_equal(g_link[0].n_tx, 4);
    assert_true(ls_net_next_deadline_us(&g_net) == 2000u + g_net.isotp_cfg.n_bs_timeout_us);
    /* The flow control comes while the link refuses our frames: the due
     * consecutive frames wait LS_NET_TX_RETRY_US, not zero (no spinning). */
    const uint8_t fc[8] = { 0x30, 0, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC };
    link_put(&g_link[0], phys(NODE, SUP_A), HAL_CAN_F_EXT, fc, sizeof fc);
    g_link[0].refuse_send = 1;
    ls_net_poll(&g_net, 3000);
    assert_int_equal(g_link[0].n_tx, 4);
    assert_true(ls_net_next_deadline_us(&g_net) == 3000u + LS_NET_TX_RETRY_US);
    g_link[0].refuse_send = 0;
    ls_net_poll(&g_net, 3000u + LS_NET_TX_RETRY_US);
    assert_int_equal(g_link[0].n_tx, 6); /* 6 + 7 bytes in two consecutive frames */
    assert_true(ls_net_next_deadline_us(&g_net) == UINT64_MAX);
}

/* The comms thread's loop without a fixed period: it polls only when a
 * frame is waiting or the deadline has come, and a multi-frame request
 * and answer complete, with no time passing (STmin 0: no timer runs). */
static void test_an_event_driven_loop_completes_an_exchange(void **state)
{
    (void)state;
    setup_net(1);
    static sup_t a;
    sup_init(&a, SUP_A, &g_link[0]);
    const size_t answer_len = LS_DOWNLINK_MAX < 300u ? LS_DOWNLINK_MAX : 300u;
    g_echo_len = answer_len; /* multi-frame answer, several blocks of BS 8 */
    uint8_t req[40];
    memset(req, 0x40, sizeof req);
    assert_int_equal(ls_isotp_send(&a.tp, req, sizeof req, 0), LS_OK);
    size_t seen = 0, n = 0;
    uint8_t got[LS_ISOTP_MAX_PAYLOAD];
    uint64_t t = 0;
    int polls = 0;
    while (n == 0 && polls < 200) {
        if (g_link[0].rx_count == 0) { /* no frame: sleep until the next deadline */
            uint64_t due = ls_net_next_deadline_us(&g_net);
            const uint64_t sup_due = ls_isotp_next_deadline_us(&a.tp);
            due = sup_due < due ? sup_due : due;
            assert_true(due != UINT64_MAX); /* else the exchange would hang */
            t = due > t ? due : t;
        }
        ls_net_poll(&g_net, t);
        polls++;
        sup_hear(&a, &g_link[0], &seen, t);
        ls_isotp_poll(&a.tp, t);
        n = ls_isotp_take_rx(&a.tp, got, sizeof got);
    }
    assert_int_equal(n, answer_len);
    assert_int_equal(g_calls[0].len, sizeof req);
    assert_true(t == 0);
    assert_true(polls < 20);
}

/* ---------------------------------------------------------------- LRU eviction */

static void ping(uint8_t addr, uint64_t now_us)
{
    const uint8_t req[] = { addr };
    put_sf(&g_link[0], phys(NODE, addr), req, 1);
    ls_net_poll(&g_net, now_us);
}

/* First frames the node sent to `addr` on link 0 of a message whose first
 * byte is `first` (each starts one transfer of it). */
static size_t first_frames_to(uint8_t addr, uint8_t first)
{
    size_t n = 0;
    for (size_t i = 0; i < g_link[0].n_tx; i++) {
        const hal_can_frame_t *f = &g_link[0].tx[i];
        if (f->id == phys(addr, NODE) && (f->data[0] & 0xF0u) == 0x10u && f->data[2] == first) {
            n++;
        }
    }
    return n;
}

#define PAST_N_BS_US 1001000u /* the default N_Bs (1 s) and a little */

static void test_a_downlink_without_flow_control_is_sent_again_then_given_up(void **state)
{
    (void)state;
    setup_net(1);
    uint8_t msg[20] = { 7 };
    uint8_t next[20] = { 8 };
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, msg, sizeof msg), 0);
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, next, sizeof next), 0); /* queued behind */
    uint64_t t = 100;
    ls_net_poll(&g_net, t);
    assert_int_equal(first_frames_to(SUP_A, 7), 1);
    /* Nobody answers with a flow control: each N_Bs time-out starts the same
     * message again, LS_NET_TX_TRIES transfers in all, the queued one waits. */
    for (size_t k = 2; k <= LS_NET_TX_TRIES; k++) {
        t += PAST_N_BS_US;
        ls_net_poll(&g_net, t);
        assert_int_equal(first_frames_to(SUP_A, 7), k);
        assert_int_equal(first_frames_to(SUP_A, 8), 0);
    }
    assert_int_equal(describe_value("tx_retried"), LS_NET_TX_TRIES - 1);
    assert_int_equal(describe_value("tx_given_up"), 0);
    /* The last transfer fails too: given up, counted, and the next message goes. */
    t += PAST_N_BS_US;
    ls_net_poll(&g_net, t);
    assert_int_equal(describe_value("tx_given_up"), 1);
    assert_int_equal(describe_value("isotp_timeout_bs"), LS_NET_TX_TRIES);
    assert_int_equal(first_frames_to(SUP_A, 7), LS_NET_TX_TRIES);
    assert_int_equal(first_frames_to(SUP_A, 8), 1);
}

static void test_a_downlink_sent_again_arrives_once(void **state)
{
    (void)state;
    setup_net(1);
    static sup_t a;
    sup_init(&a, SUP_A, &g_link[0]);
    uint8_t msg[40];
    for (size_t i = 0; i < sizeof msg; i++) {
        msg[i] = (uint8_t)(0x30 + i);
    }
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, msg, sizeof msg), 0);
    uint64_t t = 100;
    ls_net_poll(&g_net, t);
    /* The supervisor misses the first frame (busy for a moment)... */
    size_t seen = g_link[0].n_tx;
    t += PAST_N_BS_US;
    ls_net_poll(&g_net, t);
    assert_int_equal(first_frames_to(SUP_A, 0x30), 2);
    /* ...and takes the second transfer whole. */
    uint8_t got[LS_ISOTP_MAX_PAYLOAD];
    size_t n = 0;
    for (int turn = 0; turn < 100 && n == 0; turn++) {
        sup_hear(&a, &g_link[0], &seen, t);
        ls_isotp_poll(&a.tp, t);
        t += 100;
        ls_net_poll(&g_net, t);
        sup_hear(&a, &g_link[0], &seen, t);
        n = ls_isotp_take_rx(&a.tp, got, sizeof got);
    }
    assert_int_equal(n, sizeof msg);
    assert_memory_equal(got, msg, sizeof msg);
    /* Delivered: never sent a third time. */
    for (int k = 0; k < 3; k++) {
        t += PAST_N_BS_US;
        ls_net_poll(&g_net, t);
    }
    assert_int_equal(first_frames_to(SUP_A, 0x30), 2);
    assert_int_equal(describe_value("tx_retried"), 1);
    assert_int_equal(describe_value("tx_given_up"), 0);
}

static void test_an_answer_already_pending_is_not_queued_twice(void **state)
{
    (void)state;
    setup_net(1);
    uint8_t answer[20] = { 0x41 };
    uint8_t other[20] = { 0x42 };
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, answer, sizeof answer), 0);
    ls_net_poll(&g_net, 100); /* in flight, waiting for its flow control */
    /* The cached answer to a retransmission: the same bytes, once more in flight... */
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, answer, sizeof answer), 0);
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, other, sizeof other), 0);
    /* ...and once more waiting in the queue. */
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, other, sizeof other), 0);
    assert_int_equal(describe_value("tx_deduplicated"), 2);
    /* Another supervisor's identical bytes are its own. */
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_B, answer, sizeof answer), 0);
    assert_int_equal(describe_value("tx_deduplicated"), 2);
    /* Every transfer fails: the answer goes out LS_NET_TX_TRIES times, `other` follows once queued. */
    uint64_t t = 100;
    for (int k = 0; k < LS_NET_TX_TRIES; k++) {
        t += PAST_N_BS_US;
        ls_net_poll(&g_net, t);
    }
    assert_int_equal(first_frames_to(SUP_A, 0x41), LS_NET_TX_TRIES);
    assert_int_equal(first_frames_to(SUP_A, 0x42), 1);
}

static void test_lru_eviction_of_idle_links(void **state)
{
    (void)state;
    setup_net(1);
    /* Fill the pool: 0x30..0x35 at t = 1..6 ms. */
    for (uint8_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        ping((uint8_t)(0x30 + i), 1000u * (i + 1u));
    }
    assert_int_equal(describe_value("peers_evicted"), 0);
    /* 0x30 speaks again: now 0x31 is the least recently used. */
    ping(0x30, 10000);
    ping(0x40, 11000);
    assert_int_equal(g_calls[g_ncalls - 1].addr, 0x40);
    assert_true(peer_used(0x40));
    assert_false(peer_used(0x31));
    assert_true(peer_used(0x30));
    assert_int_equal(describe_value("peers_evicted"), 1);
    /* The evicted supervisor comes back: it takes the next LRU (0x32). */
    ping(0x31, 12000);
    assert_true(peer_used(0x31));
    assert_false(peer_used(0x32));
    assert_int_equal(describe_value("peers_evicted"), 2);
    /* The outcome counters of evicted links are kept: one reception per ping. */
    assert_int_equal(describe_value("isotp_ok"), LS_NET_MAX_PEERS + 3);
}

static void test_busy_links_are_not_evicted(void **state)
{
    (void)state;
    setup_net(1);
    for (uint8_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        ping((uint8_t)(0x30 + i), 1000u * (i + 1u));
    }
    /* 0x30 (oldest) is receiving a multi-frame message; 0x31 has a queued answer. */
    const uint8_t ff[8] = { 0x10, 0x40, 1, 2, 3, 4, 5, 6 };
    link_put(&g_link[0], phys(NODE, 0x30), HAL_CAN_F_EXT, ff, 8);
    ls_net_poll(&g_net, 7000);
    g_link[0].refuse_send = 1; /* the bus is full from now on: the answer stays pending */
    uint8_t ans[4] = { 0 };
    assert_int_equal(ls_net_send_downlink(&g_net, 0x31, ans, sizeof ans), 0);
    ls_net_poll(&g_net, 7100);
    /* Refresh the others after them, so that 0x30 and 0x31 are the oldest. */
    size_t before = g_ncalls;
    ping(0x40, 8000);
    assert_int_equal(g_ncalls, before + 1);
    assert_true(peer_used(0x30));
    assert_true(peer_used(0x31));
    assert_false(peer_used(0x32)); /* the oldest idle one */
    /* All busy, none with a session: a new source preempts the one that made
     * progress least recently, answers to session-less sources first (0x31),
     * then receptions (0x30, whose first frame is the oldest). */
    for (uint8_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        ls_net_peer_t *p = &g_net.peers[i];
        if (p->addr != 0x30 && p->addr != 0x31) {
            uint8_t ff2[8] = { 0x10, 0x40, 1, 2, 3, 4, 5, 6 };
            link_put(&g_link[0], phys(NODE, p->addr), HAL_CAN_F_EXT, ff2, 8);
        }
    }
    ls_net_poll(&g_net, 9000);
    const uint8_t ff3[8] = { 0x10, 0x40, 1, 2, 3, 4, 5, 6 };
    link_put(&g_link[0], phys(NODE, 0x41), HAL_CAN_F_EXT, ff3, 8);
    ls_net_poll(&g_net, 9100);
    assert_true(peer_used(0x41));
    assert_false(peer_used(0x31));
    assert_true(peer_used(0x30));
    assert_int_equal(describe_value("peers_preempted"), 1);
    link_put(&g_link[0], phys(NODE, 0x42), HAL_CAN_F_EXT, ff3, 8);
    ls_net_poll(&g_net, 9200);
    assert_true(peer_used(0x42));
    assert_false(peer_used(0x30));
    assert_int_equal(describe_value("peers_preempted"), 2);
    /* Every link belongs to a session: a new source finds none, its frame is dropped. */
    for (uint8_t i = 0; i < LS_NET_MAX_PEERS; i++) {
        g_session[g_net.peers[i].addr] = true;
    }
    before = g_ncalls;
    ping(0x43, 9300);
    assert_int_equal(g_ncalls, before);
    assert_false(peer_used(0x43));
    assert_int_equal(ls_net_send_downlink(&g_net, 0x43, ans, sizeof ans), LS_ENOSPC);
}

/* ---------------------------------------------------------------- budgets under floods (docs/protocol.md "Budgets under floods") */

/* The floods of docs/reliability.md section 8: first frames announcing 4095 B from changing sources
 * every few ms, and single frames from changing sources each answered. A
 * session's link is never taken, it is answered all along, and a new
 * supervisor's multi-frame connect arrives whole. */
static void test_floods_neither_evict_a_session_nor_keep_a_new_supervisor_out(void **state)
{
    (void)state;
    setup_net(1);
    static sup_t owner, newcomer;
    sup_init(&owner, SUP_A, &g_link[0]);
    sup_init(&newcomer, SUP_B, &g_link[0]);
    g_echo_len = 20; /* every uplink is answered, as the core does (NOT_CONNECTED to the flood) */
    uint64_t t = 1000;
    const uint8_t hello[] = { 0x01 };
    assert_int_equal(ls_isotp_send(&owner.tp, hello, sizeof hello, t), LS_OK);
    ls_net_poll(&g_net, t);
    g_session[SUP_A] = true; /* its connect made a session */
    size_t seen_owner = 0, seen_new = 0;
    static uint8_t connect_req[60];
    memset(connect_req, 0x5A, sizeof connect_req);
    bool sent_connect = false;
    size_t owner_answers = 0, uplinks_new = 0, uplinks_owner = 0;
    uint8_t got[LS_ISOTP_MAX_PAYLOAD];
    for (int turn = 0; turn < 2000; turn++) {
        t += 1000; /* 1 ms turns, 2 s in all */
        /* flood: a first frame from one of 12 changing sources every 2 ms, a
         * single frame from another changing source every 5 ms */
        if (turn % 2 == 0) {
            const uint8_t ff[8] = { 0x1F, 0xFF, 1, 2, 3, 4, 5, 6 };
            link_put(&g_link[0], phys(NODE, (uint8_t)(0x60 + (turn / 2) % 12)), HAL_CAN_F_EXT, ff, 8);
        }
        if (turn % 5 == 0) {
            const uint8_t req[] = { 0x77 };
            put_sf(&g_link[0], phys(NODE, (uint8_t)(0x80 + (turn / 5) % 64)), req, 1);
        }
        /* the owner asks every 50 ms; the newcomer connects after 0.5 s */
        if (turn % 50 == 0 && !ls_isotp_tx_busy(&owner.tp)) {
            assert_int_equal(ls_isotp_send(&owner.tp, hello, sizeof hello, t), LS_OK);
        }
        if (turn == 500) {
            assert_int_equal(ls_isotp_send(&newcomer.tp, connect_req, sizeof connect_req, t), LS_OK);
            sent_connect = true;
        }
        size_t before = g_ncalls;
        ls_net_poll(&g_net, t);
        for (size_t i = before; i < g_ncalls; i++) {
            uplinks_owner += g_calls[i].addr == SUP_A ? 1u : 0u;
            uplinks_new += g_calls[i].addr == SUP_B && g_calls[i].len == sizeof connect_req ? 1u : 0u;
        }
        g_ncalls = 0; /* the record is bounded; what matters is counted above */
        sup_hear(&owner, &g_link[0], &seen_owner, t);
        sup_hear(&newcomer, &g_link[0], &seen_new, t);
        ls_isotp_poll(&owner.tp, t);
        ls_isotp_poll(&newcomer.tp, t);
        owner_answers += ls_isotp_take_rx(&owner.tp, got, sizeof got) > 0 ? 1u : 0u;
        if (g_link[0].n_tx > LINK_Q - 64) { /* keep the fake link's record from filling */
            g_link[0].n_tx = 0;
            seen_owner = seen_new = 0;
        }
    }
    assert_true(sent_connect);
    assert_int_equal(uplinks_new, 1);    /* the newcomer's connect arrived whole */
    assert_int_equal(uplinks_owner, 40); /* every owner request of the loop reached the core */
    assert_true(owner_answers >= 40);    /* and was answered */
    assert_true(peer_used(SUP_A));
    assert_int_equal(describe_value("peers_preempted") > 0, 1);
}

/* A token bucket: full at first, refills at its rate, never above the burst,
 * and polled every microsecond still refills (no rounding away). */
static void test_token_bucket(void **state)
{
    (void)state;
    ls_net_bucket_t b = { 0 };
    assert_true(ls_net_bucket_take(&b, 10, 2, 0));
    assert_true(ls_net_bucket_take(&b, 10, 2, 0));
    assert_false(ls_net_bucket_take(&b, 10, 2, 0));
    assert_false(ls_net_bucket_take(&b, 10, 2, 50000)); /* half a token */
    assert_true(ls_net_bucket_take(&b, 10, 2, 100000));
    int taken = 0;
    for (uint64_t t = 100001; t <= 200000; t++) {
        taken += ls_net_bucket_take(&b, 10, 2, t) ? 1 : 0;
    }
    assert_int_equal(taken, 1);
    /* a long pause fills it to the burst, no more */
    taken = 0;
    for (int i = 0; i < 5; i++) {
        taken += ls_net_bucket_take(&b, 10, 2, 100000000) ? 1 : 0;
    }
    assert_int_equal(taken, 2);
}

/* A flood on one link reaches the others at most at the forward budget;
 * EMERGENCY frames have their own budget, so the flood cannot hold one back. */
static void test_bridged_frames_are_capped_per_output_link(void **state)
{
    (void)state;
    setup_net(2);
    const uint8_t d[8] = { 0 };
    for (int i = 0; i < 500; i++) {
        link_put(&g_link[0], STATUS_OF_42, HAL_CAN_F_EXT, d, 8);
    }
    ls_net_poll(&g_net, 1000);
    ls_net_poll(&g_net, 1000); /* 256 frames a turn: all 500 read at one instant */
    assert_int_equal(g_link[1].n_tx, LS_NET_FWD_BURST);
    assert_int_equal(describe_value("fwd_dropped"), 500 - LS_NET_FWD_BURST);
    /* the other link's own traffic is not touched: nothing goes back to link 0 */
    assert_int_equal(g_link[0].n_tx, 0);
    /* an EMERGENCY frame behind the flood still crosses, up to its own burst */
    for (unsigned i = 0; i < LS_NET_FWD_EMERGENCY_BURST + 1u; i++) {
        link_put(&g_link[0], LS_ID_EMERGENCY | 0x33u, HAL_CAN_F_EXT, d, 8);
    }
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_link[1].n_tx, LS_NET_FWD_BURST + LS_NET_FWD_EMERGENCY_BURST);
    assert_int_equal(g_link[1].tx[LS_NET_FWD_BURST].id, LS_ID_EMERGENCY | 0x33u);
    assert_int_equal(describe_value("fwd_emergency_dropped"), 1);
    /* the budget refills at its rate: 100 ms later, 200 frames */
    for (int i = 0; i < 300; i++) {
        link_put(&g_link[0], STATUS_OF_42, HAL_CAN_F_EXT, d, 8);
    }
    ls_net_poll(&g_net, 1000 + 100000);
    ls_net_poll(&g_net, 1000 + 100000);
    assert_int_equal(g_link[1].n_tx, LS_NET_FWD_BURST + LS_NET_FWD_EMERGENCY_BURST + LS_NET_FWD_RATE_FPS / 10u);
    assert_int_equal(describe_value("frames_bridged"),
                     LS_NET_FWD_BURST + LS_NET_FWD_EMERGENCY_BURST + LS_NET_FWD_RATE_FPS / 10u);
}

/* A link is held open while a session lives on it (its peer's frames came on
 * it) or its downlinks are still under way; released after. */
static void test_links_with_sessions_are_held_open(void **state)
{
    (void)state;
    setup_net(2);
    const uint8_t req[] = { 0x01 };
    put_sf(&g_link[1], phys(NODE, SUP_A), req, 1);
    g_session[SUP_A] = true;
    g_session_link[SUP_A] = 1;
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_link[1].held, 1);
    assert_int_equal(g_link[0].held, 0);
    assert_int_equal(g_link[0].hold_calls, 0); /* told only on a change */
    ls_net_poll(&g_net, 2000);
    assert_int_equal(g_link[1].hold_calls, 1);
    /* the session ends with its answer still to send: held until it is out */
    g_session[SUP_A] = false;
    uint8_t ans[20] = { 9 };
    assert_int_equal(ls_net_send_downlink(&g_net, SUP_A, ans, sizeof ans), 0);
    ls_net_poll(&g_net, 3000);
    assert_int_equal(g_link[1].held, 1);
    for (int k = 0; k <= LS_NET_TX_TRIES; k++) { /* nobody takes it: given up */
        ls_net_poll(&g_net, 3000 + (uint64_t)(k + 1) * PAST_N_BS_US);
    }
    assert_int_equal(describe_value("tx_given_up"), 1);
    assert_int_equal(g_link[1].held, 0);
    assert_int_equal(g_link[1].hold_calls, 2);
}

/* ---------------------------------------------------------------- bridging */

/* Three links where the profile has them (LS_NET_MAX_LINKS is 2 on mcu). */
#define BRIDGE_LINKS (LS_NET_MAX_LINKS < 3 ? LS_NET_MAX_LINKS : 3)
_Static_assert(BRIDGE_LINKS >= 2, "bridging needs two links");

static void test_bridging_between_links(void **state)
{
    (void)state;
    setup_net(BRIDGE_LINKS);
    const uint8_t d[8] = { 1, 2, 3, 4, 5, 6, 7, 8 };
    /* Someone else's traffic on link 1: copied to every other link, not back to 1. */
    link_put(&g_link[1], STATUS_OF_42, HAL_CAN_F_EXT, d, 8);
    link_put(&g_link[1], 0x123u, 0, d, 3); /* 11-bit frames too */
    ls_net_poll(&g_net, 1000);
    for (size_t i = 0; i < BRIDGE_LINKS; i++) {
        if (i == 1) {
            assert_int_equal(g_link[i].n_tx, 0);
            continue;
        }
        assert_int_equal(g_link[i].n_tx, 2);
        assert_int_equal(g_link[i].tx[0].id, STATUS_OF_42);
        assert_memory_equal(g_link[i].tx[0].data, d, 8);
        assert_int_equal(g_link[i].tx[1].id, 0x123u);
        assert_int_equal(g_link[i].tx[1].flags, 0);
        assert_int_equal(g_link[i].tx[1].len, 3);
    }
    assert_int_equal(g_ncalls, 0);
    /* A request for us on the last link is bridged and also served; the
     * answer goes on every link (one bus). */
    const size_t from = BRIDGE_LINKS - 1;
    size_t before[BRIDGE_LINKS];
    for (size_t i = 0; i < BRIDGE_LINKS; i++) {
        before[i] = g_link[i].n_tx;
    }
    g_echo_len = 3;
    const uint8_t req[] = { 0x50 };
    put_sf(&g_link[from], phys(NODE, SUP_A), req, 1);
    ls_net_poll(&g_net, 2000);
    assert_int_equal(g_ncalls, 1);
    for (size_t i = 0; i < BRIDGE_LINKS; i++) {
        if (i == from) {
            assert_int_equal(g_link[i].n_tx, before[i] + 1); /* the answer only */
        } else {
            assert_int_equal(g_link[i].n_tx, before[i] + 2); /* the bridged request, then the answer */
            assert_int_equal(g_link[i].tx[before[i]].id, phys(NODE, SUP_A));
        }
        assert_int_equal(g_link[i].tx[g_link[i].n_tx - 1].id, phys(SUP_A, NODE));
    }
}

/* docs/protocol.md "Security": "Sessions bound to their link". A session
 * connected on link 0: frames from its address on link 1 are dropped before
 * they reach the core or its ISO-TP link, and are not bridged; on link 0
 * they go on. Frames from the device's own address are dropped everywhere. */
static void test_frames_of_a_session_from_another_link_are_dropped(void **state)
{
    (void)state;
    setup_net(2);
    g_session[SUP_A] = true;
    g_session_link[SUP_A] = 0;
    const uint8_t req[] = { 0x0A, 0x03, 0x08, 0x01 };
    uint8_t hb[8] = { 1, 0, 1, 200, 0, 0x56, 0x34, 0x12 };
    const uint8_t ff[8] = { 0x10, 0x20, 1, 2, 3, 4, 5, 6 };
    const uint8_t fc_wait[8] = { 0x31, 0, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC };
    put_sf(&g_link[1], phys(NODE, SUP_A), req, sizeof req);
    put_sf(&g_link[1], func(LS_ADDR_ALL, SUP_A), req, sizeof req);
    link_put(&g_link[1], LS_ID_HEARTBEAT | SUP_A, HAL_CAN_F_EXT, hb, 8);
    link_put(&g_link[1], phys(NODE, SUP_A), HAL_CAN_F_EXT, ff, 8);
    link_put(&g_link[1], phys(NODE, SUP_A), HAL_CAN_F_EXT, fc_wait, 8);
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_ncalls, 0);
    assert_false(peer_used(SUP_A));      /* not even its ISO-TP link saw them */
    assert_int_equal(g_link[0].n_tx, 0); /* nor were they bridged to the session's link */
    assert_int_equal(describe_value("frames_foreign"), 5);
    /* the same frames on the session's own link go on */
    put_sf(&g_link[0], phys(NODE, SUP_A), req, sizeof req);
    put_sf(&g_link[0], func(LS_ADDR_ALL, SUP_A), req, sizeof req);
    link_put(&g_link[0], LS_ID_HEARTBEAT | SUP_A, HAL_CAN_F_EXT, hb, 8);
    ls_net_poll(&g_net, 2000);
    assert_int_equal(g_ncalls, 3);
    assert_int_equal(g_calls[0].kind, CALL_UPLINK);
    assert_int_equal(g_calls[0].link, 0);
    assert_int_equal(g_calls[1].kind, CALL_FUNCTIONAL);
    assert_int_equal(g_calls[2].kind, CALL_HEARTBEAT);
    /* a source without a session may speak on any link; the link is passed on */
    put_sf(&g_link[1], phys(NODE, SUP_B), req, sizeof req);
    ls_net_poll(&g_net, 3000);
    assert_int_equal(g_ncalls, 4);
    assert_int_equal(g_calls[3].addr, SUP_B);
    assert_int_equal(g_calls[3].link, 1);
    /* a frame that claims to come from this device is forged, whatever the link */
    put_sf(&g_link[0], phys(SUP_A, NODE), req, sizeof req);
    link_put(&g_link[1], LS_ID_HEARTBEAT | NODE, HAL_CAN_F_EXT, hb, 8);
    const size_t sent1 = g_link[1].n_tx;
    ls_net_poll(&g_net, 4000);
    assert_int_equal(g_ncalls, 4);
    assert_int_equal(g_link[1].n_tx, sent1);
    assert_int_equal(describe_value("frames_foreign"), 7);
}

static void test_single_link_does_not_echo(void **state)
{
    (void)state;
    setup_net(1);
    const uint8_t d[8] = { 0 };
    link_put(&g_link[0], STATUS_OF_42, HAL_CAN_F_EXT, d, 8);
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_link[0].n_tx, 0);
}

static void test_send_frame_on_every_link_and_full_queues(void **state)
{
    (void)state;
    setup_net(2);
    hal_can_frame_t f = { .id = LS_ID_HEARTBEAT | NODE, .flags = HAL_CAN_F_EXT, .len = 8 };
    assert_int_equal(ls_net_send_frame(&g_net, &f), 0);
    assert_int_equal(g_link[0].n_tx, 1);
    assert_int_equal(g_link[1].n_tx, 1);
    /* One link full: still sent (on the other), counted. */
    g_link[0].refuse_send = 1;
    assert_int_equal(ls_net_send_frame(&g_net, &f), 0);
    assert_int_equal(describe_value("tx_full"), 1);
    /* Both full: refused. */
    g_link[1].refuse_send = 1;
    assert_int_equal(ls_net_send_frame(&g_net, &f), LS_EAGAIN);
    assert_int_equal(describe_value("tx_full"), 3);
    assert_int_equal(describe_value("frames_out"), 2);
    /* The links' own counters are summed. */
    assert_int_equal(describe_value("link_rx_dropped"), 4);
    ls_net_close(&g_net);
    assert_int_equal(g_link[0].closed, 1);
    assert_int_equal(g_link[1].closed, 1);
}

static void test_a_busy_link_does_not_starve_the_others(void **state)
{
    (void)state;
    setup_net(2);
    const uint8_t d[8] = { 0 };
    for (int i = 0; i < 300; i++) {
        link_put(&g_link[0], STATUS_OF_42, HAL_CAN_F_EXT, d, 8);
    }
    const uint8_t req[] = { 0x60 };
    put_sf(&g_link[1], phys(NODE, SUP_B), req, 1);
    ls_net_poll(&g_net, 1000);
    assert_int_equal(g_ncalls, 1);            /* link 1's request was served this turn */
    assert_int_equal(g_link[0].rx_count, 44); /* 256 frames per link and turn */
    ls_net_poll(&g_net, 2000);
    assert_int_equal(g_link[0].rx_count, 0);
    assert_int_equal(describe_value("frames_in"), 301);
}

/* sendCommand status holds the transport's counters whole when they take
 * at most LS_TRANSPORT_DESCRIBE_MAX: they do with every counter at its
 * longest (ten digits) and every link in use. */
static void test_the_counters_at_their_longest_fit_their_budget(void **state)
{
    (void)state;
    setup_net(LS_NET_MAX_LINKS);
    g_status_count = UINT32_MAX / LS_NET_MAX_LINKS; /* the links' sums: ten digits */
    uint32_t *counters[] = { &g_net.frames_in,    &g_net.frames_out,    &g_net.frames_bridged,
                             &g_net.tx_full,      &g_net.peers_evicted, &g_net.peers_preempted,
                             &g_net.tx_retried,   &g_net.tx_given_up,   &g_net.tx_deduplicated,
                             &g_net.tx_restarted, &g_net.fwd_dropped,   &g_net.fwd_emergency_dropped };
    for (size_t i = 0; i < sizeof counters / sizeof counters[0]; i++) {
        *counters[i] = UINT32_MAX;
    }
    for (int r = 0; r < LS_ISOTP_N_RESULT_COUNT; r++) {
        g_net.rx_results_gone[r] = UINT32_MAX;
    }
    char buf[LS_TRANSPORT_DESCRIBE_MAX * 2];
    ls_net_describe(&g_net, buf, sizeof buf);
    g_status_count = 2;
    assert_true(strlen(buf) + 1u <= LS_TRANSPORT_DESCRIBE_MAX);
    assert_non_null(strstr(buf, "frames_in=4294967295\n"));
    assert_non_null(strstr(buf, "isotp_malformed=4294967295\n")); /* the last line, whole */
}

static void test_link_table_is_bounded(void **state)
{
    (void)state;
    setup_net(0);
    hal_can_link_t l = { .ops = &LINK_OPS, .self = &g_link[0] };
    for (int i = 0; i < LS_NET_MAX_LINKS; i++) {
        assert_int_equal(ls_net_add_link(&g_net, &l), 0);
    }
    assert_int_equal(ls_net_add_link(&g_net, &l), LS_ENOSPC);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_physical_single_frame_reaches_the_core),
        cmocka_unit_test(test_frames_that_are_not_ours_are_ignored),
        cmocka_unit_test(test_functional_single_frames),
        cmocka_unit_test(test_frames_of_a_session_from_another_link_are_dropped),
        cmocka_unit_test(test_heartbeats),
        cmocka_unit_test(test_emergency_frames),
        cmocka_unit_test(test_interleaved_multi_frame_requests_stay_apart),
        cmocka_unit_test(test_answer_is_sent_to_the_sender),
        cmocka_unit_test(test_downlink_queue_is_bounded),
        cmocka_unit_test(test_next_deadline_says_when_the_poll_has_work),
        cmocka_unit_test(test_an_event_driven_loop_completes_an_exchange),
        cmocka_unit_test(test_a_downlink_without_flow_control_is_sent_again_then_given_up),
        cmocka_unit_test(test_a_downlink_sent_again_arrives_once),
        cmocka_unit_test(test_an_answer_already_pending_is_not_queued_twice),
        cmocka_unit_test(test_lru_eviction_of_idle_links),
        cmocka_unit_test(test_busy_links_are_not_evicted),
        cmocka_unit_test(test_floods_neither_evict_a_session_nor_keep_a_new_supervisor_out),
        cmocka_unit_test(test_token_bucket),
        cmocka_unit_test(test_bridged_frames_are_capped_per_output_link),
        cmocka_unit_test(test_links_with_sessions_are_held_open),
        cmocka_unit_test(test_bridging_between_links),
        cmocka_unit_test(test_single_link_does_not_echo),
        cmocka_unit_test(test_send_frame_on_every_link_and_full_queues),
        cmocka_unit_test(test_a_busy_link_does_not_starve_the_others),
        cmocka_unit_test(test_the_counters_at_their_longest_fit_their_budget),
        cmocka_unit_test(test_link_table_is_bounded),
    };
    return cmocka_run_group_tests_name("ls_net", tests, NULL, NULL);
}
