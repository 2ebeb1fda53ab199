/* Black-box tests of the ISO-TP transport: every expected frame is built here
 * from the protocol bytes of ISO 15765-2, never taken from the code under test. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "ls_isotp.h"

#define ID_A 0x7E0u /* link A transmits on this id */
#define ID_B 0x7E8u
#define PAD 0xCCu
#define MAX_FRAMES 1200u

typedef struct {
    uint32_t id;
    uint8_t len;
    uint8_t d[8];
    uint64_t t_us;
} frame_t;

/* Captures every frame a link queues, stamped with the test's clock. */
typedef struct {
    frame_t f[MAX_FRAMES];
    size_t n;
    int refuse;     /* refuse this many next sends (CAN queue full) */
    size_t refused; /* sends refused so far */
    uint64_t now_us;
} cap_t;

static int cap_send(void *ctx, uint32_t id, const uint8_t *data, uint8_t len)
{
    cap_t *c = ctx;
    assert_true(len >= 1 && len <= 8);
    if (c->refuse > 0) {
        c->refuse--;
        c->refused++;
        return -1;
    }
    assert_true(c->n < MAX_FRAMES);
    frame_t *f = &c->f[c->n++];
    f->id = id;
    f->len = len;
    memset(f->d, 0, sizeof(f->d));
    memcpy(f->d, data, len);
    f->t_us = c->now_us;
    return 0;
}

/* ---- expected frames, from the standard's PCI bytes --------------------- */

static frame_t mk(uint32_t id, const uint8_t *bytes, uint8_t used, bool pad)
{
    frame_t f;
    memset(&f, 0, sizeof(f));
    f.id = id;
    memcpy(f.d, bytes, used);
    f.len = used;
    if (pad) {
        for (uint8_t i = used; i < 8; i++) {
            f.d[i] = PAD;
        }
        f.len = 8;
    }
    return f;
}

static frame_t fc_frame(uint32_t id, uint8_t fs, uint8_t bs, uint8_t stmin, bool pad)
{
    uint8_t b[3] = { (uint8_t)(0x30u | fs), bs, stmin };
    return mk(id, b, 3, pad);
}

static size_t iso_data_frames(size_t len)
{
    return len <= 7 ? 1u : 1u + (len - 6u + 6u) / 7u;
}

/* SF, or FF + CFs, for `p`. Returns the number of frames written. */
static size_t expected_data_frames(uint32_t id, const uint8_t *p, size_t len, bool pad, frame_t *out)
{
    uint8_t b[8];
    if (len <= 7) {
        b[0] = (uint8_t)len;
        memcpy(b + 1, p, len);
        out[0] = mk(id, b, (uint8_t)(1u + len), pad);
        return 1;
    }
    size_t n = 0;
    b[0] = (uint8_t)(0x10u | (len >> 8));
    b[1] = (uint8_t)(len & 0xFFu);
    memcpy(b + 2, p, 6);
    out[n++] = mk(id, b, 8, pad);
    size_t off = 6;
    uint8_t sn = 1;
    while (off < len) {
        size_t k = len - off < 7 ? len - off : 7;
        b[0] = (uint8_t)(0x20u | sn);
        memcpy(b + 1, p + off, k);
        out[n++] = mk(id, b, (uint8_t)(1u + k), pad);
        off += k;
        sn = (uint8_t)((sn + 1u) & 0xFu);
    }
    return n;
}

static void assert_frame_eq(const frame_t *got, const frame_t *want)
{
    assert_int_equal(got->id, want->id);
    assert_int_equal(got->len, want->len);
    assert_memory_equal(got->d, want->d, want->len);
}

static void fill_pattern(uint8_t *p, size_t len, uint32_t seed)
{
    uint32_t x = seed * 2654435761u + 1u;
    for (size_t i = 0; i < len; i++) {
        x = x * 1103515245u + 12345u;
        p[i] = (uint8_t)(x >> 16);
    }
}

/* ---- fixtures ------------------------------------------------------------ */

typedef struct {
    ls_isotp_link_t a, b; /* a sends on ID_A and receives ID_B; b the reverse */
    cap_t ca, cb;
    frame_t exp[MAX_FRAMES];
    uint8_t payload[LS_ISOTP_MAX_PAYLOAD];
    uint8_t out[LS_ISOTP_MAX_PAYLOAD];
} fx_t;

static fx_t fx; /* too large for the stack */

static ls_isotp_config_t cfg_of(uint8_t bs, uint8_t stmin, bool pad)
{
    ls_isotp_config_t c;
    ls_isotp_default_config(&c);
    c.block_size = bs;
    c.st_min = stmin;
    c.tx_padding = pad;
    return c;
}

static void setup_links(const ls_isotp_config_t *ca, const ls_isotp_config_t *cb)
{
    memset(&fx, 0, sizeof(fx));
    assert_int_equal(ls_isotp_init(&fx.a, ca, ID_A, ID_B, cap_send, &fx.ca), LS_OK);
    assert_int_equal(ls_isotp_init(&fx.b, cb, ID_B, ID_A, cap_send, &fx.cb), LS_OK);
}

static void feed(ls_isotp_link_t *l, cap_t *own, const uint8_t *bytes, uint8_t len, uint64_t t)
{
    own->now_us = t;
    ls_isotp_on_frame(l, bytes, len, t);
}

static void poll_at(ls_isotp_link_t *l, cap_t *own, uint64_t t)
{
    own->now_us = t;
    ls_isotp_poll(l, t);
}

/* Both links back to back: deliver frames in order, poll each step. Returns
 * the time at which the receiver completed. */
static uint64_t run_wire(uint64_t step_us, uint64_t limit_us)
{
    size_t da = 0, db = 0;
    for (uint64_t t = 0; t <= limit_us; t += step_us) {
        fx.ca.now_us = t;
        fx.cb.now_us = t;
        bool moved = true;
        while (moved) {
            moved = false;
            while (da < fx.ca.n) {
                const frame_t *f = &fx.ca.f[da++];
                ls_isotp_on_frame(&fx.b, f->d, f->len, t);
                moved = true;
            }
            while (db < fx.cb.n) {
                const frame_t *f = &fx.cb.f[db++];
                ls_isotp_on_frame(&fx.a, f->d, f->len, t);
                moved = true;
            }
            ls_isotp_poll(&fx.a, t);
            ls_isotp_poll(&fx.b, t);
            moved = moved || da < fx.ca.n || db < fx.cb.n;
        }
        if (!ls_isotp_tx_busy(&fx.a) && fx.b.rx_state == LS_ISOTP_RX_DONE) {
            return t;
        }
    }
    fail_msg("transfer did not complete within %llu us", (unsigned long long)limit_us);
    return 0;
}

