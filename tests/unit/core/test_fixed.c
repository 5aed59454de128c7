#include "core_test.h"
#include "mc/fixed.h"
#include "mc/pi.h"
#include "mc/sincos.h"
#include "mc/svpwm.h"
#include "mc/transforms.h"

#define Q15 32768.0
#define Q31 2147483648.0

/* deterministic pseudo-random values in [-r, r] */
static uint32_t rng_state = 12345u;
static double rnd(double r)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return r * (2.0 * (double)(rng_state >> 8) / 16777216.0 - 1.0);
}

static void test_converters(void **st)
{
    (void)st;
    assert_int_equal(mc_q15_from_f(0.5f), 16384);
    assert_int_equal(mc_q15_from_f(-0.5f), -16384);
    assert_int_equal(mc_q15_from_f(1.0f), 32767);     /* saturates */
    assert_int_equal(mc_q15_from_f(-1.0f), -32768);
    assert_int_equal(mc_q15_from_f(7.0f), 32767);
    assert_int_equal(mc_q15_from_f(-7.0f), -32768);
    assert_int_equal(mc_q15_from_f(1.0f / 32768.0f), 1);
    assert_near(mc_q15_to_f(-16384), -0.5, 0.0);
    assert_int_equal(mc_q31_from_f(0.25f), 536870912);
    assert_int_equal(mc_q31_from_f(1.0f), INT32_MAX);
    assert_int_equal(mc_q31_from_f(-1.0f), INT32_MIN);
    assert_int_equal(mc_q31_from_f(-3.0f), INT32_MIN);
    assert_near(mc_q31_to_f(1073741824), 0.5, 0.0);
}

static void test_sincos(void **st)
{
    (void)st;
    double w15 = 0.0;
    for (int32_t t = -32768; t <= 32767; ++t) {
        mc_sincos_q15_t r = mc_sincos_q15((mc_q15_t)t);
        double th = PI_D * t / Q15;
        w15 = fmax(w15, fabs(r.s - Q15 * sin(th)));
        /* cos(0) = 1.0 is one LSB above the Q15 range */
        w15 = fmax(w15, fabs(r.c - fmin(Q15 * cos(th), 32767.0)));
    }
    double w31 = 0.0, wf = 0.0;
    for (int64_t t = INT32_MIN; t <= INT32_MAX; t += 4093) {
        mc_sincos_q31_t r = mc_sincos_q31((mc_q31_t)t);
        double th = PI_D * (double)t / Q31;
        w31 = fmax(w31, fabs(r.s - Q31 * sin(th)));
        w31 = fmax(w31, fabs(r.c - fmin(Q31 * cos(th), 2147483647.0)));
        /* against the float mc_sincos, in Q31 LSB (float rounding dominates there) */
        mc_sincos_t f = mc_sincos((float)th);
        wf = fmax(wf, fabs(r.s / Q31 - f.s) * Q31);
    }
    printf("sincos_q15 worst %.2f LSB, sincos_q31 worst %.2f LSB vs exact (%.0f LSB vs float "
           "mc_sincos)\n", w15, w31, wf);
    assert_true(w15 <= 1.0);
    assert_true(w31 <= 2.0);
    mc_sincos_q15_t q = mc_sincos_q15(16384);                  /* pi/2 */
    assert_int_equal(q.s, 32767);
    assert_int_equal(q.c, 0);
    q = mc_sincos_q15(-32768);                                 /* -pi */
    assert_int_equal(q.s, 0);
    assert_int_equal(q.c, -32768);
}

