#include "hal_linux_socketcan.h"

#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <linux/can/error.h>
#include <linux/can/netlink.h>
#include <linux/can/raw.h>
#include <linux/if_arp.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>

#include "hal_linux_msg.h"

#ifndef SO_RXQ_OVFL
#define SO_RXQ_OVFL 40
#endif

typedef struct {
    bool in_use;
    int fd;
    char ifname[IFNAMSIZ];
    char operstate_path[64];
    hal_can_status_t st;   /* state, counters except rx_dropped */
    uint32_t parse_drops;  /* records we could not use */
    uint32_t kernel_drops; /* last SO_RXQ_OVFL count: cumulative for the socket */
} sc_link_t;

static sc_link_t g_links[HAL_LINUX_SOCKETCAN_MAX_LINKS];
static pthread_mutex_t g_pool_lock = PTHREAD_MUTEX_INITIALIZER;

/* ---- frame conversion ---------------------------------------------------- */

int hal_linux_socketcan_encode(const hal_can_frame_t *in, struct can_frame *out)
{
    if (in == NULL || out == NULL || in->len > 8u || (in->flags & ~(HAL_CAN_F_EXT | HAL_CAN_F_RTR)) != 0u) {
        return LS_EINVAL;
    }
    bool ext = (in->flags & HAL_CAN_F_EXT) != 0u;
    if (in->id > (ext ? CAN_EFF_MASK : CAN_SFF_MASK)) {
        return LS_EINVAL;
    }
    memset(out, 0, sizeof *out);
    out->can_id = in->id | (ext ? CAN_EFF_FLAG : 0u) | ((in->flags & HAL_CAN_F_RTR) != 0u ? CAN_RTR_FLAG : 0u);
    out->can_dlc = in->len;
    if ((in->flags & HAL_CAN_F_RTR) == 0u) {
        memcpy(out->data, in->data, in->len);
    }
    return LS_OK;
}

