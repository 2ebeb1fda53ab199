/* Seed 3.2 set commands, 3.3 get commands and 3.7.1 getSensorReading.
 *
 * core->settings holds SI values; every number crosses the wire in the units
 * chosen with setUnits (ls_units.h). A refused set command changes nothing:
 * every check runs before the first store. The dispatcher has already checked
 * the state and the owner. */
#include <math.h>
#include <string.h>

#include "ls_control.h"
#include "ls_core_services.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

static int32_t no_model(ls_call_t *call, const char *cmd)
{
    return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                    "%s: no robot model is composed in this firmware: start landscaped with an arm", cmd);
}

/* A value in (0, max]: the message names the parameter, the value and the
 * range in the units the supervisor speaks (`unit`). */
static int32_t check_rate(ls_call_t *call, const char *what, double v, double max, const char *unit)
{
    const double min = max * LS_RATE_MIN_FRACTION;
    if (v >= min && v <= max) {
        return ls_RetCode_CMD_EXEC_OK;
    }
    return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s %g %s: allowed [%g, %g]", what, v, unit, min, max);
}

/* ---------------------------------------------------------------- set commands */

int32_t ls_h_set_speed(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const ls_SetSpeedReq *rq = &call->req->cmd.set_speed;
    ls_settings_t *st = &core->settings;
    const double v = rq->speed;
    if (!isfinite(v)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "speed %g is not a number: give a finite value", v);
    }
    char unit[32];
    int32_t rc;
    switch (rq->attribute) {
    case ls_SpeedType_PERCENT_SPEED:
        rc = check_rate(call, "PERCENT_SPEED", v, 100.0, "%");
        if (rc < 0) {
            return rc;
        }
        st->speed_pct = v;
        st->cart_speed_from_pct = true;
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "PERCENT_SPEED %g %%", v);
    case ls_SpeedType_LINEAR_SPEED: {
        if (core->model == NULL) {
            return no_model(call, "setSpeed LINEAR_SPEED");
        }
        ls_fmt_print(unit, sizeof unit, "%s/s", ls_units_linear_name(un.linear));
        rc = check_rate(call, "LINEAR_SPEED", v, ls_units_from_si_linear(un.linear, core->model->max_linear_speed_m_s),
                        unit);
        if (rc < 0) {
            return rc;
        }
        /* fmin: the range check passed in the user's unit; rounding must not exceed the model's limit in SI */
        st->cart_speed_from_pct = false;
        st->linear_speed_m_s = fmin(ls_units_to_si_linear(un.linear, v), core->model->max_linear_speed_m_s);
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "LINEAR_SPEED %g %s", v, unit);
    }
    case ls_SpeedType_ANGULAR_SPEED: {
        if (core->model == NULL) {
            return no_model(call, "setSpeed ANGULAR_SPEED");
        }
        ls_fmt_print(unit, sizeof unit, "%s/s", ls_units_angular_name(un.angular));
        rc = check_rate(call, "ANGULAR_SPEED", v,
                        ls_units_from_si_angular(un.angular, core->model->max_angular_speed_rad_s), unit);
        if (rc < 0) {
            return rc;
        }
        st->cart_speed_from_pct = false;
        st->angular_speed_rad_s = fmin(ls_units_to_si_angular(un.angular, v), core->model->max_angular_speed_rad_s);
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "ANGULAR_SPEED %g %s", v, unit);
    }
    }
    return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                    "attribute %d is not a SpeedType: allowed PERCENT_SPEED (0), LINEAR_SPEED (1), ANGULAR_SPEED (2)",
                    (int)rq->attribute);
}

