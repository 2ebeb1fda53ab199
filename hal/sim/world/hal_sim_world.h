/* The simulated world of hal/sim: an ODE model of the 6-DOF arm described by
 * a hal_sim_arm_model_t (plain data the caller fills, e.g. from its robot
 * model), standing on the floor in front of a table, with a 6-axis
 * force/torque sensor and a laser standoff sensor at the wrist, a tool rack
 * with two tools, one simulated DIO unit and a manual jog device, the last two
 * driven from outside the process through a Unix datagram socket.
 *
 * One world per process: the state is static. open() and close() run at
 * init/shutdown and allocate (ODE bodies, joints, geoms, working memory, the
 * socket). Every device operation handed out by the getters below is meant for
 * the control loop: allocation-free and non-blocking (see "Memory" below).
 * The world is not thread-safe: call its operations from one thread at a
 * time (the control loop). If that thread is not the one that called open(),
 * it calls hal_sim_world_attach_thread() once before its first cycle.
 *
 * Frames and units: SI (m, rad, kg, N, Nm, s). The base frame is the ODE world
 * frame: origin on the floor under joint 1, z up, gravity -9.81 m/s^2 along z.
 * Poses as x y z roll pitch yaw use R = Rz(yaw) * Ry(pitch) * Rx(roll).
 *
 * ---------------------------------------------------------------------------
 * The arm
 * ---------------------------------------------------------------------------
 * Link i (1..6) is a rigid body whose frame is DH frame i of the model; joint
 * i is an ODE hinge through the origin of frame i-1 about z_{i-1}. The world is
 * built at q = 0, so the hinge angle is the joint angle q_i (the DH theta
 * offset is already in the built geometry). ODE reports hinge angles in
 * (-pi, pi]; the world unwraps them every step, so joints 4 and 6, whose ranges
 * exceed +-180 deg, read continuous angles.
 * Masses: link i carries model.link_mass_kg[i] with the inertia of a capsule
 * of radius model.link_radius_m between the origins of frames i-1 and i (a
 * sphere when they coincide); ODE needs the centre of mass at the body origin,
 * so each body sits at its capsule's midpoint and keeps its DH frame as a
 * fixed offset.
 *
 * Joint servo (hal_sim_world_step): each hinge is a velocity motor with
 *     target velocity = qd_cmd + KP * (q_cmd - q),   KP = 200 1/s,
 *     max torque      = model.torque_max_Nm,
 * and a motor damping of 2e4 Nm s/rad (hinge CFM = 5e-5), which makes the
 * servo a stiff PD (about 4e6 Nm/rad) rather than an infinitely stiff one, so
 * that pressing into the table gives a finite, penetration-proportional force.
 * The servo never drives a joint past its limit within one step (the target
 * velocity is clamped to reach q_min/q_max exactly); ODE hinge stops at
 * q_min/q_max back this up for joints whose range fits in (-pi, pi) (1, 2, 3, 5).
 * Disabled drives (enable(false)) model brakes: target velocity 0 with a
 * holding torque of 2 * torque_max, so the arm stays put unless overloaded.
 * The arm's enable() switches every joint; hal_sim_world_enable_joint()
 * switches one (a drive per joint, hal/sim/drives: a faulted drive's joint
 * brakes while the others move). A fresh world has every joint braked.
 * Integrator: dWorldStep (the exact Dantzig LCP solver), dt as the caller
 * passes it (1 ms typically); world ERP 0.2, CFM 1e-10.
 *
 * Lockstep (cfg.lockstep): hal_sim_world_step() does NOT advance the physics
 * while the joint command is bit-identical to the one of the previous step,
 * every commanded velocity is 0 and no jog is active: the arm rests exactly
 * where it is. A fresh world starts with the command q = 0, qd = 0 (the built
 * pose). Joint trajectories are then a pure function of the command sequence,
 * whatever the number of idle cycles between host commands. Without lockstep
 * the physics always advances. hal_sim_world_step() returns 1 when it
 * advanced the physics, 0 when lockstep held it, LS_EINVAL for dt outside
 * (0, 0.1] s.
 *
 * ---------------------------------------------------------------------------
 * Environment and contact
 * ---------------------------------------------------------------------------
 * Floor: the plane z = 0. Table: a box, top at z = 0.10, x 0.35..0.85,
 * y -0.40..0.40. Obstacle (cfg.with_obstacle): a 0.10 m cube on the table,
 * centred at x 0.60, y 0.20 (top at z = 0.20).
 * Only link 6 and the tool body collide, and only with the floor, table and
 * obstacle (no self collision). Contacts are soft: a spring-damper of
 * 5e4 N/m and 500 N s/m per touching pair of shapes (shared among the up to 8
 * points ODE reports for a face; ERP/CFM derived from dt each step), so in
 * steady contact the normal force is 5e4 N/m times the penetration.
 * Friction is viscous (ODE force-dependent slip, 1e-3 m/s per N, i.e.
 * 1000 N s/m) capped at mu 0.5 times the normal force (pyramid
 * approximation): with a stiff position-controlled arm, stiction would lock
 * in arbitrary lateral forces, so at rest the sensor reads only the normal
 * push. Commanding the flange 2 mm into the table presses with about 100 N.
 *
 * ---------------------------------------------------------------------------
 * Tool, force sensor, laser
 * ---------------------------------------------------------------------------
 * A tool body hangs on link 6 by an ODE fixed joint: the sensor. With no tool
 * it is the flange plate (0.1 kg, a disc of radius link_radius_m and 5 mm
 * thickness just inside the flange plane, so the flange face is its outer
 * face; tool offset 0). A coupled tool adds its mass (a rod from the flange
 * to the tip) and a 10 mm radius tip sphere whose far point is the tool tip.
 * The tool frame is the flange frame moved by the tool offset.
 *
 * "force_sensor", 6 values Fx Fy Fz Tx Ty Tz (N, Nm), tool frame, torques
 * about the tool tip: the wrench the tool exerts on its surroundings, i.e.
 * minus the external (contact) wrench acting on the tool. Pressing the tip
 * into something along tool +z (the approach direction) reads Fz > 0. It is
 * computed from the fixed joint's dJointFeedback (force and torque the joint
 * applies to the tool body) plus the tool body's own weight m*g, which is the
 * tare: the weight is known from the tool mass and is removed in whatever
 * orientation, so an unloaded tool reads ~0 at rest. Inertial forces of an
 * accelerating tool are not removed (they are small at the tool masses here).
 *
 * "laser_standoff_sensor", 1 value (m): the distance from the tool tip along
 * tool +z to the first floor/table/obstacle surface, range 0.5 m; 0.5 when
 * nothing is hit within range, 0 when the tip is inside an object.
 *
 * Tool rack (flange poses, base frame, tool pointing down, i.e. flange z
 * along -z; both reachable inside the joint limits):
 *     "gripper"  rack flange pose x 0.30 y  0.50 z 0.35, rpy (pi, 0, 0);
 *                offset (0, 0, 0.12, 0, 0, 0); 0.4 kg; tool bit 0 = close
 *     "probe"    rack flange pose x 0.30 y -0.50 z 0.35, rpy (pi, 0, 0);
 *                offset (0, 0, 0.15, 0, 0, 0); 0.2 kg; no tool bits
 *     "none"     the flange plate: offset 0 (tool_offset only)
 * couple(id, true) succeeds when no tool is coupled and the flange is within
 * 2 mm and 2 deg of the tool's rack pose; couple(id, false) when `id` is the
 * coupled tool and the flange is at its rack pose. Otherwise LS_EINVAL and
 * nothing changes. set_bits/get_bits hold the gripper's bit state (no
 * gripper fingers are simulated); bits of a tool without that bit, or with no
 * tool coupled, are LS_EINVAL; uncoupling clears the bits.
 *
 * ---------------------------------------------------------------------------
 * DIO, manual device and the control socket
 * ---------------------------------------------------------------------------
 * DIO: one unit (0); bits 0-15 are inputs, bits 16-31 outputs. read() gives
 * inputs | outputs; write() of a bit outside 16-31, or to a unit other than 0,
 * is LS_EINVAL and changes nothing; a bit in both `on` and `off` ends
 * inactive. Inputs change only through the socket.
 *
 * Control socket protocol (cfg.dio_socket_path; a Unix SOCK_DGRAM socket the
 * world binds at open and unlinks at close; a stale socket file at that path
 * is replaced). One command per datagram, ASCII, fields separated by spaces
 * or tabs, an optional trailing newline, at most 255 bytes:
 *     in <hex-on> <hex-off>    set the input bits in hex-on, then clear those
 *                              in hex-off (hex, optional 0x, bits 0-15 only)
 *     jog <vx> <vy> <vz> <wx> <wy> <wz>
 *                              set the manual twist (tool frame), decimals,
 *                              each clamped to -1..1
 *     jog-stop                 zero the twist
 *     buttons <hex>            set the manual buttons held: HAL_MANUAL_BTN_* bits
 *                              (hal/hal_manual.h; 1 = the enabling switch;
 *                              32 bits taken, the others read as 0)
 *     unplug / plug            the manual device goes away (read: not
 *                              present; twist and buttons zeroed) / comes
 *                              back as a new device (its generation counts up)
 * The socket queue is short (net.unix.max_dgram_qlen, often 10 datagrams): a
 * sender whose messages are not drained blocks, or gets EAGAIN if its socket
 * is non-blocking.
 * Anything else (unknown word, missing or extra field, bad number, bits
 * outside the inputs, over-long datagram) is counted in
 * hal_sim_world_malformed_messages() and ignored. Nothing is answered.
 * Messages take effect when the owner calls the DIO's drain_events(), which
 * reads the pending datagrams (at most 64 per call, so a flood cannot stretch
 * a control cycle) and returns how many changed some state; the
 * DIO's poll_fd() is the socket (readable when a datagram is pending). The
 * manual device's read() returns the state as of the last drain_events().
 *     e.g.  socat - UNIX-SENDTO:/tmp/ls-sim.sock <<< 'in 5 0'
 *
 * ---------------------------------------------------------------------------
 * Memory
 * ---------------------------------------------------------------------------
 * ODE allocates through dAlloc (malloc by default). At open the world
 * reserves 1 MiB of step working memory (dWorldSetStepMemoryReservationPolicy;
 * dWorldStep keeps that arena between steps and only reallocates if a step
 * needs more, which this fixed set of bodies and at most 96 contacts does not),
 * and fills then empties the contact joint group once with its maximum number
 * of contact joints (ODE's joint group is an obstack whose arenas survive
 * dJointGroupEmpty and are reused). No spaces are used: the few collision
 * pairs are tested with dCollide into a stack array. tests/unit/simworld
 * checks with counting allocation hooks that steady-state cycles allocate
 * nothing. The set-point trace (below) allocates its buffer at open.
 *
 * ---------------------------------------------------------------------------
 * Set-point trace (tests only: landscaped --setpoint-trace PATH)
 * ---------------------------------------------------------------------------
 * With cfg.trace.path set, the arm's command() records every accepted call:
 * the world's time and the 6 commanded joint positions, into a buffer of
 * cfg.trace.capacity samples that open() allocates and touches (so the
 * control loop neither allocates nor takes a first-touch page fault). The
 * world's time is the sum of the dt of every hal_sim_world_step() since open,
 * lockstep-held steps included: the control loop's time, one period per
 * cycle, whatever the wall clock did. A full buffer keeps its samples and
 * counts the later ones as dropped (the start of a run is what a test reads).
 * command() does no I/O and takes no lock: the file is written by
 * hal_sim_world_trace_write() after the control loop has stopped.
 * open() creates PATH.tmp (so that an unwritable PATH fails at start, not at
 * exit); the write fills it and renames it to PATH:
 *
 *     # landscaped setpoint trace: rate_hz=1000 samples=N dropped=D
 *     t_s,q1,q2,q3,q4,q5,q6
 *     (N rows: the time in s and the joints in rad, each number as %.17g)
 *
 * rate_hz is cfg.trace.rate_hz (the caller's control rate, for the reader).
 */
