/* The drive: ISR pipeline and background loop. The ISR reads top to bottom in mc_drive_isr(). */
#include "mc/drive.h"
#include <math.h>
#include "mc/angle.h"
#include "mc/fw_entry.h"
#include "mc/sincos.h"
#include "mc/transforms.h"
#include "drive_internal.h"
#include "hal/stage.h"

/* The telemetry, published as one consistent record; its state fields are the sequencer's, set
 * here only. */
static void publish(mc_drive_t *d)
{
    d->tm.state = d->seq.state;
    d->tm.init_step = d->seq.step;
    d->tm.faults = d->seq.faults;
    d->tm.polarity_checks = d->pol.checks;
    d->tm.polarity_flips = d->pol.flips;
    d->tm.polarity_last = d->pol.last;
    mc_drive_telbuf_write(&d->link->telem, &d->tm);
}

/* A command is taken whole or not at all: every number finite, the mode known. The validator of
 * the command buffer (mc/handover.h): it runs in the ISR on the published slot. */
static uint32_t check_command(const void *cmd, void *ctx)
{
    (void)ctx;
    const mc_drive_cmd_t *c = (const mc_drive_cmd_t *)cmd;
    if ((unsigned)c->mode >= (unsigned)MC_MODE_COUNT) {
        return (uint32_t)MC_CMD_BAD_MODE;
    }
    const bool finite = isfinite(c->i_ref.d) && isfinite(c->i_ref.q) && isfinite(c->torque_ref) &&
                        isfinite(c->speed_ref) && isfinite(c->theta_init);
    return finite ? (uint32_t)MC_CMD_OK : (uint32_t)MC_CMD_NOT_FINITE;
}

bool mc_drive_init(mc_drive_t *d, mc_drive_link_t *link, const mc_drive_cfg_t *cfg, hal_adc_t *adc, hal_pwm_t *pwm,
                   hal_qep_t *qep)
{
    *d = (mc_drive_t){0};
    d->hal = (mc_drive_hal_t){.adc = adc, .pwm = pwm, .qep = qep};
    d->link = link;
    d->cfg_err = (mc_param_err_t){.kind = MC_PERR_NONE, .param = -1, .param2 = -1};
    d->est = cfg->est;
    hal_pwm_enable(pwm, false);
    mc_drive_duties(d, (mc_abc_t){0.5f, 0.5f, 0.5f});
    const mc_drive_cmd_t idle = {.enable = false, .mode = MC_MODE_CURRENT};
    mc_drive_cmdbuf_init(&link->cmd, &idle, check_command, 0);
    mc_drive_telbuf_init(&link->telem, 0);
    /* a refused configuration still leaves a sequencer that never leaves FAULT */
    const mc_seq_cfg_t none = {.ts = 1e-4f};
    mc_seq_init(&d->seq, &none);
    /* the configuration is built in the link's first slot: the active one from now on */
    mc_drive_built_t *b = &link->cfg.slot[0];
    if (!mc_drive_build(cfg, b, &d->cfg_err)) {
        *b = (mc_drive_built_t){0};   /* the ISR scales its telemetry with it: zeros, not garbage */
        d->cfg = b;
        mc_drive_cfgbuf_init(&link->cfg, 0);
        mc_seq_fault(&d->seq, MC_FAULT_CONFIG);
        publish(d);
        return false;
    }
    mc_drive_cfgbuf_init(&link->cfg, 0);
    mc_seq_init(&d->seq, &b->blk.seq);
    mc_drive_apply(d, b);
    mc_offsets_init(&d->offs, &b->blk.offs);
    publish(d);
    return true;
}

bool mc_drive_telemetry_read(const mc_drive_t *d, mc_drive_telem_t *out)
{
    return mc_drive_telbuf_read(&d->link->telem, out, 4u, 0);
}

const mc_param_err_t *mc_drive_config_error(const mc_drive_t *d)
{
    return &d->cfg_err;
}

const mc_params_t *mc_drive_params(const mc_drive_t *d)
{
    return &d->cfg->p;
}

void mc_drive_command(mc_drive_t *d, const mc_drive_cmd_t *cmd)
{
    mc_drive_cmdbuf_write(&d->link->cmd, cmd);
}

const mc_drive_telem_t *mc_drive_telemetry(const mc_drive_t *d)
{
    return &d->tm;
}


