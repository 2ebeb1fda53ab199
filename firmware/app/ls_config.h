/* landscaped's configuration: one INI file (read with inih) and command-line
 * options that override it. Every key is validated at start; an error names
 * the file, the line, the key, the value and what is allowed:
 *
 *   /etc/landscape/landscaped.conf:12: [control] rate_hz: got '5', expected 100..10000 (control cycles per second)
 *   --node: got '0x1FF', expected 1..0xFE (node address; 0xFF is the broadcast address)
 *
 * docs/deploy.md lists the keys. All functions here run at init only: they
 * use stdio and the C library (inih reads the file line by line on the
 * stack), never the control loop. The caller owns the ls_config_t. */
#ifndef LS_CONFIG_H
#define LS_CONFIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "ls_err.h"
#include "ls_robot_model.h" /* LS_N_JOINTS: one [joint.N] section per joint */
#include "hal_linux_evdev.h"
#include "ls_manual.h"

#define LS_CONFIG_MAX_LINKS 4
#define LS_CONFIG_MAX_LINES 16
#define LS_CONFIG_MAX_OFFSET 1023u /* highest gpiod line offset accepted in inputs/outputs */
#define LS_CONFIG_DEFAULT_PATH "/etc/landscape/landscaped.conf"

/* What a drive does when it loses the controller's heartbeat (CiA 402 0x6007,
 * abort connection option code): the values are the profile's. */
typedef enum {
    LS_DRIVE_ABORT_NONE = 0,            /* no action: the drive keeps its last set-point */
    LS_DRIVE_ABORT_FAULT = 1,           /* fault: the drive's fault reaction, then FAULT */
    LS_DRIVE_ABORT_DISABLE_VOLTAGE = 2, /* power off at once: the brake catches the joint */
    LS_DRIVE_ABORT_QUICK_STOP = 3,      /* decelerate on the quick-stop ramp, then per 0x605A */
} ls_drive_abort_t;

/* An object of a drive named in the configuration: INDEX:SUB, and for a
 * bit of it (brake engaged, safe torque off active) /BIT, '!' first when
 * the bit clear says it. */
typedef struct {
    bool given;
    uint16_t index;
    uint8_t sub;
    uint8_t bit;
    bool inverted;
} ls_config_obj_t;

/* Readouts a drive may map besides its feedback (bits of ls_config_t.drives_readouts). */
#define LS_CONFIG_READOUT_VELOCITY 0x1u /* velocity actual 0x606C */
#define LS_CONFIG_READOUT_TORQUE 0x2u   /* torque actual 0x6077 */

/* One [joint.N] section: the CiA 402 drive of joint N (arm = cia402). */
typedef struct {
    bool present;                /* the section was given */
    uint8_t node;                /* node = 0x21 (1..127): the drive's CANopen node id */
    char eds[256];               /* eds = PATH: the drive's EDS or DCF file */
    double counts_per_rad;       /* counts_per_rad = N (> 0): the drive's position units per joint radian */
    int sign;                    /* sign = 1 | -1: -1 when the drive counts against the joint's direction */
    double offset_rad;           /* offset_rad = 0 (finite): the joint angle where the drive reads 0 */
    double vel_counts_per_rad_s; /* velocity_counts_per_rad_s = N (> 0; default counts_per_rad): units of
                                     0x60B1/0x606C per rad/s */
    bool home_required;          /* home_required = false (true: an incremental encoder, motion waits for a homing) */
    bool has_home_method;
    int home_method; /* home_method = (empty: the drive's own 0x6098; else -128..127) */
    bool has_home_offset;
    double home_offset_rad; /* home_offset_rad = (empty: the drive's own 0x607C; else the joint angle of home) */
    bool has_following_window;
    double following_window_rad; /* following_window_rad = (empty: the drive's own 0x6065) */
    bool has_following_timeout;
    uint32_t following_timeout_ms; /* following_timeout_ms = (empty: the drive's own 0x6066; else 0..65535) */
    ls_config_obj_t brake;         /* brake = (empty: none; INDEX:SUB/BIT that says the holding brake is engaged) */
    ls_config_obj_t sto;           /* sto = (empty: none; INDEX:SUB/BIT that says safe torque off is active) */
    ls_config_obj_t temperature;   /* temperature = (empty: none; INDEX:SUB of the drive's temperature) */
    double temperature_scale;      /* temperature_scale = 1 (degrees Celsius per unit of that object) */
} ls_config_joint_t;

/* The [manual] keys of one manual device kind, named after it (KIND is
 * teachpendant or spaceball; docs/deploy.md "Manual devices"); the map in
 * effect is ls_config_manual_map's. */
