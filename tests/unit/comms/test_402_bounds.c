/* The CiA 402 block's numbers at their bounds (mc/cia402.h, harness h402.h): the rated values
 * and the period as the block takes them from its configuration, the float -> integer objects at
 * their ranges' ends, the actual torque and current (scale and sign), the ramps (0x6083 / 0x6084
 * through zero, the last step onto the target), the clamps at their limits, the standstill and
 * velocity-window times at their largest values, the ramp-down's deceleration floor and time
 * bound, and where the ramps start (RUN entry, a torque mode taking over, a recovery in the quick
 * stop hold). Many cases use the period DT_EXACT = 1/1024 s so that ramp steps and times are
 * exact and a boundary is met exactly. */
#include "h402.h"

/* x [SI] in per-mille of `rated` as an INTEGER16 object: rounded, saturated */
static long per_mille(double x, double rated)
{
    const double v = x / rated * 1000.0;
    return v >= 32767.0 ? 32767 : v <= -32768.0 ? -32768 : lround(v);
}

/* The rated torque and current are used as configured when positive and finite (below 3e38);
 * anything else (0, negative, 3e38 and above, infinite, NaN) reads as 1 (N m, A): the actual
 * torque 0x6077 and current 0x6078 are then per-mille of 1. */
static void test_rated_values_that_make_no_sense_read_as_1(void **state)
{
    (void)state;
    static const float sane[] = {29.7f, 50.0f, 0.5f, 0.05f, 2.9e38f};
    static const float nonsense[] = {0.0f, -0.0f, -0.5f, -50.0f, 3.0e38f, 3.05e38f, INFINITY, -INFINITY, NAN};
    const double t_nm = 1.5 * 5.0 * (double)CFG.psi_pm * 2.0;   /* (2.9), i_d = 0, i_q = 2 A */
    for (int pass = 0; pass < 2; ++pass) {
        const float *r = pass == 0 ? sane : nonsense;
        const size_t n = pass == 0 ? sizeof sane / sizeof sane[0] : sizeof nonsense / sizeof nonsense[0];
        for (size_t i = 0; i < n; ++i) {
            mc_402_cfg_t c = CFG;
            c.rated_torque = r[i];
            c.rated_current = r[i];
            start_cfg(&c);
            tm.i_dq.q = 2.0f;
            step_n(1);
            const double used = pass == 0 ? (double)r[i] : 1.0;
            assert_int_equal(s.od.torque_actual, per_mille(t_nm, used));
            assert_int_equal(s.od.current_actual, per_mille(2.0, used));
        }
    }
}

/* The integer objects from floats: rounded, saturated at both ends of their type. */
static void test_conversions_round_and_saturate(void **state)
{
    (void)state;
    /* csv at the INTEGER32 ends with 0x6080 at its largest: INT32_MAX is 2^31 as a float */
    start();
    s.od.mode = MC_402_MODE_CSV;
    s.od.max_motor_speed = UINT32_MAX;
    to_enabled();
    s.od.target_velocity = INT32_MAX;
    step_n(2);
    assert_int_equal(s.od.velocity_demand, INT32_MAX);
    s.od.target_velocity = INT32_MIN;
    step_n(2);
    assert_int_equal(s.od.velocity_demand, INT32_MIN);
    /* 0x6079 DC link [mV]: a reading just below 0 (an ADC offset) is 0, not a wrap; 0.8 mV is 1;
     * 2^32 mV and above saturate */
    start();
    static const struct { float vdc; uint32_t mv; } dc[] = {
        {-0.0007f, 0u}, {-0.4f, 0u}, {0.0004f, 0u}, {0.0008f, 1u}, {300.0f, 300000u},
        {4294967.5f, UINT32_MAX}, {1.0e7f, UINT32_MAX}};
    for (size_t i = 0; i < sizeof dc / sizeof dc[0]; ++i) {
        tm.vdc = dc[i].vdc;
        step_n(1);
        assert_int_equal(s.od.dc_link_voltage, dc[i].mv);
    }
    /* 0x6080's default from the configuration, the same conversion */
    static const struct { float rpm; uint32_t obj; } ms[] = {
        {0.8f, 1u}, {-5.0f, 0u}, {4294967296.0f, UINT32_MAX}, {1.0e10f, UINT32_MAX}, {1800.4f, 1800u}};
    for (size_t i = 0; i < sizeof ms / sizeof ms[0]; ++i) {
        mc_402_cfg_t c = CFG;
        c.max_speed_rpm = ms[i].rpm;
        start_cfg(&c);
        assert_int_equal(s.od.max_motor_speed, ms[i].obj);
    }
}

