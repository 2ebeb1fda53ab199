/* bench_pathspeed: one Cartesian move planned by the firmware's planner and
 * run by the motion executor with an ideal arm at 1 ms, for the comparison
 * with toppra (bench/b_pathspeed.py).
 *
 * usage: bench_pathspeed line|arc Q1..Q6 DX DY DZ [VX VY VZ] SPEED_PCT ACCEL_PCT [STOP_S]
 *   from the flange at joints Q (no tool offset) to the flange moved by
 *   (DX, DY, DZ) m in the base frame, orientation kept; an arc passes the
 *   flange moved by (VX, VY, VZ). The Cartesian limits are SPEED_PCT and
 *   ACCEL_PCT of the model's maxima (as ls_mcmd_cart_limits makes them).
 *   STOP_S: stopMotion that long after the start, resume once paused.
 * stdout:
 *   PLAN <status> <duration_s> <requested_s> <ns per plan> <zones>
 *   WHY <refusal>               (status < 0; nothing else follows)
 *   SLOW <ls_motion_seg_slowdown's text>   (when it is slowed)
 *   CART <length_m> <turn_rad> <v_lin> <a_lin> <v_ang> <a_ang>
 *   PATH <s> <q1> .. <q6>       (1001 points of the joint path, s = 0 .. 1)
 *   RUN <duration_s> <qd_ratio> <qdd_ratio> <paused 0|1>
 *     qd_ratio, qdd_ratio: the largest joint speed and acceleration (first
 *     and second differences of the 1 ms set-points) over the joint's limit.
 * Exit 1 when the run fails, 2 on bad arguments. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cart_limits.h"
#include "ls_kin.h"
#include "ls_motion.h"

#define DT_S 1e-3
#define REPEAT 20
#define PATH_POINTS 1000
#define MAX_STEPS 2000000L

static ls_motion_plan_t plan;
static ls_motion_t motion;

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

/* The flange pose of the planned segment at s (as the executor has it). */
static void pose_at(const ls_motion_seg_t *s, double x, double T[16])
{
    ls_pose_interp(s->P0, s->P1, x, T);
    if (s->kind == LS_SEG_ARC) {
        const double a = s->angle_rad * x;
        for (int i = 0; i < 3; i++) {
            T[12 + i] = s->centre_m[i] + s->radius_m * (cos(a) * s->u[i] + sin(a) * s->v[i]);
        }
    }
}

static int run(const ls_robot_model_t *m, const double q0[LS_N_JOINTS], double stop_s)
{
    ls_motion_init(&motion, m);
    ls_motion_hold(&motion, q0);
    if (ls_motion_start(&motion, &plan) != 0) {
        printf("ERR ls_motion_start refused the plan\n");
        return 1;
    }
    double qh[3][LS_N_JOINTS], qd_ratio = 0.0, qdd_ratio = 0.0;
    for (int h = 0; h < 3; h++) {
        memcpy(qh[h], q0, sizeof qh[h]);
    }
    bool done = false, paused = false;
    long steps = 0;
    while (!done && steps < MAX_STEPS) {
        if (stop_s > 0.0 && steps == (long)lround(stop_s / DT_S)) {
            ls_motion_stop(&motion);
        }
        ls_motion_events_t ev = { .n = 0 };
        double q[LS_N_JOINTS], qd[LS_N_JOINTS];
        ls_motion_step(&motion, DT_S, motion.q_cmd, q, qd, &ev);
        steps++;
        for (int e = 0; e < ev.n; e++) {
            done |= ev.ev[e].kind == LS_MEV_DONE;
            if (ev.ev[e].kind == LS_MEV_PAUSED) {
                paused = true;
                if (ls_motion_resume(&motion) != 0) {
                    printf("ERR the resume was refused\n");
                    return 1;
                }
            }
            if (ev.ev[e].kind == LS_MEV_FAULT) {
                printf("ERR fault: %s\n", ev.ev[e].text);
                return 1;
            }
        }
        memmove(qh[1], qh[0], 2 * sizeof qh[0]);
        memcpy(qh[0], q, sizeof qh[0]);
        for (int j = 0; j < LS_N_JOINTS; j++) {
            qd_ratio = fmax(qd_ratio, fabs(qh[0][j] - qh[1][j]) / DT_S / m->qd_max_rad_s[j]);
            if (steps >= 2) {
                qdd_ratio =
                    fmax(qdd_ratio, fabs(qh[0][j] - 2.0 * qh[1][j] + qh[2][j]) / (DT_S * DT_S) / m->qdd_max_rad_s2[j]);
            }
        }
    }
    if (!done) {
        printf("ERR the move did not finish within %ld cycles\n", MAX_STEPS);
        return 1;
    }
    printf("RUN %.6f %.9f %.9f %d\n", (double)steps * DT_S, qd_ratio, qdd_ratio, paused ? 1 : 0);
    return 0;
}

