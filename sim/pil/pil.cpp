// Processor-in-the-loop engine (pil.hpp): an ARM core emulated by Unicorn 2 with the port's
// peripheral model mapped as MMIO, the instruction-class cycle model (cycle_model.hpp) on every
// basic block, and the control interrupt taken as the core takes it.
//
// What Unicorn 2.0.1 gives and what this engine adds (verified by tests/pil):
//  - WFI: QEMU's helper halts the vCPU (EXCP_HLT) with the PC after the WFI; uc_emu_start
//    returns. The engine knows the block it last entered ended with a WFI (the block cache marks
//    it; QEMU ends a translation block at a WFI), so that is "idle", and the next run continues
//    after it.
//  - Cortex-M4F: Unicorn has no NVIC/SCB (QEMU's armv7m device is not part of it), so the engine
//    maps the System Control Space 0xE000E000 (NVIC ISER/ICER/IPR, SCB CPUID/ICSR/VTOR/AIRCR/
//    CCR/CPACR, FPCCR, SysTick registers as storage) and the DWT page 0xE0001000 (CYCCNT reads
//    the model's cycle count). Unicorn never traps FP instructions on M profile (its
//    fp_exception_el() is a stub returning 0), so the engine checks CPACR itself: an FP
//    instruction while CP10/CP11 are not enabled stops the run as the NOCP UsageFault would.
//    Exception entry is done here as the hardware does it (frame of 8 words, or 26 with the FP
//    context when CONTROL.FPCA is set, 8-byte alignment with xPSR bit 9, LR = EXC_RETURN,
//    IPSR = 16 + n, CONTROL.FPCA cleared, PC = vector 16 + n from VTOR); QEMU then raises
//    EXCP_EXCEPTION_EXIT when the handler branches to EXC_RETURN in handler mode, Unicorn hands
//    it to UC_HOOK_INTR (it does not run QEMU's do_v7m_exception_exit), and the engine unstacks
//    the frame there. Register writes of IPSR do not rebuild QEMU's cached hflags (the handler-
//    mode bit the translator needs to see an exception return), so the engine rewrites
//    APSR_NZCV after them, which does.
//  - Cortex-R5F: a CPSR write through uc_reg_write switches the mode and banks SP/LR/SPSR
//    (cpsr_write with CPSRWriteByUnicorn calls switch_mode); CPS/MSR, MRC/MCR CPACR, VMSR
//    FPEXC, SUBS PC,LR / RFE run natively. IRQ entry: SPSR_irq = CPSR, mode IRQ with I and A set
//    (T = SCTLR.TE, E = SCTLR.EE), LR_irq = return address + 4, PC = 0x18 (0xFFFF0018 with
//    SCTLR.V; the VIC port address with SCTLR.VE); the ISR ends when a block starts at the
//    interrupted PC, in the interrupted mode, right after an exception-return instruction.
//  - A register write of the PC from a hook makes Unicorn resume there rather than stop; the
//    engine therefore stops in the block hook of the block at the return address (a stop
//    requested in a block hook takes effect before that block executes).
#include "pil.hpp"

#include <unicorn/unicorn.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "bootimage.hpp"
#include "cycle_model.hpp"
#include "elf.hpp"

extern "C" {
#include "hal_generic/regs.h"
}

