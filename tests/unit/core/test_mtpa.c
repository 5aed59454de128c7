#include "core_test.h"
#include <float.h>
#include "mc/mtpa.h"

/* sun2016-ipm-5kw preset (machines.md) */
static const mc_lin_params_t P = {.ld = 10.5e-3f, .lq = 12.9e-3f, .psi_pm = 0.34305f};
#define POLE_PAIRS 5.0

static double torque(double id, double iq)
{
    return 1.5 * POLE_PAIRS * (0.34305 * iq + (10.5e-3 - 12.9e-3) * id * iq);   /* (2.8) */
}

static void test_hand_values(void **st)
{
    (void)st;
    /* (2.8) per pole pair at (-2, 10): 1.5 (3.4305 + 0.048) = 5.21775 */
    assert_near(mc_torque_pp(&P, (mc_dq_t){-2.0f, 10.0f}), 5.21775, 1e-5);
    /* (2.24) at iq = 10: (0.34305 - sqrt(0.34305^2 + 4 0.0024^2 100)) / 0.0048 */
    double ref = (0.34305 - sqrt(0.34305 * 0.34305 + 4 * 0.0024 * 0.0024 * 100)) / 0.0048;
    assert_near(mc_mtpa_id(&P, 10.0f), ref, 1e-5);
    assert_near(mc_mtpa_id(&P, -10.0f), ref, 1e-5);
    assert_near(mc_mtpa_id(&P, 0.0f), 0.0, 0.0);
    const mc_lin_params_t spm = {.ld = 5e-3f, .lq = 5e-3f, .psi_pm = 0.1f};
    assert_near(mc_mtpa_id(&spm, 20.0f), 0.0, 0.0);
}

/* the point of the (2.24) curve with |I| = i_mag, by bisection on iq */
static double angle_from_224(double i_mag)
{
    double lo = 0.0, hi = i_mag;
    for (int k = 0; k < 60; ++k) {
        double iq = 0.5 * (lo + hi);
        double id = mc_mtpa_id(&P, (float)iq);
        if (hypot(id, iq) > i_mag) {
            hi = iq;
        } else {
            lo = iq;
        }
    }
    double iq = 0.5 * (lo + hi);
    return atan2(iq, -(double)mc_mtpa_id(&P, (float)iq));   /* theta_s of (2.22) */
}

static void test_mtpa_vs_brute_force(void **st)
{
    (void)st;
    const double is[] = {0.5, 1.0, 2.0, 5.0, 8.0, 10.0, 13.29, 20.0, 30.0, 40.0};
    mc_mtpa_table_t tab;
    mc_mtpa_table_fill_linear(&tab, &P, 40.0f);
    double worst224 = 0.0, worst_tab = 0.0;
    for (size_t n = 0; n < sizeof is / sizeof is[0]; ++n) {
        /* brute force: theta_s from the -d axis (2.22), 1e-6 rad grid, then a parabola fit */
        double best = -1e300, best_th = 0.0, h = 1e-6;
        for (double th = 0.0; th <= PI_D / 2; th += h) {
            double t = torque(-is[n] * cos(th), is[n] * sin(th));
            if (t > best) {
                best = t;
                best_th = th;
            }
        }
        double tm = torque(-is[n] * cos(best_th - h), is[n] * sin(best_th - h));
        double tp = torque(-is[n] * cos(best_th + h), is[n] * sin(best_th + h));
        best_th += 0.5 * h * (tm - tp) / (tm - 2.0 * best + tp);
        double d224 = fabs(angle_from_224(is[n]) - best_th);
        mc_dq_t it = mc_mtpa_table_lookup(&tab, (float)is[n]);
        double dtab = fabs(atan2(it.q, -it.d) - best_th);
        printf("|I| = %6.2f A: MTPA angle %.6f deg, (2.24) off by %.2e rad, table by %.2e rad\n",
               is[n], best_th * 180.0 / PI_D, d224, dtab);
        worst224 = fmax(worst224, d224);
        worst_tab = fmax(worst_tab, dtab);
    }
    printf("max MTPA angle difference: (2.24) %.2e rad, table (33 pts) %.2e rad\n", worst224,
           worst_tab);
    assert_true(worst224 < 1e-4);
    /* linear interpolation between grid points: worst in the first cell (0 .. 1.25 A) */
    assert_true(worst_tab < 1e-2);
}

