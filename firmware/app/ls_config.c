/* landscaped's configuration: INI file (inih) + getopt_long options, one key
 * table for both so a key and its option cannot disagree on what they accept. */
#include "ls_config.h"
#include "ls_keys.h"

#include "faulty_link.h"
#include "ls_ini_line.h"
#include "landscape.pb.h"
#include "ls_err.h"

#include <ctype.h>
#include <errno.h>
#include <getopt.h>
#include <ini.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- value parsers: LS_OK or LS_EINVAL; `why` gets the "expected ..." text */

static int copy_str(char *dst, size_t size, const char *src)
{
    size_t n = strlen(src);
    if (n >= size) {
        return LS_EINVAL;
    }
    memcpy(dst, src, n + 1);
    return 0;
}

/* Unsigned with C prefixes (0x10, 16); no sign, no blanks, no trailing junk. */
static int parse_u32(const char *s, uint32_t lo, uint32_t hi, uint32_t *out)
{
    if (!isdigit((unsigned char)s[0])) {
        return LS_EINVAL;
    }
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 0);
    if (errno != 0 || *end != '\0' || v < lo || v > hi) {
        return LS_EINVAL;
    }
    *out = (uint32_t)v;
    return 0;
}

static int parse_int(const char *s, long lo, long hi, int *out)
{
    const char *p = s[0] == '-' ? s + 1 : s;
    if (!isdigit((unsigned char)p[0])) {
        return LS_EINVAL;
    }
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno != 0 || *end != '\0' || v < lo || v > hi) {
        return LS_EINVAL;
    }
    *out = (int)v;
    return 0;
}

/* A finite decimal within [lo, hi]; no blanks, no trailing junk. */
static int parse_double(const char *s, double lo, double hi, double *out)
{
    if (s[0] == '\0' || isspace((unsigned char)s[0])) {
        return LS_EINVAL;
    }
    char *end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (errno != 0 || *end != '\0' || !isfinite(v) || v < lo || v > hi) {
        return LS_EINVAL;
    }
    *out = v;
    return 0;
}

static int parse_bool(const char *s, bool *out)
{
    static const char *yes[] = { "true", "yes", "on", "1" };
    static const char *no[] = { "false", "no", "off", "0" };
    for (size_t i = 0; i < 4; i++) {
        if (strcasecmp(s, yes[i]) == 0) {
            *out = true;
            return 0;
        }
        if (strcasecmp(s, no[i]) == 0) {
            *out = false;
            return 0;
        }
    }
    return LS_EINVAL;
}

/* "0,1, 2" -> offsets; "" -> none. */
static int parse_offsets(const char *s, unsigned *offs, uint8_t *n_out, char *why, size_t whylen)
{
    static const char *expected = "a comma-separated list of at most 16 distinct line offsets 0..1023, e.g. 0,1,2";
    uint8_t n = 0;
    const char *p = s;
    while (*p == ' ' || *p == '\t') {
        p++;
    }
    while (*p != '\0') {
        if (!isdigit((unsigned char)*p)) {
            snprintf(why, whylen, "%s", expected);
            return LS_EINVAL;
        }
        char *end = NULL;
        errno = 0;
        unsigned long v = strtoul(p, &end, 10);
        if (errno != 0 || v > LS_CONFIG_MAX_OFFSET || n >= LS_CONFIG_MAX_LINES) {
            snprintf(why, whylen, "%s", expected);
            return LS_EINVAL;
        }
        for (uint8_t i = 0; i < n; i++) {
            if (offs[i] == v) {
                snprintf(why, whylen, "%s (%lu is listed twice)", expected, v);
                return LS_EINVAL;
            }
        }
        offs[n++] = (unsigned)v;
        p = end;
        while (*p == ' ' || *p == '\t') {
            p++;
        }
        if (*p == ',') {
            p++;
            while (*p == ' ' || *p == '\t') {
                p++;
            }
            if (*p == '\0') {
                snprintf(why, whylen, "%s", expected);
                return LS_EINVAL;
            }
        } else if (*p != '\0') {
            snprintf(why, whylen, "%s", expected);
            return LS_EINVAL;
        }
    }
    *n_out = n;
    return 0;
}

/* ---- one setter per key ------------------------------------------------ */

typedef int (*setter_fn)(ls_config_t *cfg, const char *v, char *why, size_t whylen);

#define EXPECT(...) (snprintf(why, whylen, __VA_ARGS__), -1)

static int set_name(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    size_t n = strlen(v);
    bool printable = n > 0;
    for (size_t i = 0; i < n; i++) {
        printable = printable && isprint((unsigned char)v[i]);
    }
    if (!printable || copy_str(cfg->name, sizeof cfg->name, v) != 0) {
        return EXPECT("1..%zu printable characters (device name reported at connect)", sizeof cfg->name - 1);
    }
    return 0;
}

static int set_node(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    uint32_t x;
    if (parse_u32(v, 1, 0xFE, &x) != 0) {
        return EXPECT("1..0xFE (node address; 0xFF is the broadcast address)");
    }
    cfg->node = (uint8_t)x;
    return 0;
}

static int set_heartbeat(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 50, 600000, &cfg->heartbeat_timeout_ms) != 0) {
        return EXPECT("milliseconds 50..600000 (drop a supervisor after this long without heartbeat)");
    }
    return 0;
}

/* The schema's names (ls.DisconnectAction) in lower case without DISCONNECT_:
 * the one list is the enum; DISCONNECT_CONFIGURED is not a configuration. */
static int set_disconnect_action(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    static const char prefix[] = "DISCONNECT_";
    char names[96];
    size_t used = 0;
    names[0] = '\0';
    for (int a = (int)_ls_DisconnectAction_MIN + 1; a <= (int)_ls_DisconnectAction_MAX; a++) {
        const char *full = ls_DisconnectAction_name((ls_DisconnectAction)a);
        char low[48];
        size_t n = 0;
        for (const char *c = full + sizeof prefix - 1; *c != '\0' && n + 1 < sizeof low; c++) {
            low[n++] = (char)tolower((unsigned char)*c);
        }
        low[n] = '\0';
        if (strcmp(v, low) == 0) {
            cfg->disconnect_action = (uint8_t)a;
            return 0;
        }
        int w = snprintf(names + used, sizeof names - used, "%s%s", used > 0 ? ", " : "", low);
        used += w > 0 && (size_t)w < sizeof names - used ? (size_t)w : 0u;
    }
    return EXPECT("%s (what the disconnect handler does when the owner is lost, seed 2.2)", names);
}

static int set_link(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    static const char *forms = "slcan:pty:PATH or socketcan:IFNAME";
    if (strncmp(v, "slcan:pty:", 10) == 0) {
        if (v[10] == '\0') {
            return EXPECT("%s (slcan:pty: needs the PATH of the symlink to create)", forms);
        }
    } else if (strncmp(v, "socketcan:", 10) == 0) {
        const char *ifn = v + 10;
        size_t n = strlen(ifn);
        bool ok = n > 0 && n < 16 && strcmp(ifn, ".") != 0 && strcmp(ifn, "..") != 0;
        for (size_t i = 0; ok && i < n; i++) {
            ok = isgraph((unsigned char)ifn[i]) && ifn[i] != '/' && ifn[i] != ':';
        }
        if (!ok) {
            return EXPECT("%s (IFNAME is a network interface name of 1..15 characters, e.g. can0)", forms);
        }
    } else {
        return EXPECT("%s (unknown link kind)", forms);
    }
    for (size_t i = 0; i < cfg->n_links; i++) {
        if (strcmp(cfg->links[i], v) == 0) {
            return EXPECT("%s, each link once (this one is already listed)", forms);
        }
    }
    if (cfg->n_links >= LS_CONFIG_MAX_LINKS) {
        return EXPECT("%s, at most %d links", forms, LS_CONFIG_MAX_LINKS);
    }
    if (copy_str(cfg->links[cfg->n_links], sizeof cfg->links[0], v) != 0) {
        return EXPECT("%s of at most %zu characters", forms, sizeof cfg->links[0] - 1);
    }
    cfg->n_links++;
    return 0;
}

