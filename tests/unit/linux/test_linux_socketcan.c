/* SocketCAN link: diagnostics on this kernel (or the real-interface errors
 * where AF_CAN exists), frame conversion, and the link logic (recv, send,
 * error frames, drops, close, pool) over an adopted datagram socketpair. */
#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/netlink.h>
#include <linux/can/raw.h>
#include <linux/if_link.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>

#include "hal_linux_socketcan.h"
#include "test_linux.h"

/* Is AF_CAN with CAN_RAW there? Decides which diagnostic open must give. */
static bool have_af_can(int *err)
{
    int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        *err = errno;
        return false;
    }
    close(fd);
    *err = 0;
    return true;
}

static void test_open_diagnoses_missing_afcan_or_interface(void **state)
{
    (void)state;
    hal_can_link_t link;
    memset(&link, 0xA5, sizeof link);
    char msg[512] = "";
    int err = 0;
    bool afcan = have_af_can(&err);
    int rc = hal_linux_socketcan_open(&link, "lsnoiface9", msg, sizeof msg);
    if (afcan) {
        assert_int_equal(rc, LS_ENODEV);
        assert_non_null(strstr(msg, "no CAN interface 'lsnoiface9'"));
        assert_non_null(strstr(msg, "ip link set lsnoiface9 up type can bitrate 500000"));
        assert_non_null(strstr(msg, "ip link add dev vcan0 type vcan"));
        /* A non-CAN interface is refused by name, not bound. */
        rc = hal_linux_socketcan_open(&link, "lo", msg, sizeof msg);
        assert_int_equal(rc, LS_ENODEV);
        assert_non_null(strstr(msg, "'lo' is not a CAN interface"));
    } else {
        assert_int_equal(err, EAFNOSUPPORT);
        assert_int_equal(rc, LS_ENOAFCAN);
        assert_non_null(strstr(msg, "no AF_CAN (SocketCAN) support"));
        assert_non_null(strstr(msg, "modprobe can can-raw"));
        assert_non_null(strstr(msg, "CONFIG_CAN"));
        assert_non_null(strstr(msg, "--link slcan:pty:PATH"));
    }
    /* A failed open leaves nothing to call: the wrappers answer unsupported. */
    assert_null(link.ops);
    assert_null(link.self);
    hal_can_frame_t f;
    assert_int_equal(hal_can_recv(&link, &f), LS_EUNSUPPORTED);
    assert_int_equal(hal_can_poll_fd(&link), -1);
    hal_can_close(&link);

    char pmsg[512] = "";
    int prc = hal_linux_socketcan_probe("lsnoiface9", pmsg, sizeof pmsg);
    assert_int_equal(prc, afcan ? LS_ENODEV : LS_ENOAFCAN);
    (void)hal_linux_socketcan_open(&link, "lsnoiface9", msg, sizeof msg);
    assert_string_equal(pmsg, msg);
}

static void test_open_rejects_bad_arguments(void **state)
{
    (void)state;
    hal_can_link_t link;
    char msg[256];
    assert_int_equal(hal_linux_socketcan_open(NULL, "can0", msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "out is NULL"));
    assert_int_equal(hal_linux_socketcan_open(&link, NULL, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "no CAN interface name"));
    assert_int_equal(hal_linux_socketcan_open(&link, "", msg, sizeof msg), LS_EINVAL);
    assert_int_equal(hal_linux_socketcan_open(&link, "abcdefghijklmnop", msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "longer than 15 characters"));
    assert_null(link.ops);
    /* msg is optional and truncation is safe. */
    assert_int_equal(hal_linux_socketcan_open(&link, "", NULL, 0), LS_EINVAL);
    char tiny[8];
    assert_int_equal(hal_linux_socketcan_open(&link, "", tiny, sizeof tiny), LS_EINVAL);
    assert_int_equal(strlen(tiny), 7);
}

