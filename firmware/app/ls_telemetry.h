/* Telemetry fields that saturate instead of wrapping (protocol/landscape.dbc).
 *
 * Each broadcast field has a fixed range; a value outside it (a long tool
 * offset, a pose computed from a fault) is sent as the nearest end of the
 * range with its bit set in TOOL_RPY.tool_saturated, never cast into an
 * integer it does not fit (undefined behaviour in C, a wrapped value on the
 * wire). The ranges come from the DBC's generated *_is_in_phys_range: no
 * second copy here. */
#ifndef LS_TELEMETRY_H
#define LS_TELEMETRY_H

#include <stdint.h>

#include "landscape.h" /* cantools: DBC pack functions */

/* TOOL_POS and TOOL_RPY of the tool tip pose xyzrpy (m, rad) sampled at
 * time_ms. Returns the tool_saturated bits (also set in rpy). */
uint8_t ls_telemetry_tool(const double xyzrpy[6], uint16_t time_ms, struct landscape_tool_pos_t *pos,
                          struct landscape_tool_rpy_t *rpy);

#endif
