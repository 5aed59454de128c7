#include "core_test.h"
#include "mc/filters.h"

#define TS 1e-4f

/* |H(e^{jwTs})| of a biquad from its coefficients, in double */
static double biquad_gain(const mc_biquad_t *s, double f)
{
    double w = 2.0 * PI_D * f * (double)TS;
    double nr = s->b0 + s->b1 * cos(w) + s->b2 * cos(2 * w);
    double ni = -s->b1 * sin(w) - s->b2 * sin(2 * w);
    double dr = 1.0 + s->a1 * cos(w) + s->a2 * cos(2 * w);
    double di = -s->a1 * sin(w) - s->a2 * sin(2 * w);
    return sqrt((nr * nr + ni * ni) / (dr * dr + di * di));
}

/* steady-state amplitude of the filter output for a unit sine at f (time domain) */
static double sine_amp_lpf1(mc_lpf1_t *s, double f)
{
    double amp = 0.0;
    for (int k = 0; k < 40000; ++k) {
        float y = mc_lpf1_step(s, (float)sin(2.0 * PI_D * f * k * (double)TS));
        if (k > 30000) {
            amp = fmax(amp, fabs(y));
        }
    }
    return amp;
}

static double sine_amp_biquad(mc_biquad_t *s, double f)
{
    double amp = 0.0;
    for (int k = 0; k < 40000; ++k) {
        float y = mc_biquad_step(s, (float)sin(2.0 * PI_D * f * k * (double)TS));
        if (k > 30000) {
            amp = fmax(amp, fabs(y));
        }
    }
    return amp;
}

static void test_lpf1(void **st)
{
    (void)st;
    mc_lpf1_t f;
    mc_lpf1_init(&f, 100.0f, TS, 0.0f);
    /* pre-warped Tustin: K = tan(pi fc Ts) = tan(0.01 pi) = 0.0314263; b = K/(1+K) */
    assert_near(f.b, 0.0314263 / 1.0314263, 1e-6);
    float y = 0.0f;
    for (int k = 0; k < 5000; ++k) {
        y = mc_lpf1_step(&f, 1.0f);
    }
    assert_near(y, 1.0, 1e-5);                         /* DC gain 1 */
    mc_lpf1_init(&f, 100.0f, TS, 0.0f);
    double g = sine_amp_lpf1(&f, 100.0);
    printf("lpf1 gain at fc %.6f (1/sqrt2 = 0.707107)\n", g);
    assert_near(g, sqrt(0.5), 2e-3);                   /* -3 dB exactly at fc */
    /* initial value is a steady state */
    mc_lpf1_init(&f, 50.0f, TS, 3.0f);
    assert_near(mc_lpf1_step(&f, 3.0f), 3.0, 1e-6);
}

static void test_biquad_lowpass(void **st)
{
    (void)st;
    mc_biquad_t f;
    mc_biquad_init_lowpass(&f, 200.0f, 0.70710678f, TS);
    assert_near(biquad_gain(&f, 0.0), 1.0, 1e-5);
    assert_near(biquad_gain(&f, 200.0), sqrt(0.5), 1e-5);   /* |H(j w0)| = Q */
    mc_biquad_init_lowpass(&f, 200.0f, 2.0f, TS);
    assert_near(biquad_gain(&f, 200.0), 2.0, 1e-4);
    mc_biquad_reset(&f, 0.0f);
    assert_near(sine_amp_biquad(&f, 200.0), 2.0, 5e-3);
}

static void test_biquad_bandpass(void **st)
{
    (void)st;
    mc_biquad_t f;
    mc_biquad_init_bandpass(&f, 500.0f, 5.0f, TS);
    assert_near(biquad_gain(&f, 500.0), 1.0, 1e-5);       /* unity at fc */
    assert_near(biquad_gain(&f, 0.0), 0.0, 1e-6);         /* blocks DC */
    assert_true(biquad_gain(&f, 100.0) < 0.1);
    double g = sine_amp_biquad(&f, 500.0);
    printf("band-pass gain at fc %.6f\n", g);
    assert_near(g, 1.0, 2e-3);
}

static void test_biquad_notch(void **st)
{
    (void)st;
    mc_biquad_t f;
    mc_biquad_init_notch(&f, 1000.0f, 2.0f, TS);
    double depth = biquad_gain(&f, 1000.0);
    printf("notch |H(fc)| = %.3g (%.1f dB)\n", depth, 20.0 * log10(depth + 1e-300));
    assert_true(depth < 1e-5);
    assert_near(biquad_gain(&f, 0.0), 1.0, 1e-5);
    assert_near(biquad_gain(&f, 4999.0), 1.0, 1e-3);
    double g = sine_amp_biquad(&f, 1000.0);
    printf("notch time-domain residual at fc %.3g\n", g);
    assert_true(g < 1e-3);
    /* reset to a steady state: constant input gives constant output */
    mc_biquad_reset(&f, 2.0f);
    assert_near(mc_biquad_step(&f, 2.0f), 2.0, 1e-5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lpf1),
        cmocka_unit_test(test_biquad_lowpass),
        cmocka_unit_test(test_biquad_bandpass),
        cmocka_unit_test(test_biquad_notch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
