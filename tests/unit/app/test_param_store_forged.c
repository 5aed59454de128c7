/* The configuration store (mc/param_store.h) against copies a faulty or foreign writer could have
 * left, every CRC of them valid (issue 30: the survivors of the mutation run in param_store.c
 * that test_param_store.c and test_param_store_edges.c cannot see):
 *   - a parameter record of another version (or version 1 of another table), a header with a
 *     flag this firmware does not know, a record whose own CRC word is wrong (the payload CRC
 *     does not cover it, format 2), a header of an unknown format, a map beyond the grid
 *     limits: refused, the older copy loads (such a map given to a save: refused untouched);
 *   - a marker that is not exactly its pattern: no commit;
 *   - headers whose lengths cannot be this device's: they do not count for the next sequence
 *     number (their number is unknown), while a header that checks does, marked or not;
 *   - sequence numbers across 2^31 and 2^32: every save is the newest copy a load returns;
 *   - a device of two blocks, each exactly the largest copy: a save erases its own slot only;
 *   - the info a call returns says only what happened, and NULL arguments are refused;
 *   - a slot smaller than a header and its marker: no room at all; every status's name. */
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

static hal_nvm_t nvm, snap;
static uint8_t work[MC_PSTORE_WORK_MIN];
static mc_flux_map_t maps[4];
static mc_drive_cfg_t sets[4];
static mc_flux_map_t got_map;

/* The copy's layout on the host model (write unit 8): header 32 bytes, marker 8, then the
 * records padded to 8. */
#define PAYLOAD_AT 40u

/* set k: a few parameters moved, the model's scalars, an nd x nq map (0: none) */
static const mc_drive_cfg_t *make_cfg(int k, int nd, int nq)
{
    return pstore_make_cfg(&sets[k], &maps[k], k, nd, nq);
}

static mc_pstore_status_t load(mc_drive_cfg_t *got, mc_pstore_info_t *info)
{
    memset(got, 0, sizeof *got);
    mc_params_default(&got->p);
    return mc_pstore_load(&nvm, got, &got_map, work, sizeof work, info);
}

static uint32_t get32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static void put32(uint8_t *b, uint32_t w)
{
    for (int k = 0; k < 4; ++k) {
        b[k] = (uint8_t)(w >> (8 * k));
    }
}

static uint32_t round8(uint32_t x)
{
    return (x + 7u) / 8u * 8u;
}

/* ---- a (slot 0, seq 1) and b (slot 1, seq 2) committed ------------------------------------ */

static const mc_drive_cfg_t *ca, *cb;
static uint8_t *slot0, *slot1;
static uint32_t cap;   /* the record bytes a slot holds */

