/* Protection (docs/protection.md): the hard trips (over-current, a current sample at an ADC rail,
 * link over- and under-voltage), the sensor checks, the plausibility and loss-of-lock detectors
 * of the running drive, and the reactions that may replace a trip (recover by a new catch, hold
 * the field weakening). Each detector turns a condition that persists for its time (in periods;
 * 0: off) into a fault reason (the MC_FAULT_* bits of mc/sequencer.h); the caller trips. The
 * block owns its state and reads its configuration, built in the background from the protection.*
 * parameters (mc_drive_build). Units SI, rad/s electrical. */
#ifndef MC_PROTECT_H
#define MC_PROTECT_H
#include <stdbool.h>
#include <stdint.h>

#include "mc/types.h"
#include "hal/adc.h"

typedef struct {
    float ts;                    /* [s] */
    int pole_pairs;
    /* hard trips: every period the outputs are on */
    int32_t adc_max;             /* the ADC's upper rail [counts]                              */
    float i_trip, vdc_min, vdc_max;   /* [A, V, V]                                             */
    float i_sum_tol;             /* the three currents' sum [A], held i_sum_n periods           */
    /* running checks: limits in SI, persistence in periods (0: detector off) */
    float overspeed;             /* [rad/s el]                                                 */
    float track_err, lock_tol, lock_floor, stall_speed, stall_torque;
    float resid_v, resid_w_coef;  /* [V], [V s/rad]: threshold resid_v + resid_w_coef |w|     */
    uint32_t i_sum_n, track_n, lock_n, stall_n, resid_n;
    uint32_t accel_n;            /* torque plausibility persistence [periods] (0: off)          */
    uint32_t jump_n;             /* loss of lock, fast path: persistence [periods] (0: off)     */
    float jump;                  /* ... its threshold on |theta_raw - theta| [rad]               */
    float accel_torque;          /* |T_ref| from which it looks [N m]                           */
    float accel_per_nm;          /* 0.5 p / J: half the acceleration a torque gives [rad/s^2 el per N m] */
    float avg_k;                 /* the detectors' 20 Hz first-order low-pass coefficient        */
    float rs, ld, lq, psi_pm;    /* the motor entries for the residual of (5.1) [ohm, H, H, Wb]  */
    /* reactions */
    bool recover;                /* protection.lock_action = recover (sensorless only)          */
    bool hold_fw;                /* protection.overspeed_action = hold_fw                       */
    float ug_coef;               /* sqrt3 psi_pm: the line-to-line back-EMF per rad/s el [V s]  */
    uint32_t retries, retry_reset_n;
} mc_protect_cfg_t;

typedef struct {
    uint32_t i_sum_n, track_n, lock_n, stall_n, resid_n, accel_n, jump_n;   /* periods the condition held */
    float w_prev, accel;         /* last speed, its derivative low-passed [rad/s^2 el]          */
    float w_raw, err_d, err_q;   /* averages (cfg.avg_k): raw speed, current error              */
    float w_dev2;                /* mean square of the speed's swing about its track            */
    float w_trk, a_trk;          /* that track: speed, acceleration [rad/s, rad/s^2 el]         */
    float u_d, u_q, i_d, i_q, w; /* voltage, current, speed for the residual                    */
    uint32_t retries;            /* recoveries since the last retry_reset_n periods of clean RUN */
} mc_protect_t;

/* What the running checks look at in one period (RUN, Step III, the fault reaction). */
typedef struct {
    float theta, omega;          /* the angle source's estimate [rad, rad/s el]                 */
    float theta_raw, omega_raw;  /* ... before its filter                                       */
    mc_dq_t i_ref, i_fb, u_dq;   /* the current loop's reference, feedback, output [A, V]       */
    float torque_ref;            /* [N m]                                                       */
    bool speed_mode;             /* the speed loop runs ...                                     */
    float speed_ref;             /* ... towards this [rad/s mechanical]                         */
    bool reacting;               /* in the fault reaction: over-speed is latched already        */
    bool lock_paused;            /* the polarity re-check's bias moves the estimate: the averaged
                                    lock checks wait for its verdict                            */
    bool open_loop;              /* I/f (mc/if_start.h) runs: the frame is not the estimate, the
                                    lock checks (both) and the voltage model wait               */
    float if_slip;               /* ... and the frame has gained this on the estimate [rad]:
                                    a full turn is a pull-out (mc_if_out_t.slip)                */
} mc_protect_in_t;

/* The residual of the steady-state model (5.1) for voltage u, current i at speed w [V, A, rad/s el]:
 * u_d - (Rs i_d - w Lq i_q), u_q - (Rs i_q + w (Ld i_d + psi_pm)); ~0 for a machine that fits
 * the motor entries. The voltage-model check (mc_protect_running) applies it to its averages. */
static inline mc_dq_t mc_protect_residual(const mc_protect_cfg_t *c, mc_dq_t u, mc_dq_t i, float w)
{
    return (mc_dq_t){u.d - c->rs * i.d + w * c->lq * i.q, u.q - c->rs * i.q - w * (c->ld * i.d + c->psi_pm)};
}

/* The detectors' averages primed for a steady state at speed omega [rad/s el] (a caught rotor):
 * speeds at omega, the voltage at its back-EMF with no current. */
void mc_protect_reset(mc_protect_t *s, const mc_protect_cfg_t *c, float omega);
/* An enable: the recoveries count from zero. */
void mc_protect_restart(mc_protect_t *s);
/* The hard trips and the sensor checks, every period the outputs are on: the sample raw, its
 * phase currents i [A] and the link voltage vdc [V]. Returns the fault reason or 0. */
uint32_t mc_protect_sensors(mc_protect_t *s, const mc_protect_cfg_t *c, const hal_adc_sample_t *raw, mc_abc_t i,
                            float vdc);
/* The running checks after current control. Returns the fault reason or 0; *doubt: the loss-of-
 * lock checks are in doubt (a quarter of their persistence): time for a polarity re-check. */
uint32_t mc_protect_running(mc_protect_t *s, const mc_protect_cfg_t *c, const mc_protect_in_t *in, bool *doubt);
/* protection.lock_action = recover: a running-check fault while running with retries left may
 * restart the catch instead of a trip (true: counted). */
bool mc_protect_may_recover(mc_protect_t *s, const mc_protect_cfg_t *c, uint32_t reason, bool running);
/* protection.overspeed_action = hold_fw: over-speed while running above the uncontrolled-
 * generation speed (the line-to-line back-EMF at omega beyond vdc) holds the field weakening at
 * zero torque instead of turning the outputs off (below it, outputs off is current-free). */
bool mc_protect_may_hold(const mc_protect_cfg_t *c, uint32_t reason, bool running, float omega, float vdc);
/* The fault reaction may end: the back-EMF below the link with a margin. */
bool mc_protect_reaction_done(const mc_protect_cfg_t *c, float omega, float vdc);
/* Every period: ticks periods into RUN (running); long enough, the recoveries count from zero. */
void mc_protect_tick(mc_protect_t *s, const mc_protect_cfg_t *c, bool running, uint32_t ticks);

#endif
