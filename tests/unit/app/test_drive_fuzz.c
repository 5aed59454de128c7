/* Fuzzing the drive's configuration and commands (fixed seed, reproducible).
 *
 * Configuration: every entry of the parameter table gets NaN, +-inf, 0, -0, +-1e30, its min and
 * max and the next floats outside them (integer, bool and enum entries: 0, -1, min, max, min - 1,
 * max + 1, INT32_MIN, INT32_MAX and the number of choices), stored straight into mc_params_t
 * through the entry's offset and type (so mc_param_set's own refusal is bypassed) with its
 * "auto" bit cleared (else the rule would overwrite it). Then the estimator's model (rs, ld, lq,
 * psi_pm) and its flux map (grid sizes, steps, origin, a bad entry). Each on two base
 * configurations: sensorless (unop, fluxmap model, three-step start, a small linear map) and the
 * encoder default.
 *   refused: the drive must stay in FAULT(CONFIG); enabled for 300 periods, the PWM stays off;
 *   accepted: 2000 periods of an RL plant at standstill (current, torque, speed commands), a
 *             phase of ADC rail samples (each must trip when running), a NaN-heavy command phase.
 * In every period: every duty the drive wrote is finite and in [0, 1] (the host port's
 * `nonfinite` counter stays 0), and a value the table or the model check excludes was refused.
 * Commands: a few thousand periods of random valid / NaN / inf / huge fields on a running
 * sensorless drive. Run under MC_SANITIZE=ON for ASan / UBSan. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "hal_host/host.h"
#include "mc/drive.h"

#define LD 10.5e-3
#define LQ 12.9e-3
#define RS 0.4
#define PSI 0.34305
#define TS 1e-4

/* ------------------------------------------------------------------------ PRNG, bookkeeping */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static uint64_t xorshift64(void)
{
    uint64_t x = rng_state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    rng_state = x;
    return x;
}

static uint32_t rnd(uint32_t n)
{
    return (uint32_t)(xorshift64() >> 33) % n;
}

static float rnd_uniform(float lo, float hi)
{
    return lo + (hi - lo) * (float)(xorshift64() >> 40) / (float)(1u << 24);
}

static struct {
    unsigned long configs, accepted, refused;
    unsigned long periods, duty_checks, commands, commands_refused, rail_trips, reached_run;
    unsigned long numeric_trips;   /* MC_FAULT_NUMERIC: a NaN caught before the modulator */
    unsigned long nonfinite;       /* duties the host port had to replace (sum over cases)  */
} stats;

static char what[160];   /* the case under test, for the failure message */
static unsigned long period_no;

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            print_error("case [%s], period %lu: %s\n", what, period_no, #cond);                   \
            fail();                                                                                \
        }                                                                                          \
    } while (0)

/* ------------------------------------------------------------------------------------- rig */

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    mc_drive_cfg_t cfg;
    mc_drive_link_t link;
    mc_drive_t d;
    bool accepted;
    double theta_r, id, iq, vdc;
    int rail_phase;         /* -1: none; else the phase whose sample sits at a rail */
    uint16_t rail_count;
} rig_t;

static mc_flux_map_t map_ok;    /* valid: 3 x 3 linear, like test_sequencer's */
static mc_flux_map_t map_fuzz;  /* broken in one way per case */

static void fill_linear_map(mc_flux_map_t *m, int n_d, int n_q)
{
    *m = (mc_flux_map_t){0};
    m->n_d = n_d;
    m->n_q = n_q;
    const int nd = n_d < 2 ? 2 : (n_d > MC_FLUX_MAP_MAX ? MC_FLUX_MAP_MAX : n_d);
    const int nq = n_q < 2 ? 2 : (n_q > MC_FLUX_MAP_MAX ? MC_FLUX_MAP_MAX : n_q);
    m->id0 = m->iq0 = -20.0f;
    m->did = 40.0f / (float)(nd - 1);
    m->diq = 40.0f / (float)(nq - 1);
    for (int a = 0; a < nd; ++a) {
        for (int b = 0; b < nq; ++b) {
            m->psi_d[a * nq + b] = (float)(LD * (m->id0 + m->did * (float)a) + PSI);
            m->psi_q[a * nq + b] = (float)(LQ * (m->iq0 + m->diq * (float)b));
        }
    }
}

