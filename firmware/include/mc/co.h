/* CANopen device (CiA 301) over hal_can: NMT slave with boot-up and heartbeat, an SDO server
 * (expedited and segmented transfer, the standard abort codes) and the object dictionary, whose
 * manufacturer part 0x2000 + id is the drive's parameter table itself (mc/params_table.h): every
 * parameter by its stable id, read as the value in force, written through mc_drive_param_write
 * (range-checked with the table's limits, handed to the ISR at a period boundary).
 * No heap, no globals; mc_co_step is called from the background loop with bounded work.
 * EMCY (co_emcy.c): a message on every newly latched drive fault, the 0x1003 history, and "error
 * reset" when the faults clear.
 * Not yet: PDOs, CiA 402, 0x1010/0x1011 (mc/param_store.h is ready), the scope, SDO block
 * transfer. */
#ifndef MC_CO_H
#define MC_CO_H
#include <stdbool.h>
#include <stdint.h>
#include "hal/can.h"
#include "mc/drive.h"

#define MC_CO_DEVICE_TYPE  0x00020192u   /* 0x1000: CiA 402 drive profile (402 = 0x192), servo drive */
#define MC_CO_SDO_TIMEOUT_MS 1000u
#define MC_CO_RX_PER_STEP  16u          /* frames taken per mc_co_step */
#define MC_CO_SDO_BUF      32u          /* the longest object (0x1008) */

/* SDO abort codes (CiA 301 §7.2.4.3.17) */
#define MC_SDO_ABORT_TOGGLE        0x05030000u
#define MC_SDO_ABORT_TIMEOUT       0x05040000u
#define MC_SDO_ABORT_CS            0x05040001u
#define MC_SDO_ABORT_WRITE_ONLY    0x06010001u
#define MC_SDO_ABORT_READ_ONLY     0x06010002u
#define MC_SDO_ABORT_NO_OBJECT     0x06020000u
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

typedef enum {
    MC_NMT_INITIALISING = 0x00,
    MC_NMT_STOPPED = 0x04,
    MC_NMT_OPERATIONAL = 0x05,
    MC_NMT_PRE_OPERATIONAL = 0x7F
} mc_nmt_state_t;

typedef struct {
    uint8_t node_id;             /* 1..127 */
    uint16_t heartbeat_ms;       /* 0x1017 at reset (0: off) */
    uint32_t vendor_id, product_code, revision, serial;   /* 0x1018 */
} mc_co_cfg_t;

/* The SDO server's one transfer in progress. */
typedef struct {
    bool active, upload;
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
    mc_nmt_state_t nmt;
    uint16_t heartbeat_ms;
    uint32_t hb_last_ms, now_ms;
    bool boot_pending;           /* the boot-up message goes out at the next step */
    mc_co_sdo_t sdo;
    uint32_t tx_dropped;         /* responses hal_can_send refused */
    uint32_t faults_seen;        /* the drive's fault bits already reported by EMCY */
    uint32_t err_hist[8];        /* 0x1003, newest first: error code | fault bit number << 16 */
    uint8_t err_count;
} mc_co_t;

/* false: node id outside 1..127 (nothing started). */
bool mc_co_init(mc_co_t *co, const mc_co_cfg_t *cfg, hal_can_t *can, mc_drive_t *drive);
/* Background: up to MC_CO_RX_PER_STEP received frames, the SDO timeout, the heartbeat. */
void mc_co_step(mc_co_t *co, uint32_t now_ms);

/* EMCY (CiA 301 §7.2.7) for a drive fault bit: the error code (CiA 301 / CiA 402 tables) and
 * the error register bits 0x1001 it sets. */
uint16_t mc_co_emcy_code(uint32_t fault_bit);
uint8_t mc_co_error_register(uint32_t faults);
/* Background: compare the drive's faults with those reported; send what changed (co_emcy.c). */
void mc_co_emcy_step(mc_co_t *co);

/* The object dictionary (co_od.c), also for tools and tests. Values little-endian as on the bus.
 * Return 0 or an SDO abort code. */
uint32_t mc_co_od_read(mc_co_t *co, uint16_t index, uint8_t sub, uint8_t *data, uint32_t cap, uint32_t *len);
uint32_t mc_co_od_write(mc_co_t *co, uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len);

#endif
