/* Initial position Step I (thesis 5.2, 7.2.3) and the pulse-program runner of mc/initpos.h.
 *
 * Runner: at call n the sample i(n) closes the interval [n-1, n], which was driven by the vector
 * issued at call n-2 (shadow-register delay); u_line[0] holds it. The record of that interval is
 * (i(n-1), i(n), u_real - Rs (i(n-1) + i(n)) / 2).
 *
 * Step I: per direction x: V(x) m periods, V(~x) 2m, V(x) m (Fig 5.3): zero net volt-seconds, so
 * the flux, hence the current, returns to its start whatever the saturation; only the resistive
 * drop leaves a small residual, which the zero-vector gap between directions lets decay. Then
 * the cost is minimised by a coarse grid and a golden-section refinement, a fixed number of
 * cost evaluations per call so that the ISR load stays bounded. */
#include "mc/initpos.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "mc/angle.h"
#include "mc/sincos.h"
#include "mc/transforms.h"

#define GOLD_R 0.61803398874989f   /* (sqrt 5 - 1) / 2 */

enum { PH_COLLECT = 0, PH_GRID, PH_GOLD, PH_DONE, PH_FAILED };

static bool finite_ab(mc_ab_t x)
{
    /* x - x is NaN for inf and NaN; no isfinite() so as not to depend on a libm macro */
    float a = x.alpha - x.alpha, b = x.beta - x.beta;
    return (a == 0.0f) && (b == 0.0f);
}

static float norm2(mc_ab_t x) { return x.alpha * x.alpha + x.beta * x.beta; }

static void zero_duty(mc_abc_t *d)
{
    d->a = 0.0f;
    d->b = 0.0f;
    d->c = 0.0f;
}

void mc_ip_direct(unsigned pattern, float vdc, mc_duty_t *out)
{
    mc_abc_t v;
    out->a = (pattern & MC_IP_V100) ? 1.0f : 0.0f;
    out->b = (pattern & MC_IP_V010) ? 1.0f : 0.0f;
    out->c = (pattern & MC_IP_V001) ? 1.0f : 0.0f;
    v.a = (out->a - 0.5f) * vdc;
    v.b = (out->b - 0.5f) * vdc;
    v.c = (out->c - 0.5f) * vdc;
    out->u_real = mc_clarke(v);
    out->saturated = false;
}

/* segment kinds (mc_ip_seg_t.kind): low 3 bits = pattern V(abc) or vector-table index */
#define KIND_DIRECT 0x00u
#define KIND_VECTOR 0x10u
#define KIND_GAP    0x20u
#define KIND_TYPE   0xf0u
#define KIND_ARG    0x07u
_Static_assert(MC_IP_VEC_MAX <= 8, "vector index must fit KIND_ARG");

void mc_ip_run_init(mc_ip_run_t *p, float rs, float i_rest, float i_trip, int gap_max)
{
    p->rs = rs;
    p->i_rest = i_rest;
    p->i_trip = i_trip;
    p->gap_max = gap_max;
    p->n_seg = 0;
    p->n_vec = 0;
    p->n = 0;
    p->cur = 0;
    p->pos = 0;
    p->open = 0;
    p->i_prev.alpha = 0.0f;
    p->i_prev.beta = 0.0f;
    for (int k = 0; k < 2; ++k) {
        p->u_line[k].alpha = 0.0f;
        p->u_line[k].beta = 0.0f;
        p->tag_line[k] = -1;
    }
    p->n_rec = 0;
    p->i_peak = 0.0f;
    p->decay_timeout = false;
}

static bool new_seg(mc_ip_run_t *p, int len, int tag, unsigned kind)
{
    if (p->n_seg >= MC_IP_SEG_MAX || len < 1 || len > INT16_MAX || tag > MC_IP_TAG_MAX) {
        return false;
    }
    mc_ip_seg_t *s = &p->seg[p->n_seg++];
    s->len = (int16_t)len;
    s->tag = (int8_t)((tag < 0) ? -1 : tag);
    s->kind = (uint8_t)kind;
    return true;
}

bool mc_ip_run_direct(mc_ip_run_t *p, unsigned pattern, int len, int tag)
{
    return new_seg(p, len, tag, KIND_DIRECT | (pattern & 7u));
}

