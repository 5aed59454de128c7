/* Step II polarity (5.6)-(5.7) and the DVI reference, after Step I, on the saturating plant. */
#include "ip_plant.h"

#include "mc/polarity.h"

static mc_flux_map_t g_map;   /* 13 kB: static rather than on the test stack */

static mc_ip_status_t step_ip(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    return mc_initpos_step((mc_initpos_t *)e, i, vdc, d);
}

static mc_ip_status_t step_pol(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    return mc_polarity_step((mc_polarity_t *)e, i, vdc, d);
}

static mc_ip_status_t step_dvi(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    return mc_dvi_step((mc_dvi_t *)e, i, vdc, d);
}

static mc_flux_model_t map_model(void)
{
    mc_flux_model_t m = {MC_FLUX_MAP, 0.0f, 0.0f, 0.0f, &g_map};
    return m;
}

static int setup(void **st)
{
    (void)st;
    fill_sun_map(&g_map);
    return 0;
}

/* Step I (linear cost, m = 5, the thesis choice) on the plant; returns theta1 */
static float step1(plant_t *p, int *calls)
{
    mc_initpos_cfg_t c;
    mc_initpos_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.ld = (float)SUN_LD;
    c.lq = (float)SUN_LQ;
    mc_initpos_t s;
    assert_true(mc_initpos_start(&s, &c));
    mc_ip_status_t st;
    *calls += plant_run(p, step_ip, &s, 400, &st);
    assert_int_equal(st, MC_IP_DONE);
    return s.theta1;
}

typedef struct {
    int wrong, n;
    double min_margin;    /* min over angles of |log(c1 / c2)| with the right sign */
    int calls_max;
} pol_stats_t;

static void sweep_pol(int sat, double noise, const mc_flux_model_t *model, pol_stats_t *ps,
                      int verbose)
{
    memset(ps, 0, sizeof *ps);
    ps->min_margin = 1e9;
    mc_polarity_cfg_t c;
    mc_polarity_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.model = *model;
    for (int a = 0; a < 360; a += 15) {
        plant_t p;
        plant_init(&p, sat, a);
        p.noise = noise;
        p.rng = 777u + (uint64_t)a;
        int calls = 0;
        float th1 = step1(&p, &calls);
        mc_polarity_t s;
        assert_true(mc_polarity_start(&s, &c, th1));
        mc_ip_status_t st;
        calls += plant_run(&p, step_pol, &s, 400, &st);
        assert_int_equal(st, MC_IP_DONE);
        assert_true(s.theta2 >= -(float)PI_D && s.theta2 < (float)PI_D);
        double e1 = err_mod_pi_deg(th1, a * DEG), e2 = err_mod_2pi_deg(s.theta2, a * DEG);
        /* the decision is right when theta2 lies within 90 deg of the true d axis */
        int ok = e2 < 90.0;
        ps->wrong += !ok;
        ps->n++;
        double lr = log((double)s.c2 / (double)s.c1);   /* > 0: north is delta */
        double margin = (e2 < 90.0) ? fabs(lr) : -fabs(lr);
        ps->min_margin = fmin(ps->min_margin, margin);
        if (calls > ps->calls_max) {
            ps->calls_max = calls;
        }
        if (verbose) {
            print_message("  %3d deg: theta1 err %5.1f, flip %d, c1 %.3g c2 %.3g, theta2 err %5.1f,"
                          " |V| %.1f V, %d calls%s\n", a, e1, (int)s.flip, (double)s.c1,
                          (double)s.c2, e2, (double)s.v_real, calls, ok ? "" : "  WRONG");
        }
    }
}

