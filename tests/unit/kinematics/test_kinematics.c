/* Black-box tests of the kinematics C API (ls_kin.h) on the default arm and
 * on a second DH variant with other axis signs and offsets. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>

#include "kin_test_util.h"
#include "ls_kin.h"
#include "ls_robot_model.h"

#define M (&ls_robot_model_default)

/* cmocka's assert_float_equal works in float; this one in double, NaN fails. */
#define assert_near(a, b, tol)                                                                                         \
    do {                                                                                                               \
        const double a_ = (a), b_ = (b);                                                                               \
        if (!(fabs(a_ - b_) <= (tol))) {                                                                               \
            fail_msg("%s = %.17g, expected %.17g within %g", #a, a_, b_, (double)(tol));                               \
        }                                                                                                              \
    } while (0)

/* ---- helpers ---------------------------------------------------------- */

/* Expected flange pose from axes and origin (column-major). */
static void pose_from_axes(const double x[3], const double y[3], const double z[3], const double p[3], double T[16])
{
    for (int i = 0; i < 3; ++i) {
        T[0 + i] = x[i];
        T[4 + i] = y[i];
        T[8 + i] = z[i];
        T[12 + i] = p[i];
    }
    T[3] = T[7] = T[11] = 0.0;
    T[15] = 1.0;
}

static void assert_pose_near(const double A[16], const double B[16], double tol)
{
    for (int i = 0; i < 16; ++i) {
        if (fabs(A[i] - B[i]) > tol) {
            fail_msg("pose element %d: %.17g vs %.17g", i, A[i], B[i]);
        }
    }
}

static void fk_expect(const double q[6], const double x[3], const double y[3], const double z[3], const double p[3])
{
    double T[16], E[16];
    assert_int_equal(ls_kin_fk(M, q, T), LS_OK);
    pose_from_axes(x, y, z, p, E);
    assert_pose_near(T, E, 1e-12);
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

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The second arm: other signs of alpha, a lateral shoulder offset (d2), theta
 * offsets everywhere and a tilted flange (alpha6); same IK structure. */
static ls_robot_model_t variant_model(void)
{
    ls_robot_model_t v = ls_robot_model_default;
    const ls_dh_t dh[6] = {
        { .a_m = 0.10, .alpha_rad = LS_PI / 2, .d_m = 0.35, .theta_offset_rad = 0.2 },
        { .a_m = 0.45, .alpha_rad = 0.0, .d_m = 0.12, .theta_offset_rad = 0.3 },
        { .a_m = -0.05, .alpha_rad = LS_PI / 2, .d_m = 0.03, .theta_offset_rad = -0.4 },
        { .a_m = 0.0, .alpha_rad = -LS_PI / 2, .d_m = 0.42, .theta_offset_rad = 0.5 },
        { .a_m = 0.0, .alpha_rad = LS_PI / 2, .d_m = 0.0, .theta_offset_rad = -0.6 },
        { .a_m = 0.0, .alpha_rad = 0.3, .d_m = 0.10, .theta_offset_rad = 0.7 },
    };
    memcpy(v.dh, dh, sizeof dh);
    return v;
}

/* ---- forward kinematics ----------------------------------------------- */

/* Hand-computed from the DH table: a1 0.05, d1 0.4, a2 0.4, a3 0.04, d4 0.38,
 * d6 0.08; at q = 0 the upper arm is vertical and the forearm horizontal. */
static void test_fk_zero(void **state)
{
    (void)state;
    const double q[6] = { 0, 0, 0, 0, 0, 0 };
    fk_expect(q, (double[]){ 0, 0, 1 }, (double[]){ 0, -1, 0 }, (double[]){ 1, 0, 0 }, (double[]){ 0.51, 0, 0.84 });
}

static void test_fk_hand_configurations(void **state)
{
    (void)state;
    /* q1 = 90 deg: the whole arm turned about z. */
    fk_expect((double[]){ LS_PI / 2, 0, 0, 0, 0, 0 }, (double[]){ 0, 0, 1 }, (double[]){ 1, 0, 0 },
              (double[]){ 0, 1, 0 }, (double[]){ 0, 0.51, 0.84 });
    /* q2 = 90 deg: upper arm horizontal, forearm pointing down. */
    fk_expect((double[]){ 0, LS_PI / 2, 0, 0, 0, 0 }, (double[]){ 1, 0, 0 }, (double[]){ 0, -1, 0 },
              (double[]){ 0, 0, -1 }, (double[]){ 0.49, 0, -0.06 });
    /* q3 = 90 deg: upper arm vertical, forearm down from the elbow. */
    fk_expect((double[]){ 0, 0, LS_PI / 2, 0, 0, 0 }, (double[]){ 1, 0, 0 }, (double[]){ 0, -1, 0 },
              (double[]){ 0, 0, -1 }, (double[]){ 0.09, 0, 0.34 });
    /* q5 = 90 deg: wrist bent down, flange 0.08 below the wrist centre. */
    fk_expect((double[]){ 0, 0, 0, 0, LS_PI / 2, 0 }, (double[]){ 1, 0, 0 }, (double[]){ 0, -1, 0 },
              (double[]){ 0, 0, -1 }, (double[]){ 0.43, 0, 0.76 });
    /* q6 = 90 deg: flange turned about its own z. */
    fk_expect((double[]){ 0, 0, 0, 0, 0, LS_PI / 2 }, (double[]){ 0, -1, 0 }, (double[]){ 0, 0, -1 },
              (double[]){ 1, 0, 0 }, (double[]){ 0.51, 0, 0.84 });
}

static void test_fk_bad_input(void **state)
{
    (void)state;
    double T[16];
    const double q[6] = { 0, 0, NAN, 0, 0, 0 };
    const double qi[6] = { 0, 0, 0, INFINITY, 0, 0 };
    const double q0[6] = { 0 };
    assert_int_equal(ls_kin_fk(M, q, T), LS_EINVAL);
    assert_int_equal(ls_kin_fk(M, qi, T), LS_EINVAL);
    assert_int_equal(ls_kin_fk(NULL, q0, T), LS_EINVAL);
    assert_int_equal(ls_kin_fk(M, NULL, T), LS_EINVAL);
    assert_int_equal(ls_kin_fk(M, q0, NULL), LS_EINVAL);
}

/* ---- inverse kinematics ----------------------------------------------- */

/* FK(IK(FK(q))) == FK(q) for every branch, all branches within limits, q
 * among them. Returns the number of poses tested. */
static int check_ik_round_trips(const ls_robot_model_t *m, uint64_t seed, int n_poses, double *ik_s)
{
    kt_rng_t rng = { seed };
    int tested = 0, attempts = 0;
    double t_ik = 0.0;
    while (tested < n_poses) {
        assert_true(++attempts < 10 * n_poses);
        double q[6], T[16];
        kt_random_q(&rng, m, 1e-3, q);
        assert_int_equal(ls_kin_fk(m, q, T), LS_OK);
        double sh, el, wr;
        kt_singularity_margins(m, q, T, &sh, &el, &wr);
        if (sh < 0.01 || el < 0.01 || wr < 0.01) {
            continue;
        }
        ++tested;

        double qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
        int n = -1;
        const double t0 = now_s();
        const int rc = ls_kin_ik_all(m, T, qs, &n);
        t_ik += now_s() - t0;
        if (rc != LS_OK) {
            fail_msg("pose %d: ik_all returned %d", tested, rc);
        }
        assert_in_range(n, 1, LS_KIN_MAX_BRANCHES);
        int found = 0;
        for (int b = 0; b < n; ++b) {
            double Tb[16], dp, da;
            for (int j = 0; j < 6; ++j) {
                if (qs[b][j] < m->q_min_rad[j] || qs[b][j] > m->q_max_rad[j]) {
                    fail_msg("pose %d branch %d joint %d = %g outside limits", tested, b, j + 1, qs[b][j]);
                }
            }
            assert_int_equal(ls_kin_fk(m, qs[b], Tb), LS_OK);
            kt_pose_error(T, Tb, &dp, &da);
            if (dp > 1e-9 || da > 1e-9) {
                fail_msg("pose %d branch %d: FK(IK) off by %.3g m, %.3g rad", tested, b, dp, da);
            }
            found |= same_mod_2pi(qs[b], q, 1e-8);
        }
        if (!found) {
            fail_msg("pose %d: the generating q (%g %g %g %g %g %g) is not among %d branches", tested, q[0], q[1], q[2],
                     q[3], q[4], q[5], n);
        }
    }
    if (ik_s != NULL) {
        *ik_s = t_ik;
    }
    return tested;
}

static void test_ik_round_trip_10000(void **state)
{
    (void)state;
    double t = 0.0;
    const int n = check_ik_round_trips(M, 0x5eed1234u, 10000, &t);
    assert_int_equal(n, 10000);
    printf("[ info ] ls_kin_ik_all: %.2f us per call (%d poses, all branches)\n", 1e6 * t / n, n);
}

static void test_ik_round_trip_variant_model(void **state)
{
    (void)state;
    const ls_robot_model_t v = variant_model();
    assert_int_equal(check_ik_round_trips(&v, 0xabcdefu, 2000, NULL), 2000);
}

/* All 8 branches exist for a pose in the middle of the workspace. */
static void test_ik_eight_branches(void **state)
{
    (void)state;
    ls_robot_model_t wide = ls_robot_model_default;
    for (int j = 0; j < 6; ++j) {
        wide.q_min_rad[j] = -2 * LS_PI;
        wide.q_max_rad[j] = 2 * LS_PI;
    }
    const double q[6] = { 0.3, 0.2, 0.5, 0.4, 0.6, 0.7 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
    int n = 0;
    assert_int_equal(ls_kin_fk(&wide, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(&wide, T, qs, &n), LS_OK);
    assert_int_equal(n, 8);
    /* Branches differ pairwise: two shoulders (q1, q1 + pi), two elbows, two wrists. */
    for (int a = 0; a < n; ++a) {
        for (int b = a + 1; b < n; ++b) {
            assert_false(same_mod_2pi(qs[a], qs[b], 1e-6));
        }
        double Tb[16], dp, da;
        assert_int_equal(ls_kin_fk(&wide, qs[a], Tb), LS_OK);
        kt_pose_error(T, Tb, &dp, &da);
        assert_true(dp < 1e-9 && da < 1e-9);
    }
    /* Wrist flip of the generating branch: (q4 + pi, -q5, q6 + pi). */
    int flip = 0;
    const double qf[6] = { q[0], q[1], q[2], q[3] + LS_PI, -q[4], q[5] + LS_PI };
    for (int b = 0; b < n; ++b) {
        flip |= same_mod_2pi(qs[b], qf, 1e-9);
    }
    assert_true(flip);
}

static void test_ik_nearest_picks_seed_branch(void **state)
{
    (void)state;
    kt_rng_t rng = { 42 };
    int tested = 0;
    while (tested < 2000) {
        double q[6], T[16], seed[6], out[6];
        kt_random_q(&rng, M, 0.03, q);
        assert_int_equal(ls_kin_fk(M, q, T), LS_OK);
        double sh, el, wr;
        kt_singularity_margins(M, q, T, &sh, &el, &wr);
        /* Other branches are then >= 0.4 rad away in some joint. */
        if (sh < 0.05 || el < 0.2 || wr < 0.2) {
            continue;
        }
        ++tested;
        for (int j = 0; j < 6; ++j) {
            seed[j] = q[j] + kt_uniform(&rng, -0.02, 0.02);
        }
        assert_int_equal(ls_kin_ik_nearest(M, T, seed, out), LS_OK);
        for (int j = 0; j < 6; ++j) {
            /* Not modulo 2 pi: the wrap nearest the seed is the original. */
            if (fabs(out[j] - q[j]) > 1e-8) {
                fail_msg("joint %d: %.12g, expected %.12g", j + 1, out[j], q[j]);
            }
        }
    }
}

/* Joint 6 has +-350 deg: ik_all returns the wrap nearest 0, ik_nearest the
 * wrap nearest the seed. */
static void test_ik_wraps(void **state)
{
    (void)state;
    const double q[6] = { 0.1, 0.2, 0.3, 0.4, 0.5, 5.5 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = 0;
    assert_int_equal(ls_kin_fk(M, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_OK);
    int found = 0;
    for (int b = 0; b < n; ++b) {
        assert_true(fabs(qs[b][5]) <= LS_PI + 1e-12);
        if (same_mod_2pi(qs[b], q, 1e-9)) {
            found = 1;
            assert_near(qs[b][5], 5.5 - 2 * LS_PI, 1e-9);
        }
    }
    assert_true(found);
    assert_int_equal(ls_kin_ik_nearest(M, T, q, out), LS_OK);
    for (int j = 0; j < 6; ++j) {
        assert_near(out[j], q[j], 1e-9);
    }
}

static void test_ik_unreachable(void **state)
{
    (void)state;
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    const double q0[6] = { 0 };
    int n = -1;
    /* 2 m away: the arm spans well under 1 m. */
    pose_from_axes((double[]){ 0, 0, 1 }, (double[]){ 0, -1, 0 }, (double[]){ 1, 0, 0 }, (double[]){ 2.0, 0, 0.84 }, T);
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_EUNREACHABLE);
    assert_int_equal(n, 0);
    assert_int_equal(ls_kin_ik_nearest(M, T, q0, out), LS_EUNREACHABLE);
    /* Just past full stretch along the forearm. */
    pose_from_axes((double[]){ 0, 0, 1 }, (double[]){ 0, -1, 0 }, (double[]){ 1, 0, 0 },
                   (double[]){ 0.05 + 0.4 + hypot(0.04, 0.38) + 0.08 + 1e-6, 0, 0.4 }, T);
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_EUNREACHABLE);
    /* Just inside full stretch it is reachable (elbow straight, one elbow branch). */
    T[12] -= 2e-6;
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_OK);
    /* On the joint 1 axis but far above: unreachable wins over singular. */
    pose_from_axes((double[]){ 1, 0, 0 }, (double[]){ 0, 1, 0 }, (double[]){ 0, 0, 1 }, (double[]){ 0, 0, 3.0 }, T);
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_EUNREACHABLE);
}

static void test_ik_limits(void **state)
{
    (void)state;
    /* Joint 1 confined to +-10 deg; a pose at q1 = 90 deg needs q1 = 90 deg
     * (front) or -90 deg (back): reachable, but not within the limits. */
    ls_robot_model_t narrow = ls_robot_model_default;
    narrow.q_min_rad[0] = -10 * LS_PI / 180;
    narrow.q_max_rad[0] = 10 * LS_PI / 180;
    const double q[6] = { LS_PI / 2, 0.3, 0.2, 0.1, 0.5, 0.2 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = -1;
    assert_int_equal(ls_kin_fk(M, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(&narrow, T, qs, &n), LS_ELIMITS);
    assert_int_equal(n, 0);
    assert_int_equal(ls_kin_ik_nearest(&narrow, T, q, out), LS_ELIMITS);
    /* The same pose on the default arm is fine. */
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_OK);

    /* Joint 5 confined to [0.4, 0.6]: only the generating wrist branch fits. */
    ls_robot_model_t wrist = ls_robot_model_default;
    wrist.q_min_rad[4] = 0.4;
    wrist.q_max_rad[4] = 0.6;
    wrist.q_min_rad[0] = -1.0;
    wrist.q_max_rad[0] = 2.0;
    wrist.q_min_rad[2] = -0.5; /* excludes the other elbow */
    assert_int_equal(ls_kin_ik_all(&wrist, T, qs, &n), LS_OK);
    assert_int_equal(n, 1);
    for (int j = 0; j < 6; ++j) {
        assert_near(qs[0][j], q[j], 1e-9);
    }
}

static void test_ik_bad_input(void **state)
{
    (void)state;
    const double q[6] = { 0.1, 0.2, 0.3, 0.4, 0.5, 0.6 };
    double T[16], Tb[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    int n = -1;
    assert_int_equal(ls_kin_fk(M, q, T), LS_OK);

    memcpy(Tb, T, sizeof T);
    Tb[13] = NAN;
    assert_int_equal(ls_kin_ik_all(M, Tb, qs, &n), LS_EINVAL);
    assert_int_equal(n, 0);
    assert_int_equal(ls_kin_ik_nearest(M, Tb, q, out), LS_EINVAL);
    Tb[13] = T[13];
    Tb[0] = INFINITY;
    assert_int_equal(ls_kin_ik_all(M, Tb, qs, &n), LS_EINVAL);

    /* Not a rigid transform: scaled rotation, bad last row, reflection. */
    memcpy(Tb, T, sizeof T);
    Tb[0] *= 1.01;
    assert_int_equal(ls_kin_ik_all(M, Tb, qs, &n), LS_EINVAL);
    memcpy(Tb, T, sizeof T);
    Tb[3] = 0.5;
    assert_int_equal(ls_kin_ik_all(M, Tb, qs, &n), LS_EINVAL);
    memcpy(Tb, T, sizeof T);
    for (int i = 0; i < 3; ++i) {
        Tb[8 + i] = -Tb[8 + i];
    }
    assert_int_equal(ls_kin_ik_all(M, Tb, qs, &n), LS_EINVAL);

    const double qn[6] = { 0, NAN, 0, 0, 0, 0 };
    assert_int_equal(ls_kin_ik_nearest(M, T, qn, out), LS_EINVAL);
    assert_int_equal(ls_kin_ik_all(NULL, T, qs, &n), LS_EINVAL);
    assert_int_equal(ls_kin_ik_all(M, NULL, qs, &n), LS_EINVAL);
    assert_int_equal(ls_kin_ik_all(M, T, NULL, &n), LS_EINVAL);
    assert_int_equal(ls_kin_ik_all(M, T, qs, NULL), LS_EINVAL);
    assert_int_equal(ls_kin_ik_nearest(M, T, NULL, out), LS_EINVAL);
    assert_int_equal(ls_kin_ik_nearest(M, T, q, NULL), LS_EINVAL);

    /* A model without a spherical wrist has no closed form here. */
    ls_robot_model_t bent = ls_robot_model_default;
    bent.dh[4].a_m = 0.02;
    assert_int_equal(ls_kin_ik_all(&bent, T, qs, &n), LS_EINVAL);
}

/* Wrist centre on the joint 1 axis: q1 undetermined -> LS_ESINGULAR. */
static void test_ik_shoulder_singularity(void **state)
{
    (void)state;
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6];
    const double q0[6] = { 0 };
    int n = -1;
    /* Flange pointing up, 0.08 above a wrist centre at (0, 0, 0.92). */
    pose_from_axes((double[]){ 1, 0, 0 }, (double[]){ 0, 1, 0 }, (double[]){ 0, 0, 1 }, (double[]){ 0, 0, 1.0 }, T);
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_ESINGULAR);
    assert_int_equal(n, 0);
    assert_int_equal(ls_kin_ik_nearest(M, T, q0, out), LS_ESINGULAR);
    /* 1 mm off the axis it is solvable again. */
    T[12] = 1e-3;
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_OK);
    assert_true(n > 0);
}

/* q5 = 0: only q4 + q6 is defined. ik_all takes q4 = 0, ik_nearest q4 of the
 * seed; both reproduce the pose. */
static void test_ik_wrist_singularity(void **state)
{
    (void)state;
    const double q[6] = { 0.2, 0.3, 0.4, 0.7, 0.0, -0.5 };
    double T[16], Tb[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], out[6], dp, da;
    int n = -1;
    assert_int_equal(ls_kin_fk(M, q, T), LS_OK);
    assert_int_equal(ls_kin_ik_all(M, T, qs, &n), LS_OK);
    int found = 0;
    for (int b = 0; b < n; ++b) {
        assert_int_equal(ls_kin_fk(M, qs[b], Tb), LS_OK);
        kt_pose_error(T, Tb, &dp, &da);
        assert_true(dp < 1e-9 && da < 1e-9);
        if (fabs(qs[b][4]) < 1e-6) {
            assert_near(qs[b][3], 0.0, 0.0);
            if (fabs(qs[b][0] - q[0]) < 1e-9 && fabs(qs[b][2] - q[2]) < 1e-9) {
                found = 1;
                assert_near(qs[b][5], q[3] + q[5], 1e-9);
            }
        }
    }
    assert_true(found);

    /* The seed's own q4 comes back, and the seed is reproduced exactly. */
    assert_int_equal(ls_kin_ik_nearest(M, T, q, out), LS_OK);
    for (int j = 0; j < 6; ++j) {
        assert_near(out[j], q[j], 1e-9);
    }
    const double seed[6] = { 0.2, 0.3, 0.4, -1.1, 0.01, 0.0 };
    assert_int_equal(ls_kin_ik_nearest(M, T, seed, out), LS_OK);
    assert_near(out[3], -1.1, 0.0);
    assert_near(out[5], 0.2 + 1.1, 1e-9);
    assert_int_equal(ls_kin_fk(M, out, Tb), LS_OK);
    kt_pose_error(T, Tb, &dp, &da);
    assert_true(dp < 1e-9 && da < 1e-9);
}

/* ---- Jacobian ---------------------------------------------------------- */

static void test_jacobian_at_zero(void **state)
{
    (void)state;
    const double q[6] = { 0 };
    double J[36];
    assert_int_equal(ls_kin_jacobian(M, q, J), LS_OK);
    /* Joint 1 about base z with the flange at (0.51, 0, 0.84): v = z x p. */
    const double c1[6] = { 0, 0.51, 0, 0, 0, 1 };
    /* Joint 6 about the flange z = base x, through the flange: v = 0. */
    const double c6[6] = { 0, 0, 0, 1, 0, 0 };
    for (int i = 0; i < 6; ++i) {
        assert_near(J[i], c1[i], 1e-12);
        assert_near(J[30 + i], c6[i], 1e-12);
    }
    assert_int_equal(ls_kin_jacobian(M, NULL, J), LS_EINVAL);
    const double qn[6] = { 0, 0, 0, 0, NAN, 0 };
    assert_int_equal(ls_kin_jacobian(M, qn, J), LS_EINVAL);
}

static void test_jacobian_finite_differences(void **state)
{
    (void)state;
    kt_rng_t rng = { 7 };
    const double h = 1e-6;
    double worst = 0.0;
    for (int it = 0; it < 1000; ++it) {
        double q[6], J[36];
        kt_random_q(&rng, M, 0.0, q);
        assert_int_equal(ls_kin_jacobian(M, q, J), LS_OK);
        for (int j = 0; j < 6; ++j) {
            double qp[6], qm[6], Tp[16], Tm[16], Rrel[16] = { 0 }, w[3];
            memcpy(qp, q, sizeof q);
            memcpy(qm, q, sizeof q);
            qp[j] += h;
            qm[j] -= h;
            assert_int_equal(ls_kin_fk(M, qp, Tp), LS_OK);
            assert_int_equal(ls_kin_fk(M, qm, Tm), LS_OK);
            /* Rrel = R(q+h) R(q-h)^T = exp([w] 2h) in the base frame. */
            for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 3; ++c) {
                    double s = 0.0;
                    for (int k = 0; k < 3; ++k) {
                        s += Tp[k * 4 + r] * Tm[k * 4 + c];
                    }
                    Rrel[c * 4 + r] = s;
                }
            }
            kt_log_rot(Rrel, w);
            for (int i = 0; i < 3; ++i) {
                const double v_fd = (Tp[12 + i] - Tm[12 + i]) / (2 * h);
                const double w_fd = w[i] / (2 * h);
                const double ev = fabs(J[j * 6 + i] - v_fd), ew = fabs(J[j * 6 + 3 + i] - w_fd);
                worst = fmax(worst, fmax(ev, ew));
                if (ev > 1e-6 || ew > 1e-6) {
                    fail_msg("config %d column %d row %d: J v %.9g / w %.9g, FD v %.9g / w %.9g", it, j, i,
                             J[j * 6 + i], J[j * 6 + 3 + i], v_fd, w_fd);
                }
            }
        }
    }
    printf("[ info ] Jacobian vs central differences: worst deviation %.2g\n", worst);
}

