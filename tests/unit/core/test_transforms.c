#include "core_test.h"
#include "mc/transforms.h"

static void test_clarke_hand_values(void **st)
{
    (void)st;
    /* (2.4): a = 1, b = c = -1/2 -> alpha = 2/3 (1 + 1/2) = 1, beta = 0 */
    mc_ab_t y = mc_clarke((mc_abc_t){1.0f, -0.5f, -0.5f});
    assert_near(y.alpha, 1.0, 1e-7);
    assert_near(y.beta, 0.0, 1e-7);
    /* b = -c = sqrt(3)/2 -> beta = (2/3)(sqrt(3)/2)(sqrt(3)) = 1 */
    y = mc_clarke((mc_abc_t){0.0f, 0.8660254f, -0.8660254f});
    assert_near(y.alpha, 0.0, 1e-7);
    assert_near(y.beta, 1.0, 1e-6);
    /* a zero-sequence component does not appear in alpha-beta */
    y = mc_clarke((mc_abc_t){5.0f, 5.0f, 5.0f});
    assert_near(y.alpha, 0.0, 1e-6);
    assert_near(y.beta, 0.0, 1e-6);
    /* two sensors: a = 1, b = 0 (c = -1) -> alpha = 1, beta = 1/sqrt(3) */
    y = mc_clarke2(1.0f, 0.0f);
    assert_near(y.alpha, 1.0, 0.0);
    assert_near(y.beta, 1.0 / sqrt(3.0), 1e-7);
}

static void test_amplitude_invariant_sweep(void **st)
{
    (void)st;
    const double amp = 13.29;
    for (int k = 0; k < 3600; ++k) {
        double th = 2.0 * PI_D * k / 3600.0;
        mc_abc_t x = {(float)(amp * cos(th)), (float)(amp * cos(th - 2.0 * PI_D / 3.0)),
                      (float)(amp * cos(th + 2.0 * PI_D / 3.0))};
        mc_ab_t y = mc_clarke(x);
        assert_near(y.alpha, amp * cos(th), 1e-5);
        assert_near(y.beta, amp * sin(th), 1e-5);
        mc_ab_t y2 = mc_clarke2(x.a, x.b);
        assert_near(y2.alpha, y.alpha, 1e-5);
        assert_near(y2.beta, y.beta, 1e-5);
        mc_abc_t z = mc_clarke_inv(y);
        assert_near(z.a, x.a, 1e-5);
        assert_near(z.b, x.b, 1e-5);
        assert_near(z.c, x.c, 1e-5);
    }
}

static void test_park_hand_values(void **st)
{
    (void)st;
    /* (2.5) at theta = pi/2 (s = 1, c = 0): d = beta, q = -alpha */
    mc_dq_t d = mc_park((mc_ab_t){1.0f, 0.0f}, (mc_sincos_t){1.0f, 0.0f});
    assert_near(d.d, 0.0, 0.0);
    assert_near(d.q, -1.0, 0.0);
    /* theta = pi/6, (alpha, beta) = (2, 1): d = 2 cos + sin = sqrt3 + 1/2, q = -1 + sqrt3/2 */
    mc_sincos_t sc = {0.5f, 0.8660254f};
    d = mc_park((mc_ab_t){2.0f, 1.0f}, sc);
    assert_near(d.d, sqrt(3.0) + 0.5, 1e-6);
    assert_near(d.q, -1.0 + sqrt(3.0) / 2.0, 1e-6);
    mc_ab_t b = mc_park_inv(d, sc);
    assert_near(b.alpha, 2.0, 1e-6);
    assert_near(b.beta, 1.0, 1e-6);
}

static void test_park_rotating_vector(void **st)
{
    (void)st;
    for (int k = 0; k < 3600; ++k) {
        double th = -PI_D + 2.0 * PI_D * k / 3600.0;
        mc_sincos_t sc = {(float)sin(th), (float)cos(th)};
        /* a vector at angle th + 0.3 with length 5 is (5 cos 0.3, 5 sin 0.3) in that frame */
        mc_ab_t x = {(float)(5.0 * cos(th + 0.3)), (float)(5.0 * sin(th + 0.3))};
        mc_dq_t d = mc_park(x, sc);
        assert_near(d.d, 5.0 * cos(0.3), 2e-6);
        assert_near(d.q, 5.0 * sin(0.3), 2e-6);
        mc_ab_t y = mc_park_inv(d, sc);
        assert_near(y.alpha, x.alpha, 2e-6);
        assert_near(y.beta, x.beta, 2e-6);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clarke_hand_values),
        cmocka_unit_test(test_amplitude_invariant_sweep),
        cmocka_unit_test(test_park_hand_values),
        cmocka_unit_test(test_park_rotating_vector),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
