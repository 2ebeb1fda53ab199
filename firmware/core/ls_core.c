/* Sessions, ownership, state checks and dispatch: the one place where the
 * schema's valid states and owner rules are enforced (handlers never repeat
 * those checks). */
#include "ls_core.h"

#include "cmd_sensor.h"
#include "ls_control.h"
#include "ls_core_events.h"
#include "ls_fmt.h"
#include "ls_utf8.h"
#include "ls_wire.h"

#include "landscape.h"
#include "landscape_choices.h"

#include <stdarg.h>
#include <string.h>

#include <pb_decode.h>
#include <pb_encode.h>

/* The configured action, 0 meaning the seed's default. */
static ls_DisconnectAction configured_action(const ls_core_t *core)
{
    return core->cfg.disconnect_action == ls_DisconnectAction_DISCONNECT_CONFIGURED
               ? ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE
               : core->cfg.disconnect_action;
}

void ls_core_init(ls_core_t *core, const ls_core_config_t *cfg, const ls_core_io_t *io, const ls_core_actions_t *act)
{
    memset(core, 0, sizeof *core);
    core->cfg = *cfg;
    core->io = *io;
    if (act != NULL) {
        core->act = *act;
    }
    core->state = ls_State_IDLE;
    core->owner = LS_NO_SESSION;
    core->activating = LS_NO_SESSION;
    ls_fmt_print(core->motion_state, sizeof core->motion_state, "robot_at_rest");
    core->settings.speed_pct = 25.0;
    core->settings.accel_pct = 50.0;
    core->settings.linear_speed_m_s = 0.25;
    core->settings.angular_speed_rad_s = 1.0;
    core->settings.linear_accel_m_s2 = 1.0;
    core->settings.angular_accel_rad_s2 = 4.0;
    core->rsvp_next_id = 1;
    core->epoch_next = 1;
    core->run.path = LS_PATH_NONE;
    core->halt.answer_sup = LS_NO_SESSION;
    ls_fmt_print(core->sensor.mode, sizeof core->sensor.mode, "off");
    core->sensor.sup = LS_NO_SESSION;
    core->sensor.kind = -1;
    ls_fmt_print(core->tool_cmds.held, sizeof core->tool_cmds.held, "none");
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
static void drop_session(ls_core_t *core, int i, const char *why, uint64_t now_us)
{
    ls_session_t *s = &core->sessions[i];
    bool was_owner = core->owner == i;
    uint8_t addr = s->addr;
    s->connected = false;
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

void ls_core_on_heartbeat(ls_core_t *core, uint8_t addr, uint32_t token, uint64_t now_us)
{
    int i = ls_core_session_of(core, addr);
    if (i < 0) {
        return; /* not ours: e.g. a supervisor of another device on this bus */
    }
    ls_session_t *s = &core->sessions[i];
    if (token != s->hb_token) {
        /* A bare heartbeat, or another client's on this address: it must not
         * keep alive a session whose supervisor is gone. */
        s->hb_refused++;
        core->hb_refused++;
        return;
    }
    s->last_heard_us = now_us;
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

/* What a joint's drive reported (an EMCY, its error code read back): in
 * the fault log, and to every supervisor (docs/protocol.md "Drives"). */
static void on_arm_event(ls_core_t *core, const hal_arm_event_t *e, uint64_t now_us)
{
    ls_core_log_fault(core, now_us, "joint %u (node 0x%02X): %s", (unsigned)e->joint + 1u, (unsigned)e->node, e->text);
    char joint[16], node[16], code[16], meaning[72], reg[16], vendor[24];
    ls_fmt_print(joint, sizeof joint, "joint=%u", (unsigned)e->joint + 1u);
    ls_fmt_print(node, sizeof node, "node=0x%02X", (unsigned)e->node);
    ls_fmt_print(code, sizeof code, "code=0x%04X", (unsigned)e->code);
    ls_fmt_print(meaning, sizeof meaning, "meaning=%s", e->meaning);
    if (e->is_emcy) {
        ls_fmt_print(reg, sizeof reg, "register=0x%02X", (unsigned)e->reg);
        ls_fmt_print(vendor, sizeof vendor, "vendor=%02X%02X%02X%02X%02X", (unsigned)e->vendor[0],
                     (unsigned)e->vendor[1], (unsigned)e->vendor[2], (unsigned)e->vendor[3], (unsigned)e->vendor[4]);
        const char *data[] = { joint, node, code, meaning, reg, vendor };
        ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_driveEmcy, 0, false, data, 6);
    } else {
        const char *data[] = { joint, node, code, meaning };
        ls_core_notify(core, LS_ALL_SESSIONS, ls_NoticeKind_EVENT, ls_EventId_driveErrorCode, 0, false, data, 4);
    }
}

/* The one route of the control loop's events into the core. The moves,
 * jogs and tool changes that cmd_sensor.c and cmd_tool.c started take
 * their own events first; the rest go to the motion executor's side
 * (cmd_motion_events.c), the fault latch and the DIO watches. */
static void on_loop_event(ls_core_t *core, const ls_ctl_event_t *ev, uint64_t now_us)
{
    if (ls_core_tool_on_event(core, ev) || ls_core_sensor_on_event(core, ev)) {
        return;
    }
    switch (ev->kind) {
    case LS_CEV_MOTION: ls_core_on_motion_event(core, &ev->motion); break;
    case LS_CEV_FAULT: ls_core_fault(core, ev->text, now_us); break; /* its halt ends the motion */
    case LS_CEV_DIO_CHANGED: ls_core_on_dio_event(core, ev->dio.unit, ev->dio.on, ev->dio.off, now_us); break;
    case LS_CEV_ARM_EVENT: on_arm_event(core, &ev->arm, now_us); break;
    case LS_CEV_ENABLED: ls_core_on_enable_result(core, NULL, now_us); break;
    case LS_CEV_ENABLE_FAILED: ls_core_on_enable_result(core, ev->text, now_us); break;
    case LS_CEV_MANUAL: break; /* cmd_sensor.c takes them all */
    case LS_CEV_CMD_FAILED: {
        char d[80];
        ls_fmt_print(d, sizeof d, "reason=%s", ev->text);
        const char *data[] = { d };
        ls_core_notify(core, core->owner, ls_NoticeKind_ALARM, ls_EventId_commandFailed, ev->ref_seq, false, data, 1);
        ls_core_motion_failed(core, ev->ref_seq, ev->text);
        if (core->act.log_warn != NULL) {
            char line[112];
            ls_fmt_print(line, sizeof line, "control loop: %s", ev->text);
            core->act.log_warn(core->act.ctx, line);
        }
        break;
    }
    }
}

void ls_core_take_loop_events(ls_core_t *core, uint64_t now_us)
{
    if (core->ctl != NULL) {
        ls_ctl_event_t ev;
        while (ls_control_next_event(core->ctl, &ev)) {
            on_loop_event(core, &ev, now_us);
        }
    }
}

void ls_core_tick(ls_core_t *core, uint64_t now_us)
{
    ls_core_take_loop_events(core, now_us);
    ls_rsvp_tick(core, now_us);
    ls_log_alarm_tick(core, now_us);
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        ls_session_t *s = &core->sessions[i];
        const uint64_t limit = (uint64_t)s->heartbeat_timeout_ms * 1000u;
        if (s->connected && now_us > s->last_heard_us && now_us - s->last_heard_us > limit) {
            core->sessions_dropped++;
            drop_session(core, i, "heartbeat lost", now_us);
        }
    }
    ls_run_tick(core, now_us);
    ls_dio_tick(core, now_us);
    ls_core_motion_tick(core, now_us);
}

uint64_t ls_core_next_deadline_us(const ls_core_t *core, uint64_t now_us)
{
    uint64_t t = ls_dio_next_deadline_us(core, now_us);
    const uint64_t sample = now_us + LS_CORE_SAMPLE_US;
    if (core->halt.active) {
        t = sample < t ? sample : t; /* ls_run_tick: at rest yet? */
    }
    if (core->run.active && !core->run.react && core->ctl != NULL && (core->run.dio_pending || core->run.wait_active)) {
        t = sample < t ? sample : t; /* ls_core_motion_tick: the DIO of a path's aux command */
    }
    for (int i = 0; i < LS_MAX_RSVP; i++) {
        if (core->rsvp[i].used && core->rsvp[i].deadline_us < t) {
            t = core->rsvp[i].deadline_us;
        }
    }
    if (core->alarm_window.open) {
        const uint64_t end = core->alarm_window.since_us + (uint64_t)LS_ALARM_WINDOW_MS * 1000u;
        t = end < t ? end : t;
    }
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        const ls_session_t *s = &core->sessions[i];
        if (s->connected) {
            /* ls_core_tick drops it once more than the time-out has passed */
            const uint64_t lost = s->last_heard_us + (uint64_t)s->heartbeat_timeout_ms * 1000u + 1u;
            t = lost < t ? lost : t;
        }
    }
    return t;
}

