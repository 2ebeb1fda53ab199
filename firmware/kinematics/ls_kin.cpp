// Kinematics of the 6-DOF arm: standard DH forward kinematics, closed-form
// inverse kinematics for a spherical wrist and for a UR-style offset wrist,
// geometric Jacobian, pose helpers.
// Only fixed-size Eigen types: nothing here allocates or throws, so every
// entry point may run in the control loop (see ls_kin.h for costs).
#include "ls_kin.h"
#include "ls_math.h"
extern "C" {
#include "ls_fmt.h" // C, without its own extern "C"
}

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
// |cos(elbow)|, |sin(shoulder)| this close to 1 are 1: the two branches meet
// there, and rounding would otherwise split them by sqrt(2e-16) ~ 1e-8 rad.
// The pose moves only to second order (below 1e-12 m).
constexpr double kBranchesMeet = 1e-12;
constexpr double kLimitSlackRad = 1e-10; // a wrap this far past a limit is clamped onto it
constexpr double kSameBranchRad = 1e-9;  // branches closer than this are one branch
constexpr double kStructTol = 1e-12;     // DH structure checks
constexpr double kRotationTol = 1e-6;    // orthonormality of an input rotation

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

// ---- geometry classes (ls_kin_classify) ---------------------------------

bool is_zero(double v) noexcept
{
    return std::fabs(v) < kStructTol;
}

bool is_right_angle(double alpha) noexcept
{
    return std::fabs(std::cos(alpha)) < kStructTol;
}

bool is_parallel(double alpha) noexcept // alpha = 0: the next axis points the same way
{
    return std::fabs(std::sin(alpha)) < kStructTol && std::cos(alpha) > 0.0;
}

double deg(double rad) noexcept
{
    return rad * 180.0 / kPi;
}

// Finite parameters and ordered limits: what every class needs.
bool model_finite(const ls_robot_model_t &m, char *why, size_t whylen) noexcept
{
    for (int i = 0; i < LS_N_JOINTS; ++i) {
        const ls_dh_t &d = m.dh[i];
        if (!std::isfinite(d.a_m) || !std::isfinite(d.d_m) || !std::isfinite(d.alpha_rad) ||
            !std::isfinite(d.theta_offset_rad) || !std::isfinite(m.q_min_rad[i]) || !std::isfinite(m.q_max_rad[i])) {
            ls_fmt_print(why, whylen, "joint %d has a non-finite DH parameter or limit", i + 1);
            return false;
        }
        if (m.q_min_rad[i] > m.q_max_rad[i]) {
            ls_fmt_print(why, whylen, "joint %d: q_min %.6g rad is above q_max %.6g rad", i + 1, m.q_min_rad[i],
                         m.q_max_rad[i]);
            return false;
        }
    }
    return true;
}

// Each check names the first condition of its class that m breaks, written
// as "<the value>; <the rule>" for the classify message.

// What both classes need of the wrist axes and the shoulder: alpha4 and
// alpha5 +-90 deg, joint 1 not parallel to joint 2.
bool wrist_and_shoulder_fit(const ls_dh_t *d, char *why, size_t whylen) noexcept
{
    if (!is_right_angle(d[3].alpha_rad) || !is_right_angle(d[4].alpha_rad)) {
        const int j = is_right_angle(d[3].alpha_rad) ? 5 : 4;
        ls_fmt_print(why, whylen, "alpha%d = %.6g deg; alpha4 and alpha5 must be +-90 deg", j, deg(d[j - 1].alpha_rad));
        return false;
    }
    if (std::fabs(std::sin(d[0].alpha_rad)) <= 1e-9) {
        ls_fmt_print(why, whylen, "alpha1 = %.6g deg; joint 1 must not be parallel to joint 2", deg(d[0].alpha_rad));
        return false;
    }
    return true;
}

bool spherical_fits(const ls_robot_model_t &m, char *why, size_t whylen) noexcept
{
    const ls_dh_t *d = m.dh;
    const double wrist[4] = { d[3].a_m, d[4].a_m, d[5].a_m, d[4].d_m };
    static const char *const names[4] = { "a4", "a5", "a6", "d5" };
    for (int i = 0; i < 4; ++i) {
        if (!is_zero(wrist[i])) {
            ls_fmt_print(why, whylen, "%s = %.6g m; a4, a5, a6 and d5 must be 0 so that joints 4-6 meet", names[i],
                         wrist[i]);
            return false;
        }
    }
    if (!is_parallel(d[1].alpha_rad)) {
        ls_fmt_print(why, whylen, "alpha2 = %.6g deg; it must be 0 so that joints 2 and 3 are parallel",
                     deg(d[1].alpha_rad));
        return false;
    }
    if (!wrist_and_shoulder_fit(d, why, whylen)) {
        return false;
    }
    if (std::fabs(d[1].a_m) <= 1e-9 || std::hypot(d[2].a_m, d[3].d_m) <= 1e-9) {
        ls_fmt_print(why, whylen, "%s; the upper arm (a2) and the forearm (a3, d4) must not be 0",
                     std::fabs(d[1].a_m) <= 1e-9 ? "a2 = 0 m" : "a3 = d4 = 0 m");
        return false;
    }
    return true;
}

