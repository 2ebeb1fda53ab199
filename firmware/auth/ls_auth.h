/* Signed supervisors (docs/protocol.md "Security"): the device's supervisor
 * keys, the challenges of signed connects, the session keys derived from
 * them, and the truncated MACs of messages and heartbeats.
 *
 * The cryptography is libsodium's HMAC-SHA256 (crypto_auth_hmacsha256_*)
 * and its constant-time comparison (sodium_memcmp); nothing here is a
 * primitive of its own. What this module adds is the framing, which
 * docs/protocol.md "The signature" states byte for byte:
 *
 *   session key   K_s = HMAC(K, "LS1K" | host_nonce | device_nonce | host | device)
 *   message MAC   HMAC(K_s, "LS1U" or "LS1D" | source | target | epoch (LE32) | body), first 8 bytes
 *   heartbeat MAC HMAC(K_s, "LS1H" | source | epoch (LE32) | counter (LE32) | period_ms (LE16)),
 *                 first 3 bytes, little-endian: the 24-bit hb_token
 *
 * where a message's body is its bytes before the MAC field, which ends it:
 * the bytes field Uplink.mac / Downlink.mac (field LS_AUTH_MAC_FIELD, the
 * same number in both), tag, length 8, the 8 bytes.
 *
 * Portable firmware: no OS call, no clock (time is passed in), no randomness
 * of its own (the caller draws the device's nonces), no allocation. Every
 * function costs a few HMAC-SHA256 compressions (docs/performance.md: the
 * MAC of a message, in instructions) and may run in the comms thread, never
 * in the control loop. The caller owns every structure; the long-term keys
 * (ls_auth_t) belong in memory the process locks and leaves out of core
 * dumps (landscaped does), and are wiped by ls_auth_wipe. */
#ifndef LS_AUTH_H
#define LS_AUTH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <sodium/crypto_auth_hmacsha256.h>

#include "landscape.pb.h"
#include "ls_err.h"

/* The scheme's sizes: the schema's enum AuthParam, their one home. */
#define LS_AUTH_MAC_BYTES ((size_t)ls_AuthParam_AUTH_MAC_BYTES)
#define LS_AUTH_NONCE_BYTES ((size_t)ls_AuthParam_AUTH_NONCE_BYTES)
#define LS_AUTH_KEY_BYTES ((size_t)ls_AuthParam_AUTH_KEY_BYTES)
#define LS_AUTH_HB_MAC_MASK ((1u << (unsigned)ls_AuthParam_AUTH_HEARTBEAT_MAC_BITS) - 1u)
#define LS_AUTH_CHALLENGE_TTL_US ((uint64_t)ls_AuthParam_AUTH_CHALLENGE_TTL_MS * 1000u)
/* The MAC field's number, the same in Uplink and Downlink, and the bytes it
 * adds to a message: its tag (one byte for fields 1..15), its length, the MAC. */
#define LS_AUTH_MAC_FIELD ls_Uplink_mac_tag
#define LS_AUTH_TRAILER_BYTES (2u + LS_AUTH_MAC_BYTES)
/* A key id: a name of the key file, as long as ConnectReq.key_id holds. */
#define LS_AUTH_KEY_ID_SIZE sizeof(((ls_ConnectReq *)0)->key_id)

/* Keys of one device and challenges waiting for their connect. Per profile
 * (CMakeLists.txt LS_PROFILE): a challenge takes the slot of its address,
 * else a free one, else the oldest (docs/protocol.md "Budgets under floods"). */
#if LS_PROFILE_MCU
#define LS_AUTH_MAX_KEYS 2
#define LS_AUTH_MAX_CHALLENGES 4
#else
#define LS_AUTH_MAX_KEYS 8
#define LS_AUTH_MAX_CHALLENGES 8
#endif

/* Which way a message goes: the first bytes of its MAC's input. */
typedef enum {
    LS_AUTH_UP,   /* supervisor -> device: "LS1U" */
    LS_AUTH_DOWN, /* device -> supervisor: "LS1D" */
} ls_auth_dir_t;

/* A supervisor key of the key file. */
typedef struct {
    char id[LS_AUTH_KEY_ID_SIZE];
    uint8_t key[LS_AUTH_KEY_BYTES];
} ls_auth_key_t;

/* A session key, ready to MAC with (the HMAC state after the key: copying it
 * saves the key's two compressions per message). Plain data: copy freely;
 * wipe with ls_auth_wipe when the session ends. */
typedef struct {
    crypto_auth_hmacsha256_state st;
} ls_auth_session_key_t;

/* A challenge answered: good for one connect from `addr` carrying
 * host_nonce, within LS_AUTH_CHALLENGE_TTL_US of issued_us. */
typedef struct {
    bool used;
    uint8_t addr;
    uint8_t key; /* index in ls_auth_t.keys */
    uint8_t host_nonce[LS_AUTH_NONCE_BYTES];
    uint8_t device_nonce[LS_AUTH_NONCE_BYTES];
    uint64_t issued_us;
} ls_auth_challenge_t;

