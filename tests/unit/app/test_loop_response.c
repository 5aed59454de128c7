/* Loop responses bounded by their design (issue 30): each loop is built from the parameters the
 * way the drive builds it (mc_drive_build), driven by a step or a ramp, and its response is held
 * to overshoot, peak, rise and settling times computed from the designed bandwidth, never fitted
 * to the output. A gain built at half (or twice) its design moves at least one of them out.
 *  - the encoder's speed PLL (mc/encoder.h, control.encoder_pll_bw_hz): critically damped,
 *    s^2 + 2w s + w^2, both poles at -w;
 *  - the UNOP source's PLL filter (Fig. 6.9, estimator.pll_bw_hz): the same design on the raw
 *    estimate's angle;
 *  - the current loop (mc/current_ctrl.h, control.current_bw_hz) on an R-L plant: pole-zero
 *    cancellation, first order at the bandwidth;
 *  - the speed loop (mc/speed_ctrl.h, control.speed_bw_hz) on the inertia motor.inertia_kgm2:
 *    kp = J w, ki = kp w / 4, both closed-loop poles at -w/2.
 * The tolerances allow for the discretization (w ts up to 0.16 here) and nothing else. */
#include "../mc_test.h"

#include <string.h>

#include "mc/angle.h"
#include "mc/drive.h"
#include "mc/encoder.h"
#include "mc/pll.h"
#include "mc/unop.h"
#include "mc/current_ctrl.h"
#include "mc/speed_ctrl.h"

/* ---- the design responses ---------------------------------------------------------------- */

/* Step response of (2a s + a^2) / (s + a)^2: a type-2 loop with both poles at -a (the PLL's
 * speed estimate after a speed step, the speed loop after a reference step):
 * y(t) = 1 + (a t - 1) e^(-a t); peak 1 + e^-2 at t = 2 / a. */
static double crit2_step(double a, double t)
{
    return 1.0 + (a * t - 1.0) * exp(-a * t);
}

/* The angle lag of that loop after an acceleration step, over its final value alpha / a^2:
 * E(s) = s^2 / (s + a)^2 * alpha / s^3, e(t) = 1 - (1 + a t) e^(-a t). */
static double crit2_lag(double a, double t)
{
    return 1.0 - (1.0 + a * t) * exp(-a * t);
}

/* Step response of a / (s + a): the current loop after pole-zero cancellation. */
static double first_step(double a, double t)
{
    return 1.0 - exp(-a * t);
}

/* The first time f(t) reaches level (f rising from 0 through it before its peak), by bisection. */
static double first_crossing(double (*f)(double, double), double a, double level)
{
    double lo = 0.0, hi = 1.0 / a;
    while (f(a, hi) < level) {
        hi *= 2.0;
    }
    for (int k = 0; k < 200; ++k) {
        const double mid = 0.5 * (lo + hi);
        *(f(a, mid) < level ? &lo : &hi) = mid;
    }
    return 0.5 * (lo + hi);
}

/* The last time |f(t) - 1| exceeds band (the settling time), on a fine grid up to 50 / a. */
static double settling(double (*f)(double, double), double a, double band)
{
    double last = 0.0;
    for (double t = 0.0; t < 50.0 / a; t += 1e-3 / a) {
        if (fabs(f(a, t) - 1.0) > band) {
            last = t;
        }
    }
    return last;
}

/* A sampled step response y[k] (normalized: final value 1) at t = (k + 1) ts: what it shows. */
typedef struct {
    double peak, t_peak;       /* largest value and when                        */
    double t10, t90;           /* first reaching 10 % and 90 %                  */
    double t_settle;           /* after this, within the band of the final value */
} resp_t;

