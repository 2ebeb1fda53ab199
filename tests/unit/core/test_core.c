/* The controller core, black box: encoded uplinks in, decoded downlinks out.
 *
 * The io captures every downlink and decodes it with nanopb. There is no
 * control loop: the core's calls of ls_control_snapshot and ls_control_post
 * are redirected here at link time (-Wl,--wrap, see CMakeLists.txt), so a
 * test sets the snapshot (joints, DIO levels, sensors, cycle) and sees what
 * was posted, whether or not the real ls_control is linked too. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>
#include <pb_decode.h>
#include <pb_encode.h>

#include "ls_control.h"
#include "ls_core.h"
#include "ls_robot_urdf.h"
#include "cmd_sensor.h"
#include "ls_core_events.h"
#include "ls_kin.h"
#include "ls_math.h"
#include "ls_units.h"
#include "ls_utf8.h"


/* cmocka's assert_float_equal works in float: too coarse for these values. */
#define assert_near(a, b, eps) assert_near_((a), (b), (eps), #a, __FILE__, __LINE__)
static void assert_near_(double a, double b, double eps, const char *expr, const char *file, int line)
{
    if (!(fabs(a - b) <= eps)) {
        fail_msg("%s:%d: %s = %.17g, expected %.17g (+- %g)", file, line, expr, a, b, eps);
    }
}

#define HOST_A 0x21
#define HOST_B 0x22
#define MAX_RX 64

/* ---------------------------------------------------------------- fake control-loop API */

static ls_control_t g_ctl;
static ls_ctl_snapshot_t g_snap;
static ls_ctl_cmd_t g_posted[16];
static size_t g_nposted;
static bool g_post_ok;

bool __wrap_ls_control_snapshot(ls_control_t *c, ls_ctl_snapshot_t *out);
bool __wrap_ls_control_post(ls_control_t *c, const ls_ctl_cmd_t *cmd);

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

/* ---------------------------------------------------------------- fake io */

static ls_core_t g_core;
static ls_Downlink g_rx[MAX_RX];
static uint8_t g_rx_addr[MAX_RX];
static size_t g_nrx;
static uint64_t g_now;
static uint32_t g_seq;
static ls_Request g_rq;
static ls_Uplink g_up;
static uint8_t g_buf[LS_UPLINK_MAX + 64];

/* The event names the paths of these tests choose (`event NAME`): the only
 * names a notice may carry that the schema does not declare. */
static const char *const k_path_event_names[] = { "reached", "ask" };

/* Every notice the core sends: its event id is declared in the schema's enum
 * ls.EventId (or is a path's own, with AUX_NAMED_EVENT's keys) and every data
 * item is "key=value" with a key the schema lists for that id. */
static void assert_notice_declared(const ls_Notice *n)
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

static int fake_send(void *ctx, uint8_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    assert_true(g_nrx < MAX_RX);
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

static const hal_sensor_t g_sensors[2] = {
    { .name = "force_sensor", .n_values = 6 },
    { .name = "laser_standoff_sensor", .n_values = 1 },
};

static ls_Request *req(pb_size_t tag)
{
    memset(&g_rq, 0, sizeof g_rq);
    g_rq.which_cmd = tag;
    return &g_rq;
}

static void send_uplink(uint8_t addr)
{
    pb_ostream_t os = pb_ostream_from_buffer(g_buf, sizeof g_buf);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    ls_core_on_uplink(&g_core, addr, g_buf, os.bytes_written, g_now);
}

/* Send g_rq from addr; the response to it, or NULL when none came (deferred). */
static const ls_Response *send_req(uint8_t addr)
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

static const ls_Response *must(uint8_t addr)
{
    const ls_Response *r = send_req(addr);
    assert_non_null(r);
    return r;
}

static void send_rsvp_reply(uint8_t addr, uint32_t id, int32_t code)
{
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_rsvp_reply_tag;
    g_up.msg.rsvp_reply.rsvp_id = id;
    g_up.msg.rsvp_reply.ret_code = code;
    send_uplink(addr);
}

/* The client nonce of the test's supervisor at `addr` (one client per address). */
static uint64_t nonce_of(uint8_t addr)
{
    return 0x1D0000000000A000u | addr;
}

/* A heartbeat from `addr` carrying the token of its session (0: none). */
static void beat(uint8_t addr, uint64_t now_us)
{
    int i = ls_core_session_of(&g_core, addr);
    ls_core_on_heartbeat(&g_core, addr, i >= 0 ? g_core.sessions[i].hb_token : 0u, now_us);
}

static void connect_host(uint8_t addr)
{
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    c->client_nonce = nonce_of(addr);
    c->has_client_nonce = true;
    snprintf(c->client_name, sizeof c->client_name, "test-%02X", addr);
    assert_int_equal(must(addr)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

/* The configuration of the next setup_core (then back to these defaults). */
static ls_DisconnectAction g_cfg_action = ls_DisconnectAction_DISCONNECT_CONFIGURED;
static uint32_t g_cfg_timeout_ms = 600000;

/* A core with HOST_A connected and owning the device in `state`, HOST_B connected. */
static void setup_core(ls_State state)
{
    const ls_core_config_t cfg = { .device_name = "test",
                                   .firmware_version = "0",
                                   .node_addr = 0x10,
                                   .joint_count = 6,
                                   .heartbeat_timeout_ms = g_cfg_timeout_ms,
                                   .disconnect_action = g_cfg_action };
    g_cfg_action = ls_DisconnectAction_DISCONNECT_CONFIGURED;
    g_cfg_timeout_ms = 600000;
    const ls_core_io_t io = { .send_downlink = fake_send, .ctx = NULL };
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
    g_nrx = 0;
    g_now = 1000000;
    connect_host(HOST_A);
    connect_host(HOST_B);
    g_core.owner = 0;
    g_core.state = state;
    g_nrx = 0;
}

static int setup_locked(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    return 0;
}

static const ls_Notice *nth_notice(size_t from, size_t k)
{
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_notice_tag && k-- == 0) {
            return &g_rx[i].msg.notice;
        }
    }
    return NULL;
}

static size_t count_notices(size_t from)
{
    size_t n = 0;
    for (size_t i = from; i < g_nrx; i++) {
        n += g_rx[i].which_msg == ls_Downlink_notice_tag ? 1u : 0u;
    }
    return n;
}

/* ---------------------------------------------------------------- 1, 2: states and owner, every command */

static const ls_State k_states[] = { ls_State_IDLE,    ls_State_UNLOCKED, ls_State_LOCKED,
                                     ls_State_RESTING, ls_State_MOVING,   ls_State_PAUSED };

static void test_every_command_in_every_state(void **state)
{
    (void)state;
    for (size_t c = 0; c < LS_CMD_COUNT; c++) {
        const ls_cmd_desc_t *d = &ls_cmd_table[c];
        for (size_t s = 0; s < sizeof k_states / sizeof k_states[0]; s++) {
            setup_core(k_states[s]);
            req(d->tag);
            if (d->tag == ls_Request_connect_tag) {
                g_rq.cmd.connect.protocol_version = ls_Protocol_PROTOCOL_VERSION;
                g_rq.cmd.connect.has_protocol_version = true;
                g_rq.cmd.connect.schema_hash = LS_SCHEMA_HASH;
                g_rq.cmd.connect.has_schema_hash = true;
                g_rq.cmd.connect.client_nonce = nonce_of(HOST_A);
                g_rq.cmd.connect.has_client_nonce = true;
            }
            const ls_Response *r = send_req(HOST_A);
            bool valid = (d->states & (uint8_t)k_states[s]) != 0u;
            if (r == NULL) {
                /* only a deferred answer may be missing, and only in a valid state */
                assert_true(valid);
                continue;
            }
            if (valid) {
                if (r->ret_code == ls_RetCode_CMD_WRONG_STATE_ERR) {
                    fail_msg("%s in %s: %s", d->name, ls_State_name(k_states[s]), r->ret_msg);
                }
            } else {
                if (r->ret_code != ls_RetCode_CMD_WRONG_STATE_ERR) {
                    fail_msg("%s in %s answered %d (%s), expected CMD_WRONG_STATE_ERR", d->name,
                             ls_State_name(k_states[s]), (int)r->ret_code, r->ret_msg);
                }
                assert_non_null(strstr(r->ret_msg, d->name));
            }
        }
    }
}

static void test_owner_only_commands_refuse_non_owners(void **state)
{
    (void)state;
    for (size_t c = 0; c < LS_CMD_COUNT; c++) {
        const ls_cmd_desc_t *d = &ls_cmd_table[c];
        for (size_t s = 0; s < sizeof k_states / sizeof k_states[0]; s++) {
            if ((d->states & (uint8_t)k_states[s]) == 0u) {
                continue;
            }
            for (int owner_is_a = 0; owner_is_a < 2; owner_is_a++) {
                setup_core(k_states[s]);
                g_core.owner = owner_is_a ? 0 : 1;
                req(d->tag);
                if (d->tag == ls_Request_connect_tag) {
                    g_rq.cmd.connect.protocol_version = ls_Protocol_PROTOCOL_VERSION;
                    g_rq.cmd.connect.has_protocol_version = true;
                    g_rq.cmd.connect.schema_hash = LS_SCHEMA_HASH;
                    g_rq.cmd.connect.has_schema_hash = true;
                    g_rq.cmd.connect.client_nonce = nonce_of(HOST_A);
                    g_rq.cmd.connect.has_client_nonce = true;
                }
                const ls_Response *r = send_req(HOST_A);
                int32_t code = r != NULL ? r->ret_code : LS_CALL_DEFERRED;
                bool refuse = !owner_is_a && (d->flags & LS_CMD_F_OWNER_ONLY) != 0u;
                if (refuse && code != ls_RetCode_CMD_NOT_OWNER_ERR) {
                    fail_msg("%s from a non-owner in %s answered %d", d->name, ls_State_name(k_states[s]), (int)code);
                }
                if (!refuse && code == ls_RetCode_CMD_NOT_OWNER_ERR) {
                    fail_msg("%s (owner %s) in %s answered CMD_NOT_OWNER_ERR: %s", d->name,
                             owner_is_a ? "caller" : "other", ls_State_name(k_states[s]), r->ret_msg);
                }
                if (refuse) {
                    assert_non_null(strstr(r->ret_msg, "0x22")); /* names the owner */
                }
            }
        }
    }
}

/* ---------------------------------------------------------------- units */

static void test_units_conversions(void **state)
{
    (void)state;
    assert_true(ls_units_to_si_linear(ls_LinearUnit_MILLIMETERS, 1500.0) == 1.5);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_CENTIMETERS, 250.0) == 2.5);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_INCHES, 10.0) == 0.254);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_FEET, 2.0) == 0.6096);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_METERS, 0.125) == 0.125);
    assert_true(ls_units_from_si_linear(ls_LinearUnit_INCHES, 0.0254) == 1.0);
    assert_true(ls_units_from_si_linear(ls_LinearUnit_FEET, 0.9144) == 3.0);
    assert_true(ls_units_to_si_angular(ls_AngularUnit_DEGREES, 180.0) == LS_PI);
    assert_true(ls_units_from_si_angular(ls_AngularUnit_DEGREES, LS_PI / 2) == 90.0);
    assert_true(ls_units_from_si_angular(ls_AngularUnit_RADIANS, 0.5) == 0.5);
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_METERS), "meters");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_MILLIMETERS), "millimeters");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_CENTIMETERS), "centimeters");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_INCHES), "inches");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_FEET), "feet");
    assert_string_equal(ls_units_linear_name((ls_LinearUnit)7), "unknown");
    assert_string_equal(ls_units_angular_name(ls_AngularUnit_RADIANS), "radians");
    assert_string_equal(ls_units_angular_name(ls_AngularUnit_DEGREES), "degrees");
    assert_string_equal(ls_units_angular_name((ls_AngularUnit)2), "unknown");
    assert_true(isnan(ls_units_to_si_linear((ls_LinearUnit)9, 1.0)));
    assert_true(isnan(ls_units_to_si_angular((ls_AngularUnit)-1, 1.0)));
    assert_false(ls_units_linear_valid((ls_LinearUnit)5));
    assert_true(ls_units_linear_valid(ls_LinearUnit_FEET));
    assert_false(ls_units_angular_valid((ls_AngularUnit)2));

    double p[6] = { 100.0, -200.0, 50.0, 90.0, -45.0, 180.0 }, si[6], back[6];
    ls_units_pose_to_si(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES, p, si);
    assert_true(si[0] == 0.1 && si[1] == -0.2 && si[2] == 0.05);
    assert_true(si[3] == LS_PI / 2 && si[4] == -LS_PI / 4 && si[5] == LS_PI);
    ls_units_pose_from_si(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES, si, back);
    for (int i = 0; i < 6; i++) {
        assert_near(back[i], p[i], 1e-12);
    }
    ls_units_pose_to_si(ls_LinearUnit_INCHES, ls_AngularUnit_RADIANS, p, p); /* in place */
    assert_true(p[0] == 2.54 && p[3] == 90.0);
}