/* For information only: cost of FK, Jacobian and ik_nearest. */
static void test_print_timings(void **state)
{
    (void)state;
    kt_rng_t rng = { 11 };
    enum { N = 10000 };
    static double qs[N][6];
    double T[16], J[36], out[6], sink = 0.0;
    for (int i = 0; i < N; ++i) {
        kt_random_q(&rng, M, 0.0, qs[i]);
    }
    double t0 = now_s();
    for (int i = 0; i < N; ++i) {
        assert_int_equal(ls_kin_fk(M, qs[i], T), LS_OK);
        sink += T[12];
    }
    const double t_fk = (now_s() - t0) / N;
    t0 = now_s();
    for (int i = 0; i < N; ++i) {
        assert_int_equal(ls_kin_jacobian(M, qs[i], J), LS_OK);
        sink += J[0];
    }
    const double t_j = (now_s() - t0) / N;
    double t_ik = 0.0;
    for (int i = 0; i < N; ++i) {
        assert_int_equal(ls_kin_fk(M, qs[i], T), LS_OK);
        t0 = now_s();
        const int rc = ls_kin_ik_nearest(M, T, qs[i], out);
        t_ik += now_s() - t0;
        assert_true(rc == LS_OK || rc == LS_ESINGULAR);
        sink += out[0];
    }
    printf("[ info ] per call: fk %.3f us, jacobian %.3f us, ik_nearest %.3f us (checksum %.3g)\n", 1e6 * t_fk,
           1e6 * t_j, 1e6 * t_ik / N, sink);
}

