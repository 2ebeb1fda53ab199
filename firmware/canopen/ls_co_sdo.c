/* CiA 301 SDO client: expedited and segmented transfers (ls_co_sdo.h). */
#include "ls_co_sdo.h"

#include <string.h>

#include "ls_canopen.h"
#include "ls_fmt.h"

#define SDO_FRAME_LEN 8u

static void put_le32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t get_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* An 8-byte request to the server, byte 0 = `cmd`, the rest zero. */
static hal_can_frame_t request(const ls_co_sdo_t *s, uint8_t cmd)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof(f));
    f.id = LS_CO_COB_SDO_RX + s->node_id;
    f.len = SDO_FRAME_LEN;
    f.data[0] = cmd;
    return f;
}

/* A request that carries the multiplexer (initiate and abort frames). */
static hal_can_frame_t request_mux(const ls_co_sdo_t *s, uint8_t cmd)
{
    hal_can_frame_t f = request(s, cmd);
    f.data[1] = (uint8_t)s->index;
    f.data[2] = (uint8_t)(s->index >> 8);
    f.data[3] = s->sub;
    return f;
}

static void emit(ls_co_sdo_t *s, const hal_can_frame_t *f, bool is_request)
{
    s->tx = *f;
    s->tx_is_request = is_request;
    s->tx_pending = s->send(s->send_ctx, f) != LS_OK;
}

/* Send the request the next phase waits on and restart the time-out. */
static void emit_request(ls_co_sdo_t *s, const hal_can_frame_t *f, ls_co_sdo_phase_t phase, uint64_t now_us)
{
    s->phase = phase;
    s->deadline_us = now_us + s->timeout_us;
    emit(s, f, true);
}

static const char *op_name(const ls_co_sdo_t *s)
{
    return s->upload ? "read" : "write";
}

/* End the transfer with `status`; the text is the node, the operation, the
 * object and `cause`. */
static void finish(ls_co_sdo_t *s, int status, uint32_t abort_code, const char *cause)
{
    s->phase = LS_CO_SDO_IDLE;
    s->status = status;
    s->abort_code = abort_code;
    if (status == LS_OK) {
        s->text[0] = '\0';
        return;
    }
    (void)ls_fmt_print(s->text, sizeof(s->text), "node 0x%02X: SDO %s 0x%04X:%02X %s", (unsigned)s->node_id, op_name(s),
                       (unsigned)s->index, (unsigned)s->sub, cause);
}

/* End the transfer because of the server or the time-out, telling the
 * server with abort `code`, unless our request never reached the bus (the
 * server then has no transfer to abort). `what` says what went wrong. */
static void fail_with_abort(ls_co_sdo_t *s, int status, uint32_t code, const char *what)
{
    char cause[LS_CO_TEXT_LEN];
    if (s->tx_pending && s->tx_is_request) {
        s->tx_pending = false;
        (void)ls_fmt_print(cause, sizeof(cause), "%s (the request never left: CAN queue full)", what);
    } else {
        hal_can_frame_t f = request_mux(s, LS_CO_SDO_CS_ABORT);
        put_le32(&f.data[4], code);
        emit(s, &f, false);
        s->counters.aborts_sent++;
        (void)ls_fmt_print(cause, sizeof(cause), "%s (abort 0x%08X sent)", what, (unsigned)code);
    }
    finish(s, status, code, cause);
}

static void fail_protocol(ls_co_sdo_t *s, uint32_t code, const char *what)
{
    fail_with_abort(s, LS_EPROTO, code, what);
}

static void expire(ls_co_sdo_t *s, uint64_t now_us)
{
    if (s->phase == LS_CO_SDO_IDLE || now_us < s->deadline_us) {
        return;
    }
    char what[48];
    (void)ls_fmt_print(what, sizeof(what), "got no answer within %u ms", (unsigned)(s->timeout_us / 1000u));
    s->counters.timeouts++;
    fail_with_abort(s, LS_ETIMEDOUT, LS_CO_ABORT_TIMEOUT, what);
}

