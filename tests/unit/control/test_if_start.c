/* cmocka tests of the I/f block (mc/if_start.h): angle integration, the ramp, the hand-over
 * condition and its reduction, the re-entry below w_l (hysteresis), the alignment, the reseed. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>
#include "mc/if_start.h"
#include "mc/angle.h"

static mc_if_cfg_t cfg(void)
{
    return (mc_if_cfg_t){.ts = 1e-4f, .i_f = 5.0f, .accel = 1000.0f, .w_h = 100.0f, .w_l = 50.0f, .w_tol = 30.0f,
                         .n_sync = 10u, .i_drop = 50.0f, .i_min = 0.5f, .delta_h = 0.35f, .n_align = 20u, .damp = 0.0f};
}

static void test_cfg_valid(void **st)
{
    (void)st;
    mc_if_cfg_t c = cfg();
    assert_true(mc_if_cfg_valid(&c));
    c.w_l = c.w_h;   /* no hysteresis */
    assert_false(mc_if_cfg_valid(&c));
    c = cfg();
    c.i_min = 6.0f;
    assert_false(mc_if_cfg_valid(&c));
    c = cfg();
    c.damp = 1.0f;
    assert_false(mc_if_cfg_valid(&c));
}

/* the frame's speed ramps at accel to the target and its angle is the speed's integral */
static void test_ramp_and_angle(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_enter(&s, &c, 0.0f, 0.0f, 1.0f);
    mc_if_out_t o;
    double theta = 0.0, w = 0.0;
    for (int k = 0; k < 500; ++k) {   /* 50 ms at 1000 rad/s^2: 50 rad/s, below w_h */
        const mc_if_in_t in = {.omega_target = 80.0f, .theta_est = s.theta + 0.5f, .omega_est = s.omega};
        mc_if_step(&s, &c, &in, &o);
        assert_true(o.open);
        assert_float_equal(o.i_ref.d, 0.0f, 0.0f);
        assert_float_equal(o.i_ref.q, 5.0f, 0.0f);
        w = fmin(w + 1000.0 * 1e-4, 80.0);
        theta += w * 1e-4;
    }
    assert_float_equal(s.omega, 50.0f, 1e-3f);
    assert_float_equal(s.theta, (float)theta, 1e-3f);
    for (int k = 0; k < 500; ++k) {   /* the target reached: held there */
        const mc_if_in_t in = {.omega_target = 80.0f, .theta_est = s.theta + 0.5f, .omega_est = s.omega};
        mc_if_step(&s, &c, &in, &o);
    }
    assert_float_equal(s.omega, 80.0f, 1e-4f);
    assert_int_equal(s.mode, MC_IF_OPEN);   /* below w_h: never hands over */
}

/* above w_h, synchronous for n_sync: I_f falls at i_drop until the estimated load angle is
 * below delta_h, then the estimator's angle is in charge */
static void test_handover_after_reduction(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_enter(&s, &c, 0.0f, 120.0f, 1.0f);
    mc_if_out_t o = {0};
    int k = 0, reduce_at = -1;
    float delta = 1.0f;   /* rad: falls as I_f does (torque balance) */
    for (; k < 5000 && !o.handover; ++k) {
        const mc_if_in_t in = {.omega_target = 120.0f, .theta_est = mc_wrap_pi(s.theta + delta), .omega_est = 120.0f};
        mc_if_step(&s, &c, &in, &o);
        if (s.mode == MC_IF_REDUCE && reduce_at < 0) {
            reduce_at = k;
        }
        delta = acosf(fminf(1.0f, 2.7f / s.i_mag));   /* a load needing 2.7 A */
    }
    assert_int_equal(reduce_at, (int)c.n_sync - 1);
    assert_true(o.handover);
    assert_false(o.open);
    assert_int_equal(s.mode, MC_IF_CLOSED);
    /* handed over at cos(delta_h) I_f ~ 2.7 A, not at i_min */
    assert_true(s.i_mag > 2.7f && s.i_mag < 2.7f / cosf(c.delta_h) + 0.01f);
}

/* below w_l in closed loop: open loop again at the estimate, with the torque's sign; between
 * w_l and w_h nothing changes (hysteresis) */
