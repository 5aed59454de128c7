/* Step II polarity: generalized detection (5.6)-(5.7) and the DVI reference (3.5.2). */
#include "mc/polarity.h"

#include <math.h>
#include <stddef.h>

#include "mc/angle.h"
#include "mc/sincos.h"
#include "mc/transforms.h"

enum { ST_RUN = 0, ST_DONE, ST_FAILED };

/* |delta i| below this gives no usable slope in (5.6) (noise / the turning point) [A] */
#define DI_MIN 1e-3f

static float absf(float x) { return (x < 0.0f) ? -x : x; }

static mc_ab_t vec(float mag, mc_sincos_t dir)
{
    mc_ab_t u;
    u.alpha = mag * dir.c;
    u.beta = mag * dir.s;
    return u;
}

static float proj(mc_ab_t x, mc_sincos_t dir) { return x.alpha * dir.c + x.beta * dir.s; }

static void zero_duty(mc_abc_t *d)
{
    d->a = 0.0f;
    d->b = 0.0f;
    d->c = 0.0f;
}

void mc_polarity_cfg_default(mc_polarity_cfg_t *cfg)
{
    cfg->ts = 0.0f;
    cfg->rs = 0.0f;
    cfg->model = (mc_flux_model_t){.kind = MC_FLUX_CONST, .map = NULL};  /* to be filled in */
    cfg->v_pol = 200.0f;
    cfg->n = 4;
    cfg->l_at_end = false;
    cfg->i_rest = 0.3f;
    cfg->i_trip = 0.0f;
    cfg->z_min = 0.0f;
    cfg->i_max = 0.0f;
}

/* (Re)program the runner with one train of half-pulse length n */
static bool train(mc_polarity_t *s, int n)
{
    const mc_polarity_cfg_t *cfg = &s->cfg;
    mc_ip_run_init(&s->prog, cfg->rs, cfg->i_rest, cfg->i_trip, 1);
    s->n_now = n;
    s->tries++;
    mc_ab_t up = vec(cfg->v_pol, s->dir), un = vec(-cfg->v_pol, s->dir);
    /* Fig 5.7: +n, -2n, +n; zero net volt-seconds, so the current ends where it started */
    return mc_ip_run_vector(&s->prog, up, n, 0) && mc_ip_run_vector(&s->prog, un, 2 * n, 1) &&
           mc_ip_run_vector(&s->prog, up, n, 2);
}

bool mc_polarity_start(mc_polarity_t *s, const mc_polarity_cfg_t *cfg, float theta1)
{
    s->cfg = *cfg;
    s->state = ST_FAILED;
    s->theta1 = theta1;
    s->theta2 = mc_wrap_pi(theta1);
    s->c1 = s->c2 = s->asym = s->z = s->i_peak = 0.0f;
    s->verdict = MC_POL_ABORTED;
    s->tries = s->n_now = 0;
    s->flip = false;
    s->n_valid = 0;
    s->v_real = 0.0f;
    s->calls = 0;
    s->dir = mc_sincos(theta1);
    mc_ip_run_init(&s->prog, cfg->rs, cfg->i_rest, cfg->i_trip, 1);
    if (!(cfg->ts > 0.0f) || !(cfg->v_pol > 0.0f) || cfg->n < 1 || cfg->n > MC_POL_N_MAX ||
        4 * cfg->n > MC_IP_REC_MAX || !(cfg->z_min <= 1e6f) || !(cfg->i_max <= 1e6f)) {
        return false;
    }
    bool ok = train(s, cfg->n);
    if (ok) {
        s->state = ST_RUN;
        s->verdict = MC_POL_PENDING;
    }
    return ok;
}

