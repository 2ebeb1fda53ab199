/* Guarded moves, compliant moves and jogging (ls_react.h). */
#include "ls_react.h"

#include <math.h>
#include <string.h>

#include "ls_fmt.h"
#include "ls_kin.h"

enum { PH_RUN = 1, PH_BRAKE, PH_RETURN, PH_SETTLE, PH_SEEK, PH_CONTACT };

#define SETTLE_AFTER_RETURN_S 0.05
#define DERIV_FILTER_TAU_S 0.01

/* ------------------------------------------------------------- helpers */

static void rot_apply(const double T[16], const double v[3], double out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = T[i] * v[0] + T[4 + i] * v[1] + T[8 + i] * v[2];
    }
}

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static bool finite_n(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(v[i])) {
            return false;
        }
    }
    return true;
}

static void emit(ls_motion_events_t *ev, ls_motion_event_kind_t kind, uint32_t ref_seq, int32_t index, const char *text,
                 const double q[LS_N_JOINTS])
{
    if (ev == NULL || ev->n >= LS_MOTION_MAX_EVENTS) {
        return;
    }
    ls_motion_event_t *e = &ev->ev[ev->n++];
    memset(e, 0, sizeof *e);
    e->kind = kind;
    e->ref_seq = ref_seq;
    e->index = index;
    if (text != NULL) {
        /* The precision bounds the copy by the field, whatever buffer the
         * caller formatted into: a longer text is cut, and the compiler can
         * prove that nothing else is (-Wformat-truncation at -O3). */
        ls_fmt_print(e->text, sizeof e->text, "%.*s", (int)(sizeof e->text - 1), text);
    }
    if (q != NULL) {
        memcpy(e->q_rad, q, sizeof e->q_rad);
    }
}

/* Magnitude the envelope and the panic level apply to: the force of a
 * force/torque sensor, the value itself for a one-value sensor. */
static double envelope_value(const double *reading, uint8_t n)
{
    if (n >= 3) {
        return norm3(reading);
    }
    return fabs(reading[0]);
}

/* Rodrigues: the rotation by angle |w| about w, as a pose without translation. */
static void rot_of_vector(const double w[3], double R[16])
{
    memset(R, 0, 16 * sizeof R[0]);
    R[15] = 1.0;
    double th = norm3(w);
    if (th < 1e-15) {
        R[0] = R[5] = R[10] = 1.0;
        return;
    }
    double k[3] = { w[0] / th, w[1] / th, w[2] / th };
    double c = cos(th), s = sin(th), v = 1.0 - c;
    R[0] = c + k[0] * k[0] * v;
    R[1] = k[1] * k[0] * v + k[2] * s;
    R[2] = k[2] * k[0] * v - k[1] * s;
    R[4] = k[0] * k[1] * v - k[2] * s;
    R[5] = c + k[1] * k[1] * v;
    R[6] = k[2] * k[1] * v + k[0] * s;
    R[8] = k[0] * k[2] * v + k[1] * s;
    R[9] = k[1] * k[2] * v - k[0] * s;
    R[10] = c + k[2] * k[2] * v;
}

/* The joint set-point of a tip pose, nearest q_prev, within the joint,
 * speed and workspace limits. LS_OK, or LS_ERANGE with why. */
static int solve(const ls_robot_model_t *m, const double P[16], const double tool_inv[16],
                 const double q_prev[LS_N_JOINTS], double dt_s, double q_out[LS_N_JOINTS], char *why, size_t len)
{
    for (int i = 0; i < 3; i++) {
        if (P[12 + i] < m->workspace_min_m[i] || P[12 + i] > m->workspace_max_m[i]) {
            ls_fmt_print(why, len, "workspace: tip %c %.4g m outside [%.4g, %.4g]", "xyz"[i], P[12 + i],
                         m -> workspace_min_m[i], m -> workspace_max_m[i]);
            return LS_ERANGE;
        }
    }
    double F[16];
    ls_pose_mul(P, tool_inv, F);
    int st = ls_kin_ik_nearest(m, F, q_prev, q_out);
    if (st != LS_OK) {
        ls_fmt_print(why, len, "%s",
                     st == LS_ELIMITS     ? "a joint limit"
                     : st == LS_ESINGULAR ? "the shoulder singularity"
                                          : "the edge of the reachable space");
        return LS_ERANGE;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (fabs(q_out[j] - q_prev[j]) > m->qd_max_rad_s[j] * dt_s) {
            ls_fmt_print(why, len, "joint %d would jump: a joint limit or singularity ahead", j + 1);
            return LS_ERANGE;
        }
    }
    return LS_OK;
}

