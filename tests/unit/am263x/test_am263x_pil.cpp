// The AM263x port's drivers (built for the host with AM263X_MMIO_HOOKS) running against the
// processor-in-the-loop register model (sim/pil/dev_am263x.cpp): every register access of
// hal_board_init/_start, the HAL calls and the EOC handler goes to the model's read()/write(), at
// the real AM263x addresses. Checks that the model and the drivers agree: the programmed period
// and dead band, the trip as outputs off, shadowed duties latched at the period boundary, the ADC
// conversion and its interrupt through the crossbar and the VIM (IRQVEC = the registered handler,
// acknowledged), the overrun flag, the encoder sample, the time base, the NVM through the QSPI
// model onto the flash window, a CAN frame queued.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "peripherals.hpp"

extern "C" {
#include "hal/board.h"
#include "am263x/port.h"
#include "am263x/regs_adc.h"
#include "am263x/regs_mcan.h"
#include "am263x/regs_qspi.h"
#include "am263x/regs_rti.h"
#include "am263x/regs_soc.h"
#include "am263x/regs_vim.h"
}

namespace {

mcsim::pil::Peripherals* g_model = nullptr;
std::vector<uint8_t> g_flash;
int g_outside = 0;   // accesses outside every window and memory: a driver/model mismatch
uint32_t g_wire_us = 0;   // the plant's clock while the NVM driver talks to the flash

bool in_flash(uintptr_t a) { return a >= AM263X_FLASH_WIN_BASE && a < AM263X_FLASH_WIN_BASE + AM263X_FLASH_WIN_SIZE; }

bool in_window(uintptr_t a, unsigned size)
{
    for (const auto& w : g_model->windows())
        if (a >= w.base && a + size <= w.base + w.size) return true;
    return false;
}

}  // namespace

extern "C" uint32_t am263x_mmio_read(uintptr_t a, unsigned size)
{
    if (in_flash(a)) {
        uint32_t v = 0;
        std::memcpy(&v, &g_flash[a - AM263X_FLASH_WIN_BASE], size);
        return v;
    }
    if (!in_window(a, size)) {
        ++g_outside;
        return 0;
    }
    if (a == AM263X_QSPI_BASE + QSPI_SPI_DATA) {
        // each word takes ~1 us on the wire (8 bits and the controller's turnaround): the time
        // passes with the polls, so the model's sector erase (busy ~131 ms) ends while the
        // driver waits. Nothing else runs in these tests, so the boundaries carry no inputs.
        mcsim::pil::PeriphInputs in;
        in.time_us = ++g_wire_us;
        g_model->period_boundary(in);
    }
    return static_cast<uint32_t>(g_model->read(a, size));
}

extern "C" void am263x_mmio_write(uintptr_t a, unsigned size, uint32_t v)
{
    if (!in_window(a, size)) {
        ++g_outside;
        return;
    }
    g_model->write(a, size, v);
}

