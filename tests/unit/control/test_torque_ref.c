/* Torque -> current references on the sun2016-ipm-5kw constants at Vdc = 300 V: MTPA at low speed,
 * field weakening above base speed, the current circle, continuity across base speed. The
 * reference values are computed here in double from (2.8), (2.20), (2.24), (2.25). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#define PI_D 3.14159265358979323846

#include "mc/torque_ref.h"

#define P 5
#define RS 0.4
#define LD 10.5e-3
#define LQ 12.9e-3
#define PSI 0.34305
#define IMAX 13.29
#define VDC 300.0
#define UMAX (VDC / sqrt(3.0))

static void assert_near(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) {
        fail_msg("%.9g != %.9g (tol %.3g)", a, b, tol);
    }
}

static double rpm_to_we(double rpm) { return rpm * 2.0 * PI_D / 60.0 * P; }

static double ref_torque(double id, double iq) { return 1.5 * P * (PSI * iq + (LD - LQ) * id * iq); }

static double ref_mtpa_id(double iq)   /* (2.24) */
{
    const double dl = LQ - LD;
    return (PSI - sqrt(PSI * PSI + 4.0 * dl * dl * iq * iq)) / (2.0 * dl);
}

static double ref_mtpa_iq(double t)   /* bisection in double along (2.24) */
{
    double lo = 0.0, hi = 3.0 * IMAX;
    for (int k = 0; k < 200; ++k) {
        double m = 0.5 * (lo + hi);
        if (ref_torque(ref_mtpa_id(m), m) < t) lo = m; else hi = m;
    }
    return 0.5 * (lo + hi);
}

/* stator voltage magnitude (2.20) at steady state, Rs neglected as in the thesis */
static double ref_u(double id, double iq, double we)
{
    return fabs(we) * sqrt(LQ * LQ * iq * iq + (LD * id + PSI) * (LD * id + PSI));
}

static void make(mc_tref_t *s, bool table, float margin)
{
    mc_tref_cfg_t c;
    c.pole_pairs = P;
    c.mach.ld = (float)LD;
    c.mach.lq = (float)LQ;
    c.mach.psi_pm = (float)PSI;
    c.i_max = (float)IMAX;
    c.u_margin = margin;
    c.use_table = table;
    c.ts = 1e-4f;
    mc_mtpa_table_fill_linear(&c.table, &c.mach, (float)IMAX);
    mc_tref_init(s, &c);
}

static void check_low_speed(bool table, double tol_i)
{
    mc_tref_t s;
    make(&s, table, 1.0f);
    const double we = rpm_to_we(300.0);
    const double cmds[] = {0.5, 5.0, 10.0, 20.0, 30.0, 34.0};
    for (size_t k = 0; k < sizeof cmds / sizeof cmds[0]; ++k) {
        const double t = cmds[k];
        const double iq = ref_mtpa_iq(t);
        const double id = ref_mtpa_id(iq);
        mc_dq_t i = mc_tref_step(&s, (float)t, (float)we, (float)VDC);
        assert_false(s.fw_active);
        assert_false(s.i_limited);
        assert_near(i.d, id, tol_i);
        assert_near(i.q, iq, tol_i);
        assert_near(ref_torque(i.d, i.q), t, 2e-4 * t);
        /* negative torque: iq flips, id stays; negative speed changes nothing */
        mc_dq_t n = mc_tref_step(&s, (float)-t, (float)-we, (float)VDC);
        assert_near(n.d, i.d, 1e-5);
        assert_near(n.q, -i.q, 1e-5);
    }
    mc_dq_t z = mc_tref_step(&s, 0.0f, (float)we, (float)VDC);
    assert_near(z.d, 0.0, 1e-6);
    assert_near(z.q, 0.0, 1e-6);
}

static void test_low_speed_is_mtpa(void **state)
{
    (void)state;
    check_low_speed(false, 2e-4);
}

static void test_low_speed_table(void **state)
{
    (void)state;
    /* the table is linear in |I| between 33 points: small offset from the curve, exact torque */
    check_low_speed(true, 2e-2);
}

