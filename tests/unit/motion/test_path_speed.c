/* Cartesian segments whose joints set their speed (docs/architecture.md
 * "Path speed under joint limits"), planned and run by the executor with an
 * ideal arm at 1 kHz. Every joint's velocity and acceleration are the first
 * and second differences of the set-points over the period (each a mean of
 * the true value, never above its peak), checked against the model's
 * limits: on a line whose joint speed peaks mid-way (joint 4 swinging past a
 * wrist singularity), on a line into a near-singularity, on an arc, and
 * through stops and resumes anywhere on a slowed line. A line the joints
 * can follow runs as requested. The refusals: a line into the joint 1 axis
 * (a shoulder singularity, whatever the speed) and a line on which a joint
 * reaches its limit where only another configuration goes on; both whole,
 * with what to do instead. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_math.h"
#include "ls_motion.h"
#include "motion_test_util.h"

#define M (&ls_robot_model_default)
#define MARGIN 1.001 /* finite differences in doubles: within 0.1 % of a limit */

static const double g_flange[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 }; /* no tool */
/* Joint 4 swings past a wrist singularity (joint 5 from 0.15 rad to about 0.01 and back). */
static const double g_near_wrist[LS_N_JOINTS] = { 0.0, 0.3, 0.3, 0.5, 0.15, 0.0 };
/* The README's ready pose. */
static const double g_ready[LS_N_JOINTS] = { 0.0, -0.3, 0.6, 0.0, 0.9, 0.0 };

static ls_motion_plan_t g_plan;
static ls_motion_t g_m;

/* Cartesian limits at pct % of the model's speed and its full acceleration. */
static ls_motion_cart_limits_t limits_at(double pct)
{
    const ls_motion_cart_limits_t lim = { .v_lin_m_s = M->max_linear_speed_m_s * pct / 100.0,
                                          .a_lin_m_s2 = M->max_linear_accel_m_s2,
                                          .j_lin_m_s3 = M->max_linear_jerk_m_s3,
                                          .v_ang_rad_s = M->max_angular_speed_rad_s * pct / 100.0,
                                          .a_ang_rad_s2 = M->max_angular_accel_rad_s2,
                                          .j_ang_rad_s3 = M->max_angular_jerk_rad_s3,
                                          .joint_speed_frac = 1.0 };
    return lim;
}

/* The flange at q moved by d (m), orientation kept. */
static void moved(const double q[LS_N_JOINTS], double dx, double dy, double dz, double T[16])
{
    ls_kin_fk(M, q, T);
    T[12] += dx;
    T[13] += dy;
    T[14] += dz;
}

typedef struct {
    double qd, qdd; /* largest joint velocity and acceleration over their limits */
    double qd4;     /* joint 4's velocity over its limit */
    double off_m;   /* largest distance of the flange from the segment from a to b */
    long cycles;    /* until LS_MEV_DONE */
    int paused;     /* stops that ended in LS_MEV_PAUSED */
} run_t;

static double dist_to_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], d = 0.0, t = 0.0, n = 0.0;
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
        t += ap[i] * ab[i];
        n += ab[i] * ab[i];
    }
    t = n > 0.0 ? fmin(1.0, fmax(0.0, t / n)) : 0.0;
    for (int i = 0; i < 3; i++) {
        const double e = ap[i] - t * ab[i];
        d += e * e;
    }
    return sqrt(d);
}

/* Run g_plan from q0; stopMotion at each cycle of stops[] (ascending, 0:
 * none), resume once paused. The flange's distance from the segment a-b
 * (NULL: not measured). */
