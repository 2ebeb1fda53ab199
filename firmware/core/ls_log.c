/* The device's logs and the alarm rate limit. See ls_log.h. */
#include "ls_log.h"

#include <stdarg.h>
#include <string.h>

#include "ls_fmt.h"
#include "ls_send.h"

void ls_core_log_event(ls_core_t *core, uint64_t now_us, const char *fmt, ...)
{
    ls_event_entry_t *e = &core->event_log[core->event_log_count % LS_EVENT_LOG_LEN];
    e->at_us = now_us;
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vprint(e->text, sizeof e->text, fmt, ap);
    va_end(ap);
    core->event_log_count++;
}

void ls_core_log_fault(ls_core_t *core, uint64_t now_us, const char *fmt, ...)
{
    const uint32_t k = core->fault_log_count;
    const uint32_t slot =
        k < LS_FAULT_LOG_FIRST ? k : LS_FAULT_LOG_FIRST + (k - LS_FAULT_LOG_FIRST) % LS_FAULT_LOG_LATEST;
    ls_fault_entry_t *e = &core->fault_log[slot];
    e->at_us = now_us;
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vprint(e->text, sizeof e->text, fmt, ap);
    va_end(ap);
    core->fault_log_count++;
}

const ls_fault_entry_t *ls_core_fault_entry(const ls_core_t *core, uint32_t k, uint32_t *n_kept, uint32_t *dropped)
{
    const uint32_t count = core->fault_log_count;
    const uint32_t kept = count < LS_FAULT_LOG_LEN ? count : LS_FAULT_LOG_LEN;
    if (n_kept != NULL) {
        *n_kept = kept;
    }
    if (dropped != NULL) {
        *dropped = count - kept;
    }
    if (k >= kept) {
        return NULL;
    }
    if (k < LS_FAULT_LOG_FIRST) {
        return &core->fault_log[k];
    }
    /* the ring's oldest kept entry is number count - LS_FAULT_LOG_LATEST (once it has wrapped) */
    const uint32_t first_in_ring = count > LS_FAULT_LOG_LEN ? count - LS_FAULT_LOG_LATEST : LS_FAULT_LOG_FIRST;
    const uint32_t n = first_in_ring + (k - LS_FAULT_LOG_FIRST);
    return &core->fault_log[LS_FAULT_LOG_FIRST + (n - LS_FAULT_LOG_FIRST) % LS_FAULT_LOG_LATEST];
}

/* One alarm and one fault-log entry for the window's suppressed repeats;
 * the window restarts now. */
static void alarm_window_report(ls_core_t *core, uint64_t now_us)
{
    ls_alarm_window_t *w = &core->alarm_window;
    char d1[32], d2[32], d3[96];
    ls_fmt_print(d1, sizeof d1, "suppressed=%u", (unsigned)w->suppressed);
    ls_fmt_print(d2, sizeof d2, "window_ms=%u", (unsigned)((now_us - w->since_us) / 1000u));
    ls_fmt_print(d3, sizeof d3, "fault=%s", w->text);
    const char *data[] = { d1, d2, d3 };
    ls_core_log_fault(core, now_us, "%u repeats suppressed: %.60s", (unsigned)w->suppressed, w->text);
    ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_alarmsSuppressed, 0, false, data, 3);
    w->suppressed = 0;
    w->since_us = now_us;
}

/* The end of an alarm window: its repeats are reported and it runs on (they
 * may go on) until one passes without any. */
void ls_log_alarm_tick(ls_core_t *core, uint64_t now_us)
{
    ls_alarm_window_t *w = &core->alarm_window;
    if (!w->open || now_us - w->since_us < (uint64_t)LS_ALARM_WINDOW_MS * 1000u) {
        return;
    }
    if (w->suppressed == 0) {
        w->open = false;
        return;
    }
    alarm_window_report(core, now_us);
}

/* True when the alarm `text` repeats the one of the open window (counted,
 * not sent); else it opens a new window and is sent. */
bool ls_log_alarm_repeat(ls_core_t *core, const char *text, uint64_t now_us)
{
    ls_alarm_window_t *w = &core->alarm_window;
    ls_log_alarm_tick(core, now_us);
    if (w->open && strncmp(w->text, text, sizeof w->text - 1u) == 0) {
        w->suppressed++;
        core->alarms_suppressed++;
        return true;
    }
    if (w->open && w->suppressed > 0) {
        alarm_window_report(core, now_us); /* another alarm: this window's repeats first */
    }
    w->open = true;
    w->since_us = now_us;
    w->suppressed = 0;
    ls_fmt_print(w->text, sizeof w->text, "%s", text);
    return false;
}

void ls_core_owner_lost_alarm(ls_core_t *core, uint8_t addr, const char *why, ls_DisconnectAction action,
                              uint64_t now_us)
{
    const char *name = ls_core_disconnect_action_name(action);
    char d1[40], d2[64], d3[48];
    ls_fmt_print(d1, sizeof d1, "supervisor=0x%02X", addr);
    ls_fmt_print(d2, sizeof d2, "reason=%s", why);
    ls_fmt_print(d3, sizeof d3, "action=%s", name != NULL ? name : "?");
    const char *data[] = { d1, d2, d3 };
    ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_ownerLost, 0, false, data, 3);
    ls_core_log_fault(core, now_us, "owner 0x%02X lost (%s): action %s", addr, why, name != NULL ? name : "?");
}
