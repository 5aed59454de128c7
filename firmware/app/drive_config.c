/* The drive's configuration, background side: parameters -> validated, derived block
 * configurations (mc_drive_build). Nothing here runs in the ISR. */
#include <math.h>
#include "mc/drive.h"

#define RPM_TO_RAD_S (MC_2PI / 60.0f)

/* The blocks' own enums take these choices by position. */
_Static_assert(MC_CHOICE_injection_kind_off == (int)MC_INJ_OFF && MC_CHOICE_injection_kind_sine == (int)MC_INJ_SINE &&
                   MC_CHOICE_injection_kind_rect == (int)MC_INJ_RECT, "injection.kind and mc_inj_kind_t");
_Static_assert(MC_CHOICE_startup_step1_cost_linear == (int)MC_IP_COST_LINEAR &&
                   MC_CHOICE_startup_step1_cost_nonlinear == (int)MC_IP_COST_NONLINEAR &&
                   MC_CHOICE_startup_step1_cost_fluxdiff == (int)MC_IP_COST_FLUXDIFF, "startup.step1_cost and mc_ip_cost_t");

void mc_drive_cfg_default(mc_drive_cfg_t *cfg)
{
    mc_params_default(&cfg->p);
    cfg->est = (mc_est_model_t){.rs = NAN, .ld = NAN, .lq = NAN, .psi_pm = NAN, .map = 0};
}

static float or_motor(float v, float motor)
{
    return isnan(v) ? motor : v;
}

/* The estimator's model as the flux-model blocks take it: its map, or (none) its constants. */
static mc_flux_model_t est_flux_model(const mc_est_model_t *m)
{
    return (mc_flux_model_t){MC_FLUX_MAP, m->ld, m->lq, m->psi_pm, m->map};
}

/* The estimator's model: the motor's unless given, each value as plausible as the motor entry
 * it stands for; the flux map's grid must fit the table and hold finite numbers only. */
