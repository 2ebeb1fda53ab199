/* common/ls_canopen.c: what the table functions derive from an EMCY code,
 * checked against CiA 301's tables written out here. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "ls_canopen.h"

static void test_the_error_register_bits_follow_the_emcy_code_class(void **state)
{
    (void)state;
    static const struct {
        uint16_t code;
        uint8_t bits;
    } cases[] = {
        { 0x0000, 0x00 },        /* no error: nothing set */
        { 0x1000, 0x01 },        /* generic error */
        { 0x2310, 0x01 | 0x02 }, /* current */
        { 0x3210, 0x01 | 0x04 }, /* voltage */
        { 0x4210, 0x01 | 0x08 }, /* temperature */
        { 0x5410, 0x01 },        /* device hardware: generic only */
        { 0x8130, 0x01 | 0x10 }, /* heartbeat: communication */
        { 0x8210, 0x01 | 0x10 }, /* protocol error (PDO length): communication */
        { 0x8611, 0x01 | 0x20 }, /* following error: device profile */
        { 0xF001, 0x01 },        /* additional functions */
        { 0xFF42, 0x01 | 0x80 }, /* device specific: manufacturer */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        if (ls_co_error_register_bits(cases[i].code) != cases[i].bits) {
            fail_msg("EMCY 0x%04X: bits 0x%02X, expected 0x%02X", cases[i].code,
                     ls_co_error_register_bits(cases[i].code), cases[i].bits);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_error_register_bits_follow_the_emcy_code_class),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
