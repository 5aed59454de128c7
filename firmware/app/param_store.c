/* The power-cut-safe configuration store on hal_nvm (mc/param_store.h). The records are written
 * and read as a stream of 32-bit words through the caller's small work buffer, in the exact
 * format of mc/store.h (the unit test compares them with mc_store_*_encode and decodes them with
 * mc_store_*_decode), so that no 13.5 KB buffer is ever needed. */
#include "mc/param_store.h"
#include <string.h>
#include "mc/bits.h"

#define HEAD_BYTES 32u           /* 8 words */
#define PIECE      32u           /* stack buffer for read-back comparisons */

/* Where the parts of a copy sit on this device [bytes from the slot's start]. */
typedef struct {
    uint32_t block_size, unit, align;   /* align = max(unit, 8): every part starts on it  */
    uint32_t first[2], blocks;          /* each slot's first block, blocks per slot         */
    uint32_t mark_at, payload_at;       /* header at 0, marker, payload                     */
    uint32_t payload_cap;               /* payload bytes a slot holds, a multiple of align  */
    uint32_t chunk;                     /* work bytes per NVM call, a multiple of align     */
} geom_t;

typedef struct {
    uint32_t seq, flags, params_len, model_len, payload_crc, format;
    bool sane;                          /* magic, format, CRC, flags and lengths check      */
    bool marked;                        /* the commit marker is complete                    */
} head_t;

typedef enum { COPY_OK = 0, COPY_BAD, COPY_IO } copy_t;   /* IO: a read failed, nothing known */

typedef struct {
    int slot;                           /* the copy a load returns, -1: none                */
    bool fell_back;
    uint32_t seq_next;                  /* above every sane header                          */
    head_t head[2];
    mc_store_report_t rep;              /* what the returned copy's parameter record gave    */
} pick_t;

static uint32_t round_up(uint32_t x, uint32_t a)
{
    return (x + a - 1u) / a * a;
}

static uint32_t get32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static void put32(uint8_t *b, uint32_t w)
{
    b[0] = (uint8_t)w;
    b[1] = (uint8_t)(w >> 8);
    b[2] = (uint8_t)(w >> 16);
    b[3] = (uint8_t)(w >> 24);
}

/* CRC-32 (mc_crc32's: IEEE 802.3, reflected) continued over more bytes: start 0xFFFFFFFF, the
 * CRC is the complement of the end state. A nibble table: the whole copy is checked twice per
 * save and per load, 16x fewer steps than bitwise at 64 bytes of constants. */
static uint32_t crc_add(uint32_t c, const uint8_t *d, uint32_t n)
{
    static const uint32_t t[16] = {0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
                                   0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
                                   0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};
    for (uint32_t k = 0u; k < n; ++k) {
        c ^= d[k];
        c = (c >> 4) ^ t[c & 15u];
        c = (c >> 4) ^ t[c & 15u];
    }
    return c;
}

/* The marker's bytes: both 0 and 1 bits in each, so that neither an erased unit nor a scrambled
 * or half-programmed one reads as the marker. */
static uint8_t mark_byte(uint32_t k)
{
    return (k & 1u) != 0u ? 0xA5u : 0x5Au;
}

static uint32_t model_len(const mc_flux_map_t *map)
{
    return map != NULL ? 4u * (14u + 2u * (uint32_t)map->n_d * (uint32_t)map->n_q) : 32u;
}

/* ---- geometry ---------------------------------------------------------------------------- */

static mc_pstore_status_t geometry(const hal_nvm_t *nvm, geom_t *g)
{
    const uint32_t blocks = hal_nvm_blocks(nvm);
    g->block_size = hal_nvm_block_size(nvm);
    g->unit = hal_nvm_write_unit(nvm);
    if (g->unit == 0u || (g->unit & (g->unit - 1u)) != 0u || g->unit > 4096u || g->block_size == 0u ||
        g->block_size % g->unit != 0u) {
        return MC_PSTORE_BAD_ARGS;
    }
    g->align = g->unit > 8u ? g->unit : 8u;
    g->mark_at = round_up(HEAD_BYTES, g->unit);
    g->payload_at = g->mark_at + g->align;
    /* as many blocks as the largest copy needs (fewer erases), at most half the device */
    const uint32_t largest = g->payload_at + round_up(MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX, g->align);
    const uint32_t need = (largest + g->block_size - 1u) / g->block_size;
    g->blocks = blocks / 2u < need ? blocks / 2u : need;
    g->first[0] = 0u;
    g->first[1] = blocks / 2u;
    const uint32_t slot_bytes = g->blocks * g->block_size;   /* <= largest + block_size: no overflow */
    g->payload_cap = slot_bytes > g->payload_at ? (slot_bytes - g->payload_at) / g->align * g->align : 0u;
    g->chunk = 0u;
    /* the smallest set: the parameter record and the model without a map */
    if (g->blocks == 0u || g->payload_cap < round_up(MC_STORE_PARAMS_MAX + model_len(NULL), g->align)) {
        return MC_PSTORE_TOO_LARGE;
    }
    return MC_PSTORE_OK;
}

