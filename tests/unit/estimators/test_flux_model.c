#include "estim_test.h"

static mc_flux_map_t g_map;   /* 13 kB: static rather than on the test stack */

static void test_const_model(void **st)
{
    (void)st;
    mc_flux_model_t m = {MC_FLUX_CONST, 10.5e-3f, 12.9e-3f, 0.34305f, NULL};
    mc_dq_t i = {-3.0f, 7.0f}, psi;
    float L[4], dL[6];
    mc_flux_eval(&m, i, &psi, L, dL);
    assert_near(psi.d, 0.34305 - 3.0 * 10.5e-3, 1e-7);
    assert_near(psi.q, 7.0 * 12.9e-3, 1e-7);
    assert_near(L[0], 10.5e-3, 1e-9);
    assert_near(L[1], 0.0, 0.0);
    assert_near(L[2], 0.0, 0.0);
    assert_near(L[3], 12.9e-3, 1e-9);
    for (int k = 0; k < 6; ++k) {
        assert_near(dL[k], 0.0, 0.0);
    }
    /* NULL outputs allowed */
    mc_flux_eval(&m, i, &psi, NULL, NULL);
}

static void test_map_nodes_and_analytic_fit(void **st)
{
    (void)st;
    fill_sun_map(&g_map);
    mc_flux_model_t m = {MC_FLUX_MAP, 0, 0, 0, &g_map};
    /* at the nodes the interpolant is the table, and the table is the analytic model */
    double worst_node = 0.0;
    for (int a = 0; a < 41; a += 5) {
        for (int b = 0; b < 41; b += 5) {
            mc_dq_t i = {-20.0f + (float)a, -20.0f + (float)b}, psi;
            mc_flux_eval(&m, i, &psi, NULL, NULL);
            double ref[2];
            sun_psi_of_i(i.d, i.q, ref);
            worst_node = fmax(worst_node, fmax(fabs(psi.d - ref[0]), fabs(psi.q - ref[1])));
        }
    }
    mc_dq_t z = {0.0f, 0.0f}, psi0;
    float L0[4];
    mc_flux_eval(&m, z, &psi0, L0, NULL);
    /* interpolation error and differential inductances at cell centres, against the analytic model */
    double worst_psi = 0.0, worst_l = 0.0;
    for (double id = -19.5; id < 20.0; id += 1.0) {
        for (double iq = -19.5; iq < 20.0; iq += 1.0) {
            mc_dq_t i = {(float)id, (float)iq}, psi;
            float L[4];
            mc_flux_eval(&m, i, &psi, L, NULL);
            double ref[2], ii[2], j[4];
            sun_psi_of_i(id, iq, ref);
            sun_i_of_psi(ref[0], ref[1], ii, j);
            double det = j[0] * j[3] - j[1] * j[2];
            double la[4] = {j[3] / det, -j[1] / det, -j[2] / det, j[0] / det};
            worst_psi = fmax(worst_psi, fmax(fabs(psi.d - ref[0]), fabs(psi.q - ref[1])));
            for (int k = 0; k < 4; ++k) {
                worst_l = fmax(worst_l, fabs(L[k] - la[k]));
            }
        }
    }
    printf("flux map (sun2016 analytic fit, 41x41, 1 A): node error %.3g Wb, psi(0) = %.5f Wb, "
           "l_dd(0) = %.3f mH, l_qq(0) = %.3f mH; cell-centre error psi %.3g Wb, L %.3g mH\n",
           worst_node, psi0.d, 1e3 * L0[0], 1e3 * L0[3], worst_psi, 1e3 * worst_l);
    assert_true(worst_node < 1e-7);
    assert_near(psi0.d, SUN_PSI, 2e-4);
    /* (0, 0) is a node: the d-slope there is the forward difference of the first cell */
    assert_near(L0[0], SUN_LD, 0.6e-3);
    assert_near(L0[3], SUN_LQ, 0.6e-3);
    assert_true(worst_psi < 2e-3);
    assert_true(worst_l < 1.5e-3);
}

/* L and dL must be the exact derivatives of the interpolant (inside one cell it is bilinear,
 * so central differences of the float model with a step inside the cell are exact to rounding) */
