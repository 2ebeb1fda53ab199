/* ls_control, black box first: the comms-thread API (rings, plan and react
 * slots, manual, snapshot) against the real loop body (ls_control_cycle)
 * with fake devices. The arm is ideal (the measured joints are the last
 * set-point); DIO, tool, manual device and sensor are tables of function
 * pointers whose calls the tests record.
 *
 * White box only where the API cannot reach: a loop thread stopped in the
 * middle of a publish (the seqlock's odd sequence) is simulated by writing
 * the sequence, to test the bounded read's failure path. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "ls_control.h"
#include "ls_kin.h"

static const ls_robot_model_t *M = &ls_robot_model_default;
static const double Q0[LS_N_JOINTS] = { -0.2, 0.8, 0.45, 0.0, 0.3, 0.0 };

/* ---------------------------------------------------------------- fake arm */

typedef struct {
    double q[LS_N_JOINTS];
    bool enabled;
    int n_enable_calls;
    int fail_enable;  /* enable(true) returns LS_EIO */
    int fail_command; /* command returns LS_EIO */
    long steps;
    bool counter; /* q[j] follows the step count (seqlock test), commands ignored */
} fake_arm_t;

static double counter_q(long steps, int j)
{
    return (double)(steps % 1000) * 1e-3 + (double)j * 0.01;
}

static int arm_enable(void *self, bool on)
{
    fake_arm_t *a = self;
    a->n_enable_calls++;
    if (on && a->fail_enable) {
        return LS_EIO;
    }
    a->enabled = on;
    return LS_OK;
}

static int arm_command(void *self, const double *q_rad, const double *qd_rad_s)
{
    fake_arm_t *a = self;
    (void)qd_rad_s;
    if (a->fail_command) {
        return LS_EIO;
    }
    if (!a->counter) {
        memcpy(a->q, q_rad, sizeof a->q);
    }
    return LS_OK;
}

static int arm_read(void *self, double *q_rad, double *qd_rad_s)
{
    fake_arm_t *a = self;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        q_rad[j] = a->counter ? counter_q(a->steps, j) : a->q[j];
        qd_rad_s[j] = 0.0;
    }
    return LS_OK;
}

/* The config's world_step: the fake arm is its own world (counts steps). */
static int world_step(void *world_ctx, double dt_s)
{
    (void)dt_s;
    ((fake_arm_t *)world_ctx)->steps++;
    return LS_OK;
}

static const hal_arm_ops_t ARM_OPS = { .enable = arm_enable, .command = arm_command, .read = arm_read };

/* The same arm behind drives that confirm enable() only after `enable_cycles`
 * calls of update() (one per control cycle), as CiA 402 drives do in steps;
 * `fault_joint` (1-based; 0: none) reports FAULT with a drive's text. */
typedef struct {
    fake_arm_t arm;
    int enable_cycles;
    int fault_joint;
    bool bus_failed; /* update() fails, then every joint is LOST, as a drive bus gone down */
    bool bus_lost;   /* update() has failed */
    bool wanted;     /* enable(true) asked */
    int progress;    /* update() calls since */
    uint64_t last_update_us;
    int updates;
    hal_arm_event_t pending; /* reported by next_event once, when pending.node != 0 */
    /* homing: joints that must be homed, each joint's state, and a homing that
     * ends after home_cycles updates with the counter's new zero (home_shift) */
    uint32_t home_required;
    hal_home_t home[LS_N_JOINTS];
    uint32_t homing;
    int home_cycles, home_progress;
    double home_shift;
    bool home_fails;
} fake_drives_t;

static int drives_enable(void *self, bool on)
{
    fake_drives_t *d = self;
    d->wanted = on;
    d->progress = 0;
    d->arm.enabled = false;
    return LS_OK;
}

static int drives_command(void *self, const double *q_rad, const double *qd_rad_s)
{
    return arm_command(&((fake_drives_t *)self)->arm, q_rad, qd_rad_s);
}

static int drives_read(void *self, double *q_rad, double *qd_rad_s)
{
    return arm_read(&((fake_drives_t *)self)->arm, q_rad, qd_rad_s);
}

static int drives_update(void *self, uint64_t now_us)
{
    fake_drives_t *d = self;
    d->updates++;
    d->last_update_us = now_us;
    if (d->bus_failed) {
        d->bus_lost = true;
        return LS_EIO;
    }
    if (d->wanted && ++d->progress >= d->enable_cycles) {
        d->arm.enabled = true;
    }
    if (d->homing != 0u && ++d->home_progress >= d->home_cycles) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            if ((d->homing & (1u << j)) != 0u) {
                d->home[j] = d->home_fails ? HAL_HOME_FAILED : HAL_HOME_HOMED;
                d->arm.q[j] += d->home_fails ? 0.0 : d->home_shift; /* the counter's new zero */
            }
        }
        d->homing = 0u;
    }
    return LS_OK;
}

static int drives_home(void *self, uint32_t joint_mask)
{
    fake_drives_t *d = self;
    if (!d->arm.enabled || d->homing != 0u) {
        return LS_EBUSY;
    }
    d->homing = joint_mask;
    d->home_progress = 0;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if ((joint_mask & (1u << j)) != 0u) {
            d->home[j] = HAL_HOME_HOMING;
        }
    }
    return LS_OK;
}

static int drives_status(void *self, hal_joint_status_t *out)
{
    const fake_drives_t *d = self;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        memset(&out[j], 0, sizeof out[j]);
        out[j].node = (uint16_t)(0x21 + j);
        out[j].state = d->arm.enabled ? HAL_JOINT_ENABLED : d->wanted ? HAL_JOINT_ENABLING : HAL_JOINT_OFF;
        if (d->bus_lost) {
            out[j].state = HAL_JOINT_LOST;
            strcpy(out[j].text, "the drive bus fake failed: every drive is lost");
        } else if (j + 1 == d->fault_joint) {
            out[j].state = HAL_JOINT_FAULT;
            out[j].code = 0x8611u;
            strcpy(out[j].text, "FAULT, EMCY 0x8611 following error");
        }
        out[j].home = d->home[j];
        out[j].home_required = (d->home_required & (1u << j)) != 0u;
        if (d->home[j] == HAL_HOME_FAILED) {
            strcpy(out[j].text, "homing failed: the drive reports a homing error (statusword 0x2637, bit 13)");
        }
    }
    return LS_OK;
}

static int drives_next_event(void *self, hal_arm_event_t *out)
{
    fake_drives_t *d = self;
    if (d->pending.node == 0u) {
        return 0;
    }
    *out = d->pending;
    d->pending.node = 0;
    return 1;
}

static const hal_arm_ops_t DRIVES_OPS = { .enable = drives_enable,
                                          .command = drives_command,
                                          .read = drives_read,
                                          .status = drives_status,
                                          .update = drives_update,
                                          .next_event = drives_next_event,
                                          .home = drives_home };

/* ---------------------------------------------------------------- fake DIO */

#define DIO_LOG 64

typedef struct {
    uint32_t levels[2];
    int fail_write;
    size_t n_writes;
    struct {
        uint16_t unit;
        uint32_t on, off;
    } log[DIO_LOG];
} fake_dio_t;

static int dio_unit_count(void *self)
{
    (void)self;
    return 2;
}

static int dio_read(void *self, uint16_t unit, uint32_t *bits)
{
    *bits = ((fake_dio_t *)self)->levels[unit];
    return LS_OK;
}

static int dio_write(void *self, uint16_t unit, uint32_t on, uint32_t off)
{
    fake_dio_t *d = self;
    if (d->fail_write) {
        return LS_EINVAL;
    }
    if (d->n_writes < DIO_LOG) {
        d->log[d->n_writes].unit = unit;
        d->log[d->n_writes].on = on;
        d->log[d->n_writes].off = off;
    }
    d->n_writes++;
    d->levels[unit] = (d->levels[unit] | on) & ~off;
    return LS_OK;
}

static const hal_dio_ops_t DIO_OPS = { .unit_count = dio_unit_count, .read = dio_read, .write = dio_write };

/* ---------------------------------------------------------------- fake sensor, tool, manual device */

typedef struct {
    double force_N[6];
    const fake_arm_t *arm; /* counter mode: values follow the arm's step count */
} fake_sensor_t;

