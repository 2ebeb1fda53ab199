/* The arm of CiA 402 servo drives on their own CAN bus: the HAL arm
 * contract (hal/hal_arm.h) on a CiA 301 master (firmware/canopen) and one
 * CiA 402 axis per joint (ls_cia402.h), in cyclic synchronous position mode
 * (CSP, 0x6060 = 8).
 *
 * What it does on the bus:
 *  - At start (ls_drives_boot, then ls_drives_service until it says done):
 *    each drive is reset (NMT reset communication), must send its boot-up
 *    within the boot deadline, and is configured over SDO by a script built
 *    from its ls_drive_joint_t (built from the drive's EDS by the app, which
 *    only asks for objects the EDS lists as writable or mappable): its type
 *    (0x1000: a CiA 402 device) and identity (0x1018 against the EDS), its
 *    heartbeat (0x1017) and its watch of ours (0x1016), what it does when
 *    ours stops (0x6007), every PDO it has disabled, then the PDOs of
 *    ls_drives_layout (RPDO1 = controlword + target position [+ mode of
 *    operation], RPDO2 = velocity offset 0x60B1 when fed forward, TPDO1 =
 *    statusword + position actual [+ mode display] and the readouts that
 *    fit, TPDO2 the rest), all synchronous, each remapped in the order
 *    CiA 301 asks (COB-ID invalid, transmission type, sub 0 = 0, entries,
 *    sub 0 = N, COB-ID valid); the interpolation period 0x60C2 = the drive
 *    cycle; what the configuration sets of the following-error window and
 *    time-out (0x6065/0x6066), the quick-stop option (0x605A), the homing
 *    method and home offset (0x6098/0x607C); 0x6060 = 8 confirmed in
 *    0x6061; its software position limits (0x607D), position actual and
 *    statusword read. Then NMT start.
 *  - Every drive cycle (cycle_ticks control cycles, in update()): the
 *    drives' TPDOs of the previous SYNC are taken (statusword, position:
 *    unwrapped across the int32 wrap; the readouts), each axis's CiA 402
 *    stepper gives the controlword, and every RPDO goes out before the
 *    SYNC. No SDO traffic while the drives are in operation, but for the
 *    mode change of a homing on a drive whose EDS does not let 0x6060 and
 *    0x6061 be mapped (the arm holds still meanwhile).
 *  - Enable: one confirmed 402 step per drive cycle up to OPERATION ENABLED
 *    (a fault reset edge first when a drive is in FAULT); the target
 *    position is the drive's actual position until the enable-operation
 *    step and then held there until command() gives set-points, so no axis
 *    jumps. Disable: shutdown (READY TO SWITCH ON: no torque, brake on).
 *  - Homing (home(), an enabled joint at rest): the drive's own homing,
 *    CiA 402 mode 6 with its method 0x6098: the mode set (in RPDO1 and
 *    confirmed in TPDO1's 0x6061 where mapped, else over SDO), a rising
 *    edge of controlword bit 4, statusword bit 12 (attained, with bit 10)
 *    or 13 (error) awaited within LS_DRIVES_HOME_TIMEOUT_MS, then CSP again
 *    with the target at the new actual position; the position counter has
 *    a new zero, so the unwrapping starts over from it and the joint holds
 *    where it now reads. The joint stays homed across disable and enable
 *    and forgets it when its drive boots again.
 *
 * Events (next_event): every EMCY of a drive (code, register, vendor bytes,
 * the code's name), and after one, once the drives are disabled (no SDO
 * while they are in operation), the drive's error code 0x603F read back.
 *
 * Joint status (hal_joint_status_t): ENABLED when its drive confirmed
 * OPERATION ENABLED and follows the target (statusword bit 12, in CSP
 * confirmed in 0x6061 where mapped); FAULT with the drive's EMCY code and
 * its name (or the 402 stepper's words: a drive stuck in a state, one that
 * stays in FAULT; or its safe torque off input active while enabled); LOST
 * when the master lost the node (heartbeat, an unexpected boot-up) or its
 * TPDO is older than stale_cycles drive cycles; feedback_age in control
 * cycles; the homing's state.
 *
 * Readouts (readout(), the comms thread's): per joint the 402 state,
 * mode, last EMCY, position and the velocity, torque, temperature, brake
 * and safe torque off the drive publishes, homing, feedback age; the
 * master's counters. Published by the control thread at the end of every
 * drive cycle into a seqlock (ls_seqlock.h).
 *
 * Threading: init, boot and the boot's service loop at init (main thread);
 * from then on every operation from the control thread, which owns the
 * drive link, except readout(): no blocking, no allocation, O(joints) per
 * call plus the frames received. Memory: the caller owns the ls_drives_t
 * (about 60 kB with its scripts and readouts; static in landscaped). */
