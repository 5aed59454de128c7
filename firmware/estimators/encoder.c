#include "mc/encoder.h"
#include "mc/angle.h"

void mc_encoder_init(mc_encoder_t *s, const mc_encoder_cfg_t *cfg)
{
    s->cfg = *cfg;
    /* (2.18); applied to (count * p mod cpr) so the electrical angle stays exact in float */
    s->rad_per_count = MC_2PI / (float)cfg->counts_per_rev;
    s->narrow = cfg->pole_pairs >= 1 &&
                (uint64_t)cfg->counts_per_rev * (uint64_t)cfg->pole_pairs <= (uint64_t)UINT32_MAX;
    s->max_step = (cfg->pole_pairs >= 1 && cfg->counts_per_rev >= 1u)
                      ? (cfg->counts_per_rev - 1u) / (uint32_t)cfg->pole_pairs
                      : 0u;
    s->tracking = false;
    s->last_count = 0u;
    s->last_elec = 0u;
    /* Critically damped second-order PLL: s^2 + kp s + ki with both poles at -w. */
    const float w = MC_2PI * cfg->pll_bw_hz;
    const mc_pll_cfg_t pc = {.kp = 2.0f * w, .ki = w * w, .ts = cfg->ts, .speed_fc_hz = cfg->speed_fc_hz};
    mc_pll_init(&s->pll, &pc);
    s->primed = false;
}

void mc_encoder_reset(mc_encoder_t *s)
{
    s->primed = false;
}

/* (count * p) mod cpr, the electrical position in counts. */
static uint32_t elec_counts(mc_encoder_t *s, uint32_t count)
{
    const uint32_t cpr = s->cfg.counts_per_rev;
    const uint32_t last = s->last_count;
    uint32_t elec;
    /* Between two periods the counter moves by a few hundred counts at most: the residue moves
     * by (change * p) < cpr, which one conditional add or subtract of cpr keeps in [0, cpr).
     * Exact integer arithmetic on the true counter values (a counter wrap takes the full path
     * below), so it is the same residue the division gives, without a division every period. */
    if (s->tracking && count >= last && count - last <= s->max_step) {
        const uint32_t inc = (count - last) * (uint32_t)s->cfg.pole_pairs;
        elec = (s->last_elec >= cpr - inc) ? s->last_elec - (cpr - inc) : s->last_elec + inc;
    } else if (s->tracking && count < last && last - count <= s->max_step) {
        const uint32_t dec = (last - count) * (uint32_t)s->cfg.pole_pairs;
        elec = (s->last_elec >= dec) ? s->last_elec - dec : s->last_elec + (cpr - dec);
    } else if (s->narrow) {
        /* (count * p) mod cpr = ((count mod cpr) * p) mod cpr, and with cpr * p < 2^32 nothing
         * overflows: two 32-bit divisions (hardware UDIV on the M4) instead of the 64-bit one,
         * which is a library call there. Same residue, so the same angle. */
        elec = ((count % cpr) * (uint32_t)s->cfg.pole_pairs) % cpr;
    } else {
        elec = (uint32_t)(((uint64_t)count * (uint64_t)s->cfg.pole_pairs) % (uint64_t)cpr);
    }
    s->tracking = s->max_step > 0u;
    s->last_count = count;
    s->last_elec = elec;
    return elec;
}

void mc_encoder_step(mc_encoder_t *s, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    const uint32_t elec = elec_counts(s, in->qep_count);
    const float theta = mc_wrap_pi((float)elec * s->rad_per_count + s->cfg.offset_rad);
    if (!s->primed) {
        mc_pll_reset(&s->pll, theta, 0.0f);
        s->primed = true;
    }
    mc_pll_step(&s->pll, theta, 0.0f);
    /* The counter is exact to one count: use it for the angle, the PLL only for speed. */
    out->theta = theta;
    out->omega = s->pll.omega_filt;
}
