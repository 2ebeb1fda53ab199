/* ls_manual: the gate between a manual device and the jog, cycle by cycle
 * on hand-made device states (no loop, no clock: the age comes with the
 * state). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "ls_manual.h"

static const ls_manual_config_t PENDANT = {
    .enabling_switch = true,
    .stale_us = 0,
    .n_steps = 4,
    .step_pct = { 10, 25, 50, 100 },
    .start_step = 3,
};

/* A device that is there, pushed along x, with these buttons held. */
static hal_manual_state_t dev(uint32_t buttons, double vx)
{
    hal_manual_state_t st;
    memset(&st, 0, sizeof st);
    st.present = true;
    st.generation = 1;
    st.buttons = buttons;
    st.twist[0] = vx;
    return st;
}

/* One step; returns the twist's x and the events. */
static double step(ls_manual_t *m, hal_manual_state_t st, ls_manual_events_t *ev)
{
    double tw[6];
    ev->n = 0;
    (void)ls_manual_step(m, &st, LS_OK, tw, ev);
    return tw[0];
}

static int count(const ls_manual_events_t *ev, ls_manual_event_kind_t kind, int32_t value)
{
    int n = 0;
    for (uint8_t i = 0; i < ev->n; i++) {
        n += ev->ev[i].kind == kind && ev->ev[i].value == value;
    }
    return n;
}

/* Switched on, the switch seen released, then pressed: jogging at full x. */
static void jogging(ls_manual_t *m, const ls_manual_config_t *cfg, ls_manual_events_t *ev)
{
    ls_manual_start(m, cfg);
    (void)step(m, dev(0, 0), ev);
    assert_true(step(m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), ev) == 1.0);
}

static void test_the_pendant_jogs_only_while_its_enabling_switch_is_held(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &PENDANT);
    assert_true(step(&m, dev(0, 0.8), &ev) == 0.0); /* pushed, switch released */
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 0.8), &ev) == 0.8);
    assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_ENABLED), 1);
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, -0.5), &ev) == -0.5);
    assert_int_equal(ev.n, 0);                       /* held: nothing new to report */
    assert_true(step(&m, dev(0, -0.5), &ev) == 0.0); /* released: stops at once */
    assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_RELEASED), 1);
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 0.3), &ev) == 0.3); /* pressed again */
}

static void test_a_switch_held_at_switch_on_starts_nothing_until_pressed_again(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &PENDANT);
    for (int i = 0; i < 100; i++) {
        assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), &ev) == 0.0);
        if (i == 0) {
            assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_HELD_OVER), 1);
        }
    }
    assert_true(step(&m, dev(0, 1.0), &ev) == 0.0);
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), &ev) == 1.0);
}

static void test_a_switch_held_when_the_drives_come_on_must_be_pressed_again(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    jogging(&m, &PENDANT, &ev);
    ls_manual_block(&m); /* drives on */
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_HELD_OVER), 1);
    (void)step(&m, dev(0, 1.0), &ev);
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), &ev) == 1.0);
}

static void test_the_third_position_stops_and_only_a_full_release_rearms(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    jogging(&m, &PENDANT, &ev);
    /* pressed through: a real switch reports both contacts, or the third alone */
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE | HAL_MANUAL_BTN_PANIC, 1.0), &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_PANIC), 1);
    assert_true(step(&m, dev(HAL_MANUAL_BTN_PANIC, 1.0), &ev) == 0.0);
    /* letting go passes the middle position on the way out: not a press */
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_HELD_OVER), 1);
    assert_true(step(&m, dev(0, 1.0), &ev) == 0.0);
    assert_true(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 1.0), &ev) == 1.0);
}

static void test_an_unplugged_device_stops_alarms_once_and_needs_a_new_press(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    jogging(&m, &PENDANT, &ev);
    hal_manual_state_t gone;
    memset(&gone, 0, sizeof gone);
    gone.generation = 1;
    assert_true(step(&m, gone, &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_LOST, LS_MANUAL_LOST_ABSENT), 1);
    assert_true(step(&m, gone, &ev) == 0.0);
    assert_int_equal(ev.n, 0); /* once */
    /* back (re-plugged: a new generation) with the switch still held */
    hal_manual_state_t back = dev(HAL_MANUAL_BTN_ENABLE, 1.0);
    back.generation = 2;
    assert_true(step(&m, back, &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_FOUND, 2), 1);
    assert_int_equal(count(&ev, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_HELD_OVER), 1);
    back.buttons = 0;
    (void)step(&m, back, &ev);
    back.buttons = HAL_MANUAL_BTN_ENABLE;
    assert_true(step(&m, back, &ev) == 1.0);
}

static void test_a_device_replugged_between_two_reads_counts_as_lost_and_found(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    jogging(&m, &PENDANT, &ev);
    hal_manual_state_t again = dev(HAL_MANUAL_BTN_ENABLE, 1.0);
    again.generation = 2;
    assert_true(step(&m, again, &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_LOST, LS_MANUAL_LOST_ABSENT), 1);
    assert_int_equal(count(&ev, LS_MANUAL_EV_FOUND, 2), 1);
}