static void test_reentry_hysteresis(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_init(&s);
    mc_if_out_t o;
    mc_if_in_t in = {.omega_target = 0.0f, .theta_est = 1.0f, .omega_est = 60.0f, .torque_sign = -2.0f};
    mc_if_step(&s, &c, &in, &o);
    assert_false(o.open);   /* 60 > w_l: stays closed although below w_h */
    assert_float_equal(o.theta, 1.0f, 0.0f);
    in.omega_est = 49.0f;
    mc_if_step(&s, &c, &in, &o);
    assert_true(o.entered);
    assert_true(o.open);
    assert_float_equal(o.theta, 1.0f, 0.0f);
    assert_float_equal(o.omega, 49.0f, 0.0f);
    assert_float_equal(o.i_ref.q, -5.0f, 0.0f);   /* placed for the negative torque */
    /* back above w_l but below w_h: still open (no chatter) */
    for (int k = 0; k < 100; ++k) {
        in = (mc_if_in_t){.omega_target = 80.0f, .theta_est = mc_wrap_pi(s.theta - 0.5f), .omega_est = s.omega};
        mc_if_step(&s, &c, &in, &o);
        assert_true(o.open);
    }
}

/* the alignment: n_align periods at theta - 90 deg, then turned to theta over n_align, at rest */
static void test_alignment(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_align(&s, &c, 0.3f, 1.0f);
    mc_if_out_t o;
    for (uint32_t k = 0; k < 2u * c.n_align; ++k) {
        const mc_if_in_t in = {.omega_target = 80.0f, .theta_est = 0.0f, .omega_est = 0.0f};
        mc_if_step(&s, &c, &in, &o);
        assert_true(o.open);
        const float back = k < c.n_align ? 1.0f : (float)(2u * c.n_align - 1u - k) / (float)c.n_align;
        assert_float_equal(o.theta, 0.3f - 0.5f * MC_PI * back, 1e-6f);
        assert_float_equal(o.omega, 0.0f, 0.0f);
    }
    const mc_if_in_t in = {.omega_target = 80.0f, .theta_est = 0.0f, .omega_est = 0.0f};
    mc_if_step(&s, &c, &in, &o);
    assert_float_equal(o.theta, 0.3f, 1e-6f);   /* then the ramp from theta */
    assert_true(s.omega > 0.0f);
}

/* from w_l on, an estimate behind the frame by more than 45 deg (the mirrored solution) is
 * flagged for a reseed, and never handed over to */
static void test_reseed_mirror(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_enter(&s, &c, 0.0f, 150.0f, 1.0f);
    mc_if_out_t o;
    for (int k = 0; k < 100; ++k) {
        const mc_if_in_t in = {.omega_target = 150.0f, .theta_est = mc_wrap_pi(s.theta + MC_PI), .omega_est = 150.0f};
        mc_if_step(&s, &c, &in, &o);
        assert_true(o.reseed);
        assert_false(o.handover);
    }
    assert_int_equal(s.mode, MC_IF_OPEN);
    const mc_if_in_t ok = {.omega_target = 150.0f, .theta_est = mc_wrap_pi(s.theta + 0.5f), .omega_est = 150.0f};
    mc_if_step(&s, &c, &ok, &o);
    assert_false(o.reseed);
}

/* torque mode (est_only): the frame holds still; the estimate above w_h hands over at once */
static void test_est_only(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_enter(&s, &c, 0.2f, 0.0f, 1.0f);
    mc_if_out_t o = {0};
    int k = 0;
    for (; k < 100 && !o.handover; ++k) {
        const mc_if_in_t in = {.omega_target = 500.0f, .theta_est = 2.0f, .omega_est = 150.0f, .est_only = true};
        mc_if_step(&s, &c, &in, &o);
        if (!o.handover) {
            assert_float_equal(o.theta, 0.2f, 0.0f);
        }
    }
    assert_true(o.handover);
    assert_int_equal(k, (int)c.n_sync);
    assert_float_equal(o.theta, 2.0f, 0.0f);
}

/* The slip (pull-out): a rotor in step swinging +-60 deg about a 40 deg load angle keeps it within
 * a swing of the frame however long it runs; a stalled rotor (the estimate at rest, reseeded
 * whenever it cannot be the rotor's) loses a full turn once the frame has advanced 2 pi from w_l,
 * and the reseeds' jumps are not counted as the rotor's motion. */
