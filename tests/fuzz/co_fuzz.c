/* Fuzz target for the CANopen device (mc/co.h) on a real drive over the host HAL: arbitrary bytes
 * become a sequence of operations - CAN frames (biased toward what the device answers: NMT, SYNC,
 * RPDOs, SDO requests with plausible command specifiers, indices and sub-indices), time passing
 * (the drive's ISR, its background and the device's step, as the simulator runs them), the TX
 * queue drained, the DC link and currents changed - and after every operation the invariants are
 * checked; a violation aborts (the fuzzer reports it, with ASan / UBSan watching the memory and
 * the arithmetic):
 *   - every parameter in force finite and within its table range;
 *   - the drive's state, the NMT state, the CiA 402 state and the scope's state within their enums;
 *   - the duties finite; no non-finite duty ever counted by the PWM;
 *   - every frame the device sends valid, 11-bit, on an identifier it may use (EMCY, SDO response,
 *     heartbeat, or one of its TPDOs' COB-IDs).
 * libFuzzer's entry point; co_fuzz_main.c drives it without libFuzzer (gcc builds, CI). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/co.h"

#define NODE 1u
#define MAX_MS 200u   /* simulated time per input */

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    hal_can_t can;
    hal_nvm_t nvm;
    mc_drive_cfg_t cfg;
    mc_drive_t d;
    mc_drive_link_t link;
    mc_scope_t scope;
    mc_co_t co;
    uint32_t now, ms;
} rig_t;

static rig_t R;
static uint32_t cob_before[MC_CO_PDO_N];   /* the TPDO COB-IDs before the last step: a frame sent
                                              before a reset in the same step used them */
static float scope_buf[512];   /* its own object: ASan's redzones around it */
uint64_t co_fuzz_frames;   /* frames delivered, for the drivers' reports */
/* Inputs that reached a deep state (the report shows the campaign is not stuck at the surface):
 * 0 NMT operational, 1 CiA 402 operation enabled, 2 the drive in RUN, 3 a drive fault, 4 the scope
 * done, 5 a store committed, 6 an RPDO applied, 7 a TPDO remapped (not the default COB-ID). */
uint64_t co_fuzz_reached[8];
static uint32_t reached;

#include <stdio.h>
static void check_at(int ok, const char *what, int line)
{
    if (!ok) {
        fprintf(stderr, "co_fuzz: invariant violated (line %d): %s\n", line, what);
        abort();
    }
}
#define check(x) check_at((x) ? 1 : 0, #x, __LINE__)

static void invariants(void)
{
    const mc_params_t *p = mc_drive_params(&R.d);
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const float v = mc_param_get(p, id);
        check(isfinite(v) && v >= mc_param_table[id].min && v <= mc_param_table[id].max);
    }
    const mc_state_t st = mc_drive_state(&R.d);
    check(st >= MC_STATE_IDLE && st <= MC_STATE_FAULT_REACTION);
    check(R.co.nmt == MC_NMT_INITIALISING || R.co.nmt == MC_NMT_STOPPED || R.co.nmt == MC_NMT_OPERATIONAL ||
          R.co.nmt == MC_NMT_PRE_OPERATIONAL);
    check(R.co.ds.state >= MC_402_NOT_READY && R.co.ds.state <= MC_402_FAULT);
    check(mc_scope_state(&R.scope) <= MC_SCOPE_DONE);
    for (int k = 0; k < 3; ++k) {
        check(isfinite(R.pwm.shadow[k]) && isfinite(R.pwm.active[k]));
    }
    check(R.pwm.nonfinite == 0u);
    reached |= (R.co.nmt == MC_NMT_OPERATIONAL ? 1u : 0u) | (R.co.ds.state == MC_402_OPERATION_ENABLED ? 2u : 0u) |
               (st == MC_STATE_RUN ? 4u : 0u) | (st == MC_STATE_FAULT ? 8u : 0u) |
               (mc_scope_state(&R.scope) == MC_SCOPE_DONE ? 16u : 0u) | (R.nvm.steps > 0u ? 32u : 0u) |
               (R.co.rpdo_rx > 0u ? 64u : 0u) | ((R.co.tpdo[1].cob_id & 0x7FFu) != 0x280u + NODE ? 128u : 0u);
}

