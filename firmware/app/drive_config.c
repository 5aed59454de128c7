/* The drive's configuration, background side: parameters -> validated, derived block
 * configurations (mc_drive_build). Nothing here runs in the ISR. */
#include <math.h>
#include "mc/drive.h"

#define RPM_TO_RAD_S (MC_2PI / 60.0f)

/* The blocks' own enums take these choices by position. */
_Static_assert(MC_CHOICE_inj_kind_off == (int)MC_INJ_OFF && MC_CHOICE_inj_kind_sine == (int)MC_INJ_SINE &&
                   MC_CHOICE_inj_kind_rect == (int)MC_INJ_RECT, "injection.kind and mc_inj_kind_t");
_Static_assert(MC_CHOICE_ip1_cost_linear == (int)MC_IP_COST_LINEAR &&
                   MC_CHOICE_ip1_cost_nonlinear == (int)MC_IP_COST_NONLINEAR &&
                   MC_CHOICE_ip1_cost_fluxdiff == (int)MC_IP_COST_FLUXDIFF, "startup.step1_cost and mc_ip_cost_t");

void mc_drive_cfg_default(mc_drive_cfg_t *cfg)
{
    mc_params_default(&cfg->p);
    cfg->est = (mc_est_model_t){.rs = NAN, .ld = NAN, .lq = NAN, .psi_pm = NAN, .map = 0};
}

static float or_motor(float v, float motor)
{
    return isnan(v) ? motor : v;
}

/* The estimator's model: the motor's unless given, each value as plausible as the motor entry
 * it stands for; the flux map's grid must fit the table and hold finite numbers only. */
static bool check_model(const mc_params_t *p, const mc_est_model_t *in, mc_est_model_t *m, bool need_map,
                        mc_param_err_t *err)
{
    *m = (mc_est_model_t){.rs = or_motor(in->rs, p->rs), .ld = or_motor(in->ld, p->ld),
                          .lq = or_motor(in->lq, p->lq), .psi_pm = or_motor(in->psi_pm, p->psi_pm), .map = in->map};
    const struct { float v; int id; } vals[4] = {
        {m->rs, MC_PARAM_rs}, {m->ld, MC_PARAM_ld}, {m->lq, MC_PARAM_lq}, {m->psi_pm, MC_PARAM_psi_pm}};
    for (int k = 0; k < 4; ++k) {
        const mc_param_info_t *e = &mc_param_table[vals[k].id];
        if (!isfinite(vals[k].v) || vals[k].v < e->min || vals[k].v > e->max) {
            return mc_param_fail(err, MC_PERR_MODEL, vals[k].id, vals[k].v, "the estimator model's value is out of the motor entry's range");
        }
    }
    const mc_flux_map_t *map = m->map;
    if (map == 0) {
        return need_map ? mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_est_model, 0.0f, "this configuration needs the estimator's flux map")
                        : true;
    }
    if (map->n_d < 2 || map->n_d > MC_FLUX_MAP_MAX || map->n_q < 2 || map->n_q > MC_FLUX_MAP_MAX) {
        return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_est_model, (float)(map->n_d < 2 || map->n_d > MC_FLUX_MAP_MAX ? map->n_d : map->n_q),
                         "flux map grid points per axis must be 2..41");
    }
    if (!isfinite(map->id0) || !isfinite(map->iq0) || !(map->did > 0.0f) || !(map->diq > 0.0f) ||
        !isfinite(map->did) || !isfinite(map->diq)) {
        return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_est_model, map->did, "flux map grid origin and steps must be finite, steps > 0");
    }
    for (int k = 0; k < map->n_d * map->n_q; ++k) {
        if (!isfinite(map->psi_d[k]) || !isfinite(map->psi_q[k]) || fabsf(map->psi_d[k]) > 100.0f ||
            fabsf(map->psi_q[k]) > 100.0f) {
            return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_est_model, map->psi_d[k], "flux map values must be finite and below 100 Wb");
        }
    }
    return true;
}

/* periods, rounded up and bounded (the table bounds the inputs; the bound keeps a float beyond
 * uint32_t out of the conversion) */
static uint32_t periods_up(float x)
{
    return x < 1.0f ? 1u : (x > 1.0e6f ? 1000000u : (uint32_t)ceilf(x));
}

/* The catch (mc/catch.h) from the estimator's model: the time the back-EMF at the slowest speed
 * that counts as turning takes to drive a current, i Lq / (psi_pm w_min), sets the probe (a
 * quarter of catch_i_a), the longest pulse (1.5 x catch_i_a) and the longest gap (a 20 deg turn). */
