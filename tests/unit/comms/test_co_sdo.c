/* The SDO server and the NMT slave byte by byte (CiA 301 §7.2.4.3, §7.2.8.3): every response's
 * eight bytes (command specifier, index, sub-index, size or data, reserved bytes 0), the
 * segmented transfers' toggle and length bits, the client's abort, the transfer timeout at its
 * edge, frames the server must not answer, the receive budget per step, the heartbeat's
 * schedule from the boot-up, and the 402 ramps' floor for a heavy rotor. */
#include "rig.h"

static void expect_frame(const hal_can_frame_t *f, const uint8_t want[8])
{
    assert_int_equal(f->id, 0x580u + NODE);
    assert_int_equal(f->dlc, 8u);
    if (memcmp(f->data, want, 8) != 0) {
        fail_msg("SDO response %02X %02X %02X %02X %02X %02X %02X %02X, want %02X %02X %02X %02X %02X %02X %02X %02X",
                 f->data[0], f->data[1], f->data[2], f->data[3], f->data[4], f->data[5], f->data[6], f->data[7],
                 want[0], want[1], want[2], want[3], want[4], want[5], want[6], want[7]);
    }
}

/* A raw request (8 bytes), one step; the SDO responses it produced. */
static uint32_t request(const uint8_t r[8], hal_can_frame_t *f)
{
    put(0x600u + NODE, r, 8u);
    mc_co_step(&rig.co, rig.now);
    uint32_t n = 0u;
    hal_can_frame_t g;
    while (take_any(&g)) {
        if (g.id == 0x580u + NODE) {
            *f = g;
            ++n;
        }
    }
    return n;
}

static void expect_response(const uint8_t r[8], const uint8_t want[8])
{
    hal_can_frame_t f;
    assert_int_equal(request(r, &f), 1u);
    expect_frame(&f, want);
}

static void expect_abort(uint8_t cmd, uint16_t index, uint8_t sub, uint32_t code)
{
    const uint8_t r[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0};
    const uint8_t want[8] = {0x80, (uint8_t)index, (uint8_t)(index >> 8), sub,
                             (uint8_t)code, (uint8_t)(code >> 8), (uint8_t)(code >> 16), (uint8_t)(code >> 24)};
    expect_response(r, want);
}

/* Expedited transfers: upload of 1, 2 and 4 bytes (e = s = 1, n = 4 - length), download with and
 * without the size, the confirmation echoing index and sub-index, aborts with the code. */
