/* The drive: ISR pipeline and background loop. The ISR reads top to bottom in mc_drive_isr(). */
#include "mc/drive.h"
#include <math.h>
#include "mc/angle.h"
#include "mc/sincos.h"
#include "mc/transforms.h"
#include "drive_internal.h"

void mc_drive_cfg_default(mc_drive_cfg_t *c)
{
    /* sun2016-ipm-5kw (thesis Table 4.1) on the 300 V / 10 kHz bench, 12-bit ADC over +-25 A. */
    *c = (mc_drive_cfg_t){
        .pole_pairs = 5, .rs = 0.400f, .ld = 10.5e-3f, .lq = 12.9e-3f, .psi_pm = 0.34305f,
        .ts = 1.0e-4f,
        .adc_amps_per_count = 50.0f / 4095.0f, .adc_offset_nominal = 2047.5f, .adc_offset_tol = 100.0f,
        .adc_volts_per_count = 500.0f / 4095.0f, .offset_cal_samples = 256u,
        .i_trip = 20.0f, .vdc_min = 150.0f, .vdc_max = 450.0f,
        .angle_src = MC_ANGLE_SRC_ENCODER, .enc_counts_per_rev = 80000u, .enc_offset_rad = 0.0f,
        .enc_pll_bw_hz = 150.0f, .enc_speed_fc_hz = 500.0f,
        .cc_bw_hz = 500.0f, .cc_decouple = true,
        .i_max = 13.29f, .i_headroom = 0.03f, .i_slew = 10000.0f, .u_margin = 0.95f, .mtpa_table = false,
        .sc_kp = 1.0f, .sc_ki = 20.0f, .torque_max = 32.0f, .sc_decimation = 10,
        .dtc_enable = true, .dtc_i_band = 0.3f, .dead_time = 0.5e-6f,
        .pll_bw_hz = 100.0f, .pll_speed_fc_hz = 200.0f,
        .inj = {.kind = MC_INJ_SINE, .v1 = 70.0f, .f_hz = 500.0f, .omega_n1 = 209.44f, .ts = 1.0e-4f},
        .notch_q = 1.0f,
    };
    c->init_three_step = false;
    c->step3_speed_tol = 3.0f;
    c->step3_hold = 0.005f;
    c->timeout_cal = 0.1f;
    c->timeout_step12 = 0.02f;
    c->timeout_step3 = 0.5f;
    mc_initpos_cfg_default(&c->ip1);
    c->ip1.ts = c->ts;
    c->ip1.rs = c->rs;
    c->ip1.ld = c->ld;
    c->ip1.lq = c->lq;
    c->ip1.i_trip = c->i_trip;
    c->ip1_pulse3 = false;
    mc_pulse3_cfg_default(&c->pulse3);
    c->pulse3.rs = c->rs;
    c->pulse3.i_trip = c->i_trip;
    mc_polarity_cfg_default(&c->ip2);
    c->ip2.ts = c->ts;
    c->ip2.rs = c->rs;
    c->ip2.i_trip = c->i_trip;
    c->ip2_dvi = false;
    mc_dvi_cfg_default(&c->dvi);
    c->dvi.rs = c->rs;
    c->dvi.i_trip = c->i_trip;
    mc_unop_cfg_default(&c->unop);
    c->unop.ts = c->ts;
    c->unop.rs = c->rs;
    c->unop.model = (mc_flux_model_t){.kind = MC_FLUX_CONST, .ld = c->ld, .lq = c->lq, .psi_pm = c->psi_pm, .map = 0};
    c->unop.omega_n1 = c->inj.omega_n1;   /* N1 = 400 rpm: 209 rad/s electrical */
}

