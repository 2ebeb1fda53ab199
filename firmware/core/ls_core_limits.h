/* The core's limits and sentinels: table sizes, time-outs, ranges. Types
 * layer of firmware/core (docs/architecture.md "Core layers"): only macros,
 * no functions; every other core header may include it. */
#ifndef LS_CORE_LIMITS_H
#define LS_CORE_LIMITS_H

#include <stddef.h>
#include <stdint.h>

#include "landscape.pb.h"
#include "ls_math.h"

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
/* The most the transport's counters take in sendCommand status (ls_core_io_t
 * describe), its NUL included: the status answer is sized to hold them after
 * every session and watch at their longest, so it is never cut
 * (tests/unit/net checks the network layer's text, tests/unit/core the whole). */
#define LS_TRANSPORT_DESCRIBE_MAX 1024u
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
/* A Cartesian target or offset of a move, an arc or a path point: each
 * translation component within LS_POSE_REACH_FACTOR x the model's reach
 * (two reaches span the workspace from any point of it, a world frame
 * included), each angle within +-LS_FRAME_ANGLE_MAX_RAD; a finite value
 * beyond is refused naming it before any planning (none may turn the tool to
 * an orientation of its own, nor reach the planner as a NaN). */
#define LS_POSE_REACH_FACTOR 2.0

/* While the core follows the control loop's state by sampling its
 * snapshot (a halt coming to rest, a DIO write taking effect, a path's
 * `wait` for inputs), it is ticked this often. */
#define LS_CORE_SAMPLE_US 1000u

#endif