namespace {

struct IsrLog {
    int calls = 0;
    hal_adc_sample_t adc{};
    hal_qep_sample_t qep{};
    uint32_t t = 0;
    hal_board_t* board = nullptr;
};

void control_isr(void* ctx)
{
    auto* l = static_cast<IsrLog*>(ctx);
    ++l->calls;
    hal_adc_read(l->board->adc, &l->adc);
    hal_qep_read(l->board->qep, &l->qep);
    l->t = hal_time_us(l->board->time);
}

// What startup.S's IRQ entry does: IRQVEC, call, acknowledge.
void take_irq(mcsim::pil::Peripherals& m)
{
    const uint32_t vec = static_cast<uint32_t>(m.read(AM263X_VIM_BASE + VIM_IRQVEC, 4));
    ASSERT_EQ(vec, static_cast<uint32_t>(reinterpret_cast<uintptr_t>(&am263x_adc_eoc_isr)) & ~3u);
    am263x_adc_eoc_isr();
    m.write(AM263X_VIM_BASE + VIM_IRQVEC, 4, vec);
}

class Am263xPil : public ::testing::Test {
protected:
    void SetUp() override
    {
        model = mcsim::pil::make_am263x_peripherals();
        g_model = model.get();
        g_wire_us = 0;
        g_flash.assign(AM263X_FLASH_WIN_SIZE, 0x5A);
        g_outside = 0;
        model->bind_memory(
            [](uint32_t addr, const void* d, size_t n) { std::memcpy(&g_flash[addr - AM263X_FLASH_WIN_BASE], d, n); },
            [](uint32_t addr, void* d, size_t n) { std::memcpy(d, &g_flash[addr - AM263X_FLASH_WIN_BASE], n); });
        cfg.f_pwm_hz = 20000.0f;
        cfg.dead_time_s = 1e-6f;
        cfg.adc_ch_i[0] = 0;
        cfg.adc_ch_i[1] = 1;
        cfg.adc_ch_i[2] = 2;
        cfg.adc_ch_vdc = 3;
        cfg.qep_counts_per_rev = 4000;
        cfg.can_bitrate = 500000;
    }
    void TearDown() override
    {
        EXPECT_EQ(g_outside, 0);
        g_model = nullptr;
    }
    std::unique_ptr<mcsim::pil::Peripherals> model;
    hal_board_cfg_t cfg{};
    hal_board_t board{};
};

TEST_F(Am263xPil, MemoryMapAndWindows)
{
    const auto mem = model->memories();
    ASSERT_EQ(mem.size(), 4u);
    EXPECT_EQ(mem[0].base, 0x0u);
    EXPECT_EQ(mem[0].size, 32u * 1024u);
    EXPECT_EQ(mem[1].base, 0x80000u);
    EXPECT_EQ(mem[2].base, 0x70000000u);
    EXPECT_EQ(mem[2].size, 2u * 1024u * 1024u);
    EXPECT_EQ(mem[3].base, 0x60000000u);
    for (const auto& w : model->windows()) {
        EXPECT_EQ(w.base % 4096u, 0u) << w.name;
        EXPECT_EQ(w.size % 4096u, 0u) << w.name;
    }
    const auto wins = model->windows();
    for (size_t i = 0; i < wins.size(); ++i) {
        for (size_t j = i + 1; j < wins.size(); ++j) {
            const auto &w = wins[i], &v = wins[j];
            EXPECT_TRUE(w.base + w.size <= v.base || v.base + v.size <= w.base) << w.name << " " << v.name;
        }
    }
}

TEST_F(Am263xPil, BootRunsAndInterrupts)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    EXPECT_NEAR(model->pwm_period_s(), 50e-6, 1e-12);
    EXPECT_NEAR(model->dead_time_s(), 1e-6, 1e-12);
    EXPECT_NEAR(hal_pwm_period_s(board.pwm), 50e-6, 1e-10);   // float
    EXPECT_FALSE(model->outputs().enabled);
    EXPECT_FALSE(hal_pwm_enabled(board.pwm));
    IsrLog log;
    log.board = &board;
    hal_board_attach_isr(control_isr, &log);

    mcsim::pil::PeriphInputs in;
    in.adc_i[0] = 100;
    in.adc_i[1] = 200;
    in.adc_i[2] = 300;
    in.adc_vdc = 2000;
    in.qep_count = 1234;
    in.qep_index_seen = true;
    in.qep_index_count = 17;
    in.time_us = 555;
    model->period_boundary(in);   // not started: no conversion, no interrupt
    EXPECT_FALSE(model->irq_pending());

    hal_board_start();
    EXPECT_FALSE(model->irq_pending());
    EXPECT_FALSE(model->outputs().enabled);   // running, still tripped
    hal_pwm_set_duties(board.pwm, 0.2f, 0.5f, 0.9f);
    hal_pwm_enable(board.pwm, true);
    EXPECT_TRUE(hal_pwm_enabled(board.pwm));
    auto pend = model->pending_outputs();
    EXPECT_NEAR(pend.duty[0], 0.2, 1e-3);
    EXPECT_NEAR(pend.duty[2], 0.9, 1e-3);
    auto now = model->outputs();
    EXPECT_TRUE(now.enabled);
    EXPECT_NEAR(now.duty[0], 0.0, 1e-9);   // nothing latched yet: the counters just started

