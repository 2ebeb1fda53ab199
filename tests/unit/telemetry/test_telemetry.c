/* TOOL_POS / TOOL_RPY: a value outside its DBC range is sent as the nearest
 * end of the range with its tool_saturated bit, never wrapped (docs/reliability.md section 8: a 4 m
 * tool offset sent 45100 into a 16-bit field). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "ls_telemetry.h"

static void test_in_range_values_pass_unflagged(void **state)
{
    (void)state;
    const double v[6] = { 0.5, -0.25, 1.2, 3.14, -1.5, 0.0 };
    struct landscape_tool_pos_t p;
    struct landscape_tool_rpy_t r;
    assert_int_equal(ls_telemetry_tool(v, 1234, &p, &r), 0);
    assert_int_equal(r.tool_saturated, 0);
    assert_int_equal(p.tool_time_ms, 1234);
    assert_true(fabs(landscape_tool_pos_tool_x_decode(p.tool_x) - 0.5) < 1e-4);
    assert_true(fabs(landscape_tool_pos_tool_y_decode(p.tool_y) + 0.25) < 1e-4);
    assert_true(fabs(landscape_tool_pos_tool_z_decode(p.tool_z) - 1.2) < 1e-4);
    assert_true(fabs(landscape_tool_rpy_tool_roll_decode(r.tool_roll) - 3.14) < 1e-4);
    /* the ends of the range are in it */
    const double ends[6] = { 3.2767, -3.2768, 0.0, 0.0, 0.0, 0.0 };
    assert_int_equal(ls_telemetry_tool(ends, 0, &p, &r), 0);
    assert_true(p.tool_x >= INT16_MAX - 1); /* the generated encoder truncates 32766.99... */
    assert_true(p.tool_y <= INT16_MIN + 1);
}

static void test_out_of_range_values_saturate_and_flag(void **state)
{
    (void)state;
    /* 4.51 m would be raw 45100: beyond int16 */
    const double v[6] = { 4.51, -1e308, 0.3, NAN, INFINITY, -4.0 };
    struct landscape_tool_pos_t p;
    struct landscape_tool_rpy_t r;
    const uint8_t f = ls_telemetry_tool(v, 7, &p, &r);
    assert_int_equal(f, 0x01 | 0x02 | 0x08 | 0x10 | 0x20);
    assert_int_equal(r.tool_saturated, f);
    assert_int_equal(p.tool_x, INT16_MAX);
    assert_int_equal(p.tool_y, INT16_MIN);
    assert_true(fabs(landscape_tool_pos_tool_z_decode(p.tool_z) - 0.3) < 1e-4);
    assert_int_equal(r.tool_roll, INT16_MIN); /* NaN: the low end, flagged */
    assert_int_equal(r.tool_pitch, INT16_MAX);
    assert_int_equal(r.tool_yaw, INT16_MIN);
    /* the flag travels in the frame */
    uint8_t d[8];
    assert_int_equal(landscape_tool_rpy_pack(d, &r, sizeof d), 8);
    struct landscape_tool_rpy_t back;
    assert_int_equal(landscape_tool_rpy_unpack(&back, d, sizeof d), 0);
    assert_int_equal(back.tool_saturated, f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_in_range_values_pass_unflagged),
        cmocka_unit_test(test_out_of_range_values_saturate_and_flag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