static void drain(void)
{
    hal_can_frame_t f;
    while (hal_host_can_take(&R.can, &f)) {
        check(hal_can_frame_valid(&f) && !f.ext && f.dlc <= 8u);
        bool ok = f.id == 0x080u + NODE || f.id == 0x580u + NODE || f.id == 0x700u + NODE;
        for (uint32_t k = 0; k < MC_CO_PDO_N; ++k) {
            ok = ok || f.id == (R.co.tpdo[k].cob_id & 0x7FFu) || f.id == (cob_before[k] & 0x7FFu);
        }
        if (!ok) {
            fprintf(stderr, "co_fuzz: a frame on 0x%03X (dlc %u), TPDO COB-IDs 0x%08X 0x%08X 0x%08X 0x%08X\n",
                    (unsigned)f.id, (unsigned)f.dlc, (unsigned)R.co.tpdo[0].cob_id, (unsigned)R.co.tpdo[1].cob_id,
                    (unsigned)R.co.tpdo[2].cob_id, (unsigned)R.co.tpdo[3].cob_id);
        }
        check(ok);
    }
}

static void co_step(void)
{
    for (uint32_t k = 0; k < MC_CO_PDO_N; ++k) {
        cob_before[k] = R.co.tpdo[k].cob_id;
    }
    mc_co_step(&R.co, R.now);
}

static void set_inputs(uint8_t sel)
{
    const mc_drive_blk_t *b = &R.d.cfg->blk;
    static const float vdc[4] = {300.0f, 0.0f, 480.0f, 200.0f};
    for (int k = 0; k < 3; ++k) {
        R.adc.sample.i[k] = (uint16_t)(b->offs.nominal + 0.5f) + (uint16_t)((sel >> 2) & 1u) * (uint16_t)(k * 40);
    }
    R.adc.sample.vdc = (uint16_t)(vdc[sel & 3u] / b->volts_per_count + 0.5f);
}

static void run_ms(uint32_t ms)
{
    for (uint32_t k = 0; k < ms && R.ms < MAX_MS; ++k, ++R.ms) {
        for (int j = 0; j < 10; ++j) {
            hal_host_pwm_latch(&R.pwm);
            mc_drive_isr(&R.d);
            mc_scope_sample(&R.scope, mc_drive_telemetry(&R.d));
        }
        mc_drive_background(&R.d);
        R.now++;
        co_step();
        drain();   /* the TX ring is small: a real bus takes the frames away */
    }
}

static const uint16_t kIndex[] = {
    0x1000, 0x1001, 0x1003, 0x1005, 0x1008, 0x100A, 0x1010, 0x1011, 0x1017, 0x1018, 0x1400, 0x1401, 0x1403,
    0x1600, 0x1601, 0x1603, 0x1800, 0x1801, 0x1803, 0x1A00, 0x1A01, 0x1A03, 0x2000, 0x2008, 0x2012, 0x2018,
    0x2030, 0x2050, 0x2060, 0x2201, 0x2208, 0x2215, 0x2300, 0x2301, 0x2302, 0x2303, 0x2304, 0x2307, 0x2308,
    0x2FF0, 0x2FF1, 0x603F, 0x6040, 0x6041, 0x605A, 0x605B, 0x605C, 0x6060, 0x606C, 0x6071, 0x6072, 0x6080,
    0x6083, 0x6085, 0x6087, 0x60B1, 0x60FF, 0x6502, 0x6789};
static const uint8_t kCs[] = {0x40, 0x2F, 0x2B, 0x27, 0x23, 0x22, 0x21, 0x20, 0x60, 0x70, 0x00, 0x10,
                              0x01, 0x11, 0x0B, 0x80, 0xA0, 0xC0, 0xE0};

