/* SDO server of a simulated drive (sd_node.h): expedited and segmented
 * upload and download on the node's default SDO (0x600 + id in, 0x580 + id
 * out). Block transfers are refused (LS_CO_ABORT_CS). Every request frame
 * carries 8 bytes (CiA 301); a shorter frame on the SDO's COB-ID is
 * ignored. A new initiate ends a transfer in progress; a client's abort
 * ends it silently; SD_SDO_TIMEOUT_US without the next segment ends it
 * with LS_CO_ABORT_TIMEOUT. */
#include <stdbool.h>
#include <string.h>

#include "sd_node.h"

enum { SD_SDO_IDLE = 0, SD_SDO_DOWNLOAD, SD_SDO_UPLOAD };

static void respond(sd_node_t *n, const uint8_t d[8])
{
    sd_node_send(n, LS_CO_COB_SDO_TX + n->cfg.node_id, d, 8);
}

static void abort_transfer(sd_node_t *n, uint16_t index, uint8_t sub, uint32_t code)
{
    uint8_t d[8] = { LS_CO_SDO_CS_ABORT, (uint8_t)index,       (uint8_t)(index >> 8), sub,
                     (uint8_t)code,      (uint8_t)(code >> 8), (uint8_t)(code >> 16), (uint8_t)(code >> 24) };
    respond(n, d);
    n->sdo.state = SD_SDO_IDLE;
}

void sd_sdo_reset(sd_node_t *n)
{
    memset(&n->sdo, 0, sizeof n->sdo);
    n->sdo.entry = SD_OD_NONE;
}

static void mux_of(const sd_node_t *n, uint16_t *index, uint8_t *sub)
{
    *index = n->sdo.entry >= 0 ? sd_od_table[n->sdo.entry].index : 0u;
    *sub = n->sdo.entry >= 0 ? sd_od_table[n->sdo.entry].sub : 0u;
}

static void initiate_upload(sd_node_t *n, int entry, uint16_t index, uint8_t sub, uint64_t now_us)
{
    uint8_t val[SD_SDO_BUF];
    size_t len = 0;
    uint32_t abort = sd_node_read(n, entry, val, sizeof val, &len, now_us);
    if (abort != 0u) {
        abort_transfer(n, index, sub, abort);
        return;
    }
    uint8_t d[8] = { 0, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0 };
    if (len >= 1u && len <= LS_CO_SDO_EXP_DATA) {
        d[0] = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_INITIATE | ((LS_CO_SDO_EXP_DATA - len) << LS_CO_SDO_EXP_N_SHIFT) |
                         LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE);
        memcpy(d + 4, val, len);
        respond(n, d);
        n->sdo.state = SD_SDO_IDLE;
        return;
    }
    /* Segmented (also an empty string: size 0, one empty last segment). */
    d[0] = LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_SIZE;
    sd_od_pack((int64_t)len, d + 4, 4);
    memcpy(n->sdo.buf, val, len);
    n->sdo.len = len;
    n->sdo.pos = 0;
    n->sdo.toggle = 0;
    n->sdo.entry = entry;
    n->sdo.state = SD_SDO_UPLOAD;
    n->sdo.deadline_us = now_us + SD_SDO_TIMEOUT_US;
    respond(n, d);
}

/* A segment's toggle bit must alternate, starting at 0: false (with the
 * abort sent) when it does not. *index and *sub: the transfer's object. */
static bool toggle_ok(sd_node_t *n, const uint8_t *req, uint16_t *index, uint8_t *sub)
{
    mux_of(n, index, sub);
    if ((req[0] & LS_CO_SDO_TOGGLE) != n->sdo.toggle) {
        abort_transfer(n, *index, *sub, LS_CO_ABORT_TOGGLE);
        return false;
    }
    return true;
}

