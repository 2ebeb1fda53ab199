/* The fixture the core's unit tests share: see core_fixture.h. */
#include "core_fixture.h"

/* cmocka's assert_float_equal works in float: too coarse for these values. */
void assert_near_(double a, double b, double eps, const char *expr, const char *file, int line)
{
    if (!(fabs(a - b) <= eps)) {
        fail_msg("%s:%d: %s = %.17g, expected %.17g (+- %g)", file, line, expr, a, b, eps);
    }
}

ls_control_t g_ctl;
ls_ctl_snapshot_t g_snap;
ls_ctl_cmd_t g_posted[16];
size_t g_nposted;
bool g_post_ok;

hal_arm_readout_t g_readout;
int g_readout_rc;

bool __wrap_ls_control_snapshot(ls_control_t *c, ls_ctl_snapshot_t *out);
bool __wrap_ls_control_post(ls_control_t *c, const ls_ctl_cmd_t *cmd);
int __wrap_ls_control_readout(ls_control_t *c, hal_arm_readout_t *out);

/* The drives' readouts (sendCommand drives, status): g_readout when
 * g_readout_rc is LS_OK; setup_core makes it LS_EUNSUPPORTED (no drives). */
int __wrap_ls_control_readout(ls_control_t *c, hal_arm_readout_t *out)
{
    assert_ptr_equal(c, &g_ctl);
    if (g_readout_rc == LS_OK) {
        *out = g_readout;
    }
    return g_readout_rc;
}

bool __wrap_ls_control_snapshot(ls_control_t *c, ls_ctl_snapshot_t *out)
{
    assert_ptr_equal(c, &g_ctl);
    *out = g_snap;
    return true;
}

bool __wrap_ls_control_post(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    assert_ptr_equal(c, &g_ctl);
    if (!g_post_ok || g_nposted >= sizeof g_posted / sizeof g_posted[0]) {
        return false;
    }
    g_posted[g_nposted++] = *cmd;
    return true;
}

ls_core_t g_core;
ls_Downlink g_rx[MAX_RX];
uint8_t g_rx_addr[MAX_RX];
size_t g_nrx;
uint64_t g_now;
uint32_t g_seq;
ls_Request g_rq;
ls_Uplink g_up;
uint8_t g_buf[LS_UPLINK_MAX + 64];

/* The event names the paths of these tests choose (`event NAME`): the only
 * names a notice may carry that the schema does not declare. */
const char *const k_path_event_names[] = { "reached", "ask" };

/* Every notice the core sends: its event id is declared in the schema's enum
 * ls.EventId (or is a path's own, with AUX_NAMED_EVENT's keys) and every data
 * item is "key=value" with a key the schema lists for that id. */
void assert_notice_declared(const ls_Notice *n)
{
    ls_EventId id = ls_event_find(n->event_id);
    if (id == ls_EventId_EVENT_ID_NONE) {
        bool path_event = false;
        for (size_t k = 0; k < sizeof k_path_event_names / sizeof k_path_event_names[0]; k++) {
            path_event = path_event || strcmp(n->event_id, k_path_event_names[k]) == 0;
        }
        if (!path_event) {
            fail_msg("notice '%s' is not declared in protocol/landscape.proto enum EventId", n->event_id);
        }
        id = ls_EventId_AUX_NAMED_EVENT;
    }
    for (pb_size_t k = 0; k < n->data_count; k++) {
        const char *eq = strchr(n->data[k], '=');
        if (eq == NULL || !ls_event_key_declared(id, n->data[k], (size_t)(eq - n->data[k]))) {
            fail_msg("notice '%s': data '%s' has no key the schema declares for it (ls.notice_keys)", n->event_id,
                     n->data[k]);
        }
    }
}

uint8_t g_rx_raw[MAX_RX][LS_DOWNLINK_MAX];
size_t g_rx_len[MAX_RX];

