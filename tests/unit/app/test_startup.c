/* The drive's startup sequencing (startup.c) at the hand-overs a mutation run showed untested
 * (issue 30):
 *   - the calibration's end with the three-step start: the outputs come on in that period at
 *     zero voltage, and Step I runs the program startup.step1_method selects, with its
 *     configuration: its duties, period by period, are those of that program run on its own
 *     with the same inputs;
 *   - RUN entered with the given angle (no steps, no catch): the current references start from
 *     zero and move from there at control.i_slew, with no d-axis step;
 *   - Steps I-III on a synthetic saturating plant: Step II's decision quantities and flip in the
 *     telemetry;
 *   - Step III's convergence test: at least twice startup.step3_hold_s, the estimate at rest for
 *     the last step3_hold of it;
 *   - an angle-sensor drive's wait for a diode pulse's low after the calibration: bounded; its
 *     RUN entry with current flowing: references from that current (bumpless);
 *   - IDLE and FAULT leave the PWM alone;
 *   - a Step I or Step II configuration its engine refuses: the fault at once, the outputs never on;
 *   - a restart starts the blocks (the speed loop) from rest;
 *   - the recovery budget refills only with time in RUN, not in Steps I-III;
 *   - the catch against a spinning machine above the generation speed: angle, speed, the offsets
 *     (O.1) puts in place of the calibration's biased mean, and RUN holding at zero torque.
 * A plant-less rig (the host HAL, zero currents, 300 V), as test_drive.c's, or the small plants
 * below (a synthetic saturating one at rest; a turning rotor with its diodes' current). */
#include <string.h>

#include "../mc_test.h"
#include "hal_host/host.h"
#include "mc/drive.h"
#include "mc/catch.h"
#include "mc/phase_program.h"
#include "mc/transforms.h"
#include "drive_internal.h"   /* mc_drive_startup_reset, mc_drive_step3_check */
#include "spin_plant.h"

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    mc_drive_cfg_t cfg;
    mc_drive_link_t link;
    mc_drive_t d;
} rig_t;

/* source "encoder" or "unop"; init_pos "given" or "three_step"; step1 "pulses" or "three_phase"
 * (Step II dvi and the linear cost: no flux map needed) */
static void rig_init(rig_t *r, const char *source, const char *init_pos, const char *step1)
{
    memset(r, 0, sizeof *r);
    hal_host_pwm_init(&r->pwm, 1e-4f, 0.5e-6f);
    r->qep = (hal_qep_t){.counts_per_rev = 80000u};
    mc_drive_cfg_default(&r->cfg);
    mc_params_t *p = &r->cfg.p;
    assert_true(mc_param_set_choice(p, MC_PARAM_control_angle_source, source, NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_estimator_model, "const", NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_startup_catch, "off", NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_startup_init_pos, init_pos, NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_startup_step1_method, step1, NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_startup_step1_cost, "linear", NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_startup_polarity, "dvi", NULL));
    /* no plant: no voltage explains the currents (test_drive.c's rig) */
    assert_true(mc_param_set(p, MC_PARAM_protection_residual_time_s, 0.0f, NULL));
    /* a slew of 0.2 A a period: a reference step of 1 A takes 5 periods */
    assert_true(mc_param_set(p, MC_PARAM_control_i_slew_a_per_s, 2e3f, NULL));
    if (!mc_drive_init(&r->d, &r->link, &r->cfg, &r->adc, &r->pwm, &r->qep)) {
        const mc_param_err_t *e = mc_drive_config_error(&r->d);
        fail_msg("config refused: %s (parameter %d)", e->text, e->param);
    }
    for (int k = 0; k < 3; ++k) {
        r->adc.sample.i[k] = (uint16_t)r->d.cfg->blk.offs.nominal;   /* zero current */
    }
    r->adc.sample.vdc = (uint16_t)lrintf(300.0f / r->d.cfg->blk.volts_per_count);
}

static void run(rig_t *r, int n)
{
    for (int k = 0; k < n; ++k) {
        hal_host_pwm_latch(&r->pwm);
        mc_drive_isr(&r->d);
        assert_int_equal(r->pwm.nonfinite, 0u);
    }
}

/* enabled; run until the calibration ends (the period it does included) */
static void through_calibration(rig_t *r, float theta_init, mc_dq_t i_ref)
{
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT, .i_ref = i_ref, .theta_init = theta_init};
    mc_drive_command(&r->d, &c);
    const int limit = (int)r->d.cfg->p.control_offset_cal_samples + 10;
    int n = 0;
    run(r, 1);
    for (; n < limit && mc_drive_state(&r->d) == MC_STATE_OFFSET_CAL; ++n) {
        run(r, 1);
    }
    assert_true(n < limit);
}

/* The three-step start (UNOP) at the calibration's end: state INIT_POS, Step I, the outputs on
 * at zero voltage (50 % duties) in that very period (the first pulse is written the next); Step
 * I is the selected program with its configuration from the derived set: over its first periods
 * (up to 40) the drive writes the duties that program writes when run on its own with the same
 * measured currents (zero) and link voltage. (startup.c:105, the selection.) */
static void test_step1_runs_the_selected_program(void **state)
{
    (void)state;
    static rig_t r;
    const char *const methods[] = {"pulses", "three_phase"};
    for (int m = 0; m < 2; ++m) {
        rig_init(&r, "unop", "three_step", methods[m]);
        through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
        assert_int_equal(r.d.seq.step, MC_INIT_STEP1);
        assert_true(hal_pwm_enabled(&r.pwm));
        for (int k = 0; k < 3; ++k) {
            assert_true(r.pwm.shadow[k] == 0.5f);
        }
        const mc_drive_blk_t *b = &r.d.cfg->blk;
        const mc_phase_program_t *prog = m == 1 ? &mc_phase_step1_pulse3 : &mc_phase_step1_pulses;
        assert_ptr_equal(r.d.phase.prog, prog);
        static mc_phase_t own;
        assert_true(mc_phase_begin(&own, prog, m == 1 ? (const void *)&b->pulse3 : (const void *)&b->step1, 0.0f));
        const mc_phase_in_t in = {.i_ab = {0.0f, 0.0f}, .vdc = 300.0f};
        int periods = 0;
        for (; periods < 40; ++periods) {
            mc_phase_out_t out;
            if (mc_phase_step(&own, &in, &out) != MC_IP_RUNNING) {
                break;
            }
            run(&r, 1);
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
            assert_int_equal(r.d.seq.step, MC_INIT_STEP1);
            assert_true(hal_pwm_enabled(&r.pwm));
            assert_near(r.pwm.shadow[0], out.duty.a, 1e-6);
            assert_near(r.pwm.shadow[1], out.duty.b, 1e-6);
            assert_near(r.pwm.shadow[2], out.duty.c, 1e-6);
        }
        print_message("%s: %d periods compared\n", methods[m], periods);
        assert_true(periods >= 5);
    }
}

