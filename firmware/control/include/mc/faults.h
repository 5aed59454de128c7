/* The drive's faults, defined once. Each row is one latched fault reason (a bit of
 * mc_seq_t.faults), in bit order; everything else is generated from it: the MC_FAULT_<NAME>
 * masks below, the class masks (MC_FAULTS_*), the EMCY code and error register (co_emcy.c), the
 * simulator's metrics names (sim/app/runner.cpp), the telemetry's fault word and the fault tables
 * of docs/protection.md (`mcsim faults`) and docs/can.md (`co-gen faults`), the tools'
 * faults.json (scripts/gen_docs.py writes the last three). A new fault is one row here (and one in
 * MC_EMCY_CODES if its code is new) plus its detector, the code that latches MC_FAULT_<NAME>.
 * ctest comms_faults checks the table, faults_table that the sources, simulator, docs and tools
 * follow it.
 *
 * X(NAME, bit, "name", emcy, REG, REACTION, recoverable, "doc")
 *   NAME        the constant MC_FAULT_<NAME>
 *   bit         its bit, stable: it is on the bus (EMCY byte 3, 0x1003, 0x221B) and in stored error
 *               history. < 24: the telemetry carries the fault word as a float32
 *   name        the metrics.json name (scenario metrics, docs): stable too, lower-case
 *   emcy        the EMCY code (CiA 301 Table 21 / CiA 402; one of MC_EMCY_CODES below)
 *   REG         its bit in the error register 0x1001 besides generic: GENERIC (none), CURRENT,
 *               VOLTAGE, TEMPERATURE, COMMUNICATION, PROFILE, MANUFACTURER
 *   REACTION    OFF: outputs off at once (mc_drive_trip). HOLD_FW: above the uncontrolled-
 *               generation speed with protection.overspeed_action = hold_fw, FAULT_REACTION first
 *               (zero torque, field weakening kept up until the speed is safe), else OFF
 *   recoverable 1: in sensorless RUN with protection.lock_action = recover, the flying-start
 *               catch runs instead of latching (protection.retries); 0: never
 *   doc         one line: what it detects (the docs' tables) */
#ifndef MC_FAULTS_H
#define MC_FAULTS_H

/* clang-format off */
#define MC_FAULTS(X) \
X(OVERCURRENT,     0, "overcurrent",        0x2310u, CURRENT, OFF,     0, "A phase current beyond the trip level, or a sample at an ADC rail.") \
X(OVERVOLTAGE,     1, "overvoltage",        0x3210u, VOLTAGE, OFF,     0, "DC link above its window.") \
X(UNDERVOLTAGE,    2, "undervoltage",       0x3220u, VOLTAGE, OFF,     0, "DC link below its window.") \
X(OFFSET_CAL,      3, "offset_calibration", 0x5210u, CURRENT, OFF,     0, "Current-channel offsets out of the plausible range at the calibration.") \
X(CONFIG,          4, "config",             0x6320u, GENERIC, OFF,     0, "Configuration rejected (mc_drive_config_error says why).") \
X(INIT_POS,        5, "init_pos",           0x7300u, GENERIC, OFF,     0, "An initial-position step or the flying-start catch failed.") \
X(TIMEOUT,         6, "timeout",            0x6100u, GENERIC, OFF,     0, "A startup state waited longer than its timeout.") \
X(NUMERIC,         7, "numeric",            0x6100u, GENERIC, OFF,     0, "A non-finite value reached the modulator.") \
X(OVERSPEED,       8, "overspeed",          0x8400u, GENERIC, HOLD_FW, 0, "Filtered speed estimate above protection.overspeed_rpm.") \
X(CURRENT_SENSOR,  9, "current_sensor",     0x5210u, CURRENT, OFF,     0, "The three phase currents do not sum to zero: a stuck or lost channel, a drifted offset.") \
X(TRACKING,       10, "tracking",           0x8300u, CURRENT, OFF,     1, "The current does not follow its reference: a wrong angle, a missing phase at standstill.") \
X(LOSS_OF_LOCK,   11, "loss_of_lock",       0x7300u, GENERIC, OFF,     1, "A sensorless estimate on the wrong solution, swinging, or running away from the PLL.") \
X(STALL,          12, "stall",              0x7121u, GENERIC, OFF,     0, "Speed mode: the speed loop at its torque limit and no speed.") \
X(OVERRUN,        13, "isr_overrun",        0x6100u, GENERIC, OFF,     0, "The ISR overran its period (the port's flag).") \
X(VOLTAGE_MODEL,  14, "voltage_model",      0x7300u, GENERIC, OFF,     1, "The voltage the current loop needs does not fit the motor model at the angle source's speed: a frozen encoder, a wrong estimate, an open phase.") \
X(TORQUE,         15, "torque_plausibility", 0x8300u, GENERIC, OFF,    0, "Speed mode: strong torque one way, the speed estimate accelerating hard the other way (a wrong angle, an overload beyond the limit).") \
X(PULL_OUT,       16, "pull_out",           0x7121u, GENERIC, OFF,     0, "I/f open loop: the frame a full electrical turn off the estimate: the rotor pulled out (a load beyond I_f's torque, a locked rotor) or the estimator does not see it.") \
/* end of MC_FAULTS: a new row goes above this line */

