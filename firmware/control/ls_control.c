/* Control loop glue: lock-free rings, plan hand-over, seqlock snapshot. */
#include "ls_control.h"

#include <string.h>

#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_seqlock.h"

/* --- SPSC rings: the producer writes the slot then publishes head (release);
 * the consumer reads head (acquire), copies the slot, then publishes tail. */

static bool cmd_push(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    unsigned head = atomic_load_explicit(&c->cmd_head, memory_order_relaxed);
    unsigned tail = atomic_load_explicit(&c->cmd_tail, memory_order_acquire);
    if (head - tail >= LS_CTL_QUEUE_LEN) {
        return false;
    }
    c->cmd_ring[head % LS_CTL_QUEUE_LEN] = *cmd;
    atomic_store_explicit(&c->cmd_head, head + 1u, memory_order_release);
    return true;
}

static bool cmd_pop(ls_control_t *c, ls_ctl_cmd_t *out)
{
    unsigned tail = atomic_load_explicit(&c->cmd_tail, memory_order_relaxed);
    unsigned head = atomic_load_explicit(&c->cmd_head, memory_order_acquire);
    if (tail == head) {
        return false;
    }
    *out = c->cmd_ring[tail % LS_CTL_QUEUE_LEN];
    atomic_store_explicit(&c->cmd_tail, tail + 1u, memory_order_release);
    return true;
}

static void ev_push(ls_control_t *c, const ls_ctl_event_t *ev)
{
    unsigned head = atomic_load_explicit(&c->ev_head, memory_order_relaxed);
    unsigned tail = atomic_load_explicit(&c->ev_tail, memory_order_acquire);
    if (head - tail >= LS_CTL_QUEUE_LEN) {
        /* The comms thread drains it at once (woken by cfg.notify); a full
         * ring means it is stuck. Count it: the loop must not wait. */
        atomic_fetch_add_explicit(&c->events_lost, 1u, memory_order_relaxed);
        return;
    }
    c->ev_ring[head % LS_CTL_QUEUE_LEN] = *ev;
    atomic_store_explicit(&c->ev_head, head + 1u, memory_order_release);
    /* Every event: skipping the call when the ring already held one would
     * lose a wake-up when the comms thread drained that one between our
     * load of ev_tail and our store of ev_head. Events are few per cycle at
     * most (a motion's notices, DIO changes). */
    if (c->cfg.notify != NULL) {
        c->cfg.notify(c->cfg.notify_ctx);
    }
}

bool ls_control_next_event(ls_control_t *c, ls_ctl_event_t *out)
{
    unsigned tail = atomic_load_explicit(&c->ev_tail, memory_order_relaxed);
    unsigned head = atomic_load_explicit(&c->ev_head, memory_order_acquire);
    if (tail == head) {
        return false;
    }
    *out = c->ev_ring[tail % LS_CTL_QUEUE_LEN];
    atomic_store_explicit(&c->ev_tail, tail + 1u, memory_order_release);
    return true;
}

bool ls_control_post(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    return cmd_push(c, cmd);
}

ls_motion_plan_t *ls_control_plan_slot(ls_control_t *c)
{
    if (atomic_load_explicit(&c->manual_on, memory_order_acquire)) {
        return NULL;
    }
    return atomic_load_explicit(&c->plan_slot_busy, memory_order_acquire) ? NULL : &c->plan_slot;
}

ls_react_plan_t *ls_control_react_slot(ls_control_t *c)
{
    if (atomic_load_explicit(&c->manual_on, memory_order_acquire)) {
        return NULL;
    }
    return atomic_load_explicit(&c->react_slot_busy, memory_order_acquire) ? NULL : &c->react_slot;
}

bool ls_control_start_react(ls_control_t *c, uint32_t ref_seq)
{
    atomic_store_explicit(&c->react_slot_busy, true, memory_order_release);
    ls_ctl_cmd_t cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.kind = LS_CTL_REACT_START;
    cmd.ref_seq = ref_seq;
    if (!cmd_push(c, &cmd)) {
        atomic_store_explicit(&c->react_slot_busy, false, memory_order_release);
        return false;
    }
    return true;
}

bool ls_control_set_manual(ls_control_t *c, const hal_manual_t *dev, const ls_jog_config_t *jog,
                           const ls_manual_config_t *gate, uint32_t ref_seq)
{
    ls_ctl_cmd_t cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.kind = LS_CTL_MANUAL;
    cmd.ref_seq = ref_seq;
    bool on = dev != NULL && jog != NULL;
    if (on) {
        cmd.manual.dev = dev;
        cmd.manual.jog = *jog;
        if (gate != NULL) {
            cmd.manual.gate = *gate;
        }
    }
    if (!cmd_push(c, &cmd)) {
        return false;
    }
    atomic_store_explicit(&c->manual_on, on, memory_order_release);
    return true;
}

