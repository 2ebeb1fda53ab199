/* Fault-injecting CAN link decorator; see faulty_link.h for the contract. */
#include "faulty_link.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    hal_can_frame_t frame;
    uint64_t release_us; /* due when now >= release_us; 0 = due at the next call */
    bool awaits_next;    /* held for reordering: due as soon as the next frame passed */
} hold_t;

typedef struct {
    uint64_t rng;
    uint64_t th_drop, th_dup, th_corrupt, th_reorder, th_delay; /* p * 2^32 */
    uint32_t delay_us;
    hold_t hold[HAL_SIM_FAULTY_HOLD];
    size_t n_hold;
    hal_sim_fault_dir_counters_t cnt;
} dir_t;

typedef struct {
    bool used;
    hal_can_link_t inner;
    hal_clock_t clock;
    uint64_t start_us;
    uint64_t busoff_every_us, busoff_for_us;
    uint64_t window_after_us, window_for_us;
    uint64_t last_window; /* index of the last window counted */
    uint32_t busoff_windows;
    dir_t tx, rx;
} faulty_t;

static faulty_t g_pool[HAL_SIM_FAULTY_MAX_LINKS];

/* splitmix64: tiny, good enough for fault decisions, and trivially
 * reproducible from one seed. */
static uint32_t draw(dir_t *d)
{
    d->rng += 0x9E3779B97F4A7C15ull;
    uint64_t z = d->rng;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (uint32_t)(z >> 32);
}

/* p * 2^32: a draw below it happens with probability p (p = 1 always). */
static uint64_t threshold(double p)
{
    return (uint64_t)(p * 4294967296.0);
}

static uint64_t now_of(const faulty_t *f)
{
    return f->clock.now_us != NULL ? f->clock.now_us(f->clock.self) : 0u;
}

static bool busoff_now(faulty_t *f, uint64_t now)
{
    if (f->busoff_every_us == 0 || now < f->start_us) {
        return false;
    }
    uint64_t elapsed = now - f->start_us;
    uint64_t k = elapsed / f->busoff_every_us;
    if (k == 0 || elapsed % f->busoff_every_us >= f->busoff_for_us) {
        return false;
    }
    if (k != f->last_window) {
        f->last_window = k;
        f->busoff_windows++;
    }
    return true;
}

static bool hold_push(dir_t *d, const hal_can_frame_t *frame, uint64_t release_us, bool awaits_next)
{
    if (d->n_hold >= HAL_SIM_FAULTY_HOLD) {
        d->cnt.hold_overflow++;
        return false;
    }
    d->hold[d->n_hold] = (hold_t){ .frame = *frame, .release_us = release_us, .awaits_next = awaits_next };
    d->n_hold++;
    return true;
}

static void hold_remove(dir_t *d, size_t i)
{
    memmove(&d->hold[i], &d->hold[i + 1], (d->n_hold - i - 1) * sizeof d->hold[0]);
    d->n_hold--;
}

#define NO_HOLD (-1) /* hold_due: nothing is due */

/* The first due entry in arrival order, or NO_HOLD. */
static int hold_due(const dir_t *d, uint64_t now)
{
    for (size_t i = 0; i < d->n_hold; i++) {
        if (now >= d->hold[i].release_us) {
            return (int)i;
        }
    }
    return NO_HOLD;
}

/* A frame has passed: frames held for reordering are due right after it. */
static void release_reordered(dir_t *d)
{
    for (size_t i = 0; i < d->n_hold; i++) {
        if (d->hold[i].awaits_next) {
            d->hold[i].awaits_next = false;
            d->hold[i].release_us = 0;
        }
    }
}

static void hold_flush_lost(dir_t *d)
{
    d->cnt.busoff_lost += (uint32_t)d->n_hold;
    d->n_hold = 0;
}

/* Send every due held TX frame; a full inner queue keeps the rest for later. */
static void pump_tx(faulty_t *f, uint64_t now)
{
    int i;
    while ((i = hold_due(&f->tx, now)) >= 0) {
        if (hal_can_send(&f->inner, &f->tx.hold[i].frame) < 0) {
            return;
        }
        hold_remove(&f->tx, (size_t)i);
    }
}