static void test_a_silent_continuous_device_is_lost_after_its_stated_time(void **state)
{
    (void)state;
    ls_manual_config_t cfg = PENDANT;
    cfg.stale_us = 200000;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &cfg);
    (void)step(&m, dev(0, 0), &ev);
    hal_manual_state_t st = dev(HAL_MANUAL_BTN_ENABLE, 1.0);
    st.age_us = 200000; /* just within */
    assert_true(step(&m, st, &ev) == 1.0);
    st.age_us = 200001;
    assert_true(step(&m, st, &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_LOST, LS_MANUAL_LOST_SILENT), 1);
    st.age_us = 1000; /* reports again: found, but the switch was held through */
    assert_true(step(&m, st, &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_FOUND, 1), 1);
    /* a device that reports changes only is never silent */
    ls_manual_start(&m, &PENDANT);
    (void)step(&m, dev(0, 0), &ev);
    st.age_us = 3600u * 1000000u;
    assert_true(step(&m, st, &ev) == 1.0);
}

static void test_a_failed_read_stops_and_a_device_missing_at_switch_on_is_reported(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &PENDANT);
    hal_manual_state_t st = dev(HAL_MANUAL_BTN_ENABLE, 1.0);
    double tw[6] = { 9, 9, 9, 9, 9, 9 };
    ev.n = 0;
    assert_false(ls_manual_step(&m, &st, LS_EIO, tw, &ev));
    assert_true(tw[0] == 0.0 && tw[5] == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_LOST, LS_MANUAL_LOST_READ), 1);
    ls_manual_start(&m, &PENDANT);
    hal_manual_state_t none;
    memset(&none, 0, sizeof none);
    assert_true(step(&m, none, &ev) == 0.0);
    assert_int_equal(count(&ev, LS_MANUAL_EV_LOST, LS_MANUAL_LOST_ABSENT), 1);
    assert_false(ls_manual_step(NULL, &st, LS_OK, tw, &ev));
    assert_false(ls_manual_step(&m, &st, LS_OK, NULL, &ev));
}

static void test_a_mouse_without_a_switch_jogs_once_it_was_still(void **state)
{
    (void)state;
    ls_manual_config_t cfg = { .enabling_switch = false };
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &cfg);
    assert_true(step(&m, dev(0, 0.7), &ev) == 0.0); /* deflected at switch-on */
    assert_true(step(&m, dev(0, 0.0), &ev) == 0.0);
    assert_true(step(&m, dev(0, 0.7), &ev) == 0.7);
    assert_int_equal(ls_manual_override_pct(&m), 100); /* no steps: 100 % */
    hal_manual_state_t gone;
    memset(&gone, 0, sizeof gone);
    (void)step(&m, gone, &ev);
    hal_manual_state_t back = dev(0, 0.7);
    back.generation = 2;
    assert_true(step(&m, back, &ev) == 0.0); /* back deflected: waits for still */
    back.twist[0] = 0.0;
    (void)step(&m, back, &ev);
    back.twist[0] = -0.2;
    assert_true(step(&m, back, &ev) == -0.2);
}

static void test_the_override_steps_scale_the_twist_and_stop_at_the_ends(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &PENDANT);
    (void)step(&m, dev(0, 0), &ev);
    assert_int_equal(ls_manual_override_pct(&m), 100);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_UP, 0), &ev); /* at the top: nothing */
    assert_int_equal(ev.n, 0);
    (void)step(&m, dev(0, 0), &ev);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_DOWN, 0), &ev);
    assert_int_equal(count(&ev, LS_MANUAL_EV_OVERRIDE, 50), 1);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_DOWN, 0), &ev); /* held: one press */
    assert_int_equal(ev.n, 0);
    (void)step(&m, dev(0, 0), &ev);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_DOWN, 0), &ev);
    (void)step(&m, dev(0, 0), &ev);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_DOWN, 0), &ev);
    assert_int_equal(count(&ev, LS_MANUAL_EV_OVERRIDE, 10), 1);
    (void)step(&m, dev(0, 0), &ev);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_DOWN, 0), &ev);
    assert_int_equal(ev.n, 0);
    assert_true(fabs(step(&m, dev(HAL_MANUAL_BTN_ENABLE, 0.5), &ev) - 0.05) < 1e-15);
}

static void test_buttons_held_at_switch_on_are_no_presses(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &PENDANT);
    (void)step(&m, dev(HAL_MANUAL_BTN_SPEED_DOWN | HAL_MANUAL_BTN_FRAME, 0), &ev);
    assert_int_equal(ev.n, 0);
    (void)step(&m, dev(0, 0), &ev);
    (void)step(&m, dev(HAL_MANUAL_BTN_FRAME, 0), &ev);
    assert_int_equal(count(&ev, LS_MANUAL_EV_FRAME, LS_JOG_BASE), 1);
}