static int set_arm(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (strcmp(v, "sim") != 0 && strcmp(v, "cia402") != 0 && strcmp(v, "none") != 0) {
        return EXPECT("sim, cia402 or none (the ODE-simulated arm, CiA 402 drives on the [drives] bus, or no arm)");
    }
    (void)copy_str(cfg->arm, sizeof cfg->arm, v);
    return 0;
}

static int set_dio(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    bool ok = strcmp(v, "sim") == 0 || strcmp(v, "none") == 0 || (strncmp(v, "gpiod:", 6) == 0 && v[6] != '\0');
    if (!ok || copy_str(cfg->dio, sizeof cfg->dio, v) != 0) {
        return EXPECT("sim, none or gpiod:CHIP (CHIP as gpiochip0, 0, /dev/gpiochip0 or a chip label)");
    }
    return 0;
}

static int set_dio_socket(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (copy_str(cfg->dio_socket, sizeof cfg->dio_socket, v) != 0) {
        return EXPECT("a socket path of at most %zu characters, or nothing for none", sizeof cfg->dio_socket - 1);
    }
    return 0;
}

static int set_link_faults(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    hal_sim_fault_config_t fc;
    if (v[0] == '\0') {
        cfg->link_faults[0] = '\0';
        return 0;
    }
    if (copy_str(cfg->link_faults, sizeof cfg->link_faults, v) != 0) {
        return EXPECT("a fault spec of at most %zu characters", sizeof cfg->link_faults - 1);
    }
    char m[200];
    if (hal_sim_fault_parse(v, &fc, m, sizeof m) != LS_OK) {
        cfg->link_faults[0] = '\0';
        return EXPECT("a fault spec as in docs/reliability.md (%s)", m);
    }
    return 0;
}

/* A file path ("" = no trace); the simulated arm creates PATH.tmp at start
 * and renames it to PATH at exit, so a directory ("dir/") is no file name. */
static int set_setpoint_trace(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    size_t n = strlen(v);
    if ((n > 0 && v[n - 1] == '/') || copy_str(cfg->setpoint_trace, sizeof cfg->setpoint_trace, v) != 0) {
        cfg->setpoint_trace[0] = '\0';
        return EXPECT("the path of a file to write, of at most %zu characters, or nothing for none",
                      sizeof cfg->setpoint_trace - 1);
    }
    return 0;
}

static int set_clock(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (strcmp(v, "realtime") != 0 && strcmp(v, "lockstep") != 0) {
        return EXPECT("realtime or lockstep (lockstep: virtual time advancing exactly one period per cycle)");
    }
    (void)copy_str(cfg->clock, sizeof cfg->clock, v);
    return 0;
}

/* The robot model file ("" = the compiled-in ls-sim6); its contents are
 * checked when landscaped loads it (ls_robot_config.h). */
static int set_model(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    size_t n = strlen(v);
    if ((n > 0 && v[n - 1] == '/') || copy_str(cfg->model, sizeof cfg->model, v) != 0) {
        cfg->model[0] = '\0';
        return EXPECT("the path of a robot model file, of at most %zu characters, or nothing for the compiled-in "
                      "ls-sim6",
                      sizeof cfg->model - 1);
    }
    return 0;
}

static int set_rate(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 100, 10000, &cfg->rate_hz) != 0) {
        return EXPECT("100..10000 (control cycles per second)");
    }
    return 0;
}

static int set_telemetry(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 0, 200, &cfg->telemetry_hz) != 0) {
        return EXPECT("0..200 (telemetry frames per second; 0 = off)");
    }
    return 0;
}

static int set_rt_priority(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_int(v, 0, 99, &cfg->rt_priority) != 0) {
        return EXPECT("0..99 (SCHED_FIFO priority of the control thread; 0 = normal thread)");
    }
    return 0;
}

static int set_rt_cpu(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_int(v, -1, 1023, &cfg->rt_cpu) != 0) {
        return EXPECT("-1..1023 (CPU to pin the control thread to; -1 = no pinning)");
    }
    return 0;
}

static int set_auth_policy(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (strcmp(v, "unsigned") == 0) {
        cfg->auth_policy = (uint8_t)ls_AuthPolicy_AUTH_UNSIGNED;
    } else if (strcmp(v, "signed") == 0) {
        cfg->auth_policy = (uint8_t)ls_AuthPolicy_AUTH_SIGNED;
    } else {
        return EXPECT("unsigned (anyone on the bus may connect) or signed (only supervisors holding a key of "
                      "key_file)");
    }
    return 0;
}

static int set_key_file(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    size_t n = strlen(v);
    if ((n > 0 && v[n - 1] == '/') || copy_str(cfg->key_file, sizeof cfg->key_file, v) != 0) {
        cfg->key_file[0] = '\0';
        return EXPECT("the path of the supervisors' key file (mode 0600), of at most %zu characters, or nothing",
                      sizeof cfg->key_file - 1);
    }
    return 0;
}

static int set_unsigned_queries(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_bool(v, &cfg->unsigned_queries) != 0) {
        return EXPECT("true or false (also yes/no, on/off, 1/0)");
    }
    return 0;
}

static int set_lock_memory(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_bool(v, &cfg->lock_memory) != 0) {
        return EXPECT("true or false (also yes/no, on/off, 1/0)");
    }
    return 0;
}

static int set_inputs(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    return parse_offsets(v, cfg->input_offsets, &cfg->n_inputs, why, whylen);
}

static int set_outputs(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    return parse_offsets(v, cfg->output_offsets, &cfg->n_outputs, why, whylen);
}

static int set_estop(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_int(v, -1, LS_CONFIG_MAX_LINES - 1, &cfg->estop_input) != 0) {
        return EXPECT("-1..%d (input bit index that stops everything when active; -1 = none)", LS_CONFIG_MAX_LINES - 1);
    }
    return 0;
}

/* ---- [drives] */

static int set_drives_link(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    static const char *forms = "socketcan:IFNAME, slcan:tty:PATH (a serial SLCAN adapter) or slcan:pty:PATH";
    bool ok = false;
    if (strncmp(v, "socketcan:", 10) == 0) {
        const char *ifn = v + 10;
        const size_t n = strlen(ifn);
        ok = n > 0 && n < 16 && strchr(ifn, '/') == NULL && strchr(ifn, ':') == NULL;
    } else if (strncmp(v, "slcan:tty:", 10) == 0 || strncmp(v, "slcan:pty:", 10) == 0) {
        ok = v[10] != '\0';
    }
    if (!ok || copy_str(cfg->drives_link, sizeof cfg->drives_link, v) != 0) {
        return EXPECT("%s (the drive bus, its own CAN bus)", forms);
    }
    return 0;
}

static int set_drives_bitrate(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    static const uint32_t rates[] = { 10000, 20000, 50000, 100000, 125000, 250000, 500000, 800000, 1000000 };
    uint32_t x = 0;
    if (parse_u32(v, 1, 1000000, &x) == 0) {
        for (size_t i = 0; i < sizeof rates / sizeof rates[0]; i++) {
            if (rates[i] == x) {
                cfg->drives_bitrate = x;
                return 0;
            }
        }
    }
    return EXPECT("a CANopen bitrate: 10000, 20000, 50000, 100000, 125000, 250000, 500000, 800000 or 1000000 bit/s");
}

