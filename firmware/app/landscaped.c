/* landscaped: the LandScape controller.
 *
 *   landscaped --hal sim --link slcan:pty:/tmp/landscape0 [--link ...] [--node 0x10]
 *
 * Threads: this comms thread (links, ISO-TP, dispatcher, telemetry). Logs go
 * to stderr with a level prefix that journald understands. The comms thread
 * is event-driven: it sleeps until a frame arrives, the control loop pushes
 * an event or a stop signal comes (both write its eventfd), or the next
 * protocol deadline (ISO-TP, sessions, RSVPs, heartbeat, telemetry) is due
 * (docs/architecture.md "The comms thread"). */
#include <errno.h>
#include <inttypes.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>

#include "hal_linux_evdev.h"
#include "hal_linux_gpiod.h"
#include "hal_linux_rt.h"
#include "hal_linux_socketcan.h"
#include "hal_sim_world.h"
#include "landscape.h" /* cantools: DBC pack functions */
#include "ls_app_log.h"
#include "cmd_sensor.h"
#include "ls_check.h"
#include "ls_config.h"
#include "ls_control.h"
#include "ls_core.h"
#include "ls_core_events.h"
#include "ls_drive_setup.h"
#include "ls_keys.h"
#include "ls_kin.h"
#include "ls_link_open.h"
#include "faulty_link.h"
#include "ls_net.h"
#include "ls_robot_config.h"
#include "ls_robot_model_sim.h"
#include "ls_telemetry.h"
#include "slcan_pty.h"

#ifndef LS_FIRMWARE_VERSION
#define LS_FIRMWARE_VERSION "0.0.0"
#endif

static volatile sig_atomic_t g_stop; /* the signal that asked us to stop, 0: none */
/* The comms thread's wake-up: an eventfd (non-blocking) that the control
 * loop writes when it pushed an event into its ring, and a stop signal's
 * handler when it set g_stop; the comms thread sleeps on it with the links
 * and reads it before it drains the ring. An eventfd, not a pipe: its write
 * takes a spinlock for a counter add and a wake-up (a priority-inheriting
 * lock on PREEMPT_RT), where a pipe's write takes the pipe's sleeping mutex,
 * which the comms thread's read holds at normal priority. */
#define NO_FD (-1) /* g_wake_fd: none (before start, after the stop) */
static int g_wake_fd = NO_FD;

/* Async-signal-safe; never blocks (EAGAIN only at a counter of 2^64 - 2). */
static void wake_comms(void *ctx)
{
    (void)ctx;
    const int saved = errno;
    const uint64_t one = 1;
    if (g_wake_fd >= 0) {
        (void)!write(g_wake_fd, &one, sizeof one);
    }
    errno = saved;
}

static void on_signal(int sig)
{
    g_stop = sig;
    wake_comms(NULL);
}

static void take_wake_ups(void)
{
    uint64_t n;
    (void)!read(g_wake_fd, &n, sizeof n); /* resets the counter */
}

static uint64_t earliest(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

/* Signals (docs/reliability.md "Signals"): SIGTERM, SIGINT, SIGHUP and
 * SIGQUIT stop the arm (category 1), send the final notices and exit 0;
 * they are blocked in every thread but this one (block_stop_signals around
 * the control thread's start). SIGPIPE, SIGUSR1, SIGUSR2 and SIGALRM are
 * ignored process-wide: nothing here uses them, and their default action
 * would kill the controller with the drives on. */
static const int k_stop_signals[] = { SIGTERM, SIGINT, SIGHUP, SIGQUIT };
static const int k_ignored_signals[] = { SIGPIPE, SIGUSR1, SIGUSR2, SIGALRM };

static void install_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    for (size_t i = 0; i < sizeof k_stop_signals / sizeof k_stop_signals[0]; i++) {
        sigaddset(&sa.sa_mask, k_stop_signals[i]);
    }
    for (size_t i = 0; i < sizeof k_stop_signals / sizeof k_stop_signals[0]; i++) {
        (void)sigaction(k_stop_signals[i], &sa, NULL);
    }
    struct sigaction ign;
    memset(&ign, 0, sizeof ign);
    ign.sa_handler = SIG_IGN;
    sigemptyset(&ign.sa_mask);
    for (size_t i = 0; i < sizeof k_ignored_signals / sizeof k_ignored_signals[0]; i++) {
        (void)sigaction(k_ignored_signals[i], &ign, NULL);
    }
}

/* Block (true) or unblock the stop signals in the calling thread; threads
 * started while they are blocked inherit the mask. */
static void block_stop_signals(bool block)
{
    sigset_t set;
    sigemptyset(&set);
    for (size_t i = 0; i < sizeof k_stop_signals / sizeof k_stop_signals[0]; i++) {
        sigaddset(&set, k_stop_signals[i]);
    }
    (void)pthread_sigmask(block ? SIG_BLOCK : SIG_UNBLOCK, &set, NULL);
}

