/* Simulated CiA 402 servo drives: the joints of the simulated world
 * (hal/sim/world) behind CANopen slaves on a CAN link, one node per joint.
 * ls-simdrives (firmware/app/ls_simdrives.c) runs them as a program; a
 * master (landscaped's drive bus, python-canopen) sees standard drives.
 *
 * One set of drives per process: the state is static, like the world's.
 * open() and close() run at init and shutdown; everything else is called
 * from one thread (the program's loop), never blocks and never allocates.
 * The world must be open before open() and closed after close(); the link
 * is the caller's, opened before and closed after.
 *
 * Costs: a frame is O(nodes x objects it maps) (an SDO request O(log
 * objects)); a SYNC adds one world step per sub-step (1 ms unless
 * configured) of the interpolation period (ODE, about 7 us each here) with
 * every drive's command; timers are O(nodes). Memory is static (about 2.5
 * KiB a node, 8 KiB of output queue); nothing allocates after open
 * (tests/unit/simdrives proves it, the world included).
 *
 * ---------------------------------------------------------------------------
 * The object dictionary: ls-simdrive.eds
 * ---------------------------------------------------------------------------
 * hal/sim/drives/ls-simdrive.eds (installed as share/landscape/ls-simdrive.eds)
 * is the drive's description; the build generates the object dictionary from
 * it (gen_od.py), so every object, type, access right, PDO-mappability,
 * default and value limit a master reads in the EDS is what the node does.
 * Identity: vendor 0x00004C53 (not a CiA-assigned id: the simulator's own),
 * product 0x53440001, revision 0x00010000, serial 0x53440000 + node id.
 *
 * ---------------------------------------------------------------------------
 * CiA 301
 * ---------------------------------------------------------------------------
 * NMT: every node sends its boot-up (0x700 + id, one byte 0) at open and
 * after NMT reset node (every object to its default, the drive off, its
 * homing and faults forgotten) or reset communication (0x1000-0x1FFF to
 * their defaults), then is PRE-OPERATIONAL. SDO in PRE-OPERATIONAL and
 * OPERATIONAL; PDOs in OPERATIONAL only; STOPPED answers NMT and sends its
 * heartbeat, nothing else.
 * SDO server (0x600 + id -> 0x580 + id): expedited and segmented upload and
 * download; block transfer is refused (command specifier). Aborts:
 * 0x06020000 no object, 0x06090011 no sub-index, 0x06010002 write to ro or
 * const, 0x06010001 read of wo, 0x06070012/0x06070013 a length that is not
 * the type's, 0x06090031/0x06090032 beyond the EDS's HighLimit/LowLimit,
 * 0x06090030 a value the drive cannot take (an unsupported mode, a
 * homing method other than 35/37, the PDO rules below), 0x05030000 toggle
 * bit, 0x05040001 an unexpected command specifier, 0x05040000 when a
 * segmented transfer waits 1 s for the client's next frame.
 * PDOs (four each way): a valid PDO (COB-ID bit 31 clear) refuses a change
 * of its COB-ID, transmission type, inhibit time and mapping (0x06090030);
 * a mapping is changed with sub 0 = 0, the entries (refused while sub 0 is
 * not 0), then sub 0 = N, which checks entries 1..N: an object that does not
 * exist 0x06020000 or 0x06090011, one not mappable in that direction or of
 * another length 0x06040041, more than 64 bits 0x06040042. A COB-ID is
 * refused when it enables a PDO that maps nothing, has bit 29 or bits
 * 11-28 set, or is 0. RPDO types 0-240 are applied at the next SYNC, 254
 * and 255 at once; an RPDO shorter than its mapping is dropped with EMCY
 * 0x8210. TPDO types 1-240 go out at every n-th SYNC, 0 at a SYNC after a
 * change, 254/255 on a change (inhibit time 0x1800:03) and on the event
 * timer (0x1800:05); no RTR. A synchronous TPDO samples the joint at the
 * SYNC, before that SYNC's set-points act.
 * SYNC: consumed on 0x1005's COB-ID (bit 30, producing, is refused).
 * Heartbeat producer 0x1017 (ms); consumer 0x1016:1-2 (node << 16 | ms;
 * two entries for one node: 0x06040043): monitoring of a node starts at its
 * first heartbeat; a time-out sends EMCY 0x8130, applies the drive's 0x6007
 * reaction and moves NMT as 0x1029:01 says (0: OPERATIONAL -> PRE-OP, 1:
 * no change, 2: STOPPED); the node's next heartbeat resumes monitoring.
 * EMCY (0x80 + id): error code, error register 0x1001, the CiA 402 state
 * (sd_ds_t) in byte 3; every fault sends one, and 0x0000 goes out when the
 * last error clears. Not sent in STOPPED.
 *
 * ---------------------------------------------------------------------------
 * CiA 402
 * ---------------------------------------------------------------------------
 * The power state machine follows the controlword (transitions 2-12, 15,
 * 16; SWITCHED ON passes at once on enable operation from READY TO SWITCH
 * ON); fault reset acts on the rising edge of bit 7 only. Modes 0x6060:
 * 0 (hold), 6 (homing) and 8 (CSP), as 0x6502 says; 0x6061 follows at once;
 * others are refused. The brake (0x2100:01) is released only while the
 * power stage is on: OPERATION ENABLED and QUICK STOP ACTIVE; a braked
 * joint is held by the world's brake model. Position unit: counts,
 * counts_per_rad per radian, plus the configured offset and the homing
 * shift, as an int32 that wraps; velocity counts/s; torque actual per mille
 * of the joint's maximum torque (0 while braked).
 * CSP: at each SYNC the drive takes 0x607A (clamped to 0x607D when min <
 * max, statusword bit 11) and 0x60B1 (the velocity feed-forward: without it
 * the joint lags v / 200 rad); the physics then advances by the
 * interpolation period 0x60C2 (the largest of the nodes', at most 100 ms)
 * in sub-steps of about 1 ms (or substep_s), the command moving linearly
 * from where it was to the target. No SYNC, no motion. Following error:
 * |command - actual| above 0x6065 counts for 0x6066 ms -> FAULT, EMCY
 * 0x8611, statusword bit 13 (0x6065 = 0xFFFFFFFF: off); 0x60F4 reports it.
 * Entering OPERATION ENABLED holds the joint where it is; the first SYNC
 * takes 0x607A as it stands (a target far from the actual position is a
 * jump, as on a real drive, and ends in a following error).
 * Quick stop (0x605A): 0 brakes at once; otherwise the command ramps the
 * joint's actual velocity to 0 at 0x6085 counts/s^2 (in physics time: no
 * SYNC, no ramp), then 1-4 go to SWITCH ON DISABLED, 5-8 stay in QUICK STOP
 * ACTIVE (enable operation resumes). 0x6007 on a heartbeat time-out, NMT
 * stop, reset communication and bus-off, while the power stage is on: 0
 * nothing, 1 fault (the cause's code: 0x8130 heartbeat, 0x8100 NMT, 0x8140
 * bus-off), 2 disable voltage, 3 quick stop.
 * Homing (mode 6, in OPERATION ENABLED): the rising edge of controlword bit
 * 4 runs method 37 (or 35): the current position becomes 0x607C; statusword
 * bits 10 + 12 (attained); another method: 10 + 13 (error). The homing
 * survives disable and enable; reset node forgets it.
 * Temperature (0x2100:03, 0.1 degrees Celsius): 30.0 at rest, rising with
 * the torque the drive gives (a quarter of a tenth of a degree per mille of
 * the joint's maximum torque), so a readout shows a working axis warm.
 * Safe torque off (0x2100:02, set from the control socket): the power stage
 * goes off at once (SWITCH ON DISABLED, brake on, no fault) and switch on
 * is refused while it lasts; statusword bit 7 (warning) shows it.
 *
 * ---------------------------------------------------------------------------
 * Control socket (misbehaviour on command)
 * ---------------------------------------------------------------------------
 * cfg.control_socket_path: a Unix SOCK_DGRAM socket bound at open and
 * unlinked at close (a stale socket file is replaced). One command per
 * datagram, ASCII, fields separated by spaces or tabs, an optional trailing
 * newline, at most 255 bytes; numbers in C notation (0x2310 hex, 33
 * decimal); NODE is one of the configured node ids:
 *     emcy NODE CODE       EMCY with that code; the drive goes to FAULT
 *     silence NODE         the node sends nothing (heartbeat, PDO, SDO, EMCY)
 *     freeze-tpdo NODE     its TPDOs stop; heartbeat and SDO go on
 *     sticky-fault NODE N  the next N fault-reset edges leave it in FAULT
 *     no-boot NODE         after its next NMT reset it never boots: no
 *                          boot-up, no heartbeat, no answer
 *     identity NODE VENDOR PRODUCT   0x1018:01/02 answer these
 *     sto NODE on|off      the safe torque off input
 *     bus-off [MS]         the link carries nothing either way for MS ms
 *                          (default 1000); each node then sends EMCY 0x8140
 *     reset                every misbehaviour off; a node held in
 *                          initialisation boots (STO stays as set)
 * Anything else is counted (hal_sim_drives_malformed_messages()) and
 * ignored; nothing is answered. e.g.
 *     socat - UNIX-SENDTO:/tmp/ls-drives.sock <<< 'emcy 0x21 0x2310'
 */
