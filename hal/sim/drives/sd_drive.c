/* The CiA 402 side of a simulated drive (sd_node.h): the power state
 * machine, modes (CSP, homing), interpolation, following error, quick stop,
 * brake and safe torque off. hal_sim_drives.h describes what a master sees;
 * this file explains only the choices that are not the standard's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sd_node.h"

enum { SD_HM_IDLE, SD_HM_ATTAINED, SD_HM_ERROR };

#define PER_MILLE 1000.0
#define SD_TEMPERATURE_REST 300     /* 0x2100:03 at rest: 30.0 degrees Celsius (the EDS's default) */
#define SD_TEMPERATURE_PER_MILLE 4L /* per mille of the maximum torque per 0.1 degree */

static int64_t V(const sd_node_t *n, int entry)
{
    return entry >= 0 ? n->od.val[entry] : 0;
}

/* uint32 -> int32 by the two's complement, without implementation-defined
 * conversions. */
static int32_t as_i32(uint32_t u)
{
    return u < 0x80000000u ? (int32_t)u : -(int32_t)(~u) - 1;
}

static int32_t clamp_i32(double x)
{
    if (!(x > -2147483648.0)) {
        return INT32_MIN;
    }
    if (!(x < 2147483647.0)) {
        return INT32_MAX;
    }
    return (int32_t)lround(x);
}

/* The encoder count of q without homing, as a 32-bit counter. */
static uint32_t encoder(const sd_node_t *n, double q_rad)
{
    return (uint32_t)(int64_t)llround(q_rad * n->cfg.counts_per_rad) + (uint32_t)n->cfg.position_offset_counts;
}

int32_t sd_drive_counts(const sd_node_t *n, double q_rad)
{
    return as_i32(encoder(n, q_rad) + n->drv.home_shift);
}

/* Counts are read relative to the joint's zero within +-2^31 counts (far
 * beyond any joint's range), so a target across the counter's wrap maps to
 * the angle next to it. */
double sd_drive_rad(const sd_node_t *n, int32_t counts)
{
    uint32_t u = (uint32_t)counts - (uint32_t)n->cfg.position_offset_counts - n->drv.home_shift;
    return (double)as_i32(u) / n->cfg.counts_per_rad;
}

static bool power_on(const sd_node_t *n)
{
    return n->drv.state == SD_DS_OPERATION_ENABLED || n->drv.state == SD_DS_QUICK_STOP;
}

static int8_t mode_display(const sd_node_t *n)
{
    return (int8_t)V(n, n->e.modes_display);
}

static uint16_t statusword(const sd_node_t *n)
{
    const sd_drive_t *d = &n->drv;
    uint16_t sw = LS_CO_SW_REMOTE;
    switch (d->state) {
    case SD_DS_NOT_READY: sw |= LS_CO_SW_NOT_READY; break;
    case SD_DS_SWITCH_ON_DISABLED: sw |= LS_CO_SW_SWITCH_ON_DISABLED_STATE; break;
    case SD_DS_READY: sw |= LS_CO_SW_READY_STATE; break;
    case SD_DS_SWITCHED_ON: sw |= LS_CO_SW_SWITCHED_ON_STATE | LS_CO_SW_VOLTAGE_ENABLED; break;
    case SD_DS_OPERATION_ENABLED: sw |= LS_CO_SW_ENABLED_STATE | LS_CO_SW_VOLTAGE_ENABLED; break;
    case SD_DS_QUICK_STOP: sw |= LS_CO_SW_QUICK_STOP_STATE | LS_CO_SW_VOLTAGE_ENABLED; break;
    case SD_DS_FAULT_REACTION: sw |= LS_CO_SW_FAULT_REACTION_STATE; break;
    case SD_DS_FAULT: sw |= LS_CO_SW_FAULT_STATE; break;
    }
    if (d->sto) {
        sw |= LS_CO_SW_WARNING;
    }
    int8_t mode = mode_display(n);
    if (mode == LS_CO_MODE_CSP) {
        if (d->state == SD_DS_OPERATION_ENABLED) {
            sw |= LS_CO_SW_OMS12; /* the drive follows the target */
        }
        if (d->limited) {
            sw |= LS_CO_SW_INTERNAL_LIMIT;
        }
        if (d->following_error) {
            sw |= LS_CO_SW_OMS13;
        }
    } else if (mode == LS_CO_MODE_HM) {
        /* CiA 402: 10 alone = not started (or interrupted), 10 + 12 =
         * attained at the target, 10 + 13 = error at standstill. */
        sw |= LS_CO_SW_TARGET_REACHED;
        sw |= d->homing == SD_HM_ATTAINED ? LS_CO_SW_OMS12 : d->homing == SD_HM_ERROR ? LS_CO_SW_OMS13 : 0u;
    }
    return sw;
}

