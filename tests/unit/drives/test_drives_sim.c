/* The drive arm (firmware/drives/ls_drives.h) against the simulated drives
 * (hal/sim/drives) in one process (tests/support/drive_rig.h: two
 * in-memory links joined back to back, time driven by the test, nothing
 * sleeps). What the arm reports is checked against what the simulated
 * drive does (its world's joint, its objects read over the same bus),
 * never against the arm's own code: homing with the mode in the PDOs and
 * over SDO, the readouts (402 state, mode, brake, safe torque off,
 * temperature, torque, velocity), a homing kept across disable and enable
 * and lost when the drive boots again, a homing interrupted, an enable
 * right after a disable, safe torque off refusing the enable, and the
 * software position limits against a model's. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "drive_rig.h"
#include "hal_sim_drives.h"
#include "hal_sim_world.h"
#include "ls_canopen.h"
#include "ls_drives.h"

#define NJ DRIVE_RIG_JOINTS
#define CPR DRIVE_RIG_CPR
#define HOME_OFFSET DRIVE_RIG_HOME_OFFSET

static ls_drives_t g_d;
static hal_arm_t g_arm;
static uint64_t g_now;

static void step_ms(unsigned ms)
{
    drive_rig_step(&g_arm, &g_now, ms);
}

static void open_rig(bool map_mode)
{
    char msg[200] = "";
    const ls_drives_config_t c = drive_rig_config(map_mode);
    if (drive_rig_open(&c, &g_d, &g_arm, &g_now, msg, sizeof msg) != LS_OK) {
        fail_msg("%s", msg);
    }
    step_ms(20);
}

static int setup_pdo(void **state)
{
    (void)state;
    open_rig(true);
    return 0;
}

static int setup_sdo(void **state)
{
    (void)state;
    open_rig(false);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    assert_int_equal(drive_rig_bad_frames(), 0);
    drive_rig_close();
    return 0;
}

static void status(hal_joint_status_t *st)
{
    assert_int_equal(hal_arm_status(&g_arm, true, NJ, st), LS_OK);
}

/* Enable, holding where the joints are, until every joint confirms. */
static void enable(void)
{
    assert_int_equal(hal_arm_enable(&g_arm, true), LS_OK);
    hal_joint_status_t st[NJ];
    for (int ms = 0; ms < 200; ms++) {
        double q[NJ], qd[NJ];
        assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
        assert_int_equal(hal_arm_command(&g_arm, q, NULL), LS_OK);
        step_ms(1);
        status(st);
        bool all = true;
        for (int j = 0; j < NJ; j++) {
            all = all && st[j].state == HAL_JOINT_ENABLED;
        }
        if (all) {
            return;
        }
    }
    fail_msg("not enabled: joint 1 %d '%s'", (int)st[0].state, st[0].text);
}

static void readout(hal_arm_readout_t *r)
{
    assert_int_equal(hal_arm_readout(&g_arm, r), LS_OK);
    assert_int_equal(r->n_joints, NJ);
}

/* The arm holds the measured position while the drives home: the loop's
 * part. Returns the joint's home state once it is no longer HOMING. */
static hal_home_t run_homing(int j, unsigned max_ms)
{
    hal_joint_status_t st[NJ];
    for (unsigned ms = 0; ms < max_ms; ms++) {
        double q[NJ], qd[NJ];
        assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
        assert_int_equal(hal_arm_command(&g_arm, q, NULL), LS_OK);
        step_ms(1);
        status(st);
        assert_int_equal(st[j].state, HAL_JOINT_ENABLED); /* under control throughout */
        if (st[j].home != HAL_HOME_HOMING) {
            return st[j].home;
        }
    }
    fail_msg("homing did not end within %u ms", max_ms);
    return HAL_HOME_HOMING;
}

static double world_q(int j)
{
    hal_arm_t w;
    hal_sim_world_get_arm(&w);
    double q[NJ], qd[NJ];
    assert_int_equal(hal_arm_read(&w, q, qd), LS_OK);
    return q[j];
}

/* Joint j's set-point moves by `by` rad on a 200 ms ramp from where the arm
 * reads it now, then holds for 200 ms; the others hold. Returns where the
 * ramp started. */
static double ramp_joint(int j, double by)
{
    double q[NJ], qd[NJ];
    assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
    const double q0 = q[j];
    for (int ms = 0; ms < 400; ms++) {
        q[j] = q0 + by * fmin(1.0, ms / 200.0);
        assert_int_equal(hal_arm_command(&g_arm, q, NULL), LS_OK);
        step_ms(1);
    }
    return q0;
}

