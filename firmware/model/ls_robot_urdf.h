/* The arm as a URDF (robot description XML), written from ls_robot_model_t:
 * the one geometry source of the firmware and the simulator, so any 3D
 * viewer (Foxglove, RViz) and the host's recorder draw the arm the
 * controller moves. Init/tool code only: uses stdio, never the control loop.
 *
 * Frames: `base_link` is the DH base frame. Joint i is a revolute joint
 * `joint<i>` about the z axis of frame i-1 (origin rotated by the DH theta
 * offset, so the URDF joint value equals the firmware's q_i), child
 * `link<i>`; a fixed joint `link<i>_dh` carries Tz(d_i) Tx(a_i) Rx(alpha_i)
 * to frame i (`frame<i>`, the last one is `flange`). So the URDF FK of
 * `flange` equals ls_kin_fk. Joint limits, velocity limits and torque limits
 * come from the model; visuals are cylinders of the simulation's link
 * radius along each DH segment. Numbers are printed with 17 significant
 * digits (exact round trip of a double). */
#ifndef LS_ROBOT_URDF_H
#define LS_ROBOT_URDF_H

#include <stdio.h>

#include "ls_robot_model.h"

/* Writes the URDF of m to out. Returns 0, or -1 when a write failed (errno
 * as set by stdio) or m or out is NULL. */
int ls_robot_urdf_write(const ls_robot_model_t *m, FILE *out);

#endif
