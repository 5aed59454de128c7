/* The default rules of params.c against a hand computation (the arithmetic of each rule's
 * comment done in double precision, rounded to two significant digits where the rule says so)
 * on two different motors: the thesis IPMSM at 10 kHz (the table's defaults) and the
 * brodatzki-35kw automotive IPMSM (presets/brodatzki-35kw.toml) at 8 kHz with the sensorless
 * estimator and a 300 Hz injection, and again at 5 kHz with a 10-bit ADC; the thesis motor with a
 * current limit and a speed kp set by hand; the speed loop's slew bound on three motors (the
 * thesis motor and baldor-5p6kw-pmsyrm with UNOP, baldor with the encoder). Every rule of the table has its parameter checked.
 * Then what derive must leave alone: entries set by hand, and everything when an entry the rules
 * divide by is out of range. */
#include <math.h>
#include <string.h>

#include "../mc_test.h"
#include "mc/params.h"

typedef struct {
    int id;
    double want;
    double rel;   /* 0: exactly (a rounded result); else the relative tolerance */
} want_t;

/* The hand computation: each rule's formula (params.c, docs/parameters.md) evaluated in double
 * precision on the motor's data; "0" marks a result the rule rounds (two significant digits,
 * whole rpm, counts), which must come out exactly, the others within 1e-5. */
