/* UNOP speed and position estimator: residual of the discrete voltage equation (5.1)/(6.1) through
 * the shared flux model, cost (6.4)/(6.5), modified Newton with line search (6.7).
 *
 * Residual of the interval [k-1, k] for the candidate theta = theta(k-1), omega:
 *   i_dq0 = P(theta) i_ab(k-1),  i_dq1 = P(theta + omega Ts) i_ab(k)           (T(dtheta) of (6.1))
 *   r = P(theta_u) ubar - (psi(i_dq1) - psi(i_dq0)) / Ts - omega J psi_rot,  J = [0 -1; 1 0]
 *   thesis form: ubar = u - Rs i0, theta_u = theta, psi_rot = psi(i_dq0)                (5.1)
 *   mid form:    ubar = u - Rs (i0 + i1)/2, theta_u = theta + omega Ts/2,
 *                psi_rot = (psi(i_dq0) + psi(i_dq1)) / 2, voltage term times 1 + (omega Ts/2)^2/6
 * The voltage is held constant in alpha-beta over the interval while the rotor turns by omega Ts,
 * so its rotor-frame mean sits at the mid-sample angle; the thesis form evaluates it at the start
 * and the estimate absorbs the difference as an angle bias of about omega Ts / 2. */
#include "mc/unop.h"

#include <math.h>
#include <stddef.h>

#include "mc/angle.h"
#include "mc/filters.h"
#include "mc/sincos.h"
#include "mc/transforms.h"

#define EIG_FLOOR_REL 1e-4f   /* smallest eigenvalue kept, relative to the largest (6.7) */
#define ARMIJO_C      1e-4f   /* sufficient-decrease constant of the line search */

/* A planar vector and its first and second partial derivatives with respect to theta ("t") and
 * the unscaled speed omega ("w"). */
typedef struct {
    mc_dq_t v, t, w, tt, tw, ww;
} jet_t;

static const jet_t JET0;

typedef struct {
    mc_ab_t ubar;     /* resistance-compensated voltage, alpha-beta */
    float   a_u;      /* voltage angle = theta + a_u omega Ts */
    float   w0, w1;   /* weights of psi_0, psi_1 in psi_rot */
    bool    zoh;      /* apply the held-voltage gain 1 + x^2/6 */
    float   ls;       /* inductance scale: psi = psi0 + ls (psi_model - psi0) */
    mc_dq_t psi0;
} ctx_t;

static mc_dq_t dq(float d, float q)
{
    mc_dq_t r;
    r.d = d;
    r.q = q;
    return r;
}

static mc_dq_t add(mc_dq_t a, mc_dq_t b) { return dq(a.d + b.d, a.q + b.q); }
static mc_dq_t scl(float k, mc_dq_t a) { return dq(k * a.d, k * a.q); }
static mc_dq_t jmul(mc_dq_t a) { return dq(-a.q, a.d); }           /* J a */
static float dot(mc_dq_t a, mc_dq_t b) { return a.d * b.d + a.q * b.q; }
/* fmaxf/fminf are library calls on the M4 */
static float maxf(float a, float b) { return (a > b) ? a : b; }
static float minf(float a, float b) { return (a < b) ? a : b; }

static mc_dq_t lmul(const float L[4], mc_dq_t a)
{
    return dq(L[0] * a.d + L[1] * a.q, L[2] * a.d + L[3] * a.q);
}

/* second derivative of psi contracted with two current directions */
static mc_dq_t hmul(const float dL[6], mc_dq_t a, mc_dq_t b)
{
    float cross = a.d * b.q + a.q * b.d;
    return dq(dL[0] * a.d * b.d + dL[1] * cross + dL[2] * a.q * b.q,
              dL[3] * a.d * b.d + dL[4] * cross + dL[5] * a.q * b.q);
}

/* y = P(theta + c omega) x. dP/dphi x = -J y and d2P/dphi2 x = -y, and phi moves by 1 per theta
 * and by c per omega. */
static void rot_jet(mc_ab_t x, float theta, float omega, float c, bool derivs, jet_t *y)
{
    y->v = mc_park(x, mc_sincos(theta + c * omega));
    if (!derivs) {
        return;
    }
    y->t = dq(y->v.q, -y->v.d);
    y->w = scl(c, y->t);
    y->tt = scl(-1.0f, y->v);
    y->tw = scl(-c, y->v);
    y->ww = scl(-c * c, y->v);
}

