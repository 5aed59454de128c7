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
    static std::unique_ptr<Target> load(const std::string& elf_path);
    virtual ~Target() = default;

    virtual Core core() const = 0;
    virtual std::string port() const = 0;
    // Address of a symbol (STT_OBJECT or STT_FUNC, Thumb bit cleared); throws LoadError if absent.
    virtual uint32_t symbol(const std::string& name) const = 0;
    virtual bool has_symbol(const std::string& name) const = 0;
    // Memory of the emulated core (RAM, flash, TCM: whatever the image maps).
    virtual void read(uint32_t addr, void* out, size_t n) = 0;
    virtual void write(uint32_t addr, const void* in, size_t n) = 0;

    // Reset: SP and PC from the vector table (Cortex-M) or the reset vector at 0 (R5F), then run
    // until the core reaches the background loop's idle (a WFI), at most max_instructions.
    virtual void reset_and_run_to_idle(uint64_t max_instructions) = 0;
    // Continue the background loop from where it waits, until it reaches the idle again.
    virtual void run_background_to_idle(uint64_t max_instructions) = 0;
    // A period boundary on the peripherals (see Peripherals::period_boundary).
    virtual void period_boundary(const PeriphInputs& in) = 0;
    virtual PeriphOutputs outputs() const = 0;
    // Take the control interrupt if it is pending: exception entry as the core does it, the
    // handler to its return; false if nothing was pending. The cost of that ISR in `cost`.
    virtual bool take_irq(IsrCost* cost, uint64_t max_instructions) = 0;

    virtual Peripherals& peripherals() = 0;
};

}  // namespace mcsim::pil
