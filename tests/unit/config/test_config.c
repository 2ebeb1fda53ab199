/* ls_config: defaults, INI files (good and each kind of refusal, with the
 * exact message), options over the file, whole-configuration validation. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

#include "landscape.pb.h"
#include "ls_config.h"
#include "test_config.h"

#ifndef LS_DEPLOY_CONF
#error "LS_DEPLOY_CONF must name firmware/app/deploy/landscaped.conf"
#endif

typedef struct {
    ls_config_t cfg;
    char path[64];
    char msg[512];
    char want[512];
} fx_t;

static int setup(void **state)
{
    fx_t *f = calloc(1, sizeof *f);
    ls_config_defaults(&f->cfg);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fx_t *f = *state;
    if (f->path[0] != '\0') {
        unlink(f->path);
    }
    free(f);
    return 0;
}

static int load(fx_t *f, const char *text)
{
    tc_write_file(f->path, sizeof f->path, text);
    return ls_config_load_file(&f->cfg, f->path, f->msg, sizeof f->msg);
}

/* Expect a refusal of `text` with "PATH:<tail>". */
static void refused(fx_t *f, const char *text, const char *tail)
{
    assert_int_equal(load(f, text), LS_EINVAL);
    snprintf(f->want, sizeof f->want, "%s:%s", f->path, tail);
    assert_string_equal(f->msg, f->want);
}

static int args(fx_t *f, int argc, const char **argv)
{
    return ls_config_from_args(&f->cfg, argc, (char **)argv, f->msg, sizeof f->msg);
}

#define ARGS(f, ...)                                                                                                   \
    args((f), (int)(sizeof((const char *[]){ "landscaped", __VA_ARGS__ }) / sizeof(const char *)),                     \
         (const char *[]){ "landscaped", __VA_ARGS__ })

/* ---- defaults and good files ------------------------------------------- */

static void test_defaults(void **state)
{
    fx_t *f = *state;
    const ls_config_t *c = &f->cfg;
    assert_string_equal(c->config_path, "");
    assert_string_equal(c->name, "landscape-sim");
    assert_int_equal(c->node, 0x10);
    assert_int_equal(c->heartbeat_timeout_ms, 1000);
    assert_int_equal(c->disconnect_action, ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE);
    assert_int_equal(c->n_links, 0);
    assert_string_equal(c->arm, "sim");
    assert_string_equal(c->dio, "sim");
    assert_string_equal(c->dio_socket, "");
    assert_string_equal(c->clock, "realtime");
    assert_int_equal(c->rate_hz, 1000);
    assert_int_equal(c->telemetry_hz, 50);
    assert_int_equal(c->rt_priority, 80);
    assert_int_equal(c->rt_cpu, -1);
    assert_true(c->lock_memory);
    assert_int_equal(c->n_inputs, 0);
    assert_int_equal(c->n_outputs, 0);
    assert_int_equal(c->estop_input, -1);
    assert_false(c->check);
    assert_false(c->hal_sim);
    /* defaults alone lack a link */
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), LS_EINVAL);
    assert_string_equal(f->msg, "no link configured: give --link SPEC or 'link = SPEC' under [hal] "
                                "(e.g. slcan:pty:/tmp/landscape0 or socketcan:can0)");
}

static void test_good_file_sets_every_key(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "; full configuration\n"
                             "[device]\n"
                             "name = cell 4 arm\n"
                             "node = 0x22\n"
                             "heartbeat_timeout_ms = 250\n"
                             "\n"
                             "[hal]\n"
                             "link = socketcan:can0\n"
                             "link = slcan:pty:/run/landscape/ls0\n"
                             "arm = none\n"
                             "dio = gpiod:gpiochip1\n"
                             "dio_socket = /run/landscape/dio.sock\n"
                             "clock = lockstep\n"
                             "[control]\n"
                             "rate_hz = 2000 ; inline comment\n"
                             "telemetry_hz = 0\n"
                             "rt_priority = 90\n"
                             "rt_cpu = 1\n"
                             "lock_memory = off\n"
                             "# hash comment\n"
                             "[dio]\n"
                             "inputs = 0, 1,2 ,7\n"
                             "outputs = 8,9\n"
                             "estop_input = 3\n"),
                     0);
    const ls_config_t *c = &f->cfg;
    assert_string_equal(c->name, "cell 4 arm");
    assert_int_equal(c->node, 0x22);
    assert_int_equal(c->heartbeat_timeout_ms, 250);
    assert_int_equal(c->n_links, 2);
    assert_string_equal(c->links[0], "socketcan:can0");
    assert_string_equal(c->links[1], "slcan:pty:/run/landscape/ls0");
    assert_string_equal(c->arm, "none");
    assert_string_equal(c->dio, "gpiod:gpiochip1");
    assert_string_equal(c->dio_socket, "/run/landscape/dio.sock");
    assert_string_equal(c->clock, "lockstep");
    assert_int_equal(c->rate_hz, 2000);
    assert_int_equal(c->telemetry_hz, 0);
    assert_int_equal(c->rt_priority, 90);
    assert_int_equal(c->rt_cpu, 1);
    assert_false(c->lock_memory);
    assert_int_equal(c->n_inputs, 4);
    assert_int_equal(c->input_offsets[0], 0);
    assert_int_equal(c->input_offsets[1], 1);
    assert_int_equal(c->input_offsets[2], 2);
    assert_int_equal(c->input_offsets[3], 7);
    assert_int_equal(c->n_outputs, 2);
    assert_int_equal(c->output_offsets[0], 8);
    assert_int_equal(c->output_offsets[1], 9);
    assert_int_equal(c->estop_input, 3);
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0);
}

static void test_shipped_config_is_valid(void **state)
{
    fx_t *f = *state;
    assert_int_equal(ls_config_load_file(&f->cfg, LS_DEPLOY_CONF, f->msg, sizeof f->msg), 0);
    assert_int_equal(ls_config_validate(&f->cfg, f->msg, sizeof f->msg), 0);
    assert_int_equal(f->cfg.n_links, 1);
    assert_string_equal(f->cfg.links[0], "socketcan:can0");
    assert_string_equal(f->cfg.dio, "gpiod:gpiochip0");
    assert_string_equal(f->cfg.dio_socket, "");
    assert_int_equal(f->cfg.estop_input, 0);
}

