/* The seqlock (ls_seqlock.h). */
#include "ls_seqlock.h"

#include <string.h>

void ls_seqlock_write(atomic_uint *seq, atomic_uint *words, size_t n_words, const void *src, size_t size)
{
    if (n_words < LS_SEQLOCK_WORDS(size)) {
        return;
    }
    const unsigned char *p = src;
    const unsigned s = atomic_load_explicit(seq, memory_order_relaxed);
    atomic_store_explicit(seq, s + 1u, memory_order_relaxed);
    for (size_t i = 0; i < LS_SEQLOCK_WORDS(size); i++) {
        uint32_t w = 0;
        const size_t at = i * sizeof w;
        memcpy(&w, p + at, size - at < sizeof w ? size - at : sizeof w);
        atomic_store_explicit(&words[i], w, memory_order_release); /* after the odd seq */
    }
    atomic_store_explicit(seq, s + 2u, memory_order_release);
}

bool ls_seqlock_read(const atomic_uint *seq, const atomic_uint *words, size_t n_words, void *dst, size_t size,
                     unsigned tries)
{
    if (n_words < LS_SEQLOCK_WORDS(size)) {
        return false;
    }
    unsigned char *p = dst;
    for (unsigned t = 0; t < tries; t++) {
        const unsigned s1 = atomic_load_explicit(seq, memory_order_acquire);
        for (size_t i = 0; i < LS_SEQLOCK_WORDS(size); i++) {
            const uint32_t w = atomic_load_explicit(&words[i], memory_order_acquire); /* before s2 */
            const size_t at = i * sizeof w;
            memcpy(p + at, &w, size - at < sizeof w ? size - at : sizeof w);
        }
        const unsigned s2 = atomic_load_explicit(seq, memory_order_relaxed);
        if ((s1 & 1u) == 0u && s1 == s2) {
            return true;
        }
    }
    return false;
}
