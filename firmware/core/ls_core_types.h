/* The core's state: ls_core_t and everything it holds (sessions, settings,
 * RSVPs, logs, the run), and the call a handler gets. Types layer of
 * firmware/core (docs/architecture.md "Core layers"): only types, no
 * functions; the services, handlers and the dispatcher all include it.
 *
 * Comms thread only. All storage is static, inside ls_core_t. */
#ifndef LS_CORE_TYPES_H
#define LS_CORE_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_arm.h"
#include "hal/hal_dio.h"
#include "hal/hal_manual.h"
#include "landscape.pb.h"
#include "ls_auth.h"
#include "ls_cmd_table.h"
#include "ls_core_limits.h"
#include "ls_core_state.h"
#include "ls_motion.h"
#include "ls_robot_model.h"
#include "ls_units.h"

struct ls_control;

/* Why a run ended: the schema's enum MotionEnd, whose (ls.text) is the
 * `reason=` of its final notice and whose (ls.final_suffix) ends the
 * notice's event id (docs/protocol.md "Motion lifecycle"). */
typedef enum {
    LS_RUN_END_COMPLETE = ls_MotionEnd_END_COMPLETE,     /* <cmd>Complete (EVENT) */
    LS_RUN_END_ABORT = ls_MotionEnd_END_ABORT,           /* abortMotion */
    LS_RUN_END_DEACTIVATE = ls_MotionEnd_END_DEACTIVATE, /* deactivate */
    LS_RUN_END_FAULT = ls_MotionEnd_END_FAULT,           /* following error, IK, HAL, e-stop input, wait time-out */
    LS_RUN_END_EMERGENCY = ls_MotionEnd_END_EMERGENCY,   /* an EMERGENCY frame on the bus */
    LS_RUN_END_OWNER_LOST = ls_MotionEnd_END_OWNER_LOST, /* the owner's heartbeat stopped */
    LS_RUN_END_DISCONNECT = ls_MotionEnd_END_DISCONNECT, /* the owner sent disconnect */
    LS_RUN_END_AUX_FAILED = ls_MotionEnd_END_AUX_FAILED, /* a path auxiliary command failed */
    LS_RUN_END_RSVP_DECLINED = ls_MotionEnd_END_RSVP_DECLINED, /* the owner declined a path RSVP */
    LS_RUN_END_SHUTDOWN = ls_MotionEnd_END_SHUTDOWN,           /* landscaped stops (SIGTERM/SIGINT) */
    LS_RUN_END_COUNT = _ls_MotionEnd_ARRAYSIZE                 /* endings 0..LS_RUN_END_COUNT-1 */
} ls_run_end_t;

typedef struct {
    bool active;    /* started and its final notice not sent yet */
    bool react;     /* moveReact / comply (cmd_sensor.c), else a planned motion (cmd_move.c, cmd_path_program.c) */
    int sup;        /* session that started it */
    uint8_t addr;   /* its address: the final notice goes there */
    uint32_t epoch; /* its session epoch */
    /* That session's notice_seq once it has ended (disconnect, heartbeat,
     * a new connect): the run's later notices go on with its numbering, so a
     * client's gap check per session holds to the final notice. */
    uint32_t notice_seq;
    uint32_t ref_seq;
    const ls_cmd_finals_t *finals; /* its command's final notices (ls_cmd_table: ls_EventId_<command><ending>) */
    char point[LS_MOTION_NAME_LEN];
    int path;          /* index of the path queue it runs, LS_PATH_NONE for single moves */
    bool dry_run;      /* pathMove with number_of_cycles 0: its notices carry dry_run=true */
    bool stop_pending; /* stopMotion waits for the pause */
    int stop_sup;
    /* path auxiliary `wait` in progress */
    bool wait_active;
    uint16_t wait_unit;
    uint32_t wait_mask;
    uint64_t wait_deadline_us;
    char wait_text[LS_MOTION_AUX_LEN];
    int wait_point;
    /* path auxiliary `dio` posted, waiting for the loop to carry it out */
    bool dio_pending;
    bool dio_seen;
    int dio_point;
    uint64_t dio_cycle;
    /* moveReact / comply */
    bool comply;
    size_t sensor;
    bool length;
    uint8_t component;
    int32_t panic_code;
} ls_run_t;

/* A stop in progress that ends with the drives off (deactivate, fault, owner
 * loss, disconnect, shutdown). */