/* Commands change only here, at the start of a period, as one consistent copy. */
static void take_command(mc_drive_t *d)
{
    const mc_cmdbuf_status_t st = mc_drive_cmdbuf_take(&d->link->cmd, &d->cmd);
    if (st == MC_CMDBUF_REFUSED) {
        d->tm.cmd_rejected = mc_cmdbuf_refused(&d->link->cmd.base);
        d->tm.cmd_reject_last = (mc_cmd_reject_t)mc_cmdbuf_last_reason(&d->link->cmd.base);
        return;   /* the previous command stays in force */
    }
    if (st != MC_CMDBUF_TAKEN || (d->seq.faults & MC_FAULT_CONFIG) != 0u) {
        return;   /* nothing new; a rejected configuration never runs */
    }
    if (mc_seq_enable(&d->seq, d->cmd.enable)) {
        mc_drive_startup_reset(d);   /* a new enable always starts clean */
    }
}

/* A configuration the background built and validated (mc_drive_param_write) takes effect here,
 * at a period boundary, by copies only. With the outputs off every block starts from it; while
 * running only RUNTIME parameters can have changed, and the controllers keep their state. */
static void take_config(mc_drive_t *d)
{
    bool changed = false;
    const mc_drive_built_t *b = mc_drive_cfgbuf_take(&d->link->cfg, &changed);
    if (!changed) {
        return;
    }
    if (d->seq.state == MC_STATE_IDLE || d->seq.state == MC_STATE_FAULT) {
        mc_drive_apply(d, b);
        return;
    }
    mc_drive_retune(d, b);
}

/* The stator voltage with the outputs off while the phase currents flow: each phase at the rail
 * its current returns through (the lower diode for a current into the machine), with the dead-time
 * compensation's smooth sign; Clarke (2.4) drops the common part. */
static mc_ab_t diode_voltage(mc_abc_t i, float vdc, float i_band)
{
    const float h = -0.5f * vdc;
    return mc_clarke((mc_abc_t){h * mc_dtc_sgn_smooth(i.a, i_band), h * mc_dtc_sgn_smooth(i.b, i_band),
                                h * mc_dtc_sgn_smooth(i.c, i_band)});
}

/* The selected angle source (mc/angle_source.h), with its diagnostics into the telemetry. */
static void angle_source(mc_drive_t *d, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    d->src->step(&d->src_state, in, out);
    mc_angle_diag_t g;
    d->src->diag(&d->src_state, &g);
    d->tm.theta_raw = g.theta_raw;
    d->tm.omega_raw = g.omega_raw;
    d->tm.est_iters = g.iters;
    d->tm.est_cost = g.cost;
    d->tm.est_cond = g.cond;
}

/* The reference vector moves at most i_slew * ts per period: a step would make the current loop,
 * with its 1.5-period delay, overshoot by ~20 % of the step and exceed the current limit. */
static mc_dq_t slew(mc_drive_t *d, mc_dq_t target)
{
    const float dd = target.d - d->i_ref_prev.d;
    const float dq = target.q - d->i_ref_prev.q;
    const float step = d->cfg->blk.i_slew * d->cfg->blk.ts;
    const float len2 = dd * dd + dq * dq;
    /* Most periods the reference moves far less than a step: the squared length with a 0.1 %
     * margin (far above rounding) settles that without the square root; only near or above
     * the step (or for NaN) does the exact length decide, as before. */
    if (!(len2 < 0.999f * step * step)) {
        const float len = sqrtf(len2);
        if (len > step) {
            target.d = d->i_ref_prev.d + dd * (step / len);
            target.q = d->i_ref_prev.q + dq * (step / len);
        }
    }
    d->i_ref_prev = target;
    return target;
}

/* The polarity re-check's d bias (mc/polcheck.h), before the slew limit: 0 unless it runs. */
static mc_dq_t with_bias(const mc_drive_t *d, mc_dq_t r)
{
    r.d += mc_polcheck_bias(&d->pol, &d->cfg->blk.pol);
    return r;
}