/* The sensorless base: UNOP with the flux-map model and the three-step start. */
static void cfg_sensorless(mc_drive_cfg_t *c)
{
    mc_drive_cfg_default(c);
    mc_params_t *p = &c->p;
    assert_true(mc_param_set_choice(p, MC_PARAM_control_angle_source, "unop", NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_estimator_model, "fluxmap", NULL));
    assert_true(mc_param_set_choice(p, MC_PARAM_startup_init_pos, "three_step", NULL));
    assert_true(mc_param_set(p, MC_PARAM_startup_step3_speed_tol_rpm, 5.73f, NULL));
    /* the linear map gives Step II nothing to decide on (an init_pos fault with the check):
     * the thesis' comparison, so that the commands reach RUN */
    assert_true(mc_param_set(p, MC_PARAM_startup_polarity_z_min, 0.0f, NULL));
    c->est = (mc_est_model_t){.rs = NAN, .ld = (float)LD, .lq = (float)LQ, .psi_pm = (float)PSI, .map = &map_ok};
}

static void cfg_encoder(mc_drive_cfg_t *c)
{
    mc_drive_cfg_default(c);
}

/* The duties the drive wrote this period: finite, in [0, 1], none replaced by the port. */
static void check_outputs(const rig_t *r)
{
    CHECK(r->pwm.nonfinite == 0u);
    for (int k = 0; k < 3; ++k) {
        CHECK(isfinite(r->pwm.shadow[k]) && r->pwm.shadow[k] >= 0.0f && r->pwm.shadow[k] <= 1.0f);
        CHECK(isfinite(r->d.tm.duty[k]));
    }
    if (!r->accepted) {
        CHECK(!r->pwm.enabled);
    }
    const mc_state_t s = r->d.seq.state;
    if (s != MC_STATE_RUN && s != MC_STATE_INIT_POS && s != MC_STATE_FAULT_REACTION) {
        CHECK(!r->pwm.enabled);
    }
    stats.duty_checks++;
}

static uint16_t to_counts(const rig_t *r, double amps)
{
    const double c = (double)r->d.cfg->blk.offs.nominal + amps / (double)r->d.cfg->blk.offs.amps_per_count;
    const double hi = (double)r->d.cfg->blk.prot.adc_max;
    if (!(c >= 0.0)) {
        return 0u;   /* also NaN */
    }
    return c > hi ? (uint16_t)hi : (uint16_t)lrint(c);
}

static void sample(rig_t *r)
{
    if (!r->accepted) {
        /* no scaling to speak of: random 12-bit conversions */
        for (int k = 0; k < 3; ++k) {
            r->adc.sample.i[k] = (uint16_t)rnd(4096u);
        }
        r->adc.sample.vdc = (uint16_t)rnd(4096u);
        return;
    }
    const double c = cos(r->theta_r), s = sin(r->theta_r);
    const double ial = c * r->id - s * r->iq, ibe = s * r->id + c * r->iq;
    const double ia = ial, ib = -0.5 * ial + sqrt(3.0) / 2.0 * ibe;
    r->adc.sample.i[0] = to_counts(r, ia);
    r->adc.sample.i[1] = to_counts(r, ib);
    r->adc.sample.i[2] = to_counts(r, -ia - ib);
    const double v = r->vdc / (double)r->d.cfg->blk.volts_per_count;
    r->adc.sample.vdc = (uint16_t)(v > (double)r->d.cfg->blk.prot.adc_max ? (double)r->d.cfg->blk.prot.adc_max : lrint(v));
    if (r->rail_phase >= 0) {
        r->adc.sample.i[r->rail_phase] = r->rail_count;
    }
}

