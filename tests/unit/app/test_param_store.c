/* The power-cut-safe configuration store (mc/param_store.h) on the host NVM, every test with two
 * flash maps: the host's 4 x 4 KiB (unit 8: two slots of 2 blocks, maps up to 914 points; the
 * largest 41 x 41 map is dropped there and that path is tested too) and the LaunchPad's
 * S25FL128S as the AM263x port places the store (2 x 64 KiB sectors at 0x7E0000: a slot of one
 * sector, every map fits): the records on flash are mc/store.h's, bit for bit; round trip;
 * erased NVM; fall-back; and the power-cut sweeps: from a committed set, a cut at EVERY step of
 * a save (and of an erase) leaves exactly the old set or the new one, never a mix, never
 * "corrupt" or "empty", and a later save still works. Last, an erase the flash did not carry
 * out (skipped, or a 4 KiB erase in a 64 KiB sector) fails the save and keeps the old set. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/bits.h"
#include "mc/param_store.h"
#include "pstore_same.h"

/* large objects (the NVM, 13.5 KB maps) static: test state, not firmware */
static hal_nvm_t nvm, snap;
static uint8_t work[MC_PSTORE_WORK_MIN];   /* the smallest work buffer: the sweeps use it */
enum { NSETS = 10 };
static bool s25fl;   /* the group's map: false the host's 4 x 4 KiB, true the S25FL128S */
static uint32_t s1;  /* slot 1's first block */

static void nvm_init(hal_nvm_t *n)
{
    if (s25fl) {
        assert_true(hal_host_nvm_init_geom(n, &hal_host_nvm_s25fl128s, 0x7E0000u, 2u));
    } else {
        hal_host_nvm_init(n);
    }
    s1 = hal_nvm_blocks(n) / 2u;
}

static uint8_t *blk(hal_nvm_t *n, uint32_t b)
{
    return &n->mem[b * n->block_size];
}
static uint32_t le32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}
static void put_le32(uint8_t *b, uint32_t w)
{
    for (int k = 0; k < 4; ++k) {
        b[k] = (uint8_t)(w >> (8 * k));
    }
}
static mc_flux_map_t maps[NSETS];
static mc_drive_cfg_t sets[NSETS];
static mc_flux_map_t got_map;
static uint8_t rec[MC_STORE_MODEL_MAX];

/* Set k: a few parameters moved, the model's scalars (one a NaN with a payload: bits count, not
 * values), and an nd x nq map (0: none) with distinct values in every point. */
static const mc_drive_cfg_t *make_cfg(int k, int nd, int nq)
{
    mc_drive_cfg_t *c = &sets[k];
    mc_params_default(&c->p);
    assert_true(mc_param_set(&c->p, mc_param_find("control.ts_s"), 1e-4f - 1e-6f * (float)(k % 40), NULL));
    assert_true(mc_param_set(&c->p, mc_param_find("hw.encoder_lines"), (float)(1000 + k), NULL));
    assert_true(mc_param_set(&c->p, mc_param_find("hw.dead_time_s"), 1e-7f * (float)(k % 50), NULL));
    c->est.rs = 0.1f + 0.01f * (float)k;
    c->est.ld = 1e-3f * (float)(k + 1);
    c->est.lq = 2e-3f * (float)(k + 1);
    c->est.psi_pm = k % 3 == 0 ? mc_bits_f32(0x7FC00000u + (uint32_t)k + 1u) : 0.05f + 0.001f * (float)k;
    c->est.map = NULL;
    if (nd > 0) {
        mc_flux_map_t *m = &maps[k];
        memset(m, 0, sizeof *m);
        m->n_d = nd;
        m->n_q = nq;
        m->id0 = -10.0f - (float)k;
        m->did = 0.5f;
        m->iq0 = -20.0f;
        m->diq = 0.25f + 0.01f * (float)k;
        for (int i = 0; i < nd * nq; ++i) {
            m->psi_d[i] = 0.001f * (float)i + (float)k;
            m->psi_q[i] = -0.002f * (float)i - (float)k;
        }
        c->est.map = m;
    }
    return c;
}

static bool same_cfg(const mc_drive_cfg_t *got, const mc_drive_cfg_t *want, bool dropped)
{
    return same_cfg_in(got, want, dropped, &got_map);
}

static mc_pstore_status_t load(mc_drive_cfg_t *got, mc_pstore_info_t *info)
{
    memset(got, 0, sizeof *got);
    mc_params_default(&got->p);
    return mc_pstore_load(&nvm, got, &got_map, work, sizeof work, info);
}