static void test_encode_frames(void **state)
{
    (void)state;
    struct can_frame cf;
    hal_can_frame_t f = { .id = 0x123, .flags = 0, .len = 3, .data = { 1, 2, 3, 4, 5, 6, 7, 8 } };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_OK);
    assert_int_equal(cf.can_id, 0x123);
    assert_int_equal(cf.can_dlc, 3);
    assert_memory_equal(cf.data, ((uint8_t[]){ 1, 2, 3, 0, 0, 0, 0, 0 }), 8);

    f = (hal_can_frame_t){ .id = 0x1ABCDEF0, .flags = HAL_CAN_F_EXT, .len = 8, .data = { 8, 7, 6, 5, 4, 3, 2, 1 } };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_OK);
    assert_int_equal(cf.can_id, 0x1ABCDEF0u | CAN_EFF_FLAG);
    assert_memory_equal(cf.data, f.data, 8);

    f = (hal_can_frame_t){ .id = 0x7FF, .flags = HAL_CAN_F_RTR, .len = 4, .data = { 9, 9, 9, 9 } };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_OK);
    assert_int_equal(cf.can_id, 0x7FFu | CAN_RTR_FLAG);
    assert_int_equal(cf.can_dlc, 4);
    assert_memory_equal(cf.data, ((uint8_t[8]){ 0 }), 8);

    f = (hal_can_frame_t){ .id = 0x800, .flags = 0, .len = 0 };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_EINVAL);
    f = (hal_can_frame_t){ .id = 0x20000000, .flags = HAL_CAN_F_EXT, .len = 0 };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_EINVAL);
    f = (hal_can_frame_t){ .id = 1, .flags = 0, .len = 9 };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_EINVAL);
    f = (hal_can_frame_t){ .id = 1, .flags = 0x04, .len = 0 };
    assert_int_equal(hal_linux_socketcan_encode(&f, &cf), LS_EINVAL);
}

static struct can_frame err_frame(canid_t cls, uint8_t d1)
{
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = CAN_ERR_FLAG | cls;
    cf.can_dlc = CAN_ERR_DLC;
    cf.data[1] = d1;
    return cf;
}

static void test_decode_frames_and_error_states(void **state)
{
    (void)state;
    hal_can_status_t st = { 0 };
    hal_can_frame_t f;
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = 0x12345678u | CAN_EFF_FLAG;
    cf.can_dlc = 2;
    cf.data[0] = 0xAB;
    cf.data[1] = 0xCD;
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 1);
    assert_int_equal(f.id, 0x12345678u);
    assert_int_equal(f.flags, HAL_CAN_F_EXT);
    assert_int_equal(f.len, 2);
    assert_int_equal(f.data[0], 0xAB);
    assert_int_equal(f.data[1], 0xCD);

    cf.can_id = 0x055u | CAN_RTR_FLAG;
    cf.can_dlc = 1;
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 1);
    assert_int_equal(f.id, 0x055u);
    assert_int_equal(f.flags, HAL_CAN_F_RTR);
    assert_int_equal(f.len, 1);
    assert_int_equal(f.data[0], 0);
    assert_int_equal(st.error_frames, 0);

    cf = err_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING);
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 0);
    assert_int_equal(st.state, HAL_CAN_STATE_WARNING);
    cf = err_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_PASSIVE);
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 0);
    assert_int_equal(st.state, HAL_CAN_STATE_PASSIVE);
    cf = err_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW);
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 0);
    assert_int_equal(st.state, HAL_CAN_STATE_PASSIVE);
    cf = err_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE);
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 0);
    assert_int_equal(st.state, HAL_CAN_STATE_ACTIVE);
    cf = err_frame(CAN_ERR_BUSOFF, 0);
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 0);
    assert_int_equal(st.state, HAL_CAN_STATE_BUS_OFF);
    cf = err_frame(CAN_ERR_RESTARTED, 0);
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), 0);
    assert_int_equal(st.state, HAL_CAN_STATE_ACTIVE);
    assert_int_equal(st.error_frames, 6);

    memset(&cf, 0, sizeof cf);
    cf.can_id = 1;
    cf.can_dlc = 9;
    assert_int_equal(hal_linux_socketcan_decode(&cf, &f, &st), LS_EINVAL);
    assert_int_equal(st.rx_dropped, 1);
}

