/* Blended paths (ls_motion_prog_blend): the blend maths, and the executor
 * running blended programs with an ideal arm at 1 ms, measured from the
 * set-points: speed, acceleration and jerk by finite differences (each a
 * weighted mean of the true value over a few cycles, so never above its
 * peak), the distance from the path and from the points. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_motion.h"
#include "motion_test_util.h"

#define N_ZIG 6
#define MAX_STEPS 100000

static const ls_robot_model_t *M = &ls_robot_model_default;

static ls_motion_t g_m;
static ls_motion_plan_t g_plan;
static ls_motion_program_t g_prog;
static double g_corner[N_ZIG + 1][3]; /* the start, then point k at [k + 1] */

static void tip_of(const double q[LS_N_JOINTS], double P[16])
{
    double F[16], T[16];
    ls_kin_fk(M, q, F);
    mt_tool(T);
    ls_pose_mul(F, T, P);
}

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Distance from p to the segment a-b. */
static double dist_to_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3];
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
    }
    double t = (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / (ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]);
    t = fmin(1.0, fmax(0.0, t));
    double c[3];
    for (int i = 0; i < 3; i++) {
        c[i] = a[i] + t * ab[i];
    }
    return dist3(p, c);
}

/* A zig-zag of n straight lines from the home pose: point k at
 * (+4 cm (k + 1), +-3 cm, 0) from the start, same orientation, tagged
 * "Pk", blended at `frac` (the last point stops); `accel_k` scales the
 * acceleration (not the jerk) of segment `accel_seg`. */
static void make_zigzag(int n, double frac, int accel_seg, double accel_k)
{
    char why[160];
    double tool[16], P[16], q_prev[LS_N_JOINTS];
    mt_tool(tool);
    memset(&g_prog, 0, sizeof g_prog);
    memcpy(q_prev, mt_q_home, sizeof q_prev);
    tip_of(mt_q_home, P);
    memcpy(g_corner[0], P + 12, sizeof g_corner[0]);
    for (int k = 0; k < n; k++) {
        ls_motion_cart_limits_t lim;
        mt_limits(&lim);
        if (k == accel_seg) {
            lim.a_lin_m_s2 *= accel_k;
        }
        double T[16];
        memcpy(T, P, sizeof T);
        T[12] += 0.04 * (k + 1);
        T[13] += k % 2 == 0 ? 0.03 : -0.03;
        ls_motion_seg_t *s = &g_prog.seg[k];
        snprintf(s->tag, sizeof s->tag, "P%d", k);
        s->tag_index = k;
        s->point = k;
        s->blend_frac = k + 1 < n ? frac : 0.0;
        assert_int_equal(ls_motion_seg_line(s, M, q_prev, tool, T, &lim, why, sizeof why), 0);
        memcpy(q_prev, s->q1, sizeof q_prev);
        memcpy(g_corner[k + 1], T + 12, sizeof g_corner[k + 1]);
    }
    g_prog.n = (uint16_t)n;
    assert_int_equal(ls_motion_prog_blend(&g_prog, M, 1, why, sizeof why), 0);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "zig"), 0);
}

static int count_done(const ev_log_t *log)
{
    int n = 0;
    for (int i = 0; i < log->n; i++) {
        n += log->ev[i].kind == LS_MEV_DONE || log->ev[i].kind == LS_MEV_FAULT;
    }
    return n;
}

static int count_kind_tags(const ev_log_t *log)
{
    int n = 0;
    for (int i = 0; i < log->n; i++) {
        n += log->ev[i].kind == LS_MEV_TAG;
    }
    return n;
}

typedef struct {
    long steps;
    double v, a, j;         /* peaks of the tool tip's motion */
    double min_speed;       /* from passing the first point to braking for the last one */
    double off_path;        /* the largest distance from the polyline */
    double outside_bound;   /* > 0: a sample off the polyline not within its corner's bound */
    int tags, tag_in_order; /* tag events; 1 while they came as P0, P1, ... */
} run_t;

