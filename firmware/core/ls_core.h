/* The controller core: supervisor sessions, ownership, the state machine of
 * docs/state-machine.md, the command dispatcher and the seed's return codes.
 *
 * Runs in the comms thread only (never in the control loop). Time is passed
 * in. All storage is static, inside ls_core_t. */
#ifndef LS_CORE_H
#define LS_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_arm.h"
#include "hal/hal_dio.h"
#include "hal/hal_manual.h"
#include "landscape.pb.h"
#include "ls_cmd_table.h"
#include "ls_core_state.h"
#include "ls_math.h"
#include "ls_robot_model.h"
#include "ls_run.h"
#include "ls_units.h"

struct ls_control;

/* Sessions at once (describe: max_sessions). Each keeps its last answer
 * (LS_DOWNLINK_MAX) and needs an ISO-TP peer (ls_net.h). Per profile
 * (CMakeLists.txt LS_PROFILE): linux 4, mcu 2 (an owner and an observer). */
#if LS_PROFILE_MCU
#define LS_MAX_SUPERVISORS 2
#else
#define LS_MAX_SUPERVISORS 4
#endif
/* The size nanopb gives `field` of message type `msg` (protocol/landscape.options):
 * the core's copies of a wire string are sized by it, never by a second number. */
#define LS_PB_FIELD_SIZE(msg, field) sizeof(((msg *)0)->field)
#define LS_DOWNLINK_MAX ls_Downlink_size
#define LS_UPLINK_MAX ((size_t)ls_IsotpParam_ISOTP_MAX_MESSAGE_BYTES) /* one ISO-TP message */
#define LS_CALL_DEFERRED INT32_MIN                                    /* a handler will answer later */
#define LS_NO_SESSION (-1)   /* an index of ls_core_t.sessions that names none (owner: unlocked) */
#define LS_ALL_SESSIONS (-2) /* ls_core_notify: to every session */
/* The fault log keeps its first LS_FAULT_LOG_FIRST entries (the start of a
 * cascade) and a ring of the latest LS_FAULT_LOG_LATEST; the entries in
 * between are dropped and counted (sendCommand faults). */
#define LS_FAULT_LOG_FIRST 4
#define LS_FAULT_LOG_LATEST 12
#define LS_FAULT_LOG_LEN (LS_FAULT_LOG_FIRST + LS_FAULT_LOG_LATEST)
/* Alarm rate limit (docs/protocol.md "Budgets under floods"): a fault (an
 * EMERGENCY frame included) always latches and stops at once; its alarm and
 * fault-log entry go out at once too, but repeats of the same text within
 * LS_ALARM_WINDOW_MS are counted instead, and at the end of each window with
 * repeats one alarm alarmsSuppressed says how many (and is logged).
 * The window runs on while the repeats go on. */
#define LS_ALARM_WINDOW_MS 1000u
#define LS_MAX_RSVP 8
#define LS_RSVP_ENDED_LEN 8 /* ended RSVPs remembered, so a late reply is told apart from an unknown one */
#define LS_EVENT_LOG_LEN 16
/* Liveness (docs/protocol.md "Liveness"): a session ends when no HEARTBEAT
 * came for max(the configured time-out, LS_HB_MISSED_MAX heartbeat periods).
 * A supervisor states its period at connect, within these bounds (0: not
 * stated, the configured time-out alone applies). */
#define LS_HB_MISSED_MAX 5u
/* A new session counts as heard for this long after its connect: the answer
 * carrying its heartbeat token may take the network layer's transfers of a
 * downlink (ls_net.h, LS_NET_TX_TRIES x N_Bs of 1 s) to get through. */
#define LS_CONNECT_ANSWER_GRACE_US 3000000u
#define LS_HB_PERIOD_MIN_MS ((uint32_t)ls_HeartbeatPeriod_HEARTBEAT_PERIOD_MIN_MS) /* the schema's */
#define LS_HB_PERIOD_MAX_MS ((uint32_t)ls_HeartbeatPeriod_HEARTBEAT_PERIOD_MAX_MS)
/* Identity (docs/protocol.md "Identity"): a session's heartbeat token is
 * nonzero and fits the DBC's 24-bit HEARTBEAT.hb_token (protocol/landscape.dbc). */
