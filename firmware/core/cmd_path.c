/* Seed 3.5: the path queues (pathLoad, pathClearPath). A path is stored in
 * SI, checked point by point (frames, joint and workspace limits, rates,
 * auxiliary commands) before it changes: a refused pathLoad leaves the path
 * as it was. The queues are core->motion.paths (ls_core_state.h). */
#include <math.h>
#include <string.h>

#include "cmd_motion.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

int ls_path_find(const ls_core_t *core, const char *name)
{
    for (int i = 0; i < LS_PATH_MAX; i++) {
        if (core->motion.paths[i].used && strcmp(core->motion.paths[i].name, name) == 0) {
            return i;
        }
    }
    return LS_PATH_NONE;
}

static bool path_running(const ls_core_t *core, int i)
{
    return core->run.active && core->run.path == i;
}

void ls_path_delete(ls_core_t *core, int i)
{
    if (i >= 0 && i < LS_PATH_MAX) {
        core->motion.paths[i].used = false;
        core->motion.paths[i].n = 0;
        core->motion.paths[i].name[0] = '\0';
    }
}

static int32_t check_pct(ls_call_t *call, int k, const char *field, double v)
{
    if (!isfinite(v) || (v != 0.0 && v < LS_RATE_MIN_PCT) || v > 100.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "pathLoad point %d: %s %.4g is out of range: 0 (the current setting) or [%g, 100] %%", k, field,
                        v, LS_RATE_MIN_PCT);
    }
    return 0;
}

/* Validate point k of the message and convert it to SI. */
/* x as a path point stores it (ls_path_real_t), kept within [lo, hi] when
 * x is: rounding to float (the mcu profile) may cross a joint limit by one
 * unit in the last place, and the planner would then refuse the point. */
#define LS_PATH_REAL_TOWARD(s, t) _Generic((s), float : nextafterf, default : nextafter)((s), (t))
static ls_path_real_t store_within(double x, double lo, double hi)
{
    ls_path_real_t s = (ls_path_real_t)x;
    if (x >= lo && x <= hi) {
        while ((double)s > hi) {
            s = LS_PATH_REAL_TOWARD(s, (ls_path_real_t)-INFINITY);
        }
        while ((double)s < lo) {
            s = LS_PATH_REAL_TOWARD(s, (ls_path_real_t)INFINITY);
        }
    }
    return s;
}