static run_t run_zigzag(int n)
{
    run_t r = { .min_speed = INFINITY, .tag_in_order = 1 };
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    double p[4][3]; /* p[0] newest */
    for (int h = 0; h < 4; h++) {
        memcpy(p[h], g_corner[0], sizeof p[h]);
    }
    ev_log_t log = { .n = 0 };
    bool between = false, done = false;
    while (!done && r.steps < MAX_STEPS) {
        double q[LS_N_JOINTS], qd[LS_N_JOINTS], P[16];
        const int before = log.n;
        mt_step(&g_m, q, qd, &log);
        r.steps++;
        tip_of(q, P);
        memmove(p[1], p[0], 3 * sizeof p[0]);
        memcpy(p[0], P + 12, sizeof p[0]);
        double v[3], a[3], j[3];
        for (int i = 0; i < 3; i++) {
            v[i] = (p[0][i] - p[1][i]) / DT_S;
            a[i] = (p[0][i] - 2.0 * p[1][i] + p[2][i]) / (DT_S * DT_S);
            j[i] = (p[0][i] - 3.0 * p[1][i] + 3.0 * p[2][i] - p[3][i]) / (DT_S * DT_S * DT_S);
        }
        const double zero[3] = { 0, 0, 0 };
        r.v = fmax(r.v, dist3(v, zero));
        r.a = fmax(r.a, dist3(a, zero));
        r.j = fmax(r.j, dist3(j, zero));
        /* the last segment's second half brakes to the last point */
        const bool braking_to_last = g_m.seg_i_ == n - 1 && g_m.t_s > ls_motion_seg_duration_s(&g_prog.seg[n - 1]) / 2;
        for (int e = before; e < log.n; e++) {
            if (log.ev[e].kind == LS_MEV_TAG) {
                char want[16];
                snprintf(want, sizeof want, "P%d", r.tags);
                r.tag_in_order &= strcmp(log.ev[e].name, want) == 0;
                r.tags++;
                between = true;
            }
            done |= log.ev[e].kind == LS_MEV_DONE;
        }
        if (between && !braking_to_last && !done) {
            r.min_speed = fmin(r.min_speed, dist3(v, zero));
        }
        double off = INFINITY;
        for (int k = 0; k < n; k++) {
            off = fmin(off, dist_to_segment(p[0], g_corner[k], g_corner[k + 1]));
        }
        r.off_path = fmax(r.off_path, off);
        if (off > 1e-7) {
            double slack = INFINITY; /* within the bound of some blended corner? */
            for (int k = 0; k + 1 < n; k++) {
                const double bound = ls_motion_seg_blend_dev_m(&g_prog.seg[k], &g_prog.seg[k + 1]);
                slack = fmin(slack, dist3(p[0], g_corner[k + 1]) - bound);
            }
            r.outside_bound = fmax(r.outside_bound, slack - 1e-9);
        }
    }
    assert_true(done);
    return r;
}

/* The maths of one corner: the jerk scale, the window, the overlap and the
 * deviation bound, from the planned profiles. */
static void test_blend_maths_of_a_corner(void **state)
{
    (void)state;
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    make_zigzag(3, 0.6, -1, 1.0);
    for (int k = 0; k < 3; k++) {
        const ls_motion_seg_t *s = &g_prog.seg[k];
        const double J = s->path.j * s->length_m;
        double want = lim.j_lin_m_s3;
        for (int c = (k == 0 ? 0 : k - 1); c <= (k < 2 ? k : 1); c++) {
            /* corner c joins segment c and c + 1 */
            double da[3], db[3];
            for (int i = 0; i < 3; i++) {
                da[i] = g_corner[c + 1][i] - g_corner[c][i];
                db[i] = g_corner[c + 2][i] - g_corner[c + 1][i];
            }
            const double zero[3] = { 0, 0, 0 };
            const double cth = (da[0] * db[0] + da[1] * db[1] + da[2] * db[2]) / (dist3(da, zero) * dist3(db, zero));
            want = fmin(want, lim.j_lin_m_s3 / fmax(1.0, 2.0 * cos(acos(cth) / 2.0)));
        }
        assert_true(fabs(J - want) <= 1e-9 * want);
        assert_true(fabs(ls_pathspeed_first_jerk_s(&s->path) - ls_pathspeed_last_jerk_s(&s->path)) <
                    1e-12); /* symmetric */
    }
    for (int k = 0; k < 2; k++) {
        const ls_motion_seg_t *a = &g_prog.seg[k], *b = &g_prog.seg[k + 1];
        const double win = fmin(ls_pathspeed_last_jerk_s(&a->path), ls_pathspeed_first_jerk_s(&b->path));
        assert_true(win > 0.05);
        assert_true(fabs(a->overlap_s - 0.6 * win) < 1e-12);
        const double Jmax = fmax(a->path.j * a->length_m, b->path.j * b->length_m);
        const double t = a->overlap_s;
        assert_true(fabs(ls_motion_seg_blend_dev_m(a, b) - Jmax * t * t * t / 6.0) < 1e-15);
    }
    assert_true(g_prog.seg[2].overlap_s == 0.0); /* the last point stops */
    assert_true(ls_motion_seg_blend_dev_m(&g_prog.seg[2], NULL) == 0.0);

    /* Straight on (theta = 0): both jerks add fully, half each. A reversal
     * (theta = 180 degrees) cancels them: the full jerk stays. */
    char why[160];
    double tool[16], P0[16], P1[16], P2[16];
    mt_tool(tool);
    tip_of(mt_q_home, P0);
    memcpy(P1, P0, sizeof P1);
    memcpy(P2, P0, sizeof P2);
    P1[12] += 0.05;
    P2[12] += 0.10;
    for (int rev = 0; rev < 2; rev++) {
        memset(&g_prog, 0, sizeof g_prog);
        g_prog.seg[0].blend_frac = 1.0;
        assert_int_equal(ls_motion_seg_line(&g_prog.seg[0], M, mt_q_home, tool, P1, &lim, why, sizeof why), 0);
        assert_int_equal(
            ls_motion_seg_line(&g_prog.seg[1], M, g_prog.seg[0].q1, tool, rev ? P0 : P2, &lim, why, sizeof why), 0);
        g_prog.n = 2;
        assert_int_equal(ls_motion_prog_blend(&g_prog, M, 1, why, sizeof why), 0);
        const double J = g_prog.seg[0].path.j * g_prog.seg[0].length_m;
        assert_true(fabs(J - lim.j_lin_m_s3 * (rev ? 1.0 : 0.5)) < 1e-9);
        assert_true(g_prog.seg[0].overlap_s > 0.0);
    }
}