int fake_send(void *ctx, uint8_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    assert_true(g_nrx < MAX_RX);
    assert_true(len <= sizeof g_rx_raw[g_nrx]);
    memcpy(g_rx_raw[g_nrx], buf, len);
    g_rx_len[g_nrx] = len;
    pb_istream_t is = pb_istream_from_buffer(buf, len);
    memset(&g_rx[g_nrx], 0, sizeof g_rx[g_nrx]);
    assert_true(pb_decode(&is, ls_Downlink_fields, &g_rx[g_nrx]));
    if (g_rx[g_nrx].which_msg == ls_Downlink_notice_tag) {
        assert_notice_declared(&g_rx[g_nrx].msg.notice);
    }
    g_rx_addr[g_nrx] = addr;
    g_nrx++;
    return 0;
}

const hal_sensor_t g_sensors[2] = {
    { .name = "force_sensor", .n_values = 6 },
    { .name = "laser_standoff_sensor", .n_values = 1 },
};

ls_Request *req(pb_size_t tag)
{
    memset(&g_rq, 0, sizeof g_rq);
    g_rq.which_cmd = tag;
    return &g_rq;
}

void send_uplink(uint8_t addr)
{
    pb_ostream_t os = pb_ostream_from_buffer(g_buf, sizeof g_buf);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    ls_core_on_uplink(&g_core, addr, 0, g_buf, os.bytes_written, g_now);
}

/* Send g_rq from addr; the response to it, or NULL when none came (deferred). */
const ls_Response *send_req(uint8_t addr)
{
    g_rq.seq = ++g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    size_t before = g_nrx;
    send_uplink(addr);
    for (size_t i = before; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_response_tag && g_rx[i].msg.response.seq == g_seq &&
            g_rx_addr[i] == addr) {
            return &g_rx[i].msg.response;
        }
    }
    return NULL;
}

const ls_Response *must(uint8_t addr)
{
    const ls_Response *r = send_req(addr);
    assert_non_null(r);
    return r;
}

void send_rsvp_reply(uint8_t addr, uint32_t id, int32_t code)
{
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_rsvp_reply_tag;
    g_up.msg.rsvp_reply.rsvp_id = id;
    g_up.msg.rsvp_reply.ret_code = code;
    send_uplink(addr);
}

/* The client nonce of the test's supervisor at `addr` (one client per address). */
uint64_t nonce_of(uint8_t addr)
{
    return 0x1D0000000000A000u | addr;
}

/* A heartbeat from `addr` carrying the token of its session (0: none). */
void beat(uint8_t addr, uint64_t now_us)
{
    int i = ls_core_session_of(&g_core, addr);
    ls_core_on_heartbeat(&g_core, addr, 0u, 0u, i >= 0 ? g_core.sessions[i].hb_token : 0u, now_us);
}

ls_ConnectReq *connect_req(uint8_t addr)
{
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    c->client_nonce = nonce_of(addr);
    c->has_client_nonce = true;
    snprintf(c->client_name, sizeof c->client_name, "test-%02X", addr);
    return c;
}

void connect_host(uint8_t addr)
{
    (void)connect_req(addr);
    assert_int_equal(must(addr)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

/* The configuration of the next setup_core (then back to these defaults). */
ls_DisconnectAction g_cfg_action = ls_DisconnectAction_DISCONNECT_CONFIGURED;
uint32_t g_cfg_timeout_ms = 600000;

/* The device's nonces: a counter, so that every challenge differs. */
static int fake_random(void *ctx, uint8_t *buf, size_t len)
{
    static uint8_t next;
    (void)ctx;
    for (size_t i = 0; i < len; i++) {
        buf[i] = next++;
    }
    return LS_OK;
}

/* A core with nobody connected, its keys and policy in `auth` (NULL: none). */
void setup_bare_core(ls_auth_t *auth)
{
    const ls_core_config_t cfg = { .device_name = "test",
                                   .firmware_version = "0",
                                   .node_addr = 0x10,
                                   .joint_count = 6,
                                   .heartbeat_timeout_ms = g_cfg_timeout_ms,
                                   .disconnect_action = g_cfg_action,
                                   .auth = auth };
    g_cfg_action = ls_DisconnectAction_DISCONNECT_CONFIGURED;
    g_cfg_timeout_ms = 600000;
    const ls_core_io_t io = { .send_downlink = fake_send, .random = fake_random, .ctx = NULL };
    ls_core_init(&g_core, &cfg, &io, NULL);
    g_core.model = &ls_robot_model_default;
    g_core.ctl = &g_ctl;
    g_core.sensors = g_sensors;
    g_core.n_sensors = 2;
    g_core.dio_units = 1;
    g_core.dio_info[0] = (hal_dio_unit_info_t){ .input_mask = 0x0000FFFFu, .output_mask = 0xFFFF0000u };
    memset(&g_snap, 0, sizeof g_snap);
    g_snap.cycle = 100;
    g_nposted = 0;
    g_post_ok = true;
    g_readout_rc = LS_EUNSUPPORTED;
    g_nrx = 0;
    g_now = 1000000;
}

/* A core with HOST_A connected and owning the device in `state`, HOST_B connected. */
void setup_core(ls_State state)
{
    setup_bare_core(NULL);
    connect_host(HOST_A);
    connect_host(HOST_B);
    g_core.owner = 0;
    g_core.state = state;
    g_nrx = 0;
}

int setup_locked(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    return 0;
}

const ls_Notice *nth_notice(size_t from, size_t k)
{
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_notice_tag && k-- == 0) {
            return &g_rx[i].msg.notice;
        }
    }
    return NULL;
}

