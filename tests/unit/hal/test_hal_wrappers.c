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
        assert_int_equal(hal_can_send(links[i], &f), HAL_EUNSUPPORTED);
        assert_int_equal(hal_can_recv(links[i], &f), HAL_EUNSUPPORTED);
        assert_int_equal(hal_can_poll_fd(links[i]), -1);
        assert_int_equal(hal_can_status(links[i], &cs), HAL_EUNSUPPORTED);
        assert_int_equal(hal_can_hold_open(links[i], true), HAL_EUNSUPPORTED);
        hal_can_close(links[i]);
    }
    hal_dio_t dio_no_ops = { .ops = NULL, .self = &self };
    hal_dio_t *dios[] = { &dio, &dio_no_ops, NULL };
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(hal_dio_unit_count(dios[i]), HAL_EUNSUPPORTED);
        assert_int_equal(hal_dio_describe(dios[i], 0, &di), HAL_EUNSUPPORTED);
        assert_int_equal(hal_dio_read(dios[i], 0, &bits), HAL_EUNSUPPORTED);
        assert_int_equal(hal_dio_write(dios[i], 0, 1u, 0u), HAL_EUNSUPPORTED);
        assert_int_equal(hal_dio_poll_fd(dios[i]), -1);
        assert_int_equal(hal_dio_drain_events(dios[i]), HAL_EUNSUPPORTED);
        hal_dio_close(dios[i]);
    }
    assert_int_equal(hal_arm_info(&arm, &ai), HAL_EUNSUPPORTED);
    assert_int_equal(hal_arm_enable(&arm, true), HAL_EUNSUPPORTED);
    assert_int_equal(hal_arm_command(&arm, q, q), HAL_EUNSUPPORTED);
    assert_int_equal(hal_arm_read(&arm, q, q), HAL_EUNSUPPORTED);
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
    return HAL_EAGAIN;
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
    return HAL_EINVAL;
}
static int fake_dio_poll_fd(void *self)
{
    (void)self;
    return HAL_EIO; /* a failing poll_fd passes through, only "unsupported" becomes -1 */
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

    assert_int_equal(hal_can_send(&link, &f), HAL_EAGAIN);
    assert_ptr_equal(fk.self_seen, &fk);
    assert_ptr_equal(fk.frame_seen, &f);
    assert_int_equal(hal_can_recv(&link, &f), 1);
    assert_int_equal(f.id, 0x7E8);
    assert_int_equal(hal_can_poll_fd(&link), 42);
    hal_can_status_t cs;
    assert_int_equal(hal_can_status(&link, &cs), HAL_EUNSUPPORTED);
    hal_can_close(&link);
    assert_int_equal(fk.closes, 1);

    assert_int_equal(hal_dio_write(&dio, 3, 0x10000u, 0x2u), HAL_EINVAL);
    assert_int_equal(fk.unit_seen, 3);
    assert_int_equal(fk.on_seen, 0x10000u);
    assert_int_equal(fk.off_seen, 0x2u);
    assert_int_equal(hal_dio_poll_fd(&dio), HAL_EIO);
    hal_dio_close(&dio);
    assert_int_equal(fk.closes, 2);

    uint64_t t = 123456789u;
    hal_clock_t clk = { .now_us = fake_now, .self = &t };
    assert_int_equal(hal_clock_now_us(&clk), 123456789u);
}

static void test_strerror_names_every_status(void **state)
{
    (void)state;
    assert_string_equal(hal_strerror(HAL_OK), "ok");
    assert_string_equal(hal_strerror(5), "ok");
    assert_string_equal(hal_strerror(HAL_EUNSUPPORTED), "not supported by this backend");
    assert_string_equal(hal_strerror(HAL_EAGAIN), "try again");
    assert_string_equal(hal_strerror(HAL_EIO), "device I/O error");
    assert_string_equal(hal_strerror(HAL_EINVAL), "invalid argument for this device");
    assert_string_equal(hal_strerror(HAL_ENODEV), "no such device");
    assert_string_equal(hal_strerror(HAL_EPERM), "permission denied");
    assert_string_equal(hal_strerror(HAL_EBUSOFF), "CAN bus-off");
    assert_string_equal(hal_strerror(HAL_ENOAFCAN), "kernel has no AF_CAN support");
    assert_string_equal(hal_strerror(-99), "unknown error");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_null_entries_are_unsupported),
        cmocka_unit_test(test_present_entries_pass_through),
        cmocka_unit_test(test_strerror_names_every_status),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