static int set_drives_cycle(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 1, 100, &cfg->drives_cycle) != 0) {
        return EXPECT("1..100 (control periods per drive cycle: the SYNC period is cycle / rate_hz)");
    }
    return 0;
}

static int set_drives_master_node(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    uint32_t x;
    if (parse_u32(v, 1, 127, &x) != 0) {
        return EXPECT("1..127 (the controller's CANopen node id on the drive bus: its heartbeat's id)");
    }
    cfg->drives_master_node = (uint8_t)x;
    return 0;
}

static int set_drives_heartbeat(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 10, 10000, &cfg->drives_heartbeat_ms) != 0) {
        return EXPECT("10..10000 ms (the controller's heartbeat period, and each drive's, 0x1017)");
    }
    return 0;
}

static int set_drives_heartbeat_timeout(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 20, 60000, &cfg->drives_heartbeat_timeout_ms) != 0) {
        return EXPECT("20..60000 ms (a drive, or the controller, is lost after this long without heartbeat)");
    }
    return 0;
}

static int set_drives_boot_timeout(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 100, 60000, &cfg->drives_boot_timeout_ms) != 0) {
        return EXPECT("100..60000 ms (each drive's boot-up and configuration at start)");
    }
    return 0;
}

static int set_drives_budget(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 10, 100, &cfg->drives_budget_pct) != 0) {
        return EXPECT("10..100 (per cent of the bus a drive cycle may take, worst-case bit stuffing included)");
    }
    return 0;
}

static int set_drives_abort(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    static const struct {
        const char *name;
        ls_drive_abort_t value;
    } k[] = { { "none", LS_DRIVE_ABORT_NONE },
              { "fault", LS_DRIVE_ABORT_FAULT },
              { "disable_voltage", LS_DRIVE_ABORT_DISABLE_VOLTAGE },
              { "quick_stop", LS_DRIVE_ABORT_QUICK_STOP } };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        if (strcmp(v, k[i].name) == 0) {
            cfg->drives_abort = (uint8_t)k[i].value;
            return 0;
        }
    }
    return EXPECT("quick_stop, fault, disable_voltage or none (what a drive does when the controller's "
                  "heartbeat stops: CiA 402 0x6007)");
}

static int set_drives_stale(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 2, 100, &cfg->drives_stale_cycles) != 0) {
        return EXPECT("2..100 (drive cycles a drive's feedback (TPDO) may miss before the drive counts as lost)");
    }
    return 0;
}

static int set_drives_feedforward(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    if (parse_bool(v, &cfg->drives_feedforward) != 0) {
        return EXPECT("true or false (map the velocity feed-forward 0x60B1 where a drive can)");
    }
    return 0;
}

static int set_drives_quick_stop(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    cfg->drives_has_quick_stop = v[0] != '\0';
    if (cfg->drives_has_quick_stop && parse_int(v, 0, 8, &cfg->drives_quick_stop) != 0) {
        return EXPECT("0..8 (CiA 402 0x605A: how a drive stops on a quick stop; 2 = on the quick-stop ramp, then "
                      "switched off), or nothing for each drive's own setting");
    }
    return 0;
}

static int set_drives_readouts(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    static const struct {
        const char *name;
        uint32_t bit;
    } k[] = { { "velocity", LS_CONFIG_READOUT_VELOCITY }, { "torque", LS_CONFIG_READOUT_TORQUE } };
    uint32_t bits = 0;
    const char *p = v;
    while (*p != '\0') {
        while (*p == ' ' || *p == ',') {
            p++;
        }
        size_t n = strcspn(p, ", ");
        if (n == 0) {
            break;
        }
        size_t i = 0;
        while (i < sizeof k / sizeof k[0] && !(strlen(k[i].name) == n && strncmp(k[i].name, p, n) == 0)) {
            i++;
        }
        if (i == sizeof k / sizeof k[0]) {
            return EXPECT("a comma-separated list of velocity and torque (the actual values each drive maps for the "
                          "per-axis readouts; each costs bus time), or nothing for none");
        }
        bits |= k[i].bit;
        p += n;
    }
    cfg->drives_readouts = bits;
    return 0;
}

/* "INDEX:SUB" (allow_bit false) or "[!]INDEX:SUB/BIT" (BIT 0 when absent);
 * "" clears it. Numbers in C notation. LS_EINVAL for anything else, *out
 * untouched. */
static int parse_obj(const char *v, bool allow_bit, ls_config_obj_t *out)
{
    ls_config_obj_t o = { 0 };
    if (v[0] == '\0') {
        *out = o;
        return 0;
    }
    const char *p = v;
    if (allow_bit && *p == '!') {
        o.inverted = true;
        p++;
    }
    char buf[40];
    if (copy_str(buf, sizeof buf, p) != 0) {
        return LS_EINVAL;
    }
    char *bit = allow_bit ? strchr(buf, '/') : NULL;
    if (bit != NULL) {
        *bit++ = '\0';
    }
    char *sub = strchr(buf, ':');
    if (sub == NULL) {
        return LS_EINVAL;
    }
    *sub++ = '\0';
    uint32_t index = 0, s = 0, b = 0;
    if (parse_u32(buf, 0x1000, 0xFFFF, &index) != 0 || parse_u32(sub, 0, 0xFF, &s) != 0 ||
        (bit != NULL && parse_u32(bit, 0, 31, &b) != 0)) {
        return LS_EINVAL;
    }
    o.given = true;
    o.index = (uint16_t)index;
    o.sub = (uint8_t)s;
    o.bit = (uint8_t)b;
    *out = o;
    return 0;
}

/* ---- [joint.N] */

typedef int (*joint_setter_fn)(ls_config_joint_t *j, const char *v, char *why, size_t whylen);

static int set_joint_node(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    uint32_t x;
    if (parse_u32(v, 1, 127, &x) != 0) {
        return EXPECT("1..127 (the drive's CANopen node id)");
    }
    j->node = (uint8_t)x;
    return 0;
}

static int set_joint_eds(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (v[0] == '\0' || copy_str(j->eds, sizeof j->eds, v) != 0) {
        return EXPECT("the path of the drive's EDS or DCF file, of at most %zu characters", sizeof j->eds - 1);
    }
    return 0;
}

static int set_joint_counts(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_double(v, 1e-3, 1e12, &j->counts_per_rad) != 0) {
        return EXPECT("a number 0.001..1e12 (the drive's position units per joint radian: encoder counts "
                      "per motor turn x gear ratio / 2 pi)");
    }
    return 0;
}

static int set_joint_vel_counts(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_double(v, 1e-6, 1e12, &j->vel_counts_per_rad_s) != 0) {
        return EXPECT("a number 1e-6..1e12 (the drive's velocity units per joint rad/s)");
    }
    return 0;
}

static int set_joint_sign(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (strcmp(v, "1") == 0 || strcmp(v, "+1") == 0) {
        j->sign = 1;
    } else if (strcmp(v, "-1") == 0) {
        j->sign = -1;
    } else {
        return EXPECT("1 or -1 (-1 when the drive counts against the joint's positive direction)");
    }
    return 0;
}

static int set_joint_offset(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_double(v, -1e3, 1e3, &j->offset_rad) != 0) {
        return EXPECT("radians -1000..1000 (the joint angle at which the drive reads 0)");
    }
    return 0;
}

static int set_joint_home_required(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_bool(v, &j->home_required) != 0) {
        return EXPECT("true or false (true: the joint has an incremental encoder and nothing moves it until "
                      "sendCommand home has homed it)");
    }
    return 0;
}

