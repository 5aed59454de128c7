/* The parameter store on hal_nvm (mc/nvstore.h): round trip, fall-back, and the power-cut sweep:
 * a cut at every step of a save (and of a restore) leaves exactly the last committed set or the
 * new one, never a mix, never an older set, never "corrupt". */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/nvstore.h"

static hal_nvm_t nvm;
static uint8_t work[MC_NVSTORE_WORK];

/* parameter set number k: a few entries moved off their defaults */
static void make_set(mc_params_t *p, int k)
{
    mc_params_default(p);
    assert_true(mc_param_set(p, mc_param_find("control.ts_s"), 1e-4f - 1e-6f * (float)(k % 40), NULL));
    assert_true(mc_param_set(p, mc_param_find("hw.encoder_lines"), (float)(1000 + k), NULL));
    assert_true(mc_param_set(p, mc_param_find("hw.dead_time_s"), 1e-7f * (float)(k % 50), NULL));
}

static bool same(const mc_params_t *a, const mc_params_t *b)
{
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (mc_param_is_auto(a, id) != mc_param_is_auto(b, id)) {
            return false;
        }
        if (!mc_param_is_auto(a, id)) {
            const float x = mc_param_get(a, id), y = mc_param_get(b, id);
            if (memcmp(&x, &y, sizeof x) != 0) {
                return false;
            }
        }
    }
    return true;
}

static void test_empty_then_round_trip(void **state)
{
    (void)state;
    hal_host_nvm_init(&nvm);
    mc_params_t a, got;
    mc_params_default(&got);
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, NULL), MC_NVSTORE_EMPTY);
    make_set(&a, 1);
    assert_int_equal(mc_nvstore_save(&nvm, &a, work, sizeof work), MC_NVSTORE_OK);
    uint32_t seq = 0;
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, &seq), MC_NVSTORE_OK);
    assert_true(same(&a, &got));
    assert_int_equal(seq, 1u);
    /* too small a work buffer is refused, not overrun */
    assert_int_equal(mc_nvstore_save(&nvm, &a, work, 100u), MC_NVSTORE_BAD_ARGS);
}

static void test_corrupt_newest_falls_back(void **state)
{
    (void)state;
    hal_host_nvm_init(&nvm);
    mc_params_t a, b, got;
    make_set(&a, 2);
    make_set(&b, 3);
    assert_int_equal(mc_nvstore_save(&nvm, &a, work, sizeof work), MC_NVSTORE_OK);   /* slot 0 */
    assert_int_equal(mc_nvstore_save(&nvm, &b, work, sizeof work), MC_NVSTORE_OK);   /* slot 1 */
    nvm.mem[HAL_HOST_NVM_BLOCKS / 2u][200] ^= 0x04u;   /* a bit of b's record flips */
    mc_params_default(&got);
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, NULL), MC_NVSTORE_FELL_BACK);
    assert_true(same(&a, &got));
    /* the next save goes over the corrupt copy, never over the good one */
    assert_int_equal(mc_nvstore_save(&nvm, &b, work, sizeof work), MC_NVSTORE_OK);
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, NULL), MC_NVSTORE_OK);
    assert_true(same(&b, &got));
    nvm.mem[0][300] ^= 0x10u;
    nvm.mem[HAL_HOST_NVM_BLOCKS / 2u][300] ^= 0x10u;
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, NULL), MC_NVSTORE_CORRUPT);
}

/* Count the NVM steps of an operation run without a cut. */
static uint32_t steps_of(int op, const mc_params_t *p)
{
    const uint32_t before = nvm.steps;
    assert_int_equal(op == 0 ? mc_nvstore_save(&nvm, p, work, sizeof work)
                             : mc_nvstore_restore_defaults(&nvm, work, sizeof work),
                     MC_NVSTORE_OK);
    return nvm.steps - before;
}

