/* Black-box tests of the CANopen master (ls_co_master.h) against scripted
 * nodes (co_fake_node.h): NMT boot with its deadline, configuration
 * scripts, heartbeats both ways, EMCY, SYNC and PDOs. Every frame the tests
 * feed or expect is built from the CiA 301 constants of ls_canopen.h. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "co_fake_node.h"
#include "ls_co_master.h"

#define MASTER_ID 0x7Fu
#define MASTER_HB_MS 100u
#define MAX_FAKES 4u

typedef struct {
    bus_t bus;
    ls_co_master_t m;
    ls_co_master_config_t cfg;
    fake_t fakes[MAX_FAKES];
    size_t n_fakes;
    uint64_t now_us;
} world_t;

static world_t w; /* large: static */

static uint8_t id_of(size_t i)
{
    return (uint8_t)(0x21u + i);
}

/* `n` nodes 0x21.., empty scripts, RPDO1/TPDO1 at their predefined COB-IDs. */
static void configure_world(size_t n)
{
    memset(&w, 0, sizeof(w));
    w.now_us = 1000000;
    w.cfg.node_id = MASTER_ID;
    w.cfg.heartbeat_ms = MASTER_HB_MS;
    w.cfg.node_count = n;
    for (size_t i = 0; i < n; i++) {
        co_test_node(&w.cfg.nodes[i], id_of(i), NULL, 0);
        fake_init(&w.fakes[i], id_of(i));
    }
    w.n_fakes = n;
}

static fake_t *fake(uint8_t id)
{
    return &w.fakes[id - 0x21u];
}

static void start_world(void)
{
    assert_int_equal(ls_co_master_init(&w.m, &w.cfg, bus_send, &w.bus), LS_OK);
    assert_string_equal(ls_co_master_text(&w.m), "");
    assert_int_equal(ls_co_master_boot(&w.m, w.now_us), LS_OK);
}

/* Feed what the fakes sent to the master. */
static void flush_fakes(void)
{
    for (size_t i = 0; i < w.n_fakes; i++) {
        fake_t *k = &w.fakes[i];
        hal_can_frame_t out[FAKE_OUT_CAP];
        size_t n = k->n_out;
        memcpy(out, k->out, n * sizeof(out[0]));
        k->n_out = 0;
        for (size_t j = 0; j < n; j++) {
            ls_co_master_on_frame(&w.m, &out[j], w.now_us);
        }
    }
}

/* Everything the master sent reaches the fakes, their answers the master,
 * until the bus is quiet. */
static void deliver(void)
{
    const hal_can_frame_t *f;
    while ((f = bus_take(&w.bus)) != NULL) {
        hal_can_frame_t copy = *f;
        for (size_t i = 0; i < w.n_fakes; i++) {
            fake_hear(&w.fakes[i], &copy, w.now_us);
        }
        flush_fakes();
    }
}

/* `ms` control cycles of 1 ms: poll, bus, heartbeats. */
static void run_ms(unsigned ms)
{
    deliver();
    for (unsigned t = 0; t < ms; t++) {
        w.now_us += 1000u;
        ls_co_master_poll(&w.m, w.now_us);
        deliver();
        for (size_t i = 0; i < w.n_fakes; i++) {
            fake_tick(&w.fakes[i], w.now_us);
        }
        flush_fakes();
        deliver();
    }
}

/* One node 0x21 with `script`, booted. */
static void start_one(const ls_co_step_t *script, size_t script_len)
{
    configure_world(1);
    w.cfg.nodes[0].script = script;
    w.cfg.nodes[0].script_len = script_len;
    start_world();
}

static ls_co_phase_t phase(uint8_t id)
{
    return ls_co_master_node_phase(&w.m, id);
}

/* The node is in `want`, and its line says `text`. */
static void expect_phase(uint8_t id, ls_co_phase_t want, const char *text)
{
    assert_string_equal(ls_co_phase_name(phase(id)), ls_co_phase_name(want));
    assert_string_equal(ls_co_master_node_text(&w.m, id), text);
}

static ls_co_counters_t counters(void)
{
    ls_co_counters_t c;
    assert_int_equal(ls_co_master_counters(&w.m, &c), LS_OK);
    return c;
}

static void boot_to_ready(size_t n)
{
    configure_world(n);
    start_world();
    run_ms(2 * NODE_HB_MS);
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(phase(id_of(i)), LS_CO_PHASE_READY);
    }
    assert_true(ls_co_master_all_ready(&w.m));
}

/* ---- configuration ---------------------------------------------------- */

static void expect_refused(const char *text)
{
    ls_co_master_t m;
    assert_int_equal(ls_co_master_init(&m, &w.cfg, bus_send, &w.bus), LS_EINVAL);
    assert_string_equal(ls_co_master_text(&m), text);
}

