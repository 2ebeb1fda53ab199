/* ls_auth, black box: the framing of docs/protocol.md "The signature" against
 * vectors computed with Python's hmac and hashlib (an implementation of its
 * own), and what verification refuses. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <string.h>

#include "alloc_counter.h"
#include "ls_auth.h"

#define HOST 0xF1u
#define DEVICE 0x10u

static ls_auth_t g_auth;

static void from_hex(const char *hex, uint8_t *out, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        unsigned v = 0;
        for (int k = 0; k < 2; k++) {
            const char c = hex[2 * i + (size_t)k];
            v = v * 16u + (unsigned)(c <= '9' ? c - '0' : c - 'a' + 10);
        }
        out[i] = (uint8_t)v;
    }
}

/* K = 00 01 .. 1f under the name "cell", a challenge from HOST with
 * host_nonce 10 .. 1f answered with device_nonce 20 .. 2f at t = 1 s. */
static const ls_auth_challenge_t *challenged(void)
{
    uint8_t key[LS_AUTH_KEY_BYTES], nh[LS_AUTH_NONCE_BYTES], nd[LS_AUTH_NONCE_BYTES];
    for (size_t i = 0; i < sizeof key; i++) {
        key[i] = (uint8_t)i;
    }
    for (size_t i = 0; i < sizeof nh; i++) {
        nh[i] = (uint8_t)(0x10u + i);
        nd[i] = (uint8_t)(0x20u + i);
    }
    ls_auth_init(&g_auth, ls_AuthPolicy_AUTH_SIGNED, false);
    assert_int_equal(ls_auth_add_key(&g_auth, "cell", key), LS_OK);
    assert_int_equal(ls_auth_challenge_put(&g_auth, HOST, 0, nh, nd, 1000000u), LS_OK);
    const ls_auth_challenge_t *c = ls_auth_challenge_find(&g_auth, HOST, nh, sizeof nh, 1000000u);
    assert_non_null(c);
    return c;
}

static const uint8_t BODY[] = { 0x0a, 0x04, 0x08, 0x01, 0x92, 0x01 };

static void test_macs_match_the_documented_framing(void **state)
{
    (void)state;
    ls_auth_session_key_t ks;
    alloc_counter_reset();
    alloc_counter_arm();
    ls_auth_session_key(&g_auth, challenged(), HOST, DEVICE, &ks);
    uint8_t up[LS_AUTH_MAC_BYTES], down[LS_AUTH_MAC_BYTES], want[LS_AUTH_MAC_BYTES];
    ls_auth_mac(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, BODY, sizeof BODY, up);
    ls_auth_mac(&ks, LS_AUTH_DOWN, DEVICE, HOST, 7u, BODY, sizeof BODY, down);
    const uint32_t hb = ls_auth_heartbeat_mac(&ks, HOST, 7u, 300u, 200u);
    alloc_counter_disarm();
    assert_int_equal(alloc_counter_count(), 0);
    /* python3: ks = hmac(K, b"LS1K" + nh + nd + bytes([0xF1, 0x10])), then
     * hmac(ks, b"LS1U" + bytes([0xF1, 0x10]) + (7).to_bytes(4, "little") + body)[:8] */
    from_hex("a7f4824cd200fcbd", want, sizeof want);
    assert_memory_equal(up, want, sizeof want);
    from_hex("e1c846fd33ad37af", want, sizeof want);
    assert_memory_equal(down, want, sizeof want);
    /* hmac(ks, b"LS1H" + bytes([0xF1]) + le32(7) + le32(300) + le16(200))[:3], little-endian */
    assert_int_equal(hb, 0x2d4cb6u);
}