static const want_t motor_a[] = {
    {MC_PARAM_control_i_trip_a, 19.935, 1e-5},
    {MC_PARAM_control_vdc_min_v, 150.0, 0},
    {MC_PARAM_control_vdc_max_v, 450.0, 0},
    {MC_PARAM_control_i_max_a, 13.29, 1e-5},
    {MC_PARAM_control_speed_decimation, 10.0, 0},
    {MC_PARAM_injection_f_hz, 500.0, 1e-5},
    {MC_PARAM_estimator_pll_bw_hz, 30.0, 0},
    {MC_PARAM_control_current_bw_hz, 250.0, 0},
    {MC_PARAM_control_i_slew_a_per_s, 10000.0, 0},
    {MC_PARAM_control_speed_bw_hz, 25.0, 0},
    {MC_PARAM_protection_overspeed_rpm, 1625.0, 0},
    {MC_PARAM_protection_i_sum_tol_a, 0.66, 0},
    {MC_PARAM_protection_tracking_err_a, 3.3, 0},
    {MC_PARAM_protection_residual_v, 17.0, 0},
    {MC_PARAM_injection_n1_rpm, 400.0, 0},
    {MC_PARAM_protection_lock_speed_floor_rpm, 100.0, 0},
    {MC_PARAM_protection_stall_speed_rpm, 20.0, 0},
    {MC_PARAM_control_speed_kp, 2.0420352248333655, 1e-5},
    {MC_PARAM_control_speed_ki, 80.19053575885104, 1e-5},
    {MC_PARAM_control_torque_max_nm, 35.64, 1e-5},
    {MC_PARAM_control_dtc_i_band_a, 0.3, 0},
    {MC_PARAM_startup_i_rest_a, 0.3, 0},
    {MC_PARAM_control_encoder_speed_fc_hz, 500.0, 0},
    {MC_PARAM_injection_i_hf_a, 2.1264, 1e-5},
    {MC_PARAM_injection_v1_v, 70.0, 0},
    {MC_PARAM_estimator_pll_speed_fc_hz, 200.0, 0},
    {MC_PARAM_estimator_k2, 100.0, 0},
    {MC_PARAM_startup_step1_m, 5.0, 0},
    {MC_PARAM_startup_v_pol_v, 200.0, 0},
    {MC_PARAM_startup_step3_speed_tol_rpm, 5.0, 0},
    {MC_PARAM_startup_timeout_step12_s, 0.02, 1e-5},
    {MC_PARAM_startup_catch_i_a, 2.0, 0},
    {MC_PARAM_control_offset_cal_samples, 64.0, 0},
    {MC_PARAM_protection_polarity_bias_a, 6.6, 0},
    {MC_PARAM_startup_catch_min_rpm, 24.0, 0},
    {MC_PARAM_estimator_l_adapt_s, 0.01, 1e-5},
    /* I/f: nice2(0.8 i_max); nice2(T_if / 8 / J) with T_if = 1.5 p psi_pm I_f, in rpm/s; the speed
     * where psi_pm w = 5 (Vdc t_dead / Ts / 4 + 2 drop + Rs I_f / 2) (or 2 % of Vdc/sqrt3) */
    {MC_PARAM_startup_if_i_a, 11.0, 1e-5},
    {MC_PARAM_startup_if_accel_rpm_s, 2600.0, 1e-5},
    {MC_PARAM_startup_if_handover_rpm, 72.0, 1e-5},
};
static const want_t motor_b_unop[] = {
    {MC_PARAM_control_i_trip_a, 240.0, 1e-5},
    {MC_PARAM_control_vdc_min_v, 125.0, 0},
    {MC_PARAM_control_vdc_max_v, 375.0, 0},
    {MC_PARAM_control_i_max_a, 160.0, 1e-5},
    {MC_PARAM_control_speed_decimation, 8.0, 0},
    {MC_PARAM_injection_f_hz, 300.0, 1e-5},
    {MC_PARAM_estimator_pll_bw_hz, 18.0, 0},
    {MC_PARAM_control_current_bw_hz, 150.0, 0},
    {MC_PARAM_control_i_slew_a_per_s, 75000.0, 0},
    {MC_PARAM_control_speed_bw_hz, 18.0, 0},   /* the PLL's; the slew bound (144.3 - 5.8) V / (2 pi 0.5496 mH 155.2 A) / 4 = 64.6 Hz */
    {MC_PARAM_protection_overspeed_rpm, 5997.0, 0},
    {MC_PARAM_protection_i_sum_tol_a, 8.0, 0},
    {MC_PARAM_protection_tracking_err_a, 40.0, 0},
    {MC_PARAM_protection_residual_v, 14.0, 0},
    {MC_PARAM_injection_n1_rpm, 500.0, 0},
    {MC_PARAM_protection_lock_speed_floor_rpm, 130.0, 0},
    {MC_PARAM_protection_stall_speed_rpm, 25.0, 0},
    {MC_PARAM_control_speed_kp, 5.654866776461628, 1e-5},
    {MC_PARAM_control_speed_ki, 159.8875912976476, 1e-5},
    {MC_PARAM_control_torque_max_nm, 96.0, 1e-5},
    {MC_PARAM_control_dtc_i_band_a, 3.6, 0},
    {MC_PARAM_startup_i_rest_a, 3.6, 0},
    {MC_PARAM_control_encoder_speed_fc_hz, 500.0, 0},
    {MC_PARAM_injection_i_hf_a, 25.6, 1e-5},
    {MC_PARAM_injection_v1_v, 5.8, 0},
    {MC_PARAM_estimator_pll_speed_fc_hz, 140.0, 0},   /* nice2(8 x 18 Hz) */
    {MC_PARAM_estimator_k2, 3.2, 0},
    {MC_PARAM_startup_step1_m, 1.0, 0},
    {MC_PARAM_startup_v_pol_v, 22.0, 0},
    {MC_PARAM_startup_step3_speed_tol_rpm, 9.5, 0},
    {MC_PARAM_startup_timeout_step12_s, 0.025, 1e-5},
    {MC_PARAM_startup_catch_i_a, 24.0, 0},
    {MC_PARAM_control_offset_cal_samples, 51.0, 0},
    {MC_PARAM_protection_polarity_bias_a, 80.0, 0},
    {MC_PARAM_startup_catch_min_rpm, 30.0, 0},
    {MC_PARAM_estimator_l_adapt_s, 0.016666666666666666, 1e-5},
    /* I/f: nice2(0.8 i_max); nice2(T_if / 8 / J) with T_if = 1.5 p psi_pm I_f, in rpm/s; the speed
     * where psi_pm w = 5 (Vdc t_dead / Ts / 4 + 2 drop + Rs I_f / 2) (or 2 % of Vdc/sqrt3) */
    {MC_PARAM_startup_if_i_a, 130.0, 1e-5},
    {MC_PARAM_startup_if_accel_rpm_s, 1400.0, 1e-5},
    {MC_PARAM_startup_if_handover_rpm, 140.0, 1e-5},
};
static const want_t motor_b_slow[] = {
    {MC_PARAM_control_i_trip_a, 240.0, 1e-5},
    {MC_PARAM_control_vdc_min_v, 125.0, 0},
    {MC_PARAM_control_vdc_max_v, 375.0, 0},
    {MC_PARAM_control_i_max_a, 160.0, 1e-5},
    {MC_PARAM_control_speed_decimation, 5.0, 0},
    {MC_PARAM_injection_f_hz, 500.0, 1e-5},
    {MC_PARAM_estimator_pll_bw_hz, 30.0, 0},
    {MC_PARAM_control_current_bw_hz, 125.0, 0},
    {MC_PARAM_control_i_slew_a_per_s, 63000.0, 0},
    {MC_PARAM_control_speed_bw_hz, 25.0, 0},
    {MC_PARAM_protection_overspeed_rpm, 5997.0, 0},
    {MC_PARAM_protection_i_sum_tol_a, 16.0, 0},
    {MC_PARAM_protection_tracking_err_a, 40.0, 0},
    {MC_PARAM_protection_residual_v, 14.0, 0},
    {MC_PARAM_injection_n1_rpm, 500.0, 0},
    {MC_PARAM_protection_lock_speed_floor_rpm, 130.0, 0},
    {MC_PARAM_protection_stall_speed_rpm, 25.0, 0},
    {MC_PARAM_control_speed_kp, 7.853981633974484, 1e-5},
    {MC_PARAM_control_speed_ki, 308.4251375340425, 1e-5},
    {MC_PARAM_control_torque_max_nm, 96.0, 1e-5},
    {MC_PARAM_control_dtc_i_band_a, 3.6, 0},
    {MC_PARAM_startup_i_rest_a, 3.6, 0},
    {MC_PARAM_control_encoder_speed_fc_hz, 500.0, 0},
    {MC_PARAM_injection_i_hf_a, 25.6, 1e-5},
    {MC_PARAM_injection_v1_v, 9.7, 0},
    {MC_PARAM_estimator_pll_speed_fc_hz, 200.0, 0},
    {MC_PARAM_estimator_k2, 3.2, 0},
    {MC_PARAM_startup_step1_m, 1.0, 0},
    {MC_PARAM_startup_v_pol_v, 28.0, 0},
    {MC_PARAM_startup_step3_speed_tol_rpm, 130.0, 0},
    {MC_PARAM_startup_timeout_step12_s, 0.04, 1e-5},
    {MC_PARAM_startup_catch_i_a, 24.0, 0},
    {MC_PARAM_control_offset_cal_samples, 32.0, 0},
    {MC_PARAM_protection_polarity_bias_a, 80.0, 0},
    {MC_PARAM_startup_catch_min_rpm, 30.0, 0},
    {MC_PARAM_estimator_l_adapt_s, 0.01, 1e-5},
    /* I/f: nice2(0.8 i_max); nice2(T_if / 8 / J) with T_if = 1.5 p psi_pm I_f, in rpm/s; the speed
     * where psi_pm w = 5 (Vdc t_dead / Ts / 4 + 2 drop + Rs I_f / 2) (or 2 % of Vdc/sqrt3) */
    {MC_PARAM_startup_if_i_a, 130.0, 1e-5},
    {MC_PARAM_startup_if_accel_rpm_s, 1400.0, 1e-5},
    {MC_PARAM_startup_if_handover_rpm, 130.0, 1e-5},
};
static const want_t motor_a_manual[] = {
    {MC_PARAM_control_i_trip_a, 19.935, 1e-5},
    {MC_PARAM_control_vdc_min_v, 150.0, 0},
    {MC_PARAM_control_vdc_max_v, 450.0, 0},
    {MC_PARAM_control_i_max_a, 40.0, 1e-5},
    {MC_PARAM_control_speed_decimation, 10.0, 0},
    {MC_PARAM_injection_f_hz, 500.0, 1e-5},
    {MC_PARAM_estimator_pll_bw_hz, 30.0, 0},
    {MC_PARAM_control_current_bw_hz, 250.0, 0},
    {MC_PARAM_control_i_slew_a_per_s, 31000.0, 0},
    {MC_PARAM_control_speed_bw_hz, 14.0, 0},   /* nice2(173.2 V / (2 pi 12.9 mH 40 A 0.97) / 4 = 13.77 Hz) */
    {MC_PARAM_protection_overspeed_rpm, 2893.0, 0},
    {MC_PARAM_protection_i_sum_tol_a, 0.66, 0},
    {MC_PARAM_protection_tracking_err_a, 3.3, 0},
    {MC_PARAM_protection_residual_v, 17.0, 0},
    {MC_PARAM_injection_n1_rpm, 400.0, 0},
    {MC_PARAM_protection_lock_speed_floor_rpm, 100.0, 0},
    {MC_PARAM_protection_stall_speed_rpm, 20.0, 0},
    {MC_PARAM_control_speed_kp, 3.0, 1e-5},
    {MC_PARAM_control_speed_ki, 65.97344572538566, 1e-5},   /* 3 x 2 pi 14 / 4 */
    {MC_PARAM_control_torque_max_nm, 35.64, 1e-5},
    {MC_PARAM_control_dtc_i_band_a, 0.3, 0},
    {MC_PARAM_startup_i_rest_a, 0.3, 0},
    {MC_PARAM_control_encoder_speed_fc_hz, 500.0, 0},
    {MC_PARAM_injection_i_hf_a, 2.1264, 1e-5},
    {MC_PARAM_injection_v1_v, 70.0, 0},
    {MC_PARAM_estimator_pll_speed_fc_hz, 110.0, 0},   /* nice2(8 x 14 Hz) */
    {MC_PARAM_estimator_k2, 100.0, 0},
    {MC_PARAM_startup_step1_m, 5.0, 0},
    {MC_PARAM_startup_v_pol_v, 200.0, 0},
    {MC_PARAM_startup_step3_speed_tol_rpm, 5.0, 0},
    {MC_PARAM_startup_timeout_step12_s, 0.02, 1e-5},
    {MC_PARAM_startup_catch_i_a, 2.0, 0},
    {MC_PARAM_control_offset_cal_samples, 64.0, 0},
    {MC_PARAM_protection_polarity_bias_a, 6.6, 0},
    {MC_PARAM_startup_catch_min_rpm, 24.0, 0},
    {MC_PARAM_estimator_l_adapt_s, 0.01, 1e-5},
    /* I/f: nice2(0.8 i_max); nice2(T_if / 8 / J) with T_if = 1.5 p psi_pm I_f, in rpm/s; the speed
     * where psi_pm w = 5 (Vdc t_dead / Ts / 4 + 2 drop + Rs I_f / 2) (or 2 % of Vdc/sqrt3) */
    {MC_PARAM_startup_if_i_a, 32.0, 1e-5},
    {MC_PARAM_startup_if_accel_rpm_s, 7600.0, 1e-5},
    {MC_PARAM_startup_if_handover_rpm, 190.0, 1e-5},
};

