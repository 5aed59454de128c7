// The firmware on the host HAL port (drive_target.hpp).
#include <algorithm>
#include <stdexcept>

#include "drive_target.hpp"

extern "C" {
#include "hal_host/host.h"
#include "mc/co.h"
}

namespace mcsim {

namespace {

class HostDrive final : public DriveTarget {
public:
    HostDrive(const Scenario& sc, const DriveSetup& ds, double ts) : ts_(ts)
    {
        hal_host_pwm_init(&pwm_, static_cast<float>(ts), static_cast<float>(sc.f("inverter.dead_time_s")));
        qep_.counts_per_rev = 4u * static_cast<uint32_t>(sc.i("sensors.encoder_lines"));
        if (sc.i("inverter.pwm_counts") > 0)
            hal_host_pwm_set_counts(&pwm_, static_cast<uint32_t>(sc.i("inverter.pwm_counts")),
                                    sc.s("inverter.pwm_compare") == "off_time");
        hal_host_can_init(&can_);
        if (!mc_drive_init(drive_.get(), link_.get(), &ds.cfg, &adc_, &pwm_, &qep_))
            throw ScenarioError(explain_config_error(sc, *mc_drive_config_error(drive_.get())));
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
        if (k % 10 == 0) {
            mc_drive_background(drive_.get());
            if (co_) mc_co_step(co_.get(), static_cast<uint32_t>(static_cast<double>(k) * ts_ * 1000.0));
        }
    }
    bool attach_canopen(uint8_t node_id, uint16_t heartbeat_ms) override
    {
        const mc_co_cfg_t c = {node_id, heartbeat_ms, 0x00000000u, 0x00000001u, 0x00010000u, 0x00000001u};
        co_ = std::make_unique<mc_co_t>();
        return mc_co_init(co_.get(), &c, &can_, drive_.get());
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

    double ts_;
    std::unique_ptr<mc_co_t> co_;
    hal_pwm_t pwm_{};
    hal_can_t can_{};
    hal_adc_t adc_{};
    hal_qep_t qep_{};
    std::unique_ptr<mc_drive_t> drive_ = std::make_unique<mc_drive_t>();
    std::unique_ptr<mc_drive_link_t> link_ = std::make_unique<mc_drive_link_t>();
};

}  // namespace

std::unique_ptr<DriveTarget> make_host_drive(const Scenario& sc, const DriveSetup& ds, double ts)
{
    return std::make_unique<HostDrive>(sc, ds, ts);
}

}  // namespace mcsim
