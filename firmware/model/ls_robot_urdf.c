#include "ls_robot_urdf.h"

#include <math.h>

#define PI_HALF 1.57079632679489661923

/* A cylinder of radius r from (x0,0,z0) to (x1,0,z1) along one axis of the
 * link frame (the DH segments are along z (d) or x (a)). */
static int write_segment(FILE *out, double r, double x0, double z0, double x1, double z1, int along_x)
{
    double len = along_x ? fabs(x1 - x0) : fabs(z1 - z0);
    if (len < 1e-9) {
        return 0;
    }
    return fprintf(out,
                   "    <visual>\n"
                   "      <origin xyz=\"%.17g 0 %.17g\" rpy=\"0 %.17g 0\"/>\n"
                   "      <geometry><cylinder radius=\"%.17g\" length=\"%.17g\"/></geometry>\n"
                   "      <material name=\"arm\"/>\n"
                   "    </visual>\n",
                   (x0 + x1) / 2, (z0 + z1) / 2, along_x ? PI_HALF : 0.0, r, len) < 0
               ? -1
               : 0;
}

int ls_robot_urdf_write(const ls_robot_model_t *m, FILE *out)
{
    if (m == NULL || out == NULL) {
        return -1;
    }
    int rc = 0;
    const double r = m->link_radius_m;
    rc |= fprintf(out,
                  "<?xml version=\"1.0\"?>\n"
                  "<!-- Generated from firmware/model/ls_robot_model.c by ls_urdf (firmware/model/ls_robot_urdf.c):\n"
                  "     do not edit. Joint values are the controller's joint angles [rad]. -->\n"
                  "<robot name=\"%s\">\n"
                  "  <material name=\"arm\"><color rgba=\"0.93 0.55 0.13 1\"/></material>\n"
                  "  <material name=\"joint\"><color rgba=\"0.25 0.25 0.28 1\"/></material>\n"
                  "  <link name=\"base_link\">\n"
                  "    <visual>\n"
                  "      <origin xyz=\"0 0 %.17g\" rpy=\"0 0 0\"/>\n"
                  "      <geometry><cylinder radius=\"%.17g\" length=\"%.17g\"/></geometry>\n"
                  "      <material name=\"joint\"/>\n"
                  "    </visual>\n"
                  "  </link>\n",
                  m->name, r / 2, 2 * r, r) < 0
              ? -1
              : 0;
    for (int i = 0; i < LS_N_JOINTS && rc == 0; i++) {
        const ls_dh_t *dh = &m->dh[i];
        char parent[16], child[16];
        if (i == 0) {
            snprintf(parent, sizeof parent, "base_link");
        } else {
            snprintf(parent, sizeof parent, "frame%d", i);
        }
        if (i == LS_N_JOINTS - 1) {
            snprintf(child, sizeof child, "flange");
        } else {
            snprintf(child, sizeof child, "frame%d", i + 1);
        }
        rc |= fprintf(out,
                      "  <joint name=\"joint%d\" type=\"revolute\">\n"
                      "    <parent link=\"%s\"/>\n"
                      "    <child link=\"link%d\"/>\n"
                      "    <origin xyz=\"0 0 0\" rpy=\"0 0 %.17g\"/>\n"
                      "    <axis xyz=\"0 0 1\"/>\n"
                      "    <limit lower=\"%.17g\" upper=\"%.17g\" velocity=\"%.17g\" effort=\"%.17g\"/>\n"
                      "  </joint>\n"
                      "  <link name=\"link%d\">\n"
                      "    <visual>\n"
                      "      <geometry><sphere radius=\"%.17g\"/></geometry>\n"
                      "      <material name=\"joint\"/>\n"
                      "    </visual>\n",
                      i + 1, parent, i + 1, dh->theta_offset_rad, m->q_min_rad[i], m->q_max_rad[i], m->qd_max_rad_s[i],
                      m->torque_max_Nm[i], i + 1, 1.25 * r) < 0
                  ? -1
                  : 0;
        rc |= write_segment(out, r, 0.0, 0.0, 0.0, dh->d_m, 0);
        rc |= write_segment(out, r, 0.0, dh->d_m, dh->a_m, dh->d_m, 1);
        rc |= fprintf(out,
                      "  </link>\n"
                      "  <joint name=\"link%d_dh\" type=\"fixed\">\n"
                      "    <parent link=\"link%d\"/>\n"
                      "    <child link=\"%s\"/>\n"
                      "    <origin xyz=\"%.17g 0 %.17g\" rpy=\"%.17g 0 0\"/>\n"
                      "  </joint>\n"
                      "  <link name=\"%s\"/>\n",
                      i + 1, i + 1, child, dh->a_m, dh->d_m, dh->alpha_rad, child) < 0
                  ? -1
                  : 0;
    }
    if (rc == 0) {
        rc = fprintf(out, "</robot>\n") < 0 ? -1 : 0;
    }
    return rc;
}