/* RUN with the given angle (startup.init_pos given, no catch), an estimator drive: the current
 * references start from zero, not from what an earlier run left. With zero asked, they stay
 * exactly zero; with 2 A in q asked, q moves up by control.i_slew * ts a period and d stays
 * exactly zero (a d step would be a torque-free current pulse at the start); the outputs are on
 * from the entry period. The estimate starts at rest: with zero asked nothing moves, |omega_hat|
 * stays below 1e-3 rad/s over those periods (with 2 A asked and no plant to answer it, the
 * estimate moves). (startup.c:40, :56; :205, the sensor drive's entry only for a sensor
 * drive.) */
static void test_references_start_from_zero(void **state)
{
    (void)state;
    static rig_t r;
    for (int c = 0; c < 2; ++c) {
        rig_init(&r, "unop", "given", "pulses");
        const float iq = c == 0 ? 0.0f : 2.0f;
        through_calibration(&r, 0.3f, (mc_dq_t){0.0f, iq});
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
        /* an estimator drive at rest: the outputs on in the entry period, no entry law waiting
         * for a diode pulse's low (that is an angle-sensor drive's at speed) */
        assert_true(hal_pwm_enabled(&r.pwm));
        assert_false(r.d.entry.gate_on_next);
        const float step = r.d.cfg->blk.i_slew * r.d.cfg->blk.ts;
        assert_true(step > 0.0f && step < 0.5f);
        /* the pipeline ran in RUN's first period (the calibration's last): one step so far */
        float w_max = 0.0f;
        for (int k = 1; k <= 12; ++k) {
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
            /* the estimate starts at the given angle and at rest */
            w_max = fmaxf(w_max, fabsf(mc_drive_telemetry(&r.d)->omega));
            const mc_dq_t ref = mc_drive_telemetry(&r.d)->i_ref;
            assert_true(ref.d == 0.0f);
            assert_near(ref.q, fminf(iq, (float)k * step), 1e-5);
            run(&r, 1);
        }
        if (c == 0) {
            print_message("RUN's first 12 periods at 0 A: |omega_hat| <= %.3g rad/s\n", (double)w_max);
            assert_true(w_max < 1e-3f);
        }
    }
}

/* Step III hands over to RUN when the low-passed |omega_hat| has stayed below the tolerance for
 * step3_hold periods and Step III lasted at least twice that: the estimate starts at rest too,
 * so a hold from its first period alone proves nothing. Periods as the ISR runs them (the
 * sequencer's tick, then from the second tick on the pipeline and the test): at rest throughout,
 * the hand-over is at tick 2 step3_hold exactly; one period of a moving estimate (100 x the
 * tolerance: above it after the 50 Hz low-pass) at tick hold + 2 restarts the hold: the
 * hand-over comes later than a full hold after it. (startup.c:408.) */
static void test_step3_lasts_twice_the_hold(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "three_step", "pulses");
    const uint32_t hold = r.d.cfg->blk.step3_hold;
    assert_true(hold >= 3u);
    const float tol = r.d.cfg->blk.step3_speed_tol;
    for (int c = 0; c < 2; ++c) {
        mc_drive_startup_reset(&r.d);   /* Step III's convergence state at rest */
        r.d.seq.state = MC_STATE_INIT_POS;   /* as Step II's end enters Step III */
        r.d.seq.step = MC_INIT_STEP3;
        r.d.seq.ticks = 0u;
        r.d.seq.limit = 0u;   /* no timeout: the test alone decides */
        const uint32_t spike = c == 0 ? 0u : hold + 2u;
        uint32_t done = 0u, above = 0u;   /* the last tick the low-passed speed was not below */
        for (uint32_t t = 0u; t < 10u * hold && done == 0u; ++t) {
            mc_seq_tick(&r.d.seq);
            const uint32_t now = r.d.seq.ticks;   /* RUN's entry restarts the count */
            if (now > 1u) {
                mc_drive_step3_check(&r.d, now == spike ? 100.0f * tol : 0.0f);
                if (!(r.d.step3_speed.y < tol)) {
                    above = now;
                }
            }
            if (r.d.seq.state == MC_STATE_RUN) {
                done = now;
            }
        }
        if (c == 0) {
            assert_int_equal(above, 0u);
            assert_int_equal(done, 2u * hold);
        } else {
            /* a full hold of periods below the tolerance after the last one above it */
            assert_true(above > spike && above + hold > 2u * hold);
            assert_int_equal(done, above + hold);
        }
    }
}

/* An angle-sensor drive enabled on a turning rotor waits after the calibration, outputs off, for
 * a diode pulse's low, at most the catch's longest wait (flying.n_wait_max periods) and never
 * longer, also with a calibration shorter than that wait (8 samples): with a current that never
 * comes down to the low (5 A in a and -5 A in b from the calibration's last sample on: 1/8 of
 * it in the offsets), it enters RUN once it has waited n_wait_max periods, not at the
 * calibration's timeout. (startup.c:182:
 * the periods waited counted from the calibration's end.) */
static void test_sensor_wait_is_bounded(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "encoder", "given", "pulses");
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_control_offset_cal_samples, 8.0f, NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    const uint32_t samples = r.d.cfg->blk.offs.samples, wait = r.d.cfg->blk.flying.n_wait_max;
    assert_int_equal(samples, 8u);
    assert_true(wait > 2u * samples);   /* longer than the calibration, a few times */
    const float amps = 5.0f, k = r.d.cfg->blk.offs.amps_per_count, nominal = (float)r.d.cfg->blk.offs.nominal;
    const mc_ab_t i_ab = {amps, (amps + 2.0f * amps) / sqrtf(3.0f)};   /* Clarke of (5, -5, 0) A */
    assert_false(mc_catch_at_low(&r.d.cfg->blk.flying, i_ab));
    assert_true(amps < r.d.cfg->blk.prot.i_trip);
    const uint32_t step = 80000u * 1500u / 60u / 10000u;   /* counts per period at 1500 rpm */
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT};
    mc_drive_command(&r.d, &c);
    uint32_t after = 0u;   /* periods from the calibration's last (included) */
    for (int n = 0; n < 5000 && mc_drive_state(&r.d) != MC_STATE_RUN && mc_drive_state(&r.d) != MC_STATE_FAULT; ++n) {
        if (r.d.offs.count + 1u >= samples) {   /* from the sample that ends the calibration */
            r.adc.sample.i[0] = (uint16_t)lrintf(nominal + amps / k);
            r.adc.sample.i[1] = (uint16_t)lrintf(nominal - amps / k);
            ++after;
        }
        r.qep.sample.count = (r.qep.sample.count + step) % 80000u;
        run(&r, 1);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    print_message("RUN %u periods after the calibration (n_wait_max %u)\n", after, wait);
    assert_int_equal(after, 1u + wait);   /* the last sample's period, then n_wait_max waited */
}

