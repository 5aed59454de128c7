/* Protection on its own (mc/protect.h): the hard trips and sensor checks, the running detectors
 * and the reactions, each on a state and a configuration of its own, no drive. */
#include <float.h>
#include <math.h>

#include "../mc_test.h"
#include "mc/drive.h"
#include "mc/protect.h"
#include "mc/sequencer.h"

#define TS 1e-4f

/* a 5-pole-pair machine (the thesis motor's entries) on 12-bit ADCs, every detector on */
static mc_protect_cfg_t config(void)
{
    return (mc_protect_cfg_t){.ts = TS, .pole_pairs = 5, .adc_max = 4095, .i_trip = 18.0f, .vdc_min = 100.0f,
                              .vdc_max = 400.0f, .i_sum_tol = 1.0f, .i_sum_n = 10u, .overspeed = 1000.0f,
                              .track_err = 2.0f, .track_n = 200u, .lock_tol = 0.3f, .lock_floor = 20.0f,
                              .lock_n = 200u, .jump_n = 20u, .jump = 0.5f, .stall_speed = 10.0f,
                              .stall_torque = 9.0f, .stall_n = 300u, .accel_n = 100u, .accel_torque = 5.0f,
                              .accel_per_nm = 100.0f, .resid_v = 20.0f, .resid_w_coef = 0.05f, .resid_n = 300u,
                              .avg_k = 1.0f - expf(-6.2831853f * 20.0f * TS), .rs = 0.4f, .ld = 10.5e-3f,
                              .lq = 12.9e-3f, .psi_pm = 0.34305f, .recover = true, .hold_fw = true,
                              .ug_coef = 1.7320508f * 0.34305f, .retries = 2u, .retry_reset_n = 100u};
}

static hal_adc_sample_t mid(void)
{
    return (hal_adc_sample_t){.i = {2048u, 2048u, 2048u}, .vdc = 2000u, .overrun = false};
}

/* The hard trips in their order (over-current before the link voltage before the sensors), the
 * ADC rails as over-current, and the sum check counting its periods even when another trips. */
static void test_hard_trips(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    mc_protect_t s = {0};
    mc_protect_reset(&s, &c, 0.0f);
    hal_adc_sample_t raw = mid();
    const mc_abc_t zero = {0.0f, 0.0f, 0.0f};
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), 0u);
    const mc_abc_t over = {18.5f, -9.0f, -9.5f};
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, over, 300.0f), MC_FAULT_OVERCURRENT);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, over, 500.0f), MC_FAULT_OVERCURRENT);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 401.0f), MC_FAULT_OVERVOLTAGE);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 99.0f), MC_FAULT_UNDERVOLTAGE);
    for (int k = 0; k < 3; ++k) {
        raw = mid();
        raw.i[k] = 0u;
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), MC_FAULT_OVERCURRENT);
        raw.i[k] = 4095u;
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), MC_FAULT_OVERCURRENT);
        raw.i[k] = 4094u;
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), 0u);
    }
    raw = mid();
    raw.overrun = true;
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), MC_FAULT_OVERRUN);
    /* the currents do not sum to zero: a fault after i_sum_n periods in a row, not before; the
     * count goes on under a period's over-voltage trip */
    raw = mid();
    const mc_abc_t off = {1.5f, 0.0f, 0.0f};
    for (uint32_t n = 1u; n < c.i_sum_n - 1u; ++n) {
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), 0u);
    }
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 401.0f), MC_FAULT_OVERVOLTAGE);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), MC_FAULT_CURRENT_SENSOR);
    /* one good period starts it again */
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), 0u);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), 0u);
}

/* A code beyond the configured span (hw.adc_bits below the port's 16-bit word: a converter set to
 * more bits or left-aligned data) measures no current either: it trips as the upper rail on every
 * phase, in its first period, whatever the float currents say; the code just below the rail does
 * not, however long. */
static void test_adc_code_beyond_span(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const mc_abc_t zero = {0.0f, 0.0f, 0.0f};
    const uint16_t beyond[] = {(uint16_t)(c.adc_max + 1), 0x8000u, 0xFFF0u, 0xFFFFu};
    for (int k = 0; k < 3; ++k) {
        for (size_t b = 0; b < sizeof beyond / sizeof beyond[0]; ++b) {
            mc_protect_t s;
            mc_protect_reset(&s, &c, 0.0f);
            hal_adc_sample_t raw = mid();
            raw.i[k] = beyond[b];
            assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), MC_FAULT_OVERCURRENT);
        }
        mc_protect_t s;
        mc_protect_reset(&s, &c, 0.0f);
        hal_adc_sample_t raw = mid();
        raw.i[k] = (uint16_t)(c.adc_max - 1);
        for (int n = 0; n < 100; ++n) {
            assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), 0u);
        }
    }
}

/* The over-current trip level on every phase and both signs, the other two phases carrying the
 * return current (the sum stays zero): a float step beyond i_trip trips in the period it is seen
 * (detection time: one period, no persistence), i_trip itself and a little below never do. */