static void set_units(ls_LinearUnit lu, ls_AngularUnit au)
{
    ls_SetUnitsReq *u = &req(ls_Request_set_units_tag)->cmd.set_units;
    u->linear = lu;
    u->has_linear = true;
    u->angular = au;
    u->has_angular = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

static void test_units_round_trip(void **state)
{
    (void)state;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);

    req(ls_Request_get_units_tag);
    const ls_Response *r = must(HOST_A); /* the session that set them reads them */
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(r->result.get_units.linear_units, "millimeters");
    assert_string_equal(r->result.get_units.angular_units, "degrees");

    ls_SetToolOffsetReq *t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    const double off[6] = { 10.0, -20.0, 150.0, 90.0, 0.0, -30.0 };
    memcpy(t->offset, off, sizeof off);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_near(g_core.settings.tool_offset[2], 0.15, 1e-15);
    assert_near(g_core.settings.tool_offset[3], LS_PI / 2, 1e-15);

    req(ls_Request_get_tool_offsets_tag);
    r = must(HOST_A);
    assert_int_equal(r->result.get_tool_offsets.offset_count, 6);
    for (int i = 0; i < 6; i++) {
        assert_near(r->result.get_tool_offsets.offset[i], off[i], 1e-9);
    }

    ls_SetSpeedReq *sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_LINEAR_SPEED;
    sp->has_attribute = true;
    sp->speed = 500.0; /* mm/s */
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_ANGULAR_SPEED;
    sp->has_attribute = true;
    sp->speed = 90.0; /* deg/s */
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_PERCENT_SPEED;
    sp->has_attribute = true;
    sp->speed = 40.0;
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_near(g_core.settings.linear_speed_m_s, 0.5, 1e-15);
    assert_near(g_core.settings.angular_speed_rad_s, LS_PI / 2, 1e-15);

    req(ls_Request_get_velocities_tag);
    r = must(HOST_A);
    const ls_GetVelocitiesRes *v = &r->result.get_velocities;
    assert_near(v->percent_velocity, 40.0, 0);
    assert_near(v->world_linear_velocity, 500.0, 1e-9);
    assert_near(v->world_angular_velocity, 90.0, 1e-9);
    assert_int_equal(v->joint_velocities_count, 6);
    /* joint 1: 40 % of 2.5 rad/s = 1 rad/s */
    assert_near(v->joint_velocities[0], 180.0 / LS_PI, 1e-9);
    assert_near(v->joint_velocities[5], 0.4 * 6.0 * 180.0 / LS_PI, 1e-9);

    ls_SetAccelerationReq *ac = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    ac->attribute = ls_AccelType_LINEAR_ACCEL;
    ac->has_attribute = true;
    ac->accel = 2000.0; /* mm/s^2 */
    ac->has_accel = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ac = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    ac->attribute = ls_AccelType_ANGULAR_ACCEL;
    ac->has_attribute = true;
    ac->accel = 360.0; /* deg/s^2 */
    ac->has_accel = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ac = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    ac->attribute = ls_AccelType_PERCENT_ACCEL;
    ac->has_attribute = true;
    ac->accel = 100.0;
    ac->has_accel = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_get_accelerations_tag);
    const ls_GetAccelerationsRes *a = &must(HOST_A)->result.get_accelerations;
    assert_near(a->percent_accel, 100.0, 0);
    assert_near(a->world_linear_accel, 2000.0, 1e-9);
    assert_near(a->world_angular_accel, 360.0, 1e-9);
    assert_near(a->joint_accels[0], 8.0 * 180.0 / LS_PI, 1e-9);

    req(ls_Request_get_max_velocities_tag);
    const ls_GetMaxVelocitiesRes *mv = &must(HOST_A)->result.get_max_velocities;
    assert_near(mv->max_world_linear_velocity, 1000.0, 1e-9);
    assert_near(mv->max_world_angular_velocity, 3.0 * 180.0 / LS_PI, 1e-9);
    assert_int_equal(mv->max_joint_velocities_count, 6);
    assert_near(mv->max_joint_velocities[2], 3.0 * 180.0 / LS_PI, 1e-9);
    req(ls_Request_get_max_accelerations_tag);
    const ls_GetMaxAccelerationsRes *ma = &must(HOST_A)->result.get_max_accelerations;
    assert_near(ma->max_world_linear_accel, 4000.0, 1e-9);
    assert_near(ma->max_world_angular_accel, 12.0 * 180.0 / LS_PI, 1e-9);
    assert_near(ma->max_joint_accels[5], 20.0 * 180.0 / LS_PI, 1e-9);

    /* back to inches: the same SI settings read in the new unit */
    set_units(ls_LinearUnit_INCHES, ls_AngularUnit_RADIANS);
    req(ls_Request_get_tool_offsets_tag);
    r = must(HOST_A);
    assert_near(r->result.get_tool_offsets.offset[2], 0.15 / 0.0254, 1e-9);
    assert_near(r->result.get_tool_offsets.offset[3], LS_PI / 2, 1e-12);
    req(ls_Request_get_velocities_tag);
    assert_near(must(HOST_A)->result.get_velocities.world_linear_velocity, 0.5 / 0.0254, 1e-9);
    /* the other session reads the same SI settings in its own units, SI */
    req(ls_Request_get_tool_offsets_tag);
    r = must(HOST_B);
    assert_near(r->result.get_tool_offsets.offset[2], 0.15, 1e-12);
    req(ls_Request_get_velocities_tag);
    assert_near(must(HOST_B)->result.get_velocities.world_linear_velocity, 0.5, 1e-12);
}

/* ---------------------------------------------------------------- out-of-range and malformed */

static int32_t set_speed(ls_SpeedType t, double v, const char **msg)
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

static int32_t set_accel(ls_AccelType t, double v, const char **msg)
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

static void test_set_refusals_name_value_and_range(void **state)
{
    (void)state;
    const ls_settings_t before = g_core.settings;
    const char *msg;
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 150.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "PERCENT_SPEED 150 %: allowed [0.1, 100]");
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 0.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, -5.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    /* docs/protocol.md "Limits": a subnormal (or anything below 0.1 %) planned a move that never ended */
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 1e-300, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 1e-300, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "PERCENT_ACCEL 1e-300 %: allowed [0.1, 100]");
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 0.09, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 0.1, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 50.0, &msg), ls_RetCode_CMD_EXEC_OK);
    g_core.settings = before;
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, 1.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_SPEED 1.5 meters/s: allowed [0.001, 1]");
    assert_int_equal(set_speed(ls_SpeedType_ANGULAR_SPEED, 3.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "ANGULAR_SPEED 3.5 radians/s: allowed [0.003, 3]");
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, NAN, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, INFINITY, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(set_speed((ls_SpeedType)3, 10.0, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(msg, "PERCENT_SPEED (0), LINEAR_SPEED (1), ANGULAR_SPEED (2)"));

    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 100.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "PERCENT_ACCEL 100.5 %: allowed [0.1, 100]");
    assert_int_equal(set_accel(ls_AccelType_LINEAR_ACCEL, 5.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_ACCEL 5 meters/s^2: allowed [0.004, 4]");
    assert_int_equal(set_accel(ls_AccelType_ANGULAR_ACCEL, 0.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "ANGULAR_ACCEL 0 radians/s^2: allowed [0.012, 12]");
    assert_int_equal(set_accel(ls_AccelType_ANGULAR_ACCEL, -INFINITY, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(set_accel((ls_AccelType)-1, 10.0, &msg), ls_RetCode_CMD_PARAM_ERR);

    ls_SetToolOffsetReq *t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 5;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "setToolOffset takes 6 values (x y z roll pitch yaw), got 5");
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[0] = 0.1;
    t->offset[4] = NAN;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "pitch"));
    ls_SetWorldCartesianFrameReq *w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 0;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "setWorldCartesianFrame takes 6 values (x y z roll pitch yaw), got 0");
    w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 6;
    w->frame[1] = -INFINITY;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_ERR);
    /* docs/protocol.md "Limits": within the arm's reach (ls_robot_model_reach_m), angles within +-2 pi */
    const double reach_m = ls_robot_model_reach_m(g_core.model);
    assert_true(reach_m > 1.0 && reach_m < 2.0);
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 1e308;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(r->ret_msg, "setToolOffset: z 1e+308 meters is beyond the arm's reach"));
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[0] = 4.0;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 6;
    w->frame[3] = 100.0;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(r->ret_msg, "roll 100 radians"));
    w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 6;
    w->frame[1] = -(reach_m + 0.01);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    /* docs/protocol.md "Limits": empty names */
    ls_PathLoadReq *pl = &req(ls_Request_path_load_tag)->cmd.path_load;
    pl->number_of_points = 1;
    pl->has_frame = pl->has_motion_type = pl->has_offset_type = pl->has_number_of_points = true;
    pl->tags_count = 1;
    pl->tags[0].joints_count = 6;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "pathLoad: path_name is empty: give the path a name");

    ls_SetUnitsReq *u = &req(ls_Request_set_units_tag)->cmd.set_units;
    u->linear = (ls_LinearUnit)5;
    u->has_linear = true;
    u->has_angular = true; /* present (RADIANS): the refusal is the linear unit's */
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "linear unit 5"));
    u = &req(ls_Request_set_units_tag)->cmd.set_units;
    u->linear = ls_LinearUnit_MILLIMETERS;
    u->has_linear = true;
    u->angular = (ls_AngularUnit)2;
    u->has_angular = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_ERR);

    /* all-or-nothing: nothing above changed a setting (the half-valid setUnits included) */
    assert_memory_equal(&g_core.settings, &before, sizeof before);
    /* and an offset within the reach is taken */
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 0.25;
    t->offset[5] = -3.0;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_true(g_core.settings.tool_offset[2] == 0.25);
    g_core.settings = before;

    /* the range follows the units */
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, 2000.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_SPEED 2000 millimeters/s: allowed [1, 1000]");
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, 1000.0, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_true(g_core.settings.linear_speed_m_s == 1.0);
    assert_int_equal(set_speed(ls_SpeedType_ANGULAR_SPEED, 171.0, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(set_speed(ls_SpeedType_ANGULAR_SPEED, 173.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "ANGULAR_SPEED 173 degrees/s: allowed [0.171887, 171.887]");
    assert_int_equal(set_accel(ls_AccelType_LINEAR_ACCEL, 4000.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_ACCEL 4000.5 millimeters/s^2: allowed [4, 4000]");
}

static void test_set_commands_in_resting_too(void **state)
{
    (void)state;
    g_core.state = ls_State_RESTING;
    const char *msg;
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 100.0, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_true(g_core.settings.speed_pct == 100.0);
    g_core.state = ls_State_MOVING;
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 10.0, &msg), ls_RetCode_CMD_WRONG_STATE_ERR);
    assert_true(g_core.settings.speed_pct == 100.0);
}

/* ---------------------------------------------------------------- robot position, sensors */

static void test_robot_position_is_the_tool_tip_in_the_world(void **state)
{
    (void)state;
    const double q[6] = { 0.3, -0.4, 0.8, 0.1, 0.6, -0.2 };
    memcpy(g_snap.q_rad, q, sizeof q);
    /* world frame 0.5 m along the base x axis, tool 0.1 m along the flange z axis */
    g_core.settings.world_frame[0] = 0.5;
    g_core.settings.tool_offset[2] = 0.1;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);

    req(ls_Request_get_robot_position_tag);
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    const ls_GetRobotPositionRes *p = &r->result.get_robot_position;
    assert_int_equal(p->joints_count, 6);
    for (int j = 0; j < 6; j++) {
        assert_near(p->joints[j], q[j] * 180.0 / LS_PI, 1e-9);
    }
    double F[16], flange[6];
    assert_int_equal(ls_kin_fk(&ls_robot_model_default, q, F), LS_OK);
    ls_pose_to_xyzrpy(F, flange);
    /* tip = flange origin + 0.1 * flange z axis (third column), minus the world origin */
    const double tip[3] = { F[12] + 0.1 * F[8] - 0.5, F[13] + 0.1 * F[9], F[14] + 0.1 * F[10] };
    assert_int_equal(p->world_pose_count, 6);
    for (int i = 0; i < 3; i++) {
        assert_near(p->world_pose[i], tip[i] * 1000.0, 1e-9);
        assert_near(p->world_pose[i + 3], flange[i + 3] * 180.0 / LS_PI, 1e-9);
    }

    /* a rotated world frame: yaw 90 deg maps base +y to world -x */
    g_core.settings.world_frame[0] = 0.0;
    g_core.settings.world_frame[5] = LS_PI / 2;
    g_core.settings.tool_offset[2] = 0.0;
    req(ls_Request_get_robot_position_tag);
    p = &must(HOST_A)->result.get_robot_position;
    assert_near(p->world_pose[0], F[13] * 1000.0, 1e-9);
    assert_near(p->world_pose[1], -F[12] * 1000.0, 1e-9);
    assert_near(p->world_pose[2], F[14] * 1000.0, 1e-9);

    g_core.ctl = NULL;
    req(ls_Request_get_robot_position_tag);
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_non_null(strstr(r->ret_msg, "no arm backend"));
}

static void test_sensor_reading(void **state)
{
    (void)state;
    const double ft[6] = { 1.5, -2.0, 30.0, 0.25, -0.5, 0.125 };
    memcpy(g_snap.sensor[0], ft, sizeof ft);
    g_snap.sensor[1][0] = 0.2375;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);

    ls_GetSensorReadingReq *s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "force_sensor");
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.get_sensor_reading.current_data_count, 6);
    for (int i = 0; i < 6; i++) {
        assert_true(r->result.get_sensor_reading.current_data[i] == ft[i]); /* N and Nm, unscaled */
    }
    s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "laser_standoff_sensor");
    r = must(HOST_A);
    assert_int_equal(r->result.get_sensor_reading.current_data_count, 1);
    assert_near(r->result.get_sensor_reading.current_data[0], 237.5, 1e-9);
    s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "laser_standoff_sensor");
    assert_near(must(HOST_B)->result.get_sensor_reading.current_data[0], 0.2375, 1e-12); /* B's session: SI */

    s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "sonar");
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_string_equal(r->ret_msg, "no sensor 'sonar': this controller has force_sensor, laser_standoff_sensor");
    g_core.n_sensors = 0;
    req(ls_Request_get_sensor_reading_tag);
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_string_equal(r->ret_msg, "no sensor '': this controller has no sensors");
}

/* ---------------------------------------------------------------- DIO */

static const ls_Response *set_dio(const char *type, int32_t unit, uint32_t on, uint32_t off)
{
    ls_SetDigitalIOReq *d = &req(ls_Request_set_digital_io_tag)->cmd.set_digital_io;
    snprintf(d->type, sizeof d->type, "%s", type);
    d->unit_id = unit;
    d->has_unit_id = true;
    d->bits_on = on;
    d->bits_off = off;
    return send_req(HOST_A);
}

static void test_set_digital_io_refusals(void **state)
{
    (void)state;
    const ls_Response *r = set_dio("analog", 0, 0x10000, 0);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "setDigitalIO: type 'analog' is not supported: the allowed type is 'digital'");
    r = set_dio("digital", 1, 0x10000, 0);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(r->ret_msg, "setDigitalIO: unit 1: allowed 0..0");
    r = set_dio("digital", -1, 0x10000, 0);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    r = set_dio("digital", 0, 0x30000, 0x20000);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "setDigitalIO: bits 0x20000 are in both bitsON and bitsOFF: name each bit once");
    r = set_dio("digital", 0, 0x10003, 0);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(r->ret_msg, "setDigitalIO: bits 0x3 of unit 0 are not outputs: the outputs are 0xFFFF0000");
    assert_int_equal(g_nposted, 0);
    g_post_ok = false;
    r = set_dio("digital", 0, 0x10000, 0);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_BUSY_ERR);
    g_core.ctl = NULL;
    r = set_dio("digital", 0, 0x10000, 0);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_string_equal(r->ret_msg, "setDigitalIO: this controller has no digital I/O");
}

