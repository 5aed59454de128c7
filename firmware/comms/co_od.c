/* The object dictionary (mc/co.h): the fixed objects of co_objects.h, the PDO parameter ranges,
 * the parameter table as 0x2000 + id and the telemetry channels as 0x2200 + channel; reading and
 * writing with the CiA 301 checks (access, length, range, device state) in one place for the
 * SDO server and the PDOs. */
#include <stddef.h>
#include <string.h>
#include "mc/bits.h"
#include "mc/co.h"
#include "mc/telem_channels.h"
#include "co_objects.h"

/* A target image carries no texts: names, units and descriptions are for co-gen (the EDS, the
 * docs) and the tests, on the host. */
#ifdef MC_CO_NO_TEXT
#define TXT(s) ""
#else
#define TXT(s) s
#endif

#define DEVICE_NAME "ipmsm-sensorless-drive"
#define SW_VERSION  "0.2.0 (CiA 301, CiA 402)"
#define PARAM_BASE  0x2000u
#define TELEM_BASE  0x2200u

enum {
    H_DEVTYPE, H_ERRREG, H_HIST, H_SYNC, H_NAME, H_SWVER, H_ONE, H_FOUR, H_SIX, H_EIGHT, H_STORE, H_RESTORE,
    H_SCOPE_CTRL, H_SCOPE_STATUS, H_SCOPE_SAMPLES, H_SCOPE_TRIG, H_SCOPE_TS, H_SCOPE_DATA, H_SCOPE_CAP, H_HASH
};