static void two_copies(void)
{
    hal_host_nvm_init(&nvm);
    ca = make_cfg(0, 4, 5);
    cb = make_cfg(1, 6, 3);
    assert_int_equal(mc_pstore_save(&nvm, ca, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 0 */
    assert_int_equal(mc_pstore_save(&nvm, cb, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 1 */
    mc_pstore_geom_t g;
    (void)mc_pstore_geometry(&nvm, &g);
    slot0 = nvm.mem + g.slot_first[0] * nvm.block_size;
    slot1 = nvm.mem + g.slot_first[1] * nvm.block_size;
    cap = g.payload_max;
    snap = nvm;
}

/* load gives a (the newest copy refused) or b (taken) */
static void loads(const mc_drive_cfg_t *want)
{
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(load(&got, &info), want == ca ? MC_PSTORE_FELL_BACK : MC_PSTORE_OK);
    assert_int_equal(info.slot, want == ca ? 0 : 1);
    assert_int_equal(info.fell_back, want == ca);
    assert_true(same_cfg_in(&got, want, false, &got_map));
}

/* the header CRC over the header's first 28 bytes, as a writer computes it */
static void head_crc(uint8_t *slot)
{
    put32(slot + 28, mc_crc32(slot, 28u));
}

/* b's copy rewritten with these records under a format-2 header, every CRC valid */
static void forge_b(const uint8_t *pr, uint32_t pl, const uint8_t *mr, uint32_t ml)
{
    static uint8_t crc_in[MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX];
    memset(slot1 + PAYLOAD_AT, 0xFF, round8(pl + ml));
    memcpy(slot1 + PAYLOAD_AT, pr, pl);
    memcpy(slot1 + PAYLOAD_AT + pl, mr, ml);
    /* format 2: the payload CRC leaves out each record's CRC word */
    memcpy(crc_in, pr, pl - 4u);
    memcpy(crc_in + pl - 4u, mr, ml - 4u);
    put32(slot1 + 16, pl);
    put32(slot1 + 20, ml);
    put32(slot1 + 24, mc_crc32(crc_in, pl + ml - 8u));
    head_crc(slot1);
}

static void close_record(uint8_t *r, uint32_t len)
{
    put32(r + len - 4u, mc_crc32(r, len - 4u));
}

/* A parameter record of a version this firmware does not read (0, 3, the next one), or a
 * version 1 record (positions in the frozen table of main at 5265cfe) whose table word is not
 * that table's, each with every CRC of the copy valid: the record's numbering is unknown, the
 * copy is refused and the older one loads, as mc_store_params_decode refuses such a record
 * (BAD_VERSION). The same forging with this version loads. (param_store.c:401.) */
static void test_params_record_of_another_version(void **state)
{
    (void)state;
    two_copies();
    static uint8_t pr[MC_STORE_PARAMS_MAX], mr[MC_STORE_MODEL_MAX];
    const uint32_t pl = (uint32_t)mc_store_params_encode(&cb->p, pr, sizeof pr);
    const uint32_t ml = (uint32_t)mc_store_model_encode(&cb->est, mr, sizeof mr);
    forge_b(pr, pl, mr, ml);
    loads(cb);
    const uint32_t versions[] = {0u, 3u, MC_STORE_PARAMS_VERSION + 1u, 0xFFFFFFFFu};
    for (size_t i = 0; i < sizeof versions / sizeof versions[0]; ++i) {
        assert_int_not_equal(versions[i], MC_STORE_PARAMS_VERSION);
        put32(pr + 4, versions[i]);
        close_record(pr, pl);
        mc_params_t p;
        assert_int_equal(mc_store_params_decode(pr, pl, &p, NULL), MC_STORE_BAD_VERSION);
        nvm = snap;
        forge_b(pr, pl, mr, ml);
        loads(ca);
    }
    /* version 1 of another table: its positions name other parameters; of the frozen table:
     * read (the control) */
    const uint32_t tables[] = {MC_STORE_V1_TABLE - 1u, MC_STORE_V1_TABLE + 1u, 0u, MC_STORE_V1_TABLE};
    for (size_t i = 0; i < sizeof tables / sizeof tables[0]; ++i) {
        const uint32_t w[] = {MC_STORE_MAGIC_PARAMS, 1u, tables[i], 2u, 0u | MC_STORE_V1_AUTO, 0u, 1u | MC_STORE_V1_AUTO, 0u};
        uint8_t v1[4u * 9u];
        for (int k = 0; k < 8; ++k) {
            put32(v1 + 4 * k, w[k]);
        }
        close_record(v1, sizeof v1);
        nvm = snap;
        forge_b(v1, sizeof v1, mr, ml);
        mc_drive_cfg_t got;
        mc_pstore_info_t info;
        const bool frozen = tables[i] == MC_STORE_V1_TABLE;
        assert_int_equal(load(&got, &info), frozen ? MC_PSTORE_OK : MC_PSTORE_FELL_BACK);
        assert_int_equal(info.slot, frozen ? 1 : 0);
        if (frozen) {
            assert_true(info.params.other_table);
            assert_int_equal(info.params.kept + info.params.unknown, 2u);
        } else {
            assert_true(same_cfg_in(&got, ca, false, &got_map));
        }
    }
}

/* Each record ends with its own CRC word, which format 2's payload CRC leaves out: a bit of the
 * parameter record's or the model record's CRC word flipped (the header and the payload CRC
 * still valid) is caught by that record's check alone; the copy is refused, the older loads.
 * (param_store.c:493: the model record is read only after the parameter record checked.) */
static void test_record_crc_word_flipped(void **state)
{
    (void)state;
    two_copies();
    const uint32_t pl = get32(slot1 + 16), ml = get32(slot1 + 20);
    const uint32_t at[] = {PAYLOAD_AT + pl - 4u, PAYLOAD_AT + pl + ml - 4u};
    for (size_t r = 0; r < 2u; ++r) {
        for (uint32_t bit = 0u; bit < 32u; bit += 7u) {
            nvm = snap;
            slot1[at[r] + bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
            loads(ca);
        }
    }
}

/* A header with a flag bit this firmware does not know (a newer writer's), its CRC valid and
 * the records intact: what the flag means is unknown, so the copy is not taken; the older one
 * loads. (param_store.c:536.) */
static void test_unknown_header_flag_refused(void **state)
{
    (void)state;
    two_copies();
    for (uint32_t bit = 2u; bit < 32u; ++bit) {
        nvm = snap;
        put32(slot1 + 12, get32(slot1 + 12) | (1u << bit));
        head_crc(slot1);
        loads(ca);
    }
    /* the known one with its meaning (no map) on a copy that has one: still a valid header */
    nvm = snap;
    put32(slot1 + 12, MC_PSTORE_FLAG_NO_MAP);
    head_crc(slot1);
    loads(cb);
}

/* The commit marker is exactly its pattern (0x5A, 0xA5, ...): b's marker with any byte not its
 * pattern, below it (more bits cleared: 0x00, the pattern with a bit cleared, one less, another
 * write's bytes) or above it (erased 0xFF, a write cut short: a write only clears bits), is no
 * marker; b is not committed, and a load returns a (the only committed copy: OK).
 * (param_store.c:524, the marker's compare.) */
static void test_marker_exactly_its_pattern(void **state)
{
    (void)state;
    two_copies();
    for (uint32_t k = 0u; k < 8u; ++k) {
        const uint8_t pat = (k & 1u) != 0u ? 0xA5u : 0x5Au;
        assert_int_equal(slot1[32u + k], pat);
        const uint8_t other[] = {0x00u, (uint8_t)(pat & (pat - 1u)), (uint8_t)(pat - 1u), (uint8_t)(pat ^ 0x10u), 0xFFu};
        for (size_t i = 0; i < sizeof other / sizeof other[0]; ++i) {
            nvm = snap;
            slot1[32u + k] = other[i];
            mc_drive_cfg_t got;
            mc_pstore_info_t info;
            assert_int_equal(load(&got, &info), MC_PSTORE_OK);
            assert_int_equal(info.slot, 0);
            assert_false(info.fell_back);
            assert_true(same_cfg_in(&got, ca, false, &got_map));
        }
    }
}

/* The header's magic word is exactly "MCPS": b's header with another one (one above, one below,
 * another store's), its CRC valid, is not a copy of this store; the older copy loads.
 * (param_store.c:534, the magic's compare.) */
static void test_other_magic_refused(void **state)
{
    (void)state;
    two_copies();
    const uint32_t magics[] = {MC_PSTORE_MAGIC + 1u, MC_PSTORE_MAGIC - 1u, 0xFFFFFFF0u, 0u};
    for (size_t i = 0; i < sizeof magics / sizeof magics[0]; ++i) {
        nvm = snap;
        put32(slot1, magics[i]);
        head_crc(slot1);
        loads(ca);
    }
}

/* The header's format word: 2 (this firmware's) and 1 (the records' CRC words in the payload
 * CRC: read for the copies written before) are known; b's copy with any other format (0, 3, all
 * ones), its payload CRC as format 2 computes it and its header CRC valid, is not taken: how its
 * payload CRC was made is unknown. (param_store.c:534.) */
static void test_unknown_format_refused(void **state)
{
    (void)state;
    two_copies();
    const uint32_t formats[] = {0u, 3u, 0xFFFFFFFFu};
    for (size_t i = 0; i < sizeof formats / sizeof formats[0]; ++i) {
        nvm = snap;
        put32(slot1 + 4, formats[i]);
        head_crc(slot1);
        loads(ca);
    }
    nvm = snap;
    put32(slot1 + 4, MC_PSTORE_FORMAT);
    head_crc(slot1);
    loads(cb);
}

/* A model record whose map has fewer than 2 or more than MC_FLUX_MAP_MAX points on an axis (its
 * length matching its dimensions, every CRC of the copy valid) is refused as
 * mc_store_model_decode refuses it: the older copy loads, never a map no interpolation can use.
 * A save of such a map is refused (BAD_ARGS) before any NVM step. (param_store.c:455, :666.) */
static void test_map_dimensions_beyond_the_limits(void **state)
{
    (void)state;
    two_copies();
    static uint8_t pr[MC_STORE_PARAMS_MAX], mr[MC_STORE_MODEL_MAX];
    const uint32_t pl = (uint32_t)mc_store_params_encode(&cb->p, pr, sizeof pr);
    const int m = MC_FLUX_MAP_MAX;
    const int dims[][2] = {{1, 4}, {4, 1}, {2, m + 1}, {m + 1, 2}, {0, 4}, {4, 0}, {2, m}, {m, 2}};
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; ++i) {
        const int nd = dims[i][0], nq = dims[i][1];
        const bool ok = nd >= 2 && nq >= 2 && nd <= m && nq <= m;
        /* the record as an encoder without the limits would write it */
        const uint32_t cells = (uint32_t)(nd * nq);
        const uint32_t ml = 4u * (14u + 2u * cells);
        const float head[6] = {cb->est.rs, cb->est.ld, cb->est.lq, cb->est.psi_pm};
        put32(mr, MC_STORE_MAGIC_MODEL);
        put32(mr + 4, MC_STORE_VERSION);
        for (int k = 0; k < 4; ++k) {
            put32(mr + 8 + 4 * k, mc_f32_bits(head[k]));
        }
        put32(mr + 24, 1u);
        put32(mr + 28, (uint32_t)nd);
        put32(mr + 32, (uint32_t)nq);
        put32(mr + 36, mc_f32_bits(-10.0f));
        put32(mr + 40, mc_f32_bits(0.5f));
        put32(mr + 44, mc_f32_bits(-20.0f));
        put32(mr + 48, mc_f32_bits(0.25f));
        for (uint32_t k = 0u; k < 2u * cells; ++k) {
            put32(mr + 52 + 4u * k, mc_f32_bits(0.001f * (float)k));
        }
        close_record(mr, ml);
        mc_est_model_t em;
        assert_int_equal(mc_store_model_decode(mr, ml, &em, &got_map) == MC_STORE_OK, ok);
        nvm = snap;
        forge_b(pr, pl, mr, ml);
        mc_drive_cfg_t got;
        mc_pstore_info_t info;
        assert_int_equal(load(&got, &info), ok ? MC_PSTORE_OK : MC_PSTORE_FELL_BACK);
        assert_int_equal(info.slot, ok ? 1 : 0);
        if (!ok) {
            assert_true(same_cfg_in(&got, ca, false, &got_map));
        } else {
            assert_int_equal(got.est.map->n_d, nd);
            assert_int_equal(got.est.map->n_q, nq);
        }

        /* the same map given to a save */
        nvm = snap;
        mc_drive_cfg_t c = *cb;
        static mc_flux_map_t big;
        memset(&big, 0, sizeof big);
        big.n_d = nd;
        big.n_q = nq;
        big.did = 1.0f;
        big.diq = 1.0f;
        c.est.map = &big;
        assert_int_equal(mc_pstore_save(&nvm, &c, work, sizeof work, &info), ok ? MC_PSTORE_OK : MC_PSTORE_BAD_ARGS);
        if (!ok) {
            assert_int_equal(info.slot, -1);
            assert_int_equal(nvm.steps, snap.steps);
            assert_memory_equal(nvm.mem, snap.mem, sizeof nvm.mem);
        }
    }
}

/* The next save's sequence number is one above every header that checks, marked or not; a
 * header whose lengths cannot be a copy on this device (a record longer than the slot, lengths
 * whose sum is, lengths not whole words) does not check, its number is unknown and does not
 * count, whatever it says. b's header, CRC valid, claims sequence 100: with valid lengths (the
 * marker erased, not committed) the next save is 101; with each of those lengths it is 2 (a's 1
 * + 1). (param_store.c:538.) */
static void test_insane_lengths_do_not_count(void **state)
{
    (void)state;
    two_copies();
    const uint32_t pl = get32(slot1 + 16), ml = get32(slot1 + 20);
    const struct {
        uint32_t pl, ml, next;
    } cases[] = {
        {pl, ml, 101u},                     /* sane, unmarked: counts            */
        {cap + 4u, ml, 2u},                 /* a parameter record past the slot  */
        {cap + 4u, 0u, 2u},
        {0xFFFFFFFCu, 32u, 2u},
        {pl, cap - pl + 4u, 2u},            /* both together past the slot       */
        {pl + 2u, ml, 2u},                  /* not whole words                   */
        {pl, ml + 2u, 2u},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        nvm = snap;
        put32(slot1 + 8, 100u);
        put32(slot1 + 16, cases[i].pl);
        put32(slot1 + 20, cases[i].ml);
        head_crc(slot1);
        memset(slot1 + 32, 0xFF, 8u);   /* the marker erased: a copy cut before its commit */
        mc_drive_cfg_t got;
        mc_pstore_info_t info;
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, 0);
        assert_true(same_cfg_in(&got, ca, false, &got_map));
        const mc_drive_cfg_t *c = make_cfg(2, 5, 5);
        assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, 1);
        assert_int_equal(info.seq, cases[i].next);
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_int_equal(info.seq, cases[i].next);
        assert_true(same_cfg_in(&got, c, false, &got_map));
    }
}

/* Sequence numbers run on modulo 2^32 (mc/param_store.h: a newer than b when a - b is in
 * [1, 2^31)): from a committed copy numbered s, each of three saves is numbered one more and is
 * the copy a load returns, across 2^31 and across 2^32, and an erase after them too.
 * (param_store.c:568: the first header that checks sets the number, whatever it is.) */
static void test_sequence_wraps(void **state)
{
    (void)state;
    const uint32_t starts[] = {0x7FFFFFFEu, 0x80000000u, 0xBFFFFFFFu, 0xFFFFFFFEu, 0xFFFFFFFFu, 0u};
    for (size_t i = 0; i < sizeof starts / sizeof starts[0]; ++i) {
        hal_host_nvm_init(&nvm);
        const mc_drive_cfg_t *a = make_cfg(0, 3, 3);
        assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
        put32(nvm.mem + 8, starts[i]);   /* slot 0's copy, as if that many saves came before */
        head_crc(nvm.mem);
        mc_drive_cfg_t got;
        mc_pstore_info_t info;
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_int_equal(info.seq, starts[i]);
        for (uint32_t k = 1u; k <= 3u; ++k) {
            const mc_drive_cfg_t *c = make_cfg((int)k, 2 + (int)k, 4);
            assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, &info), MC_PSTORE_OK);
            assert_int_equal(info.seq, starts[i] + k);
            assert_int_equal(info.slot, (int)(k % 2u));
            assert_int_equal(load(&got, &info), MC_PSTORE_OK);
            assert_int_equal(info.seq, starts[i] + k);
            assert_int_equal(info.slot, (int)(k % 2u));
            assert_true(same_cfg_in(&got, c, false, &got_map));
        }
        assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_OK);
        assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
        assert_true(info.defaults);
        assert_int_equal(info.seq, starts[i] + 4u);
    }
}