static bool check_model(const mc_params_t *p, const mc_est_model_t *in, mc_est_model_t *m, bool need_map,
                        mc_param_err_t *err)
{
    *m = (mc_est_model_t){.rs = or_motor(in->rs, p->motor_rs_ohm), .ld = or_motor(in->ld, p->motor_ld_h),
                          .lq = or_motor(in->lq, p->motor_lq_h), .psi_pm = or_motor(in->psi_pm, p->motor_psi_pm_wb), .map = in->map};
    const struct { float v; int id; } vals[4] = {
        {m->rs, MC_PARAM_motor_rs_ohm}, {m->ld, MC_PARAM_motor_ld_h}, {m->lq, MC_PARAM_motor_lq_h}, {m->psi_pm, MC_PARAM_motor_psi_pm_wb}};
    for (int k = 0; k < 4; ++k) {
        const mc_param_info_t *e = &mc_param_table[vals[k].id];
        if (!isfinite(vals[k].v) || vals[k].v < e->min || vals[k].v > e->max) {
            return mc_param_fail(err, MC_PERR_MODEL, vals[k].id, vals[k].v, "the estimator model's value is out of the motor entry's range");
        }
    }
    const mc_flux_map_t *map = m->map;
    if (map == 0) {
        return need_map ? mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_estimator_model, 0.0f, "this configuration needs the estimator's flux map")
                        : true;
    }
    if (map->n_d < 2 || map->n_d > MC_FLUX_MAP_MAX || map->n_q < 2 || map->n_q > MC_FLUX_MAP_MAX) {
        return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_estimator_model, (float)(map->n_d < 2 || map->n_d > MC_FLUX_MAP_MAX ? map->n_d : map->n_q),
                         "flux map grid points per axis must be 2..41");
    }
    if (!isfinite(map->id0) || !isfinite(map->iq0) || !(map->did > 0.0f) || !(map->diq > 0.0f) ||
        !isfinite(map->did) || !isfinite(map->diq)) {
        return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_estimator_model, map->did, "flux map grid origin and steps must be finite, steps > 0");
    }
    for (int k = 0; k < map->n_d * map->n_q; ++k) {
        if (!isfinite(map->psi_d[k]) || !isfinite(map->psi_q[k]) || fabsf(map->psi_d[k]) > 100.0f ||
            fabsf(map->psi_q[k]) > 100.0f) {
            return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_estimator_model, map->psi_d[k], "flux map values must be finite and below 100 Wb");
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

/* The current one V(000) period drives at speed w by (C.1) of mc/catch.h, from i = 0 [A]. */
static float catch_i1(const mc_est_model_t *m, float w, float ts)
{
    const float dl = w * ts;
    const float id = (cosf(dl) - 1.0f) / m->ld, iq = sinf(dl) / m->lq;
    return m->psi_pm * sqrtf(id * id + iq * iq);
}

/* The catch (mc/catch.h) from the estimator's model: the time the back-EMF at the slowest speed
 * that counts as turning takes to drive a current, i Lq / (psi_pm w_min), sets the probe (a
 * quarter of catch_i_a), the longest pulse (1.5 x catch_i_a) and the longest gap (a 20 deg turn). */
static void build_catch(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b)
{
    const float w_min = p->startup_catch_min_rpm * RPM_TO_RAD_S * (float)p->motor_pole_pairs;
    const float t_per_a = m->lq / (m->psi_pm * w_min);   /* [s/A] at w_min */
    const float rot = 0.35f;
    /* the longest wait: where the diodes conduct (above omega_ug = Vdc / (sqrt3 psi_pm)) their
     * current comes in pulses a sixth of a turn apart; 2.5 of them at omega_ug give (C.5) its
     * sign and a low to start from (5.2 ms on the thesis motor); at least 1 ms */
    const float w_ug = p->hw_vdc_nominal_v / (1.7320508f * m->psi_pm);
    const float wait = fmaxf(2.5f * 1.0471976f / w_ug, 1e-3f);
    b->flying = (mc_catch_cfg_t){.ts = p->control_ts_s, .ld = m->ld, .lq = m->lq, .psi_pm = m->psi_pm,
                              .i_pulse = p->startup_catch_i_a, .i_detect = 0.25f * p->startup_catch_i_a, .i_rest = p->startup_i_rest_a,
                              .rot_target = rot, .high_speed_share = 0.9f, .v_device = p->hw_device_drop_v,
                              .i_band = p->control_dtc_i_band_a,
                              .n_probe = periods_up(0.25f * p->startup_catch_i_a * t_per_a / p->control_ts_s),
                              .n_pulse_max = periods_up(1.5f * p->startup_catch_i_a * t_per_a / p->control_ts_s),
                              .n_gap_max = periods_up(rot / (w_min * p->control_ts_s)),
                              .n_wait_max = periods_up(wait / p->control_ts_s)};
    if (b->flying.n_gap_max < 2u) {
        b->flying.n_gap_max = 2u;
    }
    if (b->flying.n_wait_max > b->flying.n_gap_max) {
        b->flying.n_wait_max = b->flying.n_gap_max;
    }
    /* The shortest pulse is one period: where it drives more than 1.1 i_max below the generation
     * speed, the catch cannot keep the limit there at this f_s (siemens-1ft7044-spm at 8 kHz:
     * 10 A for 8.06 A at its base speed). The speed it still can, for the configuration's
     * report, by bisection of (C.1), monotone in w ts up to pi. */
    const float i_lim = 1.1f * p->control_i_max_a;
    b->flying.w_limit = 0.0f;
    b->flying.ts_cover = 0.0f;
    if (catch_i1(m, w_ug, p->control_ts_s) > i_lim) {
        float lo = 0.0f, hi = fminf(w_ug, MC_PI / p->control_ts_s);
        for (int k = 0; k < 24; ++k) {
            const float mid = 0.5f * (lo + hi);
            if (catch_i1(m, mid, p->control_ts_s) > i_lim) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        b->flying.w_limit = lo;
        b->flying.ts_cover = lo * p->control_ts_s / w_ug;   /* (C.1) depends on w ts only */
    }
    b->seq.timeout_catch =
        (float)(2u * b->flying.n_pulse_max + 2u * b->flying.n_gap_max + 10u) * p->control_ts_s;
}

/* The flux swing [Wb] the model allows from i = 0 before |i| reaches i_lim, the smallest over the
 * +d, -d and +q directions: along +d the magnet-aided saturation lowers l_dd, so a pulse sized
 * by Ld at i = 0 overshoots there (brodatzki-35kw: 213 A for a 160 A limit). */
static float flux_room(const mc_est_model_t *m, float i_lim)
{
    const mc_flux_model_t fm = est_flux_model(m);
    mc_dq_t p0, pq;
    mc_flux_eval(&fm, (mc_dq_t){0.0f, 0.0f}, &p0, NULL, NULL);
    mc_flux_eval(&fm, (mc_dq_t){0.0f, i_lim}, &pq, NULL, NULL);
    const float r = mc_flux_swing_d(&fm, i_lim), c = pq.q - p0.q;
    return r < c ? r : c;
}

/* Standstill saliency the injection methods read (Steps I-II, Step III's HF injection): the HF
 * current's difference between the axes, i_hf |1 - l_dd / l_qq| at i = 0, against the ADC
 * quantum q. An angle is read from the q-axis HF current, about that difference per radian:
 * at least 4 quanta keep one quantum within 1/8 rad (7 deg) of angle. */
static bool saliency_usable(const mc_params_t *p, const mc_est_model_t *m)
{
    const mc_flux_model_t fm = est_flux_model(m);
    mc_dq_t psi;
    float l[4];
    mc_flux_eval(&fm, (mc_dq_t){0.0f, 0.0f}, &psi, l, NULL);
    const float ldd = l[0], lqq = l[3];
    const float q = 2.0f * p->hw_i_span_a / (float)(1L << p->hw_adc_bits);
    const float di = p->injection_i_hf_a * fabsf(1.0f - ldd / lqq);
    return ldd > 0.0f && lqq > 0.0f && di >= 4.0f * q;
}

static void build_startup(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b)
{
    mc_initpos_cfg_default(&b->step1);
    b->step1.ts = p->control_ts_s;
    b->step1.rs = m->rs;
    b->step1.ld = m->ld;
    b->step1.lq = m->lq;
    b->step1.cost = (mc_ip_cost_t)p->startup_step1_cost;
    b->step1.model = est_flux_model(m);
    b->step1.m = (int)p->startup_step1_m;
    /* the pulse's current by the model, not Ld at i = 0: at most 0.9 i_max (the 2/3 Vdc of a
     * direct vector for m periods) */
    const float room = flux_room(m, 0.9f * p->control_i_max_a);
    const float m_max = floorf(room / (2.0f / 3.0f * p->hw_vdc_nominal_v * p->control_ts_s));
    if (m_max < (float)b->step1.m) {
        b->step1.m = m_max < 1.0f ? 1 : (int)m_max;
    }
    if (m_max < 1.0f) {   /* even one period too much: a shorter vector for one period */
        b->step1.v_pulse = room / p->control_ts_s;
    }
    b->step1.n_dir = (int)p->startup_step1_dirs;
    b->step1.i_trip = p->control_i_trip_a;
    b->step1.i_rest = p->startup_i_rest_a;
    mc_pulse3_cfg_default(&b->pulse3);
    b->pulse3.rs = m->rs;
    b->pulse3.n = (int)p->startup_step1_m;
    b->pulse3.i_trip = p->control_i_trip_a;
    b->pulse3.i_rest = p->startup_i_rest_a;
    mc_polarity_cfg_default(&b->step2);
    b->step2.ts = p->control_ts_s;
    b->step2.rs = m->rs;
    b->step2.model = b->step1.model;
    b->step2.v_pol = p->startup_v_pol_v;
    b->step2.n = (int)p->startup_step2_n;
    /* +-v n Ts along d: by the model at most 0.9 i_max either way */
    const float v_max = room / ((float)b->step2.n * p->control_ts_s);
    b->step2.v_pol = b->step2.v_pol < v_max ? b->step2.v_pol : v_max;
    b->step2.i_trip = p->control_i_trip_a;
    b->step2.i_rest = p->startup_i_rest_a;
    b->step2.z_min = p->startup_polarity_z_min;
    b->step2.i_max = p->control_i_max_a;
    mc_dvi_cfg_default(&b->dvi);
    b->dvi.rs = m->rs;
    b->dvi.n = (int)p->startup_dvi_n;
    const float v_dvi = room / ((float)b->dvi.n * p->control_ts_s);
    b->dvi.v = p->startup_v_pol_v < v_dvi ? p->startup_v_pol_v : v_dvi;
    b->dvi.i_trip = p->control_i_trip_a;
    b->dvi.i_rest = p->startup_i_rest_a;
    b->dvi.z_min = p->startup_polarity_z_min;
    b->dvi.reps_max = 3;   /* 3 programs of about 4 ms: Step I + II stay within the 20 ms time-out */
    b->three_step = p->startup_init_pos == MC_CHOICE_startup_init_pos_three_step;
    b->ip1_pulse3 = p->startup_step1_method == MC_CHOICE_startup_step1_method_three_phase;
    b->ip2_dvi = p->startup_polarity == MC_CHOICE_startup_polarity_dvi;
    const float cal = 2.0f * (float)p->control_offset_cal_samples * p->control_ts_s;
    b->seq = (mc_seq_cfg_t){.ts = p->control_ts_s, .init_pos = b->three_step, .timeout_cal = cal > 0.1f ? cal : 0.1f,
                            .timeout_step12 = p->startup_timeout_step12_s, .timeout_step3 = p->startup_timeout_step3_s};
    b->seq.catch_first = p->startup_catch == MC_CHOICE_startup_catch_on && mc_angle_src_get(p->control_angle_source)->cls == MC_ANGLE_ESTIMATOR;
    b->src_measures = mc_angle_src_get(p->control_angle_source)->cls == MC_ANGLE_SENSOR;
    build_catch(p, m, b);
    b->step3_speed_tol = p->startup_step3_speed_tol_rpm * RPM_TO_RAD_S * (float)p->motor_pole_pairs;
    b->step3_hold = (uint32_t)(p->startup_step3_hold_s / p->control_ts_s + 0.5f);
    mc_lpf1_init(&b->step3_lpf, 50.0f, p->control_ts_s, 0.0f);
}

/* The selected angle source: the machine model it gets (estimator.model's form of the estimator's
 * model; the drive's decoupling and field-weakening entry use the same one), then its own
 * configuration by its descriptor; the injection follows its capabilities. */
static bool build_source(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b, mc_param_err_t *err)
{
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->control_angle_source);
    b->src.rs = m->rs;
    b->src.model = p->estimator_model == MC_CHOICE_estimator_model_fluxmap ? est_flux_model(m)
                                     : (mc_flux_model_t){MC_FLUX_CONST, m->ld, m->lq, m->psi_pm, 0};
    if (!src->build(p, b->src.rs, &b->src.model, &b->src.cfg, err)) {
        return false;
    }
    b->inject = src->needs_injection && p->injection_kind != MC_CHOICE_injection_kind_off;
    b->cc_map = b->src.model.kind == MC_FLUX_MAP && b->src.model.map != 0;
    b->inj = (mc_inj_cfg_t){.kind = (mc_inj_kind_t)p->injection_kind, .v1 = p->injection_v1_v, .f_hz = p->injection_f_hz,
                            .omega_n1 = p->injection_n1_rpm * RPM_TO_RAD_S * (float)p->motor_pole_pairs, .ts = p->control_ts_s};
    const float f_notch = p->injection_f_hz < 0.45f / p->control_ts_s ? p->injection_f_hz : 0.45f / p->control_ts_s;
    mc_biquad_init_notch(&b->notch, f_notch, p->injection_notch_q, p->control_ts_s);
    return true;
}

static uint32_t periods_of(float seconds, float ts)
{
    return seconds > 0.0f ? (uint32_t)(seconds / ts + 0.5f) : 0u;   /* bounded by the table */
}

static void build_protection(const mc_params_t *p, mc_drive_blk_t *b)
{
    const float el = RPM_TO_RAD_S * (float)p->motor_pole_pairs;
    mc_protect_cfg_t *r = &b->prot;
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->control_angle_source);
    r->ts = p->control_ts_s;
    r->pole_pairs = (int)p->motor_pole_pairs;
    r->adc_max = (int32_t)(float)((1L << p->hw_adc_bits) - 1L);
    r->i_trip = p->control_i_trip_a;
    r->vdc_min = p->control_vdc_min_v;
    r->vdc_max = p->control_vdc_max_v;
    r->rs = p->motor_rs_ohm;
    r->ld = p->motor_ld_h;
    r->lq = p->motor_lq_h;
    r->psi_pm = p->motor_psi_pm_wb;
    r->overspeed = p->protection_overspeed_rpm * el;
    r->recover = p->protection_lock_action == MC_CHOICE_protection_lock_action_recover && src->cls == MC_ANGLE_ESTIMATOR;
    r->hold_fw = p->protection_overspeed_action == MC_CHOICE_protection_overspeed_action_hold_fw;
    r->ug_coef = 1.7320508f * p->motor_psi_pm_wb;
    b->seq.timeout_reaction = p->protection_reaction_timeout_s;
    r->retries = (uint32_t)p->protection_retries;
    r->retry_reset_n = periods_of(p->protection_retry_reset_s, p->control_ts_s);
    /* 20 Hz: well below the injection and PWM ripple, fast against the 20 ms persistences */
    r->avg_k = 1.0f - expf(-MC_2PI * 20.0f * p->control_ts_s);
    r->i_sum_tol = p->protection_i_sum_tol_a;
    r->i_sum_n = periods_of(p->protection_i_sum_time_s, p->control_ts_s);
    r->track_err = p->protection_tracking_err_a;
    r->track_n = periods_of(p->protection_tracking_time_s, p->control_ts_s);
    r->lock_tol = p->protection_lock_speed_tol;
    r->lock_floor = p->protection_lock_speed_floor_rpm * el;
    r->lock_n = src->lock_checks ? periods_of(p->protection_lock_time_s, p->control_ts_s) : 0u;
    r->jump_n = src->lock_checks ? periods_of(p->protection_lock_jump_time_s, p->control_ts_s) : 0u;
    r->jump = p->protection_lock_jump_deg * (MC_PI / 180.0f);
    r->stall_speed = p->protection_stall_speed_rpm * el;
    r->stall_torque = 0.9f * p->control_torque_max_nm;
    r->stall_n = periods_of(p->protection_stall_time_s, p->control_ts_s);
    r->accel_n = periods_of(p->protection_accel_time_s, p->control_ts_s);
    r->accel_torque = 0.5f * p->control_torque_max_nm;
    r->accel_per_nm = 0.5f * (float)p->motor_pole_pairs / p->motor_inertia_kgm2;
    r->resid_v = p->protection_residual_v;
    r->resid_w_coef = 0.5f * p->motor_lq_h * p->control_i_max_a;
    r->resid_n = periods_of(p->protection_residual_time_s, p->control_ts_s);
}

