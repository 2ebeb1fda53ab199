/* Black-box tests of the fault-injecting link (hal/sim/faulty_link.h) over a
 * fake inner link and a fake clock. Rates are checked two ways: against
 * binomial bounds (the contract a user relies on) and, for drop, against an
 * oracle that replays the documented decision stream (splitmix64, six draws
 * per frame), so a change of the stream shows up as a failing test. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "faulty_link.h"

/* ---- fake inner link: a queue of frames to receive, a log of sent frames ---- */

#define FAKE_CAP 40000

typedef struct {
    hal_can_frame_t rxq[FAKE_CAP];
    size_t rx_head, rx_tail;
    hal_can_frame_t sent[FAKE_CAP];
    size_t n_sent;
    int send_ret; /* what send answers (LS_OK, or an error to inject) */
    int closed;
} fake_t;

static fake_t fake;

static int fake_send(void *self, const hal_can_frame_t *f)
{
    fake_t *k = self;
    if (k->send_ret < 0) {
        return k->send_ret;
    }
    assert_true(k->n_sent < FAKE_CAP);
    k->sent[k->n_sent++] = *f;
    return LS_OK;
}

static int fake_recv(void *self, hal_can_frame_t *f)
{
    fake_t *k = self;
    if (k->rx_head == k->rx_tail) {
        return LS_EAGAIN;
    }
    *f = k->rxq[k->rx_head++];
    return 1;
}

static int fake_poll_fd(void *self)
{
    (void)self;
    return 42;
}

static int fake_status(void *self, hal_can_status_t *out)
{
    (void)self;
    memset(out, 0, sizeof *out);
    out->state = HAL_CAN_STATE_ACTIVE;
    out->bitrate = 1000000;
    return LS_OK;
}

static void fake_close(void *self)
{
    ((fake_t *)self)->closed++;
}

static const hal_can_ops_t fake_ops = {
    .send = fake_send, .recv = fake_recv, .poll_fd = fake_poll_fd, .status = fake_status, .close = fake_close
};

static hal_can_link_t fake_link(void)
{
    hal_can_link_t l = { .ops = &fake_ops, .self = &fake };
    snprintf(l.name, sizeof l.name, "fake");
    return l;
}

static void fake_push_rx(const hal_can_frame_t *f)
{
    assert_true(fake.rx_tail < FAKE_CAP);
    fake.rxq[fake.rx_tail++] = *f;
}

/* ---- fake clock ---- */

static uint64_t g_now_us;
static uint64_t fake_now(void *self)
{
    (void)self;
    return g_now_us;
}

/* Frame number i: id and the first four data bytes carry i, the rest a pattern. */
static hal_can_frame_t frame_n(uint32_t i)
{
    hal_can_frame_t f = { .id = i & 0x1FFFFFFFu, .flags = HAL_CAN_F_EXT, .len = 8 };
    f.data[0] = (uint8_t)(i >> 24);
    f.data[1] = (uint8_t)(i >> 16);
    f.data[2] = (uint8_t)(i >> 8);
    f.data[3] = (uint8_t)i;
    for (int b = 4; b < 8; b++) {
        f.data[b] = (uint8_t)(0xA5 ^ b);
    }
    return f;
}

static hal_can_link_t link_;

static int setup(void **state)
{
    (void)state;
    memset(&fake, 0, sizeof fake);
    memset(&link_, 0, sizeof link_);
    g_now_us = 1000000; /* not zero, so "due at 0" holds cannot hide behind t = 0 */
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    hal_can_close(&link_);
    return 0;
}

static hal_sim_fault_config_t cfg_with(const char *spec)
{
    hal_sim_fault_config_t cfg;
    char msg[256];
    int r = hal_sim_fault_parse(spec, &cfg, msg, sizeof msg);
    if (r != LS_OK) {
        fail_msg("parse '%s': %s", spec, msg);
    }
    cfg.clock = (hal_clock_t){ .now_us = fake_now, .self = NULL };
    return cfg;
}

static void wrap(const char *spec)
{
    hal_can_link_t inner = fake_link();
    hal_sim_fault_config_t cfg = cfg_with(spec);
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_OK);
}

static hal_sim_fault_counters_t counters(void)
{
    hal_sim_fault_counters_t c;
    assert_int_equal(hal_sim_faulty_counters(&link_, &c), LS_OK);
    return c;
}

/* |k - n p| within 4.5 standard deviations of a binomial: a correct
 * implementation fails this about once in 150000 seeds; a wrong rate by a
 * fraction of p fails it for sure at these n. */
static void assert_binomial(uint32_t k, uint32_t n, double p)
{
    double mean = n * p;
    double sd = sqrt(n * p * (1.0 - p));
    if (fabs((double)k - mean) > 4.5 * sd) {
        fail_msg("count %u out of %u, expected %.1f +- %.1f (p=%g)", k, n, mean, 4.5 * sd, p);
    }
}

static uint32_t frame_index(const hal_can_frame_t *f)
{
    return f->id;
}

/* ------------------------------------------------------------------ wrap */

