/* Dead-time compensation in the modulator: each phase duty gets +sgn(i) * t_dead/T_pwm, with a
 * smooth sign (linear within +-i_band) so it does not chatter through zero current. */
#ifndef MC_DEADTIME_H
#define MC_DEADTIME_H
#include "mc/types.h"
#include "mc/svpwm.h"

typedef struct {
    float t_dead;   /* [s]                                   */
    float t_pwm;    /* PWM period [s]                        */
    float i_band;   /* [A] half-width of the linear zone     */
    bool  enable;
} mc_dtc_cfg_t;

typedef struct {
    mc_dtc_cfg_t cfg;
    float k;        /* t_dead / t_pwm: the duty one dead time is worth (set by init) */
} mc_dtc_t;

void mc_dtc_init(mc_dtc_t *s, const mc_dtc_cfg_t *cfg);
/* Adjusts duties in place (clamped to [0, 1]) from the phase currents expected during the
 * period the duties will be applied in. */
void mc_dtc_apply(const mc_dtc_t *s, mc_duty_t *duty, mc_abc_t i_abc);

#endif
