/* Sessions: connect, disconnect, heartbeats and their time-out, and the
 * disconnect handler. See ls_session.h. */
#include "ls_session.h"

#include <string.h>

#include "ls_fmt.h"

/* The configured action, 0 meaning the seed's default. */
static ls_DisconnectAction configured_action(const ls_core_t *core)
{
    return core->cfg.disconnect_action == ls_DisconnectAction_DISCONNECT_CONFIGURED
               ? ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE
               : core->cfg.disconnect_action;
}

static int connected_count(const ls_core_t *core)
{
    int n = 0;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        n += core->sessions[i].connected ? 1 : 0;
    }
    return n;
}

/* Seed 2.2 disconnect handler, the owner's session's action (docs/protocol.md
 * "Disconnect handler"): stop; stop, deactivate; or stop, deactivate,
 * release. A kept lock waits for the owner's address to connect again. IDLE
 * when nobody is left and nothing is held. */
void ls_session_drop(ls_core_t *core, int i, const char *why, uint64_t now_us)
{
    ls_session_t *s = &core->sessions[i];
    bool was_owner = core->owner == i;
    uint8_t addr = s->addr;
    ls_send_session_ended(core, s);
    s->connected = false;
    s->signed_session = false;
    ls_auth_wipe(&s->key, sizeof s->key);
    ls_session_end_t *e = &core->ended[core->ended_next];
    core->ended_next = (uint8_t)((core->ended_next + 1u) % LS_MAX_SUPERVISORS);
    e->addr = addr;
    e->epoch = s->epoch;
    ls_fmt_print(e->why, sizeof e->why, "%s", strcmp(why, "disconnect") == 0 ? "disconnect requested" : why);
    if (core->halt.answer_sup == i) {
        core->halt.answer_sup = LS_NO_SESSION; /* nobody to answer any more */
    }
    if (was_owner) {
        const ls_DisconnectAction action = s->disconnect_action;
        const bool release = action == ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE;
        ls_core_manual_off(core);
        core->owner = LS_NO_SESSION;
        if (!release) {
            core->held = true;
            core->held_addr = addr;
            core->held_action = action;
            ls_fmt_print(core->held_name, sizeof core->held_name, "%s", s->name);
        }
        if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED || core->halt.active) {
            /* Stop along the path (drives off unless the action is `stop`),
             * then release or keep the lock (ls_run_tick): the state says
             * MOVING until the arm is at rest. */
            bool lost = strcmp(why, "disconnect") != 0;
            ls_run_halt_owner_lost(core, lost ? LS_RUN_END_OWNER_LOST : LS_RUN_END_DISCONNECT,
                                   action == ls_DisconnectAction_DISCONNECT_STOP, now_us);
            core->halt.owner_lost = true;
            core->halt.release = release;
            core->halt.lost_action = action;
            core->halt.lost_addr = addr;
            ls_fmt_print(core->halt.lost_why, sizeof core->halt.lost_why, "%s", why);
            return;
        }
        if (core->state == ls_State_RESTING && action != ls_DisconnectAction_DISCONNECT_STOP) {
            if (core->act.enable_drives != NULL) {
                (void)core->act.enable_drives(core->act.ctx, false);
            }
            core->state = ls_State_LOCKED;
        }
        if (release) {
            core->state = ls_State_UNLOCKED;
        }
        ls_core_owner_lost_alarm(core, addr, why, action, now_us);
    }
    if (connected_count(core) == 0 && !core->halt.active && !core->held) {
        core->state = ls_State_IDLE;
    }
}

