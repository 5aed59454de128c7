/* The CiA 402 block (mc/cia402.h) on synthetic telemetry: the state machine's transitions and
 * statusword values (CiA 402-2 §6.3 Table 30), the quick stop, disable operation and shutdown
 * options, the faults with the drive's reaction, the fault-reset edge, and the modes: ramps,
 * clamps, halt, offsets, units, bumpless mode changes, the start-up hold, and inputs at their
 * extremes. The drive is a small model (drive_model): RUN while enabled (after an optional
 * start-up), IDLE when not, and with `follow` a rotor that turns at the commanded speed. */
#include "h402.h"

/* ---------------------------------------------------------------------------------------- */

static void test_defaults_and_table(void **state)
{
    (void)state;
    start();
    /* Table 30 (bits 6, 5, 3-0; x as 0) */
    assert_int_equal(mc_402_statusword_for(MC_402_NOT_READY), 0x00);
    assert_int_equal(mc_402_statusword_for(MC_402_SWITCH_ON_DISABLED), 0x40);
    assert_int_equal(mc_402_statusword_for(MC_402_READY_TO_SWITCH_ON), 0x21);
    assert_int_equal(mc_402_statusword_for(MC_402_SWITCHED_ON), 0x23);
    assert_int_equal(mc_402_statusword_for(MC_402_OPERATION_ENABLED), 0x27);
    assert_int_equal(mc_402_statusword_for(MC_402_QUICK_STOP_ACTIVE), 0x07);
    assert_int_equal(mc_402_statusword_for(MC_402_FAULT_REACTION_ACTIVE), 0x0F);
    assert_int_equal(mc_402_statusword_for(MC_402_FAULT), 0x08);
    assert_int_equal(mc_402_statusword_for((mc_402_state_t)99), 0x00);
    for (int a = 0; a <= (int)MC_402_FAULT; ++a) {
        for (int b = a + 1; b <= (int)MC_402_FAULT; ++b) {
            assert_string_not_equal(mc_402_state_name((mc_402_state_t)a), mc_402_state_name((mc_402_state_t)b));
        }
    }
    assert_string_equal(mc_402_state_name((mc_402_state_t)99), "?");
    assert_string_equal(mc_402_state_name(MC_402_QUICK_STOP_ACTIVE), "quick stop active");
    /* the object defaults */
    const mc_402_od_t *o = &s.od;
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    assert_int_equal(o->statusword, 0x0240u);
    assert_int_equal(o->quick_stop_option, 2);
    assert_int_equal(o->shutdown_option, 0);
    assert_int_equal(o->disable_op_option, 1);
    assert_int_equal(o->fault_reaction_option, 0);
    assert_int_equal(o->mode, MC_402_MODE_PV);
    assert_int_equal(o->mode_display, MC_402_MODE_PV);
    assert_int_equal(o->velocity_window, 20u);
    assert_int_equal(o->velocity_window_time, 10u);
    assert_int_equal(o->velocity_threshold, 10u);
    assert_int_equal(o->velocity_threshold_time, 10u);
    assert_int_equal(o->max_torque, 1000u);
    assert_int_equal(o->max_motor_speed, 1800u);
    assert_int_equal(o->profile_accel, 1000u);
    assert_int_equal(o->profile_decel, 1000u);
    assert_int_equal(o->quick_stop_decel, 1000u);
    assert_int_equal(o->torque_slope, 10000u);
    assert_int_equal(o->rated_current, 13290u);
    assert_int_equal(o->rated_torque, 29700u);
    assert_int_equal(o->supported_modes, 0x30Cu);   /* bits 2 pv, 3 tq, 8 csv, 9 cst */
    assert_true(mc_402_mode_supported(MC_402_MODE_PV) && mc_402_mode_supported(MC_402_MODE_TQ) &&
                mc_402_mode_supported(MC_402_MODE_CSV) && mc_402_mode_supported(MC_402_MODE_CST));
    assert_false(mc_402_mode_supported(0) || mc_402_mode_supported(1) || mc_402_mode_supported(8) ||
                 mc_402_mode_supported(-1) || mc_402_mode_supported(INT8_MIN));
    /* new motor data: the rated objects follow, the state and the rw objects stay */
    to_enabled();
    s.od.profile_accel = 77u;
    mc_402_cfg_t c2 = CFG;
    c2.rated_torque = 10.0f;
    c2.rated_current = 2.5f;
    c2.accel_rpm_s = 5.0f;
    mc_402_configure(&s, &c2);
    assert_int_equal(s.state, MC_402_OPERATION_ENABLED);
    assert_int_equal(s.od.rated_torque, 10000u);
    assert_int_equal(s.od.rated_current, 2500u);
    assert_int_equal(s.od.profile_accel, 77u);
}

/* Transitions 2, 3, 4 and 3 + 4, the commands' don't-care bits, and what is not a transition. */
static void test_walk(void **state)
{
    (void)state;
    start();
    step_n(1);
    assert_int_equal(sw(), 0x0240);   /* SOD + remote */
    assert_false(cmd.enable);
    assert_int_equal(cw(0x07), 0x0240);   /* switch on, enable operation from SOD: no transition */
    assert_int_equal(cw(0x0F), 0x0240);
    assert_int_equal(cw(0x06), 0x0221);   /* 2 */
    assert_false(cmd.enable);
    assert_int_equal(cw(0x06), 0x0221);   /* held: stays */
    assert_int_equal(cw(0x07), 0x0233);   /* 3: voltage enabled (bit 4) */
    assert_false(cmd.enable);
    assert_int_equal(cw(0x07), 0x0233);
    assert_int_equal(cw(0x0F), 0x0237);   /* 4 */
    assert_true(cmd.enable);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    assert_true(cmd.theta_init == 0.0f);
    assert_int_equal(cw(0x0F), 0x0237);
    assert_int_equal(s.od.statusword & 0x4000u, 0x4000u);   /* the model's drive is in RUN */
    /* 3 + 4 in one command from RTSO */
    assert_int_equal(cw(0x00), 0x0240);
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x0F), 0x0237);
    /* don't-care bits: shutdown x110 with bit 3 and the high bits set; bit 7 set blocks */
    assert_int_equal(cw(0x00), 0x0240);
    assert_int_equal(cw(0x0086), 0x0240);   /* bit 7: a fault reset, not a shutdown */
    assert_int_equal(cw(0xFF7E), 0x0221);   /* shutdown with every don't-care bit set */
    assert_int_equal(cw(0x0D), 0x0240);     /* x x 1 0 1: disable voltage (bit 1 = 0) */
    assert_int_equal(cw(0x0E), 0x0221);     /* 0 1 1 1 0: shutdown */
    assert_int_equal(cw(0x0B), 0x0240);     /* 0 1 0 1 1: quick stop from RTSO (7) */
    /* two controlwords between steps (mc_402_controlword): both transitions, no time passes */
    s.od.controlword = 0x06;
    mc_402_controlword(&s, &tm, &cmd);
    s.od.controlword = 0x07;
    mc_402_controlword(&s, &tm, &cmd);
    assert_int_equal(sw(), 0x0233);
    assert_int_equal(s.state, MC_402_SWITCHED_ON);
    /* bit 4 needs the DC link */
    tm.vdc = 100.0f;
    step_n(1);
    assert_int_equal(sw(), 0x0223);
    tm.vdc = NAN;
    step_n(1);
    assert_int_equal(sw(), 0x0223);
}

