/* ls_motion: planners and executor without the simulation. The arm is
 * ideal (q_meas = the set-point), one cycle is 1 ms. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_math.h"
#include "ls_motion.h"
#include "motion_test_util.h"

static void assert_near(double got, double want, double tol, int line)
{
    if (!(fabs(got - want) <= tol)) {
        fail_msg("line %d: got %.17g, want %.17g (tolerance %.3g)", line, got, want, tol);
    }
}
#define assert_double_equal(got, want, tol) assert_near((got), (want), (tol), __LINE__)

static const ls_robot_model_t *M = &ls_robot_model_default;

static ls_motion_t g_m;
static ls_motion_plan_t g_plan;
static ls_motion_program_t g_prog;

static void tip_of(const double q[LS_N_JOINTS], double P[16])
{
    double F[16], T[16];
    ls_kin_fk(M, q, F);
    mt_tool(T);
    ls_pose_mul(F, T, P);
}

/* Tip pose at q plus a translation (base frame), same orientation. */
static void shifted_tip(const double q[LS_N_JOINTS], double dx, double dy, double dz, double P[16])
{
    tip_of(q, P);
    P[12] += dx;
    P[13] += dy;
    P[14] += dz;
}

static void start(const ls_motion_plan_t *p)
{
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, p), 0);
}

static int count_kind(const ev_log_t *log, ls_motion_event_kind_t kind)
{
    int n = 0;
    for (int i = 0; i < log->n; i++) {
        n += log->ev[i].kind == kind;
    }
    return n;
}

/* ---- joint moves ---- */

static void joint_target(double q1[LS_N_JOINTS])
{
    const double d[LS_N_JOINTS] = { 0.8, -0.4, 0.5, 1.0, -0.6, 2.0 };
    for (int j = 0; j < LS_N_JOINTS; j++) {
        q1[j] = mt_q_home[j] + d[j];
    }
}

static void test_joint_move_reaches_target_in_optimal_time(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    joint_target(q1);
    char why[128];
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, q1, 0.5, 0.5, why, sizeof why), 0);
    /* Phase-synchronised (a straight line in joint space): the optimal
     * duration of the phase sigma from 0 to 1 within every joint's limits
     * over its distance, from ls_traj; never shorter than the time-synchronised
     * optimum of the same limits (each joint on its own shape). */
    ls_traj_limits_t lim;
    double vs = INFINITY, as = INFINITY, js = INFINITY;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        lim.v_max[j] = 0.5 * M->qd_max_rad_s[j];
        lim.a_max[j] = 0.5 * M->qdd_max_rad_s2[j];
        lim.j_max[j] = 0.5 * M->qddd_max_rad_s3[j];
        const double d = fabs(q1[j] - mt_q_home[j]);
        vs = fmin(vs, lim.v_max[j] / d);
        as = fmin(as, lim.a_max[j] / d);
        js = fmin(js, lim.j_max[j] / d);
    }
    ls_traj_axis_t sigma;
    assert_int_equal(ls_traj_plan_axis(&sigma, 0.0, 1.0, vs, as, js), 0);
    assert_double_equal(g_plan.one.traj.duration_s, sigma.T, 1e-12);
    ls_traj_t time_sync;
    assert_int_equal(ls_traj_plan(&time_sync, LS_N_JOINTS, mt_q_home, q1, &lim), 0);
    assert_true(time_sync.duration_s > 0.5);
    assert_true(g_plan.one.traj.duration_s >= time_sync.duration_s - 1e-12);

    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], q_prev[LS_N_JOINTS];
    memcpy(q_prev, mt_q_home, sizeof q_prev);
    long k = 0;
    while (log.n == 0 && k < 100000) {
        mt_step(&g_m, q, qd, &log);
        k++;
        for (int j = 0; j < LS_N_JOINTS; j++) {
            assert_true(fabs(qd[j]) <= lim.v_max[j] * (1.0 + 1e-9));
            assert_true(fabs(q[j] - q_prev[j]) <= lim.v_max[j] * DT_S * (1.0 + 1e-9));
        }
        memcpy(q_prev, q, sizeof q_prev);
    }
    /* DONE in the cycle whose clock first reaches the duration. */
    assert_int_equal(k, (long)ceil(sigma.T / DT_S - 1e-9));
    assert_int_equal(log.n, 1);
    assert_int_equal(log.ev[0].kind, LS_MEV_DONE);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_double_equal(q[j], q1[j], 0.0);
        assert_double_equal(log.ev[0].q_rad[j], q1[j], 0.0);
    }
    assert_int_equal(g_m.phase, LS_MOTION_IDLE);
    /* Idle afterwards: holds, no more events. */
    for (int i = 0; i < 100; i++) {
        mt_step(&g_m, q, qd, &log);
    }
    assert_int_equal(log.n, 1);
    assert_double_equal(q[5], q1[5], 0.0);
}