void ls_core_on_heartbeat(ls_core_t *core, uint8_t addr, uint8_t counter, uint16_t period_ms, uint32_t token,
                          uint64_t now_us)
{
    int i = ls_core_session_of(core, addr);
    if (i < 0) {
        return; /* not ours: e.g. a supervisor of another device on this bus */
    }
    ls_session_t *s = &core->sessions[i];
    uint32_t full = 0;
    bool ok = token == s->hb_token;
    if (s->signed_session) {
        /* Anyone reads a token off the bus; only the key holder makes the MAC
         * of a counter newer than the last one (docs/protocol.md "Security"). */
        full = ls_auth_heartbeat_counter(s->hb_counter, counter);
        ok = ls_auth_heartbeat_mac(&s->key, addr, s->epoch, full, period_ms) == token;
    }
    if (!ok) {
        /* A bare heartbeat, or another client's on this address: it must not
         * keep alive a session whose supervisor is gone. */
        s->hb_refused++;
        core->hb_refused++;
        return;
    }
    s->hb_counter = full;
    s->last_heard_us = now_us;
}

int ls_core_session_link(const ls_core_t *core, uint8_t addr)
{
    const int i = ls_core_session_of(core, addr);
    return i >= 0 ? core->sessions[i].link : LS_NO_SESSION;
}

/* The session's heartbeat token: nonzero (a bare heartbeat never matches),
 * 24 bits, new at every connect. Not a secret (every node on the bus sees it
 * in the heartbeats): it tells clients apart, it does not authenticate them. */
static uint32_t heartbeat_token(uint64_t nonce, uint32_t epoch, uint64_t now_us)
{
    const uint64_t words[3] = { nonce, epoch, now_us };
    uint64_t h = 0xcbf29ce484222325u;
    for (size_t w = 0; w < 3; w++) {
        for (unsigned b = 0; b < 64u; b += 8u) {
            h = (h ^ ((words[w] >> b) & 0xFFu)) * 0x100000001b3u;
        }
    }
    uint32_t t = (uint32_t)((h ^ (h >> 24) ^ (h >> 48)) & LS_HB_TOKEN_MASK);
    return t != 0u ? t : 1u;
}

/* What a connect asks for: its heartbeat period and the disconnect action it
 * narrows the configured one to. */
typedef struct {
    uint32_t period_ms;
    uint32_t timeout_ms; /* the configured time-out, or LS_HB_MISSED_MAX periods when longer */
    ls_DisconnectAction action;
} connect_terms_t;

/* Check the request's protocol version, schema hash, heartbeat period and
 * disconnect action: LS_OK with *t filled, or the ret_code of the refusal
 * (answered). Changes no session. */