static const char *signal_name(int sig)
{
    switch (sig) {
    case SIGTERM: return "SIGTERM";
    case SIGINT: return "SIGINT";
    case SIGHUP: return "SIGHUP";
    case SIGQUIT: return "SIGQUIT";
    default: return "a signal";
    }
}

/* sd-daemon style level prefixes: journald stores them as priorities. */
#define LOG_ERR(...) ls_app_log("landscaped", LS_APP_LOG_ERR, __VA_ARGS__)
#define LOG_WARN(...) ls_app_log("landscaped", LS_APP_LOG_WARNING, __VA_ARGS__)
#define LOG_INFO(...) ls_app_log("landscaped", LS_APP_LOG_INFO, __VA_ARGS__)

static uint64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static int open_link(const char *spec, hal_can_link_t *out)
{
    char msg[256] = "";
    const int r = ls_link_open(spec, 0, false, out, msg, sizeof msg);
    if (r < 0) {
        LOG_ERR("--link %s: %s", spec, msg);
        return r;
    }
    return LS_OK;
}

static uint64_t fault_now_us(void *self)
{
    (void)self;
    return mono_us();
}

/* --link-faults: wrap a link in the fault injector (tests only). */
static int wrap_faults(const char *spec, hal_can_link_t *link)
{
    hal_sim_fault_config_t fc;
    char msg[256];
    int r = hal_sim_fault_parse(spec, &fc, msg, sizeof msg);
    if (r != LS_OK) {
        LOG_ERR("--link-faults %s: %s", spec, msg);
        return r;
    }
    fc.clock = (hal_clock_t){ .now_us = fault_now_us, .self = NULL };
    hal_can_link_t faulty;
    r = hal_sim_faulty_wrap(&faulty, link, &fc);
    if (r != LS_OK) {
        LOG_ERR("--link-faults: at most %d links can carry faults", HAL_SIM_FAULTY_MAX_LINKS);
        return r;
    }
    *link = faulty;
    LOG_WARN("link %s: injecting faults %s", link->name, spec);
    return LS_OK;
}

static void send_heartbeat(ls_net_t *net, const ls_core_t *core, uint8_t counter)
{
    struct landscape_heartbeat_t hb = {
        .hb_counter = counter,
        .hb_state = (uint8_t)core->state,
        .hb_role = LANDSCAPE_HEARTBEAT_HB_ROLE_DEVICE_CHOICE,
        .hb_owner = core->owner >= 0 ? core->sessions[core->owner].addr : 0,
        .hb_fault = core->fault[0] != '\0' ? LANDSCAPE_HEARTBEAT_HB_FAULT_LATCHED_CHOICE
                                           : LANDSCAPE_HEARTBEAT_HB_FAULT_NONE_CHOICE,
        .hb_supervisors = 0,
    };
    for (int i = 0; i < LS_MAX_SUPERVISORS; i++) {
        hb.hb_supervisors = (uint8_t)(hb.hb_supervisors + (core->sessions[i].connected ? 1u : 0u));
    }
    hal_can_frame_t f = { .id = LS_ID_HEARTBEAT | net->node, .flags = HAL_CAN_F_EXT, .len = 8 };
    if (landscape_heartbeat_pack(f.data, &hb, sizeof f.data) == 8) {
        (void)ls_net_send_frame(net, &f);
    }
}

static ls_robot_model_t g_model; /* [robot] model, filled once before the threads start */
/* The supervisors' keys: pages of their own, locked in RAM and left out of
 * core dumps (docs/deploy.md "Signed supervisors"); wiped at exit. */
#define KEY_PAGE 4096u
static _Alignas(KEY_PAGE) ls_auth_t g_auth;
static ls_core_t g_core;
static ls_net_t g_net;
static ls_control_t g_ctl;
static hal_linux_rt_t g_rt;
static hal_arm_t g_arm;
static hal_dio_t g_dio;
static hal_tool_t g_tool;
static hal_manual_t g_manual_sim;
static hal_manual_t g_manual_evdev[LS_MANUAL_KINDS];
static bool g_world_open;
static _Atomic bool g_loop_attached;

/* The control thread's body. */
static void control_cycle(void *arg, uint64_t now_us, uint64_t cycle)
{
    (void)cycle;
    if (g_world_open && !atomic_load_explicit(&g_loop_attached, memory_order_relaxed)) {
        (void)hal_sim_world_attach_thread(); /* ODE keeps per-thread collision data */
        atomic_store_explicit(&g_loop_attached, true, memory_order_relaxed);
    }
    ls_control_cycle((ls_control_t *)arg, now_us);
}

static const ls_config_t *g_cfg_running;

/* How far the control loop's time has fallen behind the clock (hal_linux_rt.h). */
static uint64_t rt_behind_us(void)
{
    hal_rt_stats_t rs;
    hal_linux_rt_stats(&g_rt, &rs);
    return rs.behind_us;
}

