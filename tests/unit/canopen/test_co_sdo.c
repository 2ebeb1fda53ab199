/* Black-box tests of the SDO client (ls_co_sdo.h): every frame the client
 * must send, and every server frame fed to it, is built here from the CiA
 * 301 constants of ls_canopen.h. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "co_test_bus.h"
#include "ls_co_sdo.h"

#define NODE 0x23u
#define REQ (LS_CO_COB_SDO_RX + NODE)
#define RSP (LS_CO_COB_SDO_TX + NODE)
#define TIMEOUT_US 500000u

static bus_t bus;
static ls_co_sdo_t sdo;
static uint64_t now_us;

static int setup(void **state)
{
    (void)state;
    bus_reset(&bus);
    now_us = 1000;
    assert_int_equal(ls_co_sdo_init(&sdo, NODE, 0, bus_send, &bus), LS_OK);
    return 0;
}

static void feed(hal_can_frame_t f)
{
    ls_co_sdo_on_frame(&sdo, &f, now_us);
}

static void expect_frame(hal_can_frame_t want)
{
    const hal_can_frame_t *got = bus_take(&bus);
    assert_non_null(got);
    assert_int_equal(got->id, want.id);
    assert_int_equal(got->len, want.len);
    assert_memory_equal(got->data, want.data, want.len);
}

static void expect_abort(uint16_t index, uint8_t sub, uint32_t code)
{
    uint8_t c[4];
    le32(c, code);
    expect_frame(sdo_mux(REQ, LS_CO_SDO_CS_ABORT, index, sub, c));
}

static void fill(uint8_t *p, size_t n, uint8_t seed)
{
    for (size_t i = 0; i < n; i++) {
        p[i] = (uint8_t)(seed + 7u * i);
    }
}

/* ---- expedited -------------------------------------------------------- */

static void test_an_expedited_download_of_1_2_or_4_bytes_is_one_initiate_frame(void **state)
{
    (void)state;
    const size_t lens[] = { 1, 2, 4 };
    for (size_t k = 0; k < 3; k++) {
        size_t len = lens[k];
        uint8_t data[4] = { 0, 0, 0, 0 };
        fill(data, len, (uint8_t)(0x40u + k));
        assert_int_equal(ls_co_sdo_write(&sdo, 0x6040, 0, data, len, now_us), LS_OK);
        assert_int_equal(ls_co_sdo_status(&sdo), LS_EBUSY);
        uint8_t cmd =
            (uint8_t)(LS_CO_SDO_CCS_DOWNLOAD_INITIATE | ((LS_CO_SDO_EXP_DATA - len) << LS_CO_SDO_EXP_N_SHIFT) |
                      LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE);
        expect_frame(sdo_mux(REQ, cmd, 0x6040, 0, data));
        feed(sdo_mux(RSP, LS_CO_SDO_SCS_DOWNLOAD_INITIATE, 0x6040, 0, NULL));
        assert_int_equal(ls_co_sdo_status(&sdo), LS_OK);
        assert_false(ls_co_sdo_busy(&sdo));
        assert_string_equal(ls_co_sdo_text(&sdo), "");
        assert_int_equal(bus_pending(&bus), 0);
    }
}

static void test_an_expedited_upload_returns_the_bytes_its_size_indicates(void **state)
{
    (void)state;
    const size_t lens[] = { 1, 2, 4 };
    for (size_t k = 0; k < 3; k++) {
        size_t len = lens[k];
        assert_int_equal(ls_co_sdo_read(&sdo, 0x1018, 1, now_us), LS_OK);
        expect_frame(sdo_mux(REQ, LS_CO_SDO_CCS_UPLOAD_INITIATE, 0x1018, 1, NULL));
        uint8_t d4[4] = { 0xA1, 0xB2, 0xC3, 0xD4 };
        uint8_t cmd = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_INITIATE | ((LS_CO_SDO_EXP_DATA - len) << LS_CO_SDO_EXP_N_SHIFT) |
                                LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE);
        feed(sdo_mux(RSP, cmd, 0x1018, 1, d4));
        assert_int_equal(ls_co_sdo_status(&sdo), LS_OK);
        size_t got = 0;
        const uint8_t *data = ls_co_sdo_data(&sdo, &got);
        assert_int_equal(got, len);
        assert_memory_equal(data, d4, len);
        uint32_t want = 0;
        for (size_t i = 0; i < len; i++) {
            want |= (uint32_t)d4[i] << (8u * i);
        }
        assert_int_equal(ls_co_sdo_value(&sdo, NULL), want);
    }
}

