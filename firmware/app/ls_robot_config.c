/* The [robot] section: the model file, then the arm backend's needs. */
#include "ls_robot_config.h"

#include <stdio.h>
#include <string.h>

#include "hal_sim_world.h"
#include "ls_err.h"
#include "ls_robot_model_file.h"
#include "ls_robot_model_sim.h"

int ls_robot_config_load(const ls_config_t *cfg, ls_robot_model_t *model, char *msg, size_t msglen)
{
    ls_robot_model_t m = ls_robot_model_default;
    if (cfg->model[0] != '\0' && ls_robot_model_load(cfg->model, &m, msg, msglen) != LS_OK) {
        return LS_EINVAL;
    }
    if (strcmp(cfg->arm, "sim") == 0) {
        hal_sim_arm_model_t sim;
        char why[200];
        ls_robot_model_to_sim(&m, &sim);
        if (hal_sim_world_check_arm(&sim, why, sizeof why) != LS_OK) {
            snprintf(msg, msglen, "[hal] arm = sim cannot simulate robot model %s (%s): %s", m.name,
                     cfg->model[0] != '\0' ? cfg->model : "compiled in", why);
            return LS_EINVAL;
        }
    }
    *model = m;
    return LS_OK;
}
