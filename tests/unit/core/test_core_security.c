/* Signed supervisors (docs/protocol.md "Security"): the challenge and the
 * signed connect, what a signed session refuses (forged, altered, replayed
 * or stale messages from its own address: dropped unanswered, the owner's
 * state and seq untouched), signed heartbeats, the functional frames that
 * cannot carry a MAC, the signed policy and its unsigned queries, and the
 * link a session is bound to. The clients here sign with ls_auth, as a
 * supervisor would; tests/unit/auth checks ls_auth against Python's hmac. */
#include "core_fixture.h"

#define OWNER HOST_A
#define ROGUE HOST_B
#define NODE 0x10u

static ls_auth_t g_dev_auth; /* the device's keys */
static const uint8_t KEY[LS_AUTH_KEY_BYTES] = { 0x4b, 0x45, 0x59, 1, 2, 3, 4, 5, 6, 7, 8, 9 };
static const uint8_t WRONG_KEY[LS_AUTH_KEY_BYTES] = { 0x4b, 0x45, 0x59, 1, 2, 3, 4, 5, 6, 7, 8, 9, 1 };

/* One supervisor as the tests drive it. */
typedef struct {
    uint8_t addr;
    ls_auth_session_key_t ks;
    uint32_t epoch;
    bool challenge_verified; /* the challenge's answer carried the MAC of our session key */
    uint32_t hb;             /* its heartbeats' full counter */
} client_t;

static void device_with_key(ls_AuthPolicy policy, bool unsigned_queries)
{
    ls_auth_init(&g_dev_auth, policy, unsigned_queries);
    assert_int_equal(ls_auth_add_key(&g_dev_auth, "cell", KEY), LS_OK);
    setup_bare_core(&g_dev_auth);
    g_seq = 0;
}

/* The index in g_rx of the response to `seq` for `addr` since `from`, or -1. */
static int response_at(size_t from, uint8_t addr, uint32_t seq)
{
    for (size_t i = from; i < g_nrx; i++) {
        if (g_rx[i].which_msg == ls_Downlink_response_tag && g_rx[i].msg.response.seq == seq && g_rx_addr[i] == addr) {
            return (int)i;
        }
    }
    return -1;
}

/* g_up from `addr` as is, or signed with k in `epoch` (k NULL: unsigned). */
static void send_as(uint8_t addr, const ls_auth_session_key_t *k, uint32_t epoch)
{
    pb_ostream_t os = pb_ostream_from_buffer(g_buf, sizeof g_buf);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    size_t len = os.bytes_written;
    if (k != NULL) {
        const int n = ls_auth_sign(k, LS_AUTH_UP, addr, NODE, epoch, g_buf, len, sizeof g_buf);
        assert_true(n > 0);
        len = (size_t)n;
    }
    ls_core_on_uplink(&g_core, addr, 0, g_buf, len, g_now);
}

/* g_rq with a new seq from client c, signed in its session; the index of
 * its answer (whose MAC must verify) or -1 when none came. */
static int signed_req(client_t *c)
{
    g_rq.seq = ++g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    const size_t before = g_nrx;
    send_as(c->addr, &c->ks, c->epoch);
    const int i = response_at(before, c->addr, g_seq);
    if (i >= 0) {
        assert_true(ls_auth_verify(&c->ks, LS_AUTH_DOWN, NODE, c->addr, c->epoch, g_rx_raw[i], g_rx_len[i]));
    }
    return i;
}

static void fill_connect(uint8_t addr, const char *key_id, const uint8_t *host_nonce)
{
    ls_ConnectReq *cr = &req(ls_Request_connect_tag)->cmd.connect;
    cr->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    cr->has_protocol_version = true;
    cr->schema_hash = LS_SCHEMA_HASH;
    cr->has_schema_hash = true;
    cr->client_nonce = nonce_of(addr);
    cr->has_client_nonce = true;
    snprintf(cr->client_name, sizeof cr->client_name, "signed-%02X", addr);
    if (host_nonce != NULL) {
        snprintf(cr->key_id, sizeof cr->key_id, "%s", key_id);
        memcpy(cr->host_nonce.bytes, host_nonce, LS_AUTH_NONCE_BYTES);
        cr->host_nonce.size = (pb_size_t)LS_AUTH_NONCE_BYTES;
    }
}

/* challenge (unsigned) then connect signed with `key` named `key_id`: the
 * connect's ret_code, or the challenge's when it was refused. */
