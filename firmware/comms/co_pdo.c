/* Process data objects (CiA 301 §7.2.2, §7.5.2.35-38): four RPDOs and four TPDOs, byte-aligned
 * mapping of up to 8 objects and 64 bits, the SYNC.
 *
 * Transmission types. RPDO: 0..240 applied at the next SYNC, 254/255 at once. TPDO: 0 at a SYNC
 * if the data changed, 1..240 at every n-th SYNC, 254 on its event timer only, 255 on its event
 * timer and on every change of the mapped data (no faster than the inhibit time). (CiA 301 leaves
 * the events of 254 and 255 to the profile; "change" is what a CiA 402 master expects of the
 * statusword's PDO, and a timer is what a monitor wants of the actual values.) Remote requests
 * are not served (bit 30 of the COB-IDs reads 1). SYNC start (sub 6) is stored, not used.
 *
 * Mapping follows §7.5.2.36: the PDO must be invalid (COB-ID bit 31) to change sub 0, and sub 0
 * must be 0 to change an entry; an entry must name an existing object mappable in the PDO's
 * direction with its exact size, and sub 0 checks the whole mapping against 64 bits. */
#include <string.h>
#include "mc/co.h"

#define NOT_VALID 0x80000000u
#define NO_RTR    0x40000000u

static mc_co_pdo_t *pdo_at(mc_co_t *co, uint16_t index, bool *tx, bool *map)
{
    if (index >= 0x1400u && index < 0x1400u + MC_CO_PDO_N) {
        *tx = false, *map = false;
        return &co->rpdo[index - 0x1400u];
    }
    if (index >= 0x1600u && index < 0x1600u + MC_CO_PDO_N) {
        *tx = false, *map = true;
        return &co->rpdo[index - 0x1600u];
    }
    if (index >= 0x1800u && index < 0x1800u + MC_CO_PDO_N) {
        *tx = true, *map = false;
        return &co->tpdo[index - 0x1800u];
    }
    if (index >= 0x1A00u && index < 0x1A00u + MC_CO_PDO_N) {
        *tx = true, *map = true;
        return &co->tpdo[index - 0x1A00u];
    }
    return NULL;
}

static void set_map(mc_co_pdo_t *p, uint32_t a, uint32_t b)
{
    p->map[0] = a;
    p->map[1] = b;
    p->map_n = 2u;
}

void mc_co_pdo_defaults(mc_co_t *co)
{
    const uint32_t id = co->cfg.node_id;
    for (uint32_t k = 0u; k < MC_CO_PDO_N; ++k) {
        co->rpdo[k] = (mc_co_pdo_t){.cob_id = (0x200u + 0x100u * k + id) | (k >= 2u ? NOT_VALID : 0u), .type = 255u};
        co->tpdo[k] = (mc_co_pdo_t){.cob_id = (0x180u + 0x100u * k + id) | NO_RTR, .type = 254u, .event_ms = 10u,
                                    .last_len = 0xFFu};
    }
    set_map(&co->rpdo[0], 0x60400010u, 0x60600008u);   /* controlword, modes of operation */
    set_map(&co->rpdo[1], 0x60FF0020u, 0x60710010u);   /* target velocity, target torque */
    set_map(&co->tpdo[0], 0x60410010u, 0x60610008u);   /* statusword, modes display */
    co->tpdo[0].type = 255u;
    co->tpdo[0].event_ms = 100u;
    co->tpdo[0].inhibit = 10u;                          /* 1 ms */
    set_map(&co->tpdo[1], 0x606C0020u, 0x60770010u);   /* velocity actual, torque actual */
    set_map(&co->tpdo[2], 0x22070020u, 0x22080020u);   /* estimated angle, estimated speed */
    set_map(&co->tpdo[3], 0x22150020u, 0x60790020u);   /* estimator cost, DC link */
}

/* An entry the PDO may carry: 0 or the abort code. */
static uint32_t check_entry(uint32_t m, bool tx, uint32_t *bits)
{
    mc_co_entry_t e;
    bool miss;
    if (!mc_co_od_lookup((uint16_t)(m >> 16), (uint8_t)(m >> 8), &e, &miss)) {
        return miss ? MC_SDO_ABORT_NO_SUB : MC_SDO_ABORT_NO_OBJECT;
    }
    if ((e.flags & (tx ? MC_CO_F_TPDO : MC_CO_F_RPDO)) == 0u) {
        return MC_SDO_ABORT_NOT_MAPPABLE;
    }
    const uint32_t size = e.type == MC_CO_U8 || e.type == MC_CO_I8 || e.type == MC_CO_BOOL ? 8u
                          : e.type == MC_CO_U16 || e.type == MC_CO_I16                      ? 16u
                                                                                             : 32u;
    if ((m & 0xFFu) != size) {
        return MC_SDO_ABORT_NOT_MAPPABLE;   /* partial objects are not mapped */
    }
    *bits = size;
    return 0u;
}

