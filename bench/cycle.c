/* bench_cycle: the work of N control cycles of one kind, for callgrind
 * (instructions per cycle) and memcheck (allocations per cycle).
 *
 * Usage: bench_cycle CASE N
 *   N = 0 runs the set-up only (planning, model, first set-point), so that
 *   (instructions(N) - instructions(0)) / N is the cost of one cycle.
 * Cases (a cycle at 1 kHz, dt = 1 ms):
 *   traj       ls_traj_sample of a 6-axis joint move (the executor's core)
 *   fk         ls_kin_fk of the measured position (the snapshot's flange pose)
 *   cart_ik    a straight tool line: ls_pose_interp + ls_kin_ik_nearest + ls_traj_sample_axis
 *   motion_hold, motion_joint            ls_motion_step (executor; when built with it)
 *   motion_line, motion_path             a Cartesian line with IK per cycle; a 4-point path with
 *                                        joint blends (executor with Cartesian planners)
 *   control_hold, control_joint, control_line   the whole loop body (ls_control_cycle: command ring,
 *                                        executor, arm I/O, FK, seqlock snapshot) on an ideal arm
 *                                        (reads back what it was commanded; no physics)
 *   react_guarded, react_comply          ls_react_step of a guarded move (no contact: it travels) and of a
 *                                        compliant move pressing with its target force (the PD law and
 *                                        IK run every cycle); the force reading is a constant
 * Prints "cases" to list the cases this build has; otherwise one line with a
 * checksum of the set-points so no cycle can be optimised away. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_err.h"
#include "ls_kin.h"
#include "ls_robot_model.h"
#include "ls_traj.h"
#if BENCH_HAVE_MOTION
#include "ls_motion.h"
#endif
#if BENCH_HAVE_CONTROL
#include "ls_control.h"
#endif
#if BENCH_HAVE_REACT
#include "ls_react.h"
#endif

#define DT_S 1e-3

static const double q_home[LS_N_JOINTS] = { 0.1, -0.6, 1.1, 0.2, 0.9, -0.3 };
static const double q_goal[LS_N_JOINTS] = { 1.2, -0.1, 0.4, -0.8, 1.4, 0.9 };
static double checksum;

static void absorb(const double *q)
{
    for (int i = 0; i < LS_N_JOINTS; i++) {
        checksum += q[i];
    }
}

static ls_traj_limits_t slow_limits(const ls_robot_model_t *m)
{
    ls_traj_limits_t lim;
    for (int i = 0; i < LS_N_JOINTS; i++) {
        lim.v_max[i] = 0.2 * m->qd_max_rad_s[i];
        lim.a_max[i] = 0.2 * m->qdd_max_rad_s2[i];
        lim.j_max[i] = 0.2 * m->qddd_max_rad_s3[i];
    }
    return lim;
}

static int run_traj(long n)
{
    const ls_robot_model_t *m = &ls_robot_model_default;
    ls_traj_limits_t lim = slow_limits(m);
    ls_traj_t tr;
    if (ls_traj_plan(&tr, LS_N_JOINTS, q_home, q_goal, &lim) != LS_OK) {
        return LS_EINVAL;
    }
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], qdd[LS_N_JOINTS];
    for (long k = 0; k < n; k++) {
        ls_traj_sample(&tr, (double)k * DT_S, q, qd, qdd);
        absorb(q);
    }
    return tr.duration_s >= (double)n * DT_S ? 0 : 1;
}

static int run_fk(long n)
{
    const ls_robot_model_t *m = &ls_robot_model_default;
    double q[LS_N_JOINTS], T[16];
    memcpy(q, q_home, sizeof q);
    for (long k = 0; k < n; k++) {
        q[0] = q_home[0] + 1e-6 * (double)k;
        if (ls_kin_fk(m, q, T) != LS_OK) {
            return LS_EINVAL;
        }
        checksum += T[12];
    }
    return 0;
}

static int run_cart_ik(long n)
{
    const ls_robot_model_t *m = &ls_robot_model_default;
    double A[16], B[16], T[16], q[LS_N_JOINTS];
    if (ls_kin_fk(m, q_home, A) != LS_OK) {
        return LS_EINVAL;
    }
    memcpy(B, A, sizeof B);
    B[12] += 0.10; /* 10 cm along x */
    B[14] -= 0.05;
    /* The path parameter 0 -> 1 lasts longer than the N cycles, so that every cycle lies on the line. */
    ls_traj_axis_t s;
    if (ls_traj_plan_axis_duration(&s, 0.0, 1.0, 2.0, 4.0, 40.0, (double)n * DT_S + 2.0) != LS_OK) {
        return LS_EINVAL;
    }
    memcpy(q, q_home, sizeof q);
    for (long k = 0; k < n; k++) {
        double u;
        ls_traj_sample_axis(&s, (double)k * DT_S, &u, NULL, NULL);
        ls_pose_interp(A, B, u, T);
        if (ls_kin_ik_nearest(m, T, q, q) != LS_OK) {
            return LS_EINVAL;
        }
        absorb(q);
    }
    return 0;
}

