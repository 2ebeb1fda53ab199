/* Seven-segment rest-to-rest profiles (stops and brakes: ls_ramp.h).
 *
 * A symmetric rest-to-rest profile is fully described by its peak velocity
 * v: the acceleration half reaches a_p = min(a_max, sqrt(v j_max)) with jerk
 * phases of Tj = a_p / j_max and a constant-acceleration phase of
 * Ta = v / a_p - Tj. Its duration is Tacc = 2 Tj + Ta and, because the
 * velocity is point-symmetric about the middle of that half, it covers
 * v Tacc / 2. Hence for distance D:
 *   cruise Tv = D / v - Tacc  and  total T(v) = Tacc(v) + D / v.
 * T(v) strictly decreases on the feasible range (Tv >= 0), so the minimum
 * time uses the largest feasible v, and any longer duration has exactly one
 * v below it. */
#include "ls_traj.h"

#include <math.h>
#include <stddef.h>

/* Durations within this relative margin below the minimum are rounding. */
#define DURATION_REL_TOL 1e-12

static int is_limit(double x)
{
    return isfinite(x) && x > 0.0;
}

/* The acceleration half for peak velocity v (> 0). */
static void half_of_peak(double v, double a_max, double j_max, double *tj, double *ta)
{
    if (v * j_max >= a_max * a_max) {
        *tj = a_max / j_max;
        *ta = v / a_max - *tj;
        if (*ta < 0.0) {
            *ta = 0.0;
        }
    } else {
        *tj = sqrt(v / j_max);
        *ta = 0.0;
    }
}

/* Peak velocity of the minimum-time profile for distance d > 0. */
static double min_time_peak(double d, double v_max, double a_max, double j_max)
{
    double tj, ta;
    half_of_peak(v_max, a_max, j_max, &tj, &ta);
    if (v_max * (2.0 * tj + ta) <= d) {
        return v_max; /* cruise at v_max */
    }
    const double a2j = a_max * a_max / j_max;
    /* At v = a2j the acceleration just touches a_max; the half covers 2 a2j^2/a_max. */
    if (d >= 2.0 * a2j * a2j / a_max) {
        /* v^2 / a + v a / j = d, written without cancellation. */
        return 2.0 * a_max * d / (a2j + sqrt(a2j * a2j + 4.0 * a_max * d));
    }
    /* Pure jerk phases: 2 v sqrt(v / j) = d. */
    return cbrt(d * d * j_max / 4.0);
}

static void set_axis(ls_traj_axis_t *ax, double p0, double p1, double d, double tj, double ta, double tv, double jerk,
                     double T)
{
    ax->p0 = p0;
    ax->p1 = p1;
    ax->dist = d;
    ax->t[0] = ax->t[2] = ax->t[4] = ax->t[6] = tj;
    ax->t[1] = ax->t[5] = ta;
    ax->t[3] = tv;
    ax->j = jerk;
    ax->T = T;
}

static int check_axis_args(const ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max, double j_max)
{
    if (ax == NULL || !isfinite(p0) || !isfinite(p1) || !isfinite(p1 - p0)) {
        return LS_EINVAL;
    }
    if (!is_limit(v_max) || !is_limit(a_max) || !is_limit(j_max)) {
        return LS_EINVAL;
    }
    return LS_OK;
}

int ls_traj_plan_axis(ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max, double j_max)
{
    if (check_axis_args(ax, p0, p1, v_max, a_max, j_max) != LS_OK) {
        return LS_EINVAL;
    }
    const double d = p1 - p0;
    if (d == 0.0) {
        set_axis(ax, p0, p1, d, 0.0, 0.0, 0.0, 0.0, 0.0);
        return LS_OK;
    }
    const double D = fabs(d);
    const double v = min_time_peak(D, v_max, a_max, j_max);
    double tj, ta;
    half_of_peak(v, a_max, j_max, &tj, &ta);
    /* Below v_max the peak was solved for an empty cruise: keep it exactly empty. */
    double tv = v < v_max ? 0.0 : D / v - (2.0 * tj + ta);
    if (tv < 0.0) {
        tv = 0.0;
    }
    const double T = 4.0 * tj + 2.0 * ta + tv;
    if (!isfinite(T) || !isfinite(v)) {
        return LS_EINVAL; /* limits so extreme that the profile overflows */
    }
    set_axis(ax, p0, p1, d, tj, ta, tv, d > 0.0 ? j_max : -j_max, T);
    return LS_OK;
}

