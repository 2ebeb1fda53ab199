/* What the core sends, and the session lookups it needs: answers (with
 * each session's retransmission cache), notices (events and alarms, to one
 * session, to an address or to all) and the handlers' reply text. Every
 * downlink is encoded here, so only valid UTF-8 leaves the device
 * (docs/protocol.md "Strings"), and one whose queue is full is counted
 * (ls_core_t.tx_lost).
 *
 * Services layer of firmware/core (docs/architecture.md "Core layers"):
 * includes the types only; the handlers and the dispatcher call it. Comms
 * thread only; no allocation (the messages are encoded in ls_core_t's
 * scratch: core->down for answers, core->note for notices, so a handler may
 * notify while its answer is being built). */
#ifndef LS_SEND_H
#define LS_SEND_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_types.h"

/* Index of the connected session of `addr`, or LS_NO_SESSION. */
int ls_core_session_of(const ls_core_t *core, uint8_t addr);

/* The units of session `sup` (SI when sup < 0 or not connected). */
ls_units_t ls_core_units(const ls_core_t *core, int sup);

/* The units of the session that started the run (SI when it has ended):
 * the run's notices speak the units of the supervisor that started it. */
ls_units_t ls_core_run_units(const ls_core_t *core);

/* Set motion_state to STATUS st_motion `choice` (LANDSCAPE_STATUS_ST_MOTION_*_CHOICE):
 * the broadcast sends the code and getMotionControlState its DBC name, so the
 * two agree by construction. Dispatcher only. */
void ls_core_set_motion_state(ls_core_t *core, uint32_t choice);

/* The DBC's name of motion_state (getMotionControlState's motion_control_state). */
const char *ls_core_motion_state_name(const ls_core_t *core);

/* The st_motion choice of jogging with manual device `kind` (ls_manual_kind_t). */
uint32_t ls_core_manual_motion_state(int kind);

/* Whether motion_state says manual control is jogging. */
bool ls_core_motion_is_manual(const ls_core_t *core);

/* "stop", "stop_deactivate", "stop_deactivate_release" (the schema's names
 * in lower case without DISCONNECT_); "configured" for 0, NULL outside the enum. */
const char *ls_core_disconnect_action_name(ls_DisconnectAction a);

/* Fill call->res->ret_msg (printf-style) and return `code`: handlers end with
 * `return ls_reply(call, CODE, "...", ...)`. */
int32_t ls_reply(ls_call_t *call, int32_t code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Send a notice (event, alarm) to one session (sup >= 0) or to all (sup < 0:
 * LS_ALL_SESSIONS).
 * Its event id is one the schema declares (enum ls.EventId, sent by name), its
 * data "key=value" strings with the keys the schema lists for it. */
void ls_core_notify(ls_core_t *core, int sup, ls_NoticeKind kind, ls_EventId id, uint32_t ref_seq, bool final,
                    const char *const *data, size_t n_data);

/* Send a notice to the address `addr` about a request of its session
 * `epoch`: the notices of a run go to the session that started it. They are
 * numbered in that session's notice_seq, also once it has ended (the run
 * keeps the count: ls_send_session_ended). */
void ls_core_notify_to(ls_core_t *core, uint8_t addr, uint32_t epoch, ls_NoticeKind kind, ls_EventId id,
                       uint32_t ref_seq, bool final, const char *const *data, size_t n_data);

/* ls_core_notify_to for a path's auxiliary `event NAME`: the name the path
 * chose, which no schema can declare (ls.EventId AUX_NAMED_EVENT has its keys). */
void ls_core_notify_named_to(ls_core_t *core, uint8_t addr, uint32_t epoch, ls_NoticeKind kind, const char *name,
                             uint32_t ref_seq, bool final, const char *const *data, size_t n_data);

/* Session `s` ends (disconnect, heartbeat time-out, a new connect from its
 * address): the run it started, if any, keeps its notice numbering. */
void ls_send_session_ended(ls_core_t *core, const ls_session_t *s);

/* Answer a request that a handler deferred (LS_CALL_DEFERRED) for session
 * `sup`: the response carries the deferred request's seq and command id. */
void ls_core_finish_deferred(ls_core_t *core, int sup, int32_t code, const char *msg);

/* Start the answer in core->down (its encoding scratch) to request `seq` in
 * session epoch `epoch` (0: none); the caller sets the code, the text and the
 * result, then sends it (ls_send_response, or ls_send_bytes uncached). */
ls_Response *ls_send_new_response(ls_core_t *core, uint32_t seq, uint32_t epoch);

/* Start the notice in core->note (its encoding scratch): kind, event id,
 * ref_seq and up to the notice's capacity of `data` strings (each cut to the
 * field's size); the caller sets the rest (final, notice_seq, session_epoch,
 * the RSVP fields) and sends it. */
ls_Notice *ls_send_new_notice(ls_core_t *core, ls_NoticeKind kind, const char *event_id, uint32_t ref_seq,
                              const char *const *data, size_t n_data);

/* Encode `msg` into buf (its strings repaired to whole UTF-8 first): the
 * length, or 0 when it does not fit (bounded fields make that a bug). */
size_t ls_send_encode(ls_Downlink *msg, uint8_t *buf, size_t cap);

/* Queue `len` encoded bytes for the supervisor at `addr` (io.send_downlink);
 * a refusal is counted in tx_lost, never retried here. Signed first (the
 * MAC field appended in buf, `cap` bytes long: LS_DOWNLINK_MAX holds it)
 * with the key core->tx_sign names, by default the live signed session of
 * `addr`'s (docs/protocol.md "Security"). */
void ls_send_bytes(ls_core_t *core, uint8_t addr, uint8_t *buf, size_t len, size_t cap);

/* The device's policy: AUTH_UNSIGNED without keys (cfg.auth NULL). */
ls_AuthPolicy ls_core_policy(const ls_core_t *core);

/* Send the answer built in core->down to `addr`, and keep it as session
 * s's last answer (its retransmission cache; s NULL: not cached). An answer
 * that does not encode is replaced by CMD_ERR "internal: ...". */
void ls_send_response(ls_core_t *core, ls_session_t *s, uint8_t addr);

#endif
