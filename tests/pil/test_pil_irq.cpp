// The control interrupt as the emulated cores take it (sim/pil, take_irq), on tiny images
// cross-built by tests/pil/CMakeLists.txt (images/m4_irq.c, images/r5_irq.S + r5_irq.c, both on the
// generic port): the loader's picks (core from the build attributes, port, stage marker), reset
// to the idle WFI, exception entry and return (registers, stack, mode, FP context as the core
// leaves them), the handler's effect on the peripherals, and the ISR cost with its stages.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <string>

#include "pil.hpp"

using namespace mcsim::pil;

namespace {

#ifdef PIL_TEST_IMAGES
const std::string kDir = PIL_TEST_IMAGES;
#else
const std::string kDir;
#endif

std::string image(const char* name)
{
    const std::string p = kDir + "/" + name;
    return !kDir.empty() && std::ifstream(p).good() ? p : std::string();
}

uint32_t word(Target& t, const char* sym)
{
    uint32_t v = 0;
    t.read(t.symbol(sym), &v, 4);
    return v;
}

PeriphInputs inputs()
{
    PeriphInputs in;
    in.adc_i[0] = 100;
    in.adc_i[1] = 200;
    in.adc_i[2] = 300;
    in.adc_vdc = 4000;
    in.time_us = 1234;
    return in;
}

void expect_stages_consistent(const IsrCost& c)
{
    double cy = 0;
    uint64_t n = 0;
    for (const auto& s : c.stage) {
        cy += s.cycles;
        n += s.instructions;
    }
    EXPECT_NEAR(cy, c.cycles, 1e-9);
    EXPECT_EQ(n, c.instructions);
}

}  // namespace

