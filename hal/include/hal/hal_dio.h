/* Digital I/O contract (seed section 4). A backend offers units 0..n-1 of up
 * to 32 lines each; each line is an input or an output.
 * Threading: read/write may be called from the control loop: they must not
 * block or allocate. */
#ifndef HAL_DIO_H
#define HAL_DIO_H

#include <stdint.h>

#include "hal/hal_status.h"

typedef struct {
    uint32_t input_mask;  /* bits that are inputs */
    uint32_t output_mask; /* bits that are outputs */
} hal_dio_unit_info_t;

typedef struct {
    /* Number of units (>= 0). */
    int (*unit_count)(void *self);
    int (*describe)(void *self, uint16_t unit, hal_dio_unit_info_t *out);
    /* Current level of every line of the unit, inputs and outputs (1 = active). */
    int (*read)(void *self, uint16_t unit, uint32_t *bits);
    /* Switch outputs: bits in `on` become active, bits in `off` inactive.
     * LS_EINVAL when a bit is not an output (nothing is changed then). */
    int (*write)(void *self, uint16_t unit, uint32_t on, uint32_t off);
    /* A file descriptor that polls readable on an input edge, or -1 (then
     * the caller samples read() each cycle). */
    int (*poll_fd)(void *self);
    /* Consume pending edge notifications (after poll_fd was readable). */
    int (*drain_events)(void *self);
    void (*close)(void *self);
} hal_dio_ops_t;

typedef struct {
    const hal_dio_ops_t *ops;
    void *self;
    char name[64];
} hal_dio_t;

int hal_dio_unit_count(hal_dio_t *dio);
int hal_dio_describe(hal_dio_t *dio, uint16_t unit, hal_dio_unit_info_t *out);
int hal_dio_read(hal_dio_t *dio, uint16_t unit, uint32_t *bits);
int hal_dio_write(hal_dio_t *dio, uint16_t unit, uint32_t on, uint32_t off);
int hal_dio_poll_fd(hal_dio_t *dio);
int hal_dio_drain_events(hal_dio_t *dio);
void hal_dio_close(hal_dio_t *dio);

#endif
