/* ls_fmt against glibc: the formatter must print what snprintf prints (text
 * and return value) for every conversion the firmware uses, and the parser
 * must return what strtod returns (bit for bit, and the same end). */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_fmt.h"

/* Both formatters on the same arguments, into big buffers: same text, same length. */
#define SAME(...)                                                                                                      \
    do {                                                                                                               \
        char ours_[2048], glibc_[2048];                                                                                \
        const int n_ours_ = ls_fmt_print(ours_, sizeof ours_, __VA_ARGS__);                                            \
        const int n_glibc_ = snprintf(glibc_, sizeof glibc_, __VA_ARGS__);                                             \
        assert_string_equal(ours_, glibc_);                                                                            \
        assert_int_equal(n_ours_, n_glibc_);                                                                           \
    } while (0)

/* A non-literal format: only ever one of the tables below, each with one double conversion. */
static int check_double(const char *fmt, double v)
{
    char ours[2048], glibc[2048];
    const int n_ours = ls_fmt_print(ours, sizeof ours, fmt, v);
    const int n_glibc = snprintf(glibc, sizeof glibc, fmt, v);
    if (n_ours != n_glibc || strcmp(ours, glibc) != 0) {
        print_error("format \"%s\" of %a: ours \"%s\" (%d), glibc \"%s\" (%d)\n", fmt, v, ours, n_ours, glibc, n_glibc);
        return 1;
    }
    return 0;
}

/* Every double conversion the firmware uses, and the flags, widths and precisions around them. */
static const char *const DOUBLE_FORMATS[] = {
    "%g",   "%.3g",  "%.4g",   "%.6g",     "%.1f",   "%.3f",  "%.4f",     "%f",       "%e",    "%.0e",
    "%.0f", "%#.0f", "%10.3f", "%-10.2e|", "%+g",    "% g",   "%010.3f",  "%.17g",    "%.20g", "%.0g",
    "%G",   "%E",    "%F",     "%.40f",    "%.100e", "%.30g", "%012g",    "%-12g|",   "%.9g",  "%.10g",
    "%.1g", "%.2g",  "%+.3e",  "%#e",      "%#.0e",  "%8.3g", "%-+9.2f|", "% 012.4e", "%.15g", "%.16g",
};
#define N_FORMATS (sizeof DOUBLE_FORMATS / sizeof DOUBLE_FORMATS[0])

static const double SPECIAL[] = {
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    1.5,
    2.5,
    3.5,
    0.125,
    0.375,
    2.675,
    1e300,
    1e-300,
    5e-324,
    -5e-324,
    2.2250738585072014e-308,
    2.225073858507201e-308,
    1.7976931348623157e308,
    -1.7976931348623157e308,
    123.456,
    0.1,
    0.3,
    9.9999999,
    99999.5,
    999999.5,
    0.00001234,
    1e21,
    1e22,
    1e23,
    123456789012345678.0,
    9.5,
    0.95,
    0.095,
    0.0005,
    0.00015,
    1e15,
    1e16,
    1e17,
    4503599627370496.5,
    9007199254740993.0,
    0.1 + 0.2,
    1.0 / 3.0,
    2.0 / 3.0,
    100.0,
    1000.0,
    6.02214076e23,
    1.602176634e-19,
    3.14159265358979,
};

/* A deterministic stream of bit patterns (xorshift64*), so failures repeat. */
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rng(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}

