/* ls_pathspeed: the time law of a path parameter under its joints' limits.
 * A hand-worked curve (the comment works it out), the single zone against
 * ls_traj's rest-to-rest profile, and random curves sampled at 1 kHz: each
 * joint keeps its velocity and acceleration limits by the bounds of the
 * zone it is in (|q'| <= b1 s', |q''| <= b2 s'^2 + b1 |s''|) and the jerk
 * keeps its limit, also for a stop begun anywhere
 * (ls_pathspeed_plan_stop) and for a resume from rest in the middle. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "ls_pathspeed.h"
#include "ls_ramp.h"
#include "ls_traj.h"
#include "test_rng.h"

#define DT_S 1e-3 /* the control loop's period */
#define N_RANDOM 300
#define TOL 1e-9

static test_rng_t g_rng = { 0x9E3779B97F4A7C15u };

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

static const double g_vel[LS_PATHSPEED_JOINTS] = { 2.5, 2.5, 3.0, 4.0, 4.0, 6.0 };
static const double g_acc[LS_PATHSPEED_JOINTS] = { 8.0, 8.0, 10.0, 15.0, 15.0, 20.0 };

/* A stretch with |q'| bounds b1 and curvature b2 both ways (b2d: NULL)
 * or b2 with the joint's way and b2d against it. */
static int add2(ls_pathspeed_curve_t *c, double s_end, const double b1[LS_PATHSPEED_JOINTS],
                const double b2[LS_PATHSPEED_JOINTS], const double *b2d)
{
    ls_pathspeed_stretch_t st = { .s_end = s_end };
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        st.b1[i] = b1 != NULL ? b1[i] : 0.0;
        st.b2u[i] = b2 != NULL ? b2[i] : 0.0;
        st.b2d[i] = b2d != NULL ? b2d[i] : st.b2u[i];
    }
    return ls_pathspeed_curve_add(c, &st);
}

static int add(ls_pathspeed_curve_t *c, double s_end, const double b1[LS_PATHSPEED_JOINTS],
               const double b2[LS_PATHSPEED_JOINTS])
{
    return add2(c, s_end, b1, b2, NULL);
}

static void one_zone(ls_pathspeed_curve_t *c, double v, double a, double j)
{
    assert_int_equal(ls_pathspeed_curve_begin(c, v, a, j, g_vel, g_acc), LS_OK);
    assert_int_equal(add(c, 1.0, NULL, NULL), LS_OK);
}

static void one_zone_that_nothing_binds_is_ls_trajs_rest_to_rest_profile(void **state)
{
    (void)state;
    /* cruising, reaching a_max without cruising, and jerk phases only */
    const double cases[][3] = { { 1.0, 8.0, 80.0 }, { 6.0, 8.0, 80.0 }, { 6.0, 40.0, 80.0 }, { 0.3, 2.0, 300.0 } };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ls_pathspeed_curve_t c;
        one_zone(&c, cases[i][0], cases[i][1], cases[i][2]);
        ls_pathspeed_t p;
        assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
        ls_traj_axis_t ax;
        assert_int_equal(ls_traj_plan_axis(&ax, 0.0, 1.0, cases[i][0], cases[i][1], cases[i][2]), LS_OK);
        assert_close(p.duration_s, ax.T, 1e-9 * ax.T);
        for (double t = 0.0; t < ax.T; t += DT_S) {
            double s, v, a, s2, v2, a2;
            ls_pathspeed_sample(&p, t, &s, &v, &a);
            ls_traj_sample_axis(&ax, t, &s2, &v2, &a2);
            assert_close(s, s2, 1e-9);
            assert_close(v, v2, 1e-8 * cases[i][0]);
            assert_close(a, a2, 1e-7 * cases[i][1]);
        }
        assert_close(ls_pathspeed_first_jerk_s(&p), ax.t[0], 1e-12);
        assert_close(ls_pathspeed_last_jerk_s(&p), ax.t[6], 1e-12);
        ls_pathspeed_why_t w;
        assert_false(ls_pathspeed_slowed(&c, &p, &w));
    }
}