/* Turns of the comms loop (sleeps ended by a frame, a wake-up or a
 * deadline): on an idle link the heartbeat's 5/s and the telemetry's
 * --telemetry-hz. Comms thread only. */
static uint64_t g_comms_wakeups;

static void describe_rt(void *ctx, char *buf, size_t cap)
{
    ls_ctl_snapshot_t s;
    ls_control_snapshot((ls_control_t *)ctx, &s);
    hal_rt_stats_t rs;
    hal_linux_rt_stats(&g_rt, &rs);
    snprintf(
        buf, cap,
        "cycles=%llu\noverruns=%llu\nbehind_us=%llu\nmax_late_us=%u\nmax_cycle_us=%u\nrealtime=%s\nmemory_locked=%s\n"
        "events_lost=%u\ncomms_wakeups=%llu\n",
        (unsigned long long)rs.cycles, (unsigned long long)rs.overruns, (unsigned long long)rs.behind_us,
        (unsigned)rs.max_late_us, (unsigned)rs.max_cycle_us, rs.realtime ? "yes" : "no",
        rs.memory_locked ? "yes" : "no", (unsigned)s.events_lost, (unsigned long long)g_comms_wakeups);
}

static void describe_config(void *ctx, char *buf, size_t cap)
{
    (void)ctx;
    const ls_config_t *o = g_cfg_running;
    int n = snprintf(buf, cap,
                     "config=%s\nname=%s\nnode=0x%02X\nheartbeat_timeout_ms=%u\ndisconnect_action=%s\narm=%s\n"
                     "dio=%s\nclock=%s\nrate_hz=%u\ntelemetry_hz=%u\nrt_priority=%d\nestop_input=%d\nmodel=%s\n",
                     o->config_path[0] != '\0' ? o->config_path : "(options only)", o->name, (unsigned)o->node,
                     (unsigned)o->heartbeat_timeout_ms,
                     ls_core_disconnect_action_name((ls_DisconnectAction)o->disconnect_action), o->arm, o->dio,
                     o->clock, (unsigned)o->rate_hz, (unsigned)o->telemetry_hz, o->rt_priority, o->estop_input,
                     o->model[0] != '\0' ? o->model : "(compiled in ls-sim6)");
    for (size_t i = 0; i < o->n_links && n > 0 && (size_t)n < cap; i++) {
        n += snprintf(buf + n, cap - (size_t)n, "link=%s\n", o->links[i]);
    }
    if (n > 0 && (size_t)n < cap) { /* where the keys are, never what */
        n += snprintf(buf + n, cap - (size_t)n, "policy=%s\nkey_file=%s\nkeys=%u\nunsigned_queries=%s\n",
                      o->auth_policy == (uint8_t)ls_AuthPolicy_AUTH_SIGNED ? "signed" : "unsigned",
                      o->key_file[0] != '\0' ? o->key_file : "(none, or the credential " LS_KEYS_CREDENTIAL ")",
                      (unsigned)g_auth.n_keys, o->unsigned_queries ? "true" : "false");
    }
}

/* The device's nonces of signed connects (ls_core_io_t.random): the kernel's
 * random source, which never blocks once it has been seeded at boot. */
static int core_random(void *ctx, uint8_t *buf, size_t len)
{
    (void)ctx;
    size_t got = 0;
    while (got < len) {
        const ssize_t n = getrandom(buf + got, len - got, 0);
        if (n < 0 && errno != EINTR) {
            return LS_EIO;
        }
        got += n > 0 ? (size_t)n : 0u;
    }
    return LS_OK;
}

/* The key file in effect into g_auth, its pages locked and kept out of core
 * dumps. 0, or 1 with the cause logged (never a key's bytes). */
static int load_keys(const ls_config_t *opt)
{
    ls_auth_init(&g_auth, (ls_AuthPolicy)opt->auth_policy, opt->unsigned_queries);
    const size_t span = (sizeof g_auth + KEY_PAGE - 1u) / KEY_PAGE * KEY_PAGE;
    if (madvise(&g_auth, span, MADV_DONTDUMP) != 0) {
        LOG_WARN("keys: cannot leave them out of core dumps (madvise: %s)", strerror(errno));
    }
    if (mlock(&g_auth, sizeof g_auth) != 0) {
        LOG_WARN("keys: cannot lock them in RAM (mlock: %s): they may be swapped out", strerror(errno));
    }
    char path[sizeof opt->key_file + 64];
    char msg[512];
    if (ls_keys_path(opt, path, sizeof path) == NULL) {
        LOG_INFO("policy unsigned, no keys: any node on the bus may open a session");
        return 0;
    }
    if (ls_keys_load(path, &g_auth, msg, sizeof msg) != LS_OK) {
        ls_auth_wipe(&g_auth, sizeof g_auth);
        LOG_ERR("%s", msg);
        return 1;
    }
    LOG_INFO("policy %s, %u supervisor keys from %s",
             opt->auth_policy == (uint8_t)ls_AuthPolicy_AUTH_SIGNED ? "signed" : "unsigned", (unsigned)g_auth.n_keys,
             path);
    return 0;
}