int main(int argc, char **argv)
{
    const bool arc = argc > 1 && strcmp(argv[1], "arc") == 0;
    const int want = arc ? 16 : 13;
    if (argc < 2 || (!arc && strcmp(argv[1], "line") != 0) || (argc != want && argc != want + 1)) {
        fprintf(stderr, "usage: bench_pathspeed line|arc Q1..Q6 DX DY DZ [VX VY VZ] SPEED_PCT ACCEL_PCT [STOP_S]\n");
        return 2;
    }
    double q0[LS_N_JOINTS], d[3], via[3] = { 0, 0, 0 };
    for (int j = 0; j < LS_N_JOINTS; j++) {
        q0[j] = atof(argv[2 + j]);
    }
    for (int i = 0; i < 3; i++) {
        d[i] = atof(argv[8 + i]);
        via[i] = arc ? atof(argv[11 + i]) : 0.0;
    }
    const double sp = atof(argv[want - 2]) / 100.0, ap = atof(argv[want - 1]) / 100.0;
    const double stop_s = argc == want + 1 ? atof(argv[want]) : 0.0;
    if (!(sp > 0.0 && sp <= 1.0) || !(ap > 0.0 && ap <= 1.0)) {
        fprintf(stderr, "bench_pathspeed: percents in (0, 100]\n");
        return 2;
    }
    const ls_robot_model_t *m = &ls_robot_model_default;
    const ls_motion_cart_limits_t lim = bench_cart_limits(m, sp, ap);
    static const double tool[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    double P0[16], P1[16], Pv[16];
    ls_kin_fk(m, q0, P0);
    memcpy(P1, P0, sizeof P1);
    memcpy(Pv, P0, sizeof Pv);
    for (int i = 0; i < 3; i++) {
        P1[12 + i] += d[i];
        Pv[12 + i] += via[i];
    }
    char why[LS_MOTION_WHY_LEN];
    int st = 0;
    const double t0 = now_ns();
    for (int r = 0; r < REPEAT; r++) {
        st = arc ? ls_motion_plan_arc(&plan, m, q0, tool, Pv, P1, &lim, why, sizeof why)
                 : ls_motion_plan_line(&plan, m, q0, tool, P1, &lim, why, sizeof why);
    }
    const double ns = (now_ns() - t0) / REPEAT;
    const ls_motion_seg_t *s = &plan.one;
    if (st < 0) {
        printf("PLAN %d 0 0 %.0f 0\nWHY %s\n", st, ns, why);
        return 0;
    }
    ls_traj_axis_t plain;
    (void)ls_traj_plan_axis(&plain, 0.0, 1.0, s->lim_[0], s->lim_[1], s->lim_[2]);
    printf("PLAN %d %.6f %.6f %.0f %d\n", st, ls_motion_seg_duration_s(s), plain.T, ns, s->curve.n);
    char text[LS_MOTION_WHY_LEN];
    ls_motion_slowdown_t slow;
    if (ls_motion_seg_slowdown(s, &slow) && ls_motion_slowdown_text(&slow, text, sizeof text) >= 0) {
        printf("SLOW %s\n", text);
    }
    printf("CART %.9f %.9f %.9f %.9f %.9f %.9f\n", s->length_m, s->turn_rad, lim.v_lin_m_s, lim.a_lin_m_s2,
           lim.v_ang_rad_s, lim.a_ang_rad_s2);
    double q[LS_N_JOINTS];
    memcpy(q, q0, sizeof q);
    for (int k = 0; k <= PATH_POINTS; k++) {
        const double x = (double)k / PATH_POINTS;
        double T[16];
        pose_at(s, x, T);
        if (ls_kin_ik_nearest(m, T, q, q) != LS_OK) {
            printf("ERR no joint solution at s = %g\n", x);
            return 1;
        }
        printf("PATH %.6f %.12f %.12f %.12f %.12f %.12f %.12f\n", x, q[0], q[1], q[2], q[3], q[4], q[5]);
    }
    return run(m, q0, stop_s);
}