/* geometry() plus the work buffer: it takes a header and marker in one read, and is used in
 * whole multiples of the alignment. */
static mc_pstore_status_t setup(const hal_nvm_t *nvm, size_t work_len, geom_t *g)
{
    const mc_pstore_status_t st = geometry(nvm, g);
    if (st != MC_PSTORE_OK) {
        return st;
    }
    const uint32_t w = work_len > 0x10000u ? 0x10000u : (uint32_t)work_len;
    if (w < MC_PSTORE_WORK_MIN || w < g->payload_at) {
        return MC_PSTORE_BAD_ARGS;
    }
    g->chunk = w / g->align * g->align;
    return MC_PSTORE_OK;
}

mc_pstore_status_t mc_pstore_geometry(const hal_nvm_t *nvm, mc_pstore_geom_t *geom)
{
    if (nvm == NULL || geom == NULL) {
        return MC_PSTORE_BAD_ARGS;
    }
    geom_t g;
    const mc_pstore_status_t st = geometry(nvm, &g);
    memset(geom, 0, sizeof *geom);
    if (st == MC_PSTORE_BAD_ARGS) {
        return st;
    }
    geom->slot_first[0] = g.first[0];
    geom->slot_first[1] = g.first[1];
    geom->slot_blocks = g.blocks;
    geom->payload_max = g.payload_cap;
    if (st != MC_PSTORE_OK) {
        return st;
    }
    /* a map of c points: the parameter record, 14 words, 2 c words (payload_cap is aligned) */
    uint32_t cells = 0u;
    if (g.payload_cap >= MC_STORE_PARAMS_MAX + 4u * 14u + 8u * 4u) {
        cells = (g.payload_cap - MC_STORE_PARAMS_MAX - 4u * 14u) / 8u;
    }
    const uint32_t all = (uint32_t)MC_FLUX_MAP_MAX * (uint32_t)MC_FLUX_MAP_MAX;
    geom->map_cells_max = cells < all ? cells : all;
    return cells >= all ? MC_PSTORE_OK : MC_PSTORE_MAP_DROPPED;
}

/* ---- slot I/O: a slot's bytes span its blocks ---------------------------------------------- */

static bool slot_read(const hal_nvm_t *nvm, const geom_t *g, int slot, uint32_t off, uint8_t *d, uint32_t len)
{
    while (len > 0u) {   /* each pass takes at least one byte: at most len passes */
        const uint32_t in = off % g->block_size;
        const uint32_t n = g->block_size - in < len ? g->block_size - in : len;
        if (!hal_nvm_read(nvm, g->first[slot] + off / g->block_size, in, d, n)) {
            return false;
        }
        off += n;
        d += n;
        len -= n;
    }
    return true;
}

/* off and len multiples of the unit, so each piece (split at a block's end) is too */
static bool slot_write(hal_nvm_t *nvm, const geom_t *g, int slot, uint32_t off, const uint8_t *d, uint32_t len)
{
    while (len > 0u) {
        const uint32_t in = off % g->block_size;
        const uint32_t n = g->block_size - in < len ? g->block_size - in : len;
        if (!hal_nvm_write(nvm, g->first[slot] + off / g->block_size, in, d, n)) {
            return false;
        }
        off += n;
        d += n;
        len -= n;
    }
    return true;
}

/* The slot holds exactly d[0..len) at off (d NULL: erased bytes, 0xFF). */
static bool slot_same(const hal_nvm_t *nvm, const geom_t *g, int slot, uint32_t off, const uint8_t *d, uint32_t len)
{
    uint8_t piece[PIECE];
    for (uint32_t k = 0u; k < len; k += PIECE) {
        const uint32_t n = len - k < PIECE ? len - k : PIECE;
        if (!slot_read(nvm, g, slot, off + k, piece, n)) {
            return false;
        }
        for (uint32_t j = 0u; j < n; ++j) {
            if (piece[j] != (d != NULL ? d[k + j] : 0xFFu)) {
                return false;
            }
        }
    }
    return true;
}

