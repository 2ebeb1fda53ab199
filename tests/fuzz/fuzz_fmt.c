/* ls_fmt (firmware/common/ls_fmt.h) against glibc: the parser against
 * strtod (same bits, same end) on any text, and the formatter against
 * snprintf (same text, same length, same cut into a small buffer) on any
 * double, integer or string with any flags, width and precision built from
 * the input; a string also through ls_fmt_text, whose cut ends after whole
 * words with a mark. A difference traps.
 *
 * Input: byte 0 picks the mode; the rest is the text (parser), or the value
 * and the conversion's parts (formatter). Two differences are on purpose
 * (ls_fmt.h) and skipped: hexadecimal input, and '#' with %g, where glibc
 * drops zeros the C standard keeps. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_fmt.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static bool hex_prefixed(const char *s)
{
    while (*s == ' ' || (*s >= '\t' && *s <= '\r')) {
        s++;
    }
    if (*s == '+' || *s == '-') {
        s++;
    }
    return s[0] == '0' && (s[1] == 'x' || s[1] == 'X');
}

static void parse_one(const uint8_t *data, size_t size)
{
    static char text[2048];
    if (size >= sizeof text) {
        size = sizeof text - 1;
    }
    memcpy(text, data, size);
    text[size] = '\0';
    if (hex_prefixed(text)) {
        return;
    }
    char *end_ours = NULL, *end_glibc = NULL;
    const double ours = ls_fmt_parse_double(text, &end_ours);
    const double glibc = strtod(text, &end_glibc);
    const bool same =
        (isnan(ours) && isnan(glibc) && signbit(ours) == signbit(glibc)) || memcmp(&ours, &glibc, sizeof ours) == 0;
    if (!same || end_ours != end_glibc) {
        __builtin_trap();
    }
}

/* One conversion spec from the input: "%" flags width ["." precision] length conv. */
typedef struct {
    char fmt[32];
    size_t cap; /* the output buffer's size for the cut check */
} spec_t;

static size_t build_spec(spec_t *sp, const uint8_t *in, const char *flags_allowed, const char *length, char conv)
{
    size_t n = 0;
    sp->fmt[n++] = '%';
    for (size_t i = 0; flags_allowed[i] != '\0'; i++) {
        if ((in[0] >> i) & 1u) {
            sp->fmt[n++] = flags_allowed[i];
        }
    }
    const unsigned width = in[1] % 48u;
    if (width > 0) {
        n += (size_t)snprintf(sp->fmt + n, sizeof sp->fmt - n, "%u", width);
    }
    if (in[2] < 200) {
        n += (size_t)snprintf(sp->fmt + n, sizeof sp->fmt - n, ".%u", in[2] % 130u);
    }
    n += (size_t)snprintf(sp->fmt + n, sizeof sp->fmt - n, "%s%c", length, conv);
    sp->cap = in[3] % 80u;
    return n;
}

/* Both formatters, whole and cut to sp->cap: same text, same length. */
#define COMPARE(sp, ...)                                                                                               \
    do {                                                                                                               \
        static char ours_[4096], glibc_[4096];                                                                         \
        const int n_ours_ = ls_fmt_print(ours_, sizeof ours_, (sp)->fmt, __VA_ARGS__);                                 \
        const int n_glibc_ = snprintf(glibc_, sizeof glibc_, (sp)->fmt, __VA_ARGS__);                                  \
        if (n_ours_ != n_glibc_ || strcmp(ours_, glibc_) != 0) {                                                       \
            __builtin_trap();                                                                                          \
        }                                                                                                              \
        char cut_[80];                                                                                                 \
        memset(cut_, 'Z', sizeof cut_);                                                                                \
        if (ls_fmt_print((sp)->cap == 0 ? NULL : cut_, (sp)->cap, (sp)->fmt, __VA_ARGS__) != n_glibc_) {               \
            __builtin_trap();                                                                                          \
        }                                                                                                              \
        if ((sp)->cap > 0) {                                                                                           \
            const size_t kept_ = (sp)->cap - 1 < (size_t)n_glibc_ ? (sp)->cap - 1 : (size_t)n_glibc_;                  \
            if (memcmp(cut_, glibc_, kept_) != 0 || cut_[kept_] != '\0' ||                                             \
                (kept_ + 1 < sizeof cut_ && cut_[kept_ + 1] != 'Z')) {                                                 \
                __builtin_trap();                                                                                      \
            }                                                                                                          \
        }                                                                                                              \
    } while (0)