static void test_wrap_rejects_bad_arguments(void **state)
{
    (void)state;
    hal_can_link_t inner = fake_link();
    hal_sim_fault_config_t cfg;
    memset(&cfg, 0, sizeof cfg);
    assert_int_equal(hal_sim_faulty_wrap(NULL, &inner, &cfg), LS_EINVAL);
    assert_int_equal(hal_sim_faulty_wrap(&link_, NULL, &cfg), LS_EINVAL);
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, NULL), LS_EINVAL);
    cfg.tx.drop = 1.5;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    cfg.tx.drop = NAN;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    cfg.tx.drop = -0.1;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    memset(&cfg, 0, sizeof cfg);
    cfg.clock.now_us = fake_now;
    cfg.rx.delay = 0.1; /* without delay_us */
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    memset(&cfg, 0, sizeof cfg);
    cfg.clock.now_us = fake_now;
    cfg.busoff_every_us = 1000;
    cfg.busoff_for_us = 1000; /* never back on */
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    cfg.busoff_for_us = 0;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    memset(&cfg, 0, sizeof cfg);
    cfg.clock.now_us = fake_now;
    cfg.window_after_us = 1000; /* a window that never closes must say so with for > 0 */
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    /* time-dependent faults need a clock */
    memset(&cfg, 0, sizeof cfg);
    cfg.tx.reorder = 0.1;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    memset(&cfg, 0, sizeof cfg);
    cfg.busoff_every_us = 1000;
    cfg.busoff_for_us = 10;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_EINVAL);
    /* drop-only needs none */
    memset(&cfg, 0, sizeof cfg);
    cfg.rx.drop = 0.5;
    assert_int_equal(hal_sim_faulty_wrap(&link_, &inner, &cfg), LS_OK);
    assert_string_equal(link_.name, "faulty:fake");
}

static void test_pool_is_static_and_slots_come_back_on_close(void **state)
{
    (void)state;
    hal_can_link_t inner = fake_link();
    hal_sim_fault_config_t cfg;
    memset(&cfg, 0, sizeof cfg);
    hal_can_link_t l[HAL_SIM_FAULTY_MAX_LINKS + 1];
    for (int i = 0; i < HAL_SIM_FAULTY_MAX_LINKS; i++) {
        assert_int_equal(hal_sim_faulty_wrap(&l[i], &inner, &cfg), LS_OK);
    }
    assert_int_equal(hal_sim_faulty_wrap(&l[HAL_SIM_FAULTY_MAX_LINKS], &inner, &cfg), LS_EAGAIN);
    hal_can_close(&l[1]);
    assert_int_equal(fake.closed, 1);
    hal_can_close(&l[1]); /* idempotent: the inner link is closed once */
    assert_int_equal(fake.closed, 1);
    hal_sim_fault_counters_t c;
    assert_int_equal(hal_sim_faulty_counters(&l[1], &c), LS_EINVAL);
    assert_int_equal(hal_sim_faulty_wrap(&l[HAL_SIM_FAULTY_MAX_LINKS], &inner, &cfg), LS_OK);
    for (int i = 0; i <= HAL_SIM_FAULTY_MAX_LINKS; i++) {
        hal_can_close(&l[i]);
    }
    assert_int_equal(fake.closed, HAL_SIM_FAULTY_MAX_LINKS + 1);
    /* a link that is not a decorator has no counters */
    assert_int_equal(hal_sim_faulty_counters(&inner, &c), LS_EINVAL);
    char buf[16];
    assert_true(hal_sim_faulty_format(&inner, buf, sizeof buf) < 0);
}

static void test_no_faults_pass_everything_in_order(void **state)
{
    (void)state;
    wrap("drop=0,seed=7");
    for (uint32_t i = 0; i < 1000; i++) {
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
        fake_push_rx(&f);
    }
    assert_int_equal(fake.n_sent, 1000);
    for (uint32_t i = 0; i < 1000; i++) {
        hal_can_frame_t want = frame_n(i), got;
        assert_memory_equal(&fake.sent[i], &want, sizeof want);
        assert_int_equal(hal_can_recv(&link_, &got), 1);
        assert_memory_equal(&got, &want, sizeof want);
    }
    hal_can_frame_t got;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(hal_can_poll_fd(&link_), 42);
    hal_can_status_t st;
    assert_int_equal(hal_can_status(&link_, &st), LS_OK);
    assert_int_equal(st.state, HAL_CAN_STATE_ACTIVE);
    assert_int_equal(st.bitrate, 1000000);
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.tx.frames, 1000);
    assert_int_equal(c.rx.frames, 1000);
    assert_int_equal(c.tx.dropped + c.tx.duplicated + c.tx.corrupted + c.tx.reordered + c.tx.delayed, 0);
    assert_int_equal(c.rx.dropped + c.rx.duplicated + c.rx.corrupted + c.rx.reordered + c.rx.delayed, 0);
}

/* ------------------------------------------------------------------ rates */

/* The documented decision stream: splitmix64 from the seed (rx: seed ^
 * 0xD1B54A32D192ED03), six draws per frame, the first one decides drop. */
static uint32_t oracle_draw(uint64_t *s)
{
    *s += 0x9E3779B97F4A7C15ull;
    uint64_t z = *s;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (uint32_t)(z >> 32);
}

#define N_RATE 20000u

