/* Fast sin/cos: quadrant reduction + near-minimax polynomials on [-pi/4, pi/4].
 * One reduction serves both outputs, which is where the saving over sinf + cosf comes from. */
#include "mc/sincos.h"

#include <math.h>
#include <stdint.h>

#include "mc/angle.h"

/* pi/2 split so that k * hi is exact for |k| < 2^16 (8 significant bits in hi). */
#define HALF_PI_HI 1.5703125f
#define HALF_PI_LO 4.8382679489661923e-4f
#define TWO_OVER_PI 0.63661977236758134f
/* Largest |theta| reduced directly; larger inputs are wrapped first (k must fit the split). */
#define DIRECT_RANGE 50000.0f

/* Least-squares fits on Chebyshev nodes over [-pi/4, pi/4]: sin to degree 5 (truncation
 * 9.8e-7), cos to degree 6 (7e-8). One term fewer each than needed for float-level accuracy buys
 * a shorter dependency chain; the result stays well inside the 2e-6 budget of the ISR users. */
#define S3 -0.16662756079280835f
#define S5  0.008151589444884547f
#define C4  0.04166116709010426f
#define C6 -0.0013650475942955788f

mc_sincos_t mc_sincos(float theta)
{
    mc_sincos_t out;
    if (!(fabsf(theta) <= DIRECT_RANGE)) {
        theta = mc_wrap_pi(theta);
        if (theta != theta) {
            out.s = theta;   /* NaN in, NaN out (and no float->int conversion of a NaN) */
            out.c = theta;
            return out;
        }
    }
    /* nearest quadrant by a truncating conversion: floorf is a library call on targets
     * without a rounding instruction (Cortex-M4, baseline x86-64) and would dominate the cost */
    float y = theta * TWO_OVER_PI;
    int32_t k = (int32_t)(y + copysignf(0.5f, y));
    float kf = (float)k;
    float r = (theta - kf * HALF_PI_HI) - kf * HALF_PI_LO;
    float z = r * r;
    float sp = r + (r * z) * (S3 + z * S5);
    float cp = (1.0f - 0.5f * z) + (z * z) * (C4 + z * C6);

    /* theta = k pi/2 + r: rotate (sin r, cos r) by k quarter turns */
    switch ((uint32_t)k & 3u) {
    case 0u: out.s = sp;  out.c = cp;  break;
    case 1u: out.s = cp;  out.c = -sp; break;
    case 2u: out.s = -sp; out.c = -cp; break;
    default: out.s = -cp; out.c = sp;  break;
    }
    return out;
}
