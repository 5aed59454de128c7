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

#endif
