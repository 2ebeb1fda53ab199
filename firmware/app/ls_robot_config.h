/* The robot model landscaped runs ([robot] model, --model): the file the
 * configuration names, or the compiled-in ls-sim6 when it names none, and
 * with arm = sim also what the simulator can build. Other programs that
 * compose the arm from the configuration (ls-simdrives) call the same.
 * Init only: reads a file, uses stdio. */
#ifndef LS_ROBOT_CONFIG_H
#define LS_ROBOT_CONFIG_H

#include <stddef.h>

#include "ls_config.h"
#include "ls_robot_model.h"

/* Fill *model for cfg. LS_OK, or LS_EINVAL with one line in msg: the model
 * file's refusal ("FILE:LINE: [section] key: got ..., expected ...",
 * ls_robot_model_file.h) or "[hal] arm = sim cannot simulate robot model
 * NAME (FILE): ..." (hal_sim_world_check_arm). Either is a refused
 * configuration: landscaped exits 2 (LS_EXIT_BAD_CONFIG). *model untouched
 * on error. */
int ls_robot_config_load(const ls_config_t *cfg, ls_robot_model_t *model, char *msg, size_t msglen);

#endif
