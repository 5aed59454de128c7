/* The CiA 402 block (mc/cia402.h) on synthetic telemetry: the state machine's transitions and
 * statusword values (CiA 402-2 Table 30), the quick stop and disable options, the faults with the
 * drive's reaction, the fault-reset edge, and the modes: ramps, clamps, halt, offsets, units,
 * bumpless mode changes, the start-up hold, and inputs at their extremes. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>
#include "mc/cia402.h"
#include "mc/co.h"

static mc_402_t s;
static mc_drive_telem_t tm;
static mc_drive_cmd_t cmd;

static const mc_402_cfg_t CFG = {.dt = 1e-3f, .pole_pairs = 5, .rated_torque = 29.7f, .rated_current = 13.29f,
                                 .psi_pm = 0.343f, .ld = 10.5e-3f, .lq = 12.9e-3f, .vdc_on = 150.0f,
                                 .max_speed_rpm = 1800.0f, .accel_rpm_s = 1000.0f};

static void start(void)
{
    memset(&tm, 0, sizeof tm);
    tm.state = MC_STATE_IDLE;
    tm.vdc = 300.0f;
    mc_402_init(&s, &CFG);
}

static void step_n(int n)
{
    for (int k = 0; k < n; ++k) {
        mc_402_step(&s, &tm, &cmd);
        /* a drive that follows its command: RUN while enabled, IDLE when not */
        if (tm.state != MC_STATE_FAULT && tm.state != MC_STATE_FAULT_REACTION) {
            tm.state = cmd.enable ? MC_STATE_RUN : MC_STATE_IDLE;
        }
    }
}

static uint16_t cw(uint16_t w)
{
    s.od.controlword = w;
    step_n(1);
    return s.od.statusword & 0x006Fu;
}

static void to_enabled(void)
{
    assert_int_equal(cw(0x06), 0x21);
    assert_int_equal(cw(0x07), 0x23);
    assert_int_equal(cw(0x0F), 0x27);
}

static void test_walk_and_statusword(void **state)
{
    (void)state;
    start();
    step_n(1);
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    assert_int_equal(s.od.statusword & 0x026Fu, 0x0240u);   /* SOD + remote */
    assert_false(cmd.enable);
    assert_int_equal(cw(0x07), 0x40);   /* switch on from SOD: not a transition */
    assert_int_equal(cw(0x06), 0x21);
    assert_int_equal(s.od.statusword & 0x0010u, 0x0010u);   /* voltage enabled: the DC link is up */
    assert_int_equal(cw(0x07), 0x23);
    assert_false(cmd.enable);
    assert_int_equal(cw(0x0F), 0x27);
    assert_true(cmd.enable);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    step_n(1);
    assert_int_equal(s.od.statusword & 0x4000u, 0x4000u);   /* RUN */
    assert_int_equal(cw(0x07), 0x23);   /* disable operation, option 0: at once */
    assert_false(cmd.enable);
    assert_int_equal(cw(0x0F), 0x27);
    assert_int_equal(cw(0x06), 0x21);   /* shutdown from OE */
    assert_int_equal(cw(0x0F), 0x27);   /* RTSO -> OE with one command */
    /* disable voltage from every state */
    assert_int_equal(cw(0x00), 0x40);
    assert_int_equal(cw(0x06), 0x21);
    assert_int_equal(cw(0x00), 0x40);
    assert_int_equal(cw(0x06), 0x21);
    assert_int_equal(cw(0x07), 0x23);
    assert_int_equal(cw(0x00), 0x40);
    /* quick stop from RTSO and SO: SOD */
    assert_int_equal(cw(0x06), 0x21);
    assert_int_equal(cw(0x02), 0x40);
    assert_int_equal(mc_402_state_name(MC_402_QUICK_STOP_ACTIVE)[0], 'q');
}

static void test_quick_stop_options(void **state)
{
    (void)state;
    /* option 2 (default): ramp down on 0x6085, then SOD */
    start();
    to_enabled();
    s.od.target_velocity = 600;
    tm.omega = 0.0f;
    step_n(700);
    assert_true(fabsf(s.v_ramp - 600.0f) < 1e-3f);
    s.od.quick_stop_decel = 2000u;
    assert_int_equal(cw(0x02), 0x07);   /* QSA */
    assert_true(cmd.enable);
    step_n(100);   /* 0.1 s: 200 rpm less */
    assert_true(fabsf(s.v_ramp - 400.0f) < 3.0f);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    step_n(300);   /* the ramp reached 0 and the rotor (omega 0) is still */
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    assert_false(cmd.enable);
    /* option 5: stays in QSA at standstill, enable operation returns */
    start();
    s.od.quick_stop_option = 5;
    to_enabled();
    assert_int_equal(cw(0x02), 0x07);
    step_n(50);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    assert_true(cmd.enable);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(cw(0x0F), 0x27);
    /* option 0: off at once */
    s.od.quick_stop_option = 0;
    assert_int_equal(cw(0x02), 0x40);
    assert_false(cmd.enable);
    /* a rotor that does not stop: disabled after the ramp's time + 1 s anyway */
    start();
    to_enabled();
    s.od.target_velocity = 100;
    step_n(200);
    tm.omega = 100.0f;   /* 191 rpm and staying */
    s.od.quick_stop_decel = 1000u;
    assert_int_equal(cw(0x02), 0x07);
    step_n(1050);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    step_n(200);
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    /* in a torque mode the quick stop takes speed control from the actual speed */
    start();
    s.od.mode = MC_402_MODE_TQ;
    to_enabled();
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    tm.omega = 5.0f * 300.0f / 9.5493f;   /* 300 rpm */
    step_n(1);
    assert_int_equal(cw(0x02), 0x07);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    assert_true(fabsf(cmd.speed_ref * 9.5493f - 300.0f) < 5.0f);
}

