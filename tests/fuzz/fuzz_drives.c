/* libFuzzer target: the drive arm (firmware/drives/ls_drives) under any
 * frames of its drives' services and any sequence of the HAL arm's calls.
 *
 * Once per process the arm boots against the simulated drives in this
 * process (hal/sim/drives: two in-memory links back to back) with every
 * readout mapped and joint 2 homing with the mode in its PDOs, enables,
 * and is saved. Each input starts from that saved arm (its pointers point
 * into itself, so a copy back is the same arm), with the simulated drives
 * gone: the input is the only peer. Its bytes are a script:
 *   0: a frame: a service (TPDO1/TPDO2 with any bytes and length, EMCY,
 *      heartbeat, boot-up, an SDO answer), a node, a length and data
 *   1: time: 1..64 ms, one update() per ms (SYNCs, RPDOs, time-outs)
 *   2: enable(on/off)
 *   3: home(mask)
 *   4: command() with set-points from the input
 *   5: status(), readout() and every event taken
 * Checked: nothing crashes or trips ASan/UBSan; every frame the arm sends is
 * an 11-bit data frame of 0..8 bytes; status() and readout() say what they
 * promise (states in range, a text that ends, static names that are
 * strings, a homing state in range). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hal_sim_drives.h"
#include "hal_sim_world.h"
#include "ls_canopen.h"
#include "ls_drives.h"
#include "ls_robot_model_sim.h"

#define NJ 6
#define QUEUE 512

typedef struct {
    hal_can_frame_t f[QUEUE];
    size_t head, count;
} queue_t;

static queue_t g_to_sim, g_to_master;
static bool g_sim_attached; /* the simulated drives answer (boot only) */

static void push(queue_t *q, const hal_can_frame_t *f)
{
    if (q->count < QUEUE) {
        q->f[(q->head + q->count++) % QUEUE] = *f;
    }
}

static int pop(queue_t *q, hal_can_frame_t *f)
{
    if (q->count == 0) {
        return LS_EAGAIN;
    }
    *f = q->f[q->head];
    q->head = (q->head + 1) % QUEUE;
    q->count--;
    return 1;
}

static int master_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    if ((f->flags & (HAL_CAN_F_EXT | HAL_CAN_F_RTR)) != 0u || f->id > 0x7FFu || f->len > 8u) {
        abort(); /* the master sends 11-bit data frames only */
    }
    if (g_sim_attached) {
        push(&g_to_sim, f);
    }
    return LS_OK;
}
static int master_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    return pop(&g_to_master, f);
}
static int sim_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    push(&g_to_master, f);
    return LS_OK;
}
static int sim_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    return pop(&g_to_sim, f);
}
static int no_fd(void *self)
{
    (void)self;
    return -1;
}
static int ok_status(void *self, hal_can_status_t *out)
{
    (void)self;
    memset(out, 0, sizeof *out);
    return LS_OK;
}
static void no_close(void *self)
{
    (void)self;
}

static const hal_can_ops_t k_master_ops = {
    .send = master_send, .recv = master_recv, .poll_fd = no_fd, .status = ok_status, .close = no_close
};
static const hal_can_ops_t k_sim_ops = {
    .send = sim_send, .recv = sim_recv, .poll_fd = no_fd, .status = ok_status, .close = no_close
};
static hal_can_link_t g_master_link = { .ops = &k_master_ops, .self = NULL, .name = "fuzz-master" };
static hal_can_link_t g_sim_link = { .ops = &k_sim_ops, .self = NULL, .name = "fuzz-sim" };

static ls_drives_t g_d, g_saved;
static uint64_t g_saved_now, g_now;
static hal_arm_t g_arm;

static ls_drives_config_t config(void)
{
    ls_drives_config_t c;
    memset(&c, 0, sizeof c);
    c.n_joints = NJ;
    c.link = &g_master_link;
    c.control_period_us = 1000;
    c.cycle_ticks = 4;
    c.master_node = 0x7F;
    c.heartbeat_ms = 100;
    c.heartbeat_timeout_ms = 350;
    c.boot_timeout_ms = 2000;
    c.abort_option = 3;
    c.stale_cycles = 5;
    for (int j = 0; j < NJ; j++) {
        ls_drive_joint_t *dj = &c.joint[j];
        dj->node_id = (uint8_t)(0x21 + j);
        dj->scale.counts_per_rad = 100000.0;
        dj->scale.sign = j % 2 == 0 ? 1 : -1;
        dj->write_consumer_hb = dj->write_abort_option = dj->write_interp_period = true;
        dj->write_pdo_type = dj->write_tpdo_inhibit = dj->feedforward = true;
        for (int p = 0; p < 4; p++) {
            dj->rpdo_present[p] = dj->tpdo_present[p] = true;
        }
        dj->can_home = dj->read_limits = true;
        dj->map_mode = j == 1;
        dj->home_required = j == 1;
        dj->tpdo_room[0] = dj->tpdo_room[1] = 8;
        dj->brake = (ls_drive_obj_t){ .map = true, .index = SD_OBJ_BRAKE_STO, .sub = SD_SUB_BRAKE_ENGAGED, .bytes = 1 };
        dj->sto = (ls_drive_obj_t){
            .map = true, .index = SD_OBJ_BRAKE_STO, .sub = SD_SUB_STO_ACTIVE, .bytes = 1, .bit = 0, .inverted = j == 3
        };
        dj->temperature = (ls_drive_obj_t){
            .map = true, .index = SD_OBJ_BRAKE_STO, .sub = SD_SUB_TEMPERATURE, .bytes = 2, .is_signed = true
        };
        dj->temperature_scale = 0.1;
        dj->torque = (ls_drive_obj_t){ .map = true, .index = LS_CO_OBJ_TORQUE_ACTUAL, .bytes = 2, .is_signed = true };
        dj->velocity =
            (ls_drive_obj_t){ .map = true, .index = LS_CO_OBJ_VELOCITY_ACTUAL, .bytes = 4, .is_signed = true };
    }
    return c;
}

