/* The time law of a Cartesian segment under its joints' limits. See
 * ls_pathspeed.h.
 *
 * A ramp from speed v to w that starts and ends at zero acceleration, within
 * acceleration a and jerk j, is symmetric: with dv = |w - v|, jerk phases of
 * t1 = min(a / j, sqrt(dv / j)) and a constant phase of t2 = dv / a_p - t1
 * (a_p = j t1, the peak acceleration). Its velocity is point-symmetric
 * about the middle, so it covers (v + w) / 2 times its duration 2 t1 + t2.
 *
 * Zone k (of m, counted from the one that holds s0) has length L_k, speed
 * u_k where it starts and u_{k+1} where it ends; u_0 = u_m = 0 (rest). Its
 * ramps run at its accelerations for the fastest speed in it, a_up(x) and
 * a_down(x), which fall as x grows. A zone whose entry speed is above its
 * exit speed must be long enough for the ramp down between them (backward
 * pass: lower the entry), one whose exit is above its entry for the ramp up
 * (forward pass: lower the exit); lowering an entry or an exit only
 * shortens the neighbour's ramps. Then each zone cruises at the highest c
 * under its cap whose ramps, at a_up(c) and a_down(c), fit L_k. Each distance grows with the speed it
 * solves for (a higher speed, a lower acceleration), so bisection finds it. */
#include "ls_pathspeed.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define BISECT_STEPS 40
#define S_END_TOL 1e-12  /* the last zone ends at 1 within this */
#define FINISH_GAIN 1e-6 /* a join must save this share of the duration */
#define V_ROUND 1e-9     /* a sampled speed this far below 0 is rounding (at rest) */
#define JOIN_SHARE 0.005 /* a stretch whose cap is this close to its zone's joins it */

static bool pos(double x)
{
    return isfinite(x) && x > 0.0;
}

/* ------------------------------------------------------------------ curve */

int ls_pathspeed_curve_begin(ls_pathspeed_curve_t *c, double v_req, double a_req, double j,
                             const double vel[LS_PATHSPEED_JOINTS], const double acc[LS_PATHSPEED_JOINTS])
{
    if (c == NULL || !pos(v_req) || !pos(a_req) || !pos(j) || vel == NULL || acc == NULL) {
        return LS_EINVAL;
    }
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        if (!pos(vel[i]) || !pos(acc[i])) {
            return LS_EINVAL;
        }
    }
    memset(c, 0, sizeof *c);
    c->v_req = v_req;
    c->a_req = a_req;
    c->j = j;
    memcpy(c->vel, vel, sizeof c->vel);
    memcpy(c->acc, acc, sizeof c->acc);
    return LS_OK;
}

static double zone_start(const ls_pathspeed_curve_t *c, int k)
{
    return k > 0 ? c->zone[k - 1].s_end : 0.0;
}

/* A bound as a float, never below the double. */
static float up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

/* The zone's cap from its bounds: the requested speed, each joint's
 * velocity limit, each joint's curvature share. */
static void set_cap(const ls_pathspeed_curve_t *c, ls_pathspeed_zone_t *z)
{
    z->v_max = c->v_req;
    z->joint = 0;
    z->limit = LS_PATHSPEED_REQUESTED;
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        if (z->b1[i] > 0.0f && c->vel[i] / z->b1[i] < z->v_max) {
            z->v_max = c->vel[i] / z->b1[i];
            z->joint = (uint8_t)i;
            z->limit = LS_PATHSPEED_VELOCITY;
        }
    }
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        const float b2 = fmaxf(z->b2u[i], z->b2d[i]);
        const double v = b2 > 0.0f ? sqrt(LS_PATHSPEED_CURVATURE * c->acc[i] / b2) : INFINITY;
        if (v < z->v_max) {
            z->v_max = v;
            z->joint = (uint8_t)i;
            z->limit = LS_PATHSPEED_ACCELERATION;
        }
    }
}

/* The cruising time that joining zone a (starting at s_a) with the next
 * one, b, at the lower cap adds. */
static double join_cost(const ls_pathspeed_zone_t *a, double s_a, const ls_pathspeed_zone_t *b)
{
    const double la = a->s_end - s_a, lb = b->s_end - a->s_end;
    const double v = fmin(a->v_max, b->v_max);
    return la / v - la / a->v_max + lb / v - lb / b->v_max;
}

