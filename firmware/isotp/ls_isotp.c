/* ISO 15765-2 transport for classic CAN: see ls_isotp.h for the contract.
 *
 * The transmitter keeps "first frame not yet queued" as TX_SENDING with
 * tx_off == 0, so a full CAN queue at ls_isotp_send time needs no extra state:
 * the pump retries the SF/FF exactly like a CF. */
#include "ls_isotp.h"

#include <string.h>

enum {
    PCI_SF = 0x0,
    PCI_FF = 0x1,
    PCI_CF = 0x2,
    PCI_FC = 0x3,
};

enum {
    FS_CTS = 0x0,
    FS_WAIT = 0x1,
    FS_OVFLW = 0x2,
};

#define CAN_DL 8u
#define SF_MAX 7u
#define FF_DATA 6u
#define CF_DATA 7u
#define FC_LEN 3u

/* Deadlines are far-future timestamps; saturate so a caller's clock near the
 * end of uint64 cannot wrap a deadline into the past. */
static uint64_t add_sat(uint64_t now_us, uint32_t dt_us)
{
    return (now_us > UINT64_MAX - dt_us) ? UINT64_MAX : now_us + dt_us;
}

static void count_rx(ls_isotp_link_t *l, ls_isotp_result_t r)
{
    l->rx_results[r]++;
    if (r != LS_ISOTP_N_OK) {
        l->last_error = r;
    }
}

static void count_tx(ls_isotp_link_t *l, ls_isotp_result_t r)
{
    l->tx_results[r]++;
    if (r != LS_ISOTP_N_OK) {
        l->last_error = r;
    }
}

/* Pads (or not) and hands one frame to the CAN queue. `used` bytes of `f` are
 * valid; the rest is filled here when padding. */
static int emit(ls_isotp_link_t *l, uint8_t f[CAN_DL], uint8_t used)
{
    uint8_t len = used;
    if (l->cfg.tx_padding) {
        memset(f + used, l->cfg.padding_byte, CAN_DL - used);
        len = CAN_DL;
    }
    return l->send(l->send_ctx, l->tx_id, f, len);
}

static bool send_fc(ls_isotp_link_t *l, uint8_t fs)
{
    uint8_t f[CAN_DL];
    f[0] = (uint8_t)((PCI_FC << 4) | fs);
    f[1] = l->cfg.block_size;
    f[2] = l->cfg.st_min;
    return emit(l, f, FC_LEN) >= 0;
}

/* Queue a flow control now, or remember it for the next poll when the CAN
 * queue is full. A newer FC replaces an older unsent one: only the latest
 * state of the receiver matters to the peer. */
static void queue_fc(ls_isotp_link_t *l, uint8_t fs, uint64_t now_us)
{
    if (send_fc(l, fs)) {
        l->rx_fc_pending = false;
        if (fs == FS_CTS) {
            l->rx_deadline_us = add_sat(now_us, l->cfg.n_cr_timeout_us);
        }
    } else {
        l->rx_fc_pending = true;
        l->rx_fc_status = fs;
    }
}

static bool stmin_valid(uint8_t st_min)
{
    return st_min <= 0x7Fu || (st_min >= 0xF1u && st_min <= 0xF9u);
}

uint32_t ls_isotp_stmin_to_us(uint8_t st_min)
{
    if (st_min <= 0x7Fu) {
        return (uint32_t)st_min * 1000u;
    }
    if (st_min >= 0xF1u && st_min <= 0xF9u) {
        return (uint32_t)(st_min - 0xF0u) * 100u;
    }
    return 127000u;
}

void ls_isotp_default_config(ls_isotp_config_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    cfg->block_size = LS_ISOTP_DEFAULT_BS;
    cfg->st_min = LS_ISOTP_DEFAULT_ST_MIN;
    cfg->tx_padding = true;
    cfg->padding_byte = LS_ISOTP_DEFAULT_PADDING_BYTE;
    cfg->n_bs_timeout_us = LS_ISOTP_DEFAULT_N_TIMEOUT_US;
    cfg->n_cr_timeout_us = LS_ISOTP_DEFAULT_N_TIMEOUT_US;
    cfg->wft_max = 10;
}

