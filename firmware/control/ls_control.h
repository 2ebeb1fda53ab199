/* The control loop and its glue to the comms thread.
 *
 * The loop (ls_control_cycle) runs at a fixed rate on the HAL's periodic
 * runner (hal/linux real-time thread; in simulation the same runner with
 * real-time or lockstep time). Each cycle: take commands, run the motion
 * executor, command the arm, step the simulated world (config world_step),
 * read feedback, sensors and DIO, check faults, publish a snapshot and events.
 *
 * Between the threads there is no lock: commands and events travel through
 * single-producer single-consumer rings, state through a seqlock snapshot,
 * and motion plans through one plan slot handed over by a flag. Nothing in
 * the loop allocates or blocks.
 *
 * Besides planned motions (ls_motion), the loop runs the sensor-guided moves
 * and the jogging of ls_react: a guarded or compliant move is handed over in
 * a react slot like a plan (ls_control_react_slot/ls_control_start_react);
 * jogging is switched with ls_control_set_manual and then follows the manual
 * device's twist, as its gate (ls_manual.h: enabling switch, lost device,
 * override and frame buttons) lets it through, whenever the drives are on
 * and nothing else moves; tool
 * coupling and tool bits run in the loop too (LS_CTL_TOOL_*), because the
 * devices are the loop's (the simulated world is single-threaded).
 *
 * Joints that must be homed (hal_joint_status_t.home_required) and are
 * not keep every motion, react move and jog from starting (LS_CEV_CMD_FAILED
 * naming them); LS_CTL_HOME runs the drives' own homing while the arm holds
 * still, and once it ends the arm holds the new measured position.
 *
 * Comms thread API: ls_control_post, ls_control_plan_slot/ls_control_start_plan,
 * ls_control_react_slot/ls_control_start_react, ls_control_set_manual,
 * ls_control_snapshot, ls_control_next_event, ls_control_readout. */
#ifndef LS_CONTROL_H
#define LS_CONTROL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_arm.h"
#include "hal/hal_clock.h"
#include "hal/hal_dio.h"
#include "hal/hal_manual.h"
#include "ls_manual.h"
#include "ls_motion.h"
#include "ls_react.h"
#include "ls_robot_model.h"
#include "ls_seqlock.h"

/* Commands to and events from the loop (power of two). Per profile
 * (CMakeLists.txt LS_PROFILE): the mcu one halves them (one arm, one or two
 * sessions: the comms loop drains events every turn). */
#if LS_PROFILE_MCU
#define LS_CTL_QUEUE_LEN 16u
#else
#define LS_CTL_QUEUE_LEN 32u
#endif
#define LS_CTL_MAX_DIO_UNITS 4
/* The default of ls_control_config_t.enable_timeout_ms: a CiA 402 drive takes
 * three confirmed steps of one drive cycle each (a few ms to tens of ms);
 * within the host's time-out of activate (the schema's host_timeout_ms). */
#define LS_CTL_ENABLE_TIMEOUT_MS 2000u
/* Events of the arm (hal_arm_next_event) taken per cycle into the event ring. */
#define LS_CTL_ARM_EVENTS_PER_CYCLE 2

typedef enum {
    LS_CTL_ENABLE = 1, /* drives on, then hold the measured position: LS_CEV_ENABLED or LS_CEV_ENABLE_FAILED */
    LS_CTL_DISABLE,    /* drives off; a running motion first stops along its path */
    LS_CTL_START,      /* start the plan in the plan slot */
    LS_CTL_STOP,       /* decelerate along the path and pause */
    LS_CTL_RESUME,
    LS_CTL_ABORT,
    LS_CTL_DIO_WRITE,   /* dio.unit, dio.on, dio.off */
    LS_CTL_AUX_DONE,    /* a path auxiliary command finished: continue */
    LS_CTL_ESTOP_LINE,  /* dio.unit, dio.on = input bit that means e-stop when active (0: none) */
    LS_CTL_REACT_START, /* start the guarded/compliant move in the react slot */
    LS_CTL_MANUAL,      /* manual: jogging on (dev, jog) or off (dev NULL); use ls_control_set_manual */
    LS_CTL_TOOL_COUPLE, /* tool.dev, tool.id, tool.attach: LS_MEV_TOOL reports the HAL status */
    LS_CTL_TOOL_BITS,   /* tool.dev, tool.on, tool.off: LS_MEV_TOOL reports the status, dio.on the bits */
    LS_CTL_HALT,        /* as DISABLE, stopping along the path at the model's maximum deceleration */
    LS_CTL_HOME,        /* home.joints: the drives' own homing, drives on and at rest: LS_CEV_HOMED or
                           LS_CEV_HOME_FAILED */
} ls_ctl_kind_t;

