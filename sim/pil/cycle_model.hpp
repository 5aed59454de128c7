// Instruction-class cycle model of the processor-in-the-loop engine (docs/pil-cycle-model.md):
// every basic block the emulator runs is decoded once with Capstone and its instructions costed
// from a per-core timing table (one struct of data per core: Cortex-M4 TRM ARM DDI 0439,
// Cortex-R5 TRM ARM DDI 0460); taken-branch refills and mispredictions are decided when the next
// block starts (its address against the branch's fall-through).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "pil.hpp"

namespace mcsim::pil {

// Cycles per instruction class, for one core at zero wait states (docs/pil-cycle-model.md has the
// same tables with their sources). Multiple transfers: cost = base + ceil(N / per_cycle).
struct CoreTiming {
    const char* name;
    // integer
    double alu;              // data processing, moves, shifts, compare, extend, bitfield, saturate, IT, NOP
    double mul;              // MUL and the 32-bit-result multiplies (SMULxy, SMULWy, SMMUL, SMUAD, ...)
    double mac;              // MLA, MLS and the accumulating 32-bit-result multiplies
    double mul_long;         // SMULL, UMULL
    double mac_long;         // SMLAL, UMLAL, UMAAL, SMLALxy, SMLALD, SMLSLD
    double div;              // SDIV, UDIV: data dependent, a documented mid value
    double load;             // LDR/LDRB/LDRH/LDRSB/LDRSH/LDREX (one register, not PC)
    double load_pipelined;   // the same right after another single load/store (M4 pipelining)
    double store;            // STR/STRB/STRH/STREX
    double load_double;      // LDRD
    double store_double;     // STRD
    double ldm_base;         // LDM/POP/STM/PUSH: base + ceil(N / ldm_per_cycle)
    double ldm_per_cycle;
    double branch;           // B, BL, BX, BLX, CBZ/CBNZ, MOV/ADD to PC: the issue cycle
    double table_branch;     // TBB/TBH (load + branch)
    double refill;           // P: pipeline refill after a taken branch (M4); 0 on a predicting core
    double mispredict;       // a mispredicted or unpredicted branch (R5); 0 on the M4
    bool predicts;           // dynamic branch prediction + return stack (R5)
    unsigned return_stack;   // return-stack entries (R5)
    double isb;              // ISB (a pipeline flush)
    double barrier;          // DMB, DSB (zero-wait system: nothing to drain)
    double sysreg;           // MRS, MSR, CPS, MRC, MCR, VMRS/VMSR to a system register, SRS
    double wfi;              // WFI/WFE (the issue cycle; the wait is the idle)
    // floating point (single precision unless _f64)
    double fp_alu;           // VADD, VSUB, VMUL, VNMUL
    double fp_alu_f64;       // VADD.F64, VSUB.F64
    double fp_mul_f64;       // VMUL.F64, VNMUL.F64
    double fp_misc;          // VABS, VNEG, VCMP, VCVT, VMOV (register, immediate), VSEL, VRINT
    double fp_mac;           // VMLA, VMLS, VNMLA, VNMLS, VFMA, VFMS, VFNMA, VFNMS
    double fp_mac_f64;
    double fp_div, fp_div_f64;
    double fp_sqrt, fp_sqrt_f64;
    double fp_load, fp_load_f64;     // VLDR
    double fp_store, fp_store_f64;   // VSTR
    double fpm_base, fpm_per_cycle;  // VLDM/VSTM/VPUSH/VPOP: base + ceil(words / per_cycle)
    double fp_xfer;          // VMOV between one core and one FP register, VMRS/VMSR FPSCR
    double fp_xfer2;         // VMOV between two core registers and two S / one D register
    // exceptions (IsrCost, stage 0)
    double irq_entry;        // from the interrupt to the handler's first instruction
    double irq_exit;         // exception return (M4: unstacking; R5: in the return instruction)
    double fp_lazy_save;     // M4: lazy FP state preservation, when the handler first uses the FPU
    double fp_unstack;       // M4: the FP part of the frame restored on return (if it was saved)
};

extern const CoreTiming kCortexM4Timing;
extern const CoreTiming kCortexR5Timing;
const CoreTiming& core_timing(Core core);

enum class BranchKind : uint8_t {
    None,
    Direct,         // B, B<cc>, CBZ, CBNZ: target in the instruction
    Call,           // BL, BLX <imm>
    Return,         // BX LR, POP/LDM SP!{..PC}, LDR PC,[SP],#4, MOV PC,LR
    Indirect,       // BX Rm, MOV/ADD PC, LDR PC, LDM {..PC}, TBB/TBH
    IndirectCall,   // BLX Rm
    ExcReturn,      // SUBS PC,LR,#n / MOVS PC,LR / RFE / ERET / LDM {..PC}^
};

// A basic block as costed once.
struct BlockCost {
    uint32_t addr = 0, size = 0;
    bool thumb = false;
    uint32_t n = 0;              // instructions
    double cycles = 0;           // the instructions' costs (branch penalties come later)
    bool has_fp = false;         // uses the FPU (lazy stacking, CPACR check)
    uint32_t first_fp = 0;       // address of its first FP instruction
    uint32_t first_fp_n = 0;     // instructions up to and including it
    bool ends_wfi = false;       // the last instruction is WFI/WFE
    uint32_t undecoded = 0;      // bytes Capstone could not decode (costed 1 per halfword/word)
    BranchKind branch = BranchKind::None;   // the last instruction
    bool branch_cond = false;
    bool branch_has_target = false;
    uint32_t branch_target = 0;
    uint32_t branch_addr = 0;
    uint32_t fallthrough = 0;    // addr + size
    // Stores in the block, for the stage split at a store to the stage marker: the instructions
    // and cycles up to and including each.
    struct Site {
        uint32_t addr;
        uint32_t n_through;
        double cycles_through;
        // the single-register store's operands (core register numbers 0..14, -1: none), for
        // telling which store of the block wrote the marker from the registers at the store
        int8_t data = -1, base = -1, index = -1;
        uint8_t shift = 0;
        bool subtract = false, post = false;
        int32_t disp = 0;
    };
    std::vector<Site> stores;
};

class CycleModel {
public:
    using ReadCode = std::function<bool(uint32_t addr, void* out, size_t n)>;
    CycleModel(Core core, ReadCode read);
    ~CycleModel();
    CycleModel(const CycleModel&) = delete;
    CycleModel& operator=(const CycleModel&) = delete;