static int32_t load_point(ls_core_t *core, ls_call_t *call, const ls_PathLoadReq *r, int k, ls_path_point_t *pt)
{
    const ls_TagPoint *tp = &r->tags[k];
    const ls_units_t un = ls_core_units(core, call->sup);
    memset(pt, 0, sizeof *pt);
    pt->used = true;
    pt->frame = r->frame;
    pt->motion = r->motion_type;
    pt->relative = r->offset_type == ls_OffsetType_RELATIVE_DATA;
    if (r->frame == ls_ReferenceFrame_JOINT_FRAME) {
        /* The seed's tag_struct carries up to 24 jointvals; this arm has
         * LS_N_JOINTS and uses exactly that many. */
        if (tp->joints_count != LS_N_JOINTS) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "pathLoad point %d: `joints` has %u values, this arm has %d joints: give exactly %d "
                            "(JOINT_FRAME)",
                            k, (unsigned)tp->joints_count, LS_N_JOINTS, LS_N_JOINTS);
        }
        if (!ls_mcmd_all_finite(tp->joints, LS_N_JOINTS)) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathLoad point %d: `joints` must be finite numbers", k);
        }
        double q[LS_N_JOINTS];
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q[j] = tp->joints[j] * ls_units_to_si_angular(un.angular, 1.0);
            const double lo = core->model->q_min_rad[j], hi = core->model->q_max_rad[j];
            pt->v[j] = pt->relative ? (ls_path_real_t)q[j] : store_within(q[j], lo, hi);
        }
        char why[LS_MOTION_WHY_LEN];
        if (!pt->relative && ls_mcmd_joints_within(core, un, q, why, sizeof why) != LS_OK) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "pathLoad point %d: %s", k, why);
        }
    } else {
        if (tp->pose_count != 6 || !ls_mcmd_all_finite(tp->pose, 6)) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                            "pathLoad point %d: a Cartesian frame needs 6 finite values in `pose` (x y z roll pitch "
                            "yaw), got %u",
                            k, (unsigned)tp->pose_count);
        }
        char field[32];
        ls_fmt_print(field, sizeof field, "point %d pose", k);
        const int32_t bad = ls_mcmd_check_pose(core, call, "pathLoad", field, tp->pose, un, true);
        if (bad != 0) {
            return bad;
        }
        double v[6];
        ls_units_pose_to_si(un.linear, un.angular, tp->pose, v);
        for (int i = 0; i < 6; i++) {
            pt->v[i] = (ls_path_real_t)v[i];
            v[i] = pt->v[i]; /* check what is stored: what runs */
        }
        if (!pt->relative) {
            double T[16], W[16], P[16];
            ls_pose_from_xyzrpy(v, T);
            if (r->frame == ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
                ls_mcmd_world_pose(core, W);
                ls_pose_mul(W, T, P);
            } else {
                memcpy(P, T, sizeof P);
            }
            char why[LS_MOTION_WHY_LEN];
            if (ls_mcmd_tip_within(core, un, &P[12], why, sizeof why) != LS_OK) {
                return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR, "pathLoad point %d: %s", k, why);
            }
        }
    }
    int32_t code;
    if ((code = check_pct(call, k, "transition_speed_pct", tp->transition_speed_pct)) != 0 ||
        (code = check_pct(call, k, "speed_pct", tp->speed_pct)) != 0 ||
        (code = check_pct(call, k, "accel_pct", tp->accel_pct)) != 0) {
        return code;
    }
    if (!isfinite(tp->time_delay_s) || tp->time_delay_s < 0.0 || tp->time_delay_s > 3600.0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_OUT_OF_RANGE_ERR,
                        "pathLoad point %d: time_delay_s %.4g is out of range [0, 3600] s", k, tp->time_delay_s);
    }
    ls_fmt_print(pt->tag, sizeof pt->tag, "%s", tp->tag_name);
    pt->tag_index = tp->tag_index;
    pt->delay_s = (ls_path_real_t)tp->time_delay_s;
    pt->blend_pct = (ls_path_real_t)tp->transition_speed_pct;
    pt->speed_pct = (ls_path_real_t)tp->speed_pct;
    pt->accel_pct = (ls_path_real_t)tp->accel_pct;
    pt->n_aux = (uint8_t)tp->aux_commands_count;
    for (int a = 0; a < pt->n_aux; a++) {
        ls_aux_t ax;
        char why[128];
        if (ls_aux_parse(tp->aux_commands[a], &ax, why, sizeof why) != LS_OK ||
            ls_aux_check_io(core, &ax, why, sizeof why) != LS_OK) {
            return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathLoad point %d: aux command '%s': %s", k,
                            tp->aux_commands[a], why);
        }
        ls_fmt_print(pt->aux[a], sizeof pt->aux[a], "%s", tp->aux_commands[a]);
    }
    return 0;
}

