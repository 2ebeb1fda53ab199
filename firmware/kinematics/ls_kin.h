/* Kinematics of the 6-DOF arm (C++17 + Eigen behind this C API): forward
 * kinematics of any DH arm, closed-form inverse kinematics for two geometry
 * classes (ls_kin_classify), the Jacobian and pose helpers.
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

#include <stddef.h>
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
 * LS_EINVAL (NULL, non-finite or non-rigid input, a model whose ik_class its
 * geometry does not fit). */

#define LS_KIN_MAX_BRANCHES 8

/* Flange pose in the base frame for joint angles q[6]: the product of the DH
 * transforms A_i = Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i). Joint
 * limits are not checked (FK is defined everywhere). LS_EINVAL on NULL or
 * non-finite q. Cost: six 4x4 products, about 0.3 us (x86-64, -O2). */
int ls_kin_fk(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double T_base_flange[16]) LS_KIN_NOEXCEPT;

/* Which closed-form IK class the geometry of m fits (its ik_class is not
 * read). The classes, tried in this order (a, d in m, alpha in rad; "= 0"
 * within 1e-12, "+-pi/2" means |cos alpha| < 1e-12):
 *
 * - LS_IK_CLASS_SPHERICAL_WRIST: a4 = a5 = a6 = d5 = 0 (the axes of joints
 *   4-6 meet in the wrist centre), alpha4 and alpha5 +-pi/2, alpha2 = 0
 *   (joints 2 and 3 parallel), sin(alpha1) != 0, a2 != 0 and a forearm
 *   (a3, d4) that is not zero. d1, d2, d3 (a lateral shoulder offset), a1,
 *   a3, alpha3, d4, d6, alpha6 and the theta offsets may be anything. Arms:
 *   ls-sim6, KUKA KR 6-class, PUMA 560, most 6-axis industrial arms.
 * - LS_IK_CLASS_OFFSET_WRIST: a4 = a5 = a6 = 0, alpha2 = alpha3 = 0 (joints
 *   2, 3 and 4 parallel), alpha4 and alpha5 +-pi/2, sin(alpha1) != 0, a2 != 0,
 *   a3 != 0. d4 (the shoulder-to-wrist offset along the parallel axes), d5
 *   (the wrist offset) and everything else may be anything. Arms: Universal
 *   Robots UR3/5/10/16/20(e) and the cobots of the same layout.
 *
 * Returns LS_OK with *cls set; LS_EINVAL when m is NULL or non-finite, a
 * joint's q_min > q_max, or no class fits, with the reason in why (one line:
 * what each class needs that m lacks, e.g. "not a spherical wrist (a5 =
 * 0.02 m; a4, a5, a6 and d5 must be 0) and not an offset wrist (alpha3 =
 * -90 deg; alpha2 and alpha3 must be 0)"). *cls is untouched on error. why
 * may be NULL (whylen 0). Init-time (model loading), but allocation-free and
 * callable anywhere. Cost: a few dozen comparisons. */
int ls_kin_classify(const ls_robot_model_t *m, ls_ik_class_t *cls, char *why, size_t whylen) LS_KIN_NOEXCEPT;

/* Every IK solution (shoulder front/back x elbow x wrist) for a flange pose,
 * wrapped into the joint limits where possible, solved in closed form by the
 * model's class (m->ik_class, chosen at load by ls_kin_classify; a model
 * whose geometry does not fit its class, or of class NONE, gives LS_EINVAL).
 * Solutions outside the limits are not returned. n_out receives the count
 * (0..8). Returns LS_OK when n_out > 0, else the reason.
 *
 * Both classes share the shoulder: with p the point where joint 5's axis
 * meets frame 5 (the wrist centre; the flange is d6 along z5 from it), q1
 * puts p in the plane of the parallel joints at height h = d2 + d3 +
 * cos(alpha3) d4 along z1 (for an offset wrist alpha3 = 0: h = d2 + d3 + d4).
 * Spherical wrist: joints 2-3 place p (a planar two-link problem), joints
 * 4-6 turn the flange. Offset wrist: joint 5 follows from the angle between
 * z1 and z5, joint 6 and q2 + q3 + q4 from the flange's orientation, then
 * joints 2-3 place joint 4's axis (a planar two-link problem) and q4 closes
 * the sum.
 *
 * Order: shoulder front (q1 facing p) before back, then elbow sin(psi) >= 0
 * before < 0 (psi = q3 + offset3 + atan2(-sin(alpha3) d4, a3), the angle of
 * the virtual forearm to the upper arm), then wrist sin(q5 + offset5) >= 0
 * before < 0 (spherical: the flip q4 + pi, -q5, q6 + pi). Branches that
 * coincide (within 1e-9 rad, e.g. the two elbow branches at full stretch)
 * are returned once.
 *
 * Wrap: each angle is moved by multiples of 2 pi into [q_min, q_max]; when
 * several fit (joint 6 with +-350 deg, joint 4 with +-185 deg) the one nearest
 * 0 is returned. A wrap less than 1e-10 rad past a limit is clamped onto it.
 *
 * Singularities (decided conventions):
 * - wrist (|sin(q5 + offset5)| < 1e-6): two wrist axes are parallel and only
 *   the sum or the difference of their angles is defined. Spherical: joints
 *   4 and 6; q4 = 0 here (q_near[3] in ls_kin_ik_nearest, clamped into the
 *   limits) and q6 is solved. Offset wrist: joint 6 and the parallel joints
 *   2-4; q6 = 0 here (q_near[5] in ls_kin_ik_nearest, clamped into the
 *   limits) and q2, q3, q4 are solved. Returns LS_OK: the pose is reached
 *   exactly.
 * - elbow (arm stretched or folded): the coincident branch is returned once,
 *   LS_OK.
 * - shoulder: when p is as far from the joint 1 axis as the plane of the
 *   parallel joints (|h| for alpha1 = +-pi/2: an offset wrist's shoulder
 *   singularity, or a spherical wrist's with a lateral offset) the two
 *   shoulder branches coincide and are returned once, LS_OK. When p is within
 *   1e-9 m of the joint 1 axis and that plane contains the axis (h = 0), q1
 *   is undetermined: LS_ESINGULAR with n_out = 0 (if the pose is reachable
 *   at all; LS_EUNREACHABLE otherwise). Callers moving through the axis
 *   should keep their current q1 and plan in joint space.
 *
 * LS_EINVAL also when T is not a rigid transform (last row not 0 0 0 1,
 * rotation not orthonormal within 1e-6, or a reflection).
 * Cost: bounded, no iteration; bench/ik.c counts the instructions per call of
 * each class (docs/performance.md, about 3 us on x86-64). */
int ls_kin_ik_all(const ls_robot_model_t *m, const double T_base_flange[16],
                  double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) LS_KIN_NOEXCEPT;

/* The IK solution nearest to q_near: among all branches, each joint wrapped
 * to the 2 pi equivalent inside its limits that is nearest q_near, the one
 * with the smallest max_j |q_j - q_near_j|. At a wrist singularity the free
 * joint (q4 of a spherical wrist, q6 of an offset wrist) is q_near's. Same
 * status codes as ls_kin_ik_all; q_out is written only on LS_OK. LS_EINVAL on
 * a non-finite q_near. Cost: as ls_kin_ik_all. */
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