static int32_t connect_terms(ls_core_t *core, ls_call_t *call, connect_terms_t *t)
{
    const ls_ConnectReq *rq = &call->req->cmd.connect;
    if (call->connect_key == NULL && ls_core_policy(core) == ls_AuthPolicy_AUTH_SIGNED) {
        /* No session slot for a client that proved nothing (docs/protocol.md "Security"). */
        core->auth_connects_refused++;
        return ls_reply(call, ls_RetCode_CMD_AUTH_ERR,
                        "connect: this device serves signed supervisors only (policy signed): give the host one "
                        "of the keys of the device's key file (docs/protocol.md \"Security\")");
    }
    if (rq->protocol_version != (uint32_t)ls_Protocol_PROTOCOL_VERSION || rq->schema_hash != LS_SCHEMA_HASH) {
        /* The refusal carries the device's version and hash as numbers too
         * (ConnectRes), so no client has to read them out of the text. */
        call->res->which_result = ls_Response_connect_tag;
        call->res->result.connect.protocol_version = (uint32_t)ls_Protocol_PROTOCOL_VERSION;
        call->res->result.connect.schema_hash = LS_SCHEMA_HASH;
    }
    if (rq->protocol_version != (uint32_t)ls_Protocol_PROTOCOL_VERSION) {
        bool client_older = rq->protocol_version < (uint32_t)ls_Protocol_PROTOCOL_VERSION;
        return ls_reply(call, ls_RetCode_CMD_VERSION_MISMATCH_ERR,
                        "protocol version %u from the client, %u on the device: update the %s",
                        (unsigned)rq->protocol_version, (unsigned)ls_Protocol_PROTOCOL_VERSION,
                        client_older ? "client" : "firmware");
    }
    if (rq->schema_hash != LS_SCHEMA_HASH) {
        return ls_reply(call, ls_RetCode_CMD_VERSION_MISMATCH_ERR,
                        "schema %08X from the client, %08X on the device: build the client from the device's "
                        "protocol/landscape.proto, or update the firmware",
                        (unsigned)rq->schema_hash, (unsigned)LS_SCHEMA_HASH);
    }
    const uint32_t period_ms = rq->heartbeat_period_ms;
    if (period_ms != 0u && (period_ms < LS_HB_PERIOD_MIN_MS || period_ms > LS_HB_PERIOD_MAX_MS)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "connect: heartbeat_period_ms %u: allowed %u..%u (or 0: not stated, the device's time-out "
                        "of %u ms applies)",
                        (unsigned)period_ms, LS_HB_PERIOD_MIN_MS, LS_HB_PERIOD_MAX_MS,
                        (unsigned)core->cfg.heartbeat_timeout_ms);
    }
    const ls_DisconnectAction widest = configured_action(core);
    ls_DisconnectAction action = rq->disconnect_action;
    if (ls_core_disconnect_action_name(action) == NULL) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "connect: disconnect_action %d is not a DisconnectAction: allowed 0 (configured), 1 (stop), "
                        "2 (stop_deactivate), 3 (stop_deactivate_release)",
                        (int)action);
    }
    if (action == ls_DisconnectAction_DISCONNECT_CONFIGURED) {
        action = widest;
    } else if (action > widest) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "connect: disconnect_action %s is wider than the configured %s: a session may only "
                        "narrow it",
                        ls_core_disconnect_action_name(action), ls_core_disconnect_action_name(widest));
    }
    uint32_t timeout_ms = core->cfg.heartbeat_timeout_ms;
    if (period_ms * LS_HB_MISSED_MAX > timeout_ms) {
        timeout_ms = period_ms * LS_HB_MISSED_MAX;
    }
    *t = (connect_terms_t){ .period_ms = period_ms, .timeout_ms = timeout_ms, .action = action };
    return LS_OK;
}

/* The session slot of a connect from `addr`: the session this client has
 * there already (its cache cleared: a connect starts a new session, the host
 * restarts its seq; ownership stays), else a free one. LS_NO_SESSION with
 * *code the refusal (answered) when another client's session lives on the
 * address or every slot is taken; nothing of any session changes then. */
static int connect_slot(ls_core_t *core, uint8_t addr, ls_call_t *call, int32_t *code)
{
    const ls_ConnectReq *rq = &call->req->cmd.connect;
    int i = ls_core_session_of(core, addr);
    if (i >= 0 && core->sessions[i].nonce != rq->client_nonce) {
        /* Another client on a live session's address: it would take that
         * session's answers and ownership (docs/protocol.md "Identity"). Nothing
         * of that session changes, its cache included. */
        const ls_session_t *live = &core->sessions[i];
        call->sup = LS_NO_SESSION;
        call->res->session_epoch = 0u;
        core->connects_refused++;
        *code = ls_reply(call, ls_RetCode_CMD_NOT_OWNER_ERR,
                         "connect: address 0x%02X is in use by another client, \"%s\"%s: connect from an "
                         "address no live session uses",
                         addr, live->name, core->owner == i ? " (the owner)" : "");
        return LS_NO_SESSION;
    }
    if (i >= 0) {
        /* connect again from a connected address: a new session (new epoch, the
         * host restarts its seq), so the old retransmission cache must not
         * answer (or swallow) the new session's requests; ownership stays. */
        ls_session_t *old = &core->sessions[i];
        if (old->last_pending && core->halt.answer_sup == i) {
            core->halt.answer_sup = LS_NO_SESSION;
        }
        ls_send_session_ended(core, old);
        old->have_last = false;
        old->last_pending = false;
        old->last_resp_len = 0;
        old->notice_seq = 0;
        return i;
    }
    for (int k = 0; k < LS_MAX_SUPERVISORS; k++) {
        if (!core->sessions[k].connected) {
            memset(&core->sessions[k], 0, sizeof core->sessions[k]);
            return k;
        }
    }
    *code = ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                     "%d supervisors are already connected: disconnect one first", LS_MAX_SUPERVISORS);
    return LS_NO_SESSION;
}