/* One PWM period of a salient RL machine at standstill (the latched duties; nothing when off). */
static void plant(rig_t *r)
{
    if (!r->pwm.enabled) {
        r->id = r->iq = 0.0;
        return;
    }
    const double ua = (r->pwm.active[0] - 0.5) * r->vdc, ub = (r->pwm.active[1] - 0.5) * r->vdc,
                 uc = (r->pwm.active[2] - 0.5) * r->vdc;
    const double ual = (2.0 * ua - ub - uc) / 3.0, ube = (ub - uc) / sqrt(3.0);
    const double c = cos(r->theta_r), s = sin(r->theta_r);
    const double ud = c * ual + s * ube, uq = -s * ual + c * ube;
    for (int k = 0; k < 4; ++k) {
        r->id += TS / 4 * (ud - RS * r->id) / LD;
        r->iq += TS / 4 * (uq - RS * r->iq) / LQ;
    }
}

static void period(rig_t *r)
{
    hal_host_pwm_latch(&r->pwm);
    sample(r);
    const uint32_t faults0 = r->d.seq.faults;
    mc_drive_isr(&r->d);
    if ((r->d.seq.faults & ~faults0 & MC_FAULT_NUMERIC) != 0u) {
        stats.numeric_trips++;
        print_message("numeric trip: [%s] period %lu state %d\n", what, period_no, (int)r->d.seq.state);
    }
    mc_drive_background(&r->d);
    check_outputs(r);
    plant(r);
    stats.periods++;
    stats.nonfinite += r->pwm.nonfinite;
    period_no++;
}

static void send(rig_t *r, bool enable, mc_mode_t mode, float id, float iq, float torque, float speed)
{
    const mc_drive_cmd_t c = {.enable = enable, .mode = mode, .i_ref = {id, iq}, .torque_ref = torque,
                              .speed_ref = speed, .theta_init = (float)r->theta_r};
    mc_drive_command(&r->d, &c);
}

/* A command field: valid, or one of the values a broken bus would bring (1 in `one_in`
 * chance of one of the 7 broken or odd values). */
static uint32_t one_in = 1u;
static float fuzz_field(float valid)
{
    if (rnd(one_in) != 0u) {
        return valid;
    }
    switch (rnd(10u)) {
    case 0: return NAN;
    case 1: return INFINITY;
    case 2: return -INFINITY;
    case 3: return 1e30f;
    case 4: return -1e30f;
    case 5: return rnd_uniform(-1e6f, 1e6f);
    case 6: return -0.0f;
    default: return valid;
    }
}

static mc_drive_cmd_t fuzz_command(const rig_t *r)
{
    mc_drive_cmd_t c;
    c.enable = rnd(400u) != 0u;
    c.mode = rnd(8u * one_in) == 0u ? (mc_mode_t)((int)rnd(6u) - 1) : (mc_mode_t)rnd((uint32_t)MC_MODE_COUNT);
    c.i_ref.d = fuzz_field(rnd_uniform(-5.0f, 5.0f));
    c.i_ref.q = fuzz_field(rnd_uniform(-10.0f, 10.0f));
    c.torque_ref = fuzz_field(rnd_uniform(-20.0f, 20.0f));
    c.speed_ref = fuzz_field(rnd_uniform(-300.0f, 300.0f));
    c.theta_init = fuzz_field((float)r->theta_r);
    return c;
}

/* Runs until RUN (true) or FAULT / n periods. */
static bool run_until_running(rig_t *r, int n)
{
    for (int k = 0; k < n; ++k) {
        period(r);
        if (r->d.seq.state == MC_STATE_RUN) {
            return true;
        }
        if (r->d.seq.state == MC_STATE_FAULT) {
            return false;
        }
    }
    return false;
}

/* ------------------------------------------------------------------------- one configuration */