static void test_current_circle(void **state)
{
    (void)state;
    mc_tref_t s;
    make(&s, false, 1.0f);
    /* MTPA at |I| = 13.29 A by (2.23): cos = (-psi + sqrt(psi^2 + 8 dL^2 I^2)) / (4 dL I) */
    const double dl = LQ - LD;
    const double c = (-PSI + sqrt(PSI * PSI + 8.0 * dl * dl * IMAX * IMAX)) / (4.0 * dl * IMAX);
    const double id = -IMAX * c, iq = IMAX * sqrt(1.0 - c * c);   /* (-1.216, 13.234) A */
    const double tmax = ref_torque(id, iq);                      /* 34.34 N m           */
    assert_near(tmax, 34.34, 0.01);
    mc_dq_t i = mc_tref_step(&s, 50.0f, (float)rpm_to_we(100.0), (float)VDC);
    assert_true(s.i_limited);
    assert_false(s.fw_active);
    assert_true(hypot(i.d, i.q) <= IMAX * (1.0 + 1e-6));
    assert_near(i.d, id, 2e-3);
    assert_near(i.q, iq, 2e-3);
    assert_near(ref_torque(i.d, i.q), tmax, 1e-2);

    make(&s, true, 1.0f);
    i = mc_tref_step(&s, -50.0f, (float)rpm_to_we(100.0), (float)VDC);
    assert_true(s.i_limited);
    assert_true(hypot(i.d, i.q) <= IMAX * (1.0 + 1e-6));
    assert_near(ref_torque(i.d, i.q), -tmax, 2e-2);
}

static void test_no_load_base_speed(void **state)
{
    (void)state;
    mc_tref_t s;
    make(&s, false, 1.0f);
    /* no-load base speed (2.25): u_max / psi_pm = 504.9 rad/s = 964 rpm */
    mc_dq_t i = mc_tref_step(&s, 0.0f, (float)rpm_to_we(950.0), (float)VDC);
    assert_false(s.fw_active);
    assert_near(i.d, 0.0, 1e-6);
    /* 1000 rpm: id = (u_max/w - psi)/Ld = (173.205/523.599 - 0.34305)/0.0105 = -1.1669 A */
    i = mc_tref_step(&s, 0.0f, (float)rpm_to_we(1000.0), (float)VDC);
    assert_true(s.fw_active);
    assert_false(s.i_limited);
    assert_near(i.d, -1.1669, 1e-3);
    assert_near(i.q, 0.0, 1e-6);
    /* u_margin scales the voltage and so the base speed: 0.9 * 964 = 868 rpm */
    make(&s, false, 0.9f);
    (void)mc_tref_step(&s, 0.0f, (float)rpm_to_we(860.0), (float)VDC);
    assert_false(s.fw_active);
    (void)mc_tref_step(&s, 0.0f, (float)rpm_to_we(875.0), (float)VDC);
    assert_true(s.fw_active);
}

static void test_field_weakening_holds_ellipse(void **state)
{
    (void)state;
    const bool modes[] = {false, true};
    for (int m = 0; m < 2; ++m) {
        mc_tref_t s;
        make(&s, modes[m], 1.0f);
        const double we = rpm_to_we(1500.0);
        const double t = 10.0;
        const double iq_m = ref_mtpa_iq(t);
        const double id_m = ref_mtpa_id(iq_m);
        assert_true(ref_u(id_m, iq_m, we) > UMAX);   /* MTPA is not feasible here */
        mc_dq_t i = mc_tref_step(&s, (float)t, (float)we, (float)VDC);
        assert_true(s.fw_active);
        assert_false(s.i_limited);
        assert_true(i.d < id_m - 1.0);
        assert_true(ref_u(i.d, i.q, we) <= UMAX * (1.0 + 1e-4));
        assert_true(ref_u(i.d, i.q, we) >= UMAX * (1.0 - 1e-3));   /* on the boundary, not deeper */
        assert_true(hypot(i.d, i.q) <= IMAX * (1.0 + 1e-6));
        assert_near(ref_torque(i.d, i.q), t, 2e-3 * t);
        /* motoring backwards (negative torque, negative speed): mirrored iq */
        mc_dq_t n = mc_tref_step(&s, (float)-t, (float)-we, (float)VDC);
        assert_near(n.d, i.d, 1e-5);
        assert_near(n.q, -i.q, 1e-5);
    }
}