static void build_catch(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b)
{
    const float w_min = p->catch_min_rpm * RPM_TO_RAD_S * (float)p->pole_pairs;
    const float t_per_a = m->lq / (m->psi_pm * w_min);   /* [s/A] at w_min */
    const float rot = 0.35f;
    /* the longest wait: where the diodes conduct (above omega_ug = Vdc / (sqrt3 psi_pm)) their
     * current comes in pulses a sixth of a turn apart; 2.5 of them at omega_ug give (C.5) its
     * sign and a low to start from (5.2 ms on the thesis motor); at least 1 ms */
    const float w_ug = p->vdc_nominal / (1.7320508f * m->psi_pm);
    const float wait = fmaxf(2.5f * 1.0471976f / w_ug, 1e-3f);
    b->fly = (mc_catch_cfg_t){.ts = p->ts, .ld = m->ld, .lq = m->lq, .psi_pm = m->psi_pm,
                              .i_pulse = p->catch_i, .i_detect = 0.25f * p->catch_i, .i_rest = p->ip_i_rest,
                              .rot_target = rot, .high_speed_share = 0.9f, .v_device = p->v_device,
                              .i_band = p->dtc_i_band,
                              .n_probe = periods_up(0.25f * p->catch_i * t_per_a / p->ts),
                              .n_pulse_max = periods_up(1.5f * p->catch_i * t_per_a / p->ts),
                              .n_gap_max = periods_up(rot / (w_min * p->ts)),
                              .n_wait_max = periods_up(wait / p->ts)};
    if (b->fly.n_gap_max < 2u) {
        b->fly.n_gap_max = 2u;
    }
    if (b->fly.n_wait_max > b->fly.n_gap_max) {
        b->fly.n_wait_max = b->fly.n_gap_max;
    }
    b->seq.timeout_catch =
        (float)(2u * b->fly.n_pulse_max + 2u * b->fly.n_gap_max + 10u) * p->ts;
}

static void build_startup(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b)
{
    mc_initpos_cfg_default(&b->ip1);
    b->ip1.ts = p->ts;
    b->ip1.rs = m->rs;
    b->ip1.ld = m->ld;
    b->ip1.lq = m->lq;
    b->ip1.cost = (mc_ip_cost_t)p->ip1_cost;
    b->ip1.model = (mc_flux_model_t){MC_FLUX_MAP, m->ld, m->lq, m->psi_pm, m->map};
    b->ip1.m = (int)p->ip1_m;
    b->ip1.n_dir = (int)p->ip1_dirs;
    b->ip1.i_trip = p->i_trip;
    b->ip1.i_rest = p->ip_i_rest;
    mc_pulse3_cfg_default(&b->pulse3);
    b->pulse3.rs = m->rs;
    b->pulse3.n = (int)p->ip1_m;
    b->pulse3.i_trip = p->i_trip;
    b->pulse3.i_rest = p->ip_i_rest;
    mc_polarity_cfg_default(&b->ip2);
    b->ip2.ts = p->ts;
    b->ip2.rs = m->rs;
    b->ip2.model = b->ip1.model;
    b->ip2.v_pol = p->v_pol;
    b->ip2.n = (int)p->ip2_n;
    b->ip2.i_trip = p->i_trip;
    b->ip2.i_rest = p->ip_i_rest;
    mc_dvi_cfg_default(&b->dvi);
    b->dvi.rs = m->rs;
    b->dvi.v = p->v_pol;
    b->dvi.n = (int)p->dvi_n;
    b->dvi.i_trip = p->i_trip;
    b->dvi.i_rest = p->ip_i_rest;
    b->three_step = p->init_three_step == MC_CHOICE_init_three_step_three_step;
    b->ip1_pulse3 = p->ip1_pulse3 == MC_CHOICE_ip1_pulse3_three_phase;
    b->ip2_dvi = p->ip2_dvi == MC_CHOICE_ip2_dvi_dvi;
    const float cal = 2.0f * (float)p->offset_cal_samples * p->ts;
    b->seq = (mc_seq_cfg_t){.ts = p->ts, .init_pos = b->three_step, .timeout_cal = cal > 0.1f ? cal : 0.1f,
                            .timeout_step12 = p->timeout_step12, .timeout_step3 = p->timeout_step3};
    b->seq.catch_first = p->catch_on == MC_CHOICE_catch_on_on && mc_angle_src_get(p->angle_src)->cls == MC_ANGLE_ESTIMATOR;
    b->src_measures = mc_angle_src_get(p->angle_src)->cls == MC_ANGLE_SENSOR;
    build_catch(p, m, b);
    b->step3_speed_tol = p->step3_tol_rpm * RPM_TO_RAD_S * (float)p->pole_pairs;
    b->step3_hold = (uint32_t)(p->step3_hold / p->ts + 0.5f);
    mc_lpf1_init(&b->step3_lpf, 50.0f, p->ts, 0.0f);
}

