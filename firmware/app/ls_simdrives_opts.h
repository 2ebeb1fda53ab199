/* ls-simdrives' command line (ls_simdrives.c): parsed and checked here, apart
 * from the program, so that the unit tests reach every refusal. Init only;
 * no allocation. */
#ifndef LS_SIMDRIVES_OPTS_H
#define LS_SIMDRIVES_OPTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal_sim_drives.h"

#define LS_SIMDRIVES_FIRST_NODE 0x21u /* the default nodes: 0x21.. for joints 1.. */
/* The default position unit: a 2^17-count encoder behind a 100:1 gear. */
#define LS_SIMDRIVES_COUNTS_PER_REV (131072.0 * 100.0)

typedef struct {
    char link[256];        /* slcan:pty:PATH or socketcan:IFNAME */
    char control[108];     /* "" = no control socket */
    char link_faults[256]; /* "" = none (hal/sim/faulty_link.h SPEC) */
    char model[256];       /* "" = the compiled-in ls-sim6; else a robot model file (ls_robot_model_file.h) */
    size_t n_nodes;        /* drive i drives joint i + 1 */
    uint8_t nodes[HAL_SIM_DRIVES_MAX];
    int32_t offsets[HAL_SIM_DRIVES_MAX]; /* position offset per node, counts */
    double counts_per_rad;
    int rt_priority;  /* 0: a normal process; 1..99: SCHED_FIFO at that priority (drives answer in time) */
    double substep_s; /* --substep-ms: the physics' sub-step (hal_sim_drives_config_t.substep_s) */
    bool sync_stats;  /* --sync-stats: SYNC intervals as received, one line at exit (ls_simdrives_sync.h) */
} ls_simdrives_opts_t;

/* The --help text (stdout). */
extern const char ls_simdrives_usage[];

/* Parse argv into *o (defaults first). 0: run; 1: --help was asked;
 * LS_EINVAL: refused, with one line in msg naming the option, what was
 * wrong and what is expected. Uses getopt_long (resets optind). */
int ls_simdrives_parse(int argc, char **argv, ls_simdrives_opts_t *o, char *msg, size_t msglen);

#endif