#ifndef LS_DRIVES_H
#define LS_DRIVES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_arm.h"
#include "hal/hal_can.h"
#include "ls_cia402.h"
#include "ls_co_master.h"
#include "ls_seqlock.h"

#define LS_DRIVES_SCRIPT_MAX 80u   /* SDO steps of one drive's configuration (the longest: 61, tests/unit/drives) */
#define LS_DRIVES_PDO_SETS 4u      /* RPDO and TPDO parameter sets a drive may have disabled at start */
#define LS_DRIVES_RX_PER_CYCLE 64u /* frames taken per update(): bounds a cycle's time under a flood */
#define LS_DRIVES_STALE_CYCLES 5u  /* default stale_cycles */
/* An enable's steps: a drive follows one within a few cycles (a brake's
 * release takes a few hundred ms on common drives); two fault resets. Both
 * keep an enable within the control loop's LS_CTL_ENABLE_TIMEOUT_MS. */
#define LS_DRIVES_STEP_TIMEOUT_MS 500u
#define LS_DRIVES_RESET_EDGES 2u
#define LS_DRIVES_EVENTS 16u           /* reported events (EMCY, error codes read back) kept until taken */
#define LS_DRIVES_BUS_CHECK_CYCLES 64u /* the link's state (bus-off) is looked at every this many updates */
/* A homing ends within this (a method that moves to a switch takes seconds
 * on a real axis; "home here", 35/37, a few drive cycles). */
#define LS_DRIVES_HOME_TIMEOUT_MS 30000u
#define LS_DRIVES_READOUT_TRIES 16u /* seqlock copies a readout() tries */
/* SYNCs from a command's RPDO until a TPDO shows its effect: the drive
 * applies it at the SYNC after it, and the TPDO answering that SYNC was
 * sampled before (CiA 301: synchronous PDOs sample at the SYNC). A
 * statusword confirms an enable or a homing step only from then on. */
#define LS_DRIVES_SETTLE_SYNCS 2u

/* An object of a drive the arm maps into a TPDO to read it (brake, safe
 * torque off, temperature, velocity and torque actual): where it is, how
 * many bytes, and how to read it. */
typedef struct {
    bool map;       /* wanted and mappable (the EDS says so): in the layout */
    uint16_t index; /* CiA 301 object */
    uint8_t sub;
    uint8_t bytes;  /* 1, 2 or 4 (its data type's size) */
    bool is_signed; /* INTEGER types */
    uint8_t bit;    /* brake / STO: the bit that says engaged / active */
    bool inverted;  /* brake / STO: the bit clear says it */
} ls_drive_obj_t;

