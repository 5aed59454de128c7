/* Q15 / Q31 variants of sin/cos, Clarke (2.4), Park (2.5), SVPWM and PI. Integer-only: floats
 * appear only in the from_f / to_f converters. Right shifts of negative values are arithmetic
 * (true for GCC and Clang, relied upon throughout). */
#include "mc/fixed.h"

#define Q15_ONE 32768
#define Q31_ONE 2147483648LL

static mc_q15_t sat16(int64_t x)
{
    return (mc_q15_t)((x > INT16_MAX) ? INT16_MAX : ((x < INT16_MIN) ? INT16_MIN : x));
}

static mc_q31_t sat32(int64_t x)
{
    return (mc_q31_t)((x > INT32_MAX) ? INT32_MAX : ((x < INT32_MIN) ? INT32_MIN : x));
}

/* Rounding arithmetic right shift (n >= 1); a left shift for n < 0 (caller bounds the range). */
static int64_t rshr(int64_t x, int n)
{
    if (n <= 0) {
        return x * ((int64_t)1 << (-n));
    }
    return (x + ((int64_t)1 << (n - 1))) >> n;
}

/* Saturating left shift by n (right shift with rounding for n < 0). */
static int64_t shl_sat(int64_t x, int n)
{
    if (n <= 0) {
        return rshr(x, -n);
    }
    if (n > 62) {
        n = 62;
    }
    int64_t lim = INT64_MAX >> n;
    if (x > lim) {
        return INT64_MAX;
    }
    if (x < -lim) {
        return -INT64_MAX;
    }
    return x * ((int64_t)1 << n);
}

/* ---------------------------------------------------------------- converters */

mc_q15_t mc_q15_from_f(float x)
{
    float y = x * 32768.0f;
    if (!(y == y)) {
        return 0;
    }
    if (y >= 32767.0f) {
        return INT16_MAX;
    }
    if (y <= -32768.0f) {
        return INT16_MIN;
    }
    return (mc_q15_t)(y + ((y >= 0.0f) ? 0.5f : -0.5f));
}

float mc_q15_to_f(mc_q15_t x)
{
    return (float)x * (1.0f / 32768.0f);
}

mc_q31_t mc_q31_from_f(float x)
{
    float y = x * 2147483648.0f;
    if (!(y == y)) {
        return 0;
    }
    if (y >= 2147483648.0f) {
        return INT32_MAX;
    }
    if (y <= -2147483648.0f) {
        return INT32_MIN;
    }
    return (mc_q31_t)(y + ((y >= 0.0f) ? 0.5f : -0.5f));
}

float mc_q31_to_f(mc_q31_t x)
{
    return (float)x * (1.0f / 2147483648.0f);
}

/* ---------------------------------------------------------------- sin / cos */

/* Fits on t in [-0.5, 0.5] (t = quarter turns), coefficients in Q32:
 * sin(pi/2 t) = t (S1 + S3 t^2 + ... + S9 t^8), cos(pi/2 t) = C0 + C2 t^2 + ... + C10 t^10.
 * Truncation error < 4e-12, far below one Q31 LSB (4.7e-10); Q32 intermediates keep the
 * rounding of the Horner steps at about half an LSB. */
static const int64_t sin_c[5] = {6746518852LL, -2774394658LL, 342276909LL, -20105214LL, 678304LL};
static const int64_t cos_c[6] = {4294967296LL, -5298703519LL, 1089502337LL, -89609009LL,
                                 3952715LL, -114566LL};

