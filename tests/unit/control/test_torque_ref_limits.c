/* Torque -> current references over the whole operating plane (torque_ref.c): on the
 * sun2016-ipm-5kw constants at Vdc = 300 V, every torque 0..40 N m at every speed 0..3000 rpm,
 * analytic MTPA and its table. Whatever is asked, the reference stays on or inside the current
 * circle (2.21) and on or inside the voltage ellipse (2.20), or, above top speed where the two no
 * longer meet, is all current on -d; it never gives more torque than asked, and exactly what is
 * asked when no limit is flagged; field weakening only lowers id below the MTPA point's (2.25).
 * The reference values are computed here in double from (2.8), (2.20), (2.24). */
#include <math.h>

#include "../mc_test.h"
#include "mc/torque_ref.h"

#define P 5
#define LD 10.5e-3
#define LQ 12.9e-3
#define PSI 0.34305
#define IMAX 13.29
#define VDC 300.0
#define UMAX (VDC / sqrt(3.0))

static double rpm_to_we(double rpm) { return rpm * 2.0 * PI_D / 60.0 * P; }
static double ref_torque(double id, double iq) { return 1.5 * P * (PSI * iq + (LD - LQ) * id * iq); }
static double ref_mtpa_id(double iq)
{
    const double dl = LQ - LD;
    return (PSI - sqrt(PSI * PSI + 4.0 * dl * dl * iq * iq)) / (2.0 * dl);
}
static double ref_mtpa_iq(double t)
{
    double lo = 0.0, hi = 3.0 * IMAX;
    for (int k = 0; k < 200; ++k) {
        const double m = 0.5 * (lo + hi);
        if (ref_torque(ref_mtpa_id(m), m) < t) {
            lo = m;
        } else {
            hi = m;
        }
    }
    return 0.5 * (lo + hi);
}
static double ref_u(double id, double iq, double we)
{
    return fabs(we) * sqrt(LQ * LQ * iq * iq + (LD * id + PSI) * (LD * id + PSI));
}

static void make(mc_tref_t *s, bool table)
{
    mc_tref_cfg_t c = {0};
    c.pole_pairs = P;
    c.mach.ld = (float)LD;
    c.mach.lq = (float)LQ;
    c.mach.psi_pm = (float)PSI;
    c.i_max = (float)IMAX;
    c.u_margin = 1.0f;
    c.use_table = table;
    c.ts = 1e-4f;
    mc_mtpa_table_fill_linear(&c.table, &c.mach, (float)IMAX);
    mc_tref_init(s, &c);
}

static void test_operating_plane(void **state)
{
    (void)state;
    for (int m = 0; m < 2; ++m) {
        mc_tref_t s;
        make(&s, m == 1);
        uint32_t fw = 0u, top = 0u, limited = 0u;
        for (double rpm = 0.0; rpm <= 3000.0; rpm += 50.0) {
            const double we = rpm_to_we(rpm);
            for (double t = 0.0; t <= 40.0; t += 2.5) {
                const mc_dq_t i = mc_tref_step(&s, (float)t, (float)we, (float)VDC);
                const double mag = hypot(i.d, i.q);
                if (!(mag <= IMAX * (1.0 + 1e-6))) {
                    fail_msg("%s %g rpm %g N m: |i| = %g", m ? "table" : "analytic", rpm, t, mag);
                }
                const bool all_d = fabs(i.q) < 1e-6 && fabs(i.d + IMAX) < 1e-4;
                const double u = ref_u(i.d, i.q, we);
                if (all_d) {
                    ++top;
                    assert_true(s.i_limited);
                    /* only where circle and ellipse do not meet: the ellipse's d-axis point
                     * at iq = 0 lies beyond -i_max */
                    assert_true((UMAX / we - PSI) / LD < -IMAX);
                } else if (!(u <= UMAX * (1.0 + 1e-3))) {
                    fail_msg("%s %g rpm %g N m: (%g, %g) A needs %g V > %g V", m ? "table" : "analytic", rpm, t,
                             (double)i.d, (double)i.q, u, UMAX);
                }
                const double tq = ref_torque(i.d, i.q);
                if (!(tq <= t * (1.0 + 2e-3) + 1e-3)) {
                    fail_msg("%s %g rpm %g N m: gives %g N m", m ? "table" : "analytic", rpm, t, tq);
                }
                if (!s.i_limited && !(fabs(tq - t) <= 2e-3 * t + 1e-3)) {
                    fail_msg("%s %g rpm %g N m: gives %g N m, no limit flagged", m ? "table" : "analytic", rpm, t, tq);
                }
                limited += s.i_limited;
                /* field weakening lowers id below the MTPA point's, never raises it */
                const double iq_m = ref_mtpa_iq(t);
                const double id_m = ref_mtpa_id(iq_m);
                if (s.fw_active) {
                    ++fw;
                    if (!(i.d <= id_m + 1e-3 * IMAX)) {
                        fail_msg("%s %g rpm %g N m: id %g above MTPA's %g", m ? "table" : "analytic", rpm, t, (double)i.d, id_m);
                    }
                } else if (hypot(id_m, iq_m) <= IMAX) {
                    if (!(fabs(i.d - id_m) <= 0.02 && fabs(i.q - iq_m) <= 0.02)) {
                        fail_msg("%s %g rpm %g N m: (%g, %g) A is not MTPA (%g, %g)", m ? "table" : "analytic", rpm, t,
                                 (double)i.d, (double)i.q, id_m, iq_m);
                    }
                }
                /* the same request with both signs mirrored: iq mirrored */
                const mc_dq_t n = mc_tref_step(&s, (float)-t, (float)-we, (float)VDC);
                if (!(fabs(n.d - i.d) <= 1e-5 && fabs(n.q + i.q) <= 1e-5)) {
                    fail_msg("%s %g rpm %g N m: mirrored (%g, %g) vs (%g, %g)", m ? "table" : "analytic", rpm, t,
                             (double)n.d, (double)n.q, (double)i.d, (double)i.q);
                }
            }
        }
        /* the sweep covers MTPA, field weakening, the circle and the top speed */
        assert_true(fw > 100u);
        assert_true(top > 20u);
        assert_true(limited > top + 20u);
    }
}

