// A cross-built firmware image under processor-in-the-loop (drive_target.hpp, sim/pil): the
// scenario's configuration goes into the image's configuration area (mc/store.h) as a tool would
// write it before flashing, the core boots from reset to its idle loop, and then every period
// the commands go in and the telemetry comes out through the image's monitor block
// (mc/monitor.h), while the peripheral registers carry the samples and the duties.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "drive_target.hpp"
#include "image_config.hpp"
#include "metrics.hpp"

extern "C" {
#include "hal/stage.h"
#include "hal_host/host.h"
#include "mc/monitor.h"
#include "mc/store.h"
}

#ifdef MCSIM_HAVE_PIL
#include "pil.hpp"
#endif

namespace mcsim {

#ifndef MCSIM_HAVE_PIL

bool pil_available() { return false; }

std::unique_ptr<DriveTarget> make_pil_drive(const std::string& elf, const DriveSetup&, double)
{
    throw ScenarioError("--pil " + elf +
                        ": this mcsim was built without the processor-in-the-loop engine (needs libunicorn-dev and "
                        "libcapstone-dev; scripts/setup.sh installs them)");
}

#else

bool pil_available() { return true; }

namespace {

constexpr uint64_t kBootBudget = 200'000'000;   // instructions from reset to the idle loop
constexpr uint64_t kIsrBudget = 2'000'000;      // one ISR (a runaway loop stops here)
// The background's share of a period, in instructions: the period's cycles at 400 MHz (an upper
// bound for either core). A pass that needs more (a store waiting on a flash erase) is preempted
// by the next ISR and continues, as on the part (Target::run_background_for).
constexpr double kShareHz = 400e6;
const char* const kStageNames[HAL_STAGE_COUNT] = {"entry", "sample", "angle", "references", "current", "modulation"};

struct Stats {
    double sum = 0, max = 0;
    long n = 0;
    void add(double x)
    {
        sum += x;
        max = std::max(max, x);
        ++n;
    }
    double mean() const { return n > 0 ? sum / n : 0.0; }
};

class PilDrive final : public DriveTarget {
public:
    PilDrive(const std::string& elf, const DriveSetup& ds, double ts) : elf_(elf), ts_(ts)
    {
        hal_host_can_init(&can_);
        try {
            t_ = pil::Target::load(elf);
        } catch (const pil::LoadError& e) {
            throw ScenarioError(std::string("--pil: ") + e.what());
        }
        for (const char* sym : {"mc_config_area", "mc_monitor", "hal_stage_reg"})
            if (!t_->has_symbol(sym))
                throw ScenarioError("--pil " + elf + ": not a drive image (no symbol '" + sym +
                                    "'; build firmware/image with the arm-cm4f or am263x preset)");
        // The configuration a tool writes before flashing.
        const std::vector<uint8_t> area = config_area_bytes(ds.cfg, "pil");
        if (t_->symbol_size("mc_config_area") != area.size())
            throw ScenarioError("--pil " + elf + ": its configuration area is " +
                                std::to_string(t_->symbol_size("mc_config_area")) + " bytes, expected " +
                                std::to_string(area.size()) + " (an image of another firmware version)");
        t_->write(t_->symbol("mc_config_area"), area.data(), area.size());
        mon_ = t_->symbol("mc_monitor");
        // The stack is not initialised by the startup code: painted here, its high-water mark
        // is read at the end (the RAM budget counts the stack as sized, this says how much of it
        // the boot, the ISR and the background ever used).
        if (t_->has_symbol("__mc_stack_bottom") && t_->has_symbol("__mc_stack_top")) {
            stack_lo_ = t_->symbol("__mc_stack_bottom");
            stack_hi_ = t_->symbol("__mc_stack_top");
            if (stack_hi_ > stack_lo_ && stack_hi_ - stack_lo_ <= (1u << 20)) {
                const std::vector<uint8_t> paint(stack_hi_ - stack_lo_, kPaint);
                t_->write(stack_lo_, paint.data(), paint.size());
            } else {
                stack_lo_ = stack_hi_ = 0;
            }
        }
        t_->reset_and_run_to_idle(kBootBudget);
        t_->enable_profile(true);   // the ISRs' cycles by function, for the report
        const uint32_t magic = word(offsetof(mc_monitor_t, magic));
        const uint32_t boot = word(offsetof(mc_monitor_t, boot));
        if (magic != MC_MONITOR_MAGIC || word(offsetof(mc_monitor_t, version)) != MC_MONITOR_VERSION)
            throw ScenarioError("--pil " + elf + ": the image's monitor block has another layout (magic/version)");
        const auto sp = static_cast<mc_store_status_t>(word(offsetof(mc_monitor_t, store_params)));
        const auto sm = static_cast<mc_store_status_t>(word(offsetof(mc_monitor_t, store_model)));
        if (boot != 1u || sp != MC_STORE_OK || sm != MC_STORE_OK) {
            std::ostringstream m;
            m << "--pil " << elf << ": the image did not boot with the scenario's configuration (boot " << boot
              << ", parameter record " << mc_store_status_name(sp) << ", model record " << mc_store_status_name(sm)
              << ", refused parameter id " << static_cast<int32_t>(word(offsetof(mc_monitor_t, cfg_err_param)));
            const uint32_t id = word(offsetof(mc_monitor_t, cfg_err_param));
            if (id < MC_PARAM_COUNT) m << " " << mc_param_table[id].name;
            m << ")";
            throw ScenarioError(m.str());
        }
        const double prd = t_->peripherals().pwm_period_s();
        share_ = static_cast<uint64_t>(prd * kShareHz);
        if (!(std::fabs(prd - ts) <= 1e-3 * ts)) {
            std::ostringstream m;
            m << "--pil " << elf << ": the image programmed a PWM period of " << prd * 1e6 << " us, the scenario runs "
              << ts * 1e6 << " us";
            throw ScenarioError(m.str());
        }
    }

