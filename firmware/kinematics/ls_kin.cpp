// Kinematics of the 6-DOF arm: standard DH forward kinematics, closed-form
// inverse kinematics for a spherical wrist, geometric Jacobian, pose helpers.
// Only fixed-size Eigen types: nothing here allocates or throws, so every
// entry point may run in the control loop (see ls_kin.h for costs).
#include "ls_kin.h"
#include "ls_math.h"

#include <Eigen/Dense>
#include <cmath>

namespace
{

using Eigen::Map;
using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Quaterniond;
using Eigen::Vector3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

constexpr double kPi = LS_PI;
constexpr double kTwoPi = 2.0 * kPi;

// Geometry tolerances (documented in ls_kin.h).
constexpr double kWristSingularSin = 1e-6;  // |sin q5| below: wrist singular
constexpr double kShoulderSingularM = 1e-9; // wrist centre this near the joint 1 axis
constexpr double kReachSlack = 1e-10;       // rounding slack on cos(elbow) and sin(shoulder)
constexpr double kLimitSlackRad = 1e-10;    // a wrap this far past a limit is clamped onto it
constexpr double kSameBranchRad = 1e-9;     // branches closer than this are one branch
constexpr double kStructTol = 1e-12;        // DH structure checks
constexpr double kRotationTol = 1e-6;       // orthonormality of an input rotation

bool finite_n(const double *v, int n) noexcept
{
    for (int i = 0; i < n; ++i) {
        if (!std::isfinite(v[i])) {
            return false;
        }
    }
    return true;
}

Matrix4d dh_transform(const ls_dh_t &dh, double theta) noexcept
{
    // Rz(theta) Tz(d) Tx(a) Rx(alpha), written out.
    const double ct = std::cos(theta), st = std::sin(theta);
    const double ca = std::cos(dh.alpha_rad), sa = std::sin(dh.alpha_rad);
    Matrix4d A;
    A << ct, -st * ca, st * sa, dh.a_m * ct, st, ct * ca, -ct * sa, dh.a_m * st, 0.0, sa, ca, dh.d_m, 0.0, 0.0, 0.0,
        1.0;
    return A;
}

Matrix3d rot_z(double t) noexcept
{
    const double c = std::cos(t), s = std::sin(t);
    Matrix3d R;
    R << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
    return R;
}

Matrix3d rot_x(double t) noexcept
{
    const double c = std::cos(t), s = std::sin(t);
    Matrix3d R;
    R << 1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c;
    return R;
}

Matrix3d rot_y(double t) noexcept
{
    const double c = std::cos(t), s = std::sin(t);
    Matrix3d R;
    R << c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c;
    return R;
}

// Frames 0..6 (frame 0 = base) for joint angles q.
void all_frames(const ls_robot_model_t &m, const double *q, Matrix4d T[LS_N_JOINTS + 1]) noexcept
{
    T[0].setIdentity();
    for (int i = 0; i < LS_N_JOINTS; ++i) {
        T[i + 1] = T[i] * dh_transform(m.dh[i], q[i] + m.dh[i].theta_offset_rad);
    }
}

// Rotation angle of R, well conditioned over [0, pi] (acos is not near 0).
double rotation_angle(const Matrix3d &R) noexcept
{
    const Vector3d v(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
    return std::atan2(0.5 * v.norm(), 0.5 * (R.trace() - 1.0));
}

// The IK needs: a4 = a5 = a6 = d5 = 0 (joints 4-6 meet in the wrist centre),
// alpha4, alpha5 = +-pi/2, alpha2 = 0 (joints 2 and 3 parallel), sin(alpha1)
// != 0, and a non-degenerate upper arm / forearm.
bool ik_structure_ok(const ls_robot_model_t &m) noexcept
{
    const ls_dh_t *d = m.dh;
    for (int i = 0; i < LS_N_JOINTS; ++i) {
        if (!std::isfinite(d[i].a_m) || !std::isfinite(d[i].d_m) || !std::isfinite(d[i].alpha_rad) ||
            !std::isfinite(d[i].theta_offset_rad) || !std::isfinite(m.q_min_rad[i]) || !std::isfinite(m.q_max_rad[i]) ||
            m.q_min_rad[i] > m.q_max_rad[i]) {
            return false;
        }
    }
    const double forearm = std::hypot(d[2].a_m, d[3].d_m);
    return std::fabs(d[3].a_m) < kStructTol && std::fabs(d[4].a_m) < kStructTol && std::fabs(d[5].a_m) < kStructTol &&
           std::fabs(d[4].d_m) < kStructTol && std::fabs(std::cos(d[3].alpha_rad)) < kStructTol &&
           std::fabs(std::cos(d[4].alpha_rad)) < kStructTol && std::fabs(std::sin(d[1].alpha_rad)) < kStructTol &&
           std::cos(d[1].alpha_rad) > 0.0 && std::fabs(std::sin(d[0].alpha_rad)) > 1e-9 && std::fabs(d[1].a_m) > 1e-9 &&
           forearm > 1e-9;
}

bool pose_ok(const Matrix4d &T) noexcept
{
    if (!finite_n(T.data(), 16)) {
        return false;
    }
    if (T(3, 0) != 0.0 || T(3, 1) != 0.0 || T(3, 2) != 0.0 || T(3, 3) != 1.0) {
        return false;
    }
    const Matrix3d R = T.topLeftCorner<3, 3>();
    return (R.transpose() * R - Matrix3d::Identity()).cwiseAbs().maxCoeff() < kRotationTol && R.determinant() > 0.0;
}

// Move q by multiples of 2*pi into [lo, hi], nearest to ref. False if no
// multiple fits.
bool wrap_into(double q, double lo, double hi, double ref, double *out) noexcept
{
    q = std::remainder(q, kTwoPi); // (-pi, pi]
    bool found = false;
    double best = 0.0;
    // Limits up to +-(2 pi + pi) away from 0 need at most three turns.
    for (int k = -3; k <= 3; ++k) {
        double c = q + kTwoPi * static_cast<double>(k);
        if (c < lo - kLimitSlackRad || c > hi + kLimitSlackRad) {
            continue;
        }
        c = c < lo ? lo : (c > hi ? hi : c);
        if (!found || std::fabs(c - ref) < std::fabs(best - ref)) {
            best = c;
            found = true;
        }
    }
    if (found) {
        *out = best;
    }
    return found;
}

enum IkStatus { kIkOk, kIkUnreachable, kIkSingular, kIkLimits };

// Every branch, each joint wrapped into its limits nearest ref[j]. At a wrist
// singularity q4 is taken as ref[3] (clamped into the limits) and q6 solved.
// Branch order: bit 2 shoulder (0 front, 1 back), bit 1 elbow, bit 0 wrist
// (0: sin(theta5) >= 0). Branches that coincide are returned once.
IkStatus ik_branches(const ls_robot_model_t &m, const Matrix4d &T, const double ref[LS_N_JOINTS],
                     double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) noexcept
{
    const ls_dh_t *d = m.dh;
    *n_out = 0;

    const Matrix3d R = T.topLeftCorner<3, 3>();
    const Vector3d p = T.topRightCorner<3, 1>();
    const double sa6 = std::sin(d[5].alpha_rad), ca6 = std::cos(d[5].alpha_rad);
    // z5 = R Rx(-alpha6) e_z; the flange sits d6 along z5 from the wrist centre.
    const Vector3d w = p - d[5].d_m * (R * Vector3d(0.0, sa6, ca6));

    // Joint 1: the wrist centre, seen in frame 1, must lie in the plane of
    // joints 2-3, at height h = d2 + d3 + cos(alpha3) d4 along z1.
    const double sa1 = std::sin(d[0].alpha_rad), ca1 = std::cos(d[0].alpha_rad);
    const double h = d[1].d_m + d[2].d_m + std::cos(d[2].alpha_rad) * d[3].d_m;
    const double k = (ca1 * (w.z() - d[0].d_m) - h) / sa1; // = r sin(phi - theta1)
    const double r = std::hypot(w.x(), w.y());
    // On the joint 1 axis (only possible when k = 0) every q1 places the
    // centre equally well: q1 is undetermined. Reachability is still checked
    // (with q1 = 0, pi) so that a far-away pose reports unreachable.
    const bool shoulder_singular = r < kShoulderSingularM;
    double theta1[2] = { 0.0, kPi };
    if (shoulder_singular) {
        if (std::fabs(k) >= kShoulderSingularM) {
            return kIkUnreachable;
        }
    } else {
        double sk = k / r;
        if (std::fabs(sk) > 1.0 + kReachSlack) {
            return kIkUnreachable;
        }
        sk = sk > 1.0 ? 1.0 : (sk < -1.0 ? -1.0 : sk);
        const double phi = std::atan2(w.y(), w.x());
        const double as = std::asin(sk);
        theta1[0] = phi - as;
        theta1[1] = phi - kPi + as;
    }

    // Joints 2-3: planar two-link problem, upper arm a2, virtual forearm
    // (a3, -sin(alpha3) d4) of length L at angle gamma from x3.
    const double a2 = d[1].a_m;
    const double b3x = d[2].a_m, b3y = -std::sin(d[2].alpha_rad) * d[3].d_m;
    const double L = std::hypot(b3x, b3y);
    const double gamma = std::atan2(b3y, b3x);
    const double s4 = std::sin(d[3].alpha_rad) > 0.0 ? 1.0 : -1.0;
    const double s5 = std::sin(d[4].alpha_rad) > 0.0 ? 1.0 : -1.0;

    bool any_reachable = false;
    for (int sh = 0; sh < 2; ++sh) {
        const double t1 = theta1[sh];
        const double c1 = std::cos(t1), st1 = std::sin(t1);
        // p1 = Rx(-alpha1) (Rz(-theta1) w - (a1, 0, d1))
        const double X = c1 * w.x() + st1 * w.y() - d[0].a_m;
        const double Y = -st1 * w.x() + c1 * w.y();
        const double Z = w.z() - d[0].d_m;
        const double px = X, py = ca1 * Y + sa1 * Z;
        const double c = (px * px + py * py - a2 * a2 - L * L) / (2.0 * a2 * L);
        if (std::fabs(c) > 1.0 + kReachSlack) {
            continue;
        }
        any_reachable = true;
        if (shoulder_singular) {
            continue;
        }
        const double cc = c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
        const double spsi_abs = std::sqrt(1.0 - cc * cc);

        for (int el = 0; el < 2; ++el) {
            const double spsi = el == 0 ? spsi_abs : -spsi_abs;
            const double psi = std::atan2(spsi, cc);
            const double t3 = psi - gamma;
            const double t2 = std::atan2(py, px) - std::atan2(L * spsi, a2 + L * cc);

            const Matrix3d R03 = dh_transform(d[0], t1).topLeftCorner<3, 3>() *
                                 dh_transform(d[1], t2).topLeftCorner<3, 3>() *
                                 dh_transform(d[2], t3).topLeftCorner<3, 3>();
            // M = Rz(t4) Rx(alpha4) Rz(t5) Rx(alpha5) Rz(t6); its third column
            // is (s5 cos t4 sin t5, s5 sin t4 sin t5, -s4 s5 cos t5) and its
            // third row (s4 sin t5 cos t6, -s4 sin t5 sin t6, .).
            const Matrix3d M = R03.transpose() * R * rot_x(-d[5].alpha_rad);
            const double c5 = -s4 * s5 * M(2, 2);
            const double sn = std::hypot(M(0, 2), M(1, 2));

            for (int wr = 0; wr < 2; ++wr) {
                const double f = wr == 0 ? 1.0 : -1.0;
                const double t5 = std::atan2(f * sn, c5);
                double t4, t6;
                if (std::fabs(std::sin(t5)) < kWristSingularSin) {
                    // Only t4 + t6 (or t4 - t6) is defined: take q4 from ref.
                    double q4 = ref[3];
                    q4 = q4 < m.q_min_rad[3] ? m.q_min_rad[3] : (q4 > m.q_max_rad[3] ? m.q_max_rad[3] : q4);
                    t4 = q4 + d[3].theta_offset_rad;
                    const Matrix3d N =
                        (rot_z(t4) * rot_x(d[3].alpha_rad) * rot_z(t5) * rot_x(d[4].alpha_rad)).transpose() * M;
                    t6 = std::atan2(N(1, 0), N(0, 0));
                } else {
                    t4 = std::atan2(f * s5 * M(1, 2), f * s5 * M(0, 2));
                    t6 = std::atan2(-f * s4 * M(2, 1), f * s4 * M(2, 0));
                }

                const double theta[LS_N_JOINTS] = { t1, t2, t3, t4, t5, t6 };
                double q[LS_N_JOINTS];
                bool in_limits = true;
                for (int j = 0; j < LS_N_JOINTS && in_limits; ++j) {
                    in_limits =
                        wrap_into(theta[j] - d[j].theta_offset_rad, m.q_min_rad[j], m.q_max_rad[j], ref[j], &q[j]);
                }
                if (!in_limits) {
                    continue;
                }
                bool duplicate = false;
                for (int b = 0; b < *n_out && !duplicate; ++b) {
                    double diff = 0.0;
                    for (int j = 0; j < LS_N_JOINTS; ++j) {
                        diff = std::fmax(diff, std::fabs(q_out[b][j] - q[j]));
                    }
                    duplicate = diff < kSameBranchRad;
                }
                if (duplicate) {
                    continue;
                }
                for (int j = 0; j < LS_N_JOINTS; ++j) {
                    q_out[*n_out][j] = q[j];
                }
                ++*n_out;
            }
        }
    }
    if (!any_reachable) {
        return kIkUnreachable;
    }
    if (shoulder_singular) {
        return kIkSingular;
    }
    return *n_out > 0 ? kIkOk : kIkLimits;
}

int ik_status_code(IkStatus s) noexcept
{
    switch (s) {
    case kIkOk: return LS_OK;
    case kIkUnreachable: return LS_EUNREACHABLE;
    case kIkSingular: return LS_ESINGULAR;
    case kIkLimits: return LS_ELIMITS;
    }
    return LS_EINVAL;
}

void store(const Matrix4d &T, double out[16]) noexcept
{
    Map<Matrix4d> dst(out);
    dst = T;
}

} // namespace

extern "C" {

int ls_kin_fk(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double T_base_flange[16]) noexcept
{
    if (m == nullptr || q == nullptr || T_base_flange == nullptr || !finite_n(q, LS_N_JOINTS)) {
        return LS_EINVAL;
    }
    Matrix4d T = Matrix4d::Identity();
    for (int i = 0; i < LS_N_JOINTS; ++i) {
        T = T * dh_transform(m->dh[i], q[i] + m->dh[i].theta_offset_rad);
    }
    if (!finite_n(T.data(), 16)) {
        return LS_EINVAL; // non-finite DH parameters in the model
    }
    store(T, T_base_flange);
    return LS_OK;
}

int ls_kin_ik_all(const ls_robot_model_t *m, const double T_base_flange[16],
                  double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) noexcept
{
    if (n_out != nullptr) {
        *n_out = 0;
    }
    if (m == nullptr || T_base_flange == nullptr || q_out == nullptr || n_out == nullptr || !ik_structure_ok(*m)) {
        return LS_EINVAL;
    }
    const Matrix4d T = Map<const Matrix4d>(T_base_flange);
    if (!pose_ok(T)) {
        return LS_EINVAL;
    }
    const double zero[LS_N_JOINTS] = { 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 };
    return ik_status_code(ik_branches(*m, T, zero, q_out, n_out));
}

int ls_kin_ik_nearest(const ls_robot_model_t *m, const double T_base_flange[16], const double q_near[LS_N_JOINTS],
                      double q_out[LS_N_JOINTS]) noexcept
{
    if (m == nullptr || T_base_flange == nullptr || q_near == nullptr || q_out == nullptr ||
        !finite_n(q_near, LS_N_JOINTS) || !ik_structure_ok(*m)) {
        return LS_EINVAL;
    }
    const Matrix4d T = Map<const Matrix4d>(T_base_flange);
    if (!pose_ok(T)) {
        return LS_EINVAL;
    }
    double q[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
    int n = 0;
    const IkStatus s = ik_branches(*m, T, q_near, q, &n);
    if (s != kIkOk) {
        return ik_status_code(s);
    }
    int best = 0;
    double best_dist = 0.0;
    for (int b = 0; b < n; ++b) {
        double dist = 0.0;
        for (int j = 0; j < LS_N_JOINTS; ++j) {
            dist = std::fmax(dist, std::fabs(q[b][j] - q_near[j]));
        }
        if (b == 0 || dist < best_dist) {
            best = b;
            best_dist = dist;
        }
    }
    for (int j = 0; j < LS_N_JOINTS; ++j) {
        q_out[j] = q[best][j];
    }
    return LS_OK;
}

int ls_kin_jacobian(const ls_robot_model_t *m, const double q[LS_N_JOINTS], double J[36]) noexcept
{
    if (m == nullptr || q == nullptr || J == nullptr || !finite_n(q, LS_N_JOINTS)) {
        return LS_EINVAL;
    }
    Matrix4d F[LS_N_JOINTS + 1];
    all_frames(*m, q, F);
    const Vector3d pe = F[LS_N_JOINTS].topRightCorner<3, 1>();
    Mat6 Jm;
    for (int i = 0; i < LS_N_JOINTS; ++i) {
        // Joint i+1 turns about z of frame i.
        const Vector3d z = F[i].block<3, 1>(0, 2);
        const Vector3d o = F[i].topRightCorner<3, 1>();
        Jm.block<3, 1>(0, i) = z.cross(pe - o);
        Jm.block<3, 1>(3, i) = z;
    }
    if (!finite_n(Jm.data(), 36)) {
        return LS_EINVAL;
    }
    Map<Mat6> dst(J);
    dst = Jm;
    return LS_OK;
}

void ls_pose_from_xyzrpy(const double xyzrpy[6], double T[16]) noexcept
{
    if (xyzrpy == nullptr || T == nullptr) {
        return;
    }
    Matrix4d P = Matrix4d::Identity();
    P.topLeftCorner<3, 3>() = rot_z(xyzrpy[5]) * rot_y(xyzrpy[4]) * rot_x(xyzrpy[3]);
    P.topRightCorner<3, 1>() = Vector3d(xyzrpy[0], xyzrpy[1], xyzrpy[2]);
    store(P, T);
}

void ls_pose_to_xyzrpy(const double T[16], double xyzrpy[6]) noexcept
{
    if (T == nullptr || xyzrpy == nullptr) {
        return;
    }
    const Matrix4d P = Map<const Matrix4d>(T);
    const Matrix3d R = P.topLeftCorner<3, 3>();
    xyzrpy[0] = P(0, 3);
    xyzrpy[1] = P(1, 3);
    xyzrpy[2] = P(2, 3);
    const double cp = std::hypot(R(0, 0), R(1, 0));
    double yaw;
    bool gimbal = cp < 1e-12;
    if (gimbal) {
        // pitch = +-pi/2: only roll -+ yaw is defined; roll = 0 by convention.
        yaw = std::atan2(-R(0, 1), R(1, 1));
    } else {
        yaw = std::atan2(R(1, 0), R(0, 0));
    }
    // Ry(pitch) Rx(roll) = Rz(-yaw) R: reading pitch and roll from it keeps
    // them consistent with the chosen yaw even close to the gimbal lock.
    const Matrix3d N = rot_z(-yaw) * R;
    xyzrpy[4] = std::atan2(-N(2, 0), N(0, 0));
    xyzrpy[3] = gimbal ? 0.0 : std::atan2(-N(1, 2), N(1, 1));
    xyzrpy[5] = yaw;
}

void ls_pose_mul(const double A[16], const double B[16], double AB[16]) noexcept
{
    if (A == nullptr || B == nullptr || AB == nullptr) {
        return;
    }
    const Matrix4d P = Map<const Matrix4d>(A) * Map<const Matrix4d>(B); // AB may alias A or B
    store(P, AB);
}

void ls_pose_inv(const double T[16], double Tinv[16]) noexcept
{
    if (T == nullptr || Tinv == nullptr) {
        return;
    }
    const Matrix4d P = Map<const Matrix4d>(T);
    const Matrix3d Rt = P.topLeftCorner<3, 3>().transpose();
    Matrix4d I = Matrix4d::Identity();
    I.topLeftCorner<3, 3>() = Rt;
    I.topRightCorner<3, 1>() = -Rt * P.topRightCorner<3, 1>();
    store(I, Tinv);
}

void ls_pose_interp(const double A[16], const double B[16], double s, double T[16]) noexcept
{
    if (A == nullptr || B == nullptr || T == nullptr) {
        return;
    }
    const Matrix4d PA = Map<const Matrix4d>(A), PB = Map<const Matrix4d>(B);
    const Quaterniond qa(Matrix3d(PA.topLeftCorner<3, 3>()));
    const Quaterniond qb(Matrix3d(PB.topLeftCorner<3, 3>()));
    Matrix4d P = Matrix4d::Identity();
    // Eigen's slerp takes the shorter arc (it flips qb when qa . qb < 0).
    P.topLeftCorner<3, 3>() = qa.slerp(s, qb).toRotationMatrix();
    P.topRightCorner<3, 1>() = (1.0 - s) * PA.topRightCorner<3, 1>() + s * PB.topRightCorner<3, 1>();
    store(P, T);
}

double ls_pose_angle(const double A[16], const double B[16]) noexcept
{
    if (A == nullptr || B == nullptr) {
        return NAN;
    }
    const Matrix4d PA = Map<const Matrix4d>(A), PB = Map<const Matrix4d>(B);
    return rotation_angle(PA.topLeftCorner<3, 3>().transpose() * PB.topLeftCorner<3, 3>());
}

double ls_pose_dist(const double A[16], const double B[16]) noexcept
{
    if (A == nullptr || B == nullptr) {
        return NAN;
    }
    const Matrix4d PA = Map<const Matrix4d>(A), PB = Map<const Matrix4d>(B);
    return (PA.topRightCorner<3, 1>() - PB.topRightCorner<3, 1>()).norm();
}

} // extern "C"
