// The PIL loader's checks (sim/pil: Target::load, elf.cpp): every refusal is a LoadError naming
// the file and the reason. ELF files are written here byte by byte (a small ELF32 writer), plus
// /bin/true as a host (x86-64) executable and, when the cross compiler built it, a real ARM image
// without a vector table.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "pil.hpp"

using namespace mcsim::pil;

namespace {

#ifdef PIL_TEST_IMAGES
const std::string kImages = PIL_TEST_IMAGES;
#else
const std::string kImages;
#endif

struct Seg {
    uint32_t vaddr, paddr;
    std::vector<uint8_t> bytes;
    uint32_t memsz;   // 0: = bytes.size()
};

struct Spec {
    uint8_t cls = 1, data = 1;
    uint16_t type = 2, machine = 40;
    uint32_t entry = 0x101;
    std::vector<Seg> segs;
    std::vector<std::pair<std::string, uint32_t>> syms;
    std::vector<uint8_t> attributes;   // .ARM.attributes contents; empty: no such section
};

void put16(std::vector<uint8_t>& b, size_t at, uint16_t v, bool big = false)
{
    if (b.size() < at + 2) b.resize(at + 2);
    b[at] = static_cast<uint8_t>(big ? v >> 8 : v);
    b[at + 1] = static_cast<uint8_t>(big ? v : v >> 8);
}
void put32(std::vector<uint8_t>& b, size_t at, uint32_t v, bool big = false)
{
    if (b.size() < at + 4) b.resize(at + 4);
    for (int k = 0; k < 4; ++k) b[at + static_cast<size_t>(k)] = static_cast<uint8_t>(v >> (big ? 24 - 8 * k : 8 * k));
}

// An ELF32 file: header, program headers, the segments, .symtab/.strtab/.shstrtab and an optional
// .ARM.attributes, the section headers at the end.
std::vector<uint8_t> build(const Spec& s)
{
    const bool big = s.data == 2;
    std::vector<uint8_t> b(52, 0);
    b[0] = 0x7F;
    b[1] = 'E';
    b[2] = 'L';
    b[3] = 'F';
    b[4] = s.cls;
    b[5] = s.data;
    b[6] = 1;
    put16(b, 16, s.type, big);
    put16(b, 18, s.machine, big);
    put32(b, 20, 1, big);
    put32(b, 24, s.entry, big);
    put32(b, 28, 52, big);   // e_phoff
    put16(b, 40, 52, big);
    put16(b, 42, 32, big);
    put16(b, 44, static_cast<uint16_t>(s.segs.size()), big);
    put16(b, 46, 40, big);
    size_t off = 52 + 32 * s.segs.size();
    b.resize(off, 0);
    for (size_t k = 0; k < s.segs.size(); ++k) {
        const Seg& g = s.segs[k];
        const size_t ph = 52 + 32 * k;
        put32(b, ph, 1, big);   // PT_LOAD
        put32(b, ph + 4, static_cast<uint32_t>(off), big);
        put32(b, ph + 8, g.vaddr, big);
        put32(b, ph + 12, g.paddr, big);
        put32(b, ph + 16, static_cast<uint32_t>(g.bytes.size()), big);
        put32(b, ph + 20, g.memsz ? g.memsz : static_cast<uint32_t>(g.bytes.size()), big);
        put32(b, ph + 24, 5, big);
        b.insert(b.end(), g.bytes.begin(), g.bytes.end());
        off = b.size();
    }
    // string and symbol tables
    std::vector<uint8_t> strtab(1, 0), symtab(16, 0);
    for (const auto& [name, value] : s.syms) {
        const size_t e = symtab.size();
        symtab.resize(e + 16, 0);
        put32(symtab, e, static_cast<uint32_t>(strtab.size()), big);
        put32(symtab, e + 4, value, big);
        symtab[e + 12] = 0x11;   // STB_GLOBAL, STT_OBJECT
        put16(symtab, e + 14, 1, big);
        strtab.insert(strtab.end(), name.begin(), name.end());
        strtab.push_back(0);
    }
    const std::string shnames = std::string("\0.symtab\0.strtab\0.shstrtab\0.ARM.attributes\0", 44);
    struct Sec {
        uint32_t name, type, link, entsize;
        std::vector<uint8_t> data;
    };
    std::vector<Sec> secs = {{0, 0, 0, 0, {}},
                             {1, 2, 2, 16, symtab},
                             {9, 3, 0, 0, strtab},
                             {17, 3, 0, 0, std::vector<uint8_t>(shnames.begin(), shnames.end())}};
    if (!s.attributes.empty()) secs.push_back({27, 0x70000003u, 0, 0, s.attributes});
    std::vector<uint32_t> offs;
    for (const auto& sec : secs) {
        offs.push_back(static_cast<uint32_t>(b.size()));
        b.insert(b.end(), sec.data.begin(), sec.data.end());
    }
    while (b.size() % 4) b.push_back(0);
    const uint32_t shoff = static_cast<uint32_t>(b.size());
    for (size_t k = 0; k < secs.size(); ++k) {
        std::vector<uint8_t> sh(40, 0);
        put32(sh, 0, secs[k].name, big);
        put32(sh, 4, secs[k].type, big);
        put32(sh, 16, offs[k], big);
        put32(sh, 20, static_cast<uint32_t>(secs[k].data.size()), big);
        put32(sh, 24, secs[k].link, big);
        put32(sh, 36, secs[k].entsize, big);
        b.insert(b.end(), sh.begin(), sh.end());
    }
    put32(b, 32, shoff, big);
    put16(b, 48, static_cast<uint16_t>(secs.size()), big);
    put16(b, 50, 3, big);
    return b;
}

// "aeabi" File attributes: Tag_CPU_name (5), Tag_CPU_arch (6), Tag_CPU_arch_profile (7).
std::vector<uint8_t> attributes(char profile, const char* cpu, uint8_t arch)
{
    std::vector<uint8_t> file = {1, 0, 0, 0, 0, 5};
    file.insert(file.end(), cpu, cpu + std::strlen(cpu) + 1);
    file.insert(file.end(), {6, arch, 7, static_cast<uint8_t>(profile), 10, 4});   // + Tag_FP_arch
    put32(file, 1, static_cast<uint32_t>(file.size()));
    std::vector<uint8_t> sub = {0, 0, 0, 0, 'a', 'e', 'a', 'b', 'i', 0};
    sub.insert(sub.end(), file.begin(), file.end());
    put32(sub, 0, static_cast<uint32_t>(sub.size()));
    std::vector<uint8_t> a;
    a.reserve(1 + sub.size());
    a.push_back('A');
    for (uint8_t c : sub) a.push_back(c);
    return a;
}

// A Cortex-M image of the generic port: vector table (SP 0x20001000, reset 0x101), "generic" at
// 0x80, a loop at 0x100.
Spec good_m()
{
    Spec s;
    std::vector<uint8_t> img(0x104, 0);
    put32(img, 0, 0x20001000u);
    put32(img, 4, 0x101u);
    std::memcpy(img.data() + 0x80, "generic", 8);
    img[0x100] = 0xFE;   // b.n .
    img[0x101] = 0xE7;
    s.segs.push_back({0, 0, img, 0});
    s.segs.push_back({0x20000000u, 0x20000000u, {}, 0x100});   // .bss-like
    s.syms = {{"hal_port_name", 0x80}, {"hal_stage_reg", 0x20000000u}};
    s.attributes = attributes('M', "Cortex-M4", 13);
    return s;
}

Spec good_r()
{
    Spec s = good_m();
    put32(s.segs[0].bytes, 0, 0xEA00003Eu);   // b 0x100
    put32(s.segs[0].bytes, 4, 0xEAFFFFFEu);
    s.entry = 0;
    s.attributes = attributes('R', "Cortex-R5", 10);
    return s;
}

std::string write(const std::string& name, const std::vector<uint8_t>& bytes)
{
    const std::string p = ::testing::TempDir() + "pil_loader_" + name;
    std::ofstream f(p, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    return p;
}

// The LoadError of loading `path`, or "" if it loads.
std::string load_error(const std::string& path)
{
    try {
        Target::load(path);
    } catch (const LoadError& e) {
        return e.what();
    }
    return "";
}

#define EXPECT_HAS(msg, part) EXPECT_NE((msg).find(part), std::string::npos) << (msg)

}  // namespace

TEST(PilLoader, GoodImagesLoad)
{
    const std::string pm = write("m.elf", build(good_m()));
    auto m = Target::load(pm);
    EXPECT_EQ(m->core(), Core::CortexM4F);
    EXPECT_EQ(m->port(), "generic");
    EXPECT_EQ(m->symbol("hal_port_name"), 0x80u);
    EXPECT_TRUE(m->has_symbol("hal_stage_reg"));
    EXPECT_FALSE(m->has_symbol("nothing"));
    EXPECT_THROW(m->symbol("nothing"), LoadError);
    EXPECT_TRUE(m->notes().empty());
    char port[8] = {};
    m->read(0x80, port, 8);
    EXPECT_STREQ(port, "generic");

    auto r = Target::load(write("r.elf", build(good_r())));
    EXPECT_EQ(r->core(), Core::CortexR5F);
}

TEST(PilLoader, WithoutAttributesTheVectorTableDecidesAndSaysSo)
{
    Spec m = good_m();
    m.attributes.clear();
    auto t = Target::load(write("m_noattr.elf", build(m)));
    EXPECT_EQ(t->core(), Core::CortexM4F);
    ASSERT_EQ(t->notes().size(), 1u);
    EXPECT_HAS(t->notes()[0], "no .ARM.attributes");
    EXPECT_HAS(t->notes()[0], "Cortex-M4F");

    Spec r = good_r();
    r.attributes.clear();
    auto u = Target::load(write("r_noattr.elf", build(r)));
    EXPECT_EQ(u->core(), Core::CortexR5F);
    ASSERT_EQ(u->notes().size(), 1u);
    EXPECT_HAS(u->notes()[0], "Cortex-R5F");

    Spec x = good_m();
    x.attributes.clear();
    put32(x.segs[0].bytes, 0, 0x12345678u);
    x.entry = 0x100;
    EXPECT_HAS(load_error(write("x_noattr.elf", build(x))), "cannot tell the core");
}

TEST(PilLoader, NotAnElf)
{
    const std::string p = write("text.elf", std::vector<uint8_t>{'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'});
    const std::string e = load_error(p);
    EXPECT_HAS(e, p);
    EXPECT_HAS(e, "not an ELF");
    EXPECT_HAS(load_error(write("empty.elf", {})), "not an ELF");
}

TEST(PilLoader, MissingFile)
{
    const std::string p = ::testing::TempDir() + "pil_loader_does_not_exist.elf";
    const std::string e = load_error(p);
    EXPECT_HAS(e, p);
    EXPECT_HAS(e, "cannot open");
}

TEST(PilLoader, HostExecutableIsNotArm)
{
    std::ifstream f("/bin/true");
    if (!f) GTEST_SKIP() << "no /bin/true";
    const std::string e = load_error("/bin/true");
    EXPECT_HAS(e, "/bin/true");
    EXPECT_HAS(e, "not ARM");
#if defined(__x86_64__)
    EXPECT_HAS(e, "EM_X86_64 (62)");
#endif
}

TEST(PilLoader, HeaderChecks)
{
    Spec s = good_m();
    s.machine = 243;
    EXPECT_HAS(load_error(write("riscv.elf", build(s))), "EM_RISCV (243)");
    s = good_m();
    s.cls = 2;
    EXPECT_HAS(load_error(write("arm64cls.elf", build(s))), "not a 32-bit ELF");
    s = good_m();
    s.data = 2;
    EXPECT_HAS(load_error(write("be.elf", build(s))), "not little-endian");
    s = good_m();
    s.type = 1;
    EXPECT_HAS(load_error(write("rel.elf", build(s))), "ET_REL");
    std::vector<uint8_t> trunc = build(good_m());
    trunc.resize(30);
    EXPECT_HAS(load_error(write("trunc.elf", trunc)), "truncated");
}

TEST(PilLoader, ContentChecks)
{
    Spec s = good_m();
    s.segs.clear();
    EXPECT_HAS(load_error(write("noload.elf", build(s))), "no loadable segment");

    s = good_m();
    s.syms = {{"hal_stage_reg", 0x20000000u}};
    EXPECT_HAS(load_error(write("noport.elf", build(s))), "no symbol 'hal_port_name'");

    s = good_m();
    std::memcpy(s.segs[0].bytes.data() + 0x80, "stm32\0\0", 8);
    EXPECT_HAS(load_error(write("badport.elf", build(s))), "unknown port 'stm32'");

    s = good_m();
    s.segs.push_back({0x30000000u, 0x30000000u, {1, 2, 3, 4}, 0});
    {
        const std::string e = load_error(write("outside.elf", build(s)));
        EXPECT_HAS(e, "0x30000000");
        EXPECT_HAS(e, "outside the memories of port 'generic'");
    }
    s = good_m();
    s.segs[1].memsz = 0x20000;   // .bss past the end of SRAM
    EXPECT_HAS(load_error(write("bss.elf", build(s))), "outside the memories");

    s = good_m();
    s.attributes = attributes('A', "Cortex-A9", 10);
    EXPECT_HAS(load_error(write("a9.elf", build(s))), "profile");
}

TEST(PilLoader, VectorTableChecks)
{
    Spec s = good_m();
    put32(s.segs[0].bytes, 0, 0x12345678u);
    {
        const std::string e = load_error(write("badsp.elf", build(s)));
        EXPECT_HAS(e, "no vector table");
        EXPECT_HAS(e, "initial SP");
    }
    s = good_m();
    put32(s.segs[0].bytes, 4, 0x100u);   // no Thumb bit
    EXPECT_HAS(load_error(write("badpc.elf", build(s))), "reset vector");

    s = good_m();   // nothing at 0
    s.segs[0].vaddr = s.segs[0].paddr = 0x1000;
    s.syms = {{"hal_port_name", 0x1080}};
    EXPECT_HAS(load_error(write("nothing0.elf", build(s))), "no vector table");

    s = good_r();   // R5F: nothing at 0
    s.segs[0].vaddr = s.segs[0].paddr = 0x1000;
    s.syms = {{"hal_port_name", 0x1080}};
    EXPECT_HAS(load_error(write("r_nothing0.elf", build(s))), "no reset vector");
}

TEST(PilLoader, CompiledImageWithoutVectorTable)
{
    const std::string p = kImages.empty() ? std::string() : kImages + "/pil_novec.elf";
    if (p.empty() || !std::ifstream(p).good()) GTEST_SKIP() << "no cross-built test image (arm-none-eabi-gcc)";
    const std::string e = load_error(p);
    EXPECT_HAS(e, p);
    EXPECT_HAS(e, "no vector table");
}