static void upload_segment(sd_node_t *n, const uint8_t *req, uint64_t now_us)
{
    uint16_t index;
    uint8_t sub;
    if (!toggle_ok(n, req, &index, &sub)) {
        return;
    }
    uint8_t t = n->sdo.toggle;
    size_t left = n->sdo.len - n->sdo.pos;
    size_t k = left > LS_CO_SDO_SEG_DATA ? LS_CO_SDO_SEG_DATA : left;
    bool last = k == left;
    uint8_t d[8] = { 0 };
    d[0] = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_SEGMENT | t | ((LS_CO_SDO_SEG_DATA - k) << LS_CO_SDO_SEG_N_SHIFT) |
                     (last ? LS_CO_SDO_LAST : 0u));
    memcpy(d + 1, n->sdo.buf + n->sdo.pos, k);
    n->sdo.pos += k;
    n->sdo.toggle ^= LS_CO_SDO_TOGGLE;
    n->sdo.deadline_us = now_us + SD_SDO_TIMEOUT_US;
    if (last) {
        n->sdo.state = SD_SDO_IDLE;
    }
    respond(n, d);
}

/* The last segment came: write the whole value. False when it was refused
 * (the abort is sent). */
static bool finish_download(sd_node_t *n, uint16_t index, uint8_t sub, uint64_t now_us)
{
    uint32_t abort = 0;
    if (n->sdo.size_indicated != 0u && n->sdo.len != n->sdo.size_indicated) {
        abort = n->sdo.len > n->sdo.size_indicated ? LS_CO_ABORT_TYPE_LEN_HIGH : LS_CO_ABORT_TYPE_LEN_LOW;
    } else {
        abort = sd_node_write(n, n->sdo.entry, n->sdo.buf, n->sdo.len, now_us);
    }
    if (abort != 0u) {
        abort_transfer(n, index, sub, abort);
        return false;
    }
    n->sdo.state = SD_SDO_IDLE;
    return true;
}

static void initiate_download(sd_node_t *n, int entry, const uint8_t *req, uint16_t index, uint8_t sub, uint64_t now_us)
{
    if (!sd_od_writable(entry)) {
        abort_transfer(n, index, sub, LS_CO_ABORT_READ_ONLY);
        return;
    }
    uint8_t cs = req[0];
    size_t fixed = sd_od_is_number(entry) ? sd_od_size(&n->od, entry) : 0u;
    if ((cs & LS_CO_SDO_EXPEDITED) != 0u) {
        /* Without the size bit the four bytes are the value, cut to the
         * object's size (CiA 301: the size is then unspecified). */
        size_t len = (cs & LS_CO_SDO_SIZE) != 0u ? LS_CO_SDO_EXP_DATA - ((cs >> LS_CO_SDO_EXP_N_SHIFT) & 3u)
                     : fixed != 0u               ? fixed
                                                 : LS_CO_SDO_EXP_DATA;
        uint32_t abort = sd_node_write(n, entry, req + 4, len, now_us);
        if (abort != 0u) {
            abort_transfer(n, index, sub, abort);
            return;
        }
        uint8_t d[8] = { LS_CO_SDO_SCS_DOWNLOAD_INITIATE, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0 };
        respond(n, d);
        n->sdo.state = SD_SDO_IDLE;
        return;
    }
    size_t size = 0;
    if ((cs & LS_CO_SDO_SIZE) != 0u) {
        size = (size_t)((uint32_t)req[4] | (uint32_t)req[5] << 8 | (uint32_t)req[6] << 16 | (uint32_t)req[7] << 24);
        uint32_t abort = 0;
        if (fixed != 0u && size != fixed) {
            abort = size > fixed ? LS_CO_ABORT_TYPE_LEN_HIGH : LS_CO_ABORT_TYPE_LEN_LOW;
        } else if (size > SD_OD_STRING_MAX) {
            abort = LS_CO_ABORT_TYPE_LEN_HIGH;
        }
        if (abort != 0u) {
            abort_transfer(n, index, sub, abort);
            return;
        }
    }
    n->sdo.entry = entry;
    n->sdo.size_indicated = size;
    n->sdo.len = 0;
    n->sdo.toggle = 0;
    n->sdo.state = SD_SDO_DOWNLOAD;
    n->sdo.deadline_us = now_us + SD_SDO_TIMEOUT_US;
    uint8_t d[8] = { LS_CO_SDO_SCS_DOWNLOAD_INITIATE, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0 };
    respond(n, d);
}

