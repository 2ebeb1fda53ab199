/* Fixed-buffer formatter and number parser (ls_fmt.h).
 *
 * Floating point: the value is expanded exactly into base-1e9 limbs
 * (the binary significand scaled by its power of two, 29 bits at a time up
 * or 9 bits at a time down, both exact in base 1e9), then rounded half to
 * even at the requested digit. Parsing: a first guess from the leading 19
 * digits, then the guess is moved one unit in the last place at a time until
 * the exact decimal value lies between the midpoints to its neighbours,
 * compared as big integers. */
#include "ls_fmt.h"

#include "ls_err.h"

#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* ------------------------------------------------------------ output sink */

#define NO_PRECISION (-1L) /* spec_t.prec: the format gave none */

typedef struct {
    char *buf;
    size_t cap;
    size_t n; /* characters of the whole output so far */
} sink_t;

static void put(sink_t *o, char c)
{
    if (o->n + 1 < o->cap) {
        o->buf[o->n] = c;
    }
    o->n++;
}

static void put_n(sink_t *o, const char *s, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        put(o, s[i]);
    }
}

static void pad(sink_t *o, char c, long count)
{
    for (; count > 0; count--) {
        put(o, c);
    }
}

enum { F_MINUS = 1, F_PLUS = 2, F_SPACE = 4, F_ALT = 8, F_ZERO = 16 };

typedef struct {
    unsigned flags;
    long width;
    long prec; /* NO_PRECISION: none given */
} spec_t;

/* Width padding around a body of `len` characters after a `pl`-character
 * prefix: spaces before, the prefix, zeros (F_ZERO) ... */
static void pad_before(sink_t *o, const spec_t *sp, const char *prefix, size_t pl, long len, bool zero_ok)
{
    long fill = sp->width - (long)pl - len;
    if ((sp->flags & F_MINUS) == 0 && !((sp->flags & F_ZERO) != 0 && zero_ok)) {
        pad(o, ' ', fill);
    }
    put_n(o, prefix, pl);
    if ((sp->flags & F_MINUS) == 0 && (sp->flags & F_ZERO) != 0 && zero_ok) {
        pad(o, '0', fill);
    }
}

/* ... and spaces after (F_MINUS). */
static void pad_after(sink_t *o, const spec_t *sp, size_t pl, long len)
{
    if ((sp->flags & F_MINUS) != 0) {
        pad(o, ' ', sp->width - (long)pl - len);
    }
}

/* ---------------------------------------------------------------- integers */

static void fmt_int(sink_t *o, const spec_t *sp, uintmax_t mag, bool neg, char conv)
{
    char digits[24]; /* 22 octal digits of 2^64 - 1 */
    int nd = 0;
    const unsigned base = conv == 'o' ? 8u : (conv == 'x' || conv == 'X') ? 16u : 10u;
    const char *dig = conv == 'X' ? "0123456789ABCDEF" : "0123456789abcdef";
    const bool nonzero = mag != 0;
    for (; mag != 0; mag /= base) {
        digits[nd++] = dig[mag % base];
    }
    long zeros = 0;
    if (sp->prec >= 0) {
        zeros = sp->prec > nd ? sp->prec - nd : 0;
    } else if (nd == 0) {
        zeros = 1;
    }
    if (conv == 'o' && (sp->flags & F_ALT) != 0 && zeros == 0 && (nd == 0 || digits[nd - 1] != '0')) {
        zeros = 1;
    }
    char prefix[2] = { 0, 0 };
    size_t pl = 0;
    if (conv == 'd' || conv == 'i') {
        if (neg) {
            prefix[pl++] = '-';
        } else if ((sp->flags & F_PLUS) != 0) {
            prefix[pl++] = '+';
        } else if ((sp->flags & F_SPACE) != 0) {
            prefix[pl++] = ' ';
        }
    } else if ((conv == 'x' || conv == 'X') && (sp->flags & F_ALT) != 0 && nonzero) {
        prefix[pl++] = '0';
        prefix[pl++] = conv;
    }
    const long len = zeros + nd;
    pad_before(o, sp, prefix, pl, len, sp->prec < 0);
    pad(o, '0', zeros);
    while (nd > 0) {
        put(o, digits[--nd]);
    }
    pad_after(o, sp, pl, len);
}

