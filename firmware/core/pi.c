/* PI controller with output limits and anti-windup by conditional integration + clamp. */
#include "mc/pi.h"

void mc_pi_init(mc_pi_t *s, const mc_pi_cfg_t *cfg)
{
    s->cfg = *cfg;
    mc_pi_reset(s, 0.0f);
}

void mc_pi_reset(mc_pi_t *s, float integ)
{
    s->integ = integ;
    s->saturated = false;
}

float mc_pi_step_lim(mc_pi_t *s, float err, float ff, float lo, float hi)
{
    if (lo > hi) {
        /* inconsistent limits (e.g. a voltage budget that went negative): collapse, don't flip */
        float m = 0.5f * (lo + hi);
        lo = m;
        hi = m;
    }
    float p = s->cfg.kp * err;
    float integ = s->integ + s->cfg.ki * s->cfg.ts * err;   /* backward Euler: uses e(k) */
    float u = ff + p + integ;

    /* Conditional integration: while the output is at a limit and the error pushes further out,
     * the integrator only charges up to the point where the output just reaches the limit (never
     * beyond, never backwards). It then holds no excess when the error reverses, so recovery
     * starts on the next sample, and the output still settles exactly on the limit. */
    if (u > hi && err > 0.0f) {
        float room = hi - ff - p;
        integ = (integ < room) ? integ : room;
        integ = (integ > s->integ) ? integ : s->integ;
    } else if (u < lo && err < 0.0f) {
        float room = lo - ff - p;
        integ = (integ > room) ? integ : room;
        integ = (integ < s->integ) ? integ : s->integ;
    }
    /* Clamp against a limit that shrank while the integrator was charged: the integrator gives
     * up its share of the excess over the limit, counted with the feed-forward (the output is
     * ff + p + integ, so a clamp to [lo, hi] alone would let it hold up to |ff| of excess and
     * delay the recovery by that much), but the feed-forward never pushes it across zero: what
     * it holds below zero is its own estimate of the disturbance, not windup. */
    if (integ > 0.0f && ff + integ > hi) {
        const float room = hi - ff;
        integ = (room > 0.0f) ? room : 0.0f;
    } else if (integ < 0.0f && ff + integ < lo) {
        const float room = lo - ff;
        integ = (room < 0.0f) ? room : 0.0f;
    }
    s->integ = integ;
    u = ff + p + integ;

    s->saturated = (u >= hi) || (u <= lo);   /* at a limit: the caller's decoupling may care */
    if (u > hi) {
        u = hi;
    } else if (u < lo) {
        u = lo;
    }
    return u;
}

float mc_pi_step(mc_pi_t *s, float err, float ff)
{
    return mc_pi_step_lim(s, err, ff, s->cfg.out_min, s->cfg.out_max);
}
