/* The object dictionary (co_od.c): its description is consistent and every object answers; the
 * write checks of the fixed objects; 0x1010 / 0x1011 on the power-cut-safe store and the boot
 * that follows; the scope over SDO with the segmented upload of its record. */
#include "rig.h"
#include "mc/telem_channels.h"

static void test_every_object(void **state)
{
    (void)state;
    rig_init();
    const uint32_t n = mc_co_od_count();
    assert_true(n > 200u);
    uint32_t prev = 0u;
    for (uint32_t k = 0; k < n; ++k) {
        mc_co_entry_t e, l;
        bool miss = true;
        assert_true(mc_co_od_at(k, &e));
        assert_true(mc_co_od_lookup(e.index, e.sub, &l, &miss));
        assert_false(miss);
        assert_int_equal(l.type, e.type);
        assert_int_equal(l.access, e.access);
        assert_non_null(e.oname);
        assert_true(e.oname[0] != '\0');
        assert_true(e.min <= e.max || e.type == MC_CO_REAL32 || e.type == MC_CO_VSTRING || e.type == MC_CO_DOMAIN);
        const uint32_t key = ((uint32_t)e.index << 8) | e.sub;
        (void)prev;
        prev = key;
        if (e.type == MC_CO_DOMAIN || e.access == MC_CO_WO) {
            continue;
        }
        uint8_t buf[MC_CO_SDO_BUF];
        uint32_t len = 0u;
        const uint32_t a = mc_co_od_read(&rig.co, e.index, e.sub, buf, sizeof buf, &len);
        if (a != 0u) {
            fail_msg("0x%04X sub %u: abort 0x%08X", e.index, e.sub, a);
        }
        if (e.type != MC_CO_VSTRING) {
            assert_int_equal(len, e.type == MC_CO_U8 || e.type == MC_CO_I8 ? 1u : e.type == MC_CO_U16 || e.type == MC_CO_I16 ? 2u : 4u);
        }
    }
    assert_false(mc_co_od_at(n, &(mc_co_entry_t){0}));
    bool miss = false;
    mc_co_entry_t e;
    assert_false(mc_co_od_lookup(0x1018, 5, &e, &miss));
    assert_true(miss);
    assert_false(mc_co_od_lookup(0x1019, 0, &e, &miss));
    assert_false(miss);
    /* the parameter-table hash */
    uint32_t a;
    assert_int_equal(sdo_read(0x2FF0, 0, &a), mc_params_table_hash());
}

static void test_write_checks(void **state)
{
    (void)state;
    rig_init();
    assert_int_equal(sdo_write(0x6060, 0, 1, 1), MC_SDO_ABORT_VALUE);   /* profile position: not here */
    assert_int_equal(sdo_write(0x6060, 0, MC_402_MODE_CSV, 1), 0u);
    assert_int_equal(sdo_write(0x605A, 0, 9, 2), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write(0x605A, 0, 0xFFFF, 2), MC_SDO_ABORT_VALUE_LOW);   /* -1 */
    assert_int_equal(sdo_write(0x605A, 0, 5, 2), 0u);
    assert_int_equal(sdo_write(0x6041, 0, 0, 2), MC_SDO_ABORT_READ_ONLY);
    assert_int_equal(sdo_write(0x6040, 0, 6, 4), MC_SDO_ABORT_LENGTH_HIGH);
    assert_int_equal(sdo_write(0x60FF, 0, 6, 2), MC_SDO_ABORT_LENGTH_LOW);
    assert_int_equal(sdo_write(0x6083, 0, 0, 4), MC_SDO_ABORT_VALUE_LOW);
    assert_int_equal(sdo_write(0x2301, 3, 3, 1), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write(0x2301, 4, 0, 2), MC_SDO_ABORT_VALUE_LOW);
    assert_int_equal(sdo_write(0x2301, 2, 0x7FC00000u, 4), MC_SDO_ABORT_VALUE);   /* NaN level */
    assert_int_equal(sdo_write(0x2300, 1, MC_TELEM_CHANNEL_COUNT + 1u, 1), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write(0x1005, 0, 0x40000080u, 4), MC_SDO_ABORT_VALUE);   /* SYNC producer */
    assert_int_equal(sdo_write(0x1005, 0, 0x81u, 4), 0u);
    /* a refused write changes nothing */
    uint32_t a;
    assert_int_equal(sdo_read(0x605A, 0, &a), 5u);
    assert_int_equal(sdo_read(0x6060, 0, &a), (uint32_t)MC_402_MODE_CSV);
}

