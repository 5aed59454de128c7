/* R5F VIM, CONTROLSS interrupt crossbar and control-MMR lock of the AM263x port. Register facts:
 * am263x/regs_vim.h (TRM: R5FSS Vectored Interrupt Manager), am263x/regs_soc.h (TRM: Control
 * Subsystem Interrupt XBAR; Control Module lock/kick). The VIM runs in non-VIC mode (SCTLR.VE = 0,
 * set by startup.S): an IRQ enters the core's IRQ vector at 0x18, whose code reads IRQVEC. */
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_soc.h"
#include "am263x/regs_vim.h"

void am263x_vim_route(uintptr_t vim, uint32_t line, uint32_t prio, uintptr_t handler)
{
    const uint32_t bit = VIM_BIT(line);
    am263x_wr32(vim + VIM_INT_DIS(line), bit);
    am263x_wr32(vim + VIM_STS(line), bit);
    am263x_wr32(vim + VIM_INT_MAP(line), am263x_rd32(vim + VIM_INT_MAP(line)) & ~bit);    /* IRQ   */
    am263x_wr32(vim + VIM_INT_TYPE(line), am263x_rd32(vim + VIM_INT_TYPE(line)) & ~bit);  /* level */
    am263x_wr32(vim + VIM_INT_PRI(line), prio & 0xFu);
    am263x_wr32(vim + VIM_INT_VEC(line), (uint32_t)handler & 0xFFFFFFFCu);
    am263x_wr32(vim + VIM_INT_EN(line), bit);
}

void am263x_vim_clear(uintptr_t vim, uint32_t line)
{
    am263x_wr32(vim + VIM_STS(line), VIM_BIT(line));
}

void am263x_intxbar_route(uintptr_t xbar, uint32_t out, uint32_t group, uint32_t mask)
{
    for (uint32_t g = 0u; g < 7u; ++g) {
        am263x_wr32(xbar + AM263X_INTXBAR_G(out, g), g == group ? mask : 0u);
    }
}

void am263x_mmr_unlock(uintptr_t base)
{
    am263x_wr32(base + AM263X_LOCK0_KICK0, AM263X_KICK0_UNLOCK);
    am263x_wr32(base + AM263X_LOCK0_KICK1, AM263X_KICK1_UNLOCK);
}

void am263x_mmr_lock(uintptr_t base)
{
    am263x_wr32(base + AM263X_LOCK0_KICK0, AM263X_KICK_LOCK);
    am263x_wr32(base + AM263X_LOCK0_KICK1, AM263X_KICK_LOCK);
}
