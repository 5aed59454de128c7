#include "core_test.h"
#include <float.h>
#include <string.h>
#include "mc/angle.h"

/* reference: nearest multiple of 2 pi removed, in double */
static double ref_wrap(double x)
{
    return x - 2.0 * PI_D * floor((x + PI_D) / (2.0 * PI_D));
}

static void test_known_values(void **st)
{
    (void)st;
    assert_near(mc_wrap_pi(0.0f), 0.0, 0.0);
    assert_near(mc_wrap_pi(1.0f), 1.0, 0.0);
    assert_near(mc_wrap_pi((float)(1.5 * PI_D)), -0.5 * PI_D, 1e-6);
    assert_near(mc_wrap_pi((float)(-1.5 * PI_D)), 0.5 * PI_D, 1e-6);
    assert_near(mc_wrap_pi(7.0f), 7.0 - 2.0 * PI_D, 1e-6);
    assert_near(mc_wrap_pi(-7.0f), -7.0 + 2.0 * PI_D, 1e-6);
    /* 100 - 16 * 2 pi by hand: -0.530964914873 */
    assert_near(mc_wrap_pi(100.0f), -0.530964914873, 1e-6);
    /* +pi maps to -pi: the interval is half open */
    assert_true(mc_wrap_pi(MC_PI) < 0.0f);
    assert_near(mc_wrap_pi(MC_PI), -PI_D, 1e-6);
    /* float MC_PI is above true pi, so -MC_PI lies below -pi and wraps to just under +pi */
    assert_near(mc_wrap_pi(-MC_PI), PI_D, 1e-6);
    assert_near(mc_wrap_2pi(-0.1f), 2.0 * PI_D - 0.1, 1e-6);
    assert_near(mc_wrap_2pi(7.0f), 7.0 - 2.0 * PI_D, 1e-6);
}

static void test_range_and_accuracy(void **st)
{
    (void)st;
    double worst = 0.0;
    for (double x = -1000.0; x <= 1000.0; x += 0.001237) {
        float xf = (float)x;
        float r = mc_wrap_pi(xf);
        assert_true(r >= -MC_PI && r < MC_PI);
        double ref = ref_wrap((double)xf);
        double e = fabs(remainder((double)r - ref, 2.0 * PI_D));
        if (e > worst) {
            worst = e;
        }
        float r2 = mc_wrap_2pi(xf);
        assert_true(r2 >= 0.0f && r2 < MC_2PI);
    }
    printf("mc_wrap_pi max error over |x| <= 1000: %.3g rad\n", worst);
    assert_true(worst < 1e-6);
}

static void test_huge_inputs_stay_in_range(void **st)
{
    (void)st;
    const float xs[] = {1e5f, -1e5f, 123456.7f, 1e6f, -3e7f, 1e20f, -1e30f, FLT_MAX, -FLT_MAX,
                        1e-30f, -1e-30f, -0.0f};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
        float r = mc_wrap_pi(xs[i]);
        assert_true(r >= -MC_PI && r < MC_PI);
        float r2 = mc_wrap_2pi(xs[i]);
        assert_true(r2 >= 0.0f && r2 < MC_2PI);
    }
    /* seams: values just below/above odd multiples of pi */
    for (int k = -50; k <= 50; k += 2) {
        float x = (float)((k + 1) * PI_D);
        for (int j = -3; j <= 3; ++j) {
            float y = nextafterf(x, (j < 0) ? -INFINITY : INFINITY);
            float r = mc_wrap_pi(y);
            assert_true(r >= -MC_PI && r < MC_PI);
            x = y;
        }
    }
}

/* The general path of mc_wrap_pi (nearest turn count, Cody-Waite 2 pi split), which the fast
 * paths for |x| < 3 pi must reproduce bit for bit. */
static float general_wrap(float x)
{
    const float hi = 6.28125f;
    const float lo = 1.9353071795864769e-3f;
    const float y = x * 0.15915494309189535f;
    const float k = (float)(int32_t)(y + ((y >= 0.0f) ? 0.5f : -0.5f));
    float r = (x - k * hi) - k * lo;
    if (r >= MC_PI) {
        r -= MC_2PI;
    } else if (r < -MC_PI) {
        r += MC_2PI;
    }
    return r;
}

static float float_from_bits(uint32_t b)
{
    float x;
    memcpy(&x, &b, sizeof x);
    return x;
}

static void check_same_as_general(float x)
{
    const float r = mc_wrap_pi(x);
    const float g = general_wrap(x);
    if (memcmp(&r, &g, sizeof r) != 0) {
        fail_msg("mc_wrap_pi(%.9g) = %.9g, general path %.9g", (double)x, (double)r, (double)g);
    }
}

static void test_fast_paths_match_general(void **st)
{
    (void)st;
    /* a sparse sweep of all float bit patterns up to |x| = 20 (both signs, subnormals included) */
    const uint32_t top = 0x41a00000u;   /* 20.0f */
    for (uint32_t b = 0u; b <= top; b += 97u) {
        check_same_as_general(float_from_bits(b));
        check_same_as_general(float_from_bits(b | 0x80000000u));
    }
    /* every float within 4096 ulps of the path boundaries +-pi, +-3 pi */
    const float edges[] = {MC_PI, -MC_PI, 9.42477796076937972f, -9.42477796076937972f};
    for (size_t e = 0; e < sizeof edges / sizeof edges[0]; ++e) {
        float up = edges[e];
        float dn = edges[e];
        for (int j = 0; j < 4096; ++j) {
            check_same_as_general(up);
            check_same_as_general(dn);
            up = nextafterf(up, INFINITY);
            dn = nextafterf(dn, -INFINITY);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_values),
        cmocka_unit_test(test_range_and_accuracy),
        cmocka_unit_test(test_huge_inputs_stay_in_range),
        cmocka_unit_test(test_fast_paths_match_general),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
