/* Flying-start catch (mc/catch.h): zero-vector pulses (C.1)-(C.5), or one known corner (C.6). */
#include "mc/catch.h"

#include <math.h>
#include <stddef.h>

#include "mc/angle.h"
#include "mc/sincos.h"
#include "mc/svpwm.h"
#include "mc/transforms.h"

enum { WAIT = 0, PULSE1, GAP, PULSE2, END };

static bool finite_pos(float x)
{
    return x > 0.0f && x < 3.0e38f;
}

bool mc_catch_start(mc_catch_t *s, const mc_catch_cfg_t *cfg)
{
    *s = (mc_catch_t){.cfg = *cfg, .phase = WAIT, .status = MC_IP_RUNNING, .corner_w = -1, .corner_a = -1};
    const bool ok = finite_pos(cfg->ts) && finite_pos(cfg->ld) && finite_pos(cfg->lq) && finite_pos(cfg->psi_pm) &&
                    finite_pos(cfg->i_pulse) && finite_pos(cfg->i_detect) && cfg->i_detect <= cfg->i_pulse &&
                    finite_pos(cfg->i_rest) && finite_pos(cfg->rot_target) && cfg->rot_target < 2.0f &&
                    cfg->n_probe >= 1u && cfg->n_pulse_max >= cfg->n_probe && cfg->n_gap_max >= 2u &&
                    cfg->n_wait_max <= cfg->n_gap_max &&
                    finite_pos(cfg->high_speed_share) && cfg->v_device >= 0.0f && cfg->v_device < 1.0e3f &&
                    finite_pos(cfg->i_band);
    if (!ok) {
        s->status = MC_IP_FAILED;
        s->phase = END;
    }
    return ok;
}

static float mag(mc_ab_t v)
{
    return sqrtf(v.alpha * v.alpha + v.beta * v.beta);
}

static mc_ab_t sub(mc_ab_t a, mc_ab_t b)
{
    return (mc_ab_t){a.alpha - b.alpha, a.beta - b.beta};
}

/* The current a stator-frame flux change psi drives at rotor angle theta: L^-1 in the rotor
 * frame, back to the stator frame (the linear model of (C.1)). */
static mc_ab_t current_of(const mc_catch_cfg_t *c, mc_ab_t psi, float theta)
{
    const mc_sincos_t sc = mc_sincos(mc_wrap_pi(theta));
    const mc_dq_t p = mc_park(psi, sc);                              /* (2.5) */
    return mc_park_inv((mc_dq_t){p.d / c->ld, p.q / c->lq}, sc);
}

/* Both pulses measured: (C.3) for the speed, (C.2) for the angle, (C.1) as the plausibility.
 * With a device drop, the current changes first lose what the drop's flux drove (evaluated at
 * the angle found without it, then once more with the better angle). */
static mc_ip_status_t conclude(mc_catch_t *s)
{
    const mc_catch_cfg_t *c = &s->cfg;
    const float t12 = (float)(s->calls - 1u - s->end1) * c->ts;   /* end of pulse 1 to end of pulse 2 */
    mc_ab_t d1 = s->di1, d2 = s->di2;
    float kd = 0.0f, kq = 0.0f;
    for (int pass = 0; pass < (c->v_device > 0.0f ? 3 : 1); ++pass) {
        if (pass > 0) {
            d1 = sub(s->di1, current_of(c, s->psi1, s->theta - s->omega * t12));
            d2 = sub(s->di2, current_of(c, s->psi2, s->theta));
        }
        const float phi1 = atan2f(d1.beta, d1.alpha);
        const float phi2 = atan2f(d2.beta, d2.alpha);
        s->rotation = mc_wrap_pi(phi2 - phi1);
        s->omega = s->rotation / t12;                                           /* (C.3) */
        const float delta = s->omega * (float)s->n1 * c->ts;
        kd = (cosf(delta) - 1.0f) / c->ld;                                      /* (C.1) / psi_pm */
        kq = -sinf(delta) / c->lq;
        s->theta = mc_wrap_pi(phi2 - atan2f(kq, kd));                           /* (C.2) */
    }
    s->fit = mag(d2) / (c->psi_pm * sqrtf(kd * kd + kq * kq));
    /* the sign needs a rotation well above the angle noise; beyond 2.5 rad (C.3) may alias */
    const float r = fabsf(s->rotation);
    const bool ok = r >= 0.0873f && r <= 2.5f && s->fit >= 0.5f && s->fit <= 2.0f;
    s->moving = ok;
    return ok ? MC_IP_DONE : MC_IP_FAILED;
}

