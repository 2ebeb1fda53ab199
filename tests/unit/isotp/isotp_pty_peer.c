/* isotp_pty_peer: one ls_isotp link on the same SLCAN pty link that
 * landscaped uses (hal/sim/slcan_pty.h), echoing every message it receives.
 * It lets python can-isotp talk to the firmware's ISO-TP over the real pty
 * and python-can's slcan driver, with nothing in between.
 *
 * Addressing: ISO-TP normal fixed 29-bit, device 0x10 <-> host 0xF1.
 *   receives 0x18DA10F1 (host -> device), transmits 0x18DAF110 (device -> host)
 *
 * Usage: isotp_pty_peer [-b BS] [-s STMIN] [-p 0|1] slcan:pty:PATH
 *   BS and STMIN (raw ISO byte, decimal or 0x hex) are what the peer asks of
 *   the host in its flow controls; -p 0 turns padding of its frames off.
 *
 * stdout, one line per event, flushed at once (a test reads it):
 *   READY                    the pty symlink exists and the link runs
 *   R <us> <hex id> <hex data>  a frame of this link received from the host
 *   T <us> <hex id> <hex data>  a frame the link transmitted
 *                           (<us>: CLOCK_MONOTONIC in microseconds, decimal)
 *   M <len>                  a whole message received (and queued for echo)
 *   E <text>                 a transfer failed (ISO-TP N_Result) or a send was refused
 * SIGTERM or SIGINT: close the link (removes the symlink), print the counters
 * on stderr and exit 0. Exit 1: the link failed. Exit 2: bad arguments or the pty could not be made. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hal/hal_can.h"
#include "peer_ids.h"
#include "ls_isotp.h"
#include "slcan_pty.h"

#define LINK_PREFIX "slcan:pty:"
/* Upper bound of one wait: keeps the pty's pending output flowing while the
 * host reads slowly (flushing happens on recv/send calls). */
#define MAX_WAIT_MS 1
#define IDLE_WAIT_MS 50

static volatile sig_atomic_t g_stop;
static hal_can_link_t g_can;
static ls_isotp_link_t g_link;
/* Echoes waiting for the sender: a message is taken from the receiver at once
 * (a receiver holding a finished message answers a new FF with FC.OVFLW), so
 * the host may send its next message while the previous echo is going out. */
#define ECHO_QUEUE 8
static uint8_t g_q[ECHO_QUEUE][LS_ISOTP_MAX_PAYLOAD];
static size_t g_q_len[ECHO_QUEUE];
static size_t g_q_head, g_q_count;
static uint32_t g_tx_refused;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static uint64_t now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static void put_frame(char kind, uint64_t t_us, uint32_t id, const uint8_t *data, uint8_t len)
{
    printf("%c %llu %08X ", kind, (unsigned long long)t_us, (unsigned)id);
    for (uint8_t i = 0; i < len; i++) {
        printf("%02X", data[i]);
    }
    putchar('\n');
}

static int link_send(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len)
{
    (void)ctx;
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = can_id;
    f.flags = HAL_CAN_F_EXT;
    f.len = len;
    memcpy(f.data, data, len);
    int rc = hal_can_send(&g_can, &f);
    if (rc < 0) {
        g_tx_refused++; /* the pty is full: ls_isotp retries this frame on the next poll */
        return rc;
    }
    put_frame('T', now_us(), can_id, data, len);
    return 0;
}

