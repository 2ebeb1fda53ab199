/* landscaped --check: each check tries the real thing the controller will do
 * (open the socket, request the lines, raise the priority, lock memory) and
 * undoes it, so a PASS means the start will get past that step. */
#include "ls_check.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <linux/can.h>
#include <pthread.h>
#include <sched.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "hal/hal_dio.h"
#include "hal/hal_status.h"
#include "hal_linux_evdev.h"
#include "hal_linux_gpiod.h"
#include "hal_linux_socketcan.h"
#include "ls_drive_setup.h"
#include "ls_err.h"
#include "ls_keys.h"
#include "ls_robot_config.h"

typedef struct {
    FILE *out;
    unsigned n[3]; /* by ls_check_level_t */
} report_t;

static void report(report_t *r, ls_check_level_t level, const char *what, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void report(report_t *r, ls_check_level_t level, const char *what, const char *fmt, ...)
{
    static const char *names[] = { "PASS", "WARN", "FAIL" };
    r->n[level]++;
    fprintf(r->out, "%s  %s: ", names[level], what);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(r->out, fmt, ap);
    va_end(ap);
    fputc('\n', r->out);
}

static int summary(report_t *r)
{
    fprintf(r->out, "%s: %u FAIL, %u WARN, %u PASS\n",
            r->n[LS_CHECK_FAIL] > 0 ? "landscaped cannot run with this configuration"
                                    : "landscaped can run with this configuration",
            r->n[LS_CHECK_FAIL], r->n[LS_CHECK_WARN], r->n[LS_CHECK_PASS]);
    fflush(r->out);
    return r->n[LS_CHECK_FAIL] > 0 ? LS_EXIT_CHECK_FAILED : LS_EXIT_OK;
}

/* ---- configuration ---------------------------------------------------- */

/* false when the configuration as a whole is refused (docs/deploy.md: exit 2,
 * as when landscaped would start with it). The robot model it names is part
 * of it: a model that does not load refuses the configuration, named by its
 * file as every other refused key is. */
static bool check_config(report_t *r, const ls_config_t *cfg)
{
    static ls_robot_model_t m;
    char msg[512];
    const char *src = cfg->config_path[0] != '\0' ? cfg->config_path : "(command line only)";
    if (ls_config_validate(cfg, msg, sizeof msg) != 0 || ls_robot_config_load(cfg, &m, msg, sizeof msg) != LS_OK) {
        report(r, LS_CHECK_FAIL, "configuration", "%s: %s", src, msg);
        return false;
    }
    report(r, LS_CHECK_PASS, "configuration", "%s: node 0x%02X, %zu link(s), arm %s, dio %s, clock %s, %u Hz", src,
           (unsigned)cfg->node, cfg->n_links, cfg->arm, cfg->dio, cfg->clock, (unsigned)cfg->rate_hz);
    report(r, LS_CHECK_PASS, "robot model", "%s: %s, %s inverse kinematics",
           cfg->model[0] != '\0' ? cfg->model : "(compiled in)", m.name, ls_ik_class_name(m.ik_class));
    return true;
}

/* ---- CAN ----------------------------------------------------------------- */

static bool has_socketcan_link(const ls_config_t *cfg)
{
    for (size_t i = 0; i < cfg->n_links; i++) {
        if (strncmp(cfg->links[i], "socketcan:", 10) == 0) {
            return true;
        }
    }
    return false;
}

static void check_afcan(report_t *r, const ls_config_t *cfg)
{
    bool needed = has_socketcan_link(cfg);
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (fd >= 0) {
        close(fd);
        report(r, LS_CHECK_PASS, "AF_CAN", "the kernel opens CAN_RAW sockets");
        return;
    }
    int e = errno;
    const char *fix = NULL;
    if (e == EAFNOSUPPORT) {
        fix = "the kernel has no CAN sockets; fix: modprobe can can-raw (a kernel with CONFIG_CAN and CONFIG_CAN_RAW)";
    } else if (e == EPROTONOSUPPORT) {
        fix = "the kernel has AF_CAN but no CAN_RAW; fix: modprobe can-raw (CONFIG_CAN_RAW)";
    } else if (e == EPERM || e == EACCES) {
        fix = "CAN sockets are forbidden to this process; fix: allow AF_CAN (systemd RestrictAddressFamilies=, "
              "seccomp or LSM policy)";
    } else {
        fix = "unexpected error; fix: check the kernel log (dmesg)";
    }
    if (needed) {
        report(r, LS_CHECK_FAIL, "AF_CAN", "socket(AF_CAN, SOCK_RAW, CAN_RAW): %s: %s", strerror(e), fix);
    } else {
        report(r, LS_CHECK_WARN, "AF_CAN",
               "socket(AF_CAN, SOCK_RAW, CAN_RAW): %s: %s (not needed by this configuration: no socketcan link)",
               strerror(e), fix);
    }
}

/* The directory that will hold `path` (a pty symlink or a socket) must exist
 * and be writable by this user. */
static int parent_writable(const char *path, char *dir, size_t dirlen)
{
    snprintf(dir, dirlen, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash == NULL) {
        snprintf(dir, dirlen, ".");
    } else if (slash == dir) {
        dir[1] = '\0';
    } else {
        *slash = '\0';
    }
    return access(dir, W_OK | X_OK);
}

static void check_slcan_pty(report_t *r, const char *spec, const char *path)
{
    char what[160];
    snprintf(what, sizeof what, "link %s", spec);
    int fd = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) {
        report(r, LS_CHECK_FAIL, what,
               "cannot open a pseudo-terminal (/dev/ptmx): %s; fix: mount devpts and "
               "allow /dev/ptmx (systemd: DeviceAllow=/dev/ptmx rw and char-pts rw)",
               strerror(errno));
        return;
    }
    close(fd);
    char dir[256];
    if (parent_writable(path, dir, sizeof dir) != 0) {
        report(r, LS_CHECK_FAIL, what,
               "cannot create the symlink in %s: %s; fix: create the directory or choose "
               "a writable one (the service may write to /run/landscape)",
               dir, strerror(errno));
        return;
    }
    struct stat sb;
    if (lstat(path, &sb) == 0 && !S_ISLNK(sb.st_mode)) {
        report(r, LS_CHECK_FAIL, what, "%s exists and is not a symlink; fix: choose another path for the pty link",
               path);
        return;
    }
    report(r, LS_CHECK_PASS, what, "pseudo-terminals available, %s writable", dir);
}

