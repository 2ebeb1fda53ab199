/* Whole request sequences against the core (a stateful fuzzer).
 *
 * The input is a program of steps: a request of any command kind from one of
 * four supervisors (every field of its message filled from the input, names
 * from a small pool so that paths and points meet again; seq new, repeated as
 * a retransmission, reused with another request, or 0), a heartbeat, time
 * passing (the control loop runs on a perfectly tracking arm, a DIO unit and
 * a force sensor), an RSVP reply, an input edge, a force reading, an
 * emergency frame, a fault, raw bytes. The core, its handlers, ls_run and the
 * control loop with the motion executor run as landscaped composes them
 * (firmware/app/landscaped.c), in one thread.
 *
 * After every step the invariants of docs/state-machine.md and
 * docs/protocol.md are checked, and a violation traps:
 *  - every downlink decodes, carries valid UTF-8 and fits LS_DOWNLINK_MAX;
 *  - exactly one answer per request: at once, or later for a deferred one
 *    (one in flight per session), never an answer nobody asked for;
 *  - the state is one of the schema's, the owner a live session; UNLOCKED
 *    has no owner, a connected supervisor means not IDLE, a run means
 *    MOVING or PAUSED;
 *  - a final notice only for a request answered CMD_STARTED_OK (or a DIO
 *    watch), at most one per run; once the core is quiet, exactly one;
 *  - a deferred answer comes while its session lives and the loop runs;
 *  - the loop's command ring never holds more than its size.
 *
 * Every input starts from ls_core_init and ls_control_init: the core keeps
 * all its state in ls_core_t, so nothing carries from one input into the
 * next. The tool changer and jogging are not composed (no hal_tool_t,
 * hal_manual_t): their commands answer CMD_UNSUPPORTED_ERR here. */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <pb_common.h>
#include <pb_decode.h>
#include <pb_encode.h>

#include "ls_control.h"
#include "ls_core.h"
#include "ls_utf8.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define N_SUP 4
#define RATE_HZ 100u
#define CYCLE_US (1000000u / RATE_HZ)
#define MAX_CYCLES_PER_STEP 100u /* then the loop "stalls" and time jumps */
#define DRAIN_US 6000000u        /* how long the core may take to become quiet at the end */
#define MAX_DOWNLINKS_PER_STEP 64u
#define LEDGER_LEN 2048u

static const uint8_t k_addr[N_SUP] = { 0xF1, 0xF2, 0x21, 0x05 };

/* ---------------------------------------------------------------- input */

/* The input is a sequence of steps [op][n][n argument bytes]; a step reads
 * its own arguments only (0 once they run out), so a mutation stays within
 * its step. */
static const uint8_t *g_in;
static size_t g_left; /* in the current step */

static uint8_t take8(void)
{
    if (g_left == 0) {
        return 0;
    }
    g_left--;
    return *g_in++;
}

static uint32_t take32(void)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; i++) {
        v = v << 8 | take8();
    }
    return v;
}

/* ---------------------------------------------------------------- devices */

static double g_q[LS_N_JOINTS], g_qd[LS_N_JOINTS];
static bool g_enabled;
static uint32_t g_dio_levels; /* bits 0..7 inputs, 8..15 outputs */
static double g_force[6];

static int arm_info(void *self, hal_arm_info_t *out)
{
    (void)self;
    memset(out, 0, sizeof *out);
    out->n_joints = LS_N_JOINTS;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        out->q_min_rad[j] = -10.0;
        out->q_max_rad[j] = 10.0;
        out->torque_max_Nm[j] = 100.0;
    }
    return LS_OK;
}

static int arm_enable(void *self, bool on)
{
    (void)self;
    g_enabled = on;
    return LS_OK;
}

static int arm_command(void *self, const double *q, const double *qd)
{
    (void)self;
    if (g_enabled) { /* a perfect drive: it is where it was told */
        memcpy(g_q, q, sizeof g_q);
        memcpy(g_qd, qd, sizeof g_qd);
    } else {
        memset(g_qd, 0, sizeof g_qd);
    }
    return LS_OK;
}

