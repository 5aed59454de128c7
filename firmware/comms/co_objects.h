/* The object dictionary's fixed objects, once (mc/co.h): CiA 301 communication objects, the
 * scope, the device's own objects and the CiA 402 objects. The ranges are in co_od.c: PDO
 * parameters 0x1400.. 0x1A03 (4 + 4 PDOs), parameters 0x2000 + id (mc/params_table.h), telemetry
 * 0x2200 + channel (mc/telem_channels.h).
 *
 * X(index, sub, TYPE, ACCESS, FLAGS, KIND, ARG, MIN, MAX, "object name", "sub name", "unit", "doc")
 *   TYPE   BOOL I8 I16 I32 U8 U16 U32 REAL32 VSTRING DOMAIN (mc_co_type_t without MC_CO_)
 *   ACCESS RO WO RW CONST;  FLAGS 0 or MC_CO_F_* or-ed
 *   KIND   FIELD with ARG = FLD(member of mc_co_t) (its size is checked against TYPE), or HOOK
 *          with ARG = HK(name) (co_od.c)
 *   MIN, MAX  the range of an integer write (the EDS's LowLimit / HighLimit)
 * Default values are not written here: the EDS takes them from a device initialised like the
 * firmware (mc_co_init, mc_402_init, mc_co_pdo_defaults). Units in CiA 402 terms: velocities in
 * rpm (mechanical), torques in per-mille of motor.torque_rated_nm, currents in per-mille of
 * motor.i_rated_a. */
#ifndef MC_CO_OBJECTS_H
#define MC_CO_OBJECTS_H

#define MC_U32MAX 4294967295LL
#define MC_NOPT 0   /* no flags */

