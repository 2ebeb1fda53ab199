/* The verification path of signed sessions (docs/protocol.md "Security"):
 * a device of policy signed with one key, its owner 0xF1 in a signed session
 * holding the lock, and then whatever the input says an attacker sends:
 * uplinks from the owner's address (as they come, with a MAC field of the
 * input's bytes, or signed with the session key and then one bit flipped),
 * functional frames and heartbeats from that address, uplinks from an
 * address without a session. None of them may change the state, the owner,
 * the owner's session (epoch, seq) or get an answer to the owner's address;
 * none may open a session. The input is a sequence of records
 * [kind][len][len bytes]. ls_auth_body_len and ls_auth_verify also see every
 * record's bytes as they are. */
#include <stdint.h>
#include <string.h>

#include <pb_decode.h>
#include <pb_encode.h>

#include "ls_auth.h"
#include "ls_core.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define NODE 0x10u
#define OWNER 0xF1u
#define STRANGER 0xF2u

static ls_core_t g_core;
static ls_auth_t g_dev; /* the device's keys */
static ls_auth_t g_cli; /* the owner's: the same key */
static const uint8_t KEY[LS_AUTH_KEY_BYTES] = { 'f', 'u', 'z', 'z', 1, 2, 3, 4, 5, 6, 7, 8, 9 };
static uint64_t g_now;
static uint32_t g_to_owner; /* downlinks sent to OWNER */
static ls_Downlink g_last;  /* the last downlink to OWNER, decoded (setup only) */
static bool g_decode_last;
static uint8_t g_nonce_byte;

static int capture(void *ctx, uint8_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    if (addr == OWNER) {
        g_to_owner++;
        if (g_decode_last) {
            memset(&g_last, 0, sizeof g_last);
            pb_istream_t is = pb_istream_from_buffer(buf, len);
            if (!pb_decode(&is, ls_Downlink_fields, &g_last)) {
                __builtin_trap();
            }
        }
    }
    return LS_OK;
}

static int fake_random(void *ctx, uint8_t *buf, size_t len)
{
    (void)ctx;
    for (size_t i = 0; i < len; i++) {
        buf[i] = (uint8_t)(g_nonce_byte + 31u * i);
    }
    g_nonce_byte++;
    return LS_OK;
}

/* Encode `up`, sign it with k in `epoch` when k is not NULL, deliver it from OWNER. */
static size_t encode(const ls_Uplink *up, uint8_t *buf, size_t cap)
{
    pb_ostream_t os = pb_ostream_from_buffer(buf, cap);
    if (!pb_encode(&os, ls_Uplink_fields, up)) {
        __builtin_trap();
    }
    return os.bytes_written;
}

static ls_auth_session_key_t g_ks;
static uint32_t g_epoch;

/* The owner's challenge, signed connect and lock; false when the core did
 * not let it in (a bug: trapped by the caller). */
