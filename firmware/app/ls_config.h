/* landscaped's configuration: one INI file (read with inih) and command-line
 * options that override it. Every key is validated at start; an error names
 * the file, the key and the allowed values. docs/deploy.md lists the keys. */
#ifndef LS_CONFIG_H
#define LS_CONFIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define LS_CONFIG_MAX_LINKS 4
#define LS_CONFIG_MAX_LINES 16

typedef struct {
    char config_path[256];       /* --config FILE ("" = none) */
    /* [device] */
    char name[32];               /* name = landscape-sim */
    uint8_t node;                /* node = 0x10 (1..0xFE) */
    uint32_t heartbeat_timeout_ms; /* heartbeat_timeout_ms = 1000 (50..600000) */
    /* [hal] */
    char links[LS_CONFIG_MAX_LINKS][128]; /* link = slcan:pty:PATH | socketcan:IFNAME (repeatable) */
    size_t n_links;
    char arm[16];                /* arm = sim | none */
    char dio[128];               /* dio = sim | gpiod:CHIP | none */
    char dio_socket[128];        /* dio_socket = PATH (sim DIO/jog control socket; "" = none) */
    char clock[16];              /* clock = realtime | lockstep */
    /* [control] */
    uint32_t rate_hz;            /* rate_hz = 1000 (100..10000) */
    uint32_t telemetry_hz;       /* telemetry_hz = 50 (0..200; 0 = off) */
    int rt_priority;             /* rt_priority = 80 (0 = normal thread, 1..99 SCHED_FIFO) */
    int rt_cpu;                  /* rt_cpu = -1 (no pinning) */
    bool lock_memory;            /* lock_memory = true */
    /* [dio] gpiod line offsets and roles */
    uint8_t n_inputs;
    unsigned input_offsets[LS_CONFIG_MAX_LINES];   /* inputs = 0,1,2 */
    uint8_t n_outputs;
    unsigned output_offsets[LS_CONFIG_MAX_LINES];  /* outputs = 8,9 */
    int estop_input;             /* estop_input = -1 (input bit index that stops everything when active) */
    /* modes */
    bool check;                  /* --check: self-check and exit */
    bool hal_sim;                /* --hal sim: the skeleton's shorthand for arm=sim dio=sim clock=realtime */
} ls_config_t;

/* Defaults above. */
void ls_config_defaults(ls_config_t *cfg);

/* Apply argv: --config FILE is read first, then every other option overrides
 * the file. Returns 0; 1 when --help was printed (exit 0); -1 with `msg`
 * naming the option or file:key and what is allowed. */
int ls_config_from_args(ls_config_t *cfg, int argc, char **argv, char *msg, size_t msglen);

/* Read one INI file into cfg (keys override what cfg holds). -1 with msg
 * "FILE:LINE: key 'k': expected ..." on the first error. */
int ls_config_load_file(ls_config_t *cfg, const char *path, char *msg, size_t msglen);

/* Whole-configuration checks (e.g. at least one link). */
int ls_config_validate(const ls_config_t *cfg, char *msg, size_t msglen);

#endif