/* One joint's drive: what the configuration says and what its EDS offers. */
typedef struct {
    uint8_t node_id;      /* 1..127 */
    ls_402_scale_t scale; /* joint radians <-> drive counts (ls_402_scale_init) */
    /* Identity to check (0x1018 :01 vendor, :02 product, :03 revision against
     * the EDS's DeviceInfo); a field is checked when its has_ flag is set.
     * The revision is checked as optional: a mismatch is recorded, not fatal. */
    bool has_vendor, has_product, has_revision;
    uint32_t vendor_id, product_code, revision;
    bool write_consumer_hb;                /* 0x1016:01 writable: the drive watches our heartbeat */
    bool write_abort_option;               /* 0x6007 writable */
    bool write_interp_period;              /* 0x60C2:01/:02 writable */
    bool write_pdo_type;                   /* 0x1400:02 etc. writable (else the EDS's types must be synchronous) */
    bool write_tpdo_inhibit;               /* 0x1800:03 writable: set 0 (a synchronous TPDO needs none) */
    bool feedforward;                      /* 0x60B1 mappable and wanted: RPDO2 carries it */
    bool rpdo_present[LS_DRIVES_PDO_SETS]; /* 0x1400 + n in the EDS: disabled unless used */
    bool tpdo_present[LS_DRIVES_PDO_SETS]; /* 0x1800 + n */
    /* 0x6060 in RPDO1 and 0x6061 in TPDO1 (a joint configured for homing,
     * whose EDS lets them be mapped): a homing changes modes in the PDOs
     * (else over SDO, the arm at rest). */
    bool map_mode;
    bool can_home;      /* the drive offers homing mode (0x6502 bit 5, or its EDS does not say) */
    bool home_required; /* an incremental encoder: motion waits for a homing */
    bool write_home_method, write_home_offset;
    int8_t home_method;         /* 0x6098 */
    int32_t home_offset_counts; /* 0x607C */
    bool write_fe_window, write_fe_timeout;
    uint32_t fe_window_counts; /* 0x6065 */
    uint16_t fe_timeout_ms;    /* 0x6066 */
    bool write_quick_stop;
    int16_t quick_stop_option; /* 0x605A */
    bool read_limits;          /* 0x607D:01 and :02 readable: read at start */
    /* Mapping entries the EDS lets be written per TPDO (0x1A00 + n, its
     * sub 0 and entries 1..k): readouts go only where there is room. */
    uint8_t tpdo_room[LS_CO_NODE_PDOS];
    /* Readouts, each mapped when its `map` is set (ls_drives_layout says
     * where; one that does not fit in two TPDOs is left out). */
    ls_drive_obj_t brake, sto, torque, temperature, velocity;
    double temperature_scale; /* degrees Celsius per unit of the temperature object */
} ls_drive_joint_t;

/* The readouts a joint's PDOs may carry, in the order they are placed. */
typedef enum {
    LS_DRIVE_RO_BRAKE = 0,
    LS_DRIVE_RO_STO,
    LS_DRIVE_RO_TORQUE,
    LS_DRIVE_RO_TEMPERATURE,
    LS_DRIVE_RO_VELOCITY,
    LS_DRIVE_RO_COUNT
} ls_drive_ro_t;

#define LS_DRIVES_TPDOS LS_CO_NODE_PDOS /* TPDOs per joint: 1 = feedback (+ readouts that fit), 2 = the rest */
#define LS_DRIVES_MAP_MAX 8u            /* objects in one PDO (classic CAN: 8 bytes) */

/* Where a joint's objects go in its PDOs: the one home of the layout for
 * the configuration script, the master's PDO lengths, the decoding, the
 * bus budget and the warnings of what did not fit. */
typedef struct {
    uint8_t rpdo1_bytes; /* 6, 7 with the mode of operation */
    uint8_t n_tpdo;      /* 1 or 2 */
    uint8_t tpdo_bytes[LS_DRIVES_TPDOS];
    uint8_t n_map[LS_DRIVES_TPDOS];
    uint32_t map[LS_DRIVES_TPDOS][LS_DRIVES_MAP_MAX]; /* CiA 301 mapping entries (LS_CO_PDO_MAP_ENTRY) */
    struct {
        bool mapped;
        uint8_t slot;   /* TPDO 0 or 1 */
        uint8_t offset; /* its first byte */
    } ro[LS_DRIVE_RO_COUNT];
    uint32_t left_out; /* bit LS_DRIVE_RO_*: wanted, but no room in two TPDOs */
} ls_drive_layout_t;