static void test_store_restore(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    const int bw = mc_param_find("control.current_bw_hz");
    const uint16_t obj = (uint16_t)(0x2000 + bw);
    assert_int_equal(sdo_write(obj, 0, mc_f32_bits(321.0f), 4), 0u);
    mc_drive_isr(&rig.d);
    assert_int_equal(sdo_write(0x1010, 1, 0x12345678u, 4), MC_SDO_ABORT_STORE);   /* not "save" */
    /* not while the outputs are on */
    drive_inputs(300.0f);
    const mc_drive_cmd_t on = {.enable = true, .mode = MC_MODE_CURRENT};
    mc_drive_command(&rig.d, &on);
    run_ms(1);
    assert_true(mc_drive_state(&rig.d) != MC_STATE_IDLE);
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), MC_SDO_ABORT_STATE);
    const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
    mc_drive_command(&rig.d, &off);
    run_ms(1);
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), 0u);
    uint32_t a;
    assert_int_equal(sdo_read(0x1010, 1, &a), 1u);
    /* power-on: the stored set */
    hal_nvm_t nvm = rig.nvm;
    mc_drive_cfg_t base;
    mc_drive_cfg_default(&base);
    static mc_flux_map_t map;
    memset(&rig, 0, sizeof rig);
    rig.nvm = nvm;
    assert_int_equal(mc_co_boot_config(&rig.nvm, &base, &rig.cfg, &map, NULL), MC_PSTORE_OK);
    rig_start(MC_PSTORE_OK);
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == 321.0f);
    assert_int_equal(sdo_read(0x2FF1, 0, &a), 0u);
    /* restore defaults: the next power-on has none stored */
    assert_int_equal(sdo_write(0x1011, 1, 0x1234u, 4), MC_SDO_ABORT_STORE);
    assert_int_equal(sdo_write(0x1011, 1, MC_CO_LOAD_SIGNATURE, 4), 0u);
    nvm = rig.nvm;
    assert_int_equal(mc_co_boot_config(&nvm, &base, &rig.cfg, &map, NULL), MC_PSTORE_EMPTY);
    assert_true(rig.cfg.p.control_current_bw_hz == base.p.control_current_bw_hz);
    /* a corrupt store: the defaults and EMCY 0x6310 with the boot-up */
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), 0u);
    nvm = rig.nvm;
    for (uint32_t b = 0; b < HAL_HOST_NVM_BLOCKS; ++b) {
        for (uint32_t k = 8; k < 32; ++k) {   /* both copies' headers (the markers stay) */
            nvm.mem[b * HAL_HOST_NVM_BLOCK_SIZE + k] ^= 0x5Au;
        }
    }
    memset(&rig, 0, sizeof rig);
    rig.nvm = nvm;
    const mc_pstore_status_t st = mc_co_boot_config(&rig.nvm, &base, &rig.cfg, &map, NULL);
    assert_int_equal(st, MC_PSTORE_CORRUPT);
    assert_true(rig.cfg.p.control_current_bw_hz == base.p.control_current_bw_hz);
    rig_start(st);
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take_id(0x080u + NODE, &f));
    assert_int_equal(f.data[0] | (f.data[1] << 8), MC_EMCY_PARAMS_LOST);
    assert_int_equal(sdo_read(0x2FF1, 0, &a), (uint32_t)MC_PSTORE_CORRUPT);
    /* the NVM fails during the store (a power cut at its 3rd step): hardware error, EMCY 0x5530,
     * and the set committed before is what a load returns */
    drain();
    hal_host_nvm_cut_at(&rig.nvm, rig.nvm.steps + 3u);
    const uint8_t save[8] = {0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65};
    put(0x600u + NODE, save, 8u);
    mc_co_step(&rig.co, rig.now);
    bool emcy = false, abort_hw = false;
    while (take_any(&f)) {
        emcy = emcy || (f.id == 0x080u + NODE && (f.data[0] | (f.data[1] << 8)) == MC_EMCY_NVM);
        abort_hw = abort_hw || (f.id == 0x580u + NODE && f.data[0] == 0x80u && word(&f) == MC_SDO_ABORT_HW);
    }
    assert_true(emcy);
    assert_true(abort_hw);
    assert_int_equal(sdo_read(0x2FF2, 0, &a), (uint32_t)MC_PSTORE_NVM_ERROR);
    hal_host_nvm_power_on(&rig.nvm);
    /* no NVM: cannot be stored */
    rig.co.nvm = NULL;
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), MC_SDO_ABORT_STORE);
}

