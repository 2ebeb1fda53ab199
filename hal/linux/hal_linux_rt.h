/* The periodic control thread: a POSIX thread paced on absolute deadlines
 * with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME), SCHED_FIFO when the
 * process may use it, memory locked and stack prefaulted so the loop takes
 * no page faults.
 *
 * Without privilege (no CAP_SYS_NICE and RLIMIT_RTPRIO too low, or mlockall
 * refused) it prints one warning line per cause and per process to stderr,
 * naming the fix, and runs as a normal thread; stats say what was granted.
 *
 * Overruns: a cycle whose wake-up comes more than one period after its
 * deadline counts as an overrun, and the schedule is re-based on that
 * wake-up: the missed cycles are skipped, not run back to back. Each
 * re-base puts the loop's time (cycles x period, what motions and the
 * simulation advance by) behind the clock by that lateness; stats.behind_us
 * is the sum, so a stop planned to take T s of loop time takes T s plus the
 * growth of behind_us over it in wall time.
 *
 * Lockstep: fn gets now_us = start_us + cycle * period exactly (virtual
 * time, deterministic for simulation) while the thread still paces at the
 * real rate. Otherwise now_us is the monotonic clock at wake-up.
 *
 * Storage: the caller owns the hal_linux_rt_t (zero-initialised, e.g.
 * static); the loop allocates nothing. */
#ifndef HAL_LINUX_RT_H
#define HAL_LINUX_RT_H

#include <pthread.h>
#include <semaphore.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_clock.h"

/* Thread stack size and how much of it is touched before the first cycle. */
#define HAL_LINUX_RT_STACK_BYTES (2u * 1024u * 1024u)
#define HAL_LINUX_RT_PREFAULT_BYTES (256u * 1024u)
#define HAL_LINUX_RT_MAX_RATE_HZ 100000u

/* Called once per cycle on the control thread. cycle counts from 0. */
typedef void (*hal_cycle_fn)(void *arg, uint64_t now_us, uint64_t cycle);

typedef struct {
    uint32_t rate_hz; /* 1..HAL_LINUX_RT_MAX_RATE_HZ; period = 1e9 / rate_hz ns (truncated) */
    int priority;     /* SCHED_FIFO priority 1..99; 0 = normal thread, no request, no warning */
    int cpu;          /* pin to this CPU when >= 0 */
    bool lock_memory; /* mlockall(MCL_CURRENT | MCL_FUTURE): process-wide, kept after stop */
    bool lockstep;    /* virtual now_us, see above */
} hal_rt_config_t;

/* Fields are private; read them through hal_linux_rt_stats. */
typedef struct hal_linux_rt {
    pthread_t thread;
    atomic_bool running; /* started and not yet joined */
    atomic_bool stop;
    hal_rt_config_t cfg;
    hal_cycle_fn fn;
    void *arg;
    uint64_t period_ns;
    sem_t ready; /* the thread posts once its scheduling is set up */
    atomic_uint_least64_t cycles;
    atomic_uint_least64_t overruns;
    atomic_uint_least64_t behind_ns;
    atomic_uint_least32_t max_late_us;
    atomic_uint_least32_t max_cycle_us;
    atomic_bool realtime;
    atomic_bool memory_locked;
} hal_linux_rt_t;

/* Start the thread and return once it runs with its final scheduling
 * (stats.realtime is valid then); the first cycle starts right away.
 * Errors (nothing started, msg says why): LS_EINVAL for NULL rt/cfg/fn,
 * rate 0 or above the maximum, priority outside 0..99, a cpu this process
 * may not run on, or rt already running; LS_EIO when pthread_create fails.
 * Missing privilege is not an error (see above). Init-time: may print. */
int hal_linux_rt_start(hal_linux_rt_t *rt, const hal_rt_config_t *cfg, hal_cycle_fn fn, void *arg, char *msg,
                       size_t msglen);

/* Ask the thread to stop and join it: returns within one period plus the
 * running cycle. Idempotent; safe on a zeroed, never started rt. Called from
 * inside fn it only sets the flag (the owner must still call it to join). */
void hal_linux_rt_stop(hal_linux_rt_t *rt);

/* Snapshot of the statistics; any thread, any time (fields read one by one). */
void hal_linux_rt_stats(const hal_linux_rt_t *rt, hal_rt_stats_t *out);

/* CLOCK_MONOTONIC in microseconds; any thread. */
uint64_t hal_linux_monotonic_us(void);

/* A hal_clock_t reading hal_linux_monotonic_us. */
hal_clock_t hal_linux_clock(void);

#endif
