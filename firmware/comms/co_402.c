/* The CiA 402 drive profile (mc/cia402.h). Section numbers: CiA 402-2 v4.1 (= IEC 61800-7-201). */
#include <math.h>
#include "mc/cia402.h"
#include "mc/co.h"

#define TWO_PI 6.2831853f
#define RPM_PER_RAD_S (60.0f / TWO_PI)

#define SW_VOLTAGE   0x0010u   /* bit 4 */
#define SW_REMOTE    0x0200u   /* bit 9 */
#define SW_REACHED   0x0400u   /* bit 10 */
#define SW_LIMIT     0x0800u   /* bit 11 */
#define SW_OMS12     0x1000u   /* bit 12: pv speed = 0; csv, cst drive follows the command value */
#define SW_RUN       0x4000u   /* bit 14 (manufacturer): the drive is in RUN */
#define SW_STARTUP   0x8000u   /* bit 15 (manufacturer): its start-up runs */
#define CW_FAULT_RESET 0x0080u /* bit 7 */
#define CW_HALT      0x0100u   /* bit 8 */

/* Controlword commands (§6.3.1 Table 28), on bits 7, 3, 2, 1, 0. "Switch on" and "disable
 * operation" are the same pattern; which one it is depends on the state. */
typedef enum { CMD_NONE, CMD_SHUTDOWN, CMD_SWITCH_ON, CMD_ENABLE_OP, CMD_DISABLE_VOLTAGE, CMD_QUICK_STOP } cmd_t;

static cmd_t decode(uint16_t cw)
{
    if ((cw & 0x0082u) == 0x0000u) {
        return CMD_DISABLE_VOLTAGE;   /* 0 x x 0 x */
    }
    if ((cw & 0x0086u) == 0x0002u) {
        return CMD_QUICK_STOP;        /* 0 x 0 1 x */
    }
    if ((cw & 0x0087u) == 0x0006u) {
        return CMD_SHUTDOWN;          /* 0 x 1 1 0 */
    }
    if ((cw & 0x008Fu) == 0x0007u) {
        return CMD_SWITCH_ON;         /* 0 0 1 1 1 (also "disable operation") */
    }
    if ((cw & 0x008Fu) == 0x000Fu) {
        return CMD_ENABLE_OP;         /* 0 1 1 1 1 (also "switch on + enable operation") */
    }
    return CMD_NONE;                  /* bit 7 set: only the fault reset's edge counts */
}

uint16_t mc_402_statusword_for(mc_402_state_t st)
{
    /* §6.3.2 Table 30: bits 6, 5, 3, 2, 1, 0 (x read as 0) */
    switch (st) {
    case MC_402_NOT_READY: return 0x0000u;               /* x0xx 0000 */
    case MC_402_SWITCH_ON_DISABLED: return 0x0040u;      /* x1xx 0000 */
    case MC_402_READY_TO_SWITCH_ON: return 0x0021u;      /* x01x 0001 */
    case MC_402_SWITCHED_ON: return 0x0023u;             /* x01x 0011 */
    case MC_402_OPERATION_ENABLED: return 0x0027u;       /* x01x 0111 */
    case MC_402_QUICK_STOP_ACTIVE: return 0x0007u;       /* x00x 0111 */
    case MC_402_FAULT_REACTION_ACTIVE: return 0x000Fu;   /* x0xx 1111 */
    case MC_402_FAULT: return 0x0008u;                   /* x0xx 1000 */
    default: return 0x0000u;
    }
}

/* A NaN or an infinity reads as 0: every value this block derives stays finite. */
static float fin(float x)
{
    return isfinite(x) ? x : 0.0f;
}

/* Float -> integer conversions: rounded, saturated (also an infinity), NaN -> 0 (a conversion
 * out of range is UB). */
static int32_t to_i32(float x)
{
    if (isnan(x)) {
        return 0;
    }
    return x >= 2147483648.0f ? INT32_MAX : x <= -2147483648.0f ? INT32_MIN : (int32_t)roundf(x);
}

static int16_t to_i16(float x)
{
    if (isnan(x)) {
        return 0;
    }
    if (x >= 32767.0f) {
        return INT16_MAX;
    }
    if (x <= -32768.0f) {
        return INT16_MIN;
    }
    return (int16_t)roundf(x);
}