static void test_init_refuses_a_configuration_naming_what_is_wrong(void **state)
{
    (void)state;
    configure_world(2);
    w.cfg.nodes[1].node_id = 0x21;
    expect_refused("node 0x21: configured twice (or it is the master's own id)");
    configure_world(2);
    w.cfg.nodes[0].node_id = 0;
    expect_refused("node 1 has id 0: node ids are 1..127");
    configure_world(1);
    w.cfg.nodes[0].heartbeat_timeout_ms = NODE_HB_MS;
    expect_refused("node 0x21: heartbeat_timeout_ms 50 is not above heartbeat_ms 50");
    configure_world(1);
    w.cfg.nodes[0].heartbeat_ms = 0;
    expect_refused("node 0x21: heartbeat_ms is 0: the master needs the node's heartbeat (boot and liveness)");
    configure_world(1);
    w.cfg.nodes[0].rpdo[1].cob_id = 0x701;
    w.cfg.nodes[0].rpdo[1].len = 2;
    expect_refused("node 0x21: rpdo slot 1 has COB-ID 0x701, outside the PDO range 0x181-0x57F");
    configure_world(1);
    w.cfg.nodes[0].tpdo[0].len = 9;
    expect_refused("node 0x21: tpdo slot 0 has length 9: a PDO carries 1..8 bytes");
    configure_world(2);
    w.cfg.nodes[1].tpdo[0].cob_id = w.cfg.nodes[0].tpdo[0].cob_id;
    expect_refused("node 0x22: PDO COB-ID 0x1A1 is already used by node 0x21");
    configure_world(1);
    static const ls_co_step_t bad_size[] = { LS_CO_WRITE(0x6060, 0, 3, 8) };
    w.cfg.nodes[0].script = bad_size;
    w.cfg.nodes[0].script_len = 1;
    expect_refused("node 0x21: script step 1 writes 0x6060:00 with size 3: use 1, 2 or 4, or bytes of 1..64");
    configure_world(1);
    static const ls_co_step_t no_into[] = { LS_CO_READ_INTO(0x6064, 0, NULL) };
    w.cfg.nodes[0].script = no_into;
    w.cfg.nodes[0].script_len = 1;
    expect_refused("node 0x21: script step 1 reads 0x6064:00 into nothing: set `into`");
    configure_world(1);
    w.cfg.node_count = LS_CO_MAX_NODES + 1u;
    assert_int_equal(ls_co_master_init(&w.m, &w.cfg, bus_send, &w.bus), LS_EINVAL);
    configure_world(1);
    w.cfg.node_id = 0;
    expect_refused("the master's node id 0 is not 1..127 (a master heartbeat needs one)");
    configure_world(1);
    assert_int_equal(ls_co_master_init(&w.m, &w.cfg, NULL, &w.bus), LS_EINVAL);
    assert_int_equal(ls_co_master_init(NULL, &w.cfg, bus_send, &w.bus), LS_EINVAL);
    assert_int_equal(w.bus.n, 0);
}

/* ---- boot ------------------------------------------------------------- */

static const ls_co_step_t k_script[] = {
    LS_CO_EXPECT(LS_CO_OBJ_DEVICE_TYPE, 0, LS_CO_PROFILE_DRIVE, LS_CO_DEVICE_PROFILE_MASK, "device type", "the EDS"),
    LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 1, 0x000000FCu, 0, "vendor id", "the EDS"),
    LS_CO_WRITE(LS_CO_OBJ_MODES, 0, 1, LS_CO_MODE_CSP),
    LS_CO_WRITE(LS_CO_OBJ_CONSUMER_HB, 1, 4, ((uint32_t)MASTER_ID << 16) | 250u),
};

static void test_boot_resets_configures_starts_and_reaches_ready(void **state)
{
    (void)state;
    configure_world(2);
    w.cfg.nodes[0].script = k_script;
    w.cfg.nodes[0].script_len = 4;
    start_world();
    /* The master's boot-up, then reset communication to each node. */
    uint8_t bootup = LS_CO_NMT_BOOTUP;
    assert_true(frame_eq(&w.bus.f[0],
                         &(hal_can_frame_t){ .id = LS_CO_COB_HEARTBEAT + MASTER_ID, .len = 1, .data = { bootup } }));
    for (size_t i = 0; i < 2; i++) {
        uint8_t b[2] = { LS_CO_NMT_RESET_COMM, id_of(i) };
        hal_can_frame_t want = can_frame(LS_CO_COB_NMT, 2, b);
        assert_true(frame_eq(&w.bus.f[1 + i], &want));
        assert_int_equal(phase(id_of(i)), LS_CO_PHASE_BOOTING);
    }
    deliver(); /* boot-ups, the whole script, NMT start */
    fake_t *k = fake(0x21);
    assert_int_equal(k->n_log, 3);
    assert_int_equal(k->log[0].index, LS_CO_OBJ_PRODUCER_HB); /* first: the heartbeat we consume */
    assert_int_equal(k->log[0].value, NODE_HB_MS);
    assert_int_equal(k->log[1].index, LS_CO_OBJ_MODES);
    assert_int_equal(k->log[1].value, LS_CO_MODE_CSP);
    assert_int_equal(k->log[2].index, LS_CO_OBJ_CONSUMER_HB);
    assert_int_equal(k->log[2].value, ((uint32_t)MASTER_ID << 16) | 250u);
    assert_int_equal(k->sdo_requests, 5); /* two reads, three writes */
    assert_int_equal(k->state, LS_CO_NMT_OPERATIONAL);
    assert_int_equal(phase(0x21), LS_CO_PHASE_STARTING);
    /* the NMT start went after the last SDO answer */
    size_t start_at = 0, last_sdo = 0;
    for (size_t i = 0; i < w.bus.n; i++) {
        if (w.bus.f[i].id == LS_CO_COB_NMT && w.bus.f[i].data[0] == LS_CO_NMT_START && w.bus.f[i].data[1] == 0x21) {
            start_at = i;
        }
        if (w.bus.f[i].id == LS_CO_COB_SDO_RX + 0x21u) {
            last_sdo = i;
        }
    }
    assert_true(start_at > last_sdo);
    run_ms(NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(phase(0x22), LS_CO_PHASE_READY);
    assert_int_equal(ls_co_master_node_nmt_state(&w.m, 0x21), LS_CO_NMT_OPERATIONAL);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x21), "");
}

static void test_a_node_without_boot_up_fails_at_its_deadline(void **state)
{
    (void)state;
    configure_world(2);
    fake(0x22)->dead = true;
    start_world();
    run_ms(LS_CO_BOOT_TIMEOUT_MS_DEFAULT - 1u);
    assert_int_equal(phase(0x22), LS_CO_PHASE_BOOTING);
    run_ms(1);
    expect_phase(0x22, LS_CO_PHASE_FAILED, "node 0x22: no boot-up within 2000 ms");
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    /* it stays FAILED: the master reboots nothing by itself */
    fake(0x22)->dead = false;
    run_ms(3000);
    assert_int_equal(phase(0x22), LS_CO_PHASE_FAILED);
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x22, w.now_us), LS_OK);
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x22), LS_CO_PHASE_READY);
}

