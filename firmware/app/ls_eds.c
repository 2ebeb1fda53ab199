/* CiA 306 EDS/DCF files on inih. Contracts and the accepted syntax in
 * ls_eds.h.
 *
 * inih splits lines into sections and key=value pairs; this file feeds it
 * lines through its reader hook, which also sees every section header
 * first: a section's keys are collected while inih reports them and the
 * entry is built when the next header (or the end of the file) shows that
 * the section is complete, since an entry's DefaultValue can only be read
 * once its DataType is known, whatever their order in the section. */
#include "ls_eds.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <ini.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "ls_canopen.h"
#include "ls_fmt.h"

/* ---- Field kinds (ls_eds_entry_t.kind) ---------------------------------- */

enum { KIND_NONE = 0, KIND_NUMBER, KIND_RELATIVE, KIND_TEXT };

enum { HAS_VENDOR = 1u, HAS_PRODUCT = 2u, HAS_REVISION = 4u };

#define NODEID_TOKEN "$NODEID"
#define SECTION_NAME_MAX 48u    /* longer names are no section of CiA 306 */
#define MAX_OTHER_SECTIONS 256u /* [FileInfo], [Comments], a modular device's [M1ModuleInfo] ... */
#define N_DUMMIES 7u            /* DummyUsage lists Dummy0001..Dummy0007 */
#define READ_CHUNK 4096u
#define INIH_LINE_MAX 200u /* libinih's line buffer (INI_MAX_LINE), end of line and NUL included */

/* ---- Keys ------------------------------------------------------------- */

typedef enum {
    K_PARAMETER_NAME = 0,
    K_OBJECT_TYPE,
    K_DATA_TYPE,
    K_ACCESS_TYPE,
    K_PDO_MAPPING,
    K_DEFAULT_VALUE,
    K_PARAMETER_VALUE,
    K_LOW_LIMIT,
    K_HIGH_LIMIT,
    K_SUB_NUMBER,
    K_COMPACT_SUB_OBJ,
    K_VENDOR_NAME,
    K_VENDOR_NUMBER,
    K_PRODUCT_NAME,
    K_PRODUCT_NUMBER,
    K_REVISION_NUMBER,
    K_NODE_ID,
    K_DUMMY1, /* .. K_DUMMY1 + 6 */
    K_COUNT = K_DUMMY1 + N_DUMMIES
} key_t_;

typedef enum { SEC_NONE = 0, SEC_OBJECT, SEC_SUB, SEC_DEVICE_INFO, SEC_COMMISSIONING, SEC_DUMMY, SEC_OTHER } sec_kind_t;

static const struct {
    const char *name;
    sec_kind_t section; /* SEC_OBJECT: object and sub-object sections */
} KEYS[K_COUNT] = {
    [K_PARAMETER_NAME] = { "ParameterName", SEC_OBJECT },
    [K_OBJECT_TYPE] = { "ObjectType", SEC_OBJECT },
    [K_DATA_TYPE] = { "DataType", SEC_OBJECT },
    [K_ACCESS_TYPE] = { "AccessType", SEC_OBJECT },
    [K_PDO_MAPPING] = { "PDOMapping", SEC_OBJECT },
    [K_DEFAULT_VALUE] = { "DefaultValue", SEC_OBJECT },
    [K_PARAMETER_VALUE] = { "ParameterValue", SEC_OBJECT },
    [K_LOW_LIMIT] = { "LowLimit", SEC_OBJECT },
    [K_HIGH_LIMIT] = { "HighLimit", SEC_OBJECT },
    [K_SUB_NUMBER] = { "SubNumber", SEC_OBJECT },
    [K_COMPACT_SUB_OBJ] = { "CompactSubObj", SEC_OBJECT },
    [K_VENDOR_NAME] = { "VendorName", SEC_DEVICE_INFO },
    [K_VENDOR_NUMBER] = { "VendorNumber", SEC_DEVICE_INFO },
    [K_PRODUCT_NAME] = { "ProductName", SEC_DEVICE_INFO },
    [K_PRODUCT_NUMBER] = { "ProductNumber", SEC_DEVICE_INFO },
    [K_REVISION_NUMBER] = { "RevisionNumber", SEC_DEVICE_INFO },
    [K_NODE_ID] = { "NodeID", SEC_COMMISSIONING },
    [K_DUMMY1] = { "Dummy0001", SEC_DUMMY },
    [K_DUMMY1 + 1] = { "Dummy0002", SEC_DUMMY },
    [K_DUMMY1 + 2] = { "Dummy0003", SEC_DUMMY },
    [K_DUMMY1 + 3] = { "Dummy0004", SEC_DUMMY },
    [K_DUMMY1 + 4] = { "Dummy0005", SEC_DUMMY },
    [K_DUMMY1 + 5] = { "Dummy0006", SEC_DUMMY },
    [K_DUMMY1 + 6] = { "Dummy0007", SEC_DUMMY },
};

/* The fields a key fills. */
static const key_t_ FIELD_KEY[LS_EDS_FIELD_COUNT] = {
    [LS_EDS_DEFAULT] = K_DEFAULT_VALUE,
    [LS_EDS_PARAMETER] = K_PARAMETER_VALUE,
    [LS_EDS_LOW] = K_LOW_LIMIT,
    [LS_EDS_HIGH] = K_HIGH_LIMIT,
};

/* ---- Parser state ------------------------------------------------------ */

typedef struct {
    ls_eds_t *eds;
    const char *name;
    char *msg;
    size_t msg_cap;
    bool failed;

    /* the source: a file descriptor read in chunks, or a buffer */
    int fd;
    const char *buf;
    size_t buf_len;
    size_t buf_pos;
    char chunk[READ_CHUNK];
    bool read_failed;
    int read_errno;

    char line[LS_EDS_LINE_MAX + 1];
    uint32_t lineno;

    /* the section being read */
    sec_kind_t sec;
    char sec_name[SECTION_NAME_MAX + 1];
    uint32_t sec_line;
    uint16_t sec_index;
    uint8_t sec_sub;
    bool any_section;
    struct {
        uint32_t line; /* 0: not given in this section */
        char value[LS_EDS_LINE_MAX + 1];
    } key[K_COUNT];

    struct {
        char name[SECTION_NAME_MAX + 1];
        uint32_t line;
    } other[MAX_OTHER_SECTIONS];
    unsigned n_other;
    bool device_info;
    bool dummy[N_DUMMIES];
} ctx_t;