static void test_clarke_park(void **st)
{
    (void)st;
    double wc15 = 0, wc31 = 0, wp15 = 0, wp31 = 0, wi15 = 0, wi31 = 0, wf15 = 0, wf31 = 0;
    for (int n = 0; n < 200000; ++n) {
        /* balanced currents plus a small zero-sequence part, within +-0.9 */
        double a = rnd(0.45), b = rnd(0.45), c = -a - b + rnd(0.01);
        mc_abc_q15_t x15 = {mc_q15_from_f((float)a), mc_q15_from_f((float)b),
                            mc_q15_from_f((float)c)};
        mc_abc_q31_t x31 = {mc_q31_from_f((float)a), mc_q31_from_f((float)b),
                            mc_q31_from_f((float)c)};
        double a15 = x15.a / Q15, b15 = x15.b / Q15, c15 = x15.c / Q15;
        double a31 = x31.a / Q31, b31 = x31.b / Q31, c31 = x31.c / Q31;
        mc_ab_q15_t y15 = mc_clarke_q15(x15);
        mc_ab_q31_t y31 = mc_clarke_q31(x31);
        /* (2.4) in double on the same quantised inputs */
        wc15 = fmax(wc15, fabs(y15.alpha - Q15 * (2 * a15 - b15 - c15) / 3.0));
        wc15 = fmax(wc15, fabs(y15.beta - Q15 * (b15 - c15) / sqrt(3.0)));
        wc31 = fmax(wc31, fabs(y31.alpha - Q31 * (2 * a31 - b31 - c31) / 3.0));
        wc31 = fmax(wc31, fabs(y31.beta - Q31 * (b31 - c31) / sqrt(3.0)));
        mc_ab_t yf = mc_clarke((mc_abc_t){(float)a15, (float)b15, (float)c15});
        wf15 = fmax(wf15, fabs(y15.alpha - Q15 * yf.alpha));

        double th = rnd(PI_D);
        mc_sincos_q15_t s15 = mc_sincos_q15((mc_q15_t)lrint(th / PI_D * 32767.0));
        mc_sincos_q31_t s31 = mc_sincos_q31((mc_q31_t)llrint(th / PI_D * 2147483647.0));
        double S15 = s15.s / Q15, C15 = s15.c / Q15, S31 = s31.s / Q31, C31 = s31.c / Q31;
        double al = y15.alpha / Q15, be = y15.beta / Q15;
        mc_dq_q15_t d15 = mc_park_q15(y15, s15);
        wp15 = fmax(wp15, fabs(d15.d - Q15 * (C15 * al + S15 * be)));
        wp15 = fmax(wp15, fabs(d15.q - Q15 * (-S15 * al + C15 * be)));
        mc_dq_t df = mc_park((mc_ab_t){(float)al, (float)be}, (mc_sincos_t){(float)S15, (float)C15});
        wf15 = fmax(wf15, fabs(d15.d - Q15 * df.d));
        double al31 = y31.alpha / Q31, be31 = y31.beta / Q31;
        mc_dq_q31_t d31 = mc_park_q31(y31, s31);
        wp31 = fmax(wp31, fabs(d31.d - Q31 * (C31 * al31 + S31 * be31)));
        wp31 = fmax(wp31, fabs(d31.q - Q31 * (-S31 * al31 + C31 * be31)));
        mc_dq_t df31 = mc_park((mc_ab_t){(float)al31, (float)be31},
                               (mc_sincos_t){(float)S31, (float)C31});
        wf31 = fmax(wf31, fabs(d31.d - Q31 * df31.d));
        mc_ab_q15_t i15 = mc_park_inv_q15(d15, s15);
        double dd = d15.d / Q15, dq = d15.q / Q15;
        wi15 = fmax(wi15, fabs(i15.alpha - Q15 * (C15 * dd - S15 * dq)));
        wi15 = fmax(wi15, fabs(i15.beta - Q15 * (S15 * dd + C15 * dq)));
        mc_ab_q31_t i31 = mc_park_inv_q31(d31, s31);
        double dd31 = d31.d / Q31, dq31 = d31.q / Q31;
        wi31 = fmax(wi31, fabs(i31.alpha - Q31 * (C31 * dd31 - S31 * dq31)));
        wi31 = fmax(wi31, fabs(i31.beta - Q31 * (S31 * dd31 + C31 * dq31)));
    }
    printf("worst vs exact on the same inputs [LSB]: clarke q15 %.2f q31 %.2f, park q15 %.2f "
           "q31 %.2f, park_inv q15 %.2f q31 %.2f\n", wc15, wc31, wp15, wp31, wi15, wi31);
    printf("worst vs float API [LSB]: q15 %.2f, q31 %.0f (float rounding)\n", wf15, wf31);
    assert_true(wc15 <= 1.0 && wp15 <= 1.0 && wi15 <= 1.0);
    assert_true(wc31 <= 1.0 && wp31 <= 1.0 && wi31 <= 1.0);
    assert_true(wf15 <= 1.0);

    /* saturation instead of wrap-around: full-scale unbalanced input, and -1 * -1 */
    mc_ab_q15_t y = mc_clarke_q15((mc_abc_q15_t){32767, -32768, -32768});
    assert_int_equal(y.alpha, 32767);
    mc_dq_q15_t d = mc_park_q15((mc_ab_q15_t){-32768, -32768},
                                (mc_sincos_q15_t){-32768, -32768});
    assert_int_equal(d.d, 32767);
    mc_dq_q31_t d31 = mc_park_q31((mc_ab_q31_t){INT32_MIN, INT32_MIN},
                                  (mc_sincos_q31_t){INT32_MIN, INT32_MIN});
    assert_int_equal(d31.d, INT32_MAX);
    assert_int_equal(d31.q, 0);
}