/* ---- connect / disconnect: the only commands that create or end a session */

static int32_t do_connect(ls_core_t *core, uint8_t addr, ls_call_t *call)
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
    if (rq->protocol_version != (uint32_t)ls_Protocol_PROTOCOL_VERSION) {
        bool host_older = rq->protocol_version < (uint32_t)ls_Protocol_PROTOCOL_VERSION;
        return ls_reply(call, ls_RetCode_CMD_VERSION_MISMATCH_ERR,
                        "protocol version %u on the host, %u on the device: update the %s",
                        (unsigned)rq->protocol_version, (unsigned)ls_Protocol_PROTOCOL_VERSION,
                        host_older ? "host tool" : "firmware");
    }
    if (rq->schema_hash != LS_SCHEMA_HASH) {
        return ls_reply(call, ls_RetCode_CMD_VERSION_MISMATCH_ERR,
                        "schema %08X on the host, %08X on the device: install the host tool built from the "
                        "firmware's tree (or update the firmware)",
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
    int i = ls_core_session_of(core, addr);
    if (i >= 0 && core->sessions[i].nonce != rq->client_nonce) {
        /* Another client on a live session's address: it would take that
         * session's answers and ownership (docs/protocol.md "Identity"). Nothing
         * of that session changes, its cache included. */
        const ls_session_t *live = &core->sessions[i];
        call->sup = LS_NO_SESSION;
        call->res->session_epoch = 0u;
        core->connects_refused++;
        return ls_reply(call, ls_RetCode_CMD_NOT_OWNER_ERR,
                        "connect: address 0x%02X is in use by another client, \"%s\"%s: pass another "
                        "--source-address, or none to let the host pick a free one",
                        addr, live->name, core->owner == i ? " (the owner)" : "");
    }
    if (i < 0) {
        for (int k = 0; k < LS_MAX_SUPERVISORS; k++) {
            if (!core->sessions[k].connected) {
                i = k;
                break;
            }
        }
        if (i < 0) {
            return ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                            "%d supervisors are already connected: disconnect one first", LS_MAX_SUPERVISORS);
        }
        bool was_owner_slot = core->owner == i;
        memset(&core->sessions[i], 0, sizeof core->sessions[i]);
        (void)was_owner_slot;
    } else {
        /* connect again from a connected address: a new session (new epoch, the
         * host restarts its seq), so the old retransmission cache must not
         * answer (or swallow) the new session's requests; ownership stays. */
        ls_session_t *old = &core->sessions[i];
        if (old->last_pending && core->halt.answer_sup == i) {
            core->halt.answer_sup = LS_NO_SESSION;
        }
        old->have_last = false;
        old->last_pending = false;
        old->last_resp_len = 0;
        old->notice_seq = 0;
    }
    ls_session_t *s = &core->sessions[i];
    s->connected = true;
    s->addr = addr;
    s->epoch = core->epoch_next++;
    if (core->epoch_next == 0u) {
        core->epoch_next = 1u;
    }
    rs->session_epoch = s->epoch;
    s->nonce = rq->client_nonce;
    s->hb_token = heartbeat_token(s->nonce, s->epoch, call->now_us);
    rs->heartbeat_token = s->hb_token;
    /* The supervisor cannot beat before this answer, which carries the token,
     * has reached it: the session counts as heard until the network layer
     * may have given up delivering it (docs/protocol.md "Liveness"). */
    s->last_heard_us = call->now_us + LS_CONNECT_ANSWER_GRACE_US;
    s->heartbeat_period_ms = period_ms;
    s->heartbeat_timeout_ms = timeout_ms;
    s->units = LS_UNITS_SI; /* every session starts in SI (docs/conformance.md, setUnits) */
    s->disconnect_action = action;
    ls_fmt_print(s->name, sizeof s->name, "%s", rq->client_name);
    call->sup = i;
    if (core->held && core->held_addr == addr) {
        /* The lost owner is back: the kept lock is its own again. */
        core->held = false;
        core->owner = i;
    }
    rs->heartbeat_timeout_ms = timeout_ms;
    rs->disconnect_action = action;
    rs->linear_unit = s->units.linear;
    rs->angular_unit = s->units.angular;
    if (core->state == ls_State_IDLE) {
        core->state = ls_State_UNLOCKED;
    }
    rs->state = core->state;
    rs->owner = core->owner == i;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "connected to %s as 0x%02X", core->cfg.device_name, addr);
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
    drop_session(core, call->sup, "disconnect", call->now_us);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "disconnected");
}