    in.time_us = 1000;
    model->period_boundary(in);
    now = model->outputs();
    EXPECT_NEAR(now.duty[0], 0.2, 1e-3);
    EXPECT_NEAR(now.duty[1], 0.5, 1e-3);
    EXPECT_NEAR(now.duty[2], 0.9, 1e-3);
    ASSERT_TRUE(model->irq_pending());
    EXPECT_EQ(model->irq_vector(), static_cast<uint32_t>(reinterpret_cast<uintptr_t>(&am263x_adc_eoc_isr)) & ~3u);
    take_irq(*model);
    EXPECT_FALSE(model->irq_pending());
    EXPECT_EQ(log.calls, 1);
    EXPECT_EQ(log.adc.i[0], 100);
    EXPECT_EQ(log.adc.i[1], 200);
    EXPECT_EQ(log.adc.i[2], 300);
    EXPECT_EQ(log.adc.vdc, 2000);
    EXPECT_FALSE(log.adc.overrun);
    EXPECT_EQ(log.qep.count, 1234u);
    EXPECT_TRUE(log.qep.index_seen);
    EXPECT_EQ(log.qep.index_count, 17u);
    EXPECT_EQ(log.t, 1000u);

    // a period whose interrupt is not taken: the next sample reports the overrun
    in.time_us = 1050;
    model->period_boundary(in);
    in.time_us = 1100;
    in.adc_i[0] = 111;
    model->period_boundary(in);
    take_irq(*model);
    EXPECT_EQ(log.calls, 2);
    EXPECT_TRUE(log.adc.overrun);
    EXPECT_EQ(log.adc.i[0], 111);
    in.time_us = 1150;
    model->period_boundary(in);
    take_irq(*model);
    EXPECT_FALSE(log.adc.overrun);   // cleared by the read
    in.adc_overrun = true;           // fault injection
    model->period_boundary(in);
    take_irq(*model);
    EXPECT_TRUE(log.adc.overrun);

    // outputs off at once, without a boundary
    hal_pwm_enable(board.pwm, false);
    EXPECT_FALSE(model->outputs().enabled);
    EXPECT_FALSE(hal_pwm_enabled(board.pwm));
}

TEST_F(Am263xPil, ReinitKeepsOutputsOff)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    hal_board_start();
    hal_pwm_enable(board.pwm, true);
    EXPECT_TRUE(model->outputs().enabled);
    cfg.f_pwm_hz = 10000.0f;
    cfg.dead_time_s = 2e-6f;
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    EXPECT_FALSE(model->outputs().enabled);
    EXPECT_NEAR(model->pwm_period_s(), 100e-6, 1e-12);
    EXPECT_NEAR(model->dead_time_s(), 2e-6, 1e-12);
    cfg.f_pwm_hz = 500.0f;   // TBPRD 200000: refused, outputs off
    EXPECT_FALSE(hal_board_init(&cfg, &board));
    EXPECT_FALSE(model->outputs().enabled);
}

TEST_F(Am263xPil, EncoderSpeedFromTheModel)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    hal_board_start();
    mcsim::pil::PeriphInputs in;
    am263x_qep_speed_t sp{};
    // 20 counts per 50 us period = 400000 counts/s; the unit timer (1 ms) latches every 20 periods
    int polls = 0;
    for (int k = 1; k <= 60; ++k) {
        in.time_us = 50u * static_cast<uint32_t>(k);
        in.qep_count = (20u * static_cast<uint32_t>(k)) % 4000u;
        model->period_boundary(in);
        if (am263x_qep_poll_speed(board.qep, &sp)) ++polls;
    }
    EXPECT_EQ(polls, 3);
    EXPECT_NEAR(sp.unit_cps, 400000.0, 1.0);
    EXPECT_TRUE(sp.capture_valid);
    // 4 counts per 10 us = 15.625 capture ticks, latched as 16: 390625 counts/s
    EXPECT_NEAR(sp.capture_cps, 400000.0, 0.03 * 400000.0);
}

TEST_F(Am263xPil, NvmThroughTheQspiModel)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    ASSERT_TRUE(hal_nvm_erase(board.nvm, 1));
    const uint32_t base = AM263X_NVM_FLASH_OFF + 65536u;   // block 1: the S25FL128S sector at 0x7F0000
    for (uint32_t k = 0; k < 65536; ++k) ASSERT_EQ(g_flash[base + k], 0xFF);
    EXPECT_EQ(g_flash[base - 1], 0x5A);
    uint8_t d[16];
    for (int k = 0; k < 16; ++k) d[k] = static_cast<uint8_t>(0xA0 + k);
    ASSERT_TRUE(hal_nvm_write(board.nvm, 1, 32, d, 16));
    uint8_t e[8] = {0x0F, 0x0F, 0x0F, 0x0F, 0xFF, 0xFF, 0xFF, 0xFF};
    ASSERT_TRUE(hal_nvm_write(board.nvm, 1, 32, e, 8));   // AND: only clears bits
    uint8_t back[16];
    ASSERT_TRUE(hal_nvm_read(board.nvm, 1, 32, back, 16));
    for (int k = 0; k < 16; ++k) EXPECT_EQ(back[k], k < 4 ? (d[k] & 0x0F) : d[k]) << k;
}