/* (C.2)'s offset: the current's angle minus the rotor's after a rotation delta from i = 0 */
static float offset_c2(const mc_catch_cfg_t *c, float delta)
{
    return atan2f(-sinf(delta) / c->lq, (cosf(delta) - 1.0f) / c->ld);
}

/* |Delta| from |delta i| by (C.1), a fixed-point iteration on the first-order guess */
static float rotation_of(const mc_catch_cfg_t *c, float di)
{
    float d = di * c->lq / c->psi_pm;
    for (int k = 0; k < 3; ++k) {
        const float kd = (cosf(d) - 1.0f) / c->ld, kq = sinf(d) / c->lq;
        const float per = c->psi_pm * sqrtf(kd * kd + kq * kq) / d;   /* |i| / Delta */
        d = di / per;
    }
    return d;
}

/* (C.4): the sign from pulse 1's middle and last samples; false when the two signs do not
 * differ clearly enough (then the two-pulse method decides). */
static bool single_pulse_sign(mc_catch_t *s)
{
    const mc_catch_cfg_t *c = &s->cfg;
    const uint32_t n1 = s->n1, nm = n1 / 2u;
    const float frac = (float)nm / (float)n1;
    float r[2], th_end[2], dls[2];
    for (int k = 0; k < 2; ++k) {
        /* each sign on its own: its angles, then (with a device drop) the current changes without
         * the drop's part at those angles, and its angles again */
        const float sg = k == 0 ? 1.0f : -1.0f;
        mc_ab_t a = s->hist[nm - 1u], b = s->hist[n1 - 1u];
        float th_e = 0.0f, th_m = 0.0f, dl = 0.0f;
        for (int pass = 0; pass < (c->v_device > 0.0f ? 3 : 1); ++pass) {
            if (pass > 0) {
                a = sub(s->hist[nm - 1u], current_of(c, s->hist_psi[nm - 1u], th_m));
                b = sub(s->hist[n1 - 1u], current_of(c, s->hist_psi[n1 - 1u], th_e));
            }
            dl = rotation_of(c, mag(b));
            th_e = atan2f(b.beta, b.alpha) - offset_c2(c, sg * dl);
            th_m = atan2f(a.beta, a.alpha) - offset_c2(c, sg * dl * frac);
        }
        r[k] = fabsf(mc_wrap_pi(th_e - th_m - sg * dl * (1.0f - frac)));
        th_end[k] = th_e;
        dls[k] = dl;
    }
    const float dl = 0.5f * (dls[0] + dls[1]);
    /* the wrong sign misses by |Delta| (1 - frac) |2 - Lq/Ld|: ask for half of it, >= 2 deg */
    const float miss = dl * (1.0f - frac) * fabsf(2.0f - c->lq / c->ld);
    if (!(miss >= 0.07f) || !(fabsf(r[0] - r[1]) >= 0.5f * miss)) {
        return false;
    }
    const int best = r[0] < r[1] ? 0 : 1;
    const float sg = best == 0 ? 1.0f : -1.0f;
    s->omega = sg * dls[best] / ((float)n1 * c->ts);
    s->theta = mc_wrap_pi(th_end[best]);
    s->rotation = sg * dls[best];
    s->fit = 1.0f;
    s->single = true;
    s->moving = true;
    return true;
}

/* (C.6): the corner nearest to phi_i - sigma 130 deg (the entry's first vector) */
static int corner_for(mc_ab_t i_dir, int sigma)
{
    return mc_svpwm_corner_near(atan2f(i_dir.beta, i_dir.alpha) - (float)sigma * 2.2689280f);   /* 130 deg */
}

/* (C.6): angle and speed from one period of the known vector u_kv (plus the drop's flux psi):
 * i0, i1 the currents at its start and end. */