/* The running polarity re-check (mc/polcheck.h); after build_protection (its 20 Hz average). */
static void build_polcheck(const mc_params_t *p, const mc_est_model_t *m, mc_drive_blk_t *b)
{
    mc_polcheck_cfg_t *pc = &b->pol;
    pc->enable = p->protection_polarity_check != MC_CHOICE_protection_polarity_check_off;
    pc->at_start = p->protection_polarity_check == MC_CHOICE_protection_polarity_check_at_start;
    pc->inject = b->inject;
    pc->three_step = b->three_step;
    pc->omega_n1 = b->inj.omega_n1;
    pc->bias = p->protection_polarity_bias_a;
    /* the polarity re-check's expected HF ratio from the map's l_dd at +-I_b (none: 0) */
    pc->log_ratio = 0.0f;
    if (m->map != 0) {
        const mc_flux_model_t fm = est_flux_model(m);
        mc_dq_t psi;
        float lp[4], ln[4];
        mc_flux_eval(&fm, (mc_dq_t){p->protection_polarity_bias_a, 0.0f}, &psi, lp, 0);
        mc_flux_eval(&fm, (mc_dq_t){-p->protection_polarity_bias_a, 0.0f}, &psi, ln, 0);
        if (lp[0] > 0.0f && ln[0] > 0.0f) {
            pc->log_ratio = 2.0f * logf(ln[0] / lp[0]);
        }
    }
    /* 2 injection cycles to settle, 4 to measure */
    const float cyc = 1.0f / (p->injection_f_hz * p->control_ts_s);
    pc->settle_n = periods_up(2.0f * cyc);
    pc->measure_n = periods_up(4.0f * cyc);
    /* at_start: after five time constants of the PLL, when a wrong start angle has settled on
     * one of the HF saliency's two solutions */
    pc->start_n = periods_up(5.0f / (MC_2PI * p->estimator_pll_bw_hz) / p->control_ts_s);
    /* the speed estimate may drift by 5 x Step III's tolerance during the check */
    pc->w_scale = 0.1745f / (5.0f * p->startup_step3_speed_tol_rpm * RPM_TO_RAD_S * (float)p->motor_pole_pairs);
    pc->avg_k = b->prot.avg_k;
}