static resp_t measure(const double *y, int n, double ts, double band)
{
    resp_t r = {-1e30, 0.0, -1.0, -1.0, 0.0};
    for (int k = 0; k < n; ++k) {
        const double t = (double)(k + 1) * ts;
        if (y[k] > r.peak) {
            r.peak = y[k];
            r.t_peak = t;
        }
        if (r.t10 < 0.0 && y[k] >= 0.1) {
            r.t10 = t;
        }
        if (r.t90 < 0.0 && y[k] >= 0.9) {
            r.t90 = t;
        }
        if (fabs(y[k] - 1.0) > band) {
            r.t_settle = t;
        }
    }
    return r;
}

/* The measured response against the design's: peak (overshoot) within tol_os of the design's,
 * the rise (10-90 %), peak and settling times within tol_t of the design's (relative) plus one
 * sample. With overshoot == false the design has none: the peak must not exceed 1 + tol_os. */
static void check_response(const char *what, const resp_t *m, double (*f)(double, double), double a, double ts,
                           double band, bool overshoot, double tol_os, double tol_t)
{
    const double t10 = first_crossing(f, a, 0.1), t90 = first_crossing(f, a, 0.9);
    const double ts_design = settling(f, a, band);
    const double peak = overshoot ? crit2_step(a, 2.0 / a) : 1.0;
    printf("%s: overshoot %.2f %% (design %.2f %%), rise %.3f ms (%.3f), peak at %.3f ms (%.3f), "
           "settled to %.0f %% at %.3f ms (%.3f)\n",
           what, 100.0 * (m->peak - 1.0), 100.0 * (peak - 1.0), 1e3 * (m->t90 - m->t10), 1e3 * (t90 - t10),
           1e3 * m->t_peak, overshoot ? 1e3 * 2.0 / a : INFINITY, 100.0 * band, 1e3 * m->t_settle, 1e3 * ts_design);
    if (overshoot) {
        if (fabs(m->peak - peak) > tol_os) {
            fail_msg("%s: peak %.4f, design %.4f (+-%.3f)", what, m->peak, peak, tol_os);
        }
        if (fabs(m->t_peak - 2.0 / a) > tol_t * 2.0 / a + ts) {
            fail_msg("%s: peak at %.4g s, design %.4g s", what, m->t_peak, 2.0 / a);
        }
    } else if (m->peak > 1.0 + tol_os) {
        fail_msg("%s: overshoot %.4f where the design has none", what, m->peak - 1.0);
    }
    if (m->t10 < 0.0 || m->t90 < 0.0 || fabs((m->t90 - m->t10) - (t90 - t10)) > tol_t * (t90 - t10) + ts) {
        fail_msg("%s: rise time %.4g s, design %.4g s", what, m->t90 - m->t10, t90 - t10);
    }
    if (fabs(m->t_settle - ts_design) > tol_t * ts_design + ts) {
        fail_msg("%s: settled at %.4g s, design %.4g s", what, m->t_settle, ts_design);
    }
}

static void build(mc_drive_built_t *b, const char *source)
{
    mc_drive_cfg_t cfg;
    mc_drive_cfg_default(&cfg);
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_control_angle_source, source, NULL));
    mc_param_err_t err;
    assert_true(mc_drive_build(&cfg, b, &err));
}

/* ---- the encoder's speed PLL ---------------------------------------------------------------- */

enum { ENC_N = 400 };
static double y[ENC_N];

/* The encoder source as the drive builds it (control.encoder_pll_bw_hz), at rest on count c0. */
static void enc_start(mc_drive_built_t *b, mc_angle_src_state_t *st, uint32_t c0)
{
    build(b, "encoder");
    mc_angle_src_encoder.init(st, &b->blk.src.cfg);
    mc_angle_src_encoder.reset(st, 0.0f, 0.0f);
    mc_angle_out_t out;
    for (int k = 0; k < 50; ++k) {
        const mc_angle_in_t in = {.qep_count = c0};
        mc_angle_src_encoder.step(st, &in, &out);
    }
    assert_near(out.omega, 0.0, 0.0);
}