bool ls_control_manual_on(ls_control_t *c)
{
    return atomic_load_explicit(&c->manual_on, memory_order_acquire);
}

bool ls_control_start_plan(ls_control_t *c, uint32_t ref_seq)
{
    atomic_store_explicit(&c->plan_slot_busy, true, memory_order_release);
    ls_ctl_cmd_t cmd = { .kind = LS_CTL_START, .ref_seq = ref_seq };
    if (!cmd_push(c, &cmd)) {
        atomic_store_explicit(&c->plan_slot_busy, false, memory_order_release);
        return false;
    }
    return true;
}

/* --- the snapshot: a seqlock (ls_seqlock.h), the loop writes, the comms thread reads */

static void publish(ls_control_t *c, const ls_ctl_snapshot_t *s)
{
    ls_seqlock_write(&c->snap_seq, c->snap_words, LS_CTL_SNAP_WORDS, s, sizeof *s);
}

bool ls_control_snapshot(ls_control_t *c, ls_ctl_snapshot_t *out)
{
    ls_ctl_snapshot_t s;
    if (ls_seqlock_read(&c->snap_seq, c->snap_words, LS_CTL_SNAP_WORDS, &s, sizeof s, LS_CTL_SNAPSHOT_TRIES)) {
        c->snap_last = s;
        *out = s;
        return true;
    }
    c->snap_stale++;
    *out = c->snap_last;
    return false;
}

/* --- the loop */

static void enable_failed(ls_control_t *c, const char *text);

static void fault(ls_control_t *c, const char *text)
{
    if (c->enabling) {
        /* Nothing moves while the drives enable; the enable's requester waits
         * for its one answer: this is it. */
        enable_failed(c, text);
        return;
    }
    ls_motion_abort(&c->motion);
    /* The core ends whatever ran with its final alarm on LS_CEV_FAULT. */
    ls_react_abort(&c->react, c->q, NULL);
    ls_react_jog_halt(&c->react);
    if (c->enabled) {
        (void)hal_arm_enable(c->cfg.arm, false);
        c->enabled = false;
    }
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = LS_CEV_FAULT;
    ls_fmt_print(ev.text, sizeof ev.text, "%s", text);
    ev_push(c, &ev);
}

/* LS_CTL_ENABLE ended with the drives off: LS_CEV_ENABLE_FAILED saying why. */
static void enable_failed(ls_control_t *c, const char *text)
{
    if (c->cfg.arm != NULL) {
        (void)hal_arm_enable(c->cfg.arm, false);
    }
    c->enabling = false;
    c->enabled = false;
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = LS_CEV_ENABLE_FAILED;
    ev.ref_seq = c->enable_ref_seq;
    ls_fmt_print(ev.text, sizeof ev.text, "%s", text);
    ev_push(c, &ev);
}

/* An event that answers a command with a line of text. */
static void text_event(ls_control_t *c, ls_cev_kind_t kind, uint32_t ref_seq, const char *text)
{
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = kind;
    ev.ref_seq = ref_seq;
    ls_fmt_print(ev.text, sizeof ev.text, "%s", text);
    ev_push(c, &ev);
}

static void cmd_failed(ls_control_t *c, uint32_t ref_seq, const char *text)
{
    text_event(c, LS_CEV_CMD_FAILED, ref_seq, text);
}

/* Joints that must be homed and are not: bit j for joint j + 1. */
static uint32_t unhomed(const ls_control_t *c)
{
    uint32_t m = 0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (c->joints[j].home_required && c->joints[j].home != HAL_HOME_HOMED) {
            m |= 1u << j;
        }
    }
    return m;
}

/* "joints 2, 3 are not homed (...)": why a motion may not start, or NULL. */
static const char *motion_blocked(const ls_control_t *c, char *buf, size_t cap)
{
    if (c->homing_joints != 0u) {
        return "the drives are homing";
    }
    const uint32_t m = unhomed(c);
    if (m == 0u) {
        return NULL;
    }
    size_t len = (size_t)ls_fmt_print(buf, cap, "joint");
    const char *sep = (m & (m - 1u)) != 0u ? "s " : " ";
    for (int j = 0; j < LS_N_JOINTS && len < cap; j++) {
        if ((m & (1u << j)) != 0u) {
            len += (size_t)ls_fmt_print(buf + len, cap - len, "%s%d", sep, j + 1);
            sep = ", ";
        }
    }
    if (len < cap) {
        (void)ls_fmt_print(buf + len, cap - len, " must be homed first (sendCommand home)");
    }
    return buf;
}

static void read_feedback(ls_control_t *c)
{
    if (c->cfg.arm != NULL && hal_arm_read(c->cfg.arm, c->q, c->qd) < 0) {
        fault(c, "arm feedback failed");
    }
}