/* ---- the link over an adopted socketpair ---------------------------------- */

typedef struct {
    hal_can_link_t link;
    int peer;
} pair_t;

static void open_pair(pair_t *p, int type)
{
    int sv[2];
    assert_int_equal(socketpair(AF_UNIX, type, 0, sv), 0);
    char msg[128];
    assert_int_equal(hal_linux_socketcan_adopt_fd(&p->link, sv[0], "test0", msg, sizeof msg), LS_OK);
    assert_string_equal(p->link.name, "socketcan:test0");
    p->peer = sv[1];
}

static void peer_write(int peer, const struct can_frame *cf)
{
    assert_int_equal(write(peer, cf, sizeof *cf), (ssize_t)sizeof *cf);
}

static void test_link_recv_send_and_error_frames(void **state)
{
    (void)state;
    pair_t p;
    open_pair(&p, SOCK_DGRAM);
    hal_can_frame_t f;
    hal_can_status_t st;

    assert_true(hal_can_poll_fd(&p.link) >= 0);
    assert_int_equal(hal_can_recv(&p.link, &f), LS_EAGAIN);

    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = 0x321;
    cf.can_dlc = 2;
    cf.data[0] = 0x11;
    cf.data[1] = 0x22;
    peer_write(p.peer, &cf);
    assert_int_equal(hal_can_recv(&p.link, &f), 1);
    assert_int_equal(f.id, 0x321);
    assert_int_equal(f.len, 2);
    assert_int_equal(f.data[1], 0x22);

    /* An error frame is consumed silently; the data frame behind it comes out. */
    struct can_frame busoff = err_frame(CAN_ERR_BUSOFF, 0);
    peer_write(p.peer, &busoff);
    cf.can_id = 0x322;
    peer_write(p.peer, &cf);
    assert_int_equal(hal_can_recv(&p.link, &f), 1);
    assert_int_equal(f.id, 0x322);
    assert_int_equal(hal_can_status(&p.link, &st), LS_OK);
    assert_int_equal(st.state, HAL_CAN_STATE_BUS_OFF);
    assert_int_equal(st.error_frames, 1);
    /* Nothing pending while bus-off: the link says so instead of "try again". */
    assert_int_equal(hal_can_recv(&p.link, &f), LS_EBUSOFF);

    struct can_frame restarted = err_frame(CAN_ERR_RESTARTED, 0);
    peer_write(p.peer, &restarted);
    assert_int_equal(hal_can_recv(&p.link, &f), LS_EAGAIN);
    assert_int_equal(hal_can_status(&p.link, &st), LS_OK);
    assert_int_equal(st.state, HAL_CAN_STATE_ACTIVE);
    assert_int_equal(st.error_frames, 2);
    assert_int_equal(st.rx_frames, 2);

    /* A record that is not a struct can_frame is dropped and counted. */
    assert_int_equal(write(p.peer, "abcde", 5), 5);
    assert_int_equal(hal_can_recv(&p.link, &f), LS_EAGAIN);
    assert_int_equal(hal_can_status(&p.link, &st), LS_OK);
    assert_int_equal(st.rx_dropped, 1);

    /* the HAL carries any 29-bit id; this one is no protocol's */
    const uint32_t any_ext_id = 0x1ABCDE01u;
    hal_can_frame_t out = { .id = any_ext_id, .flags = HAL_CAN_F_EXT, .len = 3, .data = { 0x02, 0x10, 0x01 } };
    assert_int_equal(hal_can_send(&p.link, &out), LS_OK);
    struct can_frame got;
    assert_int_equal(read(p.peer, &got, sizeof got), (ssize_t)sizeof got);
    assert_int_equal(got.can_id, any_ext_id | CAN_EFF_FLAG);
    assert_int_equal(got.can_dlc, 3);
    assert_memory_equal(got.data, ((uint8_t[]){ 0x02, 0x10, 0x01 }), 3);
    out.len = 9;
    assert_int_equal(hal_can_send(&p.link, &out), LS_EINVAL);
    assert_int_equal(hal_can_status(&p.link, &st), LS_OK);
    assert_int_equal(st.tx_frames, 1);
    assert_int_equal(st.tx_dropped, 0);
    assert_int_equal(st.bitrate, 0);

    hal_can_close(&p.link);
    hal_can_close(&p.link); /* idempotent */
    close(p.peer);
}