static void test_bool_and_number_spellings(void **state)
{
    fx_t *f = *state;
    static const char *yes[] = { "true", "YES", "On", "1" };
    static const char *no[] = { "false", "no", "OFF", "0" };
    char text[128];
    for (size_t i = 0; i < 4; i++) {
        snprintf(text, sizeof text, "[control]\nlock_memory = %s\n", no[i]);
        assert_int_equal(load(f, text), 0);
        assert_false(f->cfg.lock_memory);
        unlink(f->path);
        snprintf(text, sizeof text, "[control]\nlock_memory = %s\n", yes[i]);
        assert_int_equal(load(f, text), 0);
        assert_true(f->cfg.lock_memory);
        unlink(f->path);
    }
    assert_int_equal(load(f, "[device]\nnode = 254\n"), 0);
    assert_int_equal(f->cfg.node, 0xFE);
    unlink(f->path);
    assert_int_equal(load(f, "[device]\nnode = 0x1\n[control]\nrt_cpu = -1\ntelemetry_hz = 200\n"), 0);
    assert_int_equal(f->cfg.node, 1);
    assert_int_equal(f->cfg.telemetry_hz, 200);
    unlink(f->path);
    assert_int_equal(load(f, "[dio]\ninputs =\noutputs = 15\n"), 0);
    assert_int_equal(f->cfg.n_inputs, 0);
    assert_int_equal(f->cfg.n_outputs, 1);
}

/* An indented line is a key of its own, not a continuation of the value
 * above (inih's multi-line values would otherwise swallow it). */
static void test_indented_line_is_its_own_key(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "[control]\nrate_hz = 500\n    telemetry_hz = 20\n"), 0);
    assert_int_equal(f->cfg.rate_hz, 500);
    assert_int_equal(f->cfg.telemetry_hz, 20);
}

/* The disconnect handler's action (seed 2.2): the schema's names, from the
 * file and from the command line; anything else is refused naming them. */
static void test_disconnect_action(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "[device]\ndisconnect_action = stop\n"), 0);
    assert_int_equal(f->cfg.disconnect_action, ls_DisconnectAction_DISCONNECT_STOP);
    unlink(f->path);
    assert_int_equal(load(f, "[device]\ndisconnect_action = stop_deactivate\n"), 0);
    assert_int_equal(f->cfg.disconnect_action, ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE);
    assert_int_equal(ARGS(f, "--disconnect-action", "stop_deactivate_release"), 0);
    assert_int_equal(f->cfg.disconnect_action, ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE);
    unlink(f->path);
    refused(f, "[device]\ndisconnect_action = release\n",
            "2: [device] disconnect_action: got 'release', expected stop, stop_deactivate, "
            "stop_deactivate_release (what the disconnect handler does when the owner is lost, seed 2.2)");
    unlink(f->path);
    refused(f, "[device]\ndisconnect_action = configured\n",
            "2: [device] disconnect_action: got 'configured', expected stop, stop_deactivate, "
            "stop_deactivate_release (what the disconnect handler does when the owner is lost, seed 2.2)");
}

/* ---- refusals: file, line, key, value, what is allowed ----------------- */

static void test_unknown_key(void **state)
{
    refused(*state, "[control]\nrate_hz = 500\nrate = 100\n",
            "3: [control] rate: unknown key; expected one of rate_hz, telemetry_hz, rt_priority, rt_cpu, lock_memory");
}

static void test_key_in_wrong_section(void **state)
{
    refused(*state, "[device]\nrate_hz = 500\n",
            "2: [device] rate_hz: unknown key; expected one of name, node, heartbeat_timeout_ms, "
            "disconnect_action");
}

static void test_unknown_section(void **state)
{
    refused(*state, "[device]\nnode = 3\n[motors]\n",
            "3: unknown section [motors]; expected [device], [hal], [control], [dio], [manual], [drives], "
            "[joint.1] .. [joint.6], [robot] or [security]");
}

static void test_robot_model_key(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "[robot]\nmodel = /usr/share/landscape/robots/ur5e.ini\n"), 0);
    assert_string_equal(f->cfg.model, "/usr/share/landscape/robots/ur5e.ini");
    refused(f, "[robot]\nmodel = /etc/landscape/\n",
            "2: [robot] model: got '/etc/landscape/', expected the path of a robot model file, of at most 255 "
            "characters, or nothing for the compiled-in ls-sim6");
}

static void test_key_outside_section(void **state)
{
    refused(*state, "# no section yet\nnode = 3\n",
            "2: key 'node' outside any section: put it under [device], [hal], [control], [dio], [manual], [drives], "
            "[joint.1] .. [joint.6], [robot] or [security]");
}

static void test_wrong_type(void **state)
{
    refused(*state, "[device]\nname = x\nnode = abc\n",
            "3: [device] node: got 'abc', expected 1..0xFE (node address; 0xFF is the broadcast address)");
}

static void test_wrong_types_of_each_kind(void **state)
{
    fx_t *f = *state;
    refused(f, "[control]\nlock_memory = maybe\n",
            "2: [control] lock_memory: got 'maybe', expected true or false (also yes/no, on/off, 1/0)");
    unlink(f->path);
    refused(f, "[hal]\nclock = wallclock\n",
            "2: [hal] clock: got 'wallclock', expected realtime or lockstep "
            "(lockstep: virtual time advancing exactly one period per cycle)");
    unlink(f->path);
    refused(f, "[hal]\ndio = gpio:0\n",
            "2: [hal] dio: got 'gpio:0', expected sim, none or gpiod:CHIP (CHIP as "
            "gpiochip0, 0, /dev/gpiochip0 or a chip label)");
    unlink(f->path);
    refused(f, "[hal]\nlink = can0\n",
            "2: [hal] link: got 'can0', expected slcan:pty:PATH or socketcan:IFNAME (unknown link kind)");
    unlink(f->path);
    refused(f, "[hal]\nlink = socketcan:averyveryverylongname\n",
            "2: [hal] link: got 'socketcan:averyveryverylongname', expected slcan:pty:PATH or socketcan:IFNAME "
            "(IFNAME is a network interface name of 1..15 characters, e.g. can0)");
    unlink(f->path);
    refused(f, "[dio]\ninputs = 1,,2\n",
            "2: [dio] inputs: got '1,,2', expected a comma-separated list of at most "
            "16 distinct line offsets 0..1023, e.g. 0,1,2");
    unlink(f->path);
    refused(f, "[dio]\noutputs = 4,5,4\n",
            "2: [dio] outputs: got '4,5,4', expected a comma-separated list of at "
            "most 16 distinct line offsets 0..1023, e.g. 0,1,2 (4 is listed twice)");
    unlink(f->path);
    refused(f, "[device]\nnode = -3\n",
            "2: [device] node: got '-3', expected 1..0xFE (node address; 0xFF is the broadcast address)");
    unlink(f->path);
    refused(f, "[device]\nname =\n",
            "2: [device] name: got '', expected 1..31 printable characters (device name "
            "reported at connect)");
}

