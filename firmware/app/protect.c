/* Plausibility and loss-of-lock detectors, cheap enough for the ISR (a few compares and three
 * first-order low-passes). Each turns a condition that persists for its time (in periods, from
 * the parameter table; 0: off) into a fault with its reason; the drive's trip then turns the
 * outputs off in the same period. Detection time = persistence + the filters' settling. */
#include <math.h>
#include "mc/protect.h"
#include "mc/angle.h"
#include "mc/sequencer.h"

/* A condition held for n periods in a row (n = 0: never). */
static bool persists(uint32_t *count, bool cond, uint32_t n)
{
    *count = cond ? *count + 1u : 0u;
    return n > 0u && *count >= n;
}

/* y += k (x - y): the first-order low-pass all the detectors' averages share */
static float avg(float *y, float x, float k)
{
    *y += k * (x - *y);
    return *y;
}

void mc_protect_reset(mc_protect_t *s, const mc_protect_cfg_t *c, float omega)
{
    s->i_sum_n = s->track_n = s->lock_n = s->stall_n = s->resid_n = 0u;
    s->accel_n = s->jump_n = 0u;
    s->w_prev = omega;
    s->accel = 0.0f;
    s->err_d = s->err_q = s->w_dev2 = 0.0f;
    /* the averages start where a steady state at the estimate's speed (a caught rotor) would
     * have them: speeds at omega, the voltage at its back-EMF with no current */
    s->w_raw = s->w = s->w_trk = omega;
    s->a_trk = 0.0f;
    s->u_d = s->i_d = s->i_q = 0.0f;
    s->u_q = omega * c->psi_pm;
}

void mc_protect_restart(mc_protect_t *s)
{
    s->retries = 0u;
}

/* the sensor checks proper (after the hard trips' conditions, which do not count periods) */
static uint32_t sensor_checks(mc_protect_t *s, const mc_protect_cfg_t *b, const hal_adc_sample_t *raw, mc_abc_t i)
{
    if (raw->overrun) {
        return MC_FAULT_OVERRUN;   /* the samples of this period are not the ones of its start */
    }
    /* an isolated star: the three measured currents sum to zero up to noise; a stuck channel,
     * an offset drifted after calibration or a lost channel does not */
    const float sum = i.a + i.b + i.c;
    if (persists(&s->i_sum_n, !(fabsf(sum) <= b->i_sum_tol), b->i_sum_n)) {
        return MC_FAULT_CURRENT_SENSOR;
    }
    return 0u;
}

uint32_t mc_protect_sensors(mc_protect_t *s, const mc_protect_cfg_t *c, const hal_adc_sample_t *raw, mc_abc_t i,
                            float vdc)
{
    /* any phase above the trip level, or a sample at an ADC rail: a clipped channel says only
     * that the current is beyond the span, which the configuration keeps above the trip level */
    bool rail = false;
    for (int k = 0; k < 3; ++k) {
        rail = rail || raw->i[k] == 0u || (int32_t)raw->i[k] >= c->adc_max;
    }
    const bool over = rail || fabsf(i.a) > c->i_trip || fabsf(i.b) > c->i_trip || fabsf(i.c) > c->i_trip;
    const uint32_t sensors = sensor_checks(s, c, raw, i);   /* counts every period */
    if (over) {
        return MC_FAULT_OVERCURRENT;
    }
    if (vdc > c->vdc_max) {
        return MC_FAULT_OVERVOLTAGE;
    }
    if (vdc < c->vdc_min) {
        return MC_FAULT_UNDERVOLTAGE;
    }
    return sensors;
}

/* The speed's swing for the loss-of-lock check: its deviation from a critically damped
 * alpha-beta track (double pole at 1 - k: the 20 Hz of the averages). A ramp is not a swing: a
 * first-order average lags a steady acceleration a by a ts / k (a 4500 rpm/s ramp on a 21-pole-
 * pair motor: 36 rpm, beyond its 24 rpm floor), the track none; a swing well above 20 Hz (the
 * L-error one: ~200 Hz) passes as before. */