/* Disable voltage from every state that has it (7, 9, 10, 12); quick stop from RTSO, SO (7, 10). */
static void test_disable_voltage(void **state)
{
    (void)state;
    start();
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x00), 0x0240);   /* 7 */
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x07), 0x0233);
    assert_int_equal(cw(0x00), 0x0240);   /* 10 */
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x07), 0x0233);
    assert_int_equal(cw(0x02), 0x0240);   /* 10 on quick stop */
    to_enabled();
    s.od.target_velocity = 500;
    step_n(300);
    assert_int_equal(cw(0x00), 0x0240);   /* 9: at once, no ramp */
    assert_false(cmd.enable);
    assert_true(cmd.speed_ref == 0.0f && cmd.torque_ref == 0.0f);
    assert_int_equal(s.od.velocity_demand, 0);
    to_enabled();
    step_n(300);
    assert_int_equal(cw(0x02), 0x0217);   /* QSA */
    assert_true(cmd.enable);
    assert_int_equal(cw(0x00), 0x0240);   /* 12 during the ramp-down */
    assert_false(cmd.enable);
    s.od.quick_stop_option = 5;
    to_enabled();
    assert_int_equal(cw(0x02), 0x0217);
    step_n(50);
    assert_int_equal(sw(), 0x0217);
    assert_int_equal(cw(0x00), 0x0240);   /* 12 from the hold */
    assert_false(cmd.enable);
}

/* Quick stop (11) with each option, 12 at the end, 16 back. */
/* A quick stop with option `opt` from 600 rpm, decelerating on 0x6084 (500 rpm/s; 0x6085 is
 * 2000 rpm/s, so the rate tells which one acts): 100 ms after it, 550 rpm. */
static void quick_stop_on_profile_decel(int16_t opt)
{
    start();
    s.od.profile_decel = 500u;
    s.od.quick_stop_decel = 2000u;
    s.od.quick_stop_option = opt;
    to_enabled();
    s.od.target_velocity = 600;
    step_n(700);
    assert_int_equal(cw(0x02), 0x0217);
    step_n(99);
    assert_true(fabsf(speed_rpm() - 550.0f) < 2.0f);
}

static void test_quick_stop_options(void **state)
{
    (void)state;
    /* 2 (default): ramp down on 0x6085 (not 0x6084), then SOD */
    start();
    s.od.profile_decel = 500u;
    s.od.quick_stop_decel = 2000u;
    to_enabled();
    s.od.target_velocity = 600;
    step_n(700);
    assert_int_equal(s.od.velocity_demand, 600);
    assert_int_equal(cw(0x02), 0x0217);
    assert_true(cmd.enable);
    assert_int_equal(cw(0x0F), 0x0217);   /* enable operation does not return with option 2 */
    step_n(98);                           /* 0.1 s after the quick stop: 200 rpm less */
    assert_true(fabsf(speed_rpm() - 400.0f) < 3.0f);
    assert_int_equal(s.od.statusword & 0x0400u, 0u);   /* not stopped yet */
    step_n(180);                          /* 280 ms: 40 rpm left */
    assert_int_equal(sw(), 0x0217);
    step_n(50);                           /* at 0 and below the threshold for its time */
    assert_int_equal(sw(), 0x0240);
    assert_false(cmd.enable);

    /* 1: the same on 0x6084 */
    quick_stop_on_profile_decel(1);
    step_n(1100);
    assert_int_equal(sw(), 0x0240);

    /* 5: on 0x6084, stays in QSA held at 0 (enabled, stopped: bit 10); enable operation: 16 */
    quick_stop_on_profile_decel(5);
    step_n(1500);
    assert_int_equal(sw(), 0x0217);
    assert_true(cmd.enable);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    assert_int_equal(cw(0x0F), 0x0237);   /* 16 */
    step_n(100);
    assert_true(fabsf(speed_rpm() - 100.0f) < 2.0f);   /* from 0 on 0x6083 */

    /* 6: on 0x6085, and enable operation during the ramp-down returns at once (16) */
    start();
    s.od.profile_decel = 500u;
    s.od.quick_stop_decel = 2000u;
    s.od.quick_stop_option = 6;
    to_enabled();
    s.od.target_velocity = 600;
    step_n(700);
    assert_int_equal(cw(0x02), 0x0217);
    step_n(99);
    assert_true(fabsf(speed_rpm() - 400.0f) < 3.0f);
    assert_int_equal(cw(0x0F), 0x0237);
    step_n(100);
    assert_true(fabsf(speed_rpm() - 500.0f) < 3.0f);   /* on toward the target from 400 */
    assert_int_equal(cw(0x02), 0x0217);
    step_n(400);
    assert_int_equal(sw(), 0x0217);   /* stays */

    /* 0: the drive function off at once */
    start();
    s.od.quick_stop_option = 0;
    to_enabled();
    s.od.target_velocity = 600;
    step_n(700);
    assert_int_equal(cw(0x02), 0x0240);
    assert_false(cmd.enable);

    /* 3, 4 end in SOD, 7 stays; a value outside the profile's acts as 2 */
    static const int16_t opts[] = {3, 4, 7, 8, -1, INT16_MIN, INT16_MAX};
    static const unsigned ends[] = {0x0240, 0x0240, 0x0217, 0x0217, 0x0240, 0x0240, 0x0240};
    for (size_t k = 0; k < sizeof opts / sizeof opts[0]; ++k) {
        start();
        s.od.quick_stop_option = opts[k];
        s.od.profile_decel = 500u;
        s.od.quick_stop_decel = 2000u;
        to_enabled();
        s.od.target_velocity = 600;
        step_n(700);
        assert_int_equal(cw(0x02), 0x0217);
        step_n(99);
        assert_true(fabsf(speed_rpm() - 400.0f) < 3.0f);   /* on 0x6085 */
        step_n(400);
        assert_int_equal(sw(), ends[k]);
    }

    /* a rotor that does not stop: disabled after the ramp's time + 1 s anyway */
    start();
    s.od.quick_stop_decel = 1000u;
    to_enabled();
    s.od.target_velocity = 200;
    step_n(300);
    drv.follow = false;   /* 200 rpm and staying */
    assert_int_equal(cw(0x02), 0x0217);
    step_n(1150);         /* 0.2 s + 1 s is the bound */
    assert_int_equal(sw(), 0x0217);
    step_n(100);
    assert_int_equal(sw(), 0x0240);
    assert_false(cmd.enable);

    /* in a torque mode the quick stop takes speed control from the actual speed */
    start();
    s.od.mode = MC_402_MODE_TQ;
    to_enabled();
    s.od.target_torque = 200;
    step_n(50);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    tm.omega = PP * 300.0f / RPM;   /* 300 rpm */
    step_n(1);
    s.od.quick_stop_decel = 1000u;
    assert_int_equal(cw(0x02), 0x0217);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    assert_true(fabsf(speed_rpm() - 300.0f) < 2.0f);
    assert_true(cmd.torque_ref == 0.0f);
    step_n(100);
    assert_true(fabsf(speed_rpm() - 200.0f) < 3.0f);   /* down on 0x6085 */
    step_n(400);
    assert_int_equal(sw(), 0x0240);
}