/* An encoder drive enabled in current mode while the rotor turns at rpm from encoder count
 * start, with i_a = -i_b = amps flowing from the calibration's last sample on: run to RUN. */
static void enter_turning(rig_t *r, uint32_t start, int32_t rpm, float amps)
{
    rig_init(r, "encoder", "given", "pulses");
    const float k = r->d.cfg->blk.offs.amps_per_count, nominal = (float)r->d.cfg->blk.offs.nominal;
    const uint32_t samples = r->d.cfg->blk.offs.samples;
    const int32_t step = rpm * 80000 / 60 / 10000;   /* counts per period */
    r->qep.sample.count = start;
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT};
    mc_drive_command(&r->d, &c);
    for (int n = 0; n < 5000 && mc_drive_state(&r->d) != MC_STATE_RUN; ++n) {
        if (r->d.offs.count + 1u >= samples) {
            r->adc.sample.i[0] = (uint16_t)lrintf(nominal + amps / k);
            r->adc.sample.i[1] = (uint16_t)lrintf(nominal - amps / k);
        }
        r->qep.sample.count = (uint32_t)(((int32_t)r->qep.sample.count + step + 80000) % 80000);
        run(r, 1);
    }
    assert_int_equal(mc_drive_state(&r->d), MC_STATE_RUN);
}

static const uint32_t entry_starts[] = {0u, 13000u, 29000u, 51000u, 70000u};

/* Bumpless RUN entry of an angle-sensor drive on a turning rotor (800 rpm, either way: the flux
 * is held, no field-weakening entry) with 5 A flowing: RUN's first current reference starts from
 * the current measured, in the frame of the sensor's angle one period on (the frame the pipeline
 * then uses), and moves one slew step (0.2 A) toward the command (0 A), along the current: its
 * angle is the current's to within 2 % of the rotor's turn in a period (0.042 rad), from several
 * rotor angles. (startup.c:207, the frame of RUN's first references: the angle a period old, or
 * one period back, is a turn off.) */
static void test_sensor_entry_references_from_the_current(void **state)
{
    (void)state;
    static rig_t r;
    const int32_t speeds[] = {800, -800};
    for (size_t v = 0; v < 2u; ++v) {
        for (size_t a = 0; a < sizeof entry_starts / sizeof entry_starts[0]; ++a) {
            enter_turning(&r, entry_starts[a], speeds[v], 5.0f);
            const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
            const float slew = r.d.cfg->blk.i_slew * r.d.cfg->blk.ts;
            const float dd = tm->i_ref.d - tm->i_dq.d, dq = tm->i_ref.q - tm->i_dq.q;
            assert_true(hypotf(tm->i_dq.d, tm->i_dq.q) > 4.0f);   /* the current flows */
            assert_near(sqrtf(dd * dd + dq * dq), slew, 1e-3);        /* one step toward 0 A */
            /* ... along the current itself: the frames agree to far below a period's turn */
            const float turn = fabsf(r.d.tm.omega * r.d.cfg->blk.ts);
            assert_true(turn > 0.03f);
            const float ang = remainderf(atan2f(tm->i_ref.q, tm->i_ref.d) - atan2f(tm->i_dq.q, tm->i_dq.d), 6.2831853f);
            assert_true(fabsf(ang) < 0.02f * turn);
        }
    }
}

/* ... and with more current flowing than the references may ask (1.2 x i_ref_max, the catch of a
 * low-inductance motor can leave that, mc/catch.h), RUN's first reference is that current scaled
 * to the limit (then one slew step toward the command), whatever its direction: not the current
 * itself, which the loop would hold above the limit. (startup.c refs_from_current.) */
static void test_sensor_entry_references_within_the_limit(void **state)
{
    (void)state;
    static rig_t r;
    for (size_t a = 0; a < sizeof entry_starts / sizeof entry_starts[0]; ++a) {
        rig_init(&r, "encoder", "given", "pulses");
        const float lim = r.d.cfg->blk.i_ref_max;
        enter_turning(&r, entry_starts[a], 800, 1.2f * lim / 1.1547005f);   /* |i| = 1.1547 amps */
        const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
        const float slew = r.d.cfg->blk.i_slew * r.d.cfg->blk.ts;
        assert_true(hypotf(tm->i_dq.d, tm->i_dq.q) > 1.1f * lim);   /* more flows than the limit */
        const float ref = hypotf(tm->i_ref.d, tm->i_ref.q);
        assert_true(ref <= lim && ref >= lim - 2.0f * slew);
    }
}

/* With the outputs off and nothing to run (IDLE, FAULT) the drive leaves the PWM alone: no duty
 * write and no enable call period after period (the duties it left at 50 % stay latched), only
 * the one outputs-off of the period it got there. (startup.c:376: outputs off only if on.) */
static void test_idle_and_fault_leave_the_pwm_alone(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "encoder", "given", "pulses");
    uint32_t w = r.pwm.writes;
    run(&r, 50);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
    assert_int_equal(r.pwm.writes, w);
    through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
    run(&r, 20);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_true(hal_pwm_enabled(&r.pwm));
    /* disabled: IDLE */
    const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
    mc_drive_command(&r.d, &off);
    run(&r, 1);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
    assert_false(hal_pwm_enabled(&r.pwm));
    w = r.pwm.writes;
    for (int k = 0; k < 50; ++k) {
        run(&r, 1);
        assert_int_equal(r.pwm.writes, w);
        assert_false(hal_pwm_enabled(&r.pwm));
    }
    /* a fault: FAULT */
    through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
    run(&r, 20);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    const float i = r.d.cfg->blk.prot.i_trip + 1.0f;
    r.adc.sample.i[0] = (uint16_t)lrintf((float)r.d.cfg->blk.offs.nominal + i / r.d.cfg->blk.offs.amps_per_count);
    run(&r, 1);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_false(hal_pwm_enabled(&r.pwm));
    for (int k = 0; k < 3; ++k) {
        assert_true(r.pwm.shadow[k] == 0.5f);
    }
    w = r.pwm.writes;
    for (int k = 0; k < 50; ++k) {
        run(&r, 1);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
        assert_int_equal(r.pwm.writes, w);
        assert_false(hal_pwm_enabled(&r.pwm));
    }
}

/* The synthetic saturating plant of the three-step tests: this period's sample is a resistive
 * answer to the voltage acting (the latched duties at 300 V), 5/3 times larger along +alpha than
 * along -alpha (magnet 0: the magnet at 0, its flux saturating the d axis) or the other way
 * (magnet 1: at pi); no back-EMF: the rotor stands. */
