/* The drive's parameter table: every tunable drive parameter once. Everything that names a
 * parameter comes from this list (docs/parameters.md):
 *   - the members of mc_params_t, named as the parameter (control.current_bw_hz is member
 *     control_current_bw_hz), and the ids MC_PARAM_<member> (mc/params.h): one name per parameter,
 *   - the runtime table mc_param_table[] (name, type, unit, range, default, group, access, doc),
 *   - validation (mc_params_validate: finiteness and range per entry, then the cross-checks),
 *   - the default rules (mc_params_derive: MC_RULE_* below, each documented in params.c),
 *   - the simulator's drive keys (`mcsim keys`, docs/simulator.md), generated from the runtime table,
 *   - the CANopen manufacturer objects 0x2000 + index (the index of an entry is its position in
 *     this list: append new entries, never reorder, or a CANopen master's object numbers move),
 *   - the stored parameter block, keyed by name and type (mc/store.h: a stored set survives a
 *     table change).
 *
 * X(group, key, TYPE, "unit", min, max, default, RULE, GROUP, ACCESS, CHOICES, "doc")
 *   group, key: the parameter's name "group.key" (scenario key, mctune name, docs); its member
 *           and id suffix are group_key
 *   TYPE    F32 | I32 | BOOL | ENUM (ENUM: the stored value is the position in its CHOICES list,
 *           MC_CHOICES_<member> below; every other type has MC_NO_CHOICES)
 *   default a constant; with a RULE other than NONE the value is derived from the motor data
 *           unless the user sets it (the constant is then unused)
 *   GROUP   MOTOR and HW entries describe the machine and the power stage: the integrator (or the
 *           simulator, from the preset and its sensor keys) sets them; the others are tuning
 *   ACCESS  INIT: only at mc_drive_init; STANDSTILL: while the outputs are off; RUNTIME: any time
 *
 * Units are the ones named; the drive converts to SI (rad/s electrical, ...) when it builds the
 * block configurations. Order matters for the rules: an entry's rule may only read entries above. */
#ifndef MC_PARAMS_TABLE_H
#define MC_PARAMS_TABLE_H
#include "mc/angle_source.h"
#include "mc/faults.h"

/* clang-format off */
/* The ENUM parameters' choices, L(member, choice) in the order of their stored values: the
 * table's choice text ("a|b|c") and the named constants MC_CHOICE_<member>_<choice> (mc/params.h)
 * come from these lists, so code compares with a name, never with a bare position. */
#define MC_NO_CHOICES(L)
#define MC_CHOICES_control_angle_source(L) MC_ANGLE_SOURCES(MC_CH_ASRC_##L)   /* the registry's order */
#define MC_CHOICES_control_mtpa(L)              L(control_mtpa, analytic) L(control_mtpa, table)
#define MC_CHOICES_estimator_model(L)           L(estimator_model, const) L(estimator_model, fluxmap)
#define MC_CHOICES_injection_kind(L)            L(injection_kind, off) L(injection_kind, sine) L(injection_kind, rect)
#define MC_CHOICES_startup_init_pos(L)          L(startup_init_pos, given) L(startup_init_pos, three_step) L(startup_init_pos, if_start) L(startup_init_pos, auto)
#define MC_CHOICES_startup_step1_method(L)      L(startup_step1_method, pulses) L(startup_step1_method, three_phase)
#define MC_CHOICES_startup_step1_cost(L)        L(startup_step1_cost, linear) L(startup_step1_cost, nonlinear) L(startup_step1_cost, fluxdiff)
#define MC_CHOICES_startup_polarity(L)          L(startup_polarity, generalized) L(startup_polarity, dvi)
#define MC_CHOICES_startup_catch(L)             L(startup_catch, off) L(startup_catch, on)
#define MC_CHOICES_protection_lock_action(L)    L(protection_lock_action, fault) L(protection_lock_action, recover)
#define MC_CHOICES_protection_overspeed_action(L) L(protection_overspeed_action, off) L(protection_overspeed_action, hold_fw)
#define MC_CHOICES_protection_polarity_check(L) L(protection_polarity_check, off) L(protection_polarity_check, on_doubt) L(protection_polarity_check, at_start)
#define MC_CH_ASRC_MC_CH_TEXT(src) MC_CH_TEXT(control_angle_source, src)
#define MC_CH_ASRC_MC_CH_ENUM(src) MC_CH_ENUM(control_angle_source, src)