/* ---- pose helpers ------------------------------------------------------ */

static void test_rpy_axis_order(void **state)
{
    (void)state;
    double T[16], E[16];
    /* R = Rz(90) Ry(0) Rx(90): x -> y, y -> z, z -> x. */
    ls_pose_from_xyzrpy((double[]){ 1, 2, 3, LS_PI / 2, 0, LS_PI / 2 }, T);
    pose_from_axes((double[]){ 0, 1, 0 }, (double[]){ 0, 0, 1 }, (double[]){ 1, 0, 0 }, (double[]){ 1, 2, 3 }, E);
    assert_pose_near(T, E, 1e-15);
    /* Pitch alone: Ry(90) sends x to -z. */
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0, LS_PI / 2, 0 }, T);
    pose_from_axes((double[]){ 0, 0, -1 }, (double[]){ 0, 1, 0 }, (double[]){ 1, 0, 0 }, (double[]){ 0, 0, 0 }, E);
    assert_pose_near(T, E, 1e-15);
}

static void test_rpy_round_trip(void **state)
{
    (void)state;
    kt_rng_t rng = { 99 };
    for (int i = 0; i < 1000; ++i) {
        const double in[6] = { kt_uniform(&rng, -1, 1),
                               kt_uniform(&rng, -1, 1),
                               kt_uniform(&rng, -1, 1),
                               kt_uniform(&rng, -LS_PI, LS_PI),
                               kt_uniform(&rng, -LS_PI / 2 + 1e-6, LS_PI / 2 - 1e-6),
                               kt_uniform(&rng, -LS_PI, LS_PI) };
        double T[16], out[6], T2[16];
        ls_pose_from_xyzrpy(in, T);
        ls_pose_to_xyzrpy(T, out);
        for (int j = 0; j < 3; ++j) {
            assert_near(out[j], in[j], 0.0);
        }
        for (int j = 3; j < 6; ++j) {
            /* roll, yaw = +-pi are the same angle. */
            assert_true(fabs(kt_angdiff(out[j], in[j])) < 1e-9);
        }
        ls_pose_from_xyzrpy(out, T2);
        assert_pose_near(T, T2, 1e-14);
    }
}

