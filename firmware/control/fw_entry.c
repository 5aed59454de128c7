/* Entry into field weakening at speed (mc/fw_entry.h, (F.1)-(F.3)). */
#include "mc/fw_entry.h"

#include <math.h>

#include "mc/svpwm.h"
#include "mc/transforms.h"

/* what the modulator gives in the rotor-frame direction (cos, sin) = (ed, eq): the hexagon's
 * reach there (sc: the rotation into the stator frame), or the circle u_max without one */
static float reach(float ed, float eq, float u_max, float vdc, mc_sincos_t sc)
{
    if (!(vdc > 0.0f)) {
        return u_max;
    }
    return mc_svpwm_reach(mc_park_inv((mc_dq_t){ed, eq}, sc), vdc);
}

/* the rotor-frame unit vector at sign(omega) (pi / 2 + beta) from the flux's (ed, eq) (F.3) */
static mc_dq_t ahead(float ed, float eq, float s, float cb, float sb)
{
    return (mc_dq_t){-sb * ed - s * cb * eq, s * cb * ed - sb * eq};
}

void mc_fwe_reset(mc_fwe_t *s)
{
    s->active = false;
    s->n = 0u;
}

void mc_fwe_begin(mc_fwe_t *s)
{
    s->active = true;
    s->n = 0u;
}

mc_fwe_status_t mc_fwe_step(mc_fwe_t *s, const mc_fwe_cfg_t *c, const mc_fwe_in_t *in, mc_dq_t *u)
{
    if (!s->active) {
        return MC_FWE_OFF;
    }
    bool on = mc_fwe_law(c, in, s->n > 0u, u);
    if (on && (!(in->i.d * in->i.d + in->i.q * in->i.q < c->i_stop * c->i_stop) ||
               (float)s->n * c->ts * fabsf(in->omega) > MC_2PI)) {
        on = false;
    }
    s->active = on;
    if (on) {
        s->n++;
        return MC_FWE_RUNNING;
    }
    return s->n > 0u ? MC_FWE_ENDED : MC_FWE_OFF;
}

bool mc_fwe_law(const mc_fwe_cfg_t *c, const mc_fwe_in_t *in, bool started, mc_dq_t *u_out)
{
    const mc_dq_t psi = in->psi, i = in->i, u_now = in->u_now;
    const float rs = c->rs, omega = in->omega, ts = c->ts, u_max = in->u_land;
    const float vdc = c->overmod ? in->vdc : 0.0f;
    const mc_sincos_t sc = in->sc;
    *u_out = u_now;
    /* the flux in the middle of the period the result acts in, 1.5 periods on, under the
     * voltage already latched (Euler: omega ts is ~0.08 rad at the thesis motor's 1500 rpm and
     * 10 kHz); one period on, the law overshot rho by 2-3 % (the result acts a period late) */
    const float h = 1.5f * ts;
    const mc_dq_t p = {psi.d + h * (u_now.d - rs * i.d + omega * psi.q),
                       psi.q + h * (u_now.q - rs * i.q - omega * psi.d)};
    const float r = sqrtf(p.d * p.d + p.q * p.q);
    const float s = omega < 0.0f ? -1.0f : 1.0f;
    if (!(u_max > 0.0f) || !(r > 0.0f) || !isfinite(omega * r)) {
        return false;
    }
    /* the voltage that would hold it, |Rs i + j omega psi| (2.7): Rs i of a braking, field-weakening
     * current points against j omega psi and lets a flux a few per cent beyond rho be held */
    const float hd = rs * i.d - omega * p.q, hq = rs * i.q + omega * p.d;
    const float need = sqrtf(hd * hd + hq * hq);
    /* the lag behind the d axis, as a test on the flux's components: phi > MC_FWE_LAG_END */
    const bool lags = -s * p.q > MC_FWE_TAN_LAG_END * p.d || !(p.d > 0.0f);
    /* never started where the flux can be held; done once it can and its lag is gone (the lag is
     * a braking q current the loop would otherwise have to remove at its voltage limit), or at
     * once without overmodulation (no voltage beyond the held flux's to take the lag back) */
    if (!(need > u_max) && (!started || !lags || !(vdc > 0.0f))) {
        return false;
    }
    /* (F.2) with Rs: the radius that counts is need / |omega|, and the voltage that moves the
     * flux is what the modulator gives in the vector's direction, U (the hexagon's reach,
     * overmodulation): cos(beta) = U / need. U depends on the direction: two passes, the first
     * with u_max. Held: tangential (F.4). In discrete time the last step lands on rho: the
     * radial part moves the flux at most the (need - u_max) / |omega| left in one period (else
     * it overshoots rho by ~1 % a period, the continuous law's radial speed vanishing only at
     * rho itself). The (F.3) direction is formed without a libm call (the same bits on every
     * target). */
    const float ed = p.d / r, eq = p.q / r;
    float m = u_max;
    mc_dq_t e = {0.0f, 0.0f};
    for (int pass = 0; pass < 2; ++pass) {
        float cb = need > m ? m / need : 1.0f;
        float sb = sqrtf(fmaxf(1.0f - cb * cb, 0.0f));
        const float sb_land = (need - u_max) / (fabsf(omega) * ts * m);
        if (sb > sb_land) {
            sb = sb_land > 0.0f ? sb_land : 0.0f;
            cb = sqrtf(1.0f - sb * sb);
        }
        e = ahead(ed, eq, s, cb, sb);
        m = reach(e.d, e.q, u_max, vdc, sc);
    }
    *u_out = (mc_dq_t){m * e.d, m * e.q};
    return true;
}