static void test_overcurrent_every_phase(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const hal_adc_sample_t raw = mid();
    for (int k = 0; k < 3; ++k) {
        for (int sign = -1; sign <= 1; sign += 2) {
            const float levels[3] = {c.i_trip - 0.05f, c.i_trip, nextafterf(c.i_trip, 2.0f * c.i_trip)};
            for (int l = 0; l < 3; ++l) {
                const float x = (float)sign * levels[l];
                float ph[3] = {-0.5f * x, -0.5f * x, -0.5f * x};
                ph[k] = x;
                const mc_abc_t i = {ph[0], ph[1], ph[2]};
                mc_protect_t s;
                mc_protect_reset(&s, &c, 0.0f);
                if (l < 2) {   /* at or below the level: never, however long */
                    for (int n = 0; n < 1000; ++n) {
                        assert_int_equal(mc_protect_sensors(&s, &c, &raw, i, 300.0f), 0u);
                    }
                } else {       /* beyond it: the first period */
                    assert_int_equal(mc_protect_sensors(&s, &c, &raw, i, 300.0f), MC_FAULT_OVERCURRENT);
                }
            }
        }
    }
}

/* A steady state that fits the model (5.1) at speed w: i_q flowing, the voltage the machine needs. */
static mc_protect_in_t steady(const mc_protect_cfg_t *c, float w, float iq)
{
    const mc_dq_t i = {0.0f, iq};
    const mc_dq_t u = {-w * c->lq * iq, c->rs * iq + w * c->psi_pm};
    return (mc_protect_in_t){.theta = 0.1f, .omega = w, .theta_raw = 0.1f, .omega_raw = w, .i_ref = i, .i_fb = i,
                             .u_dq = u, .torque_ref = 2.0f, .speed_mode = false};
}

static uint32_t run(mc_protect_t *s, const mc_protect_cfg_t *c, const mc_protect_in_t *in, int n, bool *doubt_seen)
{
    uint32_t r = 0u;
    for (int k = 0; k < n && r == 0u; ++k) {
        bool doubt = false;
        r = mc_protect_running(s, c, in, &doubt);
        if (doubt_seen != NULL) {
            *doubt_seen = *doubt_seen || doubt;
        }
    }
    return r;
}

/* The running checks: quiet on a plausible steady state; over-speed (and NaN) at once, except
 * while its reaction holds; loss of lock after its persistence, in doubt at a quarter of it and
 * waiting while the polarity re-check runs; the fast path; tracking; the residual of (5.1). */
static void test_running_checks(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    mc_protect_t s;
    const float w = 500.0f;
    mc_protect_reset(&s, &c, w);
    mc_protect_in_t in = steady(&c, w, 5.0f);
    bool doubt = false;
    assert_int_equal(run(&s, &c, &in, 5000, &doubt), 0u);
    assert_false(doubt);
    /* over-speed */
    in.omega = 1001.0f;
    assert_int_equal(run(&s, &c, &in, 1, NULL), MC_FAULT_OVERSPEED);
    in.omega = NAN;
    assert_int_equal(run(&s, &c, &in, 1, NULL), MC_FAULT_OVERSPEED);
    in.reacting = true;
    assert_int_equal(run(&s, &c, &in, 1, NULL), MC_FAULT_OVERSPEED);   /* NaN even then */
    in.omega = 1001.0f;   /* latched already in its reaction: the other checks go on */
    mc_protect_reset(&s, &c, in.omega);
    in.omega_raw = in.omega;
    assert_int_equal(run(&s, &c, &in, 1, NULL), 0u);
    /* loss of lock: the raw speed on the other side */
    mc_protect_reset(&s, &c, w);
    in = steady(&c, w, 5.0f);
    in.omega_raw = -w;
    doubt = false;
    int n = 0;
    uint32_t r = 0u;
    while (r == 0u && n < 2000) {
        bool dq = false;
        r = mc_protect_running(&s, &c, &in, &dq);
        if (dq) {
            assert_int_equal(s.lock_n, c.lock_n / 4u);
            doubt = true;
        }
        ++n;
    }
    assert_int_equal(r, MC_FAULT_LOSS_OF_LOCK);
    assert_true(doubt);
    assert_true(n >= (int)c.lock_n && n < (int)c.lock_n + 100);   /* persistence + the 20 Hz average */
    /* ... which waits while the re-check runs */
    mc_protect_reset(&s, &c, w);
    in.lock_paused = true;
    assert_int_equal(run(&s, &c, &in, 3000, NULL), 0u);
    /* the fast path: the raw angle 1 rad off the filtered one, jump_n periods */
    mc_protect_reset(&s, &c, w);
    in = steady(&c, w, 5.0f);
    in.theta_raw = in.theta + 1.0f;
    for (uint32_t k = 1u; k < c.jump_n; ++k) {
        assert_int_equal(run(&s, &c, &in, 1, NULL), 0u);
    }
    assert_int_equal(run(&s, &c, &in, 1, NULL), MC_FAULT_LOSS_OF_LOCK);
    /* tracking: the current 4 A off its reference */
    mc_protect_reset(&s, &c, w);
    in = steady(&c, w, 5.0f);
    in.i_ref.q = 9.0f;
    assert_int_equal(run(&s, &c, &in, 3000, NULL), MC_FAULT_TRACKING);
    /* the voltage model: half of the back-EMF unexplained (a wrong angle, an open phase) */
    mc_protect_reset(&s, &c, w);
    in = steady(&c, w, 5.0f);
    in.u_dq.q *= 0.5f;
    assert_int_equal(run(&s, &c, &in, 3000, NULL), MC_FAULT_VOLTAGE_MODEL);
    /* a detector with persistence 0 is off */
    mc_protect_cfg_t off = c;
    off.resid_n = 0u;
    mc_protect_reset(&s, &off, w);
    assert_int_equal(run(&s, &off, &in, 3000, NULL), 0u);
}