static void test_geometry(void **state)
{
    (void)state;
    nvm_init(&nvm);
    mc_pstore_geom_t g;
    if (s25fl) {
        /* one 64 KiB sector a slot: every map fits */
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_OK);
        assert_int_equal(g.slot_first[1], 1u);
        assert_int_equal(g.slot_blocks, 1u);
        assert_int_equal(g.payload_max, 65536u - 40u);
        assert_int_equal(g.map_cells_max, MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX);
        /* the map as hal/am263x has it (am263x_s25fl128s, checked the same way in am263x_nvm) */
        const hal_nvm_geometry_t *m = hal_nvm_geometry(&nvm);
        assert_ptr_equal(m, &hal_host_nvm_s25fl128s);
        assert_int_equal(m->size, 16u << 20);
        assert_int_equal(m->n_regions, 2);
        assert_int_equal(m->region[0].start, 0u);
        assert_int_equal(m->region[0].sector_size, 4096);
        assert_int_equal(m->region[0].count, 32);
        assert_int_equal(m->region[0].erase_cmd, 0x20);
        assert_int_equal(m->region[1].start, 0x20000u);
        assert_int_equal(m->region[1].sector_size, 65536);
        assert_int_equal(m->region[1].count, 254);
        assert_int_equal(m->region[1].erase_cmd, 0xD8);
        /* a range that is not whole sectors of one region is refused */
        static hal_nvm_t bad;
        assert_false(hal_host_nvm_init_geom(&bad, m, 0x7F8000u, 1u));
        assert_false(hal_host_nvm_init_geom(&bad, m, 0x10000u, 17u));
        assert_false(hal_host_nvm_init_geom(&bad, m, 0x7E0000u, 3u));   /* above the model's capacity */
        return;
    }
    /* 2 blocks a slot: 8192 - 40 bytes of records; 820 of parameters, 56 + 8 per map point */
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
    assert_int_equal(g.slot_first[0], 0u);
    assert_int_equal(g.slot_first[1], 2u);
    assert_int_equal(g.slot_blocks, 2u);
    assert_int_equal(g.payload_max, 8152u);
    assert_int_equal(g.map_cells_max, (8152u - MC_STORE_PARAMS_MAX - 56u) / 8u);
    assert_int_equal(g.map_cells_max, 909u);
    assert_int_equal(mc_pstore_geometry(NULL, &g), MC_PSTORE_BAD_ARGS);
    assert_string_equal(mc_pstore_status_name(MC_PSTORE_FELL_BACK), "fell_back");
    assert_string_equal(mc_pstore_status_name(MC_PSTORE_MAP_DROPPED), "map_dropped");
    assert_string_equal(mc_pstore_status_name((mc_pstore_status_t)99), "?");
}

