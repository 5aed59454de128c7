/* ISR stage markers for processor-in-the-loop cycle accounting: the drive marks where each stage
 * of its control ISR begins. A target port stores the stage number to a variable the PIL watches
 * (one store, a few cycles); the host port does nothing. */
#ifndef HAL_STAGE_H
#define HAL_STAGE_H
#include <stdint.h>

typedef enum {
    HAL_STAGE_SAMPLE = 1,    /* commands, ADC/encoder read, scaling, Clarke, startup, protection */
    HAL_STAGE_ANGLE,         /* the angle source (UNOP + PLL, encoder, ...)                      */
    HAL_STAGE_REFERENCES,    /* Park, notch, speed / torque / current references                 */
    HAL_STAGE_CURRENT,       /* current loop, injection, polarity re-check, plausibility         */
    HAL_STAGE_MODULATION,    /* inverse Park, SVPWM, dead-time compensation, duties, telemetry   */
    HAL_STAGE_COUNT
} hal_stage_t;

void hal_stage_mark(hal_stage_t stage);

#endif
