// Scenario runner: plant + sensors + host HAL + the firmware drive, one control period at a time,
// exactly in the order the target runs: PWM latch at the period boundary, ADC/QEP sample, ISR,
// plant integration over the period with the latched duties.
#pragma once
#include <string>
#include "drive_setup.hpp"
#include "scenario.hpp"

namespace mcsim {

struct RunOptions {
    std::string out_dir;      // trace.csv and metrics.json go here ("" = write nothing)
    bool progress = false;    // progress line on stderr
    std::string pil_elf;      // run this cross-built image under processor-in-the-loop ("" = host build)
    std::string can;          // "socketcand:HOST:PORT" or "socketcan:IFACE": the drive on a CAN bus
    double realtime = 0;      // > 0: pace simulated time to wall time x this factor (1 = real time)
    std::string nvm_file;     // the drive's NVM kept in this file across runs (host build)
};

struct RunSummary {
    std::string metrics_json;
    double sim_time_s = 0, wall_time_s = 0, realtime_factor = 0;
    double isr_ns_mean = 0;   // wall time of mc_drive_isr per call (noisy; for bench)
    double plant_ns_mean = 0; // wall time of Plant::step_period per call
    long periods = 0;
};

RunSummary run_scenario(const Scenario& sc, const RunOptions& opt);
// Everything run_scenario checks before it runs (preset, plant, the drive's configuration as the
// firmware will validate it); throws ScenarioError.
void check_scenario(const Scenario& sc);
// The drive's configuration for a scenario (parameters, the estimator's model and map), as
// run_scenario hands it to the drive.
DriveSetup drive_setup_for(const Scenario& sc);
// The fault table (mc/faults.h) as docs/protection.md shows it (`mcsim faults`).
std::string faults_markdown();

}  // namespace mcsim
