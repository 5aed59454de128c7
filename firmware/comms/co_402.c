/* The CiA 402 drive profile (mc/cia402.h). Section numbers: CiA 402-2 v4.1 (= IEC 61800-7-201). */
#include <math.h>
#include "mc/cia402.h"
#include "mc/co.h"

#define TWO_PI 6.2831853f
#define RPM_PER_RAD_S (60.0f / TWO_PI)

/* Controlword commands (§6.3.1, Table 28): bits 7, 3, 2, 1, 0 */
typedef enum { CMD_NONE, CMD_SHUTDOWN, CMD_SWITCH_ON, CMD_ENABLE_OP, CMD_DISABLE_VOLTAGE, CMD_QUICK_STOP } cmd_t;

static cmd_t decode(uint16_t cw)
{
    if ((cw & 0x0082u) == 0x0000u) {
        return CMD_DISABLE_VOLTAGE;   /* x 0 x x 0 x */
    }
    if ((cw & 0x0086u) == 0x0002u) {
        return CMD_QUICK_STOP;        /* 0 x x 0 1 x */
    }
    if ((cw & 0x0087u) == 0x0006u) {
        return CMD_SHUTDOWN;          /* 0 x 1 1 0 */
    }
    if ((cw & 0x008Fu) == 0x0007u) {
        return CMD_SWITCH_ON;         /* 0 0 1 1 1 (also "disable operation") */
    }
    if ((cw & 0x008Fu) == 0x000Fu) {
        return CMD_ENABLE_OP;         /* 0 1 1 1 1 */
    }
    return CMD_NONE;
}

/* Statusword state bits 0-3, 5, 6 (§6.3.2, Table 30) */
static uint16_t state_bits(mc_402_state_t st)
{
    switch (st) {
    case MC_402_SWITCH_ON_DISABLED: return 0x0040u;
    case MC_402_READY_TO_SWITCH_ON: return 0x0021u;
    case MC_402_SWITCHED_ON: return 0x0023u;
    case MC_402_OPERATION_ENABLED: return 0x0027u;
    case MC_402_QUICK_STOP_ACTIVE: return 0x0007u;
    case MC_402_FAULT_REACTION_ACTIVE: return 0x000Fu;
    case MC_402_FAULT: return 0x0008u;
    default: return 0x0000u;
    }
}

static float finite_or0(float x)
{
    return (x == x && x - x == 0.0f) ? x : 0.0f;
}

static int32_t sat_i32(float x)
{
    x = finite_or0(x);
    if (x >= 2147483520.0f) {
        return INT32_MAX;
    }
    if (x <= -2147483648.0f) {
        return INT32_MIN;
    }
    return (int32_t)lrintf(x);
}

static int16_t sat_i16(float x)
{
    x = finite_or0(x);
    return x >= 32767.0f ? INT16_MAX : x <= -32768.0f ? INT16_MIN : (int16_t)lrintf(x);
}