/* ---- single frames --------------------------------------------------------- */

static void test_sf_tx_padded_and_unpadded(void **state)
{
    (void)state;
    for (int pad = 0; pad <= 1; pad++) {
        for (size_t len = 1; len <= 7; len += 6) {
            ls_isotp_config_t c = cfg_of(8, 0, pad != 0);
            setup_links(&c, &c);
            fill_pattern(fx.payload, len, (uint32_t)len);
            assert_int_equal(ls_isotp_send(&fx.a, fx.payload, len, 0), LS_OK);
            assert_int_equal(fx.ca.n, 1);
            uint8_t b[8] = { (uint8_t)len };
            memcpy(b + 1, fx.payload, len);
            frame_t want = mk(ID_A, b, (uint8_t)(1 + len), pad != 0);
            assert_frame_eq(&fx.ca.f[0], &want);
            assert_int_equal(fx.ca.f[0].len, pad ? 8 : 1 + len);
            assert_false(ls_isotp_tx_busy(&fx.a));
            assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
        }
    }
}

static void test_sf_rx_padded_and_unpadded(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t unpadded[2] = { 0x01, 0x5A };
    feed(&fx.b, &fx.cb, unpadded, 2, 0);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_DONE);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 1);
    assert_int_equal(fx.out[0], 0x5A);
    const uint8_t padded[8] = { 0x07, 1, 2, 3, 4, 5, 6, 7 };
    feed(&fx.b, &fx.cb, padded, 8, 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 7);
    const uint8_t want[7] = { 1, 2, 3, 4, 5, 6, 7 };
    assert_memory_equal(fx.out, want, 7);
    const uint8_t padded1[8] = { 0x01, 0x42, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA };
    feed(&fx.b, &fx.cb, padded1, 8, 2);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 1);
    assert_int_equal(fx.out[0], 0x42);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_OK], 3);
    assert_int_equal(fx.cb.n, 0); /* a SF needs no flow control */
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 0);
}

/* ---- multi-frame transfers: exact frames, counts and STmin timing ---------- */

static void check_transfer(size_t len, uint8_t bs, uint8_t stmin, bool pad_a, bool pad_b)
{
    ls_isotp_config_t ca = cfg_of(8, 0, pad_a);
    ls_isotp_config_t cb = cfg_of(bs, stmin, pad_b);
    setup_links(&ca, &cb);
    fill_pattern(fx.payload, len, (uint32_t)(len * 31u + bs + stmin));
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, len, 0), LS_OK);
    (void)run_wire(100, 60000000);

    /* Sender: exactly the ISO minimum of data frames, byte for byte. */
    size_t n_exp = expected_data_frames(ID_A, fx.payload, len, pad_a, fx.exp);
    assert_int_equal(n_exp, iso_data_frames(len));
    assert_int_equal(fx.ca.n, n_exp);
    for (size_t i = 0; i < n_exp; i++) {
        assert_frame_eq(&fx.ca.f[i], &fx.exp[i]);
    }

    /* Receiver: one FC.CTS after the FF and one after every full block. */
    size_t n_cf = n_exp - 1;
    size_t n_fc = 0;
    if (len > 7) {
        n_fc = (bs == 0) ? 1 : 1 + (n_cf - 1) / bs;
    }
    assert_int_equal(fx.cb.n, n_fc);
    frame_t want_fc = fc_frame(ID_B, 0, bs, stmin, pad_b);
    for (size_t i = 0; i < n_fc; i++) {
        assert_frame_eq(&fx.cb.f[i], &want_fc);
    }

    /* STmin between CFs of a block; each block starts when its FC arrives. */
    uint32_t st_us = ls_isotp_stmin_to_us(stmin);
    for (size_t i = 1; i < n_exp; i++) {
        size_t cf_idx = i - 1; /* 0-based CF number */
        bool block_start = (cf_idx == 0) || (bs != 0 && cf_idx % bs == 0);
        if (block_start) {
            size_t fc_idx = (bs == 0) ? 0 : cf_idx / bs;
            assert_int_equal(fx.ca.f[i].t_us, fx.cb.f[fc_idx].t_us);
        } else {
            assert_int_equal(fx.ca.f[i].t_us - fx.ca.f[i - 1].t_us, st_us);
        }
    }

    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), len);
    assert_memory_equal(fx.out, fx.payload, len);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_OK], 1);
    for (int r = 1; r < LS_ISOTP_N_RESULT_COUNT; r++) {
        assert_int_equal(fx.a.tx_results[r], 0);
        assert_int_equal(fx.b.rx_results[r], 0);
    }
}

static void test_transfer_matrix(void **state)
{
    (void)state;
    static const size_t lens[] = { 1, 7, 8, 62, 63, 100, 1000, 4095 };
    static const uint8_t bss[] = { 0, 8 };
    static const uint8_t stmins[] = { 0, 1 };
    for (size_t i = 0; i < sizeof(lens) / sizeof(lens[0]); i++) {
        for (size_t j = 0; j < 2; j++) {
            for (size_t k = 0; k < 2; k++) {
                check_transfer(lens[i], bss[j], stmins[k], true, true);
                check_transfer(lens[i], bss[j], stmins[k], false, false);
                check_transfer(lens[i], bss[j], stmins[k], true, false);
            }
        }
    }
}

/* With STmin 0 and BS 0 every CF goes out in the same call that took the FC. */
static void test_stmin0_bs0_burst(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    fill_pattern(fx.payload, 100, 7);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 100, 0), LS_OK);
    assert_int_equal(fx.ca.n, 1);
    const uint8_t cts[3] = { 0x30, 0x00, 0x00 };
    feed(&fx.a, &fx.ca, cts, 3, 50);
    assert_int_equal(fx.ca.n, iso_data_frames(100));
    assert_false(ls_isotp_tx_busy(&fx.a));
}

/* ---- STmin encoding -------------------------------------------------------- */

static void test_stmin_to_us(void **state)
{
    (void)state;
    assert_int_equal(ls_isotp_stmin_to_us(0x00), 0);
    assert_int_equal(ls_isotp_stmin_to_us(0x01), 1000);
    assert_int_equal(ls_isotp_stmin_to_us(0x7F), 127000);
    assert_int_equal(ls_isotp_stmin_to_us(0xF1), 100);
    assert_int_equal(ls_isotp_stmin_to_us(0xF3), 300);
    assert_int_equal(ls_isotp_stmin_to_us(0xF9), 900);
    /* reserved: 0x80-0xF0 and 0xFA-0xFF mean 127 ms */
    assert_int_equal(ls_isotp_stmin_to_us(0x80), 127000);
    assert_int_equal(ls_isotp_stmin_to_us(0xF0), 127000);
    assert_int_equal(ls_isotp_stmin_to_us(0xFA), 127000);
    assert_int_equal(ls_isotp_stmin_to_us(0xFF), 127000);
}