typedef struct {
    bool drop, delay, reorder, corrupt, dup;
    uint32_t bit;
} verdict_t;

/* Every frame consumes exactly six draws, so one fault decision never shifts
 * the decisions for the frames after it. */
static verdict_t judge(const faulty_t *f, dir_t *d, uint64_t now)
{
    verdict_t v;
    d->cnt.frames++;
    v.drop = draw(d) < d->th_drop;
    v.delay = draw(d) < d->th_delay;
    v.reorder = draw(d) < d->th_reorder;
    v.corrupt = draw(d) < d->th_corrupt;
    v.dup = draw(d) < d->th_dup;
    v.bit = draw(d);
    if (f->window_for_us > 0) {
        uint64_t t = now - f->start_us;
        if (now < f->start_us || t < f->window_after_us || t - f->window_after_us >= f->window_for_us) {
            v.drop = v.delay = v.reorder = v.corrupt = v.dup = false;
        }
    }
    return v;
}

/* Apply drop, corrupt and the holds to `fr`. Returns true when the frame goes
 * on now (false: dropped or held). */
static bool apply(dir_t *d, const verdict_t *v, hal_can_frame_t *fr, uint64_t now)
{
    if (v->drop) {
        d->cnt.dropped++;
        return false;
    }
    if (v->corrupt && fr->len > 0) {
        uint32_t b = v->bit % ((uint32_t)fr->len * 8u);
        fr->data[b / 8u] = (uint8_t)(fr->data[b / 8u] ^ (1u << (b % 8u)));
        d->cnt.corrupted++;
    }
    if (v->delay) {
        if (hold_push(d, fr, now + d->delay_us, false)) {
            d->cnt.delayed++;
            return false;
        }
    } else if (v->reorder) {
        if (hold_push(d, fr, now + HAL_SIM_FAULTY_REORDER_MAX_US, true)) {
            d->cnt.reordered++;
            return false;
        }
    }
    return true;
}

/* After a frame went on: reordered frames follow it, then its duplicate. */
static void after_pass(dir_t *d, const verdict_t *v, const hal_can_frame_t *fr)
{
    release_reordered(d);
    if (v->dup && hold_push(d, fr, 0, false)) {
        d->cnt.duplicated++;
    }
}

static int f_send(void *self, const hal_can_frame_t *frame)
{
    faulty_t *f = self;
    uint64_t now = now_of(f);
    if (busoff_now(f, now)) {
        hold_flush_lost(&f->tx);
        f->tx.cnt.frames++;
        f->tx.cnt.busoff_lost++;
        return LS_EBUSOFF;
    }
    pump_tx(f, now);
    verdict_t v = judge(f, &f->tx, now);
    hal_can_frame_t fr = *frame;
    if (!apply(&f->tx, &v, &fr, now)) {
        return LS_OK; /* lost or held on the wire: the sender cannot tell */
    }
    int r = hal_can_send(&f->inner, &fr);
    if (r < 0) {
        return r; /* the caller keeps the frame and retries: nothing happened */
    }
    after_pass(&f->tx, &v, &fr);
    pump_tx(f, now);
    return r;
}

static int f_recv(void *self, hal_can_frame_t *out)
{
    faulty_t *f = self;
    uint64_t now = now_of(f);
    if (busoff_now(f, now)) {
        hold_flush_lost(&f->tx);
        hold_flush_lost(&f->rx);
        hal_can_frame_t junk;
        for (int k = 0; k < 256 && hal_can_recv(&f->inner, &junk) == 1; k++) {
            f->rx.cnt.frames++;
            f->rx.cnt.busoff_lost++;
        }
        return LS_EAGAIN;
    }
    pump_tx(f, now); /* recv is called every loop turn: it times TX releases too */
    int i = hold_due(&f->rx, now);
    if (i >= 0) {
        *out = f->rx.hold[i].frame;
        hold_remove(&f->rx, (size_t)i);
        return 1;
    }
    /* Bounded: a flood of dropped frames must not keep the caller here. */
    for (int k = 0; k < 256; k++) {
        hal_can_frame_t fr;
        int r = hal_can_recv(&f->inner, &fr);
        if (r != 1) {
            return r;
        }
        verdict_t v = judge(f, &f->rx, now);
        if (!apply(&f->rx, &v, &fr, now)) {
            continue;
        }
        after_pass(&f->rx, &v, &fr);
        *out = fr;
        return 1;
    }
    return LS_EAGAIN;
}

