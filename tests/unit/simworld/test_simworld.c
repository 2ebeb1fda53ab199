/* Black-box tests of the simulated world (hal/sim/world). The DH forward
 * kinematics and a numeric inverse used to reach poses are written here from
 * the model table, independent of the world's own code. */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmocka.h>
#include <ode/ode.h>

#include "hal_sim_world.h"
#include "ls_robot_model_sim.h"
#include "ls_math.h"
#include "test_rng.h"

#define NJ LS_N_JOINTS
#define DT 0.001
#define DEG (LS_PI / 180.0)

static const ls_robot_model_t *M = &ls_robot_model_default;
static hal_arm_t arm;
static double cmd_q[NJ]; /* last commanded position */

/* ---- independent kinematics oracle ---- */

/* Column-major 4x4 product C = A * B. */
static void m4_mul(const double A[16], const double B[16], double C[16])
{
    double t[16];
    for (int c = 0; c < 4; c++) {
        for (int r = 0; r < 4; r++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) {
                s += A[k * 4 + r] * B[c * 4 + k];
            }
            t[c * 4 + r] = s;
        }
    }
    memcpy(C, t, sizeof t);
}

/* Frame i of the model (0: base) at q, column-major: standard DH, each
 * joint Rz(theta) Tz(d) Tx(a) Rx(alpha). */
static void fk_frames(const double q[NJ], double T[NJ + 1][16])
{
    double acc[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    memcpy(T[0], acc, sizeof acc);
    for (int i = 0; i < NJ; i++) {
        const ls_dh_t *d = &M->dh[i];
        double th = q[i] + d->theta_offset_rad;
        double ct = cos(th), st = sin(th), ca = cos(d->alpha_rad), sa = sin(d->alpha_rad);
        double A[16] = { ct,      st,       0,  0, -st * ca,    ct * ca,     sa,     0,
                         st * sa, -ct * sa, ca, 0, d->a_m * ct, d->a_m * st, d->d_m, 1 };
        m4_mul(acc, A, acc);
        memcpy(T[i + 1], acc, sizeof acc);
    }
}

static void fk(const double q[NJ], double T[16])
{
    double frames[NJ + 1][16];
    fk_frames(q, frames);
    memcpy(T, frames[NJ], sizeof frames[NJ]);
}

/* R = Rz(yaw) Ry(pitch) Rx(roll), column-major 3x3 inside a 4x4 T. */
static void pose_to_T(const double xyzrpy[6], double T[16])
{
    double cr = cos(xyzrpy[3]), sr = sin(xyzrpy[3]), cp = cos(xyzrpy[4]), sp = sin(xyzrpy[4]);
    double cy = cos(xyzrpy[5]), sy = sin(xyzrpy[5]);
    double R[3][3] = { { cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr },
                       { sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr },
                       { -sp, cp * sr, cp * cr } };
    memset(T, 0, 16 * sizeof(double));
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            T[c * 4 + r] = R[r][c];
        }
    }
    T[12] = xyzrpy[0];
    T[13] = xyzrpy[1];
    T[14] = xyzrpy[2];
    T[15] = 1.0;
}

/* Position error and rotation angle between two poses. */
static void pose_diff(const double A[16], const double B[16], double *dp, double *dang)
{
    double dx = A[12] - B[12], dy = A[13] - B[13], dz = A[14] - B[14];
    *dp = sqrt(dx * dx + dy * dy + dz * dz);
    /* half the vee of (A^T B - B^T A) has norm sin(angle) */
    double Rt[9]; /* A^T B */
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            double s = 0.0;
            for (int k = 0; k < 3; k++) {
                s += A[r * 4 + k] * B[c * 4 + k];
            }
            Rt[r * 3 + c] = s;
        }
    }
    double v[3] = { (Rt[7] - Rt[5]) / 2, (Rt[2] - Rt[6]) / 2, (Rt[3] - Rt[1]) / 2 };
    double trace = Rt[0] + Rt[4] + Rt[8];
    *dang = atan2(sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), (trace - 1.0) / 2.0);
}

/* e = [p_t - p; 0.5 sum_k R_k x Rt_k] */
static void ik_error(const double Tt[16], const double q[NJ], double e[6])
{
    double T[16];
    fk(q, T);
    for (int k = 0; k < 3; k++) {
        e[k] = Tt[12 + k] - T[12 + k];
    }
    e[3] = e[4] = e[5] = 0.0;
    for (int c = 0; c < 3; c++) {
        const double *a = &T[c * 4], *b = &Tt[c * 4];
        e[3] += 0.5 * (a[1] * b[2] - a[2] * b[1]);
        e[4] += 0.5 * (a[2] * b[0] - a[0] * b[2]);
        e[5] += 0.5 * (a[0] * b[1] - a[1] * b[0]);
    }
}

static bool solve6(double A[6][7], double x[6])
{
    for (int c = 0; c < 6; c++) {
        int piv = c;
        for (int r = c + 1; r < 6; r++) {
            if (fabs(A[r][c]) > fabs(A[piv][c])) {
                piv = r;
            }
        }
        if (fabs(A[piv][c]) < 1e-14) {
            return false;
        }
        for (int k = 0; k < 7; k++) {
            double t = A[c][k];
            A[c][k] = A[piv][k];
            A[piv][k] = t;
        }
        for (int r = 0; r < 6; r++) {
            if (r != c) {
                double f = A[r][c] / A[c][c];
                for (int k = c; k < 7; k++) {
                    A[r][k] -= f * A[c][k];
                }
            }
        }
    }
    for (int r = 0; r < 6; r++) {
        x[r] = A[r][6] / A[r][r];
    }
    return true;
}

