/* Dead-time compensation in the modulator: each phase duty gets +sgn(i) * t_dead/T_pwm, with a
 * smooth sign (linear within +-i_band) so it does not chatter through zero current. */
#ifndef MC_DEADTIME_H
#define MC_DEADTIME_H
#include "mc/types.h"
#include "mc/svpwm.h"

typedef struct {
    float t_dead;   /* [s]                                   */
    float t_pwm;    /* PWM period [s]                        */
    float i_band;   /* [A] half-width of the linear zone     */
    bool  enable;
} mc_dtc_cfg_t;

typedef struct {
    mc_dtc_cfg_t cfg;
    float k;        /* t_dead / t_pwm: the duty one dead time is worth (set by init) */
} mc_dtc_t;

void mc_dtc_init(mc_dtc_t *s, const mc_dtc_cfg_t *cfg);

/* sign of i, linear within +-band (hard sign for band <= 0) */
static inline float mc_dtc_sgn_smooth(float i, float band)
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

static inline float mc_dtc_clamp01(float d)
{
    if (d > 1.0f) {
        return 1.0f;
    }
    if (d < 0.0f) {
        return 0.0f;
    }
    return d;
}

/* Adjusts duties in place (clamped to [0, 1]) from the phase currents expected during the
 * period the duties will be applied in. Inline: it sits at the end of the ISR's chain from
 * the current samples to the duty registers, and is three multiply-adds. */
static inline void mc_dtc_apply(const mc_dtc_t *s, mc_duty_t *duty, mc_abc_t i_abc)
{
    const float k = s->k;
    if (!s->cfg.enable || !(s->cfg.t_pwm > 0.0f)) {
        return;
    }
    duty->a = mc_dtc_clamp01(duty->a + k * mc_dtc_sgn_smooth(i_abc.a, s->cfg.i_band));
    duty->b = mc_dtc_clamp01(duty->b + k * mc_dtc_sgn_smooth(i_abc.b, s->cfg.i_band));
    duty->c = mc_dtc_clamp01(duty->c + k * mc_dtc_sgn_smooth(i_abc.c, s->cfg.i_band));
}

#endif
