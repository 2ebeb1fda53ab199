/* Footprint build (bench 7): the portable firmware on a bare Cortex-M4F,
 * no OS. The composition of landscaped without its OS parts: core +
 * network layer on one CAN link, the control loop (executor, kinematics)
 * run once per millisecond tick, its events drained into the core, the
 * heartbeat broadcast (cantools DBC code), and one trajectory plan/sample
 * per turn. The linker keeps everything those reach and drops the rest
 * (-ffunction-sections -Wl,--gc-sections).
 *
 * The HAL is stubbed: the CAN link and the arm read and write a
 * memory-mapped "controller" (volatile registers at a fixed address, as a
 * driver would), and time is a free-running counter. Not included: the sim
 * and Linux HAL backends, telemetry broadcasts and the process glue of
 * landscaped (options, logging, signals, threads). */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "hal/hal_can.h"
#include "landscape.h"
#include "ls_control.h"
#include "ls_core.h"
#include "ls_core_events.h"
#include "ls_net.h"
#include "ls_traj.h"

/* A made-up CAN controller: one RX and one TX mailbox. */
typedef struct {
    volatile uint32_t status, rx_id, rx_len, rx_data[2];
    volatile uint32_t tx_id, tx_len, tx_data[2], tx_go;
    volatile uint32_t timer_us_lo, timer_us_hi;
    volatile int32_t joint_pos_urad[LS_N_JOINTS], joint_cmd_urad[LS_N_JOINTS], drive_enable;
} can_regs_t;
#define CAN0 ((can_regs_t *)0x40006400u)

static int can_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    if ((CAN0->status & 2u) != 0) {
        return LS_EAGAIN;
    }
    uint32_t d[2];
    memcpy(d, f->data, sizeof d);
    CAN0->tx_id = f->id | ((uint32_t)f->flags << 29);
    CAN0->tx_len = f->len;
    CAN0->tx_data[0] = d[0];
    CAN0->tx_data[1] = d[1];
    CAN0->tx_go = 1;
    return LS_OK;
}

static int can_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    if ((CAN0->status & 1u) == 0) {
        return LS_EAGAIN;
    }
    uint32_t id = CAN0->rx_id;
    uint32_t d[2] = { CAN0->rx_data[0], CAN0->rx_data[1] };
    f->id = id & 0x1FFFFFFFu;
    f->flags = (uint8_t)(id >> 29);
    f->len = (uint8_t)(CAN0->rx_len & 0xFu);
    if (f->len > 8) {
        f->len = 8;
    }
    memcpy(f->data, d, sizeof d);
    CAN0->status = 1u; /* release the mailbox */
    return 1;
}

static int can_poll_fd(void *self)
{
    (void)self;
    return LS_EUNSUPPORTED; /* no descriptor: the wrapper answers "none" */
}

static int can_status(void *self, hal_can_status_t *out)
{
    (void)self;
    memset(out, 0, sizeof *out);
    out->bitrate = 1000000;
    return LS_OK;
}

static void can_close(void *self)
{
    (void)self;
}

static const hal_can_ops_t can_ops = {
    .send = can_send, .recv = can_recv, .poll_fd = can_poll_fd, .status = can_status, .close = can_close
};

static int arm_enable(void *self, bool on)
{
    (void)self;
    CAN0->drive_enable = on ? 1 : 0;
    return LS_OK;
}

static int arm_command(void *self, const double *q_rad, const double *qd_rad_s)
{
    (void)self;
    (void)qd_rad_s;
    for (int i = 0; i < LS_N_JOINTS; i++) {
        CAN0->joint_cmd_urad[i] = (int32_t)(q_rad[i] * 1e6);
    }
    return LS_OK;
}

static int arm_read(void *self, double *q_rad, double *qd_rad_s)
{
    (void)self;
    for (int i = 0; i < LS_N_JOINTS; i++) {
        q_rad[i] = (double)CAN0->joint_pos_urad[i] * 1e-6;
        if (qd_rad_s != NULL) {
            qd_rad_s[i] = 0.0;
        }
    }
    return LS_OK;
}

/* Designated: hal_arm_ops_t grows (the drives' operations), and what this
 * arm leaves out is NULL, "unsupported" through the HAL's wrappers. */
static const hal_arm_ops_t arm_ops = { .enable = arm_enable, .command = arm_command, .read = arm_read };
static hal_arm_t g_arm = { .ops = &arm_ops, .self = NULL, .name = "arm0" };

