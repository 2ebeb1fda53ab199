/* Clock and periodic execution contract.
 *
 * The control loop never reads a clock itself: the runner passes `now_us` to
 * every cycle. Backends: hal/sim (real-time pacing, or lockstep virtual time)
 * and hal/linux (SCHED_FIFO thread with clock_nanosleep(TIMER_ABSTIME)). */
#ifndef HAL_CLOCK_H
#define HAL_CLOCK_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_status.h"

/* Monotonic time in microseconds. Callable from any thread. */
typedef uint64_t (*hal_now_fn)(void *self);

typedef struct {
    hal_now_fn now_us;
    void *self;
} hal_clock_t;

uint64_t hal_clock_now_us(const hal_clock_t *clock);

/* Statistics of a periodic runner (readable from any thread, approximate). */
typedef struct {
    uint64_t cycles;
    uint64_t overruns;     /* cycles that started later than one period after their deadline */
    uint64_t behind_us;    /* how far the loop's time has fallen behind the clock: the sum of
                            * the lateness of every overrun (its skipped cycles never run, so
                            * a motion timed in cycles takes this much longer in wall time) */
    uint32_t max_late_us;  /* worst wake-up latency */
    uint32_t max_cycle_us; /* worst cycle execution time */
    bool realtime;         /* SCHED_FIFO granted */
    bool memory_locked;    /* mlockall succeeded */
} hal_rt_stats_t;

#endif
