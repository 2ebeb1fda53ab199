/* The controller core, black box (core_fixture.h). Sessions (docs/protocol.md
 * "Identity", "Liveness", "Disconnect handler"): one client per address,
 * heartbeats with their token, the stated period, and the disconnect actions. */
#include "core_fixture.h"

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
                                    "connect from an address no live session uses");
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
    assert_non_null(strstr(r->ret_msg, "address 0x22 is in use by another client, \"test-22\": connect from"));

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
    const uint64_t late = t0 + 500000000u;                           /* well inside the 600 s time-out */
    ls_core_on_heartbeat(&g_core, HOST_A, 0u, 0u, 0u, late);         /* bare */
    ls_core_on_heartbeat(&g_core, HOST_A, 0u, 0u, tok_a ^ 1u, late); /* wrong */
    ls_core_on_heartbeat(&g_core, HOST_A, 0u, 0u, tok_b, late);      /* B's token from A's address */
    ls_core_on_heartbeat(&g_core, 0x30, 0u, 0u, 0u, late);           /* no session here: not ours, not counted */
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
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_stopping");
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

/* The connect's grace covers the time its answer may take; a request after
 * it shows the answer arrived, so from then on the heartbeat time-out
 * applies: a client that connects, locks and dies is dropped (and the lock
 * released) its time-out after the lock, not 3 s later (docs/protocol.md
 * "Liveness"). */
static void test_a_request_ends_the_connect_grace(void **state)
{
    (void)state;
    g_cfg_timeout_ms = 1000;
    setup_core(ls_State_UNLOCKED);
    g_core.owner = LS_NO_SESSION;
    const int b = ls_core_session_of(&g_core, HOST_B);
    connect_host(HOST_B); /* a fresh connect: its grace starts now */
    assert_int_equal(g_core.sessions[b].last_heard_us, g_now + LS_CONNECT_ANSWER_GRACE_US);
    g_now += 200000;
    req(ls_Request_lock_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.sessions[b].last_heard_us, g_now);
    beat(HOST_A, g_now + 1000000);
    ls_core_tick(&g_core, g_now + 1000001); /* no heartbeat since the lock: dropped, the lock released */
    assert_int_equal(ls_core_session_of(&g_core, HOST_B), LS_NO_SESSION);
    assert_int_equal(g_core.owner, LS_NO_SESSION);
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
}

/* The transport's counters at their budget: LS_TRANSPORT_DESCRIBE_MAX - 1
 * bytes, its last line named so the test can find it whole. */
static void longest_transport(void *ctx, char *buf, size_t cap)
{
    (void)ctx;
    const char *tail = "last_counter=4294967295\n";
    const size_t want = LS_TRANSPORT_DESCRIBE_MAX - 1u;
    assert_true(cap > want);
    memset(buf, 'x', want - strlen(tail));
    for (size_t k = 63; k < want - strlen(tail); k += 64) {
        buf[k] = '\n';
    }
    memcpy(buf + want - strlen(tail), tail, strlen(tail) + 1u);
}

/* sendCommand status at its longest (every session with the longest name,
 * every watch, every counter at ten digits, the longest fault, a line per
 * drive at its longest, the transport's counters at their budget) arrives
 * whole: docs/protocol.md "sendCommand". */
