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

#endif
