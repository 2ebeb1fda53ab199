#include "ls_robot_model.h"

#include <math.h>

#include "ls_math.h"

#define DEG (LS_PI / 180.0)

/* Shipped as firmware/model/robots/ls-sim6.ini too, which the loader reads
 * into exactly these doubles (tests/unit/modelfile): change both together. */
const ls_robot_model_t ls_robot_model_default = {
    .name = "ls-sim6",
    .ik_class = LS_IK_CLASS_SPHERICAL_WRIST,
    .dh = {
        { .a_m = 0.050, .alpha_rad = -LS_PI / 2, .d_m = 0.400, .theta_offset_rad = 0.0 },
        { .a_m = 0.400, .alpha_rad = 0.0, .d_m = 0.0, .theta_offset_rad = -LS_PI / 2 },
        { .a_m = 0.040, .alpha_rad = -LS_PI / 2, .d_m = 0.0, .theta_offset_rad = 0.0 },
        { .a_m = 0.0, .alpha_rad = LS_PI / 2, .d_m = 0.380, .theta_offset_rad = 0.0 },
        { .a_m = 0.0, .alpha_rad = -LS_PI / 2, .d_m = 0.0, .theta_offset_rad = 0.0 },
        { .a_m = 0.0, .alpha_rad = 0.0, .d_m = 0.080, .theta_offset_rad = 0.0 },
    },
    .q_min_rad = { -170 * DEG, -110 * DEG, -110 * DEG, -185 * DEG, -125 * DEG, -350 * DEG },
    .q_max_rad = { 170 * DEG, 110 * DEG, 150 * DEG, 185 * DEG, 125 * DEG, 350 * DEG },
    .qd_max_rad_s = { 2.5, 2.5, 3.0, 4.0, 4.0, 6.0 },
    .qdd_max_rad_s2 = { 8.0, 8.0, 10.0, 15.0, 15.0, 20.0 },
    .qddd_max_rad_s3 = { 60.0, 60.0, 80.0, 120.0, 120.0, 160.0 },
    .torque_max_Nm = { 200.0, 250.0, 120.0, 30.0, 30.0, 15.0 },
    .link_mass_kg = { 5.0, 4.0, 3.0, 1.5, 1.0, 0.5 },
    .link_radius_m = 0.04,
    .max_linear_speed_m_s = 1.0,
    .max_angular_speed_rad_s = 3.0,
    .max_linear_accel_m_s2 = 4.0,
    .max_angular_accel_rad_s2 = 12.0,
    .max_linear_jerk_m_s3 = 40.0,
    .max_angular_jerk_rad_s3 = 120.0,
    .workspace_min_m = { -0.95, -0.95, 0.02 },
    .workspace_max_m = { 0.95, 0.95, 1.40 },
};

const char *ls_ik_class_name(ls_ik_class_t c)
{
    switch (c) {
    case LS_IK_CLASS_SPHERICAL_WRIST: return "spherical_wrist";
    case LS_IK_CLASS_OFFSET_WRIST: return "offset_wrist";
    case LS_IK_CLASS_NONE: break;
    }
    return "none";
}

double ls_robot_model_linear_jerk(const ls_robot_model_t *m, double a_m_s2)
{
    return m->max_linear_jerk_m_s3 * a_m_s2 / m->max_linear_accel_m_s2;
}

double ls_robot_model_angular_jerk(const ls_robot_model_t *m, double a_rad_s2)
{
    return m->max_angular_jerk_rad_s3 * a_rad_s2 / m->max_angular_accel_rad_s2;
}

double ls_robot_model_reach_m(const ls_robot_model_t *m)
{
    double r = 0.0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        r += sqrt(m->dh[j].a_m * m->dh[j].a_m + m->dh[j].d_m * m->dh[j].d_m);
    }
    return r;
}
