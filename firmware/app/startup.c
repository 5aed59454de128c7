/* The drive's startup: it sequences the blocks that own their state (protection's hard trips,
 * mc/protect.h; the offset calibration, mc/offset_cal.h; the flying-start catch, mc/catch.h: a
 * turning rotor goes straight to RUN with its angle and speed, the field-weakening entry first)
 * and the initial position (thesis ch. 5): Step I pulse injection, Step II polarity detection,
 * then Step III, which is the normal control pipeline with zero current references and the
 * injection on, until its convergence test holds; and the reactions to a running fault.
 * The sequencer (mc/sequencer.h) owns the states, timeouts and fault reasons. */
#include <math.h>
#include <stddef.h>
#include "drive_internal.h"
#include "mc/angle.h"
#include "mc/sincos.h"
#include "mc/transforms.h"

/* Outputs off and duties at 50 % (zero voltage) so a later enable starts from rest. */
static void outputs_off(mc_drive_t *d)
{
    hal_pwm_enable(d->hal.pwm, false);
    mc_drive_duties(d, (mc_abc_t){0.5f, 0.5f, 0.5f});
}

void mc_drive_trip(mc_drive_t *d, uint32_t reason)
{
    outputs_off(d);
    mc_seq_fault(&d->seq, reason);
}

/* Reset of everything the estimator pipeline keeps between periods, with the estimate at
 * (theta, omega) for the sample the pipeline takes next. */
static void pipeline_reset(mc_drive_t *d, float theta, float omega)
{
    d->src->reset(&d->src_state, theta, omega);
    mc_inj_reset(&d->inj);
    mc_cc_reset(&d->cc);
    mc_biquad_reset(&d->notch_d, 0.0f);
    mc_biquad_reset(&d->notch_q, 0.0f);
    d->step3_speed = d->cfg->blk.step3_lpf;   /* coefficients built in the background, state at rest */
    d->step3_count = 0u;
    mc_protect_reset(&d->prot, &d->cfg->blk.prot, omega);
    d->i_ref_prev = (mc_dq_t){0.0f, 0.0f};
    d->tref.fw_did = 0.0f;
    mc_polcheck_reset(&d->pol);
}

void mc_drive_startup_reset(mc_drive_t *d)
{
    mc_protect_restart(&d->prot);
    d->tm.recoveries = 0u;
    d->tm.recovered_from = 0u;
    mc_polcheck_restart(&d->pol);
    mc_offsets_restart(&d->offs);
    d->entry = (mc_catch_entry_t){.corner = false, .gate_on_next = false};
    mc_fwe_reset(&d->fw_entry);
    mc_drive_init_blocks(d);
    /* Without the three steps the estimate starts from the angle given with the enable. */
    pipeline_reset(d, d->cmd.theta_init, 0.0f);
    d->i_ab_prev = (mc_ab_t){0.0f, 0.0f};
    d->u_hist[0] = d->u_hist[1] = (mc_ab_t){0.0f, 0.0f};
    d->tm.theta1 = d->tm.theta2 = 0.0f;
    d->tm.c1 = d->tm.c2 = d->tm.pol_z = 0.0f;
    d->tm.pol_flip = false;
    d->tm.pol_verdict = 0u;
}

/* Duties decided outside the control pipeline, with the voltage history kept true, so the
 * estimator's first Step III sample pairs the currents with the pulse that really acted. */
static void write_duties(mc_drive_t *d, mc_abc_t duty, float vdc)
{
    const mc_abc_t v = {(duty.a - 0.5f) * vdc, (duty.b - 0.5f) * vdc, (duty.c - 0.5f) * vdc};
    /* (2.4) drops the common mode: line-to-neutral vector */
    mc_drive_duties_kept(d, duty, mc_clarke(v), d->u_hist[0]);
}

/* Protection's hard trips and sensor checks (mc/protect.h), every period the outputs may be on. */
static void protect(mc_drive_t *d, const hal_adc_sample_t *raw, mc_abc_t i, float vdc)
{
    const uint32_t reason = mc_protect_sensors(&d->prot, &d->cfg->blk.prot, raw, i, vdc);
    if (reason != 0u) {
        mc_drive_trip(d, reason);
    }
}

/* The phase programs of Steps I and II (mc/phase_program.h), by the value of startup.step1_method
 * and startup.polarity, each with where its configuration sits in the derived block set. */
