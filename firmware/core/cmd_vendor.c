/* Seed 4.1 sendCommand: the vendor hook. Sub-commands (docs/protocol.md):
 *   help     the list below
 *   version  firmware version, protocol version, schema hash
 *   status   state, owner, sessions and their counters
 *   faults   the flood counters, then the fault log (oldest first; the first entries and the latest)
 *   events   the event log (oldest first): RSVP answers with their data, time-outs, refused replies
 *   rtstats  the control loop: cycles, overruns, worst latency and cycle time, SCHED_FIFO, memory lock;
 *            the comms thread's wake-ups
 *   config   the running configuration (file and options merged)
 *   stopping the category-1 stop's bound per joint, from the robot model
 *   drives   the drives' readouts: a line per joint, `drives N` one in full, `drives bus` the master's counters
 *   home     the drives' own homing: `home` the joints that must be homed, `home 2 3` those (cmd_drives.h)
 * Output is plain text, one item per line, at most SendCommandRes.result's
 * size (protocol/landscape.options), which holds `status` at its longest. */
#include <string.h>

#include "cmd_drives.h"
#include "ls_core_services.h"
#include "ls_fmt.h"
#include "ls_motion.h"

typedef struct {
    char *buf;
    size_t cap, len;
} out_t;

#define put(o, ...) ls_fmt_append((o)->buf, (o)->cap, &(o)->len, __VA_ARGS__)