static void test_table_lookup(void **st)
{
    (void)st;
    mc_mtpa_table_t tab;
    mc_mtpa_table_fill_linear(&tab, &P, 32.0f);   /* grid step 1 A */
    mc_dq_t z = mc_mtpa_table_lookup(&tab, 0.0f);
    assert_near(z.d, 0.0, 0.0);
    assert_near(z.q, 0.0, 0.0);
    mc_dq_t a = mc_mtpa_table_lookup(&tab, 5.0f);
    assert_near(a.d, tab.id[5], 1e-6);
    assert_near(a.q, tab.iq[5], 1e-6);
    assert_near(hypot(a.d, a.q), 5.0, 1e-5);
    assert_near(a.d, mc_mtpa_id(&P, a.q), 1e-5);      /* table points lie on (2.24) */
    mc_dq_t m = mc_mtpa_table_lookup(&tab, 5.5f);
    assert_near(m.d, 0.5 * (tab.id[5] + tab.id[6]), 1e-6);
    mc_dq_t big = mc_mtpa_table_lookup(&tab, 100.0f);
    assert_near(big.q, tab.iq[MC_MTPA_TABLE_N - 1], 0.0);
    /* no current asked, or a negative magnitude (not an MTPA point): no current */
    const float neg[] = {-1e-3f, -0.5f, -5.0f, NAN};
    for (int k = 0; k < 4; ++k) {
        const mc_dq_t n = mc_mtpa_table_lookup(&tab, neg[k]);
        assert_true(n.d == 0.0f && n.q == 0.0f);
    }
}

/* At and beyond the table's end the lookup gives its last point and reads nothing past the table
 * (a table loaded into a record with other data behind it: NaN there must not leak in). */
static void test_table_end_in_bounds(void **st)
{
    (void)st;
    struct {
        mc_mtpa_table_t tab;
        float behind[4];
    } rec;
    mc_mtpa_table_fill_linear(&rec.tab, &P, 32.0f);
    for (int k = 0; k < 4; ++k) {
        rec.behind[k] = NAN;
    }
    const float at[] = {32.0f, 32.5f, INFINITY};
    for (int k = 0; k < 3; ++k) {
        const mc_dq_t e = mc_mtpa_table_lookup(&rec.tab, at[k]);
        assert_true(e.d == rec.tab.id[MC_MTPA_TABLE_N - 1]);
        assert_true(e.q == rec.tab.iq[MC_MTPA_TABLE_N - 1]);
    }
}

static void test_current_and_voltage_circle(void **st)
{
    (void)st;
    mc_dq_t i = mc_limit_current_circle((mc_dq_t){3.0f, 4.0f}, 5.0f);   /* on the circle */
    assert_near(i.d, 3.0, 0.0);
    assert_near(i.q, 4.0, 0.0);
    i = mc_limit_current_circle((mc_dq_t){3.0f, 8.0f}, 5.0f);           /* id kept, iq = 4 */
    assert_near(i.d, 3.0, 0.0);
    assert_near(i.q, 4.0, 1e-6);
    i = mc_limit_current_circle((mc_dq_t){-3.0f, -8.0f}, 5.0f);
    assert_near(i.d, -3.0, 0.0);
    assert_near(i.q, -4.0, 1e-6);
    i = mc_limit_current_circle((mc_dq_t){-6.0f, 1.0f}, 5.0f);          /* id alone too big */
    assert_near(i.d, -5.0, 0.0);
    assert_near(i.q, 0.0, 0.0);
    mc_dq_t u = mc_limit_voltage_circle((mc_dq_t){-60.0f, 200.0f}, 100.0f);
    assert_near(u.d, -60.0, 0.0);
    assert_near(u.q, 80.0, 1e-4);
}

static void test_field_weakening_id(void **st)
{
    (void)st;
    /* (2.26) by hand: iq = 5, w = 600, V = 150: flux 0.25, 0.25^2 - (0.0129*5)^2 = 0.05833975,
     * id = (-0.34305 + 0.2415362) / 0.0105 = -9.66798 */
    float id = mc_fw_id_max(&P, 5.0f, 600.0f, 150.0f);
    assert_near(id, (-0.34305 + sqrt(0.05833975)) / 0.0105, 1e-4);
    /* it lies on the voltage ellipse (2.20) */
    double psid = 10.5e-3 * id + 0.34305, psiq = 12.9e-3 * 5.0;
    assert_near(600.0 * sqrt(psid * psid + psiq * psiq), 150.0, 1e-3);
    /* sign of the speed does not matter */
    assert_near(mc_fw_id_max(&P, 5.0f, -600.0f, 150.0f), id, 0.0);
    /* standstill: no limit */
    assert_true(mc_fw_id_max(&P, 5.0f, 0.0f, 150.0f) == FLT_MAX);
    /* iq too large for the ellipse: the centre -psi/Ld */
    assert_near(mc_fw_id_max(&P, 30.0f, 600.0f, 150.0f), -0.34305 / 10.5e-3, 1e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hand_values),
        cmocka_unit_test(test_mtpa_vs_brute_force),
        cmocka_unit_test(test_table_lookup),
        cmocka_unit_test(test_table_end_in_bounds),
        cmocka_unit_test(test_current_and_voltage_circle),
        cmocka_unit_test(test_field_weakening_id),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