static int sensor_read(void *self, double *values)
{
    fake_sensor_t *s = self;
    for (int i = 0; i < 6; i++) {
        values[i] = s->arm != NULL ? (double)s->arm->steps + (double)i : s->force_N[i];
    }
    return LS_OK;
}

typedef struct {
    char coupled[LS_CTL_TOOL_ID_LEN];
    int n_couple;
    uint32_t bits;
    int couple_status;
} fake_tool_t;

static int tool_couple(void *self, const char *tool_id, bool attach)
{
    fake_tool_t *t = self;
    t->n_couple++;
    if (t->couple_status == LS_OK) {
        snprintf(t->coupled, sizeof t->coupled, "%s", attach ? tool_id : "");
    }
    return t->couple_status;
}

static int tool_set_bits(void *self, uint32_t on, uint32_t off)
{
    fake_tool_t *t = self;
    t->bits = (t->bits | on) & ~off;
    return LS_OK;
}

static int tool_get_bits(void *self, uint32_t *bits)
{
    *bits = ((fake_tool_t *)self)->bits;
    return LS_OK;
}

static const hal_tool_ops_t TOOL_OPS = { .couple = tool_couple, .set_bits = tool_set_bits, .get_bits = tool_get_bits };

typedef struct {
    double twist[6];
    uint32_t buttons;
    bool unplugged;
} fake_manual_t;

static int manual_read(void *self, hal_manual_state_t *out)
{
    const fake_manual_t *m = self;
    memset(out, 0, sizeof *out);
    out->generation = 1;
    if (m->unplugged) {
        return LS_OK;
    }
    out->present = true;
    memcpy(out->twist, m->twist, sizeof out->twist);
    out->buttons = m->buttons;
    return LS_OK;
}

/* ---------------------------------------------------------------- fixture */

typedef struct {
    ls_control_t ctl;
    fake_arm_t arm_state;
    hal_arm_t arm;
    fake_dio_t dio_state;
    hal_dio_t dio;
    fake_sensor_t sensor_state;
    hal_sensor_t sensor;
    fake_tool_t tool_state;
    hal_tool_t tool;
    fake_manual_t manual_state;
    hal_manual_t manual;
    uint64_t now_us;
} fx_t;

static fx_t g_fx; /* ~100 kB: not on the stack */

static fx_t *fx_init(bool with_sensor)
{
    fx_t *f = &g_fx;
    memset(f, 0, sizeof *f);
    memcpy(f->arm_state.q, Q0, sizeof Q0);
    f->arm = (hal_arm_t){ .ops = &ARM_OPS, .self = &f->arm_state, .name = "fake" };
    f->dio = (hal_dio_t){ .ops = &DIO_OPS, .self = &f->dio_state, .name = "fake" };
    f->sensor = (hal_sensor_t){ .name = "force_sensor", .n_values = 6, .read = sensor_read, .self = &f->sensor_state };
    f->tool = (hal_tool_t){ .ops = &TOOL_OPS, .self = &f->tool_state };
    f->manual = (hal_manual_t){ .read = manual_read, .self = &f->manual_state, .stale_ms = 0, .name = "fake" };
    ls_control_config_t cfg = { .model = M,
                                .arm = &f->arm,
                                .dio = &f->dio,
                                .sensors = with_sensor ? &f->sensor : NULL,
                                .n_sensors = with_sensor ? 1u : 0u,
                                .rate_hz = 1000,
                                .world_step = world_step,
                                .world_ctx = &f->arm_state };
    ls_control_init(&f->ctl, &cfg);
    return f;
}

static void cycle(fx_t *f)
{
    f->now_us += 1000u;
    ls_control_cycle(&f->ctl, f->now_us);
}

static ls_ctl_snapshot_t snap(fx_t *f)
{
    ls_ctl_snapshot_t s;
    assert_true(ls_control_snapshot(&f->ctl, &s));
    return s;
}

static void post(fx_t *f, ls_ctl_kind_t kind, uint32_t ref_seq)
{
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.ref_seq = ref_seq;
    assert_true(ls_control_post(&f->ctl, &c));
}

static void post_dio(fx_t *f, ls_ctl_kind_t kind, uint32_t ref_seq, uint16_t unit, uint32_t on, uint32_t off)
{
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.ref_seq = ref_seq;
    c.dio.unit = unit;
    c.dio.on = on;
    c.dio.off = off;
    assert_true(ls_control_post(&f->ctl, &c));
}

static ls_ctl_event_t next(fx_t *f, ls_cev_kind_t kind);

/* Drives on: the fake arm has no status(), so every joint confirms in the
 * cycle that takes the command (hal_arm.h), which reports LS_CEV_ENABLED. */
static void enable(fx_t *f)
{
    post(f, LS_CTL_ENABLE, 1);
    cycle(f);
    assert_true(snap(f).enabled);
    (void)next(f, LS_CEV_ENABLED);
}

/* The next event, which must exist and be of `kind`. */
static ls_ctl_event_t next(fx_t *f, ls_cev_kind_t kind)
{
    ls_ctl_event_t ev;
    assert_true(ls_control_next_event(&f->ctl, &ev));
    assert_int_equal(ev.kind, kind);
    return ev;
}

/* The next motion event of `mkind`, skipping nothing. */
static ls_ctl_event_t next_motion(fx_t *f, ls_motion_event_kind_t mkind)
{
    ls_ctl_event_t ev = next(f, LS_CEV_MOTION);
    assert_int_equal(ev.motion.kind, mkind);
    return ev;
}

static void assert_no_event(fx_t *f)
{
    ls_ctl_event_t ev;
    if (ls_control_next_event(&f->ctl, &ev)) {
        fail_msg("unexpected event kind %d (motion kind %d, text \"%s\")", ev.kind, ev.motion.kind, ev.text);
    }
}

/* Cycle until a motion event of `mkind` arrives (other motion events pass). */
static ls_ctl_event_t run_until(fx_t *f, ls_motion_event_kind_t mkind, int max_cycles)
{
    for (int i = 0; i < max_cycles; i++) {
        cycle(f);
        ls_ctl_event_t ev;
        while (ls_control_next_event(&f->ctl, &ev)) {
            if (ev.kind == LS_CEV_MOTION && ev.motion.kind == mkind) {
                return ev;
            }
            if (ev.kind != LS_CEV_MOTION) {
                fail_msg("unexpected control event %d (\"%s\") while waiting for motion event %d", ev.kind, ev.text,
                         mkind);
            }
        }
    }
    fail_msg("no motion event %d within %d cycles", mkind, max_cycles);
    ls_ctl_event_t none;
    memset(&none, 0, sizeof none);
    return none;
}

/* Fill the plan slot with a joint move of `dq` rad on every joint from the snapshot's set-point. */
static void fill_plan(fx_t *f, double dq, uint32_t ref_seq)
{
    ls_motion_plan_t *p = ls_control_plan_slot(&f->ctl);
    assert_non_null(p);
    ls_ctl_snapshot_t s = snap(f);
    double q1[LS_N_JOINTS];
    for (int j = 0; j < LS_N_JOINTS; j++) {
        q1[j] = s.q_cmd_rad[j] + dq;
    }
    char why[128];
    assert_int_equal(ls_motion_plan_joint(p, M, s.q_cmd_rad, q1, 0.5, 0.5, why, sizeof why), 0);
    p->ref_seq = ref_seq;
    snprintf(p->name, sizeof p->name, "p%u", (unsigned)ref_seq);
}

static void fill_react(fx_t *f, const char *sensor, double dist_m, uint32_t ref_seq)
{
    ls_react_plan_t *p = ls_control_react_slot(&f->ctl);
    assert_non_null(p);
    memset(p, 0, sizeof *p);
    p->kind = LS_REACT_GUARDED;
    p->ref_seq = ref_seq;
    snprintf(p->sensor, sizeof p->sensor, "%s", sensor);
    const double z[6] = { 0 };
    ls_pose_from_xyzrpy(z, p->tool);
    p->dir_tool[2] = 1.0;
    p->dist_m = dist_m;
    p->v_m_s = 0.02;
    p->a_m_s2 = 1.0;
    p->j_m_s3 = 10.0;
    p->a_stop_m_s2 = 4.0;
    p->j_stop_m_s3 = 40.0;
    p->component = 2;
    p->threshold = 10.0;
}

