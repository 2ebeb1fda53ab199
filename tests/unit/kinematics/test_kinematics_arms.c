/* The kinematics on the arms people have, read from the shipped model files
 * (firmware/model/robots: the makers' published DH tables): a UR5e and a
 * UR10e (offset wrist), a KUKA KR 6 R900 and a PUMA 560 (spherical wrist),
 * and ls-sim6. FK and IK round trips on every arm, every branch, the offset
 * wrist's singularity conventions, joint wrap, and the refusal of a geometry
 * no class fits. The default arm's own cases are in test_kinematics.c. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "kin_test_util.h"
#include "ls_kin.h"
#include "ls_robot_model.h"
#include "ls_robot_model_file.h"

static const char *const ARMS[] = { "ur5e.ini", "ur10e.ini", "kr6-r900.ini", "puma560.ini", "ls-sim6.ini" };
#define N_ARMS (sizeof ARMS / sizeof ARMS[0])

static ls_robot_model_t arm(const char *file)
{
    char path[512], msg[512];
    snprintf(path, sizeof path, "%s/%s", LS_ROBOTS_DIR, file);
    ls_robot_model_t m;
    if (ls_robot_model_load(path, &m, msg, sizeof msg) != LS_OK) {
        fail_msg("%s", msg);
    }
    return m;
}

static ls_robot_model_t widened(ls_robot_model_t m)
{
    for (int j = 0; j < LS_N_JOINTS; ++j) {
        m.q_min_rad[j] = -2 * LS_PI;
        m.q_max_rad[j] = 2 * LS_PI;
    }
    return m;
}

static int same_mod_2pi(const double a[6], const double b[6], double tol)
{
    for (int j = 0; j < 6; ++j) {
        if (fabs(kt_angdiff(a[j], b[j])) > tol) {
            return 0;
        }
    }
    return 1;
}

static void assert_reaches(const ls_robot_model_t *m, const double q[6], const double T[16], double tol)
{
    double Tb[16], dp, da;
    assert_int_equal(ls_kin_fk(m, q, Tb), LS_OK);
    kt_pose_error(T, Tb, &dp, &da);
    if (dp > tol || da > tol) {
        fail_msg("%s: FK(IK) off by %.3g m, %.3g rad", m->name, dp, da);
    }
}

/* FK(IK(FK(q))) == FK(q) on every branch within the limits, and q is among
 * the branches, on 3000 random configurations away from singularities. */
static void ik_round_trips_on_every_published_arm(void **state)
{
    (void)state;
    for (size_t a = 0; a < N_ARMS; ++a) {
        const ls_robot_model_t m = arm(ARMS[a]);
        kt_rng_t rng = { 0x1234u + a };
        int tested = 0, attempts = 0, branches = 0;
        while (tested < 3000) {
            assert_true(++attempts < 100000);
            double q[6], T[16], sh, el, wr;
            kt_random_q(&rng, &m, 1e-3, q);
            assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
            kt_singularity_margins(&m, q, T, &sh, &el, &wr);
            if (sh < 0.01 || el < 0.01 || wr < 0.01) {
                continue;
            }
            ++tested;
            double qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
            int n = -1;
            const int rc = ls_kin_ik_all(&m, T, qs, &n);
            if (rc != LS_OK) {
                fail_msg("%s pose %d: ik_all returned %s", m.name, tested, ls_err_name(rc));
            }
            int found = 0;
            for (int b = 0; b < n; ++b) {
                for (int j = 0; j < 6; ++j) {
                    assert_true(qs[b][j] >= m.q_min_rad[j] && qs[b][j] <= m.q_max_rad[j]);
                }
                assert_reaches(&m, qs[b], T, 1e-9);
                found |= same_mod_2pi(qs[b], q, 1e-8);
            }
            if (!found) {
                fail_msg("%s: the generating q (%g %g %g %g %g %g) is not among %d branches", m.name, q[0], q[1], q[2],
                         q[3], q[4], q[5], n);
            }
            branches += n;
        }
        printf("[ info ] %-9s %s: 3000 poses, %.2f branches each within the limits\n", m.name,
               ls_ik_class_name(m.ik_class), branches / 3000.0);
    }
}

