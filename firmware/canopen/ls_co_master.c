/* CiA 301 master: NMT boot, configuration scripts, heartbeats, EMCY, SYNC
 * and PDOs for a few nodes (ls_co_master.h). */
#include "ls_co_master.h"

#include <stdarg.h>
#include <string.h>

#include "ls_canopen.h"
#include "ls_fmt.h"

#define NO_STATE 0xFFu /* no heartbeat seen yet */
#define US_PER_MS 1000u

/* ---- Sending: every frame goes through here (counted; stops at the first
 * refusal of a call, because the CAN queue is full until the next one). */

static int tx(ls_co_master_t *m, const hal_can_frame_t *f)
{
    if (m->tx_blocked) {
        return LS_EAGAIN;
    }
    if (m->send(m->send_ctx, f) != LS_OK) {
        m->tx_blocked = true;
        m->counters.sends_refused++;
        return LS_EAGAIN;
    }
    m->counters.frames_out++;
    return LS_OK;
}

static int sdo_send_hook(void *ctx, const hal_can_frame_t *f)
{
    return tx(ctx, f);
}

static hal_can_frame_t frame(uint32_t id, uint8_t len)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof(f));
    f.id = id;
    f.len = len;
    return f;
}

/* ---- Text */

static void say(char *text, uint8_t node_id, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* "node 0x22: " and the rest. */
static void say(char *text, uint8_t node_id, const char *fmt, ...)
{
    int n = ls_fmt_print(text, LS_CO_TEXT_LEN, "node 0x%02X: ", (unsigned)node_id);
    if (n < 0 || (size_t)n >= LS_CO_TEXT_LEN) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)ls_fmt_vprint(text + n, LS_CO_TEXT_LEN - (size_t)n, fmt, ap);
    va_end(ap);
}

static void copy_text(char *dst, const char *src)
{
    size_t n = strlen(src);
    if (n >= LS_CO_TEXT_LEN) {
        n = LS_CO_TEXT_LEN - 1u;
    }
    memcpy(dst, src, n);
    dst[n] = '\0';
}

const char *ls_co_phase_name(ls_co_phase_t phase)
{
    switch (phase) {
    case LS_CO_PHASE_IDLE: return "IDLE";
    case LS_CO_PHASE_BOOTING: return "BOOTING";
    case LS_CO_PHASE_CONFIGURING: return "CONFIGURING";
    case LS_CO_PHASE_STARTING: return "STARTING";
    case LS_CO_PHASE_READY: return "READY";
    case LS_CO_PHASE_FAILED: return "FAILED";
    case LS_CO_PHASE_LOST: return "LOST";
    }
    return "unknown";
}

/* ---- Lookup */

/* nodes[] index + 1 of a configured node id, 0 when it is none of ours. */
static size_t slot_of(const ls_co_master_t *m, uint8_t node_id)
{
    return m == NULL || node_id > LS_CO_NODE_MAX ? 0u : m->index_of[node_id];
}

static ls_co_node_t *find(ls_co_master_t *m, uint8_t node_id)
{
    size_t k = slot_of(m, node_id);
    return k == 0u ? NULL : &m->nodes[k - 1u];
}

static const ls_co_node_t *find_c(const ls_co_master_t *m, uint8_t node_id)
{
    size_t k = slot_of(m, node_id);
    return k == 0u ? NULL : &m->nodes[k - 1u];
}

/* ---- Configuration check */

