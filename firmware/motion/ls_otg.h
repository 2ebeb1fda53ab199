/* State-to-state jerk-limited trajectories ("online trajectory generation"):
 * from any current position, velocity and acceleration per axis to a target
 * state, time-optimal and time-synchronised across axes, within each axis's
 * velocity, acceleration and jerk limits. The solver is ruckig 0.19.4's own
 * C++ (cmake/ruckig.cmake fetches its PyPI sdist) behind this C API; see
 * docs/architecture.md, "State-to-state trajectories".
 *
 * Two interfaces, as ruckig's:
 *  - position (ls_otg_plan_position): to a target position, velocity and
 *    acceleration; every axis arrives at the same time T, the smallest T at
 *    which all of them can (ruckig's Synchronization::Time);
 *  - velocity (ls_otg_plan_velocity): to a target velocity and acceleration,
 *    position free: a stop (target 0, 0) or a jog ramp. Synchronised too.
 *    It limits acceleration and jerk, not velocity (as ruckig's): a stop
 *    stays within |v0| + a0^2 / (2 j_max) per axis (tests/unit/otg), a ramp
 *    between two velocities may pass the faster one by what synchronising
 *    the axes asks.
 * A current state beyond the limits (faster than v_max, more acceleration
 * than a_max) is allowed: the trajectory first brakes into them (ruckig's
 * brake pre-trajectory), still jerk-limited.
 *
 * Memory: everything is the caller's and of fixed size. ls_otg_t is the
 * planned trajectory (sampled from the control loop); ls_otg_planner_t is
 * the solver's workspace (about 16 KB), needed only while planning: one per
 * thread that plans. Nothing here allocates, throws, reads a clock or does
 * I/O (tests/unit/otg proves the first two at run time and in the archives).
 * Time is passed in (t_s since the start of the trajectory).
 *
 * Cost (docs/performance.md, bench 10): planning a 6-axis problem takes a
 * few microseconds (the median) and tens at the tail, cheap enough for the
 * control loop when a stop must start now; sampling is O(axes). */
#ifndef LS_OTG_H
#define LS_OTG_H

#include <stdint.h>

#include "ls_err.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Axes one trajectory can have (compile-time: ruckig's fixed-size types). */
#define LS_OTG_MAX_AXES 6

/* Bytes of the opaque storage (checked against the C++ types at compile
 * time in ls_otg.cpp; raise them there if ruckig grows). */
#define LS_OTG_TRAJ_BYTES 3600u
#define LS_OTG_PLANNER_BYTES 16000u
#ifdef __cplusplus
#define LS_OTG_ALIGN alignas(16)
#else
#define LS_OTG_ALIGN _Alignas(16)
#endif

/* A state or a target: per axis position, velocity, acceleration (units of
 * the caller: rad, m, or a path parameter; seconds for time). */
typedef struct {
    double p[LS_OTG_MAX_AXES];
    double v[LS_OTG_MAX_AXES];
    double a[LS_OTG_MAX_AXES];
} ls_otg_state_t;

/* Limits per axis, symmetric (|v| <= v_max, ...); each finite and > 0. */
typedef struct {
    double v_max[LS_OTG_MAX_AXES];
    double a_max[LS_OTG_MAX_AXES];
    double j_max[LS_OTG_MAX_AXES];
} ls_otg_limits_t;

/* A planned trajectory. Plain data once planned: copy it freely (a copy
 * samples the same). The fields are read-only for callers. */
typedef struct {
    uint8_t n;                                           /* axes, 1..LS_OTG_MAX_AXES; 0 = never planned */
    uint8_t velocity_;                                   /* 1 for the velocity interface (private) */
    double duration_s;                                   /* T: when every axis has reached its target */
    ls_otg_state_t target;                               /* the target as given (p unused for velocity) */
    LS_OTG_ALIGN unsigned char traj_[LS_OTG_TRAJ_BYTES]; /* ruckig::Trajectory (private) */
} ls_otg_t;

/* The solver's workspace. Initialise once with ls_otg_planner_init. */
typedef struct {
    LS_OTG_ALIGN unsigned char bytes_[LS_OTG_PLANNER_BYTES];
} ls_otg_planner_t;

/* Prepares a workspace. Returns LS_OK or LS_EINVAL (pl NULL). Init only;
 * never needs undoing. */
int ls_otg_planner_init(ls_otg_planner_t *pl);

/* Plans n axes from `cur` to `tgt` (position interface). On success *tr
 * holds the trajectory; sampled at duration_s it gives exactly tgt.
 * Returns LS_OK;
 *   LS_EINVAL: a NULL pointer, pl not initialised, n not in
 *     1..LS_OTG_MAX_AXES, a value that is not finite, or a limit that is
 *     not > 0;
 *   LS_ERANGE: the target is unreachable within the limits: |tgt.v| >
 *     v_max, |tgt.a| > a_max, or a velocity that would overshoot v_max
 *     while the acceleration returns to zero (|v + a|a|/(2 j_max)| > v_max),
 *     or ruckig finds no profile (its step 1 or synchronisation fails).
 * *tr is untouched on error. Cost: a few us typical (see above); no
 * allocation; may run in the control loop or outside it. Not thread-safe
 * on the same pl. */
int ls_otg_plan_position(ls_otg_planner_t *pl, ls_otg_t *tr, uint8_t n, const ls_otg_state_t *cur,
                         const ls_otg_state_t *tgt, const ls_otg_limits_t *lim);

/* Plans n axes from `cur` to the velocity tgt->v at an acceleration of 0
 * (velocity interface; tgt->p is ignored). A tgt->a other than 0 is
 * LS_EINVAL: ruckig 0.19.4's velocity step overflows its profile array for
 * one (ls_otg.cpp). Statuses and cost as above. */
int ls_otg_plan_velocity(ls_otg_planner_t *pl, ls_otg_t *tr, uint8_t n, const ls_otg_state_t *cur,
                         const ls_otg_state_t *tgt, const ls_otg_limits_t *lim);

/* The state at t_s seconds after the start (t_s < 0 or NaN counts as 0):
 * writes tr->n values to each non-NULL array (jerk in j). At t_s >=
 * duration_s the motion continues from the target with its constant
 * acceleration (zero jerk): the position interface gives exactly tgt at
 * duration_s. A NULL or never-planned tr does nothing. O(axes), no
 * allocation: control-loop safe. */
void ls_otg_sample(const ls_otg_t *tr, double t_s, double *p, double *v, double *a, double *j);

#ifdef __cplusplus
}
#endif

#endif /* LS_OTG_H */