static void test_rpy_gimbal_lock(void **state)
{
    (void)state;
    double T[16], out[6], T2[16];
    /* pitch = +pi/2: only yaw - roll is defined; roll = 0 by convention. */
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0.3, LS_PI / 2, 0.5 }, T);
    ls_pose_to_xyzrpy(T, out);
    assert_near(out[3], 0.0, 0.0);
    assert_near(out[4], LS_PI / 2, 1e-12);
    assert_near(out[5], 0.2, 1e-12);
    ls_pose_from_xyzrpy(out, T2);
    assert_pose_near(T, T2, 1e-12);
    /* pitch = -pi/2: only yaw + roll is defined. */
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0.3, -LS_PI / 2, 0.5 }, T);
    ls_pose_to_xyzrpy(T, out);
    assert_near(out[3], 0.0, 0.0);
    assert_near(out[4], -LS_PI / 2, 1e-12);
    assert_near(out[5], 0.8, 1e-12);
    ls_pose_from_xyzrpy(out, T2);
    assert_pose_near(T, T2, 1e-12);
    /* Near (not at) the lock the angles still reproduce the rotation. */
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0.3, LS_PI / 2 - 1e-9, 0.5 }, T);
    ls_pose_to_xyzrpy(T, out);
    ls_pose_from_xyzrpy(out, T2);
    assert_pose_near(T, T2, 1e-12);
}

