/* SVPWM by min-max zero-sequence injection, and the sector method (2.10)-(2.13) it reproduces. */
#include "mc/svpwm.h"

#include <math.h>
#include <stddef.h>

#include "mc/angle.h"
#include "mc/transforms.h"

/* Requests this close to the hexagon (relative) count as inside: a vector exactly on the
 * inscribed circle must not be flagged as saturated because of float rounding. */
#define SAT_TOL 1.0e-6f

/* The active vectors U1..U6, the hexagon's corners (Table 2.1 / Figure 2.6): which legs are high,
 * and the stator-frame unit vector (2.4) of each. */
static const mc_abc_t active_duty[6] = {{1.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 0.0f},
                                        {0.0f, 1.0f, 1.0f}, {0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 1.0f}};
static const mc_ab_t active_dir[6] = {{1.0f, 0.0f},  {0.5f, 0.8660254f},   {-0.5f, 0.8660254f},
                                      {-1.0f, 0.0f}, {-0.5f, -0.8660254f}, {0.5f, -0.8660254f}};

/* plain compares: fmaxf/fminf are library calls on the Cortex-M4 */
static float maxf(float a, float b)
{
    return (a > b) ? a : b;
}

static float minf(float a, float b)
{
    return (a < b) ? a : b;
}

static float clamp01(float x)
{
    return (x < 0.0f) ? 0.0f : ((x > 1.0f) ? 1.0f : x);
}

/* Duties -> realised vector: phase voltage vs DC midpoint is (d - 0.5) vdc, then (2.4); the
 * common mode of the three legs drops out of Clarke. */
static void finish(mc_duty_t *out, float vdc)
{
    mc_abc_t v;
    out->a = clamp01(out->a);
    out->b = clamp01(out->b);
    out->c = clamp01(out->c);
    v.a = (out->a - 0.5f) * vdc;
    v.b = (out->b - 0.5f) * vdc;
    v.c = (out->c - 0.5f) * vdc;
    out->u_real = mc_clarke(v);
}

static bool bad_vdc(float vdc, mc_duty_t *out)
{
    if (vdc > 0.0f) {
        return false;
    }
    out->a = out->b = out->c = 0.5f;
    out->u_real.alpha = 0.0f;
    out->u_real.beta = 0.0f;
    out->saturated = true;
    return true;
}

void mc_svpwm(mc_ab_t u, float vdc, mc_duty_t *out)
{
    if (bad_vdc(vdc, out)) {
        return;
    }
    mc_abc_t v = mc_clarke_inv(u);
    float vmax = maxf(v.a, maxf(v.b, v.c));
    float vmin = minf(v.a, minf(v.b, v.c));
    float span = vmax - vmin;   /* largest line-to-line voltage; the hexagon is span <= vdc */
    float scale = 1.0f;
    out->saturated = false;
    if (span > vdc * (1.0f + SAT_TOL)) {
        /* scaling all phases by one factor keeps the direction: no phase error */
        scale = vdc / span;
        out->saturated = true;
    }
    /* zero sequence centring max and min in the DC link: same as equal U0/U7 times (2.11) */
    float v0 = -0.5f * (vmax + vmin);
    float k = scale / vdc;
    out->a = 0.5f + (v.a + v0) * k;
    out->b = 0.5f + (v.b + v0) * k;
    out->c = 0.5f + (v.c + v0) * k;
    finish(out, vdc);
}

float mc_svpwm_reach(mc_ab_t dir, float vdc)
{
    const mc_abc_t v = mc_clarke_inv(dir);
    const float span = maxf(v.a, maxf(v.b, v.c)) - minf(v.a, minf(v.b, v.c));
    /* a unit vector's span is 1.5 (a corner) .. sqrt(3) (a side's middle): anything else (not a
     * unit vector, NaN) gets the inscribed circle */
    return (span > 1.45f && span < 1.78f) ? vdc / span : vdc * MC_1_SQRT3;
}

int mc_svpwm_corner_near(float angle)
{
    const float k = floorf(mc_wrap_pi(angle) * (3.0f / MC_PI) + 0.5f);   /* 60 deg steps */
    const int n = (int)k;
    return ((n % 6) + 6) % 6;
}

mc_abc_t mc_svpwm_corner(int k, mc_ab_t *dir)
{
    k = ((k % 6) + 6) % 6;
    if (dir != NULL) {
        *dir = active_dir[k];
    }
    return active_duty[k];
}

void mc_svpwm_sector(mc_ab_t u, float vdc, mc_duty_t *out)
{
    if (bad_vdc(vdc, out)) {
        return;
    }
    float mag = sqrtf(u.alpha * u.alpha + u.beta * u.beta);
    float gamma = atan2f(u.beta, u.alpha);              /* (2.13) */
    if (gamma < 0.0f) {
        gamma += MC_2PI;
    }
    int n = (int)(gamma / (MC_PI / 3.0f));
    if (n > 5) {
        n = 5;
    } else if (n < 0) {
        n = 0;
    }
    float g = gamma - (float)n * (MC_PI / 3.0f);
    /* (2.13) boundary vectors, (2.10) with |U1| = 2 vdc / 3; times relative to Tc/2 */
    float tr = (2.0f / MC_SQRT3) * mag * sinf(MC_PI / 3.0f - g) / (2.0f * vdc / 3.0f);
    float tl = (2.0f / MC_SQRT3) * mag * sinf(g) / (2.0f * vdc / 3.0f);
    out->saturated = false;
    if (tr + tl > 1.0f + SAT_TOL) {
        /* no time left for zero vectors: shorten both, keeping their ratio (the angle) */
        float s = 1.0f / (tr + tl);
        tr *= s;
        tl *= s;
        out->saturated = true;
    }
    float t0 = 1.0f - tr - tl;                           /* (2.11) */
    if (t0 < 0.0f) {
        t0 = 0.0f;
    }
    const mc_abc_t r = active_duty[n];
    const mc_abc_t l = active_duty[(n + 1) % 6];
    /* (2.12) with T0 split equally between U0 and U7 */
    out->a = 0.5f * t0 + tr * r.a + tl * l.a;
    out->b = 0.5f * t0 + tr * r.b + tl * l.b;
    out->c = 0.5f * t0 + tr * r.c + tl * l.c;
    finish(out, vdc);
}