namespace mcsim::pil {
namespace {

constexpr uint64_t kNoExit = 0xFFFFFFFFull;   // odd: never a PC, so uc_emu_start never stops on it
constexpr uint32_t kScsBase = 0xE000E000u, kDwtBase = 0xE0001000u;
constexpr unsigned kControlIrq = GEN_ADC_IRQ;   // Cortex-M: the port's control interrupt line
// QEMU's ARM exception numbers (target/arm/cpu.h), as Unicorn reports them to UC_HOOK_INTR
constexpr uint32_t kExcpExceptionExit = 8;

std::string hex(uint64_t v)
{
    char b[24];
    std::snprintf(b, sizeof b, "0x%llx", static_cast<unsigned long long>(v));
    return b;
}

const char* excp_name(uint32_t n)
{
    switch (n) {
    case 1: return "undefined instruction";
    case 2: return "SVC";
    case 3: return "prefetch abort";
    case 4: return "data abort";
    case 5: return "IRQ";
    case 6: return "FIQ";
    case 7: return "breakpoint (BKPT)";
    case 8: return "exception return";
    case 11: return "HVC";
    case 13: return "SMC";
    case 16: return "semihosting call";
    case 17: return "NOCP UsageFault";
    case 18: return "INVSTATE UsageFault";
    case 20: return "fault during lazy FP stacking";
    case 22: return "UNALIGNED UsageFault";
    default: return "exception";
    }
}

bool name_is_ram(const std::string& n)
{
    std::string l(n);
    for (auto& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return l.find("ram") != std::string::npos || l.find("tcm") != std::string::npos;
}

std::string describe_memories(const std::vector<MmioWindow>& mems)
{
    std::string s;
    for (const auto& m : mems) {
        if (!s.empty()) s += ", ";
        s += m.name + " " + hex(m.base) + "-" + hex(m.base + m.size);
    }
    return s;
}

const MmioWindow* memory_of(const std::vector<MmioWindow>& mems, uint64_t a, uint64_t n)
{
    for (const auto& m : mems)
        if (a >= m.base && a + n <= m.base + m.size) return &m;
    return nullptr;
}

class UcTarget;

struct Window {
    UcTarget* t;
    uint64_t base;
    int kind;   // 0: port peripherals, 1: SCS, 2: DWT
};

class UcTarget final : public Target {
public:
    UcTarget(Core core, std::string port, std::unique_ptr<Peripherals> periph, std::string origin)
        : core_(core),
          port_(std::move(port)),
          periph_(std::move(periph)),
          origin_(std::move(origin)),
          model_(core, [this](uint32_t a, void* o, size_t n) { return uc_mem_read(uc_, a, o, n) == UC_ERR_OK; })
    {
        const bool m = core_ == Core::CortexM4F;
        uc_err e = uc_open(UC_ARCH_ARM, m ? static_cast<uc_mode>(UC_MODE_THUMB | UC_MODE_MCLASS) : UC_MODE_ARM, &uc_);
        if (e != UC_ERR_OK) throw LoadError(origin_ + ": unicorn: " + uc_strerror(e));
        try {
            setup(m);
        } catch (...) {
            uc_close(uc_);
            uc_ = nullptr;
            throw;
        }
    }
    ~UcTarget() override
    {
        if (uc_) uc_close(uc_);
    }

private:
    void setup(bool m)
    {
        uc_err e = uc_ctl_set_cpu_model(uc_, m ? UC_CPU_ARM_CORTEX_M4 : UC_CPU_ARM_CORTEX_R5F);
        if (e != UC_ERR_OK) throw LoadError(origin_ + ": unicorn: cannot select the CPU model: " + uc_strerror(e));
        mems_ = periph_->memories();
        for (const auto& mem : mems_) {
            e = uc_mem_map(uc_, mem.base, mem.size, UC_PROT_ALL);
            if (e != UC_ERR_OK)
                throw LoadError(origin_ + ": cannot map memory " + mem.name + " " + hex(mem.base) + "+" + hex(mem.size) +
                                " of port '" + port_ + "': " + uc_strerror(e));
        }
        for (const auto& w : periph_->windows()) map_window(w.base, w.size, w.name, 0);
        if (m) {
            map_window(kScsBase, 0x1000, "System Control Space", 1);
            map_window(kDwtBase, 0x1000, "DWT", 2);
        }
        uc_hook h;
        add_hook(&h, UC_HOOK_BLOCK, reinterpret_cast<void*>(&UcTarget::cb_block), 1, 0);
        add_hook(&h, UC_HOOK_INTR, reinterpret_cast<void*>(&UcTarget::cb_intr), 1, 0);
        add_hook(&h, UC_HOOK_MEM_INVALID, reinterpret_cast<void*>(&UcTarget::cb_mem_invalid), 1, 0);
        add_hook(&h, UC_HOOK_INSN_INVALID, reinterpret_cast<void*>(&UcTarget::cb_insn_invalid), 1, 0);
        scs_reset();
    }

public:
    // ---- loading
    void load_contents(const std::vector<Segment>& segs)
    {
        for (const auto& s : segs) {
            if (s.bytes.empty()) continue;
            if (!memory_of(mems_, s.addr, s.bytes.size()))
                throw LoadError(origin_ + ": contents at " + hex(s.addr) + "+" + hex(s.bytes.size()) +
                                " lie outside the memories of port '" + port_ + "' (" + describe_memories(mems_) + ")");
            if (uc_mem_write(uc_, s.addr, s.bytes.data(), s.bytes.size()) != UC_ERR_OK)
                throw LoadError(origin_ + ": cannot write " + hex(s.addr));
        }
    }
    void bind()
    {
        periph_->bind_memory(
            [this](uint32_t a, const void* d, size_t n) {
                if (uc_mem_write(uc_, a, d, n) == UC_ERR_OK && model_.overlaps_code(a, n)) model_.clear_cache();
            },
            [this](uint32_t a, void* d, size_t n) {
                if (uc_mem_read(uc_, a, d, n) != UC_ERR_OK) std::memset(d, 0, n);
            });
    }
    void set_symbols(std::map<std::string, ElfSymbol> syms) { syms_ = std::move(syms); }
    void set_vector_base(uint32_t v) { vbase_ = v; }
    void add_note(const std::string& n) { notes_.push_back(n); }

    // ---- Target
    Core core() const override { return core_; }
    std::string port() const override { return port_; }
    uint32_t symbol(const std::string& name) const override
    {
        auto it = syms_.find(name);
        if (it == syms_.end()) throw LoadError(origin_ + ": no symbol '" + name + "'");
        return it->second.type == 2 ? (it->second.value & ~1u) : it->second.value;   // STT_FUNC: Thumb bit
    }
    bool has_symbol(const std::string& name) const override { return syms_.count(name) != 0; }
    uint32_t symbol_size(const std::string& name) const override
    {
        auto it = syms_.find(name);
        if (it == syms_.end()) throw LoadError(origin_ + ": no symbol '" + name + "'");
        return it->second.size;
    }

    void read(uint32_t addr, void* out, size_t n) override
    {
        if (uc_mem_read(uc_, addr, out, n) != UC_ERR_OK)
            throw RunError("pil: read of " + std::to_string(n) + " bytes at " + hex(addr) + ": not in a memory of the target");
    }
    void write(uint32_t addr, const void* in, size_t n) override
    {
        if (uc_mem_write(uc_, addr, in, n) != UC_ERR_OK)
            throw RunError("pil: write of " + std::to_string(n) + " bytes at " + hex(addr) + ": not in a memory of the target");
        if (model_.overlaps_code(addr, n)) {   // code rewritten: drop what was decoded and translated
            model_.clear_cache();
            uc_ctl_remove_cache(uc_, static_cast<uint64_t>(addr), static_cast<uint64_t>(addr) + n);   // varargs: uint64_t
        }
    }

    void reset_and_run_to_idle(uint64_t max_instructions) override
    {
        uint32_t entry = 0;
        for (int r = UC_ARM_REG_R0; r <= UC_ARM_REG_R12; ++r) wr(r, 0);
        if (core_ == Core::CortexM4F) {
            uint32_t v[2] = {0, 0};
            read(vbase_, v, sizeof v);
            scs_reset();
            vtor_ = vbase_;
            wr(UC_ARM_REG_CONTROL, 0);
            wr(UC_ARM_REG_PRIMASK, 0);
            wr(UC_ARM_REG_FAULTMASK, 0);
            wr(UC_ARM_REG_BASEPRI, 0);
            wr(UC_ARM_REG_XPSR_NZCVQG, 0x01000000u);   // T, IPSR 0, flags clear
            wr(UC_ARM_REG_FPSCR, 0);
            wr(UC_ARM_REG_SP, v[0] & ~3u);
            wr(UC_ARM_REG_LR, 0xFFFFFFFFu);
            rebuild_hflags();
            entry = v[1] | 1u;
        } else {
            wr(UC_ARM_REG_CPSR, 0x1D3u);   // SVC, IRQ/FIQ/abort masked, ARM, little-endian
            wr(UC_ARM_REG_LR, 0);
            entry = 0;
        }
        in_isr_ = false;
        acc_ = nullptr;
        run(entry, max_instructions, "reset");
        expect_idle("reset");
    }

    void run_background_to_idle(uint64_t max_instructions) override
    {
        in_isr_ = false;
        acc_ = nullptr;
        run(current_pc(), max_instructions, "background");
        expect_idle("background");
    }

    bool run_background_for(uint64_t max_instructions) override
    {
        in_isr_ = false;
        acc_ = nullptr;
        preempt_ = true;
        preempted_ = false;
        struct End {
            UcTarget* t;
            ~End() { t->preempt_ = false; }
        } end{this};
        run(current_pc(), max_instructions, "background");
        if (preempted_) return false;   // stopped before the block at the PC: resumable there
        expect_idle("background");
        return true;
    }

    IsrCost run_counted(uint32_t entry, uint32_t sp, uint64_t max_instructions) override
    {
        IsrCost c;
        if (sp != 0) wr(UC_ARM_REG_SP, sp);
        if (core_ == Core::CortexR5F) {   // the state from bit 0, as a BX would
            const uint32_t cpsr = rd(UC_ARM_REG_CPSR);
            wr(UC_ARM_REG_CPSR, (entry & 1u) ? (cpsr | 0x20u) : (cpsr & ~0x20u));
        }
        in_isr_ = false;
        acc_ = &c;
        stage_ = 0;
        struct Reset {
            UcTarget* t;
            ~Reset() { t->acc_ = nullptr; }
        } guard{this};
        run(entry, max_instructions, "counted run");
        expect_idle("counted run");
        return c;
    }

    void period_boundary(const PeriphInputs& in) override { periph_->period_boundary(in); }
    PeriphOutputs outputs() const override { return periph_->outputs(); }
    Peripherals& peripherals() override { return *periph_; }

    bool take_irq(IsrCost* cost, uint64_t max_instructions) override
    {
        return core_ == Core::CortexM4F ? take_irq_m(cost, max_instructions) : take_irq_r(cost, max_instructions);
    }

    void set_stage_marker(uint32_t addr) override
    {
        if (stage_hook_) uc_hook_del(uc_, stage_hook_);
        stage_hook_ = 0;
        if (uc_hook_add(uc_, &stage_hook_, UC_HOOK_MEM_WRITE, reinterpret_cast<void*>(&UcTarget::cb_stage), this, addr,
                        static_cast<uint64_t>(addr) + 3) != UC_ERR_OK)
            throw LoadError(origin_ + ": cannot watch the stage marker at " + hex(addr));
        stage_addr_ = addr;
        uc_ctl_flush_tlb(uc_);   // UC_CTL_TB_FLUSH: memory accesses are now translated through the hook path
    }

    uint32_t reg(unsigned n) override
    {
        static const int ids[] = {UC_ARM_REG_R0, UC_ARM_REG_R1, UC_ARM_REG_R2,  UC_ARM_REG_R3,  UC_ARM_REG_R4,
                                  UC_ARM_REG_R5, UC_ARM_REG_R6, UC_ARM_REG_R7,  UC_ARM_REG_R8,  UC_ARM_REG_R9,
                                  UC_ARM_REG_R10, UC_ARM_REG_R11, UC_ARM_REG_R12, UC_ARM_REG_SP, UC_ARM_REG_LR,
                                  UC_ARM_REG_PC};
        if (n < 16) return rd(ids[n]);
        if (n == 16) return rd(core_ == Core::CortexM4F ? UC_ARM_REG_XPSR : UC_ARM_REG_CPSR);
        if (n == 17 && core_ == Core::CortexR5F) return rd(UC_ARM_REG_SPSR);
        if (n == 18 && core_ == Core::CortexM4F) return rd(UC_ARM_REG_CONTROL);
        throw std::out_of_range("pil: reg " + std::to_string(n));
    }

    StageCycles total() const override { return total_; }
    StageCycles isr_total() const override { return isr_total_; }
    std::vector<std::string> notes() const override { return notes_; }
    const char* timing_name() const override { return model_.timing().name; }

    void enable_profile(bool on) override
    {
        profiling_ = on;
        if (on) prof_.clear();
    }
    std::vector<ProfileEntry> profile() const override
    {
        // functions by start address, from the symbol table
        std::vector<std::pair<uint32_t, const std::pair<const std::string, ElfSymbol>*>> funcs;
        for (const auto& kv : syms_)
            if (kv.second.type == 2) funcs.push_back({kv.second.value & ~1u, &kv});
        std::sort(funcs.begin(), funcs.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        std::map<uint32_t, ProfileEntry> by;
        for (const auto& [addr, pe] : prof_) {
            auto it = std::upper_bound(funcs.begin(), funcs.end(), addr,
                                       [](uint32_t a, const auto& f) { return a < f.first; });
            ProfileEntry* e = nullptr;
            if (it != funcs.begin()) {
                --it;
                const ElfSymbol& sy = it->second->second;
                if (sy.size == 0 || addr < it->first + sy.size) {
                    e = &by[it->first];
                    e->function = it->second->first;
                    e->addr = it->first;
                }
            }
            if (!e) {
                e = &by[addr];
                e->function = hex(addr);
                e->addr = addr;
            }
            e->instructions += pe.instructions;
            e->cycles += pe.cycles;
        }
        std::vector<ProfileEntry> v;
        for (auto& kv : by) v.push_back(kv.second);
        std::sort(v.begin(), v.end(), [](const ProfileEntry& a, const ProfileEntry& b) { return a.cycles > b.cycles; });
        return v;
    }

    std::vector<InsnCost> explain(uint32_t addr, uint32_t size, bool thumb) override
    {
        std::vector<uint8_t> b(size);
        read(addr, b.data(), size);
        return model_.explain(addr, b.data(), size, thumb);
    }

private:
    // ---- plumbing
    uint32_t rd(int reg)
    {
        uint32_t v = 0;
        uc_reg_read(uc_, reg, &v);
        return v;
    }
    void wr(int reg, uint32_t v) { uc_reg_write(uc_, reg, &v); }
    // QEMU caches the translation flags (handler mode, FP context needed, ...) in env->hflags;
    // Unicorn rebuilds them on a CPSR/APSR write but not on IPSR/CONTROL writes.
    void rebuild_hflags() { wr(UC_ARM_REG_APSR_NZCV, rd(UC_ARM_REG_APSR_NZCV)); }
    uint32_t current_pc()
    {
        const uint32_t pc = rd(UC_ARM_REG_PC);
        if (core_ == Core::CortexM4F) return pc | 1u;
        return pc | ((rd(UC_ARM_REG_CPSR) & 0x20u) ? 1u : 0u);
    }
    void add_hook(uc_hook* h, int type, void* cb, uint64_t begin, uint64_t end)
    {
        if (uc_hook_add(uc_, h, type, cb, this, begin, end) != UC_ERR_OK) throw LoadError(origin_ + ": unicorn: cannot add a hook");
    }
    void map_window(uint64_t base, uint64_t size, const std::string& name, int kind)
    {
        windows_.push_back(std::make_unique<Window>(Window{this, base, kind}));
        Window* w = windows_.back().get();
        const uc_err e = uc_mmio_map(uc_, base, size, &UcTarget::cb_mmio_read, w, &UcTarget::cb_mmio_write, w);
        if (e != UC_ERR_OK)
            throw LoadError(origin_ + ": cannot map the register window " + name + " " + hex(base) + "+" + hex(size) +
                            " of port '" + port_ + "': " + uc_strerror(e));
    }

    void stop() { uc_emu_stop(uc_); }
    void fail(const std::string& why)
    {
        if (error_.empty()) error_ = why;
        stopping_ = true;
        stop();
    }

    void charge(double cycles, uint64_t n, int stage)
    {
        total_.cycles += cycles;
        total_.instructions += n;
        if (acc_) {
            acc_->cycles += cycles;
            acc_->instructions += n;
            acc_->stage[stage].cycles += cycles;
            acc_->stage[stage].instructions += n;
            if (in_isr_) {
                isr_total_.cycles += cycles;
                isr_total_.instructions += n;
            }
        }
    }

    // One emulation run from `begin` (bit 0: Thumb) until the core stops (WFI, the ISR's return,
    // an error); RunError on an error.
    void run(uint32_t begin, uint64_t max_instructions, const char* what)
    {
        budget_ = max_instructions;
        executed_ = 0;
        error_.clear();
        mem_fault_.clear();
        stopping_ = false;
        isr_done_ = false;
        prev_ = nullptr;
        cur_ = nullptr;
        last_ = nullptr;
        nocp_pending_ = false;
        uc_err e = uc_emu_start(uc_, begin, kNoExit, 0, 0);
        while (fault_entry_ && error_.empty() && e != UC_ERR_OK) {   // set_fault_entry: the core's exception
            const uint32_t entry = enter_fault(e);
            if (entry == 0) break;
            mem_fault_.clear();
            stopping_ = false;
            prev_ = nullptr;
            e = uc_emu_start(uc_, entry, kNoExit, 0, 0);
        }
        const uint32_t pc = rd(UC_ARM_REG_PC);
        if (error_.empty() && nocp_pending_ && !fp_enabled()) error_ = nocp_message();
        if (!pending_precise_.empty()) instrument_precise();
        if (!error_.empty()) throw RunError(std::string("pil (") + what + "): " + error_);
        if (e != UC_ERR_OK) throw RunError(std::string("pil (") + what + "): " + describe(e, pc));
    }

    // ---- faults as the core takes them (set_fault_entry); the handler's address (bit 0: Thumb)
    // or 0 when e is not a fault the core would take
    void set_fault_entry(bool on) override { fault_entry_ = on; }
    unsigned faults_taken() const override { return faults_; }
    uint32_t enter_fault(uc_err e)
    {
        enum { Undef, Dabt, Pabt } kind;
        switch (e) {
        case UC_ERR_INSN_INVALID: kind = Undef; break;
        case UC_ERR_READ_UNMAPPED:
        case UC_ERR_WRITE_UNMAPPED:
        case UC_ERR_READ_PROT:
        case UC_ERR_WRITE_PROT: kind = Dabt; break;
        case UC_ERR_FETCH_UNMAPPED:
        case UC_ERR_FETCH_PROT: kind = Pabt; break;
        default: return 0;
        }
        const uint32_t pc = rd(UC_ARM_REG_PC);
        charge(model_.timing().irq_entry, 0, stage_);
        ++faults_;
        if (core_ == Core::CortexM4F) return enter_hardfault(pc);
        const uint32_t cpsr = rd(UC_ARM_REG_CPSR);
        uc_arm_cp_reg sctlr_r{15, 0, 0, 1, 0, 0, 0, 0};
        uc_reg_read(uc_, UC_ARM_REG_CP_REG, &sctlr_r);
        const uint32_t sctlr = static_cast<uint32_t>(sctlr_r.val);
        const bool thumb = (cpsr & 0x20u) != 0;
        // ARMv7-R exception entry (ARM ARM B1.8): mode, masks, state; LR as the vector expects it
        static const uint32_t mode[] = {0x1Bu, 0x17u, 0x17u}, vec[] = {0x04u, 0x10u, 0x0Cu};
        const uint32_t lr = kind == Undef ? pc + (thumb ? 2u : 4u) : kind == Dabt ? pc + 8u : pc + 4u;
        uint32_t ncpsr = (cpsr & ~(0x1Fu | 0x20u | 0x0600FC00u | 0x200u)) | mode[kind] | 0x80u | 0x40u;
        if (kind != Undef) ncpsr |= 0x100u;
        if (sctlr & (1u << 30)) ncpsr |= 0x20u;
        if (sctlr & (1u << 25)) ncpsr |= 0x200u;
        wr(UC_ARM_REG_CPSR, ncpsr);   // banks SP, LR, SPSR
        wr(UC_ARM_REG_SPSR, cpsr);
        wr(UC_ARM_REG_LR, lr);
        return ((sctlr & (1u << 13)) ? 0xFFFF0000u : 0u) + vec[kind] + ((ncpsr & 0x20u) ? 1u : 0u);
    }
    uint32_t enter_hardfault(uint32_t pc)
    {
        const uint32_t control = rd(UC_ARM_REG_CONTROL), xpsr = rd(UC_ARM_REG_XPSR);
        const bool fpca = (control & 4u) != 0;
        const uint32_t sp = rd(UC_ARM_REG_SP), frame = fpca ? 0x68u : 0x20u;
        const bool align = ((sp - frame) & 4u) != 0;
        const uint32_t fptr = (sp - frame) & ~4u;
        uint32_t w[26] = {};
        const int core_regs[6] = {UC_ARM_REG_R0, UC_ARM_REG_R1, UC_ARM_REG_R2, UC_ARM_REG_R3, UC_ARM_REG_R12, UC_ARM_REG_LR};
        for (int k = 0; k < 6; ++k) w[k] = rd(core_regs[k]);
        w[6] = pc & ~1u;
        w[7] = xpsr | (align ? 0x200u : 0u);
        if (fpca) {
            for (int k = 0; k < 16; ++k) w[8 + k] = rd(UC_ARM_REG_S0 + k);
            w[24] = rd(UC_ARM_REG_FPSCR);
        }
        if (uc_mem_write(uc_, fptr, w, frame) != UC_ERR_OK) {
            fail("HardFault entry: the frame at " + hex(fptr) + " is not in memory (a lockup on the core)");
            return 0;
        }
        uint32_t vec = 0;
        if (uc_mem_read(uc_, vtor_ + 12u, &vec, 4) != UC_ERR_OK || !(vec & 1u)) {
            fail("HardFault entry: vector 3 is " + hex(vec) + ", not a Thumb handler (a lockup on the core)");
            return 0;
        }
        const bool handler = (xpsr & 0x1FFu) != 0;
        wr(UC_ARM_REG_SP, fptr);
        wr(UC_ARM_REG_LR, (handler ? 0xFFFFFFF1u : 0xFFFFFFF9u) & ~(fpca ? 0x10u : 0u));
        wr(UC_ARM_REG_CONTROL, control & ~4u);
        wr(UC_ARM_REG_XPSR_NZCVQG, (xpsr & 0xF80F0000u) | 0x01000000u | 3u);
        rebuild_hflags();
        in_isr_ = false;   // a fault in the ISR: its handler never returns to it
        return vec;
    }

    void expect_idle(const char* what)
    {
        const uint32_t pc = rd(UC_ARM_REG_PC);
        if (last_ && last_->ends_wfi && pc == last_->fallthrough) return;
        std::ostringstream m;
        m << "pil (" << what << "): the core stopped at PC " << hex(pc) << " without reaching a WFI";
        throw RunError(m.str());
    }

    std::string describe(uc_err e, uint32_t pc)
    {
        std::ostringstream m;
        switch (e) {
        case UC_ERR_READ_UNMAPPED:
        case UC_ERR_WRITE_UNMAPPED:
        case UC_ERR_FETCH_UNMAPPED:
        case UC_ERR_READ_PROT:
        case UC_ERR_WRITE_PROT:
        case UC_ERR_FETCH_PROT:
            m << (mem_fault_.empty() ? std::string(uc_strerror(e)) : mem_fault_) << " at PC "
              << access_site(e == UC_ERR_FETCH_UNMAPPED || e == UC_ERR_FETCH_PROT, pc)
              << " (outside the memories and register windows of port '" << port_ << "')";
            break;
        case UC_ERR_INSN_INVALID: {
            m << "invalid instruction at PC " << hex(pc);
            const bool thumb = core_ == Core::CortexM4F || (rd(UC_ARM_REG_CPSR) & 0x20u);
            uint8_t b[4] = {0, 0, 0, 0};
            if (uc_mem_read(uc_, pc, b, 4) == UC_ERR_OK) {
                auto v = model_.explain(pc, b, 4, thumb);
                if (!v.empty()) {
                    m << ": " << v[0].text;
                    if (core_ == Core::CortexR5F && v[0].text[0] == 'v' && !(rd(UC_ARM_REG_FPEXC) & 0x40000000u))
                        m << " (FPEXC.EN is clear: the VFP is off)";
                    if (v[0].text.rfind("wfe", 0) == 0 || v[0].text.rfind("yield", 0) == 0)
                        m << " (the engine idles on WFI only)";
                }
            }
            break;
        }
        case UC_ERR_EXCEPTION:
            m << "unhandled CPU exception at PC " << hex(pc)
              << (core_ == Core::CortexM4F ? " (e.g. an ARM-state branch: INVSTATE UsageFault)" : "");
            break;
        default:
            m << uc_strerror(e) << " at PC " << hex(pc);
        }
        return m.str();
    }

    // Unicorn leaves the PC at the start of the block after a faulting data access: name the
    // block's load/store instruction (the one, or the candidates).
    std::string access_site(bool fetch, uint32_t pc)
    {
        if (fetch || !last_ || pc < last_->addr || pc >= last_->fallthrough) return hex(pc);
        std::vector<uint8_t> b(last_->size);
        if (uc_mem_read(uc_, last_->addr, b.data(), b.size()) != UC_ERR_OK) return hex(pc);
        std::vector<InsnCost> mem;
        for (auto& i : model_.explain(last_->addr, b.data(), b.size(), last_->thumb)) {
            const std::string c = i.cls;
            if (c.find("load") != std::string::npos || c.find("store") != std::string::npos ||
                c.find("VLD") != std::string::npos || c.find("VST") != std::string::npos || c.find("table") != std::string::npos)
                mem.push_back(i);
        }
        if (mem.size() == 1) return hex(mem[0].addr) + " (" + mem[0].text + ")";
        std::string s = hex(pc) + " (in the block at " + hex(last_->addr) + "; its memory accesses:";
        for (const auto& i : mem) s += " " + hex(i.addr) + " " + i.text + ";";
        return s + ")";
    }

    // ---- hooks (no exception may leave them: they are called from C)
    static void cb_block(uc_engine*, uint64_t addr, uint32_t size, void* u)
    {
        auto* t = static_cast<UcTarget*>(u);
        try {
            t->on_block(static_cast<uint32_t>(addr), size);
        } catch (const std::exception& e) {
            t->fail(e.what());
        }
    }
    static void cb_intr(uc_engine*, uint32_t intno, void* u)
    {
        auto* t = static_cast<UcTarget*>(u);
        try {
            t->on_intr(intno);
        } catch (const std::exception& e) {
            t->fail(e.what());
        }
    }
    static bool cb_mem_invalid(uc_engine*, uc_mem_type type, uint64_t addr, int size, int64_t value, void* u)
    {
        auto* t = static_cast<UcTarget*>(u);
        (void)value;
        std::ostringstream m;
        const char* what = "access";
        switch (type) {
        case UC_MEM_READ_UNMAPPED: what = "read from unmapped address"; break;
        case UC_MEM_WRITE_UNMAPPED: what = "write to unmapped address"; break;
        case UC_MEM_FETCH_UNMAPPED: what = "instruction fetch from unmapped address"; break;
        case UC_MEM_READ_PROT: what = "read from protected address"; break;
        case UC_MEM_WRITE_PROT: what = "write to protected address"; break;
        case UC_MEM_FETCH_PROT: what = "instruction fetch from protected address"; break;
        default: break;
        }
        m << what << " " << hex(addr) << " (" << size << " bytes)";
        if (t->mem_fault_.empty()) t->mem_fault_ = m.str();
        return false;
    }
    static bool cb_insn_invalid(uc_engine*, void*) { return false; }
    static void cb_stage(uc_engine*, uc_mem_type, uint64_t addr, int size, int64_t value, void* u)
    {
        auto* t = static_cast<UcTarget*>(u);
        try {
            t->on_stage(static_cast<uint32_t>(addr), size, static_cast<uint64_t>(value));
        } catch (const std::exception& e) {
            t->fail(e.what());
        }
    }
    static void cb_precise(uc_engine*, uint64_t, uint32_t, void*) {}
    static uint64_t cb_mmio_read(uc_engine*, uint64_t off, unsigned size, void* u)
    {
        auto* w = static_cast<Window*>(u);
        try {
            if (w->kind == 1) return w->t->scs_read(static_cast<uint32_t>(off), size);
            if (w->kind == 2) return w->t->dwt_read(static_cast<uint32_t>(off), size);
            return w->t->periph_->read(w->base + off, size);
        } catch (const std::exception& e) {
            w->t->fail(std::string("peripheral read at ") + hex(w->base + off) + ": " + e.what());
            return 0;
        }
    }
    static void cb_mmio_write(uc_engine*, uint64_t off, unsigned size, uint64_t value, void* u)
    {
        auto* w = static_cast<Window*>(u);
        try {
            if (w->kind == 1)
                w->t->scs_write(static_cast<uint32_t>(off), size, static_cast<uint32_t>(value));
            else if (w->kind == 2)
                w->t->dwt_write(static_cast<uint32_t>(off), size, static_cast<uint32_t>(value));
            else
                w->t->periph_->write(w->base + off, size, value);
        } catch (const std::exception& e) {
            w->t->fail(std::string("peripheral write at ") + hex(w->base + off) + ": " + e.what());
        }
    }

    void on_block(uint32_t addr, uint32_t size)
    {
        if (stopping_) return;
        lazy_here_ = false;
        uint32_t cpsr = 0;
        bool thumb = true;
        if (core_ == Core::CortexR5F) {
            cpsr = rd(UC_ARM_REG_CPSR);
            thumb = (cpsr & 0x20u) != 0;
        }
        // the interrupted code reached again: the ISR is over (the block is not part of it)
        if (in_isr_ && addr == ret_pc_) {
            const bool back = core_ == Core::CortexM4F
                                  ? exc_returned_
                                  : (prev_ && prev_->branch == BranchKind::ExcReturn && (cpsr & 0x1Fu) == ret_mode_);
            if (back) {
                // R5F: the exception return's (unpredicted) refill is part of the ISR; M4F: the
                // EXC_RETURN branch's refill is inside the documented exit latency
                if (core_ == Core::CortexR5F && prev_) {
                    const double p = model_.branch_penalty(*prev_, addr);
                    charge(p, 0, stage_);
                    if (profiling_) prof_[prev_->addr].cycles += p;
                }
                prev_ = nullptr;
                isr_done_ = true;
                stopping_ = true;
                stop();
                return;
            }
        }
        if (prev_) {
            const double p = model_.branch_penalty(*prev_, addr);
            if (p != 0) {
                charge(p, 0, stage_);
                if (profiling_ && in_isr_) prof_[prev_->addr].cycles += p;
            }
        }
        // an FP instruction while CP10/CP11 were off, and they still are: the NOCP UsageFault
        if (nocp_pending_) {
            if (!fp_enabled()) {
                fail(nocp_message());
                return;
            }
            nocp_pending_ = false;
        }
        const BlockCost* b = model_.block(addr, size, thumb);
        if (!b) {
            fail("cannot read the code at " + hex(addr));
            return;
        }
        if (executed_ + b->n > budget_) {
            if (preempt_) {   // run_background_for: the share is over, not an error
                preempted_ = true;
                stopping_ = true;
                stop();
                return;
            }
            std::ostringstream m;
            m << "exceeded " << budget_ << " instructions (at PC " << hex(addr) << ")";
            fail(m.str());
            return;
        }
        executed_ += b->n;
        if (b->has_fp && core_ == Core::CortexM4F) {
            if (!fp_enabled()) {
                nocp_pending_ = true;
                nocp_addr_ = b->first_fp;
            }
            if (in_isr_ && fp_frame_ && !lazy_done_) {   // lazy FP state preservation
                lazy_done_ = true;
                lazy_here_ = true;
                charge(model_.timing().fp_lazy_save, 0, stage_);
            }
        }
        charge(b->cycles, b->n, stage_);
        if (profiling_ && in_isr_) {
            auto& e = prof_[b->addr];
            e.cycles += b->cycles;
            e.instructions += b->n;
        }
        prev_ = b;
        cur_ = b;
        last_ = b;
        site_next_ = 0;
    }

    void on_stage(uint32_t addr, int size, uint64_t value)
    {
        if (!acc_ || !cur_) return;   // background stores: no ISR to split
        uint32_t word = 0;
        uc_mem_read(uc_, stage_addr_, &word, 4);   // before the store
        const unsigned sh = 8u * (addr - stage_addr_);
        const uint32_t mask = size >= 4 ? 0xFFFFFFFFu : (((1u << (8u * static_cast<unsigned>(size))) - 1u) << sh);
        word = (word & ~mask) | ((static_cast<uint32_t>(value) << sh) & mask);
        if (word >= 8) return;   // not a stage (hal_stage_t has 6)
        const int next = static_cast<int>(word);
        const BlockCost::Site* site = store_site(addr, static_cast<unsigned>(size), static_cast<uint32_t>(value));
        if (site && next != stage_) {   // the rest of the block goes to the new stage
            const double cy = cur_->cycles - site->cycles_through;
            const uint32_t n = cur_->n - site->n_through;
            acc_->stage[stage_].cycles -= cy;
            acc_->stage[stage_].instructions -= n;
            acc_->stage[next].cycles += cy;
            acc_->stage[next].instructions += n;
            if (lazy_here_ && cur_->first_fp_n > site->n_through) {   // the lazy FP save comes later in the block
                const double lz = model_.timing().fp_lazy_save;
                acc_->stage[stage_].cycles -= lz;
                acc_->stage[next].cycles += lz;
            }
        }
        stage_ = next;
    }

    // Which store of the running block wrote the marker. Unicorn leaves the PC at the block's
    // start during a memory hook, but TCG has the guest registers in memory at a store (a side
    // effect op), so the stores are told apart by their operands: the first store, after the one
    // found last in this block, whose address operands give the marker's address and whose data
    // register holds the value. Failing that, the block's only store; failing that, the block
    // is run with a code hook from then on (exact PC), and this time the split falls at its end.
    const BlockCost::Site* store_site(uint32_t addr, unsigned size, uint32_t value)
    {
        const auto& st = cur_->stores;
        if (precise_.count(cur_->addr)) {
            const uint32_t pc = rd(UC_ARM_REG_PC);
            for (const auto& s : st)
                if (s.addr == pc) return &s;
            return nullptr;
        }
        const uint32_t vmask = size >= 4 ? 0xFFFFFFFFu : (1u << (8u * size)) - 1u;
        for (size_t k = site_next_; k < st.size(); ++k) {
            const BlockCost::Site& s = st[k];
            if (s.base < 0) continue;
            const uint32_t base = core_reg(s.base);
            uint32_t a = base;
            if (!s.post) {
                const uint32_t off = s.index >= 0 ? core_reg(s.index) << s.shift : static_cast<uint32_t>(s.disp);
                a = s.index >= 0 && s.subtract ? base - off : base + off;
            }
            if (a != addr) continue;
            if (s.data >= 0 && (core_reg(s.data) & vmask) != (value & vmask)) continue;
            site_next_ = k + 1;
            return &s;
        }
        if (st.size() == 1 && site_next_ == 0) {
            site_next_ = 1;
            return &st[0];
        }
        pending_precise_.insert({cur_->addr, cur_->size});
        return nullptr;
    }
    uint32_t core_reg(int n) { return rd(n <= 12 ? UC_ARM_REG_R0 + n : n == 13 ? UC_ARM_REG_SP : UC_ARM_REG_LR); }

    // A block with several stores that wrote the stage marker: from now on it runs with a code
    // hook, which makes Unicorn keep the PC exact, so that the store is found by its address.
    void instrument_precise()
    {
        for (const auto& [addr, size] : pending_precise_) {
            if (precise_.count(addr)) continue;
            uc_hook h;
            if (uc_hook_add(uc_, &h, UC_HOOK_CODE, reinterpret_cast<void*>(&UcTarget::cb_precise), this, addr,
                            static_cast<uint64_t>(addr) + size - 1) == UC_ERR_OK) {
                uc_ctl_remove_cache(uc_, static_cast<uint64_t>(addr), static_cast<uint64_t>(addr) + size);
                precise_.insert(addr);
            }
        }
        pending_precise_.clear();
    }

    void on_intr(uint32_t intno)
    {
        if (core_ == Core::CortexM4F && intno == kExcpExceptionExit && in_isr_ && !exc_returned_) {
            exception_return_m();
            return;
        }
        std::ostringstream m;
        m << excp_name(intno) << " (QEMU exception " << intno << ") at PC " << hex(rd(UC_ARM_REG_PC))
          << ": the engine emulates no exception but the control interrupt";
        if (intno == kExcpExceptionExit) m << " (an EXC_RETURN branch outside the control ISR)";
        fail(m.str());
    }

    // ---- Cortex-M4F
    bool fp_enabled() const
    {
        if (core_ != Core::CortexM4F) return true;
        const uint32_t cp10 = (cpacr_ >> 20) & 3u, cp11 = (cpacr_ >> 22) & 3u;
        return (cp10 == 1u || cp10 == 3u) && (cp11 == 1u || cp11 == 3u);
    }
    std::string nocp_message() const
    {
        return "FP instruction at " + hex(nocp_addr_) + " with CPACR " + hex(cpacr_) +
               " (CP10/CP11 not enabled): a NOCP UsageFault on the core; enable the FPU first (CPACR at 0xE000ED88)";
    }

    bool take_irq_m(IsrCost* cost, uint64_t max_instructions)
    {
        if (!periph_->irq_pending()) return false;
        if (!(nvic_en_[kControlIrq / 32] & (1u << (kControlIrq % 32)))) return false;   // not enabled in the NVIC
        if ((rd(UC_ARM_REG_PRIMASK) & 1u) || (rd(UC_ARM_REG_FAULTMASK) & 1u)) return false;
        const uint32_t basepri = rd(UC_ARM_REG_BASEPRI) & 0xF0u, prio = ipr_[kControlIrq] & 0xF0u;
        if (basepri != 0 && prio >= basepri) return false;
        const uint32_t xpsr = rd(UC_ARM_REG_XPSR);
        if (faults_ && (xpsr & 0x1FFu) >= 2u && (xpsr & 0x1FFu) <= 6u) return false;   // NMI/faults: higher priority
        if (xpsr & 0x1FFu)
            throw RunError("pil: take_irq: the core is in handler mode (IPSR " + std::to_string(xpsr & 0x1FFu) +
                           "): nested exceptions are not emulated");
        const uint32_t control = rd(UC_ARM_REG_CONTROL);
        if (control & 2u) throw RunError("pil: take_irq: thread mode on the process stack (CONTROL.SPSEL) is not emulated");
        const bool fpca = (control & 4u) != 0;
        const uint32_t sp = rd(UC_ARM_REG_SP);
        const uint32_t frame = fpca ? 0x68u : 0x20u;
        const bool align = ((sp - frame) & 4u) != 0;   // CCR.STKALIGN: 8-byte aligned frame, xPSR bit 9
        const uint32_t fptr = (sp - frame) & ~4u;
        ret_pc_ = rd(UC_ARM_REG_PC) & ~1u;
        uint32_t w[26] = {};
        const int core_regs[6] = {UC_ARM_REG_R0, UC_ARM_REG_R1, UC_ARM_REG_R2, UC_ARM_REG_R3, UC_ARM_REG_R12, UC_ARM_REG_LR};
        for (int k = 0; k < 6; ++k) w[k] = rd(core_regs[k]);
        w[6] = ret_pc_;
        w[7] = xpsr | (align ? 0x200u : 0u);
        if (fpca) {
            for (int k = 0; k < 16; ++k) w[8 + k] = rd(UC_ARM_REG_S0 + k);
            w[24] = rd(UC_ARM_REG_FPSCR);
        }
        if (uc_mem_write(uc_, fptr, w, frame) != UC_ERR_OK)
            throw RunError("pil: take_irq: the exception frame at " + hex(fptr) + " (SP " + hex(sp) +
                           ") is not in memory: stack overflow");
        uint32_t vec = 0;
        const uint32_t vaddr = vtor_ + 4u * (16u + kControlIrq);
        if (uc_mem_read(uc_, vaddr, &vec, 4) != UC_ERR_OK || !(vec & 1u))
            throw RunError("pil: take_irq: vector " + std::to_string(16 + kControlIrq) + " at " + hex(vaddr) + " is " +
                           hex(vec) + ", not a Thumb handler address (a HardFault on the core)");
        exc_return_ = fpca ? 0xFFFFFFE9u : 0xFFFFFFF9u;   // thread mode, main stack, (no) FP frame
        wr(UC_ARM_REG_SP, fptr);
        wr(UC_ARM_REG_LR, exc_return_);
        wr(UC_ARM_REG_CONTROL, control & ~4u);   // FPCA cleared on entry
        wr(UC_ARM_REG_XPSR_NZCVQG, (xpsr & 0xF80F0000u) | 0x01000000u | (16u + kControlIrq));
        rebuild_hflags();

        fp_frame_ = fpca;
        lazy_done_ = false;
        exc_returned_ = false;
        do_isr(cost, vec, max_instructions);
        return true;
    }

    // EXCP_EXCEPTION_EXIT: the handler branched to EXC_RETURN; unstack as the core does.
    void exception_return_m()
    {
        const uint32_t excret = rd(UC_ARM_REG_PC) | 1u;
        if (excret != exc_return_) {
            fail("exception return with EXC_RETURN " + hex(excret) + ", " + hex(exc_return_) + " expected");
            return;
        }
        const bool fpframe = (excret & 0x10u) == 0;
        const uint32_t frame = fpframe ? 0x68u : 0x20u;
        const uint32_t sp = rd(UC_ARM_REG_SP);
        uint32_t w[26] = {};
        if (uc_mem_read(uc_, sp, w, frame) != UC_ERR_OK) {
            fail("exception return: the frame at SP " + hex(sp) + " is not in memory");
            return;
        }
        const int core_regs[6] = {UC_ARM_REG_R0, UC_ARM_REG_R1, UC_ARM_REG_R2, UC_ARM_REG_R3, UC_ARM_REG_R12, UC_ARM_REG_LR};
        for (int k = 0; k < 6; ++k) wr(core_regs[k], w[k]);
        if (fpframe) {
            for (int k = 0; k < 16; ++k) wr(UC_ARM_REG_S0 + k, w[8 + k]);
            wr(UC_ARM_REG_FPSCR, w[24]);
        }
        wr(UC_ARM_REG_SP, sp + frame + ((w[7] & 0x200u) ? 4u : 0u));
        const uint32_t control = rd(UC_ARM_REG_CONTROL);
        wr(UC_ARM_REG_CONTROL, fpframe ? (control | 4u) : (control & ~4u));
        wr(UC_ARM_REG_XPSR_NZCVQG, w[7] & ~0x200u);
        rebuild_hflags();
        exc_returned_ = true;
        if ((w[6] & ~1u) != ret_pc_) {
            fail("exception return to " + hex(w[6]) + ", the interrupted PC was " + hex(ret_pc_) +
                 " (the handler changed its stack frame)");
            return;
        }
        wr(UC_ARM_REG_PC, w[6] | 1u);   // Unicorn resumes there; the block hook stops
    }

    // ---- Cortex-R5F
    bool take_irq_r(IsrCost* cost, uint64_t max_instructions)
    {
        if (!periph_->irq_pending()) return false;
        const uint32_t cpsr = rd(UC_ARM_REG_CPSR);
        if (cpsr & 0x80u) return false;   // IRQs masked (CPSR.I)
        const uint32_t mode = cpsr & 0x1Fu;
        if (mode == 0x12u) throw RunError("pil: take_irq: the core is in IRQ mode: nested interrupts are not emulated");
        ret_pc_ = rd(UC_ARM_REG_PC) & ~1u;
        ret_mode_ = mode;
        uc_arm_cp_reg sctlr_r{15, 0, 0, 1, 0, 0, 0, 0};
        uc_reg_read(uc_, UC_ARM_REG_CP_REG, &sctlr_r);
        const uint32_t sctlr = static_cast<uint32_t>(sctlr_r.val);
        const uint32_t vic = periph_->irq_vector();   // the interrupt controller's hand-off
        const bool te = (sctlr & (1u << 30)) != 0;
        uint32_t ncpsr = (cpsr & ~(0x1Fu | 0x20u | 0x0600FC00u | 0x200u)) | 0x12u | 0x80u | 0x100u;
        if (te) ncpsr |= 0x20u;
        if (sctlr & (1u << 25)) ncpsr |= 0x200u;   // EE -> CPSR.E
        wr(UC_ARM_REG_CPSR, ncpsr);               // banks SP, LR, SPSR (switch_mode)
        wr(UC_ARM_REG_SPSR, cpsr);
        wr(UC_ARM_REG_LR, ret_pc_ + 4u);
        uint32_t entry = (sctlr & (1u << 13)) ? 0xFFFF0018u : 0x18u;
        if ((sctlr & (1u << 24)) && vic != 0) entry = vic & ~1u;   // VE: the VIC port's address
        if (te) entry |= 1u;
        lazy_done_ = false;
        do_isr(cost, entry, max_instructions);
        return true;
    }

    // ---- ISR runs: entry cost, the handler to its return, exit cost (both in stage 0)
    void do_isr(IsrCost* cost, uint32_t entry, uint64_t max_instructions)
    {
        *cost = IsrCost{};
        acc_ = cost;
        stage_ = 0;
        in_isr_ = true;
        struct End {
            UcTarget* t;
            ~End()
            {
                t->in_isr_ = false;
                t->acc_ = nullptr;
            }
        } end{this};
        const CoreTiming& t = model_.timing();
        charge(t.irq_entry, 0, 0);
        run(entry, max_instructions, "ISR");
        if (!isr_done_) {
            std::ostringstream m;
            m << "pil (ISR): the core stopped at PC " << hex(rd(UC_ARM_REG_PC)) << " before returning to "
              << hex(ret_pc_) << (last_ && last_->ends_wfi ? " (a WFI inside the ISR)" : "");
            throw RunError(m.str());
        }
        charge(t.irq_exit + (lazy_done_ ? t.fp_unstack : 0.0), 0, 0);
    }

    // ---- System Control Space (Cortex-M)
    void scs_reset()
    {
        std::fill(std::begin(nvic_en_), std::end(nvic_en_), 0u);
        std::fill(std::begin(ipr_), std::end(ipr_), uint8_t{0});
        scs_regs_.clear();
        cpacr_ = 0;
        vtor_ = vbase_;
        scs_regs_[0xD14] = 0x200u;        // CCR: STKALIGN
        scs_regs_[0xF34] = 0xC0000000u;   // FPCCR: ASPEN, LSPEN
        dwt_ctrl_ = 0x40000000u;          // DWT_CTRL: NUMCOMP 4
    }
    uint32_t scs_word(uint32_t off)
    {
        if (off >= 0x100 && off < 0x140) return nvic_en_[(off - 0x100) / 4];
        if (off >= 0x180 && off < 0x1C0) return nvic_en_[(off - 0x180) / 4];
        if ((off >= 0x200 && off < 0x240) || (off >= 0x280 && off < 0x2C0)) {   // ISPR/ICPR
            const uint32_t k = (off & 0x3F) / 4;
            return (k == kControlIrq / 32 && periph_->irq_pending()) ? (1u << (kControlIrq % 32)) : 0u;
        }
        if (off >= 0x300 && off < 0x340) {   // IABR
            const uint32_t k = (off - 0x300) / 4;
            return (k == kControlIrq / 32 && in_isr_) ? (1u << (kControlIrq % 32)) : 0u;
        }
        if (off >= 0x400 && off < 0x4F0) {
            uint32_t v = 0;
            for (unsigned j = 0; j < 4; ++j) v |= static_cast<uint32_t>(ipr_[off - 0x400 + j]) << (8 * j);
            return v;
        }
        switch (off) {
        case 0x004: return 0;                  // ICTR: 32 lines
        case 0xD00: return 0x410FC241u;        // CPUID: Cortex-M4 r0p1
        case 0xD04: {                          // ICSR
            uint32_t v = rd(UC_ARM_REG_IPSR) & 0x1FFu;
            if (periph_->irq_pending()) v |= (1u << 22) | ((16u + kControlIrq) << 12);
            return v;
        }
        case 0xD08: return vtor_;
        case 0xD0C: return 0xFA050000u | (scs_regs_[0xD0C] & 0x700u);   // AIRCR
        case 0xD88: return cpacr_;
        default: {
            auto it = scs_regs_.find(off);
            return it == scs_regs_.end() ? 0u : it->second;
        }
        }
    }
    uint64_t scs_read(uint32_t off, unsigned size)
    {
        const uint32_t w = scs_word(off & ~3u);
        const unsigned sh = 8u * (off & 3u);
        return size >= 4 ? w : (w >> sh) & ((1u << (8u * size)) - 1u);
    }
    void scs_write(uint32_t off, unsigned size, uint32_t v)
    {
        if (off >= 0x400 && off < 0x4F0) {   // IPR: byte-accessible
            for (unsigned j = 0; j < size && off - 0x400 + j < sizeof ipr_; ++j)
                ipr_[off - 0x400 + j] = static_cast<uint8_t>(v >> (8 * j));
            return;
        }
        const uint32_t a = off & ~3u;
        if (size < 4) {
            const unsigned sh = 8u * (off & 3u);
            const uint32_t mask = ((1u << (8u * size)) - 1u) << sh;
            v = (scs_word(a) & ~mask) | ((v << sh) & mask);
        }
        if (a >= 0x100 && a < 0x140) {
            nvic_en_[(a - 0x100) / 4] |= v;
        } else if (a >= 0x180 && a < 0x1C0) {
            nvic_en_[(a - 0x180) / 4] &= ~v;
        } else if ((a >= 0x200 && a < 0x2C0) || (a >= 0x300 && a < 0x340) || a == 0xD00 || a == 0xD04 || a == 0xF00) {
            // pending/active state is the peripherals' (ISPR/ICPR/IABR/ICSR/STIR writes are not emulated); CPUID RO
        } else if (a == 0xD08) {
            vtor_ = v & 0xFFFFFF80u;
        } else if (a == 0xD0C) {
            if ((v >> 16) == 0x05FAu) {
                if (v & 4u) {
                    fail("the image requested a system reset (AIRCR.SYSRESETREQ)");
                    return;
                }
                scs_regs_[0xD0C] = v & 0x700u;
            }
        } else if (a == 0xD88) {
            cpacr_ = v & 0x00F00000u;
        } else {
            scs_regs_[a] = v;
        }
    }
    uint64_t dwt_read(uint32_t off, unsigned size)
    {
        uint32_t w = 0;
        if ((off & ~3u) == 0) w = dwt_ctrl_;
        if ((off & ~3u) == 4) w = static_cast<uint32_t>(static_cast<uint64_t>(total_.cycles) - dwt_base_);
        const unsigned sh = 8u * (off & 3u);
        return size >= 4 ? w : (w >> sh) & ((1u << (8u * size)) - 1u);
    }
    void dwt_write(uint32_t off, unsigned size, uint32_t v)
    {
        (void)size;
        if ((off & ~3u) == 0) dwt_ctrl_ = (dwt_ctrl_ & 0xF0000000u) | (v & 0x0FFFFFFFu);
        if ((off & ~3u) == 4) dwt_base_ = static_cast<uint64_t>(total_.cycles) - v;
    }

    // ---- state
    Core core_;
    std::string port_;
    std::unique_ptr<Peripherals> periph_;
    std::string origin_;
    uc_engine* uc_ = nullptr;
    CycleModel model_;
    std::vector<MmioWindow> mems_;
    std::vector<std::unique_ptr<Window>> windows_;
    std::map<std::string, ElfSymbol> syms_;
    std::vector<std::string> notes_;
    uint32_t vbase_ = 0;

    // run
    uint64_t budget_ = 0, executed_ = 0;
    std::string error_, mem_fault_;
    bool stopping_ = false;
    bool preempt_ = false, preempted_ = false;   // run_background_for
    const BlockCost* prev_ = nullptr;   // the block before, for its branch penalty
    const BlockCost* cur_ = nullptr;    // the block running (stage split)
    const BlockCost* last_ = nullptr;   // the last block entered (idle check)
    bool nocp_pending_ = false;
    uint32_t nocp_addr_ = 0;

    // accounting
    StageCycles total_, isr_total_;
    IsrCost* acc_ = nullptr;
    int stage_ = 0;
    uc_hook stage_hook_ = 0;
    uint32_t stage_addr_ = 0;
    bool profiling_ = false;
    struct Prof {
        uint64_t instructions = 0;
        double cycles = 0;
    };
    std::unordered_map<uint32_t, Prof> prof_;   // by block address
    std::unordered_set<uint32_t> precise_;
    size_t site_next_ = 0;   // stores of the running block before this one wrote the marker
    std::set<std::pair<uint32_t, uint32_t>> pending_precise_;

    // ISR
    bool in_isr_ = false, isr_done_ = false;
    bool fault_entry_ = false;   // set_fault_entry
    unsigned faults_ = 0;
    uint32_t ret_pc_ = 0, ret_mode_ = 0;
    uint32_t exc_return_ = 0;
    bool exc_returned_ = false, fp_frame_ = false, lazy_done_ = false;
    bool lazy_here_ = false;   // the lazy FP save was charged at the running block's entry

    // Cortex-M System Control Space, DWT
    uint32_t nvic_en_[16] = {};
    uint8_t ipr_[240] = {};
    std::unordered_map<uint32_t, uint32_t> scs_regs_;
    uint32_t cpacr_ = 0, vtor_ = 0;
    uint32_t dwt_ctrl_ = 0;
    uint64_t dwt_base_ = 0;
};


[[noreturn]] void load_fail(const std::string& path, const std::string& why)
{
    throw LoadError(path + ": " + why);
}

bool ram_contains_sp(const std::vector<MmioWindow>& mems, uint32_t sp)
{
    bool any_ram = false;
    for (const auto& m : mems) any_ram = any_ram || name_is_ram(m.name);
    for (const auto& m : mems)
        if ((!any_ram || name_is_ram(m.name)) && sp > m.base && sp <= m.base + m.size) return true;
    return false;
}

std::string ram_list(const std::vector<MmioWindow>& mems)
{
    std::vector<MmioWindow> r;
    for (const auto& m : mems)
        if (name_is_ram(m.name)) r.push_back(m);
    return describe_memories(r.empty() ? mems : r);
}

// Boot mode (a TI multicore boot image instead of the ELF): the memory holds what TI's SBL writes,
// each RPRC section at its address and nothing else (no .bss zeroing, no load image); the SBL's
// TCM initialisation leaves the TCMs zero (soc/am263x/bootloader_soc.c Bootloader_socMemInitCpu),
// as the emulator's memories start. The ELF beside it (same name, .elf) gives only the symbols,
// the build attributes and the port's name. One core, R5FSS0-0 (RPRC core id 0), device id 55 (the AM263x SBL's).
std::string boot_image_elf(const std::string& path)
{
    const std::string elf = std::filesystem::path(path).replace_extension(".elf").string();
    if (!std::filesystem::exists(elf))
        load_fail(path, "a boot image: its symbols come from the ELF beside it, " + elf + ", which does not exist");
    return elf;
}

std::vector<Segment> boot_image_contents(const BootImage& b, const std::string& port, const std::vector<MmioWindow>& mems)
{
    if (port != "am263x")
        load_fail(b.path, "a TI multicore boot image, but the ELF's port is '" + port + "' (the SBL boots the am263x port)");
    if (b.dev_id != 55) load_fail(b.path, "device id " + std::to_string(b.dev_id) + ", not 55 (AM263x)");
    if (b.cores.size() != 1 || b.cores[0].core_id != 0)
        load_fail(b.path, "the PIL boots one core, R5FSS0-0 (RPRC core id 0); the image has " + std::to_string(b.cores.size()) +
                              " core(s), the first with id " + (b.cores.empty() ? std::string("-") : std::to_string(b.cores[0].core_id)));
    for (const auto& s : b.cores[0].sections)
        if (!s.bytes.empty() && !memory_of(mems, s.addr, s.bytes.size()))
            load_fail(b.path, "section at " + hex(s.addr) + "+" + hex(static_cast<uint32_t>(s.bytes.size())) +
                                  " lies outside the memories of port '" + port + "' (" + describe_memories(mems) + ")");
    return b.cores[0].sections;
}

}  // namespace

std::unique_ptr<Target> Target::load(const std::string& path)
{
    std::unique_ptr<BootImage> boot;
    if (is_boot_image(path)) boot = std::make_unique<BootImage>(read_boot_image(path));
    ElfImage img = read_elf(boot ? boot_image_elf(path) : path);
    if (img.segments.empty()) load_fail(path, "no loadable segment (PT_LOAD): nothing to put into the target's memory");

    // The port: the image names it (hal_port_name), the engine maps its peripheral model.
    auto pn = img.symbols.find("hal_port_name");
    if (pn == img.symbols.end())
        load_fail(path, "no symbol 'hal_port_name': not a firmware image of this project (its HAL port names itself "
                        "there: \"generic\", \"am263x\")");
    std::string port;
    {
        bool terminated = false;
        for (uint32_t k = 0; k < 64; ++k) {
            char c = 0;
            if (!img.read_vaddr(pn->second.value + k, &c, 1))
                load_fail(path, "hal_port_name at " + hex(pn->second.value) + " is not in a loaded segment");
            if (c == 0) {
                terminated = true;
                break;
            }
            port += c;
        }
        if (!terminated) load_fail(path, "hal_port_name at " + hex(pn->second.value) + " is not a NUL-terminated name");
    }
    std::unique_ptr<Peripherals> periph;
    if (port == "generic") {
        periph = make_generic_peripherals();
    } else if (port == "am263x") {
        try {
            periph = make_am263x_peripherals();
        } catch (const LoadError& e) {
            load_fail(path, std::string("port 'am263x': ") + e.what());
        }
    } else {
        load_fail(path, "unknown port '" + port + "' (hal_port_name): the PIL has models of 'generic' and 'am263x'");
    }
    const std::vector<MmioWindow> mems = periph->memories();

    // Every segment inside the port's memories: its file image at the load address, its zeroed
    // tail (memsz > filesz) at the run address.
    std::vector<Segment> contents;
    for (const auto& s : img.segments) {
        if (s.filesz > 0 && !memory_of(mems, s.paddr, s.filesz))
            load_fail(path, "segment at " + hex(s.paddr) + "+" + hex(s.filesz) + " (load address) lies outside the memories of port '" +
                                port + "' (" + describe_memories(mems) + ")");
        if (s.memsz > s.filesz && !memory_of(mems, static_cast<uint64_t>(s.vaddr) + s.filesz, s.memsz - s.filesz))
            load_fail(path, "segment at " + hex(s.vaddr) + "+" + hex(s.memsz) + " (run address) lies outside the memories of port '" +
                                port + "' (" + describe_memories(mems) + ")");
        if (s.filesz > 0) contents.push_back({s.paddr, s.data});
        if (s.memsz > s.filesz) contents.push_back({s.vaddr + s.filesz, std::vector<uint8_t>(s.memsz - s.filesz, 0)});
    }
    if (boot) contents = boot_image_contents(*boot, port, mems);

    // The core: the build attributes, else the vector table.
    std::vector<std::string> notes;
    Core core = Core::CortexM4F;
    uint32_t w0 = 0, w1 = 0;
    const bool have0 = img.read_paddr(0, &w0, 4);
    const bool have1 = img.read_paddr(4, &w1, 4);
    if (img.cpu_arch_profile == 'M') {
        core = Core::CortexM4F;
    } else if (img.cpu_arch_profile == 'R') {
        core = Core::CortexR5F;
    } else if (img.cpu_arch_profile > 0) {
        std::string p(1, static_cast<char>(img.cpu_arch_profile));
        load_fail(path, "built for the ARM '" + p + "' profile (Tag_CPU_arch_profile" +
                            (img.cpu_name.empty() ? std::string() : ", CPU " + img.cpu_name) +
                            "): the PIL emulates Cortex-M4F ('M') and Cortex-R5F ('R')");
    } else {
        const bool arm_reset = have0 && ((w0 & 0xFF000000u) == 0xEA000000u || (w0 & 0xFFFFF000u) == 0xE59FF000u);
        const bool m_vectors = have0 && have1 && (w1 & 1u) && ram_contains_sp(mems, w0);
        const std::string why = img.has_attributes ? "no Tag_CPU_arch_profile in .ARM.attributes" : "no .ARM.attributes section";
        if (m_vectors || (img.entry & 1u)) {
            core = Core::CortexM4F;
            notes.push_back(why + ": Cortex-M4F assumed from " +
                            (m_vectors ? "the vector table at 0 (initial SP " + hex(w0) + ", reset " + hex(w1) + ")"
                                       : "the Thumb entry point " + hex(img.entry)));
        } else if (arm_reset) {
            core = Core::CortexR5F;
            notes.push_back(why + ": Cortex-R5F assumed from the ARM reset vector at 0 (" + hex(w0) + ")");
        } else {
            load_fail(path, why + ", and neither a Cortex-M vector table nor an ARM reset vector at address 0: cannot tell the core");
        }
    }

    // The vector table.
    uint32_t vbase = 0;
    if (core == Core::CortexM4F) {
        for (const char* v : {"__vectors", "g_vectors"}) {
            auto it = img.symbols.find(v);
            if (it != img.symbols.end()) {
                vbase = it->second.value & ~1u;
                break;
            }
        }
        uint32_t v[2] = {0, 0};
        if (!img.read_paddr(vbase, v, 8) && !img.read_vaddr(vbase, v, 8))
            load_fail(path, "no vector table: nothing loaded at " + hex(vbase) +
                                " (a Cortex-M boots from the vector table: initial SP, reset vector)");
        if (!ram_contains_sp(mems, v[0]))
            load_fail(path, "no vector table at " + hex(vbase) + ": word 0 (initial SP) is " + hex(v[0]) + ", not inside RAM (" +
                                ram_list(mems) + ")");
        if (!(v[1] & 1u) || !memory_of(mems, v[1] & ~1u, 2))
            load_fail(path, "no vector table at " + hex(vbase) + ": word 1 (reset vector) is " + hex(v[1]) +
                                ", not a Thumb address (bit 0 set) inside a memory (" + describe_memories(mems) + ")");
    } else {
        if (!have0)
            load_fail(path, "no reset vector: nothing loaded at address 0 (a Cortex-R5F resets to 0 in ARM state)");
    }

    auto t = std::make_unique<UcTarget>(core, port, std::move(periph), path);
    t->set_symbols(img.symbols);
    t->set_vector_base(vbase);
    t->load_contents(contents);
    t->bind();
    for (const auto& n : notes) {
        t->add_note(n);
        std::cerr << "pil: " << path << ": " << n << "\n";
    }
    auto st = img.symbols.find("hal_stage_reg");
    if (st != img.symbols.end()) t->set_stage_marker(st->second.value);
    return t;
}

std::unique_ptr<Target> Target::create(Core core, std::unique_ptr<Peripherals> periph, const std::vector<Segment>& contents,
                                       const std::string& port)
{
    if (!periph) throw LoadError("pil: create: no peripherals");
    auto t = std::make_unique<UcTarget>(core, port, std::move(periph), "pil(" + port + ")");
    t->load_contents(contents);
    t->bind();
    return t;
}

}  // namespace mcsim::pil
