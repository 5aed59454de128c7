/* Non-volatile memory interface for the parameter store (CiA 301 0x1010 / 0x1011): a few
 * equal blocks with flash semantics, so that a store can be made power-cut safe by the layer
 * above (two copies, a version and a CRC, written in an order that always leaves one whole):
 *   - erase sets a whole block to 0xFF;
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

uint32_t hal_nvm_blocks(const hal_nvm_t *nvm);       /* number of blocks */
uint32_t hal_nvm_block_size(const hal_nvm_t *nvm);   /* bytes per block (the erase unit) */
uint32_t hal_nvm_write_unit(const hal_nvm_t *nvm);   /* offsets and lengths of writes: multiples */
bool hal_nvm_erase(hal_nvm_t *nvm, uint32_t block);
bool hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len);
bool hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len);

#endif
