/* The motion executor: plans (made outside the control loop by the planners
 * below) and their execution, one control cycle at a time, in the loop.
 *
 * Planning: ls_motion_plan_* run in the comms thread (they may search, run
 * IK, check limits) and fill an ls_motion_plan_t. Refusals name the joint or
 * axis and the limit in `why`.
 * Execution: ls_motion_start/stop/resume/abort and ls_motion_step run in the
 * control loop: O(1) per cycle apart from one IK per Cartesian cycle, no
 * allocation, no blocking.
 *
 * Units: SI everywhere (m, rad, s); conversion from the user's units happens
 * in the command handlers. */
#ifndef LS_MOTION_H
#define LS_MOTION_H

#include <stdbool.h>
#include <stdint.h>

#include "ls_robot_model.h"
#include "ls_traj.h"

#define LS_MOTION_NAME_LEN 32
#define LS_MOTION_MAX_EVENTS 4 /* per cycle */

typedef enum {
    LS_MOTION_IDLE = 0,
    LS_MOTION_RUNNING,
    LS_MOTION_STOPPING, /* decelerating along the path after ls_motion_stop */
    LS_MOTION_PAUSED,
} ls_motion_phase_t;

typedef enum {
    LS_MEV_DONE = 1, /* the plan finished: name = point or path name */
    LS_MEV_TAG,      /* a tagged path point was reached: name, index, cycle */
    LS_MEV_PAUSED,   /* a stop finished decelerating */
    LS_MEV_FAULT,    /* following error, limit: text; the executor is idle afterwards */
    LS_MEV_AUX,      /* a path auxiliary command is due: text = the command; executor waits
                        until ls_motion_aux_done() */
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

/* A planned motion. Filled by a planner, copied into the executor by
 * ls_motion_start. The motion module may add fields; callers only use the
 * planners and read `ref_seq` and `name`. */
typedef enum { LS_PLAN_NONE = 0, LS_PLAN_JOINT } ls_plan_kind_t;

typedef struct {
    ls_plan_kind_t kind;
    uint32_t ref_seq;                 /* request that started it (notice ref_seq) */
    char name[LS_MOTION_NAME_LEN];    /* point name */
    ls_traj_t traj;                   /* LS_PLAN_JOINT: joint space, rest to rest */
} ls_motion_plan_t;

typedef struct {
    const ls_robot_model_t *model;
    ls_motion_phase_t phase;
    ls_motion_plan_t plan;
    double t_s;                       /* trajectory clock */
    ls_timescale_t ts;
    double following_error_max_rad;
    double q_cmd[LS_N_JOINTS];
} ls_motion_t;

void ls_motion_init(ls_motion_t *m, const ls_robot_model_t *model);

/* Planner: a joint move from q0 to q1 at `speed_frac` (0..1] of the joint
 * velocity limits and `accel_frac` of the acceleration limits. Returns 0, or
 * -1 with `why` ("joint 3: 2.9 rad beyond its limit 2.62 rad"). */
int ls_motion_plan_joint(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                         const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why,
                         unsigned whylen);

/* Control loop: start a plan from the current commanded position. Returns 0,
 * or -1 when a motion is already running (nothing changes). */
int ls_motion_start(ls_motion_t *m, const ls_motion_plan_t *p);
void ls_motion_stop(ls_motion_t *m);   /* decelerate along the path, then LS_MEV_PAUSED */
int ls_motion_resume(ls_motion_t *m); /* from PAUSED; -1 otherwise */
void ls_motion_abort(ls_motion_t *m); /* drop the motion at once: hold the current set-point */

/* One control cycle: produce the set-point from the plan; check following
 * error against q_meas; append events. When idle, holds q_cmd. */
void ls_motion_step(ls_motion_t *m, double dt_s, const double q_meas[LS_N_JOINTS], double q_cmd[LS_N_JOINTS],
                    double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev);

/* The comms thread finished the pending auxiliary command: continue the path. */
void ls_motion_aux_done(ls_motion_t *m);

/* Set the held set-point (at start-up and when the drives are enabled, so
 * the arm does not jump to a stale command). */
void ls_motion_hold(ls_motion_t *m, const double q[LS_N_JOINTS]);

#endif
