/* The CiA 402 drive profile (CiA 402-2 / IEC 61800-7-201): the power drive system state machine
 * on the controlword 0x6040 and the statusword 0x6041, the modes of operation profile velocity,
 * profile torque, cyclic synchronous velocity and cyclic synchronous torque, and the objects they
 * need, as a pure block: mc_402_step turns the objects and the drive's telemetry into the drive's
 * command (mc/drive.h). The CANopen device (mc/co.h) maps the objects onto its dictionary by
 * offsetof into mc_402_od_t.
 *
 * Units (docs/can.md): velocities in rpm, mechanical; torques in per-mille of the rated torque;
 * currents in per-mille of the rated current; the DC link in mV.
 *
 * Drive engineer's choices where the profile leaves them open:
 *   - Outputs: the drive is enabled in Operation enabled, in Quick stop active (while it ramps
 *     down; with options 5-8 also after it, held at speed 0, as the profile's "drive function
 *     enabled" in that state says) and while a fault reaction runs. Entering Operation enabled
 *     starts the drive (offset calibration, the catch or the initial position): statusword
 *     bit 15 says the start-up runs, bit 14 that the drive is in RUN.
 *   - The ramps hold at 0 while the drive starts up. At RUN entry the velocity ramp starts from 0,
 *     or from the velocity actual if that is above 0x606F (a flying start or a recovery caught a
 *     turning rotor: starting from 0 would brake it first); the torque ramp starts from 0.
 *   - Quick stop (0x605A): 0 disable at once; 1, 5 ramp down on 0x6084; 2 (default), 3, 4, 6, 7, 8
 *     on 0x6085 (the current and voltage limit stops 3, 4, 7, 8 are taken as the quick stop
 *     ramp); 1-4 end in Switch on disabled, 5-8 stay in Quick stop active (enable operation
 *     returns to Operation enabled). Other values (the manufacturer range) act as 2. Disable
 *     operation (0x605C, default 1) and shutdown (0x605B, default 0): 0 at once, any other value
 *     ramps down on 0x6084 first (the state stays Operation enabled meanwhile).
 *   - A ramp-down in a torque mode takes the drive into speed control from its actual speed
 *     (torque control cannot stop a rotor on its own).
 *   - "Stopped" is |velocity actual| <= 0x606F for 0x6070; a ramp-down that has not stopped the
 *     rotor after its nominal time (start speed / deceleration) + 1 s ends anyway.
 *   - Halt (bit 8): pv ramps to 0 on 0x6084 and holds (enabled), tq ramps the torque to 0 on
 *     0x6087; the cyclic modes ignore it (their master owns the trajectory).
 *   - Mode changes are bumpless: into speed control from the velocity actual, into torque
 *     control from the drive's torque reference; pv <-> csv and tq <-> cst continue the demand.
 *     An unsupported 0x6060 (the dictionary refuses such writes) keeps the mode in force; 0x6061
 *     shows the mode in force.
 *   - Faults: the fault reaction is the drive's own (0x605E reads 0): its state FAULT_REACTION
 *     shows as Fault reaction active with the command kept as it was (over-speed with
 *     protection.overspeed_action = hold_fw needs the outputs on); its FAULT as Fault with the
 *     command disabled. 0x603F is the EMCY code (mc_co_emcy_code) of the lowest fault bit, 0x1000
 *     with none. Fault is latched here (the drive forgets its faults once disabled) until a fault
 *     reset (rising edge of bit 7); one during the reaction is ignored. A drive fault while this
 *     block does not enable the drive (a configuration refused at init) is a Fault too.
 *   - Statusword: bit 4 (voltage enabled) as if a main contactor were closed by switch on and
 *     opened by shutdown / disable voltage / fault reset (a fault leaves it as it was), and only
 *     with the DC link at or above cfg.vdc_on. Bit 7 (warning) and bit 8 are not used (0). Bit 10
 *     target reached: pv, csv |velocity actual - target| <= 0x606D for 0x606E (pv: with the ramp
 *     at the target); tq, cst the torque demand at the (clamped) target; a halt or a ramp-down:
 *     stopped. Bit 11 internal limit active: a target clamped by 0x6080 / 0x6072, or the current
 *     controller at its voltage limit (telemetry u_limited). Bit 12: pv speed = 0 (|velocity
 *     actual| <= 0x606F for 0x6070); csv, cst the drive follows the command value (Operation
 *     enabled and RUN); tq 0. Bit 13 0 (pv: no slippage monitoring). Bit 14 the drive is in RUN;
 *     bit 15 its start-up (OFFSET_CAL or INIT_POS, which includes the catch) runs while enabled.
 * Every input may be anything a bus can carry: integer extremes saturate, a NaN or infinity in the
 * telemetry or the configuration reads as 0 (or a neutral value), every float -> integer
 * conversion saturates, the state is always one of mc_402_state_t. */
#ifndef MC_CIA402_H
#define MC_CIA402_H
#include <stdbool.h>
#include <stdint.h>
#include "mc/drive.h"

typedef enum {
    MC_402_NOT_READY = 0, MC_402_SWITCH_ON_DISABLED, MC_402_READY_TO_SWITCH_ON, MC_402_SWITCHED_ON,
    MC_402_OPERATION_ENABLED, MC_402_QUICK_STOP_ACTIVE, MC_402_FAULT_REACTION_ACTIVE, MC_402_FAULT
} mc_402_state_t;

#define MC_402_MODE_PV  3    /* profile velocity */
#define MC_402_MODE_TQ  4    /* profile torque */
#define MC_402_MODE_CSV 9    /* cyclic synchronous velocity */
#define MC_402_MODE_CST 10   /* cyclic synchronous torque */