/* ------------------------------------------------------------- plans */

void ls_react_init(ls_react_t *r, const ls_robot_model_t *model)
{
    memset(r, 0, sizeof *r);
    r->model = model;
    r->following_error_max_rad = LS_MOTION_FOLLOWING_ERROR_RAD;
}

static int refuse(char *why, size_t len, const char *text)
{
    if (why != NULL && len > 0) {
        ls_fmt_print(why, len, "%s", text);
    }
    return LS_EINVAL;
}

/* The travel from rest at `from` to `to`: a rest-to-rest profile at speed
 * v within the plan's travel acceleration and jerk (checked finite and > 0
 * by ls_react_check_plan). Should numbers that extreme still not plan, it
 * holds at `from` (the phase ends there) rather than keep an old profile. */
static void plan_travel(ls_react_t *r, double from, double to, double v)
{
    if (ls_traj_plan_axis(&r->prof_, from, to, v, r->plan.a_m_s2, r->plan.j_m_s3) != LS_OK) {
        (void)ls_traj_plan_axis(&r->prof_, from, from, 1.0, 1.0, 1.0);
    }
    r->prof_t_ = 0.0;
    r->braking_ = false;
}

/* A brake of the travel from where it is (s_, v_, a_) to rest within the
 * plan's stop acceleration and jerk. */
static void plan_brake(ls_react_t *r)
{
    if (ls_ramp_plan(&r->brake_, r->s_, r->v_, r->a_, 0.0, r->plan.a_stop_m_s2, r->plan.j_stop_m_s3) != LS_OK) {
        (void)ls_ramp_plan(&r->brake_, r->s_, 0.0, 0.0, 0.0, 1.0, 1.0);
    }
    r->prof_t_ = 0.0;
    r->braking_ = true;
}

/* One cycle of the travel along the brake or the profile: s_next_, v_, a_.
 * True when it has reached its end (at rest). */
static bool travel_step(ls_react_t *r, double dt_s)
{
    r->prof_t_ += dt_s;
    bool end;
    if (r->braking_) {
        ls_ramp_sample(&r->brake_, r->prof_t_, &r->s_next_, &r->v_, &r->a_);
        end = r->prof_t_ >= r->brake_.duration_s;
    } else {
        ls_traj_sample_axis(&r->prof_, r->prof_t_, &r->s_next_, &r->v_, &r->a_);
        end = r->prof_t_ >= r->prof_.T - 1e-9;
    }
    if (end) {
        r->v_ = r->a_ = 0.0;
    }
    return end;
}

int ls_react_check_plan(const ls_react_plan_t *p, char *why, size_t whylen)
{
    if (p == NULL) {
        return refuse(why, whylen, "no plan");
    }
    if (p->kind != LS_REACT_GUARDED && p->kind != LS_REACT_COMPLY) {
        return refuse(why, whylen, "unknown kind of sensor-guided move");
    }
    if (!finite_n(p->tool, 16) || !finite_n(p->dir_tool, 3) || !isfinite(p->dist_m) || !isfinite(p->v_m_s) ||
        !isfinite(p->a_m_s2) || !isfinite(p->j_m_s3) || !isfinite(p->a_stop_m_s2) || !isfinite(p->j_stop_m_s3) ||
        !isfinite(p->threshold) || !isfinite(p->envelope)) {
        return refuse(why, whylen, "non-finite number in the plan");
    }
    if (fabs(norm3(p->dir_tool) - 1.0) > 1e-6 || !(p->dist_m > 0.0)) {
        return refuse(why, whylen, "the direction of travel must be a unit vector and the distance > 0");
    }
    if (!(p->v_m_s > 0.0) || !(p->a_m_s2 > 0.0) || !(p->a_stop_m_s2 > 0.0) || !(p->j_m_s3 > 0.0) ||
        !(p->j_stop_m_s3 > 0.0)) {
        return refuse(why, whylen, "speed, accelerations and jerks must be > 0");
    }
    if (p->envelope < 0.0) {
        return refuse(why, whylen, "the envelope must be >= 0 (0: none)");
    }
    if (p->kind == LS_REACT_GUARDED) {
        if (p->component >= LS_REACT_MAX_VALUES) {
            return refuse(why, whylen, "sensor component out of range");
        }
        return LS_OK;
    }
    if (!finite_n(p->n_tool, 3) || !isfinite(p->c_max_m) || !isfinite(p->f_target_N) || !isfinite(p->kp_m_s_N) ||
        !isfinite(p->kd_m_N) || !isfinite(p->vc_max_m_s) || !isfinite(p->timeout_s) || !isfinite(p->panic_N)) {
        return refuse(why, whylen, "non-finite number in the plan");
    }
    if (fabs(norm3(p->n_tool) - 1.0) > 1e-6 || !(p->c_max_m > 0.0)) {
        return refuse(why, whylen, "the compliance direction must be a unit vector and its travel > 0");
    }
    if (p->f_target_N == 0.0 || !(p->kp_m_s_N > 0.0) || p->kd_m_N < 0.0 || !(p->vc_max_m_s > 0.0) ||
        !(p->timeout_s > 0.0) || !(p->panic_N > 0.0)) {
        return refuse(why, whylen,
                      "comply needs a non-zero target, kp > 0, kd >= 0, a correction speed, "
                      "time-out and panic level > 0");
    }
    return LS_OK;
}

