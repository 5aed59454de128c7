/* Every run-time parameter reaches every consumer. Generated from the parameter table: for each
 * entry whose access is RUNTIME (writable while the outputs are on) and for each registered
 * angle source, a changed valid value is written to a running drive (RUN, through
 * mc_drive_param_write and the ISR's configuration swap, i.e. mc_drive_retune), and the
 * configuration every block then runs with is compared, field by field, with a drive built fresh
 * with that value (mc_drive_init: every block configured from scratch):
 *   - the parameters in force (d->cfg->p, with their "auto" marks),
 *   - the blocks that keep their own copy: current loop (and its two PIs), speed loop (and its
 *     PI), torque reference (with its MTPA table), dead-time compensation, injection, the
 *     injection notches, Step III's low-pass, the sequencer, and the angle source's own
 *     configuration (its descriptor's cfg_of / cfg_equal),
 *   - the values the ISR reads from d->cfg->blk directly (limits, protection, the source's model).
 * A parameter added to the table as RUNTIME is covered without touching this file; so is a new
 * angle source (built again with the test-only source: target app_runtime_params_extra). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "hal_host/host.h"
#include "mc/drive.h"

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    mc_drive_cfg_t cfg;
    mc_drive_link_t link;
    mc_drive_t d;
} rig_t;

/* The configuration under test: the defaults with the given source, the model without a map
 * (no source needs one then) and no catch (a sensorless enable goes straight to RUN with the
 * handed-over angle). */
static void cfg_for(mc_drive_cfg_t *cfg, int src)
{
    mc_drive_cfg_default(cfg);
    assert_true(mc_param_set(&cfg->p, MC_PARAM_control_angle_source, (float)src, NULL));
    assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_estimator_model, "const", NULL));
    assert_true(mc_param_set_choice(&cfg->p, MC_PARAM_startup_catch, "off", NULL));
}

static bool rig_init(rig_t *r, const mc_drive_cfg_t *cfg)
{
    *r = (rig_t){0};
    hal_host_pwm_init(&r->pwm, 1e-4f, 0.5e-6f);
    r->qep = (hal_qep_t){.counts_per_rev = 80000u};
    r->cfg = *cfg;
    if (!mc_drive_init(&r->d, &r->link, &r->cfg, &r->adc, &r->pwm, &r->qep)) {
        return false;
    }
    for (int k = 0; k < 3; ++k) {
        r->adc.sample.i[k] = (uint16_t)r->d.cfg->blk.offs.nominal;   /* zero current */
    }
    r->adc.sample.vdc = (uint16_t)lrintf(300.0f / r->d.cfg->blk.volts_per_count);
    return true;
}

static void run(rig_t *r, int n)
{
    for (int k = 0; k < n; ++k) {
        hal_host_pwm_latch(&r->pwm);
        mc_drive_isr(&r->d);
        assert_int_equal(r->pwm.nonfinite, 0u);
    }
}

/* Enabled with zero current asked (no detector has anything to say about the rig's dead
 * machine): the offsets are calibrated, then RUN. */
static void enable(rig_t *r)
{
    const mc_drive_cmd_t c = {.enable = true, .mode = MC_MODE_CURRENT, .i_ref = {0.0f, 0.0f}, .theta_init = 0.3f};
    mc_drive_command(&r->d, &c);
    run(r, (int)r->d.cfg->p.control_offset_cal_samples + 1);
    assert_int_equal(mc_drive_state(&r->d), MC_STATE_RUN);
}

/* ------------------------------------------------------------------------ field comparison */

static const char *first_diff;   /* the first field that differed in the current comparison */

static bool same_f(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;   /* bit for bit: the same computation gives the same bits */
}

#define F(x)                                 \
    do {                                     \
        if (!same_f(a->x, b->x)) {           \
            first_diff = first_diff ? first_diff : #x; \
        }                                    \
    } while (0)
#define I(x)                                 \
    do {                                     \
        if ((a->x) != (b->x)) {              \
            first_diff = first_diff ? first_diff : #x; \
        }                                    \
    } while (0)

static void cmp_params(const mc_params_t *a, const mc_params_t *b)
{
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (!same_f(mc_param_get(a, id), mc_param_get(b, id)) || mc_param_is_auto(a, id) != mc_param_is_auto(b, id)) {
            first_diff = first_diff ? first_diff : mc_param_table[id].name;
        }
    }
}

static void cmp_pi(const mc_pi_cfg_t *a, const mc_pi_cfg_t *b)
{
    F(kp);
    F(ki);
    F(ts);
    F(out_min);
    F(out_max);
}

