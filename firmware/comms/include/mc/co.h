/* CANopen device (CiA 301 + CiA 402) over hal_can: NMT slave with boot-up and heartbeat, an SDO
 * server (expedited and segmented transfer, the standard abort codes), EMCY, four RPDOs and four
 * TPDOs with configurable mapping, the CiA 402 drive profile (mc/cia402.h), the scope
 * (mc/scope.h), 0x1010 / 0x1011 on the power-cut-safe store (mc/param_store.h) and the object
 * dictionary.
 *
 * The object dictionary is defined once (co_objects.h: the communication, CiA 402, scope and
 * device objects; the manufacturer ranges 0x2000 + parameter id and 0x2200 + telemetry channel
 * come from the parameter table and mc/telem_channels.h). The same description answers the SDO
 * server and the PDO mapping (mc_co_od_lookup) and is enumerated by the host generator
 * (tools/co_gen) into the EDS (CiA 306) and the object tables of docs/can.md; the EDS's default
 * values are read from a device initialised like the firmware, so nothing is written twice.
 *
 * No heap, no globals; mc_co_step is called from the background loop with bounded work: at most
 * MC_CO_RX_PER_STEP received frames, one SDO segment per request, the 402 step, at most one
 * message per TPDO, one EMCY per new fault, the heartbeat. A store (0x1010) is the exception: it
 * writes the NVM synchronously and is refused while the outputs are on. */
#ifndef MC_CO_H
#define MC_CO_H
#include <stdbool.h>
#include <stdint.h>
#include "hal/can.h"
#include "hal/nvm.h"
#include "mc/cia402.h"
#include "mc/drive.h"
#include "mc/param_store.h"
#include "mc/scope.h"

#define MC_CO_DEVICE_TYPE  0x00020192u   /* 0x1000: CiA 402 drive profile (402 = 0x192), servo drive */
#define MC_CO_SDO_TIMEOUT_MS 1000u
#define MC_CO_RX_PER_STEP  16u          /* frames taken per mc_co_step */
#define MC_CO_SDO_BUF      32u          /* the longest buffered object (0x1008) */
#define MC_CO_PDO_N        4u           /* RPDOs and TPDOs each */
#define MC_CO_PDO_MAP_N    8u           /* mapping entries per PDO */
#define MC_CO_STORE_WORK   64u          /* the store's work buffer [bytes] */
#define MC_CO_SAVE_SIGNATURE 0x65766173u /* "save" (CiA 301 §7.5.2.13) */
#define MC_CO_LOAD_SIGNATURE 0x64616F6Cu /* "load" (§7.5.2.14) */

/* SDO abort codes (CiA 301 §7.2.4.3.17) */
#define MC_SDO_ABORT_TOGGLE        0x05030000u
#define MC_SDO_ABORT_TIMEOUT       0x05040000u
#define MC_SDO_ABORT_CS            0x05040001u
#define MC_SDO_ABORT_WRITE_ONLY    0x06010001u
#define MC_SDO_ABORT_READ_ONLY     0x06010002u
#define MC_SDO_ABORT_NO_OBJECT     0x06020000u
#define MC_SDO_ABORT_NOT_MAPPABLE  0x06040041u
#define MC_SDO_ABORT_PDO_LENGTH    0x06040042u
#define MC_SDO_ABORT_INCOMPATIBLE  0x06040043u
#define MC_SDO_ABORT_HW            0x06060000u
#define MC_SDO_ABORT_LENGTH        0x06070010u
#define MC_SDO_ABORT_LENGTH_HIGH   0x06070012u
#define MC_SDO_ABORT_LENGTH_LOW    0x06070013u
#define MC_SDO_ABORT_NO_SUB        0x06090011u
#define MC_SDO_ABORT_VALUE         0x06090030u
#define MC_SDO_ABORT_VALUE_HIGH    0x06090031u
#define MC_SDO_ABORT_VALUE_LOW     0x06090032u
#define MC_SDO_ABORT_GENERAL       0x08000000u
#define MC_SDO_ABORT_STORE         0x08000020u
#define MC_SDO_ABORT_STATE         0x08000022u
#define MC_SDO_ABORT_NO_DATA       0x08000024u