static int32_t signed_connect(client_t *c, uint8_t addr, const char *key_id, const uint8_t *key)
{
    static uint8_t round;
    memset(c, 0, sizeof *c);
    c->addr = addr;
    uint8_t nh[LS_AUTH_NONCE_BYTES];
    for (size_t i = 0; i < sizeof nh; i++) {
        nh[i] = (uint8_t)(addr + i + 17u * round);
    }
    round++;
    ls_ChallengeReq *ch = &req(ls_Request_challenge_tag)->cmd.challenge;
    snprintf(ch->key_id, sizeof ch->key_id, "%s", key_id);
    memcpy(ch->host_nonce.bytes, nh, sizeof nh);
    ch->host_nonce.size = (pb_size_t)sizeof nh;
    const ls_Response *r = must(addr);
    if (r->ret_code < 0) {
        return r->ret_code;
    }
    assert_int_equal(r->session_epoch, 0);
    assert_int_equal(r->result.challenge.device_nonce.size, LS_AUTH_NONCE_BYTES);
    assert_int_equal(r->result.challenge.auth_policy, ls_core_policy(&g_core));
    /* the client's side of the key: its own table with the same key */
    static ls_auth_t client;
    ls_auth_init(&client, ls_AuthPolicy_AUTH_SIGNED, false);
    assert_int_equal(ls_auth_add_key(&client, key_id, key), LS_OK);
    assert_int_equal(ls_auth_challenge_put(&client, addr, 0, nh, r->result.challenge.device_nonce.bytes, 0u), LS_OK);
    ls_auth_session_key(&client, ls_auth_challenge_find(&client, addr, nh, sizeof nh, 0u), addr, NODE, &c->ks);
    const int ai = response_at(g_nrx - 1u, addr, g_seq);
    assert_true(ai >= 0);
    c->challenge_verified = ls_auth_verify(&c->ks, LS_AUTH_DOWN, NODE, addr, 0u, g_rx_raw[ai], g_rx_len[ai]);
    fill_connect(addr, key_id, nh);
    g_rq.seq = ++g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    const size_t before = g_nrx;
    send_as(addr, &c->ks, 0u);
    const int i = response_at(before, addr, g_seq);
    assert_true(i >= 0);
    const ls_Response *res = &g_rx[i].msg.response;
    if (res->ret_code == ls_RetCode_CMD_EXEC_OK) {
        c->epoch = res->result.connect.session_epoch;
        assert_true(ls_auth_verify(&c->ks, LS_AUTH_DOWN, NODE, addr, c->epoch, g_rx_raw[i], g_rx_len[i]));
        assert_true(res->result.connect.session_signed);
        assert_int_equal(res->result.connect.auth_policy, ls_core_policy(&g_core));
    }
    return res->ret_code;
}

static int32_t code_at(int i)
{
    assert_true(i >= 0);
    return g_rx[i].msg.response.ret_code;
}

static void test_a_signed_connect_opens_a_signed_session_whose_answers_verify(void **state)
{
    (void)state;
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    client_t c;
    assert_int_equal(signed_connect(&c, OWNER, "cell", KEY), ls_RetCode_CMD_EXEC_OK);
    assert_true(c.challenge_verified);
    const int s = ls_core_session_of(&g_core, OWNER);
    assert_true(s >= 0 && g_core.sessions[s].signed_session);
    req(ls_Request_lock_tag);
    assert_int_equal(code_at(signed_req(&c)), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.state, ls_State_LOCKED);
    /* describe says so */
    req(ls_Request_describe_tag);
    const int d = signed_req(&c);
    assert_int_equal(g_rx[d].msg.response.result.describe.auth_policy, ls_AuthPolicy_AUTH_SIGNED);
    /* the challenge's nonce served one connect: a second connect with it is refused */
    assert_int_equal(g_dev_auth.challenges[0].used, false);
    /* the answer to the disconnect that ends the session still carries its MAC
     * (signed_req verifies it), while another session's downlinks keep theirs */
    req(ls_Request_release_tag);
    assert_int_equal(code_at(signed_req(&c)), ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_disconnect_tag);
    const int e = signed_req(&c);
    assert_int_equal(code_at(e), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_rx[e].msg.response.session_epoch, c.epoch);
    assert_int_equal(ls_core_session_of(&g_core, OWNER), -1);
    assert_false(g_core.tx_sign.set);
}

