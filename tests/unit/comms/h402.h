/* The CiA 402 block (mc/cia402.h) on synthetic telemetry, for its focused tests (test_402_*.c):
 * the block, the telemetry it reads, the command it writes, and a small drive model: RUN while
 * enabled (after an optional start-up), IDLE when not, and with `follow` a rotor that turns at
 * the commanded speed. Without `follow` the rotor turns at what the test sets (set_rpm). */
#ifndef TEST_COMMS_H402_H
#define TEST_COMMS_H402_H
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <cmocka.h>
#include <string.h>
#include "mc/cia402.h"
#include "mc/co.h"

#define RPM (60.0f / 6.2831853f)   /* rpm per rad/s */
#define PP 5.0f
#define DT_EXACT (1.0f / 1024.0f)  /* a period whose sums and ramp steps are exact in float */

static mc_402_t s;
static mc_drive_telem_t tm;
static mc_drive_cmd_t cmd;
static struct {
    bool follow;     /* omega follows the speed command (an ideal speed loop) */
    int startup;     /* periods of OFFSET_CAL + INIT_POS after an enable */
    int left;
} drv;

static const mc_402_cfg_t CFG = {.dt = 1e-3f, .pole_pairs = 5, .rated_torque = 29.7f, .rated_current = 13.29f,
                                 .psi_pm = 0.343f, .ld = 10.5e-3f, .lq = 12.9e-3f, .vdc_on = 150.0f,
                                 .max_speed_rpm = 1800.0f, .accel_rpm_s = 1000.0f};

static inline void start_cfg(const mc_402_cfg_t *c)
{
    memset(&tm, 0, sizeof tm);
    memset(&cmd, 0, sizeof cmd);
    tm.state = MC_STATE_IDLE;
    tm.vdc = 300.0f;
    drv.follow = true;
    drv.startup = 0;
    drv.left = 0;
    mc_402_init(&s, c);
}

static inline void start(void)
{
    start_cfg(&CFG);
}

/* CFG with the exact period DT_EXACT */
static inline void start_exact(void)
{
    mc_402_cfg_t c = CFG;
    c.dt = DT_EXACT;
    start_cfg(&c);
}

/* The drive's answer to the command, seen by the next step. Fault states are the test's. */
static inline void drive_model(void)
{
    if (tm.state == MC_STATE_FAULT || tm.state == MC_STATE_FAULT_REACTION) {
        return;
    }
    if (!cmd.enable) {
        tm.state = MC_STATE_IDLE;
        drv.left = drv.startup;
        return;
    }
    if (drv.left > 0) {
        tm.state = drv.left > drv.startup / 2 ? MC_STATE_OFFSET_CAL : MC_STATE_INIT_POS;
        drv.left--;
        return;
    }
    tm.state = MC_STATE_RUN;
    if (drv.follow && cmd.mode == MC_MODE_SPEED) {
        tm.omega = cmd.speed_ref * PP;
    }
}

static inline void step_n(int n)
{
    for (int k = 0; k < n; ++k) {
        mc_402_step(&s, &tm, &cmd);
        drive_model();
    }
}

/* The statusword's state bits 0-6 and the remote bit 9 (Table 30 values with remote). */
static inline unsigned sw(void)
{
    return s.od.statusword & 0x027Fu;
}

static inline bool sw_bit(unsigned bit)
{
    return (s.od.statusword & (1u << bit)) != 0u;
}

/* A controlword and one step; the statusword as sw(). */
static inline unsigned cw(uint16_t w)
{
    s.od.controlword = w;
    step_n(1);
    return sw();
}

static inline void to_enabled(void)
{
    assert_int_equal(cw(0x06), 0x0221);
    assert_int_equal(cw(0x07), 0x0233);
    assert_int_equal(cw(0x0F), 0x0237);
}

static inline float speed_rpm(void)   /* the commanded speed [rpm mechanical] */
{
    return cmd.speed_ref * RPM;
}

static inline void set_rpm(float rpm)   /* the rotor's speed [rpm mechanical], without follow */
{
    drv.follow = false;
    tm.omega = rpm / RPM * PP;
}

#endif
