/* The running polarity re-check on its own (mc/polcheck.h): when it starts, its bias, its
 * verdict from the HF d current under +-I_b, the settledness test and the at_start schedule. */
#include <math.h>

#include "../mc_test.h"
#include "mc/polcheck.h"

static mc_polcheck_cfg_t config(void)
{
    return (mc_polcheck_cfg_t){.enable = true, .at_start = false, .inject = true, .three_step = false,
                               .omega_n1 = 300.0f, .bias = 2.0f, .log_ratio = 0.0f, .settle_n = 10u,
                               .measure_n = 20u, .start_n = 500u, .w_scale = 0.01f, .avg_k = 0.0125f};
}

/* Runs a started check to its end with an HF d current of amplitude a_plus under +I_b and a_minus
 * under -I_b (at a quarter of the period: a square wave of +-a). Returns the step's result of the
 * last period; *periods: how many it took. */
static bool run_check(mc_polcheck_t *s, const mc_polcheck_cfg_t *c, float a_plus, float a_minus, int *periods)
{
    bool flip = false;
    int n = 0;
    while (mc_polcheck_active(s) && n < 1000) {
        const float b = mc_polcheck_bias(s, c);
        const float a = b > 0.0f ? a_plus : a_minus;
        const float hf = (n & 1) ? a : -a;
        const mc_polcheck_in_t in = {.i_d = b + hf, .i_d_filtered = b, .theta = 0.3f, .theta_raw = 0.3f, .w_avg = 5.0f};
        flip = mc_polcheck_step(s, c, &in);
        ++n;
    }
    *periods = n;
    return flip;
}

static void test_start_and_bias(void **st)
{
    (void)st;
    mc_polcheck_cfg_t c = config();
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    assert_false(mc_polcheck_active(&s));
    assert_float_equal(mc_polcheck_bias(&s, &c), 0.0f, 0.0f);
    assert_false(mc_polcheck_start(&s, &c, 10.0f, false));    /* not in RUN */
    assert_false(mc_polcheck_start(&s, &c, 150.0f, true));    /* at half of N1 */
    assert_false(mc_polcheck_start(&s, &c, NAN, true));
    c.inject = false;
    assert_false(mc_polcheck_start(&s, &c, 10.0f, true));
    c = config();
    c.enable = false;
    assert_false(mc_polcheck_start(&s, &c, 10.0f, true));
    c = config();
    assert_int_equal(s.checks, 0u);
    assert_true(mc_polcheck_start(&s, &c, -149.0f, true));
    assert_int_equal(s.checks, 1u);
    assert_false(mc_polcheck_start(&s, &c, 10.0f, true));     /* one at a time */
    assert_float_equal(mc_polcheck_bias(&s, &c), 2.0f, 0.0f);
    mc_polcheck_reset(&s);
    assert_false(mc_polcheck_active(&s));
    assert_int_equal(s.checks, 1u);                            /* counted since the enable */
    mc_polcheck_restart(&s);
    assert_int_equal(s.checks, 0u);
}

/* Right (the HF current larger under +I_b, where the iron saturates further): -1, the estimate
 * stays; reversed: +1 and the caller turns it; equal: inconclusive. The sequence takes
 * 2 x (settle_n + measure_n) periods, +I_b first. */
static void test_verdicts(void **st)
{
    (void)st;
    const mc_polcheck_cfg_t c = config();
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    int n = 0;
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    assert_false(run_check(&s, &c, 0.12f, 0.10f, &n));
    assert_int_equal(n, 2 * (10 + 20));
    assert_int_equal(s.last, -1);
    assert_int_equal(s.flips, 0u);
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    assert_true(run_check(&s, &c, 0.10f, 0.12f, &n));
    assert_int_equal(s.last, 1);
    assert_int_equal(s.flips, 1u);
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    assert_false(run_check(&s, &c, 0.10f, 0.1005f, &n));   /* within the 2 % margin */
    assert_int_equal(s.last, 0);
    /* with the map's expected ratio r (amplitudes 1.2 apart: ln r = 2 ln 1.2 = 0.365) the verdict
     * needs r^(1/4): a log ratio beyond 0.091 */
    mc_polcheck_cfg_t m = c;
    m.log_ratio = 2.0f * logf(1.2f);
    assert_true(mc_polcheck_start(&s, &m, 10.0f, true));
    assert_true(run_check(&s, &m, 0.10f, 0.105f, &n));    /* 2 ln 1.05 = 0.098: reversed */
    assert_int_equal(s.last, 1);
    assert_true(mc_polcheck_start(&s, &m, 10.0f, true));
    assert_false(run_check(&s, &m, 0.10f, 0.104f, &n));   /* 2 ln 1.04 = 0.078: inconclusive */
    assert_int_equal(s.last, 0);
    assert_int_equal(s.checks, 5u);
    assert_int_equal(s.flips, 2u);
}

