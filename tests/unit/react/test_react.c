/* ls_react without the simulation: the arm is ideal (the measured joints are
 * the set-point), one cycle is 1 ms, and the sensors are synthetic: a wall
 * across the direction of travel that pushes back like a spring (contact
 * stiffness of hal/sim, 5e4 N/m), and a laser that measures the distance to
 * it. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_react.h"

#define DT_S 1e-3
#define K_N_M 5e4

static const ls_robot_model_t *M = &ls_robot_model_default;
/* The tool points down over the table (flange z about -z of the base). */
static const double Q0[LS_N_JOINTS] = { -0.2, 0.8, 0.45, 0.0, 0.3, 0.0 };

static void assert_near(double got, double want, double tol, int line)
{
    if (!(fabs(got - want) <= tol)) {
        fail_msg("line %d: got %.17g, want %.17g (tolerance %.3g)", line, got, want, tol);
    }
}
#define assert_double_equal(got, want, tol) assert_near((got), (want), (tol), __LINE__)

static void identity(double T[16])
{
    const double z[6] = { 0 };
    ls_pose_from_xyzrpy(z, T);
}

static void tip(const double q[LS_N_JOINTS], const double tool[16], double P[16])
{
    double F[16];
    ls_kin_fk(M, q, F);
    ls_pose_mul(F, tool, P);
}

/* Distance the tip has moved along the unit base-frame vector u since P0. */
static double along(const double P0[16], const double P[16], const double u[3])
{
    return (P[12] - P0[12]) * u[0] + (P[13] - P0[13]) * u[1] + (P[14] - P0[14]) * u[2];
}

typedef struct {
    double P0[16];
    double u[3];    /* base-frame direction the wall faces (travel direction) */
    double wall_m;  /* the wall is this far from P0 along u */
    double spike_N; /* added to the force on one cycle (0: none) */
    long spike_at;
} world_t;

/* Force/torque reading in the tool frame (Fz along the tool z = u here):
 * a spring that pushes back when the tip is beyond the wall. */
static void read_force(const world_t *w, const double q[LS_N_JOINTS], const double tool[16], long cycle, double out[6])
{
    double P[16];
    tip(q, tool, P);
    double pen = along(w->P0, P, w->u) - w->wall_m;
    memset(out, 0, 6 * sizeof out[0]);
    out[2] = pen > 0.0 ? K_N_M * pen : 0.0;
    if (w->spike_N != 0.0 && cycle == w->spike_at) {
        out[2] += w->spike_N;
    }
}

static void base_z_of_tool(const double q[LS_N_JOINTS], const double tool[16], double u[3])
{
    double P[16];
    tip(q, tool, P);
    u[0] = P[8], u[1] = P[9], u[2] = P[10];
}

static void guarded_plan(ls_react_plan_t *p, double dist_m, double v_m_s, double threshold)
{
    memset(p, 0, sizeof *p);
    p->kind = LS_REACT_GUARDED;
    p->ref_seq = 42;
    snprintf(p->sensor, sizeof p->sensor, "force_sensor");
    identity(p->tool);
    p->dir_tool[2] = 1.0;
    p->dist_m = dist_m;
    p->v_m_s = v_m_s;
    p->a_m_s2 = 1.0;
    p->j_m_s3 = 10.0;
    p->a_stop_m_s2 = 4.0;
    p->j_stop_m_s3 = 40.0;
    p->component = 2;
    p->threshold = threshold;
}

typedef struct {
    ls_motion_event_t last;
    int n_end, n_paused, n_fault, n_jog;
} log_t;

static void collect(log_t *log, const ls_motion_events_t *ev)
{
    for (uint8_t i = 0; i < ev->n; i++) {
        log->last = ev->ev[i];
        log->n_end += ev->ev[i].kind == LS_MEV_REACT_END;
        log->n_paused += ev->ev[i].kind == LS_MEV_PAUSED;
        log->n_fault += ev->ev[i].kind == LS_MEV_FAULT;
        log->n_jog += ev->ev[i].kind == LS_MEV_JOG;
    }
}