/* Speed step: the counter at rest, then a steady count rate. The PLL's speed (before its output
 * filter) follows (2w s + w^2) / (s + w)^2: 13.5 % overshoot at 2 / w, settled to 2 % at
 * 5.4 / w. A halved kp (zeta 0.5) overshoots 30 %, a halved ki (poles at -0.29 w and -1.7 w)
 * settles 3 x later. */
static void test_encoder_pll_speed_step(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    static mc_angle_src_state_t s;
    uint32_t count = 123456u;
    enc_start(&b, &s, count);
    const double w = 2.0 * PI_D * b.p.control_encoder_pll_bw_hz, ts = b.p.control_ts_s;
    const int pp = (int)b.p.motor_pole_pairs;
    const uint32_t cpr = 4u * (uint32_t)b.p.hw_encoder_lines;
    const uint32_t dc = 20u;   /* counts per period */
    const double we = 2.0 * PI_D * (double)dc * pp / (double)cpr / ts;
    mc_angle_out_t out;
    mc_angle_diag_t d;
    for (int k = 0; k < ENC_N; ++k) {
        count += dc;
        const mc_angle_in_t in = {.qep_count = count};
        mc_angle_src_encoder.step(&s, &in, &out);
        mc_angle_src_encoder.diag(&s, &d);
        y[k] = d.omega_raw / we;
    }
    const resp_t m = measure(y, ENC_N, ts, 0.02);
    check_response("encoder PLL, speed step", &m, crit2_step, w, ts, 0.02, true, 0.03, 0.15);
    /* and the filtered output has settled on the count rate */
    assert_near(out.omega, we, 1e-3 * we);
}

/* Speed ramp (counts accelerating by one count per period each period): a type-2 loop follows
 * it with a constant angle lag alpha / ki = alpha / w^2 (the same in the sampled loop: the
 * integrator must grow by alpha ts each period, ki ts e = alpha ts), reached with the poles at
 * -w (2 % after 5.8 / w). Doubles with a halved ki. */
static void test_encoder_pll_ramp_lag(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    static mc_angle_src_state_t s;
    uint32_t count = 1000u;
    enc_start(&b, &s, count);
    const double w = 2.0 * PI_D * b.p.control_encoder_pll_bw_hz, ts = b.p.control_ts_s;
    const int pp = (int)b.p.motor_pole_pairs;
    const uint32_t cpr = 4u * (uint32_t)b.p.hw_encoder_lines;
    const double rad_per_count = 2.0 * PI_D * pp / (double)cpr;   /* electrical */
    const double alpha = rad_per_count / (ts * ts);               /* [rad/s^2] */
    const double lag = alpha / (w * w);
    mc_angle_out_t out;
    mc_angle_diag_t d;
    uint32_t rate = 0u;
    double worst = 0.0;
    int n_settled = -1;
    for (int k = 0; k < ENC_N; ++k) {
        rate += 1u;
        count += rate;
        const mc_angle_in_t in = {.qep_count = count};
        mc_angle_src_encoder.step(&s, &in, &out);
        mc_angle_src_encoder.diag(&s, &d);
        const double e = (double)mc_wrap_pi(out.theta - d.theta_raw);
        if (fabs(e - lag) > 0.02 * lag) {
            n_settled = k + 1;
        }
        if ((double)(k + 1) * ts > 8.0 / w) {
            worst = fmax(worst, fabs(e - lag));
        }
    }
    const double t_design = settling(crit2_lag, w, 0.02);
    printf("encoder PLL, speed ramp %.4g rad/s^2: angle lag %.5f rad (design alpha / w^2 %.5f), "
           "within 2 %% after %.3f ms (design about %.3f)\n",
           alpha, (double)mc_wrap_pi(out.theta - d.theta_raw), lag, 1e3 * n_settled * ts, 1e3 * t_design);
    assert_true(worst < 0.02 * lag);
    assert_true(fabs((double)n_settled * ts - t_design) < 0.15 * t_design + ts);
}

/* ---- the UNOP source's PLL filter (Fig. 6.9) ------------------------------------------------- */

