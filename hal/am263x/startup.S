/* Cortex-R5F startup of the AM263x port (R5FSS0 core 0): the exception vectors at address 0
 * (ATCM, ARM state), the reset handler and the IRQ entry. ARM (A32) code throughout; the C code
 * it calls is Thumb-2.
 *
 * Reset: IRQ/FIQ masked; SCTLR with the MPU and caches off while the MPU is programmed, VE = 0
 * (IRQs through the vector at 0x18, the VIM in non-VIC mode), V = 0 (vectors at 0), TE = 0
 * (exceptions in ARM state); VFP on (CPACR cp10/cp11 full access, FPEXC.EN); MPU regions (below)
 * and the I-cache on (the D-cache stays off: no maintenance needed for the flash window the NVM
 * driver programs); a stack per mode; .bss zeroed (.data needs no copy: the loader, TI's SBL or
 * CCS, writes it at its run address, see am263x.ld); main in SYS mode, IRQs still masked
 * (hal_board_start unmasks them).
 *
 * MPU (ARMv7-R PMSA; DRACR: XN 12, AP 10:8 = 011 full access, TEX 5:3, C 1, B 0; DRSR size
 * field N = log2(size) - 1), higher region wins:
 *   0  0x00000000  4 GiB    Device (TEX 000 B 1), XN   - every peripheral
 *   1  0x00000000  32 KiB   ATCM, Normal non-cacheable
 *   2  0x00080000  32 KiB   BTCM, Normal non-cacheable, XN
 *   3  0x70000000  2 MiB    MSRAM, Normal write-back (TEX 001 C 1 B 1): code via the I-cache
 *   4  0x60000000  8 MiB    QSPI flash window, Normal non-cacheable, XN
 * (TI's SDK examples use the same four-region scheme: syscfg mpu_armv7 regions 0..3.)
 *
 * IRQ entry (non-VIC mode, TRM: R5FSS VIM "Non-vectored interrupt handling"): the return address
 * and SPSR_irq go onto the SYS-mode stack (SRS), the core switches to SYS mode, so that main and
 * the control ISR share one stack (the image's RAM budget has room for one, as on a Cortex-M);
 * there it saves the AAPCS caller-saved integer registers r0-r3, r12, lr and the caller-saved VFP
 * registers d0-d7 with FPSCR (the C code saves d8-d15 itself), aligns the stack to 8 bytes, reads
 * the VIM's IRQVEC (the registered handler of the highest-priority pending IRQ), calls it, writes
 * IRQVEC (acknowledge), restores and returns with RFE (PC and CPSR from the SRS frame). IRQs stay
 * masked in the handler (no nesting). The VIM vector registers keep bits 31:2 only, so a handler
 * address reads back word-aligned: every handler registered in the VIM by this port is a Thumb C
 * function (am263x_vim_route), and the entry sets bit 0 again before BLX. */

        .syntax unified
        .arm

        .equ    MODE_FIQ, 0x11
        .equ    MODE_IRQ, 0x12
        .equ    MODE_SVC, 0x13
        .equ    MODE_ABT, 0x17
        .equ    MODE_UND, 0x1B
        .equ    MODE_SYS, 0x1F
        .equ    VIM_BASE, 0x50F00000        @ AM263X_VIM_BASE (am263x/regs_soc.h)
        .equ    VIM_IRQVEC, 0x18

        .equ    SCTLR_M,  (1 << 0)
        .equ    SCTLR_C,  (1 << 2)
        .equ    SCTLR_I,  (1 << 12)
        .equ    SCTLR_V,  (1 << 13)
        .equ    SCTLR_VE, (1 << 24)
        .equ    SCTLR_TE, (1 << 30)

        .equ    ACC_DEVICE_XN, 0x1301       @ XN, AP 011, TEX 000 C 0 B 1
        .equ    ACC_NORMAL_NC, 0x0308       @ AP 011, TEX 001 C 0 B 0
        .equ    ACC_NORMAL_NC_XN, 0x1308
        .equ    ACC_NORMAL_WB, 0x030B       @ AP 011, TEX 001 C 1 B 1

