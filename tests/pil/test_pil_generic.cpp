// The generic port's register model (sim/pil/dev_generic.cpp) against
// hal/generic/include/hal_generic/regs.h: memory map, PWM shadowing and duties, ADC conversion,
// channel map, EOC/OVR and the interrupt, encoder and timer from the plant, flash controller.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "pil.hpp"

extern "C" {
#include "hal_generic/regs.h"
}

using namespace mcsim::pil;

namespace {

struct Fixture {
    std::unique_ptr<Peripherals> p = make_generic_peripherals();
    std::vector<uint8_t> flash = std::vector<uint8_t>(GEN_FLASH_SIZE, 0);
    Fixture()
    {
        p->bind_memory([this](uint32_t a, const void* d, size_t n) { std::memcpy(flash.data() + a, d, n); },
                       [this](uint32_t a, void* d, size_t n) { std::memcpy(d, flash.data() + a, n); });
    }
    uint32_t rd(uint32_t a) { return static_cast<uint32_t>(p->read(a, 4)); }
    void wr(uint32_t a, uint32_t v) { p->write(a, 4, v); }
};

}  // namespace

TEST(PilGeneric, MemoryMapIsTheRegisterHeaders)
{
    Fixture f;
    const auto m = f.p->memories();
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].base, GEN_FLASH_BASE);
    EXPECT_EQ(m[0].size, GEN_FLASH_SIZE);
    EXPECT_EQ(m[1].base, GEN_SRAM_BASE);
    EXPECT_EQ(m[1].size, GEN_SRAM_SIZE);
    const auto w = f.p->windows();
    ASSERT_EQ(w.size(), 6u);
    const uint64_t bases[6] = {GEN_PWM_BASE, GEN_ADC_BASE, GEN_QEP_BASE, GEN_TIM_BASE, GEN_FLC_BASE, GEN_WDT_BASE};
    for (int k = 0; k < 6; ++k) {
        EXPECT_EQ(w[k].base, bases[k]);
        EXPECT_EQ(w[k].size, 0x1000u);
    }
}

TEST(PilGeneric, PwmComparesAreShadowedUntilCounterZero)
{
    Fixture f;
    f.wr(GEN_PWM_BASE + GEN_PWM_PRD, 5000);
    f.wr(GEN_PWM_BASE + GEN_PWM_DT, 100);
    EXPECT_DOUBLE_EQ(f.p->pwm_period_s(), 2.0 * 5000 / 100e6);
    EXPECT_DOUBLE_EQ(f.p->dead_time_s(), 1e-6);
    f.wr(GEN_PWM_BASE + GEN_PWM_CMP(0), 2500);
    f.wr(GEN_PWM_BASE + GEN_PWM_CMP(1), 6000);   // clamped to 1
    f.wr(GEN_PWM_BASE + GEN_PWM_CMP(2), 1000);
    EXPECT_EQ(f.rd(GEN_PWM_BASE + GEN_PWM_CMP(1)), 6000u);   // reads the shadow
    f.p->period_boundary({});   // counter stopped: nothing latched
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[0], 0.0);
    EXPECT_FALSE(f.p->outputs().enabled);
    f.wr(GEN_PWM_BASE + GEN_PWM_CTRL, GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE);
    EXPECT_TRUE(f.p->outputs().enabled);   // at once
    EXPECT_DOUBLE_EQ(f.p->pending_outputs().duty[0], 0.5);
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[0], 0.0);
    f.p->period_boundary({});
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[0], 0.5);
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[1], 1.0);
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[2], 0.2);
    f.wr(GEN_PWM_BASE + GEN_PWM_CMP(0), 0);
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[0], 0.5);   // until the next counter zero
    f.wr(GEN_PWM_BASE + GEN_PWM_CTRL, GEN_PWM_CTRL_RUN);   // OE off: all switches off at once
    EXPECT_FALSE(f.p->outputs().enabled);
    EXPECT_FALSE(f.p->pending_outputs().enabled);
    f.p->period_boundary({});
    EXPECT_DOUBLE_EQ(f.p->outputs().duty[0], 0.0);
}