/* Disable operation (5) and shutdown (6, 8) with their options. */
static void test_disable_operation_shutdown(void **state)
{
    (void)state;
    /* disable operation, option 1 (default): ramp down on 0x6084 in OE, then SO */
    start();
    s.od.profile_decel = 1000u;
    to_enabled();
    s.od.target_velocity = 300;
    step_n(400);
    assert_int_equal(cw(0x07), 0x0237);
    assert_true(cmd.enable);
    step_n(99);
    assert_true(fabsf(speed_rpm() - 200.0f) < 2.0f);
    assert_int_equal(cw(0x0F), 0x0237);   /* enable operation again: back to the target */
    step_n(99);
    assert_true(fabsf(speed_rpm() - 300.0f) < 2.0f);
    assert_int_equal(cw(0x07), 0x0237);
    step_n(250);
    assert_int_equal(sw(), 0x0237);
    step_n(100);
    assert_int_equal(sw(), 0x0233);   /* 5 once stopped */
    assert_false(cmd.enable);
    assert_int_equal(cw(0x06), 0x0221);   /* 6 */
    /* disable operation, option 0: at once */
    s.od.disable_op_option = 0;
    assert_int_equal(cw(0x0F), 0x0237);
    step_n(400);
    assert_int_equal(cw(0x07), 0x0233);
    assert_false(cmd.enable);
    /* shutdown from OE, option 0 (default): at once (8) */
    assert_int_equal(cw(0x0F), 0x0237);
    step_n(400);
    assert_int_equal(cw(0x06), 0x0221);
    assert_false(cmd.enable);
    /* shutdown, option 1: ramp down first */
    s.od.shutdown_option = 1;
    assert_int_equal(cw(0x0F), 0x0237);
    step_n(400);
    assert_int_equal(cw(0x06), 0x0237);
    assert_true(cmd.enable);
    step_n(400);
    assert_int_equal(sw(), 0x0221);
    assert_false(cmd.enable);
    /* a quick stop during a disable-operation ramp takes over (11) */
    s.od.disable_op_option = 1;
    s.od.quick_stop_decel = 3000u;
    assert_int_equal(cw(0x0F), 0x0237);
    step_n(400);
    assert_int_equal(cw(0x07), 0x0237);
    step_n(10);
    assert_int_equal(cw(0x02), 0x0217);
    step_n(150);
    assert_int_equal(sw(), 0x0240);
}

/* Faults (13, 14) from every state, the reaction with the command kept, the latch and the
 * fault reset's edge (15). */
static void test_faults(void **state)
{
    (void)state;
    start();
    to_enabled();
    s.od.target_velocity = 500;
    step_n(300);
    /* 13: the drive's reaction: FRA, the command as it was */
    const mc_drive_cmd_t before = cmd;
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = MC_FAULT_OVERSPEED;
    step_n(1);
    assert_int_equal(sw(), 0x021F);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_true(cmd.enable);
    assert_int_equal(cmd.mode, before.mode);
    assert_true(cmd.speed_ref == before.speed_ref);
    assert_int_equal(s.od.error_code, 0x8400u);
    s.od.controlword = 0x0000;   /* disable voltage and a fault reset: ignored during the reaction */
    step_n(2);
    s.od.controlword = 0x0080;
    step_n(2);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_true(cmd.enable);
    /* 14: FAULT, disabled, the code; bit 4 stays (nothing opened the "contactor") */
    tm.state = MC_STATE_FAULT;
    step_n(1);
    assert_int_equal(sw(), 0x0218);
    assert_false(cmd.enable);
    assert_int_equal(s.od.error_code, 0x8400u);
    /* latched: the drive forgets (IDLE), Fault stays; bit 7 held since the reaction: no edge */
    tm.state = MC_STATE_IDLE;
    tm.faults = 0u;
    step_n(5);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_int_equal(cw(0x06), 0x0218);   /* no command leaves Fault */
    assert_int_equal(cw(0x0F), 0x0218);
    assert_false(cmd.enable);
    /* 15 on the edge, error code cleared */
    assert_int_equal(cw(0x0080), 0x0240);
    assert_int_equal(s.od.error_code, 0u);
    assert_int_equal(cw(0x0080), 0x0240);   /* a level does nothing more */

    /* 14 from OE without a reaction; the lowest bit's code; reset with a shutdown pattern */
    to_enabled();
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_OVERCURRENT | MC_FAULT_TRACKING;
    step_n(1);
    assert_int_equal(sw(), 0x0218);
    assert_int_equal(s.od.error_code, 0x2310u);
    assert_int_equal(cw(0x0086), 0x0240);   /* bit 7 rises with a shutdown's bits: 15 */
    step_n(3);   /* the drive still shows FAULT for a while: not a new one */
    assert_int_equal(sw(), 0x0240);
    tm.state = MC_STATE_IDLE;

    /* 14 from QSA (option 5 hold) */
    s.od.quick_stop_option = 5;
    to_enabled();
    assert_int_equal(cw(0x02), 0x0217);
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_STALL;
    step_n(1);
    assert_int_equal(sw(), 0x0218);
    assert_int_equal(s.od.error_code, 0x7121u);
    tm.state = MC_STATE_IDLE;
    assert_int_equal(cw(0x00), 0x0218);
    assert_int_equal(cw(0x80), 0x0240);

    /* a drive fault while not enabled: from SOD (no bit 4), RTSO, SO (bit 4) */
    static const uint16_t path[3][2] = {{0x00, 0x00}, {0x06, 0x06}, {0x06, 0x07}};
    static const unsigned want[3] = {0x0208, 0x0208, 0x0218};
    for (int k = 0; k < 3; ++k) {
        assert_int_equal(cw(0x00), 0x0240);
        (void)cw(path[k][0]);
        (void)cw(path[k][1]);
        tm.state = MC_STATE_FAULT;
        tm.faults = k == 0 ? 0u : MC_FAULT_CONFIG;
        step_n(1);
        assert_int_equal(s.state, MC_402_FAULT);
        assert_int_equal(sw(), want[k]);
        assert_int_equal(s.od.error_code, k == 0 ? 0x1000u : 0x6320u);   /* generic without a bit */
        tm.state = MC_STATE_IDLE;
        assert_int_equal(cw(0x00), want[k]);
        assert_int_equal(cw(0x80), 0x0240);
    }

    /* a configuration fault at init: Fault at the first step */
    start();
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_CONFIG;
    step_n(1);
    assert_int_equal(sw(), 0x0208);
    assert_int_equal(s.od.error_code, 0x6320u);
    /* reset while the drive still shows it: SOD; enabling it again: Fault again */
    assert_int_equal(cw(0x80), 0x0240);
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x07), 0x0233);
    assert_int_equal(cw(0x0F), 0x0218);
    assert_false(cmd.enable);

    /* a reaction that ends without the drive showing FAULT: Fault all the same */
    start();
    to_enabled();
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = MC_FAULT_OVERSPEED;
    step_n(3);
    tm.state = MC_STATE_IDLE;
    step_n(1);
    assert_int_equal(sw(), 0x0218);
    assert_int_equal(s.od.error_code, 0x8400u);
}

/* The error code (0x603F) names the fault that put the drive in Fault. With a reaction, the one
 * that started it, not one that came during it: over-speed holds the field weakening (a
 * reaction), an over-current trips meanwhile and the drive ends in FAULT with both bits; the
 * code stays over-speed's, although over-current's bit is the lower one (which 14 without a
 * reaction reports). Without a reaction, always the new fault's, whatever code was shown. */
static void test_fault_code_names_the_first_fault(void **state)
{
    (void)state;
    start();
    to_enabled();
    s.od.target_velocity = 500;
    step_n(50);
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = MC_FAULT_OVERSPEED;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_int_equal(s.od.error_code, 0x8400u);
    tm.faults = MC_FAULT_OVERSPEED | MC_FAULT_OVERCURRENT;   /* during the reaction */
    step_n(2);
    assert_int_equal(s.od.error_code, 0x8400u);
    tm.state = MC_STATE_FAULT;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_int_equal(sw(), 0x0218);
    assert_int_equal(s.od.error_code, 0x8400u);
    /* the same two faults at once without a reaction: the lower bit's code */
    tm.state = MC_STATE_IDLE;
    tm.faults = 0u;
    assert_int_equal(cw(0x00), 0x0218);
    assert_int_equal(cw(0x80), 0x0240);
    to_enabled();
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_OVERSPEED | MC_FAULT_OVERCURRENT;
    step_n(1);
    assert_int_equal(s.od.error_code, 0x2310u);
    /* a state word corrupted in Fault starts over (Not ready, Switch on disabled) with the last
     * error's code still shown (0x603F: the last error); the next fault, without a reaction,
     * reports its own code, not that stale one */
    s.state = (mc_402_state_t)99;
    tm.state = MC_STATE_IDLE;
    tm.faults = 0u;
    assert_int_equal(cw(0x00), 0x0240);
    assert_int_equal(s.od.error_code, 0x2310u);
    to_enabled();
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_STALL;
    step_n(1);
    assert_int_equal(sw(), 0x0218);
    assert_int_equal(s.od.error_code, 0x7121u);
}

