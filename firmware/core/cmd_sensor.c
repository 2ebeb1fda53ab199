/* Seed 3.7.2-3.7.3: moveReact, comply, manualControl (getSensorReading is in
 * cmd_settings.c).
 *
 * The handlers convert the user's units to SI, check every number, check the
 * straight line of the move with the path planner (so an unreachable move is
 * refused before anything moves) and hand an ls_react plan to the control
 * loop, which runs it (firmware/motion/ls_react.h). The loop reports the end
 * with LS_MEV_REACT_END; this file turns it into the move's one final notice.
 *
 * The guarded/compliant move in progress is core->run (ls_run.h, shared with
 * the planned motions); the manual mode is static here. */
#include <math.h>
#include <string.h>

#include "cmd_drives.h"
#include "cmd_motion.h"
#include "cmd_sensor.h"
#include "ls_control.h"
#include "landscape.h"
#include "ls_core_services.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_math.h"
#include "ls_motion.h"
#include "ls_react.h"
#include "ls_units.h"

/* Jog speeds at a full-scale twist, as a fraction of the model's Cartesian
 * maxima (docs/conformance.md, manualControl). */
#define JOG_FRAC_TEACHPENDANT 0.10
#define JOG_FRAC_SPACEBALL 0.25
/* comply defaults when the caller gives 0 */
#define COMPLY_DEFAULT_KP_M_S_N 5e-4
#define COMPLY_DEFAULT_CSPEED_FRAC 0.01
#define COMPLY_DEFAULT_TIMEOUT_S 30.0
/* comply max_timeout_s: 0 (the default above) or within these; a longer one
 * held a comply in free air at its range for as long as it said (1e308 s) */
#define COMPLY_MIN_TIMEOUT_S 0.1
#define COMPLY_MAX_TIMEOUT_S 3600.0
#define COMPLY_DEFAULT_PANIC_FACTOR 3.0
/* comply: travel and compliance directions may differ from orthogonal by this much */
#define COMPLY_MAX_COS 0.0872 /* 5 degrees */

/* What a guarded or compliant move needs besides core->run (ls_run.h). */
typedef struct {
    bool comply;
    size_t sensor;
    bool length;       /* the sensor reads a distance (units follow setUnits) */
    uint8_t component; /* moveReact: the watched component */
    int32_t panic_code;
    char seed_name[16];
} react_run_t;


/* ------------------------------------------------------------- helpers */

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static bool is_length_sensor(const char *name)
{
    return strcmp(name, "laser_standoff_sensor") == 0;
}

/* Force/torque components, in the order of a force sensor's values. */
static const char *const k_ft[] = { "Fx", "Fy", "Fz", "Tx", "Ty", "Tz" };

const char *ls_core_sensor_component(const hal_sensor_t *s, size_t k, const char **unit_si)
{
    if (s == NULL || s->name == NULL || k >= s->n_values) {
        return NULL;
    }
    if (is_length_sensor(s->name)) {
        *unit_si = "m";
        return k == 0 ? "distance" : "value";
    }
    if (k < sizeof k_ft / sizeof k_ft[0]) {
        *unit_si = k < 3 ? "N" : "Nm";
        return k_ft[k];
    }
    *unit_si = "";
    return "value";
}

/* The sensor called `name`, or an answer naming the ones there are. */
static int32_t find_sensor(ls_core_t *core, ls_call_t *call, const char *what, const char *name, size_t *idx)
{
    for (size_t i = 0; i < core->n_sensors; i++) {
        if (core->sensors[i].name != NULL && strcmp(core->sensors[i].name, name) == 0) {
            *idx = i;
            return 0;
        }
    }
    char list[96] = "";
    size_t n = 0;
    for (size_t i = 0; i < core->n_sensors && n < sizeof list; i++) {
        n += (size_t)ls_fmt_print(list + n, sizeof list - n, "%s%s", i ? ", " : "",
                                  core->sensors[i].name != NULL ? core->sensors[i].name : "?");
    }
    return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "%s: no sensor '%s': this controller has %s", what, name,
                    core->n_sensors > 0 ? list : "no sensors");
}

static int32_t refuse_if_manual(ls_core_t *core, ls_call_t *call, const char *what)
{
    if (core->ctl != NULL && ls_control_manual_on(core->ctl)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: manualControl %s is on: send manualControl off first", what,
                        core->sensor.mode);
    }
    return 0;
}

/* Check that the tip can go in a straight line from its pose at q0 to
 * `tip1` (workspace, IK, joint limits) at v_m_s all along (the move keeps
 * its speed): 0, or an answer. */
