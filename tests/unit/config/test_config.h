/* Shared by the config unit tests: the groups and a temp-file helper. */
#ifndef TEST_CONFIG_H
#define TEST_CONFIG_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

/* Write `text` to a new file under /tmp; path in `path` (caller unlinks). */
void tc_write_file(char *path, size_t pathlen, const char *text);

int tc_run_config_tests(void);
int tc_run_check_tests(void);
int tc_run_keys_tests(void);

#endif