static void core_log_warn(void *ctx, const char *line)
{
    (void)ctx;
    LOG_WARN("%s", line);
}

static void send_frame(uint32_t base, const uint8_t *data)
{
    hal_can_frame_t f = { .id = base | g_net.node, .flags = HAL_CAN_F_EXT, .len = 8 };
    memcpy(f.data, data, 8);
    (void)ls_net_send_frame(&g_net, &f);
}

/* Telemetry broadcasts of protocol/landscape.dbc (SI units). */
static void send_telemetry(void)
{
    ls_ctl_snapshot_t s;
    ls_control_snapshot(&g_ctl, &s);
    ls_core_take_loop_events(&g_core, mono_us()); /* the state agrees with the snapshot */
    uint8_t d[8];
    struct landscape_status_t st = {
        .st_state = (uint8_t)g_core.state,
        /* the core's own code, whose name getMotionControlState answers */
        .st_motion = g_core.motion_state,
        .st_control_mode = (uint8_t)(g_core.fault[0] != '\0' ? LANDSCAPE_STATUS_ST_CONTROL_MODE_CONTROLLER_ERROR_CHOICE
                                     : s.enabled             ? LANDSCAPE_STATUS_ST_CONTROL_MODE_POWER_ON_CHOICE
                                                             : LANDSCAPE_STATUS_ST_CONTROL_MODE_POWER_OFF_CHOICE),
        .st_fault =
            g_core.fault[0] != '\0' ? LANDSCAPE_STATUS_ST_FAULT_LATCHED_CHOICE : LANDSCAPE_STATUS_ST_FAULT_NONE_CHOICE,
        .st_overruns = 0,
        .st_cycle_us = 0,
    };
    hal_rt_stats_t rs;
    hal_linux_rt_stats(&g_rt, &rs);
    st.st_overruns = (uint16_t)(rs.overruns > 0xFFFFu ? 0xFFFFu : rs.overruns);
    st.st_cycle_us = (uint16_t)(rs.max_cycle_us > 0xFFFFu ? 0xFFFFu : rs.max_cycle_us);
    if (landscape_status_pack(d, &st, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_STATUS_FRAME_ID), d);
    }
    struct landscape_joints_12_t j12 = { landscape_joints_12_j1_encode(s.q_rad[0]),
                                         landscape_joints_12_j2_encode(s.q_rad[1]) };
    struct landscape_joints_34_t j34 = { landscape_joints_34_j3_encode(s.q_rad[2]),
                                         landscape_joints_34_j4_encode(s.q_rad[3]) };
    struct landscape_joints_56_t j56 = { landscape_joints_56_j5_encode(s.q_rad[4]),
                                         landscape_joints_56_j6_encode(s.q_rad[5]) };
    if (landscape_joints_12_pack(d, &j12, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_JOINTS_12_FRAME_ID), d);
    }
    if (landscape_joints_34_pack(d, &j34, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_JOINTS_34_FRAME_ID), d);
    }
    if (landscape_joints_56_pack(d, &j56, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_JOINTS_56_FRAME_ID), d);
    }
    /* The set-point of the same snapshot, before TOOL_POS closes the cycle:
     * a host pairs it with the measured joints for the following error. */
    struct landscape_joints_cmd_12_t c12 = { landscape_joints_cmd_12_j1_cmd_encode(s.q_cmd_rad[0]),
                                             landscape_joints_cmd_12_j2_cmd_encode(s.q_cmd_rad[1]) };
    struct landscape_joints_cmd_34_t c34 = { landscape_joints_cmd_34_j3_cmd_encode(s.q_cmd_rad[2]),
                                             landscape_joints_cmd_34_j4_cmd_encode(s.q_cmd_rad[3]) };
    struct landscape_joints_cmd_56_t c56 = { landscape_joints_cmd_56_j5_cmd_encode(s.q_cmd_rad[4]),
                                             landscape_joints_cmd_56_j6_cmd_encode(s.q_cmd_rad[5]) };
    if (landscape_joints_cmd_12_pack(d, &c12, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_JOINTS_CMD_12_FRAME_ID), d);
    }
    if (landscape_joints_cmd_34_pack(d, &c34, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_JOINTS_CMD_34_FRAME_ID), d);
    }
    if (landscape_joints_cmd_56_pack(d, &c56, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_JOINTS_CMD_56_FRAME_ID), d);
    }
    double tool[16], tip[16], xyzrpy[6];
    ls_pose_from_xyzrpy(g_core.settings.tool_offset, tool);
    ls_pose_mul(s.flange_pose, tool, tip);
    ls_pose_to_xyzrpy(tip, xyzrpy);
    struct landscape_tool_pos_t tp;
    struct landscape_tool_rpy_t tr;
    (void)ls_telemetry_tool(xyzrpy, (uint16_t)((s.t_us / 1000u) & 0xFFFFu), &tp, &tr); /* saturates, flags */
    if (landscape_tool_pos_pack(d, &tp, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_TOOL_POS_FRAME_ID), d);
    }
    if (landscape_tool_rpy_pack(d, &tr, sizeof d) == 8) {
        send_frame(LS_ID_OF_DBC(LANDSCAPE_TOOL_RPY_FRAME_ID), d);
    }
    if (g_core.dio_units > 0) {
        struct landscape_dio_t dio = {
            .dio_inputs = s.dio[0] & g_core.dio_info[0].input_mask,
            .dio_outputs = s.dio[0] & g_core.dio_info[0].output_mask,
        };
        if (landscape_dio_pack(d, &dio, sizeof d) == 8) {
            send_frame(LS_ID_OF_DBC(LANDSCAPE_DIO_FRAME_ID), d);
        }
    }
}

