/* The motion executor: plans (made outside the control loop by the planners
 * below) and their execution, one control cycle at a time, in the loop.
 *
 * Planning: ls_motion_plan_* and ls_motion_seg_* run in the comms thread
 * (they sample the whole motion, run IK, check limits) and fill an
 * ls_motion_plan_t or the segments of an ls_motion_program_t. Refusals name
 * the joint or axis and the limit in `why` and return a negative status.
 * Execution: ls_motion_start/stop/resume/abort/aux_done and ls_motion_step
 * run in the control loop: O(1) per cycle apart from one IK (about 3 us) per
 * Cartesian cycle, no allocation, no blocking.
 *
 * A plan is a list of segments run one after the other, `cycles` times
 * (single moves: one segment, one cycle). Each segment ends at a point where
 * the executor reports the tag, runs the auxiliary commands and dwells; it
 * blends into the next segment instead of stopping when the planner gave it
 * an overlap (joint into joint, line into line: ls_motion_prog_blend).
 *
 * Units: SI everywhere (m, rad, s); conversion from the user's units happens
 * in the command handlers. Poses are 4x4 column-major (ls_kin.h). */
#ifndef LS_MOTION_H
#define LS_MOTION_H

#include <stdbool.h>
#include <stdint.h>

#include "ls_err.h"
#include "ls_pathspeed.h"
#include "ls_ramp.h"
#include "ls_robot_model.h"
#include "ls_traj.h"

#define LS_MOTION_NAME_LEN 64  /* names and tags: 63 bytes of UTF-8 (protocol/landscape.options) */
#define LS_MOTION_MAX_EVENTS 4 /* per cycle */
#define LS_MOTION_AUX_PER_POINT 4
#define LS_MOTION_AUX_LEN 48
/* Points of one path. It sizes static tables in several translation units:
 * the build's profile picks it (CMakeLists.txt LS_PROFILE: linux, or mcu for
 * a 256 KiB-RAM Cortex-M4F, where the program of LS_MOTION_MAX_SEGS
 * segments of about 1.7 KB each bounds it); an override goes to the whole
 * build only (cmake -DCMAKE_C_FLAGS=-DLS_PATH_MAX_POINTS=64). The device
 * publishes it (describe: max_points_per_path). */
#ifndef LS_PATH_MAX_POINTS
#if LS_PROFILE_MCU
#define LS_PATH_MAX_POINTS 16
#else
#define LS_PATH_MAX_POINTS 256
#endif
#endif
#define LS_MOTION_MAX_SEGS (LS_PATH_MAX_POINTS + 1) /* a path plus the segment that closes a cycle */
#define LS_MOTION_FOLLOWING_ERROR_RAD 0.05
/* Set-points kept for the following check of an arm whose feedback lags its
 * set-points (drives on a bus: ls_motion_set_feedback_lag). Per profile. */
#if LS_PROFILE_MCU
#define LS_MOTION_LAG_MAX 32u
#else
#define LS_MOTION_LAG_MAX 64u
#endif
/* The longest text a planner writes into `why` (including the NUL): every
 * refusal fits (tests/unit/motion checks the longest ones), so callers size
 * their buffers with it and the core's answers hold it whole
 * (firmware/core/cmd_motion.c). */
#define LS_MOTION_WHY_LEN 240

/* Planner statuses (ls_err.h; negative = refused, `why` says which joint/axis
 * and limit): LS_OK; LS_EINVAL (NULL, non-finite value, fraction outside
 * (0, 1]), LS_ERANGE (a joint/workspace limit, unreachable, or a path
 * through a singularity), LS_EGEOM (degenerate geometry: collinear arc
 * points). */

typedef enum {
    LS_MOTION_IDLE = 0,
    LS_MOTION_RUNNING,
    LS_MOTION_STOPPING, /* decelerating along the path after ls_motion_stop */
    LS_MOTION_PAUSED,
} ls_motion_phase_t;

