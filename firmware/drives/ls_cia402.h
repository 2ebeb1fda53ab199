/* One CiA 402 axis as the master sees it, evaluated once per drive cycle:
 * the power state machine's state decoded from the statusword, the
 * controlword to send next, and the scaling between joint radians and the
 * drive's int32 counts.
 *
 * The stepper is a function of the latest statusword and the wanted state
 * (DISABLED, ENABLED, QUICK_STOP), plus a little memory for what a pure
 * function cannot know: whether a fault-reset edge is due, how many were
 * tried, and how long the drive has stayed in its state. It never blocks
 * and never loops: one call per drive cycle returns the controlword of that
 * cycle. The controlword it returns follows from the state the statusword
 * shows, so it changes (one step: shutdown 0x06, switch on 0x07, enable
 * operation 0x0F, ...) only after the statusword confirmed the previous
 * step; while the drive has not moved the same step is repeated. A drive
 * that stays in a state it should leave for step_timeout_cycles is
 * reported as stuck in that state, naming the step it ignores.
 *
 * Transitions used (CiA 402 part 2, figure "state machine"; the numbers are
 * the standard's):
 *   ENABLED:    SWITCH ON DISABLED -2-> READY -3-> SWITCHED ON -4-> ENABLED;
 *               QUICK STOP ACTIVE -12-> SWITCH ON DISABLED (then as above:
 *               transition 16 depends on the drive's quick stop option code)
 *   DISABLED:   ENABLED -8-> READY, SWITCHED ON -6-> READY,
 *               QUICK STOP ACTIVE -12-> SWITCH ON DISABLED; SWITCH ON
 *               DISABLED and READY TO SWITCH ON both count as disabled
 *   QUICK_STOP: ENABLED -11-> QUICK STOP ACTIVE; READY and SWITCHED ON
 *               -7/10-> SWITCH ON DISABLED; both count as stopped
 *   any wanted state, from FAULT: -15-> SWITCH ON DISABLED by a rising edge
 *               of controlword bit 7, sent only when the caller allows a
 *               reset and only after at least one cycle with bit 7 = 0
 *               (a drive that restarts with bit 7 still high from an
 *               earlier master would see no edge)
 * NOT READY TO SWITCH ON and FAULT REACTION ACTIVE end by themselves: the
 * stepper sends 0 (disable voltage) and waits.
 *
 * The stepper owns controlword bits 0-3 and 7; the caller may OR in the
 * mode-specific bits (4-6, 8 halt, 9) that its mode of operation needs.
 * It knows nothing of the mode: setting 0x6060, confirming it in 0x6061 and
 * holding the target position equal to the actual position until `enabled`
 * is the caller's part.
 *
 * Everything here is portable C11: no OS calls, no clock (time is counted
 * in calls), no allocation; O(1) per call; control-loop safe. An axis is
 * owned by one thread (the one that runs the drive cycle). */
#ifndef LS_CIA402_H
#define LS_CIA402_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_err.h"

/* ---- The power state machine's states ------------------------------- */

typedef enum {
    LS_402_UNKNOWN = 0, /* a statusword that matches no state (bits 0-3, 5, 6) */
    LS_402_NOT_READY_TO_SWITCH_ON,
    LS_402_SWITCH_ON_DISABLED,
    LS_402_READY_TO_SWITCH_ON,
    LS_402_SWITCHED_ON,
    LS_402_OPERATION_ENABLED,
    LS_402_QUICK_STOP_ACTIVE,
    LS_402_FAULT_REACTION_ACTIVE,
    LS_402_FAULT,
    LS_402_STATE_COUNT
} ls_402_state_t;

/* The state a statusword (0x6041) shows, from the masks of ls_canopen.h.
 * O(1); any context. */
ls_402_state_t ls_402_state(uint16_t statusword);

/* "OPERATION ENABLED" etc. (the standard's names, upper case, for one-line
 * messages); "UNKNOWN" for LS_402_UNKNOWN and values out of range. Never
 * NULL; O(1); any context. */
const char *ls_402_state_name(ls_402_state_t state);

/* "shutdown", "switch on", "enable operation", "disable voltage", "quick
 * stop", "fault reset" for the device control commands the stepper sends
 * (bits 0-3 and 7 of a controlword; other bits are ignored); "controlword"
 * for anything else. Never NULL; O(1); any context. */
const char *ls_402_command_name(uint16_t controlword);

/* ---- The stepper ------------------------------------------------------ */