int ls_isotp_init(ls_isotp_link_t *l, const ls_isotp_config_t *cfg, uint32_t tx_id, uint32_t rx_id,
                  ls_isotp_send_fn send, void *send_ctx)
{
    if (l == NULL || send == NULL) {
        return LS_EINVAL;
    }
    ls_isotp_config_t c;
    if (cfg != NULL) {
        c = *cfg;
    } else {
        ls_isotp_default_config(&c);
    }
    if (!stmin_valid(c.st_min) || c.n_bs_timeout_us == 0 || c.n_cr_timeout_us == 0) {
        return LS_EINVAL;
    }
    memset(l, 0, sizeof(*l));
    l->cfg = c;
    l->tx_id = tx_id;
    l->rx_id = rx_id;
    l->send = send;
    l->send_ctx = send_ctx;
    l->rx_state = LS_ISOTP_RX_IDLE;
    l->tx_state = LS_ISOTP_TX_IDLE;
    l->last_error = LS_ISOTP_N_OK;
    return LS_OK;
}

/* ---- transmitter ------------------------------------------------------- */

static void tx_finish(ls_isotp_link_t *l, ls_isotp_result_t r)
{
    count_tx(l, r);
    l->tx_state = LS_ISOTP_TX_IDLE;
}

/* Queue every frame that is due: the SF/FF if not yet out, then CFs as STmin
 * and BS allow. Stops at the first refusal of the CAN queue; the same frame is
 * rebuilt and retried on the next call. */
static void tx_pump(ls_isotp_link_t *l, uint64_t now_us)
{
    uint8_t f[CAN_DL];
    while (l->tx_state == LS_ISOTP_TX_SENDING && now_us >= l->tx_next_us) {
        if (l->tx_off == 0) {
            if (l->tx_len <= SF_MAX) {
                f[0] = (uint8_t)l->tx_len;
                memcpy(f + 1, l->tx_buf, l->tx_len);
                if (emit(l, f, (uint8_t)(1u + l->tx_len)) < 0) {
                    return;
                }
                tx_finish(l, LS_ISOTP_N_OK);
                return;
            }
            f[0] = (uint8_t)((PCI_FF << 4) | (l->tx_len >> 8));
            f[1] = (uint8_t)(l->tx_len & 0xFFu);
            memcpy(f + 2, l->tx_buf, FF_DATA);
            if (emit(l, f, CAN_DL) < 0) {
                return;
            }
            l->tx_off = FF_DATA;
            l->tx_sn = 1;
            l->tx_wft = 0;
            l->tx_state = LS_ISOTP_TX_WAIT_FC;
            l->tx_deadline_us = add_sat(now_us, l->cfg.n_bs_timeout_us);
            return;
        }
        uint16_t left = (uint16_t)(l->tx_len - l->tx_off);
        uint8_t n = (uint8_t)(left < CF_DATA ? left : CF_DATA);
        f[0] = (uint8_t)((PCI_CF << 4) | l->tx_sn);
        memcpy(f + 1, l->tx_buf + l->tx_off, n);
        if (emit(l, f, (uint8_t)(1u + n)) < 0) {
            return;
        }
        l->tx_off = (uint16_t)(l->tx_off + n);
        l->tx_sn = (uint8_t)((l->tx_sn + 1u) & 0x0Fu);
        if (l->tx_off >= l->tx_len) {
            tx_finish(l, LS_ISOTP_N_OK);
            return;
        }
        l->tx_next_us = add_sat(now_us, l->tx_stmin_us);
        if (l->tx_bs != 0 && --l->tx_bs_left == 0) {
            l->tx_state = LS_ISOTP_TX_WAIT_FC;
            l->tx_deadline_us = add_sat(now_us, l->cfg.n_bs_timeout_us);
            return;
        }
    }
}

static void on_fc(ls_isotp_link_t *l, const uint8_t *d, uint8_t len, uint64_t now_us)
{
    if (l->tx_state != LS_ISOTP_TX_WAIT_FC) {
        count_tx(l, LS_ISOTP_N_UNEXP_PDU);
        return;
    }
    if (len < FC_LEN) {
        count_tx(l, LS_ISOTP_N_MALFORMED);
        return;
    }
    switch (d[0] & 0x0Fu) {
    case FS_CTS:
        l->tx_bs = d[1];
        l->tx_bs_left = d[1];
        l->tx_stmin_us = ls_isotp_stmin_to_us(d[2]);
        l->tx_wft = 0;
        l->tx_state = LS_ISOTP_TX_SENDING;
        /* The first CF of a block may go at once; STmin separates CFs. */
        l->tx_next_us = now_us;
        tx_pump(l, now_us);
        break;
    case FS_WAIT:
        if (++l->tx_wft > l->cfg.wft_max) {
            tx_finish(l, LS_ISOTP_N_WFT_OVRN);
        } else {
            l->tx_deadline_us = add_sat(now_us, l->cfg.n_bs_timeout_us);
        }
        break;
    case FS_OVFLW: tx_finish(l, LS_ISOTP_N_BUFFER_OVFLW); break;
    default: tx_finish(l, LS_ISOTP_N_INVALID_FS); break;
    }
}

