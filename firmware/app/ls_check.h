/* `landscaped --check`: can this machine run the controller with this
 * configuration? One line per check on `out`:
 *
 *   PASS  real-time: SCHED_FIFO priority 80 granted to a test thread
 *   FAIL  AF_CAN: the kernel has no CAN sockets (...); fix: modprobe can can-raw ...
 *   WARN  memory locking: mlockall refused (...); fix: ...
 *
 * then a summary line. FAIL = the controller would not start or not work
 * with this configuration; WARN = it runs, degraded (e.g. no real-time
 * priority: the control loop runs as a normal thread with more jitter).
 *
 * Checks, in order: the configuration (ls_config_validate); AF_CAN; each
 * link (socketcan: interface exists, is up, its state and bitrate, through
 * hal_linux_socketcan_probe; slcan:pty: /dev/ptmx and the symlink's
 * directory); the DIO backend (gpiod: the chip through hal_linux_gpiod_probe,
 * then the configured lines requested and released; dio_socket's
 * directory); each manual device kind ([manual]: its evdev device through
 * hal_linux_evdev_probe: there (WARN when not plugged in: it is picked up
 * later), readable (FAIL: the udev rule / group), the map's axes and
 * buttons found (FAIL naming the missing ones); or the simulated or no
 * device); setpoint_trace's directory, when set; SCHED_FIFO at
 * rt_priority on a short-lived thread; rt_cpu in the allowed CPU set; memory
 * locking (RLIMIT_MEMLOCK and an mlockall trial, undone at once).
 *
 * Init-time only, from the main thread before anything else runs: it opens
 * and closes devices, starts and joins one thread and briefly locks the
 * process's memory. Nothing is kept: no pool entry, no line, no lock. */
#ifndef LS_CHECK_H
#define LS_CHECK_H

#include <stdio.h>

#include "ls_config.h"

/* landscaped's exit codes. */
#define LS_EXIT_OK 0
#define LS_EXIT_CHECK_FAILED 1 /* --check found a FAIL */
#define LS_EXIT_BAD_CONFIG 2   /* an option or the configuration file was refused */

typedef enum {
    LS_CHECK_PASS = 0,
    LS_CHECK_WARN = 1,
    LS_CHECK_FAIL = 2,
} ls_check_level_t;

/* Run every check for cfg, print one line per check and a summary to out.
 * Returns LS_EXIT_OK when nothing FAILed (WARNs allowed), else
 * LS_EXIT_CHECK_FAILED. cfg is only read. */
int ls_check_run(const ls_config_t *cfg, FILE *out);

/* For main when ls_config_from_args refused the configuration while --check
 * was asked: prints "FAIL  configuration: <msg>" and the summary, returns
 * LS_EXIT_BAD_CONFIG (the same code as a plain start with a bad config). */
int ls_check_config_error(const char *msg, FILE *out);

#endif
