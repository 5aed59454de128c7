/* The estimator model's checks of mc_drive_build (drive_config.c): a flux map whose grid does not
 * fit the table is refused as a model error naming estimator.model and the offending count
 * (n_d if it is the bad one, else n_q), at the grid's edges 2 and MC_FLUX_MAP_MAX; its steps,
 * origin and values; a model value outside its motor entry's range names that entry. */
#include <math.h>
#include <string.h>

#include "../mc_test.h"
#include "mc/drive.h"

static mc_flux_map_t map;

/* A linear map (the motor's own Ld, Lq, psi_pm) on an n_d x n_q grid over +-20 A. */
static void linear_map(int n_d, int n_q)
{
    memset(&map, 0, sizeof map);
    map.n_d = n_d;
    map.n_q = n_q;
    map.id0 = -20.0f;
    map.iq0 = -20.0f;
    map.did = n_d > 1 ? 40.0f / (float)(n_d - 1) : 1.0f;
    map.diq = n_q > 1 ? 40.0f / (float)(n_q - 1) : 1.0f;
    for (int j = 0; j < n_d && j < MC_FLUX_MAP_MAX; ++j) {
        for (int k = 0; k < n_q && k < MC_FLUX_MAP_MAX; ++k) {
            map.psi_d[j * n_q + k] = 0.34305f + 10.5e-3f * (map.id0 + (float)j * map.did);
            map.psi_q[j * n_q + k] = 12.9e-3f * (map.iq0 + (float)k * map.diq);
        }
    }
}

static bool build(mc_param_err_t *err)
{
    static mc_drive_cfg_t cfg;
    static mc_drive_built_t out;
    mc_drive_cfg_default(&cfg);
    cfg.est.map = &map;
    memset(err, 0, sizeof *err);
    return mc_drive_build(&cfg, &out, err);
}

static void expect_model_error(int param, float value)
{
    mc_param_err_t err;
    assert_false(build(&err));
    assert_int_equal(err.kind, MC_PERR_MODEL);
    assert_int_equal(err.param, param);
    if (!(err.value == value)) {
        fail_msg("reported value %g, want %g", (double)err.value, (double)value);
    }
    assert_non_null(err.text);
}

static void test_grid_counts(void **state)
{
    (void)state;
    mc_param_err_t err;
    linear_map(2, 2);
    assert_true(build(&err));
    linear_map(MC_FLUX_MAP_MAX, MC_FLUX_MAP_MAX);
    assert_true(build(&err));
    linear_map(5, 7);
    assert_true(build(&err));
    /* the bad count is the one reported */
    static const int bad[] = {1, 0, -3, MC_FLUX_MAP_MAX + 1, 1000};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        linear_map(5, 7);
        map.n_d = bad[k];
        expect_model_error(MC_PARAM_estimator_model, (float)bad[k]);
        linear_map(5, 7);
        map.n_q = bad[k];
        expect_model_error(MC_PARAM_estimator_model, (float)bad[k]);
    }
    /* both bad: n_d's */
    linear_map(5, 7);
    map.n_d = 50;
    map.n_q = 60;
    expect_model_error(MC_PARAM_estimator_model, 50.0f);
}

static void test_grid_steps_and_values(void **state)
{
    (void)state;
    linear_map(5, 7);
    map.did = 0.0f;
    expect_model_error(MC_PARAM_estimator_model, 0.0f);
    linear_map(5, 7);
    map.diq = -1.0f;
    expect_model_error(MC_PARAM_estimator_model, map.did);
    linear_map(5, 7);
    map.iq0 = NAN;
    expect_model_error(MC_PARAM_estimator_model, map.did);
    linear_map(5, 7);
    map.diq = INFINITY;
    expect_model_error(MC_PARAM_estimator_model, map.did);
    linear_map(5, 7);
    map.psi_d[5 * 7 - 1] = 100.5f;   /* the last value */
    expect_model_error(MC_PARAM_estimator_model, 100.5f);
    linear_map(5, 7);
    map.psi_q[0] = -101.0f;
    expect_model_error(MC_PARAM_estimator_model, map.psi_d[0]);
    linear_map(5, 7);
    map.psi_d[3] = 100.0f;   /* at the bound */
    mc_param_err_t err;
    assert_true(build(&err));
}

/* A model value given for the estimator is checked against its motor entry's range. */
static void test_model_values(void **state)
{
    (void)state;
    static mc_drive_cfg_t cfg;
    static mc_drive_built_t out;
    mc_param_err_t err;
    mc_drive_cfg_default(&cfg);
    cfg.est.lq = 20.0f;   /* motor.lq_h: at most 10 H */
    assert_false(mc_drive_build(&cfg, &out, &err));
    assert_int_equal(err.kind, MC_PERR_MODEL);
    assert_int_equal(err.param, MC_PARAM_motor_lq_h);
    assert_true(err.value == 20.0f);
    mc_drive_cfg_default(&cfg);
    cfg.est.ld = 10.0f;   /* the range's end */
    assert_true(mc_drive_build(&cfg, &out, &err));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_counts),
        cmocka_unit_test(test_grid_steps_and_values),
        cmocka_unit_test(test_model_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
