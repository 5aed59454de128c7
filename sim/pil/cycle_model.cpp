// Instruction-class cycle model (cycle_model.hpp); the tables and their sources are in
// docs/pil-cycle-model.md.
#include "cycle_model.hpp"

#include <capstone/capstone.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mcsim::pil {

// Cortex-M4 TRM (ARM DDI 0439) "Instruction timings" (table "Cortex-M4 instruction set summary")
// and the FPU chapter ("FPU instruction set" table); exception timing from the TRM's
// "Exception model" / ARM AN298 (lazy stacking). Zero wait states.
const CoreTiming kCortexM4Timing = {
    "Cortex-M4F",
    /*alu*/ 1, /*mul*/ 1, /*mac*/ 1, /*mul_long*/ 1, /*mac_long*/ 1, /*div*/ 7,
    /*load*/ 2, /*load_pipelined*/ 1, /*store*/ 1, /*load_double*/ 3, /*store_double*/ 3,
    /*ldm_base*/ 1, /*ldm_per_cycle*/ 1,
    /*branch*/ 1, /*table_branch*/ 2, /*refill*/ 2, /*mispredict*/ 0, /*predicts*/ false, /*return_stack*/ 0,
    /*isb*/ 3, /*barrier*/ 1, /*sysreg*/ 1, /*wfi*/ 1,
    /*fp_alu*/ 1, /*fp_alu_f64*/ 1, /*fp_mul_f64*/ 1, /*fp_misc*/ 1, /*fp_mac*/ 3, /*fp_mac_f64*/ 3,
    /*fp_div*/ 14, /*fp_div_f64*/ 14, /*fp_sqrt*/ 14, /*fp_sqrt_f64*/ 14,
    /*fp_load*/ 2, /*fp_load_f64*/ 3, /*fp_store*/ 2, /*fp_store_f64*/ 3, /*fpm_base*/ 1, /*fpm_per_cycle*/ 1,
    /*fp_xfer*/ 1, /*fp_xfer2*/ 2,
    /*irq_entry*/ 12, /*irq_exit*/ 10, /*fp_lazy_save*/ 17, /*fp_unstack*/ 17,
};

// Cortex-R5 TRM (ARM DDI 0460) "Cycle Timings and Interlock Behavior" (single issue: the
// documented dual-issue pairs are not taken; result latencies and interlocks are not modelled),
// the prefetch unit's branch prediction and return stack ("Prefetch Unit"), the FPU's
// instruction timing; TCM at zero wait states.
const CoreTiming kCortexR5Timing = {
    "Cortex-R5F",
    /*alu*/ 1, /*mul*/ 2, /*mac*/ 2, /*mul_long*/ 2, /*mac_long*/ 2, /*div*/ 10,
    /*load*/ 1, /*load_pipelined*/ 1, /*store*/ 1, /*load_double*/ 1, /*store_double*/ 1,
    /*ldm_base*/ 0, /*ldm_per_cycle*/ 2,
    /*branch*/ 1, /*table_branch*/ 2, /*refill*/ 0, /*mispredict*/ 8, /*predicts*/ true, /*return_stack*/ 4,
    /*isb*/ 9, /*barrier*/ 1, /*sysreg*/ 1, /*wfi*/ 1,
    /*fp_alu*/ 1, /*fp_alu_f64*/ 1, /*fp_mul_f64*/ 2, /*fp_misc*/ 1, /*fp_mac*/ 1, /*fp_mac_f64*/ 2,
    /*fp_div*/ 15, /*fp_div_f64*/ 29, /*fp_sqrt*/ 15, /*fp_sqrt_f64*/ 29,
    /*fp_load*/ 1, /*fp_load_f64*/ 1, /*fp_store*/ 1, /*fp_store_f64*/ 1, /*fpm_base*/ 0, /*fpm_per_cycle*/ 2,
    /*fp_xfer*/ 1, /*fp_xfer2*/ 1,
    /*irq_entry*/ 8, /*irq_exit*/ 0, /*fp_lazy_save*/ 0, /*fp_unstack*/ 0,
};

const CoreTiming& core_timing(Core core)
{
    return core == Core::CortexM4F ? kCortexM4Timing : kCortexR5Timing;
}

