/* The ODE world of hal/sim: arm, tool, sensors, environment (hal_sim_world.h
 * documents the model; this file explains only the non-obvious choices). */
#include "hal_sim_world.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <ode/ode.h>

#include "sim_world_internal.h"
#include "ls_math.h"

#define NJ HAL_SIM_ARM_JOINTS

#define GRAVITY_M_S2 9.81
#define SERVO_KP_1_S 200.0
#define SERVO_CFM 5e-5 /* 1 / motor damping (2e4 Nm s/rad) */
#define BRAKE_TORQUE_FACTOR 2.0
#define CONTACT_K_N_M 5e4
#define CONTACT_C_NS_M 500.0
#define CONTACT_MU 0.5
#define CONTACT_SLIP_M_S_N 1e-3 /* viscous friction below mu*N */
#define MAX_CONTACTS 96
#define CONTACTS_PER_PAIR 8 /* a cylinder face on a box gives 8 rim points */
#define STEP_RESERVE_BYTES (4u << 20)
#define PLATE_MASS_KG 0.1
#define PLATE_THICK_M 0.005
#define TOOL_ROD_RADIUS_M 0.015
#define TIP_RADIUS_M 0.01
#define LASER_RANGE_M 0.5
#define RACK_POS_TOL_M 0.002
#define RACK_ANG_TOL_RAD (2.0 * LS_PI / 180.0)
#define MAX_DT_S 0.1

typedef struct {
    const char *id;
    double offset[6]; /* flange -> tip, x y z roll pitch yaw */
    double mass_kg;
    double rack[6];    /* flange pose at the rack, base frame */
    uint32_t bit_mask; /* tool bits that exist */
} sim_tool_desc_t;

static const sim_tool_desc_t k_tools[] = {
    { "gripper", { 0.0, 0.0, 0.12, 0.0, 0.0, 0.0 }, 0.4, { 0.30, 0.50, 0.35, LS_PI, 0.0, 0.0 }, 0x1u },
    { "probe", { 0.0, 0.0, 0.15, 0.0, 0.0, 0.0 }, 0.2, { 0.30, -0.50, 0.35, LS_PI, 0.0, 0.0 }, 0x0u },
};
#define N_TOOLS ((int)(sizeof k_tools / sizeof k_tools[0]))

typedef struct {
    double R[9]; /* row-major */
    double p[3];
} frame_t;

/* A tool index (find_tool, W.tool) besides an index in k_tools. */
#define NO_TOOL (-1)      /* "none": the flange holds nothing */
#define UNKNOWN_TOOL (-2) /* no tool has this id */

static struct {
    bool open;
    hal_sim_arm_model_t m_data;
    const hal_sim_arm_model_t *m; /* &m_data while open */
    bool lockstep;
    bool with_obstacle;
    bool ode_initialised;

    dWorldID world;
    dJointGroupID contacts;
    dBodyID link[NJ];
    double frame_off[NJ][3]; /* origin of DH frame i in body i coordinates */
    dJointID hinge[NJ];
    dJointFeedback hinge_fb[NJ]; /* what each hinge applied in the last step (joint torque) */
    dBodyID tool_body;
    dJointID sensor_joint;
    dJointFeedback fb;
    double tool_mass_kg; /* tool body total (plate + tool) */
    dGeomID link6_geom, plate_geom, tip_geom, ray;
    dGeomID env[3];
    int n_env;

    int tool; /* index in k_tools, NO_TOOL: none */
    uint32_t tool_bits;

    bool joint_on[NJ]; /* false: the joint's brake holds it */
    double q[NJ], qd[NJ];
    double q_cmd[NJ], qd_cmd[NJ];
    double last_q_cmd[NJ], last_qd_cmd[NJ];

    bool in_contact, had_contact;
    double first_contact[3];

    double t_s, t_carry; /* the world's time: the sum of every step's dt since open (Kahan) */
    sim_trace_t trace;
    sim_ctl_t ctl;
} W;

/* ---- small rigid-body maths (row-major 3x3) ---- */

static void mat_mul(const double A[9], const double B[9], double C[9])
{
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            C[r * 3 + c] = A[r * 3] * B[c] + A[r * 3 + 1] * B[3 + c] + A[r * 3 + 2] * B[6 + c];
        }
    }
}

static void mat_vec(const double A[9], const double v[3], double out[3])
{
    for (int r = 0; r < 3; r++) {
        out[r] = A[r * 3] * v[0] + A[r * 3 + 1] * v[1] + A[r * 3 + 2] * v[2];
    }
}