/* `must_refuse`: the case holds a value the validation must not let through. */
static void run_config(rig_t *r, bool must_refuse)
{
    stats.configs++;
    hal_host_pwm_init(&r->pwm, (float)TS, 0.0f);
    r->adc = (hal_adc_t){0};
    r->qep = (hal_qep_t){.counts_per_rev = 80000u};
    r->id = r->iq = 0.0;
    r->rail_phase = -1;
    /* the encoder at count 0 reads 0 rad; the sensorless start has to find the rotor */
    r->theta_r = r->cfg.p.control_angle_source == (int32_t)MC_ANGLE_SRC_unop ? 0.7 : 0.0;
    period_no = 0;
    r->accepted = mc_drive_init(&r->d, &r->link, &r->cfg, &r->adc, &r->pwm, &r->qep);
    check_outputs(r);
    if (!r->accepted) {
        stats.refused++;
        const mc_param_err_t *e = mc_drive_config_error(&r->d);
        CHECK(e->kind != MC_PERR_NONE);
        CHECK(e->param >= 0 && e->param < (int)MC_PARAM_COUNT);
        CHECK(e->text != NULL);
        CHECK(r->d.seq.state == MC_STATE_FAULT && (r->d.seq.faults & MC_FAULT_CONFIG) != 0u);
        mc_param_err_t werr;
        CHECK(!mc_drive_param_write(&r->d, MC_PARAM_control_current_bw_hz, 200.0f, &werr));
        send(r, true, MC_MODE_CURRENT, 0.0f, 2.0f, 0.0f, 0.0f);
        for (int k = 0; k < 300; ++k) {
            period(r);
            if (k % 50 == 49) {
                send(r, (k / 50) % 2 == 0, MC_MODE_CURRENT, 0.0f, 2.0f, 0.0f, 0.0f);
            }
        }
        CHECK(r->d.seq.state == MC_STATE_FAULT);
        return;
    }
    CHECK(!must_refuse);
    stats.accepted++;
    /* what is in force: resolved, finite and inside the table */
    for (int k = 0; k < (int)MC_PARAM_COUNT; ++k) {
        const float v = mc_param_get(&r->d.cfg->p, k);
        CHECK(isfinite(v) && v >= mc_param_table[k].min && v <= mc_param_table[k].max);
    }
    r->vdc = (double)r->d.cfg->p.hw_vdc_nominal_v;

    /* 1. the RL plant under current, torque and speed commands */
    send(r, true, MC_MODE_CURRENT, 1.0f, 2.0f, 0.0f, 0.0f);
    bool ran = false;
    for (int k = 0; k < 2000; ++k) {
        if (k == 700) {
            send(r, true, MC_MODE_TORQUE, 0.0f, 0.0f, 3.0f, 0.0f);
        } else if (k == 1400) {
            send(r, true, MC_MODE_SPEED, 0.0f, 0.0f, 0.0f, 20.0f);
        }
        period(r);
        ran = ran || r->d.seq.state == MC_STATE_RUN;
    }
    stats.reached_run += ran ? 1u : 0u;

    /* 2. samples at an ADC rail: each one trips a running drive */
    for (int cyc = 0; cyc < 3; ++cyc) {
        send(r, false, MC_MODE_CURRENT, 0.0f, 0.0f, 0.0f, 0.0f);
        period(r);
        send(r, true, MC_MODE_CURRENT, 0.5f, 1.0f, 0.0f, 0.0f);
        run_until_running(r, 600);
        period(r);
        const mc_state_t before = r->d.seq.state;
        r->rail_phase = (int)rnd(3u);
        r->rail_count = rnd(2u) ? 0u : (uint16_t)r->d.cfg->blk.prot.adc_max;
        period(r);
        r->rail_phase = -1;
        if (before == MC_STATE_RUN || before == MC_STATE_INIT_POS) {
            CHECK(r->d.seq.state == MC_STATE_FAULT);
            CHECK((r->d.seq.faults & MC_FAULT_OVERCURRENT) != 0u);
            CHECK(!r->pwm.enabled);
            stats.rail_trips++;
        }
        for (int k = 0; k < 5; ++k) {
            period(r);
        }
    }

    /* 3. a NaN-heavy command phase */
    send(r, false, MC_MODE_CURRENT, 0.0f, 0.0f, 0.0f, 0.0f);
    period(r);
    send(r, true, MC_MODE_CURRENT, 0.0f, 1.0f, 0.0f, 0.0f);
    for (int k = 0; k < 300; ++k) {
        if (k % 3 == 0) {
            const mc_drive_cmd_t c = fuzz_command(r);
            mc_drive_command(&r->d, &c);
            stats.commands++;
        }
        period(r);
    }
}

