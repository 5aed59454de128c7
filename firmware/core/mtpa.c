/* MTPA (2.22)-(2.24), current limit (2.21), voltage limit (2.20) and field weakening (2.26)
 * for the constant-parameter model; plus an |I|-indexed MTPA table. */
#include "mc/mtpa.h"

#include <float.h>
#include <math.h>

float mc_mtpa_id(const mc_lin_params_t *p, float iq)
{
    /* (2.24) rationalised: (psi - sqrt(psi^2 + 4 dL^2 iq^2)) / (2 dL)
     *                    = -2 dL iq^2 / (psi + sqrt(psi^2 + 4 dL^2 iq^2)).
     * The second form has no cancellation at small iq and no 0/0 when Lq == Ld (SPM: id = 0). */
    float dl = p->lq - p->ld;
    float iq2 = iq * iq;
    float den = p->psi_pm + sqrtf(p->psi_pm * p->psi_pm + 4.0f * dl * dl * iq2);
    if (!(den > 0.0f)) {
        return 0.0f;
    }
    return -2.0f * dl * iq2 / den;
}

float mc_torque_pp(const mc_lin_params_t *p, mc_dq_t i)
{
    /* (2.8) divided by the pole-pair count */
    return 1.5f * (p->psi_pm * i.q + (p->ld - p->lq) * i.d * i.q);
}

/* MTPA point on the circle |I| = i_mag: root cos(theta_s) of (2.23), then (2.22). */
static mc_dq_t mtpa_point(const mc_lin_params_t *p, float i_mag)
{
    float dl = p->lq - p->ld;
    /* c = (-psi + sqrt(psi^2 + 8 dL^2 I^2)) / (4 dL I), rationalised to avoid 0/0 at I = 0 */
    float den = p->psi_pm + sqrtf(p->psi_pm * p->psi_pm + 8.0f * dl * dl * i_mag * i_mag);
    float c = (den > 0.0f) ? 2.0f * dl * i_mag / den : 0.0f;
    if (c > 1.0f) {
        c = 1.0f;
    } else if (c < -1.0f) {
        c = -1.0f;
    }
    mc_dq_t i;
    i.d = -i_mag * c;                       /* (2.22) */
    i.q = i_mag * sqrtf(1.0f - c * c);
    return i;
}

void mc_mtpa_table_fill_linear(mc_mtpa_table_t *t, const mc_lin_params_t *p, float i_max)
{
    t->i_max = i_max;
    for (int k = 0; k < MC_MTPA_TABLE_N; ++k) {
        mc_dq_t i = mtpa_point(p, i_max * (float)k / (float)(MC_MTPA_TABLE_N - 1));
        t->id[k] = i.d;
        t->iq[k] = i.q;
    }
}

mc_dq_t mc_mtpa_table_lookup(const mc_mtpa_table_t *t, float i_mag)
{
    mc_dq_t out = {0.0f, 0.0f};
    if (!(t->i_max > 0.0f) || !(i_mag > 0.0f)) {
        return out;
    }
    if (i_mag > t->i_max) {
        i_mag = t->i_max;   /* beyond the table the current limit applies anyway */
    }
    float x = i_mag * (float)(MC_MTPA_TABLE_N - 1) / t->i_max;
    int k = (int)x;
    if (k > MC_MTPA_TABLE_N - 2) {
        k = MC_MTPA_TABLE_N - 2;
    }
    float f = x - (float)k;
    out.d = t->id[k] + f * (t->id[k + 1] - t->id[k]);
    out.q = t->iq[k] + f * (t->iq[k + 1] - t->iq[k]);
    return out;
}

/* Keep the first component (up to the radius), shorten the second onto the circle. */
static mc_dq_t limit_circle_d_priority(mc_dq_t x, float r)
{
    if (!(r > 0.0f)) {
        mc_dq_t z = {0.0f, 0.0f};
        return z;
    }
    float r2 = r * r;
    if (x.d * x.d + x.q * x.q <= r2) {
        return x;
    }
    if (fabsf(x.d) >= r) {
        x.d = copysignf(r, x.d);
        x.q = 0.0f;
        return x;
    }
    x.q = copysignf(sqrtf(r2 - x.d * x.d), x.q);
    return x;
}

mc_dq_t mc_limit_current_circle(mc_dq_t i, float i_max)
{
    /* (2.21); d priority keeps the field-weakening current that holds the voltage in bounds */
    return limit_circle_d_priority(i, i_max);
}

mc_dq_t mc_limit_voltage_circle(mc_dq_t u, float u_max)
{
    return limit_circle_d_priority(u, u_max);
}

float mc_fw_id_max(const mc_lin_params_t *p, float iq, float omega_e, float u_max)
{
    float w = fabsf(omega_e);
    if (!(w > 1e-6f) || !(p->ld > 0.0f)) {
        return FLT_MAX;   /* at standstill the ellipse (2.20) is unbounded */
    }
    float flux = u_max / w;
    float rad = flux * flux - p->lq * p->lq * iq * iq;
    if (rad < 0.0f) {
        /* no id satisfies (2.20) with this iq: the ellipse centre is the closest one can get;
         * the caller has to reduce iq */
        return -p->psi_pm / p->ld;
    }
    return (-p->psi_pm + sqrtf(rad)) / p->ld;   /* (2.26) */
}
