/* evdev maps and the event decoder (hal_linux_evdev.h): pure functions;
 * libevdev serves the kernel's code names only. */
#include <ctype.h>
#include <errno.h>
#include <libevdev/libevdev.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hal_linux_evdev.h"

#define ITEM_MAX 64

static const char *const k_map_names = "gamepad, spacemouse";

static hal_evdev_axis_t ax(uint16_t type, uint16_t code, double scale)
{
    return (hal_evdev_axis_t){ .type = type, .code = code, .scale = scale, .deadband = -1.0 };
}

int hal_evdev_map_default(const char *name, hal_evdev_map_t *out)
{
    hal_evdev_map_t m;
    memset(&m, 0, sizeof m);
    if (name != NULL && strcmp(name, "gamepad") == 0) {
        /* Linux gamepad layout (Documentation/input/gamepad.rst): y axes grow downwards */
        m.axis[0] = ax(EV_ABS, ABS_X, 1.0);
        m.axis[1] = ax(EV_ABS, ABS_Y, -1.0);
        m.axis[2] = ax(EV_ABS, ABS_RY, -1.0);
        m.axis[3] = ax(EV_ABS, ABS_HAT0Y, -1.0);
        m.axis[4] = ax(EV_ABS, ABS_HAT0X, 1.0);
        m.axis[5] = ax(EV_ABS, ABS_RX, -1.0);
        m.button[HAL_MANUAL_FN_ENABLE] = BTN_TL; /* the left shoulder button, held */
        m.button[HAL_MANUAL_FN_SPEED_UP] = BTN_NORTH;
        m.button[HAL_MANUAL_FN_SPEED_DOWN] = BTN_SOUTH;
        m.button[HAL_MANUAL_FN_FRAME] = BTN_WEST;
        m.button[HAL_MANUAL_FN_JOINT] = BTN_EAST;
        m.deadband = 0.15;
    } else if (name != NULL && strcmp(name, "spacemouse") == 0) {
        /* 3Dconnexion: x right, y towards the operator, z down; rotations about those */
        m.axis[0] = ax(EV_ABS, ABS_X, 1.0);
        m.axis[1] = ax(EV_ABS, ABS_Y, -1.0);
        m.axis[2] = ax(EV_ABS, ABS_Z, -1.0);
        m.axis[3] = ax(EV_ABS, ABS_RX, 1.0);
        m.axis[4] = ax(EV_ABS, ABS_RY, -1.0);
        m.axis[5] = ax(EV_ABS, ABS_RZ, -1.0);
        m.button[HAL_MANUAL_FN_FRAME] = BTN_0;
        m.button[HAL_MANUAL_FN_JOINT] = BTN_1;
        m.deadband = 0.1;
    } else {
        return LS_EINVAL;
    }
    *out = m;
    return LS_OK;
}

const char *hal_evdev_map_names(void)
{
    return k_map_names;
}

static int why_(char *why, size_t whylen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int why_(char *why, size_t whylen, const char *fmt, ...)
{
    if (why != NULL && whylen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, whylen, fmt, ap);
        va_end(ap);
    }
    return LS_EINVAL;
}

/* The next comma-separated item of *p, trimmed, into item: 1, or 0 at the
 * end, or LS_EINVAL with why (an empty or over-long item; `form` says what
 * the text should be). */
static int next_item(const char **p, char (*item)[ITEM_MAX], const char *form, char *why, size_t whylen)
{
    const char *s = *p;
    while (*s == ' ' || *s == '\t') {
        s++;
    }
    if (*s == '\0') {
        return 0;
    }
    const char *end = strchr(s, ',');
    size_t n = end != NULL ? (size_t)(end - s) : strlen(s);
    *p = end != NULL ? end + 1 : s + n;
    while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\t')) {
        n--;
    }
    const bool too_long = n >= sizeof *item;
    if (too_long) {
        n = sizeof *item - 1;
    }
    memcpy(*item, s, n);
    (*item)[n] = '\0';
    if (too_long) {
        return why_(why, whylen, "%s (item '%s...' is too long)", form, *item);
    }
    if (n == 0) {
        return why_(why, whylen, "%s (an empty item)", form);
    }
    return 1;
}

