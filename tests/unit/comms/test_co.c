/* CANopen device (mc/co.h) against the host CAN rings and a real drive: boot-up, heartbeat, NMT,
 * SDO expedited and segmented transfers, parameters 0x2000 + id, and the abort codes. */
#include "rig.h"

/* node 5 with a 100 ms heartbeat and an identity to read back; these tests command the drive
 * themselves (the 402 layer off) */
static void rig_init_co(void)
{
    memset(&rig, 0, sizeof rig);
    hal_host_nvm_init(&rig.nvm);
    mc_drive_cfg_default(&rig.cfg);
    const mc_co_cfg_t c = {.node_id = NODE, .heartbeat_ms = 100, .step_s = 1e-3f, .vendor_id = 0x12345678u,
                           .product_code = 1u, .revision = 2u, .serial = 3u};
    rig_start_cfg(&c, MC_PSTORE_EMPTY);
    rig.co.ds_on = false;
}

/* The next frame that is not a TPDO (operational sends them on their timers). */
static bool take(hal_can_frame_t *f)
{
    while (take_any(f)) {
        if (f->id < 0x180u || f->id > 0x4FFu) {
            return true;
        }
    }
    return false;
}

static void expect_abort(const hal_can_frame_t *f, uint32_t code)
{
    assert_int_equal(f->data[0], 0x80u);
    assert_int_equal(word(f), code);
}

static void drive_run(int n, bool enable);