/* A blended zig-zag never stops between its first and last points, stays
 * on the path or within each corner's bound, keeps the tip's speed,
 * acceleration and jerk within the limits, fires each tag once, in order,
 * and is faster than the same path stopping at every point. */
static void test_blended_zigzag_within_bound_and_limits(void **state)
{
    (void)state;
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    make_zigzag(N_ZIG, 0.0, -1, 1.0);
    const run_t stop = run_zigzag(N_ZIG);
    make_zigzag(N_ZIG, 1.0, -1, 1.0);
    const run_t blend = run_zigzag(N_ZIG);

    assert_int_equal(blend.tags, N_ZIG);
    assert_true(blend.tag_in_order);
    assert_true(blend.min_speed > 1e-3);
    assert_true(blend.off_path > 1e-4); /* it does leave the corners */
    assert_true(blend.outside_bound <= 0.0);
    assert_true(blend.v <= lim.v_lin_m_s * (1.0 + 1e-6));
    assert_true(blend.a <= lim.a_lin_m_s2 * (1.0 + 1e-6));
    assert_true(blend.j <= lim.j_lin_m_s3 * (1.0 + 1e-6));
    assert_true(blend.steps < stop.steps - 100 * (N_ZIG - 1) / 2);

    /* transitionSpeed 0: stops at every point, stays on the polyline, tags
     * as before. */
    assert_int_equal(stop.tags, N_ZIG);
    assert_true(stop.tag_in_order);
    assert_true(stop.min_speed < 1e-5); /* the last millisecond of a jerk-limited stop: J dt^3 / 6 */
    assert_true(stop.off_path < 1e-7);
    assert_true(stop.j <= lim.j_lin_m_s3 * (1.0 + 1e-6));
}

/* The per-segment acceleration of a straight line sets its duration; a
 * blend between segments of different accelerations stays within the
 * larger of the two. */
static void test_line_accel_changes_its_duration(void **state)
{
    (void)state;
    make_zigzag(2, 0.0, 1, 0.25);
    const double slow = ls_motion_seg_duration_s(&g_prog.seg[1]);
    make_zigzag(2, 0.0, 1, 1.0);
    const double fast = ls_motion_seg_duration_s(&g_prog.seg[1]);
    assert_true(slow > fast + 0.05);
    make_zigzag(2, 1.0, 1, 0.25);
    const run_t r = run_zigzag(2);
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    assert_true(r.a <= lim.a_lin_m_s2 * (1.0 + 1e-6));
    assert_true(r.min_speed > 1e-4);
}

/* Two cycles of a blended line path: the last point blends into the line
 * back to the first (seg[n]), that one into seg[1]; every tag fires once
 * per cycle, nothing faults, the tip stays within the limits, and the last
 * point of the last cycle stops. */
