/* The stored records at their edges (mc/store.h): an encoder writes its record only into a buffer
 * that holds all of it, a decoder reads no byte beyond the n it is given (a record at the end of
 * a flash window or an NVM page) and writes no cell beyond the grid it stores, a version 1
 * position outside the frozen table names no parameter, and a read that dropped nothing says so. */
#define _DEFAULT_SOURCE   /* mmap's MAP_ANONYMOUS under -std=c11 */
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "../mc_test.h"
#include "mc/bits.h"
#include "mc/store.h"

static uint8_t buf[MC_CONFIG_AREA_SIZE];

/* A 5 x 7 map (not square, not the maximum) with distinct cells. */
static void small_map(mc_flux_map_t *map)
{
    memset(map, 0, sizeof *map);
    map->n_d = 5;
    map->n_q = 7;
    map->id0 = -20.0f;
    map->did = 5.0f;
    map->iq0 = -15.0f;
    map->diq = 5.0f;
    for (int k = 0; k < 35; ++k) {
        map->psi_d[k] = 0.3f + 0.001f * (float)k;
        map->psi_q[k] = -0.1f + 0.002f * (float)k;
    }
}

/* The parameter record is 4 (5 + 2 n) bytes: written whole into exactly that, refused one byte
 * short with the buffer untouched (no partial record that a later read could half-trust). */
static void test_params_encode_capacity(void **state)
{
    (void)state;
    mc_params_t p;
    mc_params_default(&p);
    const size_t len = 4u * (5u + 2u * (size_t)MC_PARAM_COUNT);
    assert_int_equal(len, MC_STORE_PARAMS_MAX);
    memset(buf, 0xA5, sizeof buf);
    assert_int_equal(mc_store_params_encode(&p, buf, len - 1u), 0u);
    for (size_t k = 0; k < len + 8u; ++k) {
        assert_int_equal(buf[k], 0xA5u);
    }
    assert_int_equal(mc_store_params_encode(&p, buf, len), len);
    assert_int_equal(buf[len], 0xA5u);   /* nothing after it */
    mc_params_t q;
    assert_int_equal(mc_store_params_decode(buf, len, &q, NULL), MC_STORE_OK);
}

/* The model record: 8 words without a map, 14 + 2 n_d n_q with one; each written into exactly
 * its size, refused one byte short with the buffer untouched. */
static void test_model_encode_capacity(void **state)
{
    (void)state;
    static mc_flux_map_t map;
    small_map(&map);
    const mc_est_model_t with = {0.4f, 0.0105f, 0.0129f, 0.343f, &map};
    const mc_est_model_t without = {0.4f, 0.0105f, 0.0129f, 0.343f, NULL};
    const struct {
        const mc_est_model_t *m;
        size_t len;
    } cases[] = {{&without, 32u}, {&with, 4u * (14u + 2u * 35u)}};
    for (size_t c = 0; c < 2u; ++c) {
        const size_t len = cases[c].len;
        memset(buf, 0xA5, sizeof buf);
        assert_int_equal(mc_store_model_encode(cases[c].m, buf, len - 1u), 0u);
        for (size_t k = 0; k < len + 8u; ++k) {
            assert_int_equal(buf[k], 0xA5u);
        }
        assert_int_equal(mc_store_model_encode(cases[c].m, buf, len), len);
        assert_int_equal(buf[len], 0xA5u);
        mc_est_model_t r;
        static mc_flux_map_t out;
        assert_int_equal(mc_store_model_decode(buf, len, &r, &out), MC_STORE_OK);
    }
}

/* A readable page followed by one that faults on any access: a record copied to end exactly at
 * the boundary is read by a decoder that must stay within its n bytes. */
