/* Manual input device contract (teach pendant, 6-DOF mouse): what
 * manualControl jogs the arm from (docs/conformance.md "manualControl").
 *
 * A backend maps its device onto a normalised twist and onto the button
 * functions below; what the buttons do (the enabling switch, the override
 * steps, the jog frame) is decided by the control loop (firmware/control/
 * ls_manual.h), the same for every backend. hal/sim/world offers one device
 * driven by its control socket; hal/linux/hal_linux_evdev.h reads a Linux
 * input device (gamepad, pendant, SpaceMouse) through evdev.
 *
 * Threading: read is called from the control loop: no blocking, no
 * allocation, O(1). A backend that reads its device elsewhere (a reader
 * thread) hands the latest state over without a lock. */
#ifndef HAL_MANUAL_H
#define HAL_MANUAL_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_status.h"

/* Button functions, by index; hal_manual_state_t.buttons holds bit
 * (1 << index) of each one held. */
enum {
    HAL_MANUAL_FN_ENABLE = 0, /* enabling switch held (its middle position) */
    HAL_MANUAL_FN_PANIC,      /* enabling switch pressed through (its third position) */
    HAL_MANUAL_FN_SPEED_UP,   /* the next higher speed override step */
    HAL_MANUAL_FN_SPEED_DOWN, /* the next lower one */
    HAL_MANUAL_FN_FRAME,      /* the next jog frame: tool, base, world, tool, ... */
    HAL_MANUAL_FN_JOINT,      /* single-joint mode on / off */
    HAL_MANUAL_BTN_COUNT
};
#define HAL_MANUAL_BTN_ENABLE (1u << HAL_MANUAL_FN_ENABLE)
#define HAL_MANUAL_BTN_PANIC (1u << HAL_MANUAL_FN_PANIC)
#define HAL_MANUAL_BTN_SPEED_UP (1u << HAL_MANUAL_FN_SPEED_UP)
#define HAL_MANUAL_BTN_SPEED_DOWN (1u << HAL_MANUAL_FN_SPEED_DOWN)
#define HAL_MANUAL_BTN_FRAME (1u << HAL_MANUAL_FN_FRAME)
#define HAL_MANUAL_BTN_JOINT (1u << HAL_MANUAL_FN_JOINT)
#define HAL_MANUAL_BTN_ALL ((1u << HAL_MANUAL_BTN_COUNT) - 1u)

#define HAL_MANUAL_NAME_LEN 128 /* a /dev/input/by-id path and its NUL */

/* The device as of one read. */
typedef struct {
    /* vx vy vz wx wy wz, each -1..1 after the backend's map (dead band,
     * sign, scale); the loop takes them in the jog frame (tool, base or
     * world), or as joint speeds in single-joint mode. */
    double twist[6];
    uint32_t buttons; /* HAL_MANUAL_BTN_* held now */
    /* The device is open and readable. false: unplugged or not (yet) there;
     * twist and buttons are then zero. */
    bool present;
    /* Microseconds since the device last reported (one input report), as of
     * this read; meaningful while present. */
    uint64_t age_us;
    /* Counts the opens of the device: a change means it went away and came
     * back (re-plugged) since the last read. */
    uint32_t generation;
} hal_manual_state_t;

typedef struct {
    /* The latest state into *out: LS_OK (also for a device that is not
     * there: present false), LS_EINVAL for a NULL out, LS_ENODEV when the
     * backend is gone; *out is zeroed on error. */
    int (*read)(void *self, hal_manual_state_t *out);
    void *self;
    /* > 0: the device reports continuously, at least every stale_ms while
     * it is there, so a longer silence means it stopped (the loop stops the
     * jog and alarms). 0: it reports changes only; silence means nothing. */
    uint32_t stale_ms;
    char name[HAL_MANUAL_NAME_LEN]; /* for alarms and logs, e.g. the device's path */
} hal_manual_t;

/* The function of button bit `index` (0..HAL_MANUAL_BTN_COUNT - 1): "enable",
 * "panic", "speed_up", "speed_down", "frame", "joint" (the names of the
 * configuration's button maps and of --check); NULL past the last. */
const char *hal_manual_button_name(unsigned index);

/* The name of twist component `index` (0..5): "vx" "vy" "vz" "wx" "wy"
 * "wz"; NULL past the last. */
const char *hal_manual_axis_name(unsigned index);

/* dev->read, or LS_EUNSUPPORTED (out zeroed) when dev or its read is NULL. */
int hal_manual_read(const hal_manual_t *dev, hal_manual_state_t *out);

#endif