static void test_polarity_sweep(void **st)
{
    (void)st;
    mc_flux_model_t m = map_model();
    pol_stats_t ps;
    print_message("Step I (linear, m 5) + Step II (+4/-8/+4, 200 V), saturating machine:\n");
    sweep_pol(1, 0.0, &m, &ps, 1);
    print_message("noise-free: %d/%d wrong, min log margin %.3f, Step I+II %d calls = %.1f ms\n",
                  ps.wrong, ps.n, ps.min_margin, ps.calls_max, ps.calls_max * SUN_TS * 1e3);
    assert_int_equal(ps.wrong, 0);
    /* Step I + II within 5 ms (thesis 4.1 ms) */
    assert_true(ps.calls_max * SUN_TS <= 5e-3);
    sweep_pol(1, 0.02, &m, &ps, 0);
    print_message("0.02 A noise: %d/%d wrong, min log margin %.3f\n", ps.wrong, ps.n,
                  ps.min_margin);
    assert_int_equal(ps.wrong, 0);
}

/* Negative control: a symmetric profile (constant l_dd) gives c1 == c2, no decision (flip
 * false), so the sweep must then see wrong polarities - the check above can fail. */
static void test_polarity_needs_asymmetry(void **st)
{
    (void)st;
    mc_flux_model_t m = {MC_FLUX_CONST, (float)SUN_LD, (float)SUN_LQ, (float)SUN_PSI, NULL};
    pol_stats_t ps;
    sweep_pol(1, 0.0, &m, &ps, 0);
    print_message("symmetric profile: %d/%d wrong\n", ps.wrong, ps.n);
    assert_true(ps.wrong >= ps.n / 3);
}

/* Outcome counts of a sweep with the confidence check (z_min, i_max) */
typedef struct {
    int n, decided, undecided, wrong, retried;
    double z_min_decided;   /* smallest z among the decisions */
    double i_peak_max;      /* largest |i| any train drew [A] */
} conf_stats_t;

static void sweep_conf(double noise, const mc_flux_model_t *model, float z_min, float i_max,
                       uint64_t seed, conf_stats_t *cs)
{
    memset(cs, 0, sizeof *cs);
    cs->z_min_decided = 1e9;
    mc_polarity_cfg_t c;
    mc_polarity_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.model = *model;
    c.z_min = z_min;
    c.i_max = i_max;
    for (int a = 0; a < 360; a += 15) {
        plant_t p;
        plant_init(&p, 1, a);
        p.noise = noise;
        p.rng = seed + (uint64_t)a;
        int calls = 0;
        float th1 = step1(&p, &calls);
        mc_polarity_t s;
        assert_true(mc_polarity_start(&s, &c, th1));
        mc_ip_status_t st;
        plant_run(&p, step_pol, &s, 400, &st);
        cs->n++;
        cs->retried += s.tries > 1;
        cs->i_peak_max = fmax(cs->i_peak_max, (double)s.i_peak);
        if (st == MC_IP_DONE) {
            assert_int_equal(s.verdict, MC_POL_DECIDED);
            assert_true(s.z >= z_min);
            cs->decided++;
            cs->wrong += err_mod_2pi_deg(s.theta2, a * DEG) >= 90.0;
            cs->z_min_decided = fmin(cs->z_min_decided, (double)s.z);
        } else {
            assert_int_equal(st, MC_IP_FAILED);
            assert_int_equal(s.verdict, MC_POL_UNDECIDED);
            assert_true(s.z < z_min);
            cs->undecided++;
        }
    }
}

/* The saturating machine with its own map: every angle decided at z >= 3 in one train, also
 * with the realistic 0.02 A noise; the thesis' decisions are kept. */
static void test_polarity_confident(void **st)
{
    (void)st;
    mc_flux_model_t m = map_model();
    conf_stats_t cs;
    for (int k = 0; k < 2; ++k) {
        sweep_conf(k ? 0.02 : 0.0, &m, 3.0f, 20.0f, 777u, &cs);
        print_message("z_min 3, noise %.2f A: %d/%d decided (min z %.1f), %d retried, %d wrong\n",
                      k ? 0.02 : 0.0, cs.decided, cs.n, cs.z_min_decided, cs.retried, cs.wrong);
        assert_int_equal(cs.decided, cs.n);
        assert_int_equal(cs.wrong, 0);
        assert_int_equal(cs.retried, 0);
    }
}

/* A symmetric profile cannot decide: with the check every angle ends UNDECIDED (never the
 * silent guess of test_polarity_needs_asymmetry), after a retry. (The constant model has no
 * saturation, so the retry's current is not predicted: its peak is printed, not bounded.) */
