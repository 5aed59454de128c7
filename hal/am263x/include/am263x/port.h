/* TI AM263x port of the HAL (R5FSS0 core 0, LP-AM263 LaunchPad): the port's structs and the
 * driver functions below the HAL contract. Every register access goes through a base address held
 * in these structs (am263x/mmio.h), so that the unit tests (tests/unit/am263x) point them at RAM
 * arrays; board.c holds the one instance of each with the real base addresses (am263x/regs_soc.h).
 *
 * Conventions of this port:
 *  - PWM: ePWM0, 1, 2 = phase a, b, c; ePWM0 is the master (sync-out at counter zero, ADC SOCA at
 *    counter zero), ePWM1/2 follow it (sync-in, phase 0). Up-down count, TBPRD = EPWMCLK /
 *    (2 f_pwm), period = 2 TBPRD counts. Action qualifier on output A (the high side): set on CAU
 *    (counter = CMPA going up), clear on CAD: A is high while the counter is above CMPA, so the
 *    high-side on-fraction is d = (TBPRD - CMPA) / TBPRD, CMPA = round((1 - d) TBPRD). At counter
 *    zero (the period boundary, where the ADC samples) every phase is low: the centre of the zero
 *    vector V0, all low-side switches on. B = complement of A with the dead band on both edges
 *    (active-high complementary); the trip zone drives A and B low.
 *  - ADC: phase a, b, c current on ADC0, ADC1, ADC2 (SOC0 of each: sampled at the same instant),
 *    Vdc on ADC0 SOC1 (inputs from hal_board_cfg_t), all triggered by ePWM0 SOCA at counter zero;
 *    ADCINT1 of ADC0 = end of its SOC1 -> INTXBAR output 0 -> VIM interrupt 146.
 *  - eQEP0 in quadrature count mode, MCAN0, RTI0 counter 0 (1 MHz), QSPI0 + its flash window. */
#ifndef AM263X_PORT_H
#define AM263X_PORT_H
#include <stdbool.h>
#include <stdint.h>
#include "hal/adc.h"
#include "hal/can.h"
#include "hal/nvm.h"
#include "hal/pwm.h"
#include "hal/qep.h"
#include "hal/time.h"
#include "hal/watchdog.h"
#include "am263x/regs_mcan.h"

/* ---------------------------------------------------------------- ePWM (epwm.c) */
struct hal_pwm {
    uintptr_t epwm[3];      /* ePWM0..2 register blocks                                   */
    uintptr_t ctrl;         /* CONTROLSS_CTRL (time-base clock enable, EPWM_CLKSYNC)      */
    uint32_t clk_hz;        /* EPWMCLK = TBCLK (dividers 1)                                */
    uint16_t prd;           /* TBPRD [counts]                                              */
    uint16_t db;            /* DBRED = DBFED [counts]                                      */
    float period_s, dead_time_s;   /* as programmed                                       */
    uint32_t nonfinite;     /* duties that arrived as NaN or infinite (became 0.5)         */
    uint32_t clamped;       /* finite duties outside [0, 1] (clamped)                      */
};

/* Dead-band floor [TBCLK counts]: 40 = 200 ns at 200 MHz, the turn-off delay plus fall time of
 * a typical low-voltage MOSFET stage with its gate driver; zero would be shoot-through. Raise it
 * for a slower stage (hw.dead_time_s is refused below it: hal_board_min_dead_time_s). */
#define AM263X_PWM_DB_MIN   40u
/* CMPA floor [counts]: TI requires CMPA >= 1 with the shadow loaded at zero; 100 counts keep the
 * low side on for at least 2 x 100 counts - dead band = 0.8 us per period at 0.2 us dead time,
 * the recharge a bootstrap supply needs: the maximum high-side duty is 1 - 100 / TBPRD
 * (98 % at 20 kHz, TBPRD 5000). */
#define AM263X_PWM_CMPA_MIN 100u
/* TBPRD and dead band in counts for f_pwm and dead_time at clk_hz; false if not realisable:
 * TBPRD outside [100, 65535], or the dead band below AM263X_PWM_DB_MIN, above 14 bits or above
 * a quarter period. */
