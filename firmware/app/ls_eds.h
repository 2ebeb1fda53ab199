/* A drive's own description: CiA 306 electronic data sheets (EDS) and
 * device configuration files (DCF), read at start-up so that the drive
 * master writes only what a drive lists as writable, maps only what it lists
 * as mappable and checks the drive's identity against its file
 * (docs/deploy.md, "Drives").
 *
 * What is read:
 *  - [DeviceInfo]: VendorName, VendorNumber, ProductName, ProductNumber,
 *    RevisionNumber; a DCF's [DeviceComissioning] NodeID.
 *  - Objects [1018] and sub-objects [1018sub1] (index and sub-index in
 *    hex): ParameterName, ObjectType (VAR when absent), DataType,
 *    AccessType (ro, wo, rw, rwr, rww, const), PDOMapping, DefaultValue,
 *    ParameterValue (a DCF's configured value: it wins over DefaultValue),
 *    LowLimit, HighLimit, SubNumber. Other keys (ObjFlags, Denotation, ...)
 *    and other sections ([FileInfo], [Comments], ...) are skipped.
 *  - [DummyUsage]: DummyNNNN=1 adds a mappable VAR at index N, sub 0, as
 *    CiA 306 says (the placeholders a PDO maps to skip bytes).
 *  - Numbers in decimal, 0x hex or 0-prefixed octal, with a '-' for signed
 *    types; hex and octal give signed types their two's complement
 *    (0xFD in an INTEGER8 is -3). Integer values may be relative to the
 *    node id: "$NODEID+0x180", "0x180+$NODEID" or "$NODEID", resolved per
 *    node by ls_eds_value; at load they must fit their type for every node
 *    id, 1 to 127. REAL32/REAL64 values are decimal; strings and DOMAIN
 *    values are kept as written.
 * Refused, with one line "FILE:LINE: [section] key: what is wrong":
 *  - a file that is not an EDS or DCF (no [DeviceInfo], no object; binary
 *    data; a line that is neither [section], key=value nor a comment);
 *  - a malformed number or one that does not fit its data type; an unknown
 *    access type, object type or data type (only CiA 301's basic types;
 *    complex and manufacturer types need sections this parser does not
 *    read); a LowLimit above its HighLimit;
 *  - a duplicate section or a key given twice in one section;
 *  - a sub-object before its object, under a VAR, or more or fewer
 *    sub-objects than the object's SubNumber;
 *  - CompactSubObj and the [XXXXName]/[XXXXValue] sections that go with it
 *    (neither vendor file of the drives this was written for uses them);
 *  - more than LS_EDS_MAX_ENTRIES objects and sub-objects, names and texts
 *    beyond LS_EDS_TEXT_BYTES, a line beyond LS_EDS_LINE_MAX characters.
 * A value outside its own LowLimit/HighLimit is not refused: vendor files
 * do that, and the drive has the last word when the master writes.
 *
 * The INI syntax is inih's (libinih, as firmware/app/ls_config.c): keys
 * and values are trimmed, ';' after a blank starts a comment, a key is
 * split from its value at the first '=' or ':'. Key, section and hex digit
 * case does not matter.
 *
 * Init-time only (load reads a file); the queries are O(log n) or O(1), no
 * allocation, usable from any thread once loaded. The table is the
 * caller's (about 180 KiB: declare it static); nothing here allocates,
 * not even stdio's buffers (the file is read with read(2) in 4 KiB
 * pieces). Not thread-safe while loading. */
#ifndef LS_EDS_H
#define LS_EDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_err.h"

#define LS_EDS_MAX_ENTRIES 2048u /* objects + sub-objects: the EPOS4 DCF has 661 */
#define LS_EDS_TEXT_BYTES 65536u /* names and text values, NUL-terminated: the EPOS4 DCF needs 19 KiB */
#define LS_EDS_LINE_MAX 1024u    /* characters in a line, without its end */
#define LS_EDS_MSG_MAX 512u      /* holds every message line for a path under 100 characters */

typedef enum {
    LS_EDS_ACCESS_NONE = 0, /* ARRAY and RECORD objects themselves */
    LS_EDS_RO,
    LS_EDS_WO,
    LS_EDS_RW,
    LS_EDS_RWR, /* read-write, mapped into TPDOs (read) */
    LS_EDS_RWW, /* read-write, mapped into RPDOs (written) */
    LS_EDS_CONST,
} ls_eds_access_t;

/* The values an entry may carry, by field. */
typedef enum {
    LS_EDS_DEFAULT = 0, /* DefaultValue */
    LS_EDS_PARAMETER,   /* ParameterValue (DCF) */
    LS_EDS_LOW,         /* LowLimit */
    LS_EDS_HIGH,        /* HighLimit */
    LS_EDS_FIELD_COUNT
} ls_eds_field_id_t;

/* One object ([1018]) or sub-object ([1018sub1]). Plain data inside its
 * table; read it through the functions below. */
typedef struct {
    uint16_t index;
    uint8_t sub;         /* 0 for an object's own section */
    bool is_sub;         /* declared as [XXXXsubN] */
    uint8_t object_type; /* LS_CO_OBJECT_VAR, _ARRAY, _RECORD, _DOMAIN, _DEFTYPE, _DEFSTRUCT */
    uint8_t access;      /* ls_eds_access_t */
    bool pdo_mapping;    /* PDOMapping=1 */
    uint8_t sub_number;  /* ARRAY/RECORD/DEFSTRUCT: SubNumber */
    uint16_t data_type;  /* LS_CO_TYPE_*; 0 for ARRAY/RECORD/DEFSTRUCT */
    uint32_t line;       /* the line of its section header */
    uint32_t name;       /* private: offset of ParameterName in the table's text */
    uint8_t kind[LS_EDS_FIELD_COUNT];
    uint64_t bits[LS_EDS_FIELD_COUNT];
} ls_eds_entry_t;