/* startup.init_pos = auto resolved (three_step where the injection reads the saliency, else
 * if_start), and I/f (mc/if_start.h; Fatu et al. 2008) below the hand-over speed wherever the
 * estimator has no saliency to read, or with if_start. Sets three_step, the sequencer's
 * init_pos and the polarity re-check's view of them before build_polcheck. */
static bool build_if(const mc_params_t *p, bool salient, mc_drive_blk_t *b, mc_param_err_t *err)
{
    const int ip = p->startup_init_pos;
    const bool estimator = mc_angle_src_get(p->control_angle_source)->cls == MC_ANGLE_ESTIMATOR;
    if (ip == MC_CHOICE_startup_init_pos_if_start && !estimator) {
        return mc_param_fail(err, MC_PERR_CROSS, MC_PARAM_startup_init_pos, (float)ip,
                             "the I/f start is for a sensorless angle source (control.angle_source = unop): an angle "
                             "sensor knows the angle");
    }
    if (ip == MC_CHOICE_startup_init_pos_auto) {
        b->three_step = salient && estimator;
        b->seq.init_pos = b->three_step;
    }
    b->if_from_zero = estimator && (ip == MC_CHOICE_startup_init_pos_if_start || (ip == MC_CHOICE_startup_init_pos_auto && !salient));
    b->if_on = estimator && (b->if_from_zero || !salient);
    if (!b->if_on) {
        return true;
    }
    const float el = RPM_TO_RAD_S * (float)p->motor_pole_pairs;
    const float w_h = p->startup_if_handover_rpm * el;
    /* the alignment steps last one period of the rotor's swing about the frame under I_f, whose
     * stiffness is the peak torque per electrical radian: 2 pi / sqrt(1.5 p psi I_f p / J) */
    const float k_el = 1.5f * (float)p->motor_pole_pairs * p->motor_psi_pm_wb * p->startup_if_i_a * (float)p->motor_pole_pairs;
    const float t_swing = MC_2PI / sqrtf(fmaxf(k_el / p->motor_inertia_kgm2, 1e-6f));
    /* the rotor swings about the frame (nothing damps it but the load): synchronous within a
     * third of w_h for 10 ms; I_f then falls to nothing in 0.1 s unless the load angle reaches
     * 20 deg first (the torque balances with 6 % to spare) */
    b->ifs = (mc_if_cfg_t){.ts = p->control_ts_s, .i_f = p->startup_if_i_a, .accel = p->startup_if_accel_rpm_s * el,
                           .w_h = w_h, .w_l = 0.5f * w_h, .w_tol = w_h / 3.0f, .n_sync = periods_up(0.01f / p->control_ts_s),
                           .i_drop = 10.0f * p->startup_if_i_a, .i_min = 0.1f * p->startup_if_i_a, .delta_h = 0.35f,
                           .damp = 0.5f, .n_align = periods_up(t_swing / p->control_ts_s)};
    if (p->startup_if_i_a > p->control_i_max_a * (1.0f - p->control_i_headroom)) {
        return mc_param_fail(err, MC_PERR_CROSS, MC_PARAM_startup_if_i_a, p->startup_if_i_a,
                             "the I/f current must stay within control.i_max_a (1 - control.i_headroom)");
    }
    if (!mc_if_cfg_valid(&b->ifs)) {
        return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_startup_if_handover_rpm, p->startup_if_handover_rpm,
                             "the I/f configuration is not usable (speeds, current, ramp must be finite and > 0)");
    }
    return true;
}