static void test_empty_and_bad_args(void **state)
{
    (void)state;
    nvm_init(&nvm);
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
    assert_int_equal(info.slot, -1);
    mc_params_t def;
    mc_params_default(&def);
    assert_memory_equal(&got.p, &def, sizeof def);   /* untouched */
    /* garbage everywhere, no marker: still nothing committed */
    for (uint32_t k = 0; k < hal_host_nvm_bytes(&nvm); ++k) {
        nvm.mem[k] = (uint8_t)(k * 37u + k / 4096u);
    }
    assert_int_equal(load(&got, NULL), MC_PSTORE_EMPTY);

    nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(0, 4, 3);
    assert_int_equal(mc_pstore_save(NULL, a, work, sizeof work, NULL), MC_PSTORE_BAD_ARGS);
    assert_int_equal(mc_pstore_save(&nvm, NULL, work, sizeof work, NULL), MC_PSTORE_BAD_ARGS);
    assert_int_equal(mc_pstore_save(&nvm, a, work, MC_PSTORE_WORK_MIN - 1u, NULL), MC_PSTORE_BAD_ARGS);
    assert_int_equal(mc_pstore_save(&nvm, a, NULL, sizeof work, NULL), MC_PSTORE_BAD_ARGS);   /* no work area */
    assert_int_equal(mc_pstore_load(NULL, &got, &maps[0], work, sizeof work, NULL), MC_PSTORE_BAD_ARGS);
    assert_int_equal(mc_pstore_erase(&nvm, work, 8u), MC_PSTORE_BAD_ARGS);
    /* map_out NULL: a stored map is checked, not loaded */
    assert_true(a->est.map != NULL);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(mc_pstore_load(&nvm, &got, NULL, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_null(got.est.map);
    assert_memory_equal(&got.p, &a->p, sizeof got.p);
    nvm_init(&nvm);
    /* a map no encoder takes, a value no load takes: refused before anything is erased */
    mc_drive_cfg_t bad = *a;
    mc_flux_map_t *m = &maps[NSETS - 1];
    *m = maps[0];
    m->n_d = 1;
    bad.est.map = m;
    const uint32_t steps = nvm.steps;
    assert_int_equal(mc_pstore_save(&nvm, &bad, work, sizeof work, NULL), MC_PSTORE_BAD_ARGS);
    bad = *a;
    const int id = mc_param_find("control.ts_s");
    assert_true(mc_param_set(&bad.p, id, mc_param_table[id].max * 2.0f, NULL));
    assert_int_equal(mc_pstore_save(&nvm, &bad, work, sizeof work, NULL), MC_PSTORE_BAD_ARGS);
    assert_int_equal(nvm.steps, steps);
}

static void test_round_trip_records_bit_exact(void **state)
{
    (void)state;
    nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(1, 5, 7);
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 0);
    assert_int_equal(info.seq, 1u);
    mc_drive_cfg_t got;
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, a, false));
    assert_int_equal(info.slot, 0);
    assert_false(info.fell_back || info.defaults || info.map_dropped);

    /* on flash: header "MCPS", marker at 32, then exactly mc/store.h's two records */
    const uint8_t *s0 = blk(&nvm, 0);
    assert_int_equal(s0[0], 'M');
    assert_int_equal(s0[3], 'S');
    assert_int_equal(s0[32], 0x5A);
    assert_int_equal(s0[33], 0xA5);
    const size_t pl = mc_store_params_encode(&a->p, rec, sizeof rec);
    assert_int_equal(pl, MC_STORE_PARAMS_MAX);
    assert_memory_equal(s0 + 40, rec, pl);
    mc_params_t p;
    assert_int_equal(mc_store_params_decode(s0 + 40, pl, &p, NULL), MC_STORE_OK);
    const size_t ml = mc_store_model_encode(&a->est, rec, sizeof rec);
    assert_memory_equal(s0 + 40 + pl, rec, ml);
    mc_est_model_t m;
    assert_int_equal(mc_store_model_decode(s0 + 40 + pl, ml, &m, &got_map), MC_STORE_OK);

    /* the second copy goes to the other slot; the first stays as it was */
    static uint8_t before[HAL_HOST_NVM_CAP];
    memcpy(before, blk(&nvm, 0), nvm.block_size);
    const mc_drive_cfg_t *b = make_cfg(2, 0, 0);
    assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 1);
    assert_int_equal(info.seq, 2u);
    assert_memory_equal(blk(&nvm, 0), before, nvm.block_size);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, b, false));
    assert_int_equal(info.seq, 2u);

    /* the largest map that fits on 4 x 4 KiB (30 x 30, over both blocks of a slot); one row more
     * is dropped there; a 64 KiB sector takes every map */
    const bool drop = !s25fl;
    const mc_pstore_status_t big_st = drop ? MC_PSTORE_MAP_DROPPED : MC_PSTORE_OK;
    const mc_drive_cfg_t *c = make_cfg(3, 30, 30);
    assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, &info), MC_PSTORE_OK);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, c, false));
    const mc_drive_cfg_t *d = make_cfg(4, 31, 30);
    assert_int_equal(mc_pstore_save(&nvm, d, work, sizeof work, &info), big_st);
    assert_true(info.map_dropped == drop);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, d, drop));
    assert_true(info.map_dropped == drop);
    const mc_drive_cfg_t *e = make_cfg(5, MC_FLUX_MAP_MAX, MC_FLUX_MAP_MAX);
    assert_int_equal(mc_pstore_save(&nvm, e, work, sizeof work, NULL), big_st);
    assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
    assert_true(same_cfg(&got, e, drop));

    /* the work buffer's size changes the number of calls, not one byte on flash */
    static hal_nvm_t ref;
    nvm_init(&ref);
    assert_int_equal(mc_pstore_save(&ref, c, work, sizeof work, NULL), MC_PSTORE_OK);
    static uint8_t big[4099];
    const size_t lens[] = {72u, 100u, 1000u, sizeof big};
    for (size_t k = 0; k < sizeof lens / sizeof lens[0]; ++k) {
        nvm_init(&nvm);
        assert_int_equal(mc_pstore_save(&nvm, c, big, lens[k], NULL), MC_PSTORE_OK);
        assert_memory_equal(nvm.mem, ref.mem, sizeof ref.mem);
        memset(&got, 0, sizeof got);
        assert_int_equal(mc_pstore_load(&nvm, &got, &got_map, big, lens[k], NULL), MC_PSTORE_OK);
        assert_true(same_cfg(&got, c, false));
    }
}

