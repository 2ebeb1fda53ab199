/* Jerk-limited trajectories (seven-segment profiles), time-synchronised across
 * axes: every axis starts and finishes together, each within its own velocity,
 * acceleration and jerk limits, and the duration is the time-optimal one
 * (the slowest axis's minimum time; the others are slowed to match).
 *
 * Planning (ls_traj_plan*) may run outside the control loop; sampling
 * (ls_traj_sample) is O(axes), allocation-free and may run in the loop.
 * Units are whatever the caller uses consistently (rad, m, s). */
#ifndef LS_TRAJ_H
#define LS_TRAJ_H

#include <stdint.h>

#define LS_TRAJ_MAX_AXES 8

#define LS_TRAJ_OK     0
#define LS_TRAJ_EARG (-1) /* bad axis count, non-finite value, non-positive limit */

/* One axis: a rest-to-rest seven-segment profile from p0 to p1. */
typedef struct {
    double p0, dist;        /* dist = p1 - p0 (signed) */
    double t[7];            /* durations of the seven phases (jerk +,0,-, cruise, -,0,+) */
    double j;               /* jerk magnitude used (signed with dist) */
    double T;               /* total duration */
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

/* Minimum-time rest-to-rest profile of one axis. */
int ls_traj_plan_axis(ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max, double j_max);

/* Rest-to-rest profile of one axis with exactly `duration_s` (>= its minimum
 * time), within the limits. */
int ls_traj_plan_axis_duration(ls_traj_axis_t *ax, double p0, double p1, double v_max, double a_max,
                               double j_max, double duration_s);

/* n axes from p0 to p1, synchronised to the slowest axis. */
int ls_traj_plan(ls_traj_t *tr, uint8_t n, const double *p0, const double *p1, const ls_traj_limits_t *lim);

/* Position, velocity and acceleration at time t (clamped to [0, duration]).
 * Any output pointer may be NULL. */
void ls_traj_sample(const ls_traj_t *tr, double t_s, double *p, double *v, double *a);
void ls_traj_sample_axis(const ls_traj_axis_t *ax, double t_s, double *p, double *v, double *a);

/* Time scaling used to stop along the planned path and to resume it:
 * the trajectory clock advances at rate r in [0, 1]; r ramps down to 0
 * (stop) or up to 1 (resume) with bounded dr/dt and d2r/dt2, so the motion
 * stays on the same path. */
typedef struct {
    double r, rd;           /* rate and its derivative */
    double target;          /* 0 or 1 */
    double rd_max, rdd_max; /* chosen at ls_timescale_set from the motion's limits */
} ls_timescale_t;

void ls_timescale_init(ls_timescale_t *ts);
/* Ramp to `target` (0 or 1) over about `ramp_s` seconds. */
void ls_timescale_set(ls_timescale_t *ts, double target, double ramp_s);
/* Advance by dt; returns the trajectory-clock increment (r * dt). */
double ls_timescale_step(ls_timescale_t *ts, double dt_s);
int ls_timescale_settled(const ls_timescale_t *ts);

#endif