#ifndef HAL_SIM_DRIVES_H
#define HAL_SIM_DRIVES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "hal_sim_world.h"

#define HAL_SIM_DRIVES_MAX HAL_SIM_ARM_JOINTS /* one drive per joint at most */
#define HAL_SIM_DRIVES_CTL_MAX_MSG 255u
#define HAL_SIM_DRIVES_BUS_OFF_DEFAULT_MS 1000u

/* The manufacturer objects of ls-simdrive.eds. */
#define SD_OBJ_LABEL 0x2000u     /* VISIBLE_STRING rw: a free label */
#define SD_OBJ_BRAKE_STO 0x2100u /* record: */
#define SD_SUB_BRAKE_ENGAGED 1u  /*   u8 ro, mappable: 1 while the holding brake holds */
#define SD_SUB_STO_ACTIVE 2u     /*   u8 ro, mappable: 1 while safe torque off is active */
#define SD_SUB_TEMPERATURE 3u    /*   i16 ro, mappable: the drive's temperature, 0.1 degrees Celsius */

#define HAL_SIM_DRIVES_SUBSTEP_S 0.001 /* the physics' default sub-step */
#define HAL_SIM_DRIVES_SUBSTEP_MAX_S 0.1
#define HAL_SIM_DRIVES_RX_PER_POLL 64u /* frames taken from the link per poll() */

