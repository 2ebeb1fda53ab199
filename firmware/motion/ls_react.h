/* Sensor-guided motion and jogging: the parts of the executor that close a
 * loop around a sensor or a manual device instead of following a planned
 * trajectory.
 *
 *   guarded move (moveReact): a straight tool-tip line that stops when a
 *       sensor component crosses a threshold, or at its maximum distance;
 *   compliant move (comply): a straight line while a PD law on the force
 *       error moves the tip along a compliance direction to hold a force;
 *   jog (manualControl): the tip follows a twist from a manual device.
 *
 * The travel of a guarded or compliant move is a jerk-limited rest-to-rest
 * profile along its line (ls_traj.h); its brake (a threshold, the envelope,
 * a time-out, stopMotion) is a jerk-limited ramp to rest (ls_ramp.h) from
 * wherever the travel is, at the plan's stop acceleration and jerk; the
 * return to the crossing point and a resume are rest-to-rest profiles again.
 * A jog's twist follows the device on jerk-limited ramps, per component
 * within a share of the acceleration and jerk limits whose squares sum to 1
 * (so that the linear and the angular vectors keep them; from rest the
 * components move in proportion). Each cycle the executor solves IK nearest to
 * the previous set-point and hands out the joint set-point and its velocity.
 * Orientation is held (guarded, comply) or turned by the twist (jog). Not
 * jerk-limited: a compliant move's force correction along its compliance
 * direction (a PD law whose speed a filter would delay), a panic stop, and
 * a jog stopped at a limit (it stops where IK fails).
 *
 * Where: ls_react_init at init; every other function in the control loop
 * (O(1): one or two IK of about 3 us per cycle, no allocation, no blocking).
 * The plans are filled in the comms thread (plain data, SI units).
 *
 * Events: the executor reports through ls_motion_events_t, kinds
 * LS_MEV_REACT_END (a guarded or compliant move ended, `index` is an
 * ls_react_end_t, q_rad the measured joints; the reading and the force
 * statistics are in ls_react_t.report), LS_MEV_PAUSED (a stop finished),
 * LS_MEV_FAULT (following error) and LS_MEV_JOG (jogging stopped at a limit,
 * text says which). */
#ifndef LS_REACT_H
#define LS_REACT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_motion.h"
#include "ls_ramp.h"
#include "ls_robot_model.h"
#include "ls_traj.h"

#define LS_REACT_MAX_VALUES 8
#define LS_REACT_SENSOR_NAME_LEN 32
/* A compliant move first approaches along its compliance direction at the
 * correction speed bound until the force reaches this fraction of the target,
 * then the PD law takes over; it starts travelling once the force error
 * first falls within LS_REACT_CONTACT_BAND of the target (contact
 * established). */
#define LS_REACT_SEEK_FRACTION 0.5
#define LS_REACT_CONTACT_BAND 0.2
/* Force statistics of a compliant move skip this long after travel starts
 * (the friction transient of the first lateral motion). */
#define LS_REACT_SETTLE_S 0.15
/* A guarded move that stopped on its threshold or envelope comes back to
 * where the reading crossed at this speed (m/s) or its own, if lower. */
#define LS_REACT_RETURN_SPEED_M_S 0.02

typedef enum { LS_REACT_GUARDED = 1, LS_REACT_COMPLY } ls_react_kind_t;

typedef enum {
    LS_REACT_END_THRESHOLD = 1, /* guarded: the reading crossed the threshold */
    LS_REACT_END_MAX_DISTANCE,  /* guarded: no threshold within the distance; comply: travel done */
    LS_REACT_END_ENVELOPE,      /* guarded: |F| (or the component) beyond the envelope */
    LS_REACT_END_TIMEOUT,       /* comply: time-out */
    LS_REACT_END_PANIC,         /* comply: |F| beyond the panic level */
    LS_REACT_END_ABORTED,       /* abort (abortMotion, drives disabled) */
    LS_REACT_END_UNREACHABLE,   /* IK failed, joint limit or joint speed limit on the way */
    LS_REACT_END_NO_SENSOR,     /* the sensor named in the plan is not composed */
} ls_react_end_t;

