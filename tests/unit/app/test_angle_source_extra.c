/* The angle-source seam (mc/angle_source.h), shown with a test-only source.
 *
 * ADDING AN ANGLE SOURCE IS ITS FILE, ONE REGISTRATION LINE AND ITS PARAMETER ROWS:
 *   1. its file(s): `const mc_angle_src_desc_t mc_angle_src_NAME` with what it is (sensor or
 *      estimator), what it needs (injection, loss-of-lock checks, the flux map for which
 *      estimator.model) and its life cycle (build from the parameters, init, retune, reset, step,
 *      diag, cfg_of, cfg_equal), its configuration and state checked with MC_ANGLE_SRC_CFG_FITS and
 *      MC_ANGLE_SRC_FITS: here tests/unit/app/src_test_hold.c;
 *   2. one line X(NAME) in MC_ANGLE_SOURCES (mc/angle_source.h). This test build does not touch
 *      the header: it adds the line through the hook, on the compiler's command line
 *      (tests/unit/app/CMakeLists.txt, target app_angle_registry), and compiles the drive's app
 *      sources (firmware/app, the list of mc_app) again with it;
 *   3. the rows of the parameters it reads in mc/params_table.h (test_hold has none of its own).
 * Nothing else changes: the line adds the enum value MC_ANGLE_SRC_test_hold, the registry entry
 * (angle_registry.c), the choice "test_hold" of control.angle_source and the upper end of its
 * range (params_table.h); the drive builds, runs and checks the source by its descriptor. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "hal_host/host.h"
#include "mc/angle.h"
#include "mc/drive.h"
#include "drive_internal.h"   /* mc_drive_recover */
#include "spin_plant.h"
#include "src_test_hold.h"

/* ------------------------------------------------------------------------------- the tests */

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    mc_drive_cfg_t cfg;
    mc_drive_link_t link;
    mc_drive_t d;
} rig_t;

static void rig_init(rig_t *r, const char *source)
{
    *r = (rig_t){0};
    hal_host_pwm_init(&r->pwm, 1e-4f, 0.5e-6f);
    r->qep = (hal_qep_t){.counts_per_rev = 80000u};
    mc_drive_cfg_default(&r->cfg);
    assert_true(mc_param_set_choice(&r->cfg.p, MC_PARAM_control_angle_source, source, NULL));
    assert_true(mc_param_set_choice(&r->cfg.p, MC_PARAM_estimator_model, "const", NULL));   /* no map */
    assert_true(mc_param_set_choice(&r->cfg.p, MC_PARAM_startup_catch, "off", NULL));   /* straight to RUN */
    assert_true(mc_drive_init(&r->d, &r->link, &r->cfg, &r->adc, &r->pwm, &r->qep));
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

static void enable_iq(rig_t *r, float theta_init, float i_q)
{
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT, .i_ref = {0.0f, i_q},
                              .theta_init = theta_init};
    mc_drive_command(&r->d, &c);
    run(r, (int)r->d.cfg->p.control_offset_cal_samples + 1);
    assert_int_equal(mc_drive_state(&r->d), MC_STATE_RUN);
}

static void enable(rig_t *r, float theta_init)
{
    enable_iq(r, theta_init, 1.0f);
}

