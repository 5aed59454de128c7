/* Entry into field weakening at speed (mc/fw_entry.h, (F.1)-(F.3)). */
#include <math.h>

#include "../mc_test.h"
#include "mc/fw_entry.h"

#define PI_D 3.14159265358979323846
/* the thesis motor (sun2016-ipm-5kw) at 1500 rpm and 300 V, linear model */
#define LD 10.5e-3
#define LQ 12.9e-3
#define PSI 0.34305
#define RS 0.4
#define W (1500.0 / 60.0 * 2.0 * PI_D * 5.0)
#define UMAX (300.0 / 1.7320508075688772)
#define TS 1e-4

static const mc_sincos_t SC0 = {0.0f, 1.0f};   /* rotor frame = stator frame */

/* the hexagon's distance from the centre in the direction of (d, q) at theta = 0, 300 V */
static double hex_reach(double d, double q)
{
    const double n = hypot(d, q), a = d / n, b = -0.5 * a + 0.8660254037844386 * q / n,
                 c = -0.5 * a - 0.8660254037844386 * q / n;
    return 300.0 / (fmax(a, fmax(b, c)) - fmin(a, fmin(b, c)));
}

static mc_dq_t flux(mc_dq_t i)
{
    return (mc_dq_t){(float)(LD * i.d + PSI), (float)(LQ * i.q)};
}

/* The law alone (mc_fwe_law) with its inputs spelled out: a circle of u_max, or with vdc > 0 the
 * hexagon of vdc (overmodulation). */
static bool law(mc_dq_t psi, mc_dq_t i, mc_dq_t u_now, float rs, float omega, float ts, float u_max, float vdc,
                mc_sincos_t sc, bool started, mc_dq_t *u)
{
    const mc_fwe_cfg_t c = {.ts = ts, .rs = rs, .i_stop = INFINITY, .overmod = vdc > 0.0f};
    const mc_fwe_in_t in = {.psi = psi, .i = i, .u_now = u_now, .omega = omega, .u_land = u_max, .vdc = vdc, .sc = sc};
    return mc_fwe_law(&c, &in, started, u);
}

/* The first vector from the magnet's flux, without overmodulation: |u| = u_max at 90 deg + beta
 * ahead of the flux with cos(beta) = u_max / |omega psi| (F.2), (F.3); mirrored for the other
 * direction. With it: |u| the hexagon's reach in the vector's direction, and (F.2) with that. */
static void test_first_vector(void **st)
{
    (void)st;
    const mc_dq_t i0 = {0.0f, 0.0f}, u0 = {0.0f, 0.0f};
    mc_dq_t u;
    assert_true(law(flux(i0), i0, u0, 0.0f, (float)W, 0.0f, (float)UMAX, 0.0f, SC0, true, &u));
    const double beta = acos(UMAX / (W * PSI));
    assert_near(atan2(u.q, u.d), PI_D / 2.0 + beta, 1e-4);   /* 140 deg */
    assert_near(hypot(u.d, u.q), UMAX, 1e-3);
    assert_true(law(flux(i0), i0, u0, 0.0f, (float)-W, 0.0f, (float)UMAX, 0.0f, SC0, false, &u));
    assert_near(atan2(u.q, u.d), -(PI_D / 2.0 + beta), 1e-4);
    assert_near(hypot(u.d, u.q), UMAX, 1e-3);
    /* overmodulation, at two rotor angles: the reach there, and (F.2) with it */
    for (int k = 0; k < 2; ++k) {
        const double th = k * 0.5;
        const mc_sincos_t sc = {(float)sin(th), (float)cos(th)};
        assert_true(law(flux(i0), i0, u0, 0.0f, (float)W, 0.0f, (float)UMAX, 300.0f, sc, true, &u));
        const double a = atan2(u.q, u.d), m = hypot(u.d, u.q);
        assert_near(m, hex_reach(cos(a + th), sin(a + th)), 1e-2);
        assert_true(m > UMAX - 1e-3);
        /* two passes: the direction from the reach one pass before, within a degree */
        assert_near(a, PI_D / 2.0 + acos(m / (W * PSI)), 0.02);
        /* the law is homogeneous in flux and voltage: a machine of 1/400 the flux on a bus of
         * 1/400 (0.75 V) gets the same vector scaled by 1/400, the hexagon's reach included */
        const double f = 1.0 / 400.0;
        const mc_dq_t psi_f = {(float)(PSI * f), 0.0f};
        mc_dq_t uf;
        assert_true(law(psi_f, i0, u0, 0.0f, (float)W, 0.0f, (float)(UMAX * f), (float)(300.0 * f), sc, true, &uf));
        assert_near(uf.d / f, u.d, 1e-2);
        assert_near(uf.q / f, u.q, 1e-2);
    }
}