static void test_svpwm(void **st)
{
    (void)st;
    double w15 = 0.0, w31 = 0.0;
    int satdiff = 0;
    for (int m = 0; m <= 24; ++m) {
        double r = 0.05 * m;   /* up to 1.2 in per-unit of vdc: deep over-modulation */
        for (int k = 0; k < 720; ++k) {
            double th = 2.0 * PI_D * (k + 0.3) / 720.0;
            mc_ab_q15_t u15 = {mc_q15_from_f((float)(r * cos(th))),
                               mc_q15_from_f((float)(r * sin(th)))};
            mc_ab_q31_t u31 = {mc_q31_from_f((float)(r * cos(th))),
                               mc_q31_from_f((float)(r * sin(th)))};
            mc_duty_q15_t d15;
            mc_duty_q31_t d31;
            mc_duty_t f15, f31;
            mc_svpwm_q15(u15, &d15);
            mc_svpwm_q31(u31, &d31);
            mc_svpwm((mc_ab_t){mc_q15_to_f(u15.alpha), mc_q15_to_f(u15.beta)}, 1.0f, &f15);
            mc_svpwm((mc_ab_t){(float)(u31.alpha / Q31), (float)(u31.beta / Q31)}, 1.0f, &f31);
            /* Q15 duty 1.0 saturates to 32767: compare against the clamped float */
            w15 = fmax(w15, fabs(d15.a - fmin(Q15 * f15.a, 32767.0)));
            w15 = fmax(w15, fabs(d15.b - fmin(Q15 * f15.b, 32767.0)));
            w15 = fmax(w15, fabs(d15.c - fmin(Q15 * f15.c, 32767.0)));
            double e31 = fmax(fabs(d31.a - fmin(Q31 * f31.a, 2147483647.0)),
                              fmax(fabs(d31.b - fmin(Q31 * f31.b, 2147483647.0)),
                                   fabs(d31.c - fmin(Q31 * f31.c, 2147483647.0))));
            w31 = fmax(w31, e31 / Q31 * Q15);   /* as Q15 LSB: float limits the reference */
            if (fabs(r - 1.0 / sqrt(3.0)) > 0.01 && r < 1.1) {
                satdiff += (d15.saturated != f15.saturated) + (d31.saturated != f31.saturated);
            }
        }
    }
    printf("svpwm worst vs float mc_svpwm: q15 %.2f LSB, q31 %.4f Q15-LSB (%.0f Q31 LSB)\n", w15,
           w31, w31 * 65536.0);
    assert_true(w15 <= 2.0);
    assert_true(w31 <= 0.05);
    assert_int_equal(satdiff, 0);
}