static void test_out_of_range(void **state)
{
    fx_t *f = *state;
    refused(f, "[control]\nrate_hz = 5\n",
            "2: [control] rate_hz: got '5', expected 100..10000 (control cycles "
            "per second)");
    unlink(f->path);
    refused(f, "[control]\nrate_hz = 10001\n",
            "2: [control] rate_hz: got '10001', expected 100..10000 (control "
            "cycles per second)");
    unlink(f->path);
    refused(f, "[device]\nnode = 0xFF\n",
            "2: [device] node: got '0xFF', expected 1..0xFE (node address; 0xFF is the broadcast address)");
    unlink(f->path);
    refused(f, "[device]\nheartbeat_timeout_ms = 49\n",
            "2: [device] heartbeat_timeout_ms: got '49', expected "
            "milliseconds 50..600000 (drop a supervisor after this long without heartbeat)");
    unlink(f->path);
    refused(f, "[control]\nrt_priority = 100\n",
            "2: [control] rt_priority: got '100', expected 0..99 (SCHED_FIFO "
            "priority of the control thread; 0 = normal thread)");
    unlink(f->path);
    refused(f, "[control]\ntelemetry_hz = 201\n",
            "2: [control] telemetry_hz: got '201', expected 0..200 (telemetry frames per second; 0 = off)");
    unlink(f->path);
    refused(f, "[dio]\nestop_input = 16\n",
            "2: [dio] estop_input: got '16', expected -1..15 (input bit index that "
            "stops everything when active; -1 = none)");
    unlink(f->path);
    refused(f, "[dio]\ninputs = 1024\n",
            "2: [dio] inputs: got '1024', expected a comma-separated list of at most "
            "16 distinct line offsets 0..1023, e.g. 0,1,2");
    unlink(f->path);
    refused(f, "[dio]\ninputs = 0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n",
            "2: [dio] inputs: got '0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16', expected a comma-separated list of "
            "at most 16 distinct line offsets 0..1023, e.g. 0,1,2");
}

static void test_duplicate_key(void **state)
{
    refused(*state, "[control]\nrate_hz = 500\ntelemetry_hz = 10\nrate_hz = 600\n",
            "4: [control] rate_hz: given twice (first on line 2); keep one");
}

static void test_duplicate_key_across_repeated_section(void **state)
{
    refused(*state, "[device]\nnode = 3\n[hal]\narm = sim\n[device]\nnode = 4\n",
            "6: [device] node: given twice (first on line 2); keep one");
}

static void test_links_repeat_up_to_four(void **state)
{
    fx_t *f = *state;
    f->cfg.n_links = 1; /* the file's first link replaces what cfg held */
    strcpy(f->cfg.links[0], "slcan:pty:/tmp/old");
    assert_int_equal(load(f, "[hal]\nlink = socketcan:can0\nlink = socketcan:can1\n"), 0);
    assert_int_equal(f->cfg.n_links, 2);
    assert_string_equal(f->cfg.links[0], "socketcan:can0");
    assert_string_equal(f->cfg.links[1], "socketcan:can1");
    unlink(f->path);
    refused(f, "[hal]\nlink = socketcan:can0\nlink = socketcan:can0\n",
            "3: [hal] link: got 'socketcan:can0', expected slcan:pty:PATH or socketcan:IFNAME, each link once "
            "(this one is already listed)");
    unlink(f->path);
    refused(f,
            "[hal]\nlink = socketcan:can0\nlink = socketcan:can1\nlink = socketcan:can2\nlink = socketcan:can3\n"
            "link = socketcan:can4\n",
            "6: [hal] link: got 'socketcan:can4', expected slcan:pty:PATH or socketcan:IFNAME, at most 4 links");
}

static void test_missing_file(void **state)
{
    fx_t *f = *state;
    assert_int_equal(ls_config_load_file(&f->cfg, "/nonexistent/landscaped.conf", f->msg, sizeof f->msg), LS_EINVAL);
    assert_string_equal(f->msg, "/nonexistent/landscaped.conf: cannot read the configuration file: No such file or "
                                "directory (give an existing file with --config FILE)");
}

static void test_syntax_error(void **state)
{
    refused(*state, "[device]\nnode 3\n", "2: syntax error: expected '[section]', 'key = value' or a ; or # comment");
}

/* A syntax error before a bad value: the first one is reported. */
static void test_first_error_wins(void **state)
{
    refused(*state, "[device]\nthis is not ini\nnode = abc\n",
            "2: syntax error: expected '[section]', 'key = value' or a ; or # comment");
}

static void test_line_too_long(void **state)
{
    char text[400];
    memset(text, 0, sizeof text);
    strcpy(text, "[device]\nname = ");
    memset(text + strlen(text), 'x', 250);
    strcat(text, "\n");
    refused(*state, text, "2: line longer than 197 characters");
}

static void test_byte_order_mark_and_nul(void **state)
{
    fx_t *f = *state;
    refused(f, "\xEF\xBB\xBF[motors]\n",
            "1: unknown section [motors]; expected [device], [hal], [control], [dio], [manual], [drives], [joint.1] "
            ".. [joint.6], [robot] or [security]");
    unlink(f->path);
    assert_int_equal(load(f, "\xEF\xBB\xBF[device]\nnode = 7\n"), 0);
    assert_int_equal(f->cfg.node, 7);
    unlink(f->path);
    static const char bin[] = "[device]\nna\0me = x\n";
    tc_write_file(f->path, sizeof f->path, "");
    FILE *fp = fopen(f->path, "w");
    assert_non_null(fp);
    assert_int_equal(fwrite(bin, 1, sizeof bin - 1, fp), sizeof bin - 1);
    fclose(fp);
    assert_int_equal(ls_config_load_file(&f->cfg, f->path, f->msg, sizeof f->msg), LS_EINVAL);
    snprintf(f->want, sizeof f->want, "%s:2: a NUL byte in the line: this is not a text file", f->path);
    assert_string_equal(f->msg, f->want);
}

/* ---- options ------------------------------------------------------------ */

static void test_skeleton_options_keep_working(void **state)
{
    fx_t *f = *state;
    assert_int_equal(ARGS(f, "--hal", "sim", "--link", "slcan:pty:/tmp/a", "--link", "slcan:pty:/tmp/b", "--node",
                          "0x20", "--heartbeat-timeout", "200", "--name", "bench"),
                     0);
    const ls_config_t *c = &f->cfg;
    assert_true(c->hal_sim);
    assert_string_equal(c->arm, "sim");
    assert_string_equal(c->dio, "sim");
    assert_string_equal(c->clock, "realtime");
    assert_int_equal(c->n_links, 2);
    assert_string_equal(c->links[0], "slcan:pty:/tmp/a");
    assert_string_equal(c->links[1], "slcan:pty:/tmp/b");
    assert_int_equal(c->node, 0x20);
    assert_int_equal(c->heartbeat_timeout_ms, 200);
    assert_string_equal(c->name, "bench");
    assert_false(c->check);
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0);
}

