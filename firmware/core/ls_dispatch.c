/* The dispatcher: every uplink in, its answer out. The one place where the
 * schema's valid states and owner rules are enforced (handlers never repeat
 * those checks), with the sequence-number rules and the retransmission
 * cache (docs/protocol.md "Sequence numbers"). Top layer of firmware/core
 * (docs/architecture.md "Core layers"): it calls the handlers through the
 * generated ls_cmd_table, and the sessions for connect. */
#include "ls_core.h"

#include <stdarg.h>
#include <string.h>

#include <pb_decode.h>

#include "ls_fmt.h"
#include "ls_session.h"
#include "ls_utf8.h"
#include "ls_wire.h"

static void answer_bad_request(ls_core_t *core, uint8_t addr, int32_t code, uint32_t seq, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

static void describe_states(uint8_t mask, char *out, size_t cap)
{
    static const ls_State all[] = { ls_State_IDLE,    ls_State_UNLOCKED, ls_State_LOCKED,
                                    ls_State_RESTING, ls_State_MOVING,   ls_State_PAUSED };
    size_t n = 0;
    out[0] = '\0';
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        if ((mask & (uint8_t)all[i]) != 0u) {
            int w = ls_fmt_print(out + n, cap - n, "%s%s", n > 0 ? "/" : "", ls_State_name(all[i]));
            if (w < 0 || (size_t)w >= cap - n) {
                return;
            }
            n += (size_t)w;
        }
    }
}

/* What the supervisor should do to reach one of the states in `mask` from `now`. */
static const char *how_to_reach(uint8_t mask, ls_State now)
{
    const uint8_t active = (uint8_t)(ls_State_RESTING | ls_State_MOVING | ls_State_PAUSED);
    bool now_active = ((uint8_t)now & active) != 0u;
    if (now == ls_State_UNLOCKED) {
        return (mask & (uint8_t)ls_State_LOCKED) != 0u ? "lock the device first" : "lock and activate the device first";
    }
    if (now == ls_State_LOCKED) {
        if ((mask & (uint8_t)ls_State_UNLOCKED) != 0u) {
            return "release the device first";
        }
        if ((mask & (uint8_t)ls_State_RESTING) != 0u) {
            return "activate the device first";
        }
        return (mask & (uint8_t)ls_State_PAUSED) != 0u ? "there is no paused motion" : "there is no motion to act on";
    }
    if (now_active) {
        if ((mask & (uint8_t)ls_State_RESTING) != 0u) {
            return now == ls_State_MOVING ? "wait until the motion completes, or stopMotion"
                                          : "resumeMotion or abortMotion first";
        }
        if ((mask & (uint8_t)ls_State_LOCKED) != 0u) {
            return "deactivate the device first";
        }
        if ((mask & (uint8_t)ls_State_PAUSED) != 0u) {
            return "it applies only after stopMotion";
        }
        if ((mask & (uint8_t)ls_State_MOVING) != 0u) {
            return "it applies only while a motion runs";
        }
        return "deactivate and release the device first";
    }
    return "see docs/state-machine.md";
}

/* The schema's presence rules (docs/protocol.md "Absent fields"): nonzero
 * after answering CMD_PARAM_ERR naming a required field that is absent, else
 * 0 with every absent field's default applied to `rq` (call->req). Checked
 * after the state and owner checks, so that those answers do not depend on
 * what a request carries. */
static int check_presence(ls_call_t *call, const ls_cmd_desc_t *d, ls_Request *rq)
{
    const char *missing = ls_request_presence(rq);
    if (missing == NULL) {
        return 0;
    }
    /* proto3 would read an absent field as 0, which here is a real value
     * (JOINT_FRAME, PERCENT_SPEED, unit 0, ...): refuse rather than guess. */
    (void)ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                   "%s: %s is missing: it is required (absent is not 0); send it, also when it is 0 "
                   "(docs/protocol.md \"Absent fields\")",
                   d->name, missing);
    return 1;
}