/* Damped Newton on the oracle FK; true when converged inside the limits. */
static bool ik_from(const double Tt[16], const double seed[NJ], double q[NJ])
{
    memcpy(q, seed, NJ * sizeof(double));
    for (int it = 0; it < 300; it++) {
        double e[6], J[6][6];
        ik_error(Tt, q, e);
        double n = 0.0;
        for (int k = 0; k < 6; k++) {
            n += e[k] * e[k];
        }
        if (n < 1e-22) {
            /* the skew error also vanishes 180 deg away: check the real pose */
            double T[16], dp, da;
            fk(q, T);
            pose_diff(Tt, T, &dp, &da);
            if (dp > 1e-9 || da > 1e-9) {
                return false;
            }
            for (int j = 0; j < NJ; j++) {
                if (q[j] < M->q_min_rad[j] || q[j] > M->q_max_rad[j]) {
                    return false;
                }
            }
            return true;
        }
        for (int j = 0; j < NJ; j++) {
            double qh[NJ], eh[6];
            memcpy(qh, q, sizeof qh);
            qh[j] += 1e-7;
            ik_error(Tt, qh, eh);
            for (int k = 0; k < 6; k++) {
                J[k][j] = (eh[k] - e[k]) / 1e-7;
            }
        }
        double A[6][7];
        for (int r = 0; r < 6; r++) {
            for (int c = 0; c < 6; c++) {
                double s = r == c ? 1e-9 : 0.0;
                for (int k = 0; k < 6; k++) {
                    s += J[k][r] * J[k][c];
                }
                A[r][c] = s;
            }
            double s = 0.0;
            for (int k = 0; k < 6; k++) {
                s -= J[k][r] * e[k];
            }
            A[r][6] = s;
        }
        double dq[6];
        if (!solve6(A, dq)) {
            return false;
        }
        double big = 0.0;
        for (int j = 0; j < NJ; j++) {
            big = fmax(big, fabs(dq[j]));
        }
        double scale = big > 0.3 ? 0.3 / big : 1.0;
        for (int j = 0; j < NJ; j++) {
            q[j] += scale * dq[j];
        }
    }
    return false;
}

static bool ik(const double xyzrpy[6], double q[NJ])
{
    double Tt[16];
    pose_to_T(xyzrpy, Tt);
    double yaw = atan2(xyzrpy[1], xyzrpy[0]);
    const double seeds[][NJ] = {
        { yaw, 0.3, 0.3, 0.0, 1.2, 0.0 }, { yaw, 0.3, 0.3, 0.0, -1.2, 0.0 },  { yaw, 0.6, 0.6, 0.0, 1.0, 0.0 },
        { yaw, 0.0, 0.8, 0.0, 0.8, 0.0 }, { yaw, 0.5, 0.0, LS_PI, 1.0, 0.0 }, { yaw, 0.2, 0.2, 0.0, -0.4, 0.0 },
        { yaw, 0.2, 0.2, 0.0, 0.4, 0.0 }, { 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 },
    };
    for (size_t s = 0; s < sizeof seeds / sizeof seeds[0]; s++) {
        if (ik_from(Tt, seeds[s], q)) {
            return true;
        }
    }
    return false;
}

/* ---- driving the arm ---- */

static void open_world(bool lockstep, bool obstacle, const char *sock)
{
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(M, &am);
    hal_sim_world_config_t cfg = {
        .arm = &am, .dio_socket_path = sock, .lockstep = lockstep, .with_obstacle = obstacle
    };
    char msg[200] = "";
    int rc = hal_sim_world_open(&cfg, msg, sizeof msg);
    if (rc != LS_OK) {
        fail_msg("open failed (%d): %s", rc, msg);
    }
    hal_sim_world_get_arm(&arm);
    memset(cmd_q, 0, sizeof cmd_q);
}

static int cycle(const double q[NJ], const double qd[NJ])
{
    assert_int_equal(hal_arm_command(&arm, q, qd), LS_OK);
    int rc = hal_sim_world_step(NULL, DT);
    assert_true(rc >= 0);
    return rc;
}

static void hold(int cycles)
{
    for (int k = 0; k < cycles; k++) {
        cycle(cmd_q, NULL);
    }
}

/* Cosine blend from the last command to q at up to `speed` x the model limit. */
static void move_to(const double q[NJ], double speed)
{
    double T = 0.05;
    for (int j = 0; j < NJ; j++) {
        T = fmax(T, fabs(q[j] - cmd_q[j]) * LS_PI / 2.0 / (speed * M->qd_max_rad_s[j]));
    }
    int n = (int)ceil(T / DT);
    double from[NJ];
    memcpy(from, cmd_q, sizeof from);
    for (int k = 1; k <= n; k++) {
        double s = (double)k / n;
        double c[NJ], cd[NJ];
        for (int j = 0; j < NJ; j++) {
            double d = q[j] - from[j];
            c[j] = from[j] + d * (1.0 - cos(LS_PI * s)) / 2.0;
            cd[j] = d * LS_PI * sin(LS_PI * s) / (2.0 * n * DT);
        }
        cycle(c, cd);
    }
    memcpy(cmd_q, q, sizeof cmd_q);
}

static void read_q(double q[NJ])
{
    assert_int_equal(hal_arm_read(&arm, q, NULL), LS_OK);
}

static const hal_sensor_t *sensor(const char *name)
{
    size_t n = 0;
    const hal_sensor_t *s = hal_sim_world_sensors(&n);
    for (size_t i = 0; i < n; i++) {
        if (strcmp(s[i].name, name) == 0) {
            return &s[i];
        }
    }
    fail_msg("no sensor %s", name);
    return NULL;
}

static double laser(void)
{
    double v = -1.0;
    const hal_sensor_t *s = sensor("laser_standoff_sensor");
    assert_int_equal(s->read(s->self, &v), LS_OK);
    return v;
}