static void test_set_digital_io_answers_when_applied(void **state)
{
    (void)state;
    g_snap.dio[0] = 0x00000005u;
    assert_null(set_dio("digital", 0, 0x00030000u, 0x00400000u)); /* deferred */
    assert_int_equal(g_nposted, 1);
    assert_int_equal(g_posted[0].kind, LS_CTL_DIO_WRITE);
    assert_int_equal(g_posted[0].dio.unit, 0);
    assert_int_equal(g_posted[0].dio.on, 0x00030000u);
    assert_int_equal(g_posted[0].dio.off, 0x00400000u);
    assert_int_equal(g_posted[0].ref_seq, g_seq);

    size_t before = g_nrx;
    g_snap.cycle = 101; /* the cycle running at the post may have taken its commands already */
    g_snap.dio[0] = 0x00030005u;
    ls_dio_tick(&g_core, g_now += 1000);
    assert_int_equal(g_nrx, before);
    g_snap.cycle = 102;
    ls_dio_tick(&g_core, g_now += 1000);
    assert_int_equal(g_nrx, before + 1);
    assert_int_equal(g_rx[before].msg.response.seq, g_seq);
    assert_int_equal(g_rx[before].msg.response.ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_rx[before].msg.response.which_result, ls_Response_set_digital_io_tag);
    assert_string_equal(g_rx[before].msg.response.ret_msg, "unit 0: levels now 0x00030005");

    ls_GetDigitalIOReq *g = &req(ls_Request_get_digital_io_tag)->cmd.get_digital_io;
    snprintf(g->type, sizeof g->type, "digital");
    g->has_unit_id = true; /* unit 0 */
    const ls_Response *r = must(HOST_B);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.get_digital_io.bits_on, 0x00030005u);
    g = &req(ls_Request_get_digital_io_tag)->cmd.get_digital_io;
    snprintf(g->type, sizeof g->type, "digital");
    g->has_unit_id = true; /* unit 0 */
    g->unit_id = 3;
    g->has_unit_id = true;
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    req(ls_Request_get_digital_io_tag)->cmd.get_digital_io.has_unit_id = true;
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_PARAM_ERR); /* type "" */

    /* a write the backend refused: the levels do not follow */
    assert_null(set_dio("digital", 0, 0x00800000u, 0));
    before = g_nrx;
    g_snap.cycle = 104;
    ls_dio_tick(&g_core, g_now += 1000);
    assert_int_equal(g_nrx, before + 1);
    assert_int_equal(g_rx[before].msg.response.ret_code, ls_RetCode_CMD_ERR);
    assert_int_equal(g_rx[before].msg.response.which_result, 0);

    /* a loop that does not run: time-out after 500 ms */
    assert_null(set_dio("digital", 0, 0x00010000u, 0));
    before = g_nrx;
    ls_dio_tick(&g_core, g_now + 499999);
    assert_int_equal(g_nrx, before);
    ls_dio_tick(&g_core, g_now + 500000);
    assert_int_equal(g_nrx, before + 1);
    assert_int_equal(g_rx[before].msg.response.ret_code, ls_RetCode_CMD_TIMEOUT_ERR);
}

static uint32_t signal_dio(uint8_t addr, uint32_t bits, int32_t timeout_ms, int32_t cycle_ms, ls_CallbackType cb,
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

static void assert_data(const ls_Notice *n, const char *d0, const char *d1, const char *d2, const char *d3)
{
    assert_int_equal(n->data_count, 4);
    assert_string_equal(n->data[0], d0);
    assert_string_equal(n->data[1], d1);
    assert_string_equal(n->data[2], d2);
    assert_string_equal(n->data[3], d3);
}

static void test_signal_event_and_alarm_on_change(void **state)
{
    (void)state;
    int32_t code;
    /* HOST_B is not the owner: any connected supervisor may watch */
    uint32_t w1 = signal_dio(HOST_B, 0x5u, 0, 0, ls_CallbackType_CB_EVENT, &code);
    assert_int_equal(code, ls_RetCode_CMD_EXEC_OK);
    uint32_t w2 = signal_dio(HOST_A, 0x4u, 0, 0, ls_CallbackType_CB_ALARM, &code);
    assert_int_equal(code, ls_RetCode_CMD_EXEC_OK);
    assert_int_not_equal(w1, w2);
    size_t before = g_nrx;
    ls_dio_tick(&g_core, g_now += 1000); /* first check: nothing set yet */
    assert_int_equal(g_nrx, before);

    ls_core_on_dio_event(&g_core, 0, 0x1u, 0x1u, g_now += 1000); /* only bit 0 of 0x5 */
    assert_int_equal(g_nrx, before);
    ls_core_on_dio_event(&g_core, 0, 0x5u, 0x4u, g_now += 1000);
    assert_int_equal(count_notices(before), 2);
    const ls_Notice *n = nth_notice(before, 0);
    assert_int_equal(n->kind, ls_NoticeKind_EVENT);
    assert_string_equal(n->event_id, "dioSignal");
    char wid[24];
    snprintf(wid, sizeof wid, "watch=%u", (unsigned)w1);
    assert_data(n, "unit=0", "bits=0x5", "levels=0x5", wid);
    assert_int_equal(g_rx_addr[before], HOST_B);
    n = nth_notice(before, 1);
    assert_int_equal(n->kind, ls_NoticeKind_ALARM);
    assert_int_equal(g_rx_addr[before + 1], HOST_A);
    snprintf(wid, sizeof wid, "watch=%u", (unsigned)w2);
    assert_data(n, "unit=0", "bits=0x4", "levels=0x5", wid);

    /* once only */
    before = g_nrx;
    ls_core_on_dio_event(&g_core, 0, 0x0u, 0x5u, g_now += 1000);
    ls_core_on_dio_event(&g_core, 0, 0x5u, 0x5u, g_now += 1000);
    ls_dio_tick(&g_core, g_now += 1000);
    assert_int_equal(g_nrx, before);
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        assert_int_equal(g_core.dio.watch[i].phase, LS_WATCH_FREE);
    }
}

static void test_signal_fires_at_once_when_bits_are_already_set(void **state)
{
    (void)state;
    g_snap.dio[0] = 0x3u;
    int32_t code;
    size_t before = g_nrx;
    uint32_t w = signal_dio(HOST_A, 0x2u, 0, 0, ls_CallbackType_CB_EVENT, &code);
    assert_int_equal(count_notices(before), 0); /* not before the answer carrying the watch id */
    ls_dio_tick(&g_core, g_now += 1000);
    assert_int_equal(count_notices(before), 1);
    char wid[24];
    snprintf(wid, sizeof wid, "watch=%u", (unsigned)w);
    assert_data(nth_notice(before, 0), "unit=0", "bits=0x2", "levels=0x3", wid);
}

static void test_signal_polling_cycle_and_timeout(void **state)
{
    (void)state;
    int32_t code;
    uint64_t t0 = g_now;
    uint32_t w = signal_dio(HOST_A, 0x8u, 100, 20, ls_CallbackType_CB_EVENT, &code);
    assert_int_equal(code, ls_RetCode_CMD_EXEC_OK);
    size_t before = g_nrx;
    ls_dio_tick(&g_core, t0 + 1000);
    /* polled: a change event does not fire it, the next poll does */
    ls_core_on_dio_event(&g_core, 0, 0x8u, 0x8u, t0 + 5000);
    assert_int_equal(count_notices(before), 0);
    g_snap.dio[0] = 0x8u;
    ls_dio_tick(&g_core, t0 + 19999);
    assert_int_equal(count_notices(before), 0);
    ls_dio_tick(&g_core, t0 + 20000);
    assert_int_equal(count_notices(before), 1);
    assert_string_equal(nth_notice(before, 0)->event_id, "dioSignal");

    /* time-out: kind follows the callback (alarm), the watch ends */
    g_snap.dio[0] = 0x0u;
    t0 = g_now = t0 + 30000;
    w = signal_dio(HOST_A, 0x8u, 100, 0, ls_CallbackType_CB_ALARM_RSVP, &code);
    before = g_nrx;
    ls_dio_tick(&g_core, t0 + 99999);
    assert_int_equal(count_notices(before), 0);
    g_snap.dio[0] = 0x1u;
    ls_dio_tick(&g_core, t0 + 100000);
    assert_int_equal(count_notices(before), 1);
    const ls_Notice *n = nth_notice(before, 0);
    assert_int_equal(n->kind, ls_NoticeKind_ALARM);
    assert_string_equal(n->event_id, "dioSignalTimeout");
    char wid[24];
    snprintf(wid, sizeof wid, "watch=%u", (unsigned)w);
    assert_data(n, "unit=0", "bits=0x8", "levels=0x1", wid);
    ls_core_on_dio_event(&g_core, 0, 0x8u, 0x8u, t0 + 200000);
    assert_int_equal(count_notices(before), 1);

    /* an event-kind time-out */
    t0 = g_now = t0 + 300000;
    signal_dio(HOST_A, 0x8u, 50, 0, ls_CallbackType_CB_EVENT_RSVP, &code);
    before = g_nrx;
    ls_dio_tick(&g_core, t0 + 50000);
    assert_int_equal(nth_notice(before, 0)->kind, ls_NoticeKind_EVENT);
    assert_string_equal(nth_notice(before, 0)->event_id, "dioSignalTimeout");
}

static void test_signal_refusals_and_table_full(void **state)
{
    (void)state;
    int32_t code;
    signal_dio(HOST_A, 0x0u, 0, 0, ls_CallbackType_CB_EVENT, &code);
    assert_int_equal(code, ls_RetCode_CMD_PARAM_ERR);
    ls_SignalDigitalIOReq *s = &req(ls_Request_signal_digital_io_tag)->cmd.signal_digital_io;
    snprintf(s->type, sizeof s->type, "digital");
    s->has_unit_id = s->has_callback_type = true; /* unit 0, CB_EVENT */
    s->bit_string = 1;
    s->polling_timeout_ms = -1;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(r->ret_msg, "signalDigitalIO: pollingTimeOut -1 ms: allowed 0 (no time-out) or more");
    s = &req(ls_Request_signal_digital_io_tag)->cmd.signal_digital_io;
    snprintf(s->type, sizeof s->type, "digital");
    s->has_unit_id = s->has_callback_type = true; /* unit 0, CB_EVENT */
    s->bit_string = 1;
    s->polling_cycle_time_ms = -5;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    signal_dio(HOST_A, 0x1u, 0, 0, (ls_CallbackType)4, &code);
    assert_int_equal(code, ls_RetCode_CMD_PARAM_ERR);
    g_core.dio_info[0].output_mask = 0x00FF0000u;
    s = &req(ls_Request_signal_digital_io_tag)->cmd.signal_digital_io;
    snprintf(s->type, sizeof s->type, "digital");
    s->has_unit_id = s->has_callback_type = true; /* unit 0, CB_EVENT */
    s->bit_string = 0x01000001u;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(r->ret_msg,
                        "signalDigitalIO: bits 0x1000000 are not lines of unit 0: its lines are 0x00FFFFFF");
    s = &req(ls_Request_signal_digital_io_tag)->cmd.signal_digital_io;
    snprintf(s->type, sizeof s->type, "dig");
    s->has_unit_id = s->has_callback_type = true; /* the refusal is the type's */
    s->bit_string = 1;
    const ls_Response *bad_type = must(HOST_A);
    assert_int_equal(bad_type->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_null(strstr(bad_type->ret_msg, "missing"));

    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        assert_int_equal(signal_dio(HOST_A, 0x1u, 0, 0, ls_CallbackType_CB_EVENT, &code), (uint32_t)i + 1u);
    }
    signal_dio(HOST_B, 0x1u, 0, 0, ls_CallbackType_CB_EVENT, &code);
    assert_int_equal(code, ls_RetCode_CMD_NO_RESOURCES_ERR);
}

static void test_watches_end_with_their_session(void **state)
{
    (void)state;
    int32_t code;
    signal_dio(HOST_B, 0x1u, 0, 0, ls_CallbackType_CB_EVENT, &code);
    signal_dio(HOST_A, 0x2u, 0, 0, ls_CallbackType_CB_EVENT, &code);
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ls_dio_tick(&g_core, g_now += 1000);
    int armed = 0;
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        armed += g_core.dio.watch[i].phase == LS_WATCH_ARMED ? 1 : 0;
    }
    assert_int_equal(armed, 1);
    /* HOST_B comes back: its old watch does not fire for it */
    connect_host(HOST_B);
    size_t before = g_nrx;
    ls_core_on_dio_event(&g_core, 0, 0x3u, 0x3u, g_now += 1000);
    assert_int_equal(count_notices(before), 1);
    assert_int_equal(g_rx_addr[before], HOST_A);
}

/* ---------------------------------------------------------------- RSVP */

static int32_t g_done_code;
static bool g_done_timed_out;
static int g_done_calls;

static const char *done_cb(ls_core_t *core, void *ctx, int32_t ret_code, bool timed_out, uint64_t now_us)
{
    (void)now_us;
    assert_ptr_equal(core, &g_core);
    assert_ptr_equal(ctx, &g_done_calls);
    g_done_code = ret_code;
    g_done_timed_out = timed_out;
    g_done_calls++;
    return timed_out ? "default-taken" : (ret_code >= 0 ? "went-on" : "dropped");
}

static void send_rsvp_reply_data(uint8_t addr, uint32_t id, int32_t code, const char *d0)
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
static const ls_RsvpAck *the_ack(size_t from, uint8_t addr)
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
static const char *events_text(void)
{
    ls_SendCommandReq *sc = &req(ls_Request_send_command_tag)->cmd.send_command;
    snprintf(sc->input, sizeof sc->input, "events");
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    return r->result.send_command.result;
}