/* EMCY codes of the device itself (CiA 301 Table 21) */
#define MC_EMCY_PARAMS_LOST        0x6310u   /* the stored set was corrupt: defaults in force; or
                                                a set of another table version kept some values
                                                at their defaults (mc/store.h)               */
#define MC_EMCY_NVM                0x5530u   /* data storage (a store failed)                 */
#define MC_EMCY_PDO_LENGTH         0x8210u   /* RPDO shorter than its mapping                 */

typedef enum {
    MC_NMT_INITIALISING = 0x00,
    MC_NMT_STOPPED = 0x04,
    MC_NMT_OPERATIONAL = 0x05,
    MC_NMT_PRE_OPERATIONAL = 0x7F
} mc_nmt_state_t;

/* CiA 301 data types (Table 44) as the EDS writes them */
typedef enum {
    MC_CO_BOOL = 0x01, MC_CO_I8 = 0x02, MC_CO_I16 = 0x03, MC_CO_I32 = 0x04, MC_CO_U8 = 0x05,
    MC_CO_U16 = 0x06, MC_CO_U32 = 0x07, MC_CO_REAL32 = 0x08, MC_CO_VSTRING = 0x09, MC_CO_DOMAIN = 0x0F
} mc_co_type_t;

typedef enum { MC_CO_RO = 0, MC_CO_WO, MC_CO_RW, MC_CO_CONST } mc_co_access_t;

#define MC_CO_F_RPDO    0x01u   /* mappable into an RPDO (written by it) */
#define MC_CO_F_TPDO    0x02u   /* mappable into a TPDO (read by it)     */
#define MC_CO_F_NODEID  0x04u   /* default value is $NODEID + the base   */
#define MC_CO_F_PREOP   0x08u   /* writable in pre-operational only      */

/* How an object's value is reached. */
typedef enum {
    MC_CO_K_FIELD = 0,   /* a member of mc_co_t at byte offset arg, of the object's type     */
    MC_CO_K_PARAM,       /* parameter table entry arg (0x2000 + arg)                          */
    MC_CO_K_TELEM,       /* telemetry channel arg (0x2200 + arg), from the step's snapshot    */
    MC_CO_K_HOOK         /* computed or with side effects (co_od.c, hook id arg)              */
} mc_co_kind_t;

/* One object (index, sub) as the dictionary describes it. */
typedef struct {
    uint16_t index;
    uint8_t sub;
    uint8_t type;        /* mc_co_type_t */
    uint8_t access;      /* mc_co_access_t */
    uint8_t flags;       /* MC_CO_F_* */
    uint8_t kind;        /* mc_co_kind_t */
    uint16_t arg;
    int64_t min, max;    /* integer types: the range a write must respect */
    const char *oname;   /* the object's name (the same for every sub-index)  */
    const char *sname;   /* the sub-index's name ("" for a plain variable)     */
    const char *unit;
    const char *doc;
} mc_co_entry_t;

/* A PDO's communication and mapping parameters (0x1400/0x1600, 0x1800/0x1A00). */
typedef struct {
    uint32_t cob_id;     /* bit 31: not valid                                     */
    uint8_t type;        /* transmission type                                     */
    uint16_t inhibit;    /* TPDO: [100 us]                                        */
    uint16_t event_ms;   /* TPDO: event timer [ms] (0: off)                       */
    uint8_t sync_start;  /* TPDO                                                  */
    uint8_t map_n;
    uint32_t map[MC_CO_PDO_MAP_N];   /* index << 16 | sub << 8 | bits          */
    /* state */
    uint32_t last_ms;    /* TPDO: last transmission                               */
    uint8_t sync_count;  /* TPDO: SYNCs since the last one                        */
    uint8_t last[8], last_len;   /* TPDO: what went last; RPDO: the frame held for the SYNC */
    bool pending;        /* RPDO: a synchronous frame waits for the SYNC          */
} mc_co_pdo_t;