int ls_react_start(ls_react_t *r, const ls_react_plan_t *p, const double q_cmd[LS_N_JOINTS], uint8_t n_values)
{
    if (r->active) {
        return LS_ESTATE;
    }
    if (ls_react_check_plan(p, NULL, 0) != LS_OK) {
        return LS_EINVAL;
    }
    r->plan = *p;
    memset(&r->report, 0, sizeof r->report);
    r->report.n_values = n_values > LS_REACT_MAX_VALUES ? LS_REACT_MAX_VALUES : n_values;
    r->report.fn_min_N = INFINITY;
    r->report.fn_max_N = -INFINITY;
    memcpy(r->q_cmd_, q_cmd, sizeof r->q_cmd_);
    double F[16];
    ls_kin_fk(r->model, q_cmd, F);
    ls_pose_mul(F, p->tool, r->P0_);
    ls_pose_inv(p->tool, r->tool_inv_);
    rot_apply(r->P0_, p->dir_tool, r->d_);
    if (p->kind == LS_REACT_COMPLY) {
        rot_apply(r->P0_, p->n_tool, r->n_);
    } else {
        memset(r->n_, 0, sizeof r->n_);
    }
    r->s_ = r->v_ = r->a_ = r->c_ = r->vc_ = r->t_ = r->s_trigger_ = r->e_prev_ = r->de_f_ = r->travel_t_ = 0.0;
    r->have_e_ = false;
    r->stopping_ = false;
    r->end_ = (ls_react_end_t)0;
    r->stop_req_ = false;
    r->paused = false;
    r->phase_ = p->kind == LS_REACT_COMPLY ? PH_SEEK : PH_RUN;
    plan_travel(r, 0.0, p->kind == LS_REACT_COMPLY ? 0.0 : p->dist_m, p->v_m_s);
    r->active = true;
    return LS_OK;
}

void ls_react_stop(ls_react_t *r)
{
    if (r->active && !r->paused) {
        r->stop_req_ = true;
    }
}

int ls_react_resume(ls_react_t *r)
{
    if (!r->active || !r->paused) {
        return LS_ESTATE;
    }
    r->paused = false;
    r->stop_req_ = false;
    /* From rest where the brake left it: the rest of the phase's travel. */
    if (r->phase_ == PH_RUN) {
        plan_travel(r, r->s_, r->plan.dist_m, r->plan.v_m_s);
    } else if (r->phase_ == PH_RETURN) {
        plan_travel(r, r->s_, r->s_trigger_, fmin(r->plan.v_m_s, LS_REACT_RETURN_SPEED_M_S));
    } else if (r->phase_ == PH_BRAKE) {
        plan_brake(r); /* at rest already: an empty brake, then the phase goes on */
    }
    return LS_OK;
}

bool ls_react_moving(const ls_react_t *r)
{
    return r->active && !r->paused;
}

static void finish(ls_react_t *r, ls_react_end_t end, const double q_meas[LS_N_JOINTS], ls_motion_events_t *ev)
{
    r->report.end = end;
    r->report.travelled_m = r->s_;
    r->report.compliance_m = r->c_;
    if (r->report.fn_samples > 0) {
        r->report.fn_mean_N /= (double)r->report.fn_samples;
    } else {
        r->report.fn_min_N = r->report.fn_max_N = r->report.fn_mean_N = 0.0;
    }
    r->active = false;
    r->paused = false;
    r->stop_req_ = false;
    emit(ev, LS_MEV_REACT_END, r->plan.ref_seq, (int32_t)end, ls_react_end_name(end), q_meas);
}

void ls_react_abort(ls_react_t *r, const double q_meas[LS_N_JOINTS], ls_motion_events_t *ev)
{
    if (!r->active) {
        return;
    }
    r->v_ = r->a_ = r->vc_ = 0.0;
    finish(r, LS_REACT_END_ABORTED, q_meas, ev);
}

