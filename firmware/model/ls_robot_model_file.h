/* A robot model from a file: the arm's DH geometry, joint and Cartesian
 * limits, drive torques and link masses, read from an INI file (inih, the
 * format of landscaped.conf) whose every key is required and carries its
 * unit (docs/deploy.md "Describe your arm" shows the default arm's file,
 * firmware/model/robots/ls-sim6.ini, as the worked example):
 *
 *   [robot]      name, link_radius
 *   [joint.1] .. [joint.6]
 *                a, alpha, d, theta_offset, min, max, max_velocity,
 *                max_acceleration, max_jerk, max_torque, mass
 *   [cartesian]  max_linear_speed, max_angular_speed, max_linear_acceleration,
 *                max_angular_acceleration, max_linear_jerk, max_angular_jerk,
 *                workspace_min, workspace_max
 *
 *   max_velocity = 180 deg/s      a number, a space, its unit
 *   workspace_min = -0.9 -0.9 0 m three numbers, one unit
 *
 * The key table below is the one home of the keys, their units and ranges:
 * the host's `landscape model check` reads it as generated JSON
 * (ls_robot_model keys, host_tools/update_generated.sh) and a test proves that the
 * host and landscaped refuse the same files with the same line.
 *
 * Init-time only: uses stdio and inih (which reads line by line on the
 * stack); never the control loop. The caller owns every buffer. */
#ifndef LS_ROBOT_MODEL_FILE_H
#define LS_ROBOT_MODEL_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "ls_robot_model.h"

/* Load and validate the model file at path into *model. Refuses, with one
 * line in msg naming the file, the line where there is one, the [section]
 * and key, what was given and what is allowed, the first of:
 *   - an unreadable file; a syntax error; a NUL byte or an over-long line;
 *   - an unknown section or key, a key outside a section, a key given twice;
 *   - a value without its unit or with a unit of another quantity, a number
 *     that is not finite decimal text, a value out of its range, a name that
 *     is not 1..31 printable ASCII characters;
 *   - a missing key ("FILE: [joint.3] max_jerk: missing; ...");
 *   - a joint's max not above its min, a workspace_max not above
 *     workspace_min on some axis;
 *   - a geometry no closed-form IK class fits (ls_kin_classify's reason).
 * On LS_OK *model is filled completely, its ik_class chosen. Returns LS_OK
 * or LS_EINVAL (msg says why); *model is untouched on error. msg may be
 * NULL with msglen 0. */
int ls_robot_model_load(const char *path, ls_robot_model_t *model, char *msg, size_t msglen);

/* The quantity of a key: which units its value may carry. */
typedef enum {
    LS_MQ_NAME,     /* text, no unit */
    LS_MQ_LENGTH,   /* m, mm */
    LS_MQ_ANGLE,    /* deg, rad */
    LS_MQ_ANG_VEL,  /* rad/s, deg/s */
    LS_MQ_ANG_ACC,  /* rad/s^2, deg/s^2 */
    LS_MQ_ANG_JERK, /* rad/s^3, deg/s^3 */
    LS_MQ_LIN_VEL,  /* m/s, mm/s */
    LS_MQ_LIN_ACC,  /* m/s^2, mm/s^2 */
    LS_MQ_LIN_JERK, /* m/s^3, mm/s^3 */
    LS_MQ_TORQUE,   /* Nm */
    LS_MQ_MASS,     /* kg */
    LS_MQ_POINT,    /* three lengths: x y z, one unit (m, mm) */
    LS_MQ_COUNT
} ls_model_quantity_t;

/* One unit: SI value = number * multiply / divide (a division for mm keeps
 * 400 mm exactly 0.4 m). */
typedef struct {
    const char *name; /* "deg", "rad/s^2" */
    double multiply, divide;
} ls_model_unit_t;

typedef struct {
    const char *section; /* "robot", "joint" ([joint.1] .. [joint.6]) or "cartesian" */
    const char *key;     /* "max_velocity" */
    ls_model_quantity_t quantity;
    double min_si, max_si; /* the allowed range in SI units */
    bool min_open;         /* the value must be above min_si, not equal */
    const char *expected;  /* the range as refusals state it ("above 0 up to 100 rad/s") */
    const char *what;      /* one line for docs and --help ("velocity limit") */
} ls_model_key_t;

/* The key table, in file order (every [joint.N] section has the "joint"
 * keys), and the units of a quantity (a NULL name ends the list). Static
 * storage; callable anywhere. */
size_t ls_robot_model_key_count(void);
const ls_model_key_t *ls_robot_model_key(size_t i);
const ls_model_unit_t *ls_robot_model_units(ls_model_quantity_t q);
/* The quantity's name in the JSON and in refusals ("an angle"). */
const char *ls_robot_model_quantity_text(ls_model_quantity_t q);
/* What a refusal of key k says is allowed, after "expected ": "an angle: a
 * number and its unit (deg or rad), -360..360 deg". Truncated to outlen. */
void ls_robot_model_expected_text(const ls_model_key_t *k, char *out, size_t outlen);

#endif