#define LS_HB_TOKEN_MASK 0xFFFFFFu
#define LS_CORE_MAX_DIO_UNITS 4
#define LS_MAX_DIO_WATCHES 8
#define LS_PATH_MAX_CYCLES 1000000 /* pathMove number_of_cycles */

/* How the core talks to the bus: implemented by the network layer (or a test). */
typedef struct {
    /* Queue one encoded ls.Downlink for the supervisor at `addr`. Returns
     * LS_OK, or a negative ls_err.h status (a full queue: LS_EAGAIN) when the
     * message is lost (the core counts it, tx_lost). */
    int (*send_downlink)(void *ctx, uint8_t addr, const uint8_t *buf, size_t len);
    /* Optional: the transport's counters as key=value lines (sendCommand status). */
    void (*describe)(void *ctx, char *buf, size_t cap);
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
    uint32_t epoch;        /* session epoch: new at every connect (docs/protocol.md) */
    uint32_t executed;     /* requests executed (not answered from the cache) */
    pb_size_t pending_tag; /* command id of the deferred request (last_pending) */
} ls_session_t;

/* Ranges of numeric parameters (docs/protocol.md "Limits"; one home):
 * a rate (setSpeed, setAcceleration, a move's or a path point's speed) is 0
 * where 0 means "the current setting", or at least LS_RATE_MIN_FRACTION of its
 * maximum: a smaller one (a subnormal such as 1e-300 included) would plan a
 * motion that never ends. Tool offsets and world frames: each translation
 * component within the model's reach (ls_robot_model_reach_m), each angle
 * within +-LS_FRAME_ANGLE_MAX_RAD. Names of points and paths are not empty. */
#define LS_RATE_MIN_FRACTION 0.001
#define LS_RATE_MIN_PCT (100.0 * LS_RATE_MIN_FRACTION)
#define LS_FRAME_ANGLE_MAX_RAD (2.0 * LS_PI)

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

typedef struct {
    const char *device_name;
    const char *firmware_version;
    uint8_t node_addr;
    uint8_t joint_count;
    uint32_t heartbeat_timeout_ms;         /* the least time-out of a session (docs/protocol.md "Liveness") */
    ls_DisconnectAction disconnect_action; /* the widest owner-loss action; 0: stop_deactivate_release */
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
    int owner;      /* index in sessions[], LS_NO_SESSION when unlocked */
    int activating; /* the session whose activate waits for the drives (LS_CEV_ENABLED), LS_NO_SESSION: none */
    ls_session_t sessions[LS_MAX_SUPERVISORS];
    char fault[LS_PB_FIELD_SIZE(ls_GetMotionControlStateRes, fault)]; /* latched fault, empty when none */
    /* seed 3.3.1 motionControlState (docs/state-machine.md) */
    char motion_state[LS_PB_FIELD_SIZE(ls_GetMotionControlStateRes, motion_control_state)];
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
} ls_call_t;

void ls_core_init(ls_core_t *core, const ls_core_config_t *cfg, const ls_core_io_t *io, const ls_core_actions_t *act);

/* Set the drive, stop and halt actions of `act` (and its ctx) to commands
 * posted on the control loop `ctl`'s command ring (ls_control_post; a full
 * ring refuses the drives with LS_EAGAIN). Every build that composes the core
 * with the control loop (the app, the footprint build, the session fuzzer)
 * takes them from here; the optional describe and log actions stay the
 * caller's. Init only. */
void ls_core_actions_for_loop(ls_core_actions_t *act, struct ls_control *ctl);

/* One ISO-TP message from the supervisor at `addr` (an encoded ls.Uplink). */
void ls_core_on_uplink(ls_core_t *core, uint8_t addr, const uint8_t *buf, size_t len, uint64_t now_us);

