/* Text formatting and number parsing into and from fixed buffers, without
 * the C library's stdio: the firmware's replacement for snprintf/vsnprintf
 * and strtod. newlib's vsnprintf references its allocator (for asprintf's
 * growing string) and its strtod allocates big numbers for long inputs, so
 * an image that uses them links malloc; these never allocate, read no
 * locale and keep no state: callable from any thread, reentrant. The
 * control loop may call them too (no allocation, no blocking), though what
 * it formats is bounded by its own buffers.
 *
 * Output is the same as glibc's for every conversion supported (the unit
 * tests and tests/fuzz/fuzz_fmt.c compare them), floating point included:
 * the decimal expansion is exact (base-1e9 limbs of the binary value) and
 * rounds half to even, as glibc does in the default rounding mode. */
#ifndef LS_FMT_H
#define LS_FMT_H

#include <stdarg.h>
#include <stddef.h>

/* snprintf's contract: writes at most cap - 1 characters and a NUL into
 * buf (nothing when cap is 0; buf may then be NULL), returns the length the
 * whole output has (so a result >= cap means it was cut), or LS_EINVAL
 * when `fmt` holds a conversion this formatter does not support (the output
 * then stops there, NUL-terminated).
 *
 * Conversions: d i u o x X c s % e E f F g G; flags - + space # 0; width
 * and precision as numbers or *; length modifiers hh h l ll z j t (L, a/A,
 * n and p are not supported). NULL for %s prints "(null)" as glibc does.
 * Cost: O(output) for integers and strings; a floating-point conversion
 * costs O(decimal digits of the value) limb operations and uses about
 * 560 bytes of stack. No allocation. */
int ls_fmt_print(char *buf, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
int ls_fmt_vprint(char *buf, size_t cap, const char *fmt, va_list ap) __attribute__((format(printf, 3, 0)));

/* The same for a text a reader gets (an answer, a notice datum): a text
 * that does not fit ends after its last whole word, with a space and an
 * ellipsis (U+2026, 3 bytes of UTF-8) saying so, never inside a word or a
 * character (docs/protocol.md "Limits": the answer text's published
 * limit); the ellipsis alone when not even the first word fits, nothing
 * when the buffer is shorter than that (cap < 4). Returns what ls_fmt_vprint returns (the length the whole text
 * has). Cost and contract otherwise as ls_fmt_vprint; no allocation. */
int ls_fmt_text(char *buf, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
int ls_fmt_vtext(char *buf, size_t cap, const char *fmt, va_list ap) __attribute__((format(printf, 3, 0)));

/* Append to a text being built in buf (cap bytes in all, *len used, kept
 * NUL-terminated): formats at buf + *len as ls_fmt_vprint and advances *len
 * by what fits. Once the text has filled buf (*len + 1 >= cap) nothing more
 * is written: a line that did not fit is cut, and the ones after it are
 * left out. For texts of several lines built piece by piece (sendCommand's
 * answers). No allocation; cost as ls_fmt_vprint. */
void ls_fmt_append(char *buf, size_t cap, size_t *len, const char *fmt, ...) __attribute__((format(printf, 4, 5)));

/* A device's name (a link such as "slcan:tty:/dev/serial/by-id/usb-...",
 * a path) for a text with little room: the whole name when it fits in
 * cap - 1 bytes; otherwise its kind (what comes before the first '/', such
 * as "slcan:tty:"), an ellipsis (U+2026) and the name's end, from a '/' when
 * one falls within it: the path's last part, the device's own name, is what
 * stays. Never splits a UTF-8 character. The kind is dropped when even it
 * leaves no room; cap < 5 writes nothing but the NUL (nothing at all when
 * cap is 0). Returns the length written. No allocation; O(length of name). */
size_t ls_fmt_name_tail(char *buf, size_t cap, const char *name);

/* strtod's contract for decimal text: skips leading white space (isspace
 * in the C locale), takes an optional sign, then "inf", "infinity", "nan"
 * or "nan(chars)" (any case), or decimal digits with an optional '.' and
 * an optional exponent (e/E, sign, digits). Returns the double nearest the
 * exact decimal value (ties to even; correctly rounded however many digits
 * are given), +-HUGE_VAL when it overflows, 0 or a subnormal when it
 * underflows. *end (when end is not NULL) points after the last character
 * used, or at s when no number was found (the result is then 0).
 * Not accepted: hexadecimal ("0x1p3" reads as 0 and stops at 'x'), locale
 * radix characters. errno is not set.
 * Cost: O(length of s) plus, for inputs that are not exact in a double's
 * first guess, a few comparisons of big numbers (about 1.2 KiB of stack).
 * No allocation. */
double ls_fmt_parse_double(const char *s, char **end);

#endif
