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



/* ---- parameters by name ------------------------------------------------------------------ */

uint32_t mc_store_param_key(int id)
{
    const mc_param_info_t *e = &mc_param_table[id];
    uint32_t h = 2166136261u;   /* FNV-1a-32: computed when a record is written or read, never in the ISR */
    for (const char *c = e->name; *c != '\0'; ++c) {
        h = (h ^ (uint8_t)*c) * 16777619u;
    }
    return (h & MC_STORE_KEY_NAME) | (uint32_t)e->type;
}

/* The keys of the last table that wrote version 1 records (main at 5265cfe, MC_STORE_V1_TABLE),
 * by position. Such a record holds only positions, so without this list a drive in the field would
 * lose its stored set with the first update: frozen, never to follow the table (generated from
 * that table's names and types by mc_store_param_key's rule, checked against the live table while
 * it was that one (app_store); the NVM image that version wrote over CANopen,
 * tests/integration/data/nvm_main_5265cfe.bin, boots with its values through it). */
static const uint32_t v1_keys[MC_STORE_V1_COUNT] = {
    0x7F49A101u, 0x190E3AC0u, 0xF0607F60u, 0x7DA5E6E0u, 0xEBF98CB0u, 0x05EFC8C0u,
    0x353C9650u, 0x19B9E210u, 0x178B7FB0u, 0x33238EC0u, 0xADADF6C1u, 0x767D2E80u,
    0xB3E989C0u, 0x9FC50710u, 0x04D269F0u, 0x5176FB31u, 0xA82F8DF0u, 0x1B4FBE00u,
    0xB7084F60u, 0x79199690u, 0xE75EEF93u, 0x40DC0491u, 0x649855A0u, 0xE1939780u,
    0x81D979B0u, 0x5DC2EA60u, 0x51DB6772u, 0x8B9B1B40u, 0x9FA6A1A3u, 0xD5DFB860u,
    0xD0D30AA0u, 0xC7D2FC80u, 0x4ECF03A1u, 0xEF206BB0u, 0x4F1D8AC2u, 0x4E1D9EA0u,
    0xDAF0F520u, 0xF9E30600u, 0xDCA13193u, 0x6A2B2271u, 0xE9346FF0u, 0xCE5DAA90u,
    0xCB5DA5E0u, 0xA3294AB0u, 0x6755FBB2u, 0x82B71782u, 0x63133A33u, 0xDE215480u,
    0xD1C9AC70u, 0x3DB66580u, 0xDB07C9C0u, 0xA7E1B460u, 0x60735AD0u, 0x7DBDA960u,
    0x4717AA23u, 0x35A31FE3u, 0x02B8F773u, 0x91B0AEF1u, 0x474356A1u, 0x74DC2640u,
    0xC9ABED63u, 0x4A788BB1u, 0x14D11EC0u, 0x8128D891u, 0xCFB9FF80u, 0x06D15170u,
    0x1E6313E0u, 0xE617A800u, 0x6BAE4D20u, 0x8BC6C4D0u, 0x498BA7C0u, 0x851FA670u,
    0x3B8E7AE0u, 0xE15C8F00u, 0xC329C9D0u, 0xAE8E2F60u, 0x5AE50900u, 0xAD07F5C0u,
    0x50D43C50u, 0x6A21EB20u, 0x82B73BC3u, 0x77D13900u, 0xDC17A4C0u, 0x22B69123u,
    0x138DBAE1u, 0x36CCC810u, 0x44DE2853u, 0x0670E180u, 0xBE2F4130u, 0xCF265EA3u,
    0xD7669B80u, 0xC2F1BDA0u, 0x6F668A90u, 0x0EBE2830u, 0x569C9350u,
};

uint32_t mc_store_v1_key(uint32_t pos)
{
    return pos < MC_STORE_V1_COUNT ? v1_keys[pos] : 0u;
}

void mc_store_report_clear(mc_store_report_t *rep)
{
    memset(rep, 0, sizeof *rep);
    rep->first = -1;
}

