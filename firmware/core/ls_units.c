/* Conversion factors of setUnits. Exact by definition (inch = 25.4 mm,
 * foot = 12 inches, degree = pi/180). */
#include "ls_units.h"

#include <math.h>

#include "ls_math.h"

/* Metres per unit; NaN for a value outside the schema. */
static double linear_factor(ls_LinearUnit u)
{
    switch (u) {
    case ls_LinearUnit_METERS: return 1.0;
    case ls_LinearUnit_MILLIMETERS: return 0.001;
    case ls_LinearUnit_CENTIMETERS: return 0.01;
    case ls_LinearUnit_INCHES: return 0.0254;
    case ls_LinearUnit_FEET: return 0.3048;
    }
    return NAN;
}

static double angular_factor(ls_AngularUnit u)
{
    switch (u) {
    case ls_AngularUnit_RADIANS: return 1.0;
    case ls_AngularUnit_DEGREES: return LS_PI / 180.0;
    }
    return NAN;
}

double ls_units_to_si_linear(ls_LinearUnit u, double v)
{
    return v * linear_factor(u);
}

double ls_units_from_si_linear(ls_LinearUnit u, double v)
{
    return v / linear_factor(u);
}

double ls_units_to_si_angular(ls_AngularUnit u, double v)
{
    return v * angular_factor(u);
}

double ls_units_from_si_angular(ls_AngularUnit u, double v)
{
    return v / angular_factor(u);
}

const char *ls_units_linear_name(ls_LinearUnit u)
{
    switch (u) {
    case ls_LinearUnit_METERS: return "meters";
    case ls_LinearUnit_MILLIMETERS: return "millimeters";
    case ls_LinearUnit_CENTIMETERS: return "centimeters";
    case ls_LinearUnit_INCHES: return "inches";
    case ls_LinearUnit_FEET: return "feet";
    }
    return "unknown";
}

const char *ls_units_angular_name(ls_AngularUnit u)
{
    switch (u) {
    case ls_AngularUnit_RADIANS: return "radians";
    case ls_AngularUnit_DEGREES: return "degrees";
    }
    return "unknown";
}

const char *ls_units_linear_symbol(ls_LinearUnit u)
{
    switch (u) {
    case ls_LinearUnit_METERS: return "m";
    case ls_LinearUnit_MILLIMETERS: return "mm";
    case ls_LinearUnit_CENTIMETERS: return "cm";
    case ls_LinearUnit_INCHES: return "in";
    case ls_LinearUnit_FEET: return "ft";
    }
    return "?";
}

const char *ls_units_angular_symbol(ls_AngularUnit u)
{
    switch (u) {
    case ls_AngularUnit_RADIANS: return "rad";
    case ls_AngularUnit_DEGREES: return "deg";
    }
    return "?";
}

bool ls_units_linear_valid(ls_LinearUnit u)
{
    return !isnan(linear_factor(u));
}

bool ls_units_angular_valid(ls_AngularUnit u)
{
    return !isnan(angular_factor(u));
}

void ls_units_pose_to_si(ls_LinearUnit lu, ls_AngularUnit au, const double in[6], double out[6])
{
    for (int i = 0; i < 3; i++) {
        out[i] = ls_units_to_si_linear(lu, in[i]);
        out[i + 3] = ls_units_to_si_angular(au, in[i + 3]);
    }
}

void ls_units_pose_from_si(ls_LinearUnit lu, ls_AngularUnit au, const double in[6], double out[6])
{
    for (int i = 0; i < 3; i++) {
        out[i] = ls_units_from_si_linear(lu, in[i]);
        out[i + 3] = ls_units_from_si_angular(au, in[i + 3]);
    }
}
