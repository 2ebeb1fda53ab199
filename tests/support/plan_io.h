/* What the trajectory planners' oracle drivers share (tests/unit/otg/
 * otg_oracle.c, bench/traj_plan.c): problems are read as whitespace-separated
 * numbers from stdin, and planning is timed on the monotonic clock. */
#ifndef LS_TEST_PLAN_IO_H
#define LS_TEST_PLAN_IO_H

#include <stdint.h>
#include <stdio.h>
#include <time.h>

/* Read n numbers into x; -1 at the end of input or on a non-number. */
static inline int read_vec(double *x, int n)
{
    for (int i = 0; i < n; ++i) {
        if (scanf("%lf", &x[i]) != 1) {
            return -1;
        }
    }
    return 0;
}

static inline uint64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

#endif