#if BENCH_HAVE_MOTION
static ls_motion_t motion;
static ls_motion_plan_t plan;

static int step_motion(long n, int expect_moving)
{
    double q_cmd[LS_N_JOINTS], qd_cmd[LS_N_JOINTS];
    ls_motion_events_t ev;
    memcpy(q_cmd, motion.q_cmd, sizeof q_cmd);
    for (long k = 0; k < n; k++) {
        ev.n = 0;
        /* The measured position follows the command exactly (no following error). */
        ls_motion_step(&motion, DT_S, q_cmd, q_cmd, qd_cmd, &ev);
        absorb(q_cmd);
    }
    if (expect_moving && n > 0 && motion.phase != LS_MOTION_RUNNING) {
        return 1; /* the motion ended before the last cycle: some cycles only held */
    }
    return 0;
}

static int run_motion(const char *which, long n)
{
    const ls_robot_model_t *m = &ls_robot_model_default;
    char why[128] = "";
    ls_motion_init(&motion, m);
    ls_motion_hold(&motion, q_home);
    if (strcmp(which, "motion_hold") == 0) {
        return step_motion(n, 0);
    }
    int rc = LS_EINVAL; /* no such motion case */
    if (strcmp(which, "motion_joint") == 0) {
        rc = ls_motion_plan_joint(&plan, m, q_home, q_goal, 0.2, 0.2, why, sizeof why);
    }
#if BENCH_HAVE_MOTION_CART
    static ls_motion_program_t prog;
    static const double tool[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0.05, 1 };
    const ls_motion_cart_limits_t lim = { 0.05, 0.5, 5.0, 0.3, 1.0, 10.0, 0.5 };
    if (strcmp(which, "motion_line") == 0) {
        double F[16], tip[16];
        ls_kin_fk(m, q_home, F);
        ls_pose_mul(F, tool, tip);
        tip[12] += 0.10;
        tip[14] -= 0.05;
        rc = ls_motion_plan_line(&plan, m, q_home, tool, tip, &lim, why, sizeof why);
    } else if (strcmp(which, "motion_path") == 0) {
        static const double pts[4][LS_N_JOINTS] = { { 0.6, -0.4, 0.9, -0.2, 1.0, 0.2 },
                                                    { 1.0, -0.2, 0.6, -0.6, 1.3, 0.6 },
                                                    { 0.4, -0.5, 1.0, 0.1, 0.8, 0.0 },
                                                    { 0.1, -0.6, 1.1, 0.2, 0.9, -0.3 } };
        const double *from = q_home;
        prog.n = 4;
        rc = 0;
        for (int i = 0; i < 4 && rc == 0; i++) {
            memset(&prog.seg[i], 0, sizeof prog.seg[i]);
            rc = ls_motion_seg_joint(&prog.seg[i], m, from, pts[i], 0.2, 0.2, why, sizeof why);
            prog.seg[i].point = i;
            from = pts[i];
        }
        for (int i = 0; i + 1 < 4 && rc == 0; i++) {
            ls_motion_seg_blend(&prog.seg[i], &prog.seg[i + 1], 1.0);
        }
        if (rc == 0) {
            rc = ls_motion_plan_path(&plan, &prog, 1, true, "bench");
        }
    }
#endif
    if (rc != 0) {
        fprintf(stderr, "bench_cycle: %s: planning failed (%d): %s\n", which, rc, why);
        return rc;
    }
    if (ls_motion_start(&motion, &plan) != 0) {
        fprintf(stderr, "bench_cycle: %s: ls_motion_start refused the plan\n", which);
        return LS_EINVAL;
    }
    return step_motion(n, 1);
}
#endif


