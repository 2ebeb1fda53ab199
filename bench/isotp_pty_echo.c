/* bench_isotp_pty_echo: the firmware's ISO-TP stack as an echo peer on an
 * SLCAN pseudo-terminal (hal/sim/slcan_pty), for the throughput and latency
 * benchmark. Every complete message received from the host is sent back.
 *
 * Addressing: normal fixed 29-bit, device 0x10, host 0xF1 (as landscaped).
 * Config: the firmware defaults (BS 8, STmin 0, padding 0xCC).
 * Usage: bench_isotp_pty_echo PATH [ANSWER_BYTES]   (PATH becomes a symlink
 * to the pty slave); runs until SIGTERM/SIGINT, then prints its counters to
 * stderr. With ANSWER_BYTES every message is answered with that many bytes
 * (the message's bytes repeated) instead of itself: an exchange of the same
 * sizes as a command and its answer (benchmark 3). The loop sleeps until a
 * frame or the next ISO-TP deadline, as landscaped's comms thread does. */
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hal/hal_can.h"
#include "landscape.pb.h"
#include "ls_isotp.h"
#include "slcan_pty.h"

/* The device's side of the default host <-> device pair (protocol/landscape.proto). */
#define DEV ((uint32_t)ls_NodeAddress_DEFAULT_DEVICE_ADDRESS)
#define HOST ((uint32_t)ls_NodeAddress_DEFAULT_HOST_ADDRESS)
#define RX_ID ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE | DEV << 8 | HOST)
#define TX_ID ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE | HOST << 8 | DEV)

static volatile sig_atomic_t stop_;
static hal_can_link_t can_;
static ls_isotp_link_t link_;
static uint8_t msg_[LS_ISOTP_MAX_PAYLOAD];

static void on_signal(int sig)
{
    (void)sig;
    stop_ = 1;
}

static uint64_t now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static int can_send(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len)
{
    (void)ctx;
    hal_can_frame_t f = { .id = can_id, .flags = HAL_CAN_F_EXT, .len = len };
    memcpy(f.data, data, len);
    return hal_can_send(&can_, &f);
}

int main(int argc, char **argv)
{
    if (argc != 2 && argc != 3) {
        fprintf(stderr, "usage: %s PATH [ANSWER_BYTES]\n", argv[0]);
        return 2;
    }
    size_t answer_len = 0; /* 0: echo */
    if (argc == 3) {
        char *end = NULL;
        const unsigned long v = strtoul(argv[2], &end, 10);
        if (end == argv[2] || *end != '\0' || v == 0 || v > LS_ISOTP_MAX_PAYLOAD) {
            fprintf(stderr, "bench_isotp_pty_echo: ANSWER_BYTES %s: expected 1..%u\n", argv[2],
                    (unsigned)LS_ISOTP_MAX_PAYLOAD);
            return 2;
        }
        answer_len = (size_t)v;
    }
    char msg[256];
    if (hal_sim_slcan_pty_open(&can_, argv[1], msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "bench_isotp_pty_echo: %s\n", msg);
        return 1;
    }
    signal(SIGTERM, on_signal);
    signal(SIGINT, on_signal);
    if (ls_isotp_init(&link_, NULL, TX_ID, RX_ID, can_send, NULL) != LS_OK) {
        fprintf(stderr, "bench_isotp_pty_echo: ISO-TP init failed\n");
        hal_can_close(&can_);
        return 1;
    }
    struct pollfd pfd = { .fd = hal_can_poll_fd(&can_), .events = POLLIN };
    while (!stop_) {
        uint64_t t = now_us();
        uint64_t due = ls_isotp_next_deadline_us(&link_);
        int timeout_ms = due == UINT64_MAX ? 100 : (due <= t ? 0 : (int)((due - t + 999u) / 1000u));
        if (timeout_ms > 100) {
            timeout_ms = 100;
        }
        /* A frame refused by a full pty queue is retried by poll: do not sleep long then. */
        if (ls_isotp_tx_busy(&link_) && timeout_ms > 1) {
            timeout_ms = 1;
        }
        if (poll(&pfd, 1, timeout_ms) < 0 && errno != EINTR) {
            break;
        }
        hal_can_frame_t f;
        int r;
        while ((r = hal_can_recv(&can_, &f)) == 1) {
            if (f.id == RX_ID && (f.flags & HAL_CAN_F_EXT) != 0) {
                ls_isotp_on_frame(&link_, f.data, f.len, now_us());
            }
        }
        if (r != LS_EAGAIN) {
            fprintf(stderr, "bench_isotp_pty_echo: link failed: %s\n", ls_err_text(r));
            break;
        }
        ls_isotp_poll(&link_, now_us());
        size_t n = ls_isotp_take_rx(&link_, msg_, sizeof msg_);
        if (n > 0 && answer_len > 0) {
            for (size_t i = n; i < answer_len; i++) {
                msg_[i] = msg_[i % n];
            }
            n = answer_len;
        }
        if (n > 0 && ls_isotp_send(&link_, msg_, n, now_us()) != LS_OK) {
            fprintf(stderr, "bench_isotp_pty_echo: echo of %zu bytes refused (still sending)\n", n);
        }
    }
    fprintf(stderr, "bench_isotp_pty_echo: rx ok %u, tx ok %u, last error %s\n",
            (unsigned)link_.rx_results[LS_ISOTP_N_OK], (unsigned)link_.tx_results[LS_ISOTP_N_OK],
            ls_isotp_result_name(link_.last_error));
    hal_can_close(&can_);
    return 0;
}
