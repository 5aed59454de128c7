/* The one angle-wrap helper: every angle difference in the firmware goes through it. */
#ifndef MC_ANGLE_H
#define MC_ANGLE_H
#include "mc/types.h"

/* Wrap any finite angle [rad] to [-pi, pi). */
float mc_wrap_pi(float x);
/* Wrap any finite angle [rad] to [0, 2pi). */
float mc_wrap_2pi(float x);

#endif
