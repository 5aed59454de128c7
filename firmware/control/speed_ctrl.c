/* Speed loop: PI on the mechanical speed error -> torque command, symmetric torque limit,
 * run every `decimation` current periods and held in between. */
#include "mc/speed_ctrl.h"

static int sc_decimation(const mc_sc_cfg_t *cfg)
{
    return (cfg->decimation >= 1) ? cfg->decimation : 1;
}

void mc_sc_init(mc_sc_t *s, const mc_sc_cfg_t *cfg)
{
    mc_pi_cfg_t pc;
    float tmax = (cfg->torque_max > 0.0f) ? cfg->torque_max : 0.0f;
    s->cfg = *cfg;
    s->cfg.torque_max = tmax;
    s->cfg.decimation = sc_decimation(cfg);
    pc.kp = cfg->kp;
    pc.ki = cfg->ki;
    pc.ts = cfg->ts;   /* already the speed-loop period (decimation included) */
    pc.out_min = -tmax;
    pc.out_max = tmax;
    mc_pi_init(&s->pi, &pc);
    mc_sc_reset(s, 0.0f);
}

void mc_sc_reset(mc_sc_t *s, float torque0)
{
    const float tmax = s->cfg.torque_max;
    if (torque0 > tmax) {
        torque0 = tmax;
    } else if (torque0 < -tmax) {
        torque0 = -tmax;
    }
    /* Preloading the integrator makes the hand-over bumpless (e.g. from a torque-mode start). */
    mc_pi_reset(&s->pi, torque0);
    s->torque_ref = torque0;
    s->count = 0;
}

float mc_sc_step(mc_sc_t *s, float omega_ref_m, float omega_m)
{
    /* Update on the first call after reset so a new command acts without waiting N periods. */
    if (s->count <= 0) {
        s->torque_ref = mc_pi_step(&s->pi, omega_ref_m - omega_m, 0.0f);
        s->count = s->cfg.decimation;
    }
    s->count--;
    return s->torque_ref;
}