static void test_blended_lines_over_two_cycles(void **state)
{
    (void)state;
    char why[160];
    double tool[16], P0[16];
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    mt_tool(tool);
    make_zigzag(3, 1.0, -1, 1.0);
    g_prog.seg[2].blend_frac = 1.0;
    ls_motion_seg_t *back = &g_prog.seg[3];
    memset(back, 0, sizeof *back);
    snprintf(back->tag, sizeof back->tag, "P0");
    back->blend_frac = 1.0;
    tip_of(g_prog.seg[0].q1, P0);
    assert_int_equal(ls_motion_seg_line(back, M, g_prog.seg[2].q1, tool, P0, &lim, why, sizeof why), 0);
    assert_int_equal(ls_motion_prog_blend(&g_prog, M, 2, why, sizeof why), 0);
    assert_true(g_prog.seg[2].overlap_s > 0.0 && g_prog.seg[3].overlap_s > 0.0);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 2, false, "zig2"), 0);
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    double p[4][3];
    tip_of(mt_q_home, P0);
    for (int h = 0; h < 4; h++) {
        memcpy(p[h], P0 + 12, sizeof p[h]);
    }
    ev_log_t log = { .n = 0 };
    const double zero[3] = { 0, 0, 0 };
    long k = 0;
    for (; k < MAX_STEPS && count_done(&log) == 0; k++) {
        double q[LS_N_JOINTS], qd[LS_N_JOINTS], P[16];
        mt_step(&g_m, q, qd, &log);
        tip_of(q, P);
        memmove(p[1], p[0], 3 * sizeof p[0]);
        memcpy(p[0], P + 12, sizeof p[0]);
        double v[3], a[3], j[3];
        for (int i = 0; i < 3; i++) {
            v[i] = (p[0][i] - p[1][i]) / DT_S;
            a[i] = (p[0][i] - 2.0 * p[1][i] + p[2][i]) / (DT_S * DT_S);
            j[i] = (p[0][i] - 3.0 * p[1][i] + 3.0 * p[2][i] - p[3][i]) / (DT_S * DT_S * DT_S);
        }
        assert_true(dist3(v, zero) <= lim.v_lin_m_s * (1.0 + 1e-6));
        assert_true(dist3(a, zero) <= lim.a_lin_m_s2 * (1.0 + 1e-6));
        assert_true(dist3(j, zero) <= lim.j_lin_m_s3 * (1.0 + 1e-6));
    }
    const char *want[7] = { "P0", "P1", "P2", "P0", "P1", "P2", "zig2" };
    assert_int_equal(log.n, 7);
    for (int e = 0; e < 7; e++) {
        assert_int_equal(log.ev[e].kind, e < 6 ? LS_MEV_TAG : LS_MEV_DONE);
        assert_string_equal(log.ev[e].name, want[e]);
    }
    assert_memory_equal(g_m.q_cmd, g_prog.seg[2].q1, sizeof g_m.q_cmd);
}

/* Space-frame rotation vector of B A^T (4x4 column-major poses): the turn
 * from A to B. */
static void rot_between(const double A[16], const double B[16], double w[3])
{
    double R[3][3];
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            R[r][c] = 0.0;
            for (int k = 0; k < 3; k++) {
                R[r][c] += B[k * 4 + r] * A[k * 4 + c]; /* B(r,k) A^T(k,c) = B(r,k) A(c,k) */
            }
        }
    }
    const double ang = acos(fmin(1.0, fmax(-1.0, (R[0][0] + R[1][1] + R[2][2] - 1.0) / 2.0)));
    const double f = ang < 1e-9 ? 0.5 : ang / (2.0 * sin(ang));
    w[0] = f * (R[2][1] - R[1][2]);
    w[1] = f * (R[0][2] - R[2][0]);
    w[2] = f * (R[1][0] - R[0][1]);
}

/* Two lines that both turn the tool: the composed rotation stays within the
 * angular speed, acceleration and jerk limits (the products of the two
 * rotations included), and the blend still happens. */