static void set(sd_node_t *n, int entry, int64_t v)
{
    if (entry >= 0) {
        n->od.val[entry] = v;
    }
}

void sd_drive_refresh(sd_node_t *n)
{
    const sd_drive_t *d = &n->drv;
    bool on = power_on(n);
    set(n, n->e.sw, statusword(n));
    set(n, n->e.pos_actual, sd_drive_counts(n, d->fb.q_rad));
    set(n, n->e.vel_actual, clamp_i32(d->fb.qd_rad_s * n->cfg.counts_per_rad));
    /* The motor's torque: nothing while the brake holds the joint. */
    int32_t per_mille = clamp_i32(d->fb.tau_Nm / n->cfg.torque_max_Nm * PER_MILLE);
    set(n, n->e.torque_actual,
        on ? (per_mille > INT16_MAX   ? INT16_MAX
              : per_mille < INT16_MIN ? INT16_MIN
                                      : per_mille)
           : 0);
    set(n, n->e.fe_actual, on ? clamp_i32((d->q_cmd - d->fb.q_rad) * n->cfg.counts_per_rad) : 0);
    set(n, n->e.error_code, n->fault_code);
    set(n, n->e.error_register, sd_node_error_register(n));
    set(n, n->e.brake, on ? 0 : 1);
    set(n, n->e.sto, d->sto ? 1 : 0);
    /* 30.0 degrees at rest, warmer with the torque given (0.1 degree units). */
    set(n, n->e.temperature, SD_TEMPERATURE_REST + (on ? labs((long)per_mille) / SD_TEMPERATURE_PER_MILLE : 0));
}

/* Hold the joint where it is (entering OPERATION ENABLED, a mode change):
 * the drive never jumps on its own, only on a target. */
static void hold_here(sd_node_t *n, double q_rad)
{
    sd_drive_t *d = &n->drv;
    d->q_cmd = d->seg_q0 = d->seg_q1 = q_rad;
    d->qd_cmd = d->seg_ff = 0.0;
    d->seg_t = d->seg_T = sd_node_period_s(n);
}

void sd_drive_reset(sd_node_t *n)
{
    sd_drive_t *d = &n->drv;
    sd_joint_fb_t fb = d->fb;
    bool sto = d->sto;
    memset(d, 0, sizeof *d);
    d->fb = fb;
    d->sto = sto;                        /* an input, not a setting */
    d->state = SD_DS_SWITCH_ON_DISABLED; /* NOT READY TO SWITCH ON passes at once */
    hold_here(n, fb.q_rad);
}

static void enter(sd_node_t *n, sd_ds_t state)
{
    sd_drive_t *d = &n->drv;
    if (state == SD_DS_OPERATION_ENABLED && d->state != SD_DS_QUICK_STOP) {
        hold_here(n, d->fb.q_rad);
        d->fe_time_s = 0.0;
    } else if (state == SD_DS_OPERATION_ENABLED) {
        hold_here(n, d->q_cmd); /* transition 16: resume where the ramp stopped */
    }
    d->state = state;
}

static int64_t qs_option(const sd_node_t *n)
{
    return V(n, n->e.qs_option);
}

/* The ramp's end: stay (options 5-8) or drop to SWITCH ON DISABLED. */
static void quick_stop_done(sd_node_t *n)
{
    int64_t opt = qs_option(n);
    if (opt < LS_CO_QS_STAY_MIN || opt > LS_CO_QS_STAY_MAX) {
        enter(n, SD_DS_SWITCH_ON_DISABLED);
    } else {
        n->drv.qd_cmd = 0.0;
    }
}

/* Transition 11: the ramp starts from the joint's actual state, at the
 * quick stop deceleration 0x6085. */