static int32_t check_line(ls_core_t *core, ls_call_t *call, const char *what, const double q0[LS_N_JOINTS],
                          const double tip1[16], double v_m_s)
{
    const ls_robot_model_t *m = core->model;
    ls_motion_cart_limits_t lim = {
        .v_lin_m_s = v_m_s,
        .a_lin_m_s2 = m->max_linear_accel_m_s2,
        .j_lin_m_s3 = m->max_linear_jerk_m_s3,
        .v_ang_rad_s = m->max_angular_speed_rad_s,
        .a_ang_rad_s2 = m->max_angular_accel_rad_s2,
        .j_ang_rad_s3 = m->max_angular_jerk_rad_s3,
        .joint_speed_frac = 1.0,
    };
    double tool[16];
    ls_mcmd_tool_pose(core, tool);
    char why[LS_MOTION_WHY_LEN];
    int st = ls_motion_seg_line(&core->sensor.check, m, q0, tool, tip1, &lim, why, sizeof why);
    if (st == 0) {
        st = ls_motion_seg_check_speed(&core->sensor.check, why, sizeof why);
    }
    if (st < 0) {
        return ls_reply(call, st == LS_ERANGE ? ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR : ls_RetCode_CMD_PARAM_ERR,
                        "%s refused, nothing moved: %s", what, why);
    }
    return 0;
}

/* Speed of a move: pct of the model's maximum, 0 = the setSpeed setting. */
static int32_t move_speed(ls_core_t *core, ls_call_t *call, const char *what, const char *field, double pct,
                          double *v_m_s)
{
    if (!isfinite(pct) || (pct != 0.0 && pct < LS_RATE_MIN_PCT) || pct > 100.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "%s: %s %.4g %% is out of range: give 0 (the current setSpeed) or a value in [%g, 100]", what,
                        field, pct, LS_RATE_MIN_PCT);
    }
    *v_m_s = pct > 0.0 ? core->model->max_linear_speed_m_s * pct / 100.0 : core->settings.linear_speed_m_s;
    *v_m_s = fmin(*v_m_s, core->model->max_linear_speed_m_s);
    return 0;
}

/* "key=v1,v2,..." with as many digits as fit a notice's 64 characters. */
static void values_text(const char *key, const double *v, size_t n, char *out, size_t cap)
{
    for (int prec = 6; prec >= 2; prec--) {
        size_t len = (size_t)ls_fmt_print(out, cap, "%s=", key);
        for (size_t k = 0; k < n && len < cap; k++) {
            len += (size_t)ls_fmt_print(out + len, cap - len, "%s%.*g", k ? "," : "", prec, v[k]);
        }
        if (len < cap) {
            return;
        }
    }
}

/* Common start of a guarded or compliant move. */
static int32_t start_react(ls_core_t *core, ls_call_t *call, ls_react_plan_t *slot, const ls_react_plan_t *plan,
                           const react_run_t *run)
{
    *slot = *plan;
    slot->ref_seq = call->req->seq;
    if (!ls_control_start_react(core->ctl, call->req->seq)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "%s: the control loop's command queue is full; try again",
                        run->seed_name);
    }
    ls_run_begin(core, call, true, run->seed_name, LS_PATH_NONE);
    core->run.comply = run->comply;
    core->run.sensor = run->sensor;
    core->run.length = run->length;
    core->run.component = run->component;
    core->run.panic_code = run->panic_code;
    return ls_reply(call, ls_RetCode_CMD_STARTED_OK, "%s started: expect %sComplete or an alarm", run->seed_name,
                    run->seed_name);
}

static ls_react_plan_t *take_slot(ls_core_t *core, ls_call_t *call, const char *what, int32_t *code)
{
    if (ls_drv_refuse_unhomed(core, call, what, code)) {
        return NULL;
    }
    ls_react_plan_t *slot = ls_control_react_slot(core->ctl);
    if (slot == NULL) {
        *code = ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                         "%s: the control loop has not taken the previous move yet; try again", what);
    }
    return slot;
}

/* The common end of moveReact and comply: limits, the tool, the straight line
 * from the current tip along `d` (tool frame) checked, then the start. */