static void check_links(report_t *r, const ls_config_t *cfg)
{
    for (size_t i = 0; i < cfg->n_links; i++) {
        const char *spec = cfg->links[i];
        if (strncmp(spec, "socketcan:", 10) == 0) {
            char msg[512];
            char what[160];
            snprintf(what, sizeof what, "link %s", spec);
            int rc = hal_linux_socketcan_probe(spec + 10, msg, sizeof msg);
            if (rc == LS_OK) {
                report(r, LS_CHECK_PASS, what, "%s", msg);
            } else {
                report(r, LS_CHECK_FAIL, what, "%s", msg);
            }
        } else if (strncmp(spec, "slcan:pty:", 10) == 0) {
            check_slcan_pty(r, spec, spec + 10);
        }
    }
}

/* ---- digital I/O ---------------------------------------------------------- */

static void format_offsets(const unsigned *offs, uint8_t n, char *out, size_t outlen)
{
    size_t used = 0;
    out[0] = '\0';
    for (uint8_t i = 0; i < n && used < outlen; i++) {
        int w = snprintf(out + used, outlen - used, "%s%u", i > 0 ? "," : "", offs[i]);
        used += w > 0 ? (size_t)w : 0u;
    }
    if (n == 0) {
        snprintf(out, outlen, "none");
    }
}

