/* One simulated drive on the bus: a CiA 301 slave (NMT, SDO server, PDOs,
 * SYNC consumer, heartbeat producer and consumer, EMCY producer; sd_node.c,
 * sd_sdo.c) carrying a CiA 402 drive for one joint (sd_drive.c). Internal
 * to hal/sim/drives: hal_sim_drives.h is the public face (and documents the
 * behaviour a master sees).
 *
 * Portable like the firmware's protocol modules: no OS calls, no
 * allocation, no clock. Time comes in as now_us (any monotonic microsecond
 * clock); the joint comes in as feedback (sd_joint_fb_t) and goes out as a
 * command (sd_joint_cmd_t), so the node never calls the world. Frames go
 * out through the tx callback of its config, called synchronously from
 * inside these functions. One thread owns a node. */
#ifndef SD_NODE_H
#define SD_NODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "hal_sim_drives.h"
#include "ls_canopen.h"
#include "sd_od.h"

#define SD_MAX_PDOS 4u                     /* RPDOs and TPDOs each: the EDS's 0x1400.. and 0x1800.. (checked at init) */
#define SD_MAX_HB_CONSUMERS 8u             /* entries of 0x1016 */
#define SD_SDO_TIMEOUT_US 1000000u         /* a segmented transfer waits this long for the client's next frame */
#define SD_SDO_BUF (SD_OD_STRING_MAX + 1u) /* one byte more than any value: an over-long download is seen */

/* CiA 402 power states (the statusword shows them, sd_drive.c). */
typedef enum {
    SD_DS_NOT_READY,
    SD_DS_SWITCH_ON_DISABLED,
    SD_DS_READY,
    SD_DS_SWITCHED_ON,
    SD_DS_OPERATION_ENABLED,
    SD_DS_QUICK_STOP,
    SD_DS_FAULT_REACTION,
    SD_DS_FAULT,
} sd_ds_t;

/* NMT state of the node: the heartbeat's byte, plus one that never boots. */
#define SD_NMT_DEAD 0xFFu /* stuck in initialisation (the no-boot misbehaviour): silent, deaf */

/* The joint as the world has it. */
typedef struct {
    double q_rad, qd_rad_s, tau_Nm;
} sd_joint_fb_t;

/* What the drive asks of its joint for one physics sub-step. */
typedef struct {
    double q_rad, qd_rad_s;
    bool drive_on; /* false: the joint's brake holds it */
} sd_joint_cmd_t;

struct sd_node;
/* Called for every frame the node sends, from inside the sd_node_* call
 * that produced it. */
typedef void (*sd_tx_fn)(void *ctx, const struct sd_node *from, const hal_can_frame_t *frame);

typedef struct {
    uint8_t node_id;                /* 1..127 */
    double counts_per_rad;          /* > 0: the position unit */
    int32_t position_offset_counts; /* added to the encoder count (wraps) */
    double torque_max_Nm;           /* > 0: torque actual is per mille of this */
    sd_tx_fn tx;
    void *tx_ctx;
} sd_node_config_t;

typedef struct {
    int16_t entry[LS_CO_PDO_MAX_ENTRIES]; /* OD entries, in frame order */
    uint8_t bytes[LS_CO_PDO_MAX_ENTRIES];
    uint8_t n;   /* mapped entries in use */
    uint8_t len; /* bytes of the frame */
    /* RPDO: the last frame, waiting for its SYNC (synchronous types) */
    bool pending;
    uint8_t data[8];
    /* TPDO */
    uint8_t sync_count;
    bool sent_once;
    uint8_t last[8];
    uint64_t inhibit_until_us, event_due_us;
} sd_pdo_t;

typedef struct {
    uint8_t state; /* SD_SDO_IDLE, _DOWNLOAD, _UPLOAD (sd_sdo.c) */
    int entry;
    uint8_t toggle;
    uint8_t buf[SD_SDO_BUF];
    size_t len, pos;
    size_t size_indicated; /* 0: the client did not say */
    uint64_t deadline_us;
} sd_sdo_t;

typedef struct {
    uint8_t node;
    uint32_t time_ms;
    bool monitoring; /* a heartbeat has come since the entry was set */
    bool timed_out;
    uint64_t last_us;
} sd_hb_consumer_t;