static bool open_owner(void)
{
    static ls_Uplink up;
    static uint8_t buf[LS_UPLINK_MAX + 16];
    uint8_t host_nonce[LS_AUTH_NONCE_BYTES];
    memset(host_nonce, 0x5A, sizeof host_nonce);

    memset(&up, 0, sizeof up);
    up.which_msg = ls_Uplink_request_tag;
    up.msg.request.seq = 1;
    up.msg.request.which_cmd = ls_Request_challenge_tag;
    strcpy(up.msg.request.cmd.challenge.key_id, "ops");
    memcpy(up.msg.request.cmd.challenge.host_nonce.bytes, host_nonce, sizeof host_nonce);
    up.msg.request.cmd.challenge.host_nonce.size = (pb_size_t)sizeof host_nonce;
    ls_core_on_uplink(&g_core, OWNER, 0, buf, encode(&up, buf, sizeof buf), g_now);
    if (g_last.which_msg != ls_Downlink_response_tag || g_last.msg.response.ret_code < 0) {
        return false;
    }
    const ls_ChallengeRes *cr = &g_last.msg.response.result.challenge;
    if (ls_auth_challenge_put(&g_cli, OWNER, 0, host_nonce, cr->device_nonce.bytes, g_now) != LS_OK) {
        return false;
    }
    const ls_auth_challenge_t *c = ls_auth_challenge_find(&g_cli, OWNER, host_nonce, sizeof host_nonce, g_now);
    if (c == NULL) {
        return false;
    }
    ls_auth_session_key(&g_cli, c, OWNER, NODE, &g_ks);

    memset(&up, 0, sizeof up);
    up.which_msg = ls_Uplink_request_tag;
    up.msg.request.seq = 2;
    up.msg.request.which_cmd = ls_Request_connect_tag;
    ls_ConnectReq *cn = &up.msg.request.cmd.connect;
    cn->has_protocol_version = true;
    cn->protocol_version = ls_Protocol_PROTOCOL_VERSION;
    cn->has_schema_hash = true;
    cn->schema_hash = LS_SCHEMA_HASH;
    cn->has_client_nonce = true;
    cn->client_nonce = 0x1234;
    strcpy(cn->client_name, "owner");
    strcpy(cn->key_id, "ops");
    memcpy(cn->host_nonce.bytes, host_nonce, sizeof host_nonce);
    cn->host_nonce.size = (pb_size_t)sizeof host_nonce;
    size_t len = encode(&up, buf, sizeof buf);
    int n = ls_auth_sign(&g_ks, LS_AUTH_UP, OWNER, NODE, 0u, buf, len, sizeof buf);
    if (n < 0) {
        return false;
    }
    ls_core_on_uplink(&g_core, OWNER, 0, buf, (size_t)n, g_now);
    if (g_last.which_msg != ls_Downlink_response_tag || g_last.msg.response.ret_code < 0 ||
        !g_last.msg.response.result.connect.session_signed) {
        return false;
    }
    g_epoch = g_last.msg.response.result.connect.session_epoch;

    memset(&up, 0, sizeof up);
    up.which_msg = ls_Uplink_request_tag;
    up.msg.request.seq = 3;
    up.msg.request.which_cmd = ls_Request_lock_tag;
    len = encode(&up, buf, sizeof buf);
    n = ls_auth_sign(&g_ks, LS_AUTH_UP, OWNER, NODE, g_epoch, buf, len, sizeof buf);
    if (n < 0) {
        return false;
    }
    ls_core_on_uplink(&g_core, OWNER, 0, buf, (size_t)n, g_now);
    return g_last.which_msg == ls_Downlink_response_tag && g_last.msg.response.ret_code >= 0 &&
           g_core.state == ls_State_LOCKED;
}

typedef struct {
    ls_State state;
    int owner;
    uint32_t epoch, last_seq, to_owner;
} snap_t;

static snap_t snapshot(void)
{
    const ls_session_t *s = &g_core.sessions[g_core.owner];
    return (snap_t){ g_core.state, g_core.owner, s->epoch, s->last_seq, g_to_owner };
}