static void test_rsvp_reply_and_timeout(void **state)
{
    (void)state;
    g_done_calls = 0;
    /* as a path's `rsvp ask T` sends it (ls.EventId AUX_NAMED_EVENT) */
    const char *data[] = { "path=p" };
    size_t before = g_nrx;
    const uint32_t epoch_b = g_core.sessions[1].epoch;
    int32_t id = ls_core_rsvp(&g_core, 1, 77, ls_NoticeKind_EVENT_RSVP, "ask", data, 1, 300, "continue", done_cb,
                              &g_done_calls, g_now);
    assert_true(id > 0);
    const ls_Notice *n = nth_notice(before, 0);
    assert_int_equal(n->rsvp_id, (uint32_t)id);
    assert_int_equal(n->rsvp_timeout_ms, 300);
    assert_string_equal(n->rsvp_default, "continue");
    assert_int_equal(n->ref_seq, 77); /* the request that armed it */
    assert_int_equal(n->session_epoch, epoch_b);
    assert_int_equal(g_rx_addr[before], HOST_B);

    /* another supervisor cannot answer it: refused, naming why */
    before = g_nrx;
    send_rsvp_reply(HOST_A, (uint32_t)id, -7);
    assert_int_equal(g_done_calls, 0);
    const ls_RsvpAck *a = the_ack(before, HOST_A);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(a->action, "");
    assert_non_null(strstr(a->ret_msg, "no RSVP with this id is waiting for 0x21"));

    /* the addressee declines: acknowledged with the action its owner took */
    before = g_nrx;
    send_rsvp_reply_data(HOST_B, (uint32_t)id, -2, "operator=no");
    assert_int_equal(g_done_calls, 1);
    assert_int_equal(g_done_code, -2);
    assert_false(g_done_timed_out);
    a = the_ack(before, HOST_B);
    assert_int_equal(a->rsvp_id, (uint32_t)id);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(a->action, "dropped");
    assert_int_equal(a->ref_seq, 77);
    assert_int_equal(a->session_epoch, epoch_b);
    /* twice: refused, nothing runs again */
    before = g_nrx;
    send_rsvp_reply(HOST_B, (uint32_t)id, 0);
    assert_int_equal(g_done_calls, 1);
    a = the_ack(before, HOST_B);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(a->ret_msg, "already answered (action dropped)"));
    ls_core_tick(&g_core, g_now + 400000);
    assert_int_equal(g_done_calls, 1);

    id = ls_core_rsvp(&g_core, 0, 0, ls_NoticeKind_ALARM_RSVP, "ask", data, 1, 300, "abort", done_cb, &g_done_calls,
                      g_now);
    ls_core_tick(&g_core, g_now + 299999);
    assert_int_equal(g_done_calls, 1);
    ls_core_tick(&g_core, g_now + 300000);
    assert_int_equal(g_done_calls, 2);
    assert_true(g_done_timed_out);
    assert_int_equal(g_done_code, ls_RetCode_CMD_TIMEOUT_ERR);
    /* late: refused with CMD_TIMEOUT_ERR naming the default that was taken */
    before = g_nrx;
    send_rsvp_reply(HOST_A, (uint32_t)id, 0);
    assert_int_equal(g_done_calls, 2);
    a = the_ack(before, HOST_A);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_TIMEOUT_ERR);
    assert_non_null(strstr(a->ret_msg, "late"));
    assert_non_null(strstr(a->ret_msg, "default-taken"));
    /* an id that was never sent */
    before = g_nrx;
    send_rsvp_reply(HOST_A, 4242u, 0);
    assert_int_equal(the_ack(before, HOST_A)->ret_code, ls_RetCode_CMD_PARAM_ERR);

    /* the event log holds every outcome, the reply's data included */
    const char *log = events_text();
    assert_non_null(strstr(log, "declined -2, action dropped, data [operator=no]"));
    assert_non_null(strstr(log, "no answer, default action default-taken"));
    assert_non_null(strstr(log, "refused: already answered"));
    assert_non_null(strstr(log, "refused: late"));
    assert_non_null(strstr(log, "rsvp 4242 from 0x21 refused: unknown id"));
}

/* A dioSignal RSVP from a watch of HOST_B on bit 0: the notice. */
static const ls_Notice *dio_rsvp(uint32_t *watch, uint32_t *req_seq)
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

static int watches_in(ls_watch_phase_t phase)
{
    int k = 0;
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        k += g_core.dio.watch[i].phase == phase ? 1 : 0;
    }
    return k;
}

/* Accept re-arms the watch: it fires again on the bits' next rising edge, not while they stay set. */
static void test_signal_rsvp_accept_rearms_the_watch(void **state)
{
    (void)state;
    uint32_t w, seq;
    const uint32_t rid = dio_rsvp(&w, &seq)->rsvp_id;
    assert_int_equal(watches_in(LS_WATCH_AWAIT_RSVP), 1); /* the slot stays taken until the answer */
    size_t before = g_nrx;
    send_rsvp_reply(HOST_B, rid, ls_RetCode_CMD_EXEC_OK);
    const ls_RsvpAck *a = the_ack(before, HOST_B);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(a->action, "rearm");
    assert_int_equal(a->ref_seq, seq);
    assert_int_equal(g_core.dio.rsvp_replied, 1);
    assert_int_equal(watches_in(LS_WATCH_ARMED), 1);
    /* still set: nothing */
    before = g_nrx;
    ls_dio_tick(&g_core, g_now += 1000);
    ls_core_on_dio_event(&g_core, 0, 0x3u, 0x2u, g_now += 1000);
    assert_int_equal(count_notices(before), 0);
    /* cleared, then set again: a second RSVP of the same watch and request */
    ls_core_on_dio_event(&g_core, 0, 0x0u, 0x3u, g_now += 1000);
    assert_int_equal(count_notices(before), 0);
    ls_core_on_dio_event(&g_core, 0, 0x1u, 0x1u, g_now += 1000);
    assert_int_equal(count_notices(before), 1);
    const ls_Notice *n = nth_notice(before, 0);
    assert_int_equal(n->kind, ls_NoticeKind_EVENT_RSVP);
    assert_int_equal(n->ref_seq, seq);
    assert_int_not_equal(n->rsvp_id, rid);
}

/* Decline cancels the watch: nothing fires any more, its slot is free. */
static void test_signal_rsvp_decline_cancels_the_watch(void **state)
{
    (void)state;
    uint32_t w, seq;
    const uint32_t rid = dio_rsvp(&w, &seq)->rsvp_id;
    size_t before = g_nrx;
    send_rsvp_reply_data(HOST_B, rid, ls_RetCode_CMD_ERR, "why=not now");
    const ls_RsvpAck *a = the_ack(before, HOST_B);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(a->action, "cancel");
    assert_int_equal(watches_in(LS_WATCH_FREE), LS_MAX_DIO_WATCHES);
    before = g_nrx;
    ls_core_on_dio_event(&g_core, 0, 0x0u, 0x1u, g_now += 1000);
    ls_core_on_dio_event(&g_core, 0, 0x1u, 0x1u, g_now += 1000);
    ls_dio_tick(&g_core, g_now += 1000);
    assert_int_equal(count_notices(before), 0);
    char want[160];
    snprintf(want, sizeof want, "rsvp %u dioSignal (seq %u) from 0x22: declined -1, action cancel, data [why=not now]",
             (unsigned)rid, (unsigned)seq);
    assert_non_null(strstr(events_text(), want));
}

static void test_signal_rsvp_unanswered_takes_the_default(void **state)
{
    (void)state;
    int32_t code;
    uint32_t w = signal_dio(HOST_A, 0x1u, 0, 0, ls_CallbackType_CB_ALARM_RSVP, &code);
    size_t before = g_nrx;
    uint64_t t = g_now += 1000;
    ls_core_on_dio_event(&g_core, 0, 0x1u, 0x1u, t);
    assert_int_equal(nth_notice(before, 0)->kind, ls_NoticeKind_ALARM_RSVP);
    const uint32_t rid = nth_notice(before, 0)->rsvp_id;
    before = g_nrx;
    ls_core_tick(&g_core, t + 1999999);
    assert_int_equal(count_notices(before), 0);
    ls_core_tick(&g_core, t + 2000000);
    assert_int_equal(g_core.dio.rsvp_timed_out, 1);
    assert_int_equal(g_core.dio.rsvp_last_code, ls_RetCode_CMD_TIMEOUT_ERR);
    assert_int_equal(count_notices(before), 1);
    const ls_Notice *n = nth_notice(before, 0);
    assert_int_equal(n->kind, ls_NoticeKind_ALARM);
    assert_string_equal(n->event_id, "dioSignalRsvpTimeout");
    char wid[24];
    snprintf(wid, sizeof wid, "watch=%u", (unsigned)w);
    assert_int_equal(n->data_count, 2);
    assert_string_equal(n->data[0], wid);
    assert_string_equal(n->data[1], "action=cancel");
    assert_int_equal(watches_in(LS_WATCH_FREE), LS_MAX_DIO_WATCHES);
    /* an answer now is late */
    before = g_nrx;
    g_now = t + 2000001;
    send_rsvp_reply(HOST_A, rid, 0);
    const ls_RsvpAck *a = the_ack(before, HOST_A);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_TIMEOUT_ERR);
    assert_non_null(strstr(a->ret_msg, "default action (cancel)"));
}

/* ---------------------------------------------------------------- the motion lifecycle (docs/state-machine.md) */

static const double k_home[6] = { 0.0, 0.3, 0.3, 0.0, 0.9, 0.0 };

/* ---------------------------------------------------------------- seq reuse (docs/protocol.md "Sequence numbers") */

/* Send g_rq again with the seq of the previous request; every response to it. */
static size_t resend_same_seq(uint8_t addr, size_t *first)
{
    g_rq.seq = g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    *first = g_nrx;
    send_uplink(addr);
    return g_nrx - *first;
}

/* A connect whose answer was lost is retransmitted byte for byte: the same
 * epoch and heartbeat token come back (a new token would leave the client
 * beating with the one of an answer that arrived late), and the session
 * counts as heard. */
static void test_a_retransmitted_connect_gets_the_same_token(void **state)
{
    (void)state;
    const int i = ls_core_session_of(&g_core, HOST_A);
    assert_true(i >= 0);
    const uint32_t epoch = g_core.sessions[i].epoch;
    connect_host(HOST_A); /* a new connect (new seq) of the same client: a reconnect */
    const uint32_t token2 = g_core.sessions[i].hb_token, epoch2 = g_core.sessions[i].epoch;
    assert_int_not_equal(epoch2, epoch);
    g_now += LS_CONNECT_ANSWER_GRACE_US + 900000; /* past the connect's grace, most of the 1 s time-out */
    size_t first;
    assert_int_equal(resend_same_seq(HOST_A, &first), 1);
    const ls_Response *r = &g_rx[first].msg.response;
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.connect.heartbeat_token, token2);
    assert_int_equal(r->session_epoch, epoch2);
    assert_int_equal(g_core.sessions[i].hb_token, token2);
    assert_int_equal(g_core.sessions[i].last_heard_us, g_now);
}

static void test_seq_reuse_with_another_request_is_refused(void **state)
{
    (void)state;
    ls_SetSpeedReq *sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_PERCENT_SPEED;
    sp->has_attribute = true;
    sp->speed = 40.0;
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    const uint32_t executed = g_core.sessions[0].executed;
    /* the identical bytes again: the cached answer, not run a second time */
    size_t first;
    assert_int_equal(resend_same_seq(HOST_A, &first), 1);
    assert_int_equal(g_rx[first].msg.response.ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.sessions[0].executed, executed);
    /* the same seq with another value: refused, named, not run */
    req(ls_Request_set_speed_tag)->cmd.set_speed.attribute = ls_SpeedType_PERCENT_SPEED;
    g_rq.cmd.set_speed.has_attribute = true;
    g_rq.cmd.set_speed.speed = 80.0;
    g_rq.cmd.set_speed.has_speed = true;
    assert_int_equal(resend_same_seq(HOST_A, &first), 1);
    const ls_Response *r = &g_rx[first].msg.response;
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(r->seq, g_seq);
    assert_non_null(strstr(r->ret_msg, "reused"));
    assert_non_null(strstr(r->ret_msg, "setSpeed"));
    assert_int_not_equal(r->session_epoch, 0);
    assert_int_equal(r->session_epoch, g_core.sessions[0].epoch); /* the refusal is this session's */
    assert_true(fabs(g_core.settings.speed_pct - 40.0) < 1e-9);
    assert_int_equal(g_core.sessions[0].executed, executed);
    /* the same seq with another command: refused as well */
    req(ls_Request_get_units_tag);
    assert_int_equal(resend_same_seq(HOST_A, &first), 1);
    assert_int_equal(g_rx[first].msg.response.ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(g_rx[first].msg.response.ret_msg, "getUnits"));
    /* the original retransmitted after all that: still its cached answer */
    req(ls_Request_set_speed_tag)->cmd.set_speed.attribute = ls_SpeedType_PERCENT_SPEED;
    g_rq.cmd.set_speed.has_attribute = true;
    g_rq.cmd.set_speed.speed = 40.0;
    g_rq.cmd.set_speed.has_speed = true;
    assert_int_equal(resend_same_seq(HOST_A, &first), 1);
    assert_int_equal(g_rx[first].msg.response.ret_code, ls_RetCode_CMD_EXEC_OK);
    /* a new seq runs normally */
    g_rq.cmd.set_speed.speed = 80.0;
    g_rq.cmd.set_speed.has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_true(fabs(g_core.settings.speed_pct - 80.0) < 1e-9);
}

/* ---------------------------------------------------------------- UTF-8 (docs/protocol.md "Strings") */