static void test_in_signed_mode_an_unsigned_connect_gets_no_session_slot(void **state)
{
    (void)state;
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    for (uint8_t a = 0x30; a < 0x30 + LS_MAX_SUPERVISORS + 2; a++) {
        fill_connect(a, NULL, NULL);
        const ls_Response *r = must(a);
        assert_int_equal(r->ret_code, ls_RetCode_CMD_AUTH_ERR);
        assert_non_null(strstr(r->ret_msg, "signed supervisors only"));
        assert_int_equal(r->which_result, 0);
    }
    assert_int_equal(ls_core_session_of(&g_core, 0x30), LS_NO_SESSION);
    assert_int_equal(g_core.auth_connects_refused, LS_MAX_SUPERVISORS + 2);
    /* every slot is still free for a key holder */
    client_t c;
    assert_int_equal(signed_connect(&c, OWNER, "cell", KEY), ls_RetCode_CMD_EXEC_OK);
    /* an unsigned request is not a session's */
    req(ls_Request_lock_tag);
    assert_int_equal(must(0x30)->ret_code, ls_RetCode_CMD_NOT_CONNECTED_ERR);
}

static void test_a_wrong_or_unknown_key_is_refused_naming_it(void **state)
{
    (void)state;
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    client_t c;
    /* a name the device does not hold: the challenge says so */
    assert_int_equal(signed_connect(&c, OWNER, "laptop", KEY), ls_RetCode_CMD_AUTH_ERR);
    assert_non_null(strstr(g_rx[g_nrx - 1u].msg.response.ret_msg, "holds no key \"laptop\""));
    /* the right name, other bytes: the challenge's answer does not verify at
     * the host, and the device refuses the connect */
    assert_int_equal(signed_connect(&c, OWNER, "cell", WRONG_KEY), ls_RetCode_CMD_AUTH_ERR);
    assert_false(c.challenge_verified);
    assert_non_null(strstr(g_rx[g_nrx - 1u].msg.response.ret_msg, "MAC does not verify"));
    assert_int_equal(ls_core_session_of(&g_core, OWNER), LS_NO_SESSION);
    /* a connect that names no fresh challenge */
    uint8_t nh[LS_AUTH_NONCE_BYTES] = { 0xAA };
    fill_connect(OWNER, "cell", nh);
    g_rq.seq = ++g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    send_as(OWNER, &c.ks, 0u);
    assert_int_equal(g_rx[g_nrx - 1u].msg.response.ret_code, ls_RetCode_CMD_AUTH_ERR);
    assert_non_null(strstr(g_rx[g_nrx - 1u].msg.response.ret_msg, "no challenge"));
    /* a challenge without its 16 random bytes */
    req(ls_Request_challenge_tag);
    snprintf(g_rq.cmd.challenge.key_id, sizeof g_rq.cmd.challenge.key_id, "cell");
    g_rq.cmd.challenge.host_nonce.size = 3;
    assert_int_equal(must(OWNER)->ret_code, ls_RetCode_CMD_PARAM_ERR);
}

/* The owner's signed session, locked, active and moving; ROGUE forges from
 * the owner's address. */
static void owner_moving(client_t *c)
{
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    assert_int_equal(signed_connect(c, OWNER, "cell", KEY), ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_lock_tag);
    assert_int_equal(code_at(signed_req(c)), ls_RetCode_CMD_EXEC_OK);
    g_core.state = ls_State_MOVING; /* as after a move the loop runs */
}

