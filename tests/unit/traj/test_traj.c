/* ls_traj: seven-segment profiles, synchronisation, sampling.
 * Expected durations and phase lengths are worked out by hand in the
 * comments; random cases use a fixed seed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "ls_traj.h"
#include "test_rng.h"

#define REL_TOL 1e-9
#define KHZ_DT_S 1e-3

/* ---- helpers ------------------------------------------------------------ */

static test_rng_t g_rng = { 0x9E3779B97F4A7C15u };

static double urand(double lo, double hi)
{
    return test_rng_uniform(&g_rng, lo, hi);
}

static void assert_close(double got, double want, double rel)
{
    const double tol = rel * (fabs(want) > 1.0 ? fabs(want) : 1.0);
    if (!(fabs(got - want) <= tol)) {
        fail_msg("got %.17g, want %.17g (tolerance %.3g)", got, want, tol);
    }
}

static double phase_sum(const ls_traj_axis_t *ax)
{
    double s = 0.0;
    for (int k = 0; k < 7; ++k) {
        s += ax->t[k];
    }
    return s;
}

/* Samples at 1 kHz plus the end: |v|, |a| and the finite-difference jerk
 * stay within the limits; the first and last samples are the end points. */
static void assert_axis_within_limits(const ls_traj_axis_t *ax, double v_max, double a_max, double j_max)
{
    double a_prev = 0.0;
    const long steps = (long)floor(ax->T / KHZ_DT_S);
    for (long k = 0; k <= steps; ++k) {
        double p, v, a;
        ls_traj_sample_axis(ax, (double)k * KHZ_DT_S, &p, &v, &a);
        if (fabs(v) > v_max * (1.0 + REL_TOL) || fabs(a) > a_max * (1.0 + REL_TOL)) {
            fail_msg("limit exceeded at t=%.6f: v=%.17g (max %g) a=%.17g (max %g)", (double)k * KHZ_DT_S, v, v_max, a,
                     a_max);
        }
        if (k > 0 && fabs(a - a_prev) / KHZ_DT_S > j_max * (1.0 + REL_TOL)) {
            fail_msg("jerk %.17g exceeds %g at t=%.6f", fabs(a - a_prev) / KHZ_DT_S, j_max, (double)k * KHZ_DT_S);
        }
        a_prev = a;
    }
}

/* p, v, a are continuous at every phase boundary and v, a are the
 * derivatives of p (central differences). */
static void assert_axis_continuous(const ls_traj_axis_t *ax)
{
    const double J = fabs(ax->j);
    const double eps = 1e-7;
    double tb = 0.0;
    for (int k = 0; k < 7; ++k) {
        tb += ax->t[k];
        if (tb <= eps || tb >= ax->T - eps) {
            continue;
        }
        double pl, vl, al, pr, vr, ar;
        ls_traj_sample_axis(ax, tb - eps, &pl, &vl, &al);
        ls_traj_sample_axis(ax, tb + eps, &pr, &vr, &ar);
        /* Over 2 eps, a moves by at most 2 J eps, v by 2 a_max eps, and so on. */
        const double scale = 1.0 + fabs(ax->dist);
        if (fabs(ar - al) > 2.0 * J * eps + 1e-9 * scale || fabs(vr - vl) > 2.0 * fabs(al) * eps + 1e-9 * scale ||
            fabs(pr - pl) > 2.0 * fabs(vl) * eps + 1e-9 * scale) {
            fail_msg("jump at boundary %d (t=%.17g): p %.17g/%.17g v %.17g/%.17g a %.17g/%.17g", k, tb, pl, pr, vl, vr,
                     al, ar);
        }
    }
    const double h = 1e-5;
    for (int k = 1; k < 50; ++k) {
        const double t = ax->T * (double)k / 50.0;
        double pm, vm, am, p, v, a, pp, vp, ap;
        ls_traj_sample_axis(ax, t - h, &pm, &vm, &am);
        ls_traj_sample_axis(ax, t, &p, &v, &a);
        ls_traj_sample_axis(ax, t + h, &pp, &vp, &ap);
        const double J_h2 = J * h * h;
        if (fabs((pp - pm) / (2.0 * h) - v) > J_h2 + 1e-8 * (1.0 + fabs(ax->dist)) ||
            fabs((vp - vm) / (2.0 * h) - a) > J * h + 1e-8) {
            fail_msg("v or a is not the derivative at t=%.17g", t);
        }
    }
}