static void test_pi(void **st)
{
    (void)st;
    /* kp = 0.5 * 2^2 = 2, ki_ts = 0.01 * 2^2 */
    mc_pi_q15_cfg_t c15 = {.kp = 16384, .ki_ts = 328, .shift = 2, .out_min = -29491,
                           .out_max = 29491};
    mc_pi_q31_cfg_t c31 = {.kp = 1073741824, .ki_ts = 21474836, .shift = 2,
                           .out_min = -1932735283, .out_max = 1932735283};
    mc_pi_cfg_t f15c = {.kp = 2.0f, .ki = (float)(4.0 * 328 / Q15), .ts = 1.0f,
                        .out_min = (float)(-29491 / Q15), .out_max = (float)(29491 / Q15)};
    mc_pi_cfg_t f31c = {.kp = 2.0f, .ki = (float)(4.0 * 21474836 / Q31), .ts = 1.0f,
                        .out_min = (float)(-1932735283 / Q31), .out_max = (float)(1932735283 / Q31)};
    mc_pi_q15_t p15;
    mc_pi_q31_t p31;
    mc_pi_t f15, f31;
    mc_pi_q15_init(&p15, &c15);
    mc_pi_q31_init(&p31, &c31);
    mc_pi_init(&f15, &f15c);
    mc_pi_init(&f31, &f31c);
    double w15 = 0.0, w31 = 0.0;
    int nsat = 0;
    for (int k = 0; k < 20000; ++k) {
        /* slow sine with steps: linear stretches and saturation episodes both ways */
        double e = 0.2 * sin(k / 300.0) + ((k / 1500) % 2 ? 0.25 : -0.25) * (k % 7000 < 3000);
        mc_q15_t e15 = mc_q15_from_f((float)e);
        mc_q31_t e31 = mc_q31_from_f((float)e);
        mc_q15_t u15 = mc_pi_q15_step(&p15, e15);
        mc_q31_t u31 = mc_pi_q31_step(&p31, e31);
        float uf15 = mc_pi_step(&f15, mc_q15_to_f(e15), 0.0f);
        float uf31 = mc_pi_step(&f31, (float)(e31 / Q31), 0.0f);
        w15 = fmax(w15, fabs(u15 - Q15 * uf15));
        w31 = fmax(w31, fabs(u31 / Q31 - (double)uf31) * Q15);
        nsat += f15.saturated;
    }
    printf("pi worst vs float mc_pi over 20000 steps (%d saturated): q15 %.2f LSB, q31 %.4f "
           "Q15-LSB (%.0f Q31 LSB)\n", nsat, w15, w31, w31 * 65536.0);
    assert_true(nsat > 1000);
    assert_true(w15 <= 4.0);
    assert_true(w31 <= 0.05);

    /* windup: long saturation, then immediate recovery, as in the float version */
    mc_pi_q15_init(&p15, &c15);
    for (int k = 0; k < 5000; ++k) {
        (void)mc_pi_q15_step(&p15, 8192);
    }
    assert_int_equal(mc_pi_q15_step(&p15, 8192), 29491);
    assert_true(mc_pi_q15_step(&p15, -8192) < 29491);
}

/* A gain whose products leave int64 (kp_eff = kp 2^shift far beyond the error's range): the
 * proportional term saturates, it must never wrap. Any error of either sign then drives the
 * output to the limit of its own sign in one step (a bang-bang, never an inverted output), from
 * the smallest error to full scale, for both formats. */