static int f_poll_fd(void *self)
{
    faulty_t *f = self;
    return hal_can_poll_fd(&f->inner);
}

static int f_status(void *self, hal_can_status_t *out)
{
    faulty_t *f = self;
    int r = hal_can_status(&f->inner, out);
    if (r >= 0 && busoff_now(f, now_of(f))) {
        out->state = HAL_CAN_STATE_BUS_OFF;
    }
    return r;
}

static void f_close(void *self)
{
    faulty_t *f = self;
    if (!f->used) {
        return;
    }
    hal_can_close(&f->inner);
    memset(f, 0, sizeof *f);
}

static int f_hold_open(void *self, bool hold)
{
    faulty_t *f = self;
    return hal_can_hold_open(&f->inner, hold);
}

static bool f_tx_pending(void *self)
{
    faulty_t *f = self;
    return hal_can_tx_pending(&f->inner);
}

/* Held frames are due at their release time (one held for reordering at
 * the latest then, sooner when the next frame passes: after a recv or send). */
static uint64_t hold_next_due(const dir_t *d, uint64_t t)
{
    for (size_t i = 0; i < d->n_hold; i++) {
        t = d->hold[i].release_us < t ? d->hold[i].release_us : t;
    }
    return t;
}

static uint64_t f_next_due_us(void *self)
{
    faulty_t *f = self;
    uint64_t t = hold_next_due(&f->rx, hal_can_next_due_us(&f->inner));
    /* While the inner link waits for room (the caller polls it writable),
     * due TX holds wait with it: they would only be refused again. */
    return hal_can_tx_pending(&f->inner) ? t : hold_next_due(&f->tx, t);
}

static const hal_can_ops_t g_ops = {
    .send = f_send,
    .recv = f_recv,
    .poll_fd = f_poll_fd,
    .status = f_status,
    .close = f_close,
    .hold_open = f_hold_open,
    .tx_pending = f_tx_pending,
    .next_due_us = f_next_due_us,
};

static bool rate_ok(double p)
{
    return p >= 0.0 && p <= 1.0;
} /* false for NaN too */

static bool rates_ok(const hal_sim_fault_rates_t *r)
{
    return rate_ok(r->drop) && rate_ok(r->dup) && rate_ok(r->corrupt) && rate_ok(r->reorder) && rate_ok(r->delay) &&
           (r->delay == 0.0 || r->delay_us > 0);
}

static void dir_init(dir_t *d, const hal_sim_fault_rates_t *r, uint64_t seed)
{
    memset(d, 0, sizeof *d);
    d->rng = seed;
    d->th_drop = threshold(r->drop);
    d->th_dup = threshold(r->dup);
    d->th_corrupt = threshold(r->corrupt);
    d->th_reorder = threshold(r->reorder);
    d->th_delay = threshold(r->delay);
    d->delay_us = r->delay_us;
}

