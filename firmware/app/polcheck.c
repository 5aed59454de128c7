/* Low-speed polarity re-check while running (protection issue, detector (e)): the principle of
 * Step II (thesis 5.3) on the running drive. The HF injection (6.4) rides on the estimated d
 * axis; its current amplitude is V1 / (2 pi f l_dd). Towards the magnet (+i_d) the iron saturates
 * further and l_dd is smaller than against it (-i_d): with a bias of +I_b the HF current is
 * larger than with -I_b. On an estimate 180 deg off (the HF saliency cannot tell, (6.4) is
 * pi-periodic) the commanded +I_b is -I_b in the machine, and the comparison comes out reversed.
 *
 * Sequence (periods in injection cycles): +I_b on the d reference, settle 2 cycles, measure the
 * mean square of the HF part of i_d (the raw current minus the notch's output) over 4 cycles; the
 * same with -I_b; then compare. With the estimator's flux map the expected ratio is known,
 * r = (l_dd(-I_b) / l_dd(+I_b))^2; the verdict needs the measured ratio beyond r^(+-1/4) (else
 * inconclusive, nothing changes). Without a map (constant model) the sign decides with a 2 %
 * margin. Reversed: the estimate turns by pi and its speed changes sign (the mirrored solution
 * is (theta + pi, -omega)), the current loop restarts. The comparison holds only if the estimate
 * was settled meanwhile: the estimator's raw angle more than 10 deg off its PLL's, or its speed
 * more than 5 x Step III's tolerance off its value at the start (both averaged at the
 * detectors' 20 Hz), at any step (a start angle
 * still settling, an estimate running away) ends the check at once without a verdict. While it
 * runs, the averaged loss-of-lock checks wait (the bias moves the estimate a little); the fast
 * path does not. */
#include <math.h>
#include "drive_internal.h"
#include "mc/angle.h"

enum { POL_IDLE = 0, POL_PLUS_SETTLE, POL_PLUS, POL_MINUS_SETTLE, POL_MINUS };

void mc_polcheck_reset(mc_drive_t *d)
{
    d->pol.phase = POL_IDLE;
    d->pol.n = 0u;
    d->pol.acc[0] = d->pol.acc[1] = 0.0f;
    d->pol.cnt[0] = d->pol.cnt[1] = 0u;
    d->pol.moved = 0.0f;
}

bool mc_polcheck_active(const mc_drive_t *d)
{
    return d->pol.phase != POL_IDLE;
}

bool mc_polcheck_start(mc_drive_t *d, float omega)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    /* only where the injection is on and strong (below half of N1) */
    if (!b->pol_check || !b->inject || d->pol.phase != POL_IDLE || !(fabsf(omega) < 0.5f * b->inj.omega_n1) ||
        d->seq.state != MC_STATE_RUN) {
        return false;
    }
    mc_polcheck_reset(d);
    d->pol.phase = POL_PLUS_SETTLE;
    d->tm.polarity_checks++;
    return true;
}

void mc_polcheck_schedule(mc_drive_t *d, float omega)
{
    /* at_start: a settling time into RUN; an inconclusive verdict (the estimate still moving)
     * tries again a settling time later, three times at most */
    const mc_drive_blk_t *b = &d->cfg->blk;
    const uint32_t k = d->pol.starts;
    if ((b->pol_at_start || d->pol.unsure) && d->seq.state == MC_STATE_RUN && !b->three_step && k < 3u &&
        (k == 0u || d->tm.polarity_last == 0) && d->seq.ticks == (k + 1u) * b->pol_start_n &&
        mc_polcheck_start(d, omega)) {
        d->pol.starts = k + 1u;
    }
}

float mc_polcheck_bias(const mc_drive_t *d)
{
    const float ib = d->cfg->blk.pol_bias;
    return (d->pol.phase == POL_PLUS_SETTLE || d->pol.phase == POL_PLUS) ? ib
           : (d->pol.phase == POL_MINUS_SETTLE || d->pol.phase == POL_MINUS) ? -ib
                                                                              : 0.0f;
}

/* The verdict: +1 reversed, -1 right, 0 inconclusive. */
static int verdict(const mc_drive_t *d)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    const float plus = d->pol.acc[0] / (float)d->pol.cnt[0], minus = d->pol.acc[1] / (float)d->pol.cnt[1];
    if (!(plus > 0.0f) || !(minus > 0.0f)) {
        return 0;
    }
    const float lr = logf(plus / minus);   /* > 0 expected when right */
    const float margin = b->pol_log_ratio > 0.0f ? 0.25f * b->pol_log_ratio : 0.02f;
    return lr > margin ? -1 : (lr < -margin ? 1 : 0);
}

bool mc_polcheck_step(mc_drive_t *d, float i_d, float i_d_filtered, const mc_angle_out_t *ang)
{
    if (d->pol.phase == POL_IDLE) {
        return false;
    }
    const mc_drive_blk_t *b = &d->cfg->blk;
    const float hf = i_d - i_d_filtered;
    /* settled: the raw angle on the PLL's, and the speed estimate steady (a start angle that
     * still settles turns the estimate at tens of rad/s while the rotor stands) */
    /* both low-passed at the detectors' 20 Hz: the noise of a single sample does not count */
    const float innov = fabsf(mc_wrap_pi(d->tm.theta_raw - ang->theta));
    if (d->pol.n == 0u && d->pol.phase == POL_PLUS_SETTLE) {
        d->pol.w0 = d->prot.w;
        d->pol.innov = innov;
    }
    d->pol.innov += b->avg_k * (innov - d->pol.innov);
    const float dep = d->pol.innov;
    const float dw = fabsf(d->prot.w - d->pol.w0) * b->pol_w_scale;
    const float worst = dep > dw ? dep : dw;
    d->pol.moved = worst > d->pol.moved ? worst : d->pol.moved;
    if (!(d->pol.moved <= 0.1745f)) {
        /* unsettled: no verdict, and the lock checks it paused take over again at once */
        d->tm.polarity_last = 0;
        mc_polcheck_reset(d);
        return false;
    }
    d->pol.n++;
    switch (d->pol.phase) {
    case POL_PLUS_SETTLE:
    case POL_MINUS_SETTLE:
        if (d->pol.n >= b->pol_settle_n) {
            d->pol.phase++;
            d->pol.n = 0u;
        }
        return false;
    case POL_PLUS:
    case POL_MINUS: {
        const int k = d->pol.phase == POL_PLUS ? 0 : 1;
        d->pol.acc[k] += hf * hf;
        d->pol.cnt[k]++;
        if (d->pol.n < b->pol_measure_n) {
            return false;
        }
        if (k == 0) {
            d->pol.phase = POL_MINUS_SETTLE;
            d->pol.n = 0u;
            return false;
        }
        const int v = verdict(d);
        d->tm.polarity_last = v;
        mc_polcheck_reset(d);
        if (v > 0) {
            /* the mirrored solution: (theta + pi, -omega) is the machine's */
            d->src->reset(&d->src_state, mc_wrap_pi(ang->theta + MC_PI), -ang->omega);
            mc_cc_reset(&d->cc);
            d->tm.polarity_flips++;
            return true;
        }
        return false;
    }
    default:
        mc_polcheck_reset(d);
        return false;
    }
}
