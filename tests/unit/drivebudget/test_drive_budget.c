/* ls_drive_budget: frame lengths and per-cycle loads worked out by hand.
 *
 * A classic 11-bit frame of n bytes: 47 + 8n bits, plus at most
 * floor((33 + 8n) / 4) stuff bits, which comes to 55 + 10n bit-times:
 * 55 (SYNC), 65 (heartbeat), 115 (6-byte PDO), 135 (8-byte SDO frame).
 *
 * Six CSP axes, each with one 6-byte RPDO (controlword + target) and one
 * 6-byte TPDO (statusword + position), plus one SYNC:
 *   55 + 12 x 115 = 1,435 bit-times, 13 frames
 *   at 1 Mbit/s: 1 ms 143.5 %, 2 ms 71.75 %, 4 ms 35.875 %
 *   under 70 %: 1435 / (k x 1000) <= 0.70 needs k >= 2.05, so 3 ms. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "ls_drive_budget.h"

static void assert_close(double got, double want)
{
    if (!(fabs(got - want) <= 1e-9 * fmax(1.0, fabs(want)))) {
        fail_msg("got %.12g, want %.12g", got, want);
    }
}

static ls_drive_budget_axis_t csp_axis(uint32_t heartbeat_ms)
{
    ls_drive_budget_axis_t a = { 0 };
    a.n_rpdo = 1;
    a.rpdo_bytes[0] = 6;
    a.n_tpdo = 1;
    a.tpdo_bytes[0] = 6;
    a.heartbeat_ms = heartbeat_ms;
    return a;
}

static ls_drive_budget_axis_t g_axes[100];

static ls_drive_budget_in_t six_csp_axes(uint32_t cycle_us, uint32_t heartbeat_ms)
{
    for (int i = 0; i < 6; i++) {
        g_axes[i] = csp_axis(heartbeat_ms);
    }
    ls_drive_budget_in_t in = { 0 };
    in.control_period_us = 1000;
    in.cycle_us = cycle_us;
    in.bitrate = 1000000;
    in.master_heartbeat_ms = heartbeat_ms;
    in.axes = g_axes;
    in.n_axes = 6;
    return in;
}

static void line_of(const ls_drive_budget_in_t *in, const ls_drive_budget_t *b, char *buf, size_t cap)
{
    int n = ls_drive_budget_format(in, b, buf, cap);
    assert_true(n > 0);
    assert_int_equal((size_t)n, strlen(buf));
}

static void test_frame_lengths_with_worst_case_stuffing_are_55_plus_10_per_byte(void **state)
{
    (void)state;
    assert_int_equal(ls_drive_budget_frame_bits(0), 55);  /* 47 + 8 */
    assert_int_equal(ls_drive_budget_frame_bits(1), 65);  /* 55 + 10 */
    assert_int_equal(ls_drive_budget_frame_bits(6), 115); /* 95 + 20 */
    assert_int_equal(ls_drive_budget_frame_bits(8), 135); /* 111 + 24 */
    for (unsigned n = 0; n <= 8; n++) {
        assert_int_equal(ls_drive_budget_frame_bits(n), 47 + 8 * n + (34 + 8 * n - 1) / 4);
    }
    assert_int_equal(ls_drive_budget_frame_bits(9), 0);
}

static void test_a_lone_sync_is_one_frame_of_55_bit_times(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = { .control_period_us = 1000, .cycle_us = 1000, .bitrate = 1000000 };
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.frames_per_cycle, 1.0);
    assert_close(b.bits_per_cycle, 55.0);
    assert_close(b.load_pct, 5.5);
    assert_close(b.ceiling_pct, 70.0);
    assert_true(b.fits);
    assert_int_equal(b.min_cycle_multiple, 1);
    /* a SYNC with its counter byte: 65 */
    in.sync_bytes = 1;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 65.0);
}

static void test_six_csp_axes_at_1_ms_are_over_the_bus(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = six_csp_axes(1000, 0);
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.frames_per_cycle, 13.0);
    assert_close(b.bits_per_cycle, 1435.0);
    assert_close(b.load_pct, 143.5);
    assert_false(b.fits);
    assert_int_equal(b.min_cycle_multiple, 3);
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 1,435 bit-times per 1 ms cycle = 144 % of 1 Mbit/s, above the 70 % "
                              "ceiling: set [drives] cycle = 3 (3 ms) or more, or map fewer PDOs");
}

static void test_six_csp_axes_at_2_ms_are_just_over_the_ceiling(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = six_csp_axes(2000, 0);
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 1435.0);
    assert_close(b.load_pct, 71.75);
    assert_false(b.fits);
    assert_int_equal(b.min_cycle_multiple, 3);
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 1,435 bit-times per 2 ms cycle = 72 % of 1 Mbit/s, above the 70 % "
                              "ceiling: set [drives] cycle = 3 (3 ms) or more, or map fewer PDOs");
}