static void test_corrupt_newest_falls_back(void **state)
{
    (void)state;
    nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(1, 6, 6), *b = make_cfg(2, 8, 5), *c = make_cfg(3, 0, 0);
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 0 */
    assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 1 */
    snap = nvm;
    /* a bit of b's map flips: the older a, and the status says so */
    blk(&nvm, s1)[40 + MC_STORE_PARAMS_MAX + 100u] ^= 0x04u;
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, a, false));
    assert_true(info.fell_back);
    assert_int_equal(info.slot, 0);
    /* the next save goes over the corrupt copy, never over the good one */
    assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 1);
    assert_int_equal(info.seq, 3u);
    assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
    assert_true(same_cfg(&got, c, false));
    /* both copies damaged: corrupt, nothing applied */
    blk(&nvm, 0)[300] ^= 0x10u;
    blk(&nvm, s1)[300] ^= 0x10u;
    assert_int_equal(load(&got, NULL), MC_PSTORE_CORRUPT);
    mc_params_t def;
    mc_params_default(&def);
    assert_memory_equal(&got.p, &def, sizeof def);

    /* a flipped bit in the newest's header (its sequence): marked, so possibly the newest */
    nvm = snap;
    blk(&nvm, s1)[8] ^= 0x01u;
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, a, false));
    /* a damaged older copy does not matter */
    nvm = snap;
    blk(&nvm, 0)[1000] ^= 0x80u;
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, b, false));
}

/* Two saves a (slot 0) and b (slot 1, newest) with records of the same lengths (same map size),
 * so that the header's length checks cannot tell one save's records from the other's; the payload
 * offsets and lengths of their records. */
static const mc_drive_cfg_t *splice_a, *splice_b;
static uint8_t *pay0, *pay1;
static const size_t splice_pl = MC_STORE_PARAMS_MAX, splice_ml = 4u * (14u + 2u * 6u * 9u);
static uint8_t splice_tmp[MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX];

static void two_saves(void)
{
    nvm_init(&nvm);
    splice_a = make_cfg(1, 6, 9);
    splice_b = make_cfg(2, 6, 9);
    assert_int_equal(mc_pstore_save(&nvm, splice_a, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 0 */
    assert_int_equal(mc_pstore_save(&nvm, splice_b, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 1 */
    snap = nvm;
    pay0 = blk(&nvm, 0) + 40;
    pay1 = blk(&nvm, s1) + 40;
    /* each record valid on its own (mc/store.h's decoders), and every record differs */
    mc_params_t p;
    mc_est_model_t m;
    for (int k = 0; k < 2; ++k) {
        const uint8_t *pay = k == 0 ? pay0 : pay1;
        assert_int_equal(mc_store_params_decode(pay, splice_pl, &p, NULL), MC_STORE_OK);
        assert_int_equal(mc_store_model_decode(pay + splice_pl, splice_ml, &m, &got_map), MC_STORE_OK);
    }
    assert_true(memcmp(pay0, pay1, splice_pl) != 0 && memcmp(pay0 + splice_pl, pay1 + splice_pl, splice_ml) != 0);
}

/* Records moved within and between copies where the record structure shows it, and a commit
 * that does not match its records: the newest copy so damaged is refused (the older copy,
 * whole, FELL_BACK); the older copy spliced does not disturb the newest. */
static void test_reordered_records_refused(void **state)
{
    (void)state;
    two_saves();
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    /* b's records in the other order (model first) */
    memcpy(splice_tmp, pay1 + splice_pl, splice_ml);
    memcpy(splice_tmp + splice_ml, pay1, splice_pl);
    memcpy(pay1, splice_tmp, splice_pl + splice_ml);
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, splice_a, false));
    assert_int_equal(info.slot, 0);
    assert_true(info.fell_back);
    /* b's parameter record twice, where the model belongs (its CRC valid, its magic wrong) */
    nvm = snap;
    memcpy(pay1 + splice_pl, pay1, splice_pl < splice_ml ? splice_pl : splice_ml);
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, splice_a, false));
    /* a commit that does not match its payload: b's header with another payload CRC and its
     * header CRC made valid again (a header written for other records); b's records intact */
    nvm = snap;
    uint8_t *h1 = blk(&nvm, s1);
    h1[24] ^= 0x01u;
    const uint32_t hc = mc_crc32(h1, 28u);
    for (int k = 0; k < 4; ++k) {
        h1[28 + k] = (uint8_t)(hc >> (8 * k));
    }
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, splice_a, false));
    assert_int_equal(info.slot, 0);
    /* the older copy spliced (b's model in a's copy), the newest intact: the newest */
    nvm = snap;
    memcpy(pay0 + splice_pl, pay1 + splice_pl, splice_ml);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, splice_b, false));
    assert_int_equal(info.slot, 1);
}