/* Every branch: with the limits wide open a generic pose has 8 distinct
 * solutions, in the documented order (shoulder, then elbow, then wrist). */
static void every_branch_of_every_arm_reaches_the_pose(void **state)
{
    (void)state;
    const double q[6] = { 0.3, -1.1, 0.9, -0.7, 0.8, 0.4 };
    for (size_t a = 0; a < N_ARMS; ++a) {
        const ls_robot_model_t m = widened(arm(ARMS[a]));
        double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
        int n = 0;
        assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
        assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_OK);
        assert_int_equal(n, 8);
        for (int b = 0; b < n; ++b) {
            assert_reaches(&m, qs[b], T, 1e-9);
            for (int c = b + 1; c < n; ++c) {
                assert_false(same_mod_2pi(qs[b], qs[c], 1e-6));
            }
        }
        /* Shoulder: the first four share q1, the last four share the other. */
        for (int b = 1; b < 4; ++b) {
            assert_true(fabs(kt_angdiff(qs[b][0], qs[0][0])) < 1e-9);
            assert_true(fabs(kt_angdiff(qs[b + 4][0], qs[4][0])) < 1e-9);
        }
        assert_true(fabs(kt_angdiff(qs[0][0], qs[4][0])) > 1e-3);
        /* Wrist: alternate branches have sin(q5 + offset5) >= 0, then < 0. */
        for (int b = 0; b < n; b += 2) {
            assert_true(sin(qs[b][4] + m.dh[4].theta_offset_rad) >= 0.0);
            assert_true(sin(qs[b + 1][4] + m.dh[4].theta_offset_rad) < 0.0);
        }
    }
}

static void ik_nearest_returns_the_seed_branch_on_every_arm(void **state)
{
    (void)state;
    for (size_t a = 0; a < N_ARMS; ++a) {
        const ls_robot_model_t m = arm(ARMS[a]);
        kt_rng_t rng = { 77u + a };
        int tested = 0;
        while (tested < 1000) {
            double q[6], T[16], seed[6], out[6], sh, el, wr;
            kt_random_q(&rng, &m, 0.03, q);
            assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
            kt_singularity_margins(&m, q, T, &sh, &el, &wr);
            if (sh < 0.05 || el < 0.2 || wr < 0.2) {
                continue;
            }
            ++tested;
            for (int j = 0; j < 6; ++j) {
                seed[j] = q[j] + kt_uniform(&rng, -0.02, 0.02);
            }
            assert_int_equal(ls_kin_ik_nearest(&m, T, seed, out), LS_OK);
            for (int j = 0; j < 6; ++j) {
                if (fabs(out[j] - q[j]) > 1e-8) {
                    fail_msg("%s joint %d: %.12g, expected %.12g", m.name, j + 1, out[j], q[j]);
                }
            }
        }
    }
}

/* UR joints turn +-360 deg: ik_all gives the wrap nearest 0, ik_nearest the
 * one nearest the seed. */
static void offset_wrist_joints_wrap_to_the_turn_asked_for(void **state)
{
    (void)state;
    const ls_robot_model_t m = arm("ur5e.ini");
    const double q[6] = { 4.0, -1.2, 1.1, -5.0, 0.9, 5.5 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = 0;
    assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_OK);
    int found = 0;
    for (int b = 0; b < n; ++b) {
        for (int j = 0; j < 6; ++j) {
            assert_true(fabs(qs[b][j]) <= LS_PI + 1e-12);
        }
        found |= same_mod_2pi(qs[b], q, 1e-9);
    }
    assert_true(found);
    assert_int_equal(ls_kin_ik_nearest(&m, T, q, out), LS_OK);
    for (int j = 0; j < 6; ++j) {
        assert_true(fabs(out[j] - q[j]) < 1e-9);
    }
}