static void run_slip(const mc_if_cfg_t *c, mc_if_t *s, int n, float sign, bool stalled, float *slip_max, int *k_turn)
{
    mc_if_enter(s, c, 0.0f, 0.0f, sign);
    mc_if_out_t o = {0};
    float est = 0.0f, frame_adv = 0.0f, frame_prev = 0.0f;
    *slip_max = 0.0f;
    *k_turn = -1;
    for (int k = 0; k < n; ++k) {
        const float t = (float)k * c->ts;
        if (!stalled) {
            est = mc_wrap_pi(s->theta + sign * (0.7f + 1.05f * sinf(2.0f * MC_PI * 7.0f * t)));
        }
        const float w_est = stalled ? 0.0f : s->omega;
        const mc_if_in_t in = {.omega_target = sign * (stalled ? 300.0f : 90.0f), .theta_est = est, .omega_est = w_est};
        const bool counted = s->slip_on;
        mc_if_step(s, c, &in, &o);
        assert_true(o.open);
        assert_float_equal(o.slip, s->slip, 0.0f);
        if (counted && s->slip_on) {   /* the frame's motion since the last period, as counted */
            frame_adv += fabsf(mc_wrap_pi(o.theta - frame_prev));
        }
        frame_prev = o.theta;
        if (o.reseed) {
            est = o.theta_reseed;   /* the source reset there; a stalled one stays */
            assert_float_equal(o.theta_reseed, mc_wrap_pi(o.theta + sign * 0.25f * MC_PI), 1e-6f);
        }
        *slip_max = fmaxf(*slip_max, o.slip);
        if (*k_turn < 0 && fabsf(o.slip) >= 2.0f * MC_PI) {
            *k_turn = k;
            /* never more than the frame turned since the count began (stalled: exactly that,
             * the reseeds' jumps left out) */
            assert_true(fabsf(o.slip) <= frame_adv + 1e-3f);
            if (stalled) {
                assert_float_equal(fabsf(o.slip), frame_adv, 1e-3f);
            }
        }
    }
}

static void test_slip_in_step(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    for (int sg = -1; sg <= 1; sg += 2) {
        mc_if_t s;
        float mx;
        int k;
        run_slip(&c, &s, 20000, (float)sg, false, &mx, &k);   /* 2 s, up to 90 rad/s: open loop */
        assert_int_equal(k, -1);
        assert_true(fabsf(s.slip) < 2.0f);   /* within the swing: 0.7 +- 1.05 rad about the start */
    }
}

static void test_slip_stalled(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    for (int sg = -1; sg <= 1; sg += 2) {
        mc_if_t s;
        float mx;
        int k;
        run_slip(&c, &s, 20000, (float)sg, true, &mx, &k);
        /* counted from w_l = 50 rad/s (k = 500) on the 1000 rad/s^2 ramp, the reseeds (every
         * quarter turn of the frame) not undoing any of it: a turn once 50 t + 500 t^2 = 2 pi,
         * t = 72.7 ms */
        assert_true(k >= 500 + 722);
        assert_true(k <= 500 + 732);
        assert_true(mx >= 2.0f * MC_PI);   /* positive: the frame ahead in the torque's direction, either sign */
    }
}

/* Not counted: below w_l, and in torque mode (est_only: no frame speed of its own) */
static void test_slip_not_counted(void **st)
{
    (void)st;
    const mc_if_cfg_t c = cfg();
    mc_if_t s;
    mc_if_enter(&s, &c, 0.0f, 0.0f, 1.0f);
    mc_if_out_t o;
    for (int k = 0; k < 490; ++k) {   /* up to 49 rad/s */
        const mc_if_in_t in = {.omega_target = 300.0f, .theta_est = 0.0f, .omega_est = 0.0f};
        mc_if_step(&s, &c, &in, &o);
        assert_float_equal(o.slip, 0.0f, 0.0f);
    }
    mc_if_enter(&s, &c, 0.0f, 200.0f, 1.0f);
    for (int k = 0; k < 2000; ++k) {
        const mc_if_in_t in = {.theta_est = 0.0f, .omega_est = 0.0f, .est_only = true};
        mc_if_step(&s, &c, &in, &o);
        assert_float_equal(o.slip, 0.0f, 0.0f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cfg_valid),         cmocka_unit_test(test_ramp_and_angle),
        cmocka_unit_test(test_handover_after_reduction), cmocka_unit_test(test_reentry_hysteresis),
        cmocka_unit_test(test_alignment),         cmocka_unit_test(test_reseed_mirror),
        cmocka_unit_test(test_est_only),          cmocka_unit_test(test_slip_in_step),
        cmocka_unit_test(test_slip_stalled),      cmocka_unit_test(test_slip_not_counted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
