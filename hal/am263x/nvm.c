/* NVM of the AM263x port on the LaunchPad's QSPI NOR flash. The AM263x has no internal flash and
 * its flash controller is TI's QSPI (QSPI0; the Cadence OSPI with its STIG command generator is
 * the AM263Px's): reads go through the memory-mapped window, program and erase are serial-NOR
 * commands sent through the controller's configuration port (am263x/regs_qspi.h):
 *   erase block:  WREN | RDSR (WEL must be set) | the region's erase command addr | RDSR until
 *                 WIP = 0 | read back through the window: every byte 0xFF
 *   write unit:   WREN | RDSR (WEL) | PP addr d0..d7 | RDSR until WIP = 0 | read back through
 *                 the window, which must equal old AND new
 * Every word of a frame is 8 bits, so the byte order on the wire is the order of the calls
 * (the address most significant byte first). Each call is bounded: its units, and per command
 * the polls counted in hal_nvm_t. Between commands the controller is switched back to the
 * memory-mapped port, so that code and reads of the window keep working.
 * Location: AM263X_NVM_FLASH_OFF (port.h), 2 blocks = two 64 KiB sectors of the flash's map
 * (am263x_s25fl128s below), each erased with its region's command. */
#include <stddef.h>
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_qspi.h"

#define BUSY_POLLS 10000u        /* one 8-bit word at >= 1 MHz: a few us; generous            */
#define ERASE_POLLS 2000000u     /* RDSR frames (~1 us each at tens of MHz): > 2 s, well above
                                    a 64 KiB sector erase (hundreds of ms)                     */
#define PROGRAM_POLLS 20000u     /* > 5 ms page program maximum                                */

static const hal_nvm_region_t s25fl128s_regions[2] = {
    {0x000000u, 0x1000u, 32u, NOR_CMD_P4E},    /* parameter sectors (TBPARM = 0) */
    {0x020000u, 0x10000u, 254u, NOR_CMD_SE},
};
const hal_nvm_geometry_t am263x_s25fl128s = {0x1000000u, 256u, 2u, s25fl128s_regions};

void am263x_nvm_init(hal_nvm_t *nvm, uintptr_t qspi, uintptr_t window, const hal_nvm_geometry_t *geom,
                     uint32_t flash_offset, uint32_t bytes)
{
    nvm->qspi = qspi;
    nvm->window = window;
    nvm->geom = geom;
    nvm->base = flash_offset;
    nvm->blocks = 0u;
    nvm->block_size = 0u;
    const hal_nvm_region_t *r = hal_nvm_region_at(geom, flash_offset);
    if (r != NULL && bytes != 0u && bytes <= geom->size && flash_offset % r->sector_size == 0u &&
        bytes % r->sector_size == 0u && hal_nvm_region_at(geom, flash_offset + bytes - 1u) == r) {
        nvm->block_size = r->sector_size;
        nvm->blocks = bytes / r->sector_size;
        nvm->erase_cmd = r->erase_cmd;
    }
    nvm->busy_polls = BUSY_POLLS;
    nvm->erase_polls = ERASE_POLLS;
    nvm->program_polls = PROGRAM_POLLS;
    nvm->wdg = NULL;
    am263x_wr32(qspi + QSPI_SPI_SWITCH, QSPI_SWITCH_MMPT_S);
}

/* One 8-bit word of a frame of flen words: write (tx) or read (returns the byte in *rx). */
static bool qspi_word(const hal_nvm_t *nvm, uint32_t flen, bool write, uint8_t tx, uint8_t *rx)
{
    const uintptr_t q = nvm->qspi;
    const uint32_t cmd = ((flen - 1u) & QSPI_CMD_FLEN_MASK) |
                         ((write ? QSPI_CMD_WRITE_SINGLE : QSPI_CMD_READ_SINGLE) << QSPI_CMD_CMD_SHIFT) |
                         ((8u - 1u) << QSPI_CMD_WLEN_SHIFT) | (0u << QSPI_CMD_CSNUM_SHIFT);
    if (write) {
        am263x_wr32(q + QSPI_SPI_DATA, tx);
    }
    am263x_wr32(q + QSPI_SPI_CMD, cmd);
    for (uint32_t k = 0u; k < nvm->busy_polls; ++k) {
        if ((am263x_rd32(q + QSPI_SPI_STATUS) & QSPI_STATUS_BUSY) == 0u) {
            if (!write) {
                *rx = (uint8_t)am263x_rd32(q + QSPI_SPI_DATA);
            }
            return true;
        }
    }
    return false;
}

/* A frame: n_tx bytes out, then n_rx bytes in. */
static bool qspi_frame(const hal_nvm_t *nvm, const uint8_t *tx, uint32_t n_tx, uint8_t *rx, uint32_t n_rx)
{
    const uint32_t flen = n_tx + n_rx;
    for (uint32_t k = 0u; k < n_tx; ++k) {
        if (!qspi_word(nvm, flen, true, tx[k], NULL)) {
            return false;
        }
    }
    for (uint32_t k = 0u; k < n_rx; ++k) {
        if (!qspi_word(nvm, flen, false, 0u, &rx[k])) {
            return false;
        }
    }
    return true;
}

