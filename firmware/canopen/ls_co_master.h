/* CiA 301 master for a few CANopen nodes (servo drives) on one CAN bus: NMT
 * boot with a deadline, a configuration script per node over SDO, heartbeat
 * consumer per node and the master's own heartbeat producer, EMCY
 * consumer, SYNC producer and up to LS_CO_NODE_PDOS RPDOs and TPDOs per
 * node. Portable like firmware/isotp: C11, no OS calls, no clock reads (time
 * is passed in), no heap (the caller owns the ls_co_master_t; every table
 * has a static size), frames out through a send function that never blocks.
 *
 * Usage (one thread: the control thread, every control cycle):
 *   init:                       ls_co_master_init(&m, &cfg, send_fn, ctx);
 *                               ls_co_master_boot(&m, now_us);
 *   every received CAN frame:   ls_co_master_on_frame(&m, &frame, now_us);
 *   every control cycle:        ls_co_master_poll(&m, now_us);
 *   every drive cycle:          ls_co_master_tpdo_get(...)   feedback, with its age
 *                               ls_co_master_rpdo_set(...)   set-points
 *                               ls_co_master_sync(&m, now_us)
 *   whenever:                   ls_co_master_node_phase / _node_text,
 *                               ls_co_master_next_emcy, ls_co_master_counters
 *
 * Cost: on_frame is O(nodes) (routing a PDO; an 8-entry scan), poll and
 * sync are O(nodes x PDOs); a configuration step costs one SDO transfer and
 * formats a line of text only when it fails. Nothing allocates or blocks;
 * all of it may run in the 1 kHz control loop.
 *
 * CiA 301 choices, and why:
 *  - Boot uses NMT "reset communication", not "reset node": it brings the
 *    node's communication objects (PDO mapping, heartbeat, COB-IDs) back to
 *    their stored values, which the script then sets, without restarting
 *    the drive's application (a reset node may take seconds, re-home an
 *    encoder or drop a brake's state). The script is the whole truth of
 *    the node's communication configuration either way.
 *  - Liveness is heartbeat, not node guarding: heartbeats cost one frame
 *    per producer period and no request, and the drives monitor the
 *    master's heartbeat in turn (0x1016), so each side stops on its own
 *    when the other goes silent. Node guarding needs RTR frames, which
 *    CiA recommends against.
 *  - CiA 301 starts heartbeat consumption at the first heartbeat received,
 *    so a node that never boots would never time out: the boot deadline
 *    (boot_timeout_ms) catches it, and the same deadline bounds the wait
 *    for OPERATIONAL after NMT start. Monitoring here begins at the first
 *    heartbeat after the node acknowledged its producer time (0x1017,
 *    the script's implicit first step): heartbeats before it come at
 *    whatever period the node had stored, which our time-out knows nothing
 *    of. So monitoring begins during configuration.
 *  - The master starts no SDO traffic by itself while a node is READY:
 *    the bus then carries the cyclic traffic the budget was computed for
 *    (a caller may run ls_co_master_sdo_* and owns that cost).
 *  - Every RPDO of a cycle goes before its SYNC: a synchronous RPDO takes
 *    effect at the next SYNC, so one behind the SYNC would act a cycle late.
 *
 * Node phases (ls_co_phase_t): IDLE until booted; BOOTING (reset
 * communication sent, boot-up awaited until the deadline); CONFIGURING
 * (the script runs while the node is PRE-OPERATIONAL); STARTING (NMT start
 * sent, an OPERATIONAL heartbeat awaited until the deadline); READY; and
 * the two ends that only ls_co_master_reboot_node leaves: FAILED (boot or
 * configuration failed) and LOST (no heartbeat within the consumer
 * time-out, a boot-up while READY: it reset, or two heartbeats in a row
 * reporting a state other than the one the master commanded). A boot-up
 * while CONFIGURING or STARTING restarts the script (the node lost what was
 * written), at most LS_CO_BOOT_RESTARTS times. The master never reboots a
 * node by itself. */
#ifndef LS_CO_MASTER_H
#define LS_CO_MASTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "ls_canopen.h"
#include "ls_co_sdo.h"
#include "ls_err.h"

/* Per profile (CMakeLists.txt LS_PROFILE): the mcu one drives six axes. */
#if LS_PROFILE_MCU
#define LS_CO_MAX_NODES 6u
#else
#define LS_CO_MAX_NODES 8u
#endif
#define LS_CO_NODE_PDOS 2u     /* RPDOs and TPDOs per node (each direction) */
#define LS_CO_EMCY_RING 8u     /* EMCY entries kept per node until drained */
#define LS_CO_BOOT_RESTARTS 3u /* boot-ups tolerated during configuration */
#define LS_CO_HB_MISMATCHES 2u /* heartbeats in a row in another state -> LOST */
#define LS_CO_BOOT_TIMEOUT_MS_DEFAULT 2000u