namespace {

bool is_dreg(int r) { return r >= ARM_REG_D0 && r <= ARM_REG_D31; }
bool is_sreg(int r) { return r >= ARM_REG_S0 && r <= ARM_REG_S31; }
bool is_core(int r)
{
    return (r >= ARM_REG_R0 && r <= ARM_REG_R12) || r == ARM_REG_SP || r == ARM_REG_LR || r == ARM_REG_PC;
}

double multi(double base, double per_cycle, unsigned n)
{
    return base + std::ceil(static_cast<double>(n) / per_cycle);
}

// What one instruction is, for the table.
struct Cls {
    const char* name = "alu";
    double cycles = 1;
    bool fp = false;
    bool single_ls = false;   // LDR/STR of one register (M4 pipelining)
    bool load = false;
    bool store = false;       // any store (stage-marker split sites)
    int load_dest = 0;        // capstone register written by a single load
    BranchKind branch = BranchKind::None;
    bool cond = false;
    bool has_target = false;
    uint32_t target = 0;
};

bool reg_in_ops(const cs_arm& a, int reg, int from = 0)
{
    for (int k = from; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_REG && a.operands[k].reg == reg) return true;
    return false;
}

unsigned reg_ops(const cs_arm& a, int from = 0)
{
    unsigned n = 0;
    for (int k = from; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_REG) ++n;
    return n;
}

unsigned fp_words(const cs_arm& a, int from = 0)
{
    unsigned n = 0;
    for (int k = from; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_REG) n += is_dreg(a.operands[k].reg) ? 2u : is_sreg(a.operands[k].reg) ? 1u : 0u;
    return n;
}

bool any_dreg(const cs_arm& a)
{
    for (int k = 0; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_REG && is_dreg(a.operands[k].reg)) return true;
    return false;
}

unsigned core_regs(const cs_arm& a)
{
    unsigned n = 0;
    for (int k = 0; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_REG && is_core(a.operands[k].reg)) ++n;
    return n;
}

int mem_base(const cs_arm& a)
{
    for (int k = 0; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_MEM) return a.operands[k].mem.base;
    return 0;
}

int mem_index(const cs_arm& a)
{
    for (int k = 0; k < a.op_count; ++k)
        if (a.operands[k].type == ARM_OP_MEM) return a.operands[k].mem.index;
    return 0;
}

// Core register number 0..14 of a capstone register, -1 for anything else (PC included).
int8_t core_num(int r)
{
    if (r >= ARM_REG_R0 && r <= ARM_REG_R12) return static_cast<int8_t>(r - ARM_REG_R0);
    if (r == ARM_REG_SP) return 13;
    if (r == ARM_REG_LR) return 14;
    return -1;
}

// A single-register store's data register and address operands.
void describe_store(const cs_arm& a, BlockCost::Site* s)
{
    if (a.op_count < 2 || a.operands[0].type != ARM_OP_REG) return;
    for (int k = 1; k < a.op_count; ++k) {
        if (a.operands[k].type != ARM_OP_MEM) continue;
        const arm_op_mem& m = a.operands[k].mem;
        const int8_t base = core_num(m.base);
        if (base < 0) return;   // PC-relative: not described
        s->data = core_num(a.operands[0].reg);
        s->base = base;
        s->index = m.index != ARM_REG_INVALID ? core_num(m.index) : -1;
        s->shift = static_cast<uint8_t>(m.lshift);
        s->subtract = a.operands[k].subtracted || m.scale < 0;
        s->disp = m.disp;
        s->post = a.writeback && k + 1 < a.op_count;   // [Rn], #imm / [Rn], Rm: the address is Rn
        return;
    }
}

bool dest_is_pc(const cs_arm& a)
{
    return a.op_count > 0 && a.operands[0].type == ARM_OP_REG && a.operands[0].reg == ARM_REG_PC;
}

Cls classify(const cs_insn& in, const CoreTiming& t)
{
    const cs_arm& a = in.detail->arm;
    Cls c;
    c.cond = a.cc != ARM_CC_AL && a.cc != ARM_CC_INVALID;
    auto set = [&](const char* n, double cy) {
        c.name = n;
        c.cycles = cy;
    };
    auto fp = [&](const char* n, double cy) {
        set(n, cy);
        c.fp = true;
    };
    switch (in.id) {
    // ---- branches
    case ARM_INS_B:
        set("branch", t.branch);
        c.branch = BranchKind::Direct;
        if (a.op_count > 0 && a.operands[0].type == ARM_OP_IMM) {
            c.has_target = true;
            c.target = static_cast<uint32_t>(a.operands[0].imm);
        }
        break;
    case ARM_INS_CBZ:
    case ARM_INS_CBNZ:
        set("branch", t.branch);
        c.branch = BranchKind::Direct;
        c.cond = true;
        if (a.op_count > 1 && a.operands[1].type == ARM_OP_IMM) {
            c.has_target = true;
            c.target = static_cast<uint32_t>(a.operands[1].imm);
        }
        break;
    case ARM_INS_BL:
        set("branch", t.branch);
        c.branch = BranchKind::Call;
        break;
    case ARM_INS_BLX:
        set("branch", t.branch);
        c.branch = (a.op_count > 0 && a.operands[0].type == ARM_OP_REG) ? BranchKind::IndirectCall : BranchKind::Call;
        break;
    case ARM_INS_BX:
    case ARM_INS_BXJ:
        set("branch", t.branch);
        c.branch = (a.op_count > 0 && a.operands[0].type == ARM_OP_REG && a.operands[0].reg == ARM_REG_LR)
                       ? BranchKind::Return
                       : BranchKind::Indirect;
        break;
    case ARM_INS_TBB:
    case ARM_INS_TBH:
        set("table branch", t.table_branch);
        c.branch = BranchKind::Indirect;
        break;
    case ARM_INS_ERET:
        set("branch", t.branch);
        c.branch = BranchKind::ExcReturn;
        break;
    case ARM_INS_RFEDA:
    case ARM_INS_RFEDB:
    case ARM_INS_RFEIA:
    case ARM_INS_RFEIB:
        set("load multiple", multi(t.ldm_base, t.ldm_per_cycle, 2));
        c.branch = BranchKind::ExcReturn;
        break;
    // ---- load/store multiple
    case ARM_INS_POP:
        set("load multiple", multi(t.ldm_base, t.ldm_per_cycle, reg_ops(a)));
        c.load = true;
        if (reg_in_ops(a, ARM_REG_PC)) c.branch = BranchKind::Return;
        break;
    case ARM_INS_LDM:
    case ARM_INS_LDMDA:
    case ARM_INS_LDMDB:
    case ARM_INS_LDMIB:
        set("load multiple", multi(t.ldm_base, t.ldm_per_cycle, reg_ops(a, 1)));
        c.load = true;
        if (reg_in_ops(a, ARM_REG_PC, 1)) {
            if (a.usermode)
                c.branch = BranchKind::ExcReturn;
            else if (a.op_count > 0 && a.operands[0].reg == ARM_REG_SP && a.writeback)
                c.branch = BranchKind::Return;
            else
                c.branch = BranchKind::Indirect;
        }
        break;
    case ARM_INS_PUSH:
        set("store multiple", multi(t.ldm_base, t.ldm_per_cycle, reg_ops(a)));
        c.store = true;
        break;
    case ARM_INS_STM:
    case ARM_INS_STMDA:
    case ARM_INS_STMDB:
    case ARM_INS_STMIB:
        set("store multiple", multi(t.ldm_base, t.ldm_per_cycle, reg_ops(a, 1)));
        c.store = true;
        break;
    case ARM_INS_SRSDA:
    case ARM_INS_SRSDB:
    case ARM_INS_SRSIA:
    case ARM_INS_SRSIB:
        set("store multiple", multi(t.ldm_base, t.ldm_per_cycle, 2));
        c.store = true;
        break;
    // ---- single loads and stores
    case ARM_INS_LDR:
    case ARM_INS_LDRB:
    case ARM_INS_LDRH:
    case ARM_INS_LDRSB:
    case ARM_INS_LDRSH:
    case ARM_INS_LDRT:
    case ARM_INS_LDRBT:
    case ARM_INS_LDRHT:
    case ARM_INS_LDRSBT:
    case ARM_INS_LDRSHT:
    case ARM_INS_LDREX:
    case ARM_INS_LDREXB:
    case ARM_INS_LDREXH:
    case ARM_INS_LDA:
    case ARM_INS_LDAB:
    case ARM_INS_LDAH:
    case ARM_INS_LDAEX:
    case ARM_INS_LDAEXB:
    case ARM_INS_LDAEXH:
        set("load", t.load);
        c.load = true;
        c.single_ls = true;
        c.load_dest = a.op_count > 0 && a.operands[0].type == ARM_OP_REG ? a.operands[0].reg : 0;
        if (dest_is_pc(a)) {
            c.single_ls = false;
            const bool post_sp = mem_base(a) == ARM_REG_SP && (a.writeback || a.op_count > 2);
            c.branch = post_sp ? BranchKind::Return : BranchKind::Indirect;
        }
        break;
    case ARM_INS_STR:
    case ARM_INS_STRB:
    case ARM_INS_STRH:
    case ARM_INS_STRT:
    case ARM_INS_STRBT:
    case ARM_INS_STRHT:
    case ARM_INS_STREX:
    case ARM_INS_STREXB:
    case ARM_INS_STREXH:
    case ARM_INS_STL:
    case ARM_INS_STLB:
    case ARM_INS_STLH:
    case ARM_INS_STLEX:
    case ARM_INS_STLEXB:
    case ARM_INS_STLEXH:
        set("store", t.store);
        c.store = true;
        c.single_ls = true;
        break;
    case ARM_INS_LDRD:
    case ARM_INS_LDREXD:
    case ARM_INS_LDAEXD:
        set("load double", t.load_double);
        c.load = true;
        break;
    case ARM_INS_STRD:
    case ARM_INS_STREXD:
    case ARM_INS_STLEXD:
        set("store double", t.store_double);
        c.store = true;
        break;
    // ---- multiply, divide
    case ARM_INS_MUL:
    case ARM_INS_SMULBB:
    case ARM_INS_SMULBT:
    case ARM_INS_SMULTB:
    case ARM_INS_SMULTT:
    case ARM_INS_SMULWB:
    case ARM_INS_SMULWT:
    case ARM_INS_SMMUL:
    case ARM_INS_SMMULR:
    case ARM_INS_SMUAD:
    case ARM_INS_SMUADX:
    case ARM_INS_SMUSD:
    case ARM_INS_SMUSDX:
    case ARM_INS_USAD8:
        set("multiply", t.mul);
        break;
    case ARM_INS_MLA:
    case ARM_INS_MLS:
    case ARM_INS_SMLABB:
    case ARM_INS_SMLABT:
    case ARM_INS_SMLATB:
    case ARM_INS_SMLATT:
    case ARM_INS_SMLAWB:
    case ARM_INS_SMLAWT:
    case ARM_INS_SMMLA:
    case ARM_INS_SMMLAR:
    case ARM_INS_SMMLS:
    case ARM_INS_SMMLSR:
    case ARM_INS_SMLAD:
    case ARM_INS_SMLADX:
    case ARM_INS_SMLSD:
    case ARM_INS_SMLSDX:
    case ARM_INS_USADA8:
        set("multiply-accumulate", t.mac);
        break;
    case ARM_INS_SMULL:
    case ARM_INS_UMULL:
        set("long multiply", t.mul_long);
        break;
    case ARM_INS_SMLAL:
    case ARM_INS_UMLAL:
    case ARM_INS_UMAAL:
    case ARM_INS_SMLALBB:
    case ARM_INS_SMLALBT:
    case ARM_INS_SMLALTB:
    case ARM_INS_SMLALTT:
    case ARM_INS_SMLALD:
    case ARM_INS_SMLALDX:
    case ARM_INS_SMLSLD:
    case ARM_INS_SMLSLDX:
        set("long multiply-accumulate", t.mac_long);
        break;
    case ARM_INS_SDIV:
    case ARM_INS_UDIV:
        set("divide", t.div);
        break;
    // ---- system
    case ARM_INS_ISB:
        set("ISB", t.isb);
        break;
    case ARM_INS_DMB:
    case ARM_INS_DSB:
        set("barrier", t.barrier);
        break;
    case ARM_INS_MRS:
    case ARM_INS_MSR:
    case ARM_INS_CPS:
    case ARM_INS_MRC:
    case ARM_INS_MCR:
    case ARM_INS_MRRC:
    case ARM_INS_MCRR:
    case ARM_INS_MRC2:
    case ARM_INS_MCR2:
    case ARM_INS_SETEND:
    case ARM_INS_CLREX:
        set("system", t.sysreg);
        break;
    case ARM_INS_WFI:
    case ARM_INS_WFE:
        set("WFI", t.wfi);
        break;
    // ---- floating point
    case ARM_INS_VADD:
    case ARM_INS_VSUB:
        if (any_dreg(a))
            fp("VADD.F64", t.fp_alu_f64);
        else
            fp("VADD/VSUB/VMUL", t.fp_alu);
        break;
    case ARM_INS_VMUL:
    case ARM_INS_VNMUL:
        if (any_dreg(a))
            fp("VMUL.F64", t.fp_mul_f64);
        else
            fp("VADD/VSUB/VMUL", t.fp_alu);
        break;
    case ARM_INS_VMLA:
    case ARM_INS_VMLS:
    case ARM_INS_VNMLA:
    case ARM_INS_VNMLS:
    case ARM_INS_VFMA:
    case ARM_INS_VFMS:
    case ARM_INS_VFNMA:
    case ARM_INS_VFNMS:
        if (any_dreg(a))
            fp("VMLA.F64", t.fp_mac_f64);
        else
            fp("VMLA/VFMA", t.fp_mac);
        break;
    case ARM_INS_VDIV:
        if (any_dreg(a))
            fp("VDIV.F64", t.fp_div_f64);
        else
            fp("VDIV", t.fp_div);
        break;
    case ARM_INS_VSQRT:
        if (any_dreg(a))
            fp("VSQRT.F64", t.fp_sqrt_f64);
        else
            fp("VSQRT", t.fp_sqrt);
        break;
    case ARM_INS_VLDR:
        fp(any_dreg(a) ? "VLDR.64" : "VLDR", any_dreg(a) ? t.fp_load_f64 : t.fp_load);
        c.load = true;
        break;
    case ARM_INS_VSTR:
        fp(any_dreg(a) ? "VSTR.64" : "VSTR", any_dreg(a) ? t.fp_store_f64 : t.fp_store);
        c.store = true;
        break;
    case ARM_INS_VPOP:
    case ARM_INS_VLDMIA:
    case ARM_INS_VLDMDB:
    case ARM_INS_FLDMIAX:
    case ARM_INS_FLDMDBX:
        fp("VLDM/VPOP", multi(t.fpm_base, t.fpm_per_cycle, fp_words(a)));
        c.load = true;
        break;
    case ARM_INS_VPUSH:
    case ARM_INS_VSTMIA:
    case ARM_INS_VSTMDB:
    case ARM_INS_FSTMIAX:
    case ARM_INS_FSTMDBX:
        fp("VSTM/VPUSH", multi(t.fpm_base, t.fpm_per_cycle, fp_words(a)));
        c.store = true;
        break;
    case ARM_INS_VMOV: {
        const unsigned core = core_regs(a);
        if (core >= 2)
            fp("VMOV (2 core registers)", t.fp_xfer2);
        else if (core == 1)
            fp("VMOV (core register)", t.fp_xfer);
        else
            fp("VMOV/VABS/VNEG/VCMP/VCVT", t.fp_misc);
        break;
    }
    case ARM_INS_VMRS:
    case ARM_INS_VMSR:
        fp("VMRS/VMSR", t.fp_xfer);
        break;
    case ARM_INS_VABS:
    case ARM_INS_VNEG:
    case ARM_INS_VCMP:
    case ARM_INS_VCMPE:
    case ARM_INS_VCVT:
    case ARM_INS_VCVTR:
    case ARM_INS_VCVTA:
    case ARM_INS_VCVTB:
    case ARM_INS_VCVTT:
    case ARM_INS_VCVTM:
    case ARM_INS_VCVTN:
    case ARM_INS_VCVTP:
    case ARM_INS_VSELEQ:
    case ARM_INS_VSELGE:
    case ARM_INS_VSELGT:
    case ARM_INS_VSELVS:
    case ARM_INS_VMAXNM:
    case ARM_INS_VMINNM:
    case ARM_INS_VRINTA:
    case ARM_INS_VRINTM:
    case ARM_INS_VRINTN:
    case ARM_INS_VRINTP:
    case ARM_INS_VRINTR:
    case ARM_INS_VRINTX:
    case ARM_INS_VRINTZ:
        fp("VMOV/VABS/VNEG/VCMP/VCVT", t.fp_misc);
        break;
    default:
        set("alu", t.alu);
        // any other V* instruction (Advanced SIMD: not on these cores) counts as FP use
        if (in.mnemonic[0] == 'v') c.fp = true;
        break;
    }
    // A data-processing instruction writing the PC is a branch (MOV PC,LR: a return; the
    // flag-setting forms MOVS/SUBS PC,LR: an exception return).
    if (c.branch == BranchKind::None && !c.load && !c.store && !c.fp && dest_is_pc(a) &&
        std::strcmp(c.name, "alu") == 0) {
        if (a.update_flags)
            c.branch = BranchKind::ExcReturn;
        else if (in.id == ARM_INS_MOV && a.op_count > 1 && a.operands[1].type == ARM_OP_REG &&
                 a.operands[1].reg == ARM_REG_LR)
            c.branch = BranchKind::Return;
        else
            c.branch = BranchKind::Indirect;
        c.cycles = t.branch;
        c.name = "branch";
    }
    return c;
}

}  // namespace