/* Second-order correction of the mid form for a voltage held constant in alpha-beta, x = omega Ts/2:
 * the rotor-frame mean of the held voltage is the mid-sample vector times sin(x)/x ~ 1 - x^2/6, and
 * the trapezoid (psi0 + psi1)/2 misses the mean flux by -Ts^2/12 psi'', which in steady state
 * (psi'' ~ -omega J u) adds +x^2/3 to the voltage balance. Net gain 1 + x^2/6 on the voltage term;
 * without it the speed estimate carries a relative bias of about -(omega Ts)^2/24 (-0.35 % at
 * 3000 rad/s, 10 kHz). dx/domega = tau. */
static void zoh_gain(jet_t *u, float x, float tau, bool derivs)
{
    float sg = 1.0f + (x * x) * (1.0f / 6.0f);
    mc_dq_t y = u->v;
    u->v = scl(sg, y);
    if (!derivs) {
        return;
    }
    float s1 = tau * x * (1.0f / 3.0f);
    float s2 = (tau * tau) * (1.0f / 3.0f);
    mc_dq_t yt = u->t, yw = u->w;
    u->t = scl(sg, yt);
    u->w = add(scl(s1, y), scl(sg, yw));
    u->tt = scl(sg, u->tt);
    u->tw = add(scl(s1, yt), scl(sg, u->tw));
    u->ww = add(add(scl(s2, y), scl(2.0f * s1, yw)), scl(sg, u->ww));
}

/* psi(y) and its derivatives by the chain rule through the flux model, its inductive part
 * scaled by c->ls (the magnet part psi0 kept): L and dL scale with it */
static void flux_jet(const mc_flux_model_t *m, const ctx_t *c, const jet_t *y, bool derivs, jet_t *p)
{
    float L[4], dL[6];
    mc_flux_eval(m, y->v, &p->v, derivs ? L : NULL, derivs ? dL : NULL);
    const bool scaled = c->ls != 1.0f;   /* bit-exact model as given while not adapted */
    if (scaled) {
        p->v = add(c->psi0, scl(c->ls, add(p->v, scl(-1.0f, c->psi0))));
    }
    if (!derivs) {
        return;
    }
    for (int k = 0; scaled && k < 6; ++k) {
        dL[k] *= c->ls;
        if (k < 4) {
            L[k] *= c->ls;
        }
    }
    p->t = lmul(L, y->t);
    p->w = lmul(L, y->w);
    p->tt = add(lmul(L, y->tt), hmul(dL, y->t, y->t));
    p->tw = add(lmul(L, y->tw), hmul(dL, y->t, y->w));
    p->ww = add(lmul(L, y->ww), hmul(dL, y->w, y->w));
}

/* -(a1 - a0)/Ts - omega J (w0 a0 + w1 a1): the flux part of r, linear in the flux terms */
static mc_dq_t comb(const ctx_t *c, float inv_ts, float omega, mc_dq_t a0, mc_dq_t a1)
{
    mc_dq_t diff = dq(a1.d - a0.d, a1.q - a0.q);
    mc_dq_t rot = add(scl(c->w0, a0), scl(c->w1, a1));
    return add(scl(-inv_ts, diff), scl(-omega, jmul(rot)));
}

static void make_ctx(const mc_unop_t *s, const mc_angle_in_t *in, ctx_t *c)
{
    const mc_unop_cfg_t *cfg = &s->cfg;
    c->ls = s->l_scale;
    c->psi0 = s->psi0;
    mc_ab_t ir = in->i_ab_prev;
    if (cfg->mid_sample) {
        ir.alpha = 0.5f * (in->i_ab_prev.alpha + in->i_ab.alpha);
        ir.beta = 0.5f * (in->i_ab_prev.beta + in->i_ab.beta);
        c->a_u = 0.5f;
        c->w0 = 0.5f;
        c->w1 = 0.5f;
        c->zoh = cfg->zoh_gain;
    } else {
        c->zoh = false;
        c->a_u = 0.0f;
        c->w0 = 1.0f;
        c->w1 = 0.0f;
    }
    c->ubar.alpha = in->u_ab_applied.alpha - cfg->rs * ir.alpha;
    c->ubar.beta = in->u_ab_applied.beta - cfg->rs * ir.beta;
}

