/* ls-simdrives: the simulated arm behind six CiA 402 drives on a CAN link.
 *
 *   ls-simdrives --link slcan:pty:/tmp/drives0 [--nodes 0x21,...] [--control PATH]
 *
 * A composition: the robot model as the world's arm (as landscaped does),
 * the world, the link, and the drives of hal/sim/drives, whose header says
 * what a master sees. One thread, event-driven: it sleeps until a frame or a
 * control command arrives or a node's timer is due (heartbeats, time-outs),
 * and exits cleanly on SIGTERM or SIGINT. Logs go to stderr with the
 * sd-daemon level prefixes journald understands. */
#include <errno.h>
#include <inttypes.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "faulty_link.h"
#include "hal_linux_socketcan.h"
#include "hal_sim_drives.h"
#include "hal_sim_world.h"
#include "ls_app_log.h"
#include "ls_check.h"
#include "ls_config.h"
#include "ls_robot_config.h"
#include "ls_robot_model_sim.h"
#include "ls_simdrives_opts.h"
#include "ls_simdrives_sync.h"
#include "slcan_pty.h"

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    g_stop = sig;
}

#define LOG_ERR(...) ls_app_log("ls-simdrives", LS_APP_LOG_ERR, __VA_ARGS__)
#define LOG_WARN(...) ls_app_log("ls-simdrives", LS_APP_LOG_WARNING, __VA_ARGS__)
#define LOG_INFO(...) ls_app_log("ls-simdrives", LS_APP_LOG_INFO, __VA_ARGS__)

static uint64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static uint64_t fault_now_us(void *self)
{
    (void)self;
    return mono_us();
}

static int open_link(const ls_simdrives_opts_t *o, hal_can_link_t *link)
{
    char msg[256] = "";
    int r = strncmp(o->link, "slcan:pty:", 10) == 0 ? hal_sim_slcan_pty_open(link, o->link + 10, msg, sizeof msg)
                                                    : hal_linux_socketcan_open(link, o->link + 10, msg, sizeof msg);
    if (r < 0) {
        LOG_ERR("--link %s: %s", o->link, msg);
        return r;
    }
    if (o->link_faults[0] != '\0') {
        hal_sim_fault_config_t fc;
        (void)hal_sim_fault_parse(o->link_faults, &fc, msg, sizeof msg); /* checked with the options */
        fc.clock = (hal_clock_t){ .now_us = fault_now_us, .self = NULL };
        hal_can_link_t faulty;
        if (hal_sim_faulty_wrap(&faulty, link, &fc) != LS_OK) {
            LOG_ERR("--link-faults: no free fault injector");
            hal_can_close(link);
            return LS_EINVAL;
        }
        *link = faulty;
        LOG_WARN("link %s: injecting faults %s", link->name, o->link_faults);
    }
    return LS_OK;
}

/* --sync-stats: the link seen through a tap that notes each SYNC's arrival
 * as the drives read it; every operation goes to the link beneath. */
typedef struct {
    hal_can_link_t inner;
    ls_sync_watch_t *watch;
} sync_tap_t;

static int tap_send(void *self, const hal_can_frame_t *f)
{
    return hal_can_send(&((sync_tap_t *)self)->inner, f);
}

static int tap_recv(void *self, hal_can_frame_t *f)
{
    sync_tap_t *t = self;
    const int r = hal_can_recv(&t->inner, f);
    if (r == 1 && ls_sync_watch_is_sync(f)) {
        ls_sync_watch_note(t->watch, mono_us());
    }
    return r;
}

static int tap_poll_fd(void *self)
{
    return hal_can_poll_fd(&((sync_tap_t *)self)->inner);
}

static int tap_status(void *self, hal_can_status_t *out)
{
    return hal_can_status(&((sync_tap_t *)self)->inner, out);
}

static void tap_close(void *self)
{
    hal_can_close(&((sync_tap_t *)self)->inner);
}

static int tap_hold_open(void *self, bool hold)
{
    return hal_can_hold_open(&((sync_tap_t *)self)->inner, hold);
}

static bool tap_tx_pending(void *self)
{
    return hal_can_tx_pending(&((sync_tap_t *)self)->inner);
}

static uint64_t tap_next_due_us(void *self)
{
    return hal_can_next_due_us(&((sync_tap_t *)self)->inner);
}