CycleModel::CycleModel(Core core, ReadCode read)
    : core_(core), t_(&core_timing(core)), read_(std::move(read)), code_pages_(1u << 22, false)
{
    csh arm = 0, thumb = 0;
    const cs_mode tm = core == Core::CortexM4F ? static_cast<cs_mode>(CS_MODE_THUMB | CS_MODE_MCLASS) : CS_MODE_THUMB;
    if (cs_open(CS_ARCH_ARM, CS_MODE_ARM, &arm) != CS_ERR_OK || cs_open(CS_ARCH_ARM, tm, &thumb) != CS_ERR_OK)
        throw std::runtime_error("pil: capstone: cannot open an ARM disassembler");
    cs_option(arm, CS_OPT_DETAIL, CS_OPT_ON);
    cs_option(thumb, CS_OPT_DETAIL, CS_OPT_ON);
    cs_arm_ = arm;
    cs_thumb_ = thumb;
}

CycleModel::~CycleModel()
{
    csh h = cs_arm_;
    if (h) cs_close(&h);
    h = cs_thumb_;
    if (h) cs_close(&h);
}

void CycleModel::clear_cache()
{
    cache_.clear();
    std::fill(code_pages_.begin(), code_pages_.end(), false);
}

bool CycleModel::overlaps_code(uint32_t addr, size_t n) const
{
    if (n == 0) return false;
    const uint64_t last = std::min<uint64_t>(static_cast<uint64_t>(addr) + n - 1, 0xFFFFFFFFull);
    for (uint64_t p = addr >> 10; p <= (last >> 10); ++p)
        if (code_pages_[static_cast<size_t>(p)]) return true;
    return false;
}

