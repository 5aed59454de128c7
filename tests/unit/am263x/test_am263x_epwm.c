/* AM263x ePWM driver against RAM register fakes: period and dead band in counts for 10/20 kHz and
 * 0.5/2 us at the 200 MHz EPWMCLK, the refused configurations, the time-base / sync / action-
 * qualifier / dead-band / trip-zone / event-trigger register values, the CMPA of the duties (and
 * that the action qualifier as programmed really gives the on-fraction: a counter walked through
 * one up-down period with the programmed CAU/CAD actions), the trip as the outputs-off state. */
#include "../mc_test.h"
#include <string.h>

#include "am263x/port.h"
#include "am263x/regs_epwm.h"
#include "am263x/regs_soc.h"

static uint8_t epwm_ram[3][0x1000] __attribute__((aligned(8)));
static uint8_t ctrl_ram[0x2000] __attribute__((aligned(8)));
static hal_pwm_t pwm;

static uint16_t r16(int m, uint32_t off)
{
    uint16_t v;
    memcpy(&v, &epwm_ram[m][off], 2);
    return v;
}
static void w16(int m, uint32_t off, uint16_t v)
{
    memcpy(&epwm_ram[m][off], &v, 2);
}
static uint32_t ctrl32(uint32_t off)
{
    uint32_t v;
    memcpy(&v, &ctrl_ram[off], 4);
    return v;
}

static int setup(void **st)
{
    (void)st;
    memset(epwm_ram, 0xA5, sizeof epwm_ram);   /* not zero: every register the test checks is written */
    memset(ctrl_ram, 0, sizeof ctrl_ram);
    memset(&pwm, 0, sizeof pwm);
    for (int k = 0; k < 3; ++k) {
        pwm.epwm[k] = (uintptr_t)epwm_ram[k];
    }
    pwm.ctrl = (uintptr_t)ctrl_ram;
    pwm.clk_hz = AM263X_EPWMCLK_HZ;
    return 0;
}

static void test_timing_values(void **st)
{
    (void)st;
    static const struct {
        float f, dt;
        uint16_t prd, db;
    } c[] = {
        {10000.0f, 0.5e-6f, 10000u, 100u},   /* 200 MHz / (2 * 10 kHz), 0.5 us * 200 MHz */
        {10000.0f, 2.0e-6f, 10000u, 400u},
        {20000.0f, 0.5e-6f, 5000u, 100u},
        {20000.0f, 2.0e-6f, 5000u, 400u},
    };
    for (size_t k = 0; k < sizeof c / sizeof c[0]; ++k) {
        setup(NULL);
        assert_true(am263x_pwm_init(&pwm, c[k].f, c[k].dt));
        for (int m = 0; m < 3; ++m) {
            assert_int_equal(r16(m, EPWM_TBPRD), c[k].prd);
            assert_int_equal(r16(m, EPWM_DBRED), c[k].db);
            assert_int_equal(r16(m, EPWM_DBFED), c[k].db);
            assert_int_equal(r16(m, EPWM_CMPA_HI), c[k].prd / 2u);   /* 50 % until the first duties */
        }
        assert_near(hal_pwm_period_s(&pwm), 1.0 / c[k].f, 1e-9);
        assert_near(hal_pwm_dead_time_s(&pwm), c[k].dt, 1e-12);
    }
}

static void test_refused_but_tripped(void **st)
{
    (void)st;
    /* 1 kHz: TBPRD 100000 > 16 bits; 1.5 MHz: TBPRD 67 < 100; 30 us at 20 kHz: above a quarter
     * period; 90 us at 2 kHz: 18000 counts > 14 bits; negative and NaN; no dead time (shoot-
     * through) and 0.1 us = 20 counts, below the floor AM263X_PWM_DB_MIN (40) */
    const float bad[][2] = {{1000.0f, 1e-6f}, {1.5e6f, 0.3e-6f}, {20000.0f, 30e-6f}, {2000.0f, 90e-6f},
                            {20000.0f, -1e-6f}, {NAN, 1e-6f}, {20000.0f, NAN}, {0.0f, 1e-6f},
                            {20000.0f, 0.0f}, {20000.0f, 0.1e-6f}, {20000.0f, 0.195e-6f}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        setup(NULL);
        assert_false(am263x_pwm_init(&pwm, bad[k][0], bad[k][1]));
        for (int m = 0; m < 3; ++m) {
            assert_int_equal(r16(m, EPWM_TZCTL), 0x000A);       /* TZA = TZB = low */
            assert_int_equal(r16(m, EPWM_TZFRC), EPWM_TZ_OST);  /* one-shot trip forced */
        }
    }
    /* the largest dead band that fits: 14 bits at a low frequency */
    uint16_t prd, db;
    assert_true(am263x_pwm_timing(AM263X_EPWMCLK_HZ, 1526.0f, 81.9e-6f, &prd, &db));
    assert_int_equal(prd, 65531);
    assert_int_equal(db, 16380);
    assert_false(am263x_pwm_timing(AM263X_EPWMCLK_HZ, 1526.0f, 82.0e-6f, &prd, &db));   /* 16400 */
    /* the floor itself: 0.2 us = 40 counts */
    assert_true(am263x_pwm_timing(AM263X_EPWMCLK_HZ, 20000.0f, 0.2e-6f, &prd, &db));
    assert_int_equal(db, AM263X_PWM_DB_MIN);
}