static int set_joint_home_method(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    j->has_home_method = v[0] != '\0';
    if (j->has_home_method && parse_int(v, -128, 127, &j->home_method) != 0) {
        return EXPECT("-128..127 (the drive's homing method 0x6098, e.g. 37: home where it stands), or nothing for "
                      "the drive's own setting");
    }
    return 0;
}

static int set_joint_home_offset(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    j->has_home_offset = v[0] != '\0';
    if (j->has_home_offset && parse_double(v, -1e3, 1e3, &j->home_offset_rad) != 0) {
        return EXPECT("radians -1000..1000 (the joint angle at the home position, written as 0x607C), or nothing for "
                      "the drive's own setting");
    }
    return 0;
}

static int set_joint_following_window(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    j->has_following_window = v[0] != '\0';
    if (j->has_following_window && parse_double(v, 1e-9, 1e3, &j->following_window_rad) != 0) {
        return EXPECT("radians above 0 up to 1000 (the drive's following error window 0x6065), or nothing for the "
                      "drive's own setting");
    }
    return 0;
}

static int set_joint_following_timeout(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    j->has_following_timeout = v[0] != '\0';
    if (j->has_following_timeout && parse_u32(v, 0, 65535, &j->following_timeout_ms) != 0) {
        return EXPECT("0..65535 ms (the drive's following error time-out 0x6066), or nothing for the drive's own "
                      "setting");
    }
    return 0;
}

static int set_joint_brake(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_obj(v, true, &j->brake) != 0) {
        return EXPECT("INDEX:SUB/BIT, e.g. 0x2100:01/0 (the drive's object and bit that say its holding brake is "
                      "engaged; '!' first when the bit clear says it), or nothing for none");
    }
    return 0;
}

static int set_joint_sto(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_obj(v, true, &j->sto) != 0) {
        return EXPECT("INDEX:SUB/BIT, e.g. 0x2100:02/0 (the drive's object and bit that say its safe torque off is "
                      "active; '!' first when the bit clear says it), or nothing for none");
    }
    return 0;
}

static int set_joint_temperature(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_obj(v, false, &j->temperature) != 0) {
        return EXPECT("INDEX:SUB, e.g. 0x2100:03 (the drive's temperature object), or nothing for none");
    }
    return 0;
}

static int set_joint_temperature_scale(ls_config_joint_t *j, const char *v, char *why, size_t whylen)
{
    if (parse_double(v, 1e-6, 1e6, &j->temperature_scale) != 0) {
        return EXPECT("a number 1e-6..1e6 (degrees Celsius per unit of the temperature object: 0.1 for tenths)");
    }
    return 0;
}

/* ---- [manual] ----------------------------------------------------------- */

static int set_manual_path(ls_config_t *cfg, ls_manual_kind_t k, const char *v, char *why, size_t whylen)
{
    if ((v[0] != '\0' && v[0] != '/') || copy_str(cfg->manual[k].path, sizeof cfg->manual[k].path, v) != 0) {
        cfg->manual[k].path[0] = '\0';
        return EXPECT(
            "an absolute device path of at most %zu characters (e.g. /dev/input/by-id/usb-...-event-joystick), "
            "or nothing for none",
            sizeof cfg->manual[k].path - 1);
    }
    return 0;
}

static int set_manual_map(ls_config_t *cfg, ls_manual_kind_t k, const char *v, char *why, size_t whylen)
{
    hal_evdev_map_t m;
    if (hal_evdev_map_default(v, &m) != LS_OK) {
        return EXPECT("%s (the default map to start from)", hal_evdev_map_names());
    }
    (void)copy_str(cfg->manual[k].map_name, sizeof cfg->manual[k].map_name, v);
    return 0;
}

/* For axes, buttons and the dead band, nothing means the map's. */
static int set_manual_axes(ls_config_t *cfg, ls_manual_kind_t k, const char *v, char *why, size_t whylen)
{
    cfg->manual[k].axes_set = false;
    if (v[0] == '\0') {
        return 0;
    }
    if (hal_evdev_parse_axes(&cfg->manual[k].given, v, why, whylen) != LS_OK) {
        return LS_EINVAL;
    }
    cfg->manual[k].axes_set = true;
    return 0;
}

static int set_manual_buttons(ls_config_t *cfg, ls_manual_kind_t k, const char *v, char *why, size_t whylen)
{
    cfg->manual[k].buttons_set = false;
    if (v[0] == '\0') {
        return 0;
    }
    if (hal_evdev_parse_buttons(&cfg->manual[k].given, v, why, whylen) != LS_OK) {
        return LS_EINVAL;
    }
    cfg->manual[k].buttons_set = true;
    return 0;
}

static int set_manual_deadband(ls_config_t *cfg, ls_manual_kind_t k, const char *v, char *why, size_t whylen)
{
    cfg->manual[k].deadband = -1.0;
    if (v[0] == '\0') {
        return 0;
    }
    char *end = NULL;
    errno = 0;
    double x = strtod(v, &end);
    if (isspace((unsigned char)v[0]) || errno != 0 || *end != '\0' || !(x >= 0.0) || x > HAL_EVDEV_MAX_DEADBAND) {
        return EXPECT("0..%g (the share of full deflection that counts as still), or nothing for the map's",
                      HAL_EVDEV_MAX_DEADBAND);
    }
    cfg->manual[k].deadband = x;
    return 0;
}

static int set_manual_stale(ls_config_t *cfg, ls_manual_kind_t k, const char *v, char *why, size_t whylen)
{
    if (parse_u32(v, 0, 60000, &cfg->manual[k].stale_ms) != 0) {
        return EXPECT(
            "milliseconds 0..60000 (> 0: the device reports continuously, and a longer silence stops the jog; "
            "0: it reports changes only)");
    }
    return 0;
}

/* One setter per kind and key: the key table holds plain functions. */
#define MANUAL_SETTERS(kind, tag)                                                                                      \
    static int set_##tag(ls_config_t *cfg, const char *v, char *why, size_t whylen)                                    \
    {                                                                                                                  \
        return set_manual_path(cfg, kind, v, why, whylen);                                                             \
    }                                                                                                                  \
    static int set_##tag##_map(ls_config_t *cfg, const char *v, char *why, size_t whylen)                              \
    {                                                                                                                  \
        return set_manual_map(cfg, kind, v, why, whylen);                                                              \
    }                                                                                                                  \
    static int set_##tag##_axes(ls_config_t *cfg, const char *v, char *why, size_t whylen)                             \
    {                                                                                                                  \
        return set_manual_axes(cfg, kind, v, why, whylen);                                                             \
    }                                                                                                                  \
    static int set_##tag##_buttons(ls_config_t *cfg, const char *v, char *why, size_t whylen)                          \
    {                                                                                                                  \
        return set_manual_buttons(cfg, kind, v, why, whylen);                                                          \
    }                                                                                                                  \
    static int set_##tag##_deadband(ls_config_t *cfg, const char *v, char *why, size_t whylen)                         \
    {                                                                                                                  \
        return set_manual_deadband(cfg, kind, v, why, whylen);                                                         \
    }                                                                                                                  \
    static int set_##tag##_stale(ls_config_t *cfg, const char *v, char *why, size_t whylen)                            \
    {                                                                                                                  \
        return set_manual_stale(cfg, kind, v, why, whylen);                                                            \
    }
MANUAL_SETTERS(LS_MANUAL_TEACHPENDANT, pendant)
MANUAL_SETTERS(LS_MANUAL_SPACEBALL, spaceball)
#undef MANUAL_SETTERS

