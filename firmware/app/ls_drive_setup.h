/* The drive arm's composition (arm = cia402): from landscaped.conf's
 * [drives] and [joint.N] sections and each drive's EDS/DCF file to a
 * booted ls_drives_t, and the same checks for `landscaped --check`
 * (docs/deploy.md "Drives").
 *
 * What start refuses, one line each, naming the joint, the file or node
 * and the fix:
 *  - an EDS that cannot be read or parsed (ls_eds's FILE:LINE message);
 *  - an EDS that lacks what cyclic synchronous position needs: 0x6040 and
 *    0x607A mappable into an RPDO, 0x6041 and 0x6064 into a TPDO, 0x6060
 *    writable and 0x6061 readable, RPDO1 and TPDO1 with writable
 *    communication and mapping parameters, 0x1017 writable; a 0x6502 that
 *    says CSP is not supported; PDO transmission types that cannot be set
 *    and are not synchronous;
 *  - a drive cycle whose bus load is above budget_pct (ls_drive_budget's
 *    line, naming the cycle that fits);
 *  - a drive link that does not open;
 *  - a drive that does not boot within boot_timeout_ms, refuses a step of
 *    its configuration (the abort code's meaning) or has another identity
 *    than its EDS;
 *  - a readout object (brake, sto, temperature) the drive's EDS does not
 *    have, a joint that must be homed on a drive without homing mode, a
 *    home offset or following-error window beyond its object's range;
 *  - a drive whose software position limits (0x607D) do not contain the
 *    robot model's joint limits.
 * Warnings (logged, and WARN lines in --check): what a drive's EDS does
 * not let the controller set (0x1016: the drive cannot watch the
 * controller's heartbeat; 0x6007; 0x60C2; 0x60B1 when feed-forward is on;
 * a configured 0x6065, 0x6066, 0x605A, 0x6098 or 0x607C; 0x6060/0x6061 in
 * the PDOs; a readout object it does not let be mapped, or that finds no
 * room in two TPDOs) or read (0x607D).
 *
 * Init-time only (reads files, opens the link, waits for the drives with
 * a deadline); nothing here runs in the control loop. The composed arm's
 * operations then belong to the control thread (ls_drives.h). */
#ifndef LS_DRIVE_SETUP_H
#define LS_DRIVE_SETUP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "hal/hal_arm.h"
#include "hal/hal_can.h"
#include "ls_config.h"
#include "ls_drives.h"
#include "ls_robot_model.h"

#define LS_DRIVE_SETUP_MAX_WARNINGS 16u
#define LS_DRIVE_SETUP_LINE 320u

/* What the offline part found: the drive arm's configuration (its link is
 * filled by ls_drive_compose), the bus budget's line and the warnings. */
typedef struct {
    ls_drives_config_t drives;
    char budget[LS_DRIVE_SETUP_LINE]; /* ls_drive_budget_format's line */
    bool budget_fits;
    size_t n_warnings;
    char warnings[LS_DRIVE_SETUP_MAX_WARNINGS][LS_DRIVE_SETUP_LINE];
} ls_drive_plan_t;

/* The offline part: every joint's EDS read and checked against what CSP
 * needs, the drives' configuration derived from it and the configuration
 * file, and the bus budget computed. Returns LS_OK (with the budget's
 * verdict in budget_fits: a refusal is the caller's, which --check reports
 * and start turns into its one line), or LS_EINVAL / LS_EIO with `msg`
 * naming the joint, the file and what is wrong. cfg must have passed
 * ls_config_validate with arm = cia402. */
int ls_drive_plan(const ls_config_t *cfg, ls_drive_plan_t *plan, char *msg, size_t msglen);

/* Start: plan (refusing a budget above the ceiling), open the drive link,
 * boot and configure every drive within its deadline, then check each
 * drive's software position limits (0x607D) against the joint limits of
 * `model` (the composition's robot model): a drive range that does not
 * contain the model's refuses the start (LS_ERANGE, naming the joint, the
 * node and both ranges), the drives reset and the link closed. On success
 * *arm is the drives' arm (valid until ls_drive_shutdown) and `log` (may
 * be NULL) got the warnings and the budget line, each line prefixed as
 * landscaped's logs. LS_OK, or a negative status with `msg` the one line
 * to log. */
int ls_drive_compose(const ls_config_t *cfg, const ls_robot_model_t *model, hal_arm_t *arm, FILE *log, char *msg,
                     size_t msglen);

/* At exit, after the control thread stopped: every drive disabled, then
 * reset communication (the drives stop their PDOs and forget the
 * controller's heartbeat, which would otherwise fault them), the link
 * closed. Idempotent; nothing when no drive arm was composed. */
void ls_drive_shutdown(void);

/* `landscaped --check`'s drive checks, each reported through `say` (level
 * 0 PASS, 1 WARN, 2 FAIL as ls_check_level_t; `what` the check's name,
 * `line` its finding): the plan (every EDS, the budget, the warnings), the
 * drive link, then on the bus each node's answer to SDO reads of 0x1000
 * and 0x1018 against its EDS, within boot_timeout_ms. No NMT command and no
 * write: a check never moves or reconfigures a drive. */
typedef void (*ls_drive_say_fn)(void *ctx, int level, const char *what, const char *line);
/* Returns false when the configuration itself is refused (an EDS's
 * content, the budget: what makes landscaped exit 2 at start), true
 * otherwise (an EDS file this machine lacks is a failed check). */
bool ls_drive_check(const ls_config_t *cfg, ls_drive_say_fn say, void *ctx);

#endif