static void test_joint_refusal_names_joint_and_limit(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    memcpy(q1, mt_q_home, sizeof q1);
    q1[2] = 2.9;
    char why[128];
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, q1, 0.5, 0.5, why, sizeof why), LS_ERANGE);
    assert_string_equal(why, "joint 3: 2.9 rad beyond its limit 2.618 rad");
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, mt_q_home, 0.0, 0.5, why, sizeof why), LS_EINVAL);
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, mt_q_home, 0.5, 1.5, why, sizeof why), LS_EINVAL);
}

static void test_start_refuses_wrong_start_and_double_start(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    joint_target(q1);
    char why[128];
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, q1, mt_q_home, 0.5, 0.5, why, sizeof why), 0);
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), LS_EINVAL); /* the plan starts at q1, the arm is at home */
    assert_int_equal(g_m.phase, LS_MOTION_IDLE);
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, q1, 0.5, 0.5, why, sizeof why), 0);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), LS_ESTATE);
}

/* ---- stop, resume, abort ---- */

static void test_stop_stays_on_path_pauses_and_resume_reaches_target(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    joint_target(q1);
    char why[128];
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), 0);
    const double T = g_plan.one.traj.duration_s;
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    long half = (long)(0.4 * T / DT_S);
    for (long k = 0; k < half; k++) {
        mt_step(&g_m, q, qd, &log);
    }
    double v_prev[LS_N_JOINTS], v_prev2[LS_N_JOINTS];
    memcpy(v_prev2, qd, sizeof v_prev2);
    mt_step(&g_m, q, qd, &log);
    memcpy(v_prev, qd, sizeof v_prev);
    ls_motion_stop(&g_m);
    assert_int_equal(g_m.phase, LS_MOTION_STOPPING);
    double sigma_prev = (q[0] - mt_q_home[0]) / (q1[0] - mt_q_home[0]);
    long k = 0;
    while (g_m.phase == LS_MOTION_STOPPING && k < 100000) {
        mt_step(&g_m, q, qd, &log);
        k++;
        /* On the planned path, a straight line in joint space: every joint
         * the same fraction sigma of its way, and sigma never goes back. */
        const double sigma = (q[0] - mt_q_home[0]) / (q1[0] - mt_q_home[0]);
        assert_true(sigma >= sigma_prev - 1e-12 && sigma < 1.0);
        sigma_prev = sigma;
        for (int j = 0; j < LS_N_JOINTS; j++) {
            assert_double_equal(q[j], mt_q_home[j] + sigma * (q1[j] - mt_q_home[j]), 1e-12);
            /* Braking within the joint's acceleration and jerk limits (the
             * set-point velocity's first and second differences). */
            const double acc = (qd[j] - v_prev[j]) / DT_S;
            const double jerk = (qd[j] - 2.0 * v_prev[j] + v_prev2[j]) / (DT_S * DT_S);
            assert_true(fabs(acc) <= M->qdd_max_rad_s2[j] * (1.0 + 1e-9));
            if (!(fabs(jerk) <= M->qddd_max_rad_s3[j] * (1.0 + 1e-6))) {
                fail_msg("joint %d: jerk %.6g beyond %.6g, %ld ms into the stop", j + 1, jerk, M->qddd_max_rad_s3[j],
                         k);
            }
        }
        memcpy(v_prev2, v_prev, sizeof v_prev2);
        memcpy(v_prev, qd, sizeof v_prev);
    }
    assert_int_equal(g_m.phase, LS_MOTION_PAUSED);
    assert_int_equal(count_kind(&log, LS_MEV_PAUSED), 1);
    assert_int_equal(count_kind(&log, LS_MEV_DONE), 0);
    assert_true(sigma_prev < 1.0);
    (void)T;
    double held[LS_N_JOINTS];
    memcpy(held, q, sizeof held);
    for (int i = 0; i < 200; i++) {
        mt_step(&g_m, q, qd, &log);
        assert_memory_equal(q, held, sizeof held);
    }
    assert_int_equal(log.n, 1);
    assert_int_equal(ls_motion_resume(&g_m), 0);
    assert_int_equal(ls_motion_resume(&g_m), LS_ESTATE);
    assert_true(mt_run_until(&g_m, LS_MEV_DONE, 100000, &log) > 0);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_double_equal(g_m.q_cmd[j], q1[j], 0.0);
    }
    assert_int_equal(count_kind(&log, LS_MEV_DONE), 1);
}