/* The layout of one joint: TPDO1 = statusword, position actual, the mode
 * display when map_mode, then the readouts in ls_drive_ro_t order, each in
 * the first TPDO with room (TPDO2 only when one needs it). Pure; any
 * context. */
void ls_drives_layout(const ls_drive_joint_t *jc, ls_drive_layout_t *out);

/* "brake", "safe torque off", "torque actual", "temperature", "velocity
 * actual"; "?" out of range. */
const char *ls_drives_ro_name(ls_drive_ro_t ro);

typedef struct {
    uint8_t n_joints; /* 1..HAL_ARM_MAX_JOINTS (and at most LS_CO_MAX_NODES) */
    ls_drive_joint_t joint[HAL_ARM_MAX_JOINTS];
    hal_can_link_t *link;          /* the drive bus; the caller opened it and keeps it */
    uint32_t control_period_us;    /* the control loop's period */
    uint16_t cycle_ticks;          /* control periods per drive cycle (>= 1) */
    uint8_t master_node;           /* our node id: our heartbeat */
    uint16_t heartbeat_ms;         /* ours and the drives' (0x1017) */
    uint16_t heartbeat_timeout_ms; /* both ways: the drives' 0x1016 and our watch of them */
    uint16_t boot_timeout_ms;
    int16_t abort_option; /* 0x6007 value (ls_config.h ls_drive_abort_t) */
    uint8_t stale_cycles; /* a TPDO older than this many drive cycles: LOST; 0: LS_DRIVES_STALE_CYCLES */
} ls_drives_config_t;

/* One axis's run-time state (private to ls_drives.c). */
typedef struct {
    ls_402_axis_t ax;
    ls_402_out_t out;
    ls_402_unwrap_t unwrap;
    bool fresh_seen;    /* a TPDO arrived since the node became READY */
    uint32_t last_age;  /* age of the TPDO, in SYNC periods */
    uint32_t sw0, pos0; /* the script's READ_INTO targets: statusword, position actual */
    uint16_t statusword;
    int32_t pos_raw;
    int32_t hold_raw; /* the target while no set-point was given */
    double q, qd;
    double q_cmd, qd_cmd;
    bool cmd_valid;        /* command() gave a set-point since enable */
    uint16_t emcy_code;    /* the last EMCY's error code (0: none since boot) */
    const char *emcy_name; /* its name */
    uint32_t feedback_age; /* control cycles since the last fresh TPDO */
    uint32_t step_epoch;   /* the enable_epoch of the last 402 step: `out` answers that enable() */
    uint32_t taken_sync;   /* the master's SYNC count when the last TPDO was taken */
    bool read_error_code;  /* an EMCY came: read 0x603F once the drives are disabled */
    bool reading;          /* that SDO read runs */
    bool rebooting;        /* an enable asked the lost drive to be configured again */
    uint32_t ready_sync;   /* its SYNC count when the drives became READY */
    uint32_t lim0[2];      /* the script's READ_INTO targets: 0x607D:01, :02 */
    int8_t mode_shown;     /* 0x6061 from TPDO1 (map_mode) or read over SDO */
    bool mode_known;
    int8_t mode_cmd; /* what RPDO1 carries (map_mode) */
    /* Homing (home()): its phase (private enum of ls_drives.c), the SYNC
     * count its last command went out before, its deadline, the SDO step
     * of a mode change without map_mode, and why it failed. */
    hal_home_t home;
    uint8_t hm_phase;
    uint8_t hm_sdo;
    uint32_t hm_sync;
    uint64_t hm_deadline_us;
    char hm_text[HAL_JOINT_TEXT_LEN];
    /* The readouts as received (TPDO1 / TPDO2). */
    uint32_t ro_raw[LS_DRIVE_RO_COUNT];
    bool ro_seen[LS_DRIVE_RO_COUNT];
    uint32_t taken_sync2; /* the SYNC count when TPDO2 was last taken */
} ls_drive_axis_t;