/* `rq` is call->req, writable: absent fields get their schema default here. */
static int32_t dispatch(ls_core_t *core, uint8_t addr, ls_call_t *call, ls_Request *rq)
{
    const ls_cmd_desc_t *d = ls_cmd_find(rq->which_cmd);
    if (d == NULL) {
        return ls_reply(call, ls_RetCode_CMD_UNKNOWN_CMD_ERR,
                        "command id %u is not in this firmware's schema: update the firmware or the client",
                        (unsigned)rq->which_cmd);
    }
    if (rq->which_cmd == ls_Request_connect_tag) {
        return check_presence(call, d, rq) != 0 ? ls_RetCode_CMD_PARAM_ERR : ls_session_connect(core, addr, call);
    }
    const ls_auth_t *auth = core->cfg.auth;
    const bool sessionless_query = call->sup < 0 && (d->flags & LS_CMD_F_QUERY) != 0u &&
                                   ls_core_policy(core) == ls_AuthPolicy_AUTH_SIGNED && auth->unsigned_queries;
    if (call->sup < 0 && !sessionless_query) {
        /* Why it has none, when the device ended one of the address: a
         * supervisor that sent no disconnect learns that someone did. */
        const ls_session_end_t *end = NULL;
        for (uint8_t k = 0; k < LS_MAX_SUPERVISORS; k++) {
            const ls_session_end_t *e =
                &core->ended[(core->ended_next + LS_MAX_SUPERVISORS - 1u - k) % LS_MAX_SUPERVISORS];
            if (e->epoch != 0u && e->addr == addr) {
                end = e;
                break;
            }
        }
        char ended[64] = "";
        if (end != NULL) {
            ls_fmt_print(ended, sizeof ended, " (its session %u ended: %s)", (unsigned)end->epoch, end->why);
        }
        return ls_reply(call, ls_RetCode_CMD_NOT_CONNECTED_ERR,
                        "%s: supervisor 0x%02X has no session%s: send connect first%s", d->name, addr, ended,
                        ls_core_policy(core) == ls_AuthPolicy_AUTH_SIGNED ? ", signed (docs/protocol.md \"Security\")"
                                                                          : "");
    }
    /* A query without a session (a signed device's unsigned_queries) reads the
     * device as it is, also while nobody is connected. */
    const uint8_t states = (uint8_t)(d->states | (sessionless_query ? (uint8_t)ls_State_IDLE : 0u));
    if ((states & (uint8_t)core->state) == 0u) {
        char valid[64];
        describe_states(d->states, valid, sizeof valid);
        /* The way to the state is the owner's to take (release, activate,
         * ...): a supervisor that is not the owner is told who is. */
        if (core->owner >= 0 && core->owner != call->sup) {
            return ls_reply(
                call, ls_RetCode_CMD_WRONG_STATE_ERR,
                "%s is valid in %s, the device is %s and supervisor 0x%02X (%s) owns it; queries still work", d->name,
                valid, ls_State_name(core->state), core->sessions[core->owner].addr, core->sessions[core->owner].name);
        }
        if (core->owner < 0 && core->held) {
            return ls_reply(call, ls_RetCode_CMD_WRONG_STATE_ERR,
                            "%s is valid in %s, the device is %s: 0x%02X (%s) was lost and keeps the lock until it "
                            "connects again",
                            d->name, valid, ls_State_name(core->state), core->held_addr, core->held_name);
        }
        return ls_reply(call, ls_RetCode_CMD_WRONG_STATE_ERR, "%s is valid in %s, the device is %s: %s", d->name, valid,
                        ls_State_name(core->state), how_to_reach(d->states, core->state));
    }
    if (core->halt.active && (d->flags & LS_CMD_F_OWNER_ONLY) != 0u) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "%s: the arm is stopping (%s), then the drives go off: wait for the motion's final "
                        "notice, then see getMotionControlState",
                        d->name, ls_run_end_name(core->halt.why));
    }
    if ((d->flags & LS_CMD_F_OWNER_ONLY) != 0u && core->owner != call->sup) {
        if (core->owner < 0 && core->held) {
            return ls_reply(call, ls_RetCode_CMD_NOT_OWNER_ERR,
                            "%s needs the owner: 0x%02X (%s) was lost and keeps the lock (disconnect action %s) "
                            "until it connects again",
                            d->name, core->held_addr, core->held_name,
                            ls_core_disconnect_action_name(core->held_action));
        }
        if (core->owner < 0) {
            return ls_reply(call, ls_RetCode_CMD_NOT_OWNER_ERR, "%s needs the owner: lock the device first", d->name);
        }
        return ls_reply(call, ls_RetCode_CMD_NOT_OWNER_ERR,
                        "%s needs the owner: supervisor 0x%02X (%s) owns the device; queries still work", d->name,
                        core->sessions[core->owner].addr, core->sessions[core->owner].name);
    }
    if (check_presence(call, d, rq) != 0) {
        return ls_RetCode_CMD_PARAM_ERR;
    }
    call->res->which_result = rq->which_cmd; /* result tag mirrors the command id */
    return d->handler(core, call);
}

