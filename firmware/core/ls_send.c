/* What the core sends: answers (the retransmission cache included) and
 * notices, and the session lookups they need. See ls_send.h. */
#include "ls_send.h"

#include <stdarg.h>
#include <string.h>

#include <pb_encode.h>

#include "landscape.h"
#include "landscape_choices.h"
#include "ls_fmt.h"
#include "ls_utf8.h"

int ls_core_session_of(const ls_core_t *core, uint8_t addr)
{
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        if (core->sessions[i].connected && core->sessions[i].addr == addr) {
            return i;
        }
    }
    return LS_NO_SESSION;
}

ls_units_t ls_core_units(const ls_core_t *core, int sup)
{
    if (sup < 0 || sup >= LS_MAX_SUPERVISORS || !core->sessions[sup].connected) {
        return LS_UNITS_SI;
    }
    return core->sessions[sup].units;
}

ls_units_t ls_core_run_units(const ls_core_t *core)
{
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        const ls_session_t *s = &core->sessions[i];
        if (s->connected && s->addr == core->run.addr && s->epoch == core->run.epoch) {
            return s->units;
        }
    }
    return LS_UNITS_SI;
}

void ls_core_set_motion_state(ls_core_t *core, uint32_t choice)
{
    core->motion_state = (uint8_t)choice;
}

const char *ls_core_motion_state_name(const ls_core_t *core)
{
    const char *name = landscape_status_st_motion_choice_name(core->motion_state);
    return name != NULL ? name : "unknown";
}

uint32_t ls_core_manual_motion_state(int kind)
{
    return kind == LS_MANUAL_SPACEBALL ? LANDSCAPE_STATUS_ST_MOTION_MANUAL_SPACEBALL_CHOICE
                                       : LANDSCAPE_STATUS_ST_MOTION_MANUAL_TEACHPENDANT_CHOICE;
}

bool ls_core_motion_is_manual(const ls_core_t *core)
{
    return core->motion_state == LANDSCAPE_STATUS_ST_MOTION_MANUAL_TEACHPENDANT_CHOICE ||
           core->motion_state == LANDSCAPE_STATUS_ST_MOTION_MANUAL_SPACEBALL_CHOICE;
}

const char *ls_core_disconnect_action_name(ls_DisconnectAction a)
{
    switch (a) {
    case ls_DisconnectAction_DISCONNECT_CONFIGURED: return "configured";
    case ls_DisconnectAction_DISCONNECT_STOP: return "stop";
    case ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE: return "stop_deactivate";
    case ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE: return "stop_deactivate_release";
    }
    return NULL;
}

size_t ls_send_encode(ls_Downlink *msg, uint8_t *buf, size_t cap)
{
    /* Only valid UTF-8 leaves the device: a string cut by a truncation loses
     * the cut character whole (docs/protocol.md "Strings"). */
    ls_utf8_repair_msg(ls_Downlink_fields, msg);
    pb_ostream_t os = pb_ostream_from_buffer(buf, cap);
    if (!pb_encode(&os, ls_Downlink_fields, msg)) {
        return 0;
    }
    return os.bytes_written;
}

ls_AuthPolicy ls_core_policy(const ls_core_t *core)
{
    return core->cfg.auth != NULL && core->cfg.auth->policy == ls_AuthPolicy_AUTH_SIGNED ? ls_AuthPolicy_AUTH_SIGNED
                                                                                         : ls_AuthPolicy_AUTH_UNSIGNED;
}

void ls_send_bytes(ls_core_t *core, uint8_t addr, uint8_t *buf, size_t len, size_t cap)
{
    const ls_auth_session_key_t *key = core->tx_sign.key;
    uint32_t epoch = core->tx_sign.epoch;
    if (!core->tx_sign.set || core->tx_sign.addr != addr) {
        const int i = ls_core_session_of(core, addr);
        key = i >= 0 && core->sessions[i].signed_session ? &core->sessions[i].key : NULL;
        epoch = i >= 0 ? core->sessions[i].epoch : 0u;
    }
    if (key != NULL) {
        const int n = ls_auth_sign(key, LS_AUTH_DOWN, core->cfg.node_addr, addr, epoch, buf, len, cap);
        if (n < 0) {
            core->tx_lost++; /* cannot happen: LS_DOWNLINK_MAX counts Downlink.mac */
            return;
        }
        len = (size_t)n;
    }
    if (core->io.send_downlink == NULL || core->io.send_downlink(core->io.ctx, addr, buf, len) != 0) {
        core->tx_lost++;
    }
}

void ls_send_response(ls_core_t *core, ls_session_t *s, uint8_t addr)
{
    size_t len = ls_send_encode(&core->down, core->enc, sizeof core->enc);
    if (len == 0) {
        /* Cannot happen with bounded fields; answer something rather than nothing. */
        ls_Response *r = &core->down.msg.response;
        r->which_result = 0;
        r->ret_code = ls_RetCode_CMD_ERR;
        ls_fmt_print(r->ret_msg, sizeof r->ret_msg, "internal: response did not encode");
        len = ls_send_encode(&core->down, core->enc, sizeof core->enc);
    }
    if (s != NULL) {
        memcpy(s->last_resp, core->enc, len);
        s->last_resp_len = len;
        s->last_pending = false;
    }
    ls_send_bytes(core, addr, core->enc, len, sizeof core->enc);
}

