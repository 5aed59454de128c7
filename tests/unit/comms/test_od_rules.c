/* The object dictionary's checks one by one (co_od.c): every writable integer object at both
 * ends of its range and one step outside (signed and unsigned, each width), each length other
 * than the object's, every read-only object refusing a write, REAL32 infinities and NaNs, the
 * error history, the SYNC COB-ID's refused bits, the parameter objects (exactness of an INTEGER32,
 * a REAL32's range, a NaN, a motor entry updating the 402 rated values), the index ranges of
 * the parameters and telemetry channels, the scope's objects without a scope and its control. */
#include "rig.h"
#include "mc/telem_channels.h"

static uint32_t od_write_u(uint16_t index, uint8_t sub, uint32_t w, uint32_t n)
{
    const uint8_t b[4] = {(uint8_t)w, (uint8_t)(w >> 8), (uint8_t)(w >> 16), (uint8_t)(w >> 24)};
    return mc_co_od_write(&rig.co, index, sub, b, n);
}

static uint32_t od_read_u(uint16_t index, uint8_t sub, uint32_t *v)
{
    uint8_t b[MC_CO_SDO_BUF] = {0};
    uint32_t len = 0u;
    const uint32_t a = mc_co_od_read(&rig.co, index, sub, b, sizeof b, &len);
    *v = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
    return a;
}

static uint32_t width(uint8_t t)
{
    return t == MC_CO_U8 || t == MC_CO_I8 || t == MC_CO_BOOL ? 1u : t == MC_CO_U16 || t == MC_CO_I16 ? 2u : 4u;
}

static bool signed_type(uint8_t t)
{
    return t == MC_CO_I8 || t == MC_CO_I16 || t == MC_CO_I32;
}

/* Every writable integer object of the fixed part (the 402 objects, the heartbeat, the scope's
 * configuration): min and max are taken and read back with the type's width, min - 1 is
 * VALUE_LOW and max + 1 VALUE_HIGH where the type can carry them; every other length is
 * LENGTH_HIGH / LENGTH_LOW; every read-only object is READ_ONLY. */
static void test_every_fixed_object_range(void **state)
{
    (void)state;
    const uint32_t count = mc_co_od_count();
    uint32_t checked = 0u, ro = 0u;
    for (uint32_t k = 0u; k < count; ++k) {
        mc_co_entry_t e;
        assert_true(mc_co_od_at(k, &e));
        if (e.index >= 0x1400u && e.index < 0x1C00u) {
            continue;   /* the PDO parameters: their own tests (test_pdo_rules.c) */
        }
        if (e.kind == MC_CO_K_PARAM || e.kind == MC_CO_K_TELEM) {
            continue;
        }
        rig_init();
        rig.co.ds_on = false;
        if (e.access == MC_CO_RO || e.access == MC_CO_CONST) {
            if (od_write_u(e.index, e.sub, 0u, width(e.type)) != MC_SDO_ABORT_READ_ONLY) {
                fail_msg("0x%04X sub %u: read-only, written", e.index, e.sub);
            }
            ++ro;
            continue;
        }
        if (e.kind != MC_CO_K_FIELD || e.type == MC_CO_REAL32 || e.index == 0x6060u) {
            continue;   /* 0x6060: the modes this drive has (test_od.c) */
        }
        const uint32_t n = width(e.type);
        const bool sg = signed_type(e.type);
        const int64_t tmin = sg ? -((int64_t)1 << (8u * n - 1u)) : 0;
        const int64_t tmax = sg ? ((int64_t)1 << (8u * n - 1u)) - 1 : ((int64_t)1 << (8u * n)) - 1;
        const int64_t vals[4] = {e.min, e.max, e.min - 1, e.max + 1};
        for (int j = 0; j < 4; ++j) {
            if (vals[j] < tmin || vals[j] > tmax) {
                continue;
            }
            const uint32_t w = (uint32_t)vals[j];
            const uint32_t want = j < 2 ? 0u : (j == 2 ? MC_SDO_ABORT_VALUE_LOW : MC_SDO_ABORT_VALUE_HIGH);
            const uint32_t a = od_write_u(e.index, e.sub, w, n);
            if (a != want) {
                fail_msg("0x%04X sub %u = %lld: abort 0x%08X, want 0x%08X", e.index, e.sub, (long long)vals[j], a, want);
            }
            if (j < 2) {
                uint32_t r = 0u;
                assert_int_equal(od_read_u(e.index, e.sub, &r), 0u);
                const uint32_t mask = n == 4u ? 0xFFFFFFFFu : (1u << (8u * n)) - 1u;
                if (r != (w & mask)) {
                    fail_msg("0x%04X sub %u = %lld read back 0x%X", e.index, e.sub, (long long)vals[j], r);
                }
            }
        }
        for (uint32_t len = 0u; len <= 4u; ++len) {
            if (len == n) {
                continue;
            }
            const uint32_t want = len > n ? MC_SDO_ABORT_LENGTH_HIGH : MC_SDO_ABORT_LENGTH_LOW;
            if (od_write_u(e.index, e.sub, (uint32_t)e.min, len) != want) {
                fail_msg("0x%04X sub %u in %u bytes", e.index, e.sub, len);
            }
        }
        ++checked;
    }
    assert_true(checked >= 25u);
    assert_true(ro >= 30u);
}

