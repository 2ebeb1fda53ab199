/* Seed 3.5.2 pathMove: the program builder. Every point of a path queue is
 * resolved against the one before it (relative points, frames, the tool)
 * and planned as a segment of its motion type (seed section 6: joint,
 * straight, slew, circular), with the cycle's closing segment and the blends
 * between segments, into core->motion.prog; the whole program is planned
 * and checked before anything moves. */
#include <math.h>
#include <string.h>

#include "cmd_motion.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

/* The tip pose (base frame) a Cartesian point names, resolved against the
 * previous tip pose P_prev when it is relative. */
static void cart_target(const ls_core_t *core, const ls_path_point_t *pt, const double P_prev[16], double P[16])
{
    double F[16], T[16], v[6];
    const double zero[6] = { 0 };
    for (int i = 0; i < 6; i++) {
        v[i] = pt->v[i];
    }
    if (pt->frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        ls_mcmd_world_pose(core, F);
    } else {
        ls_pose_from_xyzrpy(zero, F);
    }
    if (pt->relative) {
        ls_mcmd_offset_in_frame(F, P_prev, v, P);
    } else {
        ls_pose_from_xyzrpy(v, T);
        ls_pose_mul(F, T, P);
    }
}

/* Speed and acceleration fractions of a joint-space segment to pt. */
static void joint_fracs(const ls_core_t *core, const ls_path_point_t *pt, double *sf, double *af)
{
    *sf = (pt->speed_pct > 0.0 ? pt->speed_pct : core->settings.speed_pct) / 100.0;
    *af = (pt->accel_pct > 0.0 ? pt->accel_pct : core->settings.accel_pct) / 100.0;
}

static int seg_joint_kind(ls_motion_seg_t *s, const ls_core_t *core, const ls_path_point_t *pt,
                          const double q0[LS_N_JOINTS], const double q1[LS_N_JOINTS], char *why, unsigned whylen)
{
    double sf, af;
    joint_fracs(core, pt, &sf, &af);
    return pt->motion == ls_MotionType_SLEW_MOTION ? ls_motion_seg_slew(s, core->model, q0, q1, sf, af, why, whylen)
                                                   : ls_motion_seg_joint(s, core->model, q0, q1, sf, af, why, whylen);
}

/* Resolve point k (JOINT_, STRAIGHT_ or SLEW_MOTION) against the previous
 * position (q_prev, tip pose P_prev) and plan its segment into s. The target
 * is kept for the segment that closes a cycle. */
static int plan_point(ls_core_t *core, const ls_path_point_t *pt, const double q_prev[LS_N_JOINTS],
                      const double P_prev[16], ls_motion_seg_t *s, double q_target[LS_N_JOINTS], double P_target[16],
                      char *why, unsigned whylen)
{
    double tool[16];
    ls_mcmd_tool_pose(core, tool);
    if (pt->frame == ls_ReferenceFrame_JOINT_FRAME) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q_target[j] = pt->v[j] + (pt->relative ? q_prev[j] : 0.0);
        }
        ls_mcmd_tip_of(core, q_target, P_target);
        return seg_joint_kind(s, core, pt, q_prev, q_target, why, whylen);
    }
    cart_target(core, pt, P_prev, P_target);
    if (pt->motion == ls_MotionType_STRAIGHT_MOTION) {
        ls_motion_cart_limits_t lim;
        ls_mcmd_cart_limits(core, pt->speed_pct, pt->accel_pct, &lim);
        int st = ls_motion_seg_line(s, core->model, q_prev, tool, P_target, &lim, why, whylen);
        memcpy(q_target, s->q1, LS_N_JOINTS * sizeof(double));
        return st;
    }
    double tinv[16], Fl[16];
    ls_pose_inv(tool, tinv);
    ls_pose_mul(P_target, tinv, Fl);
    int ks = ls_kin_ik_nearest(core->model, Fl, q_prev, q_target);
    if (ks != LS_OK) {
        ls_fmt_print(why, whylen, "no joint solution for tip (%.4g, %.4g, %.4g) m (%s)", P_target[12], P_target[13],
                     P_target[14],
                     ks == LS_ELIMITS ? "beyond the joint limits"
                                      : (ks == LS_ESINGULAR ? "shoulder singularity" : "out of reach"));
        return LS_ERANGE;
    }
    return seg_joint_kind(s, core, pt, q_prev, q_target, why, whylen);
}