static ls_jog_config_t jog_cfg(void)
{
    ls_jog_config_t c;
    memset(&c, 0, sizeof c);
    c.v_lin_m_s = 0.1;
    c.v_ang_rad_s = 0.3;
    c.a_lin_m_s2 = 1.0;
    c.a_ang_rad_s2 = 3.0;
    c.j_lin_m_s3 = 10.0;
    c.j_ang_rad_s3 = 30.0;
    const double z[6] = { 0 };
    ls_pose_from_xyzrpy(z, c.tool);
    return c;
}

/* ---------------------------------------------------------------- command ring */

static void test_command_ring_full_then_empty(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    /* Full: LS_CTL_QUEUE_LEN commands fit, the next one is refused. */
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        post_dio(f, LS_CTL_DIO_WRITE, i, 0, 1u << (i % 32u), 0);
    }
    ls_ctl_cmd_t extra = { .kind = LS_CTL_DIO_WRITE, .ref_seq = 999 };
    assert_false(ls_control_post(&f->ctl, &extra));
    assert_int_equal(f->dio_state.n_writes, 0);
    /* One cycle drains the ring, in order; the refused one never ran. */
    cycle(f);
    assert_int_equal(f->dio_state.n_writes, LS_CTL_QUEUE_LEN);
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        assert_int_equal(f->dio_state.log[i].on, 1u << (i % 32u));
    }
    /* Empty: a cycle runs no command, and the ring takes a full load again
     * (the indices wrap past the array). */
    cycle(f);
    assert_int_equal(f->dio_state.n_writes, LS_CTL_QUEUE_LEN);
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        post_dio(f, LS_CTL_DIO_WRITE, 100u + i, 1, i, 0);
    }
    assert_false(ls_control_post(&f->ctl, &extra));
    cycle(f);
    assert_int_equal(f->dio_state.n_writes, 2u * LS_CTL_QUEUE_LEN);
    assert_int_equal(f->dio_state.log[LS_CTL_QUEUE_LEN + 5u].on, 5u);
}

/* ---------------------------------------------------------------- event ring */

static void test_event_ring_empty_full_and_events_lost(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    ls_ctl_event_t ev;
    assert_false(ls_control_next_event(&f->ctl, &ev));
    cycle(f);
    assert_false(ls_control_next_event(&f->ctl, &ev));
    /* Every refused DIO write is one LS_CEV_CMD_FAILED: fill the ring... */
    f->dio_state.fail_write = 1;
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        post_dio(f, LS_CTL_DIO_WRITE, 1u + i, 0, 1, 0);
    }
    cycle(f);
    assert_int_equal(snap(f).events_lost, 0);
    /* ...then three more find it full: the loop drops and counts them. */
    for (uint32_t i = 0; i < 3u; i++) {
        post_dio(f, LS_CTL_DIO_WRITE, 500u + i, 0, 1, 0);
    }
    cycle(f);
    assert_int_equal(snap(f).events_lost, 3);
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        ev = next(f, LS_CEV_CMD_FAILED);
        assert_int_equal(ev.ref_seq, 1u + i);
        assert_string_equal(ev.text, "DIO write refused by the backend");
    }
    assert_false(ls_control_next_event(&f->ctl, &ev));
    /* Drained: events flow again and the loss count stays. */
    post_dio(f, LS_CTL_DIO_WRITE, 77, 0, 1, 0);
    cycle(f);
    assert_int_equal(next(f, LS_CEV_CMD_FAILED).ref_seq, 77);
    assert_int_equal(snap(f).events_lost, 3);
}

/* ---------------------------------------------------------------- plan slot */

static void test_plan_slot_hand_over(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    enable(f);
    fill_plan(f, 0.05, 10);
    assert_true(ls_control_start_plan(&f->ctl, 10));
    /* Until the loop takes it, the slot is not the comms thread's. */
    assert_null(ls_control_plan_slot(&f->ctl));
    assert_null(ls_control_plan_slot(&f->ctl));
    cycle(f);
    assert_non_null(ls_control_plan_slot(&f->ctl));
    assert_int_equal(snap(f).phase, LS_MOTION_RUNNING);
    /* The loop copied the plan: scribbling on the slot changes nothing. */
    memset(ls_control_plan_slot(&f->ctl), 0xA5, sizeof(ls_motion_plan_t));
    ls_ctl_event_t done = run_until(f, LS_MEV_DONE, 5000);
    assert_int_equal(done.ref_seq, 10);
    assert_string_equal(done.motion.name, "p10");
    ls_ctl_snapshot_t s = snap(f);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_true(fabs(s.q_rad[j] - (Q0[j] + 0.05)) < 1e-9);
    }
    assert_int_equal(s.phase, LS_MOTION_IDLE);
}

static void test_plan_slot_freed_when_ring_full_or_start_refused(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        post(f, LS_CTL_AUX_DONE, i);
    }
    fill_plan(f, 0.05, 3);
    assert_false(ls_control_start_plan(&f->ctl, 3));
    assert_non_null(ls_control_plan_slot(&f->ctl)); /* not left busy */
    cycle(f);
    /* Drives off: the loop refuses the start and frees the slot. */
    assert_true(ls_control_start_plan(&f->ctl, 4));
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_CMD_FAILED);
    assert_int_equal(ev.ref_seq, 4);
    assert_string_equal(ev.text, "the drives are off");
    assert_non_null(ls_control_plan_slot(&f->ctl));
    assert_int_equal(snap(f).phase, LS_MOTION_IDLE);
    /* A second start while one runs: refused, the first goes on. */
    enable(f);
    fill_plan(f, 0.05, 5);
    assert_true(ls_control_start_plan(&f->ctl, 5));
    cycle(f);
    fill_plan(f, 0.1, 6);
    assert_true(ls_control_start_plan(&f->ctl, 6));
    cycle(f);
    ev = next(f, LS_CEV_CMD_FAILED);
    assert_int_equal(ev.ref_seq, 6);
    assert_string_equal(ev.text, "a motion is already running");
    assert_int_equal(run_until(f, LS_MEV_DONE, 5000).ref_seq, 5);
}

/* ---------------------------------------------------------------- command kinds */

/* Drives that confirm in steps: the loop waits for every joint, never
 * blocks, and reports LS_CEV_ENABLED once, with the arm held where it is. */
static fake_drives_t g_drives;
static hal_arm_t g_drives_arm;

static fx_t *fx_drives(int enable_cycles, uint32_t timeout_ms)
{
    fx_t *f = fx_init(false);
    memset(&g_drives, 0, sizeof g_drives);
    memcpy(g_drives.arm.q, Q0, sizeof Q0);
    g_drives.enable_cycles = enable_cycles;
    g_drives_arm = (hal_arm_t){ .ops = &DRIVES_OPS, .self = &g_drives, .name = "drives" };
    ls_control_config_t cfg = { .model = M, .arm = &g_drives_arm, .rate_hz = 1000, .enable_timeout_ms = timeout_ms };
    ls_control_init(&f->ctl, &cfg);
    return f;
}

static void test_enable_waits_for_every_joint_to_confirm(void **state)
{
    (void)state;
    fx_t *f = fx_drives(5, 0);
    post(f, LS_CTL_ENABLE, 12);
    for (int i = 0; i < 4; i++) {
        cycle(f);
        const ls_ctl_snapshot_t s = snap(f);
        assert_false(s.enabled);
        assert_true(s.enabling);
        assert_int_equal(s.joint_state[2], HAL_JOINT_ENABLING);
        assert_no_event(f);
    }
    cycle(f); /* the fifth update confirmed: the next cycle's status sees it */
    cycle(f);
    const ls_ctl_snapshot_t s = snap(f);
    assert_true(s.enabled);
    assert_false(s.enabling);
    assert_int_equal(s.joint_state[5], HAL_JOINT_ENABLED);
    assert_int_equal(next(f, LS_CEV_ENABLED).ref_seq, 12);
    assert_no_event(f);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_true(s.q_cmd_rad[j] == Q0[j]); /* holds where it is */
    }
    /* update() ran once per cycle with the cycle's time */
    assert_int_equal(g_drives.updates, 6);
    assert_int_equal(g_drives.last_update_us, f->now_us);
}

