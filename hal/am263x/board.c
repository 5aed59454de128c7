/* Board bring-up of the AM263x port (hal/board.h) on the LP-AM263 LaunchPad: the one instance of
 * each port struct with the real base addresses (am263x/regs_soc.h), hal_board_init / _start /
 * _idle, and the ADC end-of-conversion handler the VIM vectors to.
 *
 * Globals: the port structs below (what a HAL handle points to), and the two words the interrupt
 * wiring strictly needs: the function and context given to hal_board_attach_isr, which the EOC
 * handler (called from the IRQ entry in startup.S, no argument) must find.
 *
 * Set here (the SBL leaves them at reset): the MCAN0 functional clock (80 MHz), the RTI0 and WDT0
 * clocks (25 MHz crystal) in MSS_RCM, the pads of ePWM0-2 A/B, eQEP0 A/B/INDEX and MCAN0 RX/TX,
 * the CAN transceiver's standby GPIO driven low, and the hardware trip input's pad (GPIO11 on
 * SPI0_CS0, input, pull-up) (LP-AM263 wiring and mux modes: am263x/regs_soc.h).
 * The ePWM pads are pulled-down GPIOs until am263x_pwm_init has forced the trip, and get the ePWM
 * function only then (outputs low).
 * The ADC inputs are dedicated analog pins (no IOMUX register). ePWM/eQEP/ADC run from SYSCLK
 * (200 MHz) with their own dividers (epwm.c TBCTL, adc.c ADCCTL2, eqep.c).
 * Left as TI's SBL configured them: the PLLs, SYSCLK and the R5F clock (Bootloader_socConfigurePll),
 * the QSPI clock and its memory-mapped read setup (SPI_SETUP0). */
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
static hal_adc_t adc0 = {
    .adc = {AM263X_ADC_BASE(0u), AM263X_ADC_BASE(1u), AM263X_ADC_BASE(2u)},
    .result = {AM263X_ADC_RESULT_BASE(0u), AM263X_ADC_RESULT_BASE(1u), AM263X_ADC_RESULT_BASE(2u)},
};
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

/* pad, value: ePWM0-2 A/B first (the six bridge gates), then eQEP0 and MCAN0 */
#define PAD_FN(fn) (uint16_t)((fn) | AM263X_PAD_NOPULL | AM263X_PAD_SLEW_LOW)
#define N_PWM_PADS 6u
static const uint16_t pads[][2] = {
    {AM263X_PAD_EPWM_A(0u), PAD_FN(AM263X_PAD_FN_EPWM)}, {AM263X_PAD_EPWM_B(0u), PAD_FN(AM263X_PAD_FN_EPWM)},
    {AM263X_PAD_EPWM_A(1u), PAD_FN(AM263X_PAD_FN_EPWM)}, {AM263X_PAD_EPWM_B(1u), PAD_FN(AM263X_PAD_FN_EPWM)},
    {AM263X_PAD_EPWM_A(2u), PAD_FN(AM263X_PAD_FN_EPWM)}, {AM263X_PAD_EPWM_B(2u), PAD_FN(AM263X_PAD_FN_EPWM)},
    {AM263X_PAD_EQEP0_A, PAD_FN(AM263X_PAD_FN_EQEP)},    {AM263X_PAD_EQEP0_B, PAD_FN(AM263X_PAD_FN_EQEP)},
    {AM263X_PAD_EQEP0_INDEX, PAD_FN(AM263X_PAD_FN_EQEP)}, {AM263X_PAD_MCAN0_RX, PAD_FN(AM263X_PAD_FN_MCAN)},
    {AM263X_PAD_MCAN0_TX, PAD_FN(AM263X_PAD_FN_MCAN)},   {AM263X_PAD_EPWM4_A, PAD_FN(AM263X_PAD_GPIO)},
    /* the trip input: the gate driver's open-drain nFAULT, active low (epwm.c: TZ1 trips on low).
     * Pulled up: an open-drain line reads high only through a pull, so a pull-down would hold the
     * trip for ever. The cost: an nFAULT wire that is broken reads 'no fault' and loses the
     * hardware trip (the software protection and the watchdog remain; the bring-up checklist
     * tests the trip by pulling the line low). An absent driver switches no gate. */
    {AM263X_PAD_SPI0_CS0, (uint16_t)(AM263X_PAD_GPIO | AM263X_PAD_PULLUP | AM263X_PAD_SLEW_LOW)},
};

/* pads[first..end-1]: their function, or (safe) a GPIO with the pull-down on (PI = 0, PUPDSEL =
 * 0) and no override: a gate input held low, pulled down as an input, driven low as an output
 * (OUT_DATA resets to 0, cslr_gpio.h) */
static void pads_set(uint32_t first, uint32_t end, bool safe)
{
    const uintptr_t io = AM263X_IOMUX_BASE;
    am263x_wr32(io + AM263X_IOMUX_KICK0, AM263X_IOMUX_KICK0_UNLOCK);
    am263x_wr32(io + AM263X_IOMUX_KICK1, AM263X_IOMUX_KICK1_UNLOCK);
    for (uint32_t k = first; k < end; ++k) {
        am263x_wr32(io + pads[k][0], safe ? (AM263X_PAD_GPIO | AM263X_PAD_SLEW_LOW) : pads[k][1]);
    }
    am263x_wr32(io + AM263X_IOMUX_KICK0, AM263X_KICK_LOCK);
    am263x_wr32(io + AM263X_IOMUX_KICK1, AM263X_KICK_LOCK);
}

