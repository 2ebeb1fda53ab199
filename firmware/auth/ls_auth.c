/* Signed supervisors: keys, challenges, session keys and MACs. See ls_auth.h. */
#include "ls_auth.h"

#include <string.h>

#include <pb.h>
#include <sodium/utils.h>

_Static_assert(ls_Uplink_mac_tag == ls_Downlink_mac_tag, "Uplink.mac and Downlink.mac must share a field number");
_Static_assert(LS_AUTH_MAC_FIELD <= 15u, "the MAC field's tag must fit one byte (fields 1..15)");
_Static_assert(sizeof(((ls_Uplink *)0)->mac.bytes) == LS_AUTH_MAC_BYTES, "Uplink.mac holds AUTH_MAC_BYTES");
_Static_assert(sizeof(((ls_Downlink *)0)->mac.bytes) == LS_AUTH_MAC_BYTES, "Downlink.mac holds AUTH_MAC_BYTES");
_Static_assert(sizeof(((ls_ConnectReq *)0)->host_nonce.bytes) == LS_AUTH_NONCE_BYTES,
               "ConnectReq.host_nonce holds AUTH_NONCE_BYTES");
_Static_assert(sizeof(((ls_ChallengeRes *)0)->device_nonce.bytes) == LS_AUTH_NONCE_BYTES,
               "ChallengeRes.device_nonce holds AUTH_NONCE_BYTES");
_Static_assert(LS_AUTH_KEY_BYTES == crypto_auth_hmacsha256_KEYBYTES, "a key is one HMAC-SHA256 key");
_Static_assert(LS_AUTH_MAC_BYTES <= crypto_auth_hmacsha256_BYTES, "the MAC is a cut HMAC-SHA256");

/* The labels that start each MAC's input: no two inputs of the scheme are
 * the same bytes, so a MAC of one kind is never valid as another. */
static const uint8_t LABEL_KEY[4] = { 'L', 'S', '1', 'K' };
static const uint8_t LABEL_UP[4] = { 'L', 'S', '1', 'U' };
static const uint8_t LABEL_DOWN[4] = { 'L', 'S', '1', 'D' };
static const uint8_t LABEL_HEARTBEAT[4] = { 'L', 'S', '1', 'H' };

static void put_le32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0; i < 4u; i++) {
        p[i] = (uint8_t)(v >> (8u * i));
    }
}

void ls_auth_init(ls_auth_t *a, ls_AuthPolicy policy, bool unsigned_queries)
{
    ls_auth_wipe(a, sizeof *a);
    a->policy = policy;
    a->unsigned_queries = unsigned_queries;
}

static bool id_ok(const char *id)
{
    size_t n = 0;
    for (; id[n] != '\0'; n++) {
        const char c = id[n];
        if (n + 1u >= LS_AUTH_KEY_ID_SIZE || c <= ' ' || c > '~' || c == '=' || c == '#' || c == ';') {
            return false;
        }
    }
    return n > 0;
}

int ls_auth_add_key(ls_auth_t *a, const char *id, const uint8_t *key)
{
    if (a == NULL || id == NULL || key == NULL || !id_ok(id)) {
        return LS_EINVAL;
    }
    if (ls_auth_key_index(a, id) >= 0) {
        return LS_ESTATE;
    }
    if (a->n_keys >= LS_AUTH_MAX_KEYS) {
        return LS_ENOSPC;
    }
    ls_auth_key_t *k = &a->keys[a->n_keys++];
    memcpy(k->id, id, strlen(id) + 1u);
    memcpy(k->key, key, LS_AUTH_KEY_BYTES);
    return LS_OK;
}

int ls_auth_key_index(const ls_auth_t *a, const char *id)
{
    for (uint8_t i = 0; i < a->n_keys; i++) {
        if (strcmp(a->keys[i].id, id) == 0) {
            return i;
        }
    }
    return LS_ENOENT;
}