/* Start a 20-byte send (FF + 2 CFs), answer CTS with BS 0 and `stmin` at t0,
 * then check that the 2nd CF waits exactly `gap_us`. */
static void check_sender_gap(uint8_t stmin, uint64_t gap_us)
{
    setup_links(NULL, NULL);
    fill_pattern(fx.payload, 20, stmin);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 20, 0), LS_OK);
    const uint8_t cts[3] = { 0x30, 0x00, stmin };
    feed(&fx.a, &fx.ca, cts, 3, 1000);
    assert_int_equal(fx.ca.n, 2); /* FF + first CF at once */
    assert_int_equal(fx.ca.f[1].t_us, 1000);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 1000 + gap_us);
    poll_at(&fx.a, &fx.ca, 1000 + gap_us - 1);
    assert_int_equal(fx.ca.n, 2);
    poll_at(&fx.a, &fx.ca, 1000 + gap_us);
    assert_int_equal(fx.ca.n, 3);
    assert_int_equal(fx.ca.f[2].d[0], 0x22);
    assert_false(ls_isotp_tx_busy(&fx.a));
}

static void test_sender_stmin_f3_is_300us(void **state)
{
    (void)state;
    check_sender_gap(0xF3, 300);
}

static void test_sender_stmin_reserved_is_127ms(void **state)
{
    (void)state;
    check_sender_gap(0x80, 127000);
    check_sender_gap(0xF0, 127000);
    check_sender_gap(0xFA, 127000);
    check_sender_gap(0x7F, 127000);
    check_sender_gap(0x05, 5000);
}

/* ---- sender: flow control handling ---------------------------------------- */

static void start_ff(size_t len)
{
    setup_links(NULL, NULL);
    fill_pattern(fx.payload, len, 99);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, len, 0), LS_OK);
    assert_int_equal(fx.ca.n, 1);
    assert_int_equal(fx.ca.f[0].d[0], 0x10 | (len >> 8));
    assert_int_equal(fx.a.tx_state, LS_ISOTP_TX_WAIT_FC);
}

static void test_n_bs_timeout(void **state)
{
    (void)state;
    start_ff(20);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 1000000);
    poll_at(&fx.a, &fx.ca, 999999);
    assert_true(ls_isotp_tx_busy(&fx.a));
    poll_at(&fx.a, &fx.ca, 1000000);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_TIMEOUT_BS], 1);
    assert_int_equal(fx.a.last_error, LS_ISOTP_N_TIMEOUT_BS);
    assert_int_equal(fx.ca.n, 1);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), UINT64_MAX);
    /* a late CTS now is unexpected and sends nothing */
    const uint8_t cts[3] = { 0x30, 0, 0 };
    feed(&fx.a, &fx.ca, cts, 3, 1000001);
    assert_int_equal(fx.ca.n, 1);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_UNEXP_PDU], 1);
}

/* N_Bs also guards the FC after each block. */
static void test_resend_after_a_failed_transfer(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    /* nothing sent yet: nothing to send again */
    assert_int_equal(ls_isotp_resend(&fx.a, 0), LS_EINVAL);
    assert_int_equal(ls_isotp_resend(NULL, 0), LS_EINVAL);
    start_ff(20);
    assert_int_equal(ls_isotp_resend(&fx.a, 10), LS_EBUSY); /* under way */
    poll_at(&fx.a, &fx.ca, 1000000);                        /* N_Bs: failed */
    assert_false(ls_isotp_tx_busy(&fx.a));
    /* the same bytes from the first frame again, with a fresh N_Bs */
    assert_int_equal(ls_isotp_resend(&fx.a, 1000000), LS_OK);
    assert_int_equal(fx.ca.n, 2);
    assert_memory_equal(fx.ca.f[1].d, fx.ca.f[0].d, 8);
    assert_int_equal(fx.a.tx_state, LS_ISOTP_TX_WAIT_FC);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 2000000);
    /* this time the receiver answers: the whole message arrives once */
    const uint8_t cts[3] = { 0x30, 0, 0 };
    feed(&fx.a, &fx.ca, cts, 3, 1000100);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_TIMEOUT_BS], 1);
    assert_int_equal(fx.ca.n, 4); /* FF, FF again, two CFs (20 = 6 + 7 + 7) */
}

static void test_restart_of_a_transfer_waiting_for_flow_control(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    assert_int_equal(ls_isotp_restart_waiting(&fx.a, 0), LS_EINVAL); /* nothing under way */
    start_ff(100);
    const uint8_t cts[3] = { 0x30, 0x02, 0x00 };
    feed(&fx.a, &fx.ca, cts, 3, 10);
    assert_int_equal(fx.ca.n, 3); /* FF + a block of 2 CFs, then it waits for the next FC */
    assert_int_equal(fx.a.tx_state, LS_ISOTP_TX_WAIT_FC);
    /* the receiver lost a CF and asks again: the first frame goes out now, not at N_Bs */
    assert_int_equal(ls_isotp_restart_waiting(&fx.a, 400000), LS_OK);
    assert_int_equal(fx.ca.n, 4);
    assert_memory_equal(fx.ca.f[3].d, fx.ca.f[0].d, 8);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 1400000);
    const uint8_t all[3] = { 0x30, 0x00, 0x00 };
    feed(&fx.a, &fx.ca, all, 3, 400100);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_TIMEOUT_BS], 0);
    assert_int_equal(ls_isotp_restart_waiting(&fx.a, 400200), LS_EINVAL); /* done */
}

static void test_n_bs_timeout_between_blocks(void **state)
{
    (void)state;
    start_ff(100);
    const uint8_t cts[3] = { 0x30, 0x02, 0x00 };
    feed(&fx.a, &fx.ca, cts, 3, 10);
    assert_int_equal(fx.ca.n, 3); /* FF + a block of 2 CFs */
    assert_int_equal(fx.a.tx_state, LS_ISOTP_TX_WAIT_FC);
    poll_at(&fx.a, &fx.ca, 10 + 1000000 - 1);
    assert_true(ls_isotp_tx_busy(&fx.a));
    poll_at(&fx.a, &fx.ca, 10 + 1000000);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_TIMEOUT_BS], 1);
    assert_int_equal(fx.ca.n, 3);
}

