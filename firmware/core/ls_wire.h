/* Why an uplink did not decode, named: nanopb refuses a message whose
 * repeated field has more items, or whose string or bytes field more bytes,
 * than the static sizes of protocol/landscape.options, with "array overflow"
 * or "string overflow" and no field. ls_wire_find_overflow reads the same
 * bytes against the descriptor and names the field and its limit.
 *
 * Comms thread, after a failed pb_decode. No allocation; O(len) plus one
 * descriptor search per field met; at most 8 levels of nesting. */
#ifndef LS_WIRE_H
#define LS_WIRE_H

#include <pb.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Walk buf[0..len) as message `desc`; `scratch` is any instance of that
 * message type (only its layout is used: nothing is written or read through
 * it). True when a field exceeds its static size: `where` then says which
 * and the limit ("request.path_load.tags[0].joints has 25 values, at most
 * 24"). False when every field fits (or the bytes do not parse). */
bool ls_wire_find_overflow(const pb_msgdesc_t *desc, const void *scratch, const uint8_t *buf, size_t len, char *where,
                           size_t cap);

#endif
