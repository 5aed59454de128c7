/* The drive's configuration as stored records: the parameter set and the estimator's model (with
 * its flux map), each a sequence of little-endian 32-bit words closed by a CRC-32, so that an
 * image finds its configuration in non-volatile memory at boot and a tool (the simulator's
 * processor-in-the-loop, later the CANopen store 0x1010) writes one the firmware reads
 * bit-for-bit. Versioned: a record from another parameter table (mc_params_table_hash) or
 * format is refused, never half applied. The power-cut-safe two-copy store on hal_nvm is built
 * on these records by the CANopen issue.
 *
 * Parameter record: MC_STORE_MAGIC_PARAMS, MC_STORE_VERSION, table hash, n, then n pairs
 *   (id | MC_STORE_AUTO if derived by its rule, value as IEEE-754 bits), CRC-32.
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
#define MC_STORE_VERSION      1u
#define MC_STORE_AUTO         0x80000000u
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
    MC_STORE_OTHER_TABLE,  /* written for another parameter table                     */
    MC_STORE_BAD_SIZE,     /* a count beyond the table, the map or the buffer         */
    MC_STORE_BAD_CRC,
    MC_STORE_BAD_VALUE,    /* a parameter the table refuses (id, range)               */
    MC_STORE_MAP_MISMATCH  /* view: the map in place is not the record's               */
} mc_store_status_t;

uint32_t mc_crc32(const uint8_t *data, size_t n);

/* Write the record into buf (cap bytes); returns its length, 0 if cap is too small. */
size_t mc_store_params_encode(const mc_params_t *p, uint8_t *buf, size_t cap);
size_t mc_store_model_encode(const mc_est_model_t *m, uint8_t *buf, size_t cap);
/* Read a record of at most n bytes. params: starts from the defaults, then each stored value
 * through mc_param_set (range-checked with the table's limits). model: map_out receives the map (its storage is the
 * caller's), m->map points to it if the record has one. Nothing is changed on a failure. */
mc_store_status_t mc_store_params_decode(const uint8_t *buf, size_t n, mc_params_t *p);
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