static void test_turning_lines_blend_within_angular_limits(void **state)
{
    (void)state;
    char why[160];
    double tool[16], P[3][16];
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    mt_tool(tool);
    tip_of(mt_q_home, P[0]);
    for (int k = 1; k < 3; k++) {
        const double rz[6] = { 0, 0, 0, 0.0, 0.0, 0.35 * k }, ry[6] = { 0, 0, 0, 0.0, 0.25 * k, 0.0 };
        double Rz[16], Ry[16], T[16];
        ls_pose_from_xyzrpy(rz, Rz);
        ls_pose_from_xyzrpy(ry, Ry);
        ls_pose_mul(Rz, Ry, T);
        ls_pose_mul(T, P[0], P[k]);
        memcpy(P[k] + 12, P[0] + 12, 3 * sizeof(double));
        P[k][12] += k == 1 ? 0.04 : 0.0;
        P[k][13] += 0.03 * k;
    }
    memset(&g_prog, 0, sizeof g_prog);
    double q_prev[LS_N_JOINTS];
    memcpy(q_prev, mt_q_home, sizeof q_prev);
    for (int k = 0; k < 2; k++) {
        ls_motion_seg_t *s = &g_prog.seg[k];
        snprintf(s->tag, sizeof s->tag, "T%d", k);
        s->point = k;
        s->blend_frac = k == 0 ? 1.0 : 0.0;
        assert_int_equal(ls_motion_seg_line(s, M, q_prev, tool, P[k + 1], &lim, why, sizeof why), 0);
        assert_true(s->turn_rad > 0.2);
        memcpy(q_prev, s->q1, sizeof q_prev);
    }
    g_prog.n = 2;
    assert_int_equal(ls_motion_prog_blend(&g_prog, M, 1, why, sizeof why), 0);
    assert_true(g_prog.seg[0].overlap_s > 0.02);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "turn"), 0);
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    double prev[16], w[3][3] = { { 0 } }, peak[3] = { 0 };
    memcpy(prev, P[0], sizeof prev);
    ev_log_t log = { .n = 0 };
    const double zero[3] = { 0, 0, 0 };
    for (long k = 0; k < MAX_STEPS && count_done(&log) == 0; k++) {
        double q[LS_N_JOINTS], qd[LS_N_JOINTS], T[16], d[3];
        mt_step(&g_m, q, qd, &log);
        tip_of(q, T);
        rot_between(prev, T, d);
        memcpy(prev, T, sizeof prev);
        memmove(w[1], w[0], 2 * sizeof w[0]);
        double al[3], je[3];
        for (int i = 0; i < 3; i++) {
            w[0][i] = d[i] / DT_S;
            al[i] = (w[0][i] - w[1][i]) / DT_S;
            je[i] = (w[0][i] - 2.0 * w[1][i] + w[2][i]) / (DT_S * DT_S);
        }
        peak[0] = fmax(peak[0], dist3(w[0], zero));
        peak[1] = fmax(peak[1], dist3(al, zero));
        peak[2] = fmax(peak[2], dist3(je, zero));
    }
    assert_int_equal(count_kind_tags(&log), 2);
    if (peak[0] > lim.v_ang_rad_s * 1.001 || peak[1] > lim.a_ang_rad_s2 * 1.001 || peak[2] > lim.j_ang_rad_s3 * 1.001) {
        fail_msg("angular peaks %.6g rad/s, %.6g rad/s^2, %.6g rad/s^3 above %.6g, %.6g, %.6g", peak[0], peak[1],
                 peak[2], lim.v_ang_rad_s, lim.a_ang_rad_s2, lim.j_ang_rad_s3);
    }
}

/* Joint into joint: each joint within its velocity, acceleration and jerk
 * limits, joint 1 continuing and joint 3 reversing through the points. */
/* Three joint moves (joints 1 and 3) blended through their first two points. */
static void make_joint_blend_path(void)
{
    char why[128];
    memset(&g_prog, 0, sizeof g_prog);
    double q_prev[LS_N_JOINTS];
    memcpy(q_prev, mt_q_home, sizeof q_prev);
    const double d1[3] = { 0.5, 0.4, 0.6 }, d3[3] = { 0.4, -0.5, 0.3 };
    for (int k = 0; k < 3; k++) {
        double q[LS_N_JOINTS];
        memcpy(q, q_prev, sizeof q);
        q[0] += d1[k];
        q[2] += d3[k];
        ls_motion_seg_t *s = &g_prog.seg[k];
        snprintf(s->tag, sizeof s->tag, "J%d", k);
        s->point = k;
        s->blend_frac = k < 2 ? 1.0 : 0.0;
        assert_int_equal(ls_motion_seg_joint(s, M, q_prev, q, 1.0, 1.0, why, sizeof why), 0);
        memcpy(q_prev, q, sizeof q_prev);
    }
    g_prog.n = 3;
    assert_int_equal(ls_motion_prog_blend(&g_prog, M, 1, why, sizeof why), 0);
}