static int find_key(uint32_t key, uint32_t hint)
{
    /* the same table (the common case) has it at the same position: one hash per value */
    if (hint < (uint32_t)MC_PARAM_COUNT && ((mc_store_param_key((int)hint) ^ key) & MC_STORE_KEY_NAME) == 0u) {
        return (int)hint;
    }
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (((mc_store_param_key(id) ^ key) & MC_STORE_KEY_NAME) == 0u) {
            return id;
        }
    }
    return -1;
}

void mc_store_param_apply(mc_params_t *q, uint32_t key, uint32_t value, uint32_t hint, mc_store_report_t *rep)
{
    const int id = find_key(key, hint);
    if (id < 0) {
        rep->unknown++;
        return;
    }
    mc_store_drop_t why = MC_STORE_DROP_NONE;
    const mc_param_info_t *e = &mc_param_table[id];
    if ((key & MC_STORE_KEY_TYPE) != (uint32_t)e->type) {
        why = MC_STORE_DROP_TYPE;
    } else if ((key & MC_STORE_KEY_AUTO) != 0u) {
        if (e->rule != (uint8_t)MC_RULE_NONE) {
            mc_param_set_auto(q, id, true);   /* else (a rule gone since) its constant default */
        }
    } else {
        /* this table's range and type checks: a value it refuses keeps the default */
        const float v = mc_bits_f32(value);
        if (!(v >= e->min && v <= e->max) || !mc_param_set(q, id, v, NULL)) {
            why = MC_STORE_DROP_RANGE;
        }
    }
    if (why == MC_STORE_DROP_NONE) {
        rep->kept++;
    } else {
        if (rep->dropped++ == 0u) {
            rep->first = (int16_t)id;
            rep->reason = (uint8_t)why;
        }
    }
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
    put(buf, &at, MC_STORE_PARAMS_VERSION);
    put(buf, &at, mc_params_table_hash());
    put(buf, &at, (uint32_t)MC_PARAM_COUNT);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const bool is_auto = mc_param_is_auto(p, id);
        put(buf, &at, mc_store_param_key(id) | (is_auto ? MC_STORE_KEY_AUTO : 0u));
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

static mc_store_status_t check_head(const uint8_t *buf, size_t n, uint32_t magic, uint32_t version)
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
    return get(buf, 4u) == version ? MC_STORE_OK : MC_STORE_BAD_VERSION;
}

static bool crc_ok(const uint8_t *buf, size_t len)
{
    return mc_crc32(buf, len - 4u) == get(buf, len - 4u);
}

mc_store_status_t mc_store_params_decode(const uint8_t *buf, size_t n, mc_params_t *p, mc_store_report_t *rep)
{
    mc_store_status_t st = check_head(buf, n, MC_STORE_MAGIC_PARAMS, MC_STORE_PARAMS_VERSION);
    if (st != MC_STORE_OK) {
        return st;
    }
    if (n < 20u) {
        return MC_STORE_BAD_SIZE;
    }
    const uint32_t count = get(buf, 12u);
    if (count > (n - 20u) / 8u) {
        return MC_STORE_BAD_SIZE;
    }
    const size_t len = 4u * (5u + 2u * (size_t)count);
    if (!crc_ok(buf, len)) {
        return MC_STORE_BAD_CRC;
    }
    mc_store_report_t r;
    mc_store_report_clear(&r);
    r.other_table = get(buf, 8u) != mc_params_table_hash();
    mc_params_t q;
    mc_params_default(&q);
    for (uint32_t k = 0; k < count; ++k) {
        mc_store_param_apply(&q, get(buf, 16u + 8u * k), get(buf, 20u + 8u * k), k, &r);
    }
    *p = q;
    if (rep != NULL) {
        *rep = r;
    }
    return MC_STORE_OK;
}

/* The model record's header checks and its length; nd, nq of its map (0 without one). */
static mc_store_status_t model_head(const uint8_t *buf, size_t n, uint32_t *nd, uint32_t *nq)
{
    mc_store_status_t st = check_head(buf, n, MC_STORE_MAGIC_MODEL, MC_STORE_VERSION);
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