static void test_disable_operation_ramp(void **state)
{
    (void)state;
    start();
    s.od.disable_op_option = 1;
    to_enabled();
    s.od.target_velocity = 300;
    step_n(400);
    assert_int_equal(cw(0x07), 0x27);   /* still OE while it ramps down on 0x6084 */
    assert_true(cmd.enable);
    step_n(400);
    assert_int_equal(s.od.statusword & 0x6Fu, 0x23u);
    assert_false(cmd.enable);
}

static void test_faults(void **state)
{
    (void)state;
    start();
    to_enabled();
    /* the drive's reaction: FRA with the command kept, then Fault, disabled, the code */
    const mc_drive_cmd_t before = cmd;
    tm.state = MC_STATE_FAULT_REACTION;
    tm.faults = MC_FAULT_OVERSPEED;
    step_n(1);
    assert_int_equal(s.od.statusword & 0x6Fu, 0x0Fu);
    assert_true(cmd.enable == before.enable && cmd.mode == before.mode);
    s.od.controlword = 0x80;   /* fault reset during the reaction: ignored */
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT_REACTION_ACTIVE);
    s.od.controlword = 0x0F;
    tm.state = MC_STATE_FAULT;
    step_n(1);
    assert_int_equal(s.od.statusword & 0x6Fu, 0x08u);
    assert_false(cmd.enable);
    assert_int_equal(s.od.error_code, 0x8400u);
    /* latched: the drive forgets (IDLE), the 402 Fault stays */
    tm.state = MC_STATE_IDLE;
    tm.faults = 0u;
    step_n(5);
    assert_int_equal(s.state, MC_402_FAULT);
    /* reset on the edge only */
    s.od.controlword = 0x80;
    step_n(1);
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    assert_int_equal(s.od.error_code, 0u);
    /* a fault without a reaction, from Switched on; a level bit 7 does not reset again */
    assert_int_equal(cw(0x06), 0x21);
    assert_int_equal(cw(0x07), 0x23);
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_OVERCURRENT | MC_FAULT_TRACKING;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_int_equal(s.od.error_code, 0x2310u);   /* the lowest bit's code */
    s.od.controlword = 0x86;   /* bit 7 set with a shutdown: the edge resets */
    step_n(1);
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    tm.state = MC_STATE_FAULT;   /* the drive still shows it: no new edge, no new Fault */
    step_n(3);
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);
    /* a drive that faults while not enabled (a configuration refused at init) */
    start();
    tm.state = MC_STATE_FAULT;
    tm.faults = MC_FAULT_CONFIG;
    step_n(1);
    assert_int_equal(s.state, MC_402_FAULT);
    assert_int_equal(s.od.error_code, 0x6320u);
}

static void test_profile_velocity(void **state)
{
    (void)state;
    start();
    to_enabled();
    tm.state = MC_STATE_INIT_POS;   /* still starting: the ramp holds at 0, bit 15 */
    s.od.target_velocity = 1000;
    mc_402_step(&s, &tm, &cmd);
    mc_402_step(&s, &tm, &cmd);
    assert_true(s.v_ramp == 0.0f);
    assert_int_equal(s.od.statusword & 0xC000u, 0x8000u);
    tm.state = MC_STATE_RUN;
    step_n(500);   /* 1000 rpm/s: 500 rpm */
    assert_true(fabsf(s.v_ramp - 500.0f) < 2.0f);
    assert_int_equal(s.od.velocity_demand, (int32_t)lrintf(s.v_ramp));
    step_n(600);
    assert_true(s.v_ramp == 1000.0f);
    assert_true(fabsf(cmd.speed_ref - 104.72f) < 0.01f);   /* rad/s mechanical */
    /* velocity actual from the electrical speed with 5 pole pairs; target reached in the window */
    tm.omega = 5.0f * 104.72f;
    step_n(20);
    assert_int_equal(s.od.velocity_actual, 1000);
    assert_int_equal(s.od.statusword & 0x0400u, 0x0400u);
    /* clamp by 0x6080: bit 11 */
    s.od.target_velocity = 5000;
    step_n(1);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    step_n(2000);
    assert_true(s.v_ramp == 1800.0f);
    /* halt: decelerate on 0x6084 and hold, enabled */
    s.od.profile_decel = 3000u;
    s.od.controlword = 0x010F;
    step_n(100);
    assert_true(fabsf(s.v_ramp - 1500.0f) < 3.0f);
    step_n(600);
    assert_true(s.v_ramp == 0.0f);
    assert_true(cmd.enable);
    /* speed = 0 (bit 12) when the rotor is below the threshold for its time */
    tm.omega = 0.0f;
    step_n(20);
    assert_int_equal(s.od.statusword & 0x1000u, 0x1000u);
}

