#include "test_linux.h"

int main(void)
{
    int failed = 0;
    failed += run_socketcan_tests();
    failed += run_gpiod_tests();
    failed += run_rt_tests();
    return failed;
}