/* An indeterminate torque (currents at the end of the float range with a large flux linkage:
 * psi_pm i_q -> +inf, (ld - lq) i_d i_q -> -inf in (2.9)) reads 0; the current saturates. */
static void test_indeterminate_torque_reads_0(void **state)
{
    (void)state;
    mc_402_cfg_t c = CFG;
    c.psi_pm = 2.0f;
    start_cfg(&c);
    tm.i_dq.d = 3.0e38f;
    tm.i_dq.q = 3.0e38f;
    step_n(1);
    assert_int_equal(s.od.torque_actual, 0);
    assert_int_equal(s.od.current_actual, 32767);
}

/* 0x6077 and 0x6078 at 20 x rated (the scale exactly, to the rounding), and 0x6078's sign: that
 * of i_q, with i_q = 0 (pure field weakening current) positive. */
static void test_actual_torque_and_current(void **state)
{
    (void)state;
    start();
    tm.i_dq.q = 231.0f;
    step_n(1);
    const double t_nm = 1.5 * 5.0 * (double)CFG.psi_pm * 231.0;
    assert_true(fabs(s.od.torque_actual - t_nm / (double)CFG.rated_torque * 1000.0) <= 0.51);
    assert_true(s.od.torque_actual > 19000);
    tm.i_dq.d = -150.0f;
    tm.i_dq.q = 219.6f;
    step_n(1);
    const double i_mag = sqrt(150.0 * 150.0 + (double)219.6f * (double)219.6f);
    assert_true(fabs(s.od.current_actual - i_mag / (double)CFG.rated_current * 1000.0) <= 0.51);
    assert_true(s.od.current_actual > 19000);
    static const float iq[] = {0.0f, 0.05f, 0.5f, 2.0f, -0.05f, -0.5f, -2.0f};
    for (size_t i = 0; i < sizeof iq / sizeof iq[0]; ++i) {
        tm.i_dq.d = -5.0f;
        tm.i_dq.q = iq[i];
        step_n(1);
        const double m = sqrt(25.0 + (double)iq[i] * (double)iq[i]);
        assert_int_equal(s.od.current_actual, per_mille(iq[i] < 0.0f ? -m : m, (double)CFG.rated_current));
    }
}

/* Into torque control from a speed mode: the torque demand starts at the drive's torque
 * reference (bumpless), to the float's precision; here with 0x6087 = 1 per-mille/s. */
static void test_bumpless_into_torque_control(void **state)
{
    (void)state;
    start();
    s.od.target_velocity = 600;
    to_enabled();
    step_n(700);
    tm.torque_ref = 10.0f;
    s.od.torque_slope = 1u;
    s.od.mode = MC_402_MODE_TQ;
    step_n(1);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_true(fabsf(cmd.torque_ref - 10.0f) < 1e-4f);
}

/* A target at its limit (+-0x6080, +-0x6072) is in range: bit 11 only beyond it. */
static void test_target_at_its_limit_is_not_limited(void **state)
{
    (void)state;
    start();
    to_enabled();
    static const struct { int32_t v; bool lim; } pv[] = {{1800, false}, {-1800, false}, {1801, true}, {-1801, true}};
    for (size_t i = 0; i < 4; ++i) {
        s.od.target_velocity = pv[i].v;
        step_n(1);
        assert_int_equal(sw_bit(11), pv[i].lim);
    }
    start();
    s.od.mode = MC_402_MODE_TQ;
    to_enabled();
    static const struct { int16_t t; bool lim; } tq[] = {{1000, false}, {-1000, false}, {1001, true}, {-1001, true}};
    for (size_t i = 0; i < 4; ++i) {
        s.od.target_torque = tq[i].t;
        step_n(1);
        assert_int_equal(sw_bit(11), tq[i].lim);
    }
}

