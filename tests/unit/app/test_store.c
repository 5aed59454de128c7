/* Stored configuration records (mc/store.h) and the monitor block's packing (mc/monitor.h):
 * round trips bit for bit, and every corruption refused with its reason, nothing applied. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <string.h>
#include "mc/monitor.h"
#include "mc/bits.h"
#include "mc/store.h"

static uint8_t buf[MC_CONFIG_AREA_SIZE];

static void test_crc32_check_value(void **state)
{
    (void)state;
    /* the CRC-32 (IEEE) check value of "123456789" */
    assert_int_equal(mc_crc32((const uint8_t *)"123456789", 9u), 0xCBF43926u);
}

static void test_params_round_trip(void **state)
{
    (void)state;
    mc_params_t p, q;
    mc_params_default(&p);
    const int ts = mc_param_find("control.ts_s");
    const int lines = mc_param_find("hw.encoder_lines");
    const int cc = mc_param_find("control.current_bw_hz");
    assert_true(ts >= 0 && lines >= 0);
    assert_true(mc_param_set(&p, ts, 5e-5f, NULL));
    assert_true(mc_param_set(&p, lines, 1024.0f, NULL));
    if (cc >= 0) {
        mc_param_set_auto(&p, cc, true);
    }
    const size_t n = mc_store_params_encode(&p, buf, MC_CONFIG_MODEL_OFFSET);
    assert_true(n > 0u && n <= MC_STORE_PARAMS_MAX);
    assert_int_equal(mc_store_params_decode(buf, n, &q, NULL), MC_STORE_OK);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        assert_int_equal(mc_param_is_auto(&p, id), mc_param_is_auto(&q, id));
        if (!mc_param_is_auto(&p, id)) {
            const float a = mc_param_get(&p, id), b = mc_param_get(&q, id);
            assert_memory_equal(&a, &b, sizeof a);
        }
    }
    assert_true(fabsf(mc_param_get(&q, ts) - 5e-5f) == 0.0f);
    assert_int_equal((int)mc_param_get(&q, lines), 1024);
    /* too small a buffer: nothing written */
    assert_int_equal(mc_store_params_encode(&p, buf, 16u), 0u);
}

static void test_params_corruption_refused(void **state)
{
    (void)state;
    mc_params_t p, q;
    mc_params_default(&p);
    const size_t n = mc_store_params_encode(&p, buf, MC_CONFIG_MODEL_OFFSET);
    mc_params_default(&q);
    const int ts = mc_param_find("control.ts_s");
    assert_true(mc_param_set(&q, ts, 2e-4f, NULL));
    const mc_params_t before = q;

    memset(buf + n, 0xFF, 8u);
    uint8_t save = buf[20];
    buf[20] ^= 0x01u;   /* a value bit */
    assert_int_equal(mc_store_params_decode(buf, n, &q, NULL), MC_STORE_BAD_CRC);
    buf[20] = save;
    buf[4] = 7u;        /* version */
    assert_int_equal(mc_store_params_decode(buf, n, &q, NULL), MC_STORE_BAD_VERSION);
    buf[4] = 1u;        /* version 1 (positional): only the NVM store reads it, by its frozen table */
    assert_int_equal(mc_store_params_decode(buf, n, &q, NULL), MC_STORE_BAD_VERSION);
    buf[4] = (uint8_t)MC_STORE_PARAMS_VERSION;
    buf[12] = 0xFFu;    /* a count beyond the record */
    assert_int_equal(mc_store_params_decode(buf, n, &q, NULL), MC_STORE_BAD_SIZE);
    buf[12] = (uint8_t)MC_PARAM_COUNT;
    assert_int_equal(mc_store_params_decode(buf, n - 4u, &q, NULL), MC_STORE_BAD_SIZE);
    memset(buf, 0xFF, 16u);
    assert_int_equal(mc_store_params_decode(buf, n, &q, NULL), MC_STORE_EMPTY);
    assert_memory_equal(&q, &before, sizeof q);   /* nothing applied */
}

static void put_word(size_t at, uint32_t w)
{
    for (int k = 0; k < 4; ++k) {
        buf[at + (size_t)k] = (uint8_t)(w >> (8 * k));
    }
}