static void test_enable_fails_naming_the_joint_its_node_and_what_its_drive_said(void **state)
{
    (void)state;
    fx_t *f = fx_drives(50, 0);
    post(f, LS_CTL_ENABLE, 13);
    cycle(f);
    cycle(f);
    g_drives.fault_joint = 3;
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_ENABLE_FAILED);
    assert_int_equal(ev.ref_seq, 13);
    assert_string_equal(ev.text, "joint 3 (node 0x23): FAULT, EMCY 0x8611 following error");
    assert_false(g_drives.wanted); /* every drive asked off again */
    assert_false(snap(f).enabling);
    assert_false(snap(f).enabled);
    assert_no_event(f);
}

static void test_enable_times_out_naming_a_joint_still_enabling(void **state)
{
    (void)state;
    fx_t *f = fx_drives(1000000, 20);
    post(f, LS_CTL_ENABLE, 14);
    for (int i = 0; i < 20; i++) {
        cycle(f);
        assert_no_event(f);
    }
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_ENABLE_FAILED);
    assert_string_equal(ev.text, "joint 1 (node 0x21): not enabled within 20 ms (ENABLING)");
    assert_false(g_drives.wanted);
    assert_false(snap(f).enabling);
}

/* The bus fails while the drives enable: the enable ends with the bus's
 * words (and the enable's one event), as it would were the drives on. */
static void test_a_bus_failing_during_an_enable_fails_the_enable(void **state)
{
    (void)state;
    fx_t *f = fx_drives(50, 0);
    post(f, LS_CTL_ENABLE, 18);
    cycle(f);
    cycle(f);
    assert_no_event(f);
    g_drives.bus_failed = true;
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_ENABLE_FAILED);
    assert_int_equal(ev.ref_seq, 18);
    assert_string_equal(ev.text, "the drive bus fake failed: every drive is lost");
    assert_false(g_drives.wanted);
    assert_false(snap(f).enabling);
    assert_false(snap(f).enabled);
    cycle(f);
    assert_no_event(f);
}

static void test_disable_cancels_an_enable_in_progress(void **state)
{
    (void)state;
    fx_t *f = fx_drives(50, 0);
    post(f, LS_CTL_ENABLE, 15);
    cycle(f);
    post(f, LS_CTL_DISABLE, 16);
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_ENABLE_FAILED);
    assert_int_equal(ev.ref_seq, 15);
    assert_string_equal(ev.text, "enabling cancelled: the drives were switched off");
    assert_false(g_drives.wanted);
    for (int i = 0; i < 60; i++) {
        cycle(f);
    }
    assert_false(snap(f).enabled);
    assert_no_event(f);
}

static void test_a_joint_that_faults_under_control_faults_the_arm(void **state)
{
    (void)state;
    fx_t *f = fx_drives(1, 0);
    post(f, LS_CTL_ENABLE, 17);
    cycle(f);
    cycle(f);
    (void)next(f, LS_CEV_ENABLED);
    g_drives.fault_joint = 6;
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_FAULT);
    assert_string_equal(ev.text, "joint 6 (node 0x26): FAULT, EMCY 0x8611 following error");
    assert_false(snap(f).enabled);
    assert_false(g_drives.wanted);
    assert_int_equal(snap(f).joint_state[5], HAL_JOINT_FAULT);
}

/* A drive that faults during a motion: the others come to rest along the
 * path at the model's maximum deceleration (the category-1 stop), then every
 * drive goes off; the failed joint is left out of the following check. */
static void test_a_drive_fault_while_moving_stops_the_others_along_the_path_then_disables(void **state)
{
    (void)state;
    fx_t *f = fx_drives(1, 0);
    post(f, LS_CTL_ENABLE, 18);
    cycle(f);
    cycle(f);
    (void)next(f, LS_CEV_ENABLED);
    fill_plan(f, 0.6, 19);
    assert_true(ls_control_start_plan(&f->ctl, 19));
    for (int i = 0; i < 300; i++) {
        cycle(f);
    }
    assert_int_equal(snap(f).phase, LS_MOTION_RUNNING);
    double before[LS_N_JOINTS];
    memcpy(before, snap(f).q_cmd_rad, sizeof before);
    g_drives.fault_joint = 2;
    g_drives.arm.q[1] += 0.2; /* the failed joint drops away from its set-point */
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_FAULT);
    assert_string_equal(ev.text, "joint 2 (node 0x22): FAULT, EMCY 0x8611 following error");
    ls_ctl_snapshot_t s = snap(f);
    assert_true(s.enabled); /* still under control: stopping */
    assert_int_equal(s.phase, LS_MOTION_STOPPING);
    int cycles = 0;
    double last = s.q_cmd_rad[0];
    while (snap(f).enabled && cycles < 2000) {
        cycle(f);
        cycles++;
        const double q = snap(f).q_cmd_rad[0];
        assert_true(q >= last - 1e-12); /* joint 1 goes on the same way until it rests */
        last = q;
    }
    assert_false(snap(f).enabled);
    assert_false(g_drives.wanted);
    assert_true(cycles > 20);      /* it came to rest on a ramp, not at once */
    assert_true(last > before[0]); /* further along its path than at the fault */
    ls_ctl_event_t e;
    while (ls_control_next_event(&f->ctl, &e)) {
        assert_int_not_equal(e.kind, LS_CEV_FAULT); /* one fault: the following check left joint 2 out */
    }
}

static void post_home(fx_t *f, uint32_t joints, uint32_t ref_seq)
{
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = LS_CTL_HOME;
    c.ref_seq = ref_seq;
    c.home.joints = joints;
    assert_true(ls_control_post(&f->ctl, &c));
}

/* Joint 2 counts from an incremental encoder: nothing moves before its
 * homing, which holds the new measured position when it ends. */
static void test_motion_waits_for_a_required_homing_which_holds_the_new_position(void **state)
{
    (void)state;
    fx_t *f = fx_drives(1, 0);
    g_drives.home_required = 1u << 1;
    g_drives.home_cycles = 5;
    g_drives.home_shift = 0.3;
    post(f, LS_CTL_ENABLE, 30);
    cycle(f);
    cycle(f);
    (void)next(f, LS_CEV_ENABLED);
    ls_ctl_snapshot_t s = snap(f);
    assert_int_equal(s.home_required, 1u << 1);
    assert_int_equal(s.unhomed, 1u << 1);
    fill_plan(f, 0.6, 31);
    assert_true(ls_control_start_plan(&f->ctl, 31));
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_CMD_FAILED);
    assert_int_equal(ev.ref_seq, 31);
    assert_string_equal(ev.text, "joint 2 must be homed first (sendCommand home)");
    assert_int_equal(snap(f).phase, LS_MOTION_IDLE);
    /* the homing: under way, then ended with the arm holding where joint 2 now reads */
    post_home(f, 1u << 1, 32);
    cycle(f);
    s = snap(f);
    assert_true(s.homing);
    assert_int_equal(s.joint_home[1], HAL_HOME_HOMING);
    assert_no_event(f);
    for (int i = 0; i < 6; i++) {
        cycle(f);
    }
    ev = next(f, LS_CEV_HOMED);
    assert_int_equal(ev.ref_seq, 32);
    assert_no_event(f);
    s = snap(f);
    assert_false(s.homing);
    assert_int_equal(s.unhomed, 0u);
    assert_int_equal(s.joint_home[1], HAL_HOME_HOMED);
    assert_true(s.q_cmd_rad[1] == Q0[1] + 0.3); /* no jump back to the old set-point */
    assert_true(s.q_cmd_rad[0] == Q0[0]);
    /* and now a plan runs */
    fill_plan(f, 0.6, 33);
    assert_true(ls_control_start_plan(&f->ctl, 33));
    cycle(f);
    assert_int_equal(snap(f).phase, LS_MOTION_RUNNING);
}