/* Held but lagging: tangential (F.4) with what the hexagon gives in that direction; close to rho
 * the radial part moves the flux no further than rho within the period (landing). */
static void test_held_and_landing(void **st)
{
    (void)st;
    const float rho = (float)(UMAX / W);
    const float lag = 0.2f;
    const mc_dq_t z = {0.0f, 0.0f};
    mc_dq_t u;
    /* held (0.98 rho), lagging 0.2 rad: tangential, |u| the hexagon's reach there */
    const mc_dq_t ph = {0.98f * rho * cosf(lag), -0.98f * rho * sinf(lag)};
    assert_true(law(ph, z, z, 0.0f, (float)W, 0.0f, (float)UMAX, 300.0f, SC0, true, &u));
    assert_near(hypot(u.d, u.q), hex_reach(u.d, u.q), 1e-2);
    /* without overmodulation nothing takes the lag back: held is done */
    assert_false(law(ph, z, z, 0.0f, (float)W, 0.0f, (float)UMAX, 0.0f, SC0, true, &u));
    assert_near(u.d * ph.d + u.q * ph.q, 0.0, 1e-3);   /* no radial part */
    /* 0.3 % beyond rho: the radial part covers exactly what is left in one period */
    const mc_dq_t pn = {1.003f * rho, 0.0f};
    const mc_dq_t hold = {0.0f, (float)W * pn.d};   /* j omega psi: the prediction stays put */
    assert_true(law(pn, z, hold, 0.0f, (float)W, (float)TS, (float)UMAX, 0.0f, SC0, true, &u));
    const double radial = -(u.d * pn.d + u.q * pn.q) / hypot(pn.d, pn.q);
    assert_near(radial * TS, 0.003 * rho, 2e-6);
    assert_near(hypot(u.d, u.q), UMAX, 1e-3);
}

/* Held and without lag: done, the voltage untouched; below the generation speed it never starts;
 * non-finite inputs end it. */
static void test_done_and_bad_input(void **st)
{
    (void)st;
    /* a flux that 170.5 V hold, under the voltage that holds it (2.7) */
    const mc_dq_t i = {-12.0f, 0.0f};
    const mc_dq_t u0 = {(float)(RS * i.d), (float)(W * (LD * i.d + PSI))};
    mc_dq_t u;
    assert_false(law(flux(i), i, u0, (float)RS, (float)W, (float)TS, (float)UMAX, 0.0f, SC0, true, &u));
    assert_near(u.d, u0.d, 0.0);
    assert_near(u.q, u0.q, 0.0);
    const mc_dq_t z = {0.0f, 0.0f};
    /* below the generation speed under V(000) the flux lags (4 deg in 1.5 periods): not a start */
    assert_false(law(flux(z), z, z, (float)RS, (float)(0.6 * W), (float)TS, (float)UMAX, 0.0f, SC0, false, &u));
    assert_false(law(flux(z), z, z, (float)RS, NAN, (float)TS, (float)UMAX, 0.0f, SC0, true, &u));
    const mc_dq_t bad = {NAN, 0.0f};
    assert_false(law(bad, z, z, (float)RS, (float)W, (float)TS, (float)UMAX, 0.0f, SC0, true, &u));
    assert_false(law(flux(z), z, z, (float)RS, (float)W, (float)TS, 0.0f, 0.0f, SC0, true, &u));
}

/* Closed loop on the linear machine (Rs = 0, the law's voltage acting at once, fine steps): the
 * flux shrinks to rho without ever growing, with the least lag there, sqrt(k^2 - 1) - acos(1/k)
 * (k = psi_pm / rho: 18.3 deg), on the circle u_max. Then with overmodulation (the hexagon's
 * reach, the rotor turning under it) the law takes the lag back at the held radius and ends. */