/* Seal a hand-made record of n entries (the words after the header are the caller's). */
static size_t seal(uint32_t hash, uint32_t n)
{
    const uint32_t head[4] = {MC_STORE_MAGIC_PARAMS, MC_STORE_PARAMS_VERSION, hash, n};
    for (int k = 0; k < 4; ++k) {
        put_word(4u * (size_t)k, head[k]);
    }
    const size_t len = 4u * (4u + 2u * (size_t)n);
    put_word(len, mc_crc32(buf, len));
    return len + 4u;
}

/* A record read by name and type: the values in another order, a name this table lacks, a value
 * out of range, one of another type, and parameters not in it: kept, skipped, default
 * (reported), default (reported), default. The table hash is another table's. */
static void test_params_by_name(void **state)
{
    (void)state;
    const int ts = mc_param_find("control.ts_s");
    const int lines = mc_param_find("hw.encoder_lines");
    const int cc = mc_param_find("control.current_bw_hz");
    const int dec = mc_param_find("control.decouple");
    const int act = mc_param_find("protection.lock_action");
    const int k1 = mc_param_find("estimator.k1");
    const float v_ts = 2e-4f, v_lines = 4096.0f;
    size_t at = 16u;
    const uint32_t unknown = 0x12345670u;   /* no name of this table (checked below) */
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        assert_int_not_equal(mc_store_param_key(id) & MC_STORE_KEY_NAME, unknown);
    }
    const uint32_t words[] = {
        mc_store_param_key(lines), mc_f32_bits(v_lines),                       /* reordered: kept */
        mc_store_param_key(ts), mc_f32_bits(v_ts),                             /* kept */
        unknown | 0u, mc_f32_bits(3.0f),                                       /* removed: skipped */
        mc_store_param_key(k1), mc_f32_bits(2e9f),                              /* out of range */
        (mc_store_param_key(dec) & ~MC_STORE_KEY_TYPE) | MC_PT_F32, mc_f32_bits(0.0f), /* type */
        mc_store_param_key(cc) | MC_STORE_KEY_AUTO, mc_f32_bits(123.0f),       /* derived: kept */
        mc_store_param_key(act), mc_f32_bits(1.0f),                            /* ENUM: kept */
    };
    for (size_t k = 0; k < sizeof words / sizeof words[0]; ++k) {
        put_word(at, words[k]);
        at += 4u;
    }
    const size_t n = seal(0x01020304u, (uint32_t)(sizeof words / sizeof words[0] / 2u));
    mc_params_t q, d;
    mc_params_default(&d);
    mc_param_set(&d, cc, 99.0f, NULL);   /* the derived mark must come back on it */
    q = d;
    mc_store_report_t rep;
    assert_int_equal(mc_store_params_decode(buf, n, &q, &rep), MC_STORE_OK);
    assert_true(rep.other_table);
    assert_int_equal(rep.kept, 4);
    assert_int_equal(rep.unknown, 1);
    assert_int_equal(rep.dropped, 2);
    assert_int_equal(rep.first, k1);
    assert_int_equal(rep.reason, MC_STORE_DROP_RANGE);
    assert_true(mc_param_get(&q, ts) == v_ts);
    assert_true(mc_param_get(&q, lines) == v_lines);
    assert_true(mc_param_is_auto(&q, cc));
    assert_true(mc_param_get(&q, act) == 1.0f);
    mc_params_default(&d);
    assert_true(mc_param_get(&q, k1) == mc_param_get(&d, k1));     /* defaults */
    assert_true(mc_param_get(&q, dec) == mc_param_get(&d, dec));
    assert_int_equal(mc_param_is_auto(&q, k1), mc_param_is_auto(&d, k1));
    /* the type first: the dropped value of another type alone */
    at = 16u;
    put_word(at, (mc_store_param_key(dec) & ~MC_STORE_KEY_TYPE) | MC_PT_ENUM);
    put_word(at + 4u, mc_f32_bits(0.0f));
    assert_int_equal(mc_store_params_decode(buf, seal(mc_params_table_hash(), 1u), &q, &rep), MC_STORE_OK);
    assert_false(rep.other_table);
    assert_int_equal(rep.dropped, 1);
    assert_int_equal(rep.first, dec);
    assert_int_equal(rep.reason, MC_STORE_DROP_TYPE);
}