static void mat_tvec(const double A[9], const double v[3], double out[3])
{
    for (int c = 0; c < 3; c++) {
        out[c] = A[c] * v[0] + A[3 + c] * v[1] + A[6 + c] * v[2];
    }
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void rpy_to_R(double roll, double pitch, double yaw, double R[9])
{
    double cr = cos(roll), sr = sin(roll), cp = cos(pitch), sp = sin(pitch), cy = cos(yaw), sy = sin(yaw);
    R[0] = cy * cp;
    R[1] = cy * sp * sr - sy * cr;
    R[2] = cy * sp * cr + sy * sr;
    R[3] = sy * cp;
    R[4] = sy * sp * sr + cy * cr;
    R[5] = sy * sp * cr - cy * sr;
    R[6] = -sp;
    R[7] = cp * sr;
    R[8] = cp * cr;
}

/* T_i = T_{i-1} * Rz(theta) Tz(d) Tx(a) Rx(alpha). */
static void dh_chain(const frame_t *prev, const hal_sim_dh_t *dh, double q, frame_t *out)
{
    double th = q + dh->theta_offset_rad;
    double ct = cos(th), st = sin(th), ca = cos(dh->alpha_rad), sa = sin(dh->alpha_rad);
    double A[9] = { ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca };
    double t[3] = { dh->a_m * ct, dh->a_m * st, dh->d_m };
    double pt[3];
    mat_mul(prev->R, A, out->R);
    mat_vec(prev->R, t, pt);
    for (int k = 0; k < 3; k++) {
        out->p[k] = prev->p[k] + pt[k];
    }
}

static void to_dmat(const double R[9], dMatrix3 out)
{
    for (int r = 0; r < 3; r++) {
        out[r * 4] = R[r * 3];
        out[r * 4 + 1] = R[r * 3 + 1];
        out[r * 4 + 2] = R[r * 3 + 2];
        out[r * 4 + 3] = 0.0;
    }
}

static void from_dmat(const dReal *in, double R[9])
{
    for (int r = 0; r < 3; r++) {
        R[r * 3] = in[r * 4];
        R[r * 3 + 1] = in[r * 4 + 1];
        R[r * 3 + 2] = in[r * 4 + 2];
    }
}

/* A rotation whose z column is the unit vector u (for capsule inertia). */
static void basis_from_z(const double u[3], double R[9])
{
    double helper[3] = { 1.0, 0.0, 0.0 };
    if (fabs(u[0]) > 0.9) {
        helper[0] = 0.0;
        helper[1] = 1.0;
    }
    double x[3], y[3];
    cross(helper, u, x);
    double n = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (int k = 0; k < 3; k++) {
        x[k] /= n;
    }
    cross(u, x, y);
    for (int r = 0; r < 3; r++) {
        R[r * 3] = x[r];
        R[r * 3 + 1] = y[r];
        R[r * 3 + 2] = u[r];
    }
}

static void flange_frame(frame_t *f)
{
    from_dmat(dBodyGetRotation(W.link[NJ - 1]), f->R);
    dVector3 p;
    dBodyGetRelPointPos(W.link[NJ - 1], W.frame_off[NJ - 1][0], W.frame_off[NJ - 1][1], W.frame_off[NJ - 1][2], p);
    memcpy(f->p, p, sizeof f->p);
}

static const double k_zero6[6] = { 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 };

static const double *tool_offset_of(int tool)
{
    return tool >= 0 ? k_tools[tool].offset : k_zero6;
}

/* Tool frame (at the tip) in the base frame. */
static void tool_frame(frame_t *t)
{
    frame_t f;
    flange_frame(&f);
    const double *off = tool_offset_of(W.tool);
    double Ro[9], po[3];
    rpy_to_R(off[3], off[4], off[5], Ro);
    mat_mul(f.R, Ro, t->R);
    mat_vec(f.R, off, po);
    for (int k = 0; k < 3; k++) {
        t->p[k] = f.p[k] + po[k];
    }
}

/* ---- tool body ---- */

/* Give the tool body the mass and geoms of the current tool, keeping it rigidly
 * at the flange: ODE wants the centre of mass at the body origin, so the body
 * moves to the new centre and the fixed joint is re-recorded. */
static void tool_rebuild(void)
{
    const hal_sim_arm_model_t *m = W.m;
    dMass mass, part;
    dMassSetCylinderTotal(&mass, PLATE_MASS_KG, 3, m->link_radius_m, PLATE_THICK_M);
    dMassTranslate(&mass, 0.0, 0.0, -PLATE_THICK_M / 2.0);
    double total = PLATE_MASS_KG;
    const double *off = tool_offset_of(W.tool);
    double tip_center[3] = { 0.0, 0.0, 0.0 };
    if (W.tool >= 0) {
        double len = sqrt(off[0] * off[0] + off[1] * off[1] + off[2] * off[2]);
        double u[3] = { off[0] / len, off[1] / len, off[2] / len };
        double Ru[9];
        dMatrix3 dR;
        basis_from_z(u, Ru);
        to_dmat(Ru, dR);
        dMassSetCapsuleTotal(&part, k_tools[W.tool].mass_kg, 3, TOOL_ROD_RADIUS_M, len);
        dMassRotate(&part, dR);
        dMassTranslate(&part, off[0] / 2.0, off[1] / 2.0, off[2] / 2.0);
        dMassAdd(&mass, &part);
        total += k_tools[W.tool].mass_kg;
        double Ro[9], back[3], zin[3] = { 0.0, 0.0, -TIP_RADIUS_M };
        rpy_to_R(off[3], off[4], off[5], Ro);
        mat_vec(Ro, zin, back);
        for (int k = 0; k < 3; k++) {
            tip_center[k] = off[k] + back[k];
        }
    }
    double com[3] = { mass.c[0], mass.c[1], mass.c[2] };
    dMassTranslate(&mass, -com[0], -com[1], -com[2]);

    dBodyID l6 = W.link[NJ - 1];
    frame_t f;
    flange_frame(&f);
    double comw[3];
    mat_vec(f.R, com, comw);
    for (int k = 0; k < 3; k++) {
        comw[k] += f.p[k];
    }
    dVector3 v;
    dBodyGetPointVel(l6, comw[0], comw[1], comw[2], v);
    const dReal *w = dBodyGetAngularVel(l6);
    dBodySetPosition(W.tool_body, comw[0], comw[1], comw[2]);
    dBodySetRotation(W.tool_body, dBodyGetRotation(l6));
    dBodySetLinearVel(W.tool_body, v[0], v[1], v[2]);
    dBodySetAngularVel(W.tool_body, w[0], w[1], w[2]);
    dBodySetMass(W.tool_body, &mass);
    W.tool_mass_kg = total;

    dGeomSetOffsetPosition(W.plate_geom, -com[0], -com[1], -PLATE_THICK_M / 2.0 - com[2]);
    dGeomSetOffsetPosition(W.tip_geom, tip_center[0] - com[0], tip_center[1] - com[1], tip_center[2] - com[2]);
    if (W.tool >= 0) {
        dGeomEnable(W.tip_geom);
    } else {
        dGeomDisable(W.tip_geom);
    }
    dJointSetFixed(W.sensor_joint);
    /* The feedback of the last step belongs to the old tool; until the next
     * step, report the resting value of the new one (reads as zero). */
    memset(&W.fb, 0, sizeof W.fb);
    W.fb.f1[2] = total * GRAVITY_M_S2;
}

/* ---- building the world ---- */

static void set_msg(char *msg, size_t msglen, const char *text)
{
    if (msg != NULL && msglen > 0) {
        snprintf(msg, msglen, "%s", text);
    }
}

static int check_model(const hal_sim_arm_model_t *m, char *msg, size_t msglen)
{
    if (m->n_joints != NJ) {
        set_msg(msg, msglen, "arm model: the simulation builds a 6-joint arm (n_joints = 6)");
        return LS_EINVAL;
    }
    for (int i = 0; i < NJ; i++) {
        if (!(m->q_min_rad[i] <= 0.0 && 0.0 <= m->q_max_rad[i]) || !(m->torque_max_Nm[i] > 0.0) ||
            !(m->link_mass_kg[i] > 0.0)) {
            set_msg(msg, msglen, "arm model: every joint needs q_min <= 0 <= q_max, torque_max > 0 and mass > 0");
            return LS_EINVAL;
        }
    }
    const hal_sim_dh_t *d6 = &m->dh[NJ - 1];
    if (fabs(d6->a_m) > 1e-12 || fabs(d6->alpha_rad) > 1e-12 || d6->d_m < 2.0 * PLATE_THICK_M ||
        !(m->link_radius_m > 0.0)) {
        set_msg(msg, msglen,
                "arm model: the simulation needs link 6 along z6 (a6 = alpha6 = 0, d6 >= 10 mm) and link_radius > 0");
        return LS_EINVAL;
    }
    return LS_OK;
}

int hal_sim_world_check_arm(const hal_sim_arm_model_t *arm, char *msg, size_t msglen)
{
    if (arm == NULL) {
        set_msg(msg, msglen, "arm model: none given");
        return LS_EINVAL;
    }
    return check_model(arm, msg, msglen);
}

static void build_arm(void)
{
    const hal_sim_arm_model_t *m = W.m;
    frame_t fr[NJ + 1];
    memset(&fr[0], 0, sizeof fr[0]);
    fr[0].R[0] = fr[0].R[4] = fr[0].R[8] = 1.0;
    for (int i = 0; i < NJ; i++) {
        dh_chain(&fr[i], &m->dh[i], 0.0, &fr[i + 1]);
    }
    for (int i = 0; i < NJ; i++) {
        const frame_t *a = &fr[i], *b = &fr[i + 1];
        double seg[3] = { b->p[0] - a->p[0], b->p[1] - a->p[1], b->p[2] - a->p[2] };
        double len = sqrt(seg[0] * seg[0] + seg[1] * seg[1] + seg[2] * seg[2]);
        double c[3] = { (a->p[0] + b->p[0]) / 2.0, (a->p[1] + b->p[1]) / 2.0, (a->p[2] + b->p[2]) / 2.0 };
        dMass mass;
        if (len > 1e-9) {
            double u_world[3] = { seg[0] / len, seg[1] / len, seg[2] / len };
            double u[3], Ru[9];
            dMatrix3 dR;
            mat_tvec(b->R, u_world, u);
            basis_from_z(u, Ru);
            to_dmat(Ru, dR);
            dMassSetCapsuleTotal(&mass, m->link_mass_kg[i], 3, m->link_radius_m, len);
            dMassRotate(&mass, dR);
        } else {
            dMassSetSphereTotal(&mass, m->link_mass_kg[i], m->link_radius_m);
        }
        dBodyID body = dBodyCreate(W.world);
        dMatrix3 dR;
        to_dmat(b->R, dR);
        dBodySetPosition(body, c[0], c[1], c[2]);
        dBodySetRotation(body, dR);
        dBodySetMass(body, &mass);
        double rel[3] = { b->p[0] - c[0], b->p[1] - c[1], b->p[2] - c[2] };
        mat_tvec(b->R, rel, W.frame_off[i]);
        W.link[i] = body;

        dJointID h = dJointCreateHinge(W.world, 0);
        /* body1 = child: ODE's hinge angle is body1 relative to body2 about the axis. */
        dJointAttach(h, body, i == 0 ? 0 : W.link[i - 1]);
        dJointSetHingeAnchor(h, a->p[0], a->p[1], a->p[2]);
        dJointSetHingeAxis(h, a->R[2], a->R[5], a->R[8]);
        if (m->q_min_rad[i] > -LS_PI && m->q_max_rad[i] < LS_PI) {
            dJointSetHingeParam(h, dParamLoStop, m->q_min_rad[i]);
            dJointSetHingeParam(h, dParamHiStop, m->q_max_rad[i]);
        }
        dJointSetFeedback(h, &W.hinge_fb[i]);
        W.hinge[i] = h;
    }

    /* Link 6 collides as a cylinder from frame 5 to the flange plate. */
    double len6 = m->dh[NJ - 1].d_m - PLATE_THICK_M;
    W.link6_geom = dCreateCylinder(0, m->link_radius_m, len6);
    dGeomSetBody(W.link6_geom, W.link[NJ - 1]);
    /* body origin sits at the middle of link 6: z6 = -d6/2 .. +d6/2 - plate */
    dGeomSetOffsetPosition(W.link6_geom, W.frame_off[NJ - 1][0], W.frame_off[NJ - 1][1],
                           W.frame_off[NJ - 1][2] - PLATE_THICK_M - len6 / 2.0);

    W.tool_body = dBodyCreate(W.world);
    W.plate_geom = dCreateCylinder(0, m->link_radius_m, PLATE_THICK_M);
    dGeomSetBody(W.plate_geom, W.tool_body);
    W.tip_geom = dCreateSphere(0, TIP_RADIUS_M);
    dGeomSetBody(W.tip_geom, W.tool_body);
    W.sensor_joint = dJointCreateFixed(W.world, 0);
    dJointAttach(W.sensor_joint, W.tool_body, W.link[NJ - 1]);
    dJointSetFeedback(W.sensor_joint, &W.fb);
    W.tool = NO_TOOL;
    tool_rebuild();
}

static void build_environment(void)
{
    W.n_env = 0;
    W.env[W.n_env++] = dCreatePlane(0, 0.0, 0.0, 1.0, 0.0);
    dGeomID table = dCreateBox(0, 0.50, 0.80, 0.10);
    dGeomSetPosition(table, 0.60, 0.0, 0.05);
    W.env[W.n_env++] = table;
    if (W.with_obstacle) {
        dGeomID box = dCreateBox(0, 0.10, 0.10, 0.10);
        dGeomSetPosition(box, 0.60, 0.20, 0.15);
        W.env[W.n_env++] = box;
    }
    W.ray = dCreateRay(0, LASER_RANGE_M);
}

static void set_motors(double dt)
{
    const hal_sim_arm_model_t *m = W.m;
    for (int i = 0; i < NJ; i++) {
        double vel, fmax, cfm;
        if (W.joint_on[i]) {
            vel = W.qd_cmd[i] + SERVO_KP_1_S * (W.q_cmd[i] - W.q[i]);
            double vmax = (m->q_max_rad[i] - W.q[i]) / dt;
            double vmin = (m->q_min_rad[i] - W.q[i]) / dt;
            vel = vel > vmax ? vmax : (vel < vmin ? vmin : vel);
            fmax = m->torque_max_Nm[i];
            cfm = SERVO_CFM;
        } else {
            vel = 0.0; /* brake: a hard constraint up to the holding torque */
            fmax = BRAKE_TORQUE_FACTOR * m->torque_max_Nm[i];
            cfm = 0.0;
        }
        dJointSetHingeParam(W.hinge[i], dParamVel, vel);
        dJointSetHingeParam(W.hinge[i], dParamFMax, fmax);
        dJointSetHingeParam(W.hinge[i], dParamCFM, cfm);
    }
}

/* Hinge angles come in (-pi, pi]; keep q continuous without accumulating
 * rounding: q = angle + 2 pi k with k nearest to the previous q. */
static void read_joints(void)
{
    for (int i = 0; i < NJ; i++) {
        double a = dJointGetHingeAngle(W.hinge[i]);
        double k = nearbyint((W.q[i] - a) / (2.0 * LS_PI));
        W.q[i] = a + 2.0 * LS_PI * k;
        W.qd[i] = dJointGetHingeAngleRate(W.hinge[i]);
    }
}

static void collide(double dt)
{
    dJointGroupEmpty(W.contacts);
    W.in_contact = false;
    double erp = dt * CONTACT_K_N_M / (dt * CONTACT_K_N_M + CONTACT_C_NS_M);
    double cfm = 1.0 / (dt * CONTACT_K_N_M + CONTACT_C_NS_M);
    dGeomID arm[3] = { W.link6_geom, W.plate_geom, W.tip_geom };
    int n_arm = W.tool >= 0 ? 3 : 2;
    int made = 0;
    for (int g = 0; g < n_arm; g++) {
        for (int e = 0; e < W.n_env; e++) {
            dContactGeom cg[CONTACTS_PER_PAIR];
            int n = dCollide(arm[g], W.env[e], CONTACTS_PER_PAIR, cg, (int)sizeof cg[0]);
            /* A face resting on the table yields up to 4 points: each gets 1/n
             * of the spring and damper, so the pair's force is k * depth. */
            double pair_cfm = cfm * (double)n;
            for (int k = 0; k < n && made < MAX_CONTACTS; k++, made++) {
                dContact c;
                memset(&c, 0, sizeof c);
                c.surface.mode = dContactSoftERP | dContactSoftCFM | dContactApprox1 | dContactSlip1 | dContactSlip2;
                c.surface.mu = CONTACT_MU;
                c.surface.slip1 = CONTACT_SLIP_M_S_N;
                c.surface.slip2 = CONTACT_SLIP_M_S_N;
                c.surface.soft_erp = erp;
                c.surface.soft_cfm = pair_cfm;
                c.geom = cg[k];
                dJointID j = dJointCreateContact(W.world, W.contacts, &c);
                dJointAttach(j, dGeomGetBody(arm[g]), 0);
                if (!W.had_contact) {
                    W.had_contact = true;
                    memcpy(W.first_contact, cg[k].pos, sizeof W.first_contact);
                }
                W.in_contact = true;
            }
        }
    }
}

/* The first dWorldStep sizes ODE's step arena and the contact group fills
 * its obstack; do both at init so no control cycle allocates, then put every
 * body back exactly as built. */
static void warm_up(void)
{
    dJointGroupEmpty(W.contacts);
    dContact c;
    memset(&c, 0, sizeof c);
    for (int k = 0; k < MAX_CONTACTS; k++) {
        (void)dJointCreateContact(W.world, W.contacts, &c);
    }
    dJointGroupEmpty(W.contacts);

    dBodyID bodies[NJ + 1];
    for (int i = 0; i < NJ; i++) {
        bodies[i] = W.link[i];
    }
    bodies[NJ] = W.tool_body;
    dVector3 pos[NJ + 1], lv[NJ + 1], av[NJ + 1];
    dQuaternion quat[NJ + 1];
    for (int i = 0; i <= NJ; i++) {
        memcpy(pos[i], dBodyGetPosition(bodies[i]), sizeof pos[i]);
        memcpy(quat[i], dBodyGetQuaternion(bodies[i]), sizeof quat[i]);
        memcpy(lv[i], dBodyGetLinearVel(bodies[i]), sizeof lv[i]);
        memcpy(av[i], dBodyGetAngularVel(bodies[i]), sizeof av[i]);
    }
    set_motors(0.001);
    dWorldStep(W.world, 0.001);
    for (int i = 0; i <= NJ; i++) {
        dBodySetPosition(bodies[i], pos[i][0], pos[i][1], pos[i][2]);
        dBodySetQuaternion(bodies[i], quat[i]);
        dBodySetLinearVel(bodies[i], lv[i][0], lv[i][1], lv[i][2]);
        dBodySetAngularVel(bodies[i], av[i][0], av[i][1], av[i][2]);
    }
    memset(W.hinge_fb, 0, sizeof W.hinge_fb); /* no step has happened yet */
    read_joints();
}

int hal_sim_world_open(const hal_sim_world_config_t *cfg, char *msg, size_t msglen)
{
    if (W.open) {
        set_msg(msg, msglen, "the simulated world is already open (one per process); close it first");
        return LS_EINVAL;
    }
    if (cfg == NULL || cfg->arm == NULL) {
        set_msg(msg, msglen, "hal_sim_world_open needs a config with an arm model (hal_sim_arm_model_t)");
        return LS_EINVAL;
    }
    int rc = check_model(cfg->arm, msg, msglen);
    if (rc < 0) {
        return rc;
    }
    memset(&W, 0, sizeof W);
    W.m_data = *cfg->arm;
    W.m = &W.m_data;
    W.lockstep = cfg->lockstep;
    W.with_obstacle = cfg->with_obstacle;
    rc = sim_ctl_open(&W.ctl, cfg->dio_socket_path, msg, msglen);
    if (rc < 0) {
        return rc;
    }
    rc = sim_trace_open(&W.trace, &cfg->trace, msg, msglen);
    if (rc < 0) {
        sim_ctl_close(&W.ctl);
        return rc;
    }
    if (!dInitODE2(0) || !dAllocateODEDataForThread((unsigned int)dAllocateMaskAll)) {
        sim_trace_close(&W.trace);
        sim_ctl_close(&W.ctl);
        set_msg(msg, msglen, "ODE failed to initialise (out of memory?)");
        return LS_EIO;
    }
    W.ode_initialised = true;
    dRandSetSeed(0);
    W.world = dWorldCreate();
    dWorldSetGravity(W.world, 0.0, 0.0, -GRAVITY_M_S2);
    dWorldSetERP(W.world, 0.2);
    dWorldSetCFM(W.world, 1e-10);
    dWorldStepReserveInfo reserve = { .struct_size = sizeof reserve,
                                      .reserve_factor = 1.2f,
                                      .reserve_minimum = STEP_RESERVE_BYTES };
    (void)dWorldSetStepMemoryReservationPolicy(W.world, &reserve);
    W.contacts = dJointGroupCreate(0);
    build_arm();
    build_environment();
    warm_up();
    W.open = true;
    return LS_OK;
}

int hal_sim_world_attach_thread(void)
{
    if (!W.open) {
        return LS_ENODEV;
    }
    return dAllocateODEDataForThread((unsigned int)dAllocateMaskAll) ? LS_OK : LS_EIO;
}

void hal_sim_world_close(void)
{
    if (!W.ode_initialised) {
        return;
    }
    dGeomID geoms[4] = { W.link6_geom, W.plate_geom, W.tip_geom, W.ray };
    for (int i = 0; i < 4; i++) {
        dGeomDestroy(geoms[i]);
    }
    for (int i = 0; i < W.n_env; i++) {
        dGeomDestroy(W.env[i]);
    }
    dJointGroupDestroy(W.contacts);
    dWorldDestroy(W.world); /* bodies and joints with it */
    dCloseODE();
    sim_ctl_close(&W.ctl);
    sim_trace_close(&W.trace);
    memset(&W, 0, sizeof W);
}

int hal_sim_world_trace_write(char *msg, size_t msglen)
{
    if (!W.open) {
        return LS_ENODEV;
    }
    return sim_trace_write(&W.trace, msg, msglen);
}

/* ---- arm ops ---- */

static int arm_info(void *self, hal_arm_info_t *out)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (out == NULL) {
        return LS_EINVAL;
    }
    memset(out, 0, sizeof *out);
    out->n_joints = NJ;
    for (int i = 0; i < NJ; i++) {
        out->q_min_rad[i] = W.m->q_min_rad[i];
        out->q_max_rad[i] = W.m->q_max_rad[i];
        out->torque_max_Nm[i] = W.m->torque_max_Nm[i];
    }
    return LS_OK;
}

