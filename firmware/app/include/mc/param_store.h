/* The power-cut-safe configuration store on hal_nvm, for CiA 301 0x1010 (store) and 0x1011
 * (restore defaults), called by the CANopen layer: the drive's configuration (mc_drive_cfg_t: the
 * parameter record and the model record with its flux map, mc/store.h) kept in two copies so
 * that a power cut at any point of a save or an erase never loses the last committed set: after
 * power-on a load returns that set or the new one, whole and bit-identical, never a mix.
 *
 * Slots. The device's blocks are split in two halves; slot s starts at block s * (blocks / 2)
 * and uses as many blocks as the largest copy needs (MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX
 * plus the header), at most blocks / 2 (mc_pstore_geometry tells). Geometry comes from
 * hal_nvm_blocks / block_size / write_unit at run time; the write unit must be a power of two.
 *
 * A copy, at byte offsets from its slot's first block (U: write unit, A = max(U, 8)):
 *   0      header, 8 little-endian words: MC_PSTORE_MAGIC, MC_PSTORE_FORMAT, sequence, flags
 *          (MC_PSTORE_FLAG_*), parameter record length, model record length, CRC-32 of the
 *          payload's words without the records' own CRC words (format 2; format 1, still read,
 *          had them in, which made it depend on the records' lengths only), CRC-32 of the 7
 *          words before; padded with 0xFF to H = round_up(32, U)
 *   H      the commit marker: A bytes 0x5A 0xA5 0x5A ..., written LAST (0xFF until then)
 *   H + A  the payload: the parameter record then the model record, exactly as
 *          mc_store_params_encode / mc_store_model_encode write them (each closed by its own
 *          CRC-32), padded with 0xFF to A
 * A defaults copy (flag DEFAULTS, both lengths 0, no payload) is what mc_pstore_erase commits.
 *
 * Save: finds the copy a load would return (the same checks), then erases the OTHER slot (its
 * first block, holding header and marker, first), streams the payload into it, writes the header,
 * reads everything back (bit-exact against a second encoding, then the full load checks) and
 * only then writes the marker, with sequence = newest header's + 1. Since the slot a load takes
 * is never written, a cut anywhere (an erase, a payload unit, the header, the marker: a
 * half-programmed marker does not match) leaves that copy whole, and only a complete marker
 * makes the new copy count.
 * Load: among the slots with a complete marker, the newest (sequence, compared modulo 2^32; a
 * marked copy whose header does not check counts as possibly newest) whose header checks, whose
 * payload CRC matches and whose two records decode (versions, sizes, record CRCs, map size); else
 * the other one (MC_PSTORE_FELL_BACK); else MC_PSTORE_CORRUPT; no marked copy: MC_PSTORE_EMPTY.
 * The parameter record is read by name (mc/store.h, also its version 1 written up to 5265cfe):
 * a set written by another table version loads with every value this table still takes and the
 * others at their defaults (MC_PSTORE_PARTIAL if any stored value was refused). A save commits
 * only a set that reads back whole (every value kept).
 *
 * Too small a device. A copy must hold the parameter record and the model record without its
 * map, else nothing is stored (MC_PSTORE_TOO_LARGE). A map that does not fit in a slot is left
 * out: the parameters and the model's scalars are committed without it, the save returns
 * MC_PSTORE_MAP_DROPPED, and a load returns the set with est.map = NULL and info.map_dropped.
 * The host port (4 x 4 KiB: 2 blocks per slot) holds maps up to 915 points (30 x 30), not the
 * largest 41 x 41 map; the AM263x (8 x 4 KiB) and generic (8 x 16 KiB) ports hold any map.
 *
 * RAM: the caller's work buffer, at least MC_PSTORE_WORK_MIN bytes and 2 write units (records
 * are streamed through it: more only means fewer NVM calls), plus about 1 KB of stack at the
 * deepest (Cortex-M4, -Os; 0.4 KB of it a scratch mc_params_t to check a stored set the way a
 * load does) and the port's read/write. No heap, no globals, no state between calls. A save or
 * an erase is meant for the background loop with the outputs off (the caller refuses 0x1010 /
 * 0x1011 while running): its work is bounded by the copy's size (a few block erases, one write
 * per work buffer, a few passes of reads and CRC over the copy) but is not split across calls.
 * Every loop is bounded by the geometry and the record lengths, and a failing NVM call ends the
 * operation at once (no retries). */
#ifndef MC_PARAM_STORE_H
#define MC_PARAM_STORE_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "hal/nvm.h"
#include "mc/drive.h"
#include "mc/store.h"