/* ---- Configuration scripts */

typedef enum {
    LS_CO_STEP_WRITE = 1, /* write `value` (size 1, 2 or 4 bytes) or `bytes` */
    LS_CO_STEP_EXPECT,    /* read; (read & mask) must equal (value & mask) */
    LS_CO_STEP_READ_INTO, /* read a number of 1..4 bytes into *into */
} ls_co_step_kind_t;

/* One SDO step of a node's configuration script. The caller owns the
 * array (static: it must outlive the master), and `bytes`, `label`,
 * `source` and `into` with it. */
typedef struct {
    ls_co_step_kind_t kind;
    uint16_t index;
    uint8_t sub;
    uint8_t size;         /* WRITE of a number: 1, 2 or 4; 0 with `bytes` */
    uint32_t value;       /* WRITE: the number; EXPECT: the wanted value */
    uint32_t mask;        /* EXPECT: the bits compared; 0 means all */
    const uint8_t *bytes; /* WRITE of a byte string (size 0) */
    uint8_t bytes_len;    /* 1..LS_CO_SDO_BUF_LEN */
    const char *label;    /* EXPECT: what the object is ("vendor id"), may be NULL */
    const char *source;   /* EXPECT: who wants `value` ("the EDS"), NULL: "expected" */
    uint32_t *into;       /* READ_INTO: the answer's 1..4 bytes, little-endian, zero-extended
                             (the caller sign-extends by the object's type) */
    bool optional;        /* an abort (or EXPECT mismatch) is recorded, not fatal */
} ls_co_step_t;

/* Steps as compound literals' initialisers, for the common cases. */
#define LS_CO_WRITE(i, s, sz, v)                                                                                       \
    {                                                                                                                  \
        .kind = LS_CO_STEP_WRITE, .index = (i), .sub = (s), .size = (sz), .value = (uint32_t)(v)                       \
    }
#define LS_CO_EXPECT(i, s, v, m, lbl, src)                                                                             \
    {                                                                                                                  \
        .kind = LS_CO_STEP_EXPECT, .index = (i), .sub = (s), .value = (v), .mask = (m), .label = (lbl),                \
        .source = (src)                                                                                                \
    }
#define LS_CO_READ_INTO(i, s, ptr)                                                                                     \
    {                                                                                                                  \
        .kind = LS_CO_STEP_READ_INTO, .index = (i), .sub = (s), .into = (ptr)                                          \
    }

/* A PDO the master exchanges with a node: its COB-ID (11 bits, in
 * LS_CO_PDO_COB_MIN..LS_CO_PDO_COB_MAX) and length in bytes (1..8).
 * cob_id 0 marks an unused slot. */
typedef struct {
    uint16_t cob_id;
    uint8_t len;
} ls_co_pdo_t;

/* The PDO range of the predefined connection set (TPDO1 of node 1 to
 * RPDO4 of node 127). */
#define LS_CO_PDO_COB_MIN 0x181u
#define LS_CO_PDO_COB_MAX 0x57Fu

typedef struct {
    uint8_t node_id;               /* 1..127 */
    uint16_t boot_timeout_ms;      /* boot-up and OPERATIONAL deadline; 0: LS_CO_BOOT_TIMEOUT_MS_DEFAULT */
    uint16_t heartbeat_ms;         /* the node's producer time, written to its 0x1017 first; > 0 */
    uint16_t heartbeat_timeout_ms; /* our consumer time-out on it; > heartbeat_ms */
    const ls_co_step_t *script;    /* run in order while PRE-OPERATIONAL; may be NULL when empty */
    size_t script_len;
    ls_co_pdo_t rpdo[LS_CO_NODE_PDOS]; /* master -> node, sent by ls_co_master_sync */
    ls_co_pdo_t tpdo[LS_CO_NODE_PDOS]; /* node -> master, kept for ls_co_master_tpdo_get */
} ls_co_node_config_t;

typedef struct {
    uint8_t node_id;         /* the master's own (its heartbeat, its boot-up); 0: none (then heartbeat_ms 0) */
    uint16_t heartbeat_ms;   /* the master's heartbeat period (the drives' 0x1016 watch it); 0: off */
    uint16_t sdo_timeout_ms; /* per SDO request; 0: LS_CO_SDO_TIMEOUT_US_DEFAULT */
    size_t node_count;       /* 1..LS_CO_MAX_NODES */
    ls_co_node_config_t nodes[LS_CO_MAX_NODES];
} ls_co_master_config_t;