/* pv, at the exact period: enabled, in RUN, 0x6083 = `accel`, 0x6084 = `decel` [rpm/s] */
static void pv_exact(uint32_t accel, uint32_t decel)
{
    start_exact();
    s.od.profile_accel = accel;
    s.od.profile_decel = decel;
    to_enabled();
    step_n(2);
    assert_int_equal(tm.state, MC_STATE_RUN);
    assert_true(speed_rpm() == 0.0f);
}

static void expect_speed(float rpm)
{
    step_n(1);
    assert_true(fabsf(speed_rpm() - rpm) < 1e-3f);
}

/* The pv ramp: 0x6084 while |speed| shrinks, down to 0 exactly, 0x6083 from there on, in both
 * directions; and the last step lands on the target, never beyond it. 0x6083 = 1 rpm per
 * period, 0x6084 = 1/16 rpm per period. */
static void test_pv_ramp_through_zero(void **state)
{
    (void)state;
    pv_exact(1024u, 64u);
    s.od.target_velocity = 1;
    expect_speed(1.0f);
    s.od.target_velocity = -1000;
    for (int k = 1; k <= 16; ++k) {
        expect_speed(1.0f - (float)k / 16.0f);
    }
    expect_speed(-1.0f);
    expect_speed(-2.0f);

    pv_exact(1024u, 64u);
    s.od.target_velocity = -1;
    expect_speed(-1.0f);
    s.od.target_velocity = 1000;
    for (int k = 1; k <= 16; ++k) {
        expect_speed(-1.0f + (float)k / 16.0f);
    }
    expect_speed(1.0f);
    expect_speed(2.0f);

    pv_exact(1024u, 64u);   /* from below 0 to 0: 0x6084 all the way */
    s.od.target_velocity = -2;
    expect_speed(-1.0f);
    expect_speed(-2.0f);
    s.od.target_velocity = 0;
    for (int k = 1; k <= 32; ++k) {
        expect_speed(-2.0f + (float)k / 16.0f);
    }
    expect_speed(0.0f);

    pv_exact(768u, 768u);   /* 0.75 rpm per period toward 1 rpm: 0.75, then 1 */
    s.od.target_velocity = 1;
    expect_speed(0.75f);
    expect_speed(1.0f);
    expect_speed(1.0f);
    s.od.target_velocity = -1;   /* and down: 0.25, -0.5, -1 */
    expect_speed(0.25f);
    expect_speed(-0.5f);
    expect_speed(-1.0f);
    expect_speed(-1.0f);
}

/* cfg.dt as this block's period: a positive value below 10 s; anything else (0, negative, NaN,
 * infinite, 10 s and above) lets no time pass: the ramps hold. 0x6083 = 1 rpm/s, so the speed
 * after two RUN periods is 2 dt [rpm]. */
static float speed_after_two_run_periods(float dt)
{
    mc_402_cfg_t c = CFG;
    c.dt = dt;
    start_cfg(&c);
    s.od.profile_accel = 1u;
    s.od.target_velocity = 1000;
    to_enabled();
    step_n(2);
    return speed_rpm();
}

static void test_period_out_of_range_passes_no_time(void **state)
{
    (void)state;
    static const float ok[] = {1e-3f, 2.0f, 9.999999f};
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; ++i) {
        const float v = speed_after_two_run_periods(ok[i]);
        assert_true(fabsf(v - 2.0f * ok[i]) < 1e-3f * ok[i]);
    }
    static const float bad[] = {0.0f, -0.0f, -1e-3f, -1.0f, NAN, -INFINITY, 10.0f, 10.000001f, 20.0f, INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        assert_true(speed_after_two_run_periods(bad[i]) == 0.0f);
    }
}

/* 0x606F / 0x6070 and 0x606D / 0x606E at their ends: exactly at the threshold (the window's
 * edge) counts as inside; the largest times (65.535 s) are met, not cut short. */
