/* Kinematics of the 6-DOF arm (C++17 + Eigen behind this C API).
 *
 * Every function is noexcept, allocates nothing and works on fixed-size
 * arrays, so it may run in the control loop. Poses are 4x4 homogeneous
 * transforms, column-major (Eigen's default), in metres.
 * Orientation as roll/pitch/yaw: R = Rz(yaw) * Ry(pitch) * Rx(roll)
 * (rotations about the fixed X, then Y, then Z axes).
 *
 * Frames: world -> base (setWorldCartesianFrame) -> flange (FK) -> tool tip
 * (setToolOffset). ls_kin_fk gives the flange in the base frame. */
#ifndef LS_KIN_H
#define LS_KIN_H

#include <stdint.h>

#include "ls_robot_model.h"

#ifdef __cplusplus
#define LS_KIN_NOEXCEPT noexcept
extern "C" {
#else
#define LS_KIN_NOEXCEPT
#endif

#define LS_KIN_OK            0
#define LS_KIN_EUNREACHABLE (-1) /* the pose is outside the reachable space */
#define LS_KIN_ESINGULAR    (-2) /* at or too near a singularity (wrist, elbow, shoulder) */
#define LS_KIN_ELIMITS      (-3) /* reachable, but no branch within the joint limits */
#define LS_KIN_EARG         (-4) /* NULL or non-finite input */

#define LS_KIN_MAX_BRANCHES 8

/* Flange pose in the base frame for joint angles q[6]. */
int ls_kin_fk(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double T_base_flange[16]) LS_KIN_NOEXCEPT;

/* Every IK solution (shoulder front/back x elbow up/down x wrist flip) for a
 * flange pose, wrapped into the joint limits where possible. Solutions outside
 * the limits are not returned. n_out receives the count (0..8). Returns
 * LS_KIN_OK when n_out > 0, else the reason. */
int ls_kin_ik_all(const ls_robot_model_t *m, const double T_base_flange[16],
                  double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) LS_KIN_NOEXCEPT;

/* The IK solution nearest (max joint distance) to q_near. */
int ls_kin_ik_nearest(const ls_robot_model_t *m, const double T_base_flange[16],
                      const double q_near[LS_N_JOINTS], double q_out[LS_N_JOINTS]) LS_KIN_NOEXCEPT;

/* Geometric Jacobian (6x6, column-major; rows vx vy vz wx wy wz) of the
 * flange in the base frame. */
int ls_kin_jacobian(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double J[36]) LS_KIN_NOEXCEPT;

/* Pose helpers. */
void ls_pose_from_xyzrpy(const double xyzrpy[6], double T[16]) LS_KIN_NOEXCEPT;
void ls_pose_to_xyzrpy(const double T[16], double xyzrpy[6]) LS_KIN_NOEXCEPT;
void ls_pose_mul(const double A[16], const double B[16], double AB[16]) LS_KIN_NOEXCEPT;
void ls_pose_inv(const double T[16], double Tinv[16]) LS_KIN_NOEXCEPT;
/* Interpolate between two poses: position linearly, orientation by slerp. */
void ls_pose_interp(const double A[16], const double B[16], double s, double T[16]) LS_KIN_NOEXCEPT;
/* Rotation angle between the orientations of A and B (rad) and distance (m). */
double ls_pose_angle(const double A[16], const double B[16]) LS_KIN_NOEXCEPT;
double ls_pose_dist(const double A[16], const double B[16]) LS_KIN_NOEXCEPT;

#ifdef __cplusplus
}
#endif
#endif
