#include "motion_test_util.h"

#include <string.h>

#include "ls_kin.h"

const double mt_q_home[LS_N_JOINTS] = { 0.0, 0.3, 0.3, 0.0, 0.9, 0.0 };

void mt_step(ls_motion_t *m, double q[LS_N_JOINTS], double qd[LS_N_JOINTS], ev_log_t *log)
{
    ls_motion_events_t ev;
    ev.n = 0;
    double q_meas[LS_N_JOINTS];
    memcpy(q_meas, m->q_cmd, sizeof q_meas);
    ls_motion_step(m, DT_S, q_meas, q, qd, &ev);
    for (int i = 0; i < ev.n && log != NULL && log->n < MAX_LOG; i++) {
        log->ev[log->n++] = ev.ev[i];
    }
}

long mt_run_until(ls_motion_t *m, ls_motion_event_kind_t kind, long max_cycles, ev_log_t *log)
{
    double q[LS_N_JOINTS], qd[LS_N_JOINTS];
    for (long k = 1; k <= max_cycles; k++) {
        int before = log->n;
        mt_step(m, q, qd, log);
        for (int i = before; i < log->n; i++) {
            if (log->ev[i].kind == kind) {
                return k;
            }
        }
    }
    return -1;
}

void mt_tool(double T[16])
{
    const double x[6] = { 0.0, 0.0, 0.1, 0.1745329251994330, 0.0, 0.0 };
    ls_pose_from_xyzrpy(x, T);
}

void mt_limits(ls_motion_cart_limits_t *lim)
{
    *lim = (ls_motion_cart_limits_t){ .v_lin_m_s = 0.25,
                                      .a_lin_m_s2 = 1.0,
                                      .j_lin_m_s3 = 10.0,
                                      .v_ang_rad_s = 1.0,
                                      .a_ang_rad_s2 = 4.0,
                                      .j_ang_rad_s3 = 40.0,
                                      .joint_speed_frac = 1.0 };
}
