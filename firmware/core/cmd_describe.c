/* describe (ours): the device publishes every limit a client must respect,
 * so that no client learns one from a refusal (docs/protocol.md "Device
 * description"). Each figure is read from its one home: the field bounds
 * from the table protocol/gen_registry.py derives from landscape.options,
 * table sizes from the core's headers, the DIO map, sensors and tool rack
 * from the composed HAL, joint and Cartesian limits from the robot model,
 * each joint's homing from the control loop.
 * Everything is SI, whatever setUnits chose. */
#include <string.h>

#include "cmd_sensor.h"
#include "ls_control.h"
#include "ls_core_services.h"
#include "ls_fmt.h"
#include "ls_robot_urdf.h"

_Static_assert(LS_FIELD_LIMIT_COUNT <= pb_arraysize(ls_DescribeRes, field_limits),
               "landscape.options: raise ls.DescribeRes.field_limits max_count to hold every bounded uplink field");
_Static_assert(LS_DOWNLINK_LIMIT_COUNT <= pb_arraysize(ls_DescribeRes, downlink_limits),
               "landscape.options: raise ls.DescribeRes.downlink_limits max_count to hold every downlink string");
_Static_assert(pb_arraysize(ls_FieldLimit, path) >= sizeof(((ls_field_limit_t *)0)->path),
               "FieldLimit.path must hold the generated paths");
_Static_assert(LS_CORE_MAX_DIO_UNITS <= pb_arraysize(ls_DescribeRes, dio_units),
               "landscape.options: ls.DescribeRes.dio_units must hold LS_CORE_MAX_DIO_UNITS");
_Static_assert(LS_N_JOINTS <= pb_arraysize(ls_DescribeRes, joints), "ls.DescribeRes.joints must hold every joint");
_Static_assert(sizeof(((ls_DescribeRes *)0)->robot_model) >= LS_ROBOT_MODEL_NAME_MAX &&
                   sizeof(((ls_DescribeRobotRes *)0)->robot_model) >= LS_ROBOT_MODEL_NAME_MAX,
               "landscape.options: robot_model must hold LS_ROBOT_MODEL_NAME_MAX bytes");
_Static_assert(LS_N_JOINTS <= pb_arraysize(ls_DescribeRes, homing), "ls.DescribeRes.homing must hold every joint");
/* The schema's HomeState is the HAL's hal_home_t on the wire. */
_Static_assert((int)ls_HomeState_HOME_NOT_HOMED == (int)HAL_HOME_NOT_HOMED &&
                   (int)ls_HomeState_HOME_HOMING == (int)HAL_HOME_HOMING &&
                   (int)ls_HomeState_HOME_HOMED == (int)HAL_HOME_HOMED &&
                   (int)ls_HomeState_HOME_FAILED == (int)HAL_HOME_FAILED,
               "ls.HomeState and hal_home_t must agree");

/* Each joint's homing, on an arm whose drives home (the loop's snapshot). */
static void describe_homing(ls_core_t *core, ls_DescribeRes *r)
{
    if (core->ctl == NULL) {
        return;
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    r->homing_timeout_ms = snap.home_timeout_ms;
    if (snap.home_timeout_ms == 0u) {
        return;
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        ls_JointHoming *h = &r->homing[r->homing_count++];
        h->required = (snap.home_required & (1u << j)) != 0u;
        h->state = (ls_HomeState)snap.joint_home[j];
    }
}

static void copy_limit(const ls_field_limit_t *g, ls_FieldLimit *f)
{
    for (uint8_t k = 0; k < g->depth; k++) {
        f->path[f->path_count++] = g->path[k];
    }
    f->max_bytes = (uint16_t)g->max_bytes;
    f->max_count = (uint16_t)g->max_count;
}

static void describe_limits(ls_DescribeRes *r)
{
    for (size_t i = 0; i < LS_FIELD_LIMIT_COUNT; i++) {
        copy_limit(&ls_field_limits[i], &r->field_limits[r->field_limits_count++]);
    }
    for (size_t i = 0; i < LS_DOWNLINK_LIMIT_COUNT; i++) {
        copy_limit(&ls_downlink_limits[i], &r->downlink_limits[r->downlink_limits_count++]);
    }
}

/* Returns false when the HAL has more than the message holds (the answer
 * then says so instead of publishing a partial list as if it were whole). */
static bool describe_devices(const ls_core_t *core, ls_DescribeRes *r)
{
    bool whole = true;
    if (core->dio_units > LS_CORE_MAX_DIO_UNITS) {
        whole = false;
    }
    for (uint16_t u = 0; u < core->dio_units && u < LS_CORE_MAX_DIO_UNITS; u++) {
        ls_DioUnitInfo *d = &r->dio_units[r->dio_units_count++];
        d->unit_id = u;
        d->input_mask = core->dio_info[u].input_mask;
        d->output_mask = core->dio_info[u].output_mask;
    }
    for (size_t i = 0; i < core->n_sensors; i++) {
        const hal_sensor_t *s = &core->sensors[i];
        if (r->sensors_count >= pb_arraysize(ls_DescribeRes, sensors) || s->name == NULL) {
            whole = false;
            break;
        }
        ls_SensorInfo *o = &r->sensors[r->sensors_count++];
        ls_fmt_print(o->name, sizeof o->name, "%s", s->name);
        const char *unit = "";
        const char *comp;
        for (size_t k = 0; (comp = ls_core_sensor_component(s, k, &unit)) != NULL; k++) {
            if (o->components_count >= pb_arraysize(ls_SensorInfo, components)) {
                whole = false;
                break;
            }
            ls_SensorComponent *c = &o->components[o->components_count++];
            ls_fmt_print(c->name, sizeof c->name, "%s", comp);
            ls_fmt_print(c->unit, sizeof c->unit, "%s", unit);
        }
    }
    if (core->tool != NULL && core->tool->ops != NULL && core->tool->ops->name != NULL) {
        const char *name;
        for (int i = 0; (name = core->tool->ops->name(core->tool->self, i)) != NULL; i++) {
            if (r->tools_count >= pb_arraysize(ls_DescribeRes, tools) || strlen(name) >= sizeof r->tools[0]) {
                whole = false;
                break;
            }
            ls_fmt_print(r->tools[r->tools_count++], sizeof r->tools[0], "%s", name);
        }
    }
    return whole;
}

static void describe_model(const ls_robot_model_t *m, ls_DescribeRes *r)
{
    ls_fmt_print(r->robot_model, sizeof r->robot_model, "%s", m->name);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        ls_JointLimit *l = &r->joints[r->joints_count++];
        l->min_rad = m->q_min_rad[j];
        l->max_rad = m->q_max_rad[j];
        l->max_velocity_rad_s = m->qd_max_rad_s[j];
        l->max_accel_rad_s2 = m->qdd_max_rad_s2[j];
    }
    r->max_linear_speed_m_s = m->max_linear_speed_m_s;
    r->max_angular_speed_rad_s = m->max_angular_speed_rad_s;
    r->max_linear_accel_m_s2 = m->max_linear_accel_m_s2;
    r->max_angular_accel_rad_s2 = m->max_angular_accel_rad_s2;
    for (int k = 0; k < 3; k++) {
        r->workspace_min_m[r->workspace_min_m_count++] = m->workspace_min_m[k];
        r->workspace_max_m[r->workspace_max_m_count++] = m->workspace_max_m[k];
    }
    r->reach_m = ls_robot_model_reach_m(m);
}