static const hal_can_ops_t k_tap_ops = { .send = tap_send,
                                         .recv = tap_recv,
                                         .poll_fd = tap_poll_fd,
                                         .status = tap_status,
                                         .close = tap_close,
                                         .hold_open = tap_hold_open,
                                         .tx_pending = tap_tx_pending,
                                         .next_due_us = tap_next_due_us };

static sync_tap_t g_tap;
static ls_sync_watch_t g_sync_watch; /* large: static */

/* Put the tap between the drives and *link. */
static void tap_syncs(hal_can_link_t *link)
{
    ls_sync_watch_init(&g_sync_watch);
    g_tap = (sync_tap_t){ .inner = *link, .watch = &g_sync_watch };
    hal_can_link_t tapped = { .ops = &k_tap_ops, .self = &g_tap };
    (void)snprintf(tapped.name, sizeof tapped.name, "%s", link->name);
    *link = tapped;
}

/* Sleep until a frame, a command, room for pending output or `due`; a
 * stop signal, blocked outside, ends the sleep (ppoll unblocks it). */
/* How often a failed link is tried again (its descriptor may stay readable
 * with the error, so it is not waited on meanwhile). */
#define LINK_RETRY_US 10000u
#define NO_FD (-1) /* the link's descriptor is not waited on */

static void wait_for_work(hal_can_link_t *link, bool link_failed, uint64_t due, const sigset_t *unblocked)
{
    struct pollfd fds[2];
    nfds_t n = 0;
    int lfd = link_failed ? NO_FD : hal_can_poll_fd(link);
    if (lfd >= 0) {
        short out = (hal_can_tx_pending(link) || hal_sim_drives_tx_pending()) ? POLLOUT : 0;
        fds[n++] = (struct pollfd){ .fd = lfd, .events = (short)(POLLIN | out), .revents = 0 };
    }
    if (hal_sim_drives_control_fd() >= 0) {
        fds[n++] = (struct pollfd){ .fd = hal_sim_drives_control_fd(), .events = POLLIN, .revents = 0 };
    }
    uint64_t now = mono_us();
    uint64_t wait_us = due > now ? due - now : 0u;
    const uint64_t cap = link_failed ? LINK_RETRY_US : 1000000u;
    if (wait_us > cap) {
        wait_us = cap;
    }
    const struct timespec ts = { .tv_sec = (time_t)(wait_us / 1000000u),
                                 .tv_nsec = (long)(wait_us % 1000000u) * 1000L };
    (void)ppoll(fds, n, &ts, unblocked);
}

