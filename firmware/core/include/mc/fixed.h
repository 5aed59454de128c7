/* Q15 / Q31 fixed-point variants of the inner math. Q15: int16, 1.0 == 32768 (saturating);
 * Q31: int32, 1.0 == 2^31. Angles in fixed point are per-unit of pi: -1.0 == -pi, so one full
 * turn wraps naturally in two's complement. Quantities are per-unit of a caller-chosen base.
 * Where they are used: nowhere in the shipped images (both targets have an FPU and run the float32
 * path); they are the inner math for a port without one, tested against the float32 functions in
 * tests/unit/core/test_fixed.c (docs/core.md gives the error bounds). To use them, convert at the
 * ADC and PWM boundaries and keep the estimator in float32 or port it with them. */
#ifndef MC_FIXED_H
#define MC_FIXED_H
#include <stdint.h>
#include "mc/types.h"

typedef int16_t mc_q15_t;
typedef int32_t mc_q31_t;

typedef struct { mc_q15_t a, b, c; } mc_abc_q15_t;
typedef struct { mc_q15_t alpha, beta; } mc_ab_q15_t;
typedef struct { mc_q15_t d, q; } mc_dq_q15_t;
typedef struct { mc_q15_t s, c; } mc_sincos_q15_t;
typedef struct { mc_q31_t a, b, c; } mc_abc_q31_t;
typedef struct { mc_q31_t alpha, beta; } mc_ab_q31_t;
typedef struct { mc_q31_t d, q; } mc_dq_q31_t;
typedef struct { mc_q31_t s, c; } mc_sincos_q31_t;

mc_q15_t mc_q15_from_f(float x);      /* saturating */
float    mc_q15_to_f(mc_q15_t x);
mc_q31_t mc_q31_from_f(float x);
float    mc_q31_to_f(mc_q31_t x);

mc_sincos_q15_t mc_sincos_q15(mc_q15_t theta_pu);   /* theta in per-unit of pi */
mc_sincos_q31_t mc_sincos_q31(mc_q31_t theta_pu);

mc_ab_q15_t  mc_clarke_q15(mc_abc_q15_t x);
mc_ab_q31_t  mc_clarke_q31(mc_abc_q31_t x);
mc_dq_q15_t  mc_park_q15(mc_ab_q15_t x, mc_sincos_q15_t sc);
mc_dq_q31_t  mc_park_q31(mc_ab_q31_t x, mc_sincos_q31_t sc);
mc_ab_q15_t  mc_park_inv_q15(mc_dq_q15_t x, mc_sincos_q15_t sc);
mc_ab_q31_t  mc_park_inv_q31(mc_dq_q31_t x, mc_sincos_q31_t sc);

/* SVPWM: u in per-unit of vdc (so the linear limit is 1/sqrt(3)); duties in Q15/Q31 [0, 1). */
typedef struct { mc_q15_t a, b, c; bool saturated; } mc_duty_q15_t;
typedef struct { mc_q31_t a, b, c; bool saturated; } mc_duty_q31_t;
void mc_svpwm_q15(mc_ab_q15_t u_pu, mc_duty_q15_t *out);
void mc_svpwm_q31(mc_ab_q31_t u_pu, mc_duty_q31_t *out);

/* PI in fixed point: gains as Q15/Q31 with a power-of-two shift, kp_eff = kp * 2^shift. */
typedef struct { mc_q15_t kp, ki_ts; int16_t shift; mc_q15_t out_min, out_max; } mc_pi_q15_cfg_t;
typedef struct { mc_pi_q15_cfg_t cfg; int32_t integ; } mc_pi_q15_t;   /* integ in Q31 of output */
void     mc_pi_q15_init(mc_pi_q15_t *s, const mc_pi_q15_cfg_t *cfg);
mc_q15_t mc_pi_q15_step(mc_pi_q15_t *s, mc_q15_t err);
typedef struct { mc_q31_t kp, ki_ts; int16_t shift; mc_q31_t out_min, out_max; } mc_pi_q31_cfg_t;
typedef struct { mc_pi_q31_cfg_t cfg; int64_t integ; } mc_pi_q31_t;   /* integ in Q47 of output */
void     mc_pi_q31_init(mc_pi_q31_t *s, const mc_pi_q31_cfg_t *cfg);
mc_q31_t mc_pi_q31_step(mc_pi_q31_t *s, mc_q31_t err);

#endif
