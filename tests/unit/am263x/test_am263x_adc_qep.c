/* AM263x ADC and eQEP drivers against RAM register fakes: the ADCs' trigger configuration (one
 * phase current per module ADC0..2 on SOC0, Vdc on ADC0 SOC1, all triggered by ePWM0 SOCA,
 * ADC0's ADCINT1 from its last SOC), the inputs each module has, the sample and its overrun flag; the eQEP's configuration, the speed from latched counts (unit timer) and from
 * a captured period (capture unit), the HAL sample; the RTI time base; the VIM and crossbar
 * routing of the ADC interrupt. */
#include "../mc_test.h"
#include <string.h>

#include "am263x/port.h"
#include "am263x/regs_adc.h"
#include "am263x/regs_eqep.h"
#include "am263x/regs_rti.h"
#include "am263x/regs_soc.h"
#include "am263x/regs_vim.h"

static uint8_t adc_ram[0x3000] __attribute__((aligned(8)));   /* ADC0..2 */
static uint8_t res_ram[0x3000] __attribute__((aligned(8)));
static uint8_t qep_ram[0x1000] __attribute__((aligned(8)));
static uint8_t rti_ram[0x1000] __attribute__((aligned(8)));
static uint8_t vim_ram[0x3000] __attribute__((aligned(8)));
static uint8_t xbar_ram[0x1000] __attribute__((aligned(8)));

static uint32_t rd(const uint8_t *ram, uint32_t off, unsigned size)
{
    uint32_t v = 0;
    memcpy(&v, ram + off, size);
    return v;
}
static void wr(uint8_t *ram, uint32_t off, unsigned size, uint32_t v)
{
    memcpy(ram + off, &v, size);
}

static hal_adc_t fake_adc(void)
{
    hal_adc_t adc;
    for (uint32_t m = 0; m < 3; ++m) {
        adc.adc[m] = (uintptr_t)adc_ram + 0x1000u * m;
        adc.result[m] = (uintptr_t)res_ram + 0x1000u * m;
    }
    adc.overruns = 0u;
    return adc;
}

static void test_adc_trigger_config(void **st)
{
    (void)st;
    memset(adc_ram, 0x5A, sizeof adc_ram);
    hal_adc_t adc = fake_adc();
    const uint8_t ch[4] = {5u, 5u, 0u, 2u};   /* ia ADC0_AIN5, ib ADC1_AIN5, ic ADC2_AIN0, Vdc ADC0_AIN2 */
    assert_true(am263x_adc_init(&adc, ch));
    for (uint32_t m = 0; m < 3; ++m) {
        const uint8_t *r = adc_ram + 0x1000u * m;
        /* SOC0 of every module: its phase current, on the same trigger: sampled together */
        const uint32_t n_soc = m == 0 ? 2u : 1u;
        for (uint32_t n = 0; n < n_soc; ++n) {
            const uint32_t ctl = rd(r, ADC_ADCSOCCTL(n), 4);
            assert_int_equal((ctl >> 15) & 0x1Fu, n == 0 ? ch[m] : ch[3]);   /* CHSEL */
            assert_int_equal((ctl >> 20) & 0x7Fu, 0x08u);   /* TRIGSEL = ePWM0 SOCA (SDK ADC_TRIGGER_EPWM0_SOCA) */
            assert_int_equal(ctl & 0x1FFu, 19u);            /* 20-cycle sample window */
        }
        assert_int_equal(rd(r, ADC_ADCSOCCTL(n_soc), 4), 0x5A5A5A5Au);   /* no further SOC touched */
        assert_int_equal(rd(r, ADC_ADCCTL1, 2), 0x0084);    /* EOC pulse, powered */
        assert_int_equal(rd(r, ADC_ADCCTL2, 2), 0x0006);    /* SYSCLK / 4, 12 bit, single-ended */
        assert_int_equal(rd(r, ADC_ADCSOCPRICTL, 2), n_soc);   /* its SOCs in order */
        assert_int_equal(rd(r, ADC_ADCINTSEL1N2, 2), m == 0 ? 1 : 0);   /* ADC0 INT1 <- SOC1, not yet enabled */
        assert_int_equal(rd(r, ADC_ADCINTFLGCLR, 2), 0xF);
        assert_int_equal(rd(r, ADC_ADCINTOVFCLR, 2), 0xF);
    }
    am263x_adc_enable_irq(&adc);
    assert_int_equal(rd(adc_ram, ADC_ADCINTSEL1N2, 2), 0x0021);   /* + INT1E, not continuous */
    assert_int_equal(rd(adc_ram + 0x1000u, ADC_ADCINTSEL1N2, 2), 0);
    /* refused: an input no module has (AIN0..5 only, although CHSEL has 5 bits), Vdc on ia's input */
    const uint8_t bad[][4] = {{0u, 1u, 2u, 6u}, {6u, 1u, 2u, 3u}, {0u, 1u, 31u, 3u}, {3u, 1u, 2u, 3u}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        assert_false(am263x_adc_init(&adc, bad[k]));
    }
}

