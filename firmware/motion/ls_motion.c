/* The motion executor and its planners. See ls_motion.h. */
#include "ls_motion.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_math.h"

#define START_TOL_RAD 1e-3
#define END_TOL_S 1e-9
/* While two segments blend, a stop's ramps give each at most this share of
 * its jerk limit, so that the sum of the two stays within the limit whatever
 * the directions of the two motions. */
#define BLEND_STOP_JERK_SHARE 0.5
#define SAMPLE_STEP_M 1e-3
#define SAMPLE_STEP_RAD (0.5 * LS_PI / 180.0)
#define SAMPLE_STEP_S 0.01
#define MAX_SAMPLES 20000

enum { SUB_MOVE = 0, SUB_AUX, SUB_DWELL };
enum { STOP_NONE = 0, STOP_NORMAL, STOP_FAST }; /* ls_motion_t.stop_at_end_ */

static int refuse(char *why, unsigned whylen, int code, const char *fmt, ...) __attribute__((format(printf, 4, 5)));

static int refuse(char *why, unsigned whylen, int code, const char *fmt, ...)
{
    if (why != NULL && whylen > 0) {
        va_list ap;
        va_start(ap, fmt);
        ls_fmt_vtext(why, whylen, fmt, ap);
        va_end(ap);
    }
    return code;
}

static bool finite_n(const double *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (!isfinite(v[i])) {
            return false;
        }
    }
    return true;
}

static bool frac_ok(double f)
{
    return isfinite(f) && f > 0.0 && f <= 1.0;
}

/* ------------------------------------------------------------------ init */

void ls_motion_init(ls_motion_t *m, const ls_robot_model_t *model)
{
    memset(m, 0, sizeof *m);
    m->model = model;
    m->phase = LS_MOTION_IDLE;
    m->following_error_max_rad = LS_MOTION_FOLLOWING_ERROR_RAD;
}

void ls_motion_set_feedback_lag(ls_motion_t *m, uint16_t cycles)
{
    m->lag_cycles_ = cycles < LS_MOTION_LAG_MAX ? cycles : (uint16_t)(LS_MOTION_LAG_MAX - 1u);
    for (unsigned k = 0; k < LS_MOTION_LAG_MAX; k++) {
        memcpy(m->q_hist_[k], m->q_cmd, sizeof m->q_cmd);
    }
}

void ls_motion_feedback_late(ls_motion_t *m, uint16_t extra)
{
    m->late_cycles_ = extra;
}

void ls_motion_ignore_joints(ls_motion_t *m, uint32_t joints)
{
    m->ignored_joints_ = joints;
}

void ls_motion_hold(ls_motion_t *m, const double q[LS_N_JOINTS])
{
    memcpy(m->q_cmd, q, sizeof m->q_cmd);
    for (unsigned k = 0; m->lag_cycles_ > 0u && k < LS_MOTION_LAG_MAX; k++) {
        memcpy(m->q_hist_[k], q, sizeof m->q_cmd); /* a hold starts a new history */
    }
    m->phase = LS_MOTION_IDLE;
    m->blending_ = false;
    m->sub_ = SUB_MOVE;
    m->ramping_ = false;
    m->stop_at_end_ = STOP_NONE;
}

/* -------------------------------------------------------------- planners */

static int check_joint_limits(const ls_robot_model_t *model, const double q[LS_N_JOINTS], char *why, unsigned whylen)
{
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (q[j] > model->q_max_rad[j]) {
            return refuse(why, whylen, LS_ERANGE, "joint %d: %.4g rad beyond its limit %.4g rad", j + 1, q[j],
                          model->q_max_rad[j]);
        }
        if (q[j] < model->q_min_rad[j]) {
            return refuse(why, whylen, LS_ERANGE, "joint %d: %.4g rad beyond its limit %.4g rad", j + 1, q[j],
                          model->q_min_rad[j]);
        }
    }
    return LS_OK;
}

static void seg_clear_motion(ls_motion_seg_t *s, ls_seg_kind_t kind)
{
    /* Point attributes (tag, aux, delay) belong to the caller: keep them. */
    s->kind = kind;
    memset(&s->traj, 0, sizeof s->traj);
    memset(&s->curve, 0, sizeof s->curve);
    memset(&s->path, 0, sizeof s->path);
    s->radius_m = s->angle_rad = s->length_m = s->turn_rad = 0.0;
    s->overlap_s = 0.0;
    memset(s->lim_, 0, sizeof s->lim_);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        s->jerk_scale_[j] = 1.0;
    }
    s->slew_ = false;
}

/* Joint-space segment limits at speed_frac / accel_frac of the model's,
 * jerk also times the segment's jerk scale (blends). */
static void joint_limits(const ls_robot_model_t *model, double speed_frac, double accel_frac,
                         const double jerk_scale[LS_N_JOINTS], ls_traj_limits_t *lim)
{
    memset(lim, 0, sizeof *lim);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        lim->v_max[j] = model->qd_max_rad_s[j] * speed_frac;
        lim->a_max[j] = model->qdd_max_rad_s2[j] * accel_frac;
        lim->j_max[j] = model->qddd_max_rad_s3[j] * accel_frac * (jerk_scale != NULL ? jerk_scale[j] : 1.0);
    }
}

/* The phase of a phase-synchronised joint profile: sigma from 0 to 1, each
 * joint at x0 + (q1 - x0) sigma, within every moving joint's limits (the
 * tightest of limit / |q1 - x0| per derivative). Each joint's axis of *tr is
 * sigma's profile scaled by its distance, so sampling it gives the joint. */
static int phase_profile(const double x0[LS_N_JOINTS], const double q1[LS_N_JOINTS], const ls_traj_limits_t *lim,
                         ls_traj_t *tr)
{
    double vs = INFINITY, as = INFINITY, js = INFINITY;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const double d = fabs(q1[j] - x0[j]);
        if (d > 0.0) {
            vs = fmin(vs, lim->v_max[j] / d);
            as = fmin(as, lim->a_max[j] / d);
            js = fmin(js, lim->j_max[j] / d);
        }
    }
    if (!isfinite(vs)) { /* nothing moves */
        return ls_traj_plan(tr, LS_N_JOINTS, x0, q1, lim);
    }
    ls_traj_axis_t sig;
    const int rc = ls_traj_plan_axis(&sig, 0.0, 1.0, vs, as, js);
    if (rc != LS_OK) {
        return rc;
    }
    memset(tr, 0, sizeof *tr);
    tr->n = LS_N_JOINTS;
    tr->duration_s = sig.T;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        ls_traj_axis_t *ax = &tr->axis[j];
        *ax = sig;
        ax->p0 = x0[j];
        ax->p1 = q1[j];
        ax->dist = q1[j] - x0[j];
        ax->j = sig.j * ax->dist;
    }
    return LS_OK;
}

/* The profile of joint segment s from the joints at x0 to q1 at its stored
 * fractions and jerk scale: phase-synchronised (a straight line in joint
 * space, so that a stop and a resume keep to it), or each joint on its own
 * (slew). The plan itself starts at q0; a resume starts where a stop left
 * the joints. The planner's status on error, and in *failed (when not
 * NULL) the 0-based joint a slew could not plan (-1: the phase). */
static int joint_profile_from(const ls_motion_seg_t *s, const ls_robot_model_t *model, const double x0[LS_N_JOINTS],
                              ls_traj_t *out, int *failed)
{
    ls_traj_limits_t lim;
    joint_limits(model, s->lim_[0], s->lim_[1], s->jerk_scale_, &lim);
    ls_traj_t tr;
    int rc = phase_profile(x0, s->q1, &lim, &tr);
    if (rc != LS_OK) {
        if (failed != NULL) {
            *failed = -1;
        }
        return rc;
    }
    if (s->slew_) {
        tr.duration_s = 0.0;
        for (int j = 0; j < LS_N_JOINTS; j++) {
            rc = ls_traj_plan_axis(&tr.axis[j], x0[j], s->q1[j], lim.v_max[j], lim.a_max[j], lim.j_max[j]);
            if (rc != LS_OK) {
                if (failed != NULL) {
                    *failed = j;
                }
                return rc;
            }
            tr.duration_s = fmax(tr.duration_s, tr.axis[j].T);
        }
    }
    *out = tr;
    return LS_OK;
}

/* Plan the profile of joint segment s (q0, q1 set); see joint_profile_from. */
static int joint_profile(ls_motion_seg_t *s, const ls_robot_model_t *model, int *failed)
{
    return joint_profile_from(s, model, s->q0, &s->traj, failed);
}

int ls_motion_seg_joint(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                        const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why, unsigned whylen)
{
    if (s == NULL || model == NULL || q0 == NULL || q1 == NULL || !finite_n(q0, LS_N_JOINTS) ||
        !finite_n(q1, LS_N_JOINTS)) {
        return refuse(why, whylen, LS_EINVAL, "joint move: missing or non-finite joint values");
    }
    if (!frac_ok(speed_frac) || !frac_ok(accel_frac)) {
        return refuse(why, whylen, LS_EINVAL, "speed %.4g and acceleration %.4g must be in (0, 1] of the maxima",
                      speed_frac, accel_frac);
    }
    int r = check_joint_limits(model, q1, why, whylen);
    if (r < 0) {
        return r;
    }
    seg_clear_motion(s, LS_SEG_JOINT);
    memcpy(s->q0, q0, sizeof s->q0);
    memcpy(s->q1, q1, sizeof s->q1);
    s->lim_[0] = speed_frac;
    s->lim_[1] = accel_frac;
    if (joint_profile(s, model, NULL) != LS_OK) {
        return refuse(why, whylen, LS_EINVAL, "joint move: the trajectory could not be planned");
    }
    return LS_OK;
}

int ls_motion_seg_slew(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                       const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why, unsigned whylen)
{
    /* The synchronised planner checks the arguments and the limits; then
     * each joint gets its own minimum-time profile (and a stop, its own
     * ramp: the joints share no path). */
    int r = ls_motion_seg_joint(s, model, q0, q1, speed_frac, accel_frac, why, whylen);
    if (r < 0) {
        return r;
    }
    s->slew_ = true;
    int failed = -1;
    if (joint_profile(s, model, &failed) != LS_OK) {
        return refuse(why, whylen, LS_EINVAL, "slew: joint %d could not be planned", failed + 1);
    }
    return LS_OK;
}

static void plan_init(ls_motion_plan_t *p, ls_plan_kind_t kind)
{
    p->kind = kind;
    p->prog = NULL;
    p->cycles = 1;
    p->dry_run = false;
    memset(p->one.tag, 0, sizeof p->one.tag);
    p->one.tag_index = 0;
    p->one.point = 0;
    p->one.delay_s = 0.0;
    p->one.blend_frac = 0.0;
    p->one.n_aux = 0;
}

int ls_motion_plan_joint(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                         const double q1[LS_N_JOINTS], double speed_frac, double accel_frac, char *why, unsigned whylen)
{
    if (p == NULL) {
        return refuse(why, whylen, LS_EINVAL, "no plan");
    }
    plan_init(p, LS_PLAN_JOINT);
    int r = ls_motion_seg_joint(&p->one, model, q0, q1, speed_frac, accel_frac, why, whylen);
    if (r < 0) {
        p->kind = LS_PLAN_NONE;
    }
    return r;
}

