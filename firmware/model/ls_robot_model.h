/* The 6-DOF arm: one description shared by the kinematics (firmware/motion)
 * and the ODE simulation (hal/sim), so that FK of the simulated joint angles
 * equals the simulated tool pose (tested).
 *
 * Geometry: standard Denavit-Hartenberg (a, alpha, d, theta offset), base
 * frame at the floor under joint 1, z up; a spherical wrist (joints 4-6 axes
 * meet), so inverse kinematics is closed form with up to 8 branches.
 * Units: m, rad, kg, s, Nm. */
#ifndef LS_ROBOT_MODEL_H
#define LS_ROBOT_MODEL_H

#define LS_N_JOINTS 6

typedef struct {
    double a_m, alpha_rad, d_m, theta_offset_rad;
} ls_dh_t;

typedef struct {
    const char *name;
    ls_dh_t dh[LS_N_JOINTS];
    double q_min_rad[LS_N_JOINTS], q_max_rad[LS_N_JOINTS];
    double qd_max_rad_s[LS_N_JOINTS];    /* joint velocity limits */
    double qdd_max_rad_s2[LS_N_JOINTS];  /* joint acceleration limits */
    double qddd_max_rad_s3[LS_N_JOINTS]; /* joint jerk limits */
    double torque_max_Nm[LS_N_JOINTS];
    double link_mass_kg[LS_N_JOINTS]; /* link i moves with joint i */
    double link_radius_m;             /* capsule radius used by the simulation */
    double max_linear_speed_m_s, max_angular_speed_rad_s;
    double max_linear_accel_m_s2, max_angular_accel_rad_s2;
    double max_linear_jerk_m_s3, max_angular_jerk_rad_s3;
    double workspace_min_m[3], workspace_max_m[3]; /* tool tip box, base frame */
} ls_robot_model_t;

/* How far the flange can be from the base frame's origin at most (m): the
 * sum of the links' lengths sqrt(a^2 + d^2), a bound on any pose's reach.
 * Tool offsets and world frames are limited by it (docs/protocol.md
 * "Limits"). */
double ls_robot_model_reach_m(const ls_robot_model_t *m);

/* The Cartesian jerk that goes with a Cartesian acceleration: the same
 * share of the model's maximum (a move at half the maximum acceleration
 * gets half the maximum jerk). Moves, guarded moves and jogs all take their
 * jerk from here. */
double ls_robot_model_linear_jerk(const ls_robot_model_t *m, double a_m_s2);
double ls_robot_model_angular_jerk(const ls_robot_model_t *m, double a_rad_s2);

/* The simulated arm (about the size of a small industrial arm). */
extern const ls_robot_model_t ls_robot_model_default;

#endif