static int32_t plan_and_start(ls_core_t *core, ls_call_t *call, const char *what, const hal_sensor_t *sensor,
                              const double d[3], ls_react_plan_t *plan, react_run_t *run)
{
    const ls_settings_t *set = &core->settings;
    int32_t code;
    plan->a_m_s2 = fmin(set->linear_accel_m_s2, core->model->max_linear_accel_m_s2);
    plan->j_m_s3 = ls_robot_model_linear_jerk(core->model, plan->a_m_s2);
    /* The brake: the model's maxima, jerk-limited as every other motion. */
    plan->a_stop_m_s2 = core->model->max_linear_accel_m_s2;
    plan->j_stop_m_s3 = core->model->max_linear_jerk_m_s3;
    ls_fmt_print(plan->sensor, sizeof plan->sensor, "%s", sensor->name);
    ls_mcmd_tool_pose(core, plan->tool);

    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    double F[16], P0[16], D[16], P1[16];
    ls_kin_fk(core->model, snap.q_cmd_rad, F);
    ls_pose_mul(F, plan->tool, P0);
    const double off[6] = { d[0], d[1], d[2], 0, 0, 0 };
    ls_pose_from_xyzrpy(off, D);
    ls_pose_mul(P0, D, P1);
    if ((code = check_line(core, call, what, snap.q_cmd_rad, P1, plan->v_m_s)) != 0) {
        return code;
    }
    ls_react_plan_t *slot = take_slot(core, call, what, &code);
    if (slot == NULL) {
        return code;
    }
    ls_fmt_print(run->seed_name, sizeof run->seed_name, "%s", what);
    return start_react(core, call, slot, plan, run);
}

/* ------------------------------------------------------------- moveReact */

int32_t ls_h_move_react(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const char *what = "moveReact";
    const ls_MoveReactReq *r = &call->req->cmd.move_react;
    if (core->ctl == NULL || core->model == NULL) {
        return ls_mcmd_no_arm(call, what);
    }
    int32_t code = refuse_if_manual(core, call, what);
    if (code != 0) {
        return code;
    }
    size_t si = 0;
    if ((code = find_sensor(core, call, what, r->sensor_type, &si)) != 0) {
        return code;
    }
    const hal_sensor_t *sensor = &core->sensors[si];
    bool length = is_length_sensor(sensor->name);
    if (r->motion_offsets_count != 3 && r->motion_offsets_count != 6) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: motion_offsets has %u values; give x y z (or x y z c_x c_y c_z) in the tool frame", what,
                        (unsigned)r->motion_offsets_count);
    }
    /* every number, the ones moveReact does not use too (gains, envelope min, c_speed) */
    if (!ls_mcmd_all_finite(r->motion_offsets, r->motion_offsets_count) ||
        !ls_mcmd_all_finite(r->thresholds, r->thresholds_count) || !ls_mcmd_all_finite(r->gains, r->gains_count) ||
        !ls_mcmd_all_finite(r->envelope_min, r->envelope_min_count) ||
        !ls_mcmd_all_finite(r->envelope_max, r->envelope_max_count) || !isfinite(r->motion_speed_pct) ||
        !isfinite(r->compliance_speed_pct)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: values must be finite numbers", what);
    }
    for (size_t k = 3; k < r->motion_offsets_count; k++) {
        if (r->motion_offsets[k] != 0.0) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "%s moves straight until the sensor reacts: c_x c_y c_z must be 0 (use comply for "
                            "compliant motion)",
                            what);
        }
    }
    ls_react_plan_t plan;
    memset(&plan, 0, sizeof plan);
    plan.kind = LS_REACT_GUARDED;
    double d[3];
    for (int i = 0; i < 3; i++) {
        d[i] = ls_units_to_si_linear(un.linear, r->motion_offsets[i]);
    }
    plan.dist_m = norm3(d);
    if (!(plan.dist_m > 1e-9)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: motion offset x y z is zero: give the direction and maximum distance to move", what);
    }
    for (int i = 0; i < 3; i++) {
        plan.dir_tool[i] = d[i] / plan.dist_m;
    }
    if ((code = move_speed(core, call, what, "speed", r->motion_speed_pct, &plan.v_m_s)) != 0) {
        return code;
    }
    /* the one threshold: its index is the sensor component */
    int comp = -1;
    for (size_t k = 0; k < r->thresholds_count; k++) {
        if (r->thresholds[k] != 0.0) {
            if (comp >= 0) {
                return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                                "%s: thresholds %d and %zu are both non-zero; give exactly one (its position selects "
                                "the sensor component)",
                                what, comp + 1, k + 1);
            }
            comp = (int)k;
        }
    }
    if (comp < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: every threshold is 0; give one non-zero threshold (t1 = component 0: Fx of a "
                        "force_sensor, the distance of a laser_standoff_sensor)",
                        what);
    }
    if (comp >= sensor->n_values) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "%s: threshold %d selects component %d, but %s has %u values", what, comp + 1, comp,
                        sensor->name, (unsigned)sensor->n_values);
    }
    plan.component = (uint8_t)comp;
    double t = r->thresholds[comp];
    if (length) {
        plan.threshold = ls_units_to_si_linear(un.linear, t);
        plan.below = true; /* stop when the distance falls below it */
        if (t < 0.0) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                            "%s: a distance threshold must be > 0 (the move stops when the distance falls below it)",
                            what);
        }
    } else {
        plan.threshold = t;
        plan.below = t < 0.0; /* a negative threshold: stop when the reading falls below it */
    }
    double env = r->envelope_max_count > 0 ? r->envelope_max[0] : 0.0;
    if (env < 0.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s: envelope max %.4g must be >= 0 (0: none)",
                        what, env);
    }
    if (env > 0.0 && length) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: the envelope bounds a force; %s reads a distance: give envelope max 0", what,
                        sensor->name);
    }
    if (env > 0.0 && env <= fabs(t)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "%s: envelope max %.4g N must exceed the threshold's magnitude %.4g", what, env, fabs(t));
    }
    plan.envelope = env;
    react_run_t run = { .comply = false, .sensor = si, .length = length, .component = plan.component };
    return plan_and_start(core, call, what, sensor, d, &plan, &run);
}

