/* Seed 4: setDigitalIO, getDigitalIO, signalDigitalIO.
 *
 * The core has no DIO handle: outputs are switched by the control loop
 * (LS_CTL_DIO_WRITE) and levels are read from its snapshot. setDigitalIO is
 * blocking in the seed, so its answer waits (LS_CALL_DEFERRED) until a
 * snapshot taken after the loop applied the write shows the outputs; a
 * getDigitalIO that follows therefore reads what was written.
 *
 * signalDigitalIO watches (a static table of LS_MAX_DIO_WATCHES) fire once,
 * when every bit of bitString is set: on LS_CEV_DIO_CHANGED events
 * (ls_core_on_dio_event) or, with a polling cycle, at each cycle
 * (ls_dio_tick), and always once at the first tick after the answer, so bits
 * that are already set fire at once. With an RSVP callback the watch waits
 * for the supervisor's answer (docs/protocol.md "RSVP"): accept re-arms it
 * (it fires again once the bits have been not all set and are all set
 * again), decline cancels it, no answer within LS_DIO_RSVP_TIMEOUT_MS takes
 * the default, cancel. Comms thread only. */
#include <string.h>

#include "ls_control.h"
#include "ls_core_services.h"
#include "ls_core_events.h"
#include "ls_fmt.h"

_Static_assert(LS_CORE_MAX_DIO_UNITS == LS_CTL_MAX_DIO_UNITS, "the core and the loop must agree on DIO units");

#define LS_DIO_WRITE_TIMEOUT_US 500000u /* a loop that does not apply a write in this time is not running */
#define LS_DIO_RSVP_TIMEOUT_MS 2000u    /* how long a dioSignal RSVP waits for its answer */
#define LS_DIO_RSVP_ACCEPT "rearm"      /* the watch's action on accept (docs/protocol.md "RSVP") */
#define LS_DIO_RSVP_DECLINE "cancel"    /* on decline */
#define LS_DIO_RSVP_DEFAULT "cancel"    /* on time-out */
#define LS_DIO_TYPE "digital"

static int32_t check_type(ls_call_t *call, const char *cmd, const char *type)
{
    if (strcmp(type, LS_DIO_TYPE) == 0) {
        return ls_RetCode_CMD_EXEC_OK;
    }
    return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: type '%s' is not supported: the allowed type is '%s'", cmd,
                    type, LS_DIO_TYPE);
}

static int32_t check_unit(ls_core_t *core, ls_call_t *call, const char *cmd, int32_t unit)
{
    if (core->ctl == NULL || core->dio_units == 0) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "%s: this controller has no digital I/O", cmd);
    }
    if (unit < 0 || unit >= (int32_t)core->dio_units) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s: unit %d: allowed 0..%u", cmd, (int)unit,
                        (unsigned)core->dio_units - 1u);
    }
    return ls_RetCode_CMD_EXEC_OK;
}

int32_t ls_h_set_digital_io(struct ls_core *core, struct ls_call *call)
{
    const ls_SetDigitalIOReq *rq = &call->req->cmd.set_digital_io;
    int32_t rc = check_type(call, "setDigitalIO", rq->type);
    if (rc < 0) {
        return rc;
    }
    rc = check_unit(core, call, "setDigitalIO", rq->unit_id);
    if (rc < 0) {
        return rc;
    }
    const uint16_t unit = (uint16_t)rq->unit_id;
    if ((rq->bits_on & rq->bits_off) != 0u) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "setDigitalIO: bits 0x%X are in both bitsON and bitsOFF: name each bit once",
                        (unsigned)(rq->bits_on & rq->bits_off));
    }
    const uint32_t outputs = core->dio_info[unit].output_mask;
    const uint32_t bad = (rq->bits_on | rq->bits_off) & ~outputs;
    if (bad != 0u) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "setDigitalIO: bits 0x%X of unit %u are not outputs: the outputs are 0x%08X", (unsigned)bad,
                        (unsigned)unit, (unsigned)outputs);
    }
    if ((rq->bits_on | rq->bits_off) == 0u) {
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "unit %u: no bits given, nothing switched", (unsigned)unit);
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    ls_ctl_cmd_t cmd = { .kind = LS_CTL_DIO_WRITE,
                         .ref_seq = call->req->seq,
                         .dio = { .unit = unit, .on = rq->bits_on, .off = rq->bits_off } };
    if (!ls_control_post(core->ctl, &cmd)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "setDigitalIO: the control loop's command queue is full: retry");
    }
    core->dio.write_wait[call->sup] = (ls_dio_write_wait_t){ .pending = true,
                                                             .cycle0 = snap.cycle,
                                                             .deadline_us = call->now_us + LS_DIO_WRITE_TIMEOUT_US,
                                                             .unit = unit,
                                                             .on = rq->bits_on,
                                                             .off = rq->bits_off };
    return LS_CALL_DEFERRED;
}