static int refuse(ls_co_master_t *m, uint8_t node_id, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static int refuse(ls_co_master_t *m, uint8_t node_id, const char *fmt, ...)
{
    char what[LS_CO_TEXT_LEN];
    va_list ap;
    va_start(ap, fmt);
    (void)ls_fmt_vprint(what, sizeof(what), fmt, ap);
    va_end(ap);
    if (node_id != 0u) {
        say(m->text, node_id, "%s", what);
    } else {
        copy_text(m->text, what);
    }
    return LS_EINVAL;
}

static int check_step(ls_co_master_t *m, uint8_t id, size_t i, const ls_co_step_t *st)
{
    switch (st->kind) {
    case LS_CO_STEP_WRITE:
        if (st->size == 0u && st->bytes != NULL && st->bytes_len >= 1u && st->bytes_len <= LS_CO_SDO_BUF_LEN) {
            return LS_OK;
        }
        if (st->bytes == NULL && (st->size == 1u || st->size == 2u || st->size == 4u)) {
            return LS_OK;
        }
        return refuse(m, id, "script step %zu writes 0x%04X:%02X with size %u: use 1, 2 or 4, or bytes of 1..%u",
                      i + 1u, (unsigned)st->index, (unsigned)st->sub, (unsigned)st->size, (unsigned)LS_CO_SDO_BUF_LEN);
    case LS_CO_STEP_EXPECT: return LS_OK;
    case LS_CO_STEP_READ_INTO:
        if (st->into != NULL) {
            return LS_OK;
        }
        return refuse(m, id, "script step %zu reads 0x%04X:%02X into nothing: set `into`", i + 1u, (unsigned)st->index,
                      (unsigned)st->sub);
    }
    return refuse(m, id, "script step %zu has no kind: use LS_CO_STEP_WRITE, _EXPECT or _READ_INTO", i + 1u);
}

static int check_pdo(ls_co_master_t *m, uint8_t id, const char *dir, size_t slot, const ls_co_pdo_t *p)
{
    if (p->cob_id == 0u) {
        return LS_OK;
    }
    if (p->cob_id < LS_CO_PDO_COB_MIN || p->cob_id > LS_CO_PDO_COB_MAX) {
        return refuse(m, id, "%s slot %zu has COB-ID 0x%03X, outside the PDO range 0x%03X-0x%03X", dir, slot,
                      (unsigned)p->cob_id, LS_CO_PDO_COB_MIN, LS_CO_PDO_COB_MAX);
    }
    if (p->len < 1u || p->len > 8u) {
        return refuse(m, id, "%s slot %zu has length %u: a PDO carries 1..8 bytes", dir, slot, (unsigned)p->len);
    }
    return LS_OK;
}

/* Every PDO COB-ID used once (a TPDO routed to two nodes, or an RPDO that
 * two nodes take, would be a wiring error). */
static int check_cob_ids(ls_co_master_t *m, const ls_co_master_config_t *cfg)
{
    for (size_t a = 0; a < cfg->node_count * 2u * LS_CO_NODE_PDOS; a++) {
        const ls_co_node_config_t *na = &cfg->nodes[a / (2u * LS_CO_NODE_PDOS)];
        size_t ka = a % (2u * LS_CO_NODE_PDOS);
        uint16_t ca = ka < LS_CO_NODE_PDOS ? na->rpdo[ka].cob_id : na->tpdo[ka - LS_CO_NODE_PDOS].cob_id;
        if (ca == 0u) {
            continue;
        }
        for (size_t b = a + 1u; b < cfg->node_count * 2u * LS_CO_NODE_PDOS; b++) {
            const ls_co_node_config_t *nb = &cfg->nodes[b / (2u * LS_CO_NODE_PDOS)];
            size_t kb = b % (2u * LS_CO_NODE_PDOS);
            uint16_t cb = kb < LS_CO_NODE_PDOS ? nb->rpdo[kb].cob_id : nb->tpdo[kb - LS_CO_NODE_PDOS].cob_id;
            if (ca == cb) {
                return refuse(m, nb->node_id, "PDO COB-ID 0x%03X is already used by node 0x%02X", (unsigned)cb,
                              (unsigned)na->node_id);
            }
        }
    }
    return LS_OK;
}

static int check_node(ls_co_master_t *m, const ls_co_master_config_t *cfg, size_t i, uint8_t *seen)
{
    const ls_co_node_config_t *nc = &cfg->nodes[i];
    uint8_t id = nc->node_id;
    if (id < LS_CO_NODE_MIN || id > LS_CO_NODE_MAX) {
        return refuse(m, 0, "node %zu has id %u: node ids are 1..127", i + 1u, (unsigned)id);
    }
    if (seen[id] != 0u || id == cfg->node_id) {
        return refuse(m, id, "configured twice (or it is the master's own id)");
    }
    seen[id] = 1u;
    if (nc->heartbeat_ms == 0u) {
        return refuse(m, id, "heartbeat_ms is 0: the master needs the node's heartbeat (boot and liveness)");
    }
    if (nc->heartbeat_timeout_ms <= nc->heartbeat_ms) {
        return refuse(m, id, "heartbeat_timeout_ms %u is not above heartbeat_ms %u", (unsigned)nc->heartbeat_timeout_ms,
                      (unsigned)nc->heartbeat_ms);
    }
    if (nc->script_len > 0u && nc->script == NULL) {
        return refuse(m, id, "script_len is %zu but script is NULL", nc->script_len);
    }
    for (size_t k = 0; k < nc->script_len; k++) {
        int rc = check_step(m, id, k, &nc->script[k]);
        if (rc != LS_OK) {
            return rc;
        }
    }
    for (size_t k = 0; k < LS_CO_NODE_PDOS; k++) {
        int rc = check_pdo(m, id, "rpdo", k, &nc->rpdo[k]);
        if (rc == LS_OK) {
            rc = check_pdo(m, id, "tpdo", k, &nc->tpdo[k]);
        }
        if (rc != LS_OK) {
            return rc;
        }
    }
    return LS_OK;
}

int ls_co_master_init(ls_co_master_t *m, const ls_co_master_config_t *cfg, ls_co_send_fn send, void *send_ctx)
{
    if (m == NULL) {
        return LS_EINVAL;
    }
    m->text[0] = '\0';
    if (cfg == NULL || send == NULL) {
        return refuse(m, 0, "no configuration or no send function");
    }
    if (cfg->node_count == 0u || cfg->node_count > LS_CO_MAX_NODES) {
        return refuse(m, 0, "node_count is %zu: configure 1..%u nodes", cfg->node_count, LS_CO_MAX_NODES);
    }
    if (cfg->node_id > LS_CO_NODE_MAX || (cfg->heartbeat_ms != 0u && cfg->node_id == 0u)) {
        return refuse(m, 0, "the master's node id %u is not 1..127 (a master heartbeat needs one)",
                      (unsigned)cfg->node_id);
    }
    uint8_t seen[LS_CO_NODE_MAX + 1u];
    memset(seen, 0, sizeof(seen));
    for (size_t i = 0; i < cfg->node_count; i++) {
        int rc = check_node(m, cfg, i, seen);
        if (rc != LS_OK) {
            return rc;
        }
    }
    int rc = check_cob_ids(m, cfg);
    if (rc != LS_OK) {
        return rc;
    }

    memset(m, 0, sizeof(*m));
    m->node_id = cfg->node_id;
    m->heartbeat_ms = cfg->heartbeat_ms;
    m->sdo_timeout_us = (uint32_t)cfg->sdo_timeout_ms * US_PER_MS; /* 0: the client's default */
    m->node_count = cfg->node_count;
    m->send = send;
    m->send_ctx = send_ctx;
    m->own_state = LS_CO_NMT_PREOPERATIONAL;
    for (size_t i = 0; i < cfg->node_count; i++) {
        ls_co_node_t *n = &m->nodes[i];
        n->cfg = cfg->nodes[i];
        if (n->cfg.boot_timeout_ms == 0u) {
            n->cfg.boot_timeout_ms = LS_CO_BOOT_TIMEOUT_MS_DEFAULT;
        }
        (void)ls_co_sdo_init(&n->sdo, n->cfg.node_id, m->sdo_timeout_us, sdo_send_hook, m);
        n->phase = LS_CO_PHASE_IDLE;
        n->nmt_state = NO_STATE;
        m->index_of[n->cfg.node_id] = (uint8_t)(i + 1u);
    }
    return LS_OK;
}

const char *ls_co_master_text(const ls_co_master_t *m)
{
    return m == NULL ? "" : m->text;
}

/* ---- NMT */

static void flush_nmt(ls_co_master_t *m)
{
    if (m->nmt_all_pending != 0u) {
        hal_can_frame_t f = frame(LS_CO_COB_NMT, 2);
        f.data[0] = m->nmt_all_pending;
        f.data[1] = LS_CO_NMT_ALL_NODES;
        if (tx(m, &f) != LS_OK) {
            return;
        }
        m->nmt_all_pending = 0;
    }
    for (size_t i = 0; i < m->node_count; i++) {
        ls_co_node_t *n = &m->nodes[i];
        if (n->nmt_pending == 0u) {
            continue;
        }
        hal_can_frame_t f = frame(LS_CO_COB_NMT, 2);
        f.data[0] = n->nmt_pending;
        f.data[1] = n->cfg.node_id;
        if (tx(m, &f) != LS_OK) {
            return;
        }
        n->nmt_pending = 0;
    }
}

static void queue_nmt(ls_co_master_t *m, ls_co_node_t *n, uint8_t command)
{
    n->nmt_pending = command;
    flush_nmt(m);
}

/* Forget what the node was sent and sent us: a boot or a reset begins. */
static void forget_data(ls_co_node_t *n)
{
    for (size_t k = 0; k < LS_CO_NODE_PDOS; k++) {
        n->rpdo[k].valid = false;
        n->tpdo[k].valid = false;
    }
    n->hb_monitoring = false;
    n->hb_mismatches = 0;
    n->step_running = false;
    n->caller_sdo = false;
}

static void boot_node(ls_co_master_t *m, ls_co_node_t *n, uint64_t now_us)
{
    ls_co_sdo_cancel(&n->sdo, "cancelled: the node is booted again");
    forget_data(n);
    n->phase = LS_CO_PHASE_BOOTING;
    n->deadline_us = now_us + (uint64_t)n->cfg.boot_timeout_ms * US_PER_MS;
    n->step = 0;
    n->restarts = 0;
    n->nmt_state = NO_STATE;
    n->nmt_wanted = LS_CO_NMT_OPERATIONAL;
    n->text[0] = '\0';
    queue_nmt(m, n, LS_CO_NMT_RESET_COMM);
}

int ls_co_master_reboot_node(ls_co_master_t *m, uint8_t node_id, uint64_t now_us)
{
    ls_co_node_t *n = find(m, node_id);
    if (n == NULL) {
        return LS_EINVAL;
    }
    m->tx_blocked = false;
    boot_node(m, n, now_us);
    return LS_OK;
}

void ls_co_master_drop_unsent(ls_co_master_t *m)
{
    m->nmt_all_pending = 0;
    for (size_t i = 0; i < m->node_count; i++) {
        m->nodes[i].nmt_pending = 0;
    }
    m->cycle_pending = false;
    m->bootup_pending = false;
    m->hb_pending = false;
    m->tx_blocked = false;
}

static void send_own(ls_co_master_t *m)
{
    if (m->bootup_pending) {
        hal_can_frame_t f = frame(LS_CO_COB_HEARTBEAT + m->node_id, 1);
        f.data[0] = LS_CO_NMT_BOOTUP;
        if (tx(m, &f) != LS_OK) {
            return;
        }
        m->bootup_pending = false;
    }
    if (m->hb_pending) {
        hal_can_frame_t f = frame(LS_CO_COB_HEARTBEAT + m->node_id, 1);
        f.data[0] = m->own_state;
        if (tx(m, &f) == LS_OK) {
            m->hb_pending = false;
        }
    }
}

int ls_co_master_boot(ls_co_master_t *m, uint64_t now_us)
{
    if (m == NULL || m->send == NULL) {
        return LS_EINVAL;
    }
    m->tx_blocked = false;
    m->own_state = LS_CO_NMT_OPERATIONAL;
    if (m->node_id != 0u) {
        m->bootup_pending = true;
        m->hb_next_us = now_us + (uint64_t)m->heartbeat_ms * US_PER_MS;
        send_own(m);
    }
    for (size_t i = 0; i < m->node_count; i++) {
        boot_node(m, &m->nodes[i], now_us);
    }
    return LS_OK;
}

static uint8_t state_of_command(uint8_t command)
{
    switch (command) {
    case LS_CO_NMT_START: return LS_CO_NMT_OPERATIONAL;
    case LS_CO_NMT_STOP: return LS_CO_NMT_STOPPED;
    case LS_CO_NMT_ENTER_PREOP: return LS_CO_NMT_PREOPERATIONAL;
    default: return LS_CO_NMT_BOOTUP; /* the resets */
    }
}

/* What a command the caller sent does to our view of the node. */
static void commanded(ls_co_node_t *n, uint8_t command)
{
    uint8_t state = state_of_command(command);
    if (state == LS_CO_NMT_BOOTUP) {
        if (n->phase != LS_CO_PHASE_IDLE) {
            ls_co_sdo_cancel(&n->sdo, "cancelled: the master reset the node");
            forget_data(n);
            n->phase = LS_CO_PHASE_IDLE;
            say(n->text, n->cfg.node_id, "reset by the master (NMT 0x%02X); boot it again to use it",
                (unsigned)command);
        }
        return;
    }
    if (n->phase == LS_CO_PHASE_READY) {
        n->nmt_wanted = state;
        n->hb_mismatches = 0;
    }
}

int ls_co_master_nmt(ls_co_master_t *m, uint8_t node_id, uint8_t command, uint64_t now_us)
{
    (void)now_us;
    if (m == NULL || m->send == NULL) {
        return LS_EINVAL;
    }
    if (command != LS_CO_NMT_START && command != LS_CO_NMT_STOP && command != LS_CO_NMT_ENTER_PREOP &&
        command != LS_CO_NMT_RESET_NODE && command != LS_CO_NMT_RESET_COMM) {
        return LS_EINVAL;
    }
    m->tx_blocked = false;
    if (node_id == LS_CO_NMT_ALL_NODES) {
        for (size_t i = 0; i < m->node_count; i++) {
            m->nodes[i].nmt_pending = 0; /* the broadcast is the latest command for each */
            commanded(&m->nodes[i], command);
        }
        m->nmt_all_pending = command;
        flush_nmt(m);
        return LS_OK;
    }
    ls_co_node_t *n = find(m, node_id);
    if (n == NULL) {
        return LS_EINVAL;
    }
    commanded(n, command);
    queue_nmt(m, n, command);
    return LS_OK;
}

uint8_t ls_co_master_state(const ls_co_master_t *m)
{
    return m == NULL ? LS_CO_NMT_BOOTUP : m->own_state;
}

int ls_co_master_set_state(ls_co_master_t *m, uint8_t state)
{
    if (m == NULL ||
        (state != LS_CO_NMT_PREOPERATIONAL && state != LS_CO_NMT_OPERATIONAL && state != LS_CO_NMT_STOPPED)) {
        return LS_EINVAL;
    }
    m->own_state = state;
    return LS_OK;
}

/* ---- Phases */

static void fail(ls_co_node_t *n, ls_co_phase_t phase)
{
    ls_co_sdo_cancel(&n->sdo, phase == LS_CO_PHASE_LOST ? "cancelled: the node was lost" : "cancelled");
    n->step_running = false;
    n->caller_sdo = false;
    n->hb_monitoring = false;
    n->phase = phase;
}

static void start_configuring(ls_co_node_t *n)
{
    ls_co_sdo_cancel(&n->sdo, "cancelled: the node booted");
    n->phase = LS_CO_PHASE_CONFIGURING;
    n->step = 0;
    n->step_running = false;
    n->caller_sdo = false;
    n->hb_monitoring = false;
    n->hb_mismatches = 0;
}

static void put_le(uint8_t *out, uint32_t v, uint8_t size)
{
    for (uint8_t i = 0; i < size; i++) {
        out[i] = (uint8_t)(v >> (8u * i));
    }
}

static int start_step(ls_co_master_t *m, ls_co_node_t *n, uint64_t now_us)
{
    (void)m;
    if (n->step == 0u) {
        uint8_t b[2];
        put_le(b, n->cfg.heartbeat_ms, 2);
        return ls_co_sdo_write(&n->sdo, LS_CO_OBJ_PRODUCER_HB, 0, b, sizeof(b), now_us);
    }
    const ls_co_step_t *st = &n->cfg.script[n->step - 1u];
    if (st->kind != LS_CO_STEP_WRITE) {
        return ls_co_sdo_read(&n->sdo, st->index, st->sub, now_us);
    }
    if (st->bytes != NULL) {
        return ls_co_sdo_write(&n->sdo, st->index, st->sub, st->bytes, st->bytes_len, now_us);
    }
    uint8_t b[4];
    put_le(b, st->value, st->size);
    return ls_co_sdo_write(&n->sdo, st->index, st->sub, b, st->size, now_us);
}

/* A step that failed: fatal, or (optional, refused or mismatched) a note. */
static bool step_failed(ls_co_master_t *m, ls_co_node_t *n, const ls_co_step_t *st, bool refusal, const char *text)
{
    if (st != NULL && st->optional && refusal) {
        m->counters.optional_failures++;
        (void)ls_fmt_print(n->text, sizeof(n->text), "%s (optional: carried on)", text);
        return true;
    }
    copy_text(n->text, text);
    fail(n, LS_CO_PHASE_FAILED);
    return false;
}

/* The outcome of the running step; false when the node failed. */
static bool finish_step(ls_co_master_t *m, ls_co_node_t *n)
{
    const ls_co_step_t *st = n->step == 0u ? NULL : &n->cfg.script[n->step - 1u];
    int status = ls_co_sdo_status(&n->sdo);
    if (status != LS_OK) {
        return step_failed(m, n, st, status == LS_EABORTED, ls_co_sdo_text(&n->sdo));
    }
    if (st == NULL || st->kind == LS_CO_STEP_WRITE) {
        return true;
    }
    size_t len = 0;
    uint32_t v = ls_co_sdo_value(&n->sdo, &len);
    char text[LS_CO_TEXT_LEN];
    if (len == 0u || len > 4u) {
        say(text, n->cfg.node_id, "0x%04X:%02X answered %zu bytes where a number of 1..4 was expected",
            (unsigned)st->index, (unsigned)st->sub, len);
        return step_failed(m, n, st, true, text);
    }
    if (st->kind == LS_CO_STEP_READ_INTO) {
        *st->into = v;
        return true;
    }
    uint32_t mask = st->mask != 0u ? st->mask : 0xFFFFFFFFu;
    if ((v & mask) == (st->value & mask)) {
        return true;
    }
    char bits[32] = "";
    if (mask != 0xFFFFFFFFu) {
        (void)ls_fmt_print(bits, sizeof(bits), " (bits 0x%08X)", (unsigned)mask);
    }
    say(text, n->cfg.node_id, "%s%s0x%04X:%02X is 0x%08X, %s%s 0x%08X%s", st->label != NULL ? st->label : "",
        st->label != NULL ? " " : "", (unsigned)st->index, (unsigned)st->sub, (unsigned)(v & mask),
        st->source != NULL ? st->source : "expected", st->source != NULL ? " says" : "", (unsigned)(st->value & mask),
        bits);
    return step_failed(m, n, st, true, text);
}

static void configure(ls_co_master_t *m, ls_co_node_t *n, uint64_t now_us)
{
    while (n->phase == LS_CO_PHASE_CONFIGURING) {
        if (n->step_running) {
            if (ls_co_sdo_status(&n->sdo) == LS_EBUSY) {
                return;
            }
            n->step_running = false;
            if (!finish_step(m, n)) {
                return;
            }
            n->step++;
            continue;
        }
        if (ls_co_sdo_busy(&n->sdo)) {
            return; /* an abort of ours waits for room in the queue */
        }
        if (n->step > n->cfg.script_len) {
            n->phase = LS_CO_PHASE_STARTING;
            n->deadline_us = now_us + (uint64_t)n->cfg.boot_timeout_ms * US_PER_MS;
            n->nmt_wanted = LS_CO_NMT_OPERATIONAL;
            queue_nmt(m, n, LS_CO_NMT_START);
            return;
        }
        if (start_step(m, n, now_us) != LS_OK) {
            return; /* not reached: the client is idle and the step was checked at init */
        }
        n->step_running = true;
    }
}

/* A transfer of the caller's finished: a failure becomes the node's text. */
static void caller_sdo_done(ls_co_node_t *n)
{
    if (!n->caller_sdo || ls_co_sdo_status(&n->sdo) == LS_EBUSY) {
        return;
    }
    n->caller_sdo = false;
    if (ls_co_sdo_status(&n->sdo) != LS_OK) {
        copy_text(n->text, ls_co_sdo_text(&n->sdo));
    }
}

static void lose(ls_co_master_t *m, ls_co_node_t *n)
{
    (void)m;
    fail(n, LS_CO_PHASE_LOST);
}

static void node_timers(ls_co_master_t *m, ls_co_node_t *n, uint64_t now_us)
{
    uint8_t id = n->cfg.node_id;
    switch (n->phase) {
    case LS_CO_PHASE_BOOTING:
        if (now_us >= n->deadline_us) {
            say(n->text, id, "no boot-up within %u ms%s", (unsigned)n->cfg.boot_timeout_ms,
                n->nmt_pending != 0u ? " (the reset never left: CAN queue full)" : "");
            fail(n, LS_CO_PHASE_FAILED);
        }
        return;
    case LS_CO_PHASE_STARTING:
        if (now_us >= n->deadline_us) {
            if (n->nmt_state == NO_STATE || n->nmt_state == LS_CO_NMT_BOOTUP) {
                say(n->text, id, "not OPERATIONAL within %u ms of NMT start (no heartbeat since its boot-up)",
                    (unsigned)n->cfg.boot_timeout_ms);
            } else {
                say(n->text, id, "not OPERATIONAL within %u ms of NMT start (its heartbeat says %s)",
                    (unsigned)n->cfg.boot_timeout_ms, ls_co_nmt_state_name(n->nmt_state));
            }
            fail(n, LS_CO_PHASE_FAILED);
            return;
        }
        break;
    case LS_CO_PHASE_CONFIGURING:
    case LS_CO_PHASE_READY: break;
    case LS_CO_PHASE_IDLE:
    case LS_CO_PHASE_FAILED:
    case LS_CO_PHASE_LOST: return;
    }
    if (n->hb_monitoring && now_us - n->hb_last_us > (uint64_t)n->cfg.heartbeat_timeout_ms * US_PER_MS) {
        say(n->text, id, "no heartbeat for %u ms (time-out %u ms) while %s",
            (unsigned)((now_us - n->hb_last_us) / US_PER_MS), (unsigned)n->cfg.heartbeat_timeout_ms,
            ls_co_phase_name(n->phase));
        m->counters.heartbeats_lost++;
        lose(m, n);
    }
}

/* ---- Cyclic traffic */

static bool rpdo_due(const ls_co_node_t *n, size_t slot)
{
    return n->phase == LS_CO_PHASE_READY && n->nmt_wanted == LS_CO_NMT_OPERATIONAL && n->cfg.rpdo[slot].cob_id != 0u &&
           n->rpdo[slot].valid;
}

/* Send the rest of the cycle; true when its SYNC went. */
static bool flush_cycle(ls_co_master_t *m)
{
    for (; m->cycle_node < m->node_count; m->cycle_node++, m->cycle_pdo = 0) {
        const ls_co_node_t *n = &m->nodes[m->cycle_node];
        for (; m->cycle_pdo < LS_CO_NODE_PDOS; m->cycle_pdo++) {
            if (!rpdo_due(n, m->cycle_pdo)) {
                continue;
            }
            hal_can_frame_t f = frame(n->cfg.rpdo[m->cycle_pdo].cob_id, n->cfg.rpdo[m->cycle_pdo].len);
            memcpy(f.data, n->rpdo[m->cycle_pdo].data, f.len);
            if (tx(m, &f) != LS_OK) {
                return false;
            }
        }
    }
    hal_can_frame_t s = frame(LS_CO_COB_SYNC, 0);
    if (tx(m, &s) != LS_OK) {
        return false;
    }
    m->sync_count++;
    m->counters.sync_sent++;
    m->cycle_pending = false;
    return true;
}

int ls_co_master_sync(ls_co_master_t *m, uint64_t now_us)
{
    (void)now_us;
    if (m == NULL || m->send == NULL) {
        return LS_EINVAL;
    }
    m->tx_blocked = false;
    if (m->cycle_pending) {
        m->counters.sync_overruns++;
    }
    m->cycle_pending = true;
    m->cycle_node = 0;
    m->cycle_pdo = 0;
    if (flush_cycle(m)) {
        return LS_OK;
    }
    m->counters.sync_deferred++;
    return LS_EAGAIN;
}

int ls_co_master_rpdo_set(ls_co_master_t *m, uint8_t node_id, size_t slot, const uint8_t *data, size_t len)
{
    ls_co_node_t *n = find(m, node_id);
    if (n == NULL || slot >= LS_CO_NODE_PDOS || data == NULL || n->cfg.rpdo[slot].cob_id == 0u) {
        return LS_EINVAL;
    }
    if (len != n->cfg.rpdo[slot].len) {
        return LS_ELEN;
    }
    memcpy(n->rpdo[slot].data, data, len);
    n->rpdo[slot].valid = true;
    return LS_OK;
}

int ls_co_master_tpdo_get(const ls_co_master_t *m, uint8_t node_id, size_t slot, uint8_t *out, size_t *len,
                          uint32_t *age_syncs)
{
    const ls_co_node_t *n = find_c(m, node_id);
    if (n == NULL || slot >= LS_CO_NODE_PDOS || out == NULL || n->cfg.tpdo[slot].cob_id == 0u) {
        return LS_EINVAL;
    }
    if (!n->tpdo[slot].valid) {
        return LS_EAGAIN;
    }
    memcpy(out, n->tpdo[slot].data, n->tpdo[slot].len);
    if (len != NULL) {
        *len = n->tpdo[slot].len;
    }
    if (age_syncs != NULL) {
        *age_syncs = m->sync_count - n->tpdo[slot].sync_count;
    }
    return LS_OK;
}

void ls_co_master_poll(ls_co_master_t *m, uint64_t now_us)
{
    if (m == NULL || m->send == NULL) {
        return;
    }
    m->tx_blocked = false;
    if (m->cycle_pending) {
        (void)flush_cycle(m);
    }
    flush_nmt(m);
    if (m->node_id != 0u && m->heartbeat_ms != 0u && m->hb_next_us != 0u && now_us >= m->hb_next_us) {
        uint64_t period = (uint64_t)m->heartbeat_ms * US_PER_MS;
        m->hb_pending = true; /* a heartbeat still waiting is replaced, not doubled */
        m->hb_next_us += period;
        if (m->hb_next_us <= now_us) {
            m->hb_next_us = now_us + period; /* polls stalled: no burst to catch up */
        }
    }
    send_own(m);
    for (size_t i = 0; i < m->node_count; i++) {
        ls_co_node_t *n = &m->nodes[i];
        ls_co_sdo_poll(&n->sdo, now_us);
        node_timers(m, n, now_us);
        caller_sdo_done(n);
        configure(m, n, now_us);
    }
}

/* ---- Reception */

static void on_heartbeat(ls_co_master_t *m, ls_co_node_t *n, const hal_can_frame_t *f, uint64_t now_us)
{
    if (f->len < 1u) {
        m->counters.unexpected++;
        return;
    }
    uint8_t state = f->data[0] & 0x7Fu; /* bit 7 is node guarding's toggle */
    n->nmt_state = state;
    uint8_t id = n->cfg.node_id;
    switch (n->phase) {
    case LS_CO_PHASE_BOOTING:
        if (state == LS_CO_NMT_BOOTUP) {
            if (n->nmt_pending == LS_CO_NMT_RESET_COMM) {
                n->nmt_pending = 0; /* it booted by itself: our reset is not needed */
            }
            start_configuring(n);
            configure(m, n, now_us);
        }
        return;
    case LS_CO_PHASE_CONFIGURING:
    case LS_CO_PHASE_STARTING:
        if (state == LS_CO_NMT_BOOTUP) {
            n->restarts++;
            if (n->restarts > LS_CO_BOOT_RESTARTS) {
                say(n->text, id, "reset itself %u times during configuration", n->restarts);
                fail(n, LS_CO_PHASE_FAILED);
                return;
            }
            start_configuring(n);
            configure(m, n, now_us);
            return;
        }
        if (n->phase == LS_CO_PHASE_STARTING || n->step > 0u) {
            n->hb_monitoring = true; /* its producer time is ours now */
            n->hb_last_us = now_us;
        }
        if (n->phase == LS_CO_PHASE_STARTING && state == LS_CO_NMT_OPERATIONAL) {
            n->phase = LS_CO_PHASE_READY;
            n->hb_mismatches = 0;
        }
        return;
    case LS_CO_PHASE_READY:
        if (state == LS_CO_NMT_BOOTUP) {
            say(n->text, id, "reset itself (boot-up while READY)");
            lose(m, n);
            return;
        }
        n->hb_last_us = now_us;
        if (state == n->nmt_wanted) {
            n->hb_mismatches = 0;
            return;
        }
        if (++n->hb_mismatches >= LS_CO_HB_MISMATCHES) {
            say(n->text, id, "heartbeat says %s, not %s", ls_co_nmt_state_name(state),
                ls_co_nmt_state_name(n->nmt_wanted));
            lose(m, n);
        }
        return;
    case LS_CO_PHASE_IDLE:
    case LS_CO_PHASE_FAILED:
    case LS_CO_PHASE_LOST: return;
    }
}

static void on_emcy(ls_co_master_t *m, ls_co_node_t *n, const hal_can_frame_t *f, uint64_t now_us)
{
    if (f->len < 3u) {
        m->counters.unexpected++;
        return;
    }
    m->counters.emcy_received++;
    if (n->emcy_count == LS_CO_EMCY_RING) {
        m->counters.emcy_lost++;
        return;
    }
    ls_co_emcy_t *e = &n->emcy[(n->emcy_head + n->emcy_count) % LS_CO_EMCY_RING];
    n->emcy_count++;
    memset(e, 0, sizeof(*e));
    e->code = (uint16_t)(f->data[0] | (f->data[1] << 8));
    e->reg = f->data[2];
    size_t vendor = f->len > 3u ? (size_t)f->len - 3u : 0u;
    if (vendor > sizeof(e->vendor)) {
        vendor = sizeof(e->vendor);
    }
    memcpy(e->vendor, &f->data[3], vendor);
    e->t_us = now_us;
    e->name = ls_co_emcy_name(e->code);
}

static bool on_tpdo(ls_co_master_t *m, const hal_can_frame_t *f, uint64_t now_us)
{
    for (size_t i = 0; i < m->node_count; i++) {
        ls_co_node_t *n = &m->nodes[i];
        for (size_t k = 0; k < LS_CO_NODE_PDOS; k++) {
            if (n->cfg.tpdo[k].cob_id == 0u || n->cfg.tpdo[k].cob_id != f->id) {
                continue;
            }
            if (f->len < n->cfg.tpdo[k].len) {
                m->counters.unexpected++;
                return true;
            }
            memcpy(n->tpdo[k].data, f->data, n->cfg.tpdo[k].len);
            n->tpdo[k].len = n->cfg.tpdo[k].len;
            n->tpdo[k].valid = true;
            n->tpdo[k].t_us = now_us;
            n->tpdo[k].sync_count = m->sync_count;
            return true;
        }
    }
    return false;
}

void ls_co_master_on_frame(ls_co_master_t *m, const hal_can_frame_t *f, uint64_t now_us)
{
    if (m == NULL || m->send == NULL || f == NULL || (f->flags & (HAL_CAN_F_EXT | HAL_CAN_F_RTR)) != 0u ||
        f->id > LS_CO_COB_MASK || f->len > 8u) {
        return;
    }
    m->counters.frames_in++;
    m->tx_blocked = false;
    uint32_t id = f->id;
    if (id == LS_CO_COB_NMT || id == LS_CO_COB_SYNC) {
        m->counters.unexpected++; /* another master on our bus */
        return;
    }
    uint32_t node_id = id & 0x7Fu;
    uint32_t function = id & ~0x7Fu;
    ls_co_node_t *n = find(m, (uint8_t)node_id);
    if (n != NULL && function == LS_CO_COB_EMCY) {
        on_emcy(m, n, f, now_us);
    } else if (n != NULL && function == LS_CO_COB_SDO_TX) {
        ls_co_sdo_on_frame(&n->sdo, f, now_us);
        caller_sdo_done(n);
        configure(m, n, now_us);
    } else if (n != NULL && function == LS_CO_COB_HEARTBEAT) {
        on_heartbeat(m, n, f, now_us);
    } else {
        (void)on_tpdo(m, f, now_us);
    }
}

/* ---- Queries */

int ls_co_master_next_emcy(ls_co_master_t *m, uint8_t node_id, ls_co_emcy_t *out)
{
    ls_co_node_t *n = find(m, node_id);
    if (n == NULL || out == NULL) {
        return LS_EINVAL;
    }
    if (n->emcy_count == 0u) {
        return 0;
    }
    *out = n->emcy[n->emcy_head];
    n->emcy_head = (n->emcy_head + 1u) % LS_CO_EMCY_RING;
    n->emcy_count--;
    return 1;
}

static int caller_sdo_allowed(ls_co_master_t *m, ls_co_node_t *n)
{
    if (n == NULL) {
        return LS_EINVAL;
    }
    if (n->phase == LS_CO_PHASE_BOOTING || n->phase == LS_CO_PHASE_CONFIGURING || ls_co_sdo_busy(&n->sdo)) {
        return LS_EBUSY;
    }
    m->tx_blocked = false;
    return LS_OK;
}

int ls_co_master_sdo_write(ls_co_master_t *m, uint8_t node_id, uint16_t index, uint8_t sub, const uint8_t *data,
                           size_t len, uint64_t now_us)
{
    ls_co_node_t *n = find(m, node_id);
    int rc = caller_sdo_allowed(m, n);
    if (rc == LS_OK) {
        rc = ls_co_sdo_write(&n->sdo, index, sub, data, len, now_us);
        n->caller_sdo = rc == LS_OK;
    }
    return rc;
}

int ls_co_master_sdo_read(ls_co_master_t *m, uint8_t node_id, uint16_t index, uint8_t sub, uint64_t now_us)
{
    ls_co_node_t *n = find(m, node_id);
    int rc = caller_sdo_allowed(m, n);
    if (rc == LS_OK) {
        rc = ls_co_sdo_read(&n->sdo, index, sub, now_us);
        n->caller_sdo = rc == LS_OK;
    }
    return rc;
}

int ls_co_master_sdo_result(const ls_co_master_t *m, uint8_t node_id, uint8_t *out, size_t cap, size_t *len)
{
    const ls_co_node_t *n = find_c(m, node_id);
    if (n == NULL) {
        return LS_EINVAL;
    }
    int status = ls_co_sdo_status(&n->sdo);
    if (status == LS_EBUSY) {
        return status;
    }
    size_t have = 0;
    const uint8_t *data = ls_co_sdo_data(&n->sdo, &have);
    size_t copy = have < cap ? have : cap;
    if (out != NULL && copy > 0u) {
        memcpy(out, data, copy);
    }
    if (len != NULL) {
        *len = out != NULL ? copy : have;
    }
    return status;
}

ls_co_phase_t ls_co_master_node_phase(const ls_co_master_t *m, uint8_t node_id)
{
    const ls_co_node_t *n = find_c(m, node_id);
    return n == NULL ? LS_CO_PHASE_IDLE : n->phase;
}

uint8_t ls_co_master_node_nmt_state(const ls_co_master_t *m, uint8_t node_id)
{
    const ls_co_node_t *n = find_c(m, node_id);
    return n == NULL ? NO_STATE : n->nmt_state;
}

const char *ls_co_master_node_text(const ls_co_master_t *m, uint8_t node_id)
{
    const ls_co_node_t *n = find_c(m, node_id);
    return n == NULL ? "" : n->text;
}

bool ls_co_master_all_ready(const ls_co_master_t *m)
{
    if (m == NULL || m->node_count == 0u) {
        return false;
    }
    for (size_t i = 0; i < m->node_count; i++) {
        if (m->nodes[i].phase != LS_CO_PHASE_READY) {
            return false;
        }
    }
    return true;
}

int ls_co_master_counters(const ls_co_master_t *m, ls_co_counters_t *out)
{
    if (m == NULL || out == NULL) {
        return LS_EINVAL;
    }
    *out = m->counters;
    for (size_t i = 0; i < m->node_count; i++) {
        const ls_co_sdo_counters_t *c = &m->nodes[i].sdo.counters;
        out->sdo_aborts_sent += c->aborts_sent;
        out->sdo_aborts_received += c->aborts_received;
        out->sdo_timeouts += c->timeouts;
        out->unexpected += c->stray;
    }
    return LS_OK;
}