/* The one line registered the source everywhere: enum, registry, the parameter's choices and range. */
static void test_registry_has_extra_source(void **st)
{
    (void)st;
    assert_int_equal(MC_ANGLE_SRC_COUNT, 3);
    assert_int_equal(MC_ANGLE_SRC_encoder, 0);   /* the existing values stay where they were */
    assert_int_equal(MC_ANGLE_SRC_unop, 1);
    assert_int_equal(MC_ANGLE_SRC_test_hold, 2);
    assert_ptr_equal(mc_angle_src_get(MC_ANGLE_SRC_test_hold), &mc_angle_src_test_hold);
    assert_ptr_equal(mc_angle_src_get(MC_ANGLE_SRC_unop), &mc_angle_src_unop);
    assert_null(mc_angle_src_get(MC_ANGLE_SRC_COUNT));

    const int id = mc_param_find("control.angle_source");
    assert_int_equal(id, MC_PARAM_control_angle_source);
    assert_non_null(strstr(mc_param_table[id].choices, "test_hold"));
    assert_float_equal(mc_param_table[id].max, (float)(MC_ANGLE_SRC_COUNT - 1), 0.0f);

    mc_params_t p;
    mc_params_default(&p);
    mc_param_err_t err;
    assert_true(mc_param_set_choice(&p, id, "test_hold", &err));
    assert_int_equal(p.control_angle_source, MC_ANGLE_SRC_test_hold);
    char buf[32];
    mc_param_choice_text(&p, id, buf, sizeof buf);
    assert_string_equal(buf, "test_hold");
    mc_params_derive(&p);
    assert_true(mc_params_validate(&p, &err));
    /* a source that is not registered is still refused */
    assert_false(mc_param_set_choice(&p, id, "test_hol", &err));
    assert_int_equal(err.kind, MC_PERR_RANGE);
    assert_int_equal(p.control_angle_source, MC_ANGLE_SRC_test_hold);
    /* and one past the end of the list is out of range */
    p.control_angle_source = MC_ANGLE_SRC_COUNT;
    assert_false(mc_params_validate(&p, &err));
    assert_int_equal(err.param, MC_PARAM_control_angle_source);
    assert_int_equal(err.kind, MC_PERR_RANGE);
}

/* The drive runs on it: the controller's angle is the held one, and without needs_injection the
 * drive injects nothing (with injection.kind = sine, the default), yet as an estimator with
 * lock_checks it has the loss-of-lock detectors (which stay quiet: its raw estimate agrees). */
static void test_drive_runs_with_held_angle(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    assert_ptr_equal(r.d.src, &mc_angle_src_test_hold);
    assert_int_equal(r.d.cfg->p.injection_kind, MC_CHOICE_injection_kind_sine);   /* sine: would inject with an estimator */
    assert_false(r.d.cfg->blk.inject);
    assert_true(r.d.cfg->blk.prot.lock_n > 0u);
    const float held = 1.234f;
    enable(&r, held);
    for (int k = 0; k < 200; ++k) {
        run(&r, 1);
        mc_drive_telem_t tm;
        assert_true(mc_drive_telemetry_read(&r.d, &tm));
        assert_int_equal(tm.state, MC_STATE_RUN);
        assert_true(tm.theta == held);
        assert_true(tm.omega == 0.0f);
        assert_true(tm.theta_raw == held);
        assert_true(tm.u_inj == 0.0f);
    }
    /* a new enable takes the new angle */
    const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
    mc_drive_command(&r.d, &off);
    run(&r, 2);
    enable(&r, -2.5f);
    run(&r, 5);
    assert_true(mc_drive_telemetry(&r.d)->theta == -2.5f);
}

/* The ramp variant: the angle advances omega ts per period, wrapped to [-pi, pi). */
static void test_drive_follows_ramp(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 300.0f;
    rig_init(&r, "test_hold");
    /* it starts at its ramp speed from a hand-over at standstill: the loss-of-lock check's speed
     * swing would rightly call that implausible, so that detector is off here (lock_time 0) */
    mc_param_err_t err;
    assert_true(mc_drive_param_write(&r.d, MC_PARAM_protection_lock_time_s, 0.0f, &err));
    run(&r, 1);
    assert_int_equal(r.d.cfg->blk.prot.lock_n, 0u);
    enable(&r, 3.0f);
    float prev = mc_drive_telemetry(&r.d)->theta;
    int wraps = 0;
    for (int k = 0; k < 400; ++k) {
        run(&r, 1);
        const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
        assert_true(tm->omega == 300.0f);
        assert_true(tm->u_inj == 0.0f);
        assert_true(tm->theta >= -MC_PI && tm->theta < MC_PI);
        const float step = mc_wrap_pi(tm->theta - prev);
        assert_float_equal(step, 300.0f * r.d.cfg->p.control_ts_s, 1e-5f);
        wraps += tm->theta < prev ? 1 : 0;
        prev = tm->theta;
    }
    assert_int_equal(wraps, 2);   /* 400 periods x 0.03 rad = 12 rad, from 3 rad */
    test_hold_omega = 0.0f;
}

