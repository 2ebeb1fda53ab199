/* The drive bus's budget: how many frames and bit-times one drive cycle
 * puts on a classic CAN bus, what share of the bitrate that is, and the
 * shortest drive cycle that stays under a ceiling. landscaped refuses a
 * configuration above the ceiling with ls_drive_budget_format's line
 * (docs/deploy.md, "Drives").
 *
 * What a cycle carries: one SYNC, every RPDO and TPDO of every axis, the
 * heartbeats of the drives and of the master amortised over their periods
 * (a 100 ms heartbeat adds 2 % of a frame to a 2 ms cycle), and an optional
 * reserve of SDO exchanges (request and answer, 8 bytes each). EMCY frames
 * come only with faults and are not counted.
 *
 * Frame lengths: classic CAN, 11-bit identifiers. A frame of n data bytes
 * takes 47 + 8n bit-times (SOF to the end of the intermission) before
 * stuffing; the stuffed span, SOF to the CRC sequence, is 34 + 8n bits and
 * in the worst case gains one stuff bit per 4 after the first:
 * floor((34 + 8n - 1) / 4). So a SYNC (0 bytes) takes at most 55
 * bit-times, a 6-byte PDO 115, an 8-byte SDO frame 135.
 *
 * Init-time and --check code, but portable: no OS calls, no clock, no
 * allocation, O(axes x PDOs) per call. */
#ifndef LS_DRIVE_BUDGET_H
#define LS_DRIVE_BUDGET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_err.h"

#define LS_DRIVE_BUDGET_MAX_PDOS 8u                /* per direction and axis */
#define LS_DRIVE_BUDGET_MAX_DATA 8u                /* classic CAN */
#define LS_DRIVE_BUDGET_CEILING_PCT 70.0           /* the default ceiling */
#define LS_DRIVE_BUDGET_MAX_MULTIPLE 1000u         /* the longest cycle searched, in control periods */
#define LS_DRIVE_BUDGET_CYCLE_KEY "[drives] cycle" /* the setting the refusal names */

/* Bit-times of one frame with `data_bytes` (0..8) bytes, worst-case
 * stuffing included; 0 for more than 8. */
unsigned ls_drive_budget_frame_bits(unsigned data_bytes);

/* One axis (one drive node). */
typedef struct {
    uint8_t n_rpdo;                               /* PDOs the master sends every cycle */
    uint8_t rpdo_bytes[LS_DRIVE_BUDGET_MAX_PDOS]; /* data length of each, 0..8 */
    uint8_t n_tpdo;                               /* PDOs the drive answers every cycle */
    uint8_t tpdo_bytes[LS_DRIVE_BUDGET_MAX_PDOS];
    uint32_t heartbeat_ms; /* the drive's producer heartbeat (0x1017); 0: none */
} ls_drive_budget_axis_t;

typedef struct {
    uint32_t control_period_us;   /* the control loop's period: drive cycles are multiples of it */
    uint32_t cycle_us;            /* the drive cycle to check (a multiple of control_period_us) */
    uint32_t bitrate;             /* bit/s, e.g. 1000000 */
    uint8_t sync_bytes;           /* 0, or 1 with the SYNC counter (0x1019) */
    uint32_t master_heartbeat_ms; /* the master's producer heartbeat; 0: none */
    uint32_t sdo_per_cycle;       /* SDO exchanges reserved per cycle (0: none in operation) */
    double ceiling_pct;           /* 0 < ceiling <= 100; 0 means LS_DRIVE_BUDGET_CEILING_PCT */
    const ls_drive_budget_axis_t *axes;
    size_t n_axes;
} ls_drive_budget_in_t;

typedef struct {
    double frames_per_cycle; /* heartbeats amortised, so not whole */
    double bits_per_cycle;   /* bit-times, worst-case stuffing */
    double load_pct;         /* bits_per_cycle over the bit-times of one cycle, in % */
    double ceiling_pct;      /* the ceiling applied */
    bool fits;               /* load_pct <= ceiling_pct */
    /* The shortest drive cycle, in control periods, whose load is under the
     * ceiling (searched up to LS_DRIVE_BUDGET_MAX_MULTIPLE); 0 when none
     * is: the heartbeats alone, or the frames of one cycle at the longest
     * multiple, exceed it. */
    uint32_t min_cycle_multiple;
} ls_drive_budget_t;

/* Compute the budget. Returns LS_OK, or LS_EINVAL (a NULL pointer, axes
 * NULL with n_axes > 0, a zero period, cycle or bitrate, a cycle that is not
 * a multiple of the control period, sync_bytes > 1, a PDO count above
 * LS_DRIVE_BUDGET_MAX_PDOS or a length above 8, a ceiling not in (0, 100]);
 * *out untouched on error. */
int ls_drive_budget_compute(const ls_drive_budget_in_t *in, ls_drive_budget_t *out);

/* The line landscaped prints (and --check shows) for a computed budget, at
 * most `cap` bytes with the NUL (cut to fit). Above the ceiling:
 *   "drive bus: 1,661 bit-times per 2 ms cycle = 83 % of 1 Mbit/s, above
 *    the 70 % ceiling: set [drives] cycle = 3 (3 ms) or more, or map fewer
 *    PDOs"
 * (when no cycle fits: "... above the 70 % ceiling at every cycle up to
 * 1000 control periods: map fewer PDOs, slow the heartbeats or raise the
 * bitrate"); within it:
 *   "drive bus: 1,445 bit-times per 4 ms cycle = 36 % of 1 Mbit/s, within
 *    the 70 % ceiling"
 * Bit-times are rounded up; a load that would round to the ceiling gets
 * one decimal, so the figure never contradicts the verdict. Returns the
 * length the whole line has (>= cap: it was cut), or LS_EINVAL (NULL, cap
 * 0). No allocation; any context. */
int ls_drive_budget_format(const ls_drive_budget_in_t *in, const ls_drive_budget_t *b, char *buf, size_t cap);

#endif