bool mc_ip_run_vector(mc_ip_run_t *p, mc_ab_t u, int len, int tag)
{
    /* the same vector (bit for bit) shares one table entry */
    int v = 0;
    while (v < p->n_vec && memcmp(&p->vec[v], &u, sizeof u) != 0) {
        ++v;
    }
    if (v >= MC_IP_VEC_MAX || !new_seg(p, len, tag, KIND_VECTOR | (unsigned)v)) {
        return false;
    }
    if (v == p->n_vec) {
        p->vec[p->n_vec++] = u;
    }
    return true;
}

bool mc_ip_run_gap(mc_ip_run_t *p, int len_min)
{
    return new_seg(p, len_min, -1, KIND_GAP);
}

/* Has the segment being issued run its course, judged at call n with sample i(n)? */
static bool seg_finished(mc_ip_run_t *p, mc_ab_t i)
{
    const mc_ip_seg_t *s = &p->seg[p->cur];
    if ((s->kind & KIND_TYPE) != KIND_GAP) {
        return p->pos >= s->len;
    }
    /* only after two gap periods has a whole zero-vector interval ended at this sample */
    int need = (s->len > 2) ? s->len : 2;
    if (p->pos < need) {
        return false;
    }
    if (norm2(i) <= p->i_rest * p->i_rest) {
        return true;
    }
    if (p->pos >= p->gap_max) {
        p->decay_timeout = true;
        return true;
    }
    return false;
}

mc_ip_status_t mc_ip_run_step(mc_ip_run_t *p, mc_ab_t i, float vdc, mc_abc_t *duty,
                              mc_ip_rec_t *rec, int *tag_out)
{
    zero_duty(duty);
    *tag_out = -1;
    float i2 = norm2(i);
    if (!(vdc > 0.0f) || !finite_ab(i) || (p->i_trip > 0.0f && i2 > p->i_trip * p->i_trip)) {
        return MC_IP_FAILED;
    }
    if (i2 > p->i_peak * p->i_peak) {
        p->i_peak = sqrtf(i2);
    }
    /* close [n-1, n] */
    if (p->n >= 1 && p->tag_line[0] >= 0) {
        p->open--;
        p->n_rec++;
        rec->i0 = p->i_prev;
        rec->i1 = i;
        rec->ubar.alpha = p->u_line[0].alpha - 0.5f * p->rs * (p->i_prev.alpha + i.alpha);
        rec->ubar.beta = p->u_line[0].beta - 0.5f * p->rs * (p->i_prev.beta + i.beta);
        *tag_out = p->tag_line[0];
    }
    p->u_line[0] = p->u_line[1];
    p->tag_line[0] = p->tag_line[1];

    /* choose the vector for [n+1, n+2]; each segment is passed at most once per call */
    while (p->cur < p->n_seg && seg_finished(p, i)) {
        p->cur++;
        p->pos = 0;
    }
    mc_duty_t d;
    int8_t tag = -1;
    if (p->cur < p->n_seg) {
        const mc_ip_seg_t *s = &p->seg[p->cur];
        unsigned type = s->kind & KIND_TYPE, arg = s->kind & KIND_ARG;
        if (type == KIND_GAP) {
            mc_ip_direct(0u, vdc, &d);
        } else if (type == KIND_DIRECT) {
            mc_ip_direct(arg, vdc, &d);
        } else {
            mc_svpwm(p->vec[arg], vdc, &d);
        }
        tag = s->tag;
        p->pos++;
        if (tag >= 0) {
            p->open++;
        }
    } else {
        mc_ip_direct(0u, vdc, &d);
    }
    duty->a = d.a;
    duty->b = d.b;
    duty->c = d.c;
    p->u_line[1] = d.u_real;
    p->tag_line[1] = tag;
    p->i_prev = i;
    p->n++;
    return (p->cur >= p->n_seg && p->open <= 0) ? MC_IP_DONE : MC_IP_RUNNING;
}

void mc_ip_prog_init(mc_ip_prog_t *p, float rs, float i_rest, float i_trip, int gap_max)
{
    mc_ip_run_init(&p->run, rs, i_rest, i_trip, gap_max);
    p->n_rec = 0;
    p->overflow = false;
}

