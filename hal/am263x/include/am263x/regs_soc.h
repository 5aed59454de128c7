/* TI AM263x (R5FSS0 core 0, LP-AM263 LaunchPad): memory map, peripheral base addresses, clocks
 * and interrupt numbers used by this port.
 *
 * Sources of the facts (TI's public MCU+ SDK, mcupsdk-core, read for this port; no SDK code is
 * used): base addresses from source/drivers/hw_include/am263x/cslr_soc_baseaddress.h (TRM:
 * "Memory Map"), the R5F interrupt numbers from cslr_intr_r5fss0_core0.h (TRM: "Interrupts",
 * R5FSS0_CORE0 interrupt map), the interrupt crossbar layout from cslr_controlss_intxbar.h and
 * soc_xbar.h (TRM: "Control Subsystem, Interrupt XBAR"), the control-MMR lock (KICK0/KICK1) from
 * source/drivers/soc/am263x/soc.c and cslr_controlss_ctrl.h / cslr_top_ctrl.h (TRM: "Control
 * Module, Lock/Kick mechanism"). */
#ifndef AM263X_REGS_SOC_H
#define AM263X_REGS_SOC_H
#include <stdint.h>

/* ---- Memories (R5FSS0 core 0 view) */
#define AM263X_ATCM_BASE        0x00000000u   /* TCM A, 32 KiB: vectors + startup              */
#define AM263X_ATCM_SIZE        0x00008000u
#define AM263X_BTCM_BASE        0x00080000u   /* TCM B, 32 KiB: .data, .bss, stacks            */
#define AM263X_BTCM_SIZE        0x00008000u
#define AM263X_MSRAM_BASE       0x70000000u   /* on-chip shared RAM (L2OCRAM), 2 MiB           */
#define AM263X_MSRAM_SIZE       0x00200000u
/* QSPI flash, memory-mapped read window (CSL_EXT_FLASH0_U_BASE; the controller's window is
 * 32 MiB up to CSL_EXT_FLASH1_U_BASE). This port maps and uses the first 8 MiB: the LaunchPad's
 * QSPI NOR part is assumed to be at least 8 MiB (its exact part and size were not verified from
 * a TI source here). */
#define AM263X_FLASH_WIN_BASE   0x60000000u
#define AM263X_FLASH_WIN_SIZE   0x00800000u

/* ---- Peripherals (TRM: Memory Map; each block 4 KiB unless noted) */
#define AM263X_EPWM_BASE(n)     (0x50000000u + 0x1000u * (uint32_t)(n))  /* CONTROLSS_G0_EPWMn  */
#define AM263X_ADC_RESULT_BASE(n) (0x50100000u + 0x1000u * (uint32_t)(n)) /* CONTROLSS_ADCn_RESULT */
#define AM263X_EQEP_BASE(n)     (0x50270000u + 0x1000u * (uint32_t)(n))  /* CONTROLSS_EQEPn      */
#define AM263X_ADC_BASE(n)      (0x502C0000u + 0x1000u * (uint32_t)(n))  /* CONTROLSS_ADCn       */
#define AM263X_INTXBAR_BASE     0x502D5000u   /* CONTROLSS_INTXBAR                             */
#define AM263X_CTRLSS_CTRL_BASE 0x502F0000u   /* CONTROLSS_CTRL (8 KiB: lock at 0x1008)        */
#define AM263X_TOP_CTRL_BASE    0x50D80000u   /* TOP_CTRL (8 KiB: lock at 0x1008)              */
#define AM263X_VIM_BASE         0x50F00000u   /* R5FSS0 core 0 VIM (12 KiB: vectors at 0x2000) */
#define AM263X_RTI_BASE(n)      (0x52180000u + 0x1000u * (uint32_t)(n))  /* RTIn               */
#define AM263X_MCAN_MSGRAM_BASE(n) (0x52600000u + 0x10000u * (uint32_t)(n)) /* MCANn message RAM */
#define AM263X_MCAN_CFG_BASE(n) (0x52608000u + 0x10000u * (uint32_t)(n))  /* MCANn MCANSS wrapper;
                                                                              M_CAN core at +0x200 */
#define AM263X_QSPI_BASE        0x48200000u   /* QSPI0 controller (TI QSPI, config port)       */
#define AM263X_GPIO0_BASE       0x52000000u   /* GPIO0 (CSL_GPIO0_U_BASE), gpio v0 layout      */
#define AM263X_IOMUX_BASE       0x53100000u   /* IOMUX: pad configuration (CSL_IOMUX_U_BASE)   */
#define AM263X_MSS_RCM_BASE     0x53208000u   /* MSS_RCM: module clock source/divider          */