static void quick_stop(sd_node_t *n)
{
    sd_drive_t *d = &n->drv;
    if (qs_option(n) == LS_CO_QS_DISABLE_DRIVE) {
        enter(n, SD_DS_SWITCH_ON_DISABLED);
        return;
    }
    d->q_cmd = d->fb.q_rad;
    d->v_qs = d->fb.qd_rad_s;
    d->state = SD_DS_QUICK_STOP;
}

static void home(sd_node_t *n)
{
    sd_drive_t *d = &n->drv;
    int64_t method = V(n, n->e.homing_method);
    if (n->e.homing_method < 0 ||
        (method != LS_CO_HOMING_CURRENT_POSITION && method != LS_CO_HOMING_CURRENT_POSITION_OLD)) {
        d->homing = SD_HM_ERROR;
        return;
    }
    /* "Home here": the current position reads the home offset from now on. */
    d->home_shift = (uint32_t)V(n, n->e.home_offset) - encoder(n, d->fb.q_rad);
    d->homed = true;
    d->homing = SD_HM_ATTAINED;
}

/* Device control commands (CiA 402 table 36) from the controlword bits. */
#define CW_CMD_BITS (LS_CO_CW_SWITCH_ON | LS_CO_CW_ENABLE_VOLTAGE | LS_CO_CW_QUICK_STOP | LS_CO_CW_ENABLE_OPERATION)
static bool cmd_disable_voltage(uint16_t cw)
{
    return (cw & LS_CO_CW_ENABLE_VOLTAGE) == 0u;
}
static bool cmd_quick_stop(uint16_t cw)
{
    return (cw & (LS_CO_CW_ENABLE_VOLTAGE | LS_CO_CW_QUICK_STOP)) == LS_CO_CW_ENABLE_VOLTAGE;
}
static bool cmd_shutdown(uint16_t cw)
{
    return (cw & (LS_CO_CW_SWITCH_ON | LS_CO_CW_ENABLE_VOLTAGE | LS_CO_CW_QUICK_STOP)) == LS_CO_CW_CMD_SHUTDOWN;
}
static bool cmd_switch_on(uint16_t cw) /* also "disable operation" */
{
    return (cw & CW_CMD_BITS) == LS_CO_CW_CMD_SWITCH_ON;
}
static bool cmd_enable(uint16_t cw)
{
    return (cw & CW_CMD_BITS) == LS_CO_CW_CMD_ENABLE_OPERATION;
}

/* One step of the power state machine for the controlword; true when the
 * state changed (READY TO SWITCH ON with enable operation takes 3 then 4). */
static bool step(sd_node_t *n, uint16_t cw)
{
    sd_drive_t *d = &n->drv;
    sd_ds_t s = d->state;
    switch (s) {
    case SD_DS_SWITCH_ON_DISABLED:
        if (cmd_shutdown(cw)) {
            enter(n, SD_DS_READY); /* 2 */
        }
        break;
    case SD_DS_READY:
        if (cmd_disable_voltage(cw) || cmd_quick_stop(cw)) {
            enter(n, SD_DS_SWITCH_ON_DISABLED); /* 7 */
        } else if ((cmd_switch_on(cw) || cmd_enable(cw)) && !d->sto) {
            enter(n, SD_DS_SWITCHED_ON); /* 3: not while safe torque off holds the power stage off */
        }
        break;
    case SD_DS_SWITCHED_ON:
        if (cmd_disable_voltage(cw) || cmd_quick_stop(cw)) {
            enter(n, SD_DS_SWITCH_ON_DISABLED); /* 10 */
        } else if (cmd_shutdown(cw)) {
            enter(n, SD_DS_READY); /* 6 */
        } else if (cmd_enable(cw)) {
            enter(n, SD_DS_OPERATION_ENABLED); /* 4 */
        }
        break;
    case SD_DS_OPERATION_ENABLED:
        if (cmd_disable_voltage(cw)) {
            enter(n, SD_DS_SWITCH_ON_DISABLED); /* 9 */
        } else if (cmd_quick_stop(cw)) {
            quick_stop(n); /* 11 */
        } else if (cmd_shutdown(cw)) {
            enter(n, SD_DS_READY); /* 8 */
        } else if (cmd_switch_on(cw)) {
            enter(n, SD_DS_SWITCHED_ON); /* 5 */
        }
        break;
    case SD_DS_QUICK_STOP:
        if (cmd_disable_voltage(cw)) {
            enter(n, SD_DS_SWITCH_ON_DISABLED); /* 12 */
        } else if (cmd_enable(cw) && qs_option(n) >= LS_CO_QS_STAY_MIN && qs_option(n) <= LS_CO_QS_STAY_MAX) {
            enter(n, SD_DS_OPERATION_ENABLED); /* 16 */
        }
        break;
    case SD_DS_NOT_READY:
    case SD_DS_FAULT_REACTION:
    case SD_DS_FAULT: break;
    }
    return d->state != s;
}

