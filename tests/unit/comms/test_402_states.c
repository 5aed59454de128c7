/* The CiA 402 block's state machine at its edges (mc/cia402.h, harness h402.h): the state
 * names, what is a controlword command and what is not (bit 7, the don't-care bits), the quick
 * stop option codes outside 1-8, faults while disabling, and the statusword bits 4, 10, 11, 12,
 * 15 and the command's mode and references in the states where they are easy to get wrong: a
 * ramp-down, the quick stop hold (options 5-8), a fault reaction, a fault. */
#include <time.h>
#include "h402.h"

/* Fresh, then to `st` by the controlword: RTSO, SO, OE, or Quick stop active held after a quick
 * stop with option 6 at standstill. */
static void reach(mc_402_state_t st)
{
    start();
    cw(0x06);
    if (st >= MC_402_SWITCHED_ON) {
        cw(0x07);
    }
    if (st >= MC_402_OPERATION_ENABLED) {
        cw(0x0F);
    }
    if (st == MC_402_QUICK_STOP_ACTIVE) {
        s.od.quick_stop_option = 6;
        cw(0x02);
        step_n(30);
        assert_false(s.stopping);
    }
    assert_int_equal(s.state, st);
}

/* The names of Table 30, each one exactly. */
static void test_state_names(void **state)
{
    (void)state;
    assert_string_equal(mc_402_state_name(MC_402_NOT_READY), "not ready to switch on");
    assert_string_equal(mc_402_state_name(MC_402_SWITCH_ON_DISABLED), "switch on disabled");
    assert_string_equal(mc_402_state_name(MC_402_READY_TO_SWITCH_ON), "ready to switch on");
    assert_string_equal(mc_402_state_name(MC_402_SWITCHED_ON), "switched on");
    assert_string_equal(mc_402_state_name(MC_402_OPERATION_ENABLED), "operation enabled");
    assert_string_equal(mc_402_state_name(MC_402_QUICK_STOP_ACTIVE), "quick stop active");
    assert_string_equal(mc_402_state_name(MC_402_FAULT_REACTION_ACTIVE), "fault reaction active");
    assert_string_equal(mc_402_state_name(MC_402_FAULT), "fault");
}

/* Table 28: every command has bit 7 = 0; a controlword with bit 7 set (a fault reset held, with
 * any pattern on bits 0-3) is no command in any state but Fault. Quick stop active leaves only
 * on disable voltage (12) or enable operation (16), not on shutdown or switch on. */
static void test_bit7_set_is_no_command(void **state)
{
    (void)state;
    static const uint16_t pat[] = {0x00, 0x02, 0x06, 0x07, 0x0F};
    static const mc_402_state_t from[] = {MC_402_READY_TO_SWITCH_ON, MC_402_SWITCHED_ON,
                                          MC_402_OPERATION_ENABLED, MC_402_QUICK_STOP_ACTIVE};
    for (size_t i = 0; i < sizeof from / sizeof from[0]; ++i) {
        for (size_t k = 0; k < sizeof pat / sizeof pat[0]; ++k) {
            reach(from[i]);
            cw((uint16_t)(0x80u | pat[k]));
            step_n(3);
            assert_int_equal(s.state, from[i]);
        }
    }
    reach(MC_402_QUICK_STOP_ACTIVE);
    cw(0x06);   /* shutdown */
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    cw(0x07);   /* switch on */
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    cw(0x0F);   /* 16 */
    assert_int_equal(s.state, MC_402_OPERATION_ENABLED);
}

/* Bits 4-6 (mode specific) and 8-15 are don't care for the commands: switch on and enable
 * operation with them set are still those commands. */
static void test_dont_care_bits(void **state)
{
    (void)state;
    reach(MC_402_READY_TO_SWITCH_ON);
    cw(0x17);
    assert_int_equal(s.state, MC_402_SWITCHED_ON);   /* 3 with bit 4 */
    reach(MC_402_READY_TO_SWITCH_ON);
    cw(0xFF77);
    assert_int_equal(s.state, MC_402_SWITCHED_ON);   /* 3 with bits 4-6, 8-15 */
    reach(MC_402_SWITCHED_ON);
    cw(0x1F);
    assert_int_equal(s.state, MC_402_OPERATION_ENABLED);   /* 4 with bit 4 */
    reach(MC_402_READY_TO_SWITCH_ON);
    cw(0xFF7F);
    assert_int_equal(s.state, MC_402_OPERATION_ENABLED);   /* 3 + 4 with bits 4-6, 8-15 */
}

