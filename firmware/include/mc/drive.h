/* The drive: wires the blocks into the control ISR (mc_drive_isr) and the background loop
 * (mc_drive_background). One configuration struct carries motor and drive parameters. */
#ifndef MC_DRIVE_H
#define MC_DRIVE_H
#include "mc/types.h"
#include "mc/angle_source.h"
#include "mc/current_ctrl.h"
#include "mc/deadtime.h"
#include "mc/encoder.h"
#include "mc/filters.h"
#include "mc/injection.h"
#include "mc/pll.h"
#include "mc/initpos.h"
#include "mc/polarity.h"
#include "mc/pulse3.h"
#include "mc/sequencer.h"
#include "mc/unop.h"
#include "mc/speed_ctrl.h"
#include "mc/svpwm.h"
#include "mc/torque_ref.h"
#include "hal/adc.h"
#include "hal/pwm.h"
#include "hal/qep.h"


typedef enum {
    MC_MODE_CURRENT = 0,    /* i_d, i_q references directly                           */
    MC_MODE_TORQUE,         /* torque -> MTPA / field weakening -> currents            */
    MC_MODE_SPEED           /* speed PI -> torque -> currents                          */
} mc_mode_t;

typedef struct {
    /* motor model the controller uses (small-signal, SI) */
    int   pole_pairs;
    float rs, ld, lq, psi_pm;
    /* timing */
    float ts;                    /* control period = PWM period [s]                    */
    /* ADC scaling: i = (count - offset) * amps_per_count; vdc = count * volts_per_count */
    float adc_amps_per_count;
    float adc_offset_nominal;    /* [counts] expected offset, checked by the calibration */
    float adc_offset_tol;        /* [counts] allowed deviation from the nominal offset   */
    float adc_volts_per_count;
    uint16_t offset_cal_samples; /* periods averaged at enable                          */
    /* protection */
    float i_trip;                /* phase current trip [A]                              */
    float vdc_min, vdc_max;      /* [V]                                                 */
    /* angle source */
    mc_angle_src_kind_t angle_src;
    uint32_t enc_counts_per_rev;
    float enc_offset_rad;
    float enc_pll_bw_hz, enc_speed_fc_hz;
    /* sensorless: UNOP + PLL filter (Fig. 6.9), HF injection (6.6) with a notch on the feedback */
    mc_unop_cfg_t unop;          /* its flux-model map pointer must outlive the drive   */
    float pll_bw_hz;             /* PLL after the estimator                             */
    float pll_speed_fc_hz;       /* its speed output filter                             */
    mc_inj_cfg_t inj;
    float notch_q;               /* notch at the injection frequency in i_dq feedback   */
    /* startup (thesis ch. 5): Step I pulses, Step II polarity, Step III continuous injection */
    bool  init_three_step;       /* sensorless: run INIT_POS; false: the angle comes with
                                    the enable command (mc_drive_cmd_t.theta_init)      */
    mc_initpos_cfg_t ip1;        /* Step I                                              */
    bool  ip1_pulse3;            /* Step I by the three-phase pulse reference (3.21)    */
    mc_pulse3_cfg_t pulse3;
    bool  ip2_dvi;               /* Step II by dual-voltage injection instead of (5.7)  */
    mc_polarity_cfg_t ip2;       /* Step II; its model must carry the l_dd asymmetry (map) */
    mc_dvi_cfg_t dvi;
    float step3_speed_tol;       /* [rad/s el] Step III converged when the filtered speed
                                    estimate stays below this ...                       */
    float step3_hold;            /* [s] ... for this long                               */
    float timeout_cal, timeout_step12, timeout_step3;   /* [s]                          */
    /* current loop */
    float cc_bw_hz;
    bool  cc_decouple;
    /* references */
    float i_max;                 /* phase current limit, peak [A]                       */
    float i_headroom;            /* share of i_max kept free for regulation error, noise
                                    and ripple: references stay within i_max (1 - this)  */
    float i_slew;                /* max rate of the current reference vector [A/s]; keeps
                                    the delayed loop from overshooting i_max on big steps */
    float u_margin;              /* share of vdc/sqrt(3) the references plan for         */
    bool  mtpa_table;
    /* speed loop (mechanical rad/s) */
    float sc_kp, sc_ki, torque_max;
    int   sc_decimation;
    /* modulator */
    bool  dtc_enable;
    float dtc_i_band;
    float dead_time;             /* [s] for the compensation                            */
} mc_drive_cfg_t;