/* ---- tests ---- */

static void test_the_readouts_say_what_the_drives_publish(void **state)
{
    (void)state;
    hal_arm_readout_t r;
    readout(&r);
    assert_true(r.t_us > 0u);
    for (int j = 0; j < NJ; j++) {
        const hal_drive_readout_t *o = &r.joint[j];
        assert_int_equal(o->node, 0x21 + j);
        assert_string_equal(o->state, "SWITCH ON DISABLED");
        assert_int_equal(o->mode, LS_CO_MODE_CSP);
        assert_int_equal(o->brake, HAL_TRI_ON); /* off: the brake holds */
        assert_int_equal(o->sto, HAL_TRI_OFF);
        assert_true(o->has_temperature && fabs(o->temperature_c - 30.0) < 1e-9);
        assert_true(o->has_torque && o->torque_permille == 0);
        /* 2 + 4 + 1 (mode) + 1 (brake) bytes, then 1 + 2 + 2: the velocity's 4 do not fit */
        assert_false(o->has_velocity);
        assert_int_equal(g_d.layout[j].left_out, 1u << LS_DRIVE_RO_VELOCITY);
        assert_int_equal(o->last_error, 0);
        assert_string_equal(o->error_name, "");
        assert_int_equal(o->home, HAL_HOME_NOT_HOMED);
        assert_int_equal(o->home_required, j == 1);
        assert_true(o->feedback_age < 8u);
    }
    bool syncs = false;
    for (uint8_t k = 0; k < r.n_counters; k++) {
        syncs = syncs || (strcmp(r.counter[k].name, "sync_sent") == 0 && r.counter[k].value > 0u);
    }
    assert_true(syncs);
    enable();
    step_ms(40);
    readout(&r);
    for (int j = 0; j < NJ; j++) {
        assert_string_equal(r.joint[j].state, "OPERATION ENABLED");
        assert_int_equal(r.joint[j].brake, HAL_TRI_OFF); /* released: from the drive, not our command */
        assert_true(fabs(r.joint[j].position_rad - world_q(j)) < 1e-3);
    }
    /* the shoulder holds the arm against gravity: it gives torque, and warms */
    assert_true(abs(r.joint[1].torque_permille) > 0);
    assert_true(r.joint[1].temperature_c > 30.0);
}

static void test_a_joint_homes_to_its_offset_without_moving(void **state)
{
    (void)state;
    enable();
    const double q_before = world_q(1);
    hal_joint_status_t st[NJ];
    status(st);
    assert_true(st[1].home_required);
    assert_int_equal(st[1].home, HAL_HOME_NOT_HOMED);
    assert_int_equal(hal_arm_home(&g_arm, 1u << 1), LS_OK);
    status(st);
    assert_int_equal(st[1].home, HAL_HOME_HOMING);
    assert_int_equal(hal_arm_home(&g_arm, 1u << 1), LS_EBUSY); /* one at a time */
    assert_int_equal(run_homing(1, 500), HAL_HOME_HOMED);
    /* the drive's counter now reads the home offset where the joint stands */
    double q[NJ], qd[NJ];
    assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
    assert_true(fabs(q[1] - HOME_OFFSET / CPR) < 2e-4);
    /* held there in CSP: the joint did not move, and keeps not moving */
    for (int ms = 0; ms < 200; ms++) {
        assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
        assert_int_equal(hal_arm_command(&g_arm, q, NULL), LS_OK);
        step_ms(1);
    }
    status(st);
    assert_int_equal(st[1].state, HAL_JOINT_ENABLED);
    assert_true(fabs(world_q(1) - q_before) < 1e-3);
    hal_arm_readout_t r;
    readout(&r);
    assert_int_equal(r.joint[1].mode, LS_CO_MODE_CSP);
    assert_int_equal(r.joint[1].home, HAL_HOME_HOMED);
    assert_int_equal(r.joint[0].home, HAL_HOME_NOT_HOMED);
    /* a set-point from here moves it as commanded */
    (void)ramp_joint(1, 0.05);
    assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
    assert_true(fabs(q[1] - (HOME_OFFSET / CPR + 0.05)) < 5e-3);
    assert_true(fabs(world_q(1) - (q_before + 0.05)) < 5e-3);
}