/* NMT reset node: the drive's parameters to their power-on values (the stored set, else the
 * defaults), once its outputs are off; a set the drive refuses keeps them, with EMCY 0x6320. */
static void test_reset_node_reloads(void **state)
{
    (void)state;
    rig_init();
    static mc_params_t defaults;
    defaults = rig.cfg.p;
    mc_co_set_defaults(&rig.co, &defaults);
    rig.co.ds_on = false;
    drive_inputs(300.0f);
    const int bw = mc_param_find("control.current_bw_hz");
    const uint16_t obj = (uint16_t)(0x2000 + bw);
    uint32_t a;
    assert_int_equal(sdo_write(obj, 0, mc_f32_bits(321.0f), 4), 0u);
    run_ms(1);
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), 0u);
    assert_int_equal(sdo_write(obj, 0, mc_f32_bits(400.0f), 4), 0u);
    run_ms(1);
    /* outputs on: the reload waits */
    const mc_drive_cmd_t on = {.enable = true, .mode = MC_MODE_CURRENT};
    mc_drive_command(&rig.d, &on);
    run_ms(2);
    assert_true(mc_drive_state(&rig.d) != MC_STATE_IDLE);
    nmt(0x81);
    run_ms(3);
    drain();
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == 400.0f);
    const mc_drive_cmd_t off = {.enable = false, .mode = MC_MODE_CURRENT};
    mc_drive_command(&rig.d, &off);
    run_ms(3);
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == 321.0f);   /* the stored set */
    /* restore, reset node: the defaults */
    assert_int_equal(sdo_write(0x1011, 1, MC_CO_LOAD_SIGNATURE, 4), 0u);
    nmt(0x81);
    run_ms(3);
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == defaults.control_current_bw_hz);
    /* a stored set with another INIT parameter (the PWM period) is refused: EMCY, nothing changes */
    mc_drive_cfg_t other = {.p = rig.d.cfg->p, .est = rig.d.est};
    assert_true(mc_param_set(&other.p, mc_param_find("control.ts_s"), 2e-4f, NULL));
    assert_true(mc_param_set(&other.p, bw, 123.0f, NULL));
    uint8_t work[MC_CO_STORE_WORK];
    assert_int_equal(mc_pstore_save(&rig.nvm, &other, work, sizeof work, NULL), MC_PSTORE_OK);
    drain();
    nmt(0x81);
    run_ms(3);
    hal_can_frame_t f;
    assert_true(take_id(0x080u + NODE, &f));
    assert_int_equal(f.data[0] | (f.data[1] << 8), 0x6320);
    assert_int_equal(f.data[4] | (f.data[5] << 8), mc_param_find("control.ts_s"));
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == defaults.control_current_bw_hz);
    /* without defaults a reset node keeps the parameters */
    mc_co_set_defaults(&rig.co, NULL);
    assert_int_equal(sdo_write(obj, 0, mc_f32_bits(222.0f), 4), 0u);
    run_ms(1);
    nmt(0x81);
    run_ms(3);
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == 222.0f);
}

/* A segmented download whose data does not match the size it announced. */
static void test_segmented_size_mismatch(void **state)
{
    (void)state;
    rig_init();
    hal_can_frame_t f = sdo(0x21, 0x1017, 0, 4);   /* announces 4 bytes for a 2-byte object */
    assert_int_equal(f.data[0], 0x60u);
    const uint8_t seg[8] = {(uint8_t)((5u << 1) | 1u), 0x2C, 0x01, 0, 0, 0, 0, 0};   /* 2 bytes, last */
    put(0x600u + NODE, seg, 8u);
    mc_co_step(&rig.co, rig.now);
    assert_true(take_id(0x580u + NODE, &f));
    assert_int_equal(f.data[0], 0x80u);
    assert_int_equal(word(&f), MC_SDO_ABORT_LENGTH);
    uint32_t a;
    assert_int_equal(sdo_read(0x1017, 0, &a), 0u);   /* unchanged */
    /* a segmented download longer than any object */
    f = sdo(0x21, 0x1017, 0, 100);
    assert_int_equal(word(&f), MC_SDO_ABORT_LENGTH_HIGH);
}

