/* Torque command -> current reference (thesis 2.5, Fig. 2.17).
 *
 * 1. MTPA point for |T| (2.24) or from the table, found by a bounded root search of the torque
 *    (2.8) along the curve; the search range stops at the current circle (2.21).
 * 2. If that point violates the voltage ellipse (2.20) at omega_e, field weakening: move along the
 *    ellipse boundary, id = id_fw(iq) from (2.26), to the iq that still gives |T|. This point meets
 *    the MTPA point exactly at base speed (2.25), so the reference is continuous there.
 * 3. If that needs more than i_max, take the circle/ellipse intersection (2.26): the most torque
 *    both limits allow (no MTPV branch: for the presets psi_pm/Ld > i_max).
 * The sign of T goes to iq only. Every search is a fixed-count Illinois iteration. */
#include "mc/torque_ref.h"

#include <math.h>

#include "mc/svpwm.h"

#define TREF_MAX_IT 32

typedef enum {
    TREF_MTPA_TORQUE,   /* torque along MTPA minus |T|; x = iq (analytic) or |I| (table)    */
    TREF_MTPA_CIRCLE,   /* |I|^2 - i_max^2 along MTPA; x = iq (analytic only)                */
    TREF_FW_TORQUE,     /* torque along the ellipse boundary minus |T|; x = iq              */
    TREF_FW_CIRCLE      /* |I|^2 - i_max^2 along the ellipse boundary; x = iq                */
} tref_fn_t;

typedef struct {
    const mc_tref_t *s;
    float torque;   /* |T| [N m]                                        */
    float omega;    /* |omega_e| [rad/s]                                 */
    float u_max;    /* [V]                                               */
    float id_cap;   /* MTPA id: field weakening never raises id above it */
} tref_ctx_t;

static float tref_torque(const mc_tref_t *s, mc_dq_t i)
{
    return (float)s->cfg.pole_pairs * mc_torque_pp(&s->cfg.mach, i);   /* (2.8) */
}

/* Largest id on or inside the ellipse for this iq; where the ellipse has no point at this iq
 * (omega Lq |iq| > u_max) the centre -psi_pm/Ld is the closest one can get. */
static float tref_fw_id(const tref_ctx_t *c, float iq)
{
    const mc_lin_params_t *p = &c->s->cfg.mach;
    float id = mc_fw_id_max(p, iq, c->omega, c->u_max);   /* (2.26) */
    if (isnan(id)) {
        id = -p->psi_pm / p->ld;
    }
    return id;
}

/* Whether the point i lies outside the voltage ellipse (2.20) at omega: tref_fw_id(c, i.q) < i.d.
 * Clearly inside, w^2 ((Ld id + psi)^2 + (Lq iq)^2) < 0.999 u_max^2, is decided with a few
 * multiplies; the 0.1 % margin (5e-4 of psi_pm in flux) is far above the rounding of either form,
 * so where the shortcut answers, the exact test (two divisions and a square root) would answer
 * the same. Near the boundary, at standstill, for u_max = 0 and for NaN the exact test decides. */
static bool tref_outside_ellipse(const tref_ctx_t *c, mc_dq_t i)
{
    const mc_lin_params_t *p = &c->s->cfg.mach;
    const float fd = p->ld * i.d + p->psi_pm;
    const float fq = p->lq * i.q;
    if (c->omega * c->omega * (fd * fd + fq * fq) < 0.999f * c->u_max * c->u_max) {
        return false;
    }
    return tref_fw_id(c, i.q) < i.d;
}

static mc_dq_t tref_point(const tref_ctx_t *c, tref_fn_t f, float x)
{
    mc_dq_t i;
    if (f == TREF_MTPA_TORQUE || f == TREF_MTPA_CIRCLE) {
        if (c->s->cfg.use_table) {
            return mc_mtpa_table_lookup(&c->s->cfg.table, x);
        }
        i.d = mc_mtpa_id(&c->s->cfg.mach, x);   /* (2.24) */
        i.q = x;
        return i;
    }
    i.d = tref_fw_id(c, x);
    if (i.d > c->id_cap) {
        i.d = c->id_cap;
    }
    i.q = x;
    return i;
}

