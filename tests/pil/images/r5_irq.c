/* The Thumb C part of the Cortex-R5F test image (r5_irq.S): the peripherals, the ADC handler
 * (assembly, hand-counted: stage markers, FPU use, caller-saved registers clobbered), the idle
 * loop (known register values across WFI, IRQs unmasked). */
#include <stdint.h>
#include "hal_generic/regs.h"

#define REG32(a) (*(volatile uint32_t *)(a))

const char hal_port_name[] = "generic";
volatile uint32_t hal_stage_reg;
volatile uint32_t isr_count, adc_sum, bg_count, irq_spsr, irq_sp;
volatile float isr_f = 1.0f;

void setup(void);
void adc_irq(void);
void idle_loop(void);

void setup(void)
{
    REG32(GEN_PWM_BASE + GEN_PWM_PRD) = 5000u;
    REG32(GEN_PWM_BASE + GEN_PWM_CTRL) = GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE;
    REG32(GEN_ADC_BASE + GEN_ADC_CHMAP) = 0x00010203u;
    REG32(GEN_ADC_BASE + GEN_ADC_CTRL) = GEN_ADC_CTRL_EN | GEN_ADC_CTRL_IE;
}

/* The handler in assembly (Thumb), so that its cost is hand-countable (tests/pil/test_pil_irq.cpp):
 * Cortex-R5 cycles from docs/pil-cycle-model.md on the right, "|" where the stage changes. It runs
 * in IRQ mode on the IRQ stack, called from irq_entry (r5_irq.S); the VFP registers are not
 * saved there, so it leaves s0 alone. */
__attribute__((naked)) void adc_irq(void)
{
    __asm volatile(
        "push    {r4, r5, r6, r7}\n"       /* 2    two registers per cycle         stage 0 */
        "ldr     r6, =hal_stage_reg\n"     /* 1                                            */
        "movs    r7, #1\n"                 /* 1                                            */
        "str     r7, [r6]\n"               /* 1    | stage 1            stage 0: 5 (4 insns) */
        "ldr     r5, =0x40001000\n"        /* 1                                            */
        "ldr     r3, [r5, #16]\n"          /* 1                                            */
        "ldr     r2, [r5, #20]\n"          /* 1                                            */
        "adds    r3, r3, r2\n"             /* 1                                            */
        "ldr     r2, [r5, #24]\n"          /* 1                                            */
        "adds    r3, r3, r2\n"             /* 1                                            */
        "ldr     r4, [r5, #28]\n"          /* 1                                            */
        "adds    r4, r4, r3\n"             /* 1                                            */
        "ldr     r1, =adc_sum\n"           /* 1                                            */
        "str     r4, [r1]\n"               /* 1                                            */
        "movs    r3, #2\n"                 /* 1                                            */
        "str     r3, [r6]\n"               /* 1    | stage 2          stage 1: 12 (12 insns) */
        "ldr     r3, =isr_f\n"             /* 1                                            */
        "vldr    s14, [r3]\n"              /* 1                                            */
        "vmov    s15, r4\n"                /* 1                                            */
        "vcvt.f32.u32 s15, s15\n"          /* 1                                            */
        "vmov.f32 s13, #0.5\n"             /* 1                                            */
        "vmul.f32 s14, s14, s13\n"         /* 1                                            */
        "vadd.f32 s15, s15, s14\n"         /* 1                                            */
        "vstr    s15, [r3]\n"              /* 1                                            */
        "movs    r0, #0\n"                 /* 1    clobbers the background's r0-r3, r12     */
        "movs    r1, #0\n"                 /* 1                                            */
        "movs    r2, #0\n"                 /* 1                                            */
        "movs    r3, #0\n"                 /* 1                                            */
        "mov     r12, r0\n"                /* 1                                            */
        "movw    r2, #5000\n"              /* 1                                            */
        "udiv    r3, r4, r2\n"             /* 10   (data dependent: the table's mid value) */
        "mls     r3, r2, r3, r4\n"         /* 2                                            */
        "mov.w   r2, #0x40000000\n"        /* 1                                            */
        "str     r3, [r2, #12]\n"          /* 1    PWM CMP0 = sum % 5000                    */
        "ldr     r1, =isr_count\n"         /* 1                                            */
        "ldr     r3, [r1]\n"               /* 1                                            */
        "adds    r3, r3, #1\n"             /* 1                                            */
        "str     r3, [r1]\n"               /* 1                                            */
        "movs    r3, #1\n"                 /* 1                                            */
        "str     r3, [r5, #4]\n"           /* 1    ADC STS: EOC acknowledged                */
        "pop     {r4, r5, r6, r7}\n"       /* 2                                            */
        "bx      lr\n"                     /* 1    return stack: predicted                 */
        ".ltorg\n");                       /*                 stage 2: 37 (26 insns)      */
}

__attribute__((naked)) void idle_loop(void)
{
    __asm volatile(
        "ldr r0, =0x11111111\n"
        "ldr r1, =0x22222222\n"
        "ldr r2, =0x33333333\n"
        "ldr r3, =0x44444444\n"
        "ldr r12, =0x55555555\n"
        "cpsie i\n"
        "1: wfi\n"
        "ldr r6, =bg_count\n"
        "ldr r7, [r6]\n"
        "adds r7, r7, #1\n"
        "str r7, [r6]\n"
        "b 1b\n"
        ".ltorg\n");
}
