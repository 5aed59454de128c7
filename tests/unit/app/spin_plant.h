/* A spinning machine for the drive's tests (test_startup.c, test_angle_source_extra.c): the host
 * HAL's PWM and ADC around mc_drive_isr. Double precision, no noise. */
#ifndef SPIN_PLANT_H
#define SPIN_PLANT_H
#include <math.h>
#include <stdint.h>

#include "hal_host/host.h"
#include "mc/drive.h"
#include "mc/transforms.h"

/* A turning rotor on the drive's defaults (the thesis motor: 10.5 / 12.9 mH, 0.34305 Wb, 300 V),
 * R = 0, the speed constant. With the outputs on the latched duties' line-to-neutral vector
 * moves the stator flux (V(000) keeps it); with them off the diodes rectify the back-EMF into the
 * link above the generation speed: a sawtooth current, six teeth to the electrical turn, rising
 * to a peak that grows with the back-EMF's excess over the link (6.6 A at 1500 rpm, 0.3 A at
 * 1003 rpm) along a direction fixed in the rotor frame (braking: against q for w > 0, and lean
 * times that against d), a function of the rotor angle, so with half-wave symmetry (mc/offset_cal.h);
 * below the generation speed none. The current follows the flux: i_d = (psi_d - psi_pm) / Ld,
 * i_q = psi_q / Lq (rotor frame). */
typedef struct {
    double w, th, pa, pb, lean;
    double th_sample;   /* the angle at the last sample */
} spin_t;

#define SPIN_LD 10.5e-3
#define SPIN_LQ 12.9e-3
#define SPIN_PSI 0.34305
#define SPIN_VDC 300.0

static inline void spin_current(const spin_t *p, double *ia, double *ib)
{
    const double c = cos(p->th), s = sin(p->th);
    const double pd = c * p->pa + s * p->pb, pq = -s * p->pa + c * p->pb;
    const double id = (pd - SPIN_PSI) / SPIN_LD, iq = pq / SPIN_LQ;
    *ia = c * id - s * iq;
    *ib = s * id + c * iq;
}

static inline void spin_diodes(spin_t *p)
{
    /* the peak grows with the line-to-line back-EMF's excess over the link: 6.6 A at 1500 rpm */
    const double excess = sqrt(3.0) * fabs(p->w) * SPIN_PSI - SPIN_VDC;
    double a = 0.0;
    if (excess > 0.0) {
        const double x = (p->w > 0.0 ? 6.0 : -6.0) * p->th / (2.0 * 3.14159265358979);   /* rising in time */
        a = 6.6 * excess / (sqrt(3.0) * 785.398 * SPIN_PSI - SPIN_VDC) * (x - floor(x));
    }
    const double id = -p->lean * a, iq = (p->w > 0.0 ? -1.0 : 1.0) * a;
    const double c = cos(p->th), s = sin(p->th);
    const double pd = SPIN_LD * id + SPIN_PSI, pq = SPIN_LQ * iq;
    p->pa = c * pd - s * pq;
    p->pb = s * pd + c * pq;
}

/* One period of the rig on the spinning machine: the duties written last period latched, the
 * diodes' current where the outputs are off, the sample, the ISR, then the machine over the
 * period with what acts in it. Returns the current sampled [A] (the raw counts are in adc). */
static inline mc_ab_t spin_period_on(spin_t *p, mc_drive_t *d, hal_pwm_t *pwm, hal_adc_t *adc)
{
    hal_host_pwm_latch(pwm);
    if (!hal_pwm_enabled(pwm)) {
        spin_diodes(p);
    }
    double ia, ib;
    spin_current(p, &ia, &ib);
    const mc_abc_t i = mc_clarke_inv((mc_ab_t){(float)ia, (float)ib});
    const float k = d->cfg->blk.offs.amps_per_count, nominal = (float)d->cfg->blk.offs.nominal;
    adc->sample.i[0] = (uint16_t)lrintf(nominal + i.a / k);
    adc->sample.i[1] = (uint16_t)lrintf(nominal + i.b / k);
    adc->sample.i[2] = (uint16_t)lrintf(nominal + i.c / k);
    p->th_sample = p->th;
    mc_drive_isr(d);
    p->th = remainder(p->th + p->w * 1e-4, 2.0 * 3.14159265358979);
    if (hal_pwm_enabled(pwm)) {
        const double va = (pwm->active[0] - 0.5) * SPIN_VDC, vb = (pwm->active[1] - 0.5) * SPIN_VDC,
                     vc = (pwm->active[2] - 0.5) * SPIN_VDC;
        p->pa += 1e-4 * (2.0 / 3.0) * (va - 0.5 * (vb + vc));
        p->pb += 1e-4 * (vb - vc) / sqrt(3.0);
    }
    return (mc_ab_t){(float)ia, (float)ib};
}

#endif