int hal_sim_faulty_wrap(hal_can_link_t *out, const hal_can_link_t *inner, const hal_sim_fault_config_t *cfg)
{
    if (out == NULL || inner == NULL || inner->ops == NULL || cfg == NULL || !rates_ok(&cfg->tx) ||
        !rates_ok(&cfg->rx)) {
        return LS_EINVAL;
    }
    bool busoff = cfg->busoff_every_us > 0 || cfg->busoff_for_us > 0;
    if (busoff && (cfg->busoff_for_us == 0 || cfg->busoff_for_us >= cfg->busoff_every_us)) {
        return LS_EINVAL;
    }
    if (cfg->window_after_us > 0 && cfg->window_for_us == 0) {
        return LS_EINVAL;
    }
    bool timed = busoff || cfg->window_for_us > 0 || cfg->tx.delay > 0.0 || cfg->rx.delay > 0.0 ||
                 cfg->tx.reorder > 0.0 || cfg->rx.reorder > 0.0;
    if (timed && cfg->clock.now_us == NULL) {
        return LS_EINVAL;
    }
    faulty_t *f = NULL;
    for (size_t i = 0; i < HAL_SIM_FAULTY_MAX_LINKS; i++) {
        if (!g_pool[i].used) {
            f = &g_pool[i];
            break;
        }
    }
    if (f == NULL) {
        return LS_EAGAIN;
    }
    memset(f, 0, sizeof *f);
    f->used = true;
    f->inner = *inner;
    f->clock = cfg->clock;
    f->busoff_every_us = cfg->busoff_every_us;
    f->busoff_for_us = cfg->busoff_for_us;
    f->window_after_us = cfg->window_after_us;
    f->window_for_us = cfg->window_for_us;
    /* Two streams, so the faults of one direction do not depend on the
     * traffic of the other. */
    dir_init(&f->tx, &cfg->tx, cfg->seed);
    dir_init(&f->rx, &cfg->rx, cfg->seed ^ 0xD1B54A32D192ED03ull);
    f->start_us = now_of(f);
    out->ops = &g_ops;
    out->self = f;
    snprintf(out->name, sizeof out->name, "faulty:%.120s", inner->name);
    return LS_OK;
}

static faulty_t *live(const hal_can_link_t *link)
{
    if (link == NULL || link->ops != &g_ops) {
        return NULL;
    }
    faulty_t *f = link->self;
    return f != NULL && f->used ? f : NULL;
}

int hal_sim_faulty_counters(const hal_can_link_t *link, hal_sim_fault_counters_t *out)
{
    faulty_t *f = live(link);
    if (f == NULL || out == NULL) {
        return LS_EINVAL;
    }
    out->tx = f->tx.cnt;
    out->rx = f->rx.cnt;
    out->busoff_windows = f->busoff_windows;
    return LS_OK;
}

int hal_sim_faulty_format(const hal_can_link_t *link, char *buf, size_t buflen)
{
    hal_sim_fault_counters_t c;
    if (hal_sim_faulty_counters(link, &c) != LS_OK || buf == NULL || buflen == 0) {
        return LS_EINVAL;
    }
    const hal_sim_fault_dir_counters_t *d[2] = { &c.tx, &c.rx };
    static const char *names[2] = { "tx", "rx" };
    size_t n = 0;
    for (int i = 0; i < 2; i++) {
        int w = snprintf(buf + n, buflen - n,
                         "%s%s frames=%u drop=%u dup=%u corrupt=%u reorder=%u delay=%u busoff_lost=%u "
                         "hold_overflow=%u",
                         i > 0 ? " " : "", names[i], d[i]->frames, d[i]->dropped, d[i]->duplicated, d[i]->corrupted,
                         d[i]->reordered, d[i]->delayed, d[i]->busoff_lost, d[i]->hold_overflow);
        if (w < 0) {
            return LS_EINVAL;
        }
        n += (size_t)w;
        if (n >= buflen) {
            return (int)(buflen - 1);
        }
    }
    int w = snprintf(buf + n, buflen - n, " busoff_windows=%u", c.busoff_windows);
    if (w < 0) {
        return LS_EINVAL;
    }
    n += (size_t)w;
    return (int)(n >= buflen ? buflen - 1 : n);
}

/* ------------------------------------------------------------------ spec parser */

enum { K_DROP, K_DUP, K_CORRUPT, K_REORDER, K_DELAY, K_BUSOFF, K_WINDOW, K_SEED, K_COUNT };
static const char *const g_keys[K_COUNT] = { "drop", "dup", "corrupt", "reorder", "delay", "busoff", "window", "seed" };

static int fail(char *msg, size_t msglen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail(char *msg, size_t msglen, const char *fmt, ...)
{
    if (msg != NULL && msglen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msglen, fmt, ap);
        va_end(ap);
    }
    return LS_EINVAL;
}

/* A plain decimal number at the start of s (no sign, no spaces, no inf/nan:
 * strtod would take those). */
static bool number(const char *s, double *out, const char **end)
{
    if (!((*s >= '0' && *s <= '9') || *s == '.')) {
        return false;
    }
    char *e = NULL;
    errno = 0;
    double v = strtod(s, &e);
    if (e == s || errno != 0 || !isfinite(v)) {
        return false;
    }
    *out = v;
    *end = e;
    return true;
}