/* A number in [lo, hi]; no blanks, no junk. */
static bool number(const char *s, double lo, double hi, double *out)
{
    if (s[0] == '\0' || isspace((unsigned char)s[0])) {
        return false;
    }
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (errno != 0 || *end != '\0' || !isfinite(v) || v < lo || v > hi) {
        return false;
    }
    *out = v;
    return true;
}

#define NO_CODE (-1) /* libevdev's answer for a name it does not know */

static int code_of(const char *name, int type)
{
    if (libevdev_event_type_from_code_name(name) != type) {
        return NO_CODE;
    }
    return libevdev_event_code_from_code_name(name);
}

static const char *code_name(unsigned type, unsigned code)
{
    const char *n = libevdev_event_code_get_name(type, code);
    return n != NULL ? n : "?";
}

int hal_evdev_parse_axes(hal_evdev_map_t *map, const char *text, char *why, size_t whylen)
{
    static const char *form = "COMPONENT:[-]CODE[:SCALE[:DEADBAND]] items separated by commas, COMPONENT one of "
                              "vx, vy, vz, wx, wy, wz, CODE an ABS_* or REL_* axis, e.g. vx:ABS_X, vy:-ABS_Y:0.5";
    if (map == NULL || text == NULL) {
        return why_(why, whylen, "%s", form);
    }
    hal_evdev_axis_t axes[HAL_EVDEV_AXES];
    memset(axes, 0, sizeof axes);
    const char *p = text;
    char item[ITEM_MAX];
    unsigned n = 0;
    int got;
    while ((got = next_item(&p, &item, form, why, whylen)) == 1) {
        char *f[4] = { item, NULL, NULL, NULL };
        unsigned nf = 1;
        for (char *c = item; *c != '\0' && nf <= 4; c++) {
            if (*c == ':') {
                *c = '\0';
                if (nf == 4) {
                    nf = 5;
                    break;
                }
                f[nf++] = c + 1;
            }
        }
        if (nf < 2 || nf > 4) {
            return why_(why, whylen, "%s (item %u has %u fields)", form, n + 1, nf);
        }
        int k = -1;
        for (unsigned i = 0; i < HAL_EVDEV_AXES; i++) {
            if (strcmp(f[0], hal_manual_axis_name(i)) == 0) {
                k = (int)i;
            }
        }
        if (k < 0) {
            return why_(why, whylen, "%s (unknown component '%s')", form, f[0]);
        }
        if (axes[k].type != 0) {
            return why_(why, whylen, "%s (%s is mapped twice)", form, f[0]);
        }
        const char *cname = f[1];
        double sign = 1.0;
        if (cname[0] == '-') {
            sign = -1.0;
            cname++;
        }
        int type = libevdev_event_type_from_code_name(cname);
        int code = type == EV_ABS || type == EV_REL ? libevdev_event_code_from_code_name(cname) : NO_CODE;
        if (code < 0) {
            return why_(why, whylen, "%s (%s: '%s' is no ABS_* or REL_* axis)", form, f[0], cname);
        }
        double scale = 1.0;
        double db = -1.0;
        if (nf >= 3 && !(number(f[2], -HAL_EVDEV_MAX_SCALE, HAL_EVDEV_MAX_SCALE, &scale) && scale != 0.0)) {
            return why_(why, whylen, "%s (%s: scale '%s' is not a number in (0, %g] or [-%g, 0))", form, f[0], f[2],
                        HAL_EVDEV_MAX_SCALE, HAL_EVDEV_MAX_SCALE);
        }
        if (nf == 4 && !number(f[3], 0.0, HAL_EVDEV_MAX_DEADBAND, &db)) {
            return why_(why, whylen, "%s (%s: dead band '%s' is not a number in 0..%g)", form, f[0], f[3],
                        HAL_EVDEV_MAX_DEADBAND);
        }
        axes[k] =
            (hal_evdev_axis_t){ .type = (uint16_t)type, .code = (uint16_t)code, .scale = sign * scale, .deadband = db };
        n++;
    }
    if (got < 0) {
        return got;
    }
    if (n == 0) {
        return why_(why, whylen, "%s (none given)", form);
    }
    memcpy(map->axis, axes, sizeof axes);
    return LS_OK;
}