typedef struct {
    ls_AuthPolicy policy;  /* AUTH_UNSIGNED or AUTH_SIGNED */
    bool unsigned_queries; /* signed: answer unsigned queries without a session */
    ls_auth_key_t keys[LS_AUTH_MAX_KEYS];
    uint8_t n_keys;
    ls_auth_challenge_t challenges[LS_AUTH_MAX_CHALLENGES];
    uint32_t challenges_replaced; /* challenges dropped for another before their connect */
} ls_auth_t;

/* Start with no key and no challenge. `policy` AUTH_SIGNED without a key
 * is the caller's to refuse (it would serve nobody). Init only. */
void ls_auth_init(ls_auth_t *a, ls_AuthPolicy policy, bool unsigned_queries);

/* Add the key `id` (1 .. LS_AUTH_KEY_ID_SIZE - 1 bytes, printable ASCII
 * without blanks, '=' or '#': a name of the key file) of LS_AUTH_KEY_BYTES
 * bytes (copied). LS_OK; LS_EINVAL (a bad id or a NULL); LS_ESTATE (the id
 * is taken); LS_ENOSPC (LS_AUTH_MAX_KEYS already). Untouched on error.
 * Init only. */
int ls_auth_add_key(ls_auth_t *a, const char *id, const uint8_t *key);

/* The index of key `id`, or LS_ENOENT. O(keys). */
int ls_auth_key_index(const ls_auth_t *a, const char *id);

/* Remember a challenge: key index `key` for a connect from `addr` carrying
 * `host_nonce`, answered with `device_nonce` (both LS_AUTH_NONCE_BYTES,
 * copied), at now_us. It replaces the challenge of the same address, else
 * takes a free slot, else the oldest one (counted in challenges_replaced).
 * LS_OK; LS_EINVAL (a key index that is not one). O(challenges). */
int ls_auth_challenge_put(ls_auth_t *a, uint8_t addr, int key, const uint8_t *host_nonce, const uint8_t *device_nonce,
                          uint64_t now_us);

/* The challenge waiting for a connect from `addr` with this host nonce
 * (`len` bytes), or NULL: none, another nonce, or older than
 * LS_AUTH_CHALLENGE_TTL_US. O(challenges); the table is not changed. */
const ls_auth_challenge_t *ls_auth_challenge_find(const ls_auth_t *a, uint8_t addr, const uint8_t *host_nonce,
                                                  size_t len, uint64_t now_us);

/* Forget the challenge of `addr` (its connect has been taken: a nonce is
 * good for one connect). O(challenges). */
void ls_auth_challenge_drop(ls_auth_t *a, uint8_t addr);

/* The session key of challenge `c` between supervisor `host` and `device`
 * into *out (K_s above). `c` must come from ls_auth_challenge_find on `a`. */
void ls_auth_session_key(const ls_auth_t *a, const ls_auth_challenge_t *c, uint8_t host, uint8_t device,
                         ls_auth_session_key_t *out);

/* The MAC of `len` body bytes going `dir` from `source` to `target` in
 * session epoch `epoch` (0 before the session exists: a challenge's answer,
 * a connect), into out[LS_AUTH_MAC_BYTES]. */
void ls_auth_mac(const ls_auth_session_key_t *k, ls_auth_dir_t dir, uint8_t source, uint8_t target, uint32_t epoch,
                 const uint8_t *body, size_t len, uint8_t *out);

/* The length of the body of message `msg` (`len` bytes) when it ends with a
 * MAC field (LS_AUTH_TRAILER_BYTES); LS_ENOENT when it does not (it carries
 * none, or not last). */
int ls_auth_body_len(const uint8_t *msg, size_t len);

/* Whether message `msg` ends with a MAC field holding the MAC of its body
 * (ls_auth_mac with the same arguments), compared in constant time. */
bool ls_auth_verify(const ls_auth_session_key_t *k, ls_auth_dir_t dir, uint8_t source, uint8_t target, uint32_t epoch,
                    const uint8_t *msg, size_t len);

/* Append the MAC field of the `len` body bytes in buf (`cap` bytes long) and
 * return the new length; LS_ENOSPC when it does not fit (buf untouched). */
int ls_auth_sign(const ls_auth_session_key_t *k, ls_auth_dir_t dir, uint8_t source, uint8_t target, uint32_t epoch,
                 uint8_t *buf, size_t len, size_t cap);

/* The 24-bit MAC a signed session's HEARTBEAT carries in hb_token: from
 * `source` in `epoch`, its full counter and the period it states. */
uint32_t ls_auth_heartbeat_mac(const ls_auth_session_key_t *k, uint8_t source, uint32_t epoch, uint32_t counter,
                               uint16_t period_ms);

/* The full heartbeat counter a frame's 8-bit hb_counter `low` stands for,
 * after the last one accepted (`last`): the first value above `last` whose
 * low 8 bits are `low` (a gap of up to 255 lost heartbeats is bridged; a
 * replayed frame yields a counter its MAC was not made with). */
uint32_t ls_auth_heartbeat_counter(uint32_t last, uint8_t low);

/* Overwrite `len` bytes at p with zeros in a way the compiler keeps
 * (sodium_memzero): keys, session keys, a challenge. */
void ls_auth_wipe(void *p, size_t len);

#endif