static void test_fc_wait_then_cts(void **state)
{
    (void)state;
    start_ff(20);
    const uint8_t wait[3] = { 0x31, 0, 0 };
    feed(&fx.a, &fx.ca, wait, 3, 900000);
    /* WAIT restarted N_Bs: still waiting after the original deadline */
    poll_at(&fx.a, &fx.ca, 1800000);
    assert_true(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.ca.n, 1);
    const uint8_t cts[3] = { 0x30, 0, 0 };
    feed(&fx.a, &fx.ca, cts, 3, 1850000);
    assert_int_equal(fx.ca.n, 3);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
    size_t n = expected_data_frames(ID_A, fx.payload, 20, true, fx.exp);
    for (size_t i = 0; i < n; i++) {
        assert_frame_eq(&fx.ca.f[i], &fx.exp[i]);
    }
}

static void test_fc_wait_restarts_n_bs_then_times_out(void **state)
{
    (void)state;
    start_ff(20);
    const uint8_t wait[3] = { 0x31, 0, 0 };
    feed(&fx.a, &fx.ca, wait, 3, 500000);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 1500000);
    poll_at(&fx.a, &fx.ca, 1500000);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_TIMEOUT_BS], 1);
}

static void test_wft_max_overrun(void **state)
{
    (void)state;
    ls_isotp_config_t c = cfg_of(8, 0, true);
    c.wft_max = 2;
    memset(&fx, 0, sizeof(fx));
    assert_int_equal(ls_isotp_init(&fx.a, &c, ID_A, ID_B, cap_send, &fx.ca), LS_OK);
    fill_pattern(fx.payload, 30, 1);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 30, 0), LS_OK);
    const uint8_t wait[3] = { 0x31, 0, 0 };
    feed(&fx.a, &fx.ca, wait, 3, 10);
    feed(&fx.a, &fx.ca, wait, 3, 20);
    assert_true(ls_isotp_tx_busy(&fx.a));
    feed(&fx.a, &fx.ca, wait, 3, 30);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_WFT_OVRN], 1);
    assert_int_equal(fx.a.last_error, LS_ISOTP_N_WFT_OVRN);
    assert_int_equal(fx.ca.n, 1);
}

/* The WAIT count is "in a row": a CTS resets it for the next block. */
static void test_wft_counter_resets_on_cts(void **state)
{
    (void)state;
    ls_isotp_config_t c = cfg_of(8, 0, true);
    c.wft_max = 1;
    memset(&fx, 0, sizeof(fx));
    assert_int_equal(ls_isotp_init(&fx.a, &c, ID_A, ID_B, cap_send, &fx.ca), LS_OK);
    fill_pattern(fx.payload, 30, 1);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 30, 0), LS_OK);
    const uint8_t wait[3] = { 0x31, 0, 0 };
    const uint8_t cts1[3] = { 0x30, 1, 0 };
    feed(&fx.a, &fx.ca, wait, 3, 10);
    feed(&fx.a, &fx.ca, cts1, 3, 20);
    assert_int_equal(fx.ca.n, 2);
    feed(&fx.a, &fx.ca, wait, 3, 30);
    assert_true(ls_isotp_tx_busy(&fx.a));
    feed(&fx.a, &fx.ca, cts1, 3, 40);
    assert_int_equal(fx.ca.n, 3);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_WFT_OVRN], 0);
}

static void test_fc_ovflw_aborts_sender(void **state)
{
    (void)state;
    start_ff(3000);
    const uint8_t ovf[3] = { 0x32, 0, 0 };
    feed(&fx.a, &fx.ca, ovf, 3, 10);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_BUFFER_OVFLW], 1);
    assert_int_equal(fx.a.last_error, LS_ISOTP_N_BUFFER_OVFLW);
    poll_at(&fx.a, &fx.ca, 2000000);
    assert_int_equal(fx.ca.n, 1);
}

static void test_invalid_fs_aborts_sender(void **state)
{
    (void)state;
    start_ff(20);
    const uint8_t bad[8] = { 0x33, 0, 0, PAD, PAD, PAD, PAD, PAD };
    feed(&fx.a, &fx.ca, bad, 8, 10);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_INVALID_FS], 1);
    assert_int_equal(fx.ca.n, 1);
}

static void test_fc_when_not_waiting_is_ignored(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t cts[3] = { 0x30, 0, 0 };
    feed(&fx.a, &fx.ca, cts, 3, 0);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_UNEXP_PDU], 1);
    assert_int_equal(fx.ca.n, 0);
    /* also while sending CFs with BS 0 */
    start_ff(100);
    const uint8_t cts_slow[3] = { 0x30, 0, 10 };
    feed(&fx.a, &fx.ca, cts_slow, 3, 0);
    assert_int_equal(fx.ca.n, 2);
    feed(&fx.a, &fx.ca, cts, 3, 1);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_UNEXP_PDU], 1);
    assert_int_equal(fx.ca.n, 2);
    assert_int_equal(fx.a.tx_stmin_us, 10000);
}

static void test_short_fc_is_malformed(void **state)
{
    (void)state;
    start_ff(20);
    const uint8_t shortfc[2] = { 0x30, 0 };
    feed(&fx.a, &fx.ca, shortfc, 2, 10);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_MALFORMED], 1);
    assert_int_equal(fx.a.tx_state, LS_ISOTP_TX_WAIT_FC);
    const uint8_t cts[3] = { 0x30, 0, 0 };
    feed(&fx.a, &fx.ca, cts, 3, 20);
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
}

/* ---- receiver -------------------------------------------------------------- */

static void rx_ff(uint16_t len, uint64_t t)
{
    uint8_t ff[8] = { (uint8_t)(0x10u | (len >> 8)), (uint8_t)len, 0, 1, 2, 3, 4, 5 };
    feed(&fx.b, &fx.cb, ff, 8, t);
}

static void rx_cf(uint8_t sn, uint8_t fillv, uint64_t t)
{
    uint8_t cf[8];
    memset(cf, fillv, sizeof(cf));
    cf[0] = (uint8_t)(0x20u | sn);
    feed(&fx.b, &fx.cb, cf, 8, t);
}

static void test_rx_ff_sends_cts_with_our_params(void **state)
{
    (void)state;
    ls_isotp_config_t cb = cfg_of(4, 0xF2, true);
    setup_links(NULL, &cb);
    rx_ff(20, 0);
    assert_int_equal(fx.cb.n, 1);
    frame_t want = fc_frame(ID_B, 0, 4, 0xF2, true);
    assert_frame_eq(&fx.cb.f[0], &want);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_RECEIVING);

    ls_isotp_config_t cu = cfg_of(0, 3, false);
    setup_links(NULL, &cu);
    rx_ff(20, 0);
    frame_t want_u = fc_frame(ID_B, 0, 0, 3, false);
    assert_int_equal(fx.cb.f[0].len, 3);
    assert_frame_eq(&fx.cb.f[0], &want_u);
}