static void test_abort_holds_the_set_point(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    joint_target(q1);
    char why[128];
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), 0);
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    for (int k = 0; k < 300; k++) {
        mt_step(&g_m, q, qd, &log);
    }
    ls_motion_stop(&g_m);
    assert_true(mt_run_until(&g_m, LS_MEV_PAUSED, 100000, &log) > 0);
    ls_motion_abort(&g_m);
    assert_int_equal(g_m.phase, LS_MOTION_IDLE);
    double held[LS_N_JOINTS];
    memcpy(held, g_m.q_cmd, sizeof held);
    for (int k = 0; k < 3000; k++) {
        mt_step(&g_m, q, qd, &log);
        assert_memory_equal(q, held, sizeof held);
        for (int j = 0; j < LS_N_JOINTS; j++) {
            assert_double_equal(qd[j], 0.0, 0.0);
        }
    }
    assert_int_equal(count_kind(&log, LS_MEV_DONE), 0);
    assert_int_equal(ls_motion_resume(&g_m), LS_ESTATE);
}

static void test_following_error_faults(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    joint_target(q1);
    char why[128];
    assert_int_equal(ls_motion_plan_joint(&g_plan, M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), 0);
    start(&g_plan);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], meas[LS_N_JOINTS];
    ls_motion_events_t ev = { .n = 0 };
    for (int k = 0; k < 10; k++) {
        ls_motion_step(&g_m, DT_S, g_m.q_cmd, q, qd, &ev);
    }
    assert_int_equal(ev.n, 0);
    memcpy(meas, g_m.q_cmd, sizeof meas);
    meas[3] -= 0.06;
    ls_motion_step(&g_m, DT_S, meas, q, qd, &ev);
    assert_int_equal(ev.n, 1);
    assert_int_equal(ev.ev[0].kind, LS_MEV_FAULT);
    assert_string_equal(ev.ev[0].text, "following error joint 4: -0.06 rad");
    assert_int_equal(g_m.phase, LS_MOTION_IDLE);
}

/* ---- Cartesian ---- */

static double dist_to_line(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3];
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
    }
    const double t = (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / (ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]);
    assert_true(t >= -1e-9 && t <= 1.0 + 1e-9);
    double d = 0.0;
    for (int i = 0; i < 3; i++) {
        const double e = ap[i] - t * ab[i];
        d += e * e;
    }
    return sqrt(d);
}

