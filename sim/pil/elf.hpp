// ELF32 reader for the processor-in-the-loop loader (no libelf): the header checks, the PT_LOAD
// segments, the symbol table and the ARM build attributes (.ARM.attributes, "aeabi").
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace mcsim::pil {

struct ElfSegment {
    uint32_t paddr = 0, vaddr = 0;   // load (LMA) and run (VMA) address
    uint32_t filesz = 0, memsz = 0;
    uint32_t flags = 0;              // PF_X 1, PF_W 2, PF_R 4
    std::vector<uint8_t> data;       // filesz bytes
};

struct ElfSymbol {
    uint32_t value = 0, size = 0;
    uint8_t type = 0, bind = 0;      // STT_*, STB_*
    uint16_t shndx = 0;
};

struct ElfImage {
    std::string path;
    uint16_t type = 0, machine = 0;
    uint32_t entry = 0, flags = 0;
    std::vector<ElfSegment> segments;          // PT_LOAD, in file order
    std::map<std::string, ElfSymbol> symbols;  // defined symbols; a global wins over a local
    bool has_attributes = false;               // .ARM.attributes with an "aeabi" File subsection
    int cpu_arch = -1;                         // Tag_CPU_arch (6), -1 if absent
    int cpu_arch_profile = -1;                 // Tag_CPU_arch_profile (7): 'M', 'R', 'A', 'S'; 0 none
    std::string cpu_name;                      // Tag_CPU_name (5)

    // Bytes of the image at a run address (the segments' file data by p_vaddr); false if any byte
    // is not in a segment's file image.
    bool read_vaddr(uint32_t addr, void* out, size_t n) const;
    // The same by load address (p_paddr): what the memory holds after loading.
    bool read_paddr(uint32_t addr, void* out, size_t n) const;
};

// Reads and checks an ELF file: throws LoadError naming the file and the reason (missing or
// unreadable, not an ELF, not ARM (with the machine it is), not 32-bit, not little-endian, not an
// executable, truncated or inconsistent headers).
ElfImage read_elf(const std::string& path);

// "EM_X86_64 (62)"
std::string elf_machine_name(uint16_t machine);

}  // namespace mcsim::pil