static float swing_dev(mc_protect_t *s, float omega, float k, float ts)
{
    const float e = omega - (s->w_trk + s->a_trk * ts);
    s->w_trk += s->a_trk * ts + (2.0f * k - k * k) * e;
    s->a_trk += k * k * e / ts;
    return e;
}

uint32_t mc_protect_running(mc_protect_t *s, const mc_protect_cfg_t *b, const mc_protect_in_t *in, bool *doubt)
{
    *doubt = false;
    const float omega = in->omega, omega_raw = in->omega_raw;
    const mc_dq_t i_ref = in->i_ref, i_fb = in->i_fb, u_dq = in->u_dq;
    if (!(fabsf(omega) <= b->overspeed) && !(in->reacting && isfinite(omega))) {
        return MC_FAULT_OVERSPEED;   /* also a NaN or infinite speed; latched already in its reaction */
    }
    /* (a) the estimator's raw speed against the filtered one: a lock on the wrong solution shows
     * as a raw speed of the wrong sign or size while the PLL keeps its speed (thesis Fig. 6.9) */
    const float k = b->avg_k;
    const float w_raw = avg(&s->w_raw, omega_raw, k);
    const float lock_band = b->lock_tol * fabsf(omega) + b->lock_floor;
    /* ... or the filtered speed itself swinging about its 20 Hz track by more than the floor
     * (rms): an estimator whose speed error feeds back through the speed and current loops
     * (a model error, see docs/protection.md) oscillates like this for a while before it loses
     * the angle */
    const float dev = swing_dev(s, omega, k, b->ts);
    const float dev2 = avg(&s->w_dev2, dev * dev, k);
    const bool swing = b->lock_n > 0u && dev2 > b->lock_floor * b->lock_floor;
    const bool lock_doubt = swing || !(fabsf(w_raw - omega) <= lock_band);
    /* I/f's open loop: the frame a full electrical turn ahead of (or behind) the estimate. A
     * rotor in step stays within its load angle of the frame (less than half a turn), so this is
     * a pull-out (the load beyond I_f's torque, a ramp too fast for the inertia) or an estimator
     * that does not see the rotor: either way the frame is not the rotor (mc/if_start.h) */
    if (in->open_loop && !(fabsf(in->if_slip) < 2.0f * MC_PI)) {
        return MC_FAULT_PULL_OUT;
    }
    if (in->lock_paused || in->open_loop) {
        /* the re-check's bias moves the estimate, and I/f's frame leads instead: the checks wait */
    } else if (persists(&s->lock_n, lock_doubt, b->lock_n)) {
        return MC_FAULT_LOSS_OF_LOCK;
    } else if (s->lock_n > 0u && s->lock_n == b->lock_n / 4u) {
        *doubt = true;   /* in doubt: is the estimate reversed? (the caller re-checks the polarity) */
    }
    /* ... and its fast path: the raw angle far off the PLL's (the PLL's own error). An estimate
     * that runs away does so in a few milliseconds (an inductance error at standstill under load:
     * 25 -> 150 deg in 8 ms), faster than the averages above can say */
    const float innov = fabsf(mc_wrap_pi(in->theta_raw - in->theta));
    if (persists(&s->jump_n, b->jump_n > 0u && !in->open_loop && !(innov <= b->jump), b->jump_n)) {
        return MC_FAULT_LOSS_OF_LOCK;
    }
    /* (c) the current does not follow its reference (a wrong angle, a missing phase at
     * standstill): the error vector low-passed, so that the ringing of a large step (which
     * averages out) does not count, a lasting offset does */
    const float ed = avg(&s->err_d, i_ref.d - i_fb.d, k);
    const float eq = avg(&s->err_q, i_ref.q - i_fb.q, k);
    if (persists(&s->track_n, !(ed * ed + eq * eq <= b->track_err * b->track_err), b->track_n)) {
        return MC_FAULT_TRACKING;
    }
    /* (b) the voltage the current loop needs against the steady-state model (5.1) with the
     * angle source's speed, all low-passed first: the L di/dt term and any oscillation of the
     * speed estimate average out, while a frozen encoder, an estimate on the wrong solution or an
     * open phase leave a lasting part of the back-EMF unexplained. The threshold grows with speed
     * by half of w Lq i_max: the controller's model is small-signal, saturation lowers the flux */
    const float ud = avg(&s->u_d, u_dq.d, k), uq = avg(&s->u_q, u_dq.q, k);
    const float id = avg(&s->i_d, i_fb.d, k), iq = avg(&s->i_q, i_fb.q, k);
    const float w = avg(&s->w, omega, k);
    const mc_dq_t r = mc_protect_residual(b, (mc_dq_t){ud, uq}, (mc_dq_t){id, iq}, w);
    const float rd = r.d, rq = r.q;
    const float r_max = b->resid_v + b->resid_w_coef * fabsf(w);
    if (persists(&s->resid_n, !in->open_loop && !(rd * rd + rq * rq <= r_max * r_max), b->resid_n)) {
        return MC_FAULT_VOLTAGE_MODEL;
    }
    /* (d) speed mode: the speed loop asks for (nearly) all its torque and the rotor does not turn */
    const bool stall = in->speed_mode && fabsf(in->speed_ref) * (float)b->pole_pairs > b->stall_speed &&
                       fabsf(omega) < b->stall_speed && fabsf(in->torque_ref) >= b->stall_torque;
    if (persists(&s->stall_n, stall, b->stall_n)) {
        return MC_FAULT_STALL;
    }
    /* (d) speed mode: strong torque one way, the speed estimate accelerating the other way at
     * more than half of what that torque alone would give. A lock on the mirrored solution is
     * consistent in its own frame (it sees -w and a torque that "accelerates" it), so this
     * catches the partial errors (near 90 deg the torque vanishes and the load decelerates the
     * rotor), and an overload far beyond the torque limit */
    const float acc = avg(&s->accel, (omega - s->w_prev) / b->ts, k);
    s->w_prev = omega;
    const float t_ref = in->torque_ref;
    const bool implausible_acc = in->speed_mode && fabsf(t_ref) >= b->accel_torque &&
                                 (t_ref > 0.0f ? -acc : acc) > b->accel_per_nm * fabsf(t_ref);
    if (persists(&s->accel_n, implausible_acc, b->accel_n)) {
        return MC_FAULT_TORQUE;
    }
    return 0u;
}

bool mc_protect_may_recover(mc_protect_t *s, const mc_protect_cfg_t *c, uint32_t reason, bool running)
{
    if (!c->recover || (reason & ~MC_FAULTS_RECOVERABLE) != 0u || s->retries >= c->retries || !running) {
        return false;
    }
    s->retries++;
    return true;
}

bool mc_protect_may_hold(const mc_protect_cfg_t *c, uint32_t reason, bool running, float omega, float vdc)
{
    return c->hold_fw && reason != 0u && (reason & ~MC_FAULTS_HOLD_FW) == 0u && running && c->ug_coef * fabsf(omega) > vdc;
}

bool mc_protect_reaction_done(const mc_protect_cfg_t *c, float omega, float vdc)
{
    /* the link is safe once the line-to-line back-EMF is below it with a margin */
    return c->ug_coef * fabsf(omega) < 0.95f * vdc;
}

void mc_protect_tick(mc_protect_t *s, const mc_protect_cfg_t *c, bool running, uint32_t ticks)
{
    if (running && ticks >= c->retry_reset_n) {
        s->retries = 0u;   /* long enough in RUN: the recoveries count from zero again */
    }
}