/* ---- Cartesian geometry ---- */

static void v3_sub(const double a[3], const double b[3], double out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = a[i] - b[i];
    }
}
static double v3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void v3_cross(const double a[3], const double b[3], double out[3])
{
    double c[3] = { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
    memcpy(out, c, sizeof c);
}
static double v3_norm(const double a[3])
{
    return sqrt(v3_dot(a, a));
}

/* Tool-tip pose of the segment at s in [0, 1], base frame. */
static void seg_tip_pose(const ls_motion_seg_t *s, double x, double T[16])
{
    ls_pose_interp(s->P0, s->P1, x, T);
    if (s->kind == LS_SEG_ARC) {
        const double a = s->angle_rad * x;
        const double c = cos(a), sn = sin(a);
        for (int i = 0; i < 3; i++) {
            T[12 + i] = s->centre_m[i] + s->radius_m * (c * s->u[i] + sn * s->v[i]);
        }
    } else if (x >= 1.0) {
        memcpy(T, s->P1, 16 * sizeof(double));
    }
}

/* Joint solution for the tip pose at s, nearest `seed`. */
static int seg_ik(const ls_robot_model_t *model, const ls_motion_seg_t *s, double x, const double seed[LS_N_JOINTS],
                  double q[LS_N_JOINTS])
{
    double T[16], F[16];
    seg_tip_pose(s, x, T);
    ls_pose_mul(T, s->tool_inv, F);
    return ls_kin_ik_nearest(model, F, seed, q);
}

static const char *const axis_name[3] = { "x", "y", "z" };

/* Explain an IK failure at tip pose T: a joint beyond its limit (solved with
 * the limits opened), a singularity, or out of reach. */
static int explain_ik(const ls_robot_model_t *model, const ls_motion_seg_t *s, double x, const double seed[LS_N_JOINTS],
                      int kin_status, char *why, unsigned whylen)
{
    double T[16], F[16];
    seg_tip_pose(s, x, T);
    ls_pose_mul(T, s->tool_inv, F);
    if (kin_status == LS_ELIMITS) {
        ls_robot_model_t wide = *model;
        for (int j = 0; j < LS_N_JOINTS; j++) {
            wide.q_min_rad[j] = -4.0 * LS_PI;
            wide.q_max_rad[j] = 4.0 * LS_PI;
        }
        double q[LS_N_JOINTS];
        if (ls_kin_ik_nearest(&wide, F, seed, q) == LS_OK) {
            char tmp[96];
            if (check_joint_limits(model, q, tmp, sizeof tmp) < 0) {
                return refuse(why, whylen, LS_ERANGE, "%s at tip (%.4g, %.4g, %.4g) m", tmp, T[12], T[13], T[14]);
            }
        }
        return refuse(why, whylen, LS_ERANGE, "no joint solution within the joint limits at tip (%.4g, %.4g, %.4g) m",
                      T[12], T[13], T[14]);
    }
    if (kin_status == LS_ESINGULAR) {
        return refuse(why, whylen, LS_ERANGE,
                      "shoulder singularity (wrist centre on the joint 1 axis) at tip (%.4g, %.4g, %.4g) m: "
                      "use a joint move",
                      T[12], T[13], T[14]);
    }
    return refuse(why, whylen, LS_ERANGE, "unreachable: tip (%.4g, %.4g, %.4g) m is out of the arm's reach", T[12],
                  T[13], T[14]);
}

static int check_box(const ls_robot_model_t *model, const double T[16], char *why, unsigned whylen)
{
    for (int i = 0; i < 3; i++) {
        const double pi = T[12 + i];
        if (pi < model->workspace_min_m[i] || pi > model->workspace_max_m[i]) {
            return refuse(why, whylen, LS_ERANGE,
                          "axis %s: %.4g m beyond the workspace limit %.4g m (base frame, tool tip)", axis_name[i], pi,
                          pi < model->workspace_min_m[i] ? model->workspace_min_m[i] : model->workspace_max_m[i]);
        }
    }
    return LS_OK;
}

static bool cart_still(const ls_motion_seg_t *s)
{
    return !(s->length_m > 1e-9 || s->turn_rad > 1e-9);
}

/* The time law of Cartesian segment s from x0 to 1 under its curve at its
 * jerk scale (the plan: from 0; a resume: from where a stop left it). A
 * segment that does not move has nothing to run. */
static int cart_profile_from(const ls_motion_seg_t *s, double x0, ls_pathspeed_t *out)
{
    return ls_pathspeed_plan(out, &s->curve, cart_still(s) ? 1.0 : x0, s->jerk_scale_[0]);
}

/* Plan the time law of a Cartesian segment over s in [0, 1]. */
static int cart_profile(ls_motion_seg_t *s)
{
    return cart_profile_from(s, 0.0, &s->path);
}

/* ---- path speed under joint limits (docs/architecture.md "Path speed
 * under joint limits") ----
 *
 * The planner samples the path (every 1 mm, 0.5 deg and 10 ms of the
 * requested profile) and halves a step until no joint turns more than
 * STEP_JOINT_MAX_RAD in it; a joint that still does after STEP_SPLITS_MAX
 * halvings (1/4096 of the step) runs away: the path goes through a
 * singularity, where no finite speed helps. Between two samples the joints'
 * dq/ds is their chord; its bound over the stretch adds the stretch's length
 * times the bound of d2q/ds2 (the larger second difference at its ends plus
 * their change), and both get BOUND_MARGIN. ls_pathspeed turns the bounds
 * into the speed-limit curve and the time law. */
#define STEP_JOINT_MAX_RAD 0.01
#define STEP_SPLITS_MAX 12
#define STEP_AIM 0.7 /* a step aims at this share of STEP_JOINT_MAX_RAD */
#define MAX_PATH_SAMPLES (2 * MAX_SAMPLES)
#define BOUND_MARGIN 1.05
#define SLOWED_SHARE 1e-3
#define WRIST_ONLY 0.2 /* joints 1-3 below this share of the motion the arm cannot make: the wrist's */

/* The stretches of one path as they are sampled: the last one waits for
 * the second derivative at its end (the next sample's chord). */
typedef struct {
    ls_pathspeed_curve_t *curve;
    bool pending;
    bool have_d2a;
    double x_end, h;
    double m[LS_N_JOINTS];   /* the pending stretch's chord, dq/ds */
    double d2a[LS_N_JOINTS]; /* d2q/ds2 at its start */
} speed_track_t;

/* The bounds of the pending stretch, d2b the second derivative at its end
 * (NULL: none, the end of the path), into the curve. */
static int track_close(speed_track_t *t, const double *d2b)
{
    ls_pathspeed_stretch_t st = { .s_end = t->x_end };
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const double zero = 0.0;
        const double *a = t->have_d2a ? &t->d2a[j] : d2b != NULL ? &d2b[j] : &zero;
        const double *b = d2b != NULL ? &d2b[j] : a;
        const double change = fabs(*b - *a), d2 = (fmax(fabs(*a), fabs(*b)) + change) * BOUND_MARGIN;
        st.b1[j] = (fabs(t->m[j]) + t->h * d2) * BOUND_MARGIN;
        /* The curvature split by the way the joint goes, when it goes one
         * way all along the stretch (|dq/ds| stays above 0). */
        if (fabs(t->m[j]) > t->h * d2) {
            const double sg = t->m[j] > 0.0 ? 1.0 : -1.0;
            st.b2u[j] = fmax(0.0, fmax(sg * *a, sg * *b) + change) * BOUND_MARGIN;
            st.b2d[j] = fmax(0.0, fmax(-sg * *a, -sg * *b) + change) * BOUND_MARGIN;
        } else {
            st.b2u[j] = st.b2d[j] = d2;
        }
    }
    t->pending = false;
    return ls_pathspeed_curve_add(t->curve, &st);
}

/* A new sample at x (the previous at x - h): the stretch before it waits,
 * the one before that closes. */
static int track_add(speed_track_t *t, double x, double h, const double q_prev[LS_N_JOINTS],
                     const double q[LS_N_JOINTS])
{
    double m[LS_N_JOINTS], d2[LS_N_JOINTS];
    for (int j = 0; j < LS_N_JOINTS; j++) {
        m[j] = (q[j] - q_prev[j]) / h;
    }
    const bool had = t->pending;
    if (had) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            d2[j] = 2.0 * (m[j] - t->m[j]) / (t->h + h);
        }
        const int r = track_close(t, d2);
        if (r < 0) {
            return r;
        }
        memcpy(t->d2a, d2, sizeof d2);
    }
    t->have_d2a = had;
    t->pending = true;
    t->x_end = x;
    t->h = h;
    memcpy(t->m, m, sizeof m);
    return LS_OK;
}

/* x = A^-1 b for a 6x6 A (column-major, as ls_kin's Jacobian), Gaussian
 * elimination with partial pivoting; false when A is singular to working
 * precision. */
static bool solve6(const double A[36], const double b[6], double x[6])
{
    double M[6][7];
    for (int r = 0; r < 6; r++) {
        for (int c = 0; c < 6; c++) {
            M[r][c] = A[c * 6 + r];
        }
        M[r][6] = b[r];
    }
    for (int c = 0; c < 6; c++) {
        int piv = c;
        for (int r = c + 1; r < 6; r++) {
            piv = fabs(M[r][c]) > fabs(M[piv][c]) ? r : piv;
        }
        if (!(fabs(M[piv][c]) > 0.0)) {
            return false;
        }
        for (int k = 0; k < 7; k++) {
            const double t = M[c][k];
            M[c][k] = M[piv][k];
            M[piv][k] = t;
        }
        for (int r = c + 1; r < 6; r++) {
            const double f = M[r][c] / M[c][c];
            for (int k = c; k < 7; k++) {
                M[r][k] -= f * M[c][k];
            }
        }
    }
    for (int r = 5; r >= 0; r--) {
        double t = M[r][6];
        for (int k = r + 1; k < 6; k++) {
            t -= M[r][k] * x[k];
        }
        x[r] = t / M[r][r];
    }
    return true;
}

/* The joint motion the arm at q cannot turn into tool motion: the direction
 * of J's smallest singular value, by inverse iteration on J^T J (plus a
 * tiny ridge so that an exact singularity still solves). */
static void null_direction(const ls_robot_model_t *model, const double q[LS_N_JOINTS], double v[LS_N_JOINTS])
{
    double J[36], A[36], tr = 0.0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        v[j] = 1.0;
    }
    if (ls_kin_jacobian(model, q, J) != LS_OK) {
        return;
    }
    for (int c = 0; c < 6; c++) {
        for (int r = 0; r < 6; r++) {
            double d = 0.0;
            for (int k = 0; k < 6; k++) {
                d += J[r * 6 + k] * J[c * 6 + k];
            }
            A[c * 6 + r] = d;
        }
        tr += A[c * 6 + c];
    }
    for (int c = 0; c < 6; c++) {
        A[c * 6 + c] += 1e-12 * tr;
    }
    for (int it = 0; it < 8; it++) {
        double x[6], n = 0.0;
        if (!solve6(A, v, x)) {
            return;
        }
        for (int j = 0; j < 6; j++) {
            n += x[j] * x[j];
        }
        for (int j = 0; j < 6; j++) {
            v[j] = x[j] / sqrt(n);
        }
    }
}