/* fold one interval into (5.6)-(5.7) */
static void fold(mc_polarity_t *s, const mc_ip_rec_t *r)
{
    float i0 = proj(r->i0, s->dir), i1 = proj(r->i1, s->dir);
    float di = i1 - i0;
    if (absf(di) < DI_MIN) {
        return;
    }
    float ldiff = s->cfg.ts * proj(r->ubar, s->dir) / di;   /* (5.6) */
    float ie = s->cfg.l_at_end ? i1 : 0.5f * (i0 + i1);
    mc_dq_t ip, in, psi;
    float lp[4], ln[4];
    ip.d = ie;
    ip.q = 0.0f;
    in.d = -ie;
    in.q = 0.0f;
    mc_flux_eval(&s->cfg.model, ip, &psi, lp, NULL);
    mc_flux_eval(&s->cfg.model, in, &psi, ln, NULL);
    float d1 = ldiff - lp[0], d2 = ldiff - ln[0];          /* (5.7) */
    s->c1 += d1 * d1;
    s->c2 += d2 * d2;
    if (s->n_valid < MC_IP_REC_MAX) {
        s->i_delta[s->n_valid] = i1;
        s->l_diff[s->n_valid] = ldiff;
        s->l_even[s->n_valid] = 0.5f * (lp[0] + ln[0]);
        s->l_odd[s->n_valid] = 0.5f * (lp[0] - ln[0]);
    }
    s->n_valid++;
}

/* The fit of the header, L(j) = a E(j) + b O(j) by least squares over the stored intervals (two
 * passes: the residual is summed, not taken as a difference of large sums); b and z = |b| / se(b).
 * false when the odd profile is absent or collinear with the even one (nothing to decide on). */
static bool fit_odd(mc_polarity_t *s)
{
    const int m = s->n_valid < MC_IP_REC_MAX ? s->n_valid : MC_IP_REC_MAX;
    float see = 0.0f, soo = 0.0f, seo = 0.0f, sel = 0.0f, sol = 0.0f;
    for (int j = 0; j < m; ++j) {
        const float e = s->l_even[j], o = s->l_odd[j], l = s->l_diff[j];
        see += e * e;
        soo += o * o;
        seo += e * o;
        sel += e * l;
        sol += o * l;
    }
    const float det = see * soo - seo * seo;
    if (m < 3 || !(det > 1e-6f * see * soo)) {
        return false;
    }
    const float a = (sel * soo - sol * seo) / det, b = (sol * see - sel * seo) / det;
    float rss = 0.0f;
    for (int j = 0; j < m; ++j) {
        const float r = s->l_diff[j] - a * s->l_even[j] - b * s->l_odd[j];
        rss += r * r;
    }
    const float var_b = rss / (float)(m - 2) * see / det;
    s->asym = b;
    const float z = var_b > 0.0f ? (b < 0.0f ? -b : b) / sqrtf(var_b) : 1e6f;   /* exact fit */
    s->z = z < 1e6f ? z : 1e6f;
    return s->z == s->z;
}

/* Half-pulse length of the next train: the longest whose flux swing +-v n Ts the model turns into
 * at most 0.9 i_max either way (the current's rise is the model's saturation, not linear), at
 * least the first train's; the intervals still free in the store bound it (the fit needs them
 * all). 0: no further train (full, or no i_max: retries off). */
static int retry_n(const mc_polarity_t *s)
{
    const float im = 0.9f * s->cfg.i_max;
    if (!(im > 0.0f) || !(s->v_real > 0.0f)) {
        return 0;
    }
    float n = floorf(mc_flux_swing_d(&s->cfg.model, im) / (s->v_real * s->cfg.ts));
    n = n > (float)s->cfg.n ? n : (float)s->cfg.n;   /* at least the first train's length */
    int nmax = (MC_IP_REC_MAX - s->n_valid) / 4;
    nmax = nmax < MC_POL_N_MAX ? nmax : MC_POL_N_MAX;
    return !(n >= 1.0f) || nmax < 1 ? 0 : n >= (float)nmax ? nmax : (int)n;
}