int32_t ls_h_path_load(struct ls_core *core, struct ls_call *call)
{
    const ls_PathLoadReq *r = &call->req->cmd.path_load;
    if (core->model == NULL) {
        return ls_mcmd_no_arm(call, "pathLoad");
    }
    int32_t named = ls_mcmd_check_name(call, "pathLoad", "path_name", r->path_name);
    if (named != 0) {
        return named;
    }
    if (r->number_of_points < 1 || (pb_size_t)r->number_of_points != r->tags_count) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: number_of_points %d must equal the number of points sent (%u) and be >= 1",
                        (int)r->number_of_points, (unsigned)r->tags_count);
    }
    if (r->frame != ls_ReferenceFrame_JOINT_FRAME && r->frame != ls_ReferenceFrame_BASE_CARTESIAN_FRAME &&
        r->frame != ls_ReferenceFrame_WORLD_CARTESIAN_FRAME) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: frame must be JOINT_FRAME, BASE_CARTESIAN_FRAME or WORLD_CARTESIAN_FRAME");
    }
    if (r->motion_type != ls_MotionType_JOINT_MOTION && r->motion_type != ls_MotionType_STRAIGHT_MOTION &&
        r->motion_type != ls_MotionType_SLEW_MOTION && r->motion_type != ls_MotionType_CIRCULAR_MOTION) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: motion_type %d is not a MotionType: JOINT_MOTION (0), STRAIGHT_MOTION (1), "
                        "SLEW_MOTION (2) or CIRCULAR_MOTION (3)",
                        (int)r->motion_type);
    }
    if ((r->motion_type == ls_MotionType_STRAIGHT_MOTION || r->motion_type == ls_MotionType_CIRCULAR_MOTION) &&
        r->frame == ls_ReferenceFrame_JOINT_FRAME) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR,
                        "pathLoad: %s needs Cartesian points (BASE_ or WORLD_CARTESIAN_FRAME)",
                        r->motion_type == ls_MotionType_STRAIGHT_MOTION ? "STRAIGHT_MOTION" : "CIRCULAR_MOTION");
    }
    int i = ls_path_find(core, r->path_name);
    if (i >= 0 && path_running(core, i)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "pathLoad: path '%s' belongs to a stopped motion: abortMotion first", r->path_name);
    }
    if (i < 0) {
        for (int k = 0; k < LS_PATH_MAX; k++) {
            if (!core->motion.paths[k].used) {
                i = k;
                break;
            }
        }
        if (i < 0) {
            return ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                            "pathLoad: all %d path queues are in use: pathClearPath one first", LS_PATH_MAX);
        }
    }
    ls_path_t *p = &core->motion.paths[i];
    const uint16_t have = p->used ? p->n : 0;
    if ((size_t)have + r->tags_count > LS_PATH_MAX_POINTS) {
        return ls_reply(call, ls_RetCode_CMD_NO_RESOURCES_ERR,
                        "pathLoad: path '%s' holds %u points, %u more exceed its %d", r->path_name, (unsigned)have,
                        (unsigned)r->tags_count, LS_PATH_MAX_POINTS);
    }
    /* Validate every point into the free tail first: the path changes only
     * when all of them are good. */
    for (int k = 0; k < (int)r->tags_count; k++) {
        int32_t code = load_point(core, call, r, k, &p->pt[have + k]);
        if (code != 0) {
            return code;
        }
    }
    if (!p->used) {
        p->used = true;
        ls_fmt_print(p->name, sizeof p->name, "%s", r->path_name);
    }
    p->n = (uint16_t)(have + r->tags_count);
    call->res->result.path_load.points_in_path = p->n;
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "path '%s' holds %u points", p->name, (unsigned)p->n);
}

int32_t ls_h_path_clear_path(struct ls_core *core, struct ls_call *call)
{
    const char *name = call->req->cmd.path_clear_path.path_name;
    int i = ls_path_find(core, name);
    if (i < 0) {
        return ls_reply(call, ls_RetCode_CMD_PARAM_ERR, "pathClearPath: there is no path named '%s'", name);
    }
    if (path_running(core, i)) {
        return ls_reply(call, ls_RetCode_CMD_BUSY_ERR,
                        "pathClearPath: path '%s' belongs to a stopped motion: abortMotion clears it", name);
    }
    ls_path_delete(core, i);
    return ls_reply(call, ls_RetCode_CMD_EXEC_OK, "path '%s' deleted", name);
}
