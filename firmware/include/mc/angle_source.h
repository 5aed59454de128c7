/* The angle-source seam. Every rotor-angle provider (the encoder, UNOP; EEMF, PSVI, blend and the
 * KIT identifier next) takes the same per-period inputs and returns an angle and a speed, with
 * its own speed filter or PLL inside. Each source is one file that defines its state and a
 * descriptor; the drive keeps one union of source states (mc_angle_src_state_t, sized by
 * MC_ANGLE_SRC_STATE_MAX) and calls the selected descriptor at the same point of the ISR.
 *
 * Adding a source: one file with `const mc_angle_src_desc_t mc_angle_src_NAME` (its state must
 * fit MC_ANGLE_SRC_STATE_MAX: check with MC_ANGLE_SRC_FITS), plus one line X(NAME) in
 * MC_ANGLE_SOURCES below. The line also adds NAME to the choices of control.angle_source. A test
 * build adds its own through MC_ANGLE_SOURCES_EXTRA (tests/unit/app/test_angle_source_extra.c, target app_angle_registry). */
#ifndef MC_ANGLE_SOURCE_H
#define MC_ANGLE_SOURCE_H
#include "mc/types.h"
#include "mc/flux_model.h"

/* What the drive hands to an angle source every period k. */
typedef struct {
    mc_ab_t i_ab;          /* i_ab(k), measured at the start of period k [A]                  */
    mc_ab_t i_ab_prev;     /* i_ab(k-1) [A]                                                    */
    mc_ab_t u_ab_applied;  /* voltage actually applied during [k-1, k] (commanded two ISRs ago,
                              limited by the modulator, dead-time compensated) [V]             */
    float   vdc;           /* [V]                                                              */
    uint32_t qep_count;    /* encoder counter (for the encoder source)                          */
} mc_angle_in_t;

typedef struct {
    float theta;           /* electrical angle at sample k, [-pi, pi) [rad], filtered          */
    float omega;           /* electrical speed [rad/s], filtered                               */
} mc_angle_out_t;

/* What a source reports beside its output (telemetry, loss-of-lock checks later). */
typedef struct {
    float theta_raw, omega_raw;   /* before the source's filter / PLL [rad, rad/s el]          */
    int   iters;                  /* solver iterations this period (0: none)                  */
    float cost, cond;             /* final cost, conditioning (0: none)                       */
} mc_angle_diag_t;

/* Everything a source may need to configure itself, in SI: built by the drive from its
 * parameters in the background, never in the ISR. A source reads the parts it needs. */
typedef struct {
    float ts;                     /* [s]                                                      */
    int   pole_pairs;
    /* encoder */
    uint32_t enc_counts_per_rev;
    float enc_offset_rad, enc_pll_bw_hz, enc_speed_fc_hz;
    /* model-based estimators: the estimator's machine model and solver */
    float rs;                     /* [ohm]                                                    */
    mc_flux_model_t model;
    int   iter_max;
    float step_tol, k1, k2, omega_n1, omega_base;
    bool  mid_sample, reg_predicted;
    /* the PLL filter after a raw estimator (Fig. 6.9) */
    float pll_bw_hz, pll_speed_fc_hz;
} mc_angle_src_cfg_t;

#define MC_ANGLE_SRC_STATE_MAX 200   /* bytes: the largest source state (UNOP + PLL: ~150) */

typedef union {
    unsigned char bytes[MC_ANGLE_SRC_STATE_MAX];
    float align_f;
    uint32_t align_u;
    void *align_p;
} mc_angle_src_state_t;

#define MC_ANGLE_SRC_FITS(type) _Static_assert(sizeof(type) <= MC_ANGLE_SRC_STATE_MAX, #type " too large")

typedef struct mc_angle_src_desc {
    const char *name;
    bool needs_injection;         /* the drive injects the HF voltage (6.4) while it runs     */
    bool measures_angle;          /* an angle sensor: no initial-position search, no catch    */
    void (*init)(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *cfg);
    /* estimate set to (theta, omega), filters primed: at enable and after the initial position */
    void (*reset)(mc_angle_src_state_t *s, float theta, float omega);
    void (*step)(mc_angle_src_state_t *s, const mc_angle_in_t *in, mc_angle_out_t *out);
    void (*diag)(const mc_angle_src_state_t *s, mc_angle_diag_t *d);
} mc_angle_src_desc_t;

/* ---- the registry: one line per source (order = value of control.angle_source) ---- */
#ifndef MC_ANGLE_SOURCES_EXTRA
#define MC_ANGLE_SOURCES_EXTRA(X)
#endif
#define MC_ANGLE_SOURCES(X) \
    X(encoder)              \
    X(unop)                 \
    MC_ANGLE_SOURCES_EXTRA(X)

typedef enum {
#define MC_X(name) MC_ANGLE_SRC_##name,
    MC_ANGLE_SOURCES(MC_X)
#undef MC_X
    MC_ANGLE_SRC_COUNT
} mc_angle_src_kind_t;


#define MC_X2(name) extern const mc_angle_src_desc_t mc_angle_src_##name;
MC_ANGLE_SOURCES(MC_X2)
#undef MC_X2

/* The descriptor of a kind, or NULL. */
const mc_angle_src_desc_t *mc_angle_src_get(int kind);

#endif