static uint8_t *page_end(void)
{
    static uint8_t *end;
    if (end == NULL) {
        const size_t pg = (size_t)sysconf(_SC_PAGESIZE);
        const size_t span = ((MC_STORE_MODEL_MAX + pg - 1u) / pg) * pg;
        uint8_t *base = mmap(NULL, span + pg, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        assert_true(base != MAP_FAILED);
        assert_int_equal(mprotect(base + span, pg, PROT_NONE), 0);
        end = base + span;
    }
    return end;
}

/* Every prefix of a record (a write cut short by a power loss, a length field that lies) at the
 * end of readable memory: refused as too short, or read whole, never a byte beyond n. The model
 * record with a map cut inside its map header (32..55 bytes) is the case a decoder must not
 * take for a map's dimensions it does not have. */
static void test_decode_reads_within_n(void **state)
{
    (void)state;
    static mc_flux_map_t map, out;
    small_map(&map);
    const mc_est_model_t m = {0.4f, 0.0105f, 0.0129f, 0.343f, &map};
    const size_t full = mc_store_model_encode(&m, buf, sizeof buf);
    assert_int_equal(full, 4u * (14u + 2u * 35u));
    uint8_t *const end = page_end();
    for (size_t n = 0; n <= full; ++n) {
        uint8_t *rec = end - n;
        memcpy(rec, buf, n);
        mc_est_model_t r = {0};
        const mc_store_status_t want = n == full ? MC_STORE_OK : MC_STORE_BAD_SIZE;
        assert_int_equal(mc_store_model_decode(rec, n, &r, &out), want);
        assert_int_equal(mc_store_model_view(rec, n, &r, &map), want);
    }
    mc_params_t p, q;
    mc_params_default(&p);
    const size_t pfull = mc_store_params_encode(&p, buf, sizeof buf);
    for (size_t n = 0; n <= pfull; ++n) {
        uint8_t *rec = end - n;
        memcpy(rec, buf, n);
        assert_int_equal(mc_store_params_decode(rec, n, &q, NULL), n == pfull ? MC_STORE_OK : MC_STORE_BAD_SIZE);
    }
}

/* The decoded map is the stored grid and nothing more: the caller's cells beyond n_d n_q keep
 * what they held, and a full 41 x 41 map ends at the end of the caller's mc_flux_map_t. */
static void test_decode_writes_within_grid(void **state)
{
    (void)state;
    static mc_flux_map_t map;
    static struct {
        mc_flux_map_t map;
        uint32_t guard[4];   /* what the caller keeps right after its map */
    } out;
    small_map(&map);
    const mc_est_model_t m = {0.4f, 0.0105f, 0.0129f, 0.343f, &map};
    size_t n = mc_store_model_encode(&m, buf, sizeof buf);
    for (int k = 0; k < MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX; ++k) {
        out.map.psi_d[k] = out.map.psi_q[k] = -7.0f;
    }
    mc_est_model_t r;
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out.map), MC_STORE_OK);
    assert_memory_equal(out.map.psi_d, map.psi_d, 35u * sizeof(float));
    assert_memory_equal(out.map.psi_q, map.psi_q, 35u * sizeof(float));
    for (int k = 35; k < MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX; ++k) {
        assert_true(out.map.psi_d[k] == -7.0f && out.map.psi_q[k] == -7.0f);
    }

    static mc_flux_map_t big;
    memset(&big, 0, sizeof big);
    big.n_d = big.n_q = MC_FLUX_MAP_MAX;
    big.id0 = -40.0f;
    big.did = 2.0f;
    big.iq0 = -40.0f;
    big.diq = 2.0f;
    for (int k = 0; k < MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX; ++k) {
        big.psi_d[k] = 0.001f * (float)k;
        big.psi_q[k] = -0.001f * (float)k;
    }
    const mc_est_model_t mb = {0.4f, 0.0105f, 0.0129f, 0.343f, &big};
    n = mc_store_model_encode(&mb, buf, sizeof buf);
    assert_int_equal(n, MC_STORE_MODEL_MAX);
    for (int k = 0; k < 4; ++k) {
        out.guard[k] = 0x600DF00Du;
    }
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out.map), MC_STORE_OK);
    assert_memory_equal(&out.map, &big, sizeof big);
    for (int k = 0; k < 4; ++k) {
        assert_int_equal(out.guard[k], 0x600DF00Du);
    }
}

/* A model record without a map needs no map storage (map_out NULL: the scalars alone); one with
 * a map and nowhere to put it is refused, the model untouched. */
static void test_model_decode_without_map_storage(void **state)
{
    (void)state;
    static mc_flux_map_t map;
    small_map(&map);
    const mc_est_model_t nomap = {0.4f, 0.0105f, 0.0129f, 0.343f, NULL};
    size_t n = mc_store_model_encode(&nomap, buf, sizeof buf);
    mc_est_model_t r = {0};
    r.map = &map;
    assert_int_equal(mc_store_model_decode(buf, n, &r, NULL), MC_STORE_OK);
    assert_true(r.rs == 0.4f && r.ld == 0.0105f && r.lq == 0.0129f && r.psi_pm == 0.343f);
    assert_null(r.map);

    const mc_est_model_t with = {0.5f, 0.01f, 0.02f, 0.3f, &map};
    n = mc_store_model_encode(&with, buf, sizeof buf);
    const mc_est_model_t before = r;
    assert_int_equal(mc_store_model_decode(buf, n, &r, NULL), MC_STORE_BAD_SIZE);
    assert_memory_equal(&r, &before, sizeof r);
}

/* a record's word: little-endian */
static void put_le(size_t at, uint32_t w)
{
    for (int k = 0; k < 4; ++k) {
        buf[at + (size_t)k] = (uint8_t)(w >> (8 * k));
    }
}