static void test_every_option(void **state)
{
    fx_t *f = *state;
    assert_int_equal(ARGS(f, "--link", "socketcan:vcan0", "--arm", "none", "--dio", "gpiod:0", "--dio-socket",
                          "/run/x.sock", "--clock", "lockstep", "--rate", "500", "--telemetry-hz", "25",
                          "--rt-priority", "0", "--rt-cpu", "0", "--no-lock-memory", "--estop-input", "2", "--model",
                          "/etc/landscape/arm.ini", "--check"),
                     0);
    const ls_config_t *c = &f->cfg;
    assert_false(c->hal_sim);
    assert_int_equal(c->n_links, 1);
    assert_string_equal(c->links[0], "socketcan:vcan0");
    assert_string_equal(c->arm, "none");
    assert_string_equal(c->dio, "gpiod:0");
    assert_string_equal(c->dio_socket, "/run/x.sock");
    assert_string_equal(c->clock, "lockstep");
    assert_int_equal(c->rate_hz, 500);
    assert_int_equal(c->telemetry_hz, 25);
    assert_int_equal(c->rt_priority, 0);
    assert_int_equal(c->rt_cpu, 0);
    assert_false(c->lock_memory);
    assert_int_equal(c->estop_input, 2);
    assert_string_equal(c->model, "/etc/landscape/arm.ini");
    assert_true(c->check);
}

static void test_options_override_the_file(void **state)
{
    fx_t *f = *state;
    tc_write_file(f->path, sizeof f->path,
                  "[device]\nname = from-file\nnode = 0x30\n[hal]\nlink = socketcan:can0\nlink = socketcan:can1\n"
                  "dio = gpiod:gpiochip0\n[control]\nrate_hz = 500\ntelemetry_hz = 10\nlock_memory = true\n");
    /* --config comes last on purpose: the file is read first wherever it is */
    assert_int_equal(ARGS(f, "--rate", "2000", "--link", "slcan:pty:/tmp/x", "--hal", "sim", "--no-lock-memory",
                          "--config", f->path),
                     0);
    const ls_config_t *c = &f->cfg;
    assert_string_equal(c->config_path, f->path);
    assert_string_equal(c->name, "from-file"); /* file, no option */
    assert_int_equal(c->node, 0x30);           /* file */
    assert_int_equal(c->telemetry_hz, 10);     /* file */
    assert_int_equal(c->rate_hz, 2000);        /* option over file */
    assert_int_equal(c->n_links, 1);           /* --link replaces the file's links */
    assert_string_equal(c->links[0], "slcan:pty:/tmp/x");
    assert_string_equal(c->dio, "sim"); /* --hal sim over dio = gpiod:... */
    assert_false(c->lock_memory);
}

static void test_later_option_wins(void **state)
{
    fx_t *f = *state;
    assert_int_equal(
        ARGS(f, "--hal", "sim", "--dio", "none", "--rate", "300", "--rate", "400", "--link", "slcan:pty:/tmp/a"), 0);
    assert_string_equal(f->cfg.dio, "none");
    assert_int_equal(f->cfg.rate_hz, 400);
}

static void test_option_errors(void **state)
{
    fx_t *f = *state;
    assert_int_equal(ARGS(f, "--hal", "sim", "--link", "slcan:pty:/tmp/x", "--node", "0x1FF"), LS_EINVAL);
    assert_string_equal(f->msg, "--node: got '0x1FF', expected 1..0xFE (node address; 0xFF is the broadcast address)");
    assert_int_equal(ARGS(f, "--hal", "real", "--link", "slcan:pty:/tmp/x"), LS_EINVAL);
    assert_string_equal(f->msg, "--hal: got 'real', expected sim (or set --arm, --dio, --clock)");
    assert_int_equal(ARGS(f, "--hal", "sim", "--link", "bogus:x"), LS_EINVAL);
    assert_string_equal(f->msg,
                        "--link: got 'bogus:x', expected slcan:pty:PATH or socketcan:IFNAME (unknown link kind)");
    assert_int_equal(ARGS(f, "--rate", "5"), LS_EINVAL);
    assert_string_equal(f->msg, "--rate: got '5', expected 100..10000 (control cycles per second)");
    assert_int_equal(ARGS(f, "--heartbeat-timeout", "10"), LS_EINVAL);
    assert_string_equal(f->msg, "--heartbeat-timeout: got '10', expected milliseconds 50..600000 (drop a supervisor "
                                "after this long without heartbeat)");
    assert_int_equal(ARGS(f, "--frobnicate"), LS_EINVAL);
    assert_string_equal(f->msg, "unknown option '--frobnicate' (see --help)");
    assert_int_equal(ARGS(f, "--rate"), LS_EINVAL);
    assert_string_equal(f->msg, "--rate: missing value (see --help)");
    assert_int_equal(ARGS(f, "--rate", "100", "extra"), LS_EINVAL);
    assert_string_equal(f->msg, "unexpected argument 'extra' (see --help)");
    assert_int_equal(ARGS(f, "--config", "/a", "--config", "/b"), LS_EINVAL);
    assert_string_equal(f->msg, "--config given twice ('/a' and '/b'): give one file");
}

static void test_config_error_through_args_keeps_check(void **state)
{
    fx_t *f = *state;
    tc_write_file(f->path, sizeof f->path, "[control]\nrate_hz = 5\n");
    assert_int_equal(ARGS(f, "--check", "--config", f->path), LS_EINVAL);
    snprintf(f->want, sizeof f->want,
             "%s:2: [control] rate_hz: got '5', expected 100..10000 (control cycles per "
             "second)",
             f->path);
    assert_string_equal(f->msg, f->want);
    assert_true(f->cfg.check);
    assert_string_equal(f->cfg.config_path, f->path);
}

static void test_missing_config_through_args(void **state)
{
    fx_t *f = *state;
    assert_int_equal(ARGS(f, "--config", "/nonexistent/x.conf", "--hal", "sim"), LS_EINVAL);
    assert_string_equal(f->msg, "/nonexistent/x.conf: cannot read the configuration file: No such file or directory "
                                "(give an existing file with --config FILE)");
}