/* The lowest sampling rate this motor allows (docs/parameters.md, "The lowest sampling rate"), in
 * samples a period of the electrical frequency at the no-load base speed Vdc / (sqrt3 psi_pm):
 * - 6 with any angle source: the voltage lands 1.5 periods after its angle was read, and the
 *   advance that compensates it assumes a constant speed; 6 keep that within a quarter turn;
 * - 20 sensorless: the current loop's rule bandwidth f_s / 40 is then half that frequency, so the
 *   back-EMF of a frame off the rotor (an angle error, I/f's open-loop frame), which turns at the
 *   electrical frequency, stays within the loop's reach (the demo failed below it: brodatzki-35kw
 *   at 5 kHz, siemens-1ft7044-spm at 7 kHz);
 * - while injecting, 4 a period of the injection (a sampled sine's two quadratures; at 2 a sine
 *   is seen only at its zero crossings or its peaks).
 * Refused above it with the period it needs (exit 2 in mcsim). */
static bool check_sampling(const mc_params_t *p, mc_param_err_t *err)
{
    const float f_el = p->hw_vdc_nominal_v * 0.57735027f / (MC_2PI * p->motor_psi_pm_wb);
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->control_angle_source);
    float fs_min = (src->cls == MC_ANGLE_ESTIMATOR ? 20.0f : 6.0f) * f_el;
    int why = MC_PARAM_motor_psi_pm_wb;
    if (src->needs_injection && p->injection_kind != MC_CHOICE_injection_kind_off && 4.0f * p->injection_f_hz > fs_min) {
        fs_min = 4.0f * p->injection_f_hz;
        why = MC_PARAM_injection_f_hz;
    }
    if (p->control_ts_s * fs_min <= 1.0f) {
        return true;
    }
    if (err != NULL) {
        *err = (mc_param_err_t){.kind = MC_PERR_CROSS, .param = MC_PARAM_control_ts_s, .param2 = why, .value = p->control_ts_s,
                                .value2 = mc_param_get(p, why), .min = mc_param_table[MC_PARAM_control_ts_s].min, .max = 1.0f / fs_min,
                                .text = why == MC_PARAM_injection_f_hz
                                            ? "f_s is below 4 x injection.f_hz: shorten control.ts_s or lower injection.f_hz"
                                            : "f_s is below this motor's lowest, 20 (sensorless; 6 with a sensor) x the electrical "
                                              "frequency at Vdc / (sqrt3 psi_pm): shorten control.ts_s"};
    }
    return false;
}

