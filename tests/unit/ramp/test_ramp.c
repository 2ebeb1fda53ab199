/* ls_ramp: velocity ramps from any state to a target velocity at zero
 * acceleration. Hand-worked cases in the comments; random cases use a fixed
 * seed and compare the minimum duration with ruckig's velocity interface
 * (ls_otg_plan_velocity), one axis and six synchronised. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "ls_otg.h"
#include "ls_ramp.h"
#include "test_rng.h"

#define REL_TOL 1e-9
#define DT_S 1e-4
#define N_RANDOM 2000

static test_rng_t g_rng = { 0xD1B54A32D192ED03u };
static ls_otg_planner_t g_pl;

static double urand(double lo, double hi)
{
    return test_rng_uniform(&g_rng, lo, hi);
}

static void assert_close(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol)) {
        fail_msg("got %.17g, want %.17g (tolerance %.3g)", got, want, tol);
    }
}

/* A random problem within the limits: |a0| <= a_max. */
typedef struct {
    double v0, a0, v1, a_max, j_max;
} problem_t;

static problem_t random_problem(void)
{
    problem_t q;
    q.a_max = urand(0.5, 20.0);
    q.j_max = urand(5.0, 400.0);
    q.v0 = urand(-3.0, 3.0);
    q.a0 = urand(-q.a_max, q.a_max);
    q.v1 = (urand(0.0, 1.0) < 0.5) ? 0.0 : urand(-3.0, 3.0);
    return q;
}

/* Sampled every DT_S: |a| within max(a_max, |a0|), the jerk between samples
 * within j_max, and the end state (v1, 0) from the duration on. */
static void assert_ramp_within_limits(const ls_ramp_t *r, const problem_t *q)
{
    const double a_lim = fmax(q->a_max, fabs(q->a0)) * (1.0 + REL_TOL) + 1e-12;
    double a_prev = q->a0;
    const long steps = (long)ceil(r->duration_s / DT_S) + 2;
    for (long k = 1; k <= steps; k++) {
        double v, a;
        ls_ramp_sample(r, (double)k * DT_S, NULL, &v, &a);
        if (fabs(a) > a_lim) {
            fail_msg("a = %.17g beyond %.17g at t = %g", a, a_lim, (double)k * DT_S);
        }
        if (fabs(a - a_prev) > q->j_max * DT_S * (1.0 + 1e-6) + 1e-12) {
            fail_msg("jerk %.17g beyond %g at t = %g", (a - a_prev) / DT_S, q->j_max, (double)k * DT_S);
        }
        a_prev = a;
    }
    double v, a;
    ls_ramp_sample(r, r->duration_s, NULL, &v, &a);
    assert_close(v, q->v1, 1e-9 * (1.0 + fabs(q->v0) + fabs(q->v1)));
    assert_close(a, 0.0, 1e-9 * q->a_max);
    /* The sample just before the end agrees with the end (no jump). */
    double v_b, a_b;
    ls_ramp_sample(r, r->duration_s * (1.0 - 1e-12), NULL, &v_b, &a_b);
    assert_close(v_b, q->v1, 1e-8 * (1.0 + fabs(q->v0) + fabs(q->v1)));
}

static double otg_duration(uint8_t n, const problem_t *q)
{
    ls_otg_state_t cur = { 0 }, tgt = { 0 };
    ls_otg_limits_t lim;
    for (uint8_t i = 0; i < n; i++) {
        cur.v[i] = q[i].v0;
        cur.a[i] = q[i].a0;
        tgt.v[i] = q[i].v1;
        lim.v_max[i] = 1e3; /* the velocity interface does not limit velocity */
        lim.a_max[i] = q[i].a_max;
        lim.j_max[i] = q[i].j_max;
    }
    ls_otg_t tr;
    assert_int_equal(ls_otg_plan_velocity(&g_pl, &tr, n, &cur, &tgt, &lim), LS_OK);
    return tr.duration_s;
}

/* ---- hand-worked ------------------------------------------------------- */

