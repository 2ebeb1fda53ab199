/* Black-box tests of the simulated drives (hal/sim/drives) through their
 * public API, on the real world and a fake link that records what the
 * nodes send. Every frame a test sends or expects is built here from the
 * CiA 301 / 402 constants of ls_canopen.h, never with the drives' own code,
 * and time is the test's: nothing here sleeps. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmocka.h>

#include "alloc_counter.h"
#include "hal_sim_drives.h"
#include "hal_sim_world.h"
#include "ls_canopen.h"
#include "ls_err.h"
#include "ls_robot_model_sim.h"

#define N1 0x21u /* the first node: joint 1 */
#define N2 0x22u
#define CPR 100000.0 /* counts per radian in these tests */
#define MAX_SENT 8192
/* Bytes 1-3 of an SDO frame: index (little-endian) and sub-index. */
#define MUX(index, sub) (uint8_t)(index), (uint8_t)((index) >> 8), (uint8_t)(sub)

/* ---- the fake link ---- */

static hal_can_frame_t g_sent[MAX_SENT];
static size_t g_n_sent;
static uint64_t g_now;

static bool g_link_down; /* the fake link fails every call, as SocketCAN on an interface taken down */

static int fake_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    if (g_link_down) {
        return LS_EIO;
    }
    if (g_n_sent < MAX_SENT) {
        g_sent[g_n_sent++] = *f;
    }
    return LS_OK;
}
static uint32_t g_flood; /* frames the fake link still has to give (another node's PDO each) */
static uint32_t g_taken; /* frames it gave */
static int fake_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    if (g_link_down) {
        return LS_EIO;
    }
    if (g_flood == 0u) {
        return LS_EAGAIN;
    }
    g_flood--;
    g_taken++;
    *f = (hal_can_frame_t){ .id = LS_CO_COB_TPDO1 + 0x50u, .flags = 0, .len = 8, .data = { 0 } };
    return 1;
}
static int fake_fd(void *self)
{
    (void)self;
    return -1;
}
static int fake_status(void *self, hal_can_status_t *out)
{
    (void)self;
    memset(out, 0, sizeof *out);
    return LS_OK;
}
static void fake_close(void *self)
{
    (void)self;
}
static const hal_can_ops_t k_fake_ops = {
    .send = fake_send, .recv = fake_recv, .poll_fd = fake_fd, .status = fake_status, .close = fake_close
};
static hal_can_link_t g_link = { .ops = &k_fake_ops, .self = NULL, .name = "fake" };

/* ---- set-up ---- */

static void open_world(void)
{
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(&ls_robot_model_default, &am);
    hal_sim_world_config_t wc = { .arm = &am };
    char msg[200] = "";
    if (hal_sim_world_open(&wc, msg, sizeof msg) != LS_OK) {
        fail_msg("world: %s", msg);
    }
}

static double g_substep_s; /* the next open's physics sub-step (0: the default) */

/* Drives for nodes ids[0..n) on joints 1..n, with the given offsets (NULL: 0). */
static void open_drives_at(size_t n, const uint8_t *ids, const int32_t *offsets, const char *ctl)
{
    open_world();
    hal_sim_drives_config_t dc = {
        .link = &g_link, .n_drives = n, .counts_per_rad = CPR, .control_socket_path = ctl, .substep_s = g_substep_s
    };
    for (size_t i = 0; i < n; i++) {
        dc.drives[i] = (hal_sim_drive_config_t){ ids[i], (uint8_t)i, offsets != NULL ? offsets[i] : 0 };
    }
    g_n_sent = 0;
    g_now = 1000000u;
    char msg[200] = "";
    if (hal_sim_drives_open(&dc, g_now, msg, sizeof msg) != LS_OK) {
        fail_msg("drives: %s", msg);
    }
}

static void open_drives(size_t n)
{
    static const uint8_t ids[] = { N1, N2, 0x23, 0x24, 0x25, 0x26 };
    open_drives_at(n, ids, NULL, NULL);
}

static int teardown(void **state)
{
    (void)state;
    hal_sim_drives_close();
    hal_sim_world_close();
    return 0;
}

/* ---- frames ---- */

static void rx(uint32_t id, const uint8_t *data, uint8_t len)
{
    hal_can_frame_t f = { .id = id, .flags = 0, .len = len };
    if (len > 0) {
        memcpy(f.data, data, len);
    }
    assert_int_equal(hal_sim_drives_rx(&f, g_now), LS_OK);
}

static void advance_ms(uint32_t ms)
{
    for (uint32_t k = 0; k < ms; k++) {
        g_now += 1000u;
        assert_int_equal(hal_sim_drives_poll(g_now), LS_OK);
    }
}

static void nmt(uint8_t cs, uint8_t node)
{
    uint8_t d[2] = { cs, node };
    rx(LS_CO_COB_NMT, d, 2);
}

static void sync_frame(void)
{
    rx(LS_CO_COB_SYNC, NULL, 0);
}

/* Frames with `id` sent since index `from`; the last of them in *last. */
static int count_sent(uint32_t id, size_t from, hal_can_frame_t *last)
{
    int k = 0;
    for (size_t i = from; i < g_n_sent; i++) {
        if (g_sent[i].id == id) {
            k++;
            if (last != NULL) {
                *last = g_sent[i];
            }
        }
    }
    return k;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* One SDO request; the answer (exactly one frame on 0x580 + node). */
static hal_can_frame_t sdo_exchange(uint8_t node, const uint8_t req[8])
{
    size_t mark = g_n_sent;
    rx(LS_CO_COB_SDO_RX + node, req, 8);
    hal_can_frame_t r = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_SDO_TX + node, mark, &r), 1);
    return r;
}

static uint32_t abort_of(const hal_can_frame_t *r)
{
    return r->data[0] == LS_CO_SDO_CS_ABORT ? le32(r->data + 4) : 0u;
}

/* Expedited download of `size` bytes (1-4). 0 or the abort code. */
static uint32_t sdo_write(uint8_t node, uint16_t index, uint8_t sub, uint32_t value, unsigned size)
{
    uint8_t req[8] = { (uint8_t)(LS_CO_SDO_CCS_DOWNLOAD_INITIATE | ((4u - size) << LS_CO_SDO_EXP_N_SHIFT) |
                                 LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE),
                       (uint8_t)index,
                       (uint8_t)(index >> 8),
                       sub,
                       (uint8_t)value,
                       (uint8_t)(value >> 8),
                       (uint8_t)(value >> 16),
                       (uint8_t)(value >> 24) };
    hal_can_frame_t r = sdo_exchange(node, req);
    if (r.data[0] == LS_CO_SDO_CS_ABORT) {
        return abort_of(&r);
    }
    assert_int_equal(r.data[0], LS_CO_SDO_SCS_DOWNLOAD_INITIATE);
    assert_int_equal(r.data[1] | r.data[2] << 8, index);
    assert_int_equal(r.data[3], sub);
    return 0;
}

/* Upload (expedited or segmented) into buf. 0 or the abort code. */
static uint32_t sdo_read_bytes(uint8_t node, uint16_t index, uint8_t sub, uint8_t *buf, size_t cap, size_t *len)
{
    uint8_t req[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0 };
    hal_can_frame_t r = sdo_exchange(node, req);
    if (r.data[0] == LS_CO_SDO_CS_ABORT) {
        return abort_of(&r);
    }
    assert_int_equal(r.data[0] & LS_CO_SDO_CS_MASK, LS_CO_SDO_SCS_UPLOAD_INITIATE);
    assert_int_equal(r.data[1] | r.data[2] << 8, index);
    if ((r.data[0] & LS_CO_SDO_EXPEDITED) != 0u) {
        assert_true((r.data[0] & LS_CO_SDO_SIZE) != 0u);
        *len = LS_CO_SDO_EXP_DATA - ((r.data[0] >> LS_CO_SDO_EXP_N_SHIFT) & 3u);
        memcpy(buf, r.data + 4, *len);
        return 0;
    }
    size_t size = le32(r.data + 4);
    size_t got = 0;
    uint8_t toggle = 0;
    for (;;) {
        uint8_t seg[8] = { (uint8_t)(LS_CO_SDO_CCS_UPLOAD_SEGMENT | toggle), 0, 0, 0, 0, 0, 0, 0 };
        hal_can_frame_t s = sdo_exchange(node, seg);
        if (s.data[0] == LS_CO_SDO_CS_ABORT) {
            return abort_of(&s);
        }
        assert_int_equal(s.data[0] & LS_CO_SDO_TOGGLE, toggle);
        size_t k = LS_CO_SDO_SEG_DATA - ((s.data[0] >> LS_CO_SDO_SEG_N_SHIFT) & 7u);
        assert_true(got + k <= cap);
        memcpy(buf + got, s.data + 1, k);
        got += k;
        toggle ^= LS_CO_SDO_TOGGLE;
        if ((s.data[0] & LS_CO_SDO_LAST) != 0u) {
            break;
        }
    }
    assert_int_equal(got, size);
    *len = got;
    return 0;
}

