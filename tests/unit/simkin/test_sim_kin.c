/* The simulation and the firmware's kinematics describe the same arm:
 * ls_kin_fk of the joint angles ODE reports equals the flange pose ODE
 * reports, over random configurations (issue 5 acceptance, 0.1 mm). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "hal_sim_world.h"
#include "ls_kin.h"
#include "ls_robot_model.h"
#include "ls_robot_model_sim.h"

static const ls_robot_model_t *M = &ls_robot_model_default;

static void drive_to(hal_arm_t *arm, const double q1[LS_N_JOINTS])
{
    double q0[LS_N_JOINTS], qd[LS_N_JOINTS], q[LS_N_JOINTS], zero[LS_N_JOINTS] = { 0 };
    assert_int_equal(hal_arm_read(arm, q0, qd), LS_OK);
    const int steps = 1500; /* 1.5 s ramp at 1 kHz, then 0.5 s to settle */
    for (int k = 1; k <= steps + 500; k++) {
        double s = k >= steps ? 1.0 : (double)k / steps;
        s = s * s * (3.0 - 2.0 * s);
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q[j] = q0[j] + s * (q1[j] - q0[j]);
        }
        assert_int_equal(hal_arm_command(arm, q, zero), LS_OK);
        assert_true(hal_sim_world_step(NULL, 0.001) >= 0);
    }
}

static void test_fk_of_sim_joints_equals_sim_flange(void **state)
{
    (void)state;
    char msg[256];
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(M, &am);
    hal_sim_world_config_t cfg = { .arm = &am, .dio_socket_path = NULL, .lockstep = false, .with_obstacle = false };
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_OK);
    hal_arm_t arm;
    hal_sim_world_get_arm(&arm);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    srand(7);
    double worst_m = 0.0, worst_rad = 0.0;
    for (int n = 0; n < 40; n++) {
        double target[LS_N_JOINTS];
        for (int j = 0; j < LS_N_JOINTS; j++) {
            /* inside the limits, and high enough that the tool stays off the table */
            double lo = M->q_min_rad[j] * 0.6, hi = M->q_max_rad[j] * 0.6;
            target[j] = lo + (hi - lo) * ((double)rand() / RAND_MAX);
        }
        target[1] = fmin(target[1], 0.3);
        drive_to(&arm, target);
        double q[LS_N_JOINTS], qd[LS_N_JOINTS], T_sim[16], T_kin[16];
        assert_int_equal(hal_arm_read(&arm, q, qd), LS_OK);
        assert_int_equal(hal_sim_world_flange_pose(T_sim), LS_OK);
        assert_int_equal(ls_kin_fk(M, q, T_kin), LS_OK);
        double d = ls_pose_dist(T_sim, T_kin), a = ls_pose_angle(T_sim, T_kin);
        worst_m = fmax(worst_m, d);
        worst_rad = fmax(worst_rad, a);
        assert_true(d < 1e-4);
        assert_true(a < 1e-3);
    }
    print_message("worst FK vs sim over 40 configurations: %.3g m, %.3g rad\n", worst_m, worst_rad);
    hal_sim_world_close();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fk_of_sim_joints_equals_sim_flange),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