/* Joint 3 (velocity limit 3) moves 3 rad per unit of s over [0.4, 0.6) and
 * 1.5 elsewhere, so the caps are 2, 1, 2; the joints' accelerations are far
 * away (b2 = 0, a(v) = acc / b1 >= 3.3 < a_req only where...): a_req = 4 is
 * made the smaller by acc = 1e3. Hand-worked with caps 1, 0.5, 1 scaled by
 * 2: a = 4, j = 40, so a ramp whose speed changes by dv >= a^2 / j = 0.4
 * has jerk phases of 0.1 s and a constant phase of dv / 4 - 0.1:
 *   0 -> 1: 0.35 s, covering 0.5 x 0.35 = 0.175;
 *   1 -> 0.5: 0.225 s, covering 0.75 x 0.225 = 0.16875.
 * With v_req = 1 and joint 3 moving 6 rad per unit of s in the middle
 * (cap 0.5), 3 elsewhere (cap 1, the request's):
 * Zone 1: up 0.175 + down 0.16875 = 0.34375, cruise 0.05625 at 1: 0.05625 s.
 * Zone 2: 0.2 at 0.5: 0.4 s. Zone 3 mirrors zone 1.
 * Total 2 x (0.35 + 0.05625 + 0.225) + 0.4 = 1.6625 s. */
static void a_zone_capped_in_the_middle_is_crossed_at_its_cap(void **state)
{
    (void)state;
    const double acc[LS_PATHSPEED_JOINTS] = { 1e3, 1e3, 1e3, 1e3, 1e3, 1e3 };
    ls_pathspeed_curve_t c;
    assert_int_equal(ls_pathspeed_curve_begin(&c, 1.0, 4.0, 40.0, g_vel, acc), LS_OK);
    const double slow[LS_PATHSPEED_JOINTS] = { 0, 0, 6.0, 0, 0, 0 }, fast[LS_PATHSPEED_JOINTS] = { 0, 0, 3.0, 0, 0, 0 };
    assert_int_equal(add(&c, 0.4, fast, NULL), LS_OK);
    assert_int_equal(add(&c, 0.6, slow, NULL), LS_OK);
    assert_int_equal(add(&c, 1.0, fast, NULL), LS_OK);
    assert_int_equal(c.n, 3);
    assert_close(c.zone[1].v_max, 0.5, 1e-7); /* 3 / 6, through the bound's float */
    assert_int_equal(c.zone[1].joint, 2);
    assert_int_equal(c.zone[1].limit, LS_PATHSPEED_VELOCITY);
    ls_pathspeed_t p;
    assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
    assert_close(p.duration_s, 1.6625, 1e-6);
    double s, v, a;
    ls_pathspeed_sample(&p, 0.35 + 0.05625 + 0.225 + 0.2, &s, &v, &a);
    assert_close(s, 0.5, 1e-6);
    assert_close(v, 0.5, 1e-6);
    assert_close(a, 0.0, 1e-9);
    ls_pathspeed_sample(&p, p.duration_s, &s, &v, &a);
    assert_true(s == 1.0 && v == 0.0 && a == 0.0);

    ls_pathspeed_why_t w;
    assert_true(ls_pathspeed_slowed(&c, &p, &w));
    assert_close(w.frac, 0.5, 1e-7);
    assert_close(w.s_from, 0.4, 0.0);
    assert_close(w.s_to, 0.6, 0.0);
    assert_int_equal(w.joint, 2);
    assert_int_equal(w.limit, LS_PATHSPEED_VELOCITY);
    assert_true(w.a_frac == 1.0);
}

/* A random curve of up to 3 x MAX stretches: each joint's |q'| bound
 * 0..2 (some 0), |q''| bound 0..20, a few stretches near a singularity
 * (large bounds). */
static void random_curve(ls_pathspeed_curve_t *c)
{
    assert_int_equal(ls_pathspeed_curve_begin(c, urand(0.5, 6.0), urand(2.0, 30.0), urand(20.0, 300.0), g_vel, g_acc),
                     LS_OK);
    const int n = 1 + (int)urand(0.0, 3.0 * LS_PATHSPEED_MAX_ZONES);
    double s = 0.0;
    for (int k = 0; k < n; k++) {
        s = k + 1 == n ? 1.0 : fmax(s + 1e-3, fmin(1.0 - 1e-3 * (n - k), s + urand(0.0, 2.0 / n)));
        double b1[LS_PATHSPEED_JOINTS], b2[LS_PATHSPEED_JOINTS], b2d[LS_PATHSPEED_JOINTS];
        const double peak = urand(0.0, 1.0) < 0.1 ? urand(5.0, 50.0) : 1.0;
        for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
            b1[i] = urand(0.0, 1.0) < 0.2 ? 0.0 : urand(0.0, 2.0) * peak;
            b2[i] = urand(0.0, 20.0) * peak * peak;
            b2d[i] = urand(0.0, 1.0) < 0.5 ? b2[i] : urand(0.0, 20.0) * peak * peak; /* some split by way */
        }
        assert_int_equal(add2(c, s, b1, b2, b2d), LS_OK);
    }
}

