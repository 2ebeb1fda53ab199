/* The --link-faults spec parser (hal/sim/faulty_link.h): any bytes either
 * parse into a configuration the decorator accepts, or fail with a message
 * that names the problem. An accepted configuration then carries a few frames
 * through the decorator over a null link. */
#include <stdint.h>
#include <string.h>

#include "faulty_link.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint64_t g_now_us;
static uint64_t fake_now(void *self)
{
    (void)self;
    return g_now_us;
}

static int null_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    (void)f;
    return LS_OK;
}

static int null_recv(void *self, hal_can_frame_t *f)
{
    unsigned *n = self;
    if (*n == 0) {
        return LS_EAGAIN;
    }
    (*n)--;
    memset(f, 0, sizeof *f);
    f->len = 8;
    return 1;
}

static const hal_can_ops_t null_ops = { .send = null_send, .recv = null_recv };

static int valid_rates(const hal_sim_fault_rates_t *r)
{
    return r->drop >= 0 && r->drop <= 1 && r->dup >= 0 && r->dup <= 1 && r->corrupt >= 0 && r->corrupt <= 1 &&
           r->reorder >= 0 && r->reorder <= 1 && r->delay >= 0 && r->delay <= 1 && (r->delay == 0 || r->delay_us > 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char spec[4096];
    if (size >= sizeof spec) {
        return 0;
    }
    memcpy(spec, data, size);
    spec[size] = '\0';
    hal_sim_fault_config_t cfg;
    char msg[200];
    int r = hal_sim_fault_parse(spec, &cfg, msg, sizeof msg);
    if (r != LS_OK) {
        if (r != LS_EINVAL || msg[0] == '\0' || strlen(msg) >= sizeof msg) {
            __builtin_trap();
        }
        return 0;
    }
    if (!valid_rates(&cfg.tx) || !valid_rates(&cfg.rx) ||
        (cfg.busoff_every_us != 0 && cfg.busoff_for_us >= cfg.busoff_every_us)) {
        __builtin_trap();
    }
    cfg.clock = (hal_clock_t){ .now_us = fake_now, .self = NULL };
    unsigned pending = 64;
    hal_can_link_t inner = { .ops = &null_ops, .self = &pending, .name = "null" };
    hal_can_link_t link;
    g_now_us = 0;
    if (hal_sim_faulty_wrap(&link, &inner, &cfg) != LS_OK) {
        __builtin_trap(); /* everything the parser accepts, the decorator must too */
    }
    hal_can_frame_t f = { .id = 1, .len = 8 };
    for (int i = 0; i < 64; i++) {
        (void)hal_can_send(&link, &f);
        (void)hal_can_recv(&link, &f);
        g_now_us += 1000;
    }
    hal_can_close(&link);
    return 0;
}
