/* Flying-start catch: the rotor angle and speed of a machine that already turns, from the phase
 * currents alone (no voltage sensing), before the estimator takes over. Not in the thesis; the
 * principle is the one of its Step I (a known voltage, the current response), with the zero
 * vector V(000) as the known voltage and the magnet's back-EMF as what the current reveals.
 *
 * PRINCIPLE. Under V(000) the stator voltage is zero, so (R neglected) the stator flux linkage
 * stands still in the stator frame while the magnet turns on: psi_ab(t) = psi_ab(t0). From
 * i = 0 at t0 (psi = psi_pm along d), after a rotation Delta = omega t the flux in the rotor
 * frame at t is psi_pm (cos Delta, -sin Delta), so with the linear model psi_d = Ld i_d + psi_pm,
 * psi_q = Lq i_q:
 *     i_d = psi_pm (cos Delta - 1) / Ld,     i_q = -psi_pm sin Delta / Lq                  (C.1)
 * i.e. mostly against q (braking), with a second-order part against d. The current's angle in
 * the stator frame is therefore
 *     phi = theta(t) + atan2(-sin Delta / Lq, (cos Delta - 1) / Ld)                         (C.2)
 * which gives theta from the measured phi once Delta (the sign and size of the speed) is known.
 * A single pulse cannot tell (theta, omega) from (theta + pi, -omega): to first order both give
 * the same current. Two equal pulses separated by T12 can: the current's direction turns with
 * the rotor, phi2 - phi1 = omega T12 (C.3), whose sign is the direction of rotation and whose
 * size is the speed (no psi_pm, no L in it). T12 is chosen from the first pulse's magnitude
 * (|omega| ~ |i| Lq / (psi_pm t)) for a rotation of about 20 deg: well above the angle noise
 * of a current of i_pulse, well below the pi where (C.3) aliases.
 *
 * PROGRAM (mc/phase_program.h calling convention; duties always V(000), only `off` toggles):
 *   wait:    outputs off until |i| <= i_rest (at most n_wait_max periods): none at an enable
 *            below the uncontrolled-generation speed, a few periods when a recovery restarts
 *            the catch; above that speed the diodes' current never rests and pulse 1 starts
 *            from it (the current differences of (C.1)-(C.3) are then exact only for Ld = Lq);
 *            Where the diodes' current flows in the wait, it flows in pulses that rise from about
 *            zero while the rotor turns a sixth of a turn and then fall: within one such pulse its
 *            direction is nearly fixed in the rotor frame, so in the stator frame it turns with the
 *            rotor, and the sum of its angle steps tells the direction of rotation with no current
 *            of the drive's own (C.5). Pulse 1 then starts at such a pulse's low (|i| below
 *            i_rest + 0.3 i_pulse) once the sign is known (or after n_wait_max), and with the
 *            sign known needs only i_pulse to give the angle;
 *   pulse 1: V(000) until |i - i(start)| >= i_pulse (or n_pulse_max periods). After n_probe
 *            periods a current below i_detect means the rotor stands (below omega_min): DONE,
 *            not moving (the caller goes on with the standstill start);
 *   gap:     outputs off (the diodes return the current to the link) for the rotation time,
 *            and until |i| <= i_rest (bounded);
 *   pulse 2: V(000) for exactly as long as pulse 1, so that the second-order part of (C.2) is
 *            the same in both and cancels in (C.3). It ends with the outputs on (the V(000)
 *            latched for the next period acts until the control's first duties), except where a
 *            period's mean rise |delta i2| / n1 is i_pulse or more: that period would double the
 *            current of a one-period pulse at speed (siemens-1ft7044-spm at half its base speed:
 *            9.7 A for an 8.06 A limit), so the outputs go off and come on with the control's
 *            duties, as after a single pulse;
 *   result:  omega from (C.3), theta at the last sample from (C.2) with Delta = omega t_pulse.
 * HIGH SPEED: where the back-EMF's line-to-line peak sqrt3 |omega| psi_pm comes near Vdc, the
 * gap cannot be a gap: the diodes rectify and the current grows while the outputs are off
 * (uncontrolled generation). There, pulse 1 is lengthened to 2 i_pulse and the sign is read from
 * its own curvature: (C.2) applied to its middle and last samples gives two angles whose
 * difference must be sigma |Delta| (1 - n_mid / n1); the wrong sign misses by about
 * |Delta| (1 - n_mid / n1) |2 - Lq / Ld| (C.4). When that margin is too small (Lq near 2 Ld) the
 * two-pulse method runs anyway.
 * (C.5) PASSIVE SIGN: the wait sums wrap(phi_k - phi_k-1) over consecutive samples of the diodes'
 * current both above i_pulse / 4 and rising (the same pulse); at least MC_CATCH_PASSIVE_N steps
 * summing to more than 10 deg, 80 % of them one way, give the sign sigma. The single pulse then
 * uses it with (C.1) for |Delta| and (C.2) for theta. The rotation in the rotor frame within a
 * diode pulse is small against the rotor's and in its direction (measured: the thesis motor at
 * 1500 rpm turns the current 6.2 deg per period for the rotor's 4.5), so only the sign is used.
 * (C.6) KNOWN-VECTOR PULSE. Where the diodes conduct and (C.5) has the sign, a V(000) pulse is a
 * period of lag that the field-weakening entry after it must carry (mc/fw_entry.h): on the thesis
 * motor at 1500 rpm the best hand-over a search finds from a V(000) pulse's current is 13.6 A, from
 * a pulse of the hexagon's corner against the back-EMF 12.6 A (`mctools fly-current`,
 * docs/protection.md). So the pulse there is an active vector u (a corner, 2 vdc / 3, the gates
 * held one period): the one nearest to where the entry's first vector will point, from the diode
 * current's direction phi_i (against q: theta ~ phi_i + sigma pi/2, the entry's vector ~ theta +
 * sigma (pi/2 + 50 deg), so phi_i - sigma 130 deg; a corner is within 30 deg of it, and the search
 * finds no loss within 40 deg). Its duties are latched while the outputs are still off, so the pulse
 * starts at the low with the enable, and they are written once more so that the same vector
 * acts in the period after, when the entry's first vector is computed. With the flux change
 * known, Delta psi_s = u Ts (+ the devices' drop), and the linear model psi_s = L i + psi_pm e^{j theta}
 * with L = Lbar + (Ld - Lq)/2 e^{j 2 theta} conj(.) (stator frame, complex):
 *     w = Delta psi_s - Lbar Delta i - (Ld - Lq)/2 (e^{j 2 theta1} conj(i1) - e^{j 2 theta0} conj(i0))
 *       = psi_pm (e^{j theta1} - e^{j theta0}) = 2 psi_pm sin(Delta / 2) j e^{j theta_m}            (C.6)
 * gives |Delta| = 2 asin(|w| / (2 psi_pm)), theta_m = arg(w) - sigma pi/2, theta1 = theta_m +
 * Delta / 2 from one period, the saliency term by three fixed-point passes (from 0). With u = 0 it
 * is (C.1), (C.2) for Ld = Lq. FAILED when |w| exceeds 2 psi_pm (a model or sensor far off; a
 * psi_pm only a few times too small reads a speed as many times too high, which the over-speed
 * check then trips on at RUN entry: a checked fault, not a guess that runs). A check against the
 * diode pulses' rate (six to a turn) was tried and dropped: near the generation speed their
 * falls are not regular enough (1100-1200 rpm: a fall 3 periods after another).
 * THE LIMIT. The shortest pulse is one period: from i = 0 at speed w it drives
 * psi |((cos w Ts - 1) / Ld, sin w Ts / Lq)| by (C.1), ~ w psi Ts / L, whatever voltage the period
 * holds (the back-EMF's direction is what the pulse is to find). Below the generation speed this
 * is at most one period of Vdc / sqrt3 across L: on a motor whose psi / L is several times its
 * rating at a low f_s, more than the current limit (siemens-1ft7044-spm at 8 kHz: 9.9 A for
 * 8.06 A at its base speed; minicheetah-24v-lv at 20 kHz: 20 A for 14 A). The configuration
 * reports the speed up to which the catch keeps 1.1 x the limit and the period that would keep
 * it at every speed (w_limit, ts_cover), and does not refuse: a rotor that fast at the enable is
 * the exception, and the pulse ends after that one period (siemens at its generation speed:
 * 10.3 A, below its 12.1 A trip; minicheetah above ~2400 rpm: over its 21 A trip, a fault).
 * V(000) PULSES, (C.1)-(C.5): FAILED when the rotation is too small to give its sign (|phi2 - phi1| < 5 deg) or the second
 * current does not fit (C.1) within a factor of 2 (a model or sensor far off): the caller faults
 * rather than guess. The current peaks at about i_pulse plus one period's rise.
 *
 * Units SI: A, V, s, H, Wb, rad, rad/s electrical. */