static void test_forged_requests_from_the_owners_address_change_nothing_and_keep_its_seq(void **state)
{
    (void)state;
    client_t c;
    owner_moving(&c);
    const uint32_t epoch = c.epoch;
    const uint32_t next = g_seq + 1u;
    const size_t posted = g_nposted;
    const size_t start = g_nrx;
    /* release, disconnect, deactivate, a move, abort: unsigned, signed with
     * a guessed key, or with the right MAC of another epoch; each with the
     * owner's next seq (the seq poisoning) */
    const pb_size_t forged[] = { ls_Request_release_tag, ls_Request_disconnect_tag, ls_Request_deactivate_tag,
                                 ls_Request_abort_motion_tag, ls_Request_stop_motion_tag };
    ls_auth_session_key_t guess = c.ks;
    guess.st.octx.state[0] ^= 1u;
    for (size_t k = 0; k < sizeof forged / sizeof forged[0]; k++) {
        for (int how = 0; how < 3; how++) {
            req(forged[k])->seq = next;
            memset(&g_up, 0, sizeof g_up);
            g_up.which_msg = ls_Uplink_request_tag;
            g_up.msg.request = g_rq;
            const size_t before = g_nrx;
            send_as(OWNER, how == 0 ? NULL : how == 1 ? &guess : &c.ks, how == 2 ? epoch + 1u : epoch);
            assert_int_equal(g_nrx, before); /* not answered */
        }
    }
    /* an RSVP reply and bytes that do not decode: dropped too */
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_rsvp_reply_tag;
    g_up.msg.rsvp_reply.rsvp_id = 1;
    send_as(OWNER, NULL, 0u);
    const uint8_t junk[] = { 0xFF, 0xFF, 0xFF };
    ls_core_on_uplink(&g_core, OWNER, 0, junk, sizeof junk, g_now);
    assert_int_equal(g_nrx, start);
    assert_int_equal(g_core.state, ls_State_MOVING);
    assert_int_equal(g_core.owner, ls_core_session_of(&g_core, OWNER));
    assert_int_equal(g_nposted, posted);
    assert_int_equal(g_core.sessions[g_core.owner].epoch, epoch);
    assert_int_equal(g_core.auth_refused, 5u * 3u + 2u); /* every one counted */
    /* the owner's own request with that seq runs */
    req(ls_Request_get_motion_control_state_tag);
    assert_int_equal(next, g_seq + 1u);
    assert_int_equal(code_at(signed_req(&c)), ls_RetCode_CMD_EXEC_OK);
}

