// The PIL cycle model against hand-counted instruction sequences on both cores (sim/pil,
// docs/pil-cycle-model.md): machine code assembled once with arm-none-eabi-as (the source is in
// the comments), mapped into a synthetic target (the generic port's memories: flash at 0, SRAM at
// 0x20000000), run to its WFI, the cycles compared with the sum from the timing tables. Also the
// stage split at a store to the stage marker, the FPU-off checks, the instruction budget and an
// unmapped access.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "pil.hpp"

using namespace mcsim::pil;

namespace {

constexpr uint32_t kSeq = 0x100, kSetup = 0x1000, kStage = 0x2000, kMisc = 0x3000;
constexpr uint32_t kStack = 0x20008000, kMarker = 0x20000100;

// seq_t.s, Thumb-2, at kSeq (the same bytes run on both cores):
//  0: movs    r0, #3                M4  1   R5  1
//  2: adds    r1, r0, #4                1       1
//  4: lsls    r2, r1, #2                1       1
//  6: mul.w   r3, r1, r2                1       2   (MUL: R5 two issue cycles)
//  a: ldr     r4, [pc, #56]  @ lit      2       1
//  c: ldr     r5, [r4]                  2       1   (M4: its base is the last load's result: not pipelined)
//  e: ldr     r6, [r4, #4]              1       1   (M4: pipelined after a load)
// 10: str     r5, [r4, #8]              1       1
// 12: vmov    s0, r0                    1       1
// 16: vcvt.f32.s32 s0, s0               1       1
// 1a: vmul.f32 s1, s0, s0               1       1
// 1e: vadd.f32 s2, s1, s0               1       1
// 22: vdiv.f32 s3, s2, s0              14      15
// 26: vsqrt.f32 s4, s3                 14      15
// 2a: vmla.f32 s4, s0, s1               3       1
// 2e: cmp     r0, #3                    1       1
// 30: beq.n   34   (taken)              1+2     1+8 (R5: first sight, predicted not taken)
//                             block 1: 49 (17 insns)  54
// 32: nop                      (skipped)
// 34: cmp     r0, #4                    1       1
// 36: beq.n   42   (not taken)          1       1   (R5: predicted not taken: right)
//                             block 2:  2 (2 insns)    2
// 38: push    {r4, r5}                  1+2     1   (R5: two registers per cycle)
// 3a: pop     {r4, r5}                  1+2     1
// 3c: sdiv    r7, r0, r1                7      10   (data dependent: the tables' mid values)
// 40: wfi                               1       1
//                             block 3: 14 (4 insns)   13
// 42: b.n     42
// 44: .word   0x20000104
//                               total: 65 (23)        69 (23)
const std::vector<uint8_t> kSeqThumb = {
    0x03, 0x20, 0x01, 0x1d, 0x8a, 0x00, 0x01, 0xfb, 0x02, 0xf3, 0x0e, 0x4c, 0x25, 0x68, 0x66, 0x68, 0xa5, 0x60,
    0x00, 0xee, 0x10, 0x0a, 0xb8, 0xee, 0xc0, 0x0a, 0x60, 0xee, 0x00, 0x0a, 0x30, 0xee, 0x80, 0x1a, 0xc1, 0xee,
    0x00, 0x1a, 0xb1, 0xee, 0xe1, 0x2a, 0x00, 0xee, 0x20, 0x2a, 0x03, 0x28, 0x00, 0xd0, 0x00, 0xbf, 0x04, 0x28,
    0x04, 0xd0, 0x30, 0xb4, 0x30, 0xbc, 0x90, 0xfb, 0xf1, 0xf7, 0x30, 0xbf, 0xfe, 0xe7, 0x04, 0x01, 0x00, 0x20};

// seq_a.s, ARM state (Cortex-R5F), at kSeq:
//  0: mov     r0, #5                    1
//  4: add     r1, r0, r0, lsl #1        1
//  8: mla     r2, r0, r1, r0            2
//  c: umull   r3, r4, r0, r1            2
// 10: ldr     r5, [pc, #48]  @ lit      1
// 14: ldm     r5, {r6, r7, r8}          2   (3 registers, two per cycle)
// 18: push    {r0, r1, r2, r3}          2
// 1c: pop     {r0, r1, r2, r3}          2
// 20: vmov    d0, r0, r1                1
// 24: vadd.f64 d1, d0, d0               1
// 28: vmul.f64 d2, d1, d1               2
// 2c: vdiv.f64 d3, d2, d1              29
// 30: bl      44 <func>                 1   (direct: predicted; return address pushed)
//                             block: 47 (13 insns)
// 44: bx      lr                        1   (return stack hit)
//                             block:  1 (1)
// 34: cmp     r0, #5                    1
// 38: bne     40   (not taken)          1   (predicted not taken: right)
//                             block:  2 (2)
// 3c: wfi                               1
//                             block:  1 (1)
// 40: b       40
// 48: .word   0x20000104
//                               total: 51 (17)
const std::vector<uint8_t> kSeqArm = {
    0x05, 0x00, 0xa0, 0xe3, 0x80, 0x10, 0x80, 0xe0, 0x90, 0x01, 0x22, 0xe0, 0x90, 0x31, 0x84, 0xe0, 0x30, 0x50, 0x9f,
    0xe5, 0xc0, 0x01, 0x95, 0xe8, 0x0f, 0x00, 0x2d, 0xe9, 0x0f, 0x00, 0xbd, 0xe8, 0x10, 0x0b, 0x41, 0xec, 0x00, 0x1b,
    0x30, 0xee, 0x01, 0x2b, 0x21, 0xee, 0x01, 0x3b, 0x82, 0xee, 0x03, 0x00, 0x00, 0xeb, 0x05, 0x00, 0x50, 0xe3, 0x00,
    0x00, 0x00, 0x1a, 0x03, 0xf0, 0x20, 0xe3, 0xfe, 0xff, 0xff, 0xea, 0x1e, 0xff, 0x2f, 0xe1, 0x04, 0x01, 0x00, 0x20};

// setup.s, Thumb, at kSetup:
//  m4_setup (0x00): ldr r0, =0xE000ED88; ldr r1, [r0]; orr.w r1, r1, #0xF00000; str r1, [r0];
//                   dsb; isb; wfi                      (CPACR: CP10/CP11 full access)
//  r5_setup (0x18): mov.w r0, #0x40000000; vmsr fpexc, r0; wfi   (FPEXC.EN)
const std::vector<uint8_t> kSetupCode = {0x04, 0x48, 0x01, 0x68, 0x41, 0xf4, 0x70, 0x01, 0x01, 0x60, 0xbf, 0xf3,
                                         0x4f, 0x8f, 0xbf, 0xf3, 0x6f, 0x8f, 0x30, 0xbf, 0x88, 0xed, 0x00, 0xe0,
                                         0x4f, 0xf0, 0x80, 0x40, 0xe8, 0xee, 0x10, 0x0a, 0x30, 0xbf, 0x00, 0xbf};

// stage.s, Thumb, at kStage (the marker at 0x20000100):
//  one_store (0x00):  ldr r1, =0x20000100 (2); movs r0, #2 (1); str r0, [r1] (1) | stage 2:
//                     adds r2, #1 (1); adds r2, #1 (1); wfi (1)
//  two_stores (0x10): ldr r1, =0x20000100 (2); movs r0, #1 (1); str r0, [r1] (1) | stage 1:
//                     adds r2, #1 (1); movs r0, #3 (1); str r0, [r1] (1) | stage 3:
//                     adds r2, #1 (1); wfi (1)
//  stm_store (0x24):  ldr r1, =0x20000100 (2); ldr r3, =0x20000200 (1, pipelined);
//                     movs r0, #4 (1); str r0, [r3] (1, not the marker); stmia r1!, {r0} (1+1) |
//                     stage 4: adds r2, #1 (1); wfi (1)
const std::vector<uint8_t> kStageCode = {
    0x02, 0x49, 0x02, 0x20, 0x08, 0x60, 0x01, 0x32, 0x01, 0x32, 0x30, 0xbf, 0x00, 0x01, 0x00, 0x20,
    0x03, 0x49, 0x01, 0x20, 0x08, 0x60, 0x01, 0x32, 0x03, 0x20, 0x08, 0x60, 0x01, 0x32, 0x30, 0xbf,
    0x00, 0x01, 0x00, 0x20, 0x03, 0x49, 0x04, 0x4b, 0x04, 0x20, 0x18, 0x60, 0x01, 0xc1, 0x01, 0x32,
    0x30, 0xbf, 0x00, 0x00, 0x00, 0x01, 0x00, 0x20, 0x00, 0x02, 0x00, 0x20};

// misc.s, Thumb, at kMisc:
//  0x00: mov.w r0, #0x30000000; 0x04: ldr r1, [r0]; wfi   (a load outside every memory)
//  0x0c: b.n 0x0c                                          (a loop without end)
const std::vector<uint8_t> kMiscCode = {0x4f, 0xf0, 0x40, 0x50, 0x01, 0x68, 0x30, 0xbf,
                                        0x00, 0x00, 0x00, 0x00, 0xfe, 0xe7, 0x00, 0xbf};

std::unique_ptr<Target> synthetic(Core core)
{
    return Target::create(core, make_generic_peripherals(),
                          {{kSeq, core == Core::CortexR5F ? kSeqArm : kSeqThumb},
                           {kSetup, kSetupCode},
                           {kStage, kStageCode},
                           {kMisc, kMiscCode}});
}

double stage_sum(const IsrCost& c)
{
    double s = 0;
    for (const auto& st : c.stage) s += st.cycles;
    return s;
}

uint64_t stage_insns(const IsrCost& c)
{
    uint64_t s = 0;
    for (const auto& st : c.stage) s += st.instructions;
    return s;
}

}  // namespace

