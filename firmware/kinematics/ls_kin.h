/* Kinematics of the 6-DOF arm (C++17 + Eigen behind this C API).
 *
 * Every function is noexcept, allocates nothing (no heap, no exceptions; the
 * unit tests prove it at link level and at run time) and works on fixed-size
 * arrays, so it may run in the control loop and from any thread: there is no
 * state. The caller owns every buffer; outputs may alias inputs. Poses are
 * 4x4 homogeneous transforms, column-major (Eigen's default), in metres.
 * Orientation as roll/pitch/yaw: R = Rz(yaw) * Ry(pitch) * Rx(roll)
 * (rotations about the fixed X, then Y, then Z axes).
 *
 * Frames: world -> base (setWorldCartesianFrame) -> flange (FK) -> tool tip
 * (setToolOffset). ls_kin_fk gives the flange in the base frame. */
#ifndef LS_KIN_H
#define LS_KIN_H

#include <stdint.h>

#include "ls_err.h"
#include "ls_robot_model.h"

#ifdef __cplusplus
#define LS_KIN_NOEXCEPT noexcept
extern "C" {
#else
#define LS_KIN_NOEXCEPT
#endif

/* Statuses (ls_err.h): LS_OK; LS_EUNREACHABLE (the pose is outside the
 * reachable space), LS_ESINGULAR (shoulder singularity: q1 undetermined, see IK
 * below), LS_ELIMITS (reachable, but no branch within the joint limits),
 * LS_EINVAL (NULL, non-finite or non-rigid input, unsupported model). */

#define LS_KIN_MAX_BRANCHES 8

/* Flange pose in the base frame for joint angles q[6]: the product of the DH
 * transforms A_i = Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i). Joint
 * limits are not checked (FK is defined everywhere). LS_EINVAL on NULL or
 * non-finite q. Cost: six 4x4 products, about 0.3 us (x86-64, -O2). */
int ls_kin_fk(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double T_base_flange[16]) LS_KIN_NOEXCEPT;

/* Every IK solution (shoulder front/back x elbow up/down x wrist flip) for a
 * flange pose, wrapped into the joint limits where possible. Solutions outside
 * the limits are not returned. n_out receives the count (0..8). Returns
 * LS_OK when n_out > 0, else the reason.
 *
 * Closed form for the structure of ls_robot_model_t: a4 = a5 = a6 = d5 = 0
 * (spherical wrist), alpha4 = +-pi/2, alpha5 = +-pi/2, alpha2 = 0,
 * sin(alpha1) != 0; any other model gives LS_EINVAL. d2, d3 (lateral
 * shoulder offset), a3 and alpha6 may be anything.
 *
 * Order: shoulder front (q1 facing the wrist centre) before back, then elbow
 * sin(psi) >= 0 before < 0 (psi = q3 + offset3 + atan2(-sin(alpha3) d4, a3),
 * the angle of the virtual forearm to the upper arm), then wrist
 * sin(q5) >= 0 before the flip (q4 + pi, -q5, q6 + pi). Branches that coincide (within 1e-9 rad, e.g. the two elbow
 * branches at full stretch) are returned once.
 *
 * Wrap: each angle is moved by multiples of 2 pi into [q_min, q_max]; when
 * several fit (joint 6 with +-350 deg, joint 4 with +-185 deg) the one nearest
 * 0 is returned. A wrap less than 1e-10 rad past a limit is clamped onto it.
 *
 * Singularities (decided conventions):
 * - wrist (|sin q5| < 1e-6): only q4 +- q6 is defined; q4 = 0 here (q_near[3]
 *   in ls_kin_ik_nearest, clamped into the limits) and q6 is solved. Returns
 *   LS_OK: the pose is reached exactly at q5 = 0.
 * - elbow (arm stretched): the coincident branch is returned once, LS_OK.
 * - shoulder (wrist centre within 1e-9 m of the joint 1 axis): q1 is
 *   undetermined, so LS_ESINGULAR with n_out = 0 (if the pose is
 *   reachable at all; LS_EUNREACHABLE otherwise). Callers moving through
 *   the axis should keep their current q1 and plan in joint space.
 *
 * LS_EINVAL also when T is not a rigid transform (last row not 0 0 0 1,
 * rotation not orthonormal within 1e-6, or a reflection).
 * Cost: about 3 us (x86-64, -O2, all branches); bounded, no iteration. */
int ls_kin_ik_all(const ls_robot_model_t *m, const double T_base_flange[16],
                  double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) LS_KIN_NOEXCEPT;

/* The IK solution nearest to q_near: among all branches, each joint wrapped
 * to the 2 pi equivalent inside its limits that is nearest q_near, the one
 * with the smallest max_j |q_j - q_near_j|. At a wrist singularity q4 =
 * q_near[3]. Same status codes as ls_kin_ik_all; q_out is written only on
 * LS_OK. LS_EINVAL on a non-finite q_near. Cost: as ls_kin_ik_all. */
int ls_kin_ik_nearest(const ls_robot_model_t *m, const double T_base_flange[16], const double q_near[LS_N_JOINTS],
                      double q_out[LS_N_JOINTS]) LS_KIN_NOEXCEPT;

/* Geometric Jacobian (6x6, column-major; rows vx vy vz wx wy wz) of the
 * flange origin in the base frame: column i = (z_{i-1} x (p - o_{i-1}),
 * z_{i-1}). LS_EINVAL on NULL or non-finite q. Cost: about 0.35 us. */
int ls_kin_jacobian(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double J[36]) LS_KIN_NOEXCEPT;

/* Pose helpers. They cannot fail: NULL arguments make them a no-op (NaN for
 * the functions returning double), non-finite input gives non-finite output.
 *
 * ls_pose_to_xyzrpy returns roll, yaw in (-pi, pi], pitch in [-pi/2, pi/2].
 * At the gimbal lock (pitch = +-pi/2, cos(pitch) < 1e-12) only yaw -+ roll is
 * defined: roll = 0 and yaw carries the rest, so the result is deterministic
 * and ls_pose_from_xyzrpy of it gives back the same rotation. */
void ls_pose_from_xyzrpy(const double xyzrpy[6], double T[16]) LS_KIN_NOEXCEPT;
void ls_pose_to_xyzrpy(const double T[16], double xyzrpy[6]) LS_KIN_NOEXCEPT;
void ls_pose_mul(const double A[16], const double B[16], double AB[16]) LS_KIN_NOEXCEPT;
void ls_pose_inv(const double T[16], double Tinv[16]) LS_KIN_NOEXCEPT;
/* Interpolate between two poses: position linearly, orientation by slerp
 * along the shorter arc. s = 0 gives A, s = 1 gives B (outside: extrapolates). */
void ls_pose_interp(const double A[16], const double B[16], double s, double T[16]) LS_KIN_NOEXCEPT;
/* Rotation angle between the orientations of A and B (rad, [0, pi], accurate
 * near 0 too) and distance between their origins (m). */
double ls_pose_angle(const double A[16], const double B[16]) LS_KIN_NOEXCEPT;
double ls_pose_dist(const double A[16], const double B[16]) LS_KIN_NOEXCEPT;

#ifdef __cplusplus
}
#endif
#endif