#ifndef HAL_SIM_WORLD_H
#define HAL_SIM_WORLD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_arm.h"
#include "hal/hal_dio.h"
#include "hal/hal_manual.h"

#define HAL_SIM_ARM_JOINTS 6

/* One joint and its link in standard Denavit-Hartenberg form. */
typedef struct {
    double a_m, alpha_rad, d_m, theta_offset_rad;
} hal_sim_dh_t;

/* The arm to simulate, as data (copied by open). The simulation needs link 6
 * along z6 (a6 = alpha6 = 0, d6 >= 10 mm), q_min <= 0 <= q_max, torque and
 * mass > 0 per joint and a link radius > 0; open says which one is missing. */
typedef struct {
    const char *name; /* for the arm's name; static storage or NULL */
    uint8_t n_joints; /* HAL_SIM_ARM_JOINTS */
    hal_sim_dh_t dh[HAL_SIM_ARM_JOINTS];
    double q_min_rad[HAL_SIM_ARM_JOINTS], q_max_rad[HAL_SIM_ARM_JOINTS];
    double torque_max_Nm[HAL_SIM_ARM_JOINTS];
    double link_mass_kg[HAL_SIM_ARM_JOINTS]; /* link i moves with joint i */
    double link_radius_m;                    /* capsule radius of every link */
} hal_sim_arm_model_t;