/* ---------------------------------------------------------- floating point */

/* Limbs of the exact decimal expansion: a double's value has at most 309
 * integer digits or 1074 fractional ones (121 limbs with the integer limb). */
#define FP_LIMBS 128
#define FP_BILLION 1000000000u

/* The 9 decimal digits of x (< 1e9), zero-padded, into d[0..8]. */
static void limb_digits(uint32_t x, char d[9])
{
    for (int i = 8; i >= 0; i--) {
        d[i] = (char)('0' + x % 10u);
        x /= 10u;
    }
}

/* Digits of x without leading zeros ("0" for 0): returns where they start in d. */
static int limb_lead(uint32_t x, char d[9])
{
    limb_digits(x, d);
    int s = 0;
    while (s < 8 && d[s] == '0') {
        s++;
    }
    return s;
}

static void fmt_fp(sink_t *o, const spec_t *sp, double y, char t)
{
    char prefix[1] = { 0 };
    size_t pl = 0;
    if (signbit(y)) {
        prefix[pl++] = '-';
        y = -y;
    } else if ((sp->flags & F_PLUS) != 0) {
        prefix[pl++] = '+';
    } else if ((sp->flags & F_SPACE) != 0) {
        prefix[pl++] = ' ';
    }
    const bool upper = t >= 'A' && t <= 'Z';
    char lt = (char)(t | 32); /* e, f or g */
    if (!isfinite(y)) {
        const char *s = isnan(y) ? (upper ? "NAN" : "nan") : (upper ? "INF" : "inf");
        pad_before(o, sp, prefix, pl, 3, false);
        put_n(o, s, 3);
        pad_after(o, sp, pl, 3);
        return;
    }
    long p = sp->prec < 0 ? 6 : sp->prec;
    uint32_t big[FP_LIMBS];
    uint32_t *a, *d, *r, *z;
    int e2 = 0;
    y = frexp(y, &e2) * 2.0;
    if (y != 0.0) {
        e2--;
        y *= 0x1p28;
        e2 -= 28;
    }
    /* Negative e2: the integer limb first, fractions grow upwards. Else room
     * below for the integer part (up to 35 limbs), a few fractional limbs above. */
    a = r = z = e2 < 0 ? big : big + FP_LIMBS - 54;
    do {
        *z = (uint32_t)y;
        y = 1e9 * (y - *z++);
    } while (y != 0.0);
    while (e2 > 0) {
        uint32_t carry = 0;
        const int sh = e2 < 29 ? e2 : 29;
        for (d = z - 1; d >= a; d--) {
            const uint64_t x = ((uint64_t)*d << sh) + carry;
            *d = (uint32_t)(x % FP_BILLION);
            carry = (uint32_t)(x / FP_BILLION);
        }
        if (carry != 0) {
            *--a = carry;
        }
        while (z > a && z[-1] == 0) {
            z--;
        }
        e2 -= sh;
    }
    while (e2 < 0) {
        uint32_t carry = 0;
        const int sh = -e2 < 9 ? -e2 : 9;
        for (d = a; d < z; d++) {
            const uint32_t rm = *d & ((1u << sh) - 1u);
            *d = (*d >> sh) + carry;
            carry = (FP_BILLION >> sh) * rm;
        }
        if (*a == 0) {
            a++;
        }
        if (carry != 0) {
            *z++ = carry;
        }
        e2 += sh;
    }
    long e = 0; /* decimal exponent of the leading digit */
    if (a < z) {
        e = 9 * (long)(r - a);
        for (uint32_t i = 10; *a >= i && i < FP_BILLION; i *= 10u) {
            e++;
        }
    }
    /* Round at j digits after the radix point (j may be negative). */
    long j = p - (lt != 'f' ? e : 0) - ((lt == 'g' && p != 0) ? 1 : 0);
    if (j < 9 * (long)(z - r - 1)) {
        const long lj = j + 9L * 1100; /* positive, so / and % round down */
        d = r + 1 + (lj / 9 - 1100);
        uint32_t i = 10; /* 10^(9 - digits kept of *d) */
        for (long k = lj % 9 + 1; k < 9; k++) {
            i *= 10u;
        }
        const uint32_t x = *d % i;
        bool beyond = false;
        for (const uint32_t *q = d + 1; q < z; q++) {
            beyond = beyond || *q != 0;
        }
        if (x != 0 || beyond) {
            bool up;
            if (x > i / 2u || (x == i / 2u && beyond)) {
                up = true;
            } else if (x < i / 2u) {
                up = false;
            } else { /* an exact tie: to even */
                const uint32_t kept = i == FP_BILLION ? (d > a ? d[-1] : 0u) : *d / i;
                up = (kept & 1u) != 0;
            }
            *d -= x;
            if (up) {
                *d += i;
                while (*d > FP_BILLION - 1u) {
                    *d-- = 0;
                    if (d < a) {
                        *--a = 0;
                    }
                    (*d)++;
                }
                e = 9 * (long)(r - a);
                for (uint32_t k = 10; *a >= k && k < FP_BILLION; k *= 10u) {
                    e++;
                }
            }
        }
        if (z > d + 1) {
            z = d + 1;
        }
    }
    while (z > a && z[-1] == 0) {
        z--;
    }
    if (lt == 'g') {
        if (p == 0) {
            p = 1;
        }
        if (p > e && e >= -4) {
            lt = 'f';
            p -= e + 1;
        } else {
            lt = 'e';
            p--;
        }
        if ((sp->flags & F_ALT) == 0) {
            long tz = 9; /* trailing zeros in the last limb */
            if (z > a && z[-1] != 0) {
                tz = 0;
                for (uint32_t k = 10; z[-1] % k == 0; k *= 10u) {
                    tz++;
                }
            }
            const long have = lt == 'f' ? 9 * (long)(z - r - 1) - tz : 9 * (long)(z - r - 1) + e - tz;
            p = p < have ? p : have;
            p = p > 0 ? p : 0;
        }
    }
    const char echar = lt == 'e' ? (upper ? 'E' : 'e') : 0;
    char ebuf[8]; /* e+308 */
    size_t el = 0;
    long len = 1 + p + ((p != 0 || (sp->flags & F_ALT) != 0) ? 1 : 0);
    if (lt == 'f') {
        if (e > 0) {
            len += e;
        }
    } else {
        char tmp[6];
        size_t tl = 0;
        unsigned long ue = (unsigned long)(e < 0 ? -e : e);
        do {
            tmp[tl++] = (char)('0' + ue % 10u);
            ue /= 10u;
        } while (ue != 0);
        if (tl < 2) {
            tmp[tl++] = '0';
        }
        ebuf[el++] = echar;
        ebuf[el++] = e < 0 ? '-' : '+';
        while (tl > 0) {
            ebuf[el++] = tmp[--tl];
        }
        len += (long)el;
    }
    pad_before(o, sp, prefix, pl, len, true);
    char dg[9];
    if (lt == 'f') {
        if (a > r) {
            a = r;
        }
        for (d = a; d <= r; d++) {
            if (d != a) {
                limb_digits(*d, dg);
                put_n(o, dg, 9);
            } else {
                const int s = limb_lead(*d, dg);
                put_n(o, dg + s, (size_t)(9 - s));
            }
        }
        if (p != 0 || (sp->flags & F_ALT) != 0) {
            put(o, '.');
        }
        for (; d < z && p > 0; d++, p -= 9) {
            limb_digits(*d, dg);
            put_n(o, dg, (size_t)(p < 9 ? p : 9));
        }
        pad(o, '0', p);
    } else {
        if (z <= a) {
            z = a + 1;
        }
        for (d = a; d < z && p >= 0; d++) {
            int s = 0;
            if (d != a) {
                limb_digits(*d, dg);
            } else {
                s = limb_lead(*d, dg);
                put(o, dg[s++]);
                if (p > 0 || (sp->flags & F_ALT) != 0) {
                    put(o, '.');
                }
            }
            const long rest = 9 - s;
            put_n(o, dg + s, (size_t)(rest < p ? rest : p));
            p -= rest;
        }
        pad(o, '0', p);
        put_n(o, ebuf, el);
    }
    pad_after(o, sp, pl, len);
}