static void random_limits(double *v_max, double *a_max, double *j_max)
{
    *v_max = urand(0.05, 5.0);
    *a_max = urand(0.1, 30.0);
    *j_max = urand(0.2, 500.0);
}

/* ---- minimum-time profiles: hand-computed cases -------------------------- */

static void test_pure_jerk_profile(void **state)
{
    (void)state;
    /* d=1, v=a=j=1: v_max would need 2 of distance to reach, a_max needs 2:
     * pure jerk phases, 2 v sqrt(v) = 1, Tj = (1/2)^(1/3), T = 4 Tj = 2^(5/3). */
    ls_traj_axis_t ax;
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, 1.0, 1.0, 1.0), LS_OK);
    assert_close(ax.T, pow(2.0, 5.0 / 3.0), 1e-14);
    assert_close(ax.t[0], cbrt(0.5), 1e-14);
    assert_true(ax.t[1] == 0.0 && ax.t[3] == 0.0);
    assert_close(phase_sum(&ax), ax.T, 1e-15);
    assert_true(ax.j == 1.0);
    double p, v, a;
    ls_traj_sample_axis(&ax, ax.T / 2.0, &p, &v, &a);
    assert_close(p, 0.5, 1e-14);
    assert_close(v, pow(0.25, 1.0 / 3.0), 1e-14); /* v_peak = (d^2 j / 4)^(1/3) */
    assert_close(a, 0.0, 1e-14);
    ls_traj_sample_axis(&ax, ax.t[0], NULL, NULL, &a);
    assert_close(a, cbrt(0.5), 1e-14); /* peak acceleration j Tj < a_max */
}

static void test_cruise_without_const_accel(void **state)
{
    (void)state;
    /* d=10, v=a=j=1: a_max is reached exactly at v_max (a^2/j = v): Tj=1,
     * Ta=0, acceleration half 2 s covering 2, cruise 8 s: T = 12. */
    ls_traj_axis_t ax;
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 10.0, 1.0, 1.0, 1.0), LS_OK);
    assert_close(ax.T, 12.0, 1e-15);
    assert_close(ax.t[0], 1.0, 1e-15);
    assert_close(ax.t[1], 0.0, 1e-15);
    assert_close(ax.t[3], 8.0, 1e-15);
    /* d=20, v=4, a=10, j=1: a_max unreachable (a^2/j=100 > 4): Tj = 2,
     * half covers 4*4/2... v Tacc = 16, cruise (20-16)/4 = 1: T = 9. */
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 20.0, 4.0, 10.0, 1.0), LS_OK);
    assert_close(ax.T, 9.0, 1e-15);
    assert_close(ax.t[0], 2.0, 1e-15);
    assert_true(ax.t[1] == 0.0);
    assert_close(ax.t[3], 1.0, 1e-15);
}