static bool cfg_valid(const mc_drive_cfg_t *c)
{
    const bool motor = c->pole_pairs >= 1 && c->rs >= 0.0f && c->ld > 0.0f && c->lq > 0.0f && c->psi_pm >= 0.0f;
    const bool sensing = c->ts >= 4.9e-5f && c->ts <= 5.1e-4f && c->adc_amps_per_count > 0.0f &&
                         c->adc_volts_per_count > 0.0f && c->offset_cal_samples > 0u && c->i_trip > 0.0f &&
                         c->vdc_max > c->vdc_min && c->angle_src < MC_ANGLE_SRC_COUNT && c->enc_counts_per_rev >= 4u;
    const bool loops = c->cc_bw_hz > 0.0f && c->i_max > 0.0f && c->i_max < c->i_trip && c->i_headroom >= 0.0f &&
                       c->i_headroom < 0.5f && c->i_slew > 0.0f && c->u_margin > 0.0f && c->u_margin <= 1.0f &&
                       c->sc_decimation >= 1 && c->torque_max > 0.0f && c->dead_time >= 0.0f;
    bool sensorless = true;
    if (c->angle_src == MC_ANGLE_SRC_UNOP) {
        const mc_unop_cfg_t *u = &c->unop;
        sensorless = u->iter_max >= 1 && u->iter_max <= 18 && u->ts == c->ts && u->omega_base > 0.0f &&
                     u->k1 >= 0.0f && u->k2 >= 0.0f && (u->model.kind != MC_FLUX_MAP || u->model.map != 0) &&
                     c->pll_bw_hz > 0.0f && c->pll_speed_fc_hz > 0.0f && c->inj.v1 >= 0.0f &&
                     c->inj.ts == c->ts && (c->inj.kind == MC_INJ_OFF || (c->inj.f_hz > 0.0f && c->inj.f_hz * c->ts <= 0.5f)) &&
                     c->notch_q > 0.0f;
    }
    bool startup = c->timeout_cal > 0.0f;
    if (c->init_three_step) {
        startup = startup && c->angle_src == MC_ANGLE_SRC_UNOP && c->timeout_step12 > 0.0f &&
                  c->timeout_step3 > 0.0f && c->step3_speed_tol > 0.0f && c->step3_hold > 0.0f &&
                  c->ip1.ts == c->ts && (c->ip2_dvi || (c->ip2.ts == c->ts && c->ip2.model.kind == MC_FLUX_MAP &&
                                                      c->ip2.model.map != 0));
    }
    return motor && sensing && loops && sensorless && startup;
}

static float i_ref_max(const mc_drive_cfg_t *c)
{
    return c->i_max * (1.0f - c->i_headroom);
}

void mc_drive_init_blocks(mc_drive_t *d)
{
    const mc_drive_cfg_t *c = &d->cfg;
    const mc_encoder_cfg_t ec = {.pole_pairs = c->pole_pairs, .counts_per_rev = c->enc_counts_per_rev,
                                 .offset_rad = c->enc_offset_rad, .ts = c->ts,
                                 .pll_bw_hz = c->enc_pll_bw_hz, .speed_fc_hz = c->enc_speed_fc_hz};
    mc_encoder_init(&d->enc, &ec);

    mc_cc_cfg_t cc;
    mc_cc_cfg_from_bandwidth(&cc, c->cc_bw_hz, c->rs, c->ld, c->lq, c->psi_pm, c->ts);
    cc.decouple = c->cc_decouple;
    mc_cc_init(&d->cc, &cc);

    const mc_sc_cfg_t sc = {.kp = c->sc_kp, .ki = c->sc_ki, .ts = c->ts * (float)c->sc_decimation,
                            .torque_max = c->torque_max, .decimation = c->sc_decimation};
    mc_sc_init(&d->sc, &sc);

    mc_tref_cfg_t tc = {.pole_pairs = c->pole_pairs,
                        .mach = {.ld = c->ld, .lq = c->lq, .psi_pm = c->psi_pm},
                        .i_max = i_ref_max(c), .u_margin = c->u_margin, .use_table = c->mtpa_table};
    mc_mtpa_table_fill_linear(&tc.table, &tc.mach, i_ref_max(c));
    mc_tref_init(&d->tref, &tc);

    mc_lpf1_init(&d->step3_speed, 50.0f, c->ts, 0.0f);
    mc_unop_init(&d->unop, &c->unop);
    /* PLL after the estimator: critically damped, the estimator's speed as feed-forward. */
    const float w = MC_2PI * c->pll_bw_hz;
    const mc_pll_cfg_t pc = {.kp = 2.0f * w, .ki = w * w, .ts = c->ts, .speed_fc_hz = c->pll_speed_fc_hz};
    mc_pll_init(&d->pll, &pc);
    mc_inj_init(&d->inj, &c->inj);
    const float f_notch = c->inj.f_hz < 0.45f / c->ts ? c->inj.f_hz : 0.45f / c->ts;
    mc_biquad_init_notch(&d->notch_d, f_notch, c->notch_q, c->ts);
    mc_biquad_init_notch(&d->notch_q, f_notch, c->notch_q, c->ts);

    const mc_dtc_cfg_t dc = {.t_dead = c->dead_time, .t_pwm = c->ts, .i_band = c->dtc_i_band,
                             .enable = c->dtc_enable};
    mc_dtc_init(&d->dtc, &dc);
}