static void set(mc_params_t *p, const char *name, float v)
{
    const int id = mc_param_find(name);
    assert_true(id >= 0);
    mc_param_err_t err;
    assert_true(mc_param_set(p, id, v, &err));
    assert_false(mc_param_is_auto(p, id));
}

static void check(const mc_params_t *p, const want_t *w, size_t n)
{
    for (size_t k = 0; k < n; ++k) {
        const float got = mc_param_get(p, w[k].id);
        const bool ok = w[k].rel == 0.0 ? got == (float)w[k].want
                                        : fabs((double)got - w[k].want) <= w[k].rel * fabs(w[k].want);
        if (!ok) {
            fail_msg("%s = %.9g, hand computation %.9g", mc_param_table[w[k].id].name, (double)got, w[k].want);
        }
    }
    /* every rule of the table is in the list */
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (mc_param_table[id].rule == MC_RULE_NONE) {
            continue;
        }
        bool seen = false;
        for (size_t k = 0; k < n; ++k) {
            seen = seen || w[k].id == id;
        }
        if (!seen) {
            fail_msg("%s has a rule but no hand computation", mc_param_table[id].name);
        }
    }
}

static void thesis_motor(mc_params_t *p)
{
    mc_params_default(p);
}

/* presets/brodatzki-35kw.toml: 4 pole pairs, 0.12 / 0.55 mH, 76.7 mWb, 160 A, 80 N m; 250 V,
 * 8 kHz, a 300 A current sensor */