/* r and (derivs) its partials in theta and unscaled omega */
static void residual_jet(const mc_unop_cfg_t *cfg, const ctx_t *c, const mc_angle_in_t *in,
                         float theta, float omega, bool derivs, jet_t *r)
{
    float ts = cfg->ts;
    float inv_ts = 1.0f / ts;
    /* zeroed only to keep the compiler's flow analysis quiet on the value-only path */
    jet_t u = JET0, y0 = JET0, y1 = JET0, p0 = JET0, p1 = JET0;
    rot_jet(c->ubar, theta, omega, c->a_u * ts, derivs, &u);
    if (c->zoh) {
        zoh_gain(&u, omega * (0.5f * ts), 0.5f * ts, derivs);
    }
    rot_jet(in->i_ab_prev, theta, omega, 0.0f, derivs, &y0);
    rot_jet(in->i_ab, theta, omega, ts, derivs, &y1);
    flux_jet(&cfg->model, c, &y0, derivs, &p0);
    flux_jet(&cfg->model, c, &y1, derivs, &p1);

    r->v = add(u.v, comb(c, inv_ts, omega, p0.v, p1.v));
    if (!derivs) {
        return;
    }
    /* omega also multiplies the rotational term directly: those are the extra J terms */
    mc_dq_t jr = jmul(add(scl(c->w0, p0.v), scl(c->w1, p1.v)));
    mc_dq_t jrt = jmul(add(scl(c->w0, p0.t), scl(c->w1, p1.t)));
    mc_dq_t jrw = jmul(add(scl(c->w0, p0.w), scl(c->w1, p1.w)));
    r->t = add(u.t, comb(c, inv_ts, omega, p0.t, p1.t));
    r->w = add(add(u.w, comb(c, inv_ts, omega, p0.w, p1.w)), scl(-1.0f, jr));
    r->tt = add(u.tt, comb(c, inv_ts, omega, p0.tt, p1.tt));
    r->tw = add(add(u.tw, comb(c, inv_ts, omega, p0.tw, p1.tw)), scl(-1.0f, jrt));
    r->ww = add(add(u.ww, comb(c, inv_ts, omega, p0.ww, p1.ww)), scl(-2.0f, jrw));
}

static float inv_u2(const mc_unop_cfg_t *cfg)
{
    float un = (cfg->u_norm > 0.0f) ? cfg->u_norm : 1.0f;
    return 1.0f / (un * un);
}

static float omega_base(const mc_unop_cfg_t *cfg)
{
    return (cfg->omega_base > 0.0f) ? cfg->omega_base : 1.0f;
}

static float cost_ctx(const mc_unop_cfg_t *cfg, const ctx_t *c, const mc_angle_in_t *in,
                      float theta, float omega, float theta_ref, float omega_ref, float w1,
                      float w2, float grad[2], float hess[4])
{
    bool derivs = (grad != NULL) || (hess != NULL);
    jet_t r;
    residual_jet(cfg, c, in, theta, omega, derivs, &r);
    float k = inv_u2(cfg);
    float wb = omega_base(cfg);
    /* (6.4), normalised */
    float g = k * dot(r.v, r.v);
    /* (6.5): the angle difference through the wrap helper, the speed difference scaled */
    float e1 = mc_wrap_pi(theta - theta_ref);
    float e2 = (omega - omega_ref) / wb;
    g += w1 * e1 * e1 + w2 * e2 * e2;
    if (grad != NULL) {
        grad[0] = 2.0f * k * dot(r.v, r.t) + 2.0f * w1 * e1;
        grad[1] = wb * (2.0f * k * dot(r.v, r.w)) + 2.0f * w2 * e2;
    }
    if (hess != NULL) {
        /* full Hessian (not Gauss-Newton): r . r_xx matters away from the minimum */
        float htt = 2.0f * k * (dot(r.t, r.t) + dot(r.v, r.tt)) + 2.0f * w1;
        float htw = wb * (2.0f * k * (dot(r.t, r.w) + dot(r.v, r.tw)));
        float hww = (wb * wb) * (2.0f * k * (dot(r.w, r.w) + dot(r.v, r.ww))) + 2.0f * w2;
        hess[0] = htt;
        hess[1] = htw;
        hess[2] = htw;
        hess[3] = hww;
    }
    return g;
}

