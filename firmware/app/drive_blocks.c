/* Applying a built configuration to the drive's blocks: copies only, the derivation happened in
 * the background (drive_config.c). Used by the ISR side: at init, at a configuration swap
 * (drive.c) and at every enable edge (startup.c). And the one path duties take to the PWM. */
#include "drive_internal.h"

/* Every block configured from a built configuration (init, or a new configuration while the
 * outputs are off). Copies only: the derivation happened in mc_drive_build. */
void mc_drive_apply(mc_drive_t *d, const mc_drive_built_t *b)
{
    d->cfg = b;
    d->src = mc_angle_src_get(b->p.control_angle_source);
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
    const mc_drive_blk_t *b = &d->cfg->blk;
    const mc_cc_cfg_t cc = d->cc.cfg;
    mc_cc_init(&d->cc, &cc);
    const mc_sc_cfg_t sc = d->sc.cfg;
    mc_sc_init(&d->sc, &sc);
    d->tref.mtpa_valid = false;
    d->tref.fw_active = false;
    d->step3_speed = b->step3_lpf;   /* filters as built in the background, their state at rest */
    d->src->init(&d->src_state, &b->src.cfg);
    mc_inj_init(&d->inj, &b->inj);
    d->notch_d = b->notch;
    d->notch_q = b->notch;
    mc_drive_if_reset(d);
}

/* While running: only RUNTIME parameters (and the rules that follow them) can have changed; the
 * blocks that keep a copy of their configuration get the new gains and limits, the controllers'
 * integrators, outputs and counters stay. */
void mc_drive_retune(mc_drive_t *d, const mc_drive_built_t *b)
{
    d->cfg = b;   /* limits, slew, protection: read from it from now on */
    if (d->src->retune != 0) {   /* the source takes what it reads at run time (injection.n1_rpm) */
        d->src->retune(&d->src_state, &b->blk.src.cfg);
    }
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
    const float fw_did = d->tref.fw_did;
    mc_tref_init(&d->tref, &b->tref);
    d->tref.fw_did = fw_did;
    mc_dtc_init(&d->dtc, &b->dtc);
}

void mc_drive_duties(mc_drive_t *d, mc_abc_t duty)
{
    hal_pwm_set_duties(d->hal.pwm, duty.a, duty.b, duty.c);
}

void mc_drive_duties_kept(mc_drive_t *d, mc_abc_t duty, mc_ab_t u_real, mc_ab_t u_acting)
{
    mc_drive_duties(d, duty);
    d->u_hist[1] = u_acting;
    d->u_hist[0] = u_real;
    d->tm.duty[0] = duty.a;
    d->tm.duty[1] = duty.b;
    d->tm.duty[2] = duty.c;
}