/* ------------------------------------------------------------- the driver */

typedef enum { LEN_NONE, LEN_HH, LEN_H, LEN_L, LEN_LL, LEN_Z, LEN_J, LEN_T } len_mod_t;

static uintmax_t arg_unsigned(va_list *ap, len_mod_t lm)
{
    switch (lm) {
    case LEN_HH: return (unsigned char)va_arg(*ap, unsigned);
    case LEN_H: return (unsigned short)va_arg(*ap, unsigned);
    case LEN_L: return va_arg(*ap, unsigned long);
    case LEN_LL: return va_arg(*ap, unsigned long long);
    case LEN_Z: return va_arg(*ap, size_t);
    case LEN_J: return va_arg(*ap, uintmax_t);
    case LEN_T: return (uintmax_t)va_arg(*ap, ptrdiff_t);
    case LEN_NONE: break;
    }
    return va_arg(*ap, unsigned);
}

static intmax_t arg_signed(va_list *ap, len_mod_t lm)
{
    switch (lm) {
    case LEN_HH: return (signed char)va_arg(*ap, int);
    case LEN_H: return (short)va_arg(*ap, int);
    case LEN_L: return va_arg(*ap, long);
    case LEN_LL: return va_arg(*ap, long long);
    case LEN_Z: return (intmax_t)va_arg(*ap, size_t); /* the signed type of size_t's width */
    case LEN_J: return va_arg(*ap, intmax_t);
    case LEN_T: return va_arg(*ap, ptrdiff_t);
    case LEN_NONE: break;
    }
    return va_arg(*ap, int);
}

