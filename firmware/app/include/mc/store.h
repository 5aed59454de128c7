/* The drive's configuration as stored records: the parameter set and the estimator's model (with
 * its flux map), each a sequence of little-endian 32-bit words closed by a CRC-32, so that an
 * image finds its configuration in non-volatile memory at boot and a tool (the simulator's
 * processor-in-the-loop, the CANopen store 0x1010) writes one the firmware reads bit-for-bit.
 * The power-cut-safe two-copy store on hal_nvm (mc/param_store.h) is built on these records.
 *
 * Parameter record, version 2: MC_STORE_MAGIC_PARAMS, MC_STORE_PARAMS_VERSION, the writer's table
 *   hash (mc_params_table_hash; information only), n, then n pairs (key, value as IEEE-754 bits
 *   as mc_param_get gives it), CRC-32. The key names the parameter by its dotted name and type
 *   (mc_store_param_key), not by its position, so that a set survives a firmware update whose
 *   table added, removed, reordered or re-ranged parameters: on a read every stored value whose
 *   name and type this table still has and whose value passes this table's range and type
 *   checks is kept; a parameter the record does not hold keeps its default (its rule, "auto", as
 *   usual); a value of another type or now out of range keeps the default and is counted in the
 *   report (mc_store_report_t: the caller tells the user); a name this table lacks is skipped.
 *   A damaged record (CRC, sizes) is still refused whole. Cost: one name hash per value when the
 *   table is unchanged (each value at its position); a migrated set searches the table per value
 *   (n^2 name hashes: about 2 x 10^5 byte steps for 95 parameters), at boot, outside the ISR.
 * Parameter record, version 1 (main at 5265cfe and before): the same but keyed by the whole
 *   table's hash and (id | 0x80000000 if derived, value) by position; a record of the table of
 *   5265cfe (MC_STORE_V1_TABLE) is read through the frozen list of that table's keys (store.c), so
 *   it is migrated by name as well; one of an older table is refused, as it was. Only the NVM
 *   store reads version 1.
 * Model record: MC_STORE_MAGIC_MODEL, MC_STORE_VERSION, rs, ld, lq, psi_pm (NaN: the motor.*
 *   parameter), has_map, then if has_map: n_d, n_q, id0, did, iq0, diq, psi_d[n_d n_q],
 *   psi_q[n_d n_q]; CRC-32. */
#ifndef MC_STORE_H
#define MC_STORE_H
#include <stddef.h>
#include <stdint.h>
#include "mc/drive.h"

#define MC_STORE_MAGIC_PARAMS 0x4250434Du   /* "MCPB" */
#define MC_STORE_MAGIC_MODEL  0x424D434Du   /* "MCMB" */
#define MC_STORE_VERSION      1u           /* of the model record */
#define MC_STORE_PARAMS_VERSION 2u         /* of the parameter record */
/* A parameter's key: bits 31..4 the upper 28 bits of FNV-1a-32 over its dotted name, bit 3 set if
 * the value is derived by its rule (the value is then not used), bits 2..0 its mc_param_type_t.
 * 28 bits keep an entry at two words, the size of the version 1 record, so that the same maps
 * fit; a unit test checks that no two names of the table share them. */
#define MC_STORE_KEY_NAME     0xFFFFFFF0u
#define MC_STORE_KEY_AUTO     0x00000008u
#define MC_STORE_KEY_TYPE     0x00000007u
/* Version 1 records: the derived mark on the id, the table they were written by, its size. */
#define MC_STORE_V1_AUTO      0x80000000u
#define MC_STORE_V1_TABLE     0xF05FD3E5u
#define MC_STORE_V1_COUNT     95u
/* Upper bounds of the record sizes [bytes]. */
#define MC_STORE_PARAMS_MAX   (4u * (5u + 2u * (uint32_t)MC_PARAM_COUNT))
#define MC_STORE_MODEL_MAX    (4u * (14u + 2u * MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX))

/* The image's configuration area: a flash section (.mc_config) holding a parameter record at
 * offset 0 and a model record at MC_CONFIG_MODEL_OFFSET, erased (0xFF) in a fresh build, and the
 * model's flux map once more in its own layout (mc_flux_map_t), so that the image uses it where it
 * lies instead of copying 13 KB into RAM (mc_store_model_view checks it against the record). A
 * tool writes the motor's configuration into it before flashing (the processor-in-the-loop does
 * so in the emulated flash before reset); the image boots with it, else with the defaults. */
#define MC_CONFIG_MODEL_OFFSET  4096u
#define MC_CONFIG_RECORDS_SIZE  (MC_CONFIG_MODEL_OFFSET + 14336u)
#define MC_CONFIG_MAP_OFFSET    MC_CONFIG_RECORDS_SIZE
#define MC_CONFIG_AREA_SIZE     (MC_CONFIG_MAP_OFFSET + (uint32_t)sizeof(mc_flux_map_t))