#ifndef MC_CATCH_H
#define MC_CATCH_H
#include <math.h>
#include <stdint.h>

#include "mc/initpos.h"
#include "mc/types.h"

typedef struct {
    float ts;                 /* [s] */
    float ld, lq, psi_pm;     /* the estimator's model at i = 0 [H, H, Wb] */
    float i_pulse;            /* |delta i| that ends a measuring pulse [A] */
    float i_detect;           /* below this after n_probe periods: standing [A] */
    float i_rest;             /* the gap lasts until |i| is below this [A] */
    float rot_target;         /* rotation between the two pulses' ends [rad] */
    uint32_t n_probe;         /* [periods] */
    uint32_t n_pulse_max;     /* [periods] */
    uint32_t n_gap_max;       /* [periods] */
    uint32_t n_wait_max;      /* [periods] the longest wait for the current to rest first: it
                                 decays through the diodes within a period or two, unless the
                                 back-EMF exceeds the link (then it never does, and the wait
                                 lasts until (C.5) has its sign and a diode pulse's low) */
    float high_speed_share;   /* single-pulse sign above sqrt3 |omega| psi_pm > this x Vdc */
    float v_device;           /* the power devices' on-state drop [V] (0: none): under V(000) it
                                 opposes each phase current, acts like a resistance and, at low
                                 speed, bends the current away from (C.1); its flux is added up
                                 and its current taken out before (C.2), (C.3) */
    float i_band;             /* soft sign of that drop: linear within +-i_band [A] */
    float w_limit;            /* [rad/s el] informational, for the configuration's report (not used
                                 by the catch): above it one V(000) period, the shortest pulse,
                                 drives more than 1.1 x the current limit by (C.1); 0: not below
                                 the generation speed Vdc / (sqrt3 psi_pm), where the diodes conduct
                                 and (C.6) replaces the V(000) pulse */
    float ts_cover;           /* [s] informational: the longest period whose V(000) pulse keeps
                                 1.1 x the limit up to the generation speed (with w_limit > 0) */
} mc_catch_cfg_t;