/* pv: start-up hold, ramp rates, units, velocity actual, target reached, clamp, halt. */
static void test_profile_velocity(void **state)
{
    (void)state;
    start();
    drv.startup = 40;
    s.od.target_velocity = 1000;
    to_enabled();
    step_n(38);   /* still starting: the ramp holds at 0, bit 15, not bit 14 */
    assert_true(tm.state == MC_STATE_OFFSET_CAL || tm.state == MC_STATE_INIT_POS);
    assert_true(cmd.enable);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.velocity_demand, 0);
    assert_int_equal(s.od.statusword & 0xC000u, 0x8000u);
    step_n(2);
    assert_int_equal(tm.state, MC_STATE_RUN);
    step_n(1);   /* RUN entry: from 0 */
    assert_int_equal(s.od.statusword & 0xC000u, 0x4000u);
    assert_true(s.od.velocity_demand >= 0 && s.od.velocity_demand <= 1);
    step_n(500);   /* 0x6083 = 1000 rpm/s */
    assert_true(abs(s.od.velocity_demand - 501) <= 1);
    assert_int_equal(s.od.statusword & 0x0400u, 0u);   /* not reached while ramping */
    drv.follow = false;
    tm.omega = PP * 1000.0f / RPM;   /* a rotor at the target before the ramp: not reached either */
    step_n(20);
    assert_int_equal(s.od.statusword & 0x0400u, 0u);
    drv.follow = true;
    assert_int_equal(s.od.statusword & 0x1000u, 0u);   /* speed is not 0 */
    step_n(580);
    assert_int_equal(s.od.velocity_demand, 1000);
    assert_true(fabsf(cmd.speed_ref - 104.7198f) < 1e-3f);   /* rad/s mechanical */
    assert_int_equal(s.od.velocity_actual, 1000);   /* omega = 5 * 104.72 rad/s el */
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    /* velocity actual: mechanical rpm from electrical rad/s with 5 pole pairs, rounded */
    drv.follow = false;
    tm.omega = -PP * 1234.4f / RPM;
    step_n(1);
    assert_int_equal(s.od.velocity_actual, -1234);
    tm.omega = PP * 99.6f / RPM;
    step_n(1);
    assert_int_equal(s.od.velocity_actual, 100);
    /* target reached needs the window (20 rpm) for its time (10 ms) */
    tm.omega = PP * 1030.0f / RPM;
    step_n(20);
    assert_int_equal(s.od.statusword & 0x0400u, 0u);
    tm.omega = PP * 1015.0f / RPM;
    step_n(5);
    assert_int_equal(s.od.statusword & 0x0400u, 0u);
    step_n(10);
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    drv.follow = true;
    /* decelerating on 0x6084 */
    s.od.profile_decel = 4000u;
    s.od.target_velocity = 600;
    step_n(50);
    assert_true(abs(s.od.velocity_demand - 800) <= 1);
    step_n(100);
    /* through zero: 0x6084 down to 0, then 0x6083 up the other way */
    s.od.target_velocity = -200;
    step_n(150);
    assert_true(abs(s.od.velocity_demand - 0) <= 1);
    step_n(100);
    assert_true(abs(s.od.velocity_demand + 100) <= 1);
    /* clamp by 0x6080: bit 11, both ways */
    s.od.target_velocity = 5000;
    step_n(1);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    step_n(2500);
    assert_int_equal(s.od.velocity_demand, 1800);
    assert_int_equal(s.od.statusword & 0x0C00u, 0x0C00u);   /* reached the clamped target */
    s.od.target_velocity = 1800;
    step_n(1);
    assert_int_equal(s.od.statusword & 0x0800u, 0u);   /* at the limit is not beyond it */
    s.od.target_velocity = -5000;
    s.od.profile_decel = 100000u;
    s.od.profile_accel = 100000u;
    step_n(100);
    assert_int_equal(s.od.velocity_demand, -1800);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    /* the drive at its voltage limit: bit 11 too */
    s.od.target_velocity = 100;
    step_n(100);
    assert_int_equal(s.od.statusword & 0x0800u, 0u);
    tm.u_limited = true;
    step_n(1);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    tm.u_limited = false;
    /* halt: decelerate on 0x6084 and hold at 0, enabled; stopped: bits 10 and 12 */
    s.od.profile_accel = 1000u;
    s.od.profile_decel = 3000u;
    s.od.target_velocity = 1500;
    step_n(1600);
    assert_int_equal(s.od.velocity_demand, 1500);
    s.od.controlword = 0x010F;
    step_n(100);
    assert_true(abs(s.od.velocity_demand - 1200) <= 1);
    assert_int_equal(s.od.statusword & 0x1400u, 0u);
    step_n(450);
    assert_int_equal(s.od.velocity_demand, 0);
    assert_true(cmd.enable);
    assert_int_equal(sw(), 0x0237);
    assert_int_equal(s.od.statusword & 0x1400u, 0x1400u);
    /* halt released: on 0x6083 from 0 */
    s.od.controlword = 0x000F;
    step_n(100);
    assert_true(abs(s.od.velocity_demand - 100) <= 1);
}

/* csv: target + offset, clamped, no ramp; bit 12 = the drive follows the command. */
static void test_cyclic_velocity(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_CSV;
    to_enabled();
    assert_int_equal(s.od.mode_display, MC_402_MODE_CSV);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    s.od.target_velocity = 200;
    s.od.velocity_offset = 20;
    step_n(1);
    assert_true(fabsf(speed_rpm() - 220.0f) < 0.01f);
    assert_int_equal(s.od.velocity_demand, 220);
    assert_int_equal(s.od.statusword & 0x1000u, 0x1000u);
    /* target reached after the window time */
    s.od.target_velocity = 700;
    step_n(5);
    assert_int_equal(s.od.statusword & 0x0400u, 0u);
    step_n(10);
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    /* clamped */
    s.od.target_velocity = 1790;
    step_n(1);
    assert_int_equal(s.od.velocity_demand, 1800);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    s.od.target_velocity = -1000;
    s.od.velocity_offset = -1000;
    step_n(1);
    assert_int_equal(s.od.velocity_demand, -1800);
    /* halt is the master's business in csv: ignored */
    s.od.target_velocity = 300;
    s.od.velocity_offset = 0;
    s.od.controlword = 0x010F;
    step_n(1);
    assert_int_equal(s.od.velocity_demand, 300);
    /* not following while the drive is not in RUN */
    tm.state = MC_STATE_INIT_POS;
    drv.startup = 10;
    drv.left = 10;
    step_n(1);
    assert_int_equal(s.od.statusword & 0xD000u, 0x8000u);
    assert_int_equal(s.od.velocity_demand, 0);
}