mc_sincos_q31_t mc_sincos_q31(mc_q31_t theta_pu)
{
    /* one turn = 2^32: the nearest quadrant is the top two bits after adding half a quadrant */
    uint32_t u = (uint32_t)theta_pu;
    uint32_t quad = ((u + 0x20000000u) >> 30) & 3u;
    int32_t x = (int32_t)(u - (quad << 30));      /* [-2^29, 2^29): [-pi/4, pi/4) */
    int64_t t = (int64_t)x * 2;                   /* quarter turns in Q31, |t| <= 0.5 */
    int64_t z = rshr(t * t, 31);                  /* t^2, Q31 */

    int64_t sa = sin_c[4];
    for (int k = 3; k >= 0; --k) {
        sa = sin_c[k] + rshr(sa * z, 31);
    }
    int64_t ca = cos_c[5];
    for (int k = 4; k >= 0; --k) {
        ca = cos_c[k] + rshr(ca * z, 31);
    }
    int64_t sp = rshr(sa * t, 32);                /* Q32 * Q31 -> Q31 */
    int64_t cp = rshr(ca, 1);                     /* Q32 -> Q31 */

    int64_t s;
    int64_t c;
    switch (quad) {
    case 0u: s = sp;  c = cp;  break;
    case 1u: s = cp;  c = -sp; break;
    case 2u: s = -sp; c = -cp; break;
    default: s = -cp; c = sp;  break;
    }
    mc_sincos_q31_t out = {sat32(s), sat32(c)};
    return out;
}

mc_sincos_q15_t mc_sincos_q15(mc_q15_t theta_pu)
{
    /* reuse the Q31 kernel: the angle widens exactly, the result rounds once */
    mc_sincos_q31_t w = mc_sincos_q31((mc_q31_t)((uint32_t)(uint16_t)theta_pu << 16));
    mc_sincos_q15_t out = {sat16(rshr(w.s, 16)), sat16(rshr(w.c, 16))};
    return out;
}

/* ---------------------------------------------------------------- Clarke / Park */

#define Q20_ONE_THIRD   349525LL         /* 1/3 * 2^20: Q16 would cost half an LSB */
#define Q20_1_SQRT3     605396LL         /* 1/sqrt(3) * 2^20           */
#define Q31_ONE_THIRD   715827883LL      /* 1/3 * 2^31                 */
#define Q31_1_SQRT3     1239850262LL     /* 1/sqrt(3) * 2^31           */
#define Q31_SQRT3_2     1859775393LL     /* sqrt(3)/2 * 2^31           */
#define Q15_SQRT3_2     28378            /* sqrt(3)/2 * 2^15           */

mc_ab_q15_t mc_clarke_q15(mc_abc_q15_t x)
{
    /* (2.4): alpha = (2a - b - c)/3, beta = (b - c)/sqrt(3); unbalanced input may overflow */
    int64_t s = 2 * (int64_t)x.a - x.b - x.c;
    int64_t d = (int64_t)x.b - x.c;
    mc_ab_q15_t y = {sat16(rshr(s * Q20_ONE_THIRD, 20)), sat16(rshr(d * Q20_1_SQRT3, 20))};
    return y;
}

mc_ab_q31_t mc_clarke_q31(mc_abc_q31_t x)
{
    int64_t s = 2 * (int64_t)x.a - x.b - x.c;      /* < 2^33, times < 2^30: fits */
    int64_t d = (int64_t)x.b - x.c;                /* < 2^32, times < 2^31: fits */
    mc_ab_q31_t y = {sat32(rshr(s * Q31_ONE_THIRD, 31)), sat32(rshr(d * Q31_1_SQRT3, 31))};
    return y;
}

mc_dq_q15_t mc_park_q15(mc_ab_q15_t x, mc_sincos_q15_t sc)
{
    /* (2.5) */
    int64_t d = (int64_t)sc.c * x.alpha + (int64_t)sc.s * x.beta;
    int64_t q = -(int64_t)sc.s * x.alpha + (int64_t)sc.c * x.beta;
    mc_dq_q15_t y = {sat16(rshr(d, 15)), sat16(rshr(q, 15))};
    return y;
}

/* a*b + c*d for Q31 operands without int64 overflow (each product halved first), -> Q31 */
static mc_q31_t dot2_q31(int32_t a, int32_t b, int32_t c, int32_t d)
{
    int64_t p = ((int64_t)a * b) >> 1;
    int64_t r = ((int64_t)c * d) >> 1;
    return sat32(rshr(p + r, 30));
}

