/* The units of setUnits (seed 3.2.1): what the supervisor's numbers mean.
 * Inside the firmware every value is SI (m, rad, s); the command handlers
 * convert at the wire with these functions.
 *
 * Pure functions: any thread, no state, no allocation, O(1). An enum value
 * outside the schema's range converts with factor NaN (so a caller that did
 * not validate it cannot silently treat it as metres) and is named "unknown". */
#ifndef LS_UNITS_H
#define LS_UNITS_H

#include <stdbool.h>

#include "landscape.pb.h"

/* The units one supervisor session reads and writes in (docs/conformance.md,
 * setUnits: units belong to the session). Every session starts in SI. */
typedef struct {
    ls_LinearUnit linear;
    ls_AngularUnit angular;
} ls_units_t;

/* Metres and radians: the units of a new session and of notices that no
 * session owns. */
#define LS_UNITS_SI ((ls_units_t){ .linear = ls_LinearUnit_METERS, .angular = ls_AngularUnit_RADIANS })

/* Value in unit u -> metres (and the derived m/s, m/s^2 when v is a rate). */
double ls_units_to_si_linear(ls_LinearUnit u, double v);
/* Metres -> unit u. */
double ls_units_from_si_linear(ls_LinearUnit u, double v);
/* Value in unit u -> radians. */
double ls_units_to_si_angular(ls_AngularUnit u, double v);
/* Radians -> unit u. */
double ls_units_from_si_angular(ls_AngularUnit u, double v);

/* "meters", "millimeters", "centimeters", "inches", "feet"; "unknown" otherwise. */
const char *ls_units_linear_name(ls_LinearUnit u);
/* "radians", "degrees"; "unknown" otherwise. */
const char *ls_units_angular_name(ls_AngularUnit u);

/* The symbols for messages: "m", "mm", "cm", "in", "ft"; "rad", "deg";
 * "?" outside the schema. */
const char *ls_units_linear_symbol(ls_LinearUnit u);
const char *ls_units_angular_symbol(ls_AngularUnit u);

/* Whether u is one of the schema's values (nanopb stores any int in an enum field). */
bool ls_units_linear_valid(ls_LinearUnit u);
bool ls_units_angular_valid(ls_AngularUnit u);

/* A pose x y z roll pitch yaw: x y z in the linear unit, r p y in the angular
 * one. `in` and `out` may be the same array. */
void ls_units_pose_to_si(ls_LinearUnit lu, ls_AngularUnit au, const double in[6], double out[6]);
void ls_units_pose_from_si(ls_LinearUnit lu, ls_AngularUnit au, const double in[6], double out[6]);

#endif