/* Zone a takes in the next one, b: the larger bounds (so the lower cap),
 * b's end. */
static void absorb(const ls_pathspeed_curve_t *c, ls_pathspeed_zone_t *a, const ls_pathspeed_zone_t *b)
{
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        a->b1[i] = fmaxf(a->b1[i], b->b1[i]);
        a->b2u[i] = fmaxf(a->b2u[i], b->b2u[i]);
        a->b2d[i] = fmaxf(a->b2d[i], b->b2d[i]);
    }
    a->s_end = b->s_end;
    set_cap(c, a);
}

static void join_next(ls_pathspeed_curve_t *c, int k)
{
    absorb(c, &c->zone[k], &c->zone[k + 1]);
    memmove(&c->zone[k + 1], &c->zone[k + 2], (size_t)(c->n - k - 2) * sizeof c->zone[0]);
    c->n--;
}

int ls_pathspeed_curve_add(ls_pathspeed_curve_t *c, const ls_pathspeed_stretch_t *st)
{
    if (c == NULL || st == NULL || !isfinite(st->s_end) || st->s_end <= zone_start(c, c->n) ||
        st->s_end > 1.0 + S_END_TOL) {
        return LS_EINVAL;
    }
    ls_pathspeed_zone_t z;
    memset(&z, 0, sizeof z);
    z.s_end = fmin(st->s_end, 1.0);
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        const double b[3] = { st->b1[i], st->b2u[i], st->b2d[i] };
        for (int k = 0; k < 3; k++) {
            if (!(isfinite(b[k]) && b[k] >= 0.0)) {
                return LS_EINVAL;
            }
        }
        z.b1[i] = up(st->b1[i]);
        z.b2u[i] = up(st->b2u[i]);
        z.b2d[i] = up(st->b2d[i]);
    }
    set_cap(c, &z);
    if (!pos(z.v_max)) {
        return LS_EINVAL;
    }
    const int last = c->n - 1;
    if (last >= 0 && fabs(c->zone[last].v_max - z.v_max) <= JOIN_SHARE * fmax(c->zone[last].v_max, z.v_max)) {
        absorb(c, &c->zone[last], &z); /* (nearly) the same cap: one zone */
        return LS_OK;
    }
    if (c->n == LS_PATHSPEED_MAX_ZONES) {
        /* Full: join the neighbours that cost the least, the new zone
         * counted as the last one's neighbour. */
        int best = last;
        double cost = join_cost(&c->zone[last], zone_start(c, last), &z);
        for (int k = 0; k < last; k++) {
            const double ck = join_cost(&c->zone[k], zone_start(c, k), &c->zone[k + 1]);
            if (ck < cost) {
                cost = ck;
                best = k;
            }
        }
        if (best == last) {
            absorb(c, &c->zone[last], &z);
            return LS_OK;
        }
        join_next(c, best);
    }
    c->zone[c->n++] = z;
    return LS_OK;
}

double ls_pathspeed_zone_accel(const ls_pathspeed_curve_t *c, int k, double v, bool up_ramp, uint8_t *joint)
{
    double a = c->a_req;
    uint8_t jn = 0;
    const ls_pathspeed_zone_t *z = &c->zone[k];
    for (int i = 0; i < LS_PATHSPEED_JOINTS; i++) {
        if (z->b1[i] > 0.0f) {
            const double b2 = (double)(up_ramp ? z->b2u[i] : z->b2d[i]);
            const double ai = (c->acc[i] - b2 * v * v) / (double)z->b1[i];
            if (ai < a) {
                a = ai;
                jn = (uint8_t)i;
            }
        }
    }
    if (joint != NULL) {
        *joint = jn;
    }
    return a;
}

int ls_pathspeed_zone_of(const ls_pathspeed_curve_t *c, double s)
{
    if (c == NULL || c->n == 0) {
        return LS_PATHSPEED_NO_ZONE;
    }
    int k = 0;
    while (k + 1 < c->n && s >= c->zone[k].s_end) {
        k++;
    }
    return k;
}

/* ------------------------------------------------------------------ ramps */

