/* High-frequency voltage injection in the estimated d axis (thesis 6.4 and 7.4): sinusoidal or
 * rectangular, magnitude scheduled with the estimated speed by (6.6). */
#ifndef MC_INJECTION_H
#define MC_INJECTION_H
#include "mc/types.h"

typedef enum { MC_INJ_OFF = 0, MC_INJ_SINE, MC_INJ_RECT } mc_inj_kind_t;

typedef struct {
    mc_inj_kind_t kind;
    float v1;          /* magnitude at standstill [V] (thesis: 70 V)                  */
    float f_hz;        /* injection frequency (thesis: 500 Hz)                        */
    float omega_n1;    /* N1 of (6.6) as electrical speed [rad/s] (thesis: 400 rpm)   */
    float ts;          /* [s]                                                         */
} mc_inj_cfg_t;

typedef struct {
    mc_inj_cfg_t cfg;
    float phase;       /* [0, 1) of one injection period */
    float dphase;      /* f_hz * ts                      */
    float magnitude;   /* last magnitude (6.6) [V]       */
} mc_inj_t;

void  mc_inj_init(mc_inj_t *s, const mc_inj_cfg_t *cfg);
void  mc_inj_reset(mc_inj_t *s);
/* (6.6): V1 (N1 - |N|)/N1 below N1, zero above. */
float mc_inj_magnitude(const mc_inj_cfg_t *cfg, float omega_hat);
/* Voltage to add on the estimated d axis for the next period [V]. */
float mc_inj_step(mc_inj_t *s, float omega_hat);

#endif
