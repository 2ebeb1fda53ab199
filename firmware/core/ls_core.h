/* The controller core: supervisor sessions, ownership, the state machine of
 * docs/state-machine.md, the command dispatcher and the seed's return codes.
 * This header is the core's interface to the rest of the firmware (the app,
 * the network layer, the footprint build, the fuzzers): the top layer's
 * functions below, and through ls_core_services.h the types and services.
 * The core's own layers are in docs/architecture.md "Core layers".
 *
 * Runs in the comms thread only (never in the control loop). Time is passed
 * in. All storage is static, inside ls_core_t (ls_core_types.h). */
#ifndef LS_CORE_H
#define LS_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_services.h"


void ls_core_init(ls_core_t *core, const ls_core_config_t *cfg, const ls_core_io_t *io, const ls_core_actions_t *act);

/* Set the drive, stop and halt actions of `act` (and its ctx) to commands
 * posted on the control loop `ctl`'s command ring (ls_control_post; a full
 * ring refuses the drives with LS_EAGAIN). Every build that composes the core
 * with the control loop (the app, the footprint build, the session fuzzer)
 * takes them from here; the optional describe and log actions stay the
 * caller's. Init only. */
void ls_core_actions_for_loop(ls_core_actions_t *act, struct ls_control *ctl);

/* One ISO-TP message from the supervisor at `addr` (an encoded ls.Uplink)
 * that came on link segment `link` (a connect binds its session to it). From
 * the address of a signed session, a message that does not carry a valid MAC
 * (or a request whose seq is not newer) is dropped unanswered and counted;
 * nothing of the session changes (docs/protocol.md "Security"). */
void ls_core_on_uplink(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len, uint64_t now_us);

/* One functional single frame's payload from `addr` on `link` (docs/protocol.md
 * "Functional requests"). Where a signature is needed (the policy is signed,
 * or `addr` has a signed session) a frame cannot carry one: a stopMotion then
 * pauses the motion under way whoever sent it (like an EMERGENCY frame,
 * anyone may stop the arm), unanswered, touching no session; anything else is
 * dropped and counted. Elsewhere it runs like ls_core_on_uplink. */
void ls_core_on_functional(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len, uint64_t now_us);

/* A supervisor's HEARTBEAT frame from `addr`: its hb_counter, hb_period_ms
 * and hb_token. It keeps the session of `addr` only when `token` is that
 * session's heartbeat token, or in a signed session the MAC of the frame's
 * full counter (ls_auth_heartbeat_counter: newer than the last one taken);
 * else it is counted (hb_refused) and changes nothing. A heartbeat from an
 * address without a session here (a supervisor of another device) is
 * ignored. O(LS_MAX_SUPERVISORS) and one HMAC, no allocation. */
void ls_core_on_heartbeat(ls_core_t *core, uint8_t addr, uint8_t counter, uint16_t period_ms, uint32_t token,
                          uint64_t now_us);

/* The link segment the session of `addr` is bound to, or LS_NO_SESSION when
 * the address has none: the network layer drops a frame from `addr` that
 * comes on another one (docs/protocol.md "Security"). O(LS_MAX_SUPERVISORS). */
int ls_core_session_link(const ls_core_t *core, uint8_t addr);

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


/* When ls_core_tick next has work, for an event-driven comms thread that
 * otherwise sleeps until a frame or a control loop event (ls_control's
 * notify hook) arrives. `now_us`: the time of the last ls_core_tick. The
 * earliest of: an RSVP's time-out, the end of an alarm window, a session's
 * heartbeat time-out, a DIO watch's check, period or time-out (0: at once),
 * and now_us + LS_CORE_SAMPLE_US while something samples the snapshot.
 * UINT64_MAX: nothing is timed. O(sessions + RSVPs + watches), no clock
 * read, no allocation. */
uint64_t ls_core_next_deadline_us(const ls_core_t *core, uint64_t now_us);

#endif