typedef enum {
    LS_MEV_DONE = 1, /* the plan finished: name = point or path name, q_rad = final set-point */
    LS_MEV_TAG,      /* a tagged path point was reached: name = tag, text = path, index, cycle */
    LS_MEV_PAUSED,   /* a stop finished decelerating: text = "at a point", "between two points" or
                        "inside the blend of two points" */
    LS_MEV_FAULT,    /* following error, IK failure: text; the executor is idle afterwards */
    LS_MEV_AUX,      /* a path auxiliary command is due: text = the command, index = point,
                        cycle; the executor waits until ls_motion_aux_done() */
    /* Reported by the sensor-guided executor and the control loop (ls_react.h,
     * ls_control.h); the path executor never emits them. */
    LS_MEV_REACT_END, /* a guarded or compliant move ended: index = ls_react_end_t, q_rad = measured */
    LS_MEV_JOG,       /* jogging: stopped at a limit (text), or became possible (drives on) */
    LS_MEV_TOOL,      /* a tool command ran in the loop: name = tool, index = HAL status */
    LS_MEV_SLOW,      /* a path's segment that its joints slow down (ls_motion_seg_slowdown) begins, the
                         first time it runs: index = the segment in the program, cycle */
} ls_motion_event_kind_t;

typedef struct {
    ls_motion_event_kind_t kind;
    uint32_t ref_seq;
    char name[LS_MOTION_NAME_LEN];
    char text[64];
    int32_t index;
    int32_t cycle;
    double q_rad[LS_N_JOINTS];
} ls_motion_event_t;

typedef struct {
    ls_motion_event_t ev[LS_MOTION_MAX_EVENTS];
    uint8_t n;
} ls_motion_events_t;

typedef enum { LS_SEG_JOINT = 1, LS_SEG_LINE, LS_SEG_ARC } ls_seg_kind_t;

/* One segment: a rest-to-rest motion from q0 to q1 and the point it ends at.
 * Plain data, filled by the ls_motion_seg_* planners (path attributes by
 * the caller). */
typedef struct {
    ls_seg_kind_t kind;
    union {             /* by kind: a joint segment has no path parameter, a Cartesian one no joint profile */
        ls_traj_t traj; /* JOINT: the 6 joints */
        struct {
            ls_pathspeed_curve_t curve; /* LINE/ARC: the path parameter s's speed limits from the joints' */
            ls_pathspeed_t path;        /* LINE/ARC: s's time law from 0 to 1 under them */
        };
    };
    double q0[LS_N_JOINTS], q1[LS_N_JOINTS];
    double P0[16], P1[16];                               /* LINE/ARC: tool-tip poses at s = 0 and 1, base frame */
    double tool_inv[16];                                 /* LINE/ARC: flange = tip * tool_inv */
    double centre_m[3], u[3], v[3], radius_m, angle_rad; /* ARC: p(s) = c + r (cos(a s) u + sin(a s) v) */
    double length_m, turn_rad;                           /* LINE/ARC: path length and rotation, for reports */
    /* the point at the end of the segment (paths) */
    char tag[LS_MOTION_NAME_LEN]; /* empty: no tag event */
    int32_t tag_index;
    int32_t point;     /* index of the point in its path */
    double delay_s;    /* dwell after arriving (after the auxiliary commands) */
    double blend_frac; /* (0, 1]: blend into the next segment (transitionSpeed / 100); 0: stop here */
    double overlap_s;  /* > 0: the next segment starts this long before this one ends */
    uint8_t n_aux;
    char aux[LS_MOTION_AUX_PER_POINT][LS_MOTION_AUX_LEN];
    /* private to ls_motion.c: what the profile was planned with, so that a
     * blend can re-plan it with a lower jerk (ls_motion_prog_blend) and a
     * stop and a resume plan within the same limits */
    double lim_[4]; /* JOINT: speed_frac, accel_frac; LINE/ARC: requested v, a, j of s, joint_speed_frac */
    double jerk_scale_[LS_N_JOINTS];
    bool slew_;
} ls_motion_seg_t;

/* The segments of a path: seg[0..n-1] for the first cycle; seg[n] leads
 * from the last point back to the first and replaces seg[0] from the second
 * cycle on (filled when the program runs more than one cycle). Owned by the
 * caller, who must not change it while a plan that points to it runs. */
typedef struct {
    uint16_t n;
    ls_motion_seg_t seg[LS_MOTION_MAX_SEGS];
} ls_motion_program_t;

/* A planned motion. Filled by a planner, copied into the executor by
 * ls_motion_start. Callers read `ref_seq` and `name`. */