static bool parse_rate(const char *s, double *out)
{
    const char *e;
    double v;
    if (!number(s, &v, &e)) {
        return false;
    }
    if (*e == '%') {
        v /= 100.0;
        e++;
    }
    if (*e != '\0' || v < 0.0 || v > 1.0) {
        return false;
    }
    *out = v;
    return true;
}

/* "5ms", "2s", "250us" -> microseconds, 1 us .. max_us. */
static bool parse_time(const char *s, uint64_t max_us, uint64_t *out)
{
    const char *e;
    double v;
    if (!number(s, &v, &e)) {
        return false;
    }
    double scale;
    if (strcmp(e, "us") == 0) {
        scale = 1.0;
    } else if (strcmp(e, "ms") == 0) {
        scale = 1e3;
    } else if (strcmp(e, "s") == 0) {
        scale = 1e6;
    } else {
        return false;
    }
    double us = v * scale;
    if (us < 1.0 || us > (double)max_us) {
        return false;
    }
    *out = (uint64_t)(us + 0.5);
    return true;
}

static bool parse_seed(const char *s, uint64_t *out)
{
    int base = 10;
    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16;
        s += 2;
    }
    bool digit = (*s >= '0' && *s <= '9') || (base == 16 && ((*s >= 'a' && *s <= 'f') || (*s >= 'A' && *s <= 'F')));
    if (!digit) {
        return false;
    }
    char *e = NULL;
    errno = 0;
    unsigned long long v = strtoull(s, &e, base);
    if (errno != 0 || *e != '\0') {
        return false;
    }
    *out = (uint64_t)v;
    return true;
}

#define LS_FAULT_MAX_DELAY_US 60000000ull     /* 60 s */
#define LS_FAULT_MAX_BUSOFF_US 86400000000ull /* one day */

static void set_rate(hal_sim_fault_config_t *cfg, int key, int dir, double p, uint32_t delay_us)
{
    hal_sim_fault_rates_t *r[2] = { &cfg->tx, &cfg->rx };
    for (int i = 0; i < 2; i++) {
        if (dir != 0 && dir != i + 1) {
            continue;
        }
        switch (key) {
        case K_DROP: r[i]->drop = p; break;
        case K_DUP: r[i]->dup = p; break;
        case K_CORRUPT: r[i]->corrupt = p; break;
        case K_REORDER: r[i]->reorder = p; break;
        default:
            r[i]->delay = p;
            r[i]->delay_us = delay_us;
            break;
        }
    }
}

