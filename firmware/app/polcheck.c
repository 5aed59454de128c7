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
#include "mc/polcheck.h"

#include <math.h>

#include "mc/angle.h"

enum { POL_IDLE = 0, POL_PLUS_SETTLE, POL_PLUS, POL_MINUS_SETTLE, POL_MINUS };

void mc_polcheck_reset(mc_polcheck_t *s)
{
    s->phase = POL_IDLE;
    s->n = 0u;
    s->acc[0] = s->acc[1] = 0.0f;
    s->cnt[0] = s->cnt[1] = 0u;
    s->moved = 0.0f;
}

void mc_polcheck_restart(mc_polcheck_t *s)
{
    s->checks = s->flips = 0u;
    s->starts = 0u;
    s->unsure = false;
    s->last = 0;
    mc_polcheck_reset(s);
}

bool mc_polcheck_active(const mc_polcheck_t *s)
{
    return s->phase != POL_IDLE;
}

bool mc_polcheck_start(mc_polcheck_t *s, const mc_polcheck_cfg_t *b, float omega, bool running)
{
    /* only where the injection is on and strong (below half of N1) */
    if (!b->enable || !b->inject || s->phase != POL_IDLE || !(fabsf(omega) < 0.5f * b->omega_n1) || !running) {
        return false;
    }
    mc_polcheck_reset(s);
    s->phase = POL_PLUS_SETTLE;
    s->checks++;
    return true;
}

void mc_polcheck_schedule(mc_polcheck_t *s, const mc_polcheck_cfg_t *b, float omega, bool running, uint32_t ticks)
{
    /* at_start: a settling time into RUN; an inconclusive verdict (the estimate still moving)
     * tries again a settling time later, three times at most */
    const uint32_t k = s->starts;
    if ((b->at_start || s->unsure) && running && !b->three_step && k < 3u && (k == 0u || s->last == 0) &&
        ticks == (k + 1u) * b->start_n && mc_polcheck_start(s, b, omega, running)) {
        s->starts = k + 1u;
    }
}

float mc_polcheck_bias(const mc_polcheck_t *s, const mc_polcheck_cfg_t *c)
{
    const float ib = c->bias;
    return (s->phase == POL_PLUS_SETTLE || s->phase == POL_PLUS) ? ib
           : (s->phase == POL_MINUS_SETTLE || s->phase == POL_MINUS) ? -ib
                                                                      : 0.0f;
}

/* The verdict: +1 reversed, -1 right, 0 inconclusive. */
static int verdict(const mc_polcheck_t *s, const mc_polcheck_cfg_t *b)
{
    const float plus = s->acc[0] / (float)s->cnt[0], minus = s->acc[1] / (float)s->cnt[1];
    if (!(plus > 0.0f) || !(minus > 0.0f)) {
        return 0;
    }
    const float lr = logf(plus / minus);   /* > 0 expected when right */
    const float margin = b->log_ratio > 0.0f ? 0.25f * b->log_ratio : 0.02f;
    return lr > margin ? -1 : (lr < -margin ? 1 : 0);
}

bool mc_polcheck_step(mc_polcheck_t *s, const mc_polcheck_cfg_t *b, const mc_polcheck_in_t *in)
{
    if (s->phase == POL_IDLE) {
        return false;
    }
    const float hf = in->i_d - in->i_d_filtered;
    /* settled: the raw angle on the PLL's, and the speed estimate steady (a start angle that
     * still settles turns the estimate at tens of rad/s while the rotor stands) */
    /* both low-passed at the detectors' 20 Hz: the noise of a single sample does not count */
    const float innov = fabsf(mc_wrap_pi(in->theta_raw - in->theta));
    if (s->n == 0u && s->phase == POL_PLUS_SETTLE) {
        s->w0 = in->w_avg;
        s->innov = innov;
    }
    s->innov += b->avg_k * (innov - s->innov);
    const float dep = s->innov;
    const float dw = fabsf(in->w_avg - s->w0) * b->w_scale;
    const float worst = dep > dw ? dep : dw;
    s->moved = worst > s->moved ? worst : s->moved;
    if (!(s->moved <= 0.1745f)) {
        /* unsettled: no verdict, and the lock checks it paused take over again at once */
        s->last = 0;
        mc_polcheck_reset(s);
        return false;
    }
    s->n++;
    switch (s->phase) {
    case POL_PLUS_SETTLE:
    case POL_MINUS_SETTLE:
        if (s->n >= b->settle_n) {
            s->phase++;
            s->n = 0u;
        }
        return false;
    case POL_PLUS:
    case POL_MINUS: {
        const int k = s->phase == POL_PLUS ? 0 : 1;
        s->acc[k] += hf * hf;
        s->cnt[k]++;
        if (s->n < b->measure_n) {
            return false;
        }
        if (k == 0) {
            s->phase = POL_MINUS_SETTLE;
            s->n = 0u;
            return false;
        }
        const int v = verdict(s, b);
        s->last = v;
        mc_polcheck_reset(s);
        if (v > 0) {
            s->flips++;   /* the caller turns the estimate: (theta + pi, -omega) is the machine's */
            return true;
        }
        return false;
    }
    default:
        mc_polcheck_reset(s);
        return false;
    }
}