/* ------------------------------------------------------------- comply */

/* Gain along the unit direction n from per-component gains (Fx Fy Fz ...). */
static double gain_along(const double *g, size_t count, const double n[3])
{
    double k = 0.0;
    for (size_t i = 0; i < 3 && i < count; i++) {
        k += n[i] * n[i] * g[i];
    }
    return k;
}

int32_t ls_h_comply(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const char *what = "comply";
    const ls_ComplyReq *r = &call->req->cmd.comply;
    if (core->ctl == NULL || core->model == NULL) {
        return ls_mcmd_no_arm(call, what);
    }
    int32_t code = refuse_if_manual(core, call, what);
    if (code != 0) {
        return code;
    }
    size_t si = 0;
    if ((code = find_sensor(core, call, what, r->sensor_type, &si)) != 0) {
        return code;
    }
    const hal_sensor_t *sensor = &core->sensors[si];
    if (is_length_sensor(sensor->name) || sensor->n_values < 3) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s holds a contact force: use a force sensor, not %s", what,
                        sensor->name);
    }
    if (r->max_travel_count != 6) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: max_travel has %u values; give x y z (travel) c_x c_y c_z (compliance), tool frame", what,
                        (unsigned)r->max_travel_count);
    }
    if (r->thresholds_count != 3 && r->thresholds_count != 6) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: thresholds has %u values; give the target Fx Fy Fz (N) [Tx Ty Tz]", what,
                        (unsigned)r->thresholds_count);
    }
    if (!ls_mcmd_all_finite(r->max_travel, 6) || !ls_mcmd_all_finite(r->thresholds, r->thresholds_count) ||
        !ls_mcmd_all_finite(r->proportional_gains, r->proportional_gains_count) ||
        !ls_mcmd_all_finite(r->differential_gains, r->differential_gains_count) ||
        !ls_mcmd_all_finite(r->envelope_min, r->envelope_min_count) ||
        !ls_mcmd_all_finite(r->envelope_max, r->envelope_max_count) || !isfinite(r->max_timeout_s) ||
        !isfinite(r->speed_pct) || !isfinite(r->compliance_speed_pct)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: values must be finite numbers", what);
    }
    for (size_t k = 3; k < r->thresholds_count; k++) {
        if (r->thresholds[k] != 0.0) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "%s: torque targets (thresholds 4-6) are not supported: give 0", what);
        }
    }
    ls_react_plan_t plan;
    memset(&plan, 0, sizeof plan);
    plan.kind = LS_REACT_COMPLY;
    double d[3], c[3];
    for (int i = 0; i < 3; i++) {
        d[i] = ls_units_to_si_linear(un.linear, r->max_travel[i]);
        c[i] = ls_units_to_si_linear(un.linear, r->max_travel[3 + i]);
    }
    plan.dist_m = norm3(d);
    plan.c_max_m = norm3(c);
    if (!(plan.dist_m > 1e-9) || !(plan.c_max_m > 1e-9)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: give both a travel (x y z) and a compliance direction and range (c_x c_y c_z)", what);
    }
    for (int i = 0; i < 3; i++) {
        plan.dir_tool[i] = d[i] / plan.dist_m;
        plan.n_tool[i] = c[i] / plan.c_max_m;
    }
    double cosang =
        plan.dir_tool[0] * plan.n_tool[0] + plan.dir_tool[1] * plan.n_tool[1] + plan.dir_tool[2] * plan.n_tool[2];
    if (fabs(cosang) > COMPLY_MAX_COS) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: the travel and the compliance direction must be orthogonal (they are %.1f deg apart)",
                        what, acos(fmax(-1.0, fmin(1.0, cosang))) * 180.0 / LS_PI);
    }
    const double *ft = r->thresholds;
    plan.f_target_N = ft[0] * plan.n_tool[0] + ft[1] * plan.n_tool[1] + ft[2] * plan.n_tool[2];
    double off_axis[3];
    for (int i = 0; i < 3; i++) {
        off_axis[i] = ft[i] - plan.f_target_N * plan.n_tool[i];
    }
    if (fabs(plan.f_target_N) < 1e-9 || norm3(off_axis) > 1e-6 * (1.0 + fabs(plan.f_target_N))) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "%s: the target force (thresholds Fx Fy Fz) must be non-zero and along the compliance "
                        "direction c_x c_y c_z",
                        what);
    }
    for (size_t k = 0; k < r->proportional_gains_count; k++) {
        if (r->proportional_gains[k] < 0.0) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s: proportional gain %zu is negative", what,
                            k + 1);
        }
    }
    for (size_t k = 0; k < r->differential_gains_count; k++) {
        if (r->differential_gains[k] < 0.0) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s: differential gain %zu is negative", what,
                            k + 1);
        }
    }
    /* gains: (linear unit / s) per N and linear unit per N -> SI */
    double kp = gain_along(r->proportional_gains, r->proportional_gains_count, plan.n_tool);
    plan.kp_m_s_N = kp > 0.0 ? ls_units_to_si_linear(un.linear, kp) : COMPLY_DEFAULT_KP_M_S_N;
    plan.kd_m_N =
        ls_units_to_si_linear(un.linear, gain_along(r->differential_gains, r->differential_gains_count, plan.n_tool));
    if ((code = move_speed(core, call, what, "speed", r->speed_pct, &plan.v_m_s)) != 0) {
        return code;
    }
    if (!isfinite(r->compliance_speed_pct) || r->compliance_speed_pct < 0.0 || r->compliance_speed_pct > 100.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "%s: compliance speed %.4g %% is out of range: give 0 (default 1 %%) or a value in (0, 100]",
                        what, r->compliance_speed_pct);
    }
    double cfrac = r->compliance_speed_pct > 0.0 ? r->compliance_speed_pct / 100.0 : COMPLY_DEFAULT_CSPEED_FRAC;
    plan.vc_max_m_s = cfrac * core->model->max_linear_speed_m_s;
    if (r->max_timeout_s != 0.0 &&
        (r->max_timeout_s < COMPLY_MIN_TIMEOUT_S || r->max_timeout_s > COMPLY_MAX_TIMEOUT_S)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "%s: max_timeout %.4g s: allowed 0 (%g s) or [%g, %g] s", what, r->max_timeout_s,
                        COMPLY_DEFAULT_TIMEOUT_S, COMPLY_MIN_TIMEOUT_S, COMPLY_MAX_TIMEOUT_S);
    }
    plan.timeout_s = r->max_timeout_s > 0.0 ? r->max_timeout_s : COMPLY_DEFAULT_TIMEOUT_S;
    double env = r->envelope_max_count > 0 ? r->envelope_max[0] : 0.0;
    if (env < 0.0 || (env > 0.0 && env <= fabs(plan.f_target_N))) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "%s: envelope max %.4g N must be 0 (panic at %g x the target) or above the target %.4g N", what,
                        env, COMPLY_DEFAULT_PANIC_FACTOR, fabs(plan.f_target_N));
    }
    plan.panic_N = env > 0.0 ? env : COMPLY_DEFAULT_PANIC_FACTOR * fabs(plan.f_target_N);
    react_run_t run = { .comply = true, .sensor = si, .length = false, .panic_code = r->panic_stop_code };
    return plan_and_start(core, call, what, sensor, d, &plan, &run);
}

