/* The controller core, black box (core_fixture.h). The settings and queries:
 * units, set commands and their refusals, the robot position and the sensors. */
#include "core_fixture.h"

static void test_units_conversions(void **state)
{
    (void)state;
    assert_true(ls_units_to_si_linear(ls_LinearUnit_MILLIMETERS, 1500.0) == 1.5);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_CENTIMETERS, 250.0) == 2.5);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_INCHES, 10.0) == 0.254);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_FEET, 2.0) == 0.6096);
    assert_true(ls_units_to_si_linear(ls_LinearUnit_METERS, 0.125) == 0.125);
    assert_true(ls_units_from_si_linear(ls_LinearUnit_INCHES, 0.0254) == 1.0);
    assert_true(ls_units_from_si_linear(ls_LinearUnit_FEET, 0.9144) == 3.0);
    assert_true(ls_units_to_si_angular(ls_AngularUnit_DEGREES, 180.0) == LS_PI);
    assert_true(ls_units_from_si_angular(ls_AngularUnit_DEGREES, LS_PI / 2) == 90.0);
    assert_true(ls_units_from_si_angular(ls_AngularUnit_RADIANS, 0.5) == 0.5);
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_METERS), "meters");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_MILLIMETERS), "millimeters");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_CENTIMETERS), "centimeters");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_INCHES), "inches");
    assert_string_equal(ls_units_linear_name(ls_LinearUnit_FEET), "feet");
    assert_string_equal(ls_units_linear_name((ls_LinearUnit)7), "unknown");
    assert_string_equal(ls_units_angular_name(ls_AngularUnit_RADIANS), "radians");
    assert_string_equal(ls_units_angular_name(ls_AngularUnit_DEGREES), "degrees");
    assert_string_equal(ls_units_angular_name((ls_AngularUnit)2), "unknown");
    assert_true(isnan(ls_units_to_si_linear((ls_LinearUnit)9, 1.0)));
    assert_true(isnan(ls_units_to_si_angular((ls_AngularUnit)-1, 1.0)));
    assert_false(ls_units_linear_valid((ls_LinearUnit)5));
    assert_true(ls_units_linear_valid(ls_LinearUnit_FEET));
    assert_false(ls_units_angular_valid((ls_AngularUnit)2));

    double p[6] = { 100.0, -200.0, 50.0, 90.0, -45.0, 180.0 }, si[6], back[6];
    ls_units_pose_to_si(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES, p, si);
    assert_true(si[0] == 0.1 && si[1] == -0.2 && si[2] == 0.05);
    assert_true(si[3] == LS_PI / 2 && si[4] == -LS_PI / 4 && si[5] == LS_PI);
    ls_units_pose_from_si(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES, si, back);
    for (int i = 0; i < 6; i++) {
        assert_near(back[i], p[i], 1e-12);
    }
    ls_units_pose_to_si(ls_LinearUnit_INCHES, ls_AngularUnit_RADIANS, p, p); /* in place */
    assert_true(p[0] == 2.54 && p[3] == 90.0);
}