int ls_co_sdo_init(ls_co_sdo_t *s, uint8_t node_id, uint32_t timeout_us, ls_co_send_fn send, void *send_ctx)
{
    if (s == NULL || send == NULL || node_id < LS_CO_NODE_MIN || node_id > LS_CO_NODE_MAX) {
        return LS_EINVAL;
    }
    memset(s, 0, sizeof(*s));
    s->node_id = node_id;
    s->timeout_us = timeout_us != 0u ? timeout_us : LS_CO_SDO_TIMEOUT_US_DEFAULT;
    s->send = send;
    s->send_ctx = send_ctx;
    s->status = LS_OK;
    return LS_OK;
}

bool ls_co_sdo_busy(const ls_co_sdo_t *s)
{
    return s != NULL && (s->phase != LS_CO_SDO_IDLE || s->tx_pending);
}

static void start(ls_co_sdo_t *s, bool upload, uint16_t index, uint8_t sub)
{
    s->upload = upload;
    s->index = index;
    s->sub = sub;
    s->len = 0;
    s->off = 0;
    s->size = 0;
    s->size_known = false;
    s->toggle = 0;
    s->status = LS_EBUSY;
    s->abort_code = 0;
    s->text[0] = '\0';
    s->counters.transfers++;
}

int ls_co_sdo_write(ls_co_sdo_t *s, uint16_t index, uint8_t sub, const uint8_t *data, size_t len, uint64_t now_us)
{
    if (s == NULL || data == NULL) {
        return LS_EINVAL;
    }
    if (len == 0u || len > LS_CO_SDO_BUF_LEN) {
        return LS_ELEN;
    }
    if (ls_co_sdo_busy(s)) {
        return LS_EBUSY;
    }
    start(s, false, index, sub);
    memcpy(s->buf, data, len);
    s->len = (uint8_t)len;
    hal_can_frame_t f;
    if (len <= LS_CO_SDO_EXP_DATA) {
        unsigned unused = (unsigned)(LS_CO_SDO_EXP_DATA - len);
        f = request_mux(s, (uint8_t)(LS_CO_SDO_CCS_DOWNLOAD_INITIATE | (unused << LS_CO_SDO_EXP_N_SHIFT) |
                                     LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE));
        memcpy(&f.data[4], data, len);
        s->off = (uint8_t)len;
    } else {
        f = request_mux(s, LS_CO_SDO_CCS_DOWNLOAD_INITIATE | LS_CO_SDO_SIZE);
        put_le32(&f.data[4], (uint32_t)len);
    }
    emit_request(s, &f, LS_CO_SDO_DL_INIT, now_us);
    return LS_OK;
}

int ls_co_sdo_read(ls_co_sdo_t *s, uint16_t index, uint8_t sub, uint64_t now_us)
{
    if (s == NULL) {
        return LS_EINVAL;
    }
    if (ls_co_sdo_busy(s)) {
        return LS_EBUSY;
    }
    start(s, true, index, sub);
    hal_can_frame_t f = request_mux(s, LS_CO_SDO_CCS_UPLOAD_INITIATE);
    emit_request(s, &f, LS_CO_SDO_UL_INIT, now_us);
    return LS_OK;
}

/* The next download segment (up to 7 bytes from s->off). */
static void send_download_segment(ls_co_sdo_t *s, uint64_t now_us)
{
    uint8_t n = (uint8_t)(s->len - s->off);
    if (n > LS_CO_SDO_SEG_DATA) {
        n = LS_CO_SDO_SEG_DATA;
    }
    bool last = s->off + n == s->len;
    unsigned unused = LS_CO_SDO_SEG_DATA - n;
    hal_can_frame_t f = request(s, (uint8_t)(LS_CO_SDO_CCS_DOWNLOAD_SEGMENT | s->toggle |
                                             (unused << LS_CO_SDO_SEG_N_SHIFT) | (last ? LS_CO_SDO_LAST : 0u)));
    memcpy(&f.data[1], &s->buf[s->off], n);
    s->off = (uint8_t)(s->off + n);
    emit_request(s, &f, LS_CO_SDO_DL_SEG, now_us);
}

static void send_upload_segment_request(ls_co_sdo_t *s, uint64_t now_us)
{
    hal_can_frame_t f = request(s, (uint8_t)(LS_CO_SDO_CCS_UPLOAD_SEGMENT | s->toggle));
    emit_request(s, &f, LS_CO_SDO_UL_SEG, now_us);
}