size_t count_notices(size_t from)
{
    size_t n = 0;
    for (size_t i = from; i < g_nrx; i++) {
        n += g_rx[i].which_msg == ls_Downlink_notice_tag ? 1u : 0u;
    }
    return n;
}

const ls_State k_states[6] = { ls_State_IDLE,    ls_State_UNLOCKED, ls_State_LOCKED,
                               ls_State_RESTING, ls_State_MOVING,   ls_State_PAUSED };

void set_units(ls_LinearUnit lu, ls_AngularUnit au)
{
    ls_SetUnitsReq *u = &req(ls_Request_set_units_tag)->cmd.set_units;
    u->linear = lu;
    u->has_linear = true;
    u->angular = au;
    u->has_angular = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

int32_t set_speed(ls_SpeedType t, double v, const char **msg)
{
    ls_SetSpeedReq *sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = t;
    sp->has_attribute = true;
    sp->speed = v;
    sp->has_speed = true;
    const ls_Response *r = must(HOST_A);
    *msg = r->ret_msg;
    return r->ret_code;
}

int32_t set_accel(ls_AccelType t, double v, const char **msg)
{
    ls_SetAccelerationReq *a = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    a->attribute = t;
    a->has_attribute = true;
    a->accel = v;
    a->has_accel = true;
    const ls_Response *r = must(HOST_A);
    *msg = r->ret_msg;
    return r->ret_code;
}

const ls_Response *set_dio(const char *type, int32_t unit, uint32_t on, uint32_t off)
{
    ls_SetDigitalIOReq *d = &req(ls_Request_set_digital_io_tag)->cmd.set_digital_io;
    snprintf(d->type, sizeof d->type, "%s", type);
    d->unit_id = unit;
    d->has_unit_id = true;
    d->bits_on = on;
    d->bits_off = off;
    return send_req(HOST_A);
}

uint32_t signal_dio(uint8_t addr, uint32_t bits, int32_t timeout_ms, int32_t cycle_ms, ls_CallbackType cb,
                    int32_t *code)
{
    ls_SignalDigitalIOReq *s = &req(ls_Request_signal_digital_io_tag)->cmd.signal_digital_io;
    snprintf(s->type, sizeof s->type, "digital");
    s->has_unit_id = s->has_callback_type = true; /* unit 0, CB_EVENT */
    s->bit_string = bits;
    s->polling_timeout_ms = timeout_ms;
    s->polling_cycle_time_ms = cycle_ms;
    s->callback_type = cb;
    s->has_callback_type = true;
    s->has_unit_id = true; /* unit 0 */
    const ls_Response *r = must(addr);
    *code = r->ret_code;
    return r->ret_code == ls_RetCode_CMD_EXEC_OK ? r->result.signal_digital_io.watch_id : 0u;
}

void assert_data(const ls_Notice *n, const char *d0, const char *d1, const char *d2, const char *d3)
{
    assert_int_equal(n->data_count, 4);
    assert_string_equal(n->data[0], d0);
    assert_string_equal(n->data[1], d1);
    assert_string_equal(n->data[2], d2);
    assert_string_equal(n->data[3], d3);
}

int32_t g_done_code;
bool g_done_timed_out;
int g_done_calls;

const char *done_cb(ls_core_t *core, void *ctx, int32_t ret_code, bool timed_out, uint64_t now_us)
{
    (void)now_us;
    assert_ptr_equal(core, &g_core);
    assert_ptr_equal(ctx, &g_done_calls);
    g_done_code = ret_code;
    g_done_timed_out = timed_out;
    g_done_calls++;
    return timed_out ? "default-taken" : (ret_code >= 0 ? "went-on" : "dropped");
}

void send_rsvp_reply_data(uint8_t addr, uint32_t id, int32_t code, const char *d0)
{
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_rsvp_reply_tag;
    g_up.msg.rsvp_reply.rsvp_id = id;
    g_up.msg.rsvp_reply.ret_code = code;
    if (d0 != NULL) {
        snprintf(g_up.msg.rsvp_reply.data[0], sizeof g_up.msg.rsvp_reply.data[0], "%s", d0);
        g_up.msg.rsvp_reply.data_count = 1;
    }
    send_uplink(addr);
}

/* The one RsvpAck sent to addr since `from`. */
const ls_RsvpAck *the_ack(size_t from, uint8_t addr)
{
    const ls_RsvpAck *a = NULL;
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_rsvp_ack_tag) {
            assert_null(a);
            assert_int_equal(g_rx_addr[i], addr);
            a = &g_rx[i].msg.rsvp_ack;
        }
    }
    assert_non_null(a);
    return a;
}

