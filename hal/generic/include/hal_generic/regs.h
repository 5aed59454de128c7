/* The generic memory-mapped port (the Cortex-M4F budget reference): a minimal, documented
 * register block standing for any MCU with a centre-aligned 3-phase timer, an ADC triggered at
 * the period centre, a quadrature counter and a microsecond timer. Not a real part: its purpose
 * is that the same firmware image runs under processor-in-the-loop (sim/pil/dev_generic.cpp
 * emulates exactly these registers) and that its code and RAM size are those of a small MCU.
 * All registers 32 bits wide, little-endian, word access. */
#ifndef HAL_GENERIC_REGS_H
#define HAL_GENERIC_REGS_H
#include <stdint.h>

/* Memory map (Cortex-M: code in flash at 0, SRAM at 0x20000000, peripherals at 0x40000000). */
#define GEN_FLASH_BASE   0x00000000u
#define GEN_FLASH_SIZE   0x00080000u   /* 512 KiB: image, then the NVM blocks                  */
#define GEN_NVM_BASE     0x00060000u   /* hal_nvm: 8 blocks of 16 KiB, memory-mapped reads    */
#define GEN_NVM_BLOCKS   8u
#define GEN_NVM_BLOCK    0x4000u
#define GEN_NVM_UNIT     8u
#define GEN_SRAM_BASE    0x20000000u
#define GEN_SRAM_SIZE    0x00010000u   /* 64 KiB                                               */

/* PWM: one up-down counter (0 -> PRD -> 0: period = 2 x PRD counts of the PWM clock), three
 * compare channels. Phase x high side on while the counter is at or above PRD - CMPx: duty =
 * CMPx / PRD, the pulse centred on the counter's peak, so that counter zero (the period boundary,
 * where the ADC converts) is the centre of the zero vector V000. CMPx written by the core are
 * shadowed and take effect at counter zero. */
#define GEN_PWM_BASE     0x40000000u
#define GEN_PWM_CTRL     0x00u   /* bit0 RUN: counter runs; bit1 OE: outputs enabled (a write of
                                    0 takes effect at once: all six switches off)              */
#define GEN_PWM_PRD      0x04u   /* half period in PWM clock counts                           */
#define GEN_PWM_DT       0x08u   /* dead time in PWM clock counts (both edges)                 */
#define GEN_PWM_CMP(x)   (0x0Cu + 4u * (uint32_t)(x))   /* x = 0, 1, 2: phase a, b, c (shadow) */
#define GEN_PWM_CLK_HZ   100000000u  /* PWM clock                                             */
#define GEN_PWM_CTRL_RUN 0x1u
#define GEN_PWM_CTRL_OE  0x2u
#define GEN_PWM_DT_MIN   20u     /* dead-time floor [counts] = 200 ns: less is refused         */

/* ADC: converts the four channels at every counter zero; EOC raises IRQ GEN_ADC_IRQ if enabled. */
#define GEN_ADC_BASE     0x40001000u
#define GEN_ADC_CTRL     0x00u   /* bit0 EN: convert at counter zero; bit1 IE: EOC interrupt  */
#define GEN_ADC_STS      0x04u   /* bit0 EOC (write 1 to clear); bit1 OVR: an EOC came while the
                                    last was still set (write 1 to clear)                     */
#define GEN_ADC_CHMAP    0x08u   /* bytes 0..3: input of result 0..3                           */
#define GEN_ADC_RES(n)   (0x10u + 4u * (uint32_t)(n))   /* n = 0..3: ia, ib, ic, vdc [counts]  */
#define GEN_ADC_CTRL_EN  0x1u
#define GEN_ADC_CTRL_IE  0x2u
#define GEN_ADC_STS_EOC  0x1u
#define GEN_ADC_STS_OVR  0x2u
#define GEN_ADC_IRQ      0u      /* NVIC line                                                  */

/* Quadrature counter. */
#define GEN_QEP_BASE     0x40002000u
#define GEN_QEP_POS      0x00u   /* 0 .. MAX                                                   */
#define GEN_QEP_MAX      0x04u   /* counts per revolution - 1 (written by the core)            */
#define GEN_QEP_STS      0x08u   /* bit0: an index pulse has been seen                         */
#define GEN_QEP_IDX      0x0Cu   /* POS latched at the last index                              */

/* Microsecond timer. */
#define GEN_TIM_BASE     0x40003000u
#define GEN_TIM_US       0x00u

/* Flash controller for the NVM blocks (reads are memory-mapped at GEN_NVM_BASE). A command
 * completes before the CMD write returns (the emulation; a real part would poll STS.BUSY). */
#define GEN_FLC_BASE     0x40004000u
#define GEN_FLC_ADDR     0x00u   /* byte address in the flash (GEN_NVM_BASE ..)                */
#define GEN_FLC_DATA0    0x04u   /* program: bytes 0..3 of the 8-byte unit                     */
#define GEN_FLC_DATA1    0x08u   /* program: bytes 4..7                                        */
#define GEN_FLC_CMD      0x0Cu   /* 1: program the unit at ADDR (flash AND: bits only clear);
                                    2: erase the 16 KiB block holding ADDR (to 0xFF)           */
#define GEN_FLC_STS      0x10u   /* bit0 BUSY (always 0 here); bit1 ERR: bad address/alignment
                                    of the last command (write 1 to clear)                     */
#define GEN_FLC_CMD_PROGRAM 1u
#define GEN_FLC_CMD_ERASE   2u

/* Watchdog: a down counter in microseconds. Once CTRL.EN is set it counts down from LOAD and
 * stays enabled until reset; a write of GEN_WDT_KICK_KEY to KICK reloads it. At zero it sets
 * STS.EXP and, in hardware, clears PWM CTRL (RUN and OE: all six switches off). */
#define GEN_WDT_BASE     0x40005000u
#define GEN_WDT_LOAD     0x00u   /* timeout [us] (written before EN)                           */
#define GEN_WDT_CTRL     0x04u   /* bit0 EN                                                    */
#define GEN_WDT_KICK     0x08u   /* write GEN_WDT_KICK_KEY                                     */
#define GEN_WDT_STS      0x0Cu   /* bit0 EXP: expired (the outputs were turned off)            */
#define GEN_WDT_CTRL_EN  0x1u
#define GEN_WDT_KICK_KEY 0x5AFEu
#define GEN_WDT_STS_EXP  0x1u
#define GEN_WDT_TIMEOUT_US 10000u   /* the port's timeout: 200 periods at 20 kHz              */

/* Stage marker for cycle accounting (hal/stage.h): not a register, a RAM variable of the port,
 * `hal_stage_reg`, whose stores the PIL watches. */

#define GEN_REG(base, off) (*(volatile uint32_t *)((base) + (off)))

#endif