static int arm_enable(void *self, bool on)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    for (int i = 0; i < NJ; i++) {
        W.joint_on[i] = on;
    }
    return LS_OK;
}

int hal_sim_world_enable_joint(unsigned joint, bool on)
{
    if (!W.open) {
        return LS_ENODEV;
    }
    if (joint >= NJ) {
        return LS_EINVAL;
    }
    W.joint_on[joint] = on;
    return LS_OK;
}

/* ODE reports the force and torque a joint applies to its first body (the
 * child link) at that body's centre of mass. Moved to the hinge's anchor the
 * force carries no torque about the axis, so the torque along the axis is
 * what the motor (or brake, or stop) applied. */
int hal_sim_world_joint_torque(double tau_Nm[HAL_SIM_ARM_JOINTS])
{
    if (!W.open) {
        return LS_ENODEV;
    }
    if (tau_Nm == NULL) {
        return LS_EINVAL;
    }
    for (int i = 0; i < NJ; i++) {
        const dJointFeedback *fb = &W.hinge_fb[i];
        dVector3 anchor, axis;
        dJointGetHingeAnchor(W.hinge[i], anchor);
        dJointGetHingeAxis(W.hinge[i], axis);
        const dReal *c = dBodyGetPosition(W.link[i]);
        double r[3] = { anchor[0] - c[0], anchor[1] - c[1], anchor[2] - c[2] };
        double f[3] = { fb->f1[0], fb->f1[1], fb->f1[2] };
        double rxf[3];
        cross(r, f, rxf);
        double t[3] = { fb->t1[0] - rxf[0], fb->t1[1] - rxf[1], fb->t1[2] - rxf[2] };
        tau_Nm[i] = t[0] * axis[0] + t[1] * axis[1] + t[2] * axis[2];
    }
    return LS_OK;
}

