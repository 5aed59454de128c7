#include "mc/injection.h"
#include <math.h>
#include "mc/sincos.h"

void mc_inj_init(mc_inj_t *s, const mc_inj_cfg_t *cfg)
{
    s->cfg = *cfg;
    s->dphase = cfg->f_hz * cfg->ts;
    mc_inj_reset(s);
}

void mc_inj_reset(mc_inj_t *s)
{
    s->phase = 0.0f;
    s->magnitude = 0.0f;
}

float mc_inj_magnitude(const mc_inj_cfg_t *cfg, float omega_hat)
{
    const float w = fabsf(omega_hat);
    if (cfg->kind == MC_INJ_OFF || cfg->omega_n1 <= 0.0f || w >= cfg->omega_n1) {
        return 0.0f;
    }
    return cfg->v1 * (cfg->omega_n1 - w) / cfg->omega_n1;   /* (6.6) */
}

float mc_inj_step(mc_inj_t *s, float omega_hat)
{
    s->magnitude = mc_inj_magnitude(&s->cfg, omega_hat);
    /* The voltage is applied over the next period: take the waveform at that period's centre so
     * the period average follows the intended sine. */
    float ph = s->phase + 0.5f * s->dphase;
    ph -= floorf(ph);
    float v = 0.0f;
    if (s->cfg.kind == MC_INJ_SINE) {
        v = s->magnitude * mc_sincos(MC_2PI * ph).s;
    } else if (s->cfg.kind == MC_INJ_RECT) {
        v = ph < 0.5f ? s->magnitude : -s->magnitude;
    }
    s->phase += s->dphase;
    s->phase -= floorf(s->phase);
    return v;
}