static bool known_vector(mc_catch_t *s, mc_ab_t i0, mc_ab_t i1)
{
    const mc_catch_cfg_t *c = &s->cfg;
    const float sg = (float)s->passive;
    const float lbar = 0.5f * (c->ld + c->lq), dl2 = 0.5f * (c->ld - c->lq);
    const mc_ab_t dpsi = {s->u_kv.alpha * c->ts + s->psi.alpha, s->u_kv.beta * c->ts + s->psi.beta};
    float th0 = 0.0f, th1 = 0.0f, dl = 0.0f;
    for (int pass = 0; pass < 3; ++pass) {
        mc_ab_t w = {dpsi.alpha - lbar * (i1.alpha - i0.alpha), dpsi.beta - lbar * (i1.beta - i0.beta)};
        if (pass > 0) {
            /* (Ld - Lq)/2 e^{j 2 theta} conj(i): the saliency's part of L i */
            const float c1 = cosf(2.0f * th1), s1 = sinf(2.0f * th1), c0 = cosf(2.0f * th0), s0 = sinf(2.0f * th0);
            w.alpha -= dl2 * ((c1 * i1.alpha + s1 * i1.beta) - (c0 * i0.alpha + s0 * i0.beta));
            w.beta -= dl2 * ((s1 * i1.alpha - c1 * i1.beta) - (s0 * i0.alpha - c0 * i0.beta));
        }
        const float x = mag(w) / (2.0f * c->psi_pm);
        if (!(x < 1.0f)) {
            return false;   /* more than the magnet can give: the model or the sensing is far off */
        }
        dl = sg * 2.0f * atan2f(x, sqrtf(1.0f - x * x));                       /* (C.6) */
        const float thm = atan2f(w.beta, w.alpha) - sg * 1.5707963f;
        th0 = thm - 0.5f * dl;
        th1 = thm + 0.5f * dl;
    }
    s->n1 = 1u;
    s->di1 = sub(i1, i0);
    s->omega = dl / c->ts;
    s->theta = mc_wrap_pi(th1);
    s->rotation = dl;
    s->fit = 1.0f;
    s->single = true;
    s->moving = true;
    return true;
}

/* (C.5) sign known from the wait: |Delta| from (C.1), theta from (C.2) at this sample. */
static void known_sign(mc_catch_t *s, mc_ab_t di)
{
    const mc_catch_cfg_t *c = &s->cfg;
    const float sg = (float)s->passive;
    mc_ab_t b = di;
    float th = 0.0f, dl = 0.0f;
    for (int pass = 0; pass < (c->v_device > 0.0f ? 3 : 1); ++pass) {
        if (pass > 0) {
            b = sub(di, current_of(c, s->psi, th));
        }
        dl = rotation_of(c, mag(b));
        th = atan2f(b.beta, b.alpha) - offset_c2(c, sg * dl);
    }
    s->n1 = s->n;
    s->di1 = di;
    s->omega = sg * dl / ((float)s->n * c->ts);
    s->theta = mc_wrap_pi(th);
    s->rotation = sg * dl;
    s->fit = 1.0f;
    s->single = true;
    s->moving = true;
}

/* The device drop under V(000): every phase conducts through its low-side switch or diode, whose
 * drop opposes its current (a soft sign over i_band, as in the dead-time compensation); the
 * line-to-neutral vector (2.4) [V]. */
static float soft_drop(const mc_catch_cfg_t *c, float i)
{
    const float x = i / c->i_band;
    return -c->v_device * (x > 1.0f ? 1.0f : (x < -1.0f ? -1.0f : x));
}

static mc_ab_t drop_voltage(const mc_catch_cfg_t *c, mc_ab_t i)
{
    const mc_abc_t ph = mc_clarke_inv(i);
    return mc_clarke((mc_abc_t){soft_drop(c, ph.a), soft_drop(c, ph.b), soft_drop(c, ph.c)});   /* (2.4) */
}

/* One period of V(000) ended at this sample: its drop's flux, trapezoidal in the current. */
static void add_drop(mc_catch_t *s, mc_ab_t i_now)
{
    const mc_catch_cfg_t *c = &s->cfg;
    if (!(c->v_device > 0.0f)) {
        return;
    }
    const mc_ab_t a = drop_voltage(c, s->i_last), b = drop_voltage(c, i_now);
    s->psi.alpha += 0.5f * c->ts * (a.alpha + b.alpha);
    s->psi.beta += 0.5f * c->ts * (a.beta + b.beta);
}

