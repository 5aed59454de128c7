// The simulated drive on a CAN bus: the host port's CAN rings (hal_host/host.h) bridged to
// - socketcand:HOST:PORT  a socketcand-compatible TCP endpoint (raw mode, channel can0) served on
//                         HOST:PORT, so python-can's `socketcand` interface reaches the running
//                         simulation on machines whose kernel has no CAN;
// - socketcan:IFACE       a raw AF_CAN socket on a kernel interface (vcan0, a USB adapter).
// Pumped once per control period from the runner; never blocks the simulation.
#pragma once
#include <memory>
#include <string>

extern "C" {
#include "hal_host/host.h"
}

namespace mcsim {

class CanLink {
public:
    virtual ~CanLink() = default;
    // Frames the drive queued -> the bus; frames from the bus -> the drive's RX ring.
    // sim_time_s stamps the frames sent to a socketcand client.
    virtual void pump(hal_can_t* can, double sim_time_s) = 0;
    // One line for the user: where the bus is and whether a client is attached.
    virtual std::string describe() const = 0;
};

// spec: "socketcand:HOST:PORT" or "socketcan:IFACE". Bad specs and sockets that cannot be
// opened: ScenarioError (exit 2) with the reason.
std::unique_ptr<CanLink> make_can_link(const std::string& spec);

}  // namespace mcsim
