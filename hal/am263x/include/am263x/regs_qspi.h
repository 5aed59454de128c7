/* AM263x QSPI0 controller (TI QSPI, not the Cadence OSPI of the AM263Px) registers used by the
 * NVM driver. Offsets and fields from TI's MCU+ SDK source/drivers/qspi/v0/cslr_qspi.h and
 * lld/qspi_lld.c (TRM: "QSPI: Configuration Mode", "Memory-Mapped Mode", "QSPI Registers").
 *
 * Configuration mode (SPI_SWITCH_REG.MMPT_S = 0): a frame (chip select held) is FLEN + 1 words;
 * each word is started by a write of SPI_CMD_REG (with the frame length, the word length WLEN,
 * the chip select and the command: write single or read single), shifts the WLEN low bits of
 * SPI_DATA_REG out MSB first (write) or into SPI_DATA_REG (read), and is done when
 * SPI_STATUS_REG.BUSY reads 0. After the last word the chip select is released. Memory-mapped
 * mode (MMPT_S = 1): reads of the flash window (AM263X_FLASH_WIN_BASE) become flash read
 * commands as SPI_SETUP0_REG says (left as TI's SBL configured it). */
#ifndef AM263X_REGS_QSPI_H
#define AM263X_REGS_QSPI_H

#define QSPI_SPI_CLOCK_CNTRL 0x40u
#define QSPI_SPI_DC          0x44u
#define QSPI_SPI_CMD         0x48u
#define QSPI_SPI_STATUS      0x4Cu
#define QSPI_SPI_DATA        0x50u
#define QSPI_SPI_SETUP0      0x54u
#define QSPI_SPI_SWITCH      0x64u

/* SPI_CMD_REG: FLEN (11:0) frame length - 1 [words], WIRQ (14), FIRQ (15), CMD (18:16),
 * WLEN (25:19) word length - 1 [bits], CSNUM (29:28) */
#define QSPI_CMD_FLEN_MASK       0xFFFu
#define QSPI_CMD_CMD_SHIFT       16u
#define QSPI_CMD_CMD_MASK        0x7u
#define QSPI_CMD_READ_SINGLE     1u      /* FOUR_PIN_READ_SINGLE                             */
#define QSPI_CMD_WRITE_SINGLE    2u      /* FOUR_PIN_WRITE_SINGLE                            */
#define QSPI_CMD_WLEN_SHIFT      19u
#define QSPI_CMD_WLEN_MASK       0x7Fu
#define QSPI_CMD_CSNUM_SHIFT     28u
/* SPI_STATUS_REG: BUSY (0), WC word complete (1), FC frame complete (2) */
#define QSPI_STATUS_BUSY         0x1u
#define QSPI_STATUS_WC           0x2u
#define QSPI_STATUS_FC           0x4u
/* SPI_SWITCH_REG.MMPT_S (0): 0 configuration port, 1 memory-mapped port */
#define QSPI_SWITCH_MMPT_S       0x1u

/* Serial NOR commands (JEDEC-common, 3-byte addresses below 16 MiB) */
#define NOR_CMD_WREN   0x06u
#define NOR_CMD_RDSR   0x05u
#define NOR_CMD_PP     0x02u    /* page program (256-byte pages)                            */
#define NOR_CMD_P4E    0x20u    /* S25FL128S: 4 KiB parameter-sector erase (only there)     */
#define NOR_CMD_SE     0xD8u    /* S25FL128S: 64 KiB sector erase                           */
#define NOR_SR_WIP     0x01u
#define NOR_SR_WEL     0x02u

#endif
