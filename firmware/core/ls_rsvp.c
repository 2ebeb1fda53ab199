/* RSVPs: notices that wait for the supervisor's reply. See ls_rsvp.h. */
#include "ls_rsvp.h"

#include <stdarg.h>
#include <string.h>

#include "ls_fmt.h"
#include "ls_log.h"
#include "ls_send.h"

static void rsvp_remember(ls_core_t *core, const ls_rsvp_t *r, bool timed_out, const char *action)
{
    ls_rsvp_ended_t *e = &core->rsvp_ended[core->rsvp_ended_count % LS_RSVP_ENDED_LEN];
    core->rsvp_ended_count++;
    *e = (ls_rsvp_ended_t){
        .id = r->id, .addr = r->addr, .timed_out = timed_out, .ref_seq = r->ref_seq, .epoch = r->epoch
    };
    ls_fmt_print(e->action, sizeof e->action, "%s", action != NULL ? action : "");
}

void ls_rsvp_tick(ls_core_t *core, uint64_t now_us)
{
    for (int i = 0; i < LS_MAX_RSVP; i++) {
        ls_rsvp_t *r = &core->rsvp[i];
        if (r->used && now_us >= r->deadline_us) {
            ls_rsvp_t copy = *r;
            r->used = false;
            const char *action = copy.done(core, copy.ctx, ls_RetCode_CMD_TIMEOUT_ERR, true, now_us);
            rsvp_remember(core, &copy, true, action);
            ls_core_log_event(core, now_us, "rsvp %u %s (seq %u) to 0x%02X: no answer, default action %s",
                              (unsigned)copy.id, copy.event_id, (unsigned)copy.ref_seq, copy.addr,
                              action != NULL ? action : copy.default_action);
        }
    }
}

/* The reply's data as "a,b,c" for the event log. */
static void join_data(const ls_RsvpReply *reply, char *out, size_t cap)
{
    size_t n = 0;
    out[0] = '\0';
    for (pb_size_t k = 0; k < reply->data_count && n < cap; k++) {
        int w = ls_fmt_print(out + n, cap - n, "%s%s", k > 0 ? "," : "", reply->data[k]);
        if (w < 0) {
            return;
        }
        n += (size_t)w;
    }
}

static void send_rsvp_ack(ls_core_t *core, uint8_t addr, uint32_t id, int32_t code, const char *action,
                          uint32_t ref_seq, uint32_t epoch, const char *fmt, ...) __attribute__((format(printf, 8, 9)));
static void send_rsvp_ack(ls_core_t *core, uint8_t addr, uint32_t id, int32_t code, const char *action,
                          uint32_t ref_seq, uint32_t epoch, const char *fmt, ...)
{
    memset(&core->note, 0, sizeof core->note);
    core->note.which_msg = ls_Downlink_rsvp_ack_tag;
    ls_RsvpAck *a = &core->note.msg.rsvp_ack;
    a->rsvp_id = id;
    a->ret_code = code;
    a->ref_seq = ref_seq;
    a->session_epoch = epoch;
    /* numbered with the session's notices: a signed session's freshness */
    const int sup = ls_core_session_of(core, addr);
    a->notice_seq = sup >= 0 ? ++core->sessions[sup].notice_seq : 0u;
    ls_fmt_print(a->action, sizeof a->action, "%s", action);
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vtext(a->ret_msg, sizeof a->ret_msg, fmt, ap);
    va_end(ap);
    size_t len = ls_send_encode(&core->note, core->note_enc, sizeof core->note_enc);
    if (len > 0) {
        ls_send_bytes(core, addr, core->note_enc, len, sizeof core->note_enc);
    }
}

