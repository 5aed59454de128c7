/* Test image for the PIL engine (tests/pil/test_pil_irq.cpp): a Cortex-R5F on the generic port.
 * ARM vectors at 0; reset: IRQ and SVC stacks, VFP on (CPACR, FPEXC.EN), the peripherals (Thumb
 * C), then the idle loop in Thumb, SVC mode, IRQs on. IRQ entry (ARM): SRS of LR_irq/SPSR_irq
 * onto the IRQ stack, caller-saved registers, SPSR and SP recorded, the Thumb C handler, RFE. */
        .syntax unified
        .arm
        .section .vectors, "ax", %progbits
        .global vectors
vectors:
        ldr     pc, v_reset
        b       .
        b       .
        b       .
        b       .
        b       .
        ldr     pc, v_irq
        b       .
v_reset: .word  reset
v_irq:   .word  irq_entry

        .text
        .type   reset, %function
reset:
        cps     #0x12
        ldr     sp, =irq_stack_top
        cps     #0x13
        ldr     sp, =svc_stack_top
        mrc     p15, 0, r0, c1, c0, 2
        orr     r0, r0, #(0xF << 20)
        mcr     p15, 0, r0, c1, c0, 2
        isb
        mov     r0, #0x40000000
        vmsr    fpexc, r0
        ldr     r0, =setup
        blx     r0
        ldr     r0, =idle_loop
        bx      r0

/* Cortex-R5 cycles (docs/pil-cycle-model.md), all in stage 0 but the return (stage 2): the
 * vector's ldr pc (1, unpredicted: +8), then */
        .type   irq_entry, %function
irq_entry:
        sub     lr, lr, #4                  @ 1
        srsdb   sp!, #0x12                  @ 1   two words
        push    {r0-r3, r12, lr}            @ 3   six registers, two per cycle
        mrs     r0, spsr                    @ 1
        ldr     r1, =irq_spsr               @ 1
        str     r0, [r1]                    @ 1
        ldr     r1, =irq_sp                 @ 1
        str     sp, [r1]                    @ 1
        ldr     r0, =adc_irq                @ 1
        blx     r0                          @ 1   unpredicted: +8; 12 + 8 in all
        pop     {r0-r3, r12, lr}            @ 3
        rfeia   sp!                         @ 1   exception return, unpredicted: +8
        .ltorg
