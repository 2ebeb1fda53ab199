/* ls-simdrives --sync-stats (ls_simdrives_sync.h). */
#include "ls_simdrives_sync.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_canopen.h"

bool ls_sync_watch_is_sync(const hal_can_frame_t *f)
{
    return f->id == LS_CO_COB_SYNC && (f->flags & (HAL_CAN_F_EXT | HAL_CAN_F_RTR)) == 0u && f->len <= 1u;
}

void ls_sync_watch_init(ls_sync_watch_t *w)
{
    w->n_syncs = 0;
    w->first_us = 0;
    w->last_us = 0;
    w->n_kept = 0;
}

void ls_sync_watch_note(ls_sync_watch_t *w, uint64_t now_us)
{
    if (w->n_syncs == 0u) {
        w->first_us = now_us;
    } else if (w->n_kept < LS_SYNC_WATCH_MAX) {
        const uint64_t d = now_us > w->last_us ? now_us - w->last_us : 0u;
        w->interval_us[w->n_kept++] = d > UINT32_MAX ? UINT32_MAX : (uint32_t)d;
    }
    if (now_us > w->last_us || w->n_syncs == 0u) {
        w->last_us = now_us;
    }
    w->n_syncs++;
}

static int cmp_u32(const void *a, const void *b)
{
    const uint32_t x = *(const uint32_t *)a;
    const uint32_t y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* Nearest rank: the smallest value with at least q % of the sample at or
 * below it. */
static uint32_t rank(const uint32_t *sorted, uint32_t n, unsigned q)
{
    uint64_t k = ((uint64_t)q * n + 99u) / 100u;
    return sorted[k > 0u ? k - 1u : 0u];
}

bool ls_sync_watch_stats(ls_sync_watch_t *w, ls_sync_stats_t *out)
{
    if (w->n_syncs < 2u || w->n_kept == 0u) {
        return false;
    }
    qsort(w->interval_us, w->n_kept, sizeof w->interval_us[0], cmp_u32);
    double sum = 0.0;
    for (uint32_t i = 0; i < w->n_kept; i++) {
        sum += w->interval_us[i];
    }
    out->n_intervals = w->n_syncs - 1u;
    out->n_kept = w->n_kept;
    out->span_s = (double)(w->last_us - w->first_us) * 1e-6;
    out->median_us = rank(w->interval_us, w->n_kept, 50u);
    out->p99_us = rank(w->interval_us, w->n_kept, 99u);
    out->min_us = w->interval_us[0];
    out->max_us = w->interval_us[w->n_kept - 1u];
    out->mean_us = sum / w->n_kept;
    return true;
}

int ls_sync_watch_format(ls_sync_watch_t *w, char *buf, size_t cap)
{
    ls_sync_stats_t s;
    if (!ls_sync_watch_stats(w, &s)) {
        return snprintf(buf, cap, "SYNC intervals as received: none (%llu SYNC%s)", (unsigned long long)w->n_syncs,
                        w->n_syncs == 1u ? "" : "s");
    }
    char kept[40] = "";
    if (s.n_intervals > s.n_kept) {
        (void)snprintf(kept, sizeof kept, " (the first %u kept)", (unsigned)s.n_kept);
    }
    return snprintf(buf, cap,
                    "SYNC intervals as received: %llu over %.3f s: median %u us, p99 %u us, min %u us, max %u us, "
                    "mean %.1f us%s",
                    (unsigned long long)s.n_intervals, s.span_s, (unsigned)s.median_us, (unsigned)s.p99_us,
                    (unsigned)s.min_us, (unsigned)s.max_us, s.mean_us, kept);
}
