/* Host port: NVM with flash semantics, an erase map and scheduled power cuts (hal/nvm.h,
 * hal_host/host.h). */
#include <string.h>

#include "hal_host/host.h"

static const hal_nvm_region_t uniform4k_regions[1] = {{0u, HAL_HOST_NVM_BLOCK_SIZE, HAL_HOST_NVM_BLOCKS, 0u}};
const hal_nvm_geometry_t hal_host_nvm_uniform4k = {HAL_HOST_NVM_BLOCKS * HAL_HOST_NVM_BLOCK_SIZE, 256u, 1u,
                                                   uniform4k_regions};
/* S25FL128S, 64 KiB sectors, parameter sectors at the bottom (TBPARM = 0): the facts and their
 * sources in hal/am263x/include/am263x/port.h (am263x_s25fl128s), commands P4E 0x20 / SE 0xD8. */
static const hal_nvm_region_t s25fl128s_regions[2] = {
    {0x000000u, 0x1000u, 32u, 0x20u},
    {0x020000u, 0x10000u, 254u, 0xD8u},
};
const hal_nvm_geometry_t hal_host_nvm_s25fl128s = {0x1000000u, 256u, 2u, s25fl128s_regions};

bool hal_host_nvm_init_geom(hal_nvm_t *nvm, const hal_nvm_geometry_t *geom, uint32_t base, uint32_t blocks)
{
    const hal_nvm_region_t *r = hal_nvm_region_at(geom, base);
    if (r == NULL || blocks == 0u || (base - r->start) % r->sector_size != 0u ||
        blocks > HAL_HOST_NVM_CAP / r->sector_size || (base - r->start) / r->sector_size + blocks > r->count) {
        return false;
    }
    memset(nvm->mem, 0xFF, sizeof nvm->mem);
    nvm->geom = geom;
    nvm->base = base;
    nvm->block_size = r->sector_size;
    nvm->blocks = blocks;
    nvm->erase_size = r->sector_size;
    nvm->steps = 0u;
    nvm->cut_at = 0u;
    nvm->dead = false;
    nvm->rng = 0x9E3779B9u;
    return true;
}

void hal_host_nvm_init(hal_nvm_t *nvm)
{
    (void)hal_host_nvm_init_geom(nvm, &hal_host_nvm_uniform4k, 0u, HAL_HOST_NVM_BLOCKS);
}

uint32_t hal_host_nvm_bytes(const hal_nvm_t *nvm)
{
    return nvm->blocks * nvm->block_size;
}

void hal_host_nvm_cut_at(hal_nvm_t *nvm, uint32_t step)
{
    nvm->cut_at = step;
}

void hal_host_nvm_power_on(hal_nvm_t *nvm)
{
    nvm->dead = false;
    nvm->cut_at = 0u;
}

static uint8_t noise(hal_nvm_t *nvm)
{
    nvm->rng ^= nvm->rng << 13;   /* xorshift32 */
    nvm->rng ^= nvm->rng >> 17;
    nvm->rng ^= nvm->rng << 5;
    return (uint8_t)(nvm->rng >> 24);
}

/* the next step; true when the power fails in it */
static bool step_cut(hal_nvm_t *nvm)
{
    nvm->steps++;
    if (nvm->cut_at != 0u && nvm->steps == nvm->cut_at) {
        nvm->dead = true;
        return true;
    }
    return false;
}

uint32_t hal_nvm_blocks(const hal_nvm_t *nvm)
{
    return nvm->blocks;
}

uint32_t hal_nvm_block_size(const hal_nvm_t *nvm)
{
    return nvm->block_size;
}

uint32_t hal_nvm_write_unit(const hal_nvm_t *nvm)
{
    (void)nvm;
    return HAL_HOST_NVM_WRITE_UNIT;
}

const hal_nvm_geometry_t *hal_nvm_geometry(const hal_nvm_t *nvm)
{
    return nvm->geom;
}

static bool range_ok(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, uint32_t len)
{
    return block < nvm->blocks && offset <= nvm->block_size && len <= nvm->block_size - offset;
}

/* The device's answer to an erase of `size` bytes at device offset a: the part erases the sector
 * holding a only when size is that region's sector size (its own command); any other erase (a
 * 4 KiB P4E in a 64 KiB region) changes nothing. cut: the sector left scrambled (partly erased).
 * Only the part of the sector the model holds is touched. */
static void device_erase(hal_nvm_t *nvm, uint32_t a, uint32_t size, bool cut)
{
    const hal_nvm_region_t *r = hal_nvm_region_at(nvm->geom, a);
    if (r == NULL || size != r->sector_size) {
        return;
    }
    const uint32_t s = a - (a - r->start) % size;
    for (uint32_t k = 0u; k < size; ++k) {
        if (s + k >= nvm->base && s + k - nvm->base < HAL_HOST_NVM_CAP) {
            uint8_t *b = &nvm->mem[s + k - nvm->base];
            *b = cut ? (uint8_t)(*b | noise(nvm)) : 0xFFu;
        }
    }
}

bool hal_nvm_erase(hal_nvm_t *nvm, uint32_t block)
{
    if (nvm->dead || block >= nvm->blocks) {
        return false;
    }
    const uint32_t at = block * nvm->block_size;
    if (step_cut(nvm)) {
        device_erase(nvm, nvm->base + at, nvm->erase_size, true);
        return false;
    }
    device_erase(nvm, nvm->base + at, nvm->erase_size, false);
    /* the layer's check, as on the target: an erase that did not erase the block is an error */
    for (uint32_t k = 0u; k < nvm->block_size; ++k) {
        if (nvm->mem[at + k] != 0xFFu) {
            return false;
        }
    }
    return true;
}

bool hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (nvm->dead || data == 0 || !range_ok(nvm, block, offset, len) || offset % HAL_HOST_NVM_WRITE_UNIT != 0u ||
        len % HAL_HOST_NVM_WRITE_UNIT != 0u) {
        return false;
    }
    const uint8_t *src = (const uint8_t *)data;
    for (uint32_t u = 0; u < len; u += HAL_HOST_NVM_WRITE_UNIT) {
        uint8_t *dst = &nvm->mem[block * nvm->block_size + offset + u];
        const bool cut = step_cut(nvm);
        for (uint32_t k = 0; k < HAL_HOST_NVM_WRITE_UNIT; ++k) {
            /* flash: a write only clears bits; cut, only a random part of them */
            const uint8_t clear = (uint8_t)~src[u + k];
            dst[k] &= (uint8_t)~(cut ? (uint8_t)(clear & noise(nvm)) : clear);
        }
        if (cut) {
            return false;
        }
    }
    return true;
}

bool hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len)
{
    if (nvm->dead || data == 0 || !range_ok(nvm, block, offset, len)) {
        return false;
    }
    memcpy(data, &nvm->mem[block * nvm->block_size + offset], len);
    return true;
}
