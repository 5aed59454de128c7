/* Current controller in a given (rotor or estimated) d-q frame (thesis Fig. 2.16).
 *
 * Plant (2.6)/(2.7) in the rotor frame, Rs neglected in the coupling terms:
 *   Ld did/dt = ud - Rs id + w Lq iq
 *   Lq diq/dt = uq - Rs iq - w (Ld id + psi_pm)
 * The feed-forward cancels the speed-dependent terms, so each axis is left as R + sL and a PI with
 * kp = wb L, ki = wb R cancels the pole: closed loop wb / (s + wb). */
#include "mc/current_ctrl.h"

#include <math.h>

/* Wide enough never to bind: the per-call voltage limits in mc_cc_step are the real ones. */
#define MC_CC_UNBOUNDED 1.0e6f

void mc_cc_cfg_from_bandwidth(mc_cc_cfg_t *cfg, float fbw_hz, float rs, float ld, float lq,
                              float psi_pm, float ts)
{
    const float wb = MC_2PI * fbw_hz;
    cfg->kp_d = wb * ld;
    cfg->ki_d = wb * rs;
    cfg->kp_q = wb * lq;
    cfg->ki_q = wb * rs;
    cfg->ts = ts;
    cfg->ld = ld;
    cfg->lq = lq;
    cfg->psi_pm = psi_pm;
    cfg->decouple = true;
}

void mc_cc_init(mc_cc_t *s, const mc_cc_cfg_t *cfg)
{
    mc_pi_cfg_t pc;
    s->cfg = *cfg;
    pc.ts = cfg->ts;
    pc.out_min = -MC_CC_UNBOUNDED;
    pc.out_max = MC_CC_UNBOUNDED;
    pc.kp = cfg->kp_d;
    pc.ki = cfg->ki_d;
    mc_pi_init(&s->pi_d, &pc);
    pc.kp = cfg->kp_q;
    pc.ki = cfg->ki_q;
    mc_pi_init(&s->pi_q, &pc);
    mc_cc_reset(s);
}

void mc_cc_reset(mc_cc_t *s)
{
    mc_pi_reset(&s->pi_d, 0.0f);
    mc_pi_reset(&s->pi_q, 0.0f);
    s->u.d = 0.0f;
    s->u.q = 0.0f;
    s->limited = false;
}

/* The loop with its decoupling feed-forward given (0 when not decoupling). */
static mc_dq_t cc_core(mc_cc_t *s, mc_dq_t i_ref, mc_dq_t i_meas, float ff_d, float ff_q, float u_max, bool res_p)
{
    mc_dq_t u;
    float uq_max;

    /* NaN-safe: a bad limit must not open the clamp. */
    if (!(u_max > 0.0f)) {
        u_max = 0.0f;
    }
    /* d axis first: it sets the flux (field weakening relies on it), q gets the rest of the
     * circle. Limits go into the PI so its conditional integration stops the wind-up. */
    /* ... but not all of it: q keeps the share its back-EMF feed-forward needs (up to 95 % of
     * the circle). Without that reserve, a braking q current at the voltage limit (a rotor caught
     * above base speed) makes the decoupling -w Lq iq take the circle for d, q loses its
     * back-EMF and iq runs away further. */
    /* With the machine's own back-EMF as the feed-forward (a flux map) that share leaves q
     * nothing to correct its error with: the reserve then covers the proportional demand too. */
    const float dem_q = res_p ? ff_q + s->cfg.kp_q * (i_ref.q - i_meas.q) : ff_q;
    const float res_q = fminf(fabsf(dem_q), 0.95f * u_max);
    const float ud_max = sqrtf(fmaxf(u_max * u_max - res_q * res_q, 0.0f));
    u.d = mc_pi_step_lim(&s->pi_d, i_ref.d - i_meas.d, ff_d, -ud_max, ud_max);
    uq_max = u_max * u_max - u.d * u.d;
    uq_max = (uq_max > 0.0f) ? sqrtf(uq_max) : 0.0f;
    u.q = mc_pi_step_lim(&s->pi_q, i_ref.q - i_meas.q, ff_q, -uq_max, uq_max);

    s->u = u;
    s->limited = s->pi_d.saturated || s->pi_q.saturated;
    return u;
}

/* Measured currents, not references, in the decoupling: it cancels the plant's own coupling, so
 * the axes stay decoupled during transients as well (the references would only do so in steady
 * state). (2.7) in steady state: u_d = R i_d - w psi_q, u_q = R i_q + w psi_d. */
mc_dq_t mc_cc_step(mc_cc_t *s, mc_dq_t i_ref, mc_dq_t i_meas, float omega_e, float u_max)
{
    float ff_d = 0.0f, ff_q = 0.0f;
    if (s->cfg.decouple) {
        ff_d = -omega_e * s->cfg.lq * i_meas.q;
        ff_q = omega_e * (s->cfg.ld * i_meas.d + s->cfg.psi_pm);
    }
    return cc_core(s, i_ref, i_meas, ff_d, ff_q, u_max, false);
}

mc_dq_t mc_cc_step_psi(mc_cc_t *s, mc_dq_t i_ref, mc_dq_t i_meas, mc_dq_t psi_meas, float omega_e, float u_max)
{
    if (!(fabsf(psi_meas.d) < 1.0e6f && fabsf(psi_meas.q) < 1.0e6f)) {
        return mc_cc_step(s, i_ref, i_meas, omega_e, u_max);
    }
    float ff_d = 0.0f, ff_q = 0.0f;
    if (s->cfg.decouple) {
        ff_d = -omega_e * psi_meas.q;
        ff_q = omega_e * psi_meas.d;
    }
    return cc_core(s, i_ref, i_meas, ff_d, ff_q, u_max, true);
}