typedef enum {
    LS_402_WANT_DISABLED = 0, /* SWITCH ON DISABLED or READY TO SWITCH ON: no torque */
    LS_402_WANT_ENABLED,      /* OPERATION ENABLED */
    LS_402_WANT_QUICK_STOP,   /* QUICK STOP ACTIVE, or SWITCH ON DISABLED once stopped */
    LS_402_WANT_COUNT
} ls_402_want_t;

typedef enum {
    LS_402_OK = 0,         /* at the wanted state, or stepping toward it in time */
    LS_402_STUCK,          /* stayed in `stuck_in` for step_timeout_cycles though `stuck_command` was sent */
    LS_402_STAYS_IN_FAULT, /* still in FAULT after fault_reset_edges reset edges */
} ls_402_error_t;

typedef struct {
    uint32_t step_timeout_cycles; /* >= 1: calls a state may last while the axis should leave it */
    uint8_t fault_reset_edges;    /* >= 1: reset edges tried (each waits step_timeout_cycles) */
} ls_402_config_t;

/* The defaults for a drive cycle of cycle_us (> 0): a step time-out of
 * LS_402_STEP_TIMEOUT_MS rounded up to whole cycles, LS_402_FAULT_RESET_EDGES
 * edges. A drive answers a step within a few cycles; the time-out is long
 * because enabling may wait for a holding brake to release (hundreds of ms
 * on common drives). */
#define LS_402_STEP_TIMEOUT_MS 1000u
#define LS_402_FAULT_RESET_EDGES 3u
void ls_402_default_config(ls_402_config_t *cfg, uint32_t cycle_us);

/* One axis's memory. Plain data, filled by ls_402_init; the fields are
 * private to ls_cia402.c. */
typedef struct {
    ls_402_config_t cfg;
    uint16_t cw;          /* the controlword returned last */
    bool bit7_low_sent;   /* a controlword with bit 7 = 0 was returned since the last edge */
    ls_402_state_t state; /* decoded last call */
    uint32_t cycles_in_state;
    uint32_t cycles_since_edge;
    uint8_t edges; /* reset edges since the want changed or the wanted state was reached */
    ls_402_want_t want;
    bool reset_allowed;
    ls_402_error_t error; /* latched until the want changes or a reset is allowed anew */
    ls_402_state_t stuck_in;
    uint16_t stuck_command;
} ls_402_axis_t;

/* What one call decided. */
typedef struct {
    uint16_t controlword; /* send this cycle (bits 0-3 and 7) */
    uint16_t statusword;  /* the one given */
    ls_402_state_t state; /* decoded from it */
    bool enabled;         /* OPERATION ENABLED confirmed by the statusword */
    bool at_target;       /* the state satisfies the wanted state */
    bool fault;           /* bit 3: FAULT or FAULT REACTION ACTIVE */
    bool warning;         /* bit 7 */
    bool remote;          /* bit 9: 0 = the drive takes no controlword over the bus */
    bool following_error; /* bit 13 in OPERATION ENABLED: CSP's meaning (HM: homing error) */
    bool target_ignored;  /* bit 12 clear in OPERATION ENABLED: in CSP the drive does not follow the target */
    ls_402_error_t error;
    ls_402_state_t stuck_in;  /* with LS_402_STUCK / LS_402_STAYS_IN_FAULT */
    uint16_t stuck_command;   /* the step the drive did not follow (LS_402_STUCK) */
    uint32_t timeout_cycles;  /* the configured step time-out, for messages */
    uint8_t reset_edges_sent; /* with LS_402_STAYS_IN_FAULT */
} ls_402_out_t;

/* Prepare an axis (init time, or to start over after the drive restarted).
 * `cfg` NULL means ls_402_default_config at 1 ms. The first controlwords
 * keep bit 7 at 0. Returns LS_OK, or LS_EINVAL (ax NULL, a zero time-out or
 * edge count); *ax is untouched on error. */
int ls_402_init(ls_402_axis_t *ax, const ls_402_config_t *cfg);

/* One drive cycle: the latest statusword (repeat the last one when no new
 * one came; time-outs count calls), the wanted state, and whether a fault
 * may be reset now. Fills *out and returns LS_OK, or LS_EINVAL (NULL
 * pointer, want out of range) with *out and *ax untouched.
 *
 * A stuck axis or a FAULT that resets do not clear is reported in
 * out->error (not in the return value) and latched until `want` changes,
 * `fault_reset_allowed` goes from false to true or the drive reaches the
 * wanted state after all; meanwhile the stepper
 * keeps sending the step it was sending (or 0 in FAULT), so a drive that
 * recovers late is still led on. The reset-edge count also restarts when
 * the wanted state is reached, and only then: a drive that faults again on
 * every enable ends as LS_402_STAYS_IN_FAULT instead of looping.
 * O(1); control-loop safe. */