/* A key per name: no two of the table's names share the 28 bits a record keeps. */
static void test_param_keys_distinct(void **state)
{
    (void)state;
    for (int a = 0; a < (int)MC_PARAM_COUNT; ++a) {
        assert_int_equal(mc_store_param_key(a) & MC_STORE_KEY_TYPE, mc_param_table[a].type);
        assert_int_equal(mc_store_param_key(a) & MC_STORE_KEY_AUTO, 0u);
        for (int b = a + 1; b < (int)MC_PARAM_COUNT; ++b) {
            assert_int_not_equal(mc_store_param_key(a) & MC_STORE_KEY_NAME, mc_store_param_key(b) & MC_STORE_KEY_NAME);
        }
    }
    /* FNV-1a-32 of "motor.pole_pairs" is 0x7F49A10C (a tool computes the same), I32 = 1 */
    assert_int_equal(mc_store_param_key(mc_param_find("motor.pole_pairs")), 0x7F49A101u);
    assert_int_equal(mc_store_v1_key(MC_STORE_V1_COUNT), 0u);
    /* the frozen version 1 table is the table of its hash: while this build's table is still
     * that one, every position's key is the live one (the list was made from it) */
    if (mc_params_table_hash() == MC_STORE_V1_TABLE) {
        assert_int_equal(MC_PARAM_COUNT, MC_STORE_V1_COUNT);
        for (uint32_t k = 0; k < MC_STORE_V1_COUNT; ++k) {
            assert_int_equal(mc_store_v1_key(k), mc_store_param_key((int)k));
        }
    } else {
        print_message("table hash %08x: the frozen version 1 table is an older one\n", mc_params_table_hash());
    }
}

/* The parameter table of main at 5265cfe, the last that wrote version 1 records (positions only):
 * names and types in their order, from that commit's firmware/include/mc/params_table.h. */