/* From a store holding `old` (seq n), run op (0 save `next`, 1 restore) cut at every step. */
static unsigned sweep(const mc_params_t *history, int n_hist, const mc_params_t *next, int op)
{
    unsigned cuts = 0;
    for (uint32_t s = 1;; ++s) {
        hal_host_nvm_init(&nvm);
        for (int k = 0; k < n_hist; ++k) {
            assert_int_equal(mc_nvstore_save(&nvm, &history[k], work, sizeof work), MC_NVSTORE_OK);
        }
        const uint32_t total = steps_of(op, next);
        if (s > total) {
            break;
        }
        /* again from the same history, cut at step s of the operation */
        hal_host_nvm_init(&nvm);
        for (int k = 0; k < n_hist; ++k) {
            assert_int_equal(mc_nvstore_save(&nvm, &history[k], work, sizeof work), MC_NVSTORE_OK);
        }
        hal_host_nvm_cut_at(&nvm, nvm.steps + s);
        (void)(op == 0 ? mc_nvstore_save(&nvm, next, work, sizeof work)
                       : mc_nvstore_restore_defaults(&nvm, work, sizeof work));
        hal_host_nvm_power_on(&nvm);
        hal_host_nvm_cut_at(&nvm, 0);
        mc_params_t got;
        mc_params_default(&got);
        const mc_nvstore_status_t st = mc_nvstore_load(&nvm, &got, work, sizeof work, NULL);
        const mc_params_t *last = n_hist > 0 ? &history[n_hist - 1] : NULL;
        if (op == 0) {
            /* the last committed set, or the new one once the marker is complete */
            const bool is_old = last != NULL && st == MC_NVSTORE_OK && same(&got, last);
            const bool is_new = st == MC_NVSTORE_OK && same(&got, next);
            const bool was_empty = last == NULL && st == MC_NVSTORE_EMPTY;
            if (!(is_old || is_new || was_empty)) {
                fail_msg("save cut at step %u of %u: status %s", s, total, mc_nvstore_status_name(st));
            }
            if (s == total) {   /* the cut hit the marker itself: a half marker is no marker */
                assert_true(is_old || was_empty);
            }
        } else {
            const bool is_old = st == MC_NVSTORE_OK && last != NULL && same(&got, last);
            if (!(is_old || st == MC_NVSTORE_EMPTY)) {
                fail_msg("restore cut at step %u of %u: status %s", s, total, mc_nvstore_status_name(st));
            }
        }
        ++cuts;
    }
    return cuts;
}

static void test_power_cut_at_every_step(void **state)
{
    (void)state;
    enum { N = 12 };
    mc_params_t sets[N + 1];
    for (int k = 0; k <= N; ++k) {
        make_set(&sets[k], 10 + k);
    }
    unsigned cuts = 0;
    /* saves from an empty store and after 1..N committed saves (both slots in every role) */
    for (int n = 0; n < N; ++n) {
        cuts += sweep(sets, n, &sets[n + 1], 0);
    }
    /* restores after 1..4 saves */
    for (int n = 1; n <= 4; ++n) {
        cuts += sweep(sets, n, NULL, 1);
    }
    print_message("power cuts tested: %u\n", cuts);
    assert_true(cuts > 1000u);
}

static void test_restore_then_save(void **state)
{
    (void)state;
    hal_host_nvm_init(&nvm);
    mc_params_t a, got;
    make_set(&a, 5);
    assert_int_equal(mc_nvstore_save(&nvm, &a, work, sizeof work), MC_NVSTORE_OK);
    assert_int_equal(mc_nvstore_restore_defaults(&nvm, work, sizeof work), MC_NVSTORE_OK);
    mc_params_default(&got);
    const mc_params_t before = got;
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, NULL), MC_NVSTORE_EMPTY);
    assert_memory_equal(&got, &before, sizeof got);   /* defaults untouched */
    assert_int_equal(mc_nvstore_save(&nvm, &a, work, sizeof work), MC_NVSTORE_OK);
    assert_int_equal(mc_nvstore_load(&nvm, &got, work, sizeof work, NULL), MC_NVSTORE_OK);
    assert_true(same(&a, &got));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty_then_round_trip),
        cmocka_unit_test(test_corrupt_newest_falls_back),
        cmocka_unit_test(test_restore_then_save),
        cmocka_unit_test(test_power_cut_at_every_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
