/* Arm contract: joint commands and feedback, sensors and a tool changer
 * (the manual input devices have their own contract: hal/hal_manual.h).
 * hal/sim implements all of them on an ODE world; a real controller
 * implements what its hardware has and leaves the rest NULL.
 * The arm of real drives (firmware/drives: CiA 402 over CANopen) enables in
 * steps, one per drive cycle, and its feedback arrives once per drive cycle:
 * enable() asks, status() tells when each joint is under control, and read()
 * returns the latest feedback with its age in status(). Such an arm may also
 * home its joints (the drives' own homing: home(), its progress in status())
 * and publish per-axis readouts for operators (readout()).
 *
 * Threading: every operation except open/close and readout() is called from
 * the control loop: no blocking, no allocation. readout() is the comms
 * thread's: it copies what the control thread published, without a lock. Units: SI (m, rad, N, Nm, s).
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
    /* How long a homing (home()) may take before it fails, ms; 0: the arm
     * has no homing. */
    uint32_t home_timeout_ms;
} hal_arm_info_t;

/* One joint's drive, as the backend knows it this cycle. */
typedef enum {
    HAL_JOINT_OFF = 0,  /* disabled: no torque, a holding brake holds */
    HAL_JOINT_ENABLING, /* enable() asked, the drive has not confirmed yet */
    HAL_JOINT_ENABLED,  /* under control: follows the set-points */
    HAL_JOINT_FAULT,    /* the drive reports a fault (code, text); it holds no set-point */
    HAL_JOINT_LOST,     /* the drive stopped answering (heartbeat, feedback, bus) */
} hal_joint_state_t;

/* Where a joint's homing stands (the drive's own homing, CiA 402 mode 6).
 * A joint whose position is absolute (an absolute encoder, a simulated
 * arm) needs none; one with an incremental encoder must be homed once
 * after its drive boots before anything moves it (home_required). */
typedef enum {
    HAL_HOME_NOT_HOMED = 0, /* not homed since its drive booted */
    HAL_HOME_HOMING,        /* the drive's homing runs */
    HAL_HOME_HOMED,         /* homed since its drive booted (kept across disable and enable) */
    HAL_HOME_FAILED,        /* the last homing failed (status text says why) */
} hal_home_t;

typedef struct {
    hal_joint_state_t state;
    uint16_t node;         /* the drive's bus address, 0 when it has none (a simulated arm) */
    uint32_t code;         /* the drive's error code (CiA 402: EMCY / 0x603F), 0 when none */
    uint32_t feedback_age; /* control cycles since this joint's feedback was fresh; 0: fresh */
    /* What the drive said, for one-line messages, e.g. "FAULT, EMCY 0x8611 following
     * error" or "no heartbeat for 300 ms"; "" when there is nothing to say. */
    char text[HAL_JOINT_TEXT_LEN];
    hal_home_t home;    /* HAL_HOME_NOT_HOMED on an arm without homing */
    bool home_required; /* motion waits for HAL_HOME_HOMED (an incremental encoder) */
} hal_joint_status_t;

/* What an operator reads of each joint's drive (what moteus_tool and
 * odrivetool show): published by the control thread once per drive cycle,
 * read by the comms thread (readout()). Every value is the drive's own
 * report, not the controller's command. */
#define HAL_READOUT_COUNTERS 16 /* counters of the drive bus's master */
typedef enum {
    HAL_TRI_UNKNOWN = 0, /* the drive does not publish it (not configured, not mappable) */
    HAL_TRI_OFF,         /* brake released / safe torque off inactive */
    HAL_TRI_ON,          /* brake engaged / safe torque off active */
} hal_tri_t;

typedef struct {
    uint16_t node;          /* the drive's bus address */
    uint16_t statusword;    /* CiA 402 0x6041 as received */
    const char *state;      /* its power state, "OPERATION ENABLED" (static text) */
    int8_t mode;            /* mode of operation displayed (0x6061); 0 when unknown */
    uint16_t last_error;    /* the last EMCY's error code since the drive booted (0: none) */
    const char *error_name; /* its CiA 301/402 name (static text; "" when none) */
    double position_rad;    /* position actual, joint radians */
    bool has_velocity;      /* velocity actual (0x606C) is mapped */
    double velocity_rad_s;
    bool has_torque;         /* torque actual (0x6077) is mapped */
    int16_t torque_permille; /* per mille of the motor's rated torque */
    bool has_temperature;    /* the configured temperature object is mapped */
    double temperature_c;
    hal_tri_t brake; /* the holding brake, from the drive's status */
    hal_tri_t sto;   /* the safe torque off input, from the drive's status */
    hal_home_t home;
    bool home_required;
    uint32_t feedback_age; /* control cycles since its feedback was fresh */
} hal_drive_readout_t;

typedef struct {
    uint64_t t_us; /* the drive cycle that published it (0: none yet) */
    uint8_t n_joints;
    hal_drive_readout_t joint[HAL_ARM_MAX_JOINTS];
    uint8_t n_counters;
    struct {
        const char *name; /* "sync_sent" (static text) */
        uint32_t value;
    } counter[HAL_READOUT_COUNTERS];
} hal_arm_readout_t;

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
    /* Optional: start the drives' own homing of the joints in `joint_mask`
     * (bit j: joint j + 1), each enabled and at rest. Returns at once: the
     * homing runs over drive cycles, status() shows it (HAL_HOME_HOMING,
     * then HOMED or FAILED with the drive's words) and the joint then holds
     * its new measured position. LS_OK; LS_EINVAL (an empty mask, a joint
     * the arm has not); LS_EBUSY (a joint not ENABLED, or homing already).
     * NULL: LS_EUNSUPPORTED (an arm whose positions are absolute). */
    int (*home)(void *self, uint32_t joint_mask);
    /* Optional, the comms thread's: copy the readouts the control thread
     * published at the latest drive cycle into *out (lock-free, bounded,
     * O(joints); never the backend's working state). LS_OK, LS_EAGAIN (the
     * publish overlapped every try: *out holds the previous copy).
     * NULL: LS_EUNSUPPORTED (an arm without drives to read). */
    int (*readout)(void *self, hal_arm_readout_t *out);
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
/* home and readout without a backend operation: LS_EUNSUPPORTED. */
int hal_arm_home(hal_arm_t *arm, uint32_t joint_mask);
int hal_arm_readout(hal_arm_t *arm, hal_arm_readout_t *out);
/* "not_homed", "homing", "homed", "failed"; "?" out of range. */
const char *hal_home_name(hal_home_t home);

#endif
