#include "core_test.h"
#include "mc/angle.h"
#include "mc/pll.h"

/* critically damped (3.9): s^2 + kp s + ki = (s + wn)^2, wn = 2 pi 50 */
#define WN (2.0 * PI_D * 50.0)
static const mc_pll_cfg_t CFG = {.kp = (float)(2.0 * WN), .ki = (float)(WN * WN), .ts = 1e-4f,
                                 .speed_fc_hz = 20.0f};

static void test_ramp_zero_steady_error_and_wrap(void **st)
{
    (void)st;
    mc_pll_t p;
    mc_pll_init(&p, &CFG);
    const double w = 2.0 * PI_D * 80.0;   /* 80 Hz electrical: wraps 80 times a second */
    double worst_late = 0.0;
    for (int k = 1; k <= 5000; ++k) {
        double th = w * k * (double)CFG.ts;
        mc_pll_step(&p, mc_wrap_pi((float)fmod(th, 2.0 * PI_D)), 0.0f);
        assert_true(p.theta >= -MC_PI && p.theta < MC_PI);
        double e = fabs(remainder(th - (double)p.theta, 2.0 * PI_D));
        if (k > 3000) {
            worst_late = fmax(worst_late, e);
        }
    }
    printf("PLL ramp: steady angle error %.3g rad, speed %.4f (true %.4f), filtered %.4f\n",
           worst_late, p.omega, w, p.omega_filt);
    assert_true(worst_late < 1e-4);
    assert_near(p.omega, w, 0.05);
    assert_near(p.omega_filt, w, 0.05);
}

static void test_wrap_across_pi(void **st)
{
    (void)st;
    mc_pll_t p;
    mc_pll_init(&p, &CFG);
    /* start locked just below +pi turning positive: input jumps to -pi, estimate must follow
     * with a small error, not a 2 pi transient */
    mc_pll_reset(&p, 3.1f, 100.0f);
    double th = 3.1;
    for (int k = 0; k < 200; ++k) {
        th += 100.0 * (double)CFG.ts;
        mc_pll_step(&p, mc_wrap_pi((float)th), 0.0f);
        assert_true(fabs(remainder(th - (double)p.theta, 2.0 * PI_D)) < 1e-3);
        assert_near(p.omega, 100.0, 0.5);
    }
    /* and turning negative across -pi */
    mc_pll_reset(&p, -3.1f, -100.0f);
    th = -3.1;
    for (int k = 0; k < 200; ++k) {
        th -= 100.0 * (double)CFG.ts;
        mc_pll_step(&p, mc_wrap_pi((float)th), 0.0f);
        assert_true(fabs(remainder(th - (double)p.theta, 2.0 * PI_D)) < 1e-3);
        assert_near(p.omega, -100.0, 0.5);
    }
}

/* Accelerating input: without feed-forward the type-2 loop lags by a/ki; with the true speed
 * fed forward the lag vanishes. */
static double accel_run(int use_ff, double *late_err)
{
    const double a = 5000.0;   /* rad/s^2 */
    mc_pll_t p;
    mc_pll_init(&p, &CFG);
    double worst = 0.0, last = 0.0;
    for (int k = 1; k <= 3000; ++k) {
        double t = k * (double)CFG.ts;
        double th = 0.5 * a * t * t;
        mc_pll_step(&p, mc_wrap_pi((float)fmod(th, 2.0 * PI_D)), use_ff ? (float)(a * t) : 0.0f);
        double e = remainder(th - (double)p.theta, 2.0 * PI_D);
        worst = fmax(worst, fabs(e));
        last = e;
    }
    *late_err = last;
    return worst;
}

static void test_feedforward_removes_lag(void **st)
{
    (void)st;
    double late_noff, late_ff;
    double worst_noff = accel_run(0, &late_noff);
    double worst_ff = accel_run(1, &late_ff);
    printf("PLL under 5000 rad/s^2: lag without ff %.4f rad (a/ki = %.4f), with ff max %.3g\n",
           late_noff, 5000.0 / (WN * WN), worst_ff);
    assert_near(late_noff, 5000.0 / (WN * WN), 0.003);
    assert_true(worst_noff > 0.045);
    assert_true(worst_ff < 1e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ramp_zero_steady_error_and_wrap),
        cmocka_unit_test(test_wrap_across_pi),
        cmocka_unit_test(test_feedforward_removes_lag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
