/* hal/hal.c: the wrappers every caller goes through. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "hal/hal_arm.h"
#include "hal/hal_can.h"
#include "hal/hal_clock.h"
#include "hal/hal_dio.h"
#include "hal/hal_manual.h"

static void test_null_entries_are_unsupported(void **state)
{
    (void)state;
    static const hal_can_ops_t can_ops; /* all NULL */
    static const hal_dio_ops_t dio_ops;
    static const hal_arm_ops_t arm_ops;
    int self = 0;
    hal_can_link_t link = { .ops = &can_ops, .self = &self, .name = "x" };
    hal_dio_t dio = { .ops = &dio_ops, .self = &self, .name = "x" };
    hal_arm_t arm = { .ops = &arm_ops, .self = &self, .name = "x" };
    hal_can_frame_t f = { 0 };
    hal_can_status_t cs;
    hal_dio_unit_info_t di;
    uint32_t bits;
    hal_arm_info_t ai;
    double q[HAL_ARM_MAX_JOINTS] = { 0 };

    /* Same answers for an ops table of NULLs, no ops table and no device. */
    hal_can_link_t no_ops = { .ops = NULL, .self = &self };
    hal_can_link_t *links[] = { &link, &no_ops, NULL };
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(hal_can_send(links[i], &f), LS_EUNSUPPORTED);
        assert_int_equal(hal_can_recv(links[i], &f), LS_EUNSUPPORTED);
        assert_int_equal(hal_can_poll_fd(links[i]), -1);
        assert_int_equal(hal_can_status(links[i], &cs), LS_EUNSUPPORTED);
        assert_int_equal(hal_can_hold_open(links[i], true), LS_EUNSUPPORTED);
        hal_can_close(links[i]);
    }
    hal_dio_t dio_no_ops = { .ops = NULL, .self = &self };
    hal_dio_t *dios[] = { &dio, &dio_no_ops, NULL };
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(hal_dio_unit_count(dios[i]), LS_EUNSUPPORTED);
        assert_int_equal(hal_dio_describe(dios[i], 0, &di), LS_EUNSUPPORTED);
        assert_int_equal(hal_dio_read(dios[i], 0, &bits), LS_EUNSUPPORTED);
        assert_int_equal(hal_dio_write(dios[i], 0, 1u, 0u), LS_EUNSUPPORTED);
        assert_int_equal(hal_dio_poll_fd(dios[i]), -1);
        assert_int_equal(hal_dio_drain_events(dios[i]), LS_EUNSUPPORTED);
        hal_dio_close(dios[i]);
    }
    assert_int_equal(hal_arm_info(&arm, &ai), LS_EUNSUPPORTED);
    assert_int_equal(hal_arm_enable(&arm, true), LS_EUNSUPPORTED);
    assert_int_equal(hal_arm_command(&arm, q, q), LS_EUNSUPPORTED);
    assert_int_equal(hal_arm_read(&arm, q, q), LS_EUNSUPPORTED);
    hal_arm_close(&arm);
    hal_arm_close(NULL);
    assert_int_equal(self, 0);
}

/* A fake backend that records what reached it. */
typedef struct {
    void *self_seen;
    const hal_can_frame_t *frame_seen;
    uint16_t unit_seen;
    uint32_t on_seen, off_seen;
    int closes;
} fake_t;

static int fake_send(void *self, const hal_can_frame_t *frame)
{
    fake_t *f = self;
    f->self_seen = self;
    f->frame_seen = frame;
    return LS_EAGAIN;
}
static int fake_recv(void *self, hal_can_frame_t *frame)
{
    (void)self;
    frame->id = 0x7E8;
    return 1;
}
static int fake_poll_fd(void *self)
{
    (void)self;
    return 42;
}
static void fake_close(void *self)
{
    ((fake_t *)self)->closes++;
}
static int fake_write(void *self, uint16_t unit, uint32_t on, uint32_t off)
{
    fake_t *f = self;
    f->unit_seen = unit;
    f->on_seen = on;
    f->off_seen = off;
    return LS_EINVAL;
}
static int fake_dio_poll_fd(void *self)
{
    (void)self;
    return LS_EIO; /* a failing poll_fd passes through, only "unsupported" becomes -1 */
}
static uint64_t fake_now(void *self)
{
    return *(const uint64_t *)self;
}

static void test_present_entries_pass_through(void **state)
{
    (void)state;
    fake_t fk = { 0 };
    static const hal_can_ops_t can_ops = {
        .send = fake_send, .recv = fake_recv, .poll_fd = fake_poll_fd, .close = fake_close
    };
    static const hal_dio_ops_t dio_ops = { .write = fake_write, .poll_fd = fake_dio_poll_fd, .close = fake_close };
    hal_can_link_t link = { .ops = &can_ops, .self = &fk };
    hal_dio_t dio = { .ops = &dio_ops, .self = &fk };
    hal_can_frame_t f = { .id = 1 };

    assert_int_equal(hal_can_send(&link, &f), LS_EAGAIN);
    assert_ptr_equal(fk.self_seen, &fk);
    assert_ptr_equal(fk.frame_seen, &f);
    assert_int_equal(hal_can_recv(&link, &f), 1);
    assert_int_equal(f.id, 0x7E8);
    assert_int_equal(hal_can_poll_fd(&link), 42);
    hal_can_status_t cs;
    assert_int_equal(hal_can_status(&link, &cs), LS_EUNSUPPORTED);
    hal_can_close(&link);
    assert_int_equal(fk.closes, 1);

    assert_int_equal(hal_dio_write(&dio, 3, 0x10000u, 0x2u), LS_EINVAL);
    assert_int_equal(fk.unit_seen, 3);
    assert_int_equal(fk.on_seen, 0x10000u);
    assert_int_equal(fk.off_seen, 0x2u);
    assert_int_equal(hal_dio_poll_fd(&dio), LS_EIO);
    hal_dio_close(&dio);
    assert_int_equal(fk.closes, 2);

    uint64_t t = 123456789u;
    hal_clock_t clk = { .now_us = fake_now, .self = &t };
    assert_int_equal(hal_clock_now_us(&clk), 123456789u);
}