/* The emergency codes the table may use (CiA 301 Table 21, CiA 402 Annex), with their meaning. */
#define MC_EMCY_CODES(X) \
X(0x2310u, "continuous over-current, device output") \
X(0x3210u, "DC link over-voltage") \
X(0x3220u, "DC link under-voltage") \
X(0x5210u, "measurement circuit") \
X(0x6100u, "internal software") \
X(0x6320u, "parameter error") \
X(0x7121u, "motor blocked") \
X(0x7300u, "sensor (the angle's plausibility)") \
X(0x8300u, "torque control") \
X(0x8400u, "velocity / speed monitoring") \
/* end of MC_EMCY_CODES */
/* clang-format on */

/* The fault reasons (bit masks, latched until the next enable). */
enum {
#define MC_FAULT_ENUM_(NAME, bit, name, emcy, reg, reaction, rec, doc) MC_FAULT_##NAME = 1 << (bit),
    MC_FAULTS(MC_FAULT_ENUM_)
#undef MC_FAULT_ENUM_
};

/* CiA 301 error register (0x1001) bits, the REG column. */
#define MC_ERR_REG_GENERIC       0x01u
#define MC_ERR_REG_CURRENT       0x02u
#define MC_ERR_REG_VOLTAGE       0x04u
#define MC_ERR_REG_TEMPERATURE   0x08u
#define MC_ERR_REG_COMMUNICATION 0x10u
#define MC_ERR_REG_PROFILE       0x20u
#define MC_ERR_REG_MANUFACTURER  0x80u

/* The REACTION column. */
#define MC_FAULT_REACT_OFF     0
#define MC_FAULT_REACT_HOLD_FW 1

/* Classes of faults as masks (constant expressions). */
#define MC_FAULT_ALL_(NAME, bit, name, emcy, reg, reaction, rec, doc) | (1u << (bit))
#define MC_FAULT_REC_(NAME, bit, name, emcy, reg, reaction, rec, doc) | ((rec) ? 1u << (bit) : 0u)
#define MC_FAULT_HOLD_(NAME, bit, name, emcy, reg, reaction, rec, doc) \
    | (MC_FAULT_REACT_##reaction == MC_FAULT_REACT_HOLD_FW ? 1u << (bit) : 0u)
#define MC_FAULTS_ALL         (0u MC_FAULTS(MC_FAULT_ALL_))    /* every defined bit              */
#define MC_FAULTS_RECOVERABLE (0u MC_FAULTS(MC_FAULT_REC_))    /* recoverable = 1                */
#define MC_FAULTS_HOLD_FW     (0u MC_FAULTS(MC_FAULT_HOLD_))   /* reaction HOLD_FW                */

/* The recoverable faults' names as one string literal (" tracking loss_of_lock ..."), for texts. */
#define MC_FAULT_IF_1_(s) s
#define MC_FAULT_IF_0_(s)
#define MC_FAULT_REC_NAME_(NAME, bit, name, emcy, reg, reaction, rec, doc) MC_FAULT_IF_##rec##_(" " name)
#define MC_FAULTS_RECOVERABLE_NAMES MC_FAULTS(MC_FAULT_REC_NAME_)

#endif