/* FNV-1a, 64 bits: tells a retransmission (the same bytes) from a new
 * request that reuses the seq. */
static uint64_t request_hash(const uint8_t *buf, size_t len)
{
    uint64_t h = 0xcbf29ce484222325u;
    for (size_t i = 0; i < len; i++) {
        h = (h ^ buf[i]) * 0x100000001b3u;
    }
    return h;
}

/* The sequence-number rules (docs/protocol.md "Sequence numbers"): true
 * when the request was refused for its seq (0, or a reused one carrying
 * another request), answered without caching; nothing runs. */
static bool refused_for_its_seq(ls_core_t *core, uint8_t addr, const ls_Request *rq, const ls_session_t *s,
                                uint64_t hash)
{
    if (rq->seq == 0u && rq->which_cmd != ls_Request_connect_tag) {
        /* seq 0 is what proto3 sends when the client set none: such a request
         * could never be told from a retransmission of the one before it
         * (docs/protocol.md "Sequence numbers"). Not cached, nothing runs. */
        const ls_cmd_desc_t *d = ls_cmd_find(rq->which_cmd);
        answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, 0u,
                           "%s: seq is 0 (not set): every request but connect needs a seq > 0, a new one "
                           "for each request (docs/protocol.md \"Sequence numbers\")",
                           d != NULL ? d->name : "request");
        return true;
    }
    if (s != NULL && s->have_last && rq->seq == s->last_seq && rq->which_cmd != ls_Request_connect_tag &&
        hash != s->last_req_hash) {
        /* The same seq, another request: answering from the cache would
         * silently not run it (docs/protocol.md "Sequence numbers"). */
        const ls_cmd_desc_t *prev = ls_cmd_find(s->last_tag);
        const ls_cmd_desc_t *now = ls_cmd_find(rq->which_cmd);
        answer_bad_request(core, addr, ls_RetCode_CMD_SEQ_CONFLICT_ERR, rq->seq,
                           "seq %u reused with a different request (previous: %s, now: %s): use a new seq; "
                           "only a retransmission repeats one",
                           (unsigned)rq->seq, prev != NULL ? prev->name : "?", now != NULL ? now->name : "request");
        return true;
    }
    return false;
}

/* A retransmission of the session's last request: answered from its cache
 * (true), never executed twice. */
static bool answered_from_cache(ls_core_t *core, uint8_t addr, const ls_Request *rq, ls_session_t *s, uint64_t hash,
                                uint64_t now_us)
{
    /* A connect with seq 0 carries no seq to compare (docs/protocol.md
     * "Sequence numbers"): always a new connect, never a retransmission. */
    const bool connect_again = rq->which_cmd == ls_Request_connect_tag && rq->seq != 0u && s != NULL && s->have_last &&
                               s->last_tag == ls_Request_connect_tag && hash == s->last_req_hash;
    if (s != NULL && s->have_last && rq->seq == s->last_seq &&
        (rq->which_cmd != ls_Request_connect_tag || connect_again)) {
        /* A retransmission: answer from the cache, never execute twice. A
         * connect retransmitted byte for byte (its nonce included: the same
         * client, whose answer was lost) gets the same epoch and heartbeat
         * token, and counts as heard: the client cannot beat before it has
         * the token. Running it again would hand out a new token while an
         * earlier answer may still reach the client. */
        if (connect_again && now_us > s->last_heard_us) {
            s->last_heard_us = now_us;
        }
        if (!s->last_pending && s->last_resp_len > 0) {
            ls_send_bytes(core, addr, s->last_resp, s->last_resp_len, sizeof s->last_resp);
        }
        return true;
    }
    return false;
}