static void test_utf8_check_and_repair(void **state)
{
    (void)state;
    static const struct {
        const char *s;
        size_t bad; /* index of the first bad byte, or SIZE_MAX: valid */
    } k[] = {
        { "plain ascii", SIZE_MAX },
        { "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80", SIZE_MAX },
        { "ab\xc3", 2 },           /* a character cut in half */
        { "\xff\xfe", 0 },         /* not UTF-8 at all */
        { "x\xc0\xaf", 1 },        /* overlong '/' */
        { "\xe0\x80\xaf", 0 },     /* overlong, 3 bytes */
        { "\xed\xa0\x80", 0 },     /* a surrogate */
        { "\xf4\x90\x80\x80", 0 }, /* beyond U+10FFFF */
        { "a\xe2\x82x", 1 },       /* a continuation missing */
        { "\x80", 0 },             /* a lone continuation byte */
        { "\xf4\x8f\xbf\xbf", SIZE_MAX },
    };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        const size_t len = strlen(k[i].s);
        assert_int_equal(ls_utf8_check(k[i].s, len), k[i].bad == SIZE_MAX ? len : k[i].bad);
    }
    char a[] = "ab\xc3";
    assert_int_equal(ls_utf8_repair(a), 1);
    assert_string_equal(a, "ab");
    char b[] = "a\xe2\x82x\xc3\xa9";
    assert_int_equal(ls_utf8_repair(b), 2);
    assert_string_equal(b, "ax\xc3\xa9");
    char c[] = "caf\xc3\xa9";
    assert_int_equal(ls_utf8_repair(c), 0);
    assert_string_equal(c, "caf\xc3\xa9");
}

static void test_strings_that_are_not_utf8_are_refused_naming_the_field(void **state)
{
    (void)state;
    /* a client name of two bytes that are not UTF-8: no session, the field named */
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    c->client_nonce = nonce_of(0xF5);
    c->has_client_nonce = true;
    snprintf(c->client_name, sizeof c->client_name, "\xff\xfe");
    const ls_Response *r = must(0xF5);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "connect"));
    assert_non_null(strstr(r->ret_msg, "client_name"));
    assert_non_null(strstr(r->ret_msg, "UTF-8"));
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        assert_false(g_core.sessions[i].connected && g_core.sessions[i].addr == 0xF5);
    }
    /* deep inside a repeated message */
    ls_PathLoadReq *l = &req(ls_Request_path_load_tag)->cmd.path_load;
    snprintf(l->path_name, sizeof l->path_name, "p");
    l->number_of_points = 2;
    l->has_frame = l->has_motion_type = l->has_offset_type = l->has_number_of_points = true;
    l->tags_count = 2;
    snprintf(l->tags[1].tag_name, sizeof l->tags[1].tag_name, "t\xc3");
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "pathLoad"));
    assert_non_null(strstr(r->ret_msg, "tags[1].tag_name at byte 1"));
}

static void test_what_the_device_shortens_stays_utf8(void **state)
{
    (void)state;
    /* sendCommand quotes at most 40 bytes of an unknown input: "a" + 63 x "é"
     * puts the cut inside a character */
    ls_SendCommandReq *sc = &req(ls_Request_send_command_tag)->cmd.send_command;
    size_t n = 0;
    sc->input[n++] = 'a';
    for (int i = 0; i < 63; i++) {
        sc->input[n++] = (char)0xC3;
        sc->input[n++] = (char)0xA9;
    }
    sc->input[n] = '\0';
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(ls_utf8_check(r->ret_msg, strlen(r->ret_msg)), strlen(r->ret_msg));
    assert_non_null(strstr(r->ret_msg, "unknown"));
}

/* RESTING with HOST_A the owner; a joint move started: its seq. */
static uint32_t start_move(void)
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
    assert_string_equal(g_core.motion_state, "running_trajectory");
    return r->seq;
}

/* The loop reports the arm at rest with the drives off, two cycles later. */
static void loop_stopped(void)
{
    g_snap.cycle += 2;
    g_snap.enabled = false;
    g_snap.phase = LS_MOTION_IDLE;
    memset(g_snap.qd_rad_s, 0, sizeof g_snap.qd_rad_s);
}

static const ls_Notice *the_final(size_t from, uint32_t seq, size_t *count)
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

static bool has_data(const ls_Notice *n, const char *item)
{
    for (pb_size_t k = 0; k < n->data_count; k++) {
        if (strcmp(n->data[k], item) == 0) {
            return true;
        }
    }
    return false;
}

/* The loop posts a motion event as the control loop does (ls_control.c ev_push). */
static void loop_posts(ls_motion_event_kind_t kind, uint32_t ref_seq)
{
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = LS_CEV_MOTION;
    ev.motion.kind = kind;
    ev.motion.ref_seq = ref_seq;
    const unsigned head = atomic_load(&g_ctl.ev_head);
    g_ctl.ev_ring[head % LS_CTL_QUEUE_LEN] = ev;
    atomic_store(&g_ctl.ev_head, head + 1u);
}

/* A request is answered from the state as of its arrival: the loop's events
 * posted before it count although no ls_core_tick ran in between (the comms
 * thread woke for both at once). */
static void test_a_query_sees_the_loop_events_posted_before_it(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    atomic_store(&g_ctl.ev_tail, atomic_load(&g_ctl.ev_head));
    loop_posts(LS_MEV_PAUSED, move);
    req(ls_Request_get_motion_control_state_tag);
    const ls_Response *r = must(HOST_B);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.get_motion_control_state.state, ls_State_PAUSED);
    assert_string_equal(r->result.get_motion_control_state.motion_control_state, "robot_paused");
    assert_int_equal(atomic_load(&g_ctl.ev_tail), atomic_load(&g_ctl.ev_head)); /* taken, once */
}

static void test_deactivate_while_moving_answers_at_rest(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    const uint32_t epoch = g_core.sessions[0].epoch;
    size_t from = g_nrx, n;
    req(ls_Request_deactivate_tag);
    assert_null(send_req(HOST_A)); /* deferred */
    const uint32_t deact = g_seq;
    assert_int_equal(g_core.state, ls_State_MOVING);
    assert_string_equal(g_core.motion_state, "robot_stopping");
    /* owner-only commands wait for the stop; queries work */
    req(ls_Request_get_motion_control_state_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ls_run_tick(&g_core, g_now + 1000);
    assert_null(the_final(from, move, &n)); /* still moving */
    loop_stopped();
    ls_run_tick(&g_core, g_now + 400000);
    const ls_Notice *f = the_final(from, move, &n);
    assert_non_null(f);
    assert_int_equal(n, 1);
    assert_string_equal(f->event_id, "moveAbsoluteAborted");
    assert_true(has_data(f, "reason=deactivate"));
    assert_int_equal(f->session_epoch, epoch);
    assert_int_equal(g_core.state, ls_State_LOCKED);
    assert_string_equal(g_core.motion_state, "robot_stopped_on_command");
    /* then the deferred answer, after the notice */
    bool answered = false;
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_response_tag && g_rx[i].msg.response.seq == deact) {
            assert_int_equal(g_rx[i].msg.response.ret_code, ls_RetCode_CMD_EXEC_OK);
            assert_true((const void *)&g_rx[i] > (const void *)f); /* sent after the notice */
            answered = true;
        }
    }
    assert_true(answered);
    ls_run_tick(&g_core, g_now + 800000);
    assert_non_null(the_final(from, move, &n));
    assert_int_equal(n, 1); /* exactly one */
}

/* ls_core_next_deadline_us: the event-driven comms thread sleeps until
 * then, so each deadline is exactly when ls_core_tick next acts. */
static void test_next_deadline_is_when_the_tick_acts(void **state)
{
    (void)state;
    g_cfg_timeout_ms = 2000;
    setup_core(ls_State_LOCKED);
    g_done_calls = 0;
    /* Two sessions, heard at connect: the first heartbeat time-out. */
    uint64_t lost = UINT64_MAX;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        if (g_core.sessions[i].connected) {
            const uint64_t t = g_core.sessions[i].last_heard_us + 2000000u + 1u;
            lost = t < lost ? t : lost;
        }
    }
    assert_true(lost != UINT64_MAX);
    assert_true(ls_core_next_deadline_us(&g_core, g_now) == lost);
    /* An RSVP: its time-out is the earliest now. */
    const char *data[] = { "path=p" };
    int32_t id = ls_core_rsvp(&g_core, 0, 0, ls_NoticeKind_ALARM_RSVP, "ask", data, 1, 300, "abort", done_cb,
                              &g_done_calls, g_now);
    assert_true(id > 0);
    const uint64_t due = ls_core_next_deadline_us(&g_core, g_now);
    assert_true(due == g_now + 300000u);
    ls_core_tick(&g_core, due - 1u);
    assert_int_equal(g_done_calls, 0);
    ls_core_tick(&g_core, due);
    assert_int_equal(g_done_calls, 1);
    /* A session's time-out: dropped at the deadline, not a microsecond before. */
    const uint32_t dropped = g_core.sessions_dropped;
    assert_true(ls_core_next_deadline_us(&g_core, due) == lost);
    ls_core_tick(&g_core, lost - 1u);
    assert_int_equal(g_core.sessions_dropped, dropped);
    ls_core_tick(&g_core, lost);
    assert_true(g_core.sessions_dropped > dropped);
}

static void test_next_deadline_of_watches_and_a_halt(void **state)
{
    (void)state;
    int32_t code;
    const uint64_t t0 = g_now;
    /* A polled watch: at once (its first check), then at its period. */
    (void)signal_dio(HOST_A, 0x8u, 100, 20, ls_CallbackType_CB_EVENT, &code);
    assert_int_equal(code, ls_RetCode_CMD_EXEC_OK);
    assert_true(ls_core_next_deadline_us(&g_core, t0) == 0);
    ls_core_tick(&g_core, t0 + 1000);
    assert_true(ls_core_next_deadline_us(&g_core, t0 + 1000) == t0 + 20000u);
    size_t before = g_nrx;
    g_snap.dio[0] = 0x8u;
    ls_core_tick(&g_core, t0 + 20000u);
    assert_int_equal(count_notices(before), 1); /* the tick at that deadline fired it */
    /* A halt follows the snapshot until the arm rests: sampled. */
    (void)start_move();
    req(ls_Request_deactivate_tag);
    assert_null(send_req(HOST_A));
    assert_true(g_core.halt.active);
    assert_true(ls_core_next_deadline_us(&g_core, g_now) == g_now + LS_CORE_SAMPLE_US);
    loop_stopped();
    ls_core_tick(&g_core, g_now + 400000);
    assert_false(g_core.halt.active);
    assert_true(ls_core_next_deadline_us(&g_core, g_now + 400000) > g_now + 400000 + LS_CORE_SAMPLE_US);
}

static void test_emergency_fails_the_motion_once_stopped(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    size_t from = g_nrx, n;
    ls_core_emergency(&g_core, g_now);
    assert_int_equal(g_core.state, ls_State_MOVING); /* the drives are still on */
    assert_string_equal(g_core.fault, "emergency stop frame on the bus");
    assert_null(the_final(from, move, &n));
    loop_stopped();
    ls_run_tick(&g_core, g_now + 1000);
    const ls_Notice *f = the_final(from, move, &n);
    assert_non_null(f);
    assert_int_equal(f->kind, ls_NoticeKind_ALARM);
    assert_string_equal(f->event_id, "moveAbsoluteFailed");
    assert_true(has_data(f, "reason=emergency"));
    assert_int_equal(g_core.state, ls_State_LOCKED);
    assert_string_equal(g_core.motion_state, "robot_stopped_on_error");
}

/* ---------------------------------------------------------------- floods (docs/protocol.md "Budgets under floods") */

static int g_halt_posts;
static const char *fault_log_text(void);

static void count_halt(void *ctx)
{
    (void)ctx;
    g_halt_posts++;
}

static size_t alarms_to(size_t from, uint8_t addr, const char *event_id, const ls_Notice **last)
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

/* 500 EMERGENCY frames in a second (the issue's flood): the first stops at
 * once and raises one alarm; the repeats post no more stops and send no more
 * alarms, and one alarm at the window's end says how many were suppressed. */
static void test_an_emergency_flood_stops_once_and_counts_the_repeats(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    g_core.act.halt = count_halt;
    g_halt_posts = 0;
    const size_t from = g_nrx;
    const uint64_t t0 = g_now;
    ls_core_emergency(&g_core, t0);
    assert_int_equal(g_halt_posts, 1); /* at once */
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 1);
    assert_int_equal(alarms_to(from, HOST_B, "fault", NULL), 1);
    for (uint64_t i = 1; i < 500; i++) {
        ls_core_emergency(&g_core, t0 + i * 2000u);
        ls_core_tick(&g_core, t0 + i * 2000u);
    }
    assert_int_equal(g_halt_posts, 1);
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 1);
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), NULL), 0);
    assert_int_equal(g_core.emergency_frames, 500);
    assert_int_equal(g_core.alarms_suppressed, 499);
    assert_string_equal(g_core.fault, "emergency stop frame on the bus");
    /* the window ends: one alarm with the count, to everyone */
    ls_core_tick(&g_core, t0 + LS_ALARM_WINDOW_MS * 1000u);
    const ls_Notice *sum = NULL;
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), &sum), 1);
    assert_int_equal(alarms_to(from, HOST_B, ls_EventId_name(ls_EventId_alarmsSuppressed), NULL), 1);
    assert_true(has_data(sum, "suppressed=499"));
    assert_true(has_data(sum, "fault=emergency stop frame on the bus"));
    /* a window without repeats: nothing more */
    ls_core_tick(&g_core, t0 + 2u * LS_ALARM_WINDOW_MS * 1000u + 1u);
    ls_core_tick(&g_core, t0 + 3u * LS_ALARM_WINDOW_MS * 1000u + 2u);
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), NULL), 1);
    /* the fault log: the frame, then the count */
    uint32_t n = 0, dropped = 0;
    assert_string_equal(ls_core_fault_entry(&g_core, 0, &n, &dropped)->text, "emergency stop frame on the bus");
    assert_int_equal(n, 2);
    assert_int_equal(dropped, 0);
    assert_non_null(strstr(ls_core_fault_entry(&g_core, 1, NULL, NULL)->text, "499 repeats suppressed"));
    /* the motion still gets its one final notice */
    loop_stopped();
    ls_run_tick(&g_core, t0 + 3u * LS_ALARM_WINDOW_MS * 1000u + 3u);
    size_t finals = 0;
    assert_non_null(the_final(from, move, &finals));
    assert_int_equal(finals, 1);
    /* after the quiet window the next frame is a new alarm */
    ls_core_emergency(&g_core, t0 + 4u * LS_ALARM_WINDOW_MS * 1000u);
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 2);
}

/* Another alarm inside the window is not a repeat: sent at once, after the
 * count of the window's repeats. */