static void test_help(void **state)
{
    fx_t *f = *state;
    /* --help prints to stdout: send that to /dev/null here */
    fflush(stdout);
    int saved = dup(STDOUT_FILENO);
    int null = open("/dev/null", O_WRONLY);
    assert_true(saved >= 0 && null >= 0);
    dup2(null, STDOUT_FILENO);
    /* --help wins over everything else, even a bad value */
    int r1 = ARGS(f, "--rate", "5", "-h");
    int r2 = ARGS(f, "--help");
    fflush(stdout);
    dup2(saved, STDOUT_FILENO);
    close(saved);
    close(null);
    assert_int_equal(r1, 1);
    assert_int_equal(r2, 1);

    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    ls_config_usage(m);
    fclose(m);
    /* every option of the key table is documented */
    static const char *opts[] = {
        "--config FILE",      "--check",       "--hal sim", "--link SPEC",         "--arm",         "--dio sim",
        "--dio-socket",       "--clock",       "--node",    "--heartbeat-timeout", "--name",        "--rate",
        "--telemetry-hz",     "--rt-priority", "--rt-cpu",  "--no-lock-memory",    "--estop-input", "-h, --help",
        "--disconnect-action"
    };
    for (size_t i = 0; i < sizeof opts / sizeof opts[0]; i++) {
        if (strstr(buf, opts[i]) == NULL) {
            fail_msg("--help does not mention %s", opts[i]);
        }
    }
    free(buf);
}

/* ---- whole-configuration validation ------------------------------------- */

static void invalid(fx_t *f, const char *want)
{
    assert_int_equal(ls_config_validate(&f->cfg, f->msg, sizeof f->msg), LS_EINVAL);
    assert_string_equal(f->msg, want);
}

/* ---- [manual] -------------------------------------------------------------- */

static void test_manual_keys_set_the_maps_and_the_gates(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "[manual]\n"
                             "teachpendant = /dev/input/by-id/usb-pad-event-joystick\n"
                             "teachpendant_buttons = enable:BTN_TR, panic:BTN_TR2, frame:BTN_SELECT\n"
                             "teachpendant_deadband = 0.2\n"
                             "spaceball = /dev/input/by-id/usb-3Dconnexion-event-if00\n"
                             "spaceball_map = gamepad\n"
                             "spaceball_axes = vx:REL_X:0.5, wz:-ABS_RZ:2:0.05\n"
                             "spaceball_stale_ms = 250\n"
                             "speed_steps = 5, 20, 60\n"),
                     0);
    hal_evdev_map_t m;
    ls_config_manual_map(&f->cfg, LS_MANUAL_TEACHPENDANT, &m);
    assert_int_equal(m.axis[0].code, ABS_X); /* the gamepad's axes */
    assert_int_equal(m.button[HAL_MANUAL_FN_ENABLE], BTN_TR);
    assert_int_equal(m.button[HAL_MANUAL_FN_PANIC], BTN_TR2);
    assert_int_equal(m.button[HAL_MANUAL_FN_SPEED_UP], 0); /* buttons given replace the map's */
    assert_true(m.deadband == 0.2);
    ls_config_manual_map(&f->cfg, LS_MANUAL_SPACEBALL, &m);
    assert_int_equal(m.axis[0].type, EV_REL);
    assert_true(m.axis[0].scale == 0.5 && m.axis[0].deadband < 0.0);
    assert_int_equal(m.axis[1].type, 0); /* axes given replace the map's */
    assert_true(m.axis[5].scale == -2.0 && m.axis[5].deadband == 0.05);
    assert_int_equal(m.button[HAL_MANUAL_FN_ENABLE], BTN_TL); /* the gamepad's buttons */
    ls_manual_config_t g;
    ls_config_manual_gate(&f->cfg, LS_MANUAL_SPACEBALL, &g);
    assert_true(g.stale_us == 250000u);
    assert_int_equal(g.n_steps, 3);
    assert_int_equal(g.step_pct[2], 60);
    assert_int_equal(g.start_step, 2);
    assert_false(g.enabling_switch); /* manualControl decides that */
    assert_int_equal(ARGS(f, "--link", "socketcan:can0"), 0);
    assert_int_equal(ls_config_validate(&f->cfg, f->msg, sizeof f->msg), 0);
    /* nothing: the map's again */
    assert_int_equal(load(f, "[manual]\nteachpendant_buttons =\nteachpendant_deadband =\nspaceball_axes =\n"), 0);
    ls_config_manual_map(&f->cfg, LS_MANUAL_TEACHPENDANT, &m);
    assert_int_equal(m.button[HAL_MANUAL_FN_ENABLE], BTN_TL);
    assert_true(m.deadband == 0.15);
    ls_config_manual_map(&f->cfg, LS_MANUAL_SPACEBALL, &m);
    assert_int_equal(m.axis[1].code, ABS_Y);
}

static void test_manual_defaults_are_the_simulated_devices_and_four_steps(void **state)
{
    fx_t *f = *state;
    assert_string_equal(f->cfg.manual[LS_MANUAL_TEACHPENDANT].path, "");
    assert_string_equal(f->cfg.manual[LS_MANUAL_TEACHPENDANT].map_name, "gamepad");
    assert_string_equal(f->cfg.manual[LS_MANUAL_SPACEBALL].map_name, "spacemouse");
    ls_manual_config_t g;
    ls_config_manual_gate(&f->cfg, LS_MANUAL_TEACHPENDANT, &g);
    assert_int_equal(g.n_steps, 4);
    assert_int_equal(g.step_pct[g.start_step], 100);
    assert_true(g.stale_us == 0u);
}

/* [manual] KEY = each case's value is refused with a message holding both
 * the case's text and `also`. */
static void refused_each(fx_t *f, const char *key, const char *const (*cases)[2], size_t n, const char *also)
{
    for (size_t i = 0; i < n; i++) {
        char text[128];
        snprintf(text, sizeof text, "[manual]\n%s = %s\n", key, cases[i][0]);
        assert_int_equal(load(f, text), LS_EINVAL);
        if (strstr(f->msg, cases[i][1]) == NULL || strstr(f->msg, also) == NULL) {
            fail_msg("%s = %s: %s", key, cases[i][0], f->msg);
        }
    }
}

