/* Three-phase pulse reference method (thesis 3.5.1, Fig 3.7): V(100), V(010), V(001) for n
 * periods each; the peak phase currents follow (3.19), the angle comes from (3.21) (range
 * [-45, 45] deg) and Table 3.1 (signs of dI_a, dI_b, dI_c: a 30-deg sector modulo 180) picks
 * between theta_atan and theta_atan + 90 deg. Result modulo pi, like Step I.
 * Each pulse is followed by its complement vector for n periods (zero net volt-seconds: the
 * current returns to ~0 without waiting tens of ms for the L/Rs decay) and a zero-vector gap
 * until |i| <= i_rest, so every pulse starts from rest. Calling convention: mc/initpos.h.
 * PHASE ORDER: with the firmware's Clarke (2.4) phase b lies at +120 deg, so the phase-b
 * inductance goes with cos 2(theta - 120) and the peaks follow
 *   I_a = I0 + dI0 cos 2t,  I_b = I0 + dI0 cos(2t + 120),  I_c = I0 + dI0 cos(2t - 120);
 * (3.19) as printed has b and c the other way round (b at -120 deg). Taken literally it returns
 * -theta (found by the plant test); here (3.20)-(3.21) and Table 3.1 are used with b <-> c:
 *   tan 2t = sqrt3 (dI_c - dI_b) / (2 dI_a - dI_b - dI_c). */
#ifndef MC_PULSE3_H
#define MC_PULSE3_H
#include "mc/initpos.h"

typedef struct {
    float rs;
    int n;                    /* periods per pulse, 1..MC_IP_M_MAX (5) */
    int gap_min, gap_max;     /* [periods] */
    float i_rest, i_trip;     /* [A] */
} mc_pulse3_cfg_t;

typedef struct {
    mc_pulse3_cfg_t cfg;
    mc_ip_run_t prog;         /* runner only: the peaks are tracked as the intervals close */
    int state;
    float i_start[3];         /* internal: phase current at the first sample of each pulse [A] */
    bool seen[3];             /* internal: pulse x has started */
    float ipk[3];             /* peak phase current rise I_a, I_b, I_c during each pulse [A] */
    float di[3];              /* I_x - I_0 */
    int sector;               /* Table 3.1 row 0..5 (centre 0, 30, ..., 150 deg); -1 impossible */
    float theta_atan;         /* (3.21) [rad], [-pi/4, pi/4] */
    float theta;              /* [0, pi) */
    int calls;
} mc_pulse3_t;

void mc_pulse3_cfg_default(mc_pulse3_cfg_t *cfg);
bool mc_pulse3_start(mc_pulse3_t *s, const mc_pulse3_cfg_t *cfg);
mc_ip_status_t mc_pulse3_step(mc_pulse3_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty);
/* Table 3.1 (b, c exchanged): the row for the signs of (dIa, dIb, dIc), -1 for (+,+,+) and
 * (-,-,-) */
int mc_pulse3_sector(const float di[3]);
/* (3.21) + Table 3.1 on three peak currents: theta in [0, pi); false without saliency */
bool mc_pulse3_angle(const float ipk[3], float *theta, float *theta_atan, int *sector);

#endif