/* Joint i at speed v and acceleration a in zone k keeps its limits: the
 * velocity b1 v, and the acceleration (ls_pathspeed.h): speeding up, the
 * curvature with the joint's way plus b1 a, and the one against it alone;
 * slowing down the other way round (within rounding). */
static bool joints_keep(const ls_pathspeed_curve_t *c, int k, double v, double a)
{
    const ls_pathspeed_zone_t *z = &c->zone[k];
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        const double with = a >= 0.0 ? z->b2u[i] : z->b2d[i], against = a >= 0.0 ? z->b2d[i] : z->b2u[i];
        const double lim = c->acc[i] * (1.0 + TOL) + 1e-9;
        if (z->b1[i] * v > c->vel[i] * (1.0 + TOL) + 1e-12 || with * v * v + z->b1[i] * fabs(a) > lim ||
            against * v * v > lim) {
            return false;
        }
    }
    return v <= c->v_req * (1.0 + TOL) + 1e-12;
}

/* Every 1 ms from 0 to the end: s never goes back and stays in [s0, 1],
 * every joint keeps its limits in the zone where the sample is (or where
 * the previous one was: a zone's end is crossed between samples), the
 * acceleration's change within the jerk; the end at 1 at rest. */
static void assert_within_curve(const ls_pathspeed_curve_t *c, const ls_pathspeed_t *p, double s0)
{
    double s_prev = s0, a_prev = 0.0;
    const long steps = (long)ceil(p->duration_s / DT_S) + 1;
    for (long k = 1; k <= steps; k++) {
        const double t = (double)k * DT_S;
        double s, v, a;
        ls_pathspeed_sample(p, t, &s, &v, &a);
        if (s < s_prev - 1e-12 || s > 1.0 || v < -TOL) {
            fail_msg("s %.17g after %.17g at t = %g", s, s_prev, t);
        }
        if (!joints_keep(c, ls_pathspeed_zone_of(c, s), v, a) &&
            !joints_keep(c, ls_pathspeed_zone_of(c, s_prev), v, a)) {
            fail_msg("a joint beyond its limit at s = %.9g: s' %.9g, s'' %.9g (t = %g)", s, v, a, t);
        }
        if (fabs(a - a_prev) > p->j * DT_S * (1.0 + 1e-6) + 1e-12) {
            fail_msg("jerk %.17g beyond %.17g at t = %g", (a - a_prev) / DT_S, p->j, t);
        }
        s_prev = s;
        a_prev = a;
    }
    double s, v, a;
    ls_pathspeed_sample(p, p->duration_s, &s, &v, &a);
    assert_true(s == 1.0 && v == 0.0 && a == 0.0);
}

static void sampled_at_1_khz_every_joint_keeps_its_limits_and_the_jerk_holds(void **state)
{
    (void)state;
    for (int i = 0; i < N_RANDOM; i++) {
        ls_pathspeed_curve_t c;
        random_curve(&c);
        ls_pathspeed_t p;
        assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
        assert_within_curve(&c, &p, 0.0);
        /* the same at a blend's jerk scale, and after the curve is finished */
        assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 0.5), LS_OK);
        assert_within_curve(&c, &p, 0.0);
        ls_pathspeed_t before;
        assert_int_equal(ls_pathspeed_plan(&before, &c, 0.0, 1.0), LS_OK);
        assert_int_equal(ls_pathspeed_curve_finish(&c), LS_OK);
        assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
        assert_true(p.duration_s <= before.duration_s);
        assert_within_curve(&c, &p, 0.0);
    }
}

/* A stop (ls_pathspeed_plan_stop from the sampled state at the curve's
 * jerk, as ls_motion_stop plans it) begun at any few milliseconds keeps
 * every joint's limits in the zones it crosses and rests by s = 1. */
