// ELF32 reader (elf.hpp): the System V ABI's ELF header, program and section headers, symbol
// table; the ARM ELF ABI's build attributes (ARM IHI 0044 "ELF for the Arm Architecture",
// section "Build attributes"; the tags from ARM IHI 0045 "Addenda to, and Errata in, the ABI for
// the Arm Architecture").
#include "elf.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "pil.hpp"

namespace mcsim::pil {
namespace {

constexpr uint8_t kElfClass32 = 1, kElfClass64 = 2;
constexpr uint8_t kElfData2Lsb = 1, kElfData2Msb = 2;
constexpr uint16_t kEtExec = 2, kEtDyn = 3, kEtRel = 1, kEtCore = 4;
constexpr uint16_t kEmArm = 40;
constexpr uint32_t kPtLoad = 1;
constexpr uint32_t kShtSymtab = 2, kShtNobits = 8, kShtArmAttributes = 0x70000003u;

[[noreturn]] void fail(const std::string& path, const std::string& why)
{
    throw LoadError(path + ": " + why);
}

struct Reader {
    const std::vector<uint8_t>& b;
    bool big = false;
    bool has(size_t off, size_t n) const { return off <= b.size() && n <= b.size() - off; }
    uint16_t u16(size_t off) const
    {
        return big ? static_cast<uint16_t>(b[off] << 8 | b[off + 1]) : static_cast<uint16_t>(b[off] | b[off + 1] << 8);
    }
    uint32_t u32(size_t off) const
    {
        if (big)
            return static_cast<uint32_t>(b[off]) << 24 | static_cast<uint32_t>(b[off + 1]) << 16 |
                   static_cast<uint32_t>(b[off + 2]) << 8 | b[off + 3];
        return static_cast<uint32_t>(b[off]) | static_cast<uint32_t>(b[off + 1]) << 8 |
               static_cast<uint32_t>(b[off + 2]) << 16 | static_cast<uint32_t>(b[off + 3]) << 24;
    }
};

std::string hex(uint32_t v)
{
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

// ULEB128 from p (bounded by end); false when it runs off the end.
bool uleb(const uint8_t*& p, const uint8_t* end, uint32_t* out)
{
    uint32_t v = 0;
    unsigned shift = 0;
    while (p < end) {
        const uint8_t c = *p++;
        if (shift < 32) v |= static_cast<uint32_t>(c & 0x7F) << shift;
        shift += 7;
        if ((c & 0x80) == 0) {
            *out = v;
            return true;
        }
    }
    return false;
}

bool ntbs(const uint8_t*& p, const uint8_t* end, std::string* out)
{
    const uint8_t* s = p;
    while (p < end && *p != 0) ++p;
    if (p >= end) return false;
    if (out) out->assign(reinterpret_cast<const char*>(s), static_cast<size_t>(p - s));
    ++p;
    return true;
}

// The File-scope attributes of the "aeabi" subsection (ARM IHI 0044, "Build attributes").
void parse_attributes(const uint8_t* p, const uint8_t* end, ElfImage* img)
{
    if (p >= end || *p != 'A') return;   // format-version 'A'
    ++p;
    while (end - p >= 4) {
        uint32_t len = static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
                       static_cast<uint32_t>(p[3]) << 24;
        if (len < 4 || len > static_cast<size_t>(end - p)) return;
        const uint8_t* sub_end = p + len;
        const uint8_t* q = p + 4;
        std::string vendor;
        if (!ntbs(q, sub_end, &vendor)) return;
        if (vendor == "aeabi") {
            while (sub_end - q >= 5) {
                const uint8_t tag = *q;
                const uint32_t size = static_cast<uint32_t>(q[1]) | static_cast<uint32_t>(q[2]) << 8 |
                                      static_cast<uint32_t>(q[3]) << 16 | static_cast<uint32_t>(q[4]) << 24;
                if (size < 5 || size > static_cast<size_t>(sub_end - q)) break;
                const uint8_t* a = q + 5;
                const uint8_t* a_end = q + size;
                if (tag == 1) {   // Tag_File: the whole file's attributes
                    img->has_attributes = true;
                    while (a < a_end) {
                        uint32_t t = 0, v = 0;
                        if (!uleb(a, a_end, &t)) break;
                        if (t == 4 || t == 5 || (t > 32 && (t & 1) != 0)) {   // NTBS-valued
                            std::string s;
                            if (!ntbs(a, a_end, &s)) break;
                            if (t == 5) img->cpu_name = s;
                        } else if (t == 32) {   // Tag_compatibility: ULEB flag, NTBS vendor
                            if (!uleb(a, a_end, &v) || !ntbs(a, a_end, nullptr)) break;
                        } else {
                            if (!uleb(a, a_end, &v)) break;
                            if (t == 6) img->cpu_arch = static_cast<int>(v);
                            if (t == 7) img->cpu_arch_profile = static_cast<int>(v);
                        }
                    }
                }
                q = a_end;
            }
        }
        p = sub_end;
    }
}

}  // namespace

std::string elf_machine_name(uint16_t m)
{
    static const struct {
        uint16_t id;
        const char* name;
    } names[] = {{0, "EM_NONE"},      {2, "EM_SPARC"},    {3, "EM_386"},        {4, "EM_68K"},
                 {8, "EM_MIPS"},      {20, "EM_PPC"},     {21, "EM_PPC64"},     {22, "EM_S390"},
                 {40, "EM_ARM"},      {42, "EM_SH"},      {43, "EM_SPARCV9"},   {50, "EM_IA_64"},
                 {62, "EM_X86_64"},   {83, "EM_AVR"},     {94, "EM_XTENSA"},    {105, "EM_MSP430"},
                 {140, "EM_TI_C6000"}, {141, "EM_TI_C2000"}, {142, "EM_TI_C5500"}, {183, "EM_AARCH64"},
                 {243, "EM_RISCV"},   {258, "EM_LOONGARCH"}};
    for (const auto& n : names)
        if (n.id == m) return std::string(n.name) + " (" + std::to_string(m) + ")";
    return "machine " + std::to_string(m);
}

bool ElfImage::read_vaddr(uint32_t addr, void* out, size_t n) const
{
    auto* o = static_cast<uint8_t*>(out);
    for (size_t k = 0; k < n; ++k) {
        const uint64_t a = static_cast<uint64_t>(addr) + k;
        bool found = false;
        for (const auto& s : segments) {
            if (a >= s.vaddr && a < static_cast<uint64_t>(s.vaddr) + s.filesz) {
                o[k] = s.data[static_cast<size_t>(a - s.vaddr)];
                found = true;
                break;
            }
        }
        if (!found) return false;
    }
    return true;
}

bool ElfImage::read_paddr(uint32_t addr, void* out, size_t n) const
{
    auto* o = static_cast<uint8_t*>(out);
    for (size_t k = 0; k < n; ++k) {
        const uint64_t a = static_cast<uint64_t>(addr) + k;
        bool found = false;
        for (const auto& s : segments) {
            if (a >= s.paddr && a < static_cast<uint64_t>(s.paddr) + s.filesz) {
                o[k] = s.data[static_cast<size_t>(a - s.paddr)];
                found = true;
                break;
            }
        }
        if (!found) return false;
    }
    return true;
}

ElfImage read_elf(const std::string& path)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) fail(path, std::string("cannot open the file (") + std::strerror(errno) + ")");
    std::vector<uint8_t> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (f.bad()) fail(path, "cannot read the file");
    if (b.size() < 16 || b[0] != 0x7F || b[1] != 'E' || b[2] != 'L' || b[3] != 'F')
        fail(path, b.empty() ? "not an ELF file (empty)" : "not an ELF file (bad magic)");
    const uint8_t cls = b[4], data = b[5];
    if (data != kElfData2Lsb && data != kElfData2Msb)
        fail(path, "not a valid ELF file (EI_DATA " + std::to_string(data) + ")");
    Reader r{b, data == kElfData2Msb};
    // e_machine sits at offset 18 in both ELF classes: say what the file is for before anything
    // else (an x86-64 host executable is "not ARM", not "not 32-bit").
    if (!r.has(0, 20)) fail(path, "truncated ELF header");
    const uint16_t machine = r.u16(18);
    if (machine != kEmArm) {
        fail(path, "not ARM: e_machine is " + elf_machine_name(machine) + (cls == kElfClass64 ? " (a 64-bit ELF)" : "") +
                       "; the PIL runs 32-bit ARM images (EM_ARM, 40)");
    }
    if (cls != kElfClass32)
        fail(path, cls == kElfClass64 ? "not a 32-bit ELF (ELFCLASS64)" : "not a 32-bit ELF (EI_CLASS " + std::to_string(cls) + ")");
    if (data != kElfData2Lsb) fail(path, "not little-endian (ELFDATA2MSB): the PIL runs little-endian images");
    if (!r.has(0, 52)) fail(path, "truncated ELF header");