int32_t ls_h_set_acceleration(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const ls_SetAccelerationReq *rq = &call->req->cmd.set_acceleration;
    ls_settings_t *st = &core->settings;
    const double v = rq->accel;
    if (!isfinite(v)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "acceleration %g is not a number: give a finite value", v);
    }
    char unit[32];
    int32_t rc;
    switch (rq->attribute) {
    case ls_AccelType_PERCENT_ACCEL:
        rc = check_rate(call, "PERCENT_ACCEL", v, 100.0, "%");
        if (rc < 0) {
            return rc;
        }
        st->accel_pct = v;
        st->cart_accel_from_pct = true;
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "PERCENT_ACCEL %g %%", v);
    case ls_AccelType_LINEAR_ACCEL:
        if (core->model == NULL) {
            return no_model(call, "setAcceleration LINEAR_ACCEL");
        }
        ls_fmt_print(unit, sizeof unit, "%s/s^2", ls_units_linear_name(un.linear));
        rc = check_rate(call, "LINEAR_ACCEL", v, ls_units_from_si_linear(un.linear, core->model->max_linear_accel_m_s2),
                        unit);
        if (rc < 0) {
            return rc;
        }
        st->cart_accel_from_pct = false;
        st->linear_accel_m_s2 = fmin(ls_units_to_si_linear(un.linear, v), core->model->max_linear_accel_m_s2);
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "LINEAR_ACCEL %g %s", v, unit);
    case ls_AccelType_ANGULAR_ACCEL:
        if (core->model == NULL) {
            return no_model(call, "setAcceleration ANGULAR_ACCEL");
        }
        ls_fmt_print(unit, sizeof unit, "%s/s^2", ls_units_angular_name(un.angular));
        rc = check_rate(call, "ANGULAR_ACCEL", v,
                        ls_units_from_si_angular(un.angular, core->model->max_angular_accel_rad_s2), unit);
        if (rc < 0) {
            return rc;
        }
        st->cart_accel_from_pct = false;
        st->angular_accel_rad_s2 = fmin(ls_units_to_si_angular(un.angular, v), core->model->max_angular_accel_rad_s2);
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "ANGULAR_ACCEL %g %s", v, unit);
    }
    return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                    "attribute %d is not an AccelType: allowed PERCENT_ACCEL (0), LINEAR_ACCEL (1), ANGULAR_ACCEL (2)",
                    (int)rq->attribute);
}

/* Shared by setToolOffset and setWorldCartesianFrame: 6 finite values in the
 * current units -> SI into out (only on success). */
static int32_t take_pose(ls_core_t *core, ls_call_t *call, const char *what, const double *v, pb_size_t n,
                         double out[6])
{
    const ls_units_t un = ls_core_units(core, call->sup);
    if (n != 6) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s takes 6 values (x y z roll pitch yaw), got %u", what,
                        (unsigned)n);
    }
    for (int i = 0; i < 6; i++) {
        if (!isfinite(v[i])) {
            static const char *const names[6] = { "x", "y", "z", "roll", "pitch", "yaw" };
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "%s: %s is %g: give finite values", what, names[i], v[i]);
        }
    }
    ls_units_pose_to_si(un.linear, un.angular, v, out);
    if (core->model != NULL) {
        static const char *const axes[3] = { "x", "y", "z" };
        const double reach_m = ls_robot_model_reach_m(core->model);
        for (int i = 0; i < 3; i++) {
            if (fabs(out[i]) > reach_m) {
                return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                                "%s: %s %g %s is beyond the arm's reach: allowed [-%g, %g] %s", what, axes[i], v[i],
                                ls_units_linear_name(un.linear), ls_units_from_si_linear(un.linear, reach_m),
                                ls_units_from_si_linear(un.linear, reach_m), ls_units_linear_name(un.linear));
            }
        }
    }
    for (int i = 3; i < 6; i++) {
        if (fabs(out[i]) > LS_FRAME_ANGLE_MAX_RAD) {
            static const char *const rpy[3] = { "roll", "pitch", "yaw" };
            return ls_reply(
                call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "%s: %s %g %s: allowed [-%g, %g] %s", what, rpy[i - 3],
                v[i], ls_units_angular_name(un.angular), ls_units_from_si_angular(un.angular, LS_FRAME_ANGLE_MAX_RAD),
                ls_units_from_si_angular(un.angular, LS_FRAME_ANGLE_MAX_RAD), ls_units_angular_name(un.angular));
        }
    }
    return ls_RetCode_CMD_EXEC_OK;
}