void sd_drive_controlword(sd_node_t *n, uint16_t cw, uint64_t now_us)
{
    (void)now_us;
    sd_drive_t *d = &n->drv;
    uint16_t prev = d->cw;
    d->cw = cw;
    if (d->state == SD_DS_FAULT) {
        /* Transition 15 on the rising edge of bit 7 only (a held bit 7
         * resets nothing), unless told to stay faulted for a few edges. */
        if ((cw & LS_CO_CW_FAULT_RESET) != 0u && (prev & LS_CO_CW_FAULT_RESET) == 0u) {
            if (n->mis.sticky > 0u) {
                n->mis.sticky--;
                return;
            }
            n->fault_code = LS_CO_EMCY_NO_ERROR;
            d->following_error = false;
            d->state = SD_DS_SWITCH_ON_DISABLED;
            sd_node_error_cleared(n);
        }
        return;
    }
    if (d->state == SD_DS_OPERATION_ENABLED && mode_display(n) == LS_CO_MODE_HM && (cw & LS_CO_CW_HOMING_START) != 0u &&
        (prev & LS_CO_CW_HOMING_START) == 0u) {
        home(n);
    }
    if (step(n, cw) && d->state == SD_DS_SWITCHED_ON) {
        (void)step(n, cw);
    }
}

void sd_drive_mode(sd_node_t *n, int8_t mode)
{
    sd_drive_t *d = &n->drv;
    set(n, n->e.modes_display, mode);
    d->homing = d->homed ? SD_HM_ATTAINED : SD_HM_IDLE;
    d->limited = false;
    if (d->state == SD_DS_OPERATION_ENABLED) {
        hold_here(n, d->q_cmd);
    }
}

uint32_t sd_drive_check(const sd_node_t *n, int entry, int64_t value)
{
    if (entry == n->e.modes) {
        int64_t supported = V(n, n->e.supported_modes);
        bool ok = value == 0 || (value >= 1 && value <= 32 && ((supported >> (value - 1)) & 1) != 0);
        return ok ? 0u : LS_CO_ABORT_VALUE;
    }
    if (entry == n->e.homing_method) {
        bool ok = value == LS_CO_HOMING_CURRENT_POSITION || value == LS_CO_HOMING_CURRENT_POSITION_OLD;
        return ok ? 0u : LS_CO_ABORT_VALUE;
    }
    return 0u;
}

void sd_drive_fault(sd_node_t *n, uint16_t code, uint64_t now_us)
{
    (void)now_us;
    sd_drive_t *d = &n->drv;
    if (d->state != SD_DS_FAULT && d->state != SD_DS_FAULT_REACTION) {
        n->fault_code = code;
        d->state = SD_DS_FAULT_REACTION; /* the reaction: power stage off, brake on */
    }
    sd_node_emcy(n, code);
}

void sd_drive_abort_connection(sd_node_t *n, uint16_t code, uint64_t now_us)
{
    if (!power_on(n)) {
        return;
    }
    switch (V(n, n->e.abort_option)) {
    case LS_CO_ABORT_CONN_FAULT: sd_drive_fault(n, code, now_us); break;
    case LS_CO_ABORT_CONN_DISABLE_VOLTAGE: enter(n, SD_DS_SWITCH_ON_DISABLED); break;
    case LS_CO_ABORT_CONN_QUICK_STOP:
        if (n->drv.state == SD_DS_OPERATION_ENABLED) {
            quick_stop(n);
        }
        break;
    default: break; /* no action */
    }
}

