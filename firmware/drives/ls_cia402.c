/* One CiA 402 axis: states from the statusword, the controlword stepper,
 * the position and velocity scaling. Contracts in ls_cia402.h. */
#include "ls_cia402.h"

#include <math.h>

#include "ls_canopen.h"
#include "ls_fmt.h"

/* ---- States ------------------------------------------------------------ */

ls_402_state_t ls_402_state(uint16_t statusword)
{
    switch (statusword & LS_CO_SW_STATE_MASK_SHORT) {
    case LS_CO_SW_NOT_READY: return LS_402_NOT_READY_TO_SWITCH_ON;
    case LS_CO_SW_SWITCH_ON_DISABLED_STATE: return LS_402_SWITCH_ON_DISABLED;
    case LS_CO_SW_FAULT_REACTION_STATE: return LS_402_FAULT_REACTION_ACTIVE;
    case LS_CO_SW_FAULT_STATE: return LS_402_FAULT;
    default: break;
    }
    switch (statusword & LS_CO_SW_STATE_MASK_LONG) {
    case LS_CO_SW_READY_STATE: return LS_402_READY_TO_SWITCH_ON;
    case LS_CO_SW_SWITCHED_ON_STATE: return LS_402_SWITCHED_ON;
    case LS_CO_SW_ENABLED_STATE: return LS_402_OPERATION_ENABLED;
    case LS_CO_SW_QUICK_STOP_STATE: return LS_402_QUICK_STOP_ACTIVE;
    default: return LS_402_UNKNOWN;
    }
}

const char *ls_402_state_name(ls_402_state_t state)
{
    switch (state) {
    case LS_402_NOT_READY_TO_SWITCH_ON: return "NOT READY TO SWITCH ON";
    case LS_402_SWITCH_ON_DISABLED: return "SWITCH ON DISABLED";
    case LS_402_READY_TO_SWITCH_ON: return "READY TO SWITCH ON";
    case LS_402_SWITCHED_ON: return "SWITCHED ON";
    case LS_402_OPERATION_ENABLED: return "OPERATION ENABLED";
    case LS_402_QUICK_STOP_ACTIVE: return "QUICK STOP ACTIVE";
    case LS_402_FAULT_REACTION_ACTIVE: return "FAULT REACTION ACTIVE";
    case LS_402_FAULT: return "FAULT";
    case LS_402_UNKNOWN:
    case LS_402_STATE_COUNT:
    default: return "UNKNOWN";
    }
}

/* The bits a device control command is made of (CiA 402 table 36). */
#define CW_COMMAND_BITS                                                                                                \
    (LS_CO_CW_SWITCH_ON | LS_CO_CW_ENABLE_VOLTAGE | LS_CO_CW_QUICK_STOP | LS_CO_CW_ENABLE_OPERATION |                  \
     LS_CO_CW_FAULT_RESET)

const char *ls_402_command_name(uint16_t controlword)
{
    switch (controlword & CW_COMMAND_BITS) {
    case LS_CO_CW_CMD_SHUTDOWN: return "shutdown";
    case LS_CO_CW_CMD_SWITCH_ON: return "switch on";
    case LS_CO_CW_CMD_ENABLE_OPERATION: return "enable operation";
    case LS_CO_CW_CMD_DISABLE_VOLTAGE: return "disable voltage";
    case LS_CO_CW_CMD_QUICK_STOP: return "quick stop";
    case LS_CO_CW_FAULT_RESET: return "fault reset";
    default: return "controlword";
    }
}

/* ---- Stepper ----------------------------------------------------------- */

void ls_402_default_config(ls_402_config_t *cfg, uint32_t cycle_us)
{
    if (cfg == NULL) {
        return;
    }
    const uint64_t timeout_us = (uint64_t)LS_402_STEP_TIMEOUT_MS * 1000u;
    const uint64_t cycle = cycle_us > 0u ? cycle_us : 1000u;
    uint64_t cycles = (timeout_us + cycle - 1u) / cycle;
    cfg->step_timeout_cycles = cycles > 0u ? (uint32_t)cycles : 1u;
    cfg->fault_reset_edges = (uint8_t)LS_402_FAULT_RESET_EDGES;
}