/* A supervisor's HEARTBEAT frame from `addr` carrying `token` (hb_token).
 * It keeps the session of `addr` only when `token` is that session's
 * heartbeat token; else it is counted (hb_refused) and changes nothing. A
 * heartbeat from an address without a session here (a supervisor of another
 * device) is ignored. O(LS_MAX_SUPERVISORS), no allocation. */
void ls_core_on_heartbeat(ls_core_t *core, uint8_t addr, uint32_t token, uint64_t now_us);

/* Everything the core does with time, once every comms loop turn: it takes
 * the control loop's events (the one route by which they reach the core),
 * times out RSVPs, drops sessions whose heartbeat stopped, and advances
 * the halt (ls_run_tick), the DIO watches (ls_dio_tick) and a path's
 * auxiliary commands (ls_core_motion_tick). */
void ls_core_tick(ls_core_t *core, uint64_t now_us);

/* The control loop's events posted so far, taken now: what ls_core_tick
 * does first. A request takes them before it is dispatched, so that it is
 * answered from the state as of its arrival (a query that follows a broadcast
 * showing the arm paused never reads MOVING), and a status report takes
 * them after its snapshot (the loop posts a cycle's events before it
 * publishes the cycle's snapshot, so the report's state and its motion agree). */
void ls_core_take_loop_events(ls_core_t *core, uint64_t now_us);

/* While the core follows the control loop's state by sampling its
 * snapshot (a halt coming to rest, a DIO write taking effect, a path's
 * `wait` for inputs), it is ticked this often. */
#define LS_CORE_SAMPLE_US 1000u

/* When ls_core_tick next has work, for an event-driven comms thread that
 * otherwise sleeps until a frame or a control loop event (ls_control's
 * notify hook) arrives. `now_us`: the time of the last ls_core_tick. The
 * earliest of: an RSVP's time-out, the end of an alarm window, a session's
 * heartbeat time-out, a DIO watch's check, period or time-out (0: at once),
 * and now_us + LS_CORE_SAMPLE_US while something samples the snapshot.
 * UINT64_MAX: nothing is timed. O(sessions + RSVPs + watches), no clock
 * read, no allocation. */
uint64_t ls_core_next_deadline_us(const ls_core_t *core, uint64_t now_us);

/* Send a notice (event, alarm) to one session (sup >= 0) or to all (sup < 0:
 * LS_ALL_SESSIONS).
 * Its event id is one the schema declares (enum ls.EventId, sent by name), its
 * data "key=value" strings with the keys the schema lists for it. */
void ls_core_notify(ls_core_t *core, int sup, ls_NoticeKind kind, ls_EventId id, uint32_t ref_seq, bool final,
                    const char *const *data, size_t n_data);

/* Send a notice to the session at `addr` (if any) carrying session epoch
 * `epoch`: the notices of a run go to the session that started it. */
void ls_core_notify_to(ls_core_t *core, uint8_t addr, uint32_t epoch, ls_NoticeKind kind, ls_EventId id,
                       uint32_t ref_seq, bool final, const char *const *data, size_t n_data);

/* ls_core_notify_to for a path's auxiliary `event NAME`: the name the path
 * chose, which no schema can declare (ls.EventId AUX_NAMED_EVENT has its keys). */
void ls_core_notify_named_to(ls_core_t *core, uint8_t addr, uint32_t epoch, ls_NoticeKind kind, const char *name,
                             uint32_t ref_seq, bool final, const char *const *data, size_t n_data);

/* Latch a fault: record it, raise the alarm `fault` to everyone, stop a
 * motion along its path at the model's maximum deceleration, then drives off
 * (ACTIVE -> LOCKED once they are off; the motion's final notice then). */
void ls_core_fault(ls_core_t *core, const char *text, uint64_t now_us);
/* The control loop's answer to the drives' enable (LS_CEV_ENABLED with
 * `failure` NULL, LS_CEV_ENABLE_FAILED with its text): finishes the
 * deferred activate of core->activating (RESTING, or refused naming the
 * joint and what its drive said); drives that came on for a session that
 * ended or lost the lock are switched off again. Comms thread. */
