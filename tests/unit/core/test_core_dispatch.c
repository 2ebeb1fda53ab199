/* The controller core, black box (core_fixture.h). The dispatcher: every
 * command in every state, the owner rule, the seq rules and the retransmission
 * cache, UTF-8, the presence rules, describe and the generated final notices. */
#include "core_fixture.h"

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
    assert_int_equal(r->ret_code, ls_RetCode_CMD_SEQ_CONFLICT_ERR);
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
    assert_int_equal(g_rx[first].msg.response.ret_code, ls_RetCode_CMD_SEQ_CONFLICT_ERR);
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

/* A connect with seq 0 has no seq to be retransmitted by: every one opens
 * a new session (new epoch and token), byte-identical or not; with seq > 0
 * the same bytes again are a retransmission (docs/protocol.md "Sequence
 * numbers"). */
static void test_a_connect_with_seq_0_is_never_answered_from_the_cache(void **state)
{
    (void)state;
    const int i = ls_core_session_of(&g_core, HOST_A);
    uint32_t epochs[3];
    for (int k = 0; k < 3; k++) {
        (void)connect_req(HOST_A);
        g_seq = 0;
        size_t first;
        assert_int_equal(resend_same_seq(HOST_A, &first), 1);
        assert_int_equal(g_rx[first].msg.response.ret_code, ls_RetCode_CMD_EXEC_OK);
        epochs[k] = g_rx[first].msg.response.session_epoch;
        assert_int_equal(g_core.sessions[i].epoch, epochs[k]);
    }
    assert_true(epochs[0] != epochs[1] && epochs[1] != epochs[2]);
    assert_int_equal(g_core.owner, i); /* the same client: ownership kept */
}

/* A connect from another schema is refused with the device's protocol
 * version and schema hash as numbers (ConnectRes), not only in the text,
 * and the text speaks of the client, not of one host tool. */
static void test_a_version_refusal_carries_the_device_hash(void **state)
{
    (void)state;
    ls_ConnectReq *c = connect_req(0x30);
    c->schema_hash = LS_SCHEMA_HASH ^ 1u;
    const ls_Response *r = must(0x30);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_VERSION_MISMATCH_ERR);
    assert_int_equal(r->which_result, ls_Response_connect_tag);
    assert_int_equal(r->result.connect.schema_hash, LS_SCHEMA_HASH);
    assert_int_equal(r->result.connect.protocol_version, ls_Protocol_PROTOCOL_VERSION);
    assert_int_equal(r->result.connect.heartbeat_token, 0); /* no session */
    assert_non_null(strstr(r->ret_msg, "build the client from the device's protocol/landscape.proto"));
    assert_int_equal(ls_core_session_of(&g_core, 0x30), LS_NO_SESSION);
}

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
    /* the texts the device sends: e.g. a notice's event id (31 bytes) */
    assert_int_equal(d->downlink_limits_count, LS_DOWNLINK_LIMIT_COUNT);
    bool saw_event_id = false;
    for (pb_size_t i = 0; i < d->downlink_limits_count; i++) {
        const ls_FieldLimit *f = &d->downlink_limits[i];
        assert_true(f->max_bytes > 0); /* strings only */
        if (f->path_count == 2 && f->path[0] == ls_Downlink_notice_tag && f->path[1] == ls_Notice_event_id_tag) {
            assert_int_equal(f->max_bytes, sizeof(((ls_Notice *)0)->event_id) - 1u);
            saw_event_id = true;
        }
    }
    assert_true(saw_event_id);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_final_notice_id_is_declared_in_the_schema),
        cmocka_unit_test(test_every_command_in_every_state),
        cmocka_unit_test(test_owner_only_commands_refuse_non_owners),
        cmocka_unit_test_setup(test_seq_reuse_with_another_request_is_refused, setup_locked),
        cmocka_unit_test_setup(test_a_retransmitted_connect_gets_the_same_token, setup_locked),
        cmocka_unit_test_setup(test_a_connect_with_seq_0_is_never_answered_from_the_cache, setup_locked),
        cmocka_unit_test_setup(test_a_version_refusal_carries_the_device_hash, setup_locked),
        cmocka_unit_test(test_utf8_check_and_repair),
        cmocka_unit_test_setup(test_strings_that_are_not_utf8_are_refused_naming_the_field, setup_locked),
        cmocka_unit_test_setup(test_what_the_device_shortens_stays_utf8, setup_locked),
        cmocka_unit_test_setup(test_absent_required_fields_are_refused_naming_them, setup_locked),
        cmocka_unit_test_setup(test_seq_0_is_refused_after_connect, setup_locked),
        cmocka_unit_test_setup(test_describe_publishes_the_limits_from_their_homes, setup_locked),
        cmocka_unit_test_setup(test_describe_robot_sends_the_urdf_of_the_model_in_pieces, setup_locked),
        cmocka_unit_test(test_wrong_state_names_the_owner_to_the_others),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