static void test_a_refused_script_step_fails_the_node_naming_object_and_abort(void **state)
{
    (void)state;
    static const ls_co_step_t script[] = {
        LS_CO_WRITE(LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_COB_ID, 4, LS_CO_COBID_INVALID | LS_CO_COB_RPDO(1, 0x21)),
        LS_CO_WRITE(LS_CO_OBJ_RPDO_MAP, 0, 1, 0),
        LS_CO_WRITE(LS_CO_OBJ_RPDO_MAP, 1, 4, LS_CO_PDO_MAP_ENTRY(0x2000, 0, 32)),
        LS_CO_WRITE(LS_CO_OBJ_MODES, 0, 1, LS_CO_MODE_CSP),
    };
    start_one(script, 4);
    run_ms(10);
    expect_phase(0x21, LS_CO_PHASE_FAILED,
                 "node 0x21: SDO write 0x1600:01 aborted 0x06040041 (object cannot be mapped to the PDO)");
    assert_int_equal(fake(0x21)->n_log, 3); /* 0x1017 and the first two; nothing after the refusal */
    assert_int_equal(counters().sdo_aborts_received, 1);
    run_ms(1000);
    assert_int_equal(fake(0x21)->state, LS_CO_NMT_PREOPERATIONAL); /* never started */
}

static void test_an_optional_step_refused_is_recorded_and_configuration_goes_on(void **state)
{
    (void)state;
    static const ls_co_step_t script[] = {
        { .kind = LS_CO_STEP_WRITE,
          .index = LS_CO_OBJ_VELOCITY_OFFSET,
          .sub = 0,
          .size = 4,
          .value = 0,
          .optional = true },
        LS_CO_WRITE(LS_CO_OBJ_MODES, 0, 1, LS_CO_MODE_CSP),
    };
    start_one(script, 2);
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(fake(0x21)->log[1].index, LS_CO_OBJ_MODES);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x21),
                        "node 0x21: SDO write 0x60B1:00 aborted 0x06020000 (object does not exist in the object "
                        "dictionary) (optional: carried on)");
    assert_int_equal(counters().optional_failures, 1);
}

static void test_a_read_expect_mismatch_names_node_object_and_both_values(void **state)
{
    (void)state;
    static const ls_co_step_t script[] = {
        LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 1, 0x000000FBu, 0, "vendor id", "the EDS"),
    };
    start_one(script, 1);
    run_ms(10);
    expect_phase(0x21, LS_CO_PHASE_FAILED, "node 0x21: vendor id 0x1018:01 is 0x000000FC, the EDS says 0x000000FB");

    static const ls_co_step_t masked[] = {
        LS_CO_EXPECT(LS_CO_OBJ_DEVICE_TYPE, 0, 401u, LS_CO_DEVICE_PROFILE_MASK, "device type", NULL),
    };
    start_one(masked, 1);
    run_ms(10);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x21), "node 0x21: device type 0x1000:00 is 0x00000192, "
                                                            "expected 0x00000191 (bits 0x0000FFFF)");
}

static void test_read_into_stores_the_value_for_the_caller(void **state)
{
    (void)state;
    static uint32_t position;
    static const ls_co_step_t script[] = { LS_CO_READ_INTO(LS_CO_OBJ_POSITION_ACTUAL, 0, &position) };
    position = 0;
    start_one(script, 1);
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(position, 123456u);
}

/* The remapping the drive layer runs (CiA 301 7.5.2.36) of one PDO:
 * invalidate it, count 0, entries, count N, validate. */
#define REMAP_PDO(comm, map, cob, entry1, entry2)                                                                      \
    LS_CO_WRITE(comm, LS_CO_PDO_SUB_COB_ID, 4, LS_CO_COBID_INVALID | (cob)),                                           \
        LS_CO_WRITE(comm, LS_CO_PDO_SUB_TYPE, 1, LS_CO_PDO_TYPE_SYNC_MIN), LS_CO_WRITE(map, 0, 1, 0),                  \
        LS_CO_WRITE(map, 1, 4, entry1), LS_CO_WRITE(map, 2, 4, entry2), LS_CO_WRITE(map, 0, 1, 2),                     \
        LS_CO_WRITE(comm, LS_CO_PDO_SUB_COB_ID, 4, cob)
/* RPDO1 = controlword + target position, TPDO1 = statusword + position
 * actual, both synchronous. */
#define REMAP_STEPS(id)                                                                                                \
    REMAP_PDO(LS_CO_OBJ_RPDO_COMM, LS_CO_OBJ_RPDO_MAP, LS_CO_COB_RPDO(1, id),                                          \
              LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_CONTROLWORD, 0, 16),                                                       \
              LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32)),                                                  \
        REMAP_PDO(LS_CO_OBJ_TPDO_COMM, LS_CO_OBJ_TPDO_MAP, LS_CO_COB_TPDO(1, id),                                      \
                  LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_STATUSWORD, 0, 16),                                                    \
                  LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_POSITION_ACTUAL, 0, 32))

static void test_the_pdo_remapping_order_runs_end_to_end_against_a_strict_server(void **state)
{
    (void)state;
    static const ls_co_step_t script[] = { REMAP_STEPS(0x21) };
    const size_t n = sizeof(script) / sizeof(script[0]);
    start_one(script, n);
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    fake_t *k = fake(0x21);
    assert_int_equal(k->n_log, 1u + n);
    for (size_t i = 0; i < n; i++) { /* in the script's order, each acknowledged */
        assert_int_equal(k->log[1 + i].index, script[i].index);
        assert_int_equal(k->log[1 + i].sub, script[i].sub);
        assert_int_equal(k->log[1 + i].value, script[i].value);
    }
    assert_int_equal(fake_get(k, LS_CO_OBJ_RPDO_MAP, 0), 2);
    assert_int_equal(fake_get(k, LS_CO_OBJ_RPDO_MAP, 2), LS_CO_PDO_MAP_ENTRY(LS_CO_OBJ_TARGET_POSITION, 0, 32));
    assert_int_equal(fake_get(k, LS_CO_OBJ_TPDO_MAP, 0), 2);
    assert_int_equal(fake_get(k, LS_CO_OBJ_TPDO_COMM, LS_CO_PDO_SUB_COB_ID), LS_CO_COB_TPDO(1, 0x21));
    assert_int_equal(fake_get(k, LS_CO_OBJ_RPDO_COMM, LS_CO_PDO_SUB_TYPE), LS_CO_PDO_TYPE_SYNC_MIN);
}

