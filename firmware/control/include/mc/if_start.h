/* I/f: the current-controlled open-loop start and low-speed mode for motors whose saliency the
 * injection cannot read (issue 24, Deliver 4). Not in the thesis; the standard method of
 * Fatu, Teodorescu, Boldea, Andreescu, Blaabjerg, "I-f starting method with smooth transition to
 * EMF based motion-sensorless vector control of PM synchronous motor/generator", IEEE PESC 2008.
 *
 * A current vector of magnitude I_f along the q axis of a reference frame whose angle theta_ref is
 * the integral of a ramped speed reference omega_ref; the rotor follows, its d axis a load angle
 * delta ahead of the frame (sign(I_f) = +1: the torque k I_f cos(delta) balances the load for
 * delta in (0, 90 deg), and a rotor falling back gains torque: stable). The estimator runs in
 * parallel. Above w_h (omega_ref and the estimate synchronous) I_f is reduced until the
 * estimated delta is below delta_h, i.e. the torque just balances, then the angle source is the
 * estimator's again (the caller presets its speed loop with the torque produced). Below w_l < w_h
 * in closed loop (a reversal through zero) the block takes over again at the estimated angle:
 * the hysteresis w_l .. w_h keeps it from chattering. All angles and speeds electrical.
 * init/step on caller-owned state, no heap. */
#ifndef MC_IF_START_H
#define MC_IF_START_H
#include <stdbool.h>
#include <stdint.h>
#include "mc/types.h"

typedef struct {
    float ts;          /* [s] period                                                          */
    float i_f;         /* [A] > 0, the open-loop current magnitude                            */
    float accel;       /* [rad/s^2] > 0, ramp of omega_ref                                    */
    float w_h;         /* [rad/s] hand-over to the estimator above this                       */
    float w_l;         /* [rad/s] back to open loop below this (0 < w_l < w_h)                */
    float w_tol;       /* [rad/s] estimate within this of omega_ref: synchronous              */
    uint32_t n_sync;   /* [periods] synchronous and above w_h for this long before reducing    */
    float i_drop;      /* [A/s] rate at which I_f is reduced before the hand-over             */
    float i_min;       /* [A] the reduction stops here (then hands over anyway)               */
    float delta_h;     /* [rad] hand over once the estimated load angle is below this         */
    uint32_t n_align;  /* [periods] each of the two alignment steps of mc_if_align            */
    float damp;        /* [0..1) share of the estimate's speed deviation the frame follows from
                        * w_l on (nothing else damps the rotor's swing about the frame)       */
} mc_if_cfg_t;

typedef enum {
    MC_IF_CLOSED = 0,  /* the estimator's angle is in charge                                  */
    MC_IF_OPEN,        /* open loop: theta_ref from the ramp, |i| = I_f                         */
    MC_IF_REDUCE       /* open loop above w_h, I_f being reduced toward the hand-over          */
} mc_if_mode_t;

typedef struct {
    mc_if_mode_t mode;
    float theta;       /* theta_ref [rad], wrapped                                            */
    float omega;       /* omega_ref [rad/s]                                                   */
    float i_mag;       /* [A] present magnitude (I_f, or less while reducing)                 */
    float sign;        /* +1 / -1: the torque direction the current is placed for            */
    uint32_t n;        /* periods the hand-over condition held                                */
    uint32_t align;    /* alignment periods left (mc_if_align)                                */
    float slip;        /* [rad] the frame's advance minus the estimate's (its reseeds left out),
                        * summed in open loop from w_l on, times sign: a rotor in step stays
                        * within a load angle of it, one that pulled out loses a turn per slip
                        * period                                                             */
    float frame_prev;  /* [rad] last period's frame and estimate, for the slip                */
    float est_prev;
    bool  slip_on;     /* the slip counted last period                                        */
} mc_if_t;

typedef struct {
    float omega_target;  /* [rad/s] where the ramp goes (the speed command)                   */
    float theta_est;     /* [rad] the estimator's angle this period                           */
    float omega_est;     /* [rad/s] its speed                                                  */
    float torque_sign;   /* in closed loop: the sign of the torque produced (re-entry)        */
    bool  est_only;      /* no speed command to ramp to (torque mode): the frame holds still
                          * and the hand-over waits for the estimate alone above w_h (the
                          * load turned the rotor), at once, without the reduction             */
} mc_if_in_t;

typedef struct {
    bool  open;          /* true: use theta, omega and i_ref below; false: the estimator's    */
    bool  handover;      /* this period went from open to closed loop                          */
    bool  entered;       /* this period went from closed to open loop                          */
    float theta, omega;  /* the frame's angle and speed [rad, rad/s]                           */
    mc_dq_t i_ref;       /* [A] in that frame: (0, sign i_mag)                                 */
    float delta;         /* [rad] estimated load angle sign wrap(theta_est - theta)            */
    bool  reseed;        /* the estimate cannot be the rotor's (behind the frame by more than
                          * 45 deg, ahead by more than 135, or its speed of the other sign):
                          * set it to (theta + sign pi/4, omega) now, the middle of the load
                          * angles a synchronous rotor takes (on a machine without saliency the
                          * EMF alone has the mirrored solution theta + pi, -omega too)         */
    float theta_reseed;  /* [rad] that angle                                                   */
    float slip;          /* [rad] mc_if_t.slip: at a full turn (2 pi) the rotor is out of step
                          * or the estimator does not see it (the caller's pull-out fault)     */
} mc_if_out_t;

/* A configuration is usable when its numbers are finite and ordered: 0 < w_l < w_h, i_f > 0,
 * accel > 0, 0 <= i_min <= i_f. */
bool mc_if_cfg_valid(const mc_if_cfg_t *c);
/* Closed loop, frame at rest. */
void mc_if_init(mc_if_t *s);
/* Into open loop at (theta, omega), the current placed for torque of sign `sign` (0 counts +). */
void mc_if_enter(mc_if_t *s, const mc_if_cfg_t *c, float theta, float omega, float sign);
/* As mc_if_enter at standstill with no angle known, after an alignment so the ramp does not
 * start from the unstable point: the frame held at theta - sign 90 deg for n_align periods, then
 * turned to theta over n_align more (a rotor at the first step's unstable point, 180 deg off,
 * meets torque in the second). */
void mc_if_align(mc_if_t *s, const mc_if_cfg_t *c, float theta, float sign);
/* One period. In closed loop it only watches for |omega_est| < w_l (then enters at the
 * estimate). */
void mc_if_step(mc_if_t *s, const mc_if_cfg_t *c, const mc_if_in_t *in, mc_if_out_t *out);

#endif