static void test_map_derivatives_exact(void **st)
{
    (void)st;
    fill_sun_map(&g_map);
    mc_flux_model_t m = {MC_FLUX_MAP, 0, 0, 0, &g_map};
    uint64_t seed = 7;
    double worst_l = 0.0, worst_dl = 0.0;
    for (int n = 0; n < 500; ++n) {
        /* cell interiors, plus points beyond the grid edges (extrapolation) */
        double id = floor(urand(&seed, -24.0, 24.0)) + urand(&seed, 0.2, 0.8);
        double iq = floor(urand(&seed, -24.0, 24.0)) + urand(&seed, 0.2, 0.8);
        const double h = 0.05;
        mc_dq_t i = {(float)id, (float)iq}, p, pdp, pdm, pqp, pqm;
        float L[4], dL[6], Ldp[4], Ldm[4], Lqp[4], Lqm[4];
        mc_flux_eval(&m, i, &p, L, dL);
        mc_dq_t a = {(float)(id + h), (float)iq}, b = {(float)(id - h), (float)iq};
        mc_dq_t c = {(float)id, (float)(iq + h)}, d = {(float)id, (float)(iq - h)};
        mc_flux_eval(&m, a, &pdp, Ldp, NULL);
        mc_flux_eval(&m, b, &pdm, Ldm, NULL);
        mc_flux_eval(&m, c, &pqp, Lqp, NULL);
        mc_flux_eval(&m, d, &pqm, Lqm, NULL);
        double hd = (double)a.d - (double)b.d, hq = (double)c.q - (double)d.q;
        double fd[4] = {(pdp.d - pdm.d) / hd, (pqp.d - pqm.d) / hq, (pdp.q - pdm.q) / hd,
                        (pqp.q - pqm.q) / hq};
        for (int k = 0; k < 4; ++k) {
            worst_l = fmax(worst_l, fabs(L[k] - fd[k]));
        }
        /* second derivatives: d/diq of l_xd and d/did of l_xq equal the cross term, the pure
         * second derivatives vanish */
        double fdl[6] = {(Ldp[0] - Ldm[0]) / hd, (Lqp[0] - Lqm[0]) / hq, (Lqp[1] - Lqm[1]) / hq,
                         (Ldp[2] - Ldm[2]) / hd, (Lqp[2] - Lqm[2]) / hq, (Lqp[3] - Lqm[3]) / hq};
        for (int k = 0; k < 6; ++k) {
            worst_dl = fmax(worst_dl, fabs(dL[k] - fdl[k]));
        }
        assert_near(dL[1], (Ldp[1] - Ldm[1]) / hd, 1e-4);
    }
    printf("flux map derivatives vs finite differences of the interpolant: L %.3g H, dL %.3g H/A\n",
           worst_l, worst_dl);
    assert_true(worst_l < 2e-5);
    assert_true(worst_dl < 2e-4);
}

/* Non-square grids: did != diq, n_d != n_q, origins off zero. On a square grid a Jacobian that
 * divides by the other axis's step is still right, so every derivative of the interpolant is
 * compared here with central differences where the two steps differ by a large factor, at cell
 * interiors and at points just inside a cell edge (the difference step stays inside the cell,
 * where the interpolant is bilinear, so the differences are exact to rounding). */
static void fill_skew_map(mc_flux_map_t *m, int nd, int nq, float id0, float did, float iq0, float diq)
{
    memset(m, 0, sizeof *m);
    m->n_d = nd;
    m->n_q = nq;
    m->id0 = id0;
    m->did = did;
    m->iq0 = iq0;
    m->diq = diq;
    for (int a = 0; a < nd; ++a) {
        for (int b = 0; b < nq; ++b) {
            const double id = (double)id0 + a * (double)did, iq = (double)iq0 + b * (double)diq;
            /* saturating d axis, cross-saturation and a q slope unlike the d one: every
             * derivative differs from the others and from cell to cell */
            m->psi_d[a * nq + b] = (float)(0.3 + 0.012 * id - 2e-4 * id * id - 3e-4 * id * iq + 1e-3 * sin(0.7 * iq));
            m->psi_q[a * nq + b] = (float)(0.02 * iq - 1e-4 * iq * fabs(iq) - 4e-4 * id * iq + 2e-3 * cos(0.5 * id));
        }
    }
}