static long read_num(const char **f)
{
    long v = 0;
    while (**f >= '0' && **f <= '9') {
        if (v < INT_MAX / 10) {
            v = v * 10 + (**f - '0');
        } else {
            v = INT_MAX;
        }
        (*f)++;
    }
    return v;
}

static int format(sink_t *o, const char *fmt, va_list *ap)
{
    for (const char *f = fmt; *f != '\0';) {
        if (*f != '%') {
            put(o, *f++);
            continue;
        }
        f++;
        spec_t sp = { 0, 0, NO_PRECISION };
        for (;; f++) {
            if (*f == '-') {
                sp.flags |= F_MINUS;
            } else if (*f == '+') {
                sp.flags |= F_PLUS;
            } else if (*f == ' ') {
                sp.flags |= F_SPACE;
            } else if (*f == '#') {
                sp.flags |= F_ALT;
            } else if (*f == '0') {
                sp.flags |= F_ZERO;
            } else {
                break;
            }
        }
        if (*f == '*') {
            f++;
            const int w = va_arg(*ap, int);
            if (w < 0) {
                sp.flags |= F_MINUS;
                sp.width = -(long)w;
            } else {
                sp.width = w;
            }
        } else {
            sp.width = read_num(&f);
        }
        if (*f == '.') {
            f++;
            if (*f == '*') {
                f++;
                const int pr = va_arg(*ap, int);
                sp.prec = pr < 0 ? NO_PRECISION : pr; /* a negative one counts as none (C11 7.21.6.1) */
            } else {
                sp.prec = read_num(&f);
            }
        }
        len_mod_t lm = LEN_NONE;
        if (*f == 'h') {
            lm = f[1] == 'h' ? LEN_HH : LEN_H;
            f += f[1] == 'h' ? 2 : 1;
        } else if (*f == 'l') {
            lm = f[1] == 'l' ? LEN_LL : LEN_L;
            f += f[1] == 'l' ? 2 : 1;
        } else if (*f == 'z') {
            lm = LEN_Z;
            f++;
        } else if (*f == 'j') {
            lm = LEN_J;
            f++;
        } else if (*f == 't') {
            lm = LEN_T;
            f++;
        }
        const char conv = *f;
        switch (conv) {
        case 'd':
        case 'i': {
            const intmax_t v = arg_signed(ap, lm);
            const uintmax_t mag = v < 0 ? (uintmax_t)0 - (uintmax_t)v : (uintmax_t)v;
            fmt_int(o, &sp, mag, v < 0, conv);
            break;
        }
        case 'u':
        case 'o':
        case 'x':
        case 'X': fmt_int(o, &sp, arg_unsigned(ap, lm), false, conv); break;
        case 'c': {
            const char c = (char)va_arg(*ap, int);
            pad_before(o, &sp, "", 0, 1, false);
            put(o, c);
            pad_after(o, &sp, 0, 1);
            break;
        }
        case 's': {
            const char *s = va_arg(*ap, const char *);
            if (s == NULL) {
                s = sp.prec < 0 || sp.prec >= 6 ? "(null)" : "";
            }
            size_t n = 0;
            while ((sp.prec < 0 || (long)n < sp.prec) && s[n] != '\0') {
                n++;
            }
            pad_before(o, &sp, "", 0, (long)n, false);
            put_n(o, s, n);
            pad_after(o, &sp, 0, (long)n);
            break;
        }
        case '%': put(o, '%'); break;
        case 'e':
        case 'E':
        case 'f':
        case 'F':
        case 'g':
        case 'G': fmt_fp(o, &sp, va_arg(*ap, double), conv); break;
        default: return LS_EINVAL; /* not supported (L, a, n, p, ...) or a '%' at the end */
        }
        f++;
    }
    return 0;
}