/* Which of two committed copies is the newer: b's number minus a's, modulo 2^32, in [1, 2^31)
 * (serial number arithmetic, mc/param_store.h): b at a + 1, + 2^28, + 2^30, + 2^31 - 1 is the
 * newer; at a + 2^31 + 1 or a - 1 (a newer by the same rule) a is. Each pair from a few
 * starting numbers; the next save is one above the newer. (param_store.c:546.) */
static void test_newer_by_serial_arithmetic(void **state)
{
    (void)state;
    const uint32_t starts[] = {1u, 0x40000000u, 0xF0000000u};
    const struct {
        uint32_t db;
        bool b_newer;
    } cases[] = {{1u, true},           {0x10000000u, true},  {0x40000000u, true}, {0x7FFFFFFFu, true},
                 {0x80000001u, false}, {0xFFFFFFFFu, false}, {0xC0000000u, false}};
    for (size_t i = 0; i < sizeof starts / sizeof starts[0]; ++i) {
        for (size_t j = 0; j < sizeof cases / sizeof cases[0]; ++j) {
            two_copies();
            const uint32_t sa = starts[i], sb = starts[i] + cases[j].db;
            put32(slot0 + 8, sa);
            head_crc(slot0);
            put32(slot1 + 8, sb);
            head_crc(slot1);
            mc_drive_cfg_t got;
            mc_pstore_info_t info;
            assert_int_equal(load(&got, &info), MC_PSTORE_OK);
            assert_int_equal(info.slot, cases[j].b_newer ? 1 : 0);
            assert_int_equal(info.seq, cases[j].b_newer ? sb : sa);
            assert_true(same_cfg_in(&got, cases[j].b_newer ? cb : ca, false, &got_map));
            const mc_drive_cfg_t *c = make_cfg(2, 3, 4);
            assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, &info), MC_PSTORE_OK);
            assert_int_equal(info.slot, cases[j].b_newer ? 0 : 1);
            assert_int_equal(info.seq, (cases[j].b_newer ? sb : sa) + 1u);
        }
    }
}

