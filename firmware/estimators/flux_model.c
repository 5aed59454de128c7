/* Flux-linkage model psi_dq(i_dq): constant parameters or a bilinear flux map (see flux_model.h). */
#include "mc/flux_model.h"

#include <stddef.h>
#include <stdint.h>

/* Cell index for a grid coordinate t (in cells from the first point): the edge cells are reused
 * outside the grid, which is the documented linear extrapolation. A truncating conversion instead
 * of floorf (a library call on the M4) is enough because negative t is clamped first; NaN lands
 * in cell 0 and propagates through the fraction. */
static int32_t cell_of(float t, int32_t n)
{
    int32_t last = n - 2;
    if (!(t > 0.0f)) {
        return 0;
    }
    if (t >= (float)last) {
        return last;
    }
    return (int32_t)t;
}

static void eval_map(const mc_flux_map_t *mp, mc_dq_t i, mc_dq_t *psi, float L[4], float dL[6])
{
    int32_t nq = (int32_t)mp->n_q;
    float td = (i.d - mp->id0) / mp->did;
    float tq = (i.q - mp->iq0) / mp->diq;
    int32_t jd = cell_of(td, (int32_t)mp->n_d);
    int32_t jq = cell_of(tq, nq);
    float u = td - (float)jd;
    float v = tq - (float)jq;
    int32_t k00 = jd * nq + jq;
    int32_t k10 = k00 + nq;
    const float *tab[2] = {mp->psi_d, mp->psi_q};
    float out[2];
    for (int32_t a = 0; a < 2; ++a) {
        float f00 = tab[a][k00], f01 = tab[a][k00 + 1];
        float f10 = tab[a][k10], f11 = tab[a][k10 + 1];
        /* bilinear written as f00 + u*A + v*B + u*v*C: the same coefficients give the exact
         * derivatives of the interpolant */
        float ca = f10 - f00;
        float cb = f01 - f00;
        float cc = (f11 - f10) - (f01 - f00);
        out[a] = f00 + u * ca + v * cb + (u * v) * cc;
        if (L != NULL) {
            L[2 * a] = (ca + v * cc) / mp->did;
            L[2 * a + 1] = (cb + u * cc) / mp->diq;
        }
        if (dL != NULL) {
            dL[3 * a] = 0.0f;
            dL[3 * a + 1] = cc / (mp->did * mp->diq);
            dL[3 * a + 2] = 0.0f;
        }
    }
    psi->d = out[0];
    psi->q = out[1];
}

void mc_flux_eval(const mc_flux_model_t *m, mc_dq_t i, mc_dq_t *psi, float L[4], float dL[6])
{
    if (m->kind == MC_FLUX_MAP && m->map != NULL) {
        eval_map(m->map, i, psi, L, dL);
        return;
    }
    /* constant parameters, the model of (5.1) */
    psi->d = m->ld * i.d + m->psi_pm;
    psi->q = m->lq * i.q;
    if (L != NULL) {
        L[0] = m->ld;
        L[1] = 0.0f;
        L[2] = 0.0f;
        L[3] = m->lq;
    }
    if (dL != NULL) {
        for (int k = 0; k < 6; ++k) {
            dL[k] = 0.0f;
        }
    }
}

float mc_flux_swing_d(const mc_flux_model_t *m, float i_lim)
{
    mc_dq_t p0, pd, nd;
    mc_flux_eval(m, (mc_dq_t){0.0f, 0.0f}, &p0, NULL, NULL);
    mc_flux_eval(m, (mc_dq_t){i_lim, 0.0f}, &pd, NULL, NULL);
    mc_flux_eval(m, (mc_dq_t){-i_lim, 0.0f}, &nd, NULL, NULL);
    const float up = pd.d - p0.d, dn = p0.d - nd.d;
    return up < dn ? up : dn;
}