static void test_a_different_alarm_is_not_suppressed(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    const size_t from = g_nrx;
    ls_core_emergency(&g_core, g_now);
    ls_core_emergency(&g_core, g_now + 1000u);
    ls_core_fault(&g_core, "e-stop input", g_now + 2000u);
    assert_int_equal(alarms_to(from, HOST_A, "fault", NULL), 2);
    const ls_Notice *sum = NULL;
    assert_int_equal(alarms_to(from, HOST_A, ls_EventId_name(ls_EventId_alarmsSuppressed), &sum), 1);
    assert_true(has_data(sum, "suppressed=1"));
    assert_string_equal(g_core.fault, "e-stop input");
}

/* The first LS_FAULT_LOG_FIRST entries stay (the start of a cascade), then the
 * latest LS_FAULT_LOG_LATEST; sendCommand faults says how many were dropped. */
static void test_the_fault_log_keeps_the_first_and_the_latest(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    for (int i = 0; i < 40; i++) {
        char text[32];
        snprintf(text, sizeof text, "fault %d", i); /* distinct: none is a repeat */
        ls_core_fault(&g_core, text, g_now + (uint64_t)i);
        g_nrx = 0; /* their alarms are not what this test reads */
    }
    uint32_t n = 0, dropped = 0;
    (void)ls_core_fault_entry(&g_core, 0, &n, &dropped);
    assert_int_equal(n, LS_FAULT_LOG_LEN);
    assert_int_equal(dropped, 40 - LS_FAULT_LOG_LEN);
    for (uint32_t k = 0; k < n; k++) {
        char want[32];
        const uint32_t i = k < LS_FAULT_LOG_FIRST ? k : 40u - LS_FAULT_LOG_LEN + k;
        snprintf(want, sizeof want, "fault %u", (unsigned)i);
        assert_string_equal(ls_core_fault_entry(&g_core, k, NULL, NULL)->text, want);
    }
    assert_null(ls_core_fault_entry(&g_core, n, NULL, NULL));
    const char *text = fault_log_text();
    assert_non_null(strstr(text, "logged=40 dropped=24 "));
    assert_non_null(strstr(text, "fault 3\n... 24 entries dropped"));
    assert_non_null(strstr(text, "fault 39\n"));
    assert_null(strstr(text, "fault 27\n"));
}

static void test_disconnect_during_motion_releases_after_the_stop(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    const uint32_t epoch = g_core.sessions[0].epoch;
    size_t from = g_nrx, n;
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.state, ls_State_MOVING);
    assert_int_equal(g_core.owner, -1);
    loop_stopped();
    ls_run_tick(&g_core, g_now + 1000);
    const ls_Notice *f = the_final(from, move, &n);
    assert_non_null(f);
    assert_int_equal(n, 1);
    assert_true(has_data(f, "reason=disconnect"));
    assert_int_equal(f->session_epoch, epoch);
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
    assert_string_equal(g_core.motion_state, "robot_stopped_on_command");
    /* the same address connects again: a new epoch, so the old notice cannot match */
    connect_host(HOST_A);
    assert_int_not_equal(g_core.sessions[ls_core_session_of(&g_core, HOST_A)].epoch, epoch);
}

/* ---------------------------------------------------------------- one supervisor per address (docs/protocol.md "Identity") */

static const ls_Response *connect_as(uint8_t addr, uint64_t nonce, const char *name)
{
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    c->client_nonce = nonce;
    c->has_client_nonce = true;
    snprintf(c->client_name, sizeof c->client_name, "%s", name);
    return must(addr);
}

/* Another client on the owner's address is refused and changes nothing; the
 * same client (its nonce) reconnects and is the owner again. */
static void test_a_second_client_on_a_live_address_is_refused(void **state)
{
    (void)state;
    const int a = ls_core_session_of(&g_core, HOST_A);
    assert_int_equal(g_core.owner, a);
    const uint32_t epoch = g_core.sessions[a].epoch;
    const uint32_t token = g_core.sessions[a].hb_token;
    req(ls_Request_get_units_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    const uint32_t cached_seq = g_core.sessions[a].last_seq;

    const ls_Response *r = connect_as(HOST_A, nonce_of(HOST_A) ^ 0x5555u, "recorder");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR);
    assert_string_equal(r->ret_msg, "connect: address 0x21 is in use by another client, \"test-21\" (the owner): "
                                    "pass another --source-address, or none to let the host pick a free one");
    assert_int_equal(r->session_epoch, 0);
    assert_false(r->result.connect.owner);
    assert_int_equal(r->result.connect.heartbeat_token, 0);
    assert_int_equal(g_core.connects_refused, 1);
    /* the owner's session is untouched: same epoch, token, owner, retransmission cache */
    assert_int_equal(ls_core_session_of(&g_core, HOST_A), a);
    assert_int_equal(g_core.owner, a);
    assert_int_equal(g_core.sessions[a].epoch, epoch);
    assert_int_equal(g_core.sessions[a].hb_token, token);
    assert_int_equal(g_core.sessions[a].last_seq, cached_seq);
    assert_string_equal(g_core.sessions[a].name, "test-21");

    /* a non-owner's address: refused too, without "the owner" */
    r = connect_as(HOST_B, 7u, "other");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR);
    assert_non_null(strstr(r->ret_msg, "address 0x22 is in use by another client, \"test-22\": pass"));

    /* the same client again: a reconnect, new epoch and token, still the owner */
    r = connect_as(HOST_A, nonce_of(HOST_A), "test-21");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_true(r->result.connect.owner);
    assert_int_equal(g_core.owner, a);
    assert_true(r->result.connect.session_epoch != epoch);
    assert_int_equal(r->result.connect.heartbeat_token, g_core.sessions[a].hb_token);
    assert_true(g_core.sessions[a].hb_token != 0u && g_core.sessions[a].hb_token <= LS_HB_TOKEN_MASK);
    assert_true(r->result.connect.client_nonce == nonce_of(HOST_A)); /* the answer to this connect */

    /* once the session has ended the address is free for anyone */
    req(ls_Request_release_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    r = connect_as(HOST_A, 99u, "newcomer");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_false(r->result.connect.owner);
}

/* Only a heartbeat carrying the session's token keeps it: bare ones, wrong
 * ones and another session's token are counted and change nothing. */
static void test_heartbeats_keep_a_session_only_with_its_token(void **state)
{
    (void)state;
    const uint64_t t0 = g_now;
    const int a = ls_core_session_of(&g_core, HOST_A);
    const int b = ls_core_session_of(&g_core, HOST_B);
    const uint32_t tok_a = g_core.sessions[a].hb_token;
    const uint32_t tok_b = g_core.sessions[b].hb_token;
    assert_true(tok_a != 0u && tok_b != 0u && tok_a != tok_b);
    const uint64_t late = t0 + 500000000u;                   /* well inside the 600 s time-out */
    ls_core_on_heartbeat(&g_core, HOST_A, 0u, late);         /* bare */
    ls_core_on_heartbeat(&g_core, HOST_A, tok_a ^ 1u, late); /* wrong */
    ls_core_on_heartbeat(&g_core, HOST_A, tok_b, late);      /* B's token from A's address */
    ls_core_on_heartbeat(&g_core, 0x30, 0u, late);           /* no session here: not ours, not counted */
    beat(HOST_B, late);
    assert_int_equal(g_core.hb_refused, 3);
    assert_int_equal(g_core.sessions[a].hb_refused, 3);
    assert_int_equal(g_core.sessions[b].hb_refused, 0);
    assert_int_equal(g_core.sessions[a].last_heard_us,
                     t0 + LS_CONNECT_ANSWER_GRACE_US); /* heard until the connect answer can have arrived */
    assert_int_equal(g_core.sessions[b].last_heard_us, late);
    ls_core_tick(&g_core, t0 + LS_CONNECT_ANSWER_GRACE_US + 600000001u);
    assert_int_equal(ls_core_session_of(&g_core, HOST_A), -1); /* the bare heartbeats did not keep it */
    assert_int_equal(ls_core_session_of(&g_core, HOST_B), b);
    assert_int_equal(g_core.owner, -1); /* the owner was lost: the disconnect action ran */
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
    req(ls_Request_send_command_tag);
    snprintf(g_rq.cmd.send_command.input, sizeof g_rq.cmd.send_command.input, "status");
    const ls_Response *r = must(HOST_B);
    assert_non_null(strstr(r->result.send_command.result, "hb_refused=3\n"));
}

/* ---------------------------------------------------------------- the session's contract (docs/protocol.md "Envelope and sessions") */

static const ls_Response *connect_with(uint8_t addr, uint32_t period_ms, ls_DisconnectAction action)
{
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    c->client_nonce = nonce_of(addr);
    c->has_client_nonce = true;
    snprintf(c->client_name, sizeof c->client_name, "test-%02X", addr);
    c->heartbeat_period_ms = period_ms;
    c->disconnect_action = action;
    return must(addr);
}

/* Free session slots for `n` more clients: the profile's LS_MAX_SUPERVISORS
 * (2 on mcu) may not hold them beside setup_core's HOST_A and HOST_B, so
 * those disconnect as needed, HOST_B first. */
static void make_room(int n)
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

static void get_units_of(uint8_t addr, const char *linear, const char *angular)
{
    req(ls_Request_get_units_tag);
    const ls_Response *r = must(addr);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(r->result.get_units.linear_units, linear);
    assert_string_equal(r->result.get_units.angular_units, angular);
}

/* Units belong to the session that set them; a new session starts in SI and the connect answer says so. */
static void test_units_belong_to_the_session(void **state)
{
    (void)state;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);
    get_units_of(HOST_A, "millimeters", "degrees");
    get_units_of(HOST_B, "meters", "radians");
    /* HOST_B's numbers are read in its own units: 0.05 m, not 0.05 mm */
    ls_SetToolOffsetReq *t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 0.05;
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR); /* the owner sets; B only reads */
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 50.0; /* mm */
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_get_tool_offsets_tag);
    assert_near(must(HOST_B)->result.get_tool_offsets.offset[2], 0.05, 1e-12);
    /* a new session of the same supervisor starts in SI, and is told so */
    const ls_Response *r = connect_with(HOST_A, 0, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.connect.linear_unit, ls_LinearUnit_METERS);
    assert_int_equal(r->result.connect.angular_unit, ls_AngularUnit_RADIANS);
    assert_true(r->result.connect.owner); /* ownership stays with the address */
    get_units_of(HOST_A, "meters", "radians");
    req(ls_Request_get_tool_offsets_tag);
    assert_near(must(HOST_A)->result.get_tool_offsets.offset[2], 0.05, 1e-12);
}

/* Only HEARTBEAT frames keep a session; its time-out is max(configured, 5
 * stated periods). Two rounds of two sessions each, so the test holds on
 * every profile (LS_MAX_SUPERVISORS is 2 on mcu). */