/* ---- dispatch */

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
                        "command id %u is not in this firmware's schema: update the firmware or the host tool",
                        (unsigned)rq->which_cmd);
    }
    if (rq->which_cmd == ls_Request_connect_tag) {
        return check_presence(call, d, rq) != 0 ? ls_RetCode_CMD_PARAM_ERR : do_connect(core, addr, call);
    }
    if (call->sup < 0) {
        return ls_reply(call, ls_RetCode_CMD_NOT_CONNECTED_ERR,
                        "%s: supervisor 0x%02X has no session: send connect first", d->name, addr);
    }
    if ((d->states & (uint8_t)core->state) == 0u) {
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

static void answer_bad_request(ls_core_t *core, uint8_t addr, int32_t code, uint32_t seq, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

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

static void on_request(ls_core_t *core, uint8_t addr, ls_Request *rq, const uint8_t *raw, size_t raw_len,
                       uint64_t now_us)
{
    int sup = ls_core_session_of(core, addr);
    ls_session_t *s = sup >= 0 ? &core->sessions[sup] : NULL;
    const uint64_t hash = request_hash(raw, raw_len);
    if (rq->seq == 0u && rq->which_cmd != ls_Request_connect_tag) {
        /* seq 0 is what proto3 sends when the client set none: such a request
         * could never be told from a retransmission of the one before it
         * (docs/protocol.md "Sequence numbers"). Not cached, nothing runs. */
        const ls_cmd_desc_t *d = ls_cmd_find(rq->which_cmd);
        answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, 0u,
                           "%s: seq is 0 (not set): every request but connect needs a seq > 0, a new one "
                           "for each request (docs/protocol.md \"Sequence numbers\")",
                           d != NULL ? d->name : "request");
        return;
    }
    if (s != NULL && s->have_last && rq->seq == s->last_seq && rq->which_cmd != ls_Request_connect_tag &&
        hash != s->last_req_hash) {
        /* The same seq, another request: answering from the cache would
         * silently not run it (docs/protocol.md "Sequence numbers"). */
        const ls_cmd_desc_t *prev = ls_cmd_find(s->last_tag);
        const ls_cmd_desc_t *now = ls_cmd_find(rq->which_cmd);
        answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, rq->seq,
                           "seq %u reused with a different request (previous: %s, now: %s): use a new seq; "
                           "only a retransmission repeats one",
                           (unsigned)rq->seq, prev != NULL ? prev->name : "?", now != NULL ? now->name : "request");
        return;
    }
    const bool connect_again = rq->which_cmd == ls_Request_connect_tag && s != NULL && s->have_last &&
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
            ls_send_bytes(core, addr, s->last_resp, s->last_resp_len);
        }
        return;
    }
    if (s != NULL && s->last_pending && rq->which_cmd != ls_Request_connect_tag &&
        rq->which_cmd != ls_Request_disconnect_tag) {
        /* One request in flight per session: the deferred one keeps its
         * answer slot; this one is refused without running. */
        const ls_cmd_desc_t *pd = ls_cmd_find(s->pending_tag);
        memset(&core->down, 0, sizeof core->down);
        core->down.which_msg = ls_Downlink_response_tag;
        ls_Response *busy = &core->down.msg.response;
        busy->seq = rq->seq;
        busy->session_epoch = s->epoch;
        busy->ret_code = ls_RetCode_CMD_BUSY_ERR;
        ls_fmt_text(busy->ret_msg, sizeof busy->ret_msg, "%s (seq %u) is still running: wait for its answer",
                    pd != NULL ? pd->name : "a blocking command", (unsigned)s->last_seq);
        size_t len = ls_send_encode(&core->down, core->enc, sizeof core->enc);
        if (len > 0) {
            ls_send_bytes(core, addr, core->enc, len);
        }
        return;
    }
    memset(&core->down, 0, sizeof core->down);
    core->down.which_msg = ls_Downlink_response_tag;
    ls_Response *res = &core->down.msg.response;
    res->seq = rq->seq;
    ls_call_t call = { .core = core, .sup = sup, .req = rq, .res = res, .now_us = now_us };
    /* disconnect ends the session it answers: its answer still carries that epoch */
    res->session_epoch = s != NULL ? s->epoch : 0u;
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
    if (code < 0) {
        res->which_result = 0; /* no result on errors */
    }
    ls_send_response(core, s, addr);
}