static int64_t sdo_read(uint8_t node, uint16_t index, uint8_t sub)
{
    uint8_t buf[64];
    size_t len = 0;
    uint32_t a = sdo_read_bytes(node, index, sub, buf, sizeof buf, &len);
    if (a != 0u) {
        fail_msg("read 0x%04X:%02X aborted 0x%08X", index, sub, a);
    }
    uint64_t v = 0;
    for (size_t k = 0; k < len && k < 8; k++) {
        v |= (uint64_t)buf[k] << (8u * k);
    }
    return (int64_t)v;
}

static int32_t sdo_read_i32(uint8_t node, uint16_t index, uint8_t sub)
{
    uint32_t u = (uint32_t)sdo_read(node, index, sub);
    return (int32_t)u;
}

static uint16_t statusword(uint8_t node)
{
    return (uint16_t)sdo_read(node, LS_CO_OBJ_STATUSWORD, 0);
}

static bool in_state(uint16_t sw, uint16_t mask, uint16_t value)
{
    return (sw & mask) == value;
}

static void controlword(uint8_t node, uint16_t cw)
{
    assert_int_equal(sdo_write(node, LS_CO_OBJ_CONTROLWORD, 0, cw, 2), 0);
}

/* The drive to OPERATION ENABLED in CSP, by SDO, with the target = actual. */
static void enable_csp(uint8_t node)
{
    assert_int_equal(sdo_write(node, LS_CO_OBJ_MODES, 0, (uint32_t)LS_CO_MODE_CSP, 1), 0);
    uint32_t pos = (uint32_t)sdo_read(node, LS_CO_OBJ_POSITION_ACTUAL, 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TARGET_POSITION, 0, pos, 4), 0);
    controlword(node, LS_CO_CW_CMD_SHUTDOWN);
    controlword(node, LS_CO_CW_CMD_SWITCH_ON);
    controlword(node, LS_CO_CW_CMD_ENABLE_OPERATION);
    assert_true(in_state(statusword(node), LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_ENABLED_STATE));
}

static double joint_q(int j)
{
    double q[HAL_SIM_ARM_JOINTS];
    hal_arm_t arm;
    hal_sim_world_get_arm(&arm);
    assert_int_equal(hal_arm_read(&arm, q, NULL), LS_OK);
    return q[j];
}

/* ======================================================================
 * The object dictionary (from the EDS) over SDO
 * ====================================================================== */

static void test_the_eds_defaults_read_back_over_sdo(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_DEVICE_TYPE, 0) & LS_CO_DEVICE_PROFILE_MASK, LS_CO_PROFILE_DRIVE);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 1), 0x00004C53);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 4), 0x53440000 + N1);  /* $NODEID */
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_TPDO_COMM, 1), 0x40000180 + N1); /* $NODEID */
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_RPDO_MAP + 2, 2), LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32));
    assert_int_equal((int8_t)sdo_read(N1, LS_CO_OBJ_INTERP_PERIOD, 2), -3);
    assert_int_equal(sdo_read_i32(N1, LS_CO_OBJ_SW_POSITION_LIMIT, 1), INT32_MIN);
    assert_int_equal(statusword(N1), LS_CO_SW_SWITCH_ON_DISABLED_STATE | LS_CO_SW_REMOTE);
    assert_int_equal(sdo_read(N1, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED), 1);
    uint8_t buf[64];
    size_t len = 0;
    assert_int_equal(sdo_read_bytes(N1, LS_CO_OBJ_DEVICE_NAME, 0, buf, sizeof buf, &len), 0); /* segmented */
    assert_int_equal(len, strlen("LandScape simulated drive"));
    assert_memory_equal(buf, "LandScape simulated drive", len);
}

static void test_missing_objects_and_sub_indices_get_their_abort_codes(void **state)
{
    (void)state;
    open_drives(1);
    uint8_t buf[8];
    size_t len;
    assert_int_equal(sdo_read_bytes(N1, 0x6071, 0, buf, sizeof buf, &len), LS_CO_ABORT_NO_OBJECT);
    assert_int_equal(sdo_read_bytes(N1, LS_CO_OBJ_IDENTITY, 9, buf, sizeof buf, &len), LS_CO_ABORT_NO_SUB);
    assert_int_equal(sdo_read_bytes(N1, LS_CO_OBJ_TPDO_COMM, 4, buf, sizeof buf, &len), LS_CO_ABORT_NO_SUB);
    assert_int_equal(sdo_write(N1, 0x6071, 0, 1, 2), LS_CO_ABORT_NO_OBJECT);
}

static void test_read_only_objects_refuse_writes_and_keep_their_value(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_STATUSWORD, 0, 0, 2), LS_CO_ABORT_READ_ONLY);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_IDENTITY, 1, 5, 4), LS_CO_ABORT_READ_ONLY);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_DEVICE_TYPE, 0, 5, 4), LS_CO_ABORT_READ_ONLY);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 1), 0x00004C53);
}

static void test_a_write_of_another_length_than_the_type_is_refused(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 100, 4), LS_CO_ABORT_TYPE_LEN_HIGH);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, 100, 2), LS_CO_ABORT_TYPE_LEN_LOW);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_PRODUCER_HB, 0), 0);
}

static void test_values_beyond_the_eds_limits_are_refused(void **state)
{
    (void)state;
    open_drives(1);
    /* 0x6007: 0..3; 0x60C2:02: -6..-1; 0x6098: 35..37 */
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_ABORT_CONNECTION, 0, 4, 2), LS_CO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 2, (uint32_t)(int8_t)-7 & 0xFFu, 1), LS_CO_ABORT_VALUE_LOW);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 2, 0, 1), LS_CO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_HOMING_METHOD, 0, 36, 1), LS_CO_ABORT_VALUE); /* in range, unsupported */
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_HOMING_METHOD, 0, 35, 1), 0);
}

/* ======================================================================
 * SDO protocol
 * ====================================================================== */

static void test_a_segmented_download_writes_a_string(void **state)
{
    (void)state;
    open_drives(1);
    const char *text = "joint 1, the base"; /* 17 bytes: three segments */
    size_t n = strlen(text);
    uint8_t init[8] = { LS_CO_SDO_CCS_DOWNLOAD_INITIATE | LS_CO_SDO_SIZE,
                        (uint8_t)SD_OBJ_LABEL,
                        (uint8_t)(SD_OBJ_LABEL >> 8),
                        0,
                        (uint8_t)n,
                        0,
                        0,
                        0 };
    hal_can_frame_t r = sdo_exchange(N1, init);
    assert_int_equal(r.data[0], LS_CO_SDO_SCS_DOWNLOAD_INITIATE);
    uint8_t toggle = 0;
    for (size_t off = 0; off < n; off += LS_CO_SDO_SEG_DATA) {
        size_t k = n - off > LS_CO_SDO_SEG_DATA ? LS_CO_SDO_SEG_DATA : n - off;
        bool last = off + k == n;
        uint8_t seg[8] = { (uint8_t)(LS_CO_SDO_CCS_DOWNLOAD_SEGMENT | toggle |
                                     ((LS_CO_SDO_SEG_DATA - k) << LS_CO_SDO_SEG_N_SHIFT) |
                                     (last ? LS_CO_SDO_LAST : 0u)) };
        memcpy(seg + 1, text + off, k);
        r = sdo_exchange(N1, seg);
        assert_int_equal(r.data[0], LS_CO_SDO_SCS_DOWNLOAD_SEGMENT | toggle);
        toggle ^= LS_CO_SDO_TOGGLE;
    }
    uint8_t buf[64];
    size_t len = 0;
    assert_int_equal(sdo_read_bytes(N1, SD_OBJ_LABEL, 0, buf, sizeof buf, &len), 0);
    assert_int_equal(len, n);
    assert_memory_equal(buf, text, n);
}

static void test_a_string_longer_than_the_object_is_refused(void **state)
{
    (void)state;
    open_drives(1);
    uint8_t init[8] = { LS_CO_SDO_CCS_DOWNLOAD_INITIATE | LS_CO_SDO_SIZE,
                        (uint8_t)SD_OBJ_LABEL,
                        (uint8_t)(SD_OBJ_LABEL >> 8),
                        0,
                        200,
                        0,
                        0,
                        0 };
    hal_can_frame_t r = sdo_exchange(N1, init);
    assert_int_equal(abort_of(&r), LS_CO_ABORT_TYPE_LEN_HIGH);
}