static void brodatzki_motor(mc_params_t *p)
{
    mc_params_default(p);
    set(p, "motor.pole_pairs", 4.0f);
    set(p, "motor.rs_ohm", 0.010f);
    set(p, "motor.ld_h", 120.0e-6f);
    set(p, "motor.lq_h", 549.6e-6f);
    set(p, "motor.psi_pm_wb", 0.07666f);
    set(p, "motor.i_rated_a", 160.0f);
    set(p, "motor.torque_rated_nm", 80.0f);
    set(p, "motor.inertia_kgm2", 0.05f);
    set(p, "hw.vdc_nominal_v", 250.0f);
    set(p, "control.ts_s", 1.25e-4f);
    set(p, "hw.i_span_a", 300.0f);
}

static void test_rules_thesis_motor(void **state)
{
    (void)state;
    mc_params_t p;
    thesis_motor(&p);
    mc_params_derive(&p);
    check(&p, motor_a, sizeof motor_a / sizeof motor_a[0]);
    mc_param_err_t err;
    assert_true(mc_params_validate(&p, &err));
    /* the table's default of a rule is its value on the thesis motor: the parameter docs and
     * the EDS print it as "rule (x on the thesis motor)", to three figures (1 %) */
    int wrong = 0;
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const mc_param_info_t *e = &mc_param_table[id];
        if (e->rule != MC_RULE_NONE && !(fabsf(mc_param_get(&p, id) - e->def) <= 0.01f * fabsf(e->def))) {
            print_error("%s: the table says %.9g on the thesis motor, its rule gives %.9g\n", e->name, (double)e->def,
                        (double)mc_param_get(&p, id));
            ++wrong;
        }
    }
    assert_int_equal(wrong, 0);
}

