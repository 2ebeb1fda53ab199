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

#endif
