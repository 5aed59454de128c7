/* Host port of the HAL: plain structs standing in for the peripheral registers. The simulator
 * writes the inputs (ADC conversions, encoder counter, time) before each control interrupt and
 * reads the outputs (latched duties, output enable) while it integrates the plant. */
#ifndef HAL_HOST_H
#define HAL_HOST_H
#include "hal/adc.h"
#include "hal/pwm.h"
#include "hal/qep.h"
#include "hal/time.h"

struct hal_pwm {
    float period_s;
    float dead_time_s;
    float shadow[3];    /* written by firmware                           */
    float active[3];    /* latched at the period boundary, seen by plant */
    bool  enabled;
    uint32_t writes;    /* number of duty writes (diagnostics)            */
    uint32_t nonfinite; /* duties that arrived as NaN or infinite (a firmware bug: the drive
                           checks before it writes; the port still never passes one on) */
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

void hal_host_pwm_init(hal_pwm_t *pwm, float period_s, float dead_time_s);
/* Period boundary: shadow -> active (what the hardware does at counter zero). */
void hal_host_pwm_latch(hal_pwm_t *pwm);

#endif