static void read_sensors(ls_control_t *c)
{
    for (size_t i = 0; i < c->cfg.n_sensors && i < (size_t)HAL_MAX_SENSORS; i++) {
        if (c->cfg.sensors[i].read == NULL || c->cfg.sensors[i].read(c->cfg.sensors[i].self, c->sens[i]) < 0) {
            memset(c->sens[i], 0, sizeof c->sens[i]);
        }
    }
}

#define NO_SENSOR (-1) /* sensor_index: no sensor has the name */

/* Index of the sensor called `name`, or NO_SENSOR. */
static int sensor_index(const ls_control_t *c, const char *name)
{
    for (size_t i = 0; i < c->cfg.n_sensors && i < (size_t)HAL_MAX_SENSORS; i++) {
        if (c->cfg.sensors[i].name != NULL && strcmp(c->cfg.sensors[i].name, name) == 0) {
            return (int)i;
        }
    }
    return NO_SENSOR;
}

static void tool_event(ls_control_t *c, const ls_ctl_cmd_t *cmd, int status, uint32_t bits)
{
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = LS_CEV_MOTION;
    ev.ref_seq = cmd->ref_seq;
    ev.motion.kind = LS_MEV_TOOL;
    ev.motion.ref_seq = cmd->ref_seq;
    ev.motion.index = status;
    ls_fmt_print(ev.motion.name, sizeof ev.motion.name, "%s", cmd->tool.id);
    ls_fmt_print(ev.motion.text, sizeof ev.motion.text, "%s",
                 cmd->kind == LS_CTL_TOOL_COUPLE ? (cmd->tool.attach ? "couple" : "uncouple") : "bits");
    memcpy(ev.motion.q_rad, c->q, sizeof ev.motion.q_rad);
    ev.dio.on = bits;
    ev_push(c, &ev);
}

static void run_tool(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    const hal_tool_t *t = cmd->tool.dev;
    int st = LS_EUNSUPPORTED;
    uint32_t bits = 0;
    if (t == NULL || t->ops == NULL) {
        tool_event(c, cmd, LS_ENODEV, 0);
        return;
    }
    if (cmd->kind == LS_CTL_TOOL_COUPLE) {
        if (t->ops->couple != NULL) {
            st = t->ops->couple(t->self, cmd->tool.id, cmd->tool.attach);
        }
    } else if (t->ops->set_bits != NULL) {
        st = t->ops->set_bits(t->self, cmd->tool.on, cmd->tool.off);
    }
    if (t->ops->get_bits != NULL) {
        (void)t->ops->get_bits(t->self, &bits);
    }
    tool_event(c, cmd, st, bits);
}

/* A motion of either executor is under way (running, stopping or paused). */
static bool busy(const ls_control_t *c)
{
    return c->react.active || c->motion.phase != LS_MOTION_IDLE;
}

void ls_control_init(ls_control_t *c, const ls_control_config_t *cfg)
{
    memset(c, 0, sizeof *c);
    c->cfg = *cfg;
    c->dt_s = 1.0 / (double)(cfg->rate_hz != 0u ? cfg->rate_hz : 1000u);
    ls_motion_init(&c->motion, cfg->model);
    ls_react_init(&c->react, cfg->model);
    hal_arm_info_t info;
    if (cfg->arm != NULL && hal_arm_info(cfg->arm, &info) >= 0) {
        ls_motion_set_feedback_lag(&c->motion, info.feedback_lag_cycles);
        c->home_timeout_ms = info.home_timeout_ms;
    }
    c->react_sensor = -1;
    read_feedback(c);
    read_sensors(c);
    memcpy(c->q_cmd, c->q, sizeof c->q_cmd);
    ls_motion_hold(&c->motion, c->q);
    ls_ctl_snapshot_t s;
    memset(&s, 0, sizeof s);
    memcpy(s.q_rad, c->q, sizeof s.q_rad);
    memcpy(s.q_cmd_rad, c->q, sizeof s.q_cmd_rad);
    (void)ls_kin_fk(cfg->model, c->q, s.flange_pose);
    publish(c, &s);
    c->snap_last = s; /* before any thread starts: what a first failed read returns */
}

/* Executor events -> control events (REACT_END carries the report). */
static void motion_events(ls_control_t *c, const ls_motion_events_t *mev)
{
    for (uint8_t i = 0; i < mev->n; i++) {
        ls_ctl_event_t ev;
        memset(&ev, 0, sizeof ev);
        ev.kind = LS_CEV_MOTION;
        ev.ref_seq = mev->ev[i].ref_seq;
        ev.motion = mev->ev[i];
        if (mev->ev[i].kind == LS_MEV_REACT_END) {
            ev.react = c->react.report;
        }
        ev_push(c, &ev);
        if (mev->ev[i].kind == LS_MEV_FAULT && c->enabled) {
            (void)hal_arm_enable(c->cfg.arm, false);
            c->enabled = false;
        }
    }
}

