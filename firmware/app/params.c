/* The parameter table at run time, the default rules and the validation (mc/params.h). Runs at
 * init and in the background loop, never in the ISR. */
#include "mc/params.h"
#include <math.h>
#include <stddef.h>
#include <string.h>
#include "mc/svpwm.h"

/* "a|b|c" from a choice list: each choice with a bar before it, the first bar skipped */
#define MC_CH_TEXT(m, c) "|" #c
#define MC_CHOICE_TEXT(choices) (sizeof("" choices(MC_CH_TEXT)) > 1u ? &("" choices(MC_CH_TEXT))[1] : "")

/* An ENUM's range is its choice list: the table's max is the last position. */
#define MC_X(g, k, type, unit, lo, hi, def, rule, group, access, choices, doc) \
    _Static_assert(MC_PT_##type != MC_PT_ENUM || ((int)(lo) == 0 && (int)(hi) == MC_CHOICE_##g##_##k##_COUNT - 1), \
                   #g "." #k ": min..max must span the choice list");
MC_PARAMS(MC_X)
#undef MC_X

#ifdef MC_PARAM_NO_DOC
#define MC_PARAM_DOC(s) ""
#else
#define MC_PARAM_DOC(s) s
#endif

/* clang-format off */
const mc_param_info_t mc_param_table[MC_PARAM_COUNT] = {
#define MC_X(g, k, type_, unit_, lo, hi, def_, rule_, group_, access_, choices_, doc_) \
    {.name = #g "." #k, .unit = unit_, .choices = MC_CHOICE_TEXT(choices_), .doc = MC_PARAM_DOC(doc_), \
     .offset = (uint16_t)offsetof(mc_params_t, g##_##k), .type = (uint8_t)MC_PT_##type_, \
     .group = (uint8_t)MC_PG_##group_, .access = (uint8_t)MC_PA_##access_, \
     .rule = (uint8_t)MC_RULE_##rule_, .min = (float)(lo), .max = (float)(hi), .def = (float)(def_)},
    MC_PARAMS(MC_X)
#undef MC_X
};
/* clang-format on */

const char *mc_param_group_name(mc_param_group_t g)
{
    static const char *const names[MC_PG_COUNT] = {"motor", "hardware", "protection", "control",
                                                   "estimator", "injection", "startup"};
    return (unsigned)g < (unsigned)MC_PG_COUNT ? names[g] : "?";
}

static bool valid_id(int id)
{
    return id >= 0 && id < (int)MC_PARAM_COUNT;
}

int mc_param_find(const char *name)
{
    if (name == NULL) {
        return -1;
    }
    for (int k = 0; k < (int)MC_PARAM_COUNT; ++k) {
        if (strcmp(mc_param_table[k].name, name) == 0) {
            return k;
        }
    }
    return -1;
}

static float *f32_ptr(mc_params_t *p, int id)
{
    return (float *)(void *)((char *)p + mc_param_table[id].offset);
}
static int32_t *i32_ptr(mc_params_t *p, int id)
{
    return (int32_t *)(void *)((char *)p + mc_param_table[id].offset);
}

float mc_param_get(const mc_params_t *p, int id)
{
    if (!valid_id(id)) {
        return NAN;
    }
    const char *base = (const char *)p + mc_param_table[id].offset;
    return mc_param_table[id].type == MC_PT_F32 ? *(const float *)(const void *)base
                                                : (float)*(const int32_t *)(const void *)base;
}

bool mc_param_is_auto(const mc_params_t *p, int id)
{
    return valid_id(id) && (p->auto_mask[id / 32] >> (id % 32) & 1u) != 0u;
}

void mc_param_set_auto(mc_params_t *p, int id, bool on)
{
    if (!valid_id(id)) {
        return;
    }
    const uint32_t bit = 1u << (id % 32);
    p->auto_mask[id / 32] = on ? (p->auto_mask[id / 32] | bit) : (p->auto_mask[id / 32] & ~bit);
}

bool mc_param_fail(mc_param_err_t *err, mc_param_err_kind_t kind, int id, float value, const char *text)
{
    if (err != NULL) {
        *err = (mc_param_err_t){.kind = kind, .param = id, .param2 = -1, .value = value, .value2 = 0.0f,
                                .min = valid_id(id) ? mc_param_table[id].min : 0.0f,
                                .max = valid_id(id) ? mc_param_table[id].max : 0.0f, .text = text};
    }
    return false;
}

/* Stores without any check (defaults and derived values come from the table itself). */
static void store(mc_params_t *p, int id, float v)
{
    if (mc_param_table[id].type == MC_PT_F32) {
        *f32_ptr(p, id) = v;
    } else {
        *i32_ptr(p, id) = (int32_t)v;
    }
}

bool mc_param_set(mc_params_t *p, int id, float value, mc_param_err_t *err)
{
    if (!valid_id(id)) {
        return mc_param_fail(err, MC_PERR_UNKNOWN, id, value, "no such parameter");
    }
    if (mc_param_table[id].type != MC_PT_F32) {
        /* converting a NaN, an infinity or anything outside int32 to int32_t is undefined */
        if (!isfinite(value) || fabsf(value) > 2.0e9f) {
            return mc_param_fail(err, MC_PERR_NOT_FINITE, id, value, "not a finite integer");
        }
        if (floorf(value) != value) {
            return mc_param_fail(err, MC_PERR_NOT_INTEGER, id, value, "must be a whole number");
        }
    }
    store(p, id, value);
    mc_param_set_auto(p, id, false);
    return true;
}

/* The position of `choice` in "a|b|c", or -1. */
static int choice_index(const char *choices, const char *choice)
{
    const size_t n = strlen(choice);
    int k = 0;
    const char *s = choices;
    while (*s != '\0') {
        const char *bar = strchr(s, '|');
        const size_t len = bar != NULL ? (size_t)(bar - s) : strlen(s);
        if (len == n && n > 0u && strncmp(s, choice, n) == 0) {
            return k;
        }
        if (bar == NULL) {
            break;
        }
        s = bar + 1;
        ++k;
    }
    return -1;
}

bool mc_param_set_choice(mc_params_t *p, int id, const char *choice, mc_param_err_t *err)
{
    if (!valid_id(id) || mc_param_table[id].type != MC_PT_ENUM || choice == NULL) {
        return mc_param_fail(err, MC_PERR_UNKNOWN, id, 0.0f, "not a choice parameter");
    }
    const int k = choice_index(mc_param_table[id].choices, choice);
    if (k < 0) {
        return mc_param_fail(err, MC_PERR_RANGE, id, 0.0f, "not one of the choices");
    }
    return mc_param_set(p, id, (float)k, err);
}

void mc_param_choice_text(const mc_params_t *p, int id, char *buf, unsigned n)
{
    if (n == 0u) {
        return;
    }
    buf[0] = '\0';
    if (!valid_id(id) || mc_param_table[id].type != MC_PT_ENUM) {
        return;
    }
    int want = (int)mc_param_get(p, id);
    const char *s = mc_param_table[id].choices;
    for (; want > 0 && s != NULL; --want) {
        s = strchr(s, '|');
        s = s != NULL ? s + 1 : NULL;
    }
    if (s == NULL) {
        return;
    }
    unsigned k = 0u;
    for (; s[k] != '\0' && s[k] != '|' && k + 1u < n; ++k) {
        buf[k] = s[k];
    }
    buf[k] = '\0';
}

void mc_params_default(mc_params_t *p)
{
    memset(p, 0, sizeof *p);
    for (int k = 0; k < (int)MC_PARAM_COUNT; ++k) {
        store(p, k, mc_param_table[k].def);
        mc_param_set_auto(p, k, mc_param_table[k].rule != MC_RULE_NONE);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Default rules. Each follows the motor (p, Rs, Ld, Lq, psi_pm, rated current and torque,
 * inertia), the power stage (Vdc, ADC span and resolution) and the sampling frequency f_s, and
 * reproduces the thesis' values on the thesis motor at 10 kHz (docs/parameters.md lists them). */

/* Two significant digits: derived amplitudes and gains land on the round numbers an engineer
 * would write (70 V, 30 Hz, 0.3 A on the thesis motor) instead of 70.14 V. */
static float nice2(float x)
{
    if (!(x > 0.0f) || !isfinite(x)) {
        return x;
    }
    /* scale by an exact power of ten (a multiplication by 0.01f would round 30 * 0.01f off 0.3f) */
    const float k = 1.0f - floorf(log10f(x));
    if (k >= 0.0f) {
        const float s = powf(10.0f, k);
        return roundf(x * s) / s;
    }
    const float s = powf(10.0f, -k);
    return roundf(x / s) * s;
}

static float minf(float a, float b)
{
    return a < b ? a : b;
}
static float maxf(float a, float b)
{
    return a > b ? a : b;
}

/* What the selected angle source is and needs (mc/angle_source.h) */
static bool estimating(const mc_params_t *p)
{
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->control_angle_source);
    return src != NULL && src->cls == MC_ANGLE_ESTIMATOR;
}

static bool needs_injection(const mc_params_t *p)
{
    const mc_angle_src_desc_t *src = mc_angle_src_get(p->control_angle_source);
    return src != NULL && src->needs_injection;
}

static bool injecting(const mc_params_t *p)
{
    return needs_injection(p) && p->injection_kind != MC_CHOICE_injection_kind_off;
}

/* A quarter of the q current's large-signal bandwidth: a load step makes the speed PI ask for the
 * current at w_bw di, di up to the references' limit i_max (1 - headroom), while the voltage the
 * injection leaves slews it at most at (Vdc/sqrt3 - V1) / Lq, Lq at i = 0 the largest l_qq of a
 * saturating machine; beyond that the loop limit-cycles at the voltage limit
 * (docs/parameters.md, "Speed-loop bandwidth") */
static float speed_slew_bw(const mc_params_t *p)
{
    const float u_free = p->hw_vdc_nominal_v * 0.57735027f - (injecting(p) ? p->injection_v1_v : 0.0f);
    const float di = p->control_i_max_a * (1.0f - p->control_i_headroom);
    return 0.25f * u_free / (6.28318531f * p->motor_lq_h * di);
}

static float rule_value(const mc_params_t *p, mc_param_rule_t rule)
{
    /* f_s to the hertz: 1 / 5e-4f is 1999.99994 Hz in float, and a filter corner 2e-5 Hz off
     * its round value would change nothing but the last bits of every trace */
    const float fs = roundf(1.0f / p->control_ts_s);
    const float pi2 = 6.28318531f;
    switch (rule) {
    case MC_RULE_I_TRIP:
        /* 1.5 x rated: room above the current limit for regulation transients, below what
         * the power stage of a drive sized for the motor survives */
        return 1.5f * p->motor_i_rated_a;
    case MC_RULE_VDC_MIN:
        return 0.5f * p->hw_vdc_nominal_v;
    case MC_RULE_VDC_MAX:
        return 1.5f * p->hw_vdc_nominal_v;
    case MC_RULE_I_MAX:
        return p->motor_i_rated_a;
    case MC_RULE_CC_BW: {
        /* f_s / 40 keeps w_bw Ts = 0.16 rad, where the 1.5-period delay costs ~14 deg of phase
         * (250 Hz at 10 kHz); while injecting, at most half the injection frequency, so the
         * notch in the feedback stays outside the loop's crossover */
        const float bw = fs / 40.0f;
        return injecting(p) ? minf(bw, 0.5f * p->injection_f_hz) : bw;
    }
    case MC_RULE_I_SLEW:
        /* a reference step the loop follows without overshooting i_max: half the rated
         * current per loop time constant (10 kA/s on the thesis motor at 250 Hz) */
        return nice2(0.5f * p->control_i_max_a * pi2 * p->control_current_bw_hz);
    case MC_RULE_SPEED_BW: {
        /* at most 1/40 of the speed loop's own sampling rate (25 Hz at 10 kHz and decimation
         * 10), and sensorless at most the PLL's bandwidth, which filters the speed it uses */
        float bw = minf(25.0f, fs / (40.0f * (float)p->control_speed_decimation));
        if (estimating(p)) {
            bw = minf(bw, p->estimator_pll_bw_hz);
        }
        /* and the slew bound (speed_slew_bw): 3.6 Hz on baldor-5p6kw-pmsyrm */
        return minf(bw, nice2(speed_slew_bw(p)));
    }
    case MC_RULE_OVERSPEED: {
        /* the highest speed the drive can control: the voltage circle Vdc/sqrt3 over the flux
         * left with the whole current limit in -d (psi_pm - Ld i_max). Beyond it the current
         * runs away (the thesis motor driven past ~1690 rpm tripped on over-current), so the
         * limit is that speed itself; a machine whose characteristic current is inside the limit
         * has none: then 3x the base speed */
        const float u = p->hw_vdc_nominal_v * 0.57735027f;
        const float psi = maxf(p->motor_psi_pm_wb - p->motor_ld_h * p->control_i_max_a, p->motor_psi_pm_wb / 3.0f);
        const float w_el = u / maxf(psi, 1e-6f);
        return roundf(w_el * 60.0f / (pi2 * (float)p->motor_pole_pairs));
    }
    case MC_RULE_I_SUM: {
        /* three measured channels of an isolated star sum to zero; noise and quantisation of
         * three channels are a few counts, a stuck or drifted channel much more */
        const float lsb = 2.0f * p->hw_i_span_a / (float)((1L << p->hw_adc_bits) - 1L);
        return nice2(maxf(0.05f * p->motor_i_rated_a, 8.0f * lsb));
    }
    case MC_RULE_TRACK:
        return nice2(0.25f * p->motor_i_rated_a);
    case MC_RULE_RESID:
        /* a tenth of the voltage circle: dead time, device drops and resistance errors stay
         * far below it; a frozen angle shows the whole back-EMF psi_pm w */
        return nice2(0.1f * p->hw_vdc_nominal_v * 0.57735027f);
    case MC_RULE_LOCK_FLOOR:
        return nice2(0.25f * p->injection_n1_rpm);
    case MC_RULE_STALL:
        return nice2(0.05f * p->injection_n1_rpm);
    case MC_RULE_SC_DEC:
        /* the speed loop at 1 kHz whatever f_s: at 2 kHz a decimation of 10 left it 200 Hz and a
         * 5 Hz bandwidth, too slow to hold an active load at standstill */
        return maxf(1.0f, roundf(fs / 1000.0f));
    case MC_RULE_SPEED_KP:
        /* crossover at w_bw on the inertia alone: kp = J w_bw */
        return p->motor_inertia_kgm2 * pi2 * p->control_speed_bw_hz;
    case MC_RULE_SPEED_KI: {
        /* PI zero a quarter of the crossover below it: kp w_bw / 4 (with kp from its rule,
         * J w_bw^2 / 4, which rounds as the double computation does) */
        const float w = pi2 * p->control_speed_bw_hz;
        return mc_param_is_auto(p, MC_PARAM_control_speed_kp) ? p->motor_inertia_kgm2 * (w * w) / 4.0f : p->control_speed_kp * w / 4.0f;
    }
    case MC_RULE_TORQUE_MAX:
        return p->motor_torque_rated_nm * 6.0f / 5.0f;   /* 1.2 x, rounded once less than 1.2f * T */
    case MC_RULE_I_SMALL:
        /* a current "near zero": 2.26 % of rated, the thesis motor's 0.3 A */
        return nice2(0.0226f * p->motor_i_rated_a);
    case MC_RULE_ENC_FC:
        return minf(500.0f, fs / 4.0f);
    case MC_RULE_INJ_F:
        /* the thesis' 500 Hz; at low f_s at least 4 samples per cycle (the thesis runs UNOP with
         * 500 Hz at 2 kHz, section 7.3) */
        return minf(500.0f, fs / 4.0f);
    case MC_RULE_INJ_I:
        /* an HF current large enough to read the saliency through the sensor noise and small
         * against the rated current: 16 % of rated, the thesis' 2.1 A (70 V, 500 Hz, 10.5 mH) */
        return 0.16f * p->motor_i_rated_a;
    case MC_RULE_INJ_V1:
        /* the voltage that drives i_hf through Ld at the injection frequency (R negligible),
         * at most half the voltage circle Vdc/sqrt3, the rest is the control's */
        return minf(nice2(p->injection_i_hf_a * pi2 * p->injection_f_hz * p->motor_ld_h), 0.5f * p->hw_vdc_nominal_v * 0.57735027f);
    case MC_RULE_N1:
        /* the injection fades out at 33.3 Hz electrical, where the back-EMF (ratio to the HF
         * voltage psi_pm w / V1 ~ 1 on the thesis motor) carries the estimate: 400 rpm at p = 5 */
        return 2000.0f / (float)p->motor_pole_pairs;
    case MC_RULE_PLL_BW:
        /* 6 % of the injection frequency: the injection ripple on the raw angle is attenuated
         * ~25 dB while the PLL still follows the speed loop (30 Hz at 500 Hz); and at most 6 x
         * the speed loop's slew bound: the speed loop needs no faster angle, a faster PLL only
         * passes more of the raw estimate's noise (22 Hz on baldor-5p6kw-pmsyrm) */
        return nice2(minf(0.06f * p->injection_f_hz, 6.0f * speed_slew_bw(p)));
    case MC_RULE_PLL_FC:
        /* the speed loop reads the speed only up to a few times its bandwidth; above, its
         * proportional gain J w_bw passes the estimate's noise to the current reference. 8 x
         * costs the loop 7 deg of phase at crossover */
        return nice2(minf(minf(200.0f, fs / 10.0f), 8.0f * p->control_speed_bw_hz));
    case MC_RULE_K2: {
        /* K2 acts on the scaled speed omega / w_base; the data term's curvature in that variable
         * is (psi_pm w_base)^2. Keeping their ratio as on the thesis motor (psi_pm w_base =
         * 107.77 V at 600 rpm) keeps the regularisation's share: a weak-magnet machine
         * (brodatzki-35kw: 19 V) otherwise has its speed estimate held back 30 times harder and
         * UNOP settles in a wrong basin at a few hundred rpm */
        const float wb = p->estimator_speed_scale_rpm * pi2 / 60.0f * (float)p->motor_pole_pairs;
        const float r = p->motor_psi_pm_wb * wb / 107.77f;
        return nice2(100.0f * r * r);
    }
    case MC_RULE_STEP1_M: {
        /* the pulse raises the current by ~0.72 x rated through Ld at 2/3 Vdc (V(100) on the
         * phase): enough for the saliency, far from the trip; m = 5 on the thesis motor */
        const float di_per_period = (2.0f / 3.0f) * p->hw_vdc_nominal_v * p->control_ts_s / p->motor_ld_h;
        const float m = roundf(0.72f * p->motor_i_rated_a / di_per_period);
        return maxf(1.0f, minf(16.0f, m));
    }
    case MC_RULE_V_POL:
        /* a swing of 0.57 x rated through Ld in n periods, where l_dd's asymmetry shows: the
         * thesis' 200 V with n = 4; at most the hexagon's 2/3 Vdc */
        return minf(nice2(0.573f * p->motor_i_rated_a * p->motor_ld_h / ((float)p->startup_step2_n * p->control_ts_s)),
                    (2.0f / 3.0f) * p->hw_vdc_nominal_v);
    case MC_RULE_STEP3_TOL: {
        /* expected noise of the filtered speed estimate: one ADC count of current noise through
         * Lq over one period is a voltage error sqrt2 Lq lsb / Ts, read as speed through psi_pm,
         * averaged over the PLL's bandwidth; 5 sigma of it, but at least 0.42 Hz electrical
         * (25/p rpm: the thesis motor's 5 rpm) */
        const float lsb = 2.0f * p->hw_i_span_a / (float)((1L << p->hw_adc_bits) - 1L);
        const float psi = maxf(p->motor_psi_pm_wb, 0.1f * p->motor_lq_h * p->motor_i_rated_a);
        const float sigma_w = 1.41421356f * p->motor_lq_h * lsb / (p->control_ts_s * psi) * sqrtf(2.0f * p->estimator_pll_bw_hz * p->control_ts_s);
        const float rpm_per_el = 60.0f / (pi2 * (float)p->motor_pole_pairs);
        return nice2(maxf(25.0f / (float)p->motor_pole_pairs, 5.0f * sigma_w * rpm_per_el));
    }
    case MC_RULE_T_STEP12:
        return maxf(0.02f, 200.0f * p->control_ts_s);
    case MC_RULE_CATCH_I:
        /* a current that reads the angle to a degree through the sensor noise and brakes little:
         * 15 % of rated (the rotation it takes, i Lq / psi_pm, is 4 deg on the thesis motor).
         * Above the generation speed the pulse's current is also the flux lag the field-weakening
         * entry starts from (mc/fw_entry.h): a quarter of rated made the thesis motor's 1500 rpm
         * entry peak at 15.0 A, 15 % at 14.0 A (10 seeds x 4 estimates) */
        return nice2(0.15f * p->motor_i_rated_a);
    case MC_RULE_OFFSET_CAL:
        /* 6.4 ms of samples (64 at 10 kHz), at least 16 for the average's noise */
        return maxf(16.0f, roundf(6.4e-3f * fs));
    case MC_RULE_POL_BIAS:
        /* Step II's swing (0.57 x rated) rounded down: enough saturation to tell the poles */
        return nice2(0.5f * p->motor_i_rated_a);
    case MC_RULE_CATCH_MIN:
        /* 2 Hz electrical: slower rotors move less than 25 deg during the standstill start's
         * ~30 ms, which Step III and the estimator absorb; the probe to see it lasts ~2.5 ms */
        return 120.0f / (float)p->motor_pole_pairs;
    case MC_RULE_L_ADAPT:
        /* five injection periods: settled well before the speed loop meets the wrong model (L
         * x1.2 lost lock 18 ms after the enable), and calm enough that Step III's convergence
         * test is not delayed (2 periods: 50.4 ms instead of 36.7 at one angle of 12) */
        return 5.0f / p->injection_f_hz;
    case MC_RULE_IF_I:
        /* I/f (Fatu et al. 2008): a current that carries the load the speed loop will meet at the
         * hand-over and room to accelerate; 0.8 x the limit keeps the peak well within it */
        return nice2(0.8f * p->control_i_max_a);
    case MC_RULE_IF_ACCEL: {
        /* an eighth of the I/f current's torque on the motor's inertia: the rest carries the
         * load and the rotor's swing about the frame (a quarter peaked at 1.10 x the current
         * limit starting siemens-1ft7044-spm under 50 % load; a load inertia the motor data leaves
         * out needs a lower ramp) */
        const float t_if = 1.5f * (float)p->motor_pole_pairs * p->motor_psi_pm_wb * p->startup_if_i_a;
        return nice2(0.125f * t_if / p->motor_inertia_kgm2 * 60.0f / pi2);
    }
    case MC_RULE_IF_W_H: {
        /* the EMF-based estimate is good where the back-EMF psi_pm w is 5 x the voltage error
         * the estimator does not model: the dead time's Vdc t_dead / Ts (compensated: a quarter
         * of it left), two device drops, and half of Rs I_f (Rs known to +-50 %, warm / cold);
         * at least 2 % of the speed at which the back-EMF reaches Vdc / sqrt3 */
        const float dt = p->hw_vdc_nominal_v * p->hw_dead_time_s / p->control_ts_s * (p->control_deadtime_comp != 0 ? 0.25f : 1.0f);
        const float dv = dt + 2.0f * p->hw_device_drop_v + 0.5f * p->motor_rs_ohm * p->startup_if_i_a;
        const float psi = maxf(p->motor_psi_pm_wb, 1e-6f);
        const float w_el = maxf(5.0f * dv, 0.02f * p->hw_vdc_nominal_v * 0.57735027f) / psi;
        return nice2(w_el * 60.0f / (pi2 * (float)p->motor_pole_pairs));
    }
    case MC_RULE_NONE:
    case MC_RULE_COUNT:
    default:
        return 0.0f;
    }
}

/* Rules read the motor and hardware entries (never derived) and other rule results (speed_kp
 * and pll_speed_fc read speed_bw, which reads pll_bw, which reads inj_v1, which reads inj_f):
 * five passes settle the deepest chain whatever the table order. A rule result that is not
 * finite (a motor entry out of range) is stored as it is, for the validation to report. */
void mc_params_derive(mc_params_t *p)
{
    if (!(p->control_ts_s > 0.0f) || p->motor_pole_pairs < 1 || p->hw_adc_bits < 1 || p->hw_adc_bits > 30 || p->startup_step2_n < 1 ||
        p->control_speed_decimation < 1) {
        return;   /* the validation reports the entry; rules would divide by it */
    }
    for (int pass = 0; pass < 5; ++pass) {
        for (int k = 0; k < (int)MC_PARAM_COUNT; ++k) {
            if (mc_param_table[k].rule != MC_RULE_NONE && mc_param_is_auto(p, k)) {
                const float v = rule_value(p, (mc_param_rule_t)mc_param_table[k].rule);
                if (mc_param_table[k].type == MC_PT_F32 || (isfinite(v) && fabsf(v) < 2.0e9f)) {
                    store(p, k, v);
                }
            }
        }
    }
}

/* ------------------------------------------------------------------------------------------ */

static bool cross(mc_param_err_t *err, int id, int id2, const mc_params_t *p, float lo, float hi, const char *text)
{
    if (err != NULL) {
        *err = (mc_param_err_t){.kind = MC_PERR_CROSS, .param = id, .param2 = id2, .value = mc_param_get(p, id),
                                .value2 = id2 >= 0 ? mc_param_get(p, id2) : 0.0f, .min = lo, .max = hi,
                                .text = text};
    }
    return false;
}

bool mc_params_validate(const mc_params_t *p, mc_param_err_t *err)
{
    for (int k = 0; k < (int)MC_PARAM_COUNT; ++k) {
        const mc_param_info_t *e = &mc_param_table[k];
        const float v = mc_param_get(p, k);
        if (!isfinite(v)) {
            return mc_param_fail(err, MC_PERR_NOT_FINITE, k, v, "not a finite number");
        }
        if (v < e->min || v > e->max) {
            return mc_param_fail(err, MC_PERR_RANGE, k, v, "out of range");
        }
    }
    const float fs = 1.0f / p->control_ts_s;
    /* sensing: the trip must be seen before the ADC clips, with 10 % for noise and ripple */
    if (p->hw_i_span_a < 1.1f * p->control_i_trip_a) {
        return cross(err, MC_PARAM_hw_i_span_a, MC_PARAM_control_i_trip_a, p, 1.1f * p->control_i_trip_a, mc_param_table[MC_PARAM_hw_i_span_a].max,
                     "the current sensor span must exceed the over-current trip level by 10 %");
    }
    if (p->control_i_max_a >= p->control_i_trip_a) {
        return cross(err, MC_PARAM_control_i_max_a, MC_PARAM_control_i_trip_a, p, mc_param_table[MC_PARAM_control_i_max_a].min, p->control_i_trip_a,
                     "the current limit must be below the over-current trip level");
    }
    if (p->hw_vdc_nominal_v <= p->control_vdc_min_v || p->hw_vdc_nominal_v >= p->control_vdc_max_v) {
        return cross(err, MC_PARAM_hw_vdc_nominal_v, p->hw_vdc_nominal_v <= p->control_vdc_min_v ? MC_PARAM_control_vdc_min_v : MC_PARAM_control_vdc_max_v,
                     p, p->control_vdc_min_v, p->control_vdc_max_v, "the nominal DC link must lie inside the trip window");
    }
    if (p->hw_vdc_span_v <= p->control_vdc_max_v) {
        return cross(err, MC_PARAM_hw_vdc_span_v, MC_PARAM_control_vdc_max_v, p, p->control_vdc_max_v, mc_param_table[MC_PARAM_hw_vdc_span_v].max,
                     "the DC-link sensor span must exceed the over-voltage trip level");
    }
    if (p->control_u_margin > p->control_u_loop || p->control_u_margin > MC_SVPWM_FUND_MAX) {
        /* the references must plan for a fundamental the loop can hold: (2.14a) is below both */
        return cross(err, MC_PARAM_control_u_margin, MC_PARAM_control_u_loop, p, mc_param_table[MC_PARAM_control_u_margin].min,
                     p->control_u_loop < MC_SVPWM_FUND_MAX ? p->control_u_loop : MC_SVPWM_FUND_MAX,
                     "the references' voltage share must not exceed the current loop's (nor 1.049, the "
                     "largest steady fundamental of overmodulation)");
    }
    if (p->control_current_bw_hz * p->control_ts_s > 0.05f) {
        return cross(err, MC_PARAM_control_current_bw_hz, MC_PARAM_control_ts_s, p, mc_param_table[MC_PARAM_control_current_bw_hz].min, 0.05f * fs,
                     "the current-loop bandwidth must stay below f_s / 20");
    }
    if (p->startup_step3_hold_s < 2.0f * p->control_ts_s) {
        return cross(err, MC_PARAM_startup_step3_hold_s, MC_PARAM_control_ts_s, p, 2.0f * p->control_ts_s, mc_param_table[MC_PARAM_startup_step3_hold_s].max,
                     "the Step III hold must last at least two periods");
    }
    if (needs_injection(p)) {
        if (p->injection_kind != MC_CHOICE_injection_kind_off && p->injection_f_hz * p->control_ts_s > 0.5f) {
            return cross(err, MC_PARAM_injection_f_hz, MC_PARAM_control_ts_s, p, mc_param_table[MC_PARAM_injection_f_hz].min, 0.5f * fs,
                         "the injection frequency must be at most half the sampling frequency");
        }
        if (p->injection_v1_v > p->hw_vdc_nominal_v * 0.57735027f) {
            return cross(err, MC_PARAM_injection_v1_v, MC_PARAM_hw_vdc_nominal_v, p, 0.0f, p->hw_vdc_nominal_v * 0.57735027f,
                         "the injection must fit inside the voltage circle Vdc/sqrt3");
        }
    }
    if (p->startup_init_pos == MC_CHOICE_startup_init_pos_three_step && !needs_injection(p)) {   /* Step III runs on the injection */
        return cross(err, MC_PARAM_startup_init_pos, MC_PARAM_control_angle_source, p, 0.0f, 0.0f,
                     "the three-step start needs control.angle_source = unop");
    }
    return true;
}

static uint32_t fnv1a(uint32_t h, const char *s)
{
    for (; *s != '\0'; ++s) {
        h = (h ^ (uint8_t)*s) * 16777619u;
    }
    return (h ^ 0xffu) * 16777619u;   /* a separator: "ab" + "c" differs from "a" + "bc" */
}

uint32_t mc_params_table_hash(void)
{
    uint32_t h = 2166136261u;
    for (int k = 0; k < (int)MC_PARAM_COUNT; ++k) {
        const mc_param_info_t *e = &mc_param_table[k];
        h = (h ^ (uint32_t)k) * 16777619u;
        h = (h ^ e->type) * 16777619u;
        h = fnv1a(h, e->name);
        h = fnv1a(h, e->unit);
    }
    return h;
}