/* q5 = 0: joint 6 is parallel to joints 2-4, only q2 + q3 + q4 + q6 is
 * defined. ik_all takes q6 = 0, ik_nearest the seed's q6; both reach the
 * pose, and the seed comes back exactly. */
static void offset_wrist_singularity_keeps_q6(void **state)
{
    (void)state;
    const ls_robot_model_t m = arm("ur10e.ini");
    const double q[6] = { 0.4, -1.0, 1.2, -0.9, 0.0, 0.7 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = 0;
    assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_OK);
    int singular = 0;
    for (int b = 0; b < n; ++b) {
        assert_reaches(&m, qs[b], T, 1e-9);
        if (fabs(sin(qs[b][4])) < 1e-6) {
            ++singular;
            assert_true(qs[b][5] == 0.0);
        }
    }
    assert_true(singular > 0);
    assert_int_equal(ls_kin_ik_nearest(&m, T, q, out), LS_OK);
    for (int j = 0; j < 6; ++j) {
        assert_true(fabs(out[j] - q[j]) < 1e-9);
    }
    const double seed[6] = { 0.4, -1.0, 1.2, -0.5, 0.01, 0.3 };
    assert_int_equal(ls_kin_ik_nearest(&m, T, seed, out), LS_OK);
    assert_true(out[5] == 0.3);
    assert_true(fabs(kt_angdiff(out[1] + out[2] + out[3], q[1] + q[2] + q[3] + 0.4)) < 1e-9);
    assert_reaches(&m, out, T, 1e-9);
}

/* q3 = 0: the arm stretched, the two elbow branches coincide and come once. */
static void offset_wrist_elbow_singularity_returns_one_elbow(void **state)
{
    (void)state;
    const ls_robot_model_t m = widened(arm("ur5e.ini"));
    const double q[6] = { 0.2, -0.8, 0.0, -0.6, 0.9, 0.3 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
    int n = 0, found = 0;
    assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_OK);
    assert_true(n < 8);
    for (int b = 0; b < n; ++b) {
        assert_reaches(&m, qs[b], T, 1e-9);
        found |= same_mod_2pi(qs[b], q, 1e-7);
        for (int c = b + 1; c < n; ++c) {
            assert_false(same_mod_2pi(qs[b], qs[c], 1e-9));
        }
    }
    assert_true(found);
}

/* The wrist centre as far from the joint 1 axis as the parallel joints'
 * plane (d4 for a UR): both shoulder branches coincide, LS_OK once; a UR
 * variant with d4 = 0 and the wrist centre on the axis is undetermined. */
static void offset_wrist_shoulder_singularities(void **state)
{
    (void)state;
    const ls_robot_model_t m = widened(arm("ur5e.ini"));
    const double h = m.dh[3].d_m;
    /* Flange pointing down, wrist centre at (0, -h, 0.5): on the plane. */
    double T[16] = { 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, -h, 0.5 - m.dh[5].d_m, 1 };
    double qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = 0;
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_OK);
    assert_true(n > 0 && n <= 4);
    for (int b = 0; b < n; ++b) {
        assert_reaches(&m, qs[b], T, 1e-9);
        assert_true(fabs(kt_angdiff(qs[b][0], qs[0][0])) < 1e-6);
    }

    ls_robot_model_t flat = m;
    flat.dh[3].d_m = 0.0;
    flat.ik_class = LS_IK_CLASS_NONE;
    assert_int_equal(ls_kin_classify(&flat, &flat.ik_class, NULL, 0), LS_OK);
    assert_int_equal(flat.ik_class, LS_IK_CLASS_OFFSET_WRIST);
    double Ta[16] = { 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0.5 - flat.dh[5].d_m, 1 };
    const double q0[6] = { 0 };
    assert_int_equal(ls_kin_ik_all(&flat, Ta, qs, &n), LS_ESINGULAR);
    assert_int_equal(n, 0);
    assert_int_equal(ls_kin_ik_nearest(&flat, Ta, q0, out), LS_ESINGULAR);
    Ta[14] = 5.0; /* on the axis, out of reach: unreachable wins */
    assert_int_equal(ls_kin_ik_all(&flat, Ta, qs, &n), LS_EUNREACHABLE);
}

