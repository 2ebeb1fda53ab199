#include "kin_test_util.h"

#include <math.h>

static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double kt_uniform(kt_rng_t *r, double lo, double hi)
{
    const double u = (double)(splitmix64(&r->s) >> 11) * (1.0 / 9007199254740992.0);
    return lo + (hi - lo) * u;
}

void kt_random_q(kt_rng_t *r, const ls_robot_model_t *m, double margin_rad, double q[LS_N_JOINTS])
{
    for (int j = 0; j < LS_N_JOINTS; ++j) {
        q[j] = kt_uniform(r, m->q_min_rad[j] + margin_rad, m->q_max_rad[j] - margin_rad);
    }
}

double kt_angdiff(double a, double b)
{
    return remainder(a - b, 2.0 * LS_PI);
}

void kt_log_rot(const double R[16], double w[3])
{
    /* R given as the 3x3 block of a column-major 4x4: R[c * 4 + r]. */
#define E(r, c) R[(c)*4 + (r)]
    const double v[3] = { 0.5 * (E(2, 1) - E(1, 2)), 0.5 * (E(0, 2) - E(2, 0)), 0.5 * (E(1, 0) - E(0, 1)) };
    const double s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    const double c = 0.5 * (E(0, 0) + E(1, 1) + E(2, 2) - 1.0);
#undef E
    const double th = atan2(s, c);
    const double f = s < 1e-12 ? 1.0 : th / s; /* only used away from th = pi */
    for (int i = 0; i < 3; ++i) {
        w[i] = f * v[i];
    }
}

void kt_pose_error(const double A[16], const double B[16], double *pos_m, double *ang_rad)
{
    double dp = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double d = A[12 + i] - B[12 + i];
        dp += d * d;
    }
    *pos_m = sqrt(dp);
    /* M = R_A^T R_B, laid out like a 4x4 for kt_log_rot. */
    double M[16] = { 0 };
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k) {
                s += A[r * 4 + k] * B[c * 4 + k];
            }
            M[c * 4 + r] = s;
        }
    }
    const double v[3] = { 0.5 * (M[6] - M[9]), 0.5 * (M[8] - M[2]), 0.5 * (M[1] - M[4]) };
    const double s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    *ang_rad = atan2(s, 0.5 * (M[0] + M[5] + M[10] - 1.0));
}

void kt_singularity_margins(const ls_robot_model_t *m, const double q[LS_N_JOINTS], const double T[16],
                            double *shoulder_m, double *elbow, double *wrist)
{
    const ls_dh_t *d = m->dh;
    /* Flange z of frame 5 = R Rx(-alpha6) e_z. */
    const double sa6 = sin(d[5].alpha_rad), ca6 = cos(d[5].alpha_rad);
    double w[3];
    for (int i = 0; i < 3; ++i) {
        w[i] = T[12 + i] - d[5].d_m * (T[4 + i] * sa6 + T[8 + i] * ca6);
    }
    const double h = d[1].d_m + d[2].d_m + cos(d[2].alpha_rad) * d[3].d_m;
    const double k = (cos(d[0].alpha_rad) * (w[2] - d[0].d_m) - h) / sin(d[0].alpha_rad);
    *shoulder_m = hypot(w[0], w[1]) - fabs(k);
    const double gamma = atan2(-sin(d[2].alpha_rad) * d[3].d_m, d[2].a_m);
    *elbow = fabs(sin(q[2] + d[2].theta_offset_rad + gamma));
    *wrist = fabs(sin(q[4] + d[4].theta_offset_rad));
}