float mc_unop_cost(const mc_unop_t *s, const mc_angle_in_t *in, float theta, float omega,
                   float theta_ref, float omega_ref, float w1, float w2, float grad[2],
                   float hess[4])
{
    ctx_t c;
    make_ctx(s, in, &c);
    return cost_ctx(&s->cfg, &c, in, theta, omega, theta_ref, omega_ref, w1, w2, grad, hess);
}

mc_dq_t mc_unop_residual(const mc_unop_t *s, const mc_angle_in_t *in, float theta, float omega)
{
    ctx_t c;
    jet_t r;
    make_ctx(s, in, &c);
    residual_jet(&s->cfg, &c, in, theta, omega, false, &r);
    return r.v;
}

/* Modified Newton direction (6.7): closed-form eigen-decomposition of the symmetric 2x2 Hessian;
 * eigenvalues are replaced by max(|lambda|, floor) so a saddle or a maximum still gives a descent
 * direction of sensible length (plain clamping of a negative eigenvalue to the floor would turn it
 * into a huge step along that eigenvector). */
static void newton_dir(const float h[4], const float g[2], float d[2], float *cond, bool *mod)
{
    float a = h[0], b = 0.5f * (h[1] + h[2]), c = h[3];
    float m = 0.5f * (a + c);
    float hd = 0.5f * (a - c);
    float rr = sqrtf(hd * hd + b * b);
    float l1 = m + rr, l2 = m - rr;
    /* eigenvector of l1 from whichever row of (H - l1 I) is better conditioned */
    float vx, vy;
    if (hd >= 0.0f) {
        vx = hd + rr;
        vy = b;
    } else {
        vx = b;
        vy = rr - hd;
    }
    float n = sqrtf(vx * vx + vy * vy);
    if (n > 0.0f) {
        vx /= n;
        vy /= n;
    } else {
        vx = 1.0f;
        vy = 0.0f;
    }
    float lmax = maxf(fabsf(l1), fabsf(l2));
    if (!(lmax > 0.0f) || !(lmax < INFINITY)) {
        /* no curvature information (or NaN): no step */
        d[0] = 0.0f;
        d[1] = 0.0f;
        *cond = 0.0f;
        return;
    }
    float floor_ = EIG_FLOOR_REL * lmax;
    if (l2 < floor_) {
        *mod = true;
    }
    float m1 = maxf(fabsf(l1), floor_);
    float m2 = maxf(fabsf(l2), floor_);
    float p1 = (vx * g[0] + vy * g[1]) / m1;
    float p2 = (-vy * g[0] + vx * g[1]) / m2;
    d[0] = -(p1 * vx - p2 * vy);
    d[1] = -(p1 * vy + p2 * vx);
    *cond = minf(m1, m2) / maxf(m1, m2);
}

void mc_unop_cfg_default(mc_unop_cfg_t *cfg)
{
    cfg->ts = 0.0f;
    cfg->rs = 0.0f;
    cfg->model = (mc_flux_model_t){.kind = MC_FLUX_CONST, .map = NULL};  /* to be filled in */
    cfg->iter_max = 4;
    cfg->step_tol = 1e-6f;
    cfg->k1 = 0.0f;
    cfg->k2 = 0.0f;
    cfg->omega_n1 = 0.0f;
    cfg->omega_base = 200.0f;
    cfg->mid_sample = true;
    cfg->reg_predicted = true;
    cfg->u_norm = 100.0f;
    cfg->step_max = 1.0f;
    cfg->zoh_gain = true;
    cfg->l_adapt = 0.0f;
    cfg->l_adapt_p = 1.0f;
    cfg->bp_a1 = 0.0f;
    cfg->bp_a2 = 0.0f;
}