/* A model record with an n_d x n_q map sealed by hand (the encoder refuses the grids a damaged or
 * foreign record may claim); cells k: psi_d = 0.2 + 0.01 k, psi_q = -0.003 k. Its length. */
static size_t model_record(uint32_t nd, uint32_t nq)
{
    const uint32_t head[13] = {MC_STORE_MAGIC_MODEL, MC_STORE_VERSION, mc_f32_bits(0.4f), mc_f32_bits(0.0105f),
                               mc_f32_bits(0.0129f), mc_f32_bits(0.343f), 1u, nd, nq, mc_f32_bits(-10.0f),
                               mc_f32_bits(5.0f), mc_f32_bits(-8.0f), mc_f32_bits(4.0f)};
    size_t at = 0u;
    for (int k = 0; k < 13; ++k, at += 4u) {
        put_le(at, head[k]);
    }
    const size_t cells = (size_t)nd * nq;
    for (size_t k = 0; k < 2u * cells; ++k, at += 4u) {
        const float v = k < cells ? 0.2f + 0.01f * (float)k : -0.003f * (float)(k - cells);
        put_le(at, mc_f32_bits(v));
    }
    put_le(at, mc_crc32(buf, at));
    return at + 4u;
}

/* The map's grid needs two points per axis to interpolate and has at most MC_FLUX_MAP_MAX: a
 * record claiming 0 or 1 or MAX + 1 on either axis, its CRC right, is refused by decode and view;
 * the smallest (2 x 2, 2 x 3, 3 x 2) and the long thin (2 x MAX, MAX x 2) grids are read. */
static void test_model_grid_dimensions(void **state)
{
    (void)state;
    static mc_flux_map_t out, place;
    const uint32_t bad[][2] = {{0u, 3u}, {1u, 3u}, {3u, 0u}, {3u, 1u}, {1u, 1u}, {0u, 0u},
                               {MC_FLUX_MAP_MAX + 1u, 2u}, {2u, MC_FLUX_MAP_MAX + 1u}};
    for (size_t b = 0; b < sizeof bad / sizeof bad[0]; ++b) {
        const size_t n = model_record(bad[b][0], bad[b][1]);
        mc_est_model_t r = {0};
        assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_BAD_SIZE);
        assert_int_equal(mc_store_model_view(buf, n, &r, &out), MC_STORE_BAD_SIZE);
        assert_null(r.map);
    }
    const uint32_t good[][2] = {{2u, 2u}, {2u, 3u}, {3u, 2u}, {2u, MC_FLUX_MAP_MAX}, {MC_FLUX_MAP_MAX, 2u}};
    for (size_t g = 0; g < sizeof good / sizeof good[0]; ++g) {
        const size_t n = model_record(good[g][0], good[g][1]);
        mc_est_model_t r = {0};
        assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_OK);
        assert_ptr_equal(r.map, &out);
        assert_int_equal(out.n_d, (int)good[g][0]);
        assert_int_equal(out.n_q, (int)good[g][1]);
        assert_true(out.did == 5.0f && out.diq == 4.0f);
        const size_t cells = (size_t)good[g][0] * good[g][1];
        assert_true(out.psi_d[cells - 1u] == 0.2f + 0.01f * (float)(cells - 1u));
        assert_true(out.psi_q[cells - 1u] == -0.003f * (float)(cells - 1u));
        place = out;
        assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_OK);
        assert_ptr_equal(r.map, &place);
    }
}

/* The map in place must have the record's grid exactly: a map whose dimensions differ either way
 * on either axis (its cells the record's, so only the dimension tells) describes another grid and
 * is refused, as is one whose origin or step differs either way. */
static void test_model_view_other_grid(void **state)
{
    (void)state;
    static mc_flux_map_t good, place;
    const size_t n = model_record(4u, 5u);
    mc_est_model_t r = {0};
    assert_int_equal(mc_store_model_decode(buf, n, &r, &good), MC_STORE_OK);
    place = good;
    assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_OK);
    for (int axis = 0; axis < 2; ++axis) {
        for (int d = -1; d <= 1; d += 2) {
            place = good;
            if (axis == 0) {
                place.n_d += d;
            } else {
                place.n_q += d;
            }
            r.map = NULL;
            assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_MAP_MISMATCH);
            assert_null(r.map);
        }
    }
    for (int f = 0; f < 4; ++f) {
        for (int d = -1; d <= 1; d += 2) {
            place = good;
            float *x = f == 0 ? &place.id0 : f == 1 ? &place.did : f == 2 ? &place.iq0 : &place.diq;
            *x = mc_bits_f32((uint32_t)((int64_t)mc_f32_bits(*x) + d));   /* one ulp either way */
            assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_MAP_MISMATCH);
        }
    }
    /* ... and one whose flux differs in one cell by one ulp either way, first, middle and last,
     * on either axis: the map in place is not the stored one */
    const size_t cells = 4u * 5u, at[] = {0u, cells / 2u, cells - 1u};
    for (int axis = 0; axis < 2; ++axis) {
        for (size_t i = 0; i < 3u; ++i) {
            for (int d = -1; d <= 1; d += 2) {
                place = good;
                float *x = axis == 0 ? &place.psi_d[at[i]] : &place.psi_q[at[i]];
                *x = mc_bits_f32((uint32_t)((int64_t)mc_f32_bits(*x) + d));
                assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_MAP_MISMATCH);
            }
        }
    }
}

