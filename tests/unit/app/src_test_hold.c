/* A test-only angle source, "test_hold": what a new source is, in one file plus its registration
 * line (mc/angle_source.h; here the line comes through the MC_ANGLE_SOURCES_EXTRA hook on the
 * compiler's command line, tests/unit/app/CMakeLists.txt). It has no rows in the parameter table:
 * it reads only control.ts_s and protection.overspeed_rpm, and its ramp speed from a test global.
 *
 * It holds the angle it is reset to (the one handed over with the enable command,
 * startup.init_pos = given) at speed 0 or, with test_hold_omega set, ramps from it at that fixed
 * electrical speed. It declares itself an estimator that needs no injection, with loss-of-lock
 * checks, and needs the flux map with estimator.model = fluxmap: the drive's checks follow those
 * capabilities (tests/unit/app/test_angle_source_extra.c), not needs_injection. */
#include "src_test_hold.h"
#include "mc/angle.h"
#include "mc/angle_source.h"
#include "mc/params.h"

float test_hold_omega = 0.0f;
float test_hold_raw_offset = 0.0f;
mc_angle_in_t test_hold_in;
uint32_t test_hold_steps = 0u;

typedef struct {
    float ts, omega;   /* [s], [rad/s el] */
} test_hold_cfg_t;

typedef struct {
    test_hold_cfg_t cfg;
    float theta, omega;
} test_hold_t;

MC_ANGLE_SRC_CFG_FITS(test_hold_cfg_t);
MC_ANGLE_SRC_FITS(test_hold_t);

static bool hold_build(const mc_params_t *p, float rs, const mc_flux_model_t *model, mc_angle_src_cfg_t *cfg,
                       mc_param_err_t *err)
{
    (void)rs;
    (void)model;
    /* a ramp the over-speed detector would trip on is refused with the configuration */
    const float overspeed = p->protection_overspeed_rpm * (MC_2PI / 60.0f) * (float)p->motor_pole_pairs;
    if (!(test_hold_omega < overspeed && -test_hold_omega < overspeed)) {
        return mc_param_fail(err, MC_PERR_CROSS, MC_PARAM_protection_overspeed_rpm, p->protection_overspeed_rpm,
                             "test_hold's ramp must stay below the over-speed limit");
    }
    *cfg = (mc_angle_src_cfg_t){0};
    *(test_hold_cfg_t *)(void *)cfg = (test_hold_cfg_t){.ts = p->control_ts_s, .omega = test_hold_omega};
    return true;
}

static void hold_init(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *cfg)
{
    test_hold_t *h = (test_hold_t *)(void *)s;
    *h = (test_hold_t){.cfg = *(const test_hold_cfg_t *)(const void *)cfg, .theta = 0.0f, .omega = 0.0f};
}

static void hold_reset(mc_angle_src_state_t *s, float theta, float omega)
{
    test_hold_t *h = (test_hold_t *)(void *)s;
    (void)omega;
    h->theta = mc_wrap_pi(theta);
    h->omega = h->cfg.omega;
}

static void hold_step(mc_angle_src_state_t *s, const mc_angle_in_t *in, mc_angle_out_t *out)
{
    test_hold_t *h = (test_hold_t *)(void *)s;
    test_hold_in = *in;   /* for the tests: what the drive hands a source */
    test_hold_steps++;
    out->theta = h->theta;
    out->omega = h->omega;
    h->theta = mc_wrap_pi(h->theta + h->omega * h->cfg.ts);   /* the angle of the next sample */
}

static void hold_diag(const mc_angle_src_state_t *s, mc_angle_diag_t *d)
{
    const test_hold_t *h = (const test_hold_t *)(const void *)s;
    *d = (mc_angle_diag_t){.theta_raw = h->theta, .omega_raw = h->omega + test_hold_raw_offset};
}

static void hold_cfg_of(const mc_angle_src_state_t *s, mc_angle_src_cfg_t *cfg)
{
    *cfg = (mc_angle_src_cfg_t){0};
    *(test_hold_cfg_t *)(void *)cfg = ((const test_hold_t *)(const void *)s)->cfg;
}

static bool hold_cfg_equal(const mc_angle_src_cfg_t *cfg_a, const mc_angle_src_cfg_t *cfg_b)
{
    const test_hold_cfg_t *a = (const test_hold_cfg_t *)(const void *)cfg_a;
    const test_hold_cfg_t *b = (const test_hold_cfg_t *)(const void *)cfg_b;
    return a->ts == b->ts && a->omega == b->omega;
}

const mc_angle_src_desc_t mc_angle_src_test_hold = {
    .name = "test_hold", .cls = MC_ANGLE_ESTIMATOR,
    .needs_injection = false, .lock_checks = true, .map_models = 1u << 1,   /* estimator.model = fluxmap */
    .build = hold_build, .init = hold_init, .retune = 0, .reset = hold_reset, .step = hold_step,
    .diag = hold_diag, .cfg_of = hold_cfg_of, .cfg_equal = hold_cfg_equal,
};
