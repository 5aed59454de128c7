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
 * the hexagon is scaled toward the origin (same angle, no phase error) onto its boundary.
 *
 * OVERMODULATION. A vector of constant magnitude m vdc/sqrt(3) turning at omega, scaled so,
 * keeps its angle and loses only the part beyond the hexagon, whose distance from the centre
 * at the angle gamma from a side's middle is (vdc/sqrt(3)) / cos(gamma). Its fundamental is
 * the mean radius over a sixth of a turn (no phase error, so no other component remains):
 *     u_1 = (vdc/sqrt(3)) (3/pi) int_{-pi/6}^{pi/6} min(m, 1/cos(gamma)) d gamma            (2.14a)
 * At m = 2/sqrt(3) (the request reaches the hexagon's corners in every direction) this is the
 * mean radius of the hexagon, (3/pi) ln 3 = 1.0491 vdc/sqrt(3) (0.606 vdc; six-step would give
 * 2/pi vdc = 0.637 vdc): MC_SVPWM_FUND_MAX. The harmonics are those of the clipped radius,
 * the 5th and 7th (6th in d-q); at 1500 rpm on the thesis motor they add ~0.2 A of ripple. */
#define MC_SVPWM_FUND_MAX 1.0491f    /* (3/pi) ln 3, largest steady fundamental / (vdc/sqrt3) */
#define MC_SVPWM_REACH_MAX 1.1547f   /* 2/sqrt3: the hexagon's corners / (vdc/sqrt3) */
void mc_svpwm(mc_ab_t u, float vdc, mc_duty_t *out);

/* The hexagon's distance from the centre in the direction of the unit vector dir: vdc / (the
 * largest line-to-line voltage of dir), from vdc/sqrt(3) (a side's middle) to 2 vdc / 3 (a
 * corner). What mc_svpwm delivers in that direction when asked for more. Not a unit vector
 * (beyond a few per cent): vdc/sqrt(3). */
float mc_svpwm_reach(mc_ab_t dir, float vdc);

/* The active vector (a corner of the hexagon, 2 vdc / 3, U1..U6 as k = 0..5 from phase a) nearest
 * to the stator-frame angle [rad]; and for index k its duties, with *dir (if not NULL) its unit
 * vector. A corner held a whole period is the flying start's known-vector pulse (mc/catch.h (C.6))
 * and an angle-sensor drive's first step at speed. */
int      mc_svpwm_corner_near(float angle);
mc_abc_t mc_svpwm_corner(int k, mc_ab_t *dir);

/* Reference implementation by sectors (2.10)-(2.13), used by tests to check mc_svpwm. */
void mc_svpwm_sector(mc_ab_t u, float vdc, mc_duty_t *out);

#endif