/* What a model slot holds says itself: erased memory is "nothing stored" (the image boots on the
 * parameters' motor model), another record's magic and another version are told apart from a
 * damaged record, by decode and view alike; nothing is changed. */
static void test_model_slot_status(void **state)
{
    (void)state;
    static mc_flux_map_t out;
    const size_t n = model_record(3u, 3u);
    mc_est_model_t r = {0};
    const mc_est_model_t before = r;
    memset(buf, 0xFF, n);
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_EMPTY);
    assert_int_equal(mc_store_model_view(buf, n, &r, &out), MC_STORE_EMPTY);
    model_record(3u, 3u);
    put_le(0u, MC_STORE_MAGIC_PARAMS);
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_BAD_MAGIC);
    assert_int_equal(mc_store_model_view(buf, n, &r, &out), MC_STORE_BAD_MAGIC);
    /* a damaged magic word, one below and one above the model's own: neither is the model's */
    for (int d = -1; d <= 1; d += 2) {
        model_record(3u, 3u);
        put_le(0u, MC_STORE_MAGIC_MODEL + (uint32_t)d);
        assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_BAD_MAGIC);
        assert_int_equal(mc_store_model_view(buf, n, &r, &out), MC_STORE_BAD_MAGIC);
    }
    model_record(3u, 3u);
    put_le(4u, MC_STORE_VERSION + 1u);
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_BAD_VERSION);
    assert_int_equal(mc_store_model_view(buf, n, &r, &out), MC_STORE_BAD_VERSION);
    assert_memory_equal(&r, &before, sizeof r);
}

/* A version 1 record holds positions; one outside the frozen table of 95 (a damaged word, or the
 * largest a word can carry once its derived mark is off) names no parameter: key 0, which the
 * NVM store refuses. */
static void test_v1_key_outside_frozen_table(void **state)
{
    (void)state;
    assert_int_not_equal(mc_store_v1_key(0u), 0u);
    assert_int_not_equal(mc_store_v1_key(MC_STORE_V1_COUNT - 1u), 0u);
    const uint32_t outside[] = {MC_STORE_V1_COUNT, MC_STORE_V1_COUNT + 1u, MC_STORE_V1_COUNT + 2u, 1000u,
                                0x00FFFFFFu, ~MC_STORE_V1_AUTO, 0xFFFFFFFFu};
    for (size_t k = 0; k < sizeof outside / sizeof outside[0]; ++k) {
        assert_int_equal(mc_store_v1_key(outside[k]), 0u);
    }
}

/* A read that dropped nothing reports no first dropped parameter (-1, not an id), whatever the
 * caller's report held before. */
static void test_report_none_dropped(void **state)
{
    (void)state;
    mc_store_report_t rep;
    memset(&rep, 0x5A, sizeof rep);
    mc_store_report_clear(&rep);
    assert_int_equal(rep.first, -1);
    assert_int_equal(rep.kept, 0);
    assert_int_equal(rep.dropped, 0);
    assert_int_equal(rep.unknown, 0);
    assert_int_equal(rep.reason, MC_STORE_DROP_NONE);
    assert_false(rep.other_table);

    mc_params_t p, q;
    mc_params_default(&p);
    const size_t n = mc_store_params_encode(&p, buf, sizeof buf);
    memset(&rep, 0x5A, sizeof rep);
    assert_int_equal(mc_store_params_decode(buf, n, &q, &rep), MC_STORE_OK);
    assert_int_equal(rep.kept, MC_PARAM_COUNT);
    assert_int_equal(rep.dropped, 0);
    assert_int_equal(rep.unknown, 0);
    assert_int_equal(rep.first, -1);
    assert_false(rep.other_table);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_params_encode_capacity),
        cmocka_unit_test(test_model_encode_capacity),
        cmocka_unit_test(test_decode_reads_within_n),
        cmocka_unit_test(test_decode_writes_within_grid),
        cmocka_unit_test(test_model_decode_without_map_storage),
        cmocka_unit_test(test_model_grid_dimensions),
        cmocka_unit_test(test_model_view_other_grid),
        cmocka_unit_test(test_model_slot_status),
        cmocka_unit_test(test_v1_key_outside_frozen_table),
        cmocka_unit_test(test_report_none_dropped),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