static void test_an_expedited_upload_without_a_size_yields_four_bytes(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1000, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t d4[4] = { 0x92, 0x01, 0x02, 0x00 };
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_EXPEDITED, 0x1000, 0, d4));
    size_t len = 0;
    assert_int_equal(ls_co_sdo_status(&sdo), LS_OK);
    assert_int_equal(ls_co_sdo_value(&sdo, &len), 0x00020192u);
    assert_int_equal(len, 4);
}

/* ---- segmented -------------------------------------------------------- */

/* A whole segmented download of `len` bytes, every frame checked. */
static void run_segmented_download(size_t len)
{
    uint8_t data[LS_CO_SDO_BUF_LEN];
    fill(data, len, (uint8_t)len);
    assert_int_equal(ls_co_sdo_write(&sdo, 0x1600, 1, data, len, now_us), LS_OK);
    uint8_t size[4];
    le32(size, (uint32_t)len);
    expect_frame(sdo_mux(REQ, LS_CO_SDO_CCS_DOWNLOAD_INITIATE | LS_CO_SDO_SIZE, 0x1600, 1, size));
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_DOWNLOAD_INITIATE, 0x1600, 1, NULL));
    size_t off = 0;
    uint8_t toggle = 0;
    while (off < len) {
        size_t n = len - off < LS_CO_SDO_SEG_DATA ? len - off : LS_CO_SDO_SEG_DATA;
        bool last = off + n == len;
        uint8_t cmd = (uint8_t)(LS_CO_SDO_CCS_DOWNLOAD_SEGMENT | toggle |
                                ((LS_CO_SDO_SEG_DATA - n) << LS_CO_SDO_SEG_N_SHIFT) | (last ? LS_CO_SDO_LAST : 0u));
        expect_frame(sdo_seg(REQ, cmd, &data[off], n));
        assert_int_equal(ls_co_sdo_status(&sdo), LS_EBUSY);
        feed(sdo_seg(RSP, (uint8_t)(LS_CO_SDO_SCS_DOWNLOAD_SEGMENT | toggle), NULL, 0));
        off += n;
        toggle ^= LS_CO_SDO_TOGGLE;
    }
    assert_int_equal(ls_co_sdo_status(&sdo), LS_OK);
    assert_int_equal(bus_pending(&bus), 0);
}

static void test_a_segmented_download_alternates_the_toggle_and_marks_the_last_segment(void **state)
{
    (void)state;
    const size_t lens[] = { 5, 7, 9, 13, 14, 15, 23, LS_CO_SDO_BUF_LEN };
    for (size_t k = 0; k < sizeof(lens) / sizeof(lens[0]); k++) {
        run_segmented_download(lens[k]);
    }
}

/* A whole segmented upload of `len` bytes, the size indicated or not. */
static void run_segmented_upload(size_t len, bool sized)
{
    uint8_t data[LS_CO_SDO_BUF_LEN];
    fill(data, len, (uint8_t)(len + 3u));
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1008, 0, now_us), LS_OK);
    expect_frame(sdo_mux(REQ, LS_CO_SDO_CCS_UPLOAD_INITIATE, 0x1008, 0, NULL));
    uint8_t size[4];
    le32(size, sized ? (uint32_t)len : 0u);
    feed(sdo_mux(RSP, (uint8_t)(LS_CO_SDO_SCS_UPLOAD_INITIATE | (sized ? LS_CO_SDO_SIZE : 0u)), 0x1008, 0, size));
    size_t off = 0;
    uint8_t toggle = 0;
    while (off < len) {
        expect_frame(sdo_seg(REQ, (uint8_t)(LS_CO_SDO_CCS_UPLOAD_SEGMENT | toggle), NULL, 0));
        size_t n = len - off < LS_CO_SDO_SEG_DATA ? len - off : LS_CO_SDO_SEG_DATA;
        bool last = off + n == len;
        uint8_t cmd = (uint8_t)(LS_CO_SDO_SCS_UPLOAD_SEGMENT | toggle |
                                ((LS_CO_SDO_SEG_DATA - n) << LS_CO_SDO_SEG_N_SHIFT) | (last ? LS_CO_SDO_LAST : 0u));
        feed(sdo_seg(RSP, cmd, &data[off], n));
        off += n;
        toggle ^= LS_CO_SDO_TOGGLE;
    }
    assert_int_equal(ls_co_sdo_status(&sdo), LS_OK);
    size_t got = 0;
    const uint8_t *kept = ls_co_sdo_data(&sdo, &got);
    assert_int_equal(got, len);
    assert_memory_equal(kept, data, len);
    assert_int_equal(bus_pending(&bus), 0);
}