static void test_remapping_out_of_order_is_refused_and_named(void **state)
{
    (void)state;
    /* an entry written while the PDO is still valid */
    static const ls_co_step_t script[] = {
        LS_CO_WRITE(LS_CO_OBJ_RPDO_MAP, 0, 1, 0),
    };
    start_one(script, 1);
    run_ms(10);
    expect_phase(0x21, LS_CO_PHASE_FAILED,
                 "node 0x21: SDO write 0x1600:00 aborted 0x06010000 (unsupported access to an object)");
}

/* ---- heartbeats ------------------------------------------------------- */

static void test_heartbeat_time_out_counts_only_after_the_first_heartbeat(void **state)
{
    (void)state;
    configure_world(1);
    w.cfg.nodes[0].boot_timeout_ms = 1000;
    fake(0x21)->hb_muted = true; /* it boots and answers, but never beats */
    start_world();
    run_ms(999);
    /* far beyond the 150 ms time-out, yet not LOST: monitoring never began */
    assert_int_equal(phase(0x21), LS_CO_PHASE_STARTING);
    run_ms(1);
    expect_phase(0x21, LS_CO_PHASE_FAILED,
                 "node 0x21: not OPERATIONAL within 1000 ms of NMT start (no heartbeat since its boot-up)");
    assert_int_equal(counters().heartbeats_lost, 0);

    boot_to_ready(1);
    run_ms(500);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    fake(0x21)->hb_muted = true;
    uint64_t last = w.now_us - (w.now_us - 1000000u) % (NODE_HB_MS * 1000u); /* its last beat */
    while (phase(0x21) == LS_CO_PHASE_READY) {
        run_ms(1);
    }
    assert_int_equal(phase(0x21), LS_CO_PHASE_LOST);
    assert_int_equal(w.now_us - last, (NODE_HB_TIMEOUT_MS + 1u) * 1000u);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x21),
                        "node 0x21: no heartbeat for 151 ms (time-out 150 ms) while READY");
    assert_int_equal(counters().heartbeats_lost, 1);
}

/* A heartbeat before the node acknowledged our 0x1017 comes at the period
 * it had stored: it must not start our time-out. */
static void test_heartbeats_before_the_producer_time_is_acknowledged_start_no_time_out(void **state)
{
    (void)state;
    configure_world(1);
    fake(0x21)->dead = true;
    start_world();
    run_ms(1);
    fake(0x21)->dead = false;
    fake_boot(fake(0x21));
    fake(0x21)->dead = true; /* deaf while the 0x1017 write goes out */
    flush_fakes();
    deliver();
    hal_can_frame_t request = w.bus.f[w.bus.n - 1u];
    assert_int_equal(request.id, LS_CO_COB_SDO_RX + 0x21u);
    uint8_t pre = LS_CO_NMT_PREOPERATIONAL;
    hal_can_frame_t beat = can_frame(LS_CO_COB_HEARTBEAT + 0x21u, 1, &pre);
    ls_co_master_on_frame(&w.m, &beat, w.now_us); /* at its stored period */
    run_ms(3u * NODE_HB_TIMEOUT_MS);              /* slow, but within the SDO time-out */
    assert_int_equal(phase(0x21), LS_CO_PHASE_CONFIGURING);
    fake(0x21)->dead = false;
    fake_hear(fake(0x21), &request, w.now_us); /* it answers at last */
    flush_fakes();
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
}

static void test_a_boot_up_while_ready_makes_the_node_lost_until_rebooted(void **state)
{
    (void)state;
    boot_to_ready(2);
    fake_boot(fake(0x22)); /* it reset by itself */
    flush_fakes();
    expect_phase(0x22, LS_CO_PHASE_LOST, "node 0x22: reset itself (boot-up while READY)");
    size_t sdo_before = fake(0x22)->sdo_requests;
    run_ms(3000);
    assert_int_equal(phase(0x22), LS_CO_PHASE_LOST); /* never reconfigured by itself */
    assert_int_equal(fake(0x22)->sdo_requests, sdo_before);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x22, w.now_us), LS_OK);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x22), "");
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x22), LS_CO_PHASE_READY);
}

static void test_a_boot_up_during_configuration_restarts_the_script(void **state)
{
    (void)state;
    static const ls_co_step_t script[] = {
        LS_CO_WRITE(LS_CO_OBJ_MODES, 0, 1, LS_CO_MODE_CSP),
        LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 1, 0x000000FCu, 0, "vendor id", NULL),
    };
    configure_world(1);
    w.cfg.nodes[0].script = script;
    w.cfg.nodes[0].script_len = 2;
    fake(0x21)->dead = true;
    start_world();
    run_ms(1);
    fake(0x21)->dead = false;
    fake_boot(fake(0x21));
    flush_fakes(); /* boot-up: the 0x1017 write goes out */
    const hal_can_frame_t *f = bus_take(&w.bus);
    while (f != NULL && f->id != LS_CO_COB_SDO_RX + 0x21u) {
        f = bus_take(&w.bus);
    }
    assert_non_null(f);
    fake_boot(fake(0x21)); /* a second boot-up before answering */
    flush_fakes();
    deliver();
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(fake(0x21)->log[0].index, LS_CO_OBJ_PRODUCER_HB); /* from the start again */
    assert_int_equal(fake(0x21)->n_log, 2);

    /* a node that keeps resetting fails */
    configure_world(1);
    w.cfg.nodes[0].script = script;
    w.cfg.nodes[0].script_len = 2;
    fake(0x21)->dead = true;
    start_world();
    run_ms(1);
    for (unsigned i = 0; i <= LS_CO_BOOT_RESTARTS + 1u; i++) {
        fake_boot(fake(0x21));
        flush_fakes();
    }
    expect_phase(0x21, LS_CO_PHASE_FAILED, "node 0x21: reset itself 4 times during configuration");
}

static void test_a_node_that_stays_pre_operational_after_start_fails_at_the_deadline(void **state)
{
    (void)state;
    configure_world(1);
    fake(0x21)->ignores_start = true;
    start_world();
    run_ms(LS_CO_BOOT_TIMEOUT_MS_DEFAULT);
    expect_phase(0x21, LS_CO_PHASE_FAILED,
                 "node 0x21: not OPERATIONAL within 2000 ms of NMT start (its heartbeat says PRE-OPERATIONAL)");
}

