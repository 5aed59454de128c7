/* ePWM driver of the AM263x port: three synchronised up-down modules, complementary outputs with
 * dead band, CMPA shadowed to counter zero, ADC SOCA at counter zero, trip zone as the safe state.
 * Register facts: am263x/regs_epwm.h (TRM: ePWM Time-Base, Counter-Compare, Action-Qualifier,
 * Dead-Band, Trip-Zone and Event-Trigger Submodule Registers). The convention (duty = on-fraction
 * of output A, A high while the counter is above CMPA) is documented in am263x/port.h. */
#include <math.h>
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_epwm.h"
#include "am263x/regs_soc.h"

#define PRD_MIN 100.0f

bool am263x_pwm_timing(uint32_t clk_hz, float f_pwm_hz, float dead_time_s, uint16_t *prd, uint16_t *db)
{
    /* up-down: one period = 2 TBPRD TBCLK cycles (TRM: Time-Base Period and Frequency) */
    const float p = (float)clk_hz / (2.0f * f_pwm_hz);
    const float d = dead_time_s * (float)clk_hz;
    if (!(p >= PRD_MIN && p <= 65535.0f)) {
        return false;
    }
    const float pr = roundf(p);
    const float dr = roundf(d);
    /* the floor refuses 0 (shoot-through) and anything the power stage cannot switch apart */
    if (!(dr >= (float)AM263X_PWM_DB_MIN && dr <= (float)EPWM_DB_MAX && dr < 0.25f * pr)) {
        return false;
    }
    *prd = (uint16_t)pr;
    *db = (uint16_t)dr;
    return true;
}

uint16_t am263x_pwm_cmpa(hal_pwm_t *pwm, float d)
{
    if (!(d >= 0.0f && d <= 1.0f)) {
        if (d != d || d == INFINITY || d == -INFINITY) {
            pwm->nonfinite++;
            d = 0.5f;
        } else {
            pwm->clamped++;
            d = d < 0.0f ? 0.0f : 1.0f;
        }
    }
    /* A high while TBCTR > CMPA: on-fraction (TBPRD - CMPA) / TBPRD; CMPA >= AM263X_PWM_CMPA_MIN
     * (TI: CMPA >= 1 with load at zero; and the bootstrap supplies' recharge, see port.h) */
    const float c = roundf((1.0f - d) * (float)pwm->prd);
    return (uint16_t)(c < (float)AM263X_PWM_CMPA_MIN ? (float)AM263X_PWM_CMPA_MIN : c);
}

static void trip_all(const hal_pwm_t *pwm)
{
    for (uint32_t k = 0u; k < 3u; ++k) {
        am263x_wr16(pwm->epwm[k] + EPWM_TZCTL, EPWM_TZCTL_BOTH_LOW);
        am263x_wr16(pwm->epwm[k] + EPWM_TZFRC, EPWM_TZ_OST);
    }
}