static void test_units_round_trip(void **state)
{
    (void)state;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);

    req(ls_Request_get_units_tag);
    const ls_Response *r = must(HOST_A); /* the session that set them reads them */
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_string_equal(r->result.get_units.linear_units, "millimeters");
    assert_string_equal(r->result.get_units.angular_units, "degrees");

    ls_SetToolOffsetReq *t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    const double off[6] = { 10.0, -20.0, 150.0, 90.0, 0.0, -30.0 };
    memcpy(t->offset, off, sizeof off);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_near(g_core.settings.tool_offset[2], 0.15, 1e-15);
    assert_near(g_core.settings.tool_offset[3], LS_PI / 2, 1e-15);

    req(ls_Request_get_tool_offsets_tag);
    r = must(HOST_A);
    assert_int_equal(r->result.get_tool_offsets.offset_count, 6);
    for (int i = 0; i < 6; i++) {
        assert_near(r->result.get_tool_offsets.offset[i], off[i], 1e-9);
    }

    ls_SetSpeedReq *sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_LINEAR_SPEED;
    sp->has_attribute = true;
    sp->speed = 500.0; /* mm/s */
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_ANGULAR_SPEED;
    sp->has_attribute = true;
    sp->speed = 90.0; /* deg/s */
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    sp = &req(ls_Request_set_speed_tag)->cmd.set_speed;
    sp->attribute = ls_SpeedType_PERCENT_SPEED;
    sp->has_attribute = true;
    sp->speed = 40.0;
    sp->has_speed = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_near(g_core.settings.linear_speed_m_s, 0.5, 1e-15);
    assert_near(g_core.settings.angular_speed_rad_s, LS_PI / 2, 1e-15);

    req(ls_Request_get_velocities_tag);
    r = must(HOST_A);
    const ls_GetVelocitiesRes *v = &r->result.get_velocities;
    assert_near(v->percent_velocity, 40.0, 0);
    assert_near(v->world_linear_velocity, 500.0, 1e-9);
    assert_near(v->world_angular_velocity, 90.0, 1e-9);
    assert_int_equal(v->joint_velocities_count, 6);
    /* joint 1: 40 % of 2.5 rad/s = 1 rad/s */
    assert_near(v->joint_velocities[0], 180.0 / LS_PI, 1e-9);
    assert_near(v->joint_velocities[5], 0.4 * 6.0 * 180.0 / LS_PI, 1e-9);

    ls_SetAccelerationReq *ac = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    ac->attribute = ls_AccelType_LINEAR_ACCEL;
    ac->has_attribute = true;
    ac->accel = 2000.0; /* mm/s^2 */
    ac->has_accel = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ac = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    ac->attribute = ls_AccelType_ANGULAR_ACCEL;
    ac->has_attribute = true;
    ac->accel = 360.0; /* deg/s^2 */
    ac->has_accel = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    ac = &req(ls_Request_set_acceleration_tag)->cmd.set_acceleration;
    ac->attribute = ls_AccelType_PERCENT_ACCEL;
    ac->has_attribute = true;
    ac->accel = 100.0;
    ac->has_accel = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_get_accelerations_tag);
    const ls_GetAccelerationsRes *a = &must(HOST_A)->result.get_accelerations;
    assert_near(a->percent_accel, 100.0, 0);
    assert_near(a->world_linear_accel, 2000.0, 1e-9);
    assert_near(a->world_angular_accel, 360.0, 1e-9);
    assert_near(a->joint_accels[0], 8.0 * 180.0 / LS_PI, 1e-9);

    req(ls_Request_get_max_velocities_tag);
    const ls_GetMaxVelocitiesRes *mv = &must(HOST_A)->result.get_max_velocities;
    assert_near(mv->max_world_linear_velocity, 1000.0, 1e-9);
    assert_near(mv->max_world_angular_velocity, 3.0 * 180.0 / LS_PI, 1e-9);
    assert_int_equal(mv->max_joint_velocities_count, 6);
    assert_near(mv->max_joint_velocities[2], 3.0 * 180.0 / LS_PI, 1e-9);
    req(ls_Request_get_max_accelerations_tag);
    const ls_GetMaxAccelerationsRes *ma = &must(HOST_A)->result.get_max_accelerations;
    assert_near(ma->max_world_linear_accel, 4000.0, 1e-9);
    assert_near(ma->max_world_angular_accel, 12.0 * 180.0 / LS_PI, 1e-9);
    assert_near(ma->max_joint_accels[5], 20.0 * 180.0 / LS_PI, 1e-9);

    /* back to inches: the same SI settings read in the new unit */
    set_units(ls_LinearUnit_INCHES, ls_AngularUnit_RADIANS);
    req(ls_Request_get_tool_offsets_tag);
    r = must(HOST_A);
    assert_near(r->result.get_tool_offsets.offset[2], 0.15 / 0.0254, 1e-9);
    assert_near(r->result.get_tool_offsets.offset[3], LS_PI / 2, 1e-12);
    req(ls_Request_get_velocities_tag);
    assert_near(must(HOST_A)->result.get_velocities.world_linear_velocity, 0.5 / 0.0254, 1e-9);
    /* the other session reads the same SI settings in its own units, SI */
    req(ls_Request_get_tool_offsets_tag);
    r = must(HOST_B);
    assert_near(r->result.get_tool_offsets.offset[2], 0.15, 1e-12);
    req(ls_Request_get_velocities_tag);
    assert_near(must(HOST_B)->result.get_velocities.world_linear_velocity, 0.5, 1e-12);
}

