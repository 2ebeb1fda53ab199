/* The time law of a Cartesian segment: how its path parameter s runs from
 * s0 to 1 under the joints' limits, jerk-limited, from rest to rest, and
 * how a stop brings it to rest (docs/architecture.md "Path speed under
 * joint limits").
 *
 * The caller (ls_motion.c) samples the path and hands over, stretch by
 * stretch, bounds of each joint's |dq/ds| (b1) and of d2q/ds2, split by
 * sign: with q' = q_s s' and q'' = q_ss s'^2 + q_s s'' and sigma the sign
 * of q_s, sigma q'' = sigma q_ss s'^2 + |q_s| s''. The curvature that
 * pushes the way q_s goes (the positive part of sigma q_ss, bound b2u)
 * adds to a ramp speeding up, the other part (b2d) to a ramp slowing down.
 * So joint i keeps its velocity limit vel_i while s' <= vel_i / b1_i, and
 * its acceleration limit acc_i on a ramp up while
 *   s'' <= a_up(s') = min_i (acc_i - b2u_i s'^2) / b1_i
 * and on a ramp down while |s''| <= a_down(s') (b2d in place of b2u),
 * the other part staying within acc_i at the zone's cap.
 * The curve joins the stretches into zones, each with a cap on s' (the
 * requested speed, the joints' velocity limits, and a curvature cap that
 * keeps a share of every acc_i for the ramps) and the bounds of its
 * stretches.
 *
 * The profile cruises in each zone at a speed c no higher than its cap and
 * changes speed only on ramps that begin and end at zero acceleration
 * (three constant-jerk phases, symmetric) inside the zone: a ramp up starts
 * where the zone starts, at the zone's a_up(c), a ramp down ends where it
 * ends, at its a_down(c). Nothing in a zone is faster than c, so each joint
 * keeps its limits.
 * A stop (ls_pathspeed_plan_stop) ramps down in each zone it crosses at
 * that zone's acceleration for the speed it enters with, ending every ramp
 * at a zone's end: it slows at least as early and as hard as the profile,
 * so it meets every cap slower than the profile would and rests by s = 1.
 *
 * Planning takes boundary speeds from a backward and a forward pass over
 * the zones and each cruise speed by bisection, a fixed number of steps:
 * O(zones), no allocation, no clock, no I/O, so a resume and a stop may
 * plan in the control loop. Sampling is O(zones). All memory belongs to the
 * caller; the types are plain data (copy freely). Units: s is
 * dimensionless, time in seconds; b1, b2 and acc in any consistent units
 * (rad, rad/s^2). */
#ifndef LS_PATHSPEED_H
#define LS_PATHSPEED_H

#include <stdbool.h>
#include <stdint.h>

#include "ls_err.h"
#include "ls_ramp.h"

/* Zones of one curve. It sizes every Cartesian segment of a path program
 * (ls_motion.h), so the build's profile picks it (CMakeLists.txt
 * LS_PROFILE): more zones follow a curve more closely, fewer cost less RAM.
 * ls_pathspeed_curve_add joins the zones that cost the least time when a
 * curve has more. */
#ifndef LS_PATHSPEED_MAX_ZONES
#if LS_PROFILE_MCU
#define LS_PATHSPEED_MAX_ZONES 4
#else
#define LS_PATHSPEED_MAX_ZONES 12
#endif
#endif
/* Joints whose limits a curve keeps (ls_robot_model.h LS_N_JOINTS). */
#define LS_PATHSPEED_JOINTS 6

/* What set a zone's cap. */
typedef enum {
    LS_PATHSPEED_REQUESTED = 0, /* the requested speed: nothing slowed it */
    LS_PATHSPEED_VELOCITY,      /* a joint's velocity limit */
    LS_PATHSPEED_ACCELERATION,  /* a joint's acceleration limit (the path's curvature, which grows with s'^2) */
} ls_pathspeed_limit_t;

/* One stretch of the path as the caller measured it; every bound >= 0. */
typedef struct {
    double s_end;                    /* it ends here (it starts where the previous one ended) */
    double b1[LS_PATHSPEED_JOINTS];  /* bound of |dq/ds| over the stretch */
    double b2u[LS_PATHSPEED_JOINTS]; /* bound of sign(dq/ds) d2q/ds2 over the stretch (its positive part) */
    double b2d[LS_PATHSPEED_JOINTS]; /* bound of -sign(dq/ds) d2q/ds2 (its positive part); where the sign of
                                        dq/ds may change within the stretch both are the bound of |d2q/ds2| */
} ls_pathspeed_stretch_t;