TEST(PilIrq, CortexM4TakesTheAdcInterruptLikeTheCore)
{
    const std::string elf = image("pil_m4_irq.elf");
    if (elf.empty()) GTEST_SKIP() << "no cross-built test image (arm-none-eabi-gcc)";
    auto t = Target::load(elf);
    EXPECT_EQ(t->core(), Core::CortexM4F);
    EXPECT_EQ(t->port(), "generic");
    EXPECT_TRUE(t->notes().empty());   // core from Tag_CPU_arch_profile
    t->reset_and_run_to_idle(100000);
    EXPECT_DOUBLE_EQ(t->peripherals().pwm_period_s(), 1e-4);

    IsrCost c;
    EXPECT_FALSE(t->take_irq(&c, 100000));   // nothing converted yet
    const uint32_t sp = t->reg(13), pc = t->reg(15);
    EXPECT_EQ(sp % 8u, 4u);   // the idle loop leaves SP 4 mod 8: the frame is realigned
    EXPECT_NE(t->reg(18) & 4u, 0u);   // CONTROL.FPCA: the extended frame

    t->period_boundary(inputs());
    t->enable_profile(true);
    ASSERT_TRUE(t->take_irq(&c, 100000));
    t->enable_profile(false);
    // the core as the exception return leaves it
    EXPECT_EQ(t->reg(15), pc);
    EXPECT_EQ(t->reg(13), sp);
    EXPECT_EQ(t->reg(0), 0x11111111u);
    EXPECT_EQ(t->reg(1), 0x22222222u);
    EXPECT_EQ(t->reg(2), 0x33333333u);
    EXPECT_EQ(t->reg(3), 0x44444444u);
    EXPECT_EQ(t->reg(12), 0x55555555u);
    EXPECT_EQ(t->reg(16) & 0x1FFu, 0u);        // IPSR: thread mode
    EXPECT_NE(t->reg(16) & 0x01000000u, 0u);   // Thumb
    EXPECT_NE(t->reg(18) & 4u, 0u);            // FPCA restored from EXC_RETURN
    // the handler's work
    EXPECT_EQ(word(*t, "isr_count"), 1u);
    EXPECT_EQ(word(*t, "adc_sum"), 4600u);   // CHMAP reversed: the same four inputs
    float f = 0;
    t->read(t->symbol("isr_f"), &f, 4);
    EXPECT_FLOAT_EQ(f, 1.0f * 0.5f + 4600.0f);   // .data copied at reset (1.0), FPU in the handler
    EXPECT_FALSE(t->peripherals().irq_pending());   // acknowledged
    EXPECT_EQ(word(*t, "hal_stage_reg"), 2u);
    // the cost, hand-counted (images/m4_irq.c, adc_irq): stage 0 = entry 12 + the handler's first
    // 4 instructions 9 + exit 10 + the FP registers restored on return 17 (the handler used the
    // FPU with the FP context active) = 48; stage 1 = 16 (12 instructions); stage 2 = 40 + the
    // lazy FP save 17 at its vldr = 57 (27 instructions)
    EXPECT_EQ(c.instructions, 43u);
    EXPECT_DOUBLE_EQ(c.cycles, 121.0);
    EXPECT_DOUBLE_EQ(c.stage[0].cycles, 48.0);
    EXPECT_EQ(c.stage[0].instructions, 4u);
    EXPECT_DOUBLE_EQ(c.stage[1].cycles, 16.0);
    EXPECT_EQ(c.stage[1].instructions, 12u);
    EXPECT_DOUBLE_EQ(c.stage[2].cycles, 57.0);
    EXPECT_EQ(c.stage[2].instructions, 27u);
    expect_stages_consistent(c);
    EXPECT_DOUBLE_EQ(t->isr_total().cycles, c.cycles);
    const auto prof = t->profile();   // the handler's instructions (no entry, exit, lazy FP)
    ASSERT_EQ(prof.size(), 1u);
    EXPECT_EQ(prof[0].function, "adc_irq");
    EXPECT_DOUBLE_EQ(prof[0].cycles, 9.0 + 16.0 + 40.0);
    EXPECT_EQ(prof[0].instructions, 43u);

    // the background continues after the WFI; s0 survived the handler's use of it
    t->run_background_to_idle(100000);
    EXPECT_EQ(word(*t, "bg_count"), 1u);
    EXPECT_EQ(word(*t, "bg_s0"), 0x3FA00000u);   // 1.25f
    EXPECT_EQ(t->reg(15), pc);
    EXPECT_FALSE(t->take_irq(&c, 100000));

    // the next period: CMP0 from the handler latched at counter zero
    t->period_boundary(inputs());
    EXPECT_NEAR(t->outputs().duty[0], (4600 % 5000) / 5000.0, 1e-12);
    EXPECT_TRUE(t->outputs().enabled);
    IsrCost c2;
    ASSERT_TRUE(t->take_irq(&c2, 100000));
    EXPECT_EQ(word(*t, "isr_count"), 2u);
    EXPECT_EQ(c2.instructions, c.instructions);   // the same path: the same cost
    EXPECT_DOUBLE_EQ(c2.cycles, c.cycles);
}

TEST(PilIrq, CortexM4OverrunAndBudget)
{
    const std::string elf = image("pil_m4_irq.elf");
    if (elf.empty()) GTEST_SKIP() << "no cross-built test image (arm-none-eabi-gcc)";
    auto t = Target::load(elf);
    t->reset_and_run_to_idle(100000);
    t->period_boundary(inputs());
    IsrCost c;
    try {   // the handler does not fit in 10 instructions
        t->take_irq(&c, 10);
        FAIL() << "no RunError";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("exceeded 10 instructions"), std::string::npos) << e.what();
    }
}