static int arm_read(void *self, double *q, double *qd)
{
    (void)self;
    memcpy(q, g_q, sizeof g_q);
    memcpy(qd, g_qd, sizeof g_qd);
    return LS_OK;
}

static const hal_arm_ops_t k_arm_ops = {
    .info = arm_info, .enable = arm_enable, .command = arm_command, .read = arm_read
};

static int dio_units(void *self)
{
    (void)self;
    return 1;
}

static int dio_describe(void *self, uint16_t unit, hal_dio_unit_info_t *out)
{
    (void)self;
    if (unit != 0) {
        return LS_EINVAL;
    }
    out->input_mask = 0x00FFu;
    out->output_mask = 0xFF00u;
    return LS_OK;
}

static int dio_read(void *self, uint16_t unit, uint32_t *bits)
{
    (void)self;
    if (unit != 0) {
        return LS_EINVAL;
    }
    *bits = g_dio_levels;
    return LS_OK;
}

static int dio_write(void *self, uint16_t unit, uint32_t on, uint32_t off)
{
    (void)self;
    if (unit != 0 || ((on | off) & ~0xFF00u) != 0u) {
        return LS_EINVAL;
    }
    g_dio_levels = (g_dio_levels | on) & ~off;
    return LS_OK;
}

static int dio_poll_fd(void *self)
{
    (void)self;
    return -1;
}

static const hal_dio_ops_t k_dio_ops = {
    .unit_count = dio_units, .describe = dio_describe, .read = dio_read, .write = dio_write, .poll_fd = dio_poll_fd
};

static int force_read(void *self, double *values)
{
    (void)self;
    memcpy(values, g_force, sizeof g_force);
    return LS_OK;
}

/* ---------------------------------------------------------------- the composition */

static ls_core_t g_core;
static ls_control_t g_ctl;
static hal_arm_t g_arm;
static hal_dio_t g_dio;
static hal_sensor_t g_sensor;
static uint64_t g_now;

/* ---------------------------------------------------------------- the ledger: what the supervisors saw */

typedef struct {
    uint8_t addr;
    uint32_t seq, epoch;
    pb_size_t tag;   /* command */
    int32_t code;    /* its answer */
    uint32_t finals; /* final notices that named it */
} answered_t;

static answered_t g_answered[LEDGER_LEN];
static size_t g_n_answered;
static bool g_ledger_full;

typedef struct {
    bool active;
    uint32_t seq, epoch;
    pb_size_t tag;
} deferred_t;

static deferred_t g_deferred[N_SUP]; /* by supervisor index */

static bool g_in_request; /* a request is being delivered: its own answer is expected */
static bool g_req_any;    /* raw bytes: whatever seq the answer carries */
static int g_req_sup;
static uint32_t g_req_seq;
static unsigned g_req_answers;
static ls_Response g_req_resp; /* that answer */
static unsigned g_step_downlinks;
static uint32_t g_last_rsvp[N_SUP];
static uint32_t g_token[N_SUP]; /* each supervisor's heartbeat token (its last ConnectRes) */
static ls_Downlink g_dl;        /* scratch: large */

static int sup_of_addr(uint8_t addr)
{
    for (int i = 0; i < N_SUP; i++) {
        if (k_addr[i] == addr) {
            return i;
        }
    }
    return -1;
}

static answered_t *find_answered(uint8_t addr, uint32_t seq, uint32_t epoch)
{
    for (size_t i = g_n_answered; i-- > 0;) {
        answered_t *a = &g_answered[i];
        if (a->addr == addr && a->seq == seq && a->epoch == epoch) {
            return a;
        }
    }
    return NULL;
}