/* The path runs through a singularity between x_a and x_b (q_a: the last
 * joints before it; the joint that runs away: jr): where, what kind and
 * what to do instead. The kind is read from the motion the arm cannot make
 * there (null_direction): only the wrist's joints: the wrist (joints 4 and
 * 6 in line); else joint 1 more than joints 2 and 3: the shoulder (the
 * wrist centre on the joint 1 axis); else the elbow (stretched or folded). */
static int refuse_singular(const ls_robot_model_t *model, const ls_motion_seg_t *s, double x_a, double x_b,
                           const double q_a[LS_N_JOINTS], int jr, char *why, unsigned whylen)
{
    double v[LS_N_JOINTS];
    null_direction(model, q_a, v);
    const double arm = fmax(fabs(v[1]), fabs(v[2]));
    const char *kind = "elbow", *what = "the arm stretched out or folded", *hint = "keeps the elbow bent";
    if (fmax(fabs(v[0]), arm) < WRIST_ONLY) {
        kind = "wrist";
        what = "joints 4 and 6 in line";
        hint = "tilts the tool";
    } else if (fabs(v[0]) >= arm) {
        kind = "shoulder";
        what = "the wrist centre on the joint 1 axis";
        hint = "passes beside that axis";
    }
    double T[16];
    seg_tip_pose(s, 0.5 * (x_a + x_b), T);
    return refuse(why, whylen, LS_ERANGE,
                  "joint %d runs away at %.0f %% of the path near tip (%.4g, %.4g, %.4g) m: %s singularity (%s) that "
                  "no speed avoids: use a joint move, or a slight detour that %s",
                  jr + 1, 100.0 * x_b, T[12], T[13], T[14], kind, what, hint);
}

/* A joint runs away between x_a and x_b (q_a: the joints before; jr: the
 * one that jumps). Either the arm's configuration ends at a joint's limit
 * (the solution that goes on without a jump lies beyond it: the arm would
 * have to flip), or the path goes through a singularity. Neither is helped
 * by a lower speed. */
static int refuse_runaway(const ls_robot_model_t *model, const ls_motion_seg_t *s, double x_a, double x_b,
                          const double q_a[LS_N_JOINTS], int jr, char *why, unsigned whylen)
{
    ls_robot_model_t wide = *model;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        wide.q_min_rad[j] = -4.0 * LS_PI;
        wide.q_max_rad[j] = 4.0 * LS_PI;
    }
    double T[16], F[16], q[LS_N_JOINTS];
    seg_tip_pose(s, x_b, T);
    ls_pose_mul(T, s->tool_inv, F);
    bool smooth = ls_kin_ik_nearest(&wide, F, q_a, q) == LS_OK;
    for (int j = 0; smooth && j < LS_N_JOINTS; j++) {
        smooth = fabs(q[j] - q_a[j]) <= STEP_JOINT_MAX_RAD;
    }
    for (int j = 0; smooth && j < LS_N_JOINTS; j++) {
        const bool over = q[j] > model->q_max_rad[j], under = q[j] < model->q_min_rad[j];
        if (over || under) {
            return refuse(why, whylen, LS_ERANGE,
                          "joint %d reaches its limit %.4g rad at %.0f %% of the path near tip (%.4g, %.4g, %.4g) m; "
                          "going on needs another arm configuration, a jump no speed allows: use a joint move, or "
                          "start with joint %d turned the other way",
                          j + 1, over ? model->q_max_rad[j] : model->q_min_rad[j], 100.0 * x_b, T[12], T[13], T[14],
                          j + 1);
        }
    }
    return refuse_singular(model, s, x_a, x_b, q_a, jr, why, whylen);
}

/* Time the segment over s in [0, 1] with the slower of the linear and the
 * angular limits, then sample it: workspace box, IK, joint limits, and the
 * joints' speed-limit curve (above), a singularity refused. Fills curve,
 * path and q1. */
