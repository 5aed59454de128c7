// The firmware on the host HAL port (drive_target.hpp).
#include <algorithm>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "drive_target.hpp"

extern "C" {
#include "hal_host/host.h"
#include "mc/co.h"
}

namespace mcsim {

namespace {

class HostDrive final : public DriveTarget {
public:
    HostDrive(const Scenario& sc, const DriveSetup& ds, double ts, const std::string& nvm_file)
        : ts_(ts), nvm_file_(nvm_file)
    {
        hal_host_pwm_init(&pwm_, static_cast<float>(ts), static_cast<float>(sc.f("inverter.dead_time_s")));
        qep_.counts_per_rev = 4u * static_cast<uint32_t>(sc.i("sensors.encoder_lines"));
        if (sc.i("inverter.pwm_counts") > 0)
            hal_host_pwm_set_counts(&pwm_, static_cast<uint32_t>(sc.i("inverter.pwm_counts")),
                                    sc.s("inverter.pwm_compare") == "off_time");
        hal_host_can_init(&can_);
        // The configuration the drive boots with: the set stored in its NVM (0x1010), else the
        // scenario's, as the firmware image does with its store.
        hal_host_nvm_init(nvm_.get());
        mc_drive_cfg_t cfg = ds.cfg;
        defaults_ = ds.cfg.p;   // a CANopen reset node falls back to these after a restore
        if (!nvm_file_.empty()) {
            load_nvm();
            boot_status_ = mc_co_boot_config(nvm_.get(), &ds.cfg, &cfg, map_.get(), &boot_report_);
            nvm_steps_ = nvm_->steps;
            if (boot_status_ == MC_PSTORE_PARTIAL)   // also in 0x2FF1, the EMCY and 0x1003
                std::fprintf(stderr,
                             "mcsim: --nvm %s: a set stored by another parameter table; %u value(s) at their "
                             "defaults, the first %s (%s)\n",
                             nvm_file_.c_str(), static_cast<unsigned>(boot_report_.dropped),
                             mc_param_table[boot_report_.first].name,
                             boot_report_.reason == MC_STORE_DROP_TYPE ? "another type" : "out of range");
        }
        if (!mc_drive_init(drive_.get(), link_.get(), &cfg, &adc_, &pwm_, &qep_))
            throw ScenarioError(explain_config_error(sc, *mc_drive_config_error(drive_.get())) +
                                (boot_status_ == MC_PSTORE_OK || boot_status_ == MC_PSTORE_FELL_BACK ||
                                         boot_status_ == MC_PSTORE_PARTIAL
                                     ? " (the configuration stored in " + nvm_file_ + ")"
                                     : ""));
        scope_buf_.assign(static_cast<size_t>(sc.i("can.scope_values")), 0.0f);
        mc_scope_init(&scope_, scope_buf_.data(), static_cast<uint32_t>(scope_buf_.size()), static_cast<float>(ts));
    }
    PwmOut pending() const override { return duties(pwm_.shadow, pwm_.cmp_shadow); }
    void boundary(const DriveInputs& in) override
    {
        hal_host_pwm_latch(&pwm_);
        for (int j = 0; j < 3; ++j) adc_.sample.i[j] = in.adc_i[j];
        adc_.sample.vdc = in.adc_vdc;
        adc_.sample.overrun = in.overrun;
        qep_.sample.count = in.qep_count;
        qep_.sample.index_seen = in.qep_index_seen;
        qep_.sample.index_count = in.qep_index_count;
    }
    void command(const mc_drive_cmd_t& cmd) override { mc_drive_command(drive_.get(), &cmd); }
    hal_can_t* can() override { return &can_; }
    void isr(long k) override
    {
        mc_drive_isr(drive_.get());
        if (co_) mc_scope_sample(&scope_, mc_drive_telemetry(drive_.get()));   // the scope runs in the ISR
        if (k % 10 == 0) {
            mc_drive_background(drive_.get());
            if (co_) {
                mc_co_step(co_.get(), static_cast<uint32_t>(static_cast<double>(k) * ts_ * 1000.0));
                if (nvm_->steps != nvm_steps_) save_nvm();   // a store or restore wrote the NVM
            }
        }
    }
    bool attach_canopen(uint8_t node_id, uint16_t heartbeat_ms, bool commands) override
    {
        mc_co_cfg_t c{};
        c.node_id = node_id;
        c.heartbeat_ms = heartbeat_ms;
        c.step_s = static_cast<float>(10.0 * ts_);   // mc_co_step every 10th period
        c.vendor_id = 0x00000000u;
        c.product_code = 0x00000001u;
        c.revision = 0x00020000u;
        c.serial = 0x00000001u;
        co_ = std::make_unique<mc_co_t>();
        if (!mc_co_init(co_.get(), &c, &can_, drive_.get(), nvm_.get(), &scope_, boot_status_)) return false;
        mc_co_set_defaults(co_.get(), &defaults_);
        mc_co_set_boot_report(co_.get(), &boot_report_);
        co_->ds_on = commands;
        return true;
    }
    mc_drive_telem_t telemetry() override
    {
        mc_drive_telem_t tm;
        if (!mc_drive_telemetry_read(drive_.get(), &tm)) throw std::runtime_error("telemetry: no consistent snapshot");
        return tm;
    }
    PwmOut outputs() const override { return duties(pwm_.active, pwm_.cmp_active); }

private:
    // The duties the inverter applies: as written, or from the compare counts (in double, as a
    // PIL port model turns its compare registers into an on-fraction).
    PwmOut duties(const float* d, const uint32_t* cmp) const
    {
        PwmOut o;
        o.enabled = pwm_.enabled;
        const double n = pwm_.counts;
        for (int k = 0; k < 3; ++k) {
            if (pwm_.counts == 0) o.duty[k] = d[k];
            else if (pwm_.off_time) o.duty[k] = (n - std::min<double>(cmp[k], n)) / n;
            else o.duty[k] = std::min(std::max(static_cast<double>(cmp[k]) / n, 0.0), 1.0);
        }
        return o;
    }

