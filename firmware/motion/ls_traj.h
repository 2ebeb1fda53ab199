/* Jerk-limited trajectories (seven-segment profiles), time-synchronised across
 * axes: every axis starts and finishes together, each within its own velocity,
 * acceleration and jerk limits, and the duration is the time-optimal one
 * (the slowest axis's minimum time; the others are slowed to match).
 *
 * Planning (ls_traj_plan*) may run outside the control loop; sampling
 * (ls_traj_sample) is O(axes), allocation-free and may run in the loop.
 * Nothing here allocates, reads a clock or does I/O; all memory belongs to
 * the caller. Units are whatever the caller uses consistently (rad, m, s).
 *
 * Profiles are rest-to-rest and symmetric: phases 5-7 mirror phases 3-1, the
 * second half of the motion is the first half reflected about the midpoint.
 * Sampling exploits that: the end is computed backwards from p1, so the
 * position at t >= T is exactly p1. */
#ifndef LS_TRAJ_H
#define LS_TRAJ_H

#include <stdint.h>

#include "ls_err.h"

#define LS_TRAJ_MAX_AXES 8

/* Statuses (ls_err.h): LS_OK; LS_EINVAL (NULL pointer, bad axis count,
 * non-finite value, non-positive limit), LS_ETIME (requested duration shorter
 * than the axis's minimum time). */

/* One axis: a rest-to-rest seven-segment profile from p0 to p1.
 * Plain data: copy freely. Filled by the planners only. */
typedef struct {
    double p0, dist; /* dist = p1 - p0 (signed) */
    double p1;       /* kept so the end position is exact, not p0 + dist */
    double t[7];     /* durations of the seven phases (jerk +,0,-, cruise, -,0,+) */
    double j;        /* jerk magnitude used (signed with dist; 0 when dist == 0) */
    double T;        /* total duration */
} ls_traj_axis_t;

typedef struct {
    uint8_t n;
    double duration_s;
    ls_traj_axis_t axis[LS_TRAJ_MAX_AXES];
} ls_traj_t;

typedef struct {
    double v_max[LS_TRAJ_MAX_AXES];
    double a_max[LS_TRAJ_MAX_AXES];
    double j_max[LS_TRAJ_MAX_AXES];
} ls_traj_limits_t;

/* Minimum-time rest-to-rest profile of one axis, in closed form (no
 * iteration; a few sqrt/cbrt). dist == 0 gives duration 0; negative dist is
 * the mirror of the positive one.
 * Returns LS_OK, or LS_EINVAL (ax NULL, a non-finite position, a
 * limit that is not finite and > 0); *ax is untouched on error.
 * Call from anywhere (dispatcher, planner); O(1). */
int ls_traj_plan_axis(ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max, double j_max);

/* Rest-to-rest profile of one axis with exactly `duration_s`, within the
 * limits: same a_max and j_max, a lower peak velocity. The peak velocity is
 * the root of duration(v) = duration_s, solved in closed form (quadratic when
 * a_max is reached, cubic by the trigonometric method when it is not) and
 * polished by two Newton steps: O(1), no loop whose count depends on data.
 * dist == 0 with duration_s > 0 holds p0 for duration_s.
 * Returns LS_OK, LS_EINVAL (as above, or duration_s not finite or
 * < 0), or LS_ETIME (duration_s below the minimum time by more than a
 * relative 1e-12, which is absorbed as rounding). *ax is untouched on error. */
int ls_traj_plan_axis_duration(ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max, double j_max,
                               double duration_s);

/* n (1..LS_TRAJ_MAX_AXES) axes from p0[n] to p1[n], synchronised: duration is
 * the largest per-axis minimum time and every other axis is re-planned to
 * exactly that duration, so all axes start and finish together.
 * Returns LS_OK or LS_EINVAL (as for ls_traj_plan_axis, per axis, or
 * n out of range); *tr is untouched on error. O(n). */
int ls_traj_plan(ls_traj_t *tr, uint8_t n, const double *p0, const double *p1, const ls_traj_limits_t *lim);

/* Position, velocity and acceleration at time t (clamped to [0, duration];
 * NaN counts as 0). ls_traj_sample writes tr->n values to each non-NULL
 * output array; ls_traj_sample_axis writes one value to each non-NULL
 * pointer. At t >= duration the position is exactly p1 and v = a = 0.
 * Control-loop safe: O(1) per axis, no allocation. A NULL tr/ax does nothing. */