/* ------------------------------------------------------------------- the configuration cases */

static int32_t *i32_at(mc_params_t *p, int id)
{
    return (int32_t *)(void *)((char *)p + mc_param_table[id].offset);
}

static float *f32_at(mc_params_t *p, int id)
{
    return (float *)(void *)((char *)p + mc_param_table[id].offset);
}

static int n_choices(const char *choices)
{
    int n = 0;
    for (const char *s = choices; *s != '\0';) {
        const char *bar = strchr(s, '|');
        const size_t len = bar != NULL ? (size_t)(bar - s) : strlen(s);
        n += len > 0u ? 1 : 0;
        if (bar == NULL) {
            break;
        }
        s = bar + 1;
    }
    return n;
}

typedef void (*base_fn)(mc_drive_cfg_t *);
static const struct { const char *name; base_fn fn; } bases[] = {
    {"sensorless", cfg_sensorless},
    {"encoder", cfg_encoder},
};

static void test_fuzz_parameters(void **st)
{
    (void)st;
    static rig_t r;
    const unsigned long c0 = stats.configs;
    for (size_t b = 0; b < sizeof bases / sizeof bases[0]; ++b) {
        for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
            const mc_param_info_t *e = &mc_param_table[id];
            if (e->type == MC_PT_F32) {
                const float vals[] = {NAN, INFINITY, -INFINITY, 0.0f, -0.0f, 1e30f, -1e30f, e->min, e->max,
                                      nextafterf(e->min, -INFINITY), nextafterf(e->max, INFINITY)};
                for (size_t v = 0; v < sizeof vals / sizeof vals[0]; ++v) {
                    bases[b].fn(&r.cfg);
                    *f32_at(&r.cfg.p, id) = vals[v];
                    mc_param_set_auto(&r.cfg.p, id, false);
                    snprintf(what, sizeof what, "%s: %s = %g", bases[b].name, e->name, (double)vals[v]);
                    run_config(&r, !(vals[v] >= e->min && vals[v] <= e->max));
                }
            } else {
                const int32_t lo = (int32_t)e->min, hi = (int32_t)e->max;
                const int32_t count = e->type == MC_PT_ENUM ? n_choices(e->choices)
                                      : e->type == MC_PT_BOOL ? 2
                                                              : hi + 1;
                const int32_t vals[] = {0, -1, lo, hi, lo - 1, hi + 1, INT32_MIN, INT32_MAX, count};
                for (size_t v = 0; v < sizeof vals / sizeof vals[0]; ++v) {
                    bases[b].fn(&r.cfg);
                    *i32_at(&r.cfg.p, id) = vals[v];
                    mc_param_set_auto(&r.cfg.p, id, false);
                    snprintf(what, sizeof what, "%s: %s = %ld", bases[b].name, e->name, (long)vals[v]);
                    run_config(&r, !(vals[v] >= lo && vals[v] <= hi));
                }
            }
        }
    }
    print_message("parameter table: %lu configurations\n", stats.configs - c0);
}