mc_ip_status_t mc_catch_step(mc_catch_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty, bool *off)
{
    const mc_catch_cfg_t *c = &s->cfg;
    *duty = (mc_abc_t){0.0f, 0.0f, 0.0f};
    *off = true;
    if (s->phase == END) {
        return s->status;
    }
    const float im = mag(i_ab);
    if (im > s->i_peak) {
        s->i_peak = im;
    }
    const uint32_t call = s->calls++;
    /* (C.6): what was written last period is latched now */
    s->corner_a = s->corner_w;
    s->corner_w = -1;
    if (s->phase == WAIT) {
        /* (C.5): the diodes' current turning with the rotor, step by step within one pulse */
        /* measured from the diode pulse's low (the sample after a fall), so that an offset
         * error of the current sensing (the calibration may have averaged diode current) drops
         * out, as in (C.1)-(C.3) */
        const float i_min = 0.25f * c->i_pulse;
        const mc_ab_t d_now = sub(i_ab, s->i0), d_last = sub(s->i_last, s->i0);
        const float dm_now = mag(d_now), dm_last = mag(d_last), im_last = mag(s->i_last);
        if (s->n == 0u || im < im_last) {
            s->i0 = i_ab;   /* a new low */
        } else if (dm_now >= i_min && dm_last >= i_min && dm_now > dm_last) {
            const float dphi = mc_wrap_pi(atan2f(d_now.beta, d_now.alpha) - atan2f(d_last.beta, d_last.alpha));
            s->pas_sum += dphi;
            s->pas_abs += fabsf(dphi);
            s->pas_n++;
        }
        s->i_last = i_ab;
        if (dm_now >= i_min) {
            s->diodes = true;
        }
        /* (C.6): the diodes' current from the last real low (a fall by i_min or more in one
         * period: a pulse's end, not a dip of |i| within it), so that no offset error of the
         * sensing turns its direction; taken where it has grown to twice i_min */
        if (s->n == 0u || im < im_last - i_min) {
            s->i_low = i_ab;
        }
        const mc_ab_t d_low = sub(i_ab, s->i_low);
        if (mag(d_low) >= 2.0f * i_min) {
            s->i_dir = d_low;
        }
        if (s->pas_n >= MC_CATCH_PASSIVE_N && fabsf(s->pas_sum) >= 0.1745f &&
            fabsf(s->pas_sum) >= 0.8f * s->pas_abs) {
            s->passive = s->pas_sum > 0.0f ? 1 : -1;
        }
        /* pulse 1 starts from this sample once the current is at rest (at an enable below the
         * uncontrolled-generation speed it is; after a recovery the outputs were just switched
         * off), or, where the diodes conduct, at a diode pulse's low once (C.5) has its sign;
         * or after the longest wait */
        /* (C.6): with the diodes conducting and the sign known, the pulse will be the corner for
         * the diodes' last direction; its duties are latched ahead, the outputs still off */
        const bool kv_ok = s->diodes && s->passive != 0 && vdc > 0.0f;
        const bool ready = s->diodes ? (mc_catch_at_low(c, i_ab) && s->passive != 0) : im <= c->i_rest;
        if (!ready && s->n++ < c->n_wait_max) {
            if (kv_ok) {
                s->corner_w = corner_for(s->i_dir, s->passive);
                *duty = mc_svpwm_corner(s->corner_w, NULL);
            }
            return MC_IP_RUNNING;
        }
        s->i0 = i_ab;
        s->i_last = i_ab;
        s->psi = (mc_ab_t){0.0f, 0.0f};
        s->phase = PULSE1;
        s->n = 0u;
        s->kv = kv_ok && s->corner_a >= 0;
        if (s->kv) {
            /* the latched corner acts from now; written again, it also acts in the period after */
            const float u = (2.0f / 3.0f) * vdc;
            mc_ab_t dir;
            (void)mc_svpwm_corner(s->corner_a, &dir);
            s->u_kv = (mc_ab_t){u * dir.alpha, u * dir.beta};
            s->corner_w = s->corner_a;
            *duty = mc_svpwm_corner(s->corner_w, NULL);
        }
        *off = false;
        return MC_IP_RUNNING;
    }
    s->n++;
    if (s->phase == PULSE1 || s->phase == PULSE2) {
        add_drop(s, i_ab);
        s->i_last = i_ab;
    }
    switch (s->phase) {
    case PULSE1: {
        if (s->kv) {
            /* (C.6), before the probe (the diodes conduct: not standing): one period of the
             * known corner; the outputs stay on with it (written again: the history the caller
             * keeps then holds the vector that acts until its own duties) */
            const bool ok = known_vector(s, s->i0, i_ab);
            s->phase = END;
            s->status = ok ? MC_IP_DONE : MC_IP_FAILED;
            if (ok) {
                s->corner_w = s->corner_a;
                *duty = mc_svpwm_corner(s->corner_w, NULL);
                *off = false;
            }
            return s->status;
        }
        const mc_ab_t di = sub(i_ab, s->i0);
        const float dm = mag(di);
        if (s->n == c->n_probe && dm < c->i_detect) {
            s->moving = false;   /* no back-EMF worth the name: standing (below omega_min) */
            s->phase = END;
            s->status = MC_IP_DONE;
            return s->status;
        }
        if (s->n <= MC_CATCH_HIST) {
            s->hist[s->n - 1u] = di;
            s->hist_psi[s->n - 1u] = s->psi;
        }
        if (s->passive != 0) {
            /* the sign known from the wait (C.5): one pulse of i_pulse gives the angle */
            if (dm < c->i_pulse && s->n < c->n_pulse_max && s->n < MC_CATCH_HIST) {
                *off = false;
                return MC_IP_RUNNING;
            }
            known_sign(s, di);
            s->phase = END;
            s->status = MC_IP_DONE;
            return s->status;
        }
        /* |omega| to first order of (C.1) */
        const float w1 = dm * c->lq / (c->psi_pm * (float)s->n * c->ts);
        /* the single pulse needs two samples below 2 i_pulse: not when one period's rise is
         * already i_pulse (a low sampling rate at speed); then two one-period pulses */
        const bool coarse = s->n == 1u && dm >= c->i_pulse;
        const bool high = !coarse && 1.7320508f * w1 * c->psi_pm > c->high_speed_share * vdc;
        const float i_end = high ? 2.0f * c->i_pulse : c->i_pulse;
        if (dm < i_end && s->n < c->n_pulse_max && !(high && s->n >= MC_CATCH_HIST)) {
            *off = false;
            return MC_IP_RUNNING;
        }
        s->di1 = di;
        s->psi1 = s->psi;
        s->n1 = s->n;
        s->end1 = call;
        if (high && s->n1 >= 2u && s->n1 <= MC_CATCH_HIST && single_pulse_sign(s)) {
            s->phase = END;
            s->status = MC_IP_DONE;
            return s->status;
        }
        /* the gap: rotate ~rot_target end to end */
        const float n12 = c->rot_target / (w1 * c->ts);
        const float ng = n12 - (float)s->n1;
        /* !(ng >= 2): also a NaN (a converted NaN is undefined behaviour) */
        s->n_gap = !(ng >= 2.0f) ? 2u : (ng > (float)c->n_gap_max ? c->n_gap_max : (uint32_t)ng);
        s->phase = GAP;
        s->n = 0u;
        return MC_IP_RUNNING;
    }
    case GAP:
        if (s->n < s->n_gap || (!(im <= c->i_rest) && s->n < s->n_gap + c->n_gap_max)) {
            return MC_IP_RUNNING;
        }
        s->i0 = i_ab;   /* pulse 2 starts from this sample */
        s->i_last = i_ab;
        s->psi = (mc_ab_t){0.0f, 0.0f};
        s->phase = PULSE2;
        s->n = 0u;
        *off = false;
        return MC_IP_RUNNING;
    case PULSE2:
        *off = false;   /* kept on: the control loop takes over from the next duties */
        if (s->n < s->n1) {
            return MC_IP_RUNNING;
        }
        s->di2 = sub(i_ab, s->i0);
        s->psi2 = s->psi;
        s->phase = END;
        s->status = conclude(s);
        /* the V(000) latched for the next period acts before the control's first duties: one
         * more period's rise. Where a period's rise is i_pulse or more (a short pulse at speed)
         * that would double the current: off instead, the diodes return it to the link until
         * the control's duties come on with the outputs (siemens-1ft7044-spm at half its base
         * speed: 9.7 A for an 8.06 A limit kept on) */
        if (s->status == MC_IP_FAILED || mag(s->di2) >= c->i_pulse * (float)s->n1) {
            *off = true;
        }
        return s->status;
    default:
        return s->status;
    }
}

mc_catch_outcome_t mc_catch_outcome(mc_ip_status_t st, bool moving, bool recovering, bool finds_angle)
{
    if (st == MC_IP_FAILED) {
        return MC_CATCH_NO_FIT;
    }
    if (!moving && recovering && !finds_angle) {
        return MC_CATCH_STALE;
    }
    return moving ? MC_CATCH_TURNING : MC_CATCH_STANDING;
}

int mc_catch_entry_corner(const mc_catch_cfg_t *c, float theta, float omega, float vdc, float u_land)
{
    if (!(vdc > 0.0f) || !(fabsf(omega) * c->psi_pm > u_land)) {
        return -1;
    }
    /* the sensor's angle is a period old: the middle of the period after the next sample */
    const float s = omega < 0.0f ? -1.0f : 1.0f;
    return mc_svpwm_corner_near(theta + 2.0f * omega * c->ts + s * 2.3561945f);
}