static void force(double w[6])
{
    const hal_sensor_t *s = sensor("force_sensor");
    assert_int_equal(s->read(s->self, w), LS_OK);
}

static test_rng_t g_rng = { 0x9E3779B97F4A7C15u };
static double urand(void)
{
    return test_rng_uniform(&g_rng, 0.0, 1.0);
}

static int teardown(void **state)
{
    (void)state;
    hal_sim_world_close();
    return 0;
}

/* ---- tests ---- */

static void test_open_rejects_bad_config(void **state)
{
    (void)state;
    char msg[200] = "";
    assert_int_equal(hal_sim_world_open(NULL, msg, sizeof msg), LS_EINVAL);
    hal_sim_world_config_t cfg = { .arm = NULL };
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "arm model"));
    /* The description is checked: a joint count the world cannot build, a
     * link 6 off z6, a joint without torque. */
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(M, &am);
    cfg.arm = &am;
    am.n_joints = 5;
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "6-joint"));
    ls_robot_model_to_sim(M, &am);
    am.dh[5].a_m = 0.1;
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "link 6 along z6"));
    ls_robot_model_to_sim(M, &am);
    am.torque_max_Nm[2] = 0.0;
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "torque_max > 0"));
    ls_robot_model_to_sim(M, &am);
    char longpath[200];
    memset(longpath, 'a', sizeof longpath - 1);
    longpath[sizeof longpath - 1] = '\0';
    cfg.dio_socket_path = longpath;
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "longer than"));
    /* a closed world answers, never crashes */
    hal_sim_world_get_arm(&arm);
    double q[NJ];
    assert_int_equal(hal_arm_read(&arm, q, NULL), LS_ENODEV);
    double T[16];
    assert_int_equal(hal_sim_world_flange_pose(T), LS_ENODEV);
    open_world(false, false, NULL);
    assert_int_equal(hal_sim_world_open(&cfg, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "already open"));
    hal_arm_info_t info;
    assert_int_equal(hal_arm_info(&arm, &info), LS_OK);
    assert_int_equal(info.n_joints, 6);
    assert_true(info.q_max_rad[5] == M->q_max_rad[5] && info.torque_max_Nm[1] == M->torque_max_Nm[1]);
    assert_int_equal(hal_sim_world_step(NULL, 0.0), LS_EINVAL);
    assert_int_equal(hal_sim_world_step(NULL, NAN), LS_EINVAL);
    double bad[NJ] = { 0, NAN, 0, 0, 0, 0 };
    assert_int_equal(hal_arm_command(&arm, bad, NULL), LS_EINVAL);
    assert_int_equal(hal_arm_command(&arm, NULL, NULL), LS_EINVAL);
    /* no socket: no fd, nothing to drain */
    hal_dio_t dio;
    hal_sim_world_get_dio(&dio);
    assert_int_equal(hal_dio_poll_fd(&dio), -1);
    assert_int_equal(hal_dio_drain_events(&dio), 0);
}