static void test_full_profile(void **state)
{
    (void)state;
    /* d=10, v=2, a=1, j=2: Tj = a/j = 0.5, Ta = v/a - Tj = 1.5, Tacc = 2.5
     * covers v Tacc = 5 (both halves), cruise 5/2 = 2.5: T = 7.5. */
    ls_traj_axis_t ax;
    assert_int_equal(ls_traj_plan_axis(&ax, 1.0, 11.0, 2.0, 1.0, 2.0), LS_OK);
    assert_close(ax.T, 7.5, 1e-15);
    const double want[7] = { 0.5, 1.5, 0.5, 2.5, 0.5, 1.5, 0.5 };
    for (int k = 0; k < 7; ++k) {
        assert_close(ax.t[k], want[k], 1e-15);
    }
    double p, v, a;
    ls_traj_sample_axis(&ax, 1.0, &p, &v, &a); /* inside the constant-acceleration phase */
    assert_close(a, 1.0, 1e-15);
    /* p(0.5) = j t^3/6 = 1/24, v(0.5) = 1/4; then 0.5 s at a=1. */
    assert_close(v, 0.25 + 0.5, 1e-15);
    assert_close(p, 1.0 + 1.0 / 24.0 + 0.25 * 0.5 + 0.5 * 0.25, 1e-15);
    ls_traj_sample_axis(&ax, 3.75, &p, &v, &a); /* middle of the cruise */
    assert_close(p, 6.0, 1e-14);
    assert_close(v, 2.0, 1e-15);
    assert_close(a, 0.0, 1e-15);
    assert_axis_continuous(&ax);
    assert_axis_within_limits(&ax, 2.0, 1.0, 2.0);
}

static void test_no_cruise_with_const_accel(void **state)
{
    (void)state;
    /* d=2, v=10, a=1, j=2: v^2/a + v a/j = d gives v = (sqrt(33)-1)/4 and
     * T = v/a + a/j + d/v = (1 + sqrt(33))/2. */
    ls_traj_axis_t ax;
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 2.0, 10.0, 1.0, 2.0), LS_OK);
    assert_close(ax.T, (1.0 + sqrt(33.0)) / 2.0, 1e-14);
    assert_close(ax.t[0], 0.5, 1e-15);
    assert_close(ax.t[1], (sqrt(33.0) - 1.0) / 4.0 - 0.5, 1e-14);
    assert_true(ax.t[3] == 0.0);
    assert_axis_continuous(&ax);
    assert_axis_within_limits(&ax, 10.0, 1.0, 2.0);
}

static void test_negative_distance_mirrors(void **state)
{
    (void)state;
    ls_traj_axis_t up, down;
    assert_int_equal(ls_traj_plan_axis(&up, 0.0, 10.0, 2.0, 1.0, 2.0), LS_OK);
    assert_int_equal(ls_traj_plan_axis(&down, 3.0, -7.0, 2.0, 1.0, 2.0), LS_OK);
    assert_true(down.T == up.T);
    assert_true(down.j == -2.0);
    assert_close(down.dist, -10.0, 0.0);
    for (int k = 0; k <= 75; ++k) {
        const double t = 0.1 * (double)k;
        double pu, vu, au, pd, vd, ad;
        ls_traj_sample_axis(&up, t, &pu, &vu, &au);
        ls_traj_sample_axis(&down, t, &pd, &vd, &ad);
        assert_close(pd - 3.0, -pu, 1e-14);
        assert_close(vd, -vu, 1e-15);
        assert_close(ad, -au, 1e-15);
    }
}

static void test_zero_distance(void **state)
{
    (void)state;
    ls_traj_axis_t ax;
    assert_int_equal(ls_traj_plan_axis(&ax, 0.25, 0.25, 1.0, 1.0, 1.0), LS_OK);
    assert_true(ax.T == 0.0);
    assert_true(ax.j == 0.0);
    double p = -1.0, v = -1.0, a = -1.0;
    ls_traj_sample_axis(&ax, 0.0, &p, &v, &a);
    assert_true(p == 0.25 && v == 0.0 && a == 0.0);
    ls_traj_sample_axis(&ax, 3.0, &p, &v, &a);
    assert_true(p == 0.25 && v == 0.0 && a == 0.0);
}

