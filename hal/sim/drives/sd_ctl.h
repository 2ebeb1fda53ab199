/* The control socket's commands (hal_sim_drives.h "Control socket"): the
 * parser, apart from the socket so that tests and the fuzzer reach it.
 * Portable: no OS calls, no allocation; any thread. */
#ifndef SD_CTL_H
#define SD_CTL_H

#include <stddef.h>
#include <stdint.h>

typedef enum {
    SD_CTL_EMCY,        /* node, a = code */
    SD_CTL_SILENCE,     /* node */
    SD_CTL_FREEZE_TPDO, /* node */
    SD_CTL_STICKY,      /* node, a = edges */
    SD_CTL_NO_BOOT,     /* node */
    SD_CTL_IDENTITY,    /* node, a = vendor, b = product */
    SD_CTL_STO,         /* node, a = 1 on, 0 off */
    SD_CTL_BUS_OFF,     /* a = ms */
    SD_CTL_RESET,
} sd_ctl_kind_t;

typedef struct {
    sd_ctl_kind_t kind;
    uint8_t node; /* 1..127 for the commands that name one */
    uint32_t a, b;
} sd_ctl_cmd_t;

#define SD_CTL_STICKY_MAX 1000u /* fault-reset edges one command can ask to ignore */
#define SD_CTL_BUS_OFF_MAX_MS 60000u

/* Parse one command of `len` bytes (no NUL needed; one trailing newline
 * allowed). LS_OK with *out filled, or LS_EINVAL (unknown word, a field
 * missing or extra, a number that does not parse or is out of range, over
 * HAL_SIM_DRIVES_CTL_MAX_MSG bytes); *out untouched on error. O(len). */
int sd_ctl_parse(const char *text, size_t len, sd_ctl_cmd_t *out);

#endif