static void test_a_homing_is_refused_off_or_busy_and_a_failure_names_the_joint(void **state)
{
    (void)state;
    fx_t *f = fx_drives(1, 0);
    post_home(f, 1u << 1, 40);
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_HOME_FAILED);
    assert_int_equal(ev.ref_seq, 40);
    assert_string_equal(ev.text, "the drives are off: activate first");
    post(f, LS_CTL_ENABLE, 41);
    cycle(f);
    cycle(f);
    (void)next(f, LS_CEV_ENABLED);
    g_drives.home_cycles = 3;
    g_drives.home_fails = true;
    post_home(f, 1u << 2, 42);
    post_home(f, 1u << 2, 43); /* while one runs */
    cycle(f);
    ev = next(f, LS_CEV_HOME_FAILED);
    assert_int_equal(ev.ref_seq, 43);
    assert_string_equal(ev.text, "a homing runs already");
    for (int i = 0; i < 4; i++) {
        cycle(f);
    }
    ev = next(f, LS_CEV_HOME_FAILED);
    assert_int_equal(ev.ref_seq, 42);
    assert_string_equal(ev.text, "joint 3 (node 0x23): homing failed: the drive reports a homing error (statusword "
                                 "0x2637, bit 13)");
    assert_true(snap(f).enabled); /* a failed homing is no fault: the arm holds */
    /* an arm without homing says so */
    fx_t *g = fx_init(false);
    enable(g);
    post_home(g, 1u, 44);
    cycle(g);
    ev = next(g, LS_CEV_HOME_FAILED);
    assert_string_equal(ev.text, "this arm has no homing: its joints' positions are absolute (LS_EUNSUPPORTED)");
}

static void test_the_drives_reports_reach_the_comms_thread(void **state)
{
    (void)state;
    fx_t *f = fx_drives(1, 0);
    g_drives.pending = (hal_arm_event_t){ .joint = 3, .node = 0x24, .code = 0x2310, .reg = 0x03, .is_emcy = true };
    strcpy(g_drives.pending.text, "EMCY 0x2310 continuous over-current");
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_ARM_EVENT);
    assert_int_equal(ev.arm.node, 0x24);
    assert_int_equal(ev.arm.code, 0x2310);
    assert_string_equal(ev.arm.text, "EMCY 0x2310 continuous over-current");
    assert_no_event(f);
}

static void test_enable_and_disable(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    assert_false(snap(f).enabled);
    f->arm_state.fail_enable = 1;
    post(f, LS_CTL_ENABLE, 7);
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_ENABLE_FAILED);
    assert_int_equal(ev.ref_seq, 7);
    assert_string_equal(ev.text, "the arm backend refused to enable the drives (LS_EIO)");
    assert_false(snap(f).enabled);
    f->arm_state.fail_enable = 0;
    enable(f);
    assert_true(f->arm_state.enabled);
    /* Idle: DISABLE switches the drives off at once. */
    post(f, LS_CTL_DISABLE, 8);
    cycle(f);
    assert_false(snap(f).enabled);
    assert_false(f->arm_state.enabled);
    assert_no_event(f);
}

/* A simulated world advances once per cycle, with the drives off (brakes) too. */
static void test_world_steps_every_cycle(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    assert_int_equal(f->arm_state.steps, 0);
    cycle(f);
    cycle(f);
    assert_int_equal(f->arm_state.steps, 2);
    enable(f);
    cycle(f);
    assert_int_equal(f->arm_state.steps, 4);
}

static void test_enable_without_arm_fails(void **state)
{
    (void)state;
    ls_control_t *c = &g_fx.ctl;
    ls_control_config_t cfg = { .model = M, .rate_hz = 1000 };
    ls_control_init(c, &cfg);
    ls_ctl_cmd_t cmd = { .kind = LS_CTL_ENABLE, .ref_seq = 9 };
    assert_true(ls_control_post(c, &cmd));
    ls_control_cycle(c, 1000);
    ls_ctl_event_t ev;
    assert_true(ls_control_next_event(c, &ev));
    assert_int_equal(ev.kind, LS_CEV_ENABLE_FAILED);
    assert_non_null(strstr(ev.text, "no arm backend is composed"));
    ls_ctl_snapshot_t s;
    assert_true(ls_control_snapshot(c, &s));
    assert_false(s.enabled);
    assert_false(s.enabling);
    assert_int_equal(s.cycle, 1);
}

static void test_disable_while_moving_stops_along_the_path_first(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    enable(f);
    fill_plan(f, 0.3, 11);
    assert_true(ls_control_start_plan(&f->ctl, 11));
    for (int i = 0; i < 100; i++) {
        cycle(f);
    }
    post(f, LS_CTL_DISABLE, 12);
    cycle(f);
    ls_ctl_snapshot_t s = snap(f);
    assert_true(s.enabled); /* still braking */
    assert_int_equal(s.phase, LS_MOTION_STOPPING);
    run_until(f, LS_MEV_PAUSED, 5000);
    cycle(f);
    s = snap(f);
    assert_false(s.enabled);
    assert_false(f->arm_state.enabled);
    assert_int_equal(s.phase, LS_MOTION_IDLE);
}

static void test_stop_resume_abort(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    enable(f);
    post(f, LS_CTL_RESUME, 20); /* nothing paused */
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_CMD_FAILED);
    assert_int_equal(ev.ref_seq, 20);
    assert_string_equal(ev.text, "no paused motion to resume");
    fill_plan(f, 0.3, 21);
    assert_true(ls_control_start_plan(&f->ctl, 21));
    for (int i = 0; i < 50; i++) {
        cycle(f);
    }
    post(f, LS_CTL_STOP, 22);
    run_until(f, LS_MEV_PAUSED, 5000);
    ls_ctl_snapshot_t s = snap(f);
    assert_int_equal(s.phase, LS_MOTION_PAUSED);
    double held = s.q_rad[0];
    for (int i = 0; i < 20; i++) {
        cycle(f);
    }
    assert_true(snap(f).q_rad[0] == held); /* paused: the set-point stays */
    post(f, LS_CTL_RESUME, 23);
    cycle(f);
    assert_int_equal(snap(f).phase, LS_MOTION_RUNNING);
    for (int i = 0; i < 20; i++) {
        cycle(f);
    }
    assert_true(snap(f).q_rad[0] > held);
    post(f, LS_CTL_ABORT, 24);
    cycle(f);
    s = snap(f);
    assert_int_equal(s.phase, LS_MOTION_IDLE);
    assert_true(s.enabled); /* abort drops the motion, not the drives */
    held = s.q_rad[0];
    for (int i = 0; i < 20; i++) {
        cycle(f);
    }
    assert_true(snap(f).q_rad[0] == held);
    assert_no_event(f);
}

static void test_aux_done_continues_a_path(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    enable(f);
    static ls_motion_program_t prog;
    memset(&prog, 0, sizeof prog);
    ls_ctl_snapshot_t s = snap(f);
    double q1[LS_N_JOINTS];
    for (int j = 0; j < LS_N_JOINTS; j++) {
        q1[j] = s.q_cmd_rad[j] + 0.02;
    }
    char why[128];
    assert_int_equal(ls_motion_seg_joint(&prog.seg[0], M, s.q_cmd_rad, q1, 0.5, 0.5, why, sizeof why), 0);
    prog.seg[0].n_aux = 1;
    snprintf(prog.seg[0].aux[0], sizeof prog.seg[0].aux[0], "setOutput 1");
    prog.n = 1;
    ls_motion_plan_t *p = ls_control_plan_slot(&f->ctl);
    assert_non_null(p);
    assert_int_equal(ls_motion_plan_path(p, &prog, 1, false, "path"), 0);
    p->ref_seq = 30;
    assert_true(ls_control_start_plan(&f->ctl, 30));
    ls_ctl_event_t ev = run_until(f, LS_MEV_AUX, 5000);
    assert_string_equal(ev.motion.text, "setOutput 1");
    /* The path waits for the auxiliary command... */
    for (int i = 0; i < 200; i++) {
        cycle(f);
    }
    assert_no_event(f);
    assert_int_equal(snap(f).phase, LS_MOTION_RUNNING);
    /* ...and ends once it is done. */
    post(f, LS_CTL_AUX_DONE, 31);
    ev = run_until(f, LS_MEV_DONE, 5000);
    assert_int_equal(ev.ref_seq, 30);
}