typedef struct {
    bool active;
    ls_run_end_t why;
    char text[LS_PB_FIELD_SIZE(ls_GetMotionControlStateRes, fault)]; /* the fault, or "": as the state query holds it */
    int answer_sup;   /* deferred deactivate to answer at the end, LS_NO_SESSION: none */
    bool keep_drives; /* owner lost with the action `stop`: pause, drop the motion, drives stay on (RESTING) */
    bool fast;        /* the stop at the model's maximum deceleration is posted: repeats post nothing more */
    bool owner_lost;  /* the disconnect handler runs it: the alarm ownerLost at the end */
    bool release;     /* owner lost: UNLOCKED at the end (else LOCKED, or RESTING with keep_drives) */
    ls_DisconnectAction lost_action;
    uint8_t lost_addr; /* owner lost: whose */
    char lost_why[24];
    uint64_t since_us;
    uint64_t start_cycle;  /* the loop's cycle when the stop was posted */
    uint64_t off_since_us; /* first turn the loop reported the drives off, 0: not yet */
} ls_halt_t;

/* How the core talks to the bus: implemented by the network layer (or a test). */
typedef struct {
    /* Queue one encoded ls.Downlink for the supervisor at `addr`. Returns
     * LS_OK, or a negative ls_err.h status (a full queue: LS_EAGAIN) when the
     * message is lost (the core counts it, tx_lost). */
    int (*send_downlink)(void *ctx, uint8_t addr, const uint8_t *buf, size_t len);
    /* Optional: the transport's counters as key=value lines (sendCommand status),
     * at most LS_TRANSPORT_DESCRIBE_MAX bytes with the NUL. */
    void (*describe)(void *ctx, char *buf, size_t cap);
    /* Optional: fill `len` bytes with unpredictable ones (the device's nonce of
     * a signed connect: docs/protocol.md "Security"); LS_OK or a negative
     * ls_err.h status. NULL: the device answers no challenge. */
    int (*random)(void *ctx, uint8_t *buf, size_t len);
    void *ctx;
} ls_core_io_t;

typedef struct {
    bool connected;
    uint8_t addr;
    char name[LS_PB_FIELD_SIZE(ls_ConnectReq, client_name)];
    uint64_t last_heard_us; /* the last HEARTBEAT carrying hb_token (or the connect) */
    uint64_t nonce;         /* ConnectReq.client_nonce: who this session is */
    uint32_t hb_token;      /* ConnectRes.heartbeat_token: what its heartbeats carry */
    uint32_t hb_refused;    /* heartbeats from its address without its token */
    uint32_t heartbeat_period_ms;
    uint32_t heartbeat_timeout_ms;         /* this session's time-out (ls_core_tick) */
    ls_units_t units;                      /* what this supervisor reads and writes in (setUnits) */
    ls_DisconnectAction disconnect_action; /* run when this session's owner is lost */
    /* retransmission cache: the last request's seq and its encoded response */
    bool have_last;
    bool last_pending; /* the last request is still running (deferred) */
    uint32_t last_seq;
    uint64_t last_req_hash; /* FNV-1a of the last request's bytes: a reused seq must carry the same request */
    pb_size_t last_tag;     /* the last request's command id */
    uint8_t last_resp[LS_DOWNLINK_MAX];
    size_t last_resp_len;
    uint32_t notice_seq;
    uint32_t epoch; /* session epoch: new at every connect (docs/protocol.md) */
    int link;       /* the link segment its connect came on: its frames on another are dropped (ls_net) */
    /* A signed session (docs/protocol.md "Security"): every message both ways
     * carries a MAC with `key`; its heartbeats a MAC over their full counter. */
    bool signed_session;
    ls_auth_session_key_t key;
    uint32_t hb_counter;   /* signed: the full counter of the last heartbeat taken */
    uint32_t auth_refused; /* messages from its address that did not verify, or were not newer */
    uint32_t executed;     /* requests executed (not answered from the cache) */
    pb_size_t pending_tag; /* command id of the deferred request (last_pending) */
} ls_session_t;

/* A session that ended, kept so that a request from its address names why it
 * has none (a supervisor that never sent a disconnect learns someone did). */
typedef struct {
    uint8_t addr;
    uint32_t epoch; /* 0: an empty entry */
    char why[24];   /* "disconnect requested", "heartbeat lost" */
} ls_session_end_t;

/* Settings of seed 3.2, always in SI (m, rad, s) inside the firmware; the
 * handlers convert from and to the units of the calling session
 * (ls_session_t.units, setUnits). */
typedef struct {
    double speed_pct;           /* PERCENT_SPEED, (0, 100] */
    double accel_pct;           /* PERCENT_ACCEL, (0, 100] */
    double linear_speed_m_s;    /* LINEAR_SPEED, Cartesian moves */
    double angular_speed_rad_s; /* ANGULAR_SPEED, Cartesian moves */
    double linear_accel_m_s2;
    double angular_accel_rad_s2;
    /* Which kind of setSpeed / setAcceleration call came last, per quantity:
     * true after PERCENT_*, false after LINEAR_* or ANGULAR_* (and at start).
     * It decides the limits of Cartesian moves (docs/protocol.md "Speed and
     * acceleration"). */
    bool cart_speed_from_pct;
    bool cart_accel_from_pct;
    double tool_offset[6]; /* flange -> tool tip: x y z roll pitch yaw */
    double world_frame[6]; /* base -> world: x y z roll pitch yaw */
} ls_settings_t;