/* The selected angle source: the machine model it gets (estimator.model's form of the estimator's
 * model; the drive's decoupling and field-weakening entry use the same one), then its own
 * configuration by its descriptor; the injection follows its capabilities. */
static bool build_source(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b, mc_param_err_t *err)
{
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->angle_src);
    b->src.rs = m->rs;
    b->src.model = p->est_model == MC_CHOICE_est_model_fluxmap ? (mc_flux_model_t){MC_FLUX_MAP, m->ld, m->lq, m->psi_pm, m->map}
                                     : (mc_flux_model_t){MC_FLUX_CONST, m->ld, m->lq, m->psi_pm, 0};
    if (!src->build(p, b->src.rs, &b->src.model, &b->src.cfg, err)) {
        return false;
    }
    b->inject = src->needs_injection && p->inj_kind != MC_CHOICE_inj_kind_off;
    b->cc_map = b->src.model.kind == MC_FLUX_MAP && b->src.model.map != 0;
    b->inj = (mc_inj_cfg_t){.kind = (mc_inj_kind_t)p->inj_kind, .v1 = p->inj_v1, .f_hz = p->inj_f_hz,
                            .omega_n1 = p->n1_rpm * RPM_TO_RAD_S * (float)p->pole_pairs, .ts = p->ts};
    const float f_notch = p->inj_f_hz < 0.45f / p->ts ? p->inj_f_hz : 0.45f / p->ts;
    mc_biquad_init_notch(&b->notch, f_notch, p->notch_q, p->ts);
    return true;
}

static uint32_t periods_of(float seconds, float ts)
{
    return seconds > 0.0f ? (uint32_t)(seconds / ts + 0.5f) : 0u;   /* bounded by the table */
}

static void build_protection(const mc_params_t *p, mc_drive_blk_t *b)
{
    const float el = RPM_TO_RAD_S * (float)p->pole_pairs;
    mc_protect_cfg_t *r = &b->prot;
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->angle_src);
    r->ts = p->ts;
    r->pole_pairs = (int)p->pole_pairs;
    r->adc_max = (int32_t)(float)((1L << p->adc_bits) - 1L);
    r->i_trip = p->i_trip;
    r->vdc_min = p->vdc_min;
    r->vdc_max = p->vdc_max;
    r->rs = p->rs;
    r->ld = p->ld;
    r->lq = p->lq;
    r->psi_pm = p->psi_pm;
    r->overspeed = p->overspeed_rpm * el;
    r->recover = p->lock_action == MC_CHOICE_lock_action_recover && src->cls == MC_ANGLE_ESTIMATOR;
    r->hold_fw = p->overspeed_action == MC_CHOICE_overspeed_action_hold_fw;
    r->ug_coef = 1.7320508f * p->psi_pm;
    b->seq.timeout_reaction = p->reaction_timeout;
    r->retries = (uint32_t)p->retries;
    r->retry_reset_n = periods_of(p->retry_reset, p->ts);
    /* 20 Hz: well below the injection and PWM ripple, fast against the 20 ms persistences */
    r->avg_k = 1.0f - expf(-MC_2PI * 20.0f * p->ts);
    r->i_sum_tol = p->i_sum_tol;
    r->i_sum_n = periods_of(p->i_sum_time, p->ts);
    r->track_err = p->track_err;
    r->track_n = periods_of(p->track_time, p->ts);
    r->lock_tol = p->lock_tol;
    r->lock_floor = p->lock_floor_rpm * el;
    r->lock_n = src->lock_checks ? periods_of(p->lock_time, p->ts) : 0u;
    r->jump_n = src->lock_checks ? periods_of(p->jump_time, p->ts) : 0u;
    r->jump = p->jump_deg * (MC_PI / 180.0f);
    r->stall_speed = p->stall_rpm * el;
    r->stall_torque = 0.9f * p->torque_max;
    r->stall_n = periods_of(p->stall_time, p->ts);
    r->accel_n = periods_of(p->accel_time, p->ts);
    r->accel_torque = 0.5f * p->torque_max;
    r->accel_per_nm = 0.5f * (float)p->pole_pairs / p->inertia;
    r->resid_v = p->resid_v;
    r->resid_w_coef = 0.5f * p->lq * p->i_max;
    r->resid_n = periods_of(p->resid_time, p->ts);
}