static void cmp_cc(const mc_cc_t *a, const mc_cc_t *b)
{
    F(cfg.kp_d);
    F(cfg.ki_d);
    F(cfg.kp_q);
    F(cfg.ki_q);
    F(cfg.ts);
    F(cfg.ld);
    F(cfg.lq);
    F(cfg.psi_pm);
    I(cfg.decouple);
    cmp_pi(&a->pi_d.cfg, &b->pi_d.cfg);
    cmp_pi(&a->pi_q.cfg, &b->pi_q.cfg);
}

static void cmp_sc(const mc_sc_t *a, const mc_sc_t *b)
{
    F(cfg.kp);
    F(cfg.ki);
    F(cfg.ts);
    F(cfg.torque_max);
    I(cfg.decimation);
    cmp_pi(&a->pi.cfg, &b->pi.cfg);
}

static void cmp_tref(const mc_tref_cfg_t *a, const mc_tref_cfg_t *b)
{
    I(pole_pairs);
    F(mach.ld);
    F(mach.lq);
    F(mach.psi_pm);
    F(i_max);
    F(u_margin);
    I(use_table);
    F(ts);
    F(table.i_max);
    for (int k = 0; k < MC_MTPA_TABLE_N; ++k) {
        F(table.id[k]);
        F(table.iq[k]);
    }
}

static void cmp_dtc(const mc_dtc_t *a, const mc_dtc_t *b)
{
    F(cfg.t_dead);
    F(cfg.t_pwm);
    F(cfg.i_band);
    I(cfg.enable);
    F(k);
}

static void cmp_inj_cfg(const mc_inj_cfg_t *a, const mc_inj_cfg_t *b)
{
    I(kind);
    F(v1);
    F(f_hz);
    F(omega_n1);
    F(ts);
}

static void cmp_biquad(const mc_biquad_t *a, const mc_biquad_t *b)
{
    F(b0);
    F(b1);
    F(b2);
    F(a1);
    F(a2);
}

static void cmp_lpf(const mc_lpf1_t *a, const mc_lpf1_t *b)
{
    F(a);
    F(b);
}

static void cmp_seq(const mc_seq_cfg_t *a, const mc_seq_cfg_t *b)
{
    F(ts);
    I(init_pos);
    I(catch_first);
    F(timeout_catch);
    F(timeout_reaction);
    F(timeout_cal);
    F(timeout_step12);
    F(timeout_step3);
}

static void cmp_model(const mc_flux_model_t *a, const mc_flux_model_t *b)
{
    I(kind);
    F(ld);
    F(lq);
    F(psi_pm);
    I(map);
}

/* What the ISR reads from d->cfg->blk itself (limits, slew, protection, the source's model):
 * the configuration in force must be the new one, whole. */
static void cmp_blk(const mc_drive_blk_t *a, const mc_drive_blk_t *b)
{
    F(ts);
    I(pole_pairs);
    F(volts_per_count);
    F(i_ref_max);
    F(i_slew);
    F(u_loop);
    F(step3_speed_tol);
    I(step3_hold);
    I(inject);
    I(three_step);
    I(src_measures);
    I(cc_map);
    F(src.rs);
    cmp_model(&a->src.model, &b->src.model);
    F(flying.i_band);
    F(flying.i_pulse);
    F(flying.i_rest);
    I(flying.n_wait_max);
    /* the blocks that read their configuration from the one in force */
    F(fw_entry.ts);
    F(fw_entry.rs);
    F(fw_entry.i_stop);
    I(fw_entry.overmod);
    F(offs.amps_per_count);
    F(offs.nominal);
    F(offs.tol);
    F(offs.ts);
    I(offs.samples);
    F(prot.ts);
    I(prot.pole_pairs);
    I(prot.adc_max);
    F(prot.i_trip);
    F(prot.vdc_min);
    F(prot.vdc_max);
    F(prot.avg_k);
    F(prot.overspeed);
    F(prot.i_sum_tol);
    F(prot.track_err);
    F(prot.lock_tol);
    F(prot.lock_floor);
    F(prot.stall_speed);
    F(prot.stall_torque);
    F(prot.resid_v);
    F(prot.resid_w_coef);
    I(prot.i_sum_n);
    I(prot.track_n);
    I(prot.lock_n);
    I(prot.stall_n);
    I(prot.resid_n);
    I(prot.accel_n);
    I(prot.jump_n);
    F(prot.jump);
    F(prot.accel_torque);
    F(prot.accel_per_nm);
    F(prot.rs);
    F(prot.ld);
    F(prot.lq);
    F(prot.psi_pm);
    I(prot.recover);
    I(prot.hold_fw);
    F(prot.ug_coef);
    I(prot.retries);
    I(prot.retry_reset_n);
    I(pol.enable);
    I(pol.at_start);
    I(pol.inject);
    I(pol.three_step);
    F(pol.omega_n1);
    F(pol.bias);
    F(pol.log_ratio);
    I(pol.settle_n);
    I(pol.measure_n);
    I(pol.start_n);
    F(pol.w_scale);
    F(pol.avg_k);
}