/* Records spliced between saves, each keeping its own valid CRC: only the commit (the header's
 * payload CRC, covered by the header's CRC) can tell such a copy from a real one. The newest copy
 * spliced must give the older copy, whole, with FELL_BACK; both spliced: CORRUPT, nothing
 * applied. Never a mixed set. (Found for issue 30: with the records' CRC words inside the
 * payload CRC (format 1) a CRC over data followed by its own CRC ends in a constant state, so the
 * payload CRC of valid records depended on their lengths only and b's parameters with a's model
 * loaded as "ok"; format 2 leaves those words out.) */
static void test_spliced_records_refused(void **state)
{
    (void)state;
    two_saves();
    const mc_drive_cfg_t *a = splice_a;
    const size_t pl = splice_pl, ml = splice_ml;
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    /* 1. b's parameters with a's model: the older copy, a, whole */
    memcpy(pay1 + pl, pay0 + pl, ml);
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, a, false));
    assert_int_equal(info.slot, 0);
    assert_true(info.fell_back);

    /* 2. a's parameters with b's model */
    nvm = snap;
    memcpy(pay1, pay0, pl);
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, a, false));
    assert_int_equal(info.slot, 0);

    /* 3. the whole payload of the other copy under b's header (a's records, b's commit) */
    nvm = snap;
    memcpy(pay1, pay0, pl + ml);
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, a, false));
    assert_int_equal(info.slot, 0);

    /* 4. a record of a save that never committed here: d's parameter record (taken from a save
     * of d over a's slot) in b's copy, a's copy as it was */
    nvm = snap;
    const mc_drive_cfg_t *d = make_cfg(4, 6, 9);
    assert_int_equal(mc_pstore_save(&nvm, d, work, sizeof work, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 0);
    memcpy(splice_tmp, pay0, pl);
    nvm = snap;
    memcpy(pay1, splice_tmp, pl);
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_true(same_cfg(&got, a, false));

    /* 5. both copies spliced crosswise (each holds the other's model): neither loads, nothing is
     * applied, and a save still goes to a slot and loads */
    nvm = snap;
    memcpy(splice_tmp, pay0 + pl, ml);
    memcpy(pay0 + pl, pay1 + pl, ml);
    memcpy(pay1 + pl, splice_tmp, ml);
    assert_int_equal(load(&got, &info), MC_PSTORE_CORRUPT);
    mc_params_t def;
    mc_params_default(&def);
    assert_memory_equal(&got.p, &def, sizeof def);
    assert_null(got.est.map);
    assert_int_equal(info.slot, -1);
    const mc_drive_cfg_t *c = make_cfg(3, 0, 0);
    assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
    assert_true(same_cfg(&got, c, false));

    /* the cause: the two commits hold the same payload CRC for different records */
    assert_true(memcmp(blk(&snap, 0) + 24, blk(&snap, s1) + 24, 4u) != 0);
}

static void test_erase_restores_defaults(void **state)
{
    (void)state;
    nvm_init(&nvm);
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_OK);   /* empty: stays empty */
    assert_int_equal(load(&got, NULL), MC_PSTORE_EMPTY);
    const mc_drive_cfg_t *a = make_cfg(1, 3, 3), *b = make_cfg(2, 4, 4), *c = make_cfg(3, 2, 2);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_OK);
    assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
    assert_true(info.defaults);
    mc_params_t def;
    mc_params_default(&def);
    assert_memory_equal(&got.p, &def, sizeof def);
    /* the defaults copy damaged: no older set comes back (the other slot was erased) */
    snap = nvm;
    blk(&nvm, info.slot == 0 ? 0u : s1)[4] ^= 0x01u;
    assert_int_equal(load(&got, NULL), MC_PSTORE_CORRUPT);
    nvm = snap;
    assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
    assert_true(same_cfg(&got, c, false));
}