/* One request in flight per session: true when this one was refused (busy)
 * because the session's deferred request still runs. */
static bool refused_while_deferred(ls_core_t *core, uint8_t addr, const ls_Request *rq, const ls_session_t *s)
{
    if (s != NULL && s->last_pending && rq->which_cmd != ls_Request_connect_tag &&
        rq->which_cmd != ls_Request_disconnect_tag) {
        /* One request in flight per session: the deferred one keeps its
         * answer slot; this one is refused without running. */
        const ls_cmd_desc_t *pd = ls_cmd_find(s->pending_tag);
        ls_Response *busy = ls_send_new_response(core, rq->seq, s->epoch);
        busy->ret_code = ls_RetCode_CMD_BUSY_ERR;
        ls_fmt_text(busy->ret_msg, sizeof busy->ret_msg, "%s (seq %u) is still running: wait for its answer",
                    pd != NULL ? pd->name : "a blocking command", (unsigned)s->last_seq);
        size_t len = ls_send_encode(&core->down, core->enc, sizeof core->enc);
        if (len > 0) {
            ls_send_bytes(core, addr, core->enc, len, sizeof core->enc);
        }
        return true;
    }
    return false;
}

/* How a request arrived: the link segment, and the key a signed connect
 * was verified with (NULL: none). */
typedef struct {
    int link;
    const ls_auth_session_key_t *connect_key;
} arrival_t;

/* Run the request: dispatch it, keep it as the session's last (the
 * retransmission cache) and answer, unless its handler answers later. */
static void run_request(ls_core_t *core, uint8_t addr, ls_Request *rq, int sup, uint64_t hash, uint64_t now_us,
                        const arrival_t *how)
{
    ls_session_t *s = sup >= 0 ? &core->sessions[sup] : NULL;
    /* disconnect ends the session it answers: its answer still carries that
     * epoch, and a signed session's answer still its MAC (the key is wiped
     * with the session) */
    ls_Response *res = ls_send_new_response(core, rq->seq, s != NULL ? s->epoch : 0u);
    const bool ends_signed = s != NULL && s->signed_session && rq->which_cmd == ls_Request_disconnect_tag;
    if (ends_signed) {
        core->connect_key = s->key;
        core->tx_sign.set = true;
        core->tx_sign.addr = addr;
        core->tx_sign.key = &core->connect_key;
        core->tx_sign.epoch = s->epoch;
    }
    ls_call_t call = { .core = core,
                       .sup = sup,
                       .req = rq,
                       .res = res,
                       .now_us = now_us,
                       .link = how->link,
                       .connect_key = how->connect_key };
    int32_t code = dispatch(core, addr, &call, rq);
    sup = call.sup; /* connect may have created the session */
    s = sup >= 0 && core->sessions[sup].connected ? &core->sessions[sup] : NULL;
    if (s != NULL) {
        res->session_epoch = s->epoch;
        s->have_last = true;
        s->last_seq = rq->seq;
        s->last_req_hash = hash;
        s->last_tag = rq->which_cmd;
        s->executed++;
    }
    if (code == LS_CALL_DEFERRED) {
        if (s != NULL) {
            s->last_pending = true;
            s->pending_tag = rq->which_cmd;
        }
        return;
    }
    res->ret_code = code;
    if (code < 0 && !(code == ls_RetCode_CMD_VERSION_MISMATCH_ERR && rq->which_cmd == ls_Request_connect_tag)) {
        res->which_result = 0; /* no result on errors, but a version refusal's (connect_terms) */
    }
    ls_send_response(core, s, addr);
    if (ends_signed) {
        core->tx_sign.set = false;
        ls_auth_wipe(&core->connect_key, sizeof core->connect_key);
    }
}