/* Push the tip position of P into the history h (newest first) and return
 * the norm of its third difference: the tip's jerk over the last 3 cycles. */
static double push_tip_jerk(double h[4][3], const double P[16])
{
    memmove(h[1], h[0], 3 * sizeof h[0]);
    memcpy(h[0], P + 12, sizeof h[0]);
    double j2 = 0.0;
    for (int k = 0; k < 3; k++) {
        const double jk = (h[0][k] - 3.0 * h[1][k] + 3.0 * h[2][k] - h[3][k]) / (DT_S * DT_S * DT_S);
        j2 += jk * jk;
    }
    return sqrt(j2);
}

/* The largest tool-tip jerk of the last run() (third differences of the
 * tip's position, each a weighted mean of the true jerk over three cycles). */
static double g_max_tip_jerk;

/* Run the move against the world until it ends (or max cycles); returns cycles. */
static long run(ls_react_t *r, world_t *w, double q[LS_N_JOINTS], log_t *log, long max_cycles, double *max_pen_m)
{
    double qd[LS_N_JOINTS], reading[6], h[4][3];
    double P[16];
    tip(q, r->plan.tool, P);
    for (int k = 0; k < 4; k++) {
        memcpy(h[k], P + 12, sizeof h[k]);
    }
    g_max_tip_jerk = 0.0;
    long i;
    for (i = 0; i < max_cycles && r->active; i++) {
        read_force(w, q, r->plan.tool, i, reading);
        ls_motion_events_t ev = { .n = 0 };
        ls_react_step(r, DT_S, q, reading, q, qd, &ev);
        collect(log, &ev);
        tip(q, r->plan.tool, P);
        g_max_tip_jerk = fmax(g_max_tip_jerk, push_tip_jerk(h, P));
        if (max_pen_m != NULL) {
            double pen = along(w->P0, P, w->u) - w->wall_m;
            *max_pen_m = fmax(*max_pen_m, pen);
        }
    }
    return i;
}

/* How far a jerk-limited brake from v at (a, j) to rest travels. */
static double brake_distance(double v, double a, double j)
{
    ls_ramp_t rp;
    assert_int_equal(ls_ramp_plan(&rp, 0.0, v, 0.0, 0.0, a, j), LS_OK);
    double d;
    ls_ramp_sample(&rp, rp.duration_s, &d, NULL, NULL);
    return d;
}

/* ---------------------------------------------------------------- guarded */

