/* The parameter store on hal_nvm (mc/nvstore.h). */
#include "mc/nvstore.h"
#include <string.h>

typedef struct {
    uint32_t unit, block_size, hdr, rec_at, cap;   /* geometry of one copy [bytes]          */
    uint32_t block[2];                             /* the block of each slot                 */
} geom_t;

typedef struct {
    bool committed;     /* marker present and the header checks                             */
    uint32_t seq, len;
} copy_t;

static uint32_t round_up(uint32_t x, uint32_t u)
{
    return (x + u - 1u) / u * u;
}

static void put32(uint8_t *b, uint32_t w)
{
    b[0] = (uint8_t)w;
    b[1] = (uint8_t)(w >> 8);
    b[2] = (uint8_t)(w >> 16);
    b[3] = (uint8_t)(w >> 24);
}

static uint32_t get32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static mc_nvstore_status_t geometry(const hal_nvm_t *nvm, size_t work_len, geom_t *g)
{
    const uint32_t blocks = hal_nvm_blocks(nvm);
    g->unit = hal_nvm_write_unit(nvm);
    g->block_size = hal_nvm_block_size(nvm);
    if (g->unit == 0u || g->unit > 64u || work_len < MC_NVSTORE_WORK) {
        return MC_NVSTORE_BAD_ARGS;
    }
    g->hdr = round_up(20u, g->unit);
    g->rec_at = g->hdr + g->unit;
    if (blocks < 2u || g->block_size < g->rec_at + round_up(MC_STORE_PARAMS_MAX, g->unit)) {
        return MC_NVSTORE_TOO_SMALL;
    }
    g->cap = g->block_size - g->rec_at;
    g->block[0] = 0u;
    g->block[1] = blocks / 2u;
    return MC_NVSTORE_OK;
}

/* Marker and header of a slot (work: scratch of at least hdr + unit bytes). */
static bool read_copy(const hal_nvm_t *nvm, const geom_t *g, int slot, uint8_t *work, copy_t *c)
{
    c->committed = false;
    if (!hal_nvm_read(nvm, g->block[slot], 0u, work, g->rec_at)) {
        return false;
    }
    for (uint32_t k = 0u; k < g->unit; ++k) {
        if (work[g->hdr + k] != MC_NVSTORE_COMMIT) {
            return true;   /* no marker: not committed (erased, or cut before the marker completed) */
        }
    }
    c->seq = get32(work + 8);
    c->len = get32(work + 12);
    c->committed = get32(work) == MC_NVSTORE_MAGIC && get32(work + 4) == MC_NVSTORE_FORMAT &&
                   get32(work + 16) == mc_crc32(work, 16u) && c->len <= g->cap;
    return true;
}

/* A committed copy's record decoded into p: OK, or a reason it does not check. len 0: the
 * "defaults" copy (EMPTY). */
static mc_nvstore_status_t decode_copy(const hal_nvm_t *nvm, const geom_t *g, int slot, const copy_t *c, uint8_t *work,
                                       size_t work_len, mc_params_t *p)
{
    if (c->len == 0u) {
        return MC_NVSTORE_EMPTY;
    }
    if (c->len > work_len || !hal_nvm_read(nvm, g->block[slot], g->rec_at, work, c->len)) {
        return MC_NVSTORE_CORRUPT;
    }
    return mc_store_params_decode(work, c->len, p) == MC_STORE_OK ? MC_NVSTORE_OK : MC_NVSTORE_CORRUPT;
}

/* Which slot the loader would take (-1: none) and the highest committed sequence. */
static mc_nvstore_status_t pick(const hal_nvm_t *nvm, const geom_t *g, uint8_t *work, size_t work_len, mc_params_t *p,
                                int *slot_out, uint32_t *seq_out, uint32_t *seq_max)
{
    copy_t c[2];
    for (int s = 0; s < 2; ++s) {
        if (!read_copy(nvm, g, s, work, &c[s])) {
            return MC_NVSTORE_NVM_ERROR;
        }
    }
    *slot_out = -1;
    *seq_max = 0u;
    bool any = false;
    for (int s = 0; s < 2; ++s) {
        if (c[s].committed && (!any || c[s].seq > *seq_max)) {
            *seq_max = c[s].seq;
        }
        any = any || c[s].committed;
    }
    if (!any) {
        return MC_NVSTORE_EMPTY;
    }
    /* newest first; a sequence wraps only after 2^32 saves */
    const int first = (c[0].committed && (!c[1].committed || c[0].seq > c[1].seq)) ? 0 : 1;
    for (int k = 0; k < 2; ++k) {
        const int s = k == 0 ? first : 1 - first;
        if (!c[s].committed) {
            continue;
        }
        mc_params_t q = *p;
        const mc_nvstore_status_t st = decode_copy(nvm, g, s, &c[s], work, work_len, &q);
        if (st == MC_NVSTORE_OK || st == MC_NVSTORE_EMPTY) {
            *slot_out = s;
            *seq_out = c[s].seq;
            if (st == MC_NVSTORE_OK) {
                *p = q;
            }
            return st == MC_NVSTORE_EMPTY ? MC_NVSTORE_EMPTY : (k == 0 ? MC_NVSTORE_OK : MC_NVSTORE_FELL_BACK);
        }
    }
    return MC_NVSTORE_CORRUPT;
}