static void test_endpoints_exact_and_clamped(void **state)
{
    (void)state;
    g_rng.s = 11;
    for (int k = 0; k < 500; ++k) {
        double vm, am, jm;
        random_limits(&vm, &am, &jm);
        const double p0 = urand(-100.0, 100.0), p1 = urand(-100.0, 100.0);
        ls_traj_axis_t ax;
        assert_int_equal(ls_traj_plan_axis(&ax, p0, p1, vm, am, jm), LS_OK);
        double p, v, a;
        ls_traj_sample_axis(&ax, 0.0, &p, &v, &a);
        assert_true(p == p0 && v == 0.0 && a == 0.0);
        ls_traj_sample_axis(&ax, -5.0, &p, &v, &a);
        assert_true(p == p0 && v == 0.0 && a == 0.0);
        ls_traj_sample_axis(&ax, NAN, &p, &v, &a);
        assert_true(p == p0 && v == 0.0 && a == 0.0);
        ls_traj_sample_axis(&ax, ax.T, &p, &v, &a);
        assert_true(p == p1 && v == 0.0 && a == 0.0);
        ls_traj_sample_axis(&ax, ax.T + 1e6, &p, &v, &a);
        assert_true(p == p1 && v == 0.0 && a == 0.0);
        ls_traj_sample_axis(&ax, INFINITY, &p, &v, &a);
        assert_true(p == p1 && v == 0.0 && a == 0.0);
        assert_close(phase_sum(&ax), ax.T, 1e-14);
    }
}

/* Every profile shape, random: limits hold at 1 kHz, continuity holds, and the
 * duration is minimal: with the peak velocity it reaches, no faster
 * profile exists (it saturates v_max, or its cruise is empty). */
static void test_random_profiles_limits_continuity(void **state)
{
    (void)state;
    g_rng.s = 12345;
    int shapes[4] = { 0, 0, 0, 0 }; /* [cruise?][a_max reached?] */
    for (int k = 0; k < 300; ++k) {
        double vm, am, jm;
        random_limits(&vm, &am, &jm);
        const double d = urand(-10.0, 10.0);
        ls_traj_axis_t ax;
        assert_int_equal(ls_traj_plan_axis(&ax, 0.0, d, vm, am, jm), LS_OK);
        assert_axis_within_limits(&ax, vm, am, jm);
        assert_axis_continuous(&ax);
        const double vpk = jm * ax.t[0] * (ax.t[0] + ax.t[1]);
        assert_true(ax.t[3] == 0.0 || fabs(vpk - vm) <= 1e-12 * vm);
        shapes[(ax.t[3] > 0.0 ? 2 : 0) + (ax.t[1] > 0.0 ? 1 : 0)]++;
    }
    for (int s = 0; s < 4; ++s) {
        assert_true(shapes[s] > 10); /* all four shapes were exercised */
    }
}

/* ---- exact duration ----------------------------------------------------- */

static void test_duration_hand_cases(void **state)
{
    (void)state;
    ls_traj_axis_t ax;
    /* d=1, v=a=j=1, T=5: pure jerk with Tj=s: T = 2 s + d/(j s^2), so s = 0.5,
     * peak v = j s^2 = 0.25, cruise 5 - 4 s = 3. */
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 1.0, 1.0, 1.0, 1.0, 5.0), LS_OK);
    assert_true(ax.T == 5.0);
    assert_close(ax.t[0], 0.5, 1e-13);
    assert_true(ax.t[1] == 0.0);
    assert_close(ax.t[3], 3.0, 1e-13);
    assert_axis_within_limits(&ax, 1.0, 1.0, 1.0);
    assert_axis_continuous(&ax);
    /* d=10, v=2, a=1, j=2, T=26/3: with peak 1.5, T = v/a + a/j + d/v = 26/3:
     * Tj = 0.5, Ta = 1, cruise 26/3 - 4 = 14/3. */
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 10.0, 2.0, 1.0, 2.0, 26.0 / 3.0), LS_OK);
    assert_true(ax.T == 26.0 / 3.0);
    assert_close(ax.t[0], 0.5, 1e-14);
    assert_close(ax.t[1], 1.0, 1e-13);
    assert_close(ax.t[3], 14.0 / 3.0, 1e-13);
    double v;
    ls_traj_sample_axis(&ax, ax.T / 2.0, NULL, &v, NULL);
    assert_close(v, 1.5, 1e-13);
    /* Standing still for a given time. */
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 2.0, 2.0, 1.0, 1.0, 1.0, 3.0), LS_OK);
    assert_true(ax.T == 3.0);
    double p;
    ls_traj_sample_axis(&ax, 1.5, &p, &v, NULL);
    assert_true(p == 2.0 && v == 0.0);
}