static void test_mode_registers(void **st)
{
    (void)st;
    setup(NULL);
    assert_true(am263x_pwm_init(&pwm, 20000.0f, 1e-6f));
    /* master: stopped, up-down later, dividers 1 (HSPCLKDIV 0), shadowed TBPRD, on a debugger
     * halt a soft stop at the end of the cycle (FREE_SOFT = 1: counter zero, A low, B high) */
    assert_int_equal(r16(0, EPWM_TBCTL), 0x4003);
    /* slaves: + phase load on sync-in, count up after it */
    assert_int_equal(r16(1, EPWM_TBCTL), 0x6007);
    assert_int_equal(r16(2, EPWM_TBCTL), 0x6007);
    assert_int_equal(r16(0, EPWM_EPWMSYNCINSEL), 0);
    assert_int_equal(r16(1, EPWM_EPWMSYNCINSEL), 1);   /* SYNCOUT of ePWM0 */
    assert_int_equal(r16(2, EPWM_EPWMSYNCINSEL), 1);
    assert_int_equal(r16(0, EPWM_EPWMSYNCOUTEN), 0x0002);   /* sync-out at counter zero */
    for (int m = 0; m < 3; ++m) {
        assert_int_equal(r16(m, EPWM_CMPCTL), 0);        /* CMPA shadow, loaded at zero */
        assert_int_equal(r16(m, EPWM_AQCTLA), 0x0060);   /* CAU set, CAD clear */
        assert_int_equal(r16(m, EPWM_AQCTLB), 0);
        assert_int_equal(r16(m, EPWM_DBCTL), 0x000B);    /* AHC: RED+FED, B inverted, A source */
        assert_int_equal(r16(m, EPWM_TZCTL), 0x000A);
        assert_int_equal(r16(m, EPWM_TZFRC), EPWM_TZ_OST);
        assert_int_equal(r16(m, EPWM_TZSEL), 0x0100);   /* TZ1 (the hardware trip) one-shot */
        uint32_t tbphs;
        memcpy(&tbphs, &epwm_ram[m][EPWM_TBPHS], 4);
        assert_int_equal(tbphs, 0);
    }
    assert_int_equal(r16(0, EPWM_ETSEL), 0x0900);   /* SOCA enabled, at counter zero */
    assert_int_equal(r16(0, EPWM_ETPS), 0x0100);    /* every period */
    assert_int_equal(r16(1, EPWM_ETSEL), 0);
    /* time-base clocks off while configured; the lock closed again */
    assert_int_equal(ctrl32(AM263X_CTRLSS_EPWM_CLKSYNC) & 7u, 0);
    assert_int_equal(ctrl32(AM263X_LOCK0_KICK0), 0);

    am263x_pwm_start(&pwm);
    for (int m = 0; m < 3; ++m) {
        assert_int_equal(r16(m, EPWM_TBCTL) & 3u, 2u);   /* up-down */
    }
    assert_int_equal(r16(0, EPWM_TBCTL), 0x4002);
    assert_int_equal(ctrl32(AM263X_CTRLSS_EPWM_CLKSYNC) & 7u, 7u);
    assert_int_equal(ctrl32(AM263X_LOCK0_KICK1), 0);
    /* the outputs stay tripped until enabled */
    assert_int_equal(r16(0, EPWM_TZFRC), EPWM_TZ_OST);
}

/* High fraction of output A over one up-down period (counter 0..TBPRD..0, one count per step)
 * with the actions AQCTLA programs at CAU and CAD; A starts as it is at counter zero. */
static double a_high_fraction(uint16_t aq, uint16_t cmpa, uint16_t prd, int a0)
{
    const unsigned cau = (aq >> 4) & 3u, cad = (aq >> 6) & 3u;
    int a = a0;
    long high = 0;
    for (long t = 0; t < 2L * prd; ++t) {
        const long ctr = t <= prd ? t : 2L * prd - t;
        const int up = t < prd;
        if (ctr == cmpa) {
            const unsigned act = up ? cau : cad;
            if (act == 1u) a = 0;
            if (act == 2u) a = 1;
        }
        high += a;
    }
    return (double)high / (2.0 * prd);
}