/* ---- Messages ---------------------------------------------------------- */

/* The first error wins; the rest of the file is not read. `line` 0: the
 * message is about the whole file. */
static void fail_at(ctx_t *c, uint32_t line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void fail_at(ctx_t *c, uint32_t line, const char *fmt, ...)
{
    if (c->failed) {
        return;
    }
    c->failed = true;
    if (c->msg == NULL || c->msg_cap == 0u) {
        return;
    }
    int w = line > 0u ? snprintf(c->msg, c->msg_cap, "%s:%lu: ", c->name, (unsigned long)line)
                      : snprintf(c->msg, c->msg_cap, "%s: ", c->name);
    if (w < 0 || (size_t)w >= c->msg_cap) {
        return;
    }
    if (!c->any_section) {
        int n = snprintf(c->msg + w, c->msg_cap - (size_t)w, "not an EDS or DCF: ");
        if (n < 0 || (size_t)(w + n) >= c->msg_cap) {
            return;
        }
        w += n;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(c->msg + w, c->msg_cap - (size_t)w, fmt, ap);
    va_end(ap);
}

/* ---- Text -------------------------------------------------------------- */

static bool add_text(ctx_t *c, const char *s, uint32_t line, uint32_t *off)
{
    ls_eds_t *e = c->eds;
    const size_t n = strlen(s);
    if (n == 0u) {
        *off = 0u;
        return true;
    }
    if (n + 1u > LS_EDS_TEXT_BYTES - e->text_used) {
        fail_at(c, line, "[%s]: the names and texts of this file exceed %u bytes (LS_EDS_TEXT_BYTES)", c->sec_name,
                (unsigned)LS_EDS_TEXT_BYTES);
        return false;
    }
    memcpy(e->text + e->text_used, s, n + 1u);
    *off = e->text_used;
    e->text_used += (uint32_t)(n + 1u);
    return true;
}

/* ---- Lookup ------------------------------------------------------------ */

/* Sort key: an object's own section first, then its sub-objects. */
static uint32_t key_of(uint16_t index, bool is_sub, uint8_t sub)
{
    return ((uint32_t)index << 9) | (is_sub ? (uint32_t)sub + 1u : 0u);
}

static uint32_t entry_key(const ls_eds_entry_t *e)
{
    return key_of(e->index, e->is_sub, e->sub);
}

/* The position of `key` (found) or where it would go (not found). */
static size_t lower_bound(const ls_eds_t *eds, uint32_t key)
{
    size_t lo = 0u;
    size_t hi = eds->n_entries;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2u;
        if (entry_key(&eds->entries[mid]) < key) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

static const ls_eds_entry_t *lookup(const ls_eds_t *eds, uint32_t key)
{
    const size_t i = lower_bound(eds, key);
    if (i < eds->n_entries && entry_key(&eds->entries[i]) == key) {
        return &eds->entries[i];
    }
    return NULL;
}

static bool is_container(uint8_t object_type)
{
    return object_type == LS_CO_OBJECT_ARRAY || object_type == LS_CO_OBJECT_RECORD ||
           object_type == LS_CO_OBJECT_DEFSTRUCT;
}

/* ---- Numbers ------------------------------------------------------------ */

typedef enum { SIGNED, UNSIGNED, REAL, TEXT } type_class_t;

static type_class_t class_of(uint16_t data_type)
{
    switch (data_type) {
    case LS_CO_TYPE_INTEGER8:
    case LS_CO_TYPE_INTEGER16:
    case LS_CO_TYPE_INTEGER24:
    case LS_CO_TYPE_INTEGER32:
    case LS_CO_TYPE_INTEGER40:
    case LS_CO_TYPE_INTEGER48:
    case LS_CO_TYPE_INTEGER56:
    case LS_CO_TYPE_INTEGER64: return SIGNED;
    case LS_CO_TYPE_REAL32:
    case LS_CO_TYPE_REAL64: return REAL;
    case LS_CO_TYPE_VISIBLE_STRING:
    case LS_CO_TYPE_OCTET_STRING:
    case LS_CO_TYPE_UNICODE_STRING:
    case LS_CO_TYPE_DOMAIN: return TEXT;
    default: return UNSIGNED; /* BOOLEAN, UNSIGNEDn, TIME_OF_DAY, TIME_DIFFERENCE */
    }
}

/* Decimal, 0x hex or 0-prefixed octal, an optional sign; the magnitude in
 * *mag. False on anything else, an empty string or more than 64 bits. */
static bool parse_magnitude(const char *s, bool *neg, bool *radix_prefixed, uint64_t *mag)
{
    *neg = false;
    if (*s == '-' || *s == '+') {
        *neg = *s == '-';
        s++;
    }
    unsigned base = 10u;
    *radix_prefixed = false;
    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16u;
        s += 2;
        *radix_prefixed = true;
    } else if (s[0] == '0' && s[1] != '\0') {
        base = 8u;
        s += 1;
        *radix_prefixed = true;
    }
    if (*s == '\0') {
        return false;
    }
    uint64_t v = 0u;
    for (; *s != '\0'; s++) {
        unsigned d;
        if (*s >= '0' && *s <= '9') {
            d = (unsigned)(*s - '0');
        } else if (*s >= 'a' && *s <= 'f') {
            d = (unsigned)(*s - 'a') + 10u;
        } else if (*s >= 'A' && *s <= 'F') {
            d = (unsigned)(*s - 'A') + 10u;
        } else {
            return false;
        }
        if (d >= base || v > (UINT64_MAX - d) / base) {
            return false;
        }
        v = v * base + d;
    }
    *mag = v;
    return true;
}

/* The range of an integer type in bits (BOOLEAN: 1). */
static unsigned bits_of(uint16_t data_type)
{
    return data_type == LS_CO_TYPE_BOOLEAN ? 1u : 8u * ls_co_type_size(data_type);
}

/* An integer of `data_type` as its 64-bit pattern (signed ones sign
 * extended). False when it does not fit; *why says how. */
static bool fit_integer(uint16_t data_type, bool neg, bool radix_prefixed, uint64_t mag, uint64_t *bits,
                        const char **why)
{
    const unsigned n = bits_of(data_type);
    const uint64_t umax = n >= 64u ? UINT64_MAX : ((uint64_t)1 << n) - 1u;
    if (class_of(data_type) == UNSIGNED) {
        if (neg && mag != 0u) {
            *why = "a negative value for an unsigned type";
            return false;
        }
        if (mag > umax) {
            *why = "too large for its data type";
            return false;
        }
        *bits = mag;
        return true;
    }
    const uint64_t smax = umax >> 1; /* 2^(n-1) - 1 */
    if (neg) {
        if (mag > smax + 1u) {
            *why = "too small for its data type";
            return false;
        }
        *bits = (uint64_t)0 - mag;
        return true;
    }
    if (mag <= smax) {
        *bits = mag;
        return true;
    }
    if (radix_prefixed && mag <= umax) { /* two's complement written in hex or octal */
        *bits = n >= 64u ? mag : mag | ~umax;
        return true;
    }
    *why = "too large for its data type";
    return false;
}

/* Signed view of a pattern made by fit_integer. */
static int64_t as_signed(uint64_t bits)
{
    if (bits <= (uint64_t)INT64_MAX) {
        return (int64_t)bits;
    }
    return (int64_t)(bits - ((uint64_t)INT64_MAX + 1u)) + INT64_MIN; /* bits - 2^64, without overflow */
}

/* An integer value, maybe "$NODEID+N", "N+$NODEID" or "$NODEID". */
static bool parse_integer_field(ctx_t *c, const ls_eds_entry_t *e, key_t_ k, const char *raw, uint8_t *kind,
                                uint64_t *bits)
{
    char text[LS_EDS_LINE_MAX + 1];
    size_t n = 0u;
    for (const char *p = raw; *p != '\0' && n < LS_EDS_LINE_MAX; p++) {
        if (*p != ' ' && *p != '\t') {
            text[n++] = *p;
        }
    }
    text[n] = '\0';
    const char *num = text;
    bool relative = false;
    char *tok = NULL;
    for (char *p = text; *p != '\0'; p++) {
        if (strncasecmp(p, NODEID_TOKEN, sizeof NODEID_TOKEN - 1u) == 0) {
            tok = p;
            break;
        }
    }
    if (tok != NULL) {
        relative = true;
        char *after = tok + sizeof NODEID_TOKEN - 1u;
        if (tok == text && *after == '\0') {
            num = "0";
        } else if (tok == text && *after == '+') {
            num = after + 1;
        } else if (tok > text && tok[-1] == '+' && *after == '\0') {
            tok[-1] = '\0';
            num = text;
        } else {
            num = "";
        }
        if (strstr(num, "$") != NULL) {
            num = "";
        }
    }
    bool neg;
    bool prefixed;
    uint64_t mag;
    if (!parse_magnitude(num, &neg, &prefixed, &mag)) {
        fail_at(c, c->key[k].line, "[%s] %s: '%.60s' is not a number: write decimal, 0x hex or 0-prefixed octal%s",
                c->sec_name, KEYS[k].name, raw, relative ? ", as $NODEID+N or N+$NODEID" : "");
        return false;
    }
    const char *why = "";
    if (!relative) {
        if (!fit_integer(e->data_type, neg, prefixed, mag, bits, &why)) {
            fail_at(c, c->key[k].line, "[%s] %s: '%.60s' is %s (%s)", c->sec_name, KEYS[k].name, raw, why,
                    ls_co_type_name(e->data_type));
            return false;
        }
        *kind = KIND_NUMBER;
        return true;
    }
    /* Relative: base + every node id must fit. */
    uint64_t base;
    bool ok = fit_integer(e->data_type, neg, prefixed, mag, &base, &why);
    if (ok) {
        const unsigned nbits = bits_of(e->data_type);
        if (class_of(e->data_type) == SIGNED) {
            const int64_t smax = nbits >= 64u ? INT64_MAX : (int64_t)(((uint64_t)1 << (nbits - 1u)) - 1u);
            /* node ids are positive: only the top can be passed */
            ok = as_signed(base) <= smax - (int64_t)LS_CO_NODE_MAX;
        } else {
            const uint64_t umax = nbits >= 64u ? UINT64_MAX : ((uint64_t)1 << nbits) - 1u;
            ok = umax >= LS_CO_NODE_MAX && base <= umax - LS_CO_NODE_MAX; /* no node id fits a BOOLEAN */
        }
        why = "too large for its data type";
    }
    if (!ok) {
        fail_at(c, c->key[k].line, "[%s] %s: '%.60s' is %s (%s) for some node id 1 to 127", c->sec_name, KEYS[k].name,
                raw, why, ls_co_type_name(e->data_type));
        return false;
    }
    *kind = KIND_RELATIVE;
    *bits = base;
    return true;
}

static bool parse_field(ctx_t *c, ls_eds_entry_t *e, ls_eds_field_id_t f)
{
    const key_t_ k = FIELD_KEY[f];
    if (c->key[k].line == 0u) {
        return true;
    }
    const char *raw = c->key[k].value;
    switch (class_of(e->data_type)) {
    case TEXT: {
        uint32_t off;
        if (!add_text(c, raw, c->key[k].line, &off)) {
            return false;
        }
        e->kind[f] = KIND_TEXT;
        e->bits[f] = off;
        return true;
    }
    case REAL: {
        if (raw[0] == '\0') {
            return true;
        }
        char *end = NULL;
        const double v = ls_fmt_parse_double(raw, &end);
        const double lim = e->data_type == LS_CO_TYPE_REAL32 ? (double)FLT_MAX : DBL_MAX;
        if (end == raw || *end != '\0' || !isfinite(v) || fabs(v) > lim) {
            fail_at(c, c->key[k].line, "[%s] %s: '%.60s' is not a finite decimal number (%s)", c->sec_name,
                    KEYS[k].name, raw, ls_co_type_name(e->data_type));
            return false;
        }
        uint64_t b;
        memcpy(&b, &v, sizeof b);
        e->kind[f] = KIND_NUMBER;
        e->bits[f] = b;
        return true;
    }
    case SIGNED:
    case UNSIGNED:
    default:
        if (raw[0] == '\0') {
            return true; /* "DefaultValue=": no value */
        }
        return parse_integer_field(c, e, k, raw, &e->kind[f], &e->bits[f]);
    }
}

/* A small unsigned number of a structural key (ObjectType, SubNumber, ...). */
static bool parse_small(ctx_t *c, key_t_ k, uint64_t max, uint64_t *out)
{
    bool neg;
    bool prefixed;
    uint64_t v;
    if (!parse_magnitude(c->key[k].value, &neg, &prefixed, &v) || neg || v > max) {
        fail_at(c, c->key[k].line, "[%s] %s: '%.60s' is not a number from 0 to %llu", c->sec_name, KEYS[k].name,
                c->key[k].value, (unsigned long long)max);
        return false;
    }
    *out = v;
    return true;
}

/* ---- Sections ----------------------------------------------------------- */

static bool hex4(const char *s, uint16_t *out)
{
    unsigned v = 0u;
    for (int i = 0; i < 4; i++) {
        if (!isxdigit((unsigned char)s[i])) {
            return false;
        }
        v = v * 16u + (unsigned)(isdigit((unsigned char)s[i]) ? s[i] - '0' : (tolower((unsigned char)s[i]) - 'a') + 10);
    }
    *out = (uint16_t)v;
    return true;
}

static bool insert_entry(ctx_t *c, const ls_eds_entry_t *e)
{
    ls_eds_t *eds = c->eds;
    if (eds->n_entries >= LS_EDS_MAX_ENTRIES) {
        fail_at(c, e->line, "[%s]: more than %u objects and sub-objects (LS_EDS_MAX_ENTRIES)", c->sec_name,
                (unsigned)LS_EDS_MAX_ENTRIES);
        return false;
    }
    const size_t at = lower_bound(eds, entry_key(e));
    memmove(&eds->entries[at + 1u], &eds->entries[at], (eds->n_entries - at) * sizeof eds->entries[0]);
    eds->entries[at] = *e;
    eds->n_entries++;
    return true;
}

static bool parse_access(ctx_t *c, uint8_t *out)
{
    static const char *names[] = { "ro", "wo", "rw", "rwr", "rww", "const" };
    for (unsigned i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (strcasecmp(c->key[K_ACCESS_TYPE].value, names[i]) == 0) {
            *out = (uint8_t)(LS_EDS_RO + i);
            return true;
        }
    }
    fail_at(c, c->key[K_ACCESS_TYPE].line,
            "[%s] AccessType: unknown access type '%.60s'; expected ro, wo, rw, rwr, rww or const", c->sec_name,
            c->key[K_ACCESS_TYPE].value);
    return false;
}

/* Builds the entry of the object or sub-object section just read. */
static bool end_object(ctx_t *c)
{
    ls_eds_entry_t e;
    memset(&e, 0, sizeof e);
    e.index = c->sec_index;
    e.sub = c->sec_sub;
    e.is_sub = c->sec == SEC_SUB;
    e.line = c->sec_line;
    if (c->key[K_COMPACT_SUB_OBJ].line != 0u) {
        fail_at(c, c->key[K_COMPACT_SUB_OBJ].line,
                "[%s] CompactSubObj: compact sub-objects are not supported; write them out as [%04XsubN] sections",
                c->sec_name, (unsigned)e.index);
        return false;
    }
    if (c->key[K_PARAMETER_NAME].line == 0u) {
        fail_at(c, c->sec_line, "[%s]: no ParameterName", c->sec_name);
        return false;
    }
    uint64_t v = LS_CO_OBJECT_VAR; /* CiA 306: VAR when ObjectType is missing */
    if (c->key[K_OBJECT_TYPE].line != 0u && !parse_small(c, K_OBJECT_TYPE, 0xFFu, &v)) {
        return false;
    }
    e.object_type = (uint8_t)v;
    const bool var_like = v == LS_CO_OBJECT_VAR || v == LS_CO_OBJECT_DOMAIN || v == LS_CO_OBJECT_DEFTYPE;
    if (!var_like && !is_container(e.object_type)) {
        fail_at(c, c->key[K_OBJECT_TYPE].line,
                "[%s] ObjectType: 0x%X is not an object type; expected 0x7 (VAR), 0x8 "
                "(ARRAY), 0x9 (RECORD), 0x2 (DOMAIN), 0x5 (DEFTYPE) or 0x6 (DEFSTRUCT)",
                c->sec_name, (unsigned)v);
        return false;
    }
    if (e.is_sub && !var_like) {
        fail_at(c, c->key[K_OBJECT_TYPE].line, "[%s] ObjectType: a sub-object is a VAR (0x7), not 0x%X", c->sec_name,
                (unsigned)v);
        return false;
    }
    if (!add_text(c, c->key[K_PARAMETER_NAME].value, c->key[K_PARAMETER_NAME].line, &e.name)) {
        return false;
    }
    if (is_container(e.object_type)) {
        if (c->key[K_SUB_NUMBER].line == 0u) {
            fail_at(c, c->sec_line, "[%s]: no SubNumber (an ARRAY or RECORD names how many sub-objects follow)",
                    c->sec_name);
            return false;
        }
        if (!parse_small(c, K_SUB_NUMBER, 0xFFu, &v)) {
            return false;
        }
        e.sub_number = (uint8_t)v;
        return insert_entry(c, &e);
    }
    if (c->key[K_DATA_TYPE].line == 0u) {
        fail_at(c, c->sec_line, "[%s]: no DataType", c->sec_name);
        return false;
    }
    if (!parse_small(c, K_DATA_TYPE, 0xFFFFu, &v)) {
        return false;
    }
    if (ls_co_type_name((uint16_t)v) == NULL) {
        fail_at(c, c->key[K_DATA_TYPE].line,
                "[%s] DataType: 0x%04X is not a basic data type of CiA 301 (0x0001-0x001B); complex and "
                "manufacturer-specific types are not supported",
                c->sec_name, (unsigned)v);
        return false;
    }
    e.data_type = (uint16_t)v;
    if (c->key[K_ACCESS_TYPE].line == 0u) {
        fail_at(c, c->sec_line, "[%s]: no AccessType", c->sec_name);
        return false;
    }
    if (!parse_access(c, &e.access)) {
        return false;
    }
    if (c->key[K_PDO_MAPPING].line != 0u) {
        if (!parse_small(c, K_PDO_MAPPING, 1u, &v)) {
            return false;
        }
        e.pdo_mapping = v == 1u;
    }
    for (int f = 0; f < LS_EDS_FIELD_COUNT; f++) {
        if (!parse_field(c, &e, (ls_eds_field_id_t)f)) {
            return false;
        }
    }
    if (e.kind[LS_EDS_LOW] == KIND_NUMBER && e.kind[LS_EDS_HIGH] == KIND_NUMBER) {
        bool above;
        const uint64_t lo = e.bits[LS_EDS_LOW];
        const uint64_t hi = e.bits[LS_EDS_HIGH];
        switch (class_of(e.data_type)) {
        case SIGNED: above = as_signed(lo) > as_signed(hi); break;
        case REAL: {
            double a;
            double b;
            memcpy(&a, &lo, sizeof a);
            memcpy(&b, &hi, sizeof b);
            above = a > b;
            break;
        }
        case UNSIGNED:
        case TEXT:
        default: above = lo > hi; break;
        }
        if (above) {
            fail_at(c, c->key[K_LOW_LIMIT].line, "[%s] LowLimit: '%.60s' is above HighLimit '%.60s'", c->sec_name,
                    c->key[K_LOW_LIMIT].value, c->key[K_HIGH_LIMIT].value);
            return false;
        }
    }
    return insert_entry(c, &e);
}

static bool end_device_info(ctx_t *c)
{
    ls_eds_t *eds = c->eds;
    if (c->key[K_VENDOR_NAME].line != 0u && !add_text(c, c->key[K_VENDOR_NAME].value, 0u, &eds->vendor_name)) {
        return false;
    }
    if (c->key[K_PRODUCT_NAME].line != 0u && !add_text(c, c->key[K_PRODUCT_NAME].value, 0u, &eds->product_name)) {
        return false;
    }
    const struct {
        key_t_ k;
        uint8_t flag;
        uint32_t *dst;
    } numbers[] = {
        { K_VENDOR_NUMBER, HAS_VENDOR, &eds->vendor_number },
        { K_PRODUCT_NUMBER, HAS_PRODUCT, &eds->product_number },
        { K_REVISION_NUMBER, HAS_REVISION, &eds->revision_number },
    };
    for (size_t i = 0; i < sizeof numbers / sizeof numbers[0]; i++) {
        if (c->key[numbers[i].k].line == 0u) {
            continue;
        }
        uint64_t v;
        if (!parse_small(c, numbers[i].k, UINT32_MAX, &v)) {
            return false;
        }
        *numbers[i].dst = (uint32_t)v;
        eds->has |= numbers[i].flag;
    }
    return true;
}

/* The section just read is complete. */
static bool end_section(ctx_t *c)
{
    bool ok = true;
    switch (c->sec) {
    case SEC_OBJECT:
    case SEC_SUB: ok = end_object(c); break;
    case SEC_DEVICE_INFO: ok = end_device_info(c); break;
    case SEC_COMMISSIONING:
        if (c->key[K_NODE_ID].line != 0u) {
            uint64_t v = 0u;
            ok = parse_small(c, K_NODE_ID, LS_CO_NODE_MAX, &v);
            if (ok) {
                c->eds->dcf_node_id = (uint8_t)v;
            }
        }
        break;
    case SEC_DUMMY:
        for (unsigned i = 0; ok && i < N_DUMMIES; i++) {
            uint64_t v = 0u;
            if (c->key[K_DUMMY1 + i].line != 0u) {
                ok = parse_small(c, (key_t_)(K_DUMMY1 + i), 1u, &v);
            }
            c->dummy[i] = v == 1u;
        }
        break;
    case SEC_NONE:
    case SEC_OTHER:
    default: break;
    }
    for (int k = 0; k < K_COUNT; k++) {
        c->key[k].line = 0u;
    }
    c->sec = SEC_NONE;
    return ok;
}

/* "[...]" on line c->lineno: what kind of section, and whether it repeats one. */
static bool begin_section(ctx_t *c, const char *name)
{
    const size_t n = strlen(name);
    if (n == 0u || n > SECTION_NAME_MAX) {
        fail_at(c, c->lineno, "[%.*s]: not a section name (1 to %u characters)", (int)(n > 60u ? 60u : n), name,
                (unsigned)SECTION_NAME_MAX);
        return false;
    }
    memcpy(c->sec_name, name, n + 1u);
    c->sec_line = c->lineno;
    c->any_section = true;
    uint16_t index;
    if (hex4(name, &index)) {
        const char *rest = name + 4;
        const ls_eds_entry_t *dup;
        if (*rest == '\0') {
            c->sec = SEC_OBJECT;
            c->sec_index = index;
            c->sec_sub = 0u;
            dup = lookup(c->eds, key_of(index, false, 0u));
        } else if (strncasecmp(rest, "sub", 3) == 0 && rest[3] != '\0' && strlen(rest + 3) <= 2u &&
                   isxdigit((unsigned char)rest[3]) && (rest[4] == '\0' || isxdigit((unsigned char)rest[4]))) {
            const unsigned sub = (unsigned)strtoul(rest + 3, NULL, 16);
            c->sec = SEC_SUB;
            c->sec_index = index;
            c->sec_sub = (uint8_t)sub;
            const ls_eds_entry_t *parent = lookup(c->eds, key_of(index, false, 0u));
            if (parent == NULL) {
                fail_at(c, c->lineno, "[%s]: no [%.4s] section before it (an object's section comes first)", name,
                        name);
                return false;
            }
            if (!is_container(parent->object_type)) {
                fail_at(c, c->lineno, "[%s]: [%.4s] (line %lu) is a VAR, which has no sub-objects", name, name,
                        (unsigned long)parent->line);
                return false;
            }
            dup = lookup(c->eds, key_of(index, true, (uint8_t)sub));
        } else if (strcasecmp(rest, "Name") == 0 || strcasecmp(rest, "Value") == 0 ||
                   strcasecmp(rest, "Denotation") == 0) {
            fail_at(c, c->lineno, "[%s]: compact sub-object sections are not supported; write [%.4ssubN] sections",
                    name, name);
            return false;
        } else {
            fail_at(c, c->lineno, "[%s]: not an object or sub-object section ([XXXX] or [XXXXsubN], hex)", name);
            return false;
        }
        if (dup != NULL) {
            fail_at(c, c->lineno, "[%s]: duplicate section (first on line %lu); keep one", name,
                    (unsigned long)dup->line);
            return false;
        }
        if (index == 0u) {
            fail_at(c, c->lineno, "[%s]: index 0x0000 is no object", name);
            return false;
        }
        return true;
    }
    for (unsigned i = 0; i < c->n_other; i++) {
        if (strcasecmp(c->other[i].name, name) == 0) {
            fail_at(c, c->lineno, "[%s]: duplicate section (first on line %lu); keep one", name,
                    (unsigned long)c->other[i].line);
            return false;
        }
    }
    if (c->n_other >= MAX_OTHER_SECTIONS) {
        fail_at(c, c->lineno, "[%s]: more than %u sections that are not objects", name, (unsigned)MAX_OTHER_SECTIONS);
        return false;
    }
    memcpy(c->other[c->n_other].name, name, n + 1u);
    c->other[c->n_other].line = c->lineno;
    c->n_other++;
    if (strcasecmp(name, "DeviceInfo") == 0) {
        c->sec = SEC_DEVICE_INFO;
        c->device_info = true;
    } else if (strcasecmp(name, "DeviceComissioning") == 0) { /* CiA 306's spelling */
        c->sec = SEC_COMMISSIONING;
    } else if (strcasecmp(name, "DummyUsage") == 0) {
        c->sec = SEC_DUMMY;
    } else {
        c->sec = SEC_OTHER;
    }
    return true;
}

/* ---- Lines ---------------------------------------------------------------- */

#define END_OF_SOURCE (-1) /* next_byte: no byte left */

/* One byte of the source; END_OF_SOURCE at its end (or after a read error). */
static int next_byte(ctx_t *c)
{
    if (c->buf_pos < c->buf_len) {
        return (unsigned char)c->buf[c->buf_pos++];
    }
    if (c->fd < 0) {
        return END_OF_SOURCE;
    }
    ssize_t n;
    do {
        n = read(c->fd, c->chunk, sizeof c->chunk);
    } while (n < 0 && errno == EINTR);
    if (n <= 0) {
        if (n < 0) {
            c->read_failed = true;
            c->read_errno = errno;
        }
        c->fd = -1;
        return END_OF_SOURCE;
    }
    c->buf = c->chunk;
    c->buf_len = (size_t)n;
    c->buf_pos = 0u;
    return (unsigned char)c->buf[c->buf_pos++];
}

/* The next line into c->line without its end; false at the end of the
 * source or on an error (then c->failed). */
static bool next_line(ctx_t *c)
{
    size_t n = 0u;
    int ch = next_byte(c);
    if (ch < 0) {
        return false;
    }
    c->lineno++;
    for (; ch >= 0 && ch != '\n'; ch = next_byte(c)) {
        if (ch == '\0') {
            fail_at(c, c->lineno, "a NUL byte: this is binary data, not a text file");
            return false;
        }
        if (n >= LS_EDS_LINE_MAX) {
            fail_at(c, c->lineno, "line longer than %u characters", (unsigned)LS_EDS_LINE_MAX);
            return false;
        }
        c->line[n++] = (char)ch;
    }
    if (n > 0u && c->line[n - 1u] == '\r') {
        n--;
    }
    c->line[n] = '\0';
    return true;
}

/* inih's reader: one line per call, checked first. Leading blanks are
 * dropped so that inih never takes an indented line as the continuation
 * of the previous value. */
static char *reader(char *str, int num, void *stream)
{
    ctx_t *c = stream;
    if (c->failed) {
        return NULL;
    }
    if (!next_line(c)) {
        if (!c->failed) {
            (void)end_section(c); /* the end of the file ends the last section */
        }
        return NULL;
    }
    char *s = c->line;
    if (c->lineno == 1u && strncmp(s, "\xEF\xBB\xBF", 3) == 0) {
        s += 3; /* UTF-8 byte order mark */
    }
    while (*s == ' ' || *s == '\t') {
        s++;
    }
    const size_t room = num > 2 ? (size_t)num - 2u : 0u; /* characters that fit with '\n' and NUL */
    if (*s == '\0' || *s == ';' || *s == '#') {
        str[0] = '\n';
        str[1] = '\0';
        return str;
    }
    if (*s == '[') {
        if (!end_section(c)) {
            return NULL;
        }
        char *close = strchr(s, ']');
        if (close == NULL) {
            fail_at(c, c->lineno, "'%.60s': a section header without ']'", s);
            return NULL;
        }
        for (const char *p = close + 1; *p != '\0'; p++) {
            if (*p == ';' || *p == '#') {
                break;
            }
            if (*p != ' ' && *p != '\t') {
                fail_at(c, c->lineno, "'%.60s': text after the section header", s);
                return NULL;
            }
        }
        *close = '\0';
        char *name = s + 1;
        while (*name == ' ' || *name == '\t') {
            name++;
        }
        size_t n = strlen(name);
        while (n > 0u && (name[n - 1u] == ' ' || name[n - 1u] == '\t')) {
            name[--n] = '\0';
        }
        if (!begin_section(c, name)) {
            return NULL;
        }
        (void)snprintf(str, (size_t)num, "[%s]\n", name);
        return str;
    }
    const size_t key_len = strcspn(s, "=:");
    if (s[key_len] == '\0') {
        fail_at(c, c->lineno, "%s%s%s'%.60s' is neither [section], key=value nor a ; comment",
                c->sec != SEC_NONE ? "[" : "", c->sec != SEC_NONE ? c->sec_name : "", c->sec != SEC_NONE ? "]: " : "",
                s);
        return NULL;
    }
    if (c->sec == SEC_NONE) {
        fail_at(c, c->lineno, "'%.60s': a key outside any section", s);
        return NULL;
    }
    if (key_len == 0u) {
        fail_at(c, c->lineno, "[%s]: '%.60s' has no key before its '%c'", c->sec_name, s, s[0]);
        return NULL;
    }
    size_t len = strlen(s);
    if (len > room) {
        /* Too long for inih's buffer: refused for a key that is read,
         * cut for one that is skipped (its value is not used). */
        char key[64];
        size_t kl = key_len < sizeof key - 1u ? key_len : sizeof key - 1u;
        memcpy(key, s, kl);
        while (kl > 0u && (key[kl - 1u] == ' ' || key[kl - 1u] == '\t')) {
            kl--;
        }
        key[kl] = '\0';
        for (int k = 0; k < K_COUNT; k++) {
            if (strcasecmp(key, KEYS[k].name) == 0) {
                fail_at(c, c->lineno, "[%s] %s: longer than %u characters", c->sec_name, key, (unsigned)room);
                return NULL;
            }
        }
        len = room;
    }
    memcpy(str, s, len);
    str[len] = '\n';
    str[len + 1u] = '\0';
    return str;
}

static bool key_applies(key_t_ k, sec_kind_t sec)
{
    if (KEYS[k].section == SEC_OBJECT) {
        return sec == SEC_OBJECT || sec == SEC_SUB;
    }
    return KEYS[k].section == sec;
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    (void)section; /* the reader keeps the section: inih cuts long names */
    ctx_t *c = user;
    if (c->failed) {
        return 0;
    }
    for (int k = 0; k < K_COUNT; k++) {
        if (!key_applies((key_t_)k, c->sec) || strcasecmp(name, KEYS[k].name) != 0) {
            continue;
        }
        if (c->key[k].line != 0u) {
            fail_at(c, c->lineno, "[%s] %s: given twice (first on line %lu); keep one", c->sec_name, KEYS[k].name,
                    (unsigned long)c->key[k].line);
            return 0;
        }
        c->key[k].line = c->lineno;
        (void)snprintf(c->key[k].value, sizeof c->key[k].value, "%s", value);
        return 1;
    }
    return 1; /* a key this parser does not read */
}

/* ---- Load ------------------------------------------------------------------ */

static void clear(ls_eds_t *eds)
{
    eds->n_entries = 0u;
    eds->text_used = 1u; /* offset 0 is "" */
    eds->text[0] = '\0';
    eds->vendor_name = 0u;
    eds->product_name = 0u;
    eds->vendor_number = 0u;
    eds->product_number = 0u;
    eds->revision_number = 0u;
    eds->has = 0u;
    eds->dcf_node_id = 0u;
}

static bool finish(ctx_t *c)
{
    ls_eds_t *eds = c->eds;
    for (unsigned i = 0; i < N_DUMMIES; i++) {
        const uint16_t index = (uint16_t)(i + 1u);
        if (!c->dummy[i] || lookup(eds, key_of(index, false, 0u)) != NULL) {
            continue;
        }
        ls_eds_entry_t e;
        memset(&e, 0, sizeof e);
        e.index = index;
        e.object_type = LS_CO_OBJECT_VAR;
        e.data_type = index; /* Dummy000N stands for data type N */
        e.access = LS_EDS_CONST;
        e.pdo_mapping = true;
        (void)snprintf(c->sec_name, sizeof c->sec_name, "DummyUsage");
        char name[16];
        (void)snprintf(name, sizeof name, "Dummy%04u", (unsigned)index);
        if (!add_text(c, name, 0u, &e.name) || !insert_entry(c, &e)) {
            return false;
        }
    }
    /* Each ARRAY and RECORD has as many sub-objects as its SubNumber says. */
    for (size_t i = 0; i < eds->n_entries; i++) {
        const ls_eds_entry_t *h = &eds->entries[i];
        if (h->is_sub || !is_container(h->object_type)) {
            continue;
        }
        size_t n = 0u;
        while (i + 1u + n < eds->n_entries && eds->entries[i + 1u + n].index == h->index) {
            n++;
        }
        if (n != h->sub_number) {
            c->any_section = true;
            fail_at(c, h->line, "[%04X] SubNumber: %u sub-objects announced, %zu found", (unsigned)h->index,
                    (unsigned)h->sub_number, n);
            return false;
        }
    }
    if (!c->device_info) {
        c->any_section = false;
        fail_at(c, 0u, "no [DeviceInfo] section");
        return false;
    }
    if (eds->n_entries == 0u) {
        c->any_section = false;
        fail_at(c, 0u, "no object sections ([1000], [1018sub1], ...)");
        return false;
    }
    return true;
}

static int load(ctx_t *c)
{
    clear(c->eds);
    if (c->msg != NULL && c->msg_cap > 0u) {
        c->msg[0] = '\0';
    }
    const int r = ini_parse_stream(reader, c, handler, c);
    if (c->read_failed) {
        c->failed = false;
        c->any_section = true;
        if (c->lineno == 0u) {
            fail_at(c, 0u, "cannot read: %s", strerror(c->read_errno));
        } else {
            fail_at(c, 0u, "cannot read after line %lu: %s", (unsigned long)c->lineno, strerror(c->read_errno));
        }
        clear(c->eds);
        return LS_EIO;
    }
    if (!c->failed && r > 0) {
        fail_at(c, (uint32_t)r, "syntax error: expected [section], key=value or a ; comment");
    } else if (!c->failed && r < 0) {
        fail_at(c, 0u, "the INI reader failed (%d)", r);
    }
    if (!c->failed) {
        (void)finish(c);
    }
    if (c->failed) {
        clear(c->eds);
        return LS_EINVAL;
    }
    return LS_OK;
}

/* A message outside a load (no context yet). */
static void say(char *msg, size_t msg_cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void say(char *msg, size_t msg_cap, const char *fmt, ...)
{
    if (msg != NULL && msg_cap > 0u) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(msg, msg_cap, fmt, ap);
        va_end(ap);
    }
}

/* One load from a file descriptor (fd >= 0) or from memory. The context is
 * large (its line buffers): one per call, on the stack of an init-time
 * caller. */
static int load_from(ls_eds_t *eds, const char *name, int fd, const char *data, size_t len, char *msg, size_t msg_cap)
{
    ctx_t c;
    memset(&c, 0, sizeof c);
    c.eds = eds;
    c.name = name;
    c.msg = msg;
    c.msg_cap = msg_cap;
    c.fd = fd;
    c.buf = data;
    c.buf_len = len;
    return load(&c);
}

int ls_eds_load_buffer(ls_eds_t *eds, const char *name, const char *data, size_t len, char *msg, size_t msg_cap)
{
    if (eds == NULL || name == NULL || (data == NULL && len > 0u)) {
        say(msg, msg_cap, "ls_eds_load_buffer: a NULL argument");
        return LS_EINVAL;
    }
    return load_from(eds, name, -1, data, len, msg, msg_cap);
}

int ls_eds_load(ls_eds_t *eds, const char *path, char *msg, size_t msg_cap)
{
    if (eds == NULL || path == NULL) {
        say(msg, msg_cap, "ls_eds_load: a NULL argument");
        return LS_EINVAL;
    }
    int fd;
    do {
        fd = open(path, O_RDONLY | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    if (fd < 0) {
        clear(eds);
        say(msg, msg_cap, "%s: cannot read: %s (give the path of the drive's EDS or DCF file)", path, strerror(errno));
        return LS_EIO;
    }
    const int r = load_from(eds, path, fd, NULL, 0u, msg, msg_cap);
    (void)close(fd);
    return r;
}

/* ---- Queries --------------------------------------------------------------- */

const ls_eds_entry_t *ls_eds_find(const ls_eds_t *eds, uint16_t index, uint8_t sub)
{
    if (eds == NULL) {
        return NULL;
    }
    const ls_eds_entry_t *e = lookup(eds, key_of(index, true, sub));
    if (e == NULL && sub == 0u) {
        e = lookup(eds, key_of(index, false, 0u));
        if (e != NULL && is_container(e->object_type)) {
            e = NULL;
        }
    }
    return e;
}

const ls_eds_entry_t *ls_eds_object(const ls_eds_t *eds, uint16_t index)
{
    return eds == NULL ? NULL : lookup(eds, key_of(index, false, 0u));
}

size_t ls_eds_count(const ls_eds_t *eds)
{
    return eds == NULL ? 0u : eds->n_entries;
}

const ls_eds_entry_t *ls_eds_at(const ls_eds_t *eds, size_t i)
{
    return eds == NULL || i >= eds->n_entries ? NULL : &eds->entries[i];
}

static const char *text_at(const ls_eds_t *eds, uint64_t off)
{
    return off < eds->text_used ? eds->text + off : "";
}

const char *ls_eds_name(const ls_eds_t *eds, const ls_eds_entry_t *e)
{
    return eds == NULL || e == NULL ? "" : text_at(eds, e->name);
}

bool ls_eds_readable(const ls_eds_entry_t *e)
{
    return e != NULL && e->access != LS_EDS_ACCESS_NONE && e->access != LS_EDS_WO;
}

bool ls_eds_writable(const ls_eds_entry_t *e)
{
    return e != NULL &&
           (e->access == LS_EDS_WO || e->access == LS_EDS_RW || e->access == LS_EDS_RWR || e->access == LS_EDS_RWW);
}

bool ls_eds_mappable(const ls_eds_entry_t *e)
{
    return e != NULL && e->pdo_mapping && e->data_type != 0u;
}

const char *ls_eds_access_name(uint8_t access)
{
    switch (access) {
    case LS_EDS_RO: return "ro";
    case LS_EDS_WO: return "wo";
    case LS_EDS_RW: return "rw";
    case LS_EDS_RWR: return "rwr";
    case LS_EDS_RWW: return "rww";
    case LS_EDS_CONST: return "const";
    default: return "";
    }
}

unsigned ls_eds_size(const ls_eds_entry_t *e)
{
    return e == NULL ? 0u : ls_co_type_size(e->data_type);
}

int ls_eds_field(const ls_eds_t *eds, const ls_eds_entry_t *e, ls_eds_field_id_t field, uint8_t node_id,
                 ls_eds_value_t *v)
{
    if (eds == NULL || e == NULL || v == NULL || (unsigned)field >= (unsigned)LS_EDS_FIELD_COUNT ||
        node_id < LS_CO_NODE_MIN || node_id > LS_CO_NODE_MAX) {
        return LS_EINVAL;
    }
    ls_eds_value_t out = { .kind = LS_EDS_VALUE_NONE, .text = "" };
    const uint8_t kind = e->kind[field];
    uint64_t bits = e->bits[field];
    if (kind == KIND_RELATIVE) {
        out.node_relative = true;
        bits += node_id; /* fits for every node id: checked at load */
    }
    if (kind == KIND_TEXT) {
        out.kind = LS_EDS_VALUE_TEXT;
        out.text = text_at(eds, bits);
    } else if (kind == KIND_NUMBER || kind == KIND_RELATIVE) {
        switch (class_of(e->data_type)) {
        case SIGNED:
            out.kind = LS_EDS_VALUE_INT;
            out.i = as_signed(bits);
            break;
        case REAL:
            out.kind = LS_EDS_VALUE_REAL;
            memcpy(&out.r, &bits, sizeof out.r);
            break;
        case UNSIGNED:
        case TEXT:
        default:
            out.kind = LS_EDS_VALUE_UINT;
            out.u = bits;
            break;
        }
    }
    *v = out;
    return LS_OK;
}

int ls_eds_value(const ls_eds_t *eds, const ls_eds_entry_t *e, uint8_t node_id, ls_eds_value_t *v)
{
    if (e != NULL && e->kind[LS_EDS_PARAMETER] != KIND_NONE) {
        return ls_eds_field(eds, e, LS_EDS_PARAMETER, node_id, v);
    }
    return ls_eds_field(eds, e, LS_EDS_DEFAULT, node_id, v);
}

int ls_eds_device(const ls_eds_t *eds, ls_eds_device_t *out)
{
    if (eds == NULL || out == NULL) {
        return LS_EINVAL;
    }
    *out = (ls_eds_device_t){
        .vendor_name = text_at(eds, eds->vendor_name),
        .product_name = text_at(eds, eds->product_name),
        .vendor_number = eds->vendor_number,
        .product_number = eds->product_number,
        .revision_number = eds->revision_number,
        .has_vendor_number = (eds->has & HAS_VENDOR) != 0u,
        .has_product_number = (eds->has & HAS_PRODUCT) != 0u,
        .has_revision_number = (eds->has & HAS_REVISION) != 0u,
        .dcf_node_id = eds->dcf_node_id,
    };
    return LS_OK;
}
