/* The robot model as the simulator's arm description: hal/sim/world takes
 * its arm as plain data (hal_sim_arm_model_t) and knows nothing of the
 * firmware, so whoever composes the firmware with the simulator converts
 * here, once, at init. FK of the simulated joints equals the simulated
 * flange pose because both come from the same ls_robot_model_t
 * (tests/unit/simkin). */
#ifndef LS_ROBOT_MODEL_SIM_H
#define LS_ROBOT_MODEL_SIM_H

#include "hal_sim_world.h"
#include "ls_robot_model.h"

/* Init-time, O(joints). `out` is filled completely; it refers to m->name. */
void ls_robot_model_to_sim(const ls_robot_model_t *m, hal_sim_arm_model_t *out);

#endif