static void test_line_stays_on_the_line(void **state)
{
    (void)state;
    double tool[16], P0[16], P1[16];
    mt_tool(tool);
    tip_of(mt_q_home, P0);
    shifted_tip(mt_q_home, -0.15, 0.2, 0.1, P1);
    /* and turn the tool by 0.3 rad about the base z axis */
    const double rz[6] = { 0, 0, 0, 0, 0, 0.3 };
    double R[16], tmp[16];
    ls_pose_from_xyzrpy(rz, R);
    ls_pose_mul(R, P1, tmp);
    memcpy(tmp + 12, P1 + 12, 3 * sizeof(double));
    memcpy(P1, tmp, sizeof P1);
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    char why[160];
    assert_int_equal(ls_motion_plan_line(&g_plan, M, mt_q_home, tool, P1, &lim, why, sizeof why), 0);
    assert_double_equal(g_plan.one.length_m, sqrt(0.15 * 0.15 + 0.2 * 0.2 + 0.1 * 0.1), 1e-12);
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], Pprev[3];
    memcpy(Pprev, P0 + 12, sizeof Pprev);
    long k = 0;
    double worst = 0.0;
    while (log.n == 0 && k < 100000) {
        mt_step(&g_m, q, qd, &log);
        k++;
        double P[16];
        tip_of(q, P);
        worst = fmax(worst, dist_to_line(P + 12, P0 + 12, P1 + 12));
        double step = 0.0;
        for (int i = 0; i < 3; i++) {
            step += (P[12 + i] - Pprev[i]) * (P[12 + i] - Pprev[i]);
        }
        assert_true(sqrt(step) <= lim.v_lin_m_s * DT_S * (1.0 + 1e-6));
        memcpy(Pprev, P + 12, sizeof Pprev);
    }
    assert_true(worst < 1e-6);
    assert_int_equal(log.ev[0].kind, LS_MEV_DONE);
    double P[16];
    tip_of(q, P);
    assert_true(ls_pose_dist(P, P1) < 1e-9);
    assert_true(ls_pose_angle(P, P1) < 1e-9);
    /* The slower of linear (0.25 m/s) and angular (1 rad/s) limits sets the time. */
    assert_true(ls_motion_seg_duration_s(&g_plan.one) >= g_plan.one.length_m / lim.v_lin_m_s);
}

static void test_line_stop_stays_on_line(void **state)
{
    (void)state;
    double tool[16], P0[16], P1[16];
    mt_tool(tool);
    tip_of(mt_q_home, P0);
    shifted_tip(mt_q_home, 0.0, 0.3, -0.1, P1);
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    char why[160];
    assert_int_equal(ls_motion_plan_line(&g_plan, M, mt_q_home, tool, P1, &lim, why, sizeof why), 0);
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    for (int k = 0; k < 600; k++) {
        mt_step(&g_m, q, qd, &log);
    }
    ls_motion_stop(&g_m);
    long k = mt_run_until(&g_m, LS_MEV_PAUSED, 100000, &log);
    assert_true(k > 0);
    double P[16];
    tip_of(g_m.q_cmd, P);
    assert_true(dist_to_line(P + 12, P0 + 12, P1 + 12) < 1e-6);
    assert_true(ls_pose_dist(P, P1) > 0.01); /* paused before the end */
    assert_int_equal(ls_motion_resume(&g_m), 0);
    assert_true(mt_run_until(&g_m, LS_MEV_DONE, 100000, &log) > 0);
    tip_of(g_m.q_cmd, P);
    assert_true(ls_pose_dist(P, P1) < 1e-9);
}