static void test_node_id_checked(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_t co;
    mc_co_cfg_t c = {.node_id = 0, .step_s = 1e-3f};
    assert_false(mc_co_init(&co, &c, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    c.node_id = 128;
    assert_false(mc_co_init(&co, &c, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    c.node_id = 1;
    c.step_s = 0.0f;   /* the 402 ramps need the step period */
    assert_false(mc_co_init(&co, &c, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    c.step_s = 1e-3f;
    assert_true(mc_co_init(&co, &c, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
}

static void test_boot_heartbeat_nmt(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take(&f));   /* boot-up */
    assert_int_equal(f.id, 0x705u);
    assert_int_equal(f.dlc, 1u);
    assert_int_equal(f.data[0], 0x00u);
    assert_false(take(&f));
    rig.now = 99;
    mc_co_step(&rig.co, rig.now);
    assert_false(take(&f));
    rig.now = 100;
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));   /* heartbeat, pre-operational */
    assert_int_equal(f.id, 0x705u);
    assert_int_equal(f.data[0], 0x7Fu);
    const uint8_t start[2] = {0x01, 5}, stop[2] = {0x02, 0}, other[2] = {0x80, 6}, reset[2] = {0x82, 5};
    put(0x000u, start, 2u);
    rig.now = 200;
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.data[0], 0x05u);
    put(0x000u, other, 2u);   /* another node's command: ignored */
    put(0x000u, stop, 2u);    /* broadcast */
    rig.now = 300;
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.data[0], 0x04u);
    /* stopped: no SDO answer */
    const uint8_t r[8] = {0x40, 0x00, 0x10, 0, 0, 0, 0, 0};
    put(0x605u, r, 8u);
    mc_co_step(&rig.co, rig.now);
    assert_false(take(&f));
    put(0x000u, reset, 2u);   /* reset communication: boot-up again */
    mc_co_step(&rig.co, rig.now);
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.id, 0x705u);
    assert_int_equal(f.data[0], 0x00u);
}

static void test_sdo_expedited_and_segmented_upload(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    (void)take(&f);
    f = sdo(0x40, 0x1000, 0, 0);
    assert_int_equal(f.data[0], 0x43u);   /* expedited, 4 bytes */
    assert_int_equal(word(&f), MC_CO_DEVICE_TYPE);
    f = sdo(0x40, 0x1018, 1, 0);
    assert_int_equal(word(&f), 0x12345678u);
    f = sdo(0x40, 0x1018, 0, 0);
    assert_int_equal(f.data[0], 0x4Fu);   /* 1 byte: n = 3 */
    assert_int_equal(f.data[4], 4u);
    /* 0x1008, 22 bytes: segmented, toggling */
    f = sdo(0x40, 0x1008, 0, 0);
    assert_int_equal(f.data[0], 0x41u);
    const uint32_t size = word(&f);
    assert_int_equal(size, strlen("ipmsm-sensorless-drive"));
    char name[40] = {0};
    uint32_t got = 0;
    for (uint8_t t = 0;; t ^= 1u) {
        f = sdo((uint8_t)(0x60 | (t << 4)), 0, 0, 0);
        assert_int_equal((f.data[0] >> 4) & 1u, t);
        const uint32_t n = 7u - ((f.data[0] >> 1) & 7u);
        memcpy(name + got, f.data + 1, n);
        got += n;
        if (f.data[0] & 1u) {
            break;
        }
    }
    assert_int_equal(got, size);
    assert_string_equal(name, "ipmsm-sensorless-drive");
    /* a toggle error mid-transfer */
    (void)sdo(0x40, 0x1008, 0, 0);
    (void)sdo(0x60, 0, 0, 0);
    f = sdo(0x60, 0, 0, 0);   /* toggle should be 1 */
    expect_abort(&f, MC_SDO_ABORT_TOGGLE);
    /* a timeout */
    (void)sdo(0x40, 0x1008, 0, 0);
    rig.now += MC_CO_SDO_TIMEOUT_MS + 1u;
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    expect_abort(&f, MC_SDO_ABORT_TIMEOUT);
}

static void test_sdo_parameters(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    (void)take(&f);
    const int id = mc_param_find("control.current_bw_hz");
    assert_true(id >= 0);
    const uint16_t obj = (uint16_t)(0x2000 + id);
    f = sdo(0x40, obj, 0, 0);
    assert_true(mc_bits_f32(word(&f)) == mc_param_get(mc_drive_params(&rig.d), id));
    /* write 300 Hz: taken by the ISR at the next period, then read back */
    f = sdo(0x23, obj, 0, mc_f32_bits(300.0f));
    assert_int_equal(f.data[0], 0x60u);
    mc_drive_isr(&rig.d);
    f = sdo(0x40, obj, 0, 0);
    assert_true(mc_bits_f32(word(&f)) == 300.0f);
    /* the table's limits: 10..5000 Hz */
    f = sdo(0x23, obj, 0, mc_f32_bits(6000.0f));
    expect_abort(&f, MC_SDO_ABORT_VALUE_HIGH);
    f = sdo(0x23, obj, 0, mc_f32_bits(1.0f));
    expect_abort(&f, MC_SDO_ABORT_VALUE_LOW);
    f = sdo(0x2B, obj, 0, 0x1234);   /* 2 bytes for a 4-byte object */
    expect_abort(&f, MC_SDO_ABORT_LENGTH_LOW);
    /* an INIT-only parameter is read-only on the bus */
    const int ts = mc_param_find("control.ts_s");
    f = sdo(0x23, (uint16_t)(0x2000 + ts), 0, mc_f32_bits(1e-4f));
    expect_abort(&f, MC_SDO_ABORT_READ_ONLY);
    /* a STANDSTILL parameter while the outputs are on: not in the present state */
    const int rs = mc_param_find("motor.rs_ohm");
    drive_inputs(300.0f);
    drive_run(3, true);
    assert_true(mc_drive_state(&rig.d) != MC_STATE_IDLE);
    f = sdo(0x23, (uint16_t)(0x2000 + rs), 0, mc_f32_bits(0.5f));
    expect_abort(&f, MC_SDO_ABORT_STATE);
    drive_run(1, false);
    /* an integer parameter as INTEGER32 */
    const int lines = mc_param_find("hw.encoder_lines");
    f = sdo(0x40, (uint16_t)(0x2000 + lines), 0, 0);
    assert_int_equal((int32_t)word(&f), (int32_t)mc_param_get(mc_drive_params(&rig.d), lines));
}

static void test_sdo_aborts(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    (void)take(&f);
    f = sdo(0x40, 0x6789, 0, 0);
    expect_abort(&f, MC_SDO_ABORT_NO_OBJECT);
    f = sdo(0x40, 0x1018, 9, 0);
    expect_abort(&f, MC_SDO_ABORT_NO_SUB);
    f = sdo(0x40, (uint16_t)(0x2000 + MC_PARAM_COUNT), 0, 0);
    expect_abort(&f, MC_SDO_ABORT_NO_OBJECT);
    f = sdo(0x23, 0x1000, 0, 1);
    expect_abort(&f, MC_SDO_ABORT_READ_ONLY);
    f = sdo(0xE0, 0x1000, 0, 0);   /* ccs 7 */
    expect_abort(&f, MC_SDO_ABORT_CS);
    f = sdo(0x60, 0, 0, 0);        /* an upload segment with no transfer */
    expect_abort(&f, MC_SDO_ABORT_CS);
    /* 0x1017 is writable: the heartbeat follows */
    f = sdo(0x2B, 0x1017, 0, 50);
    assert_int_equal(f.data[0], 0x60u);
    f = sdo(0x40, 0x1017, 0, 0);
    assert_int_equal(f.data[0], 0x4Bu);
    assert_int_equal(word(&f), 50u);
}

static void test_segmented_download(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    (void)take(&f);
    /* 0x1017 (2 bytes) written segmented: initiate with size, one last segment */
    f = sdo(0x21, 0x1017, 0, 2);
    assert_int_equal(f.data[0], 0x60u);
    const uint8_t seg[8] = {(uint8_t)(0x00 | (5u << 1) | 1u), 0x2C, 0x01, 0, 0, 0, 0, 0};   /* 300 ms, last */
    put(0x605u, seg, 8u);
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.data[0], 0x20u);
    f = sdo(0x40, 0x1017, 0, 0);
    assert_int_equal(word(&f), 300u);
}

/* A segmented download whose initiate does not indicate the size (s = 0, §7.2.4.3.3) is taken at
 * whatever length the segments bring; one that indicates a size the segments do not match is
 * aborted "length does not match" and the object keeps its value. */
static void test_segmented_download_size(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    (void)take(&f);
    const uint8_t seg[8] = {(uint8_t)((5u << 1) | 1u), 0xF4, 0x01, 0, 0, 0, 0, 0};   /* 500 ms, last */
    f = sdo(0x20, 0x1017, 0, 0);   /* size not indicated */
    assert_int_equal(f.data[0], 0x60u);
    put(0x605u, seg, 8u);
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.data[0], 0x20u);
    f = sdo(0x40, 0x1017, 0, 0);
    assert_int_equal(word(&f), 500u);
    /* 4 bytes announced, 2 sent */
    f = sdo(0x21, 0x1017, 0, 4);
    assert_int_equal(f.data[0], 0x60u);
    const uint8_t seg2[8] = {(uint8_t)((5u << 1) | 1u), 0x2C, 0x01, 0, 0, 0, 0, 0};
    put(0x605u, seg2, 8u);
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    expect_abort(&f, MC_SDO_ABORT_LENGTH);
    f = sdo(0x40, 0x1017, 0, 0);
    assert_int_equal(word(&f), 500u);
}

