/* The drive: wires the blocks into the control ISR (mc_drive_isr) and the background loop
 * (mc_drive_background). Its configuration is the parameter table (mc/params.h) plus the model
 * the estimator gets; everything the ISR uses is derived from it outside the ISR. */
#ifndef MC_DRIVE_H
#define MC_DRIVE_H
#include "mc/types.h"
#include "mc/angle_source.h"
#include "mc/current_ctrl.h"
#include "mc/deadtime.h"
#include "mc/filters.h"
#include "mc/fw_entry.h"
#include "mc/handover.h"
#include "mc/if_start.h"
#include "mc/injection.h"
#include "mc/initpos.h"
#include "mc/phase_program.h"
#include "mc/params.h"
#include "mc/offset_cal.h"
#include "mc/polarity.h"
#include "mc/polcheck.h"
#include "mc/protect.h"
#include "mc/pulse3.h"
#include "mc/sequencer.h"
#include "mc/speed_ctrl.h"
#include "mc/svpwm.h"
#include "mc/torque_ref.h"
#include "hal/adc.h"
#include "hal/pwm.h"
#include "hal/qep.h"

typedef enum {
    MC_MODE_CURRENT = 0,    /* i_d, i_q references directly                           */
    MC_MODE_TORQUE,         /* torque -> MTPA / field weakening -> currents            */
    MC_MODE_SPEED,          /* speed PI -> torque -> currents                          */
    MC_MODE_COUNT
} mc_mode_t;

/* The machine model the estimator and the initial-position steps get (exact, identified or
 * deliberately scaled): not a tuning parameter but data, like the flux map it may point to.
 * A NaN field takes the motor.* parameter. */
typedef struct {
    float rs, ld, lq, psi_pm;         /* [ohm, H, H, Wb]                                   */
    const mc_flux_map_t *map;         /* psi_dq(i_dq) table; needed by estimator.model =
                                         fluxmap and by the three-step start (its l_dd profile
                                         and nonlinear costs). Must outlive the drive.      */
} mc_est_model_t;

typedef struct {
    mc_params_t p;
    mc_est_model_t est;
} mc_drive_cfg_t;

/* Commands: written by the background side (the simulator, CANopen), taken by the ISR at the start
 * of a period as one consistent copy (see mc_drive_command). */
typedef struct {
    bool      enable;
    mc_mode_t mode;
    mc_dq_t   i_ref;             /* MC_MODE_CURRENT [A]              */
    float     torque_ref;        /* MC_MODE_TORQUE [N m]             */
    float     speed_ref;         /* MC_MODE_SPEED  [rad/s mechanical] */
    float     theta_init;        /* startup.init_pos = given: rotor angle taken as known at
                                    enable [rad electrical]          */
} mc_drive_cmd_t;

/* Why a command was refused (counted; the previous command stays in force). */
typedef enum { MC_CMD_OK = 0, MC_CMD_NOT_FINITE, MC_CMD_BAD_MODE } mc_cmd_reject_t;

/* Telemetry of the last period (read from outside the ISR). */
typedef struct {
    mc_state_t state;
    mc_init_step_t init_step;
    uint32_t faults;
    uint32_t period;             /* ISR counter                      */
    mc_abc_t i_abc;              /* [A]                              */
    float    vdc;                /* [V]                              */
    float    theta;              /* angle the controller used [rad]  */
    float    omega;              /* electrical speed estimate [rad/s] */
    mc_dq_t  i_dq, i_ref;        /* [A] in the controller's frame     */
    mc_dq_t  u_dq;               /* commanded [V]                    */
    mc_ab_t  u_ab;               /* realised by the modulator [V]    */
    float    torque_ref;         /* [N m]                            */
    float    theta_raw, omega_raw;   /* angle source before its filter */
    int      est_iters;          /* solver iterations this period     */
    float    est_cost, est_cond; /* final cost, Hessian conditioning  */
    float    u_inj;              /* injected d voltage [V]            */
    float    theta1, theta2;     /* Step I (mod pi) and Step II results [rad] */
    float    c1, c2;             /* (5.7) costs, or DVI peak currents        */
    bool     pol_flip;           /* Step II added pi                         */
    uint8_t  pol_verdict;        /* Step II: mc_pol_verdict_t (mc/polarity.h) */
    uint8_t  if_mode;            /* I/f (mc/if_start.h): mc_if_mode_t, 0 the estimator's angle,
                                    1 open loop, 2 reducing toward the hand-over                 */
    float    pol_z;              /* Step II confidence |b| / se(b)           */
    float    duty[3];
    bool     u_limited, fw_active;
    bool     if_on;              /* configured to run I/f below the hand-over speed          */
    uint32_t cmd_rejected;       /* commands refused at the hand-over        */
    uint32_t recoveries;         /* recoveries since the enable (protection.lock_action)      */
    uint32_t recovered_from;     /* the reasons that started them (fault bits, or-ed)         */
    uint32_t polarity_checks, polarity_flips;   /* running polarity re-checks, and reversals */
    int      polarity_last;      /* last verdict: +1 reversed, -1 right, 0 inconclusive       */
    mc_cmd_reject_t cmd_reject_last;
} mc_drive_telem_t;