#undef F
#undef I

/* The running drive r against the fresh one f: NULL if every block runs with the same
 * configuration, else the block and (in first_diff) the first field that differs. */
static const char *compare(const mc_drive_t *r, const mc_drive_t *f)
{
    static const char *const blocks[] = {"parameters", "current loop", "speed loop", "torque reference",
                                         "dead-time comp", "injection", "notches", "step III low-pass",
                                         "sequencer", "angle source", "drive (d->cfg->blk)"};
    for (int blk = 0; blk < (int)(sizeof blocks / sizeof blocks[0]); ++blk) {
        first_diff = NULL;
        switch (blk) {
        case 0: cmp_params(&r->cfg->p, &f->cfg->p); break;
        case 1: cmp_cc(&r->cc, &f->cc); break;
        case 2: cmp_sc(&r->sc, &f->sc); break;
        case 3: cmp_tref(&r->tref.cfg, &f->tref.cfg); break;
        case 4: cmp_dtc(&r->dtc, &f->dtc); break;
        case 5:
            cmp_inj_cfg(&r->inj.cfg, &f->inj.cfg);
            cmp_inj_cfg(&r->cfg->blk.inj, &f->cfg->blk.inj);
            if (!same_f(r->inj.dphase, f->inj.dphase)) {
                first_diff = first_diff ? first_diff : "dphase";
            }
            break;
        case 6:
            cmp_biquad(&r->notch_d, &f->notch_d);
            cmp_biquad(&r->notch_q, &f->notch_q);
            break;
        case 7: cmp_lpf(&r->step3_speed, &f->step3_speed); break;
        case 8: cmp_seq(&r->seq.cfg, &f->seq.cfg); break;
        case 9: {
            if (r->src != f->src) {
                first_diff = "descriptor";
                break;
            }
            mc_angle_src_cfg_t now, fresh;
            r->src->cfg_of(&r->src_state, &now);
            f->src->cfg_of(&f->src_state, &fresh);
            if (!r->src->cfg_equal(&now, &fresh) || !r->src->cfg_equal(&r->cfg->blk.src.cfg, &fresh)) {
                first_diff = r->src->name;
            }
            break;
        }
        default: cmp_blk(&r->cfg->blk, &f->cfg->blk); break;
        }
        if (first_diff != NULL) {
            return blocks[blk];
        }
    }
    return NULL;
}

/* ------------------------------------------------------------------------ the generated test */

/* Changed values to try for entry id, from value v (the one in force): the first the drive
 * accepts is used (a cross-check may refuse one). */
static int candidates(int id, float v, float out[6])
{
    const mc_param_info_t *e = &mc_param_table[id];
    int n = 0;
    switch ((mc_param_type_t)e->type) {
    case MC_PT_BOOL: out[n++] = v != 0.0f ? 0.0f : 1.0f; break;
    case MC_PT_ENUM: out[n++] = v + 1.0f <= e->max ? v + 1.0f : e->min; break;
    case MC_PT_I32:
        out[n++] = v + 1.0f;
        out[n++] = v - 1.0f;
        break;
    case MC_PT_F32:
    default:
        out[n++] = v * 1.25f;
        out[n++] = v * 0.8f;
        out[n++] = 0.5f * (v + e->max);
        out[n++] = 0.5f * (v + e->min);
        break;
    }
    int m = 0;
    for (int k = 0; k < n; ++k) {
        if (out[k] != v && out[k] >= e->min && out[k] <= e->max) {
            out[m++] = out[k];
        }
    }
    return m;
}

static rig_t running, fresh;

