/* Host port: NVM with flash semantics and scheduled power cuts (hal/nvm.h, hal_host/host.h). */
#include <string.h>

#include "hal_host/host.h"

void hal_host_nvm_init(hal_nvm_t *nvm)
{
    memset(nvm->mem, 0xFF, sizeof nvm->mem);
    nvm->steps = 0u;
    nvm->cut_at = 0u;
    nvm->dead = false;
    nvm->rng = 0x9E3779B9u;
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
    (void)nvm;
    return HAL_HOST_NVM_BLOCKS;
}

uint32_t hal_nvm_block_size(const hal_nvm_t *nvm)
{
    (void)nvm;
    return HAL_HOST_NVM_BLOCK_SIZE;
}

uint32_t hal_nvm_write_unit(const hal_nvm_t *nvm)
{
    (void)nvm;
    return HAL_HOST_NVM_WRITE_UNIT;
}

static bool range_ok(uint32_t block, uint32_t offset, uint32_t len)
{
    return block < HAL_HOST_NVM_BLOCKS && offset <= HAL_HOST_NVM_BLOCK_SIZE &&
           len <= HAL_HOST_NVM_BLOCK_SIZE - offset;
}

bool hal_nvm_erase(hal_nvm_t *nvm, uint32_t block)
{
    if (nvm->dead || block >= HAL_HOST_NVM_BLOCKS) {
        return false;
    }
    if (step_cut(nvm)) {
        for (uint32_t k = 0; k < HAL_HOST_NVM_BLOCK_SIZE; ++k) {
            nvm->mem[block][k] |= noise(nvm);   /* partly erased */
        }
        return false;
    }
    memset(nvm->mem[block], 0xFF, HAL_HOST_NVM_BLOCK_SIZE);
    return true;
}

bool hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (nvm->dead || data == 0 || !range_ok(block, offset, len) || offset % HAL_HOST_NVM_WRITE_UNIT != 0u ||
        len % HAL_HOST_NVM_WRITE_UNIT != 0u) {
        return false;
    }
    const uint8_t *src = (const uint8_t *)data;
    for (uint32_t u = 0; u < len; u += HAL_HOST_NVM_WRITE_UNIT) {
        uint8_t *dst = &nvm->mem[block][offset + u];
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
    if (nvm->dead || data == 0 || !range_ok(block, offset, len)) {
        return false;
    }
    memcpy(data, &nvm->mem[block][offset], len);
    return true;
}
