/* AM263x ADC (type 4, C2000 lineage) registers used by this port. Offsets and fields from TI's
 * MCU+ SDK source/drivers/adc/v1/cslr_adc.h, cslr_adc_result.h and adc.h, TRM sections "ADC:
 * SOC Principle of Operation", "ADC Interrupts", "ADC Registers". The control registers are
 * 16 bits wide except ADCSOCxCTL (32); the results (16) are in a separate block. */
#ifndef AM263X_REGS_ADC_H
#define AM263X_REGS_ADC_H
#include <stdint.h>

#define ADC_ADCCTL1         0x00u
#define ADC_ADCCTL2         0x02u
#define ADC_ADCINTFLG       0x06u
#define ADC_ADCINTFLGCLR    0x08u
#define ADC_ADCINTOVF       0x0Au
#define ADC_ADCINTOVFCLR    0x0Cu
#define ADC_ADCINTSEL1N2    0x0Eu
#define ADC_ADCSOCPRICTL    0x12u
#define ADC_ADCSOCFLG1      0x18u
#define ADC_ADCSOCOVF1      0x1Cu
#define ADC_ADCSOCOVFCLR1   0x1Eu
#define ADC_ADCSOCCTL(n)    (0x20u + 4u * (uint32_t)(n))   /* (32) */
/* result block */
#define ADC_RESULT(n)       (2u * (uint32_t)(n))

/* ADCCTL1 */
#define ADC_ADCCTL1_INTPULSEPOS   0x0004u   /* 1: interrupt pulse at the end of conversion  */
#define ADC_ADCCTL1_ADCPWDNZ      0x0080u   /* analog circuits powered                      */
/* ADCCTL2: PRESCALE (3:0): 6 = ADCCLK = SYSCLK / 4; RESOLUTION (6) 0 = 12 bit;
 * SIGNALMODE (7) 0 = single-ended */
#define ADC_ADCCTL2_PRESCALE_DIV4 0x0006u
/* ADCINTSEL1N2: INT1SEL (3:0) the SOC whose EOC sets ADCINT1, INT1E (5), INT1CONT (6) */
#define ADC_INTSEL_INT1E          0x0020u
#define ADC_INTSEL_INT1CONT       0x0040u
/* ADCINTFLG / CLR / OVF / OVFCLR */
#define ADC_INT1                  0x0001u
/* ADCSOCPRICTL.SOCPRIORITY (4:0) = n: SOC0..n-1 high priority, converted in number order */
/* ADCSOCxCTL: ACQPS (8:0) sample window - 1 [SYSCLK cycles], CHSEL (19:15), TRIGSEL (26:20) */
#define ADC_SOCCTL_CHSEL_SHIFT    15u
#define ADC_SOCCTL_CHSEL_MASK     0x1Fu
/* Inputs of each AM263x ADC module (ADC0..4): AIN0..AIN5 single-ended (SDK adc.h ADC_Channel:
 * ADC_CH_ADCIN0..5, 6/7 are the internal CAL0/CAL1; the am263x-lp examples' SysConfig lists
 * ADCn_AIN0..5 for ADC0, ADC1 and ADC2). CHSEL's 5 bits allow more than exist. */
#define AM263X_ADC_INPUTS         6u
#define ADC_SOCCTL_TRIGSEL_SHIFT  20u
#define ADC_SOCCTL_TRIGSEL_MASK   0x7Fu
#define ADC_SOCCTL_ACQPS_MASK     0x1FFu
/* TRIGSEL values (SDK ADC_Trigger): 8 + 2n = ePWMn SOCA, 9 + 2n = ePWMn SOCB */
#define ADC_TRIG_EPWM_SOCA(n)     (0x08u + 2u * (uint32_t)(n))

#endif
