/* Host port of the HAL: plain structs standing in for the peripheral registers. The simulator
 * writes the inputs (ADC conversions, encoder counter, time) before each control interrupt and
 * reads the outputs (latched duties, output enable) while it integrates the plant. */
#ifndef HAL_HOST_H
#define HAL_HOST_H
#include "hal/adc.h"
#include "hal/can.h"
#include "hal/nvm.h"
#include "hal/pwm.h"
#include "hal/qep.h"
#include "hal/stage.h"
#include "hal/time.h"
#include "hal/watchdog.h"

struct hal_pwm {
    float period_s;
    float dead_time_s;
    float shadow[3];    /* written by firmware                           */
    float active[3];    /* latched at the period boundary, seen by plant */
    bool  enabled;
    uint32_t writes;    /* number of duty writes (diagnostics)            */
    uint32_t on_edges;  /* enables from off (diagnostics: on hardware even an enable undone
                           later in the same interrupt fires the gates with the latched duties) */
    uint32_t nonfinite; /* duties that arrived as NaN or infinite (a firmware bug: the drive
                           checks before it writes; the port still never passes one on) */
    uint32_t counts;    /* compare resolution: 0 ideal, N: duties in whole counts of N        */
    bool off_time;      /* the compare counts the off-time (N - round((1 - d) N))             */
    uint32_t cmp_shadow[3], cmp_active[3];   /* the compare values when counts > 0            */
};

struct hal_adc {
    hal_adc_sample_t sample;   /* written by the simulator at the period boundary */
};

struct hal_qep {
    uint32_t counts_per_rev;
    hal_qep_sample_t sample;
};

struct hal_time {
    uint32_t us;
};

/* Watchdog: a down counter in simulated microseconds, reloaded by hal_wdg_kick; its expiry turns
 * the bound PWM's outputs off, as the targets' do (hal/watchdog.h). */
struct hal_wdg {
    uint32_t timeout_us;    /* 0: not started                                               */
    uint32_t left_us;
    uint32_t kicks;
    bool expired;
    hal_pwm_t *pwm;         /* the outputs it turns off                                     */
    uint32_t isr_runs;      /* control-ISR runs, counted by the host side (hal_wdg_service)  */
    uint32_t seen;
};

/* CAN: two rings; the host side (the simulator's bus, a test) delivers received frames and
 * takes the transmitted ones. */
#define HAL_HOST_CAN_QUEUE 64u
struct hal_can {
    hal_can_frame_t tx[HAL_HOST_CAN_QUEUE], rx[HAL_HOST_CAN_QUEUE];
    uint32_t tx_head, tx_count, rx_head, rx_count;
    hal_can_state_t state;
    uint32_t tx_dropped, rx_dropped;   /* frames refused because a ring was full */
    uint32_t recoveries;               /* bus-off recoveries asked for */
};

/* NVM: a flash device with an erase map (hal_nvm_geometry_t) and the blocks a port would place
 * in it: blocks of the sector size of the region at base (as hal/am263x does), erased with that
 * region's sector erase, which the device carries out only where the size matches its map (a
 * 4 KiB erase in a 64 KiB region erases nothing, as the S25FL128S ignores a P4E outside its
 * parameter sectors); every erase is verified (all 0xFF) like the target's. Written in units of 8
 * bytes, with flash semantics. A power cut can be scheduled at any step (an erase is one step,
 * every write unit one): that step is left half done (an erase: the sector scrambled; a write:
 * the unit with a random part of its bits cleared) and every later call fails until
 * hal_host_nvm_power_on(). hal_host_nvm_init: the host map, 4 blocks of 4 KiB (16 KiB: mcsim's
 * --nvm file); hal_host_nvm_init_geom: any map, e.g. the LaunchPad's S25FL128S. */
#define HAL_HOST_NVM_BLOCKS 4u          /* hal_host_nvm_init's map */
#define HAL_HOST_NVM_BLOCK_SIZE 4096u
#define HAL_HOST_NVM_WRITE_UNIT 8u
#define HAL_HOST_NVM_CAP (2u * 65536u)  /* bytes of the device the model holds (from base) */
extern const hal_nvm_geometry_t hal_host_nvm_uniform4k;   /* 4 x 4 KiB sectors, no commands */
extern const hal_nvm_geometry_t hal_host_nvm_s25fl128s;   /* = am263x_s25fl128s (am263x/port.h) */
struct hal_nvm {
    uint8_t mem[HAL_HOST_NVM_CAP];  /* device bytes base.. ; blocks x block_size of them used */
    const hal_nvm_geometry_t *geom;
    uint32_t base, block_size, blocks;
    uint32_t erase_size;  /* the erase the layer sends (block_size; a test sets another, 0: none,
                             to model a layer that got the map wrong) */
    uint32_t steps;     /* erase and write-unit steps since init */
    uint32_t cut_at;    /* the step the power fails in (0: never) */
    bool dead;          /* after the cut */
    uint32_t rng;       /* for the scramble */
};
/* Blocks = blocks whole sectors of the region holding base; false (nothing set up) when they do
 * not fit that region or the model's capacity. */
bool hal_host_nvm_init_geom(hal_nvm_t *nvm, const hal_nvm_geometry_t *geom, uint32_t base, uint32_t blocks);
uint32_t hal_host_nvm_bytes(const hal_nvm_t *nvm);      /* blocks x block_size: mem's used part */

void hal_host_pwm_init(hal_pwm_t *pwm, float period_s, float dead_time_s);
/* Quantise duties as a timer's compare register does (counts = 0: ideal), computed in float as
 * the target ports compute their compare values, so that the host build and a PIL image get the
 * same duties: on_time: round(d N) (hal/generic); off_time: round((1 - d) N) (hal/am263x ePWM). */
void hal_host_pwm_set_counts(hal_pwm_t *pwm, uint32_t counts, bool off_time);
void hal_host_can_init(hal_can_t *can);
/* bus -> controller: false when the frame is invalid or the RX ring is full (counted) */
bool hal_host_can_deliver(hal_can_t *can, const hal_can_frame_t *f);
/* controller -> bus: the oldest queued frame; false when none */
bool hal_host_can_take(hal_can_t *can, hal_can_frame_t *f);
void hal_host_can_set_state(hal_can_t *can, hal_can_state_t s);
void hal_host_nvm_init(hal_nvm_t *nvm);                  /* every block erased */
void hal_host_nvm_cut_at(hal_nvm_t *nvm, uint32_t step); /* 0: no cut */
void hal_host_nvm_power_on(hal_nvm_t *nvm);              /* alive again, content as the cut left it */
/* Period boundary: shadow -> active (what the hardware does at counter zero). */
void hal_host_pwm_latch(hal_pwm_t *pwm);
void hal_host_wdg_start(hal_wdg_t *wdg, uint32_t timeout_us, hal_pwm_t *pwm);
/* dt_us of simulated time: true once expired (outputs off, and they stay expired). */
bool hal_host_wdg_elapse(hal_wdg_t *wdg, uint32_t dt_us);

#endif
