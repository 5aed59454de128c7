/* PDOs (mc/co.h, co_pdo.c): the default mapping, the CiA 301 mapping procedure and its aborts,
 * RPDOs applied at once or at the SYNC, TPDOs on the event timer, on change and on the SYNC,
 * the NMT state they need, and the COB-ID rules. */
#include "rig.h"

#define INVALID 0x80000000u

static void test_defaults(void **state)
{
    (void)state;
    rig_init();
    uint32_t a;
    assert_int_equal(sdo_read(0x1400, 1, &a), 0x205u);
    assert_int_equal(sdo_read(0x1402, 1, &a), INVALID | 0x405u);
    assert_int_equal(sdo_read(0x1600, 0, &a), 2u);
    assert_int_equal(sdo_read(0x1600, 1, &a), 0x60400010u);
    assert_int_equal(sdo_read(0x1600, 2, &a), 0x60600008u);
    assert_int_equal(sdo_read(0x1601, 1, &a), 0x60FF0020u);
    assert_int_equal(sdo_read(0x1800, 1, &a), 0x40000185u);
    assert_int_equal(sdo_read(0x1800, 2, &a), 255u);
    assert_int_equal(sdo_read(0x1801, 5, &a), 10u);
    assert_int_equal(sdo_read(0x1A01, 1, &a), 0x606C0020u);
    assert_int_equal(sdo_read(0x1A03, 1, &a), 0x22150020u);
    (void)sdo_read(0x1800, 4, &a);   /* reserved */
    assert_int_equal(a, MC_SDO_ABORT_NO_SUB);
    (void)sdo_read(0x1404, 1, &a);
    assert_int_equal(a, MC_SDO_ABORT_NO_OBJECT);
    assert_int_equal(sdo_write(0x1400, 0, 3, 1), MC_SDO_ABORT_READ_ONLY);
}

static void test_mapping_procedure(void **state)
{
    (void)state;
    rig_init();
    /* a valid PDO's mapping cannot change */
    assert_int_equal(sdo_write(0x1A01, 0, 0, 1), MC_SDO_ABORT_STATE);
    assert_int_equal(sdo_write(0x1A01, 1, 0x60410010u, 4), MC_SDO_ABORT_STATE);
    assert_int_equal(sdo_write(0x1801, 1, INVALID | 0x285u, 4), 0u);
    /* sub 0 first */
    assert_int_equal(sdo_write(0x1A01, 1, 0x60410010u, 4), MC_SDO_ABORT_STATE);
    assert_int_equal(sdo_write(0x1A01, 0, 0, 1), 0u);
    assert_int_equal(sdo_write(0x1A01, 1, 0x60400010u, 4), MC_SDO_ABORT_NOT_MAPPABLE);   /* controlword: RPDO only */
    assert_int_equal(sdo_write(0x1A01, 1, 0x60410008u, 4), MC_SDO_ABORT_NOT_MAPPABLE);   /* a part of an object */
    assert_int_equal(sdo_write(0x1A01, 1, 0x12340010u, 4), MC_SDO_ABORT_NO_OBJECT);
    assert_int_equal(sdo_write(0x1A01, 1, 0x60410110u, 4), MC_SDO_ABORT_NO_SUB);
    assert_int_equal(sdo_write(0x1A01, 1, (uint32_t)(0x2000 + 3) << 16 | 0x20u, 4), MC_SDO_ABORT_NOT_MAPPABLE);
    /* three 32-bit objects are 96 bits */
    assert_int_equal(sdo_write(0x1A01, 1, 0x606C0020u, 4), 0u);
    assert_int_equal(sdo_write(0x1A01, 2, 0x22080020u, 4), 0u);
    assert_int_equal(sdo_write(0x1A01, 3, 0x22060020u, 4), 0u);
    assert_int_equal(sdo_write(0x1A01, 0, 3, 1), MC_SDO_ABORT_PDO_LENGTH);
    assert_int_equal(sdo_write(0x1A01, 0, 9, 1), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write(0x1A01, 0, 2, 1), 0u);
    assert_int_equal(sdo_write(0x1801, 3, 20, 2), 0u);   /* inhibit time while invalid */
    assert_int_equal(sdo_write(0x1801, 1, 0x285u, 4), 0u);
    assert_int_equal(sdo_write(0x1801, 3, 10, 2), MC_SDO_ABORT_STATE);
    /* the CAN-ID of a valid PDO does not change; 29-bit ids are refused */
    assert_int_equal(sdo_write(0x1801, 1, 0x286u, 4), MC_SDO_ABORT_VALUE);
    assert_int_equal(sdo_write(0x1801, 1, INVALID | 0x20000000u | 0x285u, 4), MC_SDO_ABORT_VALUE);
    assert_int_equal(sdo_write(0x1801, 2, 245, 1), MC_SDO_ABORT_VALUE);   /* reserved type */
    /* operational: the new mapping goes out with the telemetry's omega in bytes 4..7 */
    nmt(0x01);
    drain();
    rig.co.tm.omega = 123.5f;
    rig.co.now_ms += 20u;
    mc_co_pdo_tx(&rig.co);
    hal_can_frame_t f;
    assert_true(take_id(0x285u, &f));
    assert_int_equal(f.dlc, 8u);
    assert_true(mc_bits_f32(word(&f)) == 123.5f);
    /* reset communication: the defaults again */
    nmt(0x82);
    uint32_t a;
    assert_int_equal(sdo_read(0x1A01, 2, &a), 0x60770010u);
}

