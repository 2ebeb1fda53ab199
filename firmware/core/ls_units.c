/* Conversions of setUnits. The names, symbols and factors are the schema's
 * (protocol/landscape.proto enum LinearUnit, AngularUnit; ls_cmd_table.c
 * has them as generated tables). */
#include "ls_units.h"

#include <math.h>

#include "ls_cmd_table.h"

/* Metres (radians) per unit, the schema's (ls.si_per_unit); NaN for a value
 * outside the schema. */
static double linear_factor(ls_LinearUnit u)
{
    const ls_unit_desc_t *d = ls_linear_unit(u);
    return d != NULL ? d->si_per_unit : NAN;
}

static double angular_factor(ls_AngularUnit u)
{
    const ls_unit_desc_t *d = ls_angular_unit(u);
    return d != NULL ? d->si_per_unit : NAN;
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
    const ls_unit_desc_t *d = ls_linear_unit(u);
    return d != NULL ? d->text : "unknown";
}

const char *ls_units_angular_name(ls_AngularUnit u)
{
    const ls_unit_desc_t *d = ls_angular_unit(u);
    return d != NULL ? d->text : "unknown";
}

const char *ls_units_linear_symbol(ls_LinearUnit u)
{
    const ls_unit_desc_t *d = ls_linear_unit(u);
    return d != NULL ? d->symbol : "?";
}

const char *ls_units_angular_symbol(ls_AngularUnit u)
{
    const ls_unit_desc_t *d = ls_angular_unit(u);
    return d != NULL ? d->symbol : "?";
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