static void check(const snap_t *before)
{
    const snap_t now = snapshot();
    if (now.state != before->state || now.owner != before->owner || now.epoch != before->epoch ||
        now.last_seq != before->last_seq || now.to_owner != before->to_owner ||
        !g_core.sessions[g_core.owner].connected || !g_core.sessions[g_core.owner].signed_session) {
        __builtin_trap(); /* something unsigned changed the owner's session or got an answer */
    }
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        if (g_core.sessions[i].connected && g_core.sessions[i].addr != OWNER) {
            __builtin_trap(); /* a session without the key, in policy signed */
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ls_auth_init(&g_dev, ls_AuthPolicy_AUTH_SIGNED, false);
    (void)ls_auth_add_key(&g_dev, "ops", KEY);
    ls_auth_init(&g_cli, ls_AuthPolicy_AUTH_SIGNED, false);
    (void)ls_auth_add_key(&g_cli, "ops", KEY);
    const ls_core_config_t cfg = { .device_name = "fuzz",
                                   .firmware_version = "0",
                                   .node_addr = NODE,
                                   .joint_count = 6,
                                   .heartbeat_timeout_ms = 600000,
                                   .auth = &g_dev };
    const ls_core_io_t io = { .send_downlink = capture, .random = fake_random, .ctx = NULL };
    ls_core_init(&g_core, &cfg, &io, NULL);
    g_now = 1000000;
    g_to_owner = 0;
    g_nonce_byte = 0;
    g_decode_last = true;
    if (!open_owner()) {
        __builtin_trap();
    }
    g_decode_last = false;
    static uint8_t buf[LS_UPLINK_MAX + 64];
    const uint8_t *p = data;
    size_t n = size;
    while (n >= 2) {
        const uint8_t kind = p[0];
        size_t len = p[1] < n - 2 ? p[1] : n - 2;
        const uint8_t *rec = p + 2;
        p += 2 + len;
        n -= 2 + len;
        (void)ls_auth_body_len(rec, len);
        if (ls_auth_verify(&g_ks, LS_AUTH_UP, OWNER, NODE, g_epoch, rec, len)) {
            continue; /* the input holds the MAC of its bytes: not a forgery (never in practice) */
        }
        const snap_t before = snapshot();
        memcpy(buf, rec, len);
        switch (kind % 6u) {
        case 0: /* as it comes */ ls_core_on_uplink(&g_core, OWNER, 0, buf, len, g_now); break;
        case 1: { /* with a MAC field of the input's last bytes */
            const size_t body = len > LS_AUTH_MAC_BYTES ? len - LS_AUTH_MAC_BYTES : 0u;
            memcpy(buf, rec, body);
            buf[body] = (uint8_t)(LS_AUTH_MAC_FIELD << 3 | 2u);
            buf[body + 1] = (uint8_t)LS_AUTH_MAC_BYTES;
            memset(buf + body + 2, 0, LS_AUTH_MAC_BYTES);
            memcpy(buf + body + 2, rec + body, len - body);
            if (ls_auth_verify(&g_ks, LS_AUTH_UP, OWNER, NODE, g_epoch, buf, body + LS_AUTH_TRAILER_BYTES)) {
                continue;
            }
            ls_core_on_uplink(&g_core, OWNER, 0, buf, body + LS_AUTH_TRAILER_BYTES, g_now);
            break;
        }
        case 2: { /* signed, then one bit flipped */
            const int m = ls_auth_sign(&g_ks, LS_AUTH_UP, OWNER, NODE, g_epoch, buf, len, sizeof buf);
            if (m <= 0) {
                continue;
            }
            const size_t bit = len > 0 ? (size_t)rec[0] * 8u + (size_t)(kind >> 3) : 0u;
            buf[(bit / 8u) % (size_t)m] ^= (uint8_t)(1u << (bit % 8u));
            ls_core_on_uplink(&g_core, OWNER, 0, buf, (size_t)m, g_now);
            break;
        }
        case 3: /* a functional single frame's payload */
            ls_core_on_functional(&g_core, OWNER, 0, buf, len < 7 ? len : 7, g_now);
            break;
        case 4: { /* a heartbeat with the input's counter, period and MAC */
            uint8_t hb[6] = { 0 };
            memcpy(hb, rec, len < sizeof hb ? len : sizeof hb);
            ls_core_on_heartbeat(&g_core, OWNER, hb[0], (uint16_t)(hb[1] | hb[2] << 8),
                                 (uint32_t)(hb[3] | hb[4] << 8 | hb[5] << 16), g_now);
            break;
        }
        default: /* from an address without a session: a connect there opens none */
            ls_core_on_uplink(&g_core, STRANGER, 0, buf, len, g_now);
            break;
        }
        g_now += 1000u * (kind >> 4);
        check(&before);
    }
    ls_auth_wipe(&g_dev, sizeof g_dev);
    return 0;
}