static uint32_t sat_u32(float x)
{
    x = finite_or0(x);
    return x <= 0.0f ? 0u : x >= 4294967040.0f ? UINT32_MAX : (uint32_t)lrintf(x);
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

/* A ramp from x toward target: rate up while |x| grows, down while it shrinks. */
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

void mc_402_configure(mc_402_t *s, const mc_402_cfg_t *cfg)
{
    s->cfg = *cfg;
    s->od.rated_current = sat_u32(cfg->rated_current * 1000.0f);
    s->od.rated_torque = sat_u32(cfg->rated_torque * 1000.0f);
}

void mc_402_init(mc_402_t *s, const mc_402_cfg_t *cfg)
{
    *s = (mc_402_t){.state = MC_402_SWITCH_ON_DISABLED, .active_mode = MC_402_MODE_PV,
                    .drive_prev = (uint32_t)MC_STATE_IDLE};
    mc_402_configure(s, cfg);
    mc_402_od_t *o = &s->od;
    o->quick_stop_option = 2;
    o->shutdown_option = 0;
    o->disable_op_option = 0;
    o->mode = MC_402_MODE_PV;
    o->mode_display = MC_402_MODE_PV;
    o->velocity_window = 20u;
    o->velocity_window_time = 10u;
    o->velocity_threshold = 10u;
    o->velocity_threshold_time = 10u;
    o->max_torque = 1000u;
    o->max_motor_speed = sat_u32(cfg->max_speed_rpm);
    o->profile_accel = sat_u32(cfg->accel_rpm_s);
    o->profile_decel = o->profile_accel;
    o->quick_stop_decel = o->profile_accel;
    o->torque_slope = 10000u;   /* the rated torque in 0.1 s */
    o->supported_modes = (1u << 2) | (1u << 3) | (1u << 8) | (1u << 9);   /* pv, tq, csv, cst (§6.5.2) */
    o->statusword = (uint16_t)(state_bits(s->state) | 0x0200u);
}

/* Begin a ramp-down to standstill that ends in `to`. */
static void begin_stop(mc_402_t *s, float decel, mc_402_state_t to)
{
    if (!s->speed_ctl) {   /* from a torque mode: speed control from the actual speed */
        s->v_ramp = (float)s->od.velocity_actual;
        s->speed_ctl = true;
    }
    s->stopping = true;
    s->stop_to = to;
    s->stop_decel = decel > 1.0f ? decel : 1.0f;
    s->stop_time = 0.0f;
    s->stop_limit = fabsf(s->v_ramp) / s->stop_decel + 1.0f;
    s->thr_time = 0.0f;
}

static void set_state(mc_402_t *s, mc_402_state_t st)
{
    if (st != s->state && st != MC_402_QUICK_STOP_ACTIVE) {
        s->stopping = false;
    }
    s->state = st;
}

/* The state machine (§6.3, Figure 13): transitions 2-12, 15, 16; 13, 14 come from the drive. */
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
            set_state(s, MC_402_OPERATION_ENABLED);   /* 3 + 4 */
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
        } else if (c == CMD_QUICK_STOP) {   /* 11 */
            const int16_t q = o->quick_stop_option;
            if (q == 0) {
                set_state(s, MC_402_SWITCH_ON_DISABLED);
            } else {
                const float d = (float)((q == 1 || q == 5) ? o->profile_decel : o->quick_stop_decel);
                set_state(s, MC_402_QUICK_STOP_ACTIVE);
                begin_stop(s, d, (q == 1 || q == 2) ? MC_402_SWITCH_ON_DISABLED : MC_402_QUICK_STOP_ACTIVE);
            }
        } else if (c == CMD_SWITCH_ON && !s->stopping) {   /* 5: disable operation */
            if (o->disable_op_option == 1) {
                begin_stop(s, (float)o->profile_decel, MC_402_SWITCHED_ON);
            } else {
                set_state(s, MC_402_SWITCHED_ON);
            }
        } else if (c == CMD_SHUTDOWN && !s->stopping) {   /* 8 */
            if (o->shutdown_option == 1) {
                begin_stop(s, (float)o->profile_decel, MC_402_READY_TO_SWITCH_ON);
            } else {
                set_state(s, MC_402_READY_TO_SWITCH_ON);
            }
        } else if (c == CMD_ENABLE_OP && s->stopping) {
            s->stopping = false;   /* back to the target before the ramp-down ended */
        }
        break;
    case MC_402_QUICK_STOP_ACTIVE:
        if (c == CMD_DISABLE_VOLTAGE) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 12 */
        } else if (c == CMD_ENABLE_OP && o->quick_stop_option >= 5) {
            s->stopping = false;
            set_state(s, MC_402_OPERATION_ENABLED);   /* 16 */
        }
        break;
    case MC_402_FAULT:
        if ((cw & 0x0080u) != 0u && (s->cw_prev & 0x0080u) == 0u) {
            set_state(s, MC_402_SWITCH_ON_DISABLED);   /* 15: fault reset */
            s->od.error_code = 0u;
        }
        break;
    default: break;
    }
}