static void saturating_answer(rig_t *r, int magnet)
{
    const float k = r->d.cfg->blk.offs.amps_per_count, nominal = (float)r->d.cfg->blk.offs.nominal;
    const mc_ab_t v = mc_clarke((mc_abc_t){(r->pwm.active[0] - 0.5f) * 300.0f, (r->pwm.active[1] - 0.5f) * 300.0f,
                                            (r->pwm.active[2] - 0.5f) * 300.0f});
    const float g = (v.alpha > 0.0f) == (magnet == 0) ? 0.05f : 0.03f;
    const mc_abc_t i = mc_clarke_inv((mc_ab_t){g * v.alpha, g * v.beta});
    r->adc.sample.i[0] = (uint16_t)lrintf(nominal + i.a / k);
    r->adc.sample.i[1] = (uint16_t)lrintf(nominal + i.b / k);
    r->adc.sample.i[2] = (uint16_t)lrintf(nominal + i.c / k);
}

/* Steps I-III on a synthetic plant whose current answers a voltage along +alpha 5/3 times more
 * than one along -alpha (a d axis saturating with the magnet's flux: the magnet at 0), or the
 * other way (the magnet at pi): Step I finds the axis (theta1 = 0), Step II (dual-voltage
 * injection) measures the peak currents of its +V and -V pulses, c1 and c2 in the telemetry, in
 * the ratio 5/3 or 3/5, and flips to pi in the second case only; Step III hands over to RUN.
 * The verdict and its confidence show once Step II has decided, none while it runs. Step III's
 * estimate starts at rest (the rotor stands). (startup.c:349-358: the decision's
 * quantities, as Step II measured them, in the telemetry; Step III from theta2 at rest.) */
static void test_step2_decision_in_telemetry(void **state)
{
    (void)state;
    static rig_t r;
    for (int magnet = 0; magnet < 2; ++magnet) {
        rig_init(&r, "unop", "three_step", "pulses");
        through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
        int n = 0;
        float w_start = 0.0f;   /* |omega_hat| over Step III's first 20 periods */
        int step2 = 0;   /* periods that ended in Step II */
        for (; n < 3000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
            saturating_answer(&r, magnet);
            run(&r, 1);
            if (r.d.seq.step == MC_INIT_STEP2) {
                /* no verdict, no confidence before Step II has decided */
                ++step2;
                assert_int_equal(mc_drive_telemetry(&r.d)->pol_verdict, 0);
                assert_true(mc_drive_telemetry(&r.d)->pol_z == 0.0f);
            }
            if (r.d.seq.step == MC_INIT_STEP3 && r.d.seq.ticks <= 20u) {
                w_start = fmaxf(w_start, fabsf(mc_drive_telemetry(&r.d)->omega));
            }
        }
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
        assert_true(step2 > 5);
        const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
        assert_near(tm->theta1, 0.0f, 1e-3);
        assert_int_equal(tm->pol_verdict, MC_POL_DECIDED);
        assert_true(tm->pol_z > 0.0f);
        assert_true(tm->c1 > 1.0f && tm->c2 > 1.0f);
        assert_near(tm->c1 / tm->c2, magnet == 0 ? 5.0f / 3.0f : 3.0f / 5.0f, 0.02);
        assert_int_equal(tm->pol_flip, magnet == 1);
        assert_near(fabsf(tm->theta2), magnet == 0 ? 0.0f : 3.14159265f, 1e-3);
        /* Step III's estimate starts at rest on the standing rotor: none of the speed it would
         * have made up from a start off zero (0.1 rad/s: 0.07-0.3 rad/s in these periods) */
        print_message("Step III's first 20 periods: |omega_hat| <= %.3g rad/s\n", (double)w_start);
        assert_true(w_start < 1e-3f);
    }
}

/* The derived set as the drive holds it: the tests below corrupt one block's configuration, which
 * the build's validation never lets through, to reach the startup's defensive branches. */
static mc_drive_blk_t *held_blocks(rig_t *r)
{
    return &((mc_drive_built_t *)r->d.cfg)->blk;
}

/* A Step I configuration its engine refuses (startup.step1_method "pulses" with m = 0, or
 * "three_phase" with n = 0): the calibration's last period faults the drive with the configuration
 * reason, the duties at 50 %, and the outputs never come on, not even for the rest of that
 * interrupt (on hardware an enable undone later in the ISR fires the gates with the duties
 * latched). (startup.c:201-203.) */
static void test_step1_refused_never_enables(void **state)
{
    (void)state;
    static rig_t r;
    const char *const methods[] = {"pulses", "three_phase"};
    for (int m = 0; m < 2; ++m) {
        rig_init(&r, "unop", "three_step", methods[m]);
        if (m == 0) {
            held_blocks(&r)->step1.m = 0;
        } else {
            held_blocks(&r)->pulse3.n = 0;
        }
        const uint32_t edges = r.pwm.on_edges;
        through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
        assert_int_equal(mc_drive_faults(&r.d), MC_FAULT_CONFIG);
        assert_false(hal_pwm_enabled(&r.pwm));
        assert_int_equal(r.pwm.on_edges, edges);
        for (int k = 0; k < 3; ++k) {
            assert_true(r.pwm.shadow[k] == 0.5f);
        }
        run(&r, 20);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
        assert_int_equal(r.pwm.on_edges, edges);
    }
}

/* A Step II configuration its engine refuses (DVI with a zero pulse voltage): Step I runs on the
 * synthetic plant and, in the very period it ends, the drive faults with the initial-position
 * reason and the outputs off; Step II never starts (no period of it, with the outputs on and
 * whatever duties its refused program holds). Step I's angle is in the telemetry.
 * (startup.c:343-344.) */
static void test_step2_refused_faults_at_step1_end(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "three_step", "pulses");
    held_blocks(&r)->dvi.v = 0.0f;
    through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
    int n = 0;
    for (; n < 3000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        assert_int_equal(r.d.seq.step, MC_INIT_STEP1);
        saturating_answer(&r, 0);
        run(&r, 1);
    }
    assert_true(n > 5 && n < 3000);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_int_equal(mc_drive_faults(&r.d), MC_FAULT_INIT_POS);
    assert_false(hal_pwm_enabled(&r.pwm));
    assert_near(mc_drive_telemetry(&r.d)->theta1, 0.0f, 1e-3);
}

/* A restart starts the blocks from rest: a speed loop wound up against a rotor that does not
 * turn (150 rad/s asked, the encoder standing) until the stall detector faults the drive, then
 * disable and enable with 0 rad/s asked: RUN's speed loop starts from zero, its torque reference
 * exactly 0 (the encoder says 0) for the first 100 periods, not the torque the last run wound up
 * to. (startup.c:54, the blocks initialised at every enable.) */