#define HAL_SIM_TRACE_PATH_MAX 255 /* characters of a set-point trace's PATH */

/* The set-point trace (see "Set-point trace" above). */
typedef struct {
    const char *path; /* NULL or "": no trace */
    uint32_t rate_hz; /* the control rate, written in the file's first line (> 0) */
    size_t capacity;  /* samples preallocated at open (> 0) */
} hal_sim_trace_config_t;

typedef struct {
    const hal_sim_arm_model_t *arm; /* copied by open */
    const char *dio_socket_path;    /* NULL: no external control socket */
    bool lockstep;                  /* see "Lockstep" above */
    bool with_obstacle;             /* a box on the table */
    hal_sim_trace_config_t trace;   /* all zero: no set-point trace */
} hal_sim_world_config_t;

/* Whether open() can build this arm (the needs listed above
 * hal_sim_arm_model_t), without building anything: LS_OK, or LS_EINVAL with
 * the reason in msg (msglen may be 0). Init-time; no allocation, no state. */
int hal_sim_world_check_arm(const hal_sim_arm_model_t *arm, char *msg, size_t msglen);

/* Build the world. Init only; allocates. Returns LS_OK, or LS_EINVAL (bad
 * config, world already open, socket path too long or taken by a non-socket,
 * trace path too long or a directory) or LS_EIO (socket/ODE failure, trace
 * buffer or PATH.tmp not made), with a reason in msg (msglen may be 0). */