/* 0x605A outside 0-8 (reserved, manufacturer) acts as 2: a ramp on 0x6085, ending in Switch on
 * disabled. From 600 rpm with 0x6084 = 500 and 0x6085 = 2000 rpm/s: 400 rpm after 100 ms. */
static void test_quick_stop_other_options_act_as_2(void **state)
{
    (void)state;
    static const int16_t opts[] = {9, 10, 127, INT16_MAX, -1, INT16_MIN};
    for (size_t i = 0; i < sizeof opts / sizeof opts[0]; ++i) {
        start();
        s.od.profile_decel = 500u;
        s.od.quick_stop_decel = 2000u;
        s.od.quick_stop_option = opts[i];
        to_enabled();
        s.od.target_velocity = 600;
        step_n(700);
        assert_int_equal(cw(0x02), 0x0217);
        step_n(99);
        assert_true(fabsf(speed_rpm() - 400.0f) < 2.0f);
        step_n(1000);
        assert_int_equal(sw(), 0x0240);
        assert_false(cmd.enable);
    }
}

/* A fault the drive reports in the step the master disables it, here during its start-up
 * (initial position), is a new fault: Fault, with its code. */
static void test_fault_while_disabling_during_startup(void **state)
{
    (void)state;
    start();
    drv.startup = 20;
    to_enabled();
    for (int k = 0; k < 40 && tm.state != MC_STATE_INIT_POS; ++k) {
        step_n(1);
    }
    assert_int_equal(tm.state, MC_STATE_INIT_POS);
    mc_402_step(&s, &tm, &cmd);   /* the block sees INIT_POS */
    s.od.controlword = 0x00;
    tm.state = MC_STATE_FAULT;
    tm.faults = 1u << 3;
    mc_402_step(&s, &tm, &cmd);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_int_equal(s.od.error_code, mc_co_emcy_code(3));
    assert_false(cmd.enable);
}

/* Bit 15 is the drive's start-up, not its fault reaction; bit 14 neither (not RUN). */
static void test_bit15_not_during_fault_reaction(void **state)
{
    (void)state;
    start();
    s.od.target_velocity = 300;
    to_enabled();
    step_n(50);
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = 1u << 2;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_true(cmd.enable);
    assert_int_equal(s.od.statusword & 0xC000u, 0u);
}

/* Bit 11 shows a target in force clamped by 0x6080 / 0x6072: in every state but a ramp-down
 * or the quick stop hold (their target is 0), and only the mode's own target (pv, csv: the
 * velocity; tq, cst: the torque). */
static void test_bit11_only_for_the_target_in_force(void **state)
{
    (void)state;
    /* disable operation's ramp-down (state Operation enabled, stopping) */
    start();
    s.od.target_velocity = 2500;
    to_enabled();
    step_n(1000);
    assert_true(sw_bit(11));
    cw(0x07);
    assert_true(s.stopping);
    assert_false(sw_bit(11));
    step_n(100);
    assert_true(s.stopping);
    assert_false(sw_bit(11));
    /* quick stop with option 6: the ramp, then the hold */
    start();
    s.od.target_velocity = 2500;
    s.od.quick_stop_option = 6;
    to_enabled();
    step_n(1000);
    assert_true(sw_bit(11));
    cw(0x02);
    assert_false(sw_bit(11));
    for (int k = 0; k < 3000 && s.stopping; ++k) {
        step_n(1);
        assert_false(sw_bit(11));
    }
    assert_false(s.stopping);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    step_n(20);
    assert_false(sw_bit(11));
    /* a fault reaction and a fault are not stops: the clamped target shows as everywhere else */
    start();
    s.od.target_velocity = 2500;
    to_enabled();
    step_n(100);
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = 1u << 2;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_true(sw_bit(11));
    tm.state = MC_STATE_FAULT;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_true(sw_bit(11));
    /* the other kind's target is not in force */
    static const int8_t modes[] = {MC_402_MODE_PV, MC_402_MODE_CSV, MC_402_MODE_TQ, MC_402_MODE_CST};
    for (size_t i = 0; i < 4; ++i) {
        start();
        s.od.mode = modes[i];
        s.od.target_velocity = 600;
        s.od.target_torque = 2000;   /* > 0x6072 = 1000 */
        to_enabled();
        step_n(10);
        assert_int_equal(sw_bit(11), i >= 2);
    }
}

/* During a ramp-down and in the quick stop hold, bit 10 means stopped (|velocity actual| <=
 * 0x606F for 0x6070), not "within 0x606D of the target 0": a rotor at 15 rpm is not stopped. */
