/* UNOP: unified nonlinear-optimisation speed and position estimator (thesis chapter 6).
 * Per control period it minimises the voltage-equation residual of the interval [k-1, k] over the
 * decision variables theta(k-1), omega (6.4), with the regularisation (6.5) at low speed, by the
 * modified Newton method with line search (6.7). The residual goes through the shared flux model
 * (mc/flux_model.h), so the constant-parameter (6.1)-(6.3) and flux-map machines use one code.
 * Decision variables are scaled, x = [theta, omega / omega_base], and the residual cost is
 * normalised by u_norm^2, so float32 sees a Hessian of order one. See docs/unop.md. */
#ifndef MC_UNOP_H
#define MC_UNOP_H
#include "mc/angle_source.h"
#include "mc/flux_model.h"

#define MC_UNOP_ITER_MAX 18   /* upper bound of cfg.iter_max (bounded loop) */
#define MC_UNOP_LS_MAX   6    /* line-search halvings: xi = 1, 1/2, ..., 1/64 (6.7) */
#define MC_UNOP_LS_LO    0.5f /* bounds of the adapted inductance scale */
#define MC_UNOP_LS_HI    2.0f

typedef struct {
    float ts;            /* sample time [s] */
    float rs;            /* [ohm] */
    mc_flux_model_t model;
    int   iter_max;      /* Newton iterations per period, 1..MC_UNOP_ITER_MAX (clamped) */
    float step_tol;      /* early exit when the scaled Newton step |d| is below this */
    float k1, k2;        /* regularisation weights (6.5) on the normalised cost; k2 acts on the
                            scaled speed; active while |omega_hat| <= omega_n1 */
    float omega_n1;      /* [rad/s electrical] N1 of (6.6) converted */
    float omega_base;    /* speed scaling: x = [theta, omega/omega_base]; <= 0 means 1 */
    bool  mid_sample;    /* true (default): resistive drop with (i0+i1)/2, voltage and rotational
                            terms at the mid-sample angle theta + omega Ts/2 with the mean flux of
                            both frames; false: thesis form (5.1)/(6.1) at theta(k-1), Rs i0 */
    bool  reg_predicted; /* true (default): K1 pulls toward theta_hat(k-1) + omega_hat Ts;
                            false: literal (6.5), toward theta_hat(k-1) */
    /* additions to the agreed API: */
    float u_norm;        /* [V] Gr = |r|^2 / u_norm^2; <= 0 means 1 V */
    float step_max;      /* cap on the scaled Newton step norm (keeps a bad Hessian from jumping
                            to the other minimum at (180 deg, -2 omega)); <= 0: no cap */
    bool  zoh_gain;      /* mid form only: voltage term times 1 + x^2/6, x = omega Ts/2: the
                            second-order correction for a voltage held in alpha-beta (held-voltage
                            mean and trapezoid flux together, steady state; default true); removes
                            a -(omega Ts)^2/24 relative speed bias */
    float l_adapt;       /* inductance-scale adaptation: forgetting rate per period of its least
                            squares (see mc_unop_adapt); 0: off, the model as given */
    float l_adapt_p;     /* [V^2] floor of the regressor power in that normalisation; the
                            injection's (amplitude 2 sqrt(l_adapt_p)) sets the prior's weight */
    float bp_a1, bp_a2;  /* denominator of the band-pass at the injection frequency the residual
                            and the regressor go through (mc_unop_cfg_band) */
} mc_unop_cfg_t;

typedef struct {
    mc_unop_cfg_t cfg;
    float theta, omega;  /* estimate at the START of the last interval: theta(k-1) [-pi, pi), omega */
    /* diagnostics of the last step */
    int   iters;         /* Newton iterations used (0..iter_max) */
    float cost;          /* Gl at the returned estimate (normalised) */
    float cond;          /* lambda_min / lambda_max of the Hessian used in the last iteration
                            (after modification) */
    bool  modified;      /* some iteration had to modify the Hessian (not positive definite) */
    bool  ls_failed;     /* a line search found no Armijo decrease (the iteration stopped there) */
    /* the model's inductive part as used: psi = psi0 + l_scale (psi_model(i) - psi0) */
    float l_scale;       /* adapted by mc_unop_adapt in [MC_UNOP_LS_LO, MC_UNOP_LS_HI]; 1 at init */
    mc_dq_t psi0;        /* psi_model(0): the magnet part, kept as given */
    float bp_z[2][2];    /* band-pass states (transposed direct form II) of r_d and phi_d */
    float ls_pow;        /* regressor power of the inductance scale's least squares (forgotten at
                            cfg.l_adapt per period) */
} mc_unop_t;

/* Algorithmic defaults (mid_sample, reg_predicted, iteration limits, scalings); leaves ts, rs,
 * model, k1, k2, omega_n1 at zero for the caller. */
void mc_unop_cfg_default(mc_unop_cfg_t *cfg);
void mc_unop_init(mc_unop_t *s, const mc_unop_cfg_t *cfg);
/* A new configuration while running (weights, N1, limits): the estimate and diagnostics stay. */
void mc_unop_retune(mc_unop_t *s, const mc_unop_cfg_t *cfg);
/* theta/omega at the current sample: the next step starts its search from them. */
void mc_unop_reset(mc_unop_t *s, float theta, float omega);
/* One estimation per control period. in: i_ab(k-1) = in->i_ab_prev, i_ab(k) = in->i_ab, voltage
 * applied during [k-1, k] = in->u_ab_applied. The decision variables are theta(k-1), omega;
 * out->theta = wrap(theta(k-1) + omega Ts) is the angle at sample k, out->omega the speed. */
void mc_unop_step(mc_unop_t *s, const mc_angle_in_t *in, mc_angle_out_t *out);
/* Inductance-scale adaptation (an extension of (6.4)): at a smooth estimate of the same interval
 * (theta = theta(k-1), omega; the PLL's, not the per-period solution, which absorbs the error),
 * the residual of a model whose inductive part is off by a factor holds (s_true - l_scale) times
 * dpsi/Ts of the model; one least-squares step moves l_scale toward s_true. Only while
 * |omega| <= omega_n1, where the HF injection excites dpsi/Ts along the estimated d axis. */
void mc_unop_adapt(mc_unop_t *s, const mc_angle_in_t *in, float theta, float omega);
/* The adaptation's band-pass (Q = 2, unity gain at f_hz) into cfg->bp_a1, bp_a2; needs cfg->ts. */
void mc_unop_cfg_band(mc_unop_cfg_t *cfg, float f_hz);

/* Gl (normalised) of candidate (theta, omega) = theta(k-1), omega on the interval of `in`, with
 * regularisation targets theta_ref, omega_ref and weights w1, w2 (6.5). grad, hess (may be NULL):
 * analytic, in the scaled variables x = [theta, omega/omega_base]; hess row-major 2x2. */
float mc_unop_cost(const mc_unop_t *s, const mc_angle_in_t *in, float theta, float omega,
                   float theta_ref, float omega_ref, float w1, float w2, float grad[2],
                   float hess[4]);
/* The residual r_dq [V] of the candidate, in the rotor frame (the norm is frame independent). In
 * the thesis form Park^-1(r_dq, theta) is the alpha-beta residual of (6.1). */
mc_dq_t mc_unop_residual(const mc_unop_t *s, const mc_angle_in_t *in, float theta, float omega);

#endif
