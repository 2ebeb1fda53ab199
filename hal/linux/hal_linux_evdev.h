/* evdev backend of the manual device contract (hal/hal_manual.h): a Linux
 * input device (a gamepad or pendant that presents itself as one, a
 * 3Dconnexion SpaceMouse) read through the kernel's input_event interface.
 *
 * Map: which absolute (ABS_*) or relative (REL_*) axis is each twist
 * component (vx vy vz wx wy wz), with its sign, scale and dead band, and
 * which key (BTN_*, KEY_*) is each button function (hal_manual_button_name:
 * enable, panic, speed_up, speed_down, frame, joint). Text forms, as in the
 * configuration (docs/deploy.md "Manual devices"):
 *   axes    = vx:ABS_X, vy:-ABS_Y, vz:-ABS_RY:0.5, wz:ABS_RX:1:0.2
 *             (COMPONENT:[-]CODE[:SCALE[:DEADBAND]]; unlisted components are 0)
 *   buttons = enable:BTN_TL, speed_up:BTN_NORTH, frame:BTN_WEST
 * Code names are the kernel's (libevdev's tables, the names evtest prints).
 *
 * Normalisation: an absolute axis maps its range [min, max] (EVIOCGABS) to
 * -1..1 around its middle; a relative axis divides its last value by
 * HAL_EVDEV_REL_FULL_SCALE. Then the dead band (the larger of the axis's,
 * else the map's, and the kernel's `flat` share of the range) is cut out
 * and the rest stretched back to full scale (no step at its edge), the
 * result multiplied by the signed scale and clamped to -1..1.
 *
 * Device: a reader thread per device opens the configured path (a
 * /dev/input/by-id link survives re-plugging; the path need not exist at
 * start), reads its events without blocking anyone, and publishes the
 * latest twist, buttons, presence and report time in a seqlock slot; read()
 * (the control loop) copies the slot. An unplugged device (ENODEV, POLLHUP)
 * is closed and the path tried again every HAL_EVDEV_RETRY_MS: the same
 * device plugged again is picked up without a restart (a new generation).
 * SYN_DROPPED (the kernel's buffer overran) re-reads the keys and axes.
 *
 * Storage: a static pool of HAL_EVDEV_MAX_DEVICES backends; no heap (the
 * input_event interface needs none, which is why not libevdev's device
 * API: its re-open on re-plug would allocate after init). The thread is
 * started by open and joined by close (init and shutdown only).
 *
 * Threading: map functions anywhere (pure). open, probe, close at init and
 * shutdown. read from the control loop: one CLOCK_MONOTONIC read and a
 * bounded seqlock copy, no lock, no allocation. */
#ifndef HAL_LINUX_EVDEV_H
#define HAL_LINUX_EVDEV_H

#include <linux/input.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_manual.h"

#define HAL_EVDEV_MAX_DEVICES 2
#define HAL_EVDEV_AXES 6
#define HAL_EVDEV_REL_FULL_SCALE 350.0 /* a SpaceMouse's relative reports at full deflection */
#define HAL_EVDEV_RETRY_MS 200         /* how often an absent device's path is tried */
#define HAL_EVDEV_MAX_DEADBAND 0.9
#define HAL_EVDEV_MAX_SCALE 100.0

typedef struct {
    uint16_t type;   /* EV_ABS or EV_REL; 0: the component is not mapped */
    uint16_t code;   /* ABS_* or REL_* */
    double scale;    /* signed gain, |scale| in (0, HAL_EVDEV_MAX_SCALE]; -1 inverts */
    double deadband; /* share of full scale, 0..HAL_EVDEV_MAX_DEADBAND; < 0: the map's */
} hal_evdev_axis_t;

typedef struct {
    hal_evdev_axis_t axis[HAL_EVDEV_AXES]; /* by twist component */
    uint16_t button[HAL_MANUAL_BTN_COUNT]; /* EV_KEY code per function bit; 0: not mapped */
    double deadband;                       /* the axes' default */
} hal_evdev_map_t;

/* ---- maps (pure: any thread, no allocation) ---- */