static void note_answer(uint8_t addr, const ls_Response *r, pb_size_t tag)
{
    answered_t *seen = find_answered(addr, r->seq, r->session_epoch);
    if (seen != NULL) {
        if (seen->code == ls_RetCode_CMD_BUSY_ERR && r->ret_code != ls_RetCode_CMD_BUSY_ERR) {
            /* the earlier answer refused it while another request was
             * deferred, which the device does not cache: the same seq sent
             * again ran this time */
            *seen =
                (answered_t){ .addr = addr, .seq = r->seq, .epoch = r->session_epoch, .tag = tag, .code = r->ret_code };
        }
        return; /* else the cache answering a retransmission */
    }
    if (g_n_answered == LEDGER_LEN) {
        g_ledger_full = true;
        return;
    }
    g_answered[g_n_answered++] =
        (answered_t){ .addr = addr, .seq = r->seq, .epoch = r->session_epoch, .tag = tag, .code = r->ret_code };
}

static void on_response(uint8_t addr, const ls_Response *r)
{
    const int sup = sup_of_addr(addr);
    if (sup < 0) {
        __builtin_trap(); /* an answer to an address that never asked */
    }
    if (r->ret_code >= 0 && r->which_result == ls_Response_connect_tag) {
        g_token[sup] = r->result.connect.heartbeat_token;
    }
    if (g_in_request && sup == g_req_sup && (r->seq == g_req_seq || g_req_any)) {
        g_req_answers++;
        if (g_req_answers > 1) {
            __builtin_trap(); /* two answers to one request */
        }
        g_req_resp = *r; /* recorded by the caller, which knows the command */
        return;
    }
    deferred_t *d = &g_deferred[sup];
    if (!d->active || d->seq != r->seq) {
        __builtin_trap(); /* an answer nobody waits for */
    }
    d->active = false;
    note_answer(addr, r, d->tag);
}

static void on_notice(uint8_t addr, const ls_Notice *n)
{
    const int sup = sup_of_addr(addr);
    if (sup < 0) {
        __builtin_trap();
    }
    if (n->rsvp_id != 0u) {
        g_last_rsvp[sup] = n->rsvp_id;
    }
    if (!n->final || n->ref_seq == 0u) {
        return;
    }
    answered_t *a = find_answered(addr, n->ref_seq, n->session_epoch);
    if (a == NULL && g_in_request && sup == g_req_sup && g_req_answers > 0u && n->ref_seq == g_req_resp.seq &&
        n->session_epoch == g_req_resp.session_epoch) {
        /* the request being answered: note its answer first */
        note_answer(addr, &g_req_resp, g_req_resp.which_result);
        a = find_answered(addr, n->ref_seq, n->session_epoch);
    }
    if (a == NULL) {
        if (!g_ledger_full) {
            __builtin_trap(); /* a final notice for a request that was never answered */
        }
        return;
    }
    if (a->tag != ls_Request_signal_digital_io_tag) {
        if (a->code != ls_RetCode_CMD_STARTED_OK) {
            __builtin_trap(); /* a final notice for a motion that never started */
        }
        if (++a->finals > 1u) {
            __builtin_trap(); /* a run ended twice */
        }
    }
}

/* FUZZ_SESSION_TRACE=1 in the environment: every answer and notice on stderr
 * (to read what an input does, e.g. a crash's reproducer). */
static bool g_trace;

static void trace(uint8_t addr, const ls_Downlink *dl)
{
    if (dl->which_msg == ls_Downlink_response_tag) {
        const ls_Response *r = &dl->msg.response;
        fprintf(stderr, "t=%llu 0x%02X <- seq %u epoch %u code %d: %s\n", (unsigned long long)g_now, addr,
                (unsigned)r->seq, (unsigned)r->session_epoch, (int)r->ret_code, r->ret_msg);
    } else if (dl->which_msg == ls_Downlink_notice_tag) {
        const ls_Notice *n = &dl->msg.notice;
        fprintf(stderr, "t=%llu 0x%02X <- notice %s ref %u epoch %u%s %s\n", (unsigned long long)g_now, addr,
                n->event_id, (unsigned)n->ref_seq, (unsigned)n->session_epoch, n->final ? " final" : "",
                n->data_count > 0 ? n->data[0] : "");
    }
}