static void tx_start(ls_isotp_link_t *l, uint64_t now_us);

int ls_isotp_send(ls_isotp_link_t *l, const uint8_t *payload, size_t len, uint64_t now_us)
{
    if (l == NULL || payload == NULL) {
        return LS_EINVAL;
    }
    if (len == 0 || len > LS_ISOTP_MAX_PAYLOAD) {
        return LS_ELEN;
    }
    if (l->tx_state != LS_ISOTP_TX_IDLE) {
        return LS_EBUSY;
    }
    memcpy(l->tx_buf, payload, len);
    l->tx_len = (uint16_t)len;
    tx_start(l, now_us);
    return LS_OK;
}

int ls_isotp_resend(ls_isotp_link_t *l, uint64_t now_us)
{
    if (l == NULL || l->tx_len == 0) {
        return LS_EINVAL;
    }
    if (l->tx_state != LS_ISOTP_TX_IDLE) {
        return LS_EBUSY;
    }
    tx_start(l, now_us);
    return LS_OK;
}

int ls_isotp_restart_waiting(ls_isotp_link_t *l, uint64_t now_us)
{
    if (l == NULL || l->tx_len == 0 || l->tx_state == LS_ISOTP_TX_IDLE) {
        return LS_EINVAL;
    }
    if (l->tx_state != LS_ISOTP_TX_WAIT_FC) {
        return LS_EBUSY;
    }
    tx_start(l, now_us);
    return LS_OK;
}

/* Begin the transfer of the tx_len bytes in tx_buf from the first frame. */
static void tx_start(ls_isotp_link_t *l, uint64_t now_us)
{
    l->tx_off = 0;
    l->tx_sn = 0;
    l->tx_bs = 0;
    l->tx_bs_left = 0;
    l->tx_wft = 0;
    l->tx_stmin_us = 0;
    l->tx_next_us = now_us;
    l->tx_state = LS_ISOTP_TX_SENDING;
    tx_pump(l, now_us);
}

bool ls_isotp_tx_busy(const ls_isotp_link_t *l)
{
    return l != NULL && l->tx_state != LS_ISOTP_TX_IDLE;
}

/* ---- receiver ---------------------------------------------------------- */

/* An aborted reception must not leave a CTS for it in the FC retry slot. */
static void rx_abort(ls_isotp_link_t *l, ls_isotp_result_t r)
{
    count_rx(l, r);
    l->rx_state = LS_ISOTP_RX_IDLE;
    l->rx_fc_pending = false;
}

/* A new SF/FF that is well formed: decide whether it may start a reception. */
static bool rx_may_start(ls_isotp_link_t *l)
{
    if (l->rx_state == LS_ISOTP_RX_DONE) {
        count_rx(l, LS_ISOTP_N_BUFFER_OVFLW);
        return false;
    }
    if (l->rx_state == LS_ISOTP_RX_RECEIVING) {
        rx_abort(l, LS_ISOTP_N_UNEXP_PDU);
    }
    return true;
}

static void on_sf(ls_isotp_link_t *l, const uint8_t *d, uint8_t len)
{
    uint8_t n = d[0] & 0x0Fu;
    if (n == 0 || n > SF_MAX || len < 1u + n) {
        count_rx(l, LS_ISOTP_N_MALFORMED);
        return;
    }
    if (!rx_may_start(l)) {
        return;
    }
    memcpy(l->rx_buf, d + 1, n);
    l->rx_len = n;
    l->rx_got = n;
    l->rx_state = LS_ISOTP_RX_DONE;
    count_rx(l, LS_ISOTP_N_OK);
}