static void test_a_segmented_upload_collects_odd_lengths_exactly_7_and_14(void **state)
{
    (void)state;
    const size_t lens[] = { 5, 7, 9, 13, 14, 15, 23, LS_CO_SDO_BUF_LEN };
    for (size_t k = 0; k < sizeof(lens) / sizeof(lens[0]); k++) {
        run_segmented_upload(lens[k], true);
        run_segmented_upload(lens[k], false);
    }
}

static void test_an_upload_longer_than_the_buffer_is_truncated_with_an_error(void **state)
{
    (void)state;
    const size_t len = 100;
    uint8_t data[100];
    fill(data, len, 1);
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1008, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t size[4];
    le32(size, (uint32_t)len);
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_SIZE, 0x1008, 0, size));
    size_t off = 0;
    uint8_t toggle = 0;
    while (ls_co_sdo_status(&sdo) == LS_EBUSY) {
        const hal_can_frame_t *req = bus_take(&bus);
        assert_non_null(req);
        assert_int_equal(req->data[0], LS_CO_SDO_CCS_UPLOAD_SEGMENT | toggle);
        feed(sdo_seg(RSP, (uint8_t)(LS_CO_SDO_SCS_UPLOAD_SEGMENT | toggle), &data[off], LS_CO_SDO_SEG_DATA));
        off += LS_CO_SDO_SEG_DATA;
        toggle ^= LS_CO_SDO_TOGGLE;
    }
    assert_int_equal(ls_co_sdo_status(&sdo), LS_ELEN);
    expect_abort(0x1008, 0, LS_CO_ABORT_NO_MEMORY);
    size_t got = 0;
    const uint8_t *kept = ls_co_sdo_data(&sdo, &got);
    assert_int_equal(got, LS_CO_SDO_BUF_LEN);
    assert_memory_equal(kept, data, LS_CO_SDO_BUF_LEN);
    assert_non_null(strstr(ls_co_sdo_text(&sdo), "node 0x23: SDO read 0x1008:00 is longer than 64 bytes"));
}

static void test_an_upload_shorter_than_its_indicated_size_is_a_protocol_error(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1008, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t size[4];
    le32(size, 10);
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_SIZE, 0x1008, 0, size));
    (void)bus_take(&bus);
    uint8_t d[7] = { 1, 2, 3, 4, 5, 6, 7 };
    feed(sdo_seg(RSP, LS_CO_SDO_SCS_UPLOAD_SEGMENT, d, 7));
    (void)bus_take(&bus);
    feed(sdo_seg(
        RSP,
        (uint8_t)(LS_CO_SDO_SCS_UPLOAD_SEGMENT | LS_CO_SDO_TOGGLE | (5u << LS_CO_SDO_SEG_N_SHIFT) | LS_CO_SDO_LAST), d,
        2));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    expect_abort(0x1008, 0, LS_CO_ABORT_TYPE_LEN);
    assert_string_equal(ls_co_sdo_text(&sdo),
                        "node 0x23: SDO read 0x1008:00 sent 9 bytes, 10 indicated (abort 0x06070010 sent)");
}

/* ---- failures --------------------------------------------------------- */

