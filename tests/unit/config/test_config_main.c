#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_config.h"

void tc_write_file(char *path, size_t pathlen, const char *text)
{
    snprintf(path, pathlen, "/tmp/ls_config_test_XXXXXX");
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    size_t n = strlen(text);
    assert_int_equal(write(fd, text, n), (ssize_t)n);
    close(fd);
}

int main(void)
{
    int failed = tc_run_config_tests();
    failed += tc_run_check_tests();
    failed += tc_run_keys_tests();
    return failed;
}
