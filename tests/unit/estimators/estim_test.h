/* Shared helpers of the estimator unit tests: machine data, the saturating flux map, and a double
 * reference of the UNOP residual / cost / Newton step written independently of the firmware
 * (plain trigonometry, finite-difference derivatives). */
#ifndef ESTIM_TEST_H
#define ESTIM_TEST_H
#include <string.h>

#include "../mc_test.h"

#include "mc/flux_model.h"
#include "mc/unop.h"

#define DEG (PI_D / 180.0)

/* sun2016 prototype (machines.md, thesis Table 4.1) */
#define SUN_LD 10.5e-3
#define SUN_LQ 12.9e-3
#define SUN_PSI 0.34305
#define SUN_RS 0.4
#define SUN_TS 1e-4
#define SUN_P 5
#define RPM_TO_WE(n) ((n) * 2.0 * PI_D / 60.0 * SUN_P)

static inline double wrapd(double x) { return remainder(x, 2.0 * PI_D); }

/* deterministic uniform in [lo, hi) */
static inline double urand(uint64_t *st, double lo, double hi)
{
    *st = *st * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * (double)(*st >> 11) * (1.0 / 9007199254740992.0);
}

/* ---- analytic saturation model of machines.md, sun2016 fit (S, T, U, V) = (2, 2, 1, 0) ----
 * i(psi) is closed form; psi(i) is found by Newton in double. */
static inline void sun_i_of_psi(double pd, double pq, double i[2], double jac[4])
{
    const double ad0 = 86.58, add = 24.52, aq0 = 58.12, aqq = 774.0, adq = 1441.3, i_f = 30.69;
    double apd = fabs(pd);
    double gd = ad0 + add * pd * pd + 0.5 * adq * apd * pq * pq;
    double gq = aq0 + aqq * pq * pq + adq / 3.0 * apd * apd * apd;
    i[0] = gd * pd - i_f;
    i[1] = gq * pq;
    double sg = (pd >= 0.0) ? 1.0 : -1.0;
    jac[0] = gd + pd * (2.0 * add * pd + 0.5 * adq * sg * pq * pq);
    jac[1] = adq * apd * pd * pq;
    jac[2] = jac[1];
    jac[3] = gq + 2.0 * aqq * pq * pq;
}

static inline void sun_psi_of_i(double id, double iq, double psi[2])
{
    double pd = SUN_PSI + SUN_LD * id, pq = SUN_LQ * iq;
    for (int k = 0; k < 60; ++k) {
        double i[2], j[4];
        sun_i_of_psi(pd, pq, i, j);
        double ed = i[0] - id, eq = i[1] - iq;
        double det = j[0] * j[3] - j[1] * j[2];
        pd -= (j[3] * ed - j[1] * eq) / det;
        pq -= (-j[2] * ed + j[0] * eq) / det;
    }
    psi[0] = pd;
    psi[1] = pq;
}

/* 41 x 41 map over [-20, 20] A in both axes (1 A cells) */
static inline void fill_sun_map(mc_flux_map_t *m)
{
    m->n_d = 41;
    m->n_q = 41;
    m->id0 = -20.0f;
    m->did = 1.0f;
    m->iq0 = -20.0f;
    m->diq = 1.0f;
    for (int a = 0; a < m->n_d; ++a) {
        for (int b = 0; b < m->n_q; ++b) {
            double psi[2];
            sun_psi_of_i(-20.0 + a, -20.0 + b, psi);
            m->psi_d[a * m->n_q + b] = (float)psi[0];
            m->psi_q[a * m->n_q + b] = (float)psi[1];
        }
    }
}

/* ---- double reference of the flux model (same table values, same cell rule) ---- */
static inline int dcell(double t, int n)
{
    if (!(t > 0.0)) {
        return 0;
    }
    if (t >= n - 2) {
        return n - 2;
    }
    return (int)t;
}