TEST(PilGeneric, AdcConvertsThroughTheChannelMap)
{
    Fixture f;
    PeriphInputs in;
    in.adc_i[0] = 11;
    in.adc_i[1] = 22;
    in.adc_i[2] = 33;
    in.adc_vdc = 44;
    f.p->period_boundary(in);   // not enabled: no conversion
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_STS), 0u);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_RES(0)), 0u);
    f.wr(GEN_ADC_BASE + GEN_ADC_CHMAP, 0x07000102u);   // results: ch2, ch1, ch0, ch7 (none)
    f.wr(GEN_ADC_BASE + GEN_ADC_CTRL, GEN_ADC_CTRL_EN);
    f.p->period_boundary(in);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_RES(0)), 33u);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_RES(1)), 22u);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_RES(2)), 11u);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_RES(3)), 0u);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_STS), GEN_ADC_STS_EOC);
    EXPECT_FALSE(f.p->irq_pending());   // IE off
    f.wr(GEN_ADC_BASE + GEN_ADC_CTRL, GEN_ADC_CTRL_EN | GEN_ADC_CTRL_IE);
    EXPECT_TRUE(f.p->irq_pending());
    f.wr(GEN_ADC_BASE + GEN_ADC_RES(0), 999);   // read-only
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_RES(0)), 33u);
    f.p->period_boundary(in);   // EOC still set: overrun
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_STS), GEN_ADC_STS_EOC | GEN_ADC_STS_OVR);
    f.wr(GEN_ADC_BASE + GEN_ADC_STS, GEN_ADC_STS_EOC);   // write 1 to clear
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_STS), GEN_ADC_STS_OVR);
    EXPECT_FALSE(f.p->irq_pending());
    f.wr(GEN_ADC_BASE + GEN_ADC_STS, GEN_ADC_STS_OVR);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_STS), 0u);
    in.adc_overrun = true;   // injected
    f.p->period_boundary(in);
    EXPECT_EQ(f.rd(GEN_ADC_BASE + GEN_ADC_STS), GEN_ADC_STS_EOC | GEN_ADC_STS_OVR);
    EXPECT_TRUE(f.p->irq_pending());
    // byte access sees the bytes of the word
    EXPECT_EQ(f.p->read(GEN_ADC_BASE + GEN_ADC_CHMAP + 3, 1), 0x07u);
    EXPECT_EQ(f.p->read(GEN_ADC_BASE + GEN_ADC_CHMAP, 2), 0x0102u);
}

TEST(PilGeneric, EncoderAndTimerFromThePlant)
{
    Fixture f;
    f.wr(GEN_QEP_BASE + GEN_QEP_MAX, 3999);
    PeriphInputs in;
    in.qep_count = 1234;
    in.qep_index_seen = true;
    in.qep_index_count = 17;
    in.time_us = 987654;
    f.p->period_boundary(in);
    EXPECT_EQ(f.rd(GEN_QEP_BASE + GEN_QEP_POS), 1234u);
    EXPECT_EQ(f.rd(GEN_QEP_BASE + GEN_QEP_MAX), 3999u);
    EXPECT_EQ(f.rd(GEN_QEP_BASE + GEN_QEP_STS), 1u);
    EXPECT_EQ(f.rd(GEN_QEP_BASE + GEN_QEP_IDX), 17u);
    EXPECT_EQ(f.rd(GEN_TIM_BASE + GEN_TIM_US), 987654u);
    f.wr(GEN_QEP_BASE + GEN_QEP_POS, 5);   // read-only
    EXPECT_EQ(f.rd(GEN_QEP_BASE + GEN_QEP_POS), 1234u);
    in.qep_count = 4000 + 3;   // kept within 0 .. MAX
    f.p->period_boundary(in);
    EXPECT_EQ(f.rd(GEN_QEP_BASE + GEN_QEP_POS), 3u);
    EXPECT_EQ(f.rd(0x40002FF0u), 0u);   // unmapped offset
}

