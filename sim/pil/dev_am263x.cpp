// Processor-in-the-loop register model of the TI AM263x port (hal/am263x): exactly the registers
// its drivers use, with the behaviour they rely on, backed by the plant's PeriphInputs at each
// period boundary (PWM counter zero). Register facts (offsets, fields, base addresses) come from
// the port's headers hal/am263x/include/am263x/regs_*.h, which cite their TI sources.
//
// Emulated:
//  - ePWM0..2: TBPRD and CMPA shadow -> active at counter zero (when the time base runs: up-down
//    mode and the module's EPWM_CLKSYNC bit), trip zone (TZFRC.OST sets TZFLG.OST, TZCLR clears
//    it; any module tripped -> outputs().enabled false), duties from the action qualifier
//    (CAU set / CAD clear: (TBPRD - CMPA) / TBPRD; CAU clear / CAD set: CMPA / TBPRD), the dead
//    band (DBRED) for dead_time_s(). CONTROLSS_CTRL and TOP_CTRL with their KICK0/KICK1 lock
//    (writes to EPWM_CLKSYNC and the ADC reference registers while locked are ignored).
//  - ADC0..2: at counter zero, if ePWM0 generates SOCA at zero, every SOC of a powered module
//    triggered by ePWM0 SOCA converts: SOC0 of ADC0/1/2 = phase a/b/c current, ADC0 SOC1 = Vdc
//    (the port's assignment; the input numbers are the board's wiring); a SOC on an input the
//    module does not have (AIN0..5) reads 0. ADC0's ADCINT1 (INT1E, INT1SEL) flag;
//    ADCINTOVF.INT1 when the flag was still set, or on PeriphInputs::adc_overrun.
//  - INTXBAR output 0 (group 2 bit 0 = ADC0 INT1) -> VIM line 146; the VIM's enable, map (IRQ),
//    priority and vector registers; IRQVEC reads the registered vector of the pending line and a
//    write acknowledges; irq_pending() = ADCINT1 set, enabled in the ADC, routed in the crossbar,
//    enabled and mapped to IRQ in the VIM.
//  - eQEP0 (whether or not the PWM runs): QPOSCNT, QPOSILAT, QEPSTS (FIMF = index seen as the
//    plant says, not cleared by the firmware's write; QDF = direction of the last change),
//    unit timer (QUPRD in SYSCLK cycles from time_us: QFLG.UTO, QPOSLAT, QCPRDLAT), a capture
//    period estimate from the counts moved (COEF when slower than the 16-bit capture timer).
//  - RTI0: RTIFRC0 = time_us scaled by RTICLK (25 MHz) / (RTICPUC0 + 1).
//  - MCAN0: MEM_INIT_DONE, CCCR (INIT reads back, CCE cleared with INIT), PSR error active, TX
//    FIFO always free (a TXBAR request is "sent" at once: the frame goes to the bus side,
//    can_take), RX FIFO 0 in the message RAM as RXF0C places it, filled by can_deliver (fill
//    level, get and put indices in RXF0S, RXF0A frees the element; full: the frame is lost and
//    IR.RF0L set).
//  - QSPI0: configuration-port frames of 8-bit words (WREN, RDSR, PP, P4E, SE) applied to the flash
//    window through bind_memory (program = AND, never busy), erases as the LaunchPad's S25FL128S
//    has them (am263x_s25fl128s, am263x/port.h): P4E = 0xFF over a 4 KiB parameter sector
//    (0x000000-0x01FFFF) and nothing elsewhere, SE = 0xFF over a 64 KiB sector above them. An SE
//    keeps the part busy (RDSR WIP, every other command ignored) for kSectorEraseUs of the plant's
//    time: the firmware waits through many control periods, as on the board.
//  - SoC bring-up, from the SoC's reset values (am263x/regs_soc.h): IOMUX pads (0x5F7: GPIO,
//    behind the IO_CFG_KICK lock) and MSS_RCM module clocks (source 0 = 25 MHz, divider 1, behind
//    its KICK lock). Only pads with their function carry the signal: the ePWM0-2 A/B pads or the
//    outputs count as off, the eQEP0 A/B pads or the encoder does not count, MCAN0 RX/TX (and
//    the transceiver's STB, GPIO51 on pad EPWM4_A, a GPIO output driven low) or no frame. The CAN bus of the bench runs at kBusBitrate: frames pass only when NBTP at the MCAN0
//    clock the RCM selects gives exactly that rate. RTIFRC0 counts at the RTI0 clock selected.
//  - WDT0 (an RTI module's DWWD): RTIDWDCTRL enable key starts the down counter at (DWDPRLD + 1)
//    x 2^13 ticks of the WDT0 clock MSS_RCM selects (reset: WUCPUCLK, 25 MHz by TI's clock map;
//    RCCLK10M 10 MHz, RCCLK32K 32 kHz, ...: a timeout the firmware did not set), the key pair E51A/A35C on RTIWDKEY reloads it, RTIDWDCNTR
//    reads it; it runs in the plant's microseconds, checked at each period boundary. At zero:
//    RTIWDSTATUS DWDST and DWWD_ST, and the reaction's effect on the bridge: the warm reset's
//    (RTIWWDRXNCTRL 0x5) pads off stand as a one-shot trip of ePWM0-2 (outputs().enabled false),
//    the core is not reset.
//  - The hardware trip input: set_pin("nFAULT", false) pulls the gate driver's open-drain fault
//    line low. It reaches GPIO11 only through pad SPI0_CS0 muxed as a GPIO (mode 7, no IE/OE
//    override: at reset it carries nothing); released, the line reads the pad's pull (down: low,
//    up or none: high). A low GPIO11 selected by INPUT XBAR 0 (group 0) is TZ1: it latches the
//    one-shot trip (TZFLG.OST) of each ePWM with TZSEL.OSHT1, at once and at each boundary.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <vector>

#include "peripherals.hpp"

#include "../../hal/am263x/include/am263x/regs_adc.h"
#include "../../hal/am263x/include/am263x/regs_epwm.h"
#include "../../hal/am263x/include/am263x/regs_eqep.h"
#include "../../hal/am263x/include/am263x/regs_mcan.h"
#include "../../hal/am263x/include/am263x/regs_qspi.h"
#include "../../hal/am263x/include/am263x/regs_rti.h"
#include "../../hal/am263x/include/am263x/regs_soc.h"
#include "../../hal/am263x/include/am263x/regs_vim.h"

