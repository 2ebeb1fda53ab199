/* Proof that the kinematics never touch the heap: this executable is linked
 * with --wrap for every allocator entry point (C and C++), so each call made
 * from libls_kin.a (or from this file) lands in a counter below. The counter
 * is armed only around calls into the library. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "kin_test_util.h"
#include "ls_kin.h"
#include "ls_robot_model.h"

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

/* The counter itself works: a malloc while armed is seen. */
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

static void test_no_allocation_in_kinematics(void **state)
{
    (void)state;
    const ls_robot_model_t *m = &ls_robot_model_default;
    kt_rng_t rng = { 2024 };
    long calls = 0;
    int failures = 0;
    g_allocs = 0;
    for (int i = 0; i < 1000; ++i) {
        double q[6], T[16], J[36], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], qn[6], rpy[6], T2[16], T3[16];
        int n = 0;
        kt_random_q(&rng, m, 0.0, q);
        g_armed = 1;
        failures += ls_kin_fk(m, q, T) != LS_OK;
        const int rc_all = ls_kin_ik_all(m, T, qs, &n);
        const int rc_near = ls_kin_ik_nearest(m, T, q, qn);
        failures += ls_kin_jacobian(m, q, J) != LS_OK;
        ls_pose_to_xyzrpy(T, rpy);
        ls_pose_from_xyzrpy(rpy, T2);
        ls_pose_inv(T2, T3);
        ls_pose_mul(T3, T, T2);
        ls_pose_interp(T, T3, 0.3, T2);
        (void)ls_pose_angle(T, T2);
        (void)ls_pose_dist(T, T2);
        /* Error paths too. */
        T[12] = NAN;
        failures += ls_kin_ik_all(m, T, qs, &n) != LS_EINVAL;
        T[12] = 5.0;
        failures += ls_kin_ik_nearest(m, T, q, qn) != LS_EUNREACHABLE;
        g_armed = 0;
        /* Poses near singularities may legitimately report ESINGULAR. */
        failures += rc_all != LS_OK && rc_all != LS_ESINGULAR;
        failures += rc_near != rc_all;
        calls += 13;
    }
    assert_int_equal(failures, 0);
    printf("[ info ] %ld kinematics calls, %ld heap allocations\n", calls, g_allocs);
    assert_int_equal(g_allocs, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counter_sees_malloc),
        cmocka_unit_test(test_no_allocation_in_kinematics),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
