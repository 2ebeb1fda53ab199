/* ls_otg: state-to-state trajectories (ruckig behind a C API).
 * Seeded random problems with non-zero start and target velocity and
 * acceleration, reachable within the limits; every trajectory is sampled at
 * 1 kHz and at its end. The exact rest-to-rest minimum time comes from
 * ls_traj (an independent closed-form planner, itself checked against
 * ruckig in tests/unit/traj). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "ls_otg.h"
#include "ls_traj.h"
#include "test_rng.h"

#define KHZ_DT_S 1e-3
#define LIMIT_REL_TOL 1e-9
#define PROBLEMS 400

static ls_otg_planner_t g_pl;
static test_rng_t g_rng = { 0x2545F4914F6CDD1Du };

static double urand(double lo, double hi)
{
    return test_rng_uniform(&g_rng, lo, hi);
}

static int setup(void **state)
{
    (void)state;
    return ls_otg_planner_init(&g_pl) == LS_OK ? 0 : -1;
}

static void random_limits(ls_otg_limits_t *lim, uint8_t n)
{
    for (uint8_t i = 0; i < n; i++) {
        lim->v_max[i] = urand(0.2, 4.0);
        lim->a_max[i] = urand(0.5, 20.0);
        lim->j_max[i] = urand(2.0, 200.0);
    }
}

/* A state within the limits that can be reached and left within them:
 * |a| <= a_max and |v +- a^2 / 2j| <= v_max (the velocity on either side
 * of the state when the acceleration ramps from or to zero). */
static void random_state(ls_otg_state_t *s, const ls_otg_limits_t *lim, uint8_t n)
{
    for (uint8_t i = 0; i < n; i++) {
        s->p[i] = urand(-3.0, 3.0);
        const double a_hold = fmin(0.9 * lim->a_max[i], sqrt(lim->v_max[i] * lim->j_max[i]));
        s->a[i] = urand(-1.0, 1.0) * a_hold;
        const double reserve = s->a[i] * s->a[i] / (2.0 * lim->j_max[i]); /* <= v_max / 2 */
        const double span = 0.9 * lim->v_max[i] - reserve;
        s->v[i] = urand(-span, span);
    }
}

/* Samples every 1 ms and at T: within v/a/j limits (relative 1e-9), and
 * exactly the target state at T. The velocity interface does not limit the
 * velocity (as ruckig's): a stop (target 0, 0) stays within |v0| + a0^2/2j,
 * the speed the start's acceleration forces; a ramp to another velocity is
 * checked for a and j only (cur NULL: position interface, v within v_max). */
static void check_trajectory(const ls_otg_t *tr, const ls_otg_state_t *tgt, const ls_otg_limits_t *lim,
                             const ls_otg_state_t *cur)
{
    const int position = cur == NULL;
    double v_bound[LS_OTG_MAX_AXES];
    for (uint8_t i = 0; i < tr->n; i++) {
        v_bound[i] = lim->v_max[i];
        if (!position) {
            const int stop = tgt->v[i] == 0.0 && tgt->a[i] == 0.0;
            v_bound[i] = stop ? fabs(cur->v[i]) + cur->a[i] * cur->a[i] / (2 * lim->j_max[i]) : INFINITY;
        }
    }
    double p[LS_OTG_MAX_AXES], v[LS_OTG_MAX_AXES], a[LS_OTG_MAX_AXES], j[LS_OTG_MAX_AXES];
    const uint8_t n = tr->n;
    assert_true(tr->duration_s >= 0.0 && isfinite(tr->duration_s));
    const long steps = (long)ceil(tr->duration_s / KHZ_DT_S);
    for (long k = 0; k <= steps; k++) {
        const double t = fmin((double)k * KHZ_DT_S, tr->duration_s);
        ls_otg_sample(tr, t, p, v, a, j);
        for (uint8_t i = 0; i < n; i++) {
            if (fabs(v[i]) > v_bound[i] * (1 + LIMIT_REL_TOL) || fabs(a[i]) > lim->a_max[i] * (1 + LIMIT_REL_TOL) ||
                fabs(j[i]) > lim->j_max[i] * (1 + LIMIT_REL_TOL)) {
                fail_msg("axis %u at t=%.6f s: v %.9g a %.9g j %.9g beyond limits %.9g %.9g %.9g", i, t, v[i], a[i],
                         j[i], v_bound[i], lim->a_max[i], lim->j_max[i]);
            }
        }
    }
    ls_otg_sample(tr, tr->duration_s, p, v, a, j);
    for (uint8_t i = 0; i < n; i++) {
        if (position) {
            assert_true(p[i] == tgt->p[i]);
        }
        assert_true(v[i] == tgt->v[i]);
        assert_true(a[i] == tgt->a[i]);
        assert_true(j[i] == 0.0);
    }
    /* Just before T the state is already close to the target (no jump at T):
     * within what the jerk limit allows over 1 us. */
    const double eps = 1e-6;
    if (tr->duration_s > eps) {
        ls_otg_sample(tr, tr->duration_s - eps, p, v, a, j);
        for (uint8_t i = 0; i < n; i++) {
            assert_true(fabs(a[i] - tgt->a[i]) <= lim->j_max[i] * eps * 1.001 + 1e-9);
            assert_true(fabs(v[i] - tgt->v[i]) <= (lim->a_max[i] * eps) * 1.001 + 1e-9);
            if (position) {
                assert_true(fabs(p[i] - tgt->p[i]) <= lim->v_max[i] * eps * 1.001 + 1e-9);
            }
        }
    }
}