namespace mcsim::pil {
namespace {

enum Win : int { kEpwm, kAdcRes, kEqep, kAdc, kXbar, kCtrlss, kTop, kVim, kRti, kMcanRam, kMcanCfg, kQspi, kIomux, kRcm, kGpio, kWdt, kInXbar, kNumWin };

struct WinDef {
    uint32_t base, size;
    const char* name;
};

constexpr WinDef kWins[kNumWin] = {
    {AM263X_EPWM_BASE(0), 0x3000, "EPWM0-2"},
    {AM263X_ADC_RESULT_BASE(0), 0x3000, "ADC0-2_RESULT"},
    {AM263X_EQEP_BASE(0), 0x1000, "EQEP0"},
    {AM263X_ADC_BASE(0), 0x3000, "ADC0-2"},
    {AM263X_INTXBAR_BASE, 0x1000, "CONTROLSS_INTXBAR"},
    {AM263X_CTRLSS_CTRL_BASE, 0x2000, "CONTROLSS_CTRL"},
    {AM263X_TOP_CTRL_BASE, 0x2000, "TOP_CTRL"},
    {AM263X_VIM_BASE, VIM_SIZE, "VIM"},
    {AM263X_RTI_BASE(0), 0x1000, "RTI0"},
    {AM263X_MCAN_MSGRAM_BASE(0), 0x8000, "MCAN0_MSG_RAM"},
    {AM263X_MCAN_CFG_BASE(0), 0x1000, "MCAN0_CFG"},
    {AM263X_QSPI_BASE, 0x1000, "QSPI0"},
    {AM263X_IOMUX_BASE, 0x1000, "IOMUX"},
    {AM263X_MSS_RCM_BASE, 0x2000, "MSS_RCM"},
    {AM263X_GPIO0_BASE, 0x1000, "GPIO0"},
    {AM263X_WDT0_BASE, 0x1000, "WDT0"},
    {AM263X_INPUTXBAR_BASE, 0x1000, "CONTROLSS_INPUTXBAR"},
};

constexpr uint32_t kAdcLine = AM263X_IRQ_ADC_EOC;
constexpr double kSysclk = AM263X_SYSCLK_HZ;
constexpr uint64_t kBusBitrate = 500000;   // the bench's CAN bus [bit/s]

class Am263x final : public Peripherals {
public:
    Am263x()
    {
        for (int w = 0; w < kNumWin; ++w) mem_[w].assign(kWins[w].size, 0);
        // reset values the drivers depend on
        put(kMcanCfg, MCANSS_STAT, 4, MCANSS_STAT_MEM_INIT_DONE);
        put(kQspi, QSPI_SPI_SWITCH, 4, QSPI_SWITCH_MMPT_S);
        for (uint32_t off = 0; off < AM263X_IOMUX_KICK0; off += 4) put(kIomux, off, 4, AM263X_PAD_RESET);
    }

    std::vector<MmioWindow> windows() const override
    {
        std::vector<MmioWindow> v;
        for (const auto& w : kWins) v.push_back({w.base, w.size, w.name});
        return v;
    }

    std::vector<MmioWindow> memories() const override
    {
        return {{AM263X_ATCM_BASE, AM263X_ATCM_SIZE, "ATCM"},
                {AM263X_BTCM_BASE, AM263X_BTCM_SIZE, "BTCM"},
                {AM263X_MSRAM_BASE, AM263X_MSRAM_SIZE, "MSRAM"},
                {AM263X_FLASH_WIN_BASE, AM263X_FLASH_WIN_SIZE, "QSPI flash window"}};
    }

    void bind_memory(MemWrite write, MemRead read) override
    {
        mem_write_ = std::move(write);
        mem_read_ = std::move(read);
    }

    uint64_t read(uint64_t addr, unsigned size) override
    {
        int w;
        uint32_t off;
        if (!find(addr, size, &w, &off)) return 0;
        switch (w) {
        case kEpwm:
            if (off % 0x1000 == EPWM_TBCTR) return 0;
            break;
        case kAdc:
            if (off == ADC_ADCINTFLG) return adc_flag_;
            if (off == ADC_ADCINTOVF) return adc_ovf_;
            if (off == ADC_ADCINTFLGCLR || off == ADC_ADCINTOVFCLR) return 0;
            break;
        case kEqep:
            return eqep_read(off, size);
        case kVim:
            return vim_read(off);
        case kRti:
            if (off == RTI_RTIFRC0) {
                const uint64_t cpuc = get(kRti, RTI_RTICPUC0, 4) + 1u;
                const uint64_t ticks = uint64_t{time_us_} * (rcm_hz(AM263X_RCM_RTI0_CLK_SRC_SEL, AM263X_RCM_RTI0_CLK_DIV_VAL, true) / 1000000u);
                return (get(kRti, RTI_RTIGCTRL, 4) & RTI_GCTRL_CNT0EN) ? static_cast<uint32_t>(ticks / cpuc) : 0u;
            }
            if (off == RTI_RTIUC0) return 0;
            break;
        case kMcanCfg:
            return mcan_read(off, size);
        case kWdt:
            if (off == RTI_RTIDWDCNTR) return static_cast<uint32_t>(wdt_left_);
            if (off == RTI_RTIWDKEY) return 0;
            break;
        case kQspi:
            if (off == QSPI_SPI_STATUS) return QSPI_STATUS_WC | QSPI_STATUS_FC;   // never busy
            break;
        default:
            break;
        }
        return get(w, off, size);
    }