/* ------------------------------------------------------------- guarded and compliant moves */

static double toward_zero(double v, double a, double dt_s)
{
    double dv = a * dt_s;
    return fabs(v) <= dv ? 0.0 : v - (v > 0.0 ? dv : -dv);
}

static bool crossed(const ls_react_plan_t *p, const double *reading)
{
    double x = reading[p->component];
    return p->below ? x <= p->threshold : x >= p->threshold;
}

static void save_reading(ls_react_t *r, const double *reading)
{
    memcpy(r->report.reading, reading, r->report.n_values * sizeof reading[0]);
}

/* moveReact: run to the threshold (or the envelope, or the distance),
 * brake, come back to where the reading crossed, settle. False when the
 * move ended (finish() has reported it). */
static bool guarded_step(ls_react_t *r, const double *reading, double env, double dt_s,
                         const double q_meas[LS_N_JOINTS], ls_motion_events_t *ev)
{
    const ls_react_plan_t *p = &r->plan;
    switch (r->phase_) {
    case PH_RUN:
        if (p->envelope > 0.0 && env > p->envelope) {
            r->end_ = LS_REACT_END_ENVELOPE;
        } else if (crossed(p, reading)) {
            r->end_ = LS_REACT_END_THRESHOLD;
        }
        if (r->end_ != 0) {
            r->report.triggered = true;
            r->report.trigger = r->end_ == LS_REACT_END_ENVELOPE ? env : reading[p->component];
            r->s_trigger_ = r->s_;
            r->phase_ = PH_BRAKE;
            plan_brake(r);
            (void)travel_step(r, dt_s);
            break;
        }
        if (travel_step(r, dt_s)) {
            r->s_next_ = p->dist_m;
            r->end_ = LS_REACT_END_MAX_DISTANCE;
            r->phase_ = PH_SETTLE;
            r->t_ = 0.0;
        }
        break;
    case PH_BRAKE:
        if (travel_step(r, dt_s)) {
            /* Back to where the reading crossed: the overshoot of the stop
             * would otherwise keep pressing with the contact's stiffness. */
            r->phase_ = PH_RETURN;
            plan_travel(r, r->s_next_, r->s_trigger_, fmin(p->v_m_s, LS_REACT_RETURN_SPEED_M_S));
        }
        break;
    case PH_RETURN:
        if (travel_step(r, dt_s)) {
            r->s_next_ = r->s_trigger_;
            r->phase_ = PH_SETTLE;
            r->t_ = 0.0;
        }
        break;
    case PH_SETTLE:
        r->v_ = r->a_ = 0.0;
        if (r->t_ >= SETTLE_AFTER_RETURN_S) {
            finish(r, r->end_, q_meas, ev);
            return false;
        }
        break;
    default: break;
    }
    return true;
}

/* comply: seek contact, hold the target force with a PD on its error while
 * travelling, brake on a time-out; a panic force ends it at once. False when
 * the move ended (finish() has reported it). */