/* For contrast, the same drive with UNOP (needs_injection) injects. */
static void test_estimator_source_injects(void **st)
{
    (void)st;
    static rig_t r;
    rig_init(&r, "unop");
    assert_true(r.d.cfg->blk.inject);
    enable(&r, 0.0f);
    float peak = 0.0f;
    for (int k = 0; k < 20; ++k) {
        run(&r, 1);
        peak = fmaxf(peak, fabsf(mc_drive_telemetry(&r.d)->u_inj));
    }
    assert_true(peak > 1.0f);
}


static uint32_t periods(float s, float ts)
{
    return (uint32_t)(s / ts + 0.5f);
}

static bool build_with(const char *source, const char *model, mc_drive_built_t *out, mc_param_err_t *err)
{
    mc_drive_cfg_t cfg;
    mc_drive_cfg_default(&cfg);
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_control_angle_source, source, NULL));
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_estimator_model, model, NULL));
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    return mc_drive_build(&cfg, out, err);
}

/* The drive's checks follow the descriptor's kind and capabilities, not needs_injection: an
 * estimator that needs no injection gets the loss-of-lock detectors, the recovery, the catch
 * and the flux-map requirement of its model; an angle sensor none of them. */
static void test_checks_follow_capabilities(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    mc_param_err_t err;
    test_hold_omega = 0.0f;
    assert_true(build_with("test_hold", "const", &b, &err));
    assert_false(b.blk.inject);
    assert_int_equal(b.blk.prot.lock_n, periods(b.p.protection_lock_time_s, b.p.control_ts_s));
    assert_int_equal(b.blk.prot.jump_n, periods(b.p.protection_lock_jump_time_s, b.p.control_ts_s));
    assert_true(b.blk.prot.lock_n > 0u && b.blk.prot.jump_n > 0u);
    assert_true(b.blk.prot.recover);
    assert_true(b.blk.seq.catch_first);   /* startup.catch = on, the default */
    assert_false(b.blk.src_measures);

    assert_true(build_with("encoder", "const", &b, &err));
    assert_int_equal(b.blk.prot.lock_n, 0u);
    assert_int_equal(b.blk.prot.jump_n, 0u);
    assert_false(b.blk.prot.recover);
    assert_false(b.blk.seq.catch_first);
    assert_true(b.blk.src_measures);

    assert_true(build_with("unop", "const", &b, &err));
    assert_true(b.blk.inject && b.blk.prot.lock_n > 0u && b.blk.prot.recover);

    /* estimator.model = fluxmap without a map: refused for the sources that declare the need */
    assert_false(build_with("test_hold", "fluxmap", &b, &err));
    assert_int_equal(err.kind, MC_PERR_MODEL);
    assert_int_equal(err.param, MC_PARAM_estimator_model);
    assert_false(build_with("unop", "fluxmap", &b, &err));
    assert_int_equal(err.kind, MC_PERR_MODEL);
    assert_true(build_with("encoder", "fluxmap", &b, &err));
}

/* The source's build reports its own refusals through mc_param_err_t, and the drive refuses the
 * whole configuration with it (init: MC_FAULT_CONFIG; a parameter write: nothing changes). */
static void test_build_error_reaches_the_drive(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    static rig_t r;
    mc_param_err_t err;
    test_hold_omega = 2000.0f;   /* above the default over-speed limit (~995 rad/s el) */
    assert_false(build_with("test_hold", "const", &b, &err));
    assert_int_equal(err.kind, MC_PERR_CROSS);
    assert_int_equal(err.param, MC_PARAM_protection_overspeed_rpm);
    assert_string_equal(err.text, "test_hold's ramp must stay below the over-speed limit");

    r = (rig_t){0};
    hal_host_pwm_init(&r.pwm, 1e-4f, 0.5e-6f);
    mc_drive_cfg_default(&r.cfg);
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_control_angle_source, "test_hold", NULL));
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_estimator_model, "const", NULL));   /* no map */
    assert_false(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    assert_int_equal(mc_drive_config_error(&r.d)->param, MC_PARAM_protection_overspeed_rpm);
    assert_true((mc_drive_faults(&r.d) & MC_FAULT_CONFIG) != 0u);

    /* a ramp within the limit runs; a live write of the limit below it is refused */
    test_hold_omega = 300.0f;
    rig_init(&r, "test_hold");
    enable(&r, 0.0f);
    const float before = r.d.cfg->p.protection_overspeed_rpm;
    assert_false(mc_drive_param_write(&r.d, MC_PARAM_protection_overspeed_rpm, 500.0f, &err));   /* 262 rad/s el */
    assert_int_equal(err.param, MC_PARAM_protection_overspeed_rpm);
    run(&r, 2);
    assert_true(r.d.cfg->p.protection_overspeed_rpm == before);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    test_hold_omega = 0.0f;
}