static int cart_time_and_check(ls_motion_seg_t *s, const ls_robot_model_t *model, const ls_motion_cart_limits_t *lim,
                               char *why, unsigned whylen)
{
    const double L = s->length_m, A = s->turn_rad;
    double v = INFINITY, a = INFINITY, j = INFINITY;
    if (L > 1e-9) {
        v = fmin(v, lim->v_lin_m_s / L);
        a = fmin(a, lim->a_lin_m_s2 / L);
        j = fmin(j, lim->j_lin_m_s3 / L);
    }
    if (A > 1e-9) {
        v = fmin(v, lim->v_ang_rad_s / A);
        a = fmin(a, lim->a_ang_rad_s2 / A);
        j = fmin(j, lim->j_ang_rad_s3 / A);
    }
    const bool still = cart_still(s);
    if (still) {
        v = a = j = 1.0;
    }
    s->lim_[0] = v;
    s->lim_[1] = a;
    s->lim_[2] = j;
    s->lim_[3] = lim->joint_speed_frac;
    double vel[LS_N_JOINTS];
    for (int jn = 0; jn < LS_N_JOINTS; jn++) {
        vel[jn] = model->qd_max_rad_s[jn] * lim->joint_speed_frac;
    }
    ls_traj_axis_t plain;
    if (ls_traj_plan_axis(&plain, 0.0, 1.0, v, a, j) != LS_OK ||
        ls_pathspeed_curve_begin(&s->curve, v, a, j, vel, model->qdd_max_rad_s2) != LS_OK) {
        return refuse(why, whylen, LS_EINVAL, "Cartesian move: the profile could not be planned");
    }

    /* The target first, so an unreachable goal is reported as such rather
     * than as the joints running away on the way to the edge of the reach. */
    {
        double F[16], sols[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
        int n_sol = 0;
        if (check_box(model, s->P1, why, whylen) < 0) {
            return LS_ERANGE;
        }
        ls_pose_mul(s->P1, s->tool_inv, F);
        const int ks = ls_kin_ik_all(model, F, sols, &n_sol);
        if (ks != LS_OK && ks != LS_ESINGULAR && ks != LS_ELIMITS) {
            return explain_ik(model, s, 1.0, s->q0, ks, why, whylen);
        }
    }
    /* Sample densely enough for 1 mm, 0.5 deg and 10 ms of the requested
     * profile, and halve a step where a joint turns fast. */
    const double n_d = fmax(fmax(L / SAMPLE_STEP_M, A / SAMPLE_STEP_RAD), plain.T / SAMPLE_STEP_S);
    const double h0 = 1.0 / fmax(1.0, fmin(ceil(n_d), (double)MAX_SAMPLES));
    const double h_min = ldexp(h0, -STEP_SPLITS_MAX);
    speed_track_t tr = { .curve = &s->curve };
    double q_prev[LS_N_JOINTS], T[16], x = 0.0, h = h0;
    memcpy(q_prev, s->q0, sizeof q_prev);
    seg_tip_pose(s, 0.0, T);
    if (check_box(model, T, why, whylen) < 0) {
        return LS_ERANGE;
    }
    for (int n = 0; x < 1.0; n++) {
        if (n > MAX_PATH_SAMPLES) {
            return refuse(why, whylen, LS_ERANGE, "the path needs more than %d samples: split it into shorter moves",
                          MAX_PATH_SAMPLES);
        }
        const double xn = 1.0 - (x + h) < 0.5 * h ? 1.0 : x + h; /* no sliver of a step at the end */
        seg_tip_pose(s, xn, T);
        int r = check_box(model, T, why, whylen);
        if (r < 0) {
            return r;
        }
        double q[LS_N_JOINTS];
        const int ks = seg_ik(model, s, xn, q_prev, q);
        if (ks == LS_ESINGULAR) {
            return refuse_singular(model, s, x, xn, q_prev, 0, why, whylen);
        }
        if (ks != LS_OK) {
            return explain_ik(model, s, xn, q_prev, ks, why, whylen);
        }
        int fastest = 0;
        for (int jn = 1; jn < LS_N_JOINTS; jn++) {
            fastest = fabs(q[jn] - q_prev[jn]) > fabs(q[fastest] - q_prev[fastest]) ? jn : fastest;
        }
        if (!still && fabs(q[fastest] - q_prev[fastest]) > STEP_JOINT_MAX_RAD) {
            if (h > h_min) {
                h *= 0.5;
                continue;
            }
            return refuse_runaway(model, s, x, xn, q_prev, fastest, why, whylen);
        }
        if (!still && track_add(&tr, xn, xn - x, q_prev, q) != LS_OK) {
            return refuse(why, whylen, LS_EINVAL, "Cartesian move: its speed limits could not be planned");
        }
        /* the next step where the fastest joint, as fast as in this one,
         * turns STEP_AIM of the most (fewer steps halved and tried again) */
        const double dq = fabs(q[fastest] - q_prev[fastest]);
        h = fmin(h0, dq > 0.0 ? STEP_AIM * STEP_JOINT_MAX_RAD * (xn - x) / dq : 2.0 * (xn - x));
        h = fmax(h, h_min);
        memcpy(q_prev, q, sizeof q_prev);
        x = xn;
    }
    if (still) {
        const ls_pathspeed_stretch_t st = { .s_end = 1.0 };
        (void)ls_pathspeed_curve_add(&s->curve, &st);
    } else if (track_close(&tr, NULL) != LS_OK || ls_pathspeed_curve_finish(&s->curve) != LS_OK) {
        return refuse(why, whylen, LS_EINVAL, "Cartesian move: its speed limits could not be planned");
    }
    memcpy(s->q1, q_prev, sizeof s->q1);
    if (cart_profile(s) != LS_OK) {
        return refuse(why, whylen, LS_EINVAL, "Cartesian move: the profile could not be planned");
    }
    return LS_OK;
}

static bool cart_lim_ok(const ls_motion_cart_limits_t *l)
{
    return l != NULL && isfinite(l->v_lin_m_s) && l->v_lin_m_s > 0.0 && isfinite(l->a_lin_m_s2) &&
           l->a_lin_m_s2 > 0.0 && isfinite(l->j_lin_m_s3) && l->j_lin_m_s3 > 0.0 && isfinite(l->v_ang_rad_s) &&
           l->v_ang_rad_s > 0.0 && isfinite(l->a_ang_rad_s2) && l->a_ang_rad_s2 > 0.0 && isfinite(l->j_ang_rad_s3) &&
           l->j_ang_rad_s3 > 0.0 && frac_ok(l->joint_speed_frac);
}

static int cart_start(ls_motion_seg_t *s, ls_seg_kind_t kind, const ls_robot_model_t *model,
                      const double q0[LS_N_JOINTS], const double tool[16], const double tip1[16],
                      const ls_motion_cart_limits_t *lim, char *why, unsigned whylen)
{
    if (s == NULL || model == NULL || q0 == NULL || tool == NULL || tip1 == NULL || !finite_n(q0, LS_N_JOINTS) ||
        !finite_n(tool, 16) || !finite_n(tip1, 16)) {
        return refuse(why, whylen, LS_EINVAL, "Cartesian move: missing or non-finite values");
    }
    if (!cart_lim_ok(lim)) {
        return refuse(why, whylen, LS_EINVAL, "Cartesian move: speed and acceleration limits must be > 0");
    }
    seg_clear_motion(s, kind);
    memcpy(s->q0, q0, sizeof s->q0);
    double F0[16];
    ls_kin_fk(model, q0, F0);
    ls_pose_mul(F0, tool, s->P0);
    memcpy(s->P1, tip1, sizeof s->P1);
    ls_pose_inv(tool, s->tool_inv);
    s->turn_rad = ls_pose_angle(s->P0, s->P1);
    return LS_OK;
}

int ls_motion_seg_line(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                       const double tool[16], const double tip1[16], const ls_motion_cart_limits_t *lim, char *why,
                       unsigned whylen)
{
    int r = cart_start(s, LS_SEG_LINE, model, q0, tool, tip1, lim, why, whylen);
    if (r < 0) {
        return r;
    }
    s->length_m = ls_pose_dist(s->P0, s->P1);
    return cart_time_and_check(s, model, lim, why, whylen);
}

/* Circumcircle of p0, pv, p1 (the circle through the three points): centre,
 * in-plane unit vectors u (towards p0) and v (90 degrees ahead of u in the
 * direction p0 -> pv -> p1), radius and the angle from p0 to p1 (0, 2 pi].
 * LS_EGEOM when the points are collinear or coincide. */
static int circumcircle(const double p0[3], const double pv[3], const double p1[3], double centre[3], double u[3],
                        double v[3], double *radius, double *angle)
{
    double a[3], b[3], n[3];
    v3_sub(pv, p0, a);
    v3_sub(p1, p0, b);
    v3_cross(a, b, n);
    const double nn = v3_norm(n), la = v3_norm(a), lb = v3_norm(b);
    double c[3];
    v3_sub(p1, pv, c);
    const double lc = v3_norm(c);
    /* Collinear when the arc point lies within 0.1 mm of the line through
     * start and goal: the circle would be huge and ill-defined by rounding. */
    if (la < 1e-6 || lb < 1e-6 || lc < 1e-6 || nn / lb < 1e-4) {
        return LS_EGEOM;
    }
    /* centre = p0 + (|a|^2 (b x n) + |b|^2 (n x a)) / (2 |n|^2) */
    double bxn[3], nxa[3];
    v3_cross(b, n, bxn);
    v3_cross(n, a, nxa);
    for (int i = 0; i < 3; i++) {
        centre[i] = p0[i] + (la * la * bxn[i] + lb * lb * nxa[i]) / (2.0 * nn * nn);
    }
    double r0[3], r1[3], w[3];
    v3_sub(p0, centre, r0);
    v3_sub(p1, centre, r1);
    *radius = v3_norm(r0);
    for (int i = 0; i < 3; i++) {
        u[i] = r0[i] / *radius;
        w[i] = n[i] / nn;
    }
    v3_cross(w, u, v);
    double ang = atan2(v3_dot(r1, v), v3_dot(r1, u));
    if (ang <= 0.0) {
        ang += 2.0 * LS_PI;
    }
    *angle = ang;
    return LS_OK;
}

int ls_motion_arc_split(const double p0[3], const double pv[3], const double p1[3], double mid_a[3], double mid_b[3])
{
    double c[3], u[3], v[3], r, ang;
    if (p0 == NULL || pv == NULL || p1 == NULL || mid_a == NULL || mid_b == NULL || !finite_n(p0, 3) ||
        !finite_n(pv, 3) || !finite_n(p1, 3)) {
        return LS_EINVAL;
    }
    if (circumcircle(p0, pv, p1, c, u, v, &r, &ang) < 0) {
        return LS_EGEOM;
    }
    double d[3];
    v3_sub(pv, c, d);
    double av = atan2(v3_dot(d, v), v3_dot(d, u));
    if (av <= 0.0) {
        av += 2.0 * LS_PI;
    }
    const double ta = 0.5 * av, tb = 0.5 * (av + ang);
    for (int i = 0; i < 3; i++) {
        mid_a[i] = c[i] + r * (cos(ta) * u[i] + sin(ta) * v[i]);
        mid_b[i] = c[i] + r * (cos(tb) * u[i] + sin(tb) * v[i]);
    }
    return LS_OK;
}

int ls_motion_seg_arc(ls_motion_seg_t *s, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                      const double tool[16], const double tip_via[16], const double tip1[16],
                      const ls_motion_cart_limits_t *lim, char *why, unsigned whylen)
{
    if (tip_via == NULL || !finite_n(tip_via, 16)) {
        return refuse(why, whylen, LS_EINVAL, "arc: missing or non-finite arc point");
    }
    int r = cart_start(s, LS_SEG_ARC, model, q0, tool, tip1, lim, why, whylen);
    if (r < 0) {
        return r;
    }
    const int g =
        circumcircle(&s->P0[12], &tip_via[12], &s->P1[12], s->centre_m, s->u, s->v, &s->radius_m, &s->angle_rad);
    if (g < 0) {
        return refuse(why, whylen, LS_EGEOM,
                      "arc: start, arc point and goal are collinear or coincide (no unique circle); use a line");
    }
    s->length_m = s->radius_m * s->angle_rad;
    return cart_time_and_check(s, model, lim, why, whylen);
}

/* A Cartesian segment that its joints slow down: a capped zone it cruises
 * at, or ramps below the requested acceleration, and a duration that shows
 * it (longer than requested by more than SLOWED_SHARE). O(zones). */
bool ls_motion_seg_slowdown(const ls_motion_seg_t *s, ls_motion_slowdown_t *out)
{
    ls_pathspeed_why_t w;
    ls_traj_axis_t plain;
    if (s == NULL || s->kind == LS_SEG_JOINT || cart_still(s) || !ls_pathspeed_slowed(&s->curve, &s->path, &w) ||
        ls_traj_plan_axis(&plain, 0.0, 1.0, s->lim_[0], s->lim_[1], s->lim_[2] * s->jerk_scale_[0]) != LS_OK ||
        !(s->path.duration_s > plain.T * (1.0 + SLOWED_SHARE))) {
        return false;
    }
    if (out != NULL) {
        out->speed_frac = w.frac;
        out->from = w.s_from;
        out->to = w.s_to;
        out->accel_frac = w.a_frac;
        out->joint = (w.frac < 1.0 ? w.joint : w.a_joint) + 1;
        out->velocity = w.frac < 1.0 && w.limit == LS_PATHSPEED_VELOCITY;
        out->duration_s = s->path.duration_s;
        out->requested_s = plain.T;
    }
    return true;
}

int ls_motion_seg_check_speed(const ls_motion_seg_t *s, char *why, unsigned whylen)
{
    if (s == NULL || s->kind == LS_SEG_JOINT || cart_still(s)) {
        return LS_OK;
    }
    int worst = -1;
    for (int k = 0; k < s->curve.n; k++) {
        if (s->curve.zone[k].v_max < s->curve.v_req * (1.0 - 1e-9) &&
            (worst < 0 || s->curve.zone[k].v_max < s->curve.zone[worst].v_max)) {
            worst = k;
        }
    }
    if (worst < 0) {
        return LS_OK;
    }
    const ls_pathspeed_zone_t *z = &s->curve.zone[worst];
    return refuse(why, whylen, LS_ERANGE,
                  "joint %d would pass its %s limit at %.0f %% of the line; this move keeps its speed: give at most "
                  "%.3g %% of it",
                  z->joint + 1, z->limit == LS_PATHSPEED_VELOCITY ? "velocity" : "acceleration",
                  100.0 * (worst > 0 ? s->curve.zone[worst - 1].s_end : 0.0), 100.0 * z->v_max / s->curve.v_req);
}

int ls_motion_slowdown_text(const ls_motion_slowdown_t *d, char *text, unsigned len)
{
    if (d == NULL) {
        return refuse(text, len, 0, "%s", "");
    }
    if (d->speed_frac < 1.0) {
        return ls_fmt_print(text, len,
                            "running at %.3g %% of the requested speed between %.0f %% and %.0f %% of the path: "
                            "joint %d at its %s limit (%.3g s instead of %.3g s)",
                            100.0 * d->speed_frac, 100.0 * d->from, 100.0 * d->to, d->joint,
                            d->velocity ? "velocity" : "acceleration", d->duration_s, d->requested_s);
    }
    return ls_fmt_print(text, len,
                        "accelerating at %.3g %% of the requested rate: joint %d at its acceleration limit (%.3g s "
                        "instead of %.3g s)",
                        100.0 * d->accel_frac, d->joint, d->duration_s, d->requested_s);
}

int ls_motion_plan_line(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                        const double tool[16], const double tip1[16], const ls_motion_cart_limits_t *lim, char *why,
                        unsigned whylen)
{
    if (p == NULL) {
        return refuse(why, whylen, LS_EINVAL, "no plan");
    }
    plan_init(p, LS_PLAN_LINE);
    int r = ls_motion_seg_line(&p->one, model, q0, tool, tip1, lim, why, whylen);
    if (r < 0) {
        p->kind = LS_PLAN_NONE;
    }
    return r;
}

int ls_motion_plan_arc(ls_motion_plan_t *p, const ls_robot_model_t *model, const double q0[LS_N_JOINTS],
                       const double tool[16], const double tip_via[16], const double tip1[16],
                       const ls_motion_cart_limits_t *lim, char *why, unsigned whylen)
{
    if (p == NULL) {
        return refuse(why, whylen, LS_EINVAL, "no plan");
    }
    plan_init(p, LS_PLAN_ARC);
    int r = ls_motion_seg_arc(&p->one, model, q0, tool, tip_via, tip1, lim, why, whylen);
    if (r < 0) {
        p->kind = LS_PLAN_NONE;
    }
    return r;
}

int ls_motion_plan_path(ls_motion_plan_t *p, const ls_motion_program_t *prog, int32_t cycles, bool dry_run,
                        const char *name)
{
    if (p == NULL || prog == NULL || prog->n < 1 || prog->n >= LS_MOTION_MAX_SEGS || cycles < 1) {
        return LS_EINVAL;
    }
    plan_init(p, LS_PLAN_PATH);
    p->prog = prog;
    p->cycles = cycles;
    p->dry_run = dry_run;
    ls_fmt_print(p->name, sizeof p->name, "%s", name != NULL ? name : "");
    return LS_OK;
}

/* ---- blending (ls_motion.h, docs/architecture.md "Blended paths") ---- */

#define BLEND_SAMPLE_S 1e-3

static bool seg_moves(const ls_motion_seg_t *s)
{
    if (s->kind != LS_SEG_JOINT) {
        return !cart_still(s);
    }
    for (int j = 0; j < s->traj.n; j++) {
        if (s->traj.axis[j].dist != 0.0) {
            return true;
        }
    }
    return false;
}

/* a may blend into b: a point without auxiliary commands or dwell, joint
 * into joint or line into line, both moving. */
static bool blend_applies(const ls_motion_seg_t *a, const ls_motion_seg_t *b, double frac)
{
    if (b == NULL || !(frac > 0.0) || a->n_aux > 0 || a->delay_s > 0.0) {
        return false;
    }
    const bool same =
        (a->kind == LS_SEG_JOINT && b->kind == LS_SEG_JOINT) || (a->kind == LS_SEG_LINE && b->kind == LS_SEG_LINE);
    return same && seg_moves(a) && seg_moves(b);
}

/* The shortest of a's last jerk phase and b's first one over the moving
 * axes: inside it each motion has one constant jerk. */
static double blend_window_s(const ls_motion_seg_t *a, const ls_motion_seg_t *b)
{
    if (a->kind != LS_SEG_JOINT) {
        return fmin(ls_pathspeed_last_jerk_s(&a->path), ls_pathspeed_first_jerk_s(&b->path));
    }
    double w = INFINITY;
    for (int j = 0; j < a->traj.n; j++) {
        if (a->traj.axis[j].dist != 0.0) {
            w = fmin(w, a->traj.axis[j].t[6]);
        }
    }
    for (int j = 0; j < b->traj.n; j++) {
        if (b->traj.axis[j].dist != 0.0) {
            w = fmin(w, b->traj.axis[j].t[0]);
        }
    }
    return isfinite(w) ? w : 0.0;
}

void ls_motion_seg_blend(ls_motion_seg_t *a, const ls_motion_seg_t *b, double frac)
{
    if (a == NULL) {
        return;
    }
    a->overlap_s = 0.0;
    if (!blend_applies(a, b, frac)) {
        return;
    }
    a->overlap_s = (frac > 1.0 ? 1.0 : frac) * blend_window_s(a, b);
}

/* Linear jerk of a line segment's profile (m/s^3). */
static double line_jerk(const ls_motion_seg_t *s)
{
    return s->path.j * s->length_m;
}

double ls_motion_seg_blend_dev_m(const ls_motion_seg_t *a, const ls_motion_seg_t *b)
{
    if (a == NULL || b == NULL || !(a->overlap_s > 0.0)) {
        return 0.0;
    }
    if (a->kind != LS_SEG_LINE) {
        return NAN;
    }
    const double t = a->overlap_s;
    return fmax(line_jerk(a), line_jerk(b)) * t * t * t / 6.0;
}

/* The jerk scale per axis that keeps the sum of the two motions' jerks
 * within the larger of their limits (ls_motion_prog_blend). */
static void blend_jerk_scale(const ls_motion_seg_t *a, const ls_motion_seg_t *b, double k[LS_N_JOINTS])
{
    for (int j = 0; j < LS_N_JOINTS; j++) {
        k[j] = 1.0;
    }
    if (a->kind == LS_SEG_JOINT) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            if (a->traj.axis[j].dist * b->traj.axis[j].dist > 0.0) {
                k[j] = 0.5; /* both jerks push the joint the same way */
            }
        }
        return;
    }
    if (a->length_m > 1e-9 && b->length_m > 1e-9) {
        double da[3], db[3];
        v3_sub(&a->P1[12], &a->P0[12], da);
        v3_sub(&b->P1[12], &b->P0[12], db);
        const double c = v3_dot(da, db) / (v3_norm(da) * v3_norm(db));
        /* |Ja da + Jb db| <= J max(1, 2 cos(theta / 2)), 2 cos(theta / 2) = sqrt(2 (1 + cos theta)) */
        k[0] = 1.0 / fmax(1.0, sqrt(fmax(0.0, 2.0 * (1.0 + c))));
    }
    if (a->turn_rad > 1e-9 && b->turn_rad > 1e-9) {
        /* half of the angular jerk for the two rotations' own jerks, half
         * for the products of the composition (blend_cap_rotation) */
        k[0] = fmin(k[0], 0.25);
    }
}