static void format_double(const uint8_t *in)
{
    double v;
    memcpy(&v, in + 4, sizeof v);
    static const char convs[] = "eEfFgG";
    const char conv = convs[in[12] % 6u];
    spec_t sp;
    /* '#' with %g/%G: glibc drops zeros the standard keeps (tests/unit/fmt). */
    build_spec(&sp, in, (conv | 32) == 'g' ? "-+ 0" : "-+ 0#", "", conv);
    COMPARE(&sp, v);
}

static void format_integer(const uint8_t *in)
{
    uint64_t u;
    memcpy(&u, in + 4, sizeof u);
    static const char convs[] = "diuxXo";
    static const char *const lengths[] = { "", "l", "ll", "h", "hh", "z" };
    const char conv = convs[in[12] % 6u];
    const unsigned lm = in[13] % 6u;
    spec_t sp;
    build_spec(&sp, in, "-+ 0#", lengths[lm], conv);
    const bool is_signed = conv == 'd' || conv == 'i';
    switch (lm) {
    case 1:
        if (is_signed) {
            COMPARE(&sp, (long)u);
        } else {
            COMPARE(&sp, (unsigned long)u);
        }
        break;
    case 2:
        if (is_signed) {
            COMPARE(&sp, (long long)u);
        } else {
            COMPARE(&sp, (unsigned long long)u);
        }
        break;
    case 5:
        if (is_signed) {
            COMPARE(&sp, (ptrdiff_t)u); /* the signed type of size_t's width */
        } else {
            COMPARE(&sp, (size_t)u);
        }
        break;
    default: /* int, short and char are passed as int */
        if (is_signed) {
            COMPARE(&sp, (int)(uint32_t)u);
        } else {
            COMPARE(&sp, (unsigned)u);
        }
        break;
    }
}

static void format_string(const uint8_t *in, const uint8_t *text, size_t len)
{
    static char s[512];
    if (len >= sizeof s) {
        len = sizeof s - 1;
    }
    memcpy(s, text, len);
    s[len] = '\0';
    spec_t sp;
    build_spec(&sp, in, "-", "", 's');
    COMPARE(&sp, s);
    /* For a reader (ls_fmt_text): the whole text when it fits; else whole
     * words of it and " \u2026", the mark alone, or nothing (cap < 4). */
    char cut[80];
    len = strlen(s); /* the text ends at its first NUL */
    if (sp.cap > 0 && ls_fmt_text(cut, sp.cap, "%s", s) != (int)len) {
        __builtin_trap();
    }
    if (sp.cap > len && strcmp(cut, s) != 0) {
        __builtin_trap();
    }
    const size_t n = sp.cap > 0 ? strlen(cut) : 0;
    const bool words = n > 3 && n < sp.cap && memcmp(cut + n - 4, " \xE2\x80\xA6", 4) == 0 &&
                       memcmp(cut, s, n - 4) == 0 && s[n - 4] == ' ';
    const bool mark_only = strcmp(cut, "\xE2\x80\xA6") == 0 && sp.cap >= 4;
    if (sp.cap > 0 && sp.cap <= len && !words && !mark_only && !(n == 0 && sp.cap < 4)) {
        __builtin_trap();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) {
        return 0;
    }
    const uint8_t mode = data[0] % 4u;
    data++;
    size--;
    if (mode == 0) {
        parse_one(data, size);
        return 0;
    }
    uint8_t in[16] = { 0 };
    memcpy(in, data, size < sizeof in ? size : sizeof in);
    if (mode == 1) {
        format_double(in);
    } else if (mode == 2) {
        format_integer(in);
    } else {
        format_string(in, size > sizeof in ? data + sizeof in : data, size > sizeof in ? size - sizeof in : 0);
    }
    return 0;
}