static void test_expedited_frames(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drain();
    expect_response((const uint8_t[8]){0x40, 0x01, 0x10, 0x00, 0xAA, 0xBB, 0xCC, 0xDD},
                    (const uint8_t[8]){0x4F, 0x01, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});   /* error register 0 */
    /* heartbeat: 2 bytes, written as 2 bytes (n = 2), as 4 (s = 0) */
    expect_response((const uint8_t[8]){0x2B, 0x17, 0x10, 0x00, 0x34, 0x12, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x17, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_response((const uint8_t[8]){0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x4B, 0x17, 0x10, 0x00, 0x34, 0x12, 0x00, 0x00});
    expect_response((const uint8_t[8]){0x22, 0x17, 0x10, 0x00, 0x78, 0x56, 0x00, 0x00},
                    (const uint8_t[8]){0x80, 0x17, 0x10, 0x00, 0x12, 0x00, 0x07, 0x06});   /* 4 bytes: too long */
    expect_response((const uint8_t[8]){0x2F, 0x17, 0x10, 0x00, 0x78, 0x56, 0x00, 0x00},
                    (const uint8_t[8]){0x80, 0x17, 0x10, 0x00, 0x13, 0x00, 0x07, 0x06});   /* 1 byte: too short */
    assert_int_equal(MC_SDO_ABORT_LENGTH_HIGH, 0x06070012u);
    assert_int_equal(MC_SDO_ABORT_LENGTH_LOW, 0x06070013u);
    /* COB-ID SYNC: 4 bytes, e = 1 s = 0 */
    expect_response((const uint8_t[8]){0x22, 0x05, 0x10, 0x00, 0x81, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_response((const uint8_t[8]){0x40, 0x05, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x43, 0x05, 0x10, 0x00, 0x81, 0x00, 0x00, 0x00});
    /* modes of operation (1 byte) in index 0x6060: the index's high byte differs from its low one */
    expect_response((const uint8_t[8]){0x2F, 0x60, 0x60, 0x00, 0x09, 0, 0, 0},
                    (const uint8_t[8]){0x60, 0x60, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_abort(0x40, 0x1234, 0x00, MC_SDO_ABORT_NO_OBJECT);
    expect_abort(0x40, 0x1017, 0x01, MC_SDO_ABORT_NO_SUB);
    expect_abort(0x23, 0x1000, 0x00, MC_SDO_ABORT_READ_ONLY);
}

/* Segmented upload of the device name (0x1008): the initiate gives the size, segments carry 7
 * bytes with the toggle the client sent and n = 7 - bytes, the last with c = 1; then the
 * transfer is over. A wrong toggle aborts, an upload segment without a transfer too. */
static void test_segmented_upload(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drain();
    uint8_t name[MC_CO_SDO_BUF];
    uint32_t len = 0u;
    assert_int_equal(mc_co_od_read(&rig.co, 0x1008u, 0u, name, sizeof name, &len), 0u);
    assert_true(len > 7u && len <= MC_CO_SDO_BUF);
    expect_response((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x41, 0x08, 0x10, 0x00, (uint8_t)len, 0x00, 0x00, 0x00});
    uint32_t pos = 0u;
    uint8_t t = 0u;
    while (pos < len) {
        const uint32_t n = len - pos > 7u ? 7u : len - pos;
        const bool last = pos + n == len;
        uint8_t want[8] = {(uint8_t)((t << 4) | ((7u - n) << 1) | (last ? 1u : 0u)), 0, 0, 0, 0, 0, 0, 0};
        memcpy(want + 1, name + pos, n);
        expect_response((const uint8_t[8]){(uint8_t)(0x60u | (t << 4)), 0, 0, 0, 0, 0, 0, 0}, want);
        pos += n;
        t ^= 1u;
    }
    assert_false(rig.co.sdo.active);
    expect_abort(0x60, 0x1008, 0x00, MC_SDO_ABORT_CS);   /* the transfer is over */
    /* a wrong toggle on the second segment */
    expect_response((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x41, 0x08, 0x10, 0x00, (uint8_t)len, 0x00, 0x00, 0x00});
    hal_can_frame_t f;
    assert_int_equal(request((const uint8_t[8]){0x60, 0, 0, 0, 0, 0, 0, 0}, &f), 1u);
    assert_int_equal(f.data[0], 0x00u);
    expect_abort(0x60, 0x1008, 0x00, MC_SDO_ABORT_TOGGLE);
    assert_false(rig.co.sdo.active);
    /* a download segment in an upload: wrong command */
    expect_response((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x41, 0x08, 0x10, 0x00, (uint8_t)len, 0x00, 0x00, 0x00});
    expect_abort(0x00, 0x1008, 0x00, MC_SDO_ABORT_CS);
}

/* Segmented download of the COB-ID SYNC (4 bytes) in two segments of 3 and 1 bytes (n = 4, n = 6):
 * each confirmed with ccs 1 and its toggle, the reserved bytes 0; the value taken at the last. */
static void test_segmented_download(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drain();
    expect_response((const uint8_t[8]){0x21, 0x05, 0x10, 0x00, 0x04, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_response((const uint8_t[8]){(uint8_t)(4u << 1), 0x82, 0x00, 0x00, 0xEE, 0xEE, 0xEE, 0xEE},
                    (const uint8_t[8]){0x20, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    assert_int_equal(rig.co.cob_sync, 0x080u);   /* not before the last segment */
    expect_response((const uint8_t[8]){(uint8_t)(0x10u | (6u << 1) | 1u), 0x00, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE},
                    (const uint8_t[8]){0x30, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    assert_int_equal(rig.co.cob_sync, 0x082u);
    assert_false(rig.co.sdo.active);
    expect_abort(0x00, 0x1005, 0x00, MC_SDO_ABORT_CS);   /* the transfer is over */
    /* 7 bytes in one segment (n = 0) for a 4-byte object: refused at the end as too long */
    expect_response((const uint8_t[8]){0x20, 0x05, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_abort(0x01, 0x1005, 0x00, MC_SDO_ABORT_LENGTH_HIGH);
    assert_int_equal(rig.co.cob_sync, 0x082u);
    /* the announced size: the buffer's exactly is taken, one more is refused at once */
    expect_response((const uint8_t[8]){0x21, 0x05, 0x10, 0x00, MC_CO_SDO_BUF, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_response((const uint8_t[8]){0x21, 0x05, 0x10, 0x00, MC_CO_SDO_BUF + 1u, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x80, 0x05, 0x10, 0x00, 0x12, 0x00, 0x07, 0x06});
    assert_false(rig.co.sdo.active);
    /* more segments than the buffer holds: 4 x 7 + 4 = 32 bytes taken, one more is too long */
    expect_response((const uint8_t[8]){0x20, 0x05, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    for (uint8_t k = 0u; k < 4u; ++k) {
        const uint8_t t = (uint8_t)((k & 1u) << 4);
        expect_response((const uint8_t[8]){t, 1, 2, 3, 4, 5, 6, 7},
                        (const uint8_t[8]){(uint8_t)(0x20u | t), 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    }
    expect_response((const uint8_t[8]){(uint8_t)(3u << 1), 1, 2, 3, 4, 0, 0, 0},
                    (const uint8_t[8]){0x20, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    assert_int_equal(rig.co.sdo.len, MC_CO_SDO_BUF);
    expect_abort(0x10 | (6u << 1), 0x1005, 0x00, MC_SDO_ABORT_LENGTH_HIGH);
    assert_false(rig.co.sdo.active);
    /* a wrong toggle aborts */
    expect_response((const uint8_t[8]){0x21, 0x05, 0x10, 0x00, 0x04, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_abort(0x10 | (3u << 1), 0x1005, 0x00, MC_SDO_ABORT_TOGGLE);
    assert_false(rig.co.sdo.active);
    /* a segmented download of a read-only object or one that does not exist: refused at the initiate */
    expect_abort(0x21, 0x1000, 0x00, MC_SDO_ABORT_READ_ONLY);
    expect_abort(0x21, 0x1234, 0x00, MC_SDO_ABORT_NO_OBJECT);
    expect_abort(0x21, 0x1017, 0x05, MC_SDO_ABORT_NO_SUB);
}

/* The client's abort (ccs 4) ends the transfer without an answer; a new initiate ends an
 * unfinished one; ccs 5..7 are no command. Frames the server does not answer: fewer than 8
 * bytes, an extended or remote frame with its id, any request in STOPPED. */
static void test_abort_and_silence(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drain();
    hal_can_frame_t f;
    assert_int_equal(request((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}, &f), 1u);
    assert_int_equal(f.data[0], 0x41u);
    assert_true(rig.co.sdo.active);
    assert_int_equal(request((const uint8_t[8]){0x80, 0x08, 0x10, 0x00, 0, 0, 0, 0}, &f), 0u);
    assert_false(rig.co.sdo.active);
    expect_abort(0x60, 0x1008, 0x00, MC_SDO_ABORT_CS);
    /* a new initiate in the middle of an upload: answered as new */
    (void)request((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}, &f);
    expect_response((const uint8_t[8]){0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0},
                    (const uint8_t[8]){0x4B, 0x17, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    assert_false(rig.co.sdo.active);
    for (uint8_t ccs = 5u; ccs <= 7u; ++ccs) {
        expect_abort((uint8_t)(ccs << 5), 0x1017, 0x00, MC_SDO_ABORT_CS);
    }
    /* not answered */
    const uint8_t r[8] = {0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0};
    for (uint8_t dlc = 0u; dlc < 8u; ++dlc) {
        put(0x600u + NODE, r, dlc);
        mc_co_step(&rig.co, rig.now);
        assert_false(take_id(0x580u + NODE, &f));
    }
    hal_can_frame_t x = {.id = 0x600u + NODE, .ext = true, .dlc = 8u};
    memcpy(x.data, r, 8);
    assert_true(hal_host_can_deliver(&rig.can, &x));
    x.ext = false;
    x.rtr = true;
    assert_true(hal_host_can_deliver(&rig.can, &x));
    mc_co_step(&rig.co, rig.now);
    assert_false(take_id(0x580u + NODE, &f));
    /* another node's SDO */
    put(0x600u + NODE + 1u, r, 8u);
    mc_co_step(&rig.co, rig.now);
    assert_false(take_id(0x580u + NODE, &f));
    assert_false(take_id(0x580u + NODE + 1u, &f));
    /* STOPPED: a transfer in progress ends, nothing answered; back in pre-operational it is gone */
    (void)request((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}, &f);
    assert_true(rig.co.sdo.active);
    nmt(0x02);
    assert_false(rig.co.sdo.active);
    assert_int_equal(request(r, &f), 0u);
    nmt(0x80);
    expect_abort(0x60, 0x1008, 0x00, MC_SDO_ABORT_CS);
}

/* A transfer the client leaves: aborted with TIMEOUT once more than MC_CO_SDO_TIMEOUT_MS have
 * passed since its last frame, not at that time itself; every segment restarts the time. */
static void test_sdo_timeout_edge(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    rig.now = 5000u;
    mc_co_step(&rig.co, rig.now);
    drain();
    hal_can_frame_t f;
    (void)request((const uint8_t[8]){0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}, &f);
    rig.now += MC_CO_SDO_TIMEOUT_MS;
    mc_co_step(&rig.co, rig.now);
    assert_false(take_id(0x580u + NODE, &f));
    assert_int_equal(request((const uint8_t[8]){0x60, 0, 0, 0, 0, 0, 0, 0}, &f), 1u);   /* a segment at 1000 ms */
    assert_int_equal(f.data[0] & 0xE0u, 0x00u);
    rig.now += MC_CO_SDO_TIMEOUT_MS;
    mc_co_step(&rig.co, rig.now);
    assert_false(take_id(0x580u + NODE, &f));
    rig.now += 1u;
    mc_co_step(&rig.co, rig.now);
    assert_true(take_id(0x580u + NODE, &f));
    assert_int_equal(f.data[0], 0x80u);
    assert_int_equal(f.data[1] | (f.data[2] << 8), 0x1008);
    assert_int_equal(word(&f), MC_SDO_ABORT_TIMEOUT);
    assert_false(rig.co.sdo.active);
    rig.now += 5000u;
    mc_co_step(&rig.co, rig.now);
    assert_false(take_id(0x580u + NODE, &f));   /* once */
}

/* At most MC_CO_RX_PER_STEP frames per step: 20 requests are answered 16 and 4. */
static void test_rx_budget(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    mc_co_step(&rig.co, rig.now);
    drain();
    const uint8_t r[8] = {0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0};
    for (int k = 0; k < 20; ++k) {
        put(0x600u + NODE, r, 8u);
    }
    uint32_t n[2] = {0u, 0u};
    for (int s = 0; s < 2; ++s) {
        mc_co_step(&rig.co, rig.now);
        hal_can_frame_t f;
        while (take_any(&f)) {
            n[s] += f.id == 0x580u + NODE;
        }
    }
    assert_int_equal(n[0], MC_CO_RX_PER_STEP);
    assert_int_equal(n[1], 20u - MC_CO_RX_PER_STEP);
}

/* The heartbeat counts from the boot-up: booted at 1000 ms with 100 ms, the first heartbeat goes
 * at 1100 ms, then every 100 ms, with the NMT state; NMT commands to other nodes or with another
 * length change nothing. */
static void test_heartbeat_schedule(void **state)
{
    (void)state;
    memset(&rig, 0, sizeof rig);
    hal_host_nvm_init(&rig.nvm);
    mc_drive_cfg_default(&rig.cfg);
    const mc_co_cfg_t c = {.node_id = NODE, .heartbeat_ms = 100, .step_s = 1e-3f};
    rig_start_cfg(&c, MC_PSTORE_EMPTY);
    rig.co.ds_on = false;
    hal_can_frame_t f;
    mc_co_step(&rig.co, 1000u);
    assert_true(take_any(&f));
    assert_int_equal(f.id, 0x700u + NODE);
    assert_int_equal(f.data[0], 0x00u);   /* boot-up */
    assert_false(take_any(&f));
    mc_co_step(&rig.co, 1099u);
    assert_false(take_any(&f));
    mc_co_step(&rig.co, 1100u);
    assert_true(take_any(&f));
    assert_int_equal(f.id, 0x700u + NODE);
    assert_int_equal(f.data[0], 0x7Fu);
    assert_int_equal(f.dlc, 1u);
    mc_co_step(&rig.co, 1199u);
    assert_false(take_any(&f));
    /* NMT: wrong length, another node: ignored */
    const uint8_t go[3] = {0x01, NODE, 0x00};
    put(0x000u, go, 3u);
    put(0x000u, go, 1u);
    const uint8_t other[2] = {0x01, NODE + 1u};
    put(0x000u, other, 2u);
    mc_co_step(&rig.co, 1200u);
    assert_true(take_id(0x700u + NODE, &f));
    assert_int_equal(f.data[0], 0x7Fu);
    const uint8_t all[2] = {0x01, 0x00};
    put(0x000u, all, 2u);
    mc_co_step(&rig.co, 1250u);
    mc_co_step(&rig.co, 1300u);
    assert_true(take_id(0x700u + NODE, &f));
    assert_int_equal(f.data[0], 0x05u);
    const uint8_t stop[2] = {0x02, NODE};
    put(0x000u, stop, 2u);
    mc_co_step(&rig.co, 1400u);
    assert_true(take_id(0x700u + NODE, &f));
    assert_int_equal(f.data[0], 0x04u);
}

/* The 402 ramps' default acceleration: 5 % of the rated torque on the inertia, in rpm/s (1091 on
 * the thesis motor), at least 1 rpm/s for a rotor too heavy for that (50 kg m^2: 0.28 rpm/s). */
static void test_ramp_floor(void **state)
{
    (void)state;
    rig_init();
    assert_int_equal(rig.co.ds.od.profile_accel, 1091u);   /* 0.05 x 29.7 / 0.013 x 60 / 2pi = 1090.8 */
    memset(&rig, 0, sizeof rig);
    hal_host_nvm_init(&rig.nvm);
    mc_drive_cfg_default(&rig.cfg);
    rig.cfg.p.motor_inertia_kgm2 = 50.0f;
    rig_start(MC_PSTORE_EMPTY);
    assert_int_equal(rig.co.ds.od.profile_accel, 1u);
    assert_int_equal(rig.co.ds.od.profile_decel, 1u);
    assert_int_equal(rig.co.ds.od.quick_stop_decel, 1u);
    memset(&rig, 0, sizeof rig);
    hal_host_nvm_init(&rig.nvm);
    mc_drive_cfg_default(&rig.cfg);
    rig.cfg.p.motor_inertia_kgm2 = 0.0145f;   /* 0.05 x 29.7 / 0.0145 x 60 / 2pi = 978.0 */
    rig_start(MC_PSTORE_EMPTY);
    assert_int_equal(rig.co.ds.od.profile_accel, 978u);
}

/* The 402 layer's configuration follows every parameter it reads, not only the motor's: the
 * under-voltage level (statusword bit 4, voltage enabled) written over SDO takes effect at the
 * next step. */
static void test_402_follows_params(void **state)
{
    (void)state;
    rig_init();
    drain();
    const float vmin = 180.0f;
    uint32_t w;
    memcpy(&w, &vmin, 4);
    expect_response((const uint8_t[8]){0x23, 0x12, 0x20, 0x00, (uint8_t)w, (uint8_t)(w >> 8), (uint8_t)(w >> 16), (uint8_t)(w >> 24)},
                    (const uint8_t[8]){0x60, 0x12, 0x20, 0x00, 0, 0, 0, 0});
    run_ms(2);   /* the drive takes the new set, the 402 layer follows */
    assert_float_equal(rig.co.ds.cfg.vdc_on, vmin, 1e-3f);
    /* and the statusword's voltage-enabled bit with it (the contactor closed by transition 3:
     * controlword 6, then 7): 170 V is below the new level, 190 V above */
    uint32_t abort = 0u;
    drive_inputs(190.0f);
    assert_int_equal(sdo_write(0x6040u, 0u, 0x06u, 2u), 0u);
    run_ms(2);
    assert_int_equal(sdo_write(0x6040u, 0u, 0x07u, 2u), 0u);
    run_ms(2);
    drive_inputs(170.0f);
    run_ms(2);
    assert_int_equal(sdo_read(0x6041u, 0u, &abort) & 0x10u, 0u);
    assert_int_equal(abort, 0u);
    drive_inputs(190.0f);
    run_ms(2);
    assert_int_equal(sdo_read(0x6041u, 0u, &abort) & 0x10u, 0x10u);
    assert_int_equal(abort, 0u);
}

/* The announced size of a segmented download is a 32-bit little-endian number: any byte of it
 * beyond the buffer refuses the transfer at the initiate; a wrong toggle on a later segment
 * aborts; a controlword written segmented counts as one and takes its transition. */
static void test_segmented_download_size_bytes(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    drain();
    static const uint8_t sizes[][4] = {{0x04, 0x01, 0, 0}, {0x04, 0, 0x01, 0}, {0x04, 0, 0, 0x01}, {0x20, 0x80, 0, 0}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k) {
        expect_response((const uint8_t[8]){0x21, 0x05, 0x10, 0x00, sizes[k][0], sizes[k][1], sizes[k][2], sizes[k][3]},
                        (const uint8_t[8]){0x80, 0x05, 0x10, 0x00, 0x12, 0x00, 0x07, 0x06});
    }
    /* the second segment with the first one's toggle */
    expect_response((const uint8_t[8]){0x21, 0x05, 0x10, 0x00, 0x04, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x05, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_response((const uint8_t[8]){(uint8_t)(5u << 1), 0x83, 0x00, 0, 0, 0, 0, 0},
                    (const uint8_t[8]){0x20, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    expect_abort((uint8_t)((5u << 1) | 1u), 0x1005, 0x00, MC_SDO_ABORT_TOGGLE);
    assert_int_equal(rig.co.cob_sync, 0x080u);
    /* the controlword in one segment: one controlword, its transition (shutdown: ready to switch on) */
    nmt(0x01);
    drain();
    const uint32_t cw0 = rig.co.cw_count;
    expect_response((const uint8_t[8]){0x21, 0x40, 0x60, 0x00, 0x02, 0x00, 0x00, 0x00},
                    (const uint8_t[8]){0x60, 0x40, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00});
    assert_int_equal(rig.co.cw_count, cw0);
    expect_response((const uint8_t[8]){(uint8_t)((5u << 1) | 1u), 0x06, 0x00, 0, 0, 0, 0, 0},
                    (const uint8_t[8]){0x20, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    assert_int_equal(rig.co.cw_count, cw0 + 1u);
    assert_int_equal(rig.co.ds.od.statusword & 0x6Fu, 0x21u);   /* ready to switch on */
}

/* The step period the 402 ramps integrate must lie in (0, 1) s. */
static void test_step_period_range(void **state)
{
    (void)state;
    rig_init();
    static const float bad[] = {0.0f, -1e-3f, 1.0f, 1.5f, NAN, INFINITY};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        const mc_co_cfg_t c = {.node_id = NODE, .step_s = bad[k]};
        mc_co_t co;
        assert_false(mc_co_init(&co, &c, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    }
    const mc_co_cfg_t c = {.node_id = NODE, .step_s = 0.999f};
    mc_co_t co;
    assert_true(mc_co_init(&co, &c, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    assert_false(mc_co_init(&co, NULL, &rig.can, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    assert_false(mc_co_init(&co, &c, NULL, &rig.d, NULL, NULL, MC_PSTORE_EMPTY));
    assert_false(mc_co_init(&co, &c, &rig.can, NULL, NULL, NULL, MC_PSTORE_EMPTY));
}

/* A reset in a batch of frames: the frames after it wait for the next step, so the boot-up goes
 * out before their answers (CiA 301 §7.2.8.3.2: nothing before the boot-up). */
static void test_reset_ends_the_batch(void **state)
{
    (void)state;
    rig_init();
    rig.co.ds_on = false;
    mc_co_step(&rig.co, rig.now);
    drain();
    const uint8_t reset[2] = {0x82, NODE};
    put(0x000u, reset, 2u);
    const uint8_t r[8] = {0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0};
    put(0x600u + NODE, r, 8u);
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_false(take_any(&f));   /* the reset's step ends there */
    mc_co_step(&rig.co, rig.now);
    assert_true(take_any(&f));
    assert_int_equal(f.id, 0x700u + NODE);
    assert_int_equal(f.data[0], 0x00u);
    assert_true(take_any(&f));
    assert_int_equal(f.id, 0x580u + NODE);
    assert_int_equal(f.data[0], 0x4Bu);
}

/* The boot's EMCY "parameters lost": for a corrupt store or a failing NVM the status in the first
 * manufacturer byte, the rest 0; for a partly kept set the count of values at their defaults,
 * at most 255. */
static void test_boot_emcy_info(void **state)
{
    (void)state;
    static const mc_pstore_status_t src[] = {MC_PSTORE_CORRUPT, MC_PSTORE_NVM_ERROR};
    for (size_t k = 0; k < 2; ++k) {
        rig_init();
        rig_start(src[k]);
        mc_co_step(&rig.co, rig.now);
        hal_can_frame_t f;
        assert_true(take_id(0x080u + NODE, &f));
        const uint8_t want[8] = {0x10, 0x63, 0x01, (uint8_t)src[k], 0, 0, 0, 0};
        assert_memory_equal(f.data, want, 8);
    }
    rig_init();
    rig_start(MC_PSTORE_PARTIAL);
    const mc_store_report_t rep = {.kept = 3u, .dropped = 300u, .first = 0x123, .reason = MC_STORE_DROP_RANGE};
    mc_co_set_boot_report(&rig.co, &rep);
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take_id(0x080u + NODE, &f));
    const uint8_t want[8] = {0x10, 0x63, 0x01, (uint8_t)MC_PSTORE_PARTIAL, 255u, 0x23, 0x01, MC_STORE_DROP_RANGE};
    assert_memory_equal(f.data, want, 8);
    /* no NVM at all: the base configuration, "empty" */
    static mc_drive_cfg_t base, out;
    static mc_flux_map_t map;
    mc_drive_cfg_default(&base);
    base.p.control_current_bw_hz = 321.0f;
    memset(&out, 0xA5, sizeof out);
    mc_store_report_t r2;
    assert_int_equal(mc_co_boot_config(NULL, &base, &out, &map, &r2), MC_PSTORE_EMPTY);
    assert_true(out.p.control_current_bw_hz == 321.0f);
    assert_int_equal(r2.dropped, 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_expedited_frames),
        cmocka_unit_test(test_segmented_upload),
        cmocka_unit_test(test_segmented_download),
        cmocka_unit_test(test_abort_and_silence),
        cmocka_unit_test(test_sdo_timeout_edge),
        cmocka_unit_test(test_rx_budget),
        cmocka_unit_test(test_heartbeat_schedule),
        cmocka_unit_test(test_ramp_floor),
        cmocka_unit_test(test_402_follows_params),
        cmocka_unit_test(test_segmented_download_size_bytes),
        cmocka_unit_test(test_step_period_range),
        cmocka_unit_test(test_reset_ends_the_batch),
        cmocka_unit_test(test_boot_emcy_info),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