static void test_rules_brodatzki_sensorless(void **state)
{
    (void)state;
    mc_params_t p;
    brodatzki_motor(&p);
    assert_true(mc_param_set_choice(&p, MC_PARAM_control_angle_source, "unop", NULL));
    set(&p, "injection.f_hz", 300.0f);
    mc_params_derive(&p);
    check(&p, motor_b_unop, sizeof motor_b_unop / sizeof motor_b_unop[0]);
    mc_param_err_t err;
    assert_true(mc_params_validate(&p, &err));
    /* the injection switched off: the current loop's bandwidth is f_s / 40 again */
    assert_true(mc_param_set_choice(&p, MC_PARAM_injection_kind, "off", NULL));
    mc_params_derive(&p);
    assert_true(p.control_current_bw_hz == 200.0f);
}

static void test_rules_brodatzki_5khz_10bit(void **state)
{
    (void)state;
    mc_params_t p;
    brodatzki_motor(&p);
    set(&p, "control.ts_s", 2.0e-4f);
    set(&p, "hw.adc_bits", 10.0f);
    set(&p, "hw.i_span_a", 1000.0f);
    set(&p, "startup.step2_n", 2.0f);
    mc_params_derive(&p);
    check(&p, motor_b_slow, sizeof motor_b_slow / sizeof motor_b_slow[0]);
    mc_param_err_t err;
    assert_true(mc_params_validate(&p, &err));
}

/* presets/baldor-5p6kw-pmsyrm.toml: a PM-assisted SyRM, its Ld, Lq, psi_pm at i = 0 from the
 * measured map (25.76 / 140.8 mH, 444 mWb), 12.45 A, 29.7 N m, 0.05 kg m^2; 540 V, 8 kHz */