static void test_adc_sample_and_overrun(void **st)
{
    (void)st;
    memset(adc_ram, 0, sizeof adc_ram);
    hal_adc_t adc = fake_adc();
    /* ADC0: ia, Vdc; ADC1: ib; ADC2: ic; the other results are not ours */
    wr(res_ram, ADC_RESULT(0), 2, 1111u);
    wr(res_ram, ADC_RESULT(1), 2, 4000u);
    wr(res_ram, ADC_RESULT(2), 2, 7u);
    wr(res_ram + 0x1000u, ADC_RESULT(0), 2, 2222u);
    wr(res_ram + 0x1000u, ADC_RESULT(1), 2, 8u);
    wr(res_ram + 0x2000u, ADC_RESULT(0), 2, 3333u);
    hal_adc_sample_t s;
    hal_adc_read(&adc, &s);
    assert_int_equal(s.i[0], 1111);
    assert_int_equal(s.i[1], 2222);
    assert_int_equal(s.i[2], 3333);
    assert_int_equal(s.vdc, 4000);
    assert_false(s.overrun);
    assert_int_equal(rd(adc_ram, ADC_ADCINTOVFCLR, 2), 0);
    wr(adc_ram, ADC_ADCINTOVF, 2, ADC_INT1);
    hal_adc_read(&adc, &s);
    assert_true(s.overrun);
    assert_int_equal(rd(adc_ram, ADC_ADCINTOVFCLR, 2), ADC_INT1);
    assert_int_equal(adc.overruns, 1);
    /* an overflow of another interrupt (INT2) is not ours */
    wr(adc_ram, ADC_ADCINTOVF, 2, 0x2u);
    hal_adc_read(&adc, &s);
    assert_false(s.overrun);
    am263x_adc_ack(&adc);
    assert_int_equal(rd(adc_ram, ADC_ADCINTFLGCLR, 2), ADC_INT1);
}