bool mc_ip_prog_direct(mc_ip_prog_t *p, unsigned pattern, int len, int tag)
{
    return mc_ip_run_direct(&p->run, pattern, len, tag);
}

bool mc_ip_prog_gap(mc_ip_prog_t *p, int len_min)
{
    return mc_ip_run_gap(&p->run, len_min);
}

mc_ip_status_t mc_ip_prog_step(mc_ip_prog_t *p, mc_ab_t i, float vdc, mc_abc_t *duty)
{
    int tag;
    mc_ip_rec_t r;
    mc_ip_status_t st = mc_ip_run_step(&p->run, i, vdc, duty, &r, &tag);
    if (tag >= 0) {
        if (p->n_rec < MC_IP_REC_MAX) {
            p->rec[p->n_rec++] = r;
        } else {
            p->overflow = true;
        }
    }
    return st;
}

/* ---------------- Step I ---------------- */

void mc_initpos_cfg_default(mc_initpos_cfg_t *cfg)
{
    cfg->ts = 0.0f;
    cfg->rs = 0.0f;
    cfg->ld = 0.0f;
    cfg->lq = 0.0f;
    cfg->model = (mc_flux_model_t){.kind = MC_FLUX_CONST, .map = NULL};  /* to be filled in */
    cfg->cost = MC_IP_COST_LINEAR;
    cfg->m = 5;
    cfg->v_pulse = 0.0f;
    cfg->n_dir = 1;
    cfg->all_pulses = false;
    cfg->grid = 36;
    cfg->tol = 0.05f * MC_PI / 180.0f;
    cfg->evals_per_call = 12;
    cfg->gap_min = 2;
    cfg->gap_max = 50;
    cfg->i_rest = 0.3f;
    cfg->i_trip = 0.0f;
}

/* tags: dir * 4 + part, part 0 = first V(x), 1 = V(~x), 2 = last V(x) */
bool mc_initpos_start(mc_initpos_t *s, const mc_initpos_cfg_t *cfg)
{
    static const unsigned dir_vec[3] = {MC_IP_V100, MC_IP_V010, MC_IP_V001};
    s->cfg = *cfg;
    s->phase = PH_FAILED;
    s->theta1 = 0.0f;
    s->theta_full = 0.0f;
    s->cost_min = 0.0f;
    s->evals = 0;
    s->calls = 0;
    s->k = 0;
    s->best_c = 0.0f;
    s->best_th = 0.0f;
    mc_ip_prog_init(&s->prog, cfg->rs, cfg->i_rest, cfg->i_trip, cfg->gap_max);
    int per_dir = cfg->all_pulses ? 4 * cfg->m : cfg->m;
    if (!(cfg->ts > 0.0f) || cfg->m < 1 || cfg->m > MC_IP_M_MAX || cfg->n_dir < 1 ||
        cfg->n_dir > 3 || cfg->n_dir * per_dir > MC_IP_REC_MAX || cfg->grid < 4 ||
        2 * cfg->grid > MC_IP_GRID_MAX || !(cfg->tol > 0.0f) || cfg->evals_per_call < 1 ||
        (cfg->cost == MC_IP_COST_LINEAR && !(cfg->ld > 0.0f && cfg->lq > 0.0f))) {
        return false;
    }
    if (!(cfg->v_pulse >= 0.0f) || cfg->v_pulse > 1e5f) {
        return false;
    }
    bool ok = true;
    for (int d = 0; d < cfg->n_dir; ++d) {
        unsigned v = dir_vec[d], vc = 7u & ~v;
        int t = 4 * d;
        if (cfg->v_pulse > 0.0f) {
            /* phase a, b, c axes at 0, 120, 240 deg: the same directions as V(100), V(010), V(001) */
            static const mc_ab_t axis[3] = {{1.0f, 0.0f}, {-0.5f, 0.8660254f}, {-0.5f, -0.8660254f}};
            const mc_ab_t up = {cfg->v_pulse * axis[d].alpha, cfg->v_pulse * axis[d].beta};
            const mc_ab_t un = {-up.alpha, -up.beta};
            ok = ok && mc_ip_run_vector(&s->prog.run, up, cfg->m, t);
            ok = ok && mc_ip_run_vector(&s->prog.run, un, 2 * cfg->m, cfg->all_pulses ? t + 1 : -1);
            ok = ok && mc_ip_run_vector(&s->prog.run, up, cfg->m, cfg->all_pulses ? t + 2 : -1);
            if (d + 1 < cfg->n_dir) {
                ok = ok && mc_ip_prog_gap(&s->prog, cfg->gap_min);
            }
            continue;
        }
        ok = ok && mc_ip_prog_direct(&s->prog, v, cfg->m, t);
        ok = ok && mc_ip_prog_direct(&s->prog, vc, 2 * cfg->m, cfg->all_pulses ? t + 1 : -1);
        ok = ok && mc_ip_prog_direct(&s->prog, v, cfg->m, cfg->all_pulses ? t + 2 : -1);
        if (d + 1 < cfg->n_dir) {
            /* the search after the last direction is the last gap */
            ok = ok && mc_ip_prog_gap(&s->prog, cfg->gap_min);
        }
    }
    if (ok) {
        s->phase = PH_COLLECT;
    }
    return ok;
}