static void test_liveness_heartbeats_only_and_the_stated_period(void **state)
{
    (void)state;
    _Static_assert(LS_MAX_SUPERVISORS >= 2, "the test keeps two sessions at once");
    g_cfg_timeout_ms = 1000;
    setup_core(ls_State_LOCKED);
    const uint64_t t0 = g_now;

    /* B keeps sending requests but no heartbeat; A sends heartbeats only */
    g_now = t0 + LS_CONNECT_ANSWER_GRACE_US + 900000;
    req(ls_Request_get_units_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    beat(HOST_A, t0 + LS_CONNECT_ANSWER_GRACE_US + 900000);
    ls_core_tick(&g_core, t0 + LS_CONNECT_ANSWER_GRACE_US + 1000001);
    assert_int_equal(ls_core_session_of(&g_core, HOST_B), -1); /* requests do not keep a session */
    assert_true(ls_core_session_of(&g_core, HOST_A) >= 0);
    ls_core_tick(&g_core, t0 + LS_CONNECT_ANSWER_GRACE_US + 1900001);
    assert_int_equal(ls_core_session_of(&g_core, HOST_A), -1);

    /* stated periods: 5 of them, never below the configured time-out */
    const uint64_t t1 = g_now = t0 + LS_CONNECT_ANSWER_GRACE_US + 2000000;
    const ls_Response *r = connect_with(0x23, 400, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.connect.heartbeat_timeout_ms, 2000);
    r = connect_with(0x24, 100, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_int_equal(r->result.connect.heartbeat_timeout_ms, 1000); /* never below the configured one */
    r = connect_with(0x25, 5, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(r->ret_msg, "connect: heartbeat_period_ms 5: allowed 10..2000 (or 0: not stated, the "
                                    "device's time-out of 1000 ms applies)");
    assert_int_equal(connect_with(0x25, 2001, ls_DisconnectAction_DISCONNECT_CONFIGURED)->ret_code,
                     ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(ls_core_session_of(&g_core, 0x25), -1);
    beat(0x24, t1 + LS_CONNECT_ANSWER_GRACE_US + 900000);
    ls_core_tick(&g_core, t1 + LS_CONNECT_ANSWER_GRACE_US + 1000001);
    assert_true(ls_core_session_of(&g_core, 0x24) >= 0);
    assert_true(ls_core_session_of(&g_core, 0x23) >= 0); /* its own, longer time-out */
    ls_core_tick(&g_core, t1 + LS_CONNECT_ANSWER_GRACE_US + 1900001);
    assert_int_equal(ls_core_session_of(&g_core, 0x24), -1);
    assert_true(ls_core_session_of(&g_core, 0x23) >= 0);
    ls_core_tick(&g_core, t1 + LS_CONNECT_ANSWER_GRACE_US + 2000001);
    assert_int_equal(ls_core_session_of(&g_core, 0x23), -1);
    assert_int_equal(g_core.sessions_dropped, 4);
}

static int g_drive_calls;
static bool g_drives_on;
static int g_stop_calls;

static int fake_drives(void *ctx, bool on)
{
    (void)ctx;
    g_drive_calls++;
    g_drives_on = on;
    return 0;
}

static void fake_stop(void *ctx)
{
    (void)ctx;
    g_stop_calls++;
}

static const ls_Notice *owner_lost_alarm(size_t from)
{
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_notice_tag && strcmp(g_rx[i].msg.notice.event_id, "ownerLost") == 0) {
            return &g_rx[i].msg.notice;
        }
    }
    return NULL;
}

static const char *fault_log_text(void)
{
    ls_SendCommandReq *sc = &req(ls_Request_send_command_tag)->cmd.send_command;
    snprintf(sc->input, sizeof sc->input, "faults");
    return must(HOST_B)->result.send_command.result;
}

/* `stop`: the drives stay on and the lock is kept for the owner's address until it connects again. */
/* Send the request being built from `addr`; assert the answer's code and, when `text` is not NULL, its text. */
static const ls_Response *expect_answer(uint8_t addr, ls_RetCode code, const char *text)
{
    const ls_Response *r = must(addr);
    assert_int_equal(r->ret_code, code);
    if (text != NULL) {
        assert_string_equal(r->ret_msg, text);
    }
    return r;
}

static void test_disconnect_action_stop_keeps_drives_and_lock(void **state)
{
    (void)state;
    g_cfg_action = ls_DisconnectAction_DISCONNECT_STOP;
    setup_core(ls_State_RESTING);
    g_core.act.enable_drives = fake_drives;
    g_drive_calls = 0;
    assert_int_equal(g_core.sessions[0].disconnect_action, ls_DisconnectAction_DISCONNECT_STOP);
    size_t from = g_nrx;
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.state, ls_State_RESTING);
    assert_int_equal(g_drive_calls, 0);
    assert_int_equal(g_core.owner, -1);
    const ls_Notice *n = owner_lost_alarm(from);
    assert_non_null(n);
    assert_true(has_data(n, "action=stop"));
    assert_true(has_data(n, "reason=disconnect"));
    assert_non_null(strstr(fault_log_text(), "owner 0x21 lost (disconnect): action stop"));
    /* the lock is kept: another supervisor is told whose it is and why */
    ls_SetSpeedReq *sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->speed = 50.0;
    sp->has_speed = sp->has_attribute = true; /* PERCENT_SPEED */
    const ls_Response *r = must(HOST_B);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR);
    assert_string_equal(r->ret_msg, "setSpeed needs the owner: 0x21 (test-21) was lost and keeps the lock "
                                    "(disconnect action stop) until it connects again");
    req(ls_Request_lock_tag);
    expect_answer(HOST_B, ls_RetCode_CMD_WRONG_STATE_ERR,
                  "lock is valid in UNLOCKED, the device is RESTING: 0x21 (test-21) was lost and keeps the lock until "
                  "it connects again");
    /* nobody left but the lock is held: not IDLE */
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.state, ls_State_RESTING);
    /* the owner comes back: its lock again */
    r = connect_with(HOST_A, 0, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_true(r->result.connect.owner);
    assert_int_equal(r->result.connect.state, ls_State_RESTING);
    sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->speed = 50.0;
    sp->has_speed = sp->has_attribute = true; /* PERCENT_SPEED */
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

/* Outside a command's states, the owner is told the way there, anyone else whose the way is. */
static void test_wrong_state_names_the_owner_to_the_others(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    req(ls_Request_lock_tag);
    expect_answer(HOST_B, ls_RetCode_CMD_WRONG_STATE_ERR,
                  "lock is valid in UNLOCKED, the device is LOCKED and supervisor 0x21 (test-21) owns it; queries "
                  "still work");
    req(ls_Request_deactivate_tag);
    const ls_Response *r = expect_answer(HOST_B, ls_RetCode_CMD_WRONG_STATE_ERR, NULL);
    assert_non_null(strstr(r->ret_msg, "the device is LOCKED and supervisor 0x21 (test-21) owns it"));
    /* the owner gets the way there */
    req(ls_Request_lock_tag);
    expect_answer(HOST_A, ls_RetCode_CMD_WRONG_STATE_ERR,
                  "lock is valid in UNLOCKED, the device is LOCKED: release the device first");
    /* no owner: the way there */
    g_core.owner = -1;
    g_core.state = ls_State_UNLOCKED;
    req(ls_Request_activate_tag);
    expect_answer(HOST_B, ls_RetCode_CMD_WRONG_STATE_ERR,
                  "activate is valid in LOCKED, the device is UNLOCKED: lock the device first");
}

/* `stop` during a motion: it pauses along the path, is dropped with the drives on, then the notices. */
static void test_disconnect_action_stop_during_a_motion(void **state)
{
    (void)state;
    g_cfg_action = ls_DisconnectAction_DISCONNECT_STOP;
    const uint32_t move = start_move();
    g_core.act.enable_drives = fake_drives;
    g_core.act.stop_motion = fake_stop;
    g_drive_calls = 0;
    g_stop_calls = 0;
    size_t from = g_nrx, n;
    g_nposted = 0;
    beat(HOST_B, g_now + LS_CONNECT_ANSWER_GRACE_US + 600000001u);
    ls_core_tick(&g_core, g_now + LS_CONNECT_ANSWER_GRACE_US + 600000001u); /* the owner's heartbeat is lost */
    assert_int_equal(g_stop_calls, 1);
    assert_int_equal(g_core.state, ls_State_MOVING);
    assert_string_equal(g_core.motion_state, "robot_stopping");
    assert_null(owner_lost_alarm(from));
    g_snap.cycle += 2;
    g_snap.phase = LS_MOTION_PAUSED; /* paused on the path, drives still on */
    ls_run_tick(&g_core, g_now + LS_CONNECT_ANSWER_GRACE_US + 600100000u);
    const ls_Notice *f = the_final(from, move, &n);
    assert_non_null(f);
    assert_int_equal(n, 1);
    assert_true(has_data(f, "reason=ownerLost"));
    assert_int_equal(g_core.state, ls_State_RESTING);
    assert_int_equal(g_drive_calls, 0);
    assert_int_equal(g_posted[g_nposted - 1].kind, LS_CTL_ABORT); /* the executor holds nothing */
    const ls_Notice *a = owner_lost_alarm(from);
    assert_non_null(a);
    assert_true(has_data(a, "action=stop"));
    assert_true(has_data(a, "reason=heartbeat lost"));
}

/* `stop_deactivate`: drives off, LOCKED, the lock kept. */
static void test_disconnect_action_stop_deactivate(void **state)
{
    (void)state;
    g_cfg_action = ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE;
    setup_core(ls_State_RESTING);
    g_core.act.enable_drives = fake_drives;
    g_drive_calls = 0;
    size_t from = g_nrx;
    beat(HOST_B, g_now + LS_CONNECT_ANSWER_GRACE_US + 600000001u);
    ls_core_tick(&g_core, g_now + LS_CONNECT_ANSWER_GRACE_US + 600000001u);
    assert_int_equal(g_drive_calls, 1);
    assert_false(g_drives_on);
    assert_int_equal(g_core.state, ls_State_LOCKED);
    assert_true(g_core.held);
    const ls_Notice *n = owner_lost_alarm(from);
    assert_non_null(n);
    assert_true(has_data(n, "action=stop_deactivate"));
    assert_non_null(strstr(fault_log_text(), "owner 0x21 lost (heartbeat lost): action stop_deactivate"));
    req(ls_Request_release_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR);
}

/* A session may narrow the configured action at connect, never widen it. */
static void test_connect_narrows_the_disconnect_action(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    assert_int_equal(g_core.sessions[0].disconnect_action, ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE);
    g_cfg_action = ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE;
    setup_core(ls_State_LOCKED);
    make_room(2);
    const ls_Response *r = connect_with(0x23, 0, ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(r->ret_msg, "connect: disconnect_action stop_deactivate_release is wider than the "
                                    "configured stop_deactivate: a session may only narrow it");
    r = connect_with(0x23, 0, (ls_DisconnectAction)7);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    r = connect_with(0x23, 0, ls_DisconnectAction_DISCONNECT_STOP);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.connect.disconnect_action, ls_DisconnectAction_DISCONNECT_STOP);
    r = connect_with(0x24, 0, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_int_equal(r->result.connect.disconnect_action, ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE);
}

/* A path with one `dio` auxiliary command, started: its seq. */
static uint32_t start_dio_path(void)
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

static void test_aux_dio_waits_for_the_write_then_goes_on(void **state)
{
    (void)state;
    (void)start_dio_path();
    ls_core_motion_tick(&g_core, g_now);
    assert_int_equal(g_nposted, 1); /* the loop has not taken the write yet */
    g_snap.cycle += 2;
    ls_core_motion_tick(&g_core, g_now); /* taken: a refusal would be drained by the next turn */
    assert_int_equal(g_nposted, 1);
    ls_core_motion_tick(&g_core, g_now);
    assert_int_equal(g_nposted, 2);
    assert_int_equal(g_posted[1].kind, LS_CTL_AUX_DONE);
}

static void test_aux_dio_refused_at_run_time_fails_the_path_and_leaves_it_usable(void **state)
{
    (void)state;
    const uint32_t seq = start_dio_path();
    size_t from = g_nrx, n;
    ls_core_motion_failed(&g_core, seq, "DIO write refused by the backend");
    const ls_Notice *f = the_final(from, seq, &n);
    assert_non_null(f);
    assert_int_equal(n, 1);
    assert_string_equal(f->event_id, "pathMoveFailed");
    assert_true(has_data(f, "reason=auxFailed"));
    assert_true(has_data(f, "at_point=0"));
    assert_true(has_data(f, "fault=DIO write refused by the backend"));
    assert_int_equal(g_posted[g_nposted - 1].kind, LS_CTL_ABORT);
    assert_int_equal(g_core.state, ls_State_RESTING);
    assert_string_equal(g_core.motion_state, "robot_stopped_on_error");
    assert_string_equal(g_core.fault, "");
    /* the path is free again, nothing waits */
    ls_core_motion_tick(&g_core, g_now);
    req(ls_Request_path_clear_path_tag);
    snprintf(g_rq.cmd.path_clear_path.path_name, sizeof g_rq.cmd.path_clear_path.path_name, "io");
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

/* ---------------------------------------------------------------- presence, seq 0, describe (docs/protocol.md) */

static void test_absent_required_fields_are_refused_naming_them(void **state)
{
    (void)state;
    g_core.state = ls_State_RESTING;
    /* a joint move without its frame: refused, named, nothing planned */
    ls_MoveAbsoluteReq *m = &req(ls_Request_move_absolute_tag)->cmd.move_absolute;
    snprintf(m->point_name, sizeof m->point_name, "p1");
    m->values_count = 6;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "moveAbsolute: frame is missing"));
    assert_int_equal(r->which_result, 0);
    assert_int_equal(g_core.state, ls_State_RESTING);
    assert_false(g_core.run.active);
    /* a speed without its attribute: the setting is unchanged */
    const double before = g_core.settings.speed_pct;
    req(ls_Request_set_speed_tag)->cmd.set_speed.speed = 1.0;
    g_rq.cmd.set_speed.has_speed = true;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "setSpeed: attribute is missing"));
    assert_true(g_core.settings.speed_pct == before);
    /* unit 0 is a real unit: an absent unit_id is not it */
    req(ls_Request_get_digital_io_tag);
    snprintf(g_rq.cmd.get_digital_io.type, sizeof g_rq.cmd.get_digital_io.type, "digital");
    r = must(HOST_B);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "getDigitalIO: unit_id is missing"));
    g_rq.cmd.get_digital_io.has_unit_id = true; /* present and 0 */
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    /* connect without a schema hash: refused, no session */
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    r = must(0xF5);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "connect: schema_hash is missing"));
    assert_int_equal(ls_core_session_of(&g_core, 0xF5), -1);
    /* ... and without a client nonce (who it is: docs/protocol.md "Identity") */
    c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    r = must(0xF5);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "connect: client_nonce is missing"));
    assert_int_equal(ls_core_session_of(&g_core, 0xF5), -1);
    /* the state and owner checks come first: their answers do not depend on the fields */
    req(ls_Request_move_absolute_tag);
    r = must(HOST_B);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR);
    g_core.state = ls_State_LOCKED;
    req(ls_Request_move_absolute_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_WRONG_STATE_ERR);
}

static void test_seq_0_is_refused_after_connect(void **state)
{
    (void)state;
    make_room(1);
    /* connect with seq 0 is fine (the seq a client that sets none sends) ... */
    ls_ConnectReq *c = &req(ls_Request_connect_tag)->cmd.connect;
    c->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    c->has_protocol_version = true;
    c->schema_hash = LS_SCHEMA_HASH;
    c->has_schema_hash = true;
    c->client_nonce = nonce_of(0xF5);
    c->has_client_nonce = true;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq; /* seq 0 */
    size_t from = g_nrx;
    send_uplink(0xF5);
    assert_int_equal(g_nrx, from + 1);
    assert_int_equal(g_rx[from].msg.response.ret_code, ls_RetCode_CMD_EXEC_OK);
    /* ... but a lock with seq 0 after it is not its retransmission: refused, nothing runs */
    req(ls_Request_lock_tag);
    g_core.owner = -1;
    g_core.state = ls_State_UNLOCKED;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    from = g_nrx;
    send_uplink(0xF5);
    assert_int_equal(g_nrx, from + 1);
    const ls_Response *r = &g_rx[from].msg.response;
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "lock: seq is 0"));
    assert_int_equal(g_core.owner, -1);
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
}

static uint32_t start_tagged_path(bool give_cycles, int32_t cycles, const char **msg)
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

static void finish_path(uint32_t seq, const ls_Notice **tag, const ls_Notice **fin)
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

static void test_path_move_cycles_absent_is_one_zero_is_a_dry_run_that_says_so(void **state)
{
    (void)state;
    const char *msg;
    const ls_Notice *tag, *fin;
    /* absent: one real cycle (seed 3.5.2), auxiliary commands run */
    uint32_t seq = start_tagged_path(false, 0, &msg);
    assert_int_equal(g_ctl.plan_slot.cycles, 1);
    assert_false(g_ctl.plan_slot.dry_run);
    assert_null(strstr(msg, "dry run"));
    finish_path(seq, &tag, &fin);
    assert_true(has_data(tag, "tag=a-tag-of-sixty-three-bytes-so-long-that-it-did-not-fit-before-x"));
    assert_true(has_data(tag, "path=a-path-name-of-sixty-three-bytes-which-is-what-names-hold-now-x"));
    assert_false(has_data(tag, "dry_run=true"));
    assert_true(has_data(fin, "point=a-path-name-of-sixty-three-bytes-which-is-what-names-hold-now-x"));
    assert_false(has_data(fin, "dry_run=true"));
    /* 0 given: the dry run, and every notice says so */
    seq = start_tagged_path(true, 0, &msg);
    assert_int_equal(g_ctl.plan_slot.cycles, 1);
    assert_true(g_ctl.plan_slot.dry_run);
    assert_non_null(strstr(msg, "dry run"));
    finish_path(seq, &tag, &fin);
    assert_true(has_data(tag, "dry_run=true"));
    assert_true(has_data(fin, "dry_run=true"));
    assert_true(has_data(fin, "reason=complete"));
    /* 2 given: two cycles */
    seq = start_tagged_path(true, 2, &msg);
    assert_int_equal(g_ctl.plan_slot.cycles, 2);
    assert_false(g_ctl.plan_slot.dry_run);
}