/* ---- State */

typedef enum {
    LS_CO_PHASE_IDLE = 0,
    LS_CO_PHASE_BOOTING,
    LS_CO_PHASE_CONFIGURING,
    LS_CO_PHASE_STARTING,
    LS_CO_PHASE_READY,
    LS_CO_PHASE_FAILED,
    LS_CO_PHASE_LOST,
} ls_co_phase_t;

/* One EMCY frame of a node, decoded (CiA 301 7.2.7.1). */
typedef struct {
    uint16_t code;     /* error code (0x0000: error reset / no error) */
    uint8_t reg;       /* error register (0x1001) */
    uint8_t vendor[5]; /* manufacturer-specific bytes (0 where the frame was shorter) */
    uint64_t t_us;     /* arrival */
    const char *name;  /* ls_co_emcy_name(code), static */
} ls_co_emcy_t;

/* Counters for a status line (all wrap at 2^32). */
typedef struct {
    uint32_t frames_in;       /* 11-bit data frames handed to on_frame */
    uint32_t frames_out;      /* frames the send function took */
    uint32_t sends_refused;   /* times the send function refused a frame (kept, retried) */
    uint32_t sdo_aborts_sent; /* by our SDO clients: time-outs, protocol errors */
    uint32_t sdo_aborts_received;
    uint32_t sdo_timeouts;
    uint32_t emcy_received;
    uint32_t emcy_lost;         /* EMCY frames that found their node's ring full */
    uint32_t unexpected;        /* frames of our nodes or services that fit nothing: a stray SDO
                                  response, a short heartbeat/EMCY/TPDO, a foreign NMT or SYNC */
    uint32_t sync_sent;         /* SYNC frames on the bus */
    uint32_t sync_deferred;     /* cycles whose frames did not all go at once (finished by poll) */
    uint32_t sync_overruns;     /* cycles still unfinished when the next sync came (restarted) */
    uint32_t heartbeats_lost;   /* nodes that became LOST by a heartbeat time-out */
    uint32_t optional_failures; /* optional script steps refused or mismatched (recorded, not fatal) */
} ls_co_counters_t;

/* Per-node state; private to ls_co_master.c (read through the functions). */
typedef struct {
    ls_co_node_config_t cfg;
    ls_co_sdo_t sdo;
    ls_co_phase_t phase;
    uint64_t deadline_us; /* BOOTING, STARTING */
    size_t step;          /* CONFIGURING: 0 = 0x1017, then script[step - 1] */
    bool step_running;    /* its SDO transfer is under way */
    unsigned restarts;    /* boot-ups during configuration */
    bool caller_sdo;      /* the SDO client runs a transfer of the caller's */
    uint8_t nmt_pending;  /* an NMT command for this node the queue refused; 0: none */
    uint8_t nmt_state;    /* last heartbeat state, LS_CO_NMT_* (0xFF: none yet) */
    uint8_t nmt_wanted;   /* READY: the state the master commanded */
    unsigned hb_mismatches;
    bool hb_monitoring; /* a heartbeat came since its 0x1017 was written */
    uint64_t hb_last_us;
    struct {
        uint8_t data[8];
        bool valid;
    } rpdo[LS_CO_NODE_PDOS];
    struct {
        uint8_t data[8];
        uint8_t len;
        bool valid;
        uint64_t t_us;
        uint32_t sync_count; /* the master's SYNC count at arrival */
    } tpdo[LS_CO_NODE_PDOS];
    ls_co_emcy_t emcy[LS_CO_EMCY_RING];
    unsigned emcy_head, emcy_count;
    char text[LS_CO_TEXT_LEN];
} ls_co_node_t;

typedef struct {
    uint8_t node_id;
    uint16_t heartbeat_ms;
    uint32_t sdo_timeout_us;
    size_t node_count;
    ls_co_node_t nodes[LS_CO_MAX_NODES];
    uint8_t index_of[LS_CO_NODE_MAX + 1u]; /* node id -> nodes[] index + 1; 0: not ours */

    ls_co_send_fn send;
    void *send_ctx;
    bool tx_blocked; /* the send function refused a frame during this call */

    uint8_t own_state; /* LS_CO_NMT_*: what the master's heartbeat says */
    bool hb_pending;
    uint64_t hb_next_us;
    bool bootup_pending;
    uint8_t nmt_all_pending; /* a broadcast NMT command waiting; 0: none */

    bool cycle_pending;  /* a sync cycle's frames are not all out */
    size_t cycle_node;   /* next node of the cycle to send RPDOs for */
    size_t cycle_pdo;    /* next RPDO slot of that node */
    uint32_t sync_count; /* SYNC frames sent */

    ls_co_counters_t counters; /* the master's own; the SDO clients count theirs */
    char text[LS_CO_TEXT_LEN]; /* why init refused the configuration */
} ls_co_master_t;

