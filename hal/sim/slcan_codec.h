/* SLCAN (Lawicel ASCII) line codec, as spoken by python-can's `slcan`
 * interface and by serial CAN adapters. Pure functions: no I/O, no heap; fuzzed.
 *
 * Lines end with '\r'. Frames: tIIILDD..  (11-bit), TIIIIIIIILDD.. (29-bit),
 * rIIIL / RIIIIIIIIL (remote). Commands: O (open), C (close), Sn (bitrate
 * index), V, N, F, Z. Hex digits are accepted in either case. */
#ifndef LS_SLCAN_CODEC_H
#define LS_SLCAN_CODEC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"

#define LS_SLCAN_MAX_LINE 32u /* "T" + 8 id + 1 len + 16 data = 26, plus slack */

typedef enum {
    LS_SLCAN_FRAME = 0, /* a data or remote frame: see `frame` */
    LS_SLCAN_OPEN,      /* O */
    LS_SLCAN_CLOSE,     /* C */
    LS_SLCAN_BITRATE,   /* Sn: `bitrate` holds bit/s */
    LS_SLCAN_VERSION,   /* V */
    LS_SLCAN_SERIAL,    /* N */
    LS_SLCAN_FLAGS,     /* F */
    LS_SLCAN_TIMESTAMP, /* Zn */
    LS_SLCAN_EMPTY,     /* a bare CR */
} ls_slcan_kind_t;

typedef struct {
    ls_slcan_kind_t kind;
    hal_can_frame_t frame;
    uint32_t bitrate;
} ls_slcan_msg_t;

/* Parse one line (without its CR). Returns LS_OK, or LS_EINVAL when the line is
 * malformed (unknown command, bad hex, wrong length, id out of range, DLC > 8). */
int ls_slcan_parse(const char *line, size_t len, ls_slcan_msg_t *out);

/* Format a frame as an SLCAN line including the trailing CR. Returns the
 * number of characters written (no NUL), or 0 when `cap` is too small. */
size_t ls_slcan_format(const hal_can_frame_t *frame, char *out, size_t cap);

/* Accumulates bytes into lines. A line longer than LS_SLCAN_MAX_LINE is
 * discarded up to its CR and counted in `overlong`. */
typedef struct {
    char buf[LS_SLCAN_MAX_LINE];
    size_t len;
    bool discarding;
    uint32_t overlong;
} ls_slcan_lexer_t;

void ls_slcan_lexer_init(ls_slcan_lexer_t *lx);
/* Feed one byte; returns true when a complete line is in lx->buf[0..*len). */
bool ls_slcan_lexer_feed(ls_slcan_lexer_t *lx, char c, size_t *len);

#endif