static void test_fuzz_estimator_model(void **st)
{
    (void)st;
    static rig_t r;
    const unsigned long c0 = stats.configs;
    static const char *const names[4] = {"est.rs", "est.ld", "est.lq", "est.psi_pm"};
    const int ids[4] = {MC_PARAM_motor_rs_ohm, MC_PARAM_motor_ld_h, MC_PARAM_motor_lq_h, MC_PARAM_motor_psi_pm_wb};
    for (size_t b = 0; b < sizeof bases / sizeof bases[0]; ++b) {
        for (int f = 0; f < 4; ++f) {
            const mc_param_info_t *e = &mc_param_table[ids[f]];
            const float vals[] = {NAN, INFINITY, -INFINITY, 0.0f, -0.0f, 1e30f, -1e30f, e->min, e->max,
                                  nextafterf(e->min, -INFINITY), nextafterf(e->max, INFINITY)};
            for (size_t v = 0; v < sizeof vals / sizeof vals[0]; ++v) {
                bases[b].fn(&r.cfg);
                float *fld[4] = {&r.cfg.est.rs, &r.cfg.est.ld, &r.cfg.est.lq, &r.cfg.est.psi_pm};
                *fld[f] = vals[v];
                snprintf(what, sizeof what, "%s: %s = %g", bases[b].name, names[f], (double)vals[v]);
                /* NaN: "the motor's value" */
                run_config(&r, !isnan(vals[v]) && !(vals[v] >= e->min && vals[v] <= e->max));
            }
        }
        /* the flux map: grid sizes */
        const int ns[] = {0, 1, 2, 41, 42, 60, -1};
        for (size_t a = 0; a < sizeof ns / sizeof ns[0]; ++a) {
            for (size_t q = 0; q < sizeof ns / sizeof ns[0]; ++q) {
                bases[b].fn(&r.cfg);
                fill_linear_map(&map_fuzz, ns[a], ns[q]);
                r.cfg.est.map = &map_fuzz;
                snprintf(what, sizeof what, "%s: map n_d = %d, n_q = %d", bases[b].name, ns[a], ns[q]);
                const bool ok = ns[a] >= 2 && ns[a] <= MC_FLUX_MAP_MAX && ns[q] >= 2 && ns[q] <= MC_FLUX_MAP_MAX;
                run_config(&r, !ok);
            }
        }
        /* steps and origin */
        const float steps[] = {0.0f, -0.0f, -20.0f, NAN, INFINITY, -INFINITY};
        for (int which = 0; which < 4; ++which) {
            for (size_t v = 0; v < sizeof steps / sizeof steps[0]; ++v) {
                bases[b].fn(&r.cfg);
                fill_linear_map(&map_fuzz, 3, 3);
                float *fld[4] = {&map_fuzz.did, &map_fuzz.diq, &map_fuzz.id0, &map_fuzz.iq0};
                *fld[which] = steps[v];
                r.cfg.est.map = &map_fuzz;
                snprintf(what, sizeof what, "%s: map field %d = %g", bases[b].name, which, (double)steps[v]);
                /* steps must be > 0 and finite; the origin finite (-20 is a fine origin) */
                const bool ok = which >= 2 && isfinite(steps[v]);
                run_config(&r, !ok);
            }
        }
        /* one bad entry */
        const float bad[] = {NAN, INFINITY, -INFINITY, 1e30f, 150.0f};
        const int at[] = {0, 4, 8};
        for (int tbl = 0; tbl < 2; ++tbl) {
            for (size_t v = 0; v < sizeof bad / sizeof bad[0]; ++v) {
                for (size_t k = 0; k < sizeof at / sizeof at[0]; ++k) {
                    bases[b].fn(&r.cfg);
                    fill_linear_map(&map_fuzz, 3, 3);
                    (tbl == 0 ? map_fuzz.psi_d : map_fuzz.psi_q)[at[k]] = bad[v];
                    r.cfg.est.map = &map_fuzz;
                    snprintf(what, sizeof what, "%s: map psi_%c[%d] = %g", bases[b].name, tbl == 0 ? 'd' : 'q',
                             at[k], (double)bad[v]);
                    run_config(&r, true);
                }
            }
        }
        /* no map where one is needed (sensorless fluxmap, three-step) */
        bases[b].fn(&r.cfg);
        r.cfg.est.map = NULL;
        snprintf(what, sizeof what, "%s: no map", bases[b].name);
        run_config(&r, b == 0);
    }
    print_message("estimator model and map: %lu configurations\n", stats.configs - c0);
}