/* Abort a guarded/compliant move: its one LS_MEV_REACT_END (aborted). */
static void react_abort(ls_control_t *c)
{
    if (!c->react.active) {
        return;
    }
    ls_motion_events_t mev;
    mev.n = 0;
    ls_react_abort(&c->react, c->q, &mev);
    ls_motion_hold(&c->motion, c->q_cmd);
    motion_events(c, &mev);
}

/* Jogging is possible now (manual on and drives on): LS_MEV_JOG index 0. */
static void jog_ready(ls_control_t *c, uint32_t ref_seq)
{
    ls_motion_events_t mev;
    mev.n = 1;
    memset(&mev.ev[0], 0, sizeof mev.ev[0]);
    mev.ev[0].kind = LS_MEV_JOG;
    mev.ev[0].ref_seq = ref_seq;
    mev.ev[0].index = 0;
    ls_fmt_print(mev.ev[0].text, sizeof mev.ev[0].text, "ready");
    memcpy(mev.ev[0].q_rad, c->q_cmd, sizeof mev.ev[0].q_rad);
    motion_events(c, &mev);
}

/* Drives off; a moving arm first decelerates along its path (braking a
 * moving arm is a jolt): at the configured deceleration, or (fast) at the
 * model's maximum. The guarded/compliant moves always stop at the maximum. */
static void stop_then_disable(ls_control_t *c, bool fast)
{
    if (c->enabled && (c->motion.phase == LS_MOTION_RUNNING || c->motion.phase == LS_MOTION_STOPPING)) {
        if (fast) {
            ls_motion_stop_fast(&c->motion);
        } else {
            ls_motion_stop(&c->motion);
        }
        c->disable_pending = true;
        return;
    }
    if (c->enabled && ls_react_moving(&c->react)) {
        ls_react_stop(&c->react);
        c->disable_pending = true;
        return;
    }
    ls_motion_abort(&c->motion);
    react_abort(c);
    if (c->enabling) {
        enable_failed(c, "enabling cancelled: the drives were switched off");
    }
    (void)hal_arm_enable(c->cfg.arm, false);
    c->enabled = false;
    c->disable_pending = false;
}

/* Every joint confirmed: hold where the arm is, not where an old command
 * pointed (the drives' own targets were their actual positions meanwhile). */
static void enabled_now(ls_control_t *c)
{
    c->enabling = false;
    ls_motion_hold(&c->motion, c->q);
    memcpy(c->q_cmd, c->q, sizeof c->q_cmd);
    memset(c->qd_cmd, 0, sizeof c->qd_cmd);
    c->enabled = true;
    ls_ctl_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.kind = LS_CEV_ENABLED;
    ev.ref_seq = c->enable_ref_seq;
    ev_push(c, &ev);
    if (c->manual != NULL) {
        ls_react_jog_halt(&c->react);
        ls_manual_block(&c->gate); /* an enabling switch held through the switch-on must be pressed again */
        jog_ready(c, c->enable_ref_seq);
    }
}

/* LS_CTL_ENABLE: ask the drives; check_joints() finishes it when every
 * joint has confirmed (LS_CEV_ENABLED) or one cannot be enabled
 * (LS_CEV_ENABLE_FAILED). Asked again while enabled, it confirms at once. */
static void enable_drives(ls_control_t *c, uint32_t ref_seq)
{
    c->disable_pending = false;
    c->enable_ref_seq = ref_seq;
    if (c->enabled) {
        enabled_now(c);
        return;
    }
    if (c->enabling) {
        return;
    }
    if (c->cfg.arm == NULL) {
        enable_failed(c, "no arm backend is composed (arm = none): nothing can be enabled");
        return;
    }
    const int r = hal_arm_enable(c->cfg.arm, true);
    if (r < 0) {
        char text[LS_CTL_TEXT_LEN];
        ls_fmt_print(text, sizeof text, "the arm backend refused to enable the drives (%s)", ls_err_name(r));
        enable_failed(c, text);
        return;
    }
    c->enabling = true;
    c->failed_joints = 0u;
    ls_motion_ignore_joints(&c->motion, 0u);
    const uint32_t ms = c->cfg.enable_timeout_ms != 0u ? c->cfg.enable_timeout_ms : LS_CTL_ENABLE_TIMEOUT_MS;
    c->enable_deadline_us = c->now_us + (uint64_t)ms * 1000u;
}

/* "joint 3 (node 0x23): " or "joint 3: " before what its drive said. */
static void joint_line(char *out, size_t cap, int j, const hal_joint_status_t *st, const char *what)
{
    if (st->node != 0u) {
        ls_fmt_print(out, cap, "joint %d (node 0x%02X): %s", j + 1, (unsigned)st->node, what);
    } else {
        ls_fmt_print(out, cap, "joint %d: %s", j + 1, what);
    }
}