// The emulator erases as the S25FL128S does: a 4 KiB P4E into a 64 KiB sector (a driver given
// a uniform 4 KiB map) erases nothing there, and the driver's verify refuses it.
TEST_F(Am263xPil, NvmEraseThePartDoesNotHaveIsRefused)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    static const hal_nvm_region_t uniform[1] = {{0u, 0x1000u, 4096u, 0x20u}};
    static const hal_nvm_geometry_t wrong = {0x1000000u, 256u, 1u, uniform};
    hal_nvm_t n;
    am263x_nvm_init(&n, AM263X_QSPI_BASE, AM263X_FLASH_WIN_BASE, &wrong, AM263X_NVM_FLASH_OFF, 0x8000u);
    ASSERT_EQ(hal_nvm_blocks(&n), 8u);
    EXPECT_FALSE(hal_nvm_erase(&n, 0));
    EXPECT_EQ(g_flash[AM263X_NVM_FLASH_OFF], 0x5A);
    EXPECT_TRUE(hal_nvm_erase(board.nvm, 0));   // the right map: SE
    EXPECT_EQ(g_flash[AM263X_NVM_FLASH_OFF], 0xFF);
}

TEST_F(Am263xPil, CanFrameQueued)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    EXPECT_EQ(hal_can_state(board.can), HAL_CAN_ERROR_ACTIVE);
    hal_can_frame_t f{};
    f.id = 0x701;
    f.dlc = 1;
    f.data[0] = 0x05;
    for (int k = 0; k < 20; ++k) EXPECT_TRUE(hal_can_send(board.can, &f));   // the model sends at once
    hal_can_frame_t r;
    EXPECT_FALSE(hal_can_receive(board.can, &r));
    // the bus side: the 20 frames as sent, then nothing
    mcsim::pil::CanFrame b;
    for (int k = 0; k < 20; ++k) {
        ASSERT_TRUE(model->can_take(b));
        EXPECT_EQ(b.id, 0x701u);
        EXPECT_FALSE(b.ext);
        EXPECT_EQ(b.dlc, 1);
        EXPECT_EQ(b.data[0], 0x05);
    }
    EXPECT_FALSE(model->can_take(b));
}

// Frames from the bus go into RX FIFO 0 as the driver configured it, in order; a full FIFO loses
// the newest and says so (IR.RF0L, counted by the driver); extended and short frames survive.
TEST_F(Am263xPil, CanFramesReceived)
{
    ASSERT_TRUE(model->can_supported());
    mcsim::pil::CanFrame b;
    b.id = 0x601;
    b.dlc = 8;
    EXPECT_FALSE(model->can_deliver(b));   // not initialised: not on the bus
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    for (int k = 0; k < 16; ++k) {
        b.data[0] = static_cast<uint8_t>(k);
        EXPECT_TRUE(model->can_deliver(b));
    }
    EXPECT_FALSE(model->can_deliver(b));   // 17th: the FIFO (16 elements) is full
    hal_can_frame_t r;
    for (int k = 0; k < 16; ++k) {
        ASSERT_TRUE(hal_can_receive(board.can, &r));
        EXPECT_EQ(r.id, 0x601u);
        EXPECT_EQ(r.dlc, 8);
        EXPECT_EQ(r.data[0], k);
    }
    EXPECT_FALSE(hal_can_receive(board.can, &r));
    mcsim::pil::CanFrame x;
    x.id = 0x1ABCDEF0 & 0x1FFFFFFF;
    x.ext = true;
    x.dlc = 3;
    x.data[2] = 0x77;
    EXPECT_TRUE(model->can_deliver(x));   // the FIFO wraps round
    ASSERT_TRUE(hal_can_receive(board.can, &r));
    EXPECT_TRUE(r.ext);
    EXPECT_EQ(r.id, x.id);
    EXPECT_EQ(r.dlc, 3);
    EXPECT_EQ(r.data[2], 0x77);
}