/* Bytes -> one value, or 0 when the input has run out. */
typedef struct {
    const uint8_t *p, *end;
} src_t;

static uint8_t next(src_t *s)
{
    return s->p < s->end ? *s->p++ : 0u;
}

static void frame(src_t *s)
{
    hal_can_frame_t f = {0};
    const uint8_t sel = next(s);
    switch (sel % 10u) {
    case 0: f.id = 0x000u; break;
    case 1: f.id = 0x080u; break;
    case 2: f.id = 0x200u + NODE; break;
    case 3: f.id = 0x300u + NODE; break;
    case 4:
    case 5:
    case 6:
    case 7: f.id = 0x600u + NODE; break;
    case 8: f.id = 0x600u + NODE + (sel & 0x10u ? 1u : 0u); break;   /* another node's SDO */
    default: f.id = ((uint32_t)next(s) << 8 | next(s)) & 0x7FFu; break;
    }
    f.dlc = (uint8_t)(next(s) % 9u);
    for (uint32_t k = 0; k < 8u; ++k) {
        f.data[k] = next(s);
    }
    if (f.id == 0x600u + NODE && (sel & 0x80u) == 0u) {
        /* a plausible request: command specifier, index, sub-index from the tables */
        f.dlc = 8u;
        f.data[0] = kCs[f.data[0] % sizeof kCs];
        const uint16_t idx = (uint16_t)(kIndex[f.data[1] % (sizeof kIndex / sizeof kIndex[0])] + (f.data[2] & 0x07u));
        f.data[1] = (uint8_t)idx;
        f.data[2] = (uint8_t)(idx >> 8);
        f.data[3] = (uint8_t)(f.data[3] % 10u);
    } else if (f.id == 0x000u && (sel & 0x80u) == 0u) {
        static const uint8_t cs[5] = {0x01, 0x02, 0x80, 0x81, 0x82};
        f.dlc = 2u;
        f.data[0] = cs[f.data[0] % 5u];
        f.data[1] = (uint8_t)((f.data[1] & 1u) ? NODE : 0u);
    }
    if (hal_can_frame_valid(&f)) {
        (void)hal_host_can_deliver(&R.can, &f);
        co_fuzz_frames++;
    }
}

/* ---- seeds: operation sequences that reach the deep states (a drive in RUN under CiA 402, an
 * armed scope and its upload, a store, a PDO remapped), for the drivers to mutate ---- */

typedef struct {
    uint8_t *b;
    size_t n, cap;
} out_t;

static void emit(out_t *o, uint8_t v)
{
    if (o->n < o->cap) {
        o->b[o->n] = v;
    }
    o->n++;
}

static uint8_t pos_of(const uint8_t *t, size_t n, uint8_t v)
{
    for (size_t k = 0; k < n; ++k) {
        if (t[k] == v) {
            return (uint8_t)k;
        }
    }
    return 0u;
}

/* An SDO request with command specifier cs on (index, sub) carrying v (little-endian). */
static void sdo_op(out_t *o, uint8_t cs, uint16_t index, uint8_t sub, uint32_t v)
{
    uint8_t at = 0u;
    for (size_t k = 0; k < sizeof kIndex / sizeof kIndex[0]; ++k) {
        if (kIndex[k] <= index && index - kIndex[k] < 8u) {
            at = (uint8_t)k;
            break;
        }
    }
    emit(o, 0x84u);   /* a frame (0x84 % 12 = 0), then a step (bit 7) */
    emit(o, 4u);      /* SDO, plausible */
    emit(o, 8u);
    emit(o, pos_of(kCs, sizeof kCs, cs));
    emit(o, at);
    emit(o, (uint8_t)(index - kIndex[at]));
    emit(o, sub);
    for (int k = 0; k < 4; ++k) {
        emit(o, (uint8_t)(v >> (8 * k)));
    }
}

static void nmt_op(out_t *o, uint8_t pos)   /* pos: 0 start, 1 stop, 2 pre-op, 3 reset node, 4 reset comm */
{
    const uint8_t b[11] = {0x84u, 0u, 2u, pos, 1u, 0u, 0u, 0u, 0u, 0u, 0u};
    for (int k = 0; k < 11; ++k) {
        emit(o, b[k]);
    }
}

