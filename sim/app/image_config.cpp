// mcsim image-config (image_config.hpp).
#include "image_config.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

#include "drive_setup.hpp"
#include "runner.hpp"

extern "C" {
#include "mc/store.h"
}

namespace mcsim {

std::vector<uint8_t> config_area_bytes(const mc_drive_cfg_t& cfg, const std::string& origin)
{
    // records (erased where unused), then the map in its own layout (mc_config_area_t; zero
    // without a map, where the records say there is none)
    std::vector<uint8_t> area(MC_CONFIG_AREA_SIZE, 0x00);
    std::fill(area.begin(), area.begin() + MC_CONFIG_RECORDS_SIZE, 0xFF);
    if (mc_store_params_encode(&cfg.p, area.data(), MC_CONFIG_MODEL_OFFSET) == 0 ||
        mc_store_model_encode(&cfg.est, area.data() + MC_CONFIG_MODEL_OFFSET,
                              MC_CONFIG_RECORDS_SIZE - MC_CONFIG_MODEL_OFFSET) == 0)
        throw ScenarioError(origin + ": the configuration does not fit the image's configuration area");
    if (cfg.est.map != nullptr) std::memcpy(area.data() + MC_CONFIG_MAP_OFFSET, cfg.est.map, sizeof(mc_flux_map_t));
    return area;
}

std::vector<uint8_t> config_area_bytes(const Scenario& sc)
{
    const DriveSetup ds = drive_setup_for(sc);
    return config_area_bytes(ds.cfg, sc.origin());
}

namespace {

uint32_t u32(const std::vector<uint8_t>& b, size_t at)
{
    if (at + 4 > b.size()) throw std::out_of_range("elf");
    return static_cast<uint32_t>(b[at]) | static_cast<uint32_t>(b[at + 1]) << 8 | static_cast<uint32_t>(b[at + 2]) << 16 |
           static_cast<uint32_t>(b[at + 3]) << 24;
}

uint16_t u16(const std::vector<uint8_t>& b, size_t at)
{
    if (at + 2 > b.size()) throw std::out_of_range("elf");
    return static_cast<uint16_t>(b[at] | b[at + 1] << 8);
}

}  // namespace

void patch_image_config(const std::string& in_elf, const std::string& out_elf, const std::vector<uint8_t>& area)
{
    std::ifstream f(in_elf, std::ios::binary);
    if (!f) throw ScenarioError("--image " + in_elf + ": cannot read the file");
    std::vector<uint8_t> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    auto fail = [&](const std::string& why) { return ScenarioError("--image " + in_elf + ": " + why); };
    if (b.size() < 52 || std::memcmp(b.data(), "\x7f" "ELF", 4) != 0) throw fail("not an ELF file");
    if (b[4] != 1 || b[5] != 1) throw fail("not a 32-bit little-endian ELF");
    try {
        const uint32_t shoff = u32(b, 32);
        const uint16_t shentsize = u16(b, 46), shnum = u16(b, 48), shstrndx = u16(b, 50);
        if (shentsize < 40 || shstrndx >= shnum) throw fail("no section header table");
        const uint32_t stroff = u32(b, shoff + static_cast<size_t>(shstrndx) * shentsize + 16);
        for (uint16_t k = 0; k < shnum; ++k) {
            const size_t sh = shoff + static_cast<size_t>(k) * shentsize;
            const uint32_t name = u32(b, sh);
            const char* nm = reinterpret_cast<const char*>(b.data() + stroff + name);
            if (stroff + name >= b.size() || std::strncmp(nm, ".mc_config", 11) != 0) continue;
            const uint32_t type = u32(b, sh + 4), off = u32(b, sh + 16), size = u32(b, sh + 20);
            if (type != 1 /* SHT_PROGBITS */ || size != area.size() || static_cast<size_t>(off) + size > b.size())
                throw fail(".mc_config is " + std::to_string(size) + " bytes, expected " + std::to_string(area.size()) +
                           " (an image of another firmware version)");
            std::memcpy(b.data() + off, area.data(), area.size());
            std::ofstream o(out_elf, std::ios::binary);
            if (!o.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size())))
                throw ScenarioError("--out " + out_elf + ": cannot write the file");
            return;
        }
    } catch (const std::out_of_range&) {
        throw fail("truncated ELF");
    }
    throw fail("no .mc_config section (not a drive image: build firmware/image with the arm-cm4f or am263x preset)");
}

}  // namespace mcsim
