/* Board bring-up of the AM263x port (hal/board.h) on the LP-AM263 LaunchPad: the one instance of
 * each port struct with the real base addresses (am263x/regs_soc.h), hal_board_init / _start /
 * _idle, and the ADC end-of-conversion handler the VIM vectors to.
 *
 * Globals: the port structs below (what a HAL handle points to), and the two words the interrupt
 * wiring strictly needs: the function and context given to hal_board_attach_isr, which the EOC
 * handler (called from the IRQ entry in startup.S, no argument) must find.
 *
 * Left as TI's SBL / SOC-init GEL configured them (not written by this port): PLLs and module
 * clocks and their gates (SYSCLK 200 MHz, MCAN0 80 MHz, RTI0 25 MHz: am263x/regs_soc.h; WDT0
 * 25 MHz: am263x/regs_rti.h), the GPIO11 pad of the trip input (docs/porting.md), the pin
 * multiplexing of ePWM0-2 A/B, eQEP0 A/B/I and MCAN0 TX/RX (board-specific IOMUX pads not
 * verified here), the QSPI clock and its memory-mapped read setup (SPI_SETUP0). */
#include "hal/board.h"
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_adc.h"
#include "am263x/regs_epwm.h"
#include "am263x/regs_rti.h"
#include "am263x/regs_soc.h"

#define QEP_UNIT_CLK (AM263X_SYSCLK_HZ / 1000u)   /* eQEP unit timer: 1 ms                    */
#define ADC_POWERUP_LOOPS (AM263X_CPU_HZ / 1000000u * 500u / 2u)   /* >= 500 us at >= 2 cycles
                                                                      per loop iteration        */

static hal_pwm_t pwm0 = {
    .epwm = {AM263X_EPWM_BASE(0u), AM263X_EPWM_BASE(1u), AM263X_EPWM_BASE(2u)},
    .ctrl = AM263X_CTRLSS_CTRL_BASE,
    .clk_hz = AM263X_EPWMCLK_HZ,
};
static hal_adc_t adc0 = {.adc = AM263X_ADC_BASE(0u), .result = AM263X_ADC_RESULT_BASE(0u)};
static hal_qep_t qep0 = {.eqep = AM263X_EQEP_BASE(0u)};
static hal_time_t tim0 = {.rti = AM263X_RTI_BASE(0u)};
static hal_can_t can0 = {
    .ss = AM263X_MCAN_CFG_BASE(0u),
    .core = AM263X_MCAN_CFG_BASE(0u) + MCAN_CORE_OFFSET,
    .ram = AM263X_MCAN_MSGRAM_BASE(0u),
};
static hal_nvm_t nvm0;
static hal_wdg_t wdg0 = {.wdt = AM263X_WDT0_BASE};
static const struct {
    uintptr_t vim, xbar, top;
} soc = {AM263X_VIM_BASE, AM263X_INTXBAR_BASE, AM263X_TOP_CTRL_BASE};
static bool time_up;

static hal_isr_fn_t isr_fn;
static void *isr_ctx;

static void adc_reference_on(void)
{
    /* ADC0..2 share reference buffer 0; ADC0's comparators are bits 2:0 (SOC_enableAdcReference) */
    am263x_mmr_unlock(soc.top);
    am263x_wr16(soc.top + AM263X_TOP_ADC_REFBUF0_CTRL, 0x7u);
    am263x_wr16(soc.top + AM263X_TOP_ADC_REF_COMP_CTRL,
                (uint16_t)(am263x_rd16(soc.top + AM263X_TOP_ADC_REF_COMP_CTRL) | 0x7u));
    am263x_mmr_lock(soc.top);
}

static void spin(uint32_t loops)
{
    for (uint32_t k = 0u; k < loops; ++k) {
        __asm volatile("" ::: "memory");
    }
}

