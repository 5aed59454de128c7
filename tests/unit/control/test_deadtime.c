/* Dead-time compensation: sign, magnitude, linear zone, clamp, switch. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mc/deadtime.h"

static void assert_near(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) {
        fail_msg("%.9g != %.9g (tol %.3g)", a, b, tol);
    }
}

/* 1 us dead time in a 100 us period: 0.01 of duty; linear within +-0.5 A */
static const mc_dtc_cfg_t CFG = {1e-6f, 1e-4f, 0.5f, true};

static mc_duty_t duty3(float a, float b, float c)
{
    mc_duty_t d;
    d.a = a;
    d.b = b;
    d.c = c;
    d.u_real.alpha = 0.0f;
    d.u_real.beta = 0.0f;
    d.saturated = false;
    return d;
}

static mc_abc_t abc(float a, float b, float c)
{
    mc_abc_t x;
    x.a = a;
    x.b = b;
    x.c = c;
    return x;
}

static void test_sign_and_magnitude(void **state)
{
    (void)state;
    mc_dtc_t s;
    mc_dtc_init(&s, &CFG);
    mc_duty_t d = duty3(0.5f, 0.5f, 0.5f);
    /* sourcing phase loses voltage in the dead time -> more duty; sinking -> less;
     * a quarter band (0.125 A of 0.5) -> a quarter of the correction */
    mc_dtc_apply(&s, &d, abc(5.0f, -4.875f, -0.125f));
    assert_near(d.a, 0.51, 1e-6);
    assert_near(d.b, 0.49, 1e-6);
    assert_near(d.c, 0.4975, 1e-6);
}

static void test_clamp(void **state)
{
    (void)state;
    mc_dtc_t s;
    mc_dtc_init(&s, &CFG);
    mc_duty_t d = duty3(0.995f, 0.004f, 0.5f);
    mc_dtc_apply(&s, &d, abc(3.0f, -3.0f, 0.0f));
    assert_near(d.a, 1.0, 0.0);
    assert_near(d.b, 0.0, 0.0);
    assert_near(d.c, 0.5, 0.0);   /* zero current: no correction */
}

static void test_disabled(void **state)
{
    (void)state;
    mc_dtc_cfg_t c = CFG;
    c.enable = false;
    mc_dtc_t s;
    mc_dtc_init(&s, &c);
    mc_duty_t d = duty3(0.3f, 0.6f, 0.9f);
    mc_dtc_apply(&s, &d, abc(5.0f, -2.0f, -3.0f));
    assert_near(d.a, 0.3f, 0.0);
    assert_near(d.b, 0.6f, 0.0);
    assert_near(d.c, 0.9f, 0.0);
}

/* Through zero the correction is continuous, odd, and its slope is (t_dead/T)/i_band. */
static void test_smooth_through_zero(void **state)
{
    (void)state;
    mc_dtc_t s;
    mc_dtc_init(&s, &CFG);
    const float di = 1e-3f;
    const double max_step = 0.01 / 0.5 * 1e-3 + 1e-6;
    double prev = -1.0;
    for (int k = -2000; k <= 2000; ++k) {
        float i = (float)k * di;
        mc_duty_t d = duty3(0.5f, 0.5f, 0.5f);
        mc_duty_t m = duty3(0.5f, 0.5f, 0.5f);
        mc_dtc_apply(&s, &d, abc(i, 0.0f, 0.0f));
        mc_dtc_apply(&s, &m, abc(-i, 0.0f, 0.0f));
        double corr = d.a - 0.5;
        assert_near(corr, -(m.a - 0.5), 1e-7);                 /* odd */
        assert_true(fabs(corr) <= 0.01 + 1e-7);
        if (k > -2000) {
            assert_true(corr - prev >= -1e-7);                 /* monotone */
            assert_true(corr - prev <= max_step);              /* no jump anywhere */
        }
        prev = corr;
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sign_and_magnitude),
        cmocka_unit_test(test_clamp),
        cmocka_unit_test(test_disabled),
        cmocka_unit_test(test_smooth_through_zero),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