/* Two turning lines: the composed rotation R = Ra(t) Rb0^T Rb(t) has, with
 * w, al, je the two rotations' angular speeds, accelerations and jerks,
 *   |accel| <= al_a + al_b + w_a w_b
 *   |jerk|  <= je_a + je_b + al_a w_b + 2 w_a al_b + w_a^2 w_b
 * (docs/architecture.md "Blended paths"). In the window w <= J T^2 / 2 and
 * al <= J T; shorten the overlap T until both fit the larger of the two
 * segments' angular limits, at most 40 steps of 0.8 (else no blend). */
static void blend_cap_rotation(ls_motion_seg_t *a, const ls_motion_seg_t *b)
{
    if (!(a->turn_rad > 1e-9 && b->turn_rad > 1e-9)) {
        return;
    }
    const double ja = a->path.j * a->turn_rad, jb = b->path.j * b->turn_rad;
    const double a_lim = fmax(a->lim_[1] * a->turn_rad, b->lim_[1] * b->turn_rad);
    const double j_lim = fmax(a->lim_[2] * a->turn_rad, b->lim_[2] * b->turn_rad);
    double t = a->overlap_s;
    for (int i = 0; i < 40; i++, t *= 0.8) {
        const double wa = ja * t * t / 2.0, wb = jb * t * t / 2.0;
        const double acc = fmax(ja, jb) * t + wa * wb;
        const double jerk = ja + jb + ja * t * wb + 2.0 * wa * jb * t + wa * wa * wb;
        if (acc <= a_lim && jerk <= j_lim) {
            a->overlap_s = t;
            return;
        }
    }
    a->overlap_s = 0.0;
}

/* Re-plan a segment's profile at its jerk scale (same path, same q1). */
static int seg_replan(ls_motion_seg_t *s, const ls_robot_model_t *model)
{
    if (s->kind == LS_SEG_JOINT) {
        return joint_profile(s, model, NULL);
    }
    return s->kind == LS_SEG_LINE ? cart_profile(s) : LS_OK;
}

#define NO_SEGMENT (-1) /* blend_next: a blends into nothing */

/* The segment b that a = seg[i] blends into (ls_motion_prog_blend), or NO_SEGMENT. */
static int blend_next(const ls_motion_program_t *prog, int32_t cycles, int i)
{
    const int n = prog->n;
    if (i < n - 1) {
        return i + 1;
    }
    if (cycles > 1 && i == n - 1) {
        return n;
    }
    if (cycles > 1 && i == n) {
        return n > 1 ? 1 : n;
    }
    return NO_SEGMENT;
}

/* The tool-tip pose of a at xa blended with b at xb: positions added (b's
 * displacement on top of a), b's rotation since its start composed onto a's. */
static void blend_pose(const ls_motion_seg_t *a, double xa, const ls_motion_seg_t *b, double xb, double T[16])
{
    double Ta[16], Tb[16], B0inv[16], D[16];
    seg_tip_pose(a, xa, Ta);
    seg_tip_pose(b, xb, Tb);
    ls_pose_inv(b->P0, B0inv);
    ls_pose_mul(B0inv, Tb, D);
    ls_pose_mul(Ta, D, T);
    for (int i = 0; i < 3; i++) {
        T[12 + i] = Ta[12 + i] + Tb[12 + i] - b->P0[12 + i];
    }
}

/* Sample a line blend every BLEND_SAMPLE_S: workspace box, a joint solution
 * and joint speeds within the larger joint speed fraction of the two. */
static int blend_check(const ls_robot_model_t *model, const ls_motion_seg_t *a, const ls_motion_seg_t *b, char *why,
                       unsigned whylen)
{
    const double t0 = a->path.duration_s - a->overlap_s;
    const int n = (int)fmax(1.0, ceil(a->overlap_s / BLEND_SAMPLE_S));
    const double dt = a->overlap_s / n, jsf = fmax(a->lim_[3], b->lim_[3]);
    double q_prev[LS_N_JOINTS];
    memcpy(q_prev, a->q1, sizeof q_prev);
    for (int k = 0; k <= n; k++) {
        double xa, xb, T[16], F[16], q[LS_N_JOINTS];
        ls_pathspeed_sample(&a->path, t0 + dt * k, &xa, NULL, NULL);
        ls_pathspeed_sample(&b->path, dt * k, &xb, NULL, NULL);
        blend_pose(a, xa, b, xb, T);
        char tmp[112];
        if (check_box(model, T, tmp, sizeof tmp) < 0) {
            return refuse(why, whylen, LS_ERANGE, "point %d: its blend leaves the workspace (%s)", a->point, tmp);
        }
        ls_pose_mul(T, a->tool_inv, F);
        if (ls_kin_ik_nearest(model, F, k == 0 ? a->q1 : q_prev, q) != LS_OK) {
            return refuse(why, whylen, LS_ERANGE,
                          "point %d: no joint solution on its blend at tip (%.4g, %.4g, "
                          "%.4g) m",
                          a->point, T[12], T[13], T[14]);
        }
        for (int j = 0; k > 0 && j < LS_N_JOINTS; j++) {
            const double qd = fabs(q[j] - q_prev[j]) / dt, lim = model->qd_max_rad_s[j] * jsf;
            if (qd > lim) {
                return refuse(why, whylen, LS_ERANGE,
                              "point %d: joint %d at %.4g rad/s on its blend, beyond "
                              "its limit %.4g rad/s",
                              a->point, j + 1, qd, lim);
            }
        }
        memcpy(q_prev, q, sizeof q_prev);
    }
    return LS_OK;
}

int ls_motion_prog_blend(ls_motion_program_t *prog, const ls_robot_model_t *model, int32_t cycles, char *why,
                         unsigned whylen)
{
    if (prog == NULL || model == NULL || prog->n < 1 || prog->n >= LS_MOTION_MAX_SEGS || cycles < 1) {
        return refuse(why, whylen, LS_EINVAL, "blend: no program");
    }
    const int last = cycles > 1 ? prog->n : prog->n - 1;
    for (int i = 0; i <= last; i++) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            prog->seg[i].jerk_scale_[j] = 1.0;
        }
    }
    for (int i = 0; i <= last; i++) {
        const int nb = blend_next(prog, cycles, i);
        ls_motion_seg_t *a = &prog->seg[i];
        if (nb >= 0 && blend_applies(a, &prog->seg[nb], a->blend_frac)) {
            double k[LS_N_JOINTS];
            blend_jerk_scale(a, &prog->seg[nb], k);
            for (int j = 0; j < LS_N_JOINTS; j++) {
                a->jerk_scale_[j] = fmin(a->jerk_scale_[j], k[j]);
                prog->seg[nb].jerk_scale_[j] = fmin(prog->seg[nb].jerk_scale_[j], k[j]);
            }
        }
    }
    for (int i = 0; i <= last; i++) {
        if (seg_replan(&prog->seg[i], model) != 0) {
            return refuse(why, whylen, LS_EINVAL, "point %d: its profile could not be re-planned for a blend",
                          prog->seg[i].point);
        }
    }
    for (int i = 0; i <= last; i++) {
        const int nb = blend_next(prog, cycles, i);
        ls_motion_seg_t *a = &prog->seg[i];
        ls_motion_seg_blend(a, nb >= 0 ? &prog->seg[nb] : NULL, a->blend_frac);
        if (a->overlap_s > 0.0 && a->kind == LS_SEG_LINE) {
            blend_cap_rotation(a, &prog->seg[nb]);
        }
        if (a->overlap_s > 0.0 && a->kind == LS_SEG_LINE) {
            int r = blend_check(model, a, &prog->seg[nb], why, whylen);
            if (r < 0) {
                return r;
            }
        }
    }
    return LS_OK;
}