/* Jerk phase t1 and constant phase t2 of a ramp changing speed by dv >= 0. */
static void ramp_shape(double dv, double a, double j, double *t1, double *t2)
{
    if (!(dv > 0.0)) {
        *t1 = *t2 = 0.0;
    } else if (dv * j >= a * a) {
        *t1 = a / j;
        *t2 = fmax(0.0, dv / a - *t1);
    } else {
        *t1 = sqrt(dv / j);
        *t2 = 0.0;
    }
}

static double ramp_time(double v, double w, double a, double j)
{
    double t1, t2;
    ramp_shape(fabs(w - v), a, j, &t1, &t2);
    return 2.0 * t1 + t2;
}

static double ramp_dist(double v, double w, double a, double j)
{
    return 0.5 * (v + w) * ramp_time(v, w, a, j);
}

/* Position (from the ramp's start), velocity and acceleration at tau of the
 * ramp from v to w; the last jerk phase counted back from the end. */
static void ramp_at(double v, double w, double a, double j, double tau, double *p, double *vel, double *acc)
{
    const double sg = w >= v ? 1.0 : -1.0;
    double t1, t2;
    ramp_shape(fabs(w - v), a, j, &t1, &t2);
    const double T = 2.0 * t1 + t2;
    if (tau <= t1) {
        *acc = sg * j * tau;
        *vel = v + sg * j * tau * tau / 2.0;
        *p = tau * (v + sg * j * tau * tau / 6.0);
    } else if (tau <= t1 + t2) {
        const double ap = j * t1, tt = tau - t1;
        const double v1 = v + sg * ap * t1 / 2.0;
        *acc = sg * ap;
        *vel = v1 + sg * ap * tt;
        *p = t1 * (v + sg * ap * t1 / 6.0) + tt * (v1 + sg * ap * tt / 2.0);
    } else {
        const double tr = fmax(0.0, T - tau);
        *acc = sg * j * tr;
        *vel = w - sg * j * tr * tr / 2.0;
        *p = 0.5 * (v + w) * T - tr * (w - sg * j * tr * tr / 6.0);
    }
}

/* What zone k's ramps need: up from u to c and down from c to w, at the
 * zone's accelerations for c, the fastest of the three. */
typedef struct {
    const ls_pathspeed_curve_t *c;
    int k;
    double j;
} zone_ctx_t;

static double zone_need(const zone_ctx_t *z, double u, double c, double w)
{
    const double a_up = u < c ? ls_pathspeed_zone_accel(z->c, z->k, c, true, NULL) : 1.0;
    const double a_dn = w < c ? ls_pathspeed_zone_accel(z->c, z->k, c, false, NULL) : 1.0;
    return ramp_dist(u, c, a_up, z->j) + ramp_dist(c, w, a_dn, z->j);
}

/* The largest x in [lo, hi] with need(x) <= L, need growing in x and
 * need(lo) <= L: bisection, BISECT_STEPS steps (lo is kept feasible).
 * which: 0 the entry (x down to o), 1 the exit (o up to x), 2 the cruise
 * (u = o up to x, down to w). */
static double largest(const zone_ctx_t *z, int which, double lo, double hi, double o, double w, double L)
{
    for (int i = 0; i <= BISECT_STEPS; i++) {
        const double x = i == 0 ? hi : 0.5 * (lo + hi);
        const double need = which == 0   ? zone_need(z, x, x, o)
                            : which == 1 ? zone_need(z, o, x, x)
                                         : zone_need(z, o, x, w);
        if (need <= L) {
            if (i == 0) {
                return hi;
            }
            lo = x;
        } else {
            hi = x;
        }
    }
    return lo;
}

/* ---------------------------------------------------------------- planner */

static bool curve_ok(const ls_pathspeed_curve_t *c)
{
    if (c->n < 1 || c->n > LS_PATHSPEED_MAX_ZONES || !pos(c->a_req) || !pos(c->j) || !pos(c->v_req)) {
        return false;
    }
    double prev = 0.0;
    for (int k = 0; k < c->n; k++) {
        const ls_pathspeed_zone_t *z = &c->zone[k];
        if (!isfinite(z->s_end) || z->s_end <= prev || !pos(z->v_max) ||
            !pos(ls_pathspeed_zone_accel(c, k, z->v_max, true, NULL)) ||
            !pos(ls_pathspeed_zone_accel(c, k, z->v_max, false, NULL))) {
            return false;
        }
        prev = z->s_end;
    }
    return fabs(prev - 1.0) <= S_END_TOL;
}

