/* The parameter record read by name (mc/store.h) where the position hint does not help, and the
 * model record's grid limits (issue 30, the survivors of the mutation run in store.c):
 *   - a record of this table with its entries in any order (reversed, rotated): every value is
 *     found by its name, the first parameter of the table too;
 *   - a record with more entries than this table has parameters (a newer table's): the extra
 *     ones are unknown, and looking for them reads nothing outside the table;
 *   - a derived mark after a value for the same parameter (a record spliced by a tool), and the
 *     mark applied on a set where the parameter has a value: the parameter follows its rule again;
 *   - a record in a buffer larger than itself is read to its own end;
 *   - the encoder refuses a map with fewer than 2 or more than MC_FLUX_MAP_MAX points on either
 *     axis; every status has its own name.
 * Built with ASan and UBSan (tests/unit/app/CMakeLists.txt: store.c and params.c compiled again
 * with them), so that a read of the parameter table outside its bounds fails the test. */
#include <string.h>

#include "../mc_test.h"
#include "mc/bits.h"
#include "mc/store.h"

static uint8_t buf[MC_CONFIG_AREA_SIZE];

static void put_word(size_t at, uint32_t w)
{
    buf[at] = (uint8_t)w;
    buf[at + 1u] = (uint8_t)(w >> 8);
    buf[at + 2u] = (uint8_t)(w >> 16);
    buf[at + 3u] = (uint8_t)(w >> 24);
}

/* the record's count word and its closing CRC for n entries; returns its length */
static size_t seal(uint32_t n)
{
    put_word(12u, n);
    const size_t len = 4u * (5u + 2u * (size_t)n);
    put_word(len - 4u, mc_crc32(buf, len - 4u));
    return len;
}

/* A set with every parameter that has no rule moved off its default (within its range) and every
 * other one derived, so that a value in the wrong place or lost shows. */
static void moved_set(mc_params_t *p)
{
    mc_params_default(p);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const mc_param_info_t *e = &mc_param_table[id];
        if (e->rule != (uint8_t)MC_RULE_NONE) {
            continue;
        }
        const float v = e->def < e->max ? (e->type == MC_PT_F32 ? 0.5f * (e->def + e->max) : e->def + 1.0f) : e->min;
        (void)mc_param_set(p, id, v, NULL);
    }
}

static void assert_same_set(const mc_params_t *got, const mc_params_t *want)
{
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        assert_int_equal(mc_param_is_auto(got, id), mc_param_is_auto(want, id));
        assert_int_equal(mc_f32_bits(mc_param_get(got, id)), mc_f32_bits(mc_param_get(want, id)));
    }
}

/* This table's record with its entries in another order: entry k holds parameter order(k). A
 * reader finds each by its name, whatever its position (the position only a hint): reversed,
 * the table's first parameter is the last entry; rotated by one, every entry is one off. */
static void test_entries_in_any_order(void **state)
{
    (void)state;
    static mc_params_t p, q;
    moved_set(&p);
    static uint8_t rec[MC_STORE_PARAMS_MAX];
    const size_t n = mc_store_params_encode(&p, rec, sizeof rec);
    assert_int_equal(n, MC_STORE_PARAMS_MAX);
    const uint32_t count = (uint32_t)MC_PARAM_COUNT;
    for (int order = 0; order < 3; ++order) {
        memcpy(buf, rec, n);
        for (uint32_t k = 0u; k < count; ++k) {
            const uint32_t from = order == 0 ? k : order == 1 ? count - 1u - k : (k + 1u) % count;
            memcpy(buf + 16u + 8u * k, rec + 16u + 8u * from, 8u);
        }
        assert_int_equal(seal(count), n);
        mc_store_report_t rep;
        assert_int_equal(mc_store_params_decode(buf, n, &q, &rep), MC_STORE_OK);
        assert_int_equal(rep.kept, count);
        assert_int_equal(rep.unknown, 0u);
        assert_int_equal(rep.dropped, 0u);
        assert_false(rep.other_table);
        assert_same_set(&q, &p);
    }
}

/* A newer table's record: this table's entries, then names this table does not have (their
 * positions past its last parameter): those are unknown, everything else kept. */