static void test_rx_block_size_fc_after_each_block(void **state)
{
    (void)state;
    ls_isotp_config_t cb = cfg_of(2, 0, true);
    setup_links(NULL, &cb);
    rx_ff(6 + 7 * 5, 0); /* 5 CFs: blocks of 2, 2, 1 */
    assert_int_equal(fx.cb.n, 1);
    rx_cf(1, 0x11, 1);
    assert_int_equal(fx.cb.n, 1);
    rx_cf(2, 0x22, 2);
    assert_int_equal(fx.cb.n, 2);
    rx_cf(3, 0x33, 3);
    rx_cf(4, 0x44, 4);
    assert_int_equal(fx.cb.n, 3);
    rx_cf(5, 0x55, 5);
    assert_int_equal(fx.cb.n, 3); /* complete: no FC after the last CF */
    frame_t want = fc_frame(ID_B, 0, 2, 0, true);
    for (size_t i = 0; i < 3; i++) {
        assert_frame_eq(&fx.cb.f[i], &want);
    }
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 41);
    const uint8_t head[8] = { 0, 1, 2, 3, 4, 5, 0x11, 0x11 };
    assert_memory_equal(fx.out, head, 8);
    assert_int_equal(fx.out[40], 0x55);
}

static void test_rx_sn_wraps(void **state)
{
    (void)state;
    ls_isotp_config_t cb = cfg_of(0, 0, true);
    setup_links(NULL, &cb);
    rx_ff(6 + 7 * 20, 0);
    uint8_t sn = 1;
    for (int i = 0; i < 20; i++) {
        rx_cf(sn, (uint8_t)i, (uint64_t)i + 1);
        sn = (uint8_t)((sn + 1) & 0xF);
    }
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_OK], 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 146);
    assert_int_equal(fx.out[6 + 7 * 15], 15); /* the CF after SN 15 was SN 0 */
}

static void test_rx_n_cr_timeout(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_ff(30, 100);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.b), 100 + 1000000);
    rx_cf(1, 0, 500000);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.b), 500000 + 1000000);
    poll_at(&fx.b, &fx.cb, 1499999);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_RECEIVING);
    poll_at(&fx.b, &fx.cb, 1500000);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_TIMEOUT_CR], 1);
    assert_int_equal(fx.b.last_error, LS_ISOTP_N_TIMEOUT_CR);
    rx_cf(2, 0, 1500001);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_UNEXP_PDU], 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 0);
}

/* N_Cr restarts at every CF, so a trickle (one CF just inside N_Cr) would
 * hold a 4095-byte reception for 585 N_Cr; the cap ends it after
 * 1 + ceil(585 / BS 8) = 75 N_Cr, and one at full speed is untouched. */
static void test_rx_trickle_is_capped_by_the_announced_length(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    ls_isotp_config_t c;
    ls_isotp_default_config(&c);
    const uint64_t cap_us = 75u * 1000000u;
    assert_int_equal(ls_isotp_rx_cap_us(&c, 4095), cap_us);
    assert_int_equal(ls_isotp_rx_cap_us(&c, 30), 2u * 1000000u); /* 4 CFs: one block */
    rx_ff(4095, 0);
    uint8_t sn = 1;
    uint64_t t = 0;
    while (t + 900000u < cap_us) {
        t += 900000u; /* inside N_Cr every time */
        rx_cf(sn, 0x11, t);
        sn = (uint8_t)((sn + 1u) & 0xFu);
        assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_RECEIVING);
    }
    assert_int_equal(ls_isotp_next_deadline_us(&fx.b), cap_us);
    poll_at(&fx.b, &fx.cb, cap_us - 1u);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_RECEIVING);
    poll_at(&fx.b, &fx.cb, cap_us);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_TIMEOUT_CR], 1);
    /* A 4095-byte reception at full speed completes. */
    rx_ff(4095, cap_us + 1u);
    sn = 1;
    for (int i = 0; i < 585; i++) {
        rx_cf(sn, 0x22, cap_us + 2u + (uint64_t)i);
        sn = (uint8_t)((sn + 1u) & 0xFu);
    }
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_OK], 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 4095);
}

static void test_rx_wrong_sn(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_ff(30, 0);
    rx_cf(1, 0, 1);
    rx_cf(3, 0, 2);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_WRONG_SN], 1);
    assert_int_equal(fx.b.last_error, LS_ISOTP_N_WRONG_SN);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
    rx_cf(3, 0, 3);
    rx_cf(4, 0, 4);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_UNEXP_PDU], 2);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 0);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_OK], 0);
}

static void test_rx_cf_while_idle(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_cf(1, 0, 0);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_UNEXP_PDU], 1);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
    assert_int_equal(fx.cb.n, 0);
}

static void test_rx_ff_during_reception_restarts(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_ff(30, 0);
    rx_cf(1, 0xAA, 1);
    rx_ff(13, 2);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_UNEXP_PDU], 1);
    assert_int_equal(fx.cb.n, 2); /* a fresh CTS for the new message */
    rx_cf(1, 0xBB, 3);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 13);
    const uint8_t want[13] = { 0, 1, 2, 3, 4, 5, 0xBB, 0xBB, 0xBB, 0xBB, 0xBB, 0xBB, 0xBB };
    assert_memory_equal(fx.out, want, 13);
}

static void test_rx_sf_during_reception_replaces(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_ff(30, 0);
    const uint8_t sf[3] = { 0x02, 0xDE, 0xAD };
    feed(&fx.b, &fx.cb, sf, 3, 1);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_UNEXP_PDU], 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 2);
    assert_int_equal(fx.out[0], 0xDE);
    assert_int_equal(fx.out[1], 0xAD);
}

static void test_rx_ff_escape_gets_ovflw(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t ff32[8] = { 0x10, 0x00, 0x00, 0x00, 0x10, 0x00, 0xAB, 0xCD };
    feed(&fx.b, &fx.cb, ff32, 8, 0);
    assert_int_equal(fx.cb.n, 1);
    frame_t want = fc_frame(ID_B, 2, 8, 0, true);
    assert_frame_eq(&fx.cb.f[0], &want);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_BUFFER_OVFLW], 1);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
}

