/* Speed loop: proportional and integral action, torque limit, decimation, bumpless reset,
 * anti-windup. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mc/speed_ctrl.h"

static void assert_near(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) {
        fail_msg("%.9g != %.9g (tol %.3g)", a, b, tol);
    }
}

static void test_proportional_and_limit(void **state)
{
    (void)state;
    mc_sc_cfg_t c = {0.5f, 0.0f, 1e-3f, 30.0f, 1};
    mc_sc_t s;
    mc_sc_init(&s, &c);
    assert_near(mc_sc_step(&s, 10.0f, 0.0f), 5.0, 1e-6);     /* 0.5 * 10 */
    assert_near(mc_sc_step(&s, 0.0f, 10.0f), -5.0, 1e-6);
    assert_near(mc_sc_step(&s, 200.0f, 0.0f), 30.0, 1e-6);   /* 100 N m clamped */
    assert_near(mc_sc_step(&s, -200.0f, 0.0f), -30.0, 1e-6);
}

static void test_integral_increment(void **state)
{
    (void)state;
    /* ki * ts * err = 2 * 1e-3 * 3 = 6e-3 N m per update */
    mc_sc_cfg_t c = {0.0f, 2.0f, 1e-3f, 30.0f, 1};
    mc_sc_t s;
    mc_sc_init(&s, &c);
    float prev = mc_sc_step(&s, 3.0f, 0.0f);
    for (int k = 0; k < 10; ++k) {
        float t = mc_sc_step(&s, 3.0f, 0.0f);
        assert_near(t - prev, 6e-3, 1e-6);
        prev = t;
    }
    assert_near(prev, 11 * 6e-3, 1e-5);   /* backward-Euler PI: the first update integrates too */
}

static void test_decimation(void **state)
{
    (void)state;
    mc_sc_cfg_t c = {0.5f, 0.0f, 4e-4f, 30.0f, 4};
    mc_sc_t s;
    mc_sc_init(&s, &c);
    /* the first call after reset updates at once */
    assert_near(mc_sc_step(&s, 10.0f, 0.0f), 5.0, 1e-6);
    /* the next three calls hold the value whatever the input */
    assert_near(mc_sc_step(&s, 20.0f, 0.0f), 5.0, 1e-6);
    assert_near(mc_sc_step(&s, 20.0f, 0.0f), 5.0, 1e-6);
    assert_near(mc_sc_step(&s, 20.0f, 0.0f), 5.0, 1e-6);
    /* fifth call: update */
    assert_near(mc_sc_step(&s, 20.0f, 0.0f), 10.0, 1e-6);
    int updates = 0;
    float prev = 10.0f;
    for (int k = 0; k < 40; ++k) {
        float t = mc_sc_step(&s, (float)(k + 1), 0.0f);
        if (t != prev) {
            updates++;
        }
        prev = t;
    }
    assert_int_equal(updates, 10);

    /* decimation < 1 behaves as 1 */
    c.decimation = 0;
    mc_sc_init(&s, &c);
    assert_near(mc_sc_step(&s, 2.0f, 0.0f), 1.0, 1e-6);
    assert_near(mc_sc_step(&s, 4.0f, 0.0f), 2.0, 1e-6);
}

static void test_reset_bumpless(void **state)
{
    (void)state;
    mc_sc_cfg_t c = {0.5f, 20.0f, 1e-3f, 30.0f, 2};
    mc_sc_t s;
    mc_sc_init(&s, &c);
    mc_sc_reset(&s, 12.5f);
    assert_near(s.torque_ref, 12.5, 1e-6);
    assert_near(mc_sc_step(&s, 100.0f, 100.0f), 12.5, 1e-6);   /* zero error: no bump */
    mc_sc_reset(&s, 99.0f);                                    /* clamped to the limit */
    assert_near(mc_sc_step(&s, 100.0f, 100.0f), 30.0, 1e-6);
    /* braking: a preload below -limit is clamped too, and the integrator holds -limit, not the
     * excess: a small positive error moves the torque off the limit at once */
    mc_sc_reset(&s, -99.0f);
    assert_near(s.torque_ref, -30.0, 1e-6);
    assert_near(mc_sc_step(&s, 100.0f, 100.0f), -30.0, 1e-6);
    mc_sc_reset(&s, -99.0f);
    assert_near(mc_sc_step(&s, 102.0f, 100.0f), -30.0 + 0.5 * 2.0 + 20.0 * 1e-3 * 2.0, 1e-5);
}

static void test_antiwindup(void **state)
{
    (void)state;
    mc_sc_cfg_t c = {0.2f, 5.0f, 1e-3f, 10.0f, 1};
    mc_sc_t s;
    mc_sc_init(&s, &c);
    for (int k = 0; k < 10000; ++k) {   /* 10 s of a 100 rad/s error: limited throughout */
        assert_near(mc_sc_step(&s, 100.0f, 0.0f), 10.0, 1e-6);
    }
    assert_true(s.pi.integ <= 10.0f);
    /* overspeed by 60 rad/s: P alone asks -12 N m, so it must leave +10 at once */
    float t = mc_sc_step(&s, 100.0f, 160.0f);
    assert_true(t < 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_proportional_and_limit),
        cmocka_unit_test(test_integral_increment),
        cmocka_unit_test(test_decimation),
        cmocka_unit_test(test_reset_bumpless),
        cmocka_unit_test(test_antiwindup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