static int arm_command(void *self, const double *q_rad, const double *qd_rad_s)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (q_rad == NULL) {
        return LS_EINVAL;
    }
    for (int i = 0; i < NJ; i++) {
        if (!isfinite(q_rad[i]) || (qd_rad_s != NULL && !isfinite(qd_rad_s[i]))) {
            return LS_EINVAL;
        }
    }
    memcpy(W.q_cmd, q_rad, sizeof W.q_cmd);
    if (qd_rad_s != NULL) {
        memcpy(W.qd_cmd, qd_rad_s, sizeof W.qd_cmd);
    } else {
        memset(W.qd_cmd, 0, sizeof W.qd_cmd);
    }
    sim_trace_record(&W.trace, W.t_s, q_rad); /* nothing without a trace */
    return LS_OK;
}

static int arm_read(void *self, double *q_rad, double *qd_rad_s)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (q_rad == NULL && qd_rad_s == NULL) {
        return LS_EINVAL;
    }
    if (q_rad != NULL) {
        memcpy(q_rad, W.q, sizeof W.q);
    }
    if (qd_rad_s != NULL) {
        memcpy(qd_rad_s, W.qd, sizeof W.qd);
    }
    return LS_OK;
}

/* t_s += dt with Kahan's compensation: after n steps of 1 ms the time reads
 * n ms as closely as a double holds it, not n ms plus n roundings. */