static float tref_eval(const tref_ctx_t *c, tref_fn_t f, float x)
{
    const mc_dq_t i = tref_point(c, f, x);
    if (f == TREF_MTPA_TORQUE || f == TREF_FW_TORQUE) {
        return tref_torque(c->s, i) - c->torque;
    }
    return i.d * i.d + i.q * i.q - c->s->cfg.i_max * c->s->cfg.i_max;
}

/* Root of an increasing function on [lo, hi] by Illinois (regula falsi with halving). If the
 * root lies beyond hi, returns hi and sets *beyond. Bounded: TREF_MAX_IT evaluations. */
static float tref_solve(const tref_ctx_t *c, tref_fn_t f, float lo, float hi, float tol,
                        bool *beyond)
{
    float flo = tref_eval(c, f, lo);
    float fhi = tref_eval(c, f, hi);
    float x = lo;
    int side = 0;
    int k;

    *beyond = false;
    if (!(fhi > 0.0f)) {
        *beyond = (fhi < -tol);
        return hi;
    }
    if (!(flo < 0.0f)) {
        return lo;
    }
    for (k = 0; k < TREF_MAX_IT; k++) {
        float fx;
        x = (lo * fhi - hi * flo) / (fhi - flo);
        if (!(x > lo && x < hi)) {
            x = 0.5f * (lo + hi);
        }
        fx = tref_eval(c, f, x);
        if (fabsf(fx) <= tol || (hi - lo) <= 1.0e-6f * (fabsf(hi) + 1.0e-3f)) {
            break;
        }
        if (fx < 0.0f) {
            lo = x;
            flo = fx;
            if (side < 0) {
                fhi *= 0.5f;
            }
            side = -1;
        } else {
            hi = x;
            fhi = fx;
            if (side > 0) {
                flo *= 0.5f;
            }
            side = 1;
        }
    }
    return x;
}

void mc_tref_init(mc_tref_t *s, const mc_tref_cfg_t *cfg)
{
    s->cfg = *cfg;
    if (!(s->cfg.u_margin > 0.0f)) {
        s->cfg.u_margin = 0.0f;
    } else if (s->cfg.u_margin > MC_SVPWM_FUND_MAX) {
        s->cfg.u_margin = MC_SVPWM_FUND_MAX;   /* (2.14a): no modulator holds more */
    }
    if (!(s->cfg.i_max > 0.0f)) {
        s->cfg.i_max = 0.0f;
    }
    s->fw_active = false;
    s->i_limited = false;
    s->mtpa_valid = false;   /* new parameters: the cached MTPA point no longer holds */
    s->mtpa_torque = 0.0f;
    s->mtpa_i = (mc_dq_t){0.0f, 0.0f};
    s->mtpa_lim = s->mtpa_i;
    s->mtpa_limited = false;
    s->fw_did = 0.0f;
}

mc_dq_t mc_tref_fw_feedback(mc_tref_t *s, mc_dq_t r, bool u_limited, float omega_e, float vdc)
{
    const float i_max = s->cfg.i_max, ts = s->cfg.ts;
    const bool high = fabsf(omega_e) * s->cfg.mach.psi_pm > 0.5f * MC_1_SQRT3 * vdc;
    if (u_limited && high) {
        s->fw_did -= 100.0f * i_max * ts;
    } else {
        s->fw_did += 25.0f * i_max * ts;
    }
    s->fw_did = s->fw_did > 0.0f ? 0.0f : (s->fw_did < -i_max ? -i_max : s->fw_did);
    if (!(s->fw_did < 0.0f)) {
        return r;   /* NaN-safe: a NaN state never leaves here */
    }
    r.d += s->fw_did;
    if (r.d < -i_max) {
        r.d = -i_max;
    }
    const float q_room = sqrtf(fmaxf(i_max * i_max - r.d * r.d, 0.0f));
    r.q = r.q > q_room ? q_room : (r.q < -q_room ? -q_room : r.q);
    return r;
}