/* ------------------------------------------------------------- manualControl */

/* The jog's limits for a full-deflection speed of `frac` of the model's
 * maxima: Cartesian at the setAcceleration limits, single-joint mode at the
 * joints' maxima scaled by the acceleration percent. */
static void jog_config(ls_core_t *core, double frac, ls_jog_config_t *jog)
{
    const ls_robot_model_t *m = core->model;
    const ls_settings_t *set = &core->settings;
    memset(jog, 0, sizeof *jog);
    jog->v_lin_m_s = frac * m->max_linear_speed_m_s;
    jog->v_ang_rad_s = frac * m->max_angular_speed_rad_s;
    jog->a_lin_m_s2 = fmin(set->linear_accel_m_s2, m->max_linear_accel_m_s2);
    jog->a_ang_rad_s2 = fmin(set->angular_accel_rad_s2, m->max_angular_accel_rad_s2);
    jog->j_lin_m_s3 = ls_robot_model_linear_jerk(m, jog->a_lin_m_s2);
    jog->j_ang_rad_s3 = ls_robot_model_angular_jerk(m, jog->a_ang_rad_s2);
    ls_mcmd_tool_pose(core, jog->tool);
    ls_pose_from_xyzrpy(set->world_frame, jog->world);
    const double share = fmin(fmax(set->accel_pct, 1.0), 100.0) / 100.0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        jog->qd_rad_s[j] = frac * m->qd_max_rad_s[j];
        jog->qdd_rad_s2[j] = share * m->qdd_max_rad_s2[j];
        jog->qddd_rad_s3[j] = share * m->qddd_max_rad_s3[j];
    }
}

