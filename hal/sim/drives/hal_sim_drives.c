/* The simulated drives on their link and the world (hal_sim_drives.h): the
 * nodes (sd_node.h), the physics stepped per SYNC, the frames to and from
 * the link, the control socket. */
#include "hal_sim_drives.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "sd_ctl.h"
#include "sd_node.h"

#define TX_RING 512u    /* frames waiting for the link */
#define LOCAL_RING 64u  /* frames the nodes sent, to be heard by the other nodes */
#define CTL_PER_POLL 64 /* datagrams per poll, so a flood cannot stretch a cycle */
#define NJ HAL_SIM_ARM_JOINTS
#define FROM_THE_LINK (-1) /* deliver(): a frame no local node sent */

typedef struct {
    hal_can_frame_t f;
    uint8_t from; /* index of the sending node */
} local_frame_t;

static struct {
    bool open;
    hal_can_link_t *link;
    size_t n;
    sd_node_t nodes[HAL_SIM_DRIVES_MAX];
    uint8_t joint[HAL_SIM_DRIVES_MAX];
    hal_arm_t arm;
    double substep_s; /* the physics' sub-step, about */
    double torque_max_Nm[NJ];
    hal_can_frame_t tx[TX_RING];
    size_t tx_head, tx_len;
    local_frame_t local[LOCAL_RING];
    size_t local_len;
    bool bus_off;
    uint64_t bus_off_until_us;
    int ctl_fd;
    char ctl_path[108];
    uint32_t malformed;
    hal_sim_drives_stats_t stats;
} S = { .ctl_fd = -1 };

/* ---- frames out ---- */

static void node_tx(void *ctx, const sd_node_t *from, const hal_can_frame_t *f)
{
    (void)ctx;
    if (S.bus_off) {
        S.stats.tx_dropped++;
        return;
    }
    if (S.tx_len == TX_RING) {
        S.stats.tx_dropped++;
    } else {
        S.tx[(S.tx_head + S.tx_len) % TX_RING] = *f;
        S.tx_len++;
    }
    /* The other nodes hear it, as on a bus (a consumer may watch a sibling). */
    if (S.n > 1 && S.local_len < LOCAL_RING) {
        S.local[S.local_len++] = (local_frame_t){ *f, (uint8_t)(from - S.nodes) };
    }
}

/* The frames the nodes sent, out to the link. A link that fails takes none
 * of them: they are dropped (and counted), as a drive's frames are when its
 * bus is gone, and the link's error is returned. */
static int flush_tx(void)
{
    while (S.tx_len > 0) {
        int r = hal_can_send(S.link, &S.tx[S.tx_head]);
        if (r == LS_EAGAIN) {
            return LS_OK;
        }
        if (r < 0) {
            S.stats.tx_dropped += S.tx_len;
            S.tx_len = 0;
            return r;
        }
        S.tx_head = (S.tx_head + 1) % TX_RING;
        S.tx_len--;
        S.stats.tx_frames++;
    }
    return LS_OK;
}

/* ---- the world ---- */

static int read_world(double q[NJ], double qd[NJ], double tau[NJ])
{
    int r = hal_arm_read(&S.arm, q, qd);
    if (r == LS_OK) {
        r = hal_sim_world_joint_torque(tau);
    }
    return r;
}

static void feed_all(double dt_s, uint64_t now_us)
{
    double q[NJ], qd[NJ], tau[NJ];
    if (read_world(q, qd, tau) != LS_OK) {
        return;
    }
    for (size_t i = 0; i < S.n; i++) {
        uint8_t j = S.joint[i];
        sd_joint_fb_t fb = { q[j], qd[j], tau[j] };
        sd_node_feedback(&S.nodes[i], &fb, dt_s, now_us);
    }
}

/* A SYNC: the nodes that take it sample and set their set-points, then the
 * world advances by the longest of their interpolation periods in sub-steps
 * of about substep_s, every drive commanding its joint in each. Joints without
 * a drive stay braked where they are. */
