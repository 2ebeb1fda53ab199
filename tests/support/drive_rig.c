/* The drive arm against the simulated drives in one process (drive_rig.h). */
#include "drive_rig.h"

#include <stdio.h>
#include <string.h>

#include "hal_sim_drives.h"
#include "hal_sim_world.h"
#include "ls_canopen.h"
#include "ls_robot_model_sim.h"

#define QUEUE 4096

typedef struct {
    hal_can_frame_t f[QUEUE];
    size_t head, count;
} queue_t;

static queue_t g_to_sim, g_to_master;
static bool g_attached, g_world_open;
static unsigned g_bad;

static int q_send(queue_t *q, const hal_can_frame_t *f)
{
    if (q->count == QUEUE) {
        return LS_EAGAIN;
    }
    q->f[(q->head + q->count++) % QUEUE] = *f;
    return LS_OK;
}

static int q_recv(queue_t *q, hal_can_frame_t *f)
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
    if ((f->flags & (HAL_CAN_F_EXT | HAL_CAN_F_RTR)) != 0u || f->id > LS_CO_COB_MASK || f->len > 8u) {
        g_bad++;
    }
    return g_attached ? q_send(&g_to_sim, f) : LS_OK;
}
static int master_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    return q_recv(&g_to_master, f);
}
static int sim_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    return q_send(&g_to_master, f);
}
static int sim_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    return q_recv(&g_to_sim, f);
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
static hal_can_link_t g_master_link = { .ops = &k_master_ops, .self = NULL, .name = "mem-master" };
static hal_can_link_t g_sim_link = { .ops = &k_sim_ops, .self = NULL, .name = "mem-sim" };

ls_drives_config_t drive_rig_config(bool map_mode)
{
    ls_drives_config_t c;
    memset(&c, 0, sizeof c);
    c.n_joints = DRIVE_RIG_JOINTS;
    c.link = &g_master_link;
    c.control_period_us = 1000;
    c.cycle_ticks = 4;
    c.master_node = 0x7F;
    c.heartbeat_ms = 100;
    c.heartbeat_timeout_ms = 350;
    c.boot_timeout_ms = 2000;
    c.abort_option = 3;
    c.stale_cycles = 5;
    for (int j = 0; j < DRIVE_RIG_JOINTS; j++) {
        ls_drive_joint_t *dj = &c.joint[j];
        dj->node_id = (uint8_t)(0x21 + j);
        dj->scale.counts_per_rad = DRIVE_RIG_CPR;
        dj->scale.sign = 1;
        dj->write_consumer_hb = dj->write_abort_option = dj->write_interp_period = true;
        dj->write_pdo_type = dj->write_tpdo_inhibit = true;
        dj->feedforward = true;
        for (int p = 0; p < 4; p++) {
            dj->rpdo_present[p] = dj->tpdo_present[p] = true;
        }
        dj->map_mode = map_mode;
        dj->can_home = true;
        dj->read_limits = true;
        dj->tpdo_room[0] = dj->tpdo_room[1] = 8;
        dj->brake = (ls_drive_obj_t){ .map = true, .index = SD_OBJ_BRAKE_STO, .sub = SD_SUB_BRAKE_ENGAGED, .bytes = 1 };
        dj->sto = (ls_drive_obj_t){ .map = true, .index = SD_OBJ_BRAKE_STO, .sub = SD_SUB_STO_ACTIVE, .bytes = 1 };
        dj->temperature = (ls_drive_obj_t){
            .map = true, .index = SD_OBJ_BRAKE_STO, .sub = SD_SUB_TEMPERATURE, .bytes = 2, .is_signed = true
        };
        dj->temperature_scale = 0.1;
        dj->torque = (ls_drive_obj_t){ .map = true, .index = LS_CO_OBJ_TORQUE_ACTUAL, .bytes = 2, .is_signed = true };
        dj->velocity =
            (ls_drive_obj_t){ .map = true, .index = LS_CO_OBJ_VELOCITY_ACTUAL, .bytes = 4, .is_signed = true };
    }
    c.joint[1].home_required = true;
    c.joint[1].write_home_method = true;
    c.joint[1].home_method = 37;
    c.joint[1].write_home_offset = true;
    c.joint[1].home_offset_counts = DRIVE_RIG_HOME_OFFSET;
    return c;
}

int drive_rig_open(const ls_drives_config_t *cfg, ls_drives_t *d, hal_arm_t *arm, uint64_t *now_us, char *msg,
                   size_t msglen)
{
    drive_rig_clear();
    g_bad = 0;
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(&ls_robot_model_default, &am);
    hal_sim_world_config_t wc = { .arm = &am };
    if (hal_sim_world_open(&wc, msg, msglen) != LS_OK) {
        return LS_EIO;
    }
    g_world_open = true;
    hal_sim_drives_config_t dc = { .link = &g_sim_link, .n_drives = cfg->n_joints, .counts_per_rad = DRIVE_RIG_CPR };
    for (uint8_t j = 0; j < cfg->n_joints; j++) {
        dc.drives[j] = (hal_sim_drive_config_t){ cfg->joint[j].node_id, j, 0 };
    }
    *now_us = 1000000u;
    if (hal_sim_drives_open(&dc, *now_us, msg, msglen) != LS_OK) {
        drive_rig_close();
        return LS_EIO;
    }
    g_attached = true;
    /* What the drives said before a master listened is gone (as on the
     * pty of ls-simdrives): the master's reset brings their boot-ups. */
    g_to_master.count = 0;
    ls_drives_config_t c = *cfg;
    c.link = &g_master_link;
    if (ls_drives_init(d, &c) != LS_OK || ls_drives_boot(d, *now_us) != LS_OK) {
        (void)snprintf(msg, msglen, "init: %s", ls_drives_text(d));
        drive_rig_close();
        return LS_EINVAL;
    }
    int r = 0;
    for (int ms = 0; ms < 5000 && r == 0; ms++) {
        *now_us += 1000u;
        r = ls_drives_service(d, *now_us);
        (void)hal_sim_drives_poll(*now_us);
    }
    if (r != 1) {
        (void)snprintf(msg, msglen, "boot: %d %s", r, ls_drives_text(d));
        drive_rig_close();
        return r < 0 ? r : LS_ETIMEDOUT;
    }
    ls_drives_arm(d, arm);
    return LS_OK;
}

void drive_rig_step(hal_arm_t *arm, uint64_t *now_us, unsigned ms)
{
    for (unsigned k = 0; k < ms; k++) {
        *now_us += 1000u;
        (void)hal_arm_update(arm, *now_us);
        if (g_attached) {
            (void)hal_sim_drives_poll(*now_us);
        }
    }
}

void drive_rig_detach(void)
{
    drive_rig_close();
    drive_rig_clear();
}

void drive_rig_close(void)
{
    if (g_attached) {
        hal_sim_drives_close();
        g_attached = false;
    }
    if (g_world_open) {
        hal_sim_world_close();
        g_world_open = false;
    }
}

void drive_rig_inject(const hal_can_frame_t *f)
{
    (void)q_send(&g_to_master, f);
}

void drive_rig_clear(void)
{
    g_to_sim.count = g_to_master.count = 0;
    g_to_sim.head = g_to_master.head = 0;
}

unsigned drive_rig_bad_frames(void)
{
    return g_bad;
}