void sd_drive_set_sto(sd_node_t *n, bool active, uint64_t now_us)
{
    (void)now_us;
    sd_drive_t *d = &n->drv;
    d->sto = active;
    if (active && (d->state == SD_DS_SWITCHED_ON || power_on(n))) {
        enter(n, SD_DS_SWITCH_ON_DISABLED); /* torque off at once: a category 0 stop on the brake */
    }
}

void sd_drive_sync(sd_node_t *n)
{
    sd_drive_t *d = &n->drv;
    if (d->state != SD_DS_OPERATION_ENABLED || mode_display(n) != LS_CO_MODE_CSP) {
        return;
    }
    int32_t target = (int32_t)V(n, n->e.target);
    d->limited = false;
    if (n->e.sw_min >= 0 && n->e.sw_max >= 0 && V(n, n->e.sw_min) < V(n, n->e.sw_max)) {
        int32_t lo = (int32_t)V(n, n->e.sw_min), hi = (int32_t)V(n, n->e.sw_max);
        if (target < lo || target > hi) {
            target = target < lo ? lo : hi;
            d->limited = true;
        }
    }
    d->seg_q0 = d->q_cmd;
    d->seg_q1 = sd_drive_rad(n, target);
    d->seg_ff = (double)V(n, n->e.vel_offset) / n->cfg.counts_per_rad;
    d->seg_T = sd_node_period_s(n);
    d->seg_t = 0.0;
}

void sd_drive_substep(sd_node_t *n, double dt_s, sd_joint_cmd_t *cmd)
{
    sd_drive_t *d = &n->drv;
    switch (d->state) {
    case SD_DS_OPERATION_ENABLED: {
        d->seg_t += dt_s;
        double f = d->seg_T > 0.0 ? fmin(1.0, d->seg_t / d->seg_T) : 1.0;
        d->q_cmd = d->seg_q0 + (d->seg_q1 - d->seg_q0) * f;
        d->qd_cmd = d->seg_ff; /* 0x60B1 is the drive's velocity feed-forward */
        break;
    }
    case SD_DS_QUICK_STOP: {
        double a = (double)V(n, n->e.qs_decel) / n->cfg.counts_per_rad;
        double dv = a * dt_s;
        d->v_qs = d->v_qs > 0.0 ? fmax(0.0, d->v_qs - dv) : fmin(0.0, d->v_qs + dv);
        d->q_cmd += d->v_qs * dt_s;
        d->qd_cmd = d->v_qs;
        break;
    }
    default:
        d->q_cmd = d->fb.q_rad; /* braked: the command follows the joint, so a release does not jump */
        d->qd_cmd = 0.0;
        break;
    }
    cmd->q_rad = d->q_cmd;
    cmd->qd_rad_s = d->qd_cmd;
    cmd->drive_on = power_on(n);
}

void sd_drive_feedback(sd_node_t *n, const sd_joint_fb_t *fb, double dt_s, uint64_t now_us)
{
    sd_drive_t *d = &n->drv;
    d->fb = *fb;
    if (d->state == SD_DS_OPERATION_ENABLED) {
        double err = fabs(d->q_cmd - fb->q_rad) * n->cfg.counts_per_rad;
        int64_t window = V(n, n->e.fe_window);
        if (window != (int64_t)UINT32_MAX && err > (double)window) {
            d->fe_time_s += dt_s;
            if (d->fe_time_s * 1000.0 >= (double)V(n, n->e.fe_timeout)) {
                d->following_error = true;
                sd_drive_fault(n, LS_CO_EMCY_FOLLOWING_ERROR, now_us);
            }
        } else {
            d->fe_time_s = 0.0;
        }
    } else if (d->state == SD_DS_QUICK_STOP && d->v_qs == 0.0) {
        quick_stop_done(n);
    }
}

void sd_drive_tick(sd_node_t *n, uint64_t now_us)
{
    (void)now_us;
    sd_drive_t *d = &n->drv;
    if (d->state == SD_DS_FAULT_REACTION) {
        d->state = SD_DS_FAULT; /* the reaction (brake on) is immediate */
    } else if (d->state == SD_DS_QUICK_STOP && d->v_qs == 0.0 && qs_option(n) < LS_CO_QS_STAY_MIN) {
        quick_stop_done(n); /* a ramp from standstill is over without a physics step */
    }
}
