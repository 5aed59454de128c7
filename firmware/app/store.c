/* Stored configuration records (mc/store.h). */
#include "mc/store.h"
#include <math.h>
#include <string.h>
#include "mc/bits.h"

uint32_t mc_crc32(const uint8_t *data, size_t n)
{
    /* IEEE 802.3 reflected, bitwise: runs at boot and on a store, not in the ISR */
    uint32_t c = 0xFFFFFFFFu;
    for (size_t k = 0; k < n; ++k) {
        c ^= data[k];
        for (int b = 0; b < 8; ++b) {
            c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
        }
    }
    return ~c;
}

static void put(uint8_t *buf, size_t *at, uint32_t w)
{
    buf[*at] = (uint8_t)w;
    buf[*at + 1u] = (uint8_t)(w >> 8);
    buf[*at + 2u] = (uint8_t)(w >> 16);
    buf[*at + 3u] = (uint8_t)(w >> 24);
    *at += 4u;
}

static uint32_t get(const uint8_t *buf, size_t at)
{
    return (uint32_t)buf[at] | ((uint32_t)buf[at + 1u] << 8) | ((uint32_t)buf[at + 2u] << 16) |
           ((uint32_t)buf[at + 3u] << 24);
}



static size_t close_record(uint8_t *buf, size_t at)
{
    put(buf, &at, mc_crc32(buf, at));
    return at;
}

size_t mc_store_params_encode(const mc_params_t *p, uint8_t *buf, size_t cap)
{
    const size_t len = 4u * (5u + 2u * (size_t)MC_PARAM_COUNT);
    if (cap < len) {
        return 0u;
    }
    size_t at = 0u;
    put(buf, &at, MC_STORE_MAGIC_PARAMS);
    put(buf, &at, MC_STORE_VERSION);
    put(buf, &at, mc_params_table_hash());
    put(buf, &at, (uint32_t)MC_PARAM_COUNT);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const bool is_auto = mc_param_is_auto(p, id);
        put(buf, &at, (uint32_t)id | (is_auto ? MC_STORE_AUTO : 0u));
        put(buf, &at, mc_f32_bits(mc_param_get(p, id)));
    }
    return close_record(buf, at);
}

size_t mc_store_model_encode(const mc_est_model_t *m, uint8_t *buf, size_t cap)
{
    const mc_flux_map_t *map = m->map;
    const size_t cells = map != NULL ? (size_t)map->n_d * (size_t)map->n_q : 0u;
    const size_t len = 4u * (8u + (map != NULL ? 6u + 2u * cells : 0u));
    if (cap < len || (map != NULL && (map->n_d < 2 || map->n_q < 2 || map->n_d > MC_FLUX_MAP_MAX ||
                                      map->n_q > MC_FLUX_MAP_MAX))) {
        return 0u;
    }
    size_t at = 0u;
    put(buf, &at, MC_STORE_MAGIC_MODEL);
    put(buf, &at, MC_STORE_VERSION);
    put(buf, &at, mc_f32_bits(m->rs));
    put(buf, &at, mc_f32_bits(m->ld));
    put(buf, &at, mc_f32_bits(m->lq));
    put(buf, &at, mc_f32_bits(m->psi_pm));
    put(buf, &at, map != NULL ? 1u : 0u);
    if (map != NULL) {
        put(buf, &at, (uint32_t)map->n_d);
        put(buf, &at, (uint32_t)map->n_q);
        put(buf, &at, mc_f32_bits(map->id0));
        put(buf, &at, mc_f32_bits(map->did));
        put(buf, &at, mc_f32_bits(map->iq0));
        put(buf, &at, mc_f32_bits(map->diq));
        for (size_t k = 0; k < cells; ++k) {
            put(buf, &at, mc_f32_bits(map->psi_d[k]));
        }
        for (size_t k = 0; k < cells; ++k) {
            put(buf, &at, mc_f32_bits(map->psi_q[k]));
        }
    }
    return close_record(buf, at);
}

static mc_store_status_t check_head(const uint8_t *buf, size_t n, uint32_t magic)
{
    if (n < 12u) {
        return MC_STORE_BAD_SIZE;
    }
    const uint32_t m = get(buf, 0u);
    if (m == 0xFFFFFFFFu) {
        return MC_STORE_EMPTY;
    }
    if (m != magic) {
        return MC_STORE_BAD_MAGIC;
    }
    return get(buf, 4u) == MC_STORE_VERSION ? MC_STORE_OK : MC_STORE_BAD_VERSION;
}

static bool crc_ok(const uint8_t *buf, size_t len)
{
    return mc_crc32(buf, len - 4u) == get(buf, len - 4u);
}

