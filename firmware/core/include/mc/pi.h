/* PI controller with output limits and anti-windup (conditional integration + clamp).
 * Discrete form: integ(k) = integ(k-1) + ki ts err(k); out = clamp(ff + kp err + integ).
 * While the output is at a limit and err pushes outward, the integrator charges only up to the
 * value that puts the output exactly on the limit; it is also clamped to [lo, hi]. */
#ifndef MC_PI_H
#define MC_PI_H
#include "mc/types.h"

typedef struct {
    float kp;        /* proportional gain                      */
    float ki;        /* integral gain [1/s]                    */
    float ts;        /* sample time [s]                        */
    float out_min;   /* default output limits                  */
    float out_max;
} mc_pi_cfg_t;

typedef struct {
    mc_pi_cfg_t cfg;
    float integ;     /* integrator state, in output units      */
    bool  saturated; /* last output was at (or clamped to) a limit */
} mc_pi_t;

void  mc_pi_init(mc_pi_t *s, const mc_pi_cfg_t *cfg);
void  mc_pi_reset(mc_pi_t *s, float integ);
/* out = clamp(ff + kp*err + integ, cfg limits) */
float mc_pi_step(mc_pi_t *s, float err, float ff);
/* same with limits given per call (e.g. the voltage left for this axis) */
float mc_pi_step_lim(mc_pi_t *s, float err, float ff, float lo, float hi);

#endif