static void test_a_segment_with_the_wrong_toggle_aborts(void **state)
{
    (void)state;
    open_drives(1);
    uint8_t init[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, MUX(LS_CO_OBJ_DEVICE_NAME, 0), 0, 0, 0, 0 };
    hal_can_frame_t r = sdo_exchange(N1, init);
    assert_int_equal(r.data[0], LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_SIZE);
    uint8_t seg[8] = { LS_CO_SDO_CCS_UPLOAD_SEGMENT | LS_CO_SDO_TOGGLE, 0, 0, 0, 0, 0, 0, 0 }; /* must start at 0 */
    r = sdo_exchange(N1, seg);
    assert_int_equal(abort_of(&r), LS_CO_ABORT_TOGGLE);
    assert_int_equal(r.data[1] | r.data[2] << 8, LS_CO_OBJ_DEVICE_NAME);
    /* and a segment without a transfer is an unexpected command */
    uint8_t lone[8] = { LS_CO_SDO_CCS_UPLOAD_SEGMENT, 0, 0, 0, 0, 0, 0, 0 };
    r = sdo_exchange(N1, lone);
    assert_int_equal(abort_of(&r), LS_CO_ABORT_CS);
}

static void test_a_stalled_segmented_transfer_times_out(void **state)
{
    (void)state;
    open_drives(1);
    uint8_t init[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, MUX(LS_CO_OBJ_DEVICE_NAME, 0), 0, 0, 0, 0 };
    (void)sdo_exchange(N1, init);
    size_t mark = g_n_sent;
    advance_ms(999);
    assert_int_equal(count_sent(LS_CO_COB_SDO_TX + N1, mark, NULL), 0);
    advance_ms(2);
    hal_can_frame_t r = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_SDO_TX + N1, mark, &r), 1);
    assert_int_equal(abort_of(&r), LS_CO_ABORT_TIMEOUT);
}

static void test_block_transfers_and_unknown_specifiers_are_refused(void **state)
{
    (void)state;
    open_drives(1);
    uint8_t block[8] = { LS_CO_SDO_CCS_BLOCK_UPLOAD, MUX(LS_CO_OBJ_DEVICE_TYPE, 0), 0, 0, 0, 0 };
    hal_can_frame_t r = sdo_exchange(N1, block);
    assert_int_equal(abort_of(&r), LS_CO_ABORT_CS);
    /* a client's abort gets no answer */
    uint8_t ab[8] = { LS_CO_SDO_CS_ABORT, MUX(LS_CO_OBJ_DEVICE_TYPE, 0), 0, 0, 0, 0 };
    size_t mark = g_n_sent;
    rx(LS_CO_COB_SDO_RX + N1, ab, 8);
    assert_int_equal(count_sent(LS_CO_COB_SDO_TX + N1, mark, NULL), 0);
}

/* ======================================================================
 * NMT and heartbeat
 * ====================================================================== */

static void test_boot_up_at_open_and_after_each_reset(void **state)
{
    (void)state;
    open_drives(2);
    hal_can_frame_t f = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, 0, &f), 1);
    assert_int_equal(f.len, 1);
    assert_int_equal(f.data[0], LS_CO_NMT_BOOTUP);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N2, 0, NULL), 1);
    size_t mark = g_n_sent;
    nmt(LS_CO_NMT_RESET_COMM, N1);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL), 1);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N2, mark, NULL), 0);
    mark = g_n_sent;
    nmt(LS_CO_NMT_RESET_NODE, LS_CO_NMT_ALL_NODES);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL), 1);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N2, mark, NULL), 1);
}

static void test_the_heartbeat_carries_the_nmt_state_at_its_period(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 100, 2), 0);
    size_t mark = g_n_sent;
    advance_ms(1000);
    hal_can_frame_t f = { 0 };
    int n = count_sent(LS_CO_COB_HEARTBEAT + N1, mark, &f);
    assert_true(n >= 9 && n <= 11);
    assert_int_equal(f.data[0], LS_CO_NMT_PREOPERATIONAL);
    nmt(LS_CO_NMT_START, N1);
    advance_ms(150);
    (void)count_sent(LS_CO_COB_HEARTBEAT + N1, mark, &f);
    assert_int_equal(f.data[0], LS_CO_NMT_OPERATIONAL);
    nmt(LS_CO_NMT_STOP, N1);
    advance_ms(150);
    (void)count_sent(LS_CO_COB_HEARTBEAT + N1, mark, &f);
    assert_int_equal(f.data[0], LS_CO_NMT_STOPPED);
    /* STOPPED: no SDO answer */
    uint8_t req[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, MUX(LS_CO_OBJ_DEVICE_TYPE, 0), 0, 0, 0, 0 };
    mark = g_n_sent;
    rx(LS_CO_COB_SDO_RX + N1, req, 8);
    assert_int_equal(count_sent(LS_CO_COB_SDO_TX + N1, mark, NULL), 0);
    nmt(LS_CO_NMT_ENTER_PREOP, N1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_PRODUCER_HB, 0), 100);
}

static void test_a_flooded_link_leaves_the_heartbeat_on_time(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 100, 2), 0);
    advance_ms(150);
    size_t mark = g_n_sent;
    g_flood = 100000u; /* more than the drives take in a poll: a bus faster than this machine */
    g_taken = 0u;
    for (int ms = 0; ms < 1000; ms++) {
        g_now += 1000u;
        assert_int_equal(hal_sim_drives_poll(g_now), LS_OK);
    }
    assert_int_equal(g_taken, 1000u * HAL_SIM_DRIVES_RX_PER_POLL);
    int n = count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL);
    g_flood = 0u;
    assert_true(n >= 9 && n <= 11);
}

static void test_reset_communication_keeps_the_drive_objects(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 50, 2), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_HOME_OFFSET, 0, 1234, 4), 0);
    nmt(LS_CO_NMT_RESET_COMM, N1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_PRODUCER_HB, 0), 0);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_HOME_OFFSET, 0), 1234);
    nmt(LS_CO_NMT_RESET_NODE, N1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_HOME_OFFSET, 0), 0);
}

/* ======================================================================
 * PDOs
 * ====================================================================== */

static void test_pdo_remapping_follows_the_cia_301_order(void **state)
{
    (void)state;
    open_drives(1);
    const uint16_t comm = LS_CO_OBJ_RPDO_COMM, map = LS_CO_OBJ_RPDO_MAP; /* RPDO1: valid at power-on */
    uint32_t cob = LS_CO_COB_RPDO(1, N1);
    /* a valid PDO keeps its mapping, type and COB-ID */
    assert_int_equal(sdo_write(N1, map, 0, 0, 1), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_TYPE, 1, 1), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_COB_ID, cob + 1, 4), LS_CO_ABORT_VALUE);
    /* bit 31 first */
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_COB_ID, cob | LS_CO_COBID_INVALID, 4), 0);
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_TYPE, 1, 1), 0);
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_TYPE, 241, 1), LS_CO_ABORT_VALUE);
    /* entries only while sub 0 is 0 */
    uint32_t e1 = LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_CONTROLWORD, 0, 16);
    uint32_t e2 = LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32);
    assert_int_equal(sdo_write(N1, map, 2, e2, 4), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_write(N1, map, 0, 0, 1), 0);
    /* entries that cannot be mapped into an RPDO */
    assert_int_equal(sdo_write(N1, map, 2, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_STATUSWORD, 0, 16), 4), LS_CO_ABORT_NO_MAP);
    assert_int_equal(sdo_write(N1, map, 2, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_HOME_OFFSET, 0, 32), 4), LS_CO_ABORT_NO_MAP);
    assert_int_equal(sdo_write(N1, map, 2, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 16), 4),
                     LS_CO_ABORT_NO_MAP);
    assert_int_equal(sdo_write(N1, map, 2, LS_CO_PDO_MAP_ENTRY(0x6071, 0, 16), 4), LS_CO_ABORT_NO_OBJECT);
    assert_int_equal(sdo_write(N1, map, 1, e1, 4), 0);
    assert_int_equal(sdo_write(N1, map, 2, e2, 4), 0);
    assert_int_equal(sdo_write(N1, map, 3, e2, 4), 0);
    /* sub 0 = N checks entries 1..N: 16 + 32 + 32 + 32 bits do not fit */
    assert_int_equal(sdo_write(N1, map, 4, e2, 4), 0);
    assert_int_equal(sdo_write(N1, map, 0, 4, 1), LS_CO_ABORT_MAP_LEN);
    assert_int_equal(sdo_write(N1, map, 0, 2, 1), 0);
    /* a COB-ID with bit 29 or reserved bits, or 0, is not taken */
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_COB_ID, cob | LS_CO_COBID_FRAME, 4), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_COB_ID, 0, 4), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_write(N1, comm, LS_CO_PDO_SUB_COB_ID, cob, 4), 0);
    assert_int_equal(sdo_read(N1, map, 0), 2);
    /* a TPDO takes what an RPDO cannot */
    uint16_t tmap = LS_CO_OBJ_TPDO_MAP + 3; /* TPDO4: invalid at power-on */
    assert_int_equal(sdo_write(N1, tmap, 0, 0, 1), 0);
    assert_int_equal(sdo_write(N1, tmap, 1, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_STATUSWORD, 0, 16), 4), 0);
    assert_int_equal(sdo_write(N1, tmap, 2, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32), 4),
                     LS_CO_ABORT_NO_MAP);
    /* a PDO that maps nothing cannot be enabled */
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM + 3, LS_CO_PDO_SUB_COB_ID, LS_CO_COB_TPDO(4, N1), 4),
                     LS_CO_ABORT_VALUE);
}