static void test_set_refusals_name_value_and_range(void **state)
{
    (void)state;
    const ls_settings_t before = g_core.settings;
    const char *msg;
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 150.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "PERCENT_SPEED 150 %: allowed [0.1, 100]");
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 0.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, -5.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    /* docs/protocol.md "Limits": a subnormal (or anything below 0.1 %) planned a move that never ended */
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 1e-300, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 1e-300, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "PERCENT_ACCEL 1e-300 %: allowed [0.1, 100]");
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 0.09, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 0.1, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 50.0, &msg), ls_RetCode_CMD_EXEC_OK);
    g_core.settings = before;
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, 1.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_SPEED 1.5 meters/s: allowed [0.001, 1]");
    assert_int_equal(set_speed(ls_SpeedType_ANGULAR_SPEED, 3.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "ANGULAR_SPEED 3.5 radians/s: allowed [0.003, 3]");
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, NAN, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, INFINITY, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(set_speed((ls_SpeedType)3, 10.0, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(msg, "PERCENT_SPEED (0), LINEAR_SPEED (1), ANGULAR_SPEED (2)"));

    assert_int_equal(set_accel(ls_AccelType_PERCENT_ACCEL, 100.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "PERCENT_ACCEL 100.5 %: allowed [0.1, 100]");
    assert_int_equal(set_accel(ls_AccelType_LINEAR_ACCEL, 5.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_ACCEL 5 meters/s^2: allowed [0.004, 4]");
    assert_int_equal(set_accel(ls_AccelType_ANGULAR_ACCEL, 0.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "ANGULAR_ACCEL 0 radians/s^2: allowed [0.012, 12]");
    assert_int_equal(set_accel(ls_AccelType_ANGULAR_ACCEL, -INFINITY, &msg), ls_RetCode_CMD_PARAM_ERR);
    assert_int_equal(set_accel((ls_AccelType)-1, 10.0, &msg), ls_RetCode_CMD_PARAM_ERR);

    ls_SetToolOffsetReq *t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 5;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "setToolOffset takes 6 values (x y z roll pitch yaw), got 5");
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[0] = 0.1;
    t->offset[4] = NAN;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "pitch"));
    ls_SetWorldCartesianFrameReq *w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 0;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "setWorldCartesianFrame takes 6 values (x y z roll pitch yaw), got 0");
    w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 6;
    w->frame[1] = -INFINITY;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_ERR);
    /* docs/protocol.md "Limits": within the arm's reach (ls_robot_model_reach_m), angles within +-2 pi */
    const double reach_m = ls_robot_model_reach_m(g_core.model);
    assert_true(reach_m > 1.0 && reach_m < 2.0);
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 1e308;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(r->ret_msg, "setToolOffset: z 1e+308 meters is beyond the arm's reach"));
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[0] = 4.0;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 6;
    w->frame[3] = 100.0;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(r->ret_msg, "roll 100 radians"));
    w = &req(ls_Request_set_world_cartesian_frame_tag)->cmd.set_world_cartesian_frame;
    w->frame_count = 6;
    w->frame[1] = -(reach_m + 0.01);
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    /* docs/protocol.md "Limits": empty names */
    ls_PathLoadReq *pl = &req(ls_Request_path_load_tag)->cmd.path_load;
    pl->number_of_points = 1;
    pl->has_frame = pl->has_motion_type = pl->has_offset_type = pl->has_number_of_points = true;
    pl->tags_count = 1;
    pl->tags[0].joints_count = 6;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_string_equal(r->ret_msg, "pathLoad: path_name is empty: give the path a name");

    ls_SetUnitsReq *u = &req(ls_Request_set_units_tag)->cmd.set_units;
    u->linear = (ls_LinearUnit)5;
    u->has_linear = true;
    u->has_angular = true; /* present (RADIANS): the refusal is the linear unit's */
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_ERR);
    assert_non_null(strstr(r->ret_msg, "linear unit 5"));
    u = &req(ls_Request_set_units_tag)->cmd.set_units;
    u->linear = ls_LinearUnit_MILLIMETERS;
    u->has_linear = true;
    u->angular = (ls_AngularUnit)2;
    u->has_angular = true;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_ERR);

    /* all-or-nothing: nothing above changed a setting (the half-valid setUnits included) */
    assert_memory_equal(&g_core.settings, &before, sizeof before);
    /* and an offset within the reach is taken */
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 0.25;
    t->offset[5] = -3.0;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_true(g_core.settings.tool_offset[2] == 0.25);
    g_core.settings = before;

    /* the range follows the units */
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, 2000.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_SPEED 2000 millimeters/s: allowed [1, 1000]");
    assert_int_equal(set_speed(ls_SpeedType_LINEAR_SPEED, 1000.0, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_true(g_core.settings.linear_speed_m_s == 1.0);
    assert_int_equal(set_speed(ls_SpeedType_ANGULAR_SPEED, 171.0, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(set_speed(ls_SpeedType_ANGULAR_SPEED, 173.0, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "ANGULAR_SPEED 173 degrees/s: allowed [0.171887, 171.887]");
    assert_int_equal(set_accel(ls_AccelType_LINEAR_ACCEL, 4000.5, &msg), ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_string_equal(msg, "LINEAR_ACCEL 4000.5 millimeters/s^2: allowed [4, 4000]");
}

static void test_set_commands_in_resting_too(void **state)
{
    (void)state;
    g_core.state = ls_State_RESTING;
    const char *msg;
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 100.0, &msg), ls_RetCode_CMD_EXEC_OK);
    assert_true(g_core.settings.speed_pct == 100.0);
    g_core.state = ls_State_MOVING;
    assert_int_equal(set_speed(ls_SpeedType_PERCENT_SPEED, 10.0, &msg), ls_RetCode_CMD_WRONG_STATE_ERR);
    assert_true(g_core.settings.speed_pct == 100.0);
}

static void test_robot_position_is_the_tool_tip_in_the_world(void **state)
{
    (void)state;
    const double q[6] = { 0.3, -0.4, 0.8, 0.1, 0.6, -0.2 };
    memcpy(g_snap.q_rad, q, sizeof q);
    /* world frame 0.5 m along the base x axis, tool 0.1 m along the flange z axis */
    g_core.settings.world_frame[0] = 0.5;
    g_core.settings.tool_offset[2] = 0.1;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);

    req(ls_Request_get_robot_position_tag);
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    const ls_GetRobotPositionRes *p = &r->result.get_robot_position;
    assert_int_equal(p->joints_count, 6);
    for (int j = 0; j < 6; j++) {
        assert_near(p->joints[j], q[j] * 180.0 / LS_PI, 1e-9);
    }
    double F[16], flange[6];
    assert_int_equal(ls_kin_fk(&ls_robot_model_default, q, F), LS_OK);
    ls_pose_to_xyzrpy(F, flange);
    /* tip = flange origin + 0.1 * flange z axis (third column), minus the world origin */
    const double tip[3] = { F[12] + 0.1 * F[8] - 0.5, F[13] + 0.1 * F[9], F[14] + 0.1 * F[10] };
    assert_int_equal(p->world_pose_count, 6);
    for (int i = 0; i < 3; i++) {
        assert_near(p->world_pose[i], tip[i] * 1000.0, 1e-9);
        assert_near(p->world_pose[i + 3], flange[i + 3] * 180.0 / LS_PI, 1e-9);
    }

    /* a rotated world frame: yaw 90 deg maps base +y to world -x */
    g_core.settings.world_frame[0] = 0.0;
    g_core.settings.world_frame[5] = LS_PI / 2;
    g_core.settings.tool_offset[2] = 0.0;
    req(ls_Request_get_robot_position_tag);
    p = &must(HOST_A)->result.get_robot_position;
    assert_near(p->world_pose[0], F[13] * 1000.0, 1e-9);
    assert_near(p->world_pose[1], -F[12] * 1000.0, 1e-9);
    assert_near(p->world_pose[2], F[14] * 1000.0, 1e-9);

    g_core.ctl = NULL;
    req(ls_Request_get_robot_position_tag);
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_non_null(strstr(r->ret_msg, "no arm backend"));
}

static void test_sensor_reading(void **state)
{
    (void)state;
    const double ft[6] = { 1.5, -2.0, 30.0, 0.25, -0.5, 0.125 };
    memcpy(g_snap.sensor[0], ft, sizeof ft);
    g_snap.sensor[1][0] = 0.2375;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);

    ls_GetSensorReadingReq *s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "force_sensor");
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.get_sensor_reading.current_data_count, 6);
    for (int i = 0; i < 6; i++) {
        assert_true(r->result.get_sensor_reading.current_data[i] == ft[i]); /* N and Nm, unscaled */
    }
    s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "laser_standoff_sensor");
    r = must(HOST_A);
    assert_int_equal(r->result.get_sensor_reading.current_data_count, 1);
    assert_near(r->result.get_sensor_reading.current_data[0], 237.5, 1e-9);
    s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "laser_standoff_sensor");
    assert_near(must(HOST_B)->result.get_sensor_reading.current_data[0], 0.2375, 1e-12); /* B's session: SI */

    s = &req(ls_Request_get_sensor_reading_tag)->cmd.get_sensor_reading;
    snprintf(s->sensor_type, sizeof s->sensor_type, "sonar");
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_string_equal(r->ret_msg, "no sensor 'sonar': this controller has force_sensor, laser_standoff_sensor");
    g_core.n_sensors = 0;
    req(ls_Request_get_sensor_reading_tag);
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_UNSUPPORTED_ERR);
    assert_string_equal(r->ret_msg, "no sensor '': this controller has no sensors");
}

