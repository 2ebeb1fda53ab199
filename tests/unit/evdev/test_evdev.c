/* hal_linux_evdev: maps, decoding and the backend without a device. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "hal_linux_evdev.h"

static struct input_event ev(uint16_t type, uint16_t code, int32_t value)
{
    struct input_event e;
    memset(&e, 0, sizeof e);
    e.type = type;
    e.code = code;
    e.value = value;
    return e;
}

static hal_evdev_decoder_t gamepad(void)
{
    hal_evdev_map_t m;
    assert_int_equal(hal_evdev_map_default("gamepad", &m), LS_OK);
    hal_evdev_decoder_t d;
    hal_evdev_decoder_init(&d, &m);
    for (int i = 0; i < HAL_EVDEV_AXES; i++) {
        d.abs[i].minimum = -32768;
        d.abs[i].maximum = 32767;
    }
    d.abs[3].minimum = d.abs[4].minimum = -1; /* the d-pad */
    d.abs[3].maximum = d.abs[4].maximum = 1;
    return d;
}

static void test_an_axis_maps_its_range_to_plus_minus_one_with_its_sign(void **state)
{
    (void)state;
    hal_evdev_decoder_t d = gamepad();
    double tw[6];
    assert_int_equal(hal_evdev_decoder_feed(&d, &(struct input_event){ .type = EV_ABS, .code = ABS_X, .value = 32767 }),
                     HAL_EVDEV_FED);
    struct input_event y = ev(EV_ABS, ABS_Y, -32768); /* stick up: y grows downwards */
    (void)hal_evdev_decoder_feed(&d, &y);
    struct input_event hat = ev(EV_ABS, ABS_HAT0Y, -1);
    (void)hal_evdev_decoder_feed(&d, &hat);
    struct input_event syn = ev(EV_SYN, SYN_REPORT, 0);
    assert_int_equal(hal_evdev_decoder_feed(&d, &syn), HAL_EVDEV_REPORT);
    hal_evdev_decoder_twist(&d, tw);
    assert_true(fabs(tw[0] - 1.0) < 1e-4);
    assert_true(tw[1] == 1.0); /* -1 beyond full scale by half a count: clamped */
    assert_true(tw[3] == 1.0); /* the d-pad's -1, inverted */
    assert_true(tw[2] == 0.0 && tw[4] == 0.0 && tw[5] == 0.0);
}

static void test_the_dead_band_is_cut_out_without_a_step(void **state)
{
    (void)state;
    hal_evdev_decoder_t d = gamepad(); /* dead band 0.15 */
    double tw[6];
    const int32_t at[] = { 0, 4000, 4915, 4916, 6000, 16384, 32767 };
    double prev = -1.0;
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        struct input_event e = ev(EV_ABS, ABS_X, at[i]);
        (void)hal_evdev_decoder_feed(&d, &e);
        hal_evdev_decoder_twist(&d, tw);
        const double x = (at[i] + 0.5) / 32767.5;
        const double want = x <= 0.15 ? 0.0 : (x - 0.15) / 0.85;
        assert_true(fabs(tw[0] - want) < 1e-9);
        assert_true(tw[0] >= prev);
        prev = tw[0];
    }
    assert_true(prev > 0.9999);
    /* the kernel's flat zone widens it */
    d.abs[0].flat = 16384;
    struct input_event e = ev(EV_ABS, ABS_X, 16000);
    (void)hal_evdev_decoder_feed(&d, &e);
    hal_evdev_decoder_twist(&d, tw);
    assert_true(tw[0] == 0.0);
    /* an axis with no range (not reported by the device) stays 0 */
    d.abs[0].minimum = d.abs[0].maximum = 0;
    hal_evdev_decoder_twist(&d, tw);
    assert_true(tw[0] == 0.0);
}

static void test_a_relative_axis_divides_by_its_full_scale_and_holds(void **state)
{
    (void)state;
    hal_evdev_map_t m;
    memset(&m, 0, sizeof m);
    assert_int_equal(hal_evdev_parse_axes(&m, "wz:-REL_RZ:2:0", NULL, 0), LS_OK);
    hal_evdev_decoder_t d;
    hal_evdev_decoder_init(&d, &m);
    struct input_event e = ev(EV_REL, REL_RZ, 35);
    (void)hal_evdev_decoder_feed(&d, &e);
    double tw[6];
    hal_evdev_decoder_twist(&d, tw);
    assert_true(fabs(tw[5] - (-2.0 * 35.0 / HAL_EVDEV_REL_FULL_SCALE)) < 1e-12);
    hal_evdev_decoder_twist(&d, tw); /* no new report: the same */
    assert_true(fabs(tw[5] + 0.2) < 1e-12);
}

