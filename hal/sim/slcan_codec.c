#include "slcan_codec.h"

#include <string.h>

static int hexval(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    return LS_EINVAL;
}

static int parse_hex(const char *s, size_t n, uint32_t *out)
{
    uint32_t v = 0;
    for (size_t i = 0; i < n; i++) {
        int h = hexval(s[i]);
        if (h < 0) {
            return LS_EINVAL;
        }
        v = (v << 4) | (uint32_t)h;
    }
    *out = v;
    return 0;
}

static int parse_frame(const char *line, size_t len, bool ext, bool rtr, hal_can_frame_t *f)
{
    size_t id_digits = ext ? 8u : 3u;
    if (len < 1u + id_digits + 1u) {
        return LS_EINVAL;
    }
    uint32_t id = 0;
    uint32_t dlc = 0;
    if (parse_hex(line + 1, id_digits, &id) != 0 || parse_hex(line + 1 + id_digits, 1, &dlc) != 0) {
        return LS_EINVAL;
    }
    if ((ext && id > 0x1FFFFFFFu) || (!ext && id > 0x7FFu) || dlc > 8u) {
        return LS_EINVAL;
    }
    size_t data_at = 1u + id_digits + 1u;
    size_t want = rtr ? data_at : data_at + 2u * dlc;
    if (len != want) {
        return LS_EINVAL;
    }
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = (uint8_t)dlc;
    f->flags = (uint8_t)((ext ? HAL_CAN_F_EXT : 0u) | (rtr ? HAL_CAN_F_RTR : 0u));
    if (!rtr) {
        for (uint32_t i = 0; i < dlc; i++) {
            uint32_t b = 0;
            if (parse_hex(line + data_at + 2u * i, 2, &b) != 0) {
                return LS_EINVAL;
            }
            f->data[i] = (uint8_t)b;
        }
    }
    return 0;
}

int ls_slcan_parse(const char *line, size_t len, ls_slcan_msg_t *out)
{
    static const uint32_t rates[] = { 10000, 20000, 50000, 100000, 125000, 250000, 500000, 800000, 1000000 };
    memset(out, 0, sizeof *out);
    if (len == 0) {
        out->kind = LS_SLCAN_EMPTY;
        return 0;
    }
    switch (line[0]) {
    case 't': return parse_frame(line, len, false, false, &out->frame);
    case 'T': return parse_frame(line, len, true, false, &out->frame);
    case 'r': return parse_frame(line, len, false, true, &out->frame);
    case 'R': return parse_frame(line, len, true, true, &out->frame);
    case 'O': out->kind = LS_SLCAN_OPEN; return len == 1 ? LS_OK : LS_EINVAL;
    case 'C': out->kind = LS_SLCAN_CLOSE; return len == 1 ? LS_OK : LS_EINVAL;
    case 'V': out->kind = LS_SLCAN_VERSION; return len == 1 ? LS_OK : LS_EINVAL;
    case 'N': out->kind = LS_SLCAN_SERIAL; return len == 1 ? LS_OK : LS_EINVAL;
    case 'F': out->kind = LS_SLCAN_FLAGS; return len == 1 ? LS_OK : LS_EINVAL;
    case 'Z': out->kind = LS_SLCAN_TIMESTAMP; return len == 2 && (line[1] == '0' || line[1] == '1') ? LS_OK : LS_EINVAL;
    case 'S':
        if (len != 2 || line[1] < '0' || line[1] > '8') {
            return LS_EINVAL;
        }
        out->kind = LS_SLCAN_BITRATE;
        out->bitrate = rates[line[1] - '0'];
        return 0;
    default: return LS_EINVAL;
    }
}

size_t ls_slcan_format(const hal_can_frame_t *f, char *out, size_t cap)
{
    static const char hex[] = "0123456789ABCDEF";
    bool ext = (f->flags & HAL_CAN_F_EXT) != 0u;
    bool rtr = (f->flags & HAL_CAN_F_RTR) != 0u;
    uint8_t dlc = f->len > 8u ? 8u : f->len;
    size_t id_digits = ext ? 8u : 3u;
    size_t need = 1u + id_digits + 1u + (rtr ? 0u : 2u * dlc) + 1u;
    if (cap < need) {
        return 0;
    }
    size_t n = 0;
    out[n++] = rtr ? (ext ? 'R' : 'r') : (ext ? 'T' : 't');
    uint32_t id = f->id & (ext ? 0x1FFFFFFFu : 0x7FFu);
    for (size_t i = 0; i < id_digits; i++) {
        out[n++] = hex[(id >> (4u * (id_digits - 1u - i))) & 0xFu];
    }
    out[n++] = hex[dlc];
    if (!rtr) {
        for (uint8_t i = 0; i < dlc; i++) {
            out[n++] = hex[f->data[i] >> 4];
            out[n++] = hex[f->data[i] & 0xFu];
        }
    }
    out[n++] = '\r';
    return n;
}

void ls_slcan_lexer_init(ls_slcan_lexer_t *lx)
{
    memset(lx, 0, sizeof *lx);
}

bool ls_slcan_lexer_feed(ls_slcan_lexer_t *lx, char c, size_t *len)
{
    if (c == '\r' || c == '\n') {
        if (lx->discarding) {
            lx->discarding = false;
            lx->len = 0;
            return false;
        }
        if (c == '\n' && lx->len == 0) {
            return false; /* CRLF: the CR already ended the line */
        }
        *len = lx->len;
        lx->len = 0;
        return true;
    }
    if (lx->discarding) {
        return false;
    }
    if (lx->len >= sizeof lx->buf) {
        lx->discarding = true;
        lx->overlong++;
        lx->len = 0;
        return false;
    }
    lx->buf[lx->len++] = c;
    return false;
}