static void on_ff(ls_isotp_link_t *l, const uint8_t *d, uint8_t len, uint64_t now_us)
{
    if (len < CAN_DL) {
        count_rx(l, LS_ISOTP_N_MALFORMED);
        return;
    }
    uint32_t msg_len = ((uint32_t)(d[0] & 0x0Fu) << 8) | d[1];
    /* 0 is the 32-bit escape (ISO 15765-2:2016); lengths 1..7 belong in a SF. */
    if (msg_len != 0 && msg_len <= SF_MAX) {
        count_rx(l, LS_ISOTP_N_MALFORMED);
        return;
    }
    if (l->rx_state == LS_ISOTP_RX_DONE) {
        /* Tell the sender at once instead of letting it wait out N_Bs. */
        count_rx(l, LS_ISOTP_N_BUFFER_OVFLW);
        queue_fc(l, FS_OVFLW, now_us);
        return;
    }
    if (l->rx_state == LS_ISOTP_RX_RECEIVING) {
        rx_abort(l, LS_ISOTP_N_UNEXP_PDU);
    }
    if (msg_len == 0 || msg_len > LS_ISOTP_MAX_PAYLOAD) {
        count_rx(l, LS_ISOTP_N_BUFFER_OVFLW);
        queue_fc(l, FS_OVFLW, now_us);
        return;
    }
    memcpy(l->rx_buf, d + 2, FF_DATA);
    l->rx_len = (uint16_t)msg_len;
    const uint64_t cap_us = ls_isotp_rx_cap_us(&l->cfg, l->rx_len);
    l->rx_end_us = now_us > UINT64_MAX - cap_us ? UINT64_MAX : now_us + cap_us;
    l->rx_got = FF_DATA;
    l->rx_sn = 1;
    l->rx_bs_left = l->cfg.block_size;
    l->rx_state = LS_ISOTP_RX_RECEIVING;
    l->rx_deadline_us = add_sat(now_us, l->cfg.n_cr_timeout_us);
    queue_fc(l, FS_CTS, now_us);
}

static void on_cf(ls_isotp_link_t *l, const uint8_t *d, uint8_t len, uint64_t now_us)
{
    if (l->rx_state != LS_ISOTP_RX_RECEIVING) {
        count_rx(l, LS_ISOTP_N_UNEXP_PDU);
        return;
    }
    uint16_t left = (uint16_t)(l->rx_len - l->rx_got);
    uint8_t n = (uint8_t)(left < CF_DATA ? left : CF_DATA);
    if (len < 1u + n) {
        /* ISO 15765-2 says ignore a too-short CF; N_Cr still runs. */
        count_rx(l, LS_ISOTP_N_MALFORMED);
        return;
    }
    if ((d[0] & 0x0Fu) != l->rx_sn) {
        rx_abort(l, LS_ISOTP_N_WRONG_SN);
        return;
    }
    memcpy(l->rx_buf + l->rx_got, d + 1, n);
    l->rx_got = (uint16_t)(l->rx_got + n);
    l->rx_sn = (uint8_t)((l->rx_sn + 1u) & 0x0Fu);
    if (l->rx_got >= l->rx_len) {
        l->rx_state = LS_ISOTP_RX_DONE;
        count_rx(l, LS_ISOTP_N_OK);
        return;
    }
    l->rx_deadline_us = add_sat(now_us, l->cfg.n_cr_timeout_us);
    if (l->cfg.block_size != 0 && --l->rx_bs_left == 0) {
        l->rx_bs_left = l->cfg.block_size;
        queue_fc(l, FS_CTS, now_us);
    }
}

static void expire(ls_isotp_link_t *l, uint64_t now_us)
{
    if (l->tx_state == LS_ISOTP_TX_WAIT_FC && now_us >= l->tx_deadline_us) {
        tx_finish(l, LS_ISOTP_N_TIMEOUT_BS);
    }
    if (l->rx_state == LS_ISOTP_RX_RECEIVING && (now_us >= l->rx_deadline_us || now_us >= l->rx_end_us)) {
        rx_abort(l, LS_ISOTP_N_TIMEOUT_CR);
    }
}

uint64_t ls_isotp_rx_cap_us(const ls_isotp_config_t *cfg, uint16_t msg_len)
{
    const uint32_t cfs = msg_len > FF_DATA ? (msg_len - FF_DATA + CF_DATA - 1u) / CF_DATA : 0u;
    const uint32_t block = cfg->block_size != 0 ? cfg->block_size : LS_ISOTP_RX_CAP_BLOCK;
    const uint32_t blocks = (cfs + block - 1u) / block;
    return (uint64_t)cfg->n_cr_timeout_us * (1u + blocks);
}