/* ---- streaming the records out: write them, or compare them with the slot ------------------ */

typedef enum { SINK_WRITE, SINK_VERIFY } sink_mode_t;

typedef struct {
    hal_nvm_t *nvm;
    const geom_t *g;
    int slot;
    sink_mode_t mode;
    uint8_t *buf;                 /* the work buffer: g->chunk bytes                       */
    uint32_t fill, at;            /* bytes in buf; payload offset of buf[0]                */
    uint32_t rec, pay;            /* CRC states: the current record, the whole payload     */
    bool ok;                      /* false after a failed call or a difference: stop there */
} sink_t;

static void sink_flush(sink_t *s, bool last)
{
    uint32_t n = s->fill;
    if (last) {
        while (n % s->g->align != 0u) {   /* fill < chunk here, chunk a multiple of align */
            s->buf[n++] = 0xFFu;
        }
    }
    const uint32_t off = s->g->payload_at + s->at;
    if (!s->ok || n == 0u) {
        /* after a failure the records still run to their end (the buffer is reused), no I/O */
    } else if (s->at + n > s->g->payload_cap) {
        s->ok = false;   /* the caller checked the size: never, but never beyond the slot either */
    } else if (s->mode == SINK_WRITE) {
        s->ok = slot_write(s->nvm, s->g, s->slot, off, s->buf, n);
    } else {
        s->ok = slot_same(s->nvm, s->g, s->slot, off, s->buf, n);
    }
    s->at += n;
    s->fill = 0u;
}

static void sink_word(sink_t *s, uint32_t w, bool in_pay)
{
    uint8_t *b = s->buf + s->fill;
    put32(b, w);
    s->rec = crc_add(s->rec, b, 4u);
    if (in_pay) {
        s->pay = crc_add(s->pay, b, 4u);
    }
    s->fill += 4u;
    if (s->fill == s->g->chunk) {
        sink_flush(s, false);
    }
}

static void sink_put(sink_t *s, uint32_t w)
{
    sink_word(s, w, true);
}

/* a record ends with the CRC-32 of its words before (the same as mc_crc32 over them); that word
 * stays out of the payload CRC (format 2): a CRC run over data and then the data's own CRC ends
 * in a constant, so with it the payload CRC of valid records depended on their lengths only and
 * records spliced from two saves passed */
static void sink_close(sink_t *s)
{
    sink_word(s, ~s->rec, false);
    s->rec = 0xFFFFFFFFu;
}

/* mc_store_params_encode's record */
static void put_params(sink_t *s, const mc_params_t *p)
{
    sink_put(s, MC_STORE_MAGIC_PARAMS);
    sink_put(s, MC_STORE_PARAMS_VERSION);
    sink_put(s, mc_params_table_hash());
    sink_put(s, (uint32_t)MC_PARAM_COUNT);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        sink_put(s, mc_store_param_key(id) | (mc_param_is_auto(p, id) ? MC_STORE_KEY_AUTO : 0u));
        sink_put(s, mc_f32_bits(mc_param_get(p, id)));
    }
    sink_close(s);
}

/* mc_store_model_encode's record, with map (NULL: none) in place of m->map */
static void put_model(sink_t *s, const mc_est_model_t *m, const mc_flux_map_t *map)
{
    sink_put(s, MC_STORE_MAGIC_MODEL);
    sink_put(s, MC_STORE_VERSION);
    sink_put(s, mc_f32_bits(m->rs));
    sink_put(s, mc_f32_bits(m->ld));
    sink_put(s, mc_f32_bits(m->lq));
    sink_put(s, mc_f32_bits(m->psi_pm));
    sink_put(s, map != NULL ? 1u : 0u);
    if (map != NULL) {
        const uint32_t cells = (uint32_t)map->n_d * (uint32_t)map->n_q;
        sink_put(s, (uint32_t)map->n_d);
        sink_put(s, (uint32_t)map->n_q);
        sink_put(s, mc_f32_bits(map->id0));
        sink_put(s, mc_f32_bits(map->did));
        sink_put(s, mc_f32_bits(map->iq0));
        sink_put(s, mc_f32_bits(map->diq));
        for (uint32_t k = 0u; k < cells; ++k) {
            sink_put(s, mc_f32_bits(map->psi_d[k]));
        }
        for (uint32_t k = 0u; k < cells; ++k) {
            sink_put(s, mc_f32_bits(map->psi_q[k]));
        }
    }
    sink_close(s);
}