typedef struct {
    double s_end;                  /* the zone covers [the previous zone's s_end (0 for the first), s_end) */
    double v_max;                  /* cap on s' inside the zone (1/s), > 0 */
    float b1[LS_PATHSPEED_JOINTS]; /* the largest bounds of its stretches, rounded up */
    float b2u[LS_PATHSPEED_JOINTS];
    float b2d[LS_PATHSPEED_JOINTS];
    uint8_t joint; /* 0-based joint that set v_max (LS_PATHSPEED_REQUESTED: meaningless) */
    uint8_t limit; /* ls_pathspeed_limit_t */
} ls_pathspeed_zone_t;

/* The speed-limit curve. Filled by ls_pathspeed_curve_begin/_add/_finish. */
typedef struct {
    uint8_t n;
    ls_pathspeed_zone_t zone[LS_PATHSPEED_MAX_ZONES];
    double v_req, a_req;             /* the requested s' and s'' */
    double j;                        /* jerk of every ramp, before a blend's jerk scale */
    double vel[LS_PATHSPEED_JOINTS]; /* the joints' velocity limits */
    double acc[LS_PATHSPEED_JOINTS]; /* the joints' acceleration limits */
} ls_pathspeed_curve_t;

/* One zone's part of a profile: ramp from u up to c (or none) at a_up,
 * cruise at c, ramp from c down to w (or none) at a_dn. */
typedef struct {
    double t0_s;       /* when the part begins (profile time) */
    double s0;         /* where it begins */
    double u, c, w;    /* s' at the start, cruising, at the end */
    double a_up, a_dn; /* the zone's accelerations at c */
    double t_cruise_s; /* how long it cruises */
} ls_pathspeed_part_t;

/* A planned profile. Filled by ls_pathspeed_plan only. */
typedef struct {
    uint8_t n; /* parts; 0: nothing to do (s0 = 1), s = 1 at every time */
    ls_pathspeed_part_t part[LS_PATHSPEED_MAX_ZONES];
    double j;       /* as planned (with the jerk scale) */
    double s_start; /* s0 */
    double duration_s;
} ls_pathspeed_t;

/* A stop: ramps down, one per zone it crosses, each followed by a cruise
 * to the zone's end; the last ends at rest. Filled by
 * ls_pathspeed_plan_stop and ls_pathspeed_stop_one only. */
typedef struct {
    uint8_t n;
    ls_ramp_t ramp[LS_PATHSPEED_MAX_ZONES];
    double t0_s[LS_PATHSPEED_MAX_ZONES]; /* when ramp k begins */
    double duration_s;                   /* at rest from then on */
} ls_pathspeed_stop_t;

/* Statuses (ls_err.h): LS_OK; LS_EINVAL (NULL, a value not finite, a
 * limit, speed, acceleration or jerk not > 0, a bound < 0, stretch ends not
 * increasing, a curve that does not end at 1, s0 outside [0, 1], a jerk
 * scale outside (0, 1]). Outputs are untouched on error. */

/* Start an empty curve for the requested s', s'' and jerk (all > 0) and the
 * joints' velocity and acceleration limits (each > 0). LS_EINVAL, c
 * untouched, on a bad argument. Comms thread (planning); O(1). */
int ls_pathspeed_curve_begin(ls_pathspeed_curve_t *c, double v_req, double a_req, double j,
                             const double vel[LS_PATHSPEED_JOINTS], const double acc[LS_PATHSPEED_JOINTS]);

/* Append stretch st, from the previous end to st->s_end (> it, <= 1). Its
 * cap is the lowest of v_req, vel_i / b1_i and sqrt(LS_PATHSPEED_CURVATURE
 * acc_i / max(b2u_i, b2d_i)). A stretch whose cap is within 0.5 % of the
 * last zone's joins it (the larger bounds, so the lower cap); when a curve would hold more than
 * LS_PATHSPEED_MAX_ZONES zones, the two neighbours whose join adds the
 * least cruising time (length / lower cap) are joined. Never raises a cap
 * or lowers a bound. LS_EINVAL (c untouched) on a bad argument.
 * Comms thread; O(zones). */
int ls_pathspeed_curve_add(ls_pathspeed_curve_t *c, const ls_pathspeed_stretch_t *st);

/* The share of a joint's acceleration limit the path's curvature may take
 * at a zone's cap (b2 s'^2); what is left is the ramps'. */
#define LS_PATHSPEED_CURVATURE 0.95

