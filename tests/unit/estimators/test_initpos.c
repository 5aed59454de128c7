/* Step I initial position (5.5) / (7.1) against the simulated standstill plant of ip_plant.h. */
#include "ip_plant.h"

static mc_flux_map_t g_map;   /* 13 kB: static rather than on the test stack */
static int g_map_ready;

static const mc_flux_map_t *sun_map(void)
{
    if (!g_map_ready) {
        fill_sun_map(&g_map);
        g_map_ready = 1;
    }
    return &g_map;
}

static mc_ip_status_t step_ip(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    return mc_initpos_step((mc_initpos_t *)e, i, vdc, d);
}

static mc_initpos_cfg_t ip_cfg(mc_ip_cost_t cost, int m)
{
    mc_initpos_cfg_t c;
    mc_initpos_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.ld = (float)SUN_LD;
    c.lq = (float)SUN_LQ;
    c.model.kind = MC_FLUX_MAP;
    c.model.map = sun_map();
    c.cost = cost;
    c.m = m;
    return c;
}

/* run Step I on a fresh plant; returns the error modulo pi [deg] */
static double run_step1(const mc_initpos_cfg_t *c, int sat, double th_deg, double noise,
                        mc_initpos_t *s, plant_t *p)
{
    plant_init(p, sat, th_deg);
    p->noise = noise;
    assert_true(mc_initpos_start(s, c));
    mc_ip_status_t st;
    plant_run(p, step_ip, s, 400, &st);
    assert_int_equal(st, MC_IP_DONE);
    assert_true(s->theta1 >= 0.0f && s->theta1 < (float)PI_D);
    return err_mod_pi_deg(s->theta1, th_deg * DEG);
}

/* Shorter pulse vectors (v_pulse, for a motor whose current one period of 2/3 Vdc would take
 * past its limit): the same directions at the given magnitude. On the linear machine the peak
 * scales with the voltage (100 V against the 200 V of V(100) at 300 V: half), every angle is
 * still found, and the three directions (6 vectors) fit the runner's vector table. */
static void test_short_pulse_vectors(void **st)
{
    (void)st;
    for (int nd = 1; nd <= 3; nd += 2) {
        double peak[2] = {0.0, 0.0}, worst = 0.0;
        for (int k = 0; k < 2; ++k) {
            mc_initpos_cfg_t c = ip_cfg(MC_IP_COST_LINEAR, 5);
            c.n_dir = nd;
            c.v_pulse = k ? 100.0f : 0.0f;
            for (int a = 0; a < 360; a += 15) {
                mc_initpos_t s;
                plant_t p;
                double e = run_step1(&c, 0, a, 0.0, &s, &p);
                peak[k] = fmax(peak[k], (double)s.prog.run.i_peak);
                if (k) {
                    worst = fmax(worst, e);
                }
            }
        }
        print_message("n_dir %d: peak %.2f A at V(100), %.2f A at 100 V; worst error %.3f deg\n", nd,
                      peak[0], peak[1], worst);
        assert_float_equal(peak[1] / peak[0], 0.5, 0.02);
        assert_true(worst < 1.0);
    }
    mc_initpos_cfg_t c = ip_cfg(MC_IP_COST_LINEAR, 5);
    mc_initpos_t s;
    c.v_pulse = -1.0f;
    assert_false(mc_initpos_start(&s, &c));
    c.v_pulse = NAN;
    assert_false(mc_initpos_start(&s, &c));
}