mc_ip_status_t mc_polarity_step(mc_polarity_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty)
{
    zero_duty(duty);
    if (s->state != ST_RUN) {
        return (s->state == ST_DONE) ? MC_IP_DONE : MC_IP_FAILED;
    }
    s->calls++;
    mc_ip_rec_t r;
    int tag;
    mc_ip_status_t st = mc_ip_run_step(&s->prog, i_ab, vdc, duty, &r, &tag);
    if (s->prog.n == 1) {
        mc_ab_t u = s->prog.u_line[1];
        s->v_real = sqrtf(u.alpha * u.alpha + u.beta * u.beta);
    }
    s->i_peak = s->prog.i_peak > s->i_peak ? s->prog.i_peak : s->i_peak;   /* over all trains */
    if (st == MC_IP_FAILED) {
        s->state = ST_FAILED;
        s->verdict = MC_POL_ABORTED;
        zero_duty(duty);
        return MC_IP_FAILED;
    }
    /* at most one interval closes per call: two model evaluations of work per call */
    if (tag >= 0) {
        fold(s, &r);
    }
    if (st != MC_IP_DONE) {
        return MC_IP_RUNNING;
    }
    if (s->n_valid < 2 || !(s->c1 >= 0.0f) || !(s->c2 >= 0.0f)) {
        s->state = ST_FAILED;
        s->verdict = MC_POL_NO_DATA;
        return MC_IP_FAILED;
    }
    /* the thesis' (5.7) without the check; with it the sign of the fitted odd share */
    const bool fitted = s->cfg.z_min > 0.0f && fit_odd(s);
    s->flip = fitted ? s->asym < 0.0f : s->c1 > s->c2;
    s->theta2 = mc_wrap_pi(s->theta1 + (s->flip ? MC_PI : 0.0f));
    if (s->cfg.z_min <= 0.0f || (fitted && s->z >= s->cfg.z_min)) {
        s->verdict = MC_POL_DECIDED;
        s->state = ST_DONE;
        return MC_IP_DONE;
    }
    /* not sure: more trains, with longer pulses where the current limit leaves room (more
     * current, more asymmetry), until the stored intervals are full; all of them in the fit */
    const int n2 = retry_n(s);
    if (n2 >= 1 && train(s, n2)) {
        return MC_IP_RUNNING;
    }
    s->verdict = MC_POL_UNDECIDED;
    s->state = ST_FAILED;
    return MC_IP_FAILED;
}

/* ---------------- DVI ---------------- */

void mc_dvi_cfg_default(mc_dvi_cfg_t *cfg)
{
    cfg->rs = 0.0f;
    cfg->v = 200.0f;
    cfg->n = 6;
    cfg->gap_min = 2;
    cfg->gap_max = 50;
    cfg->i_rest = 0.3f;
    cfg->i_trip = 0.0f;
    cfg->z_min = 0.0f;
    cfg->reps_max = 1;
}

/* (Re)program the runner with one DVI program */
static bool dvi_program(mc_dvi_t *s)
{
    const mc_dvi_cfg_t *cfg = &s->cfg;
    mc_ip_run_init(&s->prog, cfg->rs, cfg->i_rest, cfg->i_trip, cfg->gap_max);
    s->peak_pos = s->peak_neg = s->chg_pos = s->chg_neg = s->i_start = 0.0f;
    s->tag_prev = -1;
    mc_ab_t up = vec(cfg->v, s->dir), un = vec(-cfg->v, s->dir);
    /* the opposite pulse of equal volt-seconds brings the current back to (nearly) zero far
     * faster than the zero vector (tau = L / Rs, tens of ms); the gap waits for the rest */
    return mc_ip_run_vector(&s->prog, up, cfg->n, 0) && mc_ip_run_vector(&s->prog, un, cfg->n, -1) &&
           mc_ip_run_gap(&s->prog, cfg->gap_min) && mc_ip_run_vector(&s->prog, un, cfg->n, 1) &&
           mc_ip_run_vector(&s->prog, up, cfg->n, -1);
}

bool mc_dvi_start(mc_dvi_t *s, const mc_dvi_cfg_t *cfg, float theta1)
{
    s->cfg = *cfg;
    s->state = ST_FAILED;
    s->theta1 = theta1;
    s->theta2 = mc_wrap_pi(theta1);
    s->peak_pos = s->peak_neg = 0.0f;
    s->flip = false;
    s->calls = 0;
    s->sum_pos = s->sum_neg = s->s_d2 = s->di_prev = s->z = s->chg_pos = s->chg_neg = s->i_start = 0.0f;
    s->n_d2 = s->reps = 0;
    s->tag_prev = -1;
    s->verdict = MC_POL_ABORTED;
    s->dir = mc_sincos(theta1);
    mc_ip_run_init(&s->prog, cfg->rs, cfg->i_rest, cfg->i_trip, cfg->gap_max);
    if (!(cfg->v > 0.0f) || cfg->n < 1 || cfg->n > MC_POL_N_MAX || !(cfg->z_min <= 1e6f) ||
        cfg->reps_max < 1 || cfg->reps_max > MC_DVI_REPS_MAX) {
        return false;
    }
    bool ok = dvi_program(s);
    if (ok) {
        s->state = ST_RUN;
        s->verdict = MC_POL_PENDING;
    }
    return ok;
}

