/* The life of a started motion: one owner in the core (docs/state-machine.md,
 * "Motion lifecycle").
 *
 * Every request answered CMD_STARTED_OK (moveAbsolute, moveRelative, moveArc,
 * pathMove, moveReact, comply) becomes the one run of ls_core_t.run. The run
 * ends exactly once, with exactly one final notice carrying the request's
 * ref_seq and session epoch, whatever ends it (ls_run_end_t). Endings that
 * stop the arm first (deactivate, faults, owner loss, disconnect, shutdown)
 * go through a halt: the stop is posted to the control loop, the core stays
 * MOVING/PAUSED ("robot_stopping") until the loop reports the arm at rest
 * with the drives off, then the final notice goes out, the state changes
 * (LOCKED, UNLOCKED) and a deferred deactivate is answered.
 *
 * Comms thread only. No allocation. */
#ifndef LS_RUN_H
#define LS_RUN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "landscape.pb.h"
#include "ls_core_types.h"

struct ls_core;
struct ls_call;

/* The ending's reason= text and its final notice's suffix ("Complete",
 * "Failed" or "Aborted"): the schema's, generated (ls_cmd_table.h). */
const char *ls_run_end_name(ls_run_end_t why);
const char *ls_run_end_suffix(ls_run_end_t why);

/* Take the run for the request being answered (call): its final notices are
 * its command's (the schema's, ls_cmd_desc_t.finals); ls_core_t.state becomes
 * MOVING and motion_state running_trajectory. */
void ls_run_begin(struct ls_core *core, const struct ls_call *call, bool react, const char *point, int path);

/* Send the run's one final notice now and close it (no-op when no run).
 * extra: data strings after `point=` and `reason=` (e.g. joints=, fault=). */
void ls_run_finish(struct ls_core *core, ls_run_end_t why, const char *const *extra, size_t n_extra);

/* Start a halt: post the stop (fast: the model's maximum deceleration, else
 * the configured one), keep the state until the loop reports the arm at rest
 * with the drives off. answer_sup: a deactivate to answer then (LS_NO_SESSION: none).
 * A second halt while one runs can only make it faster and change the
 * reason to a fault. */
void ls_run_halt(struct ls_core *core, ls_run_end_t why, const char *text, bool fast, int answer_sup, uint64_t now_us);

/* The disconnect handler's stop (owner lost or disconnected): as
 * ls_run_halt at the configured deceleration; keep_drives (action `stop`):
 * pause along the path and drop the motion with the drives on. A halt
 * already under way goes on as it is. The caller sets owner_lost, release,
 * lost_* afterwards. */
void ls_run_halt_owner_lost(struct ls_core *core, ls_run_end_t why, bool keep_drives, uint64_t now_us);

/* Every comms loop turn: finish a halt once the arm is at rest with the
 * drives off (with keep_drives: at rest, paused). */
void ls_run_tick(struct ls_core *core, uint64_t now_us);

/* A halt that has not reached rest with the drives off after this long ends
 * anyway (the notices must not wait for ever on a broken loop). */
#define LS_RUN_HALT_MAX_US 5000000u
/* The shutdown's budget, in one place (docs/reliability.md "Signals"):
 * landscaped waits at most LS_RUN_SHUTDOWN_STOP_MAX_US for the halt (its own
 * bound and a second of slack; in practice the slowest joint's category-1
 * stop, under 1 s), then keeps the links up LS_RUN_SHUTDOWN_FLUSH_US for the
 * final notices. The systemd unit's TimeoutStopSec
 * (firmware/app/deploy/landscaped.service) is LS_RUN_SHUTDOWN_BUDGET_S, their
 * sum and a second of margin; tests/unit/core/test_shutdown_budget.c checks it. */
#define LS_RUN_SHUTDOWN_STOP_MAX_US (LS_RUN_HALT_MAX_US + 1000000u)
#define LS_RUN_SHUTDOWN_FLUSH_US 1000000u
#define LS_RUN_SHUTDOWN_BUDGET_S ((LS_RUN_SHUTDOWN_STOP_MAX_US + LS_RUN_SHUTDOWN_FLUSH_US) / 1000000u + 1u)

/* landscaped stops: halt whatever moves at the model's maximum deceleration
 * (call once). Returns true when a halt runs: call ls_run_tick until
 * core->halt.active is false. */
bool ls_run_shutdown(struct ls_core *core, uint64_t now_us);

/* Manual control ends with the owner's control of the device (release, or
 * the owner lost) and with every halt: the next owner must switch it on
 * itself. Here, below the handlers, because a halt needs it too
 * (cmd_sensor.c switches it on). */
void ls_core_manual_off(ls_core_t *core);

#endif