typedef enum { LS_PLAN_NONE = 0, LS_PLAN_JOINT, LS_PLAN_LINE, LS_PLAN_ARC, LS_PLAN_PATH } ls_plan_kind_t;

typedef struct {
    ls_plan_kind_t kind;
    uint32_t ref_seq;                /* request that started it (notice ref_seq) */
    char name[LS_MOTION_NAME_LEN];   /* point name, or path name */
    ls_motion_seg_t one;             /* single moves */
    const ls_motion_program_t *prog; /* LS_PLAN_PATH */
    int32_t cycles;                  /* LS_PLAN_PATH: >= 1 */
    bool dry_run;                    /* LS_PLAN_PATH: skip the auxiliary commands */
} ls_motion_plan_t;

/* Limits of a Cartesian move, SI, all > 0. The tool tip moves at most at
 * v_lin (m/s) and turns at most at v_ang (rad/s); the slower of the two
 * sets the time. Where the joints need it, the move runs slower: within
 * joint_speed_frac of the model's joint velocity limits and within its
 * joint acceleration limits (docs/architecture.md "Path speed under joint
 * limits"). */
typedef struct {
    double v_lin_m_s, a_lin_m_s2, j_lin_m_s3;
    double v_ang_rad_s, a_ang_rad_s2, j_ang_rad_s3;
    double joint_speed_frac;
} ls_motion_cart_limits_t;

typedef struct {
    const ls_robot_model_t *model;
    ls_motion_phase_t phase;
    ls_motion_plan_t plan;
    double t_s; /* trajectory clock of the current segment */
    double following_error_max_rad;
    double q_cmd[LS_N_JOINTS];
    /* The last set-points, newest at q_hist_[hist_head_]: a measurement
     * lagging by up to lag_cycles_ cycles is compared with the nearest of
     * them (ls_motion_set_feedback_lag). */
    double q_hist_[LS_MOTION_LAG_MAX][LS_N_JOINTS];
    uint16_t hist_head_, lag_cycles_, late_cycles_;
    uint32_t ignored_joints_; /* ls_motion_ignore_joints */
    /* private to ls_motion.c */
    uint16_t seg_i_;
    int32_t cycle_;
    bool blending_;
    double t_next_s_;
    int sub_; /* moving, auxiliary commands, dwell */
    uint8_t aux_k_;
    bool aux_wait_;
    double dwell_left_s_;
    /* Stops and resumes (docs/architecture.md, "Stopping and resuming").
     * The moving segment [0] and the one it blends into [1] each have their
     * own axes: a joint segment its joints, a Cartesian one its path
     * parameter. A stop drives every axis to rest on its own jerk-limited
     * ramp (halt_, from where it was); a resume re-plans each segment from
     * where its ramps left it to its end (resumed_). */
    bool ramping_;                   /* the ramps drive the axes (STOPPING), or left them at rest (PAUSED) */
    double ramp_t_s_;                /* time since the ramps began */
    double ramp_T_s_;                /* when the last of them ends */
    union {                          /* by the kind of segment k */
        ls_ramp_t ramp[LS_N_JOINTS]; /* a joint segment's, one per axis */
        ls_pathspeed_stop_t stop;    /* a Cartesian segment's path parameter */
    } halt_[2];
    bool slow_told_;         /* this segment's LS_MEV_SLOW is out (or not due) */
    bool off_plan_[2];       /* segment k runs resumed_[k], not its planned profile */
    uint8_t stop_at_end_;    /* a stop that waits for the blend to end: 0 none, 1 normal, 2 fast */
    union {                  /* by the kind of segment k */
        ls_traj_t traj;      /* a joint segment's */
        ls_pathspeed_t path; /* a Cartesian segment's */
    } resumed_[2];
} ls_motion_t;

/* Init-time: idle, holding q = 0 until ls_motion_hold. */
void ls_motion_init(ls_motion_t *m, const ls_robot_model_t *model);

/* ---- planners (comms thread; cost: joint O(1), Cartesian one IK per sample,
 * samples every 1 mm / 0.5 deg / 10 ms of the motion, at most 20000) ---- */

/* A joint move from q0 to q1 at `speed_frac` (0..1] of the joint velocity
 * limits and `accel_frac` of the acceleration and jerk limits. Returns 0, or
 * negative with `why` ("joint 3: 2.9 rad beyond its limit 2.62 rad"). */