typedef struct {
    uint8_t node_id;                /* 1..127, distinct */
    uint8_t joint;                  /* 0..5, distinct */
    int32_t position_offset_counts; /* the encoder count at q = 0 (wraps) */
} hal_sim_drive_config_t;

typedef struct {
    hal_can_link_t *link; /* the caller's; used until close() */
    size_t n_drives;      /* 1..HAL_SIM_DRIVES_MAX */
    hal_sim_drive_config_t drives[HAL_SIM_DRIVES_MAX];
    double counts_per_rad;           /* > 0, at most 1e9 */
    const char *control_socket_path; /* NULL: no control socket */
    /* The physics' sub-step, about (a period is cut into whole steps): 0
     * means HAL_SIM_DRIVES_SUBSTEP_S. Longer steps for a machine that cannot
     * step the world every millisecond in real time (the VM tier's emulated
     * guest, about 4 ms of CPU per step); at most 0.1 s. */
    double substep_s;
} hal_sim_drives_config_t;

typedef struct {
    uint64_t syncs;      /* SYNC frames that stepped the physics */
    uint64_t substeps;   /* physics sub-steps */
    uint64_t rx_frames;  /* frames from the link */
    uint64_t tx_frames;  /* frames handed to the link */
    uint64_t tx_dropped; /* frames lost: queue full, link refused, bus-off */
} hal_sim_drives_stats_t;

/* Build the nodes (every one sends its boot-up) on the open world. Init
 * only: binds the control socket. LS_OK, or LS_EINVAL (bad config, already
 * open, an EDS that lacks what the drive needs, socket path too long or
 * taken by a non-socket), LS_ENODEV (the world is not open) or LS_EIO
 * (socket), with msg naming the cause; nothing is left open on error. */
int hal_sim_drives_open(const hal_sim_drives_config_t *cfg, uint64_t now_us, char *msg, size_t msglen);

/* Close the control socket (unlinking its file). Safe when not open. */
void hal_sim_drives_close(void);

/* Everything due: the link's received frames (at most
 * HAL_SIM_DRIVES_RX_PER_POLL: a SYNC steps the world, and a machine too slow
 * for the bus must still run the timers, as a drive's heartbeat runs
 * whatever the bus carries), the control socket's commands (at most 64 per
 * call), timers, then the frames the nodes sent, out to the link; the
 * frames left wait for the next call. LS_OK, LS_ENODEV when not open, or the
 * link's negative status when it failed: the nodes ran on all the same (a
 * drive outlives its bus: its heartbeat consumer acts), and the frames the
 * link would not take are dropped and counted (tx_dropped). */
int hal_sim_drives_poll(uint64_t now_us);

/* One frame as if it came from the link, and the frames it caused handed
 * to the link (tests, fuzzing). LS_OK or LS_ENODEV. */
int hal_sim_drives_rx(const hal_can_frame_t *frame, uint64_t now_us);

/* One control command (the socket's protocol, without the socket): 1 when
 * applied, LS_EINVAL when malformed (and counted), LS_ENODEV when closed. */
int hal_sim_drives_control(const char *text, size_t len, uint64_t now_us);

/* When poll() next has work without a frame or a command arriving;
 * UINT64_MAX: nothing. */
uint64_t hal_sim_drives_next_due_us(uint64_t now_us);

/* The control socket (readable when a command waits), -1 without one. */
int hal_sim_drives_control_fd(void);

/* True while frames wait for room in the link (poll its fd writable). */
bool hal_sim_drives_tx_pending(void);

uint32_t hal_sim_drives_malformed_messages(void);
void hal_sim_drives_stats(hal_sim_drives_stats_t *out);

#endif
