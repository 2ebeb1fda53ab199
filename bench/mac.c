/* Benchmark 17: the cost of a signed session's MAC (firmware/auth), for
 * callgrind. `bench_mac CASE BYTES N`: set-up (a key, a challenge, the session
 * key, a message body of BYTES bytes signed once), then N calls of CASE:
 *   verify      ls_auth_verify of the signed message (what every uplink of a
 *               signed session costs the device before it is decoded)
 *   sign        ls_auth_sign of the body (every downlink)
 *   heartbeat   ls_auth_heartbeat_mac (every supervisor heartbeat)
 *   session     ls_auth_session_key (once per signed connect)
 * Instructions per call = (total of an N-call run - total of N = 0) / N.
 * Prints a checksum that keeps the calls alive. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_auth.h"

int main(int argc, char **argv)
{
    const char *cases = "verify|sign|heartbeat|session";
    if (argc != 4 || strstr(cases, argv[1]) == NULL || strchr(argv[1], '|') != NULL) {
        fprintf(stderr, "usage: bench_mac %s BYTES N\n", cases);
        return 2;
    }
    const size_t bytes = (size_t)strtoul(argv[2], NULL, 10);
    const long n = strtol(argv[3], NULL, 10);
    static uint8_t buf[4096 + LS_AUTH_TRAILER_BYTES];
    if (bytes > 4096) {
        fprintf(stderr, "bench_mac: BYTES is at most 4096\n");
        return 2;
    }
    static ls_auth_t auth;
    uint8_t key[LS_AUTH_KEY_BYTES], hn[LS_AUTH_NONCE_BYTES], dn[LS_AUTH_NONCE_BYTES];
    for (size_t i = 0; i < sizeof key; i++) {
        key[i] = (uint8_t)(i * 7u + 1u);
    }
    memset(hn, 0x11, sizeof hn);
    memset(dn, 0x22, sizeof dn);
    ls_auth_init(&auth, ls_AuthPolicy_AUTH_SIGNED, false);
    if (ls_auth_add_key(&auth, "bench", key) != LS_OK || ls_auth_challenge_put(&auth, 0xF1, 0, hn, dn, 0u) != LS_OK) {
        return 1;
    }
    const ls_auth_challenge_t *c = ls_auth_challenge_find(&auth, 0xF1, hn, sizeof hn, 0u);
    if (c == NULL) {
        return 1;
    }
    ls_auth_session_key_t ks;
    ls_auth_session_key(&auth, c, 0xF1, 0x10, &ks);
    for (size_t i = 0; i < bytes; i++) {
        buf[i] = (uint8_t)(i ^ 0x5Au);
    }
    const int len = ls_auth_sign(&ks, LS_AUTH_UP, 0xF1, 0x10, 7u, buf, bytes, sizeof buf);
    if (len < 0) {
        return 1;
    }
    unsigned sum = 0;
    for (long k = 0; k < n; k++) {
        if (strcmp(argv[1], "verify") == 0) {
            sum += ls_auth_verify(&ks, LS_AUTH_UP, 0xF1, 0x10, 7u, buf, (size_t)len) ? 1u : 0u;
        } else if (strcmp(argv[1], "sign") == 0) {
            sum += (unsigned)ls_auth_sign(&ks, LS_AUTH_DOWN, 0x10, 0xF1, 7u, buf, bytes, sizeof buf);
        } else if (strcmp(argv[1], "heartbeat") == 0) {
            sum += ls_auth_heartbeat_mac(&ks, 0xF1, 7u, (uint32_t)k, 200u);
        } else {
            ls_auth_session_key_t s2;
            ls_auth_session_key(&auth, c, 0xF1, 0x10, &s2);
            sum += s2.st.ictx.state[0];
        }
    }
    printf("%u\n", sum);
    ls_auth_wipe(&auth, sizeof auth);
    return 0;
}