static void test_joint_blend_within_joint_limits(void **state)
{
    (void)state;
    make_joint_blend_path();
    assert_true(isnan(ls_motion_seg_blend_dev_m(&g_prog.seg[0], &g_prog.seg[1])));
    assert_true(g_prog.seg[0].jerk_scale_[0] == 0.5 && g_prog.seg[0].jerk_scale_[2] == 1.0);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "j"), 0);
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    double h[4][LS_N_JOINTS];
    for (int i = 0; i < 4; i++) {
        memcpy(h[i], mt_q_home, sizeof h[i]);
    }
    ev_log_t log = { .n = 0 };
    double min_speed = INFINITY;
    int tags = 0;
    long k = 0;
    for (; k < MAX_STEPS && log.n < 4; k++) {
        double q[LS_N_JOINTS], qd[LS_N_JOINTS];
        const int before = log.n;
        mt_step(&g_m, q, qd, &log);
        memmove(h[1], h[0], 3 * sizeof h[0]);
        memcpy(h[0], q, sizeof h[0]);
        for (int j = 0; j < LS_N_JOINTS; j++) {
            const double v = (h[0][j] - h[1][j]) / DT_S;
            const double a = (h[0][j] - 2.0 * h[1][j] + h[2][j]) / (DT_S * DT_S);
            const double jk = (h[0][j] - 3.0 * h[1][j] + 3.0 * h[2][j] - h[3][j]) / (DT_S * DT_S * DT_S);
            assert_true(fabs(v) <= M->qd_max_rad_s[j] * (1.0 + 1e-6));
            assert_true(fabs(a) <= M->qdd_max_rad_s2[j] * (1.0 + 1e-6));
            if (fabs(jk) > M->qddd_max_rad_s3[j] * (1.0 + 1e-6)) {
                fail_msg("joint %d: jerk %.6g above %.6g at cycle %ld", j + 1, jk, M->qddd_max_rad_s3[j], k);
            }
        }
        for (int e = before; e < log.n; e++) {
            tags += log.ev[e].kind == LS_MEV_TAG;
        }
        if (tags >= 1 && !(g_m.seg_i_ == 2 && g_m.t_s > ls_motion_seg_duration_s(&g_prog.seg[2]) / 2) && log.n < 4) {
            min_speed = fmin(min_speed, fabs(qd[0]));
        }
    }
    assert_int_equal(tags, 3);
    assert_int_equal(log.ev[3].kind, LS_MEV_DONE);
    assert_true(min_speed > 0.01); /* joint 1 never stops on the way */
    assert_memory_equal(g_m.q_cmd, g_prog.seg[2].q1, sizeof g_m.q_cmd);
}

/* What a run with a stop and a resume measured from the set-points. */
typedef struct {
    double tip_j, tip_a;                         /* peaks of the tool tip's jerk and acceleration */
    double joint_j_ratio;                        /* the largest |joint jerk| / the joint's jerk limit */
    double q_lo[LS_N_JOINTS], q_hi[LS_N_JOINTS]; /* the set-points' range per joint */
    bool stopped_blending;                       /* the stop came while two segments overlapped */
    long stop_cycles;                            /* from the stop to the pause */
    int paused, tags, done;
} stop_run_t;

/* Run g_plan from home; `at_ms` cycles into blend number `blend` (1 = the
 * first corner) stop (fast: ls_motion_stop_fast), hold 50 cycles paused,
 * resume and run to the end. Jerks by third differences of the set-points
 * (a weighted mean of the true jerk over three cycles, never above its
 * peak), including the cycles where the stop and the resume begin. */
