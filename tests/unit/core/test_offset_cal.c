/* Offsets over whole half-periods (mc/offset_cal.h, (O.1)). */
#include <math.h>
#include <stdlib.h>

#include "core_test.h"
#include "mc/offset_cal.h"

#define APC 0.0122   /* A per count: a 50 A span at 12 bits */
#define PI_D 3.14159265358979323846
static const float OFF[3] = {2048.0f + 13.0f, 2048.0f - 7.0f, 2048.0f + 2.5f};

/* A rectified current with half-wave symmetry: six sawtooth teeth per electrical period (as the
 * diodes drive on the thesis motor at 1500 rpm), phase b and c 120 deg later. [A] */
static double diode_current(double theta)
{
    const double t6 = fmod(fmod(theta, 2.0 * PI_D) + 2.0 * PI_D, PI_D / 3.0) / (PI_D / 3.0);
    return 6.5 * t6 * sin(theta + 0.4) + 0.8 * sin(3.0 * theta);
}

static double noise(unsigned *state)
{
    *state = *state * 1103515245u + 12345u;
    return ((double)((*state >> 8) & 0xffff) / 65535.0 - 0.5) * 2.0;   /* uniform, +-1 */
}

static void fill_from(mc_ocal_t *s, double omega, double ts, unsigned n, double amp, double noise_a,
                      unsigned n_transient)
{
    unsigned st = 7u;
    mc_ocal_reset(s);
    for (unsigned j = 0; j < n; ++j) {
        uint16_t raw[3];
        for (int k = 0; k < 3; ++k) {
            const double th = omega * ts * j + 0.3 - 2.0 * PI_D / 3.0 * k;
            /* the first n_transient samples carry 5 A more on every phase (a transient) */
            const double tr = j < n_transient ? 5.0 : 0.0;
            const double i = amp * diode_current(th) + noise_a * noise(&st) + tr;
            raw[k] = (uint16_t)lround(OFF[k] + i / APC);
        }
        mc_ocal_add(s, raw);
    }
}

static void fill(mc_ocal_t *s, double omega, double ts, unsigned n, double amp, double noise_a)
{
    fill_from(s, omega, ts, n, amp, noise_a, 0u);
}

static double worst_err_a(const float off[3])
{
    double e = 0.0;
    for (int k = 0; k < 3; ++k) {
        e = fmax(e, fabs((double)(off[k] - OFF[k])) * APC);
    }
    return e;
}

/* At a standstill the plain mean is the offset, and (O.1) agrees with it. */
static void test_standstill(void **st)
{
    (void)st;
    mc_ocal_t s;
    float off[3], per[3];
    fill(&s, 0.0, 1e-4, 64, 0.0, 0.05);
    assert_true(mc_ocal_mean(&s, off));
    assert_true(worst_err_a(off) < 0.02);
    assert_true(mc_ocal_periodic(&s, 785.4f, 1e-4f, per));
    assert_true(worst_err_a(per) < 0.02);
}

/* Above the generation speed: the plain mean is biased by the diodes' current (0.4-1.1 A here),
 * (O.1) is not (0.02 A at most with 25 or more samples per half-period), with the lag a fraction of
 * a sample off a whole number, and with the speed 1 % off. */
static void test_diode_current(void **st)
{
    (void)st;
    const double speeds[] = {785.4, 700.0, 1100.0, -785.4, 2500.0};
    for (unsigned q = 0; q < sizeof speeds / sizeof speeds[0]; ++q) {
        mc_ocal_t s;
        float off[3], per[3];
        fill(&s, speeds[q], 1e-4, 64, 1.0, 0.02);
        assert_true(mc_ocal_mean(&s, off));
        assert_true(worst_err_a(off) > 0.3);   /* what the plain mean made of it */
        assert_true(mc_ocal_periodic(&s, (float)speeds[q], 1e-4f, per));
        /* the interpolated sample of a pair that straddles a tooth's edge is off by a share of
         * the edge: the fewer samples per half-period, the more (12.6 at the last speed) */
        const double tol = fabs(speeds[q]) > 1500.0 ? 0.2 : 0.06;
        assert_true(worst_err_a(per) < tol);
        assert_true(mc_ocal_periodic(&s, (float)(1.01 * speeds[q]), 1e-4f, per));
        assert_true(worst_err_a(per) < 0.25);
    }
}

/* Only the last MC_OCAL_N samples count: an earlier transient does not. */
static void test_ring(void **st)
{
    (void)st;
    mc_ocal_t s;
    float per[3];
    fill_from(&s, 785.4, 1e-4, MC_OCAL_N + 50u, 1.0, 0.0, 50u);
    assert_true(mc_ocal_periodic(&s, 785.4f, 1e-4f, per));
    assert_true(worst_err_a(per) < 0.05);
}

/* Where half a period does not fit in the samples (with the pairs asked for), or for a speed of
 * zero or NaN, (O.1) declines and leaves the offsets alone. */
static void test_declines(void **st)
{
    (void)st;
    mc_ocal_t s;
    float per[3] = {1.0f, 2.0f, 3.0f};
    fill(&s, 300.0, 1e-4, 64, 1.0, 0.0);   /* half-period: 105 samples */
    assert_false(mc_ocal_periodic(&s, 300.0f, 1e-4f, per));
    assert_false(mc_ocal_periodic(&s, 0.0f, 1e-4f, per));
    assert_false(mc_ocal_periodic(&s, NAN, 1e-4f, per));
    assert_false(mc_ocal_periodic(&s, INFINITY, 0.0f, per));
    assert_near(per[0], 1.0, 0.0);
    assert_near(per[2], 3.0, 0.0);
    mc_ocal_reset(&s);
    assert_false(mc_ocal_mean(&s, per));
    assert_false(mc_ocal_periodic(&s, 785.4f, 1e-4f, per));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_standstill),
        cmocka_unit_test(test_diode_current),
        cmocka_unit_test(test_ring),
        cmocka_unit_test(test_declines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