struct ls_core;
/* Outcome of an RSVP: the supervisor's ret_code (>= 0 accept, < 0 decline),
 * or timed_out with the default taken. Returns the action the device took
 * (a static string: it goes into the RsvpAck and the event log). */
typedef const char *(*ls_rsvp_done_fn)(struct ls_core *core, void *ctx, int32_t ret_code, bool timed_out,
                                       uint64_t now_us);

typedef struct {
    bool used;
    uint32_t id;
    uint8_t addr;
    uint32_t ref_seq; /* the request that armed it */
    uint32_t epoch;   /* that request's session epoch */
    uint64_t deadline_us;
    ls_rsvp_done_fn done;
    void *ctx;
    char event_id[LS_PB_FIELD_SIZE(ls_Notice, event_id)];
    char default_action[LS_PB_FIELD_SIZE(ls_RsvpAck, action)]; /* what the ack names when it times out */
} ls_rsvp_t;

/* An RSVP that ended (answered or timed out): a reply that comes later is
 * refused naming what happened. */
typedef struct {
    uint32_t id;
    uint8_t addr;
    bool timed_out;
    uint32_t ref_seq, epoch;
    char action[LS_PB_FIELD_SIZE(ls_RsvpAck, action)];
} ls_rsvp_ended_t;

typedef struct {
    uint64_t at_us;
    char text[160];
} ls_event_entry_t;

typedef struct {
    uint64_t at_us;
    char text[80];
} ls_fault_entry_t;

/* The alarm rate limit's window (LS_ALARM_WINDOW_MS). */
typedef struct {
    bool open;
    uint64_t since_us;   /* start of the window */
    char text[80];       /* the alarm whose repeats it counts */
    uint32_t suppressed; /* repeats within the window */
} ls_alarm_window_t;

typedef struct {
    const char *device_name;
    const char *firmware_version;
    uint8_t node_addr;
    uint8_t joint_count;
    uint32_t heartbeat_timeout_ms;         /* the least time-out of a session (docs/protocol.md "Liveness") */
    ls_DisconnectAction disconnect_action; /* the widest owner-loss action; 0: stop_deactivate_release */
    /* The supervisor keys and the policy (docs/protocol.md "Security"), owned
     * by the caller (landscaped keeps them out of core dumps). NULL: no keys,
     * the policy unsigned. */
    ls_auth_t *auth;
} ls_core_config_t;

/* Actions the core asks of the rest of the firmware (drives, motion). */
typedef struct {
    /* Enable or disable the drives; returns 0 when done, a negative HAL
     * status, or (on) 1 when enabling has started and its end comes as a
     * loop event (LS_CEV_ENABLED or LS_CEV_ENABLE_FAILED): activate then
     * answers when it comes. */
    int (*enable_drives)(void *ctx, bool on);
    /* Stop any motion along its path at the configured deceleration (pause). */
    void (*stop_motion)(void *ctx);
    /* Optional: stop along the path at the model's maximum deceleration, then
     * drives off (faults, emergency, shutdown). NULL: enable_drives(false),
     * which stops at the configured deceleration first. */
    void (*halt)(void *ctx);
    /* Optional, for sendCommand: the control loop's real-time statistics and
     * the running configuration, as key=value lines. */
    void (*describe_rt)(void *ctx, char *buf, size_t cap);
    void (*describe_config)(void *ctx, char *buf, size_t cap);
    /* Optional: a warning for the device's log (a command the control loop refused). */
    void (*log_warn)(void *ctx, const char *line);
    void *ctx;
} ls_core_actions_t;