/* The loss-of-lock detector acts on the estimator without injection: a raw speed that disagrees
 * with the output trips it within protection.lock_time_s and its 20 Hz average. */
static void test_lock_loss_detected_without_injection(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    enable_iq(&r, 0.5f, 0.0f);   /* no current asked of the rig's dead machine: no other detector */
    run(&r, 1000);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    test_hold_raw_offset = 500.0f;   /* lock band: 0.5 |w| + 52 rad/s el */
    const uint32_t limit = r.d.cfg->blk.prot.lock_n + 100u;
    uint32_t n = 0u;
    while (mc_drive_state(&r.d) == MC_STATE_RUN && n < limit) {
        run(&r, 1);
        ++n;
    }
    test_hold_raw_offset = 0.0f;
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_true((mc_drive_faults(&r.d) & MC_FAULT_LOSS_OF_LOCK) != 0u);
    assert_true(n >= r.d.cfg->blk.prot.lock_n);
}

/* With protection.lock_action = recover the same loss of lock is not a fault: in that period the
 * outputs go off and the duties latched for the catch's first pulse are V(000) (every phase at
 * 0: the lower switches short the windings, the back-EMF alone drives the probe current), the
 * state is the catch, and the reason is counted as recovered from. */
static void test_lock_loss_recovers_with_v000(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    enable_iq(&r, 0.5f, 0.0f);
    run(&r, 1000);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_true(hal_pwm_enabled(&r.pwm));
    test_hold_raw_offset = 500.0f;
    const uint32_t limit = r.d.cfg->blk.prot.lock_n + 100u;
    uint32_t n = 0u;
    while (mc_drive_state(&r.d) == MC_STATE_RUN && n < limit) {
        run(&r, 1);
        ++n;
    }
    test_hold_raw_offset = 0.0f;
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
    assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
    assert_int_equal(mc_drive_faults(&r.d), 0u);
    assert_int_equal(mc_drive_telemetry(&r.d)->recoveries, 1u);
    assert_int_equal(mc_drive_telemetry(&r.d)->recovered_from, MC_FAULT_LOSS_OF_LOCK);
    assert_false(hal_pwm_enabled(&r.pwm));
    for (int k = 0; k < 3; ++k) {
        assert_float_equal(r.pwm.shadow[k], 0.0f, 0.0f);
        assert_float_equal(mc_drive_telemetry(&r.d)->duty[k], 0.0f, 0.0f);
    }
}

/* Loses the lock (the raw speed 500 rad/s off the output) until the drive leaves RUN. */
static void lose_lock(rig_t *r)
{
    const uint32_t limit = r->d.cfg->blk.prot.lock_n + 100u;
    test_hold_raw_offset = 500.0f;
    for (uint32_t n = 0u; mc_drive_state(&r->d) == MC_STATE_RUN && n < limit; ++n) {
        run(r, 1);
    }
    test_hold_raw_offset = 0.0f;
}

/* What the drive hands the angle source in RUN's first periods after an enable (the given angle,
 * no steps): the voltage that acted over the period before, none (the outputs off through the
 * calibration, then on at 50 % duties), and the current of the sample before. A later enable
 * starts from the same. (startup.c:58: the voltage history starts at zero with every enable.) */