static void test_arc_stays_on_its_circle(void **state)
{
    (void)state;
    double tool[16], P0[16], Pv[16], P1[16];
    mt_tool(tool);
    tip_of(mt_q_home, P0);
    shifted_tip(mt_q_home, 0.1, 0.1, 0.0, Pv);
    shifted_tip(mt_q_home, 0.0, 0.2, 0.0, P1);
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    char why[160];
    assert_int_equal(ls_motion_plan_arc(&g_plan, M, mt_q_home, tool, Pv, P1, &lim, why, sizeof why), 0);
    /* The circle through (0,0), (0.1,0.1), (0,0.2) (relative): centre (0, 0.1), radius 0.1, a half turn. */
    assert_double_equal(g_plan.one.radius_m, 0.1, 1e-12);
    assert_double_equal(g_plan.one.angle_rad, LS_PI, 1e-9);
    const double c[3] = { P0[12], P0[13] + 0.1, P0[14] };
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    double worst = 0.0, nearest_via = 1.0;
    long k = 0;
    while (log.n == 0 && k < 100000) {
        mt_step(&g_m, q, qd, &log);
        k++;
        double P[16];
        tip_of(q, P);
        const double r = sqrt((P[12] - c[0]) * (P[12] - c[0]) + (P[13] - c[1]) * (P[13] - c[1]));
        worst = fmax(worst, fmax(fabs(r - 0.1), fabs(P[14] - c[2])));
        nearest_via = fmin(nearest_via, ls_pose_dist(P, Pv));
    }
    assert_true(worst < 1e-6);
    assert_true(nearest_via < 2e-4); /* it passes through the arc point */
    double P[16];
    tip_of(q, P);
    assert_true(ls_pose_dist(P, P1) < 1e-9);
}

static void test_arc_collinear_refused(void **state)
{
    (void)state;
    double tool[16], Pv[16], P1[16];
    mt_tool(tool);
    shifted_tip(mt_q_home, 0.05, 0.0, 0.0, Pv);
    shifted_tip(mt_q_home, 0.1, 0.0, 0.0, P1);
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    char why[160];
    assert_int_equal(ls_motion_plan_arc(&g_plan, M, mt_q_home, tool, Pv, P1, &lim, why, sizeof why), LS_EGEOM);
    assert_non_null(strstr(why, "collinear"));
}

static void test_cartesian_refusals_name_axis_and_reason(void **state)
{
    (void)state;
    double tool[16], P1[16];
    mt_tool(tool);
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    char why[160];
    /* Below the floor of the workspace box (z >= 0.02 m). */
    tip_of(mt_q_home, P1);
    P1[14] = -0.05;
    assert_int_equal(ls_motion_plan_line(&g_plan, M, mt_q_home, tool, P1, &lim, why, sizeof why), LS_ERANGE);
    assert_non_null(strstr(why, "axis z: "));
    assert_non_null(strstr(why, "beyond the workspace limit 0.02 m"));
    /* Inside the box but out of reach. */
    tip_of(mt_q_home, P1);
    P1[12] = 0.9;
    P1[13] = 0.9;
    assert_int_equal(ls_motion_plan_line(&g_plan, M, mt_q_home, tool, P1, &lim, why, sizeof why), LS_ERANGE);
    assert_non_null(strstr(why, "unreachable"));
    /* Past the joint 1 axis, 0.1 mm beside it: the arm reaches over and joint 5
     * comes to its limit, where only a jump to another configuration goes on. */
    double q0[LS_N_JOINTS] = { 0.0, -0.2, 1.4, 0.0, 0.6, 0.0 };
    double P0[16];
    tip_of(q0, P0);
    memcpy(P1, P0, sizeof P1);
    P1[12] = -P0[12];
    P1[13] = 1e-4;
    char whole[LS_MOTION_WHY_LEN];
    int st = ls_motion_plan_line(&g_plan, M, q0, tool, P1, &lim, whole, sizeof whole);
    assert_int_equal(st, LS_ERANGE);
    assert_true(strncmp(whole, "joint 5 reaches its limit 2.182 rad at ", 39) == 0);
    assert_non_null(
        strstr(whole, "a jump no speed allows: use a joint move, or start with joint 5 turned the other way"));
    /* Nothing is planned on refusal. */
    assert_int_equal(g_plan.kind, LS_PLAN_NONE);
}

/* ---- paths ---- */