static void test_a_ready_node_reporting_another_state_twice_in_a_row_is_lost(void **state)
{
    (void)state;
    boot_to_ready(1);
    fake(0x21)->state = LS_CO_NMT_PREOPERATIONAL; /* it left OPERATIONAL by itself */
    run_ms(NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY); /* one heartbeat may predate a command */
    run_ms(NODE_HB_MS);
    expect_phase(0x21, LS_CO_PHASE_LOST,
                 "node 0x21: heartbeat says PRE-OPERATIONAL, not "
                 "OPERATIONAL");
}

static void test_the_master_heartbeat_carries_its_state_at_its_period(void **state)
{
    (void)state;
    boot_to_ready(1);
    w.bus.n = w.bus.seen = 0;
    uint64_t t0 = w.now_us;
    size_t beats = 0;
    for (unsigned t = 0; t < 1000; t++) {
        run_ms(1);
        for (size_t i = 0; i < w.bus.n; i++) {
            if (w.bus.f[i].id == LS_CO_COB_HEARTBEAT + MASTER_ID) {
                assert_int_equal(w.bus.f[i].len, 1);
                assert_int_equal(w.bus.f[i].data[0], LS_CO_NMT_OPERATIONAL);
                assert_int_equal((w.now_us - 1000000u) % (MASTER_HB_MS * 1000u), 0);
                beats++;
            }
        }
        w.bus.n = w.bus.seen = 0;
    }
    assert_int_equal(beats, (w.now_us - t0) / (MASTER_HB_MS * 1000u));
    assert_int_equal(ls_co_master_state(&w.m), LS_CO_NMT_OPERATIONAL);
    assert_int_equal(ls_co_master_set_state(&w.m, LS_CO_NMT_STOPPED), LS_OK);
    assert_int_equal(ls_co_master_set_state(&w.m, LS_CO_NMT_BOOTUP), LS_EINVAL);
    run_ms(MASTER_HB_MS);
    bool seen = false;
    for (size_t i = 0; i < w.bus.n; i++) {
        if (w.bus.f[i].id == LS_CO_COB_HEARTBEAT + MASTER_ID) {
            assert_int_equal(w.bus.f[i].data[0], LS_CO_NMT_STOPPED);
            seen = true;
        }
    }
    assert_true(seen);
}

/* ---- EMCY ------------------------------------------------------------- */

static void test_emcy_frames_are_decoded_in_order_and_overflow_is_counted(void **state)
{
    (void)state;
    boot_to_ready(1);
    for (unsigned i = 0; i < LS_CO_EMCY_RING + 3u; i++) {
        uint16_t code = (uint16_t)(LS_CO_EMCY_FOLLOWING_ERROR + i);
        uint8_t b[8] = { (uint8_t)code, (uint8_t)(code >> 8), 0x21, 1, 2, 3, 4, (uint8_t)i };
        hal_can_frame_t f = can_frame(LS_CO_COB_EMCY + 0x21u, 8, b);
        ls_co_master_on_frame(&w.m, &f, w.now_us + i);
    }
    ls_co_emcy_t e;
    assert_int_equal(ls_co_master_next_emcy(&w.m, 0x21, &e), 1);
    assert_int_equal(e.code, LS_CO_EMCY_FOLLOWING_ERROR);
    assert_int_equal(e.reg, 0x21);
    uint8_t vendor[5] = { 1, 2, 3, 4, 0 };
    assert_memory_equal(e.vendor, vendor, 5);
    assert_string_equal(e.name, "following error");
    assert_int_equal(e.t_us, w.now_us);
    for (unsigned i = 1; i < LS_CO_EMCY_RING; i++) {
        assert_int_equal(ls_co_master_next_emcy(&w.m, 0x21, &e), 1);
        assert_int_equal(e.code, LS_CO_EMCY_FOLLOWING_ERROR + i); /* the first ones kept: they name the cause */
    }
    assert_int_equal(ls_co_master_next_emcy(&w.m, 0x21, &e), 0);
    ls_co_counters_t c = counters();
    assert_int_equal(c.emcy_received, LS_CO_EMCY_RING + 3u);
    assert_int_equal(c.emcy_lost, 3);
    /* a short one: code and register only; shorter still is counted */
    uint8_t s[3] = { 0x10, 0x23, 0x01 };
    hal_can_frame_t f = can_frame(LS_CO_COB_EMCY + 0x21u, 3, s);
    ls_co_master_on_frame(&w.m, &f, w.now_us);
    assert_int_equal(ls_co_master_next_emcy(&w.m, 0x21, &e), 1);
    assert_int_equal(e.code, 0x2310);
    assert_string_equal(e.name, ls_co_emcy_name(0x2310));
    f.len = 2;
    ls_co_master_on_frame(&w.m, &f, w.now_us);
    assert_int_equal(counters().unexpected, 1);
    assert_int_equal(ls_co_master_next_emcy(&w.m, 0x30, &e), LS_EINVAL);
}

/* ---- SYNC and PDOs ---------------------------------------------------- */

static void set_all_rpdos(size_t n, uint8_t tag)
{
    for (size_t i = 0; i < n; i++) {
        uint8_t d[6] = { tag, (uint8_t)i, 0, 0, 0, 0 };
        assert_int_equal(ls_co_master_rpdo_set(&w.m, id_of(i), 0, d, 6), LS_OK);
    }
}