static void on_sync(const hal_can_frame_t *f, uint64_t now_us)
{
    double period_s = 0.0;
    for (size_t i = 0; i < S.n; i++) {
        if (sd_node_is_sync(&S.nodes[i], f)) {
            sd_node_sync(&S.nodes[i], now_us);
            period_s = fmax(period_s, sd_node_period_s(&S.nodes[i]));
        }
    }
    if (period_s <= 0.0) {
        return;
    }
    long steps = lround(period_s / S.substep_s);
    steps = steps < 1 ? 1 : steps;
    double dt_s = period_s / (double)steps;
    for (long s = 0; s < steps; s++) {
        double q[NJ], qd[NJ], tau[NJ];
        bool on[NJ] = { false };
        if (read_world(q, qd, tau) != LS_OK) {
            return;
        }
        for (int j = 0; j < NJ; j++) {
            qd[j] = 0.0;
        }
        for (size_t i = 0; i < S.n; i++) {
            sd_joint_cmd_t cmd;
            sd_node_substep(&S.nodes[i], dt_s, &cmd);
            uint8_t j = S.joint[i];
            q[j] = cmd.q_rad;
            qd[j] = cmd.qd_rad_s;
            on[j] = cmd.drive_on;
        }
        for (unsigned j = 0; j < NJ; j++) {
            (void)hal_sim_world_enable_joint(j, on[j]);
        }
        (void)hal_arm_command(&S.arm, q, qd);
        (void)hal_sim_world_step(NULL, dt_s);
        feed_all(dt_s, now_us);
        S.stats.substeps++;
    }
    S.stats.syncs++;
}

/* ---- frames in ---- */

static void tick_all(uint64_t now_us)
{
    for (size_t i = 0; i < S.n; i++) {
        sd_node_tick(&S.nodes[i], now_us);
    }
}

static void deliver(const hal_can_frame_t *f, int skip, uint64_t now_us)
{
    bool sync = false;
    for (size_t i = 0; i < S.n; i++) {
        sync = sync || ((int)i != skip && sd_node_is_sync(&S.nodes[i], f));
    }
    if (sync && skip == FROM_THE_LINK) {
        on_sync(f, now_us);
    }
    for (size_t i = 0; i < S.n; i++) {
        if ((int)i != skip) {
            sd_node_rx(&S.nodes[i], f, now_us);
        }
    }
}

/* What the nodes sent, heard by the others; bounded: what they send in
 * answer is heard too, up to the ring's size per call. */
static void deliver_local(uint64_t now_us)
{
    for (size_t k = 0; k < S.local_len && k < LOCAL_RING; k++) {
        local_frame_t lf = S.local[k];
        deliver(&lf.f, lf.from, now_us);
    }
    S.local_len = 0;
}

static void handle_frame(const hal_can_frame_t *f, uint64_t now_us)
{
    S.stats.rx_frames++;
    if (S.bus_off) {
        return;
    }
    deliver(f, FROM_THE_LINK, now_us);
    deliver_local(now_us);
    tick_all(now_us);
}

int hal_sim_drives_rx(const hal_can_frame_t *frame, uint64_t now_us)
{
    if (!S.open) {
        return LS_ENODEV;
    }
    handle_frame(frame, now_us);
    (void)flush_tx();
    return LS_OK;
}

/* ---- control ---- */

static sd_node_t *node_by_id(uint8_t id)
{
    for (size_t i = 0; i < S.n; i++) {
        if (S.nodes[i].cfg.node_id == id) {
            return &S.nodes[i];
        }
    }
    return NULL;
}

static void set_bus_off(bool off, uint64_t now_us)
{
    if (S.bus_off == off) {
        return;
    }
    if (off) {
        for (size_t i = 0; i < S.n; i++) {
            sd_node_bus_off(&S.nodes[i], now_us);
        }
        S.bus_off = true;
        S.tx_len = 0; /* what waited for the link is lost with it */
        return;
    }
    S.bus_off = false;
    for (size_t i = 0; i < S.n; i++) {
        sd_node_bus_recovered(&S.nodes[i], now_us);
    }
}

int hal_sim_drives_control(const char *text, size_t len, uint64_t now_us)
{
    if (!S.open) {
        return LS_ENODEV;
    }
    sd_ctl_cmd_t c;
    sd_node_t *n = NULL;
    if (sd_ctl_parse(text, len, &c) != LS_OK ||
        (c.kind != SD_CTL_BUS_OFF && c.kind != SD_CTL_RESET && (n = node_by_id(c.node)) == NULL)) {
        S.malformed++;
        return LS_EINVAL;
    }
    switch (c.kind) {
    case SD_CTL_EMCY: sd_node_inject_emcy(n, (uint16_t)c.a, now_us); break;
    case SD_CTL_SILENCE: n->mis.silent = true; break;
    case SD_CTL_FREEZE_TPDO: n->mis.tpdo_frozen = true; break;
    case SD_CTL_STICKY: n->mis.sticky = c.a; break;
    case SD_CTL_NO_BOOT: n->mis.no_boot = true; break;
    case SD_CTL_IDENTITY:
        n->mis.identity = true;
        n->mis.vendor = c.a;
        n->mis.product = c.b;
        break;
    case SD_CTL_STO: sd_node_set_sto(n, c.a != 0u, now_us); break;
    case SD_CTL_BUS_OFF:
        set_bus_off(true, now_us);
        S.bus_off_until_us = now_us + (uint64_t)c.a * 1000u;
        break;
    case SD_CTL_RESET:
        set_bus_off(false, now_us);
        for (size_t i = 0; i < S.n; i++) {
            sd_node_behave(&S.nodes[i], now_us);
        }
        break;
    }
    deliver_local(now_us);
    tick_all(now_us);
    (void)flush_tx();
    return 1;
}

