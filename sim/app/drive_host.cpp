// The firmware on the host HAL port (drive_target.hpp).
#include <stdexcept>

#include "drive_target.hpp"

extern "C" {
#include "hal_host/host.h"
}

namespace mcsim {

namespace {

class HostDrive final : public DriveTarget {
public:
    HostDrive(const Scenario& sc, const DriveSetup& ds, double ts)
    {
        hal_host_pwm_init(&pwm_, static_cast<float>(ts), static_cast<float>(sc.f("inverter.dead_time_s")));
        qep_.counts_per_rev = 4u * static_cast<uint32_t>(sc.i("sensors.encoder_lines"));
        if (!mc_drive_init(drive_.get(), link_.get(), &ds.cfg, &adc_, &pwm_, &qep_))
            throw ScenarioError(explain_config_error(sc, *mc_drive_config_error(drive_.get())));
    }
    PwmOut pending() const override
    {
        return {{pwm_.shadow[0], pwm_.shadow[1], pwm_.shadow[2]}, pwm_.enabled};
    }
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
    void isr(long k) override
    {
        mc_drive_isr(drive_.get());
        if (k % 10 == 0) mc_drive_background(drive_.get());
    }
    mc_drive_telem_t telemetry() override
    {
        mc_drive_telem_t tm;
        if (!mc_drive_telemetry_read(drive_.get(), &tm)) throw std::runtime_error("telemetry: no consistent snapshot");
        return tm;
    }
    PwmOut outputs() const override
    {
        return {{pwm_.active[0], pwm_.active[1], pwm_.active[2]}, pwm_.enabled};
    }

private:
    hal_pwm_t pwm_{};
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