/* ---- Clocks (assumptions: the LaunchPad's defaults as TI's SBL / SOC init GEL leave them) */
#define AM263X_CPU_HZ           400000000u    /* R5F core clock                                */
#define AM263X_SYSCLK_HZ        200000000u    /* CONTROLSS SYSCLK = EPWMCLK = eQEP/ADC clock:
                                                 TI's ePWM examples use 200 MHz (SYSCLK_FREQ)   */
#define AM263X_EPWMCLK_HZ       AM263X_SYSCLK_HZ
#define AM263X_MCAN_FCLK_HZ     80000000u     /* MCAN functional clock: 400 MHz / 5 (board.c)  */
#define AM263X_RTI_CLK_HZ       25000000u     /* RTI input clock: the 25 MHz crystal (board.c) */

/* ---- Interrupts. The ADC interrupts reach the R5F through the CONTROLSS interrupt crossbar:
 * INTXBAR output k (registers INTXBARk_G0..G6, groups: G0 ePWM INT, G1 ePWM TZINT, G2 ADC
 * INT1..4/EVT) drives R5FSS0_CORE0 interrupt CONTROLSS_INTRXBAR0_OUT_k = 146 + k. */
#define AM263X_INTXBAR_G(out, g) (0x100u + 0x40u * (uint32_t)(out) + 4u * (uint32_t)(g))
#define AM263X_INTXBAR_GROUP_ADC 2u
#define AM263X_INTXBAR_ADC0_INT1 0x00000001u   /* bit in group 2                              */
#define AM263X_INTXBAR_OUT_ADC   0u            /* the crossbar output this port uses          */
#define AM263X_IRQ_INTXBAR_OUT0  146u          /* CSLR_R5FSS0_CORE0_CONTROLSS_INTRXBAR0_OUT_0 */
#define AM263X_IRQ_ADC_EOC       (AM263X_IRQ_INTXBAR_OUT0 + AM263X_INTXBAR_OUT_ADC)

/* ---- Control MMR lock (partition 0 of CONTROLSS_CTRL and TOP_CTRL): writes to the protected
 * registers need KICK0 then KICK1 written with these values; 0 locks again. */
#define AM263X_LOCK0_KICK0      0x1008u
#define AM263X_LOCK0_KICK1      0x100Cu
#define AM263X_KICK0_UNLOCK     0x01234567u
#define AM263X_KICK1_UNLOCK     0x0FEDCBA8u
#define AM263X_KICK_LOCK        0x00000000u
/* CONTROLSS_CTRL: the ePWM time-base clock enables (one bit per ePWM module): the counters of
 * the enabled modules start together (the C2000 "TBCLKSYNC"). */
#define AM263X_CTRLSS_EPWM_CLKSYNC 0x010u
/* TOP_CTRL: ADC reference buffers (SOC_enableAdcReference: REFBUF0 = 7 for ADC0..2, the
 * comparator enables 0x7 << 0 for ADC0). */
#define AM263X_TOP_ADC_REFBUF0_CTRL   0xC00u
#define AM263X_TOP_ADC_REF_COMP_CTRL  0xC08u

/* ---- Module clocks (MSS_RCM, cslr_mss_rcm.h; source codes and divider format from TI's
 * source/drivers/soc/am263x/soc_rcm.c: gMcanClkSrcValMap / gRtiClkSrcValMap, and
 * SOC_rcmSetPeripheralClock, which writes the divider (N - 1 in each of the three nibbles) first,
 * then the source, each read back (erratum i2324)). Reset value of both registers: 0 = WUCPUCLK
 * (25 MHz), divider 1; TI's SBL (bootloader_soc.c, Bootloader_socConfigurePll) sets the PLLs
 * (core HSDIV0 CLKOUT0 400 MHz, PER HSDIV0 CLKOUT0/1 160/192 MHz) but no module clock, so an
 * application that assumes 80 MHz must select it itself. */
#define AM263X_RCM_MCAN0_CLK_SRC_SEL  0x100u
#define AM263X_RCM_RTI0_CLK_SRC_SEL   0x114u
#define AM263X_RCM_MCAN0_CLK_DIV_VAL  0x200u
#define AM263X_RCM_RTI0_CLK_DIV_VAL   0x214u
/* WDT0 (cslr_mss_rcm.h CSL_MSS_RCM_WDT0_CLK_SRC_SEL / _DIV_VAL; soc_rcm.c gWdtClkSrcValMap: the
 * same codes as RTI for WUCPUCLK 0x000 and XTALCLK 0x666, RCCLK10M 0x111/0x555, RCCLK32K 0x777) */