#define LS_CTL_TOOL_ID_LEN 64 /* a tool id of the schema (63 bytes) and its NUL */

typedef struct {
    ls_ctl_kind_t kind;
    uint32_t ref_seq;
    struct {
        uint16_t unit;
        uint32_t on, off;
    } dio;
    struct {
        const hal_tool_t *dev;
        char id[LS_CTL_TOOL_ID_LEN];
        bool attach;
        uint32_t on, off;
    } tool;
    struct {
        const hal_manual_t *dev; /* NULL: jogging off */
        ls_jog_config_t jog;
        ls_manual_config_t gate; /* the device's enabling switch, staleness, override steps */
    } manual;
    struct {
        uint32_t joints; /* bit j: joint j + 1 */
    } home;
} ls_ctl_cmd_t;

typedef enum {
    LS_CEV_MOTION = 1,    /* motion: a motion executor event */
    LS_CEV_FAULT,         /* text: the loop disabled the drives (HAL error), or is stopping a motion
                            along its path at the model's maximum deceleration before it
                            disables them (e-stop input) */
    LS_CEV_DIO_CHANGED,   /* dio.unit, dio.on = new levels, dio.off = bits that changed */
    LS_CEV_CMD_FAILED,    /* ref_seq, text: a command the loop could not carry out */
    LS_CEV_ENABLED,       /* ref_seq: every joint confirmed ENABLED (LS_CTL_ENABLE): the arm holds where it is */
    LS_CEV_ENABLE_FAILED, /* ref_seq, text: LS_CTL_ENABLE ended with the drives off: which joint, its node and
                             what its drive said, or that no arm is composed, or that it was cancelled */
    LS_CEV_MANUAL,        /* manual: what the operator's device did (ls_manual.h), while manual control is on */
    LS_CEV_ARM_EVENT,     /* arm: what a joint's drive reported (an EMCY, its error code read back) */
    LS_CEV_HOMED,         /* ref_seq: every joint of LS_CTL_HOME homed; the arm holds its new measured position */
    LS_CEV_HOME_FAILED,   /* ref_seq, text: LS_CTL_HOME refused or ended with a joint not homed: which, and why */
} ls_cev_kind_t;

/* An event's text: one line naming a joint, its drive's node and what the
 * drive said ("joint 3 (node 0x23): FAULT, EMCY 0x8611 following error"). */
#define LS_CTL_TEXT_LEN 128

typedef struct {
    ls_cev_kind_t kind;
    uint32_t ref_seq;
    char text[LS_CTL_TEXT_LEN];
    struct {
        uint16_t unit;
        uint32_t on, off;
    } dio;
    /* What one kind carries and the others do not: one of them at a time
     * (the ring holds LS_CTL_QUEUE_LEN events: their size is static RAM). */
    union {
        struct {
            ls_motion_event_t motion; /* LS_CEV_MOTION */
            ls_react_report_t react;  /* LS_MEV_REACT_END: the reading and the force statistics */
        };
        ls_manual_event_t manual; /* LS_CEV_MANUAL */
        hal_arm_event_t arm;      /* LS_CEV_ARM_EVENT */
    };
} ls_ctl_event_t;

/* What the comms thread may read at any time (copied under a seqlock). */
typedef struct {
    uint64_t cycle;
    uint64_t t_us;
    bool enabled;
    bool enabling; /* LS_CTL_ENABLE asked, not every joint has confirmed yet */
    ls_motion_phase_t phase;
    double q_rad[LS_N_JOINTS];
    double qd_rad_s[LS_N_JOINTS];
    double q_cmd_rad[LS_N_JOINTS];
    uint32_t dio[LS_CTL_MAX_DIO_UNITS];
    /* sensors in the order of ls_control_config_t.sensors, SI, tool frame */
    double sensor[HAL_MAX_SENSORS][HAL_SENSOR_MAX_VALUES];
    double flange_pose[16]; /* FK of q_rad, base frame, column-major */
    uint32_t events_lost;
    uint32_t max_cycle_us;
    bool react_active;                /* a guarded/compliant move runs or is paused */
    bool manual_on;                   /* jogging is switched on */
    bool jogging;                     /* the set-point moved by jogging this cycle */
    uint8_t joint_state[LS_N_JOINTS]; /* hal_joint_state_t of each joint's drive */
    uint8_t joint_home[LS_N_JOINTS];  /* hal_home_t of each joint */
    uint32_t home_required;           /* bit j: joint j + 1 must be homed before it moves */
    uint32_t unhomed;                 /* bit j: joint j + 1 must be, and is not (motion is refused) */
    bool homing;                      /* LS_CTL_HOME runs */
    uint32_t home_timeout_ms;         /* how long a homing may take (hal_arm_info_t); 0: the arm has none */
} ls_ctl_snapshot_t;