void ls_core_on_enable_result(ls_core_t *core, const char *failure, uint64_t now_us);
/* The same for an EMERGENCY frame on the bus (reason=emergency). Repeats of
 * the alarm within LS_ALARM_WINDOW_MS are counted, not sent; the stop is
 * never delayed. */
void ls_core_emergency(ls_core_t *core, uint64_t now_us);
/* Append to the fault log (the first LS_FAULT_LOG_FIRST entries stay). */
void ls_core_log_fault(ls_core_t *core, uint64_t now_us, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* The fault log's entry k (0 = oldest kept), NULL past the end; *n_kept and
 * *dropped (entries between the first and the latest that were overwritten)
 * when not NULL. */
const ls_fault_entry_t *ls_core_fault_entry(const ls_core_t *core, uint32_t k, uint32_t *n_kept, uint32_t *dropped);
/* The alarm ownerLost to everyone and its fault-log entry naming the
 * disconnect action taken (ls_run.c calls it when the owner's motion has
 * stopped). */
void ls_core_owner_lost_alarm(ls_core_t *core, uint8_t addr, const char *why, ls_DisconnectAction action,
                              uint64_t now_us);

/* "stop", "stop_deactivate", "stop_deactivate_release" (the schema's names
 * in lower case without DISCONNECT_); "configured" for 0, NULL outside the enum. */
const char *ls_core_disconnect_action_name(ls_DisconnectAction a);

/* Append a line to the event log (sendCommand events): RSVP outcomes with
 * their data. */
void ls_core_log_event(ls_core_t *core, uint64_t now_us, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Set motion_state (getMotionControlState's motion_control_state) to the DBC's
 * name of STATUS st_motion `choice` (LANDSCAPE_STATUS_ST_MOTION_*_CHOICE), so the
 * text and the telemetry code have one home. Dispatcher only. */
void ls_core_set_motion_state(ls_core_t *core, uint32_t choice);

/* The units of session `sup` (SI when sup < 0 or not connected). */
ls_units_t ls_core_units(const ls_core_t *core, int sup);
/* The units of the session that started the run (SI when it has ended):
 * the run's notices speak the units of the supervisor that started it. */
ls_units_t ls_core_run_units(const ls_core_t *core);

/* Answer a request that a handler deferred (LS_CALL_DEFERRED) for session
 * `sup`: the response carries the deferred request's seq and command id. */
void ls_core_finish_deferred(ls_core_t *core, int sup, int32_t code, const char *msg);

/* Send an RSVP notice to session `sup` about the request `ref_seq` (of
 * that session: the notice carries its seq and epoch) and wait (without
 * blocking) for the reply; `done` runs once: with the reply's ret_code, or
 * after timeout_ms with timed_out = true (then the caller takes
 * `default_action`, which the notice announces). The reply is answered with
 * an RsvpAck naming the action `done` returned, and logged with its data.
 * Returns the rsvp id (> 0), LS_EINVAL (`sup` has no session, `done` is NULL,
 * the notice does not encode) or LS_ENOSPC (LS_MAX_RSVP are waiting). */
int32_t ls_core_rsvp(ls_core_t *core, int sup, uint32_t ref_seq, ls_NoticeKind kind, const char *event_id,
                     const char *const *data, size_t n_data, uint32_t timeout_ms, const char *default_action,
                     ls_rsvp_done_fn done, void *ctx, uint64_t now_us);

/* Index of the connected session of `addr`, or LS_NO_SESSION. */
int ls_core_session_of(const ls_core_t *core, uint8_t addr);

/* Fill call->res->ret_msg (printf-style) and return `code`: handlers end with
 * `return ls_reply(call, CODE, "...", ...)`. */
int32_t ls_reply(ls_call_t *call, int32_t code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

#endif