static mc_dq_t references(mc_drive_t *d, float omega, float vdc)
{
    float torque = 0.0f;
    /* a fault reaction (FAULT_REACTION) holds zero torque: the field-weakening current only */
    switch (d->seq.state == MC_STATE_FAULT_REACTION ? MC_MODE_TORQUE : d->cmd.mode) {
    case MC_MODE_CURRENT:
        d->tm.torque_ref = 0.0f;
        return slew(d, with_bias(d, mc_limit_current_circle(d->cmd.i_ref, d->cfg->blk.i_ref_max)));
    case MC_MODE_SPEED:
        torque = mc_sc_step(&d->sc, d->cmd.speed_ref, omega / (float)d->cfg->blk.pole_pairs);
        break;
    case MC_MODE_TORQUE:
    default:
        torque = d->seq.state == MC_STATE_FAULT_REACTION ? 0.0f : d->cmd.torque_ref;
        break;
    }
    d->tm.torque_ref = torque;
    const mc_dq_t r = mc_tref_step(&d->tref, torque, omega, vdc);
    return slew(d, with_bias(d, mc_tref_fw_feedback(&d->tref, r, d->cc.limited, omega, vdc)));
}

/* The injection's notches start again from the current that flows (while injecting). */
static void notch_restart(mc_drive_t *d, const mc_drive_blk_t *c, mc_dq_t i)
{
    if (c->inject) {
        mc_biquad_reset(&d->notch_d, i.d);
        mc_biquad_reset(&d->notch_q, i.q);
    }
}

/* ISR step 5: the current loop's feedback. While injecting, the loop sees the currents with the
 * injection frequency notched out, so it does not cancel it. */
static mc_dq_t feedback(mc_drive_t *d, const mc_drive_blk_t *c, float omega, mc_dq_t i_dq)
{
    mc_dq_t i_fb = i_dq;
    if (c->inject && !(fabsf(omega) > 1.2f * d->inj.cfg.omega_n1)) {
        i_fb.d = mc_biquad_step(&d->notch_d, i_dq.d);
        i_fb.q = mc_biquad_step(&d->notch_q, i_dq.q);
    } else {
        /* well above N1 nothing is injected, and the notch would only delay the loop's currents
         * (a torque step at 1400 rpm drove i_d 1.3 A past its reference through it): bypassed
         * from 1.2 N1 (the margin lets the injection's last current decay through it first),
         * its state kept at the current so that it starts from it below again */
        notch_restart(d, c, i_dq);
    }
    return i_fb;
}

/* A RUN entry at speed first takes the flux into the voltage limit with the least current
 * (mc/fw_entry.h): true while it runs, *u_dq its voltage; the loop then idles with its
 * references on the current that flows (bumpless) and starts from them when the entry ends. */
static bool fw_entry(mc_drive_t *d, const mc_drive_blk_t *c, const mc_angle_out_t *ang, mc_dq_t i_dq, mc_dq_t i_fb,
                     mc_dq_t *i_ref, mc_ab_t u_acting, mc_sincos_t sc_u, float vdc, mc_dq_t *u_dq)
{
    if (!mc_fwe_active(&d->fw_entry)) {
        return false;
    }
    /* the raw currents: the injection's notch would delay a current that moves by a tenth of the
     * limit per period. It lands on the flux the references will hold (control.u_margin), but
     * not beyond the inscribed circle: the tangential phase (F.4) takes the lag back only where
     * the hexagon reaches beyond the held flux's voltage, and its sides reach no more than the
     * circle (at u_margin 1.04 the lag never went and the law ran on, braking at -15 N m). Moved
     * with what the hexagon gives in each direction (sc_u: where the vector will act) when the
     * loop may overmodulate. */
    mc_fwe_in_t in = {.i = i_dq, .omega = ang->omega, .vdc = vdc, .sc = sc_u};
    mc_flux_eval(&c->src.model, i_dq, &in.psi, 0, 0);
    in.u_now = mc_park(u_acting, mc_sincos(mc_wrap_pi(ang->theta + 0.5f * ang->omega * c->ts)));
    in.u_land = mc_drive_u_land(d, vdc);
    switch (mc_fwe_step(&d->fw_entry, &c->fw_entry, &in, u_dq)) {
    case MC_FWE_RUNNING:
        *i_ref = i_fb;   /* bumpless, for the loop after it and for the tracking check */
        d->i_ref_prev = i_fb;
        notch_restart(d, c, i_dq);
        d->cc.u = *u_dq;   /* the plausibility checks see the voltage applied */
        return true;
    case MC_FWE_ENDED:
        mc_cc_reset(&d->cc);   /* the loop starts from the references it was left */
        return false;
    case MC_FWE_OFF:
    default:
        return false;
    }
}

/* ISR step 7: the current loop, limited to a circle of u_loop vdc/sqrt3: the inscribed circle of
 * the voltage hexagon (linear), or beyond it up to the corners, which mc_svpwm scales into the
 * hexagon keeping the direction (overmodulation, mc/svpwm.h (2.14a)); or, after a RUN entry above
 * the generation speed, the field-weakening entry's voltage until the loop takes over from the
 * current that then flows. The HF injection (6.6) rides on the estimated d axis. */