int32_t ls_h_manual_control(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const char *type = call->req->cmd.manual_control.type;
    double frac = 0.0;
    int kind = -1;
    if (strcmp(type, LS_MANUAL_NAME_TEACHPENDANT) == 0) {
        frac = JOG_FRAC_TEACHPENDANT;
        kind = LS_MANUAL_TEACHPENDANT;
    } else if (strcmp(type, LS_MANUAL_NAME_SPACEBALL) == 0) {
        frac = JOG_FRAC_SPACEBALL;
        kind = LS_MANUAL_SPACEBALL;
    } else if (strcmp(type, "off") != 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "manualControl: unknown type '%s': give %s, %s or off", type,
                        LS_MANUAL_NAME_TEACHPENDANT, LS_MANUAL_NAME_SPACEBALL);
    }
    if (core->ctl == NULL || core->model == NULL) {
        return ls_mcmd_no_arm(call, "manualControl");
    }
    hal_manual_t *dev = kind >= 0 ? core->manual[kind] : NULL;
    if (kind >= 0 && (dev == NULL || dev->read == NULL)) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                        "manualControl: no %s is composed in this controller (docs/deploy.md \"Manual devices\")",
                        type);
    }
    bool ok;
    ls_jog_config_t jog;
    int32_t refused = 0;
    if (kind >= 0 && ls_drv_refuse_unhomed(core, call, "manualControl", &refused)) {
        return refused;
    }
    if (kind >= 0) {
        jog_config(core, frac, &jog);
        ls_manual_config_t gate = core->manual_gate[kind];
        /* docs/conformance.md "manualControl": a teach pendant jogs only while its enabling switch is held */
        gate.enabling_switch = kind == LS_MANUAL_TEACHPENDANT;
        ok = ls_control_set_manual(core->ctl, dev, &jog, &gate, call->req->seq);
    } else {
        ok = ls_control_set_manual(core->ctl, NULL, NULL, NULL, call->req->seq);
    }
    if (!ok) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "manualControl: the control loop's command queue is full; try again");
    }
    ls_fmt_print(core->sensor.mode, sizeof core->sensor.mode, "%s", type);
    core->sensor.sup = kind >= 0 ? call->sup : LS_NO_SESSION;
    core->sensor.kind = kind;
    if (frac > 0.0) {
        ls_core_set_motion_state(core, ls_core_manual_motion_state(kind));
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK,
                        "%s jogging on: %.3g %s/s and %.3g %s/s at full deflection%s; motion commands are refused "
                        "until manualControl off",
                        type, ls_units_from_si_linear(un.linear, jog.v_lin_m_s), ls_units_linear_name(un.linear),
                        ls_units_from_si_angular(un.angular, jog.v_ang_rad_s), ls_units_angular_name(un.angular),
                        core->state == ls_State_RESTING ? "" : " (moves once activated)");
    }
    if (ls_core_motion_is_manual(core)) {
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "manual control off");
}

/* ------------------------------------------------------------- loop events */

static void rest(ls_core_t *core)
{
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_AT_REST_CHOICE);
    }
}

ls_EventId ls_core_sensor_final(const ls_cmd_finals_t *f, ls_react_end_t end)
{
    if (f == NULL) {
        return ls_EventId_EVENT_ID_NONE;
    }
    switch (end) {
    case LS_REACT_END_THRESHOLD:
    case LS_REACT_END_MAX_DISTANCE: return f->complete;
    case LS_REACT_END_ENVELOPE: return f->envelope;
    case LS_REACT_END_TIMEOUT: return f->timeout;
    case LS_REACT_END_PANIC: return f->panic_stop;
    case LS_REACT_END_ABORTED: return f->aborted;
    case LS_REACT_END_UNREACHABLE:
    case LS_REACT_END_NO_SENSOR: break;
    }
    return f->failed;
}

