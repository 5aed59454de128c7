// The drive as the runner sees it: the firmware built for the host and called directly
// (HostDrive), or a cross-built image executed by the processor-in-the-loop engine (PIL, sim/pil)
// with its peripheral registers backed by the plant. Same calls, same order, one period at a time.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "drive_setup.hpp"

extern "C" {
#include "hal/can.h"
#include "mc/drive.h"
}

namespace mcsim {

struct PwmOut {
    std::array<double, 3> duty{0.5, 0.5, 0.5};
    bool enabled = false;
};

// What the sensors give the drive at a period boundary.
struct DriveInputs {
    uint16_t adc_i[3] = {0, 0, 0};
    uint16_t adc_vdc = 0;
    bool overrun = false;
    uint32_t qep_count = 0;
    bool qep_index_seen = false;
    uint32_t qep_index_count = 0;
    double t = 0;
};

class DriveTarget {
public:
    virtual ~DriveTarget() = default;
    // The duties the coming period will use (the shadow registers about to be latched) and the
    // output enable: what the ADC model needs before the boundary.
    virtual PwmOut pending() const = 0;
    // Period boundary: shadow -> active, the ADC and encoder samples in the registers.
    virtual void boundary(const DriveInputs& in) = 0;
    // The background side publishes the command for the coming ISR.
    virtual void command(const mc_drive_cmd_t& cmd) = 0;
    // The control ISR of period k, then the background's slow work when k % 10 == 0.
    virtual void isr(long k) = 0;
    virtual mc_drive_telem_t telemetry() = 0;
    // The duties in force over the period just started, and the enable.
    virtual PwmOut outputs() const = 0;
    // The drive's CAN controller (the host port's rings), or nullptr where the target has none
    // the simulator can reach.
    virtual hal_can_t* can() { return nullptr; }
    // Run the drive's CANopen device (mc/co.h) in its background loop; false where there is none.
    // commands: the CiA 402 layer commands the drive (else the scenario does).
    virtual bool attach_canopen(uint8_t node_id, uint16_t heartbeat_ms, bool commands)
    {
        (void)node_id;
        (void)heartbeat_ms;
        (void)commands;
        return false;
    }
    // Extra metrics of this target (the PIL's cycle figures), as JSON fields.
    virtual std::vector<std::pair<std::string, std::string>> metrics() const { return {}; }
};

// The firmware built for the host, through the host HAL port.
// nvm_file: the drive's NVM (the CANopen store 0x1010) kept in this file across runs ("" = a fresh
// erased NVM per run); the drive boots with the set stored there, as a real one does.
std::unique_ptr<DriveTarget> make_host_drive(const Scenario& sc, const DriveSetup& ds, double ts,
                                             const std::string& nvm_file = "");
// A firmware image under PIL: the scenario's configuration written into the image's
// configuration area, reset, booted to its idle loop. Bad images: ScenarioError (exit 2).
std::unique_ptr<DriveTarget> make_pil_drive(const std::string& elf, const DriveSetup& ds, double ts);
// Whether this mcsim was built with the PIL engine (libunicorn, libcapstone).
bool pil_available();

}  // namespace mcsim
