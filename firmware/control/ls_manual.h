/* The manual device's gate: what the operator's device may do to the jog.
 *
 * The control loop reads the device (hal/hal_manual.h) every cycle while
 * manualControl is on and hands the state to ls_manual_step, which decides
 * the twist the jog follows (ls_react_jog_step) and reports what the
 * operator did (docs/conformance.md "manualControl"):
 *
 *   Enabling switch (config enabling_switch, the teach pendant): the twist
 *   passes only while HAL_MANUAL_BTN_ENABLE is held, and only once the
 *   switch was seen released after manualControl was switched on, the
 *   drives came on (ls_manual_block) or the device came back: a switch held
 *   through any of those starts nothing until it is released and pressed
 *   again. Releasing it, or pressing it through to its third position
 *   (HAL_MANUAL_BTN_PANIC), zeroes the twist at once: the jog brakes on its
 *   jerk-limited ramp. After the third position only a full release (neither
 *   bit) re-arms it. A device without one (the 6-DOF mouse) passes its twist
 *   whenever it is there, and after it came back once it reported a still
 *   twist (so a device that returns deflected does not start moving).
 *
 *   Lost device: not present (unplugged, a read error), or, for a device
 *   that reports continuously (stale_us > 0), no report for longer than
 *   stale_us: the twist is zeroed and LS_MANUAL_EV_LOST says why, once; its
 *   return (present and reporting again) gives LS_MANUAL_EV_FOUND, and a
 *   new generation (re-plugged) counts as a return. The gate starts as if
 *   the device were there, so a device missing at switch-on is reported.
 *
 *   Buttons, on their press (a rising edge): SPEED_UP / SPEED_DOWN step the
 *   speed override through cfg.step_pct (the twist is scaled by it),
 *   FRAME cycles the jog frame tool -> base -> world, JOINT toggles
 *   single-joint mode; each reports an event. They act whether or not the
 *   drives are on or the enabling switch is held; a device's buttons held
 *   when it appears count as pressed only after they were released.
 *
 * Portable: no clock (the device's age comes with its state), no I/O, no
 * allocation; O(1) per call. Where: every function in the control loop
 * (ls_manual_start also before the loop runs, e.g. in tests). The caller
 * owns ls_manual_t. */
#ifndef LS_MANUAL_H
#define LS_MANUAL_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_manual.h"
#include "ls_react.h"

/* The manual devices by the seed's manualControl types: the one list of
 * their names (manualControl's argument, the [manual] configuration keys,
 * the events' device=). */
typedef enum {
    LS_MANUAL_TEACHPENDANT = 0, /* jogs only while its enabling switch is held */
    LS_MANUAL_SPACEBALL,        /* a 6-DOF mouse */
} ls_manual_kind_t;
#define LS_MANUAL_KINDS 2
#define LS_MANUAL_NAME_TEACHPENDANT "teachpendant"
#define LS_MANUAL_NAME_SPACEBALL "spaceball"

#define LS_MANUAL_MAX_STEPS 8
#define LS_MANUAL_MAX_EVENTS 8 /* per step: at most one of each kind but LOST/FOUND, and both of those */

typedef struct {
    bool enabling_switch; /* motion only while HAL_MANUAL_BTN_ENABLE is held */
    uint64_t stale_us;    /* > 0: a silence longer than this loses the device */
    /* Speed override steps in percent of the jog's full-deflection speed,
     * ascending, each 1..100; n_steps 0 means one step of 100. */
    uint8_t n_steps;
    uint8_t step_pct[LS_MANUAL_MAX_STEPS];
    uint8_t start_step; /* index of the step a switch-on starts at (clamped) */
} ls_manual_config_t;

typedef enum {
    LS_MANUAL_EV_SWITCH = 1, /* value: ls_manual_switch_t, the enabling switch's new state */
    LS_MANUAL_EV_OVERRIDE,   /* value: the new override percent */
    LS_MANUAL_EV_FRAME,      /* value: ls_jog_frame_t; joint: single-joint mode */
    LS_MANUAL_EV_LOST,       /* value: ls_manual_lost_t */
    LS_MANUAL_EV_FOUND,      /* the device is back (value: its generation) */
} ls_manual_event_kind_t;

