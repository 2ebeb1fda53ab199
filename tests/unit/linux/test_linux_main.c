#include <string.h>

#include "test_linux.h"

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], RT_CHILD_ARG) == 0) {
        return rt_child_without_privilege();
    }
    int failed = 0;
    failed += run_socketcan_tests();
    failed += run_gpiod_tests();
    failed += run_rt_tests();
    failed += run_slcan_tty_tests();
    return failed;
}