static void test_buttons_follow_their_keys_and_other_codes_are_ignored(void **state)
{
    (void)state;
    hal_evdev_decoder_t d = gamepad();
    struct input_event e = ev(EV_KEY, BTN_TL, 1);
    (void)hal_evdev_decoder_feed(&d, &e);
    e = ev(EV_KEY, BTN_WEST, 2); /* autorepeat counts as held */
    (void)hal_evdev_decoder_feed(&d, &e);
    e = ev(EV_KEY, BTN_START, 1); /* not mapped */
    (void)hal_evdev_decoder_feed(&d, &e);
    e = ev(EV_ABS, ABS_Z, 1000); /* not mapped */
    (void)hal_evdev_decoder_feed(&d, &e);
    assert_int_equal(d.buttons, HAL_MANUAL_BTN_ENABLE | HAL_MANUAL_BTN_FRAME);
    e = ev(EV_KEY, BTN_TL, 0);
    (void)hal_evdev_decoder_feed(&d, &e);
    assert_int_equal(d.buttons, HAL_MANUAL_BTN_FRAME);
}

static void test_after_syn_dropped_events_wait_for_a_resync(void **state)
{
    (void)state;
    hal_evdev_decoder_t d = gamepad();
    struct input_event e = ev(EV_SYN, SYN_DROPPED, 0);
    assert_int_equal(hal_evdev_decoder_feed(&d, &e), HAL_EVDEV_FED);
    e = ev(EV_KEY, BTN_TL, 1); /* of a report that lost events: ignored */
    (void)hal_evdev_decoder_feed(&d, &e);
    assert_int_equal(d.buttons, 0u);
    e = ev(EV_SYN, SYN_REPORT, 0);
    assert_int_equal(hal_evdev_decoder_feed(&d, &e), HAL_EVDEV_RESYNC);
    e = ev(EV_KEY, BTN_TL, 1);
    (void)hal_evdev_decoder_feed(&d, &e);
    e = ev(EV_SYN, SYN_REPORT, 0);
    assert_int_equal(hal_evdev_decoder_feed(&d, &e), HAL_EVDEV_REPORT);
    assert_int_equal(d.buttons, HAL_MANUAL_BTN_ENABLE);
}

static void test_maps_format_back_to_what_parses(void **state)
{
    (void)state;
    const char *names[] = { "gamepad", "spacemouse" };
    for (size_t i = 0; i < 2; i++) {
        hal_evdev_map_t m, back;
        assert_int_equal(hal_evdev_map_default(names[i], &m), LS_OK);
        m.axis[2].scale = -0.5;
        m.axis[1].deadband = 0.25;
        char axes[256], buttons[256];
        hal_evdev_format_axes(&m, axes, sizeof axes);
        hal_evdev_format_buttons(&m, buttons, sizeof buttons);
        memset(&back, 0, sizeof back);
        back.deadband = m.deadband;
        assert_int_equal(hal_evdev_parse_axes(&back, axes, NULL, 0), LS_OK);
        assert_int_equal(hal_evdev_parse_buttons(&back, buttons, NULL, 0), LS_OK);
        assert_memory_equal(&back, &m, sizeof m);
    }
    hal_evdev_map_t m;
    assert_int_equal(hal_evdev_map_default("gamepad", &m), LS_OK);
    char text[256];
    hal_evdev_format_axes(&m, text, sizeof text);
    assert_string_equal(text, "vx:ABS_X, vy:-ABS_Y, vz:-ABS_RY, wx:-ABS_HAT0Y, wy:ABS_HAT0X, wz:-ABS_RX");
    hal_evdev_format_buttons(&m, text, sizeof text);
    /* names as the kernel's header spells them (BTN_SOUTH is also BTN_A) */
    assert_non_null(strstr(text, "enable:BTN_TL"));
    memset(&m, 0, sizeof m);
    hal_evdev_format_buttons(&m, text, sizeof text);
    assert_string_equal(text, "none");
    assert_int_equal(hal_evdev_map_default("joystick", &m), LS_EINVAL);
    assert_string_equal(hal_evdev_map_names(), "gamepad, spacemouse");
}

static void test_a_refused_map_text_leaves_the_map_as_it_was(void **state)
{
    (void)state;
    hal_evdev_map_t m, before;
    assert_int_equal(hal_evdev_map_default("spacemouse", &m), LS_OK);
    before = m;
    char why[512];
    assert_int_equal(hal_evdev_parse_axes(&m, "vx:ABS_X, vy:KEY_A", why, sizeof why), LS_EINVAL);
    assert_non_null(strstr(why, "vy: 'KEY_A' is no ABS_* or REL_* axis"));
    assert_int_equal(hal_evdev_parse_axes(&m, " , ", why, sizeof why), LS_EINVAL);
    assert_non_null(strstr(why, "(an empty item)"));
    assert_int_equal(hal_evdev_parse_axes(&m, " ", why, sizeof why), LS_EINVAL);
    assert_non_null(strstr(why, "(none given)"));
    char longitem[200];
    memset(longitem, 'x', sizeof longitem - 1);
    longitem[sizeof longitem - 1] = '\0';
    assert_int_equal(hal_evdev_parse_buttons(&m, longitem, why, sizeof why), LS_EINVAL);
    assert_non_null(strstr(why, "is too long"));
    assert_memory_equal(&m, &before, sizeof m);
    assert_int_equal(hal_evdev_parse_buttons(&m, "", why, sizeof why), LS_OK); /* no buttons at all */
    assert_int_equal(m.button[HAL_MANUAL_FN_FRAME], 0);
}