int ls_402_init(ls_402_axis_t *ax, const ls_402_config_t *cfg)
{
    ls_402_config_t c;
    if (cfg != NULL) {
        c = *cfg;
    } else {
        ls_402_default_config(&c, 1000u);
    }
    if (ax == NULL || c.step_timeout_cycles == 0u || c.fault_reset_edges == 0u) {
        return LS_EINVAL;
    }
    *ax = (ls_402_axis_t){ 0 };
    ax->cfg = c;
    ax->cw = LS_CO_CW_CMD_DISABLE_VOLTAGE;
    ax->bit7_low_sent = false; /* the drive may still hold bit 7 high from before */
    ax->state = LS_402_UNKNOWN;
    ax->want = LS_402_WANT_DISABLED;
    return LS_OK;
}

/* The command that moves state `s` one transition toward `want` (or holds
 * it there), for every state but FAULT. */
static uint16_t command_for(ls_402_state_t s, ls_402_want_t want, bool *at_target)
{
    *at_target = false;
    switch (s) {
    case LS_402_SWITCH_ON_DISABLED:
        if (want == LS_402_WANT_ENABLED) {
            return LS_CO_CW_CMD_SHUTDOWN;
        }
        *at_target = true;
        return want == LS_402_WANT_QUICK_STOP ? LS_CO_CW_CMD_QUICK_STOP : LS_CO_CW_CMD_DISABLE_VOLTAGE;
    case LS_402_READY_TO_SWITCH_ON:
        if (want == LS_402_WANT_ENABLED) {
            return LS_CO_CW_CMD_SWITCH_ON;
        }
        if (want == LS_402_WANT_QUICK_STOP) {
            return LS_CO_CW_CMD_QUICK_STOP;
        }
        *at_target = true;
        return LS_CO_CW_CMD_SHUTDOWN;
    case LS_402_SWITCHED_ON:
        if (want == LS_402_WANT_ENABLED) {
            return LS_CO_CW_CMD_ENABLE_OPERATION;
        }
        return want == LS_402_WANT_QUICK_STOP ? LS_CO_CW_CMD_QUICK_STOP : LS_CO_CW_CMD_SHUTDOWN;
    case LS_402_OPERATION_ENABLED:
        if (want == LS_402_WANT_ENABLED) {
            *at_target = true;
            return LS_CO_CW_CMD_ENABLE_OPERATION;
        }
        return want == LS_402_WANT_QUICK_STOP ? LS_CO_CW_CMD_QUICK_STOP : LS_CO_CW_CMD_SHUTDOWN;
    case LS_402_QUICK_STOP_ACTIVE:
        if (want == LS_402_WANT_QUICK_STOP) {
            *at_target = true;
            return LS_CO_CW_CMD_QUICK_STOP;
        }
        /* Transition 12 works whatever the drive's quick stop option code;
         * 16 (straight back to ENABLED) only with codes 5-8. */
        return LS_CO_CW_CMD_DISABLE_VOLTAGE;
    case LS_402_NOT_READY_TO_SWITCH_ON:
    case LS_402_FAULT_REACTION_ACTIVE:
    case LS_402_FAULT:
    case LS_402_UNKNOWN:
    case LS_402_STATE_COUNT:
    default: return LS_CO_CW_CMD_DISABLE_VOLTAGE; /* the drive moves by itself; keep bit 7 low */
    }
}

/* FAULT: the reset edge when allowed. An edge is a controlword with bit 7
 * set after one with bit 7 clear; it is held high while the drive gets
 * step_timeout_cycles to leave FAULT, then dropped for a cycle before the
 * next edge. */
static uint16_t fault_command(ls_402_axis_t *ax, bool allowed)
{
    if (!allowed || ax->error == LS_402_STAYS_IN_FAULT) {
        return LS_CO_CW_CMD_DISABLE_VOLTAGE;
    }
    if ((ax->cw & LS_CO_CW_FAULT_RESET) != 0u) {
        if (ax->cycles_since_edge < ax->cfg.step_timeout_cycles) {
            ax->cycles_since_edge++;
            return LS_CO_CW_FAULT_RESET;
        }
        return LS_CO_CW_CMD_DISABLE_VOLTAGE;
    }
    if (!ax->bit7_low_sent) {
        return LS_CO_CW_CMD_DISABLE_VOLTAGE;
    }
    if (ax->edges < ax->cfg.fault_reset_edges) {
        ax->edges++;
        ax->cycles_since_edge = 0u;
        return LS_CO_CW_FAULT_RESET;
    }
    ax->error = LS_402_STAYS_IN_FAULT;
    ax->stuck_in = LS_402_FAULT;
    ax->stuck_command = LS_CO_CW_FAULT_RESET;
    return LS_CO_CW_CMD_DISABLE_VOLTAGE;
}

