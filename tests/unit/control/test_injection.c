/* HF voltage injection (mc/injection.h, thesis 6.4, 7.4): the magnitude schedule (6.6), nothing
 * at all when the injection is off, and the waveforms a period at a time (the thesis motor's
 * 70 V at 500 Hz, N1 = 400 rpm, 10 kHz). */
#include "../mc_test.h"
#include "mc/injection.h"

#define N1 (400.0 / 60.0 * 2.0 * PI_D * 5.0)   /* electrical [rad/s] */

static mc_inj_cfg_t config(mc_inj_kind_t kind)
{
    return (mc_inj_cfg_t){.kind = kind, .v1 = 70.0f, .f_hz = 500.0f, .omega_n1 = (float)N1, .ts = 1e-4f};
}

/* (6.6): V1 at standstill, falling linearly to 0 at N1 and staying 0 beyond, either direction. */
static void test_schedule(void **st)
{
    (void)st;
    const mc_inj_cfg_t c = config(MC_INJ_SINE);
    assert_near(mc_inj_magnitude(&c, 0.0f), 70.0, 1e-5);
    assert_near(mc_inj_magnitude(&c, (float)(0.25 * N1)), 52.5, 1e-4);
    assert_near(mc_inj_magnitude(&c, (float)(-0.5 * N1)), 35.0, 1e-4);
    assert_near(mc_inj_magnitude(&c, (float)N1), 0.0, 0.0);
    assert_near(mc_inj_magnitude(&c, (float)(-3.0 * N1)), 0.0, 0.0);
    mc_inj_cfg_t z = c;
    z.omega_n1 = 0.0f;   /* no schedule configured: nothing, not a division by zero */
    assert_near(mc_inj_magnitude(&z, 0.0f), 0.0, 0.0);
}

/* Off: no magnitude at any speed (what the block reports is what it injects) and no voltage. */
static void test_off_injects_nothing(void **st)
{
    (void)st;
    const mc_inj_cfg_t c = config(MC_INJ_OFF);
    mc_inj_t s;
    mc_inj_init(&s, &c);
    const float ws[] = {0.0f, (float)(0.5 * N1), (float)(-0.9 * N1)};
    for (int k = 0; k < 3; ++k) {
        assert_near(mc_inj_magnitude(&c, ws[k]), 0.0, 0.0);
        for (int n = 0; n < 40; ++n) {
            assert_near(mc_inj_step(&s, ws[k]), 0.0, 0.0);
            assert_near(s.magnitude, 0.0, 0.0);
        }
    }
}

/* One injection period (20 samples at 500 Hz / 10 kHz): the sine peaks near the magnitude and
 * averages to 0; the rectangle is +magnitude for the first half, -magnitude for the second. */
static void test_waveforms(void **st)
{
    (void)st;
    mc_inj_t s;
    const mc_inj_cfg_t sine = config(MC_INJ_SINE);
    mc_inj_init(&s, &sine);
    double sum = 0.0, peak = 0.0;
    for (int n = 0; n < 20; ++n) {
        const float v = mc_inj_step(&s, (float)(0.5 * N1));
        sum += v;
        peak = fmax(peak, fabs(v));
    }
    assert_near(s.magnitude, 35.0, 1e-4);
    assert_near(sum, 0.0, 1e-3);
    assert_true(peak <= 35.0 + 1e-4 && peak >= 35.0 * cos(PI_D / 20.0) - 1e-4);
    const mc_inj_cfg_t rect = config(MC_INJ_RECT);
    mc_inj_init(&s, &rect);
    for (int n = 0; n < 40; ++n) {
        const float v = mc_inj_step(&s, 0.0f);
        assert_near(v, (n % 20) < 10 ? 70.0 : -70.0, 1e-4);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_schedule),
        cmocka_unit_test(test_off_injects_nothing),
        cmocka_unit_test(test_waveforms),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