bool am263x_pwm_timing(uint32_t clk_hz, float f_pwm_hz, float dead_time_s, uint16_t *prd, uint16_t *db);
/* CMPA for a high-side on-fraction d (clamped / NaN as hal_pwm_set_duties). */
uint16_t am263x_pwm_cmpa(hal_pwm_t *pwm, float d);
/* Outputs tripped (both low) first, then the three modules configured with their counters
 * stopped; false (outputs left tripped) if am263x_pwm_timing refuses. */
bool am263x_pwm_init(hal_pwm_t *pwm, float f_pwm_hz, float dead_time_s);
/* Counters running (up-down), the three time-base clocks enabled together. Outputs stay tripped. */
void am263x_pwm_start(hal_pwm_t *pwm);

/* ---------------------------------------------------------------- ADC (adc.c) */
struct hal_adc {
    uintptr_t adc[3];       /* ADC0..2 control blocks (ADC0: Vdc too, and the interrupt)   */
    uintptr_t result[3];    /* ADC0..2 result blocks                                       */
    uint32_t overruns;      /* samples read with the overflow flag set                     */
};
#define AM263X_ADC_ACQ_CYCLES 20u   /* sample window [SYSCLK cycles] = 100 ns                  */
#define AM263X_ADC_LAST_SOC   1u    /* ADC0's last SOC (Vdc): its EOC raises ADCINT1           */
/* ADC0..2 powered up (the caller waits the power-up time): ADCm SOC0 on input ch[m] (phase m),
 * ADC0 SOC1 on ch[3] (Vdc), all triggered by ePWM0 SOCA; ADC0's ADCINT1 at the end of SOC1 (not
 * yet enabled); flags cleared. false for an input a module does not have (each has AIN0..5:
 * AM263X_ADC_INPUTS) or Vdc on ia's input. */
bool am263x_adc_init(hal_adc_t *adc, const uint8_t ch[4]);
void am263x_adc_enable_irq(hal_adc_t *adc);
/* End of the control ISR: ADCINT1 cleared, so that the next EOC is not an overflow. */
void am263x_adc_ack(hal_adc_t *adc);

/* ---------------------------------------------------------------- eQEP (eqep.c) */
struct hal_qep {
    uintptr_t eqep;
    uint32_t counts_per_rev;
    uint32_t unit_clk;      /* QUPRD [SYSCLK cycles]                                       */
    uint32_t last_lat;      /* QPOSLAT of the previous unit time-out                       */
    bool have_last;
};
#define AM263X_QEP_UPPS 2u          /* unit position event every 2^2 = 4 counts (one line)     */
#define AM263X_QEP_CCPS 7u          /* capture clock SYSCLK / 2^7 = 1.5625 MHz                 */
/* Quadrature count mode, QPOSMAX = counts_per_rev - 1 (reset on maximum), index latch on the
 * rising edge, unit timer of unit_clk SYSCLK cycles latching QPOSLAT and QCPRDLAT, capture unit
 * on. false: counts_per_rev < 4 or unit_clk 0. */
bool am263x_qep_init(hal_qep_t *qep, uint32_t counts_per_rev, uint32_t unit_clk);

typedef struct {
    float unit_cps;     /* position change over the unit period [counts/s], signed           */
    float capture_cps;  /* 2^UPPS counts / the captured edge period [counts/s], signed; 0 when
                           the capture overflowed (too slow) or the direction changed        */
    bool capture_valid;
} am263x_qep_speed_t;

/* Signed position change from latch prev to latch cur (both 0..cpr-1) over at most half a
 * revolution; 'up' (QEPSTS.QDF) resolves an exact half turn. */
int32_t am263x_qep_delta(uint32_t prev, uint32_t cur, uint32_t cpr, bool up);
/* [counts/s] from a change of delta counts over unit_clk cycles of clk_hz. */
float am263x_qep_unit_speed(int32_t delta, uint32_t unit_clk, uint32_t clk_hz);
/* [counts/s] from a captured period of qcprd capture-clock ticks between unit position events
 * (2^upps counts), capture clock = clk_hz / 2^ccps; 0 for qcprd 0. */