/* z of the DVI check: the mean change difference over its standard error, sqrt(2 sigma^2 / reps)
 * for the noise and, in quadrature, 1 % of the mean change for what the sequence itself makes
 * differ (0.5 % on a machine without saturation, where the two pulses should be equal) */
static float dvi_confidence(const mc_dvi_t *s)
{
    const float d = (s->sum_neg - s->sum_pos) / (float)s->reps;
    const float var = s->n_d2 > 0 ? s->s_d2 / (6.0f * (float)s->n_d2) : 0.0f;
    const float sys = 0.01f * 0.5f * (s->sum_neg + s->sum_pos) / (float)s->reps;
    const float se = sqrtf(2.0f * var / (float)s->reps + sys * sys);
    const float ad = d < 0.0f ? -d : d;
    if (!(ad > 0.0f)) {
        return 0.0f;
    }
    const float z = se > 0.0f ? ad / se : 1e6f;
    return z < 1e6f ? z : 1e6f;
}

mc_ip_status_t mc_dvi_step(mc_dvi_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty)
{
    zero_duty(duty);
    if (s->state != ST_RUN) {
        return (s->state == ST_DONE) ? MC_IP_DONE : MC_IP_FAILED;
    }
    s->calls++;
    mc_ip_rec_t r;
    int tag;
    mc_ip_status_t st = mc_ip_run_step(&s->prog, i_ab, vdc, duty, &r, &tag);
    if (st == MC_IP_FAILED) {
        s->state = ST_FAILED;
        s->verdict = MC_POL_ABORTED;
        zero_duty(duty);
        return MC_IP_FAILED;
    }
    /* peak |i_delta| of each pulse, over its intervals as they close */
    if (tag == 0 || tag == 1) {
        float a = absf(proj(r.i1, s->dir));
        if (tag == 0 && a > s->peak_pos) {
            s->peak_pos = a;
        } else if (tag == 1 && a > s->peak_neg) {
            s->peak_neg = a;
        }
        const float di = proj(r.i1, s->dir) - proj(r.i0, s->dir);
        if (tag == s->tag_prev) {
            const float d2 = di - s->di_prev;
            s->s_d2 += d2 * d2;
            s->n_d2++;
        } else {
            s->i_start = proj(r.i0, s->dir);   /* the pulse's first interval */
        }
        const float c = absf(proj(r.i1, s->dir) - s->i_start);
        if (tag == 0 && c > s->chg_pos) {
            s->chg_pos = c;
        } else if (tag == 1 && c > s->chg_neg) {
            s->chg_neg = c;
        }
        s->di_prev = di;
        s->tag_prev = tag;
    }
    if (st != MC_IP_DONE) {
        return MC_IP_RUNNING;
    }
    s->reps++;
    s->sum_pos += s->chg_pos;
    s->sum_neg += s->chg_neg;
    if (s->cfg.z_min <= 0.0f) {
        s->flip = s->peak_neg > s->peak_pos;   /* 3.5.2: the larger peak points north */
    } else {
        s->z = dvi_confidence(s);
        s->flip = s->sum_neg > s->sum_pos;
        if (s->z < s->cfg.z_min) {
            if (s->reps < s->cfg.reps_max && dvi_program(s)) {
                return MC_IP_RUNNING;
            }
            s->verdict = MC_POL_UNDECIDED;
            s->state = ST_FAILED;
            return MC_IP_FAILED;
        }
    }
    s->verdict = MC_POL_DECIDED;
    s->theta2 = mc_wrap_pi(s->theta1 + (s->flip ? MC_PI : 0.0f));
    s->state = ST_DONE;
    return MC_IP_DONE;
}