/* Statuses (ls_err.h) of the functions below, unless one says otherwise:
 * LS_OK; LS_EINVAL (m NULL, a node id that is not one of the configured
 * nodes, an argument out of its range). Nothing changes on error. */

/* Check `cfg` and prepare the master (init time). Copies the configuration
 * (the scripts stay the caller's); every node IDLE; own state
 * PRE-OPERATIONAL. Sends nothing. O(nodes x script steps).
 * LS_EINVAL for: m, cfg or send NULL; node_count 0 or above
 * LS_CO_MAX_NODES; a node id outside 1..127, repeated or the master's own;
 * heartbeat_ms 0 or heartbeat_timeout_ms not above it; a master heartbeat
 * without a master node id; a script step of unknown kind, a WRITE size
 * other than 1, 2, 4 (or bytes without a length 1..LS_CO_SDO_BUF_LEN), a
 * READ_INTO without `into`, script_len > 0 with script NULL; a PDO with a
 * COB-ID outside LS_CO_PDO_COB_MIN..MAX, a length outside 1..8, or a
 * COB-ID used twice. ls_co_master_text() then names the field in one line
 * and nothing else of *m may be used. */
int ls_co_master_init(ls_co_master_t *m, const ls_co_master_config_t *cfg, ls_co_send_fn send, void *send_ctx);

/* Why init refused the configuration; "" after a successful init. */
const char *ls_co_master_text(const ls_co_master_t *m);

/* Boot every node (each as ls_co_master_reboot_node) and, with a master
 * node id, send the master's boot-up and start its heartbeat; the master
 * enters OPERATIONAL (a self-starting NMT master). O(nodes). */
int ls_co_master_boot(ls_co_master_t *m, uint64_t now_us);

/* Boot one node again from any phase: drop its SDO transfer and PDO data,
 * send it NMT reset communication, and wait for its boot-up until its
 * deadline. The only way out of FAILED and LOST. O(1). */
int ls_co_master_reboot_node(ls_co_master_t *m, uint8_t node_id, uint64_t now_us);

/* The link failed: what was waiting to be sent (NMT commands, the rest of a
 * sync cycle, the master's boot-up and heartbeat) is dropped, as a dead bus
 * carried none of it. Without this, the first frame after the link is back
 * would send every node's stale command, and a reboot then its own again:
 * two resets, two boot-ups. Nodes keep their phases; SDO transfers time out
 * as usual. O(nodes). */
void ls_co_master_drop_unsent(ls_co_master_t *m);

/* Feed one received CAN frame. 29-bit and remote frames, and frames of no
 * configured node or service, are ignored (the bus may carry other
 * traffic). Routes SDO responses (the next request or configuration step
 * goes at once), heartbeats, EMCY and TPDOs; boot deadlines and heartbeat
 * time-outs are judged by poll. Never fails. O(nodes). */
void ls_co_master_on_frame(ls_co_master_t *m, const hal_can_frame_t *frame, uint64_t now_us);

/* Timers and queued frames: the rest of a sync cycle first (in order, SYNC
 * last), then NMT commands, the master's heartbeat, then each node's SDO
 * client; deadlines and heartbeat time-outs; the next configuration step
 * or NMT start. Stops offering frames at the first refusal (the CAN queue
 * is full; the rest goes at the next poll). O(nodes). */
void ls_co_master_poll(ls_co_master_t *m, uint64_t now_us);

/* One drive cycle: every set RPDO of every READY node that the master
 * keeps OPERATIONAL, node by node in configuration order, then the SYNC
 * frame. A frame the send function refuses is kept and the cycle finishes
 * on the next polls, in order, SYNC last (counted in sync_deferred); a
 * cycle still unfinished when the next sync comes is restarted from its
 * first RPDO (counted in sync_overruns): its RPDO bytes are the newest
 * anyway. Sends no SDO. O(nodes x PDOs). */
int ls_co_master_sync(ls_co_master_t *m, uint64_t now_us);

