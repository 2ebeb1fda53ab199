/* Private to the core: what the motion handlers share. The handlers are
 * split by what they do:
 *   cmd_motion.c         pose maths, limits, checks, handing a plan over (below)
 *   cmd_move.c           moveAbsolute/Relative/Arc, stop/resume/abort, getTagId
 *   cmd_path.c           the path queues: pathLoad, pathClearPath
 *   cmd_path_program.c   pathMove: the program builder
 *   cmd_aux.c            a path's auxiliary commands: parser and runner
 *   cmd_motion_events.c  the executor's events -> state and notices
 * Their storage is core->motion (ls_core_state.h). Comms thread only. */
#ifndef LS_CMD_MOTION_H
#define LS_CMD_MOTION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_control.h"
#include "ls_core_services.h"
#include "ls_motion.h"

/* ------------------------------------------------------------- cmd_motion.c */

/* The longest text the path builder puts before a planner's own (the
 * point and its kind): what it passes to ls_mcmd_refused holds both. */
#define LS_MCMD_POINT_PREFIX_LEN 48
#define LS_MCMD_WHY_LEN (LS_MCMD_POINT_PREFIX_LEN + LS_MOTION_WHY_LEN)

/* Answer a planner's refusal: CMD_PARAM_OUT_OF_RANGE_ERR for LS_ERANGE,
 * CMD_PARAM_ERR otherwise; "nothing moved". `why` (at most
 * LS_MCMD_WHY_LEN bytes with its NUL) fits the answer whole. */
int32_t ls_mcmd_refused(ls_call_t *call, int status, const char *what, const char *why);
/* The control loop's snapshot; false (and *snap untouched) without a loop. */
bool ls_mcmd_snapshot(ls_core_t *core, ls_ctl_snapshot_t *snap);
/* Flange -> tool tip, base -> world (the settings), as poses. */
void ls_mcmd_tool_pose(const ls_core_t *core, double T[16]);
void ls_mcmd_world_pose(const ls_core_t *core, double T[16]);
/* Tool-tip pose (base frame) of joints q. */
void ls_mcmd_tip_of(const ls_core_t *core, const double q[LS_N_JOINTS], double P[16]);
/* A relative Cartesian offset d (x y z roll pitch yaw, SI) applied to the
 * tip pose P in the axes of frame F (base: identity, world: the world frame). */
void ls_mcmd_offset_in_frame(const double F[16], const double P[16], const double d[6], double out[16]);
/* Cartesian limits of a move at speed_pct and accel_pct of the model's
 * Cartesian maxima; 0 for either: the settings (the kind of the most recent
 * setSpeed / setAcceleration call decides, docs/protocol.md). */
void ls_mcmd_cart_limits(const ls_core_t *core, double speed_pct, double accel_pct, ls_motion_cart_limits_t *lim);
/* Checks that answer the refusal themselves: 0 when good, else the code. */
int32_t ls_mcmd_check_speed_pct(ls_call_t *call, double pct);
int32_t ls_mcmd_check_name(ls_call_t *call, const char *what, const char *field, const char *name);
bool ls_mcmd_all_finite(const double *v, size_t n);
/* Range checks in the session's units `un`, so a refusal speaks the units
 * the request was written in ("joint 1: 500 deg beyond its limit 170 deg"):
 * LS_OK, or LS_ERANGE with `why` naming the first joint of q_rad (SI) outside
 * the model's limits, or the first axis of the tip position p_m (base frame,
 * SI) outside its workspace box. No allocation; O(joints). */
int ls_mcmd_joints_within(const ls_core_t *core, ls_units_t un, const double q_rad[LS_N_JOINTS], char *why,
                          size_t whylen);
int ls_mcmd_tip_within(const ls_core_t *core, ls_units_t un, const double p_m[3], char *why, size_t whylen);
/* The 6 values x y z roll pitch yaw of `field` (in the caller's units `un`)
 * within the bounds of LS_FRAME_ANGLE_MAX_RAD and, when `translations`,
 * LS_POSE_REACH_FACTOR (an absolute target's position is the workspace
 * check's, ls_mcmd_tip_within): 0, or CMD_PARAM_OUT_OF_RANGE_ERR answered
 * naming the value and the bound. */
int32_t ls_mcmd_check_pose(const ls_core_t *core, ls_call_t *call, const char *what, const char *field, const double *v,
                           ls_units_t un, bool translations);
/* CMD_UNSUPPORTED_ERR: no arm is composed. */
int32_t ls_mcmd_no_arm(ls_call_t *call, const char *what);
/* The plan slot, or NULL after answering in *code: CMD_BUSY_ERR, or a joint
 * that must be homed is not (ls_drv_refuse_unhomed). */
ls_motion_plan_t *ls_mcmd_take_slot(ls_core_t *core, ls_call_t *call, const char *what, int32_t *code);
/* Hand the plan in the slot over and enter MOVING (the answer: STARTED_OK,
 * with `note` after it when not NULL: why the move runs slower, say). */
int32_t ls_mcmd_start_plan(ls_core_t *core, ls_call_t *call, ls_motion_plan_t *slot, const char *seed_name,
                           const char *point, int path, const char *note);
/* Post a command without arguments to the loop; false when its queue is full. */
bool ls_mcmd_post(ls_core_t *core, ls_ctl_kind_t kind, uint32_t ref_seq);

/* ------------------------------------------------------------- cmd_path.c */

/* Index of the path queue named `name`, or LS_PATH_NONE. */
int ls_path_find(const ls_core_t *core, const char *name);
/* Empty path queue i (no-op outside 0..LS_PATH_MAX-1). */
void ls_path_delete(ls_core_t *core, int i);

/* ------------------------------------------------------------- cmd_aux.c */

typedef enum { LS_AUX_DIO = 1, LS_AUX_WAIT, LS_AUX_EVENT, LS_AUX_RSVP } ls_aux_kind_t;

typedef struct {
    ls_aux_kind_t kind;
    uint16_t unit;
    uint32_t on, off; /* dio: bits to set, bits to clear; wait: on = mask */
    double timeout_s;
    char name[LS_MOTION_NAME_LEN];
} ls_aux_t;

/* Parse one auxiliary command; LS_OK, or LS_EINVAL with `why` saying what is expected. */
int ls_aux_parse(const char *text, ls_aux_t *a, char *why, size_t whylen);
/* The DIO unit and bits a `dio` or `wait` names exist here; LS_OK or LS_EINVAL with `why`. */
int ls_aux_check_io(const ls_core_t *core, const ls_aux_t *a, char *why, size_t whylen);
/* The executor reached a point's auxiliary command (LS_MEV_AUX): run it. */
void ls_aux_run(ls_core_t *core, const ls_motion_event_t *ev);

#endif