static void test_duties(void **st)
{
    (void)st;
    setup(NULL);
    assert_true(am263x_pwm_init(&pwm, 10000.0f, 1e-6f));   /* TBPRD 10000 */
    hal_pwm_set_duties(&pwm, 0.25f, 0.5f, 0.9f);
    assert_int_equal(r16(0, EPWM_CMPA_HI), 7500);
    assert_int_equal(r16(1, EPWM_CMPA_HI), 5000);
    assert_int_equal(r16(2, EPWM_CMPA_HI), 1000);
    const float d[3] = {0.25f, 0.5f, 0.9f};
    for (int m = 0; m < 3; ++m) {
        /* at counter zero A is low (V0 at the sampling instant): start low */
        assert_near(a_high_fraction(r16(m, EPWM_AQCTLA), r16(m, EPWM_CMPA_HI), 10000u, 0), d[m], 1e-4);
    }
    /* clamps and a NaN, counted */
    hal_pwm_set_duties(&pwm, -0.3f, 1.7f, NAN);
    assert_int_equal(r16(0, EPWM_CMPA_HI), 10000);   /* 0 */
    assert_int_equal(r16(1, EPWM_CMPA_HI), AM263X_PWM_CMPA_MIN);   /* 1 -> the maximum duty */
    assert_int_equal(r16(2, EPWM_CMPA_HI), 5000);    /* NaN -> 0.5 */
    assert_int_equal(pwm.clamped, 2);
    assert_int_equal(pwm.nonfinite, 1);
    hal_pwm_set_duties(&pwm, INFINITY, 0.5f, -INFINITY);
    assert_int_equal(r16(0, EPWM_CMPA_HI), 5000);
    assert_int_equal(pwm.nonfinite, 3);
    /* rounding to the nearest count */
    hal_pwm_set_duties(&pwm, 0.12344f, 0.00004f, 0.99996f);
    assert_int_equal(r16(0, EPWM_CMPA_HI), 8766);
    assert_int_equal(r16(1, EPWM_CMPA_HI), 10000);
    assert_int_equal(r16(2, EPWM_CMPA_HI), AM263X_PWM_CMPA_MIN);
    /* never CMPA 0 (TI: >= 1 with load at zero); the maximum duty 1 - CMPA_MIN / TBPRD = 99 % at
     * TBPRD 10000, a low-side pulse every period for the bootstrap supplies */
    hal_pwm_set_duties(&pwm, 1.0f, 0.99f, 0.995f);
    assert_int_equal(r16(0, EPWM_CMPA_HI), AM263X_PWM_CMPA_MIN);
    assert_int_equal(r16(1, EPWM_CMPA_HI), 100);
    assert_int_equal(r16(2, EPWM_CMPA_HI), AM263X_PWM_CMPA_MIN);
}

static void test_enable_is_the_trip(void **st)
{
    (void)st;
    setup(NULL);
    assert_true(am263x_pwm_init(&pwm, 20000.0f, 1e-6f));
    for (int m = 0; m < 3; ++m) {
        w16(m, EPWM_TZFRC, 0);
        w16(m, EPWM_TZCLR, 0);
        w16(m, EPWM_TZFLG, EPWM_TZ_OST);   /* what the hardware shows after the forced trip */
    }
    assert_false(hal_pwm_enabled(&pwm));
    hal_pwm_enable(&pwm, true);
    for (int m = 0; m < 3; ++m) {
        assert_int_equal(r16(m, EPWM_TZCLR), EPWM_TZ_OST | EPWM_TZ_INT);
        assert_int_equal(r16(m, EPWM_TZFRC), 0);
        w16(m, EPWM_TZFLG, 0);   /* cleared by the hardware */
    }
    assert_true(hal_pwm_enabled(&pwm));
    /* a trip on one module (e.g. a hardware source) is outputs off */
    w16(1, EPWM_TZFLG, EPWM_TZ_OST);
    assert_false(hal_pwm_enabled(&pwm));
    w16(1, EPWM_TZFLG, 0);
    hal_pwm_enable(&pwm, false);
    for (int m = 0; m < 3; ++m) {
        assert_int_equal(r16(m, EPWM_TZFRC), EPWM_TZ_OST);
        assert_int_equal(r16(m, EPWM_TZCTL), 0x000A);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_timing_values, setup),
        cmocka_unit_test_setup(test_refused_but_tripped, setup),
        cmocka_unit_test_setup(test_mode_registers, setup),
        cmocka_unit_test_setup(test_duties, setup),
        cmocka_unit_test_setup(test_enable_is_the_trip, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