    void write(uint64_t addr, unsigned size, uint64_t value) override
    {
        int w;
        uint32_t off;
        if (!find(addr, size, &w, &off)) return;
        const auto v = static_cast<uint32_t>(value);
        switch (w) {
        case kEpwm:
            if (epwm_write(off, size, v)) return;
            break;
        case kAdc:
            if (off == ADC_ADCINTFLGCLR) {
                adc_flag_ &= ~v;
                return;
            }
            if (off == ADC_ADCINTOVFCLR) {
                adc_ovf_ &= ~v;
                return;
            }
            break;
        case kEqep:
            if (eqep_write(off, v)) return;
            break;
        case kIomux:
            if (off == AM263X_IOMUX_KICK0 || off == AM263X_IOMUX_KICK1) break;
            if (get(kIomux, AM263X_IOMUX_KICK0, 4) != AM263X_IOMUX_KICK0_UNLOCK ||
                get(kIomux, AM263X_IOMUX_KICK1, 4) != AM263X_IOMUX_KICK1_UNLOCK) {
                ++locked_writes_;
                return;
            }
            break;
        case kCtrlss:
        case kTop:
        case kRcm:
            if (off == AM263X_LOCK0_KICK0 || off == AM263X_LOCK0_KICK1) break;
            if (!unlocked(w) && is_protected(w, off)) {
                ++locked_writes_;
                return;
            }
            break;
        case kVim:
            if (vim_write(off, v)) return;
            break;
        case kMcanCfg:
            if (mcan_write(off, v)) return;
            break;
        case kQspi:
            if (off == QSPI_SPI_CMD) {
                qspi_cmd(v);
                return;
            }
            break;
        case kGpio:
            if (gpio_write(off, v)) return;
            break;
        case kWdt:
            if (wdt_write(off, v)) return;
            break;
        default:
            break;
        }
        put(w, off, size, v);
    }

    void period_boundary(const PeriphInputs& in) override
    {
        const uint32_t dt_us = in.time_us - time_us_;
        time_us_ = in.time_us;
        eqep_advance(in, dt_us);   // the encoder counts whether or not the PWM runs
        wdt_advance(dt_us);
        trip_input();
        if (!running()) return;
        for (int m = 0; m < 3; ++m) {
            const uint32_t b = 0x1000u * static_cast<uint32_t>(m);
            if ((get(kEpwm, b + EPWM_CMPCTL, 2) & (EPWM_CMPCTL_SHDWAMODE | EPWM_CMPCTL_LOADAMODE_MASK)) == 0)
                cmpa_active_[m] = static_cast<uint16_t>(get(kEpwm, b + EPWM_CMPA_HI, 2));
            if ((get(kEpwm, b + EPWM_TBCTL, 2) & EPWM_TBCTL_PRDLD) == 0)
                prd_active_[m] = static_cast<uint16_t>(get(kEpwm, b + EPWM_TBPRD, 2));
        }
        adc_convert(in);
    }

    PeriphOutputs outputs() const override { return out(cmpa_active_, prd_active_); }

    PeriphOutputs pending_outputs() const override
    {
        uint16_t c[3], p[3];
        for (int m = 0; m < 3; ++m) {
            const uint32_t b = 0x1000u * static_cast<uint32_t>(m);
            const bool shadow = (get(kEpwm, b + EPWM_CMPCTL, 2) & EPWM_CMPCTL_SHDWAMODE) == 0;
            c[m] = shadow ? static_cast<uint16_t>(get(kEpwm, b + EPWM_CMPA_HI, 2)) : cmpa_active_[m];
            p[m] = (get(kEpwm, b + EPWM_TBCTL, 2) & EPWM_TBCTL_PRDLD) == 0 ? static_cast<uint16_t>(get(kEpwm, b + EPWM_TBPRD, 2))
                                                                         : prd_active_[m];
        }
        return out(c, p);
    }

    bool irq_pending() const override
    {
        const uint32_t g = VIM_INT_EN(kAdcLine);
        return adc_line() && (vim_en_[idx(g)] & VIM_BIT(kAdcLine)) != 0 &&
               (get(kVim, VIM_INT_MAP(kAdcLine), 4) & VIM_BIT(kAdcLine)) == 0;
    }

    uint32_t irq_vector() override { return irq_pending() ? get(kVim, VIM_INT_VEC(kAdcLine), 4) : 0u; }

    double pwm_period_s() const override
    {
        return 2.0 * static_cast<double>(get(kEpwm, EPWM_TBPRD, 2)) / static_cast<double>(AM263X_EPWMCLK_HZ);
    }

    uint32_t pwm_counts() const override { return get(kEpwm, EPWM_TBPRD, 2); }
    bool pwm_off_time() const override
    {
        // A set at CMPA going up, cleared going down: on while TBCTR > CMPA, CMPA counts the off-time
        const uint32_t aq = get(kEpwm, EPWM_AQCTLA, 2);
        return ((aq >> EPWM_AQ_CAU_SHIFT) & 3u) == EPWM_AQ_SET && ((aq >> EPWM_AQ_CAD_SHIFT) & 3u) == EPWM_AQ_CLEAR;
    }

    double dead_time_s() const override
    {
        if ((get(kEpwm, EPWM_DBCTL, 2) & 0x3u) != 0x3u) return 0.0;
        return static_cast<double>(get(kEpwm, EPWM_DBRED, 2)) / static_cast<double>(AM263X_EPWMCLK_HZ);
    }

private:
    // ---- plumbing
    static bool find(uint64_t addr, unsigned size, int* w, uint32_t* off)
    {
        for (int k = 0; k < kNumWin; ++k) {
            if (addr >= kWins[k].base && addr + size <= uint64_t{kWins[k].base} + kWins[k].size) {
                *w = k;
                *off = static_cast<uint32_t>(addr - kWins[k].base);
                return true;
            }
        }
        return false;
    }
    uint32_t get(int w, uint32_t off, unsigned size) const
    {
        uint32_t v = 0;
        for (unsigned k = 0; k < size; ++k) v |= uint32_t{mem_[w][off + k]} << (8 * k);
        return v;
    }
    void put(int w, uint32_t off, unsigned size, uint32_t v)
    {
        for (unsigned k = 0; k < size; ++k) mem_[w][off + k] = static_cast<uint8_t>(v >> (8 * k));
    }
    static size_t idx(uint32_t vim_group_reg) { return (vim_group_reg - 0x400u) / 0x20u; }

    // ---- control MMR lock
    bool unlocked(int w) const
    {
        return get(w, AM263X_LOCK0_KICK0, 4) == AM263X_KICK0_UNLOCK && get(w, AM263X_LOCK0_KICK1, 4) == AM263X_KICK1_UNLOCK;
    }
    static bool is_protected(int w, uint32_t off)
    {
        if (w == kCtrlss) return off == AM263X_CTRLSS_EPWM_CLKSYNC;
        if (w == kRcm) return true;
        return off == AM263X_TOP_ADC_REFBUF0_CTRL || off == AM263X_TOP_ADC_REF_COMP_CTRL;
    }

