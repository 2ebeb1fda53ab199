/* The drive bus's budget per cycle. Contracts and the frame arithmetic in
 * ls_drive_budget.h. */
#include "ls_drive_budget.h"

#include <math.h>
#include <stdarg.h>

#include "ls_fmt.h"

/* Bits of a classic frame with an 11-bit identifier, from SOF to the end of
 * the intermission, before stuffing: SOF 1, identifier 11, RTR 1, IDE 1,
 * r0 1, DLC 4, data 8n, CRC 15, CRC delimiter 1, ACK 2, EOF 7,
 * intermission 3. */
#define FRAME_BITS_FIXED 47u
/* The stuffed span, SOF to the CRC sequence: 1 + 11 + 1 + 1 + 1 + 4 + 8n + 15. */
#define STUFFED_SPAN_FIXED 34u
#define HEARTBEAT_BYTES 1u /* one NMT state byte */
#define SDO_FRAME_BYTES 8u /* an SDO request or answer is always 8 bytes */
/* A load this close to the ceiling counts as on it (rounding of the
 * amortised heartbeats, not of the configuration). */
#define LOAD_EPS 1e-9

unsigned ls_drive_budget_frame_bits(unsigned data_bytes)
{
    if (data_bytes > LS_DRIVE_BUDGET_MAX_DATA) {
        return 0u;
    }
    const unsigned stuffed = STUFFED_SPAN_FIXED + 8u * data_bytes;
    return FRAME_BITS_FIXED + 8u * data_bytes + (stuffed - 1u) / 4u;
}

/* Frames and bits every cycle, whatever its length. */
static void fixed_per_cycle(const ls_drive_budget_in_t *in, double *frames, double *bits)
{
    double f = 1.0;
    double b = ls_drive_budget_frame_bits(in->sync_bytes);
    for (size_t i = 0; i < in->n_axes; i++) {
        const ls_drive_budget_axis_t *a = &in->axes[i];
        for (unsigned k = 0; k < a->n_rpdo; k++) {
            f += 1.0;
            b += ls_drive_budget_frame_bits(a->rpdo_bytes[k]);
        }
        for (unsigned k = 0; k < a->n_tpdo; k++) {
            f += 1.0;
            b += ls_drive_budget_frame_bits(a->tpdo_bytes[k]);
        }
    }
    f += 2.0 * in->sdo_per_cycle;
    b += 2.0 * in->sdo_per_cycle * ls_drive_budget_frame_bits(SDO_FRAME_BYTES);
    *frames = f;
    *bits = b;
}

/* Heartbeat frames per microsecond: each producer's one frame per period. */
static double heartbeats_per_us(const ls_drive_budget_in_t *in)
{
    double r = 0.0;
    for (size_t i = 0; i < in->n_axes; i++) {
        if (in->axes[i].heartbeat_ms > 0u) {
            r += 1.0 / (1000.0 * in->axes[i].heartbeat_ms);
        }
    }
    if (in->master_heartbeat_ms > 0u) {
        r += 1.0 / (1000.0 * in->master_heartbeat_ms);
    }
    return r;
}

static double load_pct(double bits, double cycle_us, uint32_t bitrate)
{
    return 100.0 * bits / ((double)bitrate * cycle_us * 1e-6);
}

static bool fits(double load, double ceiling)
{
    return load <= ceiling * (1.0 + LOAD_EPS);
}

static bool valid(const ls_drive_budget_in_t *in)
{
    if (in->control_period_us == 0u || in->cycle_us == 0u || in->bitrate == 0u ||
        in->cycle_us % in->control_period_us != 0u || in->sync_bytes > 1u || (in->axes == NULL && in->n_axes > 0u)) {
        return false;
    }
    if (!(in->ceiling_pct >= 0.0 && in->ceiling_pct <= 100.0)) { /* NaN fails too */
        return false;
    }
    for (size_t i = 0; i < in->n_axes; i++) {
        const ls_drive_budget_axis_t *a = &in->axes[i];
        if (a->n_rpdo > LS_DRIVE_BUDGET_MAX_PDOS || a->n_tpdo > LS_DRIVE_BUDGET_MAX_PDOS) {
            return false;
        }
        for (unsigned k = 0; k < a->n_rpdo; k++) {
            if (a->rpdo_bytes[k] > LS_DRIVE_BUDGET_MAX_DATA) {
                return false;
            }
        }
        for (unsigned k = 0; k < a->n_tpdo; k++) {
            if (a->tpdo_bytes[k] > LS_DRIVE_BUDGET_MAX_DATA) {
                return false;
            }
        }
    }
    return true;
}

