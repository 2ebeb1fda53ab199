/* ls_check_run: the self-check's lines and exit code. The CAN and GPIO
 * expectations follow what this kernel offers (probed here independently):
 * the host has neither, the VM tier has both. */
#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "ls_check.h"
#include "ls_config.h"
#include "test_config.h"

typedef struct {
    ls_config_t cfg;
    char *buf;
    size_t len;
    FILE *out;
    char dir[64];
    char line[512];
} cx_t;

static int setup(void **state)
{
    cx_t *c = calloc(1, sizeof *c);
    ls_config_defaults(&c->cfg);
    c->cfg.rt_priority = 0;
    c->cfg.lock_memory = false;
    snprintf(c->dir, sizeof c->dir, "/tmp/ls_check_XXXXXX");
    assert_non_null(mkdtemp(c->dir));
    c->out = open_memstream(&c->buf, &c->len);
    *state = c;
    return 0;
}

static int teardown(void **state)
{
    cx_t *c = *state;
    if (c->out != NULL) {
        fclose(c->out);
    }
    free(c->buf);
    rmdir(c->dir);
    free(c);
    return 0;
}

static int run(cx_t *c)
{
    int rc = ls_check_run(&c->cfg, c->out);
    fflush(c->out);
    return rc;
}

/* The line "LEVEL  what...", or fail. */
/* A fresh report for the next run. */
static void clear(cx_t *c)
{
    fclose(c->out);
    free(c->buf);
    c->buf = NULL;
    c->out = open_memstream(&c->buf, &c->len);
}

static const char *line_of(cx_t *c, const char *what)
{
    size_t wl = strlen(what);
    for (const char *p = c->buf; p != NULL && *p != '\0';) {
        size_t n = strcspn(p, "\n");
        if (n > 6 && strncmp(p + 4, "  ", 2) == 0 && strncmp(p + 6, what, wl) == 0) {
            assert_true(n < sizeof c->line);
            memcpy(c->line, p, n);
            c->line[n] = '\0';
            return c->line;
        }
        p = p[n] == '\n' ? p + n + 1 : NULL;
    }
    fail_msg("no line for '%s' in:\n%s", what, c->buf);
    return NULL;
}

static void assert_starts(const char *s, const char *prefix)
{
    if (strncmp(s, prefix, strlen(prefix)) != 0) {
        fail_msg("'%s' does not start with '%s'", s, prefix);
    }
}

static void assert_contains(const char *s, const char *part)
{
    if (strstr(s, part) == NULL) {
        fail_msg("'%s' does not contain '%s'", s, part);
    }
}

static bool kernel_has_afcan(void)
{
    int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd >= 0) {
        close(fd);
        return true;
    }
    return false;
}

static void add_link(cx_t *c, const char *spec)
{
    size_t n = strlen(spec);
    assert_true(n < sizeof c->cfg.links[0]);
    memcpy(c->cfg.links[c->cfg.n_links++], spec, n + 1);
}