int ls_402_step(ls_402_axis_t *ax, uint16_t statusword, ls_402_want_t want, bool fault_reset_allowed,
                ls_402_out_t *out);

/* One line for a log or a refusal, at most `cap` bytes with the NUL
 * (truncated to fit): "stuck in READY TO SWITCH ON: switch on (0x0007) not
 * followed within 100 cycles (statusword 0x0221)", "stays in FAULT after 3
 * fault resets (statusword 0x0208)", or the state and flags when there is
 * no error ("OPERATION ENABLED, warning"). Adds "the drive is under local
 * control (statusword bit 9 = 0)" when remote is clear. Returns the length
 * written, or LS_EINVAL (out or buf NULL, cap 0). O(length); no
 * allocation; any context. */
int ls_402_describe(const ls_402_out_t *out, char *buf, size_t cap);

/* ---- Position and velocity scaling ------------------------------------ */

/* Joint angle q (rad) and drive counts c (the int32 of 0x6064 / 0x607A,
 * unwrapped into an int64, see below):
 *   q = zero_offset_rad + sign * c / counts_per_rad
 * so zero_offset_rad is the joint angle where the drive reads 0. Velocities
 * (0x606C actual, 0x60B1 feed-forward) in counts/s:
 *   v_counts = sign * v_rad_s * vel_counts_per_rad
 * vel_counts_per_rad is the drive's velocity unit per rad/s: equal to
 * counts_per_rad when the drive's velocity unit is counts per second. */
typedef struct {
    double counts_per_rad;     /* finite, > 0 */
    double vel_counts_per_rad; /* finite, > 0 */
    double zero_offset_rad;    /* finite */
    int sign;                  /* +1 or -1 */
} ls_402_scale_t;

/* Check and fill a scale (init time). vel_counts_per_rad 0 means equal to
 * counts_per_rad. Returns LS_OK, or LS_EINVAL (s NULL, a factor not finite
 * or not > 0, an offset not finite, sign not +-1); *s untouched on error. */
int ls_402_scale_init(ls_402_scale_t *s, double counts_per_rad, int sign, double zero_offset_rad,
                      double vel_counts_per_rad);

/* The drive's position counter is an int32 that wraps: a joint that turns
 * far enough (or an encoder that starts near the end of its range) crosses
 * from INT32_MAX to INT32_MIN. The tracker takes each reading's difference
 * from the previous one modulo 2^32 as a signed step (|step| < 2^31 counts
 * between two readings) and accumulates it in an int64, so the joint angle
 * stays continuous. The first reading is taken as it is: the unwrapped
 * count and the drive's counter agree modulo 2^32 from then on. */
typedef struct {
    int64_t count; /* unwrapped counts */
    int32_t raw;   /* last reading */
    bool primed;   /* a reading was taken */
} ls_402_unwrap_t;

/* Forget every reading (init, or after the drive restarted). Any context. */
void ls_402_unwrap_reset(ls_402_unwrap_t *u);

/* Take one position-actual reading; returns the unwrapped count. O(1). */
int64_t ls_402_unwrap(ls_402_unwrap_t *u, int32_t raw);

/* The joint angle of an unwrapped count. O(1). */
double ls_402_pos_rad(const ls_402_scale_t *s, int64_t count);

/* The raw target position (0x607A) for q_rad, consistent with the tracker:
 * the nearest count to q_rad, taken modulo 2^32, which is what the drive's
 * own wrapped counter reads at that position. Returns LS_OK, LS_EINVAL (a
 * NULL pointer, q_rad not finite, no reading taken yet) or LS_ERANGE (the
 * target is 2^31 counts or more from the last reading: the drive could not
 * tell the direction); *raw untouched on error. O(1); control-loop safe. */
int ls_402_target_raw(const ls_402_scale_t *s, const ls_402_unwrap_t *u, double q_rad, int32_t *raw);

/* Velocity in the drive's unit (0x60B1 feed-forward), rounded to the
 * nearest. Returns LS_OK, LS_EINVAL (NULL, not finite) or LS_ERANGE (beyond
 * int32); *raw untouched on error. O(1). */
int ls_402_vel_raw(const ls_402_scale_t *s, double v_rad_s, int32_t *raw);

/* Velocity in rad/s of a drive reading (0x606C). O(1). */
double ls_402_vel_rad_s(const ls_402_scale_t *s, int32_t raw);

#endif