/* RPDO1 = controlword + target position, TPDO1 = statusword + position
 * actual, both synchronous every SYNC; the rest off. */
static void map_csp(uint8_t node)
{
    for (uint16_t k = 0; k < 4; k++) {
        assert_int_equal(sdo_write(node, (uint16_t)(LS_CO_OBJ_RPDO_COMM + k), LS_CO_PDO_SUB_COB_ID,
                                   LS_CO_COB_RPDO(k + 1, node) | LS_CO_COBID_INVALID, 4),
                         0);
        assert_int_equal(sdo_write(node, (uint16_t)(LS_CO_OBJ_TPDO_COMM + k), LS_CO_PDO_SUB_COB_ID,
                                   LS_CO_COB_TPDO(k + 1, node) | LS_CO_COBID_INVALID, 4),
                         0);
    }
    assert_int_equal(sdo_write(node, LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_TYPE, 1, 1), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_RPDO_MAP, 0, 0, 1), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_RPDO_MAP, 1, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_CONTROLWORD, 0, 16), 4), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_RPDO_MAP, 2, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32), 4),
                     0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_RPDO_MAP, 0, 2, 1), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_COB_ID, LS_CO_COB_RPDO(1, node), 4), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_TYPE, 1, 1), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TPDO_MAP, 0, 0, 1), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TPDO_MAP, 1, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_STATUSWORD, 0, 16), 4), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TPDO_MAP, 2, LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_POSITION_ACTUAL, 0, 32), 4),
                     0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TPDO_MAP, 0, 2, 1), 0);
    assert_int_equal(sdo_write(node, LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_COB_ID, LS_CO_COB_TPDO(1, node), 4), 0);
}

static void rpdo1(uint8_t node, uint16_t cw, int32_t target)
{
    uint32_t t = (uint32_t)target;
    uint8_t d[6] = { (uint8_t)cw,       (uint8_t)(cw >> 8), (uint8_t)t,
                     (uint8_t)(t >> 8), (uint8_t)(t >> 16), (uint8_t)(t >> 24) };
    rx(LS_CO_COB_RPDO(1, node), d, 6);
}

static void test_a_synchronous_rpdo_acts_at_the_next_sync_and_tpdos_follow_each_sync(void **state)
{
    (void)state;
    open_drives(1);
    map_csp(N1);
    size_t mark = g_n_sent;
    sync_frame(); /* PRE-OPERATIONAL: no PDOs */
    assert_int_equal(count_sent(LS_CO_COB_TPDO(1, N1), mark, NULL), 0);
    nmt(LS_CO_NMT_START, N1);
    rpdo1(N1, LS_CO_CW_CMD_SHUTDOWN, 0);
    assert_true(in_state(statusword(N1), LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_SWITCH_ON_DISABLED_STATE));
    mark = g_n_sent;
    sync_frame();
    hal_can_frame_t f = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_TPDO(1, N1), mark, &f), 1);
    assert_int_equal(f.len, 6);
    /* sampled at the SYNC, before its RPDO acted */
    assert_true(
        in_state((uint16_t)(f.data[0] | f.data[1] << 8), LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_SWITCH_ON_DISABLED_STATE));
    assert_true(in_state(statusword(N1), LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_READY_STATE));
    mark = g_n_sent;
    sync_frame();
    assert_int_equal(count_sent(LS_CO_COB_TPDO(1, N1), mark, &f), 1);
    assert_true(in_state((uint16_t)(f.data[0] | f.data[1] << 8), LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_READY_STATE));
    /* every third SYNC */
    nmt(LS_CO_NMT_ENTER_PREOP, N1);
    uint32_t cob = LS_CO_COB_TPDO(1, N1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, 1, cob | LS_CO_COBID_INVALID, 4), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_TYPE, 3, 1), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, 1, cob, 4), 0);
    nmt(LS_CO_NMT_START, N1);
    mark = g_n_sent;
    for (int k = 0; k < 9; k++) {
        sync_frame();
    }
    assert_int_equal(count_sent(cob, mark, NULL), 3);
    /* a short RPDO is dropped with EMCY 0x8210 */
    mark = g_n_sent;
    uint8_t shortd[2] = { 0, 0 };
    rx(LS_CO_COB_RPDO(1, N1), shortd, 2);
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 1);
    assert_int_equal(f.data[0] | f.data[1] << 8, LS_CO_EMCY_PDO_LENGTH);
    assert_true((f.data[2] & LS_CO_ERR_REG_COMMUNICATION) != 0u);
    rpdo1(N1, LS_CO_CW_CMD_SHUTDOWN, 0); /* a good one clears it */
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 2);
    assert_int_equal(f.data[0] | f.data[1] << 8, LS_CO_EMCY_NO_ERROR);
}

static void test_event_driven_tpdos_follow_changes_inhibit_time_and_event_timer(void **state)
{
    (void)state;
    open_drives(1);
    /* TPDO1 = statusword, type 255 at power-on: inhibit 50 ms, timer 200 ms */
    uint32_t cob = LS_CO_COBID_NO_RTR | LS_CO_COB_TPDO(1, N1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, 1, cob | LS_CO_COBID_INVALID, 4), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_INHIBIT, 500, 2), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_EVENT_TIMER, 200, 2), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TPDO_COMM, 1, cob, 4), 0);
    size_t mark = g_n_sent;
    nmt(LS_CO_NMT_START, N1);
    uint32_t id = LS_CO_COB_TPDO(1, N1);
    assert_int_equal(count_sent(id, mark, NULL), 1); /* once on entering OPERATIONAL */
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);          /* a change within the inhibit time: held */
    assert_int_equal(count_sent(id, mark, NULL), 1);
    advance_ms(51);
    assert_int_equal(count_sent(id, mark, NULL), 2);
    mark = g_n_sent;
    advance_ms(1000); /* no change: the event timer */
    int n = count_sent(id, mark, NULL);
    assert_true(n >= 4 && n <= 5);
}

/* ======================================================================
 * Heartbeat consumer and 0x6007
 * ====================================================================== */

static void test_a_lost_heartbeat_reacts_as_0x6007_says(void **state)
{
    (void)state;
    open_drives(1);
    const uint8_t master = 0x7F;
    uint32_t entry = (uint32_t)master << LS_CO_HB_CONSUMER_NODE_SHIFT | 100u;
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_CONSUMER_HB, 1, entry, 4), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_CONSUMER_HB, 2, entry + 50u, 4), LS_CO_ABORT_PARAM_INCOMPAT);
    nmt(LS_CO_NMT_START, N1);
    enable_csp(N1);
    uint8_t hb = LS_CO_NMT_OPERATIONAL;
    size_t mark = g_n_sent;
    advance_ms(500); /* no heartbeat yet: monitoring has not started */
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, NULL), 0);
    for (int k = 0; k < 5; k++) {
        rx(LS_CO_COB_HEARTBEAT + master, &hb, 1);
        advance_ms(80);
    }
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, NULL), 0);
    advance_ms(30); /* 110 ms since the last one */
    hal_can_frame_t f = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 1);
    assert_int_equal(f.data[0] | f.data[1] << 8, LS_CO_EMCY_HEARTBEAT);
    assert_true(in_state(statusword(N1), LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE)); /* 0x6007 = 1 */
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_ERROR_CODE, 0), LS_CO_EMCY_HEARTBEAT);
    assert_int_equal(sdo_read(N1, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED), 1);
    /* 0x1029:01 = 0: OPERATIONAL -> PRE-OPERATIONAL */
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 10, 2), 0);
    mark = g_n_sent;
    advance_ms(15);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, &f), 1);
    assert_int_equal(f.data[0], LS_CO_NMT_PREOPERATIONAL);

    /* 0x6007 = 3: quick stop (and 0x605A = 6 stays there) */
    controlword(N1, LS_CO_CW_FAULT_RESET);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_ABORT_CONNECTION, 0, LS_CO_ABORT_CONN_QUICK_STOP, 2), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_QUICK_STOP_OPTION, 0, 6, 2), 0);
    rx(LS_CO_COB_HEARTBEAT + master, &hb, 1);
    enable_csp(N1);
    advance_ms(101);
    assert_true(in_state(statusword(N1), LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_QUICK_STOP_STATE));
    /* 0x6007 = 2: disable voltage */
    controlword(N1, LS_CO_CW_CMD_DISABLE_VOLTAGE);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_ABORT_CONNECTION, 0, LS_CO_ABORT_CONN_DISABLE_VOLTAGE, 2), 0);
    rx(LS_CO_COB_HEARTBEAT + master, &hb, 1);
    enable_csp(N1);
    advance_ms(101);
    assert_true(in_state(statusword(N1), LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_SWITCH_ON_DISABLED_STATE));
}