#define MC_CATCH_HIST 16      /* samples of pulse 1 kept for the single-pulse sign (C.4) */
#define MC_CATCH_PASSIVE_N 4u /* angle steps of the diodes' current for a passive sign (C.5) */

typedef struct {
    mc_catch_cfg_t cfg;
    int phase;                /* internal */
    uint32_t n, n1, n_gap, calls, end1;
    mc_ab_t i0, di1, di2;     /* pulse start current, both pulses' current changes [A] */
    mc_ab_t hist[MC_CATCH_HIST];  /* pulse 1: delta i after n = 1..16 periods */
    mc_ab_t hist_psi[MC_CATCH_HIST];  /* ... and the device drop's flux by then [Wb] */
    mc_ab_t i_last, psi, psi1, psi2;  /* last sample; the drop's flux in this pulse, pulses 1, 2 */
    bool single;              /* the sign came from pulse 1 alone (C.4) or the wait (C.5) */
    float pas_sum, pas_abs;   /* (C.5): the wait's summed angle steps and their magnitudes [rad] */
    uint32_t pas_n;           /* ... and how many */
    int passive;              /* (C.5) sign: +1, -1, or 0 (none) */
    bool diodes;              /* the wait saw the diodes' current (above i_pulse / 4) */
    mc_ab_t i_dir;            /* (C.6): the diodes' current since their last real low [A] */
    mc_ab_t i_low;            /* (C.6): the current at that low [A] */
    int corner_w, corner_a;   /* (C.6): the corner written this period, the one latched (-1: V(000)) */
    mc_ab_t u_kv;             /* (C.6): the pulse's voltage, stator frame [V] */
    bool kv;                  /* (C.6): this pulse is a known active vector */
    mc_ip_status_t status;
    /* results */
    bool moving;              /* false: the rotor stands (below omega_min) */
    float theta;              /* at the last sample [rad], (C.2) */
    float omega;              /* [rad/s el], (C.3) */
    float rotation;           /* phi2 - phi1 [rad] */
    float fit;                /* |delta i2| / (C.1) */
    float i_peak;             /* [A] */
} mc_catch_t;