static void test_estop_line_faults_and_disables(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    post_dio(f, LS_CTL_ESTOP_LINE, 40, 1, 0x4, 0);
    enable(f);
    f->dio_state.levels[1] = 0x2; /* another input: no fault */
    cycle(f);
    next(f, LS_CEV_DIO_CHANGED);
    assert_true(snap(f).enabled);
    f->dio_state.levels[1] = 0x6;
    cycle(f);
    next(f, LS_CEV_DIO_CHANGED);
    ls_ctl_event_t ev = next(f, LS_CEV_FAULT);
    assert_string_equal(ev.text, "e-stop input active");
    assert_false(snap(f).enabled);
    assert_false(f->arm_state.enabled);
    /* Line 0 (none): the same input no longer faults. */
    post_dio(f, LS_CTL_ESTOP_LINE, 41, 1, 0, 0);
    f->dio_state.levels[1] = 0x0;
    post(f, LS_CTL_ENABLE, 1);
    cycle(f);
    next(f, LS_CEV_DIO_CHANGED); /* read before the drives' states */
    next(f, LS_CEV_ENABLED);
    f->dio_state.levels[1] = 0x4;
    cycle(f);
    next(f, LS_CEV_DIO_CHANGED);
    assert_no_event(f);
    assert_true(snap(f).enabled);
}

static void test_arm_command_failure_is_a_fault(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    enable(f);
    f->arm_state.fail_command = 1;
    cycle(f);
    assert_string_equal(next(f, LS_CEV_FAULT).text, "arm command failed");
    assert_false(snap(f).enabled);
}

static void test_react_slot_hand_over(void **state)
{
    (void)state;
    fx_t *f = fx_init(true);
    /* The sensor named in the plan must be composed. */
    enable(f);
    fill_react(f, "laser_standoff_sensor", 0.01, 50);
    assert_true(ls_control_start_react(&f->ctl, 50));
    assert_null(ls_control_react_slot(&f->ctl));
    cycle(f);
    assert_non_null(ls_control_react_slot(&f->ctl));
    ls_ctl_event_t ev = next(f, LS_CEV_CMD_FAILED);
    assert_int_equal(ev.ref_seq, 50);
    assert_string_equal(ev.text, "the move's sensor is not composed");
    /* A guarded move in free space ends at its maximum distance. */
    fill_react(f, "force_sensor", 0.005, 51);
    assert_true(ls_control_start_react(&f->ctl, 51));
    cycle(f);
    assert_true(snap(f).react_active);
    assert_int_equal(snap(f).phase, LS_MOTION_RUNNING);
    ev = run_until(f, LS_MEV_REACT_END, 5000);
    assert_int_equal(ev.ref_seq, 51);
    assert_int_equal(ev.motion.index, LS_REACT_END_MAX_DISTANCE);
    assert_true(fabs(ev.react.travelled_m - 0.005) < 1e-6);
    assert_false(snap(f).react_active);
    /* A contact on the way: the threshold (10 N on Fz) ends it, and the
     * report carries the reading. ABORT of a running one: REACT_END aborted. */
    fill_react(f, "force_sensor", 0.05, 52);
    assert_true(ls_control_start_react(&f->ctl, 52));
    for (int i = 0; i < 20; i++) {
        cycle(f);
    }
    post(f, LS_CTL_ABORT, 53);
    ev = run_until(f, LS_MEV_REACT_END, 2);
    assert_int_equal(ev.ref_seq, 52);
    assert_int_equal(ev.motion.index, LS_REACT_END_ABORTED);
    assert_false(snap(f).react_active);
}

static void test_react_refused_when_off_or_busy_and_freed_when_ring_full(void **state)
{
    (void)state;
    fx_t *f = fx_init(true);
    fill_react(f, "force_sensor", 0.01, 60);
    assert_true(ls_control_start_react(&f->ctl, 60));
    cycle(f);
    assert_string_equal(next(f, LS_CEV_CMD_FAILED).text, "the drives are off");
    enable(f);
    fill_plan(f, 0.2, 61);
    assert_true(ls_control_start_plan(&f->ctl, 61));
    cycle(f);
    fill_react(f, "force_sensor", 0.01, 62);
    assert_true(ls_control_start_react(&f->ctl, 62));
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_CMD_FAILED);
    assert_int_equal(ev.ref_seq, 62);
    assert_string_equal(ev.text, "a motion is already running");
    post(f, LS_CTL_ABORT, 63);
    cycle(f);
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        post(f, LS_CTL_AUX_DONE, i);
    }
    fill_react(f, "force_sensor", 0.01, 64);
    assert_false(ls_control_start_react(&f->ctl, 64));
    assert_non_null(ls_control_react_slot(&f->ctl));
}

static void test_manual_jogging(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    ls_jog_config_t jog = jog_cfg();
    assert_false(ls_control_manual_on(&f->ctl));
    assert_true(ls_control_set_manual(&f->ctl, &f->manual, &jog, NULL, 70));
    /* Plans and guarded moves are refused at once while jogging is on. */
    assert_true(ls_control_manual_on(&f->ctl));
    assert_null(ls_control_plan_slot(&f->ctl));
    assert_null(ls_control_react_slot(&f->ctl));
    cycle(f);
    assert_true(snap(f).manual_on);
    assert_no_event(f); /* drives off: not ready yet */
    post(f, LS_CTL_ENABLE, 71);
    cycle(f);
    assert_int_equal(next(f, LS_CEV_ENABLED).ref_seq, 71);
    ls_ctl_event_t ev = next_motion(f, LS_MEV_JOG);
    assert_int_equal(ev.motion.index, 0);
    assert_string_equal(ev.motion.text, "ready");
    assert_int_equal(ev.ref_seq, 71);
    /* The device's twist moves the set-point. */
    double P0[16], P1[16];
    ls_ctl_snapshot_t s = snap(f);
    memcpy(P0, s.flange_pose, sizeof P0);
    assert_false(s.jogging);
    f->manual_state.twist[2] = 1.0;
    for (int i = 0; i < 200; i++) {
        cycle(f);
    }
    s = snap(f);
    assert_true(s.jogging);
    memcpy(P1, s.flange_pose, sizeof P1);
    double moved = sqrt((P1[12] - P0[12]) * (P1[12] - P0[12]) + (P1[13] - P0[13]) * (P1[13] - P0[13]) +
                        (P1[14] - P0[14]) * (P1[14] - P0[14]));
    assert_true(moved > 0.005);
    /* Off: the set-point holds and plans are possible again. */
    f->manual_state.twist[2] = 0.0;
    assert_true(ls_control_set_manual(&f->ctl, NULL, NULL, NULL, 72));
    assert_false(ls_control_manual_on(&f->ctl));
    cycle(f);
    s = snap(f);
    assert_false(s.manual_on);
    assert_false(s.jogging);
    assert_non_null(ls_control_plan_slot(&f->ctl));
    /* A full ring: the switch is refused and manual_on does not change. */
    assert_true(ls_control_set_manual(&f->ctl, &f->manual, &jog, NULL, 73));
    cycle(f);
    next_motion(f, LS_MEV_JOG);
    for (uint32_t i = 0; i < LS_CTL_QUEUE_LEN; i++) {
        post(f, LS_CTL_AUX_DONE, i);
    }
    assert_false(ls_control_set_manual(&f->ctl, NULL, NULL, NULL, 74));
    assert_true(ls_control_manual_on(&f->ctl));
}

/* The manual events of the ring (other events are dropped); the count. */
static int manual_events(fx_t *f, ls_manual_event_kind_t kind, int32_t value)
{
    int n = 0;
    ls_ctl_event_t ev;
    while (ls_control_next_event(&f->ctl, &ev)) {
        n += ev.kind == LS_CEV_MANUAL && ev.manual.kind == kind && ev.manual.value == value;
    }
    return n;
}

static double flange_speed(fx_t *f, double P0[3])
{
    ls_ctl_snapshot_t s = snap(f);
    double d = 0.0;
    for (int i = 0; i < 3; i++) {
        d += (s.flange_pose[12 + i] - P0[i]) * (s.flange_pose[12 + i] - P0[i]);
        P0[i] = s.flange_pose[12 + i];
    }
    return sqrt(d) / 1e-3;
}

/* A teach pendant through the loop: the switch held when the drives come on
 * starts nothing; pressed again, the jog follows; released, the tip brakes
 * on the jog's ramp (v / a + a / j = 0.2 s from 0.1 m/s at 1 m/s^2 and
 * 10 m/s^3) and stays still; unplugged, the loop reports it once. */