static const char *joint_state_name(hal_joint_state_t s)
{
    switch (s) {
    case HAL_JOINT_OFF: return "OFF";
    case HAL_JOINT_ENABLING: return "ENABLING";
    case HAL_JOINT_ENABLED: return "ENABLED";
    case HAL_JOINT_FAULT: return "FAULT";
    case HAL_JOINT_LOST: return "LOST";
    }
    return "?";
}

/* A joint under control faulted or was lost: the category-1 stop. The
 * healthy joints come to rest along the path at the model's maximum
 * deceleration, then every drive goes off (as the e-stop input does); the
 * failed ones no longer follow, so the following check leaves them out. A
 * stop under way takes further failures into that set; when no joint is
 * left to stop with, or nothing moves, the drives go off at once. */
static void drive_fault(ls_control_t *c, uint32_t bad_mask, const char *line)
{
    const uint32_t all = (1u << LS_N_JOINTS) - 1u;
    const bool first = c->failed_joints == 0u;
    c->failed_joints |= bad_mask;
    ls_motion_ignore_joints(&c->motion, c->failed_joints);
    const bool moving =
        c->motion.phase == LS_MOTION_RUNNING || c->motion.phase == LS_MOTION_STOPPING || ls_react_moving(&c->react);
    if (!moving || (c->failed_joints & all) == all) {
        fault(c, line);
        return;
    }
    if (first) {
        stop_then_disable(c, true);
        ls_ctl_event_t ev;
        memset(&ev, 0, sizeof ev);
        ev.kind = LS_CEV_FAULT;
        ls_fmt_print(ev.text, sizeof ev.text, "%s", line);
        ev_push(c, &ev);
    }
}

/* LS_CTL_HOME: the drives' own homing of `joints`, the drives on and the
 * arm at rest; the arm holds where it is meanwhile. */
static void home_joints(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    const char *why = NULL;
    char text[LS_CTL_TEXT_LEN];
    if (!c->enabled) {
        why = "the drives are off: activate first";
    } else if (busy(c) || c->jogging || c->homing_joints != 0u) {
        why = c->homing_joints != 0u ? "a homing runs already" : "the arm is moving: home it at rest";
    } else {
        const int r = hal_arm_home(c->cfg.arm, cmd->home.joints);
        if (r == LS_OK) {
            c->homing_joints = cmd->home.joints;
            c->home_ref_seq = cmd->ref_seq;
            ls_motion_hold(&c->motion, c->q_cmd);
            return;
        }
        ls_fmt_print(text, sizeof text, "%s (%s)",
                     r == LS_EUNSUPPORTED ? "this arm has no homing: its joints' positions are absolute"
                     : r == LS_EBUSY      ? "a joint to home is not enabled or homes already"
                                          : "the arm refused the joints to home",
                     ls_err_name(r));
        why = text;
    }
    text_event(c, LS_CEV_HOME_FAILED, cmd->ref_seq, why); /* a homing under way keeps its own */
}

/* A homing under way: its end, once no joint of it is HOMING any more.
 * The drive's counter may have a new zero: the arm holds where it now
 * reads, not where the old set-point pointed. */
static void check_homing(ls_control_t *c)
{
    if (c->homing_joints == 0u) {
        return;
    }
    int failed = -1;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if ((c->homing_joints & (1u << j)) == 0u) {
            continue;
        }
        if (c->joints[j].home == HAL_HOME_HOMING) {
            return;
        }
        if (c->joints[j].home != HAL_HOME_HOMED && failed < 0) {
            failed = j;
        }
    }
    c->homing_joints = 0u;
    if (c->enabled) {
        ls_motion_hold(&c->motion, c->q);
        memcpy(c->q_cmd, c->q, sizeof c->q_cmd);
        memset(c->qd_cmd, 0, sizeof c->qd_cmd);
    }
    if (failed < 0) {
        text_event(c, LS_CEV_HOMED, c->home_ref_seq, "");
        return;
    }
    const hal_joint_status_t *st = &c->joints[failed];
    char line[LS_CTL_TEXT_LEN];
    joint_line(line, sizeof line, failed, st, st->text[0] != '\0' ? st->text : "homing failed");
    text_event(c, LS_CEV_HOME_FAILED, c->home_ref_seq, line);
}

/* The drives' states, once per cycle: finish an enable, and fault when a
 * joint under control faults or is lost. A backend whose status() fails is
 * a lost arm. */
