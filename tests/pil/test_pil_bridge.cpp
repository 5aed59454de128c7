// A bridge that stops (issue 29, item 4), on the cross-built drive images in the emulator
// (sim/pil): the AM263x (Cortex-R5F) and the generic Cortex-M4F port, each booted to its idle and
// run period by period (boundary, control ISR, background loop) as mcsim does, its outputs then
// enabled by hand (the trip zone / PWM CTRL.OE cleared, as the drive would on a start command):
//  - a data abort and an undefined instruction injected where the background loop resumes: the
//    core takes the exception (Target::set_fault_entry), its handler forces the trip, and the
//    cycles from the first injected instruction to the handler's park are at most kFaultCycles;
//  - the watchdog: healthy running kicks it; a stalled control ISR (the interrupt no longer
//    taken) or a hung background loop (the ISR still taken) lets it expire within its timeout
//    plus a period, and its expiry turns the outputs off.
// On the code before this change each fails: the handlers looped without tripping (the run
// exceeds its instruction budget with the outputs still on) and no watchdog ran.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <fstream>
#include <string>

#include "pil.hpp"

extern "C" {
#include "mc/monitor.h"
}

using namespace mcsim::pil;

namespace {

// Measured (the cycle model, from the first injected instruction to the handler's WFI, the
// exception entry included): R5F 58 (data abort) / 55 (undefined), M4F 23 / 18. The trip's last
// store comes a few cycles before the park, so the outputs are off within this bound.
constexpr double kFaultCycles = 60.0;
constexpr uint64_t kBoot = 200'000'000, kRun = 20'000'000;

#ifdef PIL_BRIDGE_AM263X
const std::string kAm263x = PIL_BRIDGE_AM263X;
#else
const std::string kAm263x;
#endif
#ifdef PIL_BRIDGE_GENERIC
const std::string kGeneric = PIL_BRIDGE_GENERIC;
#else
const std::string kGeneric;
#endif

// ePWM0-2 TZCLR (0x12E) and the generic PWM CTRL: the outputs switching, as after a start command
constexpr uint32_t kEpwm0 = 0x50000000u, kTzclr = 0x12Eu, kTzOst = 0x4u;
constexpr uint32_t kGenPwmCtrl = 0x40000000u;

struct Drive {
    std::unique_ptr<Target> t;
    uint32_t time_us = 0, period_us = 0;

    explicit Drive(const std::string& elf)
    {
        t = Target::load(elf);
        t->set_fault_entry(true);
        t->reset_and_run_to_idle(kBoot);
        EXPECT_EQ(mon(offsetof(mc_monitor_t, boot)), 1u) << "the image did not boot";
        period_us = static_cast<uint32_t>(t->peripherals().pwm_period_s() * 1e6 + 0.5);
    }
    uint32_t mon(size_t off)
    {
        uint32_t v = 0;
        t->read(t->symbol("mc_monitor") + static_cast<uint32_t>(off), &v, 4);
        return v;
    }
    void outputs_on()
    {
        if (t->port() == "am263x") {
            for (uint32_t m = 0; m < 3; ++m) t->peripherals().write(kEpwm0 + 0x1000u * m + kTzclr, 2, kTzOst | 1u);
        } else {
            t->peripherals().write(kGenPwmCtrl, 4, 3u);
        }
        ASSERT_TRUE(t->outputs().enabled);
    }
    // One period: the boundary, then (each optional) the control ISR and the background loop.
    void period(bool isr, bool background)
    {
        time_us += period_us;
        PeriphInputs in;
        in.adc_i[0] = in.adc_i[1] = in.adc_i[2] = 2048;
        in.adc_vdc = 2000;
        in.time_us = time_us;
        t->period_boundary(in);
        IsrCost c;
        if (isr) t->take_irq(&c, kRun);
        if (background) t->run_background_to_idle(kRun);
    }
    // Thumb code at the PC where the background loop resumes.
    void inject(const uint16_t* code, size_t n)
    {
        if (t->core() == Core::CortexR5F) {
            ASSERT_NE(t->reg(16) & 0x20u, 0u) << "the idle loop is not Thumb code";
        }
        t->write(t->reg(15), code, 2 * n);
    }
    // The injected code run as the background: the exception taken, its handler to the park.
    double run_fault(const uint16_t* code, size_t n)
    {
        outputs_on();
        inject(code, n);
        const double before = t->total().cycles;
        t->run_background_to_idle(kRun);
        const double cycles = t->total().cycles - before;
        EXPECT_EQ(t->faults_taken(), 1u);
        EXPECT_FALSE(t->outputs().enabled) << "the fault handler left the outputs on";
        return cycles;
    }
};

std::vector<std::string> images()
{
    std::vector<std::string> v;
    for (const auto& p : {kAm263x, kGeneric})
        if (!p.empty() && std::ifstream(p).good()) v.push_back(p);
    return v;
}

// movs r0, #15; mvns r0, r0; ldr r1, [r0]: a load from 0xFFFFFFF0, outside every memory
const uint16_t kDataAbort[] = {0x200F, 0x43C0, 0x6801};
// udf #0
const uint16_t kUndef[] = {0xDE00};

}  // namespace