static bool comply_step(ls_react_t *r, const double *reading, double env, double dt_s, const double q_meas[LS_N_JOINTS],
                        ls_motion_events_t *ev)
{
    const ls_react_plan_t *p = &r->plan;
    double fn = dot3(reading, p->n_tool);
    if (r->phase_ != PH_BRAKE) {
        if (env > p->panic_N) {
            /* Panic: stop at once, no braking ramp (comply speeds are low). */
            r->v_ = r->a_ = r->vc_ = 0.0;
            finish(r, LS_REACT_END_PANIC, q_meas, ev);
            return false;
        }
        if (r->t_ > p->timeout_s) {
            r->end_ = LS_REACT_END_TIMEOUT;
            r->phase_ = PH_BRAKE;
            plan_brake(r);
        }
    }
    /* PD on the force error, as a correction speed along n. */
    double e = p->f_target_N - fn;
    double de = r->have_e_ ? (e - r->e_prev_) / dt_s : 0.0;
    r->have_e_ = true;
    r->e_prev_ = e;
    double alpha = dt_s / (DERIV_FILTER_TAU_S + dt_s);
    r->de_f_ += alpha * (de - r->de_f_);
    double vc = p->kp_m_s_N * e + p->kd_m_N * r->de_f_;
    if (vc > p->vc_max_m_s) {
        vc = p->vc_max_m_s;
    } else if (vc < -p->vc_max_m_s) {
        vc = -p->vc_max_m_s;
    }
    switch (r->phase_) {
    case PH_SEEK:
        /* No contact yet: approach at the correction speed (the PD's
         * output for the whole target would be slow with a stable gain). */
        if ((p->f_target_N > 0.0 ? fn : -fn) >= LS_REACT_SEEK_FRACTION * fabs(p->f_target_N)) {
            r->phase_ = PH_CONTACT;
            r->vc_ = vc;
        } else {
            r->vc_ = p->f_target_N > 0.0 ? p->vc_max_m_s : -p->vc_max_m_s;
        }
        break;
    case PH_CONTACT:
        r->vc_ = vc;
        if (fabs(e) <= LS_REACT_CONTACT_BAND * fabs(p->f_target_N)) {
            r->phase_ = PH_RUN;
            plan_travel(r, r->s_, p->dist_m, p->v_m_s);
        }
        break;
    case PH_RUN: {
        r->vc_ = vc;
        const bool arrived = travel_step(r, dt_s);
        r->travel_t_ += dt_s;
        if (r->travel_t_ >= LS_REACT_SETTLE_S) {
            r->report.fn_mean_N += fn;
            r->report.fn_min_N = fmin(r->report.fn_min_N, fn);
            r->report.fn_max_N = fmax(r->report.fn_max_N, fn);
            r->report.fn_samples++;
        }
        if (arrived) {
            r->s_ = p->dist_m;
            finish(r, LS_REACT_END_MAX_DISTANCE, q_meas, ev);
            return false;
        }
        break;
    }
    case PH_BRAKE:
        r->vc_ = 0.0;
        if (travel_step(r, dt_s)) {
            r->s_ = r->s_next_;
            finish(r, r->end_, q_meas, ev);
            return false;
        }
        break;
    default: break;
    }
    return true;
}

/* Advance the tip along the travel (s) and the compliance direction (c)
 * and solve for the joints. */
static void advance_tip(ls_react_t *r, double dt_s, bool comply, const double q_meas[LS_N_JOINTS],
                        double q_cmd[LS_N_JOINTS], double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev)
{
    const ls_react_plan_t *p = &r->plan;
    double s_new = r->s_next_;
    if (r->phase_ == PH_RUN && s_new > p->dist_m) {
        s_new = p->dist_m;
    }
    double c_new = r->c_ + r->vc_ * dt_s;
    if (c_new > p->c_max_m) {
        c_new = p->c_max_m;
    } else if (c_new < -p->c_max_m) {
        c_new = -p->c_max_m;
    }
    if (!comply) {
        c_new = 0.0;
    }
    double P[16];
    memcpy(P, r->P0_, sizeof P);
    for (int i = 0; i < 3; i++) {
        P[12 + i] += s_new * r->d_[i] + c_new * r->n_[i];
    }
    double q_new[LS_N_JOINTS];
    char why[64];
    if (solve(r->model, P, r->tool_inv_, r->q_cmd_, dt_s, q_new, why, sizeof why) != LS_OK) {
        r->v_ = r->a_ = r->vc_ = 0.0;
        finish(r, LS_REACT_END_UNREACHABLE, q_meas, ev);
        return;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        qd_cmd[j] = (q_new[j] - r->q_cmd_[j]) / dt_s;
    }
    memcpy(r->q_cmd_, q_new, sizeof r->q_cmd_);
    memcpy(q_cmd, q_new, sizeof r->q_cmd_);
    r->s_ = s_new;
    r->c_ = c_new;
}

void ls_react_step(ls_react_t *r, double dt_s, const double q_meas[LS_N_JOINTS], const double *reading,
                   double q_cmd[LS_N_JOINTS], double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev)
{
    if (!r->active) {
        return;
    }
    const ls_react_plan_t *p = &r->plan;
    memcpy(q_cmd, r->q_cmd_, sizeof r->q_cmd_);
    memset(qd_cmd, 0, LS_N_JOINTS * sizeof qd_cmd[0]);
    if (reading == NULL || r->report.n_values <= p->component) {
        finish(r, LS_REACT_END_NO_SENSOR, q_meas, ev);
        return;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (fabs(q_meas[j] - r->q_cmd_[j]) > r->following_error_max_rad) {
            char t[64];
            ls_fmt_print(t, sizeof t, "following error joint %d: %.3g rad", j + 1, q_meas[j] - r->q_cmd_[j]);
            r->active = false;
            emit(ev, LS_MEV_FAULT, p->ref_seq, 0, t, q_meas);
            return;
        }
    }
    save_reading(r, reading);
    if (r->paused) {
        return;
    }
    r->t_ += dt_s;
    bool comply = p->kind == LS_REACT_COMPLY;
    double env = envelope_value(reading, r->report.n_values);

    r->s_next_ = r->s_; /* phases that do not travel keep it */
    if (r->stop_req_) {
        /* stopMotion: brake both motions and pause where they come to rest
         * (the force correction at the stop acceleration: not jerk-limited). */
        if (!r->stopping_) {
            plan_brake(r);
            r->stopping_ = true;
        }
        const bool at_rest = travel_step(r, dt_s);
        r->vc_ = toward_zero(r->vc_, p->a_stop_m_s2, dt_s);
        if (at_rest && r->vc_ == 0.0) {
            r->paused = true;
            r->stop_req_ = false;
            r->stopping_ = false;
            emit(ev, LS_MEV_PAUSED, p->ref_seq, 0, "on the move's line", q_meas);
        }
    } else if (!comply) {
        if (!guarded_step(r, reading, env, dt_s, q_meas, ev)) {
            return;
        }
    } else if (!comply_step(r, reading, env, dt_s, q_meas, ev)) {
        return;
    }
    advance_tip(r, dt_s, comply, q_meas, q_cmd, qd_cmd, ev);
}