typedef struct {
    uint8_t node_id;             /* 1..127 */
    uint16_t heartbeat_ms;       /* 0x1017 at reset (0: off) */
    float step_s;                /* the period mc_co_step is called at [s] (the 402 ramps) */
    uint32_t vendor_id, product_code, revision, serial;   /* 0x1018 */
} mc_co_cfg_t;

/* The SDO server's one transfer in progress. A buffered object (everything but a DOMAIN) is
 * copied at the initiation, so the client gets one consistent value; a DOMAIN (the scope's
 * record) is read part by part as the segments go. */
typedef struct {
    bool active, upload, domain;
    uint16_t index;
    uint8_t sub, toggle;
    uint8_t buf[MC_CO_SDO_BUF];
    uint32_t len, pos, size;
    uint32_t t0_ms;
} mc_co_sdo_t;

typedef struct {
    mc_co_cfg_t cfg;
    hal_can_t *can;
    mc_drive_t *drive;
    hal_nvm_t *nvm;              /* NULL: 0x1010 / 0x1011 answer "cannot be stored"          */
    mc_scope_t *scope;           /* NULL: the scope objects are absent                       */
    mc_nmt_state_t nmt;
    uint16_t heartbeat_ms;
    uint32_t hb_last_ms, now_ms;
    bool boot_pending;           /* the boot-up message goes out at the next step */
    mc_co_sdo_t sdo;
    uint32_t tx_dropped;         /* messages hal_can_send refused */
    uint32_t faults_seen;        /* the drive's fault bits already reported by EMCY */
    uint32_t err_hist[8];        /* 0x1003, newest first: error code | fault bit number << 16;
                                    0x6310 (boot: a stored set migrated with values at their
                                    defaults) | the first such parameter's id << 16           */
    uint8_t err_count;
    uint32_t cob_sync;           /* 0x1005 */
    mc_co_pdo_t rpdo[MC_CO_PDO_N], tpdo[MC_CO_PDO_N];
    uint32_t rpdo_rx, rpdo_bad;  /* RPDOs applied; refused (length, NMT state) */
    mc_402_t ds;                 /* CiA 402 objects and state machine */
    bool ds_on;                  /* publish the 402 command to the drive (a scenario may command instead) */
    mc_drive_telem_t tm;         /* telemetry of the last step (the 402 layer, TPDOs, 0x2200+) */
    mc_scope_cfg_t scope_cfg;    /* 0x2300 / 0x2301, taken at arm                          */
    uint8_t scope_ctrl;          /* 0x2302, last written                                   */
    uint8_t cfg_source;          /* 0x2FF1: mc_pstore_status_t of the boot's load           */
    mc_store_report_t boot_params; /* what that load kept of the stored parameters          */
    uint32_t store_status;       /* mc_pstore_status_t of the last 0x1010 / 0x1011          */
    const mc_params_t *defaults; /* the integrator's set a reset node falls back to (NULL: a
                                    reset node keeps the parameters in force)                */
    bool reload_pending;         /* reset node: the stored (or default) set goes to the drive
                                    once its outputs are off                                 */
    bool cw_written;             /* the controlword was written since the 402 step        */
    uint32_t cw_count;           /* controlwords received (SDO or RPDO)                   */
} mc_co_t;

/* false: node id outside 1..127 or a NULL can/drive (nothing started). nvm and scope may be
 * NULL. cfg_source: the store's status of the configuration the drive was started with
 * (MC_PSTORE_CORRUPT sends an EMCY "parameters lost" once the device is up; MC_PSTORE_PARTIAL
 * the same EMCY with the first value kept at its default, also into 0x1003: give its report
 * with mc_co_set_boot_report). */
bool mc_co_init(mc_co_t *co, const mc_co_cfg_t *cfg, hal_can_t *can, mc_drive_t *drive, hal_nvm_t *nvm,
                mc_scope_t *scope, mc_pstore_status_t cfg_source);
/* The parameter set the drive started with before any stored one (the scenario's, the image's
 * configuration area): NMT reset node then sets the drive's parameters to their power-on values,
 * the stored set or, after a restore (0x1011), these (CiA 301 §7.2.8.3.2.1). Without it a reset
 * node keeps the parameters in force. */
