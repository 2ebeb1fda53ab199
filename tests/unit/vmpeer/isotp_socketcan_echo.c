/* isotp_socketcan_echo: the firmware's ISO-TP (ls_isotp) on a real SocketCAN
 * interface through the Linux HAL, echoing every message it receives. The VM
 * tier talks to it with the kernel's CAN_ISOTP (can-utils, Python sockets) to
 * show that both ISO-TP implementations interoperate on a real bus.
 *
 * Addressing: ISO-TP normal fixed 29-bit, device 0x10, host 0xF1.
 *   receives 0x18DA10F1 (host -> device), transmits 0x18DAF110 (device -> host)
 *
 * Usage: isotp_socketcan_echo IFNAME [-t SECONDS]
 *   Prints "ready socketcan:IFNAME" once the link is open, then one line
 *   "echo <len>" per message echoed, and a summary on stderr at exit. Exits
 *   0 on SIGINT/SIGTERM or when SECONDS (default 300) have passed, so that a
 *   forgotten peer never outlives a test run; 2 on bad usage or when the
 *   interface cannot be opened (the HAL's message says why).
 *
 * A received message waits in the link until the previous echo has gone out:
 * while it waits, the link rejects new messages (ls_isotp.h receiver policy),
 * which a request/response peer never sees. */
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hal/hal_can.h"
#include "hal_linux_socketcan.h"
#include "peer_ids.h"
#include "ls_isotp.h"


static volatile sig_atomic_t stop_requested;
static hal_can_link_t can_link;
static ls_isotp_link_t tp_link;
static uint8_t msg_buf[LS_ISOTP_MAX_PAYLOAD];

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
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
    return hal_can_send(&can_link, &f) == LS_OK ? 0 : -1;
}

/* Milliseconds poll() may sleep: until the link's next deadline, at most 100 ms
 * (so signals and the lifetime limit are seen promptly). */
static int sleep_ms(uint64_t now)
{
    uint64_t due = ls_isotp_next_deadline_us(&tp_link);
    if (due <= now) {
        return 0;
    }
    uint64_t ms = (due - now + 999u) / 1000u;
    return ms > 100u ? 100 : (int)ms;
}

static int parse_args(int argc, char **argv, const char **ifname, unsigned long *lifetime_s)
{
    if (argc != 2 && argc != 4) {
        return -1;
    }
    *ifname = argv[1];
    if (argc == 4) {
        char *end = NULL;
        if (strcmp(argv[2], "-t") != 0) {
            return -1;
        }
        *lifetime_s = strtoul(argv[3], &end, 10);
        if (end == argv[3] || *end != '\0' || *lifetime_s == 0) {
            return -1;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *ifname = NULL;
    unsigned long lifetime_s = 300;
    if (parse_args(argc, argv, &ifname, &lifetime_s) != 0) {
        fprintf(stderr, "usage: %s IFNAME [-t SECONDS]   (e.g. %s vcan0 -t 60)\n", argv[0], argv[0]);
        return 2;
    }
    char why[256] = "";
    int rc = hal_linux_socketcan_open(&can_link, ifname, why, sizeof(why));
    if (rc != LS_OK) {
        fprintf(stderr, "isotp_socketcan_echo: cannot open %s: %s (%s)\n", ifname, why, ls_err_text(rc));
        return 2;
    }
    if (ls_isotp_init(&tp_link, NULL, LS_PEER_TX_ID, LS_PEER_RX_ID, can_send, NULL) != LS_OK) {
        fprintf(stderr, "isotp_socketcan_echo: ls_isotp_init failed\n");
        hal_can_close(&can_link);
        return 2;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_signal; /* no SA_RESTART: poll() returns EINTR */
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    printf("ready %s\n", can_link.name);
    fflush(stdout);

    const uint64_t end_us = now_us() + (uint64_t)lifetime_s * 1000000u;
    unsigned echoed = 0;
    int exit_code = 0;
    struct pollfd pfd = { .fd = hal_can_poll_fd(&can_link), .events = POLLIN };
    while (!stop_requested) {
        uint64_t t = now_us();
        if (t >= end_us) {
            fprintf(stderr, "isotp_socketcan_echo: lifetime of %lu s over\n", lifetime_s);
            break;
        }
        if (poll(&pfd, 1, sleep_ms(t)) < 0 && errno != EINTR) {
            perror("isotp_socketcan_echo: poll");
            exit_code = 1;
            break;
        }
        t = now_us();
        hal_can_frame_t f;
        while ((rc = hal_can_recv(&can_link, &f)) == 1) {
            if (f.id == LS_PEER_RX_ID && (f.flags & HAL_CAN_F_EXT) != 0 && (f.flags & HAL_CAN_F_RTR) == 0) {
                ls_isotp_on_frame(&tp_link, f.data, f.len, t);
            }
        }
        if (rc != LS_EAGAIN) {
            fprintf(stderr, "isotp_socketcan_echo: link failed: %s\n", ls_err_text(rc));
            exit_code = 1;
            break;
        }
        ls_isotp_poll(&tp_link, t);
        if (!ls_isotp_tx_busy(&tp_link)) {
            size_t n = ls_isotp_take_rx(&tp_link, msg_buf, sizeof(msg_buf));
            if (n > 0 && ls_isotp_send(&tp_link, msg_buf, n, t) == LS_OK) {
                echoed++;
                printf("echo %zu\n", n);
                fflush(stdout);
            }
        }
    }
    fprintf(stderr, "isotp_socketcan_echo: echoed %u, rx ok %u, tx ok %u, last error %s\n", echoed,
            (unsigned)tp_link.rx_results[LS_ISOTP_N_OK], (unsigned)tp_link.tx_results[LS_ISOTP_N_OK],
            ls_isotp_result_name(tp_link.last_error));
    hal_can_close(&can_link);
    return exit_code;
}