    // ---- SoC bring-up: pads and module clocks
    bool gpio_write(uint32_t off, uint32_t v)   // SET_DATA / CLR_DATA act on OUT_DATA
    {
        if (off < 0x10u || (off - 0x10u) % 0x28u < 0x08u) return false;
        const uint32_t r = (off - 0x10u) % 0x28u, out = off - r + 0x04u;
        if (r == 0x08u) put(kGpio, out, 4, get(kGpio, out, 4) | v);
        else if (r == 0x0Cu) put(kGpio, out, 4, get(kGpio, out, 4) & ~v);
        else return false;
        return true;
    }
    bool pad_is(uint32_t pad, uint32_t fn) const { return (get(kIomux, pad, 4) & AM263X_PAD_FUNC_MASK) == fn; }
    bool pwm_pads() const
    {
        for (uint32_t m = 0; m < 3; ++m)
            if (!pad_is(AM263X_PAD_EPWM_A(m), AM263X_PAD_FN_EPWM) || !pad_is(AM263X_PAD_EPWM_B(m), AM263X_PAD_FN_EPWM))
                return false;
        return true;
    }
    // A module clock [Hz] from its MSS_RCM source code and divider (soc_rcm.c's maps; the PLL
    // outputs as TI's SBL sets them); 0 for a source this model does not know.
    uint64_t rcm_hz(uint32_t src_reg, uint32_t div_reg, bool rti) const
    {
        const uint32_t src = get(kRcm, src_reg, 4) & 0xFFFu;
        const uint64_t div = (get(kRcm, div_reg, 4) & 0xFu) + 1u;
        uint64_t hz = 0;
        if (src == AM263X_RCM_SRC_WUCPUCLK || src == AM263X_RCM_SRC_XTALCLK) hz = AM263X_XTAL_HZ;
        else if (src == 0x222u) hz = AM263X_SYSCLK_HZ;
        else if (src == 0x333u) hz = 192000000u;                        // PER HSDIV0 CLKOUT1
        else if (src == 0x444u) hz = rti ? 500000000u : AM263X_CORE_HSDIV0_HZ;   // CORE HSDIV0 CLKOUT1 / 0
        return hz / div;
    }
    bool can_on_bus() const
    {
        if (!pad_is(AM263X_PAD_MCAN0_RX, AM263X_PAD_FN_MCAN) || !pad_is(AM263X_PAD_MCAN0_TX, AM263X_PAD_FN_MCAN)) return false;
        // transceiver standby: the pad a plain GPIO (no IE/OE override), the pin an output, low
        const uint32_t n = AM263X_CAN_STB_GPIO / 32u, bit = 1u << (AM263X_CAN_STB_GPIO % 32u);
        if ((get(kIomux, AM263X_PAD_EPWM4_A, 4) & 0xFFu) != AM263X_PAD_GPIO ||
            (get(kGpio, AM263X_GPIO_DIR(n), 4) & bit) || (get(kGpio, AM263X_GPIO_OUT_DATA(n), 4) & bit))
            return false;
        const uint32_t nbtp = get(kMcanCfg, MCAN_CORE_OFFSET + MCAN_NBTP, 4);
        const uint64_t brp = ((nbtp >> MCAN_NBTP_NBRP_SHIFT) & 0x1FFu) + 1u;
        const uint64_t tq = 1u + ((nbtp >> MCAN_NBTP_NTSEG1_SHIFT) & 0xFFu) + 1u + ((nbtp >> MCAN_NBTP_NTSEG2_SHIFT) & 0x7Fu) + 1u;
        return rcm_hz(AM263X_RCM_MCAN0_CLK_SRC_SEL, AM263X_RCM_MCAN0_CLK_DIV_VAL, false) == kBusBitrate * brp * tq;
    }

    // ---- ePWM
    bool running() const
    {
        const uint32_t sync = get(kCtrlss, AM263X_CTRLSS_EPWM_CLKSYNC, 4);
        for (uint32_t m = 0; m < 3; ++m) {
            if ((sync & (1u << m)) == 0) return false;
            if ((get(kEpwm, 0x1000u * m + EPWM_TBCTL, 2) & EPWM_TBCTL_CTRMODE_MASK) != EPWM_TBCTL_CTRMODE_UPDOWN) return false;
        }
        return true;
    }
    // ---- WDT0's DWWD (true: handled)
    bool wdt_write(uint32_t off, uint32_t v)
    {
        if (off == RTI_RTIDWDCTRL) {
            if (v == RTI_DWDCTRL_ENABLE && !wdt_en_) {
                wdt_en_ = true;
                wdt_reload();
            }
            put(kWdt, off, 4, wdt_en_ ? RTI_DWDCTRL_ENABLE : v);
            return true;
        }
        if (off == RTI_RTIWDKEY) {
            if (v == RTI_WDKEY_2 && wdt_key1_ && wdt_en_ && !wdt_expired_) wdt_reload();
            wdt_key1_ = v == RTI_WDKEY_1;
            return true;
        }
        if (off == RTI_RTIWDSTATUS) {
            put(kWdt, off, 4, get(kWdt, off, 4) & ~v);
            return true;
        }
        return false;
    }
    // WDT0's clock from MSS_RCM (soc_rcm.c gWdtClkSrcValMap; frequencies from TI's SysConfig clock
    // map: WUCPUCLK and XTALCLK 25 MHz, RCCLK10M 10 MHz)
    uint64_t wdt_hz() const
    {
        const uint32_t src = get(kRcm, AM263X_RCM_WDT0_CLK_SRC_SEL, 4) & 0xFFFu;
        const uint64_t div = (get(kRcm, AM263X_RCM_WDT0_CLK_DIV_VAL, 4) & 0xFu) + 1u;
        if (src == 0x111u || src == 0x555u) return 10000000u / div;
        if (src == 0x777u) return 32000u / div;
        return rcm_hz(AM263X_RCM_WDT0_CLK_SRC_SEL, AM263X_RCM_WDT0_CLK_DIV_VAL, true);
    }
    // The trip input (see the header): the level at GPIO11, and TZ1 when INPUT XBAR 0 selects it.
    bool gpio11_low() const
    {
        const uint32_t pad = get(kIomux, AM263X_PAD_SPI0_CS0, 4);
        if ((pad & 0xFFu) != AM263X_PAD_GPIO) return false;   // not muxed: carries nothing
        if (nfault_low_) return true;
        return (pad & AM263X_PAD_NOPULL) == 0 && (pad & AM263X_PAD_PULLUP) == 0;   // pulled down
    }
    void trip_input()
    {
        if (!gpio11_low() || get(kInXbar, AM263X_INPUTXBAR_GSEL(0u), 4) != 0u ||
            get(kInXbar, AM263X_INPUTXBAR_G0(0u), 4) != AM263X_TRIP_GPIO)
            return;
        for (uint32_t m = 0; m < 3; ++m)
            if (get(kEpwm, 0x1000u * m + EPWM_TZSEL, 2) & EPWM_TZSEL_OSHT1)
                put(kEpwm, 0x1000u * m + EPWM_TZFLG, 2, get(kEpwm, 0x1000u * m + EPWM_TZFLG, 2) | EPWM_TZ_OST | EPWM_TZ_INT);
    }

public:
    bool set_pin(const std::string& name, bool high) override
    {
        if (name != "nFAULT") return false;
        nfault_low_ = !high;
        trip_input();
        return true;
    }

private:
    void wdt_reload() { wdt_left_ = (uint64_t{get(kWdt, RTI_RTIDWDPRLD, 4) & 0xFFFu} + 1u) << RTI_DWD_PRLD_SHIFT; }
    void wdt_advance(uint32_t dt_us)
    {
        if (!wdt_en_ || wdt_expired_) return;
        const uint64_t t = uint64_t{dt_us} * wdt_hz() + wdt_frac_;   // ticks x 1e6
        const uint64_t ticks = t / 1000000u;
        wdt_frac_ = t % 1000000u;
        if (ticks < wdt_left_) {
            wdt_left_ -= ticks;
            return;
        }
        wdt_left_ = 0;
        wdt_expired_ = true;
        put(kWdt, RTI_RTIWDSTATUS, 4, get(kWdt, RTI_RTIWDSTATUS, 4) | RTI_WDSTATUS_DWDST | 0x20u);
        for (uint32_t m = 0; m < 3; ++m)   // the reset's effect on the bridge: all outputs off
            put(kEpwm, 0x1000u * m + EPWM_TZFLG, 2, get(kEpwm, 0x1000u * m + EPWM_TZFLG, 2) | EPWM_TZ_OST | EPWM_TZ_INT);
    }