/* Open session i for the connect's client: a new epoch and heartbeat token,
 * SI units, the terms it asked for. */
static void connect_open(ls_core_t *core, int i, uint8_t addr, const ls_call_t *call, const connect_terms_t *t)
{
    const ls_ConnectReq *rq = &call->req->cmd.connect;
    ls_session_t *s = &core->sessions[i];
    s->connected = true;
    s->addr = addr;
    s->epoch = core->epoch_next++;
    if (core->epoch_next == 0u) {
        core->epoch_next = 1u;
    }
    s->nonce = rq->client_nonce;
    s->hb_token = heartbeat_token(s->nonce, s->epoch, call->now_us);
    s->link = call->link;
    s->signed_session = call->connect_key != NULL;
    s->hb_counter = 0;
    if (call->connect_key != NULL) {
        s->key = *call->connect_key;
    } else {
        ls_auth_wipe(&s->key, sizeof s->key);
    }
    /* The supervisor cannot beat before this answer, which carries the token,
     * has reached it: the session counts as heard until the network layer
     * may have given up delivering it (docs/protocol.md "Liveness"). */
    s->last_heard_us = call->now_us + LS_CONNECT_ANSWER_GRACE_US;
    s->heartbeat_period_ms = t->period_ms;
    s->heartbeat_timeout_ms = t->timeout_ms;
    s->units = LS_UNITS_SI; /* every session starts in SI (docs/conformance.md, setUnits) */
    s->disconnect_action = t->action;
    ls_fmt_print(s->name, sizeof s->name, "%s", rq->client_name);
}

int32_t ls_session_connect(ls_core_t *core, uint8_t addr, ls_call_t *call)
{
    const ls_ConnectReq *rq = &call->req->cmd.connect;
    ls_ConnectRes *rs = &call->res->result.connect;
    call->res->which_result = ls_Response_connect_tag;
    rs->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    rs->schema_hash = LS_SCHEMA_HASH;
    ls_fmt_print(rs->device_name, sizeof rs->device_name, "%s", core->cfg.device_name);
    ls_fmt_print(rs->firmware_version, sizeof rs->firmware_version, "%s", core->cfg.firmware_version);
    rs->joint_count = core->cfg.joint_count;
    rs->heartbeat_timeout_ms = core->cfg.heartbeat_timeout_ms;
    rs->client_nonce = rq->client_nonce; /* an error carries no result: only an accepted connect's */
    rs->auth_policy = ls_core_policy(core);
    connect_terms_t t = { 0 };
    int32_t code = connect_terms(core, call, &t);
    if (code != LS_OK) {
        return code;
    }
    const int i = connect_slot(core, addr, call, &code);
    if (i == LS_NO_SESSION) {
        return code;
    }
    connect_open(core, i, addr, call, &t);
    const ls_session_t *s = &core->sessions[i];
    call->sup = i;
    if (core->held && core->held_addr == addr) {
        /* The lost owner is back: the kept lock is its own again. */
        core->held = false;
        core->owner = i;
    }
    if (core->state == ls_State_IDLE) {
        core->state = ls_State_UNLOCKED;
    }
    rs->session_epoch = s->epoch;
    rs->heartbeat_token = s->hb_token;
    rs->heartbeat_timeout_ms = t.timeout_ms;
    rs->disconnect_action = t.action;
    rs->linear_unit = s->units.linear;
    rs->angular_unit = s->units.angular;
    rs->state = core->state;
    rs->owner = core->owner == i;
    rs->session_signed = s->signed_session;
    if (s->signed_session) {
        /* the acceptance is the session's first signed message, in its epoch */
        core->tx_sign.set = true;
        core->tx_sign.addr = s->addr;
        core->tx_sign.key = &s->key;
        core->tx_sign.epoch = s->epoch;
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "connected to %s as 0x%02X%s", core->cfg.device_name, addr,
                    s->signed_session ? ", signed" : "");
}