/* Units belong to the session that set them; a new session starts in SI and the connect answer says so. */
static void test_units_belong_to_the_session(void **state)
{
    (void)state;
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);
    get_units_of(HOST_A, "millimeters", "degrees");
    get_units_of(HOST_B, "meters", "radians");
    /* HOST_B's numbers are read in its own units: 0.05 m, not 0.05 mm */
    ls_SetToolOffsetReq *t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 0.05;
    assert_int_equal(must(HOST_B)->ret_code, ls_RetCode_CMD_NOT_OWNER_ERR); /* the owner sets; B only reads */
    t = &req(ls_Request_set_tool_offset_tag)->cmd.set_tool_offset;
    t->offset_count = 6;
    t->offset[2] = 50.0; /* mm */
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_EXEC_OK);
    req(ls_Request_get_tool_offsets_tag);
    assert_near(must(HOST_B)->result.get_tool_offsets.offset[2], 0.05, 1e-12);
    /* a new session of the same supervisor starts in SI, and is told so */
    const ls_Response *r = connect_with(HOST_A, 0, ls_DisconnectAction_DISCONNECT_CONFIGURED);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_EXEC_OK);
    assert_int_equal(r->result.connect.linear_unit, ls_LinearUnit_METERS);
    assert_int_equal(r->result.connect.angular_unit, ls_AngularUnit_RADIANS);
    assert_true(r->result.connect.owner); /* ownership stays with the address */
    get_units_of(HOST_A, "meters", "radians");
    req(ls_Request_get_tool_offsets_tag);
    assert_near(must(HOST_A)->result.get_tool_offsets.offset[2], 0.05, 1e-12);
}