/* A challenge: answered at once, outside every session (no seq rule, no
 * cache): it changes nothing but the challenge table. */
static void on_challenge(ls_core_t *core, uint8_t addr, ls_Request *rq, uint64_t now_us)
{
    ls_Response *res = ls_send_new_response(core, rq->seq, 0u);
    ls_call_t call = { .core = core, .sup = LS_NO_SESSION, .req = rq, .res = res, .now_us = now_us };
    res->ret_code = ls_session_challenge(core, addr, &call);
    if (res->ret_code < 0) {
        res->which_result = 0;
    }
    ls_send_response(core, NULL, addr);
}

static void on_request(ls_core_t *core, uint8_t addr, ls_Request *rq, const uint8_t *raw, size_t raw_len,
                       uint64_t now_us, const arrival_t *how)
{
    const int sup = ls_core_session_of(core, addr);
    ls_session_t *s = sup >= 0 ? &core->sessions[sup] : NULL;
    const uint64_t hash = request_hash(raw, raw_len);
    if (rq->which_cmd == ls_Request_challenge_tag) {
        on_challenge(core, addr, rq, now_us);
        return;
    }
    if (s != NULL && s->signed_session && s->have_last && rq->seq < s->last_seq &&
        rq->which_cmd != ls_Request_connect_tag) {
        /* A signed request is fresh when its seq is newer than the session's
         * last: a replayed one is dropped unanswered (docs/protocol.md "Security"). */
        s->auth_refused++;
        core->auth_stale++;
        return;
    }
    if (s != NULL && rq->which_cmd != ls_Request_connect_tag && s->last_heard_us > now_us) {
        /* A request after the connect shows its answer arrived: the connect's
         * grace ends and the heartbeat time-out runs from here, so a client
         * that locks and dies keeps nothing for 3 s more (docs/protocol.md
         * "Liveness"). */
        s->last_heard_us = now_us;
    }
    if (refused_for_its_seq(core, addr, rq, s, hash) || answered_from_cache(core, addr, rq, s, hash, now_us) ||
        refused_while_deferred(core, addr, rq, s)) {
        return;
    }
    run_request(core, addr, rq, sup, hash, now_us, how);
}

/* Open the ls.Uplink member `field` (a message) of buf as *sub, without
 * decoding the rest: LS_OK; LS_EPROTO when it is there but cut short (its
 * length runs past the buffer); LS_EINVAL when it is absent or the framing
 * broke before it. Used when the full decode failed, so the answer still
 * names what it can. */
static int open_uplink_member(const uint8_t *buf, size_t len, uint32_t field, pb_istream_t *s, pb_istream_t *sub)
{
    *s = pb_istream_from_buffer(buf, len);
    for (;;) {
        pb_wire_type_t wt;
        uint32_t tag;
        bool eof = false;
        if (!pb_decode_tag(s, &wt, &tag, &eof)) {
            return LS_EINVAL;
        }
        if (tag == field && wt == PB_WT_STRING) {
            return pb_make_string_substream(s, sub) ? LS_OK : LS_EPROTO;
        }
        if (!pb_skip_field(s, wt)) {
            return LS_EINVAL;
        }
    }
}

/* Read the seq and the command's field number of an ls.Uplink without
 * decoding it: used when the full decode failed (an oversize value) or the
 * command is unknown to this schema (nanopb drops unknown fields), so that
 * the answer still carries the request's seq and names the command. */
static bool scan_request(const uint8_t *buf, size_t len, uint32_t *seq, uint32_t *cmd)
{
    pb_istream_t s, sub;
    *seq = 0;
    *cmd = 0;
    if (open_uplink_member(buf, len, ls_Uplink_request_tag, &s, &sub) != LS_OK) {
        return false;
    }
    bool ok = true;
    while (ok && sub.bytes_left > 0) {
        pb_wire_type_t wt;
        uint32_t tag;
        bool eof = false;
        ok = pb_decode_tag(&sub, &wt, &tag, &eof);
        if (!ok) {
            break;
        }
        if (tag == ls_Request_seq_tag && wt == PB_WT_VARINT) {
            uint64_t v = 0;
            ok = pb_decode_varint(&sub, &v);
            *seq = (uint32_t)v;
        } else {
            if (*cmd == 0u) {
                *cmd = tag;
            }
            ok = pb_skip_field(&sub, wt);
        }
    }
    (void)pb_close_string_substream(&s, &sub);
    return true;
}