typedef struct {
    uint8_t records[MC_CONFIG_RECORDS_SIZE];
    mc_flux_map_t map;
} mc_config_area_t;

typedef enum {
    MC_STORE_OK = 0,
    MC_STORE_EMPTY,        /* erased memory (0xFFFFFFFF magic): nothing stored        */
    MC_STORE_BAD_MAGIC,
    MC_STORE_BAD_VERSION,
    MC_STORE_OTHER_TABLE,  /* (no longer returned: another table's set is read by name) */
    MC_STORE_BAD_SIZE,     /* a count beyond the table, the map or the buffer         */
    MC_STORE_BAD_CRC,
    MC_STORE_BAD_VALUE,    /* (no longer returned: such a value keeps its default)    */
    MC_STORE_MAP_MISMATCH  /* view: the map in place is not the record's               */
} mc_store_status_t;

/* Why a stored value was not taken (mc_store_report_t.reason). */
typedef enum { MC_STORE_DROP_NONE = 0, MC_STORE_DROP_TYPE, MC_STORE_DROP_RANGE } mc_store_drop_t;

/* What a read of a parameter record did with the stored values. */
typedef struct {
    uint16_t kept;           /* stored values (or derived marks) in force                     */
    uint16_t dropped;        /* stored values at their defaults: another type, or out of range */
    uint16_t unknown;        /* stored names this table does not have: skipped                 */
    int16_t first;           /* the first dropped one's parameter id, -1: none                 */
    uint8_t reason;          /* its mc_store_drop_t                                            */
    bool other_table;        /* written by another table version (a record of version 1, or
                                another table hash): migrated by name                          */
} mc_store_report_t;

uint32_t mc_crc32(const uint8_t *data, size_t n);
/* The key of parameter id (MC_STORE_KEY_*, the derived mark clear). */
uint32_t mc_store_param_key(int id);
/* The key version 1 stored at position pos (its frozen table); 0 if pos >= MC_STORE_V1_COUNT. */
uint32_t mc_store_v1_key(uint32_t pos);
void mc_store_report_clear(mc_store_report_t *rep);
/* One stored value into q (defaulted by the caller) by its key, as the record's read does (see
 * above), counted in rep; hint: the id to try first (the position it was written at). */
void mc_store_param_apply(mc_params_t *q, uint32_t key, uint32_t value, uint32_t hint, mc_store_report_t *rep);

/* Write the record into buf (cap bytes); returns its length, 0 if cap is too small. */
size_t mc_store_params_encode(const mc_params_t *p, uint8_t *buf, size_t cap);
size_t mc_store_model_encode(const mc_est_model_t *m, uint8_t *buf, size_t cap);
/* Read a record of at most n bytes. params (version 2): starts from the defaults, then each stored
 * value by mc_store_param_apply; rep (may be NULL) says what was kept. model: map_out receives the
 * map (its storage is the caller's), m->map points to it if the record has one. Nothing is changed
 * on a failure. */
mc_store_status_t mc_store_params_decode(const uint8_t *buf, size_t n, mc_params_t *p, mc_store_report_t *rep);
mc_store_status_t mc_store_model_decode(const uint8_t *buf, size_t n, mc_est_model_t *m, mc_flux_map_t *map_out);
/* The same checks, but the map is not copied: *map_in_place must hold exactly the record's map
 * (dimensions, grid and every cell bit for bit; cells beyond n_d n_q are not looked at), and
 * m->map points to it (MC_STORE_MAP_MISMATCH otherwise). A record without a map sets m->map =
 * NULL and does not read map_in_place. For an image whose map lies in flash. */
mc_store_status_t mc_store_model_view(const uint8_t *buf, size_t n, mc_est_model_t *m,
                                      const mc_flux_map_t *map_in_place);
const char *mc_store_status_name(mc_store_status_t s);

#ifndef __cplusplus
_Static_assert(MC_STORE_PARAMS_MAX <= MC_CONFIG_MODEL_OFFSET, "parameter record too large");
_Static_assert(MC_CONFIG_MODEL_OFFSET + MC_STORE_MODEL_MAX <= MC_CONFIG_RECORDS_SIZE, "model record too large");
/* the map's layout is the same on the host (the tool that writes it) and the targets */
_Static_assert(sizeof(mc_flux_map_t) == 4u * (6u + 2u * MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX), "map layout");
_Static_assert(sizeof(mc_config_area_t) == MC_CONFIG_AREA_SIZE, "area layout");
#endif

#endif