int ls_fmt_vprint(char *buf, size_t cap, const char *fmt, va_list ap)
{
    sink_t o = { buf, cap, 0 };
    va_list aq;
    va_copy(aq, ap);
    const int rc = format(&o, fmt, &aq);
    va_end(aq);
    if (cap > 0) {
        buf[o.n < cap ? o.n : cap - 1] = '\0';
    }
    if (rc < 0) {
        return rc;
    }
    return o.n > (size_t)INT_MAX ? INT_MAX : (int)o.n;
}

int ls_fmt_print(char *buf, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const int n = ls_fmt_vprint(buf, cap, fmt, ap);
    va_end(ap);
    return n;
}

/* A text of more than cap - 1 bytes, its first cap - 1 in buf: end it after
 * its last whole word with " \u2026" (a word ends before a space), or be
 * the mark alone when not even the first word fits. */
static void cut_after_word(char *buf, size_t cap)
{
    static const char mark[] = " \xE2\x80\xA6";
    const size_t mark_len = sizeof mark - 1;
    if (cap < mark_len) {
        buf[0] = '\0';
        return;
    }
    size_t k = cap > mark_len + 1 ? cap - 1 - mark_len : 0; /* text kept: [0, k) */
    while (k > 0 && buf[k] != ' ') {
        k--;
    }
    while (k > 0 && buf[k - 1] == ' ') {
        k--;
    }
    if (k == 0) {
        memcpy(buf, mark + 1, mark_len); /* the ellipsis and the NUL */
        return;
    }
    memcpy(buf + k, mark, mark_len + 1);
}

int ls_fmt_vtext(char *buf, size_t cap, const char *fmt, va_list ap)
{
    const int n = ls_fmt_vprint(buf, cap, fmt, ap);
    if (n >= 0 && cap > 0 && (size_t)n >= cap) {
        cut_after_word(buf, cap);
    }
    return n;
}

int ls_fmt_text(char *buf, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const int n = ls_fmt_vtext(buf, cap, fmt, ap);
    va_end(ap);
    return n;
}

void ls_fmt_append(char *buf, size_t cap, size_t *len, const char *fmt, ...)
{
    if (*len + 1u >= cap) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    const int w = ls_fmt_vprint(buf + *len, cap - *len, fmt, ap);
    va_end(ap);
    if (w > 0) {
        *len += (size_t)w < cap - *len ? (size_t)w : cap - *len - 1u;
    }
}

