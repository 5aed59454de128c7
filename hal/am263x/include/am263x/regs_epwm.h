/* AM263x ePWM (type 4/5, C2000 lineage) registers used by this port. Offsets and fields from TI's
 * MCU+ SDK source/drivers/epwm/v1/cslr_etpwm.h and etpwm.h (the AM263x driver), TRM sections
 * "ePWM: Time-Base Submodule Registers", "Counter-Compare Submodule", "Action-Qualifier
 * Submodule", "Dead-Band Generator Submodule", "Trip-Zone Submodule", "Event-Trigger Submodule".
 * Width: 16 bits unless marked (32). */
#ifndef AM263X_REGS_EPWM_H
#define AM263X_REGS_EPWM_H
#include <stdint.h>

#define EPWM_TBCTL          0x000u
#define EPWM_EPWMSYNCINSEL  0x006u
#define EPWM_TBCTR          0x008u
#define EPWM_EPWMSYNCOUTEN  0x00Cu
#define EPWM_CMPCTL         0x010u
#define EPWM_DBCTL          0x018u
#define EPWM_AQCTLA         0x080u
#define EPWM_AQCTLB         0x084u
#define EPWM_AQCSFRC        0x092u
#define EPWM_DBRED          0x0A2u
#define EPWM_DBFED          0x0A6u
#define EPWM_TBPHS          0x0C0u   /* (32) TBPHS in bits 31:16, TBPHSHR in 15:0               */
#define EPWM_TBPRD          0x0C6u
#define EPWM_CMPA           0x0D4u   /* (32) CMPA in bits 31:16, CMPAHR in 15:0                 */
#define EPWM_CMPA_HI        0x0D6u   /* the 16-bit CMPA half (SDK: HW_WR_REG16(CMPA + 2))       */
#define EPWM_TZSEL          0x100u
#define EPWM_TZCTL          0x108u
#define EPWM_TZFLG          0x126u
#define EPWM_TZCLR          0x12Eu
#define EPWM_TZFRC          0x136u
#define EPWM_ETSEL          0x148u
#define EPWM_ETPS           0x14Cu
#define EPWM_ETFLG          0x150u
#define EPWM_ETCLR          0x154u

/* TBCTL */
#define EPWM_TBCTL_CTRMODE_MASK   0x0003u
#define EPWM_TBCTL_CTRMODE_UPDOWN 0x0002u
#define EPWM_TBCTL_CTRMODE_STOP   0x0003u   /* stop-freeze                                     */
#define EPWM_TBCTL_PHSEN          0x0004u   /* load TBCTR from TBPHS on a sync-in              */
#define EPWM_TBCTL_PRDLD          0x0008u   /* 1: TBPRD written directly (0: shadow, at zero)  */
#define EPWM_TBCTL_HSPCLKDIV_SHIFT 7u       /* /1,/2,/4..: 0 = /1 (reset value 1 = /2)         */
#define EPWM_TBCTL_CLKDIV_SHIFT   10u       /* 0 = /1                                          */
#define EPWM_TBCTL_PHSDIR         0x2000u   /* up-down mode: count up after a sync             */
#define EPWM_TBCTL_FREE_RUN       0x8000u   /* FREE_SOFT = 2: free run on emulation halt       */
#define EPWM_TBCTL_SOFT_STOP      0x4000u   /* FREE_SOFT = 1: on emulation halt, stop when the
                                               counter completes the cycle (up-down: at zero);
                                               0 = stop after the next count (TRM: TBCTL)     */
#define EPWM_TBCTL_FREE_SOFT_MASK 0xC000u
/* EPWMSYNCINSEL.SEL: 0 disabled, n+1 = SYNCOUT of ePWMn */
#define EPWM_SYNCIN_EPWM(n)       ((uint16_t)((n) + 1u))
/* EPWMSYNCOUTEN */
#define EPWM_SYNCOUT_ZEROEN       0x0002u
/* CMPCTL: SHDWAMODE (bit 4) 0 = shadow; LOADAMODE (bits 1:0) 0 = load at counter zero */
#define EPWM_CMPCTL_SHDWAMODE     0x0010u
#define EPWM_CMPCTL_LOADAMODE_MASK 0x0003u
/* AQCTLx: 2-bit actions 0 none, 1 clear (low), 2 set (high), 3 toggle at
 * ZRO (1:0), PRD (3:2), CAU (5:4), CAD (7:6), CBU (9:8), CBD (11:10) */
#define EPWM_AQ_NONE   0u
#define EPWM_AQ_CLEAR  1u
#define EPWM_AQ_SET    2u
#define EPWM_AQ_ZRO_SHIFT 0u
#define EPWM_AQ_PRD_SHIFT 2u
#define EPWM_AQ_CAU_SHIFT 4u
#define EPWM_AQ_CAD_SHIFT 6u
/* DBCTL: OUT_MODE (1:0) bit0 FED path on B, bit1 RED path on A; POLSEL (3:2) bit2 invert A,
 * bit3 invert B; IN_MODE (5:4) 0: ePWMxA is the source of both delays. Active-high
 * complementary (AHC) = OUT_MODE 3, POLSEL 2, IN_MODE 0. */
#define EPWM_DBCTL_AHC            0x000Bu
#define EPWM_DB_MAX               0x3FFFu   /* DBRED/DBFED: 14 bits, in TBCLK counts           */
/* TZSEL: OSHTn (bit 8 + n - 1) makes TZn a one-shot trip source (cslr_epwm.h EPWM_TZSEL) */
#define EPWM_TZSEL_OSHT1          0x0100u
/* The hardware trip path on the LP-AM263 (TI MCU+ SDK examples/drivers/epwm/epwm_trip_zone/
 * am263x-lp example.syscfg: pad SPI0_CS0 as GPIO11 -> INPUT XBAR output 0 -> ePWM TZ1 as OSHT1;
 * register layout hw_include/am263x/cslr_controlss_inputxbar.h): the gate driver's open-drain
 * nFAULT (or an over-current comparator), active low like every TZn input. */
#define AM263X_INPUTXBAR_BASE     0x502D0000u   /* CSL_CONTROLSS_INPUTXBAR_U_BASE            */
#define AM263X_INPUTXBAR_GSEL(n)  (0x100u + 0x40u * (uint32_t)(n))   /* 0: group 0 (GPIOs)   */
#define AM263X_INPUTXBAR_G0(n)    (0x104u + 0x40u * (uint32_t)(n))   /* group 0: GPIO number */
#define AM263X_TRIP_GPIO          11u
/* TZCTL: TZA (1:0), TZB (3:2): 0 high-Z, 1 high, 2 low, 3 no action */
#define EPWM_TZ_LOW               2u
#define EPWM_TZCTL_BOTH_LOW       ((uint16_t)((EPWM_TZ_LOW << 0) | (EPWM_TZ_LOW << 2)))
/* TZFLG / TZCLR / TZFRC */
#define EPWM_TZ_INT               0x0001u
#define EPWM_TZ_OST               0x0004u
/* ETSEL: SOCASEL (10:8) 1 = counter zero, SOCAEN (11) */
#define EPWM_ETSEL_SOCASEL_SHIFT  8u
#define EPWM_ETSEL_SOCASEL_ZERO   1u
#define EPWM_ETSEL_SOCAEN         0x0800u
/* ETPS: SOCAPRD (9:8): SOCA on every 1st, 2nd, 3rd event */
#define EPWM_ETPS_SOCAPRD_SHIFT   8u

#endif
