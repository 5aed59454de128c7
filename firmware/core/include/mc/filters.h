/* First-order low-pass and biquad (low-pass, band-pass, notch), discretised by Tustin with
 * frequency pre-warping so the corner/centre frequency is exact. */
#ifndef MC_FILTERS_H
#define MC_FILTERS_H
#include "mc/types.h"

/* y(k) = b (x(k) + x(k-1)) + a y(k-1); y is the output, x1 the previous input. */
typedef struct { float a; float b; float x1; float y; } mc_lpf1_t;
/* fc is limited to 0.45/ts; y0 is taken as the steady state (input and output). */
void  mc_lpf1_init(mc_lpf1_t *s, float fc_hz, float ts, float y0);
void  mc_lpf1_reset(mc_lpf1_t *s, float y0);
/* Inline: two multiplies and an add, called every period by the PLLs. */
static inline float mc_lpf1_step(mc_lpf1_t *s, float x)
{
    s->y = s->b * (x + s->x1) + s->a * s->y;
    s->x1 = x;
    return s->y;
}

typedef struct {
    float b0, b1, b2, a1, a2;   /* y = b0 x + b1 x1 + b2 x2 - a1 y1 - a2 y2 */
    float x1, x2, y1, y2;
} mc_biquad_t;
void  mc_biquad_init_lowpass(mc_biquad_t *s, float fc_hz, float q, float ts);
void  mc_biquad_init_bandpass(mc_biquad_t *s, float fc_hz, float q, float ts); /* unity gain at fc */
void  mc_biquad_init_notch(mc_biquad_t *s, float fc_hz, float q, float ts);    /* zero gain at fc */
void  mc_biquad_reset(mc_biquad_t *s, float x0);   /* state as if x0 had been applied forever */
float mc_biquad_step(mc_biquad_t *s, float x);

#endif