/* Commands: written by the background side (sim, later CANopen), taken by the ISR at the start
 * of a period as one consistent copy. */
typedef struct {
    bool      enable;
    mc_mode_t mode;
    mc_dq_t   i_ref;             /* MC_MODE_CURRENT [A]              */
    float     torque_ref;        /* MC_MODE_TORQUE [N m]             */
    float     speed_ref;         /* MC_MODE_SPEED  [rad/s mechanical] */
    float     theta_init;        /* sensorless: rotor angle taken as known at enable [rad]
                                    (until the initial-position routine provides it)  */
} mc_drive_cmd_t;

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
    float    theta_raw, omega_raw;   /* estimator output before the PLL */
    int      est_iters;          /* Newton iterations this period     */
    float    est_cost, est_cond; /* final cost, Hessian conditioning  */
    float    u_inj;              /* injected d voltage [V]            */
    float    theta1, theta2;     /* Step I (mod pi) and Step II results [rad] */
    float    c1, c2;             /* (5.7) costs, or DVI peak currents        */
    bool     pol_flip;           /* Step II added pi                         */
    float    duty[3];
    bool     u_limited, fw_active;
} mc_drive_telem_t;

typedef struct {
    hal_adc_t *adc;
    hal_pwm_t *pwm;
    hal_qep_t *qep;
} mc_drive_hal_t;

typedef struct {
    mc_drive_cfg_t cfg;
    mc_drive_hal_t hal;
    mc_drive_cmd_t cmd_next;     /* written by mc_drive_command()            */
    volatile uint32_t cmd_seq;   /* bumped on every write; ISR copies when it changes */
    uint32_t cmd_seen;
    mc_drive_cmd_t cmd;          /* the ISR's copy                           */

    mc_seq_t seq;                /* state, init step, faults          */
    uint32_t cal_count;
    float cal_sum[3];
    float offset[3];             /* calibrated [counts]                      */

    mc_encoder_t enc;
    mc_unop_t unop;
    mc_pll_t pll;
    mc_inj_t inj;
    mc_biquad_t notch_d, notch_q;
    mc_initpos_t ip1;
    mc_pulse3_t pulse3;
    mc_polarity_t ip2;
    mc_dvi_t dvi;
    mc_lpf1_t step3_speed;       /* |omega_hat| low-passed for the convergence test */
    uint32_t step3_count;
    mc_cc_t cc;
    mc_sc_t sc;
    mc_tref_t tref;
    mc_dtc_t dtc;

    mc_dq_t i_ref_prev;          /* slew-limited reference of the last period */
    mc_ab_t i_ab_prev;
    mc_ab_t u_hist[2];           /* [0]: commanded last ISR (acts during k..k+1), [1]: the one before */
    mc_drive_telem_t tm;
} mc_drive_t;

/* Returns false (and latches MC_FAULT_CONFIG) when cfg is out of range. */
bool mc_drive_init(mc_drive_t *d, const mc_drive_cfg_t *cfg, hal_adc_t *adc, hal_pwm_t *pwm, hal_qep_t *qep);
void mc_drive_command(mc_drive_t *d, const mc_drive_cmd_t *cmd);
void mc_drive_isr(mc_drive_t *d);          /* the control period, top to bottom               */
void mc_drive_background(mc_drive_t *d);   /* slow work, outside the ISR                      */
mc_state_t mc_drive_state(const mc_drive_t *d);
uint32_t mc_drive_faults(const mc_drive_t *d);
const mc_drive_telem_t *mc_drive_telemetry(const mc_drive_t *d);
/* A configuration with the sun2016-ipm-5kw parameters at 10 kHz, for tests and as a template. */
void mc_drive_cfg_default(mc_drive_cfg_t *cfg);

#endif