bool am263x_pwm_init(hal_pwm_t *pwm, float f_pwm_hz, float dead_time_s)
{
    /* the safe state first: whatever the modules did before, A and B low */
    trip_all(pwm);
    uint16_t prd, db;
    if (!am263x_pwm_timing(pwm->clk_hz, f_pwm_hz, dead_time_s, &prd, &db)) {
        return false;
    }
    pwm->prd = prd;
    pwm->db = db;
    pwm->period_s = 2.0f * (float)prd / (float)pwm->clk_hz;
    pwm->dead_time_s = (float)db / (float)pwm->clk_hz;

    /* time-base clocks off while configuring: the counters start together in am263x_pwm_start */
    am263x_mmr_unlock(pwm->ctrl);
    am263x_wr32(pwm->ctrl + AM263X_CTRLSS_EPWM_CLKSYNC,
                am263x_rd32(pwm->ctrl + AM263X_CTRLSS_EPWM_CLKSYNC) & ~0x7u);
    am263x_mmr_lock(pwm->ctrl);

    const uint16_t cmpa = (uint16_t)(prd / 2u);
    for (uint32_t k = 0u; k < 3u; ++k) {
        const uintptr_t b = pwm->epwm[k];
        /* Time base: stopped, TBCLK = EPWMCLK (both dividers 1), TBPRD shadowed (loaded at zero),
         * on an emulation halt (a breakpoint) a soft stop: the counter stops when it next reaches
         * zero, where A is low and B high on every phase (the zero vector V000, the bootstraps
         * charged) instead of freezing mid-pulse or running on with stale duties. Module 0 master,
         * 1 and 2 load TBPHS = 0 on its sync-out and count up after it. */
        uint16_t tbctl = (uint16_t)(EPWM_TBCTL_SOFT_STOP | EPWM_TBCTL_CTRMODE_STOP);
        if (k != 0u) {
            tbctl = (uint16_t)(tbctl | EPWM_TBCTL_PHSEN | EPWM_TBCTL_PHSDIR);
        }
        am263x_wr16(b + EPWM_TBCTL, tbctl);
        am263x_wr16(b + EPWM_TBPRD, prd);
        am263x_wr32(b + EPWM_TBPHS, 0u);
        am263x_wr16(b + EPWM_TBCTR, 0u);
        am263x_wr16(b + EPWM_EPWMSYNCINSEL, (uint16_t)(k == 0u ? 0u : EPWM_SYNCIN_EPWM(0u)));
        am263x_wr16(b + EPWM_EPWMSYNCOUTEN, (uint16_t)(k == 0u ? EPWM_SYNCOUT_ZEROEN : 0u));
        /* CMPA shadowed, shadow -> active at counter zero; 50 % until the first duties */
        am263x_wr16(b + EPWM_CMPCTL, 0u);
        am263x_wr16(b + EPWM_CMPA_HI, cmpa);
        /* A: set on CAU, clear on CAD; B from the dead band */
        am263x_wr16(b + EPWM_AQCTLA, (uint16_t)((EPWM_AQ_SET << EPWM_AQ_CAU_SHIFT) |
                                                  (EPWM_AQ_CLEAR << EPWM_AQ_CAD_SHIFT)));
        am263x_wr16(b + EPWM_AQCTLB, 0u);
        am263x_wr16(b + EPWM_AQCSFRC, 0u);
        am263x_wr16(b + EPWM_DBCTL, EPWM_DBCTL_AHC);
        am263x_wr16(b + EPWM_DBRED, db);
        am263x_wr16(b + EPWM_DBFED, db);
        /* the hardware trip: TZ1 (INPUTXBAR output 0, routed by board.c from the gate driver's
         * nFAULT pin, docs/porting.md) as a one-shot source: a fault latches A and B low */
        am263x_wr16(b + EPWM_TZSEL, EPWM_TZSEL_OSHT1);
        /* master: SOCA at counter zero, every period */
        if (k == 0u) {
            am263x_wr16(b + EPWM_ETSEL, (uint16_t)(EPWM_ETSEL_SOCAEN |
                                                   (EPWM_ETSEL_SOCASEL_ZERO << EPWM_ETSEL_SOCASEL_SHIFT)));
            am263x_wr16(b + EPWM_ETPS, (uint16_t)(1u << EPWM_ETPS_SOCAPRD_SHIFT));
            am263x_wr16(b + EPWM_ETCLR, 0x000Du);   /* INT, SOCA, SOCB flags */
        } else {
            am263x_wr16(b + EPWM_ETSEL, 0u);
        }
    }
    return true;
}

void am263x_pwm_start(hal_pwm_t *pwm)
{
    for (uint32_t k = 0u; k < 3u; ++k) {
        const uintptr_t b = pwm->epwm[k];
        const uint16_t tbctl = am263x_rd16(b + EPWM_TBCTL);
        am263x_wr16(b + EPWM_TBCTL, (uint16_t)((tbctl & ~EPWM_TBCTL_CTRMODE_MASK) | EPWM_TBCTL_CTRMODE_UPDOWN));
    }
    am263x_mmr_unlock(pwm->ctrl);
    am263x_wr32(pwm->ctrl + AM263X_CTRLSS_EPWM_CLKSYNC,
                am263x_rd32(pwm->ctrl + AM263X_CTRLSS_EPWM_CLKSYNC) | 0x7u);
    am263x_mmr_lock(pwm->ctrl);
}

/* ---- hal/pwm.h */
void hal_pwm_set_duties(hal_pwm_t *pwm, float da, float db, float dc)
{
    am263x_wr16(pwm->epwm[0] + EPWM_CMPA_HI, am263x_pwm_cmpa(pwm, da));
    am263x_wr16(pwm->epwm[1] + EPWM_CMPA_HI, am263x_pwm_cmpa(pwm, db));
    am263x_wr16(pwm->epwm[2] + EPWM_CMPA_HI, am263x_pwm_cmpa(pwm, dc));
}

void hal_pwm_enable(hal_pwm_t *pwm, bool on)
{
    if (!on) {
        trip_all(pwm);   /* one-shot trip: both outputs low at once, held without the CPU */
        return;
    }
    for (uint32_t k = 0u; k < 3u; ++k) {
        am263x_wr16(pwm->epwm[k] + EPWM_TZCLR, (uint16_t)(EPWM_TZ_OST | EPWM_TZ_INT));
    }
}

bool hal_pwm_enabled(const hal_pwm_t *pwm)
{
    /* the trip-zone flags are the truth: a hardware trip shows here too */
    for (uint32_t k = 0u; k < 3u; ++k) {
        if ((am263x_rd16(pwm->epwm[k] + EPWM_TZFLG) & EPWM_TZ_OST) != 0u) {
            return false;
        }
    }
    return true;
}

float hal_pwm_period_s(const hal_pwm_t *pwm)
{
    return pwm->period_s;
}

float hal_pwm_dead_time_s(const hal_pwm_t *pwm)
{
    return pwm->dead_time_s;
}
