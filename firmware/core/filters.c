/* First-order low-pass and biquads by Tustin's rule with pre-warping at the corner/centre
 * frequency: s = w0 / K * (1 - z^-1) / (1 + z^-1), K = tan(w0 Ts / 2), so the discrete response
 * at fc equals the analog one at fc exactly (-3 dB corner, unity band-pass peak, notch zero). */
#include "mc/filters.h"

#include <math.h>

/* Pre-warp factor; fc is kept below Nyquist where tan() blows up. */
static float prewarp(float fc_hz, float ts)
{
    float f = fc_hz * ts;
    if (f > 0.45f) {
        f = 0.45f;
    } else if (f < 0.0f) {
        f = 0.0f;
    }
    return tanf(MC_PI * f);
}

void mc_lpf1_init(mc_lpf1_t *s, float fc_hz, float ts, float y0)
{
    /* H(s) = 1 / (1 + s/w0) -> H(z) = K (1 + z^-1) / ((1 + K) - (1 - K) z^-1) */
    float k = prewarp(fc_hz, ts);
    s->b = k / (1.0f + k);
    s->a = (1.0f - k) / (1.0f + k);
    mc_lpf1_reset(s, y0);
}

void mc_lpf1_reset(mc_lpf1_t *s, float y0)
{
    s->x1 = y0;
    s->y = y0;
}


/* Common denominator of the three second-order sections:
 * s^2 + s w0/Q + w0^2 -> (1 + K/Q + K^2) + 2 (K^2 - 1) z^-1 + (1 - K/Q + K^2) z^-2 */
static float biquad_den(mc_biquad_t *s, float fc_hz, float q, float ts, float *k_out)
{
    float k = prewarp(fc_hz, ts);
    if (!(q > 0.0f)) {
        q = 0.7071068f;
    }
    float kq = k / q;
    float k2 = k * k;
    float norm = 1.0f / (1.0f + kq + k2);
    s->a1 = 2.0f * (k2 - 1.0f) * norm;
    s->a2 = (1.0f - kq + k2) * norm;
    *k_out = k;
    return norm;
}

void mc_biquad_init_lowpass(mc_biquad_t *s, float fc_hz, float q, float ts)
{
    /* w0^2 / (s^2 + s w0/Q + w0^2) */
    float k;
    float norm = biquad_den(s, fc_hz, q, ts, &k);
    s->b0 = k * k * norm;
    s->b1 = 2.0f * s->b0;
    s->b2 = s->b0;
    mc_biquad_reset(s, 0.0f);
}

void mc_biquad_init_bandpass(mc_biquad_t *s, float fc_hz, float q, float ts)
{
    /* (s w0/Q) / (s^2 + s w0/Q + w0^2): unity gain and zero phase at w0 */
    float k;
    float norm = biquad_den(s, fc_hz, q, ts, &k);
    if (!(q > 0.0f)) {
        q = 0.7071068f;
    }
    s->b0 = k / q * norm;
    s->b1 = 0.0f;
    s->b2 = -s->b0;
    mc_biquad_reset(s, 0.0f);
}

void mc_biquad_init_notch(mc_biquad_t *s, float fc_hz, float q, float ts)
{
    /* (s^2 + w0^2) / (s^2 + s w0/Q + w0^2): zeros exactly on the unit circle at w0 */
    float k;
    float norm = biquad_den(s, fc_hz, q, ts, &k);
    s->b0 = (1.0f + k * k) * norm;
    s->b1 = 2.0f * (k * k - 1.0f) * norm;
    s->b2 = s->b0;
    mc_biquad_reset(s, 0.0f);
}

void mc_biquad_reset(mc_biquad_t *s, float x0)
{
    float den = 1.0f + s->a1 + s->a2;
    float g = (den != 0.0f) ? (s->b0 + s->b1 + s->b2) / den : 0.0f;   /* DC gain */
    s->x1 = x0;
    s->x2 = x0;
    s->y1 = g * x0;
    s->y2 = g * x0;
}

float mc_biquad_step(mc_biquad_t *s, float x)
{
    /* direct form I: no internal overflow-prone state, exact reset to a steady state */
    float y = s->b0 * x + s->b1 * s->x1 + s->b2 * s->x2 - s->a1 * s->y1 - s->a2 * s->y2;
    s->x2 = s->x1;
    s->x1 = x;
    s->y2 = s->y1;
    s->y1 = y;
    return y;
}