/* --setpoint-trace: the simulated arm keeps the first this many seconds of
 * the loop's set-points (docs/deploy.md "Test-only keys"). */
#define SETPOINT_TRACE_S 120u

/* At shutdown, once the control loop has stopped: the set-point trace the
 * simulated arm recorded goes to its file; a failure is logged, never fatal. */
static void write_setpoint_trace(void)
{
    char msg[640];
    int r = hal_sim_world_trace_write(msg, sizeof msg);
    if (r < 0) {
        LOG_ERR("--setpoint-trace: %s", msg);
    } else if (r > 0) {
        LOG_INFO("setpoint trace: %s", msg);
    }
}

/* The manual devices: a configured [manual] path is an evdev device, else
 * the simulated world's control socket stands in (arm = sim), else none. */
static int compose_manual(const ls_config_t *o)
{
    for (int k = 0; k < LS_MANUAL_KINDS; k++) {
        const char *kind = ls_manual_kind_name((ls_manual_kind_t)k);
        ls_config_manual_gate(o, (ls_manual_kind_t)k, &g_core.manual_gate[k]);
        g_core.manual[k] = g_world_open ? &g_manual_sim : NULL;
        if (o->manual[k].path[0] == '\0') {
            continue;
        }
        hal_evdev_config_t ec = { .path = o->manual[k].path, .stale_ms = o->manual[k].stale_ms };
        ls_config_manual_map(o, (ls_manual_kind_t)k, &ec.map);
        char msg[256];
        const int r = hal_linux_evdev_open(&g_manual_evdev[k], &ec, msg, sizeof msg);
        if (r != LS_OK) {
            LOG_ERR("[manual] %s: %s", kind, msg);
            return r;
        }
        g_core.manual[k] = &g_manual_evdev[k];
        char axes[192], buttons[192];
        hal_evdev_format_axes(&ec.map, axes, sizeof axes);
        hal_evdev_format_buttons(&ec.map, buttons, sizeof buttons);
        LOG_INFO("manual %s: %s (axes %s; buttons %s%s)", kind, o->manual[k].path, axes, buttons,
                 access(o->manual[k].path, R_OK) == 0 ? "" : "; not there yet: it is picked up when plugged in");
    }
    return 0;
}