/* ------------------------------------------------------------------ vectors at 0 */
        .section .vectors, "ax", %progbits
        .global am263x_vectors
        .type   am263x_vectors, %function
am263x_vectors:
        ldr     pc, v_reset
        ldr     pc, v_undef
        ldr     pc, v_svc
        ldr     pc, v_pabt
        ldr     pc, v_dabt
        ldr     pc, v_rsvd
        ldr     pc, v_irq
        ldr     pc, v_fiq
v_reset: .word  am263x_reset
v_undef: .word  am263x_undef
v_svc:   .word  am263x_svc
v_pabt:  .word  am263x_pabt
v_dabt:  .word  am263x_dabt
v_rsvd:  .word  am263x_rsvd
v_irq:   .word  am263x_irq_entry
v_fiq:   .word  am263x_fiq
        .size   am263x_vectors, . - am263x_vectors

/* ------------------------------------------------------------------ reset */
        .macro  mpu_region n, base, sizef, acc
        mov     r0, #\n
        mcr     p15, 0, r0, c6, c2, 0       @ RGNR
        ldr     r0, =\base
        mcr     p15, 0, r0, c6, c1, 0       @ DRBAR
        ldr     r0, =\acc
        mcr     p15, 0, r0, c6, c1, 4       @ DRACR
        ldr     r0, =((\sizef << 1) | 1)
        mcr     p15, 0, r0, c6, c1, 2       @ DRSR: size, enable
        .endm

        .section .text.am263x_startup, "ax", %progbits
        .global am263x_reset
        .type   am263x_reset, %function
am263x_reset:
        cpsid   if
        /* SCTLR: MPU, caches, VIC port, high vectors, Thumb exceptions off */
        mrc     p15, 0, r0, c1, c0, 0
        ldr     r1, =(SCTLR_M | SCTLR_C | SCTLR_I | SCTLR_V | SCTLR_VE | SCTLR_TE)
        bic     r0, r0, r1
        dsb
        mcr     p15, 0, r0, c1, c0, 0
        isb
        /* VFP: CPACR cp10, cp11 full access, then FPEXC.EN */
        mrc     p15, 0, r0, c1, c0, 2
        orr     r0, r0, #(0xF << 20)
        mcr     p15, 0, r0, c1, c0, 2
        isb
        mov     r0, #0x40000000
        vmsr    fpexc, r0
        mov     r0, #0
        vmsr    fpscr, r0
        /* MPU */
        mpu_region 0, 0x00000000, 31, ACC_DEVICE_XN
        mpu_region 1, 0x00000000, 14, ACC_NORMAL_NC
        mpu_region 2, 0x00080000, 14, ACC_NORMAL_NC_XN
        mpu_region 3, 0x70000000, 20, ACC_NORMAL_WB
        mpu_region 4, 0x60000000, 22, ACC_NORMAL_NC_XN
        /* I-cache invalidated, then the MPU and the I-cache on */
        mov     r0, #0
        mcr     p15, 0, r0, c7, c5, 0       @ ICIALLU
        mrc     p15, 0, r0, c1, c0, 0
        orr     r0, r0, #SCTLR_M
        orr     r0, r0, #SCTLR_I
        dsb
        mcr     p15, 0, r0, c1, c0, 0
        isb
        /* stacks (IRQ and FIQ stay masked): SYS the real one; IRQ only its SP (the entry pushes on
         * the SYS stack); FIQ, UND, ABT, SVC a small shared one (their handlers trip and park, no stack use) */
        cps     #MODE_FIQ
        ldr     sp, =__exc_stack_top
        cps     #MODE_UND
        ldr     sp, =__exc_stack_top
        cps     #MODE_ABT
        ldr     sp, =__exc_stack_top
        cps     #MODE_SVC
        ldr     sp, =__exc_stack_top
        cps     #MODE_IRQ
        ldr     sp, =__exc_stack_top
        cps     #MODE_SYS
        ldr     sp, =__sys_stack_top
        /* .bss zeroed (8-aligned by the linker script); .data is already in place (am263x.ld) */
        ldr     r1, =__bss_start
        ldr     r2, =__bss_end
        mov     r3, #0
