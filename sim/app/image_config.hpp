// `mcsim image-config`: the scenario's drive configuration (parameters, estimator model, flux map)
// written into a firmware image's configuration area (.mc_config, mc/store.h), as flashed: the
// image then boots with that motor's configuration instead of the defaults.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "scenario.hpp"

extern "C" {
#include "mc/drive.h"
}

namespace mcsim {

// The configuration area's bytes for a scenario (the records the image decodes at boot).
std::vector<uint8_t> config_area_bytes(const Scenario& sc);
// The area (mc_config_area_t) for a drive configuration: the records, then the map in place.
std::vector<uint8_t> config_area_bytes(const mc_drive_cfg_t& cfg, const std::string& origin);
// Copy the ELF at in_elf to out_elf with its .mc_config section replaced by `area`. Throws
// ScenarioError naming the file when it is not a 32-bit little-endian ELF with that section of
// the right size.
void patch_image_config(const std::string& in_elf, const std::string& out_elf, const std::vector<uint8_t>& area);

}  // namespace mcsim
