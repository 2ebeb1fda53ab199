/* Test driver for the ruckig oracle (test_ruckig_oracle.py).
 *
 * stdin: one problem per line: n, p0[n], p1[n], v_max[n], a_max[n], j_max[n].
 * stdout: one line per problem:
 *   OK <duration> <max |v|/v_max> <max |a|/a_max> <max |jerk|/j_max> <sync err> <end err>
 * or "ERR <status>" when planning fails. The ratios are maxima over all axes
 * and over samples at 1 kHz (plus the end point); the jerk is the finite
 * difference of a between consecutive 1 kHz samples, which the mean-value
 * theorem bounds by j_max for a continuous, piecewise linear a. The sync
 * error is max |axis T - duration|, the end error max |p(duration) - p1|.
 * Exit status: 0, or 2 on malformed input. */
#include <math.h>
#include <stdio.h>

#include "ls_traj.h"

#define SAMPLE_DT_S 1e-3

static int read_vec(double *x, int n)
{
    for (int i = 0; i < n; ++i) {
        if (scanf("%lf", &x[i]) != 1) {
            return -1;
        }
    }
    return 0;
}

static double maxd(double a, double b)
{
    return a > b ? a : b;
}

int main(void)
{
    int n;
    while (scanf("%d", &n) == 1) {
        if (n < 1 || n > LS_TRAJ_MAX_AXES) {
            fprintf(stderr, "traj_oracle: axis count %d out of range 1..%d\n", n, LS_TRAJ_MAX_AXES);
            return 2;
        }
        double p0[LS_TRAJ_MAX_AXES], p1[LS_TRAJ_MAX_AXES];
        ls_traj_limits_t lim;
        if (read_vec(p0, n) || read_vec(p1, n) || read_vec(lim.v_max, n) || read_vec(lim.a_max, n) ||
            read_vec(lim.j_max, n)) {
            fprintf(stderr, "traj_oracle: expected 5 x %d numbers after the axis count\n", n);
            return 2;
        }
        ls_traj_t tr;
        const int rc = ls_traj_plan(&tr, (uint8_t)n, p0, p1, &lim);
        if (rc != LS_OK) {
            printf("ERR %d\n", rc);
            continue;
        }
        const double T = tr.duration_s;
        double vr = 0.0, ar = 0.0, jr = 0.0, sync = 0.0, end = 0.0;
        double p[LS_TRAJ_MAX_AXES], v[LS_TRAJ_MAX_AXES], a[LS_TRAJ_MAX_AXES], a_prev[LS_TRAJ_MAX_AXES];
        const long steps = (long)floor(T / SAMPLE_DT_S);
        for (long k = 0; k <= steps + 1; ++k) {
            const int at_end = k == steps + 1;
            const double t = at_end ? T : (double)k * SAMPLE_DT_S;
            ls_traj_sample(&tr, t, p, v, a);
            for (int i = 0; i < n; ++i) {
                vr = maxd(vr, fabs(v[i]) / lim.v_max[i]);
                ar = maxd(ar, fabs(a[i]) / lim.a_max[i]);
                if (k > 0 && !at_end) {
                    jr = maxd(jr, fabs(a[i] - a_prev[i]) / SAMPLE_DT_S / lim.j_max[i]);
                }
                a_prev[i] = a[i];
            }
        }
        for (int i = 0; i < n; ++i) {
            sync = maxd(sync, fabs(tr.axis[i].T - T));
            end = maxd(end, fabs(p[i] - p1[i]));
        }
        printf("OK %.17g %.17g %.17g %.17g %.17g %.17g\n", T, vr, ar, jr, sync, end);
    }
    return 0;
}