bool mc_drive_build(const mc_drive_cfg_t *cfg, mc_drive_built_t *out, mc_param_err_t *err)
{
    out->p = cfg->p;
    mc_params_t *p = &out->p;
    mc_params_derive(p);
    if (!mc_params_validate(p, err) || !check_sampling(p, err)) {
        return false;
    }
    /* the flux map: where the source needs it with this estimator.model, and for Steps I-II's
     * l_dd profile and nonlinear costs */
    const bool need_map = (mc_angle_src_get(p->control_angle_source)->map_models & 1u << p->estimator_model) != 0u ||
                          ((p->startup_init_pos == MC_CHOICE_startup_init_pos_three_step || p->startup_init_pos == MC_CHOICE_startup_init_pos_auto) &&
                           (p->startup_polarity == MC_CHOICE_startup_polarity_generalized ||
                            (p->startup_step1_method == MC_CHOICE_startup_step1_method_pulses && p->startup_step1_cost != MC_CHOICE_startup_step1_cost_linear)));
    mc_est_model_t m;
    if (!check_model(p, &cfg->est, &m, need_map, err)) {
        return false;
    }
    const bool salient = saliency_usable(p, &m);
    if (p->startup_init_pos == MC_CHOICE_startup_init_pos_three_step && !salient) {
        return mc_param_fail(err, MC_PERR_MODEL, MC_PARAM_startup_init_pos, (float)p->startup_init_pos,
                             "needs saliency, and the motor model has none to read (l_qq = l_dd at i = 0, or their "
                             "injection currents differ by less than 4 ADC counts): start with a known angle "
                             "(startup.init_pos = given), the I/f start (if_start, or auto: it chooses) or an encoder");
    }
    mc_drive_blk_t *b = &out->blk;
    *b = (mc_drive_blk_t){0};
    b->ts = p->control_ts_s;
    b->pole_pairs = (int)p->motor_pole_pairs;
    const float max_count = (float)((1L << p->hw_adc_bits) - 1L);
    b->offs.amps_per_count = 2.0f * p->hw_i_span_a / max_count;
    b->volts_per_count = p->hw_vdc_span_v / max_count;
    b->offs.nominal = (float)(1L << (p->hw_adc_bits - 1));
    b->offs.tol = p->hw_adc_offset_tol * (float)(1L << p->hw_adc_bits);
    b->offs.ts = p->control_ts_s;
    b->i_ref_max = p->control_i_max_a * (1.0f - p->control_i_headroom);
    b->fw_entry = (mc_fwe_cfg_t){.ts = p->control_ts_s, .rs = m.rs, .i_stop = 1.1f * p->control_i_max_a, .overmod = p->control_u_loop > 1.0f};
    b->u_loop = p->control_u_loop;
    b->i_slew = p->control_i_slew_a_per_s;
    b->offs.samples = (uint32_t)p->control_offset_cal_samples;
    build_startup(p, &m, b);
    if (!build_source(p, &m, b, err)) {
        return false;
    }
    if (!build_if(p, salient, b, err)) {
        return false;
    }
    build_protection(p, b);
    build_polcheck(p, &m, b);

    mc_cc_cfg_from_bandwidth(&out->cc, p->control_current_bw_hz, p->motor_rs_ohm, p->motor_ld_h, p->motor_lq_h, p->motor_psi_pm_wb, p->control_ts_s);
    out->cc.decouple = p->control_decouple != 0;
    out->sc = (mc_sc_cfg_t){.kp = p->control_speed_kp, .ki = p->control_speed_ki, .ts = p->control_ts_s * (float)p->control_speed_decimation,
                            .torque_max = p->control_torque_max_nm, .decimation = (int)p->control_speed_decimation};
    out->tref = (mc_tref_cfg_t){.pole_pairs = (int)p->motor_pole_pairs,
                                .mach = {.ld = p->motor_ld_h, .lq = p->motor_lq_h, .psi_pm = p->motor_psi_pm_wb},
                                .i_max = b->i_ref_max, .u_margin = p->control_u_margin, .use_table = p->control_mtpa == MC_CHOICE_control_mtpa_table,
                                .ts = p->control_ts_s};
    mc_mtpa_table_fill_linear(&out->tref.table, &out->tref.mach, b->i_ref_max);
    out->dtc = (mc_dtc_cfg_t){.t_dead = p->hw_dead_time_s, .t_pwm = p->control_ts_s, .i_band = p->control_dtc_i_band_a,
                              .enable = p->control_deadtime_comp != 0};
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