// ---- Bring-up (hal_board_init's pads and module clocks) against the model, which starts from the
// SoC's reset values. To show that a step is needed, a test puts one register back to its reset
// value (the lock opened as a debugger would) and looks for the symptom at the pins or the bus.
void poke_pad(mcsim::pil::Peripherals& m, uint32_t pad, uint32_t v)
{
    m.write(AM263X_IOMUX_BASE + AM263X_IOMUX_KICK0, 4, AM263X_IOMUX_KICK0_UNLOCK);
    m.write(AM263X_IOMUX_BASE + AM263X_IOMUX_KICK1, 4, AM263X_IOMUX_KICK1_UNLOCK);
    m.write(AM263X_IOMUX_BASE + pad, 4, v);
    m.write(AM263X_IOMUX_BASE + AM263X_IOMUX_KICK0, 4, 0);
    m.write(AM263X_IOMUX_BASE + AM263X_IOMUX_KICK1, 4, 0);
}

void poke_rcm(mcsim::pil::Peripherals& m, uint32_t off, uint32_t v)
{
    m.write(AM263X_MSS_RCM_BASE + AM263X_LOCK0_KICK0, 4, AM263X_KICK0_UNLOCK);
    m.write(AM263X_MSS_RCM_BASE + AM263X_LOCK0_KICK1, 4, AM263X_KICK1_UNLOCK);
    m.write(AM263X_MSS_RCM_BASE + off, 4, v);
    m.write(AM263X_MSS_RCM_BASE + AM263X_LOCK0_KICK0, 4, 0);
    m.write(AM263X_MSS_RCM_BASE + AM263X_LOCK0_KICK1, 4, 0);
}

uint32_t pad(mcsim::pil::Peripherals& m, uint32_t off) { return static_cast<uint32_t>(m.read(AM263X_IOMUX_BASE + off, 4)); }
uint32_t rcm(mcsim::pil::Peripherals& m, uint32_t off) { return static_cast<uint32_t>(m.read(AM263X_MSS_RCM_BASE + off, 4)); }

const uint32_t kPwmPads[6] = {AM263X_PAD_EPWM_A(0), AM263X_PAD_EPWM_B(0), AM263X_PAD_EPWM_A(1),
                              AM263X_PAD_EPWM_B(1), AM263X_PAD_EPWM_A(2), AM263X_PAD_EPWM_B(2)};

