/* landscaped: the LandScape controller.
 *
 *   landscaped --hal sim --link slcan:pty:/tmp/landscape0 [--link ...] [--node 0x10]
 *
 * Threads: this comms thread (links, ISO-TP, dispatcher, telemetry). Logs go
 * to stderr with a level prefix that journald understands. */
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "landscape.h" /* cantools: DBC pack functions */
#include "ls_core.h"
#include "ls_net.h"
#include "slcan_pty.h"

#ifndef LS_FIRMWARE_VERSION
#define LS_FIRMWARE_VERSION "0.0.0"
#endif

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

/* sd-daemon style level prefixes: journald stores them as priorities. */
static void logf_(int level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void logf_(int level, const char *fmt, ...)
{
    static const char *names[] = { "", "", "", "error", "warning", "", "info", "debug" };
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "<%d>landscaped: %s: ", level, names[level & 7]);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}
#define LOG_ERR(...) logf_(3, __VA_ARGS__)
#define LOG_WARN(...) logf_(4, __VA_ARGS__)
#define LOG_INFO(...) logf_(6, __VA_ARGS__)

static uint64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

typedef struct {
    const char *hal;
    const char *links[LS_NET_MAX_LINKS];
    size_t n_links;
    unsigned node;
    unsigned heartbeat_timeout_ms;
    const char *name;
} options_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: landscaped --hal sim --link SPEC [--link SPEC ...] [options]\n"
            "\n"
            "  --hal sim                 simulated controller (the only HAL composition so far)\n"
            "  --link slcan:pty:PATH     SLCAN on a new pseudo-terminal; PATH becomes a symlink to it\n"
            "                            (repeatable: every link is one segment of the same bus)\n"
            "  --node ADDR               node address on the bus (default 0x10)\n"
            "  --heartbeat-timeout MS    drop a supervisor after MS without heartbeat (default 1000)\n"
            "  --name NAME               device name reported at connect (default landscape-sim)\n"
            "  -h, --help                this text\n");
}

static int parse_uint(const char *s, unsigned max, unsigned *out)
{
    char *end = NULL;
    errno = 0;
    unsigned long v = strtoul(s, &end, 0);
    if (errno != 0 || end == s || *end != '\0' || v > max) {
        return -1;
    }
    *out = (unsigned)v;
    return 0;
}

static int parse_options(int argc, char **argv, options_t *o)
{
    static const struct option longopts[] = {
        { "hal", required_argument, NULL, 'H' },
        { "link", required_argument, NULL, 'l' },
        { "node", required_argument, NULL, 'n' },
        { "heartbeat-timeout", required_argument, NULL, 't' },
        { "name", required_argument, NULL, 'N' },
        { "help", no_argument, NULL, 'h' },
        { NULL, 0, NULL, 0 },
    };
    memset(o, 0, sizeof *o);
    o->node = 0x10;
    o->heartbeat_timeout_ms = 1000;
    o->name = "landscape-sim";
    int c;
    while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        switch (c) {
        case 'H': o->hal = optarg; break;
        case 'l':
            if (o->n_links >= LS_NET_MAX_LINKS) {
                LOG_ERR("at most %d --link options", LS_NET_MAX_LINKS);
                return -1;
            }
            o->links[o->n_links++] = optarg;
            break;
        case 'n':
            if (parse_uint(optarg, 0xFE, &o->node) != 0 || o->node == 0) {
                LOG_ERR("--node %s: expected an address 1..0xFE (0xFF is the broadcast address)", optarg);
                return -1;
            }
            break;
        case 't':
            if (parse_uint(optarg, 600000, &o->heartbeat_timeout_ms) != 0 || o->heartbeat_timeout_ms < 50) {
                LOG_ERR("--heartbeat-timeout %s: expected milliseconds 50..600000", optarg);
                return -1;
            }
            break;
        case 'N': o->name = optarg; break;
        case 'h': usage(stdout); exit(0);
        default: usage(stderr); return -1;
        }
    }
    if (optind < argc) {
        LOG_ERR("unexpected argument '%s' (see --help)", argv[optind]);
        return -1;
    }
    if (o->hal == NULL || strcmp(o->hal, "sim") != 0) {
        LOG_ERR("--hal %s: expected --hal sim", o->hal != NULL ? o->hal : "(missing)");
        return -1;
    }
    if (o->n_links == 0) {
        LOG_ERR("no --link given: add e.g. --link slcan:pty:/tmp/landscape0");
        return -1;
    }
    return 0;
}

static int open_link(const char *spec, hal_can_link_t *out)
{
    char msg[256] = "";
    if (strncmp(spec, "slcan:pty:", 10) == 0) {
        int r = hal_sim_slcan_pty_open(out, spec + 10, msg, sizeof msg);
        if (r < 0) {
            LOG_ERR("--link %s: %s", spec, msg);
            return -1;
        }
        return 0;
    }
    LOG_ERR("--link %s: unknown link kind; expected slcan:pty:PATH", spec);
    return -1;
}

static void send_heartbeat(ls_net_t *net, const ls_core_t *core, uint8_t counter)
{
    struct landscape_heartbeat_t hb = {
        .hb_counter = counter,
        .hb_state = (uint8_t)core->state,
        .hb_role = 0,
        .hb_owner = core->owner >= 0 ? core->sessions[core->owner].addr : 0,
        .hb_fault = core->fault[0] != '\0' ? 1u : 0u,
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

static ls_core_t g_core;
static ls_net_t g_net;

int main(int argc, char **argv)
{
    options_t opt;
    if (parse_options(argc, argv, &opt) != 0) {
        return 2;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    ls_core_config_t cfg = {
        .device_name = opt.name,
        .firmware_version = LS_FIRMWARE_VERSION,
        .node_addr = (uint8_t)opt.node,
        .joint_count = 6,
        .heartbeat_timeout_ms = opt.heartbeat_timeout_ms,
    };
    ls_core_io_t io = { .send_downlink = ls_net_send_downlink, .ctx = &g_net };
    ls_core_init(&g_core, &cfg, &io, NULL);
    ls_net_init(&g_net, (uint8_t)opt.node, &g_core);

    int rc = 0;
    for (size_t i = 0; i < opt.n_links; i++) {
        hal_can_link_t link;
        if (open_link(opt.links[i], &link) != 0) {
            rc = 1;
            break;
        }
        (void)ls_net_add_link(&g_net, &link);
        LOG_INFO("link %s up", link.name);
    }
    if (rc == 0) {
        LOG_INFO("%s ready: node 0x%02X, firmware %s, schema %08X", opt.name, opt.node, LS_FIRMWARE_VERSION,
                 (unsigned)LS_SCHEMA_HASH);
    }
    uint64_t next_hb = mono_us();
    uint8_t hb_counter = 0;
    while (rc == 0 && !g_stop) {
        struct pollfd fds[LS_NET_MAX_LINKS];
        nfds_t n = 0;
        for (size_t i = 0; i < g_net.n_links; i++) {
            int fd = hal_can_poll_fd(&g_net.links[i]);
            if (fd >= 0) {
                fds[n].fd = fd;
                fds[n].events = POLLIN;
                fds[n].revents = 0;
                n++;
            }
        }
        (void)poll(fds, n, 1);
        uint64_t now = mono_us();
        ls_net_poll(&g_net, now);
        ls_core_tick(&g_core, now);
        if (now >= next_hb) {
            send_heartbeat(&g_net, &g_core, hb_counter++);
            next_hb = now + 200000u;
        }
    }
    LOG_INFO("shutting down");
    ls_net_close(&g_net);
    return rc;
}