/* A REAL32 object takes any finite value, not an infinity or a NaN (any payload, either sign). */
static void test_real32_not_finite(void **state)
{
    (void)state;
    rig_init();
    static const uint32_t bad[] = {0x7F800000u, 0xFF800000u, 0x7FC00000u, 0xFFC00000u, 0x7F800001u, 0xFFFFFFFFu};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        assert_int_equal(od_write_u(0x2301u, 2u, bad[k], 4u), MC_SDO_ABORT_VALUE);
    }
    static const uint32_t good[] = {0x7F7FFFFFu, 0xFF7FFFFFu, 0x00000001u, 0x80000000u, 0x42C80000u};
    for (size_t k = 0; k < sizeof good / sizeof good[0]; ++k) {
        assert_int_equal(od_write_u(0x2301u, 2u, good[k], 4u), 0u);
        uint32_t r;
        assert_int_equal(od_read_u(0x2301u, 2u, &r), 0u);
        assert_int_equal(r, good[k]);
    }
}

/* 0x1003: sub 0 the number of errors, subs up to it the entries newest first, the others 0;
 * writing sub 0 with 0 clears, anything else is refused. */
static void test_error_history(void **state)
{
    (void)state;
    rig_init();
    rig.co.err_count = 3u;
    for (uint32_t k = 0u; k < 8u; ++k) {
        rig.co.err_hist[k] = 0x1000u + k;
    }
    uint32_t v;
    assert_int_equal(od_read_u(0x1003u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, 3u);
    for (uint8_t s = 1u; s <= 8u; ++s) {
        assert_int_equal(od_read_u(0x1003u, s, &v), 0u);
        assert_int_equal(v, s <= 3u ? 0x1000u + s - 1u : 0u);
    }
    assert_int_equal(od_write_u(0x1003u, 0u, 1u, 1u), MC_SDO_ABORT_VALUE_HIGH);   /* its range is 0..0 */
    assert_int_equal(rig.co.err_count, 3u);
    assert_int_equal(od_write_u(0x1003u, 1u, 0u, 4u), MC_SDO_ABORT_READ_ONLY);
    assert_int_equal(od_write_u(0x1003u, 0u, 0u, 1u), 0u);
    assert_int_equal(rig.co.err_count, 0u);
    assert_int_equal(od_read_u(0x1003u, 1u, &v), 0u);
    assert_int_equal(v, 0u);
}

/* 0x1005: this device consumes the SYNC with an 11-bit id; bit 30 (producer), bit 29 (29-bit
 * frame) and bits 11..28 are refused; bit 31 is "don't care" for a consumer. */
static void test_sync_cob_id(void **state)
{
    (void)state;
    rig_init();
    for (uint32_t b = 11u; b <= 30u; ++b) {
        assert_int_equal(od_write_u(0x1005u, 0u, (1u << b) | 0x81u, 4u), MC_SDO_ABORT_VALUE);
        assert_int_equal(rig.co.cob_sync, 0x080u);
    }
    assert_int_equal(od_write_u(0x1005u, 0u, 0x7FFu, 4u), 0u);
    assert_int_equal(rig.co.cob_sync, 0x7FFu);
    assert_int_equal(od_write_u(0x1005u, 0u, 0x80000082u, 4u), 0u);
    assert_int_equal(rig.co.cob_sync, 0x082u);
    uint32_t v;
    assert_int_equal(od_read_u(0x1005u, 0u, &v), 0u);
    assert_int_equal(v, 0x082u);
}

/* Parameters as 0x2000 + id: an INTEGER32 must be a value the table's float holds exactly; a
 * REAL32 outside the table's range is VALUE_HIGH / VALUE_LOW at its edges, a NaN is VALUE, and
 * a refused value changes nothing; a motor entry updates the 402 rated values at the next step;
 * an INIT entry is read-only. */
static void test_parameter_objects(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    const uint16_t bw = (uint16_t)(0x2000u + MC_PARAM_control_current_bw_hz);   /* 10..5000 Hz */
    assert_int_equal(od_write_u(bw, 0u, mc_f32_bits(nextafterf(5000.0f, 1e9f)), 4u), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(od_write_u(bw, 0u, mc_f32_bits(nextafterf(10.0f, 0.0f)), 4u), MC_SDO_ABORT_VALUE_LOW);
    assert_int_equal(od_write_u(bw, 0u, 0x7FC00000u, 4u), MC_SDO_ABORT_VALUE);
    assert_int_equal(od_write_u(bw, 0u, mc_f32_bits(300.0f), 3u), MC_SDO_ABORT_LENGTH_LOW);
    uint32_t v;
    assert_int_equal(od_read_u(bw, 0u, &v), 0u);
    assert_true(mc_bits_f32(v) == 250.0f);
    assert_int_equal(od_write_u(bw, 0u, mc_f32_bits(300.0f), 4u), 0u);
    run_ms(1);   /* taken by the ISR at its next period */
    assert_int_equal(od_read_u(bw, 0u, &v), 0u);
    assert_true(mc_bits_f32(v) == 300.0f);
    /* an INTEGER32 the float cannot hold exactly (2^24 + 1), one it can */
    const uint16_t off = (uint16_t)(0x2000u + MC_PARAM_control_offset_cal_samples);   /* 1..65535 */
    assert_int_equal(od_write_u(off, 0u, 65536u, 4u), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(od_write_u(off, 0u, 0u, 4u), MC_SDO_ABORT_VALUE_LOW);
    assert_int_equal(od_write_u(off, 0u, 0xFFFFFFFFu, 4u), MC_SDO_ABORT_VALUE_LOW);   /* -1 */
    assert_int_equal(od_write_u(off, 0u, 16777217u, 4u), MC_SDO_ABORT_VALUE);
    assert_int_equal(od_write_u(off, 0u, 65535u, 4u), 0u);
    run_ms(1);
    assert_int_equal(od_read_u(off, 0u, &v), 0u);
    assert_int_equal(v, 65535u);
    assert_int_equal(od_write_u((uint16_t)(0x2000u + MC_PARAM_motor_pole_pairs), 0u, 4u, 4u), MC_SDO_ABORT_READ_ONLY);
    /* the rated current: 0x6075 follows motor.i_rated_a at the next step */
    assert_int_equal(od_read_u(0x6075u, 0u, &v), 0u);
    assert_int_equal(v, 13290u);
    assert_int_equal(od_write_u((uint16_t)(0x2000u + MC_PARAM_motor_i_rated_a), 0u, mc_f32_bits(12.0f), 4u), 0u);
    run_ms(2);
    assert_int_equal(od_read_u(0x6075u, 0u, &v), 0u);
    assert_int_equal(v, 12000u);
    assert_int_equal(od_write_u(bw, 0u, mc_f32_bits(260.0f), 4u), 0u);
}

/* The index ranges: parameters 0x2000 .. 0x2000 + count - 1 (sub 0 only), telemetry channels
 * 0x2201 .. 0x2200 + count (0x2200 is none), the scope 0x2300 .. 0x2308. */
static void test_index_ranges(void **state)
{
    (void)state;
    rig_init();
    mc_co_entry_t e;
    bool miss = true;
    assert_true(mc_co_od_lookup(0x2000u, 0u, &e, &miss));
    assert_int_equal(e.kind, MC_CO_K_PARAM);
    assert_int_equal(e.arg, 0u);
    assert_true(mc_co_od_lookup((uint16_t)(0x2000u + MC_PARAM_COUNT - 1u), 0u, &e, &miss));
    assert_int_equal(e.arg, MC_PARAM_COUNT - 1u);
    assert_false(mc_co_od_lookup(0x2000u, 1u, &e, &miss));
    assert_true(miss);
    assert_false(mc_co_od_lookup((uint16_t)(0x2000u + MC_PARAM_COUNT), 0u, &e, &miss));
    assert_false(miss);
    assert_false(mc_co_od_lookup(0x2200u, 0u, &e, &miss));
    assert_false(miss);
    assert_true(mc_co_od_lookup(0x2201u, 0u, &e, &miss));
    assert_int_equal(e.kind, MC_CO_K_TELEM);
    assert_int_equal(e.arg, 1u);
    assert_true(mc_co_od_lookup((uint16_t)(0x2200u + MC_TELEM_CHANNEL_COUNT), 0u, &e, NULL));
    assert_int_equal(e.arg, MC_TELEM_CHANNEL_COUNT);
    assert_false(mc_co_od_lookup(0x2201u, 1u, &e, &miss));
    assert_true(miss);
    assert_false(mc_co_od_lookup((uint16_t)(0x2201u + MC_TELEM_CHANNEL_COUNT), 0u, &e, &miss));
    assert_false(miss);
    /* a telemetry channel reads its value */
    rig.co.tm.vdc = 321.5f;
    uint32_t v;
    for (uint32_t ch = 1u; ch <= MC_TELEM_CHANNEL_COUNT; ++ch) {
        assert_int_equal(od_read_u((uint16_t)(0x2200u + ch), 0u, &v), 0u);
        const float want = mc_telem_channel(&rig.co.tm, ch);
        assert_true(mc_bits_f32(v) == want || (want != want && mc_bits_f32(v) != mc_bits_f32(v)));
        assert_int_equal(od_write_u((uint16_t)(0x2200u + ch), 0u, 0u, 4u), MC_SDO_ABORT_READ_ONLY);
    }
    /* the objects the enumeration gives are the ones lookup finds, each once */
    const uint32_t n = mc_co_od_count();
    for (uint32_t k = 0u; k < n; ++k) {
        mc_co_entry_t a;
        assert_true(mc_co_od_at(k, &a));
        for (uint32_t j = k + 1u; j < n && j < k + 40u; ++j) {
            mc_co_entry_t b;
            assert_true(mc_co_od_at(j, &b));
            if (a.index == b.index && a.sub == b.sub) {
                fail_msg("0x%04X sub %u enumerated at %u and %u", a.index, a.sub, k, j);
            }
        }
    }
    uint32_t params = 0u, telem = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        mc_co_entry_t a;
        assert_true(mc_co_od_at(k, &a));
        params += a.kind == MC_CO_K_PARAM;
        telem += a.kind == MC_CO_K_TELEM;
    }
    assert_int_equal(params, MC_PARAM_COUNT);
    assert_int_equal(telem, MC_TELEM_CHANNEL_COUNT);
}

/* A device without a scope has none of its objects (0x2300 .. 0x2308: NO_OBJECT for every sub,
 * read or write); the objects beside them answer. */
static void test_no_scope(void **state)
{
    (void)state;
    rig_init();
    const mc_co_cfg_t c = {.node_id = NODE, .step_s = 1e-3f};
    assert_true(mc_co_init(&rig.co, &c, &rig.can, &rig.d, &rig.nvm, NULL, MC_PSTORE_EMPTY));
    const uint32_t n = mc_co_od_count();
    uint32_t seen = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        mc_co_entry_t e;
        assert_true(mc_co_od_at(k, &e));
        if (e.index < 0x2300u || e.index > 0x2308u) {
            continue;
        }
        uint32_t v;
        if (od_read_u(e.index, e.sub, &v) != MC_SDO_ABORT_NO_OBJECT) {
            fail_msg("0x%04X sub %u read without a scope", e.index, e.sub);
        }
        if (od_write_u(e.index, e.sub, 1u, width(e.type)) != MC_SDO_ABORT_NO_OBJECT) {
            fail_msg("0x%04X sub %u written without a scope", e.index, e.sub);
        }
        ++seen;
    }
    assert_true(seen >= 17u);
    assert_int_equal(mc_co_od_domain_size(&rig.co, 0x2307u, 0u), 0u);
    uint32_t v;
    assert_int_equal(od_read_u(0x2FF0u, 0u, &v), 0u);
    assert_int_equal(v, mc_params_table_hash());
    assert_int_equal(od_read_u(0x2201u, 0u, &v), 0u);
}

/* 0x2302: 1 arms with 0x2300 / 0x2301, 2 forces the trigger (the next sample is the trigger),
 * anything else stops; it reads back what was written; arming while armed is STATE, arming an
 * impossible record VALUE. */
static void test_scope_control(void **state)
{
    (void)state;
    rig_init();
    uint32_t v;
    assert_int_equal(od_write_u(0x2302u, 0u, 1u, 1u), MC_SDO_ABORT_VALUE);   /* no channel */
    assert_int_equal(od_write_u(0x2300u, 1u, 1u, 1u), 0u);
    assert_int_equal(od_write_u(0x2301u, 1u, 1u, 1u), 0u);
    assert_int_equal(od_write_u(0x2301u, 2u, mc_f32_bits(1e9f), 4u), 0u);   /* a level never reached */
    assert_int_equal(od_write_u(0x2301u, 6u, 16u, 4u), 0u);
    assert_int_equal(od_write_u(0x2302u, 0u, 1u, 1u), 0u);
    assert_int_equal(od_read_u(0x2302u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, 1u);
    for (int k = 0; k < 5; ++k) {
        mc_scope_sample(&rig.scope, mc_drive_telemetry(&rig.d));
    }
    assert_int_equal(od_read_u(0x2303u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, (uint32_t)MC_SCOPE_ARMED);
    assert_int_equal(od_write_u(0x2302u, 0u, 1u, 1u), MC_SDO_ABORT_STATE);
    assert_int_equal(od_write_u(0x2302u, 0u, 2u, 1u), 0u);
    assert_int_equal(od_read_u(0x2302u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, 2u);
    mc_scope_sample(&rig.scope, mc_drive_telemetry(&rig.d));
    assert_int_equal(od_read_u(0x2303u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, (uint32_t)MC_SCOPE_TRIGGERED);
    for (int k = 0; k < 20; ++k) {
        mc_scope_sample(&rig.scope, mc_drive_telemetry(&rig.d));
    }
    assert_int_equal(od_read_u(0x2303u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, (uint32_t)MC_SCOPE_DONE);
    assert_int_equal(mc_co_od_domain_size(&rig.co, 0x2307u, 0u), 16u * 4u);
    assert_int_equal(mc_co_od_domain_size(&rig.co, 0x2307u, 1u), 0u);
    assert_int_equal(mc_co_od_domain_size(&rig.co, 0x2306u, 0u), 0u);
    /* stop */
    assert_int_equal(od_write_u(0x2302u, 0u, 1u, 1u), 0u);
    assert_int_equal(od_write_u(0x2302u, 0u, 0u, 1u), 0u);
    assert_int_equal(od_read_u(0x2303u, 0u, &v), 0u);
    assert_int_equal(v & 0xFFu, (uint32_t)MC_SCOPE_IDLE);
    assert_int_equal(od_write_u(0x2302u, 0u, 3u, 1u), MC_SDO_ABORT_VALUE_HIGH);
}

/* The constant hooks read their values (highest sub-indices, "on command" flags, the device
 * type); a buffer too small for the value is a general error, not a cut value; a DOMAIN is not
 * read in one piece. */
static void test_hook_values_and_buffer(void **state)
{
    (void)state;
    rig_init();
    static const struct {
        uint16_t index;
        uint8_t sub;
        uint32_t value, len;
    } c[] = {{0x1010u, 0u, 1u, 1u}, {0x1011u, 0u, 1u, 1u}, {0x1010u, 1u, 1u, 4u}, {0x1011u, 1u, 1u, 4u},
             {0x1018u, 0u, 4u, 1u}, {0x2300u, 0u, 8u, 1u}, {0x2301u, 0u, 6u, 1u}, {0x1000u, 0u, MC_CO_DEVICE_TYPE, 4u},
             {0x1003u, 0u, 0u, 1u}, {0x1005u, 0u, 0x80u, 4u}};
    for (size_t k = 0; k < sizeof c / sizeof c[0]; ++k) {
        uint8_t b[8];
        memset(b, 0xEE, sizeof b);
        uint32_t len = 0u;
        assert_int_equal(mc_co_od_read(&rig.co, c[k].index, c[k].sub, b, sizeof b, &len), 0u);
        assert_int_equal(len, c[k].len);
        uint32_t v = 0u;
        for (uint32_t j = 0u; j < len; ++j) {
            v |= (uint32_t)b[j] << (8u * j);
        }
        if (v != c[k].value) {
            fail_msg("0x%04X sub %u reads 0x%X, want 0x%X", c[k].index, c[k].sub, v, c[k].value);
        }
        assert_int_equal(b[len], 0xEEu);   /* nothing written past it */
        /* a buffer of exactly the value's size, one byte too small */
        uint8_t exact[4];
        uint32_t l1 = 0u;
        assert_int_equal(mc_co_od_read(&rig.co, c[k].index, c[k].sub, exact, c[k].len, &l1), 0u);
        assert_int_equal(l1, c[k].len);
        uint8_t small[4];
        uint32_t l2 = 77u;
        assert_int_equal(mc_co_od_read(&rig.co, c[k].index, c[k].sub, small, c[k].len - 1u, &l2), MC_SDO_ABORT_GENERAL);
        assert_int_equal(l2, 77u);
    }
    /* strings: their length exactly, one less is refused */
    uint8_t name[MC_CO_SDO_BUF];
    uint32_t len = 0u;
    assert_int_equal(mc_co_od_read(&rig.co, 0x1008u, 0u, name, sizeof name, &len), 0u);
    assert_int_equal(len, strlen("ipmsm-sensorless-drive"));
    assert_memory_equal(name, "ipmsm-sensorless-drive", len);
    uint32_t l2 = 0u;
    assert_int_equal(mc_co_od_read(&rig.co, 0x1008u, 0u, name, len, &l2), 0u);
    assert_int_equal(mc_co_od_read(&rig.co, 0x1008u, 0u, name, len - 1u, &l2), MC_SDO_ABORT_GENERAL);
    assert_int_equal(mc_co_od_read(&rig.co, 0x100Au, 0u, name, sizeof name, &len), 0u);
    assert_memory_equal(name, "0.2.0 (CiA 301, CiA 402)", len);
    /* a parameter and a telemetry channel into 3 bytes */
    assert_int_equal(mc_co_od_read(&rig.co, 0x2000u, 0u, name, 3u, &l2), MC_SDO_ABORT_GENERAL);
    assert_int_equal(mc_co_od_read(&rig.co, 0x2201u, 0u, name, 3u, &l2), MC_SDO_ABORT_GENERAL);
    /* the scope's record */
    assert_int_equal(mc_co_od_read(&rig.co, 0x2307u, 0u, name, sizeof name, &l2), MC_SDO_ABORT_GENERAL);
}

/* What the dictionary says of its entries (co-gen writes it into the EDS): the PDO parameter
 * objects are all enumerated (4 x (3 + 9 + 6 + 9)); their sub 0 is the highest sub-index,
 * constant for the communication parameters, 0..8 for a mapping; a parameter object carries its
 * table range as INTEGER32 (REAL32: the range is checked on write), INIT ones read-only. */
static void test_entry_descriptions(void **state)
{
    (void)state;
    const uint32_t n = mc_co_od_count();
    uint32_t pdo = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        mc_co_entry_t e;
        assert_true(mc_co_od_at(k, &e));
        pdo += e.index >= 0x1400u && e.index < 0x1C00u;
    }
    assert_int_equal(pdo, MC_CO_PDO_N * (3u + 9u + 6u + 9u));
    mc_co_entry_t e;
    assert_true(mc_co_od_lookup(0x1603u, 0u, &e, NULL));
    assert_int_equal(e.access, MC_CO_RW);
    assert_true(e.min == 0 && e.max == 8);
    assert_true(mc_co_od_lookup(0x1A00u, 8u, &e, NULL));
    assert_int_equal(e.type, MC_CO_U32);
    assert_true(mc_co_od_lookup(0x1402u, 0u, &e, NULL));
    assert_int_equal(e.access, MC_CO_CONST);
    assert_true(e.min == 2 && e.max == 2);
    assert_true(mc_co_od_lookup(0x1801u, 0u, &e, NULL));
    assert_true(e.min == 6 && e.max == 6);
    assert_true(mc_co_od_lookup(0x1801u, 2u, &e, NULL));
    assert_true(e.type == MC_CO_U8 && e.max == 255);
    assert_true(mc_co_od_lookup(0x1801u, 6u, &e, NULL));
    assert_true(e.type == MC_CO_U8 && e.max == 240);
    assert_true(mc_co_od_lookup(0x1801u, 3u, &e, NULL));
    assert_true(e.type == MC_CO_U16 && e.max == 65535);
    assert_string_equal(e.unit, "100 us");
    assert_true(mc_co_od_lookup(0x1801u, 5u, &e, NULL));
    assert_string_equal(e.unit, "ms");
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const mc_param_info_t *p = &mc_param_table[id];
        assert_true(mc_co_od_lookup((uint16_t)(0x2000 + id), 0u, &e, NULL));
        assert_int_equal(e.type, p->type == MC_PT_F32 ? MC_CO_REAL32 : MC_CO_I32);
        assert_int_equal(e.access, p->access == MC_PA_INIT ? MC_CO_RO : MC_CO_RW);
        if (p->type == MC_PT_F32) {
            assert_true(e.min == 0 && e.max == 0);
        } else if (e.min != (int64_t)p->min || e.max != (int64_t)p->max) {
            fail_msg("%s: 0x%04X has %lld..%lld", p->name, 0x2000 + id, (long long)e.min, (long long)e.max);
        }
        assert_string_equal(e.oname, p->name);
    }
}

/* A parameter write the drive refuses because a value derived from it leaves its own range: the
 * abort says which way (a rated current of 10 mA puts the dead-time band below its 1 mA minimum;
 * 10 kA puts the trip level above its 10 kA maximum); nothing changes. */
static void test_parameter_derived_out_of_range(void **state)
{
    (void)state;
    rig_init();
    const uint16_t ir = (uint16_t)(0x2000u + MC_PARAM_motor_i_rated_a);
    assert_int_equal(od_write_u(ir, 0u, mc_f32_bits(0.01f), 4u), MC_SDO_ABORT_VALUE_LOW);
    assert_int_equal(od_write_u(ir, 0u, mc_f32_bits(10000.0f), 4u), MC_SDO_ABORT_VALUE_HIGH);
    run_ms(1);
    uint32_t v;
    assert_int_equal(od_read_u(ir, 0u, &v), 0u);
    assert_true(mc_bits_f32(v) == 13.29f);
}

/* Store and restore (0x1010 / 0x1011) while the drive is in FAULT: its outputs are off. */
static void test_store_in_fault(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drive_inputs(300.0f);
    const mc_drive_cmd_t on = {.enable = true, .mode = MC_MODE_CURRENT};
    mc_drive_command(&rig.d, &on);
    run_ms(20);
    drive_inputs(rig.d.cfg->p.control_vdc_max_v + 20.0f);
    run_ms(2);
    assert_int_equal(mc_drive_state(&rig.d), MC_STATE_FAULT);
    assert_int_equal(od_write_u(0x1010u, 1u, MC_CO_SAVE_SIGNATURE, 4u), 0u);
    assert_int_equal(rig.co.store_status, (uint32_t)MC_PSTORE_OK);
    assert_int_equal(od_write_u(0x1011u, 1u, MC_CO_LOAD_SIGNATURE, 4u), 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_fixed_object_range),
        cmocka_unit_test(test_real32_not_finite),
        cmocka_unit_test(test_error_history),
        cmocka_unit_test(test_sync_cob_id),
        cmocka_unit_test(test_parameter_objects),
        cmocka_unit_test(test_index_ranges),
        cmocka_unit_test(test_no_scope),
        cmocka_unit_test(test_scope_control),
        cmocka_unit_test(test_hook_values_and_buffer),
        cmocka_unit_test(test_entry_descriptions),
        cmocka_unit_test(test_parameter_derived_out_of_range),
        cmocka_unit_test(test_store_in_fault),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