TEST_F(Am263xPil, BringUpFromTheResetValues)
{
    // reset: every pad a GPIO (0x5F7), both module clocks from source 0 (25 MHz), locked
    for (uint32_t p : kPwmPads) EXPECT_EQ(pad(*model, p), AM263X_PAD_RESET);
    EXPECT_EQ(pad(*model, AM263X_PAD_MCAN0_TX), AM263X_PAD_RESET);
    EXPECT_EQ(rcm(*model, AM263X_RCM_MCAN0_CLK_SRC_SEL), 0u);
    model->write(AM263X_IOMUX_BASE + AM263X_PAD_EPWM_A(0), 4, 0x500u);   // locked: ignored
    model->write(AM263X_MSS_RCM_BASE + AM263X_RCM_MCAN0_CLK_SRC_SEL, 4, 0x444u);
    EXPECT_EQ(pad(*model, AM263X_PAD_EPWM_A(0)), AM263X_PAD_RESET);
    EXPECT_EQ(rcm(*model, AM263X_RCM_MCAN0_CLK_SRC_SEL), 0u);

    ASSERT_TRUE(hal_board_init(&cfg, &board));
    for (uint32_t p : kPwmPads) EXPECT_EQ(pad(*model, p) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_EPWM) << p;
    EXPECT_EQ(pad(*model, AM263X_PAD_EQEP0_A) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_EQEP);
    EXPECT_EQ(pad(*model, AM263X_PAD_EQEP0_B) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_EQEP);
    EXPECT_EQ(pad(*model, AM263X_PAD_EQEP0_INDEX) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_EQEP);
    EXPECT_EQ(pad(*model, AM263X_PAD_MCAN0_RX) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_MCAN);
    EXPECT_EQ(pad(*model, AM263X_PAD_MCAN0_TX) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_MCAN);
    EXPECT_EQ(pad(*model, AM263X_PAD_EPWM4_A) & 0xFFu, AM263X_PAD_GPIO);   // STB: GPIO, no override
    const uint32_t stb = 1u << (AM263X_CAN_STB_GPIO % 32u);
    EXPECT_EQ(model->read(AM263X_GPIO0_BASE + AM263X_GPIO_DIR(1), 4) & stb, 0u);        // output
    EXPECT_EQ(model->read(AM263X_GPIO0_BASE + AM263X_GPIO_OUT_DATA(1), 4) & stb, 0u);   // low
    // MCAN0: 400 MHz / 5; RTI0: the 25 MHz crystal / 1 (TI's soc_rcm.c source codes)
    EXPECT_EQ(rcm(*model, AM263X_RCM_MCAN0_CLK_SRC_SEL), 0x444u);
    EXPECT_EQ(rcm(*model, AM263X_RCM_MCAN0_CLK_DIV_VAL), 0x444u);
    EXPECT_EQ(rcm(*model, AM263X_RCM_RTI0_CLK_SRC_SEL), 0x666u);
    EXPECT_EQ(rcm(*model, AM263X_RCM_RTI0_CLK_DIV_VAL), 0x000u);
    // WDT0: the crystal / 1 too; the trip input's pad a GPIO input, pull enabled and up
    EXPECT_EQ(rcm(*model, AM263X_RCM_WDT0_CLK_SRC_SEL), 0x666u);
    EXPECT_EQ(rcm(*model, AM263X_RCM_WDT0_CLK_DIV_VAL), 0x000u);
    EXPECT_EQ(pad(*model, AM263X_PAD_SPI0_CS0) & 0x3FFu, AM263X_PAD_GPIO | AM263X_PAD_PULLUP);
    // both locks closed again
    model->write(AM263X_IOMUX_BASE + AM263X_PAD_EPWM_A(0), 4, AM263X_PAD_RESET);
    model->write(AM263X_MSS_RCM_BASE + AM263X_RCM_MCAN0_CLK_SRC_SEL, 4, 0u);
    EXPECT_EQ(pad(*model, AM263X_PAD_EPWM_A(0)) & AM263X_PAD_FUNC_MASK, AM263X_PAD_FN_EPWM);
    EXPECT_EQ(rcm(*model, AM263X_RCM_MCAN0_CLK_SRC_SEL), 0x444u);
}

// A PWM configuration the counters cannot realise: the gate pads stay GPIO inputs pulled down,
// never the ePWM function.
TEST_F(Am263xPil, GatePadsSafeWhenThePwmIsRefused)
{
    cfg.f_pwm_hz = 500.0f;
    EXPECT_FALSE(hal_board_init(&cfg, &board));
    for (uint32_t p : kPwmPads) {
        EXPECT_EQ(pad(*model, p) & AM263X_PAD_FUNC_MASK, AM263X_PAD_GPIO) << p;
        EXPECT_EQ(pad(*model, p) & (AM263X_PAD_NOPULL | 0x200u), 0u) << p;   // pull enabled, down
    }
    EXPECT_FALSE(model->outputs().enabled);
}

TEST_F(Am263xPil, PwmPadWithoutItsMuxShowsNoPwm)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    hal_board_start();
    hal_pwm_enable(board.pwm, true);
    EXPECT_TRUE(model->outputs().enabled);
    for (uint32_t p : kPwmPads) {
        poke_pad(*model, p, AM263X_PAD_RESET);
        EXPECT_FALSE(model->outputs().enabled) << p;
        poke_pad(*model, p, AM263X_PAD_FN_EPWM | AM263X_PAD_NOPULL | AM263X_PAD_SLEW_LOW);
        EXPECT_TRUE(model->outputs().enabled) << p;
    }
}