#define AM263X_RCM_WDT0_CLK_SRC_SEL   0x128u
#define AM263X_RCM_WDT0_CLK_DIV_VAL   0x228u
#define AM263X_RCM_SRC_WUCPUCLK       0x000u   /* reset: 25 MHz                               */
#define AM263X_RCM_SRC_XTALCLK        0x666u   /* 25 MHz crystal (MCAN and RTI)               */
#define AM263X_RCM_SRC_MCAN_CORE_HSDIV0 0x444u /* DPLL_CORE_HSDIV0_CLKOUT0, 400 MHz (MCAN)    */
#define AM263X_RCM_DIV(n)             (((uint32_t)(n) - 1u) * 0x111u)
#define AM263X_CORE_HSDIV0_HZ         400000000u
#define AM263X_XTAL_HZ                25000000u

/* ---- Pad configuration (IOMUX, cslr_iomux.h / TI's pinmux.h bit layout): FUNC_SEL (3:0), the
 * IE/OE override controls (7:4), PI (8) 1 = pull disabled, PUPDSEL (9) 1 = up, SLEWRATE (10)
 * 1 = low. Reset value of every pad used here 0x5F7: mode 7 = GPIO, overrides on, no pull.
 * Writes need the IO_CFG_KICK0/1 unlock (values from TI's pinmux.c). */
#define AM263X_IOMUX_KICK0            0x298u
#define AM263X_IOMUX_KICK1            0x29Cu
#define AM263X_IOMUX_KICK0_UNLOCK     0x83E70B13u
#define AM263X_IOMUX_KICK1_UNLOCK     0x95A4F1E0u
#define AM263X_PAD_RESET              0x5F7u
#define AM263X_PAD_FUNC_MASK          0xFu
#define AM263X_PAD_GPIO               7u
#define AM263X_PAD_NOPULL             0x100u
#define AM263X_PAD_SLEW_LOW           0x400u
#define AM263X_PAD_PULLUP             0x200u   /* PUPDSEL: up (with PI = 0)                   */
/* The LP-AM263 pads (cslr_iomux.h offsets). Which pads the LaunchPad wires: TI's am263x-lp
 * examples of mcupsdk-core assign ePWM0..2 A/B to the pads of the same name
 * (examples/drivers/epwm/epwm_deadband/am263x-lp/.../example.syscfg), eQEP0 A/B/INDEX to pads
 * EQEP0_A/B/INDEX (eqep/eqep_frequency_measurement/am263x-lp), MCAN0 RX/TX to pads MCAN0_RX/TX
 * (mcan/canfd_external_read_write/am263x-lp, whose canfd_transceiver.c drives the transceiver's
 * STB low through the GPIO on pad EPWM4_A). Function numbers from SysConfig-generated
 * ti_pinmux_config.c for AM263x ZCZ: ePWM on its pad mode 0, eQEP0 on its pads mode 8 (balls
 * B14/A14/D11); MCAN0 on its pads mode 0 (the pad's primary function, as ePWM and UART0). */
#define AM263X_PAD_MCAN0_RX           0x01Cu
#define AM263X_PAD_MCAN0_TX           0x020u
#define AM263X_PAD_EPWM_A(n)          (0x0ACu + 8u * (uint32_t)(n))
#define AM263X_PAD_EPWM_B(n)          (0x0B0u + 8u * (uint32_t)(n))
#define AM263X_PAD_EQEP0_A            0x208u
#define AM263X_PAD_EQEP0_B            0x20Cu
#define AM263X_PAD_EQEP0_INDEX        0x214u
/* The hardware trip input (docs/porting.md): the gate driver's nFAULT on pad SPI0_CS0 as GPIO11
 * (pinmux.h PIN_SPI0_CS0 0x2C, mode 7), INPUT XBAR 0 -> TZ1 (regs_epwm.h AM263X_TRIP_GPIO). */
#define AM263X_PAD_SPI0_CS0           0x02Cu/* The MCAN transceiver's standby input: GPIO51 on pad EPWM4_A (ball D1; "GPIO51 -> EPWM4_A"
 * in SysConfig-generated ti_pinmux_config.c, mode 7), driven low to leave standby
 * (canfd_external_read_write/am263x-lp/canfd_transceiver.c: GPIO_setDirMode output,
 * GPIO_pinWriteLow). gpio v0 registers (source/drivers/gpio/v0/cslr_gpio.h, gpio.h): 32 pins per
 * register set n = pin / 32 at 0x28 n; DIR bit 0 = output (GPIO_DIRECTION_OUTPUT 0). */
#define AM263X_PAD_EPWM4_A            0x0CCu
#define AM263X_CAN_STB_GPIO           51u
#define AM263X_GPIO_DIR(n)            (0x10u + 0x28u * (uint32_t)(n))
#define AM263X_GPIO_OUT_DATA(n)       (0x14u + 0x28u * (uint32_t)(n))
#define AM263X_GPIO_CLR_DATA(n)       (0x1Cu + 0x28u * (uint32_t)(n))
#define AM263X_PAD_FN_EPWM            0u
#define AM263X_PAD_FN_EQEP            8u
#define AM263X_PAD_FN_MCAN            0u

#endif
