/* The drive arm's configuration script: what it writes, in which order,
 * and only what the joint's EDS allows (firmware/drives/ls_drives.h). The
 * steps are compared with values spelled from CiA 301/402 here, not with
 * the code's own encoder. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "ls_drives.h"

static ls_drives_t g_d;
static hal_can_link_t g_link; /* never used: init sends nothing */

static ls_drives_config_t config(void)
{
    ls_drives_config_t c;
    memset(&c, 0, sizeof c);
    c.n_joints = 6;
    c.link = &g_link;
    c.control_period_us = 1000;
    c.cycle_ticks = 4;
    c.master_node = 0x7F;
    c.heartbeat_ms = 100;
    c.heartbeat_timeout_ms = 350;
    c.boot_timeout_ms = 2000;
    c.abort_option = 3;
    for (int j = 0; j < 6; j++) {
        ls_drive_joint_t *dj = &c.joint[j];
        dj->node_id = (uint8_t)(0x21 + j);
        dj->scale.counts_per_rad = 1000.0;
        dj->scale.sign = 1;
        dj->has_vendor = dj->has_product = true;
        dj->vendor_id = 0xFB;
        dj->product_code = 0x65520000;
        dj->write_consumer_hb = dj->write_abort_option = dj->write_interp_period = true;
        dj->write_pdo_type = dj->write_tpdo_inhibit = true;
        dj->feedforward = true;
        for (int p = 0; p < 4; p++) {
            dj->rpdo_present[p] = dj->tpdo_present[p] = true;
        }
    }
    return c;
}

/* Index of the first step writing (index, sub) = value at or after `from`; -1 if none. */
static int find_write(const ls_co_step_t *s, size_t n, size_t from, uint16_t index, uint8_t sub, uint32_t value)
{
    for (size_t i = from; i < n; i++) {
        if (s[i].kind == LS_CO_STEP_WRITE && s[i].index == index && s[i].sub == sub && s[i].value == value) {
            return (int)i;
        }
    }
    return -1;
}

static size_t script_len(int j)
{
    return g_d.master.nodes[j].cfg.script_len;
}

static void test_a_pdo_is_remapped_in_the_order_cia_301_asks(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[2];
    const size_t n = script_len(2);
    /* RPDO1 of node 0x23: COB-ID 0x223 */
    const int off = find_write(s, n, 0, 0x1400, 1, 0x80000223u);
    const int type = find_write(s, n, (size_t)off, 0x1400, 2, 1);
    const int zero = find_write(s, n, (size_t)off, 0x1600, 0, 0);
    const int e1 = find_write(s, n, (size_t)off, 0x1600, 1, 0x60400010u);
    const int e2 = find_write(s, n, (size_t)off, 0x1600, 2, 0x607A0020u);
    const int count = find_write(s, n, (size_t)off, 0x1600, 0, 2);
    const int on = find_write(s, n, (size_t)off, 0x1400, 1, 0x223u);
    assert_true(off >= 0 && off < type && type < zero && zero < e1 && e1 < e2 && e2 < count && count < on);
    /* TPDO1: statusword + position actual, synchronous, no inhibit */
    const int toff = find_write(s, n, 0, 0x1800, 1, 0x800001A3u);
    assert_true(toff >= 0);
    assert_true(find_write(s, n, (size_t)toff, 0x1800, 2, 1) > toff);
    assert_true(find_write(s, n, (size_t)toff, 0x1800, 3, 0) > toff);
    assert_true(find_write(s, n, (size_t)toff, 0x1A00, 1, 0x60410010u) > toff);
    assert_true(find_write(s, n, (size_t)toff, 0x1A00, 2, 0x60640020u) > toff);
    assert_true(find_write(s, n, (size_t)toff, 0x1800, 1, 0x1A3u) > toff);
    /* RPDO2: the velocity offset */
    const int ff = find_write(s, n, 0, 0x1401, 1, 0x80000323u);
    assert_true(ff >= 0 && find_write(s, n, (size_t)ff, 0x1601, 1, 0x60B10020u) > ff);
    assert_true(find_write(s, n, (size_t)ff, 0x1401, 1, 0x323u) > ff);
}

static void test_every_power_on_pdo_goes_off_before_any_mapping(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[0];
    const size_t n = script_len(0);
    const int first_map = find_write(s, n, 0, 0x1600, 0, 0);
    for (uint16_t p = 0; p < 4; p++) {
        const int r = find_write(s, n, 0, (uint16_t)(0x1400 + p), 1, 0x80000000u | (0x221u + 0x100u * p));
        const int t = find_write(s, n, 0, (uint16_t)(0x1800 + p), 1, 0x80000000u | (0x1A1u + 0x100u * p));
        assert_true(r >= 0 && r < first_map);
        assert_true(t >= 0 && t < first_map);
    }
}