static void test_pi_high_gain_saturates(void **st)
{
    (void)st;
    const mc_pi_q15_cfg_t c15 = {.kp = 32767, .ki_ts = 32767, .shift = 40, .out_min = -29491, .out_max = 29491};
    const mc_pi_q31_cfg_t c31 = {.kp = 2147483647, .ki_ts = 2147483647, .shift = 40,
                                 .out_min = -1932735283, .out_max = 1932735283};
    const int32_t e15[] = {1, 3, 1000, 32767};
    const int64_t e31[] = {1, 200, 1073741824, 2147483647};
    for (int k = 0; k < 4; ++k) {
        for (int sign = -1; sign <= 1; sign += 2) {
            mc_pi_q15_t p15;
            mc_pi_q31_t p31;
            mc_pi_q15_init(&p15, &c15);
            mc_pi_q31_init(&p31, &c31);
            const mc_q15_t u15 = mc_pi_q15_step(&p15, (mc_q15_t)(sign * e15[k]));
            const mc_q31_t u31 = mc_pi_q31_step(&p31, (mc_q31_t)(sign * e31[k]));
            assert_int_equal(u15, sign > 0 ? c15.out_max : c15.out_min);
            assert_int_equal(u31, sign > 0 ? c31.out_max : c31.out_min);
        }
    }
    /* the most negative error too (|INT_MIN| > INT_MAX) */
    mc_pi_q15_t p15;
    mc_pi_q31_t p31;
    mc_pi_q15_init(&p15, &c15);
    mc_pi_q31_init(&p31, &c31);
    assert_int_equal(mc_pi_q15_step(&p15, INT16_MIN), c15.out_min);
    assert_int_equal(mc_pi_q31_step(&p31, INT32_MIN), c31.out_min);
}

/* Small values to Q31 round to the nearest LSB, both signs (a sensor offset of a few LSB must not
 * be truncated or pushed to the next one). */
static void test_q31_from_f_rounds_to_nearest(void **st)
{
    (void)st;
    for (int j = 0; j < 200; ++j) {
        const float lo = ldexpf((float)j + 0.25f, -31), hi = ldexpf((float)j + 0.75f, -31);
        assert_int_equal(mc_q31_from_f(lo), j);
        assert_int_equal(mc_q31_from_f(hi), j + 1);
        assert_int_equal(mc_q31_from_f(-lo), -j);
        assert_int_equal(mc_q31_from_f(-hi), -j - 1);
    }
}

/* The gain is kp * 2^shift whatever the split: 0.25 written with every shift the format allows
 * (Q15: -1..13, Q31: -1..29) gives the same proportional output, 0.25 * err within an LSB. */
static void test_pi_gain_shifts(void **st)
{
    (void)st;
    const float errs[] = {0.3f, -0.7f, 0.01f};
    for (size_t k = 0; k < sizeof errs / sizeof errs[0]; ++k) {
        const mc_q15_t e15 = mc_q15_from_f(errs[k]);
        const mc_q31_t e31 = mc_q31_from_f(errs[k]);
        for (int sh = -1; sh <= 13; ++sh) {
            const mc_pi_q15_cfg_t c = {.kp = (mc_q15_t)(1 << (13 - sh)), .ki_ts = 0, .shift = (int16_t)sh,
                                       .out_min = INT16_MIN, .out_max = INT16_MAX};
            mc_pi_q15_t p;
            mc_pi_q15_init(&p, &c);
            const mc_q15_t u = mc_pi_q15_step(&p, e15);
            if (!(fabs(u - 0.25 * e15) <= 1.0)) {
                fail_msg("q15 shift %d: %d for %g", sh, u, 0.25 * e15);
            }
        }
        for (int sh = -1; sh <= 29; ++sh) {
            const mc_pi_q31_cfg_t c = {.kp = (mc_q31_t)(1L << (29 - sh)), .ki_ts = 0, .shift = (int16_t)sh,
                                       .out_min = INT32_MIN, .out_max = INT32_MAX};
            mc_pi_q31_t p;
            mc_pi_q31_init(&p, &c);
            const mc_q31_t u = mc_pi_q31_step(&p, e31);
            if (!(fabs(u - 0.25 * e31) <= 1.0)) {
                fail_msg("q31 shift %d: %d for %g", sh, u, 0.25 * e31);
            }
        }
    }
}