int ls_pathspeed_plan(ls_pathspeed_t *p, const ls_pathspeed_curve_t *c, double s0, double jerk_scale)
{
    if (p == NULL || c == NULL || !curve_ok(c) || !isfinite(s0) || s0 < 0.0 || s0 > 1.0 || !pos(jerk_scale) ||
        jerk_scale > 1.0) {
        return LS_EINVAL;
    }
    const double j = c->j * jerk_scale;
    const int i0 = ls_pathspeed_zone_of(c, s0);
    ls_pathspeed_t out;
    memset(&out, 0, sizeof out);
    out.j = j;
    out.s_start = s0;
    const int m = c->n - i0;
    if (s0 >= 1.0) {
        out.s_start = 1.0;
        *p = out;
        return LS_OK;
    }
    double b[LS_PATHSPEED_MAX_ZONES + 1], u[LS_PATHSPEED_MAX_ZONES + 1];
    b[0] = s0;
    for (int k = 0; k < m; k++) {
        b[k + 1] = k + 1 == m ? 1.0 : c->zone[i0 + k].s_end;
    }
    u[0] = u[m] = 0.0;
    for (int k = 1; k < m; k++) {
        u[k] = fmin(c->zone[i0 + k - 1].v_max, c->zone[i0 + k].v_max);
    }
    for (int k = m - 1; k >= 0; k--) { /* room to ramp down from the entry to the exit */
        const zone_ctx_t z = { c, i0 + k, j };
        if (u[k] > u[k + 1]) {
            u[k] = largest(&z, 0, u[k + 1], u[k], u[k + 1], 0.0, b[k + 1] - b[k]);
        }
    }
    for (int k = 0; k < m; k++) { /* room to ramp up from the entry to the exit */
        const zone_ctx_t z = { c, i0 + k, j };
        if (u[k + 1] > u[k]) {
            u[k + 1] = largest(&z, 1, u[k], u[k + 1], u[k], 0.0, b[k + 1] - b[k]);
        }
    }
    double t = 0.0;
    for (int k = 0; k < m; k++) {
        const zone_ctx_t z = { c, i0 + k, j };
        const double L = b[k + 1] - b[k];
        ls_pathspeed_part_t *pt = &out.part[k];
        pt->t0_s = t;
        pt->s0 = b[k];
        pt->u = u[k];
        pt->w = u[k + 1];
        const double lo = fmax(pt->u, pt->w);
        pt->c = lo >= c->zone[i0 + k].v_max ? lo : largest(&z, 2, lo, c->zone[i0 + k].v_max, pt->u, pt->w, L);
        pt->a_up = ls_pathspeed_zone_accel(c, i0 + k, pt->c, true, NULL);
        pt->a_dn = ls_pathspeed_zone_accel(c, i0 + k, pt->c, false, NULL);
        const double ramps = ramp_dist(pt->u, pt->c, pt->a_up, j) + ramp_dist(pt->c, pt->w, pt->a_dn, j);
        pt->t_cruise_s = pt->c > 0.0 ? fmax(0.0, (L - ramps) / pt->c) : 0.0;
        t += ramp_time(pt->u, pt->c, pt->a_up, j) + pt->t_cruise_s + ramp_time(pt->c, pt->w, pt->a_dn, j);
    }
    out.n = (uint8_t)m;
    out.duration_s = t;
    *p = out;
    return LS_OK;
}

int ls_pathspeed_curve_finish(ls_pathspeed_curve_t *c)
{
    if (c == NULL || !curve_ok(c)) {
        return LS_EINVAL;
    }
    ls_pathspeed_t p;
    (void)ls_pathspeed_plan(&p, c, 0.0, 1.0);
    bool joined = true;
    while (joined && c->n > 1) {
        joined = false;
        for (int k = 0; k + 1 < c->n; k++) {
            ls_pathspeed_curve_t trial = *c;
            join_next(&trial, k);
            ls_pathspeed_t q;
            if (ls_pathspeed_plan(&q, &trial, 0.0, 1.0) == LS_OK && q.duration_s < p.duration_s * (1.0 - FINISH_GAIN)) {
                *c = trial;
                p = q;
                joined = true;
            }
        }
    }
    return LS_OK;
}