static uint32_t to_u32(float x)
{
    if (isnan(x)) {
        return 0u;
    }
    return x <= 0.0f ? 0u : x >= 4294967296.0f ? UINT32_MAX : (uint32_t)roundf(x);
}

static float clampf(float x, float lim, bool *clamped)
{
    if (x > lim) {
        *clamped = true;
        return lim;
    }
    if (x < -lim) {
        *clamped = true;
        return -lim;
    }
    return x;
}

/* A ramp from x toward target: `up` while |x| grows, `down` while it shrinks (pv:
 * 0x6083 accelerates, 0x6084 decelerates, also through zero). */
static float ramp(float x, float target, float up, float down, float dt)
{
    const bool growing = (target > x && x >= 0.0f) || (target < x && x <= 0.0f);
    const float step = (growing ? up : down) * dt;
    if (target > x) {
        return x + step < target ? x + step : target;
    }
    return x - step > target ? x - step : target;
}

bool mc_402_mode_supported(int8_t mode)
{
    return mode == MC_402_MODE_PV || mode == MC_402_MODE_TQ || mode == MC_402_MODE_CSV || mode == MC_402_MODE_CST;
}

static bool speed_mode(int8_t mode)
{
    return mode == MC_402_MODE_PV || mode == MC_402_MODE_CSV;
}

/* The configuration's values as this block uses them: a pole pair count, rated values and a
 * period that make sense whatever the caller passed. */
static float pole_pairs(const mc_402_cfg_t *c)
{
    return (float)(c->pole_pairs > 0 && c->pole_pairs < 1000 ? c->pole_pairs : 1);
}

static float positive_or1(float x)
{
    return x > 0.0f && x < 3.0e38f ? x : 1.0f;
}

void mc_402_configure(mc_402_t *s, const mc_402_cfg_t *cfg)
{
    s->cfg = *cfg;
    s->od.rated_current = to_u32(cfg->rated_current * 1000.0f);
    s->od.rated_torque = to_u32(cfg->rated_torque * 1000.0f);
}

void mc_402_init(mc_402_t *s, const mc_402_cfg_t *cfg)
{
    *s = (mc_402_t){.state = MC_402_SWITCH_ON_DISABLED, .active_mode = MC_402_MODE_PV,
                    .drive_prev = (uint32_t)MC_STATE_IDLE};
    mc_402_configure(s, cfg);
    mc_402_od_t *o = &s->od;
    /* the option codes' defaults of the profile (0x605E: the drive's own reaction, 0) */
    o->quick_stop_option = 2;
    o->shutdown_option = 0;
    o->disable_op_option = 1;
    o->fault_reaction_option = 0;
    o->mode = MC_402_MODE_PV;
    o->mode_display = MC_402_MODE_PV;
    o->velocity_window = 20u;
    o->velocity_window_time = 10u;
    o->velocity_threshold = 10u;
    o->velocity_threshold_time = 10u;
    o->max_torque = 1000u;
    o->max_motor_speed = to_u32(cfg->max_speed_rpm);
    o->profile_accel = to_u32(cfg->accel_rpm_s);
    o->profile_decel = o->profile_accel;
    o->quick_stop_decel = o->profile_accel;
    o->torque_slope = 10000u;   /* the rated torque in 0.1 s */
    o->supported_modes = (1u << 2) | (1u << 3) | (1u << 8) | (1u << 9);   /* pv, tq, csv, cst (§6.5.2) */
    o->statusword = (uint16_t)(mc_402_statusword_for(s->state) | SW_REMOTE);
}

static void set_state(mc_402_t *s, mc_402_state_t st)
{
    if (st != s->state && st != MC_402_QUICK_STOP_ACTIVE) {
        s->stopping = false;   /* a ramp-down ends with the state it was for (or is cut short) */
    }
    if (st == MC_402_SWITCHED_ON || st == MC_402_OPERATION_ENABLED) {
        s->voltage = true;     /* transition 3 closes the "main contactor" ... */
    } else if (st == MC_402_SWITCH_ON_DISABLED || st == MC_402_READY_TO_SWITCH_ON || st == MC_402_NOT_READY) {
        s->voltage = false;    /* ... 2, 6-10, 12, 15 open it; 11, 13, 14 leave it */
    }
    s->state = st;
}