static void test_the_drives_run_on_while_their_link_is_down(void **state)
{
    (void)state;
    open_drives(1);
    const uint8_t master = 0x7F;
    uint32_t entry = (uint32_t)master << LS_CO_HB_CONSUMER_NODE_SHIFT | 100u;
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_CONSUMER_HB, 1, entry, 4), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 20, 2), 0);
    nmt(LS_CO_NMT_START, N1);
    enable_csp(N1);
    uint8_t hb = LS_CO_NMT_OPERATIONAL;
    rx(LS_CO_COB_HEARTBEAT + master, &hb, 1);
    advance_ms(50);
    hal_sim_drives_stats_t before;
    hal_sim_drives_stats(&before);
    size_t mark = g_n_sent;
    g_link_down = true;
    for (int ms = 0; ms < 200; ms++) {
        g_now += 1000u;
        assert_int_equal(hal_sim_drives_poll(g_now), LS_EIO); /* said every call, and the drive runs on */
    }
    g_link_down = false;
    hal_sim_drives_stats_t during;
    hal_sim_drives_stats(&during);
    assert_int_equal(g_n_sent, mark);
    /* its heartbeats (one per 20 ms) and the EMCY of its consumer's time-out: dropped, counted */
    assert_true(during.tx_dropped >= before.tx_dropped + 10u);
    advance_ms(1); /* the link carries frames again */
    assert_true(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL) <= 1);
    /* the heartbeat consumer acted while the bus was gone (0x6007 = 1: fault) */
    assert_true(in_state(statusword(N1), LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE));
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_ERROR_CODE, 0), LS_CO_EMCY_HEARTBEAT);
    advance_ms(25);
    assert_true(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL) >= 1);
}

/* ======================================================================
 * The CiA 402 power state machine
 * ====================================================================== */

static void expect_state(uint16_t mask, uint16_t value)
{
    uint16_t sw = statusword(N1);
    if (!in_state(sw, mask, value)) {
        fail_msg("statusword 0x%04X, expected 0x%04X under mask 0x%04X", sw, value, mask);
    }
}

static void test_every_power_state_transition(void **state)
{
    (void)state;
    open_drives(1);
    const uint16_t L = LS_CO_SW_STATE_MASK_LONG, S = LS_CO_SW_STATE_MASK_SHORT;
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN); /* 2 */
    expect_state(L, LS_CO_SW_READY_STATE);
    controlword(N1, LS_CO_CW_CMD_SWITCH_ON); /* 3 */
    expect_state(L, LS_CO_SW_SWITCHED_ON_STATE);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION); /* 4 */
    expect_state(L, LS_CO_SW_ENABLED_STATE);
    assert_int_equal(sdo_read(N1, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED), 0);
    controlword(N1, LS_CO_CW_CMD_SWITCH_ON); /* 5 */
    expect_state(L, LS_CO_SW_SWITCHED_ON_STATE);
    assert_int_equal(sdo_read(N1, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED), 1);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN); /* 6 */
    expect_state(L, LS_CO_SW_READY_STATE);
    controlword(N1, LS_CO_CW_CMD_DISABLE_VOLTAGE); /* 7 */
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION); /* 3 + 4 */
    expect_state(L, LS_CO_SW_ENABLED_STATE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN); /* 8 */
    expect_state(L, LS_CO_SW_READY_STATE);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION);
    controlword(N1, LS_CO_CW_CMD_DISABLE_VOLTAGE); /* 9 */
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_SWITCH_ON);
    controlword(N1, LS_CO_CW_CMD_QUICK_STOP); /* 10 */
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION);
    controlword(N1, LS_CO_CW_CMD_QUICK_STOP); /* 11, then 12 by itself (0x605A = 2, at rest) */
    advance_ms(1);
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_QUICK_STOP_OPTION, 0, 6, 2), 0);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION);
    controlword(N1, LS_CO_CW_CMD_QUICK_STOP); /* 11, and 0x605A = 6 stays */
    advance_ms(5);
    expect_state(L, LS_CO_SW_QUICK_STOP_STATE);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION); /* 16 */
    expect_state(L, LS_CO_SW_ENABLED_STATE);
    controlword(N1, LS_CO_CW_CMD_QUICK_STOP);
    controlword(N1, LS_CO_CW_CMD_DISABLE_VOLTAGE); /* 12 by command */
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    /* 13, 14, 15 */
    char cmd[] = "emcy 0x21 0x2310";
    assert_int_equal(hal_sim_drives_control(cmd, strlen(cmd), g_now), 1);
    advance_ms(1);
    expect_state(S, LS_CO_SW_FAULT_STATE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN); /* no way out but a reset */
    expect_state(S, LS_CO_SW_FAULT_STATE);
    controlword(N1, LS_CO_CW_FAULT_RESET);
    expect_state(S, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
}

static void test_fault_reset_acts_on_the_rising_edge_of_bit_7_only(void **state)
{
    (void)state;
    open_drives(1);
    controlword(N1, LS_CO_CW_FAULT_RESET); /* bit 7 held high before the fault */
    char cmd[] = "emcy 0x21 0x4210";
    size_t mark = g_n_sent;
    assert_int_equal(hal_sim_drives_control(cmd, strlen(cmd), g_now), 1);
    hal_can_frame_t f = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 1);
    assert_int_equal(f.data[0] | f.data[1] << 8, 0x4210);
    assert_int_equal(f.data[2], LS_CO_ERR_REG_GENERIC | LS_CO_ERR_REG_TEMPERATURE);
    advance_ms(1);
    controlword(N1, LS_CO_CW_FAULT_RESET); /* still high: no edge */
    expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_ERROR_CODE, 0), 0x4210);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_ERROR_REGISTER, 0), LS_CO_ERR_REG_GENERIC | LS_CO_ERR_REG_TEMPERATURE);
    controlword(N1, 0);
    mark = g_n_sent;
    controlword(N1, LS_CO_CW_FAULT_RESET); /* the edge */
    expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_ERROR_CODE, 0), 0);
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 1); /* error reset */
    assert_int_equal(f.data[0] | f.data[1] << 8 | f.data[2], 0);
}

static void test_modes_are_checked_and_the_display_follows(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_SUPPORTED_MODES, 0),
                     1u << (LS_CO_MODE_CSP - 1) | 1u << (LS_CO_MODE_HM - 1));
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_MODES, 0, LS_CO_MODE_CSV, 1), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_MODES, 0, (uint32_t)(uint8_t)-1, 1), LS_CO_ABORT_VALUE);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_MODES_DISPLAY, 0), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_MODES, 0, LS_CO_MODE_CSP, 1), 0);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_MODES_DISPLAY, 0), LS_CO_MODE_CSP);
}

/* ======================================================================
 * CSP: the physics per SYNC
 * ====================================================================== */