void ls_pathspeed_sample(const ls_pathspeed_t *p, double t_s, double *s, double *v, double *a)
{
    if (p == NULL) {
        return;
    }
    double ps = 1.0, pv = 0.0, pa = 0.0;
    const double t = (isnan(t_s) || t_s < 0.0) ? 0.0 : t_s;
    if (p->n > 0 && t < p->duration_s) {
        int k = 0;
        while (k + 1 < p->n && t >= p->part[k + 1].t0_s) {
            k++;
        }
        const ls_pathspeed_part_t *pt = &p->part[k];
        const double t_up = ramp_time(pt->u, pt->c, pt->a_up, p->j);
        double tau = t - pt->t0_s, dp;
        if (tau < t_up) {
            ramp_at(pt->u, pt->c, pt->a_up, p->j, tau, &dp, &pv, &pa);
        } else if (tau < t_up + pt->t_cruise_s) {
            dp = ramp_dist(pt->u, pt->c, pt->a_up, p->j) + pt->c * (tau - t_up);
            pv = pt->c;
            pa = 0.0;
        } else {
            tau -= t_up + pt->t_cruise_s;
            double d;
            ramp_at(pt->c, pt->w, pt->a_dn, p->j, tau, &d, &pv, &pa);
            dp = ramp_dist(pt->u, pt->c, pt->a_up, p->j) + pt->c * pt->t_cruise_s + d;
        }
        ps = pt->s0 + dp;
    }
    if (s != NULL) {
        *s = ps;
    }
    if (v != NULL) {
        *v = pv;
    }
    if (a != NULL) {
        *a = pa;
    }
}

/* ------------------------------------------------------------------ stops */

/* Where ramp r comes to its end speed. */
static double ramp_end(const ls_ramp_t *r)
{
    double p;
    ls_ramp_sample(r, r->duration_s, &p, NULL, NULL);
    return p;
}

int ls_pathspeed_plan_stop(ls_pathspeed_stop_t *st, const ls_pathspeed_curve_t *c, double s0, double v0, double a0,
                           double j)
{
    if (st == NULL || c == NULL || !curve_ok(c) || !isfinite(s0) || !isfinite(v0) || v0 < -V_ROUND || !isfinite(a0) ||
        !pos(j)) {
        return LS_EINVAL;
    }
    ls_pathspeed_stop_t out;
    memset(&out, 0, sizeof out);
    double s = s0, v = fmax(0.0, v0), a = a0, t = 0.0;
    for (int k = ls_pathspeed_zone_of(c, s0); k < c->n; k++) {
        /* where the acceleration eases to 0 at j, and the fastest it runs here */
        const double eased = fmax(0.0, v + a * fabs(a) / (2.0 * j)), top = fmax(v, eased);
        const double acc = ls_pathspeed_zone_accel(c, k, top, false, NULL);
        const double end = k + 1 == c->n ? INFINITY : c->zone[k].s_end;
        ls_ramp_t *r = &out.ramp[out.n];
        out.t0_s[out.n] = t;
        out.n++;
        if (ls_ramp_plan(r, s, v, a, 0.0, acc, j) != LS_OK) {
            return LS_EINVAL; /* acc <= 0: a state beyond the zone's cap, never on a profile of this curve */
        }
        if (ramp_end(r) <= end) {
            break; /* at rest inside this zone */
        }
        /* The lowest speed it can reach by the zone's end: between rest
         * (too far) and `eased` (the acceleration only eased to 0). */
        double lo = 0.0, hi = eased;
        ls_ramp_t rh;
        (void)ls_ramp_plan(&rh, s, v, a, hi, acc, j);
        for (int i = 0; i < BISECT_STEPS && ramp_end(&rh) <= end; i++) {
            const double mid = 0.5 * (lo + hi);
            ls_ramp_t rm;
            (void)ls_ramp_plan(&rm, s, v, a, mid, acc, j);
            if (ramp_end(&rm) <= end) {
                hi = mid;
                rh = rm;
            } else {
                lo = mid;
            }
        }
        *r = rh;
        const double w = hi, p_end = ramp_end(r);
        t += r->duration_s + (w > 0.0 ? fmax(0.0, end - p_end) / w : 0.0);
        s = end;
        v = w;
        a = 0.0;
    }
    out.duration_s = out.t0_s[out.n - 1] + out.ramp[out.n - 1].duration_s;
    *st = out;
    return LS_OK;
}