/* src_unop.c's configuration (private there): the estimator's, then the PLL's. Checked below
 * field by field against the parameters, so that a change of that layout fails here loudly. */
typedef struct {
    mc_unop_cfg_t unop;
    mc_pll_cfg_t pll;
} unop_cfg_mirror_t;

/* The PLL after the estimator filters its angle: with the estimated speed as feed-forward the
 * raw angle goes through (kp s + ki) / (s^2 + kp s + ki), critically damped at
 * w = 2 pi estimator.pll_bw_hz (3.9): a jump of the raw angle (no speed in it) comes through
 * with 13.5 % overshoot at 2 / w and settles to 2 % in 5.4 / w. The PLL as the unop source
 * builds it from the parameters. */
static void test_unop_pll_filter_step(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    mc_drive_cfg_t cfg;
    mc_drive_cfg_default(&cfg);
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_control_angle_source, "unop", NULL));
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_estimator_model, "const", NULL));   /* no map here */
    mc_param_err_t err;
    assert_true(mc_drive_build(&cfg, &b, &err));
    unop_cfg_mirror_t c;
    memcpy(&c, &b.blk.src.cfg, sizeof c);
    assert_true(c.unop.ts == b.p.control_ts_s && c.unop.k1 == b.p.estimator_k1 && c.unop.k2 == b.p.estimator_k2 &&
                c.unop.iter_max == (int)b.p.estimator_iter_max);
    assert_true(c.pll.ts == b.p.control_ts_s && c.pll.speed_fc_hz == b.p.estimator_pll_speed_fc_hz);
    const double w = 2.0 * PI_D * b.p.estimator_pll_bw_hz, ts = b.p.control_ts_s;
    mc_pll_t pll;
    mc_pll_init(&pll, &c.pll);
    /* running at a steady estimated speed, the raw angle jumps by 0.2 rad once */
    const double we = 300.0, jump = 0.2;
    double th = 0.5;
    mc_pll_reset(&pll, (float)(th - we * ts), (float)we);
    pll.integ = 0.0f;
    for (int k = 0; k < 20; ++k) {
        mc_pll_step(&pll, (float)th, (float)we);
        th += we * ts;
    }
    enum { UN = 1500 };
    static double yu[UN];
    for (int k = 0; k < UN; ++k) {
        mc_pll_step(&pll, mc_wrap_pi((float)(th + jump)), (float)we);
        /* the PLL's angle, relative to the raw one without the jump, over the jump */
        yu[k] = (double)mc_wrap_pi((float)((double)pll.theta - th)) / jump;
        th += we * ts;
    }
    /* the first sample is the prediction made before the jump: the response starts one late */
    const resp_t m = measure(yu + 1, UN - 1, ts, 0.02);
    check_response("unop PLL filter, raw angle jump", &m, crit2_step, w, ts, 0.02, true, 0.03, 0.15);
}

/* ---- the current loop ----------------------------------------------------------------------- */

enum { CC_N = 300, SC_N = 3000 };
static double y2[SC_N];

/* A reference step on one axis (the other held at 0, at standstill: no decoupling terms), the
 * controller as built from control.current_bw_hz on the R-L plant it was designed for (the motor
 * parameters, exact zero-order hold over each period, the voltage applied in the period it is
 * computed): pole-zero cancellation leaves wb / (s + wb), no overshoot, 10-90 % in ln 9 / wb,
 * 2 % in ln 50 / wb. A halved kp halves the bandwidth (and overshoots in the sampled loop); a
 * halved ki leaves a slow tail. */
