/* The seqlock (common/ls_seqlock.h): what a reader gets is always
 * one published value whole, never a mix of two, while a writer publishes
 * as fast as it can on another thread. */
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "ls_seqlock.h"

/* An odd size: the last word is partly used. */
typedef struct {
    uint32_t stamp;
    uint32_t copy[40];
    uint8_t tail[3];
} value_t;

#define WORDS LS_SEQLOCK_WORDS(sizeof(value_t))

static atomic_uint g_seq;
static atomic_uint g_words[WORDS];
static atomic_bool g_stop;

static void fill(value_t *v, uint32_t stamp)
{
    v->stamp = stamp;
    for (size_t i = 0; i < sizeof v->copy / sizeof v->copy[0]; i++) {
        v->copy[i] = stamp;
    }
    memset(v->tail, (int)(stamp & 0xFFu), sizeof v->tail);
}

static void test_a_value_never_published_reads_as_zeros(void **state)
{
    (void)state;
    atomic_uint seq = 0;
    atomic_uint words[WORDS] = { 0 };
    value_t v;
    memset(&v, 0xAB, sizeof v);
    assert_true(ls_seqlock_read(&seq, words, WORDS, &v, sizeof v, 1));
    value_t zero;
    memset(&zero, 0, sizeof zero);
    assert_memory_equal(&v, &zero, sizeof v);
}

static void test_the_reader_gets_what_was_published_last(void **state)
{
    (void)state;
    atomic_uint seq = 0;
    atomic_uint words[WORDS] = { 0 };
    value_t in, out;
    fill(&in, 7);
    ls_seqlock_write(&seq, words, WORDS, &in, sizeof in);
    fill(&in, 8);
    ls_seqlock_write(&seq, words, WORDS, &in, sizeof in);
    assert_true(ls_seqlock_read(&seq, words, WORDS, &out, sizeof out, 1));
    assert_memory_equal(&in, &out, sizeof in);
}

static void test_a_write_in_progress_is_not_taken_for_a_value(void **state)
{
    (void)state;
    atomic_uint seq = 1; /* the writer stopped half-way through a publish */
    atomic_uint words[WORDS] = { 0 };
    value_t out;
    assert_false(ls_seqlock_read(&seq, words, WORDS, &out, sizeof out, 4));
}

static void test_too_few_words_are_refused(void **state)
{
    (void)state;
    atomic_uint seq = 0;
    atomic_uint words[WORDS] = { 0 };
    value_t v;
    fill(&v, 3);
    ls_seqlock_write(&seq, words, WORDS - 1u, &v, sizeof v);
    assert_int_equal(atomic_load(&seq), 0); /* nothing written */
    assert_false(ls_seqlock_read(&seq, words, WORDS - 1u, &v, sizeof v, 1));
}

static void *writer(void *arg)
{
    (void)arg;
    value_t v;
    for (uint32_t stamp = 1; !atomic_load(&g_stop); stamp++) {
        fill(&v, stamp);
        ls_seqlock_write(&g_seq, g_words, WORDS, &v, sizeof v);
    }
    return NULL;
}

static void test_a_reader_racing_a_writer_never_sees_a_torn_value(void **state)
{
    (void)state;
    atomic_store(&g_stop, false);
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, writer, NULL), 0);
    unsigned whole = 0;
    uint32_t last = 0;
    for (int k = 0; k < 200000; k++) {
        value_t v;
        if (!ls_seqlock_read(&g_seq, g_words, WORDS, &v, sizeof v, 16)) {
            continue;
        }
        whole++;
        for (size_t i = 0; i < sizeof v.copy / sizeof v.copy[0]; i++) {
            assert_int_equal(v.copy[i], v.stamp);
        }
        assert_int_equal(v.tail[2], v.stamp & 0xFFu);
        assert_true(v.stamp >= last); /* never an older value after a newer one */
        last = v.stamp;
    }
    atomic_store(&g_stop, true);
    assert_int_equal(pthread_join(t, NULL), 0);
    assert_true(whole > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_value_never_published_reads_as_zeros),
        cmocka_unit_test(test_the_reader_gets_what_was_published_last),
        cmocka_unit_test(test_a_write_in_progress_is_not_taken_for_a_value),
        cmocka_unit_test(test_too_few_words_are_refused),
        cmocka_unit_test(test_a_reader_racing_a_writer_never_sees_a_torn_value),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