static void test_torque_and_cyclic(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_TQ;
    to_enabled();
    s.od.target_torque = 500;
    s.od.torque_slope = 1000u;   /* per-mille/s */
    step_n(250);
    assert_true(fabsf(s.t_ramp - 250.0f) < 2.0f);
    step_n(300);
    assert_true(s.t_ramp == 500.0f);
    assert_true(fabsf(cmd.torque_ref - 14.85f) < 1e-3f);   /* half the rated torque */
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_int_equal(s.od.mode_display, MC_402_MODE_TQ);
    /* clamp by 0x6072 */
    s.od.max_torque = 300u;
    step_n(300);
    assert_true(s.t_ramp == 300.0f);
    assert_int_equal(s.od.statusword & 0x0800u, 0x0800u);
    /* cst: target + offset, no ramp */
    s.od.max_torque = 1000u;
    s.od.mode = MC_402_MODE_CST;
    s.od.target_torque = 100;
    s.od.torque_offset = 50;
    step_n(1);
    assert_true(fabsf(cmd.torque_ref - 0.15f * 29.7f) < 1e-3f);
    assert_int_equal(s.od.statusword & 0x1000u, 0x1000u);   /* follows the command value */
    /* torque actual from i_dq by (2.9): i_q = 6 A, i_d = -2 A */
    tm.i_dq.d = -2.0f;
    tm.i_dq.q = 6.0f;
    step_n(1);
    const float t = 1.5f * 5.0f * (0.343f * 6.0f + (10.5e-3f - 12.9e-3f) * -2.0f * 6.0f);
    assert_int_equal(s.od.torque_actual, (int16_t)lrintf(t / 29.7f * 1000.0f));
    assert_int_equal(s.od.current_actual, (int16_t)lrintf(sqrtf(40.0f) / 13.29f * 1000.0f));
    /* to csv, bumpless from the actual speed; target + offset at once */
    tm.omega = 5.0f * 31.416f;   /* 300 rpm */
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 200;
    s.od.velocity_offset = 20;
    step_n(1);
    assert_int_equal(cmd.mode, MC_MODE_SPEED);
    assert_true(fabsf(cmd.speed_ref * 9.5493f - 220.0f) < 0.1f);
    /* to pv: the ramp starts from the speed it was at */
    s.od.mode = MC_402_MODE_PV;
    s.od.target_velocity = 1000;
    step_n(1);
    assert_true(s.v_ramp > 219.0f && s.v_ramp < 225.0f);
    assert_false(mc_402_mode_supported(1));
    assert_true(mc_402_mode_supported(MC_402_MODE_CST));
}

static void test_extremes(void **state)
{
    (void)state;
    start();
    to_enabled();
    s.od.target_velocity = INT32_MIN;
    s.od.velocity_offset = INT32_MIN;
    s.od.profile_accel = UINT32_MAX;
    s.od.max_motor_speed = UINT32_MAX;
    tm.omega = NAN;
    tm.i_dq.d = INFINITY;
    tm.i_dq.q = -INFINITY;
    tm.vdc = NAN;
    tm.torque_ref = NAN;
    for (int m = 0; m < 4; ++m) {
        static const int8_t modes[4] = {MC_402_MODE_PV, MC_402_MODE_CSV, MC_402_MODE_TQ, MC_402_MODE_CST};
        s.od.mode = modes[m];
        s.od.target_torque = INT16_MIN;
        s.od.torque_offset = INT16_MIN;
        s.od.torque_slope = UINT32_MAX;
        step_n(3);
        assert_true(isfinite(cmd.speed_ref) && isfinite(cmd.torque_ref));
        assert_int_equal(s.od.velocity_actual, 0);
        assert_int_equal(s.od.torque_actual, 0);
        assert_int_equal(s.od.dc_link_voltage, 0u);
    }
    s.od.mode = MC_402_MODE_CSV;
    tm.omega = 1e30f;
    step_n(1);
    assert_int_equal(s.od.velocity_actual, INT32_MAX);
    /* every controlword: the state stays one of the enum */
    for (uint32_t w = 0; w < 0x10000u; w += 7u) {
        s.od.controlword = (uint16_t)w;
        step_n(1);
        assert_true(s.state >= MC_402_NOT_READY && s.state <= MC_402_FAULT);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_walk_and_statusword),
        cmocka_unit_test(test_quick_stop_options),
        cmocka_unit_test(test_disable_operation_ramp),
        cmocka_unit_test(test_faults),
        cmocka_unit_test(test_profile_velocity),
        cmocka_unit_test(test_torque_and_cyclic),
        cmocka_unit_test(test_extremes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