/* clang-format off */
#define MC_CO_OBJECTS(X) \
X(0x1000, 0, U32, RO, MC_NOPT, HOOK, HK(DEVTYPE), 0, MC_U32MAX, "Device type", "", "", "0x00020192: CiA 402, servo drive.") \
X(0x1001, 0, U8, RO, MC_CO_F_TPDO, HOOK, HK(ERRREG), 0, 255, "Error register", "", "", "Bit 0 generic, 1 current, 2 voltage: from the drive's latched faults.") \
X(0x1003, 0, U8, RW, MC_NOPT, HOOK, HK(HIST), 0, 0, "Pre-defined error field", "Number of errors", "", "Errors in the history (newest first); write 0 to clear.") \
X(0x1003, 1, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 1", "", "EMCY code | drive fault bit << 16.") \
X(0x1003, 2, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 2", "", "") \
X(0x1003, 3, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 3", "", "") \
X(0x1003, 4, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 4", "", "") \
X(0x1003, 5, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 5", "", "") \
X(0x1003, 6, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 6", "", "") \
X(0x1003, 7, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 7", "", "") \
X(0x1003, 8, U32, RO, MC_NOPT, HOOK, HK(HIST), 0, MC_U32MAX, "Pre-defined error field", "Standard error field 8", "", "") \
X(0x1005, 0, U32, RW, MC_NOPT, HOOK, HK(SYNC), 0, MC_U32MAX, "COB-ID SYNC", "", "", "The SYNC the synchronous PDOs follow (this device consumes it, never produces it).") \
X(0x1008, 0, VSTRING, CONST, MC_NOPT, HOOK, HK(NAME), 0, 0, "Manufacturer device name", "", "", "") \
X(0x100A, 0, VSTRING, CONST, MC_NOPT, HOOK, HK(SWVER), 0, 0, "Manufacturer software version", "", "", "") \
X(0x1010, 0, U8, CONST, MC_NOPT, HOOK, HK(ONE), 1, 1, "Store parameters", "Highest sub-index supported", "", "") \
X(0x1010, 1, U32, RW, MC_NOPT, HOOK, HK(STORE), 0, MC_U32MAX, "Store parameters", "Save all parameters", "", "Write 0x65766173 (\"save\") with the outputs off: the drive's configuration (parameters, the estimator's model and its map) goes to the power-cut-safe store (mc/param_store.h). Reads 1: saves on command.") \
X(0x1011, 0, U8, CONST, MC_NOPT, HOOK, HK(ONE), 1, 1, "Restore default parameters", "Highest sub-index supported", "", "") \
X(0x1011, 1, U32, RW, MC_NOPT, HOOK, HK(RESTORE), 0, MC_U32MAX, "Restore default parameters", "Restore all default parameters", "", "Write 0x64616F6C (\"load\") with the outputs off: the stored set is erased; the defaults are in force from the next reset node or power-on.") \
X(0x1017, 0, U16, RW, MC_NOPT, FIELD, FLD(heartbeat_ms), 0, 65535, "Producer heartbeat time", "", "ms", "0: no heartbeat.") \
X(0x1018, 0, U8, CONST, MC_NOPT, HOOK, HK(FOUR), 4, 4, "Identity object", "Highest sub-index supported", "", "") \
X(0x1018, 1, U32, RO, MC_NOPT, FIELD, FLD(cfg.vendor_id), 0, MC_U32MAX, "Identity object", "Vendor-ID", "", "") \
X(0x1018, 2, U32, RO, MC_NOPT, FIELD, FLD(cfg.product_code), 0, MC_U32MAX, "Identity object", "Product code", "", "") \
X(0x1018, 3, U32, RO, MC_NOPT, FIELD, FLD(cfg.revision), 0, MC_U32MAX, "Identity object", "Revision number", "", "") \
X(0x1018, 4, U32, RO, MC_NOPT, FIELD, FLD(cfg.serial), 0, MC_U32MAX, "Identity object", "Serial number", "", "") \
X(0x2300, 0, U8, CONST, MC_NOPT, HOOK, HK(EIGHT), 8, 8, "Scope channels", "Highest sub-index supported", "", "") \
X(0x2300, 1, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[0]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 1", "", "Telemetry channel id (0x2200 + id; 0: unused), taken when the scope is armed.") \
X(0x2300, 2, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[1]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 2", "", "") \
X(0x2300, 3, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[2]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 3", "", "") \
X(0x2300, 4, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[3]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 4", "", "") \
X(0x2300, 5, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[4]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 5", "", "") \
X(0x2300, 6, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[5]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 6", "", "") \
X(0x2300, 7, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[6]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 7", "", "") \
X(0x2300, 8, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.ch[7]), 0, MC_TELEM_CHANNEL_COUNT, "Scope channels", "Channel 8", "", "") \
X(0x2301, 0, U8, CONST, MC_NOPT, HOOK, HK(SIX), 6, 6, "Scope trigger", "Highest sub-index supported", "", "") \
X(0x2301, 1, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.trig_ch), 0, MC_TELEM_CHANNEL_COUNT, "Scope trigger", "Channel", "", "Trigger channel (0: trigger as soon as armed).") \
X(0x2301, 2, REAL32, RW, MC_NOPT, FIELD, FLD(scope_cfg.trig_level), 0, 0, "Scope trigger", "Level", "", "In the trigger channel's unit.") \
X(0x2301, 3, U8, RW, MC_NOPT, FIELD, FLD(scope_cfg.edge), 0, 2, "Scope trigger", "Edge", "", "0 rising, 1 falling, 2 either.") \
X(0x2301, 4, U16, RW, MC_NOPT, FIELD, FLD(scope_cfg.decimation), 1, 65535, "Scope trigger", "Decimation", "periods", "One sample every N control periods.") \
X(0x2301, 5, U32, RW, MC_NOPT, FIELD, FLD(scope_cfg.pre), 0, MC_U32MAX, "Scope trigger", "Pre-trigger", "samples", "Samples kept before the trigger.") \
X(0x2301, 6, U32, RW, MC_NOPT, FIELD, FLD(scope_cfg.length), 0, MC_U32MAX, "Scope trigger", "Length", "samples", "Samples per channel (0: as many as fit).") \
X(0x2302, 0, U8, RW, MC_NOPT, HOOK, HK(SCOPE_CTRL), 0, 2, "Scope control", "", "", "1 arm (takes 0x2300 / 0x2301; refused with the reason as abort 0x06090030 when they do not fit), 2 force the trigger, 0 stop.") \
X(0x2303, 0, U8, RO, MC_NOPT, HOOK, HK(SCOPE_STATUS), 0, 3, "Scope status", "", "", "0 idle, 1 armed, 2 triggered, 3 done.") \
X(0x2304, 0, U32, RO, MC_NOPT, HOOK, HK(SCOPE_SAMPLES), 0, MC_U32MAX, "Scope samples", "", "samples", "Samples per channel in the record (when done).") \
X(0x2305, 0, U32, RO, MC_NOPT, HOOK, HK(SCOPE_TRIG), 0, MC_U32MAX, "Scope trigger index", "", "samples", "Index of the trigger sample in the record.") \
X(0x2306, 0, REAL32, RO, MC_NOPT, HOOK, HK(SCOPE_TS), 0, 0, "Scope sample period", "", "s", "") \
X(0x2307, 0, DOMAIN, RO, MC_NOPT, HOOK, HK(SCOPE_DATA), 0, 0, "Scope data", "", "", "The record by segmented upload: little-endian float32, sample-major (s0 ch1 .. ch n, s1 ch1 ..).") \
X(0x2308, 0, U32, RO, MC_NOPT, HOOK, HK(SCOPE_CAP), 0, MC_U32MAX, "Scope capacity", "", "values", "Buffer size: samples x channels at most.") \
X(0x2FF0, 0, U32, RO, MC_NOPT, HOOK, HK(HASH), 0, MC_U32MAX, "Parameter table hash", "", "", "Changes with the parameter table: a tool compares it with its EDS.") \
X(0x2FF1, 0, U8, RO, MC_NOPT, FIELD, FLD(cfg_source), 0, 255, "Configuration source", "", "", "The store's answer at boot: 0 the stored set, 1 none stored (defaults), 2 the older copy (the newer was corrupt), 3 corrupt (defaults), 4 NVM error (defaults), 8 the stored set migrated from another table version with some values at their defaults (EMCY 0x6310, 0x1003).") \
X(0x2FF2, 0, U32, RO, MC_NOPT, FIELD, FLD(store_status), 0, MC_U32MAX, "Store status", "", "", "The last 0x1010 / 0x1011: mc_pstore_status_t (0 ok, 4 NVM error, 5 too large, 7 saved without the flux map).") \
X(0x603F, 0, U16, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.error_code), 0, 65535, "Error code", "", "", "The EMCY code of the fault that put the drive in Fault (0: none).") \
X(0x6040, 0, U16, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.controlword), 0, 65535, "Controlword", "", "", "CiA 402 state machine commands.") \
X(0x6041, 0, U16, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.statusword), 0, 65535, "Statusword", "", "", "CiA 402 state; bit 14: the drive is in RUN; bit 15: its start-up (offset calibration, initial position, catch) runs.") \
X(0x605A, 0, I16, RW, MC_NOPT, FIELD, FLD(ds.od.quick_stop_option), 0, 8, "Quick stop option code", "", "", "0 disable at once; 1 slow down on 0x6084, 2 (3, 4: the current / voltage limit stops, taken as it) on 0x6085, then Switch on disabled; 5-8 the same, staying in Quick stop active.") \
X(0x605B, 0, I16, RW, MC_NOPT, FIELD, FLD(ds.od.shutdown_option), 0, 1, "Shutdown option code", "", "", "0 disable at once; 1 slow down on 0x6084 first (default 0).") \
X(0x605C, 0, I16, RW, MC_NOPT, FIELD, FLD(ds.od.disable_op_option), 0, 1, "Disable operation option code", "", "", "0 disable at once; 1 slow down on 0x6084 first (default 1, as CiA 402).") \
X(0x605E, 0, I16, RO, MC_NOPT, FIELD, FLD(ds.od.fault_reaction_option), 0, 0, "Fault reaction option code", "", "", "0: the drive's own reaction (outputs off; over-speed above the generation limit with protection.overspeed_action = hold_fw keeps field weakening first).") \
X(0x6060, 0, I8, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.mode), -128, 127, "Modes of operation", "", "", "3 profile velocity, 4 profile torque, 9 cyclic synchronous velocity, 10 cyclic synchronous torque.") \
X(0x6061, 0, I8, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.mode_display), -128, 127, "Modes of operation display", "", "", "") \
X(0x606B, 0, I32, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.velocity_demand), -2147483648LL, 2147483647LL, "Velocity demand value", "", "rpm", "") \
X(0x606C, 0, I32, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.velocity_actual), -2147483648LL, 2147483647LL, "Velocity actual value", "", "rpm", "The speed estimate (sensorless: UNOP after its PLL), mechanical.") \
X(0x606D, 0, U16, RW, MC_NOPT, FIELD, FLD(ds.od.velocity_window), 0, 65535, "Velocity window", "", "rpm", "Target reached (pv, csv) within this ...") \
X(0x606E, 0, U16, RW, MC_NOPT, FIELD, FLD(ds.od.velocity_window_time), 0, 65535, "Velocity window time", "", "ms", "... for this long.") \
X(0x606F, 0, U16, RW, MC_NOPT, FIELD, FLD(ds.od.velocity_threshold), 0, 65535, "Velocity threshold", "", "rpm", "Speed = 0 (pv statusword bit 12) below this ...") \
X(0x6070, 0, U16, RW, MC_NOPT, FIELD, FLD(ds.od.velocity_threshold_time), 0, 65535, "Velocity threshold time", "", "ms", "... for this long.") \
X(0x6071, 0, I16, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.target_torque), -32768, 32767, "Target torque", "", "per-mille", "Of the rated torque 0x6076.") \
X(0x6072, 0, U16, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.max_torque), 0, 65535, "Max torque", "", "per-mille", "Limits the torque targets (the speed loop has its own, control.torque_max_nm).") \
X(0x6074, 0, I16, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.torque_demand), -32768, 32767, "Torque demand", "", "per-mille", "") \
X(0x6075, 0, U32, RO, MC_NOPT, FIELD, FLD(ds.od.rated_current), 0, MC_U32MAX, "Motor rated current", "", "mA", "motor.i_rated_a.") \
X(0x6076, 0, U32, RO, MC_NOPT, FIELD, FLD(ds.od.rated_torque), 0, MC_U32MAX, "Motor rated torque", "", "mN m", "motor.torque_rated_nm.") \
X(0x6077, 0, I16, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.torque_actual), -32768, 32767, "Torque actual value", "", "per-mille", "From the measured currents by the torque equation (2.9).") \
X(0x6078, 0, I16, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.current_actual), -32768, 32767, "Current actual value", "", "per-mille", "|i_dq| with the sign of i_q, of the rated current.") \
X(0x6079, 0, U32, RO, MC_CO_F_TPDO, FIELD, FLD(ds.od.dc_link_voltage), 0, MC_U32MAX, "DC link circuit voltage", "", "mV", "") \
X(0x6080, 0, U32, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.max_motor_speed), 0, MC_U32MAX, "Max motor speed", "", "rpm", "Clamps the velocity targets.") \
X(0x6083, 0, U32, RW, MC_NOPT, FIELD, FLD(ds.od.profile_accel), 1, MC_U32MAX, "Profile acceleration", "", "rpm/s", "") \
X(0x6084, 0, U32, RW, MC_NOPT, FIELD, FLD(ds.od.profile_decel), 1, MC_U32MAX, "Profile deceleration", "", "rpm/s", "") \
X(0x6085, 0, U32, RW, MC_NOPT, FIELD, FLD(ds.od.quick_stop_decel), 1, MC_U32MAX, "Quick stop deceleration", "", "rpm/s", "") \
X(0x6087, 0, U32, RW, MC_NOPT, FIELD, FLD(ds.od.torque_slope), 1, MC_U32MAX, "Torque slope", "", "per-mille/s", "") \
X(0x60B1, 0, I32, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.velocity_offset), -2147483648LL, 2147483647LL, "Velocity offset", "", "rpm", "Added to the target in csv.") \
X(0x60B2, 0, I16, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.torque_offset), -32768, 32767, "Torque offset", "", "per-mille", "Added to the target in cst.") \
X(0x60FF, 0, I32, RW, MC_CO_F_RPDO, FIELD, FLD(ds.od.target_velocity), -2147483648LL, 2147483647LL, "Target velocity", "", "rpm", "") \
X(0x6502, 0, U32, RO, MC_NOPT, FIELD, FLD(ds.od.supported_modes), 0, MC_U32MAX, "Supported drive modes", "", "", "pv, tq, csv, cst.")
/* clang-format on */

#endif
