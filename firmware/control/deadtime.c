/* Dead-time compensation: during the dead time the freewheeling diode decides the phase
 * voltage, so a phase sourcing current (i > 0) loses t_dead/T_pwm of its duty and a sinking one
 * gains it. Adding it back with a sign that is linear within +-i_band avoids chattering from
 * current ripple and measurement noise around the zero crossing. */
#include "mc/deadtime.h"

void mc_dtc_init(mc_dtc_t *s, const mc_dtc_cfg_t *cfg)
{
    s->cfg = *cfg;
    /* the one division, here instead of every period */
    s->k = (cfg->t_pwm > 0.0f) ? cfg->t_dead / cfg->t_pwm : 0.0f;
}