/* A strongly salient machine (Lq = 2.5 Ld), for the residual's cross-coupling terms. */
static mc_protect_cfg_t salient(void)
{
    mc_protect_cfg_t c = config();
    c.ld = 6.0e-3f;
    c.lq = 15.0e-3f;
    return c;
}

/* The voltage (5.1) needs at speed w with current i, computed in double on its own. */
static mc_dq_t model_u(const mc_protect_cfg_t *c, float w, mc_dq_t i)
{
    const double ud = (double)c->rs * i.d - (double)w * c->lq * i.q;
    const double uq = (double)c->rs * i.q + (double)w * ((double)c->ld * i.d + c->psi_pm);
    return (mc_dq_t){(float)ud, (float)uq};
}

/* The residual of (5.1) itself on a salient machine: ~0 where the machine fits the model (at
 * speeds, currents and signs where w (Lq - Ld) i_q and w (Lq - Ld) i_d are tens of volts, far
 * beyond the tolerance), and exactly an added voltage where it does not. */
static void test_residual(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = salient();
    const float ws[] = {500.0f, -500.0f, 150.0f};
    const mc_dq_t is[] = {{0.0f, 8.0f}, {-3.0f, 8.0f}, {-6.0f, -10.0f}};
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            const mc_dq_t u = model_u(&c, ws[a], is[b]);
            const mc_dq_t r = mc_protect_residual(&c, u, is[b], ws[a]);
            assert_float_equal(r.d, 0.0f, 2e-3f);
            assert_float_equal(r.q, 0.0f, 2e-3f);
            const mc_dq_t r2 = mc_protect_residual(&c, (mc_dq_t){u.d + 3.0f, u.q - 4.0f}, is[b], ws[a]);
            assert_float_equal(r2.d, 3.0f, 2e-3f);
            assert_float_equal(r2.q, -4.0f, 2e-3f);
        }
    }
    /* the speed's terms on their own: a machine at standstill leaves only the resistance */
    const mc_dq_t r0 = mc_protect_residual(&c, (mc_dq_t){1.0f, 2.0f}, (mc_dq_t){2.5f, 5.0f}, 0.0f);
    assert_float_equal(r0.d, 1.0f - 0.4f * 2.5f, 1e-6f);
    assert_float_equal(r0.q, 2.0f - 0.4f * 5.0f, 1e-6f);
}

/* The voltage-model check (protection.residual_time_s) near its threshold on the salient
 * machine at 500 rad/s el, 8 A in q, -3 A in d: a voltage off the model by 1.1 x the threshold
 * (resid_v + resid_w_coef |w| = 45 V) along +-d or +-q trips after the 20 Hz average has crossed
 * the threshold (191 periods, as for the torque check) plus the persistence; 0.9 x never. */
/* Runs the running checks on a fixed input until a fault or n periods; *periods: how many ran. */
static uint32_t run_for(mc_protect_t *s, const mc_protect_cfg_t *c, const mc_protect_in_t *in, int n, int *periods)
{
    uint32_t r = 0u;
    int k = 0;
    while (k < n && r == 0u) {
        bool doubt;
        r = mc_protect_running(s, c, in, &doubt);
        ++k;
    }
    *periods = k;
    return r;
}

static void test_voltage_model_threshold(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = salient();
    const float w = 500.0f;
    const mc_dq_t i = {-3.0f, 8.0f};
    const float r_max = c.resid_v + c.resid_w_coef * w;
    const int cross = (int)ceilf(logf(1.0f - 1.0f / 1.1f) / logf(1.0f - c.avg_k));
    const mc_dq_t dirs[] = {{-1.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, -1.0f}, {0.0f, 1.0f}};
    for (int d = 0; d < 4; ++d) {
        for (int side = 0; side < 2; ++side) {
            const float f = side == 0 ? 0.9f : 1.1f;
            const mc_dq_t u = model_u(&c, w, i);
            mc_protect_in_t in = {.theta = 0.1f, .omega = w, .theta_raw = 0.1f, .omega_raw = w, .i_ref = i,
                                  .i_fb = i, .torque_ref = 2.0f, .speed_mode = false};
            in.u_dq = (mc_dq_t){u.d + f * r_max * dirs[d].d, u.q + f * r_max * dirs[d].q};
            mc_protect_t s;
            mc_protect_reset(&s, &c, w);
            int n = 0;
            const uint32_t r = run_for(&s, &c, &in, 3000, &n);
            if (side == 0) {
                assert_int_equal(r, 0u);
            } else {
                assert_int_equal(r, MC_FAULT_VOLTAGE_MODEL);
                assert_true(n >= cross + (int)c.resid_n - 2 && n <= cross + (int)c.resid_n + 2);
            }
        }
    }
}

/* Speed mode: a stall (the torque at its limit, no speed) and a torque that the speed estimate
 * contradicts; neither outside speed mode. */
static void test_speed_mode_checks(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    mc_protect_t s;
    mc_protect_reset(&s, &c, 0.0f);
    mc_protect_in_t in = steady(&c, 0.0f, 5.0f);
    in.torque_ref = 9.5f;
    in.speed_ref = 100.0f;   /* 500 rad/s el */
    assert_int_equal(run(&s, &c, &in, 1000, NULL), 0u);
    in.speed_mode = true;
    assert_int_equal(run(&s, &c, &in, 1000, NULL), MC_FAULT_STALL);
    /* accelerating at 2000 rad/s^2 against 8 N m (half of its 800 would be plausible) */
    mc_protect_reset(&s, &c, 300.0f);
    in = steady(&c, 300.0f, 5.0f);
    in.speed_mode = true;
    in.speed_ref = 100.0f;
    in.torque_ref = 8.0f;
    in.i_ref = in.i_fb = (mc_dq_t){0.0f, 0.0f};
    uint32_t r = 0u;
    for (int k = 0; k < 2000 && r == 0u; ++k) {
        in.omega = in.omega_raw = 300.0f - 2000.0f * TS * (float)k;
        in.u_dq = (mc_dq_t){0.0f, in.omega * c.psi_pm};
        bool doubt;
        r = mc_protect_running(&s, &c, &in, &doubt);
    }
    assert_int_equal(r, MC_FAULT_TORQUE);
}