static void test_manual_keys_refuse_bad_values(void **state)
{
    fx_t *f = *state;
    refused(f, "[manual]\nteachpendant = dev/input/x\n",
            "2: [manual] teachpendant: got 'dev/input/x', expected an absolute device path of at most 127 characters "
            "(e.g. /dev/input/by-id/usb-...-event-joystick), or nothing for none");
    refused(f, "[manual]\nspaceball_map = joystick\n",
            "2: [manual] spaceball_map: got 'joystick', expected gamepad, spacemouse (the default map to start from)");
    static const char *const bad_axes[][2] = {
        { "vq:ABS_X", "unknown component 'vq'" },
        { "vx:ABS_X, vx:ABS_Y", "vx is mapped twice" },
        { "vx:BTN_TL", "vx: 'BTN_TL' is no ABS_* or REL_* axis" },
        { "vx:ABS_NOPE", "vx: 'ABS_NOPE' is no ABS_* or REL_* axis" },
        { "vx:ABS_X:0", "vx: scale '0' is not a number in (0, 100] or [-100, 0)" },
        { "vx:ABS_X:1:0.95", "vx: dead band '0.95' is not a number in 0..0.9" },
        { "vx:ABS_X:1:0.1:7", "item 1 has 5 fields" },
        { "vx", "item 1 has 1 fields" },
    };
    refused_each(f, "spaceball_axes", bad_axes, sizeof bad_axes / sizeof bad_axes[0], "expected COMPONENT:[-]CODE");
    static const char *const bad_buttons[][2] = {
        { "enable:BTN_TL, frame:BTN_TL", "BTN_TL is both enable and frame" },
        { "enable:BTN_TL, enable:BTN_TR", "enable is mapped twice" },
        { "brake:BTN_TL", "unknown function 'brake'" },
        { "enable:ABS_X", "enable: 'ABS_X' is no BTN_* or KEY_* code" },
        { "enable", "item 'enable'" },
    };
    refused_each(f, "teachpendant_buttons", bad_buttons, sizeof bad_buttons / sizeof bad_buttons[0],
                 "expected FUNCTION:KEY");
    refused(f, "[manual]\nteachpendant_deadband = 1\n",
            "2: [manual] teachpendant_deadband: got '1', expected 0..0.9 (the share of full deflection that counts as "
            "still), or nothing for the map's");
    refused(f, "[manual]\nspaceball_stale_ms = 70000\n",
            "2: [manual] spaceball_stale_ms: got '70000', expected milliseconds 0..60000 (> 0: the device reports "
            "continuously, and a longer silence stops the jog; 0: it reports changes only)");
    static const char *const bad_steps[][2] = {
        { "50,25", "" }, { "0,10", "" }, { "10,101", "" }, { "", "" }, { "1,2,3,4,5,6,7,8,9", "" }, { "10,10", "" }
    };
    refused_each(f, "speed_steps", bad_steps, sizeof bad_steps / sizeof bad_steps[0],
                 "expected 1..8 ascending percentages 1..100");
}

static void test_a_teachpendant_without_an_enabling_switch_is_refused(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "[hal]\nlink = socketcan:can0\n[manual]\nteachpendant = /dev/input/event3\n"
                             "teachpendant_buttons = frame:BTN_WEST\n"),
                     0);
    assert_int_equal(ls_config_validate(&f->cfg, f->msg, sizeof f->msg), LS_EINVAL);
    assert_string_equal(f->msg, "[manual] teachpendant = /dev/input/event3 has no enabling switch in its map: a teach "
                                "pendant jogs only while one is held; add enable:KEY to teachpendant_buttons (e.g. "
                                "enable:BTN_TL)");
    /* a spaceball needs none */
    ls_config_defaults(&f->cfg);
    assert_int_equal(load(f, "[hal]\nlink = socketcan:can0\n[manual]\nspaceball = /dev/input/event4\n"), 0);
    assert_int_equal(ls_config_validate(&f->cfg, f->msg, sizeof f->msg), 0);
}

static void test_validate(void **state)
{
    fx_t *f = *state;
    ls_config_t *c = &f->cfg;
    c->n_links = 1;
    strcpy(c->links[0], "slcan:pty:/tmp/a");
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0);

    c->rate_hz = 100;
    c->telemetry_hz = 150;
    invalid(f, "[control] telemetry_hz = 150 is above rate_hz = 100: telemetry is sent from control cycles; lower "
               "telemetry_hz");
    c->telemetry_hz = 100;
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0);

    c->n_inputs = 2;
    c->input_offsets[0] = 4;
    c->input_offsets[1] = 5;
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0); /* ignored by dio = sim */
    strcpy(c->dio, "gpiod:gpiochip0");
    c->n_outputs = 1;
    c->output_offsets[0] = 5;
    invalid(f, "[dio] line 5 is both in inputs and in outputs: a line has one role");
    c->output_offsets[0] = 6;
    c->estop_input = 2;
    invalid(f, "[dio] estop_input = 2 but only 2 inputs are configured: use an input bit 0..1 or -1");
    c->estop_input = 1;
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0);

    strcpy(c->dio, "none");
    c->n_inputs = 0;
    c->n_outputs = 0;
    invalid(f, "[dio] estop_input = 1 needs a DIO backend but [hal] dio = none");
}

/* ---- the drive bus and its joints (arm = cia402) ----------------------- */

static const char DRIVES_FILE[] = "[hal]\n"
                                  "arm = cia402\n"
                                  "[drives]\n"
                                  "link = slcan:tty:/dev/ttyACM0\n"
                                  "bitrate = 500000\n"
                                  "cycle = 8\n"
                                  "master_node = 0x70\n"
                                  "heartbeat_ms = 50\n"
                                  "heartbeat_timeout_ms = 175\n"
                                  "boot_timeout_ms = 2500\n"
                                  "budget_pct = 60\n"
                                  "abort_connection = disable_voltage\n"
                                  "velocity_feedforward = no\n"
                                  "quick_stop_option = 6\n"
                                  "readouts = torque, velocity\n"
                                  "[joint.1]\nnode = 0x21\neds = /a.eds\ncounts_per_rad = 2086000.5\n"
                                  "brake = 0x2100:01\nsto = !0x60FD:00/3\ntemperature = 0x2100:03\n"
                                  "temperature_scale = 0.1\n"
                                  "[joint.2]\nnode = 34\neds = /b.dcf\ncounts_per_rad = 1e6\nsign = -1\n"
                                  "offset_rad = -1.5707963\nvelocity_counts_per_rad_s = 9.549\n"
                                  "home_required = yes\nhome_method = 35\nhome_offset_rad = 0.25\n"
                                  "following_window_rad = 0.02\nfollowing_timeout_ms = 50\n"
                                  "[joint.3]\nnode = 0x23\neds = /a.eds\ncounts_per_rad = 1000\n"
                                  "[joint.4]\nnode = 0x24\neds = /a.eds\ncounts_per_rad = 1000\n"
                                  "[joint.5]\nnode = 0x25\neds = /a.eds\ncounts_per_rad = 1000\n"
                                  "[joint.6]\nnode = 0x26\neds = /a.eds\ncounts_per_rad = 1000\n";