typedef struct {
    char path[HAL_MANUAL_NAME_LEN]; /* KIND: /dev/input/by-id/... ("" = none: the simulated device with arm = sim) */
    char map_name[16];              /* KIND_map: gamepad | spacemouse (default: gamepad for the teach pendant,
                                       spacemouse for the spaceball) */
    hal_evdev_map_t given;          /* the axes / buttons given, when axes_set / buttons_set */
    bool axes_set, buttons_set;     /* KIND_axes, KIND_buttons ("" = the map's) */
    double deadband;                /* KIND_deadband: 0..0.9 (< 0, "": the map's) */
    uint32_t stale_ms;              /* KIND_stale_ms: 0..60000 (0; > 0: reports continuously) */
} ls_config_manual_t;

typedef struct {
    char config_path[256]; /* --config FILE ("" = none) */
    /* [device] */
    char name[32];                 /* name = landscape-sim (1..31 printable characters) */
    uint8_t node;                  /* node = 0x10 (1..0xFE) */
    uint32_t heartbeat_timeout_ms; /* heartbeat_timeout_ms = 1000 (50..600000) */
    uint8_t disconnect_action;     /* disconnect_action = stop_deactivate_release (ls.DisconnectAction:
                                      stop, stop_deactivate, stop_deactivate_release) */
    /* [hal] */
    char links[LS_CONFIG_MAX_LINKS][128]; /* link = slcan:pty:PATH | socketcan:IFNAME (repeatable) */
    size_t n_links;
    char arm[16];  /* arm = sim | cia402 | none (default sim) */
    char dio[128]; /* dio = sim | gpiod:CHIP | none (default sim) */
    char link_faults
        [192]; /* [hal] link_faults, --link-faults SPEC: tests only, faults injected on every link ("" = none) */
    char dio_socket[128];     /* dio_socket = PATH (sim DIO/jog control socket; "" = none) */
    char setpoint_trace[256]; /* [hal] setpoint_trace, --setpoint-trace PATH: tests only, arm = sim only: every
                                 cycle's commanded joints to a CSV file at exit ("" = none) */
    char clock[16];           /* clock = realtime | lockstep (default realtime) */
    /* [control] */
    uint32_t rate_hz;      /* rate_hz = 1000 (100..10000) */
    uint32_t telemetry_hz; /* telemetry_hz = 50 (0..200, <= rate_hz; 0 = off) */
    int rt_priority;       /* rt_priority = 80 (0 = normal thread, 1..99 SCHED_FIFO) */
    int rt_cpu;            /* rt_cpu = -1 (no pinning; else 0..1023) */
    bool lock_memory;      /* lock_memory = true */
    /* [dio] gpiod line offsets and roles (used by dio = gpiod:CHIP only, so that
     * --hal sim can run a gpiod configuration on a bench) */
    uint8_t n_inputs;
    unsigned input_offsets[LS_CONFIG_MAX_LINES]; /* inputs = 0,1,2 (default none) */
    uint8_t n_outputs;
    unsigned output_offsets[LS_CONFIG_MAX_LINES]; /* outputs = 8,9 (default none) */
    int estop_input; /* estop_input = -1 (input bit index 0..15 that stops everything when active) */
    /* [drives]: the CiA 402 drive bus (arm = cia402) */
    char drives_link[128];                /* link = socketcan:IFNAME | slcan:tty:PATH | slcan:pty:PATH */
    uint32_t drives_bitrate;              /* bitrate = 1000000 (bit/s; SLCAN adapters and the bus budget) */
    uint32_t drives_cycle;                /* cycle = 4 (1..100 control periods per drive cycle: SYNC period) */
    uint8_t drives_master_node;           /* master_node = 0x7F (1..127: the controller's node id, its heartbeat) */
    uint32_t drives_heartbeat_ms;         /* heartbeat_ms = 100 (10..10000: ours, and each drive's 0x1017) */
    uint32_t drives_heartbeat_timeout_ms; /* heartbeat_timeout_ms = 350 (both directions; > heartbeat_ms) */
    uint32_t drives_boot_timeout_ms;      /* boot_timeout_ms = 5000 (100..60000: boot-up and configuration) */
    uint32_t drives_budget_pct;           /* budget_pct = 70 (10..100: the bus load a drive cycle may take) */
    uint8_t drives_abort;                 /* abort_connection = quick_stop (ls_drive_abort_t) */
    bool drives_feedforward;              /* velocity_feedforward = true (map 0x60B1 where the drive can) */
    uint32_t drives_stale_cycles;         /* stale_cycles = 5 (2..100: a drive whose TPDO misses this many drive cycles
                                     is lost) */
    bool drives_has_quick_stop;
    int drives_quick_stop;    /* quick_stop_option = (empty: each drive's own 0x605A; else 0..8) */
    uint32_t drives_readouts; /* readouts = (empty: none; velocity, torque: LS_CONFIG_READOUT_*) */
    ls_config_joint_t joint[LS_N_JOINTS];
    /* [manual] */
    ls_config_manual_t manual[LS_MANUAL_KINDS]; /* by ls_manual_kind_t, from these keys: */
    /* teachpendant = (empty: none) */
    /* teachpendant_map = gamepad */
    /* teachpendant_axes = (empty: the map's) */
    /* teachpendant_buttons = (empty: the map's) */
    /* teachpendant_deadband = (empty: the map's) */
    /* teachpendant_stale_ms = 0 */
    /* spaceball = (empty: none) */
    /* spaceball_map = spacemouse */
    /* spaceball_axes = (empty: the map's) */
    /* spaceball_buttons = (empty: the map's) */
    /* spaceball_deadband = (empty: the map's) */
    /* spaceball_stale_ms = 0 */
    uint8_t n_speed_steps; /* speed_steps = 10,25,50,100 (percent, ascending, 1..100) */
    uint8_t speed_steps[LS_MANUAL_MAX_STEPS];
    /* [robot] */
    char model[256]; /* model = PATH of a robot model file (default "": the compiled-in ls-sim6) */
    /* [security] (docs/protocol.md "Security"; file only: no key on a command line) */
    uint8_t auth_policy;   /* policy = unsigned | signed (ls.AuthPolicy; default unsigned) */
    char key_file[256];    /* key_file = PATH of the supervisors' keys ("" = none, or the service's
                              credential LS_KEYS_CREDENTIAL: ls_keys_path) */
    bool unsigned_queries; /* unsigned_queries = false (signed: answer queries without a session) */
    /* modes */
    bool check;   /* --check: self-check and exit */
    bool hal_sim; /* --hal sim: the skeleton's shorthand for arm=sim dio=sim clock=realtime */
} ls_config_t;