static void test_vectors(void **st)
{
    (void)st;
    mc_duty_t d;
    mc_ip_direct(MC_IP_V100, 300.0f, &d);
    assert_near(d.a, 1.0, 0.0);
    assert_near(d.b, 0.0, 0.0);
    assert_near(d.u_real.alpha, 200.0, 1e-3);
    assert_near(d.u_real.beta, 0.0, 1e-3);
    mc_ip_direct(MC_IP_V010 | MC_IP_V001, 300.0f, &d);   /* V(011) = -V(100) */
    assert_near(d.u_real.alpha, -200.0, 1e-3);
    /* the hexagon in the thesis direction 41.5 deg: 173.2 / cos(11.5 deg) = 176.8 V */
    mc_ab_t u = {200.0f * cosf(41.5f * (float)DEG), 200.0f * sinf(41.5f * (float)DEG)};
    mc_svpwm(u, 300.0f, &d);
    double mag = hypot(d.u_real.alpha, d.u_real.beta);
    assert_near(mag, 173.205 / cos(11.5 * DEG), 0.05);
    assert_true(d.saturated);
    /* every direct pattern, written over that saturated result: the switches' states as duties,
     * the corner 2/3 vdc at 60 k deg (V(000), V(111): zero), never a scaled-back request */
    for (unsigned pat = 0u; pat < 8u; ++pat) {
        mc_ip_direct(pat, 300.0f, &d);
        assert_false(d.saturated);
        assert_true(d.a == ((pat & MC_IP_V100) ? 1.0f : 0.0f));
        assert_true(d.b == ((pat & MC_IP_V010) ? 1.0f : 0.0f));
        assert_true(d.c == ((pat & MC_IP_V001) ? 1.0f : 0.0f));
        const double va = d.a - 0.5, vb = d.b - 0.5, vc = d.c - 0.5;
        assert_near(d.u_real.alpha, 300.0 * (2.0 * va - vb - vc) / 3.0, 1e-3);
        assert_near(d.u_real.beta, 300.0 * (vb - vc) / sqrt(3.0), 1e-3);
        const double m = hypot(d.u_real.alpha, d.u_real.beta);
        assert_near(m, (pat == 0u || pat == 7u) ? 0.0 : 200.0, 1e-3);
        mc_svpwm(u, 300.0f, &d);
    }
}

/* The record must hold the vector that really acted between the two samples: with the plant's
 * one-period delay the first interval of V(100) shows alpha 200 V - Rs i and di = La^-1 u Ts. */
static void test_timing_record(void **st)
{
    (void)st;
    mc_initpos_cfg_t c = ip_cfg(MC_IP_COST_LINEAR, 5);
    mc_initpos_t s;
    plant_t p;
    double th = 30.0 * DEG;
    run_step1(&c, 0, 30.0, 0.0, &s, &p);
    assert_int_equal(s.prog.n_rec, 5);
    const mc_ip_rec_t *r = &s.prog.rec[0];
    assert_near(r->i0.alpha, 0.0, 1e-6);
    assert_near(r->ubar.alpha, 200.0 - 0.5 * SUN_RS * r->i1.alpha, 1e-3);
    assert_near(r->ubar.beta, -0.5 * SUN_RS * r->i1.beta, 1e-3);
    /* La^-1 u Ts, u = 200 V alpha (Rs small: 1 % tolerance) */
    double l1 = 0.5 * (SUN_LD + SUN_LQ), l2 = 0.5 * (SUN_LD - SUN_LQ);
    double a11 = l1 + l2 * cos(2 * th), a12 = l2 * sin(2 * th), a22 = l1 - l2 * cos(2 * th);
    double det = a11 * a22 - a12 * a12;
    assert_near(r->i1.alpha, a22 / det * 200.0 * SUN_TS, 0.01 * 200.0 * SUN_TS / SUN_LD);
    assert_near(r->i1.beta, -a12 / det * 200.0 * SUN_TS, 0.01 * 200.0 * SUN_TS / SUN_LD);
    /* the last interval closes 2 calls after its command: 4m pulse calls + 2 + search */
    assert_true(s.calls >= 4 * 5 + 2);
    /* cost at the minimum is the resistive trapezoid error only */
    double g_ok = s.cost_min;
    assert_true(g_ok < 1.0);

    /* negative control: a plant without the shadow-register delay breaks the voltage/current
     * pairing, and the fit shows it */
    plant_init(&p, 0, 30.0);
    p.no_delay = 1;
    assert_true(mc_initpos_start(&s, &c));
    mc_ip_status_t stt;
    plant_run(&p, step_ip, &s, 400, &stt);
    assert_int_equal(stt, MC_IP_DONE);
    print_message("timing: cost_min with delay %.3g V^2, without %.3g V^2\n", g_ok, s.cost_min);
    assert_true(s.cost_min > 1000.0 * (g_ok + 1e-3));
}