/* The worst of the RX and TX states a controller-problem error frame reports. */
static hal_can_state_t crtl_state(uint8_t d1, hal_can_state_t current)
{
    if ((d1 & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0u) {
        return HAL_CAN_STATE_PASSIVE;
    }
    if ((d1 & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0u) {
        return HAL_CAN_STATE_WARNING;
    }
    if ((d1 & CAN_ERR_CRTL_ACTIVE) != 0u) {
        return HAL_CAN_STATE_ACTIVE;
    }
    return current; /* overflow reports and unspecified problems leave the state as it is */
}

int hal_linux_socketcan_decode(const struct can_frame *in, hal_can_frame_t *out, hal_can_status_t *st)
{
    if (in == NULL || out == NULL || st == NULL) {
        return LS_EINVAL;
    }
    if ((in->can_id & CAN_ERR_FLAG) != 0u) {
        canid_t cls = in->can_id & CAN_ERR_MASK;
        st->error_frames++;
        /* A restart report comes after bus-off; the same frame may carry a new
         * controller state, which then wins. */
        if ((cls & CAN_ERR_RESTARTED) != 0u) {
            st->state = HAL_CAN_STATE_ACTIVE;
        }
        if ((cls & CAN_ERR_CRTL) != 0u && in->can_dlc >= 2u) {
            st->state = crtl_state(in->data[1], st->state);
        }
        if ((cls & CAN_ERR_BUSOFF) != 0u) {
            st->state = HAL_CAN_STATE_BUS_OFF;
        }
        return 0;
    }
    if (in->can_dlc > 8u) {
        st->rx_dropped++;
        return LS_EINVAL;
    }
    memset(out, 0, sizeof *out);
    bool ext = (in->can_id & CAN_EFF_FLAG) != 0u;
    out->id = in->can_id & (ext ? CAN_EFF_MASK : CAN_SFF_MASK);
    out->flags = (uint8_t)((ext ? HAL_CAN_F_EXT : 0u) | ((in->can_id & CAN_RTR_FLAG) != 0u ? HAL_CAN_F_RTR : 0u));
    out->len = in->can_dlc;
    if ((out->flags & HAL_CAN_F_RTR) == 0u) {
        memcpy(out->data, in->data, in->can_dlc);
    }
    return 1;
}

/* ---- link operations ----------------------------------------------------- */

static int sc_send(void *self, const hal_can_frame_t *frame)
{
    sc_link_t *l = self;
    struct can_frame cf;
    if (hal_linux_socketcan_encode(frame, &cf) != LS_OK) {
        return LS_EINVAL;
    }
    for (;;) {
        ssize_t n = write(l->fd, &cf, sizeof cf);
        if (n == (ssize_t)sizeof cf) {
            l->st.tx_frames++;
            return LS_OK;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK)) {
            /* A full TX queue during bus-off drains only after a restart. */
            return l->st.state == HAL_CAN_STATE_BUS_OFF ? LS_EBUSOFF : LS_EAGAIN;
        }
        l->st.tx_dropped++;
        return LS_EIO; /* ENETDOWN (interface went down), EBADF, short write */
    }
}

/* Error frames are consumed here; a bounded number per call so a storm of
 * them cannot keep the comms thread in recv. */
#define SC_MAX_RECORDS_PER_RECV 32

static int sc_recv(void *self, hal_can_frame_t *frame)
{
    sc_link_t *l = self;
    if (frame == NULL) {
        return LS_EINVAL;
    }
    for (int i = 0; i < SC_MAX_RECORDS_PER_RECV; i++) {
        struct can_frame cf;
        struct iovec iov = { .iov_base = &cf, .iov_len = sizeof cf };
        union {
            char buf[CMSG_SPACE(sizeof(uint32_t))];
            struct cmsghdr align;
        } ctrl;
        struct msghdr mh = {
            .msg_iov = &iov, .msg_iovlen = 1, .msg_control = ctrl.buf, .msg_controllen = sizeof ctrl.buf
        };
        ssize_t n = recvmsg(l->fd, &mh, MSG_DONTWAIT);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                break;
            }
            return LS_EIO; /* ENETDOWN: the interface went down */
        }
        if (n == 0) {
            return LS_EIO; /* the peer of an adopted stream/seqpacket socket closed */
        }
        for (struct cmsghdr *c = CMSG_FIRSTHDR(&mh); c != NULL; c = CMSG_NXTHDR(&mh, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL &&
                c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
                memcpy(&l->kernel_drops, CMSG_DATA(c), sizeof l->kernel_drops);
            }
        }
        if (n != (ssize_t)sizeof cf || (mh.msg_flags & MSG_TRUNC) != 0) {
            l->parse_drops++; /* CAN FD or foreign record */
            continue;
        }
        hal_can_status_t st = l->st;
        st.rx_dropped = 0;
        int r = hal_linux_socketcan_decode(&cf, frame, &st);
        l->parse_drops += st.rx_dropped;
        st.rx_dropped = 0;
        l->st = st;
        if (r == 1) {
            l->st.rx_frames++;
            return 1;
        }
    }
    return l->st.state == HAL_CAN_STATE_BUS_OFF ? LS_EBUSOFF : LS_EAGAIN;
}

static int sc_poll_fd(void *self)
{
    const sc_link_t *l = self;
    return l->fd;
}

/* operstate "down" with the interface administratively up is what the kernel
 * shows after bus-off without restart-ms (carrier off); either way the link
 * is not on the bus. */
static bool operstate_off_bus(const char *path)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        return false; /* adopted socket or sysfs not mounted: trust error frames */
    }
    char buf[32];
    ssize_t n = read(fd, buf, sizeof buf - 1);
    (void)close(fd);
    if (n <= 0) {
        return false;
    }
    buf[n] = '\0';
    return strncmp(buf, "down", 4) == 0 || strncmp(buf, "lowerlayerdown", 14) == 0 ||
           strncmp(buf, "notpresent", 10) == 0;
}