TEST(PilBridge, DataAbortTripsTheOutputs)
{
    if (images().empty()) GTEST_SKIP() << "no cross-built drive image";
    for (const auto& elf : images()) {
        SCOPED_TRACE(elf);
        Drive d(elf);
        for (int k = 0; k < 20; ++k) d.period(true, true);
        const double cy = d.run_fault(kDataAbort, 3);
        std::printf("%s: data abort -> outputs off and parked in %.1f cycles\n", d.t->port().c_str(), cy);
        EXPECT_LE(cy, kFaultCycles);
        if (d.t->core() == Core::CortexR5F) {
            EXPECT_EQ(d.t->reg(16) & 0x1Fu, 0x17u);   // ABT mode
            EXPECT_NE(d.t->reg(16) & 0x80u, 0u);      // IRQs masked: the control loop is over
        } else {
            EXPECT_EQ(d.t->reg(16) & 0x1FFu, 3u);     // HardFault
        }
        // the control interrupt is no longer taken, and the outputs stay off
        d.period(true, true);
        EXPECT_FALSE(d.t->outputs().enabled);
    }
}

TEST(PilBridge, UndefinedInstructionTripsTheOutputs)
{
    if (images().empty()) GTEST_SKIP() << "no cross-built drive image";
    for (const auto& elf : images()) {
        SCOPED_TRACE(elf);
        Drive d(elf);
        for (int k = 0; k < 20; ++k) d.period(true, true);
        const double cy = d.run_fault(kUndef, 1);
        std::printf("%s: undefined instruction -> outputs off and parked in %.1f cycles\n", d.t->port().c_str(), cy);
        EXPECT_LE(cy, kFaultCycles);
        if (d.t->core() == Core::CortexR5F) {
            EXPECT_EQ(d.t->reg(16) & 0x1Fu, 0x1Bu);   // UND mode
        } else {
            EXPECT_EQ(d.t->reg(16) & 0x1FFu, 3u);     // UsageFault escalated to HardFault
        }
    }
}

// The watchdog's expired flag: RTIWDSTATUS.DWDST of WDT0 / GEN_WDT STS.EXP.
static bool expired(Drive& d)
{
    if (d.t->port() == "am263x") return (d.t->peripherals().read(0x52100098u, 4) & 0x2u) != 0;
    return (d.t->peripherals().read(0x4000500Cu, 4) & 0x1u) != 0;
}

// The periods until the watchdog expires with the given parts of the loop running (0: not
// within `limit`).
static int periods_to_expiry(Drive& d, bool isr, bool background, int limit)
{
    for (int k = 1; k <= limit; ++k) {
        d.period(isr, background);
        if (expired(d)) return k;
    }
    return 0;
}