/* Set RPDO `slot` (0..LS_CO_NODE_PDOS-1) of a node: `len` must be its
 * configured length (else LS_ELEN). Sent by every sync from now on while
 * the node is READY and OPERATIONAL. O(len). */
int ls_co_master_rpdo_set(ls_co_master_t *m, uint8_t node_id, size_t slot, const uint8_t *data, size_t len);

/* The last TPDO `slot` received from a node: its bytes (out holds 8), its
 * configured length, and its age in SYNC periods (0: it arrived after the
 * latest SYNC, the answer to it; n: n SYNCs went out since). LS_EAGAIN when
 * none arrived since the node's last boot (outputs untouched). A TPDO
 * shorter than configured is dropped and counted in `unexpected`; longer
 * ones are cut to the configured length. O(8). */
int ls_co_master_tpdo_get(const ls_co_master_t *m, uint8_t node_id, size_t slot, uint8_t *out, size_t *len,
                          uint32_t *age_syncs);

/* Take the oldest EMCY of a node from its ring (LS_CO_EMCY_RING entries;
 * when full, new frames are dropped and counted in emcy_lost: the first
 * errors name the cause). Returns 1 when *out was written, 0 when the ring
 * is empty, LS_EINVAL. O(1). */
int ls_co_master_next_emcy(ls_co_master_t *m, uint8_t node_id, ls_co_emcy_t *out);

/* Send an NMT command (LS_CO_NMT_START, _STOP, _ENTER_PREOP, _RESET_NODE,
 * _RESET_COMM) to one configured node, or to all (node_id
 * LS_CO_NMT_ALL_NODES: one broadcast frame). A refused frame waits, the
 * latest command per node winning. READY nodes are then expected in the
 * commanded state (their heartbeats are checked against it); a reset
 * returns the node to IDLE (configure it again with
 * ls_co_master_reboot_node). LS_EINVAL for any other command. O(nodes). */
int ls_co_master_nmt(ls_co_master_t *m, uint8_t node_id, uint8_t command, uint64_t now_us);

/* The master's own NMT state (LS_CO_NMT_*), carried by its heartbeat. */
uint8_t ls_co_master_state(const ls_co_master_t *m);
/* Set it: LS_CO_NMT_PREOPERATIONAL, _OPERATIONAL or _STOPPED (LS_EINVAL
 * otherwise). The next heartbeat carries it. */
int ls_co_master_set_state(ls_co_master_t *m, uint8_t state);

/* Run one SDO transfer of the caller's on a node in any phase but
 * CONFIGURING and BOOTING (LS_EBUSY then, or while its client is busy);
 * on a READY node the caller owns the bus time it takes. Also LS_ELEN as
 * ls_co_sdo_write. The transfer ends with LS_EIO when the node is lost or
 * booted again meanwhile. The outcome: */
int ls_co_master_sdo_write(ls_co_master_t *m, uint8_t node_id, uint16_t index, uint8_t sub, const uint8_t *data,
                           size_t len, uint64_t now_us);
int ls_co_master_sdo_read(ls_co_master_t *m, uint8_t node_id, uint16_t index, uint8_t sub, uint64_t now_us);
/* LS_EBUSY while it runs; then as ls_co_sdo_status, the bytes copied to
 * `out` (up to cap; *len gets the count, out and len may be NULL). A failure
 * also sets the node's text. */
int ls_co_master_sdo_result(const ls_co_master_t *m, uint8_t node_id, uint8_t *out, size_t cap, size_t *len);

/* The node's phase (LS_CO_PHASE_IDLE for an unknown node id). */
ls_co_phase_t ls_co_master_node_phase(const ls_co_master_t *m, uint8_t node_id);
/* The node's last heartbeat state (LS_CO_NMT_*), 0xFF when none came. */
uint8_t ls_co_master_node_nmt_state(const ls_co_master_t *m, uint8_t node_id);
/* One line on the node's last failure or notable event, naming the node,
 * the object and the cause ("node 0x22: no boot-up within 2000 ms"); ""
 * when nothing happened since its boot. Never NULL. */
const char *ls_co_master_node_text(const ls_co_master_t *m, uint8_t node_id);
/* True when every configured node is READY. O(nodes). */
bool ls_co_master_all_ready(const ls_co_master_t *m);

/* The counters, the SDO clients' summed in: fills *out. LS_EINVAL when
 * either is NULL. O(nodes). */
int ls_co_master_counters(const ls_co_master_t *m, ls_co_counters_t *out);

/* "BOOTING" etc.; "unknown" for any other value. */
const char *ls_co_phase_name(ls_co_phase_t phase);

#endif