static void test_six_csp_axes_at_4_ms_fit(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = six_csp_axes(4000, 0);
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.load_pct, 35.875);
    assert_true(b.fits);
    assert_int_equal(b.min_cycle_multiple, 3);
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 1,435 bit-times per 4 ms cycle = 36 % of 1 Mbit/s, within the 70 % ceiling");
}

/* Seven producers (six drives, the master) of one 65-bit heartbeat every
 * 100 ms: 7 x 65 x 2 / 100 = 9.1 bit-times and 0.14 frames per 2 ms. */
static void test_heartbeats_are_amortised_over_their_periods(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = six_csp_axes(2000, 100);
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.frames_per_cycle, 13.14);
    assert_close(b.bits_per_cycle, 1444.1);
    assert_close(b.load_pct, 72.205);
    assert_false(b.fits);
    /* headroom 0.7 - 7 x 65 / 100000 = 0.69545 bit/us: k >= 1435 / 695.45 = 2.06 */
    assert_int_equal(b.min_cycle_multiple, 3);
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 1,445 bit-times per 2 ms cycle = 72 % of 1 Mbit/s, above the 70 % "
                              "ceiling: set [drives] cycle = 3 (3 ms) or more, or map fewer PDOs");
    /* at 4 ms the same heartbeats weigh twice as much per cycle */
    in.cycle_us = 4000;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 1453.2);
    assert_true(b.fits);
}

static void test_a_slower_bus_needs_a_longer_cycle(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = six_csp_axes(4000, 0);
    in.bitrate = 500000;
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.load_pct, 71.75);
    assert_int_equal(b.min_cycle_multiple, 5); /* 1435 / (k x 500) <= 0.7: k >= 4.1 */
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 1,435 bit-times per 4 ms cycle = 72 % of 500 kbit/s, above the 70 % "
                              "ceiling: set [drives] cycle = 5 (5 ms) or more, or map fewer PDOs");
    /* a 500 us control loop: the same bus time is 9 control periods */
    in.control_period_us = 500;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_int_equal(b.min_cycle_multiple, 9);
    line_of(&in, &b, line, sizeof line);
    assert_non_null(strstr(line, "set [drives] cycle = 9 (4.5 ms) or more"));
}

static void test_an_sdo_reserve_adds_two_8_byte_frames_per_exchange(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = six_csp_axes(4000, 0);
    in.sdo_per_cycle = 1;
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.frames_per_cycle, 15.0);
    assert_close(b.bits_per_cycle, 1435.0 + 270.0);
}

static void test_the_ceiling_is_inclusive_and_configurable(void **state)
{
    (void)state;
    ls_drive_budget_in_t in = { .control_period_us = 1000, .cycle_us = 1000, .bitrate = 1000000 };
    in.ceiling_pct = 5.5; /* exactly the SYNC's 55 bit-times */
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_true(b.fits);
    assert_int_equal(b.min_cycle_multiple, 1);
    in.ceiling_pct = 5.4;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_false(b.fits);
    assert_int_equal(b.min_cycle_multiple, 2);
}

/* 705 bit-times per ms are 70.5 %: printed "70" (half to even) it would
 * contradict "above the 70 % ceiling". 695 are 69.5 % under a 69.5 %
 * ceiling: "70" would contradict "within". */
static void test_a_load_next_to_the_ceiling_gets_the_decimals_that_tell_it_apart(void **state)
{
    (void)state;
    /* SYNC + ten 1-byte frames: 55 + 10 x 65 = 705 */
    ls_drive_budget_axis_t a = {
        .n_rpdo = 5, .rpdo_bytes = { 1, 1, 1, 1, 1 }, .n_tpdo = 5, .tpdo_bytes = { 1, 1, 1, 1, 1 }
    };
    ls_drive_budget_in_t in = {
        .control_period_us = 1000, .cycle_us = 1000, .bitrate = 1000000, .axes = &a, .n_axes = 1
    };
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 705.0);
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 705 bit-times per 1 ms cycle = 70.5 % of 1 Mbit/s, above the 70 % "
                              "ceiling: set [drives] cycle = 2 (2 ms) or more, or map fewer PDOs");
    /* SYNC + eight frames with 20 bytes in all: 55 + 8 x 55 + 200 = 695 */
    ls_drive_budget_axis_t c = { .n_rpdo = 4, .rpdo_bytes = { 8, 8, 4, 0 }, .n_tpdo = 4 };
    in.axes = &c;
    in.ceiling_pct = 69.5;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 695.0);
    assert_true(b.fits);
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 695 bit-times per 1 ms cycle = 69.5 % of 1 Mbit/s, within the 69.5 % "
                              "ceiling");
}