void ls_traj_sample(const ls_traj_t *tr, double t_s, double *p, double *v, double *a);
void ls_traj_sample_axis(const ls_traj_axis_t *ax, double t_s, double *p, double *v, double *a);

/* Time scaling used to stop along the planned path and to resume it:
 * the trajectory clock tau advances at rate r in [0, 1] (dtau = r dt); r
 * ramps to a target with bounded dr/dt and d2r/dt2, so the motion stays on
 * the same path q(tau) and tau never runs backwards.
 *
 * Seen in real time, the motion is q(tau(t)) with
 *   dq/dt   = q' r
 *   d2q/dt2 = q'' r^2 + q' dr/dt
 *   d3q/dt3 = q''' r^3 + 3 q'' r dr/dt + q' d2r/dt2
 * so r <= 1 keeps |dq/dt| <= v_max, and the terms that the ramp adds are
 * |q' dr/dt| <= v_peak rd_max and |q' d2r/dt2| <= v_peak rdd_max.
 * A full ramp (1 -> 0) over ramp_s has rd_max = LS_TIMESCALE_RD_GAIN / ramp_s
 * and rdd_max = LS_TIMESCALE_RDD_GAIN / ramp_s^2 (rdd ramps over thirds of
 * ramp_s), so ramp_s >= 1.5 v_max / a_max keeps the added acceleration term
 * within a_max: see ls_traj_stop_ramp_s. During a cruise (q'' = 0) that is
 * the whole acceleration; when stopping while the path itself brakes, the
 * two terms can add up to at most 2 a_max (|q''| r^2 <= a_max as well). */
#define LS_TIMESCALE_RD_GAIN 1.5
#define LS_TIMESCALE_RDD_GAIN 4.5

typedef struct {
    double r, rd;           /* rate and its derivative */
    double target;          /* in [0, 1]: 0 stops, 1 runs at the planned speed */
    double rd_max, rdd_max; /* chosen at ls_timescale_set from ramp_s (see above) */
    /* The current ramp, planned at ls_timescale_set (private to ls_traj.c):
     * starting state, time since then, and three phases of constant d2r/dt2. */
    double r0_, rd0_, t_s_;
    double ph_s_[3], u_[3];
} ls_timescale_t;

/* r = target = 1, settled (the clock runs at the planned speed). */
void ls_timescale_init(ls_timescale_t *ts);

/* Ramp r to `target` in [0, 1]; a full 0 <-> 1 change takes ramp_s seconds
 * (shorter changes less). May be called during a ramp (e.g. resume while
 * stopping): it continues from the current r and dr/dt without a jump; if
 * the new, gentler limits could not stop r before 0 or 1, rdd_max is raised
 * just enough for this ramp. Returns LS_OK, or LS_EINVAL (ts NULL,
 * target not in [0, 1], ramp_s not finite or <= 0) leaving ts unchanged.
 * Control-loop safe: O(1). */
int ls_timescale_set(ls_timescale_t *ts, double target, double ramp_s);

/* Advance by dt_s; returns the trajectory-clock increment: the exact integral
 * of r over the step (r * dt once settled), >= 0. A dt_s that is not finite
 * or <= 0 changes nothing and returns 0. Control-loop safe: O(1). */
double ls_timescale_step(ls_timescale_t *ts, double dt_s);

/* 1 when r has reached its target and dr/dt = 0, else 0. */
int ls_timescale_settled(const ls_timescale_t *ts);

/* The shortest ramp_s for a stop (ls_timescale_set(ts, 0, ramp_s)) of `tr`
 * such that the terms the ramp adds stay within each axis's limits:
 * v_peak * rd_max <= a_max and v_peak * rdd_max <= j_max, where v_peak is the
 * axis's peak planned speed (below v_max for the axes slowed by
 * synchronisation). That is max over axes of
 *   max(1.5 v_peak / a_max, sqrt(4.5 v_peak / j_max)).
 * Returns 0 for a trajectory that does not move, or LS_EINVAL (as a
 * double) for NULL pointers, tr->n out of range or bad limits. O(n). */
double ls_traj_stop_ramp_s(const ls_traj_t *tr, const ls_traj_limits_t *lim);

#endif
