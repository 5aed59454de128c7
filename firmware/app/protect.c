/* Plausibility and loss-of-lock detectors, cheap enough for the ISR (a few compares and three
 * first-order low-passes). Each turns a condition that persists for its time (in periods, from
 * the parameter table; 0: off) into a fault with its reason; the drive's trip then turns the
 * outputs off in the same period. Detection time = persistence + the filters' settling. */
#include <math.h>
#include "drive_internal.h"
#include "mc/angle.h"

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

void mc_protect_reset(mc_drive_t *d, float omega)
{
    d->prot.i_sum_n = d->prot.track_n = d->prot.lock_n = d->prot.stall_n = d->prot.resid_n = 0u;
    d->prot.accel_n = d->prot.jump_n = 0u;
    d->prot.w_prev = omega;
    d->prot.accel = 0.0f;
    d->prot.err_d = d->prot.err_q = d->prot.w_dev2 = 0.0f;
    /* the averages start where a steady state at the estimate's speed (a caught rotor) would
     * have them: speeds at omega, the voltage at its back-EMF with no current */
    d->prot.w_raw = d->prot.w = omega;
    d->prot.u_d = d->prot.i_d = d->prot.i_q = 0.0f;
    d->prot.u_q = omega * d->cfg->p.psi_pm;
}

uint32_t mc_protect_sensors(mc_drive_t *d, const hal_adc_sample_t *raw, mc_abc_t i)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    if (raw->overrun) {
        return MC_FAULT_OVERRUN;   /* the samples of this period are not the ones of its start */
    }
    /* an isolated star: the three measured currents sum to zero up to noise; a stuck channel,
     * an offset drifted after calibration or a lost channel does not */
    const float sum = i.a + i.b + i.c;
    if (persists(&d->prot.i_sum_n, !(fabsf(sum) <= b->i_sum_tol), b->i_sum_n)) {
        return MC_FAULT_CURRENT_SENSOR;
    }
    return 0u;
}