static void test_the_enabling_switch_gates_the_jog_and_a_release_brakes_on_the_ramp(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    ls_jog_config_t jog = jog_cfg();
    ls_manual_config_t gate = { .enabling_switch = true };
    assert_true(ls_control_set_manual(&f->ctl, &f->manual, &jog, &gate, 90));
    cycle(f);
    f->manual_state.buttons = HAL_MANUAL_BTN_ENABLE;
    f->manual_state.twist[0] = 1.0;
    post(f, LS_CTL_ENABLE, 91);
    for (int i = 0; i < 100; i++) {
        cycle(f);
        assert_false(snap(f).jogging);
    }
    assert_int_equal(manual_events(f, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_HELD_OVER), 1);
    f->manual_state.buttons = 0;
    cycle(f);
    f->manual_state.buttons = HAL_MANUAL_BTN_ENABLE;
    cycle(f);
    assert_int_equal(manual_events(f, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_ENABLED), 1);
    double P[3] = { 0 };
    (void)flange_speed(f, P);
    double v_jog = 0.0;
    for (int i = 0; i < 500; i++) {
        cycle(f);
        v_jog = flange_speed(f, P);
    }
    assert_true(fabs(v_jog - 0.1) < 1e-3); /* at the jog speed */
    f->manual_state.buttons = 0;           /* released: the tip brakes on the ramp */
    int moving = 0;
    double v_prev = 0.1;
    for (int i = 0; i < 400; i++) {
        cycle(f);
        const double v = flange_speed(f, P);
        assert_true(v <= v_prev + 1e-6); /* never speeds up */
        v_prev = v;
        moving += snap(f).jogging;
    }
    assert_in_range(moving, 195, 205);
    assert_true(v_prev < 1e-9);
    assert_int_equal(manual_events(f, LS_MANUAL_EV_SWITCH, LS_MANUAL_SWITCH_RELEASED), 1);
    f->manual_state.unplugged = true;
    cycle(f);
    cycle(f);
    assert_int_equal(manual_events(f, LS_MANUAL_EV_LOST, LS_MANUAL_LOST_ABSENT), 1);
    f->manual_state.unplugged = false;
    cycle(f);
    assert_int_equal(manual_events(f, LS_MANUAL_EV_FOUND, 1), 1);
}

/* The frame button changes the jog's axes: in the base frame +x moves the
 * tip along the base's x whatever the tool's orientation. */
static void test_the_frame_button_switches_the_jog_to_the_base_frame(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    ls_jog_config_t jog = jog_cfg();
    assert_true(ls_control_set_manual(&f->ctl, &f->manual, &jog, NULL, 92));
    post(f, LS_CTL_ENABLE, 93);
    cycle(f);
    f->manual_state.buttons = HAL_MANUAL_BTN_FRAME;
    cycle(f);
    f->manual_state.buttons = 0;
    cycle(f);
    assert_int_equal(manual_events(f, LS_MANUAL_EV_FRAME, LS_JOG_BASE), 1);
    ls_ctl_snapshot_t s0 = snap(f);
    f->manual_state.twist[0] = 1.0;
    for (int i = 0; i < 300; i++) {
        cycle(f);
    }
    ls_ctl_snapshot_t s1 = snap(f);
    const double dx = s1.flange_pose[12] - s0.flange_pose[12];
    const double dy = s1.flange_pose[13] - s0.flange_pose[13];
    const double dz = s1.flange_pose[14] - s0.flange_pose[14];
    assert_true(dx > 0.01);
    assert_true(fabs(dy) < 1e-6 * dx && fabs(dz) < 1e-6 * dx);
}

static void test_tool_couple_and_bits(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    ls_ctl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = LS_CTL_TOOL_COUPLE;
    c.ref_seq = 80;
    c.tool.dev = &f->tool;
    snprintf(c.tool.id, sizeof c.tool.id, "gripper");
    c.tool.attach = true;
    assert_true(ls_control_post(&f->ctl, &c));
    cycle(f);
    ls_ctl_event_t ev = next_motion(f, LS_MEV_TOOL);
    assert_int_equal(ev.ref_seq, 80);
    assert_int_equal(ev.motion.index, LS_OK);
    assert_string_equal(ev.motion.name, "gripper");
    assert_string_equal(ev.motion.text, "couple");
    assert_string_equal(f->tool_state.coupled, "gripper");
    /* The HAL's refusal is reported as its status. */
    f->tool_state.couple_status = LS_EINVAL;
    c.ref_seq = 81;
    c.tool.attach = false;
    assert_true(ls_control_post(&f->ctl, &c));
    cycle(f);
    ev = next_motion(f, LS_MEV_TOOL);
    assert_int_equal(ev.motion.index, LS_EINVAL);
    assert_string_equal(ev.motion.text, "uncouple");
    /* Bits: the event carries the tool's bits after the change. */
    memset(&c, 0, sizeof c);
    c.kind = LS_CTL_TOOL_BITS;
    c.ref_seq = 82;
    c.tool.dev = &f->tool;
    c.tool.on = 0x5;
    assert_true(ls_control_post(&f->ctl, &c));
    c.ref_seq = 83;
    c.tool.on = 0x8;
    c.tool.off = 0x1;
    assert_true(ls_control_post(&f->ctl, &c));
    cycle(f);
    ev = next_motion(f, LS_MEV_TOOL);
    assert_int_equal(ev.motion.index, LS_OK);
    assert_string_equal(ev.motion.text, "bits");
    assert_int_equal(ev.dio.on, 0x5);
    ev = next_motion(f, LS_MEV_TOOL);
    assert_int_equal(ev.ref_seq, 83);
    assert_int_equal(ev.dio.on, 0xC);
    /* No device: LS_ENODEV. */
    c.tool.dev = NULL;
    c.ref_seq = 84;
    assert_true(ls_control_post(&f->ctl, &c));
    cycle(f);
    assert_int_equal(next_motion(f, LS_MEV_TOOL).motion.index, LS_ENODEV);
    /* Coupling while a motion runs: LS_EAGAIN, the tool is not touched. */
    enable(f);
    fill_plan(f, 0.1, 85);
    assert_true(ls_control_start_plan(&f->ctl, 85));
    cycle(f);
    int calls = f->tool_state.n_couple;
    memset(&c, 0, sizeof c);
    c.kind = LS_CTL_TOOL_COUPLE;
    c.ref_seq = 86;
    c.tool.dev = &f->tool;
    c.tool.attach = true;
    assert_true(ls_control_post(&f->ctl, &c));
    cycle(f);
    ev = next_motion(f, LS_MEV_TOOL);
    assert_int_equal(ev.ref_seq, 86);
    assert_int_equal(ev.motion.index, LS_EAGAIN);
    assert_int_equal(f->tool_state.n_couple, calls);
}

static void test_dio_write(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    post_dio(f, LS_CTL_DIO_WRITE, 90, 1, 0x3, 0x0);
    post_dio(f, LS_CTL_DIO_WRITE, 91, 1, 0x0, 0x1);
    cycle(f);
    assert_int_equal(f->dio_state.n_writes, 2);
    assert_int_equal(f->dio_state.log[0].unit, 1);
    assert_int_equal(f->dio_state.log[1].off, 0x1);
    /* The loop reads the levels back the next cycle and reports the change. */
    cycle(f);
    ls_ctl_event_t ev = next(f, LS_CEV_DIO_CHANGED);
    assert_int_equal(ev.dio.on, 0x2);
    assert_int_equal(snap(f).dio[1], 0x2);
}

/* ---------------------------------------------------------------- seqlock */

typedef struct {
    ls_control_t *ctl;
    atomic_bool stop;
    atomic_ulong cycles;
} writer_t;

static void *writer_main(void *arg)
{
    writer_t *w = arg;
    uint64_t n = 0;
    while (!atomic_load_explicit(&w->stop, memory_order_relaxed)) {
        n++;
        ls_control_cycle(w->ctl, n * 1000u + 7u);
        atomic_store_explicit(&w->cycles, (unsigned long)n, memory_order_relaxed);
    }
    return NULL;
}

/* Every field is a function of the cycle number: a copy mixing two
 * publishes fails one of these. */