    ElfImage img;
    img.path = path;
    img.type = r.u16(16);
    img.machine = machine;
    img.entry = r.u32(24);
    img.flags = r.u32(36);
    if (img.type != kEtExec) {
        const char* what = img.type == kEtRel ? "a relocatable object (ET_REL)"
                           : img.type == kEtDyn ? "a shared object (ET_DYN)"
                           : img.type == kEtCore ? "a core dump (ET_CORE)"
                                                 : "not an executable";
        fail(path, std::string("not a linked executable: ") + what + "; link the image (ET_EXEC)");
    }
    const uint32_t phoff = r.u32(28), shoff = r.u32(32);
    const uint16_t phentsize = r.u16(42), phnum = r.u16(44), shentsize = r.u16(46), shnum = r.u16(48);

    // Program headers: the loadable segments.
    if (phnum > 0) {
        if (phentsize < 32 || !r.has(phoff, static_cast<size_t>(phnum) * phentsize))
            fail(path, "truncated or malformed program header table");
        for (uint16_t k = 0; k < phnum; ++k) {
            const size_t o = phoff + static_cast<size_t>(k) * phentsize;
            if (r.u32(o) != kPtLoad) continue;
            ElfSegment s;
            const uint32_t off = r.u32(o + 4);
            s.vaddr = r.u32(o + 8);
            s.paddr = r.u32(o + 12);
            s.filesz = r.u32(o + 16);
            s.memsz = r.u32(o + 20);
            s.flags = r.u32(o + 24);
            if (s.filesz == 0 && s.memsz == 0) continue;
            if (s.filesz > s.memsz) fail(path, "segment at " + hex(s.vaddr) + ": p_filesz > p_memsz");
            if (!r.has(off, s.filesz)) fail(path, "segment at " + hex(s.vaddr) + " runs past the end of the file");
            s.data.assign(b.begin() + static_cast<std::ptrdiff_t>(off),
                          b.begin() + static_cast<std::ptrdiff_t>(off + s.filesz));
            img.segments.push_back(std::move(s));
        }
    }

