/* The angle sources' configuration comparison (mc_angle_src_desc_t.cfg_equal, the drive's test
 * whether a parameter write changed what a running source holds): for the "unop" and "encoder"
 * sources, each parameter the source reads (their headers list them), set alone to another valid
 * value, gives a configuration cfg_equal tells apart, both ways round; the same parameters
 * again, or a parameter the source does not read, give an equal one. */
#include "../mc_test.h"

#include <string.h>

#include "mc/angle_source.h"
#include "mc/drive.h"
#include "mc/params.h"

static mc_drive_built_t g_base, g_other;

typedef struct {
    int id;
    float value;
} change_t;

static const mc_angle_src_desc_t *build(mc_drive_cfg_t *cfg, const char *source, mc_drive_built_t *out)
{
    mc_param_err_t err;
    assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_control_angle_source, source, NULL));
    assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_estimator_model, "const", NULL));
    if (!mc_drive_build(cfg, out, &err)) {
        fail_msg("%s: the build refused the configuration", source);
    }
    const mc_angle_src_desc_t *src = NULL;
    for (int k = 0; k < (int)MC_ANGLE_SRC_COUNT; ++k) {
        if (strcmp(mc_angle_src_get(k)->name, source) == 0) {
            src = mc_angle_src_get(k);
        }
    }
    assert_non_null(src);
    return src;
}

static void check_source(const char *source, const change_t *read, int n_read, const change_t *unread, int n_unread)
{
    mc_drive_cfg_t base;
    mc_drive_cfg_default(&base);
    const mc_angle_src_desc_t *src = build(&base, source, &g_base);
    /* the same parameters built again: equal */
    mc_drive_cfg_t same = base;
    build(&same, source, &g_other);
    assert_true(src->cfg_equal(&g_base.blk.src.cfg, &g_other.blk.src.cfg));
    for (int k = 0; k < n_read + n_unread; ++k) {
        const change_t *c = k < n_read ? &read[k] : &unread[k - n_read];
        mc_drive_cfg_t cfg = base;
        if (!mc_param_set(&cfg.p, c->id, c->value, NULL)) {
            fail_msg("%s: parameter %d refused %g", source, c->id, (double)c->value);
        }
        build(&cfg, source, &g_other);
        const bool ab = src->cfg_equal(&g_base.blk.src.cfg, &g_other.blk.src.cfg);
        const bool ba = src->cfg_equal(&g_other.blk.src.cfg, &g_base.blk.src.cfg);
        assert_true(ab == ba);
        if (ab != (k >= n_read)) {
            fail_msg("%s: parameter %d at %g: cfg_equal %d", source, c->id, (double)c->value, (int)ab);
        }
    }
}

static void test_unop_tells_each_parameter(void **st)
{
    (void)st;
    const change_t read[] = {
        {MC_PARAM_control_ts_s, 2e-4f},
        {MC_PARAM_estimator_iter_max, 6.0f},
        {MC_PARAM_estimator_step_tol, 2e-4f},
        {MC_PARAM_estimator_k1, 0.7f},
        {MC_PARAM_estimator_k2, 120.0f},
        {MC_PARAM_injection_n1_rpm, 450.0f},
        {MC_PARAM_estimator_speed_scale_rpm, 700.0f},
        {MC_PARAM_estimator_mid_sample, 0.0f},
        {MC_PARAM_estimator_reg_predicted, 0.0f},
        {MC_PARAM_estimator_l_adapt_s, 0.02f},
        {MC_PARAM_injection_v1_v, 80.0f},
        {MC_PARAM_injection_f_hz, 600.0f},
        {MC_PARAM_estimator_pll_bw_hz, 40.0f},
        {MC_PARAM_estimator_pll_speed_fc_hz, 250.0f},
        {MC_PARAM_motor_pole_pairs, 4.0f},   /* the speeds in rad/s el (n1, the speed scale) */
    };
    const change_t unread[] = {
        {MC_PARAM_control_encoder_pll_bw_hz, 160.0f},
        {MC_PARAM_hw_encoder_lines, 1024.0f},
    };
    check_source("unop", read, (int)(sizeof read / sizeof read[0]), unread, (int)(sizeof unread / sizeof unread[0]));
}

static void test_encoder_tells_each_parameter(void **st)
{
    (void)st;
    const change_t read[] = {
        {MC_PARAM_motor_pole_pairs, 4.0f},
        {MC_PARAM_hw_encoder_lines, 1024.0f},
        {MC_PARAM_hw_encoder_offset_rad, 0.3f},
        {MC_PARAM_control_ts_s, 2e-4f},
        {MC_PARAM_control_encoder_pll_bw_hz, 160.0f},
        {MC_PARAM_control_encoder_speed_fc_hz, 450.0f},
    };
    const change_t unread[] = {
        {MC_PARAM_estimator_pll_bw_hz, 40.0f},
        {MC_PARAM_estimator_k1, 0.7f},
    };
    check_source("encoder", read, (int)(sizeof read / sizeof read[0]), unread, (int)(sizeof unread / sizeof unread[0]));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unop_tells_each_parameter),
        cmocka_unit_test(test_encoder_tells_each_parameter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
