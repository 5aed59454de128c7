#include "core_test.h"
#include <float.h>
#include "mc/sincos.h"

static void test_exact_points(void **st)
{
    (void)st;
    mc_sincos_t z = mc_sincos(0.0f);
    assert_near(z.s, 0.0, 0.0);
    assert_near(z.c, 1.0, 1e-7);
    mc_sincos_t h = mc_sincos((float)(PI_D / 2));
    assert_near(h.s, 1.0, MC_SINCOS_MAX_ERR);
    assert_near(h.c, 0.0, MC_SINCOS_MAX_ERR);
    mc_sincos_t t = mc_sincos((float)(PI_D / 6));
    assert_near(t.s, 0.5, MC_SINCOS_MAX_ERR);
    assert_near(t.c, sqrt(3.0) / 2, MC_SINCOS_MAX_ERR);
    mc_sincos_t m = mc_sincos((float)(-3 * PI_D / 4));
    assert_near(m.s, -sqrt(0.5), MC_SINCOS_MAX_ERR);
    assert_near(m.c, -sqrt(0.5), MC_SINCOS_MAX_ERR);
}

/* Dense sweep against libm in double: the error figure quoted in sincos.h and docs/core.md */
static void test_sweep_vs_libm(void **st)
{
    (void)st;
    double worst = 0.0, worst_x = 0.0, worst_small = 0.0;
    for (double x = -100.0; x <= 100.0; x += 3.1e-5) {
        float xf = (float)x;
        mc_sincos_t r = mc_sincos(xf);
        double es = fabs((double)r.s - sin((double)xf));
        double ec = fabs((double)r.c - cos((double)xf));
        double e = es > ec ? es : ec;
        if (e > worst) {
            worst = e;
            worst_x = xf;
        }
        if (fabs(x) <= 2.0 * PI_D && e > worst_small) {
            worst_small = e;
        }
    }
    printf("mc_sincos max abs error: %.3g for |theta| <= 2pi, %.3g for |theta| <= 100 (at %.6f)\n",
           worst_small, worst, worst_x);
    assert_true(worst <= (double)MC_SINCOS_MAX_ERR);
    assert_true(100.0 <= (double)MC_SINCOS_RANGE);
}

static void test_large_inputs_bounded(void **st)
{
    (void)st;
    const float xs[] = {1e4f, -5e4f, 60000.0f, 1e6f, -1e9f, 1e20f, FLT_MAX, -FLT_MAX};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
        mc_sincos_t r = mc_sincos(xs[i]);
        assert_true(fabsf(r.s) <= 1.0f + 1e-6f && fabsf(r.c) <= 1.0f + 1e-6f);
        assert_near(r.s * r.s + r.c * r.c, 1.0, 1e-6);
    }
    /* up to 1e4 rad the reduction is still accurate against the float input's exact value */
    for (double x = 1000.0; x <= 10000.0; x += 0.37) {
        float xf = (float)x;
        mc_sincos_t r = mc_sincos(xf);
        assert_near(r.s, sin((double)xf), 2e-6);
        assert_near(r.c, cos((double)xf), 2e-6);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exact_points),
        cmocka_unit_test(test_sweep_vs_libm),
        cmocka_unit_test(test_large_inputs_bounded),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