    // The NVM file holds the blocks as they are (hal_host's layout); a file of another size is
    // refused rather than guessed at.
    void load_nvm()
    {
        std::ifstream f(nvm_file_, std::ios::binary);
        if (!f) return;   // none yet: an erased NVM
        std::vector<char> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        if (b.size() != hal_host_nvm_bytes(nvm_.get()))
            throw ScenarioError("--nvm " + nvm_file_ + ": " + std::to_string(b.size()) + " bytes, expected " +
                                std::to_string(hal_host_nvm_bytes(nvm_.get())) + " (not an NVM image of this drive)");
        std::memcpy(nvm_->mem, b.data(), b.size());
    }
    void save_nvm()
    {
        nvm_steps_ = nvm_->steps;
        if (nvm_file_.empty()) return;
        const std::string tmp = nvm_file_ + ".tmp";
        {
            std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
            f.write(reinterpret_cast<const char*>(nvm_->mem), hal_host_nvm_bytes(nvm_.get()));
            if (!f) throw std::runtime_error("--nvm: cannot write " + tmp);
        }
        std::filesystem::rename(tmp, nvm_file_);   // whole or not at all
    }

    double ts_;
    std::string nvm_file_;
    std::unique_ptr<hal_nvm_t> nvm_ = std::make_unique<hal_nvm_t>();
    std::unique_ptr<mc_flux_map_t> map_ = std::make_unique<mc_flux_map_t>();
    uint32_t nvm_steps_ = 0;
    mc_pstore_status_t boot_status_ = MC_PSTORE_EMPTY;
    mc_store_report_t boot_report_{0, 0, 0, -1, 0, false};
    mc_params_t defaults_{};
    mc_scope_t scope_{};
    std::vector<float> scope_buf_;
    std::unique_ptr<mc_co_t> co_;
    hal_pwm_t pwm_{};
    hal_can_t can_{};
    hal_adc_t adc_{};
    hal_qep_t qep_{};
    std::unique_ptr<mc_drive_t> drive_ = std::make_unique<mc_drive_t>();
    std::unique_ptr<mc_drive_link_t> link_ = std::make_unique<mc_drive_link_t>();
};

}  // namespace

std::unique_ptr<DriveTarget> make_host_drive(const Scenario& sc, const DriveSetup& ds, double ts,
                                             const std::string& nvm_file)
{
    return std::make_unique<HostDrive>(sc, ds, ts, nvm_file);
}

}  // namespace mcsim
