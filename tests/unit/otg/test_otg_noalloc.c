/* Proof that ls_otg (and the ruckig code under it) never touches the heap:
 * this executable is linked with --wrap for every allocator entry point (C
 * and C++) and for the exception allocator, so each call made from
 * libls_otg.a, libls_ruckig.a or this file lands in a counter below. The
 * counter is armed around planner init, planning (both interfaces, success
 * and error paths) and sampling. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "ls_otg.h"

/* volatile: the compiler knows malloc reads no user globals and would drop the
 * arming stores around it. */
static volatile int g_armed;
static volatile long g_allocs;

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__real_aligned_alloc(size_t align, size_t n);
int __real_posix_memalign(void **p, size_t align, size_t n);
void *__real__Znwm(size_t n);
void *__real__Znam(size_t n);
void *__real__ZnwmSt11align_val_t(size_t n, size_t align);
void *__real__ZnamSt11align_val_t(size_t n, size_t align);
void *__real___cxa_allocate_exception(size_t n);

void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);
void *__wrap_aligned_alloc(size_t align, size_t n);
int __wrap_posix_memalign(void **p, size_t align, size_t n);
void *__wrap__Znwm(size_t n);
void *__wrap__Znam(size_t n);
void *__wrap__ZnwmSt11align_val_t(size_t n, size_t align);
void *__wrap__ZnamSt11align_val_t(size_t n, size_t align);
void *__wrap___cxa_allocate_exception(size_t n);

static void count(void)
{
    if (g_armed) {
        ++g_allocs;
    }
}

void *__wrap_malloc(size_t n)
{
    count();
    return __real_malloc(n);
}
void *__wrap_calloc(size_t n, size_t size)
{
    count();
    return __real_calloc(n, size);
}
void *__wrap_realloc(void *p, size_t n)
{
    count();
    return __real_realloc(p, n);
}
void __wrap_free(void *p)
{
    count();
    __real_free(p);
}
void *__wrap_aligned_alloc(size_t align, size_t n)
{
    count();
    return __real_aligned_alloc(align, n);
}
int __wrap_posix_memalign(void **p, size_t align, size_t n)
{
    count();
    return __real_posix_memalign(p, align, n);
}
void *__wrap__Znwm(size_t n)
{
    count();
    return __real__Znwm(n);
}
void *__wrap__Znam(size_t n)
{
    count();
    return __real__Znam(n);
}
void *__wrap__ZnwmSt11align_val_t(size_t n, size_t align)
{
    count();
    return __real__ZnwmSt11align_val_t(n, align);
}
void *__wrap__ZnamSt11align_val_t(size_t n, size_t align)
{
    count();
    return __real__ZnamSt11align_val_t(n, align);
}
void *__wrap___cxa_allocate_exception(size_t n)
{
    count();
    return __real___cxa_allocate_exception(n);
}

static void *volatile g_sink;

static void test_counter_sees_malloc(void **state)
{
    (void)state;
    g_allocs = 0;
    g_armed = 1;
    g_sink = malloc(32);
    g_armed = 0;
    free(g_sink);
    assert_int_equal(g_allocs, 1);
}

static uint64_t rng_state = 0x9E3779B97F4A7C15u;

static double urand(double lo, double hi)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return lo + (hi - lo) * (double)(rng_state >> 11) / 9007199254740992.0;
}

static ls_otg_planner_t g_pl;

static void test_no_allocation_in_otg(void **state)
{
    (void)state;
    long calls = 0;
    int failures = 0;
    g_allocs = 0;
    g_armed = 1;
    failures += ls_otg_planner_init(&g_pl) != LS_OK;
    g_armed = 0;
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
        g_armed = 1;
        failures += ls_otg_plan_position(&g_pl, &tr, LS_OTG_MAX_AXES, &cur, &tgt, &lim) != LS_OK;
        for (double t = 0.0; t <= tr.duration_s + 0.01; t += 0.01) {
            ls_otg_sample(&tr, t, p, v, a, j);
        }
        failures += ls_otg_plan_velocity(&g_pl, &tr, 3, &cur, &tgt, &lim) != LS_OK;
        ls_otg_sample(&tr, 0.5 * tr.duration_s, p, v, a, j);
        tgt.v[0] = 100.0; /* error paths */
        failures += ls_otg_plan_position(&g_pl, &tr, 2, &cur, &tgt, &lim) != LS_ERANGE;
        lim.j_max[1] = NAN;
        failures += ls_otg_plan_velocity(&g_pl, &tr, 2, &cur, &tgt, &lim) != LS_EINVAL;
        g_armed = 0;
        calls += 4;
    }
    assert_int_equal(failures, 0);
    printf("[ info ] %ld plans (and their samples), %ld heap allocations\n", calls, g_allocs);
    assert_int_equal(g_allocs, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counter_sees_malloc),
        cmocka_unit_test(test_no_allocation_in_otg),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