static void test_replayed_requests_and_connects_are_dropped(void **state)
{
    (void)state;
    client_t c;
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    assert_int_equal(signed_connect(&c, OWNER, "cell", KEY), ls_RetCode_CMD_EXEC_OK);
    /* the signed connect's bytes as they went out (g_up still holds it) */
    static uint8_t connect[LS_UPLINK_MAX];
    pb_ostream_t os = pb_ostream_from_buffer(connect, sizeof connect);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    const int cn = ls_auth_sign(&c.ks, LS_AUTH_UP, OWNER, NODE, 0u, connect, os.bytes_written, sizeof connect);
    assert_true(cn > 0);
    /* sent again at once (its answer was lost): the cached answer, same epoch */
    size_t before = g_nrx;
    ls_core_on_uplink(&g_core, OWNER, 0, connect, (size_t)cn, g_now);
    assert_int_equal(g_nrx, before + 1u);
    assert_int_equal(g_rx[before].msg.response.result.connect.session_epoch, c.epoch);
    /* a request; its bytes recorded */
    req(ls_Request_lock_tag);
    assert_int_equal(code_at(signed_req(&c)), ls_RetCode_CMD_EXEC_OK);
    uint8_t lock[256];
    pb_ostream_t ls = pb_ostream_from_buffer(lock, sizeof lock);
    assert_true(pb_encode(&ls, ls_Uplink_fields, &g_up));
    const int ln = ls_auth_sign(&c.ks, LS_AUTH_UP, OWNER, NODE, c.epoch, lock, ls.bytes_written, sizeof lock);
    req(ls_Request_release_tag);
    assert_int_equal(code_at(signed_req(&c)), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
    /* the lock replayed after the release: stale, dropped unanswered, not run */
    before = g_nrx;
    ls_core_on_uplink(&g_core, OWNER, 0, lock, (size_t)ln, g_now);
    assert_int_equal(g_nrx, before);
    assert_int_equal(g_core.state, ls_State_UNLOCKED);
    assert_int_equal(g_core.auth_stale, 1);
    /* the connect replayed now: its challenge is used, the session has moved on */
    ls_core_on_uplink(&g_core, OWNER, 0, connect, (size_t)cn, g_now);
    assert_int_equal(g_nrx, before);
    assert_int_equal(g_core.sessions[ls_core_session_of(&g_core, OWNER)].epoch, c.epoch);
    /* from another address, the same bytes are another sender's: no challenge there */
    ls_core_on_uplink(&g_core, ROGUE, 0, connect, (size_t)cn, g_now);
    assert_int_equal(g_rx[g_nrx - 1u].msg.response.ret_code, ls_RetCode_CMD_AUTH_ERR);
    assert_int_equal(ls_core_session_of(&g_core, ROGUE), LS_NO_SESSION);
}

static void beat_signed(client_t *c, uint32_t counter, uint64_t now_us)
{
    ls_core_on_heartbeat(&g_core, c->addr, (uint8_t)counter, 200u,
                         ls_auth_heartbeat_mac(&c->ks, c->addr, c->epoch, counter, 200u), now_us);
}

static void test_signed_heartbeats_keep_the_session_only_when_fresh(void **state)
{
    (void)state;
    client_t c;
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    assert_int_equal(signed_connect(&c, OWNER, "cell", KEY), ls_RetCode_CMD_EXEC_OK);
    ls_session_t *s = &g_core.sessions[ls_core_session_of(&g_core, OWNER)];
    /* the token anyone reads off the bus keeps nothing in a signed session */
    ls_core_on_heartbeat(&g_core, OWNER, 1u, 200u, s->hb_token, g_now + 5000000u);
    assert_int_equal(s->hb_refused, 1);
    beat_signed(&c, 1u, g_now + 5000000u);
    assert_int_equal(s->last_heard_us, g_now + 5000000u);
    /* the same frame again (a replay): refused */
    beat_signed(&c, 1u, g_now + 5100000u);
    assert_int_equal(s->hb_refused, 2);
    assert_int_equal(s->last_heard_us, g_now + 5000000u);
    /* lost heartbeats in between are bridged */
    beat_signed(&c, 40u, g_now + 6000000u);
    assert_int_equal(s->last_heard_us, g_now + 6000000u);
    /* another period than the one signed: refused */
    ls_core_on_heartbeat(&g_core, OWNER, 41u, 100u, ls_auth_heartbeat_mac(&c.ks, OWNER, c.epoch, 41u, 200u),
                         g_now + 6200000u);
    assert_int_equal(s->hb_refused, 3);
}

static void test_where_a_signature_is_needed_a_functional_frame_only_stops(void **state)
{
    (void)state;
    client_t c;
    owner_moving(&c);
    const uint32_t seq = g_seq;
    const size_t before = g_nrx;
    /* disconnect, release, deactivate from the owner's address: dropped */
    const pb_size_t refused[] = { ls_Request_disconnect_tag, ls_Request_release_tag, ls_Request_deactivate_tag };
    uint8_t b[8];
    for (size_t k = 0; k < sizeof refused / sizeof refused[0]; k++) {
        req(refused[k])->seq = 5;
        memset(&g_up, 0, sizeof g_up);
        g_up.which_msg = ls_Uplink_request_tag;
        g_up.msg.request = g_rq;
        pb_ostream_t os = pb_ostream_from_buffer(b, sizeof b);
        assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
        ls_core_on_functional(&g_core, OWNER, 0, b, os.bytes_written, g_now);
    }
    assert_int_equal(g_core.functional_refused, 3);
    assert_int_equal(g_core.state, ls_State_MOVING);
    assert_true(ls_core_session_of(&g_core, OWNER) >= 0);
    /* a stop from anyone (a node without a session): the motion pauses, unanswered */
    req(ls_Request_stop_motion_tag)->seq = 3;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    pb_ostream_t os = pb_ostream_from_buffer(b, sizeof b);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    const size_t posted = g_nposted;
    ls_core_on_functional(&g_core, 0x55, 0, b, os.bytes_written, g_now);
    assert_int_equal(g_nposted, posted + 1u);
    assert_int_equal(g_posted[posted].kind, LS_CTL_STOP);
    assert_true(g_core.run.stop_pending);
    assert_int_equal(g_core.anonymous_stops, 1);
    assert_int_equal(g_nrx, before);
    /* the owner's seq and cache are its own */
    const ls_session_t *s = &g_core.sessions[ls_core_session_of(&g_core, OWNER)];
    assert_int_equal(s->last_seq, seq);
}

static void test_unsigned_queries_are_answered_without_a_session_when_configured(void **state)
{
    (void)state;
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, true);
    req(ls_Request_get_motion_control_state_tag);
    const ls_Response *r = must(0x40);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK); /* in IDLE, with nobody connected */
    assert_int_equal(r->result.get_motion_control_state.state, ls_State_IDLE);
    assert_int_equal(r->session_epoch, 0);
    assert_int_equal(ls_core_session_of(&g_core, 0x40), LS_NO_SESSION);
    req(ls_Request_lock_tag);
    assert_int_equal(must(0x40)->ret_code, ls_RetCode_CMD_NOT_CONNECTED_ERR);
    req(ls_Request_send_command_tag); /* the vendor hook is not a query */
    assert_int_equal(must(0x40)->ret_code, ls_RetCode_CMD_NOT_CONNECTED_ERR);
    /* without the option, a query needs a signed session too */
    device_with_key(ls_AuthPolicy_AUTH_SIGNED, false);
    req(ls_Request_get_motion_control_state_tag);
    assert_int_equal(must(0x40)->ret_code, ls_RetCode_CMD_NOT_CONNECTED_ERR);
}