static void test_more_entries_than_the_table(void **state)
{
    (void)state;
    static mc_params_t p, q;
    moved_set(&p);
    const size_t n0 = mc_store_params_encode(&p, buf, sizeof buf);
    assert_int_equal(n0, MC_STORE_PARAMS_MAX);
    const uint32_t extra[] = {0x12345670u | MC_PT_F32, 0x0BADCAF0u | MC_PT_I32, 0x76543210u | MC_PT_F32};
    for (size_t k = 0; k < 3u; ++k) {
        for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
            assert_int_not_equal(mc_store_param_key(id) & MC_STORE_KEY_NAME, extra[k] & MC_STORE_KEY_NAME);
        }
        const size_t at = 16u + 8u * ((size_t)MC_PARAM_COUNT + k);
        put_word(at, extra[k]);
        put_word(at + 4u, mc_f32_bits(1.0f));
    }
    const size_t n = seal((uint32_t)MC_PARAM_COUNT + 3u);
    mc_store_report_t rep;
    assert_int_equal(mc_store_params_decode(buf, n, &q, &rep), MC_STORE_OK);
    assert_int_equal(rep.kept, MC_PARAM_COUNT);
    assert_int_equal(rep.unknown, 3u);
    assert_int_equal(rep.dropped, 0u);
    assert_same_set(&q, &p);
}

/* The derived mark (MC_STORE_KEY_AUTO) puts a parameter that has a rule back on it, also where
 * the set had a value for it: after a value of the same parameter earlier in the record (a
 * record spliced by a tool, the later entry wins), and applied on its own to a set that holds a
 * value. A parameter without a rule (its rule gone since the record was written) keeps its
 * value, never marked derived. */
static void test_derived_mark_after_a_value(void **state)
{
    (void)state;
    const int cc = mc_param_find("control.current_bw_hz");
    assert_int_not_equal(mc_param_table[cc].rule, MC_RULE_NONE);
    const float v = 0.5f * (mc_param_table[cc].min + mc_param_table[cc].max);
    /* the record: cc = v, then cc derived */
    const uint32_t words[] = {mc_store_param_key(cc), mc_f32_bits(v), mc_store_param_key(cc) | MC_STORE_KEY_AUTO,
                              mc_f32_bits(0.0f)};
    put_word(0u, MC_STORE_MAGIC_PARAMS);
    put_word(4u, MC_STORE_PARAMS_VERSION);
    put_word(8u, mc_params_table_hash());
    for (size_t k = 0; k < 4u; ++k) {
        put_word(16u + 4u * k, words[k]);
    }
    static mc_params_t q;
    mc_store_report_t rep;
    assert_int_equal(mc_store_params_decode(buf, seal(2u), &q, &rep), MC_STORE_OK);
    assert_int_equal(rep.kept, 2u);
    assert_true(mc_param_is_auto(&q, cc));   /* its value: the rule's, when the set is derived */
    /* only the value: it stays */
    assert_int_equal(mc_store_params_decode(buf, seal(1u), &q, &rep), MC_STORE_OK);
    assert_false(mc_param_is_auto(&q, cc));
    assert_true(mc_param_get(&q, cc) == v);

    /* the mark on its own, on a set holding a value */
    mc_store_report_clear(&rep);
    mc_store_param_apply(&q, mc_store_param_key(cc) | MC_STORE_KEY_AUTO, 0u, (uint32_t)cc, &rep);
    assert_true(mc_param_is_auto(&q, cc));
    assert_int_equal(rep.kept, 1u);
    /* a parameter without a rule: its value stays, not derived */
    const int ts = mc_param_find("control.ts_s");
    assert_int_equal(mc_param_table[ts].rule, MC_RULE_NONE);
    assert_true(mc_param_set(&q, ts, 2e-4f, NULL));
    mc_store_param_apply(&q, mc_store_param_key(ts) | MC_STORE_KEY_AUTO, 0u, (uint32_t)ts, &rep);
    assert_false(mc_param_is_auto(&q, ts));
    assert_true(mc_param_get(&q, ts) == 2e-4f);
    assert_int_equal(rep.kept, 2u);
}

/* A parameter record read from a buffer larger than the record (a flash window, the whole
 * configuration area): its own count says where it ends, the bytes after it are not looked at;
 * a buffer one word short of the record is BAD_SIZE. The smallest record, of no values, is read
 * too. (store.c:216, :220.) */