/* The whole payload through the sink; its CRC into *crc. */
static bool put_payload(hal_nvm_t *nvm, const geom_t *g, int slot, sink_mode_t mode, uint8_t *work,
                        const mc_params_t *p, const mc_est_model_t *m, const mc_flux_map_t *map, uint32_t *crc)
{
    sink_t s = {nvm, g, slot, mode, work, 0u, 0u, 0xFFFFFFFFu, 0xFFFFFFFFu, true};
    put_params(&s, p);
    put_model(&s, m, map);
    sink_flush(&s, true);
    *crc = ~s.pay;
    return s.ok;
}

/* ---- streaming the records in: check them (and decode into the caller's scratch) ---------- */

typedef struct {
    const hal_nvm_t *nvm;
    const geom_t *g;
    int slot;
    uint8_t *buf;
    uint32_t fill, pos;           /* bytes in buf, the next one to take                    */
    uint32_t at, left;            /* payload offset of the next read, bytes still unread    */
    uint32_t rec, pay;
    bool io_ok;
    bool pay_crcs;                /* format 1: the records' CRC words are in the payload CRC */
} src_t;

static bool src_word(src_t *r, uint32_t *w, bool in_pay)
{
    if (r->pos == r->fill) {
        if (r->left == 0u || !r->io_ok) {
            return false;   /* a record claiming more than the header's lengths */
        }
        const uint32_t n = r->left < r->g->chunk ? r->left : r->g->chunk;
        if (!slot_read(r->nvm, r->g, r->slot, r->g->payload_at + r->at, r->buf, n)) {
            r->io_ok = false;
            return false;
        }
        r->at += n;
        r->left -= n;
        r->fill = n;
        r->pos = 0u;
    }
    const uint8_t *b = r->buf + r->pos;   /* lengths are whole words: pos + 4 <= fill */
    r->pos += 4u;
    r->rec = crc_add(r->rec, b, 4u);
    if (in_pay) {
        r->pay = crc_add(r->pay, b, 4u);
    }
    *w = get32(b);
    return true;
}

static bool src_take(src_t *r, uint32_t *w)
{
    return src_word(r, w, true);
}

static copy_t src_fail(const src_t *r)
{
    return r->io_ok ? COPY_BAD : COPY_IO;
}

static copy_t src_crc(src_t *r)
{
    const uint32_t want = ~r->rec;
    uint32_t w;
    if (!src_word(r, &w, r->pay_crcs)) {
        return src_fail(r);
    }
    r->rec = 0xFFFFFFFFu;
    return w == want ? COPY_OK : COPY_BAD;
}

/* What mc_store_params_decode accepts, exactly len bytes, into the scratch q; and a version 1
 * record (the frozen table's positions turned into keys, mc/store.h), so that a set stored before
 * the by-name format is migrated the same way. */
static copy_t get_params(src_t *r, uint32_t len, mc_params_t *q, mc_store_report_t *rep)
{
    uint32_t h[4];
    for (int k = 0; k < 4; ++k) {
        if (!src_take(r, &h[k])) {
            return src_fail(r);
        }
    }
    const bool v1 = h[1] == 1u;
    if (h[0] != MC_STORE_MAGIC_PARAMS || !(v1 ? h[2] == MC_STORE_V1_TABLE : h[1] == MC_STORE_PARAMS_VERSION) ||
        h[3] > len / 8u || len != 4u * (5u + 2u * h[3])) {
        return COPY_BAD;
    }
    mc_store_report_clear(rep);
    rep->other_table = v1 || h[2] != mc_params_table_hash();
    mc_params_default(q);
    for (uint32_t k = 0u; k < h[3]; ++k) {
        uint32_t w, v;
        if (!src_take(r, &w) || !src_take(r, &v)) {
            return src_fail(r);
        }
        uint32_t hint = k;
        if (v1) {
            hint = w & ~MC_STORE_V1_AUTO;
            const uint32_t key = mc_store_v1_key(hint);
            if (key == 0u) {
                return COPY_BAD;
            }
            w = key | ((w & MC_STORE_V1_AUTO) != 0u ? MC_STORE_KEY_AUTO : 0u);
        }
        mc_store_param_apply(q, w, v, hint, rep);
    }
    return src_crc(r);
}