/* The verdict's margin on either side, with and without the map's ratio: log ratios 10 % inside
 * the margin are inconclusive, 10 % outside decide (right for ln(+/-) > 0, reversed below), for
 * both signs. The margin is 0.02 without a map, a quarter of the map's log ratio with one. */
static void test_verdict_margin(void **st)
{
    (void)st;
    const mc_polcheck_cfg_t c = config();
    mc_polcheck_cfg_t m = c;
    m.log_ratio = 0.4f;   /* margin 0.1 */
    const struct { const mc_polcheck_cfg_t *cfg; float margin; } cases[] = {{&c, 0.02f}, {&m, 0.1f}};
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    for (int k = 0; k < 2; ++k) {
        const mc_polcheck_cfg_t *cfg = cases[k].cfg;
        for (int side = 0; side < 2; ++side) {
            const float f = side == 0 ? 0.9f : 1.1f;   /* inside, outside */
            /* ln(plus / minus) = 2 ln(a_plus / a_minus) = +-f margin */
            const float r = expf(0.5f * f * cases[k].margin);
            int n = 0;
            assert_true(mc_polcheck_start(&s, cfg, 10.0f, true));
            const bool right_flip = run_check(&s, cfg, 0.10f * r, 0.10f, &n);
            assert_false(right_flip);
            assert_int_equal(s.last, side == 0 ? 0 : -1);
            assert_true(mc_polcheck_start(&s, cfg, 10.0f, true));
            const bool rev_flip = run_check(&s, cfg, 0.10f, 0.10f * r, &n);
            assert_int_equal(rev_flip, side == 1);
            assert_int_equal(s.last, side == 0 ? 0 : 1);
        }
    }
    assert_int_equal(s.flips, 2u);
}

/* Not settled: the raw angle 0.5 rad off the estimate ends the check at once without a verdict;
 * so does a speed estimate drifting by more than 10 deg in w_scale units. */
static void test_unsettled(void **st)
{
    (void)st;
    const mc_polcheck_cfg_t c = config();
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    s.last = -1;
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    mc_polcheck_in_t in = {.i_d = 2.0f, .i_d_filtered = 2.0f, .theta = 0.0f, .theta_raw = 0.5f, .w_avg = 0.0f};
    assert_false(mc_polcheck_step(&s, &c, &in));
    assert_false(mc_polcheck_active(&s));
    assert_int_equal(s.last, 0);
    /* the speed: 0.1745 / w_scale = 17.45 rad/s of drift */
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    in.theta_raw = 0.0f;
    int n = 0;
    while (mc_polcheck_active(&s) && n < 100) {
        in.w_avg = (float)n;
        (void)mc_polcheck_step(&s, &c, &in);
        ++n;
    }
    assert_false(mc_polcheck_active(&s));
    assert_int_equal(n, 19);   /* ended at the period 18.0 rad/s away */
}

/* No HF response at all under one or both biases (the injection not reaching the machine, a
 * dead current channel): the ratio is undefined, so no verdict, and the estimate is never turned;
 * a NaN current the same. */
static void test_no_response_no_flip(void **st)
{
    (void)st;
    const mc_polcheck_cfg_t c = config();
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    const float amps[][2] = {{0.0f, 0.0f}, {0.0f, 0.1f}, {0.1f, 0.0f}, {NAN, 0.1f}, {0.1f, NAN}};
    for (size_t k = 0; k < sizeof amps / sizeof amps[0]; ++k) {
        int n = 0;
        s.last = -1;
        assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
        assert_false(run_check(&s, &c, amps[k][0], amps[k][1], &n));
        assert_int_equal(n, 2 * (10 + 20));   /* ran to its end: a real "inconclusive" */
        assert_int_equal(s.last, 0);
    }
    assert_int_equal(s.flips, 0u);
}