/* A move beyond a joint limit or the workspace is refused in the units the
 * request was written in, not in SI (docs/protocol.md "Limits": the
 * allowed range in the units in force). */
static void test_range_refusals_speak_the_session_units(void **state)
{
    (void)state;
    setup_core(ls_State_RESTING);
    atomic_store(&g_ctl.plan_slot_busy, false); /* the loop took the previous test's plan */
    set_units(ls_LinearUnit_MILLIMETERS, ls_AngularUnit_DEGREES);
    ls_MoveAbsoluteReq *m = &req(ls_Request_move_absolute_tag)->cmd.move_absolute;
    snprintf(m->point_name, sizeof m->point_name, "far");
    m->frame = ls_ReferenceFrame_JOINT_FRAME;
    m->has_frame = true;
    m->values_count = 6;
    m->values[0] = 500.0;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    char want[96];
    snprintf(want, sizeof want, "joint 1: 500 deg beyond its limit %.4g deg",
             ls_robot_model_default.q_max_rad[0] * 180.0 / 3.14159265358979323846);
    assert_non_null(strstr(r->ret_msg, want));
    m = &req(ls_Request_move_absolute_tag)->cmd.move_absolute;
    snprintf(m->point_name, sizeof m->point_name, "high");
    m->frame = ls_ReferenceFrame_BASE_CARTESIAN_FRAME;
    m->has_frame = true;
    m->values_count = 6;
    m->values[2] = 5000.0; /* 5 m up */
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    snprintf(want, sizeof want, "axis z: 5000 mm beyond the workspace limit %.4g mm",
             ls_robot_model_default.workspace_max_m[2] * 1000.0);
    assert_non_null(strstr(r->ret_msg, want));
}