TEST(PilCycles, CortexM4ThumbSequenceMatchesTheHandCount)
{
    auto t = synthetic(Core::CortexM4F);
    EXPECT_STREQ(t->timing_name(), "Cortex-M4F");
    t->run_counted(kSetup | 1, kStack, 1000);   // FPU on
    const IsrCost c = t->run_counted(kSeq | 1, kStack, 1000);
    EXPECT_EQ(c.instructions, 23u);
    EXPECT_DOUBLE_EQ(c.cycles, 65.0);
    EXPECT_DOUBLE_EQ(c.stage[0].cycles, 65.0);   // no marker written: all in stage 0
    EXPECT_EQ(t->reg(15), kSeq + 0x42);           // stopped after the WFI
    EXPECT_EQ(t->reg(7), 0u);                     // 3 / 7
    if (::testing::Test::HasFailure())
        for (const auto& i : t->explain(kSeq, 0x44, true))
            std::printf("  %04x %-28s %-26s %g\n", i.addr, i.text.c_str(), i.cls, i.cycles);
}

TEST(PilCycles, CortexR5ThumbSequenceMatchesTheHandCount)
{
    auto t = Target::create(Core::CortexR5F, make_generic_peripherals(), {{kSeq, kSeqThumb}, {kSetup, kSetupCode}});
    EXPECT_STREQ(t->timing_name(), "Cortex-R5F");
    t->run_counted((kSetup + 0x18) | 1, kStack, 1000);   // FPEXC.EN
    const IsrCost c = t->run_counted(kSeq | 1, kStack, 1000);
    EXPECT_EQ(c.instructions, 23u);
    EXPECT_DOUBLE_EQ(c.cycles, 69.0);
    EXPECT_EQ(t->reg(15), kSeq + 0x42);
    EXPECT_NE(t->reg(16) & 0x20u, 0u);   // Thumb state
}

