/* ls_ini_next_line: lines counted, a byte order mark and leading blanks
 * dropped, a NUL byte and an over-long line refused with their words. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "ls_ini_line.h"

static FILE *text(const char *s, size_t n)
{
    FILE *f = fmemopen((void *)s, n, "r");
    assert_non_null(f);
    return f;
}

static void lines_are_counted_and_leading_blanks_dropped(void **state)
{
    (void)state;
    static const char s[] = "\xEF\xBB\xBF  [robot]\n\tname = x\n\nlast";
    FILE *f = text(s, sizeof s - 1);
    char buf[64], why[64];
    int line = 0;
    assert_string_equal(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why), "[robot]\n");
    assert_string_equal(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why), "name = x\n");
    assert_string_equal(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why), "\n");
    assert_string_equal(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why), "last");
    assert_int_equal(line, 4);
    assert_null(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why));
    assert_string_equal(why, "");
    fclose(f);
}

static void a_nul_byte_and_an_over_long_line_are_refused(void **state)
{
    (void)state;
    static const char nul[] = "a = 1\nb = \0 2\nc = 3\n";
    FILE *f = text(nul, sizeof nul - 1);
    char buf[16], why[64];
    int line = 0;
    assert_non_null(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why));
    assert_null(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why));
    assert_int_equal(line, 2);
    assert_string_equal(why, "a NUL byte in the line: this is not a text file");
    fclose(f);
    static const char longer[] = "key = a value longer than the buffer\nnext\n";
    f = text(longer, sizeof longer - 1);
    line = 0;
    assert_null(ls_ini_next_line(buf, sizeof buf, f, &line, why, sizeof why));
    assert_int_equal(line, 1);
    assert_string_equal(why, "line longer than 13 characters");
    fclose(f);
}

/* Blanks go from both ends, in place; a blank line becomes empty. */
static void test_trim_cuts_the_blanks_at_both_ends(void **state)
{
    (void)state;
    char a[] = " \t key = value \r\n";
    assert_string_equal(ls_ini_trim(a), "key = value");
    char b[] = " \t\n";
    assert_string_equal(ls_ini_trim(b), "");
    char c[] = "x";
    assert_ptr_equal(ls_ini_trim(c), c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trim_cuts_the_blanks_at_both_ends),
        cmocka_unit_test(lines_are_counted_and_leading_blanks_dropped),
        cmocka_unit_test(a_nul_byte_and_an_over_long_line_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