static inline void dflux(const mc_flux_model_t *m, double id, double iq, double psi[2])
{
    if (m->kind == MC_FLUX_CONST) {
        psi[0] = (double)m->ld * id + (double)m->psi_pm;
        psi[1] = (double)m->lq * iq;
        return;
    }
    const mc_flux_map_t *mp = m->map;
    double td = (id - mp->id0) / mp->did, tq = (iq - mp->iq0) / mp->diq;
    int a = dcell(td, mp->n_d), b = dcell(tq, mp->n_q);
    double u = td - a, v = tq - b;
    const float *tab[2] = {mp->psi_d, mp->psi_q};
    for (int k = 0; k < 2; ++k) {
        double f00 = tab[k][a * mp->n_q + b], f01 = tab[k][a * mp->n_q + b + 1];
        double f10 = tab[k][(a + 1) * mp->n_q + b], f11 = tab[k][(a + 1) * mp->n_q + b + 1];
        psi[k] = f00 * (1 - u) * (1 - v) + f10 * u * (1 - v) + f01 * (1 - u) * v + f11 * u * v;
    }
}

/* ---- double reference of the UNOP residual and cost ---- */
typedef struct {
    double i0[2], i1[2], u[2];   /* alpha-beta: i(k-1), i(k), u applied during [k-1, k] */
} dsample_t;

static inline void dpark(const double x[2], double th, double y[2])
{
    double c = cos(th), s = sin(th);
    y[0] = c * x[0] + s * x[1];
    y[1] = -s * x[0] + c * x[1];
}

static inline void dpark_inv(const double x[2], double th, double y[2])
{
    double c = cos(th), s = sin(th);
    y[0] = c * x[0] - s * x[1];
    y[1] = s * x[0] + c * x[1];
}

static inline void dform(const mc_unop_cfg_t *cfg, double *au, double *w0, double *w1)
{
    *au = cfg->mid_sample ? 0.5 : 0.0;
    *w0 = cfg->mid_sample ? 0.5 : 1.0;
    *w1 = cfg->mid_sample ? 0.5 : 0.0;
}

/* the mid form's held-voltage gain (see unop.c) */
static inline double dzoh(const mc_unop_cfg_t *cfg, double om)
{
    double x = 0.5 * om * cfg->ts;
    return (cfg->mid_sample && cfg->zoh_gain) ? 1.0 + x * x / 6.0 : 1.0;
}

static inline void dres(const mc_unop_cfg_t *cfg, const dsample_t *in, double th, double om,
                        double r[2])
{
    double ts = cfg->ts, rs = cfg->rs, au, w0, w1;
    dform(cfg, &au, &w0, &w1);
    double ir[2] = {in->i0[0], in->i0[1]};
    if (cfg->mid_sample) {
        ir[0] = 0.5 * (in->i0[0] + in->i1[0]);
        ir[1] = 0.5 * (in->i0[1] + in->i1[1]);
    }
    double ub[2] = {in->u[0] - rs * ir[0], in->u[1] - rs * ir[1]};
    double v[2], y0[2], y1[2], p0[2], p1[2];
    dpark(ub, th + au * om * ts, v);
    double sg = dzoh(cfg, om);
    v[0] *= sg;
    v[1] *= sg;
    dpark(in->i0, th, y0);
    dpark(in->i1, th + om * ts, y1);
    dflux(&cfg->model, y0[0], y0[1], p0);
    dflux(&cfg->model, y1[0], y1[1], p1);
    double pr[2] = {w0 * p0[0] + w1 * p1[0], w0 * p0[1] + w1 * p1[1]};
    r[0] = v[0] - (p1[0] - p0[0]) / ts + om * pr[1];
    r[1] = v[1] - (p1[1] - p0[1]) / ts - om * pr[0];
}

/* cost in the scaled variables x = [theta, omega / omega_base] */
static inline double dcost(const mc_unop_cfg_t *cfg, const dsample_t *in, double th, double s,
                           double thref, double omref, double k1, double k2)
{
    double wb = cfg->omega_base > 0 ? cfg->omega_base : 1.0;
    double un = cfg->u_norm > 0 ? cfg->u_norm : 1.0;
    double r[2];
    dres(cfg, in, th, s * wb, r);
    double e1 = wrapd(th - thref), e2 = (s * wb - omref) / wb;
    return (r[0] * r[0] + r[1] * r[1]) / (un * un) + k1 * e1 * e1 + k2 * e2 * e2;
}