bool offset_fits(const ls_robot_model_t &m, char *why, size_t whylen) noexcept
{
    const ls_dh_t *d = m.dh;
    for (int i = 3; i < 6; ++i) {
        if (!is_zero(d[i].a_m)) {
            ls_fmt_print(why, whylen, "a%d = %.6g m; a4, a5 and a6 must be 0", i + 1, d[i].a_m);
            return false;
        }
    }
    if (!is_parallel(d[1].alpha_rad) || !is_parallel(d[2].alpha_rad)) {
        const int j = is_parallel(d[1].alpha_rad) ? 3 : 2;
        ls_fmt_print(why, whylen, "alpha%d = %.6g deg; alpha2 and alpha3 must be 0 so that joints 2-4 are parallel", j,
                     deg(d[j - 1].alpha_rad));
        return false;
    }
    if (!wrist_and_shoulder_fit(d, why, whylen)) {
        return false;
    }
    if (std::fabs(d[1].a_m) <= 1e-9 || std::fabs(d[2].a_m) <= 1e-9) {
        ls_fmt_print(why, whylen, "a%d = 0 m; the upper arm (a2) and the forearm (a3) must not be 0",
                     std::fabs(d[1].a_m) <= 1e-9 ? 2 : 3);
        return false;
    }
    return true;
}