    PwmOut pending() const override { return conv(t_->peripherals().pending_outputs()); }
    void boundary(const DriveInputs& in) override
    {
        pil::PeriphInputs p;
        for (int j = 0; j < 3; ++j) p.adc_i[j] = in.adc_i[j];
        p.adc_vdc = in.adc_vdc;
        p.adc_overrun = in.overrun;
        p.qep_count = in.qep_count;
        p.qep_index_seen = in.qep_index_seen;
        p.qep_index_count = in.qep_index_count;
        p.time_us = static_cast<uint32_t>(static_cast<uint64_t>(std::llround(in.t * 1e6)));
        t_->period_boundary(p);
    }
    void command(const mc_drive_cmd_t& cmd) override
    {
        uint32_t w[MC_MONITOR_CMD_WORDS];
        mc_monitor_pack_cmd(&cmd, w);
        t_->write(mon_ + offsetof(mc_monitor_t, cmd), w, sizeof w);
        ++cmd_seq_;
        t_->write(mon_ + offsetof(mc_monitor_t, cmd_seq), &cmd_seq_, 4);
        (void)t_->run_background_for(share_);   // the loop hands it to the drive
    }
    void isr(long k) override
    {
        pil::IsrCost c;
        if (!t_->take_irq(&c, kIsrBudget)) {
            std::ostringstream m;
            m << "pil: the control interrupt was not pending at period " << k
              << " (the image did not enable its ADC end-of-conversion interrupt)";
            throw std::runtime_error(m.str());
        }
        (void)t_->run_background_for(share_);   // telemetry, background work
        if (can_on_) bridge_can();
        last_ = c;
        last_k_ = k;
        have_last_ = true;
    }
    mc_drive_telem_t telemetry() override
    {
        uint32_t w[MC_MONITOR_TM_WORDS];
        t_->read(mon_ + offsetof(mc_monitor_t, tm), w, sizeof w);
        mc_drive_telem_t tm;
        mc_monitor_unpack_telem(w, &tm);
        if (have_last_) {   // the ISR's cost, by the state it ran in
            have_last_ = false;
            if (last_.cycles > all_.max) {
                max_k_ = last_k_;
                max_state_ = tm.state;
                max_iters_ = tm.est_iters;
            }
            all_.add(last_.cycles);
            instr_.add(static_cast<double>(last_.instructions));
            if (tm.state == MC_STATE_RUN) {
                run_.add(last_.cycles);
                for (int s = 0; s < HAL_STAGE_COUNT; ++s) stage_[s].add(last_.stage[s].cycles);
            }
        }
        return tm;
    }
    PwmOut outputs() const override { return conv(t_->outputs()); }

    // The image's CAN controller model (AM263x MCAN) on the simulator's bus: the link reaches it
    // through a host CAN ring, bridged after every period's background run.
    hal_can_t* can() override { return t_->peripherals().can_supported() ? &can_ : nullptr; }
    bool attach_canopen(uint8_t node_id, uint16_t heartbeat_ms, bool commands) override
    {
        (void)commands;   // the image: the last commander heard wins (the runner sends none then)
        if (!t_->peripherals().can_supported()) return false;
        if (node_id != 1 || heartbeat_ms != 1000)
            throw ScenarioError("--pil with --can: the image's CANopen device is node 1 with a 1000 ms heartbeat "
                                "(firmware/image/main.c): set can.node_id = 1 and can.heartbeat_ms = 1000");
        can_on_ = true;
        return true;
    }