static int set_speed_steps(ls_config_t *cfg, const char *v, char *why, size_t whylen)
{
    unsigned offs[LS_CONFIG_MAX_LINES];
    uint8_t n = 0;
    char w[160];
    if (parse_offsets(v, offs, &n, w, sizeof w) != 0 || n == 0 || n > LS_MANUAL_MAX_STEPS) {
        n = 0;
    }
    for (uint8_t i = 0; i < n; i++) {
        if (offs[i] < 1u || offs[i] > 100u || (i > 0 && offs[i] <= offs[i - 1])) {
            n = 0;
        }
    }
    if (n == 0) {
        return EXPECT("1..%d ascending percentages 1..100, comma-separated (the jog's speed override steps), "
                      "e.g. 10,25,50,100",
                      LS_MANUAL_MAX_STEPS);
    }
    for (uint8_t i = 0; i < n; i++) {
        cfg->speed_steps[i] = (uint8_t)offs[i];
    }
    cfg->n_speed_steps = n;
    return 0;
}

#undef EXPECT

typedef struct {
    const char *key;
    joint_setter_fn set;
    bool required;
} joint_key_def_t;

static const joint_key_def_t JOINT_KEYS[] = {
    { "node", set_joint_node, true },
    { "eds", set_joint_eds, true },
    { "counts_per_rad", set_joint_counts, true },
    { "sign", set_joint_sign, false },
    { "offset_rad", set_joint_offset, false },
    { "velocity_counts_per_rad_s", set_joint_vel_counts, false },
    { "home_required", set_joint_home_required, false },
    { "home_method", set_joint_home_method, false },
    { "home_offset_rad", set_joint_home_offset, false },
    { "following_window_rad", set_joint_following_window, false },
    { "following_timeout_ms", set_joint_following_timeout, false },
    { "brake", set_joint_brake, false },
    { "sto", set_joint_sto, false },
    { "temperature", set_joint_temperature, false },
    { "temperature_scale", set_joint_temperature_scale, false },
};
#define N_JOINT_KEYS (sizeof JOINT_KEYS / sizeof JOINT_KEYS[0])

#define NO_JOINT (-1) /* joint_section: not a [joint.N] of this arm */

/* "joint.3" -> 2; NO_JOINT when `section` is no [joint.N] of this arm. */
static int joint_section(const char *section)
{
    if (strncmp(section, "joint.", 6) != 0 || section[6] < '1' || section[6] > '9' || section[7] != '\0') {
        return NO_JOINT;
    }
    const int n = section[6] - '0';
    return n <= LS_N_JOINTS ? n - 1 : NO_JOINT;
}

/* ---- the key table ----------------------------------------------------- */

typedef struct {
    const char *section;
    const char *key;
    const char *option; /* long option taking the value; NULL when file-only */
    bool repeatable;
    setter_fn set;
} key_def_t;

enum { KEY_LINK = 3 };