static void test_bit10_in_a_stop_is_stopped(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_CSV;
    to_enabled();
    set_rpm(15.0f);
    step_n(30);
    assert_true(sw_bit(10));   /* csv: within 0x606D of the target 0 */
    cw(0x07);                  /* disable operation: a ramp-down (0x605C = 1) */
    step_n(100);
    assert_true(s.stopping);
    assert_false(sw_bit(10));
    start();
    s.od.quick_stop_option = 6;
    to_enabled();
    set_rpm(15.0f);
    step_n(30);
    cw(0x02);
    step_n(1100);   /* the rotor never stops: the ramp-down ends after 15/1000 s + 1 s */
    assert_false(s.stopping);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    assert_false(sw_bit(10));
    step_n(50);
    assert_false(sw_bit(10));
    set_rpm(5.0f);
    step_n(12);
    assert_true(sw_bit(10));   /* now stopped */
}

/* Bit 12 in csv (and cst): the drive follows the command value, only in Operation enabled, in
 * RUN and not ramping down: not during disable operation's ramp, not in the step that switches
 * off at once (the drive still reports RUN), not in the quick stop hold. */
static void test_csv_bit12_only_while_following(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 300;
    to_enabled();
    step_n(20);
    assert_true(sw_bit(12));
    cw(0x07);
    assert_true(s.stopping);
    assert_false(sw_bit(12));
    step_n(20);
    assert_false(sw_bit(12));

    start();
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 300;
    s.od.disable_op_option = 0;
    to_enabled();
    step_n(20);
    assert_true(sw_bit(12));
    assert_int_equal(cw(0x07), 0x0233);   /* 5 at once */
    assert_int_equal(tm.state, MC_STATE_IDLE);   /* the model answered; the step saw RUN */
    assert_false(sw_bit(12));

    start();
    s.od.mode = MC_402_MODE_CSV;
    s.od.quick_stop_option = 6;
    to_enabled();
    step_n(20);
    assert_true(sw_bit(12));
    cw(0x02);
    step_n(30);
    assert_false(s.stopping);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    assert_false(sw_bit(12));
}

/* Target reached waits for the ramp to arrive also when it comes down (pv: 0x6084, tq: 0x6087),
 * even with the rotor inside the velocity window all along. */
static void test_bit10_waits_for_a_decreasing_ramp(void **state)
{
    (void)state;
    start();
    s.od.target_velocity = 600;
    to_enabled();
    step_n(1000);
    assert_true(sw_bit(10));
    s.od.profile_decel = 100u;   /* 0.1 rpm per step: 100 steps to 590 */
    s.od.target_velocity = 590;
    step_n(50);
    assert_false(sw_bit(10));
    step_n(70);
    assert_true(sw_bit(10));

    start();
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 500;
    to_enabled();
    step_n(100);
    assert_true(sw_bit(10));
    s.od.torque_slope = 1000u;   /* 1 per-mille per step: 400 steps to 100 */
    s.od.target_torque = 100;
    step_n(100);
    assert_int_equal(s.od.torque_demand, 400);
    assert_false(sw_bit(10));
    step_n(300);
    assert_true(sw_bit(10));
}

/* The command's kind: speed control while a ramp-down runs and in the quick stop hold (also in
 * a torque mode); otherwise the mode's own, also when disabled (the step a ramp-down ends in
 * Switched on, a fault); and a torque command carries no speed reference, a disabled one none. */
static void test_command_kind_and_references(void **state)
{
    (void)state;
    /* tq, quick stop option 6: held at speed 0 in speed control */
    start();
    s.od.mode = MC_402_MODE_TQ;
    s.od.quick_stop_option = 6;
    s.od.target_torque = 300;
    to_enabled();
    step_n(100);
    tm.torque_ref = 3.0f;
    cw(0x02);
    for (int k = 0; k < 20; ++k) {
        assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
        assert_false(s.stopping);
        assert_true(cmd.enable);
        assert_int_equal(cmd.mode, MC_MODE_SPEED);
        assert_true(cmd.speed_ref == 0.0f && cmd.torque_ref == 0.0f);
        step_n(1);
    }
    /* tq, disable operation (ramp, 0x605C = 1) at standstill: it ends in the same step */
    start();
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 300;
    to_enabled();
    step_n(100);
    tm.torque_ref = 3.0f;   /* what the drive's last torque reference was */
    assert_int_equal(cw(0x07), 0x0233);
    assert_false(cmd.enable);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_true(cmd.speed_ref == 0.0f && cmd.torque_ref == 0.0f);
    /* tq, a fault: disabled, still a torque command */
    start();
    s.od.mode = MC_402_MODE_TQ;
    to_enabled();
    step_n(10);
    tm.state = MC_STATE_FAULT;
    tm.faults = 1u << 1;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_false(cmd.enable);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    /* tq after a flying start at 300 rpm: no speed reference in the torque command */
    start();
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 100;
    set_rpm(300.0f);
    to_enabled();
    step_n(5);
    assert_true(cmd.enable);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_true(cmd.speed_ref == 0.0f);
    assert_true(cmd.torque_ref > 0.0f);
}