static void check_joints(ls_control_t *c)
{
    if (c->cfg.arm == NULL) {
        return;
    }
    const int r = hal_arm_status(c->cfg.arm, c->enabled || c->enabling, LS_N_JOINTS, c->joints);
    if (r < 0) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            memset(&c->joints[j], 0, sizeof c->joints[j]);
            c->joints[j].state = HAL_JOINT_LOST;
            ls_fmt_print(c->joints[j].text, sizeof c->joints[j].text, "the arm backend's status failed (%s)",
                         ls_err_name(r));
        }
    }
    check_homing(c);
    if (!c->enabling && !c->enabled) {
        return;
    }
    /* A late answer is compared with the set-points of its own time. */
    uint32_t oldest = 0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        oldest = c->joints[j].feedback_age > oldest ? c->joints[j].feedback_age : oldest;
    }
    ls_motion_feedback_late(&c->motion, (uint16_t)(oldest < UINT16_MAX ? oldest : UINT16_MAX));
    int bad = -1, waiting = -1;
    uint32_t bad_mask = 0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        const hal_joint_state_t s = c->joints[j].state;
        if (s == HAL_JOINT_FAULT || s == HAL_JOINT_LOST || (c->enabled && s != HAL_JOINT_ENABLED)) {
            bad_mask |= 1u << j;
            bad = bad < 0 ? j : bad;
        } else if (s != HAL_JOINT_ENABLED && waiting < 0) {
            waiting = j;
        }
    }
    char what[LS_CTL_TEXT_LEN], line[LS_CTL_TEXT_LEN];
    if (bad >= 0) {
        const hal_joint_status_t *st = &c->joints[bad];
        if (st->text[0] != '\0') {
            ls_fmt_print(what, sizeof what, "%s", st->text);
        } else {
            ls_fmt_print(what, sizeof what, "%s", joint_state_name(st->state));
        }
        joint_line(line, sizeof line, bad, st, what);
        if (c->enabling) {
            enable_failed(c, line);
        } else {
            drive_fault(c, bad_mask, line);
        }
        return;
    }
    if (!c->enabling) {
        return;
    }
    if (waiting < 0) {
        enabled_now(c);
    } else if (c->now_us >= c->enable_deadline_us) {
        const hal_joint_status_t *st = &c->joints[waiting];
        const uint32_t ms = c->cfg.enable_timeout_ms != 0u ? c->cfg.enable_timeout_ms : LS_CTL_ENABLE_TIMEOUT_MS;
        ls_fmt_print(what, sizeof what, "not enabled within %u ms (%s%s%s)", (unsigned)ms, joint_state_name(st->state),
                     st->text[0] != '\0' ? ": " : "", st->text);
        joint_line(line, sizeof line, waiting, st, what);
        enable_failed(c, line);
    }
}

/* LS_CTL_START: the plan in the plan slot becomes the motion. */
static void start_plan(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    char buf[LS_CTL_TEXT_LEN];
    const char *blocked = motion_blocked(c, buf, sizeof buf);
    if (!c->enabled || c->react.active || c->manual != NULL || blocked != NULL ||
        ls_motion_start(&c->motion, &c->plan_slot) != 0) {
        cmd_failed(c, cmd->ref_seq,
                   !c->enabled         ? "the drives are off"
                   : c->manual != NULL ? "manualControl is on: switch it off first"
                   : blocked != NULL   ? blocked
                                       : "a motion is already running");
    }
    atomic_store_explicit(&c->plan_slot_busy, false, memory_order_release);
}

/* LS_CTL_REACT_START: the plan in the react slot becomes the sensor-guided move. */
static void start_react(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    int si = sensor_index(c, c->react_slot.sensor);
    char buf[LS_CTL_TEXT_LEN];
    const char *blocked = motion_blocked(c, buf, sizeof buf);
    if (!c->enabled || busy(c) || c->manual != NULL || si < 0 || blocked != NULL ||
        ls_react_start(&c->react, &c->react_slot, c->q_cmd, c->cfg.sensors[si].n_values) != 0) {
        cmd_failed(c, cmd->ref_seq,
                   !c->enabled         ? "the drives are off"
                   : busy(c)           ? "a motion is already running"
                   : c->manual != NULL ? "manualControl is on: switch it off first"
                   : blocked != NULL   ? blocked
                   : si < 0            ? "the move's sensor is not composed"
                                       : "the sensor-guided move was refused");
    } else {
        c->react_sensor = si;
    }
    atomic_store_explicit(&c->react_slot_busy, false, memory_order_release);
}