static void test_geometry_matches_dh(void **state)
{
    (void)state;
    open_world(false, true, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    double T_ode[16], T_fk[16], q[NJ];
    /* q = 0: the built pose */
    read_q(q);
    for (int j = 0; j < NJ; j++) {
        assert_true(fabs(q[j]) < 1e-12);
    }
    double worst_p = 0.0, worst_a = 0.0;
    for (int n = 0; n < 200; n++) {
        double target[NJ];
        for (int j = 0; j < NJ; j++) {
            target[j] = M->q_min_rad[j] + urand() * (M->q_max_rad[j] - M->q_min_rad[j]);
        }
        move_to(target, 1.0);
        hold(50);
        read_q(q);
        assert_int_equal(hal_sim_world_flange_pose(T_ode), LS_OK);
        fk(q, T_fk);
        double dp, da;
        pose_diff(T_ode, T_fk, &dp, &da);
        worst_p = fmax(worst_p, dp);
        worst_a = fmax(worst_a, da);
        if (dp > 1e-4 || da > 1e-4) {
            fail_msg("config %d: flange differs from DH FK by %.3g m / %.3g rad", n, dp, da);
        }
    }
    print_message("geometry: worst %.3g m, %.3g rad over 200 configurations\n", worst_p, worst_a);
}

/* The command sequence of the determinism test: a move, a hold, a move. */
static void run_sequence(int idle_cycles, double out[][NJ], int n_out)
{
    double zero[NJ] = { 0 };
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    for (int k = 0; k < idle_cycles; k++) {
        cycle(zero, zero);
    }
    double a[NJ] = { 0.4, -0.3, 0.5, 0.8, -0.6, 1.0 };
    double b[NJ] = { -0.2, 0.2, 0.1, -0.5, 0.9, -2.0 };
    int k = 0;
    for (int phase = 0; phase < 3 && k < n_out; phase++) {
        int n = phase == 1 ? 300 : 1000;
        for (int i = 0; i < n && k < n_out; i++, k++) {
            double s = (double)(i + 1) / n, c[NJ], cd[NJ];
            for (int j = 0; j < NJ; j++) {
                if (phase == 1) {
                    c[j] = a[j];
                    cd[j] = 0.0;
                } else {
                    double from = phase == 0 ? 0.0 : a[j], to = phase == 0 ? a[j] : b[j];
                    c[j] = from + (to - from) * (1.0 - cos(LS_PI * s)) / 2.0;
                    cd[j] = (to - from) * LS_PI * sin(LS_PI * s) / (2.0 * n * DT);
                }
            }
            cycle(c, cd);
            read_q(out[k]);
        }
    }
}

#define SEQ_LEN 2300
static double traj_a[SEQ_LEN][NJ], traj_b[SEQ_LEN][NJ];

static void test_lockstep_determinism(void **state)
{
    (void)state;
    open_world(true, false, NULL);
    run_sequence(0, traj_a, SEQ_LEN);
    hal_sim_world_close();
    open_world(true, false, NULL);
    /* idle cycles do not advance the physics */
    double zero[NJ] = { 0 };
    assert_int_equal(cycle(zero, zero), 0);
    run_sequence(777, traj_b, SEQ_LEN);
    assert_memory_equal(traj_a, traj_b, sizeof traj_a);
    /* the arm really moved, and in lockstep a hold stops it where it is */
    assert_true(fabs(traj_a[999][0] - 0.4) < 1e-3);
    assert_memory_equal(traj_a[1001], traj_a[1299], sizeof traj_a[0]);
    hal_sim_world_close();

    /* without lockstep idle time does change the trajectory (gravity) */
    open_world(false, false, NULL);
    run_sequence(777, traj_b, SEQ_LEN);
    assert_true(memcmp(traj_a, traj_b, sizeof traj_a) != 0);
}

static void test_tracking(void **state)
{
    (void)state;
    open_world(false, false, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    const double amp[NJ] = { 0.5, 0.4, -0.5, 0.6, 0.5, 0.8 };
    const double w = LS_PI; /* 0.5 Hz */
    double worst = 0.0;
    for (int k = 0; k < 4000; k++) {
        double t = k * DT, c[NJ], cd[NJ], q[NJ];
        read_q(q);
        for (int j = 0; j < NJ; j++) {
            c[j] = amp[j] * (1.0 - cos(w * t));
            cd[j] = amp[j] * w * sin(w * t);
            worst = fmax(worst, fabs(c[j] - q[j]));
        }
        cycle(c, cd);
    }
    print_message("tracking: worst following error %.3g rad\n", worst);
    assert_true(worst < 1e-3);
}

static void test_contact_force_and_laser(void **state)
{
    (void)state;
    open_world(false, false, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    double q[NJ], w[6], T[16];
    double pose[6] = { 0.55, 0.0, 0.30, LS_PI, 0.0, 0.0 };
    assert_true(ik(pose, q));
    move_to(q, 0.5);
    hold(300);
    bool touching = true;
    double pt[3];
    assert_int_equal(hal_sim_world_contact(&touching, pt), 0);
    assert_false(touching);
    force(w);
    assert_true(fabs(w[0]) < 0.2 && fabs(w[1]) < 0.2 && fabs(w[2]) < 0.2);
    assert_true(fabs(w[3]) < 0.02 && fabs(w[4]) < 0.02 && fabs(w[5]) < 0.02);
    /* tool frame = flange (no tool): 0.20 above the table top */
    assert_true(fabs(laser() - 0.20) < 1e-3);

    /* descend at 20 mm/s to 2 mm below the table top */
    double prev = laser();
    int samples = 0;
    for (double z = 0.30; z > 0.098; z -= 0.00002) {
        pose[2] = z;
        double qn[NJ], Tt[16];
        pose_to_T(pose, Tt);
        assert_true(ik_from(Tt, q, qn));
        double qd[NJ];
        for (int j = 0; j < NJ; j++) {
            qd[j] = (qn[j] - q[j]) / DT;
        }
        cycle(qn, qd);
        memcpy(q, qn, sizeof q);
        if (++samples % 50 == 0) {
            assert_int_equal(hal_sim_world_flange_pose(T), LS_OK);
            double l = laser();
            if (T[14] > 0.1005) {
                assert_true(l < prev);
                assert_true(fabs(l - (T[14] - 0.10)) < 5e-4);
                force(w);
                assert_true(fabs(w[2]) < 1.0);
            }
            prev = l;
        }
    }
    memcpy(cmd_q, q, sizeof cmd_q);
    hold(500);
    force(w);
    assert_int_equal(hal_sim_world_flange_pose(T), LS_OK);
    double pen = 0.10 - T[14];
    print_message("contact: penetration %.3g m, F = %.3g %.3g %.3g N, T = %.3g %.3g %.3g Nm\n", pen, w[0], w[1], w[2],
                  w[3], w[4], w[5]);
    assert_true(pen > 0.0);
    assert_true(w[2] > 5.0);                                 /* the tool pushes along its approach axis */
    assert_true(fabs(w[2] - 5e4 * pen) < 0.05 * w[2] + 1.0); /* spring law */
    /* a flat, centred press: no lateral force (viscous friction relaxes) and
     * no torque about the tool tip */
    assert_true(fabs(w[0]) < 0.01 * w[2] && fabs(w[1]) < 0.01 * w[2]);
    assert_true(fabs(w[3]) < 0.01 && fabs(w[4]) < 0.01 && fabs(w[5]) < 0.01);
    assert_true(laser() == 0.0); /* tip inside the table */
    assert_int_equal(hal_sim_world_contact(&touching, pt), 1);
    assert_true(touching);
    assert_true(fabs(pt[0] - 0.55) < 0.045 && fabs(pt[1]) < 0.045 && fabs(pt[2] - 0.10) < 0.003);
}

static void go_to_pose(const double pose[6])
{
    double q[NJ];
    if (!ik(pose, q)) {
        fail_msg("pose %.3f %.3f %.3f is not reachable", pose[0], pose[1], pose[2]);
    }
    move_to(q, 0.5);
    hold(200);
}

static void test_tool_rack(void **state)
{
    (void)state;
    open_world(false, false, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    hal_tool_t tool;
    hal_sim_world_get_tool(&tool);
    double rack_g[6], rack_p[6], off[6];
    assert_int_equal(tool.ops->rack_pose(tool.self, "gripper", rack_g), LS_OK);
    assert_int_equal(tool.ops->rack_pose(tool.self, "probe", rack_p), LS_OK);
    assert_int_equal(tool.ops->rack_pose(tool.self, "hammer", rack_p), LS_EINVAL);
    assert_int_equal(tool.ops->rack_pose(tool.self, "none", rack_p), LS_EINVAL);
    const double want_g[6] = { 0.30, 0.50, 0.35, LS_PI, 0.0, 0.0 };
    assert_memory_equal(rack_g, want_g, sizeof want_g);
    assert_int_equal(tool.ops->tool_offset(tool.self, "gripper", off), LS_OK);
    const double want_off[6] = { 0, 0, 0.12, 0, 0, 0 };
    assert_memory_equal(off, want_off, sizeof off);
    assert_int_equal(tool.ops->tool_offset(tool.self, "probe", off), LS_OK);
    assert_true(off[2] == 0.15);
    assert_int_equal(tool.ops->tool_offset(tool.self, "none", off), LS_OK);
    assert_true(off[2] == 0.0);
    assert_string_equal(hal_sim_world_current_tool(), "none");
    assert_int_equal(tool.ops->set_bits(tool.self, 1, 0), LS_EINVAL); /* no tool */

    /* not at the rack: refused */
    assert_int_equal(tool.ops->couple(tool.self, "gripper", true), LS_EINVAL);

    go_to_pose(rack_g);
    assert_true(fabs(laser() - 0.35) < 1e-3);                                   /* flange over the floor */
    assert_int_equal(tool.ops->couple(tool.self, "probe", true), LS_EINVAL);    /* wrong rack */
    assert_int_equal(tool.ops->couple(tool.self, "gripper", false), LS_EINVAL); /* not coupled */
    assert_int_equal(tool.ops->couple(tool.self, "gripper", true), LS_OK);
    assert_string_equal(hal_sim_world_current_tool(), "gripper");
    assert_true(fabs(laser() - 0.23) < 1e-3);                                  /* tip 0.12 below the flange */
    assert_int_equal(tool.ops->couple(tool.self, "gripper", true), LS_EINVAL); /* already */
    hold(300);
    double w[6];
    force(w);
    for (int k = 0; k < 6; k++) {
        assert_true(fabs(w[k]) < 0.1); /* the tool's weight is tared */
    }
    /* the tare holds in any orientation: tool horizontal, along +x */
    const double level[6] = { 0.55, 0.0, 0.50, 0.0, LS_PI / 2, 0.0 };
    go_to_pose(level);
    hold(300);
    force(w);
    print_message("tool level: F = %.3g %.3g %.3g N, T = %.3g %.3g %.3g Nm\n", w[0], w[1], w[2], w[3], w[4], w[5]);
    for (int k = 0; k < 6; k++) {
        assert_true(fabs(w[k]) < 0.1);
    }
    assert_true(fabs(laser() - 0.5) < 1e-12); /* nothing ahead within range */
    go_to_pose(rack_g);
    uint32_t bits = 9;
    assert_int_equal(tool.ops->set_bits(tool.self, 1, 0), LS_OK);
    assert_int_equal(tool.ops->get_bits(tool.self, &bits), LS_OK);
    assert_int_equal(bits, 1);
    assert_int_equal(tool.ops->set_bits(tool.self, 2, 0), LS_EINVAL);
    assert_int_equal(tool.ops->get_bits(tool.self, &bits), LS_OK);
    assert_int_equal(bits, 1);

    /* 5 cm above the rack: cannot put it back there */
    double above[6];
    memcpy(above, rack_g, sizeof above);
    above[2] += 0.05;
    go_to_pose(above);
    assert_int_equal(tool.ops->couple(tool.self, "gripper", false), LS_EINVAL);
    assert_string_equal(hal_sim_world_current_tool(), "gripper");
    go_to_pose(rack_g);
    assert_int_equal(tool.ops->couple(tool.self, "gripper", false), LS_OK);
    assert_string_equal(hal_sim_world_current_tool(), "none");
    assert_int_equal(tool.ops->get_bits(tool.self, &bits), LS_OK);
    assert_int_equal(bits, 0);
    assert_true(fabs(laser() - 0.35) < 1e-3);

    /* the probe's rack is reachable too */
    go_to_pose(rack_p);
    assert_int_equal(tool.ops->couple(tool.self, "probe", true), LS_OK);
    assert_string_equal(hal_sim_world_current_tool(), "probe");
    assert_true(fabs(laser() - 0.20) < 1e-3);
    assert_int_equal(tool.ops->set_bits(tool.self, 1, 0), LS_EINVAL); /* no bits */
    assert_int_equal(tool.ops->couple(tool.self, "probe", false), LS_OK);
}

static int send_text(int fd, const char *path, const void *text, size_t len)
{
    struct sockaddr_un a;
    memset(&a, 0, sizeof a);
    a.sun_family = AF_UNIX;
    snprintf(a.sun_path, sizeof a.sun_path, "%s", path);
    return (int)sendto(fd, text, len, 0, (struct sockaddr *)&a, sizeof a);
}

static void send_str(int fd, const char *path, const char *text)
{
    assert_int_equal(send_text(fd, path, text, strlen(text)), (int)strlen(text));
}

static void test_dio_socket(void **state)
{
    (void)state;
    char path[108];
    snprintf(path, sizeof path, "/tmp/ls-simworld-%d.sock", (int)getpid());
    open_world(true, false, path);
    hal_dio_t dio;
    hal_manual_t man;
    hal_sim_world_get_dio(&dio);
    hal_sim_world_get_manual(&man);
    int cli = socket(AF_UNIX, SOCK_DGRAM, 0);
    assert_true(cli >= 0);
    assert_int_equal(hal_dio_unit_count(&dio), 1);
    hal_dio_unit_info_t info;
    assert_int_equal(hal_dio_describe(&dio, 0, &info), LS_OK);
    assert_int_equal(info.input_mask, 0xFFFFu);
    assert_int_equal(info.output_mask, 0xFFFF0000u);
    assert_int_equal(hal_dio_describe(&dio, 1, &info), LS_EINVAL);

    int fd = hal_dio_poll_fd(&dio);
    assert_true(fd >= 0);
    send_str(cli, path, "in 5 0");
    struct pollfd p = { .fd = fd, .events = POLLIN };
    assert_int_equal(poll(&p, 1, 1000), 1);
    uint32_t bits = 0xdead;
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0); /* not applied before drain */
    assert_int_equal(hal_dio_drain_events(&dio), 1);
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0x5);
    send_str(cli, path, "in 0x5 0\n"); /* no change */
    assert_int_equal(hal_dio_drain_events(&dio), 0);
    assert_int_equal(hal_sim_world_malformed_messages(), 0);

    /* malformed: counted and ignored */
    const char *bad[] = { "in",      "in 10000 0",        "in 5 0 7",
                          "in -1 0", "in 5 zz",           "foo 1",
                          "jog 1 2", "jog 1 2 3 4 5 x",   "jog 1 2 3 4 5 1e",
                          "buttons", "buttons 123456789", "jog-stop now",
                          "IN 5 0",  "in 5\x01 0" };
    size_t n_bad = sizeof bad / sizeof bad[0];
    /* in small batches: the kernel queues few datagrams per socket */
    for (size_t i = 0; i < n_bad; i++) {
        send_str(cli, path, bad[i]);
        if (i % 4 == 3) {
            assert_int_equal(hal_dio_drain_events(&dio), 0);
        }
    }
    assert_int_equal(hal_dio_drain_events(&dio), 0);
    char big[400];
    memset(big, 'x', sizeof big);
    assert_int_equal(send_text(cli, path, big, sizeof big), (int)sizeof big);
    assert_int_equal(send_text(cli, path, "", 0), 0);
    assert_int_equal(send_text(cli, path, "in 1\0 0", 7), 7);
    assert_int_equal(hal_dio_drain_events(&dio), 0);
    assert_int_equal(hal_sim_world_malformed_messages(), (uint32_t)n_bad + 3);
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0x5);

    send_str(cli, path, "in 0 1");
    send_str(cli, path, "in\t8000  0 ");
    assert_int_equal(hal_dio_drain_events(&dio), 2);
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0x8004);

    /* outputs */
    assert_int_equal(hal_dio_write(&dio, 0, 1u << 16, 0), LS_OK);
    assert_int_equal(hal_dio_write(&dio, 0, 1u << 3, 0), LS_EINVAL);        /* input bit */
    assert_int_equal(hal_dio_write(&dio, 0, 1u << 17, 1u << 2), LS_EINVAL); /* input bit in off */
    assert_int_equal(hal_dio_write(&dio, 1, 1u << 17, 0), LS_EINVAL);       /* no unit 1 */
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0x18004);
    assert_int_equal(hal_dio_write(&dio, 0, 0, 1u << 16), LS_OK);
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0x8004);
    /* a bit in both on and off ends inactive, on the socket as in write() */
    assert_int_equal(hal_dio_write(&dio, 0, 3u << 16, 1u << 16), LS_OK);
    send_str(cli, path, "in 3 1");
    assert_int_equal(hal_dio_drain_events(&dio), 1);
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
    assert_int_equal(bits, 0x28006);
    assert_int_equal(hal_dio_write(&dio, 0, 0, 1u << 17), LS_OK);
    send_str(cli, path, "in 0 2");
    assert_int_equal(hal_dio_drain_events(&dio), 1);

    /* manual device; a jog keeps a lockstep world running */
    hal_manual_state_t ms;
    assert_int_equal(hal_manual_read(&man, &ms), LS_OK);
    assert_true(ms.present);
    assert_int_equal(ms.buttons, 0);
    assert_int_equal(ms.generation, 1);
    assert_string_equal(man.name, "sim");
    double zero[NJ] = { 0 };
    assert_int_equal(cycle(zero, zero), 0);
    send_str(cli, path, "jog 0.5 -2 0 +0 -0.25 1e-1");
    send_str(cli, path, "buttons 0x43");
    assert_int_equal(hal_dio_drain_events(&dio), 2);
    assert_int_equal(hal_manual_read(&man, &ms), LS_OK);
    const double want[6] = { 0.5, -1.0, 0.0, 0.0, -0.25, 0.1 };
    for (int k = 0; k < 6; k++) {
        assert_true(fabs(ms.twist[k] - want[k]) < 1e-15);
    }
    assert_int_equal(ms.buttons, 3); /* the functions of hal_manual.h only */
    assert_int_equal(cycle(zero, zero), 1);
    send_str(cli, path, "jog-stop");
    assert_int_equal(hal_dio_drain_events(&dio), 1);
    assert_int_equal(hal_manual_read(&man, &ms), LS_OK);
    for (int k = 0; k < 6; k++) {
        assert_true(ms.twist[k] == 0.0);
    }
    assert_int_equal(cycle(zero, zero), 0);
    /* unplugged: not present, nothing held; plugged again: a new generation */
    send_str(cli, path, "unplug");
    send_str(cli, path, "unplug");
    assert_int_equal(hal_dio_drain_events(&dio), 1);
    assert_int_equal(hal_manual_read(&man, &ms), LS_OK);
    assert_false(ms.present);
    assert_int_equal(ms.buttons, 0);
    send_str(cli, path, "plug");
    assert_int_equal(hal_dio_drain_events(&dio), 1);
    assert_int_equal(hal_manual_read(&man, &ms), LS_OK);
    assert_true(ms.present);
    assert_int_equal(ms.generation, 2);
    send_str(cli, path, "plug now");
    assert_int_equal(hal_dio_drain_events(&dio), 0);
    assert_int_equal(hal_sim_world_malformed_messages(), (uint32_t)n_bad + 4);

    close(cli);
    hal_sim_world_close();
    assert_int_equal(access(path, F_OK), -1); /* unlinked */
    assert_int_equal(errno, ENOENT);
    assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_ENODEV);
}

