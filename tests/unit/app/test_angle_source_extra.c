/* The angle-source seam (mc/angle_source.h), shown with a test-only source.
 *
 * ADDING AN ANGLE SOURCE IS THIS FILE PLUS ONE REGISTRATION LINE:
 *   1. one file that defines `const mc_angle_src_desc_t mc_angle_src_NAME` (its state checked
 *      with MC_ANGLE_SRC_FITS), as below;
 *   2. one line X(NAME) in MC_ANGLE_SOURCES (mc/angle_source.h). This test build does not touch
 *      the header: it adds the line through the hook, on the compiler's command line
 *      (tests/unit/app/CMakeLists.txt, target app_angle_registry):
 *          target_compile_definitions(app_angle_registry PRIVATE "MC_ANGLE_SOURCES_EXTRA(X)=X(test_hold)")
 *      and compiles the drive's app sources (firmware/app, the list of mc_app) again with it.
 * Nothing else changes: the line adds the enum value MC_ANGLE_SRC_test_hold, the registry entry
 * (angle_registry.c), the choice "test_hold" of control.angle_source and the upper end of its
 * range (params_table.h), and the drive calls the descriptor at the same point of the ISR.
 *
 * The source "test_hold": holds the angle it is reset to (the one handed over with the enable
 * command, startup.init_pos = given) at speed 0, or, with test_hold_omega set, ramps from it at
 * that fixed electrical speed. It needs no injection (needs_injection = false), so the drive
 * injects nothing while it runs. */
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

/* ------------------------------------------------------------------ the source (the seam) */

static float test_hold_omega = 0.0f;   /* ramp speed [rad/s el]; 0: hold */

typedef struct {
    float theta, omega, ts;
} test_hold_t;

MC_ANGLE_SRC_FITS(test_hold_t);

static void hold_init(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *cfg)
{
    test_hold_t *h = (test_hold_t *)(void *)s;
    *h = (test_hold_t){.theta = 0.0f, .omega = 0.0f, .ts = cfg->ts};
}

static void hold_reset(mc_angle_src_state_t *s, float theta, float omega)
{
    test_hold_t *h = (test_hold_t *)(void *)s;
    (void)omega;
    h->theta = mc_wrap_pi(theta);
    h->omega = test_hold_omega;
}

static void hold_step(mc_angle_src_state_t *s, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    test_hold_t *h = (test_hold_t *)(void *)s;
    (void)in;
    out->theta = h->theta;
    out->omega = h->omega;
    h->theta = mc_wrap_pi(h->theta + h->omega * h->ts);   /* the angle of the next sample */
}

static void hold_diag(const mc_angle_src_state_t *s, mc_angle_diag_t *d)
{
    const test_hold_t *h = (const test_hold_t *)(const void *)s;
    *d = (mc_angle_diag_t){.theta_raw = h->theta, .omega_raw = h->omega};
}

const mc_angle_src_desc_t mc_angle_src_test_hold = {
    .name = "test_hold", .needs_injection = false,
    .init = hold_init, .reset = hold_reset, .step = hold_step, .diag = hold_diag,
};

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
    assert_true(mc_param_set_choice(&r->cfg.p, MC_PARAM_angle_src, source, NULL));
    assert_true(mc_param_set_choice(&r->cfg.p, MC_PARAM_est_model, "const", NULL));   /* no map */
    assert_true(mc_param_set_choice(&r->cfg.p, MC_PARAM_catch_on, "off", NULL));   /* straight to RUN */
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

static void enable(rig_t *r, float theta_init)
{
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT, .i_ref = {0.0f, 1.0f},
                              .theta_init = theta_init};
    mc_drive_command(&r->d, &c);
    run(r, (int)r->d.cfg->p.offset_cal_samples + 1);
    assert_int_equal(mc_drive_state(&r->d), MC_STATE_RUN);
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
    assert_int_equal(id, MC_PARAM_angle_src);
    assert_non_null(strstr(mc_param_table[id].choices, "test_hold"));
    assert_float_equal(mc_param_table[id].max, (float)(MC_ANGLE_SRC_COUNT - 1), 0.0f);

    mc_params_t p;
    mc_params_default(&p);
    mc_param_err_t err;
    assert_true(mc_param_set_choice(&p, id, "test_hold", &err));
    assert_int_equal(p.angle_src, MC_ANGLE_SRC_test_hold);
    char buf[32];
    mc_param_choice_text(&p, id, buf, sizeof buf);
    assert_string_equal(buf, "test_hold");
    mc_params_derive(&p);
    assert_true(mc_params_validate(&p, &err));
    /* a source that is not registered is still refused */
    assert_false(mc_param_set_choice(&p, id, "test_hol", &err));
    assert_int_equal(err.kind, MC_PERR_RANGE);
    assert_int_equal(p.angle_src, MC_ANGLE_SRC_test_hold);
    /* and one past the end of the list is out of range */
    p.angle_src = MC_ANGLE_SRC_COUNT;
    assert_false(mc_params_validate(&p, &err));
    assert_int_equal(err.param, MC_PARAM_angle_src);
    assert_int_equal(err.kind, MC_PERR_RANGE);
}

/* The drive runs on it: the controller's angle is the held one, and without needs_injection the
 * drive injects nothing (with injection.kind = sine, the default). */
static void test_drive_runs_with_held_angle(void **st)
{
    (void)st;
    static rig_t r;
    test_hold_omega = 0.0f;
    rig_init(&r, "test_hold");
    assert_ptr_equal(r.d.src, &mc_angle_src_test_hold);
    assert_int_equal(r.d.cfg->p.inj_kind, 1);   /* sine: would inject with an estimator */
    assert_false(r.d.cfg->blk.inject);
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
        assert_float_equal(step, 300.0f * r.d.cfg->p.ts, 1e-5f);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_registry_has_extra_source),
        cmocka_unit_test(test_drive_runs_with_held_angle),
        cmocka_unit_test(test_drive_follows_ramp),
        cmocka_unit_test(test_estimator_source_injects),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