/* tq and cst: slope, clamp, halt, units, offset; the actual torque and current. */
static void test_torque_modes(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_TQ;
    to_enabled();
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_int_equal(s.od.mode_display, MC_402_MODE_TQ);
    s.od.target_torque = 500;
    s.od.torque_slope = 1000u;   /* per-mille/s */
    step_n(250);
    assert_true(abs(s.od.torque_demand - 250) <= 1);
    assert_int_equal(s.od.statusword & 0x1400u, 0u);   /* not reached; bit 12 reserved in tq */
    step_n(300);
    assert_int_equal(s.od.torque_demand, 500);
    assert_true(fabsf(cmd.torque_ref - 14.85f) < 1e-3f);   /* half the rated torque */
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.statusword & 0x1400u, 0x0400u);
    assert_int_equal(s.od.velocity_demand, 0);
    /* down and negative on the same slope */
    s.od.target_torque = -100;
    step_n(300);
    assert_true(abs(s.od.torque_demand - 200) <= 1);
    step_n(400);
    assert_int_equal(s.od.torque_demand, -100);
    /* clamp by 0x6072: bit 11 */
    s.od.max_torque = 300u;
    s.od.target_torque = 900;
    step_n(700);
    assert_int_equal(s.od.torque_demand, 300);
    assert_int_equal(s.od.statusword & 0x0C00u, 0x0C00u);
    /* halt: the torque ramps to 0 on the slope */
    s.od.controlword = 0x010F;
    step_n(100);
    assert_true(abs(s.od.torque_demand - 200) <= 1);
    step_n(250);
    assert_int_equal(s.od.torque_demand, 0);
    assert_true(cmd.enable);
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    s.od.controlword = 0x000F;
    /* cst: target + offset, no ramp, clamped */
    s.od.max_torque = 1000u;
    s.od.mode = MC_402_MODE_CST;
    s.od.target_torque = 100;
    s.od.torque_offset = 50;
    step_n(1);
    assert_int_equal(s.od.mode_display, MC_402_MODE_CST);
    assert_true(fabsf(cmd.torque_ref - 0.15f * 29.7f) < 1e-3f);
    assert_int_equal(s.od.torque_demand, 150);
    assert_int_equal(s.od.statusword & 0x1C00u, 0x1400u);   /* follows the command, reached */
    s.od.target_torque = 990;
    step_n(1);
    assert_int_equal(s.od.torque_demand, 1000);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    s.od.target_torque = -2000;
    step_n(1);
    assert_int_equal(s.od.torque_demand, -1000);
    /* torque actual from i_dq by (2.9), current actual |i_dq| signed by i_q, DC link in mV */
    tm.i_dq.d = -2.0f;
    tm.i_dq.q = 6.0f;
    tm.vdc = 312.5f;
    step_n(1);
    const float t = 1.5f * 5.0f * (0.343f * 6.0f + (10.5e-3f - 12.9e-3f) * -2.0f * 6.0f);
    assert_int_equal(s.od.torque_actual, (int16_t)lrintf(t / 29.7f * 1000.0f));
    assert_int_equal(s.od.current_actual, (int16_t)lrintf(sqrtf(40.0f) / 13.29f * 1000.0f));
    assert_int_equal(s.od.dc_link_voltage, 312500u);
    tm.i_dq.q = -6.0f;
    step_n(1);
    assert_int_equal(s.od.current_actual, -(int16_t)lrintf(sqrtf(40.0f) / 13.29f * 1000.0f));
    assert_true(s.od.torque_actual < 0);
}

/* Mode changes while enabled are bumpless; an unsupported mode keeps the one in force. */
static void test_mode_change(void **state)
{
    (void)state;
    start();
    to_enabled();
    s.od.target_velocity = 1000;
    step_n(1100);
    assert_int_equal(s.od.velocity_demand, 1000);
    /* pv -> tq: from the torque the speed loop asks for (5.94 N m = 200 per-mille) */
    tm.torque_ref = 5.94f;
    step_n(1);
    assert_int_equal(s.od.torque_demand, 200);   /* the speed loop's torque in speed control */
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 600;
    s.od.torque_slope = 1000u;
    step_n(1);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_true(fabsf(cmd.torque_ref - 5.94f) < 0.05f);   /* not 0, not the target */
    step_n(100);
    assert_true(abs(s.od.torque_demand - 301) <= 1);
    /* tq -> pv: from the velocity actual (the rotor at 700 rpm) */
    drv.follow = false;
    tm.omega = PP * 700.0f / RPM;
    step_n(1);
    s.od.mode = MC_402_MODE_PV;
    drv.follow = true;
    step_n(1);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    assert_true(fabsf(speed_rpm() - 701.0f) < 1.5f);
    step_n(100);
    assert_true(fabsf(speed_rpm() - 801.0f) < 1.5f);
    /* pv -> csv -> pv: csv takes its target at once, pv continues from the csv demand */
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 400;
    step_n(1);
    assert_true(fabsf(speed_rpm() - 400.0f) < 0.01f);
    s.od.mode = MC_402_MODE_PV;
    s.od.target_velocity = 1000;
    step_n(1);
    assert_true(fabsf(speed_rpm() - 401.0f) < 0.01f);
    /* tq -> cst continues nothing (cst has no ramp), cst -> tq ramps from the cst demand */
    s.od.mode = MC_402_MODE_CST;
    s.od.target_torque = 100;
    step_n(1);
    assert_int_equal(s.od.torque_demand, 100);
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 500;
    step_n(1);
    assert_int_equal(s.od.torque_demand, 101);
    /* an unsupported value (written past the dictionary) keeps the mode in force */
    s.od.mode = 0;
    step_n(1);
    assert_int_equal(s.od.mode_display, MC_402_MODE_TQ);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_int_equal(s.od.torque_demand, 102);
    s.od.mode = -128;
    step_n(1);
    assert_int_equal(s.od.mode_display, MC_402_MODE_TQ);
    /* a mode of 0 from the start: pv, the init default, stays in force */
    start();
    s.od.mode = 0;
    to_enabled();
    assert_int_equal(s.od.mode_display, MC_402_MODE_PV);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
}

/* A flying start (or a recovery): the ramp starts from the caught speed, not from 0. */
static void test_run_entry(void **state)
{
    (void)state;
    start();
    drv.startup = 20;
    s.od.target_velocity = 1000;
    drv.follow = false;
    tm.omega = PP * 600.0f / RPM;   /* turning at 600 rpm while the catch runs */
    to_enabled();
    step_n(19);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.statusword & 0xC000u, 0x8000u);
    step_n(3);
    assert_int_equal(s.od.statusword & 0xC000u, 0x4000u);
    assert_true(speed_rpm() > 598.0f && speed_rpm() < 604.0f);
    /* a recovery (RUN -> INIT_POS -> RUN) does the same */
    step_n(100);
    tm.state = MC_STATE_INIT_POS;
    tm.omega = PP * 650.0f / RPM;
    mc_402_step(&s, &tm, &cmd);
    mc_402_step(&s, &tm, &cmd);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.statusword & 0xC000u, 0x8000u);
    tm.state = MC_STATE_RUN;
    mc_402_step(&s, &tm, &cmd);
    assert_true(speed_rpm() > 649.0f && speed_rpm() < 653.0f);
    /* bit 15 only while this block enables the drive (not on a stale INIT_POS after a disable) */
    s.od.controlword = 0x00;
    mc_402_step(&s, &tm, &cmd);
    tm.state = MC_STATE_INIT_POS;
    mc_402_step(&s, &tm, &cmd);
    assert_false(cmd.enable);
    assert_int_equal(s.od.statusword & 0xC000u, 0u);
    /* below the threshold: from 0 */
    start();
    drv.startup = 20;
    drv.follow = false;
    s.od.target_velocity = 1000;
    tm.omega = PP * 6.0f / RPM;
    to_enabled();
    step_n(22);
    assert_true(speed_rpm() >= 0.0f && speed_rpm() < 3.5f);
}

