/* Groups of test_linux_hal, one per backend. */
#ifndef TEST_LINUX_H
#define TEST_LINUX_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

int run_socketcan_tests(void);
int run_gpiod_tests(void);
int run_rt_tests(void);

#endif