/* Begin a ramp-down to standstill that ends in `to`. */
static void begin_stop(mc_402_t *s, uint32_t decel, mc_402_state_t to)
{
    s->stopping = true;
    s->stop_to = to;
    s->stop_decel = decel > 1u ? (float)decel : 1.0f;
    s->stop_time = 0.0f;
    /* v_ramp is where the ramp starts: a torque mode switches to speed control from the velocity
     * actual in this step (control_kind), so the bound takes the larger of the two */
    const float v0 = fmaxf(fabsf(s->v_ramp), fabsf((float)s->od.velocity_actual));
    s->stop_limit = fminf(v0, (float)s->od.max_motor_speed) / s->stop_decel + 1.0f;
}

/* The fault code of 0x603F: the EMCY code of the lowest fault bit (co_emcy.c), generic without. */
static uint16_t fault_code(uint32_t faults)
{
    for (uint32_t bit = 0u; bit < 32u; ++bit) {
        if ((faults & (1u << bit)) != 0u) {
            return mc_co_emcy_code(bit);
        }
    }
    return 0x1000u;
}

/* The drive's fault states (§6.3 Figure 13, transitions 13, 14), from its telemetry. */
static void drive_faults(mc_402_t *s, const mc_drive_telem_t *tm)
{
    const uint32_t ds = (uint32_t)tm->state, prev = s->drive_prev;
    s->drive_prev = ds;
    const bool enabling = s->state == MC_402_OPERATION_ENABLED || s->state == MC_402_QUICK_STOP_ACTIVE ||
                          s->state == MC_402_FAULT_REACTION_ACTIVE;
    if (s->state == MC_402_FAULT) {
        return;   /* latched until the fault reset */
    }
    if (ds == (uint32_t)MC_STATE_FAULT_REACTION) {
        if (s->state != MC_402_FAULT_REACTION_ACTIVE) {
            s->od.error_code = fault_code(tm->faults);
            set_state(s, MC_402_FAULT_REACTION_ACTIVE);   /* 13 */
        }
    } else if (ds == (uint32_t)MC_STATE_FAULT) {
        /* while enabling: the drive's fault; else only a new one (the drive may still show the
         * fault just reset while it is being disabled) */
        if (enabling || prev != (uint32_t)MC_STATE_FAULT) {
            if (s->state != MC_402_FAULT_REACTION_ACTIVE || s->od.error_code == 0u) {
                s->od.error_code = fault_code(tm->faults);
            }
            set_state(s, MC_402_FAULT);   /* 14 (13 + 14 at once without a reaction) */
        }
    } else if (s->state == MC_402_FAULT_REACTION_ACTIVE) {
        /* the reaction ended without the drive showing FAULT (it was disabled meanwhile): the
         * fault stays a fault */
        set_state(s, MC_402_FAULT);   /* 14 */
    }
}

/* The quick stop (transition 11) with its option code 0x605A. */
static void quick_stop(mc_402_t *s)
{
    const int16_t q = s->od.quick_stop_option;
    if (q == 0) {
        set_state(s, MC_402_SWITCH_ON_DISABLED);   /* disable the drive function at once */
        return;
    }
    const bool stay = q >= 5 && q <= 8;
    const uint32_t decel = (q == 1 || q == 5) ? s->od.profile_decel : s->od.quick_stop_decel;
    set_state(s, MC_402_QUICK_STOP_ACTIVE);
    begin_stop(s, decel, stay ? MC_402_QUICK_STOP_ACTIVE : MC_402_SWITCH_ON_DISABLED);
}

