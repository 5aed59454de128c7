/* PI controller with output limits and anti-windup (conditional integration + clamp). */
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
    bool  saturated; /* last output was clamped                */
} mc_pi_t;

void  mc_pi_init(mc_pi_t *s, const mc_pi_cfg_t *cfg);
void  mc_pi_reset(mc_pi_t *s, float integ);
/* out = clamp(ff + kp*err + integ, cfg limits) */
float mc_pi_step(mc_pi_t *s, float err, float ff);
/* same with limits given per call (e.g. the voltage left for this axis) */
float mc_pi_step_lim(mc_pi_t *s, float err, float ff, float lo, float hi);

#endif