/* Speed mode at torque t_ref with the speed estimate on a ramp of slope acc [rad/s^2 el] from w0,
 * the rest of the drive plausible (no current, the back-EMF as the voltage). Returns the fault
 * and in *periods the period it came in (1-based), or 0 after n periods. */
static uint32_t ramp(const mc_protect_cfg_t *c, float t_ref, float w0, float acc, int n, int *periods)
{
    mc_protect_t s;
    mc_protect_reset(&s, c, w0);
    mc_protect_in_t in = steady(c, w0, 0.0f);
    in.speed_mode = true;
    in.speed_ref = 100.0f;
    in.torque_ref = t_ref;
    uint32_t r = 0u;
    int k = 0;
    while (k < n && r == 0u) {
        in.omega = in.omega_raw = w0 + acc * TS * (float)k;
        in.u_dq = (mc_dq_t){0.0f, in.omega * c->psi_pm};
        bool doubt;
        r = mc_protect_running(&s, c, &in, &doubt);
        ++k;
    }
    *periods = k;
    return r;
}

/* Torque plausibility (MC_FAULT_TORQUE, protection.accel_time_s): a strong torque (|T| from
 * accel_torque) with the speed estimate accelerating the other way at more than accel_per_nm |T|
 * (half of what the torque alone would give). Either sign; at 10 % beyond that limit it trips
 * after the average has crossed it (the 20 Hz low-pass: ln(1 - 800/880) / ln(1 - k) = 191
 * periods) plus the persistence, at 10 % within it never; a speed following its torque (even
 * fast) never, nor a torque below accel_torque, nor outside speed mode. */
static void test_torque_plausibility(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const float lim = c.accel_per_nm * 8.0f;   /* 800 rad/s^2 el at 8 N m */
    const int cross = (int)ceilf(logf(1.0f - 1.0f / 1.1f) / logf(1.0f - c.avg_k));
    int n = 0;
    /* against the torque at 1.1 x the limit: trips, each sign, after crossing + persistence */
    assert_int_equal(ramp(&c, 8.0f, 300.0f, -1.1f * lim, 5000, &n), MC_FAULT_TORQUE);
    assert_true(n >= cross + (int)c.accel_n - 2 && n <= cross + (int)c.accel_n + 2);
    assert_int_equal(ramp(&c, -8.0f, -300.0f, 1.1f * lim, 5000, &n), MC_FAULT_TORQUE);
    assert_true(n >= cross + (int)c.accel_n - 2 && n <= cross + (int)c.accel_n + 2);
    /* a shorter persistence: the detection time follows it */
    mc_protect_cfg_t shorter = c;
    shorter.accel_n = 10u;
    assert_int_equal(ramp(&shorter, 8.0f, 300.0f, -1.1f * lim, 5000, &n), MC_FAULT_TORQUE);
    assert_true(n >= cross + 10 - 2 && n <= cross + 10 + 2);
    /* against the torque at 0.9 x the limit: never (3000 periods, the average settled) */
    assert_int_equal(ramp(&c, 8.0f, 300.0f, -0.9f * lim, 3000, &n), 0u);
    assert_int_equal(ramp(&c, -8.0f, -300.0f, 0.9f * lim, 3000, &n), 0u);
    /* the speed following a strong torque, 2.5 x the limit: never */
    assert_int_equal(ramp(&c, 8.0f, -300.0f, 2.5f * lim, 3000, &n), 0u);
    assert_int_equal(ramp(&c, -8.0f, 300.0f, -2.5f * lim, 3000, &n), 0u);
    /* a torque just below accel_torque, even against a hard deceleration: never */
    assert_int_equal(ramp(&c, nextafterf(c.accel_torque, 0.0f), 300.0f, -2000.0f, 3000, &n), 0u);
    assert_int_equal(ramp(&c, c.accel_torque, 300.0f, -2000.0f, 3000, &n), MC_FAULT_TORQUE);
}

/* Periods for a 20 Hz average starting at 0 to cross 1 / f of its final value. */
static int crossing(const mc_protect_cfg_t *c, float f)
{
    return (int)ceilf(logf(1.0f - 1.0f / f) / logf(1.0f - c->avg_k));
}

/* The sensor checks next to their limits: the current sum 1 % beyond i_sum_tol (either sign)
 * after exactly i_sum_n periods, 1 % within never; the link at its window's edges never, one
 * float step outside at once. */
