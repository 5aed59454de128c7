/* Speed controller: PI from electrical speed error to torque command, with limits. */
#ifndef MC_SPEED_CTRL_H
#define MC_SPEED_CTRL_H
#include "mc/types.h"
#include "mc/pi.h"

typedef struct {
    float kp;         /* [N m s / rad] (mechanical rad/s)          */
    float ki;         /* [N m / rad]                              */
    float ts;         /* sample time of the speed loop [s]        */
    float torque_max; /* [N m], symmetric limit                   */
    int   decimation; /* run the speed loop every N current periods (>= 1) */
} mc_sc_cfg_t;

typedef struct {
    mc_sc_cfg_t cfg;
    mc_pi_t pi;
    int count;
    float torque_ref; /* held between updates [N m] */
} mc_sc_t;

void  mc_sc_init(mc_sc_t *s, const mc_sc_cfg_t *cfg);
void  mc_sc_reset(mc_sc_t *s, float torque0);
/* speeds in mechanical rad/s; call every current period; updates every `decimation` calls */
float mc_sc_step(mc_sc_t *s, float omega_ref_m, float omega_m);

#endif