int ls_402_step(ls_402_axis_t *ax, uint16_t statusword, ls_402_want_t want, bool fault_reset_allowed, ls_402_out_t *out)
{
    if (ax == NULL || out == NULL || (unsigned)want >= (unsigned)LS_402_WANT_COUNT) {
        return LS_EINVAL;
    }
    const ls_402_state_t s = ls_402_state(statusword);
    const bool rearm = want != ax->want || (fault_reset_allowed && !ax->reset_allowed);
    ax->want = want;
    ax->reset_allowed = fault_reset_allowed;
    if (rearm) {
        ax->error = LS_402_OK;
        ax->edges = 0u;
        ax->cycles_in_state = 0u;
    }
    if (s != ax->state) {
        ax->state = s;
        ax->cycles_in_state = 0u;
    } else if (!rearm && ax->cycles_in_state < UINT32_MAX) {
        ax->cycles_in_state++;
    }

    bool at_target = false;
    uint16_t cw;
    if (s == LS_402_FAULT) {
        cw = fault_command(ax, fault_reset_allowed);
    } else {
        cw = command_for(s, want, &at_target);
        if (at_target) {
            ax->edges = 0u;
            ax->error = LS_402_OK;
        } else if (ax->error == LS_402_OK && ax->cycles_in_state >= ax->cfg.step_timeout_cycles) {
            ax->error = LS_402_STUCK;
            ax->stuck_in = s;
            ax->stuck_command = cw;
        }
    }
    ax->cw = cw;
    if ((cw & LS_CO_CW_FAULT_RESET) == 0u) {
        ax->bit7_low_sent = true;
    } else {
        ax->bit7_low_sent = false;
    }

    const bool enabled = s == LS_402_OPERATION_ENABLED;
    *out = (ls_402_out_t){
        .controlword = cw,
        .statusword = statusword,
        .state = s,
        .enabled = enabled,
        .at_target = at_target,
        .fault = (statusword & LS_CO_SW_FAULT) != 0u,
        .warning = (statusword & LS_CO_SW_WARNING) != 0u,
        .remote = (statusword & LS_CO_SW_REMOTE) != 0u,
        .following_error = enabled && (statusword & LS_CO_SW_OMS13) != 0u,
        .target_ignored = enabled && (statusword & LS_CO_SW_OMS12) == 0u,
        .error = ax->error,
        .stuck_in = ax->error != LS_402_OK ? ax->stuck_in : LS_402_UNKNOWN,
        .stuck_command = ax->error != LS_402_OK ? ax->stuck_command : 0u,
        .timeout_cycles = ax->cfg.step_timeout_cycles,
        .reset_edges_sent = ax->edges,
    };
    return LS_OK;
}

int ls_402_describe(const ls_402_out_t *out, char *buf, size_t cap)
{
    if (out == NULL || buf == NULL || cap == 0u) {
        return LS_EINVAL;
    }
    size_t len = 0u;
    buf[0] = '\0';
    switch (out->error) {
    case LS_402_STUCK:
        if (out->stuck_in == LS_402_NOT_READY_TO_SWITCH_ON || out->stuck_in == LS_402_FAULT_REACTION_ACTIVE) {
            ls_fmt_append(buf, cap, &len, "stuck in %s: not left by itself within %lu cycles",
                          ls_402_state_name(out->stuck_in), (unsigned long)out->timeout_cycles);
        } else if (out->stuck_in == LS_402_UNKNOWN) {
            ls_fmt_append(buf, cap, &len, "the statusword shows no CiA 402 state for %lu cycles",
                          (unsigned long)out->timeout_cycles);
        } else {
            ls_fmt_append(buf, cap, &len, "stuck in %s: %s (0x%04X) not followed within %lu cycles",
                          ls_402_state_name(out->stuck_in), ls_402_command_name(out->stuck_command),
                          (unsigned)out->stuck_command, (unsigned long)out->timeout_cycles);
        }
        break;
    case LS_402_STAYS_IN_FAULT:
        ls_fmt_append(buf, cap, &len, "stays in FAULT after %u fault resets", (unsigned)out->reset_edges_sent);
        break;
    case LS_402_OK:
    default:
        ls_fmt_append(buf, cap, &len, "%s", ls_402_state_name(out->state));
        if (out->warning) {
            ls_fmt_append(buf, cap, &len, ", warning");
        }
        if (out->following_error) {
            ls_fmt_append(buf, cap, &len, ", following error");
        }
        if (out->target_ignored) {
            ls_fmt_append(buf, cap, &len, ", target ignored");
        }
        break;
    }
    ls_fmt_append(buf, cap, &len, " (statusword 0x%04X)", (unsigned)out->statusword);
    if (!out->remote) {
        ls_fmt_append(buf, cap, &len, "; the drive is under local control (statusword bit 9 = 0)");
    }
    return (int)len;
}