void mc_unop_retune(mc_unop_t *s, const mc_unop_cfg_t *cfg)
{
    s->cfg = *cfg;
    if (s->cfg.iter_max < 1) {
        s->cfg.iter_max = 1;
    } else if (s->cfg.iter_max > MC_UNOP_ITER_MAX) {
        s->cfg.iter_max = MC_UNOP_ITER_MAX;
    }
    mc_flux_eval(&s->cfg.model, dq(0.0f, 0.0f), &s->psi0, NULL, NULL);
}

void mc_unop_init(mc_unop_t *s, const mc_unop_cfg_t *cfg)
{
    mc_unop_retune(s, cfg);
    s->l_scale = 1.0f;
    /* the prior weighs as much as the injection (amplitude 2 sqrt(l_adapt_p)) over one time
     * constant: steady state of the power sum below */
    s->ls_pow = (cfg->l_adapt > 0.0f) ? 2.0f * cfg->l_adapt_p / cfg->l_adapt : 0.0f;
    mc_unop_reset(s, 0.0f, 0.0f);
}

void mc_unop_reset(mc_unop_t *s, float theta, float omega)
{
    /* stored as the start of the interval just ended, so the next prediction lands on theta */
    s->theta = mc_wrap_pi(theta - omega * s->cfg.ts);
    s->omega = omega;
    s->iters = 0;
    s->cost = 0.0f;
    s->cond = 1.0f;
    s->modified = false;
    s->ls_failed = false;
    s->bp_z[0][0] = s->bp_z[0][1] = s->bp_z[1][0] = s->bp_z[1][1] = 0.0f;
}

void mc_unop_step(mc_unop_t *s, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    const mc_unop_cfg_t *cfg = &s->cfg;
    float wb = omega_base(cfg);
    /* (6.6): K1, K2 only below N1; above it the cost is (6.4) */
    bool reg = fabsf(s->omega) <= cfg->omega_n1;
    float w1 = reg ? cfg->k1 : 0.0f;
    float w2 = reg ? cfg->k2 : 0.0f;
    /* the search starts from the previous estimate carried one period forward; the literal (6.5)
     * target theta_hat(k-1) is one period behind that, so K1 would drag the estimate back by
     * about omega Ts every period */
    float th_pred = s->theta + s->omega * cfg->ts;
    float th_ref = cfg->reg_predicted ? th_pred : s->theta;
    float om_ref = s->omega;

    ctx_t c;
    make_ctx(s, in, &c);
    float x[2] = {th_pred, s->omega / wb};
    float g[2], h[4], d[2];
    float cost = cost_ctx(cfg, &c, in, x[0], x[1] * wb, th_ref, om_ref, w1, w2, g, h);
    s->iters = 0;
    s->modified = false;
    s->ls_failed = false;
    s->cond = 1.0f;
    for (int it = 0; it < cfg->iter_max; ++it) {
        newton_dir(h, g, d, &s->cond, &s->modified);
        float nd = sqrtf(d[0] * d[0] + d[1] * d[1]);
        if (cfg->step_max > 0.0f && nd > cfg->step_max) {
            float k = cfg->step_max / nd;
            d[0] *= k;
            d[1] *= k;
            nd = cfg->step_max;
        }
        if (!(nd >= cfg->step_tol)) {
            /* converged: the remaining step is below the noise of the cost, take it unchecked */
            if (nd == nd) {
                x[0] += d[0];
                x[1] += d[1];
            }
            s->iters = it + 1;
            break;
        }
        /* (6.7) with xi = 1, 1/2, ... until sufficient decrease (Armijo) */
        float slope = g[0] * d[0] + g[1] * d[1];
        float xi = 1.0f;
        bool ok = false;
        float xt0 = x[0], xt1 = x[1], ct = cost;
        for (int j = 0; j <= MC_UNOP_LS_MAX; ++j) {
            xt0 = x[0] + xi * d[0];
            xt1 = x[1] + xi * d[1];
            ct = cost_ctx(cfg, &c, in, xt0, xt1 * wb, th_ref, om_ref, w1, w2, NULL, NULL);
            if (ct <= cost + ARMIJO_C * xi * slope) {
                ok = true;
                break;
            }
            xi *= 0.5f;
        }
        if (!ok) {
            s->ls_failed = true;
            break;
        }
        x[0] = xt0;
        x[1] = xt1;
        cost = ct;
        s->iters = it + 1;
        if (xi * nd < cfg->step_tol) {
            break;
        }
        if (it + 1 < cfg->iter_max) {
            cost = cost_ctx(cfg, &c, in, x[0], x[1] * wb, th_ref, om_ref, w1, w2, g, h);
        }
    }
    s->cost = cost;
    s->theta = mc_wrap_pi(x[0]);
    s->omega = x[1] * wb;
    out->theta = mc_wrap_pi(x[0] + s->omega * cfg->ts);
    out->omega = s->omega;
}