static int sc_status(void *self, hal_can_status_t *out)
{
    const sc_link_t *l = self;
    if (out == NULL) {
        return LS_EINVAL;
    }
    *out = l->st;
    out->rx_dropped = l->parse_drops + l->kernel_drops;
    if (l->operstate_path[0] != '\0' && operstate_off_bus(l->operstate_path)) {
        out->state = HAL_CAN_STATE_BUS_OFF;
    }
    return LS_OK;
}

static void sc_close(void *self)
{
    sc_link_t *l = self;
    (void)pthread_mutex_lock(&g_pool_lock);
    if (l->in_use) {
        (void)close(l->fd);
        l->fd = -1;
        l->in_use = false;
    }
    (void)pthread_mutex_unlock(&g_pool_lock);
}

static const hal_can_ops_t sc_ops = {
    .send = sc_send,
    .recv = sc_recv,
    .poll_fd = sc_poll_fd,
    .status = sc_status,
    .close = sc_close,
};

/* ---- rtnetlink: bitrate and controller state at open (best effort) ------- */

typedef hal_linux_socketcan_link_info_t sc_netlink_info_t;

/* Walk netlink attributes without the RTA_* macros (their int arithmetic
 * trips -Wsign-conversion): the next attribute at *off, false at the end or
 * on a malformed length. */
static bool attr_next(const char *base, size_t len, size_t *off, unsigned short *type, const char **payload,
                      size_t *plen)
{
    if (*off + sizeof(struct rtattr) > len) {
        return false;
    }
    struct rtattr a;
    memcpy(&a, base + *off, sizeof a);
    if (a.rta_len < sizeof(struct rtattr) || a.rta_len > len - *off) {
        return false;
    }
    *type = a.rta_type;
    *payload = base + *off + RTA_LENGTH(0u);
    *plen = a.rta_len - RTA_LENGTH(0u);
    *off += RTA_ALIGN((size_t)a.rta_len);
    return true;
}

static void parse_can_data(const char *data, size_t len, sc_netlink_info_t *info)
{
    size_t off = 0;
    unsigned short type;
    const char *p;
    size_t plen;
    while (attr_next(data, len, &off, &type, &p, &plen)) {
        if (type == IFLA_CAN_BITTIMING && plen >= sizeof(struct can_bittiming)) {
            struct can_bittiming bt;
            memcpy(&bt, p, sizeof bt);
            info->bitrate = bt.bitrate;
        } else if (type == IFLA_CAN_STATE && plen >= sizeof(uint32_t)) {
            uint32_t s;
            memcpy(&s, p, sizeof s);
            info->have_state = true;
            switch (s) {
            case CAN_STATE_ERROR_ACTIVE: info->state = HAL_CAN_STATE_ACTIVE; break;
            case CAN_STATE_ERROR_WARNING: info->state = HAL_CAN_STATE_WARNING; break;
            case CAN_STATE_ERROR_PASSIVE: info->state = HAL_CAN_STATE_PASSIVE; break;
            default: info->state = HAL_CAN_STATE_BUS_OFF; break; /* bus-off, stopped, sleeping */
            }
        }
    }
}

static bool parse_linkinfo(const char *li, size_t len, sc_netlink_info_t *info)
{
    bool is_can = false;
    const char *data = NULL;
    size_t data_len = 0;
    size_t off = 0;
    unsigned short type;
    const char *p;
    size_t plen;
    while (attr_next(li, len, &off, &type, &p, &plen)) {
        if ((type & NLA_TYPE_MASK) == IFLA_INFO_KIND) {
            is_can = plen >= 3u && memcmp(p, "can", 3) == 0 && (plen == 3u || p[3] == '\0');
        } else if ((type & NLA_TYPE_MASK) == IFLA_INFO_DATA) {
            data = p;
            data_len = plen;
        }
    }
    if (is_can && data != NULL) {
        parse_can_data(data, data_len, info);
        return true;
    }
    return false;
}