int ls_drive_budget_compute(const ls_drive_budget_in_t *in, ls_drive_budget_t *out)
{
    if (in == NULL || out == NULL || !valid(in)) {
        return LS_EINVAL;
    }
    const double ceiling = in->ceiling_pct > 0.0 ? in->ceiling_pct : LS_DRIVE_BUDGET_CEILING_PCT;
    const double hb_bits = ls_drive_budget_frame_bits(HEARTBEAT_BYTES);
    double frames;
    double bits;
    fixed_per_cycle(in, &frames, &bits);
    const double hb_rate = heartbeats_per_us(in);

    ls_drive_budget_t b = { 0 };
    b.frames_per_cycle = frames + hb_rate * in->cycle_us;
    b.bits_per_cycle = bits + hb_bits * hb_rate * in->cycle_us;
    b.load_pct = load_pct(b.bits_per_cycle, in->cycle_us, in->bitrate);
    b.ceiling_pct = ceiling;
    b.fits = fits(b.load_pct, ceiling);

    /* The load falls as the cycle grows (the fixed frames spread over more
     * time; the heartbeats' share stays): the shortest multiple k solves
     * bits + hb_bits hb_rate k T <= ceiling bitrate k T, estimated in closed
     * form and settled with the same test as `fits`. */
    const double T = in->control_period_us;
    const double headroom = ceiling / 100.0 * in->bitrate * 1e-6 - hb_bits * hb_rate; /* bits per us */
    if (headroom > 0.0) {
        double est = ceil(bits / (T * headroom));
        uint32_t k = est < 1.0                            ? 1u
                     : est > LS_DRIVE_BUDGET_MAX_MULTIPLE ? LS_DRIVE_BUDGET_MAX_MULTIPLE + 1u
                                                          : (uint32_t)est;
#define LOAD_AT(m) load_pct(bits + hb_bits * hb_rate * (m)*T, (m)*T, in->bitrate)
        while (k > 1u && k <= LS_DRIVE_BUDGET_MAX_MULTIPLE && fits(LOAD_AT(k - 1u), ceiling)) {
            k--;
        }
        while (k <= LS_DRIVE_BUDGET_MAX_MULTIPLE && !fits(LOAD_AT(k), ceiling)) {
            k++;
        }
#undef LOAD_AT
        b.min_cycle_multiple = k <= LS_DRIVE_BUDGET_MAX_MULTIPLE ? k : 0u;
    }
    *out = b;
    return LS_OK;
}

/* ---- The line ---------------------------------------------------------- */

typedef struct {
    char *buf;
    size_t cap;
    size_t len; /* the whole line's length, even past cap */
} line_t;

static void put(line_t *l, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(line_t *l, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const size_t at = l->len < l->cap ? l->len : l->cap - 1u;
    int n = ls_fmt_vprint(l->buf + at, l->cap - at, fmt, ap);
    va_end(ap);
    if (n > 0) {
        l->len += (size_t)n;
    }
}

/* 1661 -> "1,661". */
static void put_grouped(line_t *l, uint64_t v)
{
    if (v >= 1000u) {
        put_grouped(l, v / 1000u);
        put(l, ",%03u", (unsigned)(v % 1000u));
    } else {
        put(l, "%u", (unsigned)v);
    }
}

/* A duration in us as ms: "2 ms", "2.5 ms", "0.25 ms". */
static void put_ms(line_t *l, uint64_t us)
{
    put(l, "%g ms", (double)us / 1000.0);
}

static void put_bitrate(line_t *l, uint32_t bitrate)
{
    if (bitrate % 1000000u == 0u) {
        put(l, "%u Mbit/s", (unsigned)(bitrate / 1000000u));
    } else if (bitrate % 1000u == 0u) {
        put(l, "%u kbit/s", (unsigned)(bitrate / 1000u));
    } else {
        put(l, "%u bit/s", (unsigned)bitrate);
    }
}

/* The load with the fewest decimals (0..3) that still agree with the
 * verdict: 70.4 above a 70 % ceiling reads "70.4", not "70". The figure is
 * judged as printed (the formatter rounds half to even). */
static void put_load(line_t *l, double load, double ceiling, bool ok)
{
    int p = 0;
    for (; p < 3; p++) {
        char digits[48];
        (void)ls_fmt_print(digits, sizeof digits, "%.*f", p, load);
        const double shown = ls_fmt_parse_double(digits, NULL);
        if (ok ? shown <= ceiling : shown > ceiling) {
            break;
        }
    }
    put(l, "%.*f %%", p, load);
}

int ls_drive_budget_format(const ls_drive_budget_in_t *in, const ls_drive_budget_t *b, char *buf, size_t cap)
{
    if (in == NULL || b == NULL || buf == NULL || cap == 0u) {
        return LS_EINVAL;
    }
    line_t l = { .buf = buf, .cap = cap, .len = 0u };
    buf[0] = '\0';
    put(&l, "drive bus: ");
    put_grouped(&l, (uint64_t)ceil(b->bits_per_cycle));
    put(&l, " bit-times per ");
    put_ms(&l, in->cycle_us);
    put(&l, " cycle = ");
    put_load(&l, b->load_pct, b->ceiling_pct, b->fits);
    put(&l, " of ");
    put_bitrate(&l, in->bitrate);
    if (b->fits) {
        put(&l, ", within the %g %% ceiling", b->ceiling_pct);
    } else if (b->min_cycle_multiple == 0u) {
        put(&l,
            ", above the %g %% ceiling at every cycle up to %u control periods: map fewer PDOs, slow the "
            "heartbeats or raise the bitrate",
            b->ceiling_pct, (unsigned)LS_DRIVE_BUDGET_MAX_MULTIPLE);
    } else {
        put(&l, ", above the %g %% ceiling: set %s = %u (", b->ceiling_pct, LS_DRIVE_BUDGET_CYCLE_KEY,
            (unsigned)b->min_cycle_multiple);
        put_ms(&l, (uint64_t)b->min_cycle_multiple * in->control_period_us);
        put(&l, ") or more, or map fewer PDOs");
    }
    return l.len > (size_t)INT32_MAX ? INT32_MAX : (int)l.len;
}