static void test_drop_rate_both_ways_is_exact_for_a_seed(void **state)
{
    (void)state;
    wrap("drop=0.05,seed=1");
    uint64_t s_tx = 1, s_rx = 1 ^ 0xD1B54A32D192ED03ull;
    uint32_t th = (uint32_t)(0.05 * 4294967296.0);
    size_t want_tx = 0, want_rx = 0;
    bool kept_tx[N_RATE];
    for (uint32_t i = 0; i < N_RATE; i++) {
        kept_tx[i] = oracle_draw(&s_tx) >= th;
        want_tx += kept_tx[i] ? 1u : 0u;
        want_rx += oracle_draw(&s_rx) >= th ? 1u : 0u;
        for (int k = 0; k < 5; k++) {
            (void)oracle_draw(&s_tx);
            (void)oracle_draw(&s_rx);
        }
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK); /* a dropped frame looks sent */
        fake_push_rx(&f);
    }
    size_t got_rx = 0;
    hal_can_frame_t f;
    uint32_t last = 0;
    while (hal_can_recv(&link_, &f) == 1) {
        assert_true(got_rx == 0 || frame_index(&f) > last); /* order kept */
        last = frame_index(&f);
        got_rx++;
    }
    assert_int_equal(fake.n_sent, want_tx);
    assert_int_equal(got_rx, want_rx);
    size_t j = 0;
    for (uint32_t i = 0; i < N_RATE; i++) {
        if (kept_tx[i]) {
            assert_int_equal(frame_index(&fake.sent[j++]), i); /* exactly the frames the oracle kept */
        }
    }
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.tx.frames, N_RATE);
    assert_int_equal(c.rx.frames, N_RATE);
    assert_int_equal(c.tx.dropped, N_RATE - want_tx);
    assert_int_equal(c.rx.dropped, N_RATE - want_rx);
    assert_binomial(c.tx.dropped, N_RATE, 0.05);
    assert_binomial(c.rx.dropped, N_RATE, 0.05);
}

static void test_each_fault_rate_within_binomial_bounds(void **state)
{
    (void)state;
    /* one fault at a time, each direction, several rates */
    static const char *const specs[] = {
        "dup=0.01,seed=3",
        "dup=0.2,seed=4",
        "corrupt=0.05,seed=5",
        "reorder=0.05,seed=6",
        "delay=0.05:1ms,seed=7",
        "drop=0.2,seed=8",
        "rx.drop=0.01,tx.dup=0.3,seed=9",
    };
    for (size_t s = 0; s < sizeof specs / sizeof specs[0]; s++) {
        setup(NULL);
        wrap(specs[s]);
        hal_sim_fault_config_t cfg = cfg_with(specs[s]);
        size_t got_rx = 0;
        for (uint32_t i = 0; i < N_RATE; i++) {
            hal_can_frame_t f = frame_n(i);
            assert_int_equal(hal_can_send(&link_, &f), LS_OK);
            fake_push_rx(&f);
            g_now_us += 100; /* 10 kframes/s */
            while (hal_can_recv(&link_, &f) == 1) {
                got_rx++;
            }
        }
        g_now_us += 1000000; /* every hold falls due */
        hal_can_frame_t f;
        while (hal_can_recv(&link_, &f) == 1) {
            got_rx++;
        }
        hal_sim_fault_counters_t c = counters();
        const hal_sim_fault_rates_t *r[2] = { &cfg.tx, &cfg.rx };
        const hal_sim_fault_dir_counters_t *d[2] = { &c.tx, &c.rx };
        for (int k = 0; k < 2; k++) {
            uint32_t n = d[k]->frames;
            assert_int_equal(n, N_RATE);
            assert_binomial(d[k]->dropped, n, r[k]->drop);
            uint32_t kept = n - d[k]->dropped;
            assert_binomial(d[k]->delayed, kept, r[k]->delay);
            assert_binomial(d[k]->corrupted, kept, r[k]->corrupt);
            /* reorder is drawn for frames that are not delayed */
            assert_binomial(d[k]->reordered, kept - d[k]->delayed, r[k]->reorder);
            /* dup applies to frames that go on at once */
            assert_binomial(d[k]->duplicated, kept - d[k]->delayed - d[k]->reordered, r[k]->dup);
            assert_int_equal(d[k]->hold_overflow, 0);
        }
        /* conservation: out = in - dropped + duplicated */
        assert_int_equal(fake.n_sent, N_RATE - c.tx.dropped + c.tx.duplicated);
        assert_int_equal(got_rx, N_RATE - c.rx.dropped + c.rx.duplicated);
        teardown(NULL);
    }
}

static void test_same_seed_same_faults_other_seed_other_faults(void **state)
{
    (void)state;
    static hal_can_frame_t first[4000];
    size_t n_first = 0;
    for (int run = 0; run < 3; run++) {
        setup(NULL);
        wrap(run < 2 ? "drop=0.1,dup=0.1,corrupt=0.1,reorder=0.1,delay=0.1:2ms,seed=99"
                     : "drop=0.1,dup=0.1,corrupt=0.1,reorder=0.1,delay=0.1:2ms,seed=100");
        for (uint32_t i = 0; i < 2000; i++) {
            hal_can_frame_t f = frame_n(i);
            assert_int_equal(hal_can_send(&link_, &f), LS_OK);
            g_now_us += 500;
        }
        g_now_us += 1000000;
        hal_can_frame_t f;
        (void)hal_can_recv(&link_, &f); /* releases what is still held */
        if (run == 0) {
            n_first = fake.n_sent;
            memcpy(first, fake.sent, n_first * sizeof first[0]);
        } else if (run == 1) {
            assert_int_equal(fake.n_sent, n_first);
            assert_memory_equal(fake.sent, first, n_first * sizeof first[0]);
        } else {
            assert_true(fake.n_sent != n_first || memcmp(fake.sent, first, n_first * sizeof first[0]) != 0);
        }
        teardown(NULL);
    }
}