static void test_pose_mul_inv(void **state)
{
    (void)state;
    kt_rng_t rng = { 5 };
    for (int i = 0; i < 100; ++i) {
        double in[6], T[16], Ti[16], P[16], I[16];
        for (int j = 0; j < 6; ++j) {
            in[j] = kt_uniform(&rng, -3, 3);
        }
        ls_pose_from_xyzrpy(in, T);
        ls_pose_inv(T, Ti);
        ls_pose_mul(Ti, T, P);
        pose_from_axes((double[]){ 1, 0, 0 }, (double[]){ 0, 1, 0 }, (double[]){ 0, 0, 1 }, (double[]){ 0, 0, 0 }, I);
        assert_pose_near(P, I, 1e-14);
        ls_pose_mul(T, Ti, P);
        assert_pose_near(P, I, 1e-14);
    }
    /* Exact composition: A = Rz(90) at (1, 0, 0), B = translation (1, 0, 0):
     * AB is at (1, 1, 0) with A's rotation. In-place output works. */
    double A[16], B[16], E[16];
    ls_pose_from_xyzrpy((double[]){ 1, 0, 0, 0, 0, LS_PI / 2 }, A);
    ls_pose_from_xyzrpy((double[]){ 1, 0, 0, 0, 0, 0 }, B);
    ls_pose_mul(A, B, A);
    pose_from_axes((double[]){ 0, 1, 0 }, (double[]){ -1, 0, 0 }, (double[]){ 0, 0, 1 }, (double[]){ 1, 1, 0 }, E);
    assert_pose_near(A, E, 1e-15);
}