/* The event log (sendCommand events) as the owner reads it. */
const char *events_text(void)
{
    ls_SendCommandReq *sc = &req(ls_Request_send_command_tag)->cmd.send_command;
    snprintf(sc->input, sizeof sc->input, "events");
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    return r->result.send_command.result;
}

/* A dioSignal RSVP from a watch of HOST_B on bit 0: the notice. */
const ls_Notice *dio_rsvp(uint32_t *watch, uint32_t *req_seq)
{
    int32_t code;
    *watch = signal_dio(HOST_B, 0x1u, 0, 0, ls_CallbackType_CB_EVENT_RSVP, &code);
    *req_seq = g_seq;
    size_t before = g_nrx;
    g_snap.dio[0] = 0x1u;
    ls_core_on_dio_event(&g_core, 0, 0x1u, 0x1u, g_now += 1000);
    const ls_Notice *n = nth_notice(before, 0);
    assert_non_null(n);
    assert_int_equal(n->kind, ls_NoticeKind_EVENT_RSVP);
    assert_string_equal(n->event_id, "dioSignal");
    assert_string_equal(n->rsvp_default, "cancel");
    assert_int_equal(n->rsvp_timeout_ms, 2000);
    assert_int_equal(n->ref_seq, *req_seq);
    assert_int_equal(n->session_epoch, g_core.sessions[1].epoch);
    char wid[24];
    snprintf(wid, sizeof wid, "watch=%u", (unsigned)*watch);
    assert_data(n, "unit=0", "bits=0x1", "levels=0x1", wid);
    return n;
}

int watches_in(ls_watch_phase_t phase)
{
    int k = 0;
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        k += g_core.dio.watch[i].phase == phase ? 1 : 0;
    }
    return k;
}

const double k_home[6] = { 0.0, 0.3, 0.3, 0.0, 0.9, 0.0 };

/* Send g_rq again with the seq of the previous request; every response to it. */
size_t resend_same_seq(uint8_t addr, size_t *first)
{
    g_rq.seq = g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    *first = g_nrx;
    send_uplink(addr);
    return g_nrx - *first;
}

