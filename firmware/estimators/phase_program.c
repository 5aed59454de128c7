/* Phase programs (mc/phase_program.h): adapters from the one interface onto the engines'
 * own start / step functions, so both paths compute exactly the same. */
#include "mc/phase_program.h"

#include <stddef.h>

_Static_assert(sizeof(mc_phase_ws_t) <= MC_PHASE_WS_BUDGET,
               "phase-program workspace over budget (see mc/phase_program.h)");

static void zero_out(mc_phase_out_t *out)
{
    out->duty.a = 0.0f;
    out->duty.b = 0.0f;
    out->duty.c = 0.0f;
    out->off = false;
}

static void clear_result(mc_phase_result_t *r)
{
    r->theta = 0.0f;
    r->theta_aux = 0.0f;
    r->flip = false;
    r->c1 = 0.0f;
    r->c2 = 0.0f;
    r->conf = 0.0f;
    r->verdict = 0;
    r->omega = 0.0f;
    r->moving = false;
    r->i_peak = 0.0f;
    r->calls = 0;
}

/* ---- Step I pulses (5.5) / (7.1) ---- */

static bool ip1_begin(mc_phase_ws_t *ws, const void *cfg, float theta_in)
{
    (void)theta_in;
    if (cfg != NULL) {
        return mc_initpos_start(&ws->ip1, (const mc_initpos_cfg_t *)cfg);
    }
    mc_initpos_cfg_t bad;
    mc_initpos_cfg_default(&bad);
    bad.m = 0;   /* invalid: leaves the engine FAILED */
    (void)mc_initpos_start(&ws->ip1, &bad);
    return false;
}

static mc_ip_status_t ip1_step(mc_phase_ws_t *ws, const mc_phase_in_t *in, mc_phase_out_t *out)
{
    return mc_initpos_step(&ws->ip1, in->i_ab, in->vdc, &out->duty);
}

static void ip1_result(const mc_phase_ws_t *ws, mc_phase_result_t *r)
{
    const mc_initpos_t *s = &ws->ip1;
    clear_result(r);
    r->theta = s->theta1;
    r->theta_aux = s->theta_full;
    r->c1 = s->cost_min;
    r->i_peak = s->prog.run.i_peak;
    r->calls = s->calls;
}

const mc_phase_program_t mc_phase_step1_pulses = {
    "step1_pulses", sizeof(mc_initpos_cfg_t), ip1_begin, ip1_step, ip1_result};

/* ---- three-phase pulse method (3.19)-(3.21) ---- */

static bool p3_begin(mc_phase_ws_t *ws, const void *cfg, float theta_in)
{
    (void)theta_in;
    if (cfg != NULL) {
        return mc_pulse3_start(&ws->pulse3, (const mc_pulse3_cfg_t *)cfg);
    }
    mc_pulse3_cfg_t bad;
    mc_pulse3_cfg_default(&bad);
    bad.n = 0;
    (void)mc_pulse3_start(&ws->pulse3, &bad);
    return false;
}

static mc_ip_status_t p3_step(mc_phase_ws_t *ws, const mc_phase_in_t *in, mc_phase_out_t *out)
{
    return mc_pulse3_step(&ws->pulse3, in->i_ab, in->vdc, &out->duty);
}

static void p3_result(const mc_phase_ws_t *ws, mc_phase_result_t *r)
{
    const mc_pulse3_t *s = &ws->pulse3;
    clear_result(r);
    r->theta = s->theta;
    r->theta_aux = s->theta_atan;
    r->i_peak = s->prog.i_peak;
    r->calls = s->calls;
}

const mc_phase_program_t mc_phase_step1_pulse3 = {
    "step1_pulse3", sizeof(mc_pulse3_cfg_t), p3_begin, p3_step, p3_result};

/* ---- Step II generalized polarity (5.6)-(5.7) ---- */

static bool pol_begin(mc_phase_ws_t *ws, const void *cfg, float theta_in)
{
    if (cfg != NULL) {
        return mc_polarity_start(&ws->pol, (const mc_polarity_cfg_t *)cfg, theta_in);
    }
    mc_polarity_cfg_t bad;
    mc_polarity_cfg_default(&bad);
    bad.n = 0;
    (void)mc_polarity_start(&ws->pol, &bad, theta_in);
    return false;
}

static mc_ip_status_t pol_step(mc_phase_ws_t *ws, const mc_phase_in_t *in, mc_phase_out_t *out)
{
    return mc_polarity_step(&ws->pol, in->i_ab, in->vdc, &out->duty);
}