static int compose(const ls_config_t *o)
{
    char msg[256] = "";
    hal_arm_t *arm = NULL;
    hal_dio_t *dio = NULL;
    const hal_sensor_t *sensors = NULL;
    size_t n_sensors = 0;
    if (strcmp(o->arm, "sim") == 0) {
        hal_sim_arm_model_t sim_arm;
        ls_robot_model_to_sim(&g_model, &sim_arm);
        hal_sim_world_config_t wc = {
            .arm = &sim_arm,
            .dio_socket_path = o->dio_socket[0] != '\0' ? o->dio_socket : NULL,
            .lockstep = strcmp(o->clock, "lockstep") == 0,
            .with_obstacle = true,
            .trace = { .path = o->setpoint_trace,
                       .rate_hz = o->rate_hz,
                       .capacity = (size_t)SETPOINT_TRACE_S * o->rate_hz },
        };
        const int r = hal_sim_world_open(&wc, msg, sizeof msg);
        if (r < 0) {
            LOG_ERR("--arm sim: %s", msg);
            return r;
        }
        g_world_open = true;
        if (o->setpoint_trace[0] != '\0') {
            LOG_WARN("arm sim: recording the first %u s of set-points for %s (a test option)", SETPOINT_TRACE_S,
                     o->setpoint_trace);
        }
        hal_sim_world_get_arm(&g_arm);
        hal_sim_world_get_tool(&g_tool);
        hal_sim_world_get_manual(&g_manual_sim);
        sensors = hal_sim_world_sensors(&n_sensors);
        arm = &g_arm;
        g_core.tool = &g_tool;
        if (strcmp(o->dio, "sim") == 0) {
            hal_sim_world_get_dio(&g_dio);
            dio = &g_dio;
        }
    } else if (strcmp(o->arm, "cia402") == 0) {
        /* The drives boot and are configured here, within their deadline,
         * before the control loop reads the arm (docs/deploy.md "Drives"). */
        char dmsg[512];
        const int r = ls_drive_compose(o, &g_model, &g_arm, stderr, dmsg, sizeof dmsg);
        if (r != LS_OK) {
            LOG_ERR("%s", dmsg);
            return r;
        }
        arm = &g_arm;
        LOG_INFO("drives: %u joints ready on %s", (unsigned)LS_N_JOINTS, o->drives_link);
    }
    if (strncmp(o->dio, "gpiod:", 6) == 0) {
        hal_linux_gpiod_config_t gc;
        memset(&gc, 0, sizeof gc);
        gc.chip = o->dio + 6;
        gc.n_inputs = o->n_inputs;
        gc.n_outputs = o->n_outputs;
        memcpy(gc.input_offsets, o->input_offsets, sizeof o->input_offsets);
        memcpy(gc.output_offsets, o->output_offsets, sizeof o->output_offsets);
        const int r = hal_linux_gpiod_open(&g_dio, &gc, msg, sizeof msg);
        if (r < 0) {
            LOG_ERR("--dio %s: %s", o->dio, msg);
            return r;
        }
        dio = &g_dio;
    }
    const int mr = compose_manual(o);
    if (mr != LS_OK) {
        return mr;
    }
    g_core.model = &g_model;
    g_core.sensors = sensors;
    g_core.n_sensors = n_sensors;
    int units = dio != NULL ? hal_dio_unit_count(dio) : 0;
    for (int u = 0; u < units && u < LS_CTL_MAX_DIO_UNITS; u++) {
        (void)hal_dio_describe(dio, (uint16_t)u, &g_core.dio_info[u]);
        g_core.dio_units = (uint16_t)(u + 1);
    }
    ls_control_config_t cc = { .model = &g_model,
                               .arm = arm,
                               .dio = dio,
                               .sensors = sensors,
                               .n_sensors = n_sensors,
                               .rate_hz = o->rate_hz,
                               .world_step = g_world_open ? hal_sim_world_step : NULL,
                               .notify = wake_comms };
    ls_control_init(&g_ctl, &cc);
    g_core.ctl = &g_ctl;
    if (o->estop_input >= 0) {
        ls_ctl_cmd_t cmd = { .kind = LS_CTL_ESTOP_LINE, .dio = { 0, 1u << (unsigned)o->estop_input, 0 } };
        (void)ls_control_post(&g_ctl, &cmd);
    }
    hal_rt_config_t rc = { .rate_hz = o->rate_hz,
                           .priority = o->rt_priority,
                           .cpu = o->rt_cpu,
                           .lock_memory = o->lock_memory,
                           .lockstep = strcmp(o->clock, "lockstep") == 0 };
    const int r = hal_linux_rt_start(&g_rt, &rc, control_cycle, &g_ctl, msg, sizeof msg);
    if (r < 0) {
        LOG_ERR("control thread: %s", msg);
        return r;
    }
    LOG_INFO("control loop at %u Hz (%s clock), arm %s (robot model %s, %s inverse kinematics), dio %s, %zu sensors",
             (unsigned)o->rate_hz, o->clock, o->arm, g_model.name, ls_ik_class_name(g_model.ik_class), o->dio,
             n_sensors);
    return LS_OK;
}

/* The command line and the configuration file: true to go on; false with
 * *exit_code when landscaped ends here (--help, --check, a bad
 * configuration: one line on stderr, or --check's report on stdout). */
static bool read_configuration(ls_config_t *opt, int argc, char **argv, int *exit_code)
{
    char cmsg[512];
    ls_config_defaults(opt);
    int cr = ls_config_from_args(opt, argc, argv, cmsg, sizeof cmsg);
    if (cr == 1) {
        *exit_code = LS_EXIT_OK; /* --help */
        return false;
    }
    if (cr < 0) {
        if (opt->check) {
            *exit_code = ls_check_config_error(cmsg, stdout);
            return false;
        }
        LOG_ERR("%s", cmsg);
        *exit_code = LS_EXIT_BAD_CONFIG;
        return false;
    }
    if (opt->check) {
        *exit_code = ls_check_run(opt, stdout);
        return false;
    }
    if (ls_config_validate(opt, cmsg, sizeof cmsg) != 0 ||
        ls_robot_config_load(opt, &g_model, cmsg, sizeof cmsg) != 0) {
        LOG_ERR("%s", cmsg);
        *exit_code = LS_EXIT_BAD_CONFIG;
        return false;
    }
    if (strcmp(opt->arm, "cia402") == 0) {
        /* The drives' EDS files and the bus budget are configuration too:
         * refused like a bad key, before anything opens (exit 2). */
        static ls_drive_plan_t plan;
        const int pr = ls_drive_plan(opt, &plan, cmsg, sizeof cmsg);
        if (pr != LS_OK) {
            LOG_ERR("%s", cmsg);
            *exit_code = pr == LS_EIO ? 1 : LS_EXIT_BAD_CONFIG; /* an unreadable EDS file is the machine's */
            return false;
        }
        if (!plan.budget_fits) {
            LOG_ERR("%s", plan.budget);
            *exit_code = LS_EXIT_BAD_CONFIG;
            return false;
        }
    }
    return true;
}