static void step_ms(unsigned ms)
{
    for (unsigned k = 0; k < ms; k++) {
        g_now += 1000u;
        (void)hal_arm_update(&g_arm, g_now);
        if (g_sim_attached) {
            (void)hal_sim_drives_poll(g_now);
        }
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(&ls_robot_model_default, &am);
    hal_sim_world_config_t wc = { .arm = &am };
    char msg[200] = "";
    if (hal_sim_world_open(&wc, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "fuzz_drives: world: %s\n", msg);
        abort();
    }
    hal_sim_drives_config_t dc = { .link = &g_sim_link, .n_drives = NJ, .counts_per_rad = 100000.0 };
    for (int j = 0; j < NJ; j++) {
        dc.drives[j] = (hal_sim_drive_config_t){ (uint8_t)(0x21 + j), (uint8_t)j, 0 };
    }
    g_now = 1000000u;
    if (hal_sim_drives_open(&dc, g_now, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "fuzz_drives: drives: %s\n", msg);
        abort();
    }
    g_sim_attached = true;
    g_to_master.count = 0; /* their boot-ups before the master listened */
    ls_drives_config_t c = config();
    if (ls_drives_init(&g_d, &c) != LS_OK || ls_drives_boot(&g_d, g_now) != LS_OK) {
        abort();
    }
    int r = 0;
    for (int ms = 0; ms < 5000 && r == 0; ms++) {
        g_now += 1000u;
        r = ls_drives_service(&g_d, g_now);
        (void)hal_sim_drives_poll(g_now);
    }
    if (r != 1) {
        fprintf(stderr, "fuzz_drives: boot: %s\n", ls_drives_text(&g_d));
        abort();
    }
    ls_drives_arm(&g_d, &g_arm);
    (void)hal_arm_enable(&g_arm, true);
    step_ms(100);
    /* from here on the input is the drives' only voice */
    g_sim_attached = false;
    hal_sim_drives_close();
    hal_sim_world_close();
    g_to_sim.count = g_to_master.count = 0;
    g_saved = g_d;
    g_saved_now = g_now;
    return 0;
}

static const uint32_t k_services[] = { LS_CO_COB_TPDO1, LS_CO_COB_TPDO1 + 0x100u, LS_CO_COB_EMCY, LS_CO_COB_HEARTBEAT,
                                       LS_CO_COB_SDO_TX };

static void check_views(void)
{
    hal_joint_status_t st[NJ];
    if (hal_arm_status(&g_arm, true, NJ, st) != LS_OK) {
        abort();
    }
    for (int j = 0; j < NJ; j++) {
        if ((unsigned)st[j].state > (unsigned)HAL_JOINT_LOST || (unsigned)st[j].home > (unsigned)HAL_HOME_FAILED ||
            memchr(st[j].text, '\0', sizeof st[j].text) == NULL) {
            abort();
        }
    }
    hal_arm_readout_t r;
    (void)hal_arm_readout(&g_arm, &r);
    if (r.n_joints > HAL_ARM_MAX_JOINTS || r.n_counters > HAL_READOUT_COUNTERS) {
        abort();
    }
    for (uint8_t j = 0; j < r.n_joints; j++) {
        const hal_drive_readout_t *o = &r.joint[j];
        if (o->state == NULL || o->error_name == NULL || strlen(o->state) > 32u ||
            (unsigned)o->home > (unsigned)HAL_HOME_FAILED) {
            abort();
        }
    }
    hal_arm_event_t ev;
    for (int k = 0; k < 64 && hal_arm_next_event(&g_arm, &ev) == 1; k++) {
        if (memchr(ev.text, '\0', sizeof ev.text) == NULL || memchr(ev.meaning, '\0', sizeof ev.meaning) == NULL) {
            abort();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    g_d = g_saved;
    g_now = g_saved_now;
    g_to_sim.count = g_to_master.count = 0;
    ls_drives_arm(&g_d, &g_arm);
    size_t i = 0;
    while (i < size) {
        const uint8_t op = data[i++] % 6u;
        const uint8_t a = i < size ? data[i++] : 0u;
        switch (op) {
        case 0: {
            hal_can_frame_t f;
            memset(&f, 0, sizeof f);
            const uint8_t node = (uint8_t)(0x21 + (a >> 4) % 8u); /* two ids beyond the arm's */
            f.id = k_services[(a & 0x0Fu) % (sizeof k_services / sizeof k_services[0])] + node;
            f.len = i < size ? (uint8_t)(data[i++] % 9u) : 0u;
            for (uint8_t k = 0; k < f.len && i < size; k++) {
                f.data[k] = data[i++];
            }
            push(&g_to_master, &f);
            break;
        }
        case 1: step_ms(1u + (unsigned)(a % 64u)); break;
        case 2: (void)hal_arm_enable(&g_arm, (a & 1u) != 0u); break;
        case 3: (void)hal_arm_home(&g_arm, a); break;
        case 4: {
            double q[NJ], qd[NJ];
            (void)hal_arm_read(&g_arm, q, qd);
            for (int j = 0; j < NJ; j++) {
                q[j] += ((double)(int8_t)a) * 1e-3 * (double)(j + 1);
            }
            (void)hal_arm_command(&g_arm, q, qd);
            break;
        }
        default: check_views(); break;
        }
    }
    check_views();
    return 0;
}