static void test_rpdo(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    const uint8_t d[6] = {0xDC, 0x05, 0x00, 0x00, 0x64, 0x00};   /* 1500 rpm, 100 per-mille */
    put(0x305u, d, 6u);   /* pre-operational: not processed */
    mc_co_step(&rig.co, rig.now);
    uint32_t a;
    assert_int_equal(sdo_read(0x60FF, 0, &a), 0u);
    nmt(0x01);
    put(0x305u, d, 6u);
    mc_co_step(&rig.co, rig.now);
    assert_int_equal(sdo_read(0x60FF, 0, &a), 1500u);
    assert_int_equal(sdo_read(0x6071, 0, &a), 100u);
    assert_int_equal(rig.co.rpdo_rx, 1u);
    /* too short: EMCY 0x8210, nothing applied */
    drain();
    const uint8_t s[3] = {0x10, 0x27, 0x00};
    put(0x305u, s, 3u);
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take_id(0x080u + NODE, &f));
    assert_int_equal(f.data[0] | (f.data[1] << 8), MC_EMCY_PDO_LENGTH);
    assert_int_equal(sdo_read(0x60FF, 0, &a), 1500u);
    assert_int_equal(rig.co.rpdo_bad, 1u);
    /* a mode this drive does not have: that object keeps its value, the other one is taken */
    const uint8_t m[3] = {0x06, 0x00, 0x01};   /* controlword 6, mode 1 (profile position) */
    put(0x205u, m, 3u);
    mc_co_step(&rig.co, rig.now);
    assert_int_equal(sdo_read(0x6040, 0, &a), 6u);
    assert_int_equal(sdo_read(0x6060, 0, &a), (uint32_t)MC_402_MODE_PV);
    assert_int_equal(rig.co.rpdo_bad, 2u);
    /* synchronous RPDO: held until the SYNC */
    assert_int_equal(sdo_write(0x1401, 2, 0, 1), 0u);
    const uint8_t v[6] = {0xE8, 0x03, 0x00, 0x00, 0x00, 0x00};   /* 1000 rpm */
    put(0x305u, v, 6u);
    mc_co_step(&rig.co, rig.now);
    assert_int_equal(sdo_read(0x60FF, 0, &a), 1500u);
    put(0x080u, v, 0u);
    mc_co_step(&rig.co, rig.now);
    assert_int_equal(sdo_read(0x60FF, 0, &a), 1000u);
}

static void test_tpdo_timing(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drive_inputs(300.0f);
    run_ms(50);
    hal_can_frame_t f;
    assert_false(take_id(0x285u, &f));   /* pre-operational: none */
    nmt(0x01);
    drain();
    run_ms(100);
    uint32_t n2 = 0, n1 = 0;
    while (take_any(&f)) {
        n2 += f.id == 0x285u;
        n1 += f.id == 0x185u;
    }
    assert_in_range(n2, 9, 11);   /* every 10 ms */
    assert_in_range(n1, 1, 2);    /* statusword unchanged: its 100 ms timer */
    /* on change: the statusword's PDO (type 255) goes out within a step of the change */
    rig.co.ds.od.statusword ^= 0x4000u;
    rig.co.now_ms++;
    mc_co_pdo_tx(&rig.co);
    assert_true(take_id(0x185u, &f));
    /* SYNC types: TPDO2 every 2nd SYNC, nothing on its timer */
    assert_int_equal(sdo_write(0x1801, 2, 2, 1), 0u);
    drain();
    run_ms(30);
    assert_false(take_id(0x285u, &f));
    const uint8_t none[1] = {0};
    for (int k = 0; k < 6; ++k) {
        put(0x080u, none, 0u);
        mc_co_step(&rig.co, rig.now);
    }
    uint32_t n = 0;
    while (take_any(&f)) {
        n += f.id == 0x285u;
    }
    assert_int_equal(n, 3u);
    /* stopped: nothing */
    nmt(0x02);
    drain();
    run_ms(30);
    assert_false(take_id(0x285u, &f));
}