static void a_stop_begun_anywhere_keeps_every_joints_limits(void **state)
{
    (void)state;
    for (int i = 0; i < N_RANDOM / 3; i++) {
        ls_pathspeed_curve_t c;
        random_curve(&c);
        ls_pathspeed_t p;
        assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
        for (double t0 = DT_S; t0 < p.duration_s; t0 += 7.0 * DT_S) {
            double s0, v0, a0;
            ls_pathspeed_sample(&p, t0, &s0, &v0, &a0);
            ls_pathspeed_stop_t st;
            assert_int_equal(ls_pathspeed_plan_stop(&st, &c, s0, v0, a0, c.j), LS_OK);
            double s_prev = s0, a_prev = a0;
            for (double t = DT_S / 4.0; t <= st.duration_s + DT_S; t += DT_S / 4.0) {
                double s, v, a;
                ls_pathspeed_stop_sample(&st, t, &s, &v, &a);
                if (!joints_keep(&c, ls_pathspeed_zone_of(&c, s), v, a) &&
                    !joints_keep(&c, ls_pathspeed_zone_of(&c, s_prev), v, a)) {
                    fail_msg("a stop from t = %g: a joint beyond its limit at s = %.9g, s' %.9g, s'' %.9g", t0, s, v,
                             a);
                }
                if (s > 1.0 + 1e-9 || v < -1e-9) { /* rounding: 1e-9 of the path */
                    fail_msg("a stop from t = %g passes the end or turns back: s = %.17g, s' = %.17g", t0, s, v);
                }
                if (fabs(a - a_prev) > c.j * DT_S / 4.0 * (1.0 + 1e-6) + 1e-9) {
                    fail_msg("a stop from t = %g: jerk %.9g beyond %.9g", t0, (a - a_prev) / (DT_S / 4.0), c.j);
                }
                s_prev = s;
                a_prev = a;
            }
            double v_end, a_end;
            ls_pathspeed_stop_sample(&st, st.duration_s, NULL, &v_end, &a_end);
            assert_close(v_end, 0.0, 1e-9);
            assert_close(a_end, 0.0, 1e-9);
        }
    }
}

static void a_resume_from_rest_mid_path_keeps_the_limits_and_ends_at_one(void **state)
{
    (void)state;
    for (int i = 0; i < N_RANDOM; i++) {
        ls_pathspeed_curve_t c;
        random_curve(&c);
        const double s0 = urand(0.0, 1.0);
        ls_pathspeed_t p;
        assert_int_equal(ls_pathspeed_plan(&p, &c, s0, 1.0), LS_OK);
        double s;
        ls_pathspeed_sample(&p, 0.0, &s, NULL, NULL);
        assert_close(s, s0, 1e-12);
        assert_within_curve(&c, &p, s0);
    }
    /* from the end: nothing to do */
    ls_pathspeed_curve_t c;
    one_zone(&c, 1.0, 1.0, 1.0);
    ls_pathspeed_t p;
    assert_int_equal(ls_pathspeed_plan(&p, &c, 1.0, 1.0), LS_OK);
    assert_int_equal(p.n, 0);
    assert_true(p.duration_s == 0.0);
    double s;
    ls_pathspeed_sample(&p, 0.0, &s, NULL, NULL);
    assert_true(s == 1.0);
}

/* 200 stretches into a curve of at most MAX zones: no zone's bounds are
 * below those of a stretch it covers, so no cap is above its stretches'. */
static void a_curve_with_more_stretches_than_zones_joins_them_and_never_loosens_a_limit(void **state)
{
    (void)state;
    enum { N = 200 };
    static double b1[N][LS_PATHSPEED_JOINTS], b2[N][LS_PATHSPEED_JOINTS];
    ls_pathspeed_curve_t c;
    assert_int_equal(ls_pathspeed_curve_begin(&c, 4.0, 20.0, 200.0, g_vel, g_acc), LS_OK);
    for (int k = 0; k < N; k++) {
        /* a dip in the middle (a joint near a singularity), noise on top */
        const double peak = 1.0 + 30.0 / (1.0 + fabs((double)k - N / 2.0));
        for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
            b1[k][i] = urand(0.1, 1.0) * (i == 3 ? peak : 1.0);
            b2[k][i] = urand(0.0, 5.0) * (i == 3 ? peak * peak : 1.0);
        }
        assert_int_equal(add(&c, (double)(k + 1) / N, b1[k], b2[k]), LS_OK);
        assert_true(c.n <= LS_PATHSPEED_MAX_ZONES);
    }
    assert_close(c.zone[c.n - 1].s_end, 1.0, 0.0);
    for (int k = 0; k < N; k++) {
        const ls_pathspeed_zone_t *z = &c.zone[ls_pathspeed_zone_of(&c, (double)k / N)];
        for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
            assert_true(z->b1[i] >= b1[k][i] && z->b2u[i] >= b2[k][i] && z->b2d[i] >= b2[k][i]);
        }
    }
    ls_pathspeed_t p;
    assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
    assert_within_curve(&c, &p, 0.0);
}

