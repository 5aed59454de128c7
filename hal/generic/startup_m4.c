/* Cortex-M4F startup for the generic port: the vector table, the reset handler (.data copy,
 * .bss zero, FPU on), main. Every exception other than reset and the ADC interrupt is a fault
 * (the image uses none of them): Default_Handler turns the outputs off first, then parks. */
#include <stdint.h>
#include "hal_generic/regs.h"

extern uint32_t __data_load[], __data_start[], __data_end[], __bss_start[], __bss_end[], __stack_top[];
int main(void);
void hal_generic_adc_irq(void);
void Reset_Handler(void);
void Default_Handler(void);

/* NMI, HardFault (the port leaves SHCSR's MemManage/BusFault/UsageFault enables off, so those
 * escalate to it), the unused ones: one store clears PWM CTRL (RUN and OE: all six switches off
 * at once, hal_generic/regs.h) before anything that could fault again; no stack beyond the
 * hardware's frame, no call. Measured in the PIL (tests/pil/test_pil_bridge.cpp): outputs off
 * within 60 cycles of the faulting instruction, entry included (23 for a bus fault, 18 for an
 * undefined instruction). Parks in WFI (a debugger finds IPSR = the fault's number). */
__attribute__((noreturn)) void Default_Handler(void)
{
    GEN_REG(GEN_PWM_BASE, GEN_PWM_CTRL) = 0u;
    __asm volatile("dsb" ::: "memory");
    for (;;) {
        __asm volatile("wfi");
    }
}

void Reset_Handler(void)
{
    /* FPU: CP10 and CP11 full access (CPACR, ARMv7-M ARM B3.2.20), before any float code */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm volatile("dsb\n isb" ::: "memory");
    for (uint32_t *s = __data_load, *d = __data_start; d < __data_end;) {
        *d++ = *s++;
    }
    for (uint32_t *d = __bss_start; d < __bss_end;) {
        *d++ = 0u;
    }
    (void)main();
    for (;;) {
    }
}

/* 16 system vectors, then the external interrupts (GEN_ADC_IRQ = 0). */
__attribute__((section(".vectors"), used))
void (*const g_vectors[17])(void) = {
    (void (*)(void))(uintptr_t)__stack_top,
    Reset_Handler,
    Default_Handler, /* NMI */
    Default_Handler, /* HardFault */
    Default_Handler, /* MemManage */
    Default_Handler, /* BusFault */
    Default_Handler, /* UsageFault */
    0, 0, 0, 0,
    Default_Handler, /* SVCall */
    Default_Handler, /* DebugMon */
    0,
    Default_Handler, /* PendSV */
    Default_Handler, /* SysTick */
    hal_generic_adc_irq,
};
