/* Entry into field weakening at speed: the voltage law that takes the stator flux of a rotor
 * caught above the generation speed into the voltage limit with the least current (protection
 * issue, flying start). Not in the thesis.
 *
 * WHY. Enabled at speed, the stator flux is about the magnet's, psi_pm, and |omega| psi_pm is more
 * than the inverter can hold (sqrt3 |omega| psi_pm > Vdc): the flux must shrink to
 * rho = u_max / |omega| while the rotor turns on. A current loop asked for the field-weakening
 * current at its voltage limit does that late and overshoots (16.6 A on the thesis motor at
 * 1500 rpm, the limit 13.29 A); the least peak a search over voltage sequences finds is 12.9 A
 * (`mctools fly-current`, docs/protection.md), and its sequence is this law.
 *
 * PRINCIPLE (stator frame, Rs neglected). The stator flux psi_s moves with its voltage,
 * d psi_s / dt = u_s, at most u_max fast; the magnet's flux turns at |omega| on a circle of radius
 * psi_pm; the current is set by their difference. Write psi_s = r e^{j (omega t - phi)}: r the
 * flux's magnitude, phi its lag behind the rotor. A voltage split into a part along psi_s (radial,
 * -u_max sin(beta)) and a part ahead of it (tangential, u_max cos(beta)) gives
 *     dr/dt = -u_max sin(beta),   dphi/dt = |omega| - u_max cos(beta) / r                   (F.1)
 * While r > rho the lag only grows (u_max / r < |omega|); it costs current (a braking q current
 * and more d current), so the law brings r down to rho with the least lag: minimising
 * dphi/dr = (|omega| - u_max cos(beta) / r) / (u_max sin(beta)) over beta gives
 *     cos(beta) = u_max / (|omega| r)                                                       (F.2)
 * and the lag at r = rho is phi = sqrt(k^2 - 1) - acos(1 / k), k = psi_pm / rho (18 deg on the
 * thesis motor at 1500 rpm, 300 V). In the rotor frame the voltage then points
 *     angle(u) = angle(psi) + sign(omega) (pi / 2 + beta),   |u| = u_max                     (F.3)
 * from 140 deg (against the flux, ahead of it) at the start down to 90 deg + the lag at rho. The
 * search of `mctools fly-current` (the preset's saturation model, Rs, one vector per period) found
 * this sequence on its own: 140 deg falling to 75 deg over 1.4 ms, lag 17.8 deg, 12.9 A.
 *
 * With Rs the flux that counts is need / |omega|, need = |Rs i + j omega psi| (2.7), the voltage
 * that holds it: a braking, field-weakening current's Rs i points against j omega psi, and a flux
 * a few per cent beyond rho can be held (the search's end state: 3 % beyond).
 * Once held, the law keeps the voltage tangential (beta = 0) until the lag is gone (F.4): with
 * more voltage than |omega| r, dphi/dt = |omega| - u / r < 0 at a constant radius, and the
 * current falls as the lag does. That needs more than u_max: the law asks the modulator for the
 * hexagon's (direction-preserving overmodulation); at exactly u_max the lag would stay.
 * With overmodulation the voltage that moves the flux while it shrinks is also the hexagon's
 * reach U in the vector's direction (vdc/sqrt3 at a side's middle to 2 vdc/3 at a corner), not
 * the circle: (F.2) with U, cos(beta) = U / (|omega| r), the more tangential the more U, so the
 * lag grows less. rho stays u_max / |omega|: the flux the references hold (control.u_margin),
 * the drive caps it at the inscribed circle's (the hexagon's sides reach no further, so beyond
 * it the lag of (F.4) may never go) and ends the law after one electrical turn (mc_fwe_step).
 * Measured on the thesis motor: the vector's stator-frame direction stays nearly fixed while the
 * flux shrinks (its rotor-frame angle falls about as fast as the rotor turns), and the catch's
 * entry instant, a diode pulse's low, puts it near a side of the hexagon, so the gain is small
 * (+-1400 rpm 12.5-12.7 -> 12.4 A, +-1500 rpm 0.02 A). A corner instead (the tangent from
 * (need, 0) to the hexagon in the (tangential, radial) plane) alternated between the two corners
 * of that side, the same mean: no gain, not kept.
 *
 * USE. Once per period from a RUN entry at speed while the flux is not holdable: the flux at the
 * sample from the model psi(i), predicted 1.5 periods on (the middle of the period the result
 * acts in) with the voltage already latched (d psi / dt = u - Rs i - j omega psi, rotor frame),
 * and (F.2), (F.3) there; the result is the rotor-frame voltage for the next period. Done (false)
 * once the predicted flux can be held without lag: the current loop takes over from the current
 * that flows. The law has no current feedback of its own: a model error shows as a flux off by
 * the same share, and the current loop after it corrects what is left. Units SI, rotor frame,
 * rad/s electrical. */