/* -------------------------------------------------------------- executor */

static uint16_t plan_nsegs(const ls_motion_plan_t *p)
{
    return p->kind == LS_PLAN_PATH ? p->prog->n : 1;
}

static const ls_motion_seg_t *plan_seg(const ls_motion_plan_t *p, uint16_t i, int32_t cycle)
{
    if (p->kind != LS_PLAN_PATH) {
        return &p->one;
    }
    if (i == 0 && cycle > 1) {
        return &p->prog->seg[p->prog->n];
    }
    return &p->prog->seg[i];
}

/* The segment after (i, cycle), or NULL at the end of the plan. */
static const ls_motion_seg_t *next_seg(const ls_motion_t *m)
{
    uint16_t n = plan_nsegs(&m->plan);
    if (m->seg_i_ + 1 < n) {
        return plan_seg(&m->plan, (uint16_t)(m->seg_i_ + 1), m->cycle_);
    }
    if (m->cycle_ < m->plan.cycles) {
        return plan_seg(&m->plan, 0, m->cycle_ + 1);
    }
    return NULL;
}

static ls_motion_event_t *push_event(ls_motion_t *m, ls_motion_events_t *ev, ls_motion_event_kind_t kind)
{
    if (ev == NULL || ev->n >= LS_MOTION_MAX_EVENTS) {
        return NULL;
    }
    ls_motion_event_t *e = &ev->ev[ev->n++];
    memset(e, 0, sizeof *e);
    e->kind = kind;
    e->ref_seq = m->plan.ref_seq;
    memcpy(e->name, m->plan.name, sizeof e->name);
    e->index = m->seg_i_;
    e->cycle = m->cycle_;
    memcpy(e->q_rad, m->q_cmd, sizeof e->q_rad);
    return e;
}

static void fault(ls_motion_t *m, ls_motion_events_t *ev, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static void fault(ls_motion_t *m, ls_motion_events_t *ev, const char *fmt, ...)
{
    ls_motion_event_t *e = push_event(m, ev, LS_MEV_FAULT);
    if (e != NULL) {
        va_list ap;
        va_start(ap, fmt);
        ls_fmt_vprint(e->text, sizeof e->text, fmt, ap);
        va_end(ap);
    }
    m->phase = LS_MOTION_IDLE;
    m->blending_ = false;
    m->sub_ = SUB_MOVE;
    m->ramping_ = false;
    m->stop_at_end_ = STOP_NONE;
}

int ls_motion_start(ls_motion_t *m, const ls_motion_plan_t *p)
{
    if (m->phase != LS_MOTION_IDLE) {
        return LS_ESTATE;
    }
    if (p == NULL || p->kind == LS_PLAN_NONE || (p->kind == LS_PLAN_PATH && (p->prog == NULL || p->cycles < 1))) {
        return LS_EINVAL;
    }
    const ls_motion_seg_t *first = plan_seg(p, 0, 1);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (fabs(first->q0[j] - m->q_cmd[j]) > START_TOL_RAD) {
            return LS_EINVAL;
        }
    }
    m->plan = *p;
    m->seg_i_ = 0;
    m->cycle_ = 1;
    m->t_s = 0.0;
    m->blending_ = false;
    m->t_next_s_ = 0.0;
    m->sub_ = SUB_MOVE;
    m->aux_wait_ = false;
    m->ramping_ = false;
    m->off_plan_[0] = m->off_plan_[1] = false;
    m->slow_told_ = false;
    m->stop_at_end_ = STOP_NONE;
    m->phase = LS_MOTION_RUNNING;
    return 0;
}

/* A joint segment other than a slew moves along a straight line in joint
 * space, parameterised by its phase sigma (phase_profile). */
static bool seg_phased(const ls_motion_seg_t *s)
{
    return s->kind == LS_SEG_JOINT && !s->slew_;
}

/* The axes the executor drives for segment s: a slew's joints each on its
 * own, else one path parameter (a joint segment's phase, a Cartesian
 * segment's s). */
static int seg_axes(const ls_motion_seg_t *s)
{
    return (s->kind == LS_SEG_JOINT && s->slew_) ? LS_N_JOINTS : 1;
}

/* The moving segment [0] and, while blending, the one it blends into [1]. */
static int moving_segs(const ls_motion_t *m, const ls_motion_seg_t *seg[2])
{
    seg[0] = plan_seg(&m->plan, m->seg_i_, m->cycle_);
    seg[1] = m->blending_ ? next_seg(m) : NULL;
    return seg[1] != NULL ? 2 : 1;
}

/* The profile joint segment k runs: its planned one, or the one a resume
 * made; a Cartesian segment's time law the same way. */
static const ls_traj_t *seg_traj(const ls_motion_t *m, int k, const ls_motion_seg_t *s)
{
    return m->off_plan_[k] ? &m->resumed_[k].traj : &s->traj;
}

static const ls_pathspeed_t *seg_path(const ls_motion_t *m, int k, const ls_motion_seg_t *s)
{
    return m->off_plan_[k] ? &m->resumed_[k].path : &s->path;
}

/* How long segment k's profile runs (from its clock's 0). */
static double run_duration_s(const ls_motion_t *m, int k, const ls_motion_seg_t *s)
{
    return s->kind == LS_SEG_JOINT ? seg_traj(m, k, s)->duration_s : seg_path(m, k, s)->duration_s;
}

double ls_motion_seg_duration_s(const ls_motion_seg_t *s)
{
    if (s == NULL) {
        return 0.0;
    }
    return s->kind == LS_SEG_JOINT ? s->traj.duration_s : s->path.duration_s;
}

/* The joint that moves furthest in a phase-synchronised profile (-1: none). */
static int lead_joint(const ls_traj_t *tr)
{
    int lead = -1;
    double d = 0.0;
    for (int j = 0; j < tr->n; j++) {
        if (fabs(tr->axis[j].dist) > d) {
            d = fabs(tr->axis[j].dist);
            lead = j;
        }
    }
    return lead;
}

/* Position, velocity and acceleration of axis i of profile tr at t: the
 * axis itself, or for a phase-synchronised profile its phase (read from
 * the joint that moves furthest). */
static void profile_axis(const ls_traj_t *tr, bool phased, int i, double t, double *p, double *v, double *a)
{
    if (!phased) {
        ls_traj_sample_axis(&tr->axis[i], t, p, v, a);
        return;
    }
    const int lead = lead_joint(tr);
    if (lead < 0) {
        *p = *v = *a = 0.0;
        return;
    }
    const ls_traj_axis_t *ax = &tr->axis[lead];
    ls_traj_sample_axis(ax, t, p, v, a);
    *p = (*p - ax->p0) / ax->dist;
    *v /= ax->dist;
    *a /= ax->dist;
}

/* Position, velocity and acceleration of segment k's axes now: from the
 * stop's ramps while they drive the axes, else from the profile at the
 * segment's clock. xd and xdd may be NULL. */
static void seg_state(const ls_motion_t *m, int k, const ls_motion_seg_t *s, double *x, double *xd, double *xdd)
{
    const double t = k == 0 ? m->t_s : m->t_next_s_;
    const ls_traj_t *tr = seg_traj(m, k, s);
    for (int i = 0; i < seg_axes(s); i++) {
        double p, v, a;
        if (m->ramping_ && s->kind != LS_SEG_JOINT) {
            ls_pathspeed_stop_sample(&m->halt_[k].stop, m->ramp_t_s_, &p, &v, &a);
        } else if (m->ramping_) {
            ls_ramp_sample(&m->halt_[k].ramp[i], m->ramp_t_s_, &p, &v, &a);
        } else if (s->kind != LS_SEG_JOINT) {
            ls_pathspeed_sample(seg_path(m, k, s), t, &p, &v, &a);
        } else {
            profile_axis(tr, seg_phased(s), i, t, &p, &v, &a);
        }
        x[i] = p;
        if (xd != NULL) {
            xd[i] = v;
        }
        if (xdd != NULL) {
            xdd[i] = a;
        }
    }
}

/* The joints (and their velocities, qd may be NULL) of joint segment k at
 * its axes x, xd: a slew's are its axes, a phase-synchronised segment's
 * x0 + (q1 - x0) sigma along the profile it runs. */
static void seg_joints(const ls_motion_t *m, int k, const ls_motion_seg_t *s, const double *x, const double *xd,
                       double q[LS_N_JOINTS], double qd[LS_N_JOINTS])
{
    const ls_traj_t *tr = seg_traj(m, k, s);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (seg_phased(s)) {
            q[j] = tr->axis[j].p0 + tr->axis[j].dist * x[0];
            if (qd != NULL) {
                qd[j] = tr->axis[j].dist * xd[0];
            }
        } else {
            q[j] = x[j];
            if (qd != NULL) {
                qd[j] = xd[j];
            }
        }
    }
}

/* The jerk share of a stop ramp: 1 alone; while two segments blend the
 * smaller of BLEND_STOP_JERK_SHARE (the two sum within the limit) and the
 * scale the segment was planned with (a turning pair's rotation terms keep
 * the budget the plan left them). */
static double stop_jerk_share(const ls_motion_seg_t *s, int i, bool blend)
{
    return blend ? fmin(BLEND_STOP_JERK_SHARE, s->jerk_scale_[i]) : 1.0;
}

/* The acceleration and jerk limits of a stop of axis i of segment s
 * running profile tr: the segment's own (its joints' at its acceleration
 * fraction, on a phase: the tightest over the moving joints; its path
 * parameter's), or for a fast stop the model's maxima (on the path
 * parameter: the model's Cartesian maxima over the segment's length and
 * turn, when they are higher than the segment's); the jerk times
 * stop_jerk_share. Never below the acceleration the segment was planned
 * with, nor (alone) its jerk: the ramp then stops no further than the
 * planned profile would, short of the segment's end. */
static void stop_limits(const ls_robot_model_t *model, const ls_motion_seg_t *s, const ls_traj_t *tr, int i, bool fast,
                        bool blend, double x, double xd, double *a, double *j)
{
    if (s->kind == LS_SEG_JOINT) {
        const double f = fast ? 1.0 : s->lim_[1];
        if (!s->slew_) {
            *a = *j = INFINITY;
            for (int k = 0; k < LS_N_JOINTS; k++) {
                const double d = fabs(tr->axis[k].dist);
                if (d > 0.0) {
                    *a = fmin(*a, model->qdd_max_rad_s2[k] * f / d);
                    *j = fmin(*j, model->qddd_max_rad_s3[k] * f * stop_jerk_share(s, k, blend) / d);
                }
            }
        } else {
            *a = model->qdd_max_rad_s2[i] * f;
            *j = model->qddd_max_rad_s3[i] * f * stop_jerk_share(s, i, blend);
        }
    } else {
        /* the zone's acceleration for its speed now (a single ramp: a fast
         * stop, a stop inside a blend; ls_pathspeed_plan_stop otherwise) */
        const int z = ls_pathspeed_zone_of(&s->curve, x);
        *a = z >= 0 ? ls_pathspeed_zone_accel(&s->curve, z, xd, false, NULL) : 0.0;
        *j = s->curve.j;
        if (fast && !cart_still(s)) {
            double af = INFINITY, jf = INFINITY;
            if (s->length_m > 1e-9) {
                af = fmin(af, model->max_linear_accel_m_s2 / s->length_m);
                jf = fmin(jf, model->max_linear_jerk_m_s3 / s->length_m);
            }
            if (s->turn_rad > 1e-9) {
                af = fmin(af, model->max_angular_accel_rad_s2 / s->turn_rad);
                jf = fmin(jf, model->max_angular_jerk_rad_s3 / s->turn_rad);
            }
            *a = fmax(af, *a);
            *j = fmax(jf, *j);
        }
        *j *= stop_jerk_share(s, 0, blend);
    }
    if (!(*a > 0.0 && isfinite(*a)) || !(*j > 0.0 && isfinite(*j))) {
        *a = *j = 1.0; /* a segment that does not move: its ramps are empty */
    }
}

