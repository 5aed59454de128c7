/* RTI (real-time interrupt) timer, counter block 0, used as the microsecond time base. Offsets
 * from TI's MCU+ SDK source/drivers/rti/v0/cslr_rti.h (TRM: "RTI: Counter Operation"): the up
 * counter RTIUC0 counts RTICLK and, on reaching RTICPUC0, resets and increments the free-running
 * counter RTIFRC0, so FRC0 runs at RTICLK / (RTICPUC0 + 1). */
#ifndef AM263X_REGS_RTI_H
#define AM263X_REGS_RTI_H

#define RTI_RTIGCTRL    0x00u
#define RTI_RTITBCTRL   0x04u
#define RTI_RTICAPCTRL  0x08u
#define RTI_RTICOMPCTRL 0x0Cu
#define RTI_RTIFRC0     0x10u
#define RTI_RTIUC0      0x14u
#define RTI_RTICPUC0    0x18u
#define RTI_GCTRL_CNT0EN 0x00000001u

/* Digital windowed watchdog (DWWD) of an RTI module; the AM263x's watchdogs are the RTI instances
 * WDT0..3 (MCU+ SDK hw_include/am263x/cslr_soc_baseaddress.h: CSL_WDT0_U_BASE 0x52100000; driver
 * source/drivers/watchdog/v0/watchdog_rti.c, offsets and values from watchdog/v1/cslr_rti.h).
 * The down counter starts at (DWDPRLD + 1) x 2^13 watchdog-clock cycles when enabled and at each
 * key sequence; at zero (or a key outside the window) the reaction of RTIWWDRXNCTRL fires. Once
 * enabled it runs until a reset. RTIGCTRL.COS (bit 15) = 0: it stops while the CPU is halted by
 * a debugger (a breakpoint does not reset the part). */
#define AM263X_WDT0_BASE   0x52100000u
#define AM263X_WDT_CLK_HZ  25000000u   /* WDT0 functional clock: XTAL, divider 1, set by
                                          board.c (MSS_RCM WDT0_CLK_SRC_SEL / _DIV_VAL)     */
#define RTI_RTIDWDCTRL     0x90u   /* write RTI_DWDCTRL_ENABLE: start                          */
#define RTI_RTIDWDPRLD     0x94u   /* 12 bits                                                  */
#define RTI_RTIWDSTATUS    0x98u   /* bit1 DWDST: expired; bit5 DWWD_ST; write 1s to clear     */
#define RTI_RTIWDKEY       0x9Cu   /* RTI_WDKEY_1 then RTI_WDKEY_2: the counter reloaded       */
#define RTI_RTIDWDCNTR     0xA0u   /* the down counter (read-only)                             */
#define RTI_RTIWWDRXNCTRL  0xA4u   /* reaction: 0x5 reset (reset value), 0xA interrupt (NMI)   */
#define RTI_RTIWWDSIZECTRL 0xA8u   /* window: 0x5 = 100 % (no closed window)                   */
#define RTI_DWDCTRL_ENABLE 0xA98559DAu
#define RTI_WDKEY_1        0xE51Au
#define RTI_WDKEY_2        0xA35Cu
#define RTI_WDSTATUS_DWDST 0x2u
#define RTI_WWDRXN_RESET   0x5u
#define RTI_WWDSIZE_100    0x5u
#define RTI_DWD_PRLD_SHIFT 13u

#endif
