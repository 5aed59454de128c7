/* Angle source "unop": the Newton-based estimator (thesis ch. 6, mc/unop.h) followed by the PLL
 * as a filter with the estimated speed as feed-forward (Fig. 6.9). The controller uses the PLL's
 * angle and filtered speed; the raw estimate is the diagnostic. Needs the HF injection (6.4)
 * at low speed. */
#include "mc/angle_source.h"
#include "mc/pll.h"
#include "mc/unop.h"

typedef struct {
    mc_unop_t unop;
    mc_pll_t pll;
    mc_angle_out_t raw;
} src_unop_t;

MC_ANGLE_SRC_FITS(src_unop_t);

static void unop_init(mc_angle_src_state_t *st, const mc_angle_src_cfg_t *c)
{
    src_unop_t *s = (src_unop_t *)(void *)st;
    mc_unop_cfg_t u;
    mc_unop_cfg_default(&u);
    u.ts = c->ts;
    u.rs = c->rs;
    u.model = c->model;
    u.iter_max = c->iter_max;
    u.step_tol = c->step_tol;
    u.k1 = c->k1;
    u.k2 = c->k2;
    u.omega_n1 = c->omega_n1;
    u.omega_base = c->omega_base;
    u.mid_sample = c->mid_sample;
    u.reg_predicted = c->reg_predicted;
    mc_unop_init(&s->unop, &u);
    /* critically damped PLL (3.9) */
    const float w = MC_2PI * c->pll_bw_hz;
    const mc_pll_cfg_t pc = {.kp = 2.0f * w, .ki = w * w, .ts = c->ts, .speed_fc_hz = c->pll_speed_fc_hz};
    mc_pll_init(&s->pll, &pc);
    s->raw = (mc_angle_out_t){0.0f, 0.0f};
}

static void unop_reset(mc_angle_src_state_t *st, float theta, float omega)
{
    src_unop_t *s = (src_unop_t *)(void *)st;
    mc_unop_reset(&s->unop, theta, omega);
    /* like the estimator: the PLL's next prediction lands on theta; the speed comes in as the
     * estimator's feed-forward, so the integrator holds none of it (mc/pll.h) */
    mc_pll_reset(&s->pll, theta - omega * s->pll.cfg.ts, omega);
    s->pll.integ = 0.0f;
    s->raw = (mc_angle_out_t){theta, omega};
}

static void unop_step(mc_angle_src_state_t *st, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    src_unop_t *s = (src_unop_t *)(void *)st;
    mc_unop_step(&s->unop, in, &s->raw);
    mc_pll_step(&s->pll, s->raw.theta, s->raw.omega);
    out->theta = s->pll.theta;
    out->omega = s->pll.omega_filt;
}

static void unop_diag(const mc_angle_src_state_t *st, mc_angle_diag_t *d)
{
    const src_unop_t *s = (const src_unop_t *)(const void *)st;
    *d = (mc_angle_diag_t){.theta_raw = s->raw.theta, .omega_raw = s->raw.omega, .iters = s->unop.iters,
                           .cost = s->unop.cost, .cond = s->unop.cond};
}

const mc_angle_src_desc_t mc_angle_src_unop = {
    .name = "unop", .needs_injection = true,
    .init = unop_init, .reset = unop_reset, .step = unop_step, .diag = unop_diag,
};