/* What mc_store_model_decode accepts, exactly len bytes, into m; the map into map_out (NULL:
 * checked only). */
static copy_t get_model(src_t *r, uint32_t len, mc_est_model_t *m, mc_flux_map_t *map_out)
{
    uint32_t h[7];
    for (int k = 0; k < 7; ++k) {
        if (!src_take(r, &h[k])) {
            return src_fail(r);
        }
    }
    if (h[0] != MC_STORE_MAGIC_MODEL || h[1] != MC_STORE_VERSION) {
        return COPY_BAD;
    }
    m->rs = mc_bits_f32(h[2]);
    m->ld = mc_bits_f32(h[3]);
    m->lq = mc_bits_f32(h[4]);
    m->psi_pm = mc_bits_f32(h[5]);
    m->map = NULL;
    if (h[6] == 0u) {
        return len == 32u ? src_crc(r) : COPY_BAD;
    }
    uint32_t g[6];
    for (int k = 0; k < 6; ++k) {
        if (!src_take(r, &g[k])) {
            return src_fail(r);
        }
    }
    const uint32_t nd = g[0], nq = g[1];
    if (nd < 2u || nq < 2u || nd > (uint32_t)MC_FLUX_MAP_MAX || nq > (uint32_t)MC_FLUX_MAP_MAX ||
        len != 4u * (14u + 2u * nd * nq)) {
        return COPY_BAD;
    }
    const uint32_t cells = nd * nq;
    for (uint32_t k = 0u; k < 2u * cells; ++k) {
        uint32_t w;
        if (!src_take(r, &w)) {
            return src_fail(r);
        }
        if (map_out != NULL) {
            float *dst = k < cells ? &map_out->psi_d[k] : &map_out->psi_q[k - cells];
            *dst = mc_bits_f32(w);
        }
    }
    if (map_out != NULL) {
        map_out->n_d = (int)nd;
        map_out->n_q = (int)nq;
        map_out->id0 = mc_bits_f32(g[2]);
        map_out->did = mc_bits_f32(g[3]);
        map_out->iq0 = mc_bits_f32(g[4]);
        map_out->diq = mc_bits_f32(g[5]);
        m->map = map_out;
    }
    return src_crc(r);
}

/* A copy whose header checks: its payload CRC and both records, decoded into q, m, map_out. */
static copy_t check_copy(const hal_nvm_t *nvm, const geom_t *g, int slot, const head_t *h, uint8_t *work,
                         mc_params_t *q, mc_est_model_t *m, mc_flux_map_t *map_out, mc_store_report_t *rep)
{
    mc_store_report_clear(rep);
    if ((h->flags & MC_PSTORE_FLAG_DEFAULTS) != 0u) {
        return COPY_OK;   /* nothing else in it (read_head checked the lengths are 0) */
    }
    src_t r = {nvm, g, slot, work, 0u, 0u, 0u, h->params_len + h->model_len, 0xFFFFFFFFu, 0xFFFFFFFFu, true,
               h->format == 1u};
    copy_t st = get_params(&r, h->params_len, q, rep);
    if (st == COPY_OK) {
        st = get_model(&r, h->model_len, m, map_out);
    }
    if (st != COPY_OK) {
        return st;
    }
    return r.left == 0u && r.pos == r.fill && ~r.pay == h->payload_crc ? COPY_OK : COPY_BAD;
}

/* ---- headers and the choice of a copy ---------------------------------------------------- */

static void head_bytes(const head_t *h, uint8_t *b)
{
    put32(b, MC_PSTORE_MAGIC);
    put32(b + 4, MC_PSTORE_FORMAT);
    put32(b + 8, h->seq);
    put32(b + 12, h->flags);
    put32(b + 16, h->params_len);
    put32(b + 20, h->model_len);
    put32(b + 24, h->payload_crc);
    put32(b + 28, ~crc_add(0xFFFFFFFFu, b, 28u));
}

