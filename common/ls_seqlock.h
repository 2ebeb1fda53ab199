/* A seqlock: one thread (the writer) publishes a plain-data value, another
 * (the reader) copies it without a lock and without waiting. The control
 * loop publishes its snapshot this way (ls_control.h) and the drive arm its
 * per-axis readouts (ls_drives.h): the comms thread reads them while the
 * real-time thread never blocks on it.
 *
 * The value lives in 32-bit atomic words, so a read racing a write is
 * defined behaviour; the orders of the accesses themselves, not fences,
 * keep a torn copy from passing the sequence check (fences ThreadSanitizer
 * cannot follow, and GCC refuses them under it). Writer: seq odd, each
 * word with release (none is seen before the odd seq), seq even with
 * release. Reader: seq with acquire, each word with acquire (none is read
 * after the second seq), seq again: a word of a newer write makes the
 * second seq differ. On x86 these are plain moves; on Cortex-M a barrier
 * per word. 32-bit words stay lock-free on Cortex-M.
 *
 * The caller owns the storage (an atomic_uint sequence and
 * LS_SEQLOCK_WORDS(sizeof value) atomic_uint words, zero-initialised or
 * left as ls_seqlock_write found them). One writer and one reader per
 * seqlock. Portable C11: no OS calls, no allocation; O(size) per call. */
#ifndef LS_SEQLOCK_H
#define LS_SEQLOCK_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The words a value of `size` bytes takes. */
#define LS_SEQLOCK_WORDS(size) (((size) + sizeof(uint32_t) - 1u) / sizeof(uint32_t))

/* Publish `size` bytes of `src` (the writer's thread only; real-time safe:
 * no waiting). `n_words` must be at least LS_SEQLOCK_WORDS(size); nothing
 * is written when it is not. */
void ls_seqlock_write(atomic_uint *seq, atomic_uint *words, size_t n_words, const void *src, size_t size);

/* Copy the latest published value into `dst` (`size` bytes; the reader's
 * thread only). Tries at most `tries` times (each one a copy of the whole
 * value, about as long as a publish): true when `dst` holds one published
 * value whole; false when every try overlapped a publish (the writer
 * stopped in the middle of one, or publishes back to back) or n_words is
 * too small. On false `dst` may hold a torn mix: a reader that must show
 * something keeps its last good copy. A value never published reads as
 * zero bytes. */
bool ls_seqlock_read(const atomic_uint *seq, const atomic_uint *words, size_t n_words, void *dst, size_t size,
                     unsigned tries);

#endif
