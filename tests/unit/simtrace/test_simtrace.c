/* The set-point trace of the simulated arm (hal_sim_world.h "Set-point
 * trace"), through the world's interface: what the arm's command() records
 * and with which time, the full buffer, the file as a reader sees it, and
 * the failures to make or write it. Each test works in a fresh directory. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "alloc_counter.h"
#include "hal_sim_world.h"
#include "ls_robot_model_sim.h"

#define NJ HAL_SIM_ARM_JOINTS
#define DT 0.001
#define RATE_HZ 1000u
#define MAX_ROWS 64

static char g_dir[64];   /* a fresh directory per test */
static char g_path[128]; /* g_dir/trace.csv */
static char g_tmp[132];  /* g_path.tmp */
static hal_arm_t arm;

/* The trace file as a test reads it. */
typedef struct {
    unsigned rate_hz;
    size_t samples;
    unsigned long long dropped;
    size_t rows;
    double t_s[MAX_ROWS];
    double q[MAX_ROWS][NJ];
} csv_t;

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/ls-simtrace-XXXXXX");
    assert_non_null(mkdtemp(g_dir));
    snprintf(g_path, sizeof g_path, "%s/trace.csv", g_dir);
    snprintf(g_tmp, sizeof g_tmp, "%s.tmp", g_path);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    hal_sim_world_close();
    (void)unlink(g_path);
    (void)unlink(g_tmp);
    (void)rmdir(g_dir);
    return 0;
}

static int open_world(const char *trace_path, size_t capacity, char *msg, size_t msglen)
{
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(&ls_robot_model_default, &am);
    hal_sim_world_config_t cfg = { .arm = &am,
                                   .lockstep = true,
                                   .trace = { .path = trace_path, .rate_hz = RATE_HZ, .capacity = capacity } };
    int rc = hal_sim_world_open(&cfg, msg, msglen);
    if (rc == LS_OK) {
        hal_sim_world_get_arm(&arm);
        assert_int_equal(hal_arm_enable(&arm, true), LS_OK);
    }
    return rc;
}

static void open_traced(size_t capacity)
{
    char msg[512] = "";
    int rc = open_world(g_path, capacity, msg, sizeof msg);
    if (rc != LS_OK) {
        fail_msg("open failed (%d): %s", rc, msg);
    }
}

/* Set-point k: distinct per joint and per k, and not short in decimal. */
static void q_of(int k, double q[NJ])
{
    for (int j = 0; j < NJ; j++) {
        q[j] = (double)(k + 1) / 3.0 + 0.01 * (double)j;
    }
}

static void command(int k)
{
    double q[NJ];
    q_of(k, q);
    assert_int_equal(hal_arm_command(&arm, q, NULL), LS_OK);
}

static bool exists(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0;
}

static void parse_row(const char *line, csv_t *c)
{
    assert_true(c->rows < MAX_ROWS);
    double v[NJ + 1];
    const char *p = line;
    for (int i = 0; i <= NJ; i++) {
        char *end = NULL;
        v[i] = strtod(p, &end);
        assert_true(end != p);
        assert_int_equal(*end, i < NJ ? ',' : '\n');
        p = end + 1;
    }
    c->t_s[c->rows] = v[0];
    memcpy(c->q[c->rows], v + 1, sizeof c->q[0]);
    c->rows++;
}

static void read_csv(const char *path, csv_t *c)
{
    memset(c, 0, sizeof *c);
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fail_msg("%s: %s", path, strerror(errno));
    }
    char line[512];
    int used = 0;
    assert_non_null(fgets(line, sizeof line, f));
    assert_int_equal(sscanf(line, "# landscaped setpoint trace: rate_hz=%u samples=%zu dropped=%llu\n%n", &c->rate_hz,
                            &c->samples, &c->dropped, &used),
                     3);
    assert_int_equal((size_t)used, strlen(line));
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "t_s,q1,q2,q3,q4,q5,q6\n");
    while (fgets(line, sizeof line, f) != NULL) {
        parse_row(line, c);
    }
    fclose(f);
}

/* ---- tests ---- */

static void test_commands_are_recorded_with_the_worlds_time(void **state)
{
    (void)state;
    open_traced(100);
    for (int k = 0; k < 10; k++) {
        command(k);
        assert_int_equal(hal_sim_world_step(NULL, DT), 1);
    }
    /* no command for 5 cycles (the drives were off, say), the last one
     * held by lockstep: the world's time goes on all the same */
    for (int k = 0; k < 5; k++) {
        assert_true(hal_sim_world_step(NULL, DT) >= 0);
    }
    command(9);
    assert_int_equal(hal_sim_world_step(NULL, DT), 0);
    double bad[NJ] = { 0.0, NAN, 0.0, 0.0, 0.0, 0.0 };
    assert_int_equal(hal_arm_command(&arm, bad, NULL), LS_EINVAL); /* refused: not handed to the arm */
    command(10);

    char msg[512];
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 1);
    char want[512];
    snprintf(want, sizeof want, "12 samples (0 dropped) written to %s", g_path);
    assert_string_equal(msg, want);
    assert_false(exists(g_tmp));
    csv_t c;
    read_csv(g_path, &c);
    assert_int_equal(c.rate_hz, RATE_HZ);
    assert_int_equal(c.samples, 12);
    assert_int_equal(c.dropped, 0);
    assert_int_equal(c.rows, 12);
    const int cycle_of_row[12] = { 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 15, 16 };
    const int k_of_row[12] = { 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 10 };
    for (size_t r = 0; r < c.rows; r++) {
        double q[NJ];
        q_of(k_of_row[r], q);
        assert_memory_equal(c.q[r], q, sizeof q); /* %.17g gives the doubles back exactly */
        assert_true(fabs(c.t_s[r] - cycle_of_row[r] * DT) < 1e-15);
    }
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 0); /* written already */
}