static void react_end(ls_core_t *core, const ls_ctl_event_t *ev)
{
    const ls_units_t un = ls_core_run_units(core); /* the final notice speaks the run's session's units */
    const ls_react_report_t *rep = &ev->react;
    const ls_settings_t *set = &core->settings;
    /* where: the tool tip in the world frame, current units */
    double F[16], T[16], W[16], Wi[16], tip[16], wt[16], pose[6];
    ls_kin_fk(core->model, ev->motion.q_rad, F);
    ls_mcmd_tool_pose(core, T);
    ls_pose_mul(F, T, tip);
    ls_pose_from_xyzrpy(set->world_frame, W);
    ls_pose_inv(W, Wi);
    ls_pose_mul(Wi, tip, wt);
    ls_pose_to_xyzrpy(wt, pose);
    ls_units_pose_from_si(un.linear, un.angular, pose, pose);
    char d_reason[40], d_pose[64], d_read[64], d_trav[40], d_extra[4][64];
    const char *data[10];
    size_t n = 0;
    const char *reason =
        rep->end == LS_REACT_END_MAX_DISTANCE && core->run.comply ? "max_travel" : ls_react_end_name(rep->end);
    ls_fmt_print(d_reason, sizeof d_reason, "reason=%s", reason);
    data[n++] = d_reason;
    values_text("pose", pose, 6, d_pose, sizeof d_pose);
    data[n++] = d_pose;
    if (core->run.length) {
        double dist = ls_units_from_si_linear(un.linear, rep->reading[0]);
        values_text("distance", &dist, 1, d_read, sizeof d_read);
    } else {
        values_text("force", rep->reading, rep->n_values, d_read, sizeof d_read);
    }
    data[n++] = d_read;
    char d_trig[48];
    if (rep->triggered) {
        double tv = core->run.length ? ls_units_from_si_linear(un.linear, rep->trigger) : rep->trigger;
        const char *comp = rep->end == LS_REACT_END_ENVELOPE ? "|F|"
                           : core->run.length                ? "distance"
                           : core->run.component < 6         ? k_ft[core->run.component]
                                                             : "value";
        ls_fmt_print(d_trig, sizeof d_trig, "trigger=%s:%.6g", comp, tv);
        data[n++] = d_trig;
    }
    double trav = ls_units_from_si_linear(un.linear, rep->travelled_m);
    values_text("travelled", &trav, 1, d_trav, sizeof d_trav);
    data[n++] = d_trav;
    if (core->run.comply) {
        values_text("fn_mean", &rep->fn_mean_N, 1, d_extra[0], sizeof d_extra[0]);
        values_text("fn_min", &rep->fn_min_N, 1, d_extra[1], sizeof d_extra[1]);
        values_text("fn_max", &rep->fn_max_N, 1, d_extra[2], sizeof d_extra[2]);
        data[n++] = d_extra[0];
        data[n++] = d_extra[1];
        data[n++] = d_extra[2];
        if (rep->end == LS_REACT_END_PANIC) {
            ls_fmt_print(d_extra[3], sizeof d_extra[3], "panic_stop_code=%d", (int)core->run.panic_code);
            data[n++] = d_extra[3];
        }
    }
    bool ok = rep->end == LS_REACT_END_THRESHOLD || rep->end == LS_REACT_END_MAX_DISTANCE;
    const ls_EventId id = ls_core_sensor_final(core->run.finals, rep->end);
    core->run.active = false;
    rest(core);
    ls_core_notify_to(core, core->run.addr, core->run.epoch, ok ? ls_NoticeKind_EVENT : ls_NoticeKind_ALARM, id,
                      core->run.ref_seq, true, data, n);
}

static void jog_event(ls_core_t *core, const ls_ctl_event_t *ev)
{
    if (ev->motion.index == 0) {
        /* drives on with manual control on: only the supervisor that
         * switched it on may jog; a new owner gets it switched off. */
        if (core->sensor.sup < 0 || core->owner != core->sensor.sup) {
            (void)ls_control_set_manual(core->ctl, NULL, NULL, NULL, 0);
            ls_fmt_print(core->sensor.mode, sizeof core->sensor.mode, "off");
            core->sensor.sup = LS_NO_SESSION;
            core->sensor.kind = -1;
            return;
        }
        if (core->state == ls_State_RESTING) {
            ls_core_set_motion_state(core, ls_core_manual_motion_state(core->sensor.kind));
        }
        return;
    }
    char d1[72];
    ls_fmt_print(d1, sizeof d1, "reason=%s", ev->motion.text);
    const char *data[] = { d1 };
    ls_core_notify(core, core->sensor.sup, ls_NoticeKind_EVENT, ls_EventId_manualLimit, 0, false, data, 1);
}