static void test_heartbeats_abort_option_interpolation_and_csp(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[5];
    const size_t n = script_len(5);
    assert_true(find_write(s, n, 0, 0x1016, 1, (0x7Fu << 16) | 350u) >= 0); /* the drive watches node 0x7F */
    assert_true(find_write(s, n, 0, 0x6007, 0, 3) >= 0);                    /* quick stop when we go silent */
    assert_true(find_write(s, n, 0, 0x60C2, 1, 4) >= 0);                    /* 4 x 10^-3 s */
    assert_true(find_write(s, n, 0, 0x60C2, 2, 0xFDu) >= 0);
    const int mode = find_write(s, n, 0, 0x6060, 0, 8);
    assert_true(mode >= 0);
    /* the mode is confirmed in 0x6061 before anything else, then the actual
     * position and the statusword are read for target = actual */
    assert_int_equal(s[mode + 1].kind, LS_CO_STEP_EXPECT);
    assert_int_equal(s[mode + 1].index, 0x6061);
    assert_int_equal(s[mode + 1].value, 8);
    assert_int_equal(s[mode + 2].kind, LS_CO_STEP_READ_INTO);
    assert_int_equal(s[mode + 2].index, 0x6064);
    /* the identity first: a CiA 402 device, then the EDS's vendor and product */
    assert_int_equal(s[0].kind, LS_CO_STEP_EXPECT);
    assert_int_equal(s[0].index, 0x1000);
    assert_int_equal(s[0].mask, 0xFFFFu);
    assert_int_equal(s[0].value, 402);
    assert_int_equal(s[1].index, 0x1018);
    assert_int_equal(s[1].sub, 1);
    assert_int_equal(s[1].value, 0xFB);
    assert_int_equal(s[2].sub, 2);
}

static void test_only_what_the_eds_allows_is_written(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    ls_drive_joint_t *dj = &c.joint[1];
    dj->write_consumer_hb = dj->write_abort_option = dj->write_interp_period = false;
    dj->write_pdo_type = dj->write_tpdo_inhibit = dj->feedforward = false;
    dj->has_vendor = dj->has_product = false;
    for (int p = 1; p < 4; p++) {
        dj->rpdo_present[p] = dj->tpdo_present[p] = false;
    }
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[1];
    const size_t n = script_len(1);
    for (size_t i = 0; i < n; i++) {
        const uint16_t x = s[i].index;
        assert_true(x != 0x1016 && x != 0x6007 && x != 0x60C2 && x != 0x1018 && x != 0x1401 && x != 0x1601);
        assert_true(x < 0x1401 || x > 0x1403);
        assert_true(x < 0x1801 || x > 0x1803);
        if (s[i].kind == LS_CO_STEP_WRITE && (x == 0x1400 || x == 0x1800)) {
            assert_int_equal(s[i].sub, 1); /* no transmission type, no inhibit */
        }
    }
    /* the drive arm's PDOs in the master follow: no RPDO2 without feed-forward */
    assert_int_equal(g_d.master.nodes[1].cfg.rpdo[1].cob_id, 0);
    assert_int_equal(g_d.master.nodes[0].cfg.rpdo[1].cob_id, 0x321);
}

static void test_interpolation_periods_in_ms_and_below(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    c.control_period_us = 500; /* 2 kHz x 5 = 2.5 ms: 25 x 10^-4 s */
    c.cycle_ticks = 5;
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[0];
    assert_true(find_write(s, script_len(0), 0, 0x60C2, 1, 25) >= 0);
    assert_true(find_write(s, script_len(0), 0, 0x60C2, 2, 0xFCu) >= 0);
}

static void test_a_bad_configuration_is_named(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    c.joint[3].scale.counts_per_rad = 0.0;
    assert_int_equal(ls_drives_init(&g_d, &c), LS_EINVAL);
    assert_string_equal(ls_drives_text(&g_d), "joint 4: its scaling is invalid (counts_per_rad > 0, sign 1 or -1)");
    c = config();
    c.joint[4].node_id = c.joint[2].node_id;
    assert_int_equal(ls_drives_init(&g_d, &c), LS_EINVAL);
    assert_non_null(strstr(ls_drives_text(&g_d), "drives: "));
    c = config();
    c.heartbeat_timeout_ms = 100;
    assert_int_equal(ls_drives_init(&g_d, &c), LS_EINVAL);
}