static void advance_time(double dt_s)
{
    double y = dt_s - W.t_carry;
    double t = W.t_s + y;
    W.t_carry = (t - W.t_s) - y;
    W.t_s = t;
}

int hal_sim_world_step(void *self, double dt_s)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (!(dt_s > 0.0 && dt_s <= MAX_DT_S)) {
        return LS_EINVAL;
    }
    advance_time(dt_s); /* the loop's time advances in held steps too */
    bool same =
        memcmp(W.q_cmd, W.last_q_cmd, sizeof W.q_cmd) == 0 && memcmp(W.qd_cmd, W.last_qd_cmd, sizeof W.qd_cmd) == 0;
    bool still = true;
    for (int i = 0; i < NJ; i++) {
        if (W.qd_cmd[i] != 0.0) {
            still = false;
        }
    }
    memcpy(W.last_q_cmd, W.q_cmd, sizeof W.q_cmd);
    memcpy(W.last_qd_cmd, W.qd_cmd, sizeof W.qd_cmd);
    if (W.lockstep && same && still && !sim_ctl_jog_active(&W.ctl)) {
        return 0;
    }
    set_motors(dt_s);
    collide(dt_s);
    dWorldStep(W.world, dt_s);
    read_joints();
    return 1;
}

static void arm_close(void *self)
{
    (void)self; /* the world is closed by hal_sim_world_close() */
}