static void check_gpiod(report_t *r, const ls_config_t *cfg, const char *chip)
{
    char msg[512];
    char what[384];
    snprintf(what, sizeof what, "gpio chip %s", chip);
    int rc = hal_linux_gpiod_probe(chip, msg, sizeof msg);
    if (rc != LS_OK) {
        report(r, LS_CHECK_FAIL, what, "%s", msg);
        return;
    }
    report(r, LS_CHECK_PASS, what, "%s", msg);

    hal_linux_gpiod_config_t gc;
    memset(&gc, 0, sizeof gc);
    gc.chip = chip;
    gc.n_inputs = cfg->n_inputs;
    gc.n_outputs = cfg->n_outputs;
    memcpy(gc.input_offsets, cfg->input_offsets, sizeof cfg->input_offsets);
    memcpy(gc.output_offsets, cfg->output_offsets, sizeof cfg->output_offsets);
    char ins[96];
    char outs[96];
    format_offsets(cfg->input_offsets, cfg->n_inputs, ins, sizeof ins);
    format_offsets(cfg->output_offsets, cfg->n_outputs, outs, sizeof outs);
    snprintf(what, sizeof what, "gpio lines %s (inputs %s, outputs %s)", chip, ins, outs);
    hal_dio_t dio;
    rc = hal_linux_gpiod_open(&dio, &gc, msg, sizeof msg);
    if (rc != LS_OK) {
        report(r, LS_CHECK_FAIL, what, "%s", msg);
        return;
    }
    hal_dio_close(&dio);
    report(r, LS_CHECK_PASS, what, "requested and released");
}

static void check_dio(report_t *r, const ls_config_t *cfg)
{
    if (strncmp(cfg->dio, "gpiod:", 6) == 0) {
        check_gpiod(r, cfg, cfg->dio + 6);
    } else {
        report(r, LS_CHECK_PASS, "dio", "%s backend, no GPIO chip needed", cfg->dio);
    }
    if (cfg->dio_socket[0] != '\0') {
        char dir[256];
        if (parent_writable(cfg->dio_socket, dir, sizeof dir) != 0) {
            report(r, LS_CHECK_FAIL, "dio_socket",
                   "cannot create %s in %s: %s; fix: create the directory or choose "
                   "a writable one (the service may write to /run/landscape)",
                   cfg->dio_socket, dir, strerror(errno));
        } else {
            report(r, LS_CHECK_PASS, "dio_socket", "%s writable", dir);
        }
    }
}

/* ---- manual devices ----------------------------------------------------------- */

/* Each kind: its evdev device (there, readable by this user, the map's axes
 * and buttons found), or the simulated one, or none. A device that is not
 * plugged in is a WARN: landscaped starts and picks it up when it appears. */
static void check_manual(report_t *r, const ls_config_t *cfg)
{
    for (int k = 0; k < LS_MANUAL_KINDS; k++) {
        const char *kind = ls_manual_kind_name((ls_manual_kind_t)k);
        char what[48];
        snprintf(what, sizeof what, "manual %s", kind);
        const char *path = cfg->manual[k].path;
        if (path[0] == '\0') {
            report(r, LS_CHECK_PASS, what, "%s",
                   strcmp(cfg->arm, "sim") == 0
                       ? "the simulated device (the control socket's jog and buttons); set [manual] to use a real one"
                       : "none configured: manualControl refuses it");
            continue;
        }
        hal_evdev_map_t map;
        ls_config_manual_map(cfg, (ls_manual_kind_t)k, &map);
        char msg[768];
        const int rc = hal_linux_evdev_probe(path, &map, msg, sizeof msg);
        report(r, rc == LS_OK ? LS_CHECK_PASS : (rc == LS_ENODEV ? LS_CHECK_WARN : LS_CHECK_FAIL), what, "%s", msg);
    }
}

/* ---- set-point trace (tests) ----------------------------------------------- */

/* The simulated arm creates PATH.tmp at start and renames it to PATH at exit. */
static void check_setpoint_trace(report_t *r, const ls_config_t *cfg)
{
    if (cfg->setpoint_trace[0] == '\0') {
        return;
    }
    char dir[256];
    struct stat sb;
    if (stat(cfg->setpoint_trace, &sb) == 0 && S_ISDIR(sb.st_mode)) {
        report(r, LS_CHECK_FAIL, "setpoint_trace", "%s is a directory; fix: give the path of a file to write",
               cfg->setpoint_trace);
    } else if (parent_writable(cfg->setpoint_trace, dir, sizeof dir) != 0) {
        report(r, LS_CHECK_FAIL, "setpoint_trace",
               "cannot create %s.tmp in %s: %s; fix: create the directory or choose a writable one",
               cfg->setpoint_trace, dir, strerror(errno));
    } else {
        report(r, LS_CHECK_PASS, "setpoint_trace", "%s writable (a test key: the simulated arm's set-points)", dir);
    }
}