/* What the operator did on the manual device, to the session that switched
 * manual control on: an event each, an alarm (and a log line) for a lost
 * device. Nothing once manual control is off. */
static void manual_event(ls_core_t *core, const ls_ctl_event_t *ev)
{
    if (core->sensor.sup < 0 || core->sensor.kind < 0 || core->sensor.kind >= LS_MANUAL_KINDS) {
        return;
    }
    const ls_manual_event_t *e = &ev->manual;
    const hal_manual_t *dev = core->manual[core->sensor.kind];
    const char *path = dev != NULL ? dev->name : "";
    char d0[32], d1[HAL_MANUAL_NAME_LEN + 8], d2[HAL_MANUAL_NAME_LEN + 8];
    ls_fmt_print(d0, sizeof d0, "device=%s", core->sensor.mode);
    const char *data[] = { d0, d1, d2 };
    ls_NoticeKind kind = ls_NoticeKind_EVENT;
    ls_EventId id;
    size_t n = 2;
    switch (e->kind) {
    case LS_MANUAL_EV_SWITCH:
        id = ls_EventId_manualSwitch;
        ls_fmt_print(d1, sizeof d1, "switch=%s", ls_manual_switch_name((ls_manual_switch_t)e->value));
        break;
    case LS_MANUAL_EV_OVERRIDE:
        id = ls_EventId_manualOverride;
        ls_fmt_print(d1, sizeof d1, "percent=%d", (int)e->value);
        break;
    case LS_MANUAL_EV_FRAME:
        id = ls_EventId_manualFrame;
        ls_fmt_print(d1, sizeof d1, "frame=%s", e->joint ? "joint" : ls_manual_frame_name((ls_jog_frame_t)e->value));
        break;
    case LS_MANUAL_EV_LOST:
        kind = ls_NoticeKind_ALARM;
        id = ls_EventId_manualDeviceLost;
        ls_fmt_print(d1, sizeof d1, "reason=%s", ls_manual_lost_name((ls_manual_lost_t)e->value));
        ls_fmt_print(d2, sizeof d2, "path=%s", path);
        n = 3;
        if (core->act.log_warn != NULL) {
            char line[HAL_MANUAL_NAME_LEN + 96];
            ls_fmt_print(line, sizeof line, "manual device %s (%s) lost (%s): the jog stopped", core->sensor.mode, path,
                         ls_manual_lost_name((ls_manual_lost_t)e->value));
            core->act.log_warn(core->act.ctx, line);
        }
        break;
    case LS_MANUAL_EV_FOUND:
        id = ls_EventId_manualDeviceFound;
        ls_fmt_print(d1, sizeof d1, "path=%s", path);
        break;
    default: return;
    }
    ls_core_notify(core, core->sensor.sup, kind, id, 0, false, data, n);
}

bool ls_core_sensor_on_event(ls_core_t *core, const ls_ctl_event_t *ev)
{
    bool mine = core->run.active && core->run.react && ev->ref_seq == core->run.ref_seq;
    switch (ev->kind) {
    case LS_CEV_MOTION:
        if (ev->motion.kind == LS_MEV_REACT_END) {
            /* During a halt (deactivate, fault, owner lost) the halt sends the
             * final notice once the drives are off (ls_run_tick). */
            if (mine && !core->halt.active) {
                react_end(core, ev);
            }
            return true;
        }
        if (ev->motion.kind == LS_MEV_JOG) {
            jog_event(core, ev);
            return true;
        }
        /* LS_MEV_FAULT: the motion handler latches the fault, whose halt ends the run. */
        return false;
    case LS_CEV_FAULT: return false; /* the same */
    case LS_CEV_CMD_FAILED:
        if (mine && !core->halt.active) {
            char d[80];
            ls_fmt_print(d, sizeof d, "fault=%s", ev->text);
            const char *extra[] = { d };
            rest(core);
            ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_ERROR_CHOICE);
            ls_run_finish(core, LS_RUN_END_FAULT, extra, 1);
            return true;
        }
        return false;
    case LS_CEV_DIO_CHANGED:
    case LS_CEV_ARM_EVENT:
    case LS_CEV_ENABLED:
    case LS_CEV_ENABLE_FAILED:
    case LS_CEV_HOMED:
    case LS_CEV_HOME_FAILED: return false;
    case LS_CEV_MANUAL: manual_event(core, ev); return true;
    }
    return false;
}