/* Inputs at their extremes: nothing overflows, everything stays finite and in range. */
static void test_extremes(void **state)
{
    (void)state;
    static const int8_t modes[4] = {MC_402_MODE_PV, MC_402_MODE_CSV, MC_402_MODE_TQ, MC_402_MODE_CST};
    start();
    to_enabled();
    s.od.target_velocity = INT32_MIN;
    s.od.velocity_offset = INT32_MIN;
    s.od.profile_accel = UINT32_MAX;
    s.od.profile_decel = 0u;
    s.od.quick_stop_decel = 0u;
    s.od.torque_slope = UINT32_MAX;
    s.od.velocity_window = UINT16_MAX;
    s.od.velocity_window_time = UINT16_MAX;
    s.od.velocity_threshold_time = UINT16_MAX;
    drv.follow = false;
    tm.omega = NAN;
    tm.i_dq.d = INFINITY;
    tm.i_dq.q = -INFINITY;
    tm.vdc = NAN;
    tm.torque_ref = NAN;
    for (int m = 0; m < 4; ++m) {
        s.od.mode = modes[m];
        s.od.target_torque = INT16_MIN;
        s.od.torque_offset = INT16_MIN;
        step_n(3);
        assert_true(isfinite(cmd.speed_ref) && isfinite(cmd.torque_ref));
        assert_true(fabsf(speed_rpm()) <= 1800.5f);
        assert_true(fabsf(cmd.torque_ref) <= 29.71f);
        assert_int_equal(s.od.velocity_actual, 0);
        assert_int_equal(s.od.torque_actual, 0);
        assert_int_equal(s.od.current_actual, 0);
        assert_int_equal(s.od.dc_link_voltage, 0u);
        assert_int_equal(s.od.torque_demand, m < 2 ? 0 : -1000);
        assert_int_equal(s.state, MC_402_OPERATION_ENABLED);
    }
    s.od.max_motor_speed = UINT32_MAX;
    s.od.max_torque = UINT16_MAX;
    s.od.mode = MC_402_MODE_CST;
    step_n(1);
    assert_int_equal(s.od.torque_demand, INT16_MIN);   /* 2 * INT16_MIN, saturated */
    assert_true(isfinite(cmd.torque_ref));
    s.od.mode = MC_402_MODE_CSV;
    step_n(1);
    assert_int_equal(s.od.velocity_demand, INT32_MIN);   /* 2 * INT32_MIN, saturated */
    assert_true(isfinite(cmd.speed_ref));
    s.od.target_velocity = INT32_MAX;
    s.od.velocity_offset = INT32_MAX;
    step_n(1);
    assert_int_equal(s.od.velocity_demand, INT32_MAX);
    /* huge telemetry saturates */
    tm.omega = 1e30f;
    tm.i_dq.q = 1e30f;
    tm.i_dq.d = 0.0f;
    tm.vdc = 1e30f;
    tm.torque_ref = 1e30f;
    step_n(1);
    assert_int_equal(s.od.velocity_actual, INT32_MAX);
    assert_int_equal(s.od.torque_actual, INT16_MAX);
    assert_int_equal(s.od.current_actual, INT16_MAX);
    assert_int_equal(s.od.dc_link_voltage, UINT32_MAX);
    assert_int_equal(s.od.torque_demand, INT16_MAX);
    tm.omega = -1e30f;
    tm.i_dq.q = -1e30f;
    tm.vdc = -5.0f;
    step_n(1);
    assert_int_equal(s.od.velocity_actual, INT32_MIN);
    assert_int_equal(s.od.torque_actual, INT16_MIN);
    assert_int_equal(s.od.dc_link_voltage, 0u);
    /* a quick stop from there (0 decelerations, a huge speed): bounded, still ends */
    s.od.mode = MC_402_MODE_TQ;
    s.od.quick_stop_option = INT16_MIN;
    assert_int_equal(cw(0x02), 0x0207);   /* QSA; the DC link is "negative": no bit 4 */
    assert_true(isfinite(cmd.speed_ref));
    assert_true(fabsf(speed_rpm()) <= 4.3e9f);
    /* every controlword, with the drive's state and the options anything: the state stays one
     * of the enum's, the command finite */
    for (uint32_t w = 0; w < 0x10000u; w += 7u) {
        s.od.controlword = (uint16_t)w;
        s.od.quick_stop_option = (int16_t)(w * 2654435761u >> 16);
        s.od.disable_op_option = (int16_t)(w * 40503u);
        s.od.mode = (int8_t)(w >> 3);
        tm.state = (mc_state_t)(w % 7u);
        tm.faults = w * 0x9E3779B9u;
        mc_402_step(&s, &tm, &cmd);
        assert_true(s.state >= MC_402_NOT_READY && s.state <= MC_402_FAULT);
        assert_true(isfinite(cmd.speed_ref) && isfinite(cmd.torque_ref));
    }
    /* a corrupted state starts over; a configuration of nonsense does not break anything */
    start();
    s.state = (mc_402_state_t)1234;
    step_n(1);
    assert_int_equal(sw(), 0x0240);
    mc_402_cfg_t bad = {.dt = NAN, .pole_pairs = 0, .rated_torque = NAN, .rated_current = -1.0f, .psi_pm = INFINITY,
                        .ld = NAN, .lq = 1e38f, .vdc_on = NAN, .max_speed_rpm = 1e30f, .accel_rpm_s = -5.0f};
    mc_402_init(&s, &bad);
    assert_int_equal(s.od.max_motor_speed, UINT32_MAX);
    assert_int_equal(s.od.profile_accel, 0u);
    assert_int_equal(s.od.rated_torque, 0u);
    assert_int_equal(s.od.rated_current, 0u);
    tm = (mc_drive_telem_t){.state = MC_STATE_IDLE, .omega = 100.0f, .i_dq = {.d = 1.0f, .q = 1.0f}, .vdc = 300.0f};
    drv.follow = false;
    to_enabled();
    s.od.target_velocity = 100;
    step_n(10);
    assert_true(isfinite(cmd.speed_ref) && isfinite(cmd.torque_ref));
    assert_int_equal(s.od.velocity_actual, 955);   /* 1 pole pair taken */
    bad.dt = INFINITY;
    mc_402_configure(&s, &bad);
    step_n(10);
    assert_true(isfinite(cmd.speed_ref));
}

/* A pole pair count that is not one (0, negative, 1000 or more) reads as 1: the actual values
 * keep the rotor's direction. A negative count taken as is would invert 0x606C and 0x6077, and
 * a master closing its loop on them would drive the motor away from its target. */
static void test_pole_pairs_out_of_range(void **state)
{
    (void)state;
    static const int bad[] = {0, -1, -5, INT_MIN, 1000, INT_MAX};
    const int32_t v1 = (int32_t)lrintf(100.0f * RPM);   /* 100 rad/s el with 1 pole pair: 955 rpm */
    const int16_t t1 = (int16_t)lrintf(1.5f * 0.343f * 6.0f / 29.7f * 1000.0f);   /* (2.9), i_d = 0 */
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        start();
        mc_402_cfg_t c = CFG;
        c.pole_pairs = bad[k];
        mc_402_init(&s, &c);
        tm.omega = 100.0f;
        tm.i_dq.q = 6.0f;
        step_n(1);
        assert_int_equal(s.od.velocity_actual, v1);
        assert_int_equal(s.od.torque_actual, t1);
        tm.omega = -100.0f;
        step_n(1);
        assert_int_equal(s.od.velocity_actual, -v1);
    }
    /* a count in 1..999 is taken as it is */
    static const int good[] = {1, 2, 5, 998, 999};
    for (size_t k = 0; k < sizeof good / sizeof good[0]; ++k) {
        start();
        mc_402_cfg_t c = CFG;
        c.pole_pairs = good[k];
        mc_402_init(&s, &c);
        tm.omega = 100.0f * (float)good[k];
        step_n(1);
        assert_int_equal(s.od.velocity_actual, v1);
    }
}

/* Disable voltage (9) or a quick stop with option 0 during a disable-operation ramp (5 with
 * 0x605C = 1) ends that ramp for good. Left running, it would complete into Switched on once the
 * coasting rotor stops (closing the "main contactor" and showing 0x0233 without a command). A
 * drive enabled again while the rotor still turns picks it up and goes on to its target. */