/* Rest to rest the synchronised duration is the slowest axis's minimum
 * time: ls_traj's closed form gives it independently. */
static void test_rest_to_rest_matches_closed_form(void **state)
{
    (void)state;
    for (int k = 0; k < 200; k++) {
        ls_otg_limits_t lim;
        ls_traj_limits_t tl;
        ls_otg_state_t cur = { 0 }, tgt = { 0 };
        random_limits(&lim, 6);
        for (int i = 0; i < 6; i++) {
            cur.p[i] = urand(-3, 3);
            tgt.p[i] = urand(-3, 3);
            tl.v_max[i] = lim.v_max[i];
            tl.a_max[i] = lim.a_max[i];
            tl.j_max[i] = lim.j_max[i];
        }
        ls_otg_t tr;
        ls_traj_t ref;
        assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 6, &cur, &tgt, &lim), LS_OK);
        assert_int_equal(ls_traj_plan(&ref, 6, cur.p, tgt.p, &tl), LS_OK);
        if (fabs(tr.duration_s - ref.duration_s) > 1e-9 * fmax(1.0, ref.duration_s)) {
            fail_msg("problem %d: ls_otg %.12g s, closed form %.12g s", k, tr.duration_s, ref.duration_s);
        }
        check_trajectory(&tr, &tgt, &lim, NULL);
    }
}

/* State to state, 6 axes: within limits at 1 kHz, exact target at T, and
 * time-synchronised: T is at least every axis's own minimum time (planned
 * alone) and equals the largest one unless that duration is blocked for
 * another axis (ruckig then takes the next feasible one, still optimal). */
static void test_state_to_state_within_limits_synchronised(void **state)
{
    (void)state;
    int equal_to_slowest = 0;
    for (int k = 0; k < PROBLEMS; k++) {
        ls_otg_limits_t lim;
        ls_otg_state_t cur, tgt;
        random_limits(&lim, 6);
        random_state(&cur, &lim, 6);
        random_state(&tgt, &lim, 6);
        ls_otg_t tr;
        const int rc6 = ls_otg_plan_position(&g_pl, &tr, 6, &cur, &tgt, &lim);
        if (rc6 != LS_OK) {
            for (int i = 0; i < 6; i++) {
                print_message("axis %d: p %.17g -> %.17g v %.17g -> %.17g a %.17g -> %.17g lim %.17g %.17g %.17g\n", i,
                              cur.p[i], tgt.p[i], cur.v[i], tgt.v[i], cur.a[i], tgt.a[i], lim.v_max[i], lim.a_max[i],
                              lim.j_max[i]);
            }
            fail_msg("problem %d: %s", k, ls_err_name(rc6));
        }
        assert_int_equal(tr.n, 6);
        check_trajectory(&tr, &tgt, &lim, NULL);
        double slowest = 0.0;
        for (int i = 0; i < 6; i++) {
            ls_otg_state_t c1 = { 0 }, t1 = { 0 };
            ls_otg_limits_t l1 = { 0 };
            c1.p[0] = cur.p[i], c1.v[0] = cur.v[i], c1.a[0] = cur.a[i];
            t1.p[0] = tgt.p[i], t1.v[0] = tgt.v[i], t1.a[0] = tgt.a[i];
            l1.v_max[0] = lim.v_max[i], l1.a_max[0] = lim.a_max[i], l1.j_max[0] = lim.j_max[i];
            ls_otg_t one;
            const int rc = ls_otg_plan_position(&g_pl, &one, 1, &c1, &t1, &l1);
            if (rc != LS_OK) {
                fail_msg(
                    "problem %d axis %d alone: %s; p %.17g %.17g v %.17g %.17g a %.17g %.17g lim %.17g %.17g %.17g", k,
                    i, ls_err_name(rc), c1.p[0], t1.p[0], c1.v[0], t1.v[0], c1.a[0], t1.a[0], l1.v_max[0], l1.a_max[0],
                    l1.j_max[0]);
            }
            assert_true(one.duration_s <= tr.duration_s * (1 + 1e-12) + 1e-12);
            slowest = fmax(slowest, one.duration_s);
        }
        if (fabs(slowest - tr.duration_s) <= 1e-9 * fmax(1.0, slowest)) {
            equal_to_slowest++;
        }
    }
    /* Blocked intervals are the exception, not the rule. */
    assert_true(equal_to_slowest > PROBLEMS * 8 / 10);
}