int ls_motion_plan_joint(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                         const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why,
                         unsigned whylen);

/* A straight line of the tool tip from its pose at q0 (FK(q0) * tool) to
 * `tip1` (base frame): position linear, orientation slerped. `tool` is the
 * flange -> tip transform. Its speed follows the joints' limits along the
 * path (slower where they need it: ls_motion_seg_slowdown says where).
 * Refused when a sampled point leaves the model's workspace box, has no IK
 * solution or needs a joint beyond its position limit, or when the path
 * runs through a singularity (a joint's speed grows without bound: `why`
 * names the joint, where, the kind and what to do instead). */
int ls_motion_plan_line(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                        const double tool[16], const double tip1[16], const ls_motion_cart_limits_t *lim, char *why,
                        unsigned whylen);

/* A circular arc of the tool tip from its pose at q0 through the position of
 * `tip_via` to `tip1`; orientation slerped from start to `tip1`. Collinear
 * (or coincident) points: LS_EGEOM. Other refusals as for lines. */
int ls_motion_plan_arc(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                       const double tool[16], const double tip_via[16], const double tip1[16],
                       const ls_motion_cart_limits_t *lim, char *why, unsigned whylen);

/* A path program: `prog` must hold prog->n >= 1 segments (and seg[n] when
 * cycles > 1). dry_run skips the auxiliary commands. */
int ls_motion_plan_path(ls_motion_plan_t *p, const ls_motion_program_t *prog, int32_t cycles, bool dry_run,
                        const char *name);

/* Segment planners behind the plan_* functions (for path programs). They
 * fill the motion fields only and leave the point attributes alone. */
int ls_motion_seg_joint(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                        const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why, unsigned whylen);
int ls_motion_seg_line(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                       const double tool[16], const double tip1[16], const ls_motion_cart_limits_t *lim, char *why,
                       unsigned whylen);
int ls_motion_seg_arc(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                      const double tool[16], const double tip_via[16], const double tip1[16],
                      const ls_motion_cart_limits_t *lim, char *why, unsigned whylen);

/* The duration of segment s as planned (s): its joints' or its path
 * parameter's profile. O(1). */
double ls_motion_seg_duration_s(const ls_motion_seg_t *s);

/* Why and where a Cartesian segment runs slower than requested: its joints
 * (docs/architecture.md "Path speed under joint limits"). */
typedef struct {
    double speed_frac;  /* the lowest speed it cruises at over the requested (1: only its ramps are slower) */
    double from, to;    /* where it runs that slow: fractions of the segment (0, 0 when only the ramps) */
    double accel_frac;  /* the lowest acceleration of its ramps over the requested */
    int joint;          /* the joint (1-based) whose limit sets the lowest speed (else the ramps') */
    bool velocity;      /* that joint's velocity limit (else its acceleration limit) */
    double duration_s;  /* as planned */
    double requested_s; /* at the requested speed and acceleration alone */
} ls_motion_slowdown_t;

/* When Cartesian segment s runs slower than requested because of its
 * joints (longer than requested by more than 0.1 %): true and *out (may be
 * NULL). false for a segment that runs as requested and for a joint
 * segment. Comms thread; O(zones). */
bool ls_motion_seg_slowdown(const ls_motion_seg_t *s, ls_motion_slowdown_t *out);

/* For a move that keeps one speed along line s (a guarded move,
 * ls_react.h): LS_OK when the joints allow the requested speed all along,
 * else LS_ERANGE with `why` naming the joint, its limit, where, and the
 * highest share of the speed they allow. O(zones). */
int ls_motion_seg_check_speed(const ls_motion_seg_t *s, char *why, unsigned whylen);

/* The slowdown as a sentence for an answer (LS_MOTION_WHY_LEN holds it):
 * "running at 64 % of the requested speed between 20 % and 55 % of the
 * path: joint 3 at its velocity limit (0.52 s instead of 0.41 s)", or for
 * a segment slowed only in its ramps "accelerating at 40 % of the
 * requested rate: joint 2 at its acceleration limit (...)". Returns what
 * ls_fmt_print returns. */
int ls_motion_slowdown_text(const ls_motion_slowdown_t *d, char *text, unsigned len);