static void baldor_motor(mc_params_t *p)
{
    mc_params_default(p);
    set(p, "motor.pole_pairs", 2.0f);
    set(p, "motor.rs_ohm", 0.63f);
    set(p, "motor.ld_h", 25.76e-3f);
    set(p, "motor.lq_h", 140.8e-3f);
    set(p, "motor.psi_pm_wb", 0.44415f);
    set(p, "motor.i_rated_a", 12.45f);
    set(p, "motor.torque_rated_nm", 29.7f);
    set(p, "motor.inertia_kgm2", 0.05f);
    set(p, "hw.vdc_nominal_v", 540.0f);
    set(p, "control.ts_s", 1.25e-4f);
    set(p, "hw.i_span_a", 25.0f);
    set(p, "hw.vdc_span_v", 1000.0f);
}

/* The speed loop's slew bound, a quarter of (Vdc/sqrt3 - V1) / (2 pi Lq i_max (1 - headroom)), V1
 * only while injecting, rounded to two digits, the PLL at most 6 x the bound (unrounded), the speed filter at
 * 8 x the bandwidth (nice2), with the gains J w_bw and J w_bw^2 / 4 that follow; on two motors
 * (more above: brodatzki with UNOP, where the PLL's 18 Hz binds, and the thesis motor at 40 A,
 * 14 Hz). */
static void test_rules_speed_slew(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        void (*motor)(mc_params_t *);
        const char *source;
        double v1, pll, bw, fc, kp, ki;
    } c[] = {
        /* 173.2 V - 70 V over 2 pi 12.9 mH 12.89 A (13.29 A less the 3 % headroom): 98.8 Hz, a
         * quarter 24.69 Hz, two digits 25: the thesis' 25 Hz stays */
        {"thesis, UNOP", thesis_motor, "unop", 70.0, 30.0, 25.0, 200.0, 2.0420352248333655, 80.19053575885104},
        /* the injection at its cap, half of 311.8 V; 155.9 V over 2 pi 140.8 mH 12.08 A: 14.6 Hz,
         * a quarter 3.648 Hz; the PLL nice2(6 x 3.648) = 22 Hz below 6 % of 500 Hz */
        {"baldor, UNOP", baldor_motor, "unop", 155.88457268119896, 22.0, 3.6, 29.0, 1.1309733552923256, 6.395503651905904},
        /* no injection: the whole 311.8 V, 29.2 Hz, a quarter 7.30 Hz (6 x: 44 Hz, the PLL's 30) */
        {"baldor, encoder", baldor_motor, "encoder", -1.0, 30.0, 7.3, 58.0, 2.293362637120549, 26.29756092670259},
    };
    for (size_t k = 0; k < sizeof c / sizeof c[0]; ++k) {
        mc_params_t p;
        c[k].motor(&p);
        assert_true(mc_param_set_choice(&p, MC_PARAM_control_angle_source, c[k].source, NULL));
        mc_params_derive(&p);
        const double got[] = {p.injection_v1_v, p.estimator_pll_bw_hz, p.control_speed_bw_hz, p.estimator_pll_speed_fc_hz,
                              p.control_speed_kp, p.control_speed_ki};
        const double want[] = {c[k].v1, c[k].pll, c[k].bw, c[k].fc, c[k].kp, c[k].ki};
        for (size_t j = 0; j < 6; ++j) {
            if (want[j] >= 0.0 && !(fabs(got[j] - want[j]) <= 1e-5 * fabs(want[j]))) {
                fail_msg("%s: value %u = %.9g, hand computation %.9g", c[k].name, (unsigned)j, got[j], want[j]);
            }
        }
        mc_param_err_t err;
        if (!mc_params_validate(&p, &err)) {
            fail_msg("%s: %s (%s)", c[k].name, err.text, mc_param_table[err.param].name);
        }
    }
    /* a bandwidth given by hand is kept, and the filter follows it */
    mc_params_t p;
    baldor_motor(&p);
    assert_true(mc_param_set_choice(&p, MC_PARAM_control_angle_source, "unop", NULL));
    set(&p, "control.speed_bw_hz", 20.0f);
    mc_params_derive(&p);
    assert_true(p.control_speed_bw_hz == 20.0f);
    assert_true(p.estimator_pll_speed_fc_hz == 160.0f);
}

/* Entries set by hand are kept and the rules that read them follow them: the current limit
 * (overspeed, current slew) and the speed kp (ki from the kp given, kp w_bw / 4). */