static void test_a_drive_configuration_sets_every_drive_key(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, DRIVES_FILE), 0);
    const ls_config_t *c = &f->cfg;
    assert_string_equal(c->arm, "cia402");
    assert_string_equal(c->drives_link, "slcan:tty:/dev/ttyACM0");
    assert_int_equal(c->drives_bitrate, 500000);
    assert_int_equal(c->drives_cycle, 8);
    assert_int_equal(c->drives_master_node, 0x70);
    assert_int_equal(c->drives_heartbeat_ms, 50);
    assert_int_equal(c->drives_heartbeat_timeout_ms, 175);
    assert_int_equal(c->drives_boot_timeout_ms, 2500);
    assert_int_equal(c->drives_budget_pct, 60);
    assert_int_equal(c->drives_abort, LS_DRIVE_ABORT_DISABLE_VOLTAGE);
    assert_false(c->drives_feedforward);
    assert_true(c->joint[0].present);
    assert_int_equal(c->joint[0].node, 0x21);
    assert_string_equal(c->joint[0].eds, "/a.eds");
    assert_true(c->joint[0].counts_per_rad == 2086000.5);
    assert_int_equal(c->joint[0].sign, 1); /* the default */
    assert_int_equal(c->joint[1].node, 34);
    assert_int_equal(c->joint[1].sign, -1);
    assert_true(c->joint[1].offset_rad == -1.5707963);
    assert_true(c->joint[1].vel_counts_per_rad_s == 9.549);
    /* what the drives publish and do of their own */
    assert_true(c->drives_has_quick_stop);
    assert_int_equal(c->drives_quick_stop, 6);
    assert_int_equal(c->drives_readouts, LS_CONFIG_READOUT_TORQUE | LS_CONFIG_READOUT_VELOCITY);
    assert_true(c->joint[0].brake.given && !c->joint[0].brake.inverted);
    assert_int_equal(c->joint[0].brake.index, 0x2100);
    assert_int_equal(c->joint[0].brake.sub, 1);
    assert_int_equal(c->joint[0].brake.bit, 0);
    assert_true(c->joint[0].sto.given && c->joint[0].sto.inverted);
    assert_int_equal(c->joint[0].sto.index, 0x60FD);
    assert_int_equal(c->joint[0].sto.bit, 3);
    assert_int_equal(c->joint[0].temperature.sub, 3);
    assert_true(c->joint[0].temperature_scale == 0.1);
    assert_false(c->joint[0].home_required || c->joint[0].has_home_method || c->joint[0].has_following_window);
    assert_true(c->joint[2].temperature_scale == 1.0); /* the default */
    assert_false(c->joint[1].brake.given);
    assert_true(c->joint[1].home_required);
    assert_true(c->joint[1].has_home_method && c->joint[1].home_method == 35);
    assert_true(c->joint[1].has_home_offset && c->joint[1].home_offset_rad == 0.25);
    assert_true(c->joint[1].has_following_window && c->joint[1].following_window_rad == 0.02);
    assert_true(c->joint[1].has_following_timeout && c->joint[1].following_timeout_ms == 50);
    f->cfg.n_links = 1;
    strcpy(f->cfg.links[0], "slcan:pty:/tmp/a");
    strcpy(f->cfg.dio, "none");
    assert_int_equal(ls_config_validate(&f->cfg, f->msg, sizeof f->msg), 0);
}

static void test_drive_keys_refuse_bad_values_naming_what_is_allowed(void **state)
{
    fx_t *f = *state;
    refused(f, "[drives]\nlink = can0\n",
            "2: [drives] link: got 'can0', expected socketcan:IFNAME, slcan:tty:PATH (a serial SLCAN adapter) or "
            "slcan:pty:PATH (the drive bus, its own CAN bus)");
    refused(f, "[drives]\nbitrate = 1000001\n",
            "2: [drives] bitrate: got '1000001', expected a CANopen bitrate: 10000, 20000, 50000, 100000, 125000, "
            "250000, 500000, 800000 or 1000000 bit/s");
    refused(f, "[drives]\ncycle = 0\n",
            "2: [drives] cycle: got '0', expected 1..100 (control periods per drive cycle: the SYNC period is "
            "cycle / rate_hz)");
    refused(f, "[drives]\nabort_connection = stop\n",
            "2: [drives] abort_connection: got 'stop', expected quick_stop, fault, disable_voltage or none (what a "
            "drive does when the controller's heartbeat stops: CiA 402 0x6007)");
    refused(f, "[joint.7]\nnode = 1\n",
            "1: unknown section [joint.7]; expected [device], [hal], [control], [dio], [manual], [drives], [joint.1] "
            ".. [joint.6], [robot] or [security]");
    refused(f, "[joint.2]\nnode = 128\n",
            "2: [joint.2] node: got '128', expected 1..127 (the drive's CANopen node id)");
    refused(f, "[joint.2]\ncounts_per_rad = nan\n",
            "2: [joint.2] counts_per_rad: got 'nan', expected a number 0.001..1e12 (the drive's position units per "
            "joint radian: encoder counts per motor turn x gear ratio / 2 pi)");
    refused(f, "[joint.2]\nsign = 2\n",
            "2: [joint.2] sign: got '2', expected 1 or -1 (-1 when the drive counts against the joint's positive "
            "direction)");
    refused(f, "[joint.1]\nnode = 1\nnode = 2\n", "3: [joint.1] node: given twice (first on line 2); keep one");
    refused(f, "[joint.1]\nnodes = 1\n",
            "2: [joint.1] nodes: unknown key; expected one of node, eds, counts_per_rad, sign, offset_rad, "
            "velocity_counts_per_rad_s, home_required, home_method, home_offset_rad, following_window_rad, "
            "following_timeout_ms, brake, sto, temperature, temperature_scale");
    refused(f, "[drives]\nquick_stop_option = 9\n",
            "2: [drives] quick_stop_option: got '9', expected 0..8 (CiA 402 0x605A: how a drive stops on a quick "
            "stop; 2 = on the quick-stop ramp, then switched off), or nothing for each drive's own setting");
    refused(f, "[drives]\nreadouts = velocity, current\n",
            "2: [drives] readouts: got 'velocity, current', expected a comma-separated list of velocity and torque "
            "(the actual values each drive maps for the per-axis readouts; each costs bus time), or nothing for none");
    refused(f, "[joint.3]\nbrake = 0x2100\n",
            "2: [joint.3] brake: got '0x2100', expected INDEX:SUB/BIT, e.g. 0x2100:01/0 (the drive's object and bit "
            "that say its holding brake is engaged; '!' first when the bit clear says it), or nothing for none");
    refused(f, "[joint.3]\nsto = 0x2100:02/32\n",
            "2: [joint.3] sto: got '0x2100:02/32', expected INDEX:SUB/BIT, e.g. 0x2100:02/0 (the drive's object and "
            "bit that say its safe torque off is active; '!' first when the bit clear says it), or nothing for none");
    refused(f, "[joint.3]\ntemperature = 0x2100:03/1\n",
            "2: [joint.3] temperature: got '0x2100:03/1', expected INDEX:SUB, e.g. 0x2100:03 (the drive's "
            "temperature object), or nothing for none");
    refused(f, "[joint.3]\nhome_method = 200\n",
            "2: [joint.3] home_method: got '200', expected -128..127 (the drive's homing method 0x6098, e.g. 37: "
            "home where it stands), or nothing for the drive's own setting");
    refused(f, "[joint.3]\nhome_required = maybe\n",
            "2: [joint.3] home_required: got 'maybe', expected true or false (true: the joint has an incremental "
            "encoder and nothing moves it until sendCommand home has homed it)");
    refused(f, "[joint.3]\nfollowing_window_rad = 0\n",
            "2: [joint.3] following_window_rad: got '0', expected radians above 0 up to 1000 (the drive's following "
            "error window 0x6065), or nothing for the drive's own setting");
    refused(f, "[joint.3]\nfollowing_timeout_ms = 70000\n",
            "2: [joint.3] following_timeout_ms: got '70000', expected 0..65535 ms (the drive's following error "
            "time-out 0x6066), or nothing for the drive's own setting");
}

