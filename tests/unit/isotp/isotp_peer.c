/* isotp_peer: one ls_isotp link driven by a line protocol on stdin/stdout, so
 * that a test in another language can put it on a (virtual) CAN bus.
 *
 * Addressing: ISO-TP normal fixed 29-bit, device 0x10, host 0xF1.
 *   receives 0x18DA10F1 (host -> device), transmits 0x18DAF110 (device -> host)
 *
 * Input lines:   F <hex id> <hex data>   a CAN frame seen on the bus
 *                T <us>                  time is now <us> (monotonic, decimal)
 *                S <hex payload>         send a message
 *                Q                       quit
 * Output lines:  F <hex id> <hex data> <us>
 *                                        a frame the link transmits, and the
 *                                        link's time when it did (so a test
 *                                        can check STmin on the device's clock)
 *                M <hex payload>         a message the link received
 *                E <text>                a rejected input line or API error
 * Frames with another id are ignored (the bus is shared). The link is polled
 * after every input line.
 *
 * Usage: isotp_peer [-b BS] [-s STMIN] [-p 0|1]   (STMIN is the raw ISO byte,
 * decimal or 0x hex; -p 0 turns padding off). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "peer_ids.h"
#include "ls_isotp.h"

#define LINE_MAX_CHARS (2u * LS_ISOTP_MAX_PAYLOAD + 64u)

static ls_isotp_link_t link_;
static char line[LINE_MAX_CHARS];
static uint8_t buf[LS_ISOTP_MAX_PAYLOAD];

static void put_hex(const uint8_t *d, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        printf("%02X", d[i]);
    }
}

static int peer_send(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len)
{
    const uint64_t *now_us = ctx;
    printf("F %08X ", (unsigned)can_id);
    put_hex(data, len);
    printf(" %llu\n", (unsigned long long)*now_us);
    return 0;
}

static int hex_nibble(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

/* Parses hex digits up to the end of the token; returns the byte count or -1. */
static long parse_hex(const char *s, uint8_t *out, size_t cap)
{
    size_t n = 0;
    while (*s != '\0' && *s != '\n' && *s != '\r' && *s != ' ') {
        int hi = hex_nibble(s[0]);
        int lo = hex_nibble(s[1]);
        if (hi < 0 || lo < 0 || n >= cap) {
            return -1;
        }
        out[n++] = (uint8_t)((hi << 4) | lo);
        s += 2;
    }
    return (long)n;
}

static int parse_args(int argc, char **argv, ls_isotp_config_t *cfg)
{
    for (int i = 1; i < argc; i++) {
        if (i + 1 >= argc) {
            return -1;
        }
        char *end = NULL;
        unsigned long v = strtoul(argv[i + 1], &end, 0);
        if (end == argv[i + 1] || *end != '\0' || v > 0xFFu) {
            return -1;
        }
        if (strcmp(argv[i], "-b") == 0) {
            cfg->block_size = (uint8_t)v;
        } else if (strcmp(argv[i], "-s") == 0) {
            cfg->st_min = (uint8_t)v;
        } else if (strcmp(argv[i], "-p") == 0) {
            cfg->tx_padding = v != 0;
        } else {
            return -1;
        }
        i++;
    }
    return 0;
}

int main(int argc, char **argv)
{
    ls_isotp_config_t cfg;
    ls_isotp_default_config(&cfg);
    if (parse_args(argc, argv, &cfg) != 0) {
        fprintf(stderr, "usage: %s [-b BS] [-s STMIN] [-p 0|1]\n", argv[0]);
        return 2;
    }
    uint64_t now_us = 0;
    if (ls_isotp_init(&link_, &cfg, LS_PEER_TX_ID, LS_PEER_RX_ID, peer_send, &now_us) != LS_OK) {
        fprintf(stderr, "isotp_peer: invalid configuration (reserved STmin?)\n");
        return 2;
    }
    while (fgets(line, sizeof(line), stdin) != NULL) {
        if (strchr(line, '\n') == NULL && !feof(stdin)) {
            printf("E line too long\n");
            int c;
            while ((c = getchar()) != EOF && c != '\n') {
            }
            continue;
        }
        char kind = line[0];
        if (kind == 'Q') {
            break;
        } else if (kind == 'T' && line[1] == ' ') {
            char *end = NULL;
            unsigned long long t = strtoull(line + 2, &end, 10);
            if (end == line + 2) {
                printf("E bad time: %s", line);
            } else if (t > now_us) {
                now_us = t; /* time never runs backwards for the link */
            }
        } else if (kind == 'F' && line[1] == ' ') {
            char *end = NULL;
            unsigned long id = strtoul(line + 2, &end, 16);
            long n = (end != line + 2 && *end == ' ') ? parse_hex(end + 1, buf, 8) : -1;
            if (n < 1) {
                printf("E bad frame: %s", line);
            } else if (id == LS_PEER_RX_ID) {
                ls_isotp_on_frame(&link_, buf, (uint8_t)n, now_us);
            }
        } else if (kind == 'S' && line[1] == ' ') {
            long n = parse_hex(line + 2, buf, sizeof(buf));
            int rc = n < 1 ? LS_ELEN : ls_isotp_send(&link_, buf, (size_t)n, now_us);
            if (rc != LS_OK) {
                printf("E send failed: %d\n", rc);
            }
        } else if (line[0] != '\n') {
            printf("E unknown line: %s", line);
        }
        ls_isotp_poll(&link_, now_us);
        size_t got = ls_isotp_take_rx(&link_, buf, sizeof(buf));
        if (got > 0) {
            printf("M ");
            put_hex(buf, got);
            putchar('\n');
        }
        fflush(stdout);
    }
    fprintf(stderr, "isotp_peer: rx ok %u, tx ok %u, last error %s\n", (unsigned)link_.rx_results[LS_ISOTP_N_OK],
            (unsigned)link_.tx_results[LS_ISOTP_N_OK], ls_isotp_result_name(link_.last_error));
    return 0;
}