static void pol_result(const mc_phase_ws_t *ws, mc_phase_result_t *r)
{
    const mc_polarity_t *s = &ws->pol;
    clear_result(r);
    r->theta = s->theta2;
    r->theta_aux = s->theta1;
    r->flip = s->flip;
    r->c1 = s->c1;
    r->c2 = s->c2;
    r->conf = s->z;
    r->verdict = (int)s->verdict;
    r->i_peak = s->i_peak;
    r->calls = s->calls;
}

const mc_phase_program_t mc_phase_step2_polarity = {
    "step2_polarity", sizeof(mc_polarity_cfg_t), pol_begin, pol_step, pol_result};

/* ---- DVI (3.5.2) ---- */

static bool dvi_begin(mc_phase_ws_t *ws, const void *cfg, float theta_in)
{
    if (cfg != NULL) {
        return mc_dvi_start(&ws->dvi, (const mc_dvi_cfg_t *)cfg, theta_in);
    }
    mc_dvi_cfg_t bad;
    mc_dvi_cfg_default(&bad);
    bad.n = 0;
    (void)mc_dvi_start(&ws->dvi, &bad, theta_in);
    return false;
}

static mc_ip_status_t dvi_step(mc_phase_ws_t *ws, const mc_phase_in_t *in, mc_phase_out_t *out)
{
    return mc_dvi_step(&ws->dvi, in->i_ab, in->vdc, &out->duty);
}

static void dvi_result(const mc_phase_ws_t *ws, mc_phase_result_t *r)
{
    const mc_dvi_t *s = &ws->dvi;
    clear_result(r);
    r->theta = s->theta2;
    r->theta_aux = s->theta1;
    r->flip = s->flip;
    r->c1 = s->peak_pos;
    r->c2 = s->peak_neg;
    r->conf = s->z;
    r->verdict = (int)s->verdict;
    r->i_peak = s->prog.i_peak;
    r->calls = s->calls;
}

const mc_phase_program_t mc_phase_step2_dvi = {
    "step2_dvi", sizeof(mc_dvi_cfg_t), dvi_begin, dvi_step, dvi_result};

/* ---- flying-start catch (C.1)-(C.3) ---- */

static bool fly_begin(mc_phase_ws_t *ws, const void *cfg, float theta_in)
{
    (void)theta_in;
    if (cfg != NULL) {
        return mc_catch_start(&ws->fly, (const mc_catch_cfg_t *)cfg);
    }
    const mc_catch_cfg_t bad = {0};
    (void)mc_catch_start(&ws->fly, &bad);
    return false;
}

static mc_ip_status_t fly_step(mc_phase_ws_t *ws, const mc_phase_in_t *in, mc_phase_out_t *out)
{
    return mc_catch_step(&ws->fly, in->i_ab, in->vdc, &out->duty, &out->off);
}

static void fly_result(const mc_phase_ws_t *ws, mc_phase_result_t *r)
{
    const mc_catch_t *s = &ws->fly;
    clear_result(r);
    r->theta = s->theta;
    r->theta_aux = s->rotation;
    r->c1 = s->fit;
    r->omega = s->omega;
    r->moving = s->moving;
    r->i_peak = s->i_peak;
    r->calls = (int)s->calls;
}

const mc_phase_program_t mc_phase_catch = {"catch", sizeof(mc_catch_cfg_t), fly_begin, fly_step, fly_result};

/* ---- holder ---- */

bool mc_phase_begin(mc_phase_t *ph, const mc_phase_program_t *prog, const void *cfg,
                    float theta_in)
{
    ph->prog = prog;
    if (prog == NULL) {
        return false;
    }
    return prog->begin(&ph->ws, cfg, theta_in);
}

mc_ip_status_t mc_phase_step(mc_phase_t *ph, const mc_phase_in_t *in, mc_phase_out_t *out)
{
    zero_out(out);
    if (ph->prog == NULL) {
        return MC_IP_FAILED;
    }
    return ph->prog->step(&ph->ws, in, out);
}

void mc_phase_result(const mc_phase_t *ph, mc_phase_result_t *res)
{
    if (ph->prog == NULL) {
        clear_result(res);
        return;
    }
    ph->prog->result(&ph->ws, res);
}

void mc_phase_stop(mc_phase_t *ph)
{
    ph->prog = NULL;
}
