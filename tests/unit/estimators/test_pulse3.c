/* Three-phase pulse reference method (3.19)-(3.21) + Table 3.1. */
#include "ip_plant.h"

#include "mc/pulse3.h"

static mc_ip_status_t step_p3(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    return mc_pulse3_step((mc_pulse3_t *)e, i, vdc, d);
}

/* Table 3.1 rows at the sector centres, from the peak law with the firmware phase order
 * (b at +120 deg: (3.19) with b and c exchanged, see mc/pulse3.h), dI0 > 0 */
static void test_table(void **st)
{
    (void)st;
    for (int row = 0; row < 6; ++row) {
        double t = row * 30.0 * DEG;
        float di[3] = {(float)cos(2 * t), (float)cos(2 * t + 2 * PI_D / 3),
                       (float)cos(2 * t - 2 * PI_D / 3)};
        assert_int_equal(mc_pulse3_sector(di), row);
    }
    float all_pos[3] = {1.0f, 1.0f, 1.0f};
    assert_int_equal(mc_pulse3_sector(all_pos), -1);
}

/* (3.21) + Table 3.1 on exact peak-law data: every angle modulo pi, no 90-deg ambiguity left */
static void test_angle_exact(void **st)
{
    (void)st;
    double worst = 0.0;
    for (int a = -180; a < 360; a += 1) {
        double t = a * DEG + 0.3 * DEG;   /* off the sector edges */
        float ipk[3] = {(float)(5.0 + 0.4 * cos(2 * t)), (float)(5.0 + 0.4 * cos(2 * t + 2 * PI_D / 3)),
                        (float)(5.0 + 0.4 * cos(2 * t - 2 * PI_D / 3))};
        float th, ta;
        int sec;
        assert_true(mc_pulse3_angle(ipk, &th, &ta, &sec));
        assert_true(th >= 0.0f && th < (float)PI_D);
        assert_true(fabs(ta) <= PI_D / 4 + 1e-6);
        worst = fmax(worst, err_mod_pi_deg(th, t));
    }
    assert_true(worst < 0.01);
    float flat[3] = {5.0f, 5.0f, 5.0f}, th, ta;
    int sec;
    assert_false(mc_pulse3_angle(flat, &th, &ta, &sec));
}

static void sweep(int sat, int n, double noise, double *mean, double *worst, int *calls,
                  double *ipk)
{
    mc_pulse3_cfg_t c;
    mc_pulse3_cfg_default(&c);
    c.rs = (float)SUN_RS;
    c.n = n;
    *mean = *worst = *ipk = 0.0;
    int k = 0;
    for (int a = 0; a < 360; a += 15) {
        plant_t p;
        plant_init(&p, sat, a);
        p.noise = noise;
        p.rng = 4242u + (uint64_t)a;
        mc_pulse3_t s;
        assert_true(mc_pulse3_start(&s, &c));
        mc_ip_status_t st;
        *calls = plant_run(&p, step_p3, &s, 600, &st);
        assert_int_equal(st, MC_IP_DONE);
        double e = err_mod_pi_deg(s.theta, a * DEG);
        *mean += e;
        *worst = fmax(*worst, e);
        *ipk = fmax(*ipk, p.i_phase_peak);
        ++k;
    }
    *mean /= k;
}

static void test_plant(void **st)
{
    (void)st;
    double mean, worst, ipk;
    int calls;
    sweep(0, 5, 0.0, &mean, &worst, &calls, &ipk);
    print_message("linear machine, n 5: mean %.3f deg, worst %.3f deg, %d calls, I_peak %.2f A\n",
                  mean, worst, calls, ipk);
    assert_true(worst < 2.0);
    sweep(0, 5, 0.02, &mean, &worst, &calls, &ipk);
    print_message("linear machine, n 5, 0.02 A noise: mean %.3f deg, worst %.3f deg\n", mean, worst);
    assert_true(worst < 10.0);
    for (int n = 3; n <= 5; ++n) {
        sweep(1, n, 0.0, &mean, &worst, &calls, &ipk);
        print_message("saturating machine, n %d: mean %.2f deg, worst %.2f deg, I_peak %.2f A "
                      "(%.2f p.u.)\n", n, mean, worst, ipk, ipk / SUN_IRATED);
    }
}