/* Peak velocity v <= v_hi with Tacc(v) + D / v = T, for T above the minimum
 * time (whose peak is v_hi). */
static double peak_for_duration(double D, double a_max, double j_max, double v_hi, double T)
{
    const double a2j = a_max * a_max / j_max; /* peak at which a_max is just reached */
    double v;
    if (v_hi > a2j && T <= 2.0 * a_max / j_max + D / a2j) {
        /* a_max reached: v^2 / a + (a / j - T) v + D = 0, the smaller root
         * (the larger one lies beyond the feasible range), cancellation-free. */
        const double b = T - a_max / j_max;
        double disc = b * b - 4.0 * D / a_max;
        if (disc < 0.0) {
            disc = 0.0;
        }
        v = 2.0 * D / (b + sqrt(disc));
    } else {
        /* Pure jerk phases, s = Tj = sqrt(v / j): 2 s^3 - T s^2 + D / j = 0.
         * Of its three real roots, the middle one (the smallest positive) is
         * ours. Trigonometric form: s = T/6 + (T/3) cos(theta/3 - 2 pi/3)
         * with cos(theta) = 1 - 54 D / (j T^3); rewritten as
         * s = (T/3) (sin^2(x/2) + (sqrt(3)/2) sin x), x = theta/3, and
         * theta = 2 asin(sqrt(27 D / (j T^3))), it has no cancellation when
         * T is long and s tiny. Newton polishes it: f'(s) < 0 there, well
         * away from the double root at s = T / 3. */
        double e = sqrt(27.0 * D / j_max / T) / T;
        if (e > 1.0) {
            e = 1.0;
        }
        const double x = 2.0 * asin(e) / 3.0;
        const double sh = sin(0.5 * x);
        double s = (T / 3.0) * (sh * sh + 0.5 * sqrt(3.0) * sin(x));
        for (int k = 0; k < 2; ++k) {
            const double f = (2.0 * s - T) * s * s + D / j_max;
            const double fd = (6.0 * s - 2.0 * T) * s;
            if (fd < 0.0) {
                const double sn = s - f / fd;
                if (sn > 0.0) {
                    s = sn;
                }
            }
        }
        v = j_max * s * s;
    }
    if (!(v <= v_hi)) {
        v = v_hi;
    }
    return v;
}

int ls_traj_plan_axis_duration(ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max, double j_max,
                               double duration_s)
{
    if (check_axis_args(ax, p0, p1, v_max, a_max, j_max) != LS_OK || !isfinite(duration_s) || duration_s < 0.0) {
        return LS_EINVAL;
    }
    ls_traj_axis_t fast;
    if (ls_traj_plan_axis(&fast, p0, p1, v_max, a_max, j_max) != LS_OK) {
        return LS_EINVAL;
    }
    if (duration_s < fast.T * (1.0 - DURATION_REL_TOL)) {
        return LS_ETIME;
    }
    const double d = fast.dist;
    if (d == 0.0) {
        set_axis(ax, p0, p1, d, 0.0, 0.0, duration_s, 0.0, duration_s);
        return LS_OK;
    }
    if (duration_s <= fast.T) {
        *ax = fast;
        ax->T = duration_s; /* equal up to rounding */
        return LS_OK;
    }
    const double D = fabs(d);
    const double v_hi = min_time_peak(D, v_max, a_max, j_max);
    const double v = peak_for_duration(D, a_max, j_max, v_hi, duration_s);
    if (!(v > 0.0)) {
        return LS_EINVAL; /* duration so long against the distance that the peak underflows */
    }
    double tj, ta;
    half_of_peak(v, a_max, j_max, &tj, &ta);
    double tv = duration_s - 2.0 * (2.0 * tj + ta);
    if (tv < 0.0) {
        tv = 0.0;
    }
    set_axis(ax, p0, p1, d, tj, ta, tv, d > 0.0 ? j_max : -j_max, duration_s);
    return LS_OK;
}