int32_t ls_h_describe(struct ls_core *core, struct ls_call *call)
{
    ls_DescribeRes *r = &call->res->result.describe;
    r->max_sessions = LS_MAX_SUPERVISORS;
    r->max_paths = LS_PATH_MAX;
    r->max_points_per_path = LS_PATH_MAX_POINTS;
    r->max_dio_watches = LS_MAX_DIO_WATCHES;
    r->max_cycles = LS_PATH_MAX_CYCLES;
    r->min_rate_pct = LS_RATE_MIN_PCT;
    r->frame_angle_max_rad = LS_FRAME_ANGLE_MAX_RAD;
    r->max_answer_bytes = (uint32_t)sizeof call->res->ret_msg - 1u; /* less the NUL */
    r->max_notice_datum_bytes = (uint32_t)sizeof(((ls_Notice *)0)->data[0]) - 1u;
    r->auth_policy = ls_core_policy(core);
    describe_limits(r);
    bool whole = describe_devices(core, r);
    if (core->model != NULL) {
        describe_model(core->model, r);
    }
    describe_homing(core, r);
    if (!whole) {
        return ls_reply(call, ls_RetCode_CMD_EXEC_OK,
                        "described, but the HAL has more sensors, components or tools than describe holds "
                        "(protocol/landscape.options): the lists are cut");
    }
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "%s",
                    core->model != NULL ? "described (SI units)" : "described (SI units); no arm is composed");
}

/* describeRobot (ours): the URDF of the model, one window of it per answer
 * (docs/protocol.md "Robot description"). The text is formatted afresh for
 * every piece: no buffer holds all of it. */
int32_t ls_h_describe_robot(struct ls_core *core, struct ls_call *call)
{
    const ls_DescribeRobotReq *rq = &call->req->cmd.describe_robot;
    ls_DescribeRobotRes *r = &call->res->result.describe_robot;
    if (core->model == NULL) {
        return ls_reply(call, ls_RetCode_CMD_UNSUPPORTED_ERR, "no arm is composed: there is no robot to describe");
    }
    size_t total = 0;
    const int n = ls_robot_urdf_window(core->model, rq->offset, r->urdf, sizeof r->urdf, &total);
    if (n < 0 || rq->offset > total) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "offset %u is past the end of the URDF (%u bytes): ask from 0 to %u", (unsigned)rq->offset,
                        (unsigned)total, (unsigned)total);
    }
    r->offset = rq->offset;
    r->total_bytes = (uint32_t)total;
    ls_fmt_print(r->robot_model, sizeof r->robot_model, "%s", core->model->name);
    ls_fmt_print(r->ik_class, sizeof r->ik_class, "%s", ls_ik_class_name(core->model->ik_class));
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "URDF bytes %u..%u of %u", (unsigned)rq->offset,
                    (unsigned)(rq->offset + (uint32_t)n), (unsigned)total);
}