void ls_pathspeed_stop_one(ls_pathspeed_stop_t *st, const ls_ramp_t *r)
{
    if (st == NULL || r == NULL) {
        return;
    }
    memset(st, 0, sizeof *st);
    st->n = 1;
    st->ramp[0] = *r;
    st->duration_s = r->duration_s;
}

void ls_pathspeed_stop_sample(const ls_pathspeed_stop_t *st, double t_s, double *s, double *v, double *a)
{
    if (st == NULL || st->n == 0) {
        return;
    }
    const double t = (isnan(t_s) || t_s < 0.0) ? 0.0 : t_s;
    int k = 0;
    while (k + 1 < st->n && t >= st->t0_s[k + 1]) {
        k++;
    }
    const ls_ramp_t *r = &st->ramp[k];
    double ps, pv, pa;
    /* after the ramp it moves on at its end speed: the cruise to the zone's end */
    ls_ramp_sample(r, k + 1 == st->n ? fmin(t - st->t0_s[k], r->duration_s) : t - st->t0_s[k], &ps, &pv, &pa);
    if (s != NULL) {
        *s = ps;
    }
    if (v != NULL) {
        *v = pv;
    }
    if (a != NULL) {
        *a = pa;
    }
}

/* ----------------------------------------------------------------- report */

double ls_pathspeed_first_jerk_s(const ls_pathspeed_t *p)
{
    if (p == NULL || p->n == 0) {
        return 0.0;
    }
    double t1, t2;
    ramp_shape(p->part[0].c - p->part[0].u, p->part[0].a_up, p->j, &t1, &t2);
    return t1;
}

double ls_pathspeed_last_jerk_s(const ls_pathspeed_t *p)
{
    if (p == NULL || p->n == 0) {
        return 0.0;
    }
    const ls_pathspeed_part_t *pt = &p->part[p->n - 1];
    double t1, t2;
    ramp_shape(pt->c - pt->w, pt->a_dn, p->j, &t1, &t2);
    return t1;
}

bool ls_pathspeed_slowed(const ls_pathspeed_curve_t *c, const ls_pathspeed_t *p, ls_pathspeed_why_t *out)
{
    if (c == NULL || p == NULL || out == NULL) {
        return false;
    }
    memset(out, 0, sizeof *out);
    out->frac = out->a_frac = 1.0;
    /* A cap slows the profile where it cruises at it. */
    bool capped = false;
    for (int k = 0; k < p->n; k++) {
        const int zk = ls_pathspeed_zone_of(c, p->part[k].s0);
        const ls_pathspeed_zone_t *z = &c->zone[zk];
        if (z->limit == LS_PATHSPEED_REQUESTED || p->part[k].c < z->v_max * (1.0 - 1e-9)) {
            continue;
        }
        if (!capped) {
            out->s_from = p->part[k].s0;
        }
        capped = true;
        out->s_to = z->s_end;
        if (z->v_max / c->v_req < out->frac) {
            out->frac = z->v_max / c->v_req;
            out->joint = z->joint;
            out->limit = z->limit;
        }
    }
    for (int k = 0; k < p->n; k++) {
        const int zk = ls_pathspeed_zone_of(c, p->part[k].s0);
        for (int up = 0; up < 2; up++) {
            uint8_t jn;
            const double a = ls_pathspeed_zone_accel(c, zk, p->part[k].c, up != 0, &jn);
            if (a / c->a_req < out->a_frac * (1.0 - 1e-9)) {
                out->a_frac = a / c->a_req;
                out->a_joint = jn;
            }
        }
    }
    return capped || out->a_frac < 1.0;
}