static void test_duration_very_long(void **state)
{
    (void)state;
    /* d=10, v=1, a=10, j=1 (a_max out of reach: pure jerk phases) stretched
     * to 1e9 s: the peak v ~ 1e-8 must still satisfy the defining equation
     * d = v (T - Tacc), Tacc = 2 sqrt(v / j), and the halves must meet. */
    const double T[2] = { 1e9, 1e6 };
    for (int k = 0; k < 2; ++k) {
        ls_traj_axis_t ax;
        assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 10.0, 1.0, 10.0, 1.0, T[k]), LS_OK);
        const double v = ax.t[0] * ax.t[0]; /* j Tj^2 with j = 1 */
        assert_close(v * (T[k] - 2.0 * ax.t[0]), 10.0, 1e-12);
        double pl, pr;
        ls_traj_sample_axis(&ax, T[k] / 2.0 * (1.0 - 1e-15), &pl, NULL, NULL);
        ls_traj_sample_axis(&ax, T[k] / 2.0 * (1.0 + 1e-15), &pr, NULL, NULL);
        assert_close(pl, 5.0, 1e-12);
        assert_close(pr, 5.0, 1e-12);
    }
}

static void test_duration_too_short(void **state)
{
    (void)state;
    ls_traj_axis_t ax, before;
    memset(&ax, 0x5a, sizeof ax);
    before = ax;
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 10.0, 1.0, 1.0, 1.0, 11.9), LS_ETIME);
    assert_memory_equal(&ax, &before, sizeof ax);
    /* Rounding below the minimum is absorbed. */
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 10.0, 1.0, 1.0, 1.0, 12.0 * (1.0 - 1e-14)), LS_OK);
    assert_true(ax.T == 12.0 * (1.0 - 1e-14));
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 10.0, 1.0, 1.0, 1.0, 12.0), LS_OK);
    assert_close(ax.t[3], 8.0, 1e-15);
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0), LS_OK);
    assert_true(ax.T == 0.0);
}

static void test_duration_random(void **state)
{
    (void)state;
    g_rng.s = 777;
    for (int k = 0; k < 300; ++k) {
        double vm, am, jm;
        random_limits(&vm, &am, &jm);
        const double d = urand(-10.0, 10.0);
        ls_traj_axis_t fast, ax;
        assert_int_equal(ls_traj_plan_axis(&fast, 1.0, 1.0 + d, vm, am, jm), LS_OK);
        const double T = fast.T * (k % 3 == 0 ? urand(1.0, 1.01) : urand(1.0, 20.0));
        assert_int_equal(ls_traj_plan_axis_duration(&ax, 1.0, 1.0 + d, vm, am, jm, T), LS_OK);
        assert_true(ax.T == T);
        assert_close(phase_sum(&ax), T, 1e-13);
        /* The profile really covers d: the two halves meet in the middle. */
        double pl, pr;
        ls_traj_sample_axis(&ax, T / 2.0 * (1.0 - 1e-15), &pl, NULL, NULL);
        ls_traj_sample_axis(&ax, T / 2.0 * (1.0 + 1e-15), &pr, NULL, NULL);
        assert_close(pl, pr, 1e-12);
        assert_close(pl, 1.0 + d / 2.0, 1e-12);
        assert_axis_within_limits(&ax, vm, am, jm);
        assert_axis_continuous(&ax);
        double p;
        ls_traj_sample_axis(&ax, T, &p, NULL, NULL);
        assert_true(p == 1.0 + d);
    }
}