static void test_send_command_status_at_its_longest_is_whole(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    g_core.io.describe = longest_transport;
    memset(g_core.fault, 'f', sizeof g_core.fault - 1u);
    g_core.fault[sizeof g_core.fault - 1u] = '\0';
    g_core.rx_malformed = g_core.tx_lost = g_core.sessions_dropped = UINT32_MAX;
    g_core.hb_refused = g_core.connects_refused = UINT32_MAX;
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        ls_session_t *s = &g_core.sessions[i];
        s->connected = true;
        s->addr = (uint8_t)(0x30 + i);
        memset(s->name, 'n', sizeof s->name - 1u);
        s->name[sizeof s->name - 1u] = '\0';
        s->units = (ls_units_t){ .linear = ls_LinearUnit_MILLIMETERS, .angular = ls_AngularUnit_DEGREES };
        s->heartbeat_timeout_ms = s->hb_refused = s->executed = UINT32_MAX;
        s->disconnect_action = ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE;
    }
    g_core.sessions[0].addr = HOST_A;
    for (int i = 0; i < LS_MAX_DIO_WATCHES; i++) {
        ls_dio_watch_t *w = &g_core.dio.watch[i];
        w->phase = LS_WATCH_AWAIT_RSVP;
        w->id = w->bits = w->fired = UINT32_MAX;
        w->unit = UINT16_MAX;
        w->addr = 0xFF;
    }
    g_readout_rc = LS_OK;
    g_readout = (hal_arm_readout_t){ .t_us = 1u, .n_joints = LS_N_JOINTS };
    for (int j = 0; j < LS_N_JOINTS; j++) {
        g_readout.joint[j] = (hal_drive_readout_t){ .node = 0x7F,
                                                    .state = "A STATE NAME LONGER THAN ANY CIA 402 ONE",
                                                    .mode = INT8_MIN,
                                                    .last_error = 0xFFFF,
                                                    .brake = HAL_TRI_OFF,
                                                    .sto = HAL_TRI_ON,
                                                    .home = HAL_HOME_NOT_HOMED,
                                                    .home_required = true };
    }
    req(ls_Request_send_command_tag);
    snprintf(g_rq.cmd.send_command.input, sizeof g_rq.cmd.send_command.input, "status");
    const char *out = must(HOST_A)->result.send_command.result;
    assert_non_null(strstr(out, "drive j6 node=0x7F")); /* the drives' lines are there */
    const size_t n = strlen(out);
    print_message("status at its longest: %zu bytes of %zu\n", n,
                  sizeof g_rx[0].msg.response.result.send_command.result);
    assert_true(n + 1u < sizeof g_rx[0].msg.response.result.send_command.result);
    assert_true(n > strlen("last_counter=4294967295\n"));
    assert_string_equal(out + n - strlen("last_counter=4294967295\n"), "last_counter=4294967295\n");
}

/* A request from an address whose session the device ended names why, so a
 * supervisor that sent no disconnect learns that one came from its address
 * (or that its heartbeats stopped arriving). */
static void test_a_refusal_without_a_session_names_why_it_ended(void **state)
{
    (void)state;
    req(ls_Request_release_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    const uint32_t epoch = g_core.sessions[ls_core_session_of(&g_core, HOST_A)].epoch;
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_get_units_tag);
    const ls_Response *r = send_req(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_CONNECTED_ERR);
    char want[128];
    snprintf(want, sizeof want, "getUnits: supervisor 0x21 has no session (its session %u ended: disconnect requested)",
             (unsigned)epoch);
    assert_non_null(strstr(r->ret_msg, want));
    /* an address that never had one: no cause */
    req(ls_Request_get_units_tag);
    r = send_req(0x33);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_CONNECTED_ERR);
    assert_null(strstr(r->ret_msg, "ended"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_a_second_client_on_a_live_address_is_refused, setup_locked),
        cmocka_unit_test_setup(test_heartbeats_keep_a_session_only_with_its_token, setup_locked),
        cmocka_unit_test(test_liveness_heartbeats_only_and_the_stated_period),
        cmocka_unit_test(test_disconnect_action_stop_keeps_drives_and_lock),
        cmocka_unit_test(test_disconnect_action_stop_during_a_motion),
        cmocka_unit_test(test_disconnect_action_stop_deactivate),
        cmocka_unit_test(test_connect_narrows_the_disconnect_action),
        cmocka_unit_test(test_send_command_status_at_its_longest_is_whole),
        cmocka_unit_test(test_a_request_ends_the_connect_grace),
        cmocka_unit_test_setup(test_a_refusal_without_a_session_names_why_it_ended, setup_locked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