int32_t ls_session_challenge(ls_core_t *core, uint8_t addr, ls_call_t *call)
{
    const ls_ChallengeReq *rq = &call->req->cmd.challenge;
    ls_ChallengeRes *rs = &call->res->result.challenge;
    ls_auth_t *auth = core->cfg.auth;
    call->res->which_result = ls_Response_challenge_tag;
    rs->auth_policy = ls_core_policy(core);
    ls_fmt_print(rs->key_id, sizeof rs->key_id, "%s", rq->key_id);
    if (rq->host_nonce.size != LS_AUTH_NONCE_BYTES) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "challenge: host_nonce has %u bytes, needs %u random ones (docs/protocol.md \"Security\")",
                        (unsigned)rq->host_nonce.size, (unsigned)LS_AUTH_NONCE_BYTES);
    }
    const int key = auth != NULL ? ls_auth_key_index(auth, rq->key_id) : LS_ENOENT;
    if (key < 0) {
        return ls_reply(call, ls_RetCode_CMD_AUTH_ERR,
                        "challenge: the device holds no key \"%s\" (%u keys in its key file): add it to the "
                        "device's key file, or give the host one it holds",
                        rq->key_id, auth != NULL ? (unsigned)auth->n_keys : 0u);
    }
    uint8_t nd[LS_AUTH_NONCE_BYTES];
    if (core->io.random == NULL || core->io.random(core->io.ctx, nd, sizeof nd) != LS_OK) {
        return ls_reply(call, ls_RetCode_CMD_ERR, "challenge: the device has no random source for its nonce");
    }
    (void)ls_auth_challenge_put(auth, addr, key, rq->host_nonce.bytes, nd, call->now_us);
    const ls_auth_challenge_t *c =
        ls_auth_challenge_find(auth, addr, rq->host_nonce.bytes, LS_AUTH_NONCE_BYTES, call->now_us);
    /* The answer is signed with the session key the connect will use, so the
     * host knows now whether both hold the same key. */
    ls_auth_session_key(auth, c, addr, core->cfg.node_addr, &core->connect_key);
    core->tx_sign.set = true;
    core->tx_sign.addr = addr;
    core->tx_sign.key = &core->connect_key;
    core->tx_sign.epoch = 0u;
    memcpy(rs->device_nonce.bytes, nd, sizeof nd);
    rs->device_nonce.size = (pb_size_t)sizeof nd;
    ls_auth_wipe(nd, sizeof nd);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "sign a connect with key \"%s\" within %u ms", rq->key_id,
                    (unsigned)ls_AuthParam_AUTH_CHALLENGE_TTL_MS);
}

int32_t ls_h_challenge(struct ls_core *core, struct ls_call *call)
{
    (void)core;
    return ls_reply(call, ls_RetCode_CMD_ERR, "challenge is handled by the dispatcher");
}

int32_t ls_h_connect(struct ls_core *core, struct ls_call *call)
{
    (void)core;
    (void)call;
    return ls_reply(call, ls_RetCode_CMD_ERR, "connect is handled by the dispatcher");
}

int32_t ls_h_disconnect(struct ls_core *core, struct ls_call *call)
{
    call->res->which_result = ls_Response_disconnect_tag;
    ls_session_drop(core, call->sup, "disconnect", call->now_us);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "disconnected");
}

void ls_session_tick(ls_core_t *core, uint64_t now_us)
{
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        ls_session_t *s = &core->sessions[i];
        const uint64_t limit = (uint64_t)s->heartbeat_timeout_ms * 1000u;
        if (s->connected && now_us > s->last_heard_us && now_us - s->last_heard_us > limit) {
            core->sessions_dropped++;
            ls_session_drop(core, i, "heartbeat lost", now_us);
        }
    }
}
