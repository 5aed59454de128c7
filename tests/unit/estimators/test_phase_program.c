/* Phase-program interface (mc/phase_program.h): each program driven through the interface on
 * the standstill plant of ip_plant.h gives, period by period, the same duties and in the end the
 * same result, bit for bit, as its engine driven through its own API; the shared workspace
 * stays within its budget; a bad configuration is refused. */
#include "ip_plant.h"

#include "mc/phase_program.h"

static mc_flux_map_t g_map;   /* 13 kB: static rather than on the test stack */
static mc_phase_t g_ph;       /* the interface path */
static mc_phase_ws_t g_ref;   /* the direct path (any engine fits the union) */

static int setup(void **st)
{
    (void)st;
    fill_sun_map(&g_map);
    return 0;
}

static mc_flux_model_t map_model(void)
{
    mc_flux_model_t m = {MC_FLUX_MAP, 0.0f, 0.0f, 0.0f, &g_map};
    return m;
}

static int same_f(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static mc_ip_status_t d_ip1(void *e, mc_ab_t i, float v, mc_abc_t *d)
{
    return mc_initpos_step((mc_initpos_t *)e, i, v, d);
}
static mc_ip_status_t d_p3(void *e, mc_ab_t i, float v, mc_abc_t *d)
{
    return mc_pulse3_step((mc_pulse3_t *)e, i, v, d);
}
static mc_ip_status_t d_pol(void *e, mc_ab_t i, float v, mc_abc_t *d)
{
    return mc_polarity_step((mc_polarity_t *)e, i, v, d);
}
static mc_ip_status_t d_dvi(void *e, mc_ab_t i, float v, mc_abc_t *d)
{
    return mc_dvi_step((mc_dvi_t *)e, i, v, d);
}

static int g_steps;   /* step calls the last lockstep made (PWM periods), the final one included */

/* Run the direct engine on plant pa and the program on plant pb (identical copies) in lockstep;
 * every period the duties and the status must agree exactly. Returns the final status. */
static mc_ip_status_t lockstep(plant_t *pa, plant_t *pb, ip_step_fn f, void *eng, int max_calls)
{
    mc_ip_status_t sa = MC_IP_RUNNING, sb = MC_IP_RUNNING;
    g_steps = 0;
    for (int n = 0; n < max_calls && sa == MC_IP_RUNNING; ++n) {
        ++g_steps;
        mc_ab_t ia = plant_sample(pa), ib = plant_sample(pb);
        assert_true(same_f(ia.alpha, ib.alpha) && same_f(ia.beta, ib.beta));
        mc_abc_t da;
        sa = f(eng, ia, (float)VDC, &da);
        mc_phase_in_t in = {ib, (float)VDC};
        mc_phase_out_t out;
        sb = mc_phase_step(&g_ph, &in, &out);
        assert_int_equal(sa, sb);
        assert_true(same_f(da.a, out.duty.a) && same_f(da.b, out.duty.b) &&
                    same_f(da.c, out.duty.c));
        plant_advance(pa, pa->pending, VDC);
        pa->pending = da;
        plant_advance(pb, pb->pending, VDC);
        pb->pending = out.duty;
    }
    return sa;
}

static void two_plants(plant_t *pa, plant_t *pb, int sat, double th_deg, double noise)
{
    plant_init(pa, sat, th_deg);
    pa->noise = noise;
    pa->rng = 31u + (uint64_t)(th_deg + 360.0);
    *pb = *pa;
}

static mc_initpos_cfg_t ip1_cfg(mc_ip_cost_t cost)
{
    mc_initpos_cfg_t c;
    mc_initpos_cfg_default(&c);
    c.ts = (float)SUN_TS;
    c.rs = (float)SUN_RS;
    c.ld = (float)SUN_LD;
    c.lq = (float)SUN_LQ;
    c.model = map_model();
    c.cost = cost;
    return c;
}

static void check_common(const mc_phase_result_t *r, float i_peak, int calls)
{
    assert_true(same_f(r->i_peak, i_peak));
    assert_true(r->i_peak > 0.0f);
    assert_int_equal(r->calls, calls);
    /* ... and that is the periods the program took: every step call until it ended */
    assert_int_equal(r->calls, g_steps);
    /* the catch's fields stay zero for the standstill programs */
    assert_true(r->omega == 0.0f);
    assert_false(r->moving);
}

static void test_step1_pulses(void **st)
{
    (void)st;
    int n = 0;
    for (int cost = 0; cost < 3; ++cost) {
        for (int a = 0; a < 360; a += 35) {
            mc_initpos_cfg_t c = ip1_cfg((mc_ip_cost_t)cost);
            c.n_dir = 1 + a % 3;
            plant_t pa, pb;
            /* the constant-parameter cost (5.5) only on the linear machine (saturation biases
             * it by tens of degrees, Table 7.1), the model costs on the saturating one */
            two_plants(&pa, &pb, cost != MC_IP_COST_LINEAR, a, (a % 2) ? 0.02 : 0.0);
            assert_true(mc_initpos_start(&g_ref.ip1, &c));
            assert_true(mc_phase_begin(&g_ph, &mc_phase_step1_pulses, &c, 0.0f));
            assert_int_equal(lockstep(&pa, &pb, d_ip1, &g_ref.ip1, 600), MC_IP_DONE);
            mc_phase_result_t r;
            mc_phase_result(&g_ph, &r);
            const mc_initpos_t *s = &g_ref.ip1;
            assert_true(same_f(r.theta, s->theta1));
            assert_true(same_f(r.theta_aux, s->theta_full));
            assert_true(same_f(r.c1, s->cost_min));
            assert_false(r.flip);
            check_common(&r, s->prog.run.i_peak, s->calls);
            assert_true(err_mod_pi_deg(r.theta, a * DEG) < 10.0);
            ++n;
        }
    }
    print_message("step1_pulses: %d runs identical to mc_initpos_*\n", n);
}

static void test_step1_pulse3(void **st)
{
    (void)st;
    int n = 0;
    for (int len = 3; len <= 6; ++len) {
        for (int a = 0; a < 360; a += 25) {
            mc_pulse3_cfg_t c;
            mc_pulse3_cfg_default(&c);
            c.rs = (float)SUN_RS;
            c.n = len;
            plant_t pa, pb;
            two_plants(&pa, &pb, len & 1, a, (a % 2) ? 0.02 : 0.0);
            assert_true(mc_pulse3_start(&g_ref.pulse3, &c));
            assert_true(mc_phase_begin(&g_ph, &mc_phase_step1_pulse3, &c, 0.0f));
            assert_int_equal(lockstep(&pa, &pb, d_p3, &g_ref.pulse3, 900), MC_IP_DONE);
            mc_phase_result_t r;
            mc_phase_result(&g_ph, &r);
            const mc_pulse3_t *s = &g_ref.pulse3;
            assert_true(same_f(r.theta, s->theta));
            assert_true(same_f(r.theta_aux, s->theta_atan));
            assert_false(r.flip);
            check_common(&r, s->prog.i_peak, s->calls);
            ++n;
        }
    }
    print_message("step1_pulse3: %d runs identical to mc_pulse3_*\n", n);
}

/* Step II after a direct Step I on the same plant (theta1 from the engine) */
static float plant_step1(plant_t *p)
{
    mc_initpos_cfg_t c = ip1_cfg(MC_IP_COST_LINEAR);
    static mc_initpos_t s;
    assert_true(mc_initpos_start(&s, &c));
    mc_ip_status_t stt;
    plant_run(p, d_ip1, &s, 400, &stt);
    assert_int_equal(stt, MC_IP_DONE);
    return s.theta1;
}

static void test_step2_polarity(void **st)
{
    (void)st;
    int n = 0, flips = 0;
    for (int lend = 0; lend < 2; ++lend) {
        for (int a = 0; a < 360; a += 20) {
            mc_polarity_cfg_t c;
            mc_polarity_cfg_default(&c);
            c.ts = (float)SUN_TS;
            c.rs = (float)SUN_RS;
            c.model = map_model();
            c.l_at_end = lend;
            plant_t pa, pb;
            two_plants(&pa, &pb, 1, a, (a % 40) ? 0.0 : 0.02);
            float th1 = plant_step1(&pa);
            pb = pa;
            assert_true(mc_polarity_start(&g_ref.pol, &c, th1));
            assert_true(mc_phase_begin(&g_ph, &mc_phase_step2_polarity, &c, th1));
            assert_int_equal(lockstep(&pa, &pb, d_pol, &g_ref.pol, 400), MC_IP_DONE);
            mc_phase_result_t r;
            mc_phase_result(&g_ph, &r);
            const mc_polarity_t *s = &g_ref.pol;
            assert_true(same_f(r.theta, s->theta2));
            assert_true(same_f(r.theta_aux, th1));
            assert_true(r.flip == s->flip);
            assert_true(same_f(r.c1, s->c1) && same_f(r.c2, s->c2));
            check_common(&r, s->prog.i_peak, s->calls);
            assert_true(err_mod_2pi_deg(r.theta, a * DEG) < 90.0);
            flips += r.flip;
            ++n;
        }
    }
    print_message("step2_polarity: %d runs identical to mc_polarity_* (%d flipped)\n", n, flips);
    assert_true(flips > 0 && flips < n);
}

static void test_step2_dvi(void **st)
{
    (void)st;
    int n = 0, flips = 0;
    for (int len = 4; len <= 8; len += 2) {
        for (int a = 0; a < 360; a += 30) {
            mc_dvi_cfg_t c;
            mc_dvi_cfg_default(&c);
            c.rs = (float)SUN_RS;
            c.n = len;
            plant_t pa, pb;
            two_plants(&pa, &pb, 1, a, 0.0);
            float th1 = plant_step1(&pa);
            pb = pa;
            assert_true(mc_dvi_start(&g_ref.dvi, &c, th1));
            assert_true(mc_phase_begin(&g_ph, &mc_phase_step2_dvi, &c, th1));
            assert_int_equal(lockstep(&pa, &pb, d_dvi, &g_ref.dvi, 600), MC_IP_DONE);
            mc_phase_result_t r;
            mc_phase_result(&g_ph, &r);
            const mc_dvi_t *s = &g_ref.dvi;
            assert_true(same_f(r.theta, s->theta2));
            assert_true(same_f(r.theta_aux, th1));
            assert_true(r.flip == s->flip);
            assert_true(same_f(r.c1, s->peak_pos) && same_f(r.c2, s->peak_neg));
            check_common(&r, s->prog.i_peak, s->calls);
            flips += r.flip;
            ++n;
        }
    }
    print_message("step2_dvi: %d runs identical to mc_dvi_* (%d flipped)\n", n, flips);
    assert_true(flips > 0 && flips < n);
}

/* The drive's sequence through one holder: Step I, then Step II begun on the same workspace
 * with theta1 from the Step I result (what startup.c does with two engines). */
static void test_chain_one_workspace(void **st)
{
    (void)st;
    mc_initpos_cfg_t c1 = ip1_cfg(MC_IP_COST_FLUXDIFF);
    mc_polarity_cfg_t c2;
    mc_polarity_cfg_default(&c2);
    c2.ts = (float)SUN_TS;
    c2.rs = (float)SUN_RS;
    c2.model = map_model();
    for (int a = 0; a < 360; a += 45) {
        plant_t p;
        plant_init(&p, 1, a);
        const mc_phase_program_t *seq[2] = {&mc_phase_step1_pulses, &mc_phase_step2_polarity};
        const void *cfg[2] = {&c1, &c2};
        float theta = 0.0f;
        int calls = 0;
        for (int k = 0; k < 2; ++k) {
            assert_true(mc_phase_begin(&g_ph, seq[k], cfg[k], theta));
            mc_ip_status_t stt = MC_IP_RUNNING;
            while (stt == MC_IP_RUNNING && calls < 1000) {
                mc_phase_in_t in = {plant_sample(&p), (float)VDC};
                mc_phase_out_t out;
                stt = mc_phase_step(&g_ph, &in, &out);
                plant_advance(&p, p.pending, VDC);
                p.pending = out.duty;
                ++calls;
            }
            assert_int_equal(stt, MC_IP_DONE);
            mc_phase_result_t r;
            mc_phase_result(&g_ph, &r);
            theta = r.theta;
        }
        assert_true(err_mod_2pi_deg(theta, a * DEG) < 2.0);   /* d axis and its polarity */
    }
}

static void test_sizes(void **st)
{
    (void)st;
    print_message("sizeof mc_phase_ws_t %zu (budget %d): mc_initpos_t %zu, mc_pulse3_t %zu, "
                  "mc_polarity_t %zu, mc_dvi_t %zu; mc_ip_run_t %zu, mc_ip_prog_t %zu, "
                  "mc_phase_t %zu\n", sizeof(mc_phase_ws_t), MC_PHASE_WS_BUDGET,
                  sizeof(mc_initpos_t), sizeof(mc_pulse3_t), sizeof(mc_polarity_t),
                  sizeof(mc_dvi_t), sizeof(mc_ip_run_t), sizeof(mc_ip_prog_t),
                  sizeof(mc_phase_t));
    assert_true(sizeof(mc_phase_ws_t) <= MC_PHASE_WS_BUDGET);
    assert_true(sizeof(mc_initpos_t) <= sizeof(mc_phase_ws_t));
    assert_true(sizeof(mc_pulse3_t) <= sizeof(mc_phase_ws_t));
    assert_true(sizeof(mc_polarity_t) <= sizeof(mc_phase_ws_t));
    assert_true(sizeof(mc_dvi_t) <= sizeof(mc_phase_ws_t));
    /* the descriptors are complete */
    const mc_phase_program_t *all[4] = {&mc_phase_step1_pulses, &mc_phase_step1_pulse3,
                                        &mc_phase_step2_polarity, &mc_phase_step2_dvi};
    const size_t cfgsz[4] = {sizeof(mc_initpos_cfg_t), sizeof(mc_pulse3_cfg_t),
                             sizeof(mc_polarity_cfg_t), sizeof(mc_dvi_cfg_t)};
    for (int k = 0; k < 4; ++k) {
        assert_non_null(all[k]->name);
        assert_non_null(all[k]->begin);
        assert_non_null(all[k]->step);
        assert_non_null(all[k]->result);
        assert_int_equal(all[k]->cfg_size, cfgsz[k]);
    }
}

/* a bad or missing configuration: begin false, then only FAILED with V(000) */
static void expect_dead(void)
{
    mc_phase_in_t in = {{0.0f, 0.0f}, (float)VDC};
    mc_phase_out_t out = {{0.5f, 0.5f, 0.5f}, true};
    assert_int_equal(mc_phase_step(&g_ph, &in, &out), MC_IP_FAILED);
    assert_true(out.duty.a == 0.0f && out.duty.b == 0.0f && out.duty.c == 0.0f);
}

static void test_bad_cfg(void **st)
{
    (void)st;
    const mc_phase_program_t *all[4] = {&mc_phase_step1_pulses, &mc_phase_step1_pulse3,
                                        &mc_phase_step2_polarity, &mc_phase_step2_dvi};
    for (int k = 0; k < 4; ++k) {
        assert_false(mc_phase_begin(&g_ph, all[k], NULL, 0.0f));
        expect_dead();
        /* a refused program took no period and reports none */
        mc_phase_result_t r;
        mc_phase_result(&g_ph, &r);
        assert_int_equal(r.calls, 0);
        assert_false(r.flip);
    }
    mc_initpos_cfg_t c1 = ip1_cfg(MC_IP_COST_LINEAR);
    c1.m = MC_IP_M_MAX + 1;
    assert_false(mc_phase_begin(&g_ph, &mc_phase_step1_pulses, &c1, 0.0f));
    expect_dead();
    c1 = ip1_cfg(MC_IP_COST_LINEAR);
    c1.ts = 0.0f;
    assert_false(mc_phase_begin(&g_ph, &mc_phase_step1_pulses, &c1, 0.0f));
    expect_dead();
    mc_pulse3_cfg_t c3;
    mc_pulse3_cfg_default(&c3);
    c3.n = 0;
    assert_false(mc_phase_begin(&g_ph, &mc_phase_step1_pulse3, &c3, 0.0f));
    expect_dead();
    mc_polarity_cfg_t c2;
    mc_polarity_cfg_default(&c2);   /* ts unset */
    assert_false(mc_phase_begin(&g_ph, &mc_phase_step2_polarity, &c2, 0.3f));
    expect_dead();
    c2.ts = (float)SUN_TS;
    c2.n = MC_POL_N_MAX + 1;
    assert_false(mc_phase_begin(&g_ph, &mc_phase_step2_polarity, &c2, 0.3f));
    expect_dead();
    mc_dvi_cfg_t cd;
    mc_dvi_cfg_default(&cd);
    cd.v = -1.0f;
    assert_false(mc_phase_begin(&g_ph, &mc_phase_step2_dvi, &cd, 0.3f));
    expect_dead();
    /* no program at all */
    assert_false(mc_phase_begin(&g_ph, NULL, &cd, 0.0f));
    expect_dead();
    mc_phase_result_t r;
    mc_phase_result(&g_ph, &r);
    assert_true(r.theta == 0.0f && r.calls == 0);
    /* a good begin after a bad one works; stop idles the holder */
    mc_dvi_cfg_default(&cd);
    assert_true(mc_phase_begin(&g_ph, &mc_phase_step2_dvi, &cd, 0.3f));
    mc_phase_stop(&g_ph);
    expect_dead();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sizes),
        cmocka_unit_test(test_step1_pulses),
        cmocka_unit_test(test_step1_pulse3),
        cmocka_unit_test(test_step2_polarity),
        cmocka_unit_test(test_step2_dvi),
        cmocka_unit_test(test_chain_one_workspace),
        cmocka_unit_test(test_bad_cfg),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