static void test_polarity_symmetric_undecided(void **st)
{
    (void)st;
    mc_flux_model_t m = {MC_FLUX_CONST, (float)SUN_LD, (float)SUN_LQ, (float)SUN_PSI, NULL};
    conf_stats_t cs;
    sweep_conf(0.0, &m, 3.0f, 20.0f, 777u, &cs);
    print_message("symmetric profile, z_min 3: %d decided, %d undecided, %d retried, peak %.1f A\n",
                  cs.decided, cs.undecided, cs.retried, cs.i_peak_max);
    assert_int_equal(cs.undecided, cs.n);
    assert_int_equal(cs.retried, cs.n);
}

/* Heavy noise (0.2 A rms, 10x the realistic; 0.7 A on a 1.9 A current step of (5.6)): the check
 * may refuse, a retry with longer pulses rescues some, but a decision it takes is right. Without
 * the check the same trains guess wrong. The retry's peak (noise included) stays within the
 * issue's 1.1 x the limit. */
static void test_polarity_noise_never_wrong(void **st)
{
    (void)st;
    mc_flux_model_t m = map_model();
    conf_stats_t cs, blind;
    int wrong = 0, decided = 0, retried = 0, undecided = 0, wrong_blind = 0;
    double peak = 0.0;
    for (uint64_t seed = 1; seed <= 4; ++seed) {
        sweep_conf(0.2, &m, 3.0f, 20.0f, 1000u * seed, &cs);
        sweep_conf(0.2, &m, 0.0f, 0.0f, 1000u * seed, &blind);
        wrong += cs.wrong;
        decided += cs.decided;
        undecided += cs.undecided;
        retried += cs.retried;
        wrong_blind += blind.wrong;
        peak = fmax(peak, cs.i_peak_max);
    }
    print_message("0.2 A noise, 96 starts: z_min 3: %d decided, %d undecided, %d retried, %d wrong, "
                  "peak %.1f A; no check: %d wrong\n", decided, undecided, retried, wrong, peak,
                  wrong_blind);
    assert_int_equal(wrong, 0);
    assert_true(retried > 0);
    assert_true(decided > undecided);
    assert_true(peak <= 1.1 * 20.0);
    assert_true(wrong_blind > 0);   /* the noise is heavy enough to matter */
}

/* A current sample held for one period (a stuck conversion) inside the train: the interval it
 * closes shows no current change, so (5.6) has no slope there; it is left out of (5.7) (15 of the
 * 16 intervals used) and c1, c2 stay finite: a decision is taken. (The next interval then carries
 * two periods' change, half the slope, which may tip a blind (5.7) decision: its rightness is
 * the sweeps' business, not asserted here.) */
static void test_polarity_skips_a_flat_interval(void **st)
{
    (void)st;
    mc_polarity_cfg_t c;
    mc_polarity_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.model = map_model();
    for (int a = 0; a < 360; a += 30) {
        for (int hold = 4; hold <= 12; hold += 4) {
            plant_t p;
            plant_init(&p, 1, a);
            int calls = 0;
            const float th1 = step1(&p, &calls);
            mc_polarity_t s;
            assert_true(mc_polarity_start(&s, &c, th1));
            mc_ip_status_t stt = MC_IP_RUNNING;
            mc_ab_t last = {0.0f, 0.0f};
            for (int k = 0; k < 400 && stt == MC_IP_RUNNING; ++k) {
                mc_ab_t i = plant_sample(&p);
                if (k == hold) {
                    i = last;   /* the previous conversion once more */
                }
                last = i;
                mc_abc_t d;
                stt = mc_polarity_step(&s, i, (float)VDC, &d);
                plant_advance(&p, p.pending, VDC);
                p.pending = d;
            }
            assert_int_equal(stt, MC_IP_DONE);
            assert_int_equal(s.verdict, MC_POL_DECIDED);
            assert_int_equal(s.n_valid, 4 * c.n - 1);
            if (!isfinite(s.c1) || !isfinite(s.c2)) {
                fail_msg("%d deg, sample %d held: c1 %g, c2 %g", a, hold, (double)s.c1, (double)s.c2);
            }
        }
    }
}