#if BENCH_HAVE_CONTROL
/* An ideal arm: it is where it was commanded, at once. */
static double arm_q[LS_N_JOINTS], arm_qd[LS_N_JOINTS];
static int arm_enable(void *self, bool on)
{
    (void)self;
    (void)on;
    return 0;
}
static int arm_command(void *self, const double *q, const double *qd)
{
    (void)self;
    memcpy(arm_q, q, sizeof arm_q);
    memcpy(arm_qd, qd, sizeof arm_qd);
    return 0;
}
static int arm_read(void *self, double *q, double *qd)
{
    (void)self;
    memcpy(q, arm_q, sizeof arm_q);
    if (qd != NULL) {
        memcpy(qd, arm_qd, sizeof arm_qd);
    }
    return 0;
}
static const hal_arm_ops_t arm_ops = { .enable = arm_enable, .command = arm_command, .read = arm_read };
static hal_arm_t arm = { &arm_ops, NULL, "ideal" };
static ls_control_t ctl;

static int run_control(const char *which, long n)
{
    const ls_robot_model_t *m = &ls_robot_model_default;
    memcpy(arm_q, q_home, sizeof arm_q);
    ls_control_config_t cfg = { .model = m, .arm = &arm, .rate_hz = 1000 };
    ls_control_init(&ctl, &cfg);
    ls_ctl_cmd_t en = { .kind = LS_CTL_ENABLE };
    if (!ls_control_post(&ctl, &en)) {
        return LS_EAGAIN;
    }
    uint64_t t_us = 0;
    ls_control_cycle(&ctl, t_us += 1000u);
    int moving = strcmp(which, "control_hold") != 0;
    if (moving) {
        char why[128] = "";
        ls_motion_plan_t *slot = ls_control_plan_slot(&ctl);
        int rc = slot == NULL ? LS_EAGAIN : ls_motion_plan_joint(slot, m, q_home, q_goal, 0.2, 0.2, why, sizeof why);
#if BENCH_HAVE_MOTION_CART
        if (slot != NULL && strcmp(which, "control_line") == 0) {
            static const double tool[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0.05, 1 };
            const ls_motion_cart_limits_t lim = { 0.05, 0.5, 5.0, 0.3, 1.0, 10.0, 0.5 };
            double F[16], tip[16];
            ls_kin_fk(m, q_home, F);
            ls_pose_mul(F, tool, tip);
            tip[12] += 0.10;
            tip[14] -= 0.05;
            rc = ls_motion_plan_line(slot, m, q_home, tool, tip, &lim, why, sizeof why);
        }
#endif
        if (rc != 0 || !ls_control_start_plan(&ctl, 1)) {
            fprintf(stderr, "bench_cycle: %s: planning failed: %s\n", which, why);
            return LS_EINVAL;
        }
        ls_control_cycle(&ctl, t_us += 1000u);
    }
    ls_ctl_event_t ev;
    for (long k = 0; k < n; k++) {
        ls_control_cycle(&ctl, t_us += 1000u);
        while (ls_control_next_event(&ctl, &ev)) {
        }
        absorb(ctl.q_cmd);
    }
    if (!ctl.enabled) {
        fprintf(stderr, "bench_cycle: %s: the loop disabled the drives\n", which);
        return LS_EIO;
    }
    return moving && n > 0 && ctl.motion.phase != LS_MOTION_RUNNING ? 1 : 0;
}
#endif

#if BENCH_HAVE_REACT
/* The pose of ls_react's unit tests: the tool points down over the table. */
static const double q_react[LS_N_JOINTS] = { -0.2, 0.8, 0.45, 0.0, 0.3, 0.0 };
static ls_react_t react;