/* The velocity interface: stops and ramps from a moving state, including
 * one faster than its limits (braked into them first). */
static void test_velocity_interface_stops(void **state)
{
    (void)state;
    for (int k = 0; k < PROBLEMS; k++) {
        ls_otg_limits_t lim;
        ls_otg_state_t cur, tgt = { 0 };
        random_limits(&lim, 6);
        random_state(&cur, &lim, 6);
        if (k % 2) {
            random_state(&tgt, &lim, 6); /* a jog ramp to another velocity */
            for (int i = 0; i < 6; i++) {
                tgt.a[i] = 0.0; /* reached at rest acceleration (ls_otg.h) */
            }
        }
        ls_otg_t tr;
        assert_int_equal(ls_otg_plan_velocity(&g_pl, &tr, 6, &cur, &tgt, &lim), LS_OK);
        check_trajectory(&tr, &tgt, &lim, &cur);
        double p[LS_OTG_MAX_AXES];
        ls_otg_sample(&tr, 0.0, p, NULL, NULL, NULL);
        for (int i = 0; i < 6; i++) {
            assert_true(fabs(p[i] - cur.p[i]) <= 1e-12);
        }
    }
    /* 1 axis moving at twice its v_max: brakes, jerk-limited, to rest. */
    ls_otg_limits_t lim = { .v_max = { 1.0 }, .a_max = { 2.0 }, .j_max = { 10.0 } };
    ls_otg_state_t cur = { .v = { 2.0 } }, tgt = { 0 };
    ls_otg_t tr;
    assert_int_equal(ls_otg_plan_velocity(&g_pl, &tr, 1, &cur, &tgt, &lim), LS_OK);
    double v, a, j;
    for (double t = 0; t <= tr.duration_s; t += KHZ_DT_S) {
        ls_otg_sample(&tr, t, NULL, &v, &a, &j);
        assert_true(fabs(a) <= 2.0 * (1 + LIMIT_REL_TOL) && fabs(j) <= 10.0 * (1 + LIMIT_REL_TOL));
    }
    ls_otg_sample(&tr, tr.duration_s + 1.0, NULL, &v, &a, &j);
    assert_true(v == 0.0 && a == 0.0 && j == 0.0);
}

/* Sampling: before 0 and NaN count as 0, after T continues from the
 * target with constant acceleration. */
static void test_sample_edges(void **state)
{
    (void)state;
    ls_otg_limits_t lim = { .v_max = { 1.0, 1.0 }, .a_max = { 1.0, 1.0 }, .j_max = { 1.0, 1.0 } };
    ls_otg_state_t cur = { .p = { 0.5, -0.25 }, .v = { 0.1, 0.0 } }, tgt = { .p = { 2.0, 1.0 }, .v = { 0.2, 0.0 } };
    ls_otg_t tr;
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 2, &cur, &tgt, &lim), LS_OK);
    double p[2], v[2];
    ls_otg_sample(&tr, NAN, p, v, NULL, NULL);
    assert_true(fabs(p[0] - 0.5) < 1e-12 && fabs(p[1] + 0.25) < 1e-12 && fabs(v[0] - 0.1) < 1e-12);
    ls_otg_sample(&tr, -3.0, p, NULL, NULL, NULL);
    assert_true(fabs(p[0] - 0.5) < 1e-12);
    ls_otg_sample(&tr, tr.duration_s + 2.0, p, v, NULL, NULL);
    assert_true(fabs(p[0] - (2.0 + 0.4)) < 1e-12 && v[0] == 0.2 && p[1] == 1.0);
    /* A copy samples the same (plain data). */
    ls_otg_t copy;
    memcpy(&copy, &tr, sizeof copy);
    double q[2];
    ls_otg_sample(&tr, 0.37 * tr.duration_s, p, NULL, NULL, NULL);
    ls_otg_sample(&copy, 0.37 * tr.duration_s, q, NULL, NULL, NULL);
    assert_true(p[0] == q[0] && p[1] == q[1]);
    ls_otg_sample(NULL, 0.0, p, v, NULL, NULL); /* does nothing */
}