/* The controlword's transitions (§6.3 Figure 13, Table 29): 1-12, 15, 16. */
static void transitions(mc_402_t *s, uint16_t cw)
{
    const cmd_t c = decode(cw);
    const mc_402_od_t *o = &s->od;
    switch (s->state) {
    case MC_402_NOT_READY: set_state(s, MC_402_SWITCH_ON_DISABLED); break;   /* 1 */
    case MC_402_SWITCH_ON_DISABLED:
        if (c == CMD_SHUTDOWN) {
            set_state(s, MC_402_READY_TO_SWITCH_ON);   /* 2 */
        }
        break;
    case MC_402_READY_TO_SWITCH_ON:
        if (c == CMD_SWITCH_ON) {
            set_state(s, MC_402_SWITCHED_ON);   /* 3 */
        } else if (c == CMD_ENABLE_OP) {
            set_state(s, MC_402_OPERATION_ENABLED);   /* 3 + 4 (Table 28 note: switch on + enable) */
        } else if (c == CMD_DISABLE_VOLTAGE || c == CMD_QUICK_STOP) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 7 */
        }
        break;
    case MC_402_SWITCHED_ON:
        if (c == CMD_ENABLE_OP) {
            set_state(s, MC_402_OPERATION_ENABLED);   /* 4 */
        } else if (c == CMD_SHUTDOWN) {
            set_state(s, MC_402_READY_TO_SWITCH_ON);   /* 6 */
        } else if (c == CMD_DISABLE_VOLTAGE || c == CMD_QUICK_STOP) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 10 */
        }
        break;
    case MC_402_OPERATION_ENABLED:
        if (c == CMD_DISABLE_VOLTAGE) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 9 */
        } else if (c == CMD_QUICK_STOP) {
            quick_stop(s);   /* 11 (also during a disable operation / shutdown ramp: the faster one) */
        } else if (c == CMD_SWITCH_ON && !s->stopping) {   /* 5: disable operation */
            if (o->disable_op_option != 0) {
                begin_stop(s, o->profile_decel, MC_402_SWITCHED_ON);
            } else {
                set_state(s, MC_402_SWITCHED_ON);
            }
        } else if (c == CMD_SHUTDOWN && !s->stopping) {   /* 8 */
            if (o->shutdown_option != 0) {
                begin_stop(s, o->profile_decel, MC_402_READY_TO_SWITCH_ON);
            } else {
                set_state(s, MC_402_READY_TO_SWITCH_ON);
            }
        } else if (c == CMD_ENABLE_OP && s->stopping) {
            s->stopping = false;   /* enable operation again before the ramp-down ended */
        }
        break;
    case MC_402_QUICK_STOP_ACTIVE:
        if (c == CMD_DISABLE_VOLTAGE) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 12 */
        } else if (c == CMD_ENABLE_OP && (!s->stopping || s->stop_to == MC_402_QUICK_STOP_ACTIVE)) {
            set_state(s, MC_402_OPERATION_ENABLED);   /* 16: options 5-8 only (they stay here) */
        }
        break;
    case MC_402_FAULT:
        if ((cw & CW_FAULT_RESET) != 0u && (s->cw_prev & CW_FAULT_RESET) == 0u) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 15: fault reset, on the rising edge */
            s->od.error_code = 0u;
        }
        break;
    default: break;   /* fault reaction active: only the drive ends it (14) */
    }
}

/* Speed or torque control, and the bumpless start of the ramp that takes over. */
static void control_kind(mc_402_t *s, const mc_drive_telem_t *tm, float t_rated)
{
    const bool want = s->stopping || s->state == MC_402_QUICK_STOP_ACTIVE || speed_mode(s->active_mode);
    if (want == s->speed_ctl) {
        return;
    }
    bool dummy = false;
    if (want) {   /* from the velocity actual */
        s->v_ramp = clampf((float)s->od.velocity_actual, (float)s->od.max_motor_speed, &dummy);
    } else {      /* from the torque the drive's speed loop asks for */
        s->t_ramp = clampf(fin(tm->torque_ref) / t_rated * 1000.0f, (float)s->od.max_torque, &dummy);
    }
    s->speed_ctl = want;
}

