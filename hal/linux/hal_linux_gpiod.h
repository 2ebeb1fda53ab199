/* libgpiod (v1.6 API) backend of the digital I/O contract (hal/hal_dio.h).
 *
 * One GPIO chip gives one DIO unit (unit 0) with this fixed bit mapping:
 *   bit i       (0 <= i < n_inputs)  = line input_offsets[i], an input with
 *                                      edge events on both edges;
 *   bit 16 + j  (0 <= j < n_outputs) = line output_offsets[j], an output,
 *                                      driven 0 (inactive) at open.
 * So at most 16 inputs and 16 outputs; other bits read 0 and are not
 * writable. Levels are the line values libgpiod reports (1 = active; a line
 * the device tree marks active-low is inverted by the kernel).
 *
 * read() returns a cache: inputs from one gpiod_line_get_value each at open,
 * then from edge events; outputs as last written. Call drain_events when
 * poll_fd is readable (or each cycle: it never blocks) to keep it fresh.
 *
 * Storage: a static pool of HAL_LINUX_GPIOD_MAX_UNITS backends; libgpiod
 * allocates its chip and line objects during open (init-time) and frees them
 * at close. Nothing after open allocates.
 *
 * Threading: open, probe, close at init/shutdown. read, write, describe,
 * unit_count from the control loop (write is one GPIO ioctl per changed line;
 * read is an atomic load). drain_events from one thread (the control loop or
 * an I/O thread): bounded non-blocking reads. The input cache is atomic, so
 * read and drain_events may run in different threads. */
#ifndef HAL_LINUX_GPIOD_H
#define HAL_LINUX_GPIOD_H

#include <stddef.h>
#include <stdint.h>

#include "hal/hal_dio.h"

#define HAL_LINUX_GPIOD_MAX_UNITS 2
#define HAL_LINUX_GPIOD_MAX_INPUTS 16
#define HAL_LINUX_GPIOD_MAX_OUTPUTS 16
#define HAL_LINUX_GPIOD_OUTPUT_SHIFT 16
#define HAL_LINUX_GPIOD_CONSUMER "landscaped"

typedef struct {
    const char *chip; /* "gpiochip0", "0", "/dev/gpiochip0" or a chip label; NULL = "gpiochip0" */
    uint8_t n_inputs; /* <= HAL_LINUX_GPIOD_MAX_INPUTS */
    unsigned input_offsets[32];
    uint8_t n_outputs; /* <= HAL_LINUX_GPIOD_MAX_OUTPUTS */
    unsigned output_offsets[32];
} hal_linux_gpiod_config_t;

/* Open the chip and request the lines. On error `out` holds no ops and `msg`
 * names the cause and the fix:
 *   LS_EINVAL  NULL argument, too many lines, an offset used twice, an offset
 *               beyond the chip's lines, or the pool is full;
 *   LS_ENODEV  no such chip (or the path is not a GPIO character device);
 *   LS_EPERM   no access to /dev/gpiochipN (udev rule / group hint);
 *   LS_EIO     a line is busy (message names its offset and consumer) or
 *               cannot give edge events, or another libgpiod call failed.
 * Init-time only: libgpiod allocates. */
int hal_linux_gpiod_open(hal_dio_t *out, const hal_linux_gpiod_config_t *cfg, char *msg, size_t msglen);

/* Self-check for `landscaped --check`: open and close `chip` (NULL =
 * "gpiochip0"); LS_OK with "gpiochip0 [label] 8 lines" in msg, or the
 * status and message open would give for the chip. Init-time only. */
int hal_linux_gpiod_probe(const char *chip, char *msg, size_t msglen);

#endif