static void test_qep_config_and_sample(void **st)
{
    (void)st;
    memset(qep_ram, 0xFF, sizeof qep_ram);
    hal_qep_t q = {.eqep = (uintptr_t)qep_ram};
    assert_false(am263x_qep_init(&q, 3u, 200000u));
    assert_false(am263x_qep_init(&q, 4000u, 0u));
    assert_true(am263x_qep_init(&q, 4000u, 200000u));
    assert_int_equal(rd(qep_ram, EQEP_QPOSMAX, 4), 3999);
    assert_int_equal(rd(qep_ram, EQEP_QPOSINIT, 4), 0);
    assert_int_equal(rd(qep_ram, EQEP_QUPRD, 4), 200000);
    assert_int_equal(rd(qep_ram, EQEP_QDECCTL, 2), 0);        /* quadrature count, 4x */
    assert_int_equal(rd(qep_ram, EQEP_QEPCTL, 2), 0x901E);    /* free, PCRM 1, IEL rising, QPEN, QCLM, UTE */
    assert_int_equal(rd(qep_ram, EQEP_QCAPCTL, 2), 0x8072);   /* CEN, CCPS 7, UPPS 2 */
    assert_int_equal(hal_qep_counts_per_rev(&q), 4000);
    wr(qep_ram, EQEP_QPOSCNT, 4, 1234u);
    wr(qep_ram, EQEP_QPOSILAT, 4, 17u);
    wr(qep_ram, EQEP_QEPSTS, 2, EQEP_QEPSTS_QDF);
    hal_qep_sample_t s;
    hal_qep_read(&q, &s);
    assert_int_equal(s.count, 1234);
    assert_int_equal(s.index_count, 17);
    assert_false(s.index_seen);
    wr(qep_ram, EQEP_QEPSTS, 2, EQEP_QEPSTS_FIMF);
    hal_qep_read(&q, &s);
    assert_true(s.index_seen);
}

static void test_qep_speed_from_latches(void **st)
{
    (void)st;
    /* pure parts: wrap and direction */
    assert_int_equal(am263x_qep_delta(3990u, 30u, 4000u, true), 40);
    assert_int_equal(am263x_qep_delta(30u, 3990u, 4000u, false), -40);
    assert_int_equal(am263x_qep_delta(100u, 2100u, 4000u, true), 2000);     /* half a turn: QDF decides */
    assert_int_equal(am263x_qep_delta(100u, 2100u, 4000u, false), -2000);
    assert_int_equal(am263x_qep_delta(500u, 500u, 4000u, true), 0);
    /* 40 counts in 1 ms (200000 cycles at 200 MHz) = 40000 counts/s = 10 rev/s at 4000 counts */
    assert_near(am263x_qep_unit_speed(40, 200000u, 200000000u), 40000.0, 1e-2);
    /* 4 counts per 625 ticks of 200 MHz / 128 (400 us) = 10000 counts/s */
    assert_near(am263x_qep_capture_speed(625u, 2u, 7u, 200000000u, true), 10000.0, 1e-2);
    assert_near(am263x_qep_capture_speed(625u, 2u, 7u, 200000000u, false), -10000.0, 1e-2);
    assert_near(am263x_qep_capture_speed(0u, 2u, 7u, 200000000u, true), 0.0, 0.0);

    /* through the registers: two unit time-outs */
    memset(qep_ram, 0, sizeof qep_ram);
    hal_qep_t q = {.eqep = (uintptr_t)qep_ram};
    assert_true(am263x_qep_init(&q, 4000u, 200000u));
    am263x_qep_speed_t sp;
    assert_false(am263x_qep_poll_speed(&q, &sp));   /* no time-out pending */
    wr(qep_ram, EQEP_QFLG, 2, EQEP_QFLG_UTO);
    wr(qep_ram, EQEP_QPOSLAT, 4, 3990u);
    wr(qep_ram, EQEP_QCPRDLAT, 2, 625u);
    wr(qep_ram, EQEP_QEPSTS, 2, EQEP_QEPSTS_QDF);
    wr(qep_ram, EQEP_QCLR, 2, 0u);
    assert_true(am263x_qep_poll_speed(&q, &sp));
    assert_near(sp.unit_cps, 0.0, 0.0);           /* no previous latch yet */
    assert_true(sp.capture_valid);
    assert_near(sp.capture_cps, 10000.0, 1e-2);
    assert_int_equal(rd(qep_ram, EQEP_QCLR, 2), EQEP_QFLG_UTO | EQEP_QFLG_INT);
    wr(qep_ram, EQEP_QPOSLAT, 4, 30u);            /* wrapped: +40 counts */
    wr(qep_ram, EQEP_QEPSTS, 2, EQEP_QEPSTS_QDF);
    wr(qep_ram, EQEP_QCPRDLAT, 2, 1250u);
    assert_true(am263x_qep_poll_speed(&q, &sp));
    assert_near(sp.unit_cps, 40000.0, 1e-2);
    assert_near(sp.capture_cps, 5000.0, 1e-2);
    /* reversing: QDF 0, the latch back by 25 counts; a capture overflow makes it invalid */
    wr(qep_ram, EQEP_QEPSTS, 2, EQEP_QEPSTS_COEF);
    wr(qep_ram, EQEP_QPOSLAT, 4, 5u);
    assert_true(am263x_qep_poll_speed(&q, &sp));
    assert_near(sp.unit_cps, -25000.0, 1e-2);
    assert_false(sp.capture_valid);
    assert_near(sp.capture_cps, 0.0, 0.0);
    assert_int_equal(rd(qep_ram, EQEP_QEPSTS, 2), EQEP_QEPSTS_COEF);   /* written back: clears it */
}

