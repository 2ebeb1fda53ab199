/* The manual device's gate (ls_manual.h). */
#include "ls_manual.h"

#include <math.h>
#include <string.h>

static void emit(ls_manual_events_t *ev, ls_manual_event_kind_t kind, int32_t value, bool joint)
{
    if (ev == NULL || ev->n >= LS_MANUAL_MAX_EVENTS) {
        return;
    }
    ev->ev[ev->n++] = (ls_manual_event_t){ .kind = kind, .value = value, .joint = joint };
}

void ls_manual_block(ls_manual_t *m)
{
    if (m == NULL) {
        return;
    }
    m->armed_ = false;
    m->enabled_ = false;
    m->rested_ = false;
}

void ls_manual_start(ls_manual_t *m, const ls_manual_config_t *cfg)
{
    if (m == NULL) {
        return;
    }
    memset(m, 0, sizeof *m);
    if (cfg != NULL) {
        m->cfg.enabling_switch = cfg->enabling_switch;
        m->cfg.stale_us = cfg->stale_us;
        /* insertion into ascending order, dropping what is out of range or repeated */
        uint8_t n = 0;
        const uint8_t given = cfg->n_steps < LS_MANUAL_MAX_STEPS ? cfg->n_steps : LS_MANUAL_MAX_STEPS;
        for (uint8_t i = 0; i < given; i++) {
            const uint8_t p = cfg->step_pct[i];
            if (p < 1u || p > 100u) {
                continue;
            }
            uint8_t k = n;
            while (k > 0 && m->cfg.step_pct[k - 1] > p) {
                m->cfg.step_pct[k] = m->cfg.step_pct[k - 1];
                k--;
            }
            if (k > 0 && m->cfg.step_pct[k - 1] == p) {
                memmove(&m->cfg.step_pct[k], &m->cfg.step_pct[k + 1], (size_t)(n - k) * sizeof m->cfg.step_pct[0]);
                continue;
            }
            m->cfg.step_pct[k] = p;
            n++;
        }
        m->cfg.n_steps = n;
        m->cfg.start_step = cfg->start_step;
    }
    if (m->cfg.n_steps == 0) {
        m->cfg.n_steps = 1;
        m->cfg.step_pct[0] = 100;
        m->cfg.start_step = 0;
    }
    if (m->cfg.start_step >= m->cfg.n_steps) {
        m->cfg.start_step = (uint8_t)(m->cfg.n_steps - 1u);
    }
    m->step_ = m->cfg.start_step;
    m->frame_ = LS_JOG_TOOL;
    m->present_ = true;              /* so that a device missing at switch-on is reported */
    m->ignore_ = HAL_MANUAL_BTN_ALL; /* buttons held now are no presses: see the first step */
    m->switch_ = LS_MANUAL_SWITCH_RELEASED;
    ls_manual_block(m);
}

/* Whether the device is there and reporting; why not in *why. */
static bool judge(const ls_manual_t *m, const hal_manual_state_t *st, int read_st, ls_manual_lost_t *why)
{
    if (read_st < 0 || st == NULL) {
        *why = LS_MANUAL_LOST_READ;
        return false;
    }
    if (!st->present) {
        *why = LS_MANUAL_LOST_ABSENT;
        return false;
    }
    if (m->cfg.stale_us > 0u && st->age_us > m->cfg.stale_us) {
        *why = LS_MANUAL_LOST_SILENT;
        return false;
    }
    return true;
}

/* The enabling switch's state from the buttons held; updates armed_/enabled_. */
static ls_manual_switch_t enabling_switch(ls_manual_t *m, uint32_t held)
{
    const bool en = (held & HAL_MANUAL_BTN_ENABLE) != 0u;
    const bool panic = (held & HAL_MANUAL_BTN_PANIC) != 0u;
    if (panic) {
        m->armed_ = false; /* only a full release re-arms it */
        m->enabled_ = false;
        return LS_MANUAL_SWITCH_PANIC;
    }
    if (!en) {
        m->armed_ = true;
        m->enabled_ = false;
        return LS_MANUAL_SWITCH_RELEASED;
    }
    if (m->armed_) {
        m->armed_ = false;
        m->enabled_ = true; /* pressed after a release: live until released */
    }
    return m->enabled_ ? LS_MANUAL_SWITCH_ENABLED : LS_MANUAL_SWITCH_HELD_OVER;
}

static void buttons(ls_manual_t *m, uint32_t pressed, ls_manual_events_t *ev)
{
    if ((pressed & HAL_MANUAL_BTN_SPEED_UP) != 0u && m->step_ + 1u < m->cfg.n_steps) {
        m->step_++;
        emit(ev, LS_MANUAL_EV_OVERRIDE, m->cfg.step_pct[m->step_], false);
    }
    if ((pressed & HAL_MANUAL_BTN_SPEED_DOWN) != 0u && m->step_ > 0u) {
        m->step_--;
        emit(ev, LS_MANUAL_EV_OVERRIDE, m->cfg.step_pct[m->step_], false);
    }
    bool mode = false;
    if ((pressed & HAL_MANUAL_BTN_FRAME) != 0u) {
        if (m->joint_) {
            m->joint_ = false; /* back to Cartesian, in the frame it had */
        } else {
            m->frame_ = (ls_jog_frame_t)(((unsigned)m->frame_ + 1u) % LS_JOG_FRAMES);
        }
        mode = true;
    }
    if ((pressed & HAL_MANUAL_BTN_JOINT) != 0u) {
        m->joint_ = !m->joint_;
        mode = true;
    }
    if (mode) {
        emit(ev, LS_MANUAL_EV_FRAME, (int32_t)m->frame_, m->joint_);
    }
}

