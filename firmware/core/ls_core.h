/* The controller core: supervisor sessions, ownership, the state machine of
 * docs/state-machine.md, the command dispatcher and the seed's return codes.
 *
 * Runs in the comms thread only (never in the control loop). Time is passed
 * in. All storage is static, inside ls_core_t (ls_core_types.h). */
#ifndef LS_CORE_H
#define LS_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_types.h"
#include "ls_run.h"
#include "ls_units.h"


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