static void test_strerror_names_every_status(void **state)
{
    (void)state;
    assert_string_equal(ls_err_text(LS_OK), "ok");
    assert_string_equal(ls_err_text(5), "ok");
    assert_string_equal(ls_err_text(LS_EUNSUPPORTED), "not supported by this backend");
    assert_string_equal(ls_err_text(LS_EAGAIN), "try again");
    assert_string_equal(ls_err_text(LS_EIO), "device I/O error");
    assert_string_equal(ls_err_text(LS_EINVAL), "invalid argument for this device");
    assert_string_equal(ls_err_text(LS_ENODEV), "no such device");
    assert_string_equal(ls_err_text(LS_EPERM), "permission denied");
    assert_string_equal(ls_err_text(LS_EBUSOFF), "CAN bus-off");
    assert_string_equal(ls_err_text(LS_ENOAFCAN), "kernel has no AF_CAN support");
    assert_string_equal(ls_err_text(-99), "unknown error");
    /* one error space: every code has its own value and name (ls_err.h) */
    const int codes[] = { LS_EUNSUPPORTED, LS_EAGAIN,   LS_EIO,    LS_EINVAL, LS_ENODEV,    LS_EPERM,
                          LS_EBUSOFF,      LS_ENOAFCAN, LS_EBUSY,  LS_ELEN,   LS_ETIME,     LS_EUNREACHABLE,
                          LS_ESINGULAR,    LS_ELIMITS,  LS_ERANGE, LS_EGEOM,  LS_ETIMEDOUT, LS_EABORTED,
                          LS_EPROTO,       LS_ESTATE,   LS_ENOSPC, LS_ENOENT, LS_EAUTH };
    const size_t n = sizeof codes / sizeof codes[0];
    for (size_t i = 0; i < n; i++) {
        assert_true(codes[i] < 0);
        assert_string_not_equal(ls_err_name(codes[i]), "LS_E?");
        assert_string_not_equal(ls_err_text(codes[i]), "unknown error");
        for (size_t j = 0; j < i; j++) {
            assert_int_not_equal(codes[i], codes[j]);
            assert_string_not_equal(ls_err_name(codes[i]), ls_err_name(codes[j]));
        }
    }
    assert_string_equal(ls_err_name(LS_EAGAIN), "LS_EAGAIN");
    assert_string_equal(ls_err_name(LS_OK), "LS_OK");
    assert_string_equal(ls_err_name(-99), "LS_E?");
}

static int manual_read_fake(void *self, hal_manual_state_t *out)
{
    int *mode = self;
    out->twist[2] = 0.5;
    out->buttons = HAL_MANUAL_BTN_ENABLE;
    out->present = true;
    return *mode == 0 ? LS_OK : LS_EIO;
}

static void test_manual_read_passes_through_and_zeroes_on_error(void **state)
{
    (void)state;
    int mode = 0;
    hal_manual_t dev = { .read = manual_read_fake, .self = &mode, .stale_ms = 0, .name = "fake" };
    hal_manual_state_t st;
    assert_int_equal(hal_manual_read(&dev, &st), LS_OK);
    assert_true(st.present);
    assert_int_equal(st.buttons, HAL_MANUAL_BTN_ENABLE);
    assert_true(st.twist[2] == 0.5);
    mode = 1; /* an error leaves no half-read state behind */
    assert_int_equal(hal_manual_read(&dev, &st), LS_EIO);
    assert_false(st.present);
    assert_int_equal(st.buttons, 0u);
    assert_true(st.twist[2] == 0.0);
    hal_manual_t none = { .read = NULL };
    assert_int_equal(hal_manual_read(&none, &st), LS_EUNSUPPORTED);
    assert_int_equal(hal_manual_read(NULL, &st), LS_EUNSUPPORTED);
    assert_false(st.present);
    assert_int_equal(hal_manual_read(&dev, NULL), LS_EINVAL);
}

static void test_manual_names_follow_the_bits_and_components(void **state)
{
    (void)state;
    assert_string_equal(hal_manual_button_name(0), "enable");
    assert_int_equal(HAL_MANUAL_BTN_PANIC, 1u << 1);
    assert_string_equal(hal_manual_button_name(1), "panic");
    assert_int_equal(HAL_MANUAL_BTN_JOINT, 1u << (HAL_MANUAL_BTN_COUNT - 1));
    assert_string_equal(hal_manual_button_name(HAL_MANUAL_BTN_COUNT - 1), "joint");
    assert_null(hal_manual_button_name(HAL_MANUAL_BTN_COUNT));
    assert_string_equal(hal_manual_axis_name(0), "vx");
    assert_string_equal(hal_manual_axis_name(5), "wz");
    assert_null(hal_manual_axis_name(6));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_null_entries_are_unsupported),
        cmocka_unit_test(test_present_entries_pass_through),
        cmocka_unit_test(test_strerror_names_every_status),
        cmocka_unit_test(test_manual_read_passes_through_and_zeroes_on_error),
        cmocka_unit_test(test_manual_names_follow_the_bits_and_components),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