bool ls_manual_step(ls_manual_t *m, const hal_manual_state_t *st, int read_st, double twist_out[6],
                    ls_manual_events_t *ev)
{
    if (twist_out != NULL) {
        memset(twist_out, 0, 6 * sizeof twist_out[0]);
    }
    if (m == NULL || twist_out == NULL) {
        return false;
    }
    ls_manual_lost_t why = LS_MANUAL_LOST_ABSENT;
    const bool there = judge(m, st, read_st, &why);
    if (!there) {
        if (m->present_) {
            emit(ev, LS_MANUAL_EV_LOST, (int32_t)why, false);
        }
        m->present_ = false;
        m->held_ = 0;
        m->switch_ = LS_MANUAL_SWITCH_RELEASED;
        ls_manual_block(m);
        m->ignore_ = HAL_MANUAL_BTN_ALL;
        return false;
    }
    const bool replugged = m->gen_ != 0u && st->generation != m->gen_;
    if (m->present_ && replugged) {
        emit(ev, LS_MANUAL_EV_LOST, (int32_t)LS_MANUAL_LOST_ABSENT, false); /* gone and back between two reads */
    }
    if (!m->present_ || replugged) {
        emit(ev, LS_MANUAL_EV_FOUND, (int32_t)st->generation, false);
        m->held_ = 0;
        m->switch_ = LS_MANUAL_SWITCH_RELEASED;
        ls_manual_block(m);
        m->ignore_ = HAL_MANUAL_BTN_ALL;
    }
    m->present_ = true;
    m->gen_ = st->generation;

    const uint32_t held = st->buttons & HAL_MANUAL_BTN_ALL;
    m->ignore_ &= held; /* a button held since it appeared counts once released */
    const uint32_t pressed = held & ~m->held_ & ~m->ignore_;
    m->held_ = held;
    buttons(m, pressed, ev);

    bool still = true;
    for (int i = 0; i < 6; i++) {
        still = still && !(st->twist[i] != 0.0 && isfinite(st->twist[i]));
    }
    if (m->cfg.enabling_switch) {
        const ls_manual_switch_t sw = enabling_switch(m, held);
        if (sw != m->switch_) {
            m->switch_ = sw;
            emit(ev, LS_MANUAL_EV_SWITCH, (int32_t)sw, false);
        }
    } else {
        m->rested_ = m->rested_ || still;
        m->enabled_ = m->rested_;
    }
    if (!m->enabled_) {
        return false;
    }
    const double k = (double)m->cfg.step_pct[m->step_] / 100.0;
    for (int i = 0; i < 6; i++) {
        const double x = isfinite(st->twist[i]) ? st->twist[i] : 0.0;
        twist_out[i] = (x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x)) * k;
    }
    return true;
}

uint8_t ls_manual_override_pct(const ls_manual_t *m)
{
    return m != NULL && m->step_ < m->cfg.n_steps ? m->cfg.step_pct[m->step_] : 100u;
}

ls_jog_frame_t ls_manual_frame(const ls_manual_t *m)
{
    return m != NULL ? m->frame_ : LS_JOG_TOOL;
}

bool ls_manual_joint(const ls_manual_t *m)
{
    return m != NULL && m->joint_;
}

const char *ls_manual_kind_name(ls_manual_kind_t k)
{
    switch (k) {
    case LS_MANUAL_TEACHPENDANT: return LS_MANUAL_NAME_TEACHPENDANT;
    case LS_MANUAL_SPACEBALL: return LS_MANUAL_NAME_SPACEBALL;
    }
    return NULL;
}

const char *ls_manual_switch_name(ls_manual_switch_t s)
{
    switch (s) {
    case LS_MANUAL_SWITCH_RELEASED: return "released";
    case LS_MANUAL_SWITCH_ENABLED: return "enabled";
    case LS_MANUAL_SWITCH_PANIC: return "panic";
    case LS_MANUAL_SWITCH_HELD_OVER: return "held_over";
    }
    return "unknown";
}

const char *ls_manual_frame_name(ls_jog_frame_t f)
{
    switch (f) {
    case LS_JOG_TOOL: return "tool";
    case LS_JOG_BASE: return "base";
    case LS_JOG_WORLD: return "world";
    }
    return "unknown";
}

const char *ls_manual_lost_name(ls_manual_lost_t l)
{
    switch (l) {
    case LS_MANUAL_LOST_ABSENT: return "unplugged";
    case LS_MANUAL_LOST_SILENT: return "silent";
    case LS_MANUAL_LOST_READ: return "read_error";
    }
    return "unknown";
}
