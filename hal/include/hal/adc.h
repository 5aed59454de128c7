/* ADC hardware interface: phase currents and DC-link voltage, sampled at the PWM counter's zero
 * (period boundary, centre of the zero vector V000) by the PWM trigger. Raw counts; scaling and
 * offset calibration live in the firmware (mc drive), not in the port. */
#ifndef HAL_ADC_H
#define HAL_ADC_H
#include <stdbool.h>
#include <stdint.h>

typedef struct hal_adc hal_adc_t;

typedef struct {
    uint16_t i[3];   /* phase a, b, c current channels [counts] */
    uint16_t vdc;    /* DC-link voltage channel [counts]        */
    bool overrun;    /* the conversion-complete event fired again before the ISR acknowledged
                        the last one: the previous ISR overran its period (set by the port) */
} hal_adc_sample_t;

/* Latest conversion of the current PWM period. */
void hal_adc_read(hal_adc_t *adc, hal_adc_sample_t *out);

#endif
