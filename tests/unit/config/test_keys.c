/* ls_keys: the supervisors' key file (docs/deploy.md "Signed supervisors"):
 * read into ls_auth_t only when only its owner may read it, every bad line
 * named by file and line, and no message carrying any of a key's digits. */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ls_keys.h"
#include "test_config.h"

#define KEY_HEX "00112233445566778899aabbccddeeff00112233445566778899AABBCCDDEEFF"

static int load(const char *text, mode_t mode, ls_auth_t *auth, char *msg, size_t msglen)
{
    char path[64];
    tc_write_file(path, sizeof path, text);
    assert_int_equal(chmod(path, mode), 0);
    ls_auth_init(auth, ls_AuthPolicy_AUTH_SIGNED, false);
    msg[0] = '\0';
    const int r = ls_keys_load(path, auth, msg, msglen);
    unlink(path);
    return r;
}

static void test_a_key_file_of_its_owner_loads_every_key(void **state)
{
    (void)state;
    ls_auth_t auth;
    char msg[256];
    assert_int_equal(
        load("# ops keys\nops = " KEY_HEX "\n\n; bench\nbench=" KEY_HEX "\n", 0600, &auth, msg, sizeof msg), LS_OK);
    assert_int_equal(auth.n_keys, 2);
    assert_int_equal(ls_auth_key_index(&auth, "bench"), 1);
    assert_int_equal(auth.keys[0].key[0], 0x00);
    assert_int_equal(auth.keys[0].key[31], 0xFF); /* upper-case digits too */
    ls_auth_wipe(&auth, sizeof auth);
}

static void test_a_key_file_others_may_read_is_refused_naming_the_chmod(void **state)
{
    (void)state;
    ls_auth_t auth;
    char msg[256];
    assert_int_equal(load("ops = " KEY_HEX "\n", 0640, &auth, msg, sizeof msg), LS_EPERM);
    assert_non_null(strstr(msg, "chmod 600"));
    assert_int_equal(auth.n_keys, 0);
}

static void test_bad_lines_are_named_without_their_digits(void **state)
{
    (void)state;
    ls_auth_t auth;
    char msg[256];
    /* one digit short, and not hex: the line and the name, never the value */
    assert_int_equal(
        load("ops = 00112233445566778899aabbccddeeff00112233445566778899aabbccddeef\n", 0600, &auth, msg, sizeof msg),
        LS_EINVAL);
    assert_non_null(strstr(msg, ":1: key \"ops\": expected 64 hex digits (32 random bytes), got 63 characters"));
    assert_null(strstr(msg, "00112233"));
    assert_int_equal(load("a = " KEY_HEX "\nops = zz112233445566778899aabbccddeeff00112233445566778899aabbccddeeff\n",
                          0600, &auth, msg, sizeof msg),
                     LS_EINVAL);
    assert_non_null(strstr(msg, ":2: key \"ops\": expected 64 hex digits"));
    assert_null(strstr(msg, "zz11"));
    ls_auth_wipe(&auth, sizeof auth);
    assert_int_equal(load("ops " KEY_HEX "\n", 0600, &auth, msg, sizeof msg), LS_EINVAL);
    assert_null(strstr(msg, "00112233"));
    assert_int_equal(load("ops = " KEY_HEX "\nops = " KEY_HEX "\n", 0600, &auth, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, ":2: key \"ops\" is given twice"));
    ls_auth_wipe(&auth, sizeof auth);
    assert_int_equal(load("# nothing\n", 0600, &auth, msg, sizeof msg), LS_EINVAL);
    assert_non_null(strstr(msg, "holds no key"));
}

int tc_run_keys_tests(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_key_file_of_its_owner_loads_every_key),
        cmocka_unit_test(test_a_key_file_others_may_read_is_refused_naming_the_chmod),
        cmocka_unit_test(test_bad_lines_are_named_without_their_digits),
    };
    return cmocka_run_group_tests_name("keys", tests, NULL, NULL);
}