static void test_standstill_and_window_limits(void **state)
{
    (void)state;
    start();
    set_rpm(10.0f);   /* = 0x606F */
    step_n(20);
    assert_true(sw_bit(12));
    set_rpm(11.0f);
    step_n(20);
    assert_false(sw_bit(12));

    start_exact();
    s.od.velocity_threshold_time = 65535u;
    step_n(67000);   /* 65.43 s */
    assert_false(sw_bit(12));
    step_n(200);     /* 65.63 s */
    assert_true(sw_bit(12));

    start();
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 600;
    set_rpm(620.0f);   /* target + 0x606D */
    to_enabled();
    step_n(20);
    assert_true(sw_bit(10));
    set_rpm(621.0f);
    step_n(20);
    assert_false(sw_bit(10));

    start_exact();
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 600;
    s.od.velocity_window_time = 65535u;
    to_enabled();
    step_n(67000);
    assert_false(sw_bit(10));
    step_n(200);
    assert_true(sw_bit(10));
}

/* A ramp-down's deceleration is at least 1 rpm/s: 0x6085 = 0 (or 1) takes 1 rpm off per second. */
static void test_stop_deceleration_floor(void **state)
{
    (void)state;
    for (uint32_t d = 0u; d <= 1u; ++d) {
        start_exact();
        s.od.profile_accel = 1024u;
        s.od.target_velocity = 100;
        to_enabled();
        step_n(150);
        assert_true(fabsf(speed_rpm() - 100.0f) < 1e-3f);
        s.od.quick_stop_decel = d;
        cw(0x02);
        step_n(1023);   /* 1024 periods: 1 s */
        assert_true(s.stopping);
        assert_true(fabsf(speed_rpm() - 99.0f) < 1e-3f);
    }
}

/* The ramp-down of a rotor that does not stop: the speed command reaches 0 exactly and stays
 * there, and the ramp-down ends after its nominal time + 1 s, the nominal time from the larger
 * of the ramp's and the rotor's speed (in tq the velocity ramp is idle at 0 while the rotor
 * turns at 512 rpm): 512 / 1024 s + 1 s = 1536 periods; the next ramp-down is timed afresh. */
static int stop_periods(void)
{
    cw(0x07);   /* disable operation (0x605C = 1): a ramp on 0x6084 */
    int n = 1;
    while (s.state == MC_402_OPERATION_ENABLED && n < 5000) {
        if (n >= 513) {
            assert_true(speed_rpm() == 0.0f);
        }
        step_n(1);
        ++n;
    }
    assert_int_equal(s.state, MC_402_SWITCHED_ON);
    return n;
}

static void test_stop_time_bound(void **state)
{
    (void)state;
    start_exact();
    s.od.mode = MC_402_MODE_TQ;
    s.od.profile_decel = 1024u;
    set_rpm(0.0f);
    to_enabled();
    step_n(5);
    set_rpm(512.0f);
    step_n(5);
    assert_int_equal(stop_periods(), 1536);
    cw(0x0F);
    step_n(10);
    assert_int_equal(s.state, MC_402_OPERATION_ENABLED);
    assert_int_equal(stop_periods(), 1536);
    /* a period that does not add up exactly: 0.5 s + 1 s at 1 ms */
    start();
    s.od.mode = MC_402_MODE_TQ;
    set_rpm(0.0f);
    to_enabled();
    step_n(5);
    set_rpm(500.0f);
    step_n(5);
    const int n = stop_periods();
    assert_true(n >= 1500 && n <= 1502);
}

/* At RUN entry the velocity ramp starts from 0 with the rotor at or below 0x606F, from its speed
 * above it, clamped to 0x6080; the first period then ramps 1 rpm toward 600 rpm. */
static float first_run_speed(float rotor_rpm)
{
    start_exact();
    s.od.profile_accel = 1024u;
    s.od.profile_decel = 1024u;
    s.od.target_velocity = 600;
    set_rpm(rotor_rpm);
    to_enabled();
    assert_int_equal(tm.state, MC_STATE_RUN);
    step_n(1);
    return speed_rpm();
}