int hal_sim_fault_parse(const char *spec, hal_sim_fault_config_t *cfg, char *msg, size_t msglen)
{
    static const char *const dirs[3] = { "", "tx.", "rx." };
    if (msg != NULL && msglen > 0) {
        msg[0] = '\0';
    }
    if (spec == NULL || cfg == NULL) {
        return fail(msg, msglen, "no spec given");
    }
    memset(cfg, 0, sizeof *cfg);
    if (spec[0] == '\0') {
        return fail(msg, msglen, "empty spec: expected KEY=VALUE[,KEY=VALUE...], e.g. drop=0.05,seed=1");
    }
    unsigned seen[K_COUNT] = { 0 }; /* bit d: given with direction d (0 both, 1 tx, 2 rx) */
    const char *p = spec;
    for (int item = 1;; item++) {
        const char *comma = strchr(p, ',');
        size_t len = comma != NULL ? (size_t)(comma - p) : strlen(p);
        char tok[64];
        if (len == 0) {
            return fail(msg, msglen, "item %d is empty (two commas, or a comma at either end)", item);
        }
        if (len >= sizeof tok) {
            return fail(msg, msglen, "item %d is longer than %zu characters", item, sizeof tok - 1);
        }
        memcpy(tok, p, len);
        tok[len] = '\0';
        char *eq = strchr(tok, '=');
        if (eq == NULL) {
            return fail(msg, msglen, "'%s': expected KEY=VALUE", tok);
        }
        *eq = '\0';
        const char *name = tok;
        const char *val = eq + 1;
        int dir = 0;
        if (strncmp(name, "tx.", 3) == 0) {
            dir = 1;
            name += 3;
        } else if (strncmp(name, "rx.", 3) == 0) {
            dir = 2;
            name += 3;
        }
        int key = -1;
        for (int k = 0; k < K_COUNT; k++) {
            if (strcmp(name, g_keys[k]) == 0) {
                key = k;
            }
        }
        if (key < 0) {
            return fail(msg, msglen,
                        "unknown key '%s%s': expected drop, dup, corrupt, reorder, delay (each "
                        "optionally with a tx. or rx. prefix), busoff, window or seed",
                        dirs[dir], name);
        }
        if ((key == K_BUSOFF || key == K_WINDOW || key == K_SEED) && dir != 0) {
            return fail(msg, msglen, "%s applies to the whole link: drop the '%s' prefix", name, dirs[dir]);
        }
        if (seen[key] & (1u << dir)) {
            return fail(msg, msglen, "'%s%s' given twice", dirs[dir], name);
        }
        if (dir == 0 && (seen[key] & 6u) != 0) {
            return fail(msg, msglen, "bare '%s' after a tx./rx. '%s' would override it: give the bare key first", name,
                        name);
        }
        seen[key] |= 1u << dir;
        switch (key) {
        case K_BUSOFF: {
            char *plus = strchr(val, '+');
            uint64_t every = 0, dur = 0;
            if (plus != NULL) {
                *plus = '\0';
            }
            if (plus == NULL || !parse_time(val, LS_FAULT_MAX_BUSOFF_US, &every) ||
                !parse_time(plus + 1, LS_FAULT_MAX_BUSOFF_US, &dur)) {
                return fail(msg, msglen,
                            "busoff: expected EVERY+FOR with units, e.g. busoff=30s+2s (off for 2 s "
                            "every 30 s)");
            }
            if (dur >= every) {
                return fail(msg, msglen, "busoff: FOR must be shorter than EVERY (got %s+%s)", val, plus + 1);
            }
            cfg->busoff_every_us = every;
            cfg->busoff_for_us = dur;
            break;
        }
        case K_WINDOW: {
            char *plus = strchr(val, '+');
            uint64_t after = 0, dur = 0;
            if (plus != NULL) {
                *plus = '\0';
            }
            /* AFTER may be 0 ("0s"): parse it with a floor of 0 by hand */
            bool after_ok = plus != NULL && (strcmp(val, "0") == 0 || strcmp(val, "0s") == 0 ||
                                             parse_time(val, LS_FAULT_MAX_BUSOFF_US, &after));
            if (!after_ok || !parse_time(plus + 1, LS_FAULT_MAX_BUSOFF_US, &dur)) {
                return fail(msg, msglen,
                            "window: expected AFTER+FOR with units, e.g. window=2s+30s (faults from 2 s after start "
                            "for 30 s)");
            }
            cfg->window_after_us = after;
            cfg->window_for_us = dur;
            break;
        }
        case K_SEED:
            if (!parse_seed(val, &cfg->seed)) {
                return fail(msg, msglen, "seed '%s': expected an unsigned 64-bit integer (e.g. 1 or 0x2A)", val);
            }
            break;
        case K_DELAY: {
            char *colon = strchr(val, ':');
            double rate = 0.0;
            uint64_t us = 0;
            if (colon != NULL) {
                *colon = '\0';
            }
            if (colon == NULL || !parse_rate(val, &rate) || !parse_time(colon + 1, LS_FAULT_MAX_DELAY_US, &us)) {
                return fail(msg, msglen,
                            "%sdelay: expected RATE:TIME, RATE 0..1 or a percentage, TIME 1us..60s, "
                            "e.g. delay=0.02:5ms",
                            dirs[dir]);
            }
            set_rate(cfg, key, dir, rate, (uint32_t)us);
            break;
        }
        default: {
            double rate = 0.0;
            if (!parse_rate(val, &rate)) {
                return fail(msg, msglen, "%s%s '%s': expected a probability 0..1 or a percentage, e.g. 0.05 or 5%%",
                            dirs[dir], name, val);
            }
            set_rate(cfg, key, dir, rate, 0);
            break;
        }
        }
        if (comma == NULL) {
            break;
        }
        p = comma + 1;
    }
    return LS_OK;
}