float am263x_qep_capture_speed(uint16_t qcprd, uint32_t upps, uint32_t ccps, uint32_t clk_hz, bool up);
/* At a unit time-out (QFLG.UTO): both measurements from the latched registers, the flag and the
 * capture errors cleared; false (out untouched) when no time-out is pending. The first call after
 * init has no previous latch: its unit speed is 0. */
bool am263x_qep_poll_speed(hal_qep_t *qep, am263x_qep_speed_t *out);

/* ---------------------------------------------------------------- time (rti.c) */
struct hal_time {
    uintptr_t rti;
};
/* RTI counter block 0 at 1 MHz: RTICPUC0 = rti_clk_hz / 1 MHz - 1, counters restarted. */
void am263x_time_init(hal_time_t *t, uint32_t rti_clk_hz);

/* The watchdog (WDT0's DWWD, am263x/regs_rti.h): started by hal_board_start, kicked through
 * hal_board_kick. Window 100 %, reaction a warm reset (RTIWWDRXNCTRL 0x5; TOP_RCM
 * WARM_RESET_CONFIG.WDOG0_RST_EN is enabled at its reset value): the reset returns the ePWM pads
 * to their reset state (inputs, off) and the rebooted image trips first (am263x_pwm_init), so the
 * gate inputs are held off by the gate driver's input pull-downs during and after the reset.
 * Timeout (AM263X_WDT_PRLD + 1) x 2^13 / AM263X_WDT_CLK_HZ = 9.83 ms: about 200 control periods,
 * above the background loop's longest pass, far below a thermal time constant. */
#define AM263X_WDT_PRLD   29u
struct hal_wdg {
    uintptr_t wdt;          /* WDT0 (an RTI module)                                        */
    volatile uint32_t isr_runs;   /* control-ISR entries, counted by am263x_adc_eoc_isr    */
    uint32_t seen;          /* isr_runs at the last hal_wdg_service kick                   */
};
void am263x_wdt_start(uintptr_t wdt, uint32_t prld);
void am263x_wdt_kick(uintptr_t wdt);

/* ---------------------------------------------------------------- MCAN (mcan.c) */
struct hal_can {
    uintptr_t ss;           /* MCANSS wrapper (CFG base)                                   */
    uintptr_t core;         /* M_CAN core registers (CFG base + 0x200)                     */
    uintptr_t ram;          /* message RAM                                                 */
    uint32_t tx_dropped;    /* frames refused: TX FIFO full                                */
    uint32_t rx_lost;       /* RX FIFO 0 overflows seen (frames the controller dropped)    */
    uint32_t rx_bad;        /* elements taken but not classic CAN (FDF set)                */
    bool up;                /* init completed                                              */
};
typedef struct {
    uint16_t brp;           /* prescaler 1..512                                            */
    uint8_t tseg1;          /* time quanta before the sample point (after sync) 2..256     */
    uint8_t tseg2;          /* after the sample point 1..128                               */
    uint8_t sjw;            /* 1..tseg2                                                    */
} am263x_can_timing_t;
/* Nominal bit timing for bitrate at fclk: 8..25 time quanta per bit, the sample point nearest
 * 87.5 % (CiA 301), among those an exact divisor; false if none divides exactly. */
bool am263x_can_bit_timing(uint32_t bitrate, uint32_t fclk_hz, am263x_can_timing_t *t);
uint32_t am263x_can_nbtp(const am263x_can_timing_t *t);
/* Message RAM element words of a (valid) frame / of a received element. decode: false for a CAN
 * FD element (FDF), which this port does not configure. */
void am263x_can_encode(const hal_can_frame_t *f, uint32_t w[MCAN_ELEM_WORDS]);
bool am263x_can_decode(const uint32_t w[MCAN_ELEM_WORDS], hal_can_frame_t *f);
/* Controller configured (message RAM layout in am263x/regs_mcan.h) and started on the bus;
 * false: no exact bit timing, or the controller did not enter/leave initialisation. */
bool am263x_can_init(hal_can_t *can, uint32_t bitrate, uint32_t fclk_hz);

