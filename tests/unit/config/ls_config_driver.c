/* Test driver: reads the configuration and runs --check exactly as
 * landscaped's main does (see the lead's wiring in firmware/app/landscaped.c),
 * so tests/integration can check exit codes and messages end to end. Instead
 * of starting the controller it prints the effective configuration. */
#include <stdio.h>

#include "ls_check.h"
#include "ls_config.h"

static ls_config_t g_cfg;

int main(int argc, char **argv)
{
    char msg[512];
    ls_config_defaults(&g_cfg);
    int r = ls_config_from_args(&g_cfg, argc, argv, msg, sizeof msg);
    if (r == 1) {
        return LS_EXIT_OK;
    }
    if (r < 0) {
        if (g_cfg.check) {
            return ls_check_config_error(msg, stdout);
        }
        fprintf(stderr, "<3>landscaped: error: %s\n", msg);
        return LS_EXIT_BAD_CONFIG;
    }
    if (g_cfg.check) {
        return ls_check_run(&g_cfg, stdout);
    }
    if (ls_config_validate(&g_cfg, msg, sizeof msg) != 0) {
        fprintf(stderr, "<3>landscaped: error: %s\n", msg);
        return LS_EXIT_BAD_CONFIG;
    }
    const ls_config_t *c = &g_cfg;
    printf("name = %s\nnode = 0x%02X\nheartbeat_timeout_ms = %u\n", c->name, (unsigned)c->node,
           (unsigned)c->heartbeat_timeout_ms);
    for (size_t i = 0; i < c->n_links; i++) {
        printf("link = %s\n", c->links[i]);
    }
    printf("arm = %s\ndio = %s\ndio_socket = %s\nclock = %s\n", c->arm, c->dio, c->dio_socket, c->clock);
    printf("rate_hz = %u\ntelemetry_hz = %u\nrt_priority = %d\nrt_cpu = %d\nlock_memory = %s\n", (unsigned)c->rate_hz,
           (unsigned)c->telemetry_hz, c->rt_priority, c->rt_cpu, c->lock_memory ? "true" : "false");
    printf("inputs =");
    for (unsigned i = 0; i < c->n_inputs; i++) {
        printf("%s%u", i > 0 ? "," : " ", c->input_offsets[i]);
    }
    printf("\noutputs =");
    for (unsigned i = 0; i < c->n_outputs; i++) {
        printf("%s%u", i > 0 ? "," : " ", c->output_offsets[i]);
    }
    printf("\nestop_input = %d\n", c->estop_input);
    return LS_EXIT_OK;
}