static void test_notices_and_acks_to_a_signed_session_carry_fresh_macs(void **state)
{
    (void)state;
    client_t c;
    device_with_key(ls_AuthPolicy_AUTH_UNSIGNED, false); /* a signed session on an unsigned device */
    assert_int_equal(signed_connect(&c, OWNER, "cell", KEY), ls_RetCode_CMD_EXEC_OK);
    connect_host(ROGUE); /* an unsigned one beside it */
    const size_t before = g_nrx;
    const char *d[] = { "fault=test" };
    ls_core_notify(&g_core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_fault, 0, false, d, 1);
    ls_core_notify(&g_core, LS_ALL_SESSIONS, ls_NoticeKind_ALARM, ls_EventId_fault, 0, false, d, 1);
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_rsvp_reply_tag;
    g_up.msg.rsvp_reply.rsvp_id = 99;
    send_as(OWNER, &c.ks, c.epoch);
    uint32_t last = 0;
    int signed_seen = 0;
    for (size_t i = before; i < g_nrx; i++) {
        const bool to_owner = g_rx_addr[i] == OWNER;
        assert_int_equal(ls_auth_body_len(g_rx_raw[i], g_rx_len[i]) >= 0, to_owner);
        if (to_owner) {
            assert_true(ls_auth_verify(&c.ks, LS_AUTH_DOWN, NODE, OWNER, c.epoch, g_rx_raw[i], g_rx_len[i]));
            const uint32_t n = g_rx[i].which_msg == ls_Downlink_notice_tag ? g_rx[i].msg.notice.notice_seq
                                                                           : g_rx[i].msg.rsvp_ack.notice_seq;
            assert_true(n > last);
            last = n;
            signed_seen++;
        }
    }
    assert_int_equal(signed_seen, 3); /* two alarms and the ack */
}

static void test_a_session_is_bound_to_the_link_its_connect_came_on(void **state)
{
    (void)state;
    setup_bare_core(NULL);
    fill_connect(OWNER, NULL, NULL);
    g_rq.seq = ++g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    pb_ostream_t os = pb_ostream_from_buffer(g_buf, sizeof g_buf);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    ls_core_on_uplink(&g_core, OWNER, 2, g_buf, os.bytes_written, g_now);
    assert_int_equal(ls_core_session_link(&g_core, OWNER), 2);
    assert_int_equal(ls_core_session_link(&g_core, ROGUE), LS_NO_SESSION);
    /* unsigned sessions are told apart by their link too: sendCommand security shows it */
    req(ls_Request_send_command_tag);
    snprintf(g_rq.cmd.send_command.input, sizeof g_rq.cmd.send_command.input, "security");
    g_rq.seq = ++g_seq;
    memset(&g_up, 0, sizeof g_up);
    g_up.which_msg = ls_Uplink_request_tag;
    g_up.msg.request = g_rq;
    os = pb_ostream_from_buffer(g_buf, sizeof g_buf);
    assert_true(pb_encode(&os, ls_Uplink_fields, &g_up));
    ls_core_on_uplink(&g_core, OWNER, 2, g_buf, os.bytes_written, g_now);
    assert_non_null(strstr(g_rx[g_nrx - 1u].msg.response.result.send_command.result,
                           "session 0x21 link=2 signed=no auth_refused=0\n"));
    assert_non_null(strstr(g_rx[g_nrx - 1u].msg.response.result.send_command.result, "policy=unsigned\nkeys=0\n"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_signed_connect_opens_a_signed_session_whose_answers_verify),
        cmocka_unit_test(test_in_signed_mode_an_unsigned_connect_gets_no_session_slot),
        cmocka_unit_test(test_a_wrong_or_unknown_key_is_refused_naming_it),
        cmocka_unit_test(test_forged_requests_from_the_owners_address_change_nothing_and_keep_its_seq),
        cmocka_unit_test(test_replayed_requests_and_connects_are_dropped),
        cmocka_unit_test(test_signed_heartbeats_keep_the_session_only_when_fresh),
        cmocka_unit_test(test_where_a_signature_is_needed_a_functional_frame_only_stops),
        cmocka_unit_test(test_unsigned_queries_are_answered_without_a_session_when_configured),
        cmocka_unit_test(test_notices_and_acks_to_a_signed_session_carry_fresh_macs),
        cmocka_unit_test(test_a_session_is_bound_to_the_link_its_connect_came_on),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