static const ls_co_step_t *find_step(const ls_co_step_t *s, size_t n, ls_co_step_kind_t kind, uint16_t index,
                                     uint8_t sub)
{
    for (size_t i = 0; i < n; i++) {
        if (s[i].kind == kind && s[i].index == index && s[i].sub == sub) {
            return &s[i];
        }
    }
    return NULL;
}

static void test_the_mode_rides_in_the_pdos_where_the_eds_lets_it(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    c.joint[0].map_mode = true;
    c.joint[0].tpdo_room[0] = 8;
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[0];
    const size_t n = script_len(0);
    const int r = find_write(s, n, 0, 0x1600, 3, 0x60600008u);
    assert_true(r >= 0 && find_write(s, n, (size_t)r, 0x1600, 0, 3) > r);
    const int t = find_write(s, n, 0, 0x1A00, 3, 0x60610008u);
    assert_true(t >= 0 && find_write(s, n, (size_t)t, 0x1A00, 0, 3) > t);
    assert_int_equal(g_d.master.nodes[0].cfg.rpdo[0].len, 7);
    assert_int_equal(g_d.master.nodes[0].cfg.tpdo[0].len, 7);
    /* without it the PDOs stay as they were: 6 bytes each */
    assert_int_equal(find_write(g_d.script[1], script_len(1), 0, 0x1600, 3, 0x60600008u), -1);
    assert_int_equal(g_d.master.nodes[1].cfg.rpdo[0].len, 6);
}

static void test_the_readouts_fill_tpdo1_then_tpdo2_in_their_order(void **state)
{
    (void)state;
    ls_drive_joint_t jc;
    memset(&jc, 0, sizeof jc);
    jc.map_mode = true;
    jc.tpdo_room[0] = jc.tpdo_room[1] = 8;
    jc.brake = (ls_drive_obj_t){ .map = true, .index = 0x2100, .sub = 1, .bytes = 1 };
    jc.sto = (ls_drive_obj_t){ .map = true, .index = 0x2100, .sub = 2, .bytes = 1 };
    jc.torque = (ls_drive_obj_t){ .map = true, .index = 0x6077, .bytes = 2 };
    jc.velocity = (ls_drive_obj_t){ .map = true, .index = 0x606C, .bytes = 4 };
    ls_drive_layout_t l;
    ls_drives_layout(&jc, &l);
    assert_int_equal(l.rpdo1_bytes, 7);
    assert_int_equal(l.n_tpdo, 2);
    assert_int_equal(l.tpdo_bytes[0], 8); /* statusword, position, mode display, brake */
    assert_int_equal(l.map[0][3], 0x21000108u);
    assert_true(l.ro[LS_DRIVE_RO_BRAKE].mapped && l.ro[LS_DRIVE_RO_BRAKE].slot == 0 &&
                l.ro[LS_DRIVE_RO_BRAKE].offset == 7);
    assert_int_equal(l.tpdo_bytes[1], 7); /* STO, torque, velocity */
    assert_int_equal(l.map[1][0], 0x21000208u);
    assert_int_equal(l.map[1][1], 0x60770010u);
    assert_int_equal(l.map[1][2], 0x606C0020u);
    assert_int_equal(l.ro[LS_DRIVE_RO_VELOCITY].offset, 3);
    assert_int_equal(l.left_out, 0);
    /* a temperature of 4 bytes finds no room: named, the rest stays */
    jc.temperature = (ls_drive_obj_t){ .map = true, .index = 0x2101, .bytes = 4 };
    ls_drives_layout(&jc, &l);
    assert_int_equal(l.left_out, 1u << LS_DRIVE_RO_VELOCITY);
    assert_true(l.ro[LS_DRIVE_RO_TEMPERATURE].mapped);
    /* a TPDO2 the EDS does not let be mapped takes nothing */
    jc.tpdo_room[1] = 0;
    ls_drives_layout(&jc, &l);
    assert_int_equal(l.n_tpdo, 1);
    assert_int_equal(l.left_out, (1u << LS_DRIVE_RO_STO) | (1u << LS_DRIVE_RO_TORQUE) |
                                     (1u << LS_DRIVE_RO_TEMPERATURE) | (1u << LS_DRIVE_RO_VELOCITY));
    /* nothing asked: TPDO1 as before */
    memset(&jc, 0, sizeof jc);
    ls_drives_layout(&jc, &l);
    assert_int_equal(l.n_tpdo, 1);
    assert_int_equal(l.tpdo_bytes[0], 6);
    assert_int_equal(l.rpdo1_bytes, 6);
}

