/* bench_drive_budget: the drive bus's load per cycle for six CiA 402 axes,
 * as landscaped computes it (bench/b_drives.py, benchmark 14).
 *
 *   bench_drive_budget CONFIG
 *
 * CONFIG is a landscaped.conf with arm = cia402 and six [joint.N] sections
 * (read by landscaped's own loader). For each bitrate (1 Mbit/s, 500
 * kbit/s), velocity feed-forward (off, on) and drive cycle (1, 2, 4
 * control periods at the file's rate) the program sets those three keys,
 * runs landscaped's drive plan (ls_drive_plan: every EDS read, the PDOs it
 * maps, the budget line start and --check print) and ls_drive_budget on
 * the same PDOs for the figures behind the line. The two must agree: the
 * line this program formats from its figures is compared with the plan's,
 * so a change of the PDOs landscaped maps cannot leave this benchmark
 * measuring something else.
 *
 * stdout, one line per case, tab-separated:
 *   bitrate cycle_us ff frames bits load_pct ceiling_pct fits min_multiple line
 * Exit 1 (one line on stderr) when the configuration is refused or the
 * figures disagree with the plan. */
#include <stdio.h>
#include <string.h>

#include "ls_config.h"
#include "ls_drive_budget.h"
#include "ls_drive_setup.h"

/* The PDOs ls_drives maps (ls_drives.h): RPDO1 = controlword (16 bits) +
 * target position (32), RPDO2 = velocity offset (32) when fed forward,
 * TPDO1 = statusword (16) + position actual (32). */
#define RPDO1_BYTES ((16u + 32u) / 8u)
#define RPDO2_BYTES (32u / 8u)
#define TPDO1_BYTES ((16u + 32u) / 8u)

static const uint32_t k_bitrates[] = { 1000000u, 500000u };
static const uint32_t k_cycles[] = { 1u, 2u, 4u };

static int run_case(ls_config_t *cfg, uint32_t bitrate, bool ff, uint32_t cycle)
{
    static ls_drive_plan_t plan; /* large: not on the stack */
    char msg[512];
    cfg->drives_bitrate = bitrate;
    cfg->drives_feedforward = ff;
    cfg->drives_cycle = cycle;
    if (ls_config_validate(cfg, msg, sizeof msg) != 0 || ls_drive_plan(cfg, &plan, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "bench_drive_budget: %s\n", msg);
        return 1;
    }
    ls_drive_budget_axis_t axes[LS_N_JOINTS];
    memset(axes, 0, sizeof axes);
    for (size_t j = 0; j < LS_N_JOINTS; j++) {
        const bool fed = plan.drives.joint[j].feedforward;
        axes[j].n_rpdo = fed ? 2u : 1u;
        axes[j].rpdo_bytes[0] = RPDO1_BYTES;
        axes[j].rpdo_bytes[1] = fed ? RPDO2_BYTES : 0u;
        axes[j].n_tpdo = 1u;
        axes[j].tpdo_bytes[0] = TPDO1_BYTES;
        axes[j].heartbeat_ms = cfg->drives_heartbeat_ms;
    }
    const ls_drive_budget_in_t in = { .control_period_us = plan.drives.control_period_us,
                                      .cycle_us = plan.drives.control_period_us * cycle,
                                      .bitrate = bitrate,
                                      .master_heartbeat_ms = cfg->drives_heartbeat_ms,
                                      .ceiling_pct = (double)cfg->drives_budget_pct,
                                      .axes = axes,
                                      .n_axes = LS_N_JOINTS };
    ls_drive_budget_t b;
    char line[LS_DRIVE_SETUP_LINE];
    if (ls_drive_budget_compute(&in, &b) != LS_OK) {
        fprintf(stderr, "bench_drive_budget: ls_drive_budget_compute refused the case\n");
        return 1;
    }
    (void)ls_drive_budget_format(&in, &b, line, sizeof line);
    if (strcmp(line, plan.budget) != 0 || b.fits != plan.budget_fits) {
        fprintf(stderr,
                "bench_drive_budget: the PDOs of bench/drive_budget.c no longer match landscaped's plan: '%s' vs "
                "'%s' (update RPDO1_BYTES.. from ls_drives.h)\n",
                line, plan.budget);
        return 1;
    }
    printf("%u\t%u\t%d\t%.3f\t%.3f\t%.3f\t%.1f\t%d\t%u\t%s\n", (unsigned)bitrate, (unsigned)in.cycle_us, ff ? 1 : 0,
           b.frames_per_cycle, b.bits_per_cycle, b.load_pct, b.ceiling_pct, b.fits ? 1 : 0,
           (unsigned)b.min_cycle_multiple, line);
    return 0;
}

int main(int argc, char **argv)
{
    static ls_config_t cfg;
    char msg[512];
    if (argc != 2) {
        fprintf(stderr, "usage: bench_drive_budget CONFIG (a landscaped.conf with arm = cia402)\n");
        return 2;
    }
    ls_config_defaults(&cfg);
    if (ls_config_load_file(&cfg, argv[1], msg, sizeof msg) != 0) {
        fprintf(stderr, "bench_drive_budget: %s\n", msg);
        return 1;
    }
    for (size_t b = 0; b < sizeof k_bitrates / sizeof k_bitrates[0]; b++) {
        for (int ff = 0; ff <= 1; ff++) {
            for (size_t c = 0; c < sizeof k_cycles / sizeof k_cycles[0]; c++) {
                if (run_case(&cfg, k_bitrates[b], ff != 0, k_cycles[c]) != 0) {
                    return 1;
                }
            }
        }
    }
    return 0;
}