/* Read the seq and the command's field number of an ls.Uplink without
 * decoding it: used when the full decode failed (an oversize value) or the
 * command is unknown to this schema (nanopb drops unknown fields), so that
 * the answer still carries the request's seq and names the command. */
static bool scan_request(const uint8_t *buf, size_t len, uint32_t *seq, uint32_t *cmd)
{
    pb_istream_t s = pb_istream_from_buffer(buf, len);
    *seq = 0;
    *cmd = 0;
    for (;;) {
        pb_wire_type_t wt;
        uint32_t tag;
        bool eof = false;
        if (!pb_decode_tag(&s, &wt, &tag, &eof)) {
            return false;
        }
        if (tag == ls_Uplink_request_tag && wt == PB_WT_STRING) {
            pb_istream_t sub;
            if (!pb_make_string_substream(&s, &sub)) {
                return false;
            }
            bool ok = true;
            while (ok && sub.bytes_left > 0) {
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
        if (!pb_skip_field(&s, wt)) {
            return false;
        }
    }
}

static void answer_bad_request(ls_core_t *core, uint8_t addr, int32_t code, uint32_t seq, const char *fmt, ...)
{
    memset(&core->down, 0, sizeof core->down);
    core->down.which_msg = ls_Downlink_response_tag;
    ls_Response *res = &core->down.msg.response;
    res->seq = seq;
    res->ret_code = code;
    /* Every answer carries the epoch of the session it answers (docs/protocol.md). */
    const int sup = ls_core_session_of(core, addr);
    res->session_epoch = sup >= 0 ? core->sessions[sup].epoch : 0u;
    va_list ap;
    va_start(ap, fmt);
    ls_fmt_vtext(res->ret_msg, sizeof res->ret_msg, fmt, ap);
    va_end(ap);
    ls_send_response(core, NULL, addr);
}

void ls_core_on_uplink(ls_core_t *core, uint8_t addr, const uint8_t *buf, size_t len, uint64_t now_us)
{
    ls_core_take_loop_events(core, now_us); /* answer from the state as of the request's arrival */
    memset(&core->up, 0, sizeof core->up);
    pb_istream_t is = pb_istream_from_buffer(buf, len);
    uint32_t seq = 0, cmd = 0;
    if (!pb_decode(&is, ls_Uplink_fields, &core->up)) {
        core->rx_malformed++;
        /* Answer so the host does not wait for a time-out. */
        bool scanned = scan_request(buf, len, &seq, &cmd);
        const ls_cmd_desc_t *d = scanned ? ls_cmd_find((pb_size_t)cmd) : NULL;
        char where[120];
        ls_wire_fault_t fault = ls_wire_find_overflow(ls_Uplink_fields, &core->up, buf, len, where, sizeof where);
        if (fault != LS_WIRE_FITS) {
            /* "request." is the envelope: name the field as the command has it */
            const char *field = strncmp(where, "request.", 8) == 0 ? where + 8 : where;
            answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, seq, "%s did not decode (%s): %s %s",
                               d != NULL ? d->name : "the message", PB_GET_ERROR(&is), field,
                               fault == LS_WIRE_SIZE ? "(protocol/landscape.options): send fewer"
                                                     : "(the schema's type): send a value it holds");
            return;
        }
        answer_bad_request(core, addr, ls_RetCode_CMD_PARAM_ERR, seq,
                           "%s did not decode (%s): a value exceeds the firmware's limits "
                           "(protocol/landscape.options) or the schemas differ",
                           d != NULL ? d->name : "the message", PB_GET_ERROR(&is));
        return;
    }
    if (core->up.which_msg == ls_Uplink_request_tag && core->up.msg.request.which_cmd == 0) {
        (void)scan_request(buf, len, &seq, &cmd);
        if (cmd != 0u) {
            answer_bad_request(core, addr, ls_RetCode_CMD_UNKNOWN_CMD_ERR, core->up.msg.request.seq,
                               "command id %u is not in this firmware's schema: update the firmware or the "
                               "host tool (they must come from the same tree)",
                               (unsigned)cmd);
        } else {
            answer_bad_request(core, addr, ls_RetCode_CMD_UNKNOWN_CMD_ERR, core->up.msg.request.seq,
                               "the request carries no command: the host tool must set one");
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
        }
        return;
    }
    if (core->up.which_msg == ls_Uplink_request_tag) {
        on_request(core, addr, &core->up.msg.request, buf, len, now_us);
    } else if (core->up.which_msg == ls_Uplink_rsvp_reply_tag) {
        /* Only HEARTBEAT frames keep a session (docs/protocol.md "Liveness"). */
        ls_rsvp_on_reply(core, addr, &core->up.msg.rsvp_reply, now_us);
    } else {
        core->rx_malformed++;
    }
}
