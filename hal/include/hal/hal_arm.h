/* Arm contract: joint commands and feedback, sensors and a tool changer
 * (the manual input devices have their own contract: hal/hal_manual.h).
 * hal/sim implements all of them on an ODE world; a real controller
 * implements what its hardware has and leaves the rest NULL.
 * The arm of real drives (firmware/drives: CiA 402 over CANopen) enables in
 * steps, one per drive cycle, and its feedback arrives once per drive cycle:
 * enable() asks, status() tells when each joint is under control, and read()
 * returns the latest feedback with its age in status().
 *
 * Threading: every operation except open/close is called from the control
 * loop: no blocking, no allocation. Units: SI (m, rad, N, Nm, s).
 * A simulated world advances through its own call (hal/sim/world:
 * hal_sim_world_step), which the contract of a real arm does not have. */
#ifndef HAL_ARM_H
#define HAL_ARM_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_status.h"

#define HAL_ARM_MAX_JOINTS 8
#define HAL_MAX_SENSORS 4
#define HAL_SENSOR_MAX_VALUES 8
#define HAL_JOINT_TEXT_LEN 96 /* hal_joint_status_t.text with its NUL */

typedef struct {
    uint8_t n_joints;
    double q_min_rad[HAL_ARM_MAX_JOINTS];
    double q_max_rad[HAL_ARM_MAX_JOINTS];
    double torque_max_Nm[HAL_ARM_MAX_JOINTS];
    /* How many control cycles the measured joints lag the set-points at
     * most (a drive bus: the set-point's way out, the drive's
     * interpolation, the feedback's way back); 0: they follow within the
     * cycle. The following-error check allows for it. */
    uint16_t feedback_lag_cycles;
} hal_arm_info_t;

/* One joint's drive, as the backend knows it this cycle. */
typedef enum {
    HAL_JOINT_OFF = 0,  /* disabled: no torque, a holding brake holds */
    HAL_JOINT_ENABLING, /* enable() asked, the drive has not confirmed yet */
    HAL_JOINT_ENABLED,  /* under control: follows the set-points */
    HAL_JOINT_FAULT,    /* the drive reports a fault (code, text); it holds no set-point */
    HAL_JOINT_LOST,     /* the drive stopped answering (heartbeat, feedback, bus) */
} hal_joint_state_t;

typedef struct {
    hal_joint_state_t state;
    uint16_t node;         /* the drive's bus address, 0 when it has none (a simulated arm) */
    uint32_t code;         /* the drive's error code (CiA 402: EMCY / 0x603F), 0 when none */
    uint32_t feedback_age; /* control cycles since this joint's feedback was fresh; 0: fresh */
    /* What the drive said, for one-line messages, e.g. "FAULT, EMCY 0x8611 following
     * error" or "no heartbeat for 300 ms"; "" when there is nothing to say. */
    char text[HAL_JOINT_TEXT_LEN];
} hal_joint_status_t;

/* Something a joint's drive reported that the supervisors should hear of:
 * an emergency message (CiA 301 EMCY) or the drive's error register read
 * back after a fault. One line of text names it all; the numbers are there
 * for the fault log and the alarm's data. */
typedef struct {
    uint8_t joint;                 /* 0-based */
    uint16_t node;                 /* the drive's bus address */
    uint16_t code;                 /* EMCY error code (CiA 301/402), or the 0x603F error code */
    uint8_t reg;                   /* EMCY error register (0x1001) */
    uint8_t vendor[5];             /* EMCY manufacturer-specific bytes */
    bool is_emcy;                  /* an EMCY frame; false: the error code read back (0x603F) */
    char meaning[48];              /* the code's name: "following error" */
    char text[HAL_JOINT_TEXT_LEN]; /* "EMCY 0x8611 following error (register 0x21)" */
} hal_arm_event_t;

