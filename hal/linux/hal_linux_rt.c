#include "hal_linux_rt.h"

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include "hal_linux_msg.h"

#define NS_PER_S 1000000000ull

/* One warning per cause per process: a restarted loop must not repeat it. */
static atomic_bool g_warned_fifo;
static atomic_bool g_warned_mlock;
static atomic_bool g_warned_affinity;

static uint64_t mono_ns(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

uint64_t hal_linux_monotonic_us(void)
{
    return mono_ns() / 1000u;
}

static uint64_t clock_now_us(void *self)
{
    (void)self;
    return hal_linux_monotonic_us();
}

hal_clock_t hal_linux_clock(void)
{
    hal_clock_t c = { .now_us = clock_now_us, .self = NULL };
    return c;
}

static void warn_once(atomic_bool *flag, const char *fmt, const char *cause)
{
    if (!atomic_exchange(flag, true)) {
        fprintf(stderr, fmt, cause);
        fflush(stderr);
    }
}

static void atomic_max32(atomic_uint_least32_t *a, uint64_t v)
{
    uint32_t c = v > UINT32_MAX ? UINT32_MAX : (uint32_t)v;
    uint_least32_t old = atomic_load_explicit(a, memory_order_relaxed);
    while (c > old && !atomic_compare_exchange_weak_explicit(a, &old, c, memory_order_relaxed, memory_order_relaxed)) {
    }
}

/* Touch the stack the loop will use, so its pages are resident (and locked
 * under MCL_FUTURE) before the first deadline. The volatile function pointer
 * keeps the compiler from dropping the memset of a dead buffer. */
static void *(*volatile g_touch)(void *, int, size_t) = memset;

static void prefault_stack(void)
{
    unsigned char buf[HAL_LINUX_RT_PREFAULT_BYTES];
    (void)g_touch(buf, 0, sizeof buf);
}

static void setup_scheduling(hal_linux_rt_t *rt)
{
    if (rt->cfg.cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET((size_t)rt->cfg.cpu, &set);
        int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
        if (e != 0) {
            warn_once(&g_warned_affinity,
                      "hal_linux_rt: warning: cannot pin the control thread to its CPU (%s): check the cpuset/cgroup "
                      "of this process; running unpinned\n",
                      strerror(e));
        }
    }
    atomic_store(&rt->realtime, false);
    if (rt->cfg.priority > 0) {
        struct sched_param sp;
        memset(&sp, 0, sizeof sp);
        sp.sched_priority = rt->cfg.priority;
        int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
        if (e == 0) {
            atomic_store(&rt->realtime, true);
        } else if (e == EPERM) {
            warn_once(
                &g_warned_fifo,
                "hal_linux_rt: warning: no permission for SCHED_FIFO (%s): run as root, grant CAP_SYS_NICE, or set "
                "LimitRTPRIO= in the systemd unit (ulimit -r); running as a normal thread\n",
                strerror(e));
        } else {
            warn_once(&g_warned_fifo,
                      "hal_linux_rt: warning: SCHED_FIFO refused (%s): check the kernel's RT group scheduling "
                      "(cpu.rt_runtime_us); running as a normal thread\n",
                      strerror(e));
        }
    }
}

static void *rt_main(void *p)
{
    hal_linux_rt_t *rt = p;
    setup_scheduling(rt);
    prefault_stack();
    const uint64_t period = rt->period_ns;
    const hal_cycle_fn fn = rt->fn;
    void *const arg = rt->arg;
    const bool lockstep = rt->cfg.lockstep;

    uint64_t deadline = mono_ns();
    const uint64_t start_us = deadline / 1000u;
    (void)sem_post(&rt->ready);

    for (uint64_t cycle = 0; !atomic_load_explicit(&rt->stop, memory_order_relaxed); cycle++) {
        uint64_t wake = mono_ns();
        uint64_t late = wake > deadline ? wake - deadline : 0u;
        atomic_max32(&rt->max_late_us, late / 1000u);
        if (late > period) {
            atomic_fetch_add_explicit(&rt->overruns, 1u, memory_order_relaxed);
            atomic_fetch_add_explicit(&rt->behind_ns, late, memory_order_relaxed);
            deadline = wake; /* re-base: skip the missed cycles */
        }
        uint64_t now_us = lockstep ? start_us + cycle * period / 1000u : wake / 1000u;
        fn(arg, now_us, cycle);
        uint64_t done = mono_ns();
        atomic_max32(&rt->max_cycle_us, (done - wake) / 1000u);
        atomic_fetch_add_explicit(&rt->cycles, 1u, memory_order_relaxed);

        deadline += period;
        struct timespec ts = { .tv_sec = (time_t)(deadline / NS_PER_S), .tv_nsec = (long)(deadline % NS_PER_S) };
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
        }
    }
    return NULL;
}