static void test_bad_input(void **state)
{
    (void)state;
    ls_otg_limits_t lim = { .v_max = { 1.0 }, .a_max = { 1.0 }, .j_max = { 1.0 } };
    ls_otg_state_t cur = { 0 }, tgt = { .p = { 1.0 } };
    ls_otg_t tr;
    memset(&tr, 0xA5, sizeof tr);
    const ls_otg_t before = tr;
    assert_int_equal(ls_otg_plan_position(NULL, &tr, 1, &cur, &tgt, &lim), LS_EINVAL);
    assert_int_equal(ls_otg_plan_position(&g_pl, NULL, 1, &cur, &tgt, &lim), LS_EINVAL);
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, NULL, &tgt, &lim), LS_EINVAL);
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, NULL, &lim), LS_EINVAL);
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &tgt, NULL), LS_EINVAL);
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 0, &cur, &tgt, &lim), LS_EINVAL);
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, LS_OTG_MAX_AXES + 1, &cur, &tgt, &lim), LS_EINVAL);
    assert_int_equal(ls_otg_planner_init(NULL), LS_EINVAL);
    static ls_otg_planner_t never_initialised;
    assert_int_equal(ls_otg_plan_position(&never_initialised, &tr, 1, &cur, &tgt, &lim), LS_EINVAL);
    /* Non-finite values. */
    ls_otg_state_t bad = cur;
    bad.p[0] = NAN;
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &bad, &tgt, &lim), LS_EINVAL);
    bad = cur;
    bad.a[0] = INFINITY;
    assert_int_equal(ls_otg_plan_velocity(&g_pl, &tr, 1, &bad, &tgt, &lim), LS_EINVAL);
    bad = tgt;
    bad.v[0] = NAN;
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &bad, &lim), LS_EINVAL);
    /* Limits: zero, negative, NaN, infinite. */
    const double bad_limits[] = { 0.0, -1.0, NAN, INFINITY };
    for (size_t k = 0; k < sizeof bad_limits / sizeof bad_limits[0]; k++) {
        for (int which = 0; which < 3; which++) {
            ls_otg_limits_t l = lim;
            double *field = which == 0 ? l.v_max : which == 1 ? l.a_max : l.j_max;
            field[0] = bad_limits[k];
            assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &tgt, &l), LS_EINVAL);
        }
    }
    /* Unreachable targets: faster than v_max, more than a_max, or a
     * velocity that overshoots v_max while the acceleration returns to 0. */
    bad = tgt;
    bad.v[0] = 1.5;
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &bad, &lim), LS_ERANGE);
    bad = tgt;
    bad.a[0] = -1.01;
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &bad, &lim), LS_ERANGE);
    /* The velocity interface ends at an acceleration of 0: any other is
     * refused (ruckig 0.19.4 overflows its profile array for one). */
    bad = tgt;
    bad.a[0] = 0.1;
    assert_int_equal(ls_otg_plan_velocity(&g_pl, &tr, 1, &cur, &bad, &lim), LS_EINVAL);
    bad.a[0] = -0.1;
    assert_int_equal(ls_otg_plan_velocity(&g_pl, &tr, 1, &cur, &bad, &lim), LS_EINVAL);
    /* Within the limits but not reachable: ending at a = 0.9 and v = 0
     * means a velocity of -0.405 while a rose from 0, beyond v_max 0.3. */
    bad = tgt;
    bad.a[0] = 0.9;
    ls_otg_limits_t slow = lim;
    slow.v_max[0] = 0.3;
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &bad, &slow), LS_ERANGE);
    assert_memory_equal(&tr, &before, sizeof tr);
    /* The planner still works afterwards. */
    assert_int_equal(ls_otg_plan_position(&g_pl, &tr, 1, &cur, &tgt, &lim), LS_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rest_to_rest_matches_closed_form),
        cmocka_unit_test(test_state_to_state_within_limits_synchronised),
        cmocka_unit_test(test_velocity_interface_stops),
        cmocka_unit_test(test_sample_edges),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
