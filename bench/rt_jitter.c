/* bench_rt_jitter: wake-up latency of the Linux backend's periodic runner
 * (hal/linux/hal_linux_rt) at RATE Hz against a bare clock_nanosleep
 * (TIMER_ABSTIME) loop on a thread with the same scheduling, run back to
 * back in this process.
 *
 * Both are measured the same way: the cycle body reads CLOCK_MONOTONIC;
 * latency_k = t_k - (t_0 + k * period), re-based like the runner when a
 * wake-up is more than one period late (an overrun).
 *
 * Usage: bench_rt_jitter SECONDS [RATE_HZ [PRIORITY]]  (PRIORITY 0: normal
 * thread; default 80, which falls back to a normal thread without privilege).
 * Output: two lines "<name> realtime <0|1> cycles <n> overruns <n>
 * p50 <ns> p99 <ns> p999 <ns> max <ns>". */
#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hal_linux_rt.h"

#define MAX_SAMPLES 200000u

typedef struct {
    uint64_t period_ns;
    uint64_t base_ns; /* t_0, re-based on overruns */
    uint64_t n, overruns;
    uint64_t *lat_ns;
    uint64_t want;
} meter_t;

static uint64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* Returns true when enough samples were taken. */
static int meter_tick(meter_t *m, uint64_t k)
{
    uint64_t t = mono_ns();
    if (k == 0) {
        m->base_ns = t;
    }
    uint64_t due = m->base_ns + k * m->period_ns;
    uint64_t late = t > due ? t - due : 0;
    if (late > m->period_ns) {
        m->overruns++;
        m->base_ns = t - k * m->period_ns;
    }
    if (m->n < m->want) {
        m->lat_ns[m->n++] = late;
    }
    return m->n >= m->want;
}

static meter_t g_hal_meter, g_bare_meter;
static atomic_bool g_hal_done;

static void hal_cycle(void *arg, uint64_t now_us, uint64_t cycle)
{
    (void)now_us;
    meter_t *m = arg;
    if (!atomic_load(&g_hal_done) && meter_tick(m, cycle)) {
        atomic_store(&g_hal_done, true);
    }
}

typedef struct {
    meter_t *m;
    int priority;
    int realtime;
} bare_arg_t;

static void *bare_main(void *p)
{
    bare_arg_t *a = p;
    if (a->priority > 0) {
        struct sched_param sp = { .sched_priority = a->priority };
        a->realtime = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
    }
    uint64_t deadline = mono_ns();
    for (uint64_t k = 0;; k++) {
        if (meter_tick(a->m, k)) {
            break;
        }
        uint64_t t = mono_ns();
        if (t > deadline + a->m->period_ns) {
            deadline = t; /* skip missed cycles, as the runner does */
        }
        deadline += a->m->period_ns;
        struct timespec ts = { .tv_sec = (time_t)(deadline / 1000000000u), .tv_nsec = (long)(deadline % 1000000000u) };
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
        }
    }
    return NULL;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

static void report(const char *name, meter_t *m, int realtime)
{
    qsort(m->lat_ns, m->n, sizeof m->lat_ns[0], cmp_u64);
    size_t n = m->n;
#define PCT(q) m->lat_ns[(size_t)((double)(n - 1) * (q))]
    printf("%s realtime %d cycles %llu overruns %llu p50 %llu p99 %llu p999 %llu max %llu\n", name, realtime,
           (unsigned long long)n, (unsigned long long)m->overruns, (unsigned long long)PCT(0.5),
           (unsigned long long)PCT(0.99), (unsigned long long)PCT(0.999), (unsigned long long)m->lat_ns[n - 1]);
#undef PCT
}

int main(int argc, char **argv)
{
    double seconds = argc > 1 ? strtod(argv[1], NULL) : 0.0;
    long rate = argc > 2 ? strtol(argv[2], NULL, 10) : 1000;
    long prio = argc > 3 ? strtol(argv[3], NULL, 10) : 80;
    if (argc < 2 || argc > 4 || seconds <= 0.0 || rate < 1 || rate > 100000 || prio < 0 || prio > 99 ||
        seconds * (double)rate > MAX_SAMPLES) {
        fprintf(stderr, "usage: %s SECONDS [RATE_HZ [PRIORITY]]  (at most %u cycles)\n", argv[0], MAX_SAMPLES);
        return 2;
    }
    uint64_t want = (uint64_t)(seconds * (double)rate);
    static uint64_t hal_lat[MAX_SAMPLES], bare_lat[MAX_SAMPLES];
    uint64_t period = 1000000000u / (uint64_t)rate;
    g_hal_meter = (meter_t){ .period_ns = period, .lat_ns = hal_lat, .want = want };
    g_bare_meter = (meter_t){ .period_ns = period, .lat_ns = bare_lat, .want = want };

    /* 1. the runner */
    static hal_linux_rt_t rt;
    hal_rt_config_t cfg = { .rate_hz = (uint32_t)rate, .priority = (int)prio, .cpu = -1, .lock_memory = true };
    char msg[256];
    if (hal_linux_rt_start(&rt, &cfg, hal_cycle, &g_hal_meter, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "bench_rt_jitter: %s\n", msg);
        return 1;
    }
    while (!atomic_load(&g_hal_done)) {
        struct timespec ts = { 0, 20000000 };
        nanosleep(&ts, NULL);
    }
    hal_rt_stats_t st;
    hal_linux_rt_stats(&rt, &st);
    hal_linux_rt_stop(&rt);

    /* 2. the bare loop, same scheduling (memory stays locked: mlockall is process-wide) */
    bare_arg_t a = { .m = &g_bare_meter, .priority = st.realtime ? (int)prio : 0, .realtime = 0 };
    pthread_t th;
    if (pthread_create(&th, NULL, bare_main, &a) != 0) {
        fprintf(stderr, "bench_rt_jitter: pthread_create failed\n");
        return 1;
    }
    pthread_join(th, NULL);

    report("hal_linux_rt", &g_hal_meter, st.realtime);
    report("bare_loop", &g_bare_meter, a.realtime);
    printf("hal_stats max_late_us %u overruns %llu memory_locked %d\n", (unsigned)st.max_late_us,
           (unsigned long long)st.overruns, st.memory_locked);
    return 0;
}