/* The receiver's FC.OVFLW reaches the sender, which aborts with N_BUFFER_OVFLW. */
static void test_ovflw_end_to_end(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t sf[2] = { 0x01, 0x77 };
    feed(&fx.b, &fx.cb, sf, 2, 0); /* b now holds an untaken message */
    fill_pattern(fx.payload, 50, 5);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 50, 0), LS_OK);
    feed(&fx.b, &fx.cb, fx.ca.f[0].d, fx.ca.f[0].len, 1);
    assert_int_equal(fx.cb.n, 1);
    frame_t want = fc_frame(ID_B, 2, 8, 0, true);
    assert_frame_eq(&fx.cb.f[0], &want);
    feed(&fx.a, &fx.ca, fx.cb.f[0].d, fx.cb.f[0].len, 2);
    assert_false(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_BUFFER_OVFLW], 1);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_BUFFER_OVFLW], 1);
    /* the held message survives */
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 1);
    assert_int_equal(fx.out[0], 0x77);
}

static void test_rx_done_drops_new_sf(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t sf1[2] = { 0x01, 0x01 };
    const uint8_t sf2[2] = { 0x01, 0x02 };
    feed(&fx.b, &fx.cb, sf1, 2, 0);
    feed(&fx.b, &fx.cb, sf2, 2, 1);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_BUFFER_OVFLW], 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 1);
    assert_int_equal(fx.out[0], 0x01);
    feed(&fx.b, &fx.cb, sf2, 2, 2);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 1);
    assert_int_equal(fx.out[0], 0x02);
}

static void test_rx_malformed_frames(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t ff_short_len[8] = { 0x10, 0x07, 1, 2, 3, 4, 5, 6 }; /* fits a SF */
    const uint8_t ff_dlc7[7] = { 0x10, 0x20, 1, 2, 3, 4, 5 };
    const uint8_t sf_len0[8] = { 0x00, 1, 2, 3, 4, 5, 6, 7 };
    const uint8_t sf_len8[8] = { 0x08, 1, 2, 3, 4, 5, 6, 7 };
    const uint8_t sf_trunc[4] = { 0x05, 1, 2, 3 };
    const uint8_t pci4[8] = { 0x40, 0, 0, 0, 0, 0, 0, 0 };
    const uint8_t nine[9] = { 0x01, 1, 0, 0, 0, 0, 0, 0, 0 };
    feed(&fx.b, &fx.cb, ff_short_len, 8, 0);
    feed(&fx.b, &fx.cb, ff_dlc7, 7, 0);
    feed(&fx.b, &fx.cb, sf_len0, 8, 0);
    feed(&fx.b, &fx.cb, sf_len8, 8, 0);
    feed(&fx.b, &fx.cb, sf_trunc, 4, 0);
    feed(&fx.b, &fx.cb, pci4, 8, 0);
    feed(&fx.b, &fx.cb, nine, 9, 0);
    feed(&fx.b, &fx.cb, nine, 0, 0);
    ls_isotp_on_frame(&fx.b, NULL, 8, 0);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_MALFORMED], 9);
    assert_int_equal(fx.b.last_error, LS_ISOTP_N_MALFORMED);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
    assert_int_equal(fx.cb.n, 0);           /* no FC for a malformed FF */
    ls_isotp_on_frame(NULL, sf_len0, 8, 0); /* no crash */
}

/* A too-short CF is ignored, the reception continues with the same SN. */
static void test_rx_short_cf_ignored(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_ff(20, 0);
    const uint8_t short_cf[5] = { 0x21, 1, 2, 3, 4 };
    feed(&fx.b, &fx.cb, short_cf, 5, 1);
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_MALFORMED], 1);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_RECEIVING);
    rx_cf(1, 9, 2);
    /* last CF needs 1 + 7 bytes: unpadded minimal frame is accepted */
    const uint8_t last[8] = { 0x22, 8, 8, 8, 8, 8, 8, 8 };
    feed(&fx.b, &fx.cb, last, 8, 3);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 20);
    assert_int_equal(fx.out[19], 8);
}

static void test_rx_unpadded_last_cf(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    rx_ff(9, 0);
    const uint8_t last[4] = { 0x21, 7, 8, 9 };
    feed(&fx.b, &fx.cb, last, 4, 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 9);
    const uint8_t want[9] = { 0, 1, 2, 3, 4, 5, 7, 8, 9 };
    assert_memory_equal(fx.out, want, 9);
}

static void test_take_rx_too_small_cap(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t sf[6] = { 0x05, 1, 2, 3, 4, 5 };
    feed(&fx.b, &fx.cb, sf, 6, 0);
    memset(fx.out, 0xEE, 8);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, 4), 0);
    assert_int_equal(fx.out[0], 0xEE); /* nothing written past or within cap */
    assert_int_equal(fx.b.rx_results[LS_ISOTP_N_BUFFER_OVFLW], 1);
    assert_int_equal(fx.b.rx_state, LS_ISOTP_RX_IDLE);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), 0);
    /* exact cap works; NULL out leaves the message in place */
    feed(&fx.b, &fx.cb, sf, 6, 1);
    assert_int_equal(ls_isotp_take_rx(&fx.b, NULL, 5), 0);
    assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, 5), 5);
}

/* ---- CAN queue full: the same frame is retried by poll -------------------- */

static void test_queue_full_retry(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    fill_pattern(fx.payload, 20, 3);
    fx.ca.refuse = 1;
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 20, 0), LS_OK);
    assert_int_equal(fx.ca.n, 0);
    assert_true(ls_isotp_tx_busy(&fx.a));
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 0);
    poll_at(&fx.a, &fx.ca, 10);
    assert_int_equal(fx.ca.n, 1);
    /* N_Bs counts from when the FF really went out */
    assert_int_equal(ls_isotp_next_deadline_us(&fx.a), 10 + 1000000);
    const uint8_t cts[3] = { 0x30, 0, 0 };
    fx.ca.refuse = 1;
    feed(&fx.a, &fx.ca, cts, 3, 20);
    assert_int_equal(fx.ca.n, 1);
    fx.ca.refuse = 1;
    poll_at(&fx.a, &fx.ca, 30);
    assert_int_equal(fx.ca.n, 1);
    poll_at(&fx.a, &fx.ca, 40);
    assert_int_equal(fx.ca.n, 3);
    assert_int_equal(fx.ca.refused, 3);
    size_t n = expected_data_frames(ID_A, fx.payload, 20, true, fx.exp);
    assert_int_equal(n, 3);
    for (size_t i = 0; i < n; i++) {
        assert_frame_eq(&fx.ca.f[i], &fx.exp[i]);
    }
    assert_int_equal(fx.a.tx_results[LS_ISOTP_N_OK], 1);
}

