/* ls-simdrives --sync-stats (firmware/app/ls_simdrives_sync.h): which frames
 * are SYNCs, the interval statistics and the line at exit, time driven by
 * the test. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "ls_canopen.h"
#include "ls_simdrives_sync.h"

static ls_sync_watch_t g_w; /* large: static */

static void test_only_a_standard_data_frame_at_the_sync_id_with_at_most_a_counter_is_a_sync(void **state)
{
    (void)state;
    hal_can_frame_t f = { .id = LS_CO_COB_SYNC, .flags = 0, .len = 0, .data = { 0 } };
    assert_true(ls_sync_watch_is_sync(&f));
    f.len = 1; /* the SYNC counter of 0x1019 */
    assert_true(ls_sync_watch_is_sync(&f));
    f.len = 8; /* a SYNC carries its counter at most */
    assert_false(ls_sync_watch_is_sync(&f));
    f = (hal_can_frame_t){ .id = LS_CO_COB_EMCY + 0x21u, .flags = 0, .len = 0, .data = { 0 } };
    assert_false(ls_sync_watch_is_sync(&f));
    f = (hal_can_frame_t){ .id = LS_CO_COB_SYNC, .flags = HAL_CAN_F_EXT, .len = 0, .data = { 0 } };
    assert_false(ls_sync_watch_is_sync(&f));
    f = (hal_can_frame_t){ .id = LS_CO_COB_SYNC, .flags = HAL_CAN_F_RTR, .len = 0, .data = { 0 } };
    assert_false(ls_sync_watch_is_sync(&f));
}

static void test_fewer_than_two_syncs_give_no_figures_and_say_how_many_came(void **state)
{
    (void)state;
    char line[256];
    ls_sync_stats_t s;
    ls_sync_watch_init(&g_w);
    assert_false(ls_sync_watch_stats(&g_w, &s));
    (void)ls_sync_watch_format(&g_w, line, sizeof line);
    assert_string_equal(line, "SYNC intervals as received: none (0 SYNCs)");
    ls_sync_watch_note(&g_w, 5000);
    (void)ls_sync_watch_format(&g_w, line, sizeof line);
    assert_string_equal(line, "SYNC intervals as received: none (1 SYNC)");
}

static void test_the_figures_are_nearest_rank_percentiles_of_the_intervals(void **state)
{
    (void)state;
    ls_sync_watch_init(&g_w);
    /* 100 intervals: 97 of 4000 us, then 3900, 4100 and one late SYNC of 9000 us. */
    uint64_t t = 1000000u;
    ls_sync_watch_note(&g_w, t);
    for (int i = 0; i < 97; i++) {
        ls_sync_watch_note(&g_w, t += 4000u);
    }
    ls_sync_watch_note(&g_w, t += 3900u);
    ls_sync_watch_note(&g_w, t += 4100u);
    ls_sync_watch_note(&g_w, t += 9000u);
    ls_sync_stats_t s;
    assert_true(ls_sync_watch_stats(&g_w, &s));
    assert_int_equal(s.n_intervals, 100);
    assert_int_equal(s.n_kept, 100);
    assert_int_equal(s.median_us, 4000);
    assert_int_equal(s.p99_us, 4100); /* the 99th of 100 sorted */
    assert_int_equal(s.min_us, 3900);
    assert_int_equal(s.max_us, 9000);
    assert_true(s.mean_us > 4049.9 && s.mean_us < 4050.1);
    assert_true(s.span_s > 0.40499 && s.span_s < 0.40501);
    char line[256];
    (void)ls_sync_watch_format(&g_w, line, sizeof line);
    assert_string_equal(line, "SYNC intervals as received: 100 over 0.405 s: median 4000 us, p99 4100 us, min 3900 us, "
                              "max 9000 us, mean 4050.0 us");
}

static void test_a_clock_that_steps_back_counts_as_a_zero_interval_not_a_huge_one(void **state)
{
    (void)state;
    ls_sync_watch_init(&g_w);
    ls_sync_watch_note(&g_w, 10000);
    ls_sync_watch_note(&g_w, 9000);
    ls_sync_watch_note(&g_w, 14000);
    ls_sync_stats_t s;
    assert_true(ls_sync_watch_stats(&g_w, &s));
    assert_int_equal(s.min_us, 0);
    assert_int_equal(s.max_us, 4000);
}

static void test_intervals_beyond_the_array_are_counted_and_the_line_says_how_many_were_kept(void **state)
{
    (void)state;
    ls_sync_watch_init(&g_w);
    uint64_t t = 0;
    for (uint32_t i = 0; i < LS_SYNC_WATCH_MAX + 11u; i++) {
        ls_sync_watch_note(&g_w, t += 1000u);
    }
    ls_sync_stats_t s;
    assert_true(ls_sync_watch_stats(&g_w, &s));
    assert_int_equal(s.n_intervals, LS_SYNC_WATCH_MAX + 10u);
    assert_int_equal(s.n_kept, LS_SYNC_WATCH_MAX);
    char line[256];
    (void)ls_sync_watch_format(&g_w, line, sizeof line);
    char want[64];
    (void)snprintf(want, sizeof want, " (the first %u kept)", LS_SYNC_WATCH_MAX);
    assert_non_null(strstr(line, want));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_only_a_standard_data_frame_at_the_sync_id_with_at_most_a_counter_is_a_sync),
        cmocka_unit_test(test_fewer_than_two_syncs_give_no_figures_and_say_how_many_came),
        cmocka_unit_test(test_the_figures_are_nearest_rank_percentiles_of_the_intervals),
        cmocka_unit_test(test_a_clock_that_steps_back_counts_as_a_zero_interval_not_a_huge_one),
        cmocka_unit_test(test_intervals_beyond_the_array_are_counted_and_the_line_says_how_many_were_kept),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