static void test_restart_starts_the_speed_loop_from_rest(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "encoder", "given", "pulses");
    mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_SPEED, .speed_ref = 150.0f};
    mc_drive_command(&r.d, &c);
    float wound = 0.0f;
    for (int n = 0; n < 20000 && mc_drive_state(&r.d) != MC_STATE_FAULT; ++n) {
        run(&r, 1);
        if (mc_drive_state(&r.d) == MC_STATE_RUN) {
            wound = mc_drive_telemetry(&r.d)->torque_ref;
        }
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    print_message("faults 0x%x, the torque reference wound up to %.2f N m\n", mc_drive_faults(&r.d), (double)wound);
    assert_true(wound > 1.0f);
    c = (mc_drive_cmd_t){.enable = false, .mode = MC_MODE_SPEED};
    mc_drive_command(&r.d, &c);
    run(&r, 2);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
    c = (mc_drive_cmd_t){.enable = true, .mode = MC_MODE_SPEED, .speed_ref = 0.0f};
    mc_drive_command(&r.d, &c);
    for (int n = 0; n < 1000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
        run(&r, 1);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    for (int k = 0; k < 100; ++k) {
        assert_true(mc_drive_telemetry(&r.d)->torque_ref == 0.0f);
        assert_true(mc_drive_telemetry(&r.d)->i_ref.q == 0.0f);
        run(&r, 1);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    }
}

/* The recovery budget (protection.retries) counts from zero again only after
 * protection.retry_reset_s of RUN: a budget spent by a recovery whose catch found the rotor
 * standing (then Steps I-III run, startup.init_pos three_step) is still spent when RUN begins, also
 * with Step III (2 x 10 ms) longer than retry_reset_s (15 ms): a loss of lock in RUN's first
 * periods faults instead of recovering again. After retry_reset_s of RUN it recovers.
 * (startup.c:399: the time counted is RUN's.) */
static void test_recovery_budget_refills_in_run_only(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "three_step", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_protection_retries, 1.0f, NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_protection_retry_reset_s, 0.015f, NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_startup_step3_hold_s, 0.01f, NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    const uint32_t reset_n = r.d.cfg->blk.prot.retry_reset_n;
    assert_int_equal(reset_n, 150u);
    assert_true(r.d.cfg->blk.prot.recover);
    through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
    r.d.prot.retries = 1u;   /* as the recovery before this start left it */
    uint32_t step3 = 0u;
    for (int n = 0; n < 5000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        saturating_answer(&r, 0);
        run(&r, 1);
        step3 += r.d.seq.step == MC_INIT_STEP3 ? 1u : 0u;
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_true(step3 > reset_n);
    const float vdc = mc_drive_telemetry(&r.d)->vdc;
    run(&r, 2);
    assert_false(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, vdc));
    assert_int_equal(r.d.prot.retries, 1u);
    /* RUN for retry_reset_s: the budget is back */
    while (r.d.seq.ticks < reset_n) {
        run(&r, 1);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    }
    assert_true(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, vdc));
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
    assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
}

/* ---- the drive's catch against a spinning machine ---- */

/* One period of the rig on the spinning machine (spin_plant.h). */
static mc_ab_t spin_period(rig_t *r, spin_t *p)
{
    const mc_ab_t i = spin_period_on(p, &r->d, &r->pwm, &r->adc);
    assert_int_equal(r->pwm.nonfinite, 0u);
    return i;
}

/* Enabled on a rotor turning at 1500 rpm either way (above the generation speed: the diodes'
 * current flows through the whole calibration), the drive's catch (startup.catch on, the given
 * angle otherwise): RUN with the caught angle within 3 deg and the speed within 3 %; the offsets
 * of the calibration's plain mean, biased by the diodes' current (its 64 samples are 1.6
 * electrical periods), are replaced by (O.1)'s over whole half-periods at the caught speed:
 * within 0.1 A of the true ones (mid-scale) where the mean was more than 0.2 A off. */
static void test_catch_at_speed_against_a_spinning_machine(void **state)
{
    (void)state;
    static rig_t r;
    const double speeds[] = {785.398, -785.398};
    const double starts[] = {0.3, 2.1, -1.2};
    for (size_t v = 0; v < 2u; ++v) {
        for (size_t a = 0; a < 3u; ++a) {
            rig_init(&r, "unop", "given", "pulses");
            assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
            assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
            assert_true(r.d.seq.cfg.catch_first);
            spin_t p = {.w = speeds[v], .th = starts[a], .lean = 0.25};
            const float k = r.d.cfg->blk.offs.amps_per_count, nominal = (float)r.d.cfg->blk.offs.nominal;
            const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_TORQUE};
            mc_drive_command(&r.d, &c);
            float mean_off = 0.0f;
            int n = 0;
            for (; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN && mc_drive_state(&r.d) != MC_STATE_FAULT; ++n) {
                const bool cal = mc_drive_state(&r.d) == MC_STATE_OFFSET_CAL || n == 0;
                (void)spin_period(&r, &p);
                if (cal && mc_drive_state(&r.d) != MC_STATE_OFFSET_CAL) {
                    for (int j = 0; j < 3; ++j) {
                        mean_off = fmaxf(mean_off, fabsf(r.d.offs.offset[j] - nominal) * k);
                    }
                }
            }
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
            const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
            const double th_err = fabs(remainder(tm->theta1 - p.th_sample, 2.0 * 3.14159265358979));
            print_message("%+.0f rad/s from %.1f rad: caught in %d periods, angle off %.2f deg, speed %.1f, plain mean "
                          "%.3f A off\n", speeds[v], starts[a], n, th_err * 57.2958, (double)tm->c2, (double)mean_off);
            assert_true(th_err < 3.0 * 3.14159265 / 180.0);
            assert_true(fabs(tm->c2 - speeds[v]) < 0.03 * fabs(speeds[v]));
            assert_true(mean_off > 0.2f);
            float off_err = 0.0f;
            for (int j = 0; j < 3; ++j) {
                off_err = fmaxf(off_err, fabsf(r.d.offs.offset[j] - nominal) * k);
            }
            assert_true(off_err < 0.1f);
            /* RUN holds at zero torque: the field-weakening entry, then the references' field
             * weakening; no trip, the current below the over-current trip, q back to zero */
            float peak = 0.0f;
            for (int j = 0; j < 400; ++j) {
                (void)spin_period(&r, &p);
                assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
                peak = fmaxf(peak, hypotf(tm->i_dq.d, tm->i_dq.q));
            }
            print_message("  offsets %.3f A off after (O.1); RUN: peak %.2f A, i_dq (%.2f, %.2f) A at the end\n",
                          (double)off_err, (double)peak, (double)tm->i_dq.d, (double)tm->i_dq.q);
            assert_true(peak < r.d.cfg->blk.prot.i_trip);
            assert_true(tm->i_dq.d < -5.0f && fabsf(tm->i_dq.q) < 0.5f);
        }
    }
}