/* ---- Scaling ----------------------------------------------------------- */

#define TWO_POW_31 2147483648.0

int ls_402_scale_init(ls_402_scale_t *s, double counts_per_rad, int sign, double zero_offset_rad,
                      double vel_counts_per_rad)
{
    if (s == NULL || !isfinite(counts_per_rad) || !(counts_per_rad > 0.0) || (sign != 1 && sign != -1) ||
        !isfinite(zero_offset_rad) || !isfinite(vel_counts_per_rad) || vel_counts_per_rad < 0.0) {
        return LS_EINVAL;
    }
    s->counts_per_rad = counts_per_rad;
    s->vel_counts_per_rad = vel_counts_per_rad > 0.0 ? vel_counts_per_rad : counts_per_rad;
    s->zero_offset_rad = zero_offset_rad;
    s->sign = sign;
    return LS_OK;
}

/* The int32 with the same low 32 bits (two's complement), without an
 * implementation-defined conversion. */
static int32_t wrap32(uint64_t v)
{
    const uint32_t u = (uint32_t)v;
    if (u <= (uint32_t)INT32_MAX) {
        return (int32_t)u;
    }
    return (int32_t)(u - 0x80000000u) + INT32_MIN;
}

void ls_402_unwrap_reset(ls_402_unwrap_t *u)
{
    if (u != NULL) {
        *u = (ls_402_unwrap_t){ 0 };
    }
}

int64_t ls_402_unwrap(ls_402_unwrap_t *u, int32_t raw)
{
    if (!u->primed) {
        u->count = raw;
        u->primed = true;
    } else {
        /* The step modulo 2^32, as a signed number: it crosses the wrap
         * the short way. */
        const int32_t step = wrap32((uint64_t)(uint32_t)raw - (uint64_t)(uint32_t)u->raw);
        u->count += step;
    }
    u->raw = raw;
    return u->count;
}

double ls_402_pos_rad(const ls_402_scale_t *s, int64_t count)
{
    return s->zero_offset_rad + (double)s->sign * (double)count / s->counts_per_rad;
}

int ls_402_target_raw(const ls_402_scale_t *s, const ls_402_unwrap_t *u, double q_rad, int32_t *raw)
{
    if (s == NULL || u == NULL || raw == NULL || !isfinite(q_rad) || !u->primed) {
        return LS_EINVAL;
    }
    /* Relative to the last reading, so that the rounding works on small
     * numbers and the distance check is direct. */
    const double counts = (q_rad - s->zero_offset_rad) * (double)s->sign * s->counts_per_rad;
    const double rel = counts - (double)u->count;
    if (!(fabs(rel) < TWO_POW_31 - 0.5)) {
        return LS_ERANGE;
    }
    const int64_t step = llround(rel);
    *raw = wrap32((uint64_t)u->count + (uint64_t)step);
    return LS_OK;
}

int ls_402_vel_raw(const ls_402_scale_t *s, double v_rad_s, int32_t *raw)
{
    if (s == NULL || raw == NULL || !isfinite(v_rad_s)) {
        return LS_EINVAL;
    }
    const double v = (double)s->sign * v_rad_s * s->vel_counts_per_rad;
    if (!(fabs(v) < TWO_POW_31 - 0.5)) {
        return LS_ERANGE;
    }
    *raw = (int32_t)lround(v);
    return LS_OK;
}

double ls_402_vel_rad_s(const ls_402_scale_t *s, int32_t raw)
{
    return (double)raw / ((double)s->sign * s->vel_counts_per_rad);
}