int ls_traj_plan(ls_traj_t *tr, uint8_t n, const double *p0, const double *p1, const ls_traj_limits_t *lim)
{
    if (tr == NULL || p0 == NULL || p1 == NULL || lim == NULL || n == 0 || n > LS_TRAJ_MAX_AXES) {
        return LS_EINVAL;
    }
    ls_traj_t out;
    out.n = n;
    out.duration_s = 0.0;
    for (uint8_t i = 0; i < n; ++i) {
        if (ls_traj_plan_axis(&out.axis[i], p0[i], p1[i], lim->v_max[i], lim->a_max[i], lim->j_max[i]) != LS_OK) {
            return LS_EINVAL;
        }
        if (out.axis[i].T > out.duration_s) {
            out.duration_s = out.axis[i].T;
        }
    }
    for (uint8_t i = 0; i < n; ++i) {
        if (out.axis[i].T == out.duration_s) {
            continue;
        }
        /* duration_s >= this axis's minimum, so ETIME cannot happen. */
        if (ls_traj_plan_axis_duration(&out.axis[i], p0[i], p1[i], lim->v_max[i], lim->a_max[i], lim->j_max[i],
                                       out.duration_s) != LS_OK) {
            return LS_EINVAL;
        }
    }
    for (uint8_t i = n; i < LS_TRAJ_MAX_AXES; ++i) {
        set_axis(&out.axis[i], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    }
    *tr = out;
    return LS_OK;
}

/* First half of the motion in the direction of travel (jerk magnitude jm),
 * at time tau from the start: phases 1-3 and the cruise. */
static void first_half(const ls_traj_axis_t *ax, double jm, double tau, double *p, double *v, double *a)
{
    const double tj = ax->t[0], ta = ax->t[1];
    if (tau <= tj) {
        *a = jm * tau;
        *v = 0.5 * jm * tau * tau;
        *p = jm * tau * tau * tau / 6.0;
        return;
    }
    const double a1 = jm * tj, v1 = 0.5 * jm * tj * tj, p1 = jm * tj * tj * tj / 6.0;
    tau -= tj;
    if (tau <= ta) {
        *a = a1;
        *v = v1 + a1 * tau;
        *p = p1 + v1 * tau + 0.5 * a1 * tau * tau;
        return;
    }
    const double v2 = v1 + a1 * ta, p2 = p1 + v1 * ta + 0.5 * a1 * ta * ta;
    tau -= ta;
    if (tau <= tj) {
        *a = a1 - jm * tau;
        *v = v2 + a1 * tau - 0.5 * jm * tau * tau;
        *p = p2 + v2 * tau + 0.5 * a1 * tau * tau - jm * tau * tau * tau / 6.0;
        return;
    }
    const double v3 = v2 + a1 * tj - 0.5 * jm * tj * tj;
    const double p3 = p2 + v2 * tj + 0.5 * a1 * tj * tj - jm * tj * tj * tj / 6.0;
    tau -= tj;
    *a = 0.0;
    *v = v3;
    *p = p3 + v3 * tau;
}

void ls_traj_sample_axis(const ls_traj_axis_t *ax, double t_s, double *p, double *v, double *a)
{
    if (ax == NULL) {
        return;
    }
    double pp, vv, aa;
    if (!(t_s > 0.0)) {
        t_s = 0.0;
    }
    if (t_s >= ax->T || ax->j == 0.0) {
        /* At rest: at the end, or an axis that does not move. */
        pp = t_s >= ax->T ? ax->p1 : ax->p0;
        vv = 0.0;
        aa = 0.0;
    } else {
        const double sgn = ax->j > 0.0 ? 1.0 : -1.0;
        const double jm = fabs(ax->j);
        double pf, vf, af;
        if (t_s <= 0.5 * ax->T) {
            first_half(ax, jm, t_s, &pf, &vf, &af);
            pp = ax->p0 + sgn * pf;
            aa = sgn * af;
        } else {
            /* The second half mirrors the first about the midpoint, counted back from p1. */
            first_half(ax, jm, ax->T - t_s, &pf, &vf, &af);
            pp = ax->p1 - sgn * pf;
            aa = -sgn * af;
        }
        vv = sgn * vf;
    }
    if (p != NULL) {
        *p = pp;
    }
    if (v != NULL) {
        *v = vv;
    }
    if (a != NULL) {
        *a = aa;
    }
}

void ls_traj_sample(const ls_traj_t *tr, double t_s, double *p, double *v, double *a)
{
    if (tr == NULL) {
        return;
    }
    const uint8_t n = tr->n <= LS_TRAJ_MAX_AXES ? tr->n : LS_TRAJ_MAX_AXES;
    if (!(t_s <= tr->duration_s)) {
        t_s = tr->duration_s; /* also guards each axis against a T rounded differently */
    }
    for (uint8_t i = 0; i < n; ++i) {
        ls_traj_sample_axis(&tr->axis[i], t_s >= tr->duration_s ? tr->axis[i].T : t_s, p ? &p[i] : NULL,
                            v ? &v[i] : NULL, a ? &a[i] : NULL);
    }
}