/* A defaults head (what an erase commits) claims no records: one with a parameter or a model
 * length (its header CRC valid, so only the length checks can tell) is not a defaults copy but a
 * damaged one, and the slot's contents are not trusted: CORRUPT, never EMPTY (which would apply
 * the defaults as if the user had restored them). */
static void test_defaults_head_with_records_refused(void **state)
{
    (void)state;
    nvm_init(&nvm);
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_save(&nvm, make_cfg(1, 3, 3), work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_OK);
    assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
    assert_true(info.defaults);
    snap = nvm;
    uint8_t *h = blk(&nvm, info.slot == 0 ? 0u : s1);
    assert_int_equal(le32(h + 12), MC_PSTORE_FLAG_DEFAULTS);
    assert_int_equal(le32(h + 16), 0u);
    assert_int_equal(le32(h + 20), 0u);
    /* byte 16: the parameter record's length, 20: the model's; each alone, then both */
    const uint32_t lens[3][2] = {{MC_STORE_PARAMS_MAX, 0u}, {0u, 32u}, {MC_STORE_PARAMS_MAX, 32u}};
    for (int k = 0; k < 3; ++k) {
        nvm = snap;
        put_le32(h + 16, lens[k][0]);
        put_le32(h + 20, lens[k][1]);
        put_le32(h + 28, mc_crc32(h, 28u));
        assert_int_equal(load(&got, &info), MC_PSTORE_CORRUPT);
        assert_false(info.defaults);
        assert_int_equal(info.slot, -1);
    }
}

/* The smallest slot the store takes holds the parameter record and the model without a map
 * (820 + 32 bytes after the 40-byte header and marker): a device of two 872-byte sectors
 * (832 bytes of payload a slot) is refused before anything is written; one of two 896-byte
 * sectors (856) takes a set, without its map, and loads it back. */
static void test_slot_too_small_refused(void **state)
{
    (void)state;
    static const hal_nvm_region_t small_r[1] = {{0u, 872u, 2u, 0u}}, fits_r[1] = {{0u, 896u, 2u, 0u}};
    static const hal_nvm_geometry_t small = {2u * 872u, 8u, 1u, small_r}, fits = {2u * 896u, 8u, 1u, fits_r};
    mc_pstore_geom_t g;
    mc_pstore_info_t info;
    mc_drive_cfg_t got;
    const mc_drive_cfg_t *a = make_cfg(5, 3, 3);
    assert_true(hal_host_nvm_init_geom(&nvm, &small, 0u, 2u));
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_TOO_LARGE);
    assert_int_equal(g.payload_max, 832u);
    assert_true(g.payload_max < MC_STORE_PARAMS_MAX + 32u);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_TOO_LARGE);
    assert_int_equal(nvm.steps, 0u);   /* nothing erased, nothing written */
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_TOO_LARGE);
    assert_int_equal(load(&got, &info), MC_PSTORE_TOO_LARGE);

    assert_true(hal_host_nvm_init_geom(&nvm, &fits, 0u, 2u));
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
    assert_int_equal(g.payload_max, MC_STORE_PARAMS_MAX + 32u + 4u);
    assert_int_equal(g.map_cells_max, 0u);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_MAP_DROPPED);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, a, true));
}

/* A dead device (after a cut, before power-on): every call fails at once. */
static void test_failing_device(void **state)
{
    (void)state;
    nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(1, 10, 10);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    hal_host_nvm_cut_at(&nvm, nvm.steps + 1u);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_NVM_ERROR);
    mc_drive_cfg_t got;
    assert_int_equal(load(&got, NULL), MC_PSTORE_NVM_ERROR);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_NVM_ERROR);
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_NVM_ERROR);
    hal_host_nvm_power_on(&nvm);
    assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
    assert_true(same_cfg(&got, a, false));
}

/* ---- power cuts ---------------------------------------------------------------------------- */

typedef struct {
    const mc_drive_cfg_t *cfg;   /* NULL: nothing committed, or restored to defaults (EMPTY) */
    bool dropped;                /* saved without its map */
} expect_t;

static bool is(mc_pstore_status_t st, const mc_drive_cfg_t *got, expect_t e)
{
    return e.cfg == NULL ? st == MC_PSTORE_EMPTY : st == MC_PSTORE_OK && same_cfg(got, e.cfg, e.dropped);
}