static void time_op(out_t *o, uint8_t ms)
{
    emit(o, 8u);
    emit(o, (uint8_t)(ms - 1u));
}

size_t co_fuzz_seed(int k, uint8_t *buf, size_t cap);

size_t co_fuzz_seed(int k, uint8_t *buf, size_t cap)
{
    out_t o = {buf, 0u, cap};
    switch (k) {
    case 0:   /* CiA 402 to Operation enabled, a velocity, a quick stop */
        nmt_op(&o, 0u);
        sdo_op(&o, 0x2F, 0x6060, 0, 3u);
        sdo_op(&o, 0x2B, 0x6040, 0, 0x06u);
        sdo_op(&o, 0x2B, 0x6040, 0, 0x07u);
        sdo_op(&o, 0x2B, 0x6040, 0, 0x0Fu);
        for (int j = 0; j < 8; ++j) {
            time_op(&o, 8u);
        }
        sdo_op(&o, 0x23, 0x60FF, 0, 300u);
        for (int j = 0; j < 8; ++j) {
            time_op(&o, 8u);
        }
        sdo_op(&o, 0x2B, 0x6040, 0, 0x02u);
        time_op(&o, 8u);
        sdo_op(&o, 0x2B, 0x6040, 0, 0x80u);
        break;
    case 1:   /* the scope: channels, length, arm, its record uploaded */
        sdo_op(&o, 0x2F, 0x2300, 1, 6u);
        sdo_op(&o, 0x2F, 0x2300, 2, 9u);
        sdo_op(&o, 0x23, 0x2301, 6, 20u);
        sdo_op(&o, 0x2F, 0x2302, 0, 1u);
        time_op(&o, 4u);
        sdo_op(&o, 0x40, 0x2307, 0, 0u);
        for (int j = 0; j < 24; ++j) {
            sdo_op(&o, (j & 1) ? 0x70 : 0x60, 0x1000, 0, 0u);
        }
        break;
    case 2:   /* store and restore */
        sdo_op(&o, 0x23, 0x2018, 0, 0x43960000u);   /* 300.0f */
        time_op(&o, 1u);
        sdo_op(&o, 0x23, 0x1010, 1, MC_CO_SAVE_SIGNATURE);
        sdo_op(&o, 0x23, 0x1011, 1, MC_CO_LOAD_SIGNATURE);
        nmt_op(&o, 3u);
        break;
    case 3:   /* a TPDO remapped, then operational */
        sdo_op(&o, 0x23, 0x1801, 1, 0x80000281u);
        sdo_op(&o, 0x2F, 0x1A01, 0, 0u);
        sdo_op(&o, 0x23, 0x1A01, 1, 0x60410010u);
        sdo_op(&o, 0x23, 0x1A01, 2, 0x22080020u);
        sdo_op(&o, 0x2F, 0x1A01, 0, 2u);
        sdo_op(&o, 0x23, 0x1801, 1, 0x281u);
        sdo_op(&o, 0x2F, 0x1801, 2, 1u);
        nmt_op(&o, 0u);
        for (int j = 0; j < 4; ++j) {
            time_op(&o, 4u);
            const uint8_t sync[11] = {0x84u, 1u, 0u, 0, 0, 0, 0, 0, 0, 0, 0};
            for (int q = 0; q < 11; ++q) {
                emit(&o, sync[q]);
            }
        }
        break;
    case 4: {   /* RPDOs: controlword and mode, then the targets */
        nmt_op(&o, 0u);
        static const uint8_t cws[3] = {0x06, 0x07, 0x0F};
        for (int j = 0; j < 3; ++j) {
            const uint8_t f[11] = {0x84u, 2u, 3u, cws[j], 0u, 3u, 0, 0, 0, 0, 0};
            for (int q = 0; q < 11; ++q) {
                emit(&o, f[q]);
            }
        }
        const uint8_t t[11] = {0x84u, 3u, 6u, 0xF4u, 0x01u, 0u, 0u, 0u, 0u, 0, 0};   /* 500 rpm */
        for (int q = 0; q < 11; ++q) {
            emit(&o, t[q]);
        }
        for (int j = 0; j < 10; ++j) {
            time_op(&o, 8u);
        }
        break;
    }
    case 5:   /* the scope over its whole buffer with a long history, forced, uploaded */
        sdo_op(&o, 0x2F, 0x2300, 1, 3u);
        sdo_op(&o, 0x2F, 0x2300, 4, 8u);
        sdo_op(&o, 0x2F, 0x2301, 1, 6u);
        sdo_op(&o, 0x23, 0x2301, 2, 0x43FA0000u);   /* 500 V: never reached */
        sdo_op(&o, 0x23, 0x2301, 5, 200u);
        sdo_op(&o, 0x23, 0x2301, 6, 0u);            /* as many as fit */
        sdo_op(&o, 0x2F, 0x2302, 0, 1u);
        for (int j = 0; j < 5; ++j) {   /* 40 ms: the ring of 256 samples wraps */
            time_op(&o, 8u);
        }
        sdo_op(&o, 0x2F, 0x2302, 0, 2u);
        time_op(&o, 8u);
        time_op(&o, 8u);
        time_op(&o, 8u);
        sdo_op(&o, 0x40, 0x2307, 0, 0u);
        for (int j = 0; j < 40; ++j) {
            sdo_op(&o, (j & 1) ? 0x70 : 0x60, 0x1000, 0, 0u);
        }
        break;
    default: return 0u;
    }
    return o.n <= cap ? o.n : 0u;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#ifdef CO_FUZZ_LIBFUZZER
/* libFuzzer has its own main: the frame count at exit. */
__attribute__((destructor)) static void report(void)
{
    fprintf(stderr, "co_fuzz: %llu frames delivered; inputs that reached 402 operation enabled %llu, drive RUN %llu, "
                    "scope record %llu, NVM written %llu\n",
            (unsigned long long)co_fuzz_frames, (unsigned long long)co_fuzz_reached[1],
            (unsigned long long)co_fuzz_reached[2], (unsigned long long)co_fuzz_reached[4],
            (unsigned long long)co_fuzz_reached[5]);
}
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    memset(&R, 0, sizeof R);
    reached = 0u;
    mc_drive_cfg_default(&R.cfg);
    hal_host_pwm_init(&R.pwm, R.cfg.p.control_ts_s, R.cfg.p.hw_dead_time_s);
    R.qep.counts_per_rev = 4u * (uint32_t)R.cfg.p.hw_encoder_lines;
    hal_host_can_init(&R.can);
    hal_host_nvm_init(&R.nvm);
    check(mc_drive_init(&R.d, &R.link, &R.cfg, &R.adc, &R.pwm, &R.qep));
    mc_scope_init(&R.scope, scope_buf, 512u, R.cfg.p.control_ts_s);
    const mc_co_cfg_t c = {.node_id = NODE, .heartbeat_ms = 50u, .step_s = 1e-3f, .product_code = 1u};
    check(mc_co_init(&R.co, &c, &R.can, &R.d, &R.nvm, &R.scope, MC_PSTORE_EMPTY));
    set_inputs(0u);
    src_t s = {data, data + size};
    while (s.p < s.end) {
        const uint8_t op = next(&s);
        switch (op % 12u) {
        case 8: run_ms(1u + next(&s) % 8u); break;
        case 9: co_step(); drain(); break;
        case 10: set_inputs(next(&s)); break;
        case 11: drain(); break;
        default:
            frame(&s);
            if ((op & 0x80u) != 0u) {   /* often a step right after, as a real loop would */
                co_step();
                drain();
            }
            break;
        }
        invariants();
    }
    run_ms(2u);
    invariants();
    for (int k = 0; k < 8; ++k) {
        co_fuzz_reached[k] += (reached >> k) & 1u;
    }
    return 0;
}
