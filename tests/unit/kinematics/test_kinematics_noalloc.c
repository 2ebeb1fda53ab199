/* Proof that the kinematics never touch the heap: this executable is linked
 * with --wrap for every allocator entry point (C and C++), so each call made
 * from libls_kin.a (or from this file) lands in the counter of
 * tests/support/alloc_counter.c. The counter is armed only around calls into
 * the library. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "alloc_counter.h"
#include "kin_test_util.h"
#include "ls_kin.h"
#include "ls_robot_model.h"

/* The default arm (spherical wrist) and a UR5e's geometry (offset wrist):
 * both IK classes. */
static ls_robot_model_t offset_wrist_arm(void)
{
    ls_robot_model_t m = ls_robot_model_default;
    const ls_dh_t dh[LS_N_JOINTS] = {
        { 0.0, LS_PI / 2, 0.1625, 0.0 }, { -0.425, 0.0, 0.0, 0.0 },        { -0.3922, 0.0, 0.0, 0.0 },
        { 0.0, LS_PI / 2, 0.1333, 0.0 }, { 0.0, -LS_PI / 2, 0.0997, 0.0 }, { 0.0, 0.0, 0.0996, 0.0 },
    };
    for (int j = 0; j < LS_N_JOINTS; ++j) {
        m.dh[j] = dh[j];
    }
    m.ik_class = LS_IK_CLASS_OFFSET_WRIST;
    return m;
}

static void test_no_allocation_in_kinematics(void **state)
{
    (void)state;
    const ls_robot_model_t ur = offset_wrist_arm();
    ls_ik_class_t cls = LS_IK_CLASS_NONE;
    char why[200];
    alloc_counter_reset();
    alloc_counter_arm();
    const int rc_cls = ls_kin_classify(&ur, &cls, why, sizeof why);
    alloc_counter_disarm();
    assert_int_equal(rc_cls, LS_OK);
    assert_int_equal(cls, LS_IK_CLASS_OFFSET_WRIST);
    kt_rng_t rng = { 2024 };
    long calls = 0;
    int failures = 0;
    for (int i = 0; i < 2000; ++i) {
        const ls_robot_model_t *m = i % 2 == 0 ? &ls_robot_model_default : &ur;
        double q[6], T[16], J[36], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], qn[6], rpy[6], T2[16], T3[16];
        int n = 0;
        kt_random_q(&rng, m, 0.0, q);
        alloc_counter_arm();
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
        alloc_counter_disarm();
        /* Poses near singularities may legitimately report ESINGULAR. */
        failures += rc_all != LS_OK && rc_all != LS_ESINGULAR;
        failures += rc_near != rc_all;
        calls += 13;
    }
    assert_int_equal(failures, 0);
    printf("[ info ] %ld kinematics calls, %ld heap allocations\n", calls, alloc_counter_count());
    assert_int_equal(alloc_counter_count(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test(test_no_allocation_in_kinematics),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
