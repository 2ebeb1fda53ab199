/* Naming the field that made nanopb refuse an uplink (ls_wire.h). */
#include "ls_wire.h"

#include <pb_common.h>
#include <pb_decode.h>
#include <stdint.h>
#include <string.h>

#include "ls_cmd_table.h"
#include "ls_fmt.h"

#define SEEN_MAX 16 /* repeated fields counted per message level */

typedef struct {
    uint32_t tag;
    size_t count;
} seen_t;

/* Items of a packed run of L bytes of scalars of type lt (0: not a scalar). */
static size_t packed_items(pb_type_t lt, const uint8_t *p, size_t L)
{
    if (lt == PB_LTYPE_FIXED64) {
        return L / 8u;
    }
    if (lt == PB_LTYPE_FIXED32) {
        return L / 4u;
    }
    size_t n = 0;
    for (size_t i = 0; i < L; i++) {
        n += (p[i] & 0x80u) == 0u;
    }
    return n;
}

/* Append "[.]name[k]" to where[used..); returns the new length. */
static size_t name_at(char *where, size_t cap, size_t used, const pb_msgdesc_t *desc, uint32_t tag, bool rep, size_t k)
{
    if (where == NULL || used + 1u >= cap) {
        return used;
    }
    const char *name = ls_field_name(desc, tag);
    int w = name != NULL ? ls_fmt_print(where + used, cap - used, "%s%s", used > 0 ? "." : "", name)
                         : ls_fmt_print(where + used, cap - used, "%sfield %u", used > 0 ? "." : "", (unsigned)tag);
    if (w > 0 && rep && used + (size_t)w < cap) {
        w += ls_fmt_print(where + used + (size_t)w, cap - used - (size_t)w, "[%zu]", k);
    }
    return w > 0 && used + (size_t)w < cap ? used + (size_t)w : cap - 1u;
}

/* A varint of an integer field that its C type holds, as nanopb decodes it
 * (pb_dec_varint: the value must survive the store). Else false, with the
 * value and the range in `why`. */
static bool varint_fits(pb_type_t lt, pb_size_t size, uint64_t v, char *why, size_t cap)
{
    if (lt == PB_LTYPE_UVARINT) {
        const uint64_t max = size >= 8 ? UINT64_MAX : (UINT64_C(1) << (8u * size)) - 1u;
        if (v <= max) {
            return true;
        }
        /* a negative number sent for it reads as its 64-bit two's complement */
        if (v > (uint64_t)INT64_MAX) {
            ls_fmt_print(why, cap, " is %lld, outside 0..%llu", (long long)(int64_t)v, (unsigned long long)max);
        } else {
            ls_fmt_print(why, cap, " is %llu, outside 0..%llu", (unsigned long long)v, (unsigned long long)max);
        }
        return false;
    }
    int64_t sv;
    if (lt == PB_LTYPE_SVARINT) {
        sv = (int64_t)(v >> 1) ^ -(int64_t)(v & 1u);
    } else if (size >= 8) {
        sv = (int64_t)v;
    } else {
        sv = (int32_t)(uint32_t)v; /* as nanopb: a field of 32 bits or less takes the low 32 */
    }
    const int64_t hi = size >= 8 ? INT64_MAX : (INT64_C(1) << (8u * size - 1u)) - 1;
    const int64_t lo = -hi - 1;
    if (sv >= lo && sv <= hi) {
        return true;
    }
    ls_fmt_print(why, cap, " is %lld, outside %lld..%lld", (long long)sv, (long long)lo, (long long)hi);
    return false;
}