static int send_downlink(void *ctx, uint8_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    if (len == 0 || len > LS_DOWNLINK_MAX || ++g_step_downlinks > MAX_DOWNLINKS_PER_STEP) {
        __builtin_trap();
    }
    memset(&g_dl, 0, sizeof g_dl);
    pb_istream_t is = pb_istream_from_buffer(buf, len);
    if (!pb_decode(&is, ls_Downlink_fields, &g_dl) || !ls_utf8_check_msg(ls_Downlink_fields, &g_dl, NULL, 0)) {
        __builtin_trap(); /* the device sent what a supervisor cannot read */
    }
    if (g_trace) {
        trace(addr, &g_dl);
    }
    switch (g_dl.which_msg) {
    case ls_Downlink_response_tag: on_response(addr, &g_dl.msg.response); break;
    case ls_Downlink_notice_tag: on_notice(addr, &g_dl.msg.notice); break;
    case ls_Downlink_rsvp_ack_tag: break;
    default: __builtin_trap();
    }
    return 0;
}

/* ---------------------------------------------------------------- invariants */

static void check_state(void)
{
    const ls_core_t *c = &g_core;
    switch (c->state) {
    case ls_State_IDLE:
    case ls_State_UNLOCKED:
    case ls_State_LOCKED:
    case ls_State_RESTING:
    case ls_State_MOVING:
    case ls_State_PAUSED: break;
    case ls_State_STATE_NONE:
    default: __builtin_trap();
    }
    if (c->owner < -1 || c->owner >= LS_MAX_SUPERVISORS || (c->owner >= 0 && !c->sessions[c->owner].connected)) {
        __builtin_trap(); /* an owner must be a live session */
    }
    bool anyone = false;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        anyone = anyone || c->sessions[i].connected;
    }
    if (anyone && c->state == ls_State_IDLE) {
        __builtin_trap();
    }
    if (c->state == ls_State_UNLOCKED && c->owner >= 0) {
        __builtin_trap();
    }
    if (c->run.active && c->state != ls_State_MOVING && c->state != ls_State_PAUSED) {
        __builtin_trap();
    }
    unsigned queued = atomic_load(&g_ctl.cmd_head) - atomic_load(&g_ctl.cmd_tail);
    unsigned events = atomic_load(&g_ctl.ev_head) - atomic_load(&g_ctl.ev_tail);
    if (queued > LS_CTL_QUEUE_LEN || events > LS_CTL_QUEUE_LEN) {
        __builtin_trap();
    }
    /* A deferred answer the core no longer owes (its session ended, or
     * connected again: a new epoch) is no longer expected. */
    for (int i = 0; i < N_SUP; i++) {
        deferred_t *d = &g_deferred[i];
        const int k = ls_core_session_of(c, k_addr[i]);
        if (d->active && (k < 0 || c->sessions[k].epoch != d->epoch || !c->sessions[k].last_pending)) {
            d->active = false;
        }
    }
}

/* ---------------------------------------------------------------- time */

static void comms_turn(void)
{
    g_step_downlinks = 0;
    ls_core_tick(&g_core, g_now); /* takes the loop's events, times, halts, DIO, aux (ls_core.h) */
}

/* Let `dt_us` pass: a loop cycle and a comms turn every CYCLE_US, at most
 * MAX_CYCLES_PER_STEP of them (then the rest of the time passes at once, as
 * for a loop that stalled). */
static void advance(uint64_t dt_us, bool heartbeats)
{
    uint64_t end = g_now + dt_us;
    for (unsigned n = 0; g_now + CYCLE_US <= end && n < MAX_CYCLES_PER_STEP; n++) {
        g_now += CYCLE_US;
        if (heartbeats && n % 10u == 0u) {
            for (int i = 0; i < N_SUP; i++) {
                ls_core_on_heartbeat(&g_core, k_addr[i], 0u, 0u, g_token[i], g_now);
            }
        }
        ls_control_cycle(&g_ctl, g_now);
        comms_turn();
    }
    g_now = end;
    if (heartbeats) { /* the supervisors beat on while the loop stalls */
        for (int i = 0; i < N_SUP; i++) {
            ls_core_on_heartbeat(&g_core, k_addr[i], 0u, 0u, g_token[i], g_now);
        }
    }
    comms_turn();
}

