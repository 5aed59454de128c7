/* The scope (mc/scope.h): validation per field, records at once and around rising / falling /
 * either edges with their pre-trigger history, an early trigger, decimation, force, stop, re-arm,
 * the busy refusal, reads at any offset, capacity, NaN. Synthetic telemetry: vdc = k (the call
 * number), i_d = -k, omega = a sine. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>
#include "mc/bits.h"
#include "mc/scope.h"
#include "mc/telem_channels.h"

#define CH_VDC 6u
#define CH_OMEGA 8u
#define CH_ID 9u

static float buf[600];
static mc_scope_t s;
static mc_drive_telem_t tm;
static int calls;

static void feed(int n, float (*omega)(int))
{
    for (int k = 0; k < n; ++k) {
        tm.vdc = (float)calls;
        tm.i_dq.d = -(float)calls;
        tm.omega = omega != NULL ? omega(calls) : 0.0f;
        mc_scope_sample(&s, &tm);
        calls++;
    }
}

static float wave(int k)
{
    return sinf(2.0f * 3.14159265f * (float)k / 50.0f);   /* 50 calls a period, up through 0 at k = 0, 50 .. */
}

static float value(uint32_t sample, uint32_t ch)
{
    uint8_t b[4];
    assert_int_equal(mc_scope_read(&s, 4u * (sample * mc_scope_channels(&s) + ch), b, 4u), 4u);
    return mc_bits_f32((uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24));
}

static void setup_scope(void)
{
    memset(&tm, 0, sizeof tm);
    calls = 0;
    mc_scope_init(&s, buf, 600u, 1e-4f);
}

static mc_scope_cfg_t cfg2(void)
{
    return (mc_scope_cfg_t){.ch = {CH_VDC, 0, CH_ID}, .decimation = 1u, .length = 20u};
}

static void test_validation(void **state)
{
    (void)state;
    setup_scope();
    mc_scope_cfg_t c = cfg2();
    c.ch[1] = MC_TELEM_CHANNEL_COUNT + 1u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_CHANNEL);
    c = (mc_scope_cfg_t){.decimation = 1u};
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_NO_CHANNEL);
    c = cfg2();
    c.trig_ch = 200u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_TRIGGER);
    c = cfg2();
    c.trig_ch = CH_VDC;
    c.edge = 3u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_EDGE);
    c.edge = 0u;
    c.trig_level = NAN;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_LEVEL);
    c.trig_level = INFINITY;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_LEVEL);
    c = cfg2();
    c.decimation = 0u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_DECIMATION);
    c = cfg2();
    c.length = 301u;   /* 2 x 301 > 600 */
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_LENGTH);
    c.length = UINT32_MAX;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_LENGTH);
    c = cfg2();
    c.pre = 20u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_PRE);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_IDLE);
    mc_scope_t none;
    mc_scope_init(&none, NULL, 100u, 1e-4f);   /* no buffer: nothing fits */
    c = cfg2();
    assert_int_equal(mc_scope_arm(&none, &c), MC_SCOPE_ERR_LENGTH);
    assert_string_equal(mc_scope_err_name(MC_SCOPE_ERR_PRE), "pre-trigger not below the length");
}

static void test_immediate_record(void **state)
{
    (void)state;
    setup_scope();
    feed(5, NULL);   /* idle: ignored */
    mc_scope_cfg_t c = cfg2();
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    assert_int_equal(mc_scope_data_size(&s), 0u);
    feed(19, NULL);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_TRIGGERED);
    feed(1, NULL);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_int_equal(mc_scope_samples(&s), 20u);
    assert_int_equal(mc_scope_channels(&s), 2u);
    assert_int_equal(mc_scope_trigger_index(&s), 0u);
    assert_int_equal(mc_scope_data_size(&s), 160u);
    for (uint32_t k = 0; k < 20u; ++k) {
        assert_true(value(k, 0) == (float)(5 + k));    /* vdc: the call number */
        assert_true(value(k, 1) == -(float)(5 + k));   /* i_d, packed after the gap */
    }
    feed(10, NULL);   /* done: the record stays */
    assert_true(value(0, 0) == 5.0f);
    /* byte by byte equals one read; past the end: nothing */
    uint8_t all[160], one[160];
    assert_int_equal(mc_scope_read(&s, 0u, all, 1000u), 160u);
    for (uint32_t k = 0; k < 160u; ++k) {
        assert_int_equal(mc_scope_read(&s, k, &one[k], 1u), 1u);
    }
    assert_memory_equal(all, one, 160u);
    assert_int_equal(mc_scope_read(&s, 160u, one, 4u), 0u);
    assert_int_equal(mc_scope_read(&s, 157u, one, 7u), 3u);
    /* little-endian float32: 5.0f = 0x40A00000 */
    assert_int_equal(all[0], 0x00u);
    assert_int_equal(all[3], 0x40u);
    assert_int_equal(all[2], 0xA0u);
}