/* ------------------------------------------------------------------ semantics */

#define N_CORRUPT 18000u /* ~17 hits per bit of the 8-byte frames */

static void test_corrupt_flips_exactly_one_data_bit(void **state)
{
    (void)state;
    wrap("corrupt=0.5,seed=11");
    for (uint32_t i = 0; i < N_CORRUPT; i++) {
        hal_can_frame_t f = frame_n(i);
        f.id = i; /* the id is never touched: it identifies the frame */
        f.len = (uint8_t)(i % 9u);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
    }
    assert_int_equal(fake.n_sent, N_CORRUPT);
    uint32_t flipped = 0;
    uint32_t bit_seen[64] = { 0 };
    for (uint32_t i = 0; i < N_CORRUPT; i++) {
        hal_can_frame_t want = frame_n(i);
        want.len = (uint8_t)(i % 9u);
        const hal_can_frame_t *got = &fake.sent[i];
        assert_int_equal(got->id, i);
        assert_int_equal(got->len, want.len);
        assert_int_equal(got->flags, want.flags);
        int bits = 0;
        for (int b = 0; b < 8; b++) {
            uint8_t x = (uint8_t)(got->data[b] ^ want.data[b]);
            if (b >= want.len) {
                assert_int_equal(x, 0); /* bytes beyond len are never touched */
            }
            for (int k = 0; k < 8; k++) {
                if (x & (1u << k)) {
                    bits++;
                    bit_seen[b * 8 + k]++;
                }
            }
        }
        assert_true(bits == 0 || bits == 1);
        flipped += (uint32_t)bits;
    }
    assert_int_equal(counters().tx.corrupted, flipped);
    for (int b = 0; b < 64; b++) {
        if (bit_seen[b] == 0) {
            fail_msg("bit %d of the data never flipped", b);
        }
    }
}

static void test_dup_delivers_the_copy_right_after_the_original(void **state)
{
    (void)state;
    wrap("dup=1,seed=2");
    hal_can_frame_t a = frame_n(1), b = frame_n(2), got;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    assert_int_equal(hal_can_send(&link_, &b), LS_OK);
    assert_int_equal(fake.n_sent, 4);
    assert_int_equal(frame_index(&fake.sent[0]), 1);
    assert_int_equal(frame_index(&fake.sent[1]), 1);
    assert_int_equal(frame_index(&fake.sent[2]), 2);
    assert_int_equal(frame_index(&fake.sent[3]), 2);
    fake_push_rx(&a);
    fake_push_rx(&b);
    uint32_t order[4];
    for (int i = 0; i < 4; i++) {
        assert_int_equal(hal_can_recv(&link_, &got), 1);
        order[i] = frame_index(&got);
    }
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(order[0], 1);
    assert_int_equal(order[1], 1);
    assert_int_equal(order[2], 2);
    assert_int_equal(order[3], 2);
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.tx.duplicated, 2);
    assert_int_equal(c.rx.duplicated, 2);
}

/* An event-driven caller sleeps until hal_can_next_due_us: held frames
 * must be due exactly when recv or send would pass them on. */
static void test_next_due_is_when_a_delayed_frame_passes(void **state)
{
    (void)state;
    wrap("delay=1:3ms,seed=3");
    assert_true(hal_can_next_due_us(&link_) == UINT64_MAX); /* nothing held */
    const uint64_t t0 = g_now_us;
    hal_can_frame_t a = frame_n(1), got;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    assert_int_equal(fake.n_sent, 0);
    assert_true(hal_can_next_due_us(&link_) == t0 + 3000u);
    g_now_us = t0 + 2999u;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 0);
    g_now_us = t0 + 3000u;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN); /* recv times TX releases too */
    assert_int_equal(fake.n_sent, 1);
    assert_true(hal_can_next_due_us(&link_) == UINT64_MAX);
    /* received frames the same way */
    fake_push_rx(&a);
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_true(hal_can_next_due_us(&link_) == t0 + 6000u);
    g_now_us = t0 + 6000u;
    assert_int_equal(hal_can_recv(&link_, &got), 1);
    assert_int_equal(frame_index(&got), 1);
    assert_true(hal_can_next_due_us(&link_) == UINT64_MAX);
}