/* The same plane on two other machines the drive supports: a strongly salient one whose magnet
 * flux is small (Lq = 4 Ld, characteristic current psi/Ld = i_max: the field-weakening point can
 * sit far right of the MTPA id at low q current), and a surface-magnet one (Ld = Lq: MTPA is
 * id = 0; psi/Ld = 25 A > i_max: without a max-torque-per-voltage region, which torque_ref.c
 * does not plan for). Whatever is asked at 48 V, the reference
 * stays in the circle and the ellipse, never magnetizes beyond the MTPA point's id, gives the
 * torque asked when no limit is flagged and, when flagged in field weakening, sits on the
 * ellipse (the most the machine can give there). */
typedef struct { const char *name; double ld, lq, psi, imax; int p; } tr_mach_t;

static double m_torque(const tr_mach_t *m, double id, double iq) { return 1.5 * m->p * (m->psi * iq + (m->ld - m->lq) * id * iq); }
static double m_mtpa_id(const tr_mach_t *m, double iq)
{
    const double dl = m->lq - m->ld;
    return dl == 0.0 ? 0.0 : (m->psi - sqrt(m->psi * m->psi + 4.0 * dl * dl * iq * iq)) / (2.0 * dl);
}
static double m_mtpa_iq(const tr_mach_t *m, double t)
{
    double lo = 0.0, hi = 3.0 * m->imax;
    for (int k = 0; k < 200; ++k) {
        const double x = 0.5 * (lo + hi);
        if (m_torque(m, m_mtpa_id(m, x), x) < t) {
            lo = x;
        } else {
            hi = x;
        }
    }
    return 0.5 * (lo + hi);
}
static double m_u(const tr_mach_t *m, double id, double iq, double we)
{
    return fabs(we) * sqrt(m->lq * m->lq * iq * iq + (m->ld * id + m->psi) * (m->ld * id + m->psi));
}

static void test_operating_plane_other_machines(void **state)
{
    (void)state;
    static const tr_mach_t machines[] = {{"salient", 5e-3, 20e-3, 0.05, 10.0, 2}, {"spm", 2e-3, 2e-3, 0.05, 20.0, 4}};
    const double vdc = 48.0, umax = vdc / sqrt(3.0);
    for (size_t mk = 0; mk < sizeof machines / sizeof machines[0]; ++mk) {
        const tr_mach_t *m = &machines[mk];
        const double t_max = m_torque(m, m_mtpa_id(m, m->imax), m->imax) * 1.3;   /* beyond the circle */
        const double w_base = umax / (m->psi + m->ld * m->imax);
        for (int tb = 0; tb < 2; ++tb) {
            mc_tref_cfg_t c = {0};
            c.pole_pairs = m->p;
            c.mach = (mc_lin_params_t){.ld = (float)m->ld, .lq = (float)m->lq, .psi_pm = (float)m->psi};
            c.i_max = (float)m->imax;
            c.u_margin = 1.0f;
            c.use_table = tb == 1;
            c.ts = 1e-4f;
            mc_mtpa_table_fill_linear(&c.table, &c.mach, (float)m->imax);
            mc_tref_t s;
            mc_tref_init(&s, &c);
            uint32_t fw = 0u, fw_limited = 0u;
            for (int iw = 0; iw <= 120; ++iw) {
                const double we = 6.0 * w_base * iw / 120.0;
                for (int it = 0; it <= 40; ++it) {
                    const double t = t_max * it / 40.0;
                    const mc_dq_t i = mc_tref_step(&s, (float)t, (float)we, (float)vdc);
                    const double tq = m_torque(m, i.d, i.q), u = m_u(m, i.d, i.q, we);
                    const double iq_m = m_mtpa_iq(m, t), id_m = m_mtpa_id(m, iq_m);
                    const bool in_circle = hypot(id_m, iq_m) <= m->imax;   /* the MTPA point itself */
                    if (!(hypot(i.d, i.q) <= m->imax * (1.0 + 1e-6)) || !(u <= umax * (1.0 + 1e-3)) ||
                        !(tq <= t * (1.0 + 2e-3) + 1e-3) || !(i.d <= 1e-6) ||
                        (s.fw_active && in_circle && !(i.d <= id_m + 1e-3 * m->imax)) ||
                        (!s.i_limited && !(fabs(tq - t) <= 2e-3 * t + 1e-3)) ||
                        (s.fw_active && s.i_limited && !(u >= umax * (1.0 - 1e-3)))) {
                        fail_msg("%s %s %.1f rad/s %.3f N m: (%g, %g) A, %g N m, %g V of %g, fw %d limited %d",
                                 m->name, tb ? "table" : "analytic", we, t, (double)i.d, (double)i.q, tq, u, umax,
                                 s.fw_active, s.i_limited);
                    }
                    fw += s.fw_active;
                    fw_limited += s.fw_active && s.i_limited;
                    const mc_dq_t n = mc_tref_step(&s, (float)-t, (float)-we, (float)vdc);
                    assert_true(fabs(n.d - i.d) <= 1e-5 && fabs(n.q + i.q) <= 1e-5);
                }
            }
            assert_true(fw > 500u && fw_limited > 200u);   /* the sweep reaches both */
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_operating_plane),
        cmocka_unit_test(test_operating_plane_other_machines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