static void test_an_empty_drive_value_means_the_drives_own_setting(void **state)
{
    fx_t *f = *state;
    assert_int_equal(load(f, "[drives]\nquick_stop_option =\nreadouts =\n[joint.4]\nhome_method =\nbrake =\n"
                             "home_offset_rad =\nfollowing_window_rad =\nfollowing_timeout_ms =\n"),
                     0);
    assert_false(f->cfg.drives_has_quick_stop);
    assert_int_equal(f->cfg.drives_readouts, 0);
    const ls_config_joint_t *j = &f->cfg.joint[3];
    assert_false(j->has_home_method || j->has_home_offset || j->has_following_window || j->has_following_timeout);
    assert_false(j->brake.given);
}

static void test_validate_a_drive_configuration(void **state)
{
    fx_t *f = *state;
    ls_config_t *c = &f->cfg;
    assert_int_equal(load(f, DRIVES_FILE), 0);
    c->n_links = 1;
    strcpy(c->links[0], "slcan:pty:/tmp/a");
    strcpy(c->dio, "none");
    c->joint[3].node = 0x70;
    invalid(f, "[joint.4] node = 0x70 is the controller's own [drives] master_node: give each drive and the "
               "controller distinct node ids");
    c->joint[3].node = 0x21;
    invalid(f, "[joint.4] node = 0x21 is also [joint.1]'s: each drive has its own node id");
    c->joint[3].node = 0x24;
    c->joint[4].eds[0] = '\0';
    invalid(f, "[joint.5]: eds is missing: arm = cia402 needs [joint.1] .. [joint.6], each with node, eds and "
               "counts_per_rad (docs/deploy.md \"Drives\")");
    strcpy(c->joint[4].eds, "/a.eds");
    c->joint[5].present = false;
    invalid(f, "[joint.6]: the section is missing: arm = cia402 needs [joint.1] .. [joint.6], each with node, eds "
               "and counts_per_rad (docs/deploy.md \"Drives\")");
    c->joint[5].present = true;
    c->drives_heartbeat_timeout_ms = 50;
    invalid(f, "[drives] heartbeat_timeout_ms = 50 is not above heartbeat_ms = 50: one late heartbeat would lose a "
               "drive; use at least 2 x heartbeat_ms plus a margin");
    c->drives_heartbeat_timeout_ms = 175;
    c->drives_link[0] = '\0';
    invalid(f, "[hal] arm = cia402 needs the drive bus: 'link = socketcan:IFNAME' (or slcan:tty:PATH) under [drives] "
               "in the --config file (docs/deploy.md \"Drives\")");
    strcpy(c->drives_link, "socketcan:can1");
    assert_int_equal(ls_config_validate(c, f->msg, sizeof f->msg), 0);
    /* drives described for an arm that is not cia402: said, not ignored */
    strcpy(c->arm, "sim");
    invalid(f, "[drives] and [joint.N] describe CiA 402 drives, but [hal] arm = sim: set arm = cia402 to drive "
               "them, or remove those sections");
}

int tc_run_config_tests(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_defaults, setup, teardown),
        cmocka_unit_test_setup_teardown(test_disconnect_action, setup, teardown),
        cmocka_unit_test_setup_teardown(test_good_file_sets_every_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_shipped_config_is_valid, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bool_and_number_spellings, setup, teardown),
        cmocka_unit_test_setup_teardown(test_indented_line_is_its_own_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unknown_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_key_in_wrong_section, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unknown_section, setup, teardown),
        cmocka_unit_test_setup_teardown(test_key_outside_section, setup, teardown),
        cmocka_unit_test_setup_teardown(test_wrong_type, setup, teardown),
        cmocka_unit_test_setup_teardown(test_wrong_types_of_each_kind, setup, teardown),
        cmocka_unit_test_setup_teardown(test_out_of_range, setup, teardown),
        cmocka_unit_test_setup_teardown(test_duplicate_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_duplicate_key_across_repeated_section, setup, teardown),
        cmocka_unit_test_setup_teardown(test_links_repeat_up_to_four, setup, teardown),
        cmocka_unit_test_setup_teardown(test_missing_file, setup, teardown),
        cmocka_unit_test_setup_teardown(test_syntax_error, setup, teardown),
        cmocka_unit_test_setup_teardown(test_first_error_wins, setup, teardown),
        cmocka_unit_test_setup_teardown(test_line_too_long, setup, teardown),
        cmocka_unit_test_setup_teardown(test_byte_order_mark_and_nul, setup, teardown),
        cmocka_unit_test_setup_teardown(test_skeleton_options_keep_working, setup, teardown),
        cmocka_unit_test_setup_teardown(test_every_option, setup, teardown),
        cmocka_unit_test_setup_teardown(test_robot_model_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_options_override_the_file, setup, teardown),
        cmocka_unit_test_setup_teardown(test_later_option_wins, setup, teardown),
        cmocka_unit_test_setup_teardown(test_option_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_config_error_through_args_keeps_check, setup, teardown),
        cmocka_unit_test_setup_teardown(test_missing_config_through_args, setup, teardown),
        cmocka_unit_test_setup_teardown(test_help, setup, teardown),
        cmocka_unit_test_setup_teardown(test_validate, setup, teardown),
        cmocka_unit_test_setup_teardown(test_manual_keys_set_the_maps_and_the_gates, setup, teardown),
        cmocka_unit_test_setup_teardown(test_manual_defaults_are_the_simulated_devices_and_four_steps, setup, teardown),
        cmocka_unit_test_setup_teardown(test_manual_keys_refuse_bad_values, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_teachpendant_without_an_enabling_switch_is_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_drive_configuration_sets_every_drive_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_drive_keys_refuse_bad_values_naming_what_is_allowed, setup, teardown),
        cmocka_unit_test_setup_teardown(test_validate_a_drive_configuration, setup, teardown),
        cmocka_unit_test_setup_teardown(test_an_empty_drive_value_means_the_drives_own_setting, setup, teardown),
    };
    return cmocka_run_group_tests_name("config", tests, NULL, NULL);
}