/* ---- synchronisation ---------------------------------------------------- */

static void test_sync_hand_case(void **state)
{
    (void)state;
    /* Axis 0 needs 12 s (d=10, v=a=j=1), axis 1 2^(5/3) s (d=-1), axis 2
     * does not move: all last 12 s. */
    const double p0[3] = { 0.0, 1.0, 5.0 }, p1[3] = { 10.0, 0.0, 5.0 };
    const ls_traj_limits_t lim = { .v_max = { 1, 1, 1 }, .a_max = { 1, 1, 1 }, .j_max = { 1, 1, 1 } };
    ls_traj_t tr;
    assert_int_equal(ls_traj_plan(&tr, 3, p0, p1, &lim), LS_OK);
    assert_int_equal(tr.n, 3);
    assert_close(tr.duration_s, 12.0, 1e-15);
    for (int i = 0; i < 3; ++i) {
        assert_true(tr.axis[i].T == tr.duration_s);
    }
    double p[3], v[3], a[3];
    ls_traj_sample(&tr, 6.0, p, v, a);
    assert_close(p[0], 5.0, 1e-14);
    assert_close(p[1], 0.5, 1e-14);
    assert_true(p[2] == 5.0 && v[2] == 0.0);
    ls_traj_sample(&tr, 12.0, p, v, a);
    for (int i = 0; i < 3; ++i) {
        assert_true(p[i] == p1[i] && v[i] == 0.0 && a[i] == 0.0);
    }
    ls_traj_sample(&tr, 1.0, NULL, v, NULL); /* NULL outputs are skipped */
    assert_true(v[0] > 0.0 && v[1] < 0.0);
}

static void test_sync_random(void **state)
{
    (void)state;
    g_rng.s = 4242;
    for (int k = 0; k < 100; ++k) {
        const uint8_t n = (uint8_t)(1 + k % LS_TRAJ_MAX_AXES);
        double p0[LS_TRAJ_MAX_AXES], p1[LS_TRAJ_MAX_AXES];
        ls_traj_limits_t lim;
        double slowest = 0.0;
        for (uint8_t i = 0; i < n; ++i) {
            p0[i] = urand(-3.0, 3.0);
            p1[i] = urand(-3.0, 3.0);
            random_limits(&lim.v_max[i], &lim.a_max[i], &lim.j_max[i]);
            ls_traj_axis_t alone;
            assert_int_equal(ls_traj_plan_axis(&alone, p0[i], p1[i], lim.v_max[i], lim.a_max[i], lim.j_max[i]), LS_OK);
            slowest = alone.T > slowest ? alone.T : slowest;
        }
        ls_traj_t tr;
        assert_int_equal(ls_traj_plan(&tr, n, p0, p1, &lim), LS_OK);
        assert_true(tr.duration_s == slowest);
        for (uint8_t i = 0; i < n; ++i) {
            assert_true(tr.axis[i].T == tr.duration_s);
            assert_axis_within_limits(&tr.axis[i], lim.v_max[i], lim.a_max[i], lim.j_max[i]);
        }
        double p[LS_TRAJ_MAX_AXES];
        ls_traj_sample(&tr, tr.duration_s, p, NULL, NULL);
        for (uint8_t i = 0; i < n; ++i) {
            assert_true(p[i] == p1[i]);
        }
    }
}

/* ---- bad input ----------------------------------------------------------- */

