/* A CANopen device on a real drive over the host HAL, for the comms tests: frames in and out,
 * one SDO request and its answer, the drive's ISR. */
#ifndef TEST_COMMS_RIG_H
#define TEST_COMMS_RIG_H
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/bits.h"
#include "mc/co.h"

#define NODE 5u

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    hal_can_t can;
    mc_drive_cfg_t cfg;
    mc_drive_t d;
    mc_drive_link_t link;
    hal_nvm_t nvm;
    mc_scope_t scope;
    float scope_buf[256];
    mc_co_t co;
    uint32_t now;
} rig_t;

static rig_t rig;

/* The drive (rig.cfg) and the device (c) on the host HAL; rig.nvm as it is. */
static inline void rig_start_cfg(const mc_co_cfg_t *c, mc_pstore_status_t src)
{
    hal_host_pwm_init(&rig.pwm, rig.cfg.p.control_ts_s, 0.5e-6f);
    rig.qep.counts_per_rev = 80000u;
    hal_host_can_init(&rig.can);
    assert_true(mc_drive_init(&rig.d, &rig.link, &rig.cfg, &rig.adc, &rig.pwm, &rig.qep));
    mc_scope_init(&rig.scope, rig.scope_buf, 256u, rig.cfg.p.control_ts_s);
    assert_true(mc_co_init(&rig.co, c, &rig.can, &rig.d, &rig.nvm, &rig.scope, src));
    rig.now = 0;
}

static inline void rig_start(mc_pstore_status_t src)
{
    const mc_co_cfg_t c = {.node_id = NODE, .heartbeat_ms = 0, .step_s = 1e-3f, .vendor_id = 1u, .product_code = 2u,
                           .revision = 3u, .serial = 4u};
    rig_start_cfg(&c, src);
}

/* A fresh rig: the default configuration, an erased NVM. */
static inline void rig_init(void)
{
    memset(&rig, 0, sizeof rig);
    hal_host_nvm_init(&rig.nvm);
    mc_drive_cfg_default(&rig.cfg);
    rig_start(MC_PSTORE_EMPTY);
}

static inline void put(uint32_t id, const uint8_t *d, uint8_t n)
{
    hal_can_frame_t f = {.id = id, .dlc = n};
    memcpy(f.data, d, n);
    assert_true(hal_host_can_deliver(&rig.can, &f));
}

static inline bool take_any(hal_can_frame_t *f)
{
    return hal_host_can_take(&rig.can, f);
}

static inline void drain(void)
{
    hal_can_frame_t f;
    while (take_any(&f)) {
    }
}

/* The next frame with this id (others skipped). */
static inline bool take_id(uint32_t id, hal_can_frame_t *f)
{
    while (take_any(f)) {
        if (f->id == id) {
            return true;
        }
    }
    return false;
}

static inline uint32_t word(const hal_can_frame_t *f)
{
    return (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) | ((uint32_t)f->data[6] << 16) |
           ((uint32_t)f->data[7] << 24);
}

/* One SDO request, one step, its response. */
static inline hal_can_frame_t sdo(uint8_t b0, uint16_t index, uint8_t sub, uint32_t data)
{
    const uint8_t r[8] = {b0, (uint8_t)index, (uint8_t)(index >> 8), sub,
                          (uint8_t)data, (uint8_t)(data >> 8), (uint8_t)(data >> 16), (uint8_t)(data >> 24)};
    put(0x600u + NODE, r, 8u);
    mc_co_step(&rig.co, rig.now);
    hal_can_frame_t f;
    assert_true(take_id(0x580u + NODE, &f));
    return f;
}

/* Expedited download of n bytes: 0 or the abort code. */
static inline uint32_t sdo_write(uint16_t index, uint8_t sub, uint32_t v, uint32_t n)
{
    const uint8_t cs = (uint8_t)(0x23u | ((4u - n) << 2));
    const hal_can_frame_t f = sdo(cs, index, sub, v);
    return f.data[0] == 0x60u ? 0u : (f.data[0] == 0x80u ? word(&f) : 0xFFFFFFFFu);
}

/* Expedited upload: the value, or the abort code in *abort_code. */
static inline uint32_t sdo_read(uint16_t index, uint8_t sub, uint32_t *abort_code)
{
    const hal_can_frame_t f = sdo(0x40, index, sub, 0);
    *abort_code = f.data[0] == 0x80u ? word(&f) : 0u;
    return f.data[0] == 0x80u ? 0u : word(&f);
}

static inline void nmt(uint8_t cs)
{
    const uint8_t d[2] = {cs, NODE};
    put(0x000u, d, 2u);
    mc_co_step(&rig.co, rig.now);
}

/* The drive's ADC inputs: currents at mid-scale, the DC link at vdc. */
static inline void drive_inputs(float vdc)
{
    const mc_drive_blk_t *b = &rig.d.cfg->blk;
    for (int k = 0; k < 3; ++k) {
        rig.adc.sample.i[k] = (uint16_t)(b->offs.nominal + 0.5f);
    }
    rig.adc.sample.vdc = (uint16_t)(vdc / b->volts_per_count + 0.5f);
}

/* ms of time: 10 ISR periods and a device step each (the simulator's rhythm at 10 kHz). */
static inline void run_ms(uint32_t ms)
{
    for (uint32_t k = 0; k < ms; ++k) {
        for (int j = 0; j < 10; ++j) {
            hal_host_pwm_latch(&rig.pwm);
            mc_drive_isr(&rig.d);
            mc_scope_sample(&rig.scope, mc_drive_telemetry(&rig.d));
        }
        mc_drive_background(&rig.d);
        rig.now++;
        mc_co_step(&rig.co, rig.now);
    }
}

#endif