int ls_auth_challenge_put(ls_auth_t *a, uint8_t addr, int key, const uint8_t *host_nonce, const uint8_t *device_nonce,
                          uint64_t now_us)
{
    if (key < 0 || key >= a->n_keys) {
        return LS_EINVAL;
    }
    ls_auth_challenge_t *slot = NULL, *free_slot = NULL, *oldest = NULL;
    for (size_t i = 0; i < LS_AUTH_MAX_CHALLENGES; i++) {
        ls_auth_challenge_t *c = &a->challenges[i];
        if (c->used && c->addr == addr) {
            slot = c;
            break;
        }
        if (!c->used) {
            free_slot = free_slot != NULL ? free_slot : c;
        } else if (oldest == NULL || c->issued_us < oldest->issued_us) {
            oldest = c;
        }
    }
    if (slot == NULL) {
        slot = free_slot;
    }
    if (slot == NULL) {
        slot = oldest;
        a->challenges_replaced++;
    }
    slot->used = true;
    slot->addr = addr;
    slot->key = (uint8_t)key;
    memcpy(slot->host_nonce, host_nonce, LS_AUTH_NONCE_BYTES);
    memcpy(slot->device_nonce, device_nonce, LS_AUTH_NONCE_BYTES);
    slot->issued_us = now_us;
    return LS_OK;
}

const ls_auth_challenge_t *ls_auth_challenge_find(const ls_auth_t *a, uint8_t addr, const uint8_t *host_nonce,
                                                  size_t len, uint64_t now_us)
{
    for (size_t i = 0; i < LS_AUTH_MAX_CHALLENGES; i++) {
        const ls_auth_challenge_t *c = &a->challenges[i];
        if (c->used && c->addr == addr) {
            const bool fresh = now_us >= c->issued_us && now_us - c->issued_us <= LS_AUTH_CHALLENGE_TTL_US;
            return fresh && len == LS_AUTH_NONCE_BYTES && memcmp(c->host_nonce, host_nonce, len) == 0 ? c : NULL;
        }
    }
    return NULL;
}

void ls_auth_challenge_drop(ls_auth_t *a, uint8_t addr)
{
    for (size_t i = 0; i < LS_AUTH_MAX_CHALLENGES; i++) {
        if (a->challenges[i].used && a->challenges[i].addr == addr) {
            ls_auth_wipe(&a->challenges[i], sizeof a->challenges[i]);
        }
    }
}

void ls_auth_session_key(const ls_auth_t *a, const ls_auth_challenge_t *c, uint8_t host, uint8_t device,
                         ls_auth_session_key_t *out)
{
    uint8_t ks[crypto_auth_hmacsha256_BYTES];
    const uint8_t addrs[2] = { host, device };
    crypto_auth_hmacsha256_state st;
    crypto_auth_hmacsha256_init(&st, a->keys[c->key].key, LS_AUTH_KEY_BYTES);
    crypto_auth_hmacsha256_update(&st, LABEL_KEY, sizeof LABEL_KEY);
    crypto_auth_hmacsha256_update(&st, c->host_nonce, LS_AUTH_NONCE_BYTES);
    crypto_auth_hmacsha256_update(&st, c->device_nonce, LS_AUTH_NONCE_BYTES);
    crypto_auth_hmacsha256_update(&st, addrs, sizeof addrs);
    crypto_auth_hmacsha256_final(&st, ks);
    crypto_auth_hmacsha256_init(&out->st, ks, sizeof ks);
    ls_auth_wipe(ks, sizeof ks);
    ls_auth_wipe(&st, sizeof st);
}

void ls_auth_mac(const ls_auth_session_key_t *k, ls_auth_dir_t dir, uint8_t source, uint8_t target, uint32_t epoch,
                 const uint8_t *body, size_t len, uint8_t *out)
{
    uint8_t head[4 + 2 + 4];
    memcpy(head, dir == LS_AUTH_UP ? LABEL_UP : LABEL_DOWN, 4);
    head[4] = source;
    head[5] = target;
    put_le32(&head[6], epoch);
    uint8_t full[crypto_auth_hmacsha256_BYTES];
    crypto_auth_hmacsha256_state st = k->st;
    crypto_auth_hmacsha256_update(&st, head, sizeof head);
    crypto_auth_hmacsha256_update(&st, body, len);
    crypto_auth_hmacsha256_final(&st, full);
    memcpy(out, full, LS_AUTH_MAC_BYTES);
    ls_auth_wipe(&st, sizeof st);
}

