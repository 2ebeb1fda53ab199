/* See alloc_counter.h. The __real_* symbols are the allocators' own entry
 * points, which --wrap renames. */
#include "alloc_counter.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

/* volatile: the compiler knows malloc reads no user globals and could move
 * or drop the stores around a call to it. */
static volatile int g_armed;
static volatile long g_allocs;

void alloc_counter_reset(void)
{
    g_armed = 0;
    g_allocs = 0;
}
void alloc_counter_arm(void)
{
    g_armed = 1;
}
void alloc_counter_disarm(void)
{
    g_armed = 0;
}
long alloc_counter_count(void)
{
    return g_allocs;
}

static void count(void)
{
    if (g_armed) {
        ++g_allocs;
    }
}

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__real_aligned_alloc(size_t align, size_t n);
int __real_posix_memalign(void **p, size_t align, size_t n);
void *__real__Znwm(size_t n);
void *__real__Znam(size_t n);
void *__real__ZnwmSt11align_val_t(size_t n, size_t align);
void *__real__ZnamSt11align_val_t(size_t n, size_t align);
void *__real___cxa_allocate_exception(size_t n);

void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);
void *__wrap_aligned_alloc(size_t align, size_t n);
int __wrap_posix_memalign(void **p, size_t align, size_t n);
void *__wrap__Znwm(size_t n);
void *__wrap__Znam(size_t n);
void *__wrap__ZnwmSt11align_val_t(size_t n, size_t align);
void *__wrap__ZnamSt11align_val_t(size_t n, size_t align);
void *__wrap___cxa_allocate_exception(size_t n);

void *__wrap_malloc(size_t n)
{
    count();
    return __real_malloc(n);
}
void *__wrap_calloc(size_t n, size_t size)
{
    count();
    return __real_calloc(n, size);
}
void *__wrap_realloc(void *p, size_t n)
{
    count();
    return __real_realloc(p, n);
}
void __wrap_free(void *p)
{
    count();
    __real_free(p);
}
void *__wrap_aligned_alloc(size_t align, size_t n)
{
    count();
    return __real_aligned_alloc(align, n);
}
int __wrap_posix_memalign(void **p, size_t align, size_t n)
{
    count();
    return __real_posix_memalign(p, align, n);
}
void *__wrap__Znwm(size_t n)
{
    count();
    return __real__Znwm(n);
}
void *__wrap__Znam(size_t n)
{
    count();
    return __real__Znam(n);
}
void *__wrap__ZnwmSt11align_val_t(size_t n, size_t align)
{
    count();
    return __real__ZnwmSt11align_val_t(n, align);
}
void *__wrap__ZnamSt11align_val_t(size_t n, size_t align)
{
    count();
    return __real__ZnamSt11align_val_t(n, align);
}
void *__wrap___cxa_allocate_exception(size_t n)
{
    count();
    return __real___cxa_allocate_exception(n);
}

static void *volatile g_sink;

void alloc_counter_test_sees_malloc(void **state)
{
    (void)state;
    alloc_counter_reset();
    alloc_counter_arm();
    g_sink = malloc(32);
    alloc_counter_disarm();
    free(g_sink);
    assert_int_equal(alloc_counter_count(), 1);
}