/* Misbehaviour on command (hal_sim_drives.h "Control socket"). */
typedef struct {
    bool silent;      /* sends nothing */
    bool tpdo_frozen; /* sends no TPDO */
    bool no_boot;     /* at its next reset it stays in initialisation */
    uint32_t sticky;  /* fault-reset edges to ignore */
    bool identity;    /* answer 0x1018:01/02 with these */
    uint32_t vendor, product;
} sd_misbehaviour_t;

typedef struct {
    sd_ds_t state;
    uint16_t cw; /* the last controlword applied */
    bool sto;    /* safe torque off input active */
    bool homed;
    uint32_t home_shift;  /* counts added to the encoder after homing */
    uint8_t homing;       /* SD_HM_* (sd_drive.c) */
    bool following_error; /* statusword bit 13 in CSP */
    bool limited;         /* the target was clamped to 0x607D */
    double fe_time_s;     /* how long the following error has exceeded the window */
    /* the joint's command: the interpolation segment of the current SYNC */
    double seg_q0, seg_q1, seg_ff, seg_T, seg_t;
    double q_cmd, qd_cmd;
    double v_qs; /* quick stop ramp: the commanded velocity, decaying to 0 */
    sd_joint_fb_t fb;
} sd_drive_t;

/* The OD entries the node uses, resolved once (sd_node_check_od): SD_OD_NONE
 * for an optional object the EDS does not have. */
typedef struct {
    int cw, sw, modes, modes_display, pos_actual, vel_actual, torque_actual, target, vel_offset, error_code,
        error_register, fe_window, fe_timeout, fe_actual, home_offset, homing_method, sw_min, sw_max, qs_option,
        qs_decel, abort_option, interp_value, interp_index, supported_modes, sync_cobid, emcy_cobid, producer_hb,
        error_behaviour, vendor, product, brake, sto, temperature, hb_count;
} sd_entries_t;

typedef struct sd_node {
    sd_node_config_t cfg;
    uint8_t nmt; /* LS_CO_NMT_* or SD_NMT_DEAD */
    sd_od_t od;
    sd_sdo_t sdo;
    uint8_t n_rpdo, n_tpdo;
    sd_pdo_t rpdo[SD_MAX_PDOS], tpdo[SD_MAX_PDOS];
    uint8_t n_consumers;
    sd_hb_consumer_t cons[SD_MAX_HB_CONSUMERS];
    uint64_t hb_next_us;
    /* errors behind the error register and EMCY (sd_node_error_*) */
    uint16_t fault_code; /* the drive's fault (0x603F); 0: none */
    bool hb_error;       /* a consumer timed out */
    bool pdo_len_error;  /* an RPDO came short */
    sd_misbehaviour_t mis;
    sd_drive_t drv;
    sd_entries_t e;
} sd_node_t;

/* Check that the EDS has every object the node needs and fits its limits
 * (PDO and consumer counts). Init; O(objects). LS_OK or LS_EINVAL with msg
 * naming the object. */
int sd_node_check_od(char *msg, size_t msglen);

/* Power on: every object to its default, the drive to SWITCH ON DISABLED
 * with its brake on, then the boot-up message and PRE-OPERATIONAL. `fb`:
 * where the joint is. Init. cfg is copied; sd_node_check_od() must have
 * passed. */
void sd_node_init(sd_node_t *n, const sd_node_config_t *cfg, const sd_joint_fb_t *fb, uint64_t now_us);

/* A frame from the bus. NMT, SYNC (see sd_node_take_sync), heartbeats,
 * SDO requests and RPDOs for this node; the rest is ignored. */
void sd_node_rx(sd_node_t *n, const hal_can_frame_t *f, uint64_t now_us);

/* True when `f` is this node's SYNC and the node listens to it
 * (PRE-OPERATIONAL or OPERATIONAL). */
bool sd_node_is_sync(const sd_node_t *n, const hal_can_frame_t *f);

/* The SYNC's work before the physics: send the synchronous TPDOs due
 * (sampled now), apply the synchronous RPDOs received since the last SYNC,
 * and let the drive take its set-point for the coming period. */
void sd_node_sync(sd_node_t *n, uint64_t now_us);

/* The interpolation period 0x60C2 in s, clamped to (0, 0.1]. */
double sd_node_period_s(const sd_node_t *n);

/* The joint command for the next physics sub-step of dt_s (advances the
 * interpolation or the quick-stop ramp), then, after the step, the joint as
 * it ended up (following error, the ramp's end). */
