/* A stored set across two parameter-table versions (issue 23): this file is built against a
 * second version of the table (params_variant.py: one parameter added in the middle, one
 * removed, two swapped, one range narrowed) with the store's own sources, and reads
 *   - the NVM that the first version (this build's real table, store_tables_write.c) saved, and
 *   - the NVM that main at 5265cfe saved over CANopen (tests/integration/data, record version 1:
 *     positional, keyed by the whole table's hash),
 * checking that every value whose name and type still exist and that passes the new range is
 * kept, the added parameter is at its default, the removed one is skipped, the narrowed one is
 * at its default and reported (MC_PSTORE_PARTIAL, the report's count, id and reason), and that
 * the migrated set, saved again by the second version, reads back whole. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/bits.h"
#include "mc/param_store.h"
#include "store_tables.h"

static hal_nvm_t nvm;
static mc_drive_cfg_t cfg, again;
static mc_params_t defaults;
static uint8_t work[256];

static void read_nvm(const char *path)
{
    hal_host_nvm_init(&nvm);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    assert_int_equal(fread(nvm.mem, hal_host_nvm_bytes(&nvm), 1u, f), 1u);
    fclose(f);
}

static mc_pstore_status_t load(mc_drive_cfg_t *c, mc_pstore_info_t *info)
{
    memset(c, 0, sizeof *c);
    mc_params_default(&c->p);
    return mc_pstore_load(&nvm, c, NULL, work, sizeof work, info);
}

static int id_of(const char *name)
{
    const int id = mc_param_find(name);
    assert_true(id >= 0);
    return id;
}

/* every parameter not named in names[] as in a fresh default set: value bits and "auto" */
static void rest_at_defaults(const mc_params_t *p, const char *const *names, size_t n)
{
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        bool named = false;
        for (size_t k = 0; k < n; ++k) {
            named = named || strcmp(mc_param_table[id].name, names[k]) == 0;
        }
        if (!named) {
            assert_int_equal(mc_param_is_auto(p, id), mc_param_is_auto(&defaults, id));
            assert_int_equal(mc_f32_bits(mc_param_get(p, id)), mc_f32_bits(mc_param_get(&defaults, id)));
        }
    }
}

static void test_second_version_is_another_table(void **state)
{
    (void)state;
    assert_true(mc_param_find("protection.lock_jump_deg") < 0);
    assert_true(id_of("estimator.iter_max") > id_of("protection.lock_action"));
    assert_true(id_of("control.test_added") < id_of("control.speed_bw_hz"));
    assert_true(mc_param_table[id_of("estimator.k1")].max == 0.6f);
    assert_int_not_equal(mc_params_table_hash(), MC_STORE_V1_TABLE);
}

static void test_set_of_the_first_version(void **state)
{
    (void)state;
    read_nvm(STORE_TABLES_FILE);
    mc_pstore_info_t info;
    assert_int_equal(load(&cfg, &info), MC_PSTORE_PARTIAL);
    const mc_store_report_t *r = &info.params;
    assert_true(r->other_table);
    assert_int_equal(r->unknown, 1);                       /* protection.lock_jump_deg */
    assert_int_equal(r->dropped, 1);
    assert_int_equal(r->first, id_of("estimator.k1"));
    assert_int_equal(r->reason, MC_STORE_DROP_RANGE);
    /* the first version has as many parameters (one added, one removed): all but those two */
    assert_int_equal(r->kept, (int)MC_PARAM_COUNT - 2);
    const char *names[STORE_TABLES_N + 1];
    for (size_t k = 0; k < STORE_TABLES_N; ++k) {
        const store_tables_value_t *v = &store_tables_values[k];
        names[k] = v->name;
        const int id = mc_param_find(v->name);
        if (id < 0) {
            continue;   /* removed */
        }
        const float want = strcmp(v->name, "estimator.k1") == 0 ? 0.5f : v->value;   /* narrowed: default */
        assert_true(mc_param_get(&cfg.p, id) == want);
        assert_false(mc_param_is_auto(&cfg.p, id));
    }
    names[STORE_TABLES_N] = "control.test_added";
    assert_true(mc_param_get(&cfg.p, id_of("control.test_added")) == 2.5f);   /* added: default */
    rest_at_defaults(&cfg.p, names, STORE_TABLES_N + 1u);

    /* the migrated set is this version's now: saved, it reads back whole */
    assert_int_equal(mc_pstore_save(&nvm, &cfg, work, sizeof work, NULL), MC_PSTORE_OK);
    assert_int_equal(load(&again, &info), MC_PSTORE_OK);
    assert_false(info.params.other_table);
    assert_int_equal(info.params.dropped, 0);
    assert_int_equal(info.params.unknown, 0);
    assert_int_equal(info.params.kept, (int)MC_PARAM_COUNT);
    assert_memory_equal(&again.p, &cfg.p, sizeof cfg.p);
}

/* The NVM main at 5265cfe saved over CANopen (its README lists the values). */
static void test_set_of_main_5265cfe(void **state)
{
    (void)state;
    read_nvm(NVM_MAIN_FIXTURE);
    mc_pstore_info_t info;
    assert_int_equal(load(&cfg, &info), MC_PSTORE_PARTIAL);
    assert_true(info.params.other_table);
    assert_int_equal(info.params.unknown, 1);
    assert_int_equal(info.params.dropped, 1);
    assert_int_equal(info.params.first, id_of("estimator.k1"));
    assert_true(mc_param_get(&cfg.p, id_of("control.current_bw_hz")) == 80.0f);
    assert_true(mc_param_get(&cfg.p, id_of("estimator.iter_max")) == 6.0f);
    assert_true(mc_param_get(&cfg.p, id_of("control.decouple")) == 0.0f);
    assert_true(mc_param_get(&cfg.p, id_of("protection.lock_action")) == 1.0f);
    assert_true(mc_param_get(&cfg.p, id_of("startup.step1_cost")) == 2.0f);
    assert_true(mc_param_get(&cfg.p, id_of("estimator.k1")) == 0.5f);
    assert_true(mc_param_get(&cfg.p, id_of("control.test_added")) == 2.5f);
    assert_true(mc_param_get(&cfg.p, id_of("startup.init_pos")) == 1.0f);   /* the scenario's three_step */
}

int main(void)
{
    mc_params_default(&defaults);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_second_version_is_another_table),
        cmocka_unit_test(test_set_of_the_first_version),
        cmocka_unit_test(test_set_of_main_5265cfe),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