TEST(PilIrq, CortexR5TakesTheIrqWithBankedRegisters)
{
    const std::string elf = image("pil_r5_irq.elf");
    if (elf.empty()) GTEST_SKIP() << "no cross-built test image (arm-none-eabi-gcc)";
    auto t = Target::load(elf);
    EXPECT_EQ(t->core(), Core::CortexR5F);
    EXPECT_EQ(t->port(), "generic");
    t->reset_and_run_to_idle(100000);
    const uint32_t cpsr = t->reg(16), sp = t->reg(13), pc = t->reg(15);
    EXPECT_EQ(cpsr & 0x1Fu, 0x13u);   // SVC
    EXPECT_NE(cpsr & 0x20u, 0u);      // Thumb
    EXPECT_EQ(cpsr & 0x80u, 0u);      // IRQs on
    EXPECT_EQ(sp, t->symbol("svc_stack_top"));

    IsrCost c;
    EXPECT_FALSE(t->take_irq(&c, 100000));
    t->period_boundary(inputs());
    t->enable_profile(true);
    ASSERT_TRUE(t->take_irq(&c, 100000));
    // inside the handler: IRQ mode on its own stack, SPSR_irq = the interrupted CPSR
    const uint32_t irq_sp = word(*t, "irq_sp");
    EXPECT_GE(irq_sp, t->symbol("irq_stack_bottom"));
    EXPECT_LT(irq_sp, t->symbol("irq_stack_top"));
    EXPECT_EQ(irq_sp, t->symbol("irq_stack_top") - 8u - 24u);   // SRS frame, six registers
    EXPECT_EQ(word(*t, "irq_spsr"), cpsr);
    // after RFE: the interrupted mode, state, stack, registers
    EXPECT_EQ(t->reg(16), cpsr);
    EXPECT_EQ(t->reg(13), sp);
    EXPECT_EQ(t->reg(15), pc);
    EXPECT_EQ(t->reg(0), 0x11111111u);
    EXPECT_EQ(t->reg(3), 0x44444444u);
    EXPECT_EQ(t->reg(12), 0x55555555u);
    EXPECT_EQ(word(*t, "isr_count"), 1u);
    EXPECT_EQ(word(*t, "adc_sum"), 4600u);
    EXPECT_FALSE(t->peripherals().irq_pending());
    // the cost, hand-counted (images/r5_irq.S, r5_irq.c): stage 0 = entry 8 + the vector's ldr pc
    // 1 + 8 (unpredicted) + irq_entry up to its blx 12 + 8 (unpredicted) + the handler's first 4
    // instructions 5 = 42 (15 instructions); stage 1 = 12 (12); stage 2 = the handler's rest 37
    // (its bx lr predicted by the return stack) + pop, rfeia 4 + 8 (exception return, unpredicted)
    // = 49 (28)
    EXPECT_EQ(c.instructions, 55u);
    EXPECT_DOUBLE_EQ(c.cycles, 103.0);
    EXPECT_DOUBLE_EQ(c.stage[0].cycles, 42.0);
    EXPECT_EQ(c.stage[0].instructions, 15u);
    EXPECT_DOUBLE_EQ(c.stage[1].cycles, 12.0);
    EXPECT_DOUBLE_EQ(c.stage[2].cycles, 49.0);
    EXPECT_EQ(c.stage[2].instructions, 28u);
    expect_stages_consistent(c);
    // by function: a branch's penalty goes to the code holding the branch
    const auto prof = t->profile();
    ASSERT_EQ(prof.size(), 3u);
    EXPECT_EQ(prof[0].function, "adc_irq");
    EXPECT_DOUBLE_EQ(prof[0].cycles, 5.0 + 12.0 + 37.0);
    EXPECT_EQ(prof[0].instructions, 42u);
    EXPECT_EQ(prof[1].function, "irq_entry");
    EXPECT_DOUBLE_EQ(prof[1].cycles, 12.0 + 8.0 + 4.0 + 8.0);
    EXPECT_EQ(prof[1].instructions, 12u);
    EXPECT_EQ(prof[2].function, "0x18");   // the vector (no function symbol)
    EXPECT_DOUBLE_EQ(prof[2].cycles, 1.0 + 8.0);

    t->run_background_to_idle(100000);
    EXPECT_EQ(word(*t, "bg_count"), 1u);
    t->period_boundary(inputs());
    IsrCost c2;
    ASSERT_TRUE(t->take_irq(&c2, 100000));
    EXPECT_EQ(c2.instructions, c.instructions);
    EXPECT_EQ(word(*t, "isr_count"), 2u);
}