static void test_a_full_buffer_keeps_the_start_and_counts_the_rest(void **state)
{
    (void)state;
    open_traced(4);
    for (int k = 0; k < 7; k++) {
        command(k);
        assert_true(hal_sim_world_step(NULL, DT) >= 0);
    }
    char msg[512];
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 1);
    assert_non_null(strstr(msg, "4 samples (3 dropped) written to "));
    csv_t c;
    read_csv(g_path, &c);
    assert_int_equal(c.samples, 4);
    assert_int_equal(c.dropped, 3);
    assert_int_equal(c.rows, 4);
    for (size_t r = 0; r < c.rows; r++) {
        double q[NJ];
        q_of((int)r, q);
        assert_memory_equal(c.q[r], q, sizeof q);
    }
}

static void test_recording_does_not_allocate(void **state)
{
    (void)state;
    open_traced(50);
    double q[NJ];
    q_of(3, q);
    alloc_counter_reset();
    alloc_counter_arm();
    for (int k = 0; k < 100; k++) { /* 50 recorded, 50 dropped */
        (void)hal_arm_command(&arm, q, NULL);
    }
    alloc_counter_disarm();
    assert_int_equal(alloc_counter_count(), 0);
    char msg[512];
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 1);
    assert_non_null(strstr(msg, "50 samples (50 dropped)"));
}

static void test_a_failed_write_names_the_file_and_leaves_nothing(void **state)
{
    (void)state;
    if (access("/dev/full", W_OK) != 0) {
        skip(); /* no /dev/full to fail the writes */
    }
    assert_int_equal(symlink("/dev/full", g_tmp), 0); /* PATH.tmp: every write fails with ENOSPC */
    open_traced(10);
    command(0);
    char msg[512];
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), LS_EIO);
    char want[512];
    snprintf(want, sizeof want, "set-point trace: cannot write %s: No space left on device; the trace is lost", g_tmp);
    assert_non_null(strstr(msg, want));
    assert_false(exists(g_tmp));
    assert_false(exists(g_path));
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 0);
}

static void test_a_failed_rename_names_both_files(void **state)
{
    (void)state;
    open_traced(10);
    command(0);
    assert_int_equal(unlink(g_tmp), 0); /* the file is written, then there is nothing to rename */
    char msg[512];
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), LS_EIO);
    char want[512];
    snprintf(want, sizeof want, "set-point trace: cannot rename %s to %s: No such file or directory", g_tmp, g_path);
    assert_non_null(strstr(msg, want));
    assert_false(exists(g_path));
}

static void test_open_refuses_a_trace_it_cannot_make(void **state)
{
    (void)state;
    char msg[512] = "";
    assert_int_equal(open_world(g_dir, 10, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "is a directory; give the path of a file to write"));

    char missing[160];
    snprintf(missing, sizeof missing, "%s/no/trace.csv", g_dir);
    assert_int_equal(open_world(missing, 10, msg, sizeof msg), LS_EIO);
    char want[256];
    snprintf(want, sizeof want, "set-point trace: cannot create %s.tmp: No such file or directory", missing);
    assert_non_null(strstr(msg, want));

    assert_int_equal(open_world(g_path, 0, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "capacity"));

    char longer[HAL_SIM_TRACE_PATH_MAX + 8];
    memset(longer, 'x', sizeof longer - 1);
    longer[0] = '/';
    longer[sizeof longer - 1] = '\0';
    assert_int_equal(open_world(longer, 10, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "longer than"));

    assert_false(exists(g_tmp));
    open_traced(10); /* nothing was left half open */
    assert_true(exists(g_tmp));
}

static void test_closing_unwritten_removes_the_tmp_file(void **state)
{
    (void)state;
    open_traced(10);
    command(0);
    assert_true(exists(g_tmp));
    hal_sim_world_close();
    assert_false(exists(g_tmp));
    assert_false(exists(g_path));
    char msg[64];
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), LS_ENODEV);
}

static void test_without_a_trace_nothing_is_written(void **state)
{
    (void)state;
    char msg[512] = "";
    assert_int_equal(open_world(NULL, 0, msg, sizeof msg), LS_OK);
    command(0);
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 0);
    hal_sim_world_close();
    assert_int_equal(open_world("", 0, msg, sizeof msg), LS_OK);
    command(0);
    assert_int_equal(hal_sim_world_trace_write(msg, sizeof msg), 0);
    assert_false(exists(g_tmp));
    assert_false(exists(g_path));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test_setup_teardown(test_commands_are_recorded_with_the_worlds_time, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_full_buffer_keeps_the_start_and_counts_the_rest, setup, teardown),
        cmocka_unit_test_setup_teardown(test_recording_does_not_allocate, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_failed_write_names_the_file_and_leaves_nothing, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_failed_rename_names_both_files, setup, teardown),
        cmocka_unit_test_setup_teardown(test_open_refuses_a_trace_it_cannot_make, setup, teardown),
        cmocka_unit_test_setup_teardown(test_closing_unwritten_removes_the_tmp_file, setup, teardown),
        cmocka_unit_test_setup_teardown(test_without_a_trace_nothing_is_written, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