/* The drive's fault states: 13 (fault reaction) and 14 (fault), on its transitions. */
static void drive_faults(mc_402_t *s, const mc_drive_telem_t *tm)
{
    const uint32_t ds = (uint32_t)tm->state, prev = s->drive_prev;
    s->drive_prev = ds;
    if (ds == (uint32_t)MC_STATE_FAULT_REACTION && s->state != MC_402_FAULT) {
        set_state(s, MC_402_FAULT_REACTION_ACTIVE);
    } else if (ds == (uint32_t)MC_STATE_FAULT &&
               (prev != (uint32_t)MC_STATE_FAULT || s->state == MC_402_FAULT_REACTION_ACTIVE ||
                s->state == MC_402_OPERATION_ENABLED || s->state == MC_402_QUICK_STOP_ACTIVE)) {
        if (s->state != MC_402_FAULT) {
            uint32_t bit = 0u;
            while (bit < 31u && (tm->faults & (1u << bit)) == 0u) {
                bit++;
            }
            s->od.error_code = tm->faults != 0u ? mc_co_emcy_code(bit) : 0x1000u;
        }
        set_state(s, MC_402_FAULT);
    } else if (s->state == MC_402_FAULT_REACTION_ACTIVE && ds != (uint32_t)MC_STATE_FAULT_REACTION) {
        set_state(s, MC_402_FAULT);   /* the reaction ended some other way */
    }
}