int32_t ls_h_set_tool_offset(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const ls_SetToolOffsetReq *rq = &call->req->cmd.set_tool_offset;
    double si[6];
    int32_t rc = take_pose(core, call, "setToolOffset", rq->offset, rq->offset_count, si);
    if (rc < 0) {
        return rc;
    }
    memcpy(core->settings.tool_offset, si, sizeof si);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "tool offset set (%s, %s)", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

int32_t ls_h_set_world_cartesian_frame(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const ls_SetWorldCartesianFrameReq *rq = &call->req->cmd.set_world_cartesian_frame;
    double si[6];
    int32_t rc = take_pose(core, call, "setWorldCartesianFrame", rq->frame, rq->frame_count, si);
    if (rc < 0) {
        return rc;
    }
    memcpy(core->settings.world_frame, si, sizeof si);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "world frame set (%s, %s)", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

int32_t ls_h_set_units(struct ls_core *core, struct ls_call *call)
{
    const ls_SetUnitsReq *rq = &call->req->cmd.set_units;
    if (!ls_units_linear_valid(rq->linear)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "linear unit %d is not a LinearUnit: allowed METERS (0), MILLIMETERS (1), CENTIMETERS (2), "
                        "INCHES (3), FEET (4)",
                        (int)rq->linear);
    }
    if (!ls_units_angular_valid(rq->angular)) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "angular unit %d is not an AngularUnit: allowed RADIANS (0), DEGREES (1)", (int)rq->angular);
    }
    /* The caller's session only: other supervisors keep theirs, and the
     * next session starts in SI (docs/conformance.md, setUnits). */
    core->sessions[call->sup].units = (ls_units_t){ .linear = rq->linear, .angular = rq->angular };
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "units: %s, %s", ls_units_linear_name(rq->linear),
                    ls_units_angular_name(rq->angular));
}

/* ---------------------------------------------------------------- get commands */

int32_t ls_h_get_units(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    ls_GetUnitsRes *r = &call->res->result.get_units;
    ls_fmt_print(r->linear_units, sizeof r->linear_units, "%s", ls_units_linear_name(un.linear));
    ls_fmt_print(r->angular_units, sizeof r->angular_units, "%s", ls_units_angular_name(un.angular));
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s, %s", r->linear_units, r->angular_units);
}

/* Per-joint values in the angular unit: pct % of the model's limits. */
static pb_size_t joint_rates(ls_units_t un, const double *limits, double pct, double *out)
{
    for (int j = 0; j < LS_N_JOINTS; j++) {
        out[j] = ls_units_from_si_angular(un.angular, limits[j] * pct / 100.0);
    }
    return LS_N_JOINTS;
}