static void test_stop_from_cruise_by_hand(void **state)
{
    (void)state;
    ls_ramp_t r;
    /* v0 = 1, a_max = 2, j_max = 10: sqrt(J v0) = 3.16 > 2, so the peak is 2:
     * jerk phases of 2/10 = 0.2 s shed 2 x 2^2/(2 x 10) = 0.4, the hold sheds
     * the remaining 0.6 at 2 in 0.3 s: 0.7 s. Distance: 0.35 (symmetric, mean
     * speed 0.5). */
    assert_int_equal(ls_ramp_plan(&r, 5.0, 1.0, 0.0, 0.0, 2.0, 10.0), LS_OK);
    assert_close(r.t[0], 0.2, 1e-12);
    assert_close(r.t[1], 0.3, 1e-12);
    assert_close(r.t[2], 0.2, 1e-12);
    assert_close(r.duration_s, 0.7, 1e-12);
    double p, v, a;
    ls_ramp_sample(&r, 10.0, &p, &v, &a);
    assert_close(p, 5.35, 1e-12);
    assert_close(v, 0.0, 0.0);
    assert_close(a, 0.0, 0.0);
    assert_close(ls_ramp_jerk(&r, 0.1), -10.0, 0.0);
    assert_close(ls_ramp_jerk(&r, 0.3), 0.0, 0.0);
    assert_close(ls_ramp_jerk(&r, 0.6), 10.0, 0.0);
    assert_close(ls_ramp_jerk(&r, 0.8), 0.0, 0.0);
}

static void test_start_already_braking_by_hand(void **state)
{
    (void)state;
    ls_ramp_t r;
    /* v0 = 0.05, a0 = -1, j_max = 10: bringing a to 0 sheds 1/20 = 0.05, all
     * that is left: one phase of +10 for 0.1 s. */
    assert_int_equal(ls_ramp_plan(&r, 0.0, 0.05, -1.0, 0.0, 2.0, 10.0), LS_OK);
    assert_close(r.duration_s, 0.1, 1e-12);
    assert_close(ls_ramp_jerk(&r, 0.05), 10.0, 0.0);
    /* Asked to take 0.5 s: the same phase, then it holds at rest. */
    assert_int_equal(ls_ramp_plan_duration(&r, 0.0, 0.05, -1.0, 0.0, 2.0, 10.0, 0.5), LS_OK);
    assert_close(r.duration_s, 0.5, 1e-12);
    double v;
    ls_ramp_sample(&r, 0.1, NULL, &v, NULL);
    assert_close(v, 0.0, 1e-12);
}

static void test_ramp_up_to_a_speed_by_hand(void **state)
{
    (void)state;
    ls_ramp_t r;
    /* From rest to 0.1 with a_max 4, j_max 40: sqrt(40 x 0.1) = 2 < 4, no
     * hold: two phases of 2/40 = 0.05 s. After the ramp it moves at 0.1. */
    assert_int_equal(ls_ramp_plan(&r, 0.0, 0.0, 0.0, 0.1, 4.0, 40.0), LS_OK);
    assert_close(r.duration_s, 0.1, 1e-12);
    double p0, p1, v;
    ls_ramp_sample(&r, 0.1, &p0, &v, NULL);
    assert_close(v, 0.1, 1e-12);
    assert_close(p0, 0.005, 1e-12); /* symmetric: mean speed 0.05 for 0.1 s */
    ls_ramp_sample(&r, 0.3, &p1, NULL, NULL);
    assert_close(p1 - p0, 0.02, 1e-12);
}

static void test_nothing_to_do(void **state)
{
    (void)state;
    ls_ramp_t r;
    assert_int_equal(ls_ramp_plan(&r, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0), LS_OK);
    assert_close(r.duration_s, 0.0, 0.0);
    assert_int_equal(ls_ramp_plan_duration(&r, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.3), LS_OK);
    assert_close(r.duration_s, 0.3, 1e-15);
    double p;
    ls_ramp_sample(&r, 0.2, &p, NULL, NULL);
    assert_close(p, 1.0, 0.0);
}

static void test_bad_input_is_refused(void **state)
{
    (void)state;
    ls_ramp_t r = { .duration_s = 42.0 };
    assert_int_equal(ls_ramp_plan(NULL, 0, 1, 0, 0, 1, 1), LS_EINVAL);
    assert_int_equal(ls_ramp_plan(&r, 0, NAN, 0, 0, 1, 1), LS_EINVAL);
    assert_int_equal(ls_ramp_plan(&r, 0, 1, INFINITY, 0, 1, 1), LS_EINVAL);
    assert_int_equal(ls_ramp_plan(&r, 0, 1, 0, 0, 0.0, 1), LS_EINVAL);
    assert_int_equal(ls_ramp_plan(&r, 0, 1, 0, 0, 1, -1.0), LS_EINVAL);
    assert_int_equal(ls_ramp_plan_duration(&r, 0, 1, 0, 0, 1, 1, NAN), LS_EINVAL);
    assert_int_equal(ls_ramp_plan_duration(&r, 0, 1, 0, 0, 1, 1, -1.0), LS_EINVAL);
    /* 1 -> 0 at a 1, j 1 takes 2 s (sqrt(1) = 1 = a_max: two 1 s phases). */
    assert_int_equal(ls_ramp_plan_duration(&r, 0, 1, 0, 0, 1, 1, 1.9), LS_ETIME);
    assert_close(r.duration_s, 42.0, 0.0); /* untouched */
    ls_ramp_sample(NULL, 0.0, NULL, NULL, NULL);
    assert_close(ls_ramp_jerk(NULL, 0.0), 0.0, 0.0);
}

