/* Quadrature encoder (eQEP) interface: position counter over 4*lines per mechanical revolution,
 * index latch, and the counter at the last index. Speed is computed by the firmware from counts. */
#ifndef HAL_QEP_H
#define HAL_QEP_H
#include <stdbool.h>
#include <stdint.h>

typedef struct hal_qep hal_qep_t;

typedef struct {
    uint32_t count;        /* 0 .. counts_per_rev-1                       */
    bool     index_seen;   /* index pulse passed at least once            */
    uint32_t index_count;  /* counter value latched at the last index     */
} hal_qep_sample_t;

void     hal_qep_read(hal_qep_t *qep, hal_qep_sample_t *out);
uint32_t hal_qep_counts_per_rev(const hal_qep_t *qep);

#endif
