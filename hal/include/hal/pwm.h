/* PWM hardware interface: three centre-aligned half bridges.
 * Duties written in period k are latched at the next period boundary (shadow registers), so they
 * act during period k+1: the one-period update delay the estimators account for. */
#ifndef HAL_PWM_H
#define HAL_PWM_H
#include <stdbool.h>
#include <stdint.h>

typedef struct hal_pwm hal_pwm_t;   /* defined by the port */

/* High-side on-fraction per phase, each in [0, 1]; latched at the next period boundary. */
void  hal_pwm_set_duties(hal_pwm_t *pwm, float da, float db, float dc);
/* Outputs off = safe state (all six switches off), takes effect immediately. */
void  hal_pwm_enable(hal_pwm_t *pwm, bool on);
bool  hal_pwm_enabled(const hal_pwm_t *pwm);
float hal_pwm_period_s(const hal_pwm_t *pwm);
float hal_pwm_dead_time_s(const hal_pwm_t *pwm);

#endif
