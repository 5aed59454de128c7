/* Torque command -> current references: MTPA (analytic (2.24) or table), current circle (2.21),
 * voltage ellipse (2.20) with field weakening (2.26) above base speed. */
#ifndef MC_TORQUE_REF_H
#define MC_TORQUE_REF_H
#include "mc/types.h"
#include "mc/mtpa.h"

typedef struct {
    int   pole_pairs;
    mc_lin_params_t mach;       /* Ld, Lq, psi_pm used for MTPA and the voltage ellipse     */
    float i_max;                /* current circle radius (peak) [A]                         */
    float u_margin;             /* fraction of vdc/sqrt(3) the references may plan for (0..1.049:
                                   above 1 with overmodulation, mc/svpwm.h (2.14a)) */
    bool  use_table;            /* MTPA from `table` instead of (2.24)                      */
    float ts;                   /* control period [s] for mc_tref_fw_feedback (0: feedback off) */
    mc_mtpa_table_t table;
} mc_tref_cfg_t;

typedef struct {
    mc_tref_cfg_t cfg;          /* set by mc_tref_init only: it also drops the cached MTPA point */
    bool fw_active;             /* field weakening moved id away from MTPA                  */
    bool i_limited;             /* torque not reachable within i_max (or the voltage limit)  */
    /* Last MTPA point (step 1): a function of |T| and cfg only, reused while |T| is unchanged
     * (in speed mode |T| changes at the speed-loop rate, not every period). */
    bool    mtpa_valid;
    float   mtpa_torque;        /* |T| it was solved for [N m]                              */
    mc_dq_t mtpa_i;             /* MTPA point, iq >= 0 [A]                                  */
    mc_dq_t mtpa_lim;           /* the same after the final circle limit (the result without
                                   field weakening, before the sign of T) [A]              */
    bool    mtpa_limited;       /* |T| beyond the current circle                            */
    float   fw_did;             /* voltage feedback's extra id [A] (<= 0)                   */
} mc_tref_t;

void    mc_tref_init(mc_tref_t *s, const mc_tref_cfg_t *cfg);
/* torque [N m], omega_e [rad/s electrical], vdc [V] -> current reference [A]. Bounded work (a few
 * root searches of at most 32 steps each, the MTPA one skipped while |T| repeats); continuous in
 * omega_e and torque. */
mc_dq_t mc_tref_step(mc_tref_t *s, float torque, float omega_e, float vdc);
/* Field weakening by voltage feedback on top of (2.26): while the current loop is at its voltage
 * limit (u_limited, its last period) above half the base speed, id goes further negative (the
 * full current in 10 ms), else back (in 40 ms); the reference r then gets that extra id, flux
 * before torque within the current circle. The model's ellipse plans the steady state; a model
 * error, a braking current caught at speed or uncontrolled generation at an enable can leave
 * the loop at the limit with the q current out of control, which the extra flux weakening
 * restores. Once per period after mc_tref_step. */
mc_dq_t mc_tref_fw_feedback(mc_tref_t *s, mc_dq_t r, bool u_limited, float omega_e, float vdc);

#endif
