/* The SLCAN serial adapter link: a pseudo-terminal plays the adapter (its
 * master side is the adapter's end of the serial line), and then the
 * simulated adapter of hal/sim (slcan_pty, what ls-simdrives offers). */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "hal_linux_slcan_tty.h"
#include "slcan_pty.h"
#include "test_linux.h"

/* An adapter's end: a pty master; returns its fd and the slave's path. */
static int adapter(char *path, size_t cap)
{
    const int m = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    assert_true(m >= 0);
    assert_int_equal(grantpt(m), 0);
    assert_int_equal(unlockpt(m), 0);
    assert_int_equal(ptsname_r(m, path, cap), 0);
    return m;
}

/* Read what the link wrote, waiting up to 1 s for `want` bytes. */
static size_t read_some(int fd, char *buf, size_t cap, size_t want)
{
    size_t n = 0;
    for (int i = 0; i < 100 && n < want; i++) {
        struct pollfd p = { .fd = fd, .events = POLLIN, .revents = 0 };
        if (poll(&p, 1, 10) > 0) {
            const ssize_t r = read(fd, buf + n, cap - 1u - n);
            if (r > 0) {
                n += (size_t)r;
            }
        }
    }
    buf[n] = '\0';
    return n;
}

static int recv_wait(hal_can_link_t *l, hal_can_frame_t *f)
{
    for (int i = 0; i < 100; i++) {
        const int r = hal_can_recv(l, f);
        if (r != LS_EAGAIN) {
            return r;
        }
        usleep(10000);
    }
    return LS_EAGAIN;
}

static void test_opening_the_channel_sets_the_bitrate_and_frames_cross_both_ways(void **state)
{
    (void)state;
    char path[128], msg[256], buf[256];
    const int m = adapter(path, sizeof path);
    hal_can_link_t l;
    assert_int_equal(hal_linux_slcan_tty_open(&l, path, 500000u, msg, sizeof msg), LS_OK);
    assert_non_null(strstr(l.name, "slcan:tty:"));
    assert_int_equal(read_some(m, buf, sizeof buf, 7), 7u);
    assert_string_equal(buf, "C\rS6\rO\r");

    /* host -> adapter: an 11-bit and a 29-bit frame as lines */
    hal_can_frame_t f = { .id = 0x623, .flags = 0, .len = 8, .data = { 0x40, 0x41, 0x60, 0, 1, 2, 3, 4 } };
    assert_int_equal(hal_can_send(&l, &f), LS_OK);
    hal_can_frame_t g = { .id = 0x18DA10F1, .flags = HAL_CAN_F_EXT, .len = 2, .data = { 0xAB, 0xCD } };
    assert_int_equal(hal_can_send(&l, &g), LS_OK);
    assert_int_equal(read_some(m, buf, sizeof buf, 37), 37u);
    assert_string_equal(buf, "t62384041600001020304\rT18DA10F12ABCD\r");

    /* adapter -> host: acknowledgements are dropped, frames returned in order */
    const char in[] = "\r\az\rt1A3600010203ABCD\rZ\rt0800\rgarbage\rt7231\x05\r";
    assert_int_equal(write(m, in, sizeof in - 1u), (ssize_t)(sizeof in - 1u));
    hal_can_frame_t r;
    assert_int_equal(recv_wait(&l, &r), 1);
    assert_int_equal(r.id, 0x1A3);
    assert_int_equal(r.len, 6);
    assert_int_equal(r.data[5], 0xCD);
    assert_int_equal(recv_wait(&l, &r), 1);
    assert_int_equal(r.id, 0x080);
    assert_int_equal(r.len, 0);
    assert_int_equal(hal_can_recv(&l, &r), LS_EAGAIN); /* "garbage" is counted, then an incomplete line */
    hal_can_status_t st;
    assert_int_equal(hal_can_status(&l, &st), LS_OK);
    assert_int_equal(st.rx_frames, 2u);
    assert_int_equal(st.rx_dropped, 2u); /* "garbage" and the frame with a non-hex byte */
    assert_int_equal(st.tx_frames, 2u);

    hal_can_close(&l);
    assert_int_equal(read_some(m, buf, sizeof buf, 2), 2u);
    assert_string_equal(buf, "C\r");
    close(m);
}