    std::vector<std::pair<std::string, std::string>> metrics() const override
    {
        std::vector<std::pair<std::string, std::string>> m;
        m.emplace_back("pil_image", json_string(elf_));
        m.emplace_back("pil_core", json_string(t_->core() == pil::Core::CortexM4F ? "cortex-m4f" : "cortex-r5f"));
        m.emplace_back("pil_port", json_string(t_->port()));
        m.emplace_back("pil_pwm_counts", std::to_string(t_->peripherals().pwm_counts()));
        m.emplace_back("pil_pwm_compare", json_string(t_->peripherals().pwm_off_time() ? "off_time" : "on_time"));
        if (stack_hi_ > stack_lo_) {
            std::vector<uint8_t> st(stack_hi_ - stack_lo_);
            t_->read(stack_lo_, st.data(), st.size());
            size_t untouched = 0;
            while (untouched < st.size() && st[untouched] == kPaint) ++untouched;
            m.emplace_back("stack_size_bytes", std::to_string(st.size()));
            m.emplace_back("stack_used_bytes", std::to_string(st.size() - untouched));
        }
        m.emplace_back("isr_cycles_mean", json_number(all_.mean()));
        m.emplace_back("isr_cycles_max", json_number(all_.max));
        m.emplace_back("isr_cycles_max_at_s", json_number(static_cast<double>(max_k_) * ts_));
        m.emplace_back("isr_cycles_max_state", std::to_string(static_cast<int>(max_state_)));
        m.emplace_back("isr_cycles_max_newton_iters", std::to_string(max_iters_));
        m.emplace_back("isr_instructions_mean", json_number(instr_.mean()));
        m.emplace_back("isr_instructions_max", json_number(instr_.max));
        m.emplace_back("isr_cycles_mean_run", json_number(run_.mean()));
        m.emplace_back("isr_cycles_max_run", json_number(run_.max));
        std::string mean = "{", max = "{";
        for (int s = 0; s < HAL_STAGE_COUNT; ++s) {
            const std::string sep = s > 0 ? ", " : "";
            mean += sep + json_string(kStageNames[s]) + ": " + json_number(stage_[s].mean());
            max += sep + json_string(kStageNames[s]) + ": " + json_number(stage_[s].max);
        }
        // where the cycles go: the functions (self time) taking the most, per ISR on average
        const std::vector<pil::ProfileEntry> prof = t_->profile();
        double total = 0;
        for (const auto& e : prof) total += e.cycles;
        std::string top = "[";
        for (size_t k = 0; k < prof.size() && k < 15; ++k) {
            top += std::string(k > 0 ? ", " : "") + "{\"function\": " + json_string(prof[k].function) +
                   ", \"cycles_per_isr\": " + json_number(all_.n > 0 ? prof[k].cycles / all_.n : 0.0) +
                   ", \"share\": " + json_number(total > 0 ? prof[k].cycles / total : 0.0) + "}";
        }
        m.emplace_back("isr_profile_top", top + "]");
        m.emplace_back("isr_stage_cycles_mean_run", mean + "}");
        m.emplace_back("isr_stage_cycles_max_run", max + "}");
        return m;
    }

private:
    void bridge_can()
    {
        pil::CanFrame f;
        while (t_->peripherals().can_take(f)) {   // the image sent it: onto the bus
            hal_can_frame_t h{};
            h.id = f.id;
            h.ext = f.ext;
            h.rtr = f.rtr;
            h.dlc = f.dlc;
            std::memcpy(h.data, f.data, 8);
            if (!hal_can_send(&can_, &h)) ++can_lost_;
        }
        hal_can_frame_t h;
        while (hal_can_receive(&can_, &h)) {   // from the bus: into the image's RX FIFO
            pil::CanFrame r;
            r.id = h.id;
            r.ext = h.ext;
            r.rtr = h.rtr;
            r.dlc = h.dlc;
            std::memcpy(r.data, h.data, 8);
            if (!t_->peripherals().can_deliver(r)) ++can_lost_;
        }
    }
    hal_can_t can_{};
    bool can_on_ = false;
    unsigned long can_lost_ = 0;

    uint32_t word(size_t off)
    {
        uint32_t w = 0;
        t_->read(mon_ + static_cast<uint32_t>(off), &w, 4);
        return w;
    }
    static PwmOut conv(const pil::PeriphOutputs& o) { return {{o.duty[0], o.duty[1], o.duty[2]}, o.enabled}; }

    std::string elf_;
    std::unique_ptr<pil::Target> t_;
    uint32_t mon_ = 0, cmd_seq_ = 0;
    uint64_t share_ = 0;   // the background's share of a period (kShareHz)
    uint32_t stack_lo_ = 0, stack_hi_ = 0;
    static constexpr uint8_t kPaint = 0xA5;
    pil::IsrCost last_;
    bool have_last_ = false;
    long last_k_ = 0, max_k_ = 0;
    mc_state_t max_state_ = MC_STATE_IDLE;
    int max_iters_ = 0;
    double ts_ = 0;
    Stats all_, run_, instr_, stage_[HAL_STAGE_COUNT];
};

}  // namespace

std::unique_ptr<DriveTarget> make_pil_drive(const std::string& elf, const DriveSetup& ds, double ts)
{
    return std::make_unique<PilDrive>(elf, ds, ts);
}

#endif

}  // namespace mcsim
