/* Bus bytes all the way in: CAN frames -> routing -> ISO-TP -> protobuf
 * decode -> dispatch -> handlers -> encode -> ISO-TP out. The input is a
 * sequence of records: [id selector][len][8 data bytes][time step]. */
#include <stdint.h>
#include <string.h>

#include "ls_core.h"
#include "ls_net.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static ls_core_t g_core;
static ls_net_t g_net;

/* A link that feeds the fuzzer's frames and swallows what the device sends. */
typedef struct {
    const uint8_t *p;
    size_t n;
} feed_t;
static feed_t g_feed;
static uint64_t g_now;

/* Ids from the schema and the DBC (ls_net.h): the device 0x10 from three hosts,
 * a functional request, a heartbeat, an emergency, another device, telemetry. */
#define FZ_PHYS(target, source) (LS_ID_ISOTP_PHYS | (uint32_t)(target) << 8 | (uint32_t)(source))
static const uint32_t ids[] = {
    FZ_PHYS(0x10u, 0xF1u),
    FZ_PHYS(0x10u, 0xF2u),
    LS_ID_ISOTP_FUNC | LS_ADDR_ALL << 8 | 0xF1u,
    LS_ID_HEARTBEAT | 0xF1u,
    LS_ID_EMERGENCY | 0xF1u,
    FZ_PHYS(0x11u, 0xF1u),
    LS_ID_OF_DBC(LANDSCAPE_STATUS_FRAME_ID) | 0x10u,
    FZ_PHYS(0x10u, 0xF3u),
};

static int feed_recv(void *self, hal_can_frame_t *f)
{
    feed_t *fd = self;
    if (fd->n < 11) {
        return LS_EAGAIN;
    }
    memset(f, 0, sizeof *f);
    f->id = ids[fd->p[0] % (sizeof ids / sizeof ids[0])];
    f->flags = (fd->p[0] & 0x80u) != 0u ? 0u : HAL_CAN_F_EXT;
    f->len = (uint8_t)(fd->p[1] % 9u);
    memcpy(f->data, fd->p + 2, 8);
    g_now += (uint64_t)fd->p[10] * 997u; /* up to ~250 ms per frame: timeouts get exercised */
    fd->p += 11;
    fd->n -= 11;
    return 1;
}

static int feed_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    if (f->len > 8) {
        __builtin_trap();
    }
    return LS_OK;
}

static const hal_can_ops_t feed_ops = { .send = feed_send, .recv = feed_recv };

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ls_core_config_t cfg = { .device_name = "fuzz",
                             .firmware_version = "0",
                             .node_addr = 0x10,
                             .joint_count = 6,
                             .heartbeat_timeout_ms = 1000 };
    ls_core_io_t io = { .send_downlink = ls_net_send_downlink, .ctx = &g_net };
    ls_core_init(&g_core, &cfg, &io, NULL);
    ls_net_init(&g_net, 0x10, &g_core);
    g_feed.p = data;
    g_feed.n = size;
    g_now = 1000000;
    hal_can_link_t link = { .ops = &feed_ops, .self = &g_feed, .name = "fuzz" };
    (void)ls_net_add_link(&g_net, &link);
    while (g_feed.n >= 11) {
        ls_net_poll(&g_net, g_now);
        ls_core_tick(&g_core, g_now);
        g_now += 100;
    }
    for (int i = 0; i < 50; i++) { /* let pending transfers run out */
        g_now += 10000;
        ls_net_poll(&g_net, g_now);
        ls_core_tick(&g_core, g_now);
    }
    if (g_core.owner >= LS_MAX_SUPERVISORS || (g_core.owner >= 0 && !g_core.sessions[g_core.owner].connected)) {
        __builtin_trap(); /* an owner must be a live session */
    }
    return 0;
}