static void test_pose_interp(void **state)
{
    (void)state;
    double A[16], B[16], T[16], E[16];
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0, 0, 0 }, A);
    ls_pose_from_xyzrpy((double[]){ 1, 2, 3, 0, 0, LS_PI / 2 }, B);
    ls_pose_interp(A, B, 0.0, T);
    assert_pose_near(T, A, 1e-15);
    ls_pose_interp(A, B, 1.0, T);
    assert_pose_near(T, B, 1e-15);
    ls_pose_interp(A, B, 0.5, T);
    ls_pose_from_xyzrpy((double[]){ 0.5, 1, 1.5, 0, 0, LS_PI / 4 }, E);
    assert_pose_near(T, E, 1e-15);
    /* Shortest arc: yaw 0 -> yaw 270 deg goes through -45 deg, not 135. */
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0, 0, 3 * LS_PI / 2 }, B);
    ls_pose_interp(A, B, 0.5, T);
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0, 0, -LS_PI / 4 }, E);
    assert_pose_near(T, E, 1e-15);
    /* Angle from A along the way is proportional to s. */
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0.4, -0.7, 2.0 }, B);
    const double total = ls_pose_angle(A, B);
    for (int i = 1; i < 10; ++i) {
        const double s = 0.1 * i;
        ls_pose_interp(A, B, s, T);
        assert_near(ls_pose_angle(A, T), s * total, 1e-12);
    }
}