static void test_reorder_releases_after_the_next_frame(void **state)
{
    (void)state;
    wrap("tx.reorder=0.2,rx.reorder=0.2,seed=21");
    for (uint32_t i = 0; i < N_RATE; i++) {
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
        fake_push_rx(&f);
    }
    /* the clock stands still: only following frames release held ones */
    static hal_can_frame_t rx[N_RATE];
    size_t n_rx = 0;
    while (n_rx < N_RATE && hal_can_recv(&link_, &rx[n_rx]) == 1) {
        n_rx++;
    }
    /* the frames held at the very end had no next frame: the cap releases
     * them, in order, after everything else (so they are not "late") */
    uint32_t tail[2] = { N_RATE - (uint32_t)fake.n_sent, N_RATE - (uint32_t)n_rx };
    assert_true(tail[0] < 10 && tail[1] < 10);
    g_now_us += HAL_SIM_FAULTY_REORDER_MAX_US;
    while (n_rx < N_RATE && hal_can_recv(&link_, &rx[n_rx]) == 1) {
        n_rx++;
    }
    hal_sim_fault_counters_t c = counters();
    assert_binomial(c.tx.reordered, N_RATE, 0.2);
    assert_binomial(c.rx.reordered, N_RATE, 0.2);
    const hal_can_frame_t *outs[2] = { fake.sent, rx };
    size_t n_out[2] = { fake.n_sent, n_rx };
    uint32_t reordered[2] = { c.tx.reordered, c.rx.reordered };
    for (int k = 0; k < 2; k++) {
        assert_int_equal(n_out[k], N_RATE); /* nothing lost, nothing added */
        static uint8_t seen[N_RATE];
        memset(seen, 0, sizeof seen);
        uint32_t late = 0, max_so_far = 0;
        bool prev_late = false;
        for (size_t j = 0; j < n_out[k]; j++) {
            uint32_t i = frame_index(&outs[k][j]);
            assert_true(i < N_RATE);
            assert_int_equal(seen[i], 0);
            seen[i] = 1;
            bool is_late = j > 0 && i < max_so_far; /* a later frame went before it */
            if (is_late) {
                late++;
                /* right behind the frame that released it, or behind another
                 * frame released with it */
                assert_true(frame_index(&outs[k][j - 1]) > i || prev_late);
            }
            prev_late = is_late;
            if (i > max_so_far) {
                max_so_far = i;
            }
        }
        assert_int_equal(late, reordered[k] - tail[k]);
    }
}

static void test_reorder_without_a_next_frame_is_released_after_the_cap(void **state)
{
    (void)state;
    wrap("reorder=1,seed=1");
    hal_can_frame_t a = frame_n(5), got;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    assert_int_equal(fake.n_sent, 0);
    g_now_us += HAL_SIM_FAULTY_REORDER_MAX_US - 1;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 0);
    g_now_us += 1;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN); /* recv calls time TX releases */
    assert_int_equal(fake.n_sent, 1);
    assert_int_equal(frame_index(&fake.sent[0]), 5);
}

static void test_delay_holds_for_the_configured_time(void **state)
{
    (void)state;
    wrap("delay=1:5ms,seed=1");
    hal_can_frame_t a = frame_n(1), b = frame_n(2), got;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    g_now_us += 1000;
    assert_int_equal(hal_can_send(&link_, &b), LS_OK); /* held until t0 + 6 ms */
    fake_push_rx(&a);
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN); /* rx a held until t0 + 6 ms */
    assert_int_equal(fake.n_sent, 0);
    g_now_us += 3999; /* t0 + 4.999 ms */
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 0);
    g_now_us += 1; /* t0 + 5 ms: a is due on TX */
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 1);
    assert_int_equal(frame_index(&fake.sent[0]), 1);
    g_now_us += 999;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 1);
    g_now_us += 1; /* t0 + 6 ms: b on TX, a on RX */
    assert_int_equal(hal_can_recv(&link_, &got), 1);
    assert_int_equal(frame_index(&got), 1);
    assert_int_equal(fake.n_sent, 2);
    assert_int_equal(frame_index(&fake.sent[1]), 2);
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.tx.delayed, 2);
    assert_int_equal(c.rx.delayed, 1);
}

static void test_delayed_frames_do_not_block_the_others(void **state)
{
    (void)state;
    wrap("delay=0.5:10ms,seed=4");
    for (uint32_t i = 0; i < 100; i++) {
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
        g_now_us += 1000; /* 1 ms apart: a delayed frame is overtaken by about 10 */
    }
    g_now_us += 10000;
    hal_can_frame_t got;
    (void)hal_can_recv(&link_, &got);
    assert_int_equal(fake.n_sent, 100);
    uint32_t delayed = counters().tx.delayed;
    assert_binomial(delayed, 100, 0.5);
    /* send time of frame i is i ms; a delayed one arrives at i + 10 ms, so
     * every frame in the output is preceded only by frames sent before its
     * arrival */
    static uint32_t out_at[100];
    for (uint32_t j = 0; j < 100; j++) {
        out_at[j] = frame_index(&fake.sent[j]);
    }
    uint32_t overtaken = 0;
    for (uint32_t j = 1; j < 100; j++) {
        if (out_at[j] < out_at[j - 1]) {
            overtaken++;
            assert_true(out_at[j - 1] - out_at[j] <= 10);
        }
    }
    assert_true(overtaken > 0);
}