static void test_start_beyond_the_acceleration_limit(void **state)
{
    (void)state;
    ls_ramp_t r;
    /* a0 = 3 with a_max = 1 (a state from faster limits): the first phase
     * comes down at j_max; the acceleration never grows. */
    const problem_t q = { .v0 = 0.5, .a0 = 3.0, .v1 = 0.0, .a_max = 1.0, .j_max = 20.0 };
    assert_int_equal(ls_ramp_plan(&r, 0.0, q.v0, q.a0, q.v1, q.a_max, q.j_max), LS_OK);
    assert_ramp_within_limits(&r, &q);
    assert_close(r.duration_s, otg_duration(1, &q), REL_TOL * r.duration_s);
}

/* ---- random, against ruckig -------------------------------------------- */

static void test_minimum_duration_is_ruckigs_one_axis(void **state)
{
    (void)state;
    for (int i = 0; i < N_RANDOM; i++) {
        const problem_t q = random_problem();
        ls_ramp_t r;
        assert_int_equal(ls_ramp_plan(&r, 0.0, q.v0, q.a0, q.v1, q.a_max, q.j_max), LS_OK);
        const double want = otg_duration(1, &q);
        if (!(fabs(r.duration_s - want) <= 1e-9 * fmax(want, 1e-3))) {
            fail_msg("case %d: v0 %.17g a0 %.17g v1 %.17g a %.17g j %.17g: %.17g s, ruckig %.17g s", i, q.v0, q.a0,
                     q.v1, q.a_max, q.j_max, r.duration_s, want);
        }
        assert_ramp_within_limits(&r, &q);
    }
}

static void test_synchronised_stop_takes_ruckigs_time_and_every_axis_fits(void **state)
{
    (void)state;
    for (int i = 0; i < N_RANDOM / 4; i++) {
        problem_t q[6];
        ls_ramp_t r[6];
        double T = 0.0;
        for (int k = 0; k < 6; k++) {
            q[k] = random_problem();
            q[k].v1 = 0.0;
            assert_int_equal(ls_ramp_plan(&r[k], 0.0, q[k].v0, q[k].a0, 0.0, q[k].a_max, q[k].j_max), LS_OK);
            T = fmax(T, r[k].duration_s);
        }
        const double want = otg_duration(6, q);
        if (!(fabs(T - want) <= 1e-9 * fmax(want, 1e-3))) {
            fail_msg("case %d: synchronised %.17g s, ruckig %.17g s", i, T, want);
        }
        for (int k = 0; k < 6; k++) {
            assert_int_equal(ls_ramp_plan_duration(&r[k], 0.0, q[k].v0, q[k].a0, 0.0, q[k].a_max, q[k].j_max, T),
                             LS_OK);
            assert_close(r[k].duration_s, T, 1e-12 * T);
            assert_ramp_within_limits(&r[k], &q[k]);
        }
    }
}

static void test_any_longer_duration_has_a_profile(void **state)
{
    (void)state;
    for (int i = 0; i < N_RANDOM; i++) {
        const problem_t q = random_problem();
        ls_ramp_t r;
        assert_int_equal(ls_ramp_plan(&r, 0.0, q.v0, q.a0, q.v1, q.a_max, q.j_max), LS_OK);
        const double T = r.duration_s * urand(1.0, 4.0) + urand(0.0, 0.05);
        assert_int_equal(ls_ramp_plan_duration(&r, 0.0, q.v0, q.a0, q.v1, q.a_max, q.j_max, T), LS_OK);
        assert_close(r.duration_s, T, 1e-12 * (1.0 + T));
        assert_ramp_within_limits(&r, &q);
    }
}

static int setup(void **state)
{
    (void)state;
    return ls_otg_planner_init(&g_pl) == LS_OK ? 0 : -1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stop_from_cruise_by_hand),
        cmocka_unit_test(test_start_already_braking_by_hand),
        cmocka_unit_test(test_ramp_up_to_a_speed_by_hand),
        cmocka_unit_test(test_nothing_to_do),
        cmocka_unit_test(test_bad_input_is_refused),
        cmocka_unit_test(test_start_beyond_the_acceleration_limit),
        cmocka_unit_test(test_minimum_duration_is_ruckigs_one_axis),
        cmocka_unit_test(test_synchronised_stop_takes_ruckigs_time_and_every_axis_fits),
        cmocka_unit_test(test_any_longer_duration_has_a_profile),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