static void test_csp_moves_the_joint_only_on_sync_over_the_interpolation_period(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 1, 4, 1), 0); /* 4 ms */
    enable_csp(N1);
    double q0 = joint_q(0);
    int32_t p0 = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
    assert_int_equal(p0, (int32_t)lround(q0 * CPR));
    int32_t target = p0 + (int32_t)(0.2 * CPR);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)target, 4), 0);
    advance_ms(200); /* no SYNC, no motion */
    assert_true(fabs(joint_q(0) - q0) < 1e-6);
    /* a ramp of set-points, 1 mrad per 4 ms period: 0.25 rad/s */
    hal_sim_drives_stats_t st0, st1;
    hal_sim_drives_stats(&st0);
    for (int k = 1; k <= 200; k++) {
        int32_t t = p0 + (int32_t)lround(k * 0.001 * CPR);
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)t, 4), 0);
        sync_frame();
    }
    hal_sim_drives_stats(&st1);
    assert_int_equal(st1.syncs - st0.syncs, 200);
    assert_int_equal(st1.substeps - st0.substeps, 800); /* 4 ms in 1 ms sub-steps */
    double q = joint_q(0);
    print_message("after 200 SYNCs: %.5f rad (command %.5f, lag %.5f)\n", q - q0, 0.2, 0.2 - (q - q0));
    assert_true(fabs((q - q0) - 0.2) < 0.25 / 200.0 * 1.5); /* within the servo's lag v / 200 */
    for (int k = 0; k < 100; k++) {
        sync_frame();
    }
    assert_true(fabs(joint_q(0) - q0 - 0.2) < 2e-4);
    int32_t pf = sdo_read_i32(N1, LS_CO_OBJ_FOLLOWING_ACTUAL, 0);
    assert_true(abs(pf) < 30);
    assert_true(fabs(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0) - (p0 + 0.2 * CPR)) < 30);
    expect_state(LS_CO_SW_OMS12 | LS_CO_SW_OMS13, LS_CO_SW_OMS12);
}

static void test_a_longer_sub_step_cuts_the_period_into_fewer_steps_to_the_same_place(void **state)
{
    (void)state;
    g_substep_s = 0.010;
    open_drives(1);
    g_substep_s = 0.0;
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 1, 20, 1), 0); /* 20 ms */
    enable_csp(N1);
    double q0 = joint_q(0);
    int32_t p0 = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
    hal_sim_drives_stats_t st0, st1;
    hal_sim_drives_stats(&st0);
    for (int k = 1; k <= 50; k++) { /* 0.1 rad in 1 s */
        int32_t t = p0 + (int32_t)lround(k * 0.002 * CPR);
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)t, 4), 0);
        sync_frame();
    }
    for (int k = 0; k < 50; k++) {
        sync_frame();
    }
    hal_sim_drives_stats(&st1);
    assert_int_equal(st1.substeps - st0.substeps, 200); /* 20 ms in 10 ms sub-steps */
    assert_true(fabs(joint_q(0) - q0 - 0.1) < 2e-4);
}

static void test_the_velocity_offset_feeds_forward(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 1, 4, 1), 0);
    enable_csp(N1);
    double worst[2] = { 0.0, 0.0 }; /* following error without, then with 0x60B1 */
    for (int pass = 0; pass < 2; pass++) {
        int32_t base = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
        int32_t v = pass == 0 ? 0 : (int32_t)(0.25 * CPR); /* 100 counts per 4 ms */
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_VELOCITY_OFFSET, 0, (uint32_t)v, 4), 0);
        for (int k = 1; k <= 100; k++) {
            assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)(base + k * 100), 4), 0);
            sync_frame();
            if (k > 20) {
                worst[pass] = fmax(worst[pass], fabs((double)sdo_read_i32(N1, LS_CO_OBJ_FOLLOWING_ACTUAL, 0)));
            }
        }
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_VELOCITY_OFFSET, 0, 0, 4), 0);
        for (int k = 0; k < 50; k++) {
            sync_frame();
        }
    }
    print_message("following error at 0.25 rad/s: %.0f counts without 0x60B1, %.0f with\n", worst[0], worst[1]);
    assert_true(worst[0] > 80.0); /* the servo's lag, about v / 200 rad: 125 counts */
    assert_true(worst[1] < worst[0] / 3.0);
}

static void test_a_following_error_faults_with_emcy_8611(void **state)
{
    (void)state;
    open_drives(1);
    enable_csp(N1);
    int32_t p0 = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
    /* a jump of 1 rad: far outside the 100000-count window */
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_FOLLOWING_WINDOW, 0, 2000, 4), 0);
    size_t mark = g_n_sent;
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)(p0 + (int32_t)CPR), 4), 0);
    for (int k = 0; k < 30; k++) {
        sync_frame();
        advance_ms(1);
    }
    hal_can_frame_t f = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 1);
    assert_int_equal(f.data[0] | f.data[1] << 8, LS_CO_EMCY_FOLLOWING_ERROR);
    expect_state(LS_CO_SW_STATE_MASK_SHORT | LS_CO_SW_OMS13, LS_CO_SW_FAULT_STATE | LS_CO_SW_OMS13);
    /* the brake holds the joint where the fault found it */
    double q = joint_q(0);
    for (int k = 0; k < 50; k++) {
        sync_frame();
    }
    assert_true(fabs(joint_q(0) - q) < 1e-5);
}

static void test_positions_wrap_around_the_int32_counter(void **state)
{
    (void)state;
    static const uint8_t ids[] = { N1 };
    const int32_t offset = INT32_MAX - 5000; /* 0.05 rad from the wrap */
    open_drives_at(1, ids, &offset, NULL);
    assert_int_equal(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0), offset);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 1, 4, 1), 0);
    enable_csp(N1);
    double q0 = joint_q(0);
    /* 0.1 rad forward crosses the wrap: the target reads negative */
    for (int k = 1; k <= 100; k++) {
        uint32_t t = (uint32_t)offset + (uint32_t)(k * 100);
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, t, 4), 0);
        sync_frame();
    }
    for (int k = 0; k < 100; k++) {
        sync_frame();
    }
    assert_true(fabs(joint_q(0) - q0 - 0.1) < 2e-4);
    int32_t p = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
    assert_true(p < 0);
    assert_true(abs((int32_t)((uint32_t)p - ((uint32_t)offset + 10000u))) < 30);
    expect_state(LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_ENABLED_STATE);
}

static void test_homing_on_the_current_position_sets_the_home_offset(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_HOME_OFFSET, 0, 123456, 4), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_MODES, 0, LS_CO_MODE_HM, 1), 0);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION);
    const uint16_t hm = LS_CO_SW_TARGET_REACHED | LS_CO_SW_OMS12 | LS_CO_SW_OMS13;
    expect_state(hm, LS_CO_SW_TARGET_REACHED); /* not started */
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION | LS_CO_CW_HOMING_START);
    expect_state(hm, LS_CO_SW_TARGET_REACHED | LS_CO_SW_OMS12); /* attained */
    assert_int_equal(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0), 123456);
    /* survives disable and enable */
    controlword(N1, LS_CO_CW_CMD_DISABLE_VOLTAGE);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION);
    expect_state(hm, LS_CO_SW_TARGET_REACHED | LS_CO_SW_OMS12);
    assert_int_equal(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0), 123456);
    /* reset node forgets it */
    nmt(LS_CO_NMT_RESET_NODE, N1);
    assert_int_equal(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0), (int32_t)lround(joint_q(0) * CPR));
}

static void test_software_limits_clamp_the_target(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_SW_POSITION_LIMIT, 1, (uint32_t)-1000, 4), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_SW_POSITION_LIMIT, 2, 5000, 4), 0);
    enable_csp(N1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, 8000, 4), 0);
    for (int k = 0; k < 300; k++) {
        sync_frame();
    }
    assert_true(abs(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0) - 5000) < 20);
    expect_state(LS_CO_SW_INTERNAL_LIMIT, LS_CO_SW_INTERNAL_LIMIT);
}

static void test_a_quick_stop_ramps_the_moving_joint_to_rest(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_INTERP_PERIOD, 1, 4, 1), 0);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_QUICK_STOP_DECEL, 0, (uint32_t)(5.0 * CPR), 4), 0); /* 5 rad/s^2 */
    enable_csp(N1);
    int32_t p0 = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
    int32_t v = (int32_t)(0.5 * CPR); /* 0.5 rad/s: 200 counts per 4 ms */
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_VELOCITY_OFFSET, 0, (uint32_t)v, 4), 0);
    for (int k = 1; k <= 100; k++) {
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)(p0 + k * 200), 4), 0);
        sync_frame();
    }
    double q_at = joint_q(0);
    controlword(N1, LS_CO_CW_CMD_QUICK_STOP);
    expect_state(LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_QUICK_STOP_STATE);
    int syncs = 0;
    while (!in_state(statusword(N1), LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_SWITCH_ON_DISABLED_STATE) && syncs < 100) {
        sync_frame();
        advance_ms(1);
        syncs++;
    }
    double dist = joint_q(0) - q_at;
    /* v^2 / 2a = 0.025 rad in v / a = 0.1 s = 25 periods */
    print_message("quick stop: %d periods, %.4f rad\n", syncs, dist);
    assert_true(syncs >= 24 && syncs <= 28);
    assert_true(dist > 0.02 && dist < 0.035);
}

