/* The one angle-wrap helper: every angle difference in the firmware goes through it. */
#ifndef MC_ANGLE_H
#define MC_ANGLE_H
#include "mc/types.h"

/* Largest float below MC_PI: inputs strictly inside +-MC_WRAP_PI_INNER are already wrapped. */
#define MC_WRAP_PI_INNER 3.14159250f

/* mc_wrap_pi for inputs outside (-MC_WRAP_PI_INNER, MC_WRAP_PI_INNER): one Cody-Waite step
 * within a turn, the general reduction beyond. */
float mc_wrap_pi_outside(float x);

/* Wrap any finite angle [rad] to [-pi, pi). Inline because nearly every call in the ISR (PLL
 * error and update, encoder angle, angle plus an increment) hands in an angle that is already
 * inside: two compares then, instead of a call. */
static inline float mc_wrap_pi(float x)
{
    if (x > -MC_WRAP_PI_INNER && x < MC_WRAP_PI_INNER) {
        return x;
    }
    return mc_wrap_pi_outside(x);
}
/* Wrap any finite angle [rad] to [0, 2pi). */
float mc_wrap_2pi(float x);

#endif