/* The deployment case of docs/deploy.md: socketcan:can0 and gpiod:gpiochip0. */
static void test_socketcan_and_gpiod_on_this_machine(void **state)
{
    cx_t *c = *state;
    add_link(c, "socketcan:can0");
    snprintf(c->cfg.dio, sizeof c->cfg.dio, "gpiod:gpiochip0");
    c->cfg.n_inputs = 2;
    c->cfg.input_offsets[0] = 0;
    c->cfg.input_offsets[1] = 1;
    int rc = run(c);
    bool afcan = kernel_has_afcan();
    bool chip = access("/dev/gpiochip0", F_OK) == 0;
    if (!afcan) {
        assert_string_equal(line_of(c, "AF_CAN"),
                            "FAIL  AF_CAN: socket(AF_CAN, SOCK_RAW, CAN_RAW): Address family not supported by "
                            "protocol: the kernel has no CAN sockets; fix: modprobe can can-raw (a kernel with "
                            "CONFIG_CAN and CONFIG_CAN_RAW)");
        assert_starts(line_of(c, "link socketcan:can0"), "FAIL  link socketcan:can0: this kernel has no AF_CAN");
    } else {
        assert_string_equal(line_of(c, "AF_CAN"), "PASS  AF_CAN: the kernel opens CAN_RAW sockets");
    }
    if (!chip) {
        assert_string_equal(line_of(c, "gpio chip gpiochip0"),
                            "FAIL  gpio chip gpiochip0: no GPIO chip 'gpiochip0' (ls /dev/gpiochip*; this kernel "
                            "may lack CONFIG_GPIOLIB)");
        assert_null(strstr(c->buf, "gpio lines"));
    } else {
        assert_starts(line_of(c, "gpio chip gpiochip0"), "PASS  gpio chip gpiochip0: gpiochip0 [");
    }
    assert_starts(line_of(c, "configuration"), "PASS  configuration: (command line only): node 0x10, 1 link(s), "
                                               "arm sim, dio gpiod:gpiochip0, clock realtime, 1000 Hz");
    if (!afcan || !chip) {
        assert_int_equal(rc, LS_EXIT_CHECK_FAILED);
        assert_contains(c->buf, "landscaped cannot run with this configuration: ");
    }
}

static void test_sim_configuration_passes(void **state)
{
    cx_t *c = *state;
    char link[128];
    snprintf(link, sizeof link, "slcan:pty:%s/ls0", c->dir);
    add_link(c, link);
    int rc = run(c);
    assert_int_equal(rc, LS_EXIT_OK);
    char want[256];
    snprintf(want, sizeof want, "PASS  link %s: pseudo-terminals available, %s writable", link, c->dir);
    assert_string_equal(line_of(c, "link slcan"), want);
    assert_string_equal(line_of(c, "dio"), "PASS  dio: sim backend, no GPIO chip needed");
    assert_string_equal(line_of(c, "robot model"),
                        "PASS  robot model: (compiled in): ls-sim6, spherical_wrist inverse kinematics");
    assert_string_equal(line_of(c, "real-time"),
                        "PASS  real-time: not requested (rt_priority = 0): the control loop is a normal thread");
    assert_string_equal(line_of(c, "memory locking"), "PASS  memory locking: not requested (lock_memory = false)");
    assert_string_equal(line_of(c, "manual teachpendant"),
                        "PASS  manual teachpendant: the simulated device (the control socket's jog and buttons); set "
                        "[manual] to use a real one");
    assert_starts(line_of(c, "manual spaceball"), "PASS  manual spaceball: the simulated device");
    if (!kernel_has_afcan()) {
        assert_starts(line_of(c, "AF_CAN"), "WARN  AF_CAN: ");
        assert_contains(c->line, "(not needed by this configuration: no socketcan link)");
        assert_contains(c->buf, "landscaped can run with this configuration: 0 FAIL, 1 WARN, 9 PASS\n");
    } else {
        assert_contains(c->buf, "landscaped can run with this configuration: 0 FAIL, 0 WARN, 10 PASS\n");
    }
}

/* A manual device not plugged in is a WARN (picked up later); a path that is
 * no input device a FAIL; with arm = none and no device, none. The VM tier
 * checks real devices (tests/vm/test_guest.py). */
