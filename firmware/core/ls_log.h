/* The device's logs and the alarm rate limit: the event log (sendCommand
 * events), the fault log (sendCommand faults: its first entries and a ring
 * of the latest) and the window that counts repeats of one alarm instead of
 * sending them (docs/protocol.md "Budgets under floods").
 *
 * Services layer of firmware/core (docs/architecture.md "Core layers"):
 * above ls_send. Comms thread only; no allocation, O(1) per entry.*/
#ifndef LS_LOG_H
#define LS_LOG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_types.h"

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

/* Append a line to the event log (sendCommand events): RSVP outcomes with
 * their data. */
void ls_core_log_event(ls_core_t *core, uint64_t now_us, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* The end of an alarm window (LS_ALARM_WINDOW_MS): its repeats are reported
 * (one alarm alarmsSuppressed and a fault-log entry) and it runs on until
 * one passes without any. Every comms loop turn (ls_core_tick). */
void ls_log_alarm_tick(ls_core_t *core, uint64_t now_us);

/* True when the alarm `text` repeats the one of the open window (counted,
 * not to be sent); else it opens a new window (the previous window's repeats
 * reported first) and the caller sends it. */
bool ls_log_alarm_repeat(ls_core_t *core, const char *text, uint64_t now_us);

#endif
