/* ADC driver of the AM263x port: the three phase currents sampled at the same instant, one per
 * ADC module (ia on ADC0, ib on ADC1, ic on ADC2, each its SOC0), all started by ePWM0 SOCA
 * (counter zero); Vdc on ADC0 SOC1, converted after ia. ADCINT1 of ADC0 at the end of SOC1: by
 * then ADC1 and ADC2 (one conversion each, started with ADC0's SOC0) are done too. The same
 * ePWM SOC starting several ADCs is TI's own pattern (mcupsdk-core examples/drivers/adc/
 * adc_multiple_soc_epwm, am263x-lp: ADC1 and ADC2 on ADC_TRIGGER_EPWM0_SOCA). Register facts:
 * am263x/regs_adc.h (TRM: ADC SOC Principle of Operation, ADC Interrupts, ADC Registers). */
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_adc.h"

static void soc(uintptr_t b, uint32_t n, uint8_t ch)
{
    am263x_wr32(b + ADC_ADCSOCCTL(n), ((uint32_t)ch << ADC_SOCCTL_CHSEL_SHIFT) |
                                          (ADC_TRIG_EPWM_SOCA(0u) << ADC_SOCCTL_TRIGSEL_SHIFT) |
                                          (AM263X_ADC_ACQ_CYCLES - 1u));
}

bool am263x_adc_init(hal_adc_t *adc, const uint8_t ch[4])
{
    for (uint32_t k = 0u; k < 4u; ++k) {
        if (ch[k] >= AM263X_ADC_INPUTS) {
            return false;
        }
    }
    if (ch[3] == ch[0]) {   /* Vdc and ia share ADC0 */
        return false;
    }
    for (uint32_t m = 0u; m < 3u; ++m) {
        const uintptr_t b = adc->adc[m];
        /* ADCCLK = SYSCLK / 4 (50 MHz), 12 bit, single-ended */
        am263x_wr16(b + ADC_ADCCTL2, ADC_ADCCTL2_PRESCALE_DIV4);
        /* interrupt pulse at the end of the conversion, analog part powered */
        am263x_wr16(b + ADC_ADCCTL1, (uint16_t)(ADC_ADCCTL1_INTPULSEPOS | ADC_ADCCTL1_ADCPWDNZ));
        /* SOC0: this module's phase current; ADC0 SOC1: Vdc. High priority: converted in number
         * order at each trigger */
        soc(b, 0u, ch[m]);
        if (m == 0u) {
            soc(b, 1u, ch[3]);
        }
        am263x_wr16(b + ADC_ADCSOCPRICTL, (uint16_t)(m == 0u ? 2u : 1u));
        /* ADCINT1 <- EOC of the module's last SOC, not continuous (a second EOC before the clear
         * is an overflow); ADC0's is enabled by am263x_adc_enable_irq, the others stay off */
        am263x_wr16(b + ADC_ADCINTSEL1N2, (uint16_t)(m == 0u ? AM263X_ADC_LAST_SOC : 0u));
        am263x_wr16(b + ADC_ADCINTFLGCLR, 0x000Fu);
        am263x_wr16(b + ADC_ADCINTOVFCLR, 0x000Fu);
        am263x_wr16(b + ADC_ADCSOCOVFCLR1, 0xFFFFu);
    }
    adc->overruns = 0u;
    return true;
}

void am263x_adc_enable_irq(hal_adc_t *adc)
{
    am263x_wr16(adc->adc[0] + ADC_ADCINTFLGCLR, ADC_INT1);
    am263x_wr16(adc->adc[0] + ADC_ADCINTOVFCLR, ADC_INT1);
    am263x_wr16(adc->adc[0] + ADC_ADCINTSEL1N2, (uint16_t)(AM263X_ADC_LAST_SOC | ADC_INTSEL_INT1E));
}

void am263x_adc_ack(hal_adc_t *adc)
{
    am263x_wr16(adc->adc[0] + ADC_ADCINTFLGCLR, ADC_INT1);
}

/* ---- hal/adc.h */
void hal_adc_read(hal_adc_t *adc, hal_adc_sample_t *out)
{
    for (uint32_t k = 0u; k < 3u; ++k) {
        out->i[k] = am263x_rd16(adc->result[k] + ADC_RESULT(0u));
    }
    out->vdc = am263x_rd16(adc->result[0] + ADC_RESULT(1u));
    /* ADCINTOVF.INT1: an EOC came while ADCINT1 was still set, i.e. before the last ISR had
     * acknowledged it (am263x_adc_ack at the ISR's end) */
    out->overrun = (am263x_rd16(adc->adc[0] + ADC_ADCINTOVF) & ADC_INT1) != 0u;
    if (out->overrun) {
        adc->overruns++;
        am263x_wr16(adc->adc[0] + ADC_ADCINTOVFCLR, ADC_INT1);
    }
}