/* mc_co_pdo_read/write serve the four PDO ranges only (0x1400.., 0x1600.., 0x1800.., 0x1A00..,
 * MC_CO_PDO_N each): an index beside a range, below 0x1400 or between two ranges, is no PDO
 * object (NO_OBJECT) and a write to it changes no PDO, whoever routes it there. The first index
 * of each range is one. */
static void test_pdo_index_ranges(void **state)
{
    (void)state;
    rig_init();
    static const uint16_t none[] = {0x0000u, 0x1000u, 0x1017u, 0x1200u, 0x13FFu,
                                    0x1400u + MC_CO_PDO_N, 0x15FFu, 0x1600u + MC_CO_PDO_N, 0x17FFu,
                                    0x1800u + MC_CO_PDO_N, 0x19FFu, 0x1A00u + MC_CO_PDO_N, 0x1BFFu, 0xFFFFu};
    static mc_co_t before;
    before = rig.co;
    for (size_t k = 0; k < sizeof none / sizeof none[0]; ++k) {
        for (uint8_t sub = 0u; sub <= 2u; ++sub) {
            uint32_t v = 0xA5A5A5A5u;
            assert_int_equal(mc_co_pdo_read(&rig.co, none[k], sub, &v), MC_SDO_ABORT_NO_OBJECT);
            assert_int_equal(v, 0xA5A5A5A5u);
            assert_int_equal(mc_co_pdo_write(&rig.co, none[k], sub, 0u), MC_SDO_ABORT_NO_OBJECT);
        }
    }
    assert_memory_equal(rig.co.rpdo, before.rpdo, sizeof before.rpdo);
    assert_memory_equal(rig.co.tpdo, before.tpdo, sizeof before.tpdo);
    static const uint16_t first[] = {0x1400u, 0x1600u, 0x1800u, 0x1A00u};
    static const uint32_t sub0[] = {2u, 2u, 6u, 2u};   /* highest sub; a mapping's entries */
    for (size_t k = 0; k < 4; ++k) {
        uint32_t v = 0u;
        assert_int_equal(mc_co_pdo_read(&rig.co, first[k], 0u, &v), 0u);
        assert_int_equal(v, sub0[k]);
    }
}

/* A controlword that comes by RPDO counts as one (the image hands the drive to CANopen on the
 * first) and takes its own 402 transition, also two in one batch (CiA 402 §6.3); an RPDO without
 * the controlword (target velocity) is none. RPDO3 is mapped here to the controlword alone. */
static void test_rpdo_controlword(void **state)
{
    (void)state;
    rig_init();
    assert_int_equal(sdo_write(0x1602, 0, 0, 1), 0u);
    assert_int_equal(sdo_write(0x1602, 1, 0x60400010u, 4), 0u);
    assert_int_equal(sdo_write(0x1602, 0, 1, 1), 0u);
    assert_int_equal(sdo_write(0x1402, 1, 0x405u, 4), 0u);
    nmt(0x01);
    drain();
    assert_int_equal(rig.co.ds.od.statusword & 0x6Fu, 0x40u);   /* switch on disabled */
    const uint32_t cw0 = rig.co.cw_count;
    const uint8_t v[6] = {0xDC, 0x05, 0x00, 0x00, 0x64, 0x00};   /* RPDO2: 1500 rpm, 100 per-mille */
    put(0x305u, v, 6u);
    mc_co_step(&rig.co, rig.now);
    uint32_t a;
    assert_int_equal(sdo_read(0x60FF, 0, &a), 1500u);
    assert_int_equal(rig.co.cw_count, cw0);
    /* shutdown then switch on, in one batch: both transitions taken */
    const uint8_t shutdown[2] = {0x06, 0x00}, switch_on[2] = {0x07, 0x00};
    put(0x405u, shutdown, 2u);
    put(0x405u, switch_on, 2u);
    mc_co_step(&rig.co, rig.now);
    assert_int_equal(rig.co.cw_count, cw0 + 2u);
    assert_int_equal(sdo_read(0x6040, 0, &a), 0x07u);
    assert_int_equal(rig.co.ds.od.statusword & 0x6Fu, 0x23u);   /* switched on */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_mapping_procedure),
        cmocka_unit_test(test_rpdo),
        cmocka_unit_test(test_tpdo_timing),
        cmocka_unit_test(test_pdo_index_ranges),
        cmocka_unit_test(test_rpdo_controlword),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
