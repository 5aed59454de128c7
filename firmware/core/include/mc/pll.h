/* Angle-tracking PLL: PI + integrator (3.9) with speed feed-forward and a speed output filter
 * (thesis Fig. 6.9, section 6.5). */
#ifndef MC_PLL_H
#define MC_PLL_H
#include "mc/types.h"
#include "mc/filters.h"

typedef struct {
    float kp;          /* [1/s]    */
    float ki;          /* [1/s^2]  */
    float ts;          /* [s]      */
    float speed_fc_hz; /* corner of the output speed low-pass */
} mc_pll_cfg_t;

typedef struct {
    mc_pll_cfg_t cfg;
    float theta;       /* tracked angle, [-pi, pi)        */
    float integ;       /* PI integrator [rad/s]           */
    float omega;       /* unfiltered speed [rad/s]        */
    mc_lpf1_t speed_lpf;
    float omega_filt;  /* filtered speed output [rad/s]   */
} mc_pll_t;

void mc_pll_init(mc_pll_t *s, const mc_pll_cfg_t *cfg);
/* omega goes into both the speed and the integrator: right when no feed-forward is used; with
 * feed-forward, set s->integ = omega - omega_ff after the reset. */
void mc_pll_reset(mc_pll_t *s, float theta, float omega);
/* theta_in: raw angle measurement; omega_ff: speed feed-forward (0 if none). */
void mc_pll_step(mc_pll_t *s, float theta_in, float omega_ff);

#endif