int32_t ls_reply(ls_call_t *call, int32_t code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vtext(call->res->ret_msg, sizeof call->res->ret_msg, fmt, ap);
    va_end(ap);
    return code;
}

ls_Notice *ls_send_new_notice(ls_core_t *core, ls_NoticeKind kind, const char *event_id, uint32_t ref_seq,
                              const char *const *data, size_t n_data)
{
    memset(&core->note, 0, sizeof core->note);
    core->note.which_msg = ls_Downlink_notice_tag;
    ls_Notice *n = &core->note.msg.notice;
    n->kind = kind;
    ls_fmt_print(n->event_id, sizeof n->event_id, "%s", event_id);
    n->ref_seq = ref_seq;
    size_t cap = sizeof n->data / sizeof n->data[0];
    for (size_t k = 0; k < n_data && k < cap; k++) {
        ls_fmt_text(n->data[k], sizeof n->data[k], "%s", data[k]);
        n->data_count++;
    }
    return n;
}

void ls_core_notify(ls_core_t *core, int sup, ls_NoticeKind kind, ls_EventId id, uint32_t ref_seq, bool final,
                    const char *const *data, size_t n_data)
{
    const char *event_id = ls_EventId_name(id);
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        ls_session_t *s = &core->sessions[i];
        if (!s->connected || (sup >= 0 && i != sup)) {
            continue;
        }
        ls_Notice *n = ls_send_new_notice(core, kind, event_id, ref_seq, data, n_data);
        n->final = final;
        n->notice_seq = ++s->notice_seq;
        n->session_epoch = ref_seq != 0u ? s->epoch : 0u;
        size_t len = ls_send_encode(&core->note, core->note_enc, sizeof core->note_enc);
        if (len > 0) {
            ls_send_bytes(core, s->addr, core->note_enc, len, sizeof core->note_enc);
        }
    }
}

void ls_core_notify_to(ls_core_t *core, uint8_t addr, uint32_t epoch, ls_NoticeKind kind, ls_EventId id,
                       uint32_t ref_seq, bool final, const char *const *data, size_t n_data)
{
    ls_core_notify_named_to(core, addr, epoch, kind, ls_EventId_name(id), ref_seq, final, data, n_data);
}

void ls_core_notify_named_to(ls_core_t *core, uint8_t addr, uint32_t epoch, ls_NoticeKind kind, const char *event_id,
                             uint32_t ref_seq, bool final, const char *const *data, size_t n_data)
{
    int i = ls_core_session_of(core, addr);
    ls_Notice *n = ls_send_new_notice(core, kind, event_id, ref_seq, data, n_data);
    n->final = final;
    n->session_epoch = epoch;
    /* The session that started it may be gone (disconnect, heartbeat, a new
     * connect): the address still gets the notice, numbered on in that
     * session's count, which the run kept. */
    if (i >= 0 && core->sessions[i].epoch == epoch) {
        n->notice_seq = ++core->sessions[i].notice_seq;
    } else if (core->run.addr == addr && core->run.epoch == epoch) {
        n->notice_seq = ++core->run.notice_seq;
    }
    size_t len = ls_send_encode(&core->note, core->note_enc, sizeof core->note_enc);
    if (len > 0) {
        ls_send_bytes(core, addr, core->note_enc, len, sizeof core->note_enc);
    }
}

void ls_send_session_ended(ls_core_t *core, const ls_session_t *s)
{
    if (core->run.active && core->run.addr == s->addr && core->run.epoch == s->epoch) {
        core->run.notice_seq = s->notice_seq;
    }
}

ls_Response *ls_send_new_response(ls_core_t *core, uint32_t seq, uint32_t epoch)
{
    memset(&core->down, 0, sizeof core->down);
    core->down.which_msg = ls_Downlink_response_tag;
    ls_Response *res = &core->down.msg.response;
    res->seq = seq;
    res->session_epoch = epoch;
    return res;
}

void ls_core_finish_deferred(ls_core_t *core, int sup, int32_t code, const char *msg)
{
    if (sup < 0 || sup >= LS_MAX_SUPERVISORS) {
        return;
    }
    ls_session_t *s = &core->sessions[sup];
    if (!s->connected || !s->last_pending) {
        return;
    }
    ls_Response *res = ls_send_new_response(core, s->last_seq, s->epoch);
    res->ret_code = code;
    res->which_result = code >= 0 ? s->pending_tag : 0;
    ls_fmt_text(res->ret_msg, sizeof res->ret_msg, "%s", msg);
    ls_send_response(core, s, s->addr);
}