static void test_sync_sends_every_rpdo_before_the_sync_frame(void **state)
{
    (void)state;
    configure_world(3);
    for (size_t i = 0; i < 3; i++) {
        w.cfg.nodes[i].rpdo[1].cob_id = (uint16_t)LS_CO_COB_RPDO(2, id_of(i));
        w.cfg.nodes[i].rpdo[1].len = 4;
    }
    start_world();
    run_ms(2 * NODE_HB_MS);
    assert_true(ls_co_master_all_ready(&w.m));
    set_all_rpdos(3, 0xA0);
    uint8_t d4[4] = { 9, 8, 7, 6 };
    assert_int_equal(ls_co_master_rpdo_set(&w.m, 0x21, 1, d4, 4), LS_OK);
    assert_int_equal(ls_co_master_rpdo_set(&w.m, 0x21, 1, d4, 3), LS_ELEN);
    w.bus.n = w.bus.seen = 0;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_OK);
    /* RPDO1 and RPDO2 of 0x21, RPDO1 of 0x22 and 0x23 (their RPDO2 was never set), then SYNC */
    assert_int_equal(w.bus.n, 5);
    assert_int_equal(w.bus.f[0].id, LS_CO_COB_RPDO(1, 0x21));
    assert_int_equal(w.bus.f[0].data[0], 0xA0);
    assert_int_equal(w.bus.f[1].id, LS_CO_COB_RPDO(2, 0x21));
    assert_memory_equal(w.bus.f[1].data, d4, 4);
    assert_int_equal(w.bus.f[1].len, 4);
    assert_int_equal(w.bus.f[2].id, LS_CO_COB_RPDO(1, 0x22));
    assert_int_equal(w.bus.f[3].id, LS_CO_COB_RPDO(1, 0x23));
    assert_int_equal(w.bus.f[4].id, LS_CO_COB_SYNC);
    assert_int_equal(w.bus.f[4].len, 0);
    /* a node that is not READY gets none */
    fake(0x22)->hb_muted = true;
    run_ms(NODE_HB_TIMEOUT_MS + NODE_HB_MS);
    assert_int_equal(phase(0x22), LS_CO_PHASE_LOST);
    w.bus.n = w.bus.seen = 0;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_OK);
    assert_int_equal(w.bus.n, 4);
    for (size_t i = 0; i < 3; i++) {
        assert_true((w.bus.f[i].id & 0x7Fu) != 0x22u);
    }
    assert_int_equal(w.bus.f[3].id, LS_CO_COB_SYNC);
    assert_int_equal(counters().sync_sent, 2);
}

static void test_a_refused_send_resumes_the_cycle_in_order_with_sync_last(void **state)
{
    (void)state;
    boot_to_ready(3);
    set_all_rpdos(3, 0xB0);
    w.bus.n = w.bus.seen = 0;
    ls_co_counters_t before = counters();
    w.bus.refuse = 1;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_EAGAIN);
    assert_int_equal(w.bus.n, 0); /* stopped at the first refusal */
    ls_co_master_poll(&w.m, w.now_us + 1000u);
    assert_int_equal(w.bus.n, 4);
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(w.bus.f[i].id, LS_CO_COB_RPDO(1, id_of(i)));
    }
    assert_int_equal(w.bus.f[3].id, LS_CO_COB_SYNC);
    /* room for two frames: the rest follows at the next poll, SYNC last */
    w.bus.n = w.bus.seen = 0;
    set_all_rpdos(3, 0xB1);
    w.bus.limited = true;
    w.bus.room = 2;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us + 2000u), LS_EAGAIN);
    assert_int_equal(w.bus.n, 2);
    ls_co_master_poll(&w.m, w.now_us + 3000u);
    assert_int_equal(w.bus.n, 2); /* still full */
    w.bus.limited = false;
    ls_co_master_poll(&w.m, w.now_us + 4000u);
    assert_int_equal(w.bus.n, 4);
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(w.bus.f[i].id, LS_CO_COB_RPDO(1, id_of(i)));
        assert_int_equal(w.bus.f[i].data[0], 0xB1);
    }
    assert_int_equal(w.bus.f[3].id, LS_CO_COB_SYNC);
    ls_co_master_poll(&w.m, w.now_us + 5000u);
    assert_int_equal(w.bus.n, 4); /* nothing twice */
    ls_co_counters_t after = counters();
    assert_int_equal(after.sends_refused, before.sends_refused + 3u);
    assert_int_equal(after.sync_deferred, before.sync_deferred + 2u);
    assert_int_equal(after.sync_sent, before.sync_sent + 2u);
}

static void test_a_sync_while_the_last_cycle_is_unfinished_restarts_it(void **state)
{
    (void)state;
    boot_to_ready(2);
    set_all_rpdos(2, 0xC0);
    w.bus.n = w.bus.seen = 0;
    w.bus.refuse_all = true;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_EAGAIN);
    set_all_rpdos(2, 0xC1);
    w.bus.refuse_all = false;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us + 4000u), LS_OK);
    assert_int_equal(w.bus.n, 3); /* one cycle, the newest bytes, not two */
    assert_int_equal(w.bus.f[0].data[0], 0xC1);
    assert_int_equal(w.bus.f[2].id, LS_CO_COB_SYNC);
    ls_co_master_poll(&w.m, w.now_us + 5000u);
    for (size_t i = 3; i < w.bus.n; i++) {
        assert_int_not_equal(w.bus.f[i].id, LS_CO_COB_SYNC);
    }
    assert_int_equal(counters().sync_overruns, 1);
}

/* A dead link sent nothing: after drop_unsent, a reboot sends its node's
 * one reset and no stale command of another node goes with it. */
static void test_after_a_dead_link_a_reboot_sends_one_reset_for_its_node_only(void **state)
{
    (void)state;
    boot_to_ready(2);
    w.bus.refuse_all = true;
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x21, w.now_us), LS_OK);
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x22, w.now_us), LS_OK);
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_EAGAIN);
    ls_co_master_drop_unsent(&w.m);
    w.bus.refuse_all = false;
    w.bus.n = w.bus.seen = 0;
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x21, w.now_us), LS_OK);
    ls_co_master_poll(&w.m, w.now_us);
    int resets = 0;
    for (size_t i = 0; i < w.bus.n; i++) {
        if (w.bus.f[i].id == LS_CO_COB_NMT) {
            assert_int_equal(w.bus.f[i].data[0], LS_CO_NMT_RESET_COMM);
            assert_int_equal(w.bus.f[i].data[1], 0x21);
            resets++;
        }
        assert_int_not_equal(w.bus.f[i].id, LS_CO_COB_SYNC); /* the dead cycle's frames stay unsent */
    }
    assert_int_equal(resets, 1);
}