static const key_def_t KEYS[] = {
    { "device", "name", "name", false, set_name },
    { "device", "node", "node", false, set_node },
    { "device", "heartbeat_timeout_ms", "heartbeat-timeout", false, set_heartbeat },
    { "hal", "link", "link", true, set_link }, /* KEY_LINK */
    { "hal", "arm", "arm", false, set_arm },
    { "hal", "dio", "dio", false, set_dio },
    { "hal", "dio_socket", "dio-socket", false, set_dio_socket },
    { "hal", "link_faults", "link-faults", false, set_link_faults },
    { "hal", "setpoint_trace", "setpoint-trace", false, set_setpoint_trace },
    { "hal", "clock", "clock", false, set_clock },
    { "control", "rate_hz", "rate", false, set_rate },
    { "control", "telemetry_hz", "telemetry-hz", false, set_telemetry },
    { "control", "rt_priority", "rt-priority", false, set_rt_priority },
    { "control", "rt_cpu", "rt-cpu", false, set_rt_cpu },
    { "control", "lock_memory", NULL, false, set_lock_memory },
    { "dio", "inputs", "inputs", false, set_inputs },
    { "dio", "outputs", "outputs", false, set_outputs },
    { "dio", "estop_input", "estop-input", false, set_estop },
    { "device", "disconnect_action", "disconnect-action", false, set_disconnect_action },
    { "drives", "link", NULL, false, set_drives_link },
    { "drives", "bitrate", NULL, false, set_drives_bitrate },
    { "drives", "cycle", NULL, false, set_drives_cycle },
    { "drives", "master_node", NULL, false, set_drives_master_node },
    { "drives", "heartbeat_ms", NULL, false, set_drives_heartbeat },
    { "drives", "heartbeat_timeout_ms", NULL, false, set_drives_heartbeat_timeout },
    { "drives", "boot_timeout_ms", NULL, false, set_drives_boot_timeout },
    { "drives", "budget_pct", NULL, false, set_drives_budget },
    { "drives", "abort_connection", NULL, false, set_drives_abort },
    { "drives", "velocity_feedforward", NULL, false, set_drives_feedforward },
#define MANUAL_KEYS(name, tag)                                                                                         \
    { "manual", name, NULL, false, set_##tag }, { "manual", name "_map", NULL, false, set_##tag##_map },               \
        { "manual", name "_axes", NULL, false, set_##tag##_axes },                                                     \
        { "manual", name "_buttons", NULL, false, set_##tag##_buttons },                                               \
        { "manual", name "_deadband", NULL, false, set_##tag##_deadband },                                             \
    {                                                                                                                  \
        "manual", name "_stale_ms", NULL, false, set_##tag##_stale                                                     \
    }
    MANUAL_KEYS(LS_MANUAL_NAME_TEACHPENDANT, pendant),
    MANUAL_KEYS(LS_MANUAL_NAME_SPACEBALL, spaceball),
#undef MANUAL_KEYS
    { "manual", "speed_steps", NULL, false, set_speed_steps },
    { "drives", "stale_cycles", NULL, false, set_drives_stale },
    { "robot", "model", "model", false, set_model },
    { "drives", "quick_stop_option", NULL, false, set_drives_quick_stop },
    { "drives", "readouts", NULL, false, set_drives_readouts },
    /* file only: the keys' home is a file of their own, never a command line */
    { "security", "policy", NULL, false, set_auth_policy },
    { "security", "key_file", NULL, false, set_key_file },
    { "security", "unsigned_queries", NULL, false, set_unsigned_queries },
};
#define N_KEYS (sizeof KEYS / sizeof KEYS[0])

static const char *SECTIONS =
    "[device], [hal], [control], [dio], [manual], [drives], [joint.1] .. [joint.6], [robot] or [security]";

static bool known_section(const char *s)
{
    if (joint_section(s) >= 0) {
        return true;
    }
    for (size_t i = 0; i < N_KEYS; i++) {
        if (strcmp(KEYS[i].section, s) == 0) {
            return true;
        }
    }
    return false;
}

/* "name, node, heartbeat_timeout_ms" for the section. */
static void keys_of(const char *section, char *out, size_t outlen)
{
    size_t used = 0;
    out[0] = '\0';
    for (size_t i = 0; i < N_KEYS; i++) {
        if (strcmp(KEYS[i].section, section) == 0 && used < outlen) {
            int w = snprintf(out + used, outlen - used, "%s%s", used > 0 ? ", " : "", KEYS[i].key);
            used += w > 0 ? (size_t)w : 0u;
        }
    }
}

void ls_config_defaults(ls_config_t *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    (void)copy_str(cfg->name, sizeof cfg->name, "landscape-sim");
    cfg->node = 0x10;
    cfg->heartbeat_timeout_ms = 1000;
    cfg->disconnect_action = (uint8_t)ls_DisconnectAction_DISCONNECT_STOP_DEACTIVATE_RELEASE;
    cfg->auth_policy = (uint8_t)ls_AuthPolicy_AUTH_UNSIGNED;
    (void)copy_str(cfg->arm, sizeof cfg->arm, "sim");
    (void)copy_str(cfg->dio, sizeof cfg->dio, "sim");
    (void)copy_str(cfg->clock, sizeof cfg->clock, "realtime");
    cfg->rate_hz = 1000;
    cfg->telemetry_hz = 50;
    cfg->rt_priority = 80;
    cfg->rt_cpu = -1;
    cfg->lock_memory = true;
    cfg->estop_input = -1;
    cfg->drives_bitrate = 1000000;
    cfg->drives_cycle = 4;
    cfg->drives_master_node = 0x7F;
    cfg->drives_heartbeat_ms = 100;
    cfg->drives_heartbeat_timeout_ms = 350;
    cfg->drives_boot_timeout_ms = 5000;
    cfg->drives_budget_pct = 70;
    cfg->drives_abort = (uint8_t)LS_DRIVE_ABORT_QUICK_STOP;
    cfg->drives_feedforward = true;
    cfg->drives_stale_cycles = 5;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        cfg->joint[j].sign = 1;
        cfg->joint[j].temperature_scale = 1.0;
    }
    for (int k = 0; k < LS_MANUAL_KINDS; k++) {
        (void)copy_str(cfg->manual[k].map_name, sizeof cfg->manual[k].map_name,
                       k == LS_MANUAL_TEACHPENDANT ? "gamepad" : "spacemouse");
        cfg->manual[k].deadband = -1.0;
    }
    static const uint8_t steps[] = { 10, 25, 50, 100 };
    memcpy(cfg->speed_steps, steps, sizeof steps);
    cfg->n_speed_steps = (uint8_t)sizeof steps;
}

void ls_config_manual_map(const ls_config_t *cfg, ls_manual_kind_t kind, hal_evdev_map_t *out)
{
    const ls_config_manual_t *m = &cfg->manual[kind];
    memset(out, 0, sizeof *out);
    (void)hal_evdev_map_default(m->map_name, out);
    if (m->axes_set) {
        memcpy(out->axis, m->given.axis, sizeof out->axis);
    }
    if (m->buttons_set) {
        memcpy(out->button, m->given.button, sizeof out->button);
    }
    if (m->deadband >= 0.0) {
        out->deadband = m->deadband;
    }
}

void ls_config_manual_gate(const ls_config_t *cfg, ls_manual_kind_t kind, ls_manual_config_t *out)
{
    memset(out, 0, sizeof *out);
    out->stale_us = (uint64_t)cfg->manual[kind].stale_ms * 1000u;
    out->n_steps = cfg->n_speed_steps;
    memcpy(out->step_pct, cfg->speed_steps, sizeof out->step_pct);
    out->start_step = cfg->n_speed_steps > 0 ? (uint8_t)(cfg->n_speed_steps - 1u) : 0u;
}

/* ---- INI file ---------------------------------------------------------- */

typedef struct {
    ls_config_t *cfg;
    const char *path;
    FILE *f;
    int line;       /* lines handed to inih so far = the line being parsed */
    int error_line; /* 0 = no error yet */
    char *msg;
    size_t msglen;
    int seen_line[N_KEYS]; /* first line of each key in this file */
    int joint_seen_line[LS_N_JOINTS][N_JOINT_KEYS];
    bool links_started;
} ini_ctx_t;

static void ctx_error(ini_ctx_t *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void ctx_error(ini_ctx_t *c, const char *fmt, ...)
{
    if (c->error_line != 0) {
        return;
    }
    c->error_line = c->line;
    int w = snprintf(c->msg, c->msglen, "%s:%d: ", c->path, c->line);
    if (w >= 0 && (size_t)w < c->msglen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->msg + w, c->msglen - (size_t)w, fmt, ap);
        va_end(ap);
    }
}

/* inih's line source (ls_ini_next_line: counted lines, over-long lines and
 * NUL bytes refused, leading blanks dropped), which also refuses unknown
 * [sections] and stops at the first error. */
static char *ini_reader_fn(char *str, int num, void *stream)
{
    ini_ctx_t *c = stream;
    char why[64];
    if (c->error_line != 0 || ls_ini_next_line(str, num, c->f, &c->line, why, sizeof why) == NULL) {
        if (c->error_line == 0 && why[0] != '\0') {
            ctx_error(c, "%s", why);
        }
        return NULL;
    }
    if (str[0] == '[') {
        char tmp[256];
        (void)copy_str(tmp, sizeof tmp, str);
        char *end = strchr(tmp, ']');
        if (end != NULL) {
            *end = '\0';
            char *name = ls_ini_trim(tmp + 1);
            if (!known_section(name)) {
                ctx_error(c, "unknown section [%s]; expected %s", name, SECTIONS);
                return NULL;
            }
        }
    }
    return str;
}

static int ini_handler_fn(void *user, const char *section, const char *name, const char *value)
{
    ini_ctx_t *c = user;
    if (c->error_line != 0) {
        return 0;
    }
    if (section[0] == '\0') {
        ctx_error(c, "key '%s' outside any section: put it under %s", name, SECTIONS);
        return 0;
    }
    const int jn = joint_section(section);
    if (jn >= 0) {
        size_t k = 0;
        while (k < N_JOINT_KEYS && strcmp(JOINT_KEYS[k].key, name) != 0) {
            k++;
        }
        if (k == N_JOINT_KEYS) {
            char keys[512];
            size_t used = 0;
            keys[0] = '\0';
            for (size_t i = 0; i < N_JOINT_KEYS && used < sizeof keys; i++) {
                const int w = snprintf(keys + used, sizeof keys - used, "%s%s", i > 0 ? ", " : "", JOINT_KEYS[i].key);
                used += w > 0 ? (size_t)w : 0u;
            }
            ctx_error(c, "[%s] %s: unknown key; expected one of %s", section, name, keys);
            return 0;
        }
        if (c->joint_seen_line[jn][k] != 0) {
            ctx_error(c, "[%s] %s: given twice (first on line %d); keep one", section, name, c->joint_seen_line[jn][k]);
            return 0;
        }
        c->joint_seen_line[jn][k] = c->line;
        c->cfg->joint[jn].present = true;
        char why[256];
        if (JOINT_KEYS[k].set(&c->cfg->joint[jn], value, why, sizeof why) != 0) {
            ctx_error(c, "[%s] %s: got '%s', expected %s", section, name, value, why);
            return 0;
        }
        return 1;
    }
    size_t k = 0;
    while (k < N_KEYS && !(strcmp(KEYS[k].section, section) == 0 && strcmp(KEYS[k].key, name) == 0)) {
        k++;
    }
    if (k == N_KEYS) {
        char keys[256];
        keys_of(section, keys, sizeof keys);
        ctx_error(c, "[%s] %s: unknown key; expected one of %s", section, name, keys);
        return 0;
    }
    if (c->seen_line[k] != 0 && !KEYS[k].repeatable) {
        ctx_error(c, "[%s] %s: given twice (first on line %d); keep one", section, name, c->seen_line[k]);
        return 0;
    }
    if (c->seen_line[k] == 0) {
        c->seen_line[k] = c->line;
    }
    if (k == KEY_LINK && !c->links_started) {
        c->links_started = true;
        c->cfg->n_links = 0;
    }
    char why[256];
    if (KEYS[k].set(c->cfg, value, why, sizeof why) != 0) {
        ctx_error(c, "[%s] %s: got '%s', expected %s", section, name, value, why);
        return 0;
    }
    return 1;
}

int ls_config_load_file(ls_config_t *cfg, const char *path, char *msg, size_t msglen)
{
    ini_ctx_t c;
    memset(&c, 0, sizeof c);
    c.cfg = cfg;
    c.path = path;
    c.msg = msg;
    c.msglen = msglen;
    c.f = fopen(path, "r");
    if (c.f == NULL) {
        snprintf(msg, msglen, "%s: cannot read the configuration file: %s (give an existing file with --config FILE)",
                 path, strerror(errno));
        return LS_EINVAL;
    }
    int r = ini_parse_stream(ini_reader_fn, &c, ini_handler_fn, &c);
    int read_error = ferror(c.f);
    fclose(c.f);
    if (c.error_line != 0) {
        /* inih reports earlier syntax errors too: keep whichever came first */
        if (r > 0 && r < c.error_line) {
            snprintf(msg, msglen, "%s:%d: syntax error: expected '[section]', 'key = value' or a ; or # comment", path,
                     r);
        }
        return LS_EINVAL;
    }
    if (read_error) {
        snprintf(msg, msglen, "%s: read error after line %d", path, c.line);
        return LS_EINVAL;
    }
    if (r > 0) {
        snprintf(msg, msglen, "%s:%d: syntax error: expected '[section]', 'key = value' or a ; or # comment", path, r);
        return LS_EINVAL;
    }
    if (r < 0) {
        snprintf(msg, msglen, "%s: the INI parser failed (%d)", path, r);
        return LS_EINVAL;
    }
    return 0;
}

/* ---- command line ------------------------------------------------------ */

enum {
    OPT_CONFIG = 1000,
    OPT_HAL,
    OPT_CHECK,
    OPT_NO_LOCK,
    OPT_KEY0 = 2000, /* OPT_KEY0 + index into KEYS */
};

void ls_config_usage(FILE *f)
{
    fprintf(f,
            "usage: landscaped [--config FILE] [--hal sim] --link SPEC [--link SPEC ...] [options]\n"
            "       landscaped --config FILE --check\n"
            "\n"
            "Options override the keys of the --config file (%s for the service):\n"
            "  --config FILE             INI configuration file (docs/deploy.md lists the keys)\n"
            "  --check                   self-check this machine for this configuration and exit\n"
            "                            (exit 0: can run; 1: a check failed; 2: bad configuration)\n"
            "  --hal sim                 shorthand for --arm sim --dio sim --clock realtime\n"
            "  --link SPEC               [hal] link: slcan:pty:PATH (SLCAN on a new pseudo-terminal; PATH\n"
            "                            becomes a symlink to it) or socketcan:IFNAME (e.g. socketcan:can0);\n"
            "                            repeatable: every link is one segment of the same bus\n"
            "  --arm sim|cia402|none     [hal] arm (default sim; cia402: the drives of [drives] and\n"
            "                            [joint.1] .. [joint.6] in the --config file, docs/deploy.md)\n"
            "  --dio sim|none|gpiod:CHIP [hal] dio: digital I/O backend (default sim)\n"
            "  --link-faults SPEC        [hal] link_faults: inject faults on every link (tests; docs/reliability.md)\n"
            "  --setpoint-trace PATH     [hal] setpoint_trace: write every cycle's commanded joints to the CSV\n"
            "                            file PATH at exit (tests; arm sim only; docs/deploy.md)\n"
            "  --dio-socket PATH         [hal] dio_socket: sim DIO/jog control socket\n"
            "  --clock realtime|lockstep [hal] clock (default realtime)\n"
            "  --node ADDR               [device] node: node address 1..0xFE on the bus (default 0x10)\n"
            "  --heartbeat-timeout MS    [device] heartbeat_timeout_ms: drop a supervisor after MS\n"
            "                            without heartbeat, 50..600000 (default 1000; a supervisor's\n"
            "                            stated heartbeat period can lengthen it: docs/protocol.md)\n"
            "  --disconnect-action A     [device] disconnect_action: stop, stop_deactivate or\n"
            "                            stop_deactivate_release (default), when the owner is lost\n"
            "  --name NAME               [device] name reported at connect (default landscape-sim)\n"
            "  --rate HZ                 [control] rate_hz: control cycles per second, 100..10000 (default 1000)\n"
            "  --telemetry-hz HZ         [control] telemetry_hz: 0..200, 0 = off (default 50)\n"
            "  --rt-priority N           [control] rt_priority: SCHED_FIFO 1..99, 0 = normal (default 80)\n"
            "  --rt-cpu N                [control] rt_cpu: pin the control thread, -1 = no (default -1)\n"
            "  --no-lock-memory          [control] lock_memory = false\n"
            "  --estop-input N           [dio] estop_input: input bit that stops everything, -1 = none\n"
            "  (file only)               [manual] teachpendant, spaceball: the manualControl devices (evdev),\n"
            "                            their maps and speed_steps (docs/deploy.md \"Manual devices\")\n"
            "  --model FILE              [robot] model: the arm's robot model file (docs/deploy.md \"Describe\n"
            "                            your arm\"; default: the compiled-in ls-sim6)\n"
            "  -h, --help                this text\n",
            LS_CONFIG_DEFAULT_PATH);
}

static int opt_error(char *msg, size_t msglen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int opt_error(char *msg, size_t msglen, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, msglen, fmt, ap);
    va_end(ap);
    return LS_EINVAL;
}

int ls_config_from_args(ls_config_t *cfg, int argc, char **argv, char *msg, size_t msglen)
{
    struct option longopts[N_KEYS + 6];
    size_t n = 0;
    longopts[n++] = (struct option){ "config", required_argument, NULL, OPT_CONFIG };
    longopts[n++] = (struct option){ "hal", required_argument, NULL, OPT_HAL };
    longopts[n++] = (struct option){ "check", no_argument, NULL, OPT_CHECK };
    longopts[n++] = (struct option){ "no-lock-memory", no_argument, NULL, OPT_NO_LOCK };
    longopts[n++] = (struct option){ "help", no_argument, NULL, 'h' };
    for (size_t k = 0; k < N_KEYS; k++) {
        if (KEYS[k].option != NULL) {
            longopts[n++] = (struct option){ KEYS[k].option, required_argument, NULL, OPT_KEY0 + (int)k };
        }
    }
    longopts[n] = (struct option){ NULL, 0, NULL, 0 };

    /* Pass 1: --config, --check, --help and syntax; pass 2 applies the rest
     * in argv order on top of the file. */
    const char *config = NULL;
    bool help = false;
    opterr = 0;
    optind = 0; /* glibc: 0 re-initialises getopt completely */
    int o;
    while ((o = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
        switch (o) {
        case OPT_CONFIG:
            if (config != NULL) {
                return opt_error(msg, msglen, "--config given twice ('%s' and '%s'): give one file", config, optarg);
            }
            config = optarg;
            break;
        case OPT_CHECK: cfg->check = true; break;
        case 'h': help = true; break;
        case ':': return opt_error(msg, msglen, "%s: missing value (see --help)", argv[optind - 1]);
        case '?': return opt_error(msg, msglen, "unknown option '%s' (see --help)", argv[optind - 1]);
        default: break;
        }
    }
    if (optind < argc) {
        return opt_error(msg, msglen, "unexpected argument '%s' (see --help)", argv[optind]);
    }
    if (help) {
        ls_config_usage(stdout);
        return 1;
    }
    if (config != NULL) {
        if (copy_str(cfg->config_path, sizeof cfg->config_path, config) != 0) {
            return opt_error(msg, msglen, "--config: path longer than %zu characters", sizeof cfg->config_path - 1);
        }
        if (ls_config_load_file(cfg, config, msg, msglen) != 0) {
            return LS_EINVAL;
        }
    }

    bool links_started = false;
    optind = 0;
    while ((o = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
        if (o == OPT_HAL) {
            if (strcmp(optarg, "sim") != 0) {
                return opt_error(msg, msglen, "--hal: got '%s', expected sim (or set --arm, --dio, --clock)", optarg);
            }
            cfg->hal_sim = true;
            (void)copy_str(cfg->arm, sizeof cfg->arm, "sim");
            (void)copy_str(cfg->dio, sizeof cfg->dio, "sim");
            (void)copy_str(cfg->clock, sizeof cfg->clock, "realtime");
        } else if (o == OPT_NO_LOCK) {
            cfg->lock_memory = false;
        } else if (o >= OPT_KEY0) {
            size_t k = (size_t)(o - OPT_KEY0);
            if (k == KEY_LINK && !links_started) {
                links_started = true;
                cfg->n_links = 0;
            }
            char why[256];
            if (KEYS[k].set(cfg, optarg, why, sizeof why) != 0) {
                return opt_error(msg, msglen, "--%s: got '%s', expected %s", KEYS[k].option, optarg, why);
            }
        }
    }
    return 0;
}

/* ---- whole configuration ----------------------------------------------- */

int ls_config_validate(const ls_config_t *cfg, char *msg, size_t msglen)
{
    if (cfg->n_links == 0) {
        return opt_error(msg, msglen,
                         "no link configured: give --link SPEC or 'link = SPEC' under [hal] "
                         "(e.g. slcan:pty:/tmp/landscape0 or socketcan:can0)");
    }
    if (cfg->telemetry_hz > cfg->rate_hz) {
        return opt_error(msg, msglen,
                         "[control] telemetry_hz = %u is above rate_hz = %u: telemetry is sent from "
                         "control cycles; lower telemetry_hz",
                         (unsigned)cfg->telemetry_hz, (unsigned)cfg->rate_hz);
    }
    for (uint8_t i = 0; i < cfg->n_inputs; i++) {
        for (uint8_t j = 0; j < cfg->n_outputs; j++) {
            if (cfg->input_offsets[i] == cfg->output_offsets[j]) {
                return opt_error(msg, msglen, "[dio] line %u is both in inputs and in outputs: a line has one role",
                                 cfg->input_offsets[i]);
            }
        }
    }
    const bool cia402 = strcmp(cfg->arm, "cia402") == 0;
    bool any_joint = false;
    for (int j = 0; j < LS_N_JOINTS; j++) {
        any_joint = any_joint || cfg->joint[j].present;
    }
    if (!cia402 && (cfg->drives_link[0] != '\0' || any_joint)) {
        return opt_error(msg, msglen,
                         "[drives] and [joint.N] describe CiA 402 drives, but [hal] arm = %s: set arm = cia402 "
                         "to drive them, or remove those sections",
                         cfg->arm);
    }
    if (cia402) {
        if (cfg->drives_link[0] == '\0') {
            return opt_error(msg, msglen,
                             "[hal] arm = cia402 needs the drive bus: 'link = socketcan:IFNAME' (or slcan:tty:PATH) "
                             "under [drives] in the --config file (docs/deploy.md \"Drives\")");
        }
        if (cfg->drives_heartbeat_timeout_ms <= cfg->drives_heartbeat_ms) {
            return opt_error(msg, msglen,
                             "[drives] heartbeat_timeout_ms = %u is not above heartbeat_ms = %u: one late "
                             "heartbeat would lose a drive; use at least 2 x heartbeat_ms plus a margin",
                             (unsigned)cfg->drives_heartbeat_timeout_ms, (unsigned)cfg->drives_heartbeat_ms);
        }
        for (int j = 0; j < LS_N_JOINTS; j++) {
            const ls_config_joint_t *jc = &cfg->joint[j];
            const char *missing = !jc->present                ? "the section"
                                  : jc->node == 0u            ? "node"
                                  : jc->eds[0] == '\0'        ? "eds"
                                  : jc->counts_per_rad <= 0.0 ? "counts_per_rad"
                                                              : NULL;
            if (missing != NULL) {
                return opt_error(msg, msglen,
                                 "[joint.%d]: %s is missing: arm = cia402 needs [joint.1] .. [joint.%d], each with "
                                 "node, eds and counts_per_rad (docs/deploy.md \"Drives\")",
                                 j + 1, missing, LS_N_JOINTS);
            }
            if (jc->node == cfg->drives_master_node) {
                return opt_error(msg, msglen,
                                 "[joint.%d] node = 0x%02X is the controller's own [drives] master_node: give "
                                 "each drive and the controller distinct node ids",
                                 j + 1, (unsigned)jc->node);
            }
            for (int k = 0; k < j; k++) {
                if (cfg->joint[k].node == jc->node) {
                    return opt_error(msg, msglen,
                                     "[joint.%d] node = 0x%02X is also [joint.%d]'s: each drive has its own node id",
                                     j + 1, (unsigned)jc->node, k + 1);
                }
            }
        }
    }
    bool gpiod = strncmp(cfg->dio, "gpiod:", 6) == 0;
    if (cfg->setpoint_trace[0] != '\0' && strcmp(cfg->arm, "sim") != 0) {
        return opt_error(msg, msglen,
                         "[hal] setpoint_trace = %s needs arm = sim: the set-point trace is recorded by the "
                         "simulated arm, and arm = %s (remove setpoint_trace / --setpoint-trace, or set arm = sim)",
                         cfg->setpoint_trace, cfg->arm);
    }
    if (strcmp(cfg->dio, "sim") == 0 && strcmp(cfg->arm, "sim") != 0) {
        return opt_error(msg, msglen,
                         "[hal] dio = sim needs arm = sim: the simulated DIO lives in the simulated "
                         "world (use dio = gpiod:CHIP or none)");
    }
    char keys[sizeof cfg->key_file + 64];
    if (cfg->auth_policy == (uint8_t)ls_AuthPolicy_AUTH_SIGNED && ls_keys_path(cfg, keys, sizeof keys) == NULL) {
        return opt_error(msg, msglen,
                         "[security] policy = signed needs the supervisors' keys: set key_file = PATH, or load the "
                         "credential " LS_KEYS_CREDENTIAL " in landscaped.service (docs/deploy.md \"Signed "
                         "supervisors\")");
    }
    const ls_config_manual_t *tp = &cfg->manual[LS_MANUAL_TEACHPENDANT];
    if (tp->path[0] != '\0') {
        hal_evdev_map_t map;
        ls_config_manual_map(cfg, LS_MANUAL_TEACHPENDANT, &map);
        if (map.button[HAL_MANUAL_FN_ENABLE] == 0) {
            return opt_error(msg, msglen,
                             "[manual] " LS_MANUAL_NAME_TEACHPENDANT " = %s has no enabling switch in its map: a teach "
                             "pendant jogs only while one is held; add enable:KEY to " LS_MANUAL_NAME_TEACHPENDANT
                             "_buttons (e.g. enable:BTN_TL)",
                             tp->path);
        }
    }
    if (cfg->estop_input >= 0) {
        if (strcmp(cfg->dio, "none") == 0) {
            return opt_error(msg, msglen, "[dio] estop_input = %d needs a DIO backend but [hal] dio = none",
                             cfg->estop_input);
        }
        if (gpiod && cfg->n_inputs == 0) {
            return opt_error(msg, msglen,
                             "[dio] estop_input = %d but [dio] inputs is empty: list the e-stop's line "
                             "under inputs, or set estop_input = -1",
                             cfg->estop_input);
        }
        if (gpiod && cfg->estop_input >= (int)cfg->n_inputs) {
            return opt_error(msg, msglen,
                             "[dio] estop_input = %d but only %u inputs are configured: use an input "
                             "bit 0..%d or -1",
                             cfg->estop_input, (unsigned)cfg->n_inputs, (int)cfg->n_inputs - 1);
        }
    }
    return 0;
}