static void test_queue_full_sf_retry(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    const uint8_t p[3] = { 9, 8, 7 };
    fx.ca.refuse = 2;
    assert_int_equal(ls_isotp_send(&fx.a, p, 3, 0), LS_OK);
    poll_at(&fx.a, &fx.ca, 1);
    assert_int_equal(fx.ca.n, 0);
    assert_int_equal(ls_isotp_send(&fx.a, p, 3, 1), LS_EBUSY);
    poll_at(&fx.a, &fx.ca, 2);
    assert_int_equal(fx.ca.n, 1);
    const uint8_t b[4] = { 0x03, 9, 8, 7 };
    frame_t want = mk(ID_A, b, 4, true);
    assert_frame_eq(&fx.ca.f[0], &want);
    assert_false(ls_isotp_tx_busy(&fx.a));
}

static void test_queue_full_fc_retry(void **state)
{
    (void)state;
    setup_links(NULL, NULL);
    fx.cb.refuse = 1;
    rx_ff(20, 0);
    assert_int_equal(fx.cb.n, 0);
    assert_true(fx.b.rx_fc_pending);
    assert_int_equal(ls_isotp_next_deadline_us(&fx.b), 0);
    poll_at(&fx.b, &fx.cb, 700000);
    assert_int_equal(fx.cb.n, 1);
    frame_t want = fc_frame(ID_B, 0, 8, 0, true);
    assert_frame_eq(&fx.cb.f[0], &want);
    /* N_Cr runs from the FC that really went out */
    assert_int_equal(ls_isotp_next_deadline_us(&fx.b), 700000 + 1000000);
}

/* ---- random loopback ------------------------------------------------------ */

static uint32_t rng_state;
static uint32_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}

static void test_loopback_random_lengths(void **state)
{
    (void)state;
    static const uint8_t stmins[] = { 0x00, 0x01, 0xF1, 0xF5 };
    rng_state = 0x12345678u;
    for (int iter = 0; iter < 120; iter++) {
        size_t len = 1u + rng() % LS_ISOTP_MAX_PAYLOAD;
        uint8_t bs = (uint8_t)(rng() % 17u);
        uint8_t st = stmins[rng() % 4u];
        ls_isotp_config_t ca = cfg_of((uint8_t)(rng() % 9u), 0, (rng() & 1u) != 0);
        ls_isotp_config_t cb = cfg_of(bs, st, (rng() & 1u) != 0);
        setup_links(&ca, &cb);
        for (size_t i = 0; i < len; i++) {
            fx.payload[i] = (uint8_t)rng();
        }
        assert_int_equal(ls_isotp_send(&fx.a, fx.payload, len, 0), LS_OK);
        (void)run_wire(50, 60000000);
        assert_int_equal(fx.ca.n, iso_data_frames(len));
        assert_int_equal(ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)), len);
        assert_memory_equal(fx.out, fx.payload, len);
        assert_int_equal(fx.a.last_error, LS_ISOTP_N_OK);
        assert_int_equal(fx.b.last_error, LS_ISOTP_N_OK);
    }
}

/* Both directions at once on the same pair of links (full duplex). */
static void test_full_duplex(void **state)
{
    (void)state;
    ls_isotp_config_t c = cfg_of(3, 0xF2, true);
    setup_links(&c, &c);
    static uint8_t p2[500];
    fill_pattern(fx.payload, 700, 11);
    fill_pattern(p2, 500, 12);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 700, 0), LS_OK);
    assert_int_equal(ls_isotp_send(&fx.b, p2, 500, 0), LS_OK);
    size_t da = 0, db = 0;
    bool got_a = false, got_b = false;
    for (uint64_t t = 0; t < 5000000 && !(got_a && got_b); t += 100) {
        fx.ca.now_us = t;
        fx.cb.now_us = t;
        while (da < fx.ca.n) {
            ls_isotp_on_frame(&fx.b, fx.ca.f[da].d, fx.ca.f[da].len, t);
            da++;
        }
        while (db < fx.cb.n) {
            ls_isotp_on_frame(&fx.a, fx.cb.f[db].d, fx.cb.f[db].len, t);
            db++;
        }
        ls_isotp_poll(&fx.a, t);
        ls_isotp_poll(&fx.b, t);
        if (!got_b && ls_isotp_take_rx(&fx.b, fx.out, sizeof(fx.out)) == 700) {
            assert_memory_equal(fx.out, fx.payload, 700);
            got_b = true;
        }
        if (!got_a && ls_isotp_take_rx(&fx.a, fx.out, sizeof(fx.out)) == 500) {
            assert_memory_equal(fx.out, p2, 500);
            got_a = true;
        }
    }
    assert_true(got_a && got_b);
}

/* ---- API contract ------------------------------------------------------------ */

static void test_api_arguments(void **state)
{
    (void)state;
    memset(&fx, 0, sizeof(fx));
    ls_isotp_config_t c;
    ls_isotp_default_config(&c);
    assert_int_equal(c.block_size, 8);
    assert_int_equal(c.st_min, 0);
    assert_true(c.tx_padding);
    assert_int_equal(c.padding_byte, 0xCC);
    assert_int_equal(c.n_bs_timeout_us, 1000000);
    assert_int_equal(c.n_cr_timeout_us, 1000000);
    assert_int_equal(c.wft_max, 10);
    ls_isotp_default_config(NULL);

    assert_int_equal(ls_isotp_init(NULL, NULL, 1, 2, cap_send, NULL), LS_EINVAL);
    assert_int_equal(ls_isotp_init(&fx.a, NULL, 1, 2, NULL, NULL), LS_EINVAL);
    c.st_min = 0x80;
    assert_int_equal(ls_isotp_init(&fx.a, &c, 1, 2, cap_send, &fx.ca), LS_EINVAL);
    c.st_min = 0xF9;
    assert_int_equal(ls_isotp_init(&fx.a, &c, 1, 2, cap_send, &fx.ca), LS_OK);
    c.n_cr_timeout_us = 0;
    assert_int_equal(ls_isotp_init(&fx.a, &c, 1, 2, cap_send, &fx.ca), LS_EINVAL);

    assert_int_equal(ls_isotp_init(&fx.a, NULL, ID_A, ID_B, cap_send, &fx.ca), LS_OK);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 0, 0), LS_ELEN);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 4096, 0), LS_ELEN);
    assert_int_equal(ls_isotp_send(&fx.a, NULL, 5, 0), LS_EINVAL);
    assert_int_equal(ls_isotp_send(NULL, fx.payload, 5, 0), LS_EINVAL);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 4095, 0), LS_OK);
    assert_int_equal(ls_isotp_send(&fx.a, fx.payload, 5, 0), LS_EBUSY);
    assert_int_equal(fx.ca.n, 1);
    assert_int_equal(fx.ca.f[0].d[0], 0x1F);
    assert_int_equal(fx.ca.f[0].d[1], 0xFF);

    assert_false(ls_isotp_tx_busy(NULL));
    assert_int_equal(ls_isotp_next_deadline_us(NULL), UINT64_MAX);
    assert_int_equal(ls_isotp_take_rx(NULL, fx.out, 10), 0);
    ls_isotp_poll(NULL, 0);
}

