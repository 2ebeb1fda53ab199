/* The simulated drive's object dictionary: the static table gen_od.py
 * derives from ls-simdrive.eds (sd_od_table.h, one entry per object and
 * sub-index) and the values one node holds for it.
 *
 * Values are kept as int64_t whatever the data type (signed types sign-,
 * unsigned ones zero-extended); strings in a fixed store per node. Nothing
 * here knows what an object means: the checks are the EDS's (access, type
 * size, low/high limits); the rules of the communication and drive
 * profiles live in sd_node.c and sd_drive.c.
 *
 * Portable: no OS calls, no allocation, no clock. Any thread that owns the
 * node. Abort codes are CiA 301's (ls_canopen.h LS_CO_ABORT_*), 0 for
 * success: they go on the bus as they are, so they are not ls_err codes. */
#ifndef SD_OD_H
#define SD_OD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define SD_OD_STRING_MAX 32u /* bytes of a VISIBLE_STRING value (gen_od.py STRING_MAX) */

/* EDS AccessType. */
typedef enum {
    SD_OD_ACCESS_RO,
    SD_OD_ACCESS_WO,
    SD_OD_ACCESS_RW,
    SD_OD_ACCESS_RWR, /* read/write, mappable into TPDOs */
    SD_OD_ACCESS_RWW, /* read/write, mappable into RPDOs */
    SD_OD_ACCESS_CONST,
} sd_od_access_t;

#define SD_OD_F_PDO 0x01u    /* PDOMapping=1 */
#define SD_OD_F_NODEID 0x02u /* DefaultValue=$NODEID+...: the node id is added at reset */

typedef struct {
    uint16_t index;
    uint8_t sub;
    uint8_t access; /* sd_od_access_t */
    uint16_t type;  /* LS_CO_TYPE_* */
    uint8_t flags;  /* SD_OD_F_* */
    uint8_t str_slot;
    int64_t def, low, high; /* numbers; low/high are the type's range unless the EDS narrows it */
    const char *def_str;    /* strings; NULL for numbers */
    const char *name;       /* ParameterName */
} sd_od_entry_t;

#include "sd_od_table.h"

typedef struct {
    int64_t val[SD_OD_N_ENTRIES];
    char str[SD_OD_N_STRINGS > 0 ? SD_OD_N_STRINGS : 1][SD_OD_STRING_MAX];
    uint8_t str_len[SD_OD_N_STRINGS > 0 ? SD_OD_N_STRINGS : 1];
} sd_od_t;

/* The entry of (index, sub): its position in sd_od_table (>= 0), or
 * LS_EINVAL with *abort = LS_CO_ABORT_NO_OBJECT (no such index) or
 * LS_CO_ABORT_NO_SUB (the index exists, the sub-index does not). O(log n). */
int sd_od_find(uint16_t index, uint8_t sub, uint32_t *abort);

/* Not an entry: an optional object the EDS does not have. */
#define SD_OD_NONE (-1)

/* The entry or SD_OD_NONE, for objects the caller may lack (optional ones). */
int sd_od_lookup(uint16_t index, uint8_t sub);

/* Restore the EDS defaults of every entry whose index lies in [from, to],
 * adding node_id where the default is $NODEID-relative. */
void sd_od_reset(sd_od_t *od, uint8_t node_id, uint16_t from, uint16_t to);

/* Bytes of the entry's value: the type's size, a string's current length. */
size_t sd_od_size(const sd_od_t *od, int entry);

/* True for a fixed-size (numeric) entry. */
bool sd_od_is_number(int entry);

bool sd_od_readable(int entry);
bool sd_od_writable(int entry);

/* Little-endian bytes of the entry's value into buf (cap >= its size);
 * *len = the size. 0, or LS_CO_ABORT_GENERAL when buf is too small. */
uint32_t sd_od_get_bytes(const sd_od_t *od, int entry, uint8_t *buf, size_t cap, size_t *len);

/* The value `len` bytes encode for the entry, checked against its type's
 * size (LS_CO_ABORT_TYPE_LEN_HIGH / _LOW; strings: at most
 * SD_OD_STRING_MAX) and its limits (LS_CO_ABORT_VALUE_HIGH / _LOW).
 * Numbers land in *value; strings are only checked. 0 or the abort code;
 * *value untouched on error. */
uint32_t sd_od_decode(int entry, const uint8_t *buf, size_t len, int64_t *value);

/* Store a decoded value (no checks: sd_od_decode made them). */
void sd_od_set(sd_od_t *od, int entry, int64_t value);
/* Store a string of len <= SD_OD_STRING_MAX bytes (longer is cut). */
void sd_od_set_string(sd_od_t *od, int entry, const uint8_t *buf, size_t len);

/* Bits of a mapped entry as a PDO carries it (type size x 8; 0 for strings). */
unsigned sd_od_bits(int entry);

/* Little-endian packing of a numeric value into `bytes` bytes, and back
 * (sign-extended for signed types). */
void sd_od_pack(int64_t value, uint8_t *out, size_t bytes);
int64_t sd_od_unpack(int entry, const uint8_t *in);

#endif
