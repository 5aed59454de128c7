/* Phase programs: ONE interface for every routine that drives the PWM duties directly while the
 * current control loop is off, i.e. at standstill before the sensorless estimator takes over:
 *   - Step I pulses (thesis 5.2, Fig 5.3; cost (5.5) or (7.1)), mc/initpos.h,
 *   - the three-phase pulse method (3.5.1, (3.19)-(3.21), Table 3.1), mc/pulse3.h,
 *   - Step II generalized polarity detection (5.3, (5.6)-(5.7)), mc/polarity.h,
 *   - dual voltage injection, DVI (3.5.2, Fig 3.8), mc/polarity.h,
 *   - the flying-start catch (two zero-vector pulses, (C.1)-(C.3)), mc/catch.h,
 * and later identification routines.
 *
 * WHY: the drive runs at most one such program at a time, so it needs one dispatch (a table of
 * three functions) and one workspace (a union of the engines' states), not one member and one
 * code path per method. The engines keep their own APIs (mc_*_start / mc_*_step); a program
 * here is a thin adapter over them, so both paths give bit-identical results.
 *
 * CALLING CONVENTION: the one of mc/initpos.h. Once per PWM period, from the ISR: sample k of
 * the phase currents (taken at the start of period k) and Vdc go in; the duties that come out
 * act during the NEXT period (shadow registers); the program keeps that delay itself. Before
 * the first step the inverter is at the zero vector (or off) with the current at rest. Status
 * RUNNING until the result is ready; the DONE / FAILED call and every later one return the zero
 * vector V(000) (all low sides on: duties 0). Programs chain directly: the next program's first
 * step is the period after the previous one's DONE.
 *
 * MEMORY: sizeof(mc_phase_ws_t) <= MC_PHASE_WS_BUDGET (checked at compile time in
 * phase_program.c). The Step I engine is the largest (its search re-evaluates the cost on every
 * stored interval: 64 x 24 bytes); the others fold each interval into their result as it closes
 * and store none. One step call uses well under 1 kB of stack (ISR).
 *
 * Units SI: A, V, s, H, rad. */
#ifndef MC_PHASE_PROGRAM_H
#define MC_PHASE_PROGRAM_H
#include <stddef.h>

#include "mc/catch.h"
#include "mc/initpos.h"
#include "mc/polarity.h"
#include "mc/pulse3.h"
#include "mc/types.h"

/* host (x86-64) bound on the shared workspace [bytes]; on the 32-bit target it is smaller */
#define MC_PHASE_WS_BUDGET 2000

/* per period, into the program */
typedef struct {
    mc_ab_t i_ab;   /* measured currents i_ab(k) (2.4), sampled at the start of period k [A] */
    float vdc;      /* DC-link voltage [V]; <= 0 fails the program */
} mc_phase_in_t;

/* per period, out of the program */
typedef struct {
    mc_abc_t duty;  /* high-side duties 0..1 for the NEXT period (V(000) = all 0) */
    bool off;       /* outputs off from this sample on (a gate disable acts at once, not a period
                       later like the duties); only the catch uses it, the others keep false */
} mc_phase_out_t;

/* Result, valid after DONE (before: the engine's fields so far).
 *                   theta            theta_aux             flip       c1, c2
 *  step1_pulses     theta1 [0, pi)   theta_full [0, 2pi)   false      cost_min [V^2], 0
 *  step1_pulse3     theta  [0, pi)   theta_atan (3.21)     false      0, 0
 *                                    [-pi/4, pi/4]
 *  step2_polarity   theta2 [-pi,pi)  theta1 (the input)    c1 > c2    (5.7) c1, c2 [H^2]
 *  step2_dvi        theta2 [-pi,pi)  theta1 (the input)    neg > pos  peak |i_delta| of the
 *                                                                     +V, -V pulse [A]
 *  catch            theta at the     phi2 - phi1 (C.3)     false      |delta i2| / (C.1), 0
 *                   last sample                                       (omega, moving: below)
 * Step I results are modulo pi (the d axis without its polarity); Step II adds pi when flip.
 * theta_full of step1_pulses: linear cost (5.5) = theta1; the nonlinear costs (7.1) search the
 * whole circle and it is the refined minimum there (a weak polarity hint, thesis 7.2.3). */