/* A guarded or compliant move, SI, tool frame = the tool frame at the start. */
typedef struct {
    ls_react_kind_t kind;
    uint32_t ref_seq;
    char sensor[LS_REACT_SENSOR_NAME_LEN]; /* resolved by the loop (hal_sensor_t.name) */
    double tool[16];                       /* flange -> tip */
    double dir_tool[3];                    /* unit direction of travel */
    double dist_m;                         /* guarded: maximum distance; comply: travel (> 0) */
    double v_m_s;                          /* travel speed (> 0) */
    double a_m_s2, j_m_s3;                 /* travel acceleration and jerk (> 0) */
    double a_stop_m_s2, j_stop_m_s3;       /* brake after a threshold, envelope, time-out or stop (> 0) */
    /* guarded */
    uint8_t component; /* watched component of the reading */
    bool below;        /* stop when reading <= threshold, else when >= threshold */
    double threshold;
    double envelope; /* > 0: |force| (force sensor) beyond it ends the move */
    /* comply */
    double n_tool[3];  /* unit compliance direction */
    double c_max_m;    /* compliance travel bound along +-n */
    double f_target_N; /* target force along n (F . n) */
    double kp_m_s_N;   /* correction speed per newton of force error */
    double kd_m_N;     /* correction speed per newton/second */
    double vc_max_m_s; /* correction speed bound */
    double timeout_s;  /* > 0 */
    double panic_N;    /* |F| beyond it: stop at once */
} ls_react_plan_t;

/* Filled when a guarded or compliant move ends (before LS_MEV_REACT_END). */
typedef struct {
    ls_react_end_t end;
    double reading[LS_REACT_MAX_VALUES]; /* the last reading (after the return and settling) */
    uint8_t n_values;
    bool triggered;                       /* guarded: threshold or envelope: */
    double trigger;                       /* the watched component's value (envelope: the force) when it crossed */
    double travelled_m;                   /* along the direction of travel */
    double fn_mean_N, fn_min_N, fn_max_N; /* comply: F . n during the travel after settling */
    uint32_t fn_samples;
    double compliance_m; /* comply: final offset along n */
} ls_react_report_t;

/* The axes a jog's twist is taken along (ls_react_jog_mode). Translation
 * and rotation are always about the tool tip; the frame gives the axes. */
typedef enum {
    LS_JOG_TOOL = 0, /* the tool frame FK(q) * tool: the axes turn with the tool */
    LS_JOG_BASE,     /* the base frame's axes */
    LS_JOG_WORLD,    /* the world frame's axes (ls_jog_config_t.world) */
} ls_jog_frame_t;
#define LS_JOG_FRAMES 3

/* Jogging limits, SI, > 0. The twist's tool frame is FK(q) * tool. */
typedef struct {
    double v_lin_m_s, v_ang_rad_s; /* at a full-scale twist (1.0) */
    double a_lin_m_s2, a_ang_rad_s2;
    double j_lin_m_s3, j_ang_rad_s3;
    double tool[16];
    double world[16]; /* base -> world frame (LS_JOG_WORLD) */
    /* Single-joint mode: joint speed at a full-scale component, and the
     * joint's acceleration and jerk. */
    double qd_rad_s[LS_N_JOINTS], qdd_rad_s2[LS_N_JOINTS], qddd_rad_s3[LS_N_JOINTS];
} ls_jog_config_t;

typedef struct {
    const ls_robot_model_t *model;
    bool active; /* a guarded or compliant move runs (or is paused) */
    bool paused;
    ls_react_plan_t plan;
    ls_react_report_t report;
    double following_error_max_rad;
    /* private to ls_react.c */
    int phase_;
    bool stop_req_;
    double q_cmd_[LS_N_JOINTS];
    double P0_[16], tool_inv_[16];
    double d_[3], n_[3]; /* base frame */
    double s_, v_, a_, c_, vc_, t_, s_trigger_, e_prev_, de_f_, travel_t_;
    bool have_e_;
    /* the travel along d_: a profile from rest (prof_) or a brake (brake_),
     * timed by prof_t_; s_next_ is where this cycle takes it */
    ls_traj_axis_t prof_;
    ls_ramp_t brake_;
    double prof_t_, s_next_;
    bool braking_, stopping_;
    ls_react_end_t end_;
    /* jog */
    bool jog_on_;
    bool jog_limited_;
    ls_jog_config_t jog_;
    double jv_[6];                               /* current twist, base frame */
    double ja_[6];                               /* its rate of change */
    double jqv_[LS_N_JOINTS], jqa_[LS_N_JOINTS]; /* single-joint mode: joint speeds and their rates */
    ls_jog_frame_t jframe_, jframe_next_;
    bool jjoint_, jjoint_next_;
} ls_react_t;