static void test_guarded_stops_at_the_wall_and_comes_back(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    guarded_plan(&p, 0.15, 0.15, 5.0);
    double q[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    world_t w = { .wall_m = 0.08 };
    tip(q, p.tool, w.P0);
    base_z_of_tool(q, p.tool, w.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    log_t log = { 0 };
    double max_pen = -1.0;
    long cycles = run(&r, &w, q, &log, 20000, &max_pen);
    assert_false(r.active);
    assert_int_equal(log.n_end, 1);
    assert_int_equal(log.last.kind, LS_MEV_REACT_END);
    assert_int_equal(log.last.index, LS_REACT_END_THRESHOLD);
    assert_int_equal(log.last.ref_seq, 42);
    /* braking from 0.15 m/s jerk-limited at 4 m/s^2 and 40 m/s^3: 9.2 mm
     * (sqrt(40 x 0.15) = 2.4 m/s^2 peak, 122 ms) plus a cycle of detection;
     * the tip's jerk never beyond the brake's, the travel's (10) below it */
    const double d_brake = brake_distance(0.15, 4.0, 40.0);
    assert_double_equal(d_brake, 0.15 * sqrt(0.15 / 40.0), 1e-12);
    assert_true(max_pen <= d_brake + 2 * 0.15 * DT_S);
    assert_true(max_pen > 0.9 * d_brake);
    assert_true(g_max_tip_jerk <= 40.0 * (1.0 + 1e-6));
    assert_true(g_max_tip_jerk > 30.0);
    /* comes back to where the force crossed 5 N (0.1 mm into the spring) */
    double P[16];
    tip(q, p.tool, P);
    double pen = along(w.P0, P, w.u) - w.wall_m;
    assert_true(pen >= 0.0 && pen <= 5.0 / K_N_M + 0.15 * DT_S);
    assert_true(r.report.triggered);
    assert_true(r.report.trigger >= 5.0);
    assert_double_equal(r.report.travelled_m, w.wall_m + pen, 1e-6);
    assert_double_equal(r.report.reading[2], K_N_M * pen, 1e-6);
    assert_true(cycles < 2000);
}

static void test_guarded_without_contact_stops_at_the_maximum_distance(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    guarded_plan(&p, 0.05, 0.1, 5.0);
    double q[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    world_t w = { .wall_m = 1.0 };
    tip(q, p.tool, w.P0);
    base_z_of_tool(q, p.tool, w.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    log_t log = { 0 };
    run(&r, &w, q, &log, 20000, NULL);
    assert_int_equal(log.n_end, 1);
    assert_int_equal(log.last.index, LS_REACT_END_MAX_DISTANCE);
    assert_false(r.report.triggered);
    double P[16];
    tip(q, p.tool, P);
    assert_double_equal(along(w.P0, P, w.u), 0.05, 1e-9);
    assert_double_equal(ls_pose_angle(w.P0, P), 0.0, 1e-9); /* orientation held */
    assert_double_equal(r.report.travelled_m, 0.05, 1e-12);
}

static void test_guarded_envelope_beats_the_threshold(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    guarded_plan(&p, 0.05, 0.05, 5.0);
    p.envelope = 50.0;
    double q[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    world_t w = { .wall_m = 1.0, .spike_N = 80.0, .spike_at = 100 };
    tip(q, p.tool, w.P0);
    base_z_of_tool(q, p.tool, w.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    log_t log = { 0 };
    run(&r, &w, q, &log, 20000, NULL);
    assert_int_equal(log.last.index, LS_REACT_END_ENVELOPE);
    assert_double_equal(r.report.trigger, 80.0, 1e-12);
}

static void test_guarded_laser_stops_below_its_threshold(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    guarded_plan(&p, 0.1, 0.05, 0.03);
    snprintf(p.sensor, sizeof p.sensor, "laser_standoff_sensor");
    p.component = 0;
    p.below = true;
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    double P0[16], u[3];
    tip(q, p.tool, P0);
    base_z_of_tool(q, p.tool, u);
    assert_int_equal(ls_react_start(&r, &p, q, 1), 0);
    log_t log = { 0 };
    for (int i = 0; i < 20000 && r.active; i++) {
        double P[16];
        tip(q, p.tool, P);
        double d = 0.08 - along(P0, P, u); /* a surface 8 cm ahead */
        ls_motion_events_t ev = { .n = 0 };
        ls_react_step(&r, DT_S, q, &d, q, qd, &ev);
        collect(&log, &ev);
    }
    assert_int_equal(log.last.index, LS_REACT_END_THRESHOLD);
    assert_true(r.report.trigger <= 0.03);
    double P[16];
    tip(q, p.tool, P);
    assert_double_equal(along(P0, P, u), 0.05, 0.05 * DT_S + 1e-9); /* back where it crossed 3 cm */
}

static void test_stop_pauses_resume_continues_abort_ends(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    guarded_plan(&p, 0.1, 0.1, 5.0);
    double q[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    world_t w = { .wall_m = 1.0 };
    tip(q, p.tool, w.P0);
    base_z_of_tool(q, p.tool, w.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    assert_int_equal(ls_react_start(&r, &p, q, 6), LS_ESTATE);
    log_t log = { 0 };
    run(&r, &w, q, &log, 200, NULL);
    ls_react_stop(&r);
    run(&r, &w, q, &log, 200, NULL);
    assert_int_equal(log.n_paused, 1);
    assert_true(r.paused && r.active);
    double Pp[16], P[16];
    tip(q, p.tool, Pp);
    run(&r, &w, q, &log, 100, NULL);
    tip(q, p.tool, P);
    assert_double_equal(ls_pose_dist(P, Pp), 0.0, 0.0); /* holds while paused */
    assert_int_equal(ls_react_resume(&r), 0);
    assert_int_equal(ls_react_resume(&r), LS_ESTATE);
    run(&r, &w, q, &log, 100, NULL);
    tip(q, p.tool, P);
    assert_true(along(w.P0, P, w.u) > along(w.P0, Pp, w.u) + 1e-3);
    ls_motion_events_t ev = { .n = 0 };
    ls_react_abort(&r, q, &ev);
    assert_int_equal(ev.n, 1);
    assert_int_equal(ev.ev[0].index, LS_REACT_END_ABORTED);
    assert_false(r.active);
    ev.n = 0;
    ls_react_abort(&r, q, &ev);
    assert_int_equal(ev.n, 0);
    assert_int_equal(log.n_end, 0);
}

static void test_missing_sensor_ends_the_move(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    guarded_plan(&p, 0.1, 0.1, 5.0);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    ls_motion_events_t ev = { .n = 0 };
    ls_react_step(&r, DT_S, q, NULL, q, qd, &ev);
    assert_int_equal(ev.n, 1);
    assert_int_equal(ev.ev[0].index, LS_REACT_END_NO_SENSOR);
    assert_memory_equal(q, Q0, sizeof q);
}

static void test_plan_checks(void **state)
{
    (void)state;
    ls_react_plan_t p;
    char why[96];
    guarded_plan(&p, 0.1, 0.1, 5.0);
    assert_int_equal(ls_react_check_plan(&p, why, sizeof why), 0);
    p.dir_tool[2] = 2.0;
    assert_int_equal(ls_react_check_plan(&p, why, sizeof why), LS_EINVAL);
    assert_non_null(strstr(why, "unit vector"));
    guarded_plan(&p, 0.1, 0.1, 5.0);
    p.v_m_s = NAN;
    assert_int_equal(ls_react_check_plan(&p, why, sizeof why), LS_EINVAL);
    guarded_plan(&p, 0.1, 0.0, 5.0);
    assert_int_equal(ls_react_check_plan(&p, why, sizeof why), LS_EINVAL);
    guarded_plan(&p, 0.1, 0.1, 5.0);
    p.kind = LS_REACT_COMPLY; /* comply fields left at 0 */
    assert_int_equal(ls_react_check_plan(&p, why, sizeof why), LS_EINVAL);
    ls_react_t r;
    ls_react_init(&r, M);
    assert_int_equal(ls_react_start(&r, &p, Q0, 6), LS_EINVAL);
    assert_false(r.active);
}

/* ---------------------------------------------------------------- comply */

static void comply_plan(ls_react_plan_t *p, double target_N)
{
    memset(p, 0, sizeof *p);
    p->kind = LS_REACT_COMPLY;
    p->ref_seq = 7;
    snprintf(p->sensor, sizeof p->sensor, "force_sensor");
    identity(p->tool);
    p->dir_tool[0] = 1.0; /* travel along tool x */
    p->n_tool[2] = 1.0;   /* press along tool z */
    p->dist_m = 0.05;
    p->c_max_m = 0.05;
    p->v_m_s = 0.03;
    p->a_m_s2 = 1.0;
    p->j_m_s3 = 10.0;
    p->a_stop_m_s2 = 4.0;
    p->j_stop_m_s3 = 40.0;
    p->f_target_N = target_N;
    p->kp_m_s_N = 5e-4;
    p->vc_max_m_s = 0.01;
    p->timeout_s = 20.0;
    p->panic_N = 3.0 * target_N;
}

static void test_comply_holds_the_force_on_a_spring(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    comply_plan(&p, 10.0);
    double q[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    world_t w = { .wall_m = 0.01 };
    tip(q, p.tool, w.P0);
    base_z_of_tool(q, p.tool, w.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    log_t log = { 0 };
    run(&r, &w, q, &log, 60000, NULL);
    assert_int_equal(log.n_end, 1);
    assert_int_equal(log.last.index, LS_REACT_END_MAX_DISTANCE);
    assert_double_equal(r.report.travelled_m, 0.05, 1e-12);
    assert_true(r.report.fn_samples > 1000);
    assert_double_equal(r.report.fn_mean_N, 10.0, 0.1);
    assert_true(r.report.fn_min_N >= 9.5 && r.report.fn_max_N <= 10.5);
    /* the tip sits 10 N / k into the spring */
    assert_double_equal(r.report.compliance_m, w.wall_m + 10.0 / K_N_M, 1e-6);
    double P[16];
    tip(q, p.tool, P);
    double x_tool[3] = { w.P0[0], w.P0[1], w.P0[2] };
    assert_double_equal(along(w.P0, P, x_tool), 0.05, 1e-6);
}

static void test_comply_panic_and_timeout(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_react_plan_t p;
    comply_plan(&p, 10.0);
    double q[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    world_t w = { .wall_m = 1.0, .spike_N = 31.0, .spike_at = 50 };
    tip(q, p.tool, w.P0);
    base_z_of_tool(q, p.tool, w.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    log_t log = { 0 };
    long n = run(&r, &w, q, &log, 60000, NULL);
    assert_int_equal(n, 51);
    assert_int_equal(log.last.index, LS_REACT_END_PANIC);
    assert_double_equal(r.report.reading[2], 31.0, 1e-12);

    /* nothing to press on within reach: the time-out ends it */
    comply_plan(&p, 10.0);
    p.timeout_s = 0.5;
    memcpy(q, Q0, sizeof q);
    world_t far = { .wall_m = 1.0 };
    tip(q, p.tool, far.P0);
    base_z_of_tool(q, p.tool, far.u);
    assert_int_equal(ls_react_start(&r, &p, q, 6), 0);
    log = (log_t){ 0 };
    n = run(&r, &far, q, &log, 60000, NULL);
    assert_int_equal(log.last.index, LS_REACT_END_TIMEOUT);
    assert_true(n >= 500 && n <= 520);
    /* the compliance travel is bounded */
    double P[16];
    tip(q, p.tool, P);
    assert_double_equal(along(far.P0, P, far.u), 0.5 * 0.01, 0.01 * DT_S + 1e-9); /* 0.5 s at 0.01 m/s, below c_max */
}

/* ---------------------------------------------------------------- jog */

static ls_jog_config_t jog_cfg(void)
{
    ls_jog_config_t c;
    memset(&c, 0, sizeof c);
    c.v_lin_m_s = 0.1;
    c.v_ang_rad_s = 0.3;
    c.a_lin_m_s2 = 1.0;
    c.a_ang_rad_s2 = 3.0;
    c.j_lin_m_s3 = 10.0;
    c.j_ang_rad_s3 = 30.0;
    identity(c.tool);
    return c;
}

static void test_jog_respects_speed_and_acceleration(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_jog_config_t c = jog_cfg();
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    const double tw[6] = { 1.0, 0.0, 0.0, 0.0, 0.0, 0.0 };
    assert_false(ls_react_jog_step(&r, DT_S, tw, q, qd, NULL)); /* off: nothing */
    ls_react_jog_config(&r, &c);
    assert_true(ls_react_jog_on(&r));
    double P0[16], Pprev[16], P[16];
    tip(q, c.tool, P0);
    memcpy(Pprev, P0, sizeof Pprev);
    double vprev = 0.0, vmax = 0.0, amax = 0.0, h[4][3];
    for (int k = 0; k < 4; k++) {
        memcpy(h[k], P0 + 12, sizeof h[k]);
    }
    for (int i = 0; i < 1000; i++) {
        assert_true(ls_react_jog_step(&r, DT_S, tw, q, qd, NULL));
        tip(q, c.tool, P);
        assert_true(push_tip_jerk(h, P) <= 10.0 * (1.0 + 1e-6));
        double v = ls_pose_dist(P, Pprev) / DT_S;
        vmax = fmax(vmax, v);
        amax = fmax(amax, fabs(v - vprev) / DT_S);
        vprev = v;
        memcpy(Pprev, P, sizeof Pprev);
    }
    assert_double_equal(vmax, 0.1, 1e-6);
    assert_true(amax <= 1.0 + 1e-3);
    /* 1 s: the jerk-limited ramp to 0.1 m/s at a = 1, j = 10 (two 0.1 s jerk
     * phases, 10 mm), then 0.1 m/s along the tool x, orientation held */
    ls_ramp_t up;
    assert_int_equal(ls_ramp_plan(&up, 0.0, 0.0, 0.0, 0.1, 1.0, 10.0), LS_OK);
    assert_double_equal(up.duration_s, 0.2, 1e-12);
    double want;
    ls_ramp_sample(&up, 1.0, &want, NULL, NULL);
    assert_double_equal(ls_pose_dist(P, P0), want, 1e-6);
    assert_double_equal(ls_pose_angle(P, P0), 0.0, 1e-9);
    double dx[3] = { P[12] - P0[12], P[13] - P0[13], P[14] - P0[14] };
    assert_double_equal((dx[0] * P0[0] + dx[1] * P0[1] + dx[2] * P0[2]) / ls_pose_dist(P, P0), 1.0, 1e-9);
    /* released: decelerates to rest, then nothing moves */
    int moving = 0;
    for (int i = 0; i < 300; i++) {
        moving += ls_react_jog_step(&r, DT_S, NULL, q, qd, NULL);
        tip(q, c.tool, P);
        const double jerk = push_tip_jerk(h, P);
        if (!(jerk <= 10.0 * (1.0 + 1e-6))) {
            fail_msg("released: tip jerk %.9g m/s^3 beyond 10 at cycle %d", jerk, i);
        }
    }
    const int ramp_cycles = (int)ceil(up.duration_s / DT_S);
    assert_true(moving >= ramp_cycles - 1 && moving <= ramp_cycles + 1);
    ls_react_jog_config(&r, NULL);
    assert_false(ls_react_jog_on(&r));
}

/* The device's twist changes while the jog still ramps (x pushed, then x
 * and y, then y alone, then released): the tip's acceleration and jerk
 * vectors stay within the limits through every change. */
static void test_jog_keeps_its_limits_when_the_twist_changes_mid_ramp(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_jog_config_t c = jog_cfg();
    ls_react_jog_config(&r, &c);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS], P[16], h[4][3];
    memcpy(q, Q0, sizeof q);
    tip(q, c.tool, P);
    for (int k = 0; k < 4; k++) {
        memcpy(h[k], P + 12, sizeof h[k]);
    }
    const double x[6] = { 1, 0, 0, 0, 0, 0 }, xy[6] = { 0.3, 1, 0, 0, 0, 0 }, y[6] = { 0, -1, 0, 0, 0, 0 };
    double a_max = 0.0, j_max = 0.0;
    for (int i = 0; i < 1200; i++) {
        const double *tw = i < 150 ? x : (i < 300 ? xy : (i < 600 ? y : NULL));
        (void)ls_react_jog_step(&r, DT_S, tw, q, qd, NULL);
        tip(q, c.tool, P);
        j_max = fmax(j_max, push_tip_jerk(h, P));
        double acc2 = 0.0;
        for (int k = 0; k < 3; k++) {
            const double ak = (h[0][k] - 2.0 * h[1][k] + h[2][k]) / (DT_S * DT_S);
            acc2 += ak * ak;
        }
        a_max = fmax(a_max, sqrt(acc2));
    }
    print_message("jog with changes mid-ramp: tip acceleration %.6f m/s^2 (limit 1), jerk %.6f m/s^3 (limit 10)\n",
                  a_max, j_max);
    assert_true(a_max <= 1.0 * (1.0 + 1e-6));
    assert_true(j_max <= 10.0 * (1.0 + 1e-6));
    assert_true(a_max > 0.9); /* it does ramp at the limit */
}

static void test_jog_stops_at_a_joint_limit_without_a_fault(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_jog_config_t c = jog_cfg();
    c.v_ang_rad_s = 1.0;
    c.a_ang_rad_s2 = 20.0;
    ls_react_jog_config(&r, &c);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    q[5] = M->q_max_rad[5] - 0.05; /* 50 mrad from joint 6's limit */
    /* turn about the tool z: joint 6 runs into its limit */
    const double tw[6] = { 0.0, 0.0, 0.0, 0.0, 0.0, 1.0 };
    log_t log = { 0 };
    int direction = 0;
    for (int i = 0; i < 2000; i++) {
        ls_motion_events_t ev = { .n = 0 };
        double before = q[5];
        (void)ls_react_jog_step(&r, DT_S, tw, q, qd, &ev);
        collect(&log, &ev);
        direction = q[5] > before ? 1 : (q[5] < before ? -1 : direction);
        assert_true(q[5] <= M->q_max_rad[5]);
    }
    assert_int_equal(log.n_fault, 0);
    assert_int_equal(log.n_jog, 1); /* reported once while pushed into it */
    if (strstr(log.last.text, "limit") == NULL) {
        fail_msg("jog event: %s", log.last.text);
    }
    assert_true(M->q_max_rad[5] - q[5] < 0.01);
    /* the other way is free again */
    const double back[6] = { 0.0, 0.0, 0.0, 0.0, 0.0, -1.0 };
    (void)ls_react_jog_step(&r, DT_S, NULL, q, qd, NULL);
    double at = q[5];
    for (int i = 0; i < 100; i++) {
        (void)ls_react_jog_step(&r, DT_S, back, q, qd, NULL);
    }
    assert_true(q[5] < at - 1e-3);
}

static ls_jog_config_t joint_jog_cfg(void)
{
    ls_jog_config_t c = jog_cfg();
    for (int j = 0; j < LS_N_JOINTS; j++) {
        c.qd_rad_s[j] = 0.25 * M->qd_max_rad_s[j];
        c.qdd_rad_s2[j] = M->qdd_max_rad_s2[j];
        c.qddd_rad_s3[j] = M->qddd_max_rad_s3[j];
    }
    return c;
}

/* Single-joint mode: the largest component drives its joint alone, within
 * the joint's acceleration and jerk, and the joint brakes on its ramp in
 * time to stop at its limit (reported once). */
static void test_jog_in_joint_mode_moves_one_joint_and_brakes_before_its_limit(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_jog_config_t c = joint_jog_cfg();
    ls_react_jog_config(&r, &c);
    ls_react_jog_mode(&r, LS_JOG_TOOL, true);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    q[5] = M->q_max_rad[5] - 0.3;
    const double q4 = q[4];
    const double tw[6] = { 0.0, 0.0, 0.0, 0.0, 0.3, 1.0 }; /* joint 6 wins over joint 5 */
    log_t log = { 0 };
    double h[4] = { q[5], q[5], q[5], q[5] };
    double v_max = 0.0, a_max = 0.0, j_max = 0.0;
    for (int i = 0; i < 2000; i++) {
        ls_motion_events_t ev = { .n = 0 };
        (void)ls_react_jog_step(&r, DT_S, tw, q, qd, &ev);
        collect(&log, &ev);
        assert_true(ls_react_jog_joint(&r));
        assert_true(q[5] <= M->q_max_rad[5]);
        assert_true(q[4] == q4);
        memmove(h + 1, h, 3 * sizeof h[0]);
        h[0] = q[5];
        if (i >= 3) {
            v_max = fmax(v_max, fabs(h[0] - h[1]) / DT_S);
            a_max = fmax(a_max, fabs(h[0] - 2.0 * h[1] + h[2]) / (DT_S * DT_S));
            j_max = fmax(j_max, fabs(h[0] - 3.0 * h[1] + 3.0 * h[2] - h[3]) / (DT_S * DT_S * DT_S));
        }
    }
    print_message("joint jog: speed %.4f rad/s (%.4f), acceleration %.3f (%.3f), jerk %.2f (%.2f); stopped %.2e rad "
                  "before the limit\n",
                  v_max, c.qd_rad_s[5], a_max, c.qdd_rad_s2[5], j_max, c.qddd_rad_s3[5], M->q_max_rad[5] - q[5]);
    assert_true(v_max <= c.qd_rad_s[5] * (1.0 + 1e-9));
    assert_true(a_max <= c.qdd_rad_s2[5] * 1.01);
    assert_true(j_max <= c.qddd_rad_s3[5] * 1.01);
    assert_true(M->q_max_rad[5] - q[5] < 5e-3);
    assert_int_equal(log.n_fault, 0);
    assert_int_equal(log.n_jog, 1);
    assert_string_equal(log.last.text, "stopped at joint 6 limit");
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_true(qd[j] == 0.0); /* at rest at the limit */
    }
}

/* A change of frame or mode waits for rest: the jog first ramps down in the
 * mode it had, then moves in the new one. */
static void test_a_jog_mode_change_takes_effect_at_rest(void **state)
{
    (void)state;
    ls_react_t r;
    ls_react_init(&r, M);
    ls_jog_config_t c = joint_jog_cfg();
    ls_react_jog_config(&r, &c);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    memcpy(q, Q0, sizeof q);
    const double tw[6] = { 1.0, 0.0, 0.0, 0.0, 0.0, 0.0 };
    for (int i = 0; i < 300; i++) {
        assert_true(ls_react_jog_step(&r, DT_S, tw, q, qd, NULL));
    }
    ls_react_jog_mode(&r, LS_JOG_BASE, true);
    int cartesian = 0;
    double q0_before = q[0];
    for (int i = 0; i < 1000 && !ls_react_jog_joint(&r); i++) {
        (void)ls_react_jog_step(&r, DT_S, tw, q, qd, NULL);
        cartesian++;
    }
    assert_true(ls_react_jog_joint(&r));
    assert_int_equal(ls_react_jog_frame(&r), LS_JOG_BASE);
    assert_in_range(cartesian, 190, 215); /* the Cartesian ramp down: 0.1 / 1 + 1 / 10 s */
    const double q1 = q[1];
    for (int i = 0; i < 100; i++) {
        (void)ls_react_jog_step(&r, DT_S, tw, q, qd, NULL);
    }
    assert_true(q[0] > q0_before); /* joint 1 moves now */
    assert_true(fabs(q[1] - q1) < 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_guarded_stops_at_the_wall_and_comes_back),
        cmocka_unit_test(test_guarded_without_contact_stops_at_the_maximum_distance),
        cmocka_unit_test(test_guarded_envelope_beats_the_threshold),
        cmocka_unit_test(test_guarded_laser_stops_below_its_threshold),
        cmocka_unit_test(test_stop_pauses_resume_continues_abort_ends),
        cmocka_unit_test(test_missing_sensor_ends_the_move),
        cmocka_unit_test(test_plan_checks),
        cmocka_unit_test(test_comply_holds_the_force_on_a_spring),
        cmocka_unit_test(test_comply_panic_and_timeout),
        cmocka_unit_test(test_jog_respects_speed_and_acceleration),
        cmocka_unit_test(test_jog_keeps_its_limits_when_the_twist_changes_mid_ramp),
        cmocka_unit_test(test_jog_stops_at_a_joint_limit_without_a_fault),
        cmocka_unit_test(test_jog_in_joint_mode_moves_one_joint_and_brakes_before_its_limit),
        cmocka_unit_test(test_a_jog_mode_change_takes_effect_at_rest),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
