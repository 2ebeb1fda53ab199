/* Fault-injecting CAN link: a decorator over any hal_can_link_t that drops,
 * duplicates, corrupts, reorders and delays frames at configurable rates in
 * each direction, and takes the bus off for a repeating window. It exists to
 * prove that the protocol stack above (ISO-TP, retransmission by sequence
 * number, heartbeat supervision) survives a bad bus; landscaped applies it to
 * every --link with `--link-faults SPEC`.
 *
 * Determinism: every decision comes from a seeded PRNG (one stream per
 * direction), and each frame consumes the same number of draws whatever
 * happens to it, so a given seed and call sequence always injects the same
 * faults. Time (delays, bus-off windows) comes from the clock in the config,
 * never from the system.
 *
 * Storage: a static pool of HAL_SIM_FAULTY_MAX_LINKS decorators, no heap. A
 * slot is taken by hal_sim_faulty_wrap() and given back by close().
 *
 * Threading: like every link, one thread (the comms thread). */
#ifndef HAL_SIM_FAULTY_LINK_H
#define HAL_SIM_FAULTY_LINK_H

#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "hal/hal_clock.h"

#define HAL_SIM_FAULTY_MAX_LINKS 4
/* Frames one direction can hold back at once (delayed, reordered, duplicated).
 * When it is full a fault that needs a slot is not applied (hold_overflow). */
#define HAL_SIM_FAULTY_HOLD 32
/* A frame held for reordering waits for the next frame, but never longer than
 * this: without a next frame it would otherwise be held for ever. */
#define HAL_SIM_FAULTY_REORDER_MAX_US 50000u

/* Probabilities are per frame, 0..1, drawn independently in this order:
 * drop; then for a frame that survives: delay, reorder (not both: delay wins),
 * corrupt (one random bit of the data; frames without data are never
 * corrupted), dup (the copy follows the original, after the next recv/send). */
typedef struct {
    double drop, dup, corrupt, reorder, delay;
    uint32_t delay_us; /* how long a delayed frame is held (> 0 when delay > 0) */
} hal_sim_fault_rates_t;

typedef struct {
    hal_sim_fault_rates_t tx; /* frames the wrapped side sends (e.g. controller -> bus) */
    hal_sim_fault_rates_t rx; /* frames the wrapped side receives */
    /* Bus-off windows: [k*busoff_every_us, k*busoff_every_us + busoff_for_us)
     * after wrap, k = 1, 2, ...; both 0 = never. While off, send answers
     * LS_EBUSOFF, recv discards what arrives and answers LS_EAGAIN, held
     * frames that fall due are lost, status reports HAL_CAN_STATE_BUS_OFF. */
    uint64_t busoff_every_us;
    uint64_t busoff_for_us;
    /* Frame faults (not bus-off) apply only in [window_after_us,
     * window_after_us + window_for_us) after wrap; both 0 = always. Lets a
     * test connect on a clean bus, run under faults, then read counters on a
     * clean bus again. Frames outside the window still consume their draws. */
    uint64_t window_after_us;
    uint64_t window_for_us;
    uint64_t seed;
    /* Needed when a delay, a reorder or bus-off is configured; not set by
     * hal_sim_fault_parse(). */
    hal_clock_t clock;
} hal_sim_fault_config_t;

typedef struct {
    uint32_t frames; /* frames offered to the decorator */
    uint32_t dropped;
    uint32_t duplicated;
    uint32_t corrupted;
    uint32_t reordered;
    uint32_t delayed;
    uint32_t busoff_lost;   /* refused (tx) or discarded (rx) while bus-off, held frames included */
    uint32_t hold_overflow; /* faults not applied because the hold queue was full */
} hal_sim_fault_dir_counters_t;

typedef struct {
    hal_sim_fault_dir_counters_t tx, rx;
    uint32_t busoff_windows; /* windows entered so far */
} hal_sim_fault_counters_t;

/* Wrap `inner` (copied; the decorator owns it from now on and closes it with
 * itself). `cfg` is copied. Init-time only. Returns LS_OK; LS_EINVAL for a
 * NULL argument, a rate outside 0..1, a delay rate without delay_us, busoff_for
 * >= busoff_every, a window with for = 0, or a time-dependent fault (delay,
 * reorder, bus-off, window) without a clock; LS_EAGAIN when
 * all HAL_SIM_FAULTY_MAX_LINKS slots are in use. O(1), no allocation. */
int hal_sim_faulty_wrap(hal_can_link_t *out, const hal_can_link_t *inner, const hal_sim_fault_config_t *cfg);

/* Parse a fault spec, e.g.
 *   "drop=0.05,dup=0.01,corrupt=0.01,reorder=0.01,delay=0.02:5ms,busoff=30s+2s,seed=1"
 * Keys: drop, dup, corrupt, reorder (RATE), delay (RATE:TIME), busoff
 * (EVERY+FOR), window (AFTER+FOR: frame faults only then), seed (integer,
 * decimal or 0x hex). RATE is 0..1 or a
 * percentage ("5%"); TIME is a number with us, ms or s. A rate key applies to
 * both directions, or to one with a "tx." / "rx." prefix ("rx.drop=0.2"),
 * which may refine a bare key given earlier; the same key twice is an error.
 * `cfg` is reset first (clock zeroed: the caller sets it). Returns LS_OK or
 * LS_EINVAL with `msg` naming the item and what is allowed (the caller adds
 * where the spec came from, e.g. "--link-faults: "). Any thread; no
 * allocation; linear in the length of `spec`. */
int hal_sim_fault_parse(const char *spec, hal_sim_fault_config_t *cfg, char *msg, size_t msglen);

/* Counters of a link returned by hal_sim_faulty_wrap(). LS_EINVAL when
 * `link` is not a live decorator. Comms thread. */
int hal_sim_faulty_counters(const hal_can_link_t *link, hal_sim_fault_counters_t *out);

/* One line for logs: "tx frames=N drop=N dup=N ... rx ... busoff_windows=N".
 * Returns the length written (truncated to buflen-1), negative when `link` is
 * not a decorator. */
int hal_sim_faulty_format(const hal_can_link_t *link, char *buf, size_t buflen);

#endif