static const hal_arm_ops_t k_arm_ops = {
    .info = arm_info,
    .enable = arm_enable,
    .command = arm_command,
    .read = arm_read,
    .close = arm_close,
};

void hal_sim_world_get_arm(hal_arm_t *out)
{
    memset(out, 0, sizeof *out);
    out->ops = &k_arm_ops;
    out->self = &W;
    snprintf(out->name, sizeof out->name, "sim-ode:%s", W.m != NULL && W.m->name != NULL ? W.m->name : "arm");
}

/* ---- sensors ---- */

static int force_read(void *self, double *values)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (values == NULL) {
        return LS_EINVAL;
    }
    /* Joint force on the tool plus the tool's weight = minus the external
     * wrench on the (resting) tool = what the tool exerts on its surroundings. */
    double F[3] = { W.fb.f1[0], W.fb.f1[1], W.fb.f1[2] - W.tool_mass_kg * GRAVITY_M_S2 };
    frame_t t;
    tool_frame(&t);
    const dReal *com = dBodyGetPosition(W.tool_body);
    double r[3] = { com[0] - t.p[0], com[1] - t.p[1], com[2] - t.p[2] };
    double rxF[3];
    cross(r, F, rxF);
    double T[3] = { W.fb.t1[0] + rxF[0], W.fb.t1[1] + rxF[1], W.fb.t1[2] + rxF[2] };
    mat_tvec(t.R, F, values);
    mat_tvec(t.R, T, values + 3);
    return LS_OK;
}