TEST(PilGeneric, FlashControllerHasFlashSemantics)
{
    Fixture f;
    // a fresh part: the NVM blocks are erased
    for (uint32_t a = GEN_NVM_BASE; a < GEN_FLASH_SIZE; a += 0x1000) EXPECT_EQ(f.flash[a], 0xFF);
    EXPECT_EQ(f.flash[GEN_NVM_BASE - 1], 0x00);
    const uint32_t u = GEN_NVM_BASE + GEN_NVM_BLOCK + 8;
    f.wr(GEN_FLC_BASE + GEN_FLC_ADDR, u);
    f.wr(GEN_FLC_BASE + GEN_FLC_DATA0, 0x44332211u);
    f.wr(GEN_FLC_BASE + GEN_FLC_DATA1, 0x88776655u);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, GEN_FLC_CMD_PROGRAM);
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 0u);
    for (uint32_t j = 0; j < 8; ++j) EXPECT_EQ(f.flash[u + j], 0x11 * (j + 1));
    // program again: bits only clear (AND)
    f.wr(GEN_FLC_BASE + GEN_FLC_DATA0, 0x0F0F0F0Fu);
    f.wr(GEN_FLC_BASE + GEN_FLC_DATA1, 0xFFFFFFFFu);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, GEN_FLC_CMD_PROGRAM);
    EXPECT_EQ(f.flash[u], 0x11 & 0x0F);
    EXPECT_EQ(f.flash[u + 1], 0x22 & 0x0F);
    EXPECT_EQ(f.flash[u + 4], 0x55);
    // misaligned and outside the NVM blocks: ERR, nothing written; ERR is write-1-to-clear
    f.wr(GEN_FLC_BASE + GEN_FLC_ADDR, u + 4);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, GEN_FLC_CMD_PROGRAM);
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 2u);
    EXPECT_EQ(f.flash[u + 4], 0x55);
    f.wr(GEN_FLC_BASE + GEN_FLC_STS, 2u);
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 0u);
    f.wr(GEN_FLC_BASE + GEN_FLC_ADDR, GEN_NVM_BASE - 8);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, GEN_FLC_CMD_PROGRAM);
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 2u);
    f.wr(GEN_FLC_BASE + GEN_FLC_STS, 2u);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, GEN_FLC_CMD_ERASE);   // ADDR still outside
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 2u);
    f.wr(GEN_FLC_BASE + GEN_FLC_STS, 2u);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, 7);   // unknown command
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 2u);
    f.wr(GEN_FLC_BASE + GEN_FLC_STS, 2u);
    // erase the block holding ADDR (any address inside it)
    f.wr(GEN_FLC_BASE + GEN_FLC_ADDR, u + 100);
    f.wr(GEN_FLC_BASE + GEN_FLC_CMD, GEN_FLC_CMD_ERASE);
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_STS), 0u);
    for (uint32_t j = 0; j < 8; ++j) EXPECT_EQ(f.flash[u + j], 0xFF);
    EXPECT_EQ(f.rd(GEN_FLC_BASE + GEN_FLC_CMD), 0u);
}

// The watchdog: counts the plant's microseconds from LOAD once enabled, a kick reloads it, at zero
// it clears PWM CTRL (outputs off) and sets STS.EXP; a kick after that does not revive anything.
TEST(PilGeneric, WatchdogExpiryTurnsTheOutputsOff)
{
    Fixture f;
    f.wr(GEN_PWM_BASE + GEN_PWM_PRD, 5000);
    f.wr(GEN_PWM_BASE + GEN_PWM_CTRL, GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE);
    f.wr(GEN_WDT_BASE + GEN_WDT_LOAD, 1000);
    f.wr(GEN_WDT_BASE + GEN_WDT_CTRL, GEN_WDT_CTRL_EN);
    PeriphInputs in;
    for (uint32_t t = 100; t <= 5000; t += 100) {   // kicked every 100 us: never expires
        in.time_us = t;
        f.p->period_boundary(in);
        f.wr(GEN_WDT_BASE + GEN_WDT_KICK, GEN_WDT_KICK_KEY);
    }
    EXPECT_TRUE(f.p->outputs().enabled);
    f.wr(GEN_WDT_BASE + GEN_WDT_KICK, 0x1234u);   // a wrong key does not reload
    in.time_us = 5900;
    f.p->period_boundary(in);
    EXPECT_TRUE(f.p->outputs().enabled);
    EXPECT_EQ(f.rd(GEN_WDT_BASE + GEN_WDT_STS), 0u);
    in.time_us = 6000;   // 1000 us since the last kick
    f.p->period_boundary(in);
    EXPECT_FALSE(f.p->outputs().enabled);
    EXPECT_EQ(f.rd(GEN_WDT_BASE + GEN_WDT_STS), GEN_WDT_STS_EXP);
    EXPECT_EQ(f.rd(GEN_PWM_BASE + GEN_PWM_CTRL), 0u);
}
