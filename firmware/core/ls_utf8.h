/* UTF-8 on the wire (docs/protocol.md "Strings"): the device checks every
 * string it receives and only ever sends valid UTF-8.
 *
 * Valid means RFC 3629: no overlong forms, no surrogates (U+D800..U+DFFF),
 * nothing above U+10FFFF. No allocation; comms thread. */
#ifndef LS_UTF8_H
#define LS_UTF8_H

#include <pb.h>
#include <stdbool.h>
#include <stddef.h>

/* Index of the first byte of s[0..len) that does not start a complete valid
 * sequence, or len when all of it is valid. */
size_t ls_utf8_check(const char *s, size_t len);

/* Make the NUL-terminated s valid in place by dropping every byte that is not
 * part of a complete valid sequence (a character cut by a truncation
 * disappears whole). Returns the number of bytes dropped. */
size_t ls_utf8_repair(char *s);

/* Every string field of the nanopb message msg (oneofs: the member set;
 * repeated: each element; submessages: recursively) is valid UTF-8. When one
 * is not: false, and `where` names it ("path_load.tags[2].tag_name at byte
 * 5"). */
bool ls_utf8_check_msg(const pb_msgdesc_t *desc, const void *msg, char *where, size_t where_cap);

/* ls_utf8_repair on every string field of msg (what the device sends). */
void ls_utf8_repair_msg(const pb_msgdesc_t *desc, void *msg);

#endif