static void test_params_record_in_a_larger_buffer(void **state)
{
    (void)state;
    static mc_params_t p, q;
    moved_set(&p);
    const size_t n = mc_store_params_encode(&p, buf, sizeof buf);
    assert_int_equal(n, MC_STORE_PARAMS_MAX);
    const size_t more[] = {0u, 4u, 7u, 8u, 100u, sizeof buf - n};
    for (size_t i = 0; i < sizeof more / sizeof more[0]; ++i) {
        memset(buf + n, (int)(0x11u * i), sizeof buf - n);
        mc_store_report_t rep;
        assert_int_equal(mc_store_params_decode(buf, n + more[i], &q, &rep), MC_STORE_OK);
        assert_int_equal(rep.kept, MC_PARAM_COUNT);
        assert_same_set(&q, &p);
    }
    assert_int_equal(mc_store_params_decode(buf, n - 4u, &q, NULL), MC_STORE_BAD_SIZE);

    /* a record of no values (20 bytes: a tool's "all defaults"): read, every parameter at its
     * default; in exactly its 20 bytes too; 16 bytes hold no record */
    put_word(8u, mc_params_table_hash());
    const size_t n0 = seal(0u);
    assert_int_equal(n0, 20u);
    static mc_params_t d;
    mc_params_default(&d);
    for (size_t extra = 0u; extra <= 8u; extra += 4u) {
        mc_store_report_t rep;
        assert_int_equal(mc_store_params_decode(buf, n0 + extra, &q, &rep), MC_STORE_OK);
        assert_int_equal(rep.kept + rep.dropped + rep.unknown, 0u);
        assert_same_set(&q, &d);
    }
    assert_int_equal(mc_store_params_decode(buf, 16u, &q, NULL), MC_STORE_BAD_SIZE);
}

/* A map the encoder takes has 2 to MC_FLUX_MAP_MAX points on each axis (the thesis' flux map
 * needs two points to interpolate, the record's size bounds it): on each axis, with the other
 * valid, 2 and MC_FLUX_MAP_MAX are written, -1, 0, 1 and MC_FLUX_MAP_MAX + 1 refused (0 bytes,
 * the buffer untouched). */
static void test_model_encode_grid_limits(void **state)
{
    (void)state;
    static mc_flux_map_t map;
    memset(&map, 0, sizeof map);
    map.did = 1.0f;
    map.diq = 1.0f;
    const mc_est_model_t m = {0.4f, 0.0105f, 0.0129f, 0.343f, &map};
    const int sizes[] = {-1, 0, 1, 2, MC_FLUX_MAP_MAX, MC_FLUX_MAP_MAX + 1};
    for (int axis = 0; axis < 2; ++axis) {
        for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
            const int n = sizes[i];
            map.n_d = axis == 0 ? n : 3;
            map.n_q = axis == 0 ? 3 : n;
            memset(buf, 0xA5, sizeof buf);
            const size_t len = mc_store_model_encode(&m, buf, sizeof buf);
            if (n >= 2 && n <= MC_FLUX_MAP_MAX) {
                assert_int_equal(len, 4u * (14u + 2u * 3u * (size_t)n));
                mc_est_model_t r;
                static mc_flux_map_t out;
                assert_int_equal(mc_store_model_decode(buf, len, &r, &out), MC_STORE_OK);
                assert_int_equal(out.n_d, map.n_d);
                assert_int_equal(out.n_q, map.n_q);
            } else {
                assert_int_equal(len, 0u);
                for (size_t k = 0; k < MC_STORE_MODEL_MAX; ++k) {
                    assert_int_equal(buf[k], 0xA5u);
                }
            }
        }
    }
}

/* Each status its own name (the tools and the log print them). */
static void test_status_names(void **state)
{
    (void)state;
    const char *const want[] = {"ok",          "empty",    "bad_magic", "bad_version", "other_table",
                                "bad_size",    "bad_crc",  "bad_value", "map_mismatch"};
    const mc_store_status_t st[] = {MC_STORE_OK,       MC_STORE_EMPTY,    MC_STORE_BAD_MAGIC,
                                    MC_STORE_BAD_VERSION, MC_STORE_OTHER_TABLE, MC_STORE_BAD_SIZE,
                                    MC_STORE_BAD_CRC,  MC_STORE_BAD_VALUE, MC_STORE_MAP_MISMATCH};
    for (size_t k = 0; k < sizeof st / sizeof st[0]; ++k) {
        assert_string_equal(mc_store_status_name(st[k]), want[k]);
    }
    assert_string_equal(mc_store_status_name((mc_store_status_t)9), "?");
    assert_string_equal(mc_store_status_name((mc_store_status_t)-1), "?");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_entries_in_any_order),
        cmocka_unit_test(test_more_entries_than_the_table),
        cmocka_unit_test(test_derived_mark_after_a_value),
        cmocka_unit_test(test_params_record_in_a_larger_buffer),
        cmocka_unit_test(test_model_encode_grid_limits),
        cmocka_unit_test(test_status_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