/* A diode pulse's low (C.5): where a pulse may start, for the catch and for a sensor drive
 * entering RUN above the uncontrolled-generation speed. */
static inline bool mc_catch_at_low(const mc_catch_cfg_t *c, mc_ab_t i_ab)
{
    return sqrtf(i_ab.alpha * i_ab.alpha + i_ab.beta * i_ab.beta) <= c->i_rest + 0.3f * c->i_pulse;
}

/* false on a bad configuration (non-positive or non-finite values): the engine then FAILs */
bool mc_catch_start(mc_catch_t *s, const mc_catch_cfg_t *cfg);
/* One period: sample i_ab; *duty: V(000), or a corner of the hexagon (C.6), acting a period later;
 * *off: the outputs are off from this sample on (a gate disable acts at once, unlike the duties).
 * A (C.6) pulse ends with the outputs on and its corner written again: the caller's control
 * takes over with that vector acting until its own first duties. */
mc_ip_status_t mc_catch_step(mc_catch_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty, bool *off);

/* The drive's side of the catch (startup.c). */

/* What a finished catch means for the drive. */
typedef enum {
    MC_CATCH_TURNING = 0,   /* RUN from the caught angle and speed (the field-weakening entry
                               first, mc/fw_entry.h)                                            */
    MC_CATCH_STANDING,      /* below omega_min: the standstill start (Step I, or RUN from the
                               angle given with the enable)                                     */
    MC_CATCH_NO_FIT,        /* FAILED (no sign, or (C.1) does not fit): MC_FAULT_INIT_POS      */
    MC_CATCH_STALE          /* a recovery that finds the rotor standing has no angle to go on
                               with (the one given with the enable is stale) and no start that
                               finds one: the reason that started it stands                     */
} mc_catch_outcome_t;

/* st: the program's last status (DONE or FAILED); moving: its verdict; recovering: the catch
 * restarted after a running fault (protection.lock_action = recover); finds_angle: the standstill
 * start is the three-step one (it finds the angle itself). */
mc_catch_outcome_t mc_catch_outcome(mc_ip_status_t st, bool moving, bool recovering, bool finds_angle);

/* A RUN entry at speed, the drive's state: the catch's, or an angle-sensor drive's above the
 * uncontrolled-generation speed (which needs no catch, but waits as it does (C.5) for a diode
 * pulse's low and latches the entry's first corner as (C.6) does). */
typedef struct {
    bool corner;            /* the corner is latched (mc_catch_entry_corner) with the outputs off:
                               it acts with them from the entry on                              */
    bool gate_on_next;      /* RUN's first duties were latched with the outputs off: they come on
                               with them at the next period's start                             */
} mc_catch_entry_t;

/* An angle-sensor drive waits (outputs off), at most the catch's longest wait (waited periods so
 * far), for a diode pulse's low (mc_catch_at_low) before it enters RUN. */
static inline bool mc_catch_sensor_waits(const mc_catch_cfg_t *c, uint32_t waited, mc_ab_t i_ab)
{
    return waited < c->n_wait_max && !mc_catch_at_low(c, i_ab);
}

/* The corner of the hexagon the field-weakening entry would start with, for a rotor at theta
 * [rad, a period old] turning at omega [rad/s el]: the angle + sign(omega) 135 deg in the middle
 * of the period after the next sample, as (C.6). -1 (none) where the entry will not run: the flux
 * psi_pm can be held with u_land [V] (mc/fw_entry.h), or no link voltage. */
int mc_catch_entry_corner(const mc_catch_cfg_t *c, float theta, float omega, float vdc, float u_land);

#endif