typedef struct {
    const mc_phase_program_t *prog;
    size_t cfg_offset;
} program_slot_t;

static const program_slot_t step1_programs[] = {
    {&mc_phase_step1_pulses, offsetof(mc_drive_blk_t, step1)},      /* "pulses"      */
    {&mc_phase_step1_pulse3, offsetof(mc_drive_blk_t, pulse3)},   /* "three_phase" */
};
static const program_slot_t step2_programs[] = {
    {&mc_phase_step2_polarity, offsetof(mc_drive_blk_t, step2)},    /* "generalized" */
    {&mc_phase_step2_dvi, offsetof(mc_drive_blk_t, dvi)},         /* "dvi"         */
};

static bool begin_program(mc_drive_t *d, const program_slot_t *slot, float theta_in)
{
    return mc_phase_begin(&d->phase, slot->prog, (const char *)&d->cfg->blk + slot->cfg_offset, theta_in);
}

static bool begin_step1(mc_drive_t *d)
{
    return begin_program(d, &step1_programs[d->cfg->blk.ip1_pulse3 ? 1 : 0], 0.0f);
}

/* RUN's current references start from the current that flows (bumpless: a rotor caught or
 * enabled at speed carries the diodes' or the catch's current), in the frame at theta, but
 * within the references' limit: a catch at speed may end above it (one zero-vector period of a
 * low-inductance motor, mc/catch.h), and references there would hold the current above it. */
static void refs_from_current(mc_drive_t *d, mc_ab_t i_ab, float theta)
{
    const mc_dq_t i = mc_park(i_ab, mc_sincos(mc_wrap_pi(theta)));
    const float m = sqrtf(i.d * i.d + i.q * i.q), lim = d->cfg->blk.i_ref_max;
    const float k = m > lim ? lim / m : 1.0f;
    d->i_ref_prev = (mc_dq_t){k * i.d, k * i.q};
}

/* A RUN entry that may find the rotor turning (the catch, an angle-sensor drive): the field-
 * weakening entry law first (mc/fw_entry.h; it ends at once where the flux can be held), and,
 * with the outputs off at this sample, RUN's first duties come on with them next period. */
static void run_at_speed(mc_drive_t *d, bool outputs_off_now)
{
    d->entry.gate_on_next = outputs_off_now;
    mc_fwe_begin(&d->fw_entry);
}

/* Once the speed is known (the catch, an angle sensor): the offsets over whole electrical half-
 * periods of the calibration's samples (O.1), which the diodes' current of a rotor turning above
 * the generation speed does not bias (mc_offsets_at_speed). Returns the change of the stator-
 * frame current this makes (new minus old) [A]; none where (O.1) does not apply. */
static mc_ab_t offsets_at_speed(mc_drive_t *d, float omega)
{
    mc_ab_t dab;
    if (mc_offsets_at_speed(&d->offs, &d->cfg->blk.offs, omega, &dab)) {
        d->i_ab_prev.alpha += dab.alpha;   /* the last sample as the new offsets give it */
        d->i_ab_prev.beta += dab.beta;
    }
    return dab;
}

/* An angle-sensor drive above the generation speed latches, every period its outputs are off
 * before RUN, the corner the field-weakening entry would start with (the sensor's angle +
 * sign(omega) 135 deg, as (C.6) of mc/catch.h): entering at a diode pulse's low, the outputs come
 * on with it at once, a step into the voltage limit instead of a period of the diodes. False
 * (nothing latched) where the entry will not run: the flux can be held, or no overmodulation. */
static bool latch_entry_corner(mc_drive_t *d)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    const float vdc = d->tm.vdc;
    if (!b->src_measures || !b->fw_entry.overmod) {
        return false;
    }
    const int k = mc_catch_entry_corner(&b->flying, d->tm.theta, d->tm.omega, vdc, mc_drive_u_land(d, vdc));
    if (k < 0) {
        return false;
    }
    write_duties(d, mc_svpwm_corner(k, NULL), vdc);
    return true;
}

/* Average the current channels with the outputs off; the offsets must be plausible. At a speed
 * where the diodes conduct, the plain mean is biased: the catch or the angle sensor replaces it
 * by offsets_at_speed() once the speed is known. */