static void test_link_send_full_queue_is_eagain(void **state)
{
    (void)state;
    pair_t p;
    open_pair(&p, SOCK_DGRAM);
    hal_can_frame_t f = { .id = 0x100, .flags = 0, .len = 8, .data = { 0 } };
    int sent = 0;
    int rc = LS_OK;
    while (sent < 100000 && (rc = hal_can_send(&p.link, &f)) == LS_OK) {
        sent++;
    }
    assert_int_equal(rc, LS_EAGAIN);
    assert_true(sent > 0);
    hal_can_status_t st;
    assert_int_equal(hal_can_status(&p.link, &st), LS_OK);
    assert_int_equal(st.tx_frames, (uint32_t)sent);
    assert_int_equal(st.tx_dropped, 0);

    /* Once the peer reads, the retried frame goes out. */
    struct can_frame got;
    assert_int_equal(read(p.peer, &got, sizeof got), (ssize_t)sizeof got);
    assert_int_equal(hal_can_send(&p.link, &f), LS_OK);

    /* During bus-off a full queue reports bus-off. */
    struct can_frame busoff = err_frame(CAN_ERR_BUSOFF, 0);
    peer_write(p.peer, &busoff);
    hal_can_frame_t r;
    assert_int_equal(hal_can_recv(&p.link, &r), LS_EBUSOFF);
    assert_int_equal(hal_can_send(&p.link, &f), LS_EBUSOFF);
    hal_can_close(&p.link);
    close(p.peer);
}

static void test_link_peer_gone_is_eio(void **state)
{
    (void)state;
    pair_t p;
    open_pair(&p, SOCK_SEQPACKET);
    close(p.peer);
    hal_can_frame_t f = { .id = 1, .flags = 0, .len = 0 };
    assert_int_equal(hal_can_recv(&p.link, &f), LS_EIO);
    assert_int_equal(hal_can_send(&p.link, &f), LS_EIO);
    hal_can_status_t st;
    assert_int_equal(hal_can_status(&p.link, &st), LS_OK);
    assert_int_equal(st.tx_dropped, 1);
    hal_can_close(&p.link);
}

static void test_pool_is_bounded_and_reused(void **state)
{
    (void)state;
    pair_t p[HAL_LINUX_SOCKETCAN_MAX_LINKS];
    for (int i = 0; i < HAL_LINUX_SOCKETCAN_MAX_LINKS; i++) {
        open_pair(&p[i], SOCK_DGRAM);
    }
    int sv[2];
    assert_int_equal(socketpair(AF_UNIX, SOCK_DGRAM, 0, sv), 0);
    hal_can_link_t extra;
    char msg[256];
    assert_int_equal(hal_linux_socketcan_adopt_fd(&extra, sv[0], "test9", msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "all 4 SocketCAN links are in use"));
    assert_null(extra.ops);
    /* The link took ownership of the fd even on failure. */
    assert_int_equal(fcntl(sv[0], F_GETFD), -1);
    assert_int_equal(errno, EBADF);

    hal_can_close(&p[1].link);
    assert_int_equal(socketpair(AF_UNIX, SOCK_DGRAM, 0, sv), 0);
    assert_int_equal(hal_linux_socketcan_adopt_fd(&extra, sv[0], "test9", msg, sizeof msg), LS_OK);
    hal_can_frame_t f;
    assert_int_equal(hal_can_recv(&extra, &f), LS_EAGAIN);
    hal_can_close(&extra);
    close(sv[1]);
    for (int i = 0; i < HAL_LINUX_SOCKETCAN_MAX_LINKS; i++) {
        if (i != 1) {
            hal_can_close(&p[i].link);
        }
        close(p[i].peer);
    }
}