/* central finite differences of dcost: gradient and Hessian in the scaled variables */
static inline void dcost_fd(const mc_unop_cfg_t *cfg, const dsample_t *in, double th, double s,
                            double thref, double omref, double k1, double k2, double g[2],
                            double h[4])
{
#define C_(a, b) dcost(cfg, in, th + (a), s + (b), thref, omref, k1, k2)
    const double e = 1e-6, f = 1e-4;
    g[0] = (C_(e, 0) - C_(-e, 0)) / (2 * e);
    g[1] = (C_(0, e) - C_(0, -e)) / (2 * e);
    double c0 = C_(0, 0);
    h[0] = (C_(f, 0) - 2 * c0 + C_(-f, 0)) / (f * f);
    h[3] = (C_(0, f) - 2 * c0 + C_(0, -f)) / (f * f);
    h[1] = (C_(f, f) - C_(f, -f) - C_(-f, f) + C_(-f, -f)) / (4 * f * f);
    h[2] = h[1];
#undef C_
}

/* data from the same discrete model: u such that the residual is zero at (th, om) */
static inline void dgen_u(const mc_unop_cfg_t *cfg, dsample_t *in, double th, double om)
{
    double ts = cfg->ts, rs = cfg->rs, au, w0, w1;
    dform(cfg, &au, &w0, &w1);
    double y0[2], y1[2], p0[2], p1[2];
    dpark(in->i0, th, y0);
    dpark(in->i1, th + om * ts, y1);
    dflux(&cfg->model, y0[0], y0[1], p0);
    dflux(&cfg->model, y1[0], y1[1], p1);
    double pr[2] = {w0 * p0[0] + w1 * p1[0], w0 * p0[1] + w1 * p1[1]};
    double v[2] = {(p1[0] - p0[0]) / ts - om * pr[1], (p1[1] - p0[1]) / ts + om * pr[0]};
    double ub[2];
    double sg = dzoh(cfg, om);
    v[0] /= sg;
    v[1] /= sg;
    dpark_inv(v, th + au * om * ts, ub);
    double ir[2] = {in->i0[0], in->i0[1]};
    if (cfg->mid_sample) {
        ir[0] = 0.5 * (in->i0[0] + in->i1[0]);
        ir[1] = 0.5 * (in->i0[1] + in->i1[1]);
    }
    in->u[0] = ub[0] + rs * ir[0];
    in->u[1] = ub[1] + rs * ir[1];
}

/* rotor-frame current of a test trajectory: operating point + an injection-like HF ripple */
typedef struct {
    double id, iq;       /* operating point [A] */
    double ih, fh;       /* HF amplitude [A] (d axis, q sees a quarter) and frequency [Hz] */
} traj_t;

static inline void traj_iab(const traj_t *tr, double th, double t, double iab[2])
{
    double w = 2.0 * PI_D * tr->fh * t;
    double idq[2] = {tr->id + tr->ih * sin(w), tr->iq + 0.25 * tr->ih * cos(w)};
    dpark_inv(idq, th, iab);
}

/* sample k of a constant-speed trajectory: interval [k-1, k], theta(k-1) = th0 + om (k-1) Ts */
static inline void dgen_sample(const mc_unop_cfg_t *cfg, const traj_t *tr, double th0, double om,
                               int k, dsample_t *in, double *th_km1)
{
    double ts = cfg->ts;
    *th_km1 = th0 + om * ts * (k - 1);
    traj_iab(tr, *th_km1, ts * (k - 1), in->i0);
    traj_iab(tr, *th_km1 + om * ts, ts * k, in->i1);
    dgen_u(cfg, in, *th_km1, om);
}

static inline mc_angle_in_t to_in(const dsample_t *d)
{
    mc_angle_in_t in;
    memset(&in, 0, sizeof in);
    in.i_ab_prev.alpha = (float)d->i0[0];
    in.i_ab_prev.beta = (float)d->i0[1];
    in.i_ab.alpha = (float)d->i1[0];
    in.i_ab.beta = (float)d->i1[1];
    in.u_ab_applied.alpha = (float)d->u[0];
    in.u_ab_applied.beta = (float)d->u[1];
    in.vdc = 300.0f;
    return in;
}

/* the float inputs seen by the firmware, back in double (so both see identical data) */
static inline dsample_t from_in(const mc_angle_in_t *in)
{
    dsample_t d;
    d.i0[0] = in->i_ab_prev.alpha;
    d.i0[1] = in->i_ab_prev.beta;
    d.i1[0] = in->i_ab.alpha;
    d.i1[1] = in->i_ab.beta;
    d.u[0] = in->u_ab_applied.alpha;
    d.u[1] = in->u_ab_applied.beta;
    return d;
}