static void test_ramp_down_cut_short(void **state)
{
    (void)state;
    for (int how = 0; how < 4; ++how) {
        start();
        s.od.profile_decel = 1000u;
        s.od.quick_stop_option = 0;
        to_enabled();
        s.od.target_velocity = 300;
        step_n(400);
        assert_int_equal(cw(0x07), 0x0237);   /* 5: ramping down in OE */
        step_n(50);
        assert_true(speed_rpm() > 200.0f);
        assert_int_equal(cw((how & 1) == 0 ? 0x00 : 0x02), 0x0240);   /* 9, or 11 with option 0 */
        assert_false(cmd.enable);
        step_n(20);
        if (how < 2) {
            /* the rotor coasts to a stop; Switch on disabled throughout, past the ramp's bound */
            tm.omega = 0.0f;
            for (int k = 0; k < 1500; ++k) {
                step_n(1);
                assert_int_equal(sw(), 0x0240);
                assert_false(cmd.enable);
            }
            to_enabled();
            step_n(100);
            assert_true(fabsf(speed_rpm() - 100.0f) < 2.0f);   /* up from 0 toward 300 */
        } else {
            /* enabled again at once, the rotor still at 250 rpm: on from there to the target
             * (a flying restart, test_run_entry) */
            drv.follow = false;
            tm.omega = PP * 250.0f / RPM;
            to_enabled();
            step_n(2);
            drv.follow = true;
            assert_true(fabsf(speed_rpm() - 251.0f) < 1.5f);
            step_n(100);
            assert_true(fabsf(speed_rpm() - 300.0f) < 1.0f);
            step_n(1500);
            assert_int_equal(sw(), 0x0237);
            assert_true(fabsf(speed_rpm() - 300.0f) < 1.0f);
        }
        assert_int_equal(sw(), 0x0237);
    }
}

/* 0x605C and 0x605B: 0 stops at once, any other value (1, and the manufacturer range below 0 a
 * caller may set on this block directly) ramps down on 0x6084 first, in Operation enabled. */
static void test_stop_option_codes_other_than_0(void **state)
{
    (void)state;
    static const int16_t opts[] = {1, -1, INT16_MIN};
    for (size_t k = 0; k < sizeof opts / sizeof opts[0]; ++k) {
        for (int shutdown = 0; shutdown < 2; ++shutdown) {
            start();
            s.od.profile_decel = 1000u;
            if (shutdown) {
                s.od.shutdown_option = opts[k];
            } else {
                s.od.disable_op_option = opts[k];
            }
            to_enabled();
            s.od.target_velocity = 300;
            step_n(400);
            assert_int_equal(cw(shutdown ? 0x06 : 0x07), 0x0237);   /* still OE, ramping */
            assert_true(cmd.enable);
            step_n(99);
            assert_true(fabsf(speed_rpm() - 200.0f) < 2.0f);
            step_n(350);
            assert_int_equal(sw(), shutdown ? 0x0221 : 0x0233);   /* 8 / 5 once stopped */
            assert_false(cmd.enable);
        }
    }
}

/* A shutdown or disable-operation ramp that cannot end by standstill (a load holds the rotor at
 * 300 rpm) still ends by its time limit, (speed / 0x6084) + 1 s, although the master repeats the
 * command every cycle, as masters do with a cyclic controlword: the repeat does not restart it. */
static void test_stop_ramp_time_limit_with_the_command_repeated(void **state)
{
    (void)state;
    for (int shutdown = 0; shutdown < 2; ++shutdown) {
        start();
        s.od.profile_decel = 1000u;
        s.od.shutdown_option = 1;
        s.od.disable_op_option = 1;
        to_enabled();
        s.od.target_velocity = 300;
        step_n(400);
        set_rpm(300.0f);   /* held there, whatever the command */
        const uint16_t c = shutdown ? 0x06 : 0x07;
        const int limit = (int)((300.0f / 1000.0f + 1.0f) / CFG.dt);
        int k = 0;
        while (k < 2 * limit && cw(c) == 0x0237) {
            ++k;
        }
        assert_int_equal(sw(), shutdown ? 0x0221 : 0x0233);
        assert_true(k >= limit - 2 && k <= limit + 2);
    }
}

/* Disable operation (0x605C = 0) and enable operation again between two steps
 * (mc_402_controlword, the drive's telemetry still showing RUN): the drive was disabled, so the
 * enable restarts it from zero torque on 0x6087, not with the torque it had before. */
static void test_reenable_in_one_batch_restarts_the_ramp(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_TQ;
    s.od.disable_op_option = 0;
    s.od.torque_slope = 1000u;
    to_enabled();
    s.od.target_torque = 500;
    step_n(600);
    assert_int_equal(s.od.torque_demand, 500);
    assert_int_equal(tm.state, MC_STATE_RUN);
    s.od.controlword = 0x07;
    mc_402_controlword(&s, &tm, &cmd);
    assert_int_equal(sw(), 0x0233);
    assert_false(cmd.enable);
    s.od.controlword = 0x0F;
    mc_402_controlword(&s, &tm, &cmd);
    assert_int_equal(sw(), 0x0237);
    assert_true(cmd.enable);
    assert_true(cmd.torque_ref == 0.0f);
    assert_int_equal(s.od.torque_demand, 0);
    step_n(100);
    assert_true(abs(s.od.torque_demand - 100) <= 1);   /* on the slope from 0 */
}

/* 0x6074 torque demand reads 0 while the drive is not enabled (disable voltage, Fault), in a
 * torque mode (its ramp) and in a speed mode (the speed loop's torque) alike. */
static void test_torque_demand_0_when_disabled(void **state)
{
    (void)state;
    for (int m = 0; m < 2; ++m) {
        start();
        s.od.mode = m == 0 ? MC_402_MODE_TQ : MC_402_MODE_PV;
        to_enabled();
        s.od.target_torque = 500;
        s.od.target_velocity = 500;
        tm.torque_ref = 5.94f;   /* the speed loop asks for 200 per-mille */
        step_n(200);
        assert_true(s.od.torque_demand >= 200);
        assert_int_equal(cw(0x00), 0x0240);   /* 9 */
        assert_int_equal(s.od.torque_demand, 0);
        step_n(5);
        assert_int_equal(s.od.torque_demand, 0);
        to_enabled();
        step_n(200);
        assert_true(s.od.torque_demand >= 200);
        tm.state = MC_STATE_FAULT;   /* 14 */
        tm.faults = MC_FAULT_OVERCURRENT;
        step_n(1);
        assert_int_equal(sw(), 0x0218);
        assert_int_equal(s.od.torque_demand, 0);
    }
}

/* Target reached (bit 10) is never set while the drive starts up (offset calibration, initial
 * position): the drive does not control the motor yet, even with a target of 0 and the rotor at
 * rest. Once in RUN, it is set after the window time (pv, csv) or at once (tq, cst). */
static void test_not_reached_during_startup(void **state)
{
    (void)state;
    static const int8_t modes[4] = {MC_402_MODE_PV, MC_402_MODE_CSV, MC_402_MODE_TQ, MC_402_MODE_CST};
    for (int m = 0; m < 4; ++m) {
        start();
        s.od.mode = modes[m];
        drv.startup = 40;
        to_enabled();
        for (int k = 0; k < 38; ++k) {
            step_n(1);
            assert_true(cmd.enable);
            assert_int_equal(s.od.statusword & 0xC400u, 0x8000u);   /* starting, not reached */
        }
        step_n(3);
        assert_int_equal(s.od.statusword & 0xC000u, 0x4000u);   /* RUN */
        step_n(15);
        assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    }
}

/* Halt in pv: target reached means stopped, |velocity actual| <= 0x606F for 0x6070, not the
 * velocity window around the (zero) target: a rotor held at 50 rpm by its load is not stopped,
 * although 0x606D (here 100 rpm) would take it as at 0. */