int hal_evdev_parse_buttons(hal_evdev_map_t *map, const char *text, char *why, size_t whylen)
{
    static const char *form = "FUNCTION:KEY items separated by commas, FUNCTION one of enable, panic, speed_up, "
                              "speed_down, frame, joint, KEY a BTN_* or KEY_* code, e.g. enable:BTN_TL, frame:BTN_WEST";
    if (map == NULL || text == NULL) {
        return why_(why, whylen, "%s", form);
    }
    uint16_t b[HAL_MANUAL_BTN_COUNT];
    memset(b, 0, sizeof b);
    const char *p = text;
    char item[ITEM_MAX];
    int got;
    while ((got = next_item(&p, &item, form, why, whylen)) == 1) {
        char *colon = strchr(item, ':');
        if (colon == NULL || strchr(colon + 1, ':') != NULL) {
            return why_(why, whylen, "%s (item '%s')", form, item);
        }
        *colon = '\0';
        int k = -1;
        for (unsigned i = 0; i < HAL_MANUAL_BTN_COUNT; i++) {
            if (strcmp(item, hal_manual_button_name(i)) == 0) {
                k = (int)i;
            }
        }
        if (k < 0) {
            return why_(why, whylen, "%s (unknown function '%s')", form, item);
        }
        if (b[k] != 0) {
            return why_(why, whylen, "%s (%s is mapped twice)", form, item);
        }
        int code = code_of(colon + 1, EV_KEY);
        if (code <= 0) {
            return why_(why, whylen, "%s (%s: '%s' is no BTN_* or KEY_* code)", form, item, colon + 1);
        }
        for (unsigned i = 0; i < HAL_MANUAL_BTN_COUNT; i++) {
            if (b[i] == (uint16_t)code) {
                return why_(why, whylen, "%s (%s is both %s and %s)", form, colon + 1, hal_manual_button_name(i), item);
            }
        }
        b[k] = (uint16_t)code;
    }
    if (got < 0) {
        return got;
    }
    memcpy(map->button, b, sizeof b);
    return LS_OK;
}

void hal_evdev_format_axes(const hal_evdev_map_t *map, char *out, size_t outlen)
{
    size_t used = 0;
    if (outlen == 0) {
        return;
    }
    out[0] = '\0';
    for (unsigned i = 0; i < HAL_EVDEV_AXES && used < outlen; i++) {
        const hal_evdev_axis_t *a = &map->axis[i];
        if (a->type == 0) {
            continue;
        }
        int w = snprintf(out + used, outlen - used, "%s%s:%s%s", used > 0 ? ", " : "", hal_manual_axis_name(i),
                         a->scale < 0.0 ? "-" : "", code_name(a->type, a->code));
        used += w > 0 ? (size_t)w : 0u;
        if (used < outlen && fabs(a->scale) != 1.0) {
            w = snprintf(out + used, outlen - used, ":%g", fabs(a->scale));
            used += w > 0 ? (size_t)w : 0u;
        }
        if (used < outlen && a->deadband >= 0.0) {
            w = snprintf(out + used, outlen - used, "%s:%g", fabs(a->scale) != 1.0 ? "" : ":1", a->deadband);
            used += w > 0 ? (size_t)w : 0u;
        }
    }
}