void CycleModel::cost_insns(uint32_t addr, const uint8_t* code, size_t size, bool thumb, BlockCost* out,
                            std::vector<InsnCost>* listing)
{
    const csh h = thumb ? cs_thumb_ : cs_arm_;
    cs_insn* in = cs_malloc(h);
    const uint8_t* p = code;
    size_t left = size;
    uint64_t pc = addr;
    bool prev_single_ls = false;
    int prev_load_dest = 0;
    while (left > 0) {
        const uint64_t at = pc;
        const uint8_t* q = p;
        if (!cs_disasm_iter(h, &q, &left, &pc, in)) {
            // undecodable: one cycle per instruction-sized unit
            size_t len = 4;
            if (thumb && left >= 2) {
                const unsigned hw = static_cast<unsigned>(p[0] | p[1] << 8);
                len = ((hw >> 11) >= 0x1D) ? 4 : 2;
            }
            len = std::min(len, left);
            out->n += 1;
            out->cycles += t_->alu;
            out->undecoded += static_cast<uint32_t>(len);
            if (listing) listing->push_back({static_cast<uint32_t>(at), static_cast<uint8_t>(len), "(undecoded)", "alu", t_->alu});
            out->branch = BranchKind::None;
            p += len;
            left -= len;
            pc = at + len;
            prev_single_ls = false;
            continue;
        }
        p = q;
        Cls c = classify(*in, *t_);
        double cy = c.cycles;
        // Cortex-M4: a single LDR right after another single load/store pipelines (one cycle
        // less), unless its address needs the previous load's result.
        if (c.single_ls && c.load && prev_single_ls && t_->load_pipelined < t_->load) {
            const cs_arm& a = in->detail->arm;
            const bool dep = prev_load_dest != 0 && (mem_base(a) == prev_load_dest || mem_index(a) == prev_load_dest);
            if (!dep) {
                cy = t_->load_pipelined;
                c.name = "load (pipelined)";
            }
        }
        prev_single_ls = c.single_ls;
        prev_load_dest = c.load && c.single_ls ? c.load_dest : 0;
        out->n += 1;
        out->cycles += cy;
        if (c.fp && !out->has_fp) {
            out->has_fp = true;
            out->first_fp = static_cast<uint32_t>(at);
            out->first_fp_n = out->n;
        }
        if (c.store) {
            BlockCost::Site site{static_cast<uint32_t>(at), out->n, out->cycles};
            if (c.single_ls) describe_store(in->detail->arm, &site);
            out->stores.push_back(site);
        }
        out->branch = c.branch;
        out->branch_cond = c.cond;
        out->branch_has_target = c.has_target;
        out->branch_target = c.target;
        out->branch_addr = static_cast<uint32_t>(at);
        out->ends_wfi = in->id == ARM_INS_WFI || in->id == ARM_INS_WFE;
        if (listing) {
            std::string text = in->mnemonic;
            if (in->op_str[0]) text += std::string(" ") + in->op_str;
            listing->push_back({static_cast<uint32_t>(at), static_cast<uint8_t>(in->size), text, c.name, cy});
        }
    }
    cs_free(in, 1);
}