static void test_sensor_limits(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const hal_adc_sample_t raw = mid();
    mc_protect_t s;
    for (int sign = -1; sign <= 1; sign += 2) {
        const float x = (float)sign * c.i_sum_tol;
        const mc_abc_t in_tol = {0.5f * x, 0.49f * x, 0.0f}, out_tol = {0.5f * x, 0.51f * x, 0.0f};
        mc_protect_reset(&s, &c, 0.0f);
        for (int n = 0; n < 1000; ++n) {
            assert_int_equal(mc_protect_sensors(&s, &c, &raw, in_tol, 300.0f), 0u);
        }
        mc_protect_reset(&s, &c, 0.0f);
        for (uint32_t n = 1u; n < c.i_sum_n; ++n) {
            assert_int_equal(mc_protect_sensors(&s, &c, &raw, out_tol, 300.0f), 0u);
        }
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, out_tol, 300.0f), MC_FAULT_CURRENT_SENSOR);
    }
    const mc_abc_t zero = {0.0f, 0.0f, 0.0f};
    mc_protect_reset(&s, &c, 0.0f);
    for (int n = 0; n < 100; ++n) {
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, c.vdc_max), 0u);
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, c.vdc_min), 0u);
    }
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, nextafterf(c.vdc_max, 1e9f)), MC_FAULT_OVERVOLTAGE);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, nextafterf(c.vdc_min, 0.0f)), MC_FAULT_UNDERVOLTAGE);
}

/* A persisting condition is a level, not an edge: once the current sum has been out of its
 * tolerance for i_sum_n periods the fault is returned in every further period it stays out, so a
 * trip of higher priority (the link voltage) in exactly the i_sum_n-th period does not hide it:
 * the next period reports it; one period back within the tolerance ends it. */
static void test_sensor_fault_persists(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const hal_adc_sample_t raw = mid();
    const mc_abc_t off = {1.5f, 0.0f, 0.0f}, zero = {0.0f, 0.0f, 0.0f};
    mc_protect_t s;
    mc_protect_reset(&s, &c, 0.0f);
    for (uint32_t n = 1u; n < c.i_sum_n; ++n) {
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), 0u);
    }
    for (int n = 0; n < 50; ++n) {
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), MC_FAULT_CURRENT_SENSOR);
    }
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, zero, 300.0f), 0u);
    /* masked in its i_sum_n-th period, reported in the next */
    mc_protect_reset(&s, &c, 0.0f);
    for (uint32_t n = 1u; n < c.i_sum_n; ++n) {
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), 0u);
    }
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 401.0f), MC_FAULT_OVERVOLTAGE);
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), MC_FAULT_CURRENT_SENSOR);
}

/* Over-speed at its limit (either sign) never, one float step beyond at once. */
static void test_overspeed_limit(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    for (int sign = -1; sign <= 1; sign += 2) {
        const float w = (float)sign * c.overspeed;
        mc_protect_t s;
        mc_protect_reset(&s, &c, w);
        mc_protect_in_t in = steady(&c, w, 5.0f);
        int n = 0;
        assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
        in.omega = in.omega_raw = nextafterf(w, 2.0f * w);
        assert_int_equal(run_for(&s, &c, &in, 1, &n), MC_FAULT_OVERSPEED);
        /* in its reaction (latched already) any finite speed, however far beyond, is no new
         * over-speed; an infinite one still is (the bound excludes only inf and NaN) */
        in.reacting = true;
        in.omega = in.omega_raw = (float)sign * FLT_MAX;
        mc_protect_reset(&s, &c, w);
        assert_int_equal(run_for(&s, &c, &in, 1, &n), 0u);
        in.omega = in.omega_raw = (float)sign * INFINITY;
        assert_int_equal(run_for(&s, &c, &in, 1, &n), MC_FAULT_OVERSPEED);
    }
}

/* Tracking next to its limit: the current error 1.1 x track_err along +-d or +-q trips after the
 * average's crossing + track_n periods, 0.9 x never. */
static void test_tracking_limit(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const float w = 500.0f;
    const mc_dq_t dirs[] = {{1.0f, 0.0f}, {-1.0f, 0.0f}, {0.0f, 1.0f}, {0.0f, -1.0f}};
    for (int d = 0; d < 4; ++d) {
        for (int side = 0; side < 2; ++side) {
            const float f = side == 0 ? 0.9f : 1.1f;
            mc_protect_t s;
            mc_protect_reset(&s, &c, w);
            mc_protect_in_t in = steady(&c, w, 5.0f);
            in.i_ref.d += f * c.track_err * dirs[d].d;
            in.i_ref.q += f * c.track_err * dirs[d].q;
            int n = 0;
            const uint32_t r = run_for(&s, &c, &in, 3000, &n);
            if (side == 0) {
                assert_int_equal(r, 0u);
            } else {
                assert_int_equal(r, MC_FAULT_TRACKING);
                const int t = crossing(&c, 1.1f) + (int)c.track_n;
                assert_true(n >= t - 2 && n <= t + 2);
            }
        }
    }
}

/* Loss of lock next to its limits: (a) the raw speed 1.1 x the band (lock_tol |w| + lock_floor)
 * off the filtered one, either side, after the average's crossing + lock_n periods, 0.9 x never;
 * the swing: the filtered speed oscillating at 200 Hz with an rms 1.1 x lock_floor about its
 * average trips within the persistence + the mean square's settling, 0.9 x never; the fast path:
 * the raw angle 1.1 x lock_jump off the PLL's (either side) after exactly jump_n periods, 0.9 x
 * never. */
