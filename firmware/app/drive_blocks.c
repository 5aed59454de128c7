/* Applying a built configuration to the drive's blocks: copies only, the derivation happened in
 * the background (drive_config.c). Used by the ISR side: at init, at a configuration swap
 * (drive.c) and at every enable edge (startup.c). */
#include "drive_internal.h"

/* Every block configured from a built configuration (init, or a new configuration while the
 * outputs are off). Copies only: the derivation happened in mc_drive_build. */
void mc_drive_apply(mc_drive_t *d, const mc_drive_built_t *b)
{
    d->p = b->p;
    d->blk = b->blk;
    d->src = mc_angle_src_get(b->p.angle_src);
    mc_cc_init(&d->cc, &b->cc);
    mc_sc_init(&d->sc, &b->sc);
    mc_tref_init(&d->tref, &b->tref);
    mc_dtc_init(&d->dtc, &b->dtc);
    mc_seq_cfg_t sc = b->blk.seq;
    sc.init_pos = b->blk.three_step;
    d->seq.cfg = sc;
    mc_drive_init_blocks(d);
}

/* The blocks' running state back to their start (at init and at every enable edge): from the
 * configurations they hold, no derivation. */
void mc_drive_init_blocks(mc_drive_t *d)
{
    const mc_drive_blk_t *b = &d->blk;
    const mc_cc_cfg_t cc = d->cc.cfg;
    mc_cc_init(&d->cc, &cc);
    const mc_sc_cfg_t sc = d->sc.cfg;
    mc_sc_init(&d->sc, &sc);
    d->tref.mtpa_valid = false;
    d->tref.fw_active = false;
    mc_lpf1_init(&d->step3_speed, 50.0f, b->ts, 0.0f);
    d->src->init(&d->src_state, &b->src);
    mc_inj_init(&d->inj, &b->inj);
    mc_biquad_init_notch(&d->notch_d, b->f_notch, b->notch_q, b->ts);
    mc_biquad_init_notch(&d->notch_q, b->f_notch, b->notch_q, b->ts);
}

/* While running: only RUNTIME parameters can have changed; gains and limits change, the
 * controllers' integrators, outputs and counters stay. */
void mc_drive_retune(mc_drive_t *d, const mc_drive_built_t *b)
{
    d->p = b->p;
    d->blk.i_ref_max = b->blk.i_ref_max;
    d->blk.i_slew = b->blk.i_slew;
    d->inj.cfg.v1 = b->blk.inj.v1;
    d->inj.cfg.omega_n1 = b->blk.inj.omega_n1;
    const float integ_d = d->cc.pi_d.integ, integ_q = d->cc.pi_q.integ;
    const mc_dq_t u = d->cc.u;
    mc_cc_init(&d->cc, &b->cc);
    d->cc.pi_d.integ = integ_d;
    d->cc.pi_q.integ = integ_q;
    d->cc.u = u;
    const float integ_s = d->sc.pi.integ, t_ref = d->sc.torque_ref;
    const int count = d->sc.count;
    mc_sc_init(&d->sc, &b->sc);
    d->sc.pi.integ = integ_s;
    d->sc.count = count;
    d->sc.torque_ref = t_ref;
    mc_tref_init(&d->tref, &b->tref);
    mc_dtc_init(&d->dtc, &b->dtc);
}
