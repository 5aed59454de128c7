#include "core_test.h"
#include "mc/svpwm.h"

#define VDC 300.0f

/* Clarke (2.4) of the phase voltages (d - 0.5) vdc, in double: what the duties realise */
static void realised(const mc_duty_t *o, double vdc, double *al, double *be)
{
    double va = (o->a - 0.5) * vdc, vb = (o->b - 0.5) * vdc, vc = (o->c - 0.5) * vdc;
    *al = (2.0 / 3.0) * (va - 0.5 * (vb + vc));
    *be = (vb - vc) / sqrt(3.0);
}

static void test_hand_values(void **st)
{
    (void)st;
    mc_duty_t o;
    mc_svpwm((mc_ab_t){0.0f, 0.0f}, VDC, &o);
    assert_near(o.a, 0.5, 0.0);
    assert_near(o.b, 0.5, 0.0);
    assert_near(o.c, 0.5, 0.0);
    assert_false(o.saturated);
    /* |u| = vdc/sqrt3 along alpha: va = vdc/sqrt3, vb = vc = -vdc/(2 sqrt3), v0 = -vdc/(4 sqrt3)
     * -> d_a = 0.5 + sqrt3/4 = 0.9330127, d_b = d_c = 0.5 - sqrt3/4 = 0.0669873 */
    mc_svpwm((mc_ab_t){VDC / MC_SQRT3, 0.0f}, VDC, &o);
    assert_near(o.a, 0.9330127, 1e-6);
    assert_near(o.b, 0.0669873, 1e-6);
    assert_near(o.c, 0.0669873, 1e-6);
    assert_false(o.saturated);
    /* vertex U1 = 2 vdc / 3 along alpha: exactly on the hexagon, duties (1, 0, 0) */
    mc_svpwm((mc_ab_t){2.0f * VDC / 3.0f, 0.0f}, VDC, &o);
    assert_near(o.a, 1.0, 1e-6);
    assert_near(o.b, 0.0, 1e-6);
    assert_near(o.c, 0.0, 1e-6);
    /* sector reference gives the same by (2.10)-(2.13) */
    mc_svpwm_sector((mc_ab_t){VDC / MC_SQRT3, 0.0f}, VDC, &o);
    assert_near(o.a, 0.9330127, 1e-6);
    assert_near(o.b, 0.0669873, 1e-6);
}

/* min-max injection == sector method, inside and outside the hexagon */
static void test_minmax_equals_sector(void **st)
{
    (void)st;
    double worst = 0.0;
    const double mags[] = {0.0, 0.05, 0.3, 0.6, 0.9, 0.99, 1.0, 1.05, 1.1, 1.1547, 1.3, 2.0, 5.0};
    for (size_t m = 0; m < sizeof mags / sizeof mags[0]; ++m) {
        for (int k = 0; k < 1440; ++k) {
            double th = 2.0 * PI_D * (k + 0.37) / 1440.0;
            double r = mags[m] * VDC / sqrt(3.0);
            mc_ab_t u = {(float)(r * cos(th)), (float)(r * sin(th))};
            mc_duty_t a, b;
            mc_svpwm(u, VDC, &a);
            mc_svpwm_sector(u, VDC, &b);
            double e = fmax(fabs(a.a - b.a), fmax(fabs(a.b - b.b), fabs(a.c - b.c)));
            worst = fmax(worst, e);
            assert_near(e, 0.0, 2e-6);
            if (fabs(mags[m] - 1.1547) > 0.01 && mags[m] != 1.0) {
                assert_int_equal(a.saturated, b.saturated);
            }
        }
    }
    printf("max |duty(min-max) - duty(sector)| = %.3g\n", worst);
}

/* linear up to the inscribed circle in every direction */
static void test_inscribed_circle_linear(void **st)
{
    (void)st;
    for (int k = 0; k < 3600; ++k) {
        double th = 2.0 * PI_D * k / 3600.0;
        float r = VDC / MC_SQRT3;
        mc_ab_t u = {r * (float)cos(th), r * (float)sin(th)};
        mc_duty_t o;
        mc_svpwm(u, VDC, &o);
        assert_false(o.saturated);
        assert_true(o.a >= 0.0f && o.a <= 1.0f && o.b >= 0.0f && o.b <= 1.0f && o.c >= 0.0f &&
                    o.c <= 1.0f);
        double al, be;
        realised(&o, VDC, &al, &be);
        assert_near(al, u.alpha, 1e-4);
        assert_near(be, u.beta, 1e-4);
        assert_near(o.u_real.alpha, u.alpha, 1e-4);
        assert_near(o.u_real.beta, u.beta, 1e-4);
    }
}

