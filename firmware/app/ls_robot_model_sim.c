#include "ls_robot_model_sim.h"

#include <string.h>

_Static_assert(LS_N_JOINTS == HAL_SIM_ARM_JOINTS, "the simulator builds an arm of LS_N_JOINTS joints");

void ls_robot_model_to_sim(const ls_robot_model_t *m, hal_sim_arm_model_t *out)
{
    memset(out, 0, sizeof *out);
    out->name = m->name;
    out->n_joints = LS_N_JOINTS;
    for (int i = 0; i < LS_N_JOINTS; i++) {
        out->dh[i].a_m = m->dh[i].a_m;
        out->dh[i].alpha_rad = m->dh[i].alpha_rad;
        out->dh[i].d_m = m->dh[i].d_m;
        out->dh[i].theta_offset_rad = m->dh[i].theta_offset_rad;
        out->q_min_rad[i] = m->q_min_rad[i];
        out->q_max_rad[i] = m->q_max_rad[i];
        out->torque_max_Nm[i] = m->torque_max_Nm[i];
        out->link_mass_kg[i] = m->link_mass_kg[i];
    }
    out->link_radius_m = m->link_radius_m;
}
