/* The unit tests' CAN bus: captures every frame the code under test sends,
 * and refuses sends on demand (a full CAN queue). Frames the tests expect
 * or feed are built here from the CiA 301 constants of ls_canopen.h, never
 * by the code under test. Header-only: each test includes it once. */
#ifndef CO_TEST_BUS_H
#define CO_TEST_BUS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "hal/hal_can.h"
#include "ls_canopen.h"
#include "ls_co_master.h"
#include "ls_err.h"

#define BUS_CAP 4096u
#define NODE_HB_MS 50u          /* the tests' nodes beat at this period ... */
#define NODE_HB_TIMEOUT_MS 150u /* ... and the master gives up after this */

typedef struct {
    hal_can_frame_t f[BUS_CAP];
    size_t n;        /* frames taken */
    size_t seen;     /* frames a test has consumed with bus_take */
    int refuse;      /* refuse this many next sends */
    bool refuse_all; /* refuse every send */
    bool limited;    /* take only `room` more frames, then refuse */
    size_t room;
    size_t refused;
} bus_t;

static inline int bus_send(void *ctx, const hal_can_frame_t *f)
{
    bus_t *b = ctx;
    if (b->refuse_all || b->refuse > 0 || (b->limited && b->room == 0u)) {
        if (b->refuse > 0) {
            b->refuse--;
        }
        b->refused++;
        return LS_EAGAIN;
    }
    if (b->n >= BUS_CAP) {
        return LS_EAGAIN;
    }
    if (b->limited) {
        b->room--;
    }
    b->f[b->n++] = *f;
    return LS_OK;
}

static inline void bus_reset(bus_t *b)
{
    memset(b, 0, sizeof(*b));
}

/* The next frame not yet consumed, or NULL. */
static inline const hal_can_frame_t *bus_take(bus_t *b)
{
    return b->seen < b->n ? &b->f[b->seen++] : NULL;
}

static inline size_t bus_pending(const bus_t *b)
{
    return b->n - b->seen;
}

static inline hal_can_frame_t can_frame(uint32_t id, uint8_t len, const uint8_t *data)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof(f));
    f.id = id;
    f.len = len;
    if (data != NULL) { /* NULL: zeros */
        memcpy(f.data, data, len < 8u ? len : 8u);
    }
    return f;
}

/* An SDO frame: command byte, multiplexer, four data bytes. */
static inline hal_can_frame_t sdo_mux(uint32_t id, uint8_t cmd, uint16_t index, uint8_t sub, const uint8_t d4[4])
{
    uint8_t b[8] = { cmd, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0 };
    if (d4 != NULL) {
        memcpy(&b[4], d4, 4);
    }
    return can_frame(id, 8, b);
}

/* An SDO segment: command byte and seven data bytes. */
static inline hal_can_frame_t sdo_seg(uint32_t id, uint8_t cmd, const uint8_t *d, size_t n)
{
    uint8_t b[8] = { cmd, 0, 0, 0, 0, 0, 0, 0 };
    if (n > 0u) {
        memcpy(&b[1], d, n);
    }
    return can_frame(id, 8, b);
}

static inline void le32(uint8_t out[4], uint32_t v)
{
    out[0] = (uint8_t)v;
    out[1] = (uint8_t)(v >> 8);
    out[2] = (uint8_t)(v >> 16);
    out[3] = (uint8_t)(v >> 24);
}

static inline uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline bool frame_eq(const hal_can_frame_t *a, const hal_can_frame_t *b)
{
    return a != NULL && b != NULL && a->id == b->id && a->len == b->len && a->flags == b->flags &&
           memcmp(a->data, b->data, a->len) == 0;
}

/* A node as the tests configure it: its id and script, heartbeat
 * NODE_HB_MS watched with NODE_HB_TIMEOUT_MS, RPDO1 and TPDO1 of 6 bytes
 * at their predefined COB-IDs. */
static inline void co_test_node(ls_co_node_config_t *nc, uint8_t id, const ls_co_step_t *script, size_t script_len)
{
    memset(nc, 0, sizeof(*nc));
    nc->node_id = id;
    nc->heartbeat_ms = NODE_HB_MS;
    nc->heartbeat_timeout_ms = NODE_HB_TIMEOUT_MS;
    nc->script = script;
    nc->script_len = script_len;
    nc->rpdo[0].cob_id = (uint16_t)LS_CO_COB_RPDO(1, id);
    nc->rpdo[0].len = 6;
    nc->tpdo[0].cob_id = (uint16_t)LS_CO_COB_TPDO(1, id);
    nc->tpdo[0].len = 6;
}

#endif
