/* ls-simdrives' command line (firmware/app/ls_simdrives_opts.h): every
 * refusal is one line naming the option, and the defaults are the brief's. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "ls_err.h"
#include "ls_math.h"
#include "ls_simdrives_opts.h"

static int parse(ls_simdrives_opts_t *o, char *msg, size_t cap, int argc, const char *const *args)
{
    char *argv[16];
    argv[0] = (char *)"ls-simdrives";
    for (int i = 0; i < argc; i++) {
        argv[i + 1] = (char *)args[i];
    }
    return ls_simdrives_parse(argc + 1, argv, o, msg, cap);
}
#define PARSE(o, msg, ...)                                                                                             \
    parse(o, msg, sizeof msg, (int)(sizeof((const char *[]){ __VA_ARGS__ }) / sizeof(const char *)),                   \
          (const char *[]){ __VA_ARGS__ })

static void test_the_defaults_are_six_drives_on_a_17_bit_encoder_behind_100_to_1(void **state)
{
    (void)state;
    ls_simdrives_opts_t o;
    char msg[256] = "";
    assert_int_equal(PARSE(&o, msg, "--link", "slcan:pty:/tmp/x"), 0);
    assert_int_equal(o.n_nodes, 6);
    for (size_t i = 0; i < 6; i++) {
        assert_int_equal(o.nodes[i], 0x21 + i);
        assert_int_equal(o.offsets[i], 0);
    }
    assert_true(fabs(o.counts_per_rad - 131072.0 * 100.0 / (2.0 * LS_PI)) < 1e-6);
    assert_string_equal(o.control, "");
    assert_false(o.sync_stats);
    assert_true(fabs(o.substep_s - 0.001) < 1e-12);
    assert_int_equal(PARSE(&o, msg, "--help"), 1);
}

static void test_nodes_come_as_a_list_or_a_first_id_and_a_count(void **state)
{
    (void)state;
    ls_simdrives_opts_t o;
    char msg[256] = "";
    assert_int_equal(PARSE(&o, msg, "--link", "socketcan:vcan1", "--nodes", "0x31,50,0x7F"), 0);
    assert_int_equal(o.n_nodes, 3);
    assert_int_equal(o.nodes[1], 50);
    assert_int_equal(PARSE(&o, msg, "--link", "socketcan:vcan1", "--first-node", "0x40", "--count", "2"), 0);
    assert_int_equal(o.n_nodes, 2);
    assert_int_equal(o.nodes[1], 0x41);
}

static void test_offsets_are_for_all_nodes_or_per_node(void **state)
{
    (void)state;
    ls_simdrives_opts_t o;
    char msg[256] = "";
    assert_int_equal(PARSE(&o, msg, "--link", "slcan:pty:/tmp/x", "--position-offset-counts", "2147483000"), 0);
    assert_int_equal(o.offsets[5], 2147483000);
    assert_int_equal(
        PARSE(&o, msg, "--link", "slcan:pty:/tmp/x", "--position-offset-counts", "0x22=-5,0x26=0xFFFFFFFE"), 0);
    assert_int_equal(o.offsets[0], 0);
    assert_int_equal(o.offsets[1], -5);
    assert_int_equal(o.offsets[5], -2);
}

static void test_the_physics_sub_step_is_given_in_milliseconds(void **state)
{
    (void)state;
    ls_simdrives_opts_t o;
    char msg[256] = "";
    assert_int_equal(PARSE(&o, msg, "--link", "socketcan:vcan1", "--substep-ms", "10"), 0);
    assert_true(fabs(o.substep_s - 0.010) < 1e-12);
    assert_int_equal(PARSE(&o, msg, "--link", "socketcan:vcan1", "--substep-ms", "0.5"), 0);
    assert_true(fabs(o.substep_s - 0.0005) < 1e-12);
}

static void test_sync_stats_is_a_switch_that_takes_no_value(void **state)
{
    (void)state;
    ls_simdrives_opts_t o;
    char msg[256] = "";
    assert_int_equal(PARSE(&o, msg, "--link", "slcan:pty:/tmp/x", "--sync-stats"), 0);
    assert_true(o.sync_stats);
    assert_int_equal(PARSE(&o, msg, "--link", "slcan:pty:/tmp/x", "--sync-stats=1"), LS_EINVAL);
    assert_non_null(strstr(msg, "--sync-stats"));
    assert_null(strchr(msg, '\n'));
}

static void test_every_bad_option_is_refused_with_one_line_naming_it(void **state)
{
    (void)state;
    ls_simdrives_opts_t o;
    char msg[256];
    static const struct {
        const char *args[4];
        int n;
        const char *names;
    } bad[] = {
        { { "--nodes", "0x21" }, 2, "--link" },
        { { "--link", "can0" }, 2, "--link can0" },
        { { "--link", "slcan:pty:/x", "--nodes", "0x21,0x80" }, 4, "--nodes" },
        { { "--link", "slcan:pty:/x", "--nodes", "0x21,0x21" }, 4, "twice" },
        { { "--link", "slcan:pty:/x", "--nodes", "1,2,3,4,5,6,7" }, 4, "--nodes" },
        { { "--link", "slcan:pty:/x", "--count", "7" }, 4, "--count" },
        { { "--link", "slcan:pty:/x", "--first-node", "0x7F" }, 4, "0x7F" },
        { { "--link", "slcan:pty:/x", "--counts-per-rad", "-3" }, 4, "--counts-per-rad" },
        { { "--link", "slcan:pty:/x", "--counts-per-rad", "1e10" }, 4, "--counts-per-rad" },
        { { "--link", "slcan:pty:/x", "--position-offset-counts", "2147483648" }, 4, "--position-offset-counts" },
        { { "--link", "slcan:pty:/x", "--position-offset-counts", "0x30=1" }, 4, "0x30" },
        { { "--link", "slcan:pty:/x", "--link-faults", "drop=2" }, 4, "--link-faults" },
        { { "--link", "slcan:pty:/x", "--substep-ms", "0" }, 4, "--substep-ms" },
        { { "--link", "slcan:pty:/x", "--substep-ms", "101" }, 4, "--substep-ms" },
        { { "--link", "slcan:pty:/x", "--substep-ms", "4ms" }, 4, "--substep-ms" },
        { { "--link", "slcan:pty:/x", "--frobnicate" }, 3, "--frobnicate" },
        { { "--link", "slcan:pty:/x", "extra" }, 3, "extra" },
        { { "--link" }, 1, "--link" },
        { { "--link", "slcan:pty:/x", "--nodes", "0x21" }, 4, NULL }, /* the good one, for contrast */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        msg[0] = '\0';
        int r = parse(&o, msg, sizeof msg, bad[i].n, bad[i].args);
        if (bad[i].names == NULL) {
            assert_int_equal(r, 0);
            continue;
        }
        if (r != LS_EINVAL || strstr(msg, bad[i].names) == NULL || strchr(msg, '\n') != NULL) {
            fail_msg("case %zu: %d '%s'", i, r, msg);
        }
    }
    assert_int_equal(PARSE(&o, msg, "--link", "slcan:pty:/x", "--nodes", "0x21", "--count", "1"), LS_EINVAL);
    assert_non_null(strstr(msg, "not both"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_defaults_are_six_drives_on_a_17_bit_encoder_behind_100_to_1),
        cmocka_unit_test(test_nodes_come_as_a_list_or_a_first_id_and_a_count),
        cmocka_unit_test(test_offsets_are_for_all_nodes_or_per_node),
        cmocka_unit_test(test_the_physics_sub_step_is_given_in_milliseconds),
        cmocka_unit_test(test_sync_stats_is_a_switch_that_takes_no_value),
        cmocka_unit_test(test_every_bad_option_is_refused_with_one_line_naming_it),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