static void test_source_inputs_at_run_entry(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    for (int cyc = 0; cyc < 2; ++cyc) {
        test_hold_steps = 0u;
        const mc_drive_cmd_t on = {.enable = true, .mode = MC_MODE_CURRENT, .i_ref = {0.0f, 1.0f}, .theta_init = 0.25f};
        mc_drive_command(&r.d, &on);
        for (int n = 0; n < 1000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
            run(&r, 1);
        }
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
        assert_int_equal(test_hold_steps, 1u);   /* RUN's first period: the calibration's last */
        for (int k = 0; k < 2; ++k) {
            if (k > 0) {
                run(&r, 1);
            }
            assert_true(test_hold_in.u_ab_applied.alpha == 0.0f && test_hold_in.u_ab_applied.beta == 0.0f);
            assert_true(fabsf(test_hold_in.i_ab_prev.alpha) < 1e-3f && fabsf(test_hold_in.i_ab_prev.beta) < 1e-3f);
        }
        /* the pipeline's voltage for 1 A in q reaches the source from the third period */
        run(&r, 20);
        assert_true(hypotf(test_hold_in.u_ab_applied.alpha, test_hold_in.u_ab_applied.beta) > 0.0f);
        const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
        mc_drive_command(&r.d, &off);
        run(&r, 2);
    }
}

/* The recovery budget (protection.retries) is per enable: with one retry, a loss of lock in
 * each of two enables recovers (outputs off, the catch). On this dead rig the catch finds the
 * rotor standing, which after a recovery with the given angle is no angle to trust: the reason
 * is latched then (mc/catch.h, MC_CATCH_STALE). The telemetry's recoveries and their reasons
 * start from none at every enable. */
static void test_recovery_budget_per_enable(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_protection_retries, 1.0f, NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    for (int cyc = 0; cyc < 2; ++cyc) {
        enable_iq(&r, 0.5f, 0.0f);
        /* the telemetry's recovery record is this enable's too */
        assert_int_equal(mc_drive_telemetry(&r.d)->recoveries, 0u);
        assert_int_equal(mc_drive_telemetry(&r.d)->recovered_from, 0u);
        run(&r, 1000);
        lose_lock(&r);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);   /* recovering: the catch */
        assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
        assert_int_equal(mc_drive_telemetry(&r.d)->recoveries, 1u);
        assert_false(hal_pwm_enabled(&r.pwm));
        for (int n = 0; n < 1000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
            run(&r, 1);
        }
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
        assert_int_equal(mc_drive_faults(&r.d), MC_FAULT_LOSS_OF_LOCK);
        assert_false(hal_pwm_enabled(&r.pwm));
        const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
        mc_drive_command(&r.d, &off);
        run(&r, 1);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_IDLE);
    }
}

/* A recovery whose catch finds the rotor standing has no angle to go on with (the given one is
 * stale after a loss of lock, and this start does not find one itself): the reason it recovered
 * from is latched at the catch's end, with recoveries left in the budget (protection.retries 3),
 * the outputs off: one recovery, never RUN again. (startup.c:281: the catch's outcome knows it
 * follows a recovery.) */
static void test_stale_catch_faults_at_once(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_param_set(&r.cfg.p, MC_PARAM_protection_retries, 3.0f, NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    assert_false(r.d.seq.cfg.init_pos);
    enable_iq(&r, 0.5f, 0.0f);
    run(&r, 1000);
    lose_lock(&r);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_INIT_POS);
    assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
    assert_int_equal(mc_drive_telemetry(&r.d)->recoveries, 1u);
    int n = 0;
    for (; n < 1000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        assert_int_equal(r.d.seq.step, MC_INIT_CATCH);
        run(&r, 1);
    }
    assert_true(n < 1000);
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_FAULT);
    assert_int_equal(mc_drive_faults(&r.d), MC_FAULT_LOSS_OF_LOCK);
    assert_int_equal(mc_drive_telemetry(&r.d)->recoveries, 1u);
    assert_false(hal_pwm_enabled(&r.pwm));
}

/* cfg_of gives the configuration the running source holds; cfg_equal compares two by their
 * fields (not their bytes) and tells a changed one apart. */
