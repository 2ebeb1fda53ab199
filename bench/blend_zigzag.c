/* bench_blend: a Cartesian zig-zag path run by the motion executor with an
 * ideal arm at 1 ms, blended or not (bench/b_blend.py).
 *
 * usage: bench_blend N STEP_M ZIG_M SPEED_PCT ACCEL_PCT TRANSITION_PCT
 *   N straight-line points from the tool tip at q = (0, 0.3, 0.3, 0, 0.9, 0)
 *   (no tool offset): point k at (+ZIG_M for even k, STEP_M (k + 1), 0) from
 *   the start, same orientation, each with the Cartesian limits of SPEED_PCT
 *   and ACCEL_PCT of the model's maxima (as ls_mcmd_cart_limits makes them)
 *   and transitionSpeed TRANSITION_PCT (the last point stops). Planned as
 *   the firmware's program builder does (ls_motion_seg_line per point, then
 *   ls_motion_prog_blend), run until LS_MEV_DONE.
 * stdout, one line:
 *   OK duration_s miss_m off_m bound_m v_ratio a_ratio j_ratio qd_ratio min_speed_m_s tags
 *   miss_m: the largest, over the points passed (all but the last), of the
 *     tip's closest approach to the point;
 *   off_m: the largest distance of the tip from the polyline;
 *   bound_m: the largest documented bound (ls_motion_seg_blend_dev_m);
 *   v/a/j_ratio: the tip's peak speed, acceleration and jerk (finite
 *     differences of the 1 ms set-points) over the limits in use;
 *   qd_ratio: the largest joint speed over its limit;
 *   min_speed_m_s: the lowest tip speed from passing point 0 until the last
 *     segment's second half (where it brakes for the last point).
 * or "ERR <why>" and exit 1. Exit 2 on bad arguments. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cart_limits.h"
#include "ls_kin.h"
#include "ls_motion.h"

#define DT_S 1e-3
#define MAX_POINTS 64
#define MAX_STEPS 2000000L

static ls_motion_program_t prog;
static ls_motion_plan_t plan;
static ls_motion_t motion;
static double corner[MAX_POINTS + 1][3];

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static double dist_to_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], c[3];
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
    }
    double t = (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / (ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]);
    t = fmin(1.0, fmax(0.0, t));
    for (int i = 0; i < 3; i++) {
        c[i] = a[i] + t * ab[i];
    }
    return dist3(p, c);
}

static int plan_zigzag(const ls_robot_model_t *m, int n, double step, double zig, const ls_motion_cart_limits_t *lim,
                       double frac, const double q_home[LS_N_JOINTS])
{
    static const double tool[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    char why[160];
    double P[16], q_prev[LS_N_JOINTS];
    ls_kin_fk(m, q_home, P);
    memcpy(q_prev, q_home, sizeof q_prev);
    memcpy(corner[0], P + 12, sizeof corner[0]);
    for (int k = 0; k < n; k++) {
        double T[16];
        memcpy(T, P, sizeof T);
        T[12] += k % 2 == 0 ? zig : 0.0;
        T[13] += step * (k + 1);
        ls_motion_seg_t *s = &prog.seg[k];
        memset(s, 0, sizeof *s);
        snprintf(s->tag, sizeof s->tag, "Z%d", k);
        s->point = k;
        s->tag_index = k;
        s->blend_frac = k + 1 < n ? frac : 0.0;
        if (ls_motion_seg_line(s, m, q_prev, tool, T, lim, why, sizeof why) != 0) {
            printf("ERR point %d: %s\n", k, why);
            return LS_EINVAL;
        }
        memcpy(q_prev, s->q1, sizeof q_prev);
        memcpy(corner[k + 1], T + 12, sizeof corner[k + 1]);
    }
    prog.n = (uint16_t)n;
    if (ls_motion_prog_blend(&prog, m, 1, why, sizeof why) != 0 ||
        ls_motion_plan_path(&plan, &prog, 1, false, "zigzag") != 0) {
        printf("ERR %s\n", why);
        return LS_EINVAL;
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 7) {
        fprintf(stderr, "usage: bench_blend N STEP_M ZIG_M SPEED_PCT ACCEL_PCT TRANSITION_PCT\n");
        return 2;
    }
    const int n = atoi(argv[1]);
    const double step = atof(argv[2]), zig = atof(argv[3]), sp = atof(argv[4]) / 100.0, ap = atof(argv[5]) / 100.0;
    const double frac = atof(argv[6]) / 100.0;
    if (n < 2 || n > MAX_POINTS || !(sp > 0.0 && sp <= 1.0) || !(ap > 0.0 && ap <= 1.0) || !(frac >= 0.0) ||
        frac > 1.0) {
        fprintf(stderr, "bench_blend: N in 2..%d, percents in (0, 100] (transition [0, 100])\n", MAX_POINTS);
        return 2;
    }
    const ls_robot_model_t *m = &ls_robot_model_default;
    const ls_motion_cart_limits_t lim = bench_cart_limits(m, sp, ap);
    const double q_home[LS_N_JOINTS] = { 0.0, 0.3, 0.3, 0.0, 0.9, 0.0 };
    if (plan_zigzag(m, n, step, zig, &lim, frac, q_home) != 0) {
        return 1;
    }
    double bound = 0.0, miss[MAX_POINTS];
    for (int k = 0; k + 1 < n; k++) {
        bound = fmax(bound, ls_motion_seg_blend_dev_m(&prog.seg[k], &prog.seg[k + 1]));
        miss[k] = INFINITY;
    }
    ls_motion_init(&motion, m);
    ls_motion_hold(&motion, q_home);
    if (ls_motion_start(&motion, &plan) != 0) {
        printf("ERR ls_motion_start refused the plan\n");
        return 1;
    }
    double p[4][3], qh[2][LS_N_JOINTS];
    for (int h = 0; h < 4; h++) {
        memcpy(p[h], corner[0], sizeof p[h]);
    }
    memcpy(qh[0], q_home, sizeof qh[0]);
    double v_pk = 0, a_pk = 0, j_pk = 0, qd_ratio = 0, off = 0, min_speed = INFINITY;
    int tags = 0;
    bool done = false;
    long steps = 0;
    while (!done && steps < MAX_STEPS) {
        ls_motion_events_t ev = { .n = 0 };
        double q[LS_N_JOINTS], qd[LS_N_JOINTS], F[16];
        ls_motion_step(&motion, DT_S, motion.q_cmd, q, qd, &ev);
        steps++;
        for (int e = 0; e < ev.n; e++) {
            tags += ev.ev[e].kind == LS_MEV_TAG;
            done |= ev.ev[e].kind == LS_MEV_DONE;
            if (ev.ev[e].kind == LS_MEV_FAULT) {
                printf("ERR fault: %s\n", ev.ev[e].text);
                return 1;
            }
        }
        ls_kin_fk(m, q, F);
        memmove(p[1], p[0], 3 * sizeof p[0]);
        memcpy(p[0], F + 12, sizeof p[0]);
        double v[3], a[3], j[3];
        const double zero[3] = { 0, 0, 0 };
        for (int i = 0; i < 3; i++) {
            v[i] = (p[0][i] - p[1][i]) / DT_S;
            a[i] = (p[0][i] - 2.0 * p[1][i] + p[2][i]) / (DT_S * DT_S);
            j[i] = (p[0][i] - 3.0 * p[1][i] + 3.0 * p[2][i] - p[3][i]) / (DT_S * DT_S * DT_S);
        }
        v_pk = fmax(v_pk, dist3(v, zero));
        a_pk = fmax(a_pk, dist3(a, zero));
        j_pk = fmax(j_pk, dist3(j, zero));
        memcpy(qh[1], qh[0], sizeof qh[1]);
        memcpy(qh[0], q, sizeof qh[0]);
        for (int jn = 0; jn < LS_N_JOINTS; jn++) {
            qd_ratio = fmax(qd_ratio, fabs(qh[0][jn] - qh[1][jn]) / DT_S / m->qd_max_rad_s[jn]);
        }
        const bool braking = motion.seg_i_ == n - 1 && motion.t_s > ls_motion_seg_duration_s(&prog.seg[n - 1]) / 2;
        if (tags > 0 && !braking && !done) {
            min_speed = fmin(min_speed, dist3(v, zero));
        }
        double d = INFINITY;
        for (int k = 0; k < n; k++) {
            d = fmin(d, dist_to_segment(p[0], corner[k], corner[k + 1]));
        }
        off = fmax(off, d);
        for (int k = 0; k + 1 < n; k++) {
            miss[k] = fmin(miss[k], dist3(p[0], corner[k + 1]));
        }
    }
    if (!done) {
        printf("ERR the path did not finish within %ld cycles\n", MAX_STEPS);
        return 1;
    }
    double miss_max = 0.0;
    for (int k = 0; k + 1 < n; k++) {
        miss_max = fmax(miss_max, miss[k]);
    }
    printf("OK %.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.6f %d\n", (double)steps * DT_S, miss_max, off, bound,
           v_pk / lim.v_lin_m_s, a_pk / lim.a_lin_m_s2, j_pk / lim.j_lin_m_s3, qd_ratio, min_speed, tags);
    return 0;
}