static void test_min_lag_path(void **st)
{
    (void)st;
    for (int dir = -1; dir <= 1; dir += 2) {
        const double w = dir * W;
        double pd = PSI, pq = 0.0, r_last = PSI, lag_at_rho = NAN;
        const double h = TS / 20.0;
        const mc_dq_t z = {0.0f, 0.0f};
        bool on = true;
        for (int k = 0; on && k < 400000; ++k) {
            const mc_dq_t i = {(float)((pd - PSI) / LD), (float)(pq / LQ)};
            /* until rho the circle, then the hexagon (the rotor at w k h) */
            const float vdc = isnan(lag_at_rho) ? 0.0f : 300.0f;
            const double th = w * k * h;
            const mc_sincos_t sc = {(float)sin(th), (float)cos(th)};
            mc_dq_t u;
            on = law((mc_dq_t){(float)pd, (float)pq}, i, z, 0.0f, (float)w, 0.0f, (float)UMAX, vdc, sc, k > 0, &u);
            if (!on) {
                break;
            }
            pd += h * (u.d + w * pq);
            pq += h * (u.q - w * pd);
            const double r = hypot(pd, pq);
            if (isnan(lag_at_rho)) {
                assert_true(r <= r_last + 1e-7);   /* shrinking until rho */
                if (fabs(w) * r <= UMAX) {
                    lag_at_rho = -dir * atan2(pq, pd);
                }
            }
            r_last = r;
        }
        assert_false(on);
        const double kk = PSI * W / UMAX;
        assert_near(lag_at_rho, sqrt(kk * kk - 1.0) - acos(1.0 / kk), 0.01);
        assert_true(-dir * atan2(pq, pd) <= MC_FWE_LAG_END + 1e-3);
        assert_true(fabs(w) * hypot(pd, pq) <= UMAX * 1.0001);
    }
}

/* The block's life cycle (begin / step / active): off until begun, then the law's voltage each
 * period until it is done, the current reaches cfg.i_stop or one electrical turn has passed;
 * ENDED tells the caller to restart its loop only when the entry ran at least a period. */
static void test_block_life_cycle(void **st)
{
    (void)st;
    const mc_fwe_cfg_t c = {.ts = (float)TS, .rs = (float)RS, .i_stop = 14.6f, .overmod = true};
    const mc_dq_t z = {0.0f, 0.0f};
    /* the magnet's flux at 1500 rpm, no current: not holdable, the law runs */
    mc_fwe_in_t in = {.psi = flux(z), .i = z, .u_now = z, .omega = (float)W, .u_land = (float)UMAX, .vdc = 300.0f,
                      .sc = SC0};
    mc_fwe_t s;
    mc_fwe_reset(&s);
    mc_dq_t u = {1.0f, 2.0f};
    assert_false(mc_fwe_active(&s));
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_OFF);
    assert_near(u.d, 1.0f, 0.0);   /* untouched: nothing ran */
    mc_fwe_begin(&s);
    assert_true(mc_fwe_active(&s));
    mc_dq_t u_law;
    assert_true(mc_fwe_law(&c, &in, false, &u_law));
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_RUNNING);
    assert_near(u.d, u_law.d, 0.0);   /* the law's own voltage */
    assert_near(u.q, u_law.q, 0.0);
    assert_int_equal(s.n, 1);
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_RUNNING);
    /* the current at i_stop: the loop takes over, whatever the law would do */
    in.i = (mc_dq_t){-14.6f, 0.0f};
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_ENDED);
    assert_false(mc_fwe_active(&s));
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_OFF);
    /* one electrical turn: W ts per period, so 2 pi / (W ts) periods at most */
    in.i = z;
    mc_fwe_begin(&s);
    const int turn = (int)ceil(2.0 * PI_D / (W * TS));
    int k = 0;
    while (mc_fwe_step(&s, &c, &in, &u) == MC_FWE_RUNNING) {
        ++k;
        assert_true(k <= turn + 1);
    }
    assert_false(mc_fwe_active(&s));
    assert_true(k >= turn - 1);
    /* begun where the flux can be held (below the generation speed): it ends at once, and as it
     * never ran the loop is not restarted (OFF, not ENDED) */
    in.omega = (float)(0.5 * W);
    mc_fwe_begin(&s);
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_OFF);
    assert_false(mc_fwe_active(&s));
    /* reset stops it */
    in.omega = (float)W;
    mc_fwe_begin(&s);
    mc_fwe_reset(&s);
    assert_int_equal(mc_fwe_step(&s, &c, &in, &u), MC_FWE_OFF);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_first_vector),
        cmocka_unit_test(test_held_and_landing),
        cmocka_unit_test(test_done_and_bad_input),
        cmocka_unit_test(test_min_lag_path),
        cmocka_unit_test(test_block_life_cycle),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