void mc_co_set_defaults(mc_co_t *co, const mc_params_t *defaults);
/* What the boot's load kept of the stored parameters (mc_co_boot_config's rep), for the
 * MC_PSTORE_PARTIAL report; before the first mc_co_step. */
void mc_co_set_boot_report(mc_co_t *co, const mc_store_report_t *rep);
/* Background: up to MC_CO_RX_PER_STEP received frames, the 402 step and its drive command (if
 * ds_on), the TPDOs, the SDO timeout, EMCY and the heartbeat. */
void mc_co_step(mc_co_t *co, uint32_t now_ms);

/* Boot: the configuration the drive starts with: the stored set (OK, FELL_BACK, PARTIAL: matched
 * by name, mc/store.h) over base, or base (EMPTY, CORRUPT, NVM_ERROR). map_out: storage for a
 * stored map (must outlive the drive), or NULL to leave a stored map in the NVM; a set without
 * its map (saved without, or not loaded) takes base's map. rep (may be NULL): what the load kept
 * of the stored parameters. Returns the store's status. */
mc_pstore_status_t mc_co_boot_config(const hal_nvm_t *nvm, const mc_drive_cfg_t *base, mc_drive_cfg_t *out,
                                     mc_flux_map_t *map_out, mc_store_report_t *rep);

/* EMCY (CiA 301 §7.2.7) for a drive fault bit: the error code (CiA 301 / CiA 402 tables) and
 * the error register bits 0x1001 it sets. */
uint16_t mc_co_emcy_code(uint32_t fault_bit);
uint8_t mc_co_error_register(uint32_t faults);
/* Background: compare the drive's faults with those reported; send what changed (co_emcy.c). */
void mc_co_emcy_step(mc_co_t *co);
/* An EMCY of the device itself (not a drive fault): code, error register, manufacturer bytes. */
void mc_co_emcy_send(mc_co_t *co, uint16_t code, uint8_t reg, const uint8_t info[5]);

/* The object dictionary (co_od.c). Lookup: false if (index, sub) does not exist (*missing_sub:
 * the index exists but not the sub). Enumeration: n = 0 .. mc_co_od_count() - 1, in index order. */
bool mc_co_od_lookup(uint16_t index, uint8_t sub, mc_co_entry_t *e, bool *missing_sub);
uint32_t mc_co_od_count(void);
bool mc_co_od_at(uint32_t n, mc_co_entry_t *e);
/* Values little-endian as on the bus. Return 0 or an SDO abort code. A write checks access,
 * length, range and the device state, then applies. */
uint32_t mc_co_od_read(mc_co_t *co, uint16_t index, uint8_t sub, uint8_t *data, uint32_t cap, uint32_t *len);
uint32_t mc_co_od_write(mc_co_t *co, uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len);
/* DOMAIN objects: total size, and a part at an offset (bytes copied). */
uint32_t mc_co_od_domain_size(const mc_co_t *co, uint16_t index, uint8_t sub);
uint32_t mc_co_od_domain_read(const mc_co_t *co, uint16_t index, uint8_t sub, uint32_t offset, uint8_t *dst,
                              uint32_t n);

/* PDOs (co_pdo.c) */
void mc_co_pdo_defaults(mc_co_t *co);
/* A received frame with an RPDO's COB-ID, or the SYNC. */
bool mc_co_pdo_rx(mc_co_t *co, const hal_can_frame_t *f);
void mc_co_pdo_sync(mc_co_t *co);
/* The TPDOs due at now_ms (event timer, change with the inhibit time). */
void mc_co_pdo_tx(mc_co_t *co);
/* 0x1400..0x1403, 0x1600.., 0x1800.., 0x1A00..: read and write with their CiA 301 rules. */
uint32_t mc_co_pdo_read(const mc_co_t *co, uint16_t index, uint8_t sub, uint32_t *value);
uint32_t mc_co_pdo_write(mc_co_t *co, uint16_t index, uint8_t sub, uint32_t value);

#endif