int32_t ls_h_send_command(struct ls_core *core, struct ls_call *call)
{
    const char *in = call->req->cmd.send_command.input;
    ls_SendCommandRes *r = &call->res->result.send_command;
    out_t o = { r->result, sizeof r->result, 0 };
    if (strcmp(in, "help") == 0 || in[0] == '\0') {
        put(&o, "help\nversion\nstatus\nsecurity\nfaults\nevents\nrtstats\nconfig\nstopping\ndrives\nhome\n");
    } else if (strcmp(in, "version") == 0) {
        put(&o, "firmware=%s\nprotocol=%u\nschema=%08X\n", core->cfg.firmware_version,
            (unsigned)ls_Protocol_PROTOCOL_VERSION, (unsigned)LS_SCHEMA_HASH);
    } else if (strcmp(in, "status") == 0) {
        put(&o, "state=%s\nowner=", ls_State_name(core->state));
        if (core->owner >= 0) {
            put(&o, "0x%02X\n", core->sessions[core->owner].addr);
        } else if (core->held) {
            put(&o, "0x%02X lost, lock kept (%s)\n", core->held_addr,
                ls_core_disconnect_action_name(core->held_action));
        } else {
            put(&o, "none\n");
        }
        put(&o, "fault=%s\nrx_malformed=%u\ntx_lost=%u\nsessions_dropped=%u\nhb_refused=%u\nconnects_refused=%u\n",
            core->fault, (unsigned)core->rx_malformed, (unsigned)core->tx_lost, (unsigned)core->sessions_dropped,
            (unsigned)core->hb_refused, (unsigned)core->connects_refused);
        for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
            const ls_session_t *s = &core->sessions[i];
            if (s->connected) {
                /* executed= stays last: tools read it as the line's tail */
                put(&o,
                    "session 0x%02X name=%s units=%s,%s heartbeat_timeout_ms=%u disconnect_action=%s hb_refused=%u "
                    "executed=%u\n",
                    s->addr, s->name, ls_units_linear_name(s->units.linear), ls_units_angular_name(s->units.angular),
                    (unsigned)s->heartbeat_timeout_ms, ls_core_disconnect_action_name(s->disconnect_action),
                    (unsigned)s->hb_refused, (unsigned)s->executed);
            }
        }
        for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
            const ls_dio_watch_t *w = &core->dio.watch[i];
            if (w->phase != LS_WATCH_FREE) {
                put(&o, "watch %u unit=%u bits=0x%X addr=0x%02X %s fired=%u\n", (unsigned)w->id, (unsigned)w->unit,
                    (unsigned)w->bits, w->addr, w->phase == LS_WATCH_ARMED ? "armed" : "awaiting_rsvp",
                    (unsigned)w->fired);
            }
        }
        ls_drv_status_lines(core, o.buf, o.cap, &o.len);
        /* the transport's counters last; the answer holds them whole after
         * every session, watch and drive line (LS_TRANSPORT_DESCRIBE_MAX) */
        if (core->io.describe != NULL && o.len < o.cap) {
            core->io.describe(core->io.ctx, o.buf + o.len, o.cap - o.len);
            o.len += strlen(o.buf + o.len);
        }
    } else if (strcmp(in, "faults") == 0) {
        uint32_t n = 0, dropped = 0;
        (void)ls_core_fault_entry(core, 0, &n, &dropped);
        /* first, one line: the counters of floods (docs/protocol.md "Budgets under floods") */
        put(&o, "logged=%u dropped=%u alarms_suppressed=%u emergency_frames=%u\n", (unsigned)core->fault_log_count,
            (unsigned)dropped, (unsigned)core->alarms_suppressed, (unsigned)core->emergency_frames);
        for (uint32_t k = 0; k < n; k++) {
            const ls_fault_entry_t *e = ls_core_fault_entry(core, k, NULL, NULL);
            if (k == LS_FAULT_LOG_FIRST && dropped > 0) {
                put(&o, "... %u entries dropped (the first %d and the latest %d are kept)\n", (unsigned)dropped,
                    LS_FAULT_LOG_FIRST, LS_FAULT_LOG_LATEST);
            }
            put(&o, "%llu.%03llu %s\n", (unsigned long long)(e->at_us / 1000000u),
                (unsigned long long)(e->at_us / 1000u % 1000u), e->text);
        }
        if (n == 0) {
            put(&o, "no faults\n");
        }

    } else if (strcmp(in, "events") == 0) {
        uint32_t n = core->event_log_count < LS_EVENT_LOG_LEN ? core->event_log_count : LS_EVENT_LOG_LEN;
        for (uint32_t k = core->event_log_count - n; k < core->event_log_count; k++) {
            const ls_event_entry_t *e = &core->event_log[k % LS_EVENT_LOG_LEN];
            put(&o, "%llu.%03llu %s\n", (unsigned long long)(e->at_us / 1000000u),
                (unsigned long long)(e->at_us / 1000u % 1000u), e->text);
        }
        if (n == 0) {
            put(&o, "no events\n");
        }
    } else if (strcmp(in, "home") == 0 || strncmp(in, "home ", 5) == 0) {
        return ls_drv_home(core, call, in + 4);
    } else if (strcmp(in, "drives") == 0 || strncmp(in, "drives ", 7) == 0) {
        const int32_t code = ls_drv_readouts(core, call, in + 6, o.buf, o.cap);
        if (code != ls_RetCode_CMD_EXEC_OK) {
            return code;
        }
    } else if (strcmp(in, "security") == 0) {
        /* docs/protocol.md "Security": the policy, what was refused, and the
         * link and signing of each session (never a key) */
        const ls_auth_t *auth = core->cfg.auth;
        put(&o,
            "policy=%s\nkeys=%u\nunsigned_queries=%s\nauth_refused=%u\nauth_stale=%u\nauth_connects_refused=%u\n"
            "functional_refused=%u\nanonymous_stops=%u\nchallenges_replaced=%u\n",
            ls_core_policy(core) == ls_AuthPolicy_AUTH_SIGNED ? "signed" : "unsigned",
            auth != NULL ? (unsigned)auth->n_keys : 0u, auth != NULL && auth->unsigned_queries ? "true" : "false",
            (unsigned)core->auth_refused, (unsigned)core->auth_stale, (unsigned)core->auth_connects_refused,
            (unsigned)core->functional_refused, (unsigned)core->anonymous_stops,
            auth != NULL ? (unsigned)auth->challenges_replaced : 0u);
        for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
            const ls_session_t *s = &core->sessions[i];
            if (s->connected) {
                put(&o, "session 0x%02X link=%d signed=%s auth_refused=%u\n", s->addr, s->link,
                    s->signed_session ? "yes" : "no", (unsigned)s->auth_refused);
            }
        }
    } else if (strcmp(in, "stopping") == 0) {
        if (core->model == NULL) {
            return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                            "sendCommand stopping: no arm model is composed in this firmware");
        }
        /* Emergency frame, e-stop input, faults, shutdown: docs/reliability.md. */
        for (int j = 0; j < LS_N_JOINTS; j++) {
            double t_s, d_rad;
            if (ls_motion_fast_stop_bound(core->model, j, &t_s, &d_rad) == 0) {
                put(&o, "j%d time_s=%.4f distance_rad=%.4f\n", j + 1, t_s, d_rad);
            }
        }
    } else if (strcmp(in, "rtstats") == 0 || strcmp(in, "config") == 0) {
        void (*fn)(void *, char *, size_t) = in[0] == 'r' ? core->act.describe_rt : core->act.describe_config;
        if (fn == NULL) {
            return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "sendCommand %s: this controller has no %s", in,
                            in[0] == 'r' ? "control loop" : "configuration to show");
        }
        fn(core->act.ctx, o.buf, o.cap);
    } else {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "sendCommand '%.40s': unknown; try 'help'", in);
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s", in[0] != '\0' ? in : "help");
}