/* CIRCULAR_MOTION: points `via` and `goal` (the next one) make one arc from
 * the previous tip pose P_prev through via's position to goal's; it runs as
 * two arcs of the same circle, split at the via point (ls_motion_arc_split),
 * into s_via and s_goal, so that each point keeps its tag, auxiliary
 * commands and dwell. Orientation is slerped from each point to the next. */
static int plan_arc_pair(ls_core_t *core, const ls_path_point_t *via, const ls_path_point_t *goal,
                         const double q_prev[LS_N_JOINTS], const double P_prev[16], ls_motion_seg_t *s_via,
                         ls_motion_seg_t *s_goal, double P_via[16], double P_goal[16], char *why, unsigned whylen,
                         int *bad_point)
{
    double tool[16], Ma[16], Mb[16], ma[3], mb[3];
    const double zero[6] = { 0 };
    ls_mcmd_tool_pose(core, tool);
    cart_target(core, via, P_prev, P_via);
    cart_target(core, goal, P_via, P_goal);
    *bad_point = 0;
    int st = ls_motion_arc_split(&P_prev[12], &P_via[12], &P_goal[12], ma, mb);
    if (st < 0) {
        ls_fmt_print(why, whylen, "no circle: the previous point, this via and its goal are collinear or coincide");
        return st;
    }
    ls_pose_from_xyzrpy(zero, Ma);
    ls_pose_from_xyzrpy(zero, Mb);
    memcpy(&Ma[12], ma, sizeof ma);
    memcpy(&Mb[12], mb, sizeof mb);
    ls_motion_cart_limits_t lim;
    ls_mcmd_cart_limits(core, via->speed_pct, via->accel_pct, &lim);
    st = ls_motion_seg_arc(s_via, core->model, q_prev, tool, Ma, P_via, &lim, why, whylen);
    if (st < 0) {
        return st;
    }
    *bad_point = 1;
    ls_mcmd_cart_limits(core, goal->speed_pct, goal->accel_pct, &lim);
    return ls_motion_seg_arc(s_goal, core->model, s_via->q1, tool, Mb, P_goal, &lim, why, whylen);
}

/* CIRCULAR_MOTION points pair up as (via, goal) in load order within each
 * run of consecutive circular points: LS_PATH_NONE when every run has an
 * even count, else the index of the via point left without a goal. */
static int unpaired_circular(const ls_path_t *p)
{
    int run = 0;
    for (int k = 0; k < p->n; k++) {
        if (p->pt[k].motion == ls_MotionType_CIRCULAR_MOTION) {
            run++;
        } else if (run % 2 != 0) {
            return k - 1;
        } else {
            run = 0;
        }
    }
    return run % 2 != 0 ? p->n - 1 : LS_PATH_NONE;
}

static void copy_point_attrs(ls_motion_seg_t *s, const ls_path_point_t *pt, int k)
{
    memcpy(s->tag, pt->tag, sizeof s->tag);
    s->tag_index = pt->tag_index;
    s->point = k;
    s->delay_s = pt->delay_s;
    s->blend_frac = pt->blend_pct / 100.0;
    s->n_aux = pt->n_aux;
    memcpy(s->aux, pt->aux, sizeof s->aux);
    s->overlap_s = 0.0;
}

/* Point k is planned: where it is first reached (q_at, P_at) is kept for point 0,
 * the place a cycle closes on; where it ends (q_end, P_end) is where the next
 * point starts. */
