/* Manual input device contract (teach pendant, 6-DOF mouse): what
 * manualControl jogs the arm from.
 *
 * Threading: read is called from the control loop: no blocking, no
 * allocation. Units: the twist is normalised, -1..1 per component. */
#ifndef HAL_MANUAL_H
#define HAL_MANUAL_H

#include <stdint.h>

#include "hal/hal_status.h"

typedef struct {
    /* twist[6] in -1..1 (vx vy vz wx wy wz, tool frame), buttons bit mask. */
    int (*read)(void *self, double *twist, uint32_t *buttons);
    void *self;
} hal_manual_t;

#endif