/* A module clock as TI's SOC_rcmSetPeripheralClock sets it: divider, then source, each read back */
static void rcm_clock(uint32_t src_reg, uint32_t div_reg, uint32_t src, uint32_t div)
{
    const uintptr_t r = AM263X_MSS_RCM_BASE;
    am263x_wr32(r + div_reg, div);
    while (am263x_rd32(r + div_reg) != div) {
    }
    am263x_wr32(r + src_reg, src);
    while (am263x_rd32(r + src_reg) != src) {
    }
}

static hal_isr_fn_t isr_fn;
static void *isr_ctx;

static void adc_reference_on(void)
{
    /* ADC0..2 share reference buffer 0; the comparators: ADC0 bits 2:0, ADC1/2 bits 6:4
     * (SOC_enableAdcReference) */
    am263x_mmr_unlock(soc.top);
    am263x_wr16(soc.top + AM263X_TOP_ADC_REFBUF0_CTRL, 0x7u);
    am263x_wr16(soc.top + AM263X_TOP_ADC_REF_COMP_CTRL,
                (uint16_t)(am263x_rd16(soc.top + AM263X_TOP_ADC_REF_COMP_CTRL) | 0x77u));
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
    /* outputs off first, whatever follows: gate pads pulled low, then the trip forced, and only
     * then the ePWM function on the pads */
    pads_set(0u, N_PWM_PADS, true);
    if (!am263x_pwm_init(&pwm0, cfg->f_pwm_hz, cfg->dead_time_s)) {
        return false;
    }
    pads_set(0u, sizeof pads / sizeof pads[0], false);
    /* the CAN transceiver out of standby: its STB GPIO an output driven low */
    {
        const uintptr_t g = AM263X_GPIO0_BASE;
        const uint32_t n = AM263X_CAN_STB_GPIO / 32u, bit = 1u << (AM263X_CAN_STB_GPIO % 32u);
        am263x_wr32(g + AM263X_GPIO_CLR_DATA(n), bit);
        am263x_wr32(g + AM263X_GPIO_DIR(n), am263x_rd32(g + AM263X_GPIO_DIR(n)) & ~bit);
    }
    am263x_mmr_unlock(AM263X_MSS_RCM_BASE);
    rcm_clock(AM263X_RCM_MCAN0_CLK_SRC_SEL, AM263X_RCM_MCAN0_CLK_DIV_VAL, AM263X_RCM_SRC_MCAN_CORE_HSDIV0,
              AM263X_RCM_DIV(AM263X_CORE_HSDIV0_HZ / AM263X_MCAN_FCLK_HZ));
    rcm_clock(AM263X_RCM_RTI0_CLK_SRC_SEL, AM263X_RCM_RTI0_CLK_DIV_VAL, AM263X_RCM_SRC_XTALCLK,
              AM263X_RCM_DIV(AM263X_XTAL_HZ / AM263X_RTI_CLK_HZ));
    /* the watchdog's timeout (port.h) assumes 25 MHz: the crystal, whatever ran before */
    rcm_clock(AM263X_RCM_WDT0_CLK_SRC_SEL, AM263X_RCM_WDT0_CLK_DIV_VAL, AM263X_RCM_SRC_XTALCLK,
              AM263X_RCM_DIV(AM263X_XTAL_HZ / AM263X_WDT_CLK_HZ));
    am263x_mmr_lock(AM263X_MSS_RCM_BASE);
    am263x_can_timing_t ct;
    const uint8_t ch[4] = {cfg->adc_ch_i[0], cfg->adc_ch_i[1], cfg->adc_ch_i[2], cfg->adc_ch_vdc};
    if (cfg->qep_counts_per_rev < 4u || !am263x_can_bit_timing(cfg->can_bitrate, AM263X_MCAN_FCLK_HZ, &ct)) {
        return false;
    }
    if (!time_up) {
        am263x_time_init(&tim0, AM263X_RTI_CLK_HZ);
        time_up = true;
    }
    /* init powers ADC0..2 together, ADC2 last: if it is on, all are */
    const bool adc_was_off = (am263x_rd16(adc0.adc[2] + ADC_ADCCTL1) & ADC_ADCCTL1_ADCPWDNZ) == 0u;
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
    am263x_nvm_init(&nvm0, AM263X_QSPI_BASE, AM263X_FLASH_WIN_BASE, &am263x_s25fl128s, AM263X_NVM_FLASH_OFF,
                    AM263X_NVM_BYTES);
    nvm0.wdg = &wdg0;   /* a store's erase waits with the watchdog serviced (hal/watchdog.h) */
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
    wdg0.isr_runs = wdg0.isr_runs + 1u;   /* the progress hal_wdg_service looks for */
    if (fn != 0) {
        fn(isr_ctx);
    }
    /* acknowledged after the control ISR: an EOC during it sets ADCINTOVF (hal_adc_read) */
    am263x_adc_ack(&adc0);
    am263x_vim_clear(soc.vim, AM263X_IRQ_ADC_EOC);
}