/* ---- a device of two blocks, each exactly the largest copy -------------------------------- */

static hal_nvm_region_t region[1];
static const hal_nvm_geometry_t device = {0u, 256u, 1u, region};

/* A slot is one block, slot 1 the device's last block: a save of the largest set (its copy
 * fills the block to the last byte) erases and writes its own block only, never the other
 * slot's (the copy a load returns) nor past the device's end, into either slot, and both sets
 * come back. (param_store.c:614, the blocks a commit erases.) */
static void test_largest_copies_touch_their_own_block(void **state)
{
    (void)state;
    const uint32_t largest = PAYLOAD_AT + round8(MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX);
    region[0] = (hal_nvm_region_t){0u, largest, 2u, 0u};
    assert_true(hal_host_nvm_init_geom(&nvm, &device, 0u, 2u));
    mc_pstore_geom_t g;
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_OK);
    assert_int_equal(g.slot_first[1], 1u);
    assert_int_equal(g.slot_blocks, 1u);
    const int n = MC_FLUX_MAP_MAX;
    for (int k = 0; k < 4; ++k) {
        const mc_drive_cfg_t *c = make_cfg(k, n, n);
        const int slot = k % 2, other = 1 - slot;
        snap = nvm;
        mc_pstore_info_t info;
        assert_int_equal(mc_pstore_save(&nvm, c, work, sizeof work, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, slot);
        assert_memory_equal(nvm.mem + (uint32_t)other * largest, snap.mem + (uint32_t)other * largest, largest);
        mc_drive_cfg_t got;
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, slot);
        assert_true(same_cfg_in(&got, c, false, &got_map));
    }
}

