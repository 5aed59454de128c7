/* The drive's sequencing, protection and bookkeeping, driven through the host HAL port. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "hal_host/host.h"
#include "mc/drive.h"

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    mc_drive_cfg_t cfg;
    mc_drive_link_t link;
    mc_drive_t d;
} rig_t;

/* ADC counts for a phase current with the drive's scaling (default 12 bit over +-25 A). */
static uint16_t counts(const mc_drive_t *d, float amps)
{
    return (uint16_t)lrintf(d->blk.offset_nominal + amps / d->blk.amps_per_count);
}

static void set_inputs(rig_t *r, float ia, float ib, float vdc)
{
    r->adc.sample.i[0] = counts(&r->d, ia);
    r->adc.sample.i[1] = counts(&r->d, ib);
    r->adc.sample.i[2] = counts(&r->d, -ia - ib);
    r->adc.sample.vdc = (uint16_t)lrintf(vdc / r->d.blk.volts_per_count);
}

static void rig_init(rig_t *r)
{
    hal_host_pwm_init(&r->pwm, 1e-4f, 0.5e-6f);
    r->adc = (hal_adc_t){0};
    r->qep = (hal_qep_t){.counts_per_rev = 80000u};
    mc_drive_cfg_default(&r->cfg);
    assert_true(mc_drive_init(&r->d, &r->link, &r->cfg, &r->adc, &r->pwm, &r->qep));
    set_inputs(r, 0.0f, 0.0f, 300.0f);
}

static void command(rig_t *r, bool enable, mc_mode_t mode, float id, float iq)
{
    const mc_drive_cmd_t c = {.enable = enable, .mode = mode, .i_ref = {id, iq}};
    mc_drive_command(&r->d, &c);
}

static void run(rig_t *r, int n)
{
    for (int k = 0; k < n; ++k) {
        hal_host_pwm_latch(&r->pwm);
        mc_drive_isr(&r->d);
    }
}

static void test_enable_calibrates_then_runs(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    run(&r, 10);
    assert_int_equal(mc_drive_telemetry(&r.d)->state, MC_STATE_IDLE);
    assert_false(hal_pwm_enabled(&r.pwm));

    /* offsets of +30 counts on phase a: the calibration must find and remove them */
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    r.adc.sample.i[0] = (uint16_t)(r.adc.sample.i[0] + 30u);
    run(&r, (int)r.d.p.offset_cal_samples - 1);
    assert_int_equal(mc_drive_telemetry(&r.d)->state, MC_STATE_OFFSET_CAL);
    assert_false(hal_pwm_enabled(&r.pwm));
    run(&r, 1);
    assert_int_equal(mc_drive_telemetry(&r.d)->state, MC_STATE_RUN);
    assert_true(hal_pwm_enabled(&r.pwm));
    run(&r, 1);
    assert_true(fabsf(mc_drive_telemetry(&r.d)->i_abc.a) < 0.02f);
}

static void test_overcurrent_trips_and_latches(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, (int)r.d.p.offset_cal_samples + 5);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);

    set_inputs(&r, r.d.p.i_trip + 1.0f, 0.0f, 300.0f);
    run(&r, 1);
    assert_int_equal(mc_drive_telemetry(&r.d)->state, MC_STATE_FAULT);
    assert_true(mc_drive_telemetry(&r.d)->faults & MC_FAULT_OVERCURRENT);
    assert_false(hal_pwm_enabled(&r.pwm));

    /* the fault stays latched while enabled, even when the cause is gone */
    set_inputs(&r, 0.0f, 0.0f, 300.0f);
    run(&r, 50);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_false(hal_pwm_enabled(&r.pwm));

    /* disable, enable: starts clean through the calibration */
    command(&r, false, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, 1);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, 1);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_OFFSET_CAL);
    assert_int_equal(mc_drive_faults(&r.d), 0u);
    run(&r, (int)r.d.p.offset_cal_samples);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
}

static void test_dc_link_limits(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, (int)r.d.p.offset_cal_samples + 2);
    set_inputs(&r, 0.0f, 0.0f, r.d.p.vdc_max + 10.0f);
    run(&r, 1);
    assert_true(mc_drive_faults(&r.d) & MC_FAULT_OVERVOLTAGE);

    rig_init(&r);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, (int)r.d.p.offset_cal_samples + 2);
    set_inputs(&r, 0.0f, 0.0f, r.d.p.vdc_min - 10.0f);
    run(&r, 1);
    assert_true(mc_drive_faults(&r.d) & MC_FAULT_UNDERVOLTAGE);
    assert_false(hal_pwm_enabled(&r.pwm));
}