/* Torque beyond the circle/ellipse intersection: both limits hold, torque reduced. */
static void test_field_weakening_circle_limit(void **state)
{
    (void)state;
    mc_tref_t s;
    make(&s, false, 1.0f);
    const double we = rpm_to_we(1400.0);
    mc_dq_t i = mc_tref_step(&s, 30.0f, (float)we, (float)VDC);
    assert_true(s.fw_active);
    assert_true(s.i_limited);
    assert_near(hypot(i.d, i.q), IMAX, 1e-3);                      /* on the circle   */
    assert_near(ref_u(i.d, i.q, we), UMAX, 1e-3 * UMAX);           /* and the ellipse */
    assert_true(ref_torque(i.d, i.q) < 30.0);

    /* above top speed (ellipse and circle no longer meet, about 1700 rpm): finite, all on d */
    i = mc_tref_step(&s, 10.0f, (float)rpm_to_we(3000.0), (float)VDC);
    assert_true(s.i_limited);
    assert_near(i.d, -IMAX, 1e-4);
    assert_near(i.q, 0.0, 1e-6);
}

/* Speed sweep 0 -> 2000 rpm in 0.5 rpm steps: no jumps at base speed, at the circle, at top
 * speed; MTPA below base speed, the ellipse above. */
static void test_continuity_across_base_speed(void **state)
{
    (void)state;
    const double torques[] = {5.0, 15.0, 30.0};
    for (int tk = 0; tk < 3; ++tk) {
        const double t = torques[tk];
        mc_tref_t s;
        make(&s, false, 1.0f);
        const double iq_m = ref_mtpa_iq(t);
        const double id_m = ref_mtpa_id(iq_m);
        const double w_base = UMAX / sqrt(LQ * LQ * iq_m * iq_m + (LD * id_m + PSI) * (LD * id_m + PSI)); /* (2.25) */
        mc_dq_t prev = {0.0f, 0.0f};
        int switches = 0;
        bool fw_prev = false;
        bool prev_lim = false;
        for (int k = 0; k <= 4000; ++k) {
            const double we = rpm_to_we(0.5 * k);
            mc_dq_t i = mc_tref_step(&s, (float)t, (float)we, (float)VDC);
            if (k > 0) {
                /* on the circle near top speed iq = sqrt(i_max^2 - id^2) has an infinite slope in
                 * id: continuous but steep, so compare iq^2 there */
                const bool on_circle = s.i_limited && prev_lim;
                const double dq = on_circle ? fabs(i.q * i.q - prev.q * prev.q) / 20.0
                                            : fabs(i.q - prev.q);
                if (!(fabs(i.d - prev.d) < 0.08 && dq < 0.08)) {
                    fail_msg("jump at %.1f rpm, T=%.0f: (%g,%g) -> (%g,%g)", 0.5 * k, t, prev.d,
                             prev.q, i.d, i.q);
                }
            }
            if (s.fw_active != fw_prev) {
                switches++;
                assert_near(we, w_base, 2e-3 * w_base);
            }
            fw_prev = s.fw_active;
            prev_lim = s.i_limited;
            if (!s.fw_active) {
                assert_near(i.d, id_m, 1e-3);
                assert_near(i.q, iq_m, 1e-3);
            } else if (!(s.i_limited && fabs(i.q) < 1e-6)) {
                assert_true(ref_u(i.d, i.q, we) <= UMAX * (1.0 + 1e-4));
                assert_true(i.d <= id_m + 1e-6);
            }
            if (!s.i_limited) {
                assert_near(ref_torque(i.d, i.q), t, 2e-3 * t);
            }
            assert_true(hypot(i.d, i.q) <= IMAX * (1.0 + 1e-6));
            prev = i;
        }
        assert_int_equal(switches, 1);
    }
}