/* Over-modulated duties (the request projected onto the hexagon) are rounded to the nearest,
 * not biased: over a sweep of angles and magnitudes the mean error of the phases between the
 * limits, counted outward from 1/2, stays far below the 1/4 LSB a one-sided rounding leaves
 * (an average voltage error on every phase at full speed). Reference: the exact projection. */
static void test_svpwm_overmod_unbiased(void **st)
{
    (void)st;
    double s31 = 0.0, s15 = 0.0;
    long n31 = 0, n15 = 0;
    for (int m = 0; m <= 40; ++m) {
        const double r = 0.54 + 0.0135 * m;
        for (int k = 0; k < 1800; ++k) {
            const double th = 2.0 * PI_D * (k + 0.37) / 1800.0;
            const mc_ab_q31_t u = {(mc_q31_t)llround(r * cos(th) * Q31), (mc_q31_t)llround(r * sin(th) * Q31)};
            const mc_ab_q15_t u15 = {(mc_q15_t)(u.alpha >> 16), (mc_q15_t)(u.beta >> 16)};
            mc_duty_q31_t d31;
            mc_duty_q15_t d15;
            mc_svpwm_q31(u, &d31);
            mc_svpwm_q15(u15, &d15);
            const double one[2] = {Q31, Q15};
            const double ab[2][2] = {{u.alpha / Q31, u.beta / Q31}, {u15.alpha / Q15, u15.beta / Q15}};
            const double got[2][3] = {{d31.a, d31.b, d31.c}, {d15.a, d15.b, d15.c}};
            const bool sat[2] = {d31.saturated, d15.saturated};
            for (int f = 0; f < 2; ++f) {
                const double a = ab[f][0], b = ab[f][1];
                const double v[3] = {a, -0.5 * a + 0.5 * sqrt(3.0) * b, -0.5 * a - 0.5 * sqrt(3.0) * b};
                const double mx = fmax(v[0], fmax(v[1], v[2])), mn = fmin(v[0], fmin(v[1], v[2]));
                if (!sat[f] || !(mx - mn > 1.0 + 1e-6)) {
                    continue;
                }
                for (int j = 0; j < 3; ++j) {
                    const double x = (2.0 * v[j] - mx - mn) / (mx - mn);   /* in [-1, 1] */
                    if (fabs(x) > 0.999) {
                        continue;   /* the phases at the limits */
                    }
                    const double e = (x > 0.0 ? 1.0 : -1.0) * (got[f][j] - (0.5 + 0.5 * x) * one[f]);
                    if (f == 0) { s31 += e; n31++; } else { s15 += e; n15++; }
                }
            }
        }
    }
    printf("svpwm over-modulated mean outward error: q31 %.4f LSB (%ld), q15 %.4f LSB (%ld)\n",
           s31 / (double)n31, n31, s15 / (double)n15, n15);
    assert_true(n31 > 20000 && n15 > 20000);
    assert_true(fabs(s31 / (double)n31) < 0.05);
    assert_true(fabs(s15 / (double)n15) < 0.05);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_converters),
        cmocka_unit_test(test_q31_from_f_rounds_to_nearest),
        cmocka_unit_test(test_pi_gain_shifts),
        cmocka_unit_test(test_svpwm_overmod_unbiased),
        cmocka_unit_test(test_sincos),
        cmocka_unit_test(test_clarke_park),
        cmocka_unit_test(test_svpwm),
        cmocka_unit_test(test_pi),
        cmocka_unit_test(test_pi_high_gain_saturates),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