static ls_wire_fault_t walk(const pb_msgdesc_t *desc, const void *msg, const uint8_t *buf, size_t len, char *where,
                            size_t cap, size_t used, int depth)
{
    if (depth > 8) {
        return LS_WIRE_FITS;
    }
    seen_t seen[SEEN_MAX];
    size_t n_seen = 0;
    pb_istream_t s = pb_istream_from_buffer(buf, len);
    while (s.bytes_left > 0) {
        pb_wire_type_t wt;
        uint32_t tag;
        bool eof;
        if (!pb_decode_tag(&s, &wt, &tag, &eof) || eof) {
            return LS_WIRE_FITS;
        }
        pb_field_iter_t it;
        /* only the layout of msg is used: iterators compute addresses, nothing is accessed */
        if (!pb_field_iter_begin_const(&it, desc, msg) || !pb_field_iter_find(&it, tag) ||
            PB_ATYPE(it.type) != PB_ATYPE_STATIC) {
            if (!pb_skip_field(&s, wt)) {
                return LS_WIRE_FITS;
            }
            continue;
        }
        const pb_type_t lt = PB_LTYPE(it.type);
        const bool rep = PB_HTYPE(it.type) == PB_HTYPE_REPEATED;
        size_t items = 1, L = 0;
        const uint8_t *p = NULL;
        if (wt == PB_WT_STRING) {
            uint32_t l32;
            if (!pb_decode_varint32(&s, &l32) || l32 > s.bytes_left) {
                return LS_WIRE_FITS;
            }
            L = l32;
            p = buf + (len - s.bytes_left);
            if (!pb_read(&s, NULL, L)) {
                return LS_WIRE_FITS;
            }
            if (rep && lt != PB_LTYPE_STRING && lt != PB_LTYPE_BYTES && !PB_LTYPE_IS_SUBMSG(lt)) {
                items = packed_items(lt, p, L);
            }
        } else if (wt == PB_WT_VARINT && !rep &&
                   (lt == PB_LTYPE_VARINT || lt == PB_LTYPE_UVARINT || lt == PB_LTYPE_SVARINT)) {
            uint64_t v;
            if (!pb_decode_varint(&s, &v)) {
                return LS_WIRE_FITS;
            }
            char why[64];
            if (!varint_fits(lt, it.data_size, v, why, sizeof why)) {
                size_t at = name_at(where, cap, used, desc, tag, false, 0);
                if (where != NULL && at + 1u < cap) {
                    ls_fmt_print(where + at, cap - at, "%s", why);
                }
                return LS_WIRE_RANGE;
            }
        } else if (!pb_skip_field(&s, wt)) {
            return LS_WIRE_FITS;
        }
        size_t k = 0;
        if (rep) {
            size_t i = 0;
            while (i < n_seen && seen[i].tag != tag) {
                i++;
            }
            if (i == n_seen && n_seen < SEEN_MAX) {
                seen[n_seen].tag = tag;
                seen[n_seen++].count = 0;
            }
            if (i < n_seen) {
                k = seen[i].count;
                seen[i].count += items;
                if (seen[i].count > it.array_size) {
                    size_t at = name_at(where, cap, used, desc, tag, false, 0);
                    if (where != NULL && at + 1u < cap) {
                        ls_fmt_print(where + at, cap - at, " has %zu %s, at most %u", seen[i].count,
                                     PB_LTYPE_IS_SUBMSG(lt) || lt == PB_LTYPE_STRING ? "items" : "values",
                                     (unsigned)it.array_size);
                    }
                    return LS_WIRE_SIZE;
                }
            }
        }
        if (p == NULL) {
            continue;
        }
        if (lt == PB_LTYPE_STRING || lt == PB_LTYPE_BYTES) {
            const size_t max = lt == PB_LTYPE_STRING ? (size_t)it.data_size - 1u
                                                     : (size_t)it.data_size - offsetof(pb_bytes_array_t, bytes);
            if (L > max) {
                size_t at = name_at(where, cap, used, desc, tag, rep, k);
                if (where != NULL && at + 1u < cap) {
                    ls_fmt_print(where + at, cap - at, " has %zu bytes, at most %zu", L, max);
                }
                return LS_WIRE_SIZE;
            }
        } else if (PB_LTYPE_IS_SUBMSG(lt) && it.submsg_desc != NULL) {
            size_t at = name_at(where, cap, used, desc, tag, rep, k);
            ls_wire_fault_t f = walk(it.submsg_desc, it.pData, p, L, where, cap, at, depth + 1);
            if (f != LS_WIRE_FITS) {
                return f;
            }
            if (where != NULL && used < cap) {
                where[used] = '\0';
            }
        }
    }
    return LS_WIRE_FITS;
}

ls_wire_fault_t ls_wire_find_overflow(const pb_msgdesc_t *desc, const void *scratch, const uint8_t *buf, size_t len,
                                      char *where, size_t cap)
{
    if (where != NULL && cap > 0) {
        where[0] = '\0';
    }
    if (desc == NULL || scratch == NULL || buf == NULL) {
        return LS_WIRE_FITS;
    }
    return walk(desc, scratch, buf, len, where, cap, 0, 0);
}