/* A loaded file. Private fields: use the functions. */
typedef struct {
    uint32_t n_entries;
    ls_eds_entry_t entries[LS_EDS_MAX_ENTRIES]; /* sorted: object, then its sub-objects by sub-index */
    uint32_t text_used;
    char text[LS_EDS_TEXT_BYTES];
    uint32_t vendor_name, product_name; /* text offsets; 0 = "" */
    uint32_t vendor_number, product_number, revision_number;
    uint8_t has; /* which numbers were given */
    uint8_t dcf_node_id;
} ls_eds_t;

/* Load a file (init time). On success returns LS_OK with the table filled
 * and msg set to "". On failure the table is left empty (never half
 * loaded) and msg holds one line, cut to msg_cap (values are quoted up to
 * 60 characters, so LS_EDS_MSG_MAX holds any line for a path under 100
 * characters): LS_EIO when the file cannot be read ("FILE: cannot read:
 * No such file or directory"), LS_EINVAL when its content is refused (the
 * list above) or an argument is NULL. Cost: O(file size + n log n) for the
 * lookups, O(n) per out-of-order section to keep the table sorted. */
int ls_eds_load(ls_eds_t *eds, const char *path, char *msg, size_t msg_cap);

/* The same from memory (the fuzzer's entry, tests): `len` bytes of `data`
 * (no NUL needed; a NUL byte inside is refused as binary data), called
 * `name` in messages. */
int ls_eds_load_buffer(ls_eds_t *eds, const char *name, const char *data, size_t len, char *msg, size_t msg_cap);

/* The entry of (index, sub): a sub-object, or for sub 0 a VAR object's own
 * section; NULL when the file does not list it (and for an ARRAY or RECORD
 * itself: see ls_eds_object). O(log n). */
const ls_eds_entry_t *ls_eds_find(const ls_eds_t *eds, uint16_t index, uint8_t sub);

/* The object's own section [XXXX] (a VAR, ARRAY, RECORD, ...); NULL when
 * absent. O(log n). */
const ls_eds_entry_t *ls_eds_object(const ls_eds_t *eds, uint16_t index);

/* Every entry in order (objects before their sub-objects): i < count. */
size_t ls_eds_count(const ls_eds_t *eds);
const ls_eds_entry_t *ls_eds_at(const ls_eds_t *eds, size_t i);

/* ParameterName; "" for NULL. Valid while the table is. */
const char *ls_eds_name(const ls_eds_t *eds, const ls_eds_entry_t *e);

/* The access rules (false for NULL and for ARRAY/RECORD headers):
 * readable: ro, rw, rwr, rww, const; writable: wo, rw, rwr, rww;
 * mappable: PDOMapping=1 on an entry with a data type. */
bool ls_eds_readable(const ls_eds_entry_t *e);
bool ls_eds_writable(const ls_eds_entry_t *e);
bool ls_eds_mappable(const ls_eds_entry_t *e);

/* "ro", "wo", "rw", "rwr", "rww", "const"; "" for none. */
const char *ls_eds_access_name(uint8_t access);

/* The entry's size in bytes (ls_co_type_size of its data type): 0 for
 * strings, DOMAIN and headers. */
unsigned ls_eds_size(const ls_eds_entry_t *e);

typedef enum {
    LS_EDS_VALUE_NONE = 0, /* the file gives no value */
    LS_EDS_VALUE_INT,      /* signed integer types: .i */
    LS_EDS_VALUE_UINT,     /* BOOLEAN, unsigned, TIME types: .u */
    LS_EDS_VALUE_REAL,     /* REAL32, REAL64: .r */
    LS_EDS_VALUE_TEXT,     /* strings, DOMAIN: .text */
} ls_eds_value_kind_t;

typedef struct {
    ls_eds_value_kind_t kind;
    bool node_relative; /* written with $NODEID: resolved for the node asked */
    int64_t i;
    uint64_t u;
    double r;
    const char *text; /* into the table; "" unless TEXT */
} ls_eds_value_t;

/* One field of an entry for `node_id` (1..127). Returns LS_OK (kind NONE
 * when the file does not give the field), or LS_EINVAL (a NULL pointer,
 * node_id out of range, a field out of range); *v untouched on error.
 * O(1). */
int ls_eds_field(const ls_eds_t *eds, const ls_eds_entry_t *e, ls_eds_field_id_t field, uint8_t node_id,
                 ls_eds_value_t *v);

/* The value a drive built from this file holds at power-on:
 * ParameterValue when given, else DefaultValue. As ls_eds_field. */
int ls_eds_value(const ls_eds_t *eds, const ls_eds_entry_t *e, uint8_t node_id, ls_eds_value_t *v);

typedef struct {
    const char *vendor_name;  /* "" when absent */
    const char *product_name; /* "" when absent */
    uint32_t vendor_number, product_number, revision_number;
    bool has_vendor_number, has_product_number, has_revision_number;
    uint8_t dcf_node_id; /* [DeviceComissioning] NodeID; 0 when absent */
} ls_eds_device_t;

/* [DeviceInfo] and the DCF's node id. Returns LS_OK or LS_EINVAL (NULL). */
int ls_eds_device(const ls_eds_t *eds, ls_eds_device_t *out);

#endif