int32_t ls_h_get_digital_io(struct ls_core *core, struct ls_call *call)
{
    const ls_GetDigitalIOReq *rq = &call->req->cmd.get_digital_io;
    int32_t rc = check_type(call, "getDigitalIO", rq->type);
    if (rc < 0) {
        return rc;
    }
    rc = check_unit(core, call, "getDigitalIO", rq->unit_id);
    if (rc < 0) {
        return rc;
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    ls_GetDigitalIORes *r = &call->res->result.get_digital_io;
    r->bits_on = snap.dio[rq->unit_id];
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "unit %d: 0x%08X", (int)rq->unit_id, (unsigned)r->bits_on);
}

static const char *cb_name(ls_CallbackType cb)
{
    switch (cb) {
    case ls_CallbackType_CB_EVENT: return "event";
    case ls_CallbackType_CB_ALARM: return "alarm";
    case ls_CallbackType_CB_EVENT_RSVP: return "event RSVP";
    case ls_CallbackType_CB_ALARM_RSVP: return "alarm RSVP";
    }
    return "?";
}

static bool cb_is_alarm(ls_CallbackType cb)
{
    return cb == ls_CallbackType_CB_ALARM || cb == ls_CallbackType_CB_ALARM_RSVP;
}

int32_t ls_h_signal_digital_io(struct ls_core *core, struct ls_call *call)
{
    const ls_SignalDigitalIOReq *rq = &call->req->cmd.signal_digital_io;
    int32_t rc = check_type(call, "signalDigitalIO", rq->type);
    if (rc < 0) {
        return rc;
    }
    rc = check_unit(core, call, "signalDigitalIO", rq->unit_id);
    if (rc < 0) {
        return rc;
    }
    const uint16_t unit = (uint16_t)rq->unit_id;
    if (rq->bit_string == 0u) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "signalDigitalIO: bitString is 0: name the bits to watch");
    }
    const uint32_t lines = core->dio_info[unit].input_mask | core->dio_info[unit].output_mask;
    if ((rq->bit_string & ~lines) != 0u) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "signalDigitalIO: bits 0x%X are not lines of unit %u: its lines are 0x%08X",
                        (unsigned)(rq->bit_string & ~lines), (unsigned)unit, (unsigned)lines);
    }
    if (rq->polling_timeout_ms < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "signalDigitalIO: pollingTimeOut %d ms: allowed 0 (no time-out) or more",
                        (int)rq->polling_timeout_ms);
    }
    if (rq->polling_cycle_time_ms < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "signalDigitalIO: pollingCycleTime %d ms: allowed 0 (on every change) or more",
                        (int)rq->polling_cycle_time_ms);
    }
    switch (rq->callback_type) {
    case ls_CallbackType_CB_EVENT:
    case ls_CallbackType_CB_ALARM:
    case ls_CallbackType_CB_EVENT_RSVP:
    case ls_CallbackType_CB_ALARM_RSVP: break;
    default:
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "signalDigitalIO: callbackType %d: allowed CB_EVENT (0), CB_ALARM (1), CB_EVENT_RSVP (2), "
                        "CB_ALARM_RSVP (3)",
                        (int)rq->callback_type);
    }
    ls_dio_watch_t *w = NULL;
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        if (core->dio.watch[i].phase == LS_WATCH_FREE) {
            w = &core->dio.watch[i];
            break;
        }
    }
    if (w == NULL) {
        return ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                        "signalDigitalIO: all %d watches are in use: wait until one fires or times out",
                        LS_MAX_DIO_WATCHES);
    }
    if (core->dio.next_id == 0u) {
        core->dio.next_id = 1u;
    }
    const uint32_t id = core->dio.next_id++;
    *w = (ls_dio_watch_t){
        .phase = LS_WATCH_ARMED,
        .id = id,
        .sup = call->sup,
        .addr = core->sessions[call->sup].addr,
        .ref_seq = call->req->seq,
        .unit = unit,
        .bits = rq->bit_string,
        .cb = rq->callback_type,
        .deadline_us = rq->polling_timeout_ms > 0 ? call->now_us + (uint64_t)rq->polling_timeout_ms * 1000u : 0u,
        .timeout_us = (uint64_t)rq->polling_timeout_ms * 1000u,
        .period_us = (uint64_t)rq->polling_cycle_time_ms * 1000u,
        .next_check_us = call->now_us,
        .check_now = true,
    };
    call->res->result.signal_digital_io.watch_id = id;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "watch %u: unit %u bits 0x%X, %s callback", (unsigned)id,
                    (unsigned)unit, (unsigned)w->bits, cb_name(w->cb));
}

/* ---------------------------------------------------------------- watches */

