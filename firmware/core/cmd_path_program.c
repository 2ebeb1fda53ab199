/* Seed 3.5.2 pathMove: the program builder. Every point of a path queue is
 * resolved against the one before it (relative points, frames, the tool)
 * and planned as a segment, with the cycle's closing segment and the blends
 * between segments, into core->motion.prog; the whole program is planned
 * and checked before anything moves. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cmd_motion.h"
#include "ls_control.h"
#include "ls_kin.h"
#include "ls_units.h"

/* Resolve point k against the previous position (q_prev, tip pose P_prev)
 * and plan its segment into s. *straight_out and the target are kept for
 * the segment that closes a cycle. */
static int plan_point(ls_core_t *core, const ls_path_point_t *pt, const double q_prev[LS_N_JOINTS],
                      const double P_prev[16], ls_motion_seg_t *s, double q_target[LS_N_JOINTS], double P_target[16],
                      char *why, unsigned whylen)
{
    const ls_settings_t *set = &core->settings;
    const double sf = (pt->speed_pct > 0.0 ? pt->speed_pct : set->speed_pct) / 100.0;
    const double af = (pt->accel_pct > 0.0 ? pt->accel_pct : set->accel_pct) / 100.0;
    double tool[16];
    ls_mcmd_tool_pose(core, tool);
    if (pt->frame == ls_ReferenceFrame_JOINT_FRAME) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q_target[j] = pt->v[j] + (pt->relative ? q_prev[j] : 0.0);
        }
        ls_mcmd_tip_of(core, q_target, P_target);
        return ls_motion_seg_joint(s, core->model, q_prev, q_target, sf, af, why, whylen);
    }
    double F[16], T[16];
    const double zero[6] = { 0 };
    if (pt->frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        ls_mcmd_world_pose(core, F);
    } else {
        ls_pose_from_xyzrpy(zero, F);
    }
    if (pt->relative) {
        ls_mcmd_offset_in_frame(F, P_prev, pt->v, P_target);
    } else {
        ls_pose_from_xyzrpy(pt->v, T);
        ls_pose_mul(F, T, P_target);
    }
    if (pt->straight) {
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
    if (ks != LS_KIN_OK) {
        snprintf(why, whylen, "no joint solution for tip (%.4g, %.4g, %.4g) m (%s)", P_target[12], P_target[13],
                 P_target[14],
                 ks == LS_KIN_ELIMITS ? "beyond the joint limits"
                                      : (ks == LS_KIN_ESINGULAR ? "shoulder singularity" : "out of reach"));
        return LS_MOTION_ERANGE;
    }
    return ls_motion_seg_joint(s, core->model, q_prev, q_target, sf, af, why, whylen);
}

static void copy_point_attrs(ls_motion_seg_t *s, const ls_path_point_t *pt, int k)
{
    memcpy(s->tag, pt->tag, sizeof s->tag);
    s->tag_index = pt->tag_index;
    s->point = k;
    s->delay_s = pt->delay_s;
    s->n_aux = pt->n_aux;
    memcpy(s->aux, pt->aux, sizeof s->aux);
    s->overlap_s = 0.0;
}

/* Plan every segment of path `p` from q_start into core->motion.prog. Returns 0 or the
 * planner status with `why` naming the point. */