/* Defaults above. Never fails. */
void ls_config_defaults(ls_config_t *cfg);

/* Apply argv on top of what cfg holds (call ls_config_defaults first):
 * --config FILE is read first, then every other option overrides the file
 * in argv order (a --link on the command line replaces the file's links).
 * --check and --config are recorded even when a later step fails, so the
 * caller can tell a failed --check apart. Returns 0; 1 when --help was
 * printed to stdout (exit 0); LS_EINVAL with `msg` (one line, no newline) naming
 * the option or FILE:LINE: [section] key, the value and what is allowed.
 * Does not call ls_config_validate. Uses getopt_long (resets optind). */
int ls_config_from_args(ls_config_t *cfg, int argc, char **argv, char *msg, size_t msglen);

/* Read one INI file into cfg (keys override what cfg holds; the file's first
 * `link` replaces cfg's links, later ones add). Refuses, with msg
 * "FILE:LINE: [section] key: got 'v', expected ...", the first of: a missing
 * or unreadable file (no line), a syntax error, an unknown section or key, a
 * key outside any section, a value of the wrong type or out of range, a
 * non-repeatable key given twice, a line longer than the parser takes.
 * Returns LS_OK or LS_EINVAL; on error cfg may hold the keys read before it. */
int ls_config_load_file(ls_config_t *cfg, const char *path, char *msg, size_t msglen);

/* Whole-configuration checks the single keys cannot make: at least one
 * link, telemetry_hz <= rate_hz, inputs and outputs disjoint, estop_input
 * within the configured inputs and a DIO backend present for it,
 * setpoint_trace only with arm = sim, a teach pendant's map with an
 * enabling switch (docs/conformance.md "manualControl"), a key file for
 * policy = signed. LS_OK, or LS_EINVAL with msg. */
int ls_config_validate(const ls_config_t *cfg, char *msg, size_t msglen);

/* The map a manual device kind uses: its <kind>_map's default with the
 * given axes, buttons and dead band over it. */
void ls_config_manual_map(const ls_config_t *cfg, ls_manual_kind_t kind, hal_evdev_map_t *out);

/* The gate configuration of a kind for the core (override steps starting
 * at the highest, staleness; manualControl adds the enabling switch). */
void ls_config_manual_gate(const ls_config_t *cfg, ls_manual_kind_t kind, ls_manual_config_t *out);

/* The --help text. */
void ls_config_usage(FILE *f);

#endif