/* After the last stretch: join the neighbouring zones whose boundary costs
 * more (a ramp that must end at zero acceleration there) than the lower
 * bounds gain, as long as the profile from 0 gets faster. Comms thread;
 * O(zones^2) plans (a few hundred microseconds at 12 zones). LS_EINVAL when the
 * curve does not end at 1. */
int ls_pathspeed_curve_finish(ls_pathspeed_curve_t *c);

/* The time-optimal profile of this scheme from rest at s0 to rest at 1
 * under curve c, every ramp at jerk c->j * jerk_scale (a blend's scale,
 * ls_motion_prog_blend; 1 otherwise). s0 = 1 gives the empty profile. With
 * a single zone and nothing binding but the requested limits it is
 * ls_traj's rest-to-rest profile. Control-loop safe (a resume): O(zones),
 * 41 bisection steps per zone and pass (a relative 1e-12), no allocation,
 * about 1 KB of stack (the profile is built there, then copied). */
int ls_pathspeed_plan(ls_pathspeed_t *p, const ls_pathspeed_curve_t *c, double s0, double jerk_scale);

/* s, s' and s'' at t_s (clamped to [0, duration]; NaN counts as 0); at
 * t >= duration s is exactly 1 and the rest 0. Writes each non-NULL output.
 * O(zones), control-loop safe. A NULL p does nothing. */
void ls_pathspeed_sample(const ls_pathspeed_t *p, double t_s, double *s, double *v, double *a);

/* The acceleration zone k of curve c allows at speed v on a ramp up (up)
 * or down: the lowest over the joints of (acc_i - b2_i v^2) / b1_i with b2u
 * or b2d, and a_req; the joint that sets it in *joint (may be NULL; 0 when
 * a_req does). O(joints). */
double ls_pathspeed_zone_accel(const ls_pathspeed_curve_t *c, int k, double v, bool up, uint8_t *joint);

#define LS_PATHSPEED_NO_ZONE (-1) /* ls_pathspeed_zone_of: the curve has no zones */

/* The zone of curve c that holds s (s >= 1: the last zone),
 * LS_PATHSPEED_NO_ZONE for a NULL or empty curve. O(zones). */
int ls_pathspeed_zone_of(const ls_pathspeed_curve_t *c, double s);

/* A stop from (s0, v0 >= 0, a0) at jerk j: in each zone it crosses, a ramp
 * down at the zone's a_down for the fastest it runs there, to rest
 * when the rest of the zone allows, else to the lowest speed it can reach
 * by the zone's end (then it cruises to that end). Control-loop safe
 * (ls_motion_stop): O(zones) ramps, 40 bisection steps each, no
 * allocation. */
int ls_pathspeed_plan_stop(ls_pathspeed_stop_t *st, const ls_pathspeed_curve_t *c, double s0, double v0, double a0,
                           double j);

/* The stop that is ramp r alone (a fast stop, a stop inside a blend). */
void ls_pathspeed_stop_one(ls_pathspeed_stop_t *st, const ls_ramp_t *r);

/* s, s' and s'' of a stop at t_s (clamped at 0); at rest after its
 * duration. Writes each non-NULL output. O(zones). A NULL st does nothing. */
void ls_pathspeed_stop_sample(const ls_pathspeed_stop_t *st, double t_s, double *s, double *v, double *a);

/* The first and the last constant-jerk phase (s): a blend's window
 * (ls_motion_seg_blend); 0 for an empty profile. O(1). */
double ls_pathspeed_first_jerk_s(const ls_pathspeed_t *p);
double ls_pathspeed_last_jerk_s(const ls_pathspeed_t *p);

/* Why profile p (planned under curve c) is slower than requested: the
 * lowest cap it cruises at as a fraction of v_req (1 when it cruises at
 * none below v_req), the joint and limit of that zone and the span from the
 * first such stretch to the end of the last (0, 0 when none); the lowest
 * ramp acceleration as a fraction of a_req (1 when none is below it) and
 * the joint that set it. */
typedef struct {
    double frac;
    double s_from, s_to;
    uint8_t joint, limit;
    double a_frac;
    uint8_t a_joint;
} ls_pathspeed_why_t;

/* true when a cap or a ramp is below the request; false (and *out all
 * "nothing slowed") otherwise or on a NULL argument. O(zones). */
bool ls_pathspeed_slowed(const ls_pathspeed_curve_t *c, const ls_pathspeed_t *p, ls_pathspeed_why_t *out);

#endif