mc_nvstore_status_t mc_nvstore_load(const hal_nvm_t *nvm, mc_params_t *p, uint8_t *work, size_t work_len,
                                    uint32_t *seq)
{
    if (nvm == NULL || p == NULL || work == NULL) {
        return MC_NVSTORE_BAD_ARGS;
    }
    geom_t g;
    mc_nvstore_status_t st = geometry(nvm, work_len, &g);
    if (st != MC_NVSTORE_OK) {
        return st;
    }
    int slot;
    uint32_t s = 0u, smax;
    mc_params_t q = *p;
    st = pick(nvm, &g, work, work_len, &q, &slot, &s, &smax);
    if (st == MC_NVSTORE_OK || st == MC_NVSTORE_FELL_BACK) {
        *p = q;
    }
    if (seq != NULL) {
        *seq = s;
    }
    return st;
}

/* A copy of len record bytes (already in work, padded with 0xFF to the unit) into the slot the
 * loader would not take, committed by its marker after a read-back check. */
static mc_nvstore_status_t commit(hal_nvm_t *nvm, uint8_t *work, size_t work_len, uint32_t len)
{
    geom_t g;
    mc_nvstore_status_t st = geometry(nvm, work_len, &g);
    if (st != MC_NVSTORE_OK) {
        return st;
    }
    const uint32_t padded = round_up(len, g.unit);
    if (padded > g.cap || padded + g.rec_at > work_len) {
        return MC_NVSTORE_TOO_SMALL;
    }
    /* the record goes to the end of the work buffer while pick() uses its start */
    uint8_t *rec = work + work_len - padded;
    memmove(rec, work, len);
    memset(rec + len, 0xFF, padded - len);
    mc_params_t scratch;
    mc_params_default(&scratch);
    int keep;
    uint32_t seq = 0u, smax = 0u;
    st = pick(nvm, &g, work, work_len - padded, &scratch, &keep, &seq, &smax);
    if (st == MC_NVSTORE_NVM_ERROR) {
        return st;
    }
    const int slot = keep == 0 ? 1 : 0;   /* never the copy a load would return */
    const uint32_t blk = g.block[slot];
    if (!hal_nvm_erase(nvm, blk) || (padded > 0u && !hal_nvm_write(nvm, blk, g.rec_at, rec, padded))) {
        return MC_NVSTORE_NVM_ERROR;
    }
    uint8_t hdr[64 + 32];
    memset(hdr, 0xFF, sizeof hdr);
    put32(hdr, MC_NVSTORE_MAGIC);
    put32(hdr + 4, MC_NVSTORE_FORMAT);
    put32(hdr + 8, smax + 1u);
    put32(hdr + 12, len);
    put32(hdr + 16, mc_crc32(hdr, 16u));
    if (!hal_nvm_write(nvm, blk, 0u, hdr, g.hdr)) {
        return MC_NVSTORE_NVM_ERROR;
    }
    /* read back before the marker: a copy that does not check is never committed */
    uint8_t back[64 + 32];
    if (!hal_nvm_read(nvm, blk, 0u, back, g.hdr) || memcmp(back, hdr, g.hdr) != 0) {
        return MC_NVSTORE_NVM_ERROR;
    }
    for (uint32_t at = 0u; at < padded; at += g.unit) {
        if (!hal_nvm_read(nvm, blk, g.rec_at + at, back, g.unit) || memcmp(back, rec + at, g.unit) != 0) {
            return MC_NVSTORE_NVM_ERROR;
        }
    }
    uint8_t mark[64];
    memset(mark, MC_NVSTORE_COMMIT, sizeof mark);
    return hal_nvm_write(nvm, blk, g.hdr, mark, g.unit) ? MC_NVSTORE_OK : MC_NVSTORE_NVM_ERROR;
}

mc_nvstore_status_t mc_nvstore_save(hal_nvm_t *nvm, const mc_params_t *p, uint8_t *work, size_t work_len)
{
    if (nvm == NULL || p == NULL || work == NULL || work_len < MC_NVSTORE_WORK) {
        return MC_NVSTORE_BAD_ARGS;
    }
    const size_t len = mc_store_params_encode(p, work, MC_STORE_PARAMS_MAX);
    if (len == 0u) {
        return MC_NVSTORE_BAD_ARGS;
    }
    return commit(nvm, work, work_len, (uint32_t)len);
}

mc_nvstore_status_t mc_nvstore_restore_defaults(hal_nvm_t *nvm, uint8_t *work, size_t work_len)
{
    if (nvm == NULL || work == NULL || work_len < MC_NVSTORE_WORK) {
        return MC_NVSTORE_BAD_ARGS;
    }
    return commit(nvm, work, work_len, 0u);
}

const char *mc_nvstore_status_name(mc_nvstore_status_t s)
{
    static const char *const names[] = {"ok", "empty", "fell_back", "corrupt", "nvm_error", "too_small", "bad_args"};
    return (unsigned)s < sizeof names / sizeof names[0] ? names[s] : "?";
}