static void test_a_signed_message_verifies_and_no_altered_one_does(void **state)
{
    (void)state;
    ls_auth_session_key_t ks;
    ls_auth_session_key(&g_auth, challenged(), HOST, DEVICE, &ks);
    uint8_t msg[sizeof BODY + LS_AUTH_TRAILER_BYTES];
    memcpy(msg, BODY, sizeof BODY);
    const int n = ls_auth_sign(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, msg, sizeof BODY, sizeof msg);
    assert_int_equal(n, (int)sizeof msg);
    assert_int_equal(ls_auth_body_len(msg, sizeof msg), (int)sizeof BODY);
    assert_true(ls_auth_verify(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, msg, sizeof msg));
    /* every byte, body and MAC field alike */
    for (size_t i = 0; i < sizeof msg; i++) {
        msg[i] ^= 0x01u;
        assert_false(ls_auth_verify(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, msg, sizeof msg));
        msg[i] ^= 0x01u;
    }
    /* another direction, epoch, sender or target: another message */
    assert_false(ls_auth_verify(&ks, LS_AUTH_DOWN, HOST, DEVICE, 7u, msg, sizeof msg));
    assert_false(ls_auth_verify(&ks, LS_AUTH_UP, HOST, DEVICE, 8u, msg, sizeof msg));
    assert_false(ls_auth_verify(&ks, LS_AUTH_UP, 0xF2u, DEVICE, 7u, msg, sizeof msg));
    assert_false(ls_auth_verify(&ks, LS_AUTH_UP, HOST, 0x11u, 7u, msg, sizeof msg));
    /* cut short, or without its MAC field */
    assert_false(ls_auth_verify(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, msg, sizeof msg - 1u));
    assert_false(ls_auth_verify(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, msg, sizeof BODY));
    assert_int_equal(ls_auth_body_len(msg, sizeof BODY), LS_ENOENT);
    assert_false(ls_auth_verify(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, msg, 3u));
    /* another key: another MAC */
    ls_auth_session_key_t other;
    const ls_auth_challenge_t *c = challenged();
    ls_auth_challenge_t swapped = *c;
    swapped.device_nonce[0] ^= 1u;
    ls_auth_session_key(&g_auth, &swapped, HOST, DEVICE, &other);
    assert_false(ls_auth_verify(&other, LS_AUTH_UP, HOST, DEVICE, 7u, msg, sizeof msg));
    /* no room for the MAC field: refused, the buffer untouched */
    uint8_t small[sizeof BODY + LS_AUTH_TRAILER_BYTES - 1u];
    memcpy(small, BODY, sizeof BODY);
    assert_int_equal(ls_auth_sign(&ks, LS_AUTH_UP, HOST, DEVICE, 7u, small, sizeof BODY, sizeof small), LS_ENOSPC);
    assert_memory_equal(small, BODY, sizeof BODY);
}

static void test_keys_are_added_once_under_valid_names(void **state)
{
    (void)state;
    const uint8_t key[LS_AUTH_KEY_BYTES] = { 1 };
    ls_auth_init(&g_auth, ls_AuthPolicy_AUTH_UNSIGNED, false);
    assert_int_equal(ls_auth_add_key(&g_auth, "a", key), LS_OK);
    assert_int_equal(ls_auth_add_key(&g_auth, "a", key), LS_ESTATE);
    static const char *const bad[] = {
        "", "two words", "a=b", "#c", "x;y", "\x7f", "0123456789012345678901234567890123"
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(ls_auth_add_key(&g_auth, bad[i], key), LS_EINVAL);
    }
    assert_int_equal(ls_auth_add_key(&g_auth, "0123456789012345678901234567890", key), LS_OK); /* 31 bytes */
    char id[8];
    for (int i = 2; i < LS_AUTH_MAX_KEYS; i++) {
        id[0] = 'k';
        id[1] = (char)('0' + i);
        id[2] = '\0';
        assert_int_equal(ls_auth_add_key(&g_auth, id, key), LS_OK);
    }
    assert_int_equal(ls_auth_add_key(&g_auth, "late", key), LS_ENOSPC);
    assert_int_equal(ls_auth_key_index(&g_auth, "a"), 0);
    assert_int_equal(ls_auth_key_index(&g_auth, "late"), LS_ENOENT);
    ls_auth_wipe(&g_auth, sizeof g_auth);
    assert_int_equal(g_auth.n_keys, 0);
    assert_int_equal(ls_auth_key_index(&g_auth, "a"), LS_ENOENT);
}

