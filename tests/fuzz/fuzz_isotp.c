/* libFuzzer target for the ISO-TP transport.
 *
 * The input is a sequence of records, each starting with an op byte:
 *   op & 7 in 0..3  frame for the receiving link:  dt, len, len bytes
 *   op & 7 == 4     frame for the sending link:    dt, len, len bytes
 *   op & 7 == 5     send request on the sending link: 2 length bytes (any value,
 *                   so 0 and > 4095 are exercised too)
 *   op & 7 == 6     deliver what each link queued to the other (back to back)
 *   op & 7 == 7     time jump: 3 bytes of microseconds, then poll both links
 *   op & 8          the CAN queue is full for this record's sends
 *   op & 0x10       take_rx on both links with cap = next byte * 17
 * dt is one byte, squared microseconds, so both STmin-sized steps and
 * timeout-sized jumps occur. `len` may exceed 8 to test the length check.
 *
 * Invariants (abort on violation): rx_got <= rx_len <= 4095, tx_off <= tx_len
 * <= 4095, every emitted frame has 1..8 bytes, take_rx never returns more than
 * cap and returns exactly the held length, time handed in never goes back. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../unit/isotp/peer_ids.h"
#include "ls_isotp.h"

#define QCAP 64u

typedef struct {
    uint8_t d[QCAP][8];
    uint8_t len[QCAP];
    size_t n;
    int full;
} fz_queue_t;

static ls_isotp_link_t rx_link, tx_link;
static fz_queue_t rx_q, tx_q; /* frames queued by rx_link / tx_link */
static uint8_t payload[LS_ISOTP_MAX_PAYLOAD + 16];
static uint8_t out[LS_ISOTP_MAX_PAYLOAD + 16];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int fz_send(void *ctx, uint32_t can_id, const uint8_t *d, uint8_t len)
{
    fz_queue_t *q = ctx;
    (void)can_id;
    if (len < 1 || len > 8 || d == NULL) {
        abort();
    }
    if (q->full || q->n >= QCAP) {
        return -1;
    }
    memcpy(q->d[q->n], d, len);
    q->len[q->n] = len;
    q->n++;
    return 0;
}

static void check(const ls_isotp_link_t *l)
{
    if (l->rx_len > LS_ISOTP_MAX_PAYLOAD || l->tx_len > LS_ISOTP_MAX_PAYLOAD) {
        abort();
    }
    if (l->rx_state != LS_ISOTP_RX_IDLE && l->rx_got > l->rx_len) {
        abort();
    }
    if (l->tx_state != LS_ISOTP_TX_IDLE && l->tx_off > l->tx_len) {
        abort();
    }
    if (l->last_error >= LS_ISOTP_N_RESULT_COUNT) {
        abort();
    }
}

/* Before its next deadline a poll must be a no-op: this is what lets the
 * caller sleep until ls_isotp_next_deadline_us. */
static void check_deadline(ls_isotp_link_t *l, fz_queue_t *q, uint64_t now_us)
{
    uint64_t d = ls_isotp_next_deadline_us(l);
    if (d <= now_us || q->full) {
        return;
    }
    size_t n = q->n;
    ls_isotp_rx_state_t rs = l->rx_state;
    ls_isotp_tx_state_t ts = l->tx_state;
    uint16_t off = l->tx_off;
    ls_isotp_poll(l, now_us);
    if (q->n != n || l->rx_state != rs || l->tx_state != ts || l->tx_off != off) {
        abort();
    }
}

static void take(ls_isotp_link_t *l, size_t cap)
{
    bool done = l->rx_state == LS_ISOTP_RX_DONE;
    size_t held = l->rx_len;
    memset(out, 0xA5, sizeof(out));
    size_t n = ls_isotp_take_rx(l, out, cap);
    if (n > cap || (n > 0 && (!done || n != held)) || (done && cap >= held && n != held)) {
        abort();
    }
    for (size_t i = cap; i < sizeof(out) && i < cap + 16; i++) {
        if (out[i] != 0xA5) { /* nothing written beyond cap */
            abort();
        }
    }
}

