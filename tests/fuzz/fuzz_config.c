/* The configuration-file parser (firmware/app/ls_config.c, inih underneath):
 * any bytes either load, and then validate or fail validation with a message,
 * or fail to load with a "FILE:LINE: ..." message; never a crash, a hang or
 * an unterminated string. The input reaches the parser as a file (a memfd
 * seen through /proc/self/fd), exactly as --config FILE does. */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_file.h"
#include "ls_config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_terminated(const char *s, size_t cap)
{
    if (memchr(s, '\0', cap) == NULL) {
        __builtin_trap();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_input_file(data, size);
    ls_config_t cfg;
    ls_config_defaults(&cfg);
    char msg[512] = "";
    if (ls_config_load_file(&cfg, path, msg, sizeof msg) != 0) {
        if (msg[0] == '\0') {
            __builtin_trap(); /* an error must say what is wrong */
        }
        check_terminated(msg, sizeof msg);
        return 0;
    }
    check_terminated(cfg.name, sizeof cfg.name);
    check_terminated(cfg.arm, sizeof cfg.arm);
    check_terminated(cfg.dio, sizeof cfg.dio);
    check_terminated(cfg.dio_socket, sizeof cfg.dio_socket);
    check_terminated(cfg.clock, sizeof cfg.clock);
    if (cfg.n_links > LS_CONFIG_MAX_LINKS || cfg.n_inputs > LS_CONFIG_MAX_LINES ||
        cfg.n_outputs > LS_CONFIG_MAX_LINES) {
        __builtin_trap();
    }
    for (size_t i = 0; i < cfg.n_links; i++) {
        check_terminated(cfg.links[i], sizeof cfg.links[i]);
    }
    msg[0] = '\0';
    if (ls_config_validate(&cfg, msg, sizeof msg) != 0 && msg[0] == '\0') {
        __builtin_trap();
    }
    return 0;
}
