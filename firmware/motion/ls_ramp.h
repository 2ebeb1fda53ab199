/* Jerk-limited velocity ramps: one axis from any state (p0, v0, a0) to a
 * target velocity v1 at zero acceleration, the position free, within
 * |a| <= a_max and |j| <= j_max. This is the velocity interface of a
 * state-to-state planner (ruckig's, ls_otg.h) for the motions that start
 * moving and end at a velocity: a stop (v1 = 0), the brake of a guarded
 * move, a jog speed change.
 *
 * The profile has three phases of constant jerk (+-j_max or 0): the
 * acceleration goes from a0 to a peak, holds it, and returns to 0. The
 * time-optimal one (ls_ramp_plan) peaks at the largest acceleration the
 * limits allow; ls_ramp_plan_duration gives the one that takes exactly T
 * (a lower peak), for a caller that stops several axes together (the
 * executor stops each axis on its own; tests/unit/ramp checks synchronised
 * stops against ruckig's). Both are closed form
 * (a square root or a quadratic; no iteration): O(1), no allocation, no
 * clock, no I/O, safe in the control loop. tests/unit/ramp compares the
 * minimum durations with ruckig's (ls_otg_plan_velocity) and samples the
 * profiles against the limits.
 *
 * A start beyond the acceleration limit (|a0| > a_max) is allowed: the first
 * phase brings it back to the peak, still at j_max. Velocity is not limited:
 * the speed stays within v0, v1 and v0 + a0 |a0| / (2 j_max) (where a0
 * carries it before it can turn), so a state within its velocity limit and
 * a target within it keep to it. */
#ifndef LS_RAMP_H
#define LS_RAMP_H

#include "ls_err.h"

/* A planned ramp. Plain data: copy freely. Filled by the planners only. */
typedef struct {
    double t[3];                /* durations of the three phases */
    double j[3];                /* jerk of each phase (signed) */
    double p_[4], v_[4], a_[4]; /* state at the start of each phase and at the end */
    double duration_s;          /* t[0] + t[1] + t[2] */
} ls_ramp_t;

/* Statuses (ls_err.h): LS_OK; LS_EINVAL (r NULL, a value not finite, a
 * limit not > 0, a duration not finite); LS_ETIME (duration_s below the
 * minimum by more than a relative 1e-9). *r is untouched on error. */

/* The time-optimal ramp. */
int ls_ramp_plan(ls_ramp_t *r, double p0, double v0, double a0, double v1, double a_max, double j_max);

/* The ramp that reaches (v1, 0) at exactly duration_s (>= the minimum);
 * it ends early and holds v1 only when the start already reaches v1 by
 * bringing the acceleration to zero. */
int ls_ramp_plan_duration(ls_ramp_t *r, double p0, double v0, double a0, double v1, double a_max, double j_max,
                          double duration_s);

/* Position, velocity and acceleration at t_s (clamped at 0; NaN counts as
 * 0); after the ramp the axis moves on at v1. Writes each non-NULL output.
 * O(1), control-loop safe. A NULL r does nothing. */
void ls_ramp_sample(const ls_ramp_t *r, double t_s, double *p, double *v, double *a);

/* The jerk at t_s: the phase's, 0 after the end. */
double ls_ramp_jerk(const ls_ramp_t *r, double t_s);

#endif