/* RESTING with HOST_A the owner; a joint move started: its seq. */
uint32_t start_move(void)
{
    setup_core(ls_State_RESTING);
    atomic_store(&g_ctl.plan_slot_busy, false); /* the loop took the previous test's plan */
    atomic_store(&g_ctl.cmd_tail, atomic_load(&g_ctl.cmd_head));
    memcpy(g_snap.q_cmd_rad, k_home, sizeof k_home);
    g_snap.enabled = true;
    ls_MoveAbsoluteReq *m = &req(ls_Request_move_absolute_tag)->cmd.move_absolute;
    snprintf(m->point_name, sizeof m->point_name, "p1");
    m->frame = ls_ReferenceFrame_JOINT_FRAME;
    m->has_frame = true;
    m->values_count = 6;
    for (int j = 0; j < 6; j++) {
        m->values[j] = k_home[j] + (j == 0 ? 0.5 : 0.0);
    }
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_STARTED_OK);
    assert_int_equal(g_core.state, ls_State_MOVING);
    assert_string_equal(ls_core_motion_state_name(&g_core), "running_trajectory");
    return r->seq;
}

/* The loop reports the arm at rest with the drives off, two cycles later. */
void loop_stopped(void)
{
    g_snap.cycle += 2;
    g_snap.enabled = false;
    g_snap.phase = LS_MOTION_IDLE;
    memset(g_snap.qd_rad_s, 0, sizeof g_snap.qd_rad_s);
}

const ls_Notice *the_final(size_t from, uint32_t seq, size_t *count)
{
    const ls_Notice *f = NULL;
    *count = 0;
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_notice_tag && g_rx[i].msg.notice.final &&
            g_rx[i].msg.notice.ref_seq == seq) {
            f = &g_rx[i].msg.notice;
            (*count)++;
        }
    }
    return f;
}

bool has_data(const ls_Notice *n, const char *item)
{
    for (pb_size_t k = 0; k < n->data_count; k++) {
        if (strcmp(n->data[k], item) == 0) {
            return true;
        }
    }
    return false;
}

/* The loop posts a motion event as the control loop does (ls_control.c ev_push). */
/* The loop's side of its event ring: `ev` posted for the core to take. */
static void ring_post(const ls_ctl_event_t *ev)
{
    const unsigned head = atomic_load(&g_ctl.ev_head);
    g_ctl.ev_ring[head % LS_CTL_QUEUE_LEN] = *ev;
    atomic_store(&g_ctl.ev_head, head + 1u);
}

void loop_posts(ls_motion_event_kind_t kind, uint32_t ref_seq)
{
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = LS_CEV_MOTION;
    ev.motion.kind = kind;
    ev.motion.ref_seq = ref_seq;
    ring_post(&ev);
}

/* The loop posts an event of `kind` with `text` (the homing's end). */
void loop_posts_event(ls_cev_kind_t kind, uint32_t ref_seq, const char *text)
{
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = kind;
    ev.ref_seq = ref_seq;
    snprintf(ev.text, sizeof ev.text, "%s", text);
    ring_post(&ev);
}

const ls_Response *send_command_from(uint8_t addr, const char *input)
{
    ls_SendCommandReq *sc = &req(ls_Request_send_command_tag)->cmd.send_command;
    snprintf(sc->input, sizeof sc->input, "%s", input);
    return send_req(addr);
}

/* The response to seq `seq` among what the device sent, or NULL. */
const ls_Response *response_to(uint32_t seq)
{
    for (size_t i = 0; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_response_tag && g_rx[i].msg.response.seq == seq) {
            return &g_rx[i].msg.response;
        }
    }
    return NULL;
}

int g_halt_posts;

void count_halt(void *ctx)
{
    (void)ctx;
    g_halt_posts++;
}

size_t alarms_to(size_t from, uint8_t addr, const char *event_id, const ls_Notice **last)
{
    size_t n = 0;
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_notice_tag && g_rx_addr[i] == addr &&
            g_rx[i].msg.notice.kind == ls_NoticeKind_ALARM && strcmp(g_rx[i].msg.notice.event_id, event_id) == 0) {
            n++;
            if (last != NULL) {
                *last = &g_rx[i].msg.notice;
            }
        }
    }
    return n;
}

const ls_Response *connect_as(uint8_t addr, uint64_t nonce, const char *name)
{
    ls_ConnectReq *c = connect_req(addr);
    c->client_nonce = nonce;
    snprintf(c->client_name, sizeof c->client_name, "%s", name);
    return must(addr);
}

const ls_Response *connect_with(uint8_t addr, uint32_t period_ms, ls_DisconnectAction action)
{
    ls_ConnectReq *c = connect_req(addr);
    c->heartbeat_period_ms = period_ms;
    c->disconnect_action = action;
    return must(addr);
}

