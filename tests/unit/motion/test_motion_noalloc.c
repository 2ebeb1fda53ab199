/* ls_motion_step never allocates: every allocator of this link is wrapped
 * (see CMakeLists.txt) and counted while the executor runs joint moves,
 * lines, arcs and a blended path with stop, resume and auxiliary waits. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_motion.h"
#include "motion_test_util.h"

static int g_counting;
static long g_allocs;

void *__real_malloc(size_t n);
void *__real_calloc(size_t k, size_t n);
void *__real_realloc(void *p, size_t n);
void *__real__Znwm(size_t n);
void *__real__Znam(size_t n);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t k, size_t n);
void *__wrap_realloc(void *p, size_t n);
void *__wrap__Znwm(size_t n);
void *__wrap__Znam(size_t n);

void *__wrap_malloc(size_t n)
{
    g_allocs += g_counting;
    return __real_malloc(n);
}
void *__wrap_calloc(size_t k, size_t n)
{
    g_allocs += g_counting;
    return __real_calloc(k, n);
}
void *__wrap_realloc(void *p, size_t n)
{
    g_allocs += g_counting;
    return __real_realloc(p, n);
}
void *__wrap__Znwm(size_t n)
{
    g_allocs += g_counting;
    return __real__Znwm(n);
}
void *__wrap__Znam(size_t n)
{
    g_allocs += g_counting;
    return __real__Znam(n);
}

static ls_motion_t g_m;
static ls_motion_plan_t g_plan;
static ls_motion_program_t g_prog;

/* Run the plan to its end, stopping and resuming once, answering aux waits;
 * only the executor calls are counted. Returns the number of DONE events. */
static int run_counted(const ls_motion_plan_t *p, long stop_at)
{
    ls_motion_init(&g_m, &ls_robot_model_default);
    ls_motion_hold(&g_m, p->kind == LS_PLAN_PATH ? p->prog->seg[0].q0 : p->one.q0);
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    int done = 0;
    g_counting = 1;
    assert_int_equal(ls_motion_start(&g_m, p), 0);
    for (long k = 0; k < 200000 && done == 0; k++) {
        ls_motion_events_t ev = { .n = 0 };
        ls_motion_step(&g_m, DT_S, g_m.q_cmd, q, qd, &ev);
        if (k == stop_at) {
            ls_motion_stop(&g_m);
        }
        for (int i = 0; i < ev.n; i++) {
            if (ev.ev[i].kind == LS_MEV_PAUSED) {
                assert_int_equal(ls_motion_resume(&g_m), 0);
            } else if (ev.ev[i].kind == LS_MEV_AUX) {
                ls_motion_aux_done(&g_m);
            } else if (ev.ev[i].kind == LS_MEV_DONE) {
                done++;
            }
        }
    }
    g_counting = 0;
    return done;
}

static void test_step_never_allocates(void **state)
{
    (void)state;
    char why[160];
    double q1[LS_N_JOINTS], tool[16], F[16], P0[16], Pv[16], P1[16];
    memcpy(q1, mt_q_home, sizeof q1);
    q1[0] += 0.7;
    q1[5] -= 1.0;
    assert_int_equal(ls_motion_plan_joint(&g_plan, &ls_robot_model_default, mt_q_home, q1, 1, 1, why, sizeof why), 0);
    assert_int_equal(run_counted(&g_plan, 200), 1);

    mt_tool(tool);
    ls_kin_fk(&ls_robot_model_default, mt_q_home, F);
    ls_pose_mul(F, tool, P0);
    memcpy(Pv, P0, sizeof Pv);
    memcpy(P1, P0, sizeof P1);
    Pv[12] += 0.1, Pv[13] += 0.1;
    P1[13] += 0.2;
    ls_motion_cart_limits_t lim;
    mt_limits(&lim);
    assert_int_equal(ls_motion_plan_line(&g_plan, &ls_robot_model_default, mt_q_home, tool, P1, &lim, why, sizeof why),
                     0);
    assert_int_equal(run_counted(&g_plan, 300), 1);
    assert_int_equal(
        ls_motion_plan_arc(&g_plan, &ls_robot_model_default, mt_q_home, tool, Pv, P1, &lim, why, sizeof why), 0);
    assert_int_equal(run_counted(&g_plan, 300), 1);

    /* A blended path of two points, two cycles, with an auxiliary command. */
    memset(&g_prog, 0, sizeof g_prog);
    assert_int_equal(ls_motion_seg_joint(&g_prog.seg[0], &ls_robot_model_default, mt_q_home, q1, 1, 1, why, sizeof why),
                     0);
    assert_int_equal(ls_motion_seg_joint(&g_prog.seg[1], &ls_robot_model_default, q1, mt_q_home, 1, 1, why, sizeof why),
                     0);
    assert_int_equal(ls_motion_seg_joint(&g_prog.seg[2], &ls_robot_model_default, mt_q_home, q1, 1, 1, why, sizeof why),
                     0);
    g_prog.n = 2;
    g_prog.seg[1].n_aux = 1;
    memcpy(g_prog.seg[1].aux[0], "event x", 8);
    ls_motion_seg_blend(&g_prog.seg[0], &g_prog.seg[1], 1.0);
    ls_motion_seg_blend(&g_prog.seg[2], &g_prog.seg[1], 1.0);
    assert_int_equal(ls_motion_plan_path(&g_plan, &g_prog, 2, false, "p"), 0);
    assert_int_equal(run_counted(&g_plan, 400), 1);

    assert_int_equal(g_allocs, 0);
    /* The counter works: an allocation while counting is seen. */
    void *(*volatile alloc)(size_t) = malloc;
    g_counting = 1;
    void *p = alloc(16);
    g_counting = 0;
    free(p);
    assert_int_equal(g_allocs, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step_never_allocates),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