static void check_derivs_vs_fd(const mc_flux_map_t *mp, double id, double iq, double h_d, double h_q,
                               double *worst_l, double *worst_dl)
{
    const mc_flux_model_t m = {MC_FLUX_MAP, 0, 0, 0, mp};
    mc_dq_t i = {(float)id, (float)iq}, p, pdp, pdm, pqp, pqm;
    float L[4], dL[6], Ldp[4], Ldm[4];
    mc_flux_eval(&m, i, &p, L, dL);
    mc_dq_t a = {(float)(id + h_d), (float)iq}, b = {(float)(id - h_d), (float)iq};
    mc_dq_t c = {(float)id, (float)(iq + h_q)}, d = {(float)id, (float)(iq - h_q)};
    mc_flux_eval(&m, a, &pdp, Ldp, NULL);
    mc_flux_eval(&m, b, &pdm, Ldm, NULL);
    mc_flux_eval(&m, c, &pqp, NULL, NULL);
    mc_flux_eval(&m, d, &pqm, NULL, NULL);
    const double hd = (double)a.d - (double)b.d, hq = (double)c.q - (double)d.q;
    /* [dpsi_d/did, dpsi_d/diq, dpsi_q/did, dpsi_q/diq] */
    const double fd[4] = {(pdp.d - pdm.d) / hd, (pqp.d - pqm.d) / hq, (pdp.q - pdm.q) / hd,
                          (pqp.q - pqm.q) / hq};
    for (int k = 0; k < 4; ++k) {
        /* rounding of psi (~0.5 Wb in float) over the step, plus a relative part */
        const double tol = 4.0 * 6e-8 / (k % 2 == 0 ? hd : hq) + 1e-4 * fabs(fd[k]);
        if (fabs(L[k] - fd[k]) > tol) {
            fail_msg("L[%d] at (%.4f, %.4f) on %dx%d grid (did %.3g, diq %.3g): %.6g, finite differences %.6g",
                     k, id, iq, mp->n_d, mp->n_q, (double)mp->did, (double)mp->diq, (double)L[k], fd[k]);
        }
        *worst_l = fmax(*worst_l, fabs(L[k] - fd[k]));
    }
    /* the cross second derivative: d/did of l_xq (= dpsi_x/diq) */
    const double fdl[2] = {(Ldp[1] - Ldm[1]) / hd, (Ldp[3] - Ldm[3]) / hd};
    const double got[2] = {dL[1], dL[4]};
    for (int k = 0; k < 2; ++k) {
        const double tol = 8.0 * 6e-8 / (hd * hq) + 1e-3 * fabs(fdl[k]);
        if (fabs(got[k] - fdl[k]) > tol) {
            fail_msg("d2psi_%c/diddiq at (%.4f, %.4f): %.6g, finite differences %.6g", k == 0 ? 'd' : 'q', id, iq,
                     got[k], fdl[k]);
        }
        *worst_dl = fmax(*worst_dl, fabs(got[k] - fdl[k]));
    }
}