2:      cmp     r1, r2
        strlo   r3, [r1], #4
        blo     2b
        ldr     r12, =main
        blx     r12
3:      b       3b                          @ main does not return
        .size   am263x_reset, . - am263x_reset
        .ltorg

/* ------------------------------------------------------------------ IRQ */
        .section .text.am263x_irq, "ax", %progbits
        .global am263x_irq_entry
        .type   am263x_irq_entry, %function
am263x_irq_entry:
        sub     lr, lr, #4                  @ the interrupted instruction
        srsdb   sp!, #MODE_SYS              @ its address and SPSR_irq onto the SYS stack
        cps     #MODE_SYS                   @ the C call runs on the one SYS stack
        push    {r0-r3, r12}
        and     r1, sp, #4                  @ 8-byte alignment for the AAPCS call
        sub     sp, sp, r1
        push    {r1, lr}                    @ the adjustment, the interrupted code's lr
        vmrs    r0, fpscr
        vpush   {d0-d7}
        push    {r0, r1}                    @ FPSCR (+ a pad word)
        ldr     r1, =VIM_BASE
        ldr     r0, [r1, #VIM_IRQVEC]       @ the handler of the pending IRQ (0: spurious)
        cmp     r0, #0
        orrne   r0, r0, #1                  @ a Thumb function (see above)
        blxne   r0
        ldr     r1, =VIM_BASE
        str     r0, [r1, #VIM_IRQVEC]       @ acknowledge (any value)
        pop     {r0, r1}
        vpop    {d0-d7}
        vmsr    fpscr, r0
        pop     {r1, lr}
        add     sp, sp, r1
        pop     {r0-r3, r12}
        rfeia   sp!                         @ PC and CPSR from the SRS frame
        .size   am263x_irq_entry, . - am263x_irq_entry
        .ltorg

/* ------------------------------------------------------------------ faults: trip, then park
 * Every vector but reset and IRQ (undefined instruction, SVC, prefetch abort, data abort, the
 * reserved one, FIQ: none is used by this image, so any of them is a fault) forces the one-shot
 * trip of ePWM0-2 first: TZCTL = A and B low, TZFRC.OST (am263x/regs_epwm.h), two 16-bit stores
 * per module with r0-r3 only (no stack, no call, no load from RAM that a fault may have hit:
 * the base is a literal in this section). Then it parks with IRQs masked (the exception entry
 * masked them); which fault it was is in the mode (CPSR.M: UND or ABT), LR and DFSR/IFSR.
 * Measured in the processor-in-the-loop (tests/pil/test_pil_bridge.cpp): the outputs are off
 * within 60 core cycles of the faulting instruction, entry included (58 for a data abort, 55 for
 * an undefined instruction). The WFI park lets a debugger halt it; the trip holds without the
 * CPU, and the watchdog, no longer kicked, resets the part ~10 ms later. */
        .equ    EPWM0_TZ, 0x50000100        @ AM263X_EPWM_BASE(0) + EPWM_TZSEL
        .equ    TZCTL_OFF, 0x08             @ EPWM_TZCTL - EPWM_TZSEL
        .equ    TZFRC_OFF, 0x36             @ EPWM_TZFRC - EPWM_TZSEL
        .section .text.am263x_fault, "ax", %progbits
        .global am263x_fault, am263x_undef, am263x_svc, am263x_pabt, am263x_dabt, am263x_rsvd, am263x_fiq
        .type   am263x_fault, %function
am263x_fault:
am263x_undef:
am263x_svc:
am263x_pabt:
am263x_dabt:
am263x_rsvd:
am263x_fiq:
        ldr     r0, =EPWM0_TZ
        mov     r1, #0xA                    @ EPWM_TZCTL_BOTH_LOW
        mov     r2, #0x4                    @ EPWM_TZ_OST
        mov     r3, #3
1:      strh    r1, [r0, #TZCTL_OFF]
        strh    r2, [r0, #TZFRC_OFF]
        add     r0, r0, #0x1000             @ the next module
        subs    r3, r3, #1
        bne     1b
        dsb                                 @ the stores reach the ePWMs before the park
2:      wfi
        b       2b
        .size   am263x_fault, . - am263x_fault
        .ltorg