static void make_joint_path(int n_points, const char *const *tags)
{
    char why[128];
    double q_prev[LS_N_JOINTS], q_first[LS_N_JOINTS];
    memcpy(q_prev, mt_q_home, sizeof q_prev);
    memset(&g_prog, 0, sizeof g_prog);
    for (int k = 0; k < n_points; k++) {
        double q[LS_N_JOINTS];
        memcpy(q, mt_q_home, sizeof q);
        q[0] += 0.2 * (k + 1);
        q[2] -= 0.1 * (k + 1);
        ls_motion_seg_t *s = &g_prog.seg[k];
        assert_int_equal(ls_motion_seg_joint(s, M, q_prev, q, 1.0, 1.0, why, sizeof why), 0);
        snprintf(s->tag, sizeof s->tag, "%s", tags[k]);
        s->tag_index = 10 + k;
        s->point = k;
        if (k == 0) {
            memcpy(q_first, q, sizeof q_first);
        }
        memcpy(q_prev, q, sizeof q_prev);
    }
    g_prog.n = (uint16_t)n_points;
    ls_motion_seg_t *w = &g_prog.seg[n_points];
    assert_int_equal(ls_motion_seg_joint(w, M, q_prev, q_first, 1.0, 1.0, why, sizeof why), 0);
    *w = g_prog.seg[n_points]; /* keep the motion */
    snprintf(w->tag, sizeof w->tag, "%s", tags[0]);
    w->tag_index = 10;
}

static void test_path_tags_in_order_for_two_cycles(void **state)
{
    (void)state;
    const char *const tags[3] = { "A", "B", "C" };
    make_joint_path(3, tags);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 2, false, "p1"), 0);
    g_plan.ref_seq = 77;
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    assert_true(mt_run_until(&g_m, LS_MEV_DONE, 1000000, &log) > 0);
    const char *want[6] = { "A", "B", "C", "A", "B", "C" };
    assert_int_equal(log.n, 7);
    for (int i = 0; i < 6; i++) {
        assert_int_equal(log.ev[i].kind, LS_MEV_TAG);
        assert_string_equal(log.ev[i].name, want[i]);
        assert_string_equal(log.ev[i].text, "p1");
        assert_int_equal(log.ev[i].index, 10 + i % 3);
        assert_int_equal(log.ev[i].cycle, 1 + i / 3);
        assert_int_equal(log.ev[i].ref_seq, 77);
    }
    assert_int_equal(log.ev[6].kind, LS_MEV_DONE);
    assert_string_equal(log.ev[6].name, "p1");
    assert_memory_equal(g_m.q_cmd, g_prog.seg[2].q1, sizeof g_m.q_cmd);
}

static void test_path_aux_waits_for_done_and_dry_run_skips(void **state)
{
    (void)state;
    const char *const tags[2] = { "A", "" };
    make_joint_path(2, tags);
    g_prog.seg[0].n_aux = 2;
    snprintf(g_prog.seg[0].aux[0], sizeof g_prog.seg[0].aux[0], "event hello");
    snprintf(g_prog.seg[0].aux[1], sizeof g_prog.seg[0].aux[1], "dio 0 0x1 0x0");
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "p2"), 0);
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    assert_true(mt_run_until(&g_m, LS_MEV_AUX, 100000, &log) > 0);
    assert_int_equal(log.n, 2);
    assert_int_equal(log.ev[0].kind, LS_MEV_TAG);
    assert_string_equal(log.ev[1].text, "event hello");
    assert_int_equal(log.ev[1].index, 0);
    double held[LS_N_JOINTS], q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(held, g_m.q_cmd, sizeof held);
    for (int k = 0; k < 500; k++) { /* waits as long as the comms thread needs */
        mt_step(&g_m, q, qd, &log);
        assert_memory_equal(q, held, sizeof held);
    }
    assert_int_equal(log.n, 2);
    ls_motion_aux_done(&g_m);
    mt_step(&g_m, q, qd, &log);
    assert_int_equal(log.n, 3);
    assert_string_equal(log.ev[2].text, "dio 0 0x1 0x0");
    ls_motion_aux_done(&g_m);
    assert_true(mt_run_until(&g_m, LS_MEV_DONE, 100000, &log) > 0);
    assert_int_equal(count_kind(&log, LS_MEV_AUX), 2);

    /* Dry run: same motion, no auxiliary commands. */
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, true, "p2"), 0);
    start(&g_plan);
    ev_log_t log2 = { .n = 0 };
    assert_true(mt_run_until(&g_m, LS_MEV_DONE, 100000, &log2) > 0);
    assert_int_equal(count_kind(&log2, LS_MEV_AUX), 0);
    assert_int_equal(count_kind(&log2, LS_MEV_TAG), 1);
}