uint32_t mc_co_pdo_read(const mc_co_t *co, uint16_t index, uint8_t sub, uint32_t *value)
{
    bool tx, map;
    const mc_co_pdo_t *p = pdo_at((mc_co_t *)co, index, &tx, &map);
    if (p == NULL) {
        return MC_SDO_ABORT_NO_OBJECT;
    }
    if (map) {
        *value = sub == 0u ? p->map_n : p->map[sub - 1u];
        return 0u;
    }
    switch (sub) {
    case 0u: *value = tx ? 6u : 2u; break;
    case 1u: *value = p->cob_id; break;
    case 2u: *value = p->type; break;
    case 3u: *value = p->inhibit; break;
    case 5u: *value = p->event_ms; break;
    case 6u: *value = p->sync_start; break;
    default: return MC_SDO_ABORT_NO_SUB;
    }
    return 0u;
}

static bool type_ok(uint32_t t)
{
    return t <= 240u || t == 254u || t == 255u;
}

uint32_t mc_co_pdo_write(mc_co_t *co, uint16_t index, uint8_t sub, uint32_t w)
{
    bool tx, map;
    mc_co_pdo_t *p = pdo_at(co, index, &tx, &map);
    if (p == NULL) {
        return MC_SDO_ABORT_NO_OBJECT;
    }
    const bool valid = (p->cob_id & NOT_VALID) == 0u;
    if (map) {
        if (sub == 0u) {
            if (valid) {
                return MC_SDO_ABORT_STATE;
            }
            if (w > MC_CO_PDO_MAP_N) {
                return MC_SDO_ABORT_VALUE_HIGH;
            }
            uint32_t total = 0u;
            for (uint32_t k = 0u; k < w; ++k) {
                uint32_t bits = 0u;
                const uint32_t a = check_entry(p->map[k], tx, &bits);
                if (a != 0u) {
                    return a;
                }
                total += bits;
            }
            if (total > 64u) {
                return MC_SDO_ABORT_PDO_LENGTH;
            }
            p->map_n = (uint8_t)w;
            return 0u;
        }
        if (valid || p->map_n != 0u) {
            return MC_SDO_ABORT_STATE;
        }
        uint32_t bits = 0u;
        const uint32_t a = check_entry(w, tx, &bits);
        if (a != 0u) {
            return a;
        }
        p->map[sub - 1u] = w;
        return 0u;
    }
    switch (sub) {
    case 1u: {
        const bool to_valid = (w & NOT_VALID) == 0u;
        if ((w & 0x3FFFF800u) != 0u) {
            return MC_SDO_ABORT_VALUE;   /* 29-bit identifiers are not supported */
        }
        if (valid && to_valid && (w & 0x7FFu) != (p->cob_id & 0x7FFu)) {
            return MC_SDO_ABORT_VALUE;   /* §7.5.2.35: the CAN-ID of a valid PDO is not changed */
        }
        p->cob_id = (w & (NOT_VALID | 0x7FFu)) | (tx ? NO_RTR : (w & NO_RTR));
        p->pending = false;
        p->last_len = 0xFFu;   /* a TPDO made valid goes out at its first event */
        return 0u;
    }
    case 2u:
        if (!type_ok(w)) {
            return MC_SDO_ABORT_VALUE;
        }
        p->type = (uint8_t)w;
        p->sync_count = 0u;
        return 0u;
    case 3u:
        if (valid) {
            return MC_SDO_ABORT_STATE;   /* §7.5.2.35: inhibit time only while the PDO is invalid */
        }
        p->inhibit = (uint16_t)w;
        return 0u;
    case 5u: p->event_ms = (uint16_t)w; return 0u;
    case 6u:
        if (valid) {
            return MC_SDO_ABORT_STATE;
        }
        if (w > 240u) {
            return MC_SDO_ABORT_VALUE_HIGH;
        }
        p->sync_start = (uint8_t)w;
        return 0u;
    default: return MC_SDO_ABORT_NO_SUB;
    }
}

static void rpdo_apply(mc_co_t *co, const mc_co_pdo_t *p, const uint8_t *data)
{
    uint32_t off = 0u;
    for (uint32_t k = 0u; k < p->map_n; ++k) {
        const uint32_t n = (p->map[k] & 0xFFu) / 8u;
        if (mc_co_od_write(co, (uint16_t)(p->map[k] >> 16), (uint8_t)(p->map[k] >> 8), data + off, n) != 0u) {
            co->rpdo_bad++;   /* e.g. a mode this drive does not have: that object keeps its value */
        }
        off += n;
        if (p->map[k] >> 16 == 0x6040u) {
            co->cw_written = true;
            co->cw_count++;
        }
    }
    co->rpdo_rx++;
}