/* A random value for a table entry: mostly inside its range (log-uniform over wide ranges),
 * sometimes one of the special ones. Returns whether it is inside. */
static bool random_value(mc_params_t *p, int id)
{
    const mc_param_info_t *e = &mc_param_table[id];
    const bool special = rnd(4u) == 0u;
    if (e->type == MC_PT_F32) {
        float v;
        if (special) {
            const float vals[] = {NAN, INFINITY, -INFINITY, 0.0f, -0.0f, 1e30f, -1e30f, e->min, e->max,
                                  nextafterf(e->min, -INFINITY), nextafterf(e->max, INFINITY)};
            v = vals[rnd((uint32_t)(sizeof vals / sizeof vals[0]))];
        } else if (e->min > 0.0f && e->max > 100.0f * e->min) {
            v = expf(rnd_uniform(logf(e->min), logf(e->max)));
            v = v < e->min ? e->min : (v > e->max ? e->max : v);
        } else {
            v = rnd_uniform(e->min, e->max);
        }
        *f32_at(p, id) = v;
        mc_param_set_auto(p, id, false);
        return v >= e->min && v <= e->max;
    }
    const int32_t lo = (int32_t)e->min, hi = (int32_t)e->max;
    int32_t v;
    if (special) {
        const int32_t vals[] = {0, -1, lo, hi, lo - 1, hi + 1, INT32_MIN, INT32_MAX};
        v = vals[rnd((uint32_t)(sizeof vals / sizeof vals[0]))];
    } else {
        v = lo + (int32_t)rnd((uint32_t)(hi - lo) + 1u);
    }
    *i32_at(p, id) = v;
    mc_param_set_auto(p, id, false);
    return v >= lo && v <= hi;
}

/* Several entries at once, random: the combinations the one-at-a-time sweep cannot reach. */
static void test_fuzz_random_configs(void **st)
{
    (void)st;
    static rig_t r;
    const unsigned long c0 = stats.configs, a0 = stats.accepted;
    for (int n = 0; n < 4000; ++n) {
        const size_t b = rnd(2u);
        bases[b].fn(&r.cfg);
        const int fields = 1 + (int)rnd(4u);
        bool inside = true;
        int len = snprintf(what, sizeof what, "random %d, %s:", n, bases[b].name);
        int ids[4] = {-1, -1, -1, -1};
        for (int f = 0; f < fields; ++f) {
            int id;
            bool dup;
            do {   /* distinct entries: a second value would overwrite the first */
                id = (int)rnd((uint32_t)MC_PARAM_COUNT);
                dup = false;
                for (int g = 0; g < f; ++g) {
                    dup = dup || ids[g] == id;
                }
            } while (dup);
            ids[f] = id;
            inside = random_value(&r.cfg.p, id) && inside;
            if (len > 0 && (size_t)len < sizeof what) {
                len += snprintf(what + len, sizeof what - (size_t)len, " %s=%g", mc_param_table[id].name,
                                (double)mc_param_get(&r.cfg.p, id));
            }
        }
        run_config(&r, !inside);
    }
    print_message("random multi-entry: %lu configurations, %lu accepted\n", stats.configs - c0,
                  stats.accepted - a0);
}

