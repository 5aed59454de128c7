/* R5F Vectored Interrupt Manager (VIM) registers used by this port. Offsets from TI's MCU+ SDK
 * source/kernel/nortos/dpl/r5/HwiP_armv7r_vim.h/.c (TRM: "R5FSS: Vectored Interrupt Manager
 * (VIM)"). Interrupt j: group g = j / 32, bit j % 32. */
#ifndef AM263X_REGS_VIM_H
#define AM263X_REGS_VIM_H
#include <stdint.h>

#define VIM_IRQVEC      0x18u   /* read: the vector address of the highest-priority pending IRQ
                                   (non-VIC mode: reading it also starts the prioritisation);
                                   write (any value): acknowledge, end of that IRQ             */
#define VIM_ACTIRQ      0x20u   /* bit 31 valid, bits 9:0 the active IRQ number               */
#define VIM_RAW(j)      (0x400u + 0x20u * ((uint32_t)(j) >> 5))   /* write 1: post (test)     */
#define VIM_STS(j)      (0x404u + 0x20u * ((uint32_t)(j) >> 5))   /* pending; write 1 clears  */
#define VIM_INT_EN(j)   (0x408u + 0x20u * ((uint32_t)(j) >> 5))   /* write 1 enables          */
#define VIM_INT_DIS(j)  (0x40Cu + 0x20u * ((uint32_t)(j) >> 5))   /* write 1 disables         */
#define VIM_INT_MAP(j)  (0x418u + 0x20u * ((uint32_t)(j) >> 5))   /* 0 IRQ, 1 FIQ             */
#define VIM_INT_TYPE(j) (0x41Cu + 0x20u * ((uint32_t)(j) >> 5))   /* 0 level, 1 pulse         */
#define VIM_INT_PRI(j)  (0x1000u + 4u * (uint32_t)(j))            /* 0 highest .. 15          */
#define VIM_INT_VEC(j)  (0x2000u + 4u * (uint32_t)(j))            /* handler address, bits 1:0
                                                                     not stored (word aligned) */
#define VIM_BIT(j)      (1u << ((uint32_t)(j) & 31u))
#define VIM_SIZE        0x3000u

#endif