/* The demand objects: 0x606B reads 0 in a torque mode; during a fault reaction 0x606B and 0x6074
 * show the held command in their units. */
static void test_demands_torque_mode_and_fault_reaction(void **state)
{
    (void)state;
    start();
    s.od.target_velocity = 600;
    to_enabled();
    step_n(700);
    assert_int_equal(s.od.velocity_demand, 600);
    s.od.mode = MC_402_MODE_TQ;
    step_n(1);
    assert_int_equal(s.od.velocity_demand, 0);

    start();
    s.od.target_velocity = 600;
    to_enabled();
    step_n(700);
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = 1u << 2;
    step_n(3);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_int_equal(s.od.velocity_demand, 600);

    start();
    s.od.mode = MC_402_MODE_CST;
    s.od.max_torque = 30000u;
    s.od.target_torque = 25000;   /* 25 x rated: 742.5 N m */
    to_enabled();
    step_n(5);
    assert_int_equal(s.od.torque_demand, 25000);
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = 1u << 2;
    step_n(3);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    assert_true(fabsf(cmd.torque_ref - 742.5f) < 1e-2f);
    assert_int_equal(s.od.torque_demand, 25000);
}

/* Bit 4 (voltage enabled) with the DC link at or above cfg.vdc_on: at it exactly, set. */
static void test_bit4_at_vdc_on(void **state)
{
    (void)state;
    start();
    cw(0x06);
    cw(0x07);
    tm.vdc = 150.0f;
    step_n(1);
    assert_true(sw_bit(4));
    tm.vdc = 149.99f;
    step_n(1);
    assert_false(sw_bit(4));
}

/* The quick stop hold's velocity target is 0: a rotor within 0x606D of 0 all through the hold
 * (here at +-20 rpm, the window's edge) has been at that target for longer than 0x606E when
 * operation is enabled again (16) in csv with the target 0: bit 10 at once. */
static void test_hold_target_0_counts_for_the_window(void **state)
{
    (void)state;
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        start();
        s.od.mode = MC_402_MODE_CSV;
        s.od.quick_stop_option = 6;
        to_enabled();
        set_rpm(20.0f * (float)sgn);
        step_n(5);
        cw(0x02);
        step_n(1100);   /* not stopped (above 0x606F): ends after 20 / 1000 s + 1 s */
        assert_false(s.stopping);
        assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
        assert_int_equal(cw(0x0F), 0x0237);
        assert_true(sw_bit(10));
    }
}

/* A drive fault without a fault bit reads 0x1000 (generic), and finding the code is bounded
 * work: entering Fault this way a few times costs no noticeable CPU time (the 402 block runs in
 * the CANopen device's background loop). */
static void test_fault_without_bits_is_generic_and_quick(void **state)
{
    (void)state;
    const clock_t t0 = clock();
    for (int k = 0; k < 3; ++k) {
        start();
        to_enabled();
        step_n(5);
        tm.state = MC_STATE_FAULT;
        tm.faults = 0u;
        step_n(1);
        assert_int_equal(s.state, MC_402_FAULT);
        assert_int_equal(s.od.error_code, 0x1000u);
    }
    assert_true((double)(clock() - t0) / CLOCKS_PER_SEC < 0.5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_state_names),
        cmocka_unit_test(test_bit7_set_is_no_command),
        cmocka_unit_test(test_dont_care_bits),
        cmocka_unit_test(test_quick_stop_other_options_act_as_2),
        cmocka_unit_test(test_fault_while_disabling_during_startup),
        cmocka_unit_test(test_bit15_not_during_fault_reaction),
        cmocka_unit_test(test_bit11_only_for_the_target_in_force),
        cmocka_unit_test(test_bit10_in_a_stop_is_stopped),
        cmocka_unit_test(test_csv_bit12_only_while_following),
        cmocka_unit_test(test_bit10_waits_for_a_decreasing_ramp),
        cmocka_unit_test(test_command_kind_and_references),
        cmocka_unit_test(test_demands_torque_mode_and_fault_reaction),
        cmocka_unit_test(test_bit4_at_vdc_on),
        cmocka_unit_test(test_hold_target_0_counts_for_the_window),
        cmocka_unit_test(test_fault_without_bits_is_generic_and_quick),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