    bool tripped() const
    {
        for (uint32_t m = 0; m < 3; ++m)
            if (get(kEpwm, 0x1000u * m + EPWM_TZFLG, 2) & EPWM_TZ_OST) return true;
        return false;
    }
    bool epwm_write(uint32_t off, unsigned size, uint32_t v)
    {
        const uint32_t b = off & ~0xFFFu, r = off & 0xFFFu;
        if (r == EPWM_TZFRC) {
            if (v & EPWM_TZ_OST) put(kEpwm, b + EPWM_TZFLG, 2, get(kEpwm, b + EPWM_TZFLG, 2) | EPWM_TZ_OST | EPWM_TZ_INT);
            return true;
        }
        if (r == EPWM_TZCLR) {
            put(kEpwm, b + EPWM_TZFLG, 2, get(kEpwm, b + EPWM_TZFLG, 2) & ~v);
            return true;
        }
        if (r == EPWM_ETCLR) {
            put(kEpwm, b + EPWM_ETFLG, 2, get(kEpwm, b + EPWM_ETFLG, 2) & ~v);
            return true;
        }
        if (r == EPWM_CMPA && size == 4) {   // 32-bit CMPA:CMPAHR
            put(kEpwm, off, 4, v);
        }
        // CMPA / TBPRD in immediate mode take effect at once
        if (r == EPWM_CMPA_HI || (r == EPWM_CMPA && size == 4)) {
            put(kEpwm, b + EPWM_CMPA_HI, 2, r == EPWM_CMPA ? v >> 16 : v);
            if (get(kEpwm, b + EPWM_CMPCTL, 2) & EPWM_CMPCTL_SHDWAMODE) cmpa_active_[b >> 12] = static_cast<uint16_t>(get(kEpwm, b + EPWM_CMPA_HI, 2));
            return true;
        }
        if (r == EPWM_TBPRD) {
            put(kEpwm, off, 2, v);
            if (get(kEpwm, b + EPWM_TBCTL, 2) & EPWM_TBCTL_PRDLD) prd_active_[b >> 12] = static_cast<uint16_t>(v);
            return true;
        }
        return false;
    }
    static double duty(uint32_t aq, uint16_t cmp, uint16_t prd)
    {
        if (prd == 0) return 0.0;
        const double c = std::min<double>(cmp, prd), p = prd;
        const uint32_t cau = (aq >> EPWM_AQ_CAU_SHIFT) & 3u, cad = (aq >> EPWM_AQ_CAD_SHIFT) & 3u;
        if (cau == EPWM_AQ_SET && cad == EPWM_AQ_CLEAR) return (p - c) / p;
        if (cau == EPWM_AQ_CLEAR && cad == EPWM_AQ_SET) return c / p;
        return 0.0;   // not a convention this model knows: the phase counts as off
    }
    PeriphOutputs out(const uint16_t* cmp, const uint16_t* prd) const
    {
        PeriphOutputs o;
        o.enabled = running() && !tripped() && pwm_pads();
        for (int m = 0; m < 3; ++m)
            o.duty[m] = duty(get(kEpwm, 0x1000u * static_cast<uint32_t>(m) + EPWM_AQCTLA, 2), cmp[m], prd[m]);
        return o;
    }