static int build_program(ls_core_t *core, const ls_path_t *p, const double q_start[LS_N_JOINTS], int32_t cycles,
                         char *why, unsigned whylen)
{
    double q_prev[LS_N_JOINTS], P_prev[16], q_first[LS_N_JOINTS], P_first[16];
    memcpy(q_prev, q_start, sizeof q_prev);
    ls_mcmd_tip_of(core, q_prev, P_prev);
    char w[112];
    for (int k = 0; k < p->n; k++) {
        ls_motion_seg_t *s = &core->motion.prog.seg[k];
        copy_point_attrs(s, &p->pt[k], k);
        double q_t[LS_N_JOINTS], P_t[16];
        int st = plan_point(core, &p->pt[k], q_prev, P_prev, s, q_t, P_t, w, sizeof w);
        if (st < 0) {
            snprintf(why, whylen, "point %d: %s", k, w);
            return st;
        }
        if (k == 0) {
            memcpy(q_first, s->q1, sizeof q_first);
            memcpy(P_first, P_t, sizeof P_first);
        }
        memcpy(q_prev, s->q1, sizeof q_prev);
        memcpy(P_prev, P_t, sizeof P_prev);
    }
    core->motion.prog.n = p->n;
    if (cycles > 1) {
        /* Close the cycle: from the last point back to point 0's position
         * (relative points were resolved once, against the start). */
        ls_motion_seg_t *s = &core->motion.prog.seg[p->n];
        const ls_path_point_t *pt0 = &p->pt[0];
        copy_point_attrs(s, pt0, 0);
        int st;
        if (pt0->frame != ls_ReferenceFrame_JOINT_FRAME && pt0->straight) {
            ls_motion_cart_limits_t lim;
            ls_mcmd_cart_limits(core, pt0->speed_pct, pt0->accel_pct, &lim);
            double tool[16];
            ls_mcmd_tool_pose(core, tool);
            st = ls_motion_seg_line(s, core->model, q_prev, tool, P_first, &lim, w, sizeof w);
            if (st == 0) {
                for (int j = 0; j < LS_N_JOINTS; j++) {
                    if (fabs(s->q1[j] - q_first[j]) > 1e-6) {
                        snprintf(w, sizeof w, "the line back to it ends in another arm configuration (joint %d)",
                                 j + 1);
                        st = LS_MOTION_ERANGE;
                        break;
                    }
                }
            }
        } else {
            const double sf = (pt0->speed_pct > 0.0 ? pt0->speed_pct : core->settings.speed_pct) / 100.0;
            const double af = (pt0->accel_pct > 0.0 ? pt0->accel_pct : core->settings.accel_pct) / 100.0;
            st = ls_motion_seg_joint(s, core->model, q_prev, q_first, sf, af, w, sizeof w);
        }
        if (st < 0) {
            snprintf(why, whylen, "point 0 (start of cycle 2): %s", w);
            return st;
        }
    }
    /* Blends: each point with the segment that follows it. */
    for (int k = 0; k < p->n; k++) {
        const ls_motion_seg_t *nx =
            k + 1 < p->n ? &core->motion.prog.seg[k + 1] : (cycles > 1 ? &core->motion.prog.seg[p->n] : NULL);
        ls_motion_seg_blend(&core->motion.prog.seg[k], nx, p->pt[k].blend_pct / 100.0);
    }
    if (cycles > 1) {
        const ls_motion_seg_t *nx = p->n > 1 ? &core->motion.prog.seg[1] : &core->motion.prog.seg[p->n];
        ls_motion_seg_blend(&core->motion.prog.seg[p->n], nx, p->pt[0].blend_pct / 100.0);
    }
    return 0;
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
    char why[160];
    int st = build_program(core, &core->motion.paths[i], snap.q_cmd_rad, cycles, why, sizeof why);
    if (st < 0) {
        return ls_mcmd_refused(call, st, "pathMove", why);
    }
    (void)ls_motion_plan_path(slot, &core->motion.prog, cycles, dry, r->path_name);
    snprintf(core->motion.tag_path, sizeof core->motion.tag_path, "%s", r->path_name);
    core->motion.tag_last[0] = '\0';
    int32_t started = ls_mcmd_start_plan(core, call, slot, "pathMove", r->path_name, i);
    if (started == ls_RetCode_CMD_STARTED_OK && dry) {
        /* Every notice of a dry run says so (its tag events and its final notice). */
        core->run.dry_run = true;
        return ls_reply(call, ls_RetCode_CMD_STARTED_OK,
                        "pathMove started as a dry run (number_of_cycles 0): one cycle without auxiliary "
                        "commands; expect pathMoveComplete with dry_run=true, or an alarm");
    }
    return started;
}
