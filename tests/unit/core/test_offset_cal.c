/* Offsets over whole half-periods (mc/offset_cal.h, (O.1)). */
#include <math.h>
#include <stdlib.h>

#include "core_test.h"
#include "mc/offset_cal.h"
#include "mc/transforms.h"

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

/* The drive's calibration block: the plain mean at the enable (checked against mid-scale),
 * then (O.1) once the speed is known, once; the currents with the offsets in force. */
static void test_block(void **st)
{
    (void)st;
    const mc_offsets_cfg_t c = {.samples = 128u, .nominal = 2048.0f, .tol = 204.8f, .amps_per_count = (float)APC,
                                .ts = 1e-4f};
    mc_offsets_t s;
    mc_offsets_init(&s, &c);
    const uint16_t mid[3] = {2048u, 2048u, 2048u};
    const mc_abc_t i0 = mc_offsets_currents(&s, &c, mid);
    assert_true(i0.a == 0.0f && i0.b == 0.0f && i0.c == 0.0f);
    /* the diodes' current at 1500 rpm: the mean is biased, (O.1) is not */
    const double omega = 1500.0 / 60.0 * 2.0 * PI_D * 5.0;
    mc_ocal_t ref;
    fill(&ref, omega, 1e-4, 128u, 1.0, 0.0);
    mc_offsets_restart(&s);
    unsigned st_n = 0u;
    for (uint32_t j = 0u; j < c.samples; ++j) {
        const uint16_t *raw = ref.buf[j];
        const mc_offsets_status_t r = mc_offsets_add(&s, &c, raw);
        assert_int_equal(r, j + 1u < c.samples ? MC_OFFSETS_COLLECTING : MC_OFFSETS_DONE);
        st_n++;
    }
    float mean[3];
    assert_true(mc_ocal_mean(&ref, mean));
    for (int k = 0; k < 3; ++k) {
        assert_float_equal(s.offset[k], mean[k], 0.0f);
    }
    assert_true(worst_err_a(s.offset) > 0.1);   /* the plain mean is off */
    assert_int_equal(mc_offsets_add(&s, &c, mid), MC_OFFSETS_COUNTING);
    assert_int_equal(s.count, st_n + 1u);
    const uint16_t probe[3] = {2100u, 2000u, 2048u};
    const mc_abc_t i_old = mc_offsets_currents(&s, &c, probe);
    mc_ab_t di;
    assert_false(s.moved);
    assert_true(mc_offsets_at_speed(&s, &c, (float)omega, &di));
    assert_true(s.moved);
    assert_true(worst_err_a(s.offset) < 0.05);
    /* di: the change of the stator-frame current the new offsets make */
    const mc_abc_t i_new = mc_offsets_currents(&s, &c, probe);
    const mc_ab_t ab_old = mc_clarke(i_old), ab_new = mc_clarke(i_new);
    assert_near(di.alpha, ab_new.alpha - ab_old.alpha, 1e-4);
    assert_near(di.beta, ab_new.beta - ab_old.beta, 1e-4);
    assert_true(fabsf(di.alpha) + fabsf(di.beta) > 0.05f);
    /* once: the samples are gone */
    s.moved = false;
    const float after[3] = {s.offset[0], s.offset[1], s.offset[2]};
    assert_false(mc_offsets_at_speed(&s, &c, (float)omega, &di));
    assert_true(di.alpha == 0.0f && di.beta == 0.0f && !s.moved);
    for (int k = 0; k < 3; ++k) {
        assert_float_equal(s.offset[k], after[k], 0.0f);
    }
    /* an implausible mean (a channel 300 counts off mid-scale): FAILED, nothing changes */
    mc_offsets_restart(&s);
    const uint16_t far[3] = {2348u, 2048u, 2048u};
    for (uint32_t j = 0u; j + 1u < c.samples; ++j) {
        assert_int_equal(mc_offsets_add(&s, &c, far), MC_OFFSETS_COLLECTING);
    }
    assert_int_equal(mc_offsets_add(&s, &c, far), MC_OFFSETS_FAILED);
    for (int k = 0; k < 3; ++k) {
        assert_float_equal(s.offset[k], after[k], 0.0f);
    }
    /* (O.1) beyond the plausible range does not apply either */
    mc_offsets_restart(&s);
    for (uint32_t j = 0u; j < c.samples; ++j) {
        (void)mc_offsets_add(&s, &c, far);
    }
    assert_false(mc_offsets_at_speed(&s, &c, (float)omega, &di));
    /* at a standstill (no speed) the mean stays */
    mc_offsets_init(&s, &c);
    for (uint32_t j = 0u; j < c.samples; ++j) {
        assert_int_not_equal(mc_offsets_add(&s, &c, mid), MC_OFFSETS_FAILED);
    }
    assert_false(mc_offsets_at_speed(&s, &c, 0.0f, &di));
    assert_float_equal(s.offset[0], 2048.0f, 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_standstill),
        cmocka_unit_test(test_diode_current),
        cmocka_unit_test(test_ring),
        cmocka_unit_test(test_declines),
        cmocka_unit_test(test_block),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
