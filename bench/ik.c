/* Benchmark 13: the cost of one inverse kinematics call per IK class, for
 * callgrind. `bench_ik CASE MODEL N`: set-up (load MODEL, "-" for the
 * compiled-in ls-sim6, and 256 random poses from FK of joint vectors inside
 * the limits), then N calls of CASE cycling through the poses:
 *   fk          ls_kin_fk of the generating joints (the reference)
 *   ik_all      ls_kin_ik_all: every branch
 *   ik_nearest  ls_kin_ik_nearest, seeded 0.01 rad from the generating joints
 * Instructions per call = (total of an N-call run - total of N = 0) / N.
 * Prints the branches found (a checksum that keeps the calls alive). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_robot_model_file.h"

#define N_POSES 256

static uint64_t g_rng = 0x9E3779B97F4A7C15ull;

static double uniform(double lo, double hi)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return lo + (hi - lo) * (double)(g_rng >> 11) * (1.0 / 9007199254740992.0);
}

int main(int argc, char **argv)
{
    if (argc != 4 ||
        (strcmp(argv[1], "fk") != 0 && strcmp(argv[1], "ik_all") != 0 && strcmp(argv[1], "ik_nearest") != 0)) {
        fprintf(stderr, "usage: bench_ik fk|ik_all|ik_nearest MODEL_FILE|- N\n");
        return 2;
    }
    static ls_robot_model_t m;
    m = ls_robot_model_default;
    char msg[512];
    if (strcmp(argv[2], "-") != 0 && ls_robot_model_load(argv[2], &m, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "bench_ik: %s\n", msg);
        return 2;
    }
    const long n = strtol(argv[3], NULL, 10);
    static double q[N_POSES][LS_N_JOINTS], seed[N_POSES][LS_N_JOINTS], T[N_POSES][16];
    for (int p = 0; p < N_POSES; p++) {
        for (int j = 0; j < LS_N_JOINTS; j++) {
            q[p][j] = uniform(m.q_min_rad[j] + 0.05, m.q_max_rad[j] - 0.05);
            seed[p][j] = q[p][j] + 0.01;
        }
        if (ls_kin_fk(&m, q[p], T[p]) != LS_OK) {
            return 1;
        }
    }
    long found = 0;
    double out[LS_KIN_MAX_BRANCHES][LS_N_JOINTS], F[16];
    for (long i = 0; i < n; i++) {
        const int p = (int)(i % N_POSES);
        int k = 0;
        if (argv[1][0] == 'f') {
            k = ls_kin_fk(&m, q[p], F) == LS_OK;
        } else if (strcmp(argv[1], "ik_all") == 0) {
            (void)ls_kin_ik_all(&m, T[p], out, &k);
        } else {
            k = ls_kin_ik_nearest(&m, T[p], seed[p], out[0]) == LS_OK;
        }
        found += k;
    }
    printf("%s %s %s: %ld calls, %ld solutions\n", argv[1], m.name, ls_ik_class_name(m.ik_class), n, found);
    return 0;
}