static void test_lock_limits(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const float w = 500.0f, band = c.lock_tol * w + c.lock_floor;
    for (int sign = -1; sign <= 1; sign += 2) {
        for (int side = 0; side < 2; ++side) {
            const float f = side == 0 ? 0.9f : 1.1f;
            mc_protect_t s;
            mc_protect_reset(&s, &c, w);
            mc_protect_in_t in = steady(&c, w, 5.0f);
            in.omega_raw = w + (float)sign * f * band;
            int n = 0;
            const uint32_t r = run_for(&s, &c, &in, 3000, &n);
            if (side == 0) {
                assert_int_equal(r, 0u);
            } else {
                assert_int_equal(r, MC_FAULT_LOSS_OF_LOCK);
                const int t = crossing(&c, 1.1f) + (int)c.lock_n;
                assert_true(n >= t - 2 && n <= t + 2);
            }
        }
    }
    /* the swing */
    for (int side = 0; side < 2; ++side) {
        const float amp = (side == 0 ? 0.9f : 1.1f) * c.lock_floor * 1.41421356f;
        mc_protect_t s;
        mc_protect_reset(&s, &c, w);
        mc_protect_in_t in = steady(&c, w, 5.0f);
        uint32_t r = 0u;
        int n = 0;
        while (r == 0u && n < 3000) {
            in.omega = in.omega_raw = w + amp * sinf(6.2831853f * 200.0f * TS * (float)n);
            in.u_dq.q = c.rs * 5.0f + in.omega * c.psi_pm;
            bool doubt;
            r = mc_protect_running(&s, &c, &in, &doubt);
            ++n;
        }
        if (side == 0) {
            assert_int_equal(r, 0u);
        } else {
            assert_int_equal(r, MC_FAULT_LOSS_OF_LOCK);
            /* mean square 1.21 floor^2 from 0: crosses floor^2 after ln(1 - 1/1.21) / ln(1 - k),
             * its 400 Hz ripple holds the condition for good a little later (18 periods here) */
            const int t = crossing(&c, 1.21f) + (int)c.lock_n;
            assert_true(n >= t && n <= t + 30);
        }
    }
    /* a ramp is not a swing: a steady acceleration whose first-order lag a ts / k is twice the
     * floor (a 20 Hz average of a 5000 rad/s^2 ramp) never trips, a swing on top of it still
     * does (the 1.1 x case above, riding the ramp) */
    for (int side = 0; side < 2; ++side) {
        const float a = 2.0f * c.lock_floor * c.avg_k / TS;
        const float amp = side == 0 ? 0.0f : 1.1f * c.lock_floor * 1.41421356f;
        mc_protect_t s;
        mc_protect_reset(&s, &c, 300.0f);
        uint32_t r = 0u;
        int n = 0;
        for (; r == 0u && n < 1200; ++n) {
            const float w = 300.0f + a * TS * (float)n;
            mc_protect_in_t in = steady(&c, w, 5.0f);
            in.omega = in.omega_raw = w + amp * sinf(6.2831853f * 200.0f * TS * (float)n);
            bool doubt;
            r = mc_protect_running(&s, &c, &in, &doubt);
        }
        assert_int_equal(r, side == 0 ? 0u : MC_FAULT_LOSS_OF_LOCK);
    }
    /* the fast path */
    for (int sign = -1; sign <= 1; sign += 2) {
        for (int side = 0; side < 2; ++side) {
            const float f = side == 0 ? 0.9f : 1.1f;
            mc_protect_t s;
            mc_protect_reset(&s, &c, w);
            mc_protect_in_t in = steady(&c, w, 5.0f);
            in.theta_raw = in.theta + (float)sign * f * c.jump;
            int n = 0;
            const uint32_t r = run_for(&s, &c, &in, 3000, &n);
            if (side == 0) {
                assert_int_equal(r, 0u);
            } else {
                assert_int_equal(r, MC_FAULT_LOSS_OF_LOCK);
                assert_int_equal(n, (int)c.jump_n);
            }
        }
    }
}

/* Stall next to its limits: the torque at stall_torque (either sign), no speed, the speed loop
 * asking for speed: after exactly stall_n periods; the speed at stall_speed, the torque a float
 * step below stall_torque, the reference at or below stall_speed, or torque mode: never. */
static void test_stall_limits(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    for (int sign = -1; sign <= 1; sign += 2) {
        const float sg = (float)sign;
        mc_protect_in_t base = steady(&c, 0.0f, 5.0f);
        base.speed_mode = true;
        base.speed_ref = sg * 100.0f;
        base.torque_ref = sg * c.stall_torque;
        base.omega = base.omega_raw = sg * nextafterf(c.stall_speed, 0.0f);
        base.u_dq.q = c.rs * 5.0f + base.omega * c.psi_pm;
        mc_protect_t s;
        mc_protect_reset(&s, &c, base.omega);
        int n = 0;
        assert_int_equal(run_for(&s, &c, &base, 3000, &n), MC_FAULT_STALL);
        assert_int_equal(n, (int)c.stall_n);
        mc_protect_in_t in = base;
        in.omega = in.omega_raw = sg * c.stall_speed;
        in.u_dq.q = c.rs * 5.0f + in.omega * c.psi_pm;
        mc_protect_reset(&s, &c, in.omega);
        assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
        /* ... and well above it (accelerating at full torque toward a far reference: no stall) */
        in.omega = in.omega_raw = sg * 10.0f * c.stall_speed;
        in.speed_ref = sg * 200.0f;
        in.u_dq.q = c.rs * 5.0f + in.omega * c.psi_pm;
        mc_protect_reset(&s, &c, in.omega);
        assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
        in = base;
        in.torque_ref = sg * nextafterf(c.stall_torque, 0.0f);
        mc_protect_reset(&s, &c, in.omega);
        assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
        in = base;
        in.speed_ref = sg * c.stall_speed / (float)c.pole_pairs;
        mc_protect_reset(&s, &c, in.omega);
        assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
        /* a reference below the stall speed (0: holding a load at standstill with full torque,
         * half of it: creeping) is the speed loop doing its job: never */
        const float below[] = {0.0f, 0.5f * c.stall_speed / (float)c.pole_pairs};
        for (int b = 0; b < 2; ++b) {
            in = base;
            in.speed_ref = sg * below[b];
            mc_protect_reset(&s, &c, in.omega);
            assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
        }
        in = base;
        in.speed_mode = false;
        mc_protect_reset(&s, &c, in.omega);
        assert_int_equal(run_for(&s, &c, &in, 3000, &n), 0u);
    }
}