static int run_react(const char *which, long n)
{
    ls_react_plan_t p;
    memset(&p, 0, sizeof p);
    snprintf(p.sensor, sizeof p.sensor, "force_sensor");
    const double zero[6] = { 0 };
    ls_pose_from_xyzrpy(zero, p.tool);
    p.ref_seq = 1;
    p.v_m_s = 0.03;
    p.a_m_s2 = 1.0;
    p.j_m_s3 = ls_robot_model_linear_jerk(&ls_robot_model_default, p.a_m_s2);
    p.a_stop_m_s2 = ls_robot_model_default.max_linear_accel_m_s2;
    p.j_stop_m_s3 = ls_robot_model_default.max_linear_jerk_m_s3;
    /* Travel long enough that all N cycles move: 0.03 m/s for N ms, plus the ramps. */
    p.dist_m = 0.03 * (double)n * DT_S + 0.01;
    double reading[6] = { 0 };
    if (strcmp(which, "react_guarded") == 0) {
        p.kind = LS_REACT_GUARDED;
        p.dir_tool[2] = 1.0;
        p.component = 2;
        p.threshold = 5.0; /* never reached: the reading stays 0 */
    } else {
        p.kind = LS_REACT_COMPLY;
        p.dir_tool[0] = 1.0; /* travel along tool x, press along tool z */
        p.n_tool[2] = 1.0;
        p.c_max_m = 0.05;
        p.f_target_N = 10.0;
        p.kp_m_s_N = 5e-4;
        p.vc_max_m_s = 0.01;
        p.timeout_s = 1e3;
        p.panic_N = 30.0;
        reading[2] = p.f_target_N; /* in contact at the target force from the start */
    }
    ls_react_init(&react, &ls_robot_model_default);
    double q_cmd[LS_N_JOINTS], qd_cmd[LS_N_JOINTS];
    memcpy(q_cmd, q_react, sizeof q_cmd);
    if (ls_react_start(&react, &p, q_cmd, 6) != 0) {
        fprintf(stderr, "bench_cycle: %s: ls_react_start refused the plan\n", which);
        return LS_EINVAL;
    }
    ls_motion_events_t ev;
    for (long k = 0; k < n; k++) {
        ev.n = 0;
        /* The measured position follows the command exactly (no following error). */
        ls_react_step(&react, DT_S, q_cmd, reading, q_cmd, qd_cmd, &ev);
        absorb(q_cmd);
    }
    if (n > 0 && !ls_react_moving(&react)) {
        fprintf(stderr, "bench_cycle: %s: the move ended before the last cycle (%s)\n", which,
                ls_react_end_name(react.report.end));
        return LS_EIO;
    }
    return 0;
}
#endif

static const char *const cases[] = {
    "traj",          "fk",
    "cart_ik",
#if BENCH_HAVE_MOTION
    "motion_hold",   "motion_joint",
#if BENCH_HAVE_MOTION_CART
    "motion_line",   "motion_path",
#endif
#endif
#if BENCH_HAVE_CONTROL
    "control_hold",  "control_joint",
#if BENCH_HAVE_MOTION_CART
    "control_line",
#endif
#endif
#if BENCH_HAVE_REACT
    "react_guarded", "react_comply",
#endif
};

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "cases") == 0) {
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            printf("%s\n", cases[i]);
        }
        return 0;
    }
    char *end = NULL;
    long n = argc == 3 ? strtol(argv[2], &end, 10) : 0;
    if (argc != 3 || end == argv[2] || *end != '\0' || n < 0) {
        fprintf(stderr, "usage: %s CASE N | %s cases\n", argv[0], argv[0]);
        return 2;
    }
    int rc = LS_EINVAL; /* every case sets it */
    if (strcmp(argv[1], "traj") == 0) {
        rc = run_traj(n);
    } else if (strcmp(argv[1], "fk") == 0) {
        rc = run_fk(n);
    } else if (strcmp(argv[1], "cart_ik") == 0) {
        rc = run_cart_ik(n);
    }
#if BENCH_HAVE_MOTION
    else if (strncmp(argv[1], "motion_", 7) == 0) {
        rc = run_motion(argv[1], n);
    }
#endif
#if BENCH_HAVE_CONTROL
    else if (strncmp(argv[1], "control_", 8) == 0) {
        rc = run_control(argv[1], n);
    }
#endif
#if BENCH_HAVE_REACT
    else if (strcmp(argv[1], "react_guarded") == 0 || strcmp(argv[1], "react_comply") == 0) {
        rc = run_react(argv[1], n);
    }
#endif
    else {
        fprintf(stderr, "bench_cycle: unknown case '%s' (see: %s cases)\n", argv[1], argv[0]);
        return 2;
    }
    if (rc < 0) {
        fprintf(stderr, "bench_cycle: %s failed\n", argv[1]);
        return 1;
    }
    printf("%s %ld cycles, checksum %.6g%s\n", argv[1], n, checksum, rc > 0 ? " (motion ended early)" : "");
    return 0;
}