static void test_path_dwell_and_blend(void **state)
{
    (void)state;
    const char *const tags[3] = { "A", "B", "C" };
    make_joint_path(3, tags);
    double plain = 0.0;
    for (int k = 0; k < 3; k++) {
        plain += g_prog.seg[k].traj.duration_s;
    }
    /* Blend through A and B: no stop there, shorter than stopping. */
    ls_motion_seg_blend(&g_prog.seg[0], &g_prog.seg[1], 1.0);
    ls_motion_seg_blend(&g_prog.seg[1], &g_prog.seg[2], 1.0);
    assert_true(g_prog.seg[0].overlap_s > 0.05);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "b"), 0);
    start(&g_plan);
    ev_log_t log = { .n = 0 };
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], v_prev[LS_N_JOINTS] = { 0 };
    long k = 0;
    double min_speed_between = INFINITY;
    while (count_kind(&log, LS_MEV_DONE) == 0 && k < 100000) {
        int before = log.n;
        mt_step(&g_m, q, qd, &log);
        k++;
        for (int j = 0; j < LS_N_JOINTS; j++) {
            /* Velocity continuous: within a_max per cycle, also while two segments overlap. */
            assert_true(fabs(qd[j] - v_prev[j]) <= M->qdd_max_rad_s2[j] * DT_S * (1.0 + 1e-6));
        }
        memcpy(v_prev, qd, sizeof v_prev);
        if (log.n > before && log.ev[log.n - 1].kind == LS_MEV_TAG && log.ev[log.n - 1].name[0] != 'C') {
            min_speed_between = fmin(min_speed_between, fabs(qd[0]));
        }
    }
    assert_true(min_speed_between > 0.1); /* moving when passing A and B */
    assert_true((double)k * DT_S < plain - 0.1);
    assert_int_equal(count_kind(&log, LS_MEV_TAG), 3);
    assert_memory_equal(g_m.q_cmd, g_prog.seg[2].q1, sizeof g_m.q_cmd);

    /* Dwell 0.25 s at B: the path takes 0.25 s longer than without. */
    make_joint_path(3, tags);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "d"), 0);
    start(&g_plan);
    ev_log_t l1 = { .n = 0 };
    long k_plain = mt_run_until(&g_m, LS_MEV_DONE, 100000, &l1);
    g_prog.seg[1].delay_s = 0.25;
    start(&g_plan);
    ev_log_t l2 = { .n = 0 };
    long k_dwell = mt_run_until(&g_m, LS_MEV_DONE, 100000, &l2);
    assert_int_equal(k_dwell - k_plain, 250);
}

/* SLEW_MOTION: each joint reaches its goal in its own minimum time (not
 * synchronised), the segment lasts as long as the slowest joint, and the
 * end is exact. */