/* Step III's check as the ISR runs it from Step III's entry (the sequencer's tick, then from the
 * second tick on the check): omega_hat 100 x the tolerance at tick 2, x from then on. Returns the
 * tick it handed over to RUN at, 0 if not within max_ticks. */
static uint32_t step3_handover(rig_t *r, float x, uint32_t max_ticks)
{
    mc_drive_startup_reset(&r->d);   /* Step III's convergence state at rest */
    r->d.seq.state = MC_STATE_INIT_POS;   /* as Step II's end enters Step III */
    r->d.seq.step = MC_INIT_STEP3;
    r->d.seq.ticks = 0u;
    r->d.seq.limit = 0u;   /* no timeout: the test alone decides */
    for (uint32_t t = 0u; t < max_ticks; ++t) {
        mc_seq_tick(&r->d.seq);
        const uint32_t now = r->d.seq.ticks;
        if (now > 1u) {
            mc_drive_step3_check(&r->d, now == 2u ? 100.0f * r->d.cfg->blk.step3_speed_tol : x);
        }
        if (r->d.seq.state == MC_STATE_RUN) {
            return now;
        }
    }
    return 0u;
}

/* Where Step III's low-pass (as built, from rest) settles for the input sequence above, and
 * whether it stayed at or above that value all the way down from the spike (*from_above). */
static float lpf_settles_at(const mc_lpf1_t *built, float spike, float x, bool *from_above, uint32_t *settled_at)
{
    mc_lpf1_t f = *built;
    float y = mc_lpf1_step(&f, spike), lowest = y;
    *settled_at = 0u;
    for (uint32_t k = 1u; k < 4000u; ++k) {
        const float prev = y;
        y = mc_lpf1_step(&f, x);
        lowest = fminf(lowest, y);
        if (y == prev && *settled_at == 0u) {
            *settled_at = k;
        } else if (y != prev) {
            *settled_at = 0u;
        }
    }
    *from_above = lowest >= y;
    return y;
}

/* Step III's convergence is "the low-passed |omega_hat| below startup.step3_speed_tol", a strict
 * bound: an estimate coming down from a spike whose low-passed magnitude settles exactly at the
 * tolerance (the tolerance as the input) never converges (Step III would time out), one that
 * settles just below it (the closest value the filter settles at: 32 float steps, 1.2e-5 of it)
 * converges a hold after it has settled at the latest (and
 * after 2 x hold). That input is searched below the tolerance with the drive's own filter (50 Hz
 * Tustin, from rest).
 * (startup.c:414, the comparison.) */
static void test_step3_tolerance_is_strict(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "three_step", "pulses");
    const float tol = r.d.cfg->blk.step3_speed_tol;
    const uint32_t hold = r.d.cfg->blk.step3_hold;
    const float spike = 100.0f * tol;
    bool above;
    uint32_t settle_at, settle_below;
    /* the tolerance itself as the input settles there, from above */
    const float x_at = tol;
    assert_true(lpf_settles_at(&r.d.cfg->blk.step3_lpf, spike, x_at, &above, &settle_at) == tol);
    assert_true(above && settle_at > 0u);
    /* the largest input that settles below it (bisection: 1 % below settles below) */
    float lo = 0.99f * tol, hi = tol;
    assert_true(lpf_settles_at(&r.d.cfg->blk.step3_lpf, spike, lo, &above, &settle_below) < tol);
    while (nextafterf(lo, INFINITY) < hi) {
        const float mid = lo + 0.5f * (hi - lo);
        if (mid <= lo || mid >= hi) {
            break;
        }
        if (lpf_settles_at(&r.d.cfg->blk.step3_lpf, spike, mid, &above, &settle_below) < tol) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    const float x_below = lo;
    const float y_below = lpf_settles_at(&r.d.cfg->blk.step3_lpf, spike, x_below, &above, &settle_below);
    assert_true(y_below < tol && above && settle_below > 0u);
    int ulps = 0;
    for (float y = y_below; y < tol && ulps < 1000; y = nextafterf(y, INFINITY)) {
        ++ulps;
    }
    print_message("tolerance %.9g rad/s: the filter settles at it (period %u) for x = tol, %d float steps below it "
                  "(period %u) for x = %.9g\n", (double)tol, settle_at, ulps, settle_below, (double)x_below);
    assert_true(tol - y_below < 2e-5f * tol);   /* the closest below that the filter settles at */
    assert_int_equal(step3_handover(&r, x_at, 4000u), 0u);
    const uint32_t done = step3_handover(&r, x_below, 4000u);
    /* the check's call k (tick k + 2) gives the filter's k-th output; the first output below the
     * tolerance is at or before the settled one */
    assert_true(done > 0u && done <= settle_below + 2u + hold);
    assert_true(done >= 2u * hold);
}

/* RUN entered from the catch without the field-weakening entry (the flux can be held): RUN's
 * current references start from the current that flows, in the caught frame (bumpless), as the
 * offsets in force from that period give it, and move one slew step (control.i_slew, 0.2 A)
 * towards the command (0 A) in the entry period. Below the generation speed (600
 * rpm either way) no current flows through the calibration and the offsets stay; just above it
 * (1003 rpm, 525 rad/s el) the diodes' small current (0.3 A peak) biases the calibration's mean
 * and (O.1) corrects the offsets at the caught speed by 15-25 mA of stator current (a calibration of
 * 128 samples, where (O.1)'s half-period of 60 samples fits), while the probe's current at the
 * catch's end still lets the flux be held. (startup.c:292-297.) */