static void test_a_homing_is_kept_across_disable_and_lost_when_the_drive_boots(void **state)
{
    (void)state;
    enable();
    assert_int_equal(hal_arm_home(&g_arm, 1u << 1), LS_OK);
    assert_int_equal(run_homing(1, 500), HAL_HOME_HOMED);
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    step_ms(40);
    hal_joint_status_t st[NJ];
    status(st);
    assert_int_equal(st[1].state, HAL_JOINT_OFF);
    assert_int_equal(st[1].home, HAL_HOME_HOMED);
    enable();
    status(st);
    assert_int_equal(st[1].home, HAL_HOME_HOMED);
    /* and it moves as commanded in the homed frame */
    double qd[NJ];
    const double w0 = world_q(1);
    const double q0 = ramp_joint(1, -0.05);
    double qm[NJ];
    assert_int_equal(hal_arm_read(&g_arm, qm, qd), LS_OK);
    assert_true(fabs(qm[1] - (q0 - 0.05)) < 5e-3);
    assert_true(fabs(world_q(1) - (w0 - 0.05)) < 5e-3);
    status(st);
    assert_int_equal(st[1].state, HAL_JOINT_ENABLED);
    /* the drive restarts (NMT reset node from elsewhere): lost, then configured again by an enable */
    const hal_can_frame_t reset = { .id = LS_CO_COB_NMT, .len = 2, .data = { LS_CO_NMT_RESET_NODE, 0x22 } };
    assert_int_equal(hal_sim_drives_rx(&reset, g_now), LS_OK);
    step_ms(40);
    status(st);
    assert_int_equal(st[1].state, HAL_JOINT_LOST);
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    step_ms(10);
    enable();
    status(st);
    assert_int_equal(st[1].home, HAL_HOME_NOT_HOMED);
}

static void test_a_homing_interrupted_fails_and_the_drive_enables_in_csp_again(void **state)
{
    (void)state;
    enable();
    assert_int_equal(hal_arm_home(&g_arm, 1u << 1), LS_OK);
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    step_ms(40);
    hal_joint_status_t st[NJ];
    status(st);
    assert_int_equal(st[1].home, HAL_HOME_FAILED);
    assert_string_equal(st[1].text, "homing failed: interrupted: the drives were switched off");
    enable(); /* in CSP again: bit 12 follows the target */
    hal_arm_readout_t r;
    readout(&r);
    assert_int_equal(r.joint[1].mode, LS_CO_MODE_CSP);
    /* and a new homing succeeds */
    assert_int_equal(hal_arm_home(&g_arm, 1u << 1), LS_OK);
    assert_int_equal(run_homing(1, 500), HAL_HOME_HOMED);
}

static void test_a_joint_homes_over_sdo_where_the_mode_cannot_be_mapped(void **state)
{
    test_a_joint_homes_to_its_offset_without_moving(state);
}

static void test_an_interrupted_homing_over_sdo_restores_csp(void **state)
{
    test_a_homing_interrupted_fails_and_the_drive_enables_in_csp_again(state);
}

static void test_homing_needs_an_enabled_joint_and_a_known_one(void **state)
{
    (void)state;
    assert_int_equal(hal_arm_home(&g_arm, 1u << 1), LS_EBUSY); /* the drives are off */
    enable();
    assert_int_equal(hal_arm_home(&g_arm, 0u), LS_EINVAL);
    assert_int_equal(hal_arm_home(&g_arm, 1u << NJ), LS_EINVAL);
}

static void test_an_enable_right_after_a_disable_holds_where_the_drive_is_as_the_drive_confirms(void **state)
{
    (void)state;
    enable();
    /* somewhere else than where the enable found the arm */
    double q[NJ], qd[NJ];
    const double q0 = ramp_joint(0, 0.1);
    const double w1 = world_q(0);
    assert_true(fabs(w1 - (q0 + 0.1)) < 5e-3);
    /* off, and on again before the drives' statuswords can show the switch-off:
     * the TPDOs still say OPERATION ENABLED for a drive that has switched off */
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    step_ms(5);
    assert_int_equal(hal_arm_enable(&g_arm, true), LS_OK);
    hal_joint_status_t st[NJ];
    bool confirmed = false;
    for (int ms = 0; ms < 300; ms++) {
        assert_int_equal(hal_arm_read(&g_arm, q, qd), LS_OK);
        assert_int_equal(hal_arm_command(&g_arm, q, NULL), LS_OK);
        step_ms(1);
        status(st);
        if (st[0].state == HAL_JOINT_ENABLED) {
            confirmed = true;
        } else if (confirmed) {
            fail_msg("joint 1 was confirmed ENABLED, then %d '%s' %d ms after the enable", (int)st[0].state, st[0].text,
                     ms);
        }
    }
    assert_true(confirmed);
    /* held where it was when enabled again: no jump back to where the first enable found it */
    assert_true(fabs(world_q(0) - w1) < 2e-3);
    /* moved on, then off and on with no drive cycle in between: the drives
     * never see the disable, and hold where they are */
    (void)ramp_joint(0, 0.1);
    const double w2 = world_q(0);
    assert_true(fabs(w2 - (w1 + 0.1)) < 5e-3);
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    assert_int_equal(hal_arm_enable(&g_arm, true), LS_OK);
    step_ms(100);
    status(st);
    assert_int_equal(st[0].state, HAL_JOINT_ENABLED);
    assert_true(fabs(world_q(0) - w2) < 2e-3);
}