/* docs/protocol.md "Limits": a finite but absurd Cartesian value of a move, an
 * arc or a path point is refused like a joint value, naming it and the bound,
 * before anything is planned (a TOOL_FRAME yaw of -1e308 turned the tool to an
 * orientation of its own; a far arc point was refused naming a NaN tip). */
static void test_absurd_cartesian_values_are_refused_naming_them(void **state)
{
    (void)state;
    g_core.state = ls_State_RESTING;
    const double reach2 = LS_POSE_REACH_FACTOR * ls_robot_model_reach_m(g_core.model);
    ls_MoveRelativeReq *m = &req(ls_Request_move_relative_tag)->cmd.move_relative;
    snprintf(m->point_name, sizeof m->point_name, "p");
    m->frame = ls_ReferenceFrame_TOOL_FRAME;
    m->has_frame = true;
    m->values_count = 6;
    m->values[5] = -1e308;
    const ls_Response *r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    char want[160];
    snprintf(want, sizeof want, "moveRelative: values yaw -1e+308 radians is out of range: allowed [-%g, %g] radians",
             LS_FRAME_ANGLE_MAX_RAD, LS_FRAME_ANGLE_MAX_RAD);
    assert_non_null(strstr(r->ret_msg, want));
    ls_MoveArcReq *a = &req(ls_Request_move_arc_tag)->cmd.move_arc;
    snprintf(a->point_name, sizeof a->point_name, "arc");
    a->frame = ls_ReferenceFrame_BASE_CARTESIAN_FRAME;
    a->has_frame = a->has_offset_type = true;
    a->arc_value_count = a->goal_value_count = 6;
    a->arc_value[0] = 1e308;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(r->ret_msg, "moveArc: arc_value x 1e+308 meters is out of range"));
    assert_null(strstr(r->ret_msg, "nan"));
    ls_MoveAbsoluteReq *b = &req(ls_Request_move_absolute_tag)->cmd.move_absolute;
    snprintf(b->point_name, sizeof b->point_name, "p");
    b->frame = ls_ReferenceFrame_WORLD_CARTESIAN_FRAME;
    b->has_frame = true;
    b->values_count = 6;
    b->values[2] = reach2 * 1.01;
    assert_int_equal(must(HOST_A)->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    ls_PathLoadReq *pl = &req(ls_Request_path_load_tag)->cmd.path_load;
    snprintf(pl->path_name, sizeof pl->path_name, "far");
    pl->frame = ls_ReferenceFrame_BASE_CARTESIAN_FRAME;
    pl->motion_type = ls_MotionType_STRAIGHT_MOTION;
    pl->number_of_points = 1;
    pl->has_frame = pl->has_motion_type = pl->has_offset_type = pl->has_number_of_points = true;
    pl->tags_count = 1;
    pl->tags[0].pose_count = 6;
    pl->tags[0].pose[4] = 7.0;
    r = must(HOST_A);
    assert_int_equal(r->ret_code, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR);
    assert_non_null(strstr(r->ret_msg, "pathLoad: point 0 pose pitch 7 radians is out of range"));
    assert_int_equal(g_core.state, ls_State_RESTING);
    assert_false(g_core.run.active);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_units_conversions),
        cmocka_unit_test_setup(test_units_round_trip, setup_locked),
        cmocka_unit_test_setup(test_set_refusals_name_value_and_range, setup_locked),
        cmocka_unit_test_setup(test_set_commands_in_resting_too, setup_locked),
        cmocka_unit_test_setup(test_robot_position_is_the_tool_tip_in_the_world, setup_locked),
        cmocka_unit_test_setup(test_sensor_reading, setup_locked),
        cmocka_unit_test_setup(test_units_belong_to_the_session, setup_locked),
        cmocka_unit_test(test_range_refusals_speak_the_session_units),
        cmocka_unit_test_setup(test_absurd_cartesian_values_are_refused_naming_them, setup_locked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