/* ---- what a call reports ------------------------------------------------------------------ */

static void info_is_none(const mc_pstore_info_t *info)
{
    assert_int_equal(info->slot, -1);
    assert_int_equal(info->seq, 0u);
    assert_false(info->defaults);
    assert_false(info->map_dropped);
    assert_false(info->fell_back);
    assert_int_equal(info->params.kept, 0u);
    assert_int_equal(info->params.dropped, 0u);
    assert_int_equal(info->params.unknown, 0u);
    assert_false(info->params.other_table);
    assert_int_equal(info->params.first, -1);
}

/* The info a save or a load fills says what happened and nothing else, whatever it held before:
 * a refused call reports no copy (slot -1, number 0, no flag), a save the slot and number it
 * wrote and no other flag, a load of the newest copy no fallback and no defaults.
 * (param_store.c:689, the info's clearing.) */
static void test_info_says_only_what_happened(void **state)
{
    (void)state;
    hal_host_nvm_init(&nvm);
    mc_pstore_info_t info;
    mc_drive_cfg_t got;
    const mc_drive_cfg_t *a = make_cfg(0, 4, 4);
    memset(&info, 0xA5, sizeof info);
    assert_int_equal(mc_pstore_save(&nvm, NULL, work, sizeof work, &info), MC_PSTORE_BAD_ARGS);
    info_is_none(&info);
    memset(&info, 0xA5, sizeof info);
    assert_int_equal(mc_pstore_load(&nvm, &got, &got_map, work, 8u, &info), MC_PSTORE_BAD_ARGS);
    info_is_none(&info);
    memset(&info, 0xA5, sizeof info);
    assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
    info_is_none(&info);

    memset(&info, 0xA5, sizeof info);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 0);
    assert_int_equal(info.seq, 1u);
    assert_false(info.defaults);
    assert_false(info.map_dropped);
    assert_false(info.fell_back);
    memset(&info, 0xA5, sizeof info);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 0);
    assert_int_equal(info.seq, 1u);
    assert_false(info.defaults);
    assert_false(info.map_dropped);
    assert_false(info.fell_back);
    assert_int_equal(info.params.kept, MC_PARAM_COUNT);
    assert_int_equal(info.params.dropped, 0u);
}

