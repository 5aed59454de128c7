#include "core_test.h"
#include "mc/pi.h"

static const mc_pi_cfg_t CFG = {.kp = 2.0f, .ki = 100.0f, .ts = 1e-3f, .out_min = -10.0f,
                                .out_max = 10.0f};

static void test_step_response_by_hand(void **st)
{
    (void)st;
    mc_pi_t pi;
    mc_pi_init(&pi, &CFG);
    /* err = 1: integrator gains ki ts = 0.1 per step (backward Euler), out(n) = 2 + 0.1 n */
    assert_near(mc_pi_step(&pi, 1.0f, 0.0f), 2.1, 1e-6);
    assert_near(mc_pi_step(&pi, 1.0f, 0.0f), 2.2, 1e-6);
    for (int n = 3; n <= 10; ++n) {
        (void)mc_pi_step(&pi, 1.0f, 0.0f);
    }
    assert_near(pi.integ, 1.0, 1e-5);
    /* feed-forward adds straight to the output: 0.5 + 2 * 0 + 1.0 */
    assert_near(mc_pi_step(&pi, 0.0f, 0.5f), 1.5, 1e-5);
    assert_false(pi.saturated);
    /* after 80 more steps: 2 + 0.1 * 90 = 11 -> clamped to 10 */
    float u = 0.0f;
    for (int n = 0; n < 80; ++n) {
        u = mc_pi_step(&pi, 1.0f, 0.0f);
    }
    assert_near(u, 10.0, 0.0);
    assert_true(pi.saturated);
    mc_pi_reset(&pi, 0.25f);
    assert_near(pi.integ, 0.25, 0.0);
    assert_false(pi.saturated);
}

/* Integrator does not wind up while the output is saturated: recovery is immediate. */
static void test_windup_recovery(void **st)
{
    (void)st;
    mc_pi_t pi;
    mc_pi_init(&pi, &CFG);
    /* err = 0.5: P = 1, I grows 0.05/step until 1 + I reaches 10, i.e. I = 9 after 180 steps */
    for (int n = 0; n < 2000; ++n) {
        (void)mc_pi_step(&pi, 0.5f, 0.0f);
    }
    assert_true(pi.saturated);
    assert_near(pi.integ, 9.0, 1e-5);
    /* error reverses: P = -1, I = 9 - 0.05 -> 7.95, out of saturation on the first step */
    float u = mc_pi_step(&pi, -0.5f, 0.0f);
    assert_near(u, 7.95, 1e-4);
    assert_false(pi.saturated);
    /* zero crossing after about (9 - 1) / 0.05 = 160 steps; a wound-up integrator (2000 steps
     * of 0.05 = 100) would need 2000 */
    int n = 1;
    while (u > 0.0f && n < 5000) {
        u = mc_pi_step(&pi, -0.5f, 0.0f);
        ++n;
    }
    assert_true(n >= 155 && n <= 165);

    /* a large error saturates by P alone: the integrator does not move at all */
    mc_pi_reset(&pi, 0.0f);
    for (int k = 0; k < 100; ++k) {
        assert_near(mc_pi_step(&pi, 100.0f, 0.0f), 10.0, 0.0);
    }
    assert_near(pi.integ, 0.0, 0.0);
    assert_near(mc_pi_step(&pi, -1.0f, 0.0f), -2.1, 1e-6);
}

static void test_limits_per_call_and_clamp(void **st)
{
    (void)st;
    mc_pi_t pi;
    mc_pi_init(&pi, &CFG);
    mc_pi_reset(&pi, 8.0f);
    /* the limit shrinks (e.g. less voltage left for this axis): integrator clamped to it */
    float u = mc_pi_step_lim(&pi, 0.0f, 0.0f, -2.0f, 2.0f);
    assert_near(u, 2.0, 0.0);
    assert_near(pi.integ, 2.0, 0.0);
    /* negative side */
    u = mc_pi_step_lim(&pi, -50.0f, 0.0f, -3.0f, 3.0f);
    assert_near(u, -3.0, 0.0);
    assert_true(pi.saturated);
    /* inverted limits collapse to their midpoint instead of flipping the sign */
    u = mc_pi_step_lim(&pi, 1.0f, 0.0f, 1.0f, -1.0f);
    assert_near(u, 0.0, 0.0);
}

/* With a feed-forward: a limit that shrinks while the integrator is charged leaves no excess
 * behind (ff + I lands on the limit), so the output leaves the limit on the first step of a
 * reversed error; and the feed-forward alone never drives the integrator across zero. */
static void test_shrinking_limit_with_feedforward(void **st)
{
    (void)st;
    mc_pi_t pi;
    mc_pi_init(&pi, &CFG);
    mc_pi_reset(&pi, 3.9f);
    float u = mc_pi_step_lim(&pi, 0.0f, 6.0f, -8.0f, 8.0f);  /* ff + I = 9.9 > 8 */
    assert_near(u, 8.0, 0.0);
    assert_near(pi.integ, 2.0, 1e-6);
    /* err = -0.1: P = -0.2, I = 2 - 0.01: out of the limit at once (7.79) */
    u = mc_pi_step_lim(&pi, -0.1f, 6.0f, -8.0f, 8.0f);
    assert_near(u, 7.79, 1e-5);
    assert_false(pi.saturated);
    /* a feed-forward beyond the limit: the output sits on the limit, the integrator keeps its
     * sign (it is only emptied, down to 0) */
    mc_pi_reset(&pi, 1.5f);
    u = mc_pi_step_lim(&pi, 0.0f, 12.0f, -10.0f, 10.0f);
    assert_near(u, 10.0, 0.0);
    assert_near(pi.integ, 0.0, 0.0);
    /* whatever its size: a disturbance estimate of a few tens of mV stays as one of volts */
    const float held[] = {-1.5f, -0.5f, -0.02f};
    for (int k = 0; k < 3; ++k) {
        mc_pi_reset(&pi, held[k]);
        u = mc_pi_step_lim(&pi, 0.0f, 12.0f, -10.0f, 10.0f);
        assert_near(u, 10.0, 0.0);
        assert_near(pi.integ, held[k], 0.0);
    }
    /* negative side, mirrored */
    mc_pi_reset(&pi, -3.9f);
    u = mc_pi_step_lim(&pi, 0.0f, -6.0f, -8.0f, 8.0f);
    assert_near(u, -8.0, 0.0);
    assert_near(pi.integ, -2.0, 1e-6);
    /* a large negative feed-forward: the integrator may exceed hi itself so that the output
     * can still reach the upper limit (the old clamp to [lo, hi] stopped it at hi) */
    mc_pi_reset(&pi, 0.0f);
    for (int k = 0; k < 4000; ++k) {
        u = mc_pi_step_lim(&pi, 0.5f, -5.0f, -10.0f, 10.0f);
    }
    assert_near(u, 10.0, 1e-5);
    assert_true(pi.integ > 10.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step_response_by_hand),
        cmocka_unit_test(test_windup_recovery),
        cmocka_unit_test(test_limits_per_call_and_clamp),
        cmocka_unit_test(test_shrinking_limit_with_feedforward),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