static void offset_wrist_unreachable_and_limits(void **state)
{
    (void)state;
    ls_robot_model_t m = arm("ur5e.ini");
    double T[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2.0, 0, 0.5, 1 }, qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
    int n = -1;
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_EUNREACHABLE);
    assert_int_equal(n, 0);
    const double q[6] = { LS_PI / 2, -1.0, 1.0, -1.2, 0.8, 0.1 };
    assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
    m.q_min_rad[0] = -0.2;
    m.q_max_rad[0] = 0.2;
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_ELIMITS);
}

/* A geometry no class fits is refused with the reason; a model whose
 * geometry no longer fits the class it claims is refused by every IK call
 * (never solved wrongly). */
static void a_geometry_no_class_fits_is_refused(void **state)
{
    (void)state;
    ls_robot_model_t m = arm("ur5e.ini");
    const double q[6] = { 0.1, -1.0, 1.0, -1.2, 0.8, 0.1 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = -1;
    assert_int_equal(ls_kin_fk(&m, q, T), LS_OK);
    m.dh[4].a_m = 0.03; /* joint 5 offset along its common normal */
    ls_ik_class_t cls = LS_IK_CLASS_OFFSET_WRIST;
    char why[400];
    assert_int_equal(ls_kin_classify(&m, &cls, why, sizeof why), LS_EINVAL);
    assert_int_equal(cls, LS_IK_CLASS_OFFSET_WRIST); /* untouched */
    assert_string_equal(why, "not a spherical wrist (a5 = 0.03 m; a4, a5, a6 and d5 must be 0 so that joints 4-6 "
                             "meet) and not an offset wrist (a5 = 0.03 m; a4, a5 and a6 must be 0)");
    assert_int_equal(ls_kin_ik_all(&m, T, qs, &n), LS_EINVAL);
    assert_int_equal(n, 0);
    assert_int_equal(ls_kin_ik_nearest(&m, T, q, out), LS_EINVAL);

    ls_robot_model_t none = arm("ur5e.ini");
    none.ik_class = LS_IK_CLASS_NONE;
    assert_int_equal(ls_kin_ik_all(&none, T, qs, &n), LS_EINVAL);
    none.ik_class = LS_IK_CLASS_SPHERICAL_WRIST; /* a UR is no spherical wrist */
    assert_int_equal(ls_kin_ik_all(&none, T, qs, &n), LS_EINVAL);

    ls_robot_model_t twisted = arm("ur5e.ini");
    twisted.dh[2].alpha_rad = 0.3;
    assert_int_equal(ls_kin_classify(&twisted, &cls, why, sizeof why), LS_EINVAL);
    assert_non_null(strstr(why, "alpha3 = 17.1887 deg; alpha2 and alpha3 must be 0 so that joints 2-4 are parallel"));
    ls_robot_model_t inverted = arm("ur5e.ini");
    inverted.q_min_rad[2] = 1.0;
    inverted.q_max_rad[2] = -1.0;
    assert_int_equal(ls_kin_classify(&inverted, &cls, why, sizeof why), LS_EINVAL);
    assert_string_equal(why, "joint 3: q_min 1 rad is above q_max -1 rad");
    assert_int_equal(ls_kin_classify(NULL, &cls, why, sizeof why), LS_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ik_round_trips_on_every_published_arm),
        cmocka_unit_test(every_branch_of_every_arm_reaches_the_pose),
        cmocka_unit_test(ik_nearest_returns_the_seed_branch_on_every_arm),
        cmocka_unit_test(offset_wrist_joints_wrap_to_the_turn_asked_for),
        cmocka_unit_test(offset_wrist_singularity_keeps_q6),
        cmocka_unit_test(offset_wrist_elbow_singularity_returns_one_elbow),
        cmocka_unit_test(offset_wrist_shoulder_singularities),
        cmocka_unit_test(offset_wrist_unreachable_and_limits),
        cmocka_unit_test(a_geometry_no_class_fits_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
