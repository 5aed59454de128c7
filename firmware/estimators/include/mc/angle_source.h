/* The angle-source seam. Every rotor-angle provider (the encoder, UNOP; EEMF, PSVI, blend and the
 * KIT identifier next) takes the same per-period inputs and returns an angle and a speed, with
 * its own speed filter or PLL inside. Each source is one file that defines its configuration, its
 * state and a descriptor (what it is, what it needs, and its life cycle: build from the
 * parameters, init, retune while running, reset, step); the drive keeps one union of
 * configurations and one of states and calls the selected descriptor at the same point of the ISR.
 * The drive's checks follow the descriptor: the HF injection (needs_injection), the loss-of-lock
 * detectors (lock_checks), the flux-map requirement (map_models), the catch, the initial-position
 * search and the recovery (cls: estimators only).
 *
 * Adding a source: its file(s) with `const mc_angle_src_desc_t mc_angle_src_NAME` (configuration
 * and state checked with MC_ANGLE_SRC_CFG_FITS and MC_ANGLE_SRC_FITS), one line X(NAME) in
 * MC_ANGLE_SOURCES below (it also adds NAME to the choices of control.angle_source), and the rows
 * of its parameters in mc/params_table.h. A test build adds its own through
 * MC_ANGLE_SOURCES_EXTRA (tests/unit/app/src_test_hold.c, targets app_angle_registry and
 * app_runtime_params_extra). */
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

/* What a source reports beside its output (telemetry; the loss-of-lock checks compare the raw
 * estimate with the output where the source has lock_checks). */
typedef struct {
    float theta_raw, omega_raw;   /* before the source's filter / PLL [rad, rad/s el]          */
    int   iters;                  /* solver iterations this period (0: none)                  */
    float cost, cond;             /* final cost, conditioning (0: none)                       */
} mc_angle_diag_t;

/* A source's own configuration, built in the background from the parameters (its descriptor's
 * build) and held by the drive in one union sized by MC_ANGLE_SRC_CFG_MAX; the source's file
 * defines the type inside it (check with MC_ANGLE_SRC_CFG_FITS). */
#define MC_ANGLE_SRC_CFG_MAX 104   /* bytes: the largest source configuration (UNOP + PLL: 104) */

typedef union {
    unsigned char bytes[MC_ANGLE_SRC_CFG_MAX];
    float align_f;
    uint32_t align_u;
    void *align_p;
} mc_angle_src_cfg_t;

#define MC_ANGLE_SRC_CFG_FITS(type) _Static_assert(sizeof(type) <= MC_ANGLE_SRC_CFG_MAX, #type " too large")

#define MC_ANGLE_SRC_STATE_MAX 200   /* bytes: the largest source state (UNOP + PLL: 196 on a 64-bit host) */

typedef union {
    unsigned char bytes[MC_ANGLE_SRC_STATE_MAX];
    float align_f;
    uint32_t align_u;
    void *align_p;
} mc_angle_src_state_t;

#define MC_ANGLE_SRC_FITS(type) _Static_assert(sizeof(type) <= MC_ANGLE_SRC_STATE_MAX, #type " too large")

/* The selected source as the drive built it: the machine model it was handed (the estimator's
 * model as given, mc_est_model_t in mc/drive.h, in the form estimator.model chooses; the drive's
 * current-loop decoupling and field-weakening entry use the same one) and its own configuration. */
typedef struct {
    float rs;                     /* [ohm]                                                    */
    mc_flux_model_t model;
    mc_angle_src_cfg_t cfg;       /* the source's own type inside (its build)                 */
} mc_angle_src_built_t;

/* What a source is; the drive's checks follow it, never the source's name. */
typedef enum {
    MC_ANGLE_SENSOR = 0,          /* measures the angle (encoder): no initial-position search, no
                                     catch, no recovery, tracked while the offsets are calibrated */
    MC_ANGLE_ESTIMATOR            /* estimates it from the machine's currents and voltages     */
} mc_angle_src_class_t;

/* The parameters and the error report of a build (mc/params.h; declared here because the table
 * includes this header for the registry below). */
typedef struct mc_params mc_params_t;
typedef struct mc_param_err mc_param_err_t;

typedef struct mc_angle_src_desc {
    const char *name;
    mc_angle_src_class_t cls;
    /* capabilities */
    bool needs_injection;         /* the drive injects the HF voltage (6.4) while it runs
                                     (with injection.kind other than off)                      */
    bool lock_checks;             /* its raw estimate (diag) beside the filtered output is worth
                                     checking: the loss-of-lock detectors run (protection.lock_*) */
    uint8_t map_models;           /* bit m set: needs the estimator's flux map while
                                     estimator.model = m (refused at build without one)        */
    /* life cycle. Background (never in the ISR): */
    /* its configuration from the parameters and the machine model; false: err says why (the
     * drive refuses the whole configuration) */
    bool (*build)(const mc_params_t *p, float rs, const mc_flux_model_t *model, mc_angle_src_cfg_t *cfg,
                  mc_param_err_t *err);
    /* ISR side, copies only: */
    void (*init)(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *cfg);
    /* while running: a new configuration in which only RUNTIME parameters (mc/params_table.h)
     * changed; takes the ones it reads at run time, keeps its estimate. NULL: it reads none. It
     * gets them built (by build, in the background), not the parameters: it runs in the ISR at
     * the configuration swap (mc_drive_retune). tests/unit/app/test_runtime_params.c checks
     * every RUNTIME parameter against a fresh build. */
    void (*retune)(mc_angle_src_state_t *s, const mc_angle_src_cfg_t *cfg);
    /* estimate set to (theta, omega), filters primed: at enable and after the initial position */
    void (*reset)(mc_angle_src_state_t *s, float theta, float omega);
    void (*step)(mc_angle_src_state_t *s, const mc_angle_in_t *in, mc_angle_out_t *out);
    void (*diag)(const mc_angle_src_state_t *s, mc_angle_diag_t *d);
    /* the configuration it runs with now, and a field-by-field comparison of two (tests, checks) */
    void (*cfg_of)(const mc_angle_src_state_t *s, mc_angle_src_cfg_t *out);
    bool (*cfg_equal)(const mc_angle_src_cfg_t *a, const mc_angle_src_cfg_t *b);
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