static void test_map_derivatives_non_square(void **st)
{
    (void)st;
    /* (n_d, n_q, id0, did, iq0, diq): steps apart by factors 3.2 to 12.5 either way */
    static const struct {
        int nd, nq;
        float id0, did, iq0, diq;
    } grids[] = {
        {9, 23, -37.0f, 5.0f, 3.5f, 0.4f},
        {31, 7, -12.25f, 0.8f, -41.0f, 10.0f},
        {2, 40, 1.5f, 3.2f, -18.0f, 1.0f},
        {17, 3, -6.0f, 0.75f, 0.0f, 9.375f},
    };
    uint64_t seed = 11;
    double worst_l = 0.0, worst_dl = 0.0;
    for (size_t g = 0; g < sizeof grids / sizeof grids[0]; ++g) {
        fill_skew_map(&g_map, grids[g].nd, grids[g].nq, grids[g].id0, grids[g].did, grids[g].iq0, grids[g].diq);
        const double did = g_map.did, diq = g_map.diq;
        for (int n = 0; n < 300; ++n) {
            /* a cell of the grid (its index along each axis), then a point in it: the interior,
             * or within 3 % of one of its four edges */
            const double cd = floor(urand(&seed, 0.0, g_map.n_d - 1.0));
            const double cq = floor(urand(&seed, 0.0, g_map.n_q - 1.0));
            double u = urand(&seed, 0.2, 0.8), v = urand(&seed, 0.2, 0.8);
            switch (n % 5) {
            case 1: u = urand(&seed, 0.01, 0.03); break;
            case 2: u = urand(&seed, 0.97, 0.99); break;
            case 3: v = urand(&seed, 0.01, 0.03); break;
            case 4: v = urand(&seed, 0.97, 0.99); break;
            default: break;
            }
            const double id = g_map.id0 + (cd + u) * did, iq = g_map.iq0 + (cq + v) * diq;
            /* steps that stay in the cell: half the distance to its nearer edge */
            const double hd = 0.5 * fmin(u, 1.0 - u) * did, hq = 0.5 * fmin(v, 1.0 - v) * diq;
            check_derivs_vs_fd(&g_map, id, iq, hd, hq, &worst_l, &worst_dl);
        }
        /* beyond the grid (extrapolation with the edge cells' slopes), below and above */
        check_derivs_vs_fd(&g_map, g_map.id0 - 0.7 * did, g_map.iq0 + 0.45 * diq, 0.1 * did, 0.1 * diq, &worst_l,
                           &worst_dl);
        check_derivs_vs_fd(&g_map, g_map.id0 + (g_map.n_d - 0.55) * did, g_map.iq0 + (g_map.n_q + 0.8) * diq,
                           0.1 * did, 0.1 * diq, &worst_l, &worst_dl);
    }
    printf("non-square flux maps: derivatives vs finite differences of the interpolant: L %.3g H, dL %.3g H/A\n",
           worst_l, worst_dl);
}

/* outside the grid: continuous at the edge, and linear along the axis leaving the grid */
static void test_map_extrapolation(void **st)
{
    (void)st;
    fill_sun_map(&g_map);
    mc_flux_model_t m = {MC_FLUX_MAP, 0, 0, 0, &g_map};
    mc_dq_t e = {20.0f, 3.3f}, o1 = {25.0f, 3.3f}, o2 = {30.0f, 3.3f}, pe, p1, p2;
    float Le[4], L1[4];
    mc_flux_eval(&m, e, &pe, Le, NULL);
    mc_flux_eval(&m, o1, &p1, L1, NULL);
    mc_flux_eval(&m, o2, &p2, NULL, NULL);
    assert_near(p1.d - pe.d, p2.d - p1.d, 1e-6);   /* linear beyond the edge */
    assert_near(p1.d - pe.d, 5.0 * Le[0], 1e-6);   /* with the edge cell's slope */
    assert_near(L1[0], Le[0], 1e-9);
    mc_dq_t lo = {-40.0f, -40.0f}, corner = {-20.0f, -20.0f}, pl, pc;
    float Lc[4];
    mc_flux_eval(&m, lo, &pl, NULL, NULL);
    mc_flux_eval(&m, corner, &pc, Lc, NULL);
    /* bilinear of the corner cell: psi(c + (-20,-20)) = psi(c) - 20 l_dd - 20 l_dq + 400 d2 */
    float dLc[6];
    mc_flux_eval(&m, corner, &pc, Lc, dLc);
    assert_near(pl.d, pc.d - 20.0 * Lc[0] - 20.0 * Lc[1] + 400.0 * dLc[1], 1e-5);
    /* NaN input propagates instead of indexing out of the table */
    mc_dq_t nan_i = {NAN, 0.0f}, pn;
    mc_flux_eval(&m, nan_i, &pn, NULL, NULL);
    assert_true(pn.d != pn.d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_const_model),
        cmocka_unit_test(test_map_nodes_and_analytic_fit),
        cmocka_unit_test(test_map_derivatives_exact),
        cmocka_unit_test(test_map_derivatives_non_square),
        cmocka_unit_test(test_map_extrapolation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