static void advance(mc_402_t *s, const mc_drive_telem_t *tm, float dt, mc_drive_cmd_t *cmd)
{
    mc_402_od_t *o = &s->od;
    const mc_402_cfg_t *c = &s->cfg;
    if ((uint32_t)s->state > (uint32_t)MC_402_FAULT) {
        s->state = MC_402_NOT_READY;   /* a corrupted state starts over (transition 1 follows) */
    }
    const uint16_t cw = o->controlword;
    const float pp = pole_pairs(c), t_rated = positive_or1(c->rated_torque), i_rated = positive_or1(c->rated_current);
    const float omega = fin(tm->omega), id = fin(tm->i_dq.d), iq = fin(tm->i_dq.q), vdc = fin(tm->vdc);

    /* the actual values 0x606C, 0x6077-0x6079 */
    o->velocity_actual = to_i32(omega / pp * RPM_PER_RAD_S);
    const float t_nm = 1.5f * pp * (fin(c->psi_pm) * iq + (fin(c->ld) - fin(c->lq)) * id * iq);   /* (2.9) */
    o->torque_actual = to_i16(t_nm / t_rated * 1000.0f);
    const float i_mag = sqrtf(id * id + iq * iq);
    o->current_actual = to_i16((iq < 0.0f ? -i_mag : i_mag) / i_rated * 1000.0f);
    o->dc_link_voltage = to_u32(vdc * 1000.0f);
    const float v_act = (float)o->velocity_actual;

    /* the controlword first, the drive's faults after it: a command that would enable a drive
     * showing FAULT (a fault reset, then enable, before the drive has left it) ends in Fault in
     * the same step, so no enable goes out to it */
    transitions(s, cw);
    s->cw_prev = cw;
    drive_faults(s, tm);

    /* the mode in force (0x6060 -> 0x6061) */
    if (mc_402_mode_supported(o->mode)) {
        s->active_mode = o->mode;
    }
    o->mode_display = s->active_mode;
    control_kind(s, tm, t_rated);

    const bool op = s->state == MC_402_OPERATION_ENABLED || s->state == MC_402_QUICK_STOP_ACTIVE;
    const bool run = tm->state == MC_STATE_RUN;
    const bool halt = (cw & CW_HALT) != 0u;
    const float vmax = (float)o->max_motor_speed, tmax = (float)o->max_torque;
    if (op && run && !s->running) {
        /* RUN entry: from standstill, or from the speed a catch found */
        bool dummy = false;
        s->v_ramp = fabsf(v_act) > (float)o->velocity_threshold ? clampf(v_act, vmax, &dummy) : 0.0f;
        s->t_ramp = 0.0f;
    }
    s->running = op && run;

    /* the target in force, clamped (bit 11) */
    s->limited = false;
    float v_target = 0.0f, t_target = 0.0f;
    if (s->stopping || s->state == MC_402_QUICK_STOP_ACTIVE) {
        /* a ramp-down, or held at 0 after it (options 5-8) */
    } else if (s->active_mode == MC_402_MODE_PV) {
        v_target = halt ? 0.0f : clampf((float)o->target_velocity, vmax, &s->limited);
    } else if (s->active_mode == MC_402_MODE_CSV) {
        v_target = clampf((float)o->target_velocity + (float)o->velocity_offset, vmax, &s->limited);
    } else if (s->active_mode == MC_402_MODE_TQ) {
        t_target = halt ? 0.0f : clampf((float)o->target_torque, tmax, &s->limited);
    } else {
        t_target = clampf((float)o->target_torque + (float)o->torque_offset, tmax, &s->limited);
    }

    /* the ramps: held at 0 while the drive is off or starts up */
    if (!s->running) {
        s->v_ramp = 0.0f;
        s->t_ramp = 0.0f;
    } else if (s->stopping) {
        s->v_ramp = ramp(s->v_ramp, 0.0f, s->stop_decel, s->stop_decel, dt);
    } else if (s->state == MC_402_QUICK_STOP_ACTIVE) {
        s->v_ramp = 0.0f;
    } else if (s->active_mode == MC_402_MODE_PV) {
        s->v_ramp = ramp(s->v_ramp, v_target, (float)o->profile_accel, (float)o->profile_decel, dt);
    } else if (s->active_mode == MC_402_MODE_CSV) {
        s->v_ramp = v_target;
    } else if (s->active_mode == MC_402_MODE_TQ) {
        s->t_ramp = ramp(s->t_ramp, t_target, (float)o->torque_slope, (float)o->torque_slope, dt);
    } else {
        s->t_ramp = t_target;
    }

    /* standstill (0x606F / 0x6070) and the velocity window (0x606D / 0x606E): a time of 0 still needs the condition */
    s->thr_time = fabsf(v_act) <= (float)o->velocity_threshold ? fminf(s->thr_time + dt, 1.0e6f) : 0.0f;
    s->win_time = fabsf(v_act - v_target) <= (float)o->velocity_window ? fminf(s->win_time + dt, 1.0e6f) : 0.0f;
    const bool still = s->thr_time >= 1e-3f * (float)o->velocity_threshold_time && fabsf(v_act) <= (float)o->velocity_threshold;
    if (s->stopping) {
        s->stop_time += dt;
        if (still || s->stop_time >= s->stop_limit) {
            set_state(s, s->stop_to);   /* 12 (1-4), 5, 8; options 5-8 stay: held at 0 */
            s->stopping = false;
            s->v_ramp = 0.0f;
            control_kind(s, tm, t_rated);
        }
    }

    /* the command, and the demand objects from it */
    const bool outputs = s->state == MC_402_OPERATION_ENABLED || s->state == MC_402_QUICK_STOP_ACTIVE;
    const bool held = s->state == MC_402_FAULT_REACTION_ACTIVE;
    if (held) {
        *cmd = s->cmd;   /* the drive's own reaction: keep what it had */
    } else {
        *cmd = (mc_drive_cmd_t){.enable = outputs, .mode = s->speed_ctl ? MC_MODE_SPEED : MC_MODE_TORQUE,
                                .speed_ref = outputs && s->speed_ctl ? s->v_ramp / RPM_PER_RAD_S : 0.0f,
                                .torque_ref = outputs && !s->speed_ctl ? s->t_ramp * 1e-3f * t_rated : 0.0f,
                                .theta_init = 0.0f};
    }
    s->cmd = *cmd;
    if (!cmd->enable) {
        o->velocity_demand = 0;
        o->torque_demand = 0;
    } else if (cmd->mode == MC_MODE_SPEED) {
        o->velocity_demand = to_i32(held ? cmd->speed_ref * RPM_PER_RAD_S : s->v_ramp);
        o->torque_demand = to_i16(fin(tm->torque_ref) / t_rated * 1000.0f);   /* the speed loop's */
    } else {
        o->velocity_demand = 0;
        o->torque_demand = to_i16(held ? cmd->torque_ref / t_rated * 1000.0f : s->t_ramp);
    }

    /* the statusword (§6.3.2 Table 30; bits 10, 12, 13 by mode) */
    uint16_t sw = (uint16_t)(mc_402_statusword_for(s->state) | SW_REMOTE);
    if (s->voltage && vdc >= fin(c->vdc_on)) {
        sw |= SW_VOLTAGE;
    }
    if (outputs && run) {
        bool reached;
        if (s->stopping || s->state == MC_402_QUICK_STOP_ACTIVE ||
            (halt && (s->active_mode == MC_402_MODE_PV || s->active_mode == MC_402_MODE_TQ))) {
            reached = s->speed_ctl ? still : s->t_ramp == 0.0f;   /* halted / stopped */
        } else if (s->speed_ctl) {
            reached = s->win_time >= 1e-3f * (float)o->velocity_window_time && fabsf(v_act - v_target) <= (float)o->velocity_window &&
                      (s->active_mode != MC_402_MODE_PV || s->v_ramp == v_target);
        } else {
            reached = s->t_ramp == t_target;
        }
        if (reached) {
            sw |= SW_REACHED;
        }
    }
    if (s->limited || tm->u_limited) {
        sw |= SW_LIMIT;
    }
    if (s->active_mode == MC_402_MODE_PV) {
        if (still) {
            sw |= SW_OMS12;
        }
    } else if (s->active_mode != MC_402_MODE_TQ && s->state == MC_402_OPERATION_ENABLED && run && !s->stopping) {
        sw |= SW_OMS12;
    }
    if (run) {
        sw |= SW_RUN;
    }
    if (cmd->enable && (tm->state == MC_STATE_OFFSET_CAL || tm->state == MC_STATE_INIT_POS)) {
        sw |= SW_STARTUP;
    }
    o->statusword = sw;
}

/* The period this block runs at, as a finite step (NaN, negative -> 0: no time passes). */
static float period(const mc_402_cfg_t *c)
{
    return c->dt > 0.0f && c->dt < 10.0f ? c->dt : 0.0f;
}

void mc_402_step(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd)
{
    advance(s, tm, period(&s->cfg), cmd);
}

void mc_402_controlword(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd)
{
    advance(s, tm, 0.0f, cmd);
}

const char *mc_402_state_name(mc_402_state_t st)
{
    switch (st) {
    case MC_402_NOT_READY: return "not ready to switch on";
    case MC_402_SWITCH_ON_DISABLED: return "switch on disabled";
    case MC_402_READY_TO_SWITCH_ON: return "ready to switch on";
    case MC_402_SWITCHED_ON: return "switched on";
    case MC_402_OPERATION_ENABLED: return "operation enabled";
    case MC_402_QUICK_STOP_ACTIVE: return "quick stop active";
    case MC_402_FAULT_REACTION_ACTIVE: return "fault reaction active";
    case MC_402_FAULT: return "fault";
    default: return "?";
    }
}
