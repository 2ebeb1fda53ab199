/* Saturating telemetry fields: see ls_telemetry.h. */
#include "ls_telemetry.h"

#include <stddef.h>

typedef struct {
    bool (*in_range)(double);
    int16_t (*encode)(double);
} field16_t;

static const field16_t k_tool[6] = {
    { landscape_tool_pos_tool_x_is_in_phys_range, landscape_tool_pos_tool_x_encode },
    { landscape_tool_pos_tool_y_is_in_phys_range, landscape_tool_pos_tool_y_encode },
    { landscape_tool_pos_tool_z_is_in_phys_range, landscape_tool_pos_tool_z_encode },
    { landscape_tool_rpy_tool_roll_is_in_phys_range, landscape_tool_rpy_tool_roll_encode },
    { landscape_tool_rpy_tool_pitch_is_in_phys_range, landscape_tool_rpy_tool_pitch_encode },
    { landscape_tool_rpy_tool_yaw_is_in_phys_range, landscape_tool_rpy_tool_yaw_encode },
};

/* The raw value of v, or the nearest end of the 16-bit raw range, which the
 * DBC's physical range spans (NaN: the low end). */
static int16_t saturate(const field16_t *f, double v, uint8_t bit, uint8_t *flags)
{
    if (f->in_range(v)) {
        return f->encode(v);
    }
    *flags = (uint8_t)(*flags | bit);
    return v > 0.0 ? INT16_MAX : INT16_MIN;
}

uint8_t ls_telemetry_tool(const double xyzrpy[6], uint16_t time_ms, struct landscape_tool_pos_t *pos,
                          struct landscape_tool_rpy_t *rpy)
{
    uint8_t flags = 0;
    int16_t raw[6];
    for (size_t i = 0; i < 6; i++) {
        raw[i] = saturate(&k_tool[i], xyzrpy[i], (uint8_t)(1u << i), &flags);
    }
    pos->tool_x = raw[0];
    pos->tool_y = raw[1];
    pos->tool_z = raw[2];
    pos->tool_time_ms = time_ms;
    rpy->tool_roll = raw[3];
    rpy->tool_pitch = raw[4];
    rpy->tool_yaw = raw[5];
    rpy->tool_saturated = flags;
    return flags;
}
