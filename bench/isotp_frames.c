/* bench_isotp_frames: frames on the bus per ISO-TP transfer, firmware stack.
 *
 * Two ls_isotp links back to back in memory (sender A, receiver B; virtual
 * time, no loss). For every length 1..4095 A sends one message to B; the
 * driver counts every CAN frame both directions put on the "bus" (SF/FF/CF
 * from A, FC from B) and checks that B got the payload intact.
 *
 * Usage: bench_isotp_frames BS
 * Output: one line per length, "<len> <frames>"; exit 1 when a transfer
 * fails or corrupts data (the figure would be meaningless). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "landscape.pb.h"
#include "ls_isotp.h"

/* A supervisor at the default host address and a device at the default
 * device address (protocol/landscape.proto). */
#define DEV ((uint32_t)ls_NodeAddress_DEFAULT_DEVICE_ADDRESS)
#define HOST ((uint32_t)ls_NodeAddress_DEFAULT_HOST_ADDRESS)
#define ID_A_TO_B ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE | DEV << 8 | HOST)
#define ID_B_TO_A ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE | HOST << 8 | DEV)
#define QUEUE_LEN 1024u

typedef struct {
    uint32_t id;
    uint8_t len;
    uint8_t data[8];
} frame_t;

static frame_t queue_[QUEUE_LEN];
static size_t q_head, q_tail;
static unsigned long frames_on_bus;
static ls_isotp_link_t link_a, link_b;
static uint8_t payload[LS_ISOTP_MAX_PAYLOAD], got[LS_ISOTP_MAX_PAYLOAD];

static int bus_send(void *ctx, uint32_t can_id, const uint8_t *data, uint8_t len)
{
    (void)ctx;
    if (q_tail - q_head >= QUEUE_LEN) {
        return LS_EAGAIN;
    }
    frame_t *f = &queue_[q_tail++ % QUEUE_LEN];
    f->id = can_id;
    f->len = len;
    memcpy(f->data, data, len);
    frames_on_bus++;
    return 0;
}

/* One transfer of `len` bytes; returns the frame count, or LS_EIO when it
 * failed or delivered other bytes. */
static long transfer(size_t len)
{
    for (size_t i = 0; i < len; i++) {
        payload[i] = (uint8_t)(i * 37u + len);
    }
    frames_on_bus = 0;
    q_head = q_tail = 0;
    uint64_t now_us = 1;
    const int rc = ls_isotp_send(&link_a, payload, len, now_us);
    if (rc != LS_OK) {
        return rc;
    }
    for (unsigned turn = 0; turn < 100000u; turn++) {
        while (q_head != q_tail) {
            frame_t f = queue_[q_head++ % QUEUE_LEN];
            ls_isotp_on_frame(f.id == ID_A_TO_B ? &link_b : &link_a, f.data, f.len, now_us);
        }
        size_t n = ls_isotp_take_rx(&link_b, got, sizeof got);
        if (n > 0) {
            return (n == len && memcmp(got, payload, len) == 0 && !ls_isotp_tx_busy(&link_a)) ? (long)frames_on_bus
                                                                                              : LS_EIO;
        }
        now_us += 10;
        ls_isotp_poll(&link_a, now_us);
        ls_isotp_poll(&link_b, now_us);
    }
    return LS_EIO;
}

int main(int argc, char **argv)
{
    char *end = NULL;
    unsigned long bs = argc == 2 ? strtoul(argv[1], &end, 0) : 256;
    if (argc != 2 || end == argv[1] || *end != '\0' || bs > 255) {
        fprintf(stderr, "usage: %s BS   (block size the receiver asks for, 0..255)\n", argv[0]);
        return 2;
    }
    ls_isotp_config_t cfg;
    ls_isotp_default_config(&cfg);
    cfg.block_size = (uint8_t)bs;
    if (ls_isotp_init(&link_a, &cfg, ID_A_TO_B, ID_B_TO_A, bus_send, NULL) != LS_OK ||
        ls_isotp_init(&link_b, &cfg, ID_B_TO_A, ID_A_TO_B, bus_send, NULL) != LS_OK) {
        fprintf(stderr, "bench_isotp_frames: link init failed\n");
        return 1;
    }
    for (size_t len = 1; len <= LS_ISOTP_MAX_PAYLOAD; len++) {
        long frames = transfer(len);
        if (frames < 0) {
            fprintf(stderr, "bench_isotp_frames: transfer of %zu bytes failed (%s)\n", len,
                    ls_isotp_result_name(link_b.last_error));
            return 1;
        }
        printf("%zu %ld\n", len, frames);
    }
    return 0;
}