typedef enum {
    LS_MANUAL_SWITCH_RELEASED = 0,
    LS_MANUAL_SWITCH_ENABLED,   /* held, and it lets the twist through */
    LS_MANUAL_SWITCH_PANIC,     /* pressed through to its third position */
    LS_MANUAL_SWITCH_HELD_OVER, /* held, but not re-pressed since switch-on, drives on or the device's return */
} ls_manual_switch_t;

typedef enum {
    LS_MANUAL_LOST_ABSENT = 1, /* not present: unplugged, or never found */
    LS_MANUAL_LOST_SILENT,     /* no report for longer than stale_us */
    LS_MANUAL_LOST_READ,       /* the backend's read failed */
} ls_manual_lost_t;

typedef struct {
    ls_manual_event_kind_t kind;
    int32_t value;
    bool joint; /* LS_MANUAL_EV_FRAME */
} ls_manual_event_t;

typedef struct {
    uint8_t n;
    ls_manual_event_t ev[LS_MANUAL_MAX_EVENTS];
} ls_manual_events_t;

typedef struct {
    ls_manual_config_t cfg;
    /* private to ls_manual.c */
    bool armed_;      /* the enabling switch was seen fully released since the last block */
    bool enabled_;    /* the twist passes */
    bool present_;    /* the device was judged there at the last step */
    bool rested_;     /* no enabling switch: the twist was still since the return */
    uint32_t gen_;    /* the generation seen last */
    uint32_t held_;   /* buttons held at the last step (edges); ENABLE/PANIC tracked by armed_ */
    uint32_t ignore_; /* buttons held when the device appeared: not presses until released */
    ls_manual_switch_t switch_;
    uint8_t step_;
    ls_jog_frame_t frame_;
    bool joint_;
} ls_manual_t;

/* manualControl switched on: the configuration (copied; steps sorted and
 * checked here: a step outside 1..100 is dropped), blocked until the switch
 * is released, override at cfg->start_step, tool frame, Cartesian. A NULL
 * cfg means no enabling switch, no staleness, one step of 100. */
void ls_manual_start(ls_manual_t *m, const ls_manual_config_t *cfg);

/* The drives came on (or anything else after which a held switch must be
 * released first): the twist stops passing until the switch is released and
 * pressed again (a device without one: until its twist was still once). */
void ls_manual_block(ls_manual_t *m);

/* One cycle: `st` is the device's state from hal_manual_read and `read_st`
 * that call's status (< 0: the read failed; st is then ignored). Writes the
 * twist to jog with into twist_out (zeros unless it passes; scaled by the
 * override), appends what changed to ev (may be NULL; at most
 * LS_MANUAL_MAX_EVENTS, ev->n is not reset here), and returns whether the
 * twist passes (the jog is live). NULL m or twist_out: returns false. */
bool ls_manual_step(ls_manual_t *m, const hal_manual_state_t *st, int read_st, double twist_out[6],
                    ls_manual_events_t *ev);

/* The override in percent, the frame and single-joint mode the operator
 * chose (the loop hands the last two to ls_react_jog_mode). */
uint8_t ls_manual_override_pct(const ls_manual_t *m);
ls_jog_frame_t ls_manual_frame(const ls_manual_t *m);
bool ls_manual_joint(const ls_manual_t *m);

/* The kind's name (LS_MANUAL_NAME_*), or NULL for an unknown kind. */
const char *ls_manual_kind_name(ls_manual_kind_t k);

/* Names for events and logs: "released", "enabled", "panic", "held_over";
 * "tool", "base", "world"; "unplugged", "silent", "read_error".
 * "unknown" for anything else. */
const char *ls_manual_switch_name(ls_manual_switch_t s);
const char *ls_manual_frame_name(ls_jog_frame_t f);
const char *ls_manual_lost_name(ls_manual_lost_t l);

#endif