static void test_hold_queue_overflow_passes_frames_unchanged(void **state)
{
    (void)state;
    wrap("tx.delay=1:1s,seed=1");
    for (uint32_t i = 0; i < HAL_SIM_FAULTY_HOLD + 5; i++) {
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
    }
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.tx.delayed, HAL_SIM_FAULTY_HOLD);
    assert_int_equal(c.tx.hold_overflow, 5);
    assert_int_equal(fake.n_sent, 5);
    assert_int_equal(frame_index(&fake.sent[0]), HAL_SIM_FAULTY_HOLD);
}

static void test_inner_send_error_is_returned_and_nothing_is_sent_twice(void **state)
{
    (void)state;
    wrap("dup=1,seed=1");
    hal_can_frame_t a = frame_n(1);
    fake.send_ret = LS_EAGAIN;
    assert_int_equal(hal_can_send(&link_, &a), LS_EAGAIN);
    fake.send_ret = LS_OK;
    hal_can_frame_t got;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 0); /* the failed frame was not kept for a duplicate */
    assert_int_equal(counters().tx.duplicated, 0);
}

static void test_busoff_windows(void **state)
{
    (void)state;
    wrap("busoff=1s+200ms,delay=1:300ms,seed=1");
    uint64_t t0 = g_now_us;
    hal_can_frame_t a = frame_n(1), got;
    hal_can_status_t st;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK); /* delayed to t0 + 300 ms */
    g_now_us = t0 + 999999;
    assert_int_equal(fake.n_sent, 0);
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 1);
    assert_int_equal(hal_can_send(&link_, &a), LS_OK); /* delayed to t0 + 1.3 s: lost in the window */
    assert_int_equal(hal_can_status(&link_, &st), LS_OK);
    assert_int_equal(st.state, HAL_CAN_STATE_ACTIVE);
    g_now_us = t0 + 1000000; /* the window opens */
    assert_int_equal(hal_can_status(&link_, &st), LS_OK);
    assert_int_equal(st.state, HAL_CAN_STATE_BUS_OFF);
    assert_int_equal(hal_can_send(&link_, &a), LS_EBUSOFF);
    fake_push_rx(&a);
    fake_push_rx(&a);
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.rx_head, fake.rx_tail); /* what arrived while off is gone */
    g_now_us = t0 + 1199999;
    assert_int_equal(hal_can_send(&link_, &a), LS_EBUSOFF);
    g_now_us = t0 + 1200000; /* back on */
    assert_int_equal(hal_can_status(&link_, &st), LS_OK);
    assert_int_equal(st.state, HAL_CAN_STATE_ACTIVE);
    g_now_us = t0 + 1600000;
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN);
    assert_int_equal(fake.n_sent, 1); /* the held frame was lost with the bus */
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.busoff_windows, 1);
    assert_int_equal(c.tx.busoff_lost, 3); /* two refused sends and one held frame */
    assert_int_equal(c.rx.busoff_lost, 2);
    g_now_us = t0 + 2000000; /* the next window */
    assert_int_equal(hal_can_send(&link_, &a), LS_EBUSOFF);
    g_now_us = t0 + 5100000;
    assert_int_equal(hal_can_send(&link_, &a), LS_EBUSOFF);
    assert_int_equal(counters().busoff_windows, 3); /* windows 2 and 5 seen; 3 and 4 passed unseen */
}

static void test_window_limits_frame_faults_in_time(void **state)
{
    (void)state;
    wrap("drop=1,window=1s+500ms,seed=1");
    uint64_t t0 = g_now_us;
    hal_can_frame_t a = frame_n(1), got;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    fake_push_rx(&a);
    assert_int_equal(hal_can_recv(&link_, &got), 1); /* before the window: clean */
    assert_int_equal(fake.n_sent, 1);
    g_now_us = t0 + 1000000;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    fake_push_rx(&a);
    assert_int_equal(hal_can_recv(&link_, &got), LS_EAGAIN); /* in it: everything dropped */
    g_now_us = t0 + 1499999;
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    assert_int_equal(fake.n_sent, 1);
    g_now_us = t0 + 1500000; /* after it: clean again */
    assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    fake_push_rx(&a);
    assert_int_equal(hal_can_recv(&link_, &got), 1);
    assert_int_equal(fake.n_sent, 2);
    hal_sim_fault_counters_t c = counters();
    assert_int_equal(c.tx.frames, 4);
    assert_int_equal(c.tx.dropped, 2);
    assert_int_equal(c.rx.frames, 3);
    assert_int_equal(c.rx.dropped, 1);
}

static void test_window_keeps_the_decision_stream(void **state)
{
    (void)state;
    /* the same seed with and without a window: frames inside the window meet
     * the same fate (each frame consumes its draws either way) */
    static uint32_t kept_always[2000];
    size_t n_always = 0;
    wrap("drop=0.3,seed=5");
    for (uint32_t i = 0; i < 2000; i++) {
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
    }
    for (size_t j = 0; j < fake.n_sent; j++) {
        kept_always[n_always++] = frame_index(&fake.sent[j]);
    }
    teardown(NULL);
    setup(NULL);
    wrap("drop=0.3,window=1ms+1000ms,seed=5");
    for (uint32_t i = 0; i < 2000; i++) {
        hal_can_frame_t f = frame_n(i);
        assert_int_equal(hal_can_send(&link_, &f), LS_OK);
        g_now_us += 1000; /* frame i at i ms: 1..1000 inside the window */
    }
    size_t j = 0, k = 0;
    for (uint32_t i = 0; i < 2000; i++) {
        bool in_window = i >= 1 && i <= 1000;
        bool kept_a = k < n_always && kept_always[k] == i;
        bool kept_w = j < fake.n_sent && frame_index(&fake.sent[j]) == i;
        k += kept_a ? 1u : 0u;
        j += kept_w ? 1u : 0u;
        if (in_window) {
            assert_int_equal(kept_a, kept_w);
        } else {
            assert_true(kept_w);
        }
    }
}