static void test_tpdo_age_counts_sync_periods_since_arrival(void **state)
{
    (void)state;
    boot_to_ready(1);
    uint8_t out[8];
    size_t len = 0;
    uint32_t age = 99;
    assert_int_equal(ls_co_master_tpdo_get(&w.m, 0x21, 0, out, &len, &age), LS_EAGAIN);
    assert_int_equal(age, 99); /* untouched */
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_OK);
    uint8_t d[8] = { 0x37, 0x06, 1, 2, 3, 4, 0xEE, 0xEE };
    hal_can_frame_t f = can_frame(LS_CO_COB_TPDO(1, 0x21), 8, d); /* longer than mapped: cut */
    ls_co_master_on_frame(&w.m, &f, w.now_us);
    assert_int_equal(ls_co_master_tpdo_get(&w.m, 0x21, 0, out, &len, &age), LS_OK);
    assert_int_equal(len, 6);
    assert_memory_equal(out, d, 6);
    assert_int_equal(age, 0); /* the answer to the latest SYNC */
    for (uint32_t k = 1; k <= 3; k++) {
        assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_OK);
        assert_int_equal(ls_co_master_tpdo_get(&w.m, 0x21, 0, out, &len, &age), LS_OK);
        assert_int_equal(age, k);
    }
    f.len = 5; /* shorter than mapped: dropped and counted */
    uint32_t unexpected = counters().unexpected;
    ls_co_master_on_frame(&w.m, &f, w.now_us);
    assert_int_equal(counters().unexpected, unexpected + 1u);
    assert_int_equal(ls_co_master_tpdo_get(&w.m, 0x21, 0, out, &len, &age), LS_OK);
    assert_int_equal(age, 3);
    assert_int_equal(ls_co_master_tpdo_get(&w.m, 0x21, 1, out, &len, &age), LS_EINVAL); /* slot not configured */
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x21, w.now_us), LS_OK);
    assert_int_equal(ls_co_master_tpdo_get(&w.m, 0x21, 0, out, &len, &age), LS_EAGAIN); /* forgotten at boot */
}

/* ---- NMT, caller SDO, frames ------------------------------------------ */

static void test_nmt_commands_reach_one_node_or_all_and_set_the_expected_state(void **state)
{
    (void)state;
    boot_to_ready(2);
    set_all_rpdos(2, 0xD0);
    w.bus.n = w.bus.seen = 0;
    assert_int_equal(ls_co_master_nmt(&w.m, 0x22, LS_CO_NMT_STOP, w.now_us), LS_OK);
    uint8_t b[2] = { LS_CO_NMT_STOP, 0x22 };
    hal_can_frame_t want = can_frame(LS_CO_COB_NMT, 2, b);
    assert_true(frame_eq(&w.bus.f[0], &want));
    run_ms(5 * NODE_HB_MS);
    assert_int_equal(phase(0x22), LS_CO_PHASE_READY); /* STOPPED as commanded: not lost */
    assert_int_equal(ls_co_master_node_nmt_state(&w.m, 0x22), LS_CO_NMT_STOPPED);
    w.bus.n = w.bus.seen = 0;
    assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_OK);
    assert_int_equal(w.bus.n, 2); /* RPDO of 0x21, SYNC: a stopped node gets no PDO */
    assert_int_equal(ls_co_master_nmt(&w.m, LS_CO_NMT_ALL_NODES, LS_CO_NMT_START, w.now_us), LS_OK);
    uint8_t all[2] = { LS_CO_NMT_START, LS_CO_NMT_ALL_NODES };
    want = can_frame(LS_CO_COB_NMT, 2, all);
    assert_true(frame_eq(&w.bus.f[2], &want));
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(ls_co_master_node_nmt_state(&w.m, 0x22), LS_CO_NMT_OPERATIONAL);
    assert_int_equal(ls_co_master_nmt(&w.m, 0x21, LS_CO_NMT_RESET_NODE, w.now_us), LS_OK);
    expect_phase(0x21, LS_CO_PHASE_IDLE, "node 0x21: reset by the master (NMT 0x81); boot it again to use it");
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_IDLE);
    assert_int_equal(ls_co_master_nmt(&w.m, 0x21, 0x03, w.now_us), LS_EINVAL);
    assert_int_equal(ls_co_master_nmt(&w.m, 0x40, LS_CO_NMT_START, w.now_us), LS_EINVAL);
}

static void test_a_caller_sdo_runs_on_a_ready_node_and_not_while_configuring(void **state)
{
    (void)state;
    configure_world(1);
    fake(0x21)->dead = true;
    start_world();
    assert_int_equal(ls_co_master_sdo_read(&w.m, 0x21, LS_CO_OBJ_POSITION_ACTUAL, 0, w.now_us), LS_EBUSY);
    fake(0x21)->dead = false;
    assert_int_equal(ls_co_master_reboot_node(&w.m, 0x21, w.now_us), LS_OK);
    run_ms(2 * NODE_HB_MS);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(ls_co_master_sdo_read(&w.m, 0x21, LS_CO_OBJ_POSITION_ACTUAL, 0, w.now_us), LS_OK);
    assert_int_equal(ls_co_master_sdo_result(&w.m, 0x21, NULL, 0, NULL), LS_EBUSY);
    deliver();
    uint8_t out[8];
    size_t len = 0;
    assert_int_equal(ls_co_master_sdo_result(&w.m, 0x21, out, sizeof(out), &len), LS_OK);
    assert_int_equal(len, 4);
    assert_int_equal(rd32(out), 123456u);
    uint8_t v = 1;
    assert_int_equal(ls_co_master_sdo_write(&w.m, 0x21, LS_CO_OBJ_STATUSWORD, 0, &v, 1, w.now_us), LS_OK);
    run_ms(1);
    assert_int_equal(ls_co_master_sdo_result(&w.m, 0x21, NULL, 0, NULL), LS_EABORTED);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x21),
                        "node 0x21: SDO write 0x6041:00 aborted 0x06010002 (attempt to write a read-only object)");
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
}