static bool mux_matches(const ls_co_sdo_t *s, const uint8_t *d)
{
    return d[1] == (uint8_t)s->index && d[2] == (uint8_t)(s->index >> 8) && d[3] == s->sub;
}

/* A response whose command specifier (or multiplexer) does not fit. */
static void unexpected(ls_co_sdo_t *s, const uint8_t *d)
{
    char what[64];
    (void)ls_fmt_print(what, sizeof(what), "got a response that does not fit: 0x%02X %02X %02X %02X", (unsigned)d[0],
                       (unsigned)d[1], (unsigned)d[2], (unsigned)d[3]);
    fail_protocol(s, LS_CO_ABORT_CS, what);
}

static bool toggle_ok(ls_co_sdo_t *s, uint8_t cmd)
{
    if ((cmd & LS_CO_SDO_TOGGLE) == s->toggle) {
        return true;
    }
    fail_protocol(s, LS_CO_ABORT_TOGGLE, "got a segment whose toggle bit did not alternate");
    return false;
}

static void on_download(ls_co_sdo_t *s, const uint8_t *d, uint64_t now_us)
{
    uint8_t cs = d[0] & LS_CO_SDO_CS_MASK;
    if (s->phase == LS_CO_SDO_DL_INIT) {
        if (cs != LS_CO_SDO_SCS_DOWNLOAD_INITIATE || !mux_matches(s, d)) {
            unexpected(s, d);
        } else if (s->off == s->len) {
            finish(s, LS_OK, 0, "");
        } else {
            send_download_segment(s, now_us);
        }
        return;
    }
    if (cs != LS_CO_SDO_SCS_DOWNLOAD_SEGMENT) {
        unexpected(s, d);
    } else if (toggle_ok(s, d[0])) {
        if (s->off == s->len) {
            finish(s, LS_OK, 0, "");
        } else {
            s->toggle ^= LS_CO_SDO_TOGGLE;
            send_download_segment(s, now_us);
        }
    }
}

/* Keep `n` more uploaded bytes; false when the buffer overflowed (the
 * transfer has then ended). */
static bool keep(ls_co_sdo_t *s, const uint8_t *src, uint8_t n)
{
    size_t room = LS_CO_SDO_BUF_LEN - s->len;
    size_t take = n < room ? n : room;
    memcpy(&s->buf[s->len], src, take);
    s->len = (uint8_t)(s->len + take);
    if (take == n) {
        return true;
    }
    char what[64];
    (void)ls_fmt_print(what, sizeof(what), "is longer than %u bytes: truncated", (unsigned)LS_CO_SDO_BUF_LEN);
    fail_with_abort(s, LS_ELEN, LS_CO_ABORT_NO_MEMORY, what);
    return false;
}

static bool size_ok(ls_co_sdo_t *s, bool last)
{
    if (!s->size_known || (s->len <= s->size && (!last || s->len == s->size))) {
        return true;
    }
    char what[64];
    (void)ls_fmt_print(what, sizeof(what), "sent %s%u bytes, %u indicated", last ? "" : "more than ", (unsigned)s->len,
                       (unsigned)s->size);
    fail_protocol(s, LS_CO_ABORT_TYPE_LEN, what);
    return false;
}