#ifndef MC_FW_ENTRY_H
#define MC_FW_ENTRY_H
#include <stdbool.h>
#include <stdint.h>

#include "mc/types.h"

#define MC_FWE_LAG_END 0.05f        /* [rad] the lag left to the current loop */
#define MC_FWE_TAN_LAG_END 0.0500417f   /* tan(MC_FWE_LAG_END) */

/* The entry's configuration, built in the background (mc_drive_build). */
typedef struct {
    float ts;        /* [s] */
    float rs;        /* the estimator model's stator resistance [ohm] */
    float i_stop;    /* the law has no current feedback: at this |i| the current loop takes over [A] */
    bool overmod;    /* the loop may overmodulate (control.u_loop > 1): the voltage in a direction
                        is the hexagon's reach there, and held flux still lagging goes on (F.4) */
} mc_fwe_cfg_t;

/* One period's inputs (rotor frame, SI). */
typedef struct {
    mc_dq_t psi;      /* the flux at the sample from the model psi(i) [Wb] */
    mc_dq_t i;        /* the current at the sample, raw (an injection notch would delay it) [A] */
    mc_dq_t u_now;    /* the voltage acting until the next sample [V] */
    float omega;      /* [rad/s el] */
    float u_land;     /* the voltage the flux is to be held with, rho = u_land / |omega| [V] */
    float vdc;        /* [V]: the hexagon's size where cfg.overmod */
    mc_sincos_t sc;   /* the rotation from this rotor frame into the stator frame in the middle of
                         the period the result acts in (mc_svpwm_reach) */
} mc_fwe_in_t;

/* Its state: running since a RUN entry at speed (mc_fwe_begin), for n periods. */
typedef struct {
    bool active;
    uint32_t n;
} mc_fwe_t;

typedef enum {
    MC_FWE_OFF = 0,      /* not running (nothing to do for the caller)                        */
    MC_FWE_RUNNING,      /* *u is the voltage for the next period; the current loop waits        */
    MC_FWE_ENDED         /* ended this period after running: the loop starts again from its
                            references                                                          */
} mc_fwe_status_t;

void mc_fwe_reset(mc_fwe_t *s);   /* not running */
void mc_fwe_begin(mc_fwe_t *s);   /* a RUN entry that may find the rotor above the generation speed */
static inline bool mc_fwe_active(const mc_fwe_t *s)
{
    return s->active;
}
/* One period while active: the law below, ended where it is done, at cfg.i_stop (a model error
 * takes the flux too far) or after one electrical turn (every direction of the hexagon has
 * passed: what it has not done by then it will not do). */
mc_fwe_status_t mc_fwe_step(mc_fwe_t *s, const mc_fwe_cfg_t *c, const mc_fwe_in_t *in, mc_dq_t *u);

/* The law alone, one period. started: it ran in an earlier period. *u_out: the voltage for the
 * period after [V]. Returns false (and *u_out = in->u_now) where the flux, 1.5 periods on, can be
 * held: at once if not started or without overmodulation, else once it also lags by at most
 * MC_FWE_LAG_END; and for non-finite inputs. */
bool mc_fwe_law(const mc_fwe_cfg_t *c, const mc_fwe_in_t *in, bool started, mc_dq_t *u_out);

#endif