static const struct { const char *name; mc_param_type_t type; } v1_table[] = {
    {"motor.pole_pairs", MC_PT_I32},
    {"motor.rs_ohm", MC_PT_F32},
    {"motor.ld_h", MC_PT_F32},
    {"motor.lq_h", MC_PT_F32},
    {"motor.psi_pm_wb", MC_PT_F32},
    {"motor.i_rated_a", MC_PT_F32},
    {"motor.torque_rated_nm", MC_PT_F32},
    {"motor.inertia_kgm2", MC_PT_F32},
    {"control.ts_s", MC_PT_F32},
    {"hw.vdc_nominal_v", MC_PT_F32},
    {"hw.adc_bits", MC_PT_I32},
    {"hw.i_span_a", MC_PT_F32},
    {"hw.vdc_span_v", MC_PT_F32},
    {"hw.adc_offset_tol", MC_PT_F32},
    {"hw.dead_time_s", MC_PT_F32},
    {"hw.encoder_lines", MC_PT_I32},
    {"hw.encoder_offset_rad", MC_PT_F32},
    {"control.i_trip_a", MC_PT_F32},
    {"control.vdc_min_v", MC_PT_F32},
    {"control.vdc_max_v", MC_PT_F32},
    {"control.angle_source", MC_PT_ENUM},
    {"control.offset_cal_samples", MC_PT_I32},
    {"control.i_max_a", MC_PT_F32},
    {"control.i_headroom", MC_PT_F32},
    {"control.current_bw_hz", MC_PT_F32},
    {"control.i_slew_a_per_s", MC_PT_F32},
    {"control.decouple", MC_PT_BOOL},
    {"control.u_margin", MC_PT_F32},
    {"control.mtpa", MC_PT_ENUM},
    {"control.speed_bw_hz", MC_PT_F32},
    {"control.speed_kp", MC_PT_F32},
    {"control.speed_ki", MC_PT_F32},
    {"control.speed_decimation", MC_PT_I32},
    {"control.torque_max_nm", MC_PT_F32},
    {"control.deadtime_comp", MC_PT_BOOL},
    {"control.dtc_i_band_a", MC_PT_F32},
    {"control.encoder_pll_bw_hz", MC_PT_F32},
    {"control.encoder_speed_fc_hz", MC_PT_F32},
    {"estimator.model", MC_PT_ENUM},
    {"estimator.iter_max", MC_PT_I32},
    {"estimator.step_tol", MC_PT_F32},
    {"estimator.k1", MC_PT_F32},
    {"estimator.k2", MC_PT_F32},
    {"estimator.speed_scale_rpm", MC_PT_F32},
    {"estimator.mid_sample", MC_PT_BOOL},
    {"estimator.reg_predicted", MC_PT_BOOL},
    {"injection.kind", MC_PT_ENUM},
    {"injection.f_hz", MC_PT_F32},
    {"injection.i_hf_a", MC_PT_F32},
    {"injection.v1_v", MC_PT_F32},
    {"injection.n1_rpm", MC_PT_F32},
    {"injection.notch_q", MC_PT_F32},
    {"estimator.pll_bw_hz", MC_PT_F32},
    {"estimator.pll_speed_fc_hz", MC_PT_F32},
    {"startup.init_pos", MC_PT_ENUM},
    {"startup.step1_method", MC_PT_ENUM},
    {"startup.step1_cost", MC_PT_ENUM},
    {"startup.step1_m", MC_PT_I32},
    {"startup.step1_dirs", MC_PT_I32},
    {"startup.i_rest_a", MC_PT_F32},
    {"startup.polarity", MC_PT_ENUM},
    {"startup.step2_n", MC_PT_I32},
    {"startup.v_pol_v", MC_PT_F32},
    {"startup.dvi_n", MC_PT_I32},
    {"startup.step3_speed_tol_rpm", MC_PT_F32},
    {"startup.step3_hold_s", MC_PT_F32},
    {"startup.timeout_step12_s", MC_PT_F32},
    {"startup.timeout_step3_s", MC_PT_F32},
    {"protection.overspeed_rpm", MC_PT_F32},
    {"protection.i_sum_tol_a", MC_PT_F32},
    {"protection.i_sum_time_s", MC_PT_F32},
    {"protection.tracking_err_a", MC_PT_F32},
    {"protection.tracking_time_s", MC_PT_F32},
    {"protection.residual_v", MC_PT_F32},
    {"protection.residual_time_s", MC_PT_F32},
    {"protection.lock_speed_tol", MC_PT_F32},
    {"protection.lock_speed_floor_rpm", MC_PT_F32},
    {"protection.lock_time_s", MC_PT_F32},
    {"protection.stall_speed_rpm", MC_PT_F32},
    {"protection.stall_time_s", MC_PT_F32},
    {"startup.catch", MC_PT_ENUM},
    {"startup.catch_i_a", MC_PT_F32},
    {"startup.catch_min_rpm", MC_PT_F32},
    {"protection.lock_action", MC_PT_ENUM},
    {"protection.retries", MC_PT_I32},
    {"protection.retry_reset_s", MC_PT_F32},
    {"protection.overspeed_action", MC_PT_ENUM},
    {"protection.reaction_timeout_s", MC_PT_F32},
    {"hw.device_drop_v", MC_PT_F32},
    {"protection.polarity_check", MC_PT_ENUM},
    {"protection.polarity_bias_a", MC_PT_F32},
    {"protection.lock_jump_deg", MC_PT_F32},
    {"protection.lock_jump_time_s", MC_PT_F32},
    {"protection.accel_time_s", MC_PT_F32},
    {"control.u_loop", MC_PT_F32},
};

/* The frozen keys are that table's, position by position: FNV-1a-32 of the name (the key rule,
 * written out here independently), its low nibble dropped, the type below. A swap of two keys
 * would hand a version 1 record's values to each other's parameters. */
static void test_v1_keys_are_the_5265cfe_table(void **state)
{
    (void)state;
    assert_int_equal(sizeof v1_table / sizeof v1_table[0], MC_STORE_V1_COUNT);
    for (uint32_t k = 0; k < MC_STORE_V1_COUNT; ++k) {
        uint32_t h = 2166136261u;
        for (const char *c = v1_table[k].name; *c != '\0'; ++c) {
            h = (h ^ (uint8_t)*c) * 16777619u;
        }
        assert_int_equal(mc_store_v1_key(k), (h & MC_STORE_KEY_NAME) | (uint32_t)v1_table[k].type);
    }
}

/* The frozen keys of the version 1 table (main at 5265cfe): each is the key of a parameter of
 * today's table (name hash and type), so a version 1 record's value finds its parameter by name.
 * A key wrong in one bit would drop that value silently at the first update (the stored value
 * replaced by the default). Parameters removed or retyped since would be listed here. */