static stop_run_t run_stopping_in_blend(int blend, long at_ms, bool fast)
{
    stop_run_t r = { 0 };
    for (int j = 0; j < LS_N_JOINTS; j++) {
        r.q_lo[j] = r.q_hi[j] = mt_q_home[j];
    }
    ls_motion_init(&g_m, M);
    ls_motion_hold(&g_m, mt_q_home);
    assert_int_equal(ls_motion_start(&g_m, &g_plan), 0);
    double h[4][LS_N_JOINTS], p[4][3], P[16];
    tip_of(mt_q_home, P);
    for (int i = 0; i < 4; i++) {
        memcpy(h[i], mt_q_home, sizeof h[i]);
        memcpy(p[i], P + 12, sizeof p[i]);
    }
    ev_log_t log = { .n = 0 };
    int blends = 0;
    long in_blend = -1, paused_for = 0, stop_at = -1;
    bool was_blending = false;
    for (long k = 0; k < MAX_STEPS && r.done == 0; k++) {
        double q[LS_N_JOINTS], qd[LS_N_JOINTS];
        const int before = log.n;
        mt_step(&g_m, q, qd, &log);
        memmove(h[1], h[0], 3 * sizeof h[0]);
        memcpy(h[0], q, sizeof h[0]);
        for (int j = 0; j < LS_N_JOINTS; j++) {
            r.q_lo[j] = fmin(r.q_lo[j], q[j]);
            r.q_hi[j] = fmax(r.q_hi[j], q[j]);
        }
        tip_of(q, P);
        memmove(p[1], p[0], 3 * sizeof p[0]);
        memcpy(p[0], P + 12, sizeof p[0]);
        if (k >= 3) {
            for (int j = 0; j < LS_N_JOINTS; j++) {
                const double jk = (h[0][j] - 3.0 * h[1][j] + 3.0 * h[2][j] - h[3][j]) / (DT_S * DT_S * DT_S);
                r.joint_j_ratio = fmax(r.joint_j_ratio, fabs(jk) / M->qddd_max_rad_s3[j]);
            }
            double a[3], j3[3];
            const double zero[3] = { 0, 0, 0 };
            for (int i = 0; i < 3; i++) {
                a[i] = (p[0][i] - 2.0 * p[1][i] + p[2][i]) / (DT_S * DT_S);
                j3[i] = (p[0][i] - 3.0 * p[1][i] + 3.0 * p[2][i] - p[3][i]) / (DT_S * DT_S * DT_S);
            }
            r.tip_a = fmax(r.tip_a, dist3(a, zero));
            r.tip_j = fmax(r.tip_j, dist3(j3, zero));
        }
        for (int e = before; e < log.n; e++) {
            r.tags += log.ev[e].kind == LS_MEV_TAG;
            r.paused += log.ev[e].kind == LS_MEV_PAUSED;
            if (log.ev[e].kind == LS_MEV_PAUSED && stop_at >= 0) {
                r.stop_cycles = k - stop_at;
            }
            r.done += log.ev[e].kind == LS_MEV_DONE;
            assert_true(log.ev[e].kind != LS_MEV_FAULT);
        }
        if (log.n > MAX_LOG - 8) {
            log.n = 0; /* counted above */
        }
        blends += g_m.blending_ && !was_blending;
        was_blending = g_m.blending_;
        if (blends == blend && in_blend < 0) {
            in_blend = 0;
        }
        if (in_blend >= 0 && g_m.phase == LS_MOTION_RUNNING && r.paused == 0 && in_blend++ == at_ms) {
            r.stopped_blending = g_m.blending_;
            stop_at = k;
            if (fast) {
                ls_motion_stop_fast(&g_m);
            } else {
                ls_motion_stop(&g_m);
            }
        }
        if (g_m.phase == LS_MOTION_PAUSED && paused_for++ == 50) {
            assert_int_equal(ls_motion_resume(&g_m), 0);
        }
    }
    return r;
}

/* A stop while two segments blend, early, midway and late in the blend:
 * both come to rest each on its own ramp at half its limits, so the sum
 * keeps the jerk limit (the tool's for lines, every joint's for joints),
 * the arm pauses once, and the resume finishes the path through every point
 * with the jerk limit kept too. */
static void test_stop_while_blending_keeps_the_jerk_limit(void **state)
{
    (void)state;
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    const double fracs[3] = { 0.1, 0.5, 0.9 };
    for (int f = 0; f < 3; f++) {
        make_zigzag(4, 1.0, -1, 1.0);
        const long at_ms = (long)(fracs[f] * g_prog.seg[1].overlap_s / DT_S);
        for (int fast = 0; fast < 2; fast++) {
            const stop_run_t r = run_stopping_in_blend(2, at_ms, fast != 0);
            const double j_lim = fast ? M->max_linear_jerk_m_s3 : lim.j_lin_m_s3;
            print_message("lines, stop %s %.0f %% into the blend: tip jerk %.4g m/s^3 (limit %.4g), accel %.4g\n",
                          fast ? "fast" : "", 100.0 * fracs[f], r.tip_j, j_lim, r.tip_a);
            assert_true(r.stopped_blending);
            assert_int_equal(r.paused, 1);
            assert_int_equal(r.tags, 4);
            assert_int_equal(r.done, 1);
            assert_true(r.tip_j <= j_lim * (1.0 + 1e-6));
            assert_memory_equal(g_m.q_cmd, g_prog.seg[3].q1, sizeof g_m.q_cmd);
        }
        make_joint_blend_path();
        assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "j"), 0);
        const long at_j = (long)(fracs[f] * g_prog.seg[0].overlap_s / DT_S);
        for (int fast = 0; fast < 2; fast++) {
            const stop_run_t r = run_stopping_in_blend(1, at_j, fast != 0);
            print_message("joints, stop %s %.0f %% into the blend: joint jerk %.4g of the limit\n", fast ? "fast" : "",
                          100.0 * fracs[f], r.joint_j_ratio);
            assert_true(r.stopped_blending);
            assert_int_equal(r.paused, 1);
            assert_int_equal(r.tags, 3);
            assert_int_equal(r.done, 1);
            assert_true(r.joint_j_ratio <= 1.0 + 1e-6);
            assert_memory_equal(g_m.q_cmd, g_prog.seg[2].q1, sizeof g_m.q_cmd);
        }
    }
}