static void test_scope_upload(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drive_inputs(300.0f);
    uint32_t a;
    (void)sdo(0x40, 0x2307, 0, 0);   /* nothing recorded */
    const hal_can_frame_t none = sdo(0x40, 0x2307, 0, 0);
    assert_int_equal(word(&none), MC_SDO_ABORT_NO_DATA);
    assert_int_equal(sdo_write(0x2302, 0, 1, 1), MC_SDO_ABORT_VALUE);   /* no channel chosen */
    assert_int_equal(sdo_write(0x2300, 1, 6, 1), 0u);    /* vdc */
    assert_int_equal(sdo_write(0x2300, 3, 1, 1), 0u);    /* state */
    assert_int_equal(sdo_write(0x2301, 4, 2, 2), 0u);    /* every 2nd period */
    assert_int_equal(sdo_write(0x2301, 6, 9, 4), 0u);    /* 9 samples */
    assert_int_equal(sdo_write(0x2302, 0, 1, 1), 0u);    /* arm: no trigger channel, at once */
    run_ms(3);
    assert_int_equal(sdo_read(0x2303, 0, &a), 3u);
    assert_int_equal(sdo_read(0x2304, 0, &a), 9u);
    assert_true(mc_bits_f32(sdo_read(0x2306, 0, &a)) == 2.0f * rig.cfg.p.control_ts_s);
    /* segmented upload: 9 samples x 2 channels x 4 bytes */
    hal_can_frame_t f = sdo(0x40, 0x2307, 0, 0);
    assert_int_equal(f.data[0], 0x41u);
    assert_int_equal(word(&f), 72u);
    uint8_t data[80];
    uint32_t got = 0;
    for (uint8_t t = 0;; t ^= 1u) {
        f = sdo((uint8_t)(0x60 | (t << 4)), 0, 0, 0);
        assert_int_equal((f.data[0] >> 4) & 1u, t);
        const uint32_t n = 7u - ((f.data[0] >> 1) & 7u);
        memcpy(data + got, f.data + 1, n);
        got += n;
        if (f.data[0] & 1u) {
            break;
        }
    }
    assert_int_equal(got, 72u);
    for (uint32_t s = 0; s < 9; ++s) {
        uint32_t w0, w1;
        memcpy(&w0, data + 8 * s, 4);
        memcpy(&w1, data + 8 * s + 4, 4);
        assert_float_equal(mc_bits_f32(w0), 300.0f, 1.0f);   /* vdc */
        assert_float_equal(mc_bits_f32(w1), (float)MC_STATE_IDLE, 0.0f);
    }
}

/* A stored set from another table version with values kept at their defaults (mc/store.h):
 * 0x2FF1 says so, EMCY 0x6310 with the boot-up carries the count, the first such parameter and
 * why, and the error history 0x1003 keeps it after the EMCY. */
static void test_boot_partial_reported(void **state)
{
    (void)state;
    rig_init();
    const int k1 = mc_param_find("estimator.k1");
    memset(&rig.co, 0, sizeof rig.co);
    rig_start(MC_PSTORE_PARTIAL);
    const mc_store_report_t rep = {.kept = 90u, .dropped = 2u, .unknown = 1u, .first = (int16_t)k1,
                                   .reason = MC_STORE_DROP_RANGE, .other_table = true};
    mc_co_set_boot_report(&rig.co, &rep);
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take_id(0x080u + NODE, &f));
    assert_int_equal(f.data[0] | (f.data[1] << 8), MC_EMCY_PARAMS_LOST);
    assert_int_equal(f.data[3], MC_PSTORE_PARTIAL);
    assert_int_equal(f.data[4], 2);
    assert_int_equal(f.data[5] | (f.data[6] << 8), k1);
    assert_int_equal(f.data[7], MC_STORE_DROP_RANGE);
    uint32_t a;
    assert_int_equal(sdo_read(0x2FF1, 0, &a), (uint32_t)MC_PSTORE_PARTIAL);
    assert_int_equal(sdo_read(0x1003, 0, &a), 1u);
    assert_int_equal(sdo_read(0x1003, 1, &a), MC_EMCY_PARAMS_LOST | ((uint32_t)k1 << 16));
}