static void test_pv_halt_reached_is_stopped(void **state)
{
    (void)state;
    start();
    s.od.velocity_window = 100u;
    s.od.profile_decel = 3000u;
    to_enabled();
    s.od.target_velocity = 300;
    step_n(400);
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    s.od.controlword = 0x010F;
    step_n(110);   /* the ramp is at 0 */
    assert_int_equal(s.od.velocity_demand, 0);
    drv.follow = false;
    tm.omega = PP * 50.0f / RPM;
    step_n(100);
    assert_int_equal(s.od.statusword & 0x1400u, 0u);   /* not stopped: not reached, speed not 0 */
    tm.omega = PP * 5.0f / RPM;
    step_n(5);
    assert_int_equal(s.od.statusword & 0x1400u, 0u);   /* below 0x606F, not yet for 0x6070 */
    step_n(10);
    assert_int_equal(s.od.statusword & 0x1400u, 0x1400u);
    assert_int_equal(sw(), 0x0237);
    assert_true(cmd.enable);
}

/* Fault is latched (§6.3: only the fault reset leaves it): a fault the drive reports meanwhile,
 * a new FAULT after it had forgotten the first or a fault reaction, changes neither the state
 * nor 0x603F (the fault that put the drive in Fault), and the command stays off. */
static void test_fault_latched_keeps_its_code(void **state)
{
    (void)state;
    start();
    to_enabled();
    s.od.target_velocity = 300;
    step_n(100);
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_OVERCURRENT;
    step_n(1);
    assert_int_equal(sw(), 0x0218);
    assert_int_equal(s.od.error_code, 0x2310u);
    tm.state = MC_STATE_IDLE;   /* the drive forgets once disabled */
    tm.faults = 0u;
    step_n(5);
    static const mc_state_t next[2] = {MC_STATE_FAULT, MC_STATE_FAULT_REACTION};
    for (int k = 0; k < 2; ++k) {
        tm.state = next[k];
        tm.faults = MC_FAULT_STALL;
        for (int n = 0; n < 5; ++n) {
            step_n(1);
            assert_int_equal(sw(), 0x0218);
            assert_int_equal(s.od.error_code, 0x2310u);
            assert_false(cmd.enable);
        }
        tm.state = MC_STATE_IDLE;
        tm.faults = 0u;
        step_n(2);
    }
    assert_int_equal(cw(0x80), 0x0240);   /* 15 */
    assert_int_equal(s.od.error_code, 0u);
}

/* While the drive starts up (offset calibration, initial position) the ramps hold at 0 in every
 * mode: the command and 0x606B / 0x6074 carry no velocity or torque before the drive controls
 * the motor, whatever the targets. */
static void test_startup_holds_the_demands(void **state)
{
    (void)state;
    static const int8_t modes[4] = {MC_402_MODE_PV, MC_402_MODE_CSV, MC_402_MODE_TQ, MC_402_MODE_CST};
    for (int m = 0; m < 4; ++m) {
        start();
        s.od.mode = modes[m];
        s.od.target_velocity = 500;
        s.od.target_torque = 300;
        s.od.torque_offset = 50;
        s.od.velocity_offset = 50;
        drv.startup = 40;
        to_enabled();
        for (int k = 0; k < 38; ++k) {
            step_n(1);
            assert_true(cmd.enable);
            assert_true(cmd.speed_ref == 0.0f && cmd.torque_ref == 0.0f);
            assert_int_equal(s.od.velocity_demand, 0);
            assert_int_equal(s.od.torque_demand, 0);
        }
        step_n(20);
        assert_int_equal(s.od.statusword & 0xC000u, 0x4000u);
        assert_true(m < 2 ? speed_rpm() > 1.0f : cmd.torque_ref > 0.5f);
    }
}

/* Target reached (bit 10) describes a drive pursuing its target: disable operation at once
 * (0x605C = 0) leaves Switched on without it in that very step, the drive's telemetry still
 * showing RUN and the rotor still at the target. */
static void test_not_reached_when_switched_on(void **state)
{
    (void)state;
    static const int8_t modes[4] = {MC_402_MODE_PV, MC_402_MODE_CSV, MC_402_MODE_TQ, MC_402_MODE_CST};
    for (int m = 0; m < 4; ++m) {
        start();
        s.od.mode = modes[m];
        s.od.disable_op_option = 0;
        s.od.target_velocity = 300;
        to_enabled();
        step_n(600);
        assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
        assert_int_equal(tm.state, MC_STATE_RUN);
        assert_int_equal(cw(0x07), 0x0233);
        assert_int_equal(s.od.statusword & 0x0400u, 0u);
    }
}

/* Halt is for pv and tq only: in csv and cst the master owns the trajectory, so bit 10 stays
 * what it is without halt (at the target: set), not "stopped". */
static void test_cyclic_modes_ignore_halt_in_bit10(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_CSV;
    to_enabled();
    s.od.target_velocity = 300;
    step_n(50);
    s.od.controlword = 0x010F;
    step_n(50);
    assert_int_equal(s.od.velocity_demand, 300);
    assert_int_equal(s.od.statusword & 0x1400u, 0x1400u);   /* reached; follows the command */
    s.od.mode = MC_402_MODE_CST;
    s.od.target_torque = 200;
    step_n(1);
    assert_int_equal(s.od.torque_demand, 200);
    assert_int_equal(s.od.statusword & 0x1400u, 0x1400u);
}

/* Bit 15 says the drive's start-up runs (OFFSET_CAL, INIT_POS) while this block enables it: not
 * in the step that enables a drive still reporting IDLE (nothing runs yet), then through the
 * start-up, and no longer in RUN (bit 14 then). */
static void test_startup_bit15_follows_the_drive(void **state)
{
    (void)state;
    start();
    drv.startup = 10;
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x07), 0x0233);
    assert_int_equal(tm.state, MC_STATE_IDLE);
    assert_int_equal(cw(0x0F), 0x0237);   /* 4: the command goes out, the drive still IDLE */
    assert_true(cmd.enable);
    assert_int_equal(s.od.statusword & 0xC000u, 0u);
    step_n(1);
    assert_int_equal(tm.state, MC_STATE_OFFSET_CAL);
    step_n(1);
    assert_int_equal(s.od.statusword & 0xC000u, 0x8000u);
    step_n(15);
    assert_int_equal(tm.state, MC_STATE_RUN);
    assert_int_equal(s.od.statusword & 0xC000u, 0x4000u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_and_table),
        cmocka_unit_test(test_walk),
        cmocka_unit_test(test_disable_voltage),
        cmocka_unit_test(test_quick_stop_options),
        cmocka_unit_test(test_disable_operation_shutdown),
        cmocka_unit_test(test_faults),
        cmocka_unit_test(test_fault_code_names_the_first_fault),
        cmocka_unit_test(test_profile_velocity),
        cmocka_unit_test(test_cyclic_velocity),
        cmocka_unit_test(test_torque_modes),
        cmocka_unit_test(test_mode_change),
        cmocka_unit_test(test_run_entry),
        cmocka_unit_test(test_extremes),
        cmocka_unit_test(test_pole_pairs_out_of_range),
        cmocka_unit_test(test_ramp_down_cut_short),
        cmocka_unit_test(test_stop_option_codes_other_than_0),
        cmocka_unit_test(test_stop_ramp_time_limit_with_the_command_repeated),
        cmocka_unit_test(test_reenable_in_one_batch_restarts_the_ramp),
        cmocka_unit_test(test_torque_demand_0_when_disabled),
        cmocka_unit_test(test_not_reached_during_startup),
        cmocka_unit_test(test_pv_halt_reached_is_stopped),
        cmocka_unit_test(test_fault_latched_keeps_its_code),
        cmocka_unit_test(test_startup_holds_the_demands),
        cmocka_unit_test(test_not_reached_when_switched_on),
        cmocka_unit_test(test_cyclic_modes_ignore_halt_in_bit10),
        cmocka_unit_test(test_startup_bit15_follows_the_drive),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