static void drain_control(uint64_t now_us)
{
    if (S.ctl_fd < 0) {
        return;
    }
    for (int k = 0; k < CTL_PER_POLL; k++) {
        char buf[HAL_SIM_DRIVES_CTL_MAX_MSG + 1];
        ssize_t r = recv(S.ctl_fd, buf, sizeof buf, MSG_DONTWAIT);
        if (r < 0) {
            return; /* EAGAIN: drained */
        }
        (void)hal_sim_drives_control(buf, (size_t)r, now_us); /* over-long: the parser refuses it */
    }
}

static int open_control(const char *path, char *msg, size_t msglen)
{
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    size_t len = strlen(path);
    if (len == 0 || len >= sizeof addr.sun_path) {
        snprintf(msg, msglen, "control socket path '%s' is empty or longer than %zu bytes; use a shorter path", path,
                 sizeof addr.sun_path - 1);
        return LS_EINVAL;
    }
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISSOCK(st.st_mode)) {
            snprintf(msg, msglen, "control socket path '%s' exists and is not a socket; remove it or pick another",
                     path);
            return LS_EINVAL;
        }
        (void)unlink(path); /* a stale socket of an earlier run */
    }
    int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        snprintf(msg, msglen, "cannot create the control socket: %s", strerror(errno));
        return LS_EIO;
    }
    memcpy(addr.sun_path, path, len);
    if (bind(fd, (const struct sockaddr *)&addr, sizeof addr) != 0) {
        snprintf(msg, msglen, "cannot bind the control socket '%s' (does the directory exist and is it writable?): %s",
                 path, strerror(errno));
        (void)close(fd);
        return LS_EIO;
    }
    S.ctl_fd = fd;
    memcpy(S.ctl_path, path, len + 1);
    return LS_OK;
}

/* ---- life cycle ---- */

static int check_config(const hal_sim_drives_config_t *cfg, char *msg, size_t msglen)
{
    if (cfg == NULL || cfg->link == NULL || cfg->link->ops == NULL) {
        snprintf(msg, msglen, "the simulated drives need a config with an open CAN link");
        return LS_EINVAL;
    }
    if (cfg->n_drives < 1 || cfg->n_drives > HAL_SIM_DRIVES_MAX) {
        snprintf(msg, msglen, "%zu drives: between 1 and %d (one per joint)", cfg->n_drives, HAL_SIM_DRIVES_MAX);
        return LS_EINVAL;
    }
    if (!(cfg->counts_per_rad > 0.0 && cfg->counts_per_rad <= 1e9)) {
        snprintf(msg, msglen, "counts per radian %g: must be above 0 and at most 1e9", cfg->counts_per_rad);
        return LS_EINVAL;
    }
    if (!(cfg->substep_s >= 0.0 && cfg->substep_s <= HAL_SIM_DRIVES_SUBSTEP_MAX_S)) {
        snprintf(msg, msglen, "physics sub-step %g s: must be above 0 and at most %g s (0: %g s)", cfg->substep_s,
                 HAL_SIM_DRIVES_SUBSTEP_MAX_S, HAL_SIM_DRIVES_SUBSTEP_S);
        return LS_EINVAL;
    }
    for (size_t i = 0; i < cfg->n_drives; i++) {
        const hal_sim_drive_config_t *d = &cfg->drives[i];
        if (d->node_id < LS_CO_NODE_MIN || d->node_id > LS_CO_NODE_MAX || d->joint >= NJ) {
            snprintf(msg, msglen, "drive %zu: node id 0x%02X (1..0x7F) or joint %u (1..%d) out of range", i + 1,
                     (unsigned)d->node_id, (unsigned)d->joint + 1u, NJ);
            return LS_EINVAL;
        }
        for (size_t k = 0; k < i; k++) {
            if (cfg->drives[k].node_id == d->node_id || cfg->drives[k].joint == d->joint) {
                snprintf(msg, msglen, "drives %zu and %zu share a node id or a joint", k + 1, i + 1);
                return LS_EINVAL;
            }
        }
    }
    return LS_OK;
}