/* ---- rtnetlink answer parsing --------------------------------------------- */

typedef struct {
    _Alignas(4) uint8_t b[512];
    size_t len;
} nlbuf_t;

/* Append an attribute; returns its offset so nests can be closed. */
static size_t put_attr(nlbuf_t *m, unsigned short type, const void *data, size_t len)
{
    size_t at = m->len;
    struct rtattr a = { .rta_len = (unsigned short)RTA_LENGTH(len), .rta_type = type };
    memcpy(m->b + at, &a, sizeof a);
    if (len > 0) {
        memcpy(m->b + at + RTA_LENGTH(0u), data, len);
    }
    m->len += RTA_ALIGN(RTA_LENGTH(len));
    return at;
}

static void end_nest(nlbuf_t *m, size_t at)
{
    unsigned short l = (unsigned short)(m->len - at);
    memcpy(m->b + at, &l, sizeof l);
}

static void build_newlink(nlbuf_t *m, const char *kind, uint32_t bitrate, int state)
{
    memset(m, 0, sizeof *m);
    m->len = NLMSG_LENGTH(sizeof(struct ifinfomsg));
    put_attr(m, IFLA_IFNAME, "can0", 5);
    size_t li = put_attr(m, IFLA_LINKINFO, NULL, 0);
    put_attr(m, IFLA_INFO_KIND, kind, strlen(kind) + 1);
    size_t data = put_attr(m, IFLA_INFO_DATA, NULL, 0);
    if (bitrate > 0) {
        struct can_bittiming bt = { .bitrate = bitrate, .sample_point = 875 };
        put_attr(m, IFLA_CAN_BITTIMING, &bt, sizeof bt);
    }
    if (state >= 0) {
        uint32_t st = (uint32_t)state;
        put_attr(m, IFLA_CAN_STATE, &st, sizeof st);
    }
    end_nest(m, data);
    end_nest(m, li);
    struct nlmsghdr nh = { .nlmsg_len = (uint32_t)m->len, .nlmsg_type = RTM_NEWLINK };
    memcpy(m->b, &nh, sizeof nh);
}

