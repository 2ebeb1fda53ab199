/* The controller core, black box (core_fixture.h). Digital I/O: setDigitalIO,
 * signalDigitalIO watches, their RSVPs and their end, and RSVPs in general. */
#include "core_fixture.h"

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

/* Accept re-arms the watch: it fires again on the bits' next rising edge, not while they stay set. */
/* Every reply gets an RsvpAck (docs/protocol.md "RSVP"), also one that does
 * not decode (more data items than the firmware holds) or carries text that
 * is not UTF-8: refused naming why, and the RSVP still waits. */
static void test_a_reply_the_device_cannot_take_is_refused_with_an_ack(void **state)
{
    (void)state;
    g_done_calls = 0;
    const char *data[] = { "path=p" };
    const uint32_t epoch_a = g_core.sessions[0].epoch;
    int32_t id = ls_core_rsvp(&g_core, 0, 41, ls_NoticeKind_EVENT_RSVP, "ask", data, 1, 5000, "continue", done_cb,
                              &g_done_calls, g_now);
    assert_true(id > 0 && id < 128);
    const size_t n_items = pb_arraysize(ls_RsvpReply, data) + 1u;
    uint8_t buf[64];
    size_t len = 0;
    buf[len++] = (uint8_t)((ls_Uplink_rsvp_reply_tag << 3) | PB_WT_STRING);
    buf[len++] = (uint8_t)(2u + 2u + 3u * n_items);
    buf[len++] = (uint8_t)((ls_RsvpReply_rsvp_id_tag << 3) | PB_WT_VARINT);
    buf[len++] = (uint8_t)id;
    buf[len++] = (uint8_t)((ls_RsvpReply_ret_code_tag << 3) | PB_WT_VARINT);
    buf[len++] = 0;
    for (size_t k = 0; k < n_items; k++) {
        buf[len++] = (uint8_t)((ls_RsvpReply_data_tag << 3) | PB_WT_STRING);
        buf[len++] = 1;
        buf[len++] = 'd';
    }
    const uint32_t malformed = g_core.rx_malformed;
    size_t before = g_nrx;
    ls_core_on_uplink(&g_core, HOST_A, 0, buf, len, g_now);
    const ls_RsvpAck *a = the_ack(before, HOST_A);
    assert_int_equal(a->rsvp_id, (uint32_t)id);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(a->ref_seq, 41);
    assert_int_equal(a->session_epoch, epoch_a);
    assert_non_null(strstr(a->ret_msg, "the RSVP still waits; the reply did not decode"));
    assert_non_null(strstr(a->ret_msg, "rsvp_reply.data"));
    assert_non_null(strstr(a->ret_msg, "send one within describe's field_limits"));
    assert_int_equal(g_core.rx_malformed, malformed + 1u);
    assert_int_equal(g_done_calls, 0);

    /* text that is not UTF-8: the same */
    buf[1] = (uint8_t)(2u + 2u + 3u);
    buf[8] = 0xFF;
    before = g_nrx;
    ls_core_on_uplink(&g_core, HOST_A, 0, buf, 2u + 4u + 3u, g_now);
    a = the_ack(before, HOST_A);
    assert_int_equal(a->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(a->ret_msg, "not valid UTF-8"));
    assert_int_equal(g_done_calls, 0);

    /* still waiting: a valid reply is taken */
    before = g_nrx;
    send_rsvp_reply(HOST_A, (uint32_t)id, 0);
    assert_int_equal(g_done_calls, 1);
    assert_int_equal(the_ack(before, HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
}

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_set_digital_io_refusals, setup_locked),
        cmocka_unit_test_setup(test_set_digital_io_answers_when_applied, setup_locked),
        cmocka_unit_test_setup(test_signal_event_and_alarm_on_change, setup_locked),
        cmocka_unit_test_setup(test_signal_fires_at_once_when_bits_are_already_set, setup_locked),
        cmocka_unit_test_setup(test_signal_polling_cycle_and_timeout, setup_locked),
        cmocka_unit_test_setup(test_signal_refusals_and_table_full, setup_locked),
        cmocka_unit_test_setup(test_watches_end_with_their_session, setup_locked),
        cmocka_unit_test_setup(test_rsvp_reply_and_timeout, setup_locked),
        cmocka_unit_test_setup(test_a_reply_the_device_cannot_take_is_refused_with_an_ack, setup_locked),
        cmocka_unit_test_setup(test_signal_rsvp_accept_rearms_the_watch, setup_locked),
        cmocka_unit_test_setup(test_signal_rsvp_decline_cancels_the_watch, setup_locked),
        cmocka_unit_test_setup(test_signal_rsvp_unanswered_takes_the_default, setup_locked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