static bool read_head(const hal_nvm_t *nvm, const geom_t *g, int slot, uint8_t *work, head_t *h)
{
    memset(h, 0, sizeof *h);
    if (!slot_read(nvm, g, slot, 0u, work, g->payload_at)) {
        return false;
    }
    h->marked = true;
    for (uint32_t k = 0u; k < g->align; ++k) {
        h->marked = h->marked && work[g->mark_at + k] == mark_byte(k);
    }
    h->seq = get32(work + 8);
    h->flags = get32(work + 12);
    h->params_len = get32(work + 16);
    h->model_len = get32(work + 20);
    h->payload_crc = get32(work + 24);
    h->format = get32(work + 4);   /* 1: written before the record CRCs left the payload CRC */
    const bool defaults = (h->flags & MC_PSTORE_FLAG_DEFAULTS) != 0u;
    const uint32_t cap = g->payload_cap;
    h->sane = get32(work) == MC_PSTORE_MAGIC && (h->format == MC_PSTORE_FORMAT || h->format == 1u) &&
              get32(work + 28) == ~crc_add(0xFFFFFFFFu, work, 28u) &&
              (h->flags & ~(MC_PSTORE_FLAG_DEFAULTS | MC_PSTORE_FLAG_NO_MAP)) == 0u &&
              (defaults ? h->params_len == 0u && h->model_len == 0u
                        : h->params_len % 4u == 0u && h->model_len % 4u == 0u && h->params_len <= cap &&
                              h->model_len <= cap - h->params_len);
    return true;
}

/* a newer than b, modulo 2^32 (a - b in [1, 2^31)) */
static bool newer(uint32_t a, uint32_t b)
{
    return a - b - 1u < 0x7FFFFFFFu;
}

/* The copy a load returns (the same choice for save and erase, so that they never write it):
 * the marked copies newest first (a marked one whose header does not check first: its sequence
 * is unknown), the first that checks. Decodes into the scratch q, m, map_out. */
static mc_pstore_status_t pick(const hal_nvm_t *nvm, const geom_t *g, uint8_t *work, mc_params_t *q,
                               mc_est_model_t *m, mc_flux_map_t *map_out, pick_t *pk)
{
    pk->slot = -1;
    pk->fell_back = false;
    mc_store_report_clear(&pk->rep);
    for (int s = 0; s < 2; ++s) {
        if (!read_head(nvm, g, s, work, &pk->head[s])) {
            return MC_PSTORE_NVM_ERROR;
        }
    }
    const head_t *h = pk->head;
    /* the next sequence number: above every header that checks, marked or not */
    uint32_t top = 0u;
    bool any = false;
    for (int s = 0; s < 2; ++s) {
        if (h[s].sane && (!any || newer(h[s].seq, top))) {
            top = h[s].seq;
            any = true;
        }
    }
    pk->seq_next = any ? top + 1u : 1u;

    int order[2], n = 0;
    for (int s = 0; s < 2; ++s) {
        if (h[s].marked) {
            order[n++] = s;
        }
    }
    if (n == 2 && ((h[0].sane && !h[1].sane) || (h[0].sane && h[1].sane && newer(h[1].seq, h[0].seq)))) {
        order[0] = 1;
        order[1] = 0;
    }
    for (int k = 0; k < n; ++k) {
        const int s = order[k];
        const copy_t c = h[s].sane ? check_copy(nvm, g, s, &h[s], work, q, m, map_out, &pk->rep) : COPY_BAD;
        if (c == COPY_IO) {
            /* never taken for "bad": a save would then overwrite the copy a load returns */
            return MC_PSTORE_NVM_ERROR;
        }
        if (c == COPY_OK) {
            pk->slot = s;
            pk->fell_back = k > 0;
            if ((h[s].flags & MC_PSTORE_FLAG_DEFAULTS) != 0u) {
                return MC_PSTORE_EMPTY;
            }
            return k > 0 ? MC_PSTORE_FELL_BACK : MC_PSTORE_OK;
        }
    }
    return n == 0 ? MC_PSTORE_EMPTY : MC_PSTORE_CORRUPT;
}

/* ---- commit ------------------------------------------------------------------------------ */

/* Write a copy with header h (its payload CRC filled here) into slot, verify it, then mark it.
 * p, m, map: the records (unused for a defaults copy); q, mm: scratch for the final check. */