    // Section headers: the symbol table, the build attributes.
    if (shnum > 0 && shoff != 0) {
        if (shentsize < 40 || !r.has(shoff, static_cast<size_t>(shnum) * shentsize))
            fail(path, "truncated or malformed section header table");
        auto sh = [&](uint32_t k, uint32_t field) { return r.u32(shoff + static_cast<size_t>(k) * shentsize + field); };
        for (uint16_t k = 0; k < shnum; ++k) {
            const uint32_t type = sh(k, 4), off = sh(k, 16), size = sh(k, 20);
            if (type == kShtNobits || !r.has(off, size)) continue;
            if (type == kShtArmAttributes) {
                parse_attributes(b.data() + off, b.data() + off + size, &img);
            } else if (type == kShtSymtab) {
                const uint32_t link = sh(k, 24), entsize = sh(k, 36) ? sh(k, 36) : 16;
                if (link >= shnum || entsize < 16) continue;
                const uint32_t str_off = sh(link, 16), str_size = sh(link, 20);
                if (!r.has(str_off, str_size)) continue;
                for (uint32_t o = off; o + 16 <= off + size; o += entsize) {
                    const uint32_t name = r.u32(o);
                    if (name == 0 || name >= str_size) continue;
                    ElfSymbol s;
                    s.value = r.u32(o + 4);
                    s.size = r.u32(o + 8);
                    s.type = b[o + 12] & 0x0F;
                    s.bind = b[o + 12] >> 4;
                    s.shndx = r.u16(o + 14);
                    if (s.shndx == 0) continue;          // undefined
                    if (s.type == 3 || s.type == 4) continue;   // STT_SECTION, STT_FILE
                    const char* n = reinterpret_cast<const char*>(b.data() + str_off + name);
                    const size_t max = str_size - name;
                    const std::string nm(n, strnlen(n, max));
                    if (nm.empty() || nm[0] == '$') continue;   // mapping symbols $a, $t, $d
                    auto it = img.symbols.find(nm);
                    if (it == img.symbols.end())
                        img.symbols.emplace(nm, s);
                    else if (it->second.bind == 0 && s.bind != 0)   // a global over a local
                        it->second = s;
                }
            }
        }
    }
    return img;
}

}  // namespace mcsim::pil