static void test_run_entry_start_speed(void **state)
{
    (void)state;
    assert_true(fabsf(first_run_speed(0.0f) - 1.0f) < 1e-3f);
    assert_true(fabsf(first_run_speed(10.0f) - 1.0f) < 1e-3f);
    assert_true(fabsf(first_run_speed(-10.0f) - 1.0f) < 1e-3f);
    assert_true(fabsf(first_run_speed(11.0f) - 12.0f) < 1e-3f);
    assert_true(fabsf(first_run_speed(-2000.0f) + 1799.0f) < 1e-2f);   /* from -0x6080 */
    assert_true(fabsf(first_run_speed(2000.0f) - 1799.0f) < 1e-2f);    /* from 0x6080 */
}

/* The torque ramp starts from 0 at RUN entry, also when the mode became tq in that very period
 * (the drive's torque reference during its start-up is no demand). */
static void test_run_entry_torque_from_0(void **state)
{
    (void)state;
    start();
    drv.startup = 6;
    to_enabled();
    for (int k = 0; k < 20 && tm.state != MC_STATE_RUN; ++k) {
        step_n(1);
    }
    assert_int_equal(tm.state, MC_STATE_RUN);
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 100;
    tm.torque_ref = 5.0f;
    step_n(1);
    assert_int_equal(cmd.mode, MC_MODE_TORQUE);
    assert_true(fabsf(cmd.torque_ref - 10.0f * 1e-3f * CFG.rated_torque) < 1e-4f);   /* 0x6087: 10 per period */
}

/* Quick stop option 6: the speed command is 0 from the period the ramp-down ends (here with
 * 0x6085 = 100 rpm/s the rotor counts as stopped at about 9 rpm), and the hold stays at 0 even if
 * the drive re-enters RUN with the rotor turning (a recovery): no ramp from the caught speed. */
static void test_quick_stop_hold_at_0(void **state)
{
    (void)state;
    start();
    s.od.quick_stop_option = 6;
    s.od.quick_stop_decel = 100u;
    s.od.target_velocity = 600;
    to_enabled();
    step_n(700);
    cw(0x02);
    for (int k = 0; k < 8000 && s.stopping; ++k) {
        step_n(1);
    }
    assert_false(s.stopping);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    assert_true(cmd.enable);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.velocity_demand, 0);
    step_n(5);
    set_rpm(300.0f);
    tm.state = MC_STATE_INIT_POS;
    for (int k = 0; k < 3; ++k) {
        mc_402_step(&s, &tm, &cmd);
    }
    tm.state = MC_STATE_RUN;
    for (int k = 0; k < 3; ++k) {
        mc_402_step(&s, &tm, &cmd);
        assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
        assert_true(cmd.enable);
        assert_true(cmd.speed_ref == 0.0f);
        assert_int_equal(s.od.velocity_demand, 0);
    }
}

/* Re-enabled in tq after a disable voltage, the torque demand is 0 through the start-up: what
 * the torque ramp had before is gone. */
static void test_torque_demand_restarts_from_0(void **state)
{
    (void)state;
    start();
    s.od.mode = MC_402_MODE_TQ;
    s.od.target_torque = 300;
    to_enabled();
    step_n(100);
    assert_int_equal(s.od.torque_demand, 300);
    cw(0x00);
    step_n(5);
    drv.startup = 10;
    to_enabled();
    for (int k = 0; k < 8; ++k) {
        assert_true(tm.state != MC_STATE_RUN);
        assert_true(cmd.enable);
        assert_true(cmd.torque_ref == 0.0f);
        assert_int_equal(s.od.torque_demand, 0);
        step_n(1);
    }
}

/* Halt in pv ramps the speed command to 0 exactly and holds it there. */
static void test_pv_halt_holds_exactly_0(void **state)
{
    (void)state;
    start();
    s.od.target_velocity = 600;
    to_enabled();
    step_n(700);
    cw(0x010F);
    step_n(700);
    assert_true(cmd.enable);
    assert_true(cmd.speed_ref == 0.0f);
    assert_int_equal(s.od.velocity_demand, 0);
}

