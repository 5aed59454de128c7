/* Space-vector PWM by min-max zero-sequence injection (equivalent to (2.10)-(2.13)). */
#ifndef MC_SVPWM_H
#define MC_SVPWM_H
#include "mc/types.h"

typedef struct {
    float a, b, c;      /* high-side duty per phase, [0, 1]                               */
    mc_ab_t u_real;     /* the stator voltage vector these duties realise [V]             */
    bool saturated;     /* the request was outside the hexagon and was scaled back        */
} mc_duty_t;

/* Linear up to |u| = vdc/sqrt(3) in every direction (inscribed circle); a request outside
 * the hexagon is scaled toward the origin (same angle, no phase error) onto its boundary. */
void mc_svpwm(mc_ab_t u, float vdc, mc_duty_t *out);

/* Reference implementation by sectors (2.10)-(2.13), used by tests to check mc_svpwm. */
void mc_svpwm_sector(mc_ab_t u, float vdc, mc_duty_t *out);

#endif
