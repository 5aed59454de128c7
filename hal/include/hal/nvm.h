/* Non-volatile memory interface for the parameter store (CiA 301 0x1010 / 0x1011): a few
 * equal blocks with flash semantics, so that a store can be made power-cut safe by the layer
 * above (two copies, a version and a CRC, written in an order that always leaves one whole):
 *   - erase sets a whole block to 0xFF, and checks that it did (a missed or wrong-sized erase
 *     is a false, never a silent success);
 *   - write programs bytes at (block, offset); it can only clear bits (a written 0 stays 0 until
 *     the next erase: the result is old AND new), in units of hal_nvm_write_unit bytes;
 *   - read copies bytes out.
 * Each call is synchronous and bounded (a target with a slow erase splits it in its port). A
 * power cut during an erase or write leaves that block (only that block) in an undefined state;
 * every other block keeps its content. false: bad arguments (block, range, alignment) or the
 * device failed; nothing is guaranteed about the addressed range then. */
#ifndef HAL_NVM_H
#define HAL_NVM_H
#include <stdbool.h>
#include <stdint.h>

typedef struct hal_nvm hal_nvm_t;   /* defined by the port */

/* The device's erase map, as the part has it: regions of equal sectors, ascending and contiguous
 * from device offset 0. A region's sectors can only be erased whole, with the region's own
 * command (a serial NOR's opcode; 0 where the device has no command set, the host model). The
 * port places its blocks in whole sectors of one region: a block is one sector. */
typedef struct {
    uint32_t start;         /* device offset of the region's first sector */
    uint32_t sector_size;   /* bytes (the erase unit in this region) */
    uint32_t count;         /* sectors */
    uint8_t erase_cmd;
} hal_nvm_region_t;
typedef struct {
    uint32_t size;          /* device bytes */
    uint32_t page_size;     /* a program command never crosses a page */
    uint32_t n_regions;
    const hal_nvm_region_t *region;
} hal_nvm_geometry_t;

/* The region holding device offset addr, NULL if none. */
static inline const hal_nvm_region_t *hal_nvm_region_at(const hal_nvm_geometry_t *g, uint32_t addr)
{
    for (uint32_t k = 0u; k < g->n_regions; ++k) {
        const hal_nvm_region_t *r = &g->region[k];
        if (addr >= r->start && (addr - r->start) / r->sector_size < r->count) {
            return r;
        }
    }
    return (const hal_nvm_region_t *)0;
}
const hal_nvm_geometry_t *hal_nvm_geometry(const hal_nvm_t *nvm);   /* the device's map */

uint32_t hal_nvm_blocks(const hal_nvm_t *nvm);       /* number of blocks */
uint32_t hal_nvm_block_size(const hal_nvm_t *nvm);   /* bytes per block (the erase unit) */
uint32_t hal_nvm_write_unit(const hal_nvm_t *nvm);   /* offsets and lengths of writes: multiples */
bool hal_nvm_erase(hal_nvm_t *nvm, uint32_t block);
bool hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len);
bool hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len);

#endif