static void test_format_names_every_counter(void **state)
{
    (void)state;
    wrap("tx.drop=1,seed=1");
    hal_can_frame_t a = frame_n(1);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(hal_can_send(&link_, &a), LS_OK);
    }
    char buf[512];
    int n = hal_sim_faulty_format(&link_, buf, sizeof buf);
    assert_int_equal(n, (int)strlen(buf));
    assert_string_equal(buf, "tx frames=3 drop=3 dup=0 corrupt=0 reorder=0 delay=0 busoff_lost=0 hold_overflow=0 "
                             "rx frames=0 drop=0 dup=0 corrupt=0 reorder=0 delay=0 busoff_lost=0 hold_overflow=0 "
                             "busoff_windows=0");
    char small[10];
    assert_int_equal(hal_sim_faulty_format(&link_, small, sizeof small), 9);
    assert_string_equal(small, "tx frames");
}

/* ------------------------------------------------------------------ parser */

static void test_parse_full_spec(void **state)
{
    (void)state;
    hal_sim_fault_config_t c;
    char msg[256];
    assert_int_equal(hal_sim_fault_parse("drop=0.05,dup=0.01,corrupt=0.01,reorder=0.01,delay=0.02:5ms,"
                                         "busoff=30s+2s,seed=1",
                                         &c, msg, sizeof msg),
                     LS_OK);
    assert_string_equal(msg, "");
    const hal_sim_fault_rates_t *r[2] = { &c.tx, &c.rx };
    for (int k = 0; k < 2; k++) {
        assert_true(r[k]->drop == 0.05);
        assert_true(r[k]->dup == 0.01);
        assert_true(r[k]->corrupt == 0.01);
        assert_true(r[k]->reorder == 0.01);
        assert_true(r[k]->delay == 0.02);
        assert_int_equal(r[k]->delay_us, 5000);
    }
    assert_int_equal(c.busoff_every_us, 30000000u);
    assert_int_equal(c.busoff_for_us, 2000000u);
    assert_int_equal(c.seed, 1);
    assert_null(c.clock.now_us);
}

static void test_parse_units_percentages_and_directions(void **state)
{
    (void)state;
    hal_sim_fault_config_t c;
    char msg[256];
    assert_int_equal(
        hal_sim_fault_parse("drop=5%,rx.drop=20%,tx.delay=1:250us,rx.delay=0.5:1.5s,seed=0xFFFFFFFFFFFFFFFF", &c, msg,
                            sizeof msg),
        LS_OK);
    assert_true(c.tx.drop == 0.05);
    assert_true(c.rx.drop == 0.2);
    assert_true(c.tx.delay == 1.0);
    assert_int_equal(c.tx.delay_us, 250);
    assert_true(c.rx.delay == 0.5);
    assert_int_equal(c.rx.delay_us, 1500000);
    assert_true(c.seed == UINT64_MAX);
    assert_int_equal(hal_sim_fault_parse("busoff=500ms+1ms", &c, msg, sizeof msg), LS_OK);
    assert_int_equal(c.busoff_every_us, 500000);
    assert_int_equal(c.busoff_for_us, 1000);
    assert_true(c.tx.drop == 0.0);
    assert_int_equal(hal_sim_fault_parse("window=2s+30s", &c, msg, sizeof msg), LS_OK);
    assert_int_equal(c.window_after_us, 2000000);
    assert_int_equal(c.window_for_us, 30000000);
    assert_int_equal(hal_sim_fault_parse("window=0+1s", &c, msg, sizeof msg), LS_OK);
    assert_int_equal(c.window_after_us, 0);
    assert_int_equal(c.window_for_us, 1000000);
    assert_int_equal(hal_sim_fault_parse("seed=18446744073709551615", &c, msg, sizeof msg), LS_OK);
    assert_true(c.seed == UINT64_MAX);
}