mc_store_status_t mc_store_params_decode(const uint8_t *buf, size_t n, mc_params_t *p)
{
    mc_store_status_t st = check_head(buf, n, MC_STORE_MAGIC_PARAMS);
    if (st != MC_STORE_OK) {
        return st;
    }
    if (n < 20u) {
        return MC_STORE_BAD_SIZE;
    }
    if (get(buf, 8u) != mc_params_table_hash()) {
        return MC_STORE_OTHER_TABLE;
    }
    const uint32_t count = get(buf, 12u);
    if (count > (uint32_t)MC_PARAM_COUNT || 4u * (5u + 2u * (size_t)count) > n) {
        return MC_STORE_BAD_SIZE;
    }
    const size_t len = 4u * (5u + 2u * (size_t)count);
    if (!crc_ok(buf, len)) {
        return MC_STORE_BAD_CRC;
    }
    mc_params_t q;
    mc_params_default(&q);
    for (uint32_t k = 0; k < count; ++k) {
        const uint32_t w = get(buf, 16u + 8u * k);
        const int id = (int)(w & ~MC_STORE_AUTO);
        if (id >= (int)MC_PARAM_COUNT) {
            return MC_STORE_BAD_VALUE;
        }
        if ((w & MC_STORE_AUTO) != 0u) {
            mc_param_set_auto(&q, id, true);
        } else {
            /* the table's range here already: a stored set is refused whole, not at the build */
            const float v = mc_bits_f32(get(buf, 20u + 8u * k));
            const mc_param_info_t *e = &mc_param_table[id];
            if (!(v >= e->min && v <= e->max) || !mc_param_set(&q, id, v, NULL)) {
                return MC_STORE_BAD_VALUE;
            }
        }
    }
    *p = q;
    return MC_STORE_OK;
}

/* The model record's header checks and its length; nd, nq of its map (0 without one). */
static mc_store_status_t model_head(const uint8_t *buf, size_t n, uint32_t *nd, uint32_t *nq)
{
    mc_store_status_t st = check_head(buf, n, MC_STORE_MAGIC_MODEL);
    if (st != MC_STORE_OK) {
        return st;
    }
    if (n < 32u) {
        return MC_STORE_BAD_SIZE;
    }
    size_t len = 32u;
    *nd = 0u;
    *nq = 0u;
    if (get(buf, 24u) != 0u) {
        if (n < 56u) {
            return MC_STORE_BAD_SIZE;
        }
        *nd = get(buf, 28u);
        *nq = get(buf, 32u);
        if (*nd < 2u || *nq < 2u || *nd > MC_FLUX_MAP_MAX || *nq > MC_FLUX_MAP_MAX) {
            return MC_STORE_BAD_SIZE;
        }
        len = 4u * (14u + 2u * (size_t)*nd * *nq);
        if (len > n) {
            return MC_STORE_BAD_SIZE;
        }
    }
    return crc_ok(buf, len) ? MC_STORE_OK : MC_STORE_BAD_CRC;
}

static void model_scalars(const uint8_t *buf, mc_est_model_t *m)
{
    m->rs = mc_bits_f32(get(buf, 8u));
    m->ld = mc_bits_f32(get(buf, 12u));
    m->lq = mc_bits_f32(get(buf, 16u));
    m->psi_pm = mc_bits_f32(get(buf, 20u));
    m->map = NULL;
}

mc_store_status_t mc_store_model_decode(const uint8_t *buf, size_t n, mc_est_model_t *m, mc_flux_map_t *map_out)
{
    uint32_t nd, nq;
    const mc_store_status_t st = model_head(buf, n, &nd, &nq);
    if (st != MC_STORE_OK) {
        return st;
    }
    if (nd != 0u && map_out == NULL) {
        return MC_STORE_BAD_SIZE;
    }
    model_scalars(buf, m);
    if (nd != 0u) {
        map_out->n_d = (int)nd;
        map_out->n_q = (int)nq;
        map_out->id0 = mc_bits_f32(get(buf, 36u));
        map_out->did = mc_bits_f32(get(buf, 40u));
        map_out->iq0 = mc_bits_f32(get(buf, 44u));
        map_out->diq = mc_bits_f32(get(buf, 48u));
        const size_t cells = (size_t)nd * nq;
        for (size_t k = 0; k < cells; ++k) {
            map_out->psi_d[k] = mc_bits_f32(get(buf, 52u + 4u * k));
            map_out->psi_q[k] = mc_bits_f32(get(buf, 52u + 4u * (cells + k)));
        }
        m->map = map_out;
    }
    return MC_STORE_OK;
}

mc_store_status_t mc_store_model_view(const uint8_t *buf, size_t n, mc_est_model_t *m,
                                      const mc_flux_map_t *map_in_place)
{
    uint32_t nd, nq;
    const mc_store_status_t st = model_head(buf, n, &nd, &nq);
    if (st != MC_STORE_OK) {
        return st;
    }
    if (nd != 0u) {
        const mc_flux_map_t *p = map_in_place;
        if (p == NULL || p->n_d != (int)nd || p->n_q != (int)nq || mc_f32_bits(p->id0) != get(buf, 36u) ||
            mc_f32_bits(p->did) != get(buf, 40u) || mc_f32_bits(p->iq0) != get(buf, 44u) ||
            mc_f32_bits(p->diq) != get(buf, 48u)) {
            return MC_STORE_MAP_MISMATCH;
        }
        const size_t cells = (size_t)nd * nq;
        for (size_t k = 0; k < cells; ++k) {
            if (mc_f32_bits(p->psi_d[k]) != get(buf, 52u + 4u * k) ||
                mc_f32_bits(p->psi_q[k]) != get(buf, 52u + 4u * (cells + k))) {
                return MC_STORE_MAP_MISMATCH;
            }
        }
    }
    model_scalars(buf, m);
    m->map = nd != 0u ? map_in_place : NULL;
    return MC_STORE_OK;
}

const char *mc_store_status_name(mc_store_status_t s)
{
    static const char *const names[] = {"ok", "empty", "bad_magic", "bad_version", "other_table",
                                        "bad_size", "bad_crc", "bad_value", "map_mismatch"};
    return (unsigned)s < sizeof names / sizeof names[0] ? names[s] : "?";
}