size_t ls_fmt_name_tail(char *buf, size_t cap, const char *name)
{
    static const char ellipsis[] = "\xE2\x80\xA6"; /* U+2026 */
    const size_t el = sizeof ellipsis - 1u;
    if (cap == 0) {
        return 0;
    }
    const size_t n = strlen(name);
    if (n < cap) {
        memcpy(buf, name, n + 1u);
        return n;
    }
    buf[0] = '\0';
    if (cap < el + 2u) {
        return 0; /* not even an ellipsis and one byte of the end */
    }
    const char *slash = strchr(name, '/');
    size_t kind = slash != NULL ? (size_t)(slash - name) : 0u;
    if (kind + el + 1u >= cap) {
        kind = 0; /* the kind alone leaves no room for the end */
    }
    const size_t room = cap - 1u - kind - el;
    const char *tail = name + n - room;
    const char *from = strchr(tail, '/');
    if (from != NULL && from[1] != '\0') {
        tail = from;
    }
    while (((unsigned char)*tail & 0xC0u) == 0x80u) {
        tail++; /* a character's continuation bytes: start at its next one */
    }
    const size_t tl = strlen(tail);
    memcpy(buf, name, kind);
    memcpy(buf + kind, ellipsis, el);
    memcpy(buf + kind + el, tail, tl + 1u);
    return kind + el + tl;
}

/* ------------------------------------------------------------------ parser */

/* Significant digits kept exactly; any further nonzero digit only makes the
 * value a little larger (sticky). 780 > 767, the most digits that can
 * matter to rounding a double. */
#define PARSE_MAX_DIGITS 780
/* Big integers of the comparisons: D (<= 780 digits) times 2^1076, or a
 * 55-bit number times 10^1104, both below 3,730 bits. */
#define BIG_WORDS 120

typedef struct {
    uint32_t w[BIG_WORDS]; /* little-endian */
    int n;                 /* words in use; w[n - 1] != 0 unless n == 0 */
} big_t;

static void big_set(big_t *b, uint64_t v)
{
    b->n = 0;
    for (; v != 0; v >>= 32) {
        b->w[b->n++] = (uint32_t)v;
    }
}

/* b = b * m + add. The sizes above keep every product within BIG_WORDS. */
static void big_mul_add(big_t *b, uint32_t m, uint32_t add)
{
    uint64_t carry = add;
    for (int i = 0; i < b->n; i++) {
        const uint64_t x = (uint64_t)b->w[i] * m + carry;
        b->w[i] = (uint32_t)x;
        carry = x >> 32;
    }
    if (carry != 0 && b->n < BIG_WORDS) {
        b->w[b->n++] = (uint32_t)carry;
    }
}

static void big_mul_pow10(big_t *b, long k)
{
    static const uint32_t p10[10] = { 1u,      10u,      100u,      1000u,      10000u,
                                      100000u, 1000000u, 10000000u, 100000000u, 1000000000u };
    for (; k >= 9; k -= 9) {
        big_mul_add(b, p10[9], 0);
    }
    if (k > 0) {
        big_mul_add(b, p10[k], 0);
    }
}

static void big_shl(big_t *b, long bits)
{
    if (b->n == 0 || bits <= 0) {
        return;
    }
    const int words = (int)(bits / 32), sh = (int)(bits % 32);
    int n = b->n + words + 1;
    if (n > BIG_WORDS) {
        n = BIG_WORDS;
    }
    for (int i = n - 1; i >= 0; i--) {
        const int src = i - words;
        uint32_t v = 0;
        if (src >= 0 && src < b->n) {
            v = b->w[src] << sh;
        }
        if (sh != 0 && src - 1 >= 0 && src - 1 < b->n) {
            v |= b->w[src - 1] >> (32 - sh);
        }
        b->w[i] = v;
    }
    b->n = n;
    while (b->n > 0 && b->w[b->n - 1] == 0) {
        b->n--;
    }
}