/* The heartbeat's state byte after the next heartbeat period. */
static uint8_t heartbeat_state(void)
{
    rig.now += 100;
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take_id(0x705u, &f));
    drain();
    return f.data[0];
}

/* NMT "enter pre-operational" (0x80, §7.2.8.3.2.2), addressed to this node or broadcast, takes an
 * operational node back to pre-operational (heartbeat 0x7F), where SDO still answers. */
static void test_nmt_enter_pre_operational(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    drain();
    assert_int_equal(heartbeat_state(), 0x7Fu);
    for (uint8_t node = 0u; node <= NODE; node = (uint8_t)(node + NODE)) {
        nmt(0x01u);
        assert_int_equal(heartbeat_state(), 0x05u);
        const uint8_t pre[2] = {0x80u, node};
        put(0x000u, pre, 2u);
        assert_int_equal(heartbeat_state(), 0x7Fu);
        const hal_can_frame_t f = sdo(0x40, 0x1017, 0, 0);
        assert_int_equal(f.data[0], 0x4Bu);
        assert_int_equal(word(&f), 100u);
    }
    /* an unknown command specifier changes nothing */
    const uint8_t unknown[2] = {0x00u, NODE};
    put(0x000u, unknown, 2u);
    assert_int_equal(heartbeat_state(), 0x7Fu);
    nmt(0x01u);
    put(0x000u, unknown, 2u);
    assert_int_equal(heartbeat_state(), 0x05u);
}