static void test_linear_sweep(void **st)
{
    (void)st;
    static const struct { int n_dir; bool all; } var[] = {{1, false}, {1, true}, {3, false}};
    for (unsigned v = 0; v < sizeof var / sizeof var[0]; ++v) {
        mc_initpos_cfg_t c = ip_cfg(MC_IP_COST_LINEAR, 5);
        c.n_dir = var[v].n_dir;
        c.all_pulses = var[v].all;
        double worst = 0.0;
        int calls = 0;
        for (int a = 0; a < 360; a += 15) {
            mc_initpos_t s;
            plant_t p;
            double e = run_step1(&c, 0, a, 0.0, &s, &p);
            worst = fmax(worst, e);
            calls = s.calls;
            assert_true(s.evals <= 36 + MC_IP_GS_MAX + 2);
        }
        print_message("linear model, linear cost, n_dir %d all %d: worst %.4f deg, %d calls\n",
                      var[v].n_dir, (int)var[v].all, worst, calls);
        assert_true(worst < 1.0);
    }
    /* the flux-model costs on the constant model must agree */
    for (int k = 1; k <= 2; ++k) {
        mc_initpos_cfg_t c = ip_cfg((mc_ip_cost_t)k, 5);
        c.model.kind = MC_FLUX_CONST;
        c.model.ld = (float)SUN_LD;
        c.model.lq = (float)SUN_LQ;
        c.model.psi_pm = (float)SUN_PSI;
        c.model.map = NULL;
        double worst = 0.0;
        for (int a = 0; a < 360; a += 15) {
            mc_initpos_t s;
            plant_t p;
            worst = fmax(worst, run_step1(&c, 0, a, 0.0, &s, &p));
        }
        print_message("linear model, cost %d on the constant model: worst %.4f deg\n", k, worst);
        assert_true(worst < 1.0);
    }
}

/* Table 7.1 on the saturating machine: mean error and current peak for m = 3, 4, 5. */
static void test_saturating_table(void **st)
{
    (void)st;
    static const char *name[3] = {"linear (5.5)", "nonlinear (7.1)", "flux diff"};
    double mean[3][3];
    print_message("saturating machine, sweep 0..345 deg step 15, noise-free\n");
    print_message("  m   cost              mean err   max err   I_peak [A]  [p.u. of 13.29 A]\n");
    for (int m = 3; m <= 5; ++m) {
        for (int k = 0; k < 3; ++k) {
            mc_initpos_cfg_t c = ip_cfg((mc_ip_cost_t)k, m);
            double sum = 0.0, worst = 0.0, ipk = 0.0;
            int n = 0;
            for (int a = 0; a < 360; a += 15) {
                mc_initpos_t s;
                plant_t p;
                double e = run_step1(&c, 1, a, 0.0, &s, &p);
                sum += e;
                worst = fmax(worst, e);
                ipk = fmax(ipk, p.i_phase_peak);
                ++n;
            }
            mean[m - 3][k] = sum / n;
            print_message("  %d   %-16s  %7.2f    %7.2f    %6.2f      %.2f\n", m, name[k],
                          mean[m - 3][k], worst, ipk, ipk / SUN_IRATED);
        }
    }
    for (int m = 0; m < 3; ++m) {
        /* the constant-parameter cost is biased by saturation; the model-based costs must be
         * clearly better (Table 7.1 trend) and both bounded */
        assert_true(mean[m][0] < 30.0);
        assert_true(mean[m][1] < mean[m][0]);
        assert_true(mean[m][2] < 2.0);
    }
}

static void test_noise_and_failures(void **st)
{
    (void)st;
    mc_initpos_cfg_t c = ip_cfg(MC_IP_COST_LINEAR, 5);
    double worst = 0.0;
    for (int a = 0; a < 360; a += 15) {
        mc_initpos_t s;
        plant_t p;
        worst = fmax(worst, run_step1(&c, 0, a, 0.02, &s, &p));
    }
    print_message("linear model, 0.02 A noise: worst %.3f deg\n", worst);
    assert_true(worst < 3.0);

    mc_initpos_t s;
    mc_abc_t d;
    mc_ab_t z = {0.0f, 0.0f};
    assert_true(mc_initpos_start(&s, &c));
    assert_int_equal(mc_initpos_step(&s, z, 0.0f, &d), MC_IP_FAILED);   /* no DC link */
    assert_near(d.a + d.b + d.c, 0.0, 0.0);
    assert_int_equal(mc_initpos_step(&s, z, 300.0f, &d), MC_IP_FAILED);   /* stays failed */
    assert_true(mc_initpos_start(&s, &c));
    mc_ab_t bad = {NAN, 0.0f};
    assert_int_equal(mc_initpos_step(&s, bad, 300.0f, &d), MC_IP_FAILED);
    /* over-current trip */
    c.i_trip = 5.0f;
    plant_t p;
    plant_init(&p, 0, 0.0);
    assert_true(mc_initpos_start(&s, &c));
    mc_ip_status_t stt;
    plant_run(&p, step_ip, &s, 400, &stt);
    assert_int_equal(stt, MC_IP_FAILED);
    /* invalid configurations */
    c = ip_cfg(MC_IP_COST_LINEAR, 5);
    c.m = 0;
    assert_false(mc_initpos_start(&s, &c));
    c = ip_cfg(MC_IP_COST_LINEAR, 8);
    c.n_dir = 3;
    c.all_pulses = true;   /* 96 records > MC_IP_REC_MAX */
    assert_false(mc_initpos_start(&s, &c));
}

