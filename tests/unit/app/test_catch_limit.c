/* The flying-start catch's current limit at configuration (drive_config.c, build_catch): its
 * shortest pulse is one V(000) period, whose current at speed w is psi |((cos wTs - 1) / Ld,
 * sin wTs / Lq)| by (C.1) of mc/catch.h. Where that exceeds 1.1 x control.i_max_a below the
 * generation speed Vdc / (sqrt3 psi), the build reports the speed the catch still keeps it at
 * (w_limit) and the longest period that would keep it everywhere (ts_cover); else both 0. */
#include <string.h>

#include "../mc_test.h"
#include "mc/drive.h"

static mc_flux_map_t map;

typedef struct {
    double ld, lq, psi, i_rated, vdc, ts;
    int p;
} motor_t;

/* siemens-1ft7044-spm on its 8 kHz (presets/): 10 A per period at its base speed, 8.06 A rated */
static const motor_t SIEMENS = {4.2e-3, 4.2e-3, 0.14815, 8.06, 600.0, 125e-6, 3};
/* the thesis motor (the table's defaults): 1.2 A per period at its base speed */
static const motor_t SUN = {10.5e-3, 12.9e-3, 0.34305, 13.29, 540.0, 100e-6, 5};

static void linear_map(const motor_t *m)
{
    memset(&map, 0, sizeof map);
    map.n_d = map.n_q = 5;
    map.id0 = map.iq0 = (float)(-2.0 * m->i_rated);
    map.did = map.diq = (float)(m->i_rated);
    for (int j = 0; j < 5; ++j) {
        for (int k = 0; k < 5; ++k) {
            map.psi_d[j * 5 + k] = (float)(m->psi + m->ld * (map.id0 + (float)j * map.did));
            map.psi_q[j * 5 + k] = (float)(m->lq * (map.iq0 + (float)k * map.diq));
        }
    }
}

static void set(mc_params_t *p, int id, double v)
{
    mc_param_err_t err;
    if (!mc_param_set(p, id, (float)v, &err)) {
        fail_msg("param %d = %g refused: %s", id, v, err.text ? err.text : "");
    }
}

static const mc_catch_cfg_t *build(const motor_t *m, double ts)
{
    static mc_drive_cfg_t cfg;
    static mc_drive_built_t out;
    mc_drive_cfg_default(&cfg);
    set(&cfg.p, MC_PARAM_motor_ld_h, m->ld);
    set(&cfg.p, MC_PARAM_motor_lq_h, m->lq);
    set(&cfg.p, MC_PARAM_motor_psi_pm_wb, m->psi);
    set(&cfg.p, MC_PARAM_motor_i_rated_a, m->i_rated);
    set(&cfg.p, MC_PARAM_motor_pole_pairs, m->p);
    set(&cfg.p, MC_PARAM_hw_vdc_span_v, 2.0 * m->vdc);   /* above the 1.5 x over-voltage trip */
    set(&cfg.p, MC_PARAM_hw_vdc_nominal_v, m->vdc);
    set(&cfg.p, MC_PARAM_control_ts_s, ts);
    linear_map(m);
    cfg.est.map = &map;
    mc_param_err_t err;
    memset(&err, 0, sizeof err);
    if (!mc_drive_build(&cfg, &out, &err)) {
        fail_msg("build refused: param %d, %s", err.param, err.text ? err.text : "");
    }
    return &out.blk.flying;
}

/* (C.1): one V(000) period from i = 0 at w [A] */
static double i1(const motor_t *m, double w, double ts)
{
    const double dl = w * ts;
    return m->psi * hypot((cos(dl) - 1.0) / m->ld, sin(dl) / m->lq);
}

static void test_siemens_limited(void **state)
{
    (void)state;
    const motor_t *m = &SIEMENS;
    const mc_catch_cfg_t *c = build(m, m->ts);
    const double w_ug = m->vdc / (sqrt(3.0) * m->psi);
    /* 6417 rpm (the generation speed is 7443): exactly 1.1 x 8.06 A there */
    assert_true(c->w_limit > 0.0f && (double)c->w_limit < w_ug);
    assert_near(i1(m, (double)c->w_limit, m->ts), 1.1 * m->i_rated, 1e-3 * m->i_rated);
    assert_near((double)c->w_limit * 60.0 / (2.0 * PI_D * m->p), 6417.0, 5.0);
    /* the period that covers every speed up to the generation speed, and there no report */
    assert_near(i1(m, w_ug, (double)c->ts_cover), 1.1 * m->i_rated, 1e-3 * m->i_rated);
    const mc_catch_cfg_t *d = build(m, 0.99 * (double)c->ts_cover);
    assert_true(d->w_limit == 0.0f && d->ts_cover == 0.0f);
}

static void test_sun_unlimited(void **state)
{
    (void)state;
    const mc_catch_cfg_t *c = build(&SUN, SUN.ts);
    assert_true(c->w_limit == 0.0f && c->ts_cover == 0.0f);
    /* at 2 kHz too: 12.1 A per period at its generation speed, 1.1 x 13.29 A = 14.6 A */
    c = build(&SUN, 500e-6);
    assert_true(c->w_limit == 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_siemens_limited),
        cmocka_unit_test(test_sun_unlimited),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
