/* Initial rotor position at standstill, Step I of thesis chapter 5: a balanced train of direct
 * voltage vectors, then the position minimising the cost (5.5) (constant La) or (7.1) (the flux
 * model's differential inductances), modulo pi. Also the pulse-program runner shared by the
 * Step II polarity engines (mc/polarity.h) and the three-phase pulse method (mc/pulse3.h).
 * See docs/initpos.md.
 *
 * CALLING CONVENTION (all engines of this family). Sample k is taken at the start of PWM period
 * k; the engine is called once per period, call k receives i_ab(k) and vdc, and returns the three
 * high-side duties. Those duties are loaded into the shadow registers and act during the NEXT
 * period, i.e. between samples k+1 and k+2. So at call k:
 *   - the interval [k-1, k] was driven by the duties returned at call k-2,
 *   - the interval [k, k+1] is driven by the duties returned at call k-1,
 *   - the duties returned now drive [k+1, k+2].
 * The engine keeps that two-deep delay line itself and records every measured interval as
 * (i(j-1), i(j), ubar) with the vector that really acted on [j-1, j]. Before the first call the
 * inverter must have been at the zero vector (or off) with the current at rest, so the first two
 * intervals [-1, 0] and [0, 1] are taken as zero voltage. The returned status is RUNNING until
 * the result is ready; the DONE/FAILED call returns the zero vector V(000) (all low sides on). */
#ifndef MC_INITPOS_H
#define MC_INITPOS_H
#include <stdint.h>

#include "mc/flux_model.h"
#include "mc/svpwm.h"
#include "mc/types.h"

#define MC_IP_REC_MAX   64   /* measured intervals a stored program (mc_ip_prog_t) keeps */
#define MC_IP_SEG_MAX   16   /* segments of one program */
#define MC_IP_VEC_MAX   8    /* distinct arbitrary (non-direct) vectors of one program */
#define MC_IP_TAG_MAX   127  /* segment tags are 0..MC_IP_TAG_MAX (int8_t) */
#define MC_IP_M_MAX     16   /* upper bound of the pulse length m [periods] */
#define MC_IP_GRID_MAX  72   /* coarse grid points of the Step I search */
#define MC_IP_GS_MAX    30   /* golden-section iterations (bounded loop) */

typedef enum { MC_IP_RUNNING = 0, MC_IP_DONE, MC_IP_FAILED } mc_ip_status_t;

/* direct voltage vectors V(abc): bit 2 = phase a high, bit 1 = b, bit 0 = c. V(100) = 4. */
#define MC_IP_V100 4u
#define MC_IP_V010 2u
#define MC_IP_V001 1u

/* ---------------- pulse-program runner (shared by initpos, polarity, pulse3) ----------------
 * Two layers, so that an engine pays only for the memory it needs:
 *  - mc_ip_run_t: the runner proper (segments, delay line, trip check). It stores no intervals:
 *    each call hands the interval closed by the new sample back to the caller, which folds it
 *    into its result at once (Step II (5.6)-(5.7), DVI peaks, the (3.19) peak currents).
 *  - mc_ip_prog_t: the runner plus a store of up to MC_IP_REC_MAX intervals, for an engine that
 *    needs all of them at the end (the Step I search re-evaluates (5.5)/(7.1) on every interval
 *    for each candidate angle). 24 bytes per interval; the store is 1.5 kB of the 1.9 kB of
 *    mc_initpos_t, the largest engine. */

/* One measured interval [j-1, j] (its segment's tag is returned beside it, not stored). */
typedef struct {
    mc_ab_t i0, i1;   /* samples i(j-1), i(j) [A] */
    mc_ab_t ubar;     /* realised vector on [j-1, j] minus Rs (i0 + i1) / 2 [V] (5.1): the mean
                         current is the trapezoid rule of the resistive drop over the interval */
} mc_ip_rec_t;

/* One segment, 4 bytes: the vector of an arbitrary-direction segment is kept once in the
 * runner's vector table (a program uses few distinct vectors: +V and -V in Step II and DVI). */
typedef struct {
    int16_t len;      /* periods (for a gap: the minimum) */
    int8_t tag;       /* >= 0: record its intervals under this tag; < 0: not recorded */
    uint8_t kind;     /* internal: gap / direct V(pattern) / vector-table entry */
} mc_ip_seg_t;

typedef struct {
    /* configuration */
    float rs;         /* [ohm] */
    float i_rest;     /* [A] a gap ends when |i| <= i_rest */
    float i_trip;     /* [A] |i| above this fails the program (<= 0: no check) */
    int gap_max;      /* [periods] a gap ends anyway (decay_timeout set) */
    mc_ip_seg_t seg[MC_IP_SEG_MAX];
    mc_ab_t vec[MC_IP_VEC_MAX];  /* requested vectors [V] (mc_svpwm, hexagon-limited) */
    int n_seg, n_vec;
    /* run state */
    int n;            /* calls so far */
    int cur, pos;     /* segment being issued, periods issued from it */
    int open;         /* recorded intervals issued whose end sample has not arrived */
    mc_ab_t i_prev;   /* i(n-1) */
    mc_ab_t u_line[2];   /* at entry of call n: vector on [n-1, n] and on [n, n+1] */
    int8_t tag_line[2];
    bool decay_timeout;
    int n_rec;        /* recorded (tag >= 0) intervals closed so far */
    float i_peak;     /* largest |i_ab| sampled [A] */
} mc_ip_run_t;

