/* Shared between the files of hal/sim/world; not a public interface. */
#ifndef SIM_WORLD_INTERNAL_H
#define SIM_WORLD_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_dio.h"
#include "hal/hal_arm.h"

#define SIM_CTL_MAX_MSG 255u
#define SIM_DIO_INPUT_MASK 0x0000FFFFu
#define SIM_DIO_OUTPUT_MASK 0xFFFF0000u

/* The control socket and the state it drives (DIO inputs, jog, buttons). */
typedef struct {
    bool open;
    int fd;            /* -1 without a socket */
    char path[108];    /* sun_path, unlinked at close */
    uint32_t dio_bits; /* inputs (0-15) and outputs (16-31) */
    double twist[6];   /* -1..1 */
    uint32_t buttons;
    uint32_t malformed; /* messages ignored since open */
} sim_ctl_t;

/* Reset the state; bind the socket when path != NULL. Init only. */
int sim_ctl_open(sim_ctl_t *ctl, const char *path, char *msg, size_t msglen);
void sim_ctl_close(sim_ctl_t *ctl);
/* Apply one message (no terminating NUL needed). Returns 1 when it changed
 * state, 0 when not, LS_EINVAL when malformed (and counts it). */
int sim_ctl_apply(sim_ctl_t *ctl, const char *text, size_t len);
/* Read and apply every pending datagram; the number that changed state. */
int sim_ctl_drain(sim_ctl_t *ctl);
bool sim_ctl_jog_active(const sim_ctl_t *ctl);

extern const hal_dio_ops_t sim_dio_ops; /* self = sim_ctl_t* (NULL: closed) */
int sim_manual_read(void *self, double *twist, uint32_t *buttons);

#endif