static void test_time_and_interrupt_routing(void **st)
{
    (void)st;
    memset(rti_ram, 0xEE, sizeof rti_ram);
    hal_time_t t = {.rti = (uintptr_t)rti_ram};
    am263x_time_init(&t, 25000000u);
    assert_int_equal(rd(rti_ram, RTI_RTICPUC0, 4), 24);   /* 25 MHz / 25 = 1 MHz */
    assert_int_equal(rd(rti_ram, RTI_RTIGCTRL, 4), RTI_GCTRL_CNT0EN);
    assert_int_equal(rd(rti_ram, RTI_RTITBCTRL, 4), 0);
    wr(rti_ram, RTI_RTIFRC0, 4, 123456u);
    assert_int_equal(hal_time_us(&t), 123456);

    memset(vim_ram, 0, sizeof vim_ram);
    wr(vim_ram, VIM_INT_MAP(146), 4, 0xFFFFFFFFu);
    wr(vim_ram, VIM_INT_TYPE(146), 4, 0xFFFFFFFFu);
    am263x_vim_route((uintptr_t)vim_ram, 146u, 0u, (uintptr_t)0x70081235u);
    assert_int_equal(VIM_INT_EN(146), 0x488);   /* group 4 */
    assert_int_equal(rd(vim_ram, 0x488, 4), 1u << 18);
    assert_int_equal(rd(vim_ram, 0x48C, 4), 1u << 18);   /* disabled first */
    assert_int_equal(rd(vim_ram, 0x484, 4), 1u << 18);   /* pending cleared */
    assert_int_equal(rd(vim_ram, 0x498, 4), ~(1u << 18));   /* IRQ, not FIQ */
    assert_int_equal(rd(vim_ram, 0x49C, 4), ~(1u << 18));   /* level */
    assert_int_equal(rd(vim_ram, 0x1000 + 4 * 146, 4), 0);
    assert_int_equal(rd(vim_ram, 0x2000 + 4 * 146, 4), 0x70081234u);   /* word-aligned */

    memset(xbar_ram, 0xFF, sizeof xbar_ram);
    am263x_intxbar_route((uintptr_t)xbar_ram, 0u, 2u, 1u);
    assert_int_equal(rd(xbar_ram, 0x100, 4), 0);   /* G0 */
    assert_int_equal(rd(xbar_ram, 0x104, 4), 0);
    assert_int_equal(rd(xbar_ram, 0x108, 4), 1);   /* G2 bit 0: ADC0 INT1 */
    assert_int_equal(rd(xbar_ram, 0x118, 4), 0);   /* G6 */
    assert_int_equal(rd(xbar_ram, 0x140, 4), 0xFFFFFFFFu);   /* output 1 untouched */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_adc_trigger_config),
        cmocka_unit_test(test_adc_sample_and_overrun),
        cmocka_unit_test(test_qep_config_and_sample),
        cmocka_unit_test(test_qep_speed_from_latches),
        cmocka_unit_test(test_time_and_interrupt_routing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
