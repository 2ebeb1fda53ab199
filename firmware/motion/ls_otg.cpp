// ls_otg: the C API of ls_otg.h over ruckig's target calculator.
//
// Fixed size and no exceptions: ruckig's types with compile-time DOFs and
// StandardVector (std::array), the calculator called with throw_error =
// false and inputs validated without throwing. The workspace and the
// trajectory live in the caller's storage, constructed in place once and
// never destroyed (their destructors would only reference operator delete
// for InputParameter's empty, unused waypoint vectors).
#include "ls_otg.h"

#include <cmath>
#include <cstring>
#include <new>
#include <type_traits>

#include <ruckig/calculator.hpp>
#include <ruckig/input_parameter.hpp>
#include <ruckig/trajectory.hpp>

namespace
{

constexpr size_t kDofs = LS_OTG_MAX_AXES;
using Input = ruckig::InputParameter<kDofs>;
using Trajectory = ruckig::Trajectory<kDofs>;
using Calculator = ruckig::Calculator<kDofs>;

constexpr uint32_t kMagic = 0x4f544731u; // "OTG1"

struct Workspace {
    // Explicit: ruckig's Calculator() is explicit, which clang refuses in
    // the aggregate initialisation Workspace{} would be.
    Workspace() : magic(0), calc(), input(), traj()
    {
    }
    uint32_t magic;
    Calculator calc;
    Input input;
    Trajectory traj; // planned here first, so *tr is untouched on error
};

static_assert(sizeof(Workspace) <= LS_OTG_PLANNER_BYTES, "raise LS_OTG_PLANNER_BYTES in ls_otg.h");
static_assert(alignof(Workspace) <= 16, "ls_otg_planner_t is 16-byte aligned");
static_assert(sizeof(Trajectory) <= LS_OTG_TRAJ_BYTES, "raise LS_OTG_TRAJ_BYTES in ls_otg.h");
static_assert(alignof(Trajectory) <= 16, "ls_otg_t's storage is 16-byte aligned");
// ls_otg_t is copied as plain data (ls_otg.h): the trajectory must be too.
static_assert(std::is_trivially_copyable<Trajectory>::value, "ruckig::Trajectory must be trivially copyable");

Workspace *workspace(ls_otg_planner_t *pl)
{
    return std::launder(reinterpret_cast<Workspace *>(pl->bytes_));
}

const Trajectory *trajectory(const ls_otg_t *tr)
{
    return std::launder(reinterpret_cast<const Trajectory *>(tr->traj_));
}

bool finite_state(const ls_otg_state_t *s, uint8_t n, bool with_position)
{
    for (uint8_t i = 0; i < n; i++) {
        if ((with_position && !std::isfinite(s->p[i])) || !std::isfinite(s->v[i]) || !std::isfinite(s->a[i])) {
            return false;
        }
    }
    return true;
}

bool good_limits(const ls_otg_limits_t *lim, uint8_t n)
{
    for (uint8_t i = 0; i < n; i++) {
        for (double x : { lim->v_max[i], lim->a_max[i], lim->j_max[i] }) {
            if (!std::isfinite(x) || !(x > 0.0)) {
                return false;
            }
        }
    }
    return true;
}

// A target that cannot be held within the limits (ruckig's
// check_target_state_within_limits): unreachable, LS_ERANGE.
bool target_within(const ls_otg_state_t *tgt, const ls_otg_limits_t *lim, uint8_t n)
{
    for (uint8_t i = 0; i < n; i++) {
        if (std::fabs(tgt->v[i]) > lim->v_max[i] || std::fabs(tgt->a[i]) > lim->a_max[i]) {
            return false;
        }
    }
    return true;
}

int plan(ls_otg_planner_t *pl, ls_otg_t *tr, uint8_t n, const ls_otg_state_t *cur, const ls_otg_state_t *tgt,
         const ls_otg_limits_t *lim, bool velocity)
{
    if (pl == nullptr || tr == nullptr || cur == nullptr || tgt == nullptr || lim == nullptr || n < 1 ||
        n > LS_OTG_MAX_AXES) {
        return LS_EINVAL;
    }
    Workspace *ws = workspace(pl);
    if (ws->magic != kMagic) {
        return LS_EINVAL;
    }
    if (!finite_state(cur, n, true) || !finite_state(tgt, n, !velocity) || !good_limits(lim, n)) {
        return LS_EINVAL;
    }
    if (!target_within(tgt, lim, n)) {
        return LS_ERANGE;
    }
    Input &in = ws->input;
    in.control_interface = velocity ? ruckig::ControlInterface::Velocity : ruckig::ControlInterface::Position;
    in.synchronization = ruckig::Synchronization::Time;
    in.duration_discretization = ruckig::DurationDiscretization::Continuous;
    for (size_t i = 0; i < kDofs; i++) {
        const bool on = i < n;
        // Unused axes are disabled: ruckig holds them where they are.
        in.enabled[i] = on;
        in.current_position[i] = on ? cur->p[i] : 0.0;
        in.current_velocity[i] = on ? cur->v[i] : 0.0;
        in.current_acceleration[i] = on ? cur->a[i] : 0.0;
        in.target_position[i] = on && !velocity ? tgt->p[i] : in.current_position[i];
        in.target_velocity[i] = on ? tgt->v[i] : 0.0;
        in.target_acceleration[i] = on ? tgt->a[i] : 0.0;
        in.max_velocity[i] = on ? lim->v_max[i] : 1.0;
        in.max_acceleration[i] = on ? lim->a_max[i] : 1.0;
        in.max_jerk[i] = on ? lim->j_max[i] : 1.0;
    }
    // Ruckig's own check of the target adds one case to target_within: a
    // velocity that would overshoot v_max while the target acceleration is
    // taken back to zero (|v + a|a| / 2j| > v_max). The inputs are finite.
    if (!in.template validate<false>(false, true)) {
        return LS_ERANGE;
    }
    bool interrupted = false;
    // delta_time only matters for a discrete duration, which is not used.
    const ruckig::Result res = ws->calc.template calculate<false>(in, ws->traj, 0.001, interrupted);
    if (res == ruckig::Result::ErrorInvalidInput) {
        return LS_EINVAL;
    }
    if (res != ruckig::Result::Working && res != ruckig::Result::Finished) {
        return LS_ERANGE; // no profile within the limits (ruckig's step 1 or synchronisation failed)
    }
    std::memcpy(tr->traj_, &ws->traj, sizeof(Trajectory));
    tr->n = n;
    tr->velocity_ = velocity ? 1u : 0u;
    tr->duration_s = ws->traj.get_duration();
    tr->target = *tgt;
    return LS_OK;
}

} // namespace