static mc_dq_t dqv(float d, float q)
{
    mc_dq_t r;
    r.d = d;
    r.q = q;
    return r;
}

float mc_initpos_cost(const mc_initpos_t *s, float theta)
{
    const mc_initpos_cfg_t *c = &s->cfg;
    const mc_ip_prog_t *p = &s->prog;
    float inv_ts = 1.0f / c->ts;
    float g = 0.0f;
    if (c->cost == MC_IP_COST_LINEAR) {
        /* (5.4) */
        mc_sincos_t t2 = mc_sincos(2.0f * theta);
        float l1 = 0.5f * (c->ld + c->lq), l2 = 0.5f * (c->ld - c->lq);
        float a11 = (l1 + l2 * t2.c) * inv_ts, a12 = l2 * t2.s * inv_ts;
        float a22 = (l1 - l2 * t2.c) * inv_ts;
        for (int k = 0; k < p->n_rec; ++k) {
            const mc_ip_rec_t *r = &p->rec[k];
            float da = r->i1.alpha - r->i0.alpha, db = r->i1.beta - r->i0.beta;
            float ea = r->ubar.alpha - (a11 * da + a12 * db);
            float eb = r->ubar.beta - (a12 * da + a22 * db);
            g += ea * ea + eb * eb;
        }
        return g;
    }
    /* (7.1): everything in the candidate rotor frame T(theta) */
    mc_sincos_t sc = mc_sincos(theta);
    for (int k = 0; k < p->n_rec; ++k) {
        const mc_ip_rec_t *r = &p->rec[k];
        mc_dq_t u = mc_park(r->ubar, sc), i1 = mc_park(r->i1, sc), i0 = mc_park(r->i0, sc);
        mc_dq_t psi1, dpsi;
        if (c->cost == MC_IP_COST_NONLINEAR) {
            float L[4];
            mc_flux_eval(&c->model, i1, &psi1, L, NULL);
            float dd = i1.d - i0.d, dq = i1.q - i0.q;
            dpsi = dqv(L[0] * dd + L[1] * dq, L[2] * dd + L[3] * dq);
        } else {
            mc_dq_t psi0;
            mc_flux_eval(&c->model, i1, &psi1, NULL, NULL);
            mc_flux_eval(&c->model, i0, &psi0, NULL, NULL);
            dpsi = dqv(psi1.d - psi0.d, psi1.q - psi0.q);
        }
        float ed = u.d - dpsi.d * inv_ts, eq = u.q - dpsi.q * inv_ts;
        g += ed * ed + eq * eq;
    }
    return g;
}

/* The linear cost has period pi; the nonlinear ones do not (saturation tells the poles apart a
 * little), so they are searched over the whole circle and the result is reported modulo pi. */
static float span_of(const mc_initpos_t *s)
{
    return (s->cfg.cost == MC_IP_COST_LINEAR) ? MC_PI : MC_2PI;
}

static int npts_of(const mc_initpos_t *s)
{
    return (s->cfg.cost == MC_IP_COST_LINEAR) ? s->cfg.grid : 2 * s->cfg.grid;
}

static float eval(mc_initpos_t *s, float th)
{
    s->evals++;
    return mc_initpos_cost(s, th);
}

