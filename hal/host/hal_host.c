/* Host HAL port: the peripheral "registers" are the structs in hal_host/host.h. */
#include "hal_host/host.h"
#include <math.h>
#include <stddef.h>

void hal_host_pwm_init(hal_pwm_t *pwm, float period_s, float dead_time_s)
{
    pwm->period_s = period_s;
    pwm->dead_time_s = dead_time_s;
    for (int k = 0; k < 3; ++k) {
        pwm->shadow[k] = 0.5f;
        pwm->active[k] = 0.5f;
    }
    pwm->enabled = false;
    pwm->writes = 0u;
    pwm->on_edges = 0u;
    pwm->nonfinite = 0u;
    pwm->counts = 0u;
    pwm->off_time = false;
}

void hal_host_pwm_set_counts(hal_pwm_t *pwm, uint32_t counts, bool off_time)
{
    pwm->counts = counts;
    pwm->off_time = off_time;
    for (int k = 0; k < 3; ++k) {
        pwm->cmp_shadow[k] = pwm->cmp_active[k] = off_time ? counts - counts / 2u : counts / 2u;
    }
}

void hal_host_pwm_latch(hal_pwm_t *pwm)
{
    for (int k = 0; k < 3; ++k) {
        pwm->active[k] = pwm->shadow[k];
        pwm->cmp_active[k] = pwm->cmp_shadow[k];
    }
}

static uint32_t compare(const hal_pwm_t *pwm, float d)
{
    const float n = (float)pwm->counts;
    return pwm->off_time ? (uint32_t)roundf((1.0f - d) * n) : (uint32_t)lroundf(d * n);
}

/* A NaN compares false both ways, so a plain clamp would pass it on: it becomes 50 % (zero
 * voltage) here, and is counted. */
static float clamp01(hal_pwm_t *pwm, float x)
{
    if (!(x >= 0.0f && x <= 1.0f)) {
        if (x != x || x == INFINITY || x == -INFINITY) {
            pwm->nonfinite++;
            return 0.5f;
        }
        return x < 0.0f ? 0.0f : 1.0f;
    }
    return x;
}

void hal_pwm_set_duties(hal_pwm_t *pwm, float da, float db, float dc)
{
    pwm->shadow[0] = clamp01(pwm, da);
    pwm->shadow[1] = clamp01(pwm, db);
    pwm->shadow[2] = clamp01(pwm, dc);
    if (pwm->counts > 0u) {
        for (int k = 0; k < 3; ++k) {
            pwm->cmp_shadow[k] = compare(pwm, pwm->shadow[k]);
        }
    }
    pwm->writes++;
}

void hal_pwm_enable(hal_pwm_t *pwm, bool on)
{
    pwm->on_edges += on && !pwm->enabled ? 1u : 0u;
    pwm->enabled = on;
}

bool hal_pwm_enabled(const hal_pwm_t *pwm)
{
    return pwm->enabled;
}

float hal_pwm_period_s(const hal_pwm_t *pwm)
{
    return pwm->period_s;
}

float hal_pwm_dead_time_s(const hal_pwm_t *pwm)
{
    return pwm->dead_time_s;
}

void hal_adc_read(hal_adc_t *adc, hal_adc_sample_t *out)
{
    *out = adc->sample;
}

void hal_qep_read(hal_qep_t *qep, hal_qep_sample_t *out)
{
    *out = qep->sample;
}

uint32_t hal_qep_counts_per_rev(const hal_qep_t *qep)
{
    return qep->counts_per_rev;
}

uint32_t hal_time_us(const hal_time_t *t)
{
    return t->us;
}

/* The host measures the ISR with a clock (mcsim) and by instruction counts (PIL), not by markers. */
void hal_stage_mark(hal_stage_t stage)
{
    (void)stage;
}

/* ---- hal/watchdog.h */
void hal_host_wdg_start(hal_wdg_t *wdg, uint32_t timeout_us, hal_pwm_t *pwm)
{
    wdg->timeout_us = timeout_us;
    wdg->left_us = timeout_us;
    wdg->kicks = 0u;
    wdg->expired = false;
    wdg->pwm = pwm;
    wdg->isr_runs = 0u;
    wdg->seen = 0u;
}

void hal_wdg_kick(hal_wdg_t *wdg)
{
    wdg->kicks++;
    if (!wdg->expired) {
        wdg->left_us = wdg->timeout_us;
    }
}

void hal_wdg_service(hal_wdg_t *wdg)
{
    if (wdg->isr_runs != wdg->seen) {
        wdg->seen = wdg->isr_runs;
        hal_wdg_kick(wdg);
    }
}

bool hal_host_wdg_elapse(hal_wdg_t *wdg, uint32_t dt_us)
{
    if (wdg->timeout_us == 0u || wdg->expired) {
        return wdg->expired;
    }
    if (dt_us >= wdg->left_us) {
        wdg->expired = true;
        wdg->left_us = 0u;
        if (wdg->pwm != NULL) {
            hal_pwm_enable(wdg->pwm, false);
        }
        return true;
    }
    wdg->left_us -= dt_us;
    return false;
}
