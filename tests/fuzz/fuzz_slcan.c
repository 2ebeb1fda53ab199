/* SLCAN lines from a supervisor (or a hostile serial peer): lexer + parser +
 * formatter round trip. */
#include <stdint.h>
#include <string.h>

#include "slcan_codec.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ls_slcan_lexer_t lx;
    ls_slcan_lexer_init(&lx);
    for (size_t i = 0; i < size; i++) {
        size_t len = 0;
        if (!ls_slcan_lexer_feed(&lx, (char)data[i], &len)) {
            continue;
        }
        if (len > sizeof lx.buf) {
            __builtin_trap();
        }
        ls_slcan_msg_t m;
        if (ls_slcan_parse(lx.buf, len, &m) == 0 && m.kind == LS_SLCAN_FRAME) {
            char line[LS_SLCAN_MAX_LINE];
            size_t n = ls_slcan_format(&m.frame, line, sizeof line);
            ls_slcan_msg_t back;
            /* what we format must parse back to the same frame */
            if (n < 2 || ls_slcan_parse(line, n - 1, &back) != 0 || back.frame.id != m.frame.id ||
                back.frame.len != m.frame.len || back.frame.flags != m.frame.flags ||
                memcmp(back.frame.data, m.frame.data, m.frame.len) != 0) {
                __builtin_trap();
            }
        }
    }
    return 0;
}
