/* The lowest sampling rate a motor allows (check_sampling in drive_config.c, docs/parameters.md
 * "The lowest sampling rate"): 20 (sensorless) or 6 (an angle sensor) samples a period of the
 * electrical frequency at the no-load base speed Vdc / (sqrt3 psi_pm), and 4 samples a period of
 * the injection while injecting. The configuration is refused just above the period it allows,
 * naming control.ts_s, the key that binds and the allowed range, and taken just below it. Hand
 * computations on four motor sets. */
#include <math.h>
#include <string.h>

#include "../mc_test.h"
#include "mc/drive.h"

typedef struct {
    const char *name;
    double vdc, psi;      /* hw.vdc_nominal_v [V], motor.psi_pm_wb [Wb] */
    double ts_sensorless; /* 1 / (20 f_el) [s], by hand */
    double ts_sensor;     /* 1 / (6 f_el) [s], by hand; above 500 us: the range's end is taken */
} motor_t;

/* f_el = (Vdc / sqrt3) / (2 pi psi_pm):
 * thesis motor at 600 V: 346.41 V / 0.34305 Wb = 1009.8 rad/s = 160.71 Hz:
 *   x 20 = 3214.3 Hz, 311.11 us; x 6 = 964.3 Hz, 1037 us;
 * brodatzki-35kw, 250 V: 144.34 V / 0.07666 Wb = 1882.8 rad/s = 299.66 Hz:
 *   x 20 = 5993.2 Hz, 166.86 us; x 6 = 1798.0 Hz, 556.2 us;
 * siemens-1ft7044-spm, 600 V: 346.41 V / 0.14815 Wb = 2338.2 rad/s = 372.14 Hz:
 *   x 20 = 7442.8 Hz, 134.36 us; x 6 = 2232.8 Hz, 447.87 us;
 * minicheetah-24v-lv, 24 V: 13.856 V / 0.0024 Wb = 5773.5 rad/s = 918.88 Hz:
 *   x 20 = 18378 Hz, 54.414 us; x 6 = 5513.3 Hz, 181.38 us */
static const motor_t MOTORS[] = {
    {"thesis at 600 V", 600.0, 0.34305, 311.11e-6, 1037.0e-6},
    {"brodatzki", 250.0, 0.07666, 166.86e-6, 556.2e-6},
    {"siemens", 600.0, 0.14815, 134.36e-6, 447.87e-6},
    {"minicheetah", 24.0, 0.0024, 54.414e-6, 181.38e-6},
};

static void setup_motor(mc_drive_cfg_t *cfg, const motor_t *m, double ts, bool sensorless)
{
    mc_drive_cfg_default(cfg);
    assert_true(mc_param_set(&cfg->p, MC_PARAM_hw_vdc_nominal_v, (float)m->vdc, NULL));
    /* the DC-link sensor above the over-voltage trip (1.5 Vdc by its rule) */
    assert_true(mc_param_set(&cfg->p, MC_PARAM_hw_vdc_span_v, (float)(2.0 * m->vdc), NULL));
    assert_true(mc_param_set(&cfg->p, MC_PARAM_motor_psi_pm_wb, (float)m->psi, NULL));
    assert_true(mc_param_set(&cfg->p, MC_PARAM_control_ts_s, (float)ts, NULL));
    if (sensorless) {   /* UNOP on constant parameters, started from a given angle: no map needed */
        assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_control_angle_source, "unop", NULL));
        assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_estimator_model, "const", NULL));
        assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_startup_init_pos, "given", NULL));
    } else {
        assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_control_angle_source, "encoder", NULL));
    }
}