/* The running polarity re-check (mc/polcheck.h); after build_protection (its 20 Hz average). */
static void build_polcheck(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b)
{
    mc_polcheck_cfg_t *pc = &b->pol;
    pc->enable = p->pol_check != MC_CHOICE_pol_check_off;
    pc->at_start = p->pol_check == MC_CHOICE_pol_check_at_start;
    pc->inject = b->inject;
    pc->three_step = b->three_step;
    pc->omega_n1 = b->inj.omega_n1;
    pc->bias = p->pol_bias;
    /* the polarity re-check's expected HF ratio from the map's l_dd at +-I_b (none: 0) */
    pc->log_ratio = 0.0f;
    if (m->map != 0) {
        const mc_flux_model_t fm = {MC_FLUX_MAP, m->ld, m->lq, m->psi_pm, m->map};
        mc_dq_t psi;
        float lp[4], ln[4];
        mc_flux_eval(&fm, (mc_dq_t){p->pol_bias, 0.0f}, &psi, lp, 0);
        mc_flux_eval(&fm, (mc_dq_t){-p->pol_bias, 0.0f}, &psi, ln, 0);
        if (lp[0] > 0.0f && ln[0] > 0.0f) {
            pc->log_ratio = 2.0f * logf(ln[0] / lp[0]);
        }
    }
    /* 2 injection cycles to settle, 4 to measure */
    const float cyc = 1.0f / (p->inj_f_hz * p->ts);
    pc->settle_n = periods_up(2.0f * cyc);
    pc->measure_n = periods_up(4.0f * cyc);
    /* at_start: after five time constants of the PLL, when a wrong start angle has settled on
     * one of the HF saliency's two solutions */
    pc->start_n = periods_up(5.0f / (MC_2PI * p->pll_bw_hz) / p->ts);
    /* the speed estimate may drift by 5 x Step III's tolerance during the check */
    pc->w_scale = 0.1745f / (5.0f * p->step3_tol_rpm * RPM_TO_RAD_S * (float)p->pole_pairs);
    pc->avg_k = b->prot.avg_k;
}

bool mc_drive_build(const mc_drive_cfg_t *cfg, mc_drive_built_t *out, mc_param_err_t *err)
{
    out->p = cfg->p;
    mc_params_t *p = &out->p;
    mc_params_derive(p);
    if (!mc_params_validate(p, err)) {
        return false;
    }
    /* the flux map: where the source needs it with this estimator.model, and for Steps I-II's
     * l_dd profile and nonlinear costs */
    const bool need_map = (mc_angle_src_get(p->angle_src)->map_models & 1u << p->est_model) != 0u ||
                          (p->init_three_step == MC_CHOICE_init_three_step_three_step &&
                           (p->ip2_dvi == MC_CHOICE_ip2_dvi_generalized ||
                            (p->ip1_pulse3 == MC_CHOICE_ip1_pulse3_pulses && p->ip1_cost != MC_CHOICE_ip1_cost_linear)));
    mc_est_model_t m;
    if (!check_model(p, &cfg->est, &m, need_map, err)) {
        return false;
    }
    mc_drive_blk_t *b = &out->blk;
    *b = (mc_drive_blk_t){0};
    b->ts = p->ts;
    b->pole_pairs = (int)p->pole_pairs;
    const float max_count = (float)((1L << p->adc_bits) - 1L);
    b->offs.amps_per_count = 2.0f * p->i_span / max_count;
    b->volts_per_count = p->vdc_span / max_count;
    b->offs.nominal = (float)(1L << (p->adc_bits - 1));
    b->offs.tol = p->adc_offset_tol * (float)(1L << p->adc_bits);
    b->offs.ts = p->ts;
    b->i_ref_max = p->i_max * (1.0f - p->i_headroom);
    b->fwe = (mc_fwe_cfg_t){.ts = p->ts, .rs = m.rs, .i_stop = 1.1f * p->i_max, .overmod = p->u_loop > 1.0f};
    b->u_loop = p->u_loop;
    b->i_slew = p->i_slew;
    b->offs.samples = (uint32_t)p->offset_cal_samples;
    build_startup(p, &m, b);
    if (!build_source(p, &m, b, err)) {
        return false;
    }
    build_protection(p, b);
    build_polcheck(p, &m, b);

    mc_cc_cfg_from_bandwidth(&out->cc, p->cc_bw_hz, p->rs, p->ld, p->lq, p->psi_pm, p->ts);
    out->cc.decouple = p->cc_decouple != 0;
    out->sc = (mc_sc_cfg_t){.kp = p->sc_kp, .ki = p->sc_ki, .ts = p->ts * (float)p->sc_decimation,
                            .torque_max = p->torque_max, .decimation = (int)p->sc_decimation};
    out->tref = (mc_tref_cfg_t){.pole_pairs = (int)p->pole_pairs,
                                .mach = {.ld = p->ld, .lq = p->lq, .psi_pm = p->psi_pm},
                                .i_max = b->i_ref_max, .u_margin = p->u_margin, .use_table = p->mtpa_table == MC_CHOICE_mtpa_table_table,
                                .ts = p->ts};
    mc_mtpa_table_fill_linear(&out->tref.table, &out->tref.mach, b->i_ref_max);
    out->dtc = (mc_dtc_cfg_t){.t_dead = p->dead_time, .t_pwm = p->ts, .i_band = p->dtc_i_band,
                              .enable = p->dtc_enable != 0};
    return true;
}