static void drive_run(int n, bool enable)
{
    const mc_drive_cmd_t c = {.enable = enable, .mode = MC_MODE_CURRENT};
    mc_drive_command(&rig.d, &c);
    for (int k = 0; k < n; ++k) {
        hal_host_pwm_latch(&rig.pwm);
        mc_drive_isr(&rig.d);
    }
}

static void test_emcy_on_fault(void **state)
{
    (void)state;
    rig_init_co();
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    (void)take(&f);   /* boot-up */
    drive_inputs(300.0f);
    drive_run((int)rig.d.cfg->p.control_offset_cal_samples + 2, true);
    mc_co_step(&rig.co, rig.now);
    assert_false(take(&f));   /* no fault, no EMCY */
    drive_inputs(rig.d.cfg->p.control_vdc_max_v + 20.0f);
    drive_run(1, true);
    assert_true(mc_drive_faults(&rig.d) & MC_FAULT_OVERVOLTAGE);
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.id, 0x085u);
    assert_int_equal(f.dlc, 8u);
    assert_int_equal(f.data[0] | (f.data[1] << 8), 0x3210);   /* DC link over-voltage */
    assert_int_equal(f.data[2], 0x05u);                        /* generic + voltage */
    assert_int_equal(f.data[3], 1u);                           /* MC_FAULT_OVERVOLTAGE's bit */
    assert_false(take(&f));   /* once */
    mc_co_step(&rig.co, rig.now);
    assert_false(take(&f));
    f = sdo(0x40, 0x1001, 0, 0);
    assert_int_equal(f.data[4], 0x05u);
    f = sdo(0x40, 0x1003, 0, 0);
    assert_int_equal(f.data[4], 1u);
    f = sdo(0x40, 0x1003, 1, 0);
    assert_int_equal(word(&f), 0x3210u | (1u << 16));
    f = sdo(0x40, 0x1003, 2, 0);   /* an empty entry reads 0 */
    assert_int_equal(word(&f), 0u);
    f = sdo(0x40, 0x1003, 9, 0);
    expect_abort(&f, MC_SDO_ABORT_NO_SUB);
    /* disable and enable: the fault clears, EMCY "error reset" */
    drive_inputs(300.0f);
    drive_run(2, false);
    drive_run(2, true);
    assert_int_equal(mc_drive_faults(&rig.d), 0u);
    mc_co_step(&rig.co, rig.now);
    assert_true(take(&f));
    assert_int_equal(f.id, 0x085u);
    assert_int_equal(f.data[0] | f.data[1] | f.data[2], 0);
    /* 0x1003 cleared by writing 0 */
    f = sdo(0x2F, 0x1003, 0, 0);
    assert_int_equal(f.data[0], 0x60u);
    f = sdo(0x40, 0x1003, 0, 0);
    assert_int_equal(f.data[4], 0u);
    assert_int_equal(mc_co_emcy_code(11u), 0x7300u);   /* loss of lock: the angle's plausibility */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_node_id_checked),
        cmocka_unit_test(test_boot_heartbeat_nmt),
        cmocka_unit_test(test_sdo_expedited_and_segmented_upload),
        cmocka_unit_test(test_sdo_parameters),
        cmocka_unit_test(test_sdo_aborts),
        cmocka_unit_test(test_segmented_download),
        cmocka_unit_test(test_emcy_on_fault),
        cmocka_unit_test(test_segmented_download_size),
        cmocka_unit_test(test_nmt_enter_pre_operational),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