static mc_pstore_status_t run(const mc_drive_cfg_t *next)
{
    return next != NULL ? mc_pstore_save(&nvm, next, work, sizeof work, NULL)
                        : mc_pstore_erase(&nvm, work, sizeof work);
}

/* From the store in snap (its last committed set: old), save next (NULL: erase) with a cut at
 * every step 1..N of the operation and once after it; then the new state becomes snap. */
static unsigned sweep(expect_t old, expect_t next, unsigned *recoveries)
{
    const mc_drive_cfg_t *r = make_cfg(NSETS - 2, 3, 2);   /* a save after the cut: it still works */
    nvm = snap;
    const uint32_t start = nvm.steps;
    const mc_pstore_status_t done = next.dropped ? MC_PSTORE_MAP_DROPPED : MC_PSTORE_OK;
    assert_int_equal(run(next.cfg), done);
    const uint32_t total = nvm.steps - start;
    static hal_nvm_t after;
    after = nvm;
    unsigned cuts = 0;
    for (uint32_t s = 1; s <= total + 1u; ++s) {
        nvm = snap;
        nvm.rng = 0x9E3779B9u ^ (s * 0x85EBCA6Bu) ^ (total << 20);   /* a different scramble each */
        if (nvm.rng == 0u) {
            nvm.rng = 1u;
        }
        hal_host_nvm_cut_at(&nvm, start + s);
        const mc_pstore_status_t st = run(next.cfg);
        assert_int_equal(st, s <= total ? MC_PSTORE_NVM_ERROR : done);
        hal_host_nvm_power_on(&nvm);
        mc_drive_cfg_t got;
        const mc_pstore_status_t ld = load(&got, NULL);
        const bool was_old = is(ld, &got, old), was_new = is(ld, &got, next);
        if (!(was_old || was_new)) {
            fail_msg("%s cut at step %u of %u: load %s", next.cfg != NULL ? "save" : "erase", s, total,
                     mc_pstore_status_name(ld));
        }
        if (s > total) {
            assert_true(was_new);
        }
        if (s == total && next.cfg != NULL) {
            assert_true(was_old);   /* the cut hit the marker: a half marker is no marker */
        }
        /* the store recovers: the next save goes over the half-written slot */
        {
            assert_int_equal(mc_pstore_save(&nvm, r, work, sizeof work, NULL), MC_PSTORE_OK);
            assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
            assert_true(same_cfg(&got, r, false));
            ++*recoveries;
        }
        ++cuts;
    }
    snap = after;
    return cuts;
}

static void test_power_cut_at_every_step(void **state)
{
    (void)state;
    nvm_init(&snap);
    const expect_t none = {NULL, false};
    /* maps of every size class: the largest that fits (over both blocks of a slot), small, none,
     * dropped (41 x 41); erases over a one-block and a two-block copy */
    const expect_t s0 = {make_cfg(0, 30, 30), false}, s1 = {make_cfg(1, 12, 9), false};
    const expect_t s2 = {make_cfg(2, 29, 31), false}, s3 = {make_cfg(3, 0, 0), false};
    const expect_t s4 = {make_cfg(4, MC_FLUX_MAP_MAX, MC_FLUX_MAP_MAX), !s25fl};
    const expect_t s5 = {make_cfg(5, 25, 28), false}, s6 = {make_cfg(6, 2, 2), false};
    const expect_t s7 = {make_cfg(7, 30, 30), false};
    const expect_t chain[][2] = {
        {none, s0},   /* the first save ever: empty or s0 (slot 0)        */
        {s0, s1},     /* slot 1, the other slot still erased              */
        {s1, s2},     /* slot 0 over s0: a long copy over a long one      */
        {s2, none},   /* 0x1011 over a two-block copy: s2 or defaults     */
        {none, s3},   /* after a restore: defaults or s3                  */
        {s3, s4},     /* saved without its map (4 x 4 KiB)                */
        {s4, s5},
        {s5, s6},     /* a short copy over a long one                     */
        {s6, none},   /* 0x1011 over a one-block copy                     */
        {none, s7},
        {s7, s1},
    };
    unsigned cuts = 0, erase_cuts = 0, rec_n = 0;
    for (size_t k = 0; k < sizeof chain / sizeof chain[0]; ++k) {
        const unsigned n = sweep(chain[k][0], chain[k][1], &rec_n);
        cuts += n;
        erase_cuts += chain[k][1].cfg == NULL ? n : 0u;
    }
    print_message("power cuts tested: %u (%u in erases), each followed by a load, %u by a save\n", cuts, erase_cuts,
                  rec_n);
    assert_true(cuts > 4000u);
}

