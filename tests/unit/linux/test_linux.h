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
int run_slcan_tty_tests(void);

/* argv[1] that makes the binary run the no-privilege child instead. */
#define RT_CHILD_ARG "--rt-child-without-privilege"
int rt_child_without_privilege(void);

#endif