static bool point_inside_env(const double p[3])
{
    if (p[2] < 0.0) {
        return true; /* below the floor */
    }
    for (int e = 1; e < W.n_env; e++) {
        if (dGeomBoxPointDepth(W.env[e], p[0], p[1], p[2]) > 0.0) {
            return true;
        }
    }
    return false;
}

static int laser_read(void *self, double *values)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (values == NULL) {
        return LS_EINVAL;
    }
    frame_t t;
    tool_frame(&t);
    if (point_inside_env(t.p)) {
        values[0] = 0.0;
        return LS_OK;
    }
    dGeomRaySet(W.ray, t.p[0], t.p[1], t.p[2], t.R[2], t.R[5], t.R[8]);
    dGeomRaySetLength(W.ray, LASER_RANGE_M);
    double best = LASER_RANGE_M;
    for (int e = 0; e < W.n_env; e++) {
        dContactGeom cg;
        if (dCollide(W.ray, W.env[e], 1, &cg, (int)sizeof cg) > 0 && cg.depth < best) {
            best = cg.depth;
        }
    }
    values[0] = best;
    return LS_OK;
}

static hal_sensor_t k_sensors[2] = {
    { .name = "force_sensor", .n_values = 6, .read = force_read, .self = &W },
    { .name = "laser_standoff_sensor", .n_values = 1, .read = laser_read, .self = &W },
};

const hal_sensor_t *hal_sim_world_sensors(size_t *count)
{
    if (count != NULL) {
        *count = 2;
    }
    return k_sensors;
}

/* ---- tool changer ---- */