static mc_dq_t current_loop(mc_drive_t *d, const mc_drive_blk_t *c, const mc_angle_out_t *ang, mc_dq_t i_dq,
                            mc_dq_t i_fb, mc_dq_t *i_ref, mc_ab_t u_acting, mc_sincos_t sc_u, float vdc)
{
    const float u_loop = vdc * MC_1_SQRT3 * c->u_loop;
    mc_dq_t u_dq;
    if (fw_entry(d, c, ang, i_dq, i_fb, i_ref, u_acting, sc_u, vdc, &u_dq)) {
        /* the entry's voltage */
    } else if (c->cc_map) {
        /* the decoupling from the flux map's psi(i): the machine's own back-EMF (mc_cc_step_psi) */
        mc_dq_t psi;
        mc_flux_eval(&c->src.model, i_fb, &psi, 0, 0);
        u_dq = mc_cc_step_psi(&d->cc, *i_ref, i_fb, psi, ang->omega, u_loop);
    } else {
        u_dq = mc_cc_step(&d->cc, *i_ref, i_fb, ang->omega, u_loop);
    }
    d->tm.u_inj = c->inject ? mc_inj_step(&d->inj, ang->omega) : 0.0f;
    u_dq.d += d->tm.u_inj;
    return u_dq;
}

/* ISR step 7a: the running polarity re-check (mc/polcheck.h), at a RUN entry not preceded by
 * Step II when so configured (else step 7b starts it when the loss-of-lock checks are in doubt).
 * A reversed estimate turns to the mirrored solution (theta + pi, -omega). */
static void polarity_recheck(mc_drive_t *d, const mc_angle_out_t *ang, mc_dq_t i_dq, mc_dq_t i_fb)
{
    const mc_polcheck_cfg_t *pc = &d->cfg->blk.pol;
    mc_polcheck_schedule(&d->pol, pc, ang->omega, d->seq.state == MC_STATE_RUN, d->seq.ticks);
    const mc_polcheck_in_t in = {.i_d = i_dq.d, .i_d_filtered = i_fb.d, .theta = ang->theta,
                                 .theta_raw = d->tm.theta_raw, .w_avg = d->prot.w};
    if (mc_polcheck_step(&d->pol, pc, &in)) {
        d->src->reset(&d->src_state, mc_wrap_pi(ang->theta + MC_PI), -ang->omega);
        mc_cc_reset(&d->cc);
    }
}

/* ISR step 7b: plausibility (mc/protect.h): over-speed, loss of lock, current tracking, the
 * voltage model, stall, torque. A fault recovers (a new catch), holds the field weakening or
 * trips, before this period's duties are written: true then. */
static bool running_fault(mc_drive_t *d, const mc_angle_out_t *ang, mc_dq_t i_ref, mc_dq_t i_fb, float vdc)
{
    const mc_protect_in_t in = {.theta = ang->theta, .omega = ang->omega, .theta_raw = d->tm.theta_raw,
                                .omega_raw = d->tm.omega_raw, .i_ref = i_ref, .i_fb = i_fb, .u_dq = d->cc.u,
                                .torque_ref = d->tm.torque_ref, .speed_mode = d->cmd.mode == MC_MODE_SPEED,
                                .speed_ref = d->cmd.speed_ref, .reacting = d->seq.state == MC_STATE_FAULT_REACTION,
                                .lock_paused = mc_polcheck_active(&d->pol), .open_loop = d->if_open,
                                .if_slip = d->if_open ? d->ifs.slip : 0.0f};   /* ifs: the union's I/f state while it runs */
    bool doubt = false;
    const uint32_t reason = mc_protect_running(&d->prot, &d->cfg->blk.prot, &in, &doubt);
    if (doubt) {
        /* the lock checks in doubt: is the estimate reversed? */
        (void)mc_polcheck_start(&d->pol, &d->cfg->blk.pol, ang->omega, d->seq.state == MC_STATE_RUN);
    }
    if (reason == 0u) {
        return false;
    }
    if (!mc_drive_recover(d, reason, vdc) && !mc_drive_react(d, reason, ang->omega, vdc)) {
        mc_drive_trip(d, reason);
    }
    return true;
}