    // ---- ADC
    void adc_convert(const PeriphInputs& in)
    {
        const uint32_t etsel = get(kEpwm, EPWM_ETSEL, 2);
        const bool soca = (etsel & EPWM_ETSEL_SOCAEN) != 0 &&
                          ((etsel >> EPWM_ETSEL_SOCASEL_SHIFT) & 7u) == EPWM_ETSEL_SOCASEL_ZERO;
        if (!soca) return;
        const uint32_t intsel = get(kAdc, ADC_ADCINTSEL1N2, 2);
        bool eoc1 = false;
        for (uint32_t m = 0; m < 3; ++m) {
            const uint32_t b = 0x1000u * m;
            if ((get(kAdc, b + ADC_ADCCTL1, 2) & ADC_ADCCTL1_ADCPWDNZ) == 0) continue;
            for (uint32_t n = 0; n < 16; ++n) {
                const uint32_t ctl = get(kAdc, b + ADC_ADCSOCCTL(n), 4);
                if (((ctl >> ADC_SOCCTL_TRIGSEL_SHIFT) & ADC_SOCCTL_TRIGSEL_MASK) != ADC_TRIG_EPWM_SOCA(0)) continue;
                const bool input = ((ctl >> ADC_SOCCTL_CHSEL_SHIFT) & ADC_SOCCTL_CHSEL_MASK) < AM263X_ADC_INPUTS;
                const uint16_t val = !input ? 0 : n == 0 ? in.adc_i[m] : (m == 0 && n == 1) ? in.adc_vdc : 0;
                put(kAdcRes, b + ADC_RESULT(n), 2, val);
                if (m == 0 && n == (intsel & 0xFu)) eoc1 = true;
            }
        }
        if (eoc1 && (intsel & ADC_INTSEL_INT1E)) {
            if ((adc_flag_ & ADC_INT1) && !(intsel & ADC_INTSEL_INT1CONT)) adc_ovf_ |= ADC_INT1;
            adc_flag_ |= ADC_INT1;
        }
        if (in.adc_overrun && (get(kAdc, ADC_ADCCTL1, 2) & ADC_ADCCTL1_ADCPWDNZ)) adc_ovf_ |= ADC_INT1;
    }
    bool adc_line() const
    {
        const bool xbar = (get(kXbar, AM263X_INTXBAR_G(AM263X_INTXBAR_OUT_ADC, AM263X_INTXBAR_GROUP_ADC), 4) &
                           AM263X_INTXBAR_ADC0_INT1) != 0;
        return xbar && (adc_flag_ & ADC_INT1) != 0 && (get(kAdc, ADC_ADCINTSEL1N2, 2) & ADC_INTSEL_INT1E) != 0;
    }

    // ---- VIM
    uint32_t vim_read(uint32_t off)
    {
        if (off == VIM_IRQVEC) return irq_vector();
        if (off == VIM_ACTIRQ) return irq_pending() ? (0x80000000u | kAdcLine) : 0u;
        if (off >= 0x400 && off < 0x600) {
            const size_t g = (off - 0x400u) / 0x20u;
            const uint32_t r = (off - 0x400u) % 0x20u;
            const uint32_t raw = (g == kAdcLine / 32 && adc_line()) ? VIM_BIT(kAdcLine) : 0u;
            if (r == 0x00) return raw;                    // RAW
            if (r == 0x04) return raw & vim_en_[g];       // STS
            if (r == 0x08 || r == 0x0C) return vim_en_[g];
        }
        return get(kVim, off, 4);
    }
    bool vim_write(uint32_t off, uint32_t v)
    {
        if (off == VIM_IRQVEC) {
            ++vim_acks_;
            return true;
        }
        if (off >= 0x400 && off < 0x600) {
            const size_t g = (off - 0x400u) / 0x20u;
            const uint32_t r = (off - 0x400u) % 0x20u;
            if (r == 0x08) {
                vim_en_[g] |= v;
                return true;
            }
            if (r == 0x0C) {
                vim_en_[g] &= ~v;
                return true;
            }
            if (r == 0x00 || r == 0x04) return true;   // level lines follow their source
        }
        return false;
    }

    // ---- eQEP
    uint32_t eqep_read(uint32_t off, unsigned size) const
    {
        switch (off) {
        case EQEP_QPOSCNT: return q_pos_;
        case EQEP_QPOSILAT: return q_ilat_;
        case EQEP_QPOSLAT: return q_lat_;
        case EQEP_QFLG: return q_flg_;
        case EQEP_QEPSTS: return q_sts_;
        case EQEP_QCPRDLAT: return q_cprdlat_;
        case EQEP_QCLR: return 0;
        default: return get(kEqep, off, size);
        }
    }
    bool eqep_write(uint32_t off, uint32_t v)
    {
        switch (off) {
        case EQEP_QPOSCNT: q_pos_ = v; return true;
        case EQEP_QCLR: q_flg_ &= ~v; return true;
        case EQEP_QEPSTS:
            // FIMF is not cleared: it mirrors PeriphInputs::qep_index_seen (an index since the
            // start of the run, which the model cannot place before or after the clear)
            q_sts_ &= ~(v & (EQEP_QEPSTS_CDEF | EQEP_QEPSTS_COEF | EQEP_QEPSTS_UPEVNT));
            return true;
        default: return false;
        }
    }
    void eqep_advance(const PeriphInputs& in, uint32_t dt_us)
    {
        const uint32_t ctl = get(kEqep, EQEP_QEPCTL, 2);
        if (!(ctl & EQEP_QEPCTL_QPEN) || !pad_is(AM263X_PAD_EQEP0_A, AM263X_PAD_FN_EQEP) ||
            !pad_is(AM263X_PAD_EQEP0_B, AM263X_PAD_FN_EQEP))
            return;   // no edges reach the module
        const uint32_t cpr = get(kEqep, EQEP_QPOSMAX, 4) + 1u;
        const uint32_t pos = cpr != 0 ? in.qep_count % cpr : in.qep_count;
        int64_t d = 0;
        if (cpr != 0) {
            const uint32_t fwd = (pos + cpr - q_pos_ % cpr) % cpr;
            d = fwd <= cpr / 2 ? int64_t{fwd} : int64_t{fwd} - int64_t{cpr};
        }
        if (d > 0) q_sts_ |= EQEP_QEPSTS_QDF;
        if (d < 0) q_sts_ &= ~EQEP_QEPSTS_QDF;
        q_pos_ = pos;
        q_ilat_ = in.qep_index_count;
        if (in.qep_index_seen)
            q_sts_ |= EQEP_QEPSTS_FIMF;
        else
            q_sts_ &= ~EQEP_QEPSTS_FIMF;
        // capture unit: period between unit position events (2^UPPS counts) in capture-clock ticks
        const uint32_t cap = get(kEqep, EQEP_QCAPCTL, 2);
        if (cap & EQEP_QCAPCTL_CEN) {
            const double capclk = kSysclk / double(1u << ((cap >> EQEP_QCAPCTL_CCPS_SHIFT) & 7u));
            const double ev = double(1u << ((cap >> EQEP_QCAPCTL_UPPS_SHIFT) & 0xFu));
            cap_t_ += dt_us * 1e-6;
            cap_n_ += std::fabs(double(d));
            if (cap_n_ >= ev) {
                const double ticks = cap_t_ * capclk * ev / cap_n_;
                q_cprd_ = ticks > 65535.0 ? 0xFFFFu : static_cast<uint32_t>(std::lround(ticks));
                if (ticks > 65535.0) q_sts_ |= EQEP_QEPSTS_COEF;
                q_sts_ |= EQEP_QEPSTS_UPEVNT;
                cap_t_ = 0;
                cap_n_ = 0;
            } else if (cap_t_ * capclk > 65535.0) {
                q_sts_ |= EQEP_QEPSTS_COEF;
                q_cprd_ = 0xFFFFu;
            }
        }
        // unit timer
        const uint32_t uprd = get(kEqep, EQEP_QUPRD, 4);
        if ((ctl & EQEP_QEPCTL_UTE) && uprd != 0) {
            ut_acc_ += dt_us * 1e-6 * kSysclk;
            if (ut_acc_ >= uprd) {
                ut_acc_ = std::fmod(ut_acc_, double(uprd));
                q_flg_ |= EQEP_QFLG_UTO;
                if (ctl & EQEP_QEPCTL_QCLM) {
                    q_lat_ = q_pos_;
                    q_cprdlat_ = q_cprd_;
                }
            }
        }
    }