/* A slew (seed section 6, SLEW_MOTION): the fastest joint-space motion from
 * q0 to q1, each joint on its own minimum-time profile at speed_frac /
 * accel_frac of its own limits, not synchronised (the joints arrive one
 * after another; the tool's path is not the synchronised move's). Checks and
 * refusals as ls_motion_seg_joint. */
int ls_motion_seg_slew(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                       const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why, unsigned whylen);

/* The circle through p0, pv and p1 (positions, m) split at pv: mid_a is the
 * middle of the arc p0 -> pv, mid_b of the arc pv -> p1, so that two
 * ls_motion_seg_arc calls (p0 via mid_a to pv, pv via mid_b to p1) run the
 * arc through the three points. LS_EGEOM when they are collinear
 * or coincide, LS_EINVAL for NULL or non-finite input. Pure, O(1). */
int ls_motion_arc_split(const double p0[3], const double pv[3], const double p1[3], double mid_a[3], double mid_b[3]);

/* Blending (docs/architecture.md, "Blended paths"). A blend of segment `a`
 * into the following `b` starts b `a->overlap_s` = T_o before a ends and
 * adds the two motions (b's displacement from its start on top of a): joint
 * into joint in joint space, line into line in Cartesian space (positions
 * added, b's rotation composed onto a's). T_o is blend_frac times the
 * window: the shorter of a's last jerk phase and b's first one, over every
 * moving axis (joints; the path parameter of a line). Inside the window
 * each motion is in a single constant-jerk phase, which bounds the sum:
 *   speed  <= J T_o^2 / 2 per motion, at most half of its peak speed;
 *   accel  <= J T_o, at most its peak acceleration;
 *   jerk   = Ja da + Jb db: ls_motion_prog_blend lowers the jerk of both
 *            segments so this stays within the larger of their limits.
 * The tool stays within max(Ja, Jb) T_o^3 / 6 of the point (a line's
 * linear jerk J = |j of s| * length). */

/* The window and overlap of one blend, without changing the profiles:
 * a->overlap_s = frac (clamped to (0, 1]) x the window, or 0 when the blend
 * does not apply (frac <= 0, kinds other than JOINT->JOINT or LINE->LINE,
 * a with auxiliary commands or a dwell, a or b not moving). Pure, O(axes). */
void ls_motion_seg_blend(ls_motion_seg_t *a, const ls_motion_seg_t *b, double frac);

/* The bound on the tool's distance from the point at the end of `a` while
 * it blends into `b` (LINE->LINE: max(Ja, Jb) T_o^3 / 6, m), 0 when a does
 * not blend, NAN for a joint blend (no Cartesian bound: joint space). */
double ls_motion_seg_blend_dev_m(const ls_motion_seg_t *a, const ls_motion_seg_t *b);

/* Blend a whole program at its points' blend_frac (seg[k] into seg[k+1];
 * with cycles > 1 also seg[n-1] into seg[n] and seg[n] into seg[1]):
 * 1. each blended pair's jerk scale: joint j moving the same way in both
 *    segments 1/2 (else 1); a line pair turning by theta
 *    1 / max(1, 2 cos(theta / 2)) for the position, 1/4 when both rotate;
 *    every segment re-planned at the smallest scale of its pairs (slower
 *    start and end ramps, same path, same peak speed);
 * 2. the overlaps (ls_motion_seg_blend), for two rotating lines shortened
 *    until the composed rotation fits the angular limits;
 * 3. line blends sampled every 1 ms of their window: workspace box, joint
 *    solution and joint speeds, as the line planner checks its samples.
 * Returns 0, or the planner status with `why` naming the point and what to
 * do. Comms thread (planning); cost O(n) plus one IK per sampled ms. */
int ls_motion_prog_blend(ls_motion_program_t *prog, const ls_robot_model_t *model, int32_t cycles, char *why,
                         unsigned whylen);

/* ---- executor (control loop) ---- */

/* Start a plan from the current commanded position. Returns LS_OK,
 * LS_ESTATE when a motion is already running, LS_EINVAL when there is no
 * plan or it does not start within 1e-3 rad of the held set-point (nothing
 * changes). Copies the plan (not a program). */