/* NULL for the device or the work buffer: refused (BAD_ARGS) by load and erase before any NVM
 * step, cfg untouched, as by save. (param_store.c:742, :775.) */
static void test_null_arguments(void **state)
{
    (void)state;
    hal_host_nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(0, 4, 4);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    snap = nvm;
    mc_drive_cfg_t got = *make_cfg(1, 0, 0);
    const mc_drive_cfg_t before = got;
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_load(&nvm, &got, &got_map, NULL, sizeof work, &info), MC_PSTORE_BAD_ARGS);
    info_is_none(&info);
    assert_int_equal(mc_pstore_load(&nvm, NULL, &got_map, work, sizeof work, &info), MC_PSTORE_BAD_ARGS);
    assert_memory_equal(&got, &before, sizeof got);
    assert_int_equal(mc_pstore_erase(NULL, work, sizeof work), MC_PSTORE_BAD_ARGS);
    assert_int_equal(mc_pstore_erase(&nvm, NULL, sizeof work), MC_PSTORE_BAD_ARGS);
    assert_int_equal(nvm.steps, snap.steps);
    assert_memory_equal(nvm.mem, snap.mem, sizeof nvm.mem);
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg_in(&got, a, false, &got_map));
}

/* With no copy a load returns (a blank device, or both copies damaged) an erase commits its
 * defaults copy into slot 0, as a save would, and erases slot 1: a load then reports the
 * defaults copy in slot 0, numbered 1 on the blank device, above the damaged ones otherwise.
 * (param_store.c:791, the slot an erase writes without a returned copy.) */