mc_dq_q31_t mc_park_q31(mc_ab_q31_t x, mc_sincos_q31_t sc)
{
    /* -s would overflow for s = -1.0; negate the other factor's product instead */
    mc_dq_q31_t y;
    y.d = dot2_q31(sc.c, x.alpha, sc.s, x.beta);
    y.q = sat32(rshr((((int64_t)sc.c * x.beta) >> 1) - (((int64_t)sc.s * x.alpha) >> 1), 30));
    return y;
}

mc_ab_q15_t mc_park_inv_q15(mc_dq_q15_t x, mc_sincos_q15_t sc)
{
    int64_t a = (int64_t)sc.c * x.d - (int64_t)sc.s * x.q;
    int64_t b = (int64_t)sc.s * x.d + (int64_t)sc.c * x.q;
    mc_ab_q15_t y = {sat16(rshr(a, 15)), sat16(rshr(b, 15))};
    return y;
}

mc_ab_q31_t mc_park_inv_q31(mc_dq_q31_t x, mc_sincos_q31_t sc)
{
    mc_ab_q31_t y;
    y.alpha = sat32(rshr((((int64_t)sc.c * x.d) >> 1) - (((int64_t)sc.s * x.q) >> 1), 30));
    y.beta = dot2_q31(sc.s, x.d, sc.c, x.q);
    return y;
}

/* ---------------------------------------------------------------- SVPWM */

/* w * 2^qbits / span, rounded, for |w| <= span < 2^34: a two-step long division, because
 * w * 2^31 alone could overflow int64 (no 128-bit type on the target). */
static int64_t scale_to_one(int64_t w, int64_t span, int qbits)
{
    int64_t a = (w < 0) ? -w : w;
    int64_t n1 = a * ((int64_t)1 << (qbits - 2));
    int64_t q1 = n1 / span;
    int64_t n2 = (n1 - q1 * span) * 4;
    int64_t q2 = (n2 + span / 2) / span;
    int64_t r = q1 * 4 + q2;
    return (w < 0) ? -r : r;
}

/* Min-max injection in per-unit of vdc with `one` = 1.0; phase voltages in int64 so requests
 * up to the full Q range cannot overflow. Writes duties in [0, one) before saturation. */
static bool svpwm_core(int64_t alpha, int64_t beta, int64_t sqrt3_2, int qbits, int64_t one,
                       int64_t d[3])
{
    int64_t h = rshr(beta * sqrt3_2, qbits);
    int64_t v[3] = {alpha, -(alpha >> 1) + h, -(alpha >> 1) - h};
    int64_t vmax = v[0];
    int64_t vmin = v[0];
    for (int k = 1; k < 3; ++k) {
        vmax = (v[k] > vmax) ? v[k] : vmax;
        vmin = (v[k] < vmin) ? v[k] : vmin;
    }
    int64_t span = vmax - vmin;              /* hexagon: largest line-line voltage <= vdc */
    int64_t sum = vmax + vmin;
    bool sat = span > one;
    for (int k = 0; k < 3; ++k) {
        int64_t w = 2 * v[k] - sum;          /* 2 (v + v0), v0 = -(vmax + vmin)/2 */
        if (sat) {
            w = scale_to_one(w, span, qbits);   /* onto the boundary, same direction */
        }
        d[k] = (one >> 1) + rshr(w, 1);
    }
    return sat;
}

void mc_svpwm_q15(mc_ab_q15_t u_pu, mc_duty_q15_t *out)
{
    int64_t d[3];
    out->saturated = svpwm_core(u_pu.alpha, u_pu.beta, Q15_SQRT3_2, 15, Q15_ONE, d);
    out->a = sat16(d[0]);
    out->b = sat16(d[1]);
    out->c = sat16(d[2]);
    out->a = (out->a < 0) ? 0 : out->a;
    out->b = (out->b < 0) ? 0 : out->b;
    out->c = (out->c < 0) ? 0 : out->c;
}

void mc_svpwm_q31(mc_ab_q31_t u_pu, mc_duty_q31_t *out)
{
    int64_t d[3];
    out->saturated = svpwm_core(u_pu.alpha, u_pu.beta, Q31_SQRT3_2, 31, Q31_ONE, d);
    out->a = sat32(d[0]);
    out->b = sat32(d[1]);
    out->c = sat32(d[2]);
    out->a = (out->a < 0) ? 0 : out->a;
    out->b = (out->b < 0) ? 0 : out->b;
    out->c = (out->c < 0) ? 0 : out->c;
}