static void test_catch_entry_references_from_the_current(void **state)
{
    (void)state;
    static rig_t r;
    const double speeds[] = {314.159, -314.159, 525.0, -525.0};
    const double starts[] = {0.3, -2.8, -0.4, 2.7};
    for (size_t v = 0; v < 4u; ++v) {
        for (size_t a = 0; a < 4u; ++a) {
            rig_init(&r, "unop", "given", "pulses");
            assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
            assert_true(mc_param_set(&r.cfg.p, MC_PARAM_control_offset_cal_samples, 128.0f, NULL));
            assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
            spin_t p = {.w = speeds[v], .th = starts[a], .lean = 0.25};
            const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT};
            mc_drive_command(&r.d, &c);
            int n = 0;
            float mean[3] = {0.0f, 0.0f, 0.0f};   /* the calibration's plain mean */
            for (; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN && mc_drive_state(&r.d) != MC_STATE_FAULT; ++n) {
                const bool cal = mc_drive_state(&r.d) == MC_STATE_OFFSET_CAL || n == 0;
                (void)spin_period(&r, &p);
                if (cal && mc_drive_state(&r.d) != MC_STATE_OFFSET_CAL) {
                    memcpy(mean, r.d.offs.offset, sizeof mean);
                }
            }
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
            const float k = r.d.cfg->blk.offs.amps_per_count;
            const mc_ab_t di = mc_clarke((mc_abc_t){(r.d.offs.offset[0] - mean[0]) * k, (r.d.offs.offset[1] - mean[1]) * k,
                                                    (r.d.offs.offset[2] - mean[2]) * k});
            const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
            const float slew = r.d.cfg->blk.i_slew * r.d.cfg->blk.ts;
            const float i = hypotf(tm->i_dq.d, tm->i_dq.q), th_err = fabsf(remainderf(tm->theta1 - (float)p.th_sample, 6.2831853f));
            const float e_d = tm->i_ref.d - tm->i_dq.d * (1.0f - slew / i), e_q = tm->i_ref.q - tm->i_dq.q * (1.0f - slew / i);
            print_message("%+.0f rad/s from %+.1f rad: RUN after %d periods, angle off %.2f deg, offsets moved by %.4f A, "
                          "i_dq (%.3f, %.3f) A, i_ref %.5f A off its step\n", speeds[v], starts[a], n,
                          (double)th_err * 57.2958, (double)hypotf(di.alpha, di.beta), (double)tm->i_dq.d, (double)tm->i_dq.q,
                          (double)hypotf(e_d, e_q));
            assert_true(th_err < 3.0f * 3.14159265f / 180.0f);
            assert_true(fabsf(tm->c2 - (float)speeds[v]) < 0.03f * fabsf((float)speeds[v]));
            assert_false(mc_fwe_active(&r.d.fw_entry));   /* the flux held: the references act */
            assert_true(i > 1.0f);
            if (v < 2u) {
                assert_true(di.alpha == 0.0f && di.beta == 0.0f);
            } else {
                assert_true(hypotf(di.alpha, di.beta) > 0.01f);
            }
            /* one slew step from the current, along it, towards zero */
            assert_true(hypotf(e_d, e_q) < 1e-3f);
        }
    }
}

/* A catch that finds the rotor turning hands over an angle it measured: RUN after it is not
 * "unsure" of its polarity, also where an earlier RUN entry of the same enable was (a standing
 * verdict with a device drop configured, hw.device_drop_v: then the re-check runs as with
 * protection.polarity_check = at_start). Here: enabled at standstill (1 V drop): the probe says
 * standing, RUN from the given angle, unsure; the rotor is then driven to 100 rpm and the drive
 * recovers (a new catch), which catches it turning: RUN again, no longer unsure, and no
 * polarity re-check starts at the at_start time into this RUN. (startup.c:298.) */
static void test_turning_catch_clears_the_unsure_polarity(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "given", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_hw_device_drop_v, 1.0f, NULL));
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    spin_t p = {.w = 0.0, .th = 0.7, .lean = 0.25};
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT, .theta_init = 0.7f};
    mc_drive_command(&r.d, &c);
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_true(r.d.pol.unsure);
    (void)spin_period(&r, &p);
    p.w = 100.0 / 60.0 * 2.0 * 3.14159265358979 * 5.0;
    assert_true(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, mc_drive_telemetry(&r.d)->vdc));
    assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
    print_message("caught at %.1f rad/s (%.1f), unsure %d, start_n %u\n", (double)tm->c2, p.w, (int)r.d.pol.unsure, r.d.cfg->blk.pol.start_n);
    assert_true(fabsf(tm->c2 - (float)p.w) < 0.05f * (float)p.w);
    assert_false(r.d.pol.unsure);
    const uint32_t checks = tm->polarity_checks;
    for (uint32_t n = 0; n < r.d.cfg->blk.pol.start_n + 20u; ++n) {
        (void)spin_period(&r, &p);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    }
    assert_int_equal(tm->polarity_checks, checks);
}

/* A recovery starts the speed loop again: after RUN at 290 rpm asked against a rotor held at 300
 * rpm (a dyno: the speed loop's integrator winds up, 0.1 s), a recovery's catch finds it turning and
 * RUN's first torque reference is what a speed loop fresh from its configuration gives for that
 * period's speed error, not the wound-up torque. (startup.c:240-241.) */
static void test_recovery_restarts_the_speed_loop(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "given", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    spin_t p = {.w = 300.0 / 60.0 * 2.0 * 3.14159265358979 * 5.0, .th = -0.9, .lean = 0.25};
    const float ref = 290.0f / 60.0f * 6.2831853f;   /* [rad/s mechanical] */
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_SPEED, .speed_ref = ref};
    mc_drive_command(&r.d, &c);
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
    for (int n = 0; n < 1000; ++n) {
        (void)spin_period(&r, &p);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    }
    const float wound = tm->torque_ref, integ = r.d.sc.pi.integ;
    assert_true(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, tm->vdc));
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    static mc_sc_t fresh;
    mc_sc_init(&fresh, &r.d.cfg->sc);
    const float want = mc_sc_step(&fresh, ref, tm->omega / (float)r.d.cfg->blk.pole_pairs);
    print_message("wound up to %.3f N m (integrator %.3f); after the recovery %.4f N m, a fresh loop %.4f N m\n",
                  (double)wound, (double)integ, (double)tm->torque_ref, (double)want);
    assert_true(fabsf(integ) > 0.5f);
    assert_near(tm->torque_ref, want, 1e-4);
}

/* An angle-sensor drive enabled at standstill enters RUN at the calibration's last period with
 * the outputs still off; RUN's first duties (latched by the pipeline in that period) come on
 * with the outputs at the next one, whatever the calibration's length, also a single sample,
 * where no period of the calibration latches an entry corner before its end (a corner is only
 * latched above the generation speed: none at rest). (startup.c:52, the entry's reset.) */
static void test_sensor_entry_at_rest_gates_on_next_period(void **state)
{
    (void)state;
    static rig_t r;
    const float samples[] = {1.0f, 2.0f, 64.0f};
    for (int k = 0; k < 3; ++k) {
        rig_init(&r, "encoder", "given", "pulses");
        assert_true(mc_param_set(&r.cfg.p, MC_PARAM_control_offset_cal_samples, samples[k], NULL));
        assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
        for (int cyc = 0; cyc < 2; ++cyc) {   /* the first enable and a later one */
            through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 1.0f});
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
            assert_false(hal_pwm_enabled(&r.pwm));
            const uint32_t edges = r.pwm.on_edges;
            run(&r, 1);
            assert_true(hal_pwm_enabled(&r.pwm));
            assert_int_equal(r.pwm.on_edges, edges + 1u);
            const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
            mc_drive_command(&r.d, &off);
            run(&r, 2);
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
        }
    }
}

