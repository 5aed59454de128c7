/* Test image for the PIL engine (tests/pil/test_pil_irq.cpp): a Cortex-M4F on the generic port.
 * Reset: FPU on (CPACR), .data/.bss, PWM running with outputs on, ADC converting with its
 * interrupt, CHMAP reversed, the NVIC line enabled, then the idle loop. The idle loop holds known
 * values in r0-r3, r12 and s0 across its WFI, with SP = 4 mod 8 (the exception frame is realigned)
 * and the FP context active (CONTROL.FPCA: the extended frame, lazy stacking). The ADC handler
 * (assembly: a hand-counted cost) marks stages 1 and 2, sums the results, uses the FPU, clobbers
 * r0-r3, r12 and s0, writes CMP0 and acknowledges EOC. */
#include <stdint.h>
#include "hal_generic/regs.h"

#define REG32(a) (*(volatile uint32_t *)(a))

const char hal_port_name[] = "generic";
volatile uint32_t hal_stage_reg;
volatile uint32_t isr_count, adc_sum, bg_count, bg_s0;
volatile float isr_f = 1.0f;   /* .data: its initial value comes from the flash image */

extern uint32_t __data_load[], __data_start[], __data_end[], __bss_start[], __bss_end[], __stack_top[];
void reset_handler(void);
void default_handler(void);
void adc_irq(void);
void idle_loop(void);

void default_handler(void)
{
    for (;;) {
    }
}

__attribute__((section(".vectors"), used)) void (*const g_vectors[17])(void) = {
    (void (*)(void))(uintptr_t)__stack_top, reset_handler, default_handler, default_handler, default_handler,
    default_handler, default_handler, 0, 0, 0, 0, default_handler, default_handler, 0, default_handler,
    default_handler, adc_irq,
};

/* The handler in assembly, so that its cost is hand-countable (tests/pil/test_pil_irq.cpp):
 * Cortex-M4 cycles from docs/pil-cycle-model.md on the right, "|" where the stage changes. */
__attribute__((naked)) void adc_irq(void)
{
    __asm volatile(
        "push    {r4, r5, r6, r7}\n"       /* 1+4                                  stage 0 */
        "ldr     r6, =hal_stage_reg\n"     /* 2                                            */
        "movs    r7, #1\n"                 /* 1                                            */
        "str     r7, [r6]\n"               /* 1    | stage 1            stage 0: 9 (4 insns) */
        "ldr     r5, =0x40001000\n"        /* 1    pipelined after a store                 */
        "ldr     r3, [r5, #16]\n"          /* 2    its base is the last load's result      */
        "ldr     r2, [r5, #20]\n"          /* 1    pipelined                               */
        "adds    r3, r3, r2\n"             /* 1                                            */
        "ldr     r2, [r5, #24]\n"          /* 2                                            */
        "adds    r3, r3, r2\n"             /* 1                                            */
        "ldr     r4, [r5, #28]\n"          /* 2                                            */
        "adds    r4, r4, r3\n"             /* 1                                            */
        "ldr     r1, =adc_sum\n"           /* 2                                            */
        "str     r4, [r1]\n"               /* 1                                            */
        "movs    r3, #2\n"                 /* 1                                            */
        "str     r3, [r6]\n"               /* 1    | stage 2          stage 1: 16 (12 insns) */
        "ldr     r3, =isr_f\n"             /* 1    pipelined                               */
        "vldr    s14, [r3]\n"              /* 2    first FP use: lazy FP save (17)         */
        "vmov    s15, r4\n"                /* 1                                            */
        "vcvt.f32.u32 s15, s15\n"          /* 1                                            */
        "vmov.f32 s13, #0.5\n"             /* 1                                            */
        "vmul.f32 s14, s14, s13\n"         /* 1                                            */
        "vadd.f32 s15, s15, s14\n"         /* 1                                            */
        "vstr    s15, [r3]\n"              /* 2                                            */
        "vmov.f32 s0, #2.0\n"              /* 1    clobbers the background's s0            */
        "movs    r0, #0\n"                 /* 1    and its r0-r3, r12                      */
        "movs    r1, #0\n"                 /* 1                                            */
        "movs    r2, #0\n"                 /* 1                                            */
        "movs    r3, #0\n"                 /* 1                                            */
        "mov     r12, r0\n"                /* 1                                            */
        "movw    r2, #5000\n"              /* 1                                            */
        "udiv    r3, r4, r2\n"             /* 7    (2..12: the table's mid value)          */
        "mls     r3, r2, r3, r4\n"         /* 1                                            */
        "mov.w   r2, #0x40000000\n"        /* 1                                            */
        "str     r3, [r2, #12]\n"          /* 1    PWM CMP0 = sum % 5000                    */
        "ldr     r1, =isr_count\n"         /* 1    pipelined                               */
        "ldr     r3, [r1]\n"               /* 2                                            */
        "adds    r3, r3, #1\n"             /* 1                                            */
        "str     r3, [r1]\n"               /* 1                                            */
        "movs    r3, #1\n"                 /* 1                                            */
        "str     r3, [r5, #4]\n"           /* 1    ADC STS: EOC acknowledged                */
        "pop     {r4, r5, r6, r7}\n"       /* 1+4                                          */
        "bx      lr\n"                     /* 1    EXC_RETURN (its refill is in the exit)  */
        ".ltorg\n");                       /*                 stage 2: 40 + 17 (27 insns) */
}

__attribute__((naked)) void idle_loop(void)
{
    __asm volatile(
        "sub sp, sp, #4\n"
        "ldr r0, =0x11111111\n"
        "ldr r1, =0x22222222\n"
        "ldr r2, =0x33333333\n"
        "ldr r3, =0x44444444\n"
        "ldr r12, =0x55555555\n"
        "vmov.f32 s0, #1.25\n"
        "1: wfi\n"
        "vmov r5, s0\n"
        "ldr r6, =bg_s0\n"
        "str r5, [r6]\n"
        "ldr r6, =bg_count\n"
        "ldr r7, [r6]\n"
        "adds r7, r7, #1\n"
        "str r7, [r6]\n"
        "b 1b\n"
        ".ltorg\n");
}

void reset_handler(void)
{
    REG32(0xE000ED88u) |= 0xFu << 20;
    __asm volatile("dsb\n isb" ::: "memory");
    for (uint32_t *s = __data_load, *d = __data_start; d < __data_end;) *d++ = *s++;
    for (uint32_t *d = __bss_start; d < __bss_end;) *d++ = 0u;
    REG32(GEN_PWM_BASE + GEN_PWM_PRD) = 5000u;
    for (uint32_t k = 0u; k < 3u; ++k) REG32(GEN_PWM_BASE + GEN_PWM_CMP(k)) = 2500u;
    REG32(GEN_PWM_BASE + GEN_PWM_CTRL) = GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE;
    REG32(GEN_ADC_BASE + GEN_ADC_CHMAP) = 0x00010203u;
    REG32(GEN_ADC_BASE + GEN_ADC_CTRL) = GEN_ADC_CTRL_EN | GEN_ADC_CTRL_IE;
    REG32(0xE000E100u) = 1u << GEN_ADC_IRQ;
    idle_loop();
}