void mc_ip_run_init(mc_ip_run_t *p, float rs, float i_rest, float i_trip, int gap_max);
/* Append a segment; false when the program (or, for a vector, the vector table) is full,
 * len < 1 or tag > MC_IP_TAG_MAX. */
bool mc_ip_run_direct(mc_ip_run_t *p, unsigned pattern, int len, int tag);
bool mc_ip_run_vector(mc_ip_run_t *p, mc_ab_t u, int len, int tag);
bool mc_ip_run_gap(mc_ip_run_t *p, int len_min);
/* One period (calling convention above). When sample i_ab closes a recorded interval, *rec
 * receives it and *tag its segment's tag (>= 0); otherwise *tag = -1 and *rec is untouched.
 * DONE once every segment has been issued and every recorded interval has its end sample; then
 * duty = V(000). FAILED: vdc <= 0, non-finite current, |i| > i_trip (nothing closed). */
mc_ip_status_t mc_ip_run_step(mc_ip_run_t *p, mc_ab_t i_ab, float vdc, mc_abc_t *duty,
                              mc_ip_rec_t *rec, int *tag);

/* Runner + interval store. */
typedef struct {
    mc_ip_run_t run;
    int n_rec;        /* intervals stored (every recorded one, up to MC_IP_REC_MAX) */
    bool overflow;    /* a recorded interval found the store full (and was dropped) */
    mc_ip_rec_t rec[MC_IP_REC_MAX];
} mc_ip_prog_t;

void mc_ip_prog_init(mc_ip_prog_t *p, float rs, float i_rest, float i_trip, int gap_max);
bool mc_ip_prog_direct(mc_ip_prog_t *p, unsigned pattern, int len, int tag);
bool mc_ip_prog_gap(mc_ip_prog_t *p, int len_min);
/* mc_ip_run_step, appending each recorded interval to rec[] (overflow when full). */
mc_ip_status_t mc_ip_prog_step(mc_ip_prog_t *p, mc_ab_t i_ab, float vdc, mc_abc_t *duty);
/* Duties and realised vector of a direct vector V(pattern) at vdc: phase voltage (d - 0.5) vdc,
 * Clarke (2.4). V(100) at 300 V gives u_alpha = 200 V. */
void mc_ip_direct(unsigned pattern, float vdc, mc_duty_t *out);

/* ---------------- Step I ---------------- */

typedef enum {
    MC_IP_COST_LINEAR = 0,  /* (5.5): La(theta) of (5.4) from cfg.ld, cfg.lq                     */
    MC_IP_COST_NONLINEAR,   /* (7.1): model Jacobian at T(theta) i(k+1) times T(theta) di         */
    MC_IP_COST_FLUXDIFF     /* addition: psi(T i(k+1)) - psi(T i(k)) through the model (exact
                               finite difference of the same map; no Jacobian-point choice)       */
} mc_ip_cost_t;

typedef struct {
    float ts, rs;            /* [s], [ohm] */
    float ld, lq;            /* [H] constant parameters of (5.4) for MC_IP_COST_LINEAR */
    mc_flux_model_t model;   /* for the nonlinear costs */
    mc_ip_cost_t cost;
    int m;                   /* periods per pulse, 1..MC_IP_M_MAX (thesis 5) */
    float v_pulse;           /* [V] 0: the direct vectors V(100), V(011) ... (2/3 Vdc, thesis);
                                > 0: vectors of this magnitude in the same directions (a motor
                                whose current one period of 2/3 Vdc would take past its limit) */
    int n_dir;               /* 1..3 pulse directions: phase A (V(100)/V(011)), then B, C */
    bool all_pulses;         /* false (thesis Fig 5.4 red dots): the first m intervals of each
                                direction; true: all 4m (needs n_dir * 4m <= MC_IP_REC_MAX) */
    int grid;                /* coarse grid points per pi, 4..MC_IP_GRID_MAX/2 (36) */
    float tol;               /* final golden-section bracket [rad] (0.1 deg / 2) */
    int evals_per_call;      /* cost evaluations per call after the pulses (ISR budget) */
    int gap_min, gap_max;    /* zero-vector gap between directions [periods] */
    float i_rest, i_trip;    /* [A], see mc_ip_prog_t */
} mc_initpos_cfg_t;

typedef struct {
    mc_initpos_cfg_t cfg;
    mc_ip_prog_t prog;       /* runner + the intervals the search evaluates */
    int phase;               /* internal: collect, grid, golden, done, failed */
    int k, gs_iter, gs_stage;
    float best_th, best_c, ga, gb, x1, x2, f1, f2;
    /* results */
    float theta1;            /* [0, pi): d-axis estimate modulo pi */
    float theta_full;        /* nonlinear costs: the refined minimum over [0, 2pi) (a weak
                                polarity hint, see 7.2.3); linear: = theta1 */
    float cost_min;          /* G at theta1 [V^2] */
    int evals;               /* cost evaluations used */
    int calls;               /* calls until DONE */
} mc_initpos_t;

/* Thesis defaults (m = 5, one direction, 36-point grid, 0.05 deg bracket, 12 evaluations per
 * call, gap 2..50 periods, i_rest 0.3 A); leaves ts, rs, ld, lq, model to the caller. */
void mc_initpos_cfg_default(mc_initpos_cfg_t *cfg);
/* false (and the engine then only returns FAILED) on an invalid configuration */
bool mc_initpos_start(mc_initpos_t *s, const mc_initpos_cfg_t *cfg);
mc_ip_status_t mc_initpos_step(mc_initpos_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty);
/* Cost of candidate theta on the recorded intervals (the function the search minimises). */
float mc_initpos_cost(const mc_initpos_t *s, float theta);

#endif
