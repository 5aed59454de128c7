/* Angle wrapping: the one helper every angle difference goes through (architecture.md). */
#include "mc/angle.h"

#include <math.h>
#include <stdint.h>

/* 2*pi split Cody-Waite style: the high part has only 8 significant bits, so k * hi is exact
 * for |k| < 2^16 and x - k*hi is exact too; the low part carries the rest of 2*pi. This keeps
 * the reduction error at the 1e-9 level for |x| up to ~4e5 rad instead of k * 1.7e-7. */
#define TWO_PI_HI  6.28125f
#define TWO_PI_LO  1.9353071795864769e-3f
#define INV_TWO_PI 0.15915494309189535f
/* Beyond this the float grid of x is coarser than the reduction error anyway; fmodf keeps the
 * multiple k small enough for the exact split above. */
#define BIG_ANGLE  100000.0f
/* Upper end of the one-turn path (3 pi). */
#define THREE_PI   9.42477796076937972f

float mc_wrap_pi_outside(float x)
{
    /* Called by mc_wrap_pi (angle.h) for everything not already inside. Up to one turn out
     * (an angle plus an increment, the sum of two wrapped angles): one Cody-Waite step instead
     * of the float->int->float round trip, which is a long dependency chain on any FPU. That
     * step is the general formula below with k = +-1. Checked over every float in [-20, 20]:
     * the same bits as the general path alone. (That is why the inside test stops one ulp
     * short of MC_PI: the general path sends +-3.1415925 to -MC_PI.) -MC_PI itself lies below
     * -pi (float pi rounds up) and still wraps to just under +pi. */
    float r;
    if (x >= MC_PI && x < THREE_PI) {
        r = (x - TWO_PI_HI) - TWO_PI_LO;
    } else if (x <= -MC_PI && x >= -THREE_PI) {
        r = (x + TWO_PI_HI) + TWO_PI_LO;
    } else {
        if (!(fabsf(x) <= BIG_ANGLE)) {
            if (x != x) {
                return x;   /* NaN: nothing sensible to wrap, and it must not reach the int cast */
            }
            x = fmodf(x, MC_2PI);
        }
        /* nearest turn count by a truncating conversion (floorf is a library call on the M4) */
        float y = x * INV_TWO_PI;
        float k = (float)(int32_t)(y + ((y >= 0.0f) ? 0.5f : -0.5f));
        r = (x - k * TWO_PI_HI) - k * TWO_PI_LO;
    }
    /* rounding at the seams may leave r one ulp outside; a single correction suffices */
    if (r >= MC_PI) {
        r -= MC_2PI;
    } else if (r < -MC_PI) {
        r += MC_2PI;
    }
    return r;
}

float mc_wrap_2pi(float x)
{
    float r = mc_wrap_pi(x);
    if (r < 0.0f) {
        r += MC_2PI;
        /* -tiny + 2pi rounds to 2pi, which is outside [0, 2pi) */
        if (r >= MC_2PI) {
            r = 0.0f;
        }
    }
    return r;
}