void sd_node_substep(sd_node_t *n, double dt_s, sd_joint_cmd_t *cmd);
void sd_node_feedback(sd_node_t *n, const sd_joint_fb_t *fb, double dt_s, uint64_t now_us);

/* Timers: heartbeat production and consumption, the SDO time-out, the fault
 * reaction's end, event-driven TPDOs (changed values, inhibit time, event
 * timer). Call after every event and when sd_node_next_due_us() comes. */
void sd_node_tick(sd_node_t *n, uint64_t now_us);
/* The earliest time sd_node_tick has work; UINT64_MAX: none. */
uint64_t sd_node_next_due_us(const sd_node_t *n, uint64_t now_us);

/* Misbehaviour and inputs from the control socket. */
void sd_node_inject_emcy(sd_node_t *n, uint16_t code, uint64_t now_us);
void sd_node_set_sto(sd_node_t *n, bool active, uint64_t now_us);
/* Reaction of the communication profile to a lost bus (0x6007). */
void sd_node_bus_off(sd_node_t *n, uint64_t now_us);
void sd_node_bus_recovered(sd_node_t *n, uint64_t now_us);
/* Clear every misbehaviour; a node held in initialisation boots. */
void sd_node_behave(sd_node_t *n, uint64_t now_us);

/* ---- shared by sd_node.c, sd_sdo.c and sd_drive.c ---- */

/* Send one frame (dropped while the node is silenced). */
void sd_node_send(sd_node_t *n, uint32_t id, const uint8_t *data, uint8_t len);

/* SDO access with the communication and drive profiles' rules: the value's
 * bytes (live values refreshed first) or the write's checks and side
 * effects. 0 or the abort code; nothing changes on error. */
uint32_t sd_node_read(sd_node_t *n, int entry, uint8_t *buf, size_t cap, size_t *len, uint64_t now_us);
uint32_t sd_node_write(sd_node_t *n, int entry, const uint8_t *buf, size_t len, uint64_t now_us);

/* The error register's bits from the errors present; raise or clear one
 * (an EMCY with the code, or 0x0000 once none is left). */
uint8_t sd_node_error_register(const sd_node_t *n);
void sd_node_emcy(sd_node_t *n, uint16_t code);
void sd_node_error_cleared(sd_node_t *n);

/* SDO server (sd_sdo.c): a request frame, and its time-out. */
void sd_sdo_rx(sd_node_t *n, const hal_can_frame_t *f, uint64_t now_us);
void sd_sdo_tick(sd_node_t *n, uint64_t now_us);
void sd_sdo_reset(sd_node_t *n);

/* CiA 402 drive (sd_drive.c). */
void sd_drive_reset(sd_node_t *n);
/* A controlword was written (SDO or RPDO): run the power state machine. */
void sd_drive_controlword(sd_node_t *n, uint16_t cw, uint64_t now_us);
/* 0x6060 was written: the mode display follows. */
void sd_drive_mode(sd_node_t *n, int8_t mode);
/* Refuse a value the drive cannot take (modes, homing methods, 0x60C2);
 * 0 or the abort code. */
uint32_t sd_drive_check(const sd_node_t *n, int entry, int64_t value);
/* Refresh the live objects (statusword, actual values, brake). */
void sd_drive_refresh(sd_node_t *n);
/* A fault: FAULT REACTION ACTIVE, the brake on, the EMCY; FAULT at the next
 * tick. A fault while already faulted keeps the first code. */
void sd_drive_fault(sd_node_t *n, uint16_t code, uint64_t now_us);
/* 0x6007's reaction to a lost connection, with the EMCY code of the cause. */
void sd_drive_abort_connection(sd_node_t *n, uint16_t code, uint64_t now_us);
void sd_drive_sync(sd_node_t *n);
void sd_drive_substep(sd_node_t *n, double dt_s, sd_joint_cmd_t *cmd);
void sd_drive_feedback(sd_node_t *n, const sd_joint_fb_t *fb, double dt_s, uint64_t now_us);
void sd_drive_tick(sd_node_t *n, uint64_t now_us);
void sd_drive_set_sto(sd_node_t *n, bool active, uint64_t now_us);
/* The encoder count of a joint angle and back (offset, homing, int32 wrap). */
int32_t sd_drive_counts(const sd_node_t *n, double q_rad);
double sd_drive_rad(const sd_node_t *n, int32_t counts);

#endif
