/* AM263x MCAN (Bosch M_CAN in TI's MCANSS wrapper) registers and message RAM elements used by
 * this port, classic CAN only. Offsets and fields from TI's MCU+ SDK source/drivers/mcan/v0/
 * hw_mcanss.h and mcan.c (the M_CAN core is at the MCANSS base + 0x200; the message RAM is the
 * separate MCANn_MSG_RAM block), TRM sections "MCAN: Message RAM", "MCAN Registers", and the
 * Bosch M_CAN user's manual layout of the RX/TX buffer elements (T0/T1, R0/R1). */
#ifndef AM263X_REGS_MCAN_H
#define AM263X_REGS_MCAN_H
#include <stdint.h>

/* MCANSS wrapper (at the CFG base) */
#define MCANSS_STAT             0x008u
#define MCANSS_STAT_MEM_INIT_DONE 0x00000002u
#define MCAN_CORE_OFFSET        0x200u    /* M_CAN core registers: CFG base + 0x200           */

/* M_CAN core (offsets from the core base) */
#define MCAN_CCCR   0x18u
#define MCAN_NBTP   0x1Cu
#define MCAN_ECR    0x40u
#define MCAN_PSR    0x44u
#define MCAN_IR     0x50u
#define MCAN_IE     0x54u
#define MCAN_ILE    0x5Cu
#define MCAN_GFC    0x80u
#define MCAN_SIDFC  0x84u
#define MCAN_XIDFC  0x88u
#define MCAN_RXF0C  0xA0u
#define MCAN_RXF0S  0xA4u
#define MCAN_RXF0A  0xA8u
#define MCAN_RXESC  0xBCu
#define MCAN_TXBC   0xC0u
#define MCAN_TXFQS  0xC4u
#define MCAN_TXESC  0xC8u
#define MCAN_TXBAR  0xD0u
#define MCAN_TXEFC  0xF0u

/* CCCR */
#define MCAN_CCCR_INIT  0x00000001u   /* initialisation (set by the controller at bus-off)   */
#define MCAN_CCCR_CCE   0x00000002u   /* configuration change enable (with INIT)             */
#define MCAN_CCCR_FDOE  0x00000100u
#define MCAN_CCCR_BRSE  0x00000200u
/* NBTP: NTSEG2 (6:0), NTSEG1 (15:8), NBRP (24:16), NSJW (31:25); each "value - 1" */
#define MCAN_NBTP_NTSEG2_SHIFT 0u
#define MCAN_NBTP_NTSEG1_SHIFT 8u
#define MCAN_NBTP_NBRP_SHIFT   16u
#define MCAN_NBTP_NSJW_SHIFT   25u
/* PSR */
#define MCAN_PSR_EP     0x00000020u   /* error passive                                       */
#define MCAN_PSR_BO     0x00000080u   /* bus-off                                             */
/* IR */
#define MCAN_IR_RF0L    0x00000008u   /* RX FIFO 0 message lost                              */
/* SIDFC: FLSSA (15:2) byte address in the message RAM, LSS (23:16) elements;
 * XIDFC: FLESA (15:2), LSE (22:16); RXF0C: F0SA (15:2), F0S (22:16), F0WM (30:24), F0OM (31);
 * TXBC: TBSA (15:2), NDTB (21:16), TFQS (29:24), TFQM (30) 0 = FIFO */
#define MCAN_LIST_SIZE_SHIFT   16u
#define MCAN_TXBC_TFQS_SHIFT   24u
/* RXF0S: F0FL (6:0) fill level, F0GI (13:8) get index, F0F (24) full, RF0L (25) lost */
#define MCAN_RXF0S_F0FL_MASK   0x7Fu
#define MCAN_RXF0S_F0GI_SHIFT  8u
#define MCAN_RXF0S_F0GI_MASK   0x3Fu
/* TXFQS: TFFL (5:0) free level, TFGI (12:8), TFQPI (20:16) put index, TFQF (21) full */
#define MCAN_TXFQS_TFQPI_SHIFT 16u
#define MCAN_TXFQS_TFQPI_MASK  0x1Fu
#define MCAN_TXFQS_TFQF        0x00200000u

/* Buffer element words (TX T0/T1, RX R0/R1 share the first word's layout):
 * word 0: ID (28:0; an 11-bit identifier in 28:18), RTR (29), XTD (30), ESI (31)
 * word 1: TX: DLC (19:16), BRS (20), FDF (21), EFC (23), MM (31:24)
 *         RX: RXTS (15:0), DLC (19:16), BRS (20), FDF (21), FIDX (30:24), ANMF (31)
 * words 2, 3: data bytes 0..3, 4..7, byte 0 in bits 7:0 */
#define MCAN_ELEM_STD_ID_SHIFT 18u
#define MCAN_ELEM_RTR          0x20000000u
#define MCAN_ELEM_XTD          0x40000000u
#define MCAN_ELEM_DLC_SHIFT    16u
#define MCAN_ELEM_FDF          0x00200000u
#define MCAN_ELEM_WORDS        4u        /* 8-byte data field (RXESC/TXESC = 0): 2 + 2 words  */

/* This port's message RAM layout (byte offsets from the MCAN0 message RAM base):
 *   0x000  standard ID filters, 8 x 1 word  (all disabled: SFEC = 0)
 *   0x020  extended ID filters, 4 x 2 words (all disabled)
 *   0x040  RX FIFO 0, 16 elements x 16 bytes (blocking mode)
 *   0x140  TX FIFO, 8 elements x 16 bytes (no dedicated TX buffers, no TX event FIFO)
 *   0x1C0  end (448 bytes used).
 * GFC accepts every frame that matches no (enabled) filter into RX FIFO 0, standard and extended,
 * data and remote: the filter lists are reserved for the CANopen layer. */
#define AM263X_CAN_SID_OFF     0x000u
#define AM263X_CAN_SID_NUM     8u
#define AM263X_CAN_XID_OFF     0x020u
#define AM263X_CAN_XID_NUM     4u
#define AM263X_CAN_RX0_OFF     0x040u
#define AM263X_CAN_RX0_NUM     16u
#define AM263X_CAN_TX_OFF      0x140u
#define AM263X_CAN_TX_NUM      8u
#define AM263X_CAN_ELEM_BYTES  16u
#define AM263X_CAN_RAM_USED    0x1C0u

#endif