static void finish(mc_initpos_t *s)
{
    float th = s->best_th, c = s->best_c;
    /* golden section keeps the better interior point; the grid point wins if it is better */
    if (s->f1 < c) {
        th = s->x1;
        c = s->f1;
    }
    if (s->f2 < c) {
        th = s->x2;
        c = s->f2;
    }
    s->theta_full = mc_wrap_2pi(th);
    float t1 = s->theta_full;
    if (t1 >= MC_PI) {
        t1 -= MC_PI;
    }
    s->theta1 = (t1 >= 0.0f && t1 < MC_PI) ? t1 : 0.0f;
    s->cost_min = c;
    s->phase = PH_DONE;
}

/* one cost evaluation of the search (or the final bookkeeping) */
static void search_step(mc_initpos_t *s)
{
    float h = span_of(s) / (float)npts_of(s);
    if (s->phase == PH_GRID) {
        float th = (float)s->k * h;
        float c = eval(s, th);
        if (s->k == 0 || c < s->best_c) {
            s->best_c = c;
            s->best_th = th;
        }
        if (++s->k >= npts_of(s)) {
            s->ga = s->best_th - h;
            s->gb = s->best_th + h;
            s->x1 = s->gb - GOLD_R * (s->gb - s->ga);
            s->x2 = s->ga + GOLD_R * (s->gb - s->ga);
            s->gs_stage = 0;
            s->gs_iter = 0;
            s->phase = PH_GOLD;
        }
        return;
    }
    if (s->gs_stage == 0) {
        s->f1 = eval(s, s->x1);
        s->gs_stage = 1;
        return;
    }
    if (s->gs_stage == 1) {
        s->f2 = eval(s, s->x2);
        s->gs_stage = 2;
        return;
    }
    if (s->gb - s->ga <= s->cfg.tol || s->gs_iter >= MC_IP_GS_MAX) {
        finish(s);
        return;
    }
    s->gs_iter++;
    if (s->f1 < s->f2) {
        s->gb = s->x2;
        s->x2 = s->x1;
        s->f2 = s->f1;
        s->x1 = s->gb - GOLD_R * (s->gb - s->ga);
        s->f1 = eval(s, s->x1);
    } else {
        s->ga = s->x1;
        s->x1 = s->x2;
        s->f1 = s->f2;
        s->x2 = s->ga + GOLD_R * (s->gb - s->ga);
        s->f2 = eval(s, s->x2);
    }
}

mc_ip_status_t mc_initpos_step(mc_initpos_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty)
{
    zero_duty(duty);
    if (s->phase == PH_DONE) {
        return MC_IP_DONE;
    }
    if (s->phase == PH_FAILED) {
        return MC_IP_FAILED;
    }
    s->calls++;
    /* the runner keeps watching the current (trip) during the search too */
    mc_ip_status_t st = mc_ip_prog_step(&s->prog, i_ab, vdc, duty);
    if (st == MC_IP_FAILED || s->prog.overflow) {
        s->phase = PH_FAILED;
        zero_duty(duty);
        return MC_IP_FAILED;
    }
    if (s->phase == PH_COLLECT) {
        if (st != MC_IP_DONE) {
            return MC_IP_RUNNING;
        }
        if (s->prog.n_rec < 1) {
            s->phase = PH_FAILED;
            return MC_IP_FAILED;
        }
        s->phase = PH_GRID;
        s->k = 0;
        s->f1 = s->f2 = 0.0f;
    }
    /* search: bounded work per call; the finishing step costs no evaluation */
    int e0 = s->evals;
    for (int b = 0; b < MC_IP_GRID_MAX + MC_IP_GS_MAX + 4; ++b) {
        if (s->phase == PH_DONE || s->evals - e0 >= s->cfg.evals_per_call) {
            break;
        }
        search_step(s);
    }
    if (s->phase == PH_GOLD && s->gs_stage == 2 &&
        (s->gb - s->ga <= s->cfg.tol || s->gs_iter >= MC_IP_GS_MAX)) {
        finish(s);   /* bookkeeping only: do not spend a call on it */
    }
    if (s->phase == PH_DONE) {
        if (!(s->cost_min >= 0.0f)) {
            s->phase = PH_FAILED;   /* NaN cost: corrupt data */
            return MC_IP_FAILED;
        }
        return MC_IP_DONE;
    }
    return MC_IP_RUNNING;
}