static void test_parse_link_reads_bitrate_and_state(void **state)
{
    (void)state;
    nlbuf_t m;
    hal_linux_socketcan_link_info_t info;

    build_newlink(&m, "can", 500000, CAN_STATE_ERROR_PASSIVE);
    memset(&info, 0, sizeof info);
    assert_int_equal(hal_linux_socketcan_parse_link(m.b, m.len, &info), 1);
    assert_int_equal(info.bitrate, 500000);
    assert_true(info.have_state);
    assert_int_equal(info.state, HAL_CAN_STATE_PASSIVE);

    build_newlink(&m, "can", 1000000, CAN_STATE_STOPPED);
    memset(&info, 0, sizeof info);
    assert_int_equal(hal_linux_socketcan_parse_link(m.b, m.len, &info), 1);
    assert_int_equal(info.bitrate, 1000000);
    assert_int_equal(info.state, HAL_CAN_STATE_BUS_OFF);

    build_newlink(&m, "can", 0, -1); /* a CAN device before its bitrate is set */
    memset(&info, 0, sizeof info);
    assert_int_equal(hal_linux_socketcan_parse_link(m.b, m.len, &info), 1);
    assert_int_equal(info.bitrate, 0);
    assert_false(info.have_state);

    build_newlink(&m, "vcan", 500000, 0); /* only kind "can" carries CAN data */
    memset(&info, 0, sizeof info);
    assert_int_equal(hal_linux_socketcan_parse_link(m.b, m.len, &info), 0);
    assert_int_equal(info.bitrate, 0);

    /* Every truncation, with the header's length cut to match so the walk
     * goes into the attributes, stays inside the bytes given (an exact-size
     * heap copy lets ASan see any overread) and finds at most what is there. */
    build_newlink(&m, "can", 250000, CAN_STATE_ERROR_ACTIVE);
    int complete = 0;
    for (size_t cut = 0; cut <= m.len; cut++) {
        uint8_t *copy = malloc(cut > 0 ? cut : 1);
        assert_non_null(copy);
        memcpy(copy, m.b, cut);
        if (cut >= sizeof(struct nlmsghdr)) {
            uint32_t l = (uint32_t)cut;
            memcpy(copy, &l, sizeof l);
        }
        memset(&info, 0, sizeof info);
        int r = hal_linux_socketcan_parse_link(copy, cut, &info);
        free(copy);
        assert_in_range(r, 0, 1);
        assert_true(info.bitrate == 0 || info.bitrate == 250000);
        assert_true(!info.have_state || info.state == HAL_CAN_STATE_ACTIVE);
        complete += info.have_state;
    }
    assert_true(complete >= 1); /* the untruncated answer, at least */
    /* An attribute claiming more than its message holds stops the walk. */
    build_newlink(&m, "can", 250000, CAN_STATE_ERROR_ACTIVE);
    size_t li_at = NLMSG_LENGTH(sizeof(struct ifinfomsg)) + RTA_ALIGN(RTA_LENGTH(5u));
    unsigned short huge = 0xFFF0;
    memcpy(m.b + li_at, &huge, sizeof huge);
    memset(&info, 0, sizeof info);
    assert_int_equal(hal_linux_socketcan_parse_link(m.b, m.len, &info), 0);
    assert_int_equal(hal_linux_socketcan_parse_link(NULL, 0, &info), LS_EINVAL);
}

/* The kernel's own answer for the loopback interface: parsed, not CAN. */
static void test_parse_link_on_a_real_answer(void **state)
{
    (void)state;
    int nl = socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    assert_true(nl >= 0);
    struct {
        struct nlmsghdr nh;
        struct ifinfomsg ifi;
    } req;
    memset(&req, 0, sizeof req);
    req.nh.nlmsg_len = NLMSG_LENGTH(sizeof req.ifi);
    req.nh.nlmsg_type = RTM_GETLINK;
    req.nh.nlmsg_flags = NLM_F_REQUEST;
    req.ifi.ifi_index = (int)if_nametoindex("lo");
    assert_true(req.ifi.ifi_index > 0);
    assert_int_equal(send(nl, &req, req.nh.nlmsg_len, 0), (ssize_t)req.nh.nlmsg_len);
    static union {
        char b[16384];
        struct nlmsghdr align;
    } resp;
    ssize_t n = recv(nl, resp.b, sizeof resp.b, 0);
    close(nl);
    assert_true(n > (ssize_t)sizeof(struct nlmsghdr));
    assert_int_equal(resp.align.nlmsg_type, RTM_NEWLINK);
    hal_linux_socketcan_link_info_t info = { 0 };
    assert_int_equal(hal_linux_socketcan_parse_link(resp.b, (size_t)n, &info), 0);
    assert_int_equal(info.bitrate, 0);
}

int run_socketcan_tests(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_open_diagnoses_missing_afcan_or_interface),
        cmocka_unit_test(test_open_rejects_bad_arguments),
        cmocka_unit_test(test_encode_frames),
        cmocka_unit_test(test_decode_frames_and_error_states),
        cmocka_unit_test(test_link_recv_send_and_error_frames),
        cmocka_unit_test(test_link_send_full_queue_is_eagain),
        cmocka_unit_test(test_link_peer_gone_is_eio),
        cmocka_unit_test(test_pool_is_bounded_and_reused),
        cmocka_unit_test(test_parse_link_reads_bitrate_and_state),
        cmocka_unit_test(test_parse_link_on_a_real_answer),
    };
    return cmocka_run_group_tests_name("socketcan", tests, NULL, NULL);
}