/* Whether an ls.Uplink that did not decode holds an RsvpReply, and its
 * rsvp_id (0 when that did not come through): such a reply is refused with
 * an RsvpAck, as every reply is answered (docs/protocol.md "RSVP"). */
static bool scan_rsvp_reply(const uint8_t *buf, size_t len, uint32_t *rsvp_id)
{
    pb_istream_t s, sub;
    *rsvp_id = 0;
    const int rc = open_uplink_member(buf, len, ls_Uplink_rsvp_reply_tag, &s, &sub);
    if (rc == LS_EPROTO) {
        return true; /* cut short: still a reply, its id unknown */
    }
    if (rc != LS_OK) {
        return false;
    }
    pb_wire_type_t wt;
    uint32_t tag;
    bool eof = false;
    while (sub.bytes_left > 0 && pb_decode_tag(&sub, &wt, &tag, &eof)) {
        if (tag == ls_RsvpReply_rsvp_id_tag && wt == PB_WT_VARINT) {
            uint64_t v = 0;
            if (pb_decode_varint(&sub, &v)) {
                *rsvp_id = (uint32_t)v;
            }
            break;
        }
        if (!pb_skip_field(&sub, wt)) {
            break;
        }
    }
    return true;
}

static void answer_bad_request(ls_core_t *core, uint8_t addr, int32_t code, uint32_t seq, const char *fmt, ...)
{
    /* Every answer carries the epoch of the session it answers (docs/protocol.md). */
    const int sup = ls_core_session_of(core, addr);
    ls_Response *res = ls_send_new_response(core, seq, sup >= 0 ? core->sessions[sup].epoch : 0u);
    res->ret_code = code;
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vtext(res->ret_msg, sizeof res->ret_msg, fmt, ap);
    va_end(ap);
    ls_send_response(core, NULL, addr);
}

/* An uplink that passed verification (or needed none): answered as the
 * schema and the session's rules say. */