/* The final notice's joints: what a user reads, so no 2.6e-20 for a joint held at 0. */
static void test_final_notice_writes_a_joint_at_rest_as_0(void **state)
{
    (void)state;
    const char *msg;
    const uint32_t seq = start_tagged_path(false, 0, &msg);
    size_t from = g_nrx, n;
    ls_motion_event_t done = { .kind = LS_MEV_DONE,
                               .ref_seq = seq,
                               .q_rad = { 2.57046e-20, -0.3, 0.6, 2.95667e-17, 0.9, -1e-12 } };
    ls_core_on_motion_event(&g_core, &done);
    const ls_Notice *fin = the_final(from, seq, &n);
    assert_non_null(fin);
    assert_true(has_data(fin, "joints=0,-0.3,0.6,0,0.9,0"));
}

static void test_describe_publishes_the_limits_from_their_homes(void **state)
{
    (void)state;
    req(ls_Request_describe_tag);
    const ls_Response *r = must(HOST_B); /* any session, not only the owner */
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->which_result, ls_Response_describe_tag);
    const ls_DescribeRes *d = &r->result.describe;
    assert_int_equal(d->max_sessions, LS_MAX_SUPERVISORS);
    assert_int_equal(d->max_paths, LS_PATH_MAX);
    assert_int_equal(d->max_points_per_path, LS_PATH_MAX_POINTS);
    assert_int_equal(d->max_dio_watches, LS_MAX_DIO_WATCHES);
    assert_int_equal(d->max_cycles, LS_PATH_MAX_CYCLES);
    assert_true(d->min_rate_pct == LS_RATE_MIN_PCT);
    /* field limits: the nanopb sizes, e.g. pathLoad.tags (32) and its tag_name (63 bytes) */
    assert_int_equal(d->field_limits_count, LS_FIELD_LIMIT_COUNT);
    bool saw_tags = false, saw_tag_name = false, saw_client = false;
    for (pb_size_t i = 0; i < d->field_limits_count; i++) {
        const ls_FieldLimit *f = &d->field_limits[i];
        if (f->path_count == 3 && f->path[0] == ls_Uplink_request_tag && f->path[1] == ls_Request_path_load_tag &&
            f->path[2] == ls_PathLoadReq_tags_tag) {
            assert_int_equal(f->max_count, pb_arraysize(ls_PathLoadReq, tags));
            assert_int_equal(f->max_bytes, 0);
            saw_tags = true;
        }
        if (f->path_count == 4 && f->path[1] == ls_Request_path_load_tag && f->path[3] == ls_TagPoint_tag_name_tag) {
            assert_int_equal(f->max_bytes, 63);
            saw_tag_name = true;
        }
        if (f->path_count == 3 && f->path[1] == ls_Request_connect_tag && f->path[2] == ls_ConnectReq_client_name_tag) {
            assert_true(f->max_bytes >= 63);
            saw_client = true;
        }
    }
    assert_true(saw_tags && saw_tag_name && saw_client);
    /* the DIO map, the sensors with their components, the model */
    assert_int_equal(d->dio_units_count, 1);
    assert_int_equal(d->dio_units[0].output_mask, 0xFFFF0000u);
    assert_int_equal(d->dio_units[0].input_mask, 0x0000FFFFu);
    assert_int_equal(d->sensors_count, 2);
    assert_string_equal(d->sensors[0].name, "force_sensor");
    assert_int_equal(d->sensors[0].components_count, 6);
    assert_string_equal(d->sensors[0].components[2].name, "Fz");
    assert_string_equal(d->sensors[0].components[2].unit, "N");
    assert_string_equal(d->sensors[0].components[5].unit, "Nm");
    assert_string_equal(d->sensors[1].components[0].name, "distance");
    assert_string_equal(d->sensors[1].components[0].unit, "m");
    assert_int_equal(d->tools_count, 0); /* no tool changer composed here */
    const ls_robot_model_t *mdl = &ls_robot_model_default;
    assert_int_equal(d->joints_count, LS_N_JOINTS);
    assert_true(d->joints[1].min_rad == mdl->q_min_rad[1] && d->joints[1].max_rad == mdl->q_max_rad[1]);
    assert_true(d->joints[5].max_velocity_rad_s == mdl->qd_max_rad_s[5]);
    assert_true(d->max_linear_speed_m_s == mdl->max_linear_speed_m_s);
    assert_int_equal(d->workspace_max_m_count, 3);
    assert_true(d->workspace_max_m[2] == mdl->workspace_max_m[2]);
    assert_true(d->reach_m == ls_robot_model_reach_m(mdl));
}

/* describeRobot: the URDF of the running model in pieces that join into
 * ls_robot_urdf_window's text; an offset past its end is refused. */
static void test_describe_robot_sends_the_urdf_of_the_model_in_pieces(void **state)
{
    (void)state;
    static char whole[16384], joined[16384];
    size_t total = 0;
    assert_true(ls_robot_urdf_window(g_core.model, 0, whole, sizeof whole, &total) > 0);
    uint32_t offset = 0;
    int pieces = 0;
    do {
        req(ls_Request_describe_robot_tag)->cmd.describe_robot.offset = offset;
        const ls_Response *r = must(HOST_B); /* any session, not only the owner */
        assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
        assert_int_equal(r->which_result, ls_Response_describe_robot_tag);
        const ls_DescribeRobotRes *d = &r->result.describe_robot;
        assert_int_equal(d->total_bytes, total);
        assert_int_equal(d->offset, offset);
        assert_string_equal(d->robot_model, "ls-sim6");
        assert_string_equal(d->ik_class, "spherical_wrist");
        const size_t n = strlen(d->urdf);
        assert_true(n > 0 && n < sizeof d->urdf);
        memcpy(joined + offset, d->urdf, n);
        offset += (uint32_t)n;
        pieces++;
    } while (offset < total);
    assert_memory_equal(joined, whole, total);
    assert_true(pieces > 1); /* longer than one answer */
    req(ls_Request_describe_robot_tag)->cmd.describe_robot.offset = (uint32_t)total;
    const ls_Response *end = must(HOST_B);
    assert_int_equal(end->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(end->result.describe_robot.urdf, "");
    req(ls_Request_describe_robot_tag)->cmd.describe_robot.offset = (uint32_t)total + 1;
    const ls_Response *past = must(HOST_B);
    assert_int_equal(past->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(past->ret_msg, "is past the end of the URDF"));
}

/* Every final notice the core sends is declared in the schema: each ending
 * of every non-blocking command, and each ending of the sensor-guided moves
 * (the generated finals of ls_cmd_table, protocol/gen_registry.py). */
static void test_every_final_notice_id_is_declared_in_the_schema(void **state)
{
    (void)state;
    size_t checked = 0;
    for (size_t i = 0; i < LS_CMD_COUNT; i++) {
        const ls_cmd_desc_t *d = &ls_cmd_table[i];
        if ((d->flags & LS_CMD_F_BLOCKING) != 0u) {
            assert_null(d->finals); /* a blocking command answers; it sends no final notice */
            continue;
        }
        for (int why = 0; why < (int)LS_RUN_END_COUNT; why++) {
            const ls_EventId id = ls_motion_end_final(d->finals, (ls_MotionEnd)why);
            if (id == ls_EventId_EVENT_ID_NONE) {
                fail_msg("%s%s (ending %s) is not declared in enum EventId", d->name,
                         ls_run_end_suffix((ls_run_end_t)why), ls_run_end_name((ls_run_end_t)why));
            }
            /* the id's name is the command's and the ending's: <command><suffix> */
            char want[48];
            snprintf(want, sizeof want, "%s%s", d->name, ls_run_end_suffix((ls_run_end_t)why));
            assert_string_equal(ls_EventId_name(id), want);
            checked++;
        }
    }
    const pb_size_t react[] = { ls_Request_move_react_tag, ls_Request_comply_tag };
    for (size_t i = 0; i < 2; i++) {
        const ls_cmd_desc_t *d = ls_cmd_find(react[i]);
        for (int end = LS_REACT_END_THRESHOLD; end <= LS_REACT_END_NO_SENSOR; end++) {
            if (ls_core_sensor_final(d->finals, (ls_react_end_t)end) == ls_EventId_EVENT_ID_NONE) {
                fail_msg("%s: the ending %d is not declared in enum EventId", d->name, end);
            }
            checked++;
        }
    }
    assert_true(checked >= 6u * LS_RUN_END_COUNT);
    /* and the lookup refuses what the schema does not declare */
    assert_int_equal(ls_motion_end_final(NULL, ls_MotionEnd_END_COMPLETE), ls_EventId_EVENT_ID_NONE);
    assert_int_equal(ls_event_find("moveComplete"), ls_EventId_EVENT_ID_NONE);
    assert_int_equal(ls_event_find("AUX_NAMED_EVENT"), ls_EventId_EVENT_ID_NONE);
    assert_string_equal(ls_EventId_name(ls_event_find("moveAbsoluteComplete")), "moveAbsoluteComplete");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_final_notice_id_is_declared_in_the_schema),
        cmocka_unit_test(test_every_command_in_every_state),
        cmocka_unit_test(test_owner_only_commands_refuse_non_owners),
        cmocka_unit_test(test_units_conversions),
        cmocka_unit_test_setup(test_units_round_trip, setup_locked),
        cmocka_unit_test_setup(test_set_refusals_name_value_and_range, setup_locked),
        cmocka_unit_test_setup(test_set_commands_in_resting_too, setup_locked),
        cmocka_unit_test_setup(test_robot_position_is_the_tool_tip_in_the_world, setup_locked),
        cmocka_unit_test_setup(test_sensor_reading, setup_locked),
        cmocka_unit_test_setup(test_set_digital_io_refusals, setup_locked),
        cmocka_unit_test_setup(test_set_digital_io_answers_when_applied, setup_locked),
        cmocka_unit_test_setup(test_signal_event_and_alarm_on_change, setup_locked),
        cmocka_unit_test_setup(test_signal_fires_at_once_when_bits_are_already_set, setup_locked),
        cmocka_unit_test_setup(test_signal_polling_cycle_and_timeout, setup_locked),
        cmocka_unit_test_setup(test_signal_refusals_and_table_full, setup_locked),
        cmocka_unit_test_setup(test_watches_end_with_their_session, setup_locked),
        cmocka_unit_test_setup(test_rsvp_reply_and_timeout, setup_locked),
        cmocka_unit_test(test_next_deadline_is_when_the_tick_acts),
        cmocka_unit_test_setup(test_next_deadline_of_watches_and_a_halt, setup_locked),
        cmocka_unit_test_setup(test_signal_rsvp_accept_rearms_the_watch, setup_locked),
        cmocka_unit_test_setup(test_signal_rsvp_decline_cancels_the_watch, setup_locked),
        cmocka_unit_test_setup(test_signal_rsvp_unanswered_takes_the_default, setup_locked),
        cmocka_unit_test_setup(test_seq_reuse_with_another_request_is_refused, setup_locked),
        cmocka_unit_test_setup(test_a_retransmitted_connect_gets_the_same_token, setup_locked),
        cmocka_unit_test(test_utf8_check_and_repair),
        cmocka_unit_test_setup(test_strings_that_are_not_utf8_are_refused_naming_the_field, setup_locked),
        cmocka_unit_test_setup(test_what_the_device_shortens_stays_utf8, setup_locked),
        cmocka_unit_test(test_a_query_sees_the_loop_events_posted_before_it),
        cmocka_unit_test(test_deactivate_while_moving_answers_at_rest),
        cmocka_unit_test(test_emergency_fails_the_motion_once_stopped),
        cmocka_unit_test(test_an_emergency_flood_stops_once_and_counts_the_repeats),
        cmocka_unit_test(test_a_different_alarm_is_not_suppressed),
        cmocka_unit_test(test_the_fault_log_keeps_the_first_and_the_latest),
        cmocka_unit_test(test_disconnect_during_motion_releases_after_the_stop),
        cmocka_unit_test(test_aux_dio_waits_for_the_write_then_goes_on),
        cmocka_unit_test(test_aux_dio_refused_at_run_time_fails_the_path_and_leaves_it_usable),
        cmocka_unit_test_setup(test_units_belong_to_the_session, setup_locked),
        cmocka_unit_test(test_liveness_heartbeats_only_and_the_stated_period),
        cmocka_unit_test(test_disconnect_action_stop_keeps_drives_and_lock),
        cmocka_unit_test(test_wrong_state_names_the_owner_to_the_others),
        cmocka_unit_test(test_disconnect_action_stop_during_a_motion),
        cmocka_unit_test(test_disconnect_action_stop_deactivate),
        cmocka_unit_test(test_connect_narrows_the_disconnect_action),
        cmocka_unit_test_setup(test_absent_required_fields_are_refused_naming_them, setup_locked),
        cmocka_unit_test_setup(test_seq_0_is_refused_after_connect, setup_locked),
        cmocka_unit_test_setup(test_a_second_client_on_a_live_address_is_refused, setup_locked),
        cmocka_unit_test_setup(test_heartbeats_keep_a_session_only_with_its_token, setup_locked),
        cmocka_unit_test(test_path_move_cycles_absent_is_one_zero_is_a_dry_run_that_says_so),
        cmocka_unit_test(test_final_notice_writes_a_joint_at_rest_as_0),
        cmocka_unit_test_setup(test_describe_publishes_the_limits_from_their_homes, setup_locked),
        cmocka_unit_test_setup(test_describe_robot_sends_the_urdf_of_the_model_in_pieces, setup_locked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