int main(int argc, char **argv)
{
    static ls_simdrives_opts_t o;
    char msg[512] = "";
    int pr = ls_simdrives_parse(argc, argv, &o, msg, sizeof msg);
    if (pr == 1) {
        fputs(ls_simdrives_usage, stdout);
        return LS_EXIT_OK;
    }
    if (pr < 0) {
        LOG_ERR("%s", msg);
        return LS_EXIT_BAD_CONFIG;
    }
    if (o.rt_priority > 0) {
        /* Hardware answers each SYNC within the cycle; a simulator on a busy
         * machine does so only when it runs before the builds. Not granted:
         * it runs on, said once. */
        const struct sched_param sp = { .sched_priority = o.rt_priority };
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            LOG_WARN("--rt-priority %d: SCHED_FIFO refused (%s): running as a normal process", o.rt_priority,
                     strerror(errno));
        }
    }
    /* Stop signals are blocked but inside ppoll: no race between the flag's
     * test and the sleep. */
    sigset_t stop_set, unblocked;
    sigemptyset(&stop_set);
    sigaddset(&stop_set, SIGTERM);
    sigaddset(&stop_set, SIGINT);
    (void)sigprocmask(SIG_BLOCK, &stop_set, &unblocked);
    sigdelset(&unblocked, SIGTERM);
    sigdelset(&unblocked, SIGINT);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    (void)sigaction(SIGTERM, &sa, NULL);
    (void)sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    /* The arm landscaped drives: its model file, as landscaped reads it and
     * with what the simulator can build checked (ls_robot_config.h). */
    static ls_config_t robot_cfg;  /* large: not on the stack */
    static ls_robot_model_t model; /* the world keeps a pointer to its name */
    ls_config_defaults(&robot_cfg);
    (void)snprintf(robot_cfg.model, sizeof robot_cfg.model, "%s", o.model);
    if (ls_robot_config_load(&robot_cfg, &model, msg, sizeof msg) != LS_OK) {
        LOG_ERR("--model: %s", msg);
        return LS_EXIT_BAD_CONFIG;
    }
    hal_sim_arm_model_t arm;
    ls_robot_model_to_sim(&model, &arm);
    hal_sim_world_config_t wc = { .arm = &arm, .dio_socket_path = NULL, .lockstep = false, .with_obstacle = true };
    if (hal_sim_world_open(&wc, msg, sizeof msg) < 0) {
        LOG_ERR("the simulated world: %s", msg);
        return 1;
    }
    hal_can_link_t link;
    if (open_link(&o, &link) < 0) {
        hal_sim_world_close();
        return 1;
    }
    if (o.sync_stats) {
        tap_syncs(&link);
    }
    hal_sim_drives_config_t dc = { .link = &link,
                                   .n_drives = o.n_nodes,
                                   .counts_per_rad = o.counts_per_rad,
                                   .substep_s = o.substep_s,
                                   .control_socket_path = o.control[0] != '\0' ? o.control : NULL };
    for (size_t i = 0; i < o.n_nodes; i++) {
        dc.drives[i] = (hal_sim_drive_config_t){ .node_id = o.nodes[i],
                                                 .joint = (uint8_t)i,
                                                 .position_offset_counts = o.offsets[i] };
    }
    int rc = hal_sim_drives_open(&dc, mono_us(), msg, sizeof msg);
    if (rc < 0) {
        LOG_ERR("%s", msg);
        hal_can_close(&link);
        hal_sim_world_close();
        return rc == LS_EINVAL ? LS_EXIT_BAD_CONFIG : 1;
    }
    char nodes[6 * HAL_SIM_DRIVES_MAX + 1] = "";
    for (size_t i = 0; i < o.n_nodes; i++) {
        snprintf(nodes + strlen(nodes), sizeof nodes - strlen(nodes), "%s0x%02X", i > 0 ? "," : "", o.nodes[i]);
    }
    LOG_INFO("ready: nodes %s (joints 1-%zu) on %s, %.6g counts/rad, control %s", nodes, o.n_nodes, link.name,
             o.counts_per_rad, o.control[0] != '\0' ? o.control : "(none)");
    uint32_t malformed = 0;
    bool link_failed = false;
    while (!g_stop) {
        uint64_t now = mono_us();
        uint64_t due = hal_sim_drives_next_due_us(now);
        uint64_t link_due = hal_can_next_due_us(&link);
        wait_for_work(&link, link_failed, link_due < due ? link_due : due, &unblocked);
        int r = hal_sim_drives_poll(mono_us());
        /* A drive outlives its bus (an interface taken down, a cable pulled):
         * the drives run on, their heartbeat consumers stop the joints, and
         * the link is tried again until it carries frames. */
        if (r < 0 && !link_failed) {
            LOG_WARN("link %s failed (%s): the drives run on without it, trying it every %u ms", link.name,
                     ls_err_text(r), LINK_RETRY_US / 1000u);
            link_failed = true;
        } else if (r == LS_OK && link_failed) {
            LOG_INFO("link %s carries frames again", link.name);
            link_failed = false;
        }
        if (hal_sim_drives_malformed_messages() != malformed) {
            malformed = hal_sim_drives_malformed_messages();
            LOG_WARN("control: a malformed command was ignored (%" PRIu32 " so far; see hal_sim_drives.h)", malformed);
        }
    }
    if (g_stop) {
        LOG_INFO("%s received: shutting down", g_stop == SIGINT ? "SIGINT" : "SIGTERM");
    }
    hal_sim_drives_stats_t st;
    hal_sim_drives_stats(&st);
    LOG_INFO("%" PRIu64 " SYNCs stepped the physics (%" PRIu64 " sub-steps); frames: %" PRIu64 " in, %" PRIu64
             " out, %" PRIu64 " lost",
             st.syncs, st.substeps, st.rx_frames, st.tx_frames, st.tx_dropped);
    if (o.sync_stats) {
        char line[256];
        (void)ls_sync_watch_format(&g_sync_watch, line, sizeof line);
        LOG_INFO("%s", line);
    }
    char faults[512];
    if (hal_sim_faulty_format(o.sync_stats ? &g_tap.inner : &link, faults, sizeof faults) >= 0) {
        LOG_INFO("link %s faults: %s", link.name, faults);
    }
    hal_sim_drives_close();
    hal_can_close(&link);
    hal_sim_world_close();
    return LS_EXIT_OK;
}