/* Every reply gets an RsvpAck: taken (with the action), late, or unknown. */
void ls_rsvp_on_reply(ls_core_t *core, uint8_t addr, const ls_RsvpReply *reply, uint64_t now_us)
{
    char data[128];
    join_data(reply, data, sizeof data);
    for (int i = 0; i < LS_MAX_RSVP; i++) {
        ls_rsvp_t *r = &core->rsvp[i];
        if (r->used && r->id == reply->rsvp_id && r->addr == addr) {
            ls_rsvp_t copy = *r;
            r->used = false;
            const char *action = copy.done(core, copy.ctx, reply->ret_code, false, now_us);
            if (action == NULL) {
                action = "none";
            }
            rsvp_remember(core, &copy, false, action);
            ls_core_log_event(core, now_us, "rsvp %u %s (seq %u) from 0x%02X: %s %d, action %s, data [%s]",
                              (unsigned)copy.id, copy.event_id, (unsigned)copy.ref_seq, addr,
                              reply->ret_code >= 0 ? "accepted" : "declined", (int)reply->ret_code, action, data);
            send_rsvp_ack(core, addr, copy.id, ls_RetCode_CMD_EXEC_OK, action, copy.ref_seq, copy.epoch,
                          "rsvp %u (%s): %s, action %s", (unsigned)copy.id, copy.event_id,
                          reply->ret_code >= 0 ? "accepted" : "declined", action);
            return;
        }
    }
    const uint32_t n = core->rsvp_ended_count < LS_RSVP_ENDED_LEN ? core->rsvp_ended_count : LS_RSVP_ENDED_LEN;
    for (uint32_t k = 0; k < n; k++) {
        const ls_rsvp_ended_t *e = &core->rsvp_ended[(core->rsvp_ended_count - 1u - k) % LS_RSVP_ENDED_LEN];
        if (e->id != reply->rsvp_id || e->addr != addr) {
            continue;
        }
        ls_core_log_event(core, now_us, "rsvp %u from 0x%02X refused: %s, answer %d, data [%s]", (unsigned)e->id, addr,
                          e->timed_out ? "late" : "already answered", (int)reply->ret_code, data);
        if (e->timed_out) {
            send_rsvp_ack(core, addr, e->id, ls_RetCode_CMD_TIMEOUT_ERR, "", e->ref_seq, e->epoch,
                          "rsvp %u: late, its time-out had passed and the default action (%s) was taken: answer "
                          "within rsvp_timeout_ms",
                          (unsigned)e->id, e->action);
        } else {
            send_rsvp_ack(core, addr, e->id, ls_RetCode_CMD_PARAM_ERR, "", e->ref_seq, e->epoch,
                          "rsvp %u: already answered (action %s): answer each RSVP once", (unsigned)e->id, e->action);
        }
        return;
    }
    ls_core_log_event(core, now_us, "rsvp %u from 0x%02X refused: unknown id, answer %d, data [%s]",
                      (unsigned)reply->rsvp_id, addr, (int)reply->ret_code, data);
    send_rsvp_ack(core, addr, reply->rsvp_id, ls_RetCode_CMD_PARAM_ERR, "", 0, 0,
                  "rsvp %u: no RSVP with this id is waiting for 0x%02X: quote the rsvp_id of an RSVP notice sent "
                  "to you",
                  (unsigned)reply->rsvp_id, addr);
}

void ls_rsvp_refuse(ls_core_t *core, uint8_t addr, uint32_t rsvp_id, const char *fmt, ...)
{
    char why[sizeof core->note.msg.rsvp_ack.ret_msg];
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vtext(why, sizeof why, fmt, ap);
    va_end(ap);
    uint32_t ref_seq = 0, epoch = 0;
    for (int i = 0; i < LS_MAX_RSVP; i++) {
        const ls_rsvp_t *r = &core->rsvp[i];
        if (r->used && r->id == rsvp_id && r->addr == addr) {
            ref_seq = r->ref_seq;
            epoch = r->epoch;
        }
    }
    send_rsvp_ack(core, addr, rsvp_id, ls_RetCode_CMD_PARAM_ERR, "", ref_seq, epoch,
                  "rsvp %u: the RSVP still waits; the reply %s", (unsigned)rsvp_id, why);
}

int32_t ls_core_rsvp(ls_core_t *core, int sup, uint32_t ref_seq, ls_NoticeKind kind, const char *event_id,
                     const char *const *data, size_t n_data, uint32_t timeout_ms, const char *default_action,
                     ls_rsvp_done_fn done, void *ctx, uint64_t now_us)
{
    if (sup < 0 || sup >= LS_MAX_SUPERVISORS || !core->sessions[sup].connected || done == NULL) {
        return LS_EINVAL;
    }
    ls_rsvp_t *slot = NULL;
    for (int i = 0; i < LS_MAX_RSVP; i++) {
        if (!core->rsvp[i].used) {
            slot = &core->rsvp[i];
            break;
        }
    }
    if (slot == NULL) {
        return LS_ENOSPC;
    }
    uint32_t id = core->rsvp_next_id++;
    if (core->rsvp_next_id == 0) {
        core->rsvp_next_id = 1;
    }
    ls_session_t *s = &core->sessions[sup];
    ls_Notice *n = ls_send_new_notice(core, kind, event_id, ref_seq, data, n_data);
    n->rsvp_id = id;
    n->session_epoch = ref_seq != 0u ? s->epoch : 0u;
    n->rsvp_timeout_ms = timeout_ms;
    ls_fmt_print(n->rsvp_default, sizeof n->rsvp_default, "%s", default_action);
    n->notice_seq = ++s->notice_seq;
    size_t len = ls_send_encode(&core->note, core->note_enc, sizeof core->note_enc);
    if (len == 0) {
        return LS_EINVAL;
    }
    *slot = (ls_rsvp_t){ .used = true,
                         .id = id,
                         .addr = s->addr,
                         .ref_seq = ref_seq,
                         .epoch = n->session_epoch,
                         .deadline_us = now_us + (uint64_t)timeout_ms * 1000u,
                         .done = done,
                         .ctx = ctx };
    ls_fmt_print(slot->event_id, sizeof slot->event_id, "%s", event_id);
    ls_fmt_print(slot->default_action, sizeof slot->default_action, "%s", default_action);
    ls_send_bytes(core, s->addr, core->note_enc, len, sizeof core->note_enc);
    return (int32_t)id;
}