/* ---- real time -------------------------------------------------------------- */

typedef struct {
    int priority;
    int err;
} rt_trial_t;

static void *rt_trial_thread(void *arg)
{
    rt_trial_t *t = arg;
    struct sched_param sp = { .sched_priority = t->priority };
    t->err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    return NULL;
}

static void check_realtime(report_t *r, const ls_config_t *cfg)
{
    if (cfg->rt_priority == 0) {
        report(r, LS_CHECK_PASS, "real-time", "not requested (rt_priority = 0): the control loop is a normal thread");
    } else {
        rt_trial_t t = { .priority = cfg->rt_priority, .err = 0 };
        pthread_t th;
        int e = pthread_create(&th, NULL, rt_trial_thread, &t);
        if (e == 0) {
            pthread_join(th, NULL);
            e = t.err;
        }
        struct rlimit rl;
        char limit[64] = "unknown";
        if (getrlimit(RLIMIT_RTPRIO, &rl) == 0) {
            if (rl.rlim_cur == RLIM_INFINITY) {
                snprintf(limit, sizeof limit, "unlimited");
            } else {
                snprintf(limit, sizeof limit, "%llu", (unsigned long long)rl.rlim_cur);
            }
        }
        if (e == 0) {
            report(r, LS_CHECK_PASS, "real-time", "SCHED_FIFO priority %d granted to a test thread (RLIMIT_RTPRIO %s)",
                   cfg->rt_priority, limit);
        } else {
            report(r, LS_CHECK_WARN, "real-time",
                   "SCHED_FIFO priority %d refused (%s; RLIMIT_RTPRIO %s): the control loop would run as a normal "
                   "thread with more jitter; fix: run as the landscaped service (LimitRTPRIO=99, "
                   "AmbientCapabilities=CAP_SYS_NICE), raise rtprio in /etc/security/limits.d, or set rt_priority = 0",
                   cfg->rt_priority, strerror(e), limit);
        }
    }
    if (cfg->rt_cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        if (sched_getaffinity(0, sizeof set, &set) != 0) {
            report(r, LS_CHECK_WARN, "rt_cpu", "cannot read the allowed CPUs: %s", strerror(errno));
        } else if (cfg->rt_cpu >= CPU_SETSIZE || !CPU_ISSET((size_t)cfg->rt_cpu, &set)) {
            report(r, LS_CHECK_FAIL, "rt_cpu",
                   "CPU %d is not one this process may run on (%d allowed); fix: set "
                   "rt_cpu to an online CPU (nproc, taskset -p $$) or -1",
                   cfg->rt_cpu, CPU_COUNT(&set));
        } else {
            report(r, LS_CHECK_PASS, "rt_cpu", "CPU %d is available", cfg->rt_cpu);
        }
    }
}

static void check_memlock(report_t *r, const ls_config_t *cfg)
{
    if (!cfg->lock_memory) {
        report(r, LS_CHECK_PASS, "memory locking", "not requested (lock_memory = false)");
        return;
    }
    struct rlimit rl;
    char limit[64] = "unknown";
    if (getrlimit(RLIMIT_MEMLOCK, &rl) == 0) {
        if (rl.rlim_cur == RLIM_INFINITY) {
            snprintf(limit, sizeof limit, "unlimited");
        } else {
            snprintf(limit, sizeof limit, "%llu KiB", (unsigned long long)rl.rlim_cur / 1024u);
        }
    }
    if (mlockall(MCL_CURRENT) == 0) {
        munlockall();
        report(r, LS_CHECK_PASS, "memory locking", "mlockall works (RLIMIT_MEMLOCK %s)", limit);
        return;
    }
    int e = errno;
    report(r, LS_CHECK_WARN, "memory locking",
           "mlockall refused (%s; RLIMIT_MEMLOCK %s): the control loop may take page faults; fix: run as the "
           "landscaped service (LimitMEMLOCK=infinity, AmbientCapabilities=CAP_IPC_LOCK), raise memlock in "
           "/etc/security/limits.d, or set lock_memory = false",
           strerror(e), limit);
}