/* Two cuts in a row (a save cut, then the next save cut too): never anything but the last
 * committed set or the one whose marker completed. */
static void test_double_cuts(void **state)
{
    (void)state;
    const mc_drive_cfg_t *a = make_cfg(0, 20, 20), *b = make_cfg(1, 15, 15), *c = make_cfg(2, 0, 0);
    nvm_init(&nvm);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);   /* both slots */
    snap = nvm;
    uint32_t t0 = nvm.steps;
    assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, NULL), MC_PSTORE_OK);
    const uint32_t nb = nvm.steps - t0;
    t0 = nvm.steps;
    assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, NULL), MC_PSTORE_OK);
    const uint32_t nc = nvm.steps - t0;
    uint32_t rnd = 12345u;
    for (int i = 0; i < 300; ++i) {
        nvm = snap;
        rnd = rnd * 1664525u + 1013904223u;
        hal_host_nvm_cut_at(&nvm, nvm.steps + 1u + (rnd >> 8) % nb);
        assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, NULL), MC_PSTORE_NVM_ERROR);
        hal_host_nvm_power_on(&nvm);
        rnd = rnd * 1664525u + 1013904223u;
        const uint32_t s2 = 1u + (rnd >> 8) % (nc + 2u);
        hal_host_nvm_cut_at(&nvm, nvm.steps + s2);
        (void)mc_pstore_save(&nvm, c, work, sizeof work, NULL);
        hal_host_nvm_power_on(&nvm);
        mc_drive_cfg_t got;
        const mc_pstore_status_t ld = load(&got, NULL);
        assert_int_equal(ld, MC_PSTORE_OK);
        if (s2 > nc) {
            assert_true(same_cfg(&got, c, false));
        } else {
            assert_true(same_cfg(&got, a, false));
        }
    }
}

/* An erase the flash did not carry out is an error, never a silent success: the layer sends a
 * 4 KiB erase (the uniform map TI's SDK config suggests) into the S25FL128S's 64 KiB sectors, or
 * no erase at all; the part ignores it, the verify sees the old copy, the save fails and the set
 * committed before still loads. On the host's own map a skipped erase is caught the same way. */
static void test_missed_erase_fails_the_save(void **state)
{
    (void)state;
    const mc_drive_cfg_t *a = make_cfg(0, 10, 10), *b = make_cfg(1, 12, 12), *c = make_cfg(2, 3, 3);
    const uint32_t wrong[] = {4096u, 0u};
    for (size_t w = 0; w < sizeof wrong / sizeof wrong[0]; ++w) {
        nvm_init(&nvm);
        assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 0 */
        assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 1 */
        if (wrong[w] == nvm.block_size) {
            continue;   /* the host's map: 4 KiB is right there */
        }
        nvm.erase_size = wrong[w];
        assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, NULL), MC_PSTORE_NVM_ERROR);   /* over a */
        assert_false(hal_nvm_erase(&nvm, 0u));
        mc_drive_cfg_t got;
        assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
        assert_true(same_cfg(&got, b, false));
        nvm.erase_size = nvm.block_size;   /* the right erase: the store goes on */
        assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, NULL), MC_PSTORE_OK);
        assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
        assert_true(same_cfg(&got, c, false));
    }
}

static int group_uniform4k(void **state)
{
    (void)state;
    s25fl = false;
    return 0;
}

static int group_s25fl128s(void **state)
{
    (void)state;
    s25fl = true;
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geometry),
        cmocka_unit_test(test_empty_and_bad_args),
        cmocka_unit_test(test_round_trip_records_bit_exact),
        cmocka_unit_test(test_corrupt_newest_falls_back),
        cmocka_unit_test(test_reordered_records_refused),
        cmocka_unit_test(test_spliced_records_refused),
        cmocka_unit_test(test_erase_restores_defaults),
        cmocka_unit_test(test_defaults_head_with_records_refused),
        cmocka_unit_test(test_slot_too_small_refused),
        cmocka_unit_test(test_failing_device),
        cmocka_unit_test(test_power_cut_at_every_step),
        cmocka_unit_test(test_double_cuts),
        cmocka_unit_test(test_missed_erase_fails_the_save),
    };
    const int r = cmocka_run_group_tests_name("host_4x4KiB", tests, group_uniform4k, NULL);
    return r + cmocka_run_group_tests_name("s25fl128s_2x64KiB", tests, group_s25fl128s, NULL);
}