static void test_safe_torque_off_is_named_and_refuses_the_enable(void **state)
{
    (void)state;
    enable();
    const char cmd[] = "sto 0x23 on";
    assert_int_equal(hal_sim_drives_control(cmd, sizeof cmd - 1u, g_now), 1);
    step_ms(20);
    hal_joint_status_t st[NJ];
    status(st);
    assert_int_equal(st[2].state, HAL_JOINT_FAULT);
    assert_non_null(strstr(st[2].text, "safe torque off is active (0x2100:02 bit 0"));
    hal_arm_readout_t r;
    readout(&r);
    assert_int_equal(r.joint[2].sto, HAL_TRI_ON);
    assert_int_equal(r.joint[2].brake, HAL_TRI_ON);
    assert_int_equal(r.joint[0].sto, HAL_TRI_OFF);
    /* off and on again: still named at once, not as a step not followed */
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    step_ms(20);
    assert_int_equal(hal_arm_enable(&g_arm, true), LS_OK);
    step_ms(20);
    status(st);
    assert_int_equal(st[2].state, HAL_JOINT_FAULT);
    const char off[] = "sto 0x23 off";
    assert_int_equal(hal_sim_drives_control(off, sizeof off - 1u, g_now), 1);
    assert_int_equal(hal_arm_enable(&g_arm, false), LS_OK);
    step_ms(20);
    enable();
}

static void test_the_drives_limits_are_checked_against_the_models(void **state)
{
    (void)state;
    const double lo[NJ] = { -3, -2, -2, -3, -2, -6 }, hi[NJ] = { 3, 2, 2, 3, 2, 6 };
    char msg[320];
    /* the simulated drives power on without limits (INT32_MIN..INT32_MAX) */
    assert_int_equal(ls_drives_check_limits(&g_d, lo, hi, msg, sizeof msg), LS_OK);
    /* as the script read them: narrower than the model on joint 4 */
    g_d.axis[3].lim0[0] = (uint32_t)(int32_t)-100000;
    g_d.axis[3].lim0[1] = 250000u;
    assert_int_equal(ls_drives_check_limits(&g_d, lo, hi, msg, sizeof msg), LS_ERANGE);
    assert_string_equal(msg, "joint 4 (node 0x24): the drive's software position limits 0x607D = -100000..250000 "
                             "counts (-1.0000..2.5000 rad) do not contain the robot model's -3.0000..3.0000 rad: "
                             "widen the drive's limits, or check counts_per_rad, sign and offset_rad");
    /* min >= max: the drive enforces none */
    g_d.axis[3].lim0[0] = g_d.axis[3].lim0[1] = 0u;
    assert_int_equal(ls_drives_check_limits(&g_d, lo, hi, msg, sizeof msg), LS_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_the_readouts_say_what_the_drives_publish, setup_pdo, teardown),
        cmocka_unit_test_setup_teardown(test_a_joint_homes_to_its_offset_without_moving, setup_pdo, teardown),
        cmocka_unit_test_setup_teardown(test_a_joint_homes_over_sdo_where_the_mode_cannot_be_mapped, setup_sdo,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_a_homing_is_kept_across_disable_and_lost_when_the_drive_boots, setup_pdo,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_a_homing_interrupted_fails_and_the_drive_enables_in_csp_again, setup_pdo,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_an_interrupted_homing_over_sdo_restores_csp, setup_sdo, teardown),
        cmocka_unit_test_setup_teardown(test_homing_needs_an_enabled_joint_and_a_known_one, setup_pdo, teardown),
        cmocka_unit_test_setup_teardown(test_safe_torque_off_is_named_and_refuses_the_enable, setup_pdo, teardown),
        cmocka_unit_test_setup_teardown(
            test_an_enable_right_after_a_disable_holds_where_the_drive_is_as_the_drive_confirms, setup_pdo, teardown),
        cmocka_unit_test_setup_teardown(test_the_drives_limits_are_checked_against_the_models, setup_pdo, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