uint32_t mc_protect_running(mc_drive_t *d, const mc_angle_out_t *ang, float omega_raw, mc_dq_t i_ref, mc_dq_t i_fb,
                            mc_dq_t u_dq)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    if (!(fabsf(ang->omega) <= b->overspeed) &&
        !(d->seq.state == MC_STATE_FAULT_REACTION && fabsf(ang->omega) < 3.0e38f)) {
        return MC_FAULT_OVERSPEED;   /* also a NaN speed; latched already in its reaction */
    }
    /* (a) the estimator's raw speed against the filtered one: a lock on the wrong solution shows
     * as a raw speed of the wrong sign or size while the PLL keeps its speed (thesis Fig. 6.9) */
    const float k = b->avg_k;
    const float w_raw = avg(&d->prot.w_raw, omega_raw, k);
    const float lock_band = b->lock_tol * fabsf(ang->omega) + b->lock_floor;
    /* ... or the filtered speed itself swinging about its 20 Hz average by more than the floor
     * (rms): an estimator whose speed error feeds back through the speed and current loops
     * (a model error, see docs/protection.md) oscillates like this for a while before it loses
     * the angle */
    const float dev = ang->omega - d->prot.w;
    const float dev2 = avg(&d->prot.w_dev2, dev * dev, k);
    const bool swing = b->lock_n > 0u && dev2 > b->lock_floor * b->lock_floor;
    const bool lock_doubt = swing || !(fabsf(w_raw - ang->omega) <= lock_band);
    if (mc_polcheck_active(d)) {
        /* the re-check's bias moves the estimate: the lock checks wait for its verdict */
    } else if (persists(&d->prot.lock_n, lock_doubt, b->lock_n)) {
        return MC_FAULT_LOSS_OF_LOCK;
    } else if (d->prot.lock_n > 0u && d->prot.lock_n == b->lock_n / 4u) {
        (void)mc_polcheck_start(d, ang->omega);   /* in doubt: is the estimate reversed? */
    }
    /* ... and its fast path: the raw angle far off the PLL's (the PLL's own error). An estimate
     * that runs away does so in a few milliseconds (an inductance error at standstill under load:
     * 25 -> 150 deg in 8 ms), faster than the averages above can say */
    const float innov = fabsf(mc_wrap_pi(d->tm.theta_raw - ang->theta));
    if (persists(&d->prot.jump_n, b->jump_n > 0u && !(innov <= b->jump), b->jump_n)) {
        return MC_FAULT_LOSS_OF_LOCK;
    }
    /* (c) the current does not follow its reference (a wrong angle, a missing phase at
     * standstill): the error vector low-passed, so that the ringing of a large step (which
     * averages out) does not count, a lasting offset does */
    const float ed = avg(&d->prot.err_d, i_ref.d - i_fb.d, k);
    const float eq = avg(&d->prot.err_q, i_ref.q - i_fb.q, k);
    if (persists(&d->prot.track_n, !(ed * ed + eq * eq <= b->track_err * b->track_err), b->track_n)) {
        return MC_FAULT_TRACKING;
    }
    /* (b) the voltage the current loop needs against the steady-state model (5.1) with the
     * angle source's speed, all low-passed first: the L di/dt term and any oscillation of the
     * speed estimate average out, while a frozen encoder, an estimate on the wrong solution or an
     * open phase leave a lasting part of the back-EMF unexplained. The threshold grows with speed
     * by half of w Lq i_max: the controller's model is small-signal, saturation lowers the flux */
    const float ud = avg(&d->prot.u_d, u_dq.d, k), uq = avg(&d->prot.u_q, u_dq.q, k);
    const float id = avg(&d->prot.i_d, i_fb.d, k), iq = avg(&d->prot.i_q, i_fb.q, k);
    const float w = avg(&d->prot.w, ang->omega, k);
    const mc_params_t *p = &d->cfg->p;
    const float rd = ud - p->rs * id + w * p->lq * iq;
    const float rq = uq - p->rs * iq - w * (p->ld * id + p->psi_pm);
    const float r_max = b->resid_v + b->resid_w_coef * fabsf(w);
    if (persists(&d->prot.resid_n, !(rd * rd + rq * rq <= r_max * r_max), b->resid_n)) {
        return MC_FAULT_VOLTAGE_MODEL;
    }
    /* (d) speed mode: the speed loop asks for (nearly) all its torque and the rotor does not turn */
    const bool stall = d->cmd.mode == MC_MODE_SPEED &&
                       fabsf(d->cmd.speed_ref) * (float)b->pole_pairs > b->stall_speed &&
                       fabsf(ang->omega) < b->stall_speed && fabsf(d->tm.torque_ref) >= b->stall_torque;
    if (persists(&d->prot.stall_n, stall, b->stall_n)) {
        return MC_FAULT_STALL;
    }
    /* (d) speed mode: strong torque one way, the speed estimate accelerating the other way at
     * more than half of what that torque alone would give. A lock on the mirrored solution is
     * consistent in its own frame (it sees -w and a torque that "accelerates" it), so this
     * catches the partial errors (near 90 deg the torque vanishes and the load decelerates the
     * rotor), and an overload far beyond the torque limit */
    const float acc = avg(&d->prot.accel, (ang->omega - d->prot.w_prev) / b->ts, k);
    d->prot.w_prev = ang->omega;
    const float t_ref = d->tm.torque_ref;
    const bool implausible_acc = d->cmd.mode == MC_MODE_SPEED && fabsf(t_ref) >= b->accel_torque &&
                                 (t_ref > 0.0f ? -acc : acc) > b->accel_per_nm * fabsf(t_ref);
    if (persists(&d->prot.accel_n, implausible_acc, b->accel_n)) {
        return MC_FAULT_TORQUE;
    }
    return 0u;
}
