/* Entry into field weakening at speed (mc/fw_entry.h, (F.1)-(F.3)). */
#include "mc/fw_entry.h"

#include <math.h>

bool mc_fwe_step(mc_dq_t psi, mc_dq_t i, mc_dq_t u_now, float rs, float omega, float ts, float u_max,
                 float u_req, bool started, mc_dq_t *u_out)
{
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
     * a braking q current the loop would otherwise have to remove at its voltage limit) */
    if (!(need > u_max) && (!started || !lags)) {
        return false;
    }
    /* (F.2) with Rs: the radius that counts is need / |omega|; held: tangential (F.4). In
     * discrete time the last step lands on rho: the radial part moves the flux at most the
     * (need - u_max) / |omega| left in one period (else it overshoots rho by ~1 % a period, the
     * continuous law's radial speed vanishing only at rho itself) */
    float cb = need > u_max ? u_max / need : 1.0f;
    float sb = sqrtf(fmaxf(1.0f - cb * cb, 0.0f));
    const float sb_land = (need - u_max) / (fabsf(omega) * ts * u_max);
    if (sb > sb_land) {
        sb = sb_land > 0.0f ? sb_land : 0.0f;
        cb = sqrtf(1.0f - sb * sb);
    }
    /* (F.3): the flux's direction turned by sign(omega) (pi / 2 + beta), without a libm call (the
     * same bits on every target) */
    const float ed = p.d / r, eq = p.q / r;
    /* (F.2) plans with u_max: more there would take the flux past rho (by 3 % with the
     * hexagon's); held, the more the faster the lag goes */
    const float m = need > u_max || !(u_req > u_max) ? u_max : u_req;
    *u_out = (mc_dq_t){m * (-sb * ed - s * cb * eq), m * (s * cb * ed - sb * eq)};
    return true;
}