static void test_slew_joints_arrive_on_their_own(void **state)
{
    (void)state;
    double q1[LS_N_JOINTS];
    memcpy(q1, mt_q_home, sizeof q1);
    q1[0] += 1.2;
    q1[2] -= 0.1;
    ls_motion_seg_t slew, sync;
    char why[128];
    assert_int_equal(ls_motion_seg_slew(&slew, M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), LS_OK);
    assert_int_equal(ls_motion_seg_joint(&sync, M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), LS_OK);
    assert_double_equal(slew.traj.duration_s, sync.traj.duration_s, 1e-9); /* the slowest joint sets both */
    assert_true(slew.traj.axis[2].T < 0.5 * slew.traj.duration_s);         /* joint 3 arrives early */
    assert_double_equal(sync.traj.axis[2].T, sync.traj.duration_s, 1e-9);
    double q[LS_N_JOINTS];
    ls_traj_sample(&slew.traj, slew.traj.axis[2].T, q, NULL, NULL);
    assert_double_equal(q[2], q1[2], 1e-12);
    assert_true(q[0] < q1[0] - 0.1);
    ls_traj_sample(&slew.traj, slew.traj.duration_s, q, NULL, NULL);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_double_equal(q[j], q1[j], 0.0);
    }
    q1[2] = 9.0; /* beyond joint 3's limit: refused as a joint move is */
    assert_int_equal(ls_motion_seg_slew(&slew, M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), LS_ERANGE);
    assert_non_null(strstr(why, "joint 3"));
}

/* CIRCULAR_MOTION's split: both middles lie on the circle through the three
 * points, on the right sides of the via point; collinear points refused. */
static void test_arc_split_midpoints_on_the_circle(void **state)
{
    (void)state;
    const double p0[3] = { 0.5, 0.0, 0.4 }, pv[3] = { 0.6, 0.1, 0.4 }, p1[3] = { 0.5, 0.2, 0.4 };
    double ma[3], mb[3];
    assert_int_equal(ls_motion_arc_split(p0, pv, p1, ma, mb), LS_OK);
    const double c[3] = { 0.5, 0.1, 0.4 }; /* radius 0.1 */
    assert_double_equal(hypot(ma[0] - c[0], ma[1] - c[1]), 0.1, 1e-12);
    assert_double_equal(hypot(mb[0] - c[0], mb[1] - c[1]), 0.1, 1e-12);
    assert_double_equal(ma[2], 0.4, 1e-12);
    /* 45 degrees from p0 towards pv, and 45 degrees past pv towards p1 */
    assert_double_equal(ma[0], 0.5 + 0.1 * sqrt(0.5), 1e-12);
    assert_double_equal(ma[1], 0.1 - 0.1 * sqrt(0.5), 1e-12);
    assert_double_equal(mb[0], 0.5 + 0.1 * sqrt(0.5), 1e-12);
    assert_double_equal(mb[1], 0.1 + 0.1 * sqrt(0.5), 1e-12);
    const double line[3] = { 0.5, 0.1, 0.4 };
    assert_int_equal(ls_motion_arc_split(p0, line, p1, ma, mb), LS_EGEOM);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_joint_move_reaches_target_in_optimal_time),
        cmocka_unit_test(test_joint_refusal_names_joint_and_limit),
        cmocka_unit_test(test_start_refuses_wrong_start_and_double_start),
        cmocka_unit_test(test_stop_stays_on_path_pauses_and_resume_reaches_target),
        cmocka_unit_test(test_abort_holds_the_set_point),
        cmocka_unit_test(test_following_error_faults),
        cmocka_unit_test(test_line_stays_on_the_line),
        cmocka_unit_test(test_line_stop_stays_on_line),
        cmocka_unit_test(test_arc_stays_on_its_circle),
        cmocka_unit_test(test_arc_collinear_refused),
        cmocka_unit_test(test_cartesian_refusals_name_axis_and_reason),
        cmocka_unit_test(test_path_tags_in_order_for_two_cycles),
        cmocka_unit_test(test_path_aux_waits_for_done_and_dry_run_skips),
        cmocka_unit_test(test_path_dwell_and_blend),
        cmocka_unit_test(test_slew_joints_arrive_on_their_own),
        cmocka_unit_test(test_arc_split_midpoints_on_the_circle),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
