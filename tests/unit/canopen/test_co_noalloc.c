/* Proof that the CANopen master never touches the heap: this executable is
 * linked with --wrap for every allocator entry point (ls_add_noalloc_test),
 * so a call from libls_canopen_master.a, libls_fmt.a or this file lands in
 * the counter of tests/support/alloc_counter.c. The counter is armed around
 * init, a boot of four nodes through their scripts (successes and
 * failures, whose lines are formatted), and many control cycles with SYNC,
 * PDOs, EMCY, heartbeats, refused sends and a lost node. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "alloc_counter.h"
#include "co_fake_node.h"
#include "ls_co_master.h"

#define N_NODES 4u

static bus_t bus;
static ls_co_master_t m;
static fake_t fakes[N_NODES];
static uint64_t now_us = 1000000;
static uint32_t position;

static const ls_co_step_t k_script[] = {
    LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 1, 0x000000FCu, 0, "vendor id", "the EDS"),
    LS_CO_WRITE(LS_CO_OBJ_MODES, 0, 1, LS_CO_MODE_CSP),
    LS_CO_READ_INTO(LS_CO_OBJ_POSITION_ACTUAL, 0, &position),
    { .kind = LS_CO_STEP_WRITE, .index = LS_CO_OBJ_VELOCITY_OFFSET, .size = 4, .optional = true },
};
static const ls_co_step_t k_bad_script[] = {
    LS_CO_EXPECT(LS_CO_OBJ_IDENTITY, 1, 0x000000FBu, 0, "vendor id", "the EDS"),
};

static void deliver(void)
{
    const hal_can_frame_t *f;
    while ((f = bus_take(&bus)) != NULL) {
        hal_can_frame_t copy = *f;
        for (size_t i = 0; i < N_NODES; i++) {
            fake_hear(&fakes[i], &copy, now_us);
            for (size_t j = 0; j < fakes[i].n_out; j++) {
                ls_co_master_on_frame(&m, &fakes[i].out[j], now_us);
            }
            fakes[i].n_out = 0;
        }
    }
    bus.n = bus.seen = 0;
}

static void cycle(unsigned k)
{
    now_us += 1000u;
    ls_co_master_poll(&m, now_us);
    if (k % 4u == 0u) {
        for (uint8_t i = 0; i < N_NODES; i++) {
            uint8_t d[6] = { (uint8_t)k, i, 0, 0, 0, 0 };
            (void)ls_co_master_rpdo_set(&m, (uint8_t)(0x21u + i), 0, d, 6);
            uint8_t out[8];
            size_t len = 0;
            uint32_t age = 0;
            (void)ls_co_master_tpdo_get(&m, (uint8_t)(0x21u + i), 0, out, &len, &age);
        }
        (void)ls_co_master_sync(&m, now_us);
    }
    deliver();
    for (size_t i = 0; i < N_NODES; i++) {
        fake_tick(&fakes[i], now_us);
        for (size_t j = 0; j < fakes[i].n_out; j++) {
            ls_co_master_on_frame(&m, &fakes[i].out[j], now_us);
        }
        fakes[i].n_out = 0;
    }
    deliver();
}

static void test_the_master_never_allocates(void **state)
{
    (void)state;
    ls_co_master_config_t cfg;
    memset(&cfg, 0, sizeof(cfg));
    cfg.node_id = 0x7F;
    cfg.heartbeat_ms = 100;
    cfg.node_count = N_NODES;
    for (uint8_t i = 0; i < N_NODES; i++) {
        uint8_t id = (uint8_t)(0x21u + i);
        if (i == 3u) {
            co_test_node(&cfg.nodes[i], id, k_bad_script, 1);
        } else {
            co_test_node(&cfg.nodes[i], id, k_script, sizeof(k_script) / sizeof(k_script[0]));
        }
        fake_init(&fakes[i], id);
    }
    fakes[2].dead = true; /* never boots: its deadline formats a line */

    alloc_counter_reset();
    alloc_counter_arm();
    assert_int_equal(ls_co_master_init(&m, &cfg, bus_send, &bus), LS_OK);
    assert_int_equal(ls_co_master_boot(&m, now_us), LS_OK);
    for (unsigned k = 0; k < 3000; k++) {
        if (k == 1000u) {
            fakes[1].hb_muted = true; /* lost: a line */
        }
        if (k == 1500u) {
            uint8_t e[8] = { 0x11, 0x86, 0x08, 0, 0, 0, 0, 0 };
            hal_can_frame_t f = can_frame(LS_CO_COB_EMCY + 0x21u, 8, e);
            for (unsigned j = 0; j < 2u * LS_CO_EMCY_RING; j++) {
                ls_co_master_on_frame(&m, &f, now_us);
            }
            ls_co_emcy_t out;
            while (ls_co_master_next_emcy(&m, 0x21, &out) == 1) {
            }
        }
        if (k == 2000u) {
            bus.refuse = 3; /* a full queue mid-cycle */
            (void)ls_co_master_sdo_read(&m, 0x21, LS_CO_OBJ_STATUSWORD, 0, now_us);
        }
        cycle(k);
    }
    ls_co_counters_t c;
    assert_int_equal(ls_co_master_counters(&m, &c), LS_OK);
    alloc_counter_disarm();

    assert_int_equal(ls_co_master_node_phase(&m, 0x21), LS_CO_PHASE_READY);
    assert_int_equal(ls_co_master_node_phase(&m, 0x22), LS_CO_PHASE_LOST);
    assert_int_equal(ls_co_master_node_phase(&m, 0x23), LS_CO_PHASE_FAILED);
    assert_int_equal(ls_co_master_node_phase(&m, 0x24), LS_CO_PHASE_FAILED);
    assert_true(c.sync_sent > 500u);
    assert_true(c.emcy_lost > 0u);
    assert_int_equal(alloc_counter_count(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test(test_the_master_never_allocates),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