static void handle_command(ls_control_t *c, const ls_ctl_cmd_t *cmd)
{
    switch (cmd->kind) {
    case LS_CTL_ENABLE: enable_drives(c, cmd->ref_seq); return;
    case LS_CTL_DISABLE:
    case LS_CTL_HALT: stop_then_disable(c, cmd->kind == LS_CTL_HALT); return;
    case LS_CTL_START: start_plan(c, cmd); return;
    case LS_CTL_REACT_START: start_react(c, cmd); return;
    case LS_CTL_STOP:
        if (c->react.active) {
            ls_react_stop(&c->react);
        } else {
            ls_motion_stop(&c->motion);
        }
        return;
    case LS_CTL_RESUME:
        if (c->react.active) {
            if (ls_react_resume(&c->react) != 0) {
                cmd_failed(c, cmd->ref_seq, "no paused motion to resume");
            }
        } else {
            const int r = ls_motion_resume(&c->motion);
            if (r != 0) {
                cmd_failed(c, cmd->ref_seq,
                           r == LS_ESTATE ? "no paused motion to resume"
                                          : "the motion could not be re-planned from where it stopped: abort it");
            }
        }
        return;
    case LS_CTL_ABORT:
        ls_motion_abort(&c->motion);
        react_abort(c);
        return;
    case LS_CTL_MANUAL:
        c->manual = cmd->manual.dev;
        ls_react_jog_config(&c->react, c->manual != NULL ? &cmd->manual.jog : NULL);
        ls_manual_start(&c->gate, &cmd->manual.gate);
        if (c->manual != NULL && c->enabled) {
            jog_ready(c, cmd->ref_seq);
        }
        return;
    case LS_CTL_TOOL_COUPLE:
    case LS_CTL_TOOL_BITS:
        if (cmd->kind == LS_CTL_TOOL_COUPLE && busy(c)) {
            tool_event(c, cmd, LS_EAGAIN, 0);
            return;
        }
        run_tool(c, cmd);
        return;
    case LS_CTL_DIO_WRITE:
        if (hal_dio_write(c->cfg.dio, cmd->dio.unit, cmd->dio.on, cmd->dio.off) < 0) {
            cmd_failed(c, cmd->ref_seq, "DIO write refused by the backend");
        }
        return;
    case LS_CTL_AUX_DONE: ls_motion_aux_done(&c->motion); return;
    case LS_CTL_ESTOP_LINE:
        c->estop_unit = cmd->dio.unit;
        c->estop_bit = cmd->dio.on;
        return;
    case LS_CTL_HOME: home_joints(c, cmd); return;
    }
}

static void read_dio(ls_control_t *c)
{
    if (c->cfg.dio == NULL) {
        return;
    }
    if (hal_dio_poll_fd(c->cfg.dio) >= 0) {
        (void)hal_dio_drain_events(c->cfg.dio);
    }
    int units = hal_dio_unit_count(c->cfg.dio);
    for (int u = 0; u < units && u < LS_CTL_MAX_DIO_UNITS; u++) {
        uint32_t bits = 0;
        if (hal_dio_read(c->cfg.dio, (uint16_t)u, &bits) < 0) {
            continue;
        }
        uint32_t changed = bits ^ c->dio_levels[u];
        c->dio_levels[u] = bits;
        if (changed != 0u) {
            ls_ctl_event_t ev;
            memset(&ev, 0, sizeof ev);
            ev.kind = LS_CEV_DIO_CHANGED;
            ev.dio.unit = (uint16_t)u;
            ev.dio.on = bits;
            ev.dio.off = changed;
            ev_push(c, &ev);
        }
        if (c->estop_bit != 0u && (unsigned)u == c->estop_unit && (bits & c->estop_bit) != 0u && c->enabled &&
            !c->disable_pending) {
            /* Stop along the path at the model's maximum deceleration, then drives off. */
            stop_then_disable(c, true);
            ls_ctl_event_t ev;
            memset(&ev, 0, sizeof ev);
            ev.kind = LS_CEV_FAULT;
            ls_fmt_print(ev.text, sizeof ev.text, "e-stop input active");
            ev_push(c, &ev);
        }
    }
}

/* The manual device through its gate, every cycle while manual control is
 * on (drives on or off): its events go out, its frame and joint mode go to
 * the jog, and twist gets what the jog may follow (zeros when it may not). */
static void read_manual(ls_control_t *c, double twist[6])
{
    memset(twist, 0, 6 * sizeof twist[0]);
    if (c->manual == NULL) {
        return;
    }
    hal_manual_state_t st;
    const int rs = hal_manual_read(c->manual, &st);
    ls_manual_events_t gev;
    gev.n = 0;
    (void)ls_manual_step(&c->gate, &st, rs, twist, &gev);
    ls_react_jog_mode(&c->react, ls_manual_frame(&c->gate), ls_manual_joint(&c->gate));
    for (uint8_t i = 0; i < gev.n; i++) {
        ls_ctl_event_t ev;
        memset(&ev, 0, sizeof ev);
        ev.kind = LS_CEV_MANUAL;
        ev.manual = gev.ev[i];
        ev_push(c, &ev);
    }
}

