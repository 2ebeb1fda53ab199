/* Deterministic pseudo-random numbers for the unit tests (Marsaglia's
 * xorshift64, shifts 13/7/17), so that a failure repeats: each test file
 * keeps its own generator, seeded with a fixed non-zero value. */
#ifndef LS_TEST_RNG_H
#define LS_TEST_RNG_H

#include <stdint.h>

typedef struct {
    uint64_t s; /* never 0 */
} test_rng_t;

static inline uint64_t test_rng_next(test_rng_t *r)
{
    r->s ^= r->s << 13;
    r->s ^= r->s >> 7;
    r->s ^= r->s << 17;
    return r->s;
}

/* Uniform in [lo, hi): the top 53 bits as a double in [0, 1). */
static inline double test_rng_uniform(test_rng_t *r, double lo, double hi)
{
    return lo + (hi - lo) * (double)(test_rng_next(r) >> 11) / 9007199254740992.0;
}

#endif