/* A reset (a new start, a retry) gives every detector its whole persistence again: a condition
 * held for all but one period before it counts from zero after it, for the sensor sum and the
 * stall alike (a carried count would trip a retry in its first period). */
static void test_reset_restarts_persistence(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    const hal_adc_sample_t raw = mid();
    const mc_abc_t off = {1.5f, 0.0f, 0.0f};
    mc_protect_t s;
    mc_protect_reset(&s, &c, 0.0f);
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t n = 1u; n < c.i_sum_n; ++n) {
            assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), 0u);
        }
        mc_protect_reset(&s, &c, 0.0f);
    }
    for (uint32_t n = 1u; n < c.i_sum_n; ++n) {
        assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), 0u);
    }
    assert_int_equal(mc_protect_sensors(&s, &c, &raw, off, 300.0f), MC_FAULT_CURRENT_SENSOR);

    mc_protect_in_t in = steady(&c, 0.0f, 5.0f);
    in.speed_mode = true;
    in.speed_ref = 100.0f;
    in.torque_ref = c.stall_torque;
    int n = 0;
    mc_protect_reset(&s, &c, 0.0f);
    assert_int_equal(run_for(&s, &c, &in, (int)c.stall_n - 1, &n), 0u);
    mc_protect_reset(&s, &c, 0.0f);
    assert_int_equal(run_for(&s, &c, &in, (int)c.stall_n - 1, &n), 0u);
    assert_int_equal(run_for(&s, &c, &in, 1, &n), MC_FAULT_STALL);
}

/* The detection times of the configuration the drive builds from its default parameters (the
 * sensorless estimator: the lock checks on), in seconds against the protection.*_time_s they
 * come from: loss of lock (the raw speed reversed: the 20 Hz average needs ~1.3 ms to say so)
 * within lock_time_s + 5 ms, its fast path (the raw angle 90 deg off) within lock_jump_time_s +
 * one period, torque plausibility (against the torque at 4 x the limit: ~2.3 ms; the lock checks
 * off as with an encoder) within accel_time_s + 5 ms, none before its time. No drive: only
 * mc_drive_build and this block. */
static void test_built_detection_times(void **st)
{
    (void)st;
    static mc_drive_cfg_t cfg;
    static mc_drive_built_t b;
    mc_param_err_t err;
    mc_drive_cfg_default(&cfg);
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_control_angle_source, "unop", NULL));
    assert_true(mc_param_set_choice(&cfg.p, MC_PARAM_estimator_model, "const", NULL));   /* no flux map */
    assert_true(mc_drive_build(&cfg, &b, &err));
    const mc_protect_cfg_t *c = &b.blk.prot;
    const float ts = b.p.control_ts_s;
    const float w = 0.5f * c->overspeed;
    mc_protect_t s;
    int n = 0;
    /* loss of lock */
    mc_protect_reset(&s, c, w);
    mc_protect_in_t in = steady(c, w, 0.0f);
    in.omega_raw = -w;
    assert_int_equal(run_for(&s, c, &in, 20000, &n), MC_FAULT_LOSS_OF_LOCK);
    float t = (float)n * ts;
    assert_true(b.p.protection_lock_time_s > 0.0f);
    assert_true(t >= b.p.protection_lock_time_s && t <= b.p.protection_lock_time_s + 5e-3f);
    /* its fast path */
    mc_protect_reset(&s, c, w);
    in = steady(c, w, 0.0f);
    in.theta_raw = in.theta + 1.5707963f;
    assert_int_equal(run_for(&s, c, &in, 20000, &n), MC_FAULT_LOSS_OF_LOCK);
    t = (float)n * ts;
    assert_true(b.p.protection_lock_jump_time_s > 0.0f);
    assert_true(t >= b.p.protection_lock_jump_time_s - 0.5f * ts && t <= b.p.protection_lock_jump_time_s + 1.5f * ts);
    /* torque plausibility */
    const float acc = -4.0f * c->accel_per_nm * c->accel_torque;
    const float w0 = 0.9f * c->overspeed;
    assert_true(w0 + acc * (b.p.protection_accel_time_s + 0.01f) > 0.0f);   /* the ramp stays in range */
    /* the lock checks off, as with an encoder: a speed estimate this steep swings about its
     * average and they would (rightly) speak first */
    mc_protect_cfg_t enc = *c;
    enc.lock_n = enc.jump_n = 0u;
    assert_int_equal(ramp(&enc, c->accel_torque, w0, acc, 20000, &n), MC_FAULT_TORQUE);
    t = (float)n * ts;
    assert_true(b.p.protection_accel_time_s > 0.0f);
    assert_true(t >= b.p.protection_accel_time_s && t <= b.p.protection_accel_time_s + 5e-3f);
}

/* The reactions: recover only the recoverable reasons, while running, retries times, counted
 * again from zero after retry_reset_n periods of RUN; hold the field weakening only for
 * over-speed above the generation speed; the reaction ends below 95 % of the link. */
