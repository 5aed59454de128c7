/* Time base: a free-running microsecond counter for the background loop and timeouts. */
#ifndef HAL_TIME_H
#define HAL_TIME_H
#include <stdint.h>

typedef struct hal_time hal_time_t;

uint32_t hal_time_us(const hal_time_t *t);   /* wraps after ~71 min */

#endif