static void test_edges_and_pre(void **state)
{
    (void)state;
    const uint8_t edges[3] = {MC_SCOPE_EDGE_RISING, MC_SCOPE_EDGE_FALLING, MC_SCOPE_EDGE_EITHER};
    for (int e = 0; e < 3; ++e) {
        setup_scope();
        mc_scope_cfg_t c = {.ch = {CH_OMEGA, CH_VDC}, .trig_ch = CH_OMEGA, .trig_level = 0.5f, .edge = edges[e],
                            .decimation = 1u, .pre = 10u, .length = 40u};
        feed(10, wave);   /* armed past the first rising crossing (call 5): 0.95 and falling */
        assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
        feed(200, wave);
        assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
        assert_int_equal(mc_scope_trigger_index(&s), 10u);
        const float before = value(9, 0), at = value(10, 0);
        if (edges[e] == MC_SCOPE_EDGE_RISING) {
            assert_true(before < 0.5f && at >= 0.5f);
            assert_true(value(10, 1) == 55.0f);   /* the next rising crossing: sin(2 pi 55/50) = 0.59 */
        } else {
            assert_true(before > 0.5f && at <= 0.5f);
            assert_true(value(10, 1) == 21.0f);   /* falling: sin(2 pi 21/50) = 0.48 */
        }
        /* contiguous in time: vdc counts up by one */
        for (uint32_t k = 1; k < 40u; ++k) {
            assert_true(value(k, 1) == value(k - 1u, 1) + 1.0f);
        }
    }
}

static void test_early_trigger(void **state)
{
    (void)state;
    setup_scope();
    /* rising through 0.5 at call 5, only 2 samples of history after the arm at call 3 */
    mc_scope_cfg_t c = {.ch = {CH_VDC}, .trig_ch = CH_OMEGA, .trig_level = 0.5f, .edge = MC_SCOPE_EDGE_RISING,
                        .decimation = 1u, .pre = 10u, .length = 30u};
    feed(3, wave);
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    feed(100, wave);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_int_equal(mc_scope_samples(&s), 30u);
    assert_int_equal(mc_scope_trigger_index(&s), 2u);
    assert_true(value(0, 0) == 3.0f);
    assert_true(value(2, 0) == 5.0f);
    assert_true(value(29, 0) == 32.0f);
}

static void test_decimation_force_stop(void **state)
{
    (void)state;
    setup_scope();
    mc_scope_cfg_t c = {.ch = {CH_VDC}, .trig_ch = CH_VDC, .trig_level = 1e6f, .decimation = 4u, .pre = 5u,
                        .length = 10u};
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    assert_true(mc_scope_sample_period(&s) == 4e-4f);
    feed(100, NULL);   /* never reaches the level */
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_ARMED);
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_BUSY);
    mc_scope_force(&s);
    feed(1, NULL);     /* call 100 triggers and is recorded */
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_TRIGGERED);
    feed(40, NULL);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_int_equal(mc_scope_trigger_index(&s), 5u);
    for (uint32_t k = 0; k < 10u; ++k) {
        assert_true(value(k, 0) == 80.0f + 4.0f * (float)k);   /* every 4th, the trigger at 100 */
    }
    /* re-arm after DONE, then stop: idle, nothing to read */
    c.decimation = 1u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    feed(3, NULL);
    mc_scope_stop(&s);
    feed(3, NULL);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_IDLE);
    assert_int_equal(mc_scope_data_size(&s), 0u);
    uint8_t b[4];
    assert_int_equal(mc_scope_read(&s, 0u, b, 4u), 0u);
}

static float nan_then_up(int k)
{
    return k < 20 ? NAN : (float)(k - 20);
}

static void test_capacity_and_nan(void **state)
{
    (void)state;
    setup_scope();
    mc_scope_cfg_t c = {.ch = {CH_VDC, CH_ID, CH_OMEGA, 1, 2, 3, 4, 5}, .decimation = 1u};   /* length 0 */
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    feed(100, NULL);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_int_equal(mc_scope_samples(&s), 75u);   /* 600 / 8 */
    assert_int_equal(mc_scope_capacity(&s), 600u);
    /* a NaN never triggers (NaN -> 3 is no crossing of 0.5); it is stored */
    setup_scope();
    c = (mc_scope_cfg_t){.ch = {CH_OMEGA}, .trig_ch = CH_OMEGA, .trig_level = 0.5f, .edge = MC_SCOPE_EDGE_EITHER,
                         .decimation = 1u, .pre = 5u, .length = 10u};
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    feed(60, nan_then_up);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_true(isnan(value(0, 0)));            /* history: NaN */
    assert_true(value(5, 0) == 1.0f);           /* 0 -> 1 crosses 0.5 at call 21 */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validation),
        cmocka_unit_test(test_immediate_record),
        cmocka_unit_test(test_edges_and_pre),
        cmocka_unit_test(test_early_trigger),
        cmocka_unit_test(test_decimation_force_stop),
        cmocka_unit_test(test_capacity_and_nan),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