static void test_parse_errors_say_what_is_wrong(void **state)
{
    (void)state;
    static const struct {
        const char *spec, *expect;
    } cases[] = {
        { "", "empty spec" },
        { "drop", "'drop': expected KEY=VALUE" },
        { "drop=0.05,", "item 2 is empty" },
        { ",drop=0.05", "item 1 is empty" },
        { "drop=0.05,,dup=0.1", "item 2 is empty" },
        { "lose=0.1", "unknown key 'lose'" },
        { "tx.lose=0.1", "unknown key 'tx.lose'" },
        { "drop=1.5", "drop '1.5': expected a probability 0..1 or a percentage" },
        { "drop=150%", "drop '150%'" },
        { "drop=-0.1", "drop '-0.1'" },
        { "drop=nan", "drop 'nan'" },
        { "drop=inf", "drop 'inf'" },
        { "drop= 0.1", "drop ' 0.1'" },
        { "drop=0.1x", "drop '0.1x'" },
        { "drop=", "drop ''" },
        { "rx.dup=abc", "rx.dup 'abc'" },
        { "delay=0.1", "delay: expected RATE:TIME" },
        { "delay=0.1:5", "delay: expected RATE:TIME" },
        { "delay=0.1:5h", "delay: expected RATE:TIME" },
        { "delay=0.1:0ms", "delay: expected RATE:TIME" },
        { "delay=0.1:61s", "delay: expected RATE:TIME" },
        { "tx.delay=2:5ms", "tx.delay: expected RATE:TIME" },
        { "busoff=30s", "busoff: expected EVERY+FOR" },
        { "busoff=30+2", "busoff: expected EVERY+FOR" },
        { "busoff=2s+2s", "FOR must be shorter than EVERY (got 2s+2s)" },
        { "busoff=1s+5s", "FOR must be shorter than EVERY" },
        { "rx.busoff=30s+2s", "busoff applies to the whole link: drop the 'rx.' prefix" },
        { "tx.seed=1", "seed applies to the whole link" },
        { "window=2s", "window: expected AFTER+FOR" },
        { "window=2s+0s", "window: expected AFTER+FOR" },
        { "window=x+1s", "window: expected AFTER+FOR" },
        { "rx.window=0+1s", "window applies to the whole link" },
        { "seed=-1", "seed '-1': expected an unsigned 64-bit integer" },
        { "seed=18446744073709551616", "seed '18446744073709551616'" },
        { "seed=0x", "seed '0x'" },
        { "seed=12ab", "seed '12ab'" },
        { "drop=0.1,drop=0.2", "'drop' given twice" },
        { "rx.drop=0.1,rx.drop=0.2", "'rx.drop' given twice" },
        { "rx.drop=0.1,drop=0.2", "bare 'drop' after a tx./rx. 'drop' would override it" },
        { "seed=1,seed=2", "'seed' given twice" },
        { "drop=0.000000000000000000000000000000000000000000000000000000000001",
          "item 1 is longer than 63 characters" },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        hal_sim_fault_config_t c;
        char msg[256] = "x";
        int r = hal_sim_fault_parse(cases[i].spec, &c, msg, sizeof msg);
        if (r != LS_EINVAL || strstr(msg, cases[i].expect) == NULL || msg[0] == '\0') {
            fail_msg("'%s': r=%d msg='%s', expected '%s'", cases[i].spec, r, msg, cases[i].expect);
        }
    }
    hal_sim_fault_config_t c;
    assert_int_equal(hal_sim_fault_parse(NULL, &c, NULL, 0), LS_EINVAL);
    assert_int_equal(hal_sim_fault_parse("drop=0.1", NULL, NULL, 0), LS_EINVAL);
    char tiny[8];
    assert_int_equal(hal_sim_fault_parse("lose=1", &c, tiny, sizeof tiny), LS_EINVAL);
    assert_string_equal(tiny, "unknown"); /* truncated, terminated */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_wrap_rejects_bad_arguments, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pool_is_static_and_slots_come_back_on_close, setup, teardown),
        cmocka_unit_test_setup_teardown(test_no_faults_pass_everything_in_order, setup, teardown),
        cmocka_unit_test_setup_teardown(test_drop_rate_both_ways_is_exact_for_a_seed, setup, teardown),
        cmocka_unit_test(test_each_fault_rate_within_binomial_bounds),
        cmocka_unit_test(test_same_seed_same_faults_other_seed_other_faults),
        cmocka_unit_test_setup_teardown(test_corrupt_flips_exactly_one_data_bit, setup, teardown),
        cmocka_unit_test_setup_teardown(test_dup_delivers_the_copy_right_after_the_original, setup, teardown),
        cmocka_unit_test_setup_teardown(test_reorder_releases_after_the_next_frame, setup, teardown),
        cmocka_unit_test_setup_teardown(test_reorder_without_a_next_frame_is_released_after_the_cap, setup, teardown),
        cmocka_unit_test_setup_teardown(test_delay_holds_for_the_configured_time, setup, teardown),
        cmocka_unit_test_setup_teardown(test_delayed_frames_do_not_block_the_others, setup, teardown),
        cmocka_unit_test_setup_teardown(test_hold_queue_overflow_passes_frames_unchanged, setup, teardown),
        cmocka_unit_test_setup_teardown(test_inner_send_error_is_returned_and_nothing_is_sent_twice, setup, teardown),
        cmocka_unit_test_setup_teardown(test_busoff_windows, setup, teardown),
        cmocka_unit_test_setup_teardown(test_window_limits_frame_faults_in_time, setup, teardown),
        cmocka_unit_test_setup_teardown(test_window_keeps_the_decision_stream, setup, teardown),
        cmocka_unit_test_setup_teardown(test_format_names_every_counter, setup, teardown),
        cmocka_unit_test_setup_teardown(test_next_due_is_when_a_delayed_frame_passes, setup, teardown),
        cmocka_unit_test(test_parse_full_spec),
        cmocka_unit_test(test_parse_units_percentages_and_directions),
        cmocka_unit_test(test_parse_errors_say_what_is_wrong),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