/* The core and the network layer on the configured links, then the rest of
 * the composition (compose: devices and the control thread). 0, or 1 with
 * the cause logged. */
static int start(const ls_config_t *opt)
{
    ls_core_config_t cfg = {
        .device_name = opt->name,
        .firmware_version = LS_FIRMWARE_VERSION,
        .node_addr = opt->node,
        .joint_count = LS_N_JOINTS,
        .heartbeat_timeout_ms = opt->heartbeat_timeout_ms,
        .disconnect_action = (ls_DisconnectAction)opt->disconnect_action,
        .auth = &g_auth,
    };
    if (load_keys(opt) != 0) {
        return 1;
    }
    ls_core_io_t io = {
        .send_downlink = ls_net_send_downlink, .describe = ls_net_describe, .random = core_random, .ctx = &g_net
    };
    g_cfg_running = opt;
    ls_core_actions_t act = { .describe_rt = describe_rt,
                              .log_warn = core_log_warn,
                              .describe_config = describe_config };
    ls_core_actions_for_loop(&act, &g_ctl);
    ls_core_init(&g_core, &cfg, &io, &act);
    ls_net_init(&g_net, opt->node, &g_core);

    int rc = 0;
    for (size_t i = 0; i < opt->n_links; i++) {
        hal_can_link_t link;
        if (open_link(opt->links[i], &link) != 0) {
            rc = 1;
            break;
        }
        if (opt->link_faults[0] != '\0' && wrap_faults(opt->link_faults, &link) != 0) {
            hal_can_close(&link);
            rc = 1;
            break;
        }
        (void)ls_net_add_link(&g_net, &link);
        LOG_INFO("link %s up", link.name);
    }
    /* The control thread (and anything it starts) never takes a stop signal:
     * this thread runs the stop. */
    block_stop_signals(true);
    if (rc == 0 && compose(opt) != 0) {
        rc = 1;
    }
    block_stop_signals(false);
    if (rc == 0) {
        LOG_INFO("%s ready: node 0x%02X, firmware %s, schema %08X", opt->name, opt->node, LS_FIRMWARE_VERSION,
                 (unsigned)LS_SCHEMA_HASH);
    }
    return rc;
}

/* SIGTERM/SIGINT/SIGHUP/SIGQUIT: a motion stops along its path at the
 * model's maximum deceleration, the drives go off, its final notice
 * (reason=shutdown) goes out, then the process exits, within the shutdown's
 * budget (ls_run.h LS_RUN_SHUTDOWN_*, which the systemd unit's
 * TimeoutStopSec follows: docs/reliability.md "Signals"). */
typedef struct {
    uint64_t at;         /* the stop signal came, 0: not yet */
    uint64_t flushed_at; /* the final notices have left by then, 0: the stop still runs */
} shutdown_t;

/* One comms turn's part of the shutdown: true when the comms loop ends now. */
static bool shutdown_over(shutdown_t *sd)
{
    if (g_stop && sd->at == 0) {
        sd->at = mono_us();
        LOG_INFO("%s received at %llu.%06llu s (CLOCK_MONOTONIC), control loop behind by %llu us",
                 signal_name((int)g_stop), (unsigned long long)(sd->at / 1000000u),
                 (unsigned long long)(sd->at % 1000000u), (unsigned long long)rt_behind_us());
        if (g_core.ctl == NULL || !ls_run_shutdown(&g_core, sd->at)) {
            return true;
        }
        LOG_INFO("shutting down: stopping the motion first");
    }
    if (sd->at == 0) {
        return false;
    }
    const uint64_t t = mono_us();
    if (g_core.halt.active && t - sd->at > LS_RUN_SHUTDOWN_STOP_MAX_US) {
        LOG_WARN("shutting down: the motion did not stop within %llu ms",
                 (unsigned long long)(LS_RUN_SHUTDOWN_STOP_MAX_US / 1000u));
        return true;
    }
    if (!g_core.halt.active && sd->flushed_at == 0) {
        /* The stop is timed in control cycles; overruns (rtstats) stretch it
         * in wall time by the growth of behind_us. */
        LOG_INFO("shutting down: the motion stopped at %llu.%06llu s, control loop behind by %llu us",
                 (unsigned long long)(t / 1000000u), (unsigned long long)(t % 1000000u),
                 (unsigned long long)rt_behind_us());
        sd->flushed_at = t + LS_RUN_SHUTDOWN_FLUSH_US; /* the final notices leave (ISO-TP flow control) */
    }
    return sd->flushed_at != 0 && t >= sd->flushed_at;
}