static void test_a_segment_whose_toggle_did_not_alternate_aborts_the_upload(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1008, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE, 0x1008, 0, NULL));
    (void)bus_take(&bus);
    uint8_t d[7] = { 'a', 'b', 'c', 'd', 'e', 'f', 'g' };
    feed(sdo_seg(RSP, LS_CO_SDO_SCS_UPLOAD_SEGMENT, d, 7)); /* toggle 0: right */
    expect_frame(sdo_seg(REQ, LS_CO_SDO_CCS_UPLOAD_SEGMENT | LS_CO_SDO_TOGGLE, NULL, 0));
    feed(sdo_seg(RSP, LS_CO_SDO_SCS_UPLOAD_SEGMENT, d, 7)); /* toggle 0 again: wrong */
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    assert_int_equal(ls_co_sdo_abort_code(&sdo), LS_CO_ABORT_TOGGLE);
    expect_abort(0x1008, 0, LS_CO_ABORT_TOGGLE);
    assert_string_equal(ls_co_sdo_text(&sdo), "node 0x23: SDO read 0x1008:00 got a segment whose toggle bit did not "
                                              "alternate (abort 0x05030000 sent)");
}

static void test_a_download_segment_response_with_the_wrong_toggle_aborts(void **state)
{
    (void)state;
    uint8_t data[10];
    fill(data, sizeof(data), 9);
    assert_int_equal(ls_co_sdo_write(&sdo, 0x2000, 3, data, sizeof(data), now_us), LS_OK);
    (void)bus_take(&bus);
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_DOWNLOAD_INITIATE, 0x2000, 3, NULL));
    (void)bus_take(&bus);
    feed(sdo_seg(RSP, LS_CO_SDO_SCS_DOWNLOAD_SEGMENT | LS_CO_SDO_TOGGLE, NULL, 0));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    expect_abort(0x2000, 3, LS_CO_ABORT_TOGGLE);
    assert_int_equal(bus_pending(&bus), 0);
}

static void test_an_abort_from_the_server_is_kept_and_named(void **state)
{
    (void)state;
    uint8_t v[4];
    le32(v, LS_CO_PDO_MAP_ENTRY(0x6041, 0, 16));
    assert_int_equal(ls_co_sdo_write(&sdo, 0x1600, 1, v, 4, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t code[4];
    le32(code, LS_CO_ABORT_NO_MAP);
    feed(sdo_mux(RSP, LS_CO_SDO_CS_ABORT, 0x1600, 1, code));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EABORTED);
    assert_int_equal(ls_co_sdo_abort_code(&sdo), LS_CO_ABORT_NO_MAP);
    assert_string_equal(ls_co_sdo_text(&sdo),
                        "node 0x23: SDO write 0x1600:01 aborted 0x06040041 (object cannot be mapped to the PDO)");
    assert_int_equal(bus_pending(&bus), 0); /* an abort is not answered */
    assert_int_equal(sdo.counters.aborts_received, 1);
}

static void test_a_time_out_sends_abort_0x05040000(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x6064, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    ls_co_sdo_poll(&sdo, now_us + TIMEOUT_US - 1u);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EBUSY);
    assert_int_equal(bus_pending(&bus), 0);
    ls_co_sdo_poll(&sdo, now_us + TIMEOUT_US);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_ETIMEDOUT);
    expect_abort(0x6064, 0, LS_CO_ABORT_TIMEOUT);
    assert_string_equal(ls_co_sdo_text(&sdo),
                        "node 0x23: SDO read 0x6064:00 got no answer within 500 ms (abort 0x05040000 sent)");
    assert_int_equal(sdo.counters.timeouts, 1);
    assert_int_equal(sdo.counters.aborts_sent, 1);
}

static void test_each_segment_restarts_the_time_out(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1008, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    now_us += TIMEOUT_US - 1u;
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE, 0x1008, 0, NULL));
    now_us += TIMEOUT_US - 1u;
    ls_co_sdo_poll(&sdo, now_us);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EBUSY);
    now_us += 1u;
    ls_co_sdo_poll(&sdo, now_us);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_ETIMEDOUT);
}

static void test_a_refused_request_is_sent_at_the_next_poll(void **state)
{
    (void)state;
    bus.refuse = 1;
    uint8_t v = 5;
    assert_int_equal(ls_co_sdo_write(&sdo, 0x6060, 0, &v, 1, now_us), LS_OK);
    assert_int_equal(bus_pending(&bus), 0);
    assert_true(ls_co_sdo_busy(&sdo));
    ls_co_sdo_poll(&sdo, now_us + 1000u);
    const hal_can_frame_t *f = bus_take(&bus);
    assert_non_null(f);
    assert_int_equal(f->id, REQ);
    ls_co_sdo_poll(&sdo, now_us + 2000u);
    assert_int_equal(bus_pending(&bus), 0); /* sent once */
}