static void test_bad_input(void **state)
{
    (void)state;
    ls_traj_axis_t ax, before;
    memset(&ax, 0x3c, sizeof ax);
    before = ax;
    const double bad[] = { NAN, INFINITY, -INFINITY };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        assert_int_equal(ls_traj_plan_axis(&ax, bad[k], 1.0, 1.0, 1.0, 1.0), LS_EINVAL);
        assert_int_equal(ls_traj_plan_axis(&ax, 0.0, bad[k], 1.0, 1.0, 1.0), LS_EINVAL);
        assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, bad[k], 1.0, 1.0), LS_EINVAL);
        assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, 1.0, bad[k], 1.0), LS_EINVAL);
        assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, 1.0, 1.0, bad[k]), LS_EINVAL);
        assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 1.0, 1.0, 1.0, 1.0, bad[k]), LS_EINVAL);
    }
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, 0.0, 1.0, 1.0), LS_EINVAL);
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, 1.0, -1.0, 1.0), LS_EINVAL);
    assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, 1.0, 1.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_traj_plan_axis(&ax, -1e308, 1e308, 1.0, 1.0, 1.0), LS_EINVAL); /* p1 - p0 overflows */
    assert_int_equal(ls_traj_plan_axis_duration(&ax, 0.0, 1.0, 1.0, 1.0, 1.0, -1.0), LS_EINVAL);
    assert_memory_equal(&ax, &before, sizeof ax);
    assert_int_equal(ls_traj_plan_axis(NULL, 0.0, 1.0, 1.0, 1.0, 1.0), LS_EINVAL);
    assert_int_equal(ls_traj_plan_axis_duration(NULL, 0.0, 1.0, 1.0, 1.0, 1.0, 5.0), LS_EINVAL);

    const double p0[LS_TRAJ_MAX_AXES + 1] = { 0 }, p1[LS_TRAJ_MAX_AXES + 1] = { 1, 1, 1, 1, 1, 1, 1, 1, 1 };
    ls_traj_limits_t lim;
    for (int i = 0; i < LS_TRAJ_MAX_AXES; ++i) {
        lim.v_max[i] = lim.a_max[i] = lim.j_max[i] = 1.0;
    }
    ls_traj_t tr, tr_before;
    memset(&tr, 0x77, sizeof tr);
    tr_before = tr;
    assert_int_equal(ls_traj_plan(&tr, 0, p0, p1, &lim), LS_EINVAL);
    assert_int_equal(ls_traj_plan(&tr, LS_TRAJ_MAX_AXES + 1, p0, p1, &lim), LS_EINVAL);
    assert_int_equal(ls_traj_plan(NULL, 2, p0, p1, &lim), LS_EINVAL);
    assert_int_equal(ls_traj_plan(&tr, 2, NULL, p1, &lim), LS_EINVAL);
    assert_int_equal(ls_traj_plan(&tr, 2, p0, NULL, &lim), LS_EINVAL);
    assert_int_equal(ls_traj_plan(&tr, 2, p0, p1, NULL), LS_EINVAL);
    lim.j_max[3] = NAN; /* one bad axis rejects the whole plan */
    assert_int_equal(ls_traj_plan(&tr, 4, p0, p1, &lim), LS_EINVAL);
    assert_memory_equal(&tr, &tr_before, sizeof tr);
    assert_int_equal(ls_traj_plan(&tr, 3, p0, p1, &lim), LS_OK); /* axis 3 unused */

    ls_traj_sample(NULL, 1.0, NULL, NULL, NULL); /* no crash */
    ls_traj_sample_axis(NULL, 1.0, NULL, NULL, NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pure_jerk_profile),
        cmocka_unit_test(test_cruise_without_const_accel),
        cmocka_unit_test(test_full_profile),
        cmocka_unit_test(test_no_cruise_with_const_accel),
        cmocka_unit_test(test_negative_distance_mirrors),
        cmocka_unit_test(test_zero_distance),
        cmocka_unit_test(test_endpoints_exact_and_clamped),
        cmocka_unit_test(test_random_profiles_limits_continuity),
        cmocka_unit_test(test_duration_hand_cases),
        cmocka_unit_test(test_duration_very_long),
        cmocka_unit_test(test_duration_too_short),
        cmocka_unit_test(test_duration_random),
        cmocka_unit_test(test_sync_hand_case),
        cmocka_unit_test(test_sync_random),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
