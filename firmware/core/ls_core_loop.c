/* The core's actions on the control loop: the one composition of the two that
 * the app, the footprint build and the session fuzzer share (ls_core.h). */
#include "ls_control.h"
#include "ls_core.h"

/* Enabling ends in the loop (every drive confirms, or one cannot): 1 tells
 * the core to wait for LS_CEV_ENABLED / LS_CEV_ENABLE_FAILED. */
static int act_enable(void *ctx, bool on)
{
    ls_ctl_cmd_t cmd = { .kind = on ? LS_CTL_ENABLE : LS_CTL_DISABLE };
    if (!ls_control_post((ls_control_t *)ctx, &cmd)) {
        return LS_EAGAIN;
    }
    return on ? 1 : 0;
}

static void act_halt(void *ctx)
{
    ls_ctl_cmd_t cmd = { .kind = LS_CTL_HALT };
    (void)ls_control_post((ls_control_t *)ctx, &cmd);
}

static void act_stop(void *ctx)
{
    ls_ctl_cmd_t cmd = { .kind = LS_CTL_STOP };
    (void)ls_control_post((ls_control_t *)ctx, &cmd);
}

void ls_core_actions_for_loop(ls_core_actions_t *act, struct ls_control *ctl)
{
    act->enable_drives = act_enable;
    act->stop_motion = act_stop;
    act->halt = act_halt;
    act->ctx = ctl;
}