static void test_a_faulted_drive_brakes_its_joint_while_the_others_move(void **state)
{
    (void)state;
    open_drives(2);
    enable_csp(N1);
    assert_int_equal(sdo_write(N2, LS_CO_OBJ_MODES, 0, LS_CO_MODE_CSP, 1), 0);
    controlword(N2, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N2, LS_CO_CW_CMD_ENABLE_OPERATION);
    char cmd[] = "emcy 0x22 0x2310";
    assert_int_equal(hal_sim_drives_control(cmd, strlen(cmd), g_now), 1);
    double q2 = joint_q(1);
    int32_t p0 = sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0);
    for (int k = 1; k <= 300; k++) {
        assert_int_equal(sdo_write(N1, LS_CO_OBJ_TARGET_POSITION, 0, (uint32_t)(p0 + (k < 100 ? k : 100) * 100), 4), 0);
        sync_frame();
    }
    assert_true(abs(sdo_read_i32(N1, LS_CO_OBJ_POSITION_ACTUAL, 0) - (p0 + 10000)) < 30);
    assert_true(fabs(joint_q(1) - q2) < 1e-5);
    assert_int_equal(sdo_read(N2, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED), 1);
    /* the torque of a braked joint reads 0, of a driven one what holds it */
    assert_int_equal(sdo_read(N2, LS_CO_OBJ_TORQUE_ACTUAL, 0), 0);
}

static void test_safe_torque_off_drops_the_power_stage_and_refuses_switch_on(void **state)
{
    (void)state;
    open_drives(1);
    enable_csp(N1);
    char on[] = "sto 0x21 on", off[] = "sto 0x21 off\n";
    assert_int_equal(hal_sim_drives_control(on, strlen(on), g_now), 1);
    expect_state(LS_CO_SW_STATE_MASK_SHORT | LS_CO_SW_WARNING, LS_CO_SW_SWITCH_ON_DISABLED_STATE | LS_CO_SW_WARNING);
    assert_int_equal(sdo_read(N1, SD_OBJ_BRAKE_STO, SD_SUB_STO_ACTIVE), 1);
    assert_int_equal(sdo_read(N1, SD_OBJ_BRAKE_STO, SD_SUB_BRAKE_ENGAGED), 1);
    controlword(N1, LS_CO_CW_CMD_SHUTDOWN);
    controlword(N1, LS_CO_CW_CMD_SWITCH_ON);
    expect_state(LS_CO_SW_STATE_MASK_LONG, LS_CO_SW_READY_STATE);
    assert_int_equal(hal_sim_drives_control(off, strlen(off), g_now), 1);
    controlword(N1, LS_CO_CW_CMD_ENABLE_OPERATION);
    expect_state(LS_CO_SW_STATE_MASK_LONG | LS_CO_SW_WARNING, LS_CO_SW_ENABLED_STATE);
}

/* ======================================================================
 * Misbehaviour on command
 * ====================================================================== */

static int control(const char *text)
{
    return hal_sim_drives_control(text, strlen(text), g_now);
}

static void test_malformed_control_commands_are_counted_and_ignored(void **state)
{
    (void)state;
    open_drives(1);
    static const char *bad[] = {
        "",
        "frobnicate 0x21",
        "emcy",
        "emcy 0x21",
        "emcy 0x21 0x10000",
        "emcy 0x21 0",
        "emcy 0x22 0x2310",
        "emcy 0x21 2310x",
        "silence",
        "silence 0x21 extra",
        "sticky-fault 0x21 -1",
        "sticky-fault 0x21 1001",
        "identity 0x21 1",
        "sto 0x21 maybe",
        "bus-off 0",
        "bus-off 60001",
        "reset now",
        "emcy 0 0x1000",
        "emcy 0x80 0x1000",
        "silence\t0x21\n\n",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (control(bad[i]) != LS_EINVAL) {
            fail_msg("'%s' was taken", bad[i]);
        }
    }
    assert_int_equal(hal_sim_drives_malformed_messages(), sizeof bad / sizeof bad[0]);
    char big[300];
    memset(big, ' ', sizeof big);
    memcpy(big, "reset", 5);
    assert_int_equal(hal_sim_drives_control(big, sizeof big, g_now), LS_EINVAL);
    assert_int_equal(control(" reset\n"), 1);
    assert_int_equal(control("bus-off"), 1);
    assert_int_equal(control("silence\t33"), 1);
    assert_int_equal(control("reset"), 1);
}

static void test_silence_stops_every_frame_and_reset_brings_them_back(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 10, 2), 0);
    assert_int_equal(control("silence 0x21"), 1);
    size_t mark = g_n_sent;
    advance_ms(100);
    uint8_t req[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, MUX(LS_CO_OBJ_DEVICE_TYPE, 0), 0, 0, 0, 0 };
    rx(LS_CO_COB_SDO_RX + N1, req, 8);
    assert_int_equal(control("emcy 0x21 0x5410"), 1);
    assert_int_equal(g_n_sent, mark);
    assert_int_equal(control("reset"), 1);
    advance_ms(20);
    assert_true(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL) >= 1);
    expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE); /* the fault is real, only unheard */
}

static void test_frozen_tpdos_stop_while_the_heartbeat_goes_on(void **state)
{
    (void)state;
    open_drives(1);
    map_csp(N1);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 10, 2), 0);
    nmt(LS_CO_NMT_START, N1);
    assert_int_equal(control("freeze-tpdo 0x21"), 1);
    size_t mark = g_n_sent;
    for (int k = 0; k < 10; k++) {
        sync_frame();
        advance_ms(10);
    }
    assert_int_equal(count_sent(LS_CO_COB_TPDO(1, N1), mark, NULL), 0);
    assert_true(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL) >= 9);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_DEVICE_TYPE, 0) & LS_CO_DEVICE_PROFILE_MASK, LS_CO_PROFILE_DRIVE);
    assert_int_equal(control("reset"), 1);
    mark = g_n_sent;
    sync_frame();
    assert_int_equal(count_sent(LS_CO_COB_TPDO(1, N1), mark, NULL), 1);
}

static void test_a_sticky_fault_ignores_the_next_reset_edges(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(control("sticky-fault 0x21 2"), 1);
    assert_int_equal(control("emcy 0x21 0x7121"), 1);
    advance_ms(1);
    for (int k = 0; k < 2; k++) {
        controlword(N1, 0);
        controlword(N1, LS_CO_CW_FAULT_RESET);
        expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE);
    }
    controlword(N1, 0);
    controlword(N1, LS_CO_CW_FAULT_RESET);
    expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_SWITCH_ON_DISABLED_STATE);
}

static void test_no_boot_leaves_the_node_silent_after_its_next_reset(void **state)
{
    (void)state;
    open_drives(2);
    assert_int_equal(control("no-boot 0x21"), 1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_DEVICE_TYPE, 0) & LS_CO_DEVICE_PROFILE_MASK, LS_CO_PROFILE_DRIVE);
    size_t mark = g_n_sent;
    nmt(LS_CO_NMT_RESET_NODE, LS_CO_NMT_ALL_NODES);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL), 0);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N2, mark, NULL), 1);
    uint8_t req[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, MUX(LS_CO_OBJ_DEVICE_TYPE, 0), 0, 0, 0, 0 };
    rx(LS_CO_COB_SDO_RX + N1, req, 8);
    nmt(LS_CO_NMT_RESET_NODE, N1);
    assert_int_equal(count_sent(LS_CO_COB_SDO_TX + N1, mark, NULL), 0);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL), 0);
    assert_int_equal(control("reset"), 1);
    assert_int_equal(count_sent(LS_CO_COB_HEARTBEAT + N1, mark, NULL), 1); /* it boots */
}

static void test_a_wrong_identity_is_answered_until_reset(void **state)
{
    (void)state;
    open_drives(1);
    assert_int_equal(control("identity 0x21 0x000000FB 0x65520000"), 1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 1), 0xFB);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 2), 0x65520000);
    nmt(LS_CO_NMT_RESET_COMM, N1); /* survives resets: it is the device's */
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 1), 0xFB);
    assert_int_equal(control("reset"), 1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_IDENTITY, 1), 0x4C53);
}

static void test_bus_off_carries_nothing_for_its_time_then_each_node_says_so(void **state)
{
    (void)state;
    open_drives(2);
    assert_int_equal(sdo_write(N1, LS_CO_OBJ_PRODUCER_HB, 0, 10, 2), 0);
    enable_csp(N1);
    assert_int_equal(control("bus-off 200"), 1);
    /* 0x6007 = 1: the enabled drive faults on bus-off */
    size_t mark = g_n_sent;
    uint8_t req[8] = { LS_CO_SDO_CCS_UPLOAD_INITIATE, MUX(LS_CO_OBJ_DEVICE_TYPE, 0), 0, 0, 0, 0 };
    rx(LS_CO_COB_SDO_RX + N1, req, 8);
    advance_ms(199);
    assert_int_equal(g_n_sent, mark);
    advance_ms(2);
    hal_can_frame_t f = { 0 };
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N1, mark, &f), 1);
    assert_int_equal(f.data[0] | f.data[1] << 8, LS_CO_EMCY_BUS_OFF_RECOVERED);
    assert_int_equal(count_sent(LS_CO_COB_EMCY + N2, mark, NULL), 1);
    assert_int_equal(sdo_read(N1, LS_CO_OBJ_ERROR_CODE, 0), LS_CO_EMCY_BUS_OFF_RECOVERED);
    expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE);
    assert_int_equal(sdo_read(N2, LS_CO_OBJ_ERROR_CODE, 0), 0); /* it was not enabled */
}