/* Sleep until a frame, a wake-up (loop event, signal) or `due`: no fixed
 * poll period. */
static void comms_sleep(uint64_t due)
{
    struct pollfd fds[LS_NET_MAX_LINKS + 1];
    nfds_t n = 0;
    fds[n++] = (struct pollfd){ .fd = g_wake_fd, .events = POLLIN, .revents = 0 };
    for (size_t i = 0; i < g_net.n_links; i++) {
        due = earliest(due, hal_can_next_due_us(&g_net.links[i]));
        int fd = hal_can_poll_fd(&g_net.links[i]);
        if (fd >= 0) {
            const short out = hal_can_tx_pending(&g_net.links[i]) ? POLLOUT : 0;
            fds[n++] = (struct pollfd){ .fd = fd, .events = (short)(POLLIN | out), .revents = 0 };
        }
    }
    const uint64_t now = mono_us();
    const uint64_t wait_us = due > now ? due - now : 0u;
    const struct timespec ts = { .tv_sec = (time_t)(wait_us / 1000000u),
                                 .tv_nsec = (long)(wait_us % 1000000u) * 1000L };
    g_comms_wakeups++;
    if (ppoll(fds, n, &ts, NULL) > 0 && (fds[0].revents & POLLIN) != 0) {
        take_wake_ups(); /* before the ring is drained (ls_core_tick): no event is missed */
    }
}

/* The comms thread's loop (docs/architecture.md "Threads"): the network
 * layer, the core's tick, the heartbeat and the telemetry, until the
 * shutdown is over. */
static void run_comms(const ls_config_t *opt)
{
    uint64_t next_hb = mono_us();
    uint64_t next_tm = next_hb;
    const uint64_t tm_period = opt->telemetry_hz > 0 ? 1000000u / opt->telemetry_hz : 0;
    uint8_t hb_counter = 0;
    uint64_t now = mono_us();
    shutdown_t sd = { 0, 0 };
    while (!shutdown_over(&sd)) {
        uint64_t due = earliest(ls_net_next_deadline_us(&g_net), ls_core_next_deadline_us(&g_core, now));
        due = earliest(due, next_hb);
        if (tm_period > 0) {
            due = earliest(due, next_tm);
        }
        if (sd.at != 0) {
            due = earliest(due, sd.flushed_at != 0 ? sd.flushed_at : sd.at + LS_RUN_SHUTDOWN_STOP_MAX_US + 1u);
        }
        comms_sleep(due);
        now = mono_us();
        ls_net_poll(&g_net, now);
        ls_core_tick(&g_core, now);
        if (now >= next_hb) {
            send_heartbeat(&g_net, &g_core, hb_counter++);
            next_hb = now + (uint64_t)LANDSCAPE_HEARTBEAT_CYCLE_TIME_MS * 1000u; /* the DBC's GenMsgCycleTime */
        }
        if (tm_period > 0 && now >= next_tm) {
            send_telemetry();
            next_tm = now + tm_period;
        }
    }
}

/* Everything down in order: the control thread, the drives off, the
 * simulated world (its set-point trace written), DIO, the links, the
 * eventfd. */
static void stop_everything(bool started)
{
    if (started) {
        LOG_INFO("shutting down");
    }
    for (size_t i = 0; i < g_net.n_links; i++) {
        char line[512];
        if (hal_sim_faulty_format(&g_net.links[i], line, sizeof line) >= 0) {
            LOG_INFO("link %s faults: %s", g_net.links[i].name, line);
        }
    }
    hal_linux_rt_stop(&g_rt);
    if (g_core.ctl != NULL) {
        (void)hal_arm_enable(&g_arm, false);
    }
    ls_drive_shutdown();
    for (int k = 0; k < LS_MANUAL_KINDS; k++) {
        hal_linux_evdev_close(&g_manual_evdev[k]);
    }
    if (g_world_open) {
        write_setpoint_trace();
        hal_sim_world_close();
    }
    if (g_dio.ops != NULL && !g_world_open) {
        hal_dio_close(&g_dio);
    }
    ls_net_close(&g_net);
    ls_auth_wipe(&g_auth, sizeof g_auth);
    const int wake_fd = g_wake_fd;
    g_wake_fd = NO_FD; /* the control thread has stopped; a late signal finds no fd */
    close(wake_fd);
}

int main(int argc, char **argv)
{
    static ls_config_t opt;
    int exit_code = LS_EXIT_OK;
    if (!read_configuration(&opt, argc, argv, &exit_code)) {
        return exit_code;
    }
    g_wake_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (g_wake_fd < 0) {
        LOG_ERR("the comms thread's eventfd: %s", strerror(errno));
        return 1;
    }
    install_signals();
    const int rc = start(&opt);
    if (rc == 0) {
        run_comms(&opt);
    }
    stop_everything(rc == 0);
    return rc;
}