typedef struct {
    hal_adc_t *adc;
    hal_pwm_t *pwm;
    hal_qep_t *qep;
} mc_drive_hal_t;

/* What the ISR uses, in SI, derived from the parameters outside the ISR (drive_config.c). */
typedef struct {
    float ts;
    int   pole_pairs;
    float volts_per_count;       /* [V / count]                                              */
    float i_ref_max, i_slew;     /* [A], [A/s]                                               */
    float u_loop;                /* the current loop's voltage circle / (vdc/sqrt3): control.u_loop */
    float step3_speed_tol;       /* [rad/s el]                                               */
    uint32_t step3_hold;         /* [periods]                                                */
    bool  inject, three_step, ip1_pulse3, ip2_dvi;
    bool  src_measures;         /* an angle sensor: tracked while the offsets are calibrated */
    bool  cc_map;               /* the current loop's decoupling from the flux map (src.model) */
    mc_biquad_t notch;           /* at the injection frequency, state at rest                 */
    mc_lpf1_t step3_lpf;         /* Step III's |omega_hat| low-pass (50 Hz), state at rest     */
    mc_seq_cfg_t seq;
    mc_angle_src_built_t src;    /* the selected source: its model and own configuration */
    mc_inj_cfg_t inj;
    mc_initpos_cfg_t step1;      /* Step I: the pulse injection (5.5)/(7.1)                       */
    mc_pulse3_cfg_t pulse3;
    mc_polarity_cfg_t step2;     /* Step II: the polarity detection (5.6)-(5.7)                   */
    mc_dvi_cfg_t dvi;
    mc_catch_cfg_t flying;       /* the flying-start catch (mc/catch.h)                           */
    mc_fwe_cfg_t fw_entry;       /* the field-weakening entry (mc/fw_entry.h)                    */
    mc_protect_cfg_t prot;       /* protection: hard trips, detectors, reactions (mc/protect.h)  */
    mc_polcheck_cfg_t pol;       /* the running polarity re-check (mc/polcheck.h)                */
    mc_if_cfg_t ifs;             /* I/f below the hand-over speed (mc/if_start.h), where if_on   */
    bool  if_on;                 /* no usable saliency (or startup.init_pos = if_start): I/f     */
    bool  if_from_zero;          /* startup.init_pos = if_start: no angle known, the frame at 0  */
    mc_offsets_cfg_t offs;       /* the current offsets' calibration and scaling (mc/offset_cal.h) */
} mc_drive_blk_t;

/* A complete derived configuration: the parameters, the ISR's values and every block's
 * configuration. Built in the background (mc_drive_build), applied at a period boundary. */
typedef struct {
    mc_params_t p;
    mc_drive_blk_t blk;
    mc_cc_cfg_t cc;
    mc_sc_cfg_t sc;
    mc_tref_cfg_t tref;
    mc_dtc_cfg_t dtc;
} mc_drive_built_t;

/* The hand-over between the background loop and the ISR (mc/handover.h): commands (double
 * buffer, validated when the ISR takes them), the telemetry (one writer, consistent snapshots)
 * and configuration changes (built in the background, swapped in at a period boundary). Owned by
 * the caller beside the drive: it is the mailbox both sides share, not the ISR's state. */
MC_CMDBUF_TYPED(mc_drive_cmdbuf, mc_drive_cmd_t)
MC_SNAPSHOT_TYPED(mc_drive_telbuf, mc_drive_telem_t)
MC_CFGSWAP_TYPED(mc_drive_cfgbuf, mc_drive_built_t)

typedef struct {
    mc_drive_cmdbuf_t cmd;
    mc_drive_telbuf_t telem;
    mc_drive_cfgbuf_t cfg;
} mc_drive_link_t;

