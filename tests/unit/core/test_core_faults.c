/* The controller core, black box (core_fixture.h). Faults and floods
 * (docs/protocol.md "Budgets under floods"): an emergency flood stops once,
 * repeats are counted, the fault log keeps the first and the latest. */
#include "core_fixture.h"

/* 500 EMERGENCY frames in a second (docs/reliability.md section 8): the first stops at
 * once and raises one alarm; the repeats post no more stops and send no more
 * alarms, and one alarm at the window's end says how many were suppressed. */
static void test_an_emergency_flood_stops_once_and_counts_the_repeats(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    g_core.act.halt = count_halt;
    g_halt_posts = 0;
    const size_t from = g_nrx;
    const uint64_t t0 = g_now;
    ls_core_emergency(&g_core, t0);
    assert_int_equal(g_halt_posts, 1); /* at once */
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 1);
    assert_int_equal(alarms_to(from, HOST_B, "fault", NULL), 1);
    for (uint64_t i = 1; i < 500; i++) {
        ls_core_emergency(&g_core, t0 + i * 2000u);
        ls_core_tick(&g_core, t0 + i * 2000u);
    }
    assert_int_equal(g_halt_posts, 1);
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 1);
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), NULL), 0);
    assert_int_equal(g_core.emergency_frames, 500);
    assert_int_equal(g_core.alarms_suppressed, 499);
    assert_string_equal(g_core.fault, "emergency stop frame on the bus");
    /* the window ends: one alarm with the count, to everyone */
    ls_core_tick(&g_core, t0 + LS_ALARM_WINDOW_MS * 1000u);
    const ls_Notice *sum = NULL;
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), &sum), 1);
    assert_int_equal(alarms_to(from, HOST_B, ls_EventId_name(ls_EventId_alarmsSuppressed), NULL), 1);
    assert_true(has_data(sum, "suppressed=499"));
    assert_true(has_data(sum, "fault=emergency stop frame on the bus"));
    /* a window without repeats: nothing more */
    ls_core_tick(&g_core, t0 + 2u * LS_ALARM_WINDOW_MS * 1000u + 1u);
    ls_core_tick(&g_core, t0 + 3u * LS_ALARM_WINDOW_MS * 1000u + 2u);
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), NULL), 1);
    /* the fault log: the frame, then the count */
    uint32_t n = 0, dropped = 0;
    assert_string_equal(ls_core_fault_entry(&g_core, 0, &n, &dropped)->text, "emergency stop frame on the bus");
    assert_int_equal(n, 2);
    assert_int_equal(dropped, 0);
    assert_non_null(strstr(ls_core_fault_entry(&g_core, 1, NULL, NULL)->text, "499 repeats suppressed"));
    /* the motion still gets its one final notice */
    loop_stopped();
    ls_run_tick(&g_core, t0 + 3u * LS_ALARM_WINDOW_MS * 1000u + 3u);
    size_t finals = 0;
    assert_non_null(the_final(from, move, &finals));
    assert_int_equal(finals, 1);
    /* after the quiet window the next frame is a new alarm */
    ls_core_emergency(&g_core, t0 + 4u * LS_ALARM_WINDOW_MS * 1000u);
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 2);
}

/* Another alarm inside the window is not a repeat: sent at once, after the
 * count of the window's repeats. */
static void test_a_different_alarm_is_not_suppressed(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    const size_t from = g_nrx;
    ls_core_emergency(&g_core, g_now);
    ls_core_emergency(&g_core, g_now + 1000u);
    ls_core_fault(&g_core, "e-stop input", g_now + 2000u);
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 2);
    const ls_Notice *sum = NULL;
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), &sum), 1);
    assert_true(has_data(sum, "suppressed=1"));
    assert_string_equal(g_core.fault, "e-stop input");
}

/* The first LS_FAULT_LOG_FIRST entries stay (the start of a cascade), then the
 * latest LS_FAULT_LOG_LATEST; sendCommand faults says how many were dropped. */
static void test_the_fault_log_keeps_the_first_and_the_latest(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    for (int i = 0; i < 40; i++) {
        char text[32];
        snprintf(text, sizeof text, "fault %d", i); /* distinct: none is a repeat */
        ls_core_fault(&g_core, text, g_now + (uint64_t)i);
        g_nrx = 0; /* their alarms are not what this test reads */
    }
    uint32_t n = 0, dropped = 0;
    (void)ls_core_fault_entry(&g_core, 0, &n, &dropped);
    assert_int_equal(n, LS_FAULT_LOG_LEN);
    assert_int_equal(dropped, 40 - LS_FAULT_LOG_LEN);
    for (uint32_t k = 0; k < n; k++) {
        char want[32];
        const uint32_t i = k < LS_FAULT_LOG_FIRST ? k : 40u - LS_FAULT_LOG_LEN + k;
        snprintf(want, sizeof want, "fault %u", (unsigned)i);
        assert_string_equal(ls_core_fault_entry(&g_core, k, NULL, NULL)->text, want);
    }
    assert_null(ls_core_fault_entry(&g_core, n, NULL, NULL));
    const char *text = fault_log_text();
    assert_non_null(strstr(text, "logged=40 dropped=24 "));
    assert_non_null(strstr(text, "fault 3\n... 24 entries dropped"));
    assert_non_null(strstr(text, "fault 39\n"));
    assert_null(strstr(text, "fault 27\n"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_emergency_flood_stops_once_and_counts_the_repeats),
        cmocka_unit_test(test_a_different_alarm_is_not_suppressed),
        cmocka_unit_test(test_the_fault_log_keeps_the_first_and_the_latest),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