static void test_erase_without_a_copy_writes_slot_0(void **state)
{
    (void)state;
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    hal_host_nvm_init(&nvm);
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_OK);
    assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
    assert_true(info.defaults);
    assert_int_equal(info.slot, 0);
    assert_int_equal(info.seq, 1u);
    /* both copies damaged (a bit of each one's records) */
    two_copies();
    slot0[PAYLOAD_AT + 100u] ^= 0x01u;
    slot1[PAYLOAD_AT + 100u] ^= 0x01u;
    assert_int_equal(load(&got, &info), MC_PSTORE_CORRUPT);
    assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_OK);
    assert_int_equal(load(&got, &info), MC_PSTORE_EMPTY);
    assert_true(info.defaults);
    assert_int_equal(info.slot, 0);
    assert_int_equal(info.seq, 3u);
    for (uint32_t k = 0u; k < 64u; ++k) {
        assert_int_equal(slot1[k], 0xFF);   /* the other slot erased */
    }
}

/* A device whose slot cannot even hold a header and its marker (two blocks of 8 to 32 bytes, the
 * copy's records starting at byte 40): TOO_LARGE for geometry (no record bytes), save and erase,
 * before any NVM step; a load finds nothing. (param_store.c:104: no record space below the
 * records' start, not a wrapped-around one.) */