/* The PDO communication parameters' numbers (transmission type, inhibit time, event timer, SYNC
 * start value) are described as the device takes them: the declared maximum is accepted and the
 * next value refused "value too high" (where the type holds it), with the PDO invalid (as the
 * CiA 301 procedure asks); the times carry the units the EDS and the tools show (inhibit time in
 * 100 us, event timer in ms, §7.5.2.35). */
static void test_pdo_comm_ranges_and_units(void **state)
{
    (void)state;
    rig_init();
    static const uint16_t comm[] = {0x1400u, 0x1403u, 0x1800u, 0x1803u};
    for (size_t k = 0; k < sizeof comm / sizeof comm[0]; ++k) {
        const uint16_t idx = comm[k];
        uint32_t a;
        const uint32_t cob = sdo_read(idx, 1, &a);
        assert_int_equal(a, 0u);
        assert_int_equal(sdo_write(idx, 1, cob | 0x80000000u, 4), 0u);
        static const uint8_t subs[] = {2u, 3u, 5u, 6u};
        for (size_t j = 0; j < sizeof subs / sizeof subs[0]; ++j) {
            mc_co_entry_t e;
            bool miss = false;
            if (!mc_co_od_lookup(idx, subs[j], &e, &miss)) {
                assert_true(miss);
                assert_true(idx < 0x1800u && subs[j] > 2u);   /* an RPDO has no timers here */
                continue;
            }
            const uint32_t n = e.type == MC_CO_U8 ? 1u : 2u;
            const int64_t type_max = n == 1u ? 255 : 65535;
            assert_true(e.max > 0 && e.max <= type_max);
            if (subs[j] == 2u) {
                assert_int_equal(e.max, 255);   /* 254/255: event-driven, the CiA 301 top types */
            }
            assert_int_equal(sdo_write(idx, subs[j], (uint32_t)e.max, n), 0u);
            if (e.max < type_max) {
                assert_int_equal(sdo_write(idx, subs[j], (uint32_t)e.max + 1u, n), MC_SDO_ABORT_VALUE_HIGH);
            }
            if (subs[j] == 3u) {
                assert_string_equal(e.unit, "100 us");
            } else if (subs[j] == 5u) {
                assert_string_equal(e.unit, "ms");
            }
        }
    }
}

/* Power-on after the newest stored copy was damaged (a bit of its header flipped): the boot
 * takes the copy stored before it, reports FELL_BACK, and the drive runs with that set, not the
 * defaults (CiA 301 0x1010: the last good save survives). */
static void test_boot_falls_back_to_older_copy(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    const int bw = mc_param_find("control.current_bw_hz");
    const uint16_t obj = (uint16_t)(0x2000 + bw);
    assert_int_equal(sdo_write(obj, 0, mc_f32_bits(321.0f), 4), 0u);
    mc_drive_isr(&rig.d);
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), 0u);
    static hal_nvm_t older;
    older = rig.nvm;
    assert_int_equal(sdo_write(obj, 0, mc_f32_bits(456.0f), 4), 0u);
    mc_drive_isr(&rig.d);
    assert_int_equal(sdo_write(0x1010, 1, MC_CO_SAVE_SIGNATURE, 4), 0u);
    static hal_nvm_t nvm;
    nvm = rig.nvm;
    /* the newest copy: the first block the second save changed; its sequence (header byte 8) */
    size_t first = 0u;
    while (first < sizeof nvm.mem && nvm.mem[first] == older.mem[first]) {
        ++first;
    }
    assert_true(first < sizeof nvm.mem);
    mc_drive_cfg_t base;
    mc_drive_cfg_default(&base);
    static mc_flux_map_t map;
    assert_int_equal(mc_co_boot_config(&nvm, &base, &rig.cfg, &map, NULL), MC_PSTORE_OK);
    assert_true(rig.cfg.p.control_current_bw_hz == 456.0f);
    nvm.mem[first / HAL_HOST_NVM_BLOCK_SIZE * HAL_HOST_NVM_BLOCK_SIZE + 8u] ^= 0x01u;
    memset(&rig, 0, sizeof rig);
    rig.nvm = nvm;
    const mc_pstore_status_t st = mc_co_boot_config(&rig.nvm, &base, &rig.cfg, &map, NULL);
    assert_int_equal(st, MC_PSTORE_FELL_BACK);
    assert_true(rig.cfg.p.control_current_bw_hz == 321.0f);
    rig_start(st);
    uint32_t a;
    assert_true(mc_bits_f32(sdo_read(obj, 0, &a)) == 321.0f);
    assert_int_equal(sdo_read(0x2FF1, 0, &a), (uint32_t)MC_PSTORE_FELL_BACK);
}

