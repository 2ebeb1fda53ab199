/* Jerk-limited velocity ramps. See ls_ramp.h.
 *
 * The solution, written for the normalised problem: the velocity must come
 * down by d = v0 - v1 (after mirroring, so that the peak acceleration -x is
 * <= 0) from the acceleration a = a0, with the braking need
 *   v_brk = d + a |a| / (2 J) >= 0
 * (what is left to shed once the acceleration is brought to 0 at J).
 * Phases: a -> -x at jerk -J (or +J when a < -x), hold -x for t2, -x -> 0 at
 * +J. The velocity each phase sheds is (a_end^2 - a_start^2) / (2 j) for a
 * jerk phase and x t2 for the hold, so
 *   time-optimal, no hold: x^2 = J d + a^2 / 2, capped at a_max (then the
 *     hold is t2 = (J d + a^2/2 - a_max^2) / (J a_max));
 *   exactly T, first phase at -J (x >= -a): x^2 + (a - J T) x + J d + a^2/2
 *     = 0, its smaller root;
 *   exactly T, first phase at +J (a < 0, x < -a): x = v_brk / (T + a / J).
 * The two duration forms meet at x = -a, and x falls from the optimum to 0
 * as T grows: every T >= the minimum has one profile. */
#include "ls_ramp.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#define REL_TIME_TOL 1e-9

static bool args_ok(double p0, double v0, double a0, double v1, double a_max, double j_max)
{
    return isfinite(p0) && isfinite(v0) && isfinite(a0) && isfinite(v1) && isfinite(a_max) && isfinite(j_max) &&
           a_max > 0.0 && j_max > 0.0;
}

/* The peak -x of the normalised problem taking exactly T (T >= the
 * minimum), x_opt being the time-optimal peak. */
static double peak_for_duration(double d, double a, double J, double T, double x_opt)
{
    if (a < 0.0) {
        const double v_brk = d - a * a / (2.0 * J);
        if (v_brk <= 0.0) {
            return 0.0; /* easing the acceleration to 0 reaches v1: then hold */
        }
        const double den = T + a / J;
        if (den > 0.0 && v_brk / den <= -a) {
            return fmin(x_opt, v_brk / den);
        }
    }
    const double b = J * T - a;
    const double c = J * d + 0.5 * a * a;
    if (b <= 0.0 || c <= 0.0) {
        return 0.0;
    }
    const double D = fmax(0.0, b * b - 4.0 * c);
    return fmin(x_opt, 2.0 * c / (b + sqrt(D))); /* the smaller root, without cancellation */
}

/* Phase durations and jerks of the ramp from (v0, a0) to (v1, 0); T < 0
 * asks for the time-optimal one. */
static void solve(double v0, double a0, double v1, double A, double J, double T, double t[3], double j[3])
{
    const double dv = v0 - v1;
    const double s = (dv + a0 * fabs(a0) / (2.0 * J) >= 0.0) ? 1.0 : -1.0; /* mirror: the peak is -x s */
    const double d = s * dv;
    const double a = s * a0;
    const double c = fmax(0.0, J * d + 0.5 * a * a);
    const double x_opt = fmin(A, sqrt(c));
    const double x = (T < 0.0) ? x_opt : peak_for_duration(d, a, J, T, x_opt);
    const double j1 = (-x < a) ? -J : J;
    t[0] = fabs(a + x) / J;
    t[2] = x / J;
    if (T >= 0.0) {
        t[1] = fmax(0.0, T - t[0] - t[2]);
    } else if (x > 0.0) {
        /* shed what the two jerk phases do not: d + (x^2 - a^2)/(2 j1) - x^2/(2J) */
        t[1] = fmax(0.0, (d + (x * x - a * a) / (2.0 * j1) - x * x / (2.0 * J)) / x);
    } else {
        t[1] = 0.0;
    }
    j[0] = s * j1;
    j[1] = 0.0;
    j[2] = s * J;
}

static void fill(ls_ramp_t *r, double p0, double v0, double a0, double v1, const double t[3], const double j[3])
{
    r->p_[0] = p0;
    r->v_[0] = v0;
    r->a_[0] = a0;
    r->duration_s = 0.0;
    for (int k = 0; k < 3; k++) {
        const double tk = t[k];
        r->t[k] = tk;
        r->j[k] = j[k];
        r->p_[k + 1] = r->p_[k] + tk * (r->v_[k] + tk * (r->a_[k] / 2.0 + tk * j[k] / 6.0));
        r->v_[k + 1] = r->v_[k] + tk * (r->a_[k] + tk * j[k] / 2.0);
        r->a_[k + 1] = r->a_[k] + tk * j[k];
        r->duration_s += tk;
    }
    /* The end state is the target by construction; drop the rounding. */
    r->v_[3] = v1;
    r->a_[3] = 0.0;
}

int ls_ramp_plan(ls_ramp_t *r, double p0, double v0, double a0, double v1, double a_max, double j_max)
{
    if (r == NULL || !args_ok(p0, v0, a0, v1, a_max, j_max)) {
        return LS_EINVAL;
    }
    double t[3], j[3];
    solve(v0, a0, v1, a_max, j_max, -1.0, t, j);
    fill(r, p0, v0, a0, v1, t, j);
    return LS_OK;
}

int ls_ramp_plan_duration(ls_ramp_t *r, double p0, double v0, double a0, double v1, double a_max, double j_max,
                          double duration_s)
{
    if (r == NULL || !args_ok(p0, v0, a0, v1, a_max, j_max) || !isfinite(duration_s) || duration_s < 0.0) {
        return LS_EINVAL;
    }
    double t[3], j[3];
    solve(v0, a0, v1, a_max, j_max, -1.0, t, j);
    const double t_min = t[0] + t[1] + t[2];
    if (duration_s < t_min * (1.0 - REL_TIME_TOL) - 1e-15) {
        return LS_ETIME;
    }
    if (duration_s > t_min) {
        solve(v0, a0, v1, a_max, j_max, duration_s, t, j);
    }
    fill(r, p0, v0, a0, v1, t, j);
    return LS_OK;
}

void ls_ramp_sample(const ls_ramp_t *r, double t_s, double *p, double *v, double *a)
{
    if (r == NULL) {
        return;
    }
    double t = (isnan(t_s) || t_s < 0.0) ? 0.0 : t_s;
    int k = 0;
    while (k < 3 && t > r->t[k]) {
        t -= r->t[k];
        k++;
    }
    const double jk = (k < 3) ? r->j[k] : 0.0;
    if (p != NULL) {
        *p = r->p_[k] + t * (r->v_[k] + t * (r->a_[k] / 2.0 + t * jk / 6.0));
    }
    if (v != NULL) {
        *v = r->v_[k] + t * (r->a_[k] + t * jk / 2.0);
    }
    if (a != NULL) {
        *a = r->a_[k] + t * jk;
    }
}

double ls_ramp_jerk(const ls_ramp_t *r, double t_s)
{
    if (r == NULL) {
        return 0.0;
    }
    double t = (isnan(t_s) || t_s < 0.0) ? 0.0 : t_s;
    for (int k = 0; k < 3; k++) {
        if (t < r->t[k]) {
            return r->j[k];
        }
        t -= r->t[k];
    }
    return 0.0;
}