typedef struct {
    char unit[16], bits[24], levels[24], watch[24];
    const char *v[4];
} watch_data_t;

static void watch_data(watch_data_t *d, const ls_dio_watch_t *w, uint32_t levels)
{
    ls_fmt_print(d->unit, sizeof d->unit, "unit=%u", (unsigned)w->unit);
    ls_fmt_print(d->bits, sizeof d->bits, "bits=0x%X", (unsigned)w->bits);
    ls_fmt_print(d->levels, sizeof d->levels, "levels=0x%X", (unsigned)levels);
    ls_fmt_print(d->watch, sizeof d->watch, "watch=%u", (unsigned)w->id);
    d->v[0] = d->unit;
    d->v[1] = d->bits;
    d->v[2] = d->levels;
    d->v[3] = d->watch;
}

static bool session_alive(const ls_core_t *core, const ls_dio_watch_t *w)
{
    const ls_session_t *s = &core->sessions[w->sup];
    return s->connected && s->addr == w->addr;
}

/* The supervisor's answer decides what the watch does: accept re-arms it,
 * decline cancels it, no answer cancels it (the default the notice announced). */
static const char *rsvp_done(ls_core_t *core, void *ctx, int32_t ret_code, bool timed_out, uint64_t now_us)
{
    ls_dio_watch_t *w = ctx;
    core->dio.rsvp_last_code = ret_code;
    if (w->phase != LS_WATCH_AWAIT_RSVP) {
        return "none";
    }
    if (timed_out) {
        core->dio.rsvp_timed_out++;
        if (session_alive(core, w)) {
            char watch[24];
            ls_fmt_print(watch, sizeof watch, "watch=%u", (unsigned)w->id);
            const char *data[] = { watch, "action=" LS_DIO_RSVP_DEFAULT };
            ls_core_notify(core, w->sup, cb_is_alarm(w->cb) ? ls_NoticeKind_ALARM : ls_NoticeKind_EVENT,
                           ls_EventId_dioSignalRsvpTimeout, w->ref_seq, false, data, 2);
        }
        w->phase = LS_WATCH_FREE;
        return LS_DIO_RSVP_DEFAULT;
    }
    core->dio.rsvp_replied++;
    if (ret_code < 0 || !session_alive(core, w)) {
        w->phase = LS_WATCH_FREE;
        return LS_DIO_RSVP_DECLINE;
    }
    w->phase = LS_WATCH_ARMED;
    w->await_clear = true; /* the bits are still set: fire on their next rising */
    w->check_now = true;
    w->next_check_us = now_us + w->period_us;
    w->deadline_us = w->timeout_us > 0u ? now_us + w->timeout_us : 0u;
    return LS_DIO_RSVP_ACCEPT;
}

static void fire(ls_core_t *core, ls_dio_watch_t *w, uint32_t levels, uint64_t now_us)
{
    watch_data_t d;
    watch_data(&d, w, levels);
    w->fired++;
    if (w->cb == ls_CallbackType_CB_EVENT_RSVP || w->cb == ls_CallbackType_CB_ALARM_RSVP) {
        ls_NoticeKind kind =
            w->cb == ls_CallbackType_CB_ALARM_RSVP ? ls_NoticeKind_ALARM_RSVP : ls_NoticeKind_EVENT_RSVP;
        if (ls_core_rsvp(core, w->sup, w->ref_seq, kind, ls_EventId_name(ls_EventId_dioSignal), d.v, 4,
                         LS_DIO_RSVP_TIMEOUT_MS, LS_DIO_RSVP_DEFAULT, rsvp_done, w, now_us) > 0) {
            w->phase = LS_WATCH_AWAIT_RSVP;
            return;
        }
        /* RSVP table full: the supervisor still learns that the bits are set. */
    }
    ls_core_notify(core, w->sup, cb_is_alarm(w->cb) ? ls_NoticeKind_ALARM : ls_NoticeKind_EVENT, ls_EventId_dioSignal,
                   w->ref_seq, false, d.v, 4);
    w->phase = LS_WATCH_FREE;
}

void ls_core_on_dio_event(ls_core_t *core, uint16_t unit, uint32_t levels, uint32_t changed, uint64_t now_us)
{
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        ls_dio_watch_t *w = &core->dio.watch[i];
        if (w->phase != LS_WATCH_ARMED || w->unit != unit || w->period_us != 0u) {
            continue;
        }
        if (!session_alive(core, w)) {
            w->phase = LS_WATCH_FREE;
            continue;
        }
        /* A watch that has been checked once can only become true through a change of its bits. */
        if ((changed & w->bits) == 0u && !w->check_now) {
            continue;
        }
        w->check_now = false;
        if ((levels & w->bits) != w->bits) {
            w->await_clear = false;
        } else if (!w->await_clear) {
            fire(core, w, levels, now_us);
        }
    }
}