static void test_the_drives_own_supervision_and_homing_are_set_at_start(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    ls_drive_joint_t *dj = &c.joint[2];
    dj->write_fe_window = dj->write_fe_timeout = dj->write_quick_stop = true;
    dj->fe_window_counts = 2000;
    dj->fe_timeout_ms = 50;
    dj->quick_stop_option = 6;
    dj->write_home_method = dj->write_home_offset = true;
    dj->home_method = 37;
    dj->home_offset_counts = -5000;
    dj->read_limits = true;
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    const ls_co_step_t *s = g_d.script[2];
    const size_t n = script_len(2);
    assert_true(find_write(s, n, 0, 0x6065, 0, 2000) >= 0);
    assert_true(find_write(s, n, 0, 0x6066, 0, 50) >= 0);
    assert_true(find_write(s, n, 0, 0x605A, 0, 6) >= 0);
    assert_true(find_write(s, n, 0, 0x6098, 0, 37) >= 0);
    assert_true(find_write(s, n, 0, 0x607C, 0, (uint32_t)(int32_t)-5000) >= 0);
    const ls_co_step_t *lo = find_step(s, n, LS_CO_STEP_READ_INTO, 0x607D, 1);
    const ls_co_step_t *hi = find_step(s, n, LS_CO_STEP_READ_INTO, 0x607D, 2);
    assert_non_null(lo);
    assert_non_null(hi);
    /* written before CSP is set: the drive is at rest, nothing maps them */
    assert_true(find_write(s, n, 0, 0x6065, 0, 2000) < find_write(s, n, 0, 0x6060, 0, 8));
    /* and nothing of it where it was not asked */
    const ls_co_step_t *s0 = g_d.script[0];
    for (size_t i = 0; i < script_len(0); i++) {
        const uint16_t x = s0[i].index;
        assert_true(x != 0x6065 && x != 0x6066 && x != 0x605A && x != 0x6098 && x != 0x607C && x != 0x607D);
    }
}

/* Every object the configuration may ask for, on a drive that offers them
 * all: the script still fits LS_DRIVES_SCRIPT_MAX. */
static void test_the_longest_configuration_fits_its_script(void **state)
{
    (void)state;
    ls_drives_config_t c = config();
    for (int j = 0; j < 6; j++) {
        ls_drive_joint_t *dj = &c.joint[j];
        dj->has_revision = true;
        dj->map_mode = dj->can_home = dj->read_limits = true;
        dj->write_fe_window = dj->write_fe_timeout = dj->write_quick_stop = true;
        dj->write_home_method = dj->write_home_offset = true;
        dj->tpdo_room[0] = dj->tpdo_room[1] = 8;
        /* one-byte readouts: the most mapping entries two TPDOs can hold */
        dj->brake = (ls_drive_obj_t){ .map = true, .index = 0x2100, .sub = 1, .bytes = 1 };
        dj->sto = (ls_drive_obj_t){ .map = true, .index = 0x2100, .sub = 2, .bytes = 1 };
        dj->temperature = (ls_drive_obj_t){ .map = true, .index = 0x2100, .sub = 3, .bytes = 1 };
        dj->torque = (ls_drive_obj_t){ .map = true, .index = 0x6077, .bytes = 2 };
        dj->velocity = (ls_drive_obj_t){ .map = true, .index = 0x606C, .bytes = 4 };
    }
    assert_int_equal(ls_drives_init(&g_d, &c), LS_OK);
    assert_int_equal(script_len(0), 61);         /* LS_DRIVES_SCRIPT_MAX's margin: ls_drives.h */
    assert_int_equal(g_d.layout[0].left_out, 0); /* 8 + 8 bytes: everything placed */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_pdo_is_remapped_in_the_order_cia_301_asks),
        cmocka_unit_test(test_every_power_on_pdo_goes_off_before_any_mapping),
        cmocka_unit_test(test_heartbeats_abort_option_interpolation_and_csp),
        cmocka_unit_test(test_only_what_the_eds_allows_is_written),
        cmocka_unit_test(test_interpolation_periods_in_ms_and_below),
        cmocka_unit_test(test_a_bad_configuration_is_named),
        cmocka_unit_test(test_the_mode_rides_in_the_pdos_where_the_eds_lets_it),
        cmocka_unit_test(test_the_readouts_fill_tpdo1_then_tpdo2_in_their_order),
        cmocka_unit_test(test_the_drives_own_supervision_and_homing_are_set_at_start),
        cmocka_unit_test(test_the_longest_configuration_fits_its_script),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