/* ------------------------------------------------------------- jog */

void ls_react_jog_config(ls_react_t *r, const ls_jog_config_t *cfg)
{
    ls_react_jog_halt(r);
    r->jog_limited_ = false;
    r->jframe_ = r->jframe_next_ = LS_JOG_TOOL;
    r->jjoint_ = r->jjoint_next_ = false;
    if (cfg == NULL) {
        r->jog_on_ = false;
        return;
    }
    r->jog_ = *cfg;
    r->jog_on_ = true;
}

void ls_react_jog_mode(ls_react_t *r, ls_jog_frame_t frame, bool joint)
{
    r->jframe_next_ = (unsigned)frame < LS_JOG_FRAMES ? frame : LS_JOG_TOOL;
    r->jjoint_next_ = joint;
}

ls_jog_frame_t ls_react_jog_frame(const ls_react_t *r)
{
    return r->jframe_;
}

bool ls_react_jog_joint(const ls_react_t *r)
{
    return r->jjoint_;
}

void ls_react_jog_halt(ls_react_t *r)
{
    memset(r->jv_, 0, sizeof r->jv_);
    memset(r->ja_, 0, sizeof r->ja_);
    memset(r->jqv_, 0, sizeof r->jqv_);
    memset(r->jqa_, 0, sizeof r->jqa_);
}

bool ls_react_jog_on(const ls_react_t *r)
{
    return r->jog_on_;
}

/* One cycle of a twist vector (3 components, with their rates a) toward
 * its target: each component on its own time-optimal jerk-limited ramp
 * (ls_ramp), re-planned every cycle from the state it reached (the rest of
 * the same ramp while the target holds). Component i gets the share
 *   s_i = sqrt(b_i^2 + R (d_i / |d|)^2),  b_i = |a_i| / a_max,  R = 1 - sum b^2
 * of a_max and j_max, for the change d = target - v: never below what it
 * accelerates at already, the shares' squares summing to 1, so the vector's
 * acceleration and jerk keep a_max and j_max; from rest the components move
 * in proportion (the vector keeps its direction and ramps as one axis
 * would). Writes the exact displacement over dt_s. */
static void approach(double v[3], double a[3], const double target[3], double a_max, double j_max, double dt_s,
                     double disp[3])
{
    const double d[3] = { target[0] - v[0], target[1] - v[1], target[2] - v[2] };
    const double dn = norm3(d);
    double b[3], bsum = 0.0;
    for (int i = 0; i < 3; i++) {
        b[i] = fabs(a[i]) / a_max;
        bsum += b[i] * b[i];
    }
    const double rest = bsum < 1.0 ? 1.0 - bsum : 0.0;
    for (int i = 0; i < 3; i++) {
        const double di = dn > 1e-12 ? d[i] / dn : 0.0;
        const double share = sqrt(b[i] * b[i] + rest * di * di);
        if (!(share > 0.0)) {
            /* Not accelerating (b_i = 0) and no budget left, or at its
             * target: it keeps its speed this cycle (a rounding's worth
             * from the target: takes it). */
            if (fabs(d[i]) <= 1e-12) {
                v[i] = target[i];
            }
            disp[i] = v[i] * dt_s;
            continue;
        }
        ls_ramp_t rp;
        if (ls_ramp_plan(&rp, 0.0, v[i], a[i], target[i], a_max * share, j_max * share) != LS_OK) {
            v[i] = a[i] = disp[i] = 0.0; /* not finite: stop */
            continue;
        }
        ls_ramp_sample(&rp, dt_s, &disp[i], &v[i], &a[i]);
    }
}