static run_t run(const double q0[LS_N_JOINTS], const long *stops, int n_stops, const double *a, const double *b)
{
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, q0);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    run_t r = { 0 };
    double qh[3][LS_N_JOINTS];
    for (int h = 0; h < 3; h++) {
        memcpy(qh[h], q0, sizeof qh[h]);
    }
    int next = 0;
    bool done = false;
    for (long k = 1; !done && k < 2000000; k++) {
        if (next < n_stops && k == stops[next]) {
            ls_motion_stop(&g_m);
            next++;
        }
        ev_log_t log = { .n = 0 };
        double q[LS_N_JOINTS], qd[LS_N_JOINTS];
        mt_step(&g_m, q, qd, &log);
        for (int e = 0; e < log.n; e++) {
            assert_int_not_equal(log.ev[e].kind, LS_MEV_FAULT);
            if (log.ev[e].kind == LS_MEV_PAUSED) {
                r.paused++;
                assert_int_equal(ls_motion_resume(&g_m), 0);
            }
            done = done || log.ev[e].kind == LS_MEV_DONE;
        }
        memmove(qh[1], qh[0], 2 * sizeof qh[0]);
        memcpy(qh[0], q, sizeof qh[0]);
        for (int j = 0; j < LS_N_JOINTS; j++) {
            const double v = fabs(qh[0][j] - qh[1][j]) / DT_S / M->qd_max_rad_s[j];
            r.qd = fmax(r.qd, v);
            r.qd4 = j == 3 ? fmax(r.qd4, v) : r.qd4;
            if (k >= 2) {
                r.qdd = fmax(r.qdd, fabs(qh[0][j] - 2.0 * qh[1][j] + qh[2][j]) / (DT_S * DT_S) / M->qdd_max_rad_s2[j]);
            }
        }
        if (a != NULL) {
            double F[16];
            ls_kin_fk(M, q, F);
            r.off_m = fmax(r.off_m, dist_to_segment(F + 12, a, b));
        }
        r.cycles = k;
    }
    assert_true(done);
    return r;
}

/* Plan into g_plan the line from g_near_wrist that swings joint 4 past the
 * wrist singularity, at 50 % speed; P0, P1: the flange at its ends. */
static void plan_swing(double P0[16], double P1[16])
{
    ls_kin_fk(M, g_near_wrist, P0);
    moved(g_near_wrist, 0.0, 0.11, -0.1, P1);
    const ls_motion_cart_limits_t lim = limits_at(50.0);
    char why[LS_MOTION_WHY_LEN];
    assert_int_equal(ls_motion_plan_line(&g_plan, M, g_near_wrist, g_flange, P1, &lim, why, sizeof why), LS_OK);
}

static void a_line_whose_joint_speed_peaks_mid_way_slows_there_within_every_limit(void **state)
{
    (void)state;
    double P0[16], P1[16];
    plan_swing(P0, P1);
    ls_motion_slowdown_t d;
    assert_true(ls_motion_seg_slowdown(&g_plan.one, &d));
    assert_int_equal(d.joint, 4);
    assert_true(d.speed_frac < 0.1 && d.from < 0.5 && d.to > 0.5); /* the slow part holds the peak */
    assert_true(d.duration_s > 2.0 * d.requested_s);
    char text[LS_MOTION_WHY_LEN];
    assert_true(ls_motion_slowdown_text(&d, text, sizeof text) < (int)sizeof text);
    assert_non_null(strstr(text, "running at "));
    assert_non_null(strstr(text, "% of the requested speed between "));
    assert_non_null(strstr(text, "of the path: joint 4 at its "));

    const run_t r = run(g_near_wrist, NULL, 0, P0 + 12, P1 + 12);
    print_message("joint speed <= %.4f, acceleration <= %.4f of the limits; %ld cycles for %.3f s planned\n", r.qd,
                  r.qdd, r.cycles, d.duration_s);
    assert_true(r.qd <= MARGIN && r.qdd <= MARGIN);
    assert_true(r.qd4 > 0.9); /* joint 4 runs at its velocity limit in the middle: the check is not vacuous */
    assert_true(r.off_m < 1e-6);
    assert_true(fabs((double)r.cycles * DT_S - d.duration_s) <= 2.0 * DT_S);
}

