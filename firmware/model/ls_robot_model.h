/* The 6-DOF arm: one description shared by the kinematics (firmware/motion),
 * the planner's limits, describe, the URDF and the ODE simulation (hal/sim),
 * so that FK of the simulated joint angles equals the simulated tool pose
 * (tested). The compiled-in ls_robot_model_default is the arm when no model
 * file is configured; any other arm comes from a model file
 * (ls_robot_model_file.h, docs/deploy.md "Describe your arm"). Everything
 * takes the model by pointer and never writes it: it is filled once at init.
 *
 * Geometry: standard Denavit-Hartenberg (a, alpha, d, theta offset), base
 * frame at the floor under joint 1, z up. Inverse kinematics is closed form
 * for the geometry classes of ls_ik_class_t (firmware/kinematics/ls_kin.h);
 * the class is chosen when the model is loaded (ls_kin_classify), and a
 * geometry that fits none is refused there. Units: m, rad, kg, s, Nm. */
#ifndef LS_ROBOT_MODEL_H
#define LS_ROBOT_MODEL_H

#define LS_N_JOINTS 6

/* Bytes of the model's name with its NUL: describe publishes it
 * (DescribeRes.robot_model, max_size in protocol/landscape.options). */
#define LS_ROBOT_MODEL_NAME_MAX 32

/* Which closed-form inverse kinematics solves the arm (ls_kin.h lists each
 * class's geometry). NONE: not classified; every IK call refuses it. */
typedef enum {
    LS_IK_CLASS_NONE = 0,
    LS_IK_CLASS_SPHERICAL_WRIST = 1, /* joints 4-6 meet in one point */
    LS_IK_CLASS_OFFSET_WRIST = 2,    /* UR-style: joints 2-4 parallel, wrist axes offset */
} ls_ik_class_t;

typedef struct {
    double a_m, alpha_rad, d_m, theta_offset_rad;
} ls_dh_t;

typedef struct {
    char name[LS_ROBOT_MODEL_NAME_MAX]; /* printable ASCII, NUL-terminated */
    ls_ik_class_t ik_class;
    ls_dh_t dh[LS_N_JOINTS];
    double q_min_rad[LS_N_JOINTS], q_max_rad[LS_N_JOINTS];
    double qd_max_rad_s[LS_N_JOINTS];    /* joint velocity limits */
    double qdd_max_rad_s2[LS_N_JOINTS];  /* joint acceleration limits */
    double qddd_max_rad_s3[LS_N_JOINTS]; /* joint jerk limits */
    double torque_max_Nm[LS_N_JOINTS];
    double link_mass_kg[LS_N_JOINTS]; /* link i moves with joint i */
    double link_radius_m;             /* capsule radius used by the simulation and the URDF's visuals */
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

/* The class's name as model files, logs and describe spell it
 * ("spherical_wrist", "offset_wrist"; "none" for LS_IK_CLASS_NONE and any
 * other value). Static storage; callable anywhere. */
const char *ls_ik_class_name(ls_ik_class_t c);

/* The simulated arm (about the size of a small industrial arm), shipped
 * also as the model file firmware/model/robots/ls-sim6.ini, which a unit
 * test proves equal to it (tests/unit/modelfile). */
extern const ls_robot_model_t ls_robot_model_default;

#endif