int hal_sim_drives_open(const hal_sim_drives_config_t *cfg, uint64_t now_us, char *msg, size_t msglen)
{
    if (S.open) {
        snprintf(msg, msglen, "the simulated drives are already open (one set per process)");
        return LS_EINVAL;
    }
    int rc = check_config(cfg, msg, msglen);
    if (rc == LS_OK) {
        rc = sd_node_check_od(msg, msglen);
    }
    if (rc != LS_OK) {
        return rc;
    }
    hal_arm_t arm;
    hal_sim_world_get_arm(&arm);
    hal_arm_info_t info;
    if (hal_arm_info(&arm, &info) != LS_OK) {
        snprintf(msg, msglen, "the simulated world is not open: open it before the drives");
        return LS_ENODEV;
    }
    memset(&S, 0, sizeof S);
    S.ctl_fd = -1;
    if (cfg->control_socket_path != NULL) {
        rc = open_control(cfg->control_socket_path, msg, msglen);
        if (rc != LS_OK) {
            return rc;
        }
    }
    S.arm = arm;
    S.link = cfg->link;
    S.substep_s = cfg->substep_s > 0.0 ? cfg->substep_s : HAL_SIM_DRIVES_SUBSTEP_S;
    S.n = cfg->n_drives;
    double q[NJ], qd[NJ], tau[NJ];
    (void)read_world(q, qd, tau);
    for (size_t i = 0; i < S.n; i++) {
        const hal_sim_drive_config_t *d = &cfg->drives[i];
        S.joint[i] = d->joint;
        sd_node_config_t nc = { .node_id = d->node_id,
                                .counts_per_rad = cfg->counts_per_rad,
                                .position_offset_counts = d->position_offset_counts,
                                .torque_max_Nm = info.torque_max_Nm[d->joint],
                                .tx = node_tx,
                                .tx_ctx = NULL };
        sd_joint_fb_t fb = { q[d->joint], qd[d->joint], 0.0 };
        sd_node_init(&S.nodes[i], &nc, &fb, now_us);
    }
    for (unsigned j = 0; j < NJ; j++) {
        (void)hal_sim_world_enable_joint(j, false);
    }
    S.local_len = 0; /* the boot-ups: nobody local listens to them */
    S.open = true;
    (void)flush_tx();
    return LS_OK;
}

void hal_sim_drives_close(void)
{
    if (S.ctl_fd >= 0) {
        (void)close(S.ctl_fd);
        (void)unlink(S.ctl_path);
    }
    memset(&S, 0, sizeof S);
    S.ctl_fd = -1;
}

int hal_sim_drives_poll(uint64_t now_us)
{
    if (!S.open) {
        return LS_ENODEV;
    }
    if (S.bus_off && now_us >= S.bus_off_until_us) {
        set_bus_off(false, now_us);
    }
    /* A drive outlives its bus: when the link fails, the nodes still keep
     * their time (a heartbeat consumer stops a moving joint, 0x6007). */
    int link_err = LS_OK;
    for (unsigned k = 0; k < HAL_SIM_DRIVES_RX_PER_POLL; k++) {
        hal_can_frame_t f;
        int r = hal_can_recv(S.link, &f);
        if (r == LS_EAGAIN) {
            break;
        }
        if (r < 0) {
            link_err = r;
            break;
        }
        handle_frame(&f, now_us);
        if (S.tx_len > TX_RING / 2) {
            (void)flush_tx(); /* keep up while a burst comes in */
        }
    }
    drain_control(now_us);
    deliver_local(now_us);
    tick_all(now_us);
    const int r = flush_tx();
    return link_err != LS_OK ? link_err : r;
}

uint64_t hal_sim_drives_next_due_us(uint64_t now_us)
{
    if (!S.open) {
        return UINT64_MAX;
    }
    uint64_t due = S.bus_off ? S.bus_off_until_us : UINT64_MAX;
    for (size_t i = 0; i < S.n; i++) {
        uint64_t t = sd_node_next_due_us(&S.nodes[i], now_us);
        due = t < due ? t : due;
    }
    return due;
}

int hal_sim_drives_control_fd(void)
{
    return S.ctl_fd;
}

bool hal_sim_drives_tx_pending(void)
{
    return S.tx_len > 0;
}

uint32_t hal_sim_drives_malformed_messages(void)
{
    return S.malformed;
}

void hal_sim_drives_stats(hal_sim_drives_stats_t *out)
{
    *out = S.stats;
}