static void check_published(const ls_ctl_snapshot_t *s)
{
    long k = (long)s->cycle;
    if (s->t_us != s->cycle * 1000u + 7u) {
        fail_msg("torn snapshot: cycle %llu with t_us %llu", (unsigned long long)s->cycle, (unsigned long long)s->t_us);
    }
    for (int j = 0; j < LS_N_JOINTS; j++) {
        if (s->q_rad[j] != counter_q(k, j) || s->q_cmd_rad[j] != counter_q(k, j)) {
            fail_msg("torn snapshot: cycle %ld, joint %d = %.17g", k, j, s->q_rad[j]);
        }
    }
    for (int i = 0; i < 6; i++) {
        if (s->sensor[0][i] != (double)k + (double)i) {
            fail_msg("torn snapshot: cycle %ld, sensor value %d = %.17g", k, i, s->sensor[0][i]);
        }
    }
    double F[16];
    (void)ls_kin_fk(M, s->q_rad, F);
    if (memcmp(F, s->flange_pose, sizeof F) != 0) {
        fail_msg("torn snapshot: cycle %ld, flange pose is not FK of its joints", k);
    }
}

static void test_snapshot_under_a_concurrent_writer(void **state)
{
    (void)state;
    fx_t *f = &g_fx;
    memset(f, 0, sizeof *f);
    f->arm_state.counter = true;
    f->arm = (hal_arm_t){ .ops = &ARM_OPS, .self = &f->arm_state };
    f->sensor_state.arm = &f->arm_state;
    f->sensor = (hal_sensor_t){ .name = "force_sensor", .n_values = 6, .read = sensor_read, .self = &f->sensor_state };
    ls_control_config_t cfg = { .model = M,
                                .arm = &f->arm,
                                .sensors = &f->sensor,
                                .n_sensors = 1,
                                .rate_hz = 1000,
                                .world_step = world_step,
                                .world_ctx = &f->arm_state };
    ls_control_init(&f->ctl, &cfg);

    static writer_t w;
    w.ctl = &f->ctl;
    atomic_init(&w.stop, false);
    atomic_init(&w.cycles, 0);
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, writer_main, &w), 0);
    /* Read until 500 different publishes were seen while the writer ran
     * (the machine may be busy: a deadline, not a read count, bounds it). */
    uint64_t last = 0;
    long reads = 0, fresh = 0, distinct = 0;
    struct timespec t0, t;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    do {
        ls_ctl_snapshot_t s;
        fresh += ls_control_snapshot(&f->ctl, &s);
        reads++;
        if (s.cycle != 0) { /* 0: the init snapshot */
            check_published(&s);
            if (s.cycle < last) {
                fail_msg("snapshot went back in time: cycle %llu after %llu", (unsigned long long)s.cycle,
                         (unsigned long long)last);
            }
            distinct += s.cycle != last;
            last = s.cycle;
        }
        clock_gettime(CLOCK_MONOTONIC, &t);
    } while (distinct < 500 && t.tv_sec - t0.tv_sec < 60);
    atomic_store_explicit(&w.stop, true, memory_order_relaxed);
    assert_int_equal(pthread_join(th, NULL), 0);
    print_message("seqlock: %ld reads (%ld fresh, %u stale) saw %ld publishes of %lu\n", reads, fresh,
                  (unsigned)f->ctl.snap_stale, distinct, atomic_load(&w.cycles));
    assert_true(distinct >= 500); /* the reads really overlapped the writes */
}

/* The bounded read: a loop thread stopped inside a publish (odd sequence,
 * half-written words) makes the read give up and return the last good copy. */
static void test_snapshot_gives_up_on_a_stuck_writer(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    for (int i = 0; i < 5; i++) {
        cycle(f);
    }
    ls_ctl_snapshot_t good = snap(f);
    assert_int_equal(good.cycle, 5);
    cycle(f);
    /* The writer "stops" mid-publish of cycle 7: odd sequence, words scribbled. */
    unsigned seq = atomic_load(&f->ctl.snap_seq);
    atomic_store(&f->ctl.snap_seq, seq + 1u);
    for (size_t i = 0; i < LS_CTL_SNAP_WORDS / 2u; i++) {
        atomic_store(&f->ctl.snap_words[i], 0xDEADBEEFu);
    }
    ls_ctl_snapshot_t out;
    memset(&out, 0x5A, sizeof out);
    assert_false(ls_control_snapshot(&f->ctl, &out));
    assert_int_equal(f->ctl.snap_stale, 1);
    assert_memory_equal(&out, &good, sizeof out); /* the last good copy, not the torn words */
    assert_false(ls_control_snapshot(&f->ctl, &out));
    assert_int_equal(f->ctl.snap_stale, 2);
    /* The loop runs again: its next publish completes and reads are fresh. */
    atomic_store(&f->ctl.snap_seq, seq);
    cycle(f);
    assert_true(ls_control_snapshot(&f->ctl, &out));
    assert_int_equal(out.cycle, 7);
    assert_int_equal(f->ctl.snap_stale, 2);
}

/* Before any fresh read, the copy a failed read returns is the one
 * ls_control_init published (never uninitialised memory). */
static void test_snapshot_stale_before_any_fresh_read_is_the_init_copy(void **state)
{
    (void)state;
    fx_t *f = fx_init(false);
    atomic_store(&f->ctl.snap_seq, atomic_load(&f->ctl.snap_seq) + 1u);
    ls_ctl_snapshot_t out;
    assert_false(ls_control_snapshot(&f->ctl, &out));
    assert_int_equal(out.cycle, 0);
    for (int j = 0; j < LS_N_JOINTS; j++) {
        assert_true(out.q_rad[j] == Q0[j]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_command_ring_full_then_empty),
        cmocka_unit_test(test_event_ring_empty_full_and_events_lost),
        cmocka_unit_test(test_plan_slot_hand_over),
        cmocka_unit_test(test_plan_slot_freed_when_ring_full_or_start_refused),
        cmocka_unit_test(test_enable_and_disable),
        cmocka_unit_test(test_enable_waits_for_every_joint_to_confirm),
        cmocka_unit_test(test_enable_fails_naming_the_joint_its_node_and_what_its_drive_said),
        cmocka_unit_test(test_enable_times_out_naming_a_joint_still_enabling),
        cmocka_unit_test(test_a_bus_failing_during_an_enable_fails_the_enable),
        cmocka_unit_test(test_disable_cancels_an_enable_in_progress),
        cmocka_unit_test(test_a_joint_that_faults_under_control_faults_the_arm),
        cmocka_unit_test(test_a_drive_fault_while_moving_stops_the_others_along_the_path_then_disables),
        cmocka_unit_test(test_motion_waits_for_a_required_homing_which_holds_the_new_position),
        cmocka_unit_test(test_a_homing_is_refused_off_or_busy_and_a_failure_names_the_joint),
        cmocka_unit_test(test_the_drives_reports_reach_the_comms_thread),
        cmocka_unit_test(test_world_steps_every_cycle),
        cmocka_unit_test(test_enable_without_arm_fails),
        cmocka_unit_test(test_disable_while_moving_stops_along_the_path_first),
        cmocka_unit_test(test_stop_resume_abort),
        cmocka_unit_test(test_aux_done_continues_a_path),
        cmocka_unit_test(test_estop_line_faults_and_disables),
        cmocka_unit_test(test_arm_command_failure_is_a_fault),
        cmocka_unit_test(test_react_slot_hand_over),
        cmocka_unit_test(test_react_refused_when_off_or_busy_and_freed_when_ring_full),
        cmocka_unit_test(test_manual_jogging),
        cmocka_unit_test(test_the_enabling_switch_gates_the_jog_and_a_release_brakes_on_the_ramp),
        cmocka_unit_test(test_the_frame_button_switches_the_jog_to_the_base_frame),
        cmocka_unit_test(test_tool_couple_and_bits),
        cmocka_unit_test(test_dio_write),
        cmocka_unit_test(test_snapshot_under_a_concurrent_writer),
        cmocka_unit_test(test_snapshot_gives_up_on_a_stuck_writer),
        cmocka_unit_test(test_snapshot_stale_before_any_fresh_read_is_the_init_copy),
    };
    return cmocka_run_group_tests_name("ls_control", tests, NULL, NULL);
}
