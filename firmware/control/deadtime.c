/* Dead-time compensation: during the dead time the freewheeling diode decides the phase
 * voltage, so a phase sourcing current (i > 0) loses t_dead/T_pwm of its duty and a sinking one
 * gains it. Adding it back with a sign that is linear within +-i_band avoids chattering from
 * current ripple and measurement noise around the zero crossing. */
#include "mc/deadtime.h"

void mc_dtc_init(mc_dtc_t *s, const mc_dtc_cfg_t *cfg)
{
    s->cfg = *cfg;
    /* the one division, here instead of every period */
    s->k = (cfg->t_pwm > 0.0f) ? cfg->t_dead / cfg->t_pwm : 0.0f;
}

static float dtc_sgn_smooth(float i, float band)
{
    float x;
    if (!(band > 0.0f)) {
        return (i > 0.0f) ? 1.0f : ((i < 0.0f) ? -1.0f : 0.0f);
    }
    x = i / band;
    if (x > 1.0f) {
        x = 1.0f;
    } else if (x < -1.0f) {
        x = -1.0f;
    }
    return x;
}

static float dtc_clamp01(float d)
{
    if (d > 1.0f) {
        return 1.0f;
    }
    if (d < 0.0f) {
        return 0.0f;
    }
    return d;
}

void mc_dtc_apply(const mc_dtc_t *s, mc_duty_t *duty, mc_abc_t i_abc)
{
    const float k = s->k;
    if (!s->cfg.enable || !(s->cfg.t_pwm > 0.0f)) {
        return;
    }
    duty->a = dtc_clamp01(duty->a + k * dtc_sgn_smooth(i_abc.a, s->cfg.i_band));
    duty->b = dtc_clamp01(duty->b + k * dtc_sgn_smooth(i_abc.b, s->cfg.i_band));
    duty->c = dtc_clamp01(duty->c + k * dtc_sgn_smooth(i_abc.c, s->cfg.i_band));
}