TEST(PilBridge, WatchdogTripsAStalledControlLoop)
{
    if (images().empty()) GTEST_SKIP() << "no cross-built drive image";
    for (const auto& elf : images()) {
        SCOPED_TRACE(elf);
        // timeouts: AM263x (29 + 1) x 2^13 / 25 MHz = 9830.4 us, generic 10000 us
        const double timeout_us = elf == kAm263x ? 30.0 * 8192.0 / 25.0 : 10000.0;
        for (int stall = 0; stall < 3; ++stall) {   // 0: healthy, 1: ISR stalled, 2: background hung
            SCOPED_TRACE(stall);
            Drive d(elf);
            for (int k = 0; k < 20; ++k) d.period(true, true);
            EXPECT_FALSE(expired(d));
            // the outputs on: the ISR-stalled drive cannot turn them off itself, only the expiry can
            if (stall == 1) d.outputs_on();
            const int limit = static_cast<int>(3.0 * timeout_us / d.period_us);
            const int n = periods_to_expiry(d, stall != 1, stall != 2, limit);
            if (stall == 0) {
                EXPECT_EQ(n, 0) << "a healthy loop let the watchdog expire";
                EXPECT_EQ(d.mon(offsetof(mc_monitor_t, isr_count)), static_cast<uint32_t>(20 + limit));
                continue;
            }
            std::printf("%s: %s -> watchdog expired after %d periods of %u us\n", d.t->port().c_str(),
                        stall == 1 ? "ISR stalled" : "background hung", n, d.period_us);
            ASSERT_GT(n, 0);
            EXPECT_GE(n * static_cast<double>(d.period_us), timeout_us - d.period_us);
            EXPECT_LE(n * static_cast<double>(d.period_us), timeout_us + d.period_us);
            EXPECT_FALSE(d.t->outputs().enabled) << "the expiry left the outputs on";
        }
    }
}

// A CANopen store (0x1010 sub 1 "save") on the AM263x image while the control ISR runs: the
// model's S25FL128S keeps each 64 KiB sector erase busy for ~131 ms (sim/pil/dev_am263x.cpp), far
// beyond the watchdog's 9.83 ms, so the background loop waits in the NVM driver across many
// periods. Each period it gets at most the period's core cycles (400 MHz) as instructions and is
// preempted by the ISR, as on the part. The store must succeed (SDO response 0x60) without the
// watchdog expiring. Before the NVM driver's waits serviced the watchdog (hal_wdg_service) it
// expired 100 periods (its 9.83 ms) into the store, which never answered.
TEST(PilBridge, WatchdogHoldsThroughAFlashStore)
{
    if (kAm263x.empty() || !std::ifstream(kAm263x).good()) GTEST_SKIP() << "no cross-built AM263x image";
    Drive d(kAm263x);
    for (int k = 0; k < 20; ++k) d.period(true, true);
    CanFrame f;
    f.id = 0x601;   // SDO request to node 1: expedited download of 4 bytes, 0x1010 sub 1, "save"
    f.dlc = 8;
    const uint8_t req[8] = {0x23, 0x10, 0x10, 0x01, 's', 'a', 'v', 'e'};
    std::copy(req, req + 8, f.data);
    ASSERT_TRUE(d.t->peripherals().can_deliver(f));
    const uint64_t slice = uint64_t{d.period_us} * 400u;
    const int limit = static_cast<int>(2'000'000 / d.period_us);   // 2 s of the plant's time
    int answered = 0, preempted = 0;
    uint8_t reply = 0;
    for (int k = 1; k <= limit && answered == 0; ++k) {
        d.time_us += d.period_us;
        PeriphInputs in;
        in.adc_i[0] = in.adc_i[1] = in.adc_i[2] = 2048;
        in.adc_vdc = 2000;
        in.time_us = d.time_us;
        d.t->period_boundary(in);
        IsrCost c;
        ASSERT_TRUE(d.t->take_irq(&c, kRun)) << "the control ISR was not taken at period " << k;
        if (!d.t->run_background_for(slice)) ++preempted;
        ASSERT_FALSE(expired(d)) << "the watchdog expired " << k << " periods into the store";
        CanFrame r;
        while (d.t->peripherals().can_take(r))
            if (r.id == 0x581) {
                answered = k;
                reply = r.data[0];
            }
    }
    std::printf("am263x: store over CANopen answered after %d periods of %u us (%d preempted), watchdog held\n",
                answered, d.period_us, preempted);
    ASSERT_GT(answered, 0) << "no SDO response to the store";
    EXPECT_EQ(reply, 0x60u) << "the store was refused (SDO abort)";
    // the erase did take the part's time: many watchdog timeouts long
    EXPECT_GT(answered * static_cast<double>(d.period_us), 131000.0);
    EXPECT_EQ(d.mon(offsetof(mc_monitor_t, isr_count)), static_cast<uint32_t>(20 + answered));
}
