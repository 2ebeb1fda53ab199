/* Proof that ls_otg (and the ruckig code under it) never touches the heap:
 * this executable is linked with --wrap for every allocator entry point (C
 * and C++) and for the exception allocator, so each call made from
 * libls_otg.a, libls_ruckig.a or this file lands in the counter of
 * tests/support/alloc_counter.c. The counter is armed around planner init,
 * planning (both interfaces, success and error paths) and sampling. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "alloc_counter.h"
#include "ls_otg.h"
#include "test_rng.h"

static test_rng_t g_rng = { 0x9E3779B97F4A7C15u };

static double urand(double lo, double hi)
{
    return test_rng_uniform(&g_rng, lo, hi);
}

static ls_otg_planner_t g_pl;

static void test_no_allocation_in_otg(void **state)
{
    (void)state;
    long calls = 0;
    int failures = 0;
    alloc_counter_reset();
    alloc_counter_arm();
    failures += ls_otg_planner_init(&g_pl) != LS_OK;
    alloc_counter_disarm();
    for (int k = 0; k < 500; k++) {
        ls_otg_limits_t lim;
        ls_otg_state_t cur, tgt;
        for (int i = 0; i < LS_OTG_MAX_AXES; i++) {
            lim.v_max[i] = urand(0.5, 3.0);
            lim.a_max[i] = urand(1.0, 10.0);
            lim.j_max[i] = urand(5.0, 100.0);
            cur.p[i] = urand(-2, 2), cur.v[i] = urand(-0.3, 0.3), cur.a[i] = urand(-0.3, 0.3);
            tgt.p[i] = urand(-2, 2), tgt.v[i] = urand(-0.3, 0.3), tgt.a[i] = urand(-0.3, 0.3);
        }
        ls_otg_t tr;
        double p[LS_OTG_MAX_AXES], v[LS_OTG_MAX_AXES], a[LS_OTG_MAX_AXES], j[LS_OTG_MAX_AXES];
        alloc_counter_arm();
        failures += ls_otg_plan_position(&g_pl, &tr, LS_OTG_MAX_AXES, &cur, &tgt, &lim) != LS_OK;
        for (double t = 0.0; t <= tr.duration_s + 0.01; t += 0.01) {
            ls_otg_sample(&tr, t, p, v, a, j);
        }
        ls_otg_state_t tgt_v = tgt; /* the velocity interface ends at a = 0 */
        for (int i = 0; i < LS_OTG_MAX_AXES; i++) {
            tgt_v.a[i] = 0.0;
        }
        failures += ls_otg_plan_velocity(&g_pl, &tr, 3, &cur, &tgt_v, &lim) != LS_OK;
        ls_otg_sample(&tr, 0.5 * tr.duration_s, p, v, a, j);
        tgt.v[0] = 100.0; /* error paths */
        failures += ls_otg_plan_position(&g_pl, &tr, 2, &cur, &tgt, &lim) != LS_ERANGE;
        lim.j_max[1] = NAN;
        failures += ls_otg_plan_velocity(&g_pl, &tr, 2, &cur, &tgt, &lim) != LS_EINVAL;
        alloc_counter_disarm();
        calls += 4;
    }
    assert_int_equal(failures, 0);
    printf("[ info ] %ld plans (and their samples), %ld heap allocations\n", calls, alloc_counter_count());
    assert_int_equal(alloc_counter_count(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test(test_no_allocation_in_otg),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