static bool jog_still(const ls_react_t *r)
{
    for (int i = 0; i < 6; i++) {
        if (fabs(r->jv_[i]) >= 1e-12 || fabs(r->ja_[i]) >= 1e-9) {
            return false;
        }
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (fabs(r->jqv_[j]) >= 1e-12 || fabs(r->jqa_[j]) >= 1e-9) {
            return false;
        }
    }
    return true;
}

/* Where joint j comes to rest braking from (q, v, a) on its jog ramp. */
static double joint_rest(const ls_jog_config_t *c, int j, double q, double v, double a)
{
    ls_ramp_t rp;
    if (ls_ramp_plan(&rp, q, v, a, 0.0, c->qdd_rad_s2[j], c->qddd_rad_s3[j]) != LS_OK) {
        return q;
    }
    return rp.p_[3];
}

/* One cycle of single-joint jogging: the largest component of tw drives its
 * joint, the other joints ramp to rest. Each joint follows its target on
 * its own jerk-limited ramp (ls_ramp) and brakes in time for its limits: a
 * step whose braking distance would pass a limit becomes a brake (braking
 * from where the previous cycle's check held stays within the limit). */
static bool jog_joint_step(ls_react_t *r, double dt_s, const double tw[6], double q_cmd[LS_N_JOINTS],
                           double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev)
{
    const ls_jog_config_t *c = &r->jog_;
    const ls_robot_model_t *m = r->model;
    int k = -1;
    for (int i = 0; i < LS_N_JOINTS && i < 6; i++) {
        if (tw[i] != 0.0 && (k < 0 || fabs(tw[i]) > fabs(tw[k]))) {
            k = i;
        }
    }
    double q_new[LS_N_JOINTS];
    int limited = -1;
    bool moved = false;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const double target = j == k ? tw[j] * c->qd_rad_s[j] : 0.0;
        double p = q_cmd[j], v = r->jqv_[j], a = r->jqa_[j];
        ls_ramp_t rp;
        if (ls_ramp_plan(&rp, q_cmd[j], r->jqv_[j], r->jqa_[j], target, c->qdd_rad_s2[j], c->qddd_rad_s3[j]) == LS_OK) {
            ls_ramp_sample(&rp, dt_s, &p, &v, &a);
        } else {
            v = a = 0.0; /* not finite: stop */
        }
        const double rest = joint_rest(c, j, p, v, a);
        if (rest < m->q_min_rad[j] || rest > m->q_max_rad[j]) {
            /* brake: from the state whose rest the previous cycle found inside */
            if (ls_ramp_plan(&rp, q_cmd[j], r->jqv_[j], r->jqa_[j], 0.0, c->qdd_rad_s2[j], c->qddd_rad_s3[j]) ==
                LS_OK) {
                ls_ramp_sample(&rp, dt_s, &p, &v, &a);
            }
            if (j == k) {
                limited = j;
            }
        }
        if (p < m->q_min_rad[j] || p > m->q_max_rad[j]) {
            /* a start outside (it never is when the jog began inside): hold */
            p = q_cmd[j];
            v = a = 0.0;
            if (j == k) {
                limited = j;
            }
        }
        q_new[j] = p;
        r->jqv_[j] = v;
        r->jqa_[j] = a;
        moved = moved || p != q_cmd[j];
    }
    double F[16], P[16];
    ls_kin_fk(m, q_new, F);
    ls_pose_mul(F, c->tool, P);
    for (int i = 0; i < 3 && moved; i++) {
        if (P[12 + i] < m->workspace_min_m[i] || P[12 + i] > m->workspace_max_m[i]) {
            ls_react_jog_halt(r);
            if (!r->jog_limited_) {
                r->jog_limited_ = true;
                char t[80];
                ls_fmt_print(t, sizeof t, "stopped at workspace: tip %c %.4g m outside [%.4g, %.4g]", "xyz"[i],
                             P[12 + i], m -> workspace_min_m[i], m -> workspace_max_m[i]);
                emit(ev, LS_MEV_JOG, 0, 1, t, q_cmd);
            }
            return false;
        }
    }
    if (limited >= 0 && !r->jog_limited_) {
        r->jog_limited_ = true;
        char t[80];
        ls_fmt_print(t, sizeof t, "stopped at joint %d limit", limited + 1);
        emit(ev, LS_MEV_JOG, 0, 1, t, q_cmd);
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        qd_cmd[j] = (q_new[j] - q_cmd[j]) / dt_s;
        q_cmd[j] = q_new[j];
    }
    if (jog_still(r)) {
        ls_react_jog_halt(r); /* at rest: exactly, from now on */
    }
    return moved;
}