static double any_double(void)
{
    const uint64_t u = rng();
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

static void test_integers_strings_chars(void **state)
{
    (void)state;
    SAME("%d %u %ld %lu %x %X", -42, 42u, -1L, 99UL, 255u, 255u);
    SAME("%02X %08X %03llu %llu %zu", 5u, 0xABCu, 7ULL, 18446744073709551615ULL, (size_t)77);
    SAME("%d %d %ld %lld", 2147483647, -2147483647 - 1, -9223372036854775807L - 1, -9223372036854775807LL - 1);
    SAME("%c%c %s %.3s %.*s|%5s|%-5s|%%", 'q', ' ', "str", "abcdef", 2, "xyz", "ab", "cd");
    SAME("%#x %#X %#o %o %#o %.0d %.0x|%5.3d|%-+6d|%+d|% d", 255u, 255u, 8u, 8u, 0u, 0, 0u, 7, 9, 0, 5);
    SAME("%hhd %hhu %hd %hu %jd %td %i %5i|%-5i|%05d %05d", 300, 300u, 70000, 70000u, (intmax_t)-9, (ptrdiff_t)4, 12,
         -3, 3, -42, 42);
    SAME("%*d|%-*d|%*d|%.*d", 5, 42, 4, 1, -6, 7, 4, 3);
    /* NULL for %s (read through a volatile, so the compiler does not refuse the call) */
    const char *const volatile null_text = NULL;
    SAME("%s|%10s|%.3s|%.6s", null_text, null_text, null_text, null_text);
    SAME("%lx %lX %llx %zx", 0xdeadbeefUL, 0xfeedUL, 0x0123456789abcdefULL, (size_t)0xffff);
    SAME("%" PRId64 " %" PRIu64 " %" PRId64 " %" PRIx64, INT64_MIN, UINT64_MAX, (int64_t)-7, (uint64_t)0xABCDEF);
    SAME("%s", "");
    SAME("no conversion at all");
}

static void test_doubles_special_values(void **state)
{
    (void)state;
    int bad = 0;
    for (size_t i = 0; i < sizeof SPECIAL / sizeof SPECIAL[0]; i++) {
        for (size_t f = 0; f < N_FORMATS; f++) {
            bad += check_double(DOUBLE_FORMATS[f], SPECIAL[i]);
        }
    }
    assert_int_equal(bad, 0);
}

static void test_doubles_rounding_half_to_even(void **state)
{
    (void)state;
    /* Exact ties (binary fractions) go to even, as glibc does; near-ties by their exact value. */
    SAME("%.0f %.0f %.0f %.0f %.0f %.0f", 0.5, 1.5, 2.5, -0.5, -1.5, -2.5);
    SAME("%.2f %.2f %.2f %.1f %.1f", 0.125, 0.375, 2.675, 0.25, 0.35);
    SAME("%.0e %.0e %.1e %.3g %.3g", 25.0, 35.0, 1.25, 1.0005, 99.95);
    SAME("%.2f %.3f %.6f", 999.995, 0.0005, 0.0000005);
    SAME("%.0f %.0f %.0f", 4503599627370495.5, 4503599627370496.5, 9007199254740991.0);
    /* Rounding that carries into a new leading digit, in each style. */
    SAME("%.0f %.2f %.3e %.3g %g %g", 9.5, 9.995, 9.9995, 9.9995, 999999.5, 0.000099999995);
}

static void test_doubles_nan_inf_widths(void **state)
{
    (void)state;
    SAME("%f %F %e %E %g %G", INFINITY, INFINITY, -INFINITY, -INFINITY, NAN, NAN);
    SAME("%f %g", -NAN, -NAN);
    SAME("%8f|%-8g|%08g|%+f|% g|%+.3e", INFINITY, -INFINITY, NAN, INFINITY, NAN, -INFINITY);
}

static void test_doubles_huge_and_tiny(void **state)
{
    (void)state;
    /* The whole decimal expansion: 309 integer digits; 1074 fractional ones. */
    SAME("%f", 1.7976931348623157e308);
    SAME("%.0f", -1e308);
    SAME("%.1074f", 5e-324);
    SAME("%.1080f", 2.2250738585072014e-308);
    SAME("%.760e %.767g", 5e-324, 4.9406564584124654e-324);
    SAME("%.100f %.300e", 1.0 / 3.0, 1e-300);
}

static void test_doubles_random_bit_patterns(void **state)
{
    (void)state;
    int bad = 0;
    for (int k = 0; k < 4000 && bad < 10; k++) {
        const double v = any_double();
        for (size_t f = 0; f < N_FORMATS; f++) {
            bad += check_double(DOUBLE_FORMATS[f], v);
        }
    }
    /* Values of the size the firmware prints (angles, metres, seconds, percentages). */
    for (int k = 0; k < 20000 && bad < 10; k++) {
        const double v = (double)(int64_t)(rng() % 2000001u - 1000000) / (double)(1u + rng() % 100000u);
        for (size_t f = 0; f < N_FORMATS; f++) {
            bad += check_double(DOUBLE_FORMATS[f], v);
        }
    }
    assert_int_equal(bad, 0);
}

/* glibc drops the zeros that '#' keeps when %#g rounds up to a new decade
 * ("1.e+03" for %#.3g of 999.5); C11 7.21.6.1 keeps them: style e with
 * precision P - 1 after rounding. The firmware never uses %#g; ls_fmt
 * follows the standard (as musl does). */
static void test_alt_g_follows_the_standard(void **state)
{
    (void)state;
    char buf[32];
    assert_int_equal(ls_fmt_print(buf, sizeof buf, "%#.3g", 999.5), 8);
    assert_string_equal(buf, "1.00e+03");
    assert_int_equal(ls_fmt_print(buf, sizeof buf, "%#g", 1.5), 7);
    assert_string_equal(buf, "1.50000");
}

static void test_truncation_always_terminated(void **state)
{
    (void)state;
    char full[256];
    const int n = snprintf(full, sizeof full, "%s=%d %.4g %x", "joint", -3, 3.14159265, 0xBEEFu);
    for (size_t cap = 0; cap <= (size_t)n + 2; cap++) {
        char buf[256];
        memset(buf, 'Z', sizeof buf);
        const int got = ls_fmt_print(cap == 0 ? NULL : buf, cap, "%s=%d %.4g %x", "joint", -3, 3.14159265, 0xBEEFu);
        assert_int_equal(got, n); /* the length the whole output has, whatever fits */
        if (cap > 0) {
            const size_t kept = cap - 1 < (size_t)n ? cap - 1 : (size_t)n;
            assert_memory_equal(buf, full, kept);
            assert_int_equal(buf[kept], '\0');
            assert_int_equal(buf[kept + 1], 'Z'); /* nothing written past the end */
        }
    }
    /* A cut in the middle of a number's digits and of its padding. */
    char small[6];
    assert_int_equal(ls_fmt_print(small, sizeof small, "%f", 1e300), 308); /* 301 digits, ".000000" */
    assert_string_equal(small, "10000");
    assert_int_equal(ls_fmt_print(small, sizeof small, "%-20s|", "ab"), 21);
    assert_string_equal(small, "ab   ");
}

static void test_unsupported_conversion_is_an_error(void **state)
{
    (void)state;
    char buf[32];
    int x = 0;
    assert_true(ls_fmt_print(buf, sizeof buf, "ab%pcd", (void *)&x) < 0);
    assert_string_equal(buf, "ab"); /* cut where it stopped, terminated */
}

/* A text for a reader that does not fit ends after a whole word with " ...";
 * one that fits is the plain output. */
static void test_a_cut_text_ends_after_a_whole_word(void **state)
{
    (void)state;
    char buf[30];
    const char *msg = "lower the speed or use a joint move";
    assert_int_equal(ls_fmt_text(buf, sizeof buf, "%s", msg), (int)strlen(msg));
    assert_string_equal(buf, "lower the speed or use a \xE2\x80\xA6");
    for (size_t cap = 1; cap <= strlen(msg) + 1; cap++) {
        char b[64];
        memset(b, 'Z', sizeof b);
        (void)ls_fmt_text(b, cap, "%s", msg);
        const size_t n = strlen(b);
        assert_true(n < cap);
        assert_int_equal(b[cap], 'Z'); /* nothing written past the end */
        if (cap > strlen(msg)) {
            assert_string_equal(b, msg);
        } else if (cap >= 4) {
            /* whole words, then the mark; or the mark alone */
            if (n > 3) {
                assert_true(memcmp(b + n - 4, " \xE2\x80\xA6", 4) == 0);
                assert_memory_equal(b, msg, n - 4);
                assert_true(msg[n - 4] == ' ');
            } else {
                assert_string_equal(b, "\xE2\x80\xA6");
            }
        } else {
            assert_string_equal(b, "");
        }
    }
    /* One long first word (of two-byte characters): the mark alone. */
    char s2[12];
    (void)ls_fmt_text(s2, sizeof s2, "%s", "\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9 x");
    assert_string_equal(s2, "\xE2\x80\xA6");
}

/* vprint through a va_list, as ls_reply does. */
static int via_va_list(char *buf, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int via_va_list(char *buf, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const int n = ls_fmt_vprint(buf, cap, fmt, ap);
    va_end(ap);
    return n;
}

static void test_vprint(void **state)
{
    (void)state;
    char buf[64];
    assert_int_equal(via_va_list(buf, sizeof buf, "%s %d %.3f", "v", 7, 2.0), 9);
    assert_string_equal(buf, "v 7 2.000");
}

/* ----------------------------------------------------------------- parser */

static int check_parse(const char *text)
{
    char *end_ours = NULL, *end_glibc = NULL;
    const double ours = ls_fmt_parse_double(text, &end_ours);
    const double glibc = strtod(text, &end_glibc);
    const bool same =
        (isnan(ours) && isnan(glibc) && signbit(ours) == signbit(glibc)) || memcmp(&ours, &glibc, sizeof ours) == 0;
    if (!same || end_ours != end_glibc) {
        print_error("parse \"%.80s\": ours %a (+%td), glibc %a (+%td)\n", text, ours, end_ours - text, glibc,
                    end_glibc - text);
        return 1;
    }
    return 0;
}

static void test_parse_hard_cases(void **state)
{
    (void)state;
    static const char *const cases[] = {
        "0",
        "-0",
        "1",
        "-1.5",
        "  \t3.14",
        "+2",
        "1e308",
        "1.7976931348623157e308",
        "1.7976931348623158e308", /* rounds down to the largest double */
        "1.797693134862315808e308",
        "1.7976931348623159e308", /* overflows */
        "1e309",
        "-1e400",
        "4.9e-324",
        "2.4703282292062327e-324",         /* just below half the least subnormal: 0 */
        "2.4703282292062328e-324",         /* just above: the least subnormal */
        "2.470328229206232720882538e-324", /* exactly half: the tie goes to 0 */
        "1e-400",
        "2.2250738585072011e-308",
        "2.2250738585072014e-308",
        "0.1",
        "123.456e-2",
        "inf",
        "-Infinity",
        "INFINITE",
        "nan",
        "-NaN",
        "nan(123)",
        "nan(abc_Z9)",
        "nan(",
        "nan(1",
        "1e",
        "1e+",
        "1e-x",
        ".5",
        "5.",
        ".",
        "-",
        "+.e3",
        "",
        "   ",
        "e5",
        "9007199254740993",
        "9007199254740993.0000000000000000000000000001",
        "9007199254740992.9999999999999999999999999999",
        "1.00000000000000011102230246251565404236316680908203125", /* a tie: to even (1.0) */
        "1.00000000000000011102230246251565404236316680908203124",
        "1.00000000000000011102230246251565404236316680908203126",
        "7.038531e-26",
        "3600",
        "0.001",
        "3600.0000001",
        "00000000000000000000000000001e5",
        "0.000000000000000000000000000000000000000000000000001e51",
        "1e-5000",
        "1e5000",
        "1e99999999999999999999",
        "1e-99999999999999999999",
        "123456789012345678901234567890e-20",
        "1.5 trailing",
        "2.5e3x",
        "1..2",
        "1.2.3",
        "0e0",
        "-0.0e-999",
    };
    int bad = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bad += check_parse(cases[i]);
    }
    assert_int_equal(bad, 0);
}

static void test_parse_long_mantissas(void **state)
{
    (void)state;
    /* The exact halfway point between two doubles written out in full (767
     * significant digits and more), then nudged by a digit far beyond the
     * 780 kept: the sticky digit decides. */
    char text[1200];
    int bad = 0;
    for (int k = 0; k < 300 && bad < 10; k++) {
        const double v = any_double();
        if (!isfinite(v) || v == 0.0) {
            continue;
        }
        const double next = nextafter(fabs(v), INFINITY);
        if (!isfinite(next)) {
            continue;
        }
        /* the midpoint, exact in binary with one more bit: print all its digits */
        const long double mid = ((long double)fabs(v) + (long double)next) / 2.0L;
        const int n = snprintf(text, sizeof text, "%.800Le", mid);
        assert_true(n > 0 && (size_t)n < sizeof text);
        bad += check_parse(text);
        /* a nonzero digit far beyond what is kept, before the exponent */
        char *e = strchr(text, 'e');
        assert_non_null(e);
        char tail[16];
        snprintf(tail, sizeof tail, "%s", e);
        snprintf(e, sizeof text - (size_t)(e - text), "0000001%s", tail);
        bad += check_parse(text);
    }
    /* Random digit strings of every length up to 900 digits, with exponents around the range's ends. */
    for (int k = 0; k < 3000 && bad < 10; k++) {
        const int digits = 1 + (int)(rng() % 900u);
        int at = 0;
        for (int d = 0; d < digits; d++) {
            text[at++] = (char)('0' + rng() % 10u);
            if (d == 0 && rng() % 2u == 0) {
                text[at++] = '.';
            }
        }
        const int exps[] = { 0, 5, -5, 300, -300, -330, -340, 310, -1000, -digits };
        snprintf(text + at, sizeof text - (size_t)at, "e%d", exps[rng() % 10u]);
        bad += check_parse(text);
    }
    assert_int_equal(bad, 0);
}

static void test_parse_round_trips(void **state)
{
    (void)state;
    int bad = 0;
    char text[64];
    for (int k = 0; k < 60000 && bad < 10; k++) {
        const double v = any_double();
        if (isnan(v)) {
            continue;
        }
        static const char *const fmts[] = { "%.17g", "%.25e", "%.12g", "%.3f", "%g" };
        snprintf(text, sizeof text, fmts[k % 5], v);
        bad += check_parse(text);
    }
    assert_int_equal(bad, 0);
}

/* The one place glibc and ls_fmt differ on purpose: no hexadecimal input. */
static void test_parse_no_hex(void **state)
{
    (void)state;
    char *end = NULL;
    const char *text = "0x10";
    assert_true(ls_fmt_parse_double(text, &end) == 0.0);
    assert_ptr_equal(end, text + 1); /* the "0", stopped at 'x' */
    assert_true(ls_fmt_parse_double("garbage", &end) == 0.0);
}

static void test_append_builds_lines_and_stops_when_the_buffer_is_full(void **state)
{
    (void)state;
    char buf[16];
    size_t len = 0;
    buf[0] = '\0';
    ls_fmt_append(buf, sizeof buf, &len, "a=%d\n", 1);
    ls_fmt_append(buf, sizeof buf, &len, "b=%s\n", "two");
    assert_string_equal(buf, "a=1\nb=two\n");
    assert_int_equal(len, 10);
    ls_fmt_append(buf, sizeof buf, &len, "c=%d\n", 123456); /* cut to fit */
    assert_string_equal(buf, "a=1\nb=two\nc=123");
    assert_int_equal(len, 15);
    ls_fmt_append(buf, sizeof buf, &len, "d\n"); /* full: nothing more */
    assert_string_equal(buf, "a=1\nb=two\nc=123");
    assert_int_equal(len, 15);
}

/* A long device name keeps its kind and its last part (the device's own
 * name), never a cut character; a short one stays whole. */
static void test_name_tail_keeps_the_kind_and_the_devices_own_name(void **state)
{
    (void)state;
    char buf[48];
    assert_int_equal(ls_fmt_name_tail(buf, sizeof buf, "socketcan:vcan1"), 15);
    assert_string_equal(buf, "socketcan:vcan1");
    const char *by_id = "slcan:tty:/dev/serial/by-id/usb-CANable_8c005eb_12345-if00";
    const size_t n = ls_fmt_name_tail(buf, sizeof buf, by_id);
    assert_string_equal(buf, "slcan:tty:\xE2\x80\xA6/usb-CANable_8c005eb_12345-if00");
    assert_int_equal(n, strlen(buf));
    assert_true(n < sizeof buf);
    /* no '/' in the part that fits: the end as it is, from a whole character */
    const char *utf = "slcan:tty:/d/\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9"
                      "\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9";
    char small[21]; /* 7 bytes of the end: the first is inside a character */
    ls_fmt_name_tail(small, sizeof small, utf);
    assert_memory_equal(small, "slcan:tty:\xE2\x80\xA6", 13);
    assert_int_equal(((unsigned char)small[13] & 0xC0u) != 0x80u, 1);
    assert_true(strlen(small) < sizeof small);
    /* a kind that leaves no room is dropped; a buffer too small for anything is empty */
    char tiny[8];
    ls_fmt_name_tail(tiny, sizeof tiny, by_id);
    assert_string_equal(tiny, "\xE2\x80\xA6"
                              "if00");
    assert_int_equal(ls_fmt_name_tail(tiny, 4, by_id), 0);
    assert_string_equal(tiny, "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_integers_strings_chars),
        cmocka_unit_test(test_doubles_special_values),
        cmocka_unit_test(test_doubles_rounding_half_to_even),
        cmocka_unit_test(test_doubles_nan_inf_widths),
        cmocka_unit_test(test_doubles_huge_and_tiny),
        cmocka_unit_test(test_doubles_random_bit_patterns),
        cmocka_unit_test(test_alt_g_follows_the_standard),
        cmocka_unit_test(test_truncation_always_terminated),
        cmocka_unit_test(test_unsupported_conversion_is_an_error),
        cmocka_unit_test(test_vprint),
        cmocka_unit_test(test_a_cut_text_ends_after_a_whole_word),
        cmocka_unit_test(test_parse_hard_cases),
        cmocka_unit_test(test_parse_long_mantissas),
        cmocka_unit_test(test_parse_round_trips),
        cmocka_unit_test(test_parse_no_hex),
        cmocka_unit_test(test_append_builds_lines_and_stops_when_the_buffer_is_full),
        cmocka_unit_test(test_name_tail_keeps_the_kind_and_the_devices_own_name),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