static int parse_args(int argc, char **argv, ls_isotp_config_t *cfg, const char **path)
{
    *path = NULL;
    for (int i = 1; i < argc; i++) {
        if (strncmp(argv[i], LINK_PREFIX, strlen(LINK_PREFIX)) == 0 && *path == NULL) {
            *path = argv[i] + strlen(LINK_PREFIX);
            continue;
        }
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
    return *path != NULL && (*path)[0] != '\0' ? 0 : -1;
}

/* Counts of failed transfers seen so far, to report each new one once. */
static uint32_t errors_total(const ls_isotp_link_t *l)
{
    uint32_t n = 0;
    for (int r = LS_ISOTP_N_OK + 1; r < LS_ISOTP_N_RESULT_COUNT; r++) {
        n += l->rx_results[r] + l->tx_results[r];
    }
    return n;
}

/* Called after every frame, not once per batch: the last CF of one message
 * and the FF of the next often arrive in one read of the pty. */
static void take_message(void)
{
    if (g_q_count >= ECHO_QUEUE) {
        return; /* the receiver keeps it (and refuses the next FF) until there is room */
    }
    size_t slot = (g_q_head + g_q_count) % ECHO_QUEUE;
    g_q_len[slot] = ls_isotp_take_rx(&g_link, g_q[slot], sizeof g_q[slot]);
    if (g_q_len[slot] > 0) {
        printf("M %zu\n", g_q_len[slot]);
        g_q_count++;
    }
}

static int wait_ms(uint64_t now)
{
    if (g_q_count > 0 || ls_isotp_tx_busy(&g_link)) {
        return MAX_WAIT_MS;
    }
    uint64_t d = ls_isotp_next_deadline_us(&g_link);
    if (d <= now) {
        return 0;
    }
    uint64_t ms = (d - now + 999u) / 1000u;
    return ms < IDLE_WAIT_MS ? (int)ms : IDLE_WAIT_MS;
}

static int serve(void)
{
    uint32_t errors_seen = 0;
    while (!g_stop) {
        struct pollfd pfd = { .fd = hal_can_poll_fd(&g_can), .events = POLLIN, .revents = 0 };
        if (poll(&pfd, 1, wait_ms(now_us())) < 0 && errno != EINTR) {
            fprintf(stderr, "isotp_pty_peer: poll: %s\n", strerror(errno));
            return -1;
        }
        uint64_t t = now_us();
        hal_can_frame_t f;
        int rc;
        while ((rc = hal_can_recv(&g_can, &f)) == 1) {
            if ((f.flags & HAL_CAN_F_EXT) != 0u && f.id == LS_PEER_RX_ID) {
                put_frame('R', t, f.id, f.data, f.len);
                ls_isotp_on_frame(&g_link, f.data, f.len, t);
                take_message();
            }
        }
        if (rc != LS_EAGAIN) {
            fprintf(stderr, "isotp_pty_peer: the pty link failed (%d)\n", rc);
            return -1;
        }
        ls_isotp_poll(&g_link, t);
        take_message();
        if (g_q_count > 0 && !ls_isotp_tx_busy(&g_link)) {
            int s = ls_isotp_send(&g_link, g_q[g_q_head], g_q_len[g_q_head], t);
            if (s != LS_OK) {
                printf("E echo of %zu bytes refused: %d\n", g_q_len[g_q_head], s);
            }
            g_q_head = (g_q_head + 1u) % ECHO_QUEUE;
            g_q_count--;
        }
        uint32_t e = errors_total(&g_link);
        if (e != errors_seen) {
            printf("E transfer failed: %s\n", ls_isotp_result_name(g_link.last_error));
            errors_seen = e;
        }
        fflush(stdout);
    }
    return 0;
}

int main(int argc, char **argv)
{
    ls_isotp_config_t cfg;
    ls_isotp_default_config(&cfg);
    const char *path = NULL;
    if (parse_args(argc, argv, &cfg, &path) != 0) {
        fprintf(stderr, "usage: %s [-b BS] [-s STMIN] [-p 0|1] slcan:pty:PATH\n", argv[0]);
        return 2;
    }
    if (ls_isotp_init(&g_link, &cfg, LS_PEER_TX_ID, LS_PEER_RX_ID, link_send, NULL) != LS_OK) {
        fprintf(stderr, "isotp_pty_peer: invalid ISO-TP configuration (reserved STmin?)\n");
        return 2;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    char msg[160];
    if (hal_sim_slcan_pty_open(&g_can, path, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "isotp_pty_peer: %s\n", msg);
        return 2;
    }
    printf("READY\n");
    fflush(stdout);
    int rc = serve();
    hal_can_close(&g_can);
    fprintf(stderr, "isotp_pty_peer: rx ok %u, tx ok %u, failed transfers %u, frames refused by the pty %u\n",
            (unsigned)g_link.rx_results[LS_ISOTP_N_OK], (unsigned)g_link.tx_results[LS_ISOTP_N_OK],
            (unsigned)errors_total(&g_link), (unsigned)g_tx_refused);
    return rc == 0 ? 0 : 1;
}