/* Free session slots for `n` more clients: the profile's LS_MAX_SUPERVISORS
 * (2 on mcu) may not hold them beside setup_core's HOST_A and HOST_B, so
 * those disconnect as needed, HOST_B first. */
void make_room(int n)
{
    static const uint8_t setup_hosts[] = { HOST_B, HOST_A };
    for (size_t k = 0; k < sizeof setup_hosts; k++) {
        int connected = 0;
        for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
            connected += g_core.sessions[i].connected ? 1 : 0;
        }
        if (LS_MAX_SUPERVISORS - connected >= n) {
            return;
        }
        if (ls_core_session_of(&g_core, setup_hosts[k]) >= 0) {
            req(ls_Request_disconnect_tag);
            assert_int_equal(must(setup_hosts[k])->ret_code, ls_RetCode_CMD_EXEC_OK);
        }
    }
    int connected = 0;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        connected += g_core.sessions[i].connected ? 1 : 0;
    }
    assert_true(LS_MAX_SUPERVISORS - connected >= n);
}

void get_units_of(uint8_t addr, const char *linear, const char *angular)
{
    req(ls_Request_get_units_tag);
    const ls_Response *r = must(addr);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(r->result.get_units.linear_units, linear);
    assert_string_equal(r->result.get_units.angular_units, angular);
}

int g_drive_calls;
bool g_drives_on;
int g_stop_calls;

int fake_drives(void *ctx, bool on)
{
    (void)ctx;
    g_drive_calls++;
    g_drives_on = on;
    return 0;
}

void fake_stop(void *ctx)
{
    (void)ctx;
    g_stop_calls++;
}

const ls_Notice *owner_lost_alarm(size_t from)
{
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_notice_tag && strcmp(g_rx[i].msg.notice.event_id, "ownerLost") == 0) {
            return &g_rx[i].msg.notice;
        }
    }
    return NULL;
}

const char *fault_log_text(void)
{
    ls_SendCommandReq *sc = &req(ls_Request_send_command_tag)->cmd.send_command;
    snprintf(sc->input, sizeof sc->input, "faults");
    return must(HOST_B)->result.send_command.result;
}

/* `stop`: the drives stay on and the lock is kept for the owner's address until it connects again. */
/* Send the request being built from `addr`; assert the answer's code and, when `text` is not NULL, its text. */
const ls_Response *expect_answer(uint8_t addr, ls_RetCode code, const char *text)
{
    const ls_Response *r = must(addr);
    assert_int_equal(r->ret_code, code);
    if (text != NULL) {
        assert_string_equal(r->ret_msg, text);
    }
    return r;
}

/* A path with one `dio` auxiliary command, started: its seq. */
uint32_t start_dio_path(void)
{
    setup_core(ls_State_RESTING);
    atomic_store(&g_ctl.plan_slot_busy, false);
    atomic_store(&g_ctl.cmd_tail, atomic_load(&g_ctl.cmd_head));
    memcpy(g_snap.q_cmd_rad, k_home, sizeof k_home);
    g_snap.enabled = true;
    ls_PathLoadReq *l = &req(ls_Request_path_load_tag)->cmd.path_load;
    snprintf(l->path_name, sizeof l->path_name, "io");
    l->frame = ls_ReferenceFrame_JOINT_FRAME;
    l->has_frame = true;
    l->motion_type = ls_MotionType_JOINT_MOTION;
    l->has_motion_type = true;
    l->number_of_points = 1;
    l->has_frame = l->has_motion_type = l->has_offset_type = l->has_number_of_points = true;
    l->tags_count = 1;
    l->tags[0].joints_count = 6;
    memcpy(l->tags[0].joints, k_home, sizeof k_home);
    l->tags[0].joints[0] += 0.2;
    l->tags[0].aux_commands_count = 1;
    snprintf(l->tags[0].aux_commands[0], sizeof l->tags[0].aux_commands[0], "dio 0 0x10000 0");
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ls_PathMoveReq *m = &req(ls_Request_path_move_tag)->cmd.path_move;
    snprintf(m->path_name, sizeof m->path_name, "io");
    m->number_of_cycles = 1;
    m->has_number_of_cycles = true;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_STARTED_OK);
    /* the executor arrives at point 0 and announces the command */
    ls_motion_event_t ev = { .kind = LS_MEV_AUX, .ref_seq = r->seq, .index = 0 };
    snprintf(ev.text, sizeof ev.text, "dio 0 0x10000 0");
    g_nposted = 0;
    ls_core_on_motion_event(&g_core, &ev);
    assert_int_equal(g_nposted, 1);
    assert_int_equal(g_posted[0].kind, LS_CTL_DIO_WRITE);
    return r->seq;
}