static void offset_cal(mc_drive_t *d, const hal_adc_sample_t *raw)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    switch (mc_offsets_add(&d->offs, &b->offs, raw->i)) {
    case MC_OFFSETS_COLLECTING:
        d->entry.corner = latch_entry_corner(d);
        return;
    case MC_OFFSETS_FAILED:
        mc_drive_trip(d, MC_FAULT_OFFSET_CAL);
        return;
    case MC_OFFSETS_DONE:
        if (b->src_measures) {
            (void)offsets_at_speed(d, d->tm.omega);   /* the sensor's speed, tracked meanwhile */
        }
        break;
    case MC_OFFSETS_COUNTING:
    default:
        break;
    }
    /* with this period's offsets: the ISR scaled the sample with the previous ones */
    const mc_ab_t i_now = b->src_measures ? mc_clarke(mc_drive_currents(d, raw)) : (mc_ab_t){0.0f, 0.0f};
    if (b->src_measures && mc_catch_sensor_waits(&b->flying, d->offs.count - b->offs.samples, i_now)) {
        /* a sensor drive needs no catch, but above the uncontrolled-generation speed the diodes
         * conduct: it waits (outputs off, at most the catch's longest wait) for a diode pulse's
         * low, as the catch does (C.5), and starts from there */
        d->entry.corner = latch_entry_corner(d);
        return;
    }
    mc_seq_event(&d->seq, MC_SEQ_CAL_DONE);
    if (d->seq.state == MC_STATE_INIT_POS && d->seq.step == MC_INIT_CATCH) {
        /* the catch switches the outputs itself; V(000) latched for its first pulse */
        if (!mc_phase_begin(&d->phase, &mc_phase_catch, &d->cfg->blk.flying, 0.0f)) {
            mc_drive_trip(d, MC_FAULT_CONFIG);
            return;
        }
        write_duties(d, (mc_abc_t){0.0f, 0.0f, 0.0f}, d->cfg->p.hw_vdc_nominal_v);
        return;
    }
    const bool started = d->seq.state != MC_STATE_INIT_POS || begin_step1(d);
    if (d->seq.state == MC_STATE_INIT_POS && !started) {
        mc_drive_trip(d, MC_FAULT_CONFIG);
        return;
    }
    mc_drive_duties(d, (mc_abc_t){0.5f, 0.5f, 0.5f});
    if (d->seq.state == MC_STATE_RUN && b->src_measures) {
        /* the sensor's angle (tracked through the calibration, a period old) one period on */
        refs_from_current(d, i_now, d->tm.theta + d->tm.omega * b->ts);
        if (d->entry.corner) {
            /* the corner latched last period acts from now (latch_entry_corner) */
            hal_pwm_enable(d->hal.pwm, true);
            run_at_speed(d, false);
            return;
        }
        /* RUN's first duties, latched by the pipeline in this period, act with the outputs from
         * the next one: switched on now, the last latched duties (zero voltage) would short the
         * back-EMF for a period first (-2 A in q at 1500 rpm on the thesis motor) */
        run_at_speed(d, true);
        return;
    }
    hal_pwm_enable(d->hal.pwm, true);
}

bool mc_drive_recover(mc_drive_t *d, uint32_t reason, float vdc)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    if (!mc_protect_may_recover(&d->prot, &b->prot, reason, d->seq.state == MC_STATE_RUN)) {
        return false;
    }
    d->tm.recoveries++;
    d->tm.recovered_from |= reason;
    /* outputs off now, V(000) latched for the catch's first pulse */
    hal_pwm_enable(d->hal.pwm, false);
    write_duties(d, (mc_abc_t){0.0f, 0.0f, 0.0f}, vdc);
    mc_seq_event(&d->seq, MC_SEQ_RECOVER);
    if (!mc_phase_begin(&d->phase, &mc_phase_catch, &b->flying, 0.0f)) {
        mc_drive_trip(d, MC_FAULT_CONFIG);
    }
    /* the speed loop starts again from the caught speed, not from what it wound up to */
    const mc_sc_cfg_t sc = d->sc.cfg;
    mc_sc_init(&d->sc, &sc);
    return true;
}

