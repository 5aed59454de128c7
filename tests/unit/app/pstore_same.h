/* Shared by the parameter-store tests: a loaded configuration compared bit for bit with the
 * saved one. */
#ifndef PSTORE_SAME_H
#define PSTORE_SAME_H

#include <stdbool.h>
#include <string.h>
#include "mc/bits.h"
#include "mc/param_store.h"

static inline bool same_bits(float a, float b)
{
    return mc_f32_bits(a) == mc_f32_bits(b);
}

/* got (loaded, its map in got_map) is exactly want; dropped: want stored without its map */
static inline bool same_cfg_in(const mc_drive_cfg_t *got, const mc_drive_cfg_t *want, bool dropped,
                               const mc_flux_map_t *got_map)
{
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (mc_param_is_auto(&got->p, id) != mc_param_is_auto(&want->p, id) ||
            !same_bits(mc_param_get(&got->p, id), mc_param_get(&want->p, id))) {
            return false;
        }
    }
    if (!same_bits(got->est.rs, want->est.rs) || !same_bits(got->est.ld, want->est.ld) ||
        !same_bits(got->est.lq, want->est.lq) || !same_bits(got->est.psi_pm, want->est.psi_pm)) {
        return false;
    }
    const mc_flux_map_t *w = dropped ? NULL : want->est.map;
    if (w == NULL) {
        return got->est.map == NULL;
    }
    const mc_flux_map_t *g = got->est.map;
    if (g != got_map || g->n_d != w->n_d || g->n_q != w->n_q || !same_bits(g->id0, w->id0) ||
        !same_bits(g->did, w->did) || !same_bits(g->iq0, w->iq0) || !same_bits(g->diq, w->diq)) {
        return false;
    }
    const size_t cells = (size_t)w->n_d * (size_t)w->n_q;
    return memcmp(g->psi_d, w->psi_d, cells * sizeof(float)) == 0 &&
           memcmp(g->psi_q, w->psi_q, cells * sizeof(float)) == 0;
}

/* Set k in storage c (its map in m): a few parameters moved, the model's scalars, an nd x nq map
 * (0: none). Uses cmocka's assert_true: include cmocka.h first. */
static inline const mc_drive_cfg_t *pstore_make_cfg(mc_drive_cfg_t *c, mc_flux_map_t *m, int k, int nd, int nq)
{
    mc_params_default(&c->p);
    assert_true(mc_param_set(&c->p, mc_param_find("control.ts_s"), 1e-4f - 1e-6f * (float)k, NULL));
    assert_true(mc_param_set(&c->p, mc_param_find("hw.encoder_lines"), (float)(1000 + k), NULL));
    c->est.rs = 0.1f + 0.01f * (float)k;
    c->est.ld = 1e-3f * (float)(k + 1);
    c->est.lq = 2e-3f * (float)(k + 1);
    c->est.psi_pm = 0.05f + 0.001f * (float)k;
    c->est.map = NULL;
    if (nd > 0) {
        memset(m, 0, sizeof *m);
        m->n_d = nd;
        m->n_q = nq;
        m->id0 = -10.0f - (float)k;
        m->did = 0.5f;
        m->iq0 = -20.0f;
        m->diq = 0.25f;
        for (int i = 0; i < nd * nq; ++i) {
            m->psi_d[i] = 0.001f * (float)i + (float)k;
            m->psi_q[i] = -0.002f * (float)i - (float)k;
        }
        c->est.map = m;
    }
    return c;
}

#endif