/* A check cut short by an unsettled estimate part-way through its +I_b measurement leaves
 * nothing behind: the next check's verdict is the one a fresh check gives (right, here, by a
 * clear 20 % in amplitude), not one weighed with the aborted check's samples. */
static void test_aborted_check_leaves_no_trace(void **st)
{
    (void)st;
    const mc_polcheck_cfg_t c = config();
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    mc_polcheck_in_t in = {.i_d = 2.1f, .i_d_filtered = 2.0f, .theta = 0.3f, .theta_raw = 0.3f, .w_avg = 5.0f};
    for (int n = 0; n < 10 + 15; ++n) {   /* settled, then 15 of the 20 measuring periods */
        in.i_d = (n & 1) ? 2.1f : 1.9f;
        assert_false(mc_polcheck_step(&s, &c, &in));
        assert_true(mc_polcheck_active(&s));
    }
    in.w_avg = 25.0f;   /* the speed estimate jumps by 20 rad/s (> 10 deg in w_scale units): aborted */
    assert_false(mc_polcheck_step(&s, &c, &in));
    assert_false(mc_polcheck_active(&s));
    int n = 0;
    assert_true(mc_polcheck_start(&s, &c, 10.0f, true));
    assert_false(run_check(&s, &c, 0.12f, 0.10f, &n));
    assert_int_equal(s.last, -1);
    assert_int_equal(s.flips, 0u);
}

/* at_start: a check a settling time into RUN, again after an inconclusive verdict, three at
 * most; none after Step II (three_step); a RUN entry marked unsure is checked as at_start. */
static void test_schedule(void **st)
{
    (void)st;
    mc_polcheck_cfg_t c = config();
    mc_polcheck_t s = {0};
    mc_polcheck_restart(&s);
    mc_polcheck_schedule(&s, &c, 10.0f, true, c.start_n);
    assert_false(mc_polcheck_active(&s));   /* polarity_check = on: only on a doubt */
    c.at_start = true;
    mc_polcheck_schedule(&s, &c, 10.0f, true, c.start_n - 1u);
    assert_false(mc_polcheck_active(&s));
    mc_polcheck_schedule(&s, &c, 10.0f, false, c.start_n);
    assert_false(mc_polcheck_active(&s));
    mc_polcheck_schedule(&s, &c, 10.0f, true, c.start_n);
    assert_true(mc_polcheck_active(&s));
    int n;
    (void)run_check(&s, &c, 0.10f, 0.10f, &n);   /* inconclusive */
    mc_polcheck_schedule(&s, &c, 10.0f, true, 2u * c.start_n);
    assert_true(mc_polcheck_active(&s));
    (void)run_check(&s, &c, 0.10f, 0.10f, &n);
    mc_polcheck_schedule(&s, &c, 10.0f, true, 3u * c.start_n);
    assert_true(mc_polcheck_active(&s));
    (void)run_check(&s, &c, 0.10f, 0.10f, &n);
    mc_polcheck_schedule(&s, &c, 10.0f, true, 4u * c.start_n);
    assert_false(mc_polcheck_active(&s));   /* three at most */
    assert_int_equal(s.checks, 3u);
    /* a conclusive first verdict: no second */
    mc_polcheck_restart(&s);
    mc_polcheck_schedule(&s, &c, 10.0f, true, c.start_n);
    (void)run_check(&s, &c, 0.12f, 0.10f, &n);
    mc_polcheck_schedule(&s, &c, 10.0f, true, 2u * c.start_n);
    assert_false(mc_polcheck_active(&s));
    /* after Step II: none */
    c.three_step = true;
    mc_polcheck_restart(&s);
    mc_polcheck_schedule(&s, &c, 10.0f, true, c.start_n);
    assert_false(mc_polcheck_active(&s));
    /* unsure, with polarity_check = on */
    c = config();
    mc_polcheck_restart(&s);
    s.unsure = true;
    mc_polcheck_schedule(&s, &c, 10.0f, true, c.start_n);
    assert_true(mc_polcheck_active(&s));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_start_and_bias),
        cmocka_unit_test(test_verdicts),
        cmocka_unit_test(test_verdict_margin),
        cmocka_unit_test(test_unsettled),
        cmocka_unit_test(test_no_response_no_flip),
        cmocka_unit_test(test_aborted_check_leaves_no_trace),
        cmocka_unit_test(test_schedule),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
