/* Angle source "unop": the Newton-based estimator (thesis ch. 6, mc/unop.h) followed by the PLL
 * as a filter with the estimated speed as feed-forward (Fig. 6.9). The controller uses the PLL's
 * angle and filtered speed; the raw estimate is the diagnostic and what the loss-of-lock checks
 * compare. Needs the HF injection (6.4) at low speed; needs the flux map with
 * estimator.model = fluxmap. Parameters: estimator.* and injection.n1_rpm (mc/params_table.h). */
#include "mc/angle_source.h"
#include "mc/params.h"
#include "mc/pll.h"
#include "mc/unop.h"

#define RPM_TO_RAD_S (MC_2PI / 60.0f)

typedef struct {
    mc_unop_cfg_t unop;
    mc_pll_cfg_t pll;
} src_unop_cfg_t;

typedef struct {
    mc_unop_t unop;
    mc_pll_t pll;
    mc_angle_out_t raw;
} src_unop_t;

MC_ANGLE_SRC_CFG_FITS(src_unop_cfg_t);
MC_ANGLE_SRC_FITS(src_unop_t);

static bool unop_build(const mc_params_t *p, float rs, const mc_flux_model_t *model, mc_angle_src_cfg_t *cfg,
                       mc_param_err_t *err)
{
    (void)err;   /* the table's ranges and the drive's model check cover everything it reads */
    *cfg = (mc_angle_src_cfg_t){0};
    src_unop_cfg_t *c = (src_unop_cfg_t *)(void *)cfg;
    const float pp = (float)p->motor_pole_pairs;
    mc_unop_cfg_default(&c->unop);
    c->unop.ts = p->control_ts_s;
    c->unop.rs = rs;
    c->unop.model = *model;
    c->unop.iter_max = (int)p->estimator_iter_max;
    c->unop.step_tol = p->estimator_step_tol;
    c->unop.k1 = p->estimator_k1;
    c->unop.k2 = p->estimator_k2;
    c->unop.omega_n1 = p->injection_n1_rpm * RPM_TO_RAD_S * pp;
    c->unop.omega_base = p->estimator_speed_scale_rpm * RPM_TO_RAD_S * pp;
    c->unop.mid_sample = p->estimator_mid_sample != 0;
    c->unop.reg_predicted = p->estimator_reg_predicted != 0;
    /* the inductance scale adapts while the injection excites it: one rate per period from the
     * time constant; the regressor power is floored at the injection's half magnitude squared,
     * so a weak excitation moves it slowly */
    const bool adapt = p->injection_kind != MC_CHOICE_injection_kind_off && p->estimator_l_adapt_s > 0.0f;
    c->unop.l_adapt = adapt ? p->control_ts_s / (p->estimator_l_adapt_s + p->control_ts_s) : 0.0f;
    c->unop.l_adapt_p = 0.25f * p->injection_v1_v * p->injection_v1_v;
    mc_unop_cfg_band(&c->unop, p->injection_f_hz);
    /* critically damped PLL (3.9) */
    const float w = MC_2PI * p->estimator_pll_bw_hz;
    c->pll = (mc_pll_cfg_t){.kp = 2.0f * w, .ki = w * w, .ts = p->control_ts_s, .speed_fc_hz = p->estimator_pll_speed_fc_hz};
    return true;
}

static void unop_init(mc_angle_src_state_t *st, const mc_angle_src_cfg_t *cfg)
{
    src_unop_t *s = (src_unop_t *)(void *)st;
    const src_unop_cfg_t *c = (const src_unop_cfg_t *)(const void *)cfg;
    mc_unop_init(&s->unop, &c->unop);
    mc_pll_init(&s->pll, &c->pll);
    s->raw = (mc_angle_out_t){0.0f, 0.0f};
}

/* Running: the solver takes its whole configuration (injection.n1_rpm, where K1, K2 fade out, is
 * RUNTIME); so does the PLL, whose bandwidth and speed filter follow the speed loop's rules
 * (control.speed_bw_hz, i_max_a, injection.v1_v are RUNTIME): new coefficients, the states kept,
 * so that a new gain or corner moves no output. */
static void unop_retune(mc_angle_src_state_t *st, const mc_angle_src_cfg_t *cfg)
{
    src_unop_t *s = (src_unop_t *)(void *)st;
    const src_unop_cfg_t *c = (const src_unop_cfg_t *)(const void *)cfg;
    mc_unop_retune(&s->unop, &c->unop);
    if (c->pll.speed_fc_hz != s->pll.cfg.speed_fc_hz) {
        const mc_lpf1_t kept = s->pll.speed_lpf;
        mc_lpf1_init(&s->pll.speed_lpf, c->pll.speed_fc_hz, c->pll.ts, kept.y);
        s->pll.speed_lpf.x1 = kept.x1;
    }
    s->pll.cfg = c->pll;
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
    /* the PLL's angle of sample k-1 and its speed: the smooth estimate the adaptation needs */
    mc_unop_adapt(&s->unop, in, s->pll.theta, s->pll.omega_filt);
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

static void unop_cfg_of(const mc_angle_src_state_t *st, mc_angle_src_cfg_t *cfg)
{
    const src_unop_t *s = (const src_unop_t *)(const void *)st;
    *cfg = (mc_angle_src_cfg_t){0};
    src_unop_cfg_t *c = (src_unop_cfg_t *)(void *)cfg;
    c->unop = s->unop.cfg;
    c->pll = s->pll.cfg;
}

static bool unop_cfg_equal(const mc_angle_src_cfg_t *cfg_a, const mc_angle_src_cfg_t *cfg_b)
{
    const src_unop_cfg_t *ca = (const src_unop_cfg_t *)(const void *)cfg_a;
    const src_unop_cfg_t *cb = (const src_unop_cfg_t *)(const void *)cfg_b;
    const mc_unop_cfg_t *a = &ca->unop, *b = &cb->unop;
    return a->ts == b->ts && a->rs == b->rs && mc_flux_model_same(&a->model, &b->model) &&
           a->iter_max == b->iter_max && a->step_tol == b->step_tol && a->k1 == b->k1 && a->k2 == b->k2 &&
           a->omega_n1 == b->omega_n1 && a->omega_base == b->omega_base && a->mid_sample == b->mid_sample &&
           a->reg_predicted == b->reg_predicted && a->u_norm == b->u_norm && a->step_max == b->step_max &&
           a->zoh_gain == b->zoh_gain && a->l_adapt == b->l_adapt && a->l_adapt_p == b->l_adapt_p &&
           a->bp_a1 == b->bp_a1 && a->bp_a2 == b->bp_a2 && ca->pll.kp == cb->pll.kp && ca->pll.ki == cb->pll.ki &&
           ca->pll.ts == cb->pll.ts && ca->pll.speed_fc_hz == cb->pll.speed_fc_hz;
}

const mc_angle_src_desc_t mc_angle_src_unop = {
    .name = "unop", .cls = MC_ANGLE_ESTIMATOR,
    .needs_injection = true, .lock_checks = true, .map_models = 1u << 1,   /* estimator.model = fluxmap */
    .build = unop_build, .init = unop_init, .retune = unop_retune, .reset = unop_reset, .step = unop_step,
    .diag = unop_diag, .cfg_of = unop_cfg_of, .cfg_equal = unop_cfg_equal,
};