bool hal_board_init(const hal_board_cfg_t *cfg, hal_board_t *out)
{
    /* outputs off first, whatever follows */
    if (!am263x_pwm_init(&pwm0, cfg->f_pwm_hz, cfg->dead_time_s)) {
        return false;
    }
    am263x_can_timing_t ct;
    const uint8_t ch[4] = {cfg->adc_ch_i[0], cfg->adc_ch_i[1], cfg->adc_ch_i[2], cfg->adc_ch_vdc};
    if (cfg->qep_counts_per_rev < 4u || !am263x_can_bit_timing(cfg->can_bitrate, AM263X_MCAN_FCLK_HZ, &ct)) {
        return false;
    }
    if (!time_up) {
        am263x_time_init(&tim0, AM263X_RTI_CLK_HZ);
        time_up = true;
    }
    const bool adc_was_off = (am263x_rd16(adc0.adc + ADC_ADCCTL1) & ADC_ADCCTL1_ADCPWDNZ) == 0u;
    adc_reference_on();
    if (!am263x_adc_init(&adc0, ch)) {
        return false;
    }
    if (adc_was_off) {
        spin(ADC_POWERUP_LOOPS);   /* analog power-up before the first conversion */
    }
    am263x_intxbar_route(soc.xbar, AM263X_INTXBAR_OUT_ADC, AM263X_INTXBAR_GROUP_ADC, AM263X_INTXBAR_ADC0_INT1);
    /* the hardware trip: GPIO11 (the gate driver's nFAULT) -> INPUT XBAR 0 -> TZ1 (epwm.c) */
    am263x_wr32(AM263X_INPUTXBAR_BASE + AM263X_INPUTXBAR_GSEL(0u), 0u);
    am263x_wr32(AM263X_INPUTXBAR_BASE + AM263X_INPUTXBAR_G0(0u), AM263X_TRIP_GPIO);
    (void)am263x_qep_init(&qep0, cfg->qep_counts_per_rev, QEP_UNIT_CLK);
    /* a controller that does not come up leaves can0 refusing (bus-off); the drive runs on */
    (void)am263x_can_init(&can0, cfg->can_bitrate, AM263X_MCAN_FCLK_HZ);
    am263x_nvm_init(&nvm0, AM263X_QSPI_BASE, AM263X_FLASH_WIN_BASE, AM263X_NVM_FLASH_OFF);
    out->adc = &adc0;
    out->pwm = &pwm0;
    out->qep = &qep0;
    out->can = &can0;
    out->nvm = &nvm0;
    out->time = &tim0;
    out->wdg = &wdg0;
    return true;
}

void hal_board_attach_isr(hal_isr_fn_t fn, void *ctx)
{
    isr_ctx = ctx;
    isr_fn = fn;
}

void hal_board_start(void)
{
    am263x_vim_route(soc.vim, AM263X_IRQ_ADC_EOC, 0u, (uintptr_t)&am263x_adc_eoc_isr);
    am263x_adc_enable_irq(&adc0);
    am263x_pwm_start(&pwm0);   /* counters run, SOCA at each counter zero; outputs still tripped */
    am263x_wdt_start(wdg0.wdt, AM263X_WDT_PRLD);   /* from here the loop must progress */
#if defined(__arm__)
    __asm volatile("cpsie i" ::: "memory");
#endif
}

void hal_wdg_kick(hal_wdg_t *wdg)
{
    am263x_wdt_kick(wdg->wdt);
}

float hal_board_min_dead_time_s(void)
{
    return (float)AM263X_PWM_DB_MIN / (float)AM263X_EPWMCLK_HZ;
}

void hal_board_idle(void)
{
#if defined(__arm__)
    __asm volatile("wfi" ::: "memory");
#endif
}

void am263x_adc_eoc_isr(void)
{
    const hal_isr_fn_t fn = isr_fn;
    if (fn != 0) {
        fn(isr_ctx);
    }
    /* acknowledged after the control ISR: an EOC during it sets ADCINTOVF (hal_adc_read) */
    am263x_adc_ack(&adc0);
    am263x_vim_clear(soc.vim, AM263X_IRQ_ADC_EOC);
}
