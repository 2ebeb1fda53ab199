/* Helpers shared by the kinematics tests: a seeded generator and pose
 * arithmetic written independently of the library under test. */
#ifndef KIN_TEST_UTIL_H
#define KIN_TEST_UTIL_H

#include <stdint.h>

#include "ls_math.h"
#include "ls_robot_model.h"


typedef struct {
    uint64_t s;
} kt_rng_t;

/* Uniform in [lo, hi). */
double kt_uniform(kt_rng_t *r, double lo, double hi);

/* Joint vector inside the limits, margin_rad away from each. */
void kt_random_q(kt_rng_t *r, const ls_robot_model_t *m, double margin_rad, double q[LS_N_JOINTS]);

/* a - b folded into (-pi, pi]. */
double kt_angdiff(double a, double b);

/* Rotation log of the 3x3 rotation block of a column-major 4x4
 * (element (r, c) at [c * 4 + r]): w with |w| = angle. */
void kt_log_rot(const double R[16], double w[3]);

/* Position distance (m) and rotation angle (rad) between two poses. */
void kt_pose_error(const double A[16], const double B[16], double *pos_m, double *ang_rad);

/* Geometry the tests use to stay away from singular configurations, for a
 * model with the IK structure: wrist centre distance from the joint 1 axis
 * minus the lateral offset |k| (shoulder), |sin(psi)| (elbow), |sin(q5)|. */
void kt_singularity_margins(const ls_robot_model_t *m, const double q[LS_N_JOINTS], const double T[16],
                            double *shoulder_m, double *elbow, double *wrist);

#endif
