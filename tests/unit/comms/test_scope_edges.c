/* The scope (mc/scope.h) at its edges: the largest channel and trigger ids, the last edge kind,
 * a record exactly the buffer's size, the longest pre-trigger history, a free-running record
 * with a NaN level, a level exactly reached, arming while triggered, the record's size and
 * trigger index only once done, reads across the ring's wrap, every error's name. Synthetic
 * telemetry: vdc = the call number. */
#include <math.h>
#include <string.h>

#include "../mc_test.h"
#include "mc/bits.h"
#include "mc/scope.h"
#include "mc/telem_channels.h"

#define CH_VDC 6u

static float buf[64];
static mc_scope_t s;
static mc_drive_telem_t tm;
static int calls;

static void setup(uint32_t cap)
{
    memset(&tm, 0, sizeof tm);
    memset(buf, 0, sizeof buf);
    calls = 0;
    mc_scope_init(&s, buf, cap, 1e-4f);
}

static void feed(int n)
{
    for (int k = 0; k < n; ++k) {
        tm.vdc = (float)calls;
        mc_scope_sample(&s, &tm);
        calls++;
    }
}

static float value(uint32_t sample, uint32_t ch)
{
    uint8_t b[4];
    assert_int_equal(mc_scope_read(&s, 4u * (sample * mc_scope_channels(&s) + ch), b, 4u), 4u);
    return mc_bits_f32((uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24));
}

static void test_arm_limits(void **state)
{
    (void)state;
    setup(64u);
    mc_scope_cfg_t c = {.ch = {0, MC_TELEM_CHANNEL_COUNT, 0, CH_VDC}, .trig_ch = MC_TELEM_CHANNEL_COUNT,
                        .edge = MC_SCOPE_EDGE_EITHER, .decimation = 1u, .pre = 31u, .length = 32u};
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);   /* 2 x 32 = the whole buffer */
    assert_int_equal(mc_scope_channels(&s), 2u);
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_BUSY);
    mc_scope_stop(&s);
    c.length = 33u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_LENGTH);
    c.length = 32u;
    c.pre = 32u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_PRE);
    c.pre = 0u;
    c.ch[7] = MC_TELEM_CHANNEL_COUNT + 1u;   /* the last slot is checked too */
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_CHANNEL);
    c.ch[7] = 0u;
    c.trig_ch = MC_TELEM_CHANNEL_COUNT + 1u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_TRIGGER);
    /* without a trigger channel the level is not looked at */
    c.trig_ch = 0u;
    c.trig_level = NAN;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    mc_scope_stop(&s);
    c.trig_ch = CH_VDC;
    c.trig_level = -INFINITY;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_LEVEL);
    c.trig_level = 3.4e38f;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_ARMED);
    /* a failed arm leaves the state alone */
    mc_scope_stop(&s);
    c.decimation = 0u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_DECIMATION);
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_IDLE);
    assert_true(mc_scope_sample_period(&s) == 1e-4f);
    c.decimation = 3u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    assert_true(mc_scope_sample_period(&s) == 1e-4f * 3.0f);
    /* no buffer */
    mc_scope_t none;
    mc_scope_init(&none, NULL, 64u, 1e-4f);
    assert_int_equal(mc_scope_capacity(&none), 0u);
    assert_int_equal(mc_scope_state(&none), MC_SCOPE_IDLE);
}

/* A level exactly reached is a crossing (rising: from below to >= level; falling: from above
 * to <= level); the longest history (pre = length - 1) puts the trigger on the last sample; the
 * record's size, sample count and trigger index are 0 until it is done, also while triggered,
 * where arming again is refused. */
static void test_level_reached_and_longest_history(void **state)
{
    (void)state;
    setup(64u);
    mc_scope_cfg_t c = {.ch = {CH_VDC}, .trig_ch = CH_VDC, .trig_level = 40.0f, .edge = MC_SCOPE_EDGE_RISING,
                        .decimation = 1u, .pre = 15u, .length = 16u};
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    feed(40);   /* 0..39 below the level */
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_ARMED);
    feed(1);    /* 40: reached */
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_int_equal(mc_scope_trigger_index(&s), 15u);
    assert_int_equal(mc_scope_samples(&s), 16u);
    assert_int_equal(mc_scope_data_size(&s), 64u);
    for (uint32_t k = 0u; k < 16u; ++k) {
        assert_true(value(k, 0) == (float)(25u + k));   /* across the ring's wrap */
    }
    /* falling, exactly reached, and the counters while triggered */
    setup(64u);
    c.edge = MC_SCOPE_EDGE_FALLING;
    c.trig_level = -5.0f;
    c.pre = 2u;
    c.length = 10u;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    for (int k = 0; k < 6; ++k) {
        tm.vdc = -(float)k;   /* 0, -1 .. -5: reaches -5 at the sixth */
        mc_scope_sample(&s, &tm);
    }
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_TRIGGERED);
    assert_int_equal(mc_scope_samples(&s), 0u);
    assert_int_equal(mc_scope_trigger_index(&s), 0u);
    assert_int_equal(mc_scope_data_size(&s), 0u);
    uint8_t b[4];
    assert_int_equal(mc_scope_read(&s, 0u, b, 4u), 0u);
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_ERR_BUSY);
    for (int k = 0; k < 7; ++k) {
        tm.vdc = 100.0f + (float)k;
        mc_scope_sample(&s, &tm);
    }
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_DONE);
    assert_int_equal(mc_scope_trigger_index(&s), 2u);
    assert_true(value(1, 0) == -4.0f);
    assert_true(value(2, 0) == -5.0f);
    assert_true(value(3, 0) == 100.0f);
    assert_true(value(9, 0) == 106.0f);
    /* a level touched from below on a falling edge is no crossing */
    setup(64u);
    c.trig_level = 3.0f;
    assert_int_equal(mc_scope_arm(&s, &c), MC_SCOPE_OK);
    feed(10);   /* 0..9 rising through 3 */
    assert_int_equal(mc_scope_state(&s), MC_SCOPE_ARMED);
}

static void test_err_names(void **state)
{
    (void)state;
    static const char *const want[] = {"ok",
                                       "a channel id beyond the telemetry table",
                                       "no channel chosen",
                                       "the trigger channel beyond the telemetry table",
                                       "edge not 0 (rising), 1 (falling) or 2 (either)",
                                       "trigger level not finite",
                                       "decimation 0",
                                       "length x channels beyond the buffer",
                                       "pre-trigger not below the length",
                                       "armed: stop first"};
    for (int e = 0; e <= (int)MC_SCOPE_ERR_BUSY; ++e) {
        assert_string_equal(mc_scope_err_name((mc_scope_err_t)e), want[e]);
    }
    assert_string_equal(mc_scope_err_name((mc_scope_err_t)((int)MC_SCOPE_ERR_BUSY + 1)), "?");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arm_limits),
        cmocka_unit_test(test_level_reached_and_longest_history),
        cmocka_unit_test(test_err_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