static void test_the_control_socket_takes_datagrams(void **state)
{
    (void)state;
    char path[108];
    snprintf(path, sizeof path, "/tmp/ls-simdrives-test-%d.sock", (int)getpid());
    static const uint8_t ids[] = { N1 };
    open_drives_at(1, ids, NULL, path);
    int fd = socket(AF_UNIX, SOCK_DGRAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_un a = { .sun_family = AF_UNIX };
    memcpy(a.sun_path, path, strlen(path) + 1);
    const char *msgs[] = { "emcy 0x21 0x2310\n", "nonsense" };
    for (size_t i = 0; i < 2; i++) {
        assert_true(sendto(fd, msgs[i], strlen(msgs[i]), 0, (struct sockaddr *)&a, sizeof a) > 0);
    }
    close(fd);
    advance_ms(1);
    expect_state(LS_CO_SW_STATE_MASK_SHORT, LS_CO_SW_FAULT_STATE);
    assert_int_equal(hal_sim_drives_malformed_messages(), 1);
    hal_sim_drives_close();
    assert_int_equal(access(path, F_OK), -1); /* unlinked */
}

/* ======================================================================
 * Open, and the cycle's cost
 * ====================================================================== */

static void test_open_refuses_a_bad_configuration(void **state)
{
    (void)state;
    char msg[200];
    hal_sim_drives_config_t dc = { .link = &g_link, .n_drives = 1, .counts_per_rad = CPR };
    dc.drives[0] = (hal_sim_drive_config_t){ N1, 0, 0 };
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_ENODEV); /* no world */
    assert_non_null(strstr(msg, "world"));
    open_world();
    dc.n_drives = 0;
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL);
    dc.n_drives = 2;
    dc.drives[1] = (hal_sim_drive_config_t){ N1, 1, 0 };
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "share"));
    dc.drives[1] = (hal_sim_drive_config_t){ 0x80, 1, 0 };
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL);
    dc.n_drives = 1;
    dc.counts_per_rad = 0.0;
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL);
    dc.counts_per_rad = CPR;
    dc.substep_s = 0.2;
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "sub-step"));
    dc.substep_s = -0.001;
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL);
    dc.substep_s = 0.0;
    dc.control_socket_path = "/nonexistent-dir/x.sock";
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EIO);
    dc.control_socket_path = NULL;
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_OK);
    assert_int_equal(hal_sim_drives_open(&dc, 0, msg, sizeof msg), LS_EINVAL); /* one set per process */
}

static void test_sync_cycles_and_sdo_do_not_allocate(void **state)
{
    (void)state;
    open_drives(6);
    for (uint8_t id = N1; id < N1 + 6; id++) {
        map_csp(id);
    }
    nmt(LS_CO_NMT_START, LS_CO_NMT_ALL_NODES);
    for (int k = 0; k < 50; k++) { /* ODE's arenas settle */
        sync_frame();
    }
    alloc_counter_reset();
    alloc_counter_arm();
    for (int k = 0; k < 200; k++) {
        for (uint8_t id = N1; id < N1 + 6; id++) {
            rpdo1(id, k < 5 ? LS_CO_CW_CMD_SHUTDOWN : LS_CO_CW_CMD_ENABLE_OPERATION, 0);
        }
        sync_frame();
        (void)sdo_read(N1, LS_CO_OBJ_DEVICE_NAME, 0);
        advance_ms(1);
    }
    alloc_counter_disarm();
    assert_int_equal(alloc_counter_count(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test_teardown(test_the_eds_defaults_read_back_over_sdo, teardown),
        cmocka_unit_test_teardown(test_missing_objects_and_sub_indices_get_their_abort_codes, teardown),
        cmocka_unit_test_teardown(test_read_only_objects_refuse_writes_and_keep_their_value, teardown),
        cmocka_unit_test_teardown(test_a_write_of_another_length_than_the_type_is_refused, teardown),
        cmocka_unit_test_teardown(test_values_beyond_the_eds_limits_are_refused, teardown),
        cmocka_unit_test_teardown(test_a_segmented_download_writes_a_string, teardown),
        cmocka_unit_test_teardown(test_a_string_longer_than_the_object_is_refused, teardown),
        cmocka_unit_test_teardown(test_a_segment_with_the_wrong_toggle_aborts, teardown),
        cmocka_unit_test_teardown(test_a_stalled_segmented_transfer_times_out, teardown),
        cmocka_unit_test_teardown(test_block_transfers_and_unknown_specifiers_are_refused, teardown),
        cmocka_unit_test_teardown(test_boot_up_at_open_and_after_each_reset, teardown),
        cmocka_unit_test_teardown(test_the_heartbeat_carries_the_nmt_state_at_its_period, teardown),
        cmocka_unit_test_teardown(test_a_flooded_link_leaves_the_heartbeat_on_time, teardown),
        cmocka_unit_test_teardown(test_reset_communication_keeps_the_drive_objects, teardown),
        cmocka_unit_test_teardown(test_pdo_remapping_follows_the_cia_301_order, teardown),
        cmocka_unit_test_teardown(test_a_synchronous_rpdo_acts_at_the_next_sync_and_tpdos_follow_each_sync, teardown),
        cmocka_unit_test_teardown(test_event_driven_tpdos_follow_changes_inhibit_time_and_event_timer, teardown),
        cmocka_unit_test_teardown(test_a_lost_heartbeat_reacts_as_0x6007_says, teardown),
        cmocka_unit_test_teardown(test_the_drives_run_on_while_their_link_is_down, teardown),
        cmocka_unit_test_teardown(test_every_power_state_transition, teardown),
        cmocka_unit_test_teardown(test_fault_reset_acts_on_the_rising_edge_of_bit_7_only, teardown),
        cmocka_unit_test_teardown(test_modes_are_checked_and_the_display_follows, teardown),
        cmocka_unit_test_teardown(test_csp_moves_the_joint_only_on_sync_over_the_interpolation_period, teardown),
        cmocka_unit_test_teardown(test_a_longer_sub_step_cuts_the_period_into_fewer_steps_to_the_same_place, teardown),
        cmocka_unit_test_teardown(test_the_velocity_offset_feeds_forward, teardown),
        cmocka_unit_test_teardown(test_a_following_error_faults_with_emcy_8611, teardown),
        cmocka_unit_test_teardown(test_positions_wrap_around_the_int32_counter, teardown),
        cmocka_unit_test_teardown(test_homing_on_the_current_position_sets_the_home_offset, teardown),
        cmocka_unit_test_teardown(test_software_limits_clamp_the_target, teardown),
        cmocka_unit_test_teardown(test_a_quick_stop_ramps_the_moving_joint_to_rest, teardown),
        cmocka_unit_test_teardown(test_a_faulted_drive_brakes_its_joint_while_the_others_move, teardown),
        cmocka_unit_test_teardown(test_safe_torque_off_drops_the_power_stage_and_refuses_switch_on, teardown),
        cmocka_unit_test_teardown(test_malformed_control_commands_are_counted_and_ignored, teardown),
        cmocka_unit_test_teardown(test_silence_stops_every_frame_and_reset_brings_them_back, teardown),
        cmocka_unit_test_teardown(test_frozen_tpdos_stop_while_the_heartbeat_goes_on, teardown),
        cmocka_unit_test_teardown(test_a_sticky_fault_ignores_the_next_reset_edges, teardown),
        cmocka_unit_test_teardown(test_no_boot_leaves_the_node_silent_after_its_next_reset, teardown),
        cmocka_unit_test_teardown(test_a_wrong_identity_is_answered_until_reset, teardown),
        cmocka_unit_test_teardown(test_bus_off_carries_nothing_for_its_time_then_each_node_says_so, teardown),
        cmocka_unit_test_teardown(test_the_control_socket_takes_datagrams, teardown),
        cmocka_unit_test_teardown(test_open_refuses_a_bad_configuration, teardown),
        cmocka_unit_test_teardown(test_sync_cycles_and_sdo_do_not_allocate, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
