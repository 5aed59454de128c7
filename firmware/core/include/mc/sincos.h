/* Fast sin/cos for the ISR: one Cody-Waite quadrant reduction + short polynomials.
 * Max abs error MC_SINCOS_MAX_ERR for |theta| <= MC_SINCOS_RANGE (dense sweep vs libm in the test;
 * measured 1.01e-6). Up to 1e4 rad the error stays below 2e-6; beyond 5e4 rad the input is first
 * wrapped with mc_wrap_pi, so outputs stay on the unit circle but carry the float grid error of
 * the huge input. NaN in gives NaN out. */
#ifndef MC_SINCOS_H
#define MC_SINCOS_H
#include "mc/types.h"

#define MC_SINCOS_MAX_ERR 1.2e-6f   /* enforced by tests/unit/core/test_sincos.c */
#define MC_SINCOS_RANGE   100.0f    /* [rad] range over which MC_SINCOS_MAX_ERR is tested */

mc_sincos_t mc_sincos(float theta);

#endif