static void chain_point(int k, const double q_at[LS_N_JOINTS], const double P_at[16], const double q_end[LS_N_JOINTS],
                        const double P_end[16], double q_first[LS_N_JOINTS], double P_first[16],
                        double q_prev[LS_N_JOINTS], double P_prev[16])
{
    if (k == 0) {
        memcpy(q_first, q_at, LS_N_JOINTS * sizeof q_at[0]);
        memcpy(P_first, P_at, 16u * sizeof P_at[0]);
    }
    memcpy(q_prev, q_end, LS_N_JOINTS * sizeof q_end[0]);
    memcpy(P_prev, P_end, 16u * sizeof P_end[0]);
}

/* Plan every segment of path `p` from q_start into core->motion.prog. Returns 0 or the
 * planner status with `why` naming the point. */
static int build_program(ls_core_t *core, const ls_path_t *p, const double q_start[LS_N_JOINTS], int32_t cycles,
                         char *why, unsigned whylen)
{
    double q_prev[LS_N_JOINTS], P_prev[16], q_first[LS_N_JOINTS], P_first[16];
    memcpy(q_prev, q_start, sizeof q_prev);
    ls_mcmd_tip_of(core, q_prev, P_prev);
    char w[LS_MOTION_WHY_LEN];
    for (int k = 0; k < p->n; k++) {
        ls_motion_seg_t *s = &core->motion.prog.seg[k];
        copy_point_attrs(s, &p->pt[k], k);
        double q_t[LS_N_JOINTS], P_t[16];
        int st;
        if (p->pt[k].motion == ls_MotionType_CIRCULAR_MOTION) {
            /* a via point and its goal (unpaired_circular checked the pairs) */
            ls_motion_seg_t *s2 = &core->motion.prog.seg[k + 1];
            copy_point_attrs(s2, &p->pt[k + 1], k + 1);
            double P_via[16];
            int bad = 0;
            st = plan_arc_pair(core, &p->pt[k], &p->pt[k + 1], q_prev, P_prev, s, s2, P_via, P_t, w, sizeof w, &bad);
            if (st < 0) {
                ls_fmt_print(why, whylen, "point %d (CIRCULAR_MOTION %s): %s", k + bad, bad ? "goal" : "via", w);
                return st;
            }
            chain_point(k, s->q1, P_via, s2->q1, P_t, q_first, P_first, q_prev, P_prev);
            k++;
            continue;
        }
        st = plan_point(core, &p->pt[k], q_prev, P_prev, s, q_t, P_t, w, sizeof w);
        if (st < 0) {
            ls_fmt_print(why, whylen, "point %d: %s", k, w);
            return st;
        }
        chain_point(k, s->q1, P_t, s->q1, P_t, q_first, P_first, q_prev, P_prev);
    }
    core->motion.prog.n = p->n;
    if (cycles > 1) {
        /* Close the cycle: from the last point back to point 0's position
         * (relative points were resolved once, against the start). */
        ls_motion_seg_t *s = &core->motion.prog.seg[p->n];
        const ls_path_point_t *pt0 = &p->pt[0];
        copy_point_attrs(s, pt0, 0);
        int st;
        /* A circular first point (a via point): a straight line back to it;
         * its arc to the goal (seg[1]) is the same in every cycle. */
        if (pt0->frame != ls_ReferenceFrame_JOINT_FRAME &&
            (pt0->motion == ls_MotionType_STRAIGHT_MOTION || pt0->motion == ls_MotionType_CIRCULAR_MOTION)) {
            ls_motion_cart_limits_t lim;
            ls_mcmd_cart_limits(core, pt0->speed_pct, pt0->accel_pct, &lim);
            double tool[16];
            ls_mcmd_tool_pose(core, tool);
            st = ls_motion_seg_line(s, core->model, q_prev, tool, P_first, &lim, w, sizeof w);
            if (st == 0) {
                for (int j = 0; j < LS_N_JOINTS; j++) {
                    if (fabs(s->q1[j] - q_first[j]) > 1e-6) {
                        ls_fmt_print(w, sizeof w, "the line back to it ends in another arm configuration (joint %d)",
                                     j + 1);
                        st = LS_ERANGE;
                        break;
                    }
                }
            }
        } else {
            st = seg_joint_kind(s, core, pt0, q_prev, q_first, w, sizeof w);
        }
        if (st < 0) {
            ls_fmt_print(why, whylen, "point 0 (start of cycle 2): %s", w);
            return st;
        }
    }
    /* Blends: each point with the segment that follows it (ls_motion_prog_blend
     * names the point when a blend cannot be run). */
    return ls_motion_prog_blend(&core->motion.prog, core->model, cycles, why, whylen);
}