/* ---------------------------------------------------------------- PI */

/* Same anti-windup as the float mc_pi (conditional integration up to the limit + clamp), on
 * int64 values in one common Q format; returns the clamped output. */
static int64_t pi_core(int64_t *integ, int64_t p, int64_t inc, int64_t err_sign, int64_t lo,
                       int64_t hi)
{
    int64_t i_new = *integ + inc;
    int64_t u = p + i_new;
    if (u > hi && err_sign > 0) {
        int64_t room = hi - p;
        i_new = (i_new < room) ? i_new : room;
        i_new = (i_new > *integ) ? i_new : *integ;
    } else if (u < lo && err_sign < 0) {
        int64_t room = lo - p;
        i_new = (i_new > room) ? i_new : room;
        i_new = (i_new < *integ) ? i_new : *integ;
    }
    i_new = (i_new > hi) ? hi : ((i_new < lo) ? lo : i_new);
    *integ = i_new;
    u = p + i_new;
    return (u > hi) ? hi : ((u < lo) ? lo : u);
}

void mc_pi_q15_init(mc_pi_q15_t *s, const mc_pi_q15_cfg_t *cfg)
{
    s->cfg = *cfg;
    s->integ = 0;
}

mc_q15_t mc_pi_q15_step(mc_pi_q15_t *s, mc_q15_t err)
{
    /* work in Q31 of the output: kp*err is Q30, so one more bit plus the gain shift */
    int sh = 1 + s->cfg.shift;
    int64_t p = shl_sat((int64_t)s->cfg.kp * err, sh);
    int64_t inc = shl_sat((int64_t)s->cfg.ki_ts * err, sh);
    int64_t lo = (int64_t)s->cfg.out_min * 65536;
    int64_t hi = (int64_t)s->cfg.out_max * 65536;
    if (lo > hi) {
        lo = hi = (lo + hi) / 2;
    }
    /* keep p + integ inside int64 as the Q31 version does: a shift of 33 or more saturates the
     * products at +-INT64_MAX, whose sum with the other term would wrap and invert the output */
    const int64_t pmax = (int64_t)1 << 61;
    p = (p > pmax) ? pmax : ((p < -pmax) ? -pmax : p);
    inc = (inc > pmax) ? pmax : ((inc < -pmax) ? -pmax : inc);
    int64_t integ = s->integ;
    int64_t u = pi_core(&integ, p, inc, err, lo, hi);
    s->integ = (int32_t)integ;     /* clamped to [out_min, out_max] << 16: fits */
    return sat16(rshr(u, 16));
}

void mc_pi_q31_init(mc_pi_q31_t *s, const mc_pi_q31_cfg_t *cfg)
{
    s->cfg = *cfg;
    s->integ = 0;
}

mc_q31_t mc_pi_q31_step(mc_pi_q31_t *s, mc_q31_t err)
{
    /* work in Q47 of the output (16 guard bits so small ki_ts*err still integrates):
     * kp*err is Q62 -> Q47 is a right shift by 15, then the gain shift */
    int sh = s->cfg.shift - 15;
    int64_t p = shl_sat((int64_t)s->cfg.kp * err, sh);
    int64_t inc = shl_sat((int64_t)s->cfg.ki_ts * err, sh);
    int64_t lo = (int64_t)s->cfg.out_min * 65536;
    int64_t hi = (int64_t)s->cfg.out_max * 65536;
    if (lo > hi) {
        lo = hi = (lo + hi) / 2;
    }
    /* keep p + integ inside int64: both are bounded to well below 2^62 here */
    const int64_t pmax = (int64_t)1 << 61;
    p = (p > pmax) ? pmax : ((p < -pmax) ? -pmax : p);
    inc = (inc > pmax) ? pmax : ((inc < -pmax) ? -pmax : inc);
    int64_t u = pi_core(&s->integ, p, inc, err, lo, hi);
    return sat32(rshr(u, 16));
}
