// TI multicore application image reader (bootimage.hpp).
#include "bootimage.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

namespace mcsim::pil {
namespace {

constexpr uint32_t kMetaStart = 0x5254534Du;   // "MSTR", BOOTLOADER_META_HDR_MAGIC_STR
constexpr uint32_t kMetaEnd = 0x444E454Du;     // "MEND", BOOTLOADER_META_HDR_MAGIC_END
constexpr uint32_t kRprcMagic = 0x43525052u;   // "RPRC", BOOTLOADER_RPRC_MAGIC_NUMBER
constexpr uint32_t kMaxFiles = 10;             // BOOTLOADER_MAX_INPUT_FILES

std::string hex(uint32_t v)
{
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

std::vector<uint8_t> slurp(const std::string& path)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) throw LoadError(path + ": cannot open the file (" + std::strerror(errno) + ")");
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

}  // namespace

bool is_boot_image(const std::string& path)
{
    std::ifstream f(path, std::ios::binary);
    char m[4] = {};
    return f.read(m, 4) && std::memcmp(m, "MSTR", 4) == 0;
}

BootImage read_boot_image(const std::string& path)
{
    const std::vector<uint8_t> b = slurp(path);
    auto fail = [&](const std::string& why) -> LoadError { return LoadError(path + ": " + why); };
    auto u32 = [&](size_t off) -> uint32_t {
        if (off > b.size() || b.size() - off < 4) throw fail("truncated at offset " + std::to_string(off));
        return static_cast<uint32_t>(b[off]) | static_cast<uint32_t>(b[off + 1]) << 8 |
               static_cast<uint32_t>(b[off + 2]) << 16 | static_cast<uint32_t>(b[off + 3]) << 24;
    };
    BootImage img;
    img.path = path;
    if (u32(0) != kMetaStart) throw fail("not a multicore boot image (no \"MSTR\" meta header)");
    const uint32_t nfiles = u32(4);
    img.dev_id = u32(8);
    if (nfiles == 0 || nfiles > kMaxFiles)
        throw fail(std::to_string(nfiles) + " files in the meta header (the SBL takes 1.." + std::to_string(kMaxFiles) + ")");
    const size_t end_off = 16 + 8 * static_cast<size_t>(nfiles);
    if (u32(end_off + 4) != kMetaEnd) throw fail("no \"MEND\" after the meta header's " + std::to_string(nfiles) + " entries");
    size_t last = end_off + 8;
    for (uint32_t k = 0; k < nfiles; ++k) {
        BootCore c;
        c.core_id = u32(16 + 8 * k);
        size_t p = u32(20 + 8 * k);
        if (u32(p) != kRprcMagic) throw fail("core " + std::to_string(c.core_id) + ": no \"RPRC\" at offset " + std::to_string(p));
        c.entry = u32(p + 4);
        const uint32_t nsec = u32(p + 12);
        if (u32(p + 16) != 1) throw fail("core " + std::to_string(c.core_id) + ": RPRC version " + std::to_string(u32(p + 16)));
        p += 20;
        for (uint32_t s = 0; s < nsec; ++s) {
            Segment seg;
            seg.addr = u32(p);
            const uint32_t size = u32(p + 8);
            p += 20;
            if (size > b.size() - p)
                throw fail("core " + std::to_string(c.core_id) + ": section at " + hex(seg.addr) + " (" + std::to_string(size) +
                           " B) runs past the end of the file");
            seg.bytes.assign(b.begin() + static_cast<std::ptrdiff_t>(p), b.begin() + static_cast<std::ptrdiff_t>(p + size));
            p += size;
            c.sections.push_back(std::move(seg));
        }
        last = std::max(last, p);
        img.cores.push_back(std::move(c));
    }
    if (last != b.size()) throw fail(std::to_string(b.size() - last) + " bytes after the last section");
    return img;
}

}  // namespace mcsim::pil