static int find_tool(const char *id)
{
    if (id == NULL) {
        return UNKNOWN_TOOL;
    }
    for (int i = 0; i < N_TOOLS; i++) {
        if (strcmp(id, k_tools[i].id) == 0) {
            return i;
        }
    }
    return strcmp(id, "none") == 0 ? NO_TOOL : UNKNOWN_TOOL;
}

static const char *tool_name(void *self, int index)
{
    (void)self;
    return index >= 0 && index < N_TOOLS ? k_tools[index].id : NULL;
}

static int tool_rack_pose(void *self, const char *tool_id, double xyzrpy[6])
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    int t = find_tool(tool_id);
    if (t < 0 || xyzrpy == NULL) {
        return LS_EINVAL;
    }
    memcpy(xyzrpy, k_tools[t].rack, sizeof k_tools[t].rack);
    return LS_OK;
}

static int tool_offset(void *self, const char *tool_id, double xyzrpy[6])
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    int t = find_tool(tool_id);
    if (t == UNKNOWN_TOOL || xyzrpy == NULL) {
        return LS_EINVAL;
    }
    memcpy(xyzrpy, tool_offset_of(t), 6 * sizeof(double));
    return LS_OK;
}

static bool flange_at_rack(int t)
{
    frame_t f;
    flange_frame(&f);
    const double *r = k_tools[t].rack;
    double Rr[9];
    rpy_to_R(r[3], r[4], r[5], Rr);
    double dx = f.p[0] - r[0], dy = f.p[1] - r[1], dz = f.p[2] - r[2];
    double trace = 0.0; /* trace(Rr^T Rf) */
    for (int k = 0; k < 9; k++) {
        trace += Rr[k] * f.R[k];
    }
    double c = (trace - 1.0) / 2.0;
    c = c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
    return sqrt(dx * dx + dy * dy + dz * dz) <= RACK_POS_TOL_M && acos(c) <= RACK_ANG_TOL_RAD;
}

static int tool_couple(void *self, const char *tool_id, bool attach)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    int t = find_tool(tool_id);
    if (t < 0 || (attach ? W.tool != NO_TOOL : W.tool != t) || !flange_at_rack(t)) {
        return LS_EINVAL;
    }
    W.tool = attach ? t : NO_TOOL;
    W.tool_bits = 0;
    tool_rebuild();
    return LS_OK;
}

static int tool_set_bits(void *self, uint32_t on, uint32_t off)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    uint32_t have = W.tool >= 0 ? k_tools[W.tool].bit_mask : 0u;
    if (((on | off) & ~have) != 0) {
        return LS_EINVAL;
    }
    W.tool_bits = (W.tool_bits | on) & ~off;
    return LS_OK;
}

static int tool_get_bits(void *self, uint32_t *bits)
{
    (void)self;
    if (!W.open) {
        return LS_ENODEV;
    }
    if (bits == NULL) {
        return LS_EINVAL;
    }
    *bits = W.tool_bits;
    return LS_OK;
}

static const hal_tool_ops_t k_tool_ops = {
    .name = tool_name,
    .rack_pose = tool_rack_pose,
    .tool_offset = tool_offset,
    .couple = tool_couple,
    .set_bits = tool_set_bits,
    .get_bits = tool_get_bits,
};

void hal_sim_world_get_tool(hal_tool_t *out)
{
    out->ops = &k_tool_ops;
    out->self = &W;
}

/* ---- DIO, manual ---- */

void hal_sim_world_get_dio(hal_dio_t *out)
{
    memset(out, 0, sizeof *out);
    out->ops = &sim_dio_ops;
    out->self = &W.ctl;
    snprintf(out->name, sizeof out->name, "sim-dio");
}

void hal_sim_world_get_manual(hal_manual_t *out)
{
    memset(out, 0, sizeof *out);
    out->read = sim_manual_read;
    out->self = &W.ctl;
    out->stale_ms = 0; /* the socket's state holds until changed */
    snprintf(out->name, sizeof out->name, "sim");
}

/* ---- ground truth ---- */

int hal_sim_world_flange_pose(double T[16])
{
    if (!W.open) {
        return LS_ENODEV;
    }
    if (T == NULL) {
        return LS_EINVAL;
    }
    frame_t f;
    flange_frame(&f);
    for (int c = 0; c < 3; c++) {
        for (int r = 0; r < 3; r++) {
            T[c * 4 + r] = f.R[r * 3 + c];
        }
        T[c * 4 + 3] = 0.0;
    }
    T[12] = f.p[0];
    T[13] = f.p[1];
    T[14] = f.p[2];
    T[15] = 1.0;
    return LS_OK;
}

int hal_sim_world_contact(bool *in_contact, double point_m[3])
{
    if (!W.open) {
        return LS_ENODEV;
    }
    if (in_contact != NULL) {
        *in_contact = W.in_contact;
    }
    if (point_m != NULL) {
        memcpy(point_m, W.first_contact, sizeof W.first_contact);
    }
    return W.had_contact ? 1 : 0;
}

const char *hal_sim_world_current_tool(void)
{
    return (W.open && W.tool >= 0) ? k_tools[W.tool].id : "none";
}

uint32_t hal_sim_world_malformed_messages(void)
{
    return W.ctl.malformed;
}