static uint32_t map_bytes(const mc_co_pdo_t *p)
{
    uint32_t n = 0u;
    for (uint32_t k = 0u; k < p->map_n; ++k) {
        n += (p->map[k] & 0xFFu) / 8u;
    }
    return n;
}

bool mc_co_pdo_rx(mc_co_t *co, const hal_can_frame_t *f)
{
    if (f->id == co->cob_sync) {
        mc_co_pdo_sync(co);
        return true;
    }
    for (uint32_t k = 0u; k < MC_CO_PDO_N; ++k) {
        mc_co_pdo_t *p = &co->rpdo[k];
        if ((p->cob_id & NOT_VALID) != 0u || (p->cob_id & 0x7FFu) != f->id) {
            continue;
        }
        if (co->nmt != MC_NMT_OPERATIONAL) {
            return true;   /* §7.3.2: PDOs only in OPERATIONAL */
        }
        const uint32_t n = map_bytes(p);
        if (f->dlc < n) {
            co->rpdo_bad++;
            const uint8_t info[5] = {(uint8_t)k, f->dlc, (uint8_t)n, 0u, 0u};
            mc_co_emcy_send(co, MC_EMCY_PDO_LENGTH, 0x10u, info);   /* error register: communication */
            return true;
        }
        if (p->type <= 240u) {
            memcpy(p->last, f->data, n);
            p->pending = true;
        } else {
            rpdo_apply(co, p, f->data);
        }
        return true;
    }
    return false;
}

/* The mapped objects' values as the TPDO carries them; the length. */
static uint32_t tpdo_data(mc_co_t *co, const mc_co_pdo_t *p, uint8_t out[8])
{
    uint32_t off = 0u;
    for (uint32_t k = 0u; k < p->map_n; ++k) {
        const uint32_t n = (p->map[k] & 0xFFu) / 8u;
        uint8_t tmp[4] = {0u, 0u, 0u, 0u};
        uint32_t len = 0u;
        if (off + n > 8u) {
            break;
        }
        (void)mc_co_od_read(co, (uint16_t)(p->map[k] >> 16), (uint8_t)(p->map[k] >> 8), tmp, n, &len);
        memcpy(out + off, tmp, n);
        off += n;
    }
    return off;
}

static void tpdo_send(mc_co_t *co, mc_co_pdo_t *p, const uint8_t *data, uint32_t n)
{
    hal_can_frame_t f = {.id = p->cob_id & 0x7FFu, .dlc = (uint8_t)n};
    memcpy(f.data, data, n);
    if (!hal_can_send(co->can, &f)) {
        co->tx_dropped++;
    }
    memcpy(p->last, data, n);
    p->last_len = (uint8_t)n;
    p->last_ms = co->now_ms;
}

void mc_co_pdo_sync(mc_co_t *co)
{
    if (co->nmt != MC_NMT_OPERATIONAL) {
        return;
    }
    for (uint32_t k = 0u; k < MC_CO_PDO_N; ++k) {
        mc_co_pdo_t *r = &co->rpdo[k];
        if (r->pending && (r->cob_id & NOT_VALID) == 0u) {
            rpdo_apply(co, r, r->last);
        }
        r->pending = false;
        mc_co_pdo_t *t = &co->tpdo[k];
        if ((t->cob_id & NOT_VALID) != 0u || t->type > 240u) {
            continue;
        }
        uint8_t d[8];
        const uint32_t n = tpdo_data(co, t, d);
        if (t->type == 0u) {
            if (n != t->last_len || memcmp(d, t->last, n) != 0) {
                tpdo_send(co, t, d, n);
            }
        } else if (++t->sync_count >= t->type) {
            t->sync_count = 0u;
            tpdo_send(co, t, d, n);
        }
    }
}

void mc_co_pdo_tx(mc_co_t *co)
{
    if (co->nmt != MC_NMT_OPERATIONAL) {
        return;
    }
    for (uint32_t k = 0u; k < MC_CO_PDO_N; ++k) {
        mc_co_pdo_t *t = &co->tpdo[k];
        if ((t->cob_id & NOT_VALID) != 0u || t->type < 254u) {
            continue;
        }
        uint8_t d[8];
        const uint32_t n = tpdo_data(co, t, d);
        const uint32_t since = co->now_ms - t->last_ms;
        const bool timer = t->event_ms != 0u && since >= t->event_ms;
        const bool changed = t->last_len == 0xFFu || n != t->last_len || memcmp(d, t->last, n) != 0;
        const bool event = t->type == 255u && changed && since * 10u >= t->inhibit;
        if (timer || event) {
            tpdo_send(co, t, d, n);
        }
    }
}
