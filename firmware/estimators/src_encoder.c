/* Angle source "encoder": the quadrature counter through (2.18) and the encoder's own speed PLL
 * (mc/encoder.h). Needs no injection. */
#include "mc/angle_source.h"
#include "mc/encoder.h"

MC_ANGLE_SRC_FITS(mc_encoder_t);

static void enc_init(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *c)
{
    const mc_encoder_cfg_t ec = {.pole_pairs = c->pole_pairs, .counts_per_rev = c->enc_counts_per_rev,
                                 .offset_rad = c->enc_offset_rad, .ts = c->ts,
                                 .pll_bw_hz = c->enc_pll_bw_hz, .speed_fc_hz = c->enc_speed_fc_hz};
    mc_encoder_init((mc_encoder_t *)(void *)s, &ec);
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

const mc_angle_src_desc_t mc_angle_src_encoder = {
    .name = "encoder", .needs_injection = false, .measures_angle = true,
    .init = enc_init, .reset = enc_reset, .step = enc_step, .diag = enc_diag,
};