/* The engine with a log of its calls: the last one that switched a pulse, the first one that
 * spent a cost evaluation (the search), and the periods of each direction's pulses. */
typedef struct {
    mc_initpos_t s;
    int n, pulses, last_pulse, first_search, gap_run, gaps;
} ip_watch_t;

static mc_ip_status_t step_watch(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    ip_watch_t *w = (ip_watch_t *)e;
    const mc_ip_status_t st = mc_initpos_step(&w->s, i, vdc, d);
    w->n++;
    if (d->a != 0.0f || d->b != 0.0f || d->c != 0.0f) {
        w->gaps += w->pulses > 0 && w->gap_run > 0;   /* a zero-vector run between two pulses */
        w->gap_run = 0;
        w->pulses++;
        w->last_pulse = w->n;
    } else {
        w->gap_run++;
    }
    if (w->first_search == 0 && w->s.evals > 0) {
        w->first_search = w->n;
    }
    return st;
}

/* The pulse program's timing, exactly: n_dir directions of 4m periods each, a zero-vector gap
 * (at least gap_min, until the current has decayed) BETWEEN two directions only, and the search
 * right after the last pulse: its interval's end sample is the next call. A gap after the last
 * direction would only delay Step I (the search runs with the outputs off anyway). */
static void test_pulse_program_length(void **st)
{
    (void)st;
    for (int nd = 1; nd <= 3; ++nd) {
        mc_initpos_cfg_t c = ip_cfg(MC_IP_COST_LINEAR, 5);
        c.n_dir = nd;
        ip_watch_t w;
        memset(&w, 0, sizeof w);
        plant_t p;
        plant_init(&p, 0, 30.0);
        assert_true(mc_initpos_start(&w.s, &c));
        mc_ip_status_t stt;
        plant_run(&p, step_watch, &w, 600, &stt);
        assert_int_equal(stt, MC_IP_DONE);
        assert_int_equal(w.pulses, nd * 4 * c.m);
        assert_int_equal(w.gaps, nd - 1);
        assert_true(w.last_pulse >= nd * 4 * c.m + (nd - 1) * c.gap_min);
        assert_int_equal(w.first_search, w.last_pulse + 1);
        assert_int_equal(w.s.prog.n_rec, nd * c.m);
        assert_int_equal(w.s.prog.run.n_seg, 3 * nd + (nd - 1));   /* V, -V twice as long, V; gaps */
    }
}

/* A gap in a pulse program lasts until the current has decayed to i_rest (at least two periods,
 * at most gap_max, then flagged): the next pulse must start from rest, or its di mixes in the
 * decay. The runner is fed a current that stays at 2 A until call `rest_at`. */
static int first_call_of_pulse2(int rest_at, bool *timeout)
{
    mc_ip_run_t r;
    mc_ip_run_init(&r, 0.0f, 0.5f, 0.0f, 12);
    assert_true(mc_ip_run_direct(&r, 1u, 2, 0));   /* V(100), 2 periods */
    assert_true(mc_ip_run_gap(&r, 1));
    assert_true(mc_ip_run_direct(&r, 2u, 1, 1));   /* V(010) */
    for (int n = 0; n < 40; ++n) {
        const mc_ab_t i = {(n >= 2 && n < rest_at) ? 2.0f : 0.0f, 0.0f};
        mc_abc_t d;
        mc_ip_rec_t rec;
        int tag;
        (void)mc_ip_run_step(&r, i, 300.0f, &d, &rec, &tag);
        if (d.b > 0.5f && d.a < 0.5f) {
            *timeout = r.decay_timeout;
            return n;
        }
    }
    fail_msg("pulse 2 never issued");
    return -1;
}

static void test_gap_waits_for_decay(void **st)
{
    (void)st;
    bool timeout = true;
    assert_int_equal(first_call_of_pulse2(8, &timeout), 8);   /* at the first sample at rest */
    assert_false(timeout);
    assert_int_equal(first_call_of_pulse2(3, &timeout), 4);   /* at rest at once: two periods */
    assert_false(timeout);
    assert_int_equal(first_call_of_pulse2(1000, &timeout), 2 + 12);   /* never: gap_max, flagged */
    assert_true(timeout);
}