/* ---------------------------------------------------------------- requests */

static const char *const k_names[] = {
    "p0",
    "p1",
    "p2",
    "tag",
    "",
    "force_sensor",
    "wait 0.1",
    "dio 8 on",
    "012345678901234567890123456789012345678901234567890123456789012", /* 63 bytes: the longest */
    "\xC3\xA9t\xC3\xA9",                                               /* UTF-8 */
    "\xFF\xFE",                                                        /* not UTF-8 */
    "status",
    "digital",
};
#define N_NAMES (sizeof k_names / sizeof k_names[0])

static double take_double(void)
{
    static const double k[] = { 0.0, 0.1, -0.1, 0.5, 1.0, -1.0, 2.0, 10.0, 50.0, 100.0, 1e-300, -0.0 };
    const uint8_t b = take8();
    if (b < 200u) {
        return k[b % (sizeof k / sizeof k[0])] * (b >= 100u ? 0.37 : 1.0);
    }
    if (b < 250u) {
        return (double)(int32_t)take32() / 65536.0;
    }
    const uint32_t hi = take32(), lo = take32();
    uint64_t bits = (uint64_t)hi << 32 | lo;
    double v;
    memcpy(&v, &bits, sizeof v);
    return v; /* any bit pattern: NaN, infinities, subnormals */
}

static uint32_t take_uint(void)
{
    const uint8_t b = take8();
    return b < 128u ? (uint32_t)b % 8u : b < 250u ? (uint32_t)b : take32();
}

/* Fill every field of `msg` (nanopb static layout) from the input. */
static void fill(const pb_msgdesc_t *desc, void *msg, int depth)
{
    pb_field_iter_t it;
    if (!pb_field_iter_begin(&it, desc, msg)) {
        return;
    }
    do {
        const pb_type_t t = it.type;
        if (PB_ATYPE(t) != PB_ATYPE_STATIC || it.pData == NULL) {
            continue;
        }
        size_t count = 1;
        if (PB_HTYPE(t) == PB_HTYPE_REPEATED) {
            const uint8_t b = take8(); /* 0: one per joint (or as many as fit) */
            count = b == 0u ? LS_N_JOINTS : b < 200u ? b % 4u : b % ((unsigned)it.array_size + 1u);
            if (count > it.array_size) {
                count = it.array_size;
            }
            *(pb_size_t *)it.pSize = (pb_size_t)count;
        } else if (PB_HTYPE(t) == PB_HTYPE_OPTIONAL && it.pSize != NULL) {
            const bool has = (take8() & 3u) != 3u;
            *(bool *)it.pSize = has;
            if (!has) {
                continue;
            }
        } else if (PB_HTYPE(t) == PB_HTYPE_ONEOF) {
            continue;
        }
        for (size_t k = 0; k < count; k++) {
            char *elem = (char *)it.pData + k * it.data_size;
            switch (PB_LTYPE(t)) {
            case PB_LTYPE_BOOL: *(bool *)elem = (take8() & 1u) != 0u; break;
            case PB_LTYPE_VARINT:
            case PB_LTYPE_UVARINT:
            case PB_LTYPE_SVARINT:
            case PB_LTYPE_FIXED32:
            case PB_LTYPE_FIXED64:
                if (it.data_size == sizeof(double) && PB_LTYPE(t) == PB_LTYPE_FIXED64) {
                    double v = take_double();
                    memcpy(elem, &v, sizeof v);
                } else if (it.data_size == sizeof(float) && PB_LTYPE(t) == PB_LTYPE_FIXED32) {
                    float v = (float)take_double();
                    memcpy(elem, &v, sizeof v);
                } else if (it.data_size == sizeof(uint64_t)) {
                    uint64_t v = take_uint();
                    memcpy(elem, &v, sizeof v);
                } else if (it.data_size == sizeof(uint32_t)) {
                    uint32_t v = take_uint();
                    if ((take8() & 0x0Fu) == 0u) {
                        v = 0u - v; /* negative enums and codes */
                    }
                    memcpy(elem, &v, sizeof v);
                } else if (it.data_size == sizeof(uint16_t)) {
                    uint16_t v = (uint16_t)take_uint();
                    memcpy(elem, &v, sizeof v);
                } else if (it.data_size == sizeof(uint8_t)) {
                    *(uint8_t *)elem = (uint8_t)take_uint();
                }
                break;
            case PB_LTYPE_STRING: {
                const char *s = k_names[take8() % N_NAMES];
                size_t n = strlen(s);
                if (n >= it.data_size) {
                    n = it.data_size - 1u;
                }
                memcpy(elem, s, n);
                elem[n] = '\0';
                break;
            }
            default:
                if (PB_LTYPE_IS_SUBMSG(t) && depth < 3) {
                    fill(it.submsg_desc, elem, depth + 1);
                }
                break;
            }
        }
    } while (pb_field_iter_next(&it));
}

