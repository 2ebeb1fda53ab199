/* The simulation and the firmware's kinematics describe the same arm:
 * ls_kin_fk of the joint angles ODE reports equals the flange pose ODE
 * reports, over random configurations (0.1 mm), for the default arm and for
 * a UR5e built from its model file (firmware/model/robots/ur5e.ini). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "hal_sim_world.h"
#include "ls_math.h"
#include "ls_kin.h"
#include "ls_robot_model.h"
#include "ls_robot_model_file.h"
#include "ls_robot_model_sim.h"

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

/* 40 random targets, each joint within `spread` of home[j] and 0.6 of its
 * limits: high enough that the tool stays off the floor and the table. */
static void check_fk_equals_sim(const ls_robot_model_t *M, const double home[LS_N_JOINTS], const double spread[2])
{
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
            double lo = fmax(M->q_min_rad[j] * 0.6, home[j] + spread[0]);
            double hi = fmin(M->q_max_rad[j] * 0.6, home[j] + spread[1]);
            target[j] = lo + (hi - lo) * ((double)rand() / RAND_MAX);
        }
        if (home[1] == 0.0) {
            target[1] = fmin(target[1], 0.3);
        }
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
    print_message("%s: worst FK vs sim over 40 configurations: %.3g m, %.3g rad\n", M->name, worst_m, worst_rad);
    hal_sim_world_close();
}

static void fk_of_the_default_arms_sim_joints_equals_its_sim_flange(void **state)
{
    (void)state;
    const double home[LS_N_JOINTS] = { 0 }, spread[2] = { -10.0, 10.0 };
    check_fk_equals_sim(&ls_robot_model_default, home, spread);
}

static void fk_of_a_ur5e_built_from_its_file_equals_its_sim_flange(void **state)
{
    (void)state;
    ls_robot_model_t ur;
    char msg[512];
    if (ls_robot_model_load(LS_ROBOTS_DIR "/ur5e.ini", &ur, msg, sizeof msg) != LS_OK) {
        fail_msg("%s", msg);
    }
    /* UR's home: upper arm up, forearm level, flange pointing down. */
    const double home[LS_N_JOINTS] = { 0.0, -LS_PI / 2, LS_PI / 2, -LS_PI / 2, -LS_PI / 2, 0.0 };
    const double spread[2] = { -0.4, 0.4 };
    check_fk_equals_sim(&ur, home, spread);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(fk_of_the_default_arms_sim_joints_equals_its_sim_flange),
        cmocka_unit_test(fk_of_a_ur5e_built_from_its_file_equals_its_sim_flange),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