static int big_cmp(const big_t *x, const big_t *y)
{
    if (x->n != y->n) {
        return (x->n > y->n) - (x->n < y->n);
    }
    for (int i = x->n - 1; i >= 0; i--) {
        if (x->w[i] != y->w[i]) {
            return (x->w[i] > y->w[i]) - (x->w[i] < y->w[i]);
        }
    }
    return 0;
}

/* The sign of D * 10^e10 (+ a sticky bit) - m * 2^e2. */
static int cmp_exact(const big_t *D, long e10, bool sticky, uint64_t m, long e2)
{
    big_t L = *D, R;
    big_set(&R, m);
    if (e10 >= 0) {
        big_mul_pow10(&L, e10);
    } else {
        big_mul_pow10(&R, -e10);
    }
    if (e2 >= 0) {
        big_shl(&R, e2);
    } else {
        big_shl(&L, -e2);
    }
    const int c = big_cmp(&L, &R);
    return c == 0 && sticky ? 1 : c;
}

/* g (finite, > 0) as M * 2^k with M an integer of at most 53 bits, k >= -1074. */
static void split(double g, uint64_t *M, long *k)
{
    int ex;
    const double fr = frexp(g, &ex); /* g = fr * 2^ex, fr in [0.5, 1) */
    long kk = (long)ex - 53;
    double m = ldexp(fr, 53);
    if (kk < -1074) {
        m = ldexp(m, (int)(kk + 1074));
        kk = -1074;
    }
    *M = (uint64_t)m;
    *k = kk;
}

/* The double nearest D * 10^e10 (+ sticky), from the first guess g. */
static double refine(const big_t *D, long e10, bool sticky, double g)
{
    for (int iter = 0; iter < 64; iter++) {
        if (g == 0.0) { /* half the least subnormal: 1 * 2^-1075 */
            const int c = cmp_exact(D, e10, sticky, 1u, -1075);
            if (c <= 0) {
                return 0.0; /* a tie goes to 0, the even one */
            }
            g = 0x1p-1074;
            continue;
        }
        if (isinf(g)) {
            g = 0x1.fffffffffffffp1023;
        }
        uint64_t M;
        long k;
        split(g, &M, &k);
        const int up = cmp_exact(D, e10, sticky, 2u * M + 1u, k - 1);
        if (up > 0 || (up == 0 && (M & 1u) != 0)) {
            const double next = nextafter(g, INFINITY);
            if (up == 0 || isinf(next)) {
                return next; /* a tie to even, or past the largest double's upper midpoint */
            }
            g = next;
            continue;
        }
        if (up == 0) {
            return g;
        }
        /* Below g's upper midpoint: is it below the lower one? At a power of
         * two the neighbour below is half as far. */
        const bool pow2 = M == (1ull << 52) && k > -1074;
        const int down =
            pow2 ? cmp_exact(D, e10, sticky, 4u * M - 1u, k - 2) : cmp_exact(D, e10, sticky, 2u * M - 1u, k - 1);
        if (down < 0) {
            g = nextafter(g, 0.0);
            continue;
        }
        if (down == 0 && !pow2 && (M & 1u) != 0) {
            return nextafter(g, 0.0); /* a tie: the neighbour below is even */
        }
        return g;
    }
    return g;
}

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static char lower(char c)
{
    return c >= 'A' && c <= 'Z' ? (char)(c - 'A' + 'a') : c;
}

/* Does s start with `word` (lower case), in any case? */
static bool starts_with(const char *s, const char *word)
{
    for (; *word != '\0'; s++, word++) {
        if (lower(*s) != *word) {
            return false;
        }
    }
    return true;
}