/* The thesis defaults (initpos.h; on a struct full of garbage): m = 5, one direction, the linear
 * cost, a 36-point grid, a 0.05 deg bracket, 12 evaluations a call, gaps of 2..50 periods ending
 * at 0.3 A, no trip; ts, rs, ld, lq, the pulse voltage zero (the caller's) and no map. */
static void test_defaults(void **st)
{
    (void)st;
    mc_initpos_cfg_t c;
    memset(&c, 0xA5, sizeof c);
    mc_initpos_cfg_default(&c);
    assert_true(c.ts == 0.0f && c.rs == 0.0f && c.ld == 0.0f && c.lq == 0.0f && c.v_pulse == 0.0f);
    assert_int_equal(c.model.kind, MC_FLUX_CONST);
    assert_null(c.model.map);
    assert_int_equal(c.cost, MC_IP_COST_LINEAR);
    assert_int_equal(c.m, 5);
    assert_int_equal(c.n_dir, 1);
    assert_false(c.all_pulses);
    assert_int_equal(c.grid, 36);
    assert_near(c.tol, 0.05 * DEG, 1e-9);
    assert_int_equal(c.evals_per_call, 12);
    assert_int_equal(c.gap_min, 2);
    assert_int_equal(c.gap_max, 50);
    assert_true(c.i_rest == 0.3f && c.i_trip == 0.0f);
}

/* The search's work per period is bounded (the ISR budget): no call spends more than
 * evals_per_call cost evaluations, the search uses that budget (some call spends all of it), the
 * result comes with the call of the last evaluation, and a smaller budget spreads the same
 * search, to the same angle bit for bit, over more calls. */
typedef struct {
    mc_initpos_t s;
    int max_evals, calls_searching, n, last_eval_call, done_call;
} ip_budget_t;

static mc_ip_status_t step_budget(void *e, mc_ab_t i, float vdc, mc_abc_t *d)
{
    ip_budget_t *b = (ip_budget_t *)e;
    const int e0 = b->s.evals;
    const mc_ip_status_t st = mc_initpos_step(&b->s, i, vdc, d);
    const int spent = b->s.evals - e0;
    b->max_evals = spent > b->max_evals ? spent : b->max_evals;
    b->calls_searching += spent > 0;
    b->n++;
    b->last_eval_call = spent > 0 ? b->n : b->last_eval_call;
    b->done_call = (st == MC_IP_DONE && b->done_call == 0) ? b->n : b->done_call;
    return st;
}

static void test_search_budget(void **st)
{
    (void)st;
    for (int cost = 0; cost < 3; ++cost) {
        float theta[4];
        int evals[4], calls[4];
        const int budget[4] = {12, 5, 3, 1};
        for (int k = 0; k < 4; ++k) {
            mc_initpos_cfg_t c = ip_cfg((mc_ip_cost_t)cost, 5);
            c.evals_per_call = budget[k];
            ip_budget_t b;
            memset(&b, 0, sizeof b);
            plant_t p;
            plant_init(&p, cost != MC_IP_COST_LINEAR, 73.0);
            assert_true(mc_initpos_start(&b.s, &c));
            mc_ip_status_t stt;
            plant_run(&p, step_budget, &b, 1000, &stt);
            assert_int_equal(stt, MC_IP_DONE);
            assert_int_equal(b.max_evals, budget[k]);
            theta[k] = b.s.theta1;
            evals[k] = b.s.evals;
            calls[k] = b.calls_searching;
            /* every call but the last spends the whole budget; the result comes with the last
             * evaluation (no call spent on bookkeeping) */
            assert_int_equal(calls[k], (evals[k] + budget[k] - 1) / budget[k]);
            assert_int_equal(b.done_call, b.last_eval_call);
        }
        for (int k = 1; k < 4; ++k) {
            assert_true(theta[k] == theta[0]);
            assert_int_equal(evals[k], evals[0]);
            assert_true(calls[k] > calls[k - 1]);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_search_budget),
        cmocka_unit_test(test_vectors),
        cmocka_unit_test(test_short_pulse_vectors),
        cmocka_unit_test(test_timing_record),
        cmocka_unit_test(test_gap_waits_for_decay),
        cmocka_unit_test(test_linear_sweep),
        cmocka_unit_test(test_saturating_table),
        cmocka_unit_test(test_noise_and_failures),
        cmocka_unit_test(test_pulse_program_length),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