#define MC_PSTORE_MAGIC         0x5350434Du   /* "MCPS" */
#define MC_PSTORE_FORMAT        2u   /* 2: the records' CRC words are not in the payload CRC; 1 is read */
#define MC_PSTORE_FLAG_DEFAULTS 1u            /* restored to defaults: no records */
#define MC_PSTORE_FLAG_NO_MAP   2u            /* the map was dropped: it did not fit */
#define MC_PSTORE_WORK_MIN      64u           /* [bytes], and at least 2 write units */

typedef enum {
    MC_PSTORE_OK = 0,        /* load: the newest committed copy; save/erase: committed        */
    MC_PSTORE_EMPTY,         /* load: nothing committed, or restored to defaults: use defaults */
    MC_PSTORE_FELL_BACK,     /* load: a newer committed copy is corrupt, the older one returned */
    MC_PSTORE_CORRUPT,       /* load: committed copies exist but none checks: use defaults      */
    MC_PSTORE_NVM_ERROR,     /* a call failed, or a read-back differed: nothing committed      */
    MC_PSTORE_TOO_LARGE,     /* a copy cannot hold the set even without its map: nothing written */
    MC_PSTORE_BAD_ARGS,      /* NULL, work too small, a bad map, a set a load would refuse, a
                                write unit not a power of two                                   */
    MC_PSTORE_MAP_DROPPED,   /* save: committed WITHOUT the flux map (a slot cannot hold it);
                                geometry: the largest map does not fit                         */
    MC_PSTORE_PARTIAL        /* load: the stored set (as OK; or the older copy), but written by
                                another table version and some of its values keep their defaults
                                (another type, or out of this table's range): info.params says
                                how many and the first one                                     */
} mc_pstore_status_t;

/* What a load returned or a save wrote (each pointer argument of this type may be NULL). */
typedef struct {
    int slot;                /* 0 or 1; -1: none                                        */
    uint32_t seq;            /* the copy's sequence number (0: none)                    */
    bool defaults;           /* the copy is a restore-to-defaults copy                  */
    bool map_dropped;        /* the set was saved without its map                       */
    bool fell_back;          /* a newer committed copy did not check                    */
    mc_store_report_t params;/* load: what the parameter record gave (kept, dropped, ...)  */
} mc_pstore_info_t;

typedef struct {
    uint32_t slot_first[2];  /* first block of each slot                                */
    uint32_t slot_blocks;    /* blocks a slot uses                                      */
    uint32_t payload_max;    /* record bytes a copy holds                               */
    uint32_t map_cells_max;  /* the largest map (n_d * n_q) stored with the set          */
} mc_pstore_geom_t;

/* The layout on this device: OK if the largest set fits, MAP_DROPPED if only maps up to
 * map_cells_max do, TOO_LARGE if not even the set without a map does, BAD_ARGS. */
mc_pstore_status_t mc_pstore_geometry(const hal_nvm_t *nvm, mc_pstore_geom_t *geom);
/* 0x1010: commit cfg->p and cfg->est (with *cfg->est.map if it has one and it fits) as the new
 * newest copy. OK or MAP_DROPPED: committed; any other status: the stored sets are as before
 * (the older copy may have been overwritten by an uncommitted one, never the one a load takes). */
mc_pstore_status_t mc_pstore_save(hal_nvm_t *nvm, const mc_drive_cfg_t *cfg, uint8_t *work, size_t work_len,
                                  mc_pstore_info_t *info);
/* The stored set into cfg (OK, FELL_BACK, PARTIAL; cfg is unchanged on any other status): cfg->p
 * (matched by name and type, mc/store.h: a set from another table version keeps every value this
 * table still takes), and
 * cfg->est with est.map = map_out if the set has a map, else NULL. map_out (the caller's storage,
 * it must outlive the drive) is scratch unless est.map points to it; NULL: a stored map is
 * checked (CRC, sizes) but not loaded and est.map is NULL (an image whose RAM cannot hold a map
 * keeps the one of its flash configuration area). */
mc_pstore_status_t mc_pstore_load(const hal_nvm_t *nvm, mc_drive_cfg_t *cfg, mc_flux_map_t *map_out, uint8_t *work,
                                  size_t work_len, mc_pstore_info_t *info);
/* 0x1011: commit a defaults copy into the slot a load does not take, then erase the other slot,
 * so that a later load reports EMPTY and no older set can come back. A cut leaves the last
 * committed set or EMPTY. */
mc_pstore_status_t mc_pstore_erase(hal_nvm_t *nvm, uint8_t *work, size_t work_len);
const char *mc_pstore_status_name(mc_pstore_status_t s);

#endif