/* The oneof members of ls.Request: every command the schema has. */
static pb_size_t g_cmds[64];
static size_t g_n_cmds;

static void list_commands(void)
{
    static ls_Request probe;
    pb_field_iter_t it;
    g_n_cmds = 0;
    if (!pb_field_iter_begin(&it, ls_Request_fields, &probe)) {
        return;
    }
    do {
        if (PB_HTYPE(it.type) == PB_HTYPE_ONEOF && g_n_cmds < sizeof g_cmds / sizeof g_cmds[0]) {
            g_cmds[g_n_cmds++] = it.tag;
        }
    } while (pb_field_iter_next(&it));
}

static ls_Uplink g_up;
static uint8_t g_enc[LS_UPLINK_MAX];
static uint8_t g_last_enc[N_SUP][LS_UPLINK_MAX];
static size_t g_last_len[N_SUP];
static uint32_t g_seq[N_SUP];

/* After a delivery: the request the core now owes an answer (it deferred it). */
static void sync_deferred(int sup)
{
    const int k = ls_core_session_of(&g_core, k_addr[sup]);
    const ls_session_t *s = k >= 0 ? &g_core.sessions[k] : NULL;
    deferred_t *d = &g_deferred[sup];
    if (s != NULL && s->last_pending && (!d->active || d->epoch != s->epoch || d->seq != s->last_seq)) {
        *d = (deferred_t){ .active = true, .seq = s->last_seq, .epoch = s->epoch, .tag = s->pending_tag };
    }
}

static void deliver(int sup, const uint8_t *buf, size_t len, uint32_t seq, pb_size_t tag, bool any)
{
    g_in_request = true;
    g_req_any = any;
    g_req_sup = sup;
    g_req_seq = seq;
    g_req_answers = 0;
    ls_core_on_uplink(&g_core, k_addr[sup], 0, buf, len, g_now);
    g_in_request = false;
    const int k = ls_core_session_of(&g_core, k_addr[sup]);
    const ls_session_t *s = k >= 0 ? &g_core.sessions[k] : NULL;
    if (g_req_answers == 0u) {
        if (!any && !(s != NULL && s->last_pending && s->last_seq == seq)) {
            __builtin_trap(); /* a request left without an answer and nothing owed */
        }
    } else {
        note_answer(k_addr[sup], &g_req_resp, any ? g_req_resp.which_result : tag);
    }
    sync_deferred(sup);
}