typedef struct {
    int (*info)(void *self, hal_arm_info_t *out);
    /* Ask the drives to enable (on) or disable. Returns at once: a drive
     * enables in steps that status() reports (ENABLING, then ENABLED), and a
     * joint that cannot be enabled reports FAULT or LOST there. Disabling
     * takes effect for the caller at once (set-points are no longer
     * followed); brakes engage as the drives confirm. */
    int (*enable)(void *self, bool on);
    /* Set-point for this cycle: position and velocity feed-forward per joint. */
    int (*command)(void *self, const double *q_rad, const double *qd_rad_s);
    /* The latest measured joint positions and velocities (their age: status). */
    int (*read)(void *self, double *q_rad, double *qd_rad_s);
    void (*close)(void *self);
    /* Optional: each joint's state, n_joints entries. NULL: every joint
     * follows enable() at once (ENABLED after enable(true), OFF after
     * enable(false)), never faults and reads fresh feedback every cycle. */
    int (*status)(void *self, hal_joint_status_t *out);
    /* Optional: the backend's own work once per control cycle, after
     * command() and before read(): bus traffic and protocol timers (a drive
     * bus sends the cycle's set-points and its SYNC, takes the drives'
     * answers). `now_us` is the cycle's time. NULL: nothing to do. */
    int (*update)(void *self, uint64_t now_us);
    /* Optional: the oldest event the drives reported and nobody took yet;
     * 1 when *out was written, 0 when none. NULL: an arm without events. */
    int (*next_event)(void *self, hal_arm_event_t *out);
} hal_arm_ops_t;

typedef struct {
    const hal_arm_ops_t *ops;
    void *self;
    char name[64];
} hal_arm_t;

/* A sensor, e.g. "force_sensor" (Fx Fy Fz Tx Ty Tz in the tool frame, N and
 * Nm) or "laser_standoff_sensor" (distance along the tool z axis, m). */
typedef struct {
    const char *name;
    uint8_t n_values;
    int (*read)(void *self, double *values); /* n_values doubles */
    void *self;
} hal_sensor_t;

/* Tool changer: the rack and the tool's output bits (a gripper in sim). */
typedef struct {
    /* The name of rack slot `index` (0..), or NULL past the last slot.
     * Called from the comms thread: constant data only. */
    const char *(*name)(void *self, int index);
    /* Where tool `index` sits in the rack: flange pose to approach, base frame. */
    int (*rack_pose)(void *self, const char *tool_id, double xyzrpy[6]);
    /* Tool offset (flange -> tool tip) of a tool, x y z roll pitch yaw. */
    int (*tool_offset)(void *self, const char *tool_id, double xyzrpy[6]);
    /* Couple the tool at the flange (1) or leave it in the rack (0). LS_EINVAL
     * when the flange is not at the rack pose of that tool. */
    int (*couple)(void *self, const char *tool_id, bool attach);
    /* Drive the coupled tool's bits. */
    int (*set_bits)(void *self, uint32_t on, uint32_t off);
    int (*get_bits)(void *self, uint32_t *bits);
} hal_tool_ops_t;

typedef struct {
    const hal_tool_ops_t *ops;
    void *self;
} hal_tool_t;

int hal_arm_info(hal_arm_t *arm, hal_arm_info_t *out);
int hal_arm_enable(hal_arm_t *arm, bool on);
int hal_arm_command(hal_arm_t *arm, const double *q_rad, const double *qd_rad_s);
int hal_arm_read(hal_arm_t *arm, double *q_rad, double *qd_rad_s);
void hal_arm_close(hal_arm_t *arm);
/* The optional operations: status() without a backend operation fills
 * `out` per enable()'s contract above from `enabled` (the caller's view)
 * and returns LS_OK; update() without one returns LS_OK. */
int hal_arm_status(hal_arm_t *arm, bool enabled, uint8_t n_joints, hal_joint_status_t *out);
int hal_arm_update(hal_arm_t *arm, uint64_t now_us);
/* next_event without a backend operation: 0 (none). */
int hal_arm_next_event(hal_arm_t *arm, hal_arm_event_t *out);

#endif
