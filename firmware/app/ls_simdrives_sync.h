/* ls-simdrives --sync-stats: the SYNC period as the drives receive it.
 *
 * A test and benchmark aid (bench/b_drives.py, docs/simulated-drives.md):
 * the master's SYNC period seen at the receiving end of the drive bus is
 * what the drives' interpolation runs on, so its jitter is the figure a
 * master's timing is judged by. ls-simdrives notes the arrival time of
 * every SYNC it reads from its link; at exit it prints one line of
 * interval statistics.
 *
 * Time is passed in (CLOCK_MONOTONIC us in ls-simdrives); no clock, no
 * OS call, no allocation: the intervals go to a fixed array inside the
 * caller's ls_sync_watch_t (about 512 kB: static in ls-simdrives). */
#ifndef LS_SIMDRIVES_SYNC_H
#define LS_SIMDRIVES_SYNC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"

/* Intervals kept: 524 s of a 4 ms SYNC. Later ones are counted, not kept. */
#define LS_SYNC_WATCH_MAX 131072u

typedef struct {
    uint64_t n_syncs;  /* SYNCs noted */
    uint64_t first_us; /* the first one's arrival */
    uint64_t last_us;  /* the last one's */
    uint32_t n_kept;   /* intervals in interval_us */
    uint32_t interval_us[LS_SYNC_WATCH_MAX];
} ls_sync_watch_t;

/* True for a CiA 301 SYNC: 11-bit id LS_CO_COB_SYNC, a data frame of 0 or 1
 * byte (the counter). An EMCY (same base + node id) is not one. */
bool ls_sync_watch_is_sync(const hal_can_frame_t *f);

/* Start empty. */
void ls_sync_watch_init(ls_sync_watch_t *w);

/* One SYNC arrived at now_us (monotonic; an earlier time than the last
 * counts as an interval of 0). O(1); any thread that owns *w. */
void ls_sync_watch_note(ls_sync_watch_t *w, uint64_t now_us);

/* Interval statistics, nearest-rank percentiles (as bench/common.py):
 * false when fewer than two SYNCs were noted (nothing is written). */
typedef struct {
    uint64_t n_intervals; /* all, kept or not */
    uint32_t n_kept;      /* the ones the figures below are of */
    double span_s;        /* first to last SYNC */
    uint32_t median_us, p99_us, min_us, max_us;
    double mean_us;
} ls_sync_stats_t;

/* Sorts the kept intervals in place (O(n log n), for the end of a run:
 * note nothing after it). Untouched on false. */
bool ls_sync_watch_stats(ls_sync_watch_t *w, ls_sync_stats_t *out);

/* The line ls-simdrives logs at exit, at most `cap` bytes with the NUL:
 *   "SYNC intervals as received: 7499 over 29.996 s: median 4000 us,
 *    p99 4391 us, min 1823 us, max 6120 us, mean 4000.1 us"
 * with " (the first 131072 kept)" when more came, or
 *   "SYNC intervals as received: none (1 SYNC)".
 * Sorts as ls_sync_watch_stats. Returns the length of the whole line. */
int ls_sync_watch_format(ls_sync_watch_t *w, char *buf, size_t cap);

#endif