TEST(PilCycles, CortexR5ArmSequenceMatchesTheHandCount)
{
    auto t = synthetic(Core::CortexR5F);
    t->run_counted((kSetup + 0x18) | 1, kStack, 1000);
    const IsrCost c = t->run_counted(kSeq, kStack, 1000);   // ARM state
    EXPECT_EQ(c.instructions, 17u);
    EXPECT_DOUBLE_EQ(c.cycles, 51.0);
    EXPECT_EQ(t->reg(15), kSeq + 0x40);
    EXPECT_EQ(t->reg(16) & 0x20u, 0u);   // ARM state
    if (::testing::Test::HasFailure())
        for (const auto& i : t->explain(kSeq, 0x48, false))
            std::printf("  %04x %-28s %-26s %g\n", i.addr, i.text.c_str(), i.cls, i.cycles);
}

TEST(PilCycles, PredictorLearnsATakenBranchOnTheR5)
{
    // The same Thumb sequence again: the beq at 0x30 was taken once (counter weakly taken now):
    // predicted right this time, 8 cycles less; everything else is the same.
    auto t = Target::create(Core::CortexR5F, make_generic_peripherals(), {{kSeq, kSeqThumb}, {kSetup, kSetupCode}});
    t->run_counted((kSetup + 0x18) | 1, kStack, 1000);
    EXPECT_DOUBLE_EQ(t->run_counted(kSeq | 1, kStack, 1000).cycles, 69.0);
    EXPECT_DOUBLE_EQ(t->run_counted(kSeq | 1, kStack, 1000).cycles, 61.0);
}

TEST(PilCycles, ExplainListsTheTableRows)
{
    auto t = synthetic(Core::CortexM4F);
    const auto v = t->explain(kSeq + 0x22, 8, true);
    ASSERT_EQ(v.size(), 2u);
    EXPECT_EQ(v[0].text.rfind("vdiv.f32", 0), 0u);
    EXPECT_DOUBLE_EQ(v[0].cycles, 14.0);
    EXPECT_EQ(v[1].text.rfind("vsqrt.f32", 0), 0u);
    EXPECT_DOUBLE_EQ(v[1].cycles, 14.0);
}