static void test_cfg_of_and_equal(void **st)
{
    (void)st;
    static rig_t r;
    static mc_drive_built_t b;
    test_hold_omega = 100.0f;
    for (int k = 0; k < (int)MC_ANGLE_SRC_COUNT; ++k) {
        const mc_angle_src_desc_t *src = mc_angle_src_get(k);
        rig_init(&r, src->name);
        mc_angle_src_cfg_t now;
        memset(&now, 0xa5, sizeof now);   /* whatever cfg_of leaves alone must not matter */
        src->cfg_of(&r.d.src_state, &now);
        assert_true(src->cfg_equal(&now, &r.d.cfg->blk.src.cfg));
        assert_true(src->cfg_equal(&r.d.cfg->blk.src.cfg, &now));
        /* control.ts_s (read by every source) at another value: another configuration */
        mc_drive_cfg_t cfg = r.cfg;
        assert_true(mc_param_set(&cfg.p, MC_PARAM_control_ts_s, 2e-4f, NULL));
        mc_param_err_t err;
        assert_true(mc_drive_build(&cfg, &b, &err));
        assert_false(src->cfg_equal(&now, &b.blk.src.cfg));
    }
    test_hold_omega = 0.0f;
}

/* RUN's first period after a catch whose (O.1) moved the offsets (mc/offset_cal.h): the source
 * gets i(k-1) and i(k) both as the new offsets give them, so that their difference is the
 * current's change and not the offsets' (the catch at 1500 rpm either way on the spinning plant,
 * spin_plant.h, whose diodes' current biased the calibration's mean by 0.7-0.8 A). The test
 * reads the two samples' raw counts and the offsets in force after the catch.
 * (startup.c:133-134: the last sample moved with the offsets.) */
static void test_source_inputs_after_offsets_moved(void **st)
{
    (void)st;
    static rig_t r;
    const double speeds[] = {785.398, -785.398};
    for (size_t v = 0; v < 2u; ++v) {
        test_hold_omega = 0.0f;
        rig_init(&r, "test_hold");
        assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
        assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
        assert_true(r.d.seq.cfg.catch_first);
        spin_t p = {.w = speeds[v], .th = 0.4, .lean = 0.25};
        const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_TORQUE};
        mc_drive_command(&r.d, &c);
        uint16_t raw_prev[3] = {0u, 0u, 0u}, raw_now[3] = {0u, 0u, 0u};
        float mean[3] = {0.0f, 0.0f, 0.0f};
        for (int n = 0; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
            memcpy(raw_prev, raw_now, sizeof raw_prev);
            const bool cal = mc_drive_state(&r.d) == MC_STATE_OFFSET_CAL || n == 0;
            (void)spin_period_on(&p, &r.d, &r.pwm, &r.adc);
            memcpy(raw_now, r.adc.sample.i, sizeof raw_now);
            if (cal && mc_drive_state(&r.d) != MC_STATE_OFFSET_CAL) {
                memcpy(mean, r.d.offs.offset, sizeof mean);
            }
        }
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
        const float k = r.d.cfg->blk.offs.amps_per_count;
        const float *off = r.d.offs.offset;
        float moved = 0.0f;
        for (int j = 0; j < 3; ++j) {
            moved = fmaxf(moved, fabsf(off[j] - mean[j]) * k);
        }
        const mc_ab_t prev = mc_clarke((mc_abc_t){((float)raw_prev[0] - off[0]) * k, ((float)raw_prev[1] - off[1]) * k,
                                                  ((float)raw_prev[2] - off[2]) * k});
        const mc_ab_t now = mc_clarke((mc_abc_t){((float)raw_now[0] - off[0]) * k, ((float)raw_now[1] - off[1]) * k,
                                                 ((float)raw_now[2] - off[2]) * k});
        print_message("%+.0f rad/s: offsets moved by up to %.3f A; i(k-1) (%.4f, %.4f) A for (%.4f, %.4f), i(k) (%.4f, "
                      "%.4f) A for (%.4f, %.4f)\n", speeds[v], (double)moved, (double)test_hold_in.i_ab_prev.alpha,
                      (double)test_hold_in.i_ab_prev.beta, (double)prev.alpha, (double)prev.beta,
                      (double)test_hold_in.i_ab.alpha, (double)test_hold_in.i_ab.beta, (double)now.alpha, (double)now.beta);
        assert_true(moved > 0.2f);
        assert_float_equal(test_hold_in.i_ab_prev.alpha, prev.alpha, 1e-4);
        assert_float_equal(test_hold_in.i_ab_prev.beta, prev.beta, 1e-4);
        assert_float_equal(test_hold_in.i_ab.alpha, now.alpha, 1e-4);
        assert_float_equal(test_hold_in.i_ab.beta, now.beta, 1e-4);
    }
}