    const CoreTiming& timing() const { return *t_; }

    // The block at addr (size bytes, Thumb or ARM state), from the cache or decoded now; nullptr
    // if its bytes cannot be read.
    const BlockCost* block(uint32_t addr, uint32_t size, bool thumb)
    {
        const uint64_t key = static_cast<uint64_t>(addr) | static_cast<uint64_t>(size & 0x7FFFFFFF) << 32 |
                             (thumb ? 1ull << 63 : 0);
        auto it = cache_.find(key);
        if (it != cache_.end()) return &it->second;
        return decode_block(key, addr, size, thumb);
    }
    // Penalty of the branch that ends `prev` when the next block starts at `next`, updating the
    // predictor (R5) as the core would.
    double branch_penalty(const BlockCost& prev, uint32_t next);
    // Code changed under the cache (a write over a decoded range).
    bool overlaps_code(uint32_t addr, size_t n) const;
    void clear_cache();

    // Instruction by instruction, for tests and reports: the listing and the cost of each.
    std::vector<InsnCost> explain(uint32_t addr, const uint8_t* code, size_t size, bool thumb);

private:
    const BlockCost* decode_block(uint64_t key, uint32_t addr, uint32_t size, bool thumb);
    void cost_insns(uint32_t addr, const uint8_t* code, size_t size, bool thumb, BlockCost* out,
                    std::vector<InsnCost>* listing);

    Core core_;
    const CoreTiming* t_;
    ReadCode read_;
    size_t cs_arm_ = 0, cs_thumb_ = 0;   // capstone handles (csh)
    std::unordered_map<uint64_t, BlockCost> cache_;
    std::vector<bool> code_pages_;       // 1 KiB pages holding decoded code (low 4 GiB / 1 KiB)
    // R5 branch prediction: 2-bit counters per branch address, a return stack
    std::unordered_map<uint32_t, uint8_t> bht_;
    std::vector<uint32_t> rs_;
};

}  // namespace mcsim::pil