bool mc_drive_init(mc_drive_t *d, const mc_drive_cfg_t *cfg, hal_adc_t *adc, hal_pwm_t *pwm, hal_qep_t *qep)
{
    *d = (mc_drive_t){0};
    d->cfg = *cfg;
    d->hal = (mc_drive_hal_t){.adc = adc, .pwm = pwm, .qep = qep};
    hal_pwm_enable(pwm, false);
    const mc_seq_cfg_t sc = {.ts = cfg->ts, .init_pos = cfg->init_three_step, .timeout_cal = cfg->timeout_cal,
                             .timeout_step12 = cfg->timeout_step12, .timeout_step3 = cfg->timeout_step3};
    mc_seq_init(&d->seq, &sc);
    for (int k = 0; k < 3; ++k) {
        d->offset[k] = cfg->adc_offset_nominal;
    }
    if (!cfg_valid(cfg)) {
        mc_seq_fault(&d->seq, MC_FAULT_CONFIG);
        d->tm.state = d->seq.state;
        d->tm.faults = d->seq.faults;
        return false;
    }
    mc_drive_init_blocks(d);
    return true;
}

void mc_drive_command(mc_drive_t *d, const mc_drive_cmd_t *cmd)
{
    d->cmd_next = *cmd;
    d->cmd_seq++;
}

const mc_drive_telem_t *mc_drive_telemetry(const mc_drive_t *d)
{
    return &d->tm;
}

static bool injecting(const mc_drive_t *d)
{
    return d->cfg.angle_src == MC_ANGLE_SRC_UNOP && d->cfg.inj.kind != MC_INJ_OFF;
}

/* Commands change only here, at the start of a period, as one consistent copy. */
static void take_command(mc_drive_t *d)
{
    if (d->cmd_seq == d->cmd_seen) {
        return;
    }
    d->cmd = d->cmd_next;
    d->cmd_seen = d->cmd_seq;
    if ((d->seq.faults & MC_FAULT_CONFIG) != 0u) {
        return;   /* a rejected configuration never runs */
    }
    if (mc_seq_enable(&d->seq, d->cmd.enable)) {
        mc_drive_startup_reset(d);   /* a new enable always starts clean */
    }
}

static void angle_source(mc_drive_t *d, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    switch (d->cfg.angle_src) {
    case MC_ANGLE_SRC_UNOP: {
        /* Fig. 6.9: Newton estimator, then the PLL as a filter with the estimated speed as
         * feed-forward; the controller uses the PLL's angle and filtered speed. */
        mc_angle_out_t raw;
        mc_unop_step(&d->unop, in, &raw);
        mc_pll_step(&d->pll, raw.theta, raw.omega);
        out->theta = d->pll.theta;
        out->omega = d->pll.omega_filt;
        d->tm.theta_raw = raw.theta;
        d->tm.omega_raw = raw.omega;
        d->tm.est_iters = d->unop.iters;
        d->tm.est_cost = d->unop.cost;
        d->tm.est_cond = d->unop.cond;
        break;
    }
    case MC_ANGLE_SRC_ENCODER:
    default:
        mc_encoder_step(&d->enc, in, out);
        d->tm.theta_raw = out->theta;
        d->tm.omega_raw = out->omega;
        break;
    }
}

/* The reference vector moves at most i_slew * ts per period: a step would make the current loop,
 * with its 1.5-period delay, overshoot by ~20 % of the step and exceed the current limit. */