static void on_verified_uplink(ls_core_t *core, uint8_t addr, const uint8_t *buf, size_t len, uint64_t now_us,
                               bool decoded, pb_istream_t *is, const arrival_t *how)
{
    uint32_t seq = 0, cmd = 0;
    if (!decoded) {
        core->rx_malformed++;
        /* Answer so the host does not wait for a time-out. */
        bool scanned = scan_request(buf, len, &seq, &cmd);
        const ls_cmd_desc_t *d = scanned ? ls_cmd_find((pb_size_t)cmd) : NULL;
        char where[120];
        ls_wire_fault_t fault = ls_wire_find_overflow(ls_Uplink_fields, &core->up, buf, len, where, sizeof where);
        uint32_t rsvp_id = 0;
        if (cmd == 0u && scan_rsvp_reply(buf, len, &rsvp_id)) {
            ls_rsvp_refuse(core, addr, rsvp_id, "did not decode (%s): %s: send one within describe's field_limits",
                           PB_GET_ERROR(is), fault != LS_WIRE_FITS ? where : "a value exceeds the firmware's limits");
            return;
        }
        if (fault != LS_WIRE_FITS) {
            /* "request." is the envelope: name the field as the command has it */
            const char *field = strncmp(where, "request.", 8) == 0 ? where + 8 : where;
            answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, seq, "%s did not decode (%s): %s %s",
                               d != NULL ? d->name : "the message", PB_GET_ERROR(is), field,
                               fault == LS_WIRE_SIZE ? "(protocol/landscape.options): send fewer"
                                                     : "(the schema's type): send a value it holds");
            return;
        }
        answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, seq,
                           "%s did not decode (%s): a value exceeds the firmware's limits "
                           "(protocol/landscape.options) or the schemas differ",
                           d != NULL ? d->name : "the message", PB_GET_ERROR(is));
        return;
    }
    if (core->up.which_msg == ls_Uplink_request_tag && core->up.msg.request.which_cmd == 0) {
        (void)scan_request(buf, len, &seq, &cmd);
        if (cmd != 0u) {
            answer_bad_request(core, addr, ls_RetCode_CMD_UNKNOWN_CMD_ERR, core->up.msg.request.seq,
                               "command id %u is not in this firmware's schema: update the firmware or the "
                               "client (they must come from the same schema)",
                               (unsigned)cmd);
        } else {
            answer_bad_request(core, addr, ls_RetCode_CMD_UNKNOWN_CMD_ERR, core->up.msg.request.seq,
                               "the request carries no command: the client must set one");
        }
        return;
    }
    char where[96];
    if (!ls_utf8_check_msg(ls_Uplink_fields, &core->up, where, sizeof where)) {
        /* Every string the device takes in is UTF-8 (docs/protocol.md "Strings"). */
        core->rx_malformed++;
        if (core->up.which_msg == ls_Uplink_request_tag) {
            const ls_cmd_desc_t *d = ls_cmd_find(core->up.msg.request.which_cmd);
            answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, core->up.msg.request.seq,
                               "%s: %s is not valid UTF-8: send text as UTF-8", d != NULL ? d->name : "request", where);
        } else if (core->up.which_msg == ls_Uplink_rsvp_reply_tag) {
            ls_rsvp_refuse(core, addr, core->up.msg.rsvp_reply.rsvp_id, "%s is not valid UTF-8: send UTF-8 text",
                           where);
        }
        return;
    }
    if (core->up.which_msg == ls_Uplink_request_tag) {
        on_request(core, addr, &core->up.msg.request, buf, len, now_us, how);
    } else if (core->up.which_msg == ls_Uplink_rsvp_reply_tag) {
        /* Only HEARTBEAT frames keep a session (docs/protocol.md "Liveness"). */
        ls_rsvp_on_reply(core, addr, &core->up.msg.rsvp_reply, now_us);
    } else {
        core->rx_malformed++;
    }
}

/* Which key a message from `addr` must verify with, and whether it does
 * (docs/protocol.md "Security"). A connect that carries a host_nonce is
 * signed with the session key of its challenge (epoch 0), else, when it is
 * the connect that opened `addr`'s signed session sent again, with that
 * session's key (epoch 0); every other message from the address of a signed
 * session with the session's key and epoch. Returns true when the message
 * may go on (how->connect_key set for a verified connect); false when it
 * was dropped (counted) or refused. */