    // ---- MCAN
    uint32_t mcan_read(uint32_t off, unsigned size) const
    {
        if (off == MCANSS_STAT) return MCANSS_STAT_MEM_INIT_DONE;
        if (off >= MCAN_CORE_OFFSET) {
            const uint32_t r = off - MCAN_CORE_OFFSET;
            if (r == MCAN_PSR) return 0;   // error active, no last error
            if (r == MCAN_ECR) return 0;
            if (r == MCAN_TXFQS) {
                const uint32_t tfqs = (get(kMcanCfg, MCAN_CORE_OFFSET + MCAN_TXBC, 4) >> MCAN_TXBC_TFQS_SHIFT) & 0x3Fu;
                return tfqs | (tx_put_ << MCAN_TXFQS_TFQPI_SHIFT) | (tx_put_ << 8);   // free, get = put
            }
            if (r == MCAN_RXF0S)
                return rx_count_ | (rx_get_ << MCAN_RXF0S_F0GI_SHIFT) | (rx_put_ << 16) |
                       (rx_count_ >= rx_size() && rx_size() != 0 ? (1u << 24) : 0u);
            if (r == MCAN_IR) return get(kMcanCfg, off, size) | (rx_lost_ ? MCAN_IR_RF0L : 0u);
        }
        return get(kMcanCfg, off, size);
    }
    bool mcan_write(uint32_t off, uint32_t v)
    {
        if (off < MCAN_CORE_OFFSET) return off == MCANSS_STAT;
        const uint32_t r = off - MCAN_CORE_OFFSET;
        if (r == MCAN_CCCR) {
            put(kMcanCfg, off, 4, (v & MCAN_CCCR_INIT) ? v : (v & ~MCAN_CCCR_CCE));
            return true;
        }
        if (r == MCAN_TXBAR) {
            const uint32_t txbc = get(kMcanCfg, MCAN_CORE_OFFSET + MCAN_TXBC, 4);
            const uint32_t tfqs = (txbc >> MCAN_TXBC_TFQS_SHIFT) & 0x3Fu;
            for (uint32_t k = 0; k < 32; ++k) {
                if (!(v & (1u << k))) continue;
                const uint32_t e = (txbc & 0xFFFCu) + AM263X_CAN_ELEM_BYTES * k;
                std::array<uint32_t, 4> words{};
                for (uint32_t j = 0; j < 4 && e + 4 * j + 4 <= kWins[kMcanRam].size; ++j) words[j] = get(kMcanRam, e + 4 * j, 4);
                if (tx_.size() < 256) tx_.push_back(words);   // the bus takes them (can_take)
                if (tfqs != 0) tx_put_ = (tx_put_ + 1) % tfqs;
            }
            return true;
        }
        if (r == MCAN_RXF0A) {   // the element at the get index is free again
            if (rx_count_ > 0 && (v & 0x3Fu) == rx_get_) {
                rx_get_ = (rx_get_ + 1) % rx_size();
                --rx_count_;
            }
            return true;
        }
        if (r == MCAN_IR) {
            if (v & MCAN_IR_RF0L) rx_lost_ = false;   // write 1 to clear
            return true;
        }
        return false;
    }
    uint32_t rx_size() const
    {
        const uint32_t n = (get(kMcanCfg, MCAN_CORE_OFFSET + MCAN_RXF0C, 4) >> MCAN_LIST_SIZE_SHIFT) & 0x7Fu;
        return n > 64 ? 64 : n;
    }

public:
    bool can_supported() const override { return true; }
    bool can_take(CanFrame& f) override
    {
        if (tx_.empty() || !can_on_bus()) return false;
        const std::array<uint32_t, 4> w = tx_.front();
        tx_.pop_front();
        f = CanFrame{};
        f.ext = (w[0] & MCAN_ELEM_XTD) != 0;
        f.rtr = (w[0] & MCAN_ELEM_RTR) != 0;
        f.id = f.ext ? (w[0] & 0x1FFFFFFFu) : (w[0] >> MCAN_ELEM_STD_ID_SHIFT) & 0x7FFu;
        const uint32_t dlc = (w[1] >> MCAN_ELEM_DLC_SHIFT) & 0xFu;
        f.dlc = static_cast<uint8_t>(dlc > 8 ? 8 : dlc);
        for (int k = 0; k < 8; ++k) f.data[k] = static_cast<uint8_t>(w[2 + k / 4] >> (8 * (k % 4)));
        return true;
    }
    bool can_deliver(const CanFrame& f) override
    {
        const uint32_t cccr = get(kMcanCfg, MCAN_CORE_OFFSET + MCAN_CCCR, 4);
        const uint32_t n = rx_size();
        if ((cccr & MCAN_CCCR_INIT) || n == 0 || !can_on_bus()) return false;   // not on the bus
        if (rx_count_ >= n) {
            rx_lost_ = true;   // blocking FIFO: the new frame is lost
            return false;
        }
        const uint32_t sa = get(kMcanCfg, MCAN_CORE_OFFSET + MCAN_RXF0C, 4) & 0xFFFCu;
        const uint32_t e = sa + AM263X_CAN_ELEM_BYTES * rx_put_;
        const uint32_t w0 = (f.ext ? (f.id & 0x1FFFFFFFu) | MCAN_ELEM_XTD : (f.id & 0x7FFu) << MCAN_ELEM_STD_ID_SHIFT) |
                            (f.rtr ? MCAN_ELEM_RTR : 0u);
        const uint32_t w1 = static_cast<uint32_t>(f.dlc & 0xFu) << MCAN_ELEM_DLC_SHIFT;
        uint32_t d[2] = {0, 0};
        for (int k = 0; k < 8; ++k) d[k / 4] |= static_cast<uint32_t>(f.data[k]) << (8 * (k % 4));
        if (e + 16 > kWins[kMcanRam].size) return false;
        put(kMcanRam, e, 4, w0);
        put(kMcanRam, e + 4, 4, w1);
        put(kMcanRam, e + 8, 4, d[0]);
        put(kMcanRam, e + 12, 4, d[1]);
        rx_put_ = (rx_put_ + 1) % n;
        ++rx_count_;
        return true;
    }

private:

    // ---- QSPI configuration port -> the flash window
    void qspi_cmd(uint32_t v)
    {
        if (get(kQspi, QSPI_SPI_SWITCH, 4) & QSPI_SWITCH_MMPT_S) return;   // memory-mapped port: ignored
        const uint32_t flen = (v & QSPI_CMD_FLEN_MASK) + 1u;
        const uint32_t cmd = (v >> QSPI_CMD_CMD_SHIFT) & QSPI_CMD_CMD_MASK;
        const uint32_t wlen = ((v >> QSPI_CMD_WLEN_SHIFT) & QSPI_CMD_WLEN_MASK) + 1u;
        if (wlen != 8) {   // this model only knows byte words
            frame_.clear();
            return;
        }
        if (cmd == QSPI_CMD_WRITE_SINGLE) {
            frame_.push_back(static_cast<uint8_t>(get(kQspi, QSPI_SPI_DATA, 4)));
        } else if (cmd == QSPI_CMD_READ_SINGLE) {
            uint8_t b = 0xFF;
            if (!frame_.empty() && frame_[0] == NOR_CMD_RDSR) b = flash_busy() ? NOR_SR_WIP : wel_ ? NOR_SR_WEL : 0;
            put(kQspi, QSPI_SPI_DATA, 4, b);
            frame_.push_back(b);
        }
        if (frame_.size() >= flen) {
            flash_frame();
            frame_.clear();
        }
    }
    void flash_frame()
    {
        const uint8_t c = frame_[0];
        if (flash_busy()) return;   // an erase running: the part takes only RDSR
        const auto addr = [&] {
            return (uint32_t{frame_[1]} << 16) | (uint32_t{frame_[2]} << 8) | frame_[3];
        };
        if (c == NOR_CMD_WREN) {
            wel_ = true;
        } else if (c == NOR_CMD_PP && frame_.size() > 4 && wel_) {
            const uint32_t a = addr();
            for (size_t k = 4; k < frame_.size(); ++k) {
                const uint32_t x = (a & ~0xFFu) | ((a + uint32_t(k - 4)) & 0xFFu);   // wraps in its page
                if (x >= AM263X_FLASH_WIN_SIZE || !mem_read_ || !mem_write_) break;
                uint8_t old = 0;
                mem_read_(AM263X_FLASH_WIN_BASE + x, &old, 1);
                const uint8_t nw = old & frame_[k];
                mem_write_(AM263X_FLASH_WIN_BASE + x, &nw, 1);
            }
            wel_ = false;
        } else if ((c == NOR_CMD_P4E || c == NOR_CMD_SE) && frame_.size() == 4 && wel_) {
            flash_erase(c, addr());
            if (c == NOR_CMD_SE) erase_end_us_ = uint64_t{time_us_} + kSectorEraseUs;
            wel_ = false;
        }
    }
    // S25FL128S (TBPARM = 0): a P4E erases only inside the 32 parameter sectors, an SE the 64 KiB
    // sectors above them; any other erase the part does not carry out (the driver's verify sees it).
    void flash_erase(uint8_t c, uint32_t a)
    {
        constexpr uint32_t kParamEnd = 0x20000;
        const uint32_t n = c == NOR_CMD_P4E ? 0x1000u : 0x10000u;
        if ((c == NOR_CMD_P4E) != (a < kParamEnd)) return;
        a &= ~(n - 1u);
        if (a < AM263X_FLASH_WIN_SIZE && mem_write_) {
            std::vector<uint8_t> ff(n, 0xFF);
            mem_write_(AM263X_FLASH_WIN_BASE + a, ff.data(), ff.size());
        }
    }

    // S25FL128S 64 KiB sector erase, typical: the datasheet (Cypress 001-98283, Features: erase
    // 0.5 to 0.65 MB/s) gives 64 KiB / 0.5 MB/s = 131 ms; its maximum is several times that.
    static constexpr uint32_t kSectorEraseUs = 131'000;
    bool flash_busy() const { return uint64_t{time_us_} < erase_end_us_; }
    uint64_t erase_end_us_ = 0;
    uint64_t wdt_frac_ = 0;     // WDT0 ticks x 1e6 not yet counted
    bool nfault_low_ = false;   // the gate driver pulls nFAULT low (set_pin)

    std::vector<uint8_t> mem_[kNumWin];
    MemWrite mem_write_;
    MemRead mem_read_;
    uint32_t time_us_ = 0;
    uint64_t wdt_left_ = 0;   // WDT0 down counter [watchdog-clock ticks]
    bool wdt_en_ = false, wdt_key1_ = false, wdt_expired_ = false;
    uint16_t cmpa_active_[3] = {0, 0, 0};
    uint16_t prd_active_[3] = {0, 0, 0};
    uint32_t adc_flag_ = 0, adc_ovf_ = 0;
    uint32_t vim_en_[16] = {};
    uint32_t vim_acks_ = 0;
    uint32_t locked_writes_ = 0;
    uint32_t q_pos_ = 0, q_ilat_ = 0, q_lat_ = 0, q_flg_ = 0, q_sts_ = 0, q_cprd_ = 0, q_cprdlat_ = 0;
    double ut_acc_ = 0, cap_t_ = 0, cap_n_ = 0;
    uint32_t tx_put_ = 0;
    std::deque<std::array<uint32_t, 4>> tx_;
    uint32_t rx_get_ = 0, rx_put_ = 0, rx_count_ = 0;
    bool rx_lost_ = false;
    std::vector<uint8_t> frame_;
    bool wel_ = false;
};

}  // namespace

std::unique_ptr<Peripherals> make_am263x_peripherals()
{
    return std::make_unique<Am263x>();
}

}  // namespace mcsim::pil
