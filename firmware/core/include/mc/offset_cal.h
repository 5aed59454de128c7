/* Current-sensor offsets that survive a turning rotor (protection issue, flying start). Not in
 * the thesis.
 *
 * WHY. The offsets are taken with the outputs off at every enable. At a standstill the phase
 * currents are zero and the plain average of the samples is the offset. Above the uncontrolled-
 * generation speed (sqrt3 |omega| psi_pm > Vdc) the diodes rectify the back-EMF into the link and
 * current flows all the time (on the thesis motor at 1500 rpm a sawtooth of up to 6.6 A per phase,
 * six teeth per electrical period, no phase ever at rest). A window that is not a whole number of
 * electrical half-periods averages part of that into the offset: the 6.4 ms window (0.8
 * periods at 1500 rpm) put about 0.8 A into the offsets, which the current loop then turned into
 * a 0.8 A current at the electrical frequency; the steady field-weakening current peaked at
 * 13.7 A for its 12.9 A reference.
 *
 * PRINCIPLE. The rectified current has half-wave symmetry, i(t + pi/|omega|) = -i(t) (a
 * symmetric machine and bridge at a steady speed), so two samples half an electrical period apart
 * sum to twice the offset, whatever the waveform:
 *     off_k = (1/M) sum_j (raw_k(j) + raw_k(j + L)) / 2,   L = pi / (|omega| Ts)          (O.1)
 * over the M pairs the kept samples hold (L is in general not a whole number of samples: the
 * later sample of each pair is interpolated linearly). A mean over a window is no substitute: over
 * a half-period it keeps 2/pi of the fundamental, and a whole period may not fit. The speed comes
 * later than the samples (from the catch, mc/catch.h, or from an angle sensor), so the samples
 * are kept (the last MC_OCAL_N) and (O.1) is evaluated once the speed is known. Where no pair fits
 * (half a period longer than the samples), (O.1) is not available and the plain mean stays
 * (below the generation speed no current flows with the outputs off, and the plain mean is
 * right); at least MC_OCAL_MIN_PAIRS pairs are asked for, against the noise. Where a pair's
 * interpolated sample straddles an abrupt edge of the waveform (the diodes commutate within a
 * sample) it is off by a share of the edge: with 25 or more samples per half-period the result
 * is within 0.02 A on the test's sawtooth of 6.5 A, with 12.6 within 0.16 A (tests/unit/core/
 * test_offset_cal.c).
 *
 * Units: ADC counts, rad/s electrical, s. */
#ifndef MC_OFFSET_CAL_H
#define MC_OFFSET_CAL_H
#include <stdbool.h>
#include <stdint.h>

#include "mc/types.h"

#define MC_OCAL_N 128u        /* samples kept: 12.8 ms at 10 kHz */
#define MC_OCAL_MIN_PAIRS 8u

typedef struct {
    uint16_t buf[MC_OCAL_N][3];   /* the last samples, a ring [counts] */
    uint32_t n;                   /* samples taken */
    float total[3];               /* sums of all of them [counts] */
} mc_ocal_t;

void mc_ocal_reset(mc_ocal_t *s);
void mc_ocal_add(mc_ocal_t *s, const uint16_t raw[3]);
/* the plain mean of all samples [counts]; false when none was taken */
bool mc_ocal_mean(const mc_ocal_t *s, float off[3]);
/* (O.1) at omega_e [rad/s el] with the period ts [s]; false (off untouched) when the kept
 * samples hold fewer than MC_OCAL_MIN_PAIRS pairs, or for a non-finite or zero speed */
bool mc_ocal_periodic(const mc_ocal_t *s, float omega_e, float ts, float off[3]);

/* The drive's offset calibration, a block around the samples above: the plain mean at every
 * enable (the outputs off), checked against mid-scale, and (O.1) once a speed is known; and the
 * phase currents with the offsets in force. Units: counts, A, rad/s el. */
typedef struct {
    uint32_t samples;             /* periods averaged (control.offset_cal_samples)             */
    float nominal, tol;           /* mid-scale and the plausible distance from it [counts]     */
    float amps_per_count;         /* [A / count]                                               */
    float ts;                     /* [s]                                                        */
} mc_offsets_cfg_t;

typedef struct {
    mc_ocal_t ocal;               /* this enable's samples                                      */
    uint32_t count;               /* periods since the enable                                   */
    float offset[3];              /* in force [counts]                                          */
    bool moved;                   /* (O.1) changed them in this period (the caller clears it)   */
} mc_offsets_t;

typedef enum {
    MC_OFFSETS_COLLECTING = 0,    /* a sample taken, more to come                               */
    MC_OFFSETS_DONE,              /* the last sample: the mean is in force                      */
    MC_OFFSETS_FAILED,            /* the mean is implausible (or none): nothing changed         */
    MC_OFFSETS_COUNTING           /* done earlier: the periods since the enable go on counting  */
} mc_offsets_status_t;

/* At init: mid-scale. */
void mc_offsets_init(mc_offsets_t *s, const mc_offsets_cfg_t *c);
/* An enable: the calibration again (the offsets in force stay until it is done). */
void mc_offsets_restart(mc_offsets_t *s);
/* One period of the calibration with the outputs off: the sample raw [counts]. */
mc_offsets_status_t mc_offsets_add(mc_offsets_t *s, const mc_offsets_cfg_t *c, const uint16_t raw[3]);
/* Once the speed omega is known [rad/s el]: (O.1) over this enable's samples, if it applies and
 * gives plausible offsets; then the samples are dropped (a later catch at another speed would
 * pair them at the wrong lag). true: the offsets moved (s->moved set), *di the change of the
 * stator-frame current this makes (new minus old) [A]; false: nothing changed, *di zero. */
bool mc_offsets_at_speed(mc_offsets_t *s, const mc_offsets_cfg_t *c, float omega, mc_ab_t *di);
/* The phase currents of a raw sample with the offsets in force [A]. */
static inline mc_abc_t mc_offsets_currents(const mc_offsets_t *s, const mc_offsets_cfg_t *c, const uint16_t raw[3])
{
    const float k = c->amps_per_count;
    return (mc_abc_t){((float)raw[0] - s->offset[0]) * k, ((float)raw[1] - s->offset[1]) * k,
                      ((float)raw[2] - s->offset[2]) * k};
}

#endif