static mc_pstore_status_t commit(hal_nvm_t *nvm, const geom_t *g, int slot, head_t *h, const mc_params_t *p,
                                 const mc_est_model_t *m, const mc_flux_map_t *map, uint8_t *work, mc_params_t *q,
                                 mc_est_model_t *mm)
{
    const bool defaults = (h->flags & MC_PSTORE_FLAG_DEFAULTS) != 0u;
    const uint32_t used = g->payload_at + round_up(h->params_len + h->model_len, g->align);
    const uint32_t nblk = (used + g->block_size - 1u) / g->block_size;
    /* the first block (header, marker) first: from then on the slot holds no committed copy */
    for (uint32_t b = 0u; b < nblk; ++b) {
        if (!hal_nvm_erase(nvm, g->first[slot] + b)) {
            return MC_PSTORE_NVM_ERROR;
        }
    }
    h->payload_crc = 0u;   /* CRC-32 of no bytes */
    if (!defaults && !put_payload(nvm, g, slot, SINK_WRITE, work, p, m, map, &h->payload_crc)) {
        return MC_PSTORE_NVM_ERROR;
    }
    memset(work, 0xFF, g->mark_at);
    head_bytes(h, work);
    if (!slot_write(nvm, g, slot, 0u, work, g->mark_at)) {
        return MC_PSTORE_NVM_ERROR;
    }
    /* read back before the marker: the header, the marker still erased, the payload bit-exact
     * against a second encoding, then the checks a load makes: only a copy that loads commits */
    uint8_t ref[HEAD_BYTES];
    head_bytes(h, ref);
    uint32_t crc2 = 0u;
    if (!slot_same(nvm, g, slot, 0u, ref, HEAD_BYTES) || !slot_same(nvm, g, slot, g->mark_at, NULL, g->align) ||
        (!defaults && (!put_payload(nvm, g, slot, SINK_VERIFY, work, p, m, map, &crc2) || crc2 != h->payload_crc))) {
        return MC_PSTORE_NVM_ERROR;
    }
    head_t back;
    if (!read_head(nvm, g, slot, work, &back)) {
        return MC_PSTORE_NVM_ERROR;
    }
    if (!back.sane || back.marked) {
        return MC_PSTORE_NVM_ERROR;
    }
    mc_store_report_t rep;
    const copy_t c = check_copy(nvm, g, slot, &back, work, q, mm, NULL, &rep);
    if (c == COPY_OK && (rep.dropped != 0u || rep.unknown != 0u)) {
        return MC_PSTORE_BAD_ARGS;   /* this table's own set reads back whole, or it is not committed */
    }
    if (c != COPY_OK) {
        /* read back bit-exact yet refused: the set itself is one a load would not take */
        return c == COPY_IO ? MC_PSTORE_NVM_ERROR : MC_PSTORE_BAD_ARGS;
    }
    for (uint32_t k = 0u; k < g->align; ++k) {
        work[k] = mark_byte(k);
    }
    if (!slot_write(nvm, g, slot, g->mark_at, work, g->align) || !slot_same(nvm, g, slot, g->mark_at, work, g->align)) {
        return MC_PSTORE_NVM_ERROR;
    }
    return MC_PSTORE_OK;
}

static bool map_ok(const mc_flux_map_t *map)
{
    return map->n_d >= 2 && map->n_q >= 2 && map->n_d <= MC_FLUX_MAP_MAX && map->n_q <= MC_FLUX_MAP_MAX;
}

/* The set as a load would decode it (get_params' checks on the values the record will hold),
 * so that a set a load would refuse is turned down before the older copy is erased. */
static bool params_ok(const mc_params_t *p, mc_params_t *q)
{
    mc_params_default(q);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (!mc_param_is_auto(p, id)) {
            const float x = mc_param_get(p, id);
            const mc_param_info_t *e = &mc_param_table[id];
            if (!(x >= e->min && x <= e->max) || !mc_param_set(q, id, x, NULL)) {
                return false;
            }
        }
    }
    return true;
}

static void info_clear(mc_pstore_info_t *info)
{
    if (info != NULL) {
        memset(info, 0, sizeof *info);
        info->slot = -1;
        mc_store_report_clear(&info->params);
    }
}