void ls_control_cycle(ls_control_t *c, uint64_t now_us)
{
    c->now_us = now_us;
    ls_ctl_cmd_t cmd;
    while (cmd_pop(c, &cmd)) {
        handle_command(c, &cmd);
    }
    read_dio(c);
    check_joints(c);
    double twist[6];
    read_manual(c, twist);
    ls_motion_events_t mev;
    mev.n = 0;
    c->jogging = false;
    if (c->enabled) {
        if (c->react.active) {
            ls_react_step(&c->react, c->dt_s, c->q, c->react_sensor >= 0 ? c->sens[c->react_sensor] : NULL, c->q_cmd,
                          c->qd_cmd, &mev);
            /* The path executor holds where the guarded move is (or ended). */
            ls_motion_hold(&c->motion, c->q_cmd);
        } else if (c->motion.phase == LS_MOTION_IDLE && c->manual != NULL && c->homing_joints == 0u &&
                   unhomed(c) == 0u) {
            c->jogging = ls_react_jog_step(&c->react, c->dt_s, twist, c->q_cmd, c->qd_cmd, &mev);
            ls_motion_hold(&c->motion, c->q_cmd);
        } else {
            ls_motion_step(&c->motion, c->dt_s, c->q, c->q_cmd, c->qd_cmd, &mev);
        }
        if (hal_arm_command(c->cfg.arm, c->q_cmd, c->qd_cmd) < 0) {
            fault(c, "arm command failed");
        }
    }
    if (c->disable_pending && c->motion.phase != LS_MOTION_RUNNING && c->motion.phase != LS_MOTION_STOPPING &&
        !ls_react_moving(&c->react)) {
        ls_motion_abort(&c->motion);
        ls_react_abort(&c->react, c->q, &mev);
        (void)hal_arm_enable(c->cfg.arm, false);
        c->enabled = false;
        c->disable_pending = false;
    }
    if (c->cfg.arm != NULL && hal_arm_update(c->cfg.arm, now_us) < 0 && (c->enabled || c->enabling)) {
        /* Every joint is gone with the bus: what the arm says of it, at once. */
        hal_joint_status_t *st = &c->joints[0];
        (void)hal_arm_status(c->cfg.arm, true, LS_N_JOINTS, c->joints);
        fault(c, st->text[0] != '\0' ? st->text : "the arm backend's bus failed");
    }
    /* What the drives reported, a few per cycle (a burst waits in the arm's own queue). */
    for (int k = 0; k < LS_CTL_ARM_EVENTS_PER_CYCLE && c->cfg.arm != NULL; k++) {
        ls_ctl_event_t ev;
        memset(&ev, 0, sizeof ev);
        if (hal_arm_next_event(c->cfg.arm, &ev.arm) != 1) {
            break;
        }
        ev.kind = LS_CEV_ARM_EVENT;
        ev_push(c, &ev);
    }
    if (c->cfg.world_step != NULL) {
        (void)c->cfg.world_step(c->cfg.world_ctx, c->dt_s); /* physics advances with the drives off too (brakes) */
    }
    read_feedback(c);
    read_sensors(c);
    motion_events(c, &mev);
    c->cycles++;
    ls_ctl_snapshot_t s;
    memset(&s, 0, sizeof s); /* padding too: the seqlock copies raw words */
    s.cycle = c->cycles;
    s.t_us = now_us;
    s.enabled = c->enabled;
    s.enabling = c->enabling;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        s.joint_state[j] = (uint8_t)c->joints[j].state;
        s.joint_home[j] = (uint8_t)c->joints[j].home;
        s.home_required |= c->joints[j].home_required ? 1u << j : 0u;
    }
    s.unhomed = unhomed(c);
    s.homing = c->homing_joints != 0u;
    s.home_timeout_ms = c->home_timeout_ms;
    s.phase = c->react.active ? (c->react.paused ? LS_MOTION_PAUSED : LS_MOTION_RUNNING) : c->motion.phase;
    s.react_active = c->react.active;
    s.manual_on = c->manual != NULL;
    s.jogging = c->jogging;
    memcpy(s.q_rad, c->q, sizeof s.q_rad);
    memcpy(s.qd_rad_s, c->qd, sizeof s.qd_rad_s);
    memcpy(s.q_cmd_rad, c->enabled ? c->q_cmd : c->q, sizeof s.q_cmd_rad);
    memcpy(s.dio, c->dio_levels, sizeof s.dio);
    memcpy(s.sensor, c->sens, sizeof s.sensor);
    (void)ls_kin_fk(c->cfg.model, c->q, s.flange_pose);
    s.events_lost = atomic_load_explicit(&c->events_lost, memory_order_relaxed);
    s.max_cycle_us = c->max_cycle_us;
    publish(c, &s);
}

int ls_control_readout(ls_control_t *c, hal_arm_readout_t *out)
{
    return hal_arm_readout(c->cfg.arm, out);
}