static uint64_t now_us(void)
{
    return ((uint64_t)CAN0->timer_us_hi << 32) | CAN0->timer_us_lo;
}

static ls_core_t g_core;
static ls_net_t g_net;
static ls_traj_t g_traj;
static ls_control_t g_ctl;

int main(void)
{
    ls_core_config_t cfg = {
        .device_name = "landscape-m4",
        .firmware_version = "0.1.0",
        .node_addr = 0x10,
        .joint_count = 6,
        .heartbeat_timeout_ms = 1000,
    };
    ls_core_io_t io = { .send_downlink = ls_net_send_downlink, .ctx = &g_net };
    ls_core_actions_t act = { 0 };
    ls_core_actions_for_loop(&act, &g_ctl);
    ls_core_init(&g_core, &cfg, &io, &act);
    ls_net_init(&g_net, 0x10, &g_core);
    hal_can_link_t link = { .ops = &can_ops, .self = NULL, .name = "can0" };
    (void)ls_net_add_link(&g_net, &link);

    const ls_robot_model_t *m = &ls_robot_model_default;
    g_core.model = m;
    ls_control_config_t cc = { .model = m, .arm = &g_arm, .rate_hz = 1000 };
    ls_control_init(&g_ctl, &cc);
    g_core.ctl = &g_ctl;
    ls_traj_limits_t lim;
    for (int i = 0; i < LS_N_JOINTS; i++) {
        lim.v_max[i] = m->qd_max_rad_s[i];
        lim.a_max[i] = m->qdd_max_rad_s2[i];
        lim.j_max[i] = m->qddd_max_rad_s3[i];
    }
    double q0[LS_N_JOINTS] = { 0 }, q1[LS_N_JOINTS] = { 0 }, q[LS_N_JOINTS];
    uint8_t hb_counter = 0;
    uint64_t next_hb = 0, next_cycle = 0;
    for (;;) {
        uint64_t t = now_us();
        if (t >= next_cycle) { /* on a board: a 1 kHz timer interrupt */
            ls_control_cycle(&g_ctl, t);
            next_cycle = t + 1000u;
        }
        ls_net_poll(&g_net, t);
        ls_core_tick(&g_core, t);
        if (t >= next_hb) {
            struct landscape_heartbeat_t hb = { .hb_counter = hb_counter++,
                                                .hb_state = (uint8_t)g_core.state,
                                                .hb_role = LANDSCAPE_HEARTBEAT_HB_ROLE_DEVICE_CHOICE };
            hal_can_frame_t f = { .id = LS_ID_HEARTBEAT | 0x10u, .flags = HAL_CAN_F_EXT, .len = 8 };
            if (landscape_heartbeat_pack(f.data, &hb, sizeof f.data) == 8) {
                (void)ls_net_send_frame(&g_net, &f);
            }
            next_hb = t + 100000u;
        }
        /* A new goal from the mailbox, planned and sampled as the control loop would. */
        q1[(t >> 4) % LS_N_JOINTS] = (double)(int32_t)CAN0->rx_data[0] * 1e-6;
        if (ls_traj_plan(&g_traj, LS_N_JOINTS, q0, q1, &lim) == LS_OK) {
            ls_traj_sample(&g_traj, (double)(t % 1000000u) * 1e-6, q, NULL, NULL);
            CAN0->tx_data[0] = (uint32_t)(int32_t)(q[0] * 1e6);
        }
    }
}

/* No OS: the entry point zeroes .bss and calls main. The toolchain's default
 * linker script keeps .data where it is loaded (no copy); a real board's
 * script and vector table (a few hundred bytes) are not part of this figure. */
extern uint32_t __bss_start__[], __bss_end__[];
void _start(void);
void _start(void)
{
    for (uint32_t *d = __bss_start__; d < __bss_end__;) {
        *d++ = 0;
    }
    (void)main();
    for (;;) {
    }
}

/* No heap: the firmware formats and parses with ls_fmt (firmware/common),
 * so nothing references newlib's allocator and the linker drops this
 * function. Should something link malloc again (newlib's vsnprintf and
 * strtod did), this _sbrk refuses every request: there is no heap region,
 * and bench 7's heap row names what pulled the allocator in. */
void *_sbrk(ptrdiff_t incr);
void *_sbrk(ptrdiff_t incr)
{
    (void)incr;
    return (void *)-1;
}