int hal_linux_socketcan_parse_link(const void *buf, size_t len, hal_linux_socketcan_link_info_t *info)
{
    if (buf == NULL || info == NULL) {
        return LS_EINVAL;
    }
    const char *base = buf;
    int found = 0;
    size_t off = 0;
    while (off + sizeof(struct nlmsghdr) <= len) {
        struct nlmsghdr nh;
        memcpy(&nh, base + off, sizeof nh);
        if (nh.nlmsg_len < sizeof nh || nh.nlmsg_len > len - off) {
            break;
        }
        size_t hdr = NLMSG_LENGTH(NLMSG_ALIGN(sizeof(struct ifinfomsg)));
        if (nh.nlmsg_type == RTM_NEWLINK && nh.nlmsg_len >= hdr) {
            size_t aoff = 0;
            unsigned short type;
            const char *p;
            size_t plen;
            while (attr_next(base + off + hdr, nh.nlmsg_len - hdr, &aoff, &type, &p, &plen)) {
                if ((type & NLA_TYPE_MASK) == IFLA_LINKINFO && parse_linkinfo(p, plen, info)) {
                    found = 1;
                }
            }
        }
        off += NLMSG_ALIGN((size_t)nh.nlmsg_len);
    }
    return found;
}

static void netlink_query(int ifindex, sc_netlink_info_t *info)
{
    int nl = socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    if (nl < 0) {
        return;
    }
    struct timeval tv = { .tv_sec = 1, .tv_usec = 0 }; /* never hang open on a stuck netlink */
    (void)setsockopt(nl, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    struct {
        struct nlmsghdr nh;
        struct ifinfomsg ifi;
    } req;
    memset(&req, 0, sizeof req);
    req.nh.nlmsg_len = NLMSG_LENGTH(sizeof req.ifi);
    req.nh.nlmsg_type = RTM_GETLINK;
    req.nh.nlmsg_flags = NLM_F_REQUEST;
    req.nh.nlmsg_seq = 1;
    req.ifi.ifi_family = AF_UNSPEC;
    req.ifi.ifi_index = ifindex;
    if (send(nl, &req, req.nh.nlmsg_len, 0) < 0) {
        (void)close(nl);
        return;
    }
    union {
        char buf[16384];
        struct nlmsghdr align;
    } resp;
    ssize_t n = recv(nl, resp.buf, sizeof resp.buf, 0);
    (void)close(nl);
    if (n <= 0) {
        return;
    }
    (void)hal_linux_socketcan_parse_link(resp.buf, (size_t)n, info);
}

/* ---- open ------------------------------------------------------------------ */

static const char *state_name(hal_can_state_t s)
{
    switch (s) {
    case HAL_CAN_STATE_ACTIVE: return "active";
    case HAL_CAN_STATE_WARNING: return "warning";
    case HAL_CAN_STATE_PASSIVE: return "passive";
    case HAL_CAN_STATE_BUS_OFF: return "bus-off";
    }
    return "unknown";
}

static const char *const k_afcan_fix =
    "load the modules (modprobe can can-raw) or use a kernel with CONFIG_CAN and CONFIG_CAN_RAW; "
    "on a machine without CAN use --link slcan:pty:PATH";

static int check_ifname(const char *ifname, char *msg, size_t msglen)
{
    if (ifname == NULL || ifname[0] == '\0') {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "no CAN interface name given (e.g. can0 or vcan0)");
    }
    if (strlen(ifname) >= IFNAMSIZ) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "CAN interface name '%s' is longer than %d characters", ifname,
                             IFNAMSIZ - 1);
    }
    return LS_OK;
}

/* Socket, interface checks, error filter, bind. On success *fd_out is a
 * bound non-blocking CAN_RAW socket. */