static void deliver(fz_queue_t *from, ls_isotp_link_t *to, uint64_t now_us)
{
    size_t n = from->n;
    from->n = 0;
    for (size_t i = 0; i < n; i++) {
        ls_isotp_on_frame(to, from->d[i], from->len[i], now_us);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ls_isotp_config_t cfg;
    ls_isotp_default_config(&cfg);
    size_t p = 0;
    /* The first bytes pick the receiver's BS/STmin/padding and wft_max. */
    if (size >= 3) {
        cfg.block_size = data[0] & 0x0Fu;
        cfg.st_min = (data[1] & 0x80u) ? (uint8_t)(0xF1u + (data[1] % 9u)) : (uint8_t)(data[1] & 0x03u);
        cfg.tx_padding = (data[2] & 1u) != 0;
        cfg.wft_max = (uint8_t)(data[2] >> 5);
        p = 3;
    }
    memset(&rx_q, 0, sizeof(rx_q));
    memset(&tx_q, 0, sizeof(tx_q));
    if (ls_isotp_init(&rx_link, &cfg, LS_PEER_TX_ID, LS_PEER_RX_ID, fz_send, &rx_q) != LS_OK ||
        ls_isotp_init(&tx_link, &cfg, LS_PEER_RX_ID, LS_PEER_TX_ID, fz_send, &tx_q) != LS_OK) {
        abort();
    }
    for (size_t i = 0; i < sizeof(payload); i++) {
        payload[i] = (uint8_t)(i * 7u);
    }
    uint64_t now_us = 0;

    while (p < size) {
        uint8_t op = data[p++];
        rx_q.full = tx_q.full = (op & 8u) != 0;
        switch (op & 7u) {
        case 0:
        case 1:
        case 2:
        case 3:
        case 4: {
            if (p + 2 > size) {
                return 0;
            }
            now_us += (uint64_t)data[p] * data[p];
            uint8_t len = data[p + 1] & 0x0Fu;
            p += 2;
            size_t avail = size - p;
            uint8_t frame[16] = { 0 };
            size_t take_n = len < avail ? len : avail;
            memcpy(frame, data + p, take_n);
            p += take_n;
            ls_isotp_link_t *l = (op & 7u) == 4u ? &tx_link : &rx_link;
            ls_isotp_on_frame(l, frame, len, now_us);
            uint8_t sf[7];
            size_t sf_cap = data[p - 1 - take_n] % 8u; /* any cap 0..7 */
            size_t sf_n = ls_isotp_decode_single(frame, len, sf, sf_cap);
            if (sf_n > sf_cap || sf_n > 7 || (sf_n > 0 && (len > 8 || sf_n != (frame[0] & 0x0Fu)))) {
                abort();
            }
            break;
        }
        case 5: {
            if (p + 2 > size) {
                return 0;
            }
            size_t len = ((size_t)data[p] << 8 | data[p + 1]) & 0x1FFFu;
            p += 2;
            bool busy = ls_isotp_tx_busy(&tx_link);
            int rc = ls_isotp_send(&tx_link, payload, len, now_us);
            int want = (len == 0 || len > LS_ISOTP_MAX_PAYLOAD) ? LS_ELEN : busy ? LS_EBUSY : LS_OK;
            if (rc != want) {
                abort();
            }
            break;
        }
        case 6:
            deliver(&tx_q, &rx_link, now_us);
            deliver(&rx_q, &tx_link, now_us);
            break;
        default: {
            if (p + 3 > size) {
                return 0;
            }
            now_us += (uint64_t)data[p] << 16 | (uint64_t)data[p + 1] << 8 | data[p + 2];
            p += 3;
            ls_isotp_poll(&rx_link, now_us);
            ls_isotp_poll(&tx_link, now_us);
            break;
        }
        }
        if ((op & 0x10u) != 0 && p < size) {
            size_t cap = (size_t)data[p++] * 17u;
            take(&rx_link, cap);
            take(&tx_link, cap);
        }
        check(&rx_link);
        check(&tx_link);
        check_deadline(&rx_link, &rx_q, now_us);
        check_deadline(&tx_link, &tx_q, now_us);
        if (!rx_q.full && rx_q.n == QCAP) {
            rx_q.n = 0;
        }
        if (!tx_q.full && tx_q.n == QCAP) {
            tx_q.n = 0;
        }
    }
    /* Drain: back to back, every transfer must end (complete or time out). */
    /* 10 ms steps: the slowest legal transfer (585 CFs at STmin 127 ms) ends
     * within ~7500 steps, and N_Bs/N_Cr (1 s) within 100. */
    for (int i = 0; i < 20000 && (ls_isotp_tx_busy(&tx_link) || rx_link.rx_state == LS_ISOTP_RX_RECEIVING); i++) {
        rx_q.full = tx_q.full = 0;
        now_us += 10000;
        deliver(&tx_q, &rx_link, now_us);
        deliver(&rx_q, &tx_link, now_us);
        ls_isotp_poll(&rx_link, now_us);
        ls_isotp_poll(&tx_link, now_us);
        take(&rx_link, sizeof(out));
        check(&rx_link);
        check(&tx_link);
    }
    if (ls_isotp_tx_busy(&tx_link) || rx_link.rx_state == LS_ISOTP_RX_RECEIVING) {
        abort(); /* a transfer that never ends would hang the firmware's link */
    }
    return 0;
}
