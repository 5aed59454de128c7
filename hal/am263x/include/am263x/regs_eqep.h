/* AM263x eQEP registers used by this port. Offsets and fields from TI's MCU+ SDK
 * source/drivers/eqep/v1/cslr_eqep.h and eqep.h, TRM sections "eQEP: Quadrature Decoder Unit",
 * "Position Counter and Control Unit", "Edge Capture Unit", "Unit Timer Base", "eQEP Registers".
 * Width: 32 bits for the position registers and QUPRD, 16 bits for the control registers. */
#ifndef AM263X_REGS_EQEP_H
#define AM263X_REGS_EQEP_H
#include <stdint.h>

#define EQEP_QPOSCNT   0x00u   /* (32) position counter                                      */
#define EQEP_QPOSINIT  0x04u   /* (32) */
#define EQEP_QPOSMAX   0x08u   /* (32) counter wraps to 0 after this (PCRM = 1)              */
#define EQEP_QPOSILAT  0x10u   /* (32) counter latched at the index event                    */
#define EQEP_QPOSLAT   0x18u   /* (32) counter latched at the unit time-out (QCLM = 1)       */
#define EQEP_QUTMR     0x1Cu   /* (32) unit timer                                            */
#define EQEP_QUPRD     0x20u   /* (32) unit period [SYSCLK cycles]                           */
#define EQEP_QDECCTL   0x28u
#define EQEP_QEPCTL    0x2Au
#define EQEP_QCAPCTL   0x2Cu
#define EQEP_QEINT     0x30u
#define EQEP_QFLG      0x32u
#define EQEP_QCLR      0x34u
#define EQEP_QEPSTS    0x38u
#define EQEP_QCTMR     0x3Au
#define EQEP_QCPRD     0x3Cu
#define EQEP_QCTMRLAT  0x3Eu
#define EQEP_QCPRDLAT  0x40u   /* capture period latched at the unit time-out (QCLM = 1)     */

/* QDECCTL: QSRC (15:14) 0 = quadrature count mode; XCR (11) 0 = both edges of QA and QB
 * (4 counts per line) */
#define EQEP_QDECCTL_QUADRATURE   0x0000u
/* QEPCTL */
#define EQEP_QEPCTL_UTE           0x0002u   /* unit timer enable                             */
#define EQEP_QEPCTL_QCLM          0x0004u   /* latch on unit time-out                        */
#define EQEP_QEPCTL_QPEN          0x0008u   /* position counter enable                       */
#define EQEP_QEPCTL_IEL_RISING    0x0010u   /* IEL (5:4) = 1: QPOSILAT on the index rising edge */
#define EQEP_QEPCTL_PCRM_MAX      0x1000u   /* PCRM (13:12) = 1: reset on the maximum position */
#define EQEP_QEPCTL_FREE_RUN      0x8000u   /* FREE_SOFT (15:14) = 2                          */
/* QCAPCTL: UPPS (3:0) unit position event = QCLK / 2^UPPS; CCPS (6:4) capture clock =
 * SYSCLK / 2^CCPS; CEN (15) */
#define EQEP_QCAPCTL_UPPS_SHIFT   0u
#define EQEP_QCAPCTL_CCPS_SHIFT   4u
#define EQEP_QCAPCTL_CEN          0x8000u
/* QFLG / QCLR */
#define EQEP_QFLG_INT             0x0001u
#define EQEP_QFLG_IEL             0x0400u   /* index event latched                           */
#define EQEP_QFLG_UTO             0x0800u   /* unit time-out                                 */
/* QEPSTS */
#define EQEP_QEPSTS_FIMF          0x0002u   /* first index marker seen (sticky, write 1 clears) */
#define EQEP_QEPSTS_CDEF          0x0004u   /* capture direction error (write 1 clears)      */
#define EQEP_QEPSTS_COEF          0x0008u   /* capture overflow (write 1 clears)             */
#define EQEP_QEPSTS_QDF           0x0020u   /* direction: 1 counting up                       */
#define EQEP_QEPSTS_UPEVNT        0x0080u   /* unit position event (write 1 clears)          */

#endif