/* ISR step 9: SVPWM (min-max injection), then dead-time compensation with the current of the
 * period the duties act in, extrapolated from the last two samples (it carries the injection
 * ripple, which decides the sign near zero crossings). false: a non-finite duty. */
static bool modulate(mc_drive_t *d, mc_ab_t u_ab, mc_ab_t i_ab, float vdc, mc_duty_t *duty)
{
    mc_svpwm(u_ab, vdc, duty);
    const mc_ab_t i_next = {i_ab.alpha + 1.5f * (i_ab.alpha - d->i_ab_prev.alpha),
                            i_ab.beta + 1.5f * (i_ab.beta - d->i_ab_prev.beta)};
    mc_dtc_apply(&d->dtc, duty, mc_clarke_inv(i_next));
    return isfinite(duty->a) && isfinite(duty->b) && isfinite(duty->c);
}

void mc_drive_isr(mc_drive_t *d)
{
    /* the configuration this period's pipeline blocks run on (the current loop, the entry, the
     * notches, the scaling): the one in force at the period's start. A configuration swapped in
     * by take_config reaches them from the next period; protection, the polarity re-check, the
     * references and the startup read it (d->cfg) at once. */
    const mc_drive_blk_t *c = &d->cfg->blk;
    hal_stage_mark(HAL_STAGE_SAMPLE);
    /* 0. A RUN entry at a diode pulse's low latched its first duties last period with the
     *    outputs off: they act from now on, with the outputs (a gate enable acts at once). */
    if (d->entry.gate_on_next) {
        d->entry.gate_on_next = false;
        if (d->seq.state == MC_STATE_RUN) {
            hal_pwm_enable(d->hal.pwm, true);
        }
    }
    take_command(d);
    take_config(d);

    /* 1. Samples of this period (ADC triggered at the PWM centre) and the encoder. */
    hal_adc_sample_t raw;
    hal_adc_read(d->hal.adc, &raw);
    hal_qep_sample_t qep;
    hal_qep_read(d->hal.qep, &qep);

    /* 2. Scaling with the calibrated offsets; Clarke (2.4), all three channels measured. */
    const float vdc = (float)raw.vdc * c->volts_per_count;
    mc_abc_t i_abc = mc_drive_currents(d, &raw);
    mc_ab_t i_ab = mc_clarke(i_abc);
    d->tm.period++;
    d->tm.i_abc = i_abc;
    d->tm.vdc = vdc;

    /* 3. Protection and the startup sequence (offset calibration, Step I and II pulses).
     *    Only RUN and Step III continue into the control pipeline; an angle sensor is also
     *    read during the offset calibration. The angle source (step 4) gets i(k-1), i(k) and
     *    the voltage applied between them. */
    mc_angle_in_t ain = {.i_ab = i_ab, .i_ab_prev = d->i_ab_prev, .u_ab_applied = d->u_hist[1],
                         .vdc = vdc, .qep_count = qep.count};
    mc_angle_out_t ang;
    if (!mc_drive_startup(d, &raw, i_abc, i_ab, vdc)) {
        if (c->src_measures && d->seq.state == MC_STATE_OFFSET_CAL) {
            /* an angle sensor is tracked while the offsets are calibrated (outputs off): RUN
             * then starts with its speed, not from 0 (a rotor already turning at 1500 rpm would
             * otherwise meet a decoupling and a field weakening planned for standstill) */
            angle_source(d, &ain, &ang);
            d->tm.theta = ang.theta;
            d->tm.omega = ang.omega;
        }
        d->i_ab_prev = d->offs.moved ? mc_clarke(mc_drive_currents(d, &raw)) : i_ab;
        d->offs.moved = false;
        publish(d);
        return;
    }
    if (d->offs.moved) {
        /* the catch moved the offsets in this very period ((O.1), startup.c): the pipeline
         * starts with the currents, this one and the last, as the new offsets give them */
        d->offs.moved = false;
        i_abc = mc_drive_currents(d, &raw);
        i_ab = mc_clarke(i_abc);
        ain.i_ab = i_ab;
        ain.i_ab_prev = d->i_ab_prev;
    }
    /* 4. Angle source. */
    hal_stage_mark(HAL_STAGE_ANGLE);
    angle_source(d, &ain, &ang);
    /* 4a. Below the hand-over speed without usable saliency: the I/f frame instead (drive_if.c;
     *     the lock checks wait, the estimator has nothing to lock on there). */
    mc_dq_t if_ref = {0.0f, 0.0f};
    const bool open = mc_drive_if_step(d, &ang, i_ab, &if_ref);

    /* 5. Park (2.5) into the controller's frame, and the loop's feedback (notched while
     *    injecting). */
    hal_stage_mark(HAL_STAGE_REFERENCES);
    const mc_dq_t i_dq = mc_park(i_ab, mc_sincos(ang.theta));
    /* The angle of step 8 is known already: its sin/cos is taken here, where it does not wait
     * for the references and the current loop (an out-of-order core overlaps the two). */
    const mc_sincos_t sc_u = mc_sincos(mc_wrap_pi(ang.theta + 1.5f * ang.omega * c->ts));
    const mc_dq_t i_fb = feedback(d, c, ang.omega, i_dq);

    /* 6. References: current, torque (MTPA / field weakening) or speed; zero during Step III. */
    const bool step3 = d->seq.state == MC_STATE_INIT_POS;
    mc_dq_t i_ref = step3 ? slew(d, (mc_dq_t){0.0f, 0.0f}) : (open ? slew(d, if_ref) : references(d, ang.omega, vdc));
    if (open) {
        d->tm.torque_ref = 0.0f;   /* no torque command: the frame's current pulls the rotor */
    }

    /* 7. Current loop (or the field-weakening entry's voltage while it runs) and the HF
     *    injection. The voltage acting until the next sample: the duties latched last period,
     *    or the diodes' with the outputs still off (a RUN entry at gate_on_next). */
    hal_stage_mark(HAL_STAGE_CURRENT);
    const mc_ab_t u_acting = d->entry.gate_on_next ? diode_voltage(i_abc, vdc, d->cfg->dtc.i_band) : d->u_hist[0];
    const mc_dq_t u_dq = current_loop(d, c, &ang, i_dq, i_fb, &i_ref, u_acting, sc_u, vdc);

    /* 7a. The running polarity re-check. */
    if (!open) {
        polarity_recheck(d, &ang, i_dq, i_fb);
    }

    /* 7b. Plausibility: a fault turns the outputs off (or reacts) before the duties. */
    if (running_fault(d, &ang, i_ref, i_fb, vdc)) {
        d->i_ab_prev = i_ab;
        publish(d);
        return;
    }

    /* 8. Inverse Park at the middle of the period the voltage will act in, (k+1, k+2): the
     *    one-period update delay plus the half period of the average (sc_u, taken in step 5). */
    hal_stage_mark(HAL_STAGE_MODULATION);
    const mc_ab_t u_ab = mc_park_inv(u_dq, sc_u);

    /* 9. Modulator: SVPWM and dead-time compensation. Never a NaN to the PWM: whatever
     *    produced it, the outputs go off with the reason. */
    mc_duty_t duty;
    if (!modulate(d, u_ab, i_ab, vdc, &duty)) {
        mc_drive_trip(d, MC_FAULT_NUMERIC);
        publish(d);
        return;
    }

    /* 10. Duties, by the one path to the PWM; the history keeps the voltage they realise and,
     *     for (k, k+1), the one acting until now (the diodes' with the outputs still off). */
    mc_drive_duties_kept(d, (mc_abc_t){duty.a, duty.b, duty.c}, duty.u_real, u_acting);

    /* 11. What the estimators need next period, and the telemetry. */
    d->i_ab_prev = i_ab;
    d->tm.theta = ang.theta;
    d->tm.omega = ang.omega;
    d->tm.i_dq = i_dq;
    d->tm.i_ref = i_ref;
    d->tm.u_dq = u_dq;
    d->tm.u_ab = duty.u_real;
    d->tm.u_limited = d->cc.limited;
    d->tm.fw_active = d->tref.fw_active;

    /* 12. Step III hands over to RUN when its convergence test holds (same estimator). */
    if (step3) {
        mc_drive_step3_check(d, ang.omega);
    }

    /* 13. The telemetry, published as one consistent record. */
    publish(d);
}

void mc_drive_background(mc_drive_t *d)
{
    /* Slow work lives here, never in the ISR: parameter changes arrive through
     * mc_drive_param_write, the CANopen stack and the parameter store will run here. It never
     * writes the ISR's state: the telemetry has one writer, the ISR. */
    (void)d;
}

mc_state_t mc_drive_state(const mc_drive_t *d)
{
    return d->seq.state;
}

uint32_t mc_drive_faults(const mc_drive_t *d)
{
    return d->seq.faults;
}