static void test_hexagon_and_record(void **st)
{
    (void)st;
    mc_polarity_cfg_t c;
    mc_polarity_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.model = map_model();
    plant_t p;
    plant_init(&p, 1, 41.5);
    mc_polarity_t s;
    assert_true(mc_polarity_start(&s, &c, (float)(41.5 * DEG)));
    mc_ip_status_t stt;
    plant_run(&p, step_pol, &s, 400, &stt);
    assert_int_equal(stt, MC_IP_DONE);
    assert_near(s.v_real, 173.205 / cos(11.5 * DEG), 0.05);
    assert_int_equal(s.prog.n_rec, 16);
    assert_int_equal(s.n_valid, 16);
    assert_false(s.flip);
    /* (5.6) on the first interval: L ~ l_dd near 0 A, 10.5 mH within saturation */
    assert_near(s.l_diff[0], SUN_LD, 1.5e-3);
    /* the train is balanced: the current ends near rest */
    double iab[2];
    plant_iab(&p, iab);
    assert_true(hypot(iab[0], iab[1]) < 0.3);
    /* south-pole start: the same angle + 180 deg must flip */
    plant_init(&p, 1, 41.5 + 180.0);
    assert_true(mc_polarity_start(&s, &c, (float)(41.5 * DEG)));
    plant_run(&p, step_pol, &s, 400, &stt);
    assert_true(s.flip);
    assert_near(err_mod_2pi_deg(s.theta2, (41.5 + 180.0) * DEG), 0.0, 1e-3);
}

static void test_dvi(void **st)
{
    (void)st;
    mc_dvi_cfg_t c;
    mc_dvi_cfg_default(&c);
    c.rs = (float)SUN_RS;
    for (int pass = 0; pass < 2; ++pass) {
        double noise = pass ? 0.02 : 0.0;
        int wrong = 0, n = 0, calls_max = 0;
        double dmin = 1e9;
        for (int a = 0; a < 360; a += 15) {
            plant_t p;
            plant_init(&p, 1, a);
            p.noise = noise;
            p.rng = 99u + (uint64_t)a;
            int calls = 0;
            float th1 = step1(&p, &calls);
            mc_dvi_t s;
            assert_true(mc_dvi_start(&s, &c, th1));
            mc_ip_status_t stt;
            calls += plant_run(&p, step_dvi, &s, 400, &stt);
            assert_int_equal(stt, MC_IP_DONE);
            int ok = err_mod_2pi_deg(s.theta2, a * DEG) < 90.0;
            wrong += !ok;
            ++n;
            dmin = fmin(dmin, ok ? fabs(s.peak_pos - s.peak_neg) : -fabs(s.peak_pos - s.peak_neg));
            calls_max = calls > calls_max ? calls : calls_max;
        }
        print_message("DVI (6 Ts, 200 V) noise %.2f A: %d/%d wrong, min peak difference %.3f A, "
                      "Step I+DVI %d calls\n", noise, wrong, n, dmin, calls_max);
        if (pass == 0) {
            assert_int_equal(wrong, 0);
        }
    }
}

/* DVI with the confidence check: on a machine without saturation asymmetry (the linear plant)
 * the two pulses differ only by noise and the sequence's own 0.5 %: every start ends UNDECIDED
 * after reps_max programs, where the thesis' rule (the larger peak) guesses (wrong at a quarter
 * of the angles or more); with 0.2 A noise on the saturating plant most decide, all right. */