/* ---- double reference of one UNOP step: same algorithm, derivatives by finite differences ---- */
typedef struct {
    double theta, omega;   /* start of the last interval */
    int iters;
} dunop_t;

static inline void dnewton_dir(const double h[4], const double g[2], double d[2])
{
    double a = h[0], b = 0.5 * (h[1] + h[2]), c = h[3];
    double m = 0.5 * (a + c), hd = 0.5 * (a - c), rr = sqrt(hd * hd + b * b);
    double l1 = m + rr, l2 = m - rr, vx, vy;
    if (hd >= 0) {
        vx = hd + rr;
        vy = b;
    } else {
        vx = b;
        vy = rr - hd;
    }
    double n = sqrt(vx * vx + vy * vy);
    if (n > 0) {
        vx /= n;
        vy /= n;
    } else {
        vx = 1;
        vy = 0;
    }
    double lmax = fmax(fabs(l1), fabs(l2)), fl = 1e-4 * lmax;
    if (!(lmax > 0)) {
        d[0] = d[1] = 0;
        return;
    }
    double m1 = fmax(fabs(l1), fl), m2 = fmax(fabs(l2), fl);
    double p1 = (vx * g[0] + vy * g[1]) / m1, p2 = (-vy * g[0] + vx * g[1]) / m2;
    d[0] = -(p1 * vx - p2 * vy);
    d[1] = -(p1 * vy + p2 * vx);
}

static inline void dunop_step(const mc_unop_cfg_t *cfg, dunop_t *st, const dsample_t *in,
                              double *theta_k, double *omega)
{
    double ts = cfg->ts, wb = cfg->omega_base;
    int reg = fabs(st->omega) <= cfg->omega_n1;
    double k1 = reg ? cfg->k1 : 0, k2 = reg ? cfg->k2 : 0;
    double thp = st->theta + st->omega * ts;
    double thr = cfg->reg_predicted ? thp : st->theta, omr = st->omega;
    double x[2] = {thp, st->omega / wb}, g[2], h[4], d[2];
    double cst = dcost(cfg, in, x[0], x[1], thr, omr, k1, k2);
    st->iters = 0;
    for (int it = 0; it < cfg->iter_max; ++it) {
        dcost_fd(cfg, in, x[0], x[1], thr, omr, k1, k2, g, h);
        dnewton_dir(h, g, d);
        double nd = hypot(d[0], d[1]);
        if (cfg->step_max > 0 && nd > cfg->step_max) {
            d[0] *= cfg->step_max / nd;
            d[1] *= cfg->step_max / nd;
            nd = cfg->step_max;
        }
        if (nd < cfg->step_tol) {
            x[0] += d[0];
            x[1] += d[1];
            st->iters = it + 1;
            break;
        }
        double slope = g[0] * d[0] + g[1] * d[1], xi = 1, ct = cst;
        int ok = 0;
        for (int j = 0; j <= MC_UNOP_LS_MAX; ++j) {
            ct = dcost(cfg, in, x[0] + xi * d[0], x[1] + xi * d[1], thr, omr, k1, k2);
            if (ct <= cst + 1e-4 * xi * slope) {
                ok = 1;
                break;
            }
            xi *= 0.5;
        }
        if (!ok) {
            break;
        }
        x[0] += xi * d[0];
        x[1] += xi * d[1];
        cst = ct;
        st->iters = it + 1;
        if (xi * nd < cfg->step_tol) {
            break;
        }
    }
    st->theta = wrapd(x[0]);
    st->omega = x[1] * wb;
    *theta_k = wrapd(x[0] + st->omega * ts);
    *omega = st->omega;
}

static inline mc_unop_cfg_t sun_cfg(const mc_flux_map_t *map, int mid)
{
    mc_unop_cfg_t c;
    mc_unop_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.model.kind = map ? MC_FLUX_MAP : MC_FLUX_CONST;
    c.model.ld = (float)SUN_LD;
    c.model.lq = (float)SUN_LQ;
    c.model.psi_pm = (float)SUN_PSI;
    c.model.map = map;
    c.mid_sample = mid != 0;
    return c;
}

#endif