typedef struct {
    ls_drives_config_t cfg;
    ls_co_master_t master;
    ls_co_step_t script[HAL_ARM_MAX_JOINTS][LS_DRIVES_SCRIPT_MAX];
    ls_drive_axis_t axis[HAL_ARM_MAX_JOINTS];
    bool want_enabled;
    bool reset_allowed;    /* an enable asked since the last disable: FAULTs may be reset */
    uint32_t enable_epoch; /* enable() calls: a joint is ENABLED only by a step taken since the last one */
    uint32_t enable_sync;  /* the master's SYNC count at the latest enable() */
    uint64_t now_us;       /* the last update()'s time (enable() has none of its own) */
    bool link_failed;      /* the link failed or is bus-off: every drive lost until an enable */
    uint32_t status_tick;
    hal_arm_event_t events[LS_DRIVES_EVENTS]; /* reported, not yet taken (next_event) */
    unsigned ev_head, ev_count;
    uint32_t events_lost;
    uint32_t tick; /* control cycles since boot, modulo cycle_ticks */
    bool booted;
    char text[LS_CO_TEXT_LEN]; /* why init or boot failed */
    ls_drive_layout_t layout[HAL_ARM_MAX_JOINTS];
    /* readouts: built by the control thread (ro_build), published through
     * the seqlock; ro_last is the comms thread's last good copy */
    hal_arm_readout_t ro_build;
    atomic_uint ro_seq;
    atomic_uint ro_words[LS_SEQLOCK_WORDS(sizeof(hal_arm_readout_t))];
    hal_arm_readout_t ro_last;
} ls_drives_t;

/* Check the configuration and prepare the master and the scripts (init
 * time; sends nothing). Returns LS_OK, or LS_EINVAL with ls_drives_text()
 * naming what is wrong (NULL pointers, joint counts, a scale that
 * ls_402_scale_init refuses, a cycle or heartbeat of 0, what
 * ls_co_master_init refuses); *d is not usable then. */
int ls_drives_init(ls_drives_t *d, const ls_drives_config_t *cfg);

/* Start the boot of every drive (NMT reset communication, the master's
 * boot-up and heartbeat). Init time. */
int ls_drives_boot(ls_drives_t *d, uint64_t now_us);

/* The bus work of one moment: take received frames (at most
 * LS_DRIVES_RX_PER_CYCLE), run the master's timers. Call it often (1 ms)
 * while booting; update() calls it every control cycle. Returns 1 when
 * every drive is READY, 0 while some still boot, LS_ETIMEDOUT / LS_EIO /
 * LS_EPROTO when one failed (boot deadline, a refused step, an identity
 * mismatch: ls_drives_text() names the joint, the node, the object and
 * the cause), LS_EIO also when the link failed. */
int ls_drives_service(ls_drives_t *d, uint64_t now_us);

/* One line on the latest failure; "" when none. Never NULL. */
const char *ls_drives_text(const ls_drives_t *d);

/* The HAL arm whose operations are these drives' (self = d). */
void ls_drives_arm(ls_drives_t *d, hal_arm_t *out);

/* After the boot (init time): each drive's software position limits
 * (0x607D, read by its script where the EDS lets them be read) against the
 * robot model's joint limits q_min_rad..q_max_rad (n_joints entries). A
 * drive range whose min is not below its max is none (the drive enforces
 * no limit: CiA 402's convention, and EPOS4's 0/0). Returns LS_OK, or
 * LS_ERANGE with `msg` naming the joint, the node and both ranges in
 * radians for the first drive whose range does not contain the model's
 * (within one count), LS_EINVAL for NULL pointers. */
int ls_drives_check_limits(const ls_drives_t *d, const double *q_min_rad, const double *q_max_rad, char *msg,
                           size_t msglen);

#endif