typedef struct ls_core {
    ls_core_config_t cfg;
    ls_core_io_t io;
    ls_core_actions_t act;
    /* devices and the control loop (NULL when not composed) */
    const ls_robot_model_t *model;
    struct ls_control *ctl;
    const hal_sensor_t *sensors;
    size_t n_sensors;
    hal_tool_t *tool;
    /* The manual devices by ls_manual_kind_t (NULL: not composed) and their
     * gates' override steps and staleness; manualControl adds the enabling
     * switch (the teach pendant's). */
    hal_manual_t *manual[LS_MANUAL_KINDS];
    ls_manual_config_t manual_gate[LS_MANUAL_KINDS];
    hal_dio_unit_info_t dio_info[LS_CORE_MAX_DIO_UNITS]; /* input/output masks per unit */
    uint16_t dio_units;
    ls_dio_state_t dio; /* signalDigitalIO watches, setDigitalIO in flight */
    ls_settings_t settings;
    ls_rsvp_t rsvp[LS_MAX_RSVP];
    uint32_t rsvp_next_id;
    ls_rsvp_ended_t rsvp_ended[LS_RSVP_ENDED_LEN];
    uint32_t rsvp_ended_count;
    ls_event_entry_t event_log[LS_EVENT_LOG_LEN]; /* sendCommand events */
    uint32_t event_log_count;
    /* The owner was lost with a disconnect action that keeps the lock
     * (stop, stop_deactivate): the device stays locked for that address
     * until it connects again and is the owner once more. */
    bool held;
    uint8_t held_addr;
    char held_name[LS_PB_FIELD_SIZE(ls_ConnectReq, client_name)]; /* the session name, whole */
    ls_DisconnectAction held_action;
    ls_State state;
    int owner;              /* index in sessions[], LS_NO_SESSION when unlocked */
    int activating;         /* the session whose activate waits for the drives (LS_CEV_ENABLED), LS_NO_SESSION: none */
    int homing;             /* the session whose sendCommand home waits (LS_CEV_HOMED), LS_NO_SESSION: none */
    uint32_t homing_joints; /* the joints it homes (bit j: joint j + 1) */
    ls_session_t sessions[LS_MAX_SUPERVISORS];
    ls_session_end_t ended[LS_MAX_SUPERVISORS]; /* the latest sessions that ended, a ring */
    uint8_t ended_next;
    char fault[LS_PB_FIELD_SIZE(ls_GetMotionControlStateRes, fault)]; /* latched fault, empty when none */
    /* seed 3.3.1 motionControlState (docs/state-machine.md) as the DBC's STATUS
     * st_motion code (LANDSCAPE_STATUS_ST_MOTION_*_CHOICE): the query sends its
     * name, the broadcast the code, so the two cannot disagree. */
    uint8_t motion_state;
    ls_run_t run;                                 /* the started motion (ls_run.h) */
    ls_halt_t halt;                               /* a stop that ends with the drives off (ls_run.h) */
    uint32_t epoch_next;                          /* the next session epoch */
    ls_motion_cmds_t motion;                      /* path queues, the program being run, getTagId */
    ls_sensor_cmds_t sensor;                      /* manual control */
    ls_tool_cmds_t tool_cmds;                     /* the end effector */
    ls_fault_entry_t fault_log[LS_FAULT_LOG_LEN]; /* the first LS_FAULT_LOG_FIRST, then a ring */
    uint32_t fault_log_count;                     /* entries ever logged */
    ls_alarm_window_t alarm_window;
    uint32_t alarms_suppressed; /* repeats not sent (LS_ALARM_WINDOW_MS) */
    uint32_t emergency_frames;  /* EMERGENCY frames taken (each one stops) */
    uint32_t rx_malformed;      /* uplinks that did not decode */
    uint32_t tx_lost;           /* downlinks the network could not queue */
    uint32_t sessions_dropped;  /* heartbeat time-outs */
    uint32_t hb_refused;        /* heartbeats that did not carry their session's token */
    uint32_t connects_refused;  /* connects from an address in use by another client */
    /* Security (docs/protocol.md "Security"): messages from a signed session's
     * address that did not verify, or whose seq was not newer (dropped
     * unanswered); connects refused for their signature or the policy;
     * functional frames that needed a signature; stopMotion taken from anyone. */
    uint32_t auth_refused;
    uint32_t auth_stale;
    uint32_t auth_connects_refused;
    uint32_t functional_refused;
    uint32_t anonymous_stops;
    /* Which key signs the downlinks being sent (ls_send_bytes): `set` false, or
     * to another address than `addr`, the live signed session of their address
     * (or none); else `key` (NULL: none) with `epoch`: the answer to a
     * challenge, a connect, or the disconnect that ended a signed session. */
    struct {
        bool set;
        uint8_t addr;
        const ls_auth_session_key_t *key;
        uint32_t epoch;
    } tx_sign;
    /* the session key of the connect or challenge being answered, or of the
     * signed session a disconnect ends (its answer is still signed) */
    ls_auth_session_key_t connect_key;
    /* scratch (kept here, not on the stack: the messages are large) */
    ls_Uplink up;
    ls_Downlink down; /* the response being built (handlers write into it) */
    uint8_t enc[LS_DOWNLINK_MAX];
    ls_Downlink note; /* notices: separate, so a handler may notify while answering */
    uint8_t note_enc[LS_DOWNLINK_MAX];
} ls_core_t;

/* One command being dispatched. */
typedef struct ls_call {
    ls_core_t *core;
    int sup; /* index of the calling session */
    const ls_Request *req;
    ls_Response *res;
    uint64_t now_us;
    int link;                                 /* the link segment it came on */
    const ls_auth_session_key_t *connect_key; /* a connect verified with this key (NULL: unsigned) */
} ls_call_t;

#endif