/* A recovery's catch that finds the rotor turning starts the current loop again from rest: RUN's
 * first voltage is what a current loop fresh from its configuration gives for that period's
 * reference, current and speed, not one carrying the integrators of the RUN before the recovery
 * (8 A in q on the spinning plant, which has no resistance, leave the q integrator at -0.1 V). At 300 rpm (the flux held: no field-weakening entry), test_hold ramping at
 * the rotor's speed; its current loop sees the currents themselves (no injection, no notch).
 * (startup.c:34, the current loop's reset with the estimate's.) */
static void test_recovery_restarts_the_current_loop(void **st)
{
    (void)st;
    static rig_t r;
    const float w = 300.0f / 60.0f * 6.2831853f * 5.0f;
    test_hold_omega = w;
    rig_init(&r, "test_hold");
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_startup_catch, "on", NULL));
    assert_true(mc_param_set_choice(&r.cfg.p, MC_PARAM_protection_lock_action, "recover", NULL));
    assert_true(mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep));
    assert_false(r.d.cfg->blk.inject);
    spin_t p = {.w = w, .th = 1.3, .lean = 0.25};
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT, .i_ref = {0.0f, 8.0f}};
    mc_drive_command(&r.d, &c);
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) != MC_STATE_RUN; ++n) {
        (void)spin_period_on(&p, &r.d, &r.pwm, &r.adc);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    for (int n = 0; n < 400; ++n) {
        (void)spin_period_on(&p, &r.d, &r.pwm, &r.adc);
        assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    }
    const mc_drive_telem_t *tm = mc_drive_telemetry(&r.d);
    const float wound_q = r.d.cc.pi_q.integ;
    print_message("RUN: i_dq (%.2f, %.2f) A, the q integrator at %.3f V\n", (double)tm->i_dq.d, (double)tm->i_dq.q,
                  (double)wound_q);
    assert_true(fabsf(wound_q) > 0.05f);   /* 50 x the comparison's tolerance below */
    assert_true(mc_drive_recover(&r.d, MC_FAULT_LOSS_OF_LOCK, tm->vdc));
    for (int n = 0; n < 2000 && mc_drive_state(&r.d) == MC_STATE_INIT_POS; ++n) {
        (void)spin_period_on(&p, &r.d, &r.pwm, &r.adc);
    }
    assert_int_equal(mc_drive_state(&r.d), MC_STATE_RUN);
    assert_false(mc_fwe_active(&r.d.fw_entry));
    static mc_cc_t fresh;
    mc_cc_init(&fresh, &r.d.cfg->cc);
    const mc_dq_t u = mc_cc_step(&fresh, tm->i_ref, tm->i_dq, tm->omega, tm->vdc * 0.57735027f * r.d.cfg->blk.u_loop);
    print_message("after the recovery: u_dq (%.4f, %.4f) V, a fresh loop (%.4f, %.4f) V\n", (double)tm->u_dq.d,
                  (double)tm->u_dq.q, (double)u.d, (double)u.q);
    assert_float_equal(tm->u_dq.d, u.d, 1e-3);
    assert_float_equal(tm->u_dq.q, u.q, 1e-3);
    test_hold_omega = 0.0f;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_registry_has_extra_source),
        cmocka_unit_test(test_drive_runs_with_held_angle),
        cmocka_unit_test(test_drive_follows_ramp),
        cmocka_unit_test(test_estimator_source_injects),
        cmocka_unit_test(test_checks_follow_capabilities),
        cmocka_unit_test(test_build_error_reaches_the_drive),
        cmocka_unit_test(test_lock_loss_detected_without_injection),
        cmocka_unit_test(test_lock_loss_recovers_with_v000),
        cmocka_unit_test(test_source_inputs_at_run_entry),
        cmocka_unit_test(test_recovery_budget_per_enable),
        cmocka_unit_test(test_source_inputs_after_offsets_moved),
        cmocka_unit_test(test_recovery_restarts_the_current_loop),
        cmocka_unit_test(test_stale_catch_faults_at_once),
        cmocka_unit_test(test_cfg_of_and_equal),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