static void request(void)
{
    const int sup = take8() % N_SUP;
    const uint8_t want = take8(); /* the command's field number in ls.Request, else an index */
    pb_size_t tag = g_cmds[want % g_n_cmds];
    for (size_t i = 0; i < g_n_cmds; i++) {
        if (g_cmds[i] == want) {
            tag = want;
        }
    }
    const uint8_t how = take8();
    if (how >= 200u && how < 230u && g_last_len[sup] > 0) {
        /* a retransmission: the same bytes again */
        pb_istream_t is = pb_istream_from_buffer(g_last_enc[sup], g_last_len[sup]);
        memset(&g_up, 0, sizeof g_up);
        if (!pb_decode(&is, ls_Uplink_fields, &g_up)) {
            __builtin_trap();
        }
        deliver(sup, g_last_enc[sup], g_last_len[sup], g_up.msg.request.seq, g_up.msg.request.which_cmd, false);
        return;
    }
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    ls_Request *rq = &g_up.msg.request;
    rq->which_cmd = tag;
    uint32_t seq = how < 230u ? ++g_seq[sup] : how < 250u ? g_seq[sup] : 0u;
    if (seq == 0u && how < 250u) {
        seq = ++g_seq[sup];
    }
    rq->seq = seq;
    /* fill the command's message: its descriptor is the oneof member's */
    pb_field_iter_t it;
    if (pb_field_iter_begin(&it, ls_Request_fields, rq) && pb_field_iter_find(&it, tag) && it.submsg_desc != NULL) {
        fill(it.submsg_desc, it.pData, 0);
    }
    if (tag == ls_Request_connect_tag && (take8() & 7u) != 7u) {
        rq->cmd.connect.has_protocol_version = true;
        rq->cmd.connect.protocol_version = ls_Protocol_PROTOCOL_VERSION;
        rq->cmd.connect.has_schema_hash = true;
        rq->cmd.connect.schema_hash = LS_SCHEMA_HASH;
        if ((take8() & 3u) != 3u) {
            rq->cmd.connect.heartbeat_period_ms = 100;
        }
        if ((take8() & 3u) != 3u) { /* the same client again (else the fuzzed nonce: another one) */
            rq->cmd.connect.has_client_nonce = true;
            rq->cmd.connect.client_nonce = 0x1000u + (uint64_t)sup;
        }
    }
    pb_ostream_t os = pb_ostream_from_buffer(g_enc, sizeof g_enc);
    if (!pb_encode(&os, ls_Uplink_fields, &g_up)) {
        return; /* too large for one message: a host could not send it either */
    }
    memcpy(g_last_enc[sup], g_enc, os.bytes_written);
    g_last_len[sup] = os.bytes_written;
    deliver(sup, g_enc, os.bytes_written, seq, tag, false);
}

static void rsvp_reply(void)
{
    const int sup = take8() % N_SUP;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_rsvp_reply_tag;
    ls_RsvpReply *r = &g_up.msg.rsvp_reply;
    const uint8_t b = take8();
    r->rsvp_id = b < 200u ? g_last_rsvp[sup] : take32();
    r->ret_code = (take8() & 1u) != 0u ? ls_RetCode_CMD_EXEC_OK : ls_RetCode_CMD_ERR;
    pb_ostream_t os = pb_ostream_from_buffer(g_enc, sizeof g_enc);
    if (pb_encode(&os, ls_Uplink_fields, &g_up)) {
        ls_core_on_uplink(&g_core, k_addr[sup], 0, g_enc, os.bytes_written, g_now);
    }
    sync_deferred(sup);
}

static void raw_bytes(void)
{
    const int sup = take8() % N_SUP;
    size_t n = take8() % 48u;
    if (n > g_left) {
        n = g_left;
    }
    const uint8_t *p = g_in;
    g_in += n;
    g_left -= n;
    deliver(sup, p, n, 0, 0, true); /* whatever it is: at most one answer */
}

/* ---------------------------------------------------------------- one input */