static void on_upload(ls_co_sdo_t *s, const uint8_t *d, uint64_t now_us)
{
    uint8_t cs = d[0] & LS_CO_SDO_CS_MASK;
    if (s->phase == LS_CO_SDO_UL_INIT) {
        if (cs != LS_CO_SDO_SCS_UPLOAD_INITIATE || !mux_matches(s, d)) {
            unexpected(s, d);
            return;
        }
        bool sized = (d[0] & LS_CO_SDO_SIZE) != 0u;
        if ((d[0] & LS_CO_SDO_EXPEDITED) != 0u) {
            uint8_t unused = sized ? (uint8_t)((d[0] >> LS_CO_SDO_EXP_N_SHIFT) & 3u) : 0u;
            (void)keep(s, &d[4], (uint8_t)(LS_CO_SDO_EXP_DATA - unused));
            finish(s, LS_OK, 0, "");
            return;
        }
        s->size_known = sized;
        s->size = sized ? get_le32(&d[4]) : 0u;
        send_upload_segment_request(s, now_us);
        return;
    }
    if (cs != LS_CO_SDO_SCS_UPLOAD_SEGMENT) {
        unexpected(s, d);
        return;
    }
    if (!toggle_ok(s, d[0])) {
        return;
    }
    bool last = (d[0] & LS_CO_SDO_LAST) != 0u;
    uint8_t unused = (uint8_t)((d[0] >> LS_CO_SDO_SEG_N_SHIFT) & 7u);
    if (!keep(s, &d[1], (uint8_t)(LS_CO_SDO_SEG_DATA - unused)) || !size_ok(s, last)) {
        return;
    }
    if (last) {
        finish(s, LS_OK, 0, "");
    } else {
        s->toggle ^= LS_CO_SDO_TOGGLE;
        send_upload_segment_request(s, now_us);
    }
}

void ls_co_sdo_on_frame(ls_co_sdo_t *s, const hal_can_frame_t *frame, uint64_t now_us)
{
    if (s == NULL || frame == NULL) {
        return;
    }
    expire(s, now_us);
    if (s->phase == LS_CO_SDO_IDLE) {
        s->counters.stray++;
        return;
    }
    const uint8_t *d = frame->data;
    if (frame->len < SDO_FRAME_LEN) {
        char what[64];
        (void)ls_fmt_print(what, sizeof(what), "got a frame of %u bytes (SDO frames have 8)", (unsigned)frame->len);
        fail_protocol(s, LS_CO_ABORT_CS, what);
        return;
    }
    if ((d[0] & LS_CO_SDO_CS_MASK) == LS_CO_SDO_CS_ABORT) {
        uint32_t code = get_le32(&d[4]);
        char what[LS_CO_TEXT_LEN];
        (void)ls_fmt_print(what, sizeof(what), "aborted 0x%08X (%s)", (unsigned)code, ls_co_abort_name(code));
        s->counters.aborts_received++;
        s->tx_pending = false; /* a request still queued is moot */
        finish(s, LS_EABORTED, code, what);
        return;
    }
    if (s->upload) {
        on_upload(s, d, now_us);
    } else {
        on_download(s, d, now_us);
    }
}

void ls_co_sdo_poll(ls_co_sdo_t *s, uint64_t now_us)
{
    if (s == NULL) {
        return;
    }
    if (s->tx_pending) {
        s->tx_pending = s->send(s->send_ctx, &s->tx) != LS_OK;
    }
    expire(s, now_us);
}

void ls_co_sdo_cancel(ls_co_sdo_t *s, const char *why)
{
    if (s == NULL) {
        return;
    }
    s->tx_pending = false;
    if (s->phase != LS_CO_SDO_IDLE) {
        finish(s, LS_EIO, 0, why != NULL ? why : "cancelled");
    }
}

int ls_co_sdo_status(const ls_co_sdo_t *s)
{
    return s == NULL ? LS_EINVAL : s->status;
}

uint32_t ls_co_sdo_abort_code(const ls_co_sdo_t *s)
{
    return s == NULL ? 0u : s->abort_code;
}

const uint8_t *ls_co_sdo_data(const ls_co_sdo_t *s, size_t *len)
{
    static const uint8_t none[1] = { 0 };
    if (s == NULL) {
        if (len != NULL) {
            *len = 0;
        }
        return none;
    }
    if (len != NULL) {
        *len = s->len;
    }
    return s->buf;
}

uint32_t ls_co_sdo_value(const ls_co_sdo_t *s, size_t *len)
{
    if (len != NULL) {
        *len = s == NULL ? 0u : s->len;
    }
    if (s == NULL) {
        return 0;
    }
    uint32_t v = 0;
    size_t n = s->len < 4u ? s->len : 4u;
    for (size_t i = 0; i < n; i++) {
        v |= (uint32_t)s->buf[i] << (8u * i);
    }
    return v;
}

const char *ls_co_sdo_text(const ls_co_sdo_t *s)
{
    return s == NULL ? "" : s->text;
}