#define MC_PARAMS(X) \
/* ---- motor: the model the controller uses (small-signal, at i = 0) ---- */ \
X(motor, pole_pairs,                  I32, "",        1,     100,    5,        NONE, MOTOR, INIT, MC_NO_CHOICES, "Pole pairs.") \
X(motor, rs_ohm,                      F32, "ohm",     1e-5f, 100,    0.400f,   NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "Stator resistance per phase.") \
X(motor, ld_h,                        F32, "H",       1e-7f, 10,     10.5e-3f, NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "d-axis inductance, small-signal at i = 0.") \
X(motor, lq_h,                        F32, "H",       1e-7f, 10,     12.9e-3f, NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "q-axis inductance, small-signal at i = 0.") \
X(motor, psi_pm_wb,                   F32, "Wb",      0,     20,     0.34305f, NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "Permanent-magnet flux linkage at i = 0.") \
X(motor, i_rated_a,                   F32, "A",       0.01f, 10000,  13.29f,   NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "Rated phase current, peak.") \
X(motor, torque_rated_nm,             F32, "N m",     1e-3f, 1e5f,   29.7f,    NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "Rated torque.") \
X(motor, inertia_kgm2,                F32, "kg m^2",  1e-7f, 1e3f,   0.013f,   NONE, MOTOR, STANDSTILL, MC_NO_CHOICES, "Inertia of rotor and load (speed-loop gains).") \
/* ---- power stage and sensing ---- */ \
X(control, ts_s,                      F32, "s",       5e-5f, 5e-4f,  1e-4f,    NONE, HW, INIT, MC_NO_CHOICES, "Control = PWM period, sampled at its centre (2 kHz to 20 kHz).") \
X(hw, vdc_nominal_v,                  F32, "V",       1,     5000,   300,      NONE, HW, STANDSTILL, MC_NO_CHOICES, "Nominal DC-link voltage (the protection window follows it).") \
X(hw, adc_bits,                       I32, "bit",     8,     16,     12,       NONE, HW, INIT, MC_NO_CHOICES, "Resolution of the current and voltage ADC.") \
X(hw, i_span_a,                       F32, "A",       0.1f,  10000,  25,       NONE, HW, INIT, MC_NO_CHOICES, "Current ADC span -span..+span (a sample at a rail counts as over-current).") \
X(hw, vdc_span_v,                     F32, "V",       1,     5000,   500,      NONE, HW, INIT, MC_NO_CHOICES, "DC-link ADC span 0..span.") \
X(hw, adc_offset_tol,                 F32, "1",       1e-3f, 0.5f,   0.05f,    NONE, HW, INIT, MC_NO_CHOICES, "Allowed offset of a current channel from mid-scale, share of the full range (else offset-calibration fault).") \
X(hw, dead_time_s,                    F32, "s",       0,     1e-5f,  0.5e-6f,  NONE, HW, STANDSTILL, MC_NO_CHOICES, "Inverter dead time (for the compensation).") \
X(hw, encoder_lines,                  I32, "lines/rev", 1,   1000000, 20000,   NONE, HW, INIT, MC_NO_CHOICES, "Quadrature encoder lines (4 counts each).") \
X(hw, encoder_offset_rad,             F32, "rad el",  -7,    7,      0,        NONE, HW, STANDSTILL, MC_NO_CHOICES, "Electrical angle at encoder count 0.") \
/* ---- protection ---- */ \
X(control, i_trip_a,                  F32, "A",       0.01f, 10000,  20,       I_TRIP,  PROTECTION, STANDSTILL, MC_NO_CHOICES, "Over-current trip, peak of any phase (default: 1.5 x motor.i_rated_a).") \
X(control, vdc_min_v,                 F32, "V",       0,     5000,   150,      VDC_MIN, PROTECTION, STANDSTILL, MC_NO_CHOICES, "Under-voltage trip (default: 0.5 x hw.vdc_nominal_v).") \
X(control, vdc_max_v,                 F32, "V",       0,     5000,   450,      VDC_MAX, PROTECTION, STANDSTILL, MC_NO_CHOICES, "Over-voltage trip (default: 1.5 x hw.vdc_nominal_v).") \
/* ---- control ---- */ \
X(control, angle_source,              ENUM, "",       0,     MC_ANGLE_SRC_COUNT - 1, 0, NONE, CONTROL, STANDSTILL, MC_CHOICES_control_angle_source, "Angle the controller uses: the encoder, or the sensorless estimator UNOP (thesis ch. 6).") \
X(control, offset_cal_samples,        I32, "periods", 1, 65535, 64, OFFSET_CAL, CONTROL, STANDSTILL, MC_NO_CHOICES, "Periods averaged for the current offsets at every enable (default: 6.4 ms worth, at least 16: 64 at 10 kHz; a count of periods made the calibration 32 ms long at 2 kHz).") \
X(control, i_max_a,                   F32, "A",       0.01f, 10000,  13.29f,   I_MAX,   CONTROL, RUNTIME, MC_NO_CHOICES, "Phase current limit, peak; references stay within i_max (1 - i_headroom) (default: motor.i_rated_a).") \
X(control, i_headroom,                F32, "1",       0,     0.49f,  0.03f,    NONE,    CONTROL, RUNTIME, MC_NO_CHOICES, "Share of control.i_max_a the references leave free for regulation error, noise and ripple.") \
X(control, current_bw_hz,             F32, "Hz",      10,    5000,   250,      CC_BW,   CONTROL, RUNTIME, MC_NO_CHOICES, "Current-loop bandwidth (default: min(f_s / 40, injection.f_hz / 2)).") \
X(control, i_slew_a_per_s,            F32, "A/s",    1,     1e8f,   10000,    I_SLEW,  CONTROL, RUNTIME, MC_NO_CHOICES, "Rate limit of the current reference vector (default: 0.5 x rated current x current-loop bandwidth in rad/s).") \
X(control, decouple,                  BOOL, "",       0,     1,      1,        NONE,    CONTROL, RUNTIME, MC_NO_CHOICES, "Decoupling feed-forward in the current loop.") \
X(control, u_margin,                  F32, "1",       0.1f,  1.049f, 1.0f,     NONE,    CONTROL, RUNTIME, MC_NO_CHOICES, "Share of Vdc/sqrt(3) the references plan for (field weakening); above 1 only with control.u_loop > 1 (overmodulation, at most its steady fundamental (2.14a), 1.049 at the corners). Default 1: 95 % of that 1.049, the rest is the current loop's headroom; with control.u_loop = 1 use 0.95.") \
X(control, mtpa,                      ENUM, "",       0,     1,      0,        NONE,    CONTROL, STANDSTILL, MC_CHOICES_control_mtpa, "MTPA law (2.24) or its table.") \
X(control, speed_bw_hz,               F32, "Hz",      0.1f,  200,    25,       SPEED_BW, CONTROL, RUNTIME, MC_NO_CHOICES, "Speed-loop bandwidth (default: min(25 Hz, f_s / (40 x decimation), estimator.pll_bw_hz when sensorless, a quarter of the q current's large-signal bandwidth (Vdc/sqrt3 - injection.v1_v while injecting) / (2 pi motor.lq_h control.i_max_a))); sets the gains unless given.") \
X(control, speed_kp,                  F32, "N m s/rad", 0,   1e4f,   2.04f,    SPEED_KP, CONTROL, RUNTIME, MC_NO_CHOICES, "Speed PI proportional gain, mechanical rad/s (default: J w_bw).") \
X(control, speed_ki,                  F32, "N m/rad", 0,     1e6f,   80.2f,    SPEED_KI, CONTROL, RUNTIME, MC_NO_CHOICES, "Speed PI integral gain (default: kp w_bw / 4).") \
X(control, speed_decimation,          I32, "periods", 1,  100,    10,       SC_DEC,  CONTROL, STANDSTILL, MC_NO_CHOICES, "The speed loop runs every N periods (default: f_s / 1 kHz, the speed loop at 1 kHz).") \
X(control, torque_max_nm,             F32, "N m",     0.01f, 1e5f,   35.6f,    TORQUE_MAX, CONTROL, RUNTIME, MC_NO_CHOICES, "Speed-loop torque limit (default: 1.2 x motor.torque_rated_nm).") \
X(control, deadtime_comp,             BOOL, "",       0,     1,      1,        NONE,    CONTROL, RUNTIME, MC_NO_CHOICES, "Dead-time compensation in the modulator.") \
X(control, dtc_i_band_a,              F32, "A",       1e-3f, 1000,   0.3f,     I_SMALL, CONTROL, RUNTIME, MC_NO_CHOICES, "Linear zone of the compensation's current sign (default: 2.26 % of motor.i_rated_a).") \
X(control, encoder_pll_bw_hz,         F32, "Hz",  1,     2000,   150,      NONE,    CONTROL, STANDSTILL, MC_NO_CHOICES, "Encoder speed PLL bandwidth.") \
X(control, encoder_speed_fc_hz,       F32, "Hz", 1,   10000,  500,      ENC_FC,  CONTROL, STANDSTILL, MC_NO_CHOICES, "Encoder speed output filter (default: min(500 Hz, f_s / 4)).") \
/* ---- sensorless estimator (UNOP, thesis ch. 6) and its PLL filter (Fig. 6.9) ---- */ \
X(estimator, model,                   ENUM, "",       0,     1,      1,        NONE, ESTIMATOR, STANDSTILL, MC_CHOICES_estimator_model, "UNOP machine model: constant Rs, Ld, Lq, psi_pm (thesis) or the flux map psi_dq(i_dq).") \
X(estimator, iter_max,                I32, "",        1,     18,     4,        NONE, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Newton iterations per sample (early exit on estimator.step_tol).") \
X(estimator, step_tol,                F32, "rad",     0,     1,      1e-4f,    NONE, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Early exit when the scaled Newton step is below this.") \
X(estimator, k1,                      F32, "1/rad^2", 0,     1e9f,   0.5f,     NONE, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Angle regularisation weight K1 of (6.5), active below injection.n1_rpm.") \
X(estimator, k2,                      F32, "1",       0,     1e9f,   100,      K2,   ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Speed regularisation weight K2 of (6.5) on the scaled speed, active below injection.n1_rpm (default: 100 (psi_pm w_base / 107.77 V)^2, so that it weighs against the back-EMF term as on the thesis motor).") \
X(estimator, speed_scale_rpm,         F32, "rpm", 1,    1e5f,   600,      NONE, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Speed that scales the decision variable omega (float32 conditioning).") \
X(estimator, mid_sample,              BOOL, "",       0,     1,      1,        NONE, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Rotational terms at the mid-sample angle (false: the thesis' first-order form (5.1)).") \
X(estimator, reg_predicted,           BOOL, "",     0,     1,      1,        NONE, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "K1 pulls toward the predicted angle theta(k-1) + omega Ts (false: literal (6.5)).") \
/* ---- HF injection (6.4), (6.6) ---- */ \
X(injection, kind,                    ENUM, "",       0,     2,      1,        NONE, INJECTION, STANDSTILL, MC_CHOICES_injection_kind, "HF voltage in the estimated d axis (6.4, 7.4); only with control.angle_source = unop.") \
X(injection, f_hz,                    F32, "Hz",      1,     10000,  500,      INJ_F,   INJECTION, STANDSTILL, MC_NO_CHOICES, "Injection frequency (default: min(500 Hz, f_s / 4): the thesis' 500 Hz, also at 2 kHz).") \
X(injection, i_hf_a,                  F32, "A",       0,     10000,  2.13f,    INJ_I,   INJECTION, STANDSTILL, MC_NO_CHOICES, "Target HF current amplitude at standstill (default: 16 % of motor.i_rated_a, the thesis' 2.1 A).") \
X(injection, v1_v,                    F32, "V",       0,     1000,   70,       INJ_V1,  INJECTION, RUNTIME, MC_NO_CHOICES, "Injection magnitude at standstill, V1 of (6.6) (default: i_hf_a 2 pi f Ld, 2 significant digits: 70 V on the thesis motor).") \
X(injection, n1_rpm,                  F32, "rpm",     0,     1e5f,   400,      N1,      INJECTION, RUNTIME, MC_NO_CHOICES, "N1 of (6.6): the injection fades to zero at this speed; K1, K2 are zero above it (default: 33.3 Hz electrical, the thesis' 400 rpm).") \
X(injection, notch_q,                 F32, "1",       0.1f,  50,     1,        NONE,    INJECTION, STANDSTILL, MC_NO_CHOICES, "Quality factor of the notch that keeps the injection out of the current feedback.") \
X(estimator, pll_bw_hz,               F32, "Hz",      1,     2000,   30,       PLL_BW,  ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Bandwidth of the PLL filter after the estimator, Fig. 6.9 (default: 6 % of injection.f_hz: 30 Hz at 500 Hz; at most 6 x the speed loop's slew bound, see control.speed_bw_hz).") \
X(estimator, pll_speed_fc_hz,         F32, "Hz", 1,     5000,   200,      PLL_FC,  ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Speed output filter of that PLL (default: min(200 Hz, f_s / 10, 8 x control.speed_bw_hz)).") \
/* ---- startup: offset calibration and the three-step initial position (thesis ch. 5) ---- */ \
X(startup, init_pos,                  ENUM, "",       0,     3,      0,        NONE, STARTUP, STANDSTILL, MC_CHOICES_startup_init_pos, "Sensorless start: the angle handed over with the enable command (given), the thesis' three steps (pulse injection, polarity detection, continuous injection), an I/f open-loop start (if_start: a current of startup.if_i_a on a ramped frame, handed over to the estimator above startup.if_handover_rpm, docs/startup.md), or auto: three_step where the model's saliency is usable for the injection (HF current difference between the axes >= 4 ADC counts), else if_start. Where the saliency is not usable (or with if_start) the drive also runs I/f below the hand-over speed in RUN.") \
X(startup, step1_method,              ENUM, "",       0,     1,      0,        NONE, STARTUP, STANDSTILL, MC_CHOICES_startup_step1_method, "Step I: the thesis' pulse injection with the cost (5.5)/(7.1), or the three-phase pulse reference method (3.21) with Table 3.1.") \
X(startup, step1_cost,                ENUM, "",       0,     2,      1,        NONE, STARTUP, STANDSTILL, MC_CHOICES_startup_step1_cost, "Step I cost: (5.5) with constant Ld, Lq; (7.1) with the flux map's differential inductances; or flux differences of the map.") \
X(startup, step1_m,                   I32, "periods", 1,     16,     5,        STEP1_M, STARTUP, STANDSTILL, MC_NO_CHOICES, "Step I pulse length m: V(100) m, V(011) 2m, V(100) m (default: a 0.72 x rated current peak through Ld at 2/3 Vdc, the thesis' 5).") \
X(startup, step1_dirs,                I32, "",        1,     3,      1,        NONE,    STARTUP, STANDSTILL, MC_NO_CHOICES, "Step I pulse directions (phase A, then B, C).") \
X(startup, i_rest_a,                  F32, "A",       1e-3f, 1000,   0.3f,     I_SMALL, STARTUP, STANDSTILL, MC_NO_CHOICES, "A pulse gap ends once |i| is below this (default: 2.26 % of motor.i_rated_a, the thesis' 0.3 A).") \
X(startup, polarity,                  ENUM, "",       0,     1,      0,        NONE,    STARTUP, STANDSTILL, MC_CHOICES_startup_polarity, "Step II: generalized polarity detection (5.6)-(5.7) or dual-voltage injection (3.5.2).") \
X(startup, step2_n,                   I32, "periods", 1,     16,     4,        NONE,    STARTUP, STANDSTILL, MC_NO_CHOICES, "Step II half-pulse length (train +n, -2n, +n).") \
X(startup, v_pol_v,                   F32, "V",       0.01f, 2000,   200,      V_POL,   STARTUP, STANDSTILL, MC_NO_CHOICES, "Step II pulse magnitude, hexagon-limited (default: a 0.57 x rated current swing through Ld in n periods, at most 2/3 Vdc: the thesis' 200 V).") \
X(startup, dvi_n,                     I32, "periods", 1,     16,     6,        NONE,    STARTUP, STANDSTILL, MC_NO_CHOICES, "DVI pulse length.") \
X(startup, step3_speed_tol_rpm,       F32, "rpm", 0.01f, 1000, 5,        STEP3_TOL, STARTUP, STANDSTILL, MC_NO_CHOICES, "Step III converged when the filtered speed estimate stays below this ... (default: the larger of 0.42 Hz electrical (the thesis motor's 5 rpm) and 5 x the estimator's expected speed noise).") \
X(startup, step3_hold_s,              F32, "s",       1e-4f, 1,      0.005f,   NONE,    STARTUP, STANDSTILL, MC_NO_CHOICES, "... for this long (1.5 time constants of its 50 Hz low-pass).") \
X(startup, timeout_step12_s,          F32, "s",    1e-3f, 10,     0.02f,    T_STEP12, STARTUP, STANDSTILL, MC_NO_CHOICES, "Step I + II must finish within this, else FAULT (default: the larger of 20 ms and 200 periods).") \
X(startup, timeout_step3_s,           F32, "s",     1e-3f, 60,     0.5f,     NONE,    STARTUP, STANDSTILL, MC_NO_CHOICES, "Step III must converge within this, else FAULT.") \
/* ---- protection: plausibility and loss-of-lock detectors (firmware/app/protect.c); a time of 0 \
 *      switches a detector off ---- */ \
X(protection, overspeed_rpm,          F32, "rpm",  1,     1e5f,   1625,     OVERSPEED, PROTECTION, RUNTIME, MC_NO_CHOICES, "Over-speed trip on the filtered speed estimate (default: the highest speed the current limit can field-weaken to at the nominal DC link, (Vdc/sqrt3) / (psi_pm - Ld i_max); beyond it the current runs away).") \
X(protection, i_sum_tol_a,            F32, "A",      1e-3f, 10000,  0.66f,    I_SUM,   PROTECTION, STANDSTILL, MC_NO_CHOICES, "Current-sensor plausibility: |i_a + i_b + i_c| above this (default: the larger of 5 % of rated and 8 ADC counts) ...") \
X(protection, i_sum_time_s,           F32, "s",     0,     1,      0.002f,   NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... for this long: current-sensor fault (a stuck channel, an offset drifted beyond calibration).") \
X(protection, tracking_err_a,         F32, "A",   1e-3f, 10000,  3.3f,     TRACK,   PROTECTION, STANDSTILL, MC_NO_CHOICES, "Current-tracking plausibility: |i_ref - i_dq| (the feedback, the error vector low-passed at 20 Hz) above this (default: 25 % of rated) ...") \
X(protection, tracking_time_s,        F32, "s",  0,     1,      0.02f,    NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... for this long: tracking fault (a wrong angle, a missing phase at standstill).") \
X(protection, residual_v,             F32, "V",      0.01f, 10000,  17,       RESID,   PROTECTION, STANDSTILL, MC_NO_CHOICES, "Voltage-model plausibility: the rms of u_dq - Rs i_dq - w J psi(i_dq) (the current loop's output against the steady-state model with the angle source's speed; mean square low-passed at 20 Hz) above this plus half of |w| Lq i_max (the model's saturation error) (default: a tenth of Vdc/sqrt3) ...") \
X(protection, residual_time_s,        F32, "s",  0,     1,      0.02f,    NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... for this long: voltage-model fault (a frozen encoder, a sensorless estimate on the wrong solution, an open phase).") \
X(protection, lock_speed_tol,         F32, "1",   0.05f, 10,     0.5f,     NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "Loss of lock: the estimator's raw speed (low-passed) differs from the filtered speed by more than this share of it ...") \
X(protection, lock_speed_floor_rpm,   F32, "rpm", 0.1f, 1e4f, 100, LOCK_FLOOR, PROTECTION, STANDSTILL, MC_NO_CHOICES, "... plus this (default: a quarter of injection.n1_rpm: below it the raw speed is mostly noise) ...") \
X(protection, lock_time_s,            F32, "s",      0,     1,      0.02f,    NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... for this long: loss-of-lock fault (sensorless only).") \
X(protection, stall_speed_rpm,        F32, "rpm", 0.1f, 1e4f,   20,       STALL,   PROTECTION, STANDSTILL, MC_NO_CHOICES, "Stall (speed mode): |speed estimate| below this (default: 5 % of injection.n1_rpm) while the speed reference is above it and the speed loop asks for at least 90 % of its torque limit ...") \
X(protection, stall_time_s,           F32, "s",     0,     10,     0.3f,     NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... for this long: stall fault.") \
/* ---- startup: the flying-start catch (mc/catch.h), appended (CANopen index = position) ---- */ \
X(startup, catch,                     ENUM, "",       0,     1,      1,        NONE,    STARTUP, STANDSTILL, MC_CHOICES_startup_catch, "Sensorless start: first probe with the zero vector whether the rotor turns; if it does, take its angle and speed from two zero-vector pulses (mc/catch.h) and go straight to RUN, else go on with startup.init_pos. Not with an angle sensor.") \
X(startup, catch_i_a,                 F32, "A",       1e-3f, 10000,  2.0f,     CATCH_I, STARTUP, STANDSTILL, MC_NO_CHOICES, "Catch pulse: the zero vector lasts until the current has changed by this (default: 15 % of motor.i_rated_a; the peak stays near it plus one period's rise; where the diodes conduct, one period of a hexagon corner instead, mc/catch.h (C.6)) ...") \
X(startup, catch_min_rpm,             F32, "rpm",     0.1f,  1e5f,   24,       CATCH_MIN, STARTUP, STANDSTILL, MC_NO_CHOICES, "... and below this speed the rotor counts as standing: the probe lasts until the back-EMF at this speed would have driven a quarter of catch_i_a, and the standstill start follows (default: 2 Hz electrical, 24 rpm on the thesis motor).") \
X(protection, lock_action,            ENUM, "",      0,     1,      0,        NONE,    PROTECTION, STANDSTILL, MC_CHOICES_protection_lock_action, "On a recoverable fault (mc/faults.h:" MC_FAULTS_RECOVERABLE_NAMES ") while sensorless: fault (outputs off, reason latched), or recover: outputs off, the flying-start catch (whatever startup.catch says), RUN with the caught angle; a standing rotor goes through Steps I-III (startup.init_pos = three_step) or faults. Default fault: with an estimator model that is wrong (docs/results.md, envelope) retries lose the angle again.") \
X(protection, retries,                I32, "",        0,     10,     3,        NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "Recoveries allowed before the fault is latched ...") \
X(protection, retry_reset_s,          F32, "s",    0.01f, 600,    1,        NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... counted again from zero after this long in RUN without one.") \
X(protection, overspeed_action,       ENUM, "", 0,   1,      1,        NONE,    PROTECTION, STANDSTILL, MC_CHOICES_protection_overspeed_action, "Over-speed above the uncontrolled-generation speed (sqrt3 |w| psi_pm > Vdc: with the outputs off the diodes would rectify the back-EMF into the link): off, or hold_fw: the fault is latched but the outputs stay on with zero torque and the field-weakening current until sqrt3 |w| psi_pm < 0.95 Vdc, then off (state FAULT_REACTION; any other fault turns the outputs off at once).") \
X(protection, reaction_timeout_s,     F32, "s", 0.01f, 600, 10,     NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "Longest fault reaction (hold_fw: with zero torque only friction slows the rotor); then the outputs go off.") \
X(hw, device_drop_v,                  F32, "V",       0,     50,     0,        NONE,    HW, STANDSTILL, MC_NO_CHOICES, "On-state drop of a power device (switch or diode): the flying-start catch takes it out of its zero-vector currents.") \
X(protection, polarity_check,         ENUM, "",   0,     2,      1,        NONE,    PROTECTION, STANDSTILL, MC_CHOICES_protection_polarity_check, "Low-speed polarity re-check while running (Step II's l_dd asymmetry with the HF injection: +-polarity_bias_a on the d reference, the HF current compared; reversed: the estimate turns by pi): off, when in doubt (the loss-of-lock checks half-way to a trip, below half of injection.n1_rpm), or also once at every RUN entry not preceded by Step II.") \
X(protection, polarity_bias_a,        F32, "A",  1e-3f, 10000,  6.6f,     POL_BIAS, PROTECTION, STANDSTILL, MC_NO_CHOICES, "The re-check's d-current bias (default: half of motor.i_rated_a: Step II's swing).") \
X(protection, lock_jump_deg,          F32, "deg",  1,     180,    30,       NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "Loss of lock, fast path: the estimator's raw angle off the PLL's by more than this (electrical; the injection ripple is a few degrees) ...") \
X(protection, lock_jump_time_s,       F32, "s", 0,     1,      0.002f,   NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "... for this long: loss-of-lock fault (sensorless only; an estimate that runs away within milliseconds, faster than the averaged checks). 0: off.") \
X(protection, accel_time_s,           F32, "s",     0,     1,      0.03f,    NONE,    PROTECTION, STANDSTILL, MC_NO_CHOICES, "Torque plausibility (speed mode): the speed loop asks for at least half its torque limit and the speed estimate (its derivative low-passed at 20 Hz) accelerates the other way at more than half of what that torque would give on motor.inertia_kgm2, for this long: fault torque_plausibility (a wrong angle; also an overload far beyond the limit). 0: off.") \
X(control, u_loop,                    F32, "1",       1,     1.1547f, 1.1547f, NONE,    CONTROL, RUNTIME, MC_NO_CHOICES, "Radius of the voltage circle the current loop may ask of the modulator, share of Vdc/sqrt(3): 1 = linear SVPWM only; above 1 the request may reach the hexagon's corners (2/sqrt(3) = 1.1547) and mc_svpwm scales it into the hexagon keeping its direction (overmodulation, mc/svpwm.h (2.14a)).") \
X(startup, polarity_z_min,            F32, "1",       0,     1000,   3,        NONE,    STARTUP, STANDSTILL, MC_NO_CHOICES, "Step II decides only at this confidence, a t statistic: generalized, the fitted share of the model's odd l_dd profile over its standard error (below it further trains with longer pulses, peak 0.9 x control.i_max_a by the model, until 64 intervals are stored); DVI, the pulses' mean current-change difference over its standard error (up to 3 programs). Still below: an init_pos fault (undecided) instead of a guess. 0: the thesis' rules, no check.") \
X(estimator, l_adapt_s,               F32, "s",       0,     10,     0.01f,    L_ADAPT, ESTIMATOR, STANDSTILL, MC_NO_CHOICES, "Time constant of UNOP's inductance-scale adaptation while injecting; 0: off (default: 5 injection periods).") \
/* ---- startup: the I/f open loop for motors without usable saliency (mc/if_start.h), appended ---- */ \
X(startup, if_i_a,                    F32, "A",       1e-3f, 10000,  11,       IF_I,     STARTUP, STANDSTILL, MC_NO_CHOICES, "I/f: the open loop's current magnitude on the frame's q axis (default: 0.8 x control.i_max_a: half the rated torque and room to accelerate).") \
X(startup, if_accel_rpm_s,            F32, "rpm/s",   1e-3f, 1e7f,   2600,     IF_ACCEL, STARTUP, STANDSTILL, MC_NO_CHOICES, "I/f: ramp of the frame's speed (default: an eighth of the torque of startup.if_i_a on motor.inertia_kgm2).") \
X(startup, if_handover_rpm,           F32, "rpm",     1e-3f, 1e5f,   72,       IF_W_H,   STARTUP, STANDSTILL, MC_NO_CHOICES, "I/f: the estimator takes over above this, I/f again below half of it (default: where the back-EMF is 5 x the voltage error: dead time, device drops, half of Rs x startup.if_i_a).")
/* clang-format on */

#endif