mc_pstore_status_t mc_pstore_save(hal_nvm_t *nvm, const mc_drive_cfg_t *cfg, uint8_t *work, size_t work_len,
                                  mc_pstore_info_t *info)
{
    info_clear(info);
    if (nvm == NULL || cfg == NULL || work == NULL) {
        return MC_PSTORE_BAD_ARGS;
    }
    geom_t g;
    mc_pstore_status_t st = setup(nvm, work_len, &g);
    if (st != MC_PSTORE_OK) {
        return st;
    }
    mc_params_t q;
    const mc_flux_map_t *map = cfg->est.map;
    if ((map != NULL && !map_ok(map)) || !params_ok(&cfg->p, &q)) {
        return MC_PSTORE_BAD_ARGS;
    }
    head_t h = {0u, 0u, MC_STORE_PARAMS_MAX, model_len(map), 0u, MC_PSTORE_FORMAT, false, false};
    if (round_up(h.params_len + h.model_len, g.align) > g.payload_cap) {
        map = NULL;   /* too big for a slot: the set without its map (geometry() saw that fits) */
        h.model_len = model_len(NULL);
        h.flags |= MC_PSTORE_FLAG_NO_MAP;
    }
    mc_est_model_t m;
    pick_t pk;
    st = pick(nvm, &g, work, &q, &m, NULL, &pk);
    if (st == MC_PSTORE_NVM_ERROR) {
        return st;
    }
    const int slot = pk.slot >= 0 ? 1 - pk.slot : 0;   /* never the copy a load returns */
    h.seq = pk.seq_next;
    st = commit(nvm, &g, slot, &h, &cfg->p, &cfg->est, map, work, &q, &m);
    if (st != MC_PSTORE_OK) {
        return st;
    }
    if (info != NULL) {
        info->slot = slot;
        info->seq = h.seq;
        info->map_dropped = (h.flags & MC_PSTORE_FLAG_NO_MAP) != 0u;
    }
    return (h.flags & MC_PSTORE_FLAG_NO_MAP) != 0u ? MC_PSTORE_MAP_DROPPED : MC_PSTORE_OK;
}

mc_pstore_status_t mc_pstore_load(const hal_nvm_t *nvm, mc_drive_cfg_t *cfg, mc_flux_map_t *map_out, uint8_t *work,
                                  size_t work_len, mc_pstore_info_t *info)
{
    info_clear(info);
    if (nvm == NULL || cfg == NULL || work == NULL) {
        return MC_PSTORE_BAD_ARGS;
    }
    geom_t g;
    mc_pstore_status_t st = setup(nvm, work_len, &g);
    if (st != MC_PSTORE_OK) {
        return st;
    }
    mc_params_t q;
    mc_est_model_t m;
    pick_t pk;
    st = pick(nvm, &g, work, &q, &m, map_out, &pk);
    if (st == MC_PSTORE_OK || st == MC_PSTORE_FELL_BACK) {
        cfg->p = q;
        cfg->est = m;
        if (pk.rep.dropped != 0u) {
            st = MC_PSTORE_PARTIAL;
        }
    }
    if (info != NULL && pk.slot >= 0) {
        const head_t *h = &pk.head[pk.slot];
        info->slot = pk.slot;
        info->seq = h->seq;
        info->defaults = (h->flags & MC_PSTORE_FLAG_DEFAULTS) != 0u;
        info->map_dropped = (h->flags & MC_PSTORE_FLAG_NO_MAP) != 0u;
        info->fell_back = pk.fell_back;
        info->params = pk.rep;
    }
    return st;
}

mc_pstore_status_t mc_pstore_erase(hal_nvm_t *nvm, uint8_t *work, size_t work_len)
{
    if (nvm == NULL || work == NULL) {
        return MC_PSTORE_BAD_ARGS;
    }
    geom_t g;
    mc_pstore_status_t st = setup(nvm, work_len, &g);
    if (st != MC_PSTORE_OK) {
        return st;
    }
    mc_params_t q;
    mc_est_model_t m;
    pick_t pk;
    st = pick(nvm, &g, work, &q, &m, NULL, &pk);
    if (st == MC_PSTORE_NVM_ERROR) {
        return st;
    }
    /* first a committed "defaults" copy (atomic by its marker, like a save) ... */
    const int slot = pk.slot >= 0 ? 1 - pk.slot : 0;
    head_t h = {pk.seq_next, MC_PSTORE_FLAG_DEFAULTS, 0u, 0u, 0u, MC_PSTORE_FORMAT, false, false};
    st = commit(nvm, &g, slot, &h, NULL, NULL, NULL, work, &q, &m);
    if (st != MC_PSTORE_OK) {
        return st;
    }
    /* ... then the old set goes, so that it cannot come back should the defaults copy ever be
     * damaged; a cut here leaves the defaults copy newest: EMPTY */
    for (uint32_t b = 0u; b < g.blocks; ++b) {
        if (!hal_nvm_erase(nvm, g.first[1 - slot] + b)) {
            return MC_PSTORE_NVM_ERROR;
        }
    }
    return MC_PSTORE_OK;
}

const char *mc_pstore_status_name(mc_pstore_status_t s)
{
    static const char *const names[] = {"ok",        "empty",     "fell_back", "corrupt",  "nvm_error",
                                        "too_large", "bad_args",  "map_dropped", "partial"};
    return (unsigned)s < sizeof names / sizeof names[0] ? names[s] : "?";
}