typedef struct {
    /* The configuration in force: the link's active slot (the ISR takes a new one at a period
     * boundary; the background never writes the active slot), so no copy is kept here. */
    const mc_drive_built_t *cfg;
    mc_est_model_t est;          /* the estimator's model as given            */
    mc_param_err_t cfg_err;      /* why mc_drive_init refused the configuration */
    mc_drive_hal_t hal;
    mc_drive_link_t *link;       /* the caller's mailbox (commands, telemetry, configuration) */
    mc_drive_cmd_t cmd;          /* the ISR's copy of the command in force   */

    mc_seq_t seq;                /* state, init step, faults          */
    mc_offsets_t offs;           /* the current offsets and their calibration (mc/offset_cal.h) */
    mc_catch_entry_t entry;      /* a RUN entry at speed: the corner latched, the gates' enable
                                    next period (mc/catch.h) */
    bool if_open;                /* I/f's open loop runs this period (mc/if_start.h)           */
    mc_fwe_t fw_entry;           /* a RUN entry at speed: the flux into the voltage limit first
                                    (mc/fw_entry.h) */

    const mc_angle_src_desc_t *src;
    mc_angle_src_state_t src_state;
    mc_inj_t inj;
    mc_biquad_t notch_d, notch_q;
    union {
        mc_phase_t phase;        /* the running phase program (Step I, II, the catch) and its workspace */
        mc_if_t ifs;             /* RUN only, where no phase program runs: I/f (mc/if_start.h), set
                                    up again at every RUN entry (drive_if.c)                    */
    };
    mc_lpf1_t step3_speed;       /* |omega_hat| low-passed for the convergence test */
    mc_protect_t prot;           /* protection's detectors and recoveries (mc/protect.h)      */
    uint32_t step3_count;
    mc_polcheck_t pol;           /* the running polarity re-check (mc/polcheck.h)             */
    mc_cc_t cc;
    mc_sc_t sc;
    mc_tref_t tref;
    mc_dtc_t dtc;

    mc_dq_t i_ref_prev;          /* slew-limited reference of the last period */
    mc_ab_t i_ab_prev;
    mc_ab_t u_hist[2];           /* [0]: commanded last ISR (acts during k..k+1), [1]: the one before */
    mc_drive_telem_t tm;
} mc_drive_t;

/* Defaults (the sun2016-ipm-5kw motor on the 300 V / 10 kHz bench as the motor and hardware
 * entries; every rule parameter "auto"); the estimator model follows the motor, no map. */
void mc_drive_cfg_default(mc_drive_cfg_t *cfg);
/* Derive the "auto" parameters, validate everything (table ranges, cross-checks, the estimator
 * model and its map) and build the block configurations. false: err says why, out unusable. */
bool mc_drive_build(const mc_drive_cfg_t *cfg, mc_drive_built_t *out, mc_param_err_t *err);
/* Before the ISR runs. Returns false (and latches MC_FAULT_CONFIG; mc_drive_config_error says
 * why) when the configuration is refused; the outputs stay off. */
bool mc_drive_init(mc_drive_t *d, mc_drive_link_t *link, const mc_drive_cfg_t *cfg, hal_adc_t *adc, hal_pwm_t *pwm,
                   hal_qep_t *qep);
const mc_param_err_t *mc_drive_config_error(const mc_drive_t *d);
/* Background: publish a command; the ISR takes the newest at the start of its next period, as one
 * copy, if every number in it is finite and the mode known (else it keeps the previous one and
 * counts the refusal in the telemetry). */
void mc_drive_command(mc_drive_t *d, const mc_drive_cmd_t *cmd);
/* Background: change one parameter. Checked against its access (INIT: refused; STANDSTILL: only
 * while the outputs are off), then the whole configuration is derived and validated again in the
 * background and handed to the ISR, which swaps it in at the next period boundary (running:
 * gains and limits change without resetting the controllers' state). false with err: nothing
 * changed (MC_PERR_BUSY: the previous change is not taken yet, retry a period later). */
bool mc_drive_param_write(mc_drive_t *d, int id, float value, mc_param_err_t *err);
/* Background: a whole parameter set at once (the CANopen reset node's stored or default set),
 * only while the outputs are off; every INIT parameter must equal the one in force (else
 * MC_PERR_ACCESS naming it). Derived, validated and handed over like mc_drive_param_write. */
bool mc_drive_params_write(mc_drive_t *d, const mc_params_t *p, mc_param_err_t *err);
/* Background: a consistent copy of the last period's telemetry (false if the ISR overwrote it on
 * every one of a few tries: practically never). */
bool mc_drive_telemetry_read(const mc_drive_t *d, mc_drive_telem_t *out);
void mc_drive_isr(mc_drive_t *d);          /* the control period, top to bottom               */
void mc_drive_background(mc_drive_t *d);   /* slow work, outside the ISR                      */
mc_state_t mc_drive_state(const mc_drive_t *d);
uint32_t mc_drive_faults(const mc_drive_t *d);
/* The ISR's own telemetry record: for single-threaded hosts and tests only (on a target, the
 * background uses mc_drive_telemetry_read). */
const mc_drive_telem_t *mc_drive_telemetry(const mc_drive_t *d);
/* The parameters in force (resolved: no "auto" left). */
const mc_params_t *mc_drive_params(const mc_drive_t *d);

#endif