static void download_segment(sd_node_t *n, const uint8_t *req, uint64_t now_us)
{
    uint16_t index;
    uint8_t sub;
    if (!toggle_ok(n, req, &index, &sub)) {
        return;
    }
    uint8_t t = n->sdo.toggle;
    size_t k = LS_CO_SDO_SEG_DATA - ((req[0] >> LS_CO_SDO_SEG_N_SHIFT) & 7u);
    if (n->sdo.len + k > sizeof n->sdo.buf) {
        abort_transfer(n, index, sub, LS_CO_ABORT_TYPE_LEN_HIGH);
        return;
    }
    memcpy(n->sdo.buf + n->sdo.len, req + 1, k);
    n->sdo.len += k;
    n->sdo.toggle ^= LS_CO_SDO_TOGGLE;
    n->sdo.deadline_us = now_us + SD_SDO_TIMEOUT_US;
    /* The last segment is confirmed only once the value is written. */
    if ((req[0] & LS_CO_SDO_LAST) != 0u && !finish_download(n, index, sub, now_us)) {
        return;
    }
    uint8_t d[8] = { (uint8_t)(LS_CO_SDO_SCS_DOWNLOAD_SEGMENT | t), 0, 0, 0, 0, 0, 0, 0 };
    respond(n, d);
}

void sd_sdo_rx(sd_node_t *n, const hal_can_frame_t *f, uint64_t now_us)
{
    if (f->len != 8u) {
        return;
    }
    const uint8_t *req = f->data;
    uint8_t ccs = req[0] & LS_CO_SDO_CS_MASK;
    if (ccs == LS_CO_SDO_CS_ABORT) {
        n->sdo.state = SD_SDO_IDLE; /* the client gave up: no answer */
        return;
    }
    if (ccs == LS_CO_SDO_CCS_DOWNLOAD_SEGMENT || ccs == LS_CO_SDO_CCS_UPLOAD_SEGMENT) {
        uint8_t want = n->sdo.state == SD_SDO_DOWNLOAD ? LS_CO_SDO_CCS_DOWNLOAD_SEGMENT
                       : n->sdo.state == SD_SDO_UPLOAD ? LS_CO_SDO_CCS_UPLOAD_SEGMENT
                                                       : 0xFFu;
        if (ccs != want) {
            uint16_t index;
            uint8_t sub;
            mux_of(n, &index, &sub);
            abort_transfer(n, index, sub, LS_CO_ABORT_CS);
            return;
        }
        if (ccs == LS_CO_SDO_CCS_DOWNLOAD_SEGMENT) {
            download_segment(n, req, now_us);
        } else {
            upload_segment(n, req, now_us);
        }
        return;
    }
    uint16_t index = (uint16_t)(req[1] | (uint16_t)req[2] << 8);
    uint8_t sub = req[3];
    n->sdo.state = SD_SDO_IDLE; /* a new initiate ends any transfer */
    if (ccs != LS_CO_SDO_CCS_DOWNLOAD_INITIATE && ccs != LS_CO_SDO_CCS_UPLOAD_INITIATE) {
        abort_transfer(n, index, sub, LS_CO_ABORT_CS); /* block transfers and unknown specifiers */
        return;
    }
    uint32_t abort = 0;
    int entry = sd_od_find(index, sub, &abort);
    if (entry < 0) {
        abort_transfer(n, index, sub, abort);
        return;
    }
    if (ccs == LS_CO_SDO_CCS_UPLOAD_INITIATE) {
        initiate_upload(n, entry, index, sub, now_us);
    } else {
        initiate_download(n, entry, req, index, sub, now_us);
    }
}

void sd_sdo_tick(sd_node_t *n, uint64_t now_us)
{
    if (n->sdo.state != SD_SDO_IDLE && now_us >= n->sdo.deadline_us) {
        uint16_t index;
        uint8_t sub;
        mux_of(n, &index, &sub);
        abort_transfer(n, index, sub, LS_CO_ABORT_TIMEOUT);
    }
}