static void test_the_frame_button_cycles_and_joint_mode_toggles(void **state)
{
    (void)state;
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &PENDANT);
    (void)step(&m, dev(0, 0), &ev);
    const ls_jog_frame_t want[] = { LS_JOG_BASE, LS_JOG_WORLD, LS_JOG_TOOL, LS_JOG_BASE };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        (void)step(&m, dev(HAL_MANUAL_BTN_FRAME, 0), &ev);
        assert_int_equal(ev.n, 1);
        assert_int_equal(ev.ev[0].value, want[i]);
        assert_false(ev.ev[0].joint);
        (void)step(&m, dev(0, 0), &ev);
    }
    (void)step(&m, dev(HAL_MANUAL_BTN_JOINT, 0), &ev);
    assert_true(ls_manual_joint(&m));
    assert_true(ev.ev[0].joint);
    (void)step(&m, dev(0, 0), &ev);
    (void)step(&m, dev(HAL_MANUAL_BTN_FRAME, 0), &ev); /* frame in joint mode: back to Cartesian, same frame */
    assert_false(ls_manual_joint(&m));
    assert_int_equal(ls_manual_frame(&m), LS_JOG_BASE);
    assert_string_equal(ls_manual_frame_name(ls_manual_frame(&m)), "base");
}

static void test_steps_are_sorted_and_bad_ones_dropped(void **state)
{
    (void)state;
    ls_manual_config_t cfg = {
        .enabling_switch = false, .n_steps = 6, .step_pct = { 50, 0, 10, 101, 50, 25 }, .start_step = 7
    };
    ls_manual_t m;
    ls_manual_start(&m, &cfg);
    assert_int_equal(m.cfg.n_steps, 3);
    assert_int_equal(m.cfg.step_pct[0], 10);
    assert_int_equal(m.cfg.step_pct[1], 25);
    assert_int_equal(m.cfg.step_pct[2], 50);
    assert_int_equal(ls_manual_override_pct(&m), 50); /* start clamped to the last */
    ls_manual_start(&m, NULL);
    assert_int_equal(ls_manual_override_pct(&m), 100);
    assert_false(m.cfg.enabling_switch);
}

static void test_a_twist_out_of_range_or_not_finite_is_clamped_or_zeroed(void **state)
{
    (void)state;
    ls_manual_config_t cfg = { .enabling_switch = false };
    ls_manual_t m;
    ls_manual_events_t ev;
    ls_manual_start(&m, &cfg);
    (void)step(&m, dev(0, 0), &ev);
    hal_manual_state_t st = dev(0, 5.0);
    st.twist[1] = -INFINITY;
    st.twist[2] = NAN;
    double tw[6];
    assert_true(ls_manual_step(&m, &st, LS_OK, tw, &ev));
    assert_true(tw[0] == 1.0 && tw[1] == 0.0 && tw[2] == 0.0);
}

static void test_names_cover_every_value(void **state)
{
    (void)state;
    assert_string_equal(ls_manual_switch_name(LS_MANUAL_SWITCH_HELD_OVER), "held_over");
    assert_string_equal(ls_manual_switch_name((ls_manual_switch_t)99), "unknown");
    assert_string_equal(ls_manual_lost_name(LS_MANUAL_LOST_SILENT), "silent");
    assert_string_equal(ls_manual_lost_name((ls_manual_lost_t)0), "unknown");
    assert_string_equal(ls_manual_frame_name(LS_JOG_WORLD), "world");
    assert_string_equal(ls_manual_frame_name((ls_jog_frame_t)7), "unknown");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_pendant_jogs_only_while_its_enabling_switch_is_held),
        cmocka_unit_test(test_a_switch_held_at_switch_on_starts_nothing_until_pressed_again),
        cmocka_unit_test(test_a_switch_held_when_the_drives_come_on_must_be_pressed_again),
        cmocka_unit_test(test_the_third_position_stops_and_only_a_full_release_rearms),
        cmocka_unit_test(test_an_unplugged_device_stops_alarms_once_and_needs_a_new_press),
        cmocka_unit_test(test_a_device_replugged_between_two_reads_counts_as_lost_and_found),
        cmocka_unit_test(test_a_silent_continuous_device_is_lost_after_its_stated_time),
        cmocka_unit_test(test_a_failed_read_stops_and_a_device_missing_at_switch_on_is_reported),
        cmocka_unit_test(test_a_mouse_without_a_switch_jogs_once_it_was_still),
        cmocka_unit_test(test_the_override_steps_scale_the_twist_and_stop_at_the_ends),
        cmocka_unit_test(test_buttons_held_at_switch_on_are_no_presses),
        cmocka_unit_test(test_the_frame_button_cycles_and_joint_mode_toggles),
        cmocka_unit_test(test_steps_are_sorted_and_bad_ones_dropped),
        cmocka_unit_test(test_a_twist_out_of_range_or_not_finite_is_clamped_or_zeroed),
        cmocka_unit_test(test_names_cover_every_value),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