/* A standing catch with the given angle (startup.init_pos given) goes to RUN: Step I is not
 * begun, so its configuration does not matter, even one its engine refuses (here m = 0): RUN,
 * the outputs on, no fault. (startup.c:309: Step I begun only where the sequencer went to it.) */
static void test_standing_catch_with_given_angle_skips_step1(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "given", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    held_blocks(&r)->step1.m = 0;
    through_calibration(&r, 0.5f, (mc_dq_t){0.0f, 0.0f});
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
    assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        run(&r, 1);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_int_equal(mc_drive_faults(&r.d), 0u);
    assert_true(hal_pwm_enabled(&r.pwm));
    run(&r, 10);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
}

/* A recovery (protection.lock_action recover) is for a running drive: in Step III (the three-step
 * start's convergence, startup.init_pos three_step) a recoverable reason is not recovered from
 * (the drive's caller then trips), the state and the budget stay; in RUN it is. (startup.c:227:
 * running = RUN.) */
static void test_no_recovery_in_step3(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "three_step", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_protection_retries, 3.0f, NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
    bool tried = false;
    for (int n = 0; n < 5000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        saturating_answer(&r, 0);
        run(&r, 1);
        if (!tried && r.d.seq.step == MC_INIT_STEP3 && r.d.seq.ticks == 10u) {
            tried = true;
            assert_false(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, mc_drive_telemetry(&r.d)->vdc));
            assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
            assert_int_equal(r.d.seq.step, MC_INIT_STEP3);
            assert_int_equal(r.d.prot.retries, 0u);
            assert_int_equal(r.d.tm.recoveries, 0u);
        }
    }
    assert_true(tried);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_true(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, mc_drive_telemetry(&r.d)->vdc));
    assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
    assert_int_equal(r.d.tm.recoveries, 1u);
}

/* A polarity re-check running when the drive recovers (the lock checks in doubt, then a fault)
 * ends with that RUN: the caught RUN starts with none running (no d-current bias, the lock
 * checks not paused by it). At 100 rpm on the spinning plant, the check begun as the drive
 * begins it in doubt (mc_polcheck_start). (startup.c:42, the re-check's reset with the
 * estimate's.) */
static void test_recovery_ends_a_running_polarity_check(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "given", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    spin_t p = {.w = 100.0 / 60.0 * 2.0 * 3.14159265358979 * 5.0, .th = 2.2, .lean = 0.25};
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT};
    mc_drive_command(&r.d, &c);
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    (void)spin_period(&r, &p);
    assert_true(mc_polcheck_start(&r.d.pol, &r.d.cfg->blk.pol, mc_drive_telemetry(&r.d)->omega, true));
    for (int n = 0; n < 5; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_true(mc_polcheck_active(&r.d.pol));
    assert_true(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, mc_drive_telemetry(&r.d)->vdc));
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        (void)spin_period(&r, &p);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_false(mc_polcheck_active(&r.d.pol));
    assert_true(mc_polcheck_bias(&r.d.pol, &r.d.cfg->blk.pol) == 0.0f);
}

/* The same refusal after a standing catch (startup.catch on, then the three-step start): in the
 * period the catch ends the drive faults with the configuration reason, the outputs off; Step I
 * never runs. (startup.c:309-311.) */
static void test_step1_refused_after_the_catch(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "three_step", "pulses");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    held_blocks(&r)->step1.m = 0;
    through_calibration(&r, 0.0f, (mc_dq_t){0.0f, 0.0f});
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
    int n = 0;
    for (; n < 2000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
        run(&r, 1);
    }
    assert_true(n > 1 && n < 2000);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_int_equal(mc_drive_faults(&r.d), MC_FAULT_CONFIG);
    assert_false(hal_pwm_enabled(&r.pwm));
}

/* In torque mode at rest RUN's references start without field weakening: the voltage feedback's
 * extra d current (mc_tref_fw_feedback) starts from none at every enable, so 0 N m asked at
 * standstill gives exactly 0 A in d (and q) from RUN's first period, at a first enable and after
 * a run that ended with it pulling (the drive's blocks keep it between periods). (startup.c:41.) */
static void test_torque_mode_starts_without_field_weakening(void **state)
{
    (void)state;
    static rig_t r;
    rig_init(&r, "unop", "given", "pulses");
    for (int cyc = 0; cyc < 2; ++cyc) {
        const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_TORQUE, .theta_init = 0.4f};
        mc_drive_command(&r.d, &c);
        for (int n = 0; n < 1000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
            run(&r, 1);
        }
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
        for (int k = 0; k < 20; ++k) {
            const mc_dq_t ref = mc_drive_telemetry(&r.d)->i_ref;
            assert_true(ref.d == 0.0f && ref.q == 0.0f);
            run(&r, 1);
        }
        r.d.tref.fw_did = -5.0f;   /* as a run at speed in the voltage limit leaves it */
        const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_TORQUE};
        mc_drive_command(&r.d, &off);
        run(&r, 2);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step1_runs_the_selected_program),
        cmocka_unit_test(test_references_start_from_zero),
        cmocka_unit_test(test_torque_mode_starts_without_field_weakening),
        cmocka_unit_test(test_step3_lasts_twice_the_hold),
        cmocka_unit_test(test_step3_tolerance_is_strict),
        cmocka_unit_test(test_catch_at_speed_against_a_spinning_machine),
        cmocka_unit_test(test_catch_entry_references_from_the_current),
        cmocka_unit_test(test_turning_catch_clears_the_unsure_polarity),
        cmocka_unit_test(test_recovery_restarts_the_speed_loop),
        cmocka_unit_test(test_step2_decision_in_telemetry),
        cmocka_unit_test(test_sensor_wait_is_bounded),
        cmocka_unit_test(test_sensor_entry_references_from_the_current),
        cmocka_unit_test(test_sensor_entry_references_within_the_limit),
        cmocka_unit_test(test_sensor_entry_at_rest_gates_on_next_period),
        cmocka_unit_test(test_idle_and_fault_leave_the_pwm_alone),
        cmocka_unit_test(test_step1_refused_never_enables),
        cmocka_unit_test(test_step1_refused_after_the_catch),
        cmocka_unit_test(test_step2_refused_faults_at_step1_end),
        cmocka_unit_test(test_standing_catch_with_given_angle_skips_step1),
        cmocka_unit_test(test_restart_starts_the_speed_loop_from_rest),
        cmocka_unit_test(test_recovery_budget_refills_in_run_only),
        cmocka_unit_test(test_no_recovery_in_step3),
        cmocka_unit_test(test_recovery_ends_a_running_polarity_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