/* ---------------------------------------------------------------- NVM (nvm.c) */
struct hal_nvm {
    uintptr_t qspi;         /* QSPI0 controller                                            */
    uintptr_t window;       /* memory-mapped flash window (flash offset 0)                 */
    const hal_nvm_geometry_t *geom;   /* the flash's erase map                             */
    uint32_t base;          /* flash offset of block 0                                     */
    uint32_t block_size;    /* the sector size of the region holding the blocks            */
    uint32_t blocks;        /* 0: the range did not fit the map (every call fails)         */
    uint8_t erase_cmd;      /* that region's erase command                                 */
    uint32_t busy_polls;    /* QSPI word-complete polls before a transfer counts as failed */
    uint32_t erase_polls;   /* status reads while an erase runs                            */
    uint32_t program_polls; /* status reads while a page program runs                      */
    hal_wdg_t *wdg;         /* serviced at each status read (hal/watchdog.h); NULL: none   */
};
/* The LaunchPad's flash, Infineon (Spansion) S25FL128S with 64 KiB sectors (the part TI's SDK
 * configures for the LP-AM263, mcupsdk-core source/board/.meta/flash/S25FL128SA.json: 16 MiB,
 * 256-byte pages, 64 KiB blocks erased with 0xD8; its "sector" of 4 KiB / 0x20 exists only as
 * the parameter sectors). S25FL128S datasheet (Infineon 001-98283), "Sector address map": 32 x
 * 4 KiB parameter sectors at 0x000000-0x01FFFF (CR1.TBPARM = 0, the factory state; TBPARM is OTP)
 * erased by P4E (0x20), then 254 x 64 KiB sectors erased by SE (0xD8). A P4E outside the
 * parameter sectors does not erase (Infineon community, "S25FL256S - 4K sector erase/write
 * issue": P4E at 0x10000 left the data): the verify after every erase catches it. Offsets
 * below 16 MiB: 3-byte addresses. */
extern const hal_nvm_geometry_t am263x_s25fl128s;
/* 2 blocks of 64 KiB (two whole SE sectors), written in units of 8 bytes, at flash offset
 * 0x7E0000..0x7FFFFF: the last 128 KiB of the first 8 MiB, far above the SBL (0x0) and the
 * application image (0x80000) that TI's flashing tools write, and in the 64 KiB region whichever
 * end TBPARM put the parameter sectors at (the bottom ones hold the SBL). */
#define AM263X_NVM_UNIT        8u
#define AM263X_NVM_FLASH_OFF   0x007E0000u
#define AM263X_NVM_BYTES       0x00020000u
/* Blocks = [flash_offset, + bytes) in sectors of geom; blocks 0 (every call fails) unless that
 * range is whole sectors of one region. */
void am263x_nvm_init(hal_nvm_t *nvm, uintptr_t qspi, uintptr_t window, const hal_nvm_geometry_t *geom,
                     uint32_t flash_offset, uint32_t bytes);

/* ---------------------------------------------------------------- VIM + crossbar (vim.c) */
/* Interrupt `line` as an IRQ (not FIQ), level type, priority prio (0 highest), vector `handler`
 * (stored word-aligned, see startup.S), its pending state cleared, enabled. */
void am263x_vim_route(uintptr_t vim, uint32_t line, uint32_t prio, uintptr_t handler);
/* The line's pending status cleared (a level line: after its source was cleared). */
void am263x_vim_clear(uintptr_t vim, uint32_t line);
/* CONTROLSS interrupt crossbar: output `out` = the OR of the sources in group g's mask (the other
 * groups of that output cleared). */
void am263x_intxbar_route(uintptr_t xbar, uint32_t out, uint32_t group, uint32_t mask);
/* Control MMR partition 0 of CONTROLSS_CTRL / TOP_CTRL (KICK0/KICK1). */
void am263x_mmr_unlock(uintptr_t base);
void am263x_mmr_lock(uintptr_t base);

/* ---------------------------------------------------------------- board.c */
/* The ADC end-of-conversion interrupt handler registered in the VIM (called by the IRQ entry of
 * startup.S): calls the function given to hal_board_attach_isr, then acknowledges the ADC and
 * the VIM line. */
void am263x_adc_eoc_isr(void);

#endif