static bool read_status(const hal_nvm_t *nvm, uint8_t *sr)
{
    const uint8_t c = NOR_CMD_RDSR;
    return qspi_frame(nvm, &c, 1u, sr, 1u);
}

static bool write_enable(const hal_nvm_t *nvm)
{
    const uint8_t c = NOR_CMD_WREN;
    uint8_t sr = 0u;
    return qspi_frame(nvm, &c, 1u, NULL, 0u) && read_status(nvm, &sr) && (sr & NOR_SR_WEL) != 0u;
}

static bool wait_ready(const hal_nvm_t *nvm, uint32_t polls)
{
    for (uint32_t k = 0u; k < polls; ++k) {
        /* a 64 KiB erase outlasts the watchdog many times: kept alive while the ISR runs */
        if (nvm->wdg != NULL) {
            hal_wdg_service(nvm->wdg);
        }
        uint8_t sr = 0xFFu;
        if (!read_status(nvm, &sr)) {
            return false;
        }
        if ((sr & NOR_SR_WIP) == 0u) {
            return true;
        }
    }
    return false;
}

static void cfg_port(const hal_nvm_t *nvm, bool on)
{
    am263x_wr32(nvm->qspi + QSPI_SPI_SWITCH, on ? 0u : QSPI_SWITCH_MMPT_S);
}

static void addr3(uint8_t *p, uint32_t a)
{
    p[0] = (uint8_t)(a >> 16);
    p[1] = (uint8_t)(a >> 8);
    p[2] = (uint8_t)a;
}

static bool in_range(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, uint32_t len)
{
    return block < nvm->blocks && offset <= nvm->block_size && len <= nvm->block_size - offset;
}

/* ---- hal/nvm.h */
uint32_t hal_nvm_blocks(const hal_nvm_t *nvm)
{
    return nvm->blocks;
}

uint32_t hal_nvm_block_size(const hal_nvm_t *nvm)
{
    return nvm->block_size;
}

const hal_nvm_geometry_t *hal_nvm_geometry(const hal_nvm_t *nvm)
{
    return nvm->geom;
}

uint32_t hal_nvm_write_unit(const hal_nvm_t *nvm)
{
    (void)nvm;
    return AM263X_NVM_UNIT;
}

bool hal_nvm_erase(hal_nvm_t *nvm, uint32_t block)
{
    if (block >= nvm->blocks) {
        return false;
    }
    const uint32_t a = nvm->base + block * nvm->block_size;
    uint8_t f[4] = {nvm->erase_cmd, 0u, 0u, 0u};
    addr3(&f[1], a);
    cfg_port(nvm, true);
    bool ok = write_enable(nvm) && qspi_frame(nvm, f, 4u, NULL, 0u) && wait_ready(nvm, nvm->erase_polls);
    cfg_port(nvm, false);
    /* erased means every byte reads 0xFF: an erase the part ignored or sized differently from
     * the map (a P4E in a 64 KiB sector) leaves old data, and the write's AND would keep it */
    for (uint32_t k = 0u; ok && k < nvm->block_size; k += 4u) {
        ok = am263x_rd32(nvm->window + a + k) == 0xFFFFFFFFu;
    }
    return ok;
}

bool hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (!in_range(nvm, block, offset, len) || offset % AM263X_NVM_UNIT != 0u || len % AM263X_NVM_UNIT != 0u) {
        return false;
    }
    const uint8_t *src = (const uint8_t *)data;
    for (uint32_t k = 0u; k < len; k += AM263X_NVM_UNIT) {
        const uint32_t a = nvm->base + block * nvm->block_size + offset + k;
        const uintptr_t w = nvm->window + a;
        uint8_t expect[AM263X_NVM_UNIT];
        uint8_t f[4u + AM263X_NVM_UNIT];
        f[0] = NOR_CMD_PP;
        addr3(&f[1], a);
        for (uint32_t j = 0u; j < AM263X_NVM_UNIT; ++j) {
            f[4u + j] = src[k + j];
            expect[j] = (uint8_t)(am263x_rd8(w + j) & src[k + j]);   /* flash: old AND new */
        }
        /* a unit is 8-aligned, so it never crosses a 256-byte page */
        cfg_port(nvm, true);
        const bool ok = write_enable(nvm) && qspi_frame(nvm, f, sizeof f, NULL, 0u) &&
                        wait_ready(nvm, nvm->program_polls);
        cfg_port(nvm, false);
        if (!ok) {
            return false;
        }
        for (uint32_t j = 0u; j < AM263X_NVM_UNIT; ++j) {
            if (am263x_rd8(w + j) != expect[j]) {
                return false;
            }
        }
    }
    return true;
}

bool hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len)
{
    if (!in_range(nvm, block, offset, len)) {
        return false;
    }
    const uintptr_t src = nvm->window + nvm->base + block * nvm->block_size + offset;
    uint8_t *dst = (uint8_t *)data;
    for (uint32_t k = 0u; k < len; ++k) {
        dst[k] = am263x_rd8(src + k);
    }
    return true;
}
