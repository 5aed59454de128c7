/* ADC driver of the AM263x port: ADC0, SOC0..3 = ia, ib, ic, Vdc, triggered by ePWM0 SOCA (counter
 * zero), converted in SOC order (SOC0..3 high priority), ADCINT1 at the end of SOC3. Register
 * facts: am263x/regs_adc.h (TRM: ADC SOC Principle of Operation, ADC Interrupts, ADC Registers). */
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_adc.h"

bool am263x_adc_init(hal_adc_t *adc, const uint8_t ch[4])
{
    for (uint32_t k = 0u; k < 4u; ++k) {
        if (ch[k] > ADC_SOCCTL_CHSEL_MASK) {
            return false;
        }
        for (uint32_t j = 0u; j < k; ++j) {
            if (ch[j] == ch[k]) {
                return false;
            }
        }
    }
    const uintptr_t b = adc->adc;
    /* ADCCLK = SYSCLK / 4 (50 MHz), 12 bit, single-ended */
    am263x_wr16(b + ADC_ADCCTL2, ADC_ADCCTL2_PRESCALE_DIV4);
    /* interrupt pulse at the end of the conversion, analog part powered */
    am263x_wr16(b + ADC_ADCCTL1, (uint16_t)(ADC_ADCCTL1_INTPULSEPOS | ADC_ADCCTL1_ADCPWDNZ));
    /* SOC0..3: channel, trigger ePWM0 SOCA, sample window */
    for (uint32_t k = 0u; k < 4u; ++k) {
        am263x_wr32(b + ADC_ADCSOCCTL(k), ((uint32_t)ch[k] << ADC_SOCCTL_CHSEL_SHIFT) |
                                              (ADC_TRIG_EPWM_SOCA(0u) << ADC_SOCCTL_TRIGSEL_SHIFT) |
                                              (AM263X_ADC_ACQ_CYCLES - 1u));
    }
    /* SOC0..3 high priority: converted in number order at each trigger */
    am263x_wr16(b + ADC_ADCSOCPRICTL, 4u);
    /* ADCINT1 <- EOC of SOC3, not continuous (a second EOC before the clear is an overflow);
     * enabled by am263x_adc_enable_irq */
    am263x_wr16(b + ADC_ADCINTSEL1N2, 3u);
    am263x_wr16(b + ADC_ADCINTFLGCLR, 0x000Fu);
    am263x_wr16(b + ADC_ADCINTOVFCLR, 0x000Fu);
    am263x_wr16(b + ADC_ADCSOCOVFCLR1, 0xFFFFu);
    adc->overruns = 0u;
    return true;
}

void am263x_adc_enable_irq(hal_adc_t *adc)
{
    am263x_wr16(adc->adc + ADC_ADCINTFLGCLR, ADC_INT1);
    am263x_wr16(adc->adc + ADC_ADCINTOVFCLR, ADC_INT1);
    am263x_wr16(adc->adc + ADC_ADCINTSEL1N2, (uint16_t)(3u | ADC_INTSEL_INT1E));
}

void am263x_adc_ack(hal_adc_t *adc)
{
    am263x_wr16(adc->adc + ADC_ADCINTFLGCLR, ADC_INT1);
}

/* ---- hal/adc.h */
void hal_adc_read(hal_adc_t *adc, hal_adc_sample_t *out)
{
    for (uint32_t k = 0u; k < 3u; ++k) {
        out->i[k] = am263x_rd16(adc->result + ADC_RESULT(k));
    }
    out->vdc = am263x_rd16(adc->result + ADC_RESULT(3u));
    /* ADCINTOVF.INT1: an EOC came while ADCINT1 was still set, i.e. before the last ISR had
     * acknowledged it (am263x_adc_ack at the ISR's end) */
    out->overrun = (am263x_rd16(adc->adc + ADC_ADCINTOVF) & ADC_INT1) != 0u;
    if (out->overrun) {
        adc->overruns++;
        am263x_wr16(adc->adc + ADC_ADCINTOVFCLR, ADC_INT1);
    }
}
