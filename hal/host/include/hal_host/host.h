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

/* NVM: 4 blocks of 4 KB, written in units of 8 bytes, with flash semantics. A power cut can be
 * scheduled at any step (an erase is one step, every write unit one): that step is left half
 * done (an erase: the block scrambled; a write: the unit with a random part of its bits cleared)
 * and every later call fails until hal_host_nvm_power_on(). */
#define HAL_HOST_NVM_BLOCKS 4u
#define HAL_HOST_NVM_BLOCK_SIZE 4096u
#define HAL_HOST_NVM_WRITE_UNIT 8u
struct hal_nvm {
    uint8_t mem[HAL_HOST_NVM_BLOCKS][HAL_HOST_NVM_BLOCK_SIZE];
    uint32_t steps;     /* erase and write-unit steps since init */
    uint32_t cut_at;    /* the step the power fails in (0: never) */
    bool dead;          /* after the cut */
    uint32_t rng;       /* for the scramble */
};

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