static void test_no_sdo_traffic_is_started_while_ready(void **state)
{
    (void)state;
    boot_to_ready(3);
    size_t before[3];
    for (size_t i = 0; i < 3; i++) {
        before[i] = fake(id_of(i))->sdo_requests;
    }
    for (unsigned cycle = 0; cycle < 2000; cycle++) {
        w.bus.n = w.bus.seen = 0;
        if (cycle % 4u == 0u) {
            set_all_rpdos(3, (uint8_t)cycle);
            assert_int_equal(ls_co_master_sync(&w.m, w.now_us), LS_OK);
        }
        run_ms(1);
        for (size_t i = 0; i < w.bus.n; i++) {
            uint32_t fn = w.bus.f[i].id & ~0x7Fu;
            assert_int_not_equal(fn, LS_CO_COB_SDO_RX);
        }
    }
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(fake(id_of(i))->sdo_requests, before[i]);
        assert_int_equal(phase(id_of(i)), LS_CO_PHASE_READY);
    }
}

static void test_foreign_and_malformed_frames_are_ignored_or_counted(void **state)
{
    (void)state;
    boot_to_ready(1);
    ls_co_counters_t c0 = counters();
    uint8_t b[8] = { LS_CO_NMT_BOOTUP, 0, 0, 0, 0, 0, 0, 0 };
    hal_can_frame_t ext = can_frame(LS_CO_COB_HEARTBEAT + 0x21u, 1, b);
    ext.flags = HAL_CAN_F_EXT;
    ls_co_master_on_frame(&w.m, &ext, w.now_us); /* a 29-bit frame is no boot-up */
    hal_can_frame_t rtr = ext;
    rtr.flags = HAL_CAN_F_RTR;
    ls_co_master_on_frame(&w.m, &rtr, w.now_us);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(counters().frames_in, c0.frames_in);
    hal_can_frame_t other = can_frame(LS_CO_COB_HEARTBEAT + 0x40u, 1, b); /* not ours */
    ls_co_master_on_frame(&w.m, &other, w.now_us);
    hal_can_frame_t other_pdo = can_frame(LS_CO_COB_TPDO(1, 0x40), 8, b);
    ls_co_master_on_frame(&w.m, &other_pdo, w.now_us);
    assert_int_equal(counters().unexpected, c0.unexpected);
    hal_can_frame_t nmt = can_frame(LS_CO_COB_NMT, 2, b); /* another master */
    ls_co_master_on_frame(&w.m, &nmt, w.now_us);
    hal_can_frame_t sync = can_frame(LS_CO_COB_SYNC, 0, b);
    ls_co_master_on_frame(&w.m, &sync, w.now_us);
    hal_can_frame_t hb0 = can_frame(LS_CO_COB_HEARTBEAT + 0x21u, 0, b);
    ls_co_master_on_frame(&w.m, &hb0, w.now_us);
    hal_can_frame_t stray = sdo_mux(LS_CO_COB_SDO_TX + 0x21u, LS_CO_SDO_SCS_DOWNLOAD_INITIATE, 0x6040, 0, NULL);
    ls_co_master_on_frame(&w.m, &stray, w.now_us);
    ls_co_counters_t c = counters();
    assert_int_equal(c.unexpected, c0.unexpected + 4u);
    assert_int_equal(c.frames_in, c0.frames_in + 6u);
    assert_int_equal(phase(0x21), LS_CO_PHASE_READY);
    assert_int_equal(ls_co_master_node_phase(&w.m, 0x40), LS_CO_PHASE_IDLE);
    assert_string_equal(ls_co_master_node_text(&w.m, 0x40), "");
    assert_string_equal(ls_co_phase_name(LS_CO_PHASE_LOST), "LOST");
    assert_string_equal(ls_co_phase_name((ls_co_phase_t)42), "unknown");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_refuses_a_configuration_naming_what_is_wrong),
        cmocka_unit_test(test_boot_resets_configures_starts_and_reaches_ready),
        cmocka_unit_test(test_a_node_without_boot_up_fails_at_its_deadline),
        cmocka_unit_test(test_a_refused_script_step_fails_the_node_naming_object_and_abort),
        cmocka_unit_test(test_an_optional_step_refused_is_recorded_and_configuration_goes_on),
        cmocka_unit_test(test_a_read_expect_mismatch_names_node_object_and_both_values),
        cmocka_unit_test(test_read_into_stores_the_value_for_the_caller),
        cmocka_unit_test(test_the_pdo_remapping_order_runs_end_to_end_against_a_strict_server),
        cmocka_unit_test(test_remapping_out_of_order_is_refused_and_named),
        cmocka_unit_test(test_heartbeat_time_out_counts_only_after_the_first_heartbeat),
        cmocka_unit_test(test_heartbeats_before_the_producer_time_is_acknowledged_start_no_time_out),
        cmocka_unit_test(test_a_boot_up_while_ready_makes_the_node_lost_until_rebooted),
        cmocka_unit_test(test_a_boot_up_during_configuration_restarts_the_script),
        cmocka_unit_test(test_a_node_that_stays_pre_operational_after_start_fails_at_the_deadline),
        cmocka_unit_test(test_a_ready_node_reporting_another_state_twice_in_a_row_is_lost),
        cmocka_unit_test(test_the_master_heartbeat_carries_its_state_at_its_period),
        cmocka_unit_test(test_emcy_frames_are_decoded_in_order_and_overflow_is_counted),
        cmocka_unit_test(test_sync_sends_every_rpdo_before_the_sync_frame),
        cmocka_unit_test(test_a_refused_send_resumes_the_cycle_in_order_with_sync_last),
        cmocka_unit_test(test_a_sync_while_the_last_cycle_is_unfinished_restarts_it),
        cmocka_unit_test(test_tpdo_age_counts_sync_periods_since_arrival),
        cmocka_unit_test(test_after_a_dead_link_a_reboot_sends_one_reset_for_its_node_only),
        cmocka_unit_test(test_nmt_commands_reach_one_node_or_all_and_set_the_expected_state),
        cmocka_unit_test(test_a_caller_sdo_runs_on_a_ready_node_and_not_while_configuring),
        cmocka_unit_test(test_no_sdo_traffic_is_started_while_ready),
        cmocka_unit_test(test_foreign_and_malformed_frames_are_ignored_or_counted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