static void test_a_request_that_never_left_times_out_without_an_abort(void **state)
{
    (void)state;
    bus.refuse_all = true;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1000, 0, now_us), LS_OK);
    ls_co_sdo_poll(&sdo, now_us + TIMEOUT_US);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_ETIMEDOUT);
    assert_false(ls_co_sdo_busy(&sdo));
    bus.refuse_all = false;
    ls_co_sdo_poll(&sdo, now_us + TIMEOUT_US + 1000u);
    assert_int_equal(bus.n, 0);
    assert_non_null(strstr(ls_co_sdo_text(&sdo), "never left"));
}

static void test_an_abort_refused_by_the_queue_goes_out_later_and_blocks_a_new_transfer(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1000, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    bus.refuse_all = true;
    ls_co_sdo_poll(&sdo, now_us + TIMEOUT_US);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_ETIMEDOUT);
    assert_true(ls_co_sdo_busy(&sdo));
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1000, 0, now_us), LS_EBUSY);
    bus.refuse_all = false;
    ls_co_sdo_poll(&sdo, now_us + TIMEOUT_US + 1000u);
    expect_abort(0x1000, 0, LS_CO_ABORT_TIMEOUT);
    assert_false(ls_co_sdo_busy(&sdo));
}

static void test_a_stray_response_while_idle_is_counted_and_not_answered(void **state)
{
    (void)state;
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_DOWNLOAD_INITIATE, 0x6040, 0, NULL));
    assert_int_equal(sdo.counters.stray, 1);
    assert_int_equal(bus.n, 0);
    assert_int_equal(ls_co_sdo_status(&sdo), LS_OK);
}

static void test_a_short_response_is_a_protocol_error(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1000, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t b[4] = { LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_EXPEDITED, 0x00, 0x10, 0x00 };
    feed(can_frame(RSP, 4, b));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    expect_abort(0x1000, 0, LS_CO_ABORT_CS);
    assert_string_equal(ls_co_sdo_text(&sdo), "node 0x23: SDO read 0x1000:00 got a frame of 4 bytes (SDO frames have "
                                              "8) (abort 0x05040001 sent)");
}

static void test_a_response_of_another_kind_aborts_with_command_specifier_unknown(void **state)
{
    (void)state;
    uint8_t v = 1;
    assert_int_equal(ls_co_sdo_write(&sdo, 0x6060, 0, &v, 1, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t d4[4] = { 8, 0, 0, 0 };
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_EXPEDITED, 0x6060, 0, d4));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    assert_int_equal(ls_co_sdo_abort_code(&sdo), LS_CO_ABORT_CS);
    expect_abort(0x6060, 0, LS_CO_ABORT_CS);
    /* and an undefined command specifier (7) */
    assert_int_equal(ls_co_sdo_read(&sdo, 0x6061, 0, now_us), LS_OK);
    (void)bus_take(&bus);
    feed(sdo_mux(RSP, 0xE0u, 0x6061, 0, NULL));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    expect_abort(0x6061, 0, LS_CO_ABORT_CS);
}

static void test_an_initiate_response_for_another_object_aborts(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1018, 1, now_us), LS_OK);
    (void)bus_take(&bus);
    uint8_t d4[4] = { 1, 0, 0, 0 };
    feed(sdo_mux(RSP, LS_CO_SDO_SCS_UPLOAD_INITIATE | LS_CO_SDO_EXPEDITED | LS_CO_SDO_SIZE, 0x1018, 2, d4));
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EPROTO);
    expect_abort(0x1018, 1, LS_CO_ABORT_CS);
}

static void test_cancel_ends_a_transfer_without_a_frame(void **state)
{
    (void)state;
    assert_int_equal(ls_co_sdo_read(&sdo, 0x1018, 1, now_us), LS_OK);
    (void)bus_take(&bus);
    ls_co_sdo_cancel(&sdo, "cancelled: the node reset");
    assert_int_equal(ls_co_sdo_status(&sdo), LS_EIO);
    assert_false(ls_co_sdo_busy(&sdo));
    assert_string_equal(ls_co_sdo_text(&sdo), "node 0x23: SDO read 0x1018:01 cancelled: the node reset");
    assert_int_equal(bus_pending(&bus), 0);
}