// The bit timing the driver computes for 80 MHz, run from the reset clock (25 MHz): 156.25 kbit/s,
// no frame on the 500 kbit/s bus.
TEST_F(Am263xPil, McanAtTheResetClockMissesTheBitRate)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    const uint32_t nbtp = static_cast<uint32_t>(model->read(AM263X_MCAN_CFG_BASE(0) + MCAN_CORE_OFFSET + MCAN_NBTP, 4));
    const uint32_t brp = ((nbtp >> MCAN_NBTP_NBRP_SHIFT) & 0x1FFu) + 1u;
    const uint32_t tq = 3u + ((nbtp >> MCAN_NBTP_NTSEG1_SHIFT) & 0xFFu) + ((nbtp >> MCAN_NBTP_NTSEG2_SHIFT) & 0x7Fu);
    EXPECT_EQ(80000000u / (brp * tq), 500000u);
    EXPECT_EQ(25000000u / (brp * tq), 156250u);   // the same timing at the reset clock
    hal_can_frame_t f{};
    f.id = 0x181;
    f.dlc = 2;
    mcsim::pil::CanFrame b;
    b.id = 0x201;
    b.dlc = 1;
    poke_rcm(*model, AM263X_RCM_MCAN0_CLK_SRC_SEL, AM263X_RCM_SRC_WUCPUCLK);
    poke_rcm(*model, AM263X_RCM_MCAN0_CLK_DIV_VAL, 0u);
    EXPECT_TRUE(hal_can_send(board.can, &f));
    EXPECT_FALSE(model->can_take(b));
    EXPECT_FALSE(model->can_deliver(b));
    poke_rcm(*model, AM263X_RCM_MCAN0_CLK_DIV_VAL, AM263X_RCM_DIV(5));
    poke_rcm(*model, AM263X_RCM_MCAN0_CLK_SRC_SEL, AM263X_RCM_SRC_MCAN_CORE_HSDIV0);
    EXPECT_TRUE(model->can_take(b));
    EXPECT_EQ(b.id, 0x181u);
    EXPECT_TRUE(model->can_deliver(b));
    // the transceiver in standby (its STB pad at reset, or the GPIO high): off the bus
    poke_pad(*model, AM263X_PAD_EPWM4_A, AM263X_PAD_RESET);
    EXPECT_TRUE(hal_can_send(board.can, &f));
    EXPECT_FALSE(model->can_take(b));
    poke_pad(*model, AM263X_PAD_EPWM4_A, AM263X_PAD_GPIO | AM263X_PAD_NOPULL | AM263X_PAD_SLEW_LOW);
    EXPECT_TRUE(model->can_take(b));
    const uint32_t stb = 1u << (AM263X_CAN_STB_GPIO % 32u);
    model->write(AM263X_GPIO0_BASE + AM263X_GPIO_CLR_DATA(1) - 4u, 4, stb);   // SET_DATA
    EXPECT_TRUE(hal_can_send(board.can, &f));
    EXPECT_FALSE(model->can_take(b));
    model->write(AM263X_GPIO0_BASE + AM263X_GPIO_CLR_DATA(1), 4, stb);
    EXPECT_TRUE(model->can_take(b));
    // the transceiver's pads back at reset: off the bus again
    poke_pad(*model, AM263X_PAD_MCAN0_TX, AM263X_PAD_RESET);
    EXPECT_TRUE(hal_can_send(board.can, &f));
    EXPECT_FALSE(model->can_take(b));
}

// The RTI counts at the clock MSS_RCM selects: the port's 25 MHz crystal gives microseconds; the
// same prescaler at SYS_CLK (200 MHz, source code 0x222) would run the time base 8 times fast.
TEST_F(Am263xPil, TimeBaseFollowsTheRtiClock)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    am263x_time_init(board.time, AM263X_RTI_CLK_HZ);   // board.c starts the RTI once per process
    mcsim::pil::PeriphInputs in;
    in.time_us = 1000;
    model->period_boundary(in);
    EXPECT_EQ(hal_time_us(board.time), 1000u);
    poke_rcm(*model, AM263X_RCM_RTI0_CLK_SRC_SEL, 0x222u);
    EXPECT_EQ(hal_time_us(board.time), 8000u);
}