static void advance(mc_402_t *s, const mc_drive_telem_t *tm, float dt, mc_drive_cmd_t *cmd)
{
    mc_402_od_t *o = &s->od;
    const uint16_t cw = o->controlword;
    const mc_402_cfg_t *c = &s->cfg;
    const float pp = (float)(c->pole_pairs > 0 ? c->pole_pairs : 1);
    const float omega = finite_or0(tm->omega), id = finite_or0(tm->i_dq.d), iq = finite_or0(tm->i_dq.q);

    /* actual values */
    o->velocity_actual = sat_i32(omega / pp * RPM_PER_RAD_S);
    const float t_nm = 1.5f * pp * (c->psi_pm * iq + (c->ld - c->lq) * id * iq);   /* (2.9) */
    const float t_rated = c->rated_torque > 0.0f ? c->rated_torque : 1.0f;
    const float i_rated = c->rated_current > 0.0f ? c->rated_current : 1.0f;
    o->torque_actual = sat_i16(t_nm / t_rated * 1000.0f);
    const float i_mag = sqrtf(id * id + iq * iq);
    o->current_actual = sat_i16((iq < 0.0f ? -i_mag : i_mag) / i_rated * 1000.0f);
    o->dc_link_voltage = sat_u32(finite_or0(tm->vdc) * 1000.0f);

    drive_faults(s, tm);
    transitions(s, cw);
    s->cw_prev = cw;

    /* the mode in force */
    if (mc_402_mode_supported(o->mode) && o->mode != s->active_mode) {
        const bool to_speed = speed_mode(o->mode);
        if (to_speed && !s->speed_ctl) {
            s->v_ramp = (float)o->velocity_actual;   /* bumpless */
        } else if (!to_speed && s->speed_ctl && !s->stopping) {
            s->t_ramp = finite_or0(tm->torque_ref) / t_rated * 1000.0f;
        }
        s->active_mode = o->mode;
    }
    o->mode_display = s->active_mode;
    if (!s->stopping) {
        s->speed_ctl = speed_mode(s->active_mode);
    }

    const bool op = s->state == MC_402_OPERATION_ENABLED || s->state == MC_402_QUICK_STOP_ACTIVE;
    const bool run = tm->state == MC_STATE_RUN;
    const bool halt = (cw & 0x0100u) != 0u;
    s->limited = false;
    const float vmax = (float)o->max_motor_speed, tmax = (float)o->max_torque;
    float v_target = 0.0f, t_target = 0.0f;
    if (s->stopping) {
        s->v_ramp = ramp(s->v_ramp, 0.0f, s->stop_decel, s->stop_decel, dt);
        s->stop_time += dt;
    } else if (!op || !run) {
        s->v_ramp = 0.0f;   /* the ramps start from standstill when the drive reaches RUN */
        s->t_ramp = 0.0f;
    } else if (s->active_mode == MC_402_MODE_PV) {
        v_target = halt ? 0.0f : clampf((float)o->target_velocity, vmax, &s->limited);
        s->v_ramp = ramp(s->v_ramp, v_target, (float)o->profile_accel, (float)o->profile_decel, dt);
    } else if (s->active_mode == MC_402_MODE_CSV) {
        v_target = clampf((float)o->target_velocity + (float)o->velocity_offset, vmax, &s->limited);
        s->v_ramp = v_target;
    } else if (s->active_mode == MC_402_MODE_TQ) {
        t_target = halt ? 0.0f : clampf((float)o->target_torque, tmax, &s->limited);
        s->t_ramp = ramp(s->t_ramp, t_target, (float)o->torque_slope, (float)o->torque_slope, dt);
    } else {
        t_target = clampf((float)o->target_torque + (float)o->torque_offset, tmax, &s->limited);
        s->t_ramp = t_target;
    }

    /* standstill and the window (0x606D-0x6070) */
    const float v_act = (float)o->velocity_actual;
    s->thr_time = fabsf(v_act) <= (float)o->velocity_threshold ? s->thr_time + dt : 0.0f;
    s->win_time = fabsf(v_act - v_target) <= (float)o->velocity_window ? s->win_time + dt : 0.0f;
    const bool still = s->thr_time >= 1e-3f * (float)o->velocity_threshold_time;
    if (s->stopping && ((s->v_ramp == 0.0f && still) || s->stop_time >= s->stop_limit)) {
        s->stopping = false;
        set_state(s, s->stop_to);
        s->v_ramp = 0.0f;   /* options 5, 6: held at standstill, enabled */
    }

    /* the command */
    const bool outputs = s->state == MC_402_OPERATION_ENABLED || s->state == MC_402_QUICK_STOP_ACTIVE;
    if (s->state == MC_402_FAULT_REACTION_ACTIVE) {
        *cmd = s->cmd;   /* the drive's own reaction: keep what it had */
    } else {
        *cmd = (mc_drive_cmd_t){.enable = outputs, .mode = s->speed_ctl ? MC_MODE_SPEED : MC_MODE_TORQUE,
                                .speed_ref = s->speed_ctl ? s->v_ramp / RPM_PER_RAD_S : 0.0f,
                                .torque_ref = s->speed_ctl ? 0.0f : s->t_ramp * 1e-3f * t_rated};
        if (s->state == MC_402_QUICK_STOP_ACTIVE && !s->stopping) {
            cmd->mode = MC_MODE_SPEED;   /* options 5, 6 after the stop: held at 0 */
            cmd->speed_ref = 0.0f;
        }
    }
    s->cmd = *cmd;
    o->velocity_demand = s->speed_ctl ? sat_i32(s->v_ramp) : 0;
    o->torque_demand = s->speed_ctl ? sat_i16(finite_or0(tm->torque_ref) / t_rated * 1000.0f) : sat_i16(s->t_ramp);

    /* the statusword (§6.3.2) */
    uint16_t sw = (uint16_t)(state_bits(s->state) | 0x0200u);   /* bit 9: remote */
    if (finite_or0(tm->vdc) >= c->vdc_on && s->state != MC_402_SWITCH_ON_DISABLED &&
        s->state != MC_402_NOT_READY) {
        sw |= 0x0010u;   /* voltage enabled */
    }
    bool reached = false;
    if (outputs && run) {
        if (s->speed_ctl) {
            reached = (s->stopping || halt || s->state == MC_402_QUICK_STOP_ACTIVE)
                          ? still
                          : s->win_time >= 1e-3f * (float)o->velocity_window_time && s->v_ramp == v_target;
        } else {
            reached = s->t_ramp == t_target;
        }
    }
    if (reached) {
        sw |= 0x0400u;
    }
    if (s->limited || tm->u_limited) {
        sw |= 0x0800u;   /* internal limit active */
    }
    if (s->active_mode == MC_402_MODE_PV) {
        if (still) {
            sw |= 0x1000u;   /* speed = 0 */
        }
    } else if (s->active_mode != MC_402_MODE_TQ && outputs && run && !s->stopping) {
        sw |= 0x1000u;   /* csv, cst: the drive follows the command value */
    }
    if (outputs && run) {
        sw |= 0x4000u;   /* manufacturer: the drive is in RUN */
    }
    if (outputs && (tm->state == MC_STATE_OFFSET_CAL || tm->state == MC_STATE_INIT_POS)) {
        sw |= 0x8000u;   /* manufacturer: its start-up runs */
    }
    o->statusword = sw;
}

void mc_402_step(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd)
{
    advance(s, tm, s->cfg.dt > 0.0f ? s->cfg.dt : 0.0f, cmd);
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