static void test_dvi_confidence(void **st)
{
    (void)st;
    mc_dvi_cfg_t c;
    mc_dvi_cfg_default(&c);
    c.rs = (float)SUN_RS;
    int decided[2] = {0, 0}, wrong[2] = {0, 0}, undecided[2] = {0, 0}, wrong_blind = 0, n = 0;
    for (int sat = 0; sat < 2; ++sat) {
        for (uint64_t seed = 1; seed <= (sat ? 4u : 1u); ++seed) {
            for (int a = 0; a < 360; a += 15) {
                for (int chk = 0; chk < 2; ++chk) {
                    plant_t p;
                    plant_init(&p, sat, a);
                    p.noise = sat ? 0.2 : 0.02;
                    p.rng = 31u * seed + (uint64_t)a;
                    int calls = 0;
                    float th1 = step1(&p, &calls);
                    c.z_min = chk ? 3.0f : 0.0f;
                    c.reps_max = chk ? 3 : 1;
                    mc_dvi_t s;
                    assert_true(mc_dvi_start(&s, &c, th1));
                    mc_ip_status_t stt;
                    plant_run(&p, step_dvi, &s, 1000, &stt);
                    const int ok = err_mod_2pi_deg(s.theta2, a * DEG) < 90.0;
                    if (!chk) {
                        assert_int_equal(stt, MC_IP_DONE);
                        wrong_blind += !sat && !ok;
                        continue;
                    }
                    n += sat;
                    if (stt == MC_IP_DONE) {
                        assert_int_equal(s.verdict, MC_POL_DECIDED);
                        assert_true(s.z >= 3.0f);
                        decided[sat]++;
                        wrong[sat] += !ok;
                    } else {
                        assert_int_equal(stt, MC_IP_FAILED);
                        assert_int_equal(s.verdict, MC_POL_UNDECIDED);
                        assert_int_equal(s.reps, 3);
                        undecided[sat]++;
                    }
                }
            }
        }
    }
    print_message("DVI z_min 3: linear plant %d decided / %d undecided; saturating, 0.2 A: %d decided, "
                  "%d undecided, %d wrong of %d (the larger peak alone, linear plant: %d wrong)\n", decided[0],
                  undecided[0], decided[1], undecided[1], wrong[1], n, wrong_blind);
    assert_int_equal(decided[0], 0);
    assert_int_equal(wrong[1], 0);
    assert_true(decided[1] > undecided[1]);
    assert_true(wrong_blind >= 6);   /* the larger peak alone guesses on the linear plant */
}

/* The thesis defaults (polarity.h; on structs full of garbage): Step II v_pol 200 V, half pulses
 * of 4 periods, l at the mean current, i_rest 0.3 A, no trip, no confidence check and no retry
 * (z_min 0, i_max 0), ts, rs unset and a constant model without a map; DVI 200 V pulses of 6
 * periods (7.2.2), gaps of 2..50 periods ending at 0.3 A, no check, one repetition. */
static void test_defaults(void **st)
{
    (void)st;
    mc_polarity_cfg_t c;
    memset(&c, 0xA5, sizeof c);
    mc_polarity_cfg_default(&c);
    assert_true(c.ts == 0.0f && c.rs == 0.0f);
    assert_int_equal(c.model.kind, MC_FLUX_CONST);
    assert_null(c.model.map);
    assert_true(c.v_pol == 200.0f);
    assert_int_equal(c.n, 4);
    assert_false(c.l_at_end);
    assert_true(c.i_rest == 0.3f && c.i_trip == 0.0f);
    assert_true(c.z_min == 0.0f && c.i_max == 0.0f);
    mc_dvi_cfg_t d;
    memset(&d, 0xA5, sizeof d);
    mc_dvi_cfg_default(&d);
    assert_true(d.rs == 0.0f && d.v == 200.0f);
    assert_int_equal(d.n, 6);
    assert_int_equal(d.gap_min, 2);
    assert_int_equal(d.gap_max, 50);
    assert_true(d.i_rest == 0.3f && d.i_trip == 0.0f && d.z_min == 0.0f);
    assert_int_equal(d.reps_max, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_polarity_skips_a_flat_interval),
        cmocka_unit_test(test_hexagon_and_record),
        cmocka_unit_test(test_polarity_sweep),
        cmocka_unit_test(test_polarity_needs_asymmetry),
        cmocka_unit_test(test_dvi),
        cmocka_unit_test(test_polarity_confident),
        cmocka_unit_test(test_polarity_symmetric_undecided),
        cmocka_unit_test(test_polarity_noise_never_wrong),
        cmocka_unit_test(test_dvi_confidence),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
