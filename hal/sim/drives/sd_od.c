/* The simulated drive's object dictionary values (sd_od.h). */
#include "sd_od.h"

#include <string.h>

#include "ls_canopen.h"
#include "ls_err.h"

static const sd_od_entry_t *E(int entry)
{
    return &sd_od_table[entry];
}

static int compare(uint16_t index, uint8_t sub, const sd_od_entry_t *e)
{
    if (index != e->index) {
        return (index > e->index) - (index < e->index);
    }
    return (sub > e->sub) - (sub < e->sub);
}

int sd_od_find(uint16_t index, uint8_t sub, uint32_t *abort)
{
    /* Lower bound: the first entry at or after (index, sub). */
    int lo = 0, hi = SD_OD_N_ENTRIES;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (compare(index, sub, E(mid)) > 0) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    if (lo < SD_OD_N_ENTRIES && compare(index, sub, E(lo)) == 0) {
        return lo;
    }
    /* The index exists when a neighbour of the gap carries it. */
    bool index_seen = (lo < SD_OD_N_ENTRIES && E(lo)->index == index) || (lo > 0 && E(lo - 1)->index == index);
    if (abort != NULL) {
        *abort = index_seen ? LS_CO_ABORT_NO_SUB : LS_CO_ABORT_NO_OBJECT;
    }
    return LS_EINVAL;
}

int sd_od_lookup(uint16_t index, uint8_t sub)
{
    int e = sd_od_find(index, sub, NULL);
    return e >= 0 ? e : SD_OD_NONE;
}

bool sd_od_is_number(int entry)
{
    return E(entry)->def_str == NULL;
}

void sd_od_reset(sd_od_t *od, uint8_t node_id, uint16_t from, uint16_t to)
{
    for (int i = 0; i < SD_OD_N_ENTRIES; i++) {
        const sd_od_entry_t *e = E(i);
        if (e->index < from || e->index > to) {
            continue;
        }
        if (!sd_od_is_number(i)) {
            size_t n = strlen(e->def_str);
            n = n > SD_OD_STRING_MAX ? SD_OD_STRING_MAX : n;
            memcpy(od->str[e->str_slot], e->def_str, n);
            od->str_len[e->str_slot] = (uint8_t)n;
            continue;
        }
        od->val[i] = e->def + ((e->flags & SD_OD_F_NODEID) != 0u ? (int64_t)node_id : 0);
    }
}

size_t sd_od_size(const sd_od_t *od, int entry)
{
    if (!sd_od_is_number(entry)) {
        return od->str_len[E(entry)->str_slot];
    }
    return ls_co_type_size(E(entry)->type);
}

unsigned sd_od_bits(int entry)
{
    return 8u * ls_co_type_size(E(entry)->type);
}

bool sd_od_readable(int entry)
{
    return E(entry)->access != SD_OD_ACCESS_WO;
}

bool sd_od_writable(int entry)
{
    uint8_t a = E(entry)->access;
    return a != SD_OD_ACCESS_RO && a != SD_OD_ACCESS_CONST;
}

void sd_od_pack(int64_t value, uint8_t *out, size_t bytes)
{
    uint64_t u = (uint64_t)value;
    for (size_t k = 0; k < bytes; k++) {
        out[k] = (uint8_t)(u >> (8u * k));
    }
}

static bool is_signed(uint16_t type)
{
    return type == LS_CO_TYPE_INTEGER8 || type == LS_CO_TYPE_INTEGER16 || type == LS_CO_TYPE_INTEGER32 ||
           type == LS_CO_TYPE_INTEGER64;
}

int64_t sd_od_unpack(int entry, const uint8_t *in)
{
    size_t n = ls_co_type_size(E(entry)->type);
    uint64_t u = 0;
    for (size_t k = 0; k < n; k++) {
        u |= (uint64_t)in[k] << (8u * k);
    }
    if (is_signed(E(entry)->type) && n < 8u && (u & (1ull << (8u * n - 1u))) != 0u) {
        u |= ~0ull << (8u * n); /* sign extension */
    }
    return (int64_t)u;
}

uint32_t sd_od_get_bytes(const sd_od_t *od, int entry, uint8_t *buf, size_t cap, size_t *len)
{
    size_t n = sd_od_size(od, entry);
    if (n > cap) {
        return LS_CO_ABORT_GENERAL;
    }
    if (sd_od_is_number(entry)) {
        sd_od_pack(od->val[entry], buf, n);
    } else {
        memcpy(buf, od->str[E(entry)->str_slot], n);
    }
    *len = n;
    return 0;
}

uint32_t sd_od_decode(int entry, const uint8_t *buf, size_t len, int64_t *value)
{
    if (!sd_od_is_number(entry)) {
        return len > SD_OD_STRING_MAX ? LS_CO_ABORT_TYPE_LEN_HIGH : 0u;
    }
    size_t n = ls_co_type_size(E(entry)->type);
    if (len != n) {
        return len > n ? LS_CO_ABORT_TYPE_LEN_HIGH : LS_CO_ABORT_TYPE_LEN_LOW;
    }
    int64_t v = sd_od_unpack(entry, buf);
    if (v > E(entry)->high) {
        return LS_CO_ABORT_VALUE_HIGH;
    }
    if (v < E(entry)->low) {
        return LS_CO_ABORT_VALUE_LOW;
    }
    *value = v;
    return 0;
}

void sd_od_set(sd_od_t *od, int entry, int64_t value)
{
    od->val[entry] = value;
}

void sd_od_set_string(sd_od_t *od, int entry, const uint8_t *buf, size_t len)
{
    len = len > SD_OD_STRING_MAX ? SD_OD_STRING_MAX : len;
    memcpy(od->str[E(entry)->str_slot], buf, len);
    od->str_len[E(entry)->str_slot] = (uint8_t)len;
}