/* Joint 1 out by the longest distance its profile covers in jerk phases
 * alone (2 A^3 / J^2 at the full limits) and back, blended at the turn: the
 * segment blending in is planned at the full jerk (joint 1 reverses, so its
 * jerk scale is 1). A stop late in the blend cannot bring it to rest at half
 * that jerk before its end; the stop waits for the blend to end and then
 * stops that segment alone at its own limits. Joint 1 never leaves the range
 * of the path, the jerk stays within the limit, the stop pauses once and
 * the path ends where it should. */
static void test_a_stop_late_in_a_blend_into_a_short_segment_stays_on_the_path(void **state)
{
    (void)state;
    char why[128];
    const double a = M->qdd_max_rad_s2[0], J = M->qddd_max_rad_s3[0];
    const double out = 2.0 * a * a * a / (J * J);
    double q1[LS_N_JOINTS];
    memcpy(q1, mt_q_home, sizeof q1);
    q1[0] += out;
    const double fracs[4] = { 0.5, 0.9, 0.97, 1.0 };
    for (int f = 0; f < 4; f++) {
        for (int fast = 0; fast < 2; fast++) {
            memset(&g_prog, 0, sizeof g_prog);
            g_prog.seg[0].blend_frac = 1.0;
            snprintf(g_prog.seg[0].tag, sizeof g_prog.seg[0].tag, "OUT");
            snprintf(g_prog.seg[1].tag, sizeof g_prog.seg[1].tag, "BACK");
            assert_int_equal(ls_motion_seg_joint(&g_prog.seg[0], M, mt_q_home, q1, 1.0, 1.0, why, sizeof why), 0);
            assert_int_equal(ls_motion_seg_joint(&g_prog.seg[1], M, q1, mt_q_home, 1.0, 1.0, why, sizeof why), 0);
            g_prog.n = 2;
            assert_int_equal(ls_motion_prog_blend(&g_prog, M, 1, why, sizeof why), 0);
            assert_true(g_prog.seg[1].jerk_scale_[0] == 1.0 && g_prog.seg[0].overlap_s > 0.1);
            assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 1, false, "out"), 0);
            const long at = (long)(fracs[f] * g_prog.seg[0].overlap_s / DT_S) - 1;
            const stop_run_t r = run_stopping_in_blend(1, at, fast != 0);
            double bound_s, bound_rad;
            assert_int_equal(ls_motion_fast_stop_bound(M, 0, &bound_s, &bound_rad), 0);
            print_message("out and back, stop%s %.0f %% into the blend: joint 1 in [%.6f, %.6f] of [%.6f, %.6f], "
                          "jerk %.4f of the limit, %ld ms to the pause (bound %.0f ms)\n",
                          fast ? " fast" : "", 100.0 * fracs[f], r.q_lo[0], r.q_hi[0], mt_q_home[0], q1[0],
                          r.joint_j_ratio, r.stop_cycles, 1e3 * bound_s);
            assert_true((double)r.stop_cycles * DT_S <= bound_s);
            assert_true(r.q_lo[0] >= mt_q_home[0] - 1e-9 && r.q_hi[0] <= q1[0] + 1e-9);
            assert_true(r.joint_j_ratio <= 1.0 + 1e-6);
            assert_int_equal(r.paused, 1);
            assert_int_equal(r.tags, 2);
            assert_int_equal(r.done, 1);
            assert_memory_equal(g_m.q_cmd, mt_q_home, sizeof g_m.q_cmd);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_blend_maths_of_a_corner),
        cmocka_unit_test(test_blended_zigzag_within_bound_and_limits),
        cmocka_unit_test(test_line_accel_changes_its_duration),
        cmocka_unit_test(test_blended_lines_over_two_cycles),
        cmocka_unit_test(test_turning_lines_blend_within_angular_limits),
        cmocka_unit_test(test_joint_blend_within_joint_limits),
        cmocka_unit_test(test_stop_while_blending_keeps_the_jerk_limit),
        cmocka_unit_test(test_a_stop_late_in_a_blend_into_a_short_segment_stays_on_the_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
