/* bench_frame_echo: the floor of a command round trip on the SLCAN pty.
 * Answers every CAN frame at once with the same frame, id unchanged apart
 * from swapping the two address bytes of a normal-fixed 29-bit ISO-TP id
 * (base|<device><host> -> base|<host><device>), so a host stack sees a single-frame answer
 * from the device. No ISO-TP, no protocol: just the link both ways.
 * Usage: bench_frame_echo PATH; runs until SIGTERM/SIGINT. */
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>

#include "hal/hal_can.h"
#include "landscape.pb.h"

#define PHYS ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE)
#define PF_MASK 0xFFFF0000u /* the id without its target and source bytes */
#include "slcan_pty.h"

static volatile sig_atomic_t stop_;

static void on_signal(int sig)
{
    (void)sig;
    stop_ = 1;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s PATH\n", argv[0]);
        return 2;
    }
    hal_can_link_t can;
    char msg[256];
    if (hal_sim_slcan_pty_open(&can, argv[1], msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "bench_frame_echo: %s\n", msg);
        return 1;
    }
    signal(SIGTERM, on_signal);
    signal(SIGINT, on_signal);
    struct pollfd pfd = { .fd = hal_can_poll_fd(&can), .events = POLLIN };
    unsigned long echoed = 0;
    while (!stop_) {
        if (poll(&pfd, 1, 100) < 0 && errno != EINTR) {
            break;
        }
        hal_can_frame_t f;
        int r;
        while ((r = hal_can_recv(&can, &f)) == 1) {
            if ((f.flags & HAL_CAN_F_EXT) != 0 && (f.id & PF_MASK) == PHYS) {
                f.id = PHYS | ((f.id & 0xFFu) << 8) | ((f.id >> 8) & 0xFFu);
            }
            if (hal_can_send(&can, &f) == LS_OK) {
                echoed++;
            }
        }
        if (r != LS_EAGAIN) {
            fprintf(stderr, "bench_frame_echo: link failed: %s\n", ls_err_text(r));
            break;
        }
    }
    fprintf(stderr, "bench_frame_echo: %lu frames echoed\n", echoed);
    hal_can_close(&can);
    return 0;
}