/* over-modulation: scaled onto the hexagon keeping the angle; duties realise u_real */
static void test_overmodulation_keeps_angle(void **st)
{
    (void)st;
    double worst_ang = 0.0;
    const double mags[] = {1.02, 1.1, 1.3, 3.0, 100.0};
    for (size_t m = 0; m < sizeof mags / sizeof mags[0]; ++m) {
        for (int k = 0; k < 3600; ++k) {
            double th = 2.0 * PI_D * (k + 0.5) / 3600.0;
            double r = mags[m] * VDC / sqrt(3.0);
            mc_ab_t u = {(float)(r * cos(th)), (float)(r * sin(th))};
            mc_duty_t o;
            mc_svpwm(u, VDC, &o);
            /* the hexagon's apothem is vdc/sqrt3 and its vertex 2vdc/3: past 1.1547 always out */
            double hex = (VDC / sqrt(3.0)) / cos(fmod(th, PI_D / 3.0) - PI_D / 6.0);
            if (r <= hex * (1.0 + 1e-5)) {
                continue;
            }
            assert_true(o.saturated);
            double ang = atan2(o.u_real.beta, o.u_real.alpha);
            double e = fabs(remainder(ang - atan2(u.beta, u.alpha), 2.0 * PI_D));
            worst_ang = fmax(worst_ang, e);
            assert_true(e < 1e-5);
            /* on the boundary: one leg fully on, one fully off */
            double dmax = fmax(o.a, fmax(o.b, o.c)), dmin = fmin(o.a, fmin(o.b, o.c));
            assert_near(dmax - dmin, 1.0, 1e-5);
            assert_near(hypot(o.u_real.alpha, o.u_real.beta), hex, 1e-3);
            double al, be;
            realised(&o, VDC, &al, &be);
            assert_near(al, o.u_real.alpha, 1e-4);
            assert_near(be, o.u_real.beta, 1e-4);
        }
    }
    printf("over-modulation: max angle error of u_real %.3g rad\n", worst_ang);
}

/* mc_svpwm_reach: the hexagon's distance in a direction, what mc_svpwm gives there when asked for
 * more; and (2.14a): a circle of 2/sqrt3 vdc/sqrt3 turned through mc_svpwm keeps a fundamental of
 * (3/pi) ln 3 vdc/sqrt3 (MC_SVPWM_FUND_MAX), a circle of 1 all of it. */
static void test_reach_and_fundamental(void **st)
{
    (void)st;
    assert_near(mc_svpwm_reach((mc_ab_t){1.0f, 0.0f}, VDC), 2.0 * VDC / 3.0, 1e-3);   /* V(100) */
    assert_near(mc_svpwm_reach((mc_ab_t){0.8660254f, 0.5f}, VDC), VDC / sqrt(3.0), 1e-3);   /* a side */
    assert_near(mc_svpwm_reach((mc_ab_t){0.0f, 0.0f}, VDC), VDC / sqrt(3.0), 1e-3);   /* not a unit vector */
    assert_near(mc_svpwm_reach((mc_ab_t){NAN, 0.0f}, VDC), VDC / sqrt(3.0), 1e-3);
    const double mags[2] = {1.0, 2.0 / sqrt(3.0)}, fund[2] = {1.0, 3.0 / PI_D * log(3.0)};
    for (int m = 0; m < 2; ++m) {
        double f = 0.0;
        const int n = 3600;
        for (int k = 0; k < n; ++k) {
            const double th = 2.0 * PI_D * (k + 0.5) / n;
            mc_ab_t u = {(float)(mags[m] * VDC / sqrt(3.0) * cos(th)), (float)(mags[m] * VDC / sqrt(3.0) * sin(th))};
            mc_duty_t o;
            mc_svpwm(u, VDC, &o);
            f += (o.u_real.alpha * cos(th) + o.u_real.beta * sin(th)) / n;   /* the fundamental */
            if (m == 1) {
                const float r = 1.0f / hypotf(u.alpha, u.beta);
                assert_near(hypot(o.u_real.alpha, o.u_real.beta),
                            mc_svpwm_reach((mc_ab_t){u.alpha * r, u.beta * r}, VDC), 2e-3);
            }
        }
        assert_near(f / (VDC / sqrt(3.0)), fund[m], 1e-4);
    }
    assert_near(MC_SVPWM_FUND_MAX, 3.0 / PI_D * log(3.0), 1e-4);
}

static void test_bad_vdc(void **st)
{
    (void)st;
    mc_duty_t o;
    mc_svpwm((mc_ab_t){10.0f, 0.0f}, 0.0f, &o);
    assert_near(o.a, 0.5, 0.0);
    assert_true(o.saturated);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hand_values),
        cmocka_unit_test(test_minmax_equals_sector),
        cmocka_unit_test(test_inscribed_circle_linear),
        cmocka_unit_test(test_overmodulation_keeps_angle),
        cmocka_unit_test(test_reach_and_fundamental),
        cmocka_unit_test(test_bad_vdc),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
