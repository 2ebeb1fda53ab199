/* bench_traj: ls_traj_plan on a batch of problems, for the comparison with
 * ruckig (bench/b_traj.py).
 *
 * stdin: one problem per line: n, p0[n], p1[n], v_max[n], a_max[n], j_max[n]
 * (the format of tests/unit/traj/traj_oracle.c). All problems are read
 * first, then each is planned REPEAT times in a row and timed with
 * CLOCK_MONOTONIC around the repeats (so the clock's cost is amortised).
 * stdout: one line per problem, "OK <duration_s> <ns per plan>" or
 * "ERR <status>". Exit 2 on malformed input. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "ls_traj.h"
#include "plan_io.h"

#define MAX_PROBLEMS 100000
#define REPEAT 20

typedef struct {
    uint8_t n;
    double p0[LS_TRAJ_MAX_AXES], p1[LS_TRAJ_MAX_AXES];
    ls_traj_limits_t lim;
} problem_t;

static problem_t problems[MAX_PROBLEMS];

int main(void)
{
    size_t count = 0;
    int n;
    while (scanf("%d", &n) == 1) {
        if (n < 1 || n > LS_TRAJ_MAX_AXES || count >= MAX_PROBLEMS) {
            fprintf(stderr, "bench_traj: axis count %d out of range 1..%d or more than %d problems\n", n,
                    LS_TRAJ_MAX_AXES, MAX_PROBLEMS);
            return 2;
        }
        problem_t *p = &problems[count];
        p->n = (uint8_t)n;
        if (read_vec(p->p0, n) || read_vec(p->p1, n) || read_vec(p->lim.v_max, n) || read_vec(p->lim.a_max, n) ||
            read_vec(p->lim.j_max, n)) {
            fprintf(stderr, "bench_traj: expected 5 x %d numbers after the axis count\n", n);
            return 2;
        }
        count++;
    }
    for (size_t k = 0; k < count; k++) {
        const problem_t *p = &problems[k];
        ls_traj_t tr;
        int rc = LS_OK;
        const uint64_t t0 = mono_ns();
        for (int r = 0; r < REPEAT; r++) {
            rc |= ls_traj_plan(&tr, p->n, p->p0, p->p1, &p->lim);
            __asm__ volatile("" : : "g"(&tr) : "memory"); /* keep every repeat */
        }
        const uint64_t dt = mono_ns() - t0;
        if (rc != LS_OK) {
            printf("ERR %d\n", rc);
        } else {
            printf("OK %.17g %.1f\n", tr.duration_s, (double)dt / REPEAT);
        }
    }
    return 0;
}