void ls_isotp_on_frame(ls_isotp_link_t *l, const uint8_t *data, uint8_t len, uint64_t now_us)
{
    if (l == NULL) {
        return;
    }
    expire(l, now_us);
    if (data == NULL || len == 0 || len > CAN_DL) {
        count_rx(l, LS_ISOTP_N_MALFORMED);
        return;
    }
    switch (data[0] >> 4) {
    case PCI_SF: on_sf(l, data, len); break;
    case PCI_FF: on_ff(l, data, len, now_us); break;
    case PCI_CF: on_cf(l, data, len, now_us); break;
    case PCI_FC: on_fc(l, data, len, now_us); break;
    default: count_rx(l, LS_ISOTP_N_MALFORMED); break;
    }
}

void ls_isotp_poll(ls_isotp_link_t *l, uint64_t now_us)
{
    if (l == NULL) {
        return;
    }
    expire(l, now_us);
    if (l->rx_fc_pending) {
        queue_fc(l, l->rx_fc_status, now_us);
    }
    tx_pump(l, now_us);
}

size_t ls_isotp_take_rx(ls_isotp_link_t *l, uint8_t *out, size_t cap)
{
    if (l == NULL || out == NULL || l->rx_state != LS_ISOTP_RX_DONE) {
        return 0;
    }
    size_t n = l->rx_len;
    l->rx_state = LS_ISOTP_RX_IDLE;
    if (n > cap) {
        count_rx(l, LS_ISOTP_N_BUFFER_OVFLW);
        return 0;
    }
    memcpy(out, l->rx_buf, n);
    return n;
}

uint64_t ls_isotp_next_deadline_us(const ls_isotp_link_t *l)
{
    if (l == NULL) {
        return UINT64_MAX;
    }
    uint64_t t = UINT64_MAX;
    if (l->rx_fc_pending) {
        t = 0;
    }
    if (l->tx_state == LS_ISOTP_TX_SENDING && l->tx_next_us < t) {
        t = l->tx_next_us;
    }
    if (l->tx_state == LS_ISOTP_TX_WAIT_FC && l->tx_deadline_us < t) {
        t = l->tx_deadline_us;
    }
    if (l->rx_state == LS_ISOTP_RX_RECEIVING) {
        const uint64_t rx_t = l->rx_deadline_us < l->rx_end_us ? l->rx_deadline_us : l->rx_end_us;
        t = rx_t < t ? rx_t : t;
    }
    return t;
}

/* ---- single frames outside a link -------------------------------------- */

size_t ls_isotp_decode_single(const uint8_t *data, uint8_t len, uint8_t *out, size_t cap)
{
    if (data == NULL || out == NULL || len == 0 || len > CAN_DL || (data[0] >> 4) != PCI_SF) {
        return 0;
    }
    uint8_t n = data[0] & 0x0Fu;
    if (n == 0 || n > SF_MAX || len < 1u + n || cap < n) {
        return 0;
    }
    memcpy(out, data + 1, n);
    return n;
}

uint8_t ls_isotp_encode_single(const uint8_t *payload, size_t len, bool pad, uint8_t pad_byte, uint8_t frame[8])
{
    if (payload == NULL || frame == NULL || len == 0 || len > SF_MAX) {
        return 0;
    }
    frame[0] = (uint8_t)len;
    memcpy(frame + 1, payload, len);
    if (!pad) {
        return (uint8_t)(1u + len);
    }
    memset(frame + 1 + len, pad_byte, CAN_DL - 1u - len);
    return CAN_DL;
}

const char *ls_isotp_result_name(ls_isotp_result_t r)
{
    switch (r) {
    case LS_ISOTP_N_OK: return "N_OK";
    case LS_ISOTP_N_TIMEOUT_BS: return "N_TIMEOUT_BS";
    case LS_ISOTP_N_TIMEOUT_CR: return "N_TIMEOUT_CR";
    case LS_ISOTP_N_WRONG_SN: return "N_WRONG_SN";
    case LS_ISOTP_N_INVALID_FS: return "N_INVALID_FS";
    case LS_ISOTP_N_UNEXP_PDU: return "N_UNEXP_PDU";
    case LS_ISOTP_N_WFT_OVRN: return "N_WFT_OVRN";
    case LS_ISOTP_N_BUFFER_OVFLW: return "N_BUFFER_OVFLW";
    case LS_ISOTP_N_MALFORMED: return "N_MALFORMED";
    case LS_ISOTP_N_RESULT_COUNT: break;
    }
    return "N_UNKNOWN";
}
