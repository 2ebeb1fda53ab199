/* The Cartesian limits of a move at speed and acceleration fractions (0, 1]
 * of the model's maxima, the jerk following the acceleration, as
 * ls_mcmd_cart_limits makes them (firmware/core/cmd_motion.c): for the
 * benchmark drivers that plan as the firmware does. */
#ifndef BENCH_CART_LIMITS_H
#define BENCH_CART_LIMITS_H

#include "ls_motion.h"

static inline ls_motion_cart_limits_t bench_cart_limits(const ls_robot_model_t *m, double speed, double accel)
{
    const ls_motion_cart_limits_t lim = { .v_lin_m_s = m->max_linear_speed_m_s * speed,
                                          .a_lin_m_s2 = m->max_linear_accel_m_s2 * accel,
                                          .j_lin_m_s3 = m->max_linear_jerk_m_s3 * accel,
                                          .v_ang_rad_s = m->max_angular_speed_rad_s * speed,
                                          .a_ang_rad_s2 = m->max_angular_accel_rad_s2 * accel,
                                          .j_ang_rad_s3 = m->max_angular_jerk_rad_s3 * accel,
                                          .joint_speed_frac = 1.0 };
    return lim;
}

#endif