/* Random commands, every field valid or broken, every period, on a running sensorless drive. */
static void test_fuzz_commands(void **st)
{
    (void)st;
    static rig_t r;
    cfg_sensorless(&r.cfg);
    snprintf(what, sizeof what, "command fuzz");
    hal_host_pwm_init(&r.pwm, (float)TS, 0.0f);
    r.adc = (hal_adc_t){0};
    r.qep = (hal_qep_t){.counts_per_rev = 80000u};
    r.theta_r = 0.7;
    r.id = r.iq = 0.0;
    r.rail_phase = -1;
    period_no = 0;
    r.accepted = mc_drive_init(&r.d, &r.link, &r.cfg, &r.adc, &r.pwm, &r.qep);
    assert_true(r.accepted);
    r.vdc = 300.0;
    send(&r, true, MC_MODE_CURRENT, 0.0f, 0.0f, 0.0f, 0.0f);
    CHECK(run_until_running(&r, 3000));
    unsigned long sent = 0, expect_refused = 0, runs = 0;
    for (int k = 0; k < 12000; ++k) {
        one_in = k < 6000 ? 8u : 1u;   /* mostly valid first, then NaN-heavy */
        mc_drive_cmd_t c = fuzz_command(&r);
        if (k % 500 == 0) {
            c.enable = false;   /* a few full restarts in between */
        }
        const bool bad = (unsigned)c.mode >= (unsigned)MC_MODE_COUNT || !isfinite(c.i_ref.d) ||
                         !isfinite(c.i_ref.q) || !isfinite(c.torque_ref) || !isfinite(c.speed_ref) ||
                         !isfinite(c.theta_init);
        mc_drive_command(&r.d, &c);
        ++sent;
        expect_refused += bad ? 1u : 0u;
        period(&r);
        mc_drive_telem_t tm;
        CHECK(mc_drive_telemetry_read(&r.d, &tm));
        CHECK(tm.cmd_rejected == expect_refused);
        if (bad) {
            CHECK(tm.cmd_reject_last == ((unsigned)c.mode >= (unsigned)MC_MODE_COUNT ? MC_CMD_BAD_MODE
                                                                                     : MC_CMD_NOT_FINITE));
        } else {
            CHECK(r.d.cmd.mode == c.mode && r.d.cmd.enable == c.enable);
        }
        CHECK(isfinite(tm.i_ref.d) && isfinite(tm.i_ref.q) && isfinite(tm.u_dq.d) && isfinite(tm.u_dq.q));
        runs += r.d.seq.state == MC_STATE_RUN ? 1u : 0u;
        /* a faulted drive is restarted, as an operator would */
        if (r.d.seq.state == MC_STATE_FAULT) {
            send(&r, false, MC_MODE_CURRENT, 0.0f, 0.0f, 0.0f, 0.0f);
            period(&r);
            ++sent;
        }
    }
    one_in = 1u;
    stats.commands += sent;
    stats.commands_refused += expect_refused;
    print_message("command fuzz: %lu commands, %lu refused, %lu periods in RUN\n", sent, expect_refused, runs);
}

static void test_fuzz_summary(void **st)
{
    (void)st;
    print_message("fuzzed %lu configurations (%lu accepted, %lu refused; %lu reached RUN), %lu commands, "
                  "%lu periods, %lu rail trips, %lu numeric trips, %lu duty checks, %lu non-finite duties\n",
                  stats.configs, stats.accepted, stats.refused, stats.reached_run, stats.commands, stats.periods,
                  stats.rail_trips, stats.numeric_trips, stats.duty_checks, stats.nonfinite);
    assert_int_equal(stats.nonfinite, 0u);
    /* no accepted configuration, under any command, produced a NaN the modulator guard had to catch */
    assert_int_equal(stats.numeric_trips, 0u);
    assert_true(stats.configs > 1000u);
    assert_true(stats.accepted > 100u && stats.reached_run > 100u);
}

int main(void)
{
    fill_linear_map(&map_ok, 3, 3);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fuzz_parameters),
        cmocka_unit_test(test_fuzz_estimator_model),
        cmocka_unit_test(test_fuzz_random_configs),
        cmocka_unit_test(test_fuzz_commands),
        cmocka_unit_test(test_fuzz_summary),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
