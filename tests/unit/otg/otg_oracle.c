/* otg_oracle: ls_otg_plan_position on a batch of state-to-state problems,
 * for the comparison with ruckig (PyPI): tests/unit/otg/test_otg_oracle.py
 * (CI, 1,000 problems) and bench/b_otg.py (bench 10, 10,000; built there as
 * bench_otg).
 *
 * stdin: one problem per line: n, then p0[n] v0[n] a0[n] (current state),
 * p1[n] v1[n] a1[n] (target), v_max[n] a_max[n] j_max[n]; the generator is
 * bench/otg_problems.py. All problems are read first, then each is planned
 * REPEAT times in a row, timed with CLOCK_MONOTONIC around the repeats (the
 * clock's cost amortised; each plan includes the input checks and the copy
 * of the trajectory into the caller's ls_otg_t), then sampled every 1 ms
 * and at T.
 * stdout, one line per problem:
 *   OK <duration_s> <ns per plan> <max |v|/v_max> <max |a|/a_max>
 *      <max |j|/j_max> <max |state(T) - target|>
 * or "ERR <status name>". Exit 2 on malformed input. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "ls_otg.h"
#include "plan_io.h"

#define MAX_PROBLEMS 20000
#define REPEAT 20
#define SAMPLE_DT_S 1e-3

typedef struct {
    uint8_t n;
    ls_otg_state_t cur, tgt;
    ls_otg_limits_t lim;
} problem_t;

static problem_t problems[MAX_PROBLEMS];
static ls_otg_planner_t planner;

static double ratio(double x, double lim)
{
    return fabs(x) / lim;
}

int main(void)
{
    size_t count = 0;
    int n;
    while (scanf("%d", &n) == 1) {
        if (n < 1 || n > LS_OTG_MAX_AXES || count >= MAX_PROBLEMS) {
            fprintf(stderr, "otg_oracle: axis count %d out of range 1..%d or more than %d problems\n", n,
                    LS_OTG_MAX_AXES, MAX_PROBLEMS);
            return 2;
        }
        problem_t *p = &problems[count];
        p->n = (uint8_t)n;
        if (read_vec(p->cur.p, n) || read_vec(p->cur.v, n) || read_vec(p->cur.a, n) || read_vec(p->tgt.p, n) ||
            read_vec(p->tgt.v, n) || read_vec(p->tgt.a, n) || read_vec(p->lim.v_max, n) || read_vec(p->lim.a_max, n) ||
            read_vec(p->lim.j_max, n)) {
            fprintf(stderr, "otg_oracle: expected 9 x %d numbers after the axis count\n", n);
            return 2;
        }
        count++;
    }
    if (ls_otg_planner_init(&planner) != LS_OK) {
        return 2;
    }
    for (size_t k = 0; k < count; k++) {
        const problem_t *p = &problems[k];
        static ls_otg_t tr;
        int rc = LS_OK;
        const uint64_t t0 = mono_ns();
        for (int r = 0; r < REPEAT; r++) {
            rc = ls_otg_plan_position(&planner, &tr, p->n, &p->cur, &p->tgt, &p->lim);
            __asm__ volatile("" : : "g"(&tr) : "memory"); /* keep every repeat */
        }
        const uint64_t dt = mono_ns() - t0;
        if (rc != LS_OK) {
            printf("ERR %s\n", ls_err_name(rc));
            continue;
        }
        double vr = 0, ar = 0, jr = 0, end_err = 0;
        double pos[LS_OTG_MAX_AXES], vel[LS_OTG_MAX_AXES], acc[LS_OTG_MAX_AXES], jerk[LS_OTG_MAX_AXES];
        const long steps = (long)ceil(tr.duration_s / SAMPLE_DT_S);
        for (long s = 0; s <= steps; s++) {
            const double t = fmin((double)s * SAMPLE_DT_S, tr.duration_s);
            ls_otg_sample(&tr, t, pos, vel, acc, jerk);
            for (uint8_t i = 0; i < p->n; i++) {
                vr = fmax(vr, ratio(vel[i], p->lim.v_max[i]));
                ar = fmax(ar, ratio(acc[i], p->lim.a_max[i]));
                jr = fmax(jr, ratio(jerk[i], p->lim.j_max[i]));
            }
        }
        ls_otg_sample(&tr, tr.duration_s, pos, vel, acc, jerk);
        for (uint8_t i = 0; i < p->n; i++) {
            end_err = fmax(end_err, fabs(pos[i] - p->tgt.p[i]));
            end_err = fmax(end_err, fabs(vel[i] - p->tgt.v[i]));
            end_err = fmax(end_err, fabs(acc[i] - p->tgt.a[i]));
        }
        printf("OK %.17g %.1f %.17g %.17g %.17g %.17g\n", tr.duration_s, (double)dt / REPEAT, vr, ar, jr, end_err);
    }
    return 0;
}