void mc_unop_adapt(mc_unop_t *s, const mc_angle_in_t *in, float theta, float omega)
{
    const mc_unop_cfg_t *cfg = &s->cfg;
    /* only while the injection is at least half its standstill magnitude (6.6): as it fades, the
     * inverter's dead time (its compensation's timing, an apparent inductance at small currents)
     * weighs more against it (brodatzki-35kw, realistic profile: +1.8 % at standstill, +4 % at
     * N1/2, +10 % at N1) */
    if (!(cfg->l_adapt > 0.0f) || !(fabsf(omega) <= 0.5f * cfg->omega_n1)) {
        return;
    }
    ctx_t c;
    jet_t r, y0, y1;
    make_ctx(s, in, &c);
    residual_jet(cfg, &c, in, theta, omega, false, &r);
    /* regressor: dr/d(l_scale) without the rotational term, dpsi/Ts of the model as given (the
     * rotational part would let l_scale explain an angle error: at speed both act along d) */
    rot_jet(in->i_ab_prev, theta, omega, 0.0f, false, &y0);
    rot_jet(in->i_ab, theta, omega, cfg->ts, false, &y1);
    mc_dq_t p0, p1;
    mc_flux_eval(&cfg->model, y0.v, &p0, NULL, NULL);
    mc_flux_eval(&cfg->model, y1.v, &p1, NULL, NULL);
    /* r and the regressor through the injection's band: white current noise enters both alike
     * (errors in the regressor bias LMS toward a smaller scale by the noise-to-signal power
     * ratio: -0.7 % at 0.02 A, -4 % at 0.05 A on the thesis motor); the band keeps the injection,
     * a tenth of the noise and none of the slow terms (back-EMF, load, angle errors). The d
     * components only: the injection excites the estimated d axis. */
    float v[2] = {r.v.d, (p1.d - p0.d) / cfg->ts};
    const float b0 = 0.5f * (1.0f - cfg->bp_a2);   /* the band-pass's b0 = kq norm = (1 - a2)/2 */
    for (int k = 0; k < 2; ++k) {
        float *z = s->bp_z[k];
        const float o = b0 * v[k] + z[0];
        z[0] = z[1] - cfg->bp_a1 * o;
        z[1] = -b0 * v[k] - cfg->bp_a2 * o;
        v[k] = o;
    }
    /* r = (s_true - l_scale) phi + ...: least squares with exponential forgetting (scalar RLS):
     * the step is normalised by the regressor's power summed at the forgetting rate, not by its
     * instantaneous square (normalised LMS, whose gain over a sine of amplitude 2 sqrt(p) averages
     * about 0.55: a time constant of ~18 ms for the 10 ms asked; the thesis motor at L x1.2
     * tripped loss_of_lock at 41 ms in 1 seed of 10) */
    s->ls_pow = (1.0f - cfg->l_adapt) * s->ls_pow + v[1] * v[1];
    const float ds = v[0] * v[1] / (s->ls_pow + cfg->l_adapt_p);
    const float ls = s->l_scale + ds;
    s->l_scale = (ls > MC_UNOP_LS_HI) ? MC_UNOP_LS_HI : ((ls >= MC_UNOP_LS_LO) ? ls : MC_UNOP_LS_LO);
}

void mc_unop_cfg_band(mc_unop_cfg_t *cfg, float f_hz)
{
    mc_biquad_t b;
    mc_biquad_init_bandpass(&b, f_hz, 2.0f, cfg->ts);
    cfg->bp_a1 = b.a1;
    cfg->bp_a2 = b.a2;
}