/* The error history 0x1003 lists the newest entry first and keeps the older ones below it: a
 * partial boot after a reset communication (the history survives it) pushes the previous boot's
 * entry to sub-index 2. */
static void test_boot_partial_history_order(void **state)
{
    (void)state;
    rig_init();
    const int k1 = mc_param_find("estimator.k1"), k2 = mc_param_find("control.current_bw_hz");
    memset(&rig.co, 0, sizeof rig.co);
    rig_start(MC_PSTORE_PARTIAL);
    mc_store_report_t rep = {.kept = 90u, .dropped = 1u, .first = (int16_t)k1, .reason = MC_STORE_DROP_RANGE,
                             .other_table = true};
    mc_co_set_boot_report(&rig.co, &rep);
    mc_co_step(&rig.co, rig.now);
    rep.first = (int16_t)k2;
    mc_co_set_boot_report(&rig.co, &rep);
    nmt(0x82u);   /* reset communication: boot-up again, with the second report */
    mc_co_step(&rig.co, rig.now);
    drain();
    uint32_t a;
    assert_int_equal(sdo_read(0x1003, 0, &a), 2u);
    assert_int_equal(sdo_read(0x1003, 1, &a), MC_EMCY_PARAMS_LOST | ((uint32_t)k2 << 16));
    assert_int_equal(sdo_read(0x1003, 2, &a), MC_EMCY_PARAMS_LOST | ((uint32_t)k1 << 16));
}

/* A mapping object's number of entries (sub 0) is described from 0: 0 is the first step of the
 * CiA 301 mapping procedure (§7.5.2.36), so the declared minimum must be what the device takes,
 * for the RPDO and the TPDO mappings alike (the PDO made invalid first). */
static void test_pdo_map_count_from_zero(void **state)
{
    (void)state;
    rig_init();
    static const uint16_t maps[] = {0x1600u, 0x1A00u};
    for (size_t k = 0; k < 2; ++k) {
        mc_co_entry_t e;
        bool miss = false;
        assert_true(mc_co_od_lookup(maps[k], 0u, &e, &miss));
        const uint16_t comm = (uint16_t)(maps[k] - 0x200u);
        uint32_t a;
        const uint32_t cob = sdo_read(comm, 1, &a);
        assert_int_equal(sdo_write(comm, 1, cob | 0x80000000u, 4), 0u);
        assert_int_equal(sdo_write(maps[k], 0, 0u, 1), 0u);   /* the device takes 0 ... */
        assert_int_equal(sdo_read(maps[k], 0, &a), 0u);
        assert_true(e.min <= 0);                                /* ... and so does its description */
        assert_true(e.max >= 1);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_object),
        cmocka_unit_test(test_write_checks),
        cmocka_unit_test(test_store_restore),
        cmocka_unit_test(test_boot_partial_reported),
        cmocka_unit_test(test_scope_upload),
        cmocka_unit_test(test_segmented_size_mismatch),
        cmocka_unit_test(test_reset_node_reloads),
        cmocka_unit_test(test_pdo_comm_ranges_and_units),
        cmocka_unit_test(test_boot_falls_back_to_older_copy),
        cmocka_unit_test(test_boot_partial_history_order),
        cmocka_unit_test(test_pdo_map_count_from_zero),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
