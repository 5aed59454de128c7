/* Magnetic polarity (Step II of thesis chapter 5) in the estimated d axis theta1 from Step I:
 *  - generalized polarity detection (5.3, (5.6)-(5.7)): train +V n, -V 2n, +V n periods in the
 *    delta axis; every interval gives L_delta^diff(j) (5.6), compared with the model profile
 *    l_dd(+i_delta, 0) (c1) and l_dd(-i_delta, 0) (c2); c1 > c2 means delta points to the south
 *    pole and theta2 = theta1 + pi;
 *  - dual voltage injection, DVI (3.5.2, Fig 3.8): +V for n periods (reset by -V n), gap, -V for
 *    n periods (reset by +V n); the pulse with the larger peak |i_delta| points north.
 * The pulse vector is V in the delta direction, limited by the hexagon (mc_svpwm scales it onto
 * the boundary: the largest magnitude <= V available in that direction, e.g. 176.8 V at 41.5 deg
 * for 300 V); the realised vector is what enters ubar. Calling convention: mc/initpos.h.
 *
 * Confidence (an addition to (5.7), with z_min > 0): the measured L(j) is fitted by least
 * squares as a E(j) + b O(j), E and O the even and odd parts of the model's profile,
 * (l_dd(+i) +- l_dd(-i)) / 2. b = +1 is the profile as assumed (delta points north), b = -1 the
 * mirrored one (flip). The even part absorbs what both hypotheses share: a scale error of the
 * model's inductance, the larger inductance seen off the d axis when Step I is a few degrees
 * off. The decision is the sign of b, its confidence z = |b| / se(b) (a t statistic). A
 * symmetric profile (O = 0), a noisy measurement or a profile the machine does not show give a
 * small z. Below z_min further trains follow, with longer pulses where the limit allows (more
 * current, where the saturation asymmetry is larger; the model's flux keeps the peak below
 * 0.9 i_max), until the MC_IP_REC_MAX stored intervals are used; still below: FAILED with
 * verdict UNDECIDED, never a guess. */
#ifndef MC_POLARITY_H
#define MC_POLARITY_H
#include "mc/initpos.h"

#define MC_POL_N_MAX 16   /* upper bound of the pulse length n [periods]; 4n <= MC_IP_REC_MAX */

typedef enum {
    MC_POL_PENDING = 0,  /* running */
    MC_POL_DECIDED,      /* theta2 valid, z >= z_min */
    MC_POL_UNDECIDED,    /* z < z_min after the strongest train the current limit allows */
    MC_POL_NO_DATA,      /* fewer than 2 usable intervals (no current change) */
    MC_POL_ABORTED       /* the pulse program failed: |i| > i_trip, vdc <= 0, non-finite current */
} mc_pol_verdict_t;

typedef struct {
    float ts, rs;            /* [s], [ohm] */
    mc_flux_model_t model;   /* the profile l_dd(i_d, 0) = dpsi_d/di_d at i_q = 0 */
    float v_pol;             /* [V] requested pulse magnitude (200) */
    int n;                   /* periods per half pulse (thesis 4) */
    bool l_at_end;           /* true: l_dd at i_delta(j), literally (5.7); false (default): at
                                the interval's mean current, where the chord slope (5.6) of a
                                smooth psi(i) is closest to the derivative */
    float i_rest, i_trip;    /* [A], see mc_ip_prog_t (no gap in this program: i_rest unused) */
    float z_min;             /* confidence a decision needs (<= 0: c1 vs c2 alone, the thesis) */
    float i_max;             /* [A] a retry's longer pulses aim at 0.9 x this peak (<= 0: no retry) */
} mc_polarity_cfg_t;