int32_t ls_h_get_velocities(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    if (core->model == NULL) {
        return no_model(call, "getVelocities");
    }
    const ls_settings_t *st = &core->settings;
    ls_GetVelocitiesRes *r = &call->res->result.get_velocities;
    r->percent_velocity = st->speed_pct;
    r->world_linear_velocity = ls_units_from_si_linear(un.linear, st->linear_speed_m_s);
    r->world_angular_velocity = ls_units_from_si_angular(un.angular, st->angular_speed_rad_s);
    r->joint_velocities_count = joint_rates(un, core->model->qd_max_rad_s, st->speed_pct, r->joint_velocities);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s/s, %s/s", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

int32_t ls_h_get_accelerations(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    if (core->model == NULL) {
        return no_model(call, "getAccelerations");
    }
    const ls_settings_t *st = &core->settings;
    ls_GetAccelerationsRes *r = &call->res->result.get_accelerations;
    r->percent_accel = st->accel_pct;
    r->world_linear_accel = ls_units_from_si_linear(un.linear, st->linear_accel_m_s2);
    r->world_angular_accel = ls_units_from_si_angular(un.angular, st->angular_accel_rad_s2);
    r->joint_accels_count = joint_rates(un, core->model->qdd_max_rad_s2, st->accel_pct, r->joint_accels);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s/s^2, %s/s^2", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

int32_t ls_h_get_max_velocities(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    if (core->model == NULL) {
        return no_model(call, "getMaxVelocities");
    }
    ls_GetMaxVelocitiesRes *r = &call->res->result.get_max_velocities;
    r->max_world_linear_velocity = ls_units_from_si_linear(un.linear, core->model->max_linear_speed_m_s);
    r->max_world_angular_velocity = ls_units_from_si_angular(un.angular, core->model->max_angular_speed_rad_s);
    r->max_joint_velocities_count = joint_rates(un, core->model->qd_max_rad_s, 100.0, r->max_joint_velocities);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s/s, %s/s", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

int32_t ls_h_get_max_accelerations(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    if (core->model == NULL) {
        return no_model(call, "getMaxAccelerations");
    }
    ls_GetMaxAccelerationsRes *r = &call->res->result.get_max_accelerations;
    r->max_world_linear_accel = ls_units_from_si_linear(un.linear, core->model->max_linear_accel_m_s2);
    r->max_world_angular_accel = ls_units_from_si_angular(un.angular, core->model->max_angular_accel_rad_s2);
    r->max_joint_accels_count = joint_rates(un, core->model->qdd_max_rad_s2, 100.0, r->max_joint_accels);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s/s^2, %s/s^2", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

int32_t ls_h_get_tool_offsets(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    ls_GetToolOffsetsRes *r = &call->res->result.get_tool_offsets;
    ls_units_pose_from_si(un.linear, un.angular, core->settings.tool_offset, r->offset);
    r->offset_count = 6;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "flange -> tool tip (%s, %s)", ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

/* The tool tip in the world frame. settings.world_frame is the world frame's
 * pose in the base frame (seed: "offsets from the robot's base frame to the
 * world frame"), so T_world_tip = inv(T_base_world) * FK(q) * T_flange_tip. */
int32_t ls_h_get_robot_position(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    if (core->ctl == NULL || core->model == NULL) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                        "getRobotPosition: no arm backend is composed in this firmware, there is no position to read");
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    double T_base_flange[16], T_base_world[16], T_world_base[16], T_flange_tip[16], T[16], T_world_tip[16];
    if (ls_kin_fk(core->model, snap.q_rad, T_base_flange) != LS_OK) {
        return ls_reply(call, ls_RetCode_CMD_ERR,
                        "getRobotPosition: the measured joint angles are not finite: check the arm backend");
    }
    ls_pose_from_xyzrpy(core->settings.world_frame, T_base_world);
    ls_pose_inv(T_base_world, T_world_base);
    ls_pose_from_xyzrpy(core->settings.tool_offset, T_flange_tip);
    ls_pose_mul(T_world_base, T_base_flange, T);
    ls_pose_mul(T, T_flange_tip, T_world_tip);
    double pose_si[6];
    ls_pose_to_xyzrpy(T_world_tip, pose_si);

    ls_GetRobotPositionRes *r = &call->res->result.get_robot_position;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        r->joints[j] = ls_units_from_si_angular(un.angular, snap.q_rad[j]);
    }
    r->joints_count = LS_N_JOINTS;
    ls_units_pose_from_si(un.linear, un.angular, pose_si, r->world_pose);
    r->world_pose_count = 6;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "joints in %s; tool tip in the world frame (%s, %s)",
                    ls_units_angular_name(un.angular), ls_units_linear_name(un.linear),
                    ls_units_angular_name(un.angular));
}

/* Sensors whose every value is a length (converted to the linear unit).
 * Forces and torques stay in N and Nm: they are not lengths, and setUnits
 * names no force unit. */
static bool sensor_is_length(const char *name)
{
    return strcmp(name, "laser_standoff_sensor") == 0;
}

int32_t ls_h_get_sensor_reading(struct ls_core *core, struct ls_call *call)
{
    const ls_units_t un = ls_core_units(core, call->sup);
    const char *want = call->req->cmd.get_sensor_reading.sensor_type;
    size_t idx = core->n_sensors;
    for (size_t i = 0; i < core->n_sensors; i++) {
        if (core->sensors[i].name != NULL && strcmp(core->sensors[i].name, want) == 0) {
            idx = i;
            break;
        }
    }
    if (idx == core->n_sensors) {
        char list[128] = "";
        size_t n = 0;
        for (size_t i = 0; i < core->n_sensors && n < sizeof list; i++) {
            int w = ls_fmt_print(list + n, sizeof list - n, "%s%s", i > 0 ? ", " : "",
                                 core->sensors[i].name != NULL ? core->sensors[i].name : "?");
            if (w < 0) {
                break;
            }
            n += (size_t)w;
        }
        if (core->n_sensors == 0) {
            return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "no sensor '%s': this controller has no sensors",
                            want);
        }
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "no sensor '%s': this controller has %s", want, list);
    }
    if (core->ctl == NULL) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR,
                        "getSensorReading: no control loop is composed, sensors are not read");
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    const hal_sensor_t *s = &core->sensors[idx];
    ls_GetSensorReadingRes *r = &call->res->result.get_sensor_reading;
    size_t n = s->n_values;
    size_t cap = sizeof r->current_data / sizeof r->current_data[0];
    if (n > cap) {
        n = cap;
    }
    if (n > HAL_SENSOR_MAX_VALUES) {
        n = HAL_SENSOR_MAX_VALUES;
    }
    bool length = sensor_is_length(s->name);
    for (size_t k = 0; k < n; k++) {
        double v = snap.sensor[idx][k];
        r->current_data[k] = length ? ls_units_from_si_linear(un.linear, v) : v;
    }
    r->current_data_count = (pb_size_t)n;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s: %u values (%s)", s->name, (unsigned)n,
                    length ? ls_units_linear_name(un.linear) : "SI: forces N, torques Nm, not scaled by setUnits");
}