static void a_line_into_a_near_singularity_slows_towards_its_end(void **state)
{
    (void)state;
    double P0[16], P1[16];
    ls_kin_fk(M, g_near_wrist, P0);
    moved(g_near_wrist, 0.0, 0.05, -0.05, P1); /* joint 5 ends at about 0.005 rad */
    const ls_motion_cart_limits_t lim = limits_at(50.0);
    char why[LS_MOTION_WHY_LEN];
    assert_int_equal(ls_motion_plan_line(&g_plan, M, g_near_wrist, g_flange, P1, &lim, why, sizeof why), LS_OK);
    ls_motion_slowdown_t d;
    assert_true(ls_motion_seg_slowdown(&g_plan.one, &d));
    assert_true(d.speed_frac < 0.1 && d.from >= 0.5 && d.to == 1.0);
    const run_t r = run(g_near_wrist, NULL, 0, P0 + 12, P1 + 12);
    assert_true(r.qd <= MARGIN && r.qdd <= MARGIN);
    assert_true(fmax(r.qd, r.qdd) > 0.9); /* a joint runs at a limit near the end: the check is not vacuous */
    assert_true(r.off_m < 1e-6);
}

static void an_arc_keeps_every_joint_limit(void **state)
{
    (void)state;
    double Pv[16], P1[16];
    moved(g_ready, 0.1, 0.1, 0.0, Pv);
    moved(g_ready, 0.0, 0.2, 0.0, P1);
    const ls_motion_cart_limits_t lim = limits_at(100.0);
    char why[LS_MOTION_WHY_LEN];
    assert_int_equal(ls_motion_plan_arc(&g_plan, M, g_ready, g_flange, Pv, P1, &lim, why, sizeof why), LS_OK);
    ls_motion_slowdown_t d;
    assert_true(ls_motion_seg_slowdown(&g_plan.one, &d)); /* at the model's maxima its joints slow it */
    const run_t r = run(g_ready, NULL, 0, NULL, NULL);
    assert_true(r.qd <= MARGIN && r.qdd <= MARGIN);
    assert_true(r.qdd > 0.5);
    double P[16];
    ls_kin_fk(M, g_m.q_cmd, P);
    assert_true(ls_pose_dist(P, P1) < 1e-9);
}

/* A stop at each of many moments of the slowed line (the plan's and the
 * stop's own ramps, its slow middle): every joint within its limits,
 * through the stop, the pause and the resume, and on the line. */
static void a_stop_anywhere_on_a_slowed_line_keeps_the_limits_and_resumes_on_it(void **state)
{
    (void)state;
    double P0[16], P1[16];
    plan_swing(P0, P1);
    const long T = (long)(ls_motion_seg_duration_s(&g_plan.one) / DT_S);
    for (int i = 1; i < 24; i++) {
        const long at = T * i / 24;
        const run_t r = run(g_near_wrist, &at, 1, P0 + 12, P1 + 12);
        if (r.qd > MARGIN || r.qdd > MARGIN || r.off_m > 1e-6 || r.paused != 1) {
            fail_msg("a stop at cycle %ld of %ld: joint speed %.4f, acceleration %.4f of the limits, %.3g m off the "
                     "line, %d pauses",
                     at, T, r.qd, r.qdd, r.off_m, r.paused);
        }
    }
}

static void a_line_the_joints_can_follow_runs_as_requested(void **state)
{
    (void)state;
    double P1[16];
    moved(g_ready, 0.15, 0.0, 0.0, P1);
    const ls_motion_cart_limits_t lim = limits_at(10.0);
    char why[LS_MOTION_WHY_LEN];
    assert_int_equal(ls_motion_plan_line(&g_plan, M, g_ready, g_flange, P1, &lim, why, sizeof why), LS_OK);
    assert_false(ls_motion_seg_slowdown(&g_plan.one, NULL));
    ls_traj_axis_t plain;
    assert_int_equal(ls_traj_plan_axis(&plain, 0.0, 0.15, lim.v_lin_m_s, lim.a_lin_m_s2, lim.j_lin_m_s3), LS_OK);
    assert_true(fabs(ls_motion_seg_duration_s(&g_plan.one) - plain.T) < 1e-9);
    assert_int_equal(ls_motion_seg_check_speed(&g_plan.one, why, sizeof why), LS_OK);
    /* at 90 % its joints slow it down; a move that keeps its speed there is refused */
    const ls_motion_cart_limits_t fast = limits_at(90.0);
    assert_int_equal(ls_motion_plan_line(&g_plan, M, g_ready, g_flange, P1, &fast, why, sizeof why), LS_OK);
    assert_true(ls_motion_seg_slowdown(&g_plan.one, NULL));
    assert_true(ls_motion_seg_duration_s(&g_plan.one) < 1.6);
    assert_int_equal(ls_motion_seg_check_speed(&g_plan.one, why, sizeof why), LS_ERANGE);
    assert_non_null(strstr(why, "this move keeps its speed: give at most "));
}