static void test_manual_devices_are_listed_with_what_they_lack(void **state)
{
    cx_t *c = *state;
    char link[128];
    snprintf(link, sizeof link, "slcan:pty:%s/ls0", c->dir);
    add_link(c, link);
    snprintf(c->cfg.manual[LS_MANUAL_TEACHPENDANT].path, sizeof c->cfg.manual[0].path, "/nonexistent/by-id/pad");
    snprintf(c->cfg.manual[LS_MANUAL_SPACEBALL].path, sizeof c->cfg.manual[0].path, "/dev/null");
    assert_int_equal(run(c), LS_EXIT_CHECK_FAILED);
    assert_starts(line_of(c, "manual teachpendant"), "WARN  manual teachpendant: /nonexistent/by-id/pad: not there");
    assert_contains(c->line, "landscaped picks it up when it appears");
    assert_starts(line_of(c, "manual spaceball"), "FAIL  manual spaceball: /dev/null: not an input event device");
    fclose(c->out);
    free(c->buf);
    c->buf = NULL;
    c->out = open_memstream(&c->buf, &c->len);
    ls_config_defaults(&c->cfg);
    c->cfg.rt_priority = 0;
    c->cfg.lock_memory = false;
    add_link(c, link);
    snprintf(c->cfg.arm, sizeof c->cfg.arm, "none");
    snprintf(c->cfg.dio, sizeof c->cfg.dio, "none");
    (void)run(c);
    assert_string_equal(line_of(c, "manual spaceball"),
                        "PASS  manual spaceball: none configured: manualControl refuses it");
}

static void test_invalid_configuration_fails(void **state)
{
    cx_t *c = *state;
    /* refused as a whole: the code landscaped exits with when it starts with it
     * (docs/deploy.md section 5), not the one of a machine check */
    assert_int_equal(run(c), LS_EXIT_BAD_CONFIG);
    assert_string_equal(line_of(c, "configuration"),
                        "FAIL  configuration: (command line only): no link configured: give --link SPEC or "
                        "'link = SPEC' under [hal] (e.g. slcan:pty:/tmp/landscape0 or socketcan:can0)");
}

/* A model file that is refused is a refused configuration (exit 2), as
 * when landscaped starts with it, on the configuration's line that names
 * its source; so is one the simulator cannot build. */
static void test_a_refused_robot_model_is_a_bad_configuration(void **state)
{
    cx_t *c = *state;
    char link[128];
    snprintf(link, sizeof link, "slcan:pty:%s/ls0", c->dir);
    add_link(c, link);
    snprintf(c->cfg.model, sizeof c->cfg.model, "%s/no-such-arm.ini", c->dir);
    assert_int_equal(run(c), LS_EXIT_BAD_CONFIG);
    char want[512];
    snprintf(want, sizeof want,
             "FAIL  configuration: (command line only): %s/no-such-arm.ini: cannot read the robot model file: No "
             "such file or directory (name an existing file in [robot] model or --model)",
             c->dir);
    assert_string_equal(line_of(c, "configuration"), want);
    snprintf(c->cfg.model, sizeof c->cfg.model, "%s/puma560.ini", LS_ROBOTS_DIR);
    clear(c);
    assert_int_equal(run(c), LS_EXIT_BAD_CONFIG);
    assert_contains(line_of(c, "configuration"), "FAIL  configuration: (command line only): [hal] arm = sim cannot "
                                                 "simulate robot model puma560 (");
    snprintf(c->cfg.model, sizeof c->cfg.model, "%s/ur5e.ini", LS_ROBOTS_DIR);
    clear(c);
    assert_int_equal(run(c), LS_EXIT_OK);
    assert_contains(line_of(c, "robot model"), "/ur5e.ini: ur5e, offset_wrist inverse kinematics");
}

static void test_unwritable_pty_directory_fails(void **state)
{
    cx_t *c = *state;
    add_link(c, "slcan:pty:/nonexistent/dir/ls0");
    assert_int_equal(run(c), LS_EXIT_CHECK_FAILED);
    assert_string_equal(line_of(c, "link slcan:pty:/nonexistent/dir/ls0"),
                        "FAIL  link slcan:pty:/nonexistent/dir/ls0: cannot create the symlink in /nonexistent/dir: "
                        "No such file or directory; fix: create the directory or choose a writable one (the "
                        "service may write to /run/landscape)");
}