static bool verified(ls_core_t *core, uint8_t addr, const uint8_t *buf, size_t len, bool decoded, uint64_t now_us,
                     arrival_t *how)
{
    const int sup = ls_core_session_of(core, addr);
    ls_session_t *s = sup >= 0 && core->sessions[sup].signed_session ? &core->sessions[sup] : NULL;
    const uint8_t node = core->cfg.node_addr;
    const ls_Request *rq = &core->up.msg.request;
    const bool signed_connect = decoded && core->up.which_msg == ls_Uplink_request_tag &&
                                rq->which_cmd == ls_Request_connect_tag && rq->cmd.connect.host_nonce.size > 0u;
    if (!signed_connect) {
        if (s != NULL && !ls_auth_verify(&s->key, LS_AUTH_UP, addr, node, s->epoch, buf, len)) {
            s->auth_refused++;
            core->auth_refused++;
            return false;
        }
        return true;
    }
    ls_auth_t *auth = core->cfg.auth;
    const ls_ConnectReq *c = &rq->cmd.connect;
    const ls_auth_challenge_t *ch =
        auth != NULL ? ls_auth_challenge_find(auth, addr, c->host_nonce.bytes, c->host_nonce.size, now_us) : NULL;
    if (ch == NULL && s != NULL && s->have_last && s->last_tag == ls_Request_connect_tag &&
        ls_auth_verify(&s->key, LS_AUTH_UP, addr, node, 0u, buf, len)) {
        return true; /* its answer was lost: answered from the cache (on_request) */
    }
    const char *why = NULL;
    if (ch == NULL) {
        why = "no challenge of this host_nonce from this address is waiting (none, used, or older than "
              "AUTH_CHALLENGE_TTL_MS): send challenge, then connect";
    } else {
        ls_auth_session_key(auth, ch, addr, node, &core->connect_key);
        if (strcmp(auth->keys[ch->key].id, c->key_id) != 0) {
            why = "its key_id is not the challenge's";
        } else if (!ls_auth_verify(&core->connect_key, LS_AUTH_UP, addr, node, 0u, buf, len)) {
            why = "its MAC does not verify: the host's key differs from the device's key of that name";
        }
    }
    if (why != NULL) {
        core->auth_connects_refused++;
        if (s != NULL) {
            /* the address of a signed session: nothing unverified gets an answer there */
            s->auth_refused++;
            core->auth_refused++;
            return false;
        }
        core->tx_sign.set = true; /* unsigned: nothing verified */
        core->tx_sign.addr = addr;
        core->tx_sign.key = NULL;
        answer_bad_request(core, addr, ls_RetCode_CMD_AUTH_ERR, rq->seq, "connect with key \"%s\" refused: %s",
                           c->key_id, why);
        return false;
    }
    ls_auth_challenge_drop(auth, addr); /* a device nonce serves one connect */
    core->tx_sign.set = true;           /* refusals of this connect: signed for its client */
    core->tx_sign.addr = addr;
    core->tx_sign.key = &core->connect_key;
    core->tx_sign.epoch = 0u;
    how->connect_key = &core->connect_key;
    return true;
}

void ls_core_on_uplink(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len, uint64_t now_us)
{
    ls_core_take_loop_events(core, now_us); /* answer from the state as of the request's arrival */
    core->tx_sign.set = false;
    memset(&core->up, 0, sizeof core->up);
    pb_istream_t is = pb_istream_from_buffer(buf, len);
    const bool decoded = pb_decode(&is, ls_Uplink_fields, &core->up);
    arrival_t how = { .link = link, .connect_key = NULL };
    if (!verified(core, addr, buf, len, decoded, now_us, &how)) {
        core->tx_sign.set = false;
        return;
    }
    on_verified_uplink(core, addr, buf, len, now_us, decoded, &is, &how);
    core->tx_sign.set = false;
}

void ls_core_on_functional(ls_core_t *core, uint8_t addr, int link, const uint8_t *buf, size_t len, uint64_t now_us)
{
    const int sup = ls_core_session_of(core, addr);
    if (ls_core_policy(core) != ls_AuthPolicy_AUTH_SIGNED && (sup < 0 || !core->sessions[sup].signed_session)) {
        ls_core_on_uplink(core, addr, link, buf, len, now_us);
        return;
    }
    /* A single frame has no room for a MAC, so nobody is known to have sent
     * it: a stop is taken from anyone, like an EMERGENCY frame, and nothing
     * else (docs/protocol.md "Security": "What stays unsigned"). */
    ls_core_take_loop_events(core, now_us);
    memset(&core->up, 0, sizeof core->up);
    pb_istream_t is = pb_istream_from_buffer(buf, len);
    ls_Request *rq = &core->up.msg.request;
    if (!pb_decode(&is, ls_Uplink_fields, &core->up) || core->up.which_msg != ls_Uplink_request_tag ||
        rq->which_cmd != ls_Request_stop_motion_tag) {
        core->functional_refused++;
        return;
    }
    core->anonymous_stops++;
    if (core->state != ls_State_MOVING || core->halt.active || core->run.stop_pending) {
        return; /* nothing moves, or a stop is under way already */
    }
    /* The owner's stopMotion without the owner's session: a pause the owner
     * resumes or aborts; no answer, no seq, no cache. */
    ls_Response *res = ls_send_new_response(core, rq->seq, 0u);
    ls_call_t call = { .core = core, .sup = LS_NO_SESSION, .req = rq, .res = res, .now_us = now_us, .link = link };
    (void)ls_h_stop_motion(core, &call);
}