static void test_a_challenge_serves_its_address_and_nonce_within_its_time(void **state)
{
    (void)state;
    const ls_auth_challenge_t *c = challenged();
    uint8_t nh[LS_AUTH_NONCE_BYTES];
    memcpy(nh, c->host_nonce, sizeof nh);
    const uint64_t t0 = 1000000u;
    assert_non_null(ls_auth_challenge_find(&g_auth, HOST, nh, sizeof nh, t0 + LS_AUTH_CHALLENGE_TTL_US));
    assert_null(ls_auth_challenge_find(&g_auth, HOST, nh, sizeof nh, t0 + LS_AUTH_CHALLENGE_TTL_US + 1u));
    assert_null(ls_auth_challenge_find(&g_auth, 0xF2u, nh, sizeof nh, t0));
    assert_null(ls_auth_challenge_find(&g_auth, HOST, nh, sizeof nh - 1u, t0));
    nh[3] ^= 1u;
    assert_null(ls_auth_challenge_find(&g_auth, HOST, nh, sizeof nh, t0));
    nh[3] ^= 1u;
    /* a new challenge of the same address replaces the old one */
    uint8_t nh2[LS_AUTH_NONCE_BYTES] = { 9 }, nd2[LS_AUTH_NONCE_BYTES] = { 8 };
    assert_int_equal(ls_auth_challenge_put(&g_auth, HOST, 0, nh2, nd2, t0 + 1u), LS_OK);
    assert_null(ls_auth_challenge_find(&g_auth, HOST, nh, sizeof nh, t0 + 1u));
    assert_non_null(ls_auth_challenge_find(&g_auth, HOST, nh2, sizeof nh2, t0 + 1u));
    /* taken: a nonce serves one connect */
    ls_auth_challenge_drop(&g_auth, HOST);
    assert_null(ls_auth_challenge_find(&g_auth, HOST, nh2, sizeof nh2, t0 + 1u));
    /* a full table: the oldest challenge makes room, counted */
    for (unsigned a = 0; a < LS_AUTH_MAX_CHALLENGES; a++) {
        nh2[0] = (uint8_t)a;
        assert_int_equal(ls_auth_challenge_put(&g_auth, (uint8_t)(0x30u + a), 0, nh2, nd2, t0 + 10u + a), LS_OK);
    }
    assert_int_equal(g_auth.challenges_replaced, 0);
    nh2[0] = 0xEE;
    assert_int_equal(ls_auth_challenge_put(&g_auth, 0x60u, 0, nh2, nd2, t0 + 100u), LS_OK);
    assert_int_equal(g_auth.challenges_replaced, 1);
    nh2[0] = 0;
    assert_null(ls_auth_challenge_find(&g_auth, 0x30u, nh2, sizeof nh2, t0 + 100u));
    nh2[0] = 1;
    assert_non_null(ls_auth_challenge_find(&g_auth, 0x31u, nh2, sizeof nh2, t0 + 100u));
    assert_int_equal(ls_auth_challenge_put(&g_auth, HOST, 5, nh2, nd2, t0), LS_EINVAL); /* no key 5 */
}

static void test_heartbeat_counters_bridge_gaps_and_refuse_replays(void **state)
{
    (void)state;
    assert_int_equal(ls_auth_heartbeat_counter(0u, 1u), 1u); /* a session's first heartbeat */
    assert_int_equal(ls_auth_heartbeat_counter(1u, 2u), 2u);
    assert_int_equal(ls_auth_heartbeat_counter(250u, 4u), 260u); /* the 8 bits wrapped */
    assert_int_equal(ls_auth_heartbeat_counter(260u, 3u), 515u); /* 255 lost */
    assert_int_equal(ls_auth_heartbeat_counter(260u, 4u), 516u); /* the same 8 bits: never the same counter */
    assert_int_equal(ls_auth_heartbeat_counter(0xFFFFFFF0u, 0xF1u), 0xFFFFFFF1u);
    /* a recorded frame (counter 2) sent again later stands for 258: its MAC,
     * made for 2, does not verify there */
    ls_auth_session_key_t ks;
    ls_auth_session_key(&g_auth, challenged(), HOST, DEVICE, &ks);
    const uint32_t mac2 = ls_auth_heartbeat_mac(&ks, HOST, 3u, 2u, 200u);
    const uint32_t full = ls_auth_heartbeat_counter(10u, 2u);
    assert_int_equal(full, 258u);
    assert_int_not_equal(ls_auth_heartbeat_mac(&ks, HOST, 3u, full, 200u), mac2);
    assert_true(mac2 <= LS_AUTH_HB_MAC_MASK);
    /* the period and the epoch count too */
    assert_int_not_equal(ls_auth_heartbeat_mac(&ks, HOST, 3u, 2u, 100u), mac2);
    assert_int_not_equal(ls_auth_heartbeat_mac(&ks, HOST, 4u, 2u, 200u), mac2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test(test_macs_match_the_documented_framing),
        cmocka_unit_test(test_a_signed_message_verifies_and_no_altered_one_does),
        cmocka_unit_test(test_keys_are_added_once_under_valid_names),
        cmocka_unit_test(test_a_challenge_serves_its_address_and_nonce_within_its_time),
        cmocka_unit_test(test_heartbeat_counters_bridge_gaps_and_refuse_replays),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
