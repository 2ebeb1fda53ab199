/* Storage of the command handlers (firmware/core/cmd_*.c), owned by
 * ls_core_t like every other piece of the core's state: the path queues and
 * the program being run (cmd_path.c, cmd_path_program.c), the last tag
 * reached (cmd_motion_events.c), manual control (cmd_sensor.c), the end
 * effector (cmd_tool.c) and the DIO watches and writes (cmd_dio.c).
 * ls_core_init gives every field its start value.
 *
 * Types layer of firmware/core (docs/architecture.md "Core layers"): only
 * types here, no functions; ls_core_types.h includes it. */
#ifndef LS_CORE_STATE_H
#define LS_CORE_STATE_H

#include <stdbool.h>
#include <stdint.h>

#include "landscape.pb.h"
#include "ls_control.h"
#include "ls_core_limits.h"
#include "ls_motion.h"

/* Path queues: LS_PATH_MAX names of LS_PATH_MAX_POINTS points (ls_motion.h).
 * With the program they are the firmware's largest static tables (the
 * table in docs/performance.md section 7). The build's profile picks the
 * value (CMakeLists.txt, LS_PROFILE: linux, or mcu for a 256 KiB-RAM
 * Cortex-M4F); -DLS_PATH_MAX=N for the whole build overrides it. The device
 * publishes it (describe: max_paths). */
#ifndef LS_PATH_MAX
#if LS_PROFILE_MCU
#define LS_PATH_MAX 2
#else
#define LS_PATH_MAX 8
#endif
#endif

/* What a path point stores its numbers in (pose or joints, dwell and
 * percentages). linux: double, as received. mcu: float, half the bytes: its
 * 24-bit significand keeps a relative 6e-8, i.e. 0.4 urad on an angle up to
 * 2 pi and 0.12 um on a coordinate up to 2 m, far below what an arm
 * repeats (tens of um, tens of urad) and below the set-points a drive
 * resolves; the dwell (<= 3600 s) keeps 0.2 ms, the percentages 6e-6 %. The
 * handlers plan from the stored value, so what is checked is what runs. */
#if LS_PROFILE_MCU
typedef float ls_path_real_t;
#else
typedef double ls_path_real_t;
#endif

/* One point of a path queue as pathLoad checked it, in SI. */
typedef struct {
    bool used;
    ls_ReferenceFrame frame;
    ls_MotionType motion; /* STRAIGHT_ and CIRCULAR_MOTION: Cartesian points only */
    bool relative;
    ls_path_real_t v[LS_N_JOINTS]; /* SI: joints (rad), or x y z (m) roll pitch yaw (rad) */
    char tag[LS_MOTION_NAME_LEN];
    int32_t tag_index;
    ls_path_real_t delay_s, blend_pct, speed_pct, accel_pct;
    uint8_t n_aux;
    char aux[LS_MOTION_AUX_PER_POINT][LS_MOTION_AUX_LEN];
} ls_path_point_t;

typedef struct {
    bool used;
    char name[LS_MOTION_NAME_LEN];
    uint16_t n;
    ls_path_point_t pt[LS_PATH_MAX_POINTS];
} ls_path_t;

#define LS_PATH_NONE (-1) /* an index of ls_motion_cmds_t.paths that names none */

/* Seed 3.4-3.6: the path queues, the program of the path being run, the
 * last tag reached (getTagId). */
typedef struct {
    ls_path_t paths[LS_PATH_MAX];
    ls_motion_program_t prog;
    char tag_path[LS_MOTION_NAME_LEN];
    char tag_last[LS_MOTION_NAME_LEN];
    uint64_t now_us;        /* the comms thread's clock at the last tick */
    ls_ctl_snapshot_t snap; /* scratch (large: not on the stack) */
} ls_motion_cmds_t;

/* Seed 3.7.2-3.7.4: manual control. */
typedef struct {
    char mode[16];         /* "off", or the manualControl mode that is on */
    int sup;               /* the session that switched it on, LS_NO_SESSION when off */
    int kind;              /* its ls_manual_kind_t, -1 when off */
    ls_motion_seg_t check; /* scratch for the reachability check of a move's line */
} ls_sensor_cmds_t;

/* getTool/putTool in progress: the rack's approach, the way in, the
 * coupling and the way out. */
typedef struct {
    bool active;
    bool attach; /* getTool (true) or putTool */
    int sup;
    uint32_t ref_seq;
    int step;
    char id[LS_CTL_TOOL_ID_LEN];
    double rack[16], approach[16]; /* flange poses, base frame */
    double offset[6];              /* the tool's offset, SI */
} ls_tool_op_t;

/* setToolBits in progress. */
typedef struct {
    bool active;
    bool on;
    int sup;
    uint32_t ref_seq;
    uint32_t bits;
} ls_bits_op_t;

/* Seed 3.8: the end effector. */
typedef struct {
    char held[LS_CTL_TOOL_ID_LEN]; /* "none" when no tool is held */
    uint32_t bits;
    ls_tool_op_t op;
    double q_hold[LS_N_JOINTS]; /* set-point where the last step ended */
    ls_bits_op_t bits_op;
} ls_tool_cmds_t;

/* signalDigitalIO watches and setDigitalIO writes in flight (firmware/core/cmd_dio.c). */
typedef enum { LS_WATCH_FREE = 0, LS_WATCH_ARMED, LS_WATCH_AWAIT_RSVP } ls_watch_phase_t;

typedef struct {
    ls_watch_phase_t phase;
    uint32_t id;
    int sup; /* the session that asked; the watch ends with it */
    uint8_t addr;
    uint32_t ref_seq; /* seq of the signalDigitalIO request */
    uint16_t unit;
    uint32_t bits;
    ls_CallbackType cb;
    uint64_t deadline_us; /* 0: no time-out */
    uint64_t timeout_us;  /* pollingTimeOut (0: none): a re-armed watch gets it again */
    uint64_t period_us;   /* 0: checked on every DIO change */
    uint64_t next_check_us;
    bool check_now;   /* first check at the next ls_dio_tick (after the answer went out) */
    bool await_clear; /* re-armed by an accepted RSVP: fires again only after the bits were not all set */
    uint32_t fired;   /* how often it fired */
} ls_dio_watch_t;

typedef struct {
    bool pending;
    uint64_t cycle0; /* control-loop cycle when the write was posted */
    uint64_t deadline_us;
    uint16_t unit;
    uint32_t on, off;
} ls_dio_write_wait_t;

typedef struct {
    ls_dio_watch_t watch[LS_MAX_DIO_WATCHES];
    uint32_t next_id;
    ls_dio_write_wait_t write_wait[LS_MAX_SUPERVISORS];
    uint32_t rsvp_replied, rsvp_timed_out;
    int32_t rsvp_last_code;
} ls_dio_state_t;

#endif