/* Every refusal ends whole: never with the cut mark. */
static void assert_whole(const char *why)
{
    const size_t n = strlen(why);
    assert_true(n > 4 && n + 1 < LS_MOTION_WHY_LEN);
    assert_false(strcmp(why + n - 3, "\xE2\x80\xA6") == 0);
}

/* A line that ends with the wrist centre on the joint 1 axis (the flange
 * pointing down over the base), where joint 1 has no defined angle. */
static void a_line_into_the_joint_1_axis_is_refused_as_a_shoulder_singularity(void **state)
{
    (void)state;
    const double a6[6] = { 0.1, 0.0, 0.4, LS_PI, 0.0, 0.0 }, b6[6] = { 0.0, 0.0, 0.4, LS_PI, 0.0, 0.0 };
    double A[16], B[16], sols[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
    ls_pose_from_xyzrpy(a6, A);
    ls_pose_from_xyzrpy(b6, B);
    int n = 0;
    assert_int_equal(ls_kin_ik_all(M, A, sols, &n), LS_OK);
    for (double pct = 100.0; pct >= 1.0; pct /= 10.0) { /* no speed avoids it */
        const ls_motion_cart_limits_t lim = limits_at(pct);
        char why[LS_MOTION_WHY_LEN];
        assert_int_equal(ls_motion_plan_line(&g_plan, M, sols[0], g_flange, B, &lim, why, sizeof why), LS_ERANGE);
        assert_true(strncmp(why, "joint 1 runs away at 100 % of the path near tip (", 49) == 0);
        assert_non_null(strstr(why, "shoulder singularity (the wrist centre on the joint 1 axis) that no speed avoids: "
                                    "use a joint move, or a slight detour that passes beside that axis"));
        assert_whole(why);
        assert_int_equal(g_plan.kind, LS_PLAN_NONE);
    }
}

/* docs/host-tool.md's square path from the ready pose: its first line turns
 * the tool half a turn (joint 4 to pi), its second would take joint 4 past
 * its limit of 185 degrees; beyond it only the flipped wrist goes on. */
static void a_line_that_takes_a_joint_to_its_limit_is_refused_naming_it(void **state)
{
    (void)state;
    const double p1[6] = { 0.45, 0.0, 0.5, 0.0, 1.57, 0.0 }, p2[6] = { 0.45, 0.1, 0.5, 0.0, 1.57, 0.0 };
    double T1[16], T2[16];
    ls_pose_from_xyzrpy(p1, T1);
    ls_pose_from_xyzrpy(p2, T2);
    const ls_motion_cart_limits_t lim = limits_at(40.0);
    char why[LS_MOTION_WHY_LEN];
    ls_motion_seg_t s1, s2;
    memset(&s1, 0, sizeof s1);
    memset(&s2, 0, sizeof s2);
    assert_int_equal(ls_motion_seg_line(&s1, M, g_ready, g_flange, T1, &lim, why, sizeof why), LS_OK);
    assert_true(fabs(s1.q1[3] - LS_PI) < 1e-6);
    assert_int_equal(ls_motion_seg_line(&s2, M, s1.q1, g_flange, T2, &lim, why, sizeof why), LS_ERANGE);
    assert_true(strncmp(why, "joint 4 reaches its limit 3.229 rad at 27 % of the path near tip (0.45, 0.02", 76) == 0);
    assert_non_null(strstr(why, "; going on needs another arm configuration, a jump no speed allows: use a joint "
                                "move, or start with joint 4 turned the other way"));
    assert_whole(why);
}

/* A path's slowed segment says so once, as it begins in the first cycle
 * that runs it (the closing segment: the second); the others say nothing. */
static void a_slowed_segment_of_a_path_says_so_once(void **state)
{
    (void)state;
    static ls_motion_program_t prog;
    memset(&prog, 0, sizeof prog);
    double Pa[16], Pb[16], P0[16];
    ls_kin_fk(M, g_near_wrist, P0);
    moved(g_near_wrist, 0.02, 0.0, 0.0, Pa);   /* a short line the joints follow */
    moved(g_near_wrist, 0.02, 0.11, -0.1, Pb); /* then the swing past the wrist singularity */
    const ls_motion_cart_limits_t lim = limits_at(50.0);
    char why[LS_MOTION_WHY_LEN];
    assert_int_equal(ls_motion_seg_line(&prog.seg[0], M, g_near_wrist, g_flange, Pa, &lim, why, sizeof why), LS_OK);
    assert_int_equal(ls_motion_seg_line(&prog.seg[1], M, prog.seg[0].q1, g_flange, Pb, &lim, why, sizeof why), LS_OK);
    assert_int_equal(ls_motion_seg_line(&prog.seg[2], M, prog.seg[1].q1, g_flange, Pa, &lim, why, sizeof why), LS_OK);
    for (int k = 0; k < 3; k++) {
        prog.seg[k].point = k;
    }
    prog.n = 2;
    assert_false(ls_motion_seg_slowdown(&prog.seg[0], NULL));
    assert_true(ls_motion_seg_slowdown(&prog.seg[1], NULL));
    assert_true(ls_motion_seg_slowdown(&prog.seg[2], NULL));
    assert_int_equal(ls_motion_prog_blend(&prog, M, 2, why, sizeof why), LS_OK);
    assert_int_equal(ls_motion_plan_path(&g_plan, &prog, 2, false, "swing"), LS_OK);
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, g_near_wrist);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    int seen[3] = { 0, 0, 0 }, cycle_of[3] = { 0, 0, 0 };
    bool done = false;
    for (long k = 0; !done && k < 1000000; k++) {
        ev_log_t log = { .n = 0 };
        double q[LS_N_JOINTS], qd[LS_N_JOINTS];
        mt_step(&g_m, q, qd, &log);
        for (int e = 0; e < log.n; e++) {
            if (log.ev[e].kind == LS_MEV_SLOW) {
                assert_true(log.ev[e].index >= 0 && log.ev[e].index < 3);
                seen[log.ev[e].index]++;
                cycle_of[log.ev[e].index] = log.ev[e].cycle;
            }
            done = done || log.ev[e].kind == LS_MEV_DONE;
        }
    }
    assert_true(done);
    assert_int_equal(seen[0], 0);
    assert_int_equal(seen[1], 1);
    assert_int_equal(cycle_of[1], 1);
    assert_int_equal(seen[2], 1); /* the segment back to point 0, run from the second cycle on */
    assert_int_equal(cycle_of[2], 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(a_line_whose_joint_speed_peaks_mid_way_slows_there_within_every_limit),
        cmocka_unit_test(a_line_into_a_near_singularity_slows_towards_its_end),
        cmocka_unit_test(an_arc_keeps_every_joint_limit),
        cmocka_unit_test(a_stop_anywhere_on_a_slowed_line_keeps_the_limits_and_resumes_on_it),
        cmocka_unit_test(a_line_the_joints_can_follow_runs_as_requested),
        cmocka_unit_test(a_line_into_the_joint_1_axis_is_refused_as_a_shoulder_singularity),
        cmocka_unit_test(a_line_that_takes_a_joint_to_its_limit_is_refused_naming_it),
        cmocka_unit_test(a_slowed_segment_of_a_path_says_so_once),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