static void test_slot_smaller_than_its_header(void **state)
{
    (void)state;
    for (uint32_t bs = 8u; bs <= 32u; bs += 8u) {
        region[0] = (hal_nvm_region_t){0u, bs, 2u, 0u};
        assert_true(hal_host_nvm_init_geom(&nvm, &device, 0u, 2u));
        mc_pstore_geom_t g;
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_TOO_LARGE);
        assert_int_equal(g.slot_blocks, 1u);
        assert_int_equal(g.payload_max, 0u);
        assert_int_equal(g.map_cells_max, 0u);
        const mc_drive_cfg_t *a = make_cfg(0, 0, 0);
        static uint8_t big[16384];
        mc_pstore_info_t info;
        assert_int_equal(mc_pstore_save(&nvm, a, big, sizeof big, &info), MC_PSTORE_TOO_LARGE);
        assert_int_equal(info.slot, -1);
        assert_int_equal(mc_pstore_erase(&nvm, big, sizeof big), MC_PSTORE_TOO_LARGE);
        assert_int_equal(nvm.steps, 0u);
        mc_drive_cfg_t got;
        assert_int_equal(mc_pstore_load(&nvm, &got, &got_map, big, sizeof big, NULL), MC_PSTORE_TOO_LARGE);
    }
}

/* Each status its own name (the tools and the log print them). (param_store.c:809.) */
static void test_status_names(void **state)
{
    (void)state;
    const char *const want[] = {"ok",        "empty",    "fell_back",   "corrupt", "nvm_error",
                                "too_large", "bad_args", "map_dropped", "partial"};
    const mc_pstore_status_t st[] = {MC_PSTORE_OK,        MC_PSTORE_EMPTY,    MC_PSTORE_FELL_BACK,
                                     MC_PSTORE_CORRUPT,   MC_PSTORE_NVM_ERROR, MC_PSTORE_TOO_LARGE,
                                     MC_PSTORE_BAD_ARGS,  MC_PSTORE_MAP_DROPPED, MC_PSTORE_PARTIAL};
    for (size_t k = 0; k < sizeof st / sizeof st[0]; ++k) {
        assert_string_equal(mc_pstore_status_name(st[k]), want[k]);
    }
    assert_string_equal(mc_pstore_status_name((mc_pstore_status_t)9), "?");
    assert_string_equal(mc_pstore_status_name((mc_pstore_status_t)-1), "?");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_params_record_of_another_version),
        cmocka_unit_test(test_record_crc_word_flipped),
        cmocka_unit_test(test_unknown_header_flag_refused),
        cmocka_unit_test(test_unknown_format_refused),
        cmocka_unit_test(test_other_magic_refused),
        cmocka_unit_test(test_marker_exactly_its_pattern),
        cmocka_unit_test(test_map_dimensions_beyond_the_limits),
        cmocka_unit_test(test_insane_lengths_do_not_count),
        cmocka_unit_test(test_sequence_wraps),
        cmocka_unit_test(test_newer_by_serial_arithmetic),
        cmocka_unit_test(test_largest_copies_touch_their_own_block),
        cmocka_unit_test(test_info_says_only_what_happened),
        cmocka_unit_test(test_null_arguments),
        cmocka_unit_test(test_erase_without_a_copy_writes_slot_0),
        cmocka_unit_test(test_slot_smaller_than_its_header),
        cmocka_unit_test(test_status_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
