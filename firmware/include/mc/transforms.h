/* Clarke (2.4, amplitude invariant) and Park (2.5) transforms and their inverses. */
#ifndef MC_TRANSFORMS_H
#define MC_TRANSFORMS_H
#include "mc/types.h"

mc_ab_t  mc_clarke(mc_abc_t x);               /* (2.4), three measured phases             */
mc_ab_t  mc_clarke2(float a, float b);        /* (2.4) with c = -a - b (two sensors)      */
mc_abc_t mc_clarke_inv(mc_ab_t x);            /* inverse of (2.4), zero sequence = 0      */
mc_dq_t  mc_park(mc_ab_t x, mc_sincos_t sc);  /* (2.5)                                    */
mc_ab_t  mc_park_inv(mc_dq_t x, mc_sincos_t sc);

#endif
