/* The parameter store on hal_nvm (CiA 301 0x1010 store / 0x1011 restore, for the CANopen layer):
 * the whole parameter set (mc/store.h's parameter record) kept in two copies so that a power cut
 * at any point of a save never loses the last committed set.
 *
 * Layout: the NVM's blocks split into two slots (slot 0: the first half of the blocks, slot 1:
 * the second; each at least one block). A copy in a slot:
 *   offset 0   header, 4 words: MC_NVSTORE_MAGIC, MC_NVSTORE_FORMAT, sequence, record length
 *   offset 16  header CRC-32 (of the 16 bytes), padded to the write unit
 *   offset H   the commit marker: one write unit of MC_NVSTORE_COMMIT bytes, written LAST
 *   offset H+U the parameter record (its own CRC-32 inside), padded to the write unit
 * A save erases the slot NOT holding the newest committed copy, writes the record, the header,
 * reads both back, and only then the marker, with sequence = newest + 1. A load takes the
 * committed copy with the highest sequence whose header and record check; the other copy is the
 * fall-back. Because the slot holding the newest committed copy is never touched by a save, a
 * cut (in the erase, in any write unit, in the marker itself: a half-programmed marker is not the
 * marker) leaves that copy whole; only a completed marker makes the new copy count.
 *
 * The machine model and its flux map are not stored here: they come with the image (its
 * configuration area, mcsim image-config) or, later, from identification. A save runs in the
 * background with bounded work per NVM call but is not split across calls (the outputs are off:
 * 0x1010 is refused while running); each save is 1 erase + (record + header + marker) / unit
 * writes. */
#ifndef MC_NVSTORE_H
#define MC_NVSTORE_H
#include <stddef.h>
#include <stdint.h>
#include "hal/nvm.h"
#include "mc/params.h"
#include "mc/store.h"

#define MC_NVSTORE_MAGIC  0x534E434Du   /* "MCNS" */
#define MC_NVSTORE_FORMAT 1u
#define MC_NVSTORE_COMMIT 0x5Au         /* every byte of the marker unit */
/* The work buffer a save or load needs [bytes]: a save holds the new record while it reads the
 * stored one back to find the slot it must not touch (two records and a copy's head). */
#define MC_NVSTORE_WORK   (2u * MC_STORE_PARAMS_MAX + 192u)

typedef enum {
    MC_NVSTORE_OK = 0,        /* the newest committed copy                                   */
    MC_NVSTORE_EMPTY,         /* no committed copy (never saved, or restored to defaults)      */
    MC_NVSTORE_FELL_BACK,     /* the newest committed copy was corrupt: the older one is used  */
    MC_NVSTORE_CORRUPT,       /* committed copies exist but none checks: defaults              */
    MC_NVSTORE_NVM_ERROR,     /* the device refused a call (power lost, bad geometry)          */
    MC_NVSTORE_TOO_SMALL,     /* fewer than two blocks, or a block smaller than a copy         */
    MC_NVSTORE_BAD_ARGS       /* NULL, a work buffer below MC_NVSTORE_WORK, a unit above 64 B  */
} mc_nvstore_status_t;

/* Store p (as given: "auto" entries stay "auto"). */
mc_nvstore_status_t mc_nvstore_save(hal_nvm_t *nvm, const mc_params_t *p, uint8_t *work, size_t work_len);
/* The stored set into p (p unchanged unless OK or FELL_BACK); seq (may be NULL): its sequence. */
mc_nvstore_status_t mc_nvstore_load(const hal_nvm_t *nvm, mc_params_t *p, uint8_t *work, size_t work_len,
                                    uint32_t *seq);
/* 0x1011: a committed "defaults" copy (record length 0) in the free slot, so that a cut leaves
 * either the last committed set or the defaults, never an older set; load then reports EMPTY. */
mc_nvstore_status_t mc_nvstore_restore_defaults(hal_nvm_t *nvm, uint8_t *work, size_t work_len);
const char *mc_nvstore_status_name(mc_nvstore_status_t s);

#endif