static void test_a_device_that_takes_nothing_keeps_whole_lines_and_refuses_when_full(void **state)
{
    (void)state;
    char path[128], msg[256], buf[8192];
    const int m = adapter(path, sizeof path);
    hal_can_link_t l;
    assert_int_equal(hal_linux_slcan_tty_open(&l, path, 1000000u, msg, sizeof msg), LS_OK);
    hal_can_frame_t f = { .id = 0x201, .len = 8, .data = { 1, 2, 3, 4, 5, 6, 7, 8 } };
    int sent = 0, refused = 0;
    for (int i = 0; i < 20000 && refused == 0; i++) {
        const int r = hal_can_send(&l, &f);
        if (r == LS_OK) {
            sent++;
        } else {
            assert_int_equal(r, LS_EAGAIN);
            refused++;
        }
    }
    assert_int_equal(refused, 1); /* the pty and the link's buffer filled: the caller keeps the frame */
    assert_true(hal_can_tx_pending(&l));
    /* drained, everything sent arrives whole: every line is "t2018" + 16 hex + CR */
    size_t total = 0;
    for (int i = 0; i < 400 && total < (size_t)sent * 22u + 7u; i++) {
        hal_can_frame_t r;
        (void)hal_can_recv(&l, &r); /* flushes the waiting lines */
        total += read_some(m, buf, sizeof buf, 1);
        assert_null(strchr(buf, '\a'));
    }
    assert_int_equal(total, (size_t)sent * 22u + 7u);
    assert_false(hal_can_tx_pending(&l));
    hal_can_close(&l);
    close(m);
}

static void test_bad_arguments_and_missing_devices_are_named(void **state)
{
    (void)state;
    char msg[256];
    hal_can_link_t l;
    assert_int_equal(hal_linux_slcan_tty_open(&l, "/dev/no-such-adapter", 1000000u, msg, sizeof msg), LS_ENODEV);
    assert_non_null(strstr(msg, "/dev/no-such-adapter: no such device"));
    assert_null(l.ops);
    assert_int_equal(hal_linux_slcan_tty_open(&l, "/dev/null", 333333u, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "no SLCAN index"));
    assert_int_equal(hal_linux_slcan_tty_open(&l, "", 1000000u, msg, sizeof msg), LS_EINVAL);
    assert_int_equal(hal_linux_slcan_bitrate_index(125000u), '4');
    assert_int_equal(hal_linux_slcan_bitrate_index(1000000u), '8');
    assert_int_equal(hal_linux_slcan_bitrate_index(0u), 0);
}

/* The two ends this project has meet: hal/sim's simulated adapter (the
 * pty ls-simdrives offers) and this host link. */
static void test_it_talks_to_the_simulated_adapter(void **state)
{
    (void)state;
    char msg[256], path[128];
    (void)snprintf(path, sizeof path, "/tmp/ls-slcan-tty-test-%d", (int)getpid());
    hal_can_link_t dev, host;
    assert_int_equal(hal_sim_slcan_pty_open(&dev, path, msg, sizeof msg), LS_OK);
    assert_int_equal(hal_linux_slcan_tty_open(&host, path, 1000000u, msg, sizeof msg), LS_OK);
    hal_can_frame_t f = { .id = 0x605, .len = 8, .data = { 0x40, 0x18, 0x10, 0x01 } };
    assert_int_equal(hal_can_send(&host, &f), LS_OK);
    hal_can_frame_t r;
    assert_int_equal(recv_wait(&dev, &r), 1); /* the adapter opened the channel ('O') first */
    assert_int_equal(r.id, 0x605);
    assert_int_equal(r.data[3], 0x01);
    hal_can_frame_t a = { .id = 0x585, .len = 8, .data = { 0x43, 0x18, 0x10, 0x01, 0xFB } };
    assert_int_equal(hal_can_send(&dev, &a), LS_OK);
    assert_int_equal(recv_wait(&host, &r), 1);
    assert_int_equal(r.id, 0x585);
    assert_int_equal(r.data[4], 0xFB);
    hal_can_close(&host);
    hal_can_close(&dev);
}

int run_slcan_tty_tests(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_opening_the_channel_sets_the_bitrate_and_frames_cross_both_ways),
        cmocka_unit_test(test_a_device_that_takes_nothing_keeps_whole_lines_and_refuses_when_full),
        cmocka_unit_test(test_bad_arguments_and_missing_devices_are_named),
        cmocka_unit_test(test_it_talks_to_the_simulated_adapter),
    };
    return cmocka_run_group_tests_name("slcan_tty", tests, NULL, NULL);
}