static int sc_configure(const char *ifname, int *fd_out, sc_netlink_info_t *info, char *msg, size_t msglen)
{
    int rc = check_ifname(ifname, msg, msglen);
    if (rc != LS_OK) {
        return rc;
    }
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        int e = errno;
        if (e == EAFNOSUPPORT) {
            return hal_linux_msg(LS_ENOAFCAN, msg, msglen, "this kernel has no AF_CAN (SocketCAN) support: %s",
                                 k_afcan_fix);
        }
        if (e == EPROTONOSUPPORT) {
            return hal_linux_msg(LS_ENOAFCAN, msg, msglen,
                                 "this kernel has AF_CAN but no CAN_RAW protocol: modprobe can-raw "
                                 "(CONFIG_CAN_RAW); on a machine without CAN use --link slcan:pty:PATH");
        }
        if (e == EPERM || e == EACCES) {
            return hal_linux_msg(LS_EPERM, msg, msglen,
                                 "no permission to open a CAN_RAW socket (%s): run as root or lift the "
                                 "seccomp/LSM policy that blocks AF_CAN",
                                 strerror(e));
        }
        return hal_linux_msg(LS_EIO, msg, msglen, "socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: %s", strerror(e));
    }

    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    memcpy(ifr.ifr_name, ifname, strlen(ifname));
    const char *bringup = "bring it up with 'ip link set %s up type can bitrate 500000' "
                          "(or 'ip link add dev vcan0 type vcan && ip link set vcan0 up')";
    char hint[192];
    (void)snprintf(hint, sizeof hint, bringup, ifname);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        int e = errno;
        (void)close(fd);
        if (e == ENODEV) {
            return hal_linux_msg(LS_ENODEV, msg, msglen, "no CAN interface '%s': %s", ifname, hint);
        }
        return hal_linux_msg(LS_EIO, msg, msglen, "cannot look up interface '%s': %s", ifname, strerror(e));
    }
    int ifindex = ifr.ifr_ifindex;

    if (ioctl(fd, SIOCGIFHWADDR, &ifr) == 0 && ifr.ifr_hwaddr.sa_family != ARPHRD_CAN) {
        (void)close(fd);
        return hal_linux_msg(LS_ENODEV, msg, msglen,
                             "interface '%s' is not a CAN interface (link type %u): name a CAN or vcan interface "
                             "(ip -details link show type can)",
                             ifname, (unsigned)ifr.ifr_hwaddr.sa_family);
    }
    if (ioctl(fd, SIOCGIFFLAGS, &ifr) == 0 && (ifr.ifr_flags & IFF_UP) == 0) {
        (void)close(fd);
        return hal_linux_msg(LS_EIO, msg, msglen,
                             "CAN interface '%s' is down: ip link set %s up type can bitrate 500000 "
                             "(for vcan: ip link set %s up)",
                             ifname, ifname, ifname);
    }

    can_err_mask_t err_mask = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) < 0) {
        int e = errno;
        (void)close(fd);
        return hal_linux_msg(LS_EIO, msg, msglen, "setsockopt(CAN_RAW_ERR_FILTER) on '%s' failed: %s", ifname,
                             strerror(e));
    }
    int one = 1;
    (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one); /* drop counter is a nicety */

    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifindex;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        int e = errno;
        (void)close(fd);
        if (e == ENODEV) {
            return hal_linux_msg(LS_ENODEV, msg, msglen, "CAN interface '%s' vanished while opening: %s", ifname, hint);
        }
        if (e == EPERM || e == EACCES) {
            return hal_linux_msg(LS_EPERM, msg, msglen, "no permission to bind to '%s' (%s): run as root", ifname,
                                 strerror(e));
        }
        return hal_linux_msg(LS_EIO, msg, msglen, "bind to CAN interface '%s' failed: %s", ifname, strerror(e));
    }
    if (info != NULL) {
        netlink_query(ifindex, info);
    }
    *fd_out = fd;
    return LS_OK;
}

static sc_link_t *pool_take(void)
{
    sc_link_t *found = NULL;
    (void)pthread_mutex_lock(&g_pool_lock);
    for (size_t i = 0; i < HAL_LINUX_SOCKETCAN_MAX_LINKS; i++) {
        if (!g_links[i].in_use) {
            found = &g_links[i];
            memset(found, 0, sizeof *found);
            found->fd = -1;
            found->in_use = true;
            break;
        }
    }
    (void)pthread_mutex_unlock(&g_pool_lock);
    return found;
}