static mc_dq_t slew(mc_drive_t *d, mc_dq_t target)
{
    const float dd = target.d - d->i_ref_prev.d;
    const float dq = target.q - d->i_ref_prev.q;
    const float step = d->cfg.i_slew * d->cfg.ts;
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

static mc_dq_t references(mc_drive_t *d, float omega, float vdc)
{
    float torque = 0.0f;
    switch (d->cmd.mode) {
    case MC_MODE_CURRENT:
        d->tm.torque_ref = 0.0f;
        return slew(d, mc_limit_current_circle(d->cmd.i_ref, i_ref_max(&d->cfg)));
    case MC_MODE_SPEED:
        torque = mc_sc_step(&d->sc, d->cmd.speed_ref, omega / (float)d->cfg.pole_pairs);
        break;
    case MC_MODE_TORQUE:
    default:
        torque = d->cmd.torque_ref;
        break;
    }
    d->tm.torque_ref = torque;
    return slew(d, mc_tref_step(&d->tref, torque, omega, vdc));
}

void mc_drive_isr(mc_drive_t *d)
{
    const mc_drive_cfg_t *c = &d->cfg;
    take_command(d);

    /* 1. Samples of this period (ADC triggered at the PWM centre) and the encoder. */
    hal_adc_sample_t raw;
    hal_adc_read(d->hal.adc, &raw);
    hal_qep_sample_t qep;
    hal_qep_read(d->hal.qep, &qep);

    /* 2. Scaling with the calibrated offsets; Clarke (2.4), all three channels measured. */
    const float vdc = (float)raw.vdc * c->adc_volts_per_count;
    const mc_abc_t i_abc = {((float)raw.i[0] - d->offset[0]) * c->adc_amps_per_count,
                            ((float)raw.i[1] - d->offset[1]) * c->adc_amps_per_count,
                            ((float)raw.i[2] - d->offset[2]) * c->adc_amps_per_count};
    const mc_ab_t i_ab = mc_clarke(i_abc);
    d->tm.period++;
    d->tm.i_abc = i_abc;
    d->tm.vdc = vdc;

    /* 3. Protection and the startup sequence (offset calibration, Step I and II pulses).
     *    Only RUN and Step III continue into the control pipeline. */
    if (!mc_drive_startup(d, &raw, i_abc, i_ab, vdc)) {
        d->i_ab_prev = i_ab;
        return;
    }

    /* 4. Angle source: it gets i(k-1), i(k) and the voltage applied between them. */
    const mc_angle_in_t ain = {.i_ab = i_ab, .i_ab_prev = d->i_ab_prev, .u_ab_applied = d->u_hist[1],
                               .vdc = vdc, .qep_count = qep.count};
    mc_angle_out_t ang;
    angle_source(d, &ain, &ang);

    /* 5. Park (2.5) into the controller's frame. While injecting, the current loop sees the
     *    currents with the injection frequency notched out, so it does not cancel it. */
    const mc_dq_t i_dq = mc_park(i_ab, mc_sincos(ang.theta));
    /* The angle of step 8 is known already: its sin/cos is taken here, where it does not wait
     * for the references and the current loop (an out-of-order core overlaps the two). */
    const mc_sincos_t sc_u = mc_sincos(mc_wrap_pi(ang.theta + 1.5f * ang.omega * c->ts));
    mc_dq_t i_fb = i_dq;
    if (injecting(d)) {
        i_fb.d = mc_biquad_step(&d->notch_d, i_dq.d);
        i_fb.q = mc_biquad_step(&d->notch_q, i_dq.q);
    }

    /* 6. References: current, torque (MTPA / field weakening) or speed; zero during Step III. */
    const bool step3 = d->seq.state == MC_STATE_INIT_POS;
    const mc_dq_t i_ref = step3 ? slew(d, (mc_dq_t){0.0f, 0.0f}) : references(d, ang.omega, vdc);

    /* 7. Current control, limited to the inscribed circle of the voltage hexagon; the HF
     *    injection (6.6) rides on the estimated d axis. */
    mc_dq_t u_dq = mc_cc_step(&d->cc, i_ref, i_fb, ang.omega, vdc * MC_1_SQRT3);
    d->tm.u_inj = injecting(d) ? mc_inj_step(&d->inj, ang.omega) : 0.0f;
    u_dq.d += d->tm.u_inj;

    /* 8. Inverse Park at the middle of the period the voltage will act in, (k+1, k+2): the
     *    one-period update delay plus the half period of the average (sc_u, taken in step 5). */
    const mc_ab_t u_ab = mc_park_inv(u_dq, sc_u);

    /* 9. SVPWM (min-max injection), then dead-time compensation with the current of that
     *    period, extrapolated from the last two samples (it carries the injection ripple, which
     *    decides the sign near zero crossings). */
    mc_duty_t duty;
    mc_svpwm(u_ab, vdc, &duty);
    const mc_ab_t i_next = {i_ab.alpha + 1.5f * (i_ab.alpha - d->i_ab_prev.alpha),
                            i_ab.beta + 1.5f * (i_ab.beta - d->i_ab_prev.beta)};
    mc_dtc_apply(&d->dtc, &duty, mc_clarke_inv(i_next));
    hal_pwm_set_duties(d->hal.pwm, duty.a, duty.b, duty.c);

    /* 10. Keep what the estimators need next period, and the telemetry. */
    d->u_hist[1] = d->u_hist[0];
    d->u_hist[0] = duty.u_real;
    d->i_ab_prev = i_ab;
    d->tm.theta = ang.theta;
    d->tm.omega = ang.omega;
    d->tm.i_dq = i_dq;
    d->tm.i_ref = i_ref;
    d->tm.u_dq = u_dq;
    d->tm.u_ab = duty.u_real;
    d->tm.duty[0] = duty.a;
    d->tm.duty[1] = duty.b;
    d->tm.duty[2] = duty.c;
    d->tm.u_limited = d->cc.limited;
    d->tm.fw_active = d->tref.fw_active;

    /* 11. Step III hands over to RUN when its convergence test holds (same estimator). */
    if (step3) {
        mc_drive_step3_check(d, ang.omega);
    }
}

void mc_drive_background(mc_drive_t *d)
{
    /* Slow work lives here, never in the ISR. For now: keep the telemetry's state in step with
     * the sequencer, so a reader never sees a stale state. */
    d->tm.state = d->seq.state;
    d->tm.init_step = d->seq.step;
    d->tm.faults = d->seq.faults;
}

mc_state_t mc_drive_state(const mc_drive_t *d)
{
    return d->seq.state;
}

uint32_t mc_drive_faults(const mc_drive_t *d)
{
    return d->seq.faults;
}
