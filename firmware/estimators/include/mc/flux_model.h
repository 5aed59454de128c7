/* The machine "residual model" shared by the model-based estimators (UNOP, initial position, the
 * flux-map identifier): flux linkage psi_dq(i_dq) with its Jacobian (differential inductances)
 * and second derivatives. Two implementations behind one call:
 *   MC_FLUX_CONST: psi_d = ld i_d + psi_pm, psi_q = lq i_q   (the thesis model of (5.1), (6.1))
 *   MC_FLUX_MAP:   bilinear interpolation of a regular-grid flux map psi_dq(i_d, i_q).
 * Peak-value space vectors in the rotor frame, SI units. */
#ifndef MC_FLUX_MODEL_H
#define MC_FLUX_MODEL_H
#include "mc/types.h"

#define MC_FLUX_MAP_MAX 41   /* grid points per axis (at most) */

typedef enum { MC_FLUX_CONST = 0, MC_FLUX_MAP } mc_flux_kind_t;

/* Regular grid: i_d = id0 + jd * did (jd = 0..n_d-1), i_q = iq0 + jq * diq (jq = 0..n_q-1).
 * Storage row-major with d slowest: psi_x[jd * n_q + jq]. Needs 2 <= n_d, n_q <= MC_FLUX_MAP_MAX
 * and did, diq > 0.
 * Evaluation: bilinear in the cell holding i. The Jacobian is the exact derivative of that
 * bilinear interpolant (piecewise: it jumps across cell edges), and so are the second
 * derivatives: inside a cell only d2psi/(did diq) is nonzero.
 * Outside the grid the edge cell is used and its bilinear polynomial is evaluated beyond the
 * edge (linear extrapolation along each axis, with that cell's slopes). */
typedef struct {
    int   n_d, n_q;
    float id0, did;          /* [A] */
    float iq0, diq;          /* [A] */
    float psi_d[MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX];   /* [Wb] */
    float psi_q[MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX];   /* [Wb] */
} mc_flux_map_t;

typedef struct {
    mc_flux_kind_t kind;
    float ld, lq, psi_pm;    /* MC_FLUX_CONST [H, H, Wb] */
    const mc_flux_map_t *map;/* MC_FLUX_MAP (NULL: evaluated as MC_FLUX_CONST) */
} mc_flux_model_t;

/* psi = psi_dq(i). L (may be NULL): dpsi/di row-major [l_dd, l_dq; l_qd, l_qq].
 * dL (may be NULL): second derivatives [d2psi_d/did2, d2psi_d/diddiq, d2psi_d/diq2,
 *                                        d2psi_q/did2, d2psi_q/diddiq, d2psi_q/diq2]. */
void mc_flux_eval(const mc_flux_model_t *m, mc_dq_t i, mc_dq_t *psi, float L[4], float dL[6]);

/* The d-axis flux swing [Wb] from i = 0 that takes i_d to +i_lim or to -i_lim, the smaller of the
 * two (a pulse program along d sized by the model's saturation, not by l_dd at 0). */
float mc_flux_swing_d(const mc_flux_model_t *m, float i_lim);

/* The same model: kind, constants and the same map (by address: the map is data, not copied). */
static inline bool mc_flux_model_same(const mc_flux_model_t *a, const mc_flux_model_t *b)
{
    return a->kind == b->kind && a->ld == b->ld && a->lq == b->lq && a->psi_pm == b->psi_pm && a->map == b->map;
}

#endif