TEST(PilCycles, StageSplitsAtTheStoringInstruction)
{
    auto t = synthetic(Core::CortexM4F);
    t->set_stage_marker(kMarker);
    const IsrCost c = t->run_counted(kStage | 1, kStack, 1000);
    EXPECT_DOUBLE_EQ(c.cycles, 7.0);
    EXPECT_DOUBLE_EQ(c.stage[0].cycles, 4.0);   // ldr, movs, str
    EXPECT_EQ(c.stage[0].instructions, 3u);
    EXPECT_DOUBLE_EQ(c.stage[2].cycles, 3.0);   // adds, adds, wfi
    EXPECT_EQ(c.stage[2].instructions, 3u);
    uint32_t m = 0;
    t->read(kMarker, &m, 4);
    EXPECT_EQ(m, 2u);
}

TEST(PilCycles, SeveralStoresInABlockAreToldApartByTheirOperands)
{
    auto t = synthetic(Core::CortexM4F);
    t->set_stage_marker(kMarker);
    for (int run = 0; run < 2; ++run) {
        const IsrCost c = t->run_counted((kStage + 0x10) | 1, kStack, 1000);
        EXPECT_DOUBLE_EQ(c.cycles, 9.0);
        EXPECT_DOUBLE_EQ(c.stage[0].cycles, 4.0);
        EXPECT_DOUBLE_EQ(c.stage[1].cycles, 3.0);
        EXPECT_EQ(c.stage[1].instructions, 3u);
        EXPECT_DOUBLE_EQ(c.stage[3].cycles, 2.0);
        EXPECT_EQ(c.stage[3].instructions, 2u);
        EXPECT_DOUBLE_EQ(stage_sum(c), c.cycles);
        EXPECT_EQ(stage_insns(c), c.instructions);
    }
}

TEST(PilCycles, AnUnresolvedStoreSplitsExactlyFromTheSecondRun)
{
    auto t = synthetic(Core::CortexM4F);
    t->set_stage_marker(kMarker);
    // first run: the marker written by an STM in a block with two stores: not resolved from the
    // operands, the split falls at the block's end
    const IsrCost a = t->run_counted((kStage + 0x24) | 1, kStack, 1000);
    EXPECT_DOUBLE_EQ(a.cycles, 9.0);
    EXPECT_DOUBLE_EQ(a.stage[0].cycles, 9.0);
    // then the block runs with a code hook (exact PC): the split is at the STM
    const IsrCost b = t->run_counted((kStage + 0x24) | 1, kStack, 1000);
    EXPECT_DOUBLE_EQ(b.cycles, 9.0);
    EXPECT_DOUBLE_EQ(b.stage[0].cycles, 7.0);
    EXPECT_EQ(b.stage[0].instructions, 5u);
    EXPECT_DOUBLE_EQ(b.stage[4].cycles, 2.0);
    EXPECT_EQ(b.stage[4].instructions, 2u);
}

TEST(PilCycles, FpBeforeCpacrIsTheNocpFaultOnTheM4)
{
    auto t = synthetic(Core::CortexM4F);
    try {
        t->run_counted(kSeq | 1, kStack, 1000);
        FAIL() << "no RunError";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("CPACR"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("0x112"), std::string::npos) << e.what();   // the vmov
    }
}

TEST(PilCycles, FpWithFpexcOffIsAnInvalidInstructionOnTheR5)
{
    auto t = synthetic(Core::CortexR5F);
    try {
        t->run_counted(kSeq, kStack, 1000);
        FAIL() << "no RunError";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("FPEXC"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("0x120"), std::string::npos) << e.what();   // the vmov d0, r0, r1
    }
}

TEST(PilCycles, InstructionBudgetAndUnmappedAccessesStopTheRun)
{
    for (Core core : {Core::CortexM4F, Core::CortexR5F}) {
        auto t = synthetic(core);
        try {
            t->run_counted((kMisc + 0x0c) | 1, kStack, 5000);
            FAIL() << "no RunError";
        } catch (const RunError& e) {
            EXPECT_NE(std::string(e.what()).find("exceeded 5000 instructions"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("0x300c"), std::string::npos) << e.what();
        }
        try {
            t->run_counted(kMisc | 1, kStack, 5000);
            FAIL() << "no RunError";
        } catch (const RunError& e) {
            EXPECT_NE(std::string(e.what()).find("read from unmapped address 0x30000000"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("PC 0x3004"), std::string::npos) << e.what();
        }
    }
}

TEST(PilCycles, TotalsAccumulate)
{
    auto t = synthetic(Core::CortexM4F);
    t->run_counted(kSetup | 1, kStack, 1000);
    const StageCycles before = t->total();
    t->run_counted(kSeq | 1, kStack, 1000);
    EXPECT_DOUBLE_EQ(t->total().cycles - before.cycles, 65.0);
    EXPECT_EQ(t->total().instructions - before.instructions, 23u);
    EXPECT_EQ(t->isr_total().instructions, 0u);   // no ISR taken
}