/* Exact equality with a fresh block: the cached MTPA point must be the very one a new search finds. */
static void assert_same_as_fresh(mc_tref_t *s, const mc_tref_cfg_t *cfg, float t, float we, float vdc)
{
    mc_tref_t f;
    mc_tref_init(&f, cfg);
    const mc_dq_t a = mc_tref_step(s, t, we, vdc);
    const mc_dq_t b = mc_tref_step(&f, t, we, vdc);
    if (!(a.d == b.d && a.q == b.q && s->fw_active == f.fw_active && s->i_limited == f.i_limited)) {
        fail_msg("T=%g we=%g: (%.9g, %.9g, fw %d, lim %d) != fresh (%.9g, %.9g, fw %d, lim %d)", (double)t,
                 (double)we, (double)a.d, (double)a.q, s->fw_active, s->i_limited, (double)b.d, (double)b.q,
                 f.fw_active, f.i_limited);
    }
}

/* The MTPA point is solved once per |T| and reused: it must follow every change of |T|, of the
 * speed and voltage (field weakening is decided every call), and of the parameters (init). */
static void test_mtpa_cache_follows_inputs(void **state)
{
    (void)state;
    const bool modes[] = {false, true};
    for (int m = 0; m < 2; ++m) {
        mc_tref_t s;
        make(&s, modes[m], 1.0f);
        const mc_tref_cfg_t cfg = s.cfg;
        const float lo = (float)rpm_to_we(300.0);
        const float hi = (float)rpm_to_we(1500.0);
        assert_same_as_fresh(&s, &cfg, 20.0f, lo, (float)VDC);
        assert_true(s.mtpa_valid);
        assert_same_as_fresh(&s, &cfg, 20.0f, lo, (float)VDC);      /* hit                          */
        assert_same_as_fresh(&s, &cfg, 20.0f, hi, (float)VDC);      /* hit, now field weakening     */
        assert_true(s.fw_active);
        assert_same_as_fresh(&s, &cfg, 20.0f, lo, 0.5f * (float)VDC);   /* hit, other voltage      */
        assert_same_as_fresh(&s, &cfg, -20.0f, -lo, (float)VDC);    /* same |T|: mirrored           */
        assert_same_as_fresh(&s, &cfg, 20.000002f, lo, (float)VDC); /* one ulp more: solved again   */
        assert_true(s.mtpa_torque == 20.000002f);
        assert_same_as_fresh(&s, &cfg, 5.0f, lo, (float)VDC);       /* new |T|                      */
        assert_same_as_fresh(&s, &cfg, 50.0f, lo, (float)VDC);      /* beyond the circle: limited   */
        assert_true(s.i_limited);
        assert_same_as_fresh(&s, &cfg, 5.0f, lo, (float)VDC);       /* and back: limit cleared      */
        assert_false(s.i_limited);
        assert_same_as_fresh(&s, &cfg, NAN, lo, (float)VDC);        /* NaN counts as zero torque    */
        assert_same_as_fresh(&s, &cfg, 0.0f, lo, (float)VDC);
    }

    /* new parameters through mc_tref_init drop the cached point, even for the same |T| */
    mc_tref_t s;
    make(&s, false, 1.0f);
    const float we = (float)rpm_to_we(300.0);
    const mc_dq_t a = mc_tref_step(&s, 20.0f, we, (float)VDC);
    mc_tref_cfg_t cfg = s.cfg;
    cfg.mach.lq = 2.0f * (float)LQ;
    mc_tref_init(&s, &cfg);
    assert_false(s.mtpa_valid);
    assert_same_as_fresh(&s, &cfg, 20.0f, we, (float)VDC);
    const mc_dq_t b = mc_tref_step(&s, 20.0f, we, (float)VDC);
    assert_true(b.d < a.d - 0.1f);   /* more saliency, more negative id: really the new point */
    cfg.i_max = 5.0f;
    mc_tref_init(&s, &cfg);
    assert_same_as_fresh(&s, &cfg, 20.0f, we, (float)VDC);
    assert_true(s.i_limited);
    cfg.use_table = true;
    mc_mtpa_table_fill_linear(&cfg.table, &cfg.mach, 5.0f);
    mc_tref_init(&s, &cfg);
    assert_same_as_fresh(&s, &cfg, 20.0f, we, (float)VDC);
}