// Each phase current comes from its own module: a module left unpowered or a SOC on an input the
// module does not have shows at once.
TEST_F(Am263xPil, PhaseCurrentsFromThreeModules)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    IsrLog log;
    log.board = &board;
    hal_board_attach_isr(control_isr, &log);
    hal_board_start();
    mcsim::pil::PeriphInputs in;
    in.adc_i[0] = 101;
    in.adc_i[1] = 202;
    in.adc_i[2] = 303;
    in.adc_vdc = 404;
    in.time_us = 50;
    model->period_boundary(in);
    take_irq(*model);
    EXPECT_EQ(log.adc.i[0], 101);
    EXPECT_EQ(log.adc.i[1], 202);
    EXPECT_EQ(log.adc.i[2], 303);
    EXPECT_EQ(log.adc.vdc, 404);
    model->write(AM263X_ADC_BASE(1) + ADC_ADCCTL1, 2, 0);   // ADC1 powered down: ib stale
    model->write(AM263X_ADC_BASE(2) + ADC_ADCSOCCTL(0), 4,
                 static_cast<uint32_t>(model->read(AM263X_ADC_BASE(2) + ADC_ADCSOCCTL(0), 4)) | (7u << ADC_SOCCTL_CHSEL_SHIFT));
    in.adc_i[1] = 222;
    in.adc_i[2] = 333;
    in.time_us = 100;
    model->period_boundary(in);
    take_irq(*model);
    EXPECT_EQ(log.adc.i[1], 202);
    EXPECT_EQ(log.adc.i[2], 0);
}

TEST_F(Am263xPil, EncoderPadsWithoutTheirMuxDoNotCount)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    mcsim::pil::PeriphInputs in;
    in.qep_count = 100;
    in.time_us = 50;
    model->period_boundary(in);
    hal_qep_sample_t q{};
    hal_qep_read(board.qep, &q);
    EXPECT_EQ(q.count, 100u);
    poke_pad(*model, AM263X_PAD_EQEP0_B, AM263X_PAD_RESET);
    in.qep_count = 200;
    in.time_us = 100;
    model->period_boundary(in);
    hal_qep_read(board.qep, &q);
    EXPECT_EQ(q.count, 100u);
}

}  // namespace

// The watchdog's timeout is the port's own: whatever clock WDT0 ran from before (here the 10 MHz
// RC oscillator, as a GEL script or an earlier image may leave it; at a true reset WUCPUCLK is
// 25 MHz by TI's clock map), hal_board_init selects the crystal, so an unkicked watchdog expires
// after (29 + 1) x 2^13 / 25 MHz = 9830.4 us. Without that step it would take 24576 us.
TEST_F(Am263xPil, WatchdogTimeoutFromTheClockTheBoardSets)
{
    poke_rcm(*model, AM263X_RCM_WDT0_CLK_SRC_SEL, 0x555u);
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    hal_board_start();
    const auto expired = [&] { return (model->read(AM263X_WDT0_BASE + RTI_RTIWDSTATUS, 4) & RTI_WDSTATUS_DWDST) != 0; };
    mcsim::pil::PeriphInputs in;
    uint32_t t = 0;
    while (!expired() && t < 50000u) {
        t += 100u;
        in.time_us = t;
        model->period_boundary(in);
    }
    EXPECT_EQ(t, 9900u) << "the watchdog expired after " << t << " us";
    EXPECT_FALSE(model->outputs().enabled);
}

// The hardware trip: the gate driver pulling nFAULT low trips the bridge through pad SPI0_CS0
// (GPIO11), INPUT XBAR 0 and TZ1; with the pad left at its reset value the same fault does
// nothing, and released the line reads the pad's pull-up (no trip).
TEST_F(Am263xPil, HardwareTripThroughItsPad)
{
    ASSERT_TRUE(hal_board_init(&cfg, &board));
    hal_board_start();
    hal_pwm_enable(board.pwm, true);
    ASSERT_TRUE(model->outputs().enabled);
    ASSERT_TRUE(model->set_pin("nFAULT", false));
    EXPECT_FALSE(model->outputs().enabled) << "a gate-driver fault left the outputs on";
    EXPECT_FALSE(hal_pwm_enabled(board.pwm));
    ASSERT_TRUE(model->set_pin("nFAULT", true));
    hal_pwm_enable(board.pwm, true);
    EXPECT_TRUE(model->outputs().enabled) << "the released line (pull-up) still trips";
    const uint32_t muxed = pad(*model, AM263X_PAD_SPI0_CS0);
    poke_pad(*model, AM263X_PAD_SPI0_CS0, AM263X_PAD_RESET);
    ASSERT_TRUE(model->set_pin("nFAULT", false));
    EXPECT_TRUE(model->outputs().enabled);   // the pad not muxed: the fault does not arrive
    poke_pad(*model, AM263X_PAD_SPI0_CS0, muxed);
    mcsim::pil::PeriphInputs in;
    in.time_us = 100u;
    model->period_boundary(in);
    EXPECT_FALSE(model->outputs().enabled);
}