bool mc_drive_react(mc_drive_t *d, uint32_t reason, float omega, float vdc)
{
    if (!mc_protect_may_hold(&d->cfg->blk.prot, reason, d->seq.state == MC_STATE_RUN, omega, vdc)) {
        return false;   /* below it, outputs off is current-free: the plain trip */
    }
    mc_seq_fault_reaction(&d->seq, reason);
    return true;
}

/* One period of the running phase program: its outputs-off flag (at once) and its duties (a
 * period later, mc/phase_program.h). */
static mc_ip_status_t phase_period(mc_drive_t *d, mc_ab_t i_ab, float vdc)
{
    const mc_phase_in_t in = {.i_ab = i_ab, .vdc = vdc};
    mc_phase_out_t out;
    const mc_ip_status_t st = mc_phase_step(&d->phase, &in, &out);
    if (out.off == hal_pwm_enabled(d->hal.pwm)) {
        hal_pwm_enable(d->hal.pwm, !out.off);
    }
    write_duties(d, out.duty, vdc);
    return st;
}

/* The catch's period; at its end a turning rotor goes to RUN with the estimate set to the
 * caught angle and speed, a standing one to Step I (or RUN with the given angle). */
static void catch_step(mc_drive_t *d, mc_ab_t i_ab, float vdc)
{
    const mc_ip_status_t st = phase_period(d, i_ab, vdc);
    if (st == MC_IP_RUNNING) {
        return;
    }
    mc_phase_result_t res;
    mc_phase_result(&d->phase, &res);
    mc_phase_stop(&d->phase);
    d->tm.theta1 = res.theta;
    d->tm.c1 = res.c1;
    d->tm.c2 = res.omega;
    switch (mc_catch_outcome(st, res.moving, d->tm.recoveries > 0u, d->seq.cfg.init_pos)) {
    case MC_CATCH_NO_FIT:
        mc_drive_trip(d, MC_FAULT_INIT_POS);   /* no sign for the speed, or (C.1) does not fit */
        return;
    case MC_CATCH_STALE:
        mc_drive_trip(d, d->tm.recovered_from);
        return;
    case MC_CATCH_TURNING: {
        /* the offsets over whole half-periods at the caught speed (the catch itself works on
         * current differences, which no offset biases) */
        const mc_ab_t di = offsets_at_speed(d, res.omega);
        i_ab.alpha += di.alpha;
        i_ab.beta += di.beta;
        /* the pipeline runs from this sample on: the estimate is the caught one */
        pipeline_reset(d, res.theta, res.omega);
        refs_from_current(d, i_ab, res.theta);
        d->pol.unsure = false;
        /* a pulse ended with the outputs off (mc/catch.h): they come on with RUN's first duties */
        run_at_speed(d, !hal_pwm_enabled(d->hal.pwm));
        mc_seq_event(&d->seq, MC_SEQ_CAUGHT);
        return;
    }
    case MC_CATCH_STANDING:
    default:
        break;
    }
    mc_seq_event(&d->seq, MC_SEQ_STEP_DONE);
    if (d->seq.state == MC_STATE_INIT_POS && !begin_step1(d)) {
        mc_drive_trip(d, MC_FAULT_CONFIG);
        return;
    }
    /* standing: the outputs stay off this period (the probe's small current decays through the
     * diodes); Step I switches them on with its first call, RUN here */
    if (d->seq.state == MC_STATE_RUN) {
        /* Under V(000) the devices' drop opposes the current like a dead zone: a back-EMF below
         * it drives none, so with a drop the probe's "standing" means only "slower than
         * omega_min + (4/3) v_device / psi_pm" (docs/protection.md; brodatzki-35kw under the harsh
         * profile: 50 rpm is 1.6 V of back-EMF behind ~2 V of drops). RUN then starts from the
         * given angle, which a turning rotor may have left anywhere: the polarity re-check runs
         * as with polarity_check = at_start, so that a wrong one is not kept at pi. */
        d->pol.unsure = d->cfg->blk.flying.v_device > 0.0f;
        hal_pwm_enable(d->hal.pwm, true);
    }
}