// Does m's geometry fit the class it claims? (Every IK call asks: a model
// edited after its classification is refused, never solved wrongly.)
bool class_fits(const ls_robot_model_t &m) noexcept
{
    if (!model_finite(m, nullptr, 0)) {
        return false;
    }
    switch (m.ik_class) {
    case LS_IK_CLASS_SPHERICAL_WRIST: return spherical_fits(m, nullptr, 0);
    case LS_IK_CLASS_OFFSET_WRIST: return offset_fits(m, nullptr, 0);
    case LS_IK_CLASS_NONE: break;
    }
    return false;
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

double clamp_into(double q, double lo, double hi) noexcept
{
    return q < lo ? lo : (q > hi ? hi : q);
}

enum IkStatus { kIkOk, kIkUnreachable, kIkSingular, kIkLimits };

// The branches found so far: DH angles in, joint angles wrapped into the
// limits nearest ref out, coincident branches once.
struct Branches {
    const ls_robot_model_t &m;
    const double *ref;
    double (*q_out)[LS_N_JOINTS];
    int *n_out;

    void add(const double theta[LS_N_JOINTS]) const noexcept
    {
        double q[LS_N_JOINTS];
        for (int j = 0; j < LS_N_JOINTS; ++j) {
            if (!wrap_into(theta[j] - m.dh[j].theta_offset_rad, m.q_min_rad[j], m.q_max_rad[j], ref[j], &q[j])) {
                return;
            }
        }
        for (int b = 0; b < *n_out; ++b) {
            double diff = 0.0;
            for (int j = 0; j < LS_N_JOINTS; ++j) {
                diff = std::fmax(diff, std::fabs(q_out[b][j] - q[j]));
            }
            if (diff < kSameBranchRad) {
                return;
            }
        }
        for (int j = 0; j < LS_N_JOINTS; ++j) {
            q_out[*n_out][j] = q[j];
        }
        ++*n_out;
    }
};

// The planar two-link problem of joints 2-3 in frame 1: the upper arm a2
// (signed) and the virtual forearm of length L at angle gamma from x3 reach
// (px, py). cos(psi) of the elbow, false when out of reach.
struct Planar {
    double a2, L, gamma;

    bool elbow_cos(double px, double py, double *c) const noexcept
    {
        const double v = (px * px + py * py - a2 * a2 - L * L) / (2.0 * a2 * L);
        if (std::fabs(v) > 1.0 + kReachSlack) {
            return false;
        }
        *c = std::fabs(v) > 1.0 - kBranchesMeet ? std::copysign(1.0, v) : v;
        return true;
    }

    // DH angles of joints 2 and 3 for elbow branch el (0: sin(psi) >= 0).
    void solve(double px, double py, double c, int el, double *t2, double *t3) const noexcept
    {
        const double s_abs = std::sqrt(1.0 - c * c);
        const double s = el == 0 ? s_abs : -s_abs;
        *t3 = std::atan2(s, c) - gamma;
        *t2 = std::atan2(py, px) - std::atan2(L * s, a2 + L * c);
    }
};

// Joint 1 for both classes: the wrist centre w (where joint 5's axis meets
// frame 5) must lie at height h along z1 from frame 1's origin. Fills
// theta1[2] (front, back); *singular when w is on the joint 1 axis.
IkStatus shoulder(const ls_robot_model_t &m, const Vector3d &w, double h, double theta1[2], bool *singular) noexcept
{
    const ls_dh_t *d = m.dh;
    const double sa1 = std::sin(d[0].alpha_rad), ca1 = std::cos(d[0].alpha_rad);
    const double k = (ca1 * (w.z() - d[0].d_m) - h) / sa1; // = r sin(phi - theta1)
    const double r = std::hypot(w.x(), w.y());
    // On the joint 1 axis (only possible when k = 0) every q1 places the
    // centre equally well: q1 is undetermined. Reachability is still checked
    // (with q1 = 0, pi) so that a far-away pose reports unreachable.
    *singular = r < kShoulderSingularM;
    theta1[0] = 0.0;
    theta1[1] = kPi;
    if (*singular) {
        return std::fabs(k) >= kShoulderSingularM ? kIkUnreachable : kIkOk;
    }
    double sk = k / r;
    if (std::fabs(sk) > 1.0 + kReachSlack) {
        return kIkUnreachable;
    }
    sk = std::fabs(sk) > 1.0 - kBranchesMeet ? std::copysign(1.0, sk) : sk;
    const double phi = std::atan2(w.y(), w.x());
    const double as = std::asin(sk);
    theta1[0] = phi - as;
    theta1[1] = phi - kPi + as;
    return kIkOk;
}

// p1 = A1(t1)^-1 p: a base-frame point in frame 1 (x, y in the plane of the
// parallel joints, z along them).
Vector3d in_frame1(const ls_dh_t &d1, double t1, const Vector3d &p) noexcept
{
    const double c1 = std::cos(t1), s1 = std::sin(t1);
    const double sa1 = std::sin(d1.alpha_rad), ca1 = std::cos(d1.alpha_rad);
    const double X = c1 * p.x() + s1 * p.y() - d1.a_m;
    const double Y = -s1 * p.x() + c1 * p.y();
    const double Z = p.z() - d1.d_m;
    return Vector3d(X, ca1 * Y + sa1 * Z, -sa1 * Y + ca1 * Z);
}

// The wrist centre: where joint 5's axis meets frame 5. The flange sits d6
// along z5 = R Rx(-alpha6) e_z from it.
Vector3d wrist_centre(const ls_dh_t &d6, const Matrix4d &T) noexcept
{
    const Matrix3d R = T.topLeftCorner<3, 3>();
    const Vector3d p = T.topRightCorner<3, 1>();
    return p - d6.d_m * (R * Vector3d(0.0, std::sin(d6.alpha_rad), std::cos(d6.alpha_rad)));
}

// The wrist product M = Rz(ta) Rx(alpha4) Rz(t5) Rx(alpha5) Rz(t6), with ta
// = t4 for a spherical wrist and t2 + t3 + t4 for an offset wrist, solved for
// the wrist branch f (+1: sin t5 >= 0). Its third column is
// (s5 cos ta sin t5, s5 sin ta sin t5, -s4 s5 cos t5) and its third row
// (s4 sin t5 cos t6, -s4 sin t5 sin t6, .). At sin t5 = 0 only ta +- t6 is
// defined: the class keeps one of them (keep_ta, else t6) at `kept` and the
// other is solved.
struct Wrist {
    double ta, t5, t6;
};

// The signs of sin(alpha4) and sin(alpha5) (both +-1: the classes need
// alpha4, alpha5 = +-90 deg), taken once per IK call.
struct WristSigns {
    double s4, s5;
};

WristSigns wrist_signs(const ls_dh_t *d) noexcept
{
    return { std::sin(d[3].alpha_rad) > 0.0 ? 1.0 : -1.0, std::sin(d[4].alpha_rad) > 0.0 ? 1.0 : -1.0 };
}

Wrist solve_wrist(const ls_robot_model_t &m, WristSigns sg, const Matrix3d &M, double f, bool keep_ta,
                  double kept) noexcept
{
    const ls_dh_t *d = m.dh;
    const double s4 = sg.s4, s5 = sg.s5;
    Wrist w{};
    w.t5 = std::atan2(f * std::hypot(M(0, 2), M(1, 2)), -s4 * s5 * M(2, 2));
    if (std::fabs(std::sin(w.t5)) >= kWristSingularSin) {
        w.ta = std::atan2(f * s5 * M(1, 2), f * s5 * M(0, 2));
        w.t6 = std::atan2(-f * s4 * M(2, 1), f * s4 * M(2, 0));
    } else if (keep_ta) {
        w.ta = kept;
        const Matrix3d N = (rot_z(w.ta) * rot_x(d[3].alpha_rad) * rot_z(w.t5) * rot_x(d[4].alpha_rad)).transpose() * M;
        w.t6 = std::atan2(N(1, 0), N(0, 0));
    } else {
        w.t6 = kept;
        const Matrix3d N = M * (rot_x(d[3].alpha_rad) * rot_z(w.t5) * rot_x(d[4].alpha_rad) * rot_z(w.t6)).transpose();
        w.ta = std::atan2(N(1, 0), N(0, 0));
    }
    return w;
}

// What the branches found add up to.
IkStatus outcome(bool any_reachable, bool shoulder_singular, int n) noexcept
{
    if (!any_reachable) {
        return kIkUnreachable;
    }
    if (shoulder_singular) {
        return kIkSingular;
    }
    return n > 0 ? kIkOk : kIkLimits;
}

// Spherical wrist (ls_kin_classify): joints 2-3 place the wrist centre,
// joints 4-6 the orientation.
IkStatus ik_spherical(const ls_robot_model_t &m, const Matrix4d &T, const Branches &out) noexcept
{
    const ls_dh_t *d = m.dh;
    const Vector3d w = wrist_centre(d[5], T);
    double theta1[2];
    bool shoulder_singular = false;
    if (shoulder(m, w, d[1].d_m + d[2].d_m + std::cos(d[2].alpha_rad) * d[3].d_m, theta1, &shoulder_singular) ==
        kIkUnreachable) {
        return kIkUnreachable;
    }
    // Upper arm a2, virtual forearm (a3, -sin(alpha3) d4) at angle gamma from x3.
    const double b3x = d[2].a_m, b3y = -std::sin(d[2].alpha_rad) * d[3].d_m;
    const Planar arm = { d[1].a_m, std::hypot(b3x, b3y), std::atan2(b3y, b3x) };
    const WristSigns sg = wrist_signs(d);
    // q4 kept at a wrist singularity: the caller's, within the limits.
    const double t4_kept = clamp_into(out.ref[3], m.q_min_rad[3], m.q_max_rad[3]) + d[3].theta_offset_rad;

    bool any_reachable = false;
    for (int sh = 0; sh < 2; ++sh) {
        const double t1 = theta1[sh];
        const Vector3d p1 = in_frame1(d[0], t1, w);
        double c;
        if (!arm.elbow_cos(p1.x(), p1.y(), &c)) {
            continue;
        }
        any_reachable = true;
        if (shoulder_singular) {
            continue;
        }
        for (int el = 0; el < 2; ++el) {
            double t2, t3;
            arm.solve(p1.x(), p1.y(), c, el, &t2, &t3);
            const Matrix3d R03 = dh_transform(d[0], t1).topLeftCorner<3, 3>() *
                                 dh_transform(d[1], t2).topLeftCorner<3, 3>() *
                                 dh_transform(d[2], t3).topLeftCorner<3, 3>();
            const Matrix3d M = R03.transpose() * T.topLeftCorner<3, 3>() * rot_x(-d[5].alpha_rad);
            for (int wr = 0; wr < 2; ++wr) {
                const Wrist wrist = solve_wrist(m, sg, M, wr == 0 ? 1.0 : -1.0, true, t4_kept);
                const double theta[LS_N_JOINTS] = { t1, t2, t3, wrist.ta, wrist.t5, wrist.t6 };
                out.add(theta);
            }
        }
    }
    return outcome(any_reachable, shoulder_singular, *out.n_out);
}

// Offset wrist (ls_kin_classify). In frame 1 the rotation is the wrist
// product with ta = t2 + t3 + t4 (solve_wrist), so t5, t6 and that sum come
// from the orientation. Joint 4's axis, d5 back from the wrist centre along
// z4 = Rz(ta) Rx(alpha4) e_z = (s4 sin ta, -s4 cos ta, 0), is the point the
// planar arm a2, a3 reaches, and t4 = ta - t2 - t3.
IkStatus ik_offset(const ls_robot_model_t &m, const Matrix4d &T, const Branches &out) noexcept
{
    const ls_dh_t *d = m.dh;
    const Vector3d w = wrist_centre(d[5], T);
    double theta1[2];
    bool shoulder_singular = false;
    if (shoulder(m, w, d[1].d_m + d[2].d_m + d[3].d_m, theta1, &shoulder_singular) == kIkUnreachable) {
        return kIkUnreachable;
    }
    const Planar arm = { d[1].a_m, std::fabs(d[2].a_m), std::atan2(0.0, d[2].a_m) };
    const WristSigns sg = wrist_signs(d);
    // q6 kept at a wrist singularity: the caller's, within the limits.
    const double t6_kept = clamp_into(out.ref[5], m.q_min_rad[5], m.q_max_rad[5]) + d[5].theta_offset_rad;

    bool any_reachable = false;
    for (int sh = 0; sh < 2; ++sh) {
        const double t1 = theta1[sh];
        const Vector3d p1 = in_frame1(d[0], t1, w);
        const Matrix3d M =
            dh_transform(d[0], t1).topLeftCorner<3, 3>().transpose() * T.topLeftCorner<3, 3>() * rot_x(-d[5].alpha_rad);
        Wrist wrist[2];
        double px[2], py[2], c[2];
        bool reach[2];
        for (int wr = 0; wr < 2; ++wr) {
            wrist[wr] = solve_wrist(m, sg, M, wr == 0 ? 1.0 : -1.0, false, t6_kept);
            px[wr] = p1.x() - d[4].d_m * sg.s4 * std::sin(wrist[wr].ta);
            py[wr] = p1.y() + d[4].d_m * sg.s4 * std::cos(wrist[wr].ta);
            reach[wr] = arm.elbow_cos(px[wr], py[wr], &c[wr]);
            any_reachable = any_reachable || reach[wr];
        }
        if (shoulder_singular) {
            continue;
        }
        for (int el = 0; el < 2; ++el) {
            for (int wr = 0; wr < 2; ++wr) {
                if (!reach[wr]) {
                    continue;
                }
                double t2, t3;
                arm.solve(px[wr], py[wr], c[wr], el, &t2, &t3);
                const double theta[LS_N_JOINTS] = { t1, t2, t3, wrist[wr].ta - t2 - t3, wrist[wr].t5, wrist[wr].t6 };
                out.add(theta);
            }
        }
    }
    return outcome(any_reachable, shoulder_singular, *out.n_out);
}

// Every branch of the model's class, each joint wrapped into its limits
// nearest ref[j] (ls_kin.h: order, conventions).
IkStatus ik_branches(const ls_robot_model_t &m, const Matrix4d &T, const double ref[LS_N_JOINTS],
                     double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) noexcept
{
    *n_out = 0;
    const Branches out = { m, ref, q_out, n_out };
    return m.ik_class == LS_IK_CLASS_OFFSET_WRIST ? ik_offset(m, T, out) : ik_spherical(m, T, out);
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

int ls_kin_classify(const ls_robot_model_t *m, ls_ik_class_t *cls, char *why, size_t whylen) noexcept
{
    if (why != nullptr && whylen > 0) {
        why[0] = '\0';
    }
    if (m == nullptr || cls == nullptr) {
        ls_fmt_print(why, whylen, "no model");
        return LS_EINVAL;
    }
    if (!model_finite(*m, why, whylen)) {
        return LS_EINVAL;
    }
    char sph[160], off[160];
    if (spherical_fits(*m, sph, sizeof sph)) {
        *cls = LS_IK_CLASS_SPHERICAL_WRIST;
        return LS_OK;
    }
    if (offset_fits(*m, off, sizeof off)) {
        *cls = LS_IK_CLASS_OFFSET_WRIST;
        return LS_OK;
    }
    ls_fmt_print(why, whylen, "not a spherical wrist (%s) and not an offset wrist (%s)", sph, off);
    return LS_EINVAL;
}

int ls_kin_ik_all(const ls_robot_model_t *m, const double T_base_flange[16],
                  double q_out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], int *n_out) noexcept
{
    if (n_out != nullptr) {
        *n_out = 0;
    }
    if (m == nullptr || T_base_flange == nullptr || q_out == nullptr || n_out == nullptr || !class_fits(*m)) {
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
        !finite_n(q_near, LS_N_JOINTS) || !class_fits(*m)) {
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