static void test_pose_angle_dist(void **state)
{
    (void)state;
    double A[16], B[16];
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 0, 0, 0 }, A);
    ls_pose_from_xyzrpy((double[]){ 3, 4, 0, 0, 0, 0.3 }, B);
    assert_near(ls_pose_dist(A, B), 5.0, 1e-15);
    assert_near(ls_pose_angle(A, B), 0.3, 1e-15);
    assert_near(ls_pose_angle(B, A), 0.3, 1e-15);
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, LS_PI, 0, 0 }, B);
    assert_near(ls_pose_angle(A, B), LS_PI, 1e-15);
    ls_pose_from_xyzrpy((double[]){ 0, 0, 0, 1e-9, 0, 0 }, B);
    assert_near(ls_pose_angle(A, B), 1e-9, 1e-20);
    assert_near(ls_pose_angle(A, A), 0.0, 0.0);
    assert_true(isnan(ls_pose_angle(A, NULL)));
    assert_true(isnan(ls_pose_dist(NULL, B)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fk_zero),
        cmocka_unit_test(test_fk_hand_configurations),
        cmocka_unit_test(test_fk_bad_input),
        cmocka_unit_test(test_ik_round_trip_10000),
        cmocka_unit_test(test_ik_round_trip_variant_model),
        cmocka_unit_test(test_ik_eight_branches),
        cmocka_unit_test(test_ik_nearest_picks_seed_branch),
        cmocka_unit_test(test_ik_wraps),
        cmocka_unit_test(test_ik_unreachable),
        cmocka_unit_test(test_ik_limits),
        cmocka_unit_test(test_ik_bad_input),
        cmocka_unit_test(test_ik_shoulder_singularity),
        cmocka_unit_test(test_ik_wrist_singularity),
        cmocka_unit_test(test_jacobian_at_zero),
        cmocka_unit_test(test_jacobian_finite_differences),
        cmocka_unit_test(test_print_timings),
        cmocka_unit_test(test_rpy_axis_order),
        cmocka_unit_test(test_rpy_round_trip),
        cmocka_unit_test(test_rpy_gimbal_lock),
        cmocka_unit_test(test_pose_mul_inv),
        cmocka_unit_test(test_pose_interp),
        cmocka_unit_test(test_pose_angle_dist),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
