// Processor-in-the-loop engine: a cross-built firmware image (ELF32, ARM) executed by Unicorn with
// its peripherals backed by the plant (peripherals.hpp), and an instruction-class cycle model
// (cycle_model.hpp) that estimates core cycles per basic block.
#pragma once
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>
#include "peripherals.hpp"

namespace mcsim::pil {

// Bad input to the loader (not an ELF, not 32-bit little-endian ARM, no vector table, a segment
// outside the core's memory map, ...): mcsim exits 2 with what().
struct LoadError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
// The emulated core stopped where it must not (fault, unmapped access, instruction budget).
struct RunError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

enum class Core { CortexM4F, CortexR5F };

struct StageCycles {
    uint64_t instructions = 0;
    double cycles = 0;
};

// Memory contents for Target::create: bytes at an address.
struct Segment {
    uint32_t addr = 0;
    std::vector<uint8_t> bytes;
};

// One decoded instruction with the cycle model's cost (Target::explain).
struct InsnCost {
    uint32_t addr = 0;
    uint8_t size = 0;
    std::string text;       // "vdiv.f32 s0, s1, s2"
    const char* cls = "";   // the timing-table row
    double cycles = 0;
};

// Where the ISRs' cycles went, by function (Target::profile).
struct ProfileEntry {
    std::string function;   // the ELF symbol (STT_FUNC) holding the code, or "0x..." without one
    uint32_t addr = 0;      // its start
    uint64_t instructions = 0;
    double cycles = 0;      // the instructions' and branch penalties (entry/exit/lazy FP excluded)
};

// One control ISR, as the cycle model saw it.
struct IsrCost {
    uint64_t instructions = 0;
    double cycles = 0;                      // including interrupt entry and exit
    StageCycles stage[8];                   // by hal_stage_t (index 0: before the first marker)
};

class Target {
public:
    // Loads the ELF (PT_LOAD segments into the core's memory map), detects the core from the ELF
    // attributes (Tag_CPU_arch_profile 'M' -> Cortex-M4F, 'R' -> Cortex-R5F), picks the port's
    // peripherals from the image (symbol hal_port_name: "generic" or "am263x") and maps them.
    // A TI multicore boot image (.appimage, bootimage.hpp) instead: boot mode, the memory holds its
    // sections only (as TI's SBL loads them), the rest from the ELF of the same name beside it.
    static std::unique_ptr<Target> load(const std::string& elf_path);
    virtual ~Target() = default;

    virtual Core core() const = 0;
    virtual std::string port() const = 0;
    // Address of a symbol (STT_OBJECT or STT_FUNC, Thumb bit cleared); throws LoadError if absent.
    virtual uint32_t symbol(const std::string& name) const = 0;
    virtual bool has_symbol(const std::string& name) const = 0;
    // Its size in bytes (st_size); throws LoadError if absent.
    virtual uint32_t symbol_size(const std::string& name) const = 0;
    // Memory of the emulated core (RAM, flash, TCM: whatever the image maps).
    virtual void read(uint32_t addr, void* out, size_t n) = 0;
    virtual void write(uint32_t addr, const void* in, size_t n) = 0;

    // Reset: SP and PC from the vector table (Cortex-M) or the reset vector at 0 (R5F), then run
    // until the core reaches the background loop's idle (a WFI), at most max_instructions.
    virtual void reset_and_run_to_idle(uint64_t max_instructions) = 0;
    // Continue the background loop from where it waits, until it reaches the idle again.
    virtual void run_background_to_idle(uint64_t max_instructions) = 0;
    // The same, preemptible: at most max_instructions (the background's share of a period), true
    // when it reached the idle, false when the share ran out first; the core then stays where it
    // was, take_irq preempts it there and the next call continues it (a background pass longer
    // than a period, e.g. a store waiting on a flash erase, runs across periods as on the part).
    virtual bool run_background_for(uint64_t max_instructions) = 0;
    // A period boundary on the peripherals (see Peripherals::period_boundary).
    virtual void period_boundary(const PeriphInputs& in) = 0;
    virtual PeriphOutputs outputs() const = 0;
    // Take the control interrupt if it is pending: exception entry as the core does it, the
    // handler to its return; false if nothing was pending. The cost of that ISR in `cost`.
    virtual bool take_irq(IsrCost* cost, uint64_t max_instructions) = 0;

    virtual Peripherals& peripherals() = 0;

    // ---- additions (tests, tools, reports); the declarations above are the engine's contract

    // A core with the given peripherals and memory contents but no ELF: for tests and tools that
    // run machine code directly. The peripherals' memories and windows are mapped as for load();
    // no vector table or port checks. The stage marker is unset (set_stage_marker).
    static std::unique_ptr<Target> create(Core core, std::unique_ptr<Peripherals> periph,
                                          const std::vector<Segment>& contents, const std::string& port = "synthetic");
    // Run from `entry` (bit 0 set: Thumb state) with SP = `sp` (0: as it is) until the core
    // executes a WFI, at most max_instructions; the cost as an ISR body (the instructions' cycles
    // and branch penalties, stage split by the marker; no interrupt entry or exit).
    virtual IsrCost run_counted(uint32_t entry, uint32_t sp, uint64_t max_instructions) = 0;
    // Address of the 32-bit stage marker (load(): the image's hal_stage_reg, if it has one).
    virtual void set_stage_marker(uint32_t addr) = 0;
    // A core register: 0..12 r0-r12, 13 SP, 14 LR, 15 PC, 16 CPSR (R5F) / xPSR (M4F), 17 SPSR (R5F),
    // 18 CONTROL (M4F).
    virtual uint32_t reg(unsigned n) = 0;
    // Everything the cycle model counted since load (ISRs and background), and the ISRs alone.
    virtual StageCycles total() const = 0;
    virtual StageCycles isr_total() const = 0;
    // Remarks of the loader, e.g. the core told from the vector table for lack of build attributes.
    virtual std::vector<std::string> notes() const = 0;
    // The cycle model's view of code: each instruction in [addr, addr + size) with its class and
    // cost (branch penalties excluded), in the given state (thumb true: Thumb).
    virtual std::vector<InsnCost> explain(uint32_t addr, uint32_t size, bool thumb) = 0;
    // The timing table in use ("Cortex-M4F", "Cortex-R5F").
    virtual const char* timing_name() const = 0;
    // Profiling of the ISRs by function (off by default): cleared when switched on; profile()
    // sorted by cycles, largest first.
    virtual void enable_profile(bool on) = 0;
    virtual std::vector<ProfileEntry> profile() const = 0;
    // Faults taken as the core takes them (off by default: a fault stops the run with a RunError
    // naming it). On: R5F an undefined instruction enters UND mode at vector 0x04, an access
    // outside every memory and register window a data abort (ABT, 0x10; LR from the PC Unicorn
    // reports, the start of the faulting block), an instruction fetch there a prefetch abort (ABT,
    // 0x0C), each with SPSR = CPSR, IRQ/FIQ (and for aborts A) masked, the state from SCTLR.TE;
    // M4F any of them a HardFault (vector 3, the 8/26-word frame, EXC_RETURN in LR: the port
    // leaves SHCSR's MemManage/BusFault/UsageFault off, so they escalate). The handler then runs
    // on as part of the same run (to its WFI); the entry costs the timing's interrupt entry.
    // An active fault handler holds the control interrupt off (take_irq: false).
    virtual void set_fault_entry(bool on) = 0;
    virtual unsigned faults_taken() const = 0;
};

}  // namespace mcsim::pil