bool ls_react_jog_step(ls_react_t *r, double dt_s, const double *twist, double q_cmd[LS_N_JOINTS],
                       double qd_cmd[LS_N_JOINTS], ls_motion_events_t *ev)
{
    memset(qd_cmd, 0, LS_N_JOINTS * sizeof qd_cmd[0]);
    if (!r->jog_on_) {
        return false;
    }
    double tw[6] = { 0 };
    bool any = false;
    if (twist != NULL) {
        for (int i = 0; i < 6; i++) {
            double x = isfinite(twist[i]) ? twist[i] : 0.0;
            tw[i] = x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x);
            any = any || tw[i] != 0.0;
        }
    }
    if (!any) {
        r->jog_limited_ = false; /* released: the next push may report a limit again */
    }
    if (r->jframe_next_ != r->jframe_ || r->jjoint_next_ != r->jjoint_) {
        if (jog_still(r)) {
            r->jframe_ = r->jframe_next_;
            r->jjoint_ = r->jjoint_next_;
        } else {
            memset(tw, 0, sizeof tw); /* to rest in the old mode first */
        }
    }
    if (r->jjoint_) {
        return jog_joint_step(r, dt_s, tw, q_cmd, qd_cmd, ev);
    }
    const ls_jog_config_t *c = &r->jog_;
    double F[16], P[16];
    ls_kin_fk(r->model, q_cmd, F);
    ls_pose_mul(F, c->tool, P);
    double vt_jog[3] = { tw[0] * c->v_lin_m_s, tw[1] * c->v_lin_m_s, tw[2] * c->v_lin_m_s };
    double wt_jog[3] = { tw[3] * c->v_ang_rad_s, tw[4] * c->v_ang_rad_s, tw[5] * c->v_ang_rad_s };
    double vt[3], wt[3];
    if (r->jframe_ == LS_JOG_BASE) {
        memcpy(vt, vt_jog, sizeof vt);
        memcpy(wt, wt_jog, sizeof wt);
    } else {
        const double *axes = r->jframe_ == LS_JOG_WORLD ? c->world : P;
        rot_apply(axes, vt_jog, vt);
        rot_apply(axes, wt_jog, wt);
    }
    double dp[3], w[3];
    approach(r->jv_, r->ja_, vt, c->a_lin_m_s2, c->j_lin_m_s3, dt_s, dp);
    approach(r->jv_ + 3, r->ja_ + 3, wt, c->a_ang_rad_s2, c->j_ang_rad_s3, dt_s, w);
    const bool still = jog_still(r);
    if (still) {
        ls_react_jog_halt(r); /* at rest: exactly, from now on */
        if (norm3(dp) < 1e-15 && norm3(w) < 1e-15) {
            return false;
        }
        /* else the last cycle of a ramp: its displacement still counts */
    }
    double Rw[16], Pr[16], P1[16];
    rot_of_vector(w, Rw);
    memcpy(Pr, P, sizeof Pr);
    Pr[12] = Pr[13] = Pr[14] = 0.0;
    ls_pose_mul(Rw, Pr, P1);
    for (int i = 0; i < 3; i++) {
        P1[12 + i] = P[12 + i] + dp[i];
    }
    double tool_inv[16], q_new[LS_N_JOINTS];
    ls_pose_inv(c->tool, tool_inv);
    char why[64];
    if (solve(r->model, P1, tool_inv, q_cmd, dt_s, q_new, why, sizeof why) != LS_OK) {
        ls_react_jog_halt(r);
        if (!r->jog_limited_) {
            r->jog_limited_ = true;
            char t[80];
            ls_fmt_print(t, sizeof t, "stopped at %.60s", why);
            emit(ev, LS_MEV_JOG, 0, 1, t, q_cmd);
        }
        return false;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        qd_cmd[j] = (q_new[j] - q_cmd[j]) / dt_s;
        q_cmd[j] = q_new[j];
    }
    return true;
}

const char *ls_react_end_name(ls_react_end_t e)
{
    switch (e) {
    case LS_REACT_END_THRESHOLD: return "threshold";
    case LS_REACT_END_MAX_DISTANCE: return "max_distance";
    case LS_REACT_END_ENVELOPE: return "envelope";
    case LS_REACT_END_TIMEOUT: return "timeout";
    case LS_REACT_END_PANIC: return "panic";
    case LS_REACT_END_ABORTED: return "aborted";
    case LS_REACT_END_UNREACHABLE: return "unreachable";
    case LS_REACT_END_NO_SENSOR: return "no_sensor";
    }
    return "unknown";
}
