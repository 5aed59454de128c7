/* Private interface between the drive's files (drive.c: API and ISR pipeline; drive_config.c: the
 * configuration, background side; drive_blocks.c: applying it to the blocks, the one path duties
 * take to the PWM; startup.c: sequencing, the initial-position steps, the reactions). Calls go
 * drive.c -> startup.c -> drive_blocks.c, never back. The blocks with their own state and
 * configuration (mc/protect.h, mc/polcheck.h, mc/offset_cal.h, mc/fw_entry.h, mc/catch.h) do not
 * see the drive. Not part of the public API. */
#ifndef MC_DRIVE_INTERNAL_H
#define MC_DRIVE_INTERNAL_H
#include "mc/drive.h"

/* The voltage the field-weakening entry lands the flux on (mc/fw_entry.h): the references' share
 * (control.u_margin), but not beyond the inscribed circle, Vdc/sqrt3 (drive.c step 7). */
static inline float mc_drive_u_land(const mc_drive_t *d, float vdc)
{
    const float m = d->cfg->tref.u_margin;
    return vdc * MC_1_SQRT3 * (m < 1.0f ? m : 1.0f);
}

/* The phase currents of a raw sample with the calibrated offsets [A] (ISR step 2, and the
 * offset calibration once it has its offsets). */
static inline mc_abc_t mc_drive_currents(const mc_drive_t *d, const hal_adc_sample_t *raw)
{
    return mc_offsets_currents(&d->offs, &d->cfg->blk.offs, raw->i);
}

/* The one path duties take to the PWM (drive_blocks.c). mc_drive_duties alone: the outputs'
 * rest at 50 % (zero voltage), no history. mc_drive_duties_kept: duties that act, with the
 * stator voltage they realise (u_real) and the one acting until they do (u_acting) kept for
 * the estimators (u_hist) and the duties in the telemetry. */
void mc_drive_duties(mc_drive_t *d, mc_abc_t duty);
void mc_drive_duties_kept(mc_drive_t *d, mc_abc_t duty, mc_ab_t u_real, mc_ab_t u_acting);
/* Every block configured from a built configuration (copies only). */
void mc_drive_apply(mc_drive_t *d, const mc_drive_built_t *b);
/* A new configuration while running: gains and limits, no state reset. */
void mc_drive_retune(mc_drive_t *d, const mc_drive_built_t *b);
/* The blocks' running state back to their start, from the configurations they hold. */
void mc_drive_init_blocks(mc_drive_t *d);
/* Rising enable edge: every block and history reset, offsets to be measured again. */
void mc_drive_startup_reset(mc_drive_t *d);
/* Protection and the startup states for this period. Returns true when the control pipeline
 * runs this period (RUN, Step III); otherwise it has already written the PWM. */
bool mc_drive_startup(mc_drive_t *d, const hal_adc_sample_t *raw, mc_abc_t i_abc, mc_ab_t i_ab, float vdc);
/* A running-check fault while sensorless (loss of lock, voltage model, tracking) with
 * protection.lock_action = recover and retries left: outputs off, RUN -> the catch again.
 * false: not recoverable, the caller trips. */
bool mc_drive_recover(mc_drive_t *d, uint32_t reason, float vdc);
/* Over-speed above the uncontrolled-generation speed with protection.overspeed_action =
 * hold_fw: the reason latched, FAULT_REACTION (zero torque, field weakening kept up) instead of
 * outputs off. false: no reaction applies, the caller trips. */
bool mc_drive_react(mc_drive_t *d, uint32_t reason, float omega, float vdc);
/* Outputs off, duties at 50 %, the reason latched (FAULT until disable + enable). */
void mc_drive_trip(mc_drive_t *d, uint32_t reason);
/* I/f (drive_if.c, mc/if_start.h): its flags back to the start (every enable edge), and ISR
 * step 4a: true while the open loop runs (ang then holds the frame's angle and speed, *i_ref
 * its current reference); on the hand-over the speed loop is preset and the references start
 * from the current that flows. */
void mc_drive_if_reset(mc_drive_t *d);
bool mc_drive_if_step(mc_drive_t *d, mc_angle_out_t *ang, mc_ab_t i_ab, mc_dq_t *i_ref);
/* Step III convergence test, after the pipeline ran; hands over to RUN. */
void mc_drive_step3_check(mc_drive_t *d, float omega_hat);

#endif