static void test_pty_path_taken_by_a_file_fails(void **state)
{
    cx_t *c = *state;
    char path[128];
    snprintf(path, sizeof path, "%s/plain", c->dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fclose(f);
    char link[160];
    snprintf(link, sizeof link, "slcan:pty:%s", path);
    add_link(c, link);
    assert_int_equal(run(c), LS_EXIT_CHECK_FAILED);
    char want[400];
    snprintf(want, sizeof want,
             "FAIL  link %s: %s exists and is not a symlink; fix: choose another path for the "
             "pty link",
             link, path);
    assert_string_equal(line_of(c, "link slcan"), want);
    unlink(path);
}

static void test_cpu_outside_the_allowed_set_fails(void **state)
{
    cx_t *c = *state;
    add_link(c, "slcan:pty:/tmp/ls_check_cpu");
    c->cfg.rt_cpu = 1023;
    assert_int_equal(run(c), LS_EXIT_CHECK_FAILED);
    assert_starts(line_of(c, "rt_cpu"), "FAIL  rt_cpu: CPU 1023 is not one this process may run on (");
    c->cfg.rt_cpu = 0;
    fclose(c->out);
    free(c->buf);
    c->out = open_memstream(&c->buf, &c->len);
    assert_int_equal(run(c), LS_EXIT_OK);
    assert_string_equal(line_of(c, "rt_cpu"), "PASS  rt_cpu: CPU 0 is available");
}

/* Real-time and memory locking are tried for real: as root both are granted,
 * otherwise they are WARN (the controller runs, degraded), never FAIL. */
static void test_realtime_and_memlock_are_tried(void **state)
{
    cx_t *c = *state;
    add_link(c, "slcan:pty:/tmp/ls_check_rt");
    c->cfg.rt_priority = 80;
    c->cfg.lock_memory = true;
    assert_int_equal(run(c), LS_EXIT_OK);
    const char *rt = line_of(c, "real-time");
    if (geteuid() == 0) {
        assert_starts(rt, "PASS  real-time: SCHED_FIFO priority 80 granted to a test thread (RLIMIT_RTPRIO ");
    } else {
        assert_true(strncmp(rt, "PASS", 4) == 0 || strncmp(rt, "WARN", 4) == 0);
    }
    const char *ml = line_of(c, "memory locking");
    if (geteuid() == 0) {
        assert_starts(ml, "PASS  memory locking: mlockall works (RLIMIT_MEMLOCK ");
    } else {
        assert_true(strncmp(ml, "PASS", 4) == 0 || strncmp(ml, "WARN", 4) == 0);
    }
}

static void test_config_error_report(void **state)
{
    cx_t *c = *state;
    assert_int_equal(ls_check_config_error("/etc/x.conf:2: [control] rate_hz: got '5', expected 100..10000", c->out),
                     LS_EXIT_BAD_CONFIG);
    fflush(c->out);
    assert_string_equal(c->buf, "FAIL  configuration: /etc/x.conf:2: [control] rate_hz: got '5', expected 100..10000\n"
                                "landscaped cannot run with this configuration: 1 FAIL, 0 WARN, 0 PASS\n");
}

int tc_run_check_tests(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_socketcan_and_gpiod_on_this_machine, setup, teardown),
        cmocka_unit_test_setup_teardown(test_sim_configuration_passes, setup, teardown),
        cmocka_unit_test_setup_teardown(test_invalid_configuration_fails, setup, teardown),
        cmocka_unit_test_setup_teardown(test_manual_devices_are_listed_with_what_they_lack, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_refused_robot_model_is_a_bad_configuration, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unwritable_pty_directory_fails, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pty_path_taken_by_a_file_fails, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cpu_outside_the_allowed_set_fails, setup, teardown),
        cmocka_unit_test_setup_teardown(test_realtime_and_memlock_are_tried, setup, teardown),
        cmocka_unit_test_setup_teardown(test_config_error_report, setup, teardown),
    };
    return cmocka_run_group_tests_name("check", tests, NULL, NULL);
}
