/* UTF-8 checks and repair: see ls_utf8.h. */
#include "ls_utf8.h"

#include <pb_common.h>
#include <stdint.h>
#include <string.h>

#include "ls_cmd_table.h"
#include "ls_fmt.h"

/* Length of the valid sequence at s[0..len), 0 when it is not one. */
static size_t seq_len(const unsigned char *s, size_t len)
{
    const unsigned c = s[0];
    if (c < 0x80u) {
        return 1;
    }
    size_t n;
    unsigned lo = 0x80u, hi = 0xBFu; /* range of the second byte */
    if (c >= 0xC2u && c <= 0xDFu) {
        n = 2;
    } else if (c >= 0xE0u && c <= 0xEFu) {
        n = 3;
        if (c == 0xE0u) {
            lo = 0xA0u; /* no overlong */
        } else if (c == 0xEDu) {
            hi = 0x9Fu; /* no surrogates */
        }
    } else if (c >= 0xF0u && c <= 0xF4u) {
        n = 4;
        if (c == 0xF0u) {
            lo = 0x90u;
        } else if (c == 0xF4u) {
            hi = 0x8Fu; /* <= U+10FFFF */
        }
    } else {
        return 0;
    }
    if (len < n || s[1] < lo || s[1] > hi) {
        return 0;
    }
    for (size_t k = 2; k < n; k++) {
        if ((s[k] & 0xC0u) != 0x80u) {
            return 0;
        }
    }
    return n;
}

size_t ls_utf8_check(const char *s, size_t len)
{
    const unsigned char *u = (const unsigned char *)s;
    size_t i = 0;
    while (i < len) {
        size_t n = seq_len(u + i, len - i);
        if (n == 0) {
            return i;
        }
        i += n;
    }
    return len;
}

size_t ls_utf8_repair(char *s)
{
    unsigned char *u = (unsigned char *)s;
    const size_t len = strlen(s);
    size_t r = 0, w = 0;
    while (r < len) {
        size_t n = seq_len(u + r, len - r);
        if (n == 0) {
            r++; /* drop the byte; a cut character's continuation bytes follow it out */
            continue;
        }
        memmove(u + w, u + r, n);
        w += n;
        r += n;
    }
    u[w] = '\0';
    return len - w;
}

/* Walk the string fields of msg; check (repair == false) or repair them. */
static bool walk(const pb_msgdesc_t *desc, void *msg, bool repair, char *where, size_t cap, size_t used, int depth)
{
    pb_field_iter_t it;
    if (depth > 8 || !pb_field_iter_begin(&it, desc, msg)) {
        return true;
    }
    do {
        const pb_type_t t = it.type;
        if (PB_ATYPE(t) != PB_ATYPE_STATIC || it.pData == NULL) {
            continue;
        }
        if (PB_HTYPE(t) == PB_HTYPE_ONEOF && *(const pb_size_t *)it.pSize != it.tag) {
            continue;
        }
        if (PB_HTYPE(t) == PB_HTYPE_OPTIONAL && it.pSize != NULL && !*(const bool *)it.pSize) {
            continue;
        }
        const bool is_str = PB_LTYPE(t) == PB_LTYPE_STRING;
        const bool is_msg = PB_LTYPE_IS_SUBMSG(t);
        if (!is_str && !is_msg) {
            continue;
        }
        const bool rep = PB_HTYPE(t) == PB_HTYPE_REPEATED;
        const size_t count = rep ? *(const pb_size_t *)it.pSize : 1u;
        for (size_t k = 0; k < count; k++) {
            char *elem = (char *)it.pData + k * it.data_size;
            size_t here = used;
            if (!repair && where != NULL && cap > used) {
                const char *name = ls_field_name(desc, it.tag);
                int w = ls_fmt_print(where + used, cap - used, "%s%s", used > 0 ? "." : "", name != NULL ? name : "?");
                if (w > 0 && rep) {
                    w += ls_fmt_print(where + used + (size_t)w, cap - used - (size_t)w, "[%zu]", k);
                }
                here = w > 0 && used + (size_t)w < cap ? used + (size_t)w : cap - 1u;
            }
            if (is_str) {
                if (repair) {
                    elem[it.data_size - 1u] = '\0';
                    (void)ls_utf8_repair(elem);
                    continue;
                }
                const char *nul = memchr(elem, '\0', it.data_size);
                const size_t len = nul != NULL ? (size_t)(nul - elem) : it.data_size;
                const size_t bad = ls_utf8_check(elem, len);
                if (bad < len) {
                    if (where != NULL && cap > here) {
                        ls_fmt_print(where + here, cap - here, " at byte %zu", bad);
                    }
                    return false;
                }
            } else if (!walk(it.submsg_desc, elem, repair, where, cap, here, depth + 1)) {
                return false;
            }
        }
    } while (pb_field_iter_next(&it));
    return true;
}

bool ls_utf8_check_msg(const pb_msgdesc_t *desc, const void *msg, char *where, size_t where_cap)
{
    if (where != NULL && where_cap > 0) {
        where[0] = '\0';
    }
    /* walk() only writes through msg when repairing */
    return walk(desc, (void *)(uintptr_t)msg, false, where, where_cap, 0, 0);
}

void ls_utf8_repair_msg(const pb_msgdesc_t *desc, void *msg)
{
    (void)walk(desc, msg, true, NULL, 0, 0, 0);
}