/* The Table 3.1 row reported with the angle: on exact peak-law data 2 deg or more inside a
 * sector, the row of that sector (centre 30 k deg, modulo 180), whatever the mean peak and the
 * fluctuation's size (the row comes from the peaks' deviations from their mean, (3.20)). */
static void test_sector_reported(void **st)
{
    (void)st;
    const double mean[] = {5.0, 2.0, 12.0}, amp[] = {0.4, 1.5, 0.05};
    for (int m = 0; m < 3; ++m) {
        for (int a = 0; a < 360; ++a) {
            const double deg = a + 0.5, in_sec = fmod(deg + 15.0, 30.0);
            if (in_sec < 2.0 || in_sec > 28.0) {
                continue;
            }
            const double t = deg * DEG;
            float ipk[3] = {(float)(mean[m] + amp[m] * cos(2 * t)),
                            (float)(mean[m] + amp[m] * cos(2 * t + 2 * PI_D / 3)),
                            (float)(mean[m] + amp[m] * cos(2 * t - 2 * PI_D / 3))};
            float th, ta;
            int sec = -2;
            assert_true(mc_pulse3_angle(ipk, &th, &ta, &sec));
            const int want = (int)floor(fmod(deg + 15.0, 180.0) / 30.0);
            if (sec != want) {
                fail_msg("%.1f deg (mean %g, amp %g): row %d, want %d", deg, mean[m], amp[m], sec, want);
            }
            assert_true(err_mod_pi_deg(th, t) < 0.05);
        }
    }
}

/* The default configuration (on a struct full of garbage): 5-period pulses, R = 0, gaps of 2 to
 * 50 periods that end once |i| <= 0.3 A, no trip level. */
static void test_defaults(void **st)
{
    (void)st;
    mc_pulse3_cfg_t c;
    memset(&c, 0xA5, sizeof c);
    mc_pulse3_cfg_default(&c);
    assert_true(c.rs == 0.0f);
    assert_int_equal(c.n, 5);
    assert_int_equal(c.gap_min, 2);
    assert_int_equal(c.gap_max, 50);
    assert_true(c.i_rest == 0.3f);
    assert_true(c.i_trip == 0.0f);
}

/* Where (3.21)'s denominator is exactly zero (the peaks of b and c equally above and below the
 * mean, a exactly at it: 45 and 135 deg) the arctan of the ratio is +-45 deg by the sign of the
 * numerator; where the numerator is zero (b and c equal: 0 and 90 deg) it is 0. Table 3.1 then
 * picks the right one of the two candidates: all four exact, and (3.21)'s own value reported. */
static void test_angle_on_the_axes(void **st)
{
    (void)st;
    const float m = 5.0f, x = 0.4f;
    const struct {
        float ipk[3];
        double deg;
    } cases[] = {
        {{m + 2.0f * x, m - x, m - x}, 0.0},    /* cos 2t = 1 */
        {{m, m - x, m + x}, 45.0},              /* cos 2t = 0, b below, c above */
        {{m - 2.0f * x, m + x, m + x}, 90.0},   /* cos 2t = -1 */
        {{m, m + x, m - x}, 135.0},
    };
    for (int k = 0; k < 4; ++k) {
        float th, ta;
        int sec;
        assert_true(mc_pulse3_angle(cases[k].ipk, &th, &ta, &sec));
        if (err_mod_pi_deg(th, cases[k].deg * DEG) > 0.01) {
            fail_msg("%g deg: theta %g deg (atan part %g deg, row %d)", cases[k].deg, th / DEG, ta / DEG, sec);
        }
        assert_true(fabs(ta) <= PI_D / 4 + 1e-6);
        /* (3.21)'s own value, reported as theta_atan: 0 on the axes, +-45 deg between */
        const double want_ta = (k == 1) ? PI_D / 4 : ((k == 3) ? -PI_D / 4 : 0.0);
        assert_near(ta, want_ta, 1e-6);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_angle_exact),
        cmocka_unit_test(test_plant),
        cmocka_unit_test(test_sector_reported),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_angle_on_the_axes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