uint32_t start_tagged_path(bool give_cycles, int32_t cycles, const char **msg)
{
    setup_core(ls_State_RESTING);
    atomic_store(&g_ctl.plan_slot_busy, false);
    atomic_store(&g_ctl.cmd_tail, atomic_load(&g_ctl.cmd_head));
    memcpy(g_snap.q_cmd_rad, k_home, sizeof k_home);
    g_snap.enabled = true;
    static const char k_path[] = "a-path-name-of-sixty-three-bytes-which-is-what-names-hold-now-x";
    req(ls_Request_path_clear_path_tag); /* the path queues are static: start from none */
    snprintf(g_rq.cmd.path_clear_path.path_name, sizeof g_rq.cmd.path_clear_path.path_name, "%s", k_path);
    (void)must(HOST_A);
    ls_PathLoadReq *l = &req(ls_Request_path_load_tag)->cmd.path_load;
    /* names and tags hold 63 bytes (protocol/landscape.options) */
    snprintf(l->path_name, sizeof l->path_name, "%s", k_path);
    assert_int_equal(strlen(l->path_name), 63);
    l->frame = ls_ReferenceFrame_JOINT_FRAME;
    l->has_frame = true;
    l->motion_type = ls_MotionType_JOINT_MOTION;
    l->has_motion_type = true;
    l->offset_type = ls_OffsetType_ABSOLUTE_DATA;
    l->has_offset_type = true;
    l->number_of_points = 1;
    l->has_frame = l->has_motion_type = l->has_offset_type = l->has_number_of_points = true;
    l->tags_count = 1;
    l->tags[0].joints_count = 6;
    memcpy(l->tags[0].joints, k_home, sizeof k_home);
    l->tags[0].joints[0] += 0.2;
    snprintf(l->tags[0].tag_name, sizeof l->tags[0].tag_name, "%s",
             "a-tag-of-sixty-three-bytes-so-long-that-it-did-not-fit-before-x");
    assert_int_equal(strlen(l->tags[0].tag_name), 63);
    l->tags[0].aux_commands_count = 1;
    snprintf(l->tags[0].aux_commands[0], sizeof l->tags[0].aux_commands[0], "event reached");
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ls_PathMoveReq *m = &req(ls_Request_path_move_tag)->cmd.path_move;
    snprintf(m->path_name, sizeof m->path_name, "%s", k_path);
    m->number_of_cycles = cycles;
    m->has_number_of_cycles = give_cycles;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_STARTED_OK);
    *msg = r->ret_msg;
    return r->seq;
}

void finish_path(uint32_t seq, const ls_Notice **tag, const ls_Notice **fin)
{
    size_t from = g_nrx, n;
    ls_motion_event_t ev = { .kind = LS_MEV_TAG, .ref_seq = seq, .index = 0, .cycle = 1 };
    snprintf(ev.name, sizeof ev.name, "%s", "a-tag-of-sixty-three-bytes-so-long-that-it-did-not-fit-before-x");
    snprintf(ev.text, sizeof ev.text, "%s", g_core.run.point);
    ls_core_on_motion_event(&g_core, &ev);
    *tag = nth_notice(from, 0);
    assert_non_null(*tag);
    assert_string_equal((*tag)->event_id, "tag");
    ls_motion_event_t done = { .kind = LS_MEV_DONE, .ref_seq = seq };
    ls_core_on_motion_event(&g_core, &done);
    *fin = the_final(from, seq, &n);
    assert_non_null(*fin);
    assert_int_equal(n, 1);
    assert_string_equal((*fin)->event_id, "pathMoveComplete");
}
