/* The systemd unit gives landscaped the shutdown's budget that the firmware
 * declares (ls_run.h LS_RUN_SHUTDOWN_BUDGET_S), so that SIGKILL never cuts
 * a stop or its final notices short (docs/reliability.md "Signals"). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "ls_run.h"

static void test_the_units_stop_timeout_is_the_firmwares_shutdown_budget(void **state)
{
    (void)state;
    FILE *f = fopen(LS_DEPLOY_DIR "/landscaped.service", "r");
    assert_non_null(f);
    char line[256];
    long timeout_s = -1L;
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, "TimeoutStopSec=", 15) == 0) {
            timeout_s = strtol(line + 15, NULL, 10);
        }
    }
    fclose(f);
    assert_int_equal(timeout_s, (long)LS_RUN_SHUTDOWN_BUDGET_S);
    /* the halt's own bound fits the stop's share of it */
    assert_true(LS_RUN_HALT_MAX_US < LS_RUN_SHUTDOWN_STOP_MAX_US);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_units_stop_timeout_is_the_firmwares_shutdown_budget),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