/* ---- the backend without a device ---- */

static void test_a_device_not_there_yet_opens_absent_and_closes_at_once(void **state)
{
    (void)state;
    hal_evdev_config_t cfg = { .path = "/nonexistent/by-id/pad-event-joystick", .stale_ms = 0 };
    assert_int_equal(hal_evdev_map_default("gamepad", &cfg.map), LS_OK);
    hal_manual_t dev;
    char msg[256];
    assert_int_equal(hal_linux_evdev_open(&dev, &cfg, msg, sizeof msg), LS_OK);
    assert_string_equal(dev.name, cfg.path);
    hal_manual_state_t st;
    for (int i = 0; i < 3; i++) {
        assert_int_equal(hal_manual_read(&dev, &st), LS_OK);
        assert_false(st.present);
        assert_int_equal(st.buttons, 0u);
    }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    hal_linux_evdev_close(&dev);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    const double s = (double)(t1.tv_sec - t0.tv_sec) + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-9;
    assert_true(s < 0.1); /* the thread wakes for the stop, not after its retry period */
    assert_null(dev.read);
    hal_linux_evdev_close(&dev); /* twice: nothing */
}

static void test_open_refuses_bad_configurations_and_a_full_pool(void **state)
{
    (void)state;
    hal_evdev_config_t cfg = { .path = "/dev/input/event-x", .stale_ms = 0 };
    memset(&cfg.map, 0, sizeof cfg.map);
    hal_manual_t dev[HAL_EVDEV_MAX_DEVICES + 1];
    char msg[256];
    assert_int_equal(hal_linux_evdev_open(&dev[0], &cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "the map has no axis"));
    assert_int_equal(hal_evdev_map_default("spacemouse", &cfg.map), LS_OK);
    cfg.path = "";
    assert_int_equal(hal_linux_evdev_open(&dev[0], &cfg, msg, sizeof msg), LS_EINVAL);
    char longpath[HAL_MANUAL_NAME_LEN + 8];
    memset(longpath, 'a', sizeof longpath - 1);
    longpath[0] = '/';
    longpath[sizeof longpath - 1] = '\0';
    cfg.path = longpath;
    assert_int_equal(hal_linux_evdev_open(&dev[0], &cfg, msg, sizeof msg), LS_EINVAL);
    cfg.path = "/nonexistent/a";
    for (int i = 0; i < HAL_EVDEV_MAX_DEVICES; i++) {
        assert_int_equal(hal_linux_evdev_open(&dev[i], &cfg, msg, sizeof msg), LS_OK);
    }
    assert_int_equal(hal_linux_evdev_open(&dev[HAL_EVDEV_MAX_DEVICES], &cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "at most 2 evdev devices"));
    for (int i = 0; i < HAL_EVDEV_MAX_DEVICES; i++) {
        hal_linux_evdev_close(&dev[i]);
    }
}

static void test_probe_names_what_is_wrong(void **state)
{
    (void)state;
    hal_evdev_map_t m;
    assert_int_equal(hal_evdev_map_default("gamepad", &m), LS_OK);
    char msg[512];
    assert_int_equal(hal_linux_evdev_probe("/nonexistent/pad", &m, msg, sizeof msg), LS_ENODEV);
    assert_non_null(strstr(msg, "plug the device in"));
    assert_int_equal(hal_linux_evdev_probe("/dev/null", &m, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "not an input event device"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_axis_maps_its_range_to_plus_minus_one_with_its_sign),
        cmocka_unit_test(test_the_dead_band_is_cut_out_without_a_step),
        cmocka_unit_test(test_a_relative_axis_divides_by_its_full_scale_and_holds),
        cmocka_unit_test(test_buttons_follow_their_keys_and_other_codes_are_ignored),
        cmocka_unit_test(test_after_syn_dropped_events_wait_for_a_resync),
        cmocka_unit_test(test_maps_format_back_to_what_parses),
        cmocka_unit_test(test_a_refused_map_text_leaves_the_map_as_it_was),
        cmocka_unit_test(test_a_device_not_there_yet_opens_absent_and_closes_at_once),
        cmocka_unit_test(test_open_refuses_bad_configurations_and_a_full_pool),
        cmocka_unit_test(test_probe_names_what_is_wrong),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