typedef struct {
    mc_polarity_cfg_t cfg;
    mc_ip_run_t prog;        /* runner only: each interval is folded into (5.7) as it closes */
    mc_sincos_t dir;         /* of theta1 */
    int state;               /* internal */
    /* results */
    float theta1;            /* input [rad] */
    float theta2;            /* [-pi, pi) */
    float c1, c2;            /* (5.7) [H^2] */
    float asym;              /* fitted share b of the model's odd profile (above; z_min > 0) */
    float z;                 /* confidence |b| / se(b) (above), >= 0 */
    mc_pol_verdict_t verdict;
    int tries, n_now;        /* trains run (1, more after retries); half-pulse length of the last */
    bool flip;               /* c1 > c2: pi added */
    int n_valid;             /* intervals used in (5.7) */
    float v_real;            /* realised |V| of the first pulse [V] */
    float i_peak;            /* largest |i_ab| sampled over all trains [A] */
    float i_delta[MC_IP_REC_MAX], l_diff[MC_IP_REC_MAX];  /* (i_delta(j), L_delta^diff(j)) */
    float l_even[MC_IP_REC_MAX], l_odd[MC_IP_REC_MAX];    /* the model's E(j), O(j) [H] */
    int calls;
} mc_polarity_t;

/* thesis defaults: v_pol 200 V, n 4, l at the mean current, i_rest 0.3 A, no confidence check
 * (z_min 0, no retry); ts, rs, model unset */
void mc_polarity_cfg_default(mc_polarity_cfg_t *cfg);
bool mc_polarity_start(mc_polarity_t *s, const mc_polarity_cfg_t *cfg, float theta1);
mc_ip_status_t mc_polarity_step(mc_polarity_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty);

/* ---- DVI reference ----
 * With z_min > 0 (an addition): each pulse's current change from its start is compared (the
 * gap leaves up to i_rest, which would bias the peaks themselves), and the program is repeated
 * (at most reps_max times) until the mean difference is z_min standard errors away from zero (the
 * noise's, and 1 % of the change for the sequence's own asymmetry);
 * still not: FAILED, verdict UNDECIDED. */
typedef struct {
    float rs;
    float v;                 /* [V] requested pulse magnitude (200) */
    int n;                   /* periods per pulse (thesis 7.2.2: 6) */
    int gap_min, gap_max;
    float i_rest, i_trip;
    float z_min;             /* confidence a decision needs (<= 0: the larger peak alone, 3.5.2) */
    int reps_max;            /* programs run at most while not confident (1..MC_DVI_REPS_MAX) */
} mc_dvi_cfg_t;

#define MC_DVI_REPS_MAX 8

typedef struct {
    mc_dvi_cfg_t cfg;
    mc_ip_run_t prog;        /* runner only: the peaks are tracked as the intervals close */
    mc_sincos_t dir;
    int state;
    float theta1, theta2;    /* theta2 in [-pi, pi) */
    float peak_pos, peak_neg;/* peak |i_delta| of the +V and -V pulses [A] (the last program) */
    bool flip;               /* peak_neg > peak_pos (with the check: in the mean over programs) */
    int calls;
    /* confidence (z_min > 0): the peaks' mean difference over the programs run against the
     * current noise, estimated from the second differences of the current within each pulse
     * (var = 6 sigma^2 for white noise; a saturation's curvature only adds to it) */
    float chg_pos, chg_neg;  /* largest |i_delta - i_delta at the pulse's start| of each pulse
                                (the gap ends at |i| <= i_rest, not at 0: the residual would
                                bias the peaks themselves) [A] */
    float i_start;           /* i_delta at the start of the pulse being measured [A] */
    float sum_pos, sum_neg;  /* sums of chg_pos, chg_neg over the programs [A] */
    float s_d2;              /* sum of squared second differences [A^2] */
    int n_d2, reps;
    float di_prev;           /* last interval's current change in the pulse being measured */
    int tag_prev;            /* its tag (-1: none yet in this program) */
    float z;                 /* |mean difference| / its standard error */
    mc_pol_verdict_t verdict;
} mc_dvi_t;

void mc_dvi_cfg_default(mc_dvi_cfg_t *cfg);
bool mc_dvi_start(mc_dvi_t *s, const mc_dvi_cfg_t *cfg, float theta1);
mc_ip_status_t mc_dvi_step(mc_dvi_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty);

#endif