static void test_reactions(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    mc_protect_t s = {0};
    mc_protect_restart(&s);
    assert_false(mc_protect_may_recover(&s, &c, MC_FAULT_OVERCURRENT, true));
    assert_false(mc_protect_may_recover(&s, &c, MC_FAULT_LOSS_OF_LOCK | MC_FAULT_STALL, true));
    assert_false(mc_protect_may_recover(&s, &c, MC_FAULT_LOSS_OF_LOCK, false));
    assert_true(mc_protect_may_recover(&s, &c, MC_FAULT_LOSS_OF_LOCK, true));
    assert_true(mc_protect_may_recover(&s, &c, MC_FAULT_TRACKING | MC_FAULT_VOLTAGE_MODEL, true));
    assert_false(mc_protect_may_recover(&s, &c, MC_FAULT_TRACKING, true));   /* retries used up */
    mc_protect_tick(&s, &c, true, c.retry_reset_n - 1u);
    assert_false(mc_protect_may_recover(&s, &c, MC_FAULT_TRACKING, true));
    mc_protect_tick(&s, &c, false, c.retry_reset_n);
    assert_false(mc_protect_may_recover(&s, &c, MC_FAULT_TRACKING, true));
    mc_protect_tick(&s, &c, true, c.retry_reset_n);
    assert_true(mc_protect_may_recover(&s, &c, MC_FAULT_TRACKING, true));
    mc_protect_restart(&s);
    assert_int_equal(s.retries, 0u);
    mc_protect_cfg_t no = c;
    no.recover = false;
    assert_false(mc_protect_may_recover(&s, &no, MC_FAULT_LOSS_OF_LOCK, true));
    /* hold_fw: the line-to-line back-EMF 0.594 V s/rad x 600 = 356 V against the link */
    assert_true(mc_protect_may_hold(&c, MC_FAULT_OVERSPEED, true, -600.0f, 300.0f));
    assert_false(mc_protect_may_hold(&c, MC_FAULT_OVERSPEED, true, 600.0f, 400.0f));
    assert_false(mc_protect_may_hold(&c, MC_FAULT_OVERSPEED, false, 600.0f, 300.0f));
    assert_false(mc_protect_may_hold(&c, MC_FAULT_TRACKING, true, 600.0f, 300.0f));
    no = c;
    no.hold_fw = false;
    assert_false(mc_protect_may_hold(&no, MC_FAULT_OVERSPEED, true, 600.0f, 300.0f));
    assert_false(mc_protect_reaction_done(&c, 600.0f, 300.0f));
    assert_false(mc_protect_reaction_done(&c, 480.0f, 300.0f));   /* 285.3 V: not below 285 */
    assert_true(mc_protect_reaction_done(&c, 475.0f, 300.0f));
}

/* I/f's open loop (mc/if_start.h): the frame a full electrical turn off the estimate is a
 * pull-out at once (either way, NaN too), just under a turn is not; out of open loop the slip
 * means nothing. In open loop the lock checks and the voltage model wait (the frame leads). */
static void test_pull_out(void **st)
{
    (void)st;
    const mc_protect_cfg_t c = config();
    mc_protect_t s;
    const float turn = 2.0f * MC_PI;
    const float slips[] = {0.999f * turn, -0.999f * turn, 1.0001f * turn, -1.0001f * turn, NAN};
    for (int k = 0; k < 5; ++k) {
        mc_protect_reset(&s, &c, 300.0f);
        mc_protect_in_t in = steady(&c, 300.0f, 5.0f);
        in.open_loop = true;
        in.if_slip = slips[k];
        assert_int_equal(run(&s, &c, &in, k < 2 ? 3000 : 1, NULL), k < 2 ? 0u : MC_FAULT_PULL_OUT);
        mc_protect_reset(&s, &c, 300.0f);
        in.open_loop = false;
        assert_int_equal(run(&s, &c, &in, 3000, NULL), 0u);
    }
    /* open loop: the raw speed far off, the raw angle off, the voltage unexplained: nothing */
    mc_protect_reset(&s, &c, 300.0f);
    mc_protect_in_t in = steady(&c, 300.0f, 5.0f);
    in.open_loop = true;
    in.omega_raw = 100.0f;
    in.theta_raw = in.theta + 2.0f;
    in.u_dq.q += 50.0f;
    assert_int_equal(run(&s, &c, &in, 3000, NULL), 0u);
    in.open_loop = false;
    assert_int_not_equal(run(&s, &c, &in, 3000, NULL), 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hard_trips),
        cmocka_unit_test(test_adc_code_beyond_span),
        cmocka_unit_test(test_overcurrent_every_phase),
        cmocka_unit_test(test_running_checks),
        cmocka_unit_test(test_residual),
        cmocka_unit_test(test_voltage_model_threshold),
        cmocka_unit_test(test_speed_mode_checks),
        cmocka_unit_test(test_torque_plausibility),
        cmocka_unit_test(test_sensor_limits),
        cmocka_unit_test(test_sensor_fault_persists),
        cmocka_unit_test(test_overspeed_limit),
        cmocka_unit_test(test_tracking_limit),
        cmocka_unit_test(test_lock_limits),
        cmocka_unit_test(test_stall_limits),
        cmocka_unit_test(test_reset_restarts_persistence),
        cmocka_unit_test(test_built_detection_times),
        cmocka_unit_test(test_reactions),
        cmocka_unit_test(test_pull_out),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