/* The snapshot as 32-bit words of a seqlock (ls_seqlock.h): a read racing
 * the loop's publish is defined behaviour, and a torn copy is caught. */
#define LS_CTL_SNAP_WORDS LS_SEQLOCK_WORDS(sizeof(ls_ctl_snapshot_t))
/* Attempts of ls_control_snapshot before it gives up. Each attempt copies
 * the whole snapshot, so it lasts about as long as the loop's own publish:
 * a publish in progress costs one or two attempts; running out means the
 * loop thread stopped in the middle of a publish (descheduled, stopped in a
 * debugger) or publishes back to back. */
#define LS_CTL_SNAPSHOT_TRIES 16u

typedef struct {
    const ls_robot_model_t *model;
    hal_arm_t *arm;              /* may be NULL: no arm backend (nothing moves) */
    hal_dio_t *dio;              /* may be NULL */
    const hal_sensor_t *sensors; /* read every cycle into the snapshot */
    size_t n_sensors;
    uint32_t rate_hz;
    /* How long LS_CTL_ENABLE waits for every joint to confirm before it
     * fails naming the joints still enabling (ms; 0: LS_CTL_ENABLE_TIMEOUT_MS). */
    uint32_t enable_timeout_ms;
    /* A simulated world: advanced once per cycle after the arm command, with
     * the drives on or off (brakes), before the feedback is read. NULL on
     * hardware. E.g. hal_sim_world_step with world_ctx NULL. */
    int (*world_step)(void *world_ctx, double dt_s);
    void *world_ctx;
    /* Optional: called in the loop after it pushed an event into the event
     * ring, so an event-driven comms thread wakes for it. It runs
     * in the real-time cycle, so it must neither block nor allocate: e.g.
     * one write(2) to a non-blocking eventfd (landscaped.c says why not a
     * pipe). NULL: the comms thread polls on its own. */
    void (*notify)(void *notify_ctx);
    void *notify_ctx;
} ls_control_config_t;

typedef struct ls_control {
    ls_control_config_t cfg;
    double dt_s;
    /* comms -> loop */
    ls_ctl_cmd_t cmd_ring[LS_CTL_QUEUE_LEN];
    atomic_uint cmd_head, cmd_tail;
    ls_motion_plan_t plan_slot;
    atomic_bool plan_slot_busy; /* set by the comms thread when filled, cleared by the loop when taken */
    ls_react_plan_t react_slot;
    atomic_bool react_slot_busy;
    atomic_bool manual_on; /* written by ls_control_set_manual: plans are refused meanwhile */
    /* loop -> comms */
    ls_ctl_event_t ev_ring[LS_CTL_QUEUE_LEN];
    atomic_uint ev_head, ev_tail;
    atomic_uint events_lost;
    /* snapshot: seqlock, even = stable, odd = the loop is writing */
    atomic_uint snap_seq;
    atomic_uint snap_words[LS_CTL_SNAP_WORDS];
    /* reader-private (comms thread): the last consistent copy, and how many
     * reads returned it instead of a fresh one */
    ls_ctl_snapshot_t snap_last;
    uint32_t snap_stale;
    /* loop-private */
    ls_motion_t motion;
    ls_react_t react;
    int react_sensor; /* index of the running move's sensor, -1: none */
    const hal_manual_t *manual;
    ls_manual_t gate;                                    /* the manual device's enabling switch and buttons */
    double sens[HAL_MAX_SENSORS][HAL_SENSOR_MAX_VALUES]; /* last reading, SI */
    bool jogging;
    bool enabled;
    bool enabling; /* LS_CTL_ENABLE asked: waiting for every joint's ENABLED */
    uint64_t enable_deadline_us;
    uint32_t enable_ref_seq;                /* the LS_CTL_ENABLE being carried out */
    uint64_t now_us;                        /* the current cycle's time */
    bool disable_pending;                   /* DISABLE while moving: stop along the path first */
    hal_joint_status_t joints[LS_N_JOINTS]; /* this cycle's status of each joint's drive */
    uint32_t failed_joints;                 /* joints whose drive failed while under control (drive_fault) */
    uint32_t homing_joints;                 /* LS_CTL_HOME runs on these (0: none) */
    uint32_t home_timeout_ms;               /* the arm's (hal_arm_info_t), read at init */
    uint32_t home_ref_seq;
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], q_cmd[LS_N_JOINTS], qd_cmd[LS_N_JOINTS];
    uint32_t dio_levels[LS_CTL_MAX_DIO_UNITS];
    uint16_t estop_unit;
    uint32_t estop_bit;
    uint64_t cycles;
    uint32_t max_cycle_us;
} ls_control_t;

