/* Board bring-up and the control interrupt: what a target port provides beyond the peripheral
 * calls (adc.h, pwm.h, qep.h, can.h, nvm.h, time.h). Target-neutral: a port (hal/am263x,
 * hal/generic) maps it onto its registers; the image's main (firmware/image) is the only caller.
 *
 * Order: hal_board_init (clocks, pins, PWM time base stopped with the outputs off, ADC triggered
 * at the PWM counter's zero, the centre of the zero vector V000, not the period's centre;
 * encoder, CAN, NVM) -> hal_board_attach_isr -> hal_board_start (time
 * base running, the ADC end-of-conversion interrupt enabled). The outputs stay off until the
 * firmware calls hal_pwm_enable(true); a trip (hal_pwm_enable(false), or the port's hardware trip
 * input) turns all six switches off at once, without the CPU (the safe state). */
#ifndef HAL_BOARD_H
#define HAL_BOARD_H
#include <stdbool.h>
#include <stdint.h>
#include "hal/adc.h"
#include "hal/can.h"
#include "hal/nvm.h"
#include "hal/pwm.h"
#include "hal/qep.h"
#include "hal/time.h"
#include "hal/watchdog.h"

typedef struct {
    float f_pwm_hz;             /* switching = sampling frequency [Hz]                        */
    float dead_time_s;          /* dead band on both edges [s]                                */
    uint8_t adc_ch_i[3];        /* current-sense channel map: ADC input of phase a, b, c       */
    uint8_t adc_ch_vdc;         /* ADC input of the DC-link divider                            */
    uint32_t qep_counts_per_rev;/* 4 x encoder lines                                          */
    uint32_t can_bitrate;       /* [bit/s], classic CAN                                       */
} hal_board_cfg_t;

typedef struct {
    hal_adc_t *adc;
    hal_pwm_t *pwm;
    hal_qep_t *qep;
    hal_can_t *can;
    hal_nvm_t *nvm;
    hal_time_t *time;
    hal_wdg_t *wdg;             /* started by hal_board_start (hal/watchdog.h)                */
} hal_board_t;

typedef void (*hal_isr_fn_t)(void *ctx);

/* false: the configuration cannot be realised (e.g. a PWM period or dead time out of the
 * counters' range, or a dead time below hal_board_min_dead_time_s); nothing is started then and
 * the outputs are off. */
bool hal_board_init(const hal_board_cfg_t *cfg, hal_board_t *out);
/* The control ISR: called once per PWM period from the ADC end-of-conversion interrupt. */
void hal_board_attach_isr(hal_isr_fn_t fn, void *ctx);
/* Time base running, the control interrupt enabled, the watchdog started. */
void hal_board_start(void);
/* The port's dead-time floor [s] (its power stage's switching; below it hal_board_init refuses,
 * and the image names hw.dead_time_s): the simulator's ideal inverter has none. */
float hal_board_min_dead_time_s(void);
/* Background loop: sleep until the next interrupt (WFI). */
void hal_board_idle(void);

#endif