/* ---- drives ---------------------------------------------------------------- */

static void say_drive(void *ctx, int level, const char *what, const char *line)
{
    report((report_t *)ctx, (ls_check_level_t)level, what, "%s", line);
}

/* false when the drives' configuration is refused (exit 2, as at start) */
static bool check_drives(report_t *r, const ls_config_t *cfg, bool config_ok)
{
    if (strcmp(cfg->arm, "cia402") == 0) {
        return !config_ok || ls_drive_check(cfg, say_drive, r);
    }
    if (strcmp(cfg->arm, "sim") == 0 && has_socketcan_link(cfg)) {
        report(r, LS_CHECK_WARN, "arm",
               "arm = sim on a controller with a real bus: supervisors would drive the simulated arm, nothing "
               "real moves; set arm = cia402 and describe the drives ([drives], [joint.N]: docs/deploy.md "
               "\"Drives\")");
    }
    return true;
}

/* ---- the supervisors' keys ------------------------------------------------ */

/* false when the key file's contents are refused (a refused configuration,
 * exit 2); a file landscaped may not read, or others may, is the machine's
 * (FAIL, exit 1). */
static bool check_keys(report_t *r, const ls_config_t *cfg)
{
    const bool signed_policy = cfg->auth_policy == (uint8_t)ls_AuthPolicy_AUTH_SIGNED;
    char path[sizeof cfg->key_file + 64];
    char msg[512];
    if (ls_keys_path(cfg, path, sizeof path) == NULL) {
        report(r, LS_CHECK_PASS, "keys",
               "none: policy unsigned, any node on the bus may open a session (docs/deploy.md \"Signed "
               "supervisors\")");
        return true;
    }
    static ls_auth_t auth; /* wiped before return: the keys stay nowhere */
    ls_auth_init(&auth, signed_policy ? ls_AuthPolicy_AUTH_SIGNED : ls_AuthPolicy_AUTH_UNSIGNED, cfg->unsigned_queries);
    const int k = ls_keys_load(path, &auth, msg, sizeof msg);
    char names[LS_AUTH_MAX_KEYS * LS_AUTH_KEY_ID_SIZE + 16] = "";
    size_t used = 0;
    for (uint8_t i = 0; i < auth.n_keys && used < sizeof names; i++) {
        const int w = snprintf(names + used, sizeof names - used, "%s%s", i > 0 ? ", " : "", auth.keys[i].id);
        used += w > 0 ? (size_t)w : 0u;
    }
    const unsigned n = auth.n_keys;
    ls_auth_wipe(&auth, sizeof auth);
    if (k != LS_OK) {
        report(r, LS_CHECK_FAIL, "keys", "%s", msg);
        return k != LS_EINVAL;
    }
    report(r, LS_CHECK_PASS, "keys", "%s: %u key%s (%s), only its owner may read it; policy %s%s", path, n,
           n == 1 ? "" : "s", names, signed_policy ? "signed" : "unsigned (keys sign the sessions that use one)",
           signed_policy && cfg->unsigned_queries ? ", unsigned queries answered" : "");
    return true;
}

int ls_check_run(const ls_config_t *cfg, FILE *out)
{
    report_t r = { .out = out, .n = { 0, 0, 0 } };
    bool config_ok = check_config(&r, cfg);
    config_ok = check_keys(&r, cfg) && config_ok;
    check_afcan(&r, cfg);
    check_links(&r, cfg);
    config_ok = check_drives(&r, cfg, config_ok) && config_ok;
    check_dio(&r, cfg);
    check_manual(&r, cfg);
    check_setpoint_trace(&r, cfg);
    check_realtime(&r, cfg);
    check_memlock(&r, cfg);
    int code = summary(&r);
    return config_ok ? code : LS_EXIT_BAD_CONFIG;
}

int ls_check_config_error(const char *msg, FILE *out)
{
    report_t r = { .out = out, .n = { 0, 0, 0 } };
    report(&r, LS_CHECK_FAIL, "configuration", "%s", msg);
    (void)summary(&r);
    return LS_EXIT_BAD_CONFIG;
}