static int check_config(const hal_linux_rt_t *rt, const hal_rt_config_t *cfg, hal_cycle_fn fn, char *msg, size_t msglen)
{
    if (rt == NULL || cfg == NULL || fn == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "hal_linux_rt_start: rt, cfg and fn must not be NULL");
    }
    if (cfg->rate_hz == 0u || cfg->rate_hz > HAL_LINUX_RT_MAX_RATE_HZ) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "control rate %u Hz is outside 1..%u Hz", (unsigned)cfg->rate_hz,
                             HAL_LINUX_RT_MAX_RATE_HZ);
    }
    int pmax = sched_get_priority_max(SCHED_FIFO);
    if (cfg->priority < 0 || cfg->priority > pmax) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "real-time priority %d is outside 0..%d (0 = normal thread)",
                             cfg->priority, pmax);
    }
    if (cfg->cpu >= 0) {
        cpu_set_t allowed;
        CPU_ZERO(&allowed);
        if (cfg->cpu >= CPU_SETSIZE || sched_getaffinity(0, sizeof allowed, &allowed) != 0 ||
            !CPU_ISSET((size_t)cfg->cpu, &allowed)) {
            return hal_linux_msg(LS_EINVAL, msg, msglen,
                                 "CPU %d is not available to this process (see nproc / taskset -p %d); "
                                 "use -1 for no pinning",
                                 cfg->cpu, (int)getpid());
        }
    }
    if (atomic_load(&rt->running)) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "the control thread is already running: stop it first");
    }
    return LS_OK;
}

int hal_linux_rt_start(hal_linux_rt_t *rt, const hal_rt_config_t *cfg, hal_cycle_fn fn, void *arg, char *msg,
                       size_t msglen)
{
    int rc = check_config(rt, cfg, fn, msg, msglen);
    if (rc != LS_OK) {
        return rc;
    }
    rt->cfg = *cfg;
    rt->fn = fn;
    rt->arg = arg;
    rt->period_ns = NS_PER_S / cfg->rate_hz;
    atomic_store(&rt->stop, false);
    atomic_store(&rt->cycles, 0u);
    atomic_store(&rt->overruns, 0u);
    atomic_store(&rt->behind_ns, 0u);
    atomic_store(&rt->max_late_us, 0u);
    atomic_store(&rt->max_cycle_us, 0u);
    atomic_store(&rt->realtime, false);
    atomic_store(&rt->memory_locked, false);

    if (cfg->lock_memory) {
        if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
            atomic_store(&rt->memory_locked, true);
        } else {
            warn_once(
                &g_warned_mlock,
                "hal_linux_rt: warning: cannot lock memory (mlockall: %s): run as root, grant CAP_IPC_LOCK, or raise "
                "LimitMEMLOCK= in the systemd unit (ulimit -l); page faults may delay control cycles\n",
                strerror(errno));
        }
    }

    if (sem_init(&rt->ready, 0, 0) != 0) {
        return hal_linux_msg(LS_EIO, msg, msglen, "sem_init failed: %s", strerror(errno));
    }
    pthread_attr_t attr;
    int e = pthread_attr_init(&attr);
    if (e == 0) {
        e = pthread_attr_setstacksize(&attr, HAL_LINUX_RT_STACK_BYTES);
        if (e == 0) {
            e = pthread_create(&rt->thread, &attr, rt_main, rt);
        }
        (void)pthread_attr_destroy(&attr);
    }
    if (e != 0) {
        (void)sem_destroy(&rt->ready);
        return hal_linux_msg(LS_EIO, msg, msglen, "cannot create the control thread: %s%s", strerror(e),
                             e == EAGAIN && atomic_load(&rt->memory_locked)
                                 ? " (memory is locked: RLIMIT_MEMLOCK may be too small for the thread stack; "
                                   "raise LimitMEMLOCK= in the systemd unit or ulimit -l)"
                                 : "");
    }
    while (sem_wait(&rt->ready) != 0 && errno == EINTR) {
    }
    (void)sem_destroy(&rt->ready);
    atomic_store(&rt->running, true);
    return hal_linux_msg(LS_OK, msg, msglen, "control thread at %u Hz, %s%s%s", (unsigned)cfg->rate_hz,
                         atomic_load(&rt->realtime) ? "SCHED_FIFO" : "normal scheduling",
                         atomic_load(&rt->memory_locked) ? ", memory locked" : "",
                         cfg->lockstep ? ", lockstep time" : "");
}

void hal_linux_rt_stop(hal_linux_rt_t *rt)
{
    if (rt == NULL) {
        return;
    }
    atomic_store(&rt->stop, true);
    if (atomic_load(&rt->running) && pthread_equal(pthread_self(), rt->thread)) {
        return; /* called from fn: cannot join itself */
    }
    if (atomic_exchange(&rt->running, false)) {
        (void)pthread_join(rt->thread, NULL);
    }
}

void hal_linux_rt_stats(const hal_linux_rt_t *rt, hal_rt_stats_t *out)
{
    if (rt == NULL || out == NULL) {
        return;
    }
    const hal_linux_rt_t *r = rt;
    out->cycles = atomic_load(&r->cycles);
    out->overruns = atomic_load(&r->overruns);
    out->behind_us = atomic_load(&r->behind_ns) / 1000u;
    out->max_late_us = (uint32_t)atomic_load(&r->max_late_us);
    out->max_cycle_us = (uint32_t)atomic_load(&r->max_cycle_us);
    out->realtime = atomic_load(&r->realtime);
    out->memory_locked = atomic_load(&r->memory_locked);
}