/* Whether ramp r of axis i of segment s running profile tr (a phased joint
 * segment: its phase, from 0 to 1; a Cartesian one: its path parameter)
 * comes to rest beyond the profile's end. */
static bool ramp_passes_end(const ls_ramp_t *r, const ls_motion_seg_t *s, const ls_traj_t *tr, int i)
{
    const bool unit = seg_phased(s) || s->kind != LS_SEG_JOINT;
    const double p0 = unit ? 0.0 : tr->axis[i].p0, p1 = unit ? 1.0 : tr->axis[i].p1;
    double p;
    ls_ramp_sample(r, r->duration_s, &p, NULL, NULL);
    return (p1 > p0 && p > p1 + 1e-12) || (p1 < p0 && p < p1 - 1e-12);
}

/* Whether the ramp r of Cartesian segment s, begun at a blend's shared jerk
 * (slower to turn than the time law), outruns the cap of the zone it is in
 * or leaves that zone before it rests (then it may meet a lower cap too
 * fast). On its own at the full jerk a stop keeps every cap (ls_pathspeed.h). */
static bool ramp_outruns_cap(const ls_ramp_t *r, const ls_motion_seg_t *s)
{
    if (s->kind == LS_SEG_JOINT) {
        return false;
    }
    const int z = ls_pathspeed_zone_of(&s->curve, r->p_[0]);
    if (z < 0) {
        return false;
    }
    const double cap = s->curve.zone[z].v_max, s_end = s->curve.zone[z].s_end;
    double p_rest;
    ls_ramp_sample(r, r->duration_s, &p_rest, NULL, NULL);
    const double peak = r->a_[0] > 0.0 ? r->v_[0] + r->a_[0] * r->a_[0] / (2.0 * fabs(r->j[0])) : r->v_[0];
    return peak > cap * (1.0 + 1e-9) || p_rest > s_end;
}

/* Start (or, for a fast stop during a stop, re-plan) the ramps that bring
 * every axis of the moving segments to rest from its current state. While
 * two segments blend, a ramp at the shared jerk may not stop the segment
 * that has just started before its end (a short one, planned at the full
 * jerk); then nothing changes yet and the stop begins when the blend ends
 * (stop_at_end_), on the one segment left, at most the overlap later.
 * ramp_ is only written once the ramps are known to be taken. */
static void begin_ramps(ls_motion_t *m, bool fast)
{
    const ls_motion_seg_t *seg[2];
    const int n = moving_segs(m, seg);
    double x[2][LS_N_JOINTS], xd[2][LS_N_JOINTS], xdd[2][LS_N_JOINTS];
    for (int k = 0; k < n; k++) {
        seg_state(m, k, seg[k], x[k], xd[k], xdd[k]); /* before the ramps change */
    }
    ls_ramp_t r[2][LS_N_JOINTS];
    double T = 0.0;
    bool passes = false;
    for (int k = 0; k < n; k++) {
        const ls_traj_t *tr = seg_traj(m, k, seg[k]);
        for (int i = 0; i < seg_axes(seg[k]); i++) {
            double a, j;
            stop_limits(m->model, seg[k], tr, i, fast, n == 2, x[k][i], xd[k][i], &a, &j);
            if (ls_ramp_plan(&r[k][i], x[k][i], xd[k][i], xdd[k][i], 0.0, a, j) != LS_OK) {
                (void)ls_ramp_plan(&r[k][i], x[k][i], 0.0, 0.0, 0.0, 1.0, 1.0); /* not finite: hold */
            }
            passes =
                passes || ramp_passes_end(&r[k][i], seg[k], tr, i) || (n == 2 && ramp_outruns_cap(&r[k][i], seg[k]));
            T = fmax(T, r[k][i].duration_s);
        }
    }
    if (n == 2 && passes) {
        m->stop_at_end_ = fast ? STOP_FAST : (m->stop_at_end_ == STOP_FAST ? STOP_FAST : STOP_NORMAL);
        return;
    }
    /* Take them: a joint segment's as planned; a Cartesian segment alone
     * stops zone by zone at its joints' limits (ls_pathspeed.h), a fast stop
     * and a stop inside a blend on the one ramp planned above. */
    T = 0.0;
    for (int k = 0; k < n; k++) {
        if (seg[k]->kind == LS_SEG_JOINT) {
            memcpy(m->halt_[k].ramp, r[k], sizeof r[k]);
            for (int i = 0; i < seg_axes(seg[k]); i++) {
                T = fmax(T, r[k][i].duration_s);
            }
            continue;
        }
        ls_pathspeed_stop_t *st = &m->halt_[k].stop;
        if (fast || n == 2 ||
            ls_pathspeed_plan_stop(st, &seg[k]->curve, x[k][0], xd[k][0], xdd[k][0], seg[k]->curve.j) != LS_OK) {
            ls_pathspeed_stop_one(st, &r[k][0]);
        }
        T = fmax(T, st->duration_s);
    }
    m->stop_at_end_ = STOP_NONE;
    m->ramping_ = true;
    m->ramp_t_s_ = 0.0;
    m->ramp_T_s_ = T;
}

void ls_motion_stop(ls_motion_t *m)
{
    if (m->phase != LS_MOTION_RUNNING) {
        return;
    }
    m->phase = LS_MOTION_STOPPING;
    if (m->sub_ == SUB_MOVE) {
        begin_ramps(m, false);
    }
    /* At a point (auxiliary command, dwell) the arm is at rest already: the
     * next step reports the pause. */
}

void ls_motion_stop_fast(ls_motion_t *m)
{
    if (m->phase != LS_MOTION_RUNNING && m->phase != LS_MOTION_STOPPING) {
        return;
    }
    m->phase = LS_MOTION_STOPPING;
    if (m->sub_ == SUB_MOVE) {
        begin_ramps(m, true);
    }
}

int ls_motion_fast_stop_bound(const ls_robot_model_t *model, int j, double *time_s, double *dist_rad)
{
    if (model == NULL || j < 0 || j >= LS_N_JOINTS || time_s == NULL || dist_rad == NULL) {
        return LS_EINVAL;
    }
    /* The fast stop's ramp from (v_max, +a_max): more speed or more
     * acceleration only lengthens a ramp, and no plan has both at once. */
    const double a = model->qdd_max_rad_s2[j];
    ls_ramp_t r;
    const int rc = ls_ramp_plan(&r, 0.0, model->qd_max_rad_s[j], a, 0.0, a, model->qddd_max_rad_s3[j]);
    if (rc != LS_OK) {
        return rc;
    }
    *time_s = r.duration_s;
    ls_ramp_sample(&r, r.duration_s, dist_rad, NULL, NULL);
    return LS_OK;
}

/* Re-plan each moving segment from where the stop's ramps left its axes to
 * its end, from rest, within its limits. Two that were blending run one
 * after the other: the one blending in waits (its clock below 0) until the
 * other has arrived, so each has its whole limits. The planner's status,
 * changing nothing, when a profile cannot be planned (its limits planned it
 * once, so only a corrupted plan gets there). */
static int plan_from_ramps(ls_motion_t *m)
{
    const ls_motion_seg_t *seg[2];
    const int n = moving_segs(m, seg);
    ls_traj_t tr[2];
    ls_pathspeed_t path[2];
    double T[2];
    for (int k = 0; k < n; k++) {
        double x[LS_N_JOINTS], q[LS_N_JOINTS];
        seg_state(m, k, seg[k], x, NULL, NULL);
        int r;
        if (seg[k]->kind == LS_SEG_JOINT) {
            seg_joints(m, k, seg[k], x, NULL, q, NULL);
            r = joint_profile_from(seg[k], m->model, q, &tr[k], NULL);
            T[k] = tr[k].duration_s;
        } else {
            r = cart_profile_from(seg[k], fmin(1.0, fmax(0.0, x[0])), &path[k]);
            T[k] = path[k].duration_s;
        }
        if (r != LS_OK) {
            return r;
        }
    }
    for (int k = 0; k < n; k++) {
        if (seg[k]->kind == LS_SEG_JOINT) {
            m->resumed_[k].traj = tr[k];
        } else {
            m->resumed_[k].path = path[k];
        }
        m->off_plan_[k] = true;
    }
    m->ramping_ = false;
    m->t_s = 0.0;
    m->t_next_s_ = n == 2 ? -T[0] : 0.0;
    return LS_OK;
}

int ls_motion_resume(ls_motion_t *m)
{
    if (m->phase != LS_MOTION_PAUSED) {
        return LS_ESTATE;
    }
    if (m->ramping_) {
        const int rc = plan_from_ramps(m);
        if (rc != LS_OK) {
            return rc;
        }
    }
    m->phase = LS_MOTION_RUNNING;
    return LS_OK;
}

void ls_motion_abort(ls_motion_t *m)
{
    m->phase = LS_MOTION_IDLE;
    m->blending_ = false;
    m->sub_ = SUB_MOVE;
    m->aux_wait_ = false;
    m->ramping_ = false;
    m->stop_at_end_ = STOP_NONE;
}

void ls_motion_aux_done(ls_motion_t *m)
{
    m->aux_wait_ = false;
}

/* Paused: after the ramps (ramping_ stays set: where they left the axes is
 * where a resume starts), or at a point. The event says where. */
static void pause_now(ls_motion_t *m, ls_motion_events_t *ev)
{
    m->phase = LS_MOTION_PAUSED;
    ls_motion_event_t *e = push_event(m, ev, LS_MEV_PAUSED);
    if (e != NULL) {
        ls_fmt_print(e->text, sizeof e->text, "%s",
                     m->sub_ != SUB_MOVE ? "at a point"
                                         : (m->blending_ ? "inside the blend of two points" : "between two points"));
    }
}

/* The set-point q and its velocity qd from the axes of the moving segment s
 * (xa, xda) and, while blending, of nx (xb, xdb): joint into joint in joint
 * space (qd: the sum), line into line by one IK of the blended tip pose; a
 * Cartesian segment alone by IK seeded by the last set-point (qd: the
 * set-point's change over dt_s); exactly q1 at the end of the segment.
 * Returns an ls_kin status. */