/* Step 1: MTPA point for |T| inside the circle (2.21), (2.24). */
static void tref_mtpa(mc_tref_t *s, const tref_ctx_t *c)
{
    const float i_max = s->cfg.i_max;
    const float t_tol = 1.0e-5f * (c->torque + 1.0f);
    const float i_tol = 1.0e-5f * (i_max * i_max + 1.0f);
    float x_hi = i_max;
    float x;
    bool beyond;
    mc_dq_t i;

    if (s->cfg.use_table && s->cfg.table.i_max < x_hi) {
        x_hi = s->cfg.table.i_max;
    }
    x = tref_solve(c, TREF_MTPA_TORQUE, 0.0f, x_hi, t_tol, &beyond);
    s->mtpa_limited = beyond;
    i = tref_point(c, TREF_MTPA_TORQUE, x);
    if (!s->cfg.use_table && i.d * i.d + i.q * i.q > i_max * i_max) {
        /* analytic search runs on iq, so its range may overshoot the circle: stop on it */
        x = tref_solve(c, TREF_MTPA_CIRCLE, 0.0f, x, i_tol, &beyond);
        i = tref_point(c, TREF_MTPA_CIRCLE, x);
        s->mtpa_limited = true;
    }
    s->mtpa_i = i;
    /* what the final step makes of it when no field weakening follows (rounding in the
     * searches must not leave the circle) */
    s->mtpa_lim = mc_limit_current_circle(i, i_max);
    s->mtpa_torque = c->torque;
    s->mtpa_valid = true;
}

/* Steps 2 and 3, for an MTPA point outside the voltage ellipse: move along the ellipse
 * boundary, and onto the circle/ellipse intersection if the torque needs more than i_max. */
static mc_dq_t tref_fw(mc_tref_t *s, tref_ctx_t *c, float torque)
{
    const float i_max = s->cfg.i_max;
    const float t_tol = 1.0e-5f * (fabsf(torque) + 1.0f);
    const float i_tol = 1.0e-5f * (i_max * i_max + 1.0f);
    mc_dq_t i = s->mtpa_i;
    const float iq_m = i.q;
    float x;
    bool beyond;

    c->id_cap = i.d;
    if (tref_fw_id(c, 0.0f) < -i_max) {
        /* above the top speed the circle and ellipse do not meet: keep all current on d */
        i.d = -i_max;
        i.q = 0.0f;
        s->i_limited = true;
    } else {
        x = tref_solve(c, TREF_FW_TORQUE, 0.0f, iq_m, t_tol, &beyond);
        s->i_limited = s->i_limited || beyond;
        i = tref_point(c, TREF_FW_TORQUE, x);
        if (i.d * i.d + i.q * i.q > i_max * i_max) {
            /* 3. circle/ellipse intersection (2.26) */
            x = tref_solve(c, TREF_FW_CIRCLE, 0.0f, x, i_tol, &beyond);
            i = tref_point(c, TREF_FW_CIRCLE, x);
            s->i_limited = true;
        }
    }
    /* rounding in the searches must not leave the circle */
    return mc_limit_current_circle(i, i_max);
}

mc_dq_t mc_tref_step(mc_tref_t *s, float torque, float omega_e, float vdc)
{
    tref_ctx_t c;
    mc_dq_t i;
    const bool neg = (torque < 0.0f);

    c.s = s;
    c.id_cap = 0.0f;
    c.torque = fabsf(torque);
    if (isnan(c.torque)) {
        c.torque = 0.0f;
    }
    c.omega = fabsf(omega_e);
    c.u_max = (vdc > 0.0f) ? s->cfg.u_margin * vdc * MC_1_SQRT3 : 0.0f;

    /* 1. MTPA point inside the circle (2.21), (2.24). It depends on |T| and the parameters only,
     *    and |T| repeats between speed-loop updates (held for sc_decimation periods) or stays put
     *    in torque mode: solve only when it changed. The search is deterministic, so the reused
     *    point is the very one a new search would find. */
    if (!s->mtpa_valid || s->mtpa_torque != c.torque) {
        tref_mtpa(s, &c);
    }
    s->i_limited = s->mtpa_limited;

    /* 2. Field weakening (2.20), (2.26), if the MTPA point violates the ellipse; otherwise the
     *    MTPA point after the final circle limit, which was kept with it. */
    s->fw_active = tref_outside_ellipse(&c, s->mtpa_i);
    i = s->fw_active ? tref_fw(s, &c, torque) : s->mtpa_lim;
    if (neg) {
        i.q = -i.q;
    }
    return i;
}