static void test_rules_follow_hand_entries(void **state)
{
    (void)state;
    mc_params_t p;
    thesis_motor(&p);
    set(&p, "control.i_max_a", 40.0f);
    set(&p, "control.speed_kp", 3.0f);
    mc_params_derive(&p);
    check(&p, motor_a_manual, sizeof motor_a_manual / sizeof motor_a_manual[0]);
    /* a rule's parameter set by hand stays as set through a change of the motor */
    set(&p, "control.i_trip_a", 60.0f);
    set(&p, "motor.i_rated_a", 20.0f);
    mc_params_derive(&p);
    assert_true(p.control_i_trip_a == 60.0f);
    assert_true(p.protection_polarity_bias_a == 10.0f);   /* 0.5 x 20 A, auto */
}

/* An entry the rules divide by (or shift by) out of range: derive changes nothing, validation
 * names that entry. At the guard's own edges (1 pole pair, 1 and 30 ADC bits, one Step II
 * period, decimation 1) the rules run. */
static void test_derive_guard(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        float bad, edge;
    } g[] = {
        {"control.ts_s", 0.0f, 5e-5f},
        {"motor.pole_pairs", 0.0f, 1.0f},
        {"hw.adc_bits", 0.0f, 1.0f},
        {"hw.adc_bits", 31.0f, 30.0f},
        {"startup.step2_n", 0.0f, 1.0f},
        {"control.speed_decimation", 0.0f, 1.0f},
    };
    for (size_t k = 0; k < sizeof g / sizeof g[0]; ++k) {
        mc_params_t p, before;
        thesis_motor(&p);
        mc_params_derive(&p);
        set(&p, g[k].name, g[k].bad);
        set(&p, "motor.i_rated_a", 20.0f);   /* what the rules would follow */
        memcpy(&before, &p, sizeof p);
        mc_params_derive(&p);
        if (memcmp(&p, &before, sizeof p) != 0) {
            fail_msg("%s = %g: derive changed the set", g[k].name, (double)g[k].bad);
        }
        mc_param_err_t err;
        assert_false(mc_params_validate(&p, &err));
        assert_int_equal(err.param, mc_param_find(g[k].name));
        set(&p, g[k].name, g[k].edge);
        mc_params_derive(&p);
        if (!(p.control_i_trip_a == 30.0f && p.control_i_max_a == 20.0f && p.protection_polarity_bias_a == 10.0f)) {
            fail_msg("%s = %g: the rules did not run", g[k].name, (double)g[k].edge);
        }
        for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
            if (!isfinite(mc_param_get(&p, id))) {
                fail_msg("%s = %g: %s not finite", g[k].name, (double)g[k].edge, mc_param_table[id].name);
            }
        }
    }
}

/* An integer rule whose result does not fit int32 keeps the entry's value (the conversion would
 * be undefined); a float rule stores what it computes. 1 ps sampling: 6.4e9 offset samples. */
static void test_derive_integer_overflow(void **state)
{
    (void)state;
    mc_params_t p;
    thesis_motor(&p);
    set(&p, "control.ts_s", 1e-12f);
    mc_params_derive(&p);
    assert_int_equal(p.control_offset_cal_samples, 64);                 /* 6.4e9: kept */
    assert_int_equal(p.control_speed_decimation, 1000000000);            /* 1e9: fits */
    assert_true(p.startup_timeout_step12_s == 0.02f);
    assert_true(p.control_current_bw_hz > 2.0e10f);   /* f_s / 40, a float */
    mc_param_err_t err;
    assert_false(mc_params_validate(&p, &err));
    assert_int_equal(err.param, MC_PARAM_control_ts_s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rules_thesis_motor),
        cmocka_unit_test(test_rules_brodatzki_sensorless),
        cmocka_unit_test(test_rules_brodatzki_5khz_10bit),
        cmocka_unit_test(test_rules_follow_hand_entries),
        cmocka_unit_test(test_rules_speed_slew),
        cmocka_unit_test(test_derive_guard),
        cmocka_unit_test(test_derive_integer_overflow),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