static void test_implausible_offset_faults(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    r.adc.sample.i[1] = (uint16_t)(r.adc.sample.i[1] + (uint16_t)(r.d.blk.offset_tol + 20.0f));
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, (int)r.d.p.offset_cal_samples + 2);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_true(mc_drive_faults(&r.d) & MC_FAULT_OFFSET_CAL);
    assert_false(hal_pwm_enabled(&r.pwm));
}

static void test_bad_config_never_runs(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    r.cfg.p.ts = 1.0f; /* 1 Hz control: out of range */
    assert_false(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    /* the reason names the parameter, its value and its range */
    const mc_param_err_t *e = mc_drive_config_error(&r.d);
    assert_int_equal(e->kind, MC_PERR_RANGE);
    assert_int_equal(e->param, MC_PARAM_ts);
    assert_string_equal(mc_param_table[e->param].name, "control.ts_s");
    assert_float_equal(e->value, 1.0f, 0.0f);
    assert_float_equal(e->max, 5e-4f, 1e-9f);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    run(&r, 300);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_true(mc_drive_faults(&r.d) & MC_FAULT_CONFIG);
    assert_false(hal_pwm_enabled(&r.pwm));
}

/* The voltage handed to the angle source at k is the one commanded two ISRs earlier (it acted
 * between samples k-1 and k), and the reference ramps at the configured slew rate. */
static void test_voltage_history_and_slew(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 5.0f);
    /* the ISR that completes the calibration already runs the first control step */
    run(&r, (int)r.d.p.offset_cal_samples);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    const float step = r.d.blk.i_slew * r.d.blk.ts;
    assert_float_equal(mc_drive_telemetry(&r.d)->i_ref.q, step, 1e-5f);
    const mc_ab_t u1 = mc_drive_telemetry(&r.d)->u_ab;
    run(&r, 1);
    assert_float_equal(mc_drive_telemetry(&r.d)->i_ref.q, 2.0f * step, 1e-5f);
    const mc_ab_t u2 = mc_drive_telemetry(&r.d)->u_ab;
    assert_true(fabsf(u2.beta - u1.beta) > 1e-3f); /* the two periods' voltages differ */
    assert_float_equal(r.d.u_hist[1].alpha, u1.alpha, 1e-6f);
    assert_float_equal(r.d.u_hist[1].beta, u1.beta, 1e-6f);
    assert_float_equal(r.d.u_hist[0].beta, u2.beta, 1e-6f);
    /* duties go to the shadow register; the active ones change only at the next latch */
    const float active_before = r.pwm.active[1];
    mc_drive_isr(&r.d);
    assert_float_equal(r.pwm.active[1], active_before, 0.0f);
    assert_true(fabsf(r.pwm.shadow[1] - active_before) > 1e-6f);
    hal_host_pwm_latch(&r.pwm);
    assert_float_equal(r.pwm.active[1], r.pwm.shadow[1], 0.0f);
}

/* Reference moves shorter than a slew step pass unchanged, whether the squared-length shortcut
 * (below 99.9 % of a step) or the exact length (from there up) decides; longer ones move one step. */
static void test_slew_step_boundary(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    const float step = r.d.blk.i_slew * r.d.blk.ts;
    command(&r, true, MC_MODE_CURRENT, 0.0f, 2.0f);
    run(&r, (int)r.d.p.offset_cal_samples + 10);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_true(mc_drive_telemetry(&r.d)->i_ref.q == 2.0f);
    /* moves in steps: within the margin, between margin and step, just beyond, far beyond */
    const float moves[] = {0.9995f, -0.4995f, 0.9999f, 1.0002f, -1.2f, -0.3f, 1.0005f};
    float prev = 2.0f;
    for (size_t k = 0; k < sizeof moves / sizeof moves[0]; ++k) {
        const float target = prev + moves[k] * step;
        command(&r, true, MC_MODE_CURRENT, 0.0f, target);
        run(&r, 1);
        const float got = mc_drive_telemetry(&r.d)->i_ref.q;
        if (fabsf(target - prev) <= step) {
            assert_true(got == target);   /* exactly the command */
        } else {
            assert_float_equal(got, prev + copysignf(step, moves[k]), 1e-6f);
        }
        prev = got;
    }
}

/* A command becomes visible to the ISR only at the next period start, as one copy. */
static void test_command_taken_at_period_start(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r);
    command(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f);
    assert_false(r.d.cmd.enable);
    run(&r, 1);
    assert_true(r.d.cmd.enable);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_OFFSET_CAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_enable_calibrates_then_runs),
        cmocka_unit_test(test_overcurrent_trips_and_latches),
        cmocka_unit_test(test_dc_link_limits),
        cmocka_unit_test(test_implausible_offset_faults),
        cmocka_unit_test(test_bad_config_never_runs),
        cmocka_unit_test(test_voltage_history_and_slew),
        cmocka_unit_test(test_slew_step_boundary),
        cmocka_unit_test(test_command_taken_at_period_start),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
