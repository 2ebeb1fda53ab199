/* Shared helpers of the motion tests: run the executor with an ideal arm
 * (q_meas = the last set-point) and collect its events. */
#ifndef MOTION_TEST_UTIL_H
#define MOTION_TEST_UTIL_H

#include "ls_motion.h"

#define DT_S 1e-3
#define MAX_LOG 64

typedef struct {
    ls_motion_event_t ev[MAX_LOG];
    int n;
} ev_log_t;

/* One cycle; events are appended to log (may be NULL). */
void mt_step(ls_motion_t *m, double q[LS_N_JOINTS], double qd[LS_N_JOINTS], ev_log_t *log);
/* Step until an event of `kind` or max_cycles; returns the cycle count
 * including the one that produced it, or -1. */
long mt_run_until(ls_motion_t *m, ls_motion_event_kind_t kind, long max_cycles, ev_log_t *log);
/* A reachable start: q = (0, 0.3, 0.3, 0, 0.9, 0). */
extern const double mt_q_home[LS_N_JOINTS];
void mt_tool(double T[16]); /* 0.1 m along the flange z, turned 10 degrees about x */
void mt_limits(ls_motion_cart_limits_t *lim);

#endif