/* Only 3, 4, 9 and 10 are supported (0x6502); any other 0x6060 keeps the mode in force. */
static void test_only_the_four_modes(void **state)
{
    (void)state;
    static const int8_t other[] = {-1, 0, 1, 2, 5, 6, 7, 8, 11, 12, 100, INT8_MAX};
    for (size_t i = 0; i < sizeof other / sizeof other[0]; ++i) {
        assert_false(mc_402_mode_supported(other[i]));
    }
    start();
    s.od.mode = MC_402_MODE_CSV;
    to_enabled();
    for (size_t i = 0; i < sizeof other / sizeof other[0]; ++i) {
        s.od.mode = other[i];
        step_n(1);
        assert_int_equal(s.od.mode_display, MC_402_MODE_CSV);
    }
}

/* 0x6070 = 0 and 0x606E = 0: no time to wait, but still the condition itself. Speed = 0 (bit 12)
 * only with |velocity actual| <= 0x606F, target reached (bit 10) only within 0x606D of the target;
 * a ramp-down still ramps (it ends when the rotor is below 0x606F, not at once); and with the rotor
 * just come inside, a controlword between two periods sees it at once. */
static void test_zero_times_still_need_the_condition(void **state)
{
    (void)state;
    start();
    s.od.velocity_threshold_time = 0u;
    s.od.velocity_window_time = 0u;
    s.od.target_velocity = 600;
    to_enabled();
    step_n(700);
    assert_int_equal(s.od.velocity_actual, 600);
    assert_false(sw_bit(12));   /* turning at 600 rpm: not speed 0 */
    assert_true(sw_bit(10));
    set_rpm(700.0f);            /* outside 0x606D */
    step_n(1);
    assert_false(sw_bit(10));
    drv.follow = true;
    step_n(5);
    cw(0x02);                   /* quick stop (option 2): a ramp on 0x6085, 1000 rpm/s */
    step_n(300);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    assert_true(s.stopping);
    assert_true(fabsf(speed_rpm() - 300.0f) < 2.0f);
    step_n(400);
    assert_int_equal(s.state, MC_402_SWITCH_ON_DISABLED);

    /* between two periods: the rotor has just come below 0x606F (csv: into the window) */
    start();
    s.od.velocity_threshold_time = 0u;
    s.od.velocity_window_time = 0u;
    s.od.quick_stop_option = 6;
    s.od.mode = MC_402_MODE_CSV;
    s.od.target_velocity = 300;
    set_rpm(0.0f);
    to_enabled();
    step_n(1);
    set_rpm(200.0f);
    step_n(1);
    assert_false(sw_bit(10));
    set_rpm(290.0f);
    mc_402_controlword(&s, &tm, &cmd);
    assert_true(sw_bit(10));
    set_rpm(0.0f);
    s.od.controlword = 0x02;
    mc_402_controlword(&s, &tm, &cmd);
    assert_int_equal(s.state, MC_402_QUICK_STOP_ACTIVE);
    assert_false(s.stopping);   /* stopped already: the ramp-down is over */
    assert_true(sw_bit(10));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rated_values_that_make_no_sense_read_as_1),
        cmocka_unit_test(test_conversions_round_and_saturate),
        cmocka_unit_test(test_actual_torque_and_current),
        cmocka_unit_test(test_indeterminate_torque_reads_0),
        cmocka_unit_test(test_bumpless_into_torque_control),
        cmocka_unit_test(test_target_at_its_limit_is_not_limited),
        cmocka_unit_test(test_pv_ramp_through_zero),
        cmocka_unit_test(test_period_out_of_range_passes_no_time),
        cmocka_unit_test(test_standstill_and_window_limits),
        cmocka_unit_test(test_stop_deceleration_floor),
        cmocka_unit_test(test_stop_time_bound),
        cmocka_unit_test(test_run_entry_start_speed),
        cmocka_unit_test(test_run_entry_torque_from_0),
        cmocka_unit_test(test_quick_stop_hold_at_0),
        cmocka_unit_test(test_torque_demand_restarts_from_0),
        cmocka_unit_test(test_pv_halt_holds_exactly_0),
        cmocka_unit_test(test_only_the_four_modes),
        cmocka_unit_test(test_zero_times_still_need_the_condition),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