/* Init-time. Reads the arm once so the first set-point equals the measured position. */
void ls_control_init(ls_control_t *c, const ls_control_config_t *cfg);

/* The loop body: call once per period with the runner's time. */
void ls_control_cycle(ls_control_t *c, uint64_t now_us);

/* --- comms thread --- */

/* Queue a command; false when the ring is full (the caller answers CMD_BUSY_ERR). */
bool ls_control_post(ls_control_t *c, const ls_ctl_cmd_t *cmd);
/* The plan slot to fill, or NULL while the loop has not taken the previous
 * plan, or while jogging is switched on (ls_control_manual_on tells which). */
ls_motion_plan_t *ls_control_plan_slot(ls_control_t *c);
/* Hand the filled slot over and queue LS_CTL_START. */
bool ls_control_start_plan(ls_control_t *c, uint32_t ref_seq);
/* The react slot to fill (SI plan, ls_react.h), or NULL while the loop has
 * not taken the previous one or jogging is on. */
ls_react_plan_t *ls_control_react_slot(ls_control_t *c);
/* Hand the filled react slot over and queue LS_CTL_REACT_START. The loop
 * answers LS_CEV_CMD_FAILED when it cannot start it (drives off, a motion
 * runs), else the move ends with one LS_MEV_REACT_END (or LS_MEV_FAULT). */
bool ls_control_start_react(ls_control_t *c, uint32_t ref_seq);
/* Jogging on (dev and jog non-NULL) or off (dev NULL), with the device's
 * gate (NULL: no enabling switch, no staleness, no override steps). From
 * then on the loop reads the device every cycle, through ls_manual (events
 * LS_CEV_MANUAL), and jogs with what it lets through whenever the drives
 * are on and nothing else moves. false when the queue is full. */
bool ls_control_set_manual(ls_control_t *c, const hal_manual_t *dev, const ls_jog_config_t *jog,
                           const ls_manual_config_t *gate, uint32_t ref_seq);
bool ls_control_manual_on(ls_control_t *c);
/* A consistent copy of the loop's state: true when `out` is the latest one
 * the loop published. Bounded: at most LS_CTL_SNAPSHOT_TRIES copies of
 * sizeof(ls_ctl_snapshot_t) bytes, no waiting.
 *
 * Failure mode: when every attempt overlapped a publish (the loop keeps the
 * seqlock busy), it returns false and fills `out` with the last consistent
 * copy this reader took (never a torn mix; its `cycle` and `t_us` tell its
 * age: that of this reader's last successful read) and counts the event in
 * `snap_stale`. Callers that report state (telemetry, status answers) use
 * that copy as it is. A caller that must act on the present state (a
 * decision that the next cycle could change) treats false like a busy loop:
 * refuse with a busy answer and let the sender retry.
 *
 * One reader: the comms thread (the last copy is its private state). */
bool ls_control_snapshot(ls_control_t *c, ls_ctl_snapshot_t *out);
/* Take the next event; false when none. */
bool ls_control_next_event(ls_control_t *c, ls_ctl_event_t *out);
/* The per-axis readouts of the arm's drives (hal_arm_readout: the copy the
 * control thread published at the latest drive cycle; lock-free). LS_OK,
 * LS_EAGAIN (a publish overlapped every try: the previous copy),
 * LS_EUNSUPPORTED (no arm, or an arm without drives to read). */
int ls_control_readout(ls_control_t *c, hal_arm_readout_t *out);

#endif
