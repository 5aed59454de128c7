/* Angle-tracking PLL: PI + integrator (3.9), speed feed-forward and filtered speed output as in
 * thesis section 6.5 / Figure 6.9. */
#include "mc/pll.h"

#include "mc/angle.h"

void mc_pll_init(mc_pll_t *s, const mc_pll_cfg_t *cfg)
{
    s->cfg = *cfg;
    mc_lpf1_init(&s->speed_lpf, cfg->speed_fc_hz, cfg->ts, 0.0f);
    mc_pll_reset(s, 0.0f, 0.0f);
}

void mc_pll_reset(mc_pll_t *s, float theta, float omega)
{
    s->theta = mc_wrap_pi(theta);
    /* all of the initial speed goes into the integrator: with no feed-forward it has to hold it */
    s->integ = omega;
    s->omega = omega;
    mc_lpf1_reset(&s->speed_lpf, omega);
    s->omega_filt = omega;
}

void mc_pll_step(mc_pll_t *s, float theta_in, float omega_ff)
{
    /* Integrator (forward Euler): theta is the estimate for this sample, predicted with the
     * previous speed. Two integrations in the loop give zero error to an angle ramp (3.9). */
    s->theta = mc_wrap_pi(s->theta + s->omega * s->cfg.ts);
    /* the error goes through the wrap helper so a jump from +pi to -pi is a small error */
    float e = mc_wrap_pi(theta_in - s->theta);
    s->integ += s->cfg.ki * s->cfg.ts * e;
    /* with feed-forward the PI only has to supply the feed-forward's error, so it need not
     * build an error to follow acceleration */
    s->omega = omega_ff + s->cfg.kp * e + s->integ;
    s->omega_filt = mc_lpf1_step(&s->speed_lpf, s->omega);
}