/* Each FIELD member has the size of its CiA type (a mismatch would read a neighbour). */
#define TSIZE_BOOL 1u
#define TSIZE_I8 1u
#define TSIZE_I16 2u
#define TSIZE_I32 4u
#define TSIZE_U8 1u
#define TSIZE_U16 2u
#define TSIZE_U32 4u
#define TSIZE_REAL32 4u
#define TSIZE_VSTRING 0u
#define TSIZE_DOMAIN 0u
#define FLD(m) sizeof(((mc_co_t *)0)->m)
#define HK(n) 0u
#define SIZE_CHECK(i, s, T, A, F, K, ARG, MIN, MAX, on, sn, u, doc) \
    _Static_assert(MC_CO_K_##K != MC_CO_K_FIELD || (ARG) == TSIZE_##T, "object " #i " sub " #s ": member size");
MC_CO_OBJECTS(SIZE_CHECK)
#undef FLD
#undef HK

#define FLD(m) offsetof(mc_co_t, m)
#define HK(n) H_##n
#define ENTRY(i, s, T, A, F, K, ARG, MIN, MAX, on, sn, u, doc) \
    {i, s, MC_CO_##T, MC_CO_##A, F, MC_CO_K_##K, (uint16_t)(ARG), MIN, MAX, TXT(on), TXT(sn), TXT(u), TXT(doc)},
static const mc_co_entry_t fixed[] = {MC_CO_OBJECTS(ENTRY)};
#define N_FIXED (sizeof fixed / sizeof fixed[0])

#define TNAME(id, name, unit, expr, doc) TXT("telem." #name),
#define TUNIT(id, name, unit, expr, doc) TXT(unit),
#define TDOC(id, name, unit, expr, doc) TXT(doc),
static const char *const telem_name[] = {MC_TELEM_CHANNELS(TNAME)};
static const char *const telem_unit[] = {MC_TELEM_CHANNELS(TUNIT)};
static const char *const telem_doc[] = {MC_TELEM_CHANNELS(TDOC)};

static const char *const pdo_name[4][4] = {
    {TXT("RPDO 1 communication parameter"), TXT("RPDO 2 communication parameter"), TXT("RPDO 3 communication parameter"),
     TXT("RPDO 4 communication parameter")},
    {TXT("RPDO 1 mapping parameter"), TXT("RPDO 2 mapping parameter"), TXT("RPDO 3 mapping parameter"), TXT("RPDO 4 mapping parameter")},
    {TXT("TPDO 1 communication parameter"), TXT("TPDO 2 communication parameter"), TXT("TPDO 3 communication parameter"),
     TXT("TPDO 4 communication parameter")},
    {TXT("TPDO 1 mapping parameter"), TXT("TPDO 2 mapping parameter"), TXT("TPDO 3 mapping parameter"), TXT("TPDO 4 mapping parameter")}};
static const char *const comm_sub[7] = {TXT("Highest sub-index supported"), TXT("COB-ID"), TXT("Transmission type"), TXT("Inhibit time"),
                                        TXT(""), TXT("Event timer"), TXT("SYNC start value")};
static const char *const map_sub[9] = {TXT("Number of mapped objects"), TXT("Mapped object 1"), TXT("Mapped object 2"),
                                       TXT("Mapped object 3"), TXT("Mapped object 4"), TXT("Mapped object 5"), TXT("Mapped object 6"),
                                       TXT("Mapped object 7"), TXT("Mapped object 8")};
static const uint8_t tpdo_comm_subs[6] = {0u, 1u, 2u, 3u, 5u, 6u};

/* The PDO parameter objects: group g (0 RPDO comm, 1 RPDO map, 2 TPDO comm, 3 TPDO map). */
static bool pdo_entry(uint16_t index, uint8_t sub, mc_co_entry_t *e, bool *missing_sub)
{
    static const uint16_t base[4] = {0x1400u, 0x1600u, 0x1800u, 0x1A00u};
    for (uint32_t g = 0u; g < 4u; ++g) {
        if (index < base[g] || index >= base[g] + MC_CO_PDO_N) {
            continue;
        }
        const uint32_t k = index - base[g];
        const bool map = (g & 1u) != 0u, tx = g >= 2u;
        const uint8_t last = map ? 8u : (tx ? 6u : 2u);
        if (sub > last || (!map && tx && sub == 4u)) {
            *missing_sub = true;
            return false;
        }
        *e = (mc_co_entry_t){.index = index, .sub = sub, .kind = MC_CO_K_HOOK, .oname = pdo_name[g][k], .unit = "",
                             .doc = ""};
        e->sname = map ? map_sub[sub] : comm_sub[sub];
        e->access = (!map && sub == 0u) ? MC_CO_CONST : MC_CO_RW;
        if (sub == 0u) {
            e->type = MC_CO_U8;
            e->min = map ? 0 : last;
            e->max = map ? 8 : last;
        } else if (map || sub == 1u) {
            e->type = MC_CO_U32;
            e->max = MC_U32MAX;
            e->flags = (uint8_t)(!map ? MC_CO_F_NODEID : 0u);
        } else if (sub == 2u || sub == 6u) {
            e->type = MC_CO_U8;
            e->max = sub == 2u ? 255 : 240;
        } else {
            e->type = MC_CO_U16;
            e->max = 65535;
            e->unit = sub == 3u ? "100 us" : "ms";
        }
        return true;
    }
    return false;
}

static void param_entry(int id, mc_co_entry_t *e)
{
    const mc_param_info_t *p = &mc_param_table[id];
    *e = (mc_co_entry_t){.index = (uint16_t)(PARAM_BASE + (uint32_t)id), .sub = 0u,
                         .type = p->type == MC_PT_F32 ? MC_CO_REAL32 : MC_CO_I32,
                         .access = p->access == MC_PA_INIT ? MC_CO_RO : MC_CO_RW, .kind = MC_CO_K_PARAM,
                         .arg = (uint16_t)id,
                         /* the range of the INTEGER32 ones (F32: the table's, checked in param_write) */
                         .min = p->type == MC_PT_F32 ? 0 : (int64_t)(int32_t)p->min,
                         .max = p->type == MC_PT_F32 ? 0 : (int64_t)(int32_t)p->max, .oname = p->name,
                         .sname = "", .unit = p->unit, .doc = TXT(p->doc)};
}

static void telem_entry(uint32_t ch, mc_co_entry_t *e)
{
    *e = (mc_co_entry_t){.index = (uint16_t)(TELEM_BASE + ch), .sub = 0u, .type = MC_CO_REAL32, .access = MC_CO_RO,
                         .flags = MC_CO_F_TPDO, .kind = MC_CO_K_TELEM, .arg = (uint16_t)ch,
                         .oname = telem_name[ch - 1u], .sname = "", .unit = telem_unit[ch - 1u],
                         .doc = telem_doc[ch - 1u]};
}

bool mc_co_od_lookup(uint16_t index, uint8_t sub, mc_co_entry_t *e, bool *missing_sub)
{
    bool miss = false;
    bool found = false;
    if (index >= PARAM_BASE && index < PARAM_BASE + (uint32_t)MC_PARAM_COUNT) {
        found = sub == 0u;
        miss = !found;
        if (found) {
            param_entry((int)(index - PARAM_BASE), e);
        }
    } else if (index > TELEM_BASE && index <= TELEM_BASE + MC_TELEM_CHANNEL_COUNT) {
        found = sub == 0u;
        miss = !found;
        if (found) {
            telem_entry(index - TELEM_BASE, e);
        }
    } else if (index >= 0x1400u && index < 0x1C00u) {
        found = pdo_entry(index, sub, e, &miss);
    } else {
        for (uint32_t k = 0u; k < N_FIXED; ++k) {
            if (fixed[k].index == index) {
                if (fixed[k].sub == sub) {
                    *e = fixed[k];
                    found = true;
                    break;
                }
                miss = true;
            }
        }
    }
    if (missing_sub != NULL) {
        *missing_sub = !found && miss;
    }
    return found;
}

#define N_PDO_ENTRIES (MC_CO_PDO_N * (3u + 9u + 6u + 9u))

uint32_t mc_co_od_count(void)
{
    return (uint32_t)N_FIXED + N_PDO_ENTRIES + (uint32_t)MC_PARAM_COUNT + MC_TELEM_CHANNEL_COUNT;
}

bool mc_co_od_at(uint32_t n, mc_co_entry_t *e)
{
    if (n < N_FIXED) {
        *e = fixed[n];
        return true;
    }
    n -= (uint32_t)N_FIXED;
    if (n < N_PDO_ENTRIES) {
        static const uint16_t base[4] = {0x1400u, 0x1600u, 0x1800u, 0x1A00u};
        static const uint8_t per[4] = {3u, 9u, 6u, 9u};
        for (uint32_t g = 0u; g < 4u; ++g) {
            const uint32_t size = MC_CO_PDO_N * per[g];
            if (n < size) {
                const uint32_t k = n / per[g], s = n % per[g];
                const uint8_t sub = g == 2u ? tpdo_comm_subs[s] : (uint8_t)s;
                bool miss;
                return pdo_entry((uint16_t)(base[g] + k), sub, e, &miss);
            }
            n -= size;
        }
    }
    n -= N_PDO_ENTRIES;
    if (n < (uint32_t)MC_PARAM_COUNT) {
        param_entry((int)n, e);
        return true;
    }
    n -= (uint32_t)MC_PARAM_COUNT;
    if (n < MC_TELEM_CHANNEL_COUNT) {
        telem_entry(n + 1u, e);
        return true;
    }
    return false;
}

/* ---- values ---- */

static uint32_t type_size(uint8_t t)
{
    switch (t) {
    case MC_CO_BOOL:
    case MC_CO_I8:
    case MC_CO_U8: return 1u;
    case MC_CO_I16:
    case MC_CO_U16: return 2u;
    default: return 4u;
    }
}

static bool is_signed(uint8_t t)
{
    return t == MC_CO_I8 || t == MC_CO_I16 || t == MC_CO_I32;
}

static uint32_t put(uint8_t *data, uint32_t cap, uint32_t *len, uint32_t v, uint32_t n)
{
    if (cap < n) {
        return MC_SDO_ABORT_GENERAL;
    }
    for (uint32_t k = 0u; k < n; ++k) {
        data[k] = (uint8_t)(v >> (8u * k));
    }
    *len = n;
    return 0u;
}

static uint32_t put_str(uint8_t *data, uint32_t cap, uint32_t *len, const char *s)
{
    const uint32_t n = (uint32_t)strlen(s);
    if (cap < n) {
        return MC_SDO_ABORT_GENERAL;
    }
    memcpy(data, s, n);
    *len = n;
    return 0u;
}

/* A FIELD member's raw bits (zero-extended), and back. */
static uint32_t field_get(const mc_co_t *co, const mc_co_entry_t *e)
{
    const uint8_t *p = (const uint8_t *)co + e->arg;
    switch (type_size(e->type)) {
    case 1u: return *p;
    case 2u: {
        uint16_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    default: {
        uint32_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    }
}

static void field_set(mc_co_t *co, const mc_co_entry_t *e, uint32_t w)
{
    uint8_t *p = (uint8_t *)co + e->arg;
    switch (type_size(e->type)) {
    case 1u: *p = (uint8_t)w; break;
    case 2u: {
        const uint16_t v = (uint16_t)w;
        memcpy(p, &v, sizeof v);
        break;
    }
    default: memcpy(p, &w, sizeof w); break;
    }
}

static bool outputs_off(const mc_co_t *co)
{
    const mc_state_t st = mc_drive_state(co->drive);
    return st == MC_STATE_IDLE || st == MC_STATE_FAULT;
}

static bool is_scope(uint16_t index)
{
    return index >= 0x2300u && index <= 0x2308u;
}

static uint32_t hook_read(mc_co_t *co, const mc_co_entry_t *e, uint8_t *data, uint32_t cap, uint32_t *len)
{
    const mc_scope_t *s = co->scope;
    switch (e->arg) {
    case H_DEVTYPE: return put(data, cap, len, MC_CO_DEVICE_TYPE, 4u);
    case H_ERRREG: return put(data, cap, len, mc_co_error_register(mc_drive_faults(co->drive)), 1u);
    case H_HIST:
        if (e->sub == 0u) {
            return put(data, cap, len, co->err_count, 1u);
        }
        return put(data, cap, len, e->sub <= co->err_count ? co->err_hist[e->sub - 1u] : 0u, 4u);
    case H_SYNC: return put(data, cap, len, co->cob_sync, 4u);
    case H_NAME: return put_str(data, cap, len, DEVICE_NAME);
    case H_SWVER: return put_str(data, cap, len, SW_VERSION);
    case H_ONE:
    case H_STORE:
    case H_RESTORE: return put(data, cap, len, 1u, type_size(e->type));   /* "on command" */
    case H_FOUR: return put(data, cap, len, 4u, 1u);
    case H_SIX: return put(data, cap, len, 6u, 1u);
    case H_EIGHT: return put(data, cap, len, 8u, 1u);
    case H_SCOPE_CTRL: return put(data, cap, len, co->scope_ctrl, 1u);
    case H_SCOPE_STATUS: return put(data, cap, len, (uint32_t)mc_scope_state(s), 1u);
    case H_SCOPE_SAMPLES: return put(data, cap, len, mc_scope_samples(s), 4u);
    case H_SCOPE_TRIG: return put(data, cap, len, mc_scope_trigger_index(s), 4u);
    case H_SCOPE_TS: return put(data, cap, len, mc_f32_bits(mc_scope_sample_period(s)), 4u);
    case H_SCOPE_CAP: return put(data, cap, len, mc_scope_capacity(s), 4u);
    case H_HASH: return put(data, cap, len, mc_params_table_hash(), 4u);
    default: return MC_SDO_ABORT_GENERAL;
    }
}

uint32_t mc_co_od_read(mc_co_t *co, uint16_t index, uint8_t sub, uint8_t *data, uint32_t cap, uint32_t *len)
{
    mc_co_entry_t e;
    bool miss;
    if (!mc_co_od_lookup(index, sub, &e, &miss) || (is_scope(index) && co->scope == NULL)) {
        return miss ? MC_SDO_ABORT_NO_SUB : MC_SDO_ABORT_NO_OBJECT;
    }
    if (e.access == MC_CO_WO) {
        return MC_SDO_ABORT_WRITE_ONLY;
    }
    if (e.type == MC_CO_DOMAIN) {
        return MC_SDO_ABORT_GENERAL;   /* streamed: mc_co_od_domain_read */
    }
    switch (e.kind) {
    case MC_CO_K_FIELD: return put(data, cap, len, field_get(co, &e), type_size(e.type));
    case MC_CO_K_PARAM: {
        const mc_param_info_t *p = &mc_param_table[e.arg];
        const float v = mc_param_get(mc_drive_params(co->drive), e.arg);
        return put(data, cap, len, p->type == MC_PT_F32 ? mc_f32_bits(v) : (uint32_t)(int32_t)v, 4u);
    }
    case MC_CO_K_TELEM: return put(data, cap, len, mc_f32_bits(mc_telem_channel(&co->tm, e.arg)), 4u);
    default:
        if (e.index >= 0x1400u && e.index < 0x1C00u) {
            uint32_t v = 0u;
            const uint32_t a = mc_co_pdo_read(co, index, sub, &v);
            return a != 0u ? a : put(data, cap, len, v, type_size(e.type));
        }
        return hook_read(co, &e, data, cap, len);
    }
}

static uint32_t param_write(mc_co_t *co, int id, uint32_t w)
{
    const mc_param_info_t *e = &mc_param_table[id];
    const float v = e->type == MC_PT_F32 ? mc_bits_f32(w) : (float)(int32_t)w;
    if (e->type != MC_PT_F32 && (int32_t)w != (int32_t)v) {
        return MC_SDO_ABORT_VALUE;   /* not representable exactly */
    }
    if (v > e->max) {
        return MC_SDO_ABORT_VALUE_HIGH;
    }
    if (v < e->min) {
        return MC_SDO_ABORT_VALUE_LOW;
    }
    mc_param_err_t err;
    if (mc_drive_param_write(co->drive, id, v, &err)) {
        return 0u;
    }
    switch (err.kind) {
    case MC_PERR_ACCESS:
    case MC_PERR_BUSY: return MC_SDO_ABORT_STATE;
    case MC_PERR_RANGE: return err.value > err.max ? MC_SDO_ABORT_VALUE_HIGH : MC_SDO_ABORT_VALUE_LOW;
    case MC_PERR_UNKNOWN: return MC_SDO_ABORT_NO_OBJECT;
    default: return MC_SDO_ABORT_VALUE;   /* not finite, not integral, a cross-check, the model */
    }
}

static uint32_t store_write(mc_co_t *co, bool save, uint32_t w)
{
    if (w != (save ? MC_CO_SAVE_SIGNATURE : MC_CO_LOAD_SIGNATURE) || co->nvm == NULL) {
        return MC_SDO_ABORT_STORE;   /* §7.5.2.13: a wrong signature is not stored */
    }
    if (!outputs_off(co)) {
        return MC_SDO_ABORT_STATE;
    }
    uint8_t work[MC_CO_STORE_WORK];
    mc_pstore_status_t st;
    if (save) {
        const mc_drive_cfg_t cfg = {.p = mc_drive_cfgbuf_latest(&co->drive->link->cfg)->p, .est = co->drive->est};
        st = mc_pstore_save(co->nvm, &cfg, work, sizeof work, NULL);
    } else {
        st = mc_pstore_erase(co->nvm, work, sizeof work);
    }
    co->store_status = (uint32_t)st;
    if (st == MC_PSTORE_OK || st == MC_PSTORE_MAP_DROPPED) {
        return 0u;
    }
    const uint8_t info[5] = {(uint8_t)st, 0u, 0u, 0u, 0u};
    mc_co_emcy_send(co, MC_EMCY_NVM, 0x01u, info);
    return st == MC_PSTORE_NVM_ERROR ? MC_SDO_ABORT_HW : MC_SDO_ABORT_STORE;
}

static uint32_t hook_write(mc_co_t *co, const mc_co_entry_t *e, uint32_t w)
{
    switch (e->arg) {
    case H_HIST:
        if (w != 0u) {
            return MC_SDO_ABORT_VALUE;   /* §7.5.2.3: only 0 (clear) may be written */
        }
        co->err_count = 0u;
        return 0u;
    case H_SYNC:
        if ((w & 0x40000000u) != 0u || (w & 0x20000000u) != 0u || (w & 0x1FFFF800u) != 0u) {
            return MC_SDO_ABORT_VALUE;   /* SYNC producer, 29-bit ids: not supported */
        }
        co->cob_sync = w & 0x7FFu;
        return 0u;
    case H_STORE: return store_write(co, true, w);
    case H_RESTORE: return store_write(co, false, w);
    case H_SCOPE_CTRL:
        if (w == 1u) {
            const mc_scope_err_t err = mc_scope_arm(co->scope, &co->scope_cfg);
            if (err != MC_SCOPE_OK) {
                return err == MC_SCOPE_ERR_BUSY ? MC_SDO_ABORT_STATE : MC_SDO_ABORT_VALUE;
            }
        } else if (w == 2u) {
            mc_scope_force(co->scope);
        } else {
            mc_scope_stop(co->scope);
        }
        co->scope_ctrl = (uint8_t)w;
        return 0u;
    default: return MC_SDO_ABORT_READ_ONLY;
    }
}

/* Values a range cannot say. */
static uint32_t field_check(const mc_co_entry_t *e, int64_t v)
{
    switch (e->index) {
    case 0x6060u: return mc_402_mode_supported((int8_t)v) ? 0u : MC_SDO_ABORT_VALUE;
    default: return 0u;
    }
}

uint32_t mc_co_od_write(mc_co_t *co, uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len)
{
    mc_co_entry_t e;
    bool miss;
    if (!mc_co_od_lookup(index, sub, &e, &miss) || (is_scope(index) && co->scope == NULL)) {
        return miss ? MC_SDO_ABORT_NO_SUB : MC_SDO_ABORT_NO_OBJECT;
    }
    if (e.access == MC_CO_RO || e.access == MC_CO_CONST) {
        return MC_SDO_ABORT_READ_ONLY;
    }
    const uint32_t n = type_size(e.type);
    if (len != n) {
        return len > n ? MC_SDO_ABORT_LENGTH_HIGH : MC_SDO_ABORT_LENGTH_LOW;
    }
    uint32_t w = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        w |= (uint32_t)data[k] << (8u * k);
    }
    if ((e.flags & MC_CO_F_PREOP) != 0u && co->nmt == MC_NMT_OPERATIONAL) {
        return MC_SDO_ABORT_STATE;
    }
    if (e.kind == MC_CO_K_PARAM) {
        return param_write(co, e.arg, w);
    }
    if (e.index >= 0x1400u && e.index < 0x1C00u) {
        return mc_co_pdo_write(co, index, sub, w);
    }
    if (e.type == MC_CO_REAL32) {
        if ((w & 0x7F800000u) == 0x7F800000u) {   /* Inf or NaN */
            return MC_SDO_ABORT_VALUE;
        }
    } else {
        int64_t v = (int64_t)w;
        if (is_signed(e.type)) {   /* sign-extend from the type's width */
            const uint32_t shift = 32u - 8u * n;
            v = (int64_t)((int32_t)(w << shift) >> shift);
        }
        if (v > e.max) {
            return MC_SDO_ABORT_VALUE_HIGH;
        }
        if (v < e.min) {
            return MC_SDO_ABORT_VALUE_LOW;
        }
        const uint32_t a = field_check(&e, v);
        if (a != 0u) {
            return a;
        }
    }
    if (e.kind == MC_CO_K_HOOK) {
        return hook_write(co, &e, w);
    }
    field_set(co, &e, w);
    return 0u;
}

uint32_t mc_co_od_domain_size(const mc_co_t *co, uint16_t index, uint8_t sub)
{
    return (index == 0x2307u && sub == 0u && co->scope != NULL) ? mc_scope_data_size(co->scope) : 0u;
}

uint32_t mc_co_od_domain_read(const mc_co_t *co, uint16_t index, uint8_t sub, uint32_t offset, uint8_t *dst,
                              uint32_t n)
{
    return (index == 0x2307u && sub == 0u && co->scope != NULL) ? mc_scope_read(co->scope, offset, dst, n) : 0u;
}