static void test_v1_keys_name_todays_parameters(void **state)
{
    (void)state;
    for (uint32_t k = 0; k < MC_STORE_V1_COUNT; ++k) {
        const uint32_t key = mc_store_v1_key(k);
        int found = -1;
        for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
            if (mc_store_param_key(id) == key) {
                found = id;
            }
        }
        if (found < 0) {
            print_message("version 1 position %u: key %08x names no parameter of today's table\n", k, key);
        }
        assert_true(found >= 0);
    }
}

static void test_model_round_trip_with_map(void **state)
{
    (void)state;
    static mc_flux_map_t map, out;
    memset(&map, 0, sizeof map);
    map.n_d = 5;
    map.n_q = 7;
    map.id0 = -20.0f;
    map.did = 5.0f;
    map.iq0 = -15.0f;
    map.diq = 5.0f;
    for (int k = 0; k < 35; ++k) {
        map.psi_d[k] = 0.3f + 0.001f * (float)k;
        map.psi_q[k] = -0.1f + 0.002f * (float)k;
    }
    mc_est_model_t m = {0.4f, 0.0105f, 0.0129f, NAN, &map}, r;
    const size_t n = mc_store_model_encode(&m, buf, sizeof buf);
    assert_int_equal(n, 4u * (14u + 70u));
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_OK);
    assert_ptr_equal(r.map, &out);
    assert_true(r.rs == 0.4f && r.ld == 0.0105f && r.lq == 0.0129f && isnan(r.psi_pm));
    assert_int_equal(out.n_d, 5);
    assert_int_equal(out.n_q, 7);
    assert_memory_equal(out.psi_d, map.psi_d, 35u * sizeof(float));
    assert_memory_equal(out.psi_q, map.psi_q, 35u * sizeof(float));
    buf[60] ^= 0x10u;
    assert_int_equal(mc_store_model_decode(buf, n, &r, &out), MC_STORE_BAD_CRC);

    mc_est_model_t nomap = {0.4f, 0.0105f, 0.0129f, 0.343f, NULL};
    const size_t n2 = mc_store_model_encode(&nomap, buf, sizeof buf);
    assert_int_equal(n2, 32u);
    assert_int_equal(mc_store_model_decode(buf, n2, &r, &out), MC_STORE_OK);
    assert_null(r.map);
}

/* The image's way: the map used where it lies, checked against the record. */
static void test_model_view_in_place(void **state)
{
    (void)state;
    static mc_flux_map_t map, place;
    memset(&map, 0, sizeof map);
    map.n_d = 4;
    map.n_q = 3;
    map.id0 = -10.0f;
    map.did = 5.0f;
    map.iq0 = 0.0f;
    map.diq = 4.0f;
    for (int k = 0; k < 12; ++k) {
        map.psi_d[k] = 0.2f + 0.01f * (float)k;
        map.psi_q[k] = 0.003f * (float)k;
    }
    const mc_est_model_t m = {0.5f, 0.01f, 0.02f, 0.3f, &map};
    const size_t n = mc_store_model_encode(&m, buf, sizeof buf);
    mc_est_model_t r = {0};
    place = map;
    for (int k = 12; k < 40; ++k) {
        place.psi_d[k] = NAN;   /* beyond n_d n_q: not looked at */
    }
    assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_OK);
    assert_ptr_equal(r.map, &place);
    assert_true(r.rs == 0.5f && r.ld == 0.01f && r.lq == 0.02f && r.psi_pm == 0.3f);
    /* one cell off by one bit */
    place.psi_q[11] = mc_bits_f32(mc_f32_bits(place.psi_q[11]) ^ 1u);
    r.map = &map;
    assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_MAP_MISMATCH);
    assert_ptr_equal(r.map, &map);   /* unchanged on a failure */
    place = map;
    place.n_q = 4;   /* other dimensions */
    assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_MAP_MISMATCH);
    place = map;
    place.did = 5.5f;
    assert_int_equal(mc_store_model_view(buf, n, &r, &place), MC_STORE_MAP_MISMATCH);
    assert_int_equal(mc_store_model_view(buf, n, &r, NULL), MC_STORE_MAP_MISMATCH);
    buf[8] ^= 1u;   /* the record itself corrupt */
    assert_int_equal(mc_store_model_view(buf, n, &r, &map), MC_STORE_BAD_CRC);
    /* a record without a map: NULL, map_in_place not read */
    const mc_est_model_t nomap = {0.5f, 0.01f, 0.02f, 0.3f, NULL};
    const size_t n2 = mc_store_model_encode(&nomap, buf, sizeof buf);
    assert_int_equal(mc_store_model_view(buf, n2, &r, NULL), MC_STORE_OK);
    assert_null(r.map);
    assert_string_equal(mc_store_status_name(MC_STORE_MAP_MISMATCH), "map_mismatch");
}

