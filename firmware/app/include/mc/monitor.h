/* The image's monitor block: a RAM structure a debugger (or the simulator's processor-in-the-
 * loop, which is one) reads and writes while the drive runs, like the "real-time variables" of
 * vendor tools. Commands go in, the last period's telemetry and the boot result come out. Fixed
 * layout (32-bit words only: the target's short enums and bools never cross), packed and
 * unpacked by the same code on both sides.
 *
 * Protocol: the writer fills cmd[] and then increments cmd_seq; the image's background loop
 * hands a new command to the drive (mc_drive_command) before the next ISR. After each ISR the
 * background copies the telemetry into tm[] and increments tm_seq. */
#ifndef MC_MONITOR_H
#define MC_MONITOR_H
#include <stdint.h>
#include "mc/drive.h"

#define MC_MONITOR_MAGIC   0x4E4D434Du   /* "MCMN" */
#define MC_MONITOR_VERSION 2u
#define MC_MONITOR_CMD_WORDS 7u
#define MC_MONITOR_TM_WORDS  48u

typedef struct {
    uint32_t magic, version;
    uint32_t boot;               /* 0 booting, 1 drive running, 2 configuration refused      */
    uint32_t store_params, store_model;   /* mc_store_status_t of the records found at boot  */
    uint32_t cfg_err_kind, cfg_err_param; /* mc_param_err_t of a refused configuration       */
    uint32_t isr_count;          /* control ISRs taken                                       */
    uint32_t cmd_seq;
    uint32_t cmd[MC_MONITOR_CMD_WORDS];
    uint32_t tm_seq;
    uint32_t tm[MC_MONITOR_TM_WORDS];
    uint32_t store_nvm;          /* mc_pstore_status_t of the set stored by CANopen 0x1010     */
} mc_monitor_t;

void mc_monitor_pack_cmd(const mc_drive_cmd_t *c, uint32_t w[MC_MONITOR_CMD_WORDS]);
void mc_monitor_unpack_cmd(const uint32_t w[MC_MONITOR_CMD_WORDS], mc_drive_cmd_t *c);
void mc_monitor_pack_telem(const mc_drive_telem_t *t, uint32_t w[MC_MONITOR_TM_WORDS]);
void mc_monitor_unpack_telem(const uint32_t w[MC_MONITOR_TM_WORDS], mc_drive_telem_t *t);

#endif