static void cc_step_axis(bool q_axis)
{
    static mc_drive_built_t b;
    build(&b, "encoder");
    const double wb = 2.0 * PI_D * b.p.control_current_bw_hz, ts = b.p.control_ts_s;
    const double r = b.p.motor_rs_ohm, l = q_axis ? b.p.motor_lq_h : b.p.motor_ld_h;
    const double phi = exp(-r * ts / l);
    mc_cc_t cc;
    mc_cc_init(&cc, &b.cc);
    const double step = 5.0;   /* [A] */
    const mc_dq_t ref = {q_axis ? 0.0f : (float)step, q_axis ? (float)step : 0.0f};
    double id = 0.0, iq = 0.0;
    for (int k = 0; k < CC_N; ++k) {
        const mc_dq_t meas = {(float)id, (float)iq};
        const mc_dq_t u = mc_cc_step(&cc, ref, meas, 0.0f, 1e3f);
        id = phi * id + (1.0 - phi) * (double)u.d / r;
        iq = phi * iq + (1.0 - phi) * (double)u.q / r;
        y[k] = (q_axis ? iq : id) / step;
        /* the other axis stays at rest */
        assert_near(q_axis ? id : iq, 0.0, 1e-6);
    }
    const resp_t m = measure(y, CC_N, ts, 0.02);
    check_response(q_axis ? "current loop, i_q step" : "current loop, i_d step", &m, first_step, wb, ts, 0.02, false,
                   0.02, 0.15);
    /* the cancellation itself: with ki off its design the slow plant pole R / L stays in the
     * loop with a residue of about (R / L) / wb, under the 2 % band; to 0.1 % the design takes
     * ln 1000 / wb */
    const resp_t fine = measure(y, CC_N, ts, 0.001);
    const double t_fine = settling(first_step, wb, 0.001);
    printf("  settled to 0.1 %% at %.3f ms (design %.3f)\n", 1e3 * fine.t_settle, 1e3 * t_fine);
    assert_true(fabs(fine.t_settle - t_fine) < 0.15 * t_fine + ts);
}

static void test_current_loop_step(void **st)
{
    (void)st;
    cc_step_axis(false);
    cc_step_axis(true);
}

/* ---- the speed loop --------------------------------------------------------------------------- */

/* A speed reference step on the inertia the gains were designed for (motor.inertia_kgm2, no
 * load, small enough that the torque limit stays out of it), the loop running every
 * control.speed_decimation periods: kp = J w, ki = kp w / 4 with w = 2 pi control.speed_bw_hz
 * give J s^2 + kp s + ki = J (s + w/2)^2 and the response (2a s + a^2) / (s + a)^2, a = w / 2:
 * 13.5 % overshoot at 4 / w, 2 % after 10.8 / w. The gains are the parameters' own
 * (control.speed_kp, control.speed_ki: their defaults follow from the bandwidth and inertia). */
static void test_speed_loop_step(void **st)
{
    (void)st;
    static mc_drive_built_t b;
    build(&b, "encoder");
    const double w = 2.0 * PI_D * b.p.control_speed_bw_hz, j = b.p.motor_inertia_kgm2;
    const double ts = b.p.control_ts_s, ts_sc = b.sc.ts;
    assert_near(ts_sc, ts * (double)b.sc.decimation, 1e-9);
    mc_sc_t sc;
    mc_sc_init(&sc, &b.sc);
    mc_sc_reset(&sc, 0.0f);
    const double step = 0.2 * b.sc.torque_max / b.sc.kp;   /* [rad/s mech]: 20 % of the limit at first */
    double om = 0.0;
    int n = 0;
    for (int k = 0; k < SC_N * b.sc.decimation && n < SC_N; ++k) {
        const float t = mc_sc_step(&sc, (float)step, (float)om);
        assert_true(fabs((double)t) < b.sc.torque_max);
        om += (double)t * ts / j;
        if ((k + 1) % b.sc.decimation == 0) {
            y2[n++] = om / step;
        }
    }
    const resp_t m = measure(y2, n, ts_sc, 0.02);
    check_response("speed loop, speed step", &m, crit2_step, 0.5 * w, ts_sc, 0.02, true, 0.03, 0.15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_encoder_pll_speed_step),
        cmocka_unit_test(test_encoder_pll_ramp_lag),
        cmocka_unit_test(test_unop_pll_filter_step),
        cmocka_unit_test(test_current_loop_step),
        cmocka_unit_test(test_speed_loop_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