static int setpoint(const ls_motion_t *m, const ls_motion_seg_t *s, const double *xa, const double *xda,
                    const ls_motion_seg_t *nx, const double *xb, const double *xdb, bool at_end, double dt_s,
                    double q[LS_N_JOINTS], double qd[LS_N_JOINTS])
{
    int ks = LS_OK;
    if (s->kind == LS_SEG_JOINT) {
        seg_joints(m, 0, s, xa, xda, q, qd);
        if (nx != NULL) {
            double qb[LS_N_JOINTS], qdb[LS_N_JOINTS];
            seg_joints(m, 1, nx, xb, xdb, qb, qdb);
            for (int j = 0; j < LS_N_JOINTS; j++) {
                q[j] += qb[j] - nx->q0[j];
                qd[j] += qdb[j];
            }
        }
        if (at_end && nx == NULL) {
            memcpy(q, s->q1, LS_N_JOINTS * sizeof(double));
        }
        return LS_OK;
    }
    if (nx == NULL) {
        if (at_end) {
            memcpy(q, s->q1, LS_N_JOINTS * sizeof(double));
        } else {
            ks = seg_ik(m->model, s, xa[0], m->q_cmd, q);
        }
    } else {
        double T[16], F[16];
        blend_pose(s, xa[0], nx, xb[0], T);
        ls_pose_mul(T, s->tool_inv, F);
        ks = ls_kin_ik_nearest(m->model, F, m->q_cmd, q);
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        qd[j] = (q[j] - m->q_cmd[j]) / dt_s;
    }
    return ks;
}

/* Move on to the next point of the plan. at_rest: no blend in progress, so
 * a pending stop pauses here. */
static void advance(ls_motion_t *m, ls_motion_events_t *ev, bool at_rest)
{
    uint16_t n = plan_nsegs(&m->plan);
    if (m->seg_i_ + 1 < n) {
        m->seg_i_++;
    } else if (m->cycle_ < m->plan.cycles) {
        m->seg_i_ = 0;
        m->cycle_++;
    } else {
        m->phase = LS_MOTION_IDLE;
        (void)push_event(m, ev, LS_MEV_DONE);
        return;
    }
    m->t_s = 0.0;
    m->sub_ = SUB_MOVE;
    m->off_plan_[0] = m->off_plan_[1] = false;
    m->slow_told_ = false;
    if (at_rest && m->phase == LS_MOTION_STOPPING) {
        pause_now(m, ev);
    }
}

/* After the point's auxiliary commands: dwell, or go on. */
static void after_aux(ls_motion_t *m, const ls_motion_seg_t *s, ls_motion_events_t *ev)
{
    if (s->delay_s > 0.0) {
        m->sub_ = SUB_DWELL;
        m->dwell_left_s_ = s->delay_s;
    } else {
        advance(m, ev, true);
    }
}

static void announce_aux(ls_motion_t *m, const ls_motion_seg_t *s, ls_motion_events_t *ev)
{
    ls_motion_event_t *e = push_event(m, ev, LS_MEV_AUX);
    if (e != NULL) {
        ls_fmt_print(e->text, sizeof e->text, "%s", s->aux[m->aux_k_]);
        e->index = s->point;
    }
    m->aux_wait_ = true;
}

static void arrive(ls_motion_t *m, const ls_motion_seg_t *s, ls_motion_events_t *ev)
{
    if (s->tag[0] != '\0') {
        ls_motion_event_t *e = push_event(m, ev, LS_MEV_TAG);
        if (e != NULL) {
            memcpy(e->name, s->tag, sizeof e->name);
            ls_fmt_print(e->text, sizeof e->text, "%s", m->plan.name);
            e->index = s->tag_index;
        }
    }
}

/* A planned joint that the measured one does not follow faults the motion. */
static void check_following(ls_motion_t *m, const double q_meas[LS_N_JOINTS], ls_motion_events_t *ev)
{
    if (m->lag_cycles_ > 0u && (unsigned)m->lag_cycles_ + m->late_cycles_ >= LS_MOTION_LAG_MAX - 1u) {
        return; /* a measurement older than the set-points kept: the arm's staleness rule judges it */
    }
    if (m->phase != LS_MOTION_IDLE && m->phase != LS_MOTION_PAUSED && q_meas != NULL) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            if ((m->ignored_joints_ & (1u << j)) != 0u) {
                continue;
            }
            double e = q_meas[j] - m->q_cmd[j];
            unsigned window = m->lag_cycles_ > 0u ? (unsigned)m->lag_cycles_ + m->late_cycles_ : 0u;
            window = window < LS_MOTION_LAG_MAX ? window : LS_MOTION_LAG_MAX - 1u;
            for (unsigned k = 1; k <= window && fabs(e) > m->following_error_max_rad; k++) {
                const unsigned i = (m->hist_head_ + LS_MOTION_LAG_MAX - k) % LS_MOTION_LAG_MAX;
                const double ek = q_meas[j] - m->q_hist_[i][j];
                e = fabs(ek) < fabs(e) ? ek : e;
            }
            if (fabs(e) > m->following_error_max_rad) {
                fault(m, ev, "following error joint %d: %.4g rad", j + 1, e);
                break;
            }
        }
    }
}

/* At the end of segment s: the point's tag, then the segment it blends
 * into becomes the current one, or the point's auxiliary commands, or its
 * dwell, or the next segment. */
static void end_of_segment(ls_motion_t *m, const ls_motion_seg_t *s, double qd[LS_N_JOINTS], ls_motion_events_t *ev)
{
    arrive(m, s, ev);
    if (m->blending_) {
        /* The next segment is under way: make it the current one, with the
         * profile it runs (its own, or a resume's). */
        const double t_next = m->t_next_s_;
        const bool off = m->off_plan_[1];
        m->blending_ = false;
        advance(m, ev, false);
        m->t_s = t_next;
        if (off) {
            m->resumed_[0] = m->resumed_[1];
            m->off_plan_[0] = true;
        }
        if (m->stop_at_end_ != STOP_NONE && m->phase == LS_MOTION_STOPPING) {
            begin_ramps(m, m->stop_at_end_ == STOP_FAST); /* the one segment left */
        }
        return;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        qd[j] = 0.0;
    }
    if (s->n_aux > 0 && !m->plan.dry_run) {
        m->sub_ = SUB_AUX;
        m->aux_k_ = 0;
        announce_aux(m, s, ev);
    } else {
        after_aux(m, s, ev);
    }
}

/* One step along segment s (and the next one while blending into it), or
 * of a stop's ramps: the set-point and its velocity qd, arrival at the
 * segment's end, and the pause that ends a stop. A segment blends into the
 * next only on its planned profile (after a resume it arrives at rest). */
/* A path's segment that its joints slow down says so as it begins, in the
 * first cycle that runs it (the program's closing segment: in the second). */
static void tell_slow(ls_motion_t *m, const ls_motion_seg_t *s, ls_motion_events_t *ev)
{
    if (m->slow_told_) {
        return;
    }
    m->slow_told_ = true;
    const bool closing = m->seg_i_ == 0 && m->cycle_ == 2;
    if (m->plan.kind == LS_PLAN_PATH && (m->cycle_ == 1 || closing) && ls_motion_seg_slowdown(s, NULL)) {
        ls_motion_event_t *e = push_event(m, ev, LS_MEV_SLOW);
        if (e != NULL) {
            e->index = closing ? m->plan.prog->n : m->seg_i_;
        }
    }
}

static void move_step(ls_motion_t *m, const ls_motion_seg_t *s, double dt_s, double qd[LS_N_JOINTS],
                      ls_motion_events_t *ev)
{
    tell_slow(m, s, ev);
    const ls_motion_seg_t *nx = NULL;
    if (m->ramping_) {
        m->ramp_t_s_ += dt_s;
        nx = m->blending_ ? next_seg(m) : NULL;
    } else {
        m->t_s += dt_s;
        if (m->blending_) {
            m->t_next_s_ += dt_s;
            nx = next_seg(m);
        } else if (s->overlap_s > 0.0 && !m->off_plan_[0] && m->t_s >= ls_motion_seg_duration_s(s) - s->overlap_s) {
            nx = next_seg(m);
            if (nx != NULL) {
                m->blending_ = true;
                m->t_next_s_ = m->t_s - (ls_motion_seg_duration_s(s) - s->overlap_s);
            }
        }
    }
    double xa[LS_N_JOINTS], xda[LS_N_JOINTS], xb[LS_N_JOINTS] = { 0 }, xdb[LS_N_JOINTS] = { 0 };
    seg_state(m, 0, s, xa, xda, NULL);
    if (nx != NULL) {
        seg_state(m, 1, nx, xb, xdb, NULL);
    }
    /* The clock sums dt_s: within END_TOL_S of the end counts as there (the
     * profile is at rest then, a jerk phase's cube away from q1). */
    const bool at_end = !m->ramping_ && m->t_s >= run_duration_s(m, 0, s) - END_TOL_S;
    double q[LS_N_JOINTS];
    const int ks = setpoint(m, s, xa, xda, nx, xb, xdb, at_end, dt_s, q, qd);
    if (ks != LS_OK) {
        fault(m, ev, "no joint solution on the planned path (IK status %d): stopped", ks);
        return;
    }
    memcpy(m->q_cmd, q, sizeof m->q_cmd);
    if (m->ramping_) {
        if (m->ramp_t_s_ >= m->ramp_T_s_) {
            for (int j = 0; j < LS_N_JOINTS; j++) {
                qd[j] = 0.0;
            }
            pause_now(m, ev);
        }
    } else if (at_end) {
        end_of_segment(m, s, qd, ev);
    }
}

void ls_motion_step(ls_motion_t *m, double dt_s, const double q_meas[LS_N_JOINTS], double q_cmd[LS_N_JOINTS],
                    double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev)
{
    double qd[LS_N_JOINTS] = { 0 };
    check_following(m, q_meas, ev);
    if ((m->phase == LS_MOTION_RUNNING || m->phase == LS_MOTION_STOPPING) && dt_s > 0.0) {
        const ls_motion_seg_t *s = plan_seg(&m->plan, m->seg_i_, m->cycle_);
        if (m->sub_ == SUB_MOVE) {
            move_step(m, s, dt_s, qd, ev);
        } else if (m->phase == LS_MOTION_STOPPING) {
            pause_now(m, ev); /* at rest at a point */
        } else if (m->sub_ == SUB_AUX) {
            if (!m->aux_wait_) {
                m->aux_k_++;
                if (m->aux_k_ < s->n_aux) {
                    announce_aux(m, s, ev);
                } else {
                    after_aux(m, s, ev);
                }
            }
        } else { /* SUB_DWELL */
            m->dwell_left_s_ -= dt_s;
            if (m->dwell_left_s_ <= 1e-12) {
                advance(m, ev, true);
            }
        }
    }
    memcpy(q_cmd, m->q_cmd, sizeof m->q_cmd);
    if (qd_cmd != NULL) {
        memcpy(qd_cmd, qd, sizeof qd);
    }
    if (m->lag_cycles_ > 0u) {
        m->hist_head_ = (uint16_t)((m->hist_head_ + 1u) % LS_MOTION_LAG_MAX);
        memcpy(m->q_hist_[m->hist_head_], m->q_cmd, sizeof m->q_cmd);
    }
}