static void refused_above_taken_below(const motor_t *m, double ts_max, bool sensorless)
{
    static mc_drive_built_t b;
    const float ts_range = mc_param_table[MC_PARAM_control_ts_s].max;
    mc_drive_cfg_t cfg;
    mc_param_err_t err;
    if (ts_max * 1.001 <= (double)ts_range) {
        /* 0.1 % above the period: refused, with the key, the binding motor entry and the range */
        setup_motor(&cfg, m, ts_max * 1.001, sensorless);
        memset(&err, 0, sizeof err);
        assert_false(mc_drive_build(&cfg, &b, &err));
        assert_int_equal(err.kind, MC_PERR_CROSS);
        assert_int_equal(err.param, MC_PARAM_control_ts_s);
        assert_int_equal(err.param2, MC_PARAM_motor_psi_pm_wb);
        assert_float_equal(err.value2, (float)m->psi, 0.0f);
        assert_float_equal(err.min, mc_param_table[MC_PARAM_control_ts_s].min, 0.0f);
        assert_float_equal(err.max, ts_max, 2e-4 * ts_max);
        assert_non_null(strstr(err.text, "shorten control.ts_s"));
    }
    /* 0.1 % below (or the range's end): taken */
    const double ts = ts_max * 0.999 < (double)ts_range ? ts_max * 0.999 : (double)ts_range;
    setup_motor(&cfg, m, ts, sensorless);
    if (!mc_drive_build(&cfg, &b, &err)) {
        fail_msg("%s (%s): refused at %g s: %s", m->name, sensorless ? "sensorless" : "sensor", ts, err.text);
    }
}

static void test_sensorless(void **st)
{
    (void)st;
    for (size_t k = 0; k < sizeof MOTORS / sizeof MOTORS[0]; ++k) {
        refused_above_taken_below(&MOTORS[k], MOTORS[k].ts_sensorless, true);
    }
}

static void test_with_a_sensor(void **st)
{
    (void)st;
    for (size_t k = 0; k < sizeof MOTORS / sizeof MOTORS[0]; ++k) {
        refused_above_taken_below(&MOTORS[k], MOTORS[k].ts_sensor, false);
    }
}

/* The injection's 4 samples a period: its own rule keeps them (min(500 Hz, f_s / 4)); set by hand
 * between f_s / 4 and f_s / 2 (the range check's Nyquist) it is refused naming injection.f_hz. The
 * thesis motor at 10 kHz: f_s,min by the motor 1607 Hz (sensorless), by the injection 4 f_inj. */
static void test_injection_samples(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    const float f_inj[3] = {2400.0f, 2500.0f, 2510.0f};
    const bool taken[3] = {true, true, false};
    for (int c = 0; c < 3; ++c) {
        mc_drive_cfg_t cfg;
        mc_param_err_t err;
        mc_drive_cfg_default(&cfg);
        assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_control_angle_source, "unop", NULL));
        assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_estimator_model, "const", NULL));
        assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_startup_init_pos, "given", NULL));
        assert_true(mc_param_set(&cfg.p, MC_PARAM_control_ts_s, 1e-4f, NULL));
        assert_true(mc_param_set(&cfg.p, MC_PARAM_injection_f_hz, f_inj[c], NULL));
        memset(&err, 0, sizeof err);
        const bool got = mc_drive_build(&cfg, &b, &err);
        if (got != taken[c]) {
            fail_msg("f_inj %g: %s (%s)", (double)f_inj[c], got ? "taken" : "refused", got ? "" : err.text);
        }
        if (!taken[c]) {
            assert_int_equal(err.param, MC_PARAM_control_ts_s);
            assert_int_equal(err.param2, MC_PARAM_injection_f_hz);
            assert_float_equal(err.max, 1.0 / (4.0 * 2510.0), 1e-9);
            assert_non_null(strstr(err.text, "4 x injection.f_hz"));
        }
    }
    /* the same injection with the angle from an encoder: nothing is injected, nothing refused */
    mc_drive_cfg_t cfg;
    mc_drive_cfg_default(&cfg);
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_control_angle_source, "encoder", NULL));
    assert_true(mc_param_set(&cfg.p, MC_PARAM_injection_f_hz, 2510.0f, NULL));
    assert_true(mc_drive_build(&cfg, &b, NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sensorless),
        cmocka_unit_test(test_with_a_sensor),
        cmocka_unit_test(test_injection_samples),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