int ls_motion_start(ls_motion_t *m, const ls_motion_plan_t *p);
/* Stop, then LS_MEV_PAUSED: every axis of the moving segment (a joint
 * segment's joints, a Cartesian segment's path parameter, and those of the
 * segment it blends into) comes to rest on its own time-optimal
 * jerk-limited ramp (ls_ramp.h) from its current position, velocity and
 * acceleration, within the segment's own acceleration and jerk limits (a
 * joint segment: on its phase, so the joints stay on their straight line; a
 * Cartesian segment: on its path parameter, ramping down zone by zone at
 * its joints' limits, ls_pathspeed_plan_stop; a slew: each joint on its
 * own). While two segments blend each gets at most half its jerk limit, so
 * that the sum stays within it; when that cannot bring the segment that has
 * just started to rest before its end, or would take a Cartesian one past
 * its zone's cap, the stop waits for the blend to end (at most the overlap)
 * and then stops that segment alone. Control-loop safe: O(zones) ramps. */
void ls_motion_stop(ls_motion_t *m);
/* The same within the model's maximum acceleration and jerk (faults,
 * emergency, shutdown): also shortens a stop already under way. */
void ls_motion_stop_fast(ls_motion_t *m);
/* The category-1 stop's bound for joint j (0-based), from the model alone
 * (docs/reliability.md, "Stopping distance and time"): the fast stop's ramp
 * from the joint's velocity limit while it still accelerates at its
 * acceleration limit, a state no plan reaches, so every stop the loop takes
 * ends within *time_s and *dist_rad (a stop that waits for a blend to end:
 * measured within it, tests/unit/motion/test_blend.c, not proved). The
 * user's settings can only make it shorter. Returns LS_OK, LS_EINVAL on a
 * bad argument, or the ramp planner's status (nothing written on error). */
int ls_motion_fast_stop_bound(const ls_robot_model_t *model, int j, double *time_s, double *dist_rad);
/* From PAUSED; LS_ESTATE otherwise. After a stop inside a segment each
 * segment is re-planned from rest where its ramps left it to its end, within
 * its own limits; two that were blending run one after the other. The
 * segment then arrives at rest instead of blending into the next. The
 * planner's status (still paused) when a profile cannot be planned.
 * Control-loop safe: closed-form
 * planning (a Cartesian segment: ls_pathspeed_plan, O(zones)), about 5 KB
 * of stack. */
int ls_motion_resume(ls_motion_t *m);
void ls_motion_abort(ls_motion_t *m); /* drop the motion at once: hold the current set-point */
/* The auxiliary command announced by LS_MEV_AUX finished: go on. */
void ls_motion_aux_done(ls_motion_t *m);

/* The arm's feedback lags its set-points by up to `cycles` control cycles
 * (drives on a bus: the set-point goes out at the next drive cycle, the
 * drive interpolates over one more, its answer comes after the next SYNC).
 * The following check then compares each measured joint with the nearest
 * of its last `cycles` + 1 set-points, so a joint that follows its path a
 * few cycles late is not taken for one that does not follow. 0 (the
 * default): the current set-point only. Clamped to LS_MOTION_LAG_MAX - 1.
 * Init time. */
void ls_motion_set_feedback_lag(ls_motion_t *m, uint16_t cycles);

/* This cycle's measurement is `extra` cycles older than the arm's usual
 * lag (a drive's answer came late): the following check widens its window
 * by that much for this cycle (the set-points of the time it was measured);
 * a measurement older than the set-points kept (LS_MOTION_LAG_MAX) is not
 * judged at all: the arm's own staleness rule (a lost drive) does that.
 * Control loop, before ls_motion_step; O(1). */
void ls_motion_feedback_late(ls_motion_t *m, uint16_t extra);

/* Joints (bit j: joint j + 1) whose drive failed and no longer follows: the
 * following check leaves them out while the others stop along the path.
 * 0 checks every joint again (a new enable). Control loop; O(1). */
void ls_motion_ignore_joints(ls_motion_t *m, uint32_t joints);

/* One control cycle: produce the set-point from the plan; check following
 * error against q_meas; append events (ev may be NULL). When idle or paused,
 * holds q_cmd. */
void ls_motion_step(ls_motion_t *m, double dt_s, const double q_meas[LS_N_JOINTS], double q_cmd[LS_N_JOINTS],
                    double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev);

/* Set the held set-point (at start-up and when the drives are enabled, so
 * the arm does not jump to a stale command); drops any motion. */
void ls_motion_hold(ls_motion_t *m, const double q[LS_N_JOINTS]);

#endif