typedef struct {
    float theta;      /* the program's angle estimate [rad] (table above) */
    float theta_aux;  /* secondary angle [rad] (table above) */
    bool flip;        /* Step II: pi was added to theta_in */
    float c1, c2;     /* decision quantities (table above) */
    float conf;       /* Step II generalized: confidence z (mc/polarity.h); others 0 */
    int verdict;      /* Step II generalized: mc_pol_verdict_t; others 0 */
    float omega;      /* catch: the speed [rad/s el] (others: 0) */
    bool moving;      /* catch: the rotor turns (false: standing, go on with the standstill start) */
    float i_peak;     /* largest |i_ab| sampled during the program [A] */
    int calls;        /* step calls consumed (PWM periods) */
} mc_phase_result_t;

/* One workspace shared by all programs: only the program that was begun on it owns it. */
typedef union {
    mc_initpos_t ip1;      /* mc_phase_step1_pulses   */
    mc_pulse3_t pulse3;    /* mc_phase_step1_pulse3   */
    mc_polarity_t pol;     /* mc_phase_step2_polarity */
    mc_dvi_t dvi;          /* mc_phase_step2_dvi      */
    mc_catch_t fly;        /* mc_phase_catch          */
} mc_phase_ws_t;

typedef struct mc_phase_program {
    const char *name;
    size_t cfg_size;  /* sizeof the configuration type begin() expects (integrator's check) */
    /* Start on ws with cfg (the engine's own type: mc_initpos_cfg_t, mc_pulse3_cfg_t,
     * mc_polarity_cfg_t, mc_dvi_cfg_t; copied, need not outlive the call) and theta_in [rad]
     * (Step II: the Step I estimate theta1; ignored by Step I). false on a bad or NULL cfg;
     * the program then only returns FAILED. Not for the ISR's time budget: a program setup. */
    bool (*begin)(mc_phase_ws_t *ws, const void *cfg, float theta_in);
    /* One PWM period (calling convention above); out is always written. */
    mc_ip_status_t (*step)(mc_phase_ws_t *ws, const mc_phase_in_t *in, mc_phase_out_t *out);
    void (*result)(const mc_phase_ws_t *ws, mc_phase_result_t *res);
} mc_phase_program_t;

extern const mc_phase_program_t mc_phase_step1_pulses;    /* cfg: mc_initpos_cfg_t  */
extern const mc_phase_program_t mc_phase_step1_pulse3;    /* cfg: mc_pulse3_cfg_t   */
extern const mc_phase_program_t mc_phase_step2_polarity;  /* cfg: mc_polarity_cfg_t */
extern const mc_phase_program_t mc_phase_step2_dvi;       /* cfg: mc_dvi_cfg_t      */
extern const mc_phase_program_t mc_phase_catch;           /* cfg: mc_catch_cfg_t    */

/* Convenience holder: the program and its workspace together, so they cannot be mismatched.
 * prog == NULL (after mc_phase_stop, or a begin with NULL prog): step returns FAILED with
 * V(000), result gives zeros. */
typedef struct {
    const mc_phase_program_t *prog;
    mc_phase_ws_t ws;
} mc_phase_t;

/* prog->begin on ph->ws; false on a NULL prog or a bad cfg */
bool mc_phase_begin(mc_phase_t *ph, const mc_phase_program_t *prog, const void *cfg,
                    float theta_in);
/* out is set to V(000) first, then prog->step */
mc_ip_status_t mc_phase_step(mc_phase_t *ph, const mc_phase_in_t *in, mc_phase_out_t *out);
void mc_phase_result(const mc_phase_t *ph, mc_phase_result_t *res);
void mc_phase_stop(mc_phase_t *ph);

#endif
