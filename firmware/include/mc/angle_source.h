/* The angle-source seam. Every rotor-angle provider (encoder now; UNOP, EEMF, PSVI, blend and
 * the flux-map identifier later) takes the same per-period inputs and returns an angle and speed.
 * The drive selects one by mc_angle_src_kind_t and calls it at the same point of the ISR. */
#ifndef MC_ANGLE_SOURCE_H
#define MC_ANGLE_SOURCE_H
#include "mc/types.h"

typedef enum {
    MC_ANGLE_SRC_ENCODER = 0,
    MC_ANGLE_SRC_UNOP,          /* Newton-based estimator (thesis ch. 6) + PLL filter */
    MC_ANGLE_SRC_COUNT
} mc_angle_src_kind_t;

/* What the drive hands to an angle source every period k. */
typedef struct {
    mc_ab_t i_ab;          /* i_ab(k), measured at the start of period k [A]                  */
    mc_ab_t i_ab_prev;     /* i_ab(k-1) [A]                                                    */
    mc_ab_t u_ab_applied;  /* voltage actually applied during [k-1, k] (commanded two ISRs ago,
                              limited by the modulator, dead-time compensated) [V]             */
    float   vdc;           /* [V]                                                              */
    uint32_t qep_count;    /* encoder counter (for the encoder source)                          */
} mc_angle_in_t;

typedef struct {
    float theta;           /* electrical angle at sample k, [-pi, pi) [rad]                   */
    float omega;           /* electrical speed [rad/s]                                        */
} mc_angle_out_t;

#endif
