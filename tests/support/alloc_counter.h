/* A heap-allocation counter for the "never allocates" proofs of the unit
 * tests. An executable made with ls_add_noalloc_test (tests/CMakeLists.txt)
 * is linked with --wrap for every allocator entry point, C and C++ (malloc,
 * calloc, realloc, free, aligned_alloc, posix_memalign, operator new and
 * new[] with and without alignment, __cxa_allocate_exception), so each call
 * made from the test or the libraries of its link lands in this counter
 * while it is armed. */
#ifndef LS_TEST_ALLOC_COUNTER_H
#define LS_TEST_ALLOC_COUNTER_H

/* Zero the count (and stop counting). */
void alloc_counter_reset(void);
/* Count the allocator calls from here on... */
void alloc_counter_arm(void);
/* ...until here (the count is kept). */
void alloc_counter_disarm(void);
/* Allocator calls seen while armed since the last reset. */
long alloc_counter_count(void);
/* A CMocka test that the counter sees a malloc: every proof runs it first,
 * so a broken --wrap cannot pass as "no allocation". */
void alloc_counter_test_sees_malloc(void **state);

#endif
