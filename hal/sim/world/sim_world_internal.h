/* Shared between the files of hal/sim/world; not a public interface. */
#ifndef SIM_WORLD_INTERNAL_H
#define SIM_WORLD_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "hal/hal_dio.h"
#include "hal/hal_arm.h"
#include "hal/hal_manual.h"
#include "hal_sim_world.h"

#define SIM_CTL_MAX_MSG 255u
#define SIM_DIO_INPUT_MASK 0x0000FFFFu
#define SIM_DIO_OUTPUT_MASK 0xFFFF0000u

/* The control socket and the state it drives (DIO inputs, jog, buttons). */
typedef struct {
    bool open;
    int fd;                     /* -1 without a socket */
    char path[108];             /* sun_path, unlinked at close */
    uint32_t dio_bits;          /* inputs (0-15) and outputs (16-31) */
    double twist[6];            /* -1..1 */
    uint32_t buttons;           /* HAL_MANUAL_BTN_* */
    bool unplugged;             /* the manual device is "unplugged" (words unplug / plug) */
    uint32_t manual_generation; /* counts plugs, from 1 at open */
    uint32_t malformed;         /* messages ignored since open */
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

/* The set-point trace (hal_sim_world.h "Set-point trace"). */
typedef struct {
    double t_s; /* the world's time at the command */
    double q_rad[HAL_SIM_ARM_JOINTS];
} sim_trace_sample_t;

typedef struct {
    FILE *tmp_file;                        /* PATH.tmp from open to the write; NULL otherwise */
    char path[HAL_SIM_TRACE_PATH_MAX + 1]; /* "" = no trace */
    char tmp[HAL_SIM_TRACE_PATH_MAX + 5];  /* path + ".tmp" */
    uint32_t rate_hz;
    sim_trace_sample_t *buf; /* capacity samples, allocated at open */
    size_t capacity, n;
    uint64_t dropped; /* commands after the buffer filled */
} sim_trace_t;

/* Reset; with a path, allocate and touch the buffer and create PATH.tmp.
 * Init only. LS_OK (also with no path), LS_EINVAL or LS_EIO with msg. */
int sim_trace_open(sim_trace_t *tr, const hal_sim_trace_config_t *cfg, char *msg, size_t msglen);
/* Control loop: append one sample, or count it as dropped when full. No
 * allocation, no I/O, no lock; nothing without a trace. */
void sim_trace_record(sim_trace_t *tr, double t_s, const double *q_rad);
/* Shutdown: write PATH.tmp and rename it to PATH (hal_sim_world_trace_write). */
int sim_trace_write(sim_trace_t *tr, char *msg, size_t msglen);
/* Free the buffer; remove PATH.tmp when it was never written. Safe twice. */
void sim_trace_close(sim_trace_t *tr);

extern const hal_dio_ops_t sim_dio_ops; /* self = sim_ctl_t* (NULL: closed) */
int sim_manual_read(void *self, hal_manual_state_t *out);

#endif