/* Step I, then Step II on the same workspace; returns the program's status. */
static mc_ip_status_t pulse_steps(mc_drive_t *d, mc_ab_t i_ab, float vdc)
{
    const mc_ip_status_t st = phase_period(d, i_ab, vdc);
    mc_phase_result_t res;
    if (st == MC_IP_FAILED && d->seq.step == MC_INIT_STEP2) {
        mc_phase_result(&d->phase, &res);   /* why it failed: an undecided polarity, a trip */
        d->tm.pol_z = res.conf;
        d->tm.pol_verdict = (uint8_t)res.verdict;
    }
    if (st != MC_IP_DONE) {
        return st;
    }
    mc_phase_result(&d->phase, &res);
    if (d->seq.step == MC_INIT_STEP1) {
        d->tm.theta1 = res.theta;
        if (!begin_program(d, &step2_programs[d->cfg->blk.ip2_dvi ? 1 : 0], res.theta)) {
            return MC_IP_FAILED;
        }
        mc_seq_event(&d->seq, MC_SEQ_STEP_DONE);
        return MC_IP_RUNNING;
    }
    d->tm.theta2 = res.theta;
    d->tm.pol_flip = res.flip;
    d->tm.c1 = res.c1;
    d->tm.c2 = res.c2;
    d->tm.pol_z = res.conf;
    d->tm.pol_verdict = (uint8_t)res.verdict;
    mc_phase_stop(&d->phase);
    /* Step III continues from theta2 with the running-state estimator itself (no method switch
     * later): only its state is set here. */
    pipeline_reset(d, res.theta, 0.0f);
    mc_seq_event(&d->seq, MC_SEQ_STEP_DONE);
    return st;
}

bool mc_drive_startup(mc_drive_t *d, const hal_adc_sample_t *raw, mc_abc_t i_abc, mc_ab_t i_ab, float vdc)
{
    const mc_state_t s0 = d->seq.state;
    if (s0 == MC_STATE_INIT_POS || s0 == MC_STATE_RUN || s0 == MC_STATE_FAULT_REACTION) {
        protect(d, raw, i_abc, vdc);
    }
    switch (d->seq.state) {
    case MC_STATE_OFFSET_CAL:
        offset_cal(d, raw);
        break;
    case MC_STATE_INIT_POS:
        if (d->seq.step == MC_INIT_CATCH) {
            catch_step(d, i_ab, vdc);
        } else if (d->seq.step == MC_INIT_STEP1 || d->seq.step == MC_INIT_STEP2) {
            if (pulse_steps(d, i_ab, vdc) == MC_IP_FAILED) {
                mc_drive_trip(d, MC_FAULT_INIT_POS);
            }
        }
        break;
    case MC_STATE_IDLE:
    case MC_STATE_FAULT:
        if (hal_pwm_enabled(d->hal.pwm)) {
            outputs_off(d);
        }
        break;
    case MC_STATE_FAULT_REACTION:
        if (mc_protect_reaction_done(&d->cfg->blk.prot, d->tm.omega, vdc)) {
            mc_seq_event(&d->seq, MC_SEQ_REACTION_DONE);
            outputs_off(d);
        }
        break;
    case MC_STATE_RUN:
    default:
        break;
    }
    mc_seq_tick(&d->seq);
    mc_protect_tick(&d->prot, &d->cfg->blk.prot, d->seq.state == MC_STATE_RUN, d->seq.ticks);
    if (d->seq.state == MC_STATE_FAULT && hal_pwm_enabled(d->hal.pwm)) {
        outputs_off(d);   /* a timeout raised by the tick */
    }
    return d->seq.state == MC_STATE_RUN || d->seq.state == MC_STATE_FAULT_REACTION ||
           (d->seq.state == MC_STATE_INIT_POS && d->seq.step == MC_INIT_STEP3 && s0 == MC_STATE_INIT_POS &&
            d->seq.ticks > 1u);
}

void mc_drive_step3_check(mc_drive_t *d, float omega_hat)
{
    /* Converged when the estimate has stopped moving: the low-passed |omega_hat| (the rotor is
     * at rest in Step III) stays below the tolerance for step3_hold, and Step III lasted at
     * least twice that (the estimate starts at rest too). */
    const float w = mc_lpf1_step(&d->step3_speed, fabsf(omega_hat));
    d->step3_count = w < d->cfg->blk.step3_speed_tol ? d->step3_count + 1u : 0u;
    const uint32_t hold = d->cfg->blk.step3_hold;
    if (d->step3_count >= hold && d->seq.ticks >= 2u * hold) {
        mc_seq_event(&d->seq, MC_SEQ_STEP_DONE);
    }
}
