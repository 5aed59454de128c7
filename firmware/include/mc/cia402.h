/* The CiA 402 drive profile (CiA 402-2 / IEC 61800-7-201): the power drive system state machine
 * on the controlword 0x6040 and the statusword 0x6041, the modes of operation profile velocity,
 * profile torque, cyclic synchronous velocity and cyclic synchronous torque, and the objects they
 * need, as a pure block: mc_402_step turns the objects and the drive's telemetry into the drive's
 * command (mc/drive.h). The CANopen device (mc/co.h) maps the objects onto its dictionary.
 *
 * Units (docs/can.md): velocities in rpm, mechanical; torques in per-mille of the rated torque;
 * currents in per-mille of the rated current; the DC link in mV.
 *
 * Drive engineer's choices where the profile leaves them open:
 *   - The drive's outputs are on in Operation enabled, in Quick stop active while it ramps down
 *     (and after it with options 5, 6) and while a fault reaction runs. Entering Operation enabled
 *     starts the drive (offset calibration, the catch or the initial position); the statusword's
 *     bit 15 says the start-up runs, bit 14 that the drive is in RUN. The velocity ramp starts
 *     from 0 when the drive reaches RUN.
 *   - A quick stop in a torque mode takes the drive into speed control from its actual speed and
 *     ramps it down (torque control cannot stop a rotor on its own).
 *   - "Stopped" is |velocity actual| <= 0x606F for 0x6070, or the ramp at 0 for that long; a
 *     ramp-down that has not stopped the rotor after its nominal time + 1 s disables anyway.
 *   - The fault reaction is the drive's own (0x605E reads 0): its state FAULT_REACTION shows as
 *     Fault reaction active with the command kept as it was (over-speed with
 *     protection.overspeed_action = hold_fw needs the outputs on); its FAULT as Fault, the command
 *     disabled and 0x603F the EMCY code of the fault. The Fault state is latched here (the drive
 *     forgets its faults once disabled) until a fault reset (rising edge of bit 7).
 *   - Bit 7 (warning) is not used; bit 11 (internal limit active): a target clamped by 0x6080 /
 *     0x6072 or the current controller at its voltage limit.
 * Every input may be anything a bus can carry: integer extremes saturate, a NaN in the telemetry
 * reads as 0, the state is always one of mc_402_state_t. */
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

/* The objects as on the bus. */
typedef struct {
    uint16_t controlword;        /* 0x6040 */
    uint16_t statusword;         /* 0x6041 */
    uint16_t error_code;         /* 0x603F */
    int16_t quick_stop_option;   /* 0x605A */
    int16_t shutdown_option;     /* 0x605B */
    int16_t disable_op_option;   /* 0x605C */
    int16_t fault_reaction_option;  /* 0x605E */
    int8_t mode;                 /* 0x6060 */
    int8_t mode_display;         /* 0x6061 */
    int32_t velocity_demand;     /* 0x606B [rpm] */
    int32_t velocity_actual;     /* 0x606C [rpm] */
    uint16_t velocity_window;    /* 0x606D [rpm] */
    uint16_t velocity_window_time;     /* 0x606E [ms] */
    uint16_t velocity_threshold; /* 0x606F [rpm] */
    uint16_t velocity_threshold_time;  /* 0x6070 [ms] */
    int16_t target_torque;       /* 0x6071 [per-mille] */
    uint16_t max_torque;         /* 0x6072 [per-mille] */
    int16_t torque_demand;       /* 0x6074 [per-mille] */
    uint32_t rated_current;      /* 0x6075 [mA] */
    uint32_t rated_torque;       /* 0x6076 [mN m] */
    int16_t torque_actual;       /* 0x6077 [per-mille] */
    int16_t current_actual;      /* 0x6078 [per-mille] */
    uint32_t dc_link_voltage;    /* 0x6079 [mV] */
    uint32_t max_motor_speed;    /* 0x6080 [rpm] */
    uint32_t profile_accel;      /* 0x6083 [rpm/s] */
    uint32_t profile_decel;      /* 0x6084 [rpm/s] */
    uint32_t quick_stop_decel;   /* 0x6085 [rpm/s] */
    uint32_t torque_slope;       /* 0x6087 [per-mille/s] */
    int32_t velocity_offset;     /* 0x60B1 [rpm] */
    int16_t torque_offset;       /* 0x60B2 [per-mille] */
    int32_t target_velocity;     /* 0x60FF [rpm] */
    uint32_t supported_modes;    /* 0x6502 */
} mc_402_od_t;

typedef struct {
    float dt;                    /* [s] the period mc_402_step is called at */
    int pole_pairs;
    float rated_torque;          /* [N m] */
    float rated_current;         /* [A] */
    float psi_pm, ld, lq;        /* torque actual = 1.5 p (psi_pm i_q + (ld - lq) i_d i_q) (2.9) */
    float vdc_on;                /* [V] statusword bit 4 (voltage enabled) above it */
    float max_speed_rpm;         /* default of 0x6080 */
    float accel_rpm_s;           /* default of 0x6083, 0x6084, 0x6085 */
} mc_402_cfg_t;

typedef struct {
    mc_402_cfg_t cfg;
    mc_402_od_t od;
    mc_402_state_t state;
    int8_t active_mode;          /* the mode in force (0x6061) */
    uint16_t cw_prev;            /* bit 7's edge */
    uint32_t drive_prev;         /* the drive's state at the last step (its fault edges) */
    float v_ramp;                /* velocity demand [rpm] */
    float t_ramp;                /* torque demand [per-mille] */
    bool stopping;               /* a ramp-down runs (quick stop, disable / shutdown option 1) */
    mc_402_state_t stop_to;      /* where it ends */
    float stop_decel;            /* [rpm/s] */
    float stop_time, stop_limit; /* [s] since it began, its bound */
    bool speed_ctl;              /* the drive is commanded in speed (a speed mode, or a stop) */
    bool limited;                /* a target was clamped this step */
    float win_time, thr_time;    /* [s] within the velocity window, below the threshold */
    mc_drive_cmd_t cmd;          /* the last command */
} mc_402_t;

void mc_402_init(mc_402_t *s, const mc_402_cfg_t *cfg);        /* defaults, Switch on disabled */
void mc_402_configure(mc_402_t *s, const mc_402_cfg_t *cfg);   /* motor data changed: rated objects follow */
bool mc_402_mode_supported(int8_t mode);
/* Every cfg.dt: the state machine on the controlword, the ramps, the actual values from tm, and
 * the drive command to publish (always complete). */
void mc_402_step(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd);
/* The same without advancing time: for a controlword written between two steps (each takes its
 * transition, also two in one batch of frames). */
void mc_402_controlword(mc_402_t *s, const mc_drive_telem_t *tm, mc_drive_cmd_t *cmd);
const char *mc_402_state_name(mc_402_state_t st);

#endif
