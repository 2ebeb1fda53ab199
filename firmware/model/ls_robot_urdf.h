/* The arm as a URDF (robot description XML), written from the loaded
 * ls_robot_model_t: the one geometry source of the firmware and the
 * simulator, so any 3D viewer (Foxglove, RViz) and the host's recorder draw
 * the arm the controller moves. The device sends it (describeRobot,
 * docs/protocol.md "Robot description"); the ls_urdf tool prints it.
 *
 * Frames: `base_link` is the DH base frame. Joint i is a revolute joint
 * `joint<i>` about the z axis of frame i-1 (origin rotated by the DH theta
 * offset, so the URDF joint value equals the firmware's q_i), child
 * `link<i>`; a fixed joint `link<i>_dh` carries Tz(d_i) Tx(a_i) Rx(alpha_i)
 * to frame i (`frame<i>`, the last one is `flange`). So the URDF FK of
 * `flange` equals ls_kin_fk. Joint limits, velocity limits and torque limits
 * come from the model; visuals are cylinders of the model's link radius
 * along each DH segment. Numbers are printed with 17 significant digits
 * (exact round trip of a double); the text is ASCII.
 *
 * Portable: no stdio, no allocation, no state (ls_fmt formats); callable
 * from the dispatcher (comms thread) and from tools, never from the control
 * loop (it formats the whole text, a few hundred microseconds). */
#ifndef LS_ROBOT_URDF_H
#define LS_ROBOT_URDF_H

#include <stddef.h>

#include "ls_robot_model.h"

/* Bytes [offset, offset + cap - 1) of the URDF of m into buf, NUL-terminated
 * (so at most cap - 1 bytes; the same model gives the same text every
 * time, so consecutive windows join into the whole). *total_bytes receives
 * the whole URDF's length. Returns the number of bytes written (0 when
 * offset is at or past the end), or LS_EINVAL when m, buf or total_bytes is
 * NULL or cap is 0 (buf and *total_bytes untouched). Cost: formats the
 * whole URDF whatever the window (about 150 numbers), no allocation. */
int ls_robot_urdf_window(const ls_robot_model_t *m, size_t offset, char *buf, size_t cap, size_t *total_bytes);

#endif
