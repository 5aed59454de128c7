/* Clarke (2.4, amplitude invariant) and Park (2.5) transforms and their inverses.
 * Defined here as static inline: each is a handful of multiplies that the ISR chains one after
 * the other, so a call (argument marshalling of small structs, and on the host a store-to-load
 * round trip for each) would cost more than the arithmetic. Same operations, same results. */
#ifndef MC_TRANSFORMS_H
#define MC_TRANSFORMS_H
#include "mc/types.h"

/* (2.4), three measured phases: the 2/3 factor keeps the space-vector length equal to the
 * phase peak */
static inline mc_ab_t mc_clarke(mc_abc_t x)
{
    mc_ab_t y;
    y.alpha = (2.0f / 3.0f) * (x.a - 0.5f * (x.b + x.c));
    y.beta = MC_1_SQRT3 * (x.b - x.c);
    return y;
}

/* (2.4) with c = -a - b substituted, for two current sensors */
static inline mc_ab_t mc_clarke2(float a, float b)
{
    mc_ab_t y;
    y.alpha = a;
    y.beta = MC_1_SQRT3 * (a + 2.0f * b);
    return y;
}

/* inverse of (2.4), zero sequence = 0 */
static inline mc_abc_t mc_clarke_inv(mc_ab_t x)
{
    mc_abc_t y;
    float h = (0.5f * MC_SQRT3) * x.beta;
    y.a = x.alpha;
    y.b = -0.5f * x.alpha + h;
    y.c = -0.5f * x.alpha - h;
    return y;
}

/* (2.5) */
static inline mc_dq_t mc_park(mc_ab_t x, mc_sincos_t sc)
{
    mc_dq_t y;
    y.d = sc.c * x.alpha + sc.s * x.beta;
    y.q = -sc.s * x.alpha + sc.c * x.beta;
    return y;
}

/* transpose of the rotation in (2.5) */
static inline mc_ab_t mc_park_inv(mc_dq_t x, mc_sincos_t sc)
{
    mc_ab_t y;
    y.alpha = sc.c * x.d - sc.s * x.q;
    y.beta = sc.s * x.d + sc.c * x.q;
    return y;
}

#endif