/* The objects as on the bus: CiA 402 types, the units above. */
typedef struct {
    uint16_t controlword;        /* 0x6040 */
    uint16_t statusword;         /* 0x6041 */
    uint16_t error_code;         /* 0x603F */
    int16_t quick_stop_option;   /* 0x605A, default 2 */
    int16_t shutdown_option;     /* 0x605B, default 0 */
    int16_t disable_op_option;   /* 0x605C, default 1 */
    int16_t fault_reaction_option;  /* 0x605E, 0: the drive's own reaction */
    int8_t mode;                 /* 0x6060, default MC_402_MODE_PV */
    int8_t mode_display;         /* 0x6061 */
    int32_t velocity_demand;     /* 0x606B [rpm] */
    int32_t velocity_actual;     /* 0x606C [rpm] */
    uint16_t velocity_window;    /* 0x606D [rpm], default 20 */
    uint16_t velocity_window_time;     /* 0x606E [ms], default 10 */
    uint16_t velocity_threshold; /* 0x606F [rpm], default 10 */
    uint16_t velocity_threshold_time;  /* 0x6070 [ms], default 10 */
    int16_t target_torque;       /* 0x6071 [per-mille] */
    uint16_t max_torque;         /* 0x6072 [per-mille], default 1000 */
    int16_t torque_demand;       /* 0x6074 [per-mille] */
    uint32_t rated_current;      /* 0x6075 [mA] */
    uint32_t rated_torque;       /* 0x6076 [mN m] */
    int16_t torque_actual;       /* 0x6077 [per-mille] */
    int16_t current_actual;      /* 0x6078 [per-mille]: |i_dq| signed by i_q */
    uint32_t dc_link_voltage;    /* 0x6079 [mV] */
    uint32_t max_motor_speed;    /* 0x6080 [rpm], default cfg.max_speed_rpm */
    uint32_t profile_accel;      /* 0x6083 [rpm/s], default cfg.accel_rpm_s */
    uint32_t profile_decel;      /* 0x6084 [rpm/s], default cfg.accel_rpm_s */
    uint32_t quick_stop_decel;   /* 0x6085 [rpm/s], default cfg.accel_rpm_s */
    uint32_t torque_slope;       /* 0x6087 [per-mille/s], default 10000 */
    int32_t velocity_offset;     /* 0x60B1 [rpm] (csv) */
    int16_t torque_offset;       /* 0x60B2 [per-mille] (cst) */
    int32_t target_velocity;     /* 0x60FF [rpm] */
    uint32_t supported_modes;    /* 0x6502: pv, tq, csv, cst (§6.5.2 bit positions) */
} mc_402_od_t;

typedef struct {
    float dt;                    /* [s] the period mc_402_step is called at */
    int pole_pairs;
    float rated_torque;          /* [N m] motor.torque_rated_nm */
    float rated_current;         /* [A] motor.i_rated_a */
    float psi_pm, ld, lq;        /* torque actual = 1.5 p (psi_pm i_q + (ld - lq) i_d i_q) (2.9) */
    float vdc_on;                /* [V] statusword bit 4 needs the DC link at or above it */
    float max_speed_rpm;         /* default of 0x6080 */
    float accel_rpm_s;           /* default of 0x6083, 0x6084, 0x6085 */
} mc_402_cfg_t;

typedef struct {
    mc_402_cfg_t cfg;
    mc_402_od_t od;
    mc_402_state_t state;
    int8_t active_mode;          /* the mode in force (0x6061) */
    uint16_t cw_prev;            /* the last controlword: bit 7's edge */
    uint32_t drive_prev;         /* the drive's state at the last step (its fault edges) */
    bool voltage;                /* the "main contactor" of statusword bit 4 */
    bool running;                /* enabled and the drive in RUN at the last step (RUN entry) */
    bool speed_ctl;              /* the drive is commanded in speed (a speed mode, or a stop) */
    float v_ramp;                /* velocity demand [rpm] */
    float t_ramp;                /* torque demand [per-mille] */
    bool stopping;               /* a ramp-down runs (quick stop, disable operation / shutdown) */
    mc_402_state_t stop_to;      /* where it ends */
    float stop_decel;            /* [rpm/s] */
    float stop_time, stop_limit; /* [s] since it began, its bound */
    bool limited;                /* a target was clamped this step */
    float win_time, thr_time;    /* [s] within the velocity window, below the threshold */
    mc_drive_cmd_t cmd;          /* the last command (held during a fault reaction) */
} mc_402_t;

void mc_402_init(mc_402_t *s, const mc_402_cfg_t *cfg);        /* od defaults, Switch on disabled */
void mc_402_configure(mc_402_t *s, const mc_402_cfg_t *cfg);   /* motor data changed: cfg and the
                                                                  rated objects follow, state kept */
bool mc_402_mode_supported(int8_t mode);
/* Every cfg.dt: reads the controlword, the mode and the targets and the drive's last telemetry;
 * advances the state machine, the ramps and the actual-value objects; fills *cmd with the drive
 * command to publish (always complete). */
void mc_402_step(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd);
/* The same without advancing time: for a controlword written between two steps (each takes its
 * transition, also two in one batch of frames). */
void mc_402_controlword(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd);
/* The statusword's state bits 0-3, 5, 6 of a state (CiA 402-2 §6.3.2 Table 30, x read as 0). */
uint16_t mc_402_statusword_for(mc_402_state_t st);
const char *mc_402_state_name(mc_402_state_t st);

#endif