static void test_when_heartbeats_alone_exceed_the_ceiling_no_cycle_fits(void **state)
{
    (void)state;
    /* a 1 ms heartbeat is 65 bit-times per ms: 130 % of 50 kbit/s alone */
    ls_drive_budget_in_t in = {
        .control_period_us = 1000, .cycle_us = 1000, .bitrate = 50000, .master_heartbeat_ms = 1
    };
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 120.0);
    assert_close(b.load_pct, 240.0);
    assert_int_equal(b.min_cycle_multiple, 0);
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_string_equal(line, "drive bus: 120 bit-times per 1 ms cycle = 240 % of 50 kbit/s, above the 70 % ceiling "
                              "at every cycle up to 1000 control periods: map fewer PDOs, slow the heartbeats "
                              "or raise the bitrate");
}

static void test_large_figures_are_grouped_by_thousands(void **state)
{
    (void)state;
    for (int i = 0; i < 100; i++) {
        ls_drive_budget_axis_t *a = &g_axes[i];
        *a = (ls_drive_budget_axis_t){ .n_rpdo = 8, .n_tpdo = 8 };
        for (int k = 0; k < 8; k++) {
            a->rpdo_bytes[k] = 8;
            a->tpdo_bytes[k] = 8;
        }
    }
    ls_drive_budget_in_t in = {
        .control_period_us = 1000, .cycle_us = 1000, .bitrate = 125000, .axes = g_axes, .n_axes = 100
    };
    ls_drive_budget_t b;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    assert_close(b.bits_per_cycle, 55.0 + 1600.0 * 135.0);
    assert_int_equal(b.min_cycle_multiple, 0); /* 2,469 ms is beyond the searched 1,000 */
    char line[256];
    line_of(&in, &b, line, sizeof line);
    assert_non_null(strstr(line, "drive bus: 216,055 bit-times per 1 ms cycle = 172844 % of 125 kbit/s"));
    /* a short buffer: cut, NUL-terminated, the whole length returned */
    char small[16];
    int n = ls_drive_budget_format(&in, &b, small, sizeof small);
    assert_int_equal(n, (int)strlen(line));
    assert_string_equal(small, "drive bus: 216,");
}

static void test_bad_input_is_refused_and_the_result_untouched(void **state)
{
    (void)state;
    ls_drive_budget_t b;
    memset(&b, 0x5A, sizeof b);
    ls_drive_budget_t copy = b;
    ls_drive_budget_in_t good = six_csp_axes(2000, 100);
    ls_drive_budget_in_t in = good;
    assert_int_equal(ls_drive_budget_compute(NULL, &b), LS_EINVAL);
    assert_int_equal(ls_drive_budget_compute(&in, NULL), LS_EINVAL);
    in.cycle_us = 2500; /* not a multiple of 1 ms */
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in = good;
    in.control_period_us = 0;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in = good;
    in.bitrate = 0;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in = good;
    in.sync_bytes = 2;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in = good;
    in.ceiling_pct = 100.5;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in.ceiling_pct = -1.0;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in.ceiling_pct = NAN;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in = good;
    in.axes = NULL;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    in = good;
    g_axes[2].rpdo_bytes[0] = 9;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    g_axes[2] = csp_axis(100);
    g_axes[3].n_tpdo = LS_DRIVE_BUDGET_MAX_PDOS + 1;
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_EINVAL);
    g_axes[3] = csp_axis(100);
    assert_memory_equal(&b, &copy, sizeof b);
    assert_int_equal(ls_drive_budget_compute(&in, &b), LS_OK);
    char line[8];
    assert_int_equal(ls_drive_budget_format(NULL, &b, line, sizeof line), LS_EINVAL);
    assert_int_equal(ls_drive_budget_format(&in, &b, line, 0), LS_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame_lengths_with_worst_case_stuffing_are_55_plus_10_per_byte),
        cmocka_unit_test(test_a_lone_sync_is_one_frame_of_55_bit_times),
        cmocka_unit_test(test_six_csp_axes_at_1_ms_are_over_the_bus),
        cmocka_unit_test(test_six_csp_axes_at_2_ms_are_just_over_the_ceiling),
        cmocka_unit_test(test_six_csp_axes_at_4_ms_fit),
        cmocka_unit_test(test_heartbeats_are_amortised_over_their_periods),
        cmocka_unit_test(test_a_slower_bus_needs_a_longer_cycle),
        cmocka_unit_test(test_an_sdo_reserve_adds_two_8_byte_frames_per_exchange),
        cmocka_unit_test(test_the_ceiling_is_inclusive_and_configurable),
        cmocka_unit_test(test_a_load_next_to_the_ceiling_gets_the_decimals_that_tell_it_apart),
        cmocka_unit_test(test_when_heartbeats_alone_exceed_the_ceiling_no_cycle_fits),
        cmocka_unit_test(test_large_figures_are_grouped_by_thousands),
        cmocka_unit_test(test_bad_input_is_refused_and_the_result_untouched),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
