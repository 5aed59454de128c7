/* Angle source "encoder": the quadrature counter through (2.18) and the encoder's own speed PLL
 * (mc/encoder.h). An angle sensor: no injection, no loss-of-lock checks, no flux map.
 * Parameters: hw.encoder_lines, hw.encoder_offset_rad, control.encoder_pll_bw_hz,
 * control.encoder_speed_fc_hz (mc/params_table.h); none of them RUNTIME. */
#include "mc/angle_source.h"
#include "mc/encoder.h"
#include "mc/params.h"

MC_ANGLE_SRC_CFG_FITS(mc_encoder_cfg_t);
MC_ANGLE_SRC_FITS(mc_encoder_t);

static bool enc_build(const mc_params_t *p, float rs, const mc_flux_model_t *model, mc_angle_src_cfg_t *cfg,
                      mc_param_err_t *err)
{
    (void)rs;
    (void)model;
    (void)err;   /* the table's ranges cover everything it reads */
    *cfg = (mc_angle_src_cfg_t){0};
    *(mc_encoder_cfg_t *)(void *)cfg =
        (mc_encoder_cfg_t){.pole_pairs = (int)p->motor_pole_pairs, .counts_per_rev = 4u * (uint32_t)p->hw_encoder_lines,
                           .offset_rad = p->hw_encoder_offset_rad, .ts = p->control_ts_s, .pll_bw_hz = p->control_encoder_pll_bw_hz,
                           .speed_fc_hz = p->control_encoder_speed_fc_hz};
    return true;
}

static void enc_init(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *cfg)
{
    mc_encoder_init((mc_encoder_t *)(void *)s, (const mc_encoder_cfg_t *)(const void *)cfg);
}

/* The counter is absolute (after the offset): its estimate needs no seed. */
static void enc_reset(mc_angle_src_state_t *s, float theta, float omega)
{
    (void)theta;
    (void)omega;
    mc_encoder_reset((mc_encoder_t *)(void *)s);
}

static void enc_step(mc_angle_src_state_t *s, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    mc_encoder_step((mc_encoder_t *)(void *)s, in, out);
}

static void enc_diag(const mc_angle_src_state_t *s, mc_angle_diag_t *d)
{
    const mc_encoder_t *e = (const mc_encoder_t *)(const void *)s;
    *d = (mc_angle_diag_t){.theta_raw = e->pll.theta, .omega_raw = e->pll.omega};
}

static void enc_cfg_of(const mc_angle_src_state_t *s, mc_angle_src_cfg_t *cfg)
{
    *cfg = (mc_angle_src_cfg_t){0};
    *(mc_encoder_cfg_t *)(void *)cfg = ((const mc_encoder_t *)(const void *)s)->cfg;
}

static bool enc_cfg_equal(const mc_angle_src_cfg_t *cfg_a, const mc_angle_src_cfg_t *cfg_b)
{
    const mc_encoder_cfg_t *a = (const mc_encoder_cfg_t *)(const void *)cfg_a;
    const mc_encoder_cfg_t *b = (const mc_encoder_cfg_t *)(const void *)cfg_b;
    return a->pole_pairs == b->pole_pairs && a->counts_per_rev == b->counts_per_rev &&
           a->offset_rad == b->offset_rad && a->ts == b->ts && a->pll_bw_hz == b->pll_bw_hz &&
           a->speed_fc_hz == b->speed_fc_hz;
}

const mc_angle_src_desc_t mc_angle_src_encoder = {
    .name = "encoder", .cls = MC_ANGLE_SENSOR, .needs_injection = false, .lock_checks = false, .map_models = 0u,
    .build = enc_build, .init = enc_init, .retune = 0, .reset = enc_reset, .step = enc_step, .diag = enc_diag,
    .cfg_of = enc_cfg_of, .cfg_equal = enc_cfg_equal,
};
