// Reader of TI's multicore application image (.appimage) for the processor-in-the-loop's boot
// mode: what TI's secondary bootloader (SBL) writes into memory, and nothing else. The format
// (TexasInstruments/mcupsdk-core, docs_src/docs/api_guide/components/tools/tools_boot.md;
// source/drivers/bootloader/bootloader_priv.h; bootloader.c Bootloader_parseMultiCoreAppImage,
// Bootloader_rprcImageLoad): a meta header "MSTR", file count, device id, reserved; per file a
// core id and the offset of its RPRC image; reserved, "MEND". Each RPRC image: "RPRC", entry,
// reserved, section count, version; per section address, reserved, size, CRC (reserved),
// reserved, then the bytes, which the SBL copies to that address. Our build writes it with
// scripts/mc_bootimage.py.
#pragma once
#include <cstdint>
#include <string>
#include <vector>
#include "pil.hpp"

namespace mcsim::pil {

struct BootCore {
    uint32_t core_id = 0;            // RPRC core id (AM263x: 0 = R5FSS0-0)
    uint32_t entry = 0;              // the RPRC entry (the AM263x SBL resets its own core to 0)
    std::vector<Segment> sections;   // at their addresses, in file order
};

struct BootImage {
    std::string path;
    uint32_t dev_id = 0;
    std::vector<BootCore> cores;
};

// True when the file starts with the meta header magic "MSTR".
bool is_boot_image(const std::string& path);
// Reads and checks the image as the SBL parses it; throws LoadError naming the file and the
// reason (magics, counts, offsets and sizes inside the file, bytes after the last section).
BootImage read_boot_image(const std::string& path);

}  // namespace mcsim::pil