/* Background side of a parameter change: the whole configuration is derived and validated again
 * from the newest one with this one value changed, into the spare slot of the link; the ISR swaps
 * it in at its next period (take_config in drive.c). */
bool mc_drive_param_write(mc_drive_t *d, int id, float value, mc_param_err_t *err)
{
    if (id < 0 || id >= (int)MC_PARAM_COUNT) {
        return mc_param_fail(err, MC_PERR_UNKNOWN, id, value, "no such parameter");
    }
    if ((mc_drive_faults(d) & MC_FAULT_CONFIG) != 0u) {
        return mc_param_fail(err, MC_PERR_ACCESS, id, value, "the configuration was refused at init: init again");
    }
    const mc_state_t st = mc_drive_state(d);
    const bool outputs_off = st == MC_STATE_IDLE || st == MC_STATE_FAULT;
    switch ((mc_param_access_t)mc_param_table[id].access) {
    case MC_PA_INIT:
        return mc_param_fail(err, MC_PERR_ACCESS, id, value, "only at init");
    case MC_PA_STANDSTILL:
        if (!outputs_off) {
            return mc_param_fail(err, MC_PERR_ACCESS, id, value, "only while the outputs are off");
        }
        break;
    case MC_PA_RUNTIME:
    default:
        break;
    }
    mc_drive_built_t *slot = mc_drive_cfgbuf_begin(&d->link->cfg);
    if (slot == 0) {
        return mc_param_fail(err, MC_PERR_BUSY, id, value, "the previous change is not taken yet: retry");
    }
    mc_drive_cfg_t cfg = {.p = mc_drive_cfgbuf_latest(&d->link->cfg)->p, .est = d->est};
    if (!mc_param_set(&cfg.p, id, value, err) || !mc_drive_build(&cfg, slot, err)) {
        return false;   /* the slot stays spare: nothing is committed */
    }
    return mc_drive_cfgbuf_commit(&d->link->cfg);
}

bool mc_drive_params_write(mc_drive_t *d, const mc_params_t *p, mc_param_err_t *err)
{
    if ((mc_drive_faults(d) & MC_FAULT_CONFIG) != 0u) {
        return mc_param_fail(err, MC_PERR_ACCESS, -1, 0.0f, "the configuration was refused at init: init again");
    }
    const mc_state_t st = mc_drive_state(d);
    if (st != MC_STATE_IDLE && st != MC_STATE_FAULT) {
        return mc_param_fail(err, MC_PERR_ACCESS, -1, 0.0f, "only while the outputs are off");
    }
    const mc_params_t *now = &mc_drive_cfgbuf_latest(&d->link->cfg)->p;
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {   /* INIT parameters stay as they are */
        if (mc_param_table[id].access == MC_PA_INIT && mc_param_get(p, id) != mc_param_get(now, id)) {
            return mc_param_fail(err, MC_PERR_ACCESS, id, mc_param_get(p, id), "only at init");
        }
    }
    mc_drive_built_t *slot = mc_drive_cfgbuf_begin(&d->link->cfg);
    if (slot == 0) {
        return mc_param_fail(err, MC_PERR_BUSY, -1, 0.0f, "the previous change is not taken yet: retry");
    }
    const mc_drive_cfg_t cfg = {.p = *p, .est = d->est};
    if (!mc_drive_build(&cfg, slot, err)) {
        return false;
    }
    return mc_drive_cfgbuf_commit(&d->link->cfg);
}