double ls_fmt_parse_double(const char *s, char **end)
{
    const char *p = s;
    while (is_space(*p)) {
        p++;
    }
    bool neg = false;
    if (*p == '+' || *p == '-') {
        neg = *p == '-';
        p++;
    }
    if (starts_with(p, "inf")) {
        p += starts_with(p, "infinity") ? 8 : 3;
        if (end != NULL) {
            *end = (char *)(uintptr_t)p;
        }
        return neg ? -INFINITY : INFINITY;
    }
    if (starts_with(p, "nan")) {
        p += 3;
        if (*p == '(') {
            const char *q = p + 1;
            while (is_digit(*q) || (lower(*q) >= 'a' && lower(*q) <= 'z') || *q == '_') {
                q++;
            }
            if (*q == ')') {
                p = q + 1;
            }
        }
        if (end != NULL) {
            *end = (char *)(uintptr_t)p;
        }
        return neg ? -NAN : NAN;
    }
    /* Mantissa: value = 0.d1 d2 ... x 10^dp over the significant digits. */
    const char *mant = p;
    bool any = false, point = false, sticky = false;
    long dp = 0;
    int nsig = 0, nkeep = 0; /* significant digits seen; kept up to the last nonzero one */
    for (;; p++) {
        if (is_digit(*p)) {
            any = true;
            if (nsig == 0 && *p == '0') {
                dp -= point ? 1 : 0;
                continue;
            }
            if (nsig < INT_MAX) {
                nsig++;
            }
            dp += point ? 0 : 1;
            if (nsig <= PARSE_MAX_DIGITS) {
                nkeep = *p != '0' ? nsig : nkeep;
            } else if (*p != '0') {
                sticky = true;
            }
        } else if (*p == '.' && !point) {
            point = true;
        } else {
            break;
        }
    }
    if (!any) {
        if (end != NULL) {
            *end = (char *)(uintptr_t)s;
        }
        return 0.0;
    }
    long exp10 = 0;
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1;
        bool eneg = false;
        if (*q == '+' || *q == '-') {
            eneg = *q == '-';
            q++;
        }
        if (is_digit(*q)) {
            for (; is_digit(*q); q++) {
                exp10 = exp10 < 100000000L ? exp10 * 10 + (*q - '0') : exp10;
            }
            exp10 = eneg ? -exp10 : exp10;
            p = q;
        }
    }
    if (end != NULL) {
        *end = (char *)(uintptr_t)p;
    }
    const double sign = neg ? -1.0 : 1.0;
    if (nkeep == 0) {
        return sign * 0.0;
    }
    const long lead = dp + exp10; /* value in [10^(lead - 1), 10^lead) */
    if (lead > 310) {
        return sign * HUGE_VAL;
    }
    if (lead <= -324) { /* below 1e-324, less than half the least subnormal */
        return sign * 0.0;
    }
    /* D: the kept digits as an integer; value = D x 10^e10. */
    const long e10 = lead - nkeep;
    big_t D;
    big_set(&D, 0);
    uint64_t first = 0; /* the leading 19 digits, for the first guess */
    int nfirst = 0, taken = 0;
    uint32_t chunk = 0, chunk_mul = 1;
    for (const char *q = mant; taken < nkeep; q++) {
        if (!is_digit(*q) || (taken == 0 && *q == '0')) {
            continue;
        }
        const uint32_t dig = (uint32_t)(*q - '0');
        if (nfirst < 19) {
            first = first * 10u + dig;
            nfirst++;
        }
        chunk = chunk * 10u + dig;
        chunk_mul *= 10u;
        taken++;
        if (chunk_mul == FP_BILLION || taken == nkeep) {
            big_mul_add(&D, chunk_mul, chunk);
            chunk = 0;
            chunk_mul = 1;
        }
    }
    /* First guess: first x 10^(e10 + nkeep - nfirst), in steps that stay
     * within a few units in the last place (an overflow becomes the largest
     * double, an underflow 0: refine walks from there). */
    double g = (double)first;
    long k10 = e10 + (nkeep - nfirst);
    static const double p10[23] = { 1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22 };
    for (; k10 > 22; k10 -= 22) {
        g *= 1e22;
    }
    for (; k10 < -22; k10 += 22) {
        g /= 1e22;
    }
    g = k10 >= 0 ? g * p10[k10] : g / p10[-k10];
    return sign * refine(&D, e10, sticky, g);
}