int hal_sim_world_open(const hal_sim_world_config_t *cfg, char *msg, size_t msglen);

/* ODE keeps per-thread collision data: a control-loop thread other than
 * the one that opened the world calls this once at its start (it allocates).
 * LS_OK, LS_ENODEV when not open, LS_EIO when ODE fails. */
int hal_sim_world_attach_thread(void);

/* Tear everything down (ODE, socket, socket file, the trace's buffer and,
 * when hal_sim_world_trace_write() did not run, its PATH.tmp). Safe when not
 * open. The device handles obtained below become invalid: their close ops do
 * nothing, the world is closed only here. */
void hal_sim_world_close(void);

/* Write the set-point trace recorded since open to its PATH (PATH.tmp, then
 * rename). Shutdown only, once the control loop has stopped: it does file
 * I/O and reads the buffer without a lock. Returns 1 when written, with
 * "N samples (D dropped) written to PATH" in msg; 0 when no trace is
 * configured or it was written already; LS_ENODEV when not open; LS_EIO when
 * writing or renaming failed, with msg naming the file and the cause (the
 * partial PATH.tmp is removed, an earlier PATH is left as it was). */
int hal_sim_world_trace_write(char *msg, size_t msglen);

/* Advance the world by dt_s (0 < dt_s <= 0.1): the joint servo, contacts and
 * one ODE step (see "Lockstep" above). Called by the control loop once per
 * cycle after commanding the arm, drives on or off (brakes). Returns 1 when
 * the physics advanced, 0 when lockstep held it, LS_EINVAL for a bad dt,
 * LS_ENODEV when not open. `self` is ignored (one world per process): the
 * signature is that of a step callback with a context. */
int hal_sim_world_step(void *self, double dt_s);

/* Device handles of the open world (static ops, self = the world). Any
 * thread, any time after open; O(1), no allocation. When the world is not
 * open the handles' operations answer LS_ENODEV. */
void hal_sim_world_get_arm(hal_arm_t *out);
void hal_sim_world_get_dio(hal_dio_t *out);
/* The two sensors above; *count = 2. The array is static. */
const hal_sensor_t *hal_sim_world_sensors(size_t *count);
void hal_sim_world_get_tool(hal_tool_t *out);
void hal_sim_world_get_manual(hal_manual_t *out);

/* Drive (true) or brake (false) one joint, 0..5: the per-joint form of the
 * arm's enable(), which sets all six. Takes effect at the next step. Control
 * loop; O(1). LS_OK, LS_EINVAL for a joint past the last, LS_ENODEV when
 * not open. */
int hal_sim_world_enable_joint(unsigned joint, bool on);

/* The torque (Nm) each joint's hinge applied about its axis in the last
 * step: the servo's motor torque while the joint is driven, the brake's
 * while it is braked (a joint stop's too, when the joint sits on one); the
 * sign is that of q. Zeros before the first step. Control loop; O(joints),
 * no allocation. LS_OK, LS_EINVAL for NULL, LS_ENODEV when not open
 * (tau_Nm untouched on error). */
int hal_sim_world_joint_torque(double tau_Nm[HAL_SIM_ARM_JOINTS]);

/* Ground truth for tests: the flange pose (DH frame 6) as ODE has it,
 * column-major 4x4, base frame. LS_OK or LS_ENODEV. */
int hal_sim_world_flange_pose(double T[16]);

/* Contact since open: *in_contact = link 6 or the tool touched the floor,
 * table or obstacle in the last step; point_m = the first contact point of
 * the first step that had any contact since open (zeros if none). Returns 1
 * when a contact has happened since open, 0 when not, LS_ENODEV when closed. */
int hal_sim_world_contact(bool *in_contact, double point_m[3]);

/* Name of the coupled tool ("gripper", "probe") or "none". Never NULL. */
const char *hal_sim_world_current_tool(void);

/* Control-socket messages ignored as malformed since open. */
uint32_t hal_sim_world_malformed_messages(void);

#endif