static void setup(void)
{
    static const ls_robot_model_t *model = &ls_robot_model_default;
    memset(g_q, 0, sizeof g_q);
    memset(g_qd, 0, sizeof g_qd);
    memset(g_force, 0, sizeof g_force);
    g_enabled = false;
    g_dio_levels = 0;
    g_arm = (hal_arm_t){ .ops = &k_arm_ops, .self = NULL, .name = "fuzz" };
    g_dio = (hal_dio_t){ .ops = &k_dio_ops, .self = NULL, .name = "fuzz" };
    g_sensor = (hal_sensor_t){ .name = "force_sensor", .n_values = 6, .read = force_read, .self = NULL };
    ls_core_config_t cfg = { .device_name = "fuzz",
                             .firmware_version = "0",
                             .node_addr = 0x10,
                             .joint_count = LS_N_JOINTS,
                             .heartbeat_timeout_ms = 1000 };
    ls_core_io_t io = { .send_downlink = send_downlink, .ctx = NULL };
    ls_core_actions_t act = { 0 };
    ls_core_actions_for_loop(&act, &g_ctl);
    ls_core_init(&g_core, &cfg, &io, &act);
    g_core.model = model;
    g_core.sensors = &g_sensor;
    g_core.n_sensors = 1;
    hal_dio_unit_info_t info;
    (void)dio_describe(NULL, 0, &info);
    g_core.dio_info[0] = info;
    g_core.dio_units = 1;
    ls_control_config_t cc = {
        .model = model, .arm = &g_arm, .dio = &g_dio, .sensors = &g_sensor, .n_sensors = 1, .rate_hz = RATE_HZ
    };
    ls_control_init(&g_ctl, &cc);
    g_core.ctl = &g_ctl;
    g_now = 1000000;
    memset(g_deferred, 0, sizeof g_deferred);
    memset(g_last_rsvp, 0, sizeof g_last_rsvp);
    memset(g_seq, 0, sizeof g_seq);
    memset(g_last_len, 0, sizeof g_last_len);
    memset(g_token, 0, sizeof g_token);
    g_n_answered = 0;
    g_ledger_full = false;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (g_n_cmds == 0) {
        list_commands();
        const char *t = getenv("FUZZ_SESSION_TRACE");
        g_trace = t != NULL && t[0] == '1';
    }
    setup();
    const uint8_t *p = data;
    const uint8_t *const end = data + size;
    while (end - p >= 2) {
        const uint8_t op = p[0];
        size_t n = p[1];
        p += 2;
        if (n > (size_t)(end - p)) {
            n = (size_t)(end - p);
        }
        g_in = p;
        g_left = n;
        p += n;
        g_step_downlinks = 0;
        switch (op % 16u) {
        case 0:
        case 1:
        case 2:
        case 3:
        case 4:
        case 5: request(); break;
        case 6:
        case 7: {
            const int sup = take8() % N_SUP;
            const uint8_t b = take8(); /* mostly its token; else another (refused: hb_refused) */
            ls_core_on_heartbeat(&g_core, k_addr[sup], 0u, 0u, b < 200u ? g_token[sup] : take32(), g_now);
            break;
        }
        case 8: advance((uint64_t)take8() * 1000u, (op & 0x10u) != 0u); break;
        case 9: advance((uint64_t)take8() * 50000u, (op & 0x10u) != 0u); break;
        case 10: rsvp_reply(); break;
        case 11: {
            const uint8_t b = take8();
            g_dio_levels = (g_dio_levels & 0xFF00u) | b;
            break;
        }
        case 12: g_force[take8() % 6u] = take_double(); break;
        case 13: ls_core_emergency(&g_core, g_now); break;
        case 14: ls_core_fault(&g_core, "fuzz: a fault", g_now); break;
        default: raw_bytes(); break;
        }
        check_state();
    }
    /* The end: supervisors keep beating, the loop runs until the core is
     * quiet (no run, no halt, no deferred answer), at most DRAIN_US. */
    for (uint64_t t = 0; t < DRAIN_US; t += 100000u) {
        bool owed = false;
        for (int i = 0; i < N_SUP; i++) {
            owed = owed || g_deferred[i].active;
        }
        if (!owed && !g_core.run.active && !g_core.halt.active) {
            break;
        }
        g_step_downlinks = 0;
        advance(100000u, true);
        check_state();
    }
    if (!g_core.run.active && !g_core.halt.active) {
        for (int i = 0; i < N_SUP; i++) {
            if (g_deferred[i].active) {
                __builtin_trap(); /* a deferred request never answered while its session lives */
            }
        }
        if (!g_ledger_full) {
            for (size_t i = 0; i < g_n_answered; i++) {
                const answered_t *a = &g_answered[i];
                if (a->code == ls_RetCode_CMD_STARTED_OK && a->finals != 1u) {
                    __builtin_trap(); /* a started motion must end with exactly one final notice */
                }
            }
        }
    }
    return 0;
}