static void test_single_frame_codec(void **state)
{
    (void)state;
    uint8_t frame[8];
    const uint8_t p[7] = { 1, 2, 3, 4, 5, 6, 7 };
    assert_int_equal(ls_isotp_encode_single(p, 3, true, 0xAA, frame), 8);
    const uint8_t want_pad[8] = { 0x03, 1, 2, 3, 0xAA, 0xAA, 0xAA, 0xAA };
    assert_memory_equal(frame, want_pad, 8);
    assert_int_equal(ls_isotp_encode_single(p, 7, false, 0xAA, frame), 8);
    const uint8_t want7[8] = { 0x07, 1, 2, 3, 4, 5, 6, 7 };
    assert_memory_equal(frame, want7, 8);
    assert_int_equal(ls_isotp_encode_single(p, 1, false, 0, frame), 2);
    assert_int_equal(ls_isotp_encode_single(p, 0, true, 0, frame), 0);
    assert_int_equal(ls_isotp_encode_single(p, 8, true, 0, frame), 0);
    assert_int_equal(ls_isotp_encode_single(NULL, 3, true, 0, frame), 0);

    uint8_t out[7];
    assert_int_equal(ls_isotp_decode_single(want_pad, 8, out, sizeof(out)), 3);
    assert_memory_equal(out, p, 3);
    assert_int_equal(ls_isotp_decode_single(want_pad, 4, out, sizeof(out)), 3);
    assert_int_equal(ls_isotp_decode_single(want_pad, 3, out, sizeof(out)), 0);
    assert_int_equal(ls_isotp_decode_single(want7, 8, out, sizeof(out)), 7);
    const uint8_t ff[8] = { 0x10, 0x10, 0, 0, 0, 0, 0, 0 };
    const uint8_t sf0[8] = { 0x00, 0, 0, 0, 0, 0, 0, 0 };
    assert_int_equal(ls_isotp_decode_single(ff, 8, out, sizeof(out)), 0);
    assert_int_equal(ls_isotp_decode_single(sf0, 8, out, sizeof(out)), 0);
    assert_int_equal(ls_isotp_decode_single(want7, 8, out, 6), 0);
    assert_int_equal(ls_isotp_decode_single(NULL, 8, out, 7), 0);
    assert_int_equal(ls_isotp_decode_single(want7, 0, out, 7), 0);
}

static void test_result_names(void **state)
{
    (void)state;
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_OK), "N_OK");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_TIMEOUT_BS), "N_TIMEOUT_BS");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_TIMEOUT_CR), "N_TIMEOUT_CR");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_WRONG_SN), "N_WRONG_SN");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_INVALID_FS), "N_INVALID_FS");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_UNEXP_PDU), "N_UNEXP_PDU");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_WFT_OVRN), "N_WFT_OVRN");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_BUFFER_OVFLW), "N_BUFFER_OVFLW");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_MALFORMED), "N_MALFORMED");
    assert_string_equal(ls_isotp_result_name(LS_ISOTP_N_RESULT_COUNT), "N_UNKNOWN");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sf_tx_padded_and_unpadded),
        cmocka_unit_test(test_sf_rx_padded_and_unpadded),
        cmocka_unit_test(test_transfer_matrix),
        cmocka_unit_test(test_stmin0_bs0_burst),
        cmocka_unit_test(test_stmin_to_us),
        cmocka_unit_test(test_sender_stmin_f3_is_300us),
        cmocka_unit_test(test_sender_stmin_reserved_is_127ms),
        cmocka_unit_test(test_n_bs_timeout),
        cmocka_unit_test(test_restart_of_a_transfer_waiting_for_flow_control),
        cmocka_unit_test(test_n_bs_timeout_between_blocks),
        cmocka_unit_test(test_resend_after_a_failed_transfer),
        cmocka_unit_test(test_fc_wait_then_cts),
        cmocka_unit_test(test_fc_wait_restarts_n_bs_then_times_out),
        cmocka_unit_test(test_wft_max_overrun),
        cmocka_unit_test(test_wft_counter_resets_on_cts),
        cmocka_unit_test(test_fc_ovflw_aborts_sender),
        cmocka_unit_test(test_invalid_fs_aborts_sender),
        cmocka_unit_test(test_fc_when_not_waiting_is_ignored),
        cmocka_unit_test(test_short_fc_is_malformed),
        cmocka_unit_test(test_rx_ff_sends_cts_with_our_params),
        cmocka_unit_test(test_rx_block_size_fc_after_each_block),
        cmocka_unit_test(test_rx_sn_wraps),
        cmocka_unit_test(test_rx_n_cr_timeout),
        cmocka_unit_test(test_rx_trickle_is_capped_by_the_announced_length),
        cmocka_unit_test(test_rx_wrong_sn),
        cmocka_unit_test(test_rx_cf_while_idle),
        cmocka_unit_test(test_rx_ff_during_reception_restarts),
        cmocka_unit_test(test_rx_sf_during_reception_replaces),
        cmocka_unit_test(test_rx_ff_escape_gets_ovflw),
        cmocka_unit_test(test_ovflw_end_to_end),
        cmocka_unit_test(test_rx_done_drops_new_sf),
        cmocka_unit_test(test_rx_malformed_frames),
        cmocka_unit_test(test_rx_short_cf_ignored),
        cmocka_unit_test(test_rx_unpadded_last_cf),
        cmocka_unit_test(test_take_rx_too_small_cap),
        cmocka_unit_test(test_queue_full_retry),
        cmocka_unit_test(test_queue_full_sf_retry),
        cmocka_unit_test(test_queue_full_fc_retry),
        cmocka_unit_test(test_loopback_random_lengths),
        cmocka_unit_test(test_full_duplex),
        cmocka_unit_test(test_api_arguments),
        cmocka_unit_test(test_single_frame_codec),
        cmocka_unit_test(test_result_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
