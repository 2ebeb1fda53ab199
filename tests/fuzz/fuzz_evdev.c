/* The evdev manual devices' parsers (hal/linux/hal_linux_evdev.h): the first
 * bytes up to a NUL are a map's text (axes, then after a newline buttons),
 * which either parses or is refused with the map untouched; the rest is a
 * stream of input_events from a device (any type, code and value, SYN_DROPPED
 * included) through the decoder, whose twist must stay finite and within
 * -1..1 whatever the axes' ranges claim. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hal_linux_evdev.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *nul = memchr(data, 0, size);
    const size_t text_len = nul != NULL ? (size_t)(nul - data) : size;
    char text[512];
    const size_t n = text_len < sizeof text - 1 ? text_len : sizeof text - 1;
    memcpy(text, data, n);
    text[n] = '\0';
    char *buttons = strchr(text, '\n');
    if (buttons != NULL) {
        *buttons++ = '\0';
    }
    hal_evdev_map_t map, before;
    (void)hal_evdev_map_default("gamepad", &map);
    before = map;
    char why[512];
    if (hal_evdev_parse_axes(&map, text, why, sizeof why) != LS_OK &&
        memcmp(&map.axis, &before.axis, sizeof map.axis) != 0) {
        abort(); /* refused, yet changed */
    }
    if (buttons != NULL && hal_evdev_parse_buttons(&map, buttons, why, sizeof why) != LS_OK &&
        memcmp(&map.button, &before.button, sizeof map.button) != 0) {
        abort();
    }
    char out[512];
    hal_evdev_format_axes(&map, out, sizeof out);
    hal_evdev_format_buttons(&map, out, sizeof out);

    hal_evdev_decoder_t d;
    hal_evdev_decoder_init(&d, &map);
    size_t off = nul != NULL ? text_len + 1 : size;
    /* the axes' ranges from the next bytes: any, inverted or empty ones too */
    for (int i = 0; i < HAL_EVDEV_AXES && off + 12 <= size; i++, off += 12) {
        memcpy(&d.abs[i].minimum, data + off, 4);
        memcpy(&d.abs[i].maximum, data + off + 4, 4);
        memcpy(&d.abs[i].flat, data + off + 8, 4);
    }
    for (; off + 8 <= size; off += 8) {
        struct input_event ev;
        memset(&ev, 0, sizeof ev);
        memcpy(&ev.type, data + off, 2);
        memcpy(&ev.code, data + off + 2, 2);
        memcpy(&ev.value, data + off + 4, 4);
        (void)hal_evdev_decoder_feed(&d, &ev);
        double tw[HAL_EVDEV_AXES];
        hal_evdev_decoder_twist(&d, tw);
        for (int i = 0; i < HAL_EVDEV_AXES; i++) {
            if (!isfinite(tw[i]) || tw[i] < -1.0 || tw[i] > 1.0) {
                abort();
            }
        }
        if ((d.buttons & ~HAL_MANUAL_BTN_ALL) != 0u) {
            abort();
        }
    }
    return 0;
}