void hal_evdev_format_buttons(const hal_evdev_map_t *map, char *out, size_t outlen)
{
    size_t used = 0;
    if (outlen == 0) {
        return;
    }
    out[0] = '\0';
    for (unsigned i = 0; i < HAL_MANUAL_BTN_COUNT && used < outlen; i++) {
        if (map->button[i] == 0) {
            continue;
        }
        int w = snprintf(out + used, outlen - used, "%s%s:%s", used > 0 ? ", " : "", hal_manual_button_name(i),
                         code_name(EV_KEY, map->button[i]));
        used += w > 0 ? (size_t)w : 0u;
    }
    if (used == 0) {
        snprintf(out, outlen, "none");
    }
}

/* ---- decoder ---- */

void hal_evdev_decoder_init(hal_evdev_decoder_t *d, const hal_evdev_map_t *map)
{
    memset(d, 0, sizeof *d);
    d->map = *map;
}

hal_evdev_feed_t hal_evdev_decoder_feed(hal_evdev_decoder_t *d, const struct input_event *ev)
{
    if (ev->type == EV_SYN) {
        if (ev->code == SYN_DROPPED) {
            d->dropping = true;
            return HAL_EVDEV_FED;
        }
        if (ev->code == SYN_REPORT) {
            if (d->dropping) {
                d->dropping = false; /* the state of the events before is unknown: re-read it */
                return HAL_EVDEV_RESYNC;
            }
            return HAL_EVDEV_REPORT;
        }
        return HAL_EVDEV_FED;
    }
    if (d->dropping) {
        return HAL_EVDEV_FED; /* the kernel's manual: ignore up to the next SYN_REPORT */
    }
    if (ev->type == EV_ABS || ev->type == EV_REL) {
        for (unsigned i = 0; i < HAL_EVDEV_AXES; i++) {
            if (d->map.axis[i].type == ev->type && d->map.axis[i].code == ev->code) {
                d->raw[i] = ev->value;
            }
        }
    } else if (ev->type == EV_KEY) {
        for (unsigned i = 0; i < HAL_MANUAL_BTN_COUNT; i++) {
            if (d->map.button[i] != 0 && d->map.button[i] == ev->code) {
                if (ev->value != 0) { /* 1 press, 2 autorepeat */
                    d->buttons |= 1u << i;
                } else {
                    d->buttons &= ~(1u << i);
                }
            }
        }
    }
    return HAL_EVDEV_FED;
}

void hal_evdev_decoder_twist(const hal_evdev_decoder_t *d, double twist[HAL_EVDEV_AXES])
{
    for (unsigned i = 0; i < HAL_EVDEV_AXES; i++) {
        const hal_evdev_axis_t *a = &d->map.axis[i];
        twist[i] = 0.0;
        double x;
        double db = a->deadband >= 0.0 ? a->deadband : d->map.deadband;
        if (a->type == EV_ABS) {
            const struct input_absinfo *ai = &d->abs[i];
            if (ai->maximum <= ai->minimum) {
                continue; /* no range: nothing to scale by */
            }
            const double half = ((double)ai->maximum - (double)ai->minimum) / 2.0;
            const double mid = ((double)ai->maximum + (double)ai->minimum) / 2.0;
            x = ((double)d->raw[i] - mid) / half;
            db = fmax(db, (double)ai->flat / half);
        } else if (a->type == EV_REL) {
            x = (double)d->raw[i] / HAL_EVDEV_REL_FULL_SCALE;
        } else {
            continue;
        }
        db = fmin(fmax(db, 0.0), HAL_EVDEV_MAX_DEADBAND);
        const double mag = fabs(x);
        if (!(mag > db)) {
            continue;
        }
        double y = copysign((mag - db) / (1.0 - db), x) * a->scale;
        twist[i] = y > 1.0 ? 1.0 : (y < -1.0 ? -1.0 : y);
    }
}