const BlockCost* CycleModel::decode_block(uint64_t key, uint32_t addr, uint32_t size, bool thumb)
{
    std::vector<uint8_t> code(size);
    if (size > 0 && !read_(addr, code.data(), size)) return nullptr;
    BlockCost b;
    b.addr = addr;
    b.size = size;
    b.thumb = thumb;
    b.fallthrough = addr + size;
    cost_insns(addr, code.data(), size, thumb, &b, nullptr);
    if (size > 0)
        for (uint64_t pg = addr >> 10; pg <= ((static_cast<uint64_t>(addr) + size - 1) >> 10) && pg < code_pages_.size(); ++pg)
            code_pages_[static_cast<size_t>(pg)] = true;
    return &cache_.emplace(key, std::move(b)).first->second;
}

std::vector<InsnCost> CycleModel::explain(uint32_t addr, const uint8_t* code, size_t size, bool thumb)
{
    BlockCost b;
    std::vector<InsnCost> v;
    cost_insns(addr, code, size, thumb, &b, &v);
    return v;
}

double CycleModel::branch_penalty(const BlockCost& b, uint32_t next)
{
    if (b.branch == BranchKind::None) return 0;
    const bool taken = next != b.fallthrough;
    if (!t_->predicts) return taken ? t_->refill : 0;   // Cortex-M4: 1 + P on every taken branch
    auto push = [&](uint32_t ret) {
        if (t_->return_stack == 0) return;
        if (rs_.size() >= t_->return_stack) rs_.erase(rs_.begin());
        rs_.push_back(ret);
    };
    switch (b.branch) {
    case BranchKind::Direct:
    case BranchKind::Call: {
        if (b.branch == BranchKind::Call && taken) push(b.fallthrough);
        if (!b.branch_cond) return 0;   // unconditional direct: predicted taken
        // conditional: a 2-bit saturating counter per branch (weakly not taken at first)
        auto it = bht_.try_emplace(b.branch_addr, uint8_t{1}).first;
        const bool predicted = it->second >= 2;
        it->second = static_cast<uint8_t>(taken ? std::min(3, it->second + 1) : std::max(0, it->second - 1));
        return predicted == taken ? 0 : t_->mispredict;
    }
    case BranchKind::IndirectCall:
        if (!taken) return 0;
        push(b.fallthrough);
        return t_->mispredict;
    case BranchKind::Return: {
        if (!taken) return 0;
        const bool hit = !rs_.empty() && rs_.back() == next;
        if (!rs_.empty()) rs_.pop_back();
        return hit ? 0 : t_->mispredict;
    }
    case BranchKind::Indirect:
    case BranchKind::ExcReturn:
        return taken ? t_->mispredict : 0;
    case BranchKind::None:
        break;
    }
    return 0;
}

}  // namespace mcsim::pil