static void test_runtime_writes_reach_every_block(void **st)
{
    (void)st;
    int checked = 0, failed = 0;
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (mc_param_table[id].access != MC_PA_RUNTIME) {
            continue;
        }
        for (int src = 0; src < (int)MC_ANGLE_SRC_COUNT; ++src) {
            mc_drive_cfg_t base;
            cfg_for(&base, src);
            assert_true(rig_init(&fresh, &base));
            const float v = mc_param_get(&fresh.d.cfg->p, id);   /* in force, derived */
            float vals[6];
            const int n = candidates(id, v, vals);
            bool done = false;
            for (int k = 0; k < n && !done; ++k) {
                mc_drive_cfg_t cfg = base;
                assert_true(mc_param_set(&cfg.p, id, vals[k], NULL));
                if (!rig_init(&fresh, &cfg)) {
                    continue;   /* refused by a cross-check: try the next value */
                }
                assert_true(rig_init(&running, &base));
                enable(&running);
                run(&running, 3);
                mc_param_err_t err;
                if (!mc_drive_param_write(&running.d, id, vals[k], &err)) {
                    print_error("%s = %g [%s]: the running drive refused what a fresh one takes (%s)\n",
                                mc_param_table[id].name, (double)vals[k], mc_angle_src_get(src)->name,
                                err.text != NULL ? err.text : "?");
                    ++failed;
                    done = true;
                    break;
                }
                run(&running, 2);   /* the ISR swaps it in at the next period */
                assert_int_equal(mc_drive_state(&running.d), MC_STATE_RUN);
                const char *blk = compare(&running.d, &fresh.d);
                if (blk != NULL) {
                    print_error("%s: %g -> %g [%s]: %s differs from a fresh build (%s)\n", mc_param_table[id].name,
                                (double)v, (double)vals[k], mc_angle_src_get(src)->name, blk, first_diff);
                    ++failed;
                }
                ++checked;
                done = true;
            }
            if (!done) {
                print_error("%s [%s]: no changed value the drive accepts\n", mc_param_table[id].name,
                            mc_angle_src_get(src)->name);
                ++failed;
            }
        }
    }
    print_message("%d RUNTIME parameter x angle source pairs checked, %d failed\n", checked, failed);
    assert_true(checked > 0);
    assert_int_equal(failed, 0);
}

/* The comparison itself tells a difference: the same running drive against a fresh one built
 * with another value of a RUNTIME parameter of each block (not written to the running one). */
static void test_comparison_sees_differences(void **st)
{
    (void)st;
    static const struct {
        int id;
        float v;
        const char *block;
    } cases[] = {
        {MC_PARAM_control_current_bw_hz, 200.0f, "parameters"},
    };
    mc_drive_cfg_t base;
    cfg_for(&base, MC_ANGLE_SRC_encoder);
    assert_true(rig_init(&running, &base));
    enable(&running);
    assert_true(rig_init(&fresh, &base));
    assert_null(compare(&running.d, &fresh.d));   /* the same configuration: no difference */
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        mc_drive_cfg_t cfg = base;
        assert_true(mc_param_set(&cfg.p, cases[k].id, cases[k].v, NULL));
        assert_true(rig_init(&fresh, &cfg));
        const char *blk = compare(&running.d, &fresh.d);
        assert_non_null(blk);
        assert_string_equal(blk, cases[k].block);
    }
    /* with equal parameters, a block's own copy alone: the current loop's gain, the source's */
    assert_true(rig_init(&fresh, &base));
    fresh.d.cc.cfg.kp_q *= 1.5f;
    assert_string_equal(compare(&running.d, &fresh.d), "current loop");
    assert_true(rig_init(&fresh, &base));
    fresh.d.tref.cfg.table.iq[MC_MTPA_TABLE_N - 1] += 1.0f;
    assert_string_equal(compare(&running.d, &fresh.d), "torque reference");
    assert_true(rig_init(&fresh, &base));
    fresh.d.inj.cfg.omega_n1 += 1.0f;
    assert_string_equal(compare(&running.d, &fresh.d), "injection");
    assert_true(rig_init(&fresh, &base));
    ((mc_drive_blk_t *)&fresh.d.cfg->blk)->prot.lock_floor += 1.0f;
    assert_string_equal(compare(&running.d, &fresh.d), "drive (d->cfg->blk)");
    assert_string_equal(first_diff, "prot.lock_floor");
    mc_drive_cfg_t other = base;
    assert_true(mc_param_set(&other.p, MC_PARAM_control_ts_s, 2e-4f, NULL));   /* read by every source */
    assert_true(rig_init(&fresh, &other));
    running.d.cfg = fresh.d.cfg;   /* the parameters and blk equal: only the held copies differ */
    assert_string_equal(compare(&running.d, &fresh.d), "current loop");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_comparison_sees_differences),
        cmocka_unit_test(test_runtime_writes_reach_every_block),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