/* A default map by name: "gamepad" (left stick x/y = vx/vy, right stick
 * y = vz, right stick x = wz, the d-pad = wx/wy; LB = enable, Y/A = speed
 * up/down, X = frame, B = joint; dead band 0.15) or "spacemouse" (the six
 * ABS axes as the kernel reports them, turned into a right-handed x right,
 * y away, z up; BTN_0 = frame, BTN_1 = joint; dead band 0.1). LS_OK, or
 * LS_EINVAL for another name (*out untouched). */
int hal_evdev_map_default(const char *name, hal_evdev_map_t *out);
/* "gamepad, spacemouse": the names hal_evdev_map_default takes. */
const char *hal_evdev_map_names(void);

/* Replace the map's axes / buttons by the text form above. LS_OK, or
 * LS_EINVAL with `why` ("expected ...", naming the item that was wrong);
 * the map is untouched on error. A component or a function given twice, a
 * key used for two functions, an unknown name or code, a code of the wrong
 * type (a key for an axis), a scale or dead band out of range: refused. */
int hal_evdev_parse_axes(hal_evdev_map_t *map, const char *text, char *why, size_t whylen);
int hal_evdev_parse_buttons(hal_evdev_map_t *map, const char *text, char *why, size_t whylen);

/* The map as text (the forms above), for logs and --check. */
void hal_evdev_format_axes(const hal_evdev_map_t *map, char *out, size_t outlen);
void hal_evdev_format_buttons(const hal_evdev_map_t *map, char *out, size_t outlen);

/* ---- decoding (pure: the reader thread; tests and the fuzzer feed it) ---- */

typedef enum {
    HAL_EVDEV_FED = 0, /* taken; the report is not complete yet */
    HAL_EVDEV_REPORT,  /* SYN_REPORT: a complete report (the state is consistent) */
    HAL_EVDEV_RESYNC,  /* SYN_DROPPED: events were lost; re-read keys and axes */
} hal_evdev_feed_t;

typedef struct {
    hal_evdev_map_t map;
    struct input_absinfo abs[HAL_EVDEV_AXES]; /* of each ABS component, from EVIOCGABS */
    int32_t raw[HAL_EVDEV_AXES];              /* each component's last value */
    uint32_t buttons;                         /* HAL_MANUAL_BTN_* held */
    bool dropping;                            /* after SYN_DROPPED, until the next SYN_REPORT */
} hal_evdev_decoder_t;

/* Start from rest with `map`; abs[] zeroed (set it from the device). */
void hal_evdev_decoder_init(hal_evdev_decoder_t *d, const hal_evdev_map_t *map);
/* One event. Events of codes the map does not use are ignored. */
hal_evdev_feed_t hal_evdev_decoder_feed(hal_evdev_decoder_t *d, const struct input_event *ev);
/* The twist of the current raw values, normalised as above. */
void hal_evdev_decoder_twist(const hal_evdev_decoder_t *d, double twist[HAL_EVDEV_AXES]);

/* ---- the device ---- */

typedef struct {
    const char *path; /* e.g. /dev/input/by-id/usb-...-event-joystick */
    hal_evdev_map_t map;
    uint32_t stale_ms; /* hal_manual_t.stale_ms: > 0 for a device that reports continuously */
} hal_evdev_config_t;

/* Take a backend from the pool and start its reader thread; the device
 * need not be there yet. LS_OK; LS_EINVAL (NULL or empty path, a path
 * longer than HAL_MANUAL_NAME_LEN - 1, no axis mapped, the pool is full) or
 * LS_EIO (the thread could not start) with `msg`. *out is filled on LS_OK
 * (name = the path), zeroed on error. Init only. */
int hal_linux_evdev_open(hal_manual_t *out, const hal_evdev_config_t *cfg, char *msg, size_t msglen);

/* Stop the thread, close the device, give the backend back. Safe on a
 * zeroed or already closed handle. Shutdown only (joins a thread). */
void hal_linux_evdev_close(hal_manual_t *dev);

/* For landscaped --check: open `path` once and describe it against `map`:
 * LS_OK with "NAME: axes ABS_X.. found, buttons BTN_.. found" in msg;
 * LS_ENODEV (no such path: not plugged in), LS_EPERM (not readable by this
 * user: the udev rule / group hint), LS_EINVAL (not an input device, or
 * mapped axes or keys it does not have, named) with msg. Init only. */
int hal_linux_evdev_probe(const char *path, const hal_evdev_map_t *map, char *msg, size_t msglen);

#endif
