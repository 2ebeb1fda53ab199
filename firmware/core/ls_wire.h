/* Why an uplink did not decode, named: nanopb refuses a message whose
 * repeated field has more items, or whose string or bytes field more bytes,
 * than the static sizes of protocol/landscape.options, with "array overflow"
 * or "string overflow" and no field, and an integer its field's type cannot
 * hold (a -1 sent for an enum of no negative values) with "integer too
 * large". ls_wire_find_overflow reads the same bytes against the descriptor
 * and names the field and its limit.
 *
 * Comms thread, after a failed pb_decode. No allocation; O(len) plus one
 * descriptor search per field met; at most 8 levels of nesting. */
#ifndef LS_WIRE_H
#define LS_WIRE_H

#include <pb.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum {
    LS_WIRE_FITS = 0, /* every field fits (or the bytes do not parse) */
    LS_WIRE_SIZE,     /* a repeated, string or bytes field over its static size */
    LS_WIRE_RANGE,    /* an integer its field's type cannot hold */
} ls_wire_fault_t;

/* Walk buf[0..len) as message `desc`; `scratch` is any instance of that
 * message type (only its layout is used: nothing is written or read through
 * it). On a fault `where` says which field and its limit
 * ("request.path_load.tags[0].joints has 25 values, at most 24";
 * "request.signal_digital_io.callback_type is -1, outside 0..4294967295"). */
ls_wire_fault_t ls_wire_find_overflow(const pb_msgdesc_t *desc, const void *scratch, const uint8_t *buf, size_t len,
                                      char *where, size_t cap);

#endif