static void bad_arguments_are_refused_and_leave_the_outputs_untouched(void **state)
{
    (void)state;
    ls_pathspeed_curve_t c, before;
    memset(&c, 0x5A, sizeof c);
    before = c;
    const double zero[LS_PATHSPEED_JOINTS] = { 0 };
    assert_int_equal(ls_pathspeed_curve_begin(NULL, 1.0, 1.0, 1.0, g_vel, g_acc), LS_EINVAL);
    assert_int_equal(ls_pathspeed_curve_begin(&c, 0.0, 1.0, 1.0, g_vel, g_acc), LS_EINVAL);
    assert_int_equal(ls_pathspeed_curve_begin(&c, 1.0, NAN, 1.0, g_vel, g_acc), LS_EINVAL);
    assert_int_equal(ls_pathspeed_curve_begin(&c, 1.0, 1.0, INFINITY, g_vel, g_acc), LS_EINVAL);
    assert_int_equal(ls_pathspeed_curve_begin(&c, 1.0, 1.0, 1.0, zero, g_acc), LS_EINVAL);
    assert_int_equal(ls_pathspeed_curve_begin(&c, 1.0, 1.0, 1.0, g_vel, NULL), LS_EINVAL);
    assert_memory_equal(&c, &before, sizeof c);

    assert_int_equal(ls_pathspeed_curve_begin(&c, 1.0, 1.0, 10.0, g_vel, g_acc), LS_OK);
    assert_int_equal(add(&c, 0.5, NULL, NULL), LS_OK);
    before = c;
    const double neg[LS_PATHSPEED_JOINTS] = { 0, -1, 0, 0, 0, 0 }, nan6[LS_PATHSPEED_JOINTS] = { NAN, 0, 0, 0, 0, 0 };
    assert_int_equal(add(&c, 0.5, NULL, NULL), LS_EINVAL); /* not past the previous end */
    assert_int_equal(add(&c, 1.5, NULL, NULL), LS_EINVAL); /* past 1 */
    assert_int_equal(add(&c, 0.8, neg, NULL), LS_EINVAL);
    assert_int_equal(add(&c, 0.8, NULL, nan6), LS_EINVAL);
    assert_int_equal(ls_pathspeed_curve_add(&c, NULL), LS_EINVAL);
    assert_memory_equal(&c, &before, sizeof c);

    ls_pathspeed_t p, pb;
    memset(&p, 0x33, sizeof p);
    pb = p;
    assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_EINVAL); /* the curve ends at 0.5 */
    assert_int_equal(ls_pathspeed_curve_finish(&c), LS_EINVAL);
    assert_int_equal(add(&c, 1.0, NULL, NULL), LS_OK);
    assert_int_equal(ls_pathspeed_plan(&p, &c, -0.1, 1.0), LS_EINVAL);
    assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.5), LS_EINVAL);
    assert_int_equal(ls_pathspeed_plan(&p, NULL, 0.0, 1.0), LS_EINVAL);
    assert_memory_equal(&p, &pb, sizeof p);
    ls_pathspeed_stop_t st, sb;
    memset(&st, 0x44, sizeof st);
    sb = st;
    assert_int_equal(ls_pathspeed_plan_stop(&st, &c, 0.5, -1.0, 0.0, 10.0), LS_EINVAL);
    assert_int_equal(ls_pathspeed_plan_stop(&st, &c, 0.5, 1.0, NAN, 10.0), LS_EINVAL);
    assert_int_equal(ls_pathspeed_plan_stop(&st, &c, 0.5, 1.0, 0.0, 0.0), LS_EINVAL);
    assert_memory_equal(&st, &sb, sizeof st);
    assert_int_equal(ls_pathspeed_plan(&p, &c, 0.0, 1.0), LS_OK);
    ls_pathspeed_sample(NULL, 0.0, NULL, NULL, NULL);
    ls_pathspeed_stop_sample(NULL, 0.0, NULL, NULL, NULL);
    assert_true(ls_pathspeed_first_jerk_s(NULL) == 0.0 && ls_pathspeed_last_jerk_s(NULL) == 0.0);
    assert_false(ls_pathspeed_slowed(NULL, NULL, NULL));
    assert_int_equal(ls_pathspeed_zone_of(NULL, 0.5), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(one_zone_that_nothing_binds_is_ls_trajs_rest_to_rest_profile),
        cmocka_unit_test(a_zone_capped_in_the_middle_is_crossed_at_its_cap),
        cmocka_unit_test(sampled_at_1_khz_every_joint_keeps_its_limits_and_the_jerk_holds),
        cmocka_unit_test(a_stop_begun_anywhere_keeps_every_joints_limits),
        cmocka_unit_test(a_resume_from_rest_mid_path_keeps_the_limits_and_ends_at_one),
        cmocka_unit_test(a_curve_with_more_stretches_than_zones_joins_them_and_never_loosens_a_limit),
        cmocka_unit_test(bad_arguments_are_refused_and_leave_the_outputs_untouched),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
