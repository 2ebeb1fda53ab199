/* Sessions (docs/protocol.md "Sessions", "Liveness", "Identity"): connect
 * and disconnect, the only commands that create or end one, the
 * supervisors' heartbeats, their time-out, and the disconnect handler
 * that runs when an owner is lost (seed 2.2). Top layer of firmware/core
 * (docs/architecture.md "Core layers"), private to it: the dispatcher and
 * the tick call these. Comms thread only; no allocation,
 * O(LS_MAX_SUPERVISORS). */
#ifndef LS_SESSION_H
#define LS_SESSION_H

#include <stdint.h>

#include "ls_core.h"

/* connect from `addr` (the dispatcher has checked its presence rules):
 * checks the protocol version, schema hash, heartbeat period and disconnect
 * action, then creates or renews the session (call->sup is set to it; a new
 * epoch and heartbeat token) and fills the ConnectRes. Returns the ret_code;
 * on a refusal nothing of any session changes. */
int32_t ls_session_connect(ls_core_t *core, uint8_t addr, ls_call_t *call);

/* challenge from `addr` (docs/protocol.md "Security"): draws the device's
 * nonce (io.random) for the key named, remembers the challenge for one
 * connect from `addr` (ls_auth_challenge_put) and fills the ChallengeRes,
 * signed with the session key the connect will use (core->tx_sign). Returns
 * the ret_code; changes no session. */
int32_t ls_session_challenge(ls_core_t *core, uint8_t addr, ls_call_t *call);

/* End session i (disconnect, heartbeat lost: `why`), running the disconnect
 * handler when it owned the device: stop, deactivate or release as its
 * action says (a motion stops first, ls_run_halt_owner_lost), a kept lock
 * waits for the owner's address. IDLE when nobody is left. */
void ls_session_drop(ls_core_t *core, int i, const char *why, uint64_t now_us);

/* Drop every session whose heartbeat stopped (heartbeat_timeout_ms);
 * counted in sessions_dropped. Every comms loop turn (ls_core_tick). */
void ls_session_tick(ls_core_t *core, uint64_t now_us);

#endif