static void test_joint_limits(void **state)
{
    (void)state;
    open_world(false, false, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    /* joints 1 and 5 have ODE stops, 4 and 6 (beyond +-180 deg) only the servo's */
    double beyond[NJ] = { M->q_max_rad[0] + 0.3, 0.0, 0.0, M->q_min_rad[3] - 0.3, M->q_max_rad[4] + 0.3,
                          M->q_max_rad[5] + 0.5 };
    move_to(beyond, 0.5);
    hold(500);
    double q[NJ];
    read_q(q);
    assert_true(fabs(q[0] - M->q_max_rad[0]) < 1e-3);
    assert_true(fabs(q[3] - M->q_min_rad[3]) < 1e-3);
    assert_true(fabs(q[4] - M->q_max_rad[4]) < 1e-3);
    assert_true(fabs(q[5] - M->q_max_rad[5]) < 1e-3);
    /* and the geometry still agrees beyond +-180 deg */
    double T_ode[16], T_fk[16], dp, da;
    assert_int_equal(hal_sim_world_flange_pose(T_ode), LS_OK);
    fk(q, T_fk);
    pose_diff(T_ode, T_fk, &dp, &da);
    assert_true(dp < 1e-4 && da < 1e-4);
}

static void test_brakes_hold_when_disabled(void **state)
{
    (void)state;
    open_world(false, false, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    double target[NJ] = { 0.3, 0.6, 0.4, 0.2, 0.5, 0.1 };
    move_to(target, 0.5);
    hold(200);
    double before[NJ], after[NJ];
    read_q(before);
    assert_int_equal(hal_arm_enable(&arm, false), LS_OK);
    double elsewhere[NJ] = { -1, -1, -1, -1, -1, -1 };
    for (int k = 0; k < 1000; k++) {
        cycle(elsewhere, NULL); /* ignored while disabled */
    }
    read_q(after);
    for (int j = 0; j < NJ; j++) {
        assert_true(fabs(after[j] - before[j]) < 1e-5);
    }
}

static void test_a_braked_joint_holds_while_the_others_move(void **state)
{
    (void)state;
    open_world(false, false, NULL);
    assert_int_equal(hal_sim_world_enable_joint(NJ, true), LS_EINVAL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    double start[NJ] = { 0.3, 0.6, 0.4, 0.2, 0.5, 0.1 };
    move_to(start, 0.5);
    hold(200);
    double before[NJ], after[NJ];
    read_q(before);
    assert_int_equal(hal_sim_world_enable_joint(2, false), LS_OK); /* joint 3 brakes */
    double target[NJ] = { -0.2, 0.3, -0.5, -0.3, 0.2, 0.6 };
    move_to(target, 0.5);
    hold(300);
    read_q(after);
    for (int j = 0; j < NJ; j++) {
        if (j == 2) {
            assert_true(fabs(after[j] - before[j]) < 1e-5);
        } else {
            assert_true(fabs(after[j] - target[j]) < 1e-3);
        }
    }
    /* and the arm's enable() sets every joint again */
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    hold(600);
    read_q(after);
    assert_true(fabs(after[2] - target[2]) < 1e-3);
    hal_sim_world_close();
    assert_int_equal(hal_sim_world_enable_joint(0, true), LS_ENODEV);
}

static void test_joint_torque_is_the_static_gravity_load(void **state)
{
    (void)state;
    double tau[NJ];
    assert_int_equal(hal_sim_world_joint_torque(tau), LS_ENODEV);
    open_world(false, false, NULL);
    assert_int_equal(hal_sim_world_joint_torque(NULL), LS_EINVAL);
    assert_int_equal(hal_sim_world_joint_torque(tau), LS_OK);
    for (int j = 0; j < NJ; j++) {
        assert_true(tau[j] == 0.0); /* no step yet */
    }
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    double q[NJ] = { 0.3, 0.6, 0.4, 0.2, 0.5, 0.1 };
    move_to(q, 0.5);
    hold(500);
    read_q(q);
    assert_int_equal(hal_sim_world_joint_torque(tau), LS_OK);
    /* The oracle: every link's mass at the middle of its segment (frame
     * i-1 to frame i), the 0.1 kg flange plate half its 5 mm thickness
     * inside the flange; the motor holds the moment of their weight. */
    double T[NJ + 1][16], c[NJ + 1][3], m[NJ + 1];
    fk_frames(q, T);
    for (int i = 0; i < NJ; i++) {
        for (int k = 0; k < 3; k++) {
            c[i][k] = (T[i][12 + k] + T[i + 1][12 + k]) / 2.0;
        }
        m[i] = M->link_mass_kg[i];
    }
    for (int k = 0; k < 3; k++) {
        c[NJ][k] = T[NJ][12 + k] - 0.0025 * T[NJ][8 + k];
    }
    m[NJ] = 0.1;
    for (int j = 0; j < NJ; j++) {
        const double *o = &T[j][12], *z = &T[j][8];
        double expect = 0.0;
        for (int b = j; b <= NJ; b++) {
            double r[3] = { c[b][0] - o[0], c[b][1] - o[1], c[b][2] - o[2] };
            double F[3] = { 0.0, 0.0, -9.81 * m[b] };
            double rxF[3] = { r[1] * F[2] - r[2] * F[1], r[2] * F[0] - r[0] * F[2], r[0] * F[1] - r[1] * F[0] };
            expect -= z[0] * rxF[0] + z[1] * rxF[1] + z[2] * rxF[2];
        }
        print_message("joint %d: torque %.4f Nm, gravity load %.4f Nm\n", j + 1, tau[j], expect);
        assert_true(fabs(tau[j] - expect) < 0.005 * fabs(expect) + 0.002);
    }
}

static void *loop_thread(void *arg)
{
    double *fz = arg;
    if (hal_sim_world_attach_thread() != LS_OK) {
        *fz = NAN;
        return NULL;
    }
    double w[6];
    for (int k = 0; k < 300; k++) {
        (void)hal_arm_command(&arm, cmd_q, NULL);
        (void)hal_sim_world_step(NULL, DT);
        (void)laser();
    }
    force(w);
    *fz = w[2];
    return NULL;
}

static void test_control_loop_on_another_thread(void **state)
{
    (void)state;
    assert_int_equal(hal_sim_world_attach_thread(), LS_ENODEV);
    open_world(false, false, NULL);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    double pose[6] = { 0.50, -0.10, 0.25, LS_PI, 0.0, 0.0 }, q[NJ];
    assert_true(ik(pose, q));
    move_to(q, 0.5);
    pose[2] = 0.099; /* 1 mm into the table: about 50 N */
    assert_true(ik(pose, q));
    move_to(q, 0.05);
    pthread_t th;
    double fz = 0.0;
    assert_int_equal(pthread_create(&th, NULL, loop_thread, &fz), 0);
    assert_int_equal(pthread_join(th, NULL), 0);
    assert_true(fabs(fz - 50.0) < 3.0);
}

/* ODE allocation counting: steady-state cycles must not allocate. */
static long ode_allocs;
static void *count_alloc(dsizeint size)
{
    ode_allocs++;
    return malloc(size);
}
static void *count_realloc(void *p, dsizeint oldsize, dsizeint newsize)
{
    (void)oldsize;
    ode_allocs++;
    return realloc(p, newsize);
}
static void count_free(void *p, dsizeint size)
{
    (void)size;
    free(p);
}

static void test_cycles_do_not_allocate(void **state)
{
    (void)state;
    dSetAllocHandler(count_alloc);
    dSetReallocHandler(count_realloc);
    dSetFreeHandler(count_free);
    char path[108];
    snprintf(path, sizeof path, "/tmp/ls-simworld-a%d.sock", (int)getpid());
    open_world(false, true, path);
    long at_open = ode_allocs;
    assert_true(at_open > 0); /* the hooks are live */
    hal_dio_t dio;
    hal_manual_t man;
    hal_tool_t tool;
    hal_sim_world_get_dio(&dio);
    hal_sim_world_get_manual(&man);
    hal_sim_world_get_tool(&tool);
    assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    /* press onto the obstacle (top z 0.20): moves, contacts, sensors, I/O */
    double pose[6] = { 0.60, 0.20, 0.30, LS_PI, 0.0, 0.0 };
    double q[NJ], w[6];
    uint32_t bits;
    hal_manual_state_t ms;
    assert_true(ik(pose, q));
    move_to(q, 0.5);
    pose[2] = 0.195;
    assert_true(ik(pose, q));
    move_to(q, 0.05);
    hold(300);
    bool touching = false;
    assert_int_equal(hal_sim_world_contact(&touching, NULL), 1);
    assert_true(touching);
    force(w);
    assert_true(w[2] > 5.0);
    print_message("allocations: %ld during open+motion, then steady state\n", ode_allocs);
    long before = ode_allocs;
    double up[NJ];
    pose[2] = 0.25;
    assert_true(ik(pose, up));
    move_to(up, 0.2);
    move_to(q, 0.2);
    for (int k = 0; k < 500; k++) {
        cycle(q, NULL);
        force(w);
        (void)laser();
        assert_int_equal(hal_dio_read(&dio, 0, &bits), LS_OK);
        assert_int_equal(hal_dio_write(&dio, 0, (uint32_t)(k & 1) << 16, (uint32_t)(~k & 1) << 16), LS_OK);
        assert_true(hal_dio_drain_events(&dio) >= 0);
        assert_int_equal(hal_manual_read(&man, &ms), LS_OK);
        assert_int_equal(tool.ops->get_bits(tool.self, &bits), LS_OK);
    }
    assert_int_equal(ode_allocs - before, 0);
    hal_sim_world_close();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_open_rejects_bad_config, teardown),
        cmocka_unit_test_teardown(test_geometry_matches_dh, teardown),
        cmocka_unit_test_teardown(test_lockstep_determinism, teardown),
        cmocka_unit_test_teardown(test_tracking, teardown),
        cmocka_unit_test_teardown(test_contact_force_and_laser, teardown),
        cmocka_unit_test_teardown(test_tool_rack, teardown),
        cmocka_unit_test_teardown(test_dio_socket, teardown),
        cmocka_unit_test_teardown(test_joint_limits, teardown),
        cmocka_unit_test_teardown(test_brakes_hold_when_disabled, teardown),
        cmocka_unit_test_teardown(test_a_braked_joint_holds_while_the_others_move, teardown),
        cmocka_unit_test_teardown(test_joint_torque_is_the_static_gravity_load, teardown),
        cmocka_unit_test_teardown(test_control_loop_on_another_thread, teardown),
        cmocka_unit_test_teardown(test_cycles_do_not_allocate, teardown),
    };
    /* e.g. CMOCKA_TEST_FILTER='test_dio*' to run a subset (valgrind) */
    const char *filter = getenv("CMOCKA_TEST_FILTER");
    if (filter != NULL) {
        cmocka_set_test_filter(filter);
    }
    return cmocka_run_group_tests(tests, NULL, NULL);
}