/* Snapshot taken at most once per tick, only when something needs it. */
typedef struct {
    bool have;
    ls_ctl_snapshot_t s;
} lazy_snap_t;

static const ls_ctl_snapshot_t *snap_get(ls_core_t *core, lazy_snap_t *ls)
{
    if (!ls->have) {
        ls_control_snapshot(core->ctl, &ls->s);
        ls->have = true;
    }
    return &ls->s;
}

static void finish_writes(ls_core_t *core, lazy_snap_t *ls, uint64_t now_us)
{
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        ls_dio_write_wait_t *ww = &core->dio.write_wait[i];
        if (!ww->pending) {
            continue;
        }
        if (!core->sessions[i].connected || core->ctl == NULL) {
            ww->pending = false;
            continue;
        }
        const ls_ctl_snapshot_t *s = snap_get(core, ls);
        char msg[128];
        /* Commands are taken at the start of a cycle and the snapshot is
         * published at its end: two cycles after the post the write is in. */
        if (s->cycle >= ww->cycle0 + 2u) {
            uint32_t lv = s->dio[ww->unit];
            ww->pending = false;
            if ((lv & ww->on) == ww->on && (lv & ww->off) == 0u) {
                ls_fmt_print(msg, sizeof msg, "unit %u: levels now 0x%08X", (unsigned)ww->unit, (unsigned)lv);
                ls_core_finish_deferred(core, i, ls_RetCode_CMD_EXEC_OK, msg);
            } else {
                ls_fmt_print(msg, sizeof msg,
                             "unit %u: after switching on 0x%X, off 0x%X the levels read 0x%08X: the DIO "
                             "backend refused the write (see the log)",
                             (unsigned)ww->unit, (unsigned)ww->on, (unsigned)ww->off, (unsigned)lv);
                ls_core_finish_deferred(core, i, ls_RetCode_CMD_ERR, msg);
            }
        } else if (now_us >= ww->deadline_us) {
            ww->pending = false;
            ls_fmt_print(msg, sizeof msg,
                         "unit %u: the control loop did not apply the write within %u ms: is it running?",
                         (unsigned)ww->unit, (unsigned)(LS_DIO_WRITE_TIMEOUT_US / 1000u));
            ls_core_finish_deferred(core, i, ls_RetCode_CMD_TIMEOUT_ERR, msg);
        }
    }
}

static uint64_t earlier(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

uint64_t ls_dio_next_deadline_us(const ls_core_t *core, uint64_t now_us)
{
    uint64_t t = UINT64_MAX;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        if (core->dio.write_wait[i].pending) {
            t = earlier(t, now_us + LS_CORE_SAMPLE_US); /* the write shows in the snapshot's cycle count */
        }
    }
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        const ls_dio_watch_t *w = &core->dio.watch[i];
        if (w->phase != LS_WATCH_ARMED) {
            continue; /* changes of the levels come as loop events */
        }
        if (w->check_now) {
            return 0;
        }
        if (w->period_us > 0u) {
            t = earlier(t, w->next_check_us);
        }
        if (w->deadline_us != 0u) {
            t = earlier(t, w->deadline_us);
        }
    }
    return t;
}

void ls_dio_tick(ls_core_t *core, uint64_t now_us)
{
    lazy_snap_t ls = { .have = false };
    finish_writes(core, &ls, now_us);
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        ls_dio_watch_t *w = &core->dio.watch[i];
        if (w->phase != LS_WATCH_ARMED) {
            continue;
        }
        if (!session_alive(core, w) || core->ctl == NULL) {
            w->phase = LS_WATCH_FREE; /* watches end with their session */
            continue;
        }
        bool due = w->check_now || (w->period_us > 0u && now_us >= w->next_check_us);
        if (due) {
            uint32_t levels = snap_get(core, &ls)->dio[w->unit];
            w->check_now = false;
            if ((levels & w->bits) != w->bits) {
                w->await_clear = false;
            } else if (!w->await_clear) {
                fire(core, w, levels, now_us);
                continue;
            }
            if (w->period_us > 0u) {
                w->next_check_us += w->period_us;
                if (w->next_check_us <= now_us) {
                    w->next_check_us = now_us + w->period_us; /* ticks came late: do not burst */
                }
            }
        }
        if (w->deadline_us != 0u && now_us >= w->deadline_us) {
            watch_data_t d;
            watch_data(&d, w, snap_get(core, &ls)->dio[w->unit]);
            ls_core_notify(core, w->sup, cb_is_alarm(w->cb) ? ls_NoticeKind_ALARM : ls_NoticeKind_EVENT,
                           ls_EventId_dioSignalTimeout, w->ref_seq, false, d.v, 4);
            w->phase = LS_WATCH_FREE;
        }
    }
}
