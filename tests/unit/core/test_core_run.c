/* The controller core, black box (core_fixture.h). The run (docs/state-
 * machine.md "Motion lifecycle"): loop events, halts, deactivate while moving,
 * a path's auxiliary commands and cycles, the final notices, when the tick
 * acts, and the drives' homing that motion waits for (sendCommand home). */
#include "core_fixture.h"

#include "landscape.h"

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
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_stopping");
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
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_stopped_on_command");
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
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_stopped_on_error");
}

static void test_disconnect_during_motion_releases_after_the_stop(void **state)
{
    (void)state;
    const uint32_t move = start_move();
    const uint32_t epoch = g_core.sessions[0].epoch;
    const uint32_t numbered = g_core.sessions[0].notice_seq;
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
    /* sent after its session ended, numbered on in that session's count */
    assert_int_equal(f->notice_seq, numbered + 1u);
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_stopped_on_command");
    /* the same address connects again: a new epoch, so the old notice cannot match */
    connect_host(HOST_A);
    assert_int_not_equal(g_core.sessions[ls_core_session_of(&g_core, HOST_A)].epoch, epoch);
}

/* How the last motion ended was its owner's news: the next lock starts at
 * rest, and the broadcast's code says the same name (docs/state-machine.md). */
static void test_a_new_lock_after_a_stopped_motion_starts_at_rest(void **state)
{
    (void)state;
    (void)start_move();
    req(ls_Request_disconnect_tag);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    loop_stopped();
    ls_run_tick(&g_core, g_now + 1000);
    assert_int_equal(g_core.motion_state, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_COMMAND_CHOICE);
    req(ls_Request_lock_tag);
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.motion_state, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_at_rest");
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
    assert_string_equal(ls_core_motion_state_name(&g_core), "robot_stopped_on_error");
    assert_string_equal(g_core.fault, "");
    /* the path is free again, nothing waits */
    ls_core_motion_tick(&g_core, g_now);
    req(ls_Request_path_clear_path_tag);
    snprintf(g_rq.cmd.path_clear_path.path_name, sizeof g_rq.cmd.path_clear_path.path_name, "io");
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
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

/* docs/protocol.md "Drives": sendCommand home runs the drives' homing and
 * answers when it ends; until the joints that must be homed are, nothing moves. */
static void test_home_answers_when_the_homing_ends_and_motion_waits_for_it(void **state)
{
    (void)state;
    setup_core(ls_State_RESTING);
    atomic_store(&g_ctl.plan_slot_busy, false);
    memcpy(g_snap.q_cmd_rad, k_home, sizeof k_home);
    g_snap.enabled = true;
    g_snap.home_timeout_ms = 30000;
    g_snap.home_required = 1u << 1;
    g_snap.unhomed = 1u << 1;
    /* a move first: refused naming the joint */
    ls_MoveAbsoluteReq *m = &req(ls_Request_move_absolute_tag)->cmd.move_absolute;
    snprintf(m->point_name, sizeof m->point_name, "p1");
    m->values_count = 6;
    m->has_frame = true;
    m->frame = ls_ReferenceFrame_JOINT_FRAME;
    memcpy(m->values, k_home, sizeof k_home);
    m->values[0] += 0.5;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_WRONG_STATE_ERR);
    assert_string_equal(r->ret_msg, "moveAbsolute refused, nothing moved: joint 2 must be homed first (an incremental "
                                    "encoder): send sendCommand home");
    assert_int_equal(g_nposted, 0);
    /* the homing: posted for the joints that must be homed, answered later */
    assert_null(send_command_from(HOST_A, "home"));
    const uint32_t seq = g_seq;
    assert_int_equal(g_nposted, 1);
    assert_int_equal(g_posted[0].kind, LS_CTL_HOME);
    assert_int_equal(g_posted[0].home.joints, 1u << 1);
    assert_int_equal(g_posted[0].ref_seq, seq);
    /* meanwhile another session's request to home is refused as busy, a move too */
    g_snap.homing = true;
    r = send_command_from(HOST_B, "home 3");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR);
    loop_posts_event(LS_CEV_HOMED, seq, "");
    g_snap.homing = false;
    g_snap.unhomed = 0u;
    ls_core_tick(&g_core, g_now);
    r = response_to(seq);
    assert_non_null(r);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(r->ret_msg, "homed: joint 2");
    assert_non_null(strstr(events_text(), "sendCommand home: joint 2 homed"));
    /* a failure names the joint and what its drive said */
    assert_null(send_command_from(HOST_A, "home 2,3"));
    const uint32_t seq2 = g_seq;
    assert_int_equal(g_posted[1].home.joints, (1u << 1) | (1u << 2));
    loop_posts_event(LS_CEV_HOME_FAILED, seq2, "joint 3 (node 0x23): homing failed: the drive reports a homing error");
    ls_core_tick(&g_core, g_now);
    r = response_to(seq2);
    assert_non_null(r);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_ERR);
    assert_string_equal(
        r->ret_msg, "sendCommand home failed: joint 3 (node 0x23): homing failed: the drive reports a homing error");
}

static void test_home_is_refused_naming_what_is_wrong(void **state)
{
    (void)state;
    setup_core(ls_State_LOCKED);
    g_snap.home_timeout_ms = 30000;
    const ls_Response *r = send_command_from(HOST_A, "home");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_WRONG_STATE_ERR);
    assert_string_equal(r->ret_msg, "sendCommand home is valid in RESTING (drives on, at rest), the device is LOCKED: "
                                    "activate first");
    g_core.state = ls_State_RESTING;
    r = send_command_from(HOST_A, "home 0");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(
        r->ret_msg, "sendCommand home: '0' is no joint: name joints 1..6, or none for every joint that must be homed");
    r = send_command_from(HOST_A, "home");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR); /* none must be homed, none named */
    assert_string_equal(r->ret_msg, "sendCommand home: no joint must be homed here ([joint.N] home_required): name "
                                    "the joints to home, e.g. 'home 2'");
    g_snap.home_timeout_ms = 0; /* an arm without homing */
    r = send_command_from(HOST_A, "home 1");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    r = send_command_from(HOST_A, "drives");
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR); /* no drives to read */
    assert_int_equal(g_nposted, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_query_sees_the_loop_events_posted_before_it),
        cmocka_unit_test(test_deactivate_while_moving_answers_at_rest),
        cmocka_unit_test(test_emergency_fails_the_motion_once_stopped),
        cmocka_unit_test(test_disconnect_during_motion_releases_after_the_stop),
        cmocka_unit_test(test_aux_dio_waits_for_the_write_then_goes_on),
        cmocka_unit_test(test_a_new_lock_after_a_stopped_motion_starts_at_rest),
        cmocka_unit_test(test_aux_dio_refused_at_run_time_fails_the_path_and_leaves_it_usable),
        cmocka_unit_test(test_path_move_cycles_absent_is_one_zero_is_a_dry_run_that_says_so),
        cmocka_unit_test(test_final_notice_writes_a_joint_at_rest_as_0),
        cmocka_unit_test(test_next_deadline_is_when_the_tick_acts),
        cmocka_unit_test_setup(test_next_deadline_of_watches_and_a_halt, setup_locked),
        cmocka_unit_test(test_home_answers_when_the_homing_ends_and_motion_waits_for_it),
        cmocka_unit_test(test_home_is_refused_naming_what_is_wrong),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