static void test_monitor_telemetry_round_trip(void **state)
{
    (void)state;
    mc_drive_telem_t t, u;
    memset(&t, 0, sizeof t);
    t.state = MC_STATE_FAULT_REACTION;
    t.init_step = MC_INIT_CATCH;
    t.faults = 0x8001u;
    t.period = 123456u;
    t.theta = -2.5f;
    t.omega = 314.0f;
    t.i_ref.q = 7.5f;
    t.est_iters = -1;
    t.duty[2] = 0.25f;
    t.fw_active = true;
    t.polarity_last = -1;
    t.cmd_reject_last = MC_CMD_BAD_MODE;
    uint32_t w[MC_MONITOR_TM_WORDS];
    mc_monitor_pack_telem(&t, w);
    /* the frame is a function of the telemetry alone: whatever the block held before (RAM after
     * reset, the previous frame), every word is written, the unused tail as 0 */
    uint32_t w2[MC_MONITOR_TM_WORDS];
    memset(w2, 0xA5, sizeof w2);
    mc_monitor_pack_telem(&t, w2);
    assert_memory_equal(w, w2, sizeof w);
    mc_drive_telem_t z;
    memset(&z, 0, sizeof z);
    mc_monitor_pack_telem(&z, w2);
    for (unsigned k = 0u; k < MC_MONITOR_TM_WORDS; ++k) {
        assert_int_equal(w2[k], 0u);   /* all-zero telemetry (+0.0f floats): all-zero words */
    }
    mc_monitor_unpack_telem(w, &u);
    assert_int_equal(u.state, MC_STATE_FAULT_REACTION);
    assert_int_equal(u.init_step, MC_INIT_CATCH);
    assert_int_equal(u.faults, 0x8001u);
    assert_int_equal(u.period, 123456u);
    assert_true(u.theta == -2.5f && u.omega == 314.0f && u.i_ref.q == 7.5f && u.duty[2] == 0.25f);
    assert_int_equal(u.est_iters, -1);
    assert_true(u.fw_active);
    assert_int_equal(u.polarity_last, -1);
    assert_int_equal(u.cmd_reject_last, MC_CMD_BAD_MODE);

    mc_drive_cmd_t c = {true, MC_MODE_SPEED, {1.0f, -2.0f}, 3.0f, 104.7f, 0.5f}, d;
    uint32_t cw[MC_MONITOR_CMD_WORDS];
    mc_monitor_pack_cmd(&c, cw);
    mc_monitor_unpack_cmd(cw, &d);
    assert_true(d.enable && d.mode == MC_MODE_SPEED && d.i_ref.d == 1.0f && d.i_ref.q == -2.0f &&
                d.torque_ref == 3.0f && d.speed_ref == 104.7f && d.theta_init == 0.5f);
    cw[1] = 99u;   /* an unknown mode stays unknown (the drive refuses it) */
    mc_monitor_unpack_cmd(cw, &d);
    assert_int_equal(d.mode, MC_MODE_COUNT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc32_check_value),
        cmocka_unit_test(test_params_round_trip),
        cmocka_unit_test(test_params_corruption_refused),
        cmocka_unit_test(test_params_by_name),
        cmocka_unit_test(test_param_keys_distinct),
        cmocka_unit_test(test_v1_keys_name_todays_parameters), cmocka_unit_test(test_v1_keys_are_the_5265cfe_table), cmocka_unit_test(test_model_round_trip_with_map),
        cmocka_unit_test(test_model_view_in_place),
        cmocka_unit_test(test_monitor_telemetry_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