extern "C" int ls_otg_planner_init(ls_otg_planner_t *pl)
{
    if (pl == nullptr) {
        return LS_EINVAL;
    }
    Workspace *ws = new (pl->bytes_) Workspace();
    ws->magic = kMagic;
    return LS_OK;
}

extern "C" int ls_otg_plan_position(ls_otg_planner_t *pl, ls_otg_t *tr, uint8_t n, const ls_otg_state_t *cur,
                                    const ls_otg_state_t *tgt, const ls_otg_limits_t *lim)
{
    return plan(pl, tr, n, cur, tgt, lim, false);
}

extern "C" int ls_otg_plan_velocity(ls_otg_planner_t *pl, ls_otg_t *tr, uint8_t n, const ls_otg_state_t *cur,
                                    const ls_otg_state_t *tgt, const ls_otg_limits_t *lim)
{
    // ruckig 0.19.4's velocity step 1 keeps its candidate profiles in an
    // array of 3 but, for a target acceleration other than 0, tries four
    // families that can yield up to 6: a write past the array on the stack
    // (AddressSanitizer, velocity_third_step1.cpp). With a target
    // acceleration of 0 it stops at the first profile found.
    if (tgt != nullptr && n <= LS_OTG_MAX_AXES) {
        for (uint8_t i = 0; i < n; i++) {
            if (tgt->a[i] != 0.0) {
                return LS_EINVAL;
            }
        }
    }
    return plan(pl, tr, n, cur, tgt, lim, true);
}

extern "C" void ls_otg_sample(const ls_otg_t *tr, double t_s, double *p, double *v, double *a, double *j)
{
    if (tr == nullptr || tr->n < 1 || tr->n > LS_OTG_MAX_AXES) {
        return;
    }
    const double T = tr->duration_s;
    const double t = (t_s > 0.0) ? t_s : 0.0; // NaN fails the comparison: 0
    std::array<double, kDofs> pp{}, vv{}, aa{}, jj{};
    size_t section = 0;
    trajectory(tr)->at_time(t < T ? t : T, pp, vv, aa, jj, section);
    const double dt = t < T ? 0.0 : t - T;
    for (uint8_t i = 0; i < tr->n; i++) {
        double pi = pp[i], vi = vv[i], ai = aa[i], ji = jj[i];
        if (t >= T) {
            // From the exact target on: constant acceleration, zero jerk.
            const double p_end = tr->velocity_ ? pp[i] : tr->target.p[i];
            pi = p_end + tr->target.v[i] * dt + 0.5 * tr->target.a[i] * dt * dt;
            vi = tr->target.v[i] + tr->target.a[i] * dt;
            ai = tr->target.a[i];
            ji = 0.0;
        }
        if (p != nullptr) {
            p[i] = pi;
        }
        if (v != nullptr) {
            v[i] = vi;
        }
        if (a != nullptr) {
            a[i] = ai;
        }
        if (j != nullptr) {
            j[i] = ji;
        }
    }
}