static int pool_full(char *msg, size_t msglen)
{
    return hal_linux_msg(LS_EINVAL, msg, msglen,
                         "all %d SocketCAN links are in use: close one or raise HAL_LINUX_SOCKETCAN_MAX_LINKS",
                         HAL_LINUX_SOCKETCAN_MAX_LINKS);
}

static void link_fill(hal_can_link_t *out, sc_link_t *l, const char *ifname, int fd)
{
    l->fd = fd;
    (void)snprintf(l->ifname, sizeof l->ifname, "%s", ifname);
    (void)snprintf(l->operstate_path, sizeof l->operstate_path, "/sys/class/net/%s/operstate", ifname);
    out->ops = &sc_ops;
    out->self = l;
    (void)snprintf(out->name, sizeof out->name, "socketcan:%s", ifname);
}

static void link_clear(hal_can_link_t *out)
{
    if (out != NULL) {
        out->ops = NULL;
        out->self = NULL;
        out->name[0] = '\0';
    }
}

int hal_linux_socketcan_open(hal_can_link_t *out, const char *ifname, char *msg, size_t msglen)
{
    if (out == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "hal_linux_socketcan_open: no link to fill (out is NULL)");
    }
    link_clear(out);
    sc_netlink_info_t info = { 0 };
    int fd = -1;
    int rc = sc_configure(ifname, &fd, &info, msg, msglen);
    if (rc != LS_OK) {
        return rc;
    }
    sc_link_t *l = pool_take();
    if (l == NULL) {
        (void)close(fd);
        return pool_full(msg, msglen);
    }
    link_fill(out, l, ifname, fd);
    l->st.bitrate = info.bitrate;
    l->st.state = info.have_state ? info.state : HAL_CAN_STATE_ACTIVE;
    return hal_linux_msg(LS_OK, msg, msglen, "%s open: bitrate %u bit/s, state %s", out->name, (unsigned)l->st.bitrate,
                         state_name(l->st.state));
}

int hal_linux_socketcan_adopt_fd(hal_can_link_t *out, int fd, const char *ifname, char *msg, size_t msglen)
{
    int rc = out == NULL ? LS_EINVAL : check_ifname(ifname, msg, msglen);
    if (out == NULL) {
        (void)hal_linux_msg(rc, msg, msglen, "hal_linux_socketcan_adopt_fd: no link to fill (out is NULL)");
    }
    link_clear(out);
    if (rc == LS_OK && fd < 0) {
        rc = hal_linux_msg(LS_EINVAL, msg, msglen, "hal_linux_socketcan_adopt_fd: invalid fd %d", fd);
    }
    if (rc != LS_OK) {
        if (fd >= 0) {
            (void)close(fd);
        }
        return rc;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0) {
        int e = errno;
        (void)close(fd);
        return hal_linux_msg(LS_EIO, msg, msglen, "cannot make fd non-blocking: %s", strerror(e));
    }
    int one = 1;
    (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
    sc_link_t *l = pool_take();
    if (l == NULL) {
        (void)close(fd);
        return pool_full(msg, msglen);
    }
    link_fill(out, l, ifname, fd);
    return hal_linux_msg(LS_OK, msg, msglen, "%s adopted fd %d", out->name, fd);
}

int hal_linux_socketcan_probe(const char *ifname, char *msg, size_t msglen)
{
    sc_netlink_info_t info = { 0 };
    int fd = -1;
    int rc = sc_configure(ifname, &fd, &info, msg, msglen);
    if (rc != LS_OK) {
        return rc;
    }
    (void)close(fd);
    return hal_linux_msg(LS_OK, msg, msglen, "socketcan:%s ok: bitrate %u bit/s, state %s", ifname,
                         (unsigned)info.bitrate, state_name(info.have_state ? info.state : HAL_CAN_STATE_ACTIVE));
}