/* Init-time. */
void ls_react_init(ls_react_t *r, const ls_robot_model_t *model);

/* Check a plan's numbers (any thread): LS_OK, or LS_EINVAL with `why`. */
int ls_react_check_plan(const ls_react_plan_t *p, char *why, size_t whylen);

/* Start a guarded or compliant move from the set-point q_cmd. `n_values` is
 * the number of values of the plan's sensor. LS_OK, LS_ESTATE when one runs
 * already, LS_EINVAL for a plan that ls_react_check_plan refuses. */
int ls_react_start(ls_react_t *r, const ls_react_plan_t *p, const double q_cmd[LS_N_JOINTS], uint8_t n_values);

/* Brake at the plan's stop limits and pause (LS_MEV_PAUSED); resume plans
 * the rest of the travel (or the return) again from rest. */
void ls_react_stop(ls_react_t *r);
int ls_react_resume(ls_react_t *r); /* LS_OK, or LS_ESTATE when not paused */
/* End at once, holding the current set-point: LS_MEV_REACT_END (ABORTED)
 * into ev (may be NULL); nothing when idle. */
void ls_react_abort(ls_react_t *r, const double q_meas[LS_N_JOINTS], ls_motion_events_t *ev);
/* Whether the move is moving (not paused, not idle). */
bool ls_react_moving(const ls_react_t *r);

/* One cycle of the running move: `reading` is the plan's sensor (NULL when
 * it is not composed: the move ends with LS_REACT_END_NO_SENSOR). Writes the
 * set-point. Does nothing when idle. */
void ls_react_step(ls_react_t *r, double dt_s, const double q_meas[LS_N_JOINTS], const double *reading,
                   double q_cmd[LS_N_JOINTS], double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev);

/* Jogging: cfg NULL turns it off (the twist is then ignored). Turning it on
 * starts in the tool frame, Cartesian. */
void ls_react_jog_config(ls_react_t *r, const ls_jog_config_t *cfg);
bool ls_react_jog_on(const ls_react_t *r);
/* The jog's frame and single-joint mode (joint true: component i of the
 * twist is the speed of joint i + 1, and only the largest component counts:
 * one joint moves at a time). A change takes effect at rest: a jog that
 * moves ramps to rest first, ignoring the twist meanwhile, so no speed of
 * the old mode carries over into the new one. */
void ls_react_jog_mode(ls_react_t *r, ls_jog_frame_t frame, bool joint);
/* The mode in effect (a requested change may still wait for rest). */
ls_jog_frame_t ls_react_jog_frame(const ls_react_t *r);
bool ls_react_jog_joint(const ls_react_t *r);
/* Forget the jog's speed (drives switched on or off, fault): the next jog
 * cycle starts from rest. */
void ls_react_jog_halt(ls_react_t *r);
/* One jog cycle from the set-point q_cmd (updated in place) with the device's
 * twist (-1..1 each, in the jog frame; NULL = still). Stops, without a
 * fault, in front of a joint limit, the workspace box, a singularity or a
 * joint speed limit (one LS_MEV_JOG event saying which, when it first stops
 * there). In single-joint mode a joint brakes on its ramp in time to stop
 * at its limit. Returns true when the set-point moved. */
bool ls_react_jog_step(ls_react_t *r, double dt_s, const double *twist, double q_cmd[LS_N_JOINTS],
                       double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev);

/* "threshold", "max_distance", "envelope", "timeout", "panic", "aborted",
 * "unreachable", "no_sensor"; "unknown" otherwise. */
const char *ls_react_end_name(ls_react_end_t e);

#endif
