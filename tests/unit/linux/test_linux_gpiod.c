/* libgpiod DIO: the diagnostics for a missing chip, a path that is not a
 * GPIO device, and configurations refused before any chip is touched. The
 * line paths need a GPIO chip and run in the VM tier (gpio-sim). */
#include <stdio.h>
#include <string.h>

#include "hal_linux_gpiod.h"
#include "test_linux.h"

static void assert_missing_chip(const char *chip)
{
    hal_linux_gpiod_config_t cfg = {
        .chip = chip, .n_inputs = 1, .input_offsets = { 0 }, .n_outputs = 1, .output_offsets = { 1 }
    };
    hal_dio_t dio;
    memset(&dio, 0x5A, sizeof dio);
    char msg[512] = "";
    assert_int_equal(hal_linux_gpiod_open(&dio, &cfg, msg, sizeof msg), LS_ENODEV);
    char want[128];
    snprintf(want, sizeof want, "no GPIO chip '%s'", chip);
    assert_non_null(strstr(msg, want));
    assert_non_null(strstr(msg, "ls /dev/gpiochip*"));
    assert_non_null(strstr(msg, "CONFIG_GPIOLIB"));
    assert_null(dio.ops);
    assert_null(dio.self);
    uint32_t bits;
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_EUNSUPPORTED);
    hal_dio_close(&dio);

    char pmsg[512] = "";
    assert_int_equal(hal_linux_gpiod_probe(chip, pmsg, sizeof pmsg), LS_ENODEV);
    assert_string_equal(pmsg, msg);
}

static void test_missing_chip_by_name(void **state)
{
    (void)state;
    assert_missing_chip("gpiochip99");
}

static void test_missing_chip_by_path(void **state)
{
    (void)state;
    assert_missing_chip("/dev/does-not-exist");
}

static void test_path_that_is_not_a_gpio_chip(void **state)
{
    (void)state;
    hal_linux_gpiod_config_t cfg = { .chip = "/dev/null", .n_inputs = 0, .n_outputs = 1, .output_offsets = { 0 } };
    hal_dio_t dio;
    char msg[512] = "";
    assert_int_equal(hal_linux_gpiod_open(&dio, &cfg, msg, sizeof msg), LS_ENODEV);
    assert_non_null(strstr(msg, "'/dev/null' is not a GPIO character device"));
    assert_non_null(strstr(msg, "CONFIG_GPIOLIB"));
    assert_null(dio.ops);
}

static void test_bad_configurations_are_refused_first(void **state)
{
    (void)state;
    hal_dio_t dio;
    char msg[256];
    hal_linux_gpiod_config_t cfg = { .chip = "gpiochip99", .n_inputs = 17 };
    assert_int_equal(hal_linux_gpiod_open(&dio, &cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "17 inputs"));
    assert_non_null(strstr(msg, "at most 16"));

    cfg = (hal_linux_gpiod_config_t){ .chip = "gpiochip99", .n_outputs = 17 };
    assert_int_equal(hal_linux_gpiod_open(&dio, &cfg, msg, sizeof msg), LS_EINVAL);

    cfg = (hal_linux_gpiod_config_t){
        .chip = "gpiochip99", .n_inputs = 2, .input_offsets = { 3, 4 }, .n_outputs = 2, .output_offsets = { 5, 4 }
    };
    assert_int_equal(hal_linux_gpiod_open(&dio, &cfg, msg, sizeof msg), LS_EINVAL);
    assert_string_equal(msg, "GPIO line 4 is configured twice");
    assert_null(dio.ops);

    assert_int_equal(hal_linux_gpiod_open(NULL, &cfg, msg, sizeof msg), LS_EINVAL);
    assert_int_equal(hal_linux_gpiod_open(&dio, NULL, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "must not be NULL"));
}

int run_gpiod_tests(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_missing_chip_by_name),
        cmocka_unit_test(test_missing_chip_by_path),
        cmocka_unit_test(test_path_that_is_not_a_gpio_chip),
        cmocka_unit_test(test_bad_configurations_are_refused_first),
    };
    return cmocka_run_group_tests_name("gpiod", tests, NULL, NULL);
}
