/* Fast sin/cos for the ISR. Max abs error over all finite inputs: MC_SINCOS_MAX_ERR (tested). */
#ifndef MC_SINCOS_H
#define MC_SINCOS_H
#include "mc/types.h"

#define MC_SINCOS_MAX_ERR 2.0e-6f   /* tightened/relaxed by the implementation; the test enforces it */

mc_sincos_t mc_sincos(float theta);

#endif