/* The MAC field's first two bytes: its tag (length-delimited) and length. */
static void trailer_head(uint8_t out[2])
{
    out[0] = (uint8_t)((LS_AUTH_MAC_FIELD << 3) | (unsigned)PB_WT_STRING);
    out[1] = (uint8_t)LS_AUTH_MAC_BYTES;
}

int ls_auth_body_len(const uint8_t *msg, size_t len)
{
    uint8_t head[2];
    trailer_head(head);
    if (msg == NULL || len < LS_AUTH_TRAILER_BYTES || len > (size_t)INT32_MAX) {
        return LS_ENOENT;
    }
    const uint8_t *t = msg + len - LS_AUTH_TRAILER_BYTES;
    return t[0] == head[0] && t[1] == head[1] ? (int)(len - LS_AUTH_TRAILER_BYTES) : LS_ENOENT;
}

bool ls_auth_verify(const ls_auth_session_key_t *k, ls_auth_dir_t dir, uint8_t source, uint8_t target, uint32_t epoch,
                    const uint8_t *msg, size_t len)
{
    const int body = ls_auth_body_len(msg, len);
    if (body < 0) {
        return false;
    }
    uint8_t mac[LS_AUTH_MAC_BYTES];
    ls_auth_mac(k, dir, source, target, epoch, msg, (size_t)body, mac);
    return sodium_memcmp(mac, msg + (size_t)body + 2u, LS_AUTH_MAC_BYTES) == 0;
}

int ls_auth_sign(const ls_auth_session_key_t *k, ls_auth_dir_t dir, uint8_t source, uint8_t target, uint32_t epoch,
                 uint8_t *buf, size_t len, size_t cap)
{
    if (len > cap || cap - len < LS_AUTH_TRAILER_BYTES) {
        return LS_ENOSPC;
    }
    uint8_t mac[LS_AUTH_MAC_BYTES];
    ls_auth_mac(k, dir, source, target, epoch, buf, len, mac);
    trailer_head(buf + len);
    memcpy(buf + len + 2u, mac, LS_AUTH_MAC_BYTES);
    return (int)(len + LS_AUTH_TRAILER_BYTES);
}

uint32_t ls_auth_heartbeat_mac(const ls_auth_session_key_t *k, uint8_t source, uint32_t epoch, uint32_t counter,
                               uint16_t period_ms)
{
    uint8_t in[4 + 1 + 4 + 4 + 2];
    memcpy(in, LABEL_HEARTBEAT, 4);
    in[4] = source;
    put_le32(&in[5], epoch);
    put_le32(&in[9], counter);
    in[13] = (uint8_t)(period_ms & 0xFFu);
    in[14] = (uint8_t)(period_ms >> 8);
    uint8_t full[crypto_auth_hmacsha256_BYTES];
    crypto_auth_hmacsha256_state st = k->st;
    crypto_auth_hmacsha256_update(&st, in, sizeof in);
    crypto_auth_hmacsha256_final(&st, full);
    ls_auth_wipe(&st, sizeof st);
    return ((uint32_t)full[0] | (uint32_t)full[1] << 8 | (uint32_t)full[2] << 16) & LS_AUTH_HB_MAC_MASK;
}

uint32_t ls_auth_heartbeat_counter(uint32_t last, uint8_t low)
{
    const uint32_t step = (uint32_t)(uint8_t)(low - (uint8_t)last);
    return last + (step == 0u ? 256u : step);
}

void ls_auth_wipe(void *p, size_t len)
{
    sodium_memzero(p, len);
}
