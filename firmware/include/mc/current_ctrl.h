/* Current controller in a given (rotor or estimated) frame: PI per axis, decoupling
 * feed-forward (-w Lq iq, +w (Ld id + psi_pm)) from the measured currents, anti-windup against
 * the voltage limit. */
#ifndef MC_CURRENT_CTRL_H
#define MC_CURRENT_CTRL_H
#include "mc/types.h"
#include "mc/pi.h"

typedef struct {
    float kp_d, ki_d, kp_q, ki_q;   /* [V/A], [V/(A s)]                                     */
    float ts;                       /* [s]                                                  */
    float ld, lq, psi_pm;           /* for the decoupling feed-forward [H], [Wb]            */
    bool  decouple;                 /* add the decoupling feed-forward                      */
} mc_cc_cfg_t;

typedef struct {
    mc_cc_cfg_t cfg;
    mc_pi_t pi_d, pi_q;
    mc_dq_t u;                      /* last output [V]                                      */
    bool limited;                   /* last output hit the voltage limit                    */
} mc_cc_t;

/* Gains from a desired bandwidth (pole-zero cancellation): kp = 2 pi fbw L, ki = 2 pi fbw R. */
void mc_cc_cfg_from_bandwidth(mc_cc_cfg_t *cfg, float fbw_hz, float rs, float ld, float lq,
                              float psi_pm, float ts);
void mc_cc_init(mc_cc_t *s, const mc_cc_cfg_t *cfg);
void mc_cc_reset(mc_cc_t *s);
/* u_max: radius of the available voltage circle (e.g. vdc/sqrt(3) * margin). d axis has
 * priority; q gets what is left. Returns the limited voltage in the same frame. */
mc_dq_t mc_cc_step(mc_cc_t *s, mc_dq_t i_ref, mc_dq_t i_meas, float omega_e, float u_max);

#endif