/* Field weakening starts exactly where the MTPA point leaves the ellipse by the exact test
 * mc_fw_id_max(iq) < id (2.26), although most calls decide it with a multiply-only shortcut:
 * speeds on both sides of the boundary down to one ulp, several torques and DC-link voltages. */
static void test_fw_decision_matches_exact_test(void **state)
{
    (void)state;
    const float torques[] = {0.0f, 1.0f, 12.5f, 30.0f, 50.0f};
    const float vdcs[] = {300.0f, 250.0f, 0.0f};
    for (int m = 0; m < 2; ++m) {
        for (size_t a = 0; a < sizeof torques / sizeof torques[0]; ++a) {
            for (size_t b = 0; b < sizeof vdcs / sizeof vdcs[0]; ++b) {
                mc_tref_t s;
                make(&s, m == 1, 0.95f);
                const float t = torques[a];
                const float vdc = vdcs[b];
                const mc_dq_t i0 = mc_tref_step(&s, t, 0.0f, vdc);   /* the MTPA point */
                const float u_max = 0.95f * vdc * 0.57735026918963f;
                /* bisect the exact predicate's switching speed to the last ulp */
                float lo = 0.0f;
                float hi = 3000.0f;
                for (int k = 0; k < 200; ++k) {
                    const float mid = 0.5f * (lo + hi);
                    if (mid <= lo || mid >= hi) {
                        break;
                    }
                    if (mc_fw_id_max(&s.cfg.mach, i0.q, mid, u_max) < i0.d) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                float w = lo;
                for (int k = 0; k < 64; ++k) {
                    w = nextafterf(w, 0.0f);
                }
                for (int k = 0; k < 128; ++k) {
                    (void)mc_tref_step(&s, t, w, vdc);
                    const bool exact = mc_fw_id_max(&s.cfg.mach, i0.q, w, u_max) < i0.d;
                    if (s.fw_active != exact) {
                        fail_msg("T %g vdc %g w %.9g: fw_active %d, exact test %d", (double)t,
                                 (double)vdc, (double)w, s.fw_active, exact);
                    }
                    w = nextafterf(w, INFINITY);
                }
                for (double f = 0.5; f < 1.5; f += 0.001) {
                    w = (float)(f * (double)lo);
                    (void)mc_tref_step(&s, t, w, vdc);
                    assert_true(s.fw_active == (mc_fw_id_max(&s.cfg.mach, i0.q, w, u_max) < i0.d));
                }
            }
        }
    }
}

/* The voltage feedback: at the voltage limit above half the base speed id goes further negative
 * by i_max per 10 ms (flux before torque inside the circle), back at a quarter of that rate;
 * below half the base speed, or not limited, it adds nothing; a NaN state adds nothing. */
static void test_fw_voltage_feedback(void **st)
{
    (void)st;
    mc_tref_t s;
    make(&s, false, 1.0f);
    const float we = (float)rpm_to_we(1200.0), ts = 1e-4f;
    const mc_dq_t r = {-8.0f, 6.0f};
    mc_dq_t o = r;
    for (int k = 0; k < 20; ++k) {
        o = mc_tref_fw_feedback(&s, r, true, we, (float)VDC);
    }
    assert_near(s.fw_did, -20.0 * 100.0 * IMAX * ts, 1e-4);    /* 2 ms: -2.658 A */
    assert_near(o.d, r.d + s.fw_did, 1e-5);
    assert_near(o.q, r.q, 1e-6);                                 /* still inside the circle */
    for (int k = 0; k < 200; ++k) {
        o = mc_tref_fw_feedback(&s, r, true, we, (float)VDC);
    }
    assert_near(o.d, -IMAX, 1e-5);                               /* at most i_max */
    assert_near(o.q, 0.0, 1e-3);                                 /* flux first */
    for (int k = 0; k < 400; ++k) {
        o = mc_tref_fw_feedback(&s, r, false, we, (float)VDC);
    }
    assert_near(s.fw_did, 0.0, 0.0);
    assert_near(o.d, r.d, 0.0);
    /* low speed: limited or not, nothing */
    o = mc_tref_fw_feedback(&s, r, true, (float)rpm_to_we(300.0), (float)VDC);
    assert_near(s.fw_did, 0.0, 0.0);
    s.fw_did = NAN;
    o = mc_tref_fw_feedback(&s, r, true, we, (float)VDC);
    assert_near(o.d, r.d, 0.0);
}

/* The voltage limit (2.20) depends on the ratio vdc / omega only: the same torque with the speed
 * and the bus both scaled down by the same factor, to a bus of a few mV near standstill, gives the
 * same reference, in MTPA (300 rpm) and in field weakening (1500 rpm, 10 N m; 1400 rpm, 30 N m on
 * the circle). */
static void test_voltage_limit_scales_with_bus(void **state)
{
    (void)state;
    const struct { double rpm, t; } pts[] = {{300.0, 20.0}, {1500.0, 10.0}, {1400.0, 30.0}};
    const double f[] = {1e-2, 1e-3, 1e-4};
    for (size_t k = 0; k < sizeof pts / sizeof pts[0]; ++k) {
        mc_tref_t s;
        make(&s, false, 1.0f);
        const double we = rpm_to_we(pts[k].rpm);
        const mc_dq_t i = mc_tref_step(&s, (float)pts[k].t, (float)we, (float)VDC);
        const bool fw = s.fw_active, lim = s.i_limited;
        for (size_t j = 0; j < sizeof f / sizeof f[0]; ++j) {
            const mc_dq_t g = mc_tref_step(&s, (float)pts[k].t, (float)(we * f[j]), (float)(VDC * f[j]));
            assert_near(g.d, i.d, 1e-3);
            assert_near(g.q, i.q, 1e-3);
            assert_int_equal(s.fw_active, fw);
            assert_int_equal(s.i_limited, lim);
        }
    }
}

/* An infinite speed reading is a speed beyond top speed whatever the bus reads, an infinite bus
 * one too: no torque current, all of it on -d (the ellipse shrinks to its centre -psi/Ld, beyond
 * the circle on this machine); an infinite bus at a finite speed bounds nothing: MTPA. */
static void test_infinite_speed_and_bus(void **state)
{
    (void)state;
    mc_tref_t s;
    make(&s, false, 1.0f);
    const float inf = INFINITY;
    const float ws[] = {inf, -inf};
    const float vs[] = {(float)VDC, inf};
    for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
            const mc_dq_t i = mc_tref_step(&s, 10.0f, ws[a], vs[b]);
            assert_true(s.fw_active);
            assert_true(s.i_limited);
            assert_near(i.d, -IMAX, 1e-4);
            assert_near(i.q, 0.0, 1e-6);
        }
    }
    const mc_dq_t m = mc_tref_step(&s, 10.0f, (float)rpm_to_we(1500.0), inf);
    const double iq = ref_mtpa_iq(10.0);
    assert_false(s.fw_active);
    assert_near(m.d, ref_mtpa_id(iq), 2e-3);
    assert_near(m.q, iq, 2e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_low_speed_is_mtpa),
        cmocka_unit_test(test_low_speed_table),
        cmocka_unit_test(test_current_circle),
        cmocka_unit_test(test_no_load_base_speed),
        cmocka_unit_test(test_field_weakening_holds_ellipse),
        cmocka_unit_test(test_field_weakening_circle_limit),
        cmocka_unit_test(test_continuity_across_base_speed),
        cmocka_unit_test(test_mtpa_cache_follows_inputs),
        cmocka_unit_test(test_fw_decision_matches_exact_test),
        cmocka_unit_test(test_fw_voltage_feedback),
        cmocka_unit_test(test_voltage_limit_scales_with_bus),
        cmocka_unit_test(test_infinite_speed_and_bus),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