int32_t ls_h_path_move(struct ls_core *core, struct ls_call *call)
{
    const ls_PathMoveReq *r = &call->req->cmd.path_move;
    if (core->ctl == NULL || core->model == NULL) {
        return ls_mcmd_no_arm(call, "pathMove");
    }
    int i = ls_path_find(core, r->path_name);
    if (i < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathMove: there is no path named '%s': pathLoad it first",
                        r->path_name);
    }
    /* An absent number_of_cycles is 1 by now (seed 3.5.2; the schema's
     * (ls.absent_means), applied by the dispatcher): only an explicit 0 is
     * a dry run. */
    if (r->number_of_cycles < 0 || r->number_of_cycles > LS_PATH_MAX_CYCLES) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "pathMove: number_of_cycles %d is out of range [0, %d] (0: dry run)", (int)r->number_of_cycles,
                        LS_PATH_MAX_CYCLES);
    }
    const int odd = unpaired_circular(&core->motion.paths[i]);
    if (odd >= 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathMove: path '%s': CIRCULAR_MOTION points pair up in load order as (via, goal) of one arc "
                        "each; point %d is a via point with no circular goal after it (an odd count): load one more "
                        "CIRCULAR_MOTION point after it or pathClearPath and load an even number",
                        r->path_name, odd);
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (snap.phase != LS_MOTION_IDLE) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR, "pathMove: the executor still holds a motion; try again");
    }
    int32_t code = 0;
    ls_motion_plan_t *slot = ls_mcmd_take_slot(core, call, "pathMove", &code);
    if (slot == NULL) {
        return code;
    }
    const bool dry = r->number_of_cycles == 0;
    const int32_t cycles = dry ? 1 : r->number_of_cycles;
    char why[LS_MCMD_WHY_LEN];
    int st = build_program(core, &core->motion.paths[i], snap.q_cmd_rad, cycles, why, sizeof why);
    if (st < 0) {
        return ls_mcmd_refused(call, st, "pathMove", why);
    }
    /* Segments the joints slow down: the answer counts them, a slowedDown
     * notice says where as each begins (cmd_motion_events.c). */
    const int n_segs = core->motion.prog.n + (cycles > 1 ? 1 : 0);
    int slowed = 0;
    for (int k = 0; k < n_segs; k++) {
        slowed += ls_motion_seg_slowdown(&core->motion.prog.seg[k], NULL) ? 1 : 0;
    }
    char note[96];
    ls_fmt_print(note, sizeof note, "%d of %d segments run slower where the joints need it (slowedDown notices)",
                 slowed, n_segs);
    (void)ls_motion_plan_path(slot, &core->motion.prog, cycles, dry, r->path_name);
    ls_fmt_print(core->motion.tag_path, sizeof core->motion.tag_path, "%s", r->path_name);
    core->motion.tag_last[0] = '\0';
    int32_t started = ls_mcmd_start_plan(core, call, slot, "pathMove", r->path_name, i, slowed > 0 ? note : NULL);
    if (started == ls_RetCode_CMD_STARTED_OK && dry) {
        /* Every notice of a dry run says so (its tag events and its final notice). */
        core->run.dry_run = true;
        return ls_reply(call, ls_RetCode_CMD_STARTED_OK,
                        "pathMove started as a dry run (number_of_cycles 0): one cycle without auxiliary "
                        "commands; expect pathMoveComplete with dry_run=true, or an alarm%s%s",
                        slowed > 0 ? "; " : "", slowed > 0 ? note : "");
    }
    return started;
}
