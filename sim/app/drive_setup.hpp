// The simulator's side of the drive's parameter table (firmware/app/include/mc/params_table.h):
// the drive keys of the scenario schema are generated from it, and a scenario configures the
// drive by name, with no hand-written mapping. Motor and hardware entries come from the preset
// and the simulator's own sensor and inverter keys.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "mcsim/machine.hpp"
#include "scenario.hpp"

extern "C" {
#include "mc/drive.h"
}

namespace mcsim {

// The drive keys (every table entry but motor.* and hw.*), as scenario key specs.
const std::vector<KeySpec>& drive_key_specs();

// What the runner hands the drive besides the scenario: the estimator's model and map.
struct DriveSetup {
    mc_drive_cfg_t cfg;
    std::unique_ptr<mc_flux_map_t> est_map;  // owned here; the drive keeps a pointer
    mc_params_t resolved;                    // cfg.p with every "auto" derived (mc_drive_build)
    bool estimator = false;                  // the angle source runs a model-based estimator
};

// Defaults the simulator derives from the preset for its sensor keys (a sensor sized for the
// motor): the current span 1.875 x rated (trip 1.5 x rated plus the firmware's 10 % margin,
// rounded up to 1-1.2-1.5-2-2.5-3-4-5-6-8), the DC-link span 1.6 x nominal, rounded up alike.
double default_i_full_scale(const MachineParams& mp);
double default_vdc_full_scale(double vdc_nominal);

// Fills cfg.p from the preset (motor.*), the simulator keys (hw.*: ADC, dead time, encoder,
// DC link, sampling) and every drive key the scenario gives. Throws ScenarioError naming the key.
void set_drive_params(const Scenario& sc, const MachineParams& mp, double vdc, double i_span, double vdc_span,
                      mc_params_t* p);

// mc_drive_build's refusal as a scenario error: the scenario keys behind the parameters, their
// values and the allowed range.
std::string explain_config_error(const Scenario& sc, const mc_param_err_t& e);

// The firmware's whole parameter table as markdown (docs/parameters.md, `mcsim params`).
std::string params_markdown();

// The scenario key behind a firmware parameter (hw.i_span_a -> sensors.i_full_scale_a, ...).
std::string scenario_key_of(int param);

}  // namespace mcsim