static void test_bad_arguments_and_a_second_transfer_are_refused(void **state)
{
    (void)state;
    ls_co_sdo_t other;
    memset(&other, 0x5A, sizeof(other));
    assert_int_equal(ls_co_sdo_init(&other, 0, 0, bus_send, &bus), LS_EINVAL);
    assert_int_equal(ls_co_sdo_init(&other, 128, 0, bus_send, &bus), LS_EINVAL);
    assert_int_equal(ls_co_sdo_init(&other, 1, 0, NULL, &bus), LS_EINVAL);
    assert_int_equal(other.node_id, 0x5A); /* untouched */
    assert_int_equal(ls_co_sdo_init(NULL, 1, 0, bus_send, &bus), LS_EINVAL);

    uint8_t big[LS_CO_SDO_BUF_LEN + 1u];
    memset(big, 0, sizeof(big));
    assert_int_equal(ls_co_sdo_write(&sdo, 0x2000, 0, big, 0, now_us), LS_ELEN);
    assert_int_equal(ls_co_sdo_write(&sdo, 0x2000, 0, big, sizeof(big), now_us), LS_ELEN);
    assert_int_equal(ls_co_sdo_write(&sdo, 0x2000, 0, NULL, 1, now_us), LS_EINVAL);
    assert_int_equal(bus.n, 0);
    assert_int_equal(ls_co_sdo_read(&sdo, 0x2000, 0, now_us), LS_OK);
    assert_int_equal(ls_co_sdo_read(&sdo, 0x2001, 0, now_us), LS_EBUSY);
    assert_int_equal(ls_co_sdo_write(&sdo, 0x2001, 0, big, 1, now_us), LS_EBUSY);
    assert_int_equal(bus.n, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_an_expedited_download_of_1_2_or_4_bytes_is_one_initiate_frame, setup),
        cmocka_unit_test_setup(test_an_expedited_upload_returns_the_bytes_its_size_indicates, setup),
        cmocka_unit_test_setup(test_an_expedited_upload_without_a_size_yields_four_bytes, setup),
        cmocka_unit_test_setup(test_a_segmented_download_alternates_the_toggle_and_marks_the_last_segment, setup),
        cmocka_unit_test_setup(test_a_segmented_upload_collects_odd_lengths_exactly_7_and_14, setup),
        cmocka_unit_test_setup(test_an_upload_longer_than_the_buffer_is_truncated_with_an_error, setup),
        cmocka_unit_test_setup(test_an_upload_shorter_than_its_indicated_size_is_a_protocol_error, setup),
        cmocka_unit_test_setup(test_a_segment_whose_toggle_did_not_alternate_aborts_the_upload, setup),
        cmocka_unit_test_setup(test_a_download_segment_response_with_the_wrong_toggle_aborts, setup),
        cmocka_unit_test_setup(test_an_abort_from_the_server_is_kept_and_named, setup),
        cmocka_unit_test_setup(test_a_time_out_sends_abort_0x05040000, setup),
        cmocka_unit_test_setup(test_each_segment_restarts_the_time_out, setup),
        cmocka_unit_test_setup(test_a_refused_request_is_sent_at_the_next_poll, setup),
        cmocka_unit_test_setup(test_a_request_that_never_left_times_out_without_an_abort, setup),
        cmocka_unit_test_setup(test_an_abort_refused_by_the_queue_goes_out_later_and_blocks_a_new_transfer, setup),
        cmocka_unit_test_setup(test_a_stray_response_while_idle_is_counted_and_not_answered, setup),
        cmocka_unit_test_setup(test_a_short_response_is_a_protocol_error, setup),
        cmocka_unit_test_setup(test_a_response_of_another_kind_aborts_with_command_specifier_unknown, setup),
        cmocka_unit_test_setup(test_an_initiate_response_for_another_object_aborts, setup),
        cmocka_unit_test_setup(test_cancel_ends_a_transfer_without_a_frame, setup),
        cmocka_unit_test_setup(test_bad_arguments_and_a_second_transfer_are_refused, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
