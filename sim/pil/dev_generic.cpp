// Processor-in-the-loop register model of the generic memory-mapped port (hal/generic): exactly
// the registers of hal/generic/include/hal_generic/regs.h, backed by the plant's PeriphInputs at
// each period boundary (PWM counter zero).
//
//  - Memories: flash 0 .. 512 KiB (the image, then the NVM blocks), SRAM 0x20000000, 64 KiB.
//  - PWM: CTRL (RUN, OE: the outputs are on iff both are set, a change takes effect at once),
//    PRD, DT, CMP0..2 written into shadows that become active at counter zero while the counter
//    runs; duty = CMPx / PRD clamped to [0, 1]; period 2 PRD / GEN_PWM_CLK_HZ.
//  - ADC: at counter zero, if CTRL.EN: result n = input channel CHMAP byte n (the port's inputs:
//    channel 0..3 = phase a, b, c current, DC link; another channel number reads 0); STS.EOC set
//    (STS.OVR too if EOC was still set, or if PeriphInputs::adc_overrun); EOC and OVR write-1-to-
//    clear; the control interrupt pending while CTRL.IE and STS.EOC.
//  - QEP: POS (read-only, the plant's count within 0 .. MAX), MAX (written by the core), STS bit0
//    (an index seen), IDX (POS at the last index), all from the plant at counter zero.
//  - TIM: US, the plant's microseconds at counter zero.
//  - FLC: ADDR, DATA0/1, CMD (1: program the 8-byte unit at ADDR with flash semantics, AND;
//    2: erase the 16 KiB block holding ADDR to 0xFF), STS (BUSY always 0, ERR for a unit that is
//    not 8-byte aligned or not inside the NVM blocks, or an unknown command; write 1 to clear).
//    The NVM blocks start erased (0xFF) where the image does not load anything into them.
//  - WDT: LOAD, CTRL.EN (sticky), KICK (the key reloads the count), STS.EXP; the count runs in the
//    plant's microseconds and is checked at each period boundary: at zero STS.EXP is set and PWM
//    CTRL cleared (the hardware's trip), once.
// Word access is the registers' contract; byte and halfword accesses see the bytes of the word.
#include <algorithm>
#include <cstring>

#include "pil.hpp"

extern "C" {
#include "hal_generic/regs.h"
}

namespace mcsim::pil {
namespace {

class GenericPeripherals final : public Peripherals {
public:
    std::vector<MmioWindow> windows() const override
    {
        return {{GEN_PWM_BASE, 0x1000, "PWM"},
                {GEN_ADC_BASE, 0x1000, "ADC"},
                {GEN_QEP_BASE, 0x1000, "QEP"},
                {GEN_TIM_BASE, 0x1000, "TIM"},
                {GEN_FLC_BASE, 0x1000, "FLC"},
                {GEN_WDT_BASE, 0x1000, "WDT"}};
    }

    std::vector<MmioWindow> memories() const override
    {
        return {{GEN_FLASH_BASE, GEN_FLASH_SIZE, "flash"}, {GEN_SRAM_BASE, GEN_SRAM_SIZE, "sram"}};
    }

    void bind_memory(MemWrite write, MemRead read) override
    {
        write_ = std::move(write);
        read_ = std::move(read);
        // A fresh part: NVM blocks the image leaves empty are erased flash.
        std::vector<uint8_t> blk(GEN_NVM_BLOCK);
        for (uint32_t k = 0; k < GEN_NVM_BLOCKS; ++k) {
            const uint32_t a = GEN_NVM_BASE + k * GEN_NVM_BLOCK;
            read_(a, blk.data(), blk.size());
            if (std::all_of(blk.begin(), blk.end(), [](uint8_t b) { return b == 0; })) {
                std::fill(blk.begin(), blk.end(), uint8_t{0xFF});
                write_(a, blk.data(), blk.size());
            }
        }
    }

    uint64_t read(uint64_t addr, unsigned size) override
    {
        const uint32_t a = static_cast<uint32_t>(addr);
        const uint32_t w = reg_read(a & ~3u);
        const unsigned sh = 8u * (a & 3u);
        return size >= 4 ? w : (w >> sh) & ((1u << (8u * size)) - 1u);
    }

    void write(uint64_t addr, unsigned size, uint64_t value) override
    {
        const uint32_t a = static_cast<uint32_t>(addr);
        const uint32_t base = a & ~3u;
        uint32_t v = static_cast<uint32_t>(value);
        if (size < 4) {
            const unsigned sh = 8u * (a & 3u);
            const uint32_t mask = ((1u << (8u * size)) - 1u) << sh;
            const bool w1c_or_cmd = base == GEN_ADC_BASE + GEN_ADC_STS || base == GEN_FLC_BASE + GEN_FLC_STS ||
                                    base == GEN_FLC_BASE + GEN_FLC_CMD;
            const uint32_t old = w1c_or_cmd ? 0u : reg_read(base);
            v = (old & ~mask) | ((v << sh) & mask);
        }
        reg_write(base, v);
    }

    void period_boundary(const PeriphInputs& in) override
    {
        // PWM: the shadow compares take effect at counter zero (while the counter runs)
        if (pwm_ctrl_ & GEN_PWM_CTRL_RUN) std::copy(std::begin(cmp_), std::end(cmp_), std::begin(cmp_active_));
        // ADC
        if (adc_ctrl_ & GEN_ADC_CTRL_EN) {
            const uint32_t ch[4] = {in.adc_i[0], in.adc_i[1], in.adc_i[2], in.adc_vdc};
            for (unsigned n = 0; n < 4; ++n) {
                const uint32_t c = (chmap_ >> (8u * n)) & 0xFFu;
                res_[n] = c < 4 ? ch[c] : 0u;
            }
            if ((adc_sts_ & GEN_ADC_STS_EOC) || in.adc_overrun) adc_sts_ |= GEN_ADC_STS_OVR;
            adc_sts_ |= GEN_ADC_STS_EOC;
        }
        // encoder, time base
        qep_count_ = in.qep_count;
        qep_index_seen_ = in.qep_index_seen;
        qep_index_count_ = in.qep_index_count;
        wdt_advance(in.time_us - time_us_);
        time_us_ = in.time_us;
    }

    PeriphOutputs outputs() const override { return make_outputs(cmp_active_); }
    PeriphOutputs pending_outputs() const override
    {
        return make_outputs((pwm_ctrl_ & GEN_PWM_CTRL_RUN) ? cmp_ : cmp_active_);
    }

    bool irq_pending() const override
    {
        return (adc_ctrl_ & GEN_ADC_CTRL_IE) != 0 && (adc_sts_ & GEN_ADC_STS_EOC) != 0;
    }

    double pwm_period_s() const override { return 2.0 * prd_ / static_cast<double>(GEN_PWM_CLK_HZ); }
    double dead_time_s() const override { return dt_ / static_cast<double>(GEN_PWM_CLK_HZ); }
    uint32_t pwm_counts() const override { return prd_; }   // duty = CMPx / PRD: the on-time

private:
    PeriphOutputs make_outputs(const uint32_t (&cmp)[3]) const
    {
        PeriphOutputs o;
        for (int k = 0; k < 3; ++k)
            o.duty[k] = prd_ == 0 ? 0.0 : std::clamp(static_cast<double>(cmp[k]) / prd_, 0.0, 1.0);
        o.enabled = (pwm_ctrl_ & (GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE)) == (GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE);
        return o;
    }

    uint32_t reg_read(uint32_t a) const
    {
        switch (a) {
        case GEN_PWM_BASE + GEN_PWM_CTRL: return pwm_ctrl_;
        case GEN_PWM_BASE + GEN_PWM_PRD: return prd_;
        case GEN_PWM_BASE + GEN_PWM_DT: return dt_;
        case GEN_PWM_BASE + GEN_PWM_CMP(0): return cmp_[0];
        case GEN_PWM_BASE + GEN_PWM_CMP(1): return cmp_[1];
        case GEN_PWM_BASE + GEN_PWM_CMP(2): return cmp_[2];
        case GEN_ADC_BASE + GEN_ADC_CTRL: return adc_ctrl_;
        case GEN_ADC_BASE + GEN_ADC_STS: return adc_sts_;
        case GEN_ADC_BASE + GEN_ADC_CHMAP: return chmap_;
        case GEN_ADC_BASE + GEN_ADC_RES(0): return res_[0];
        case GEN_ADC_BASE + GEN_ADC_RES(1): return res_[1];
        case GEN_ADC_BASE + GEN_ADC_RES(2): return res_[2];
        case GEN_ADC_BASE + GEN_ADC_RES(3): return res_[3];
        case GEN_QEP_BASE + GEN_QEP_POS: return qep_max_ != 0 ? qep_count_ % (qep_max_ + 1u) : qep_count_;
        case GEN_QEP_BASE + GEN_QEP_MAX: return qep_max_;
        case GEN_QEP_BASE + GEN_QEP_STS: return qep_index_seen_ ? 1u : 0u;
        case GEN_QEP_BASE + GEN_QEP_IDX: return qep_index_count_;
        case GEN_TIM_BASE + GEN_TIM_US: return time_us_;
        case GEN_FLC_BASE + GEN_FLC_ADDR: return flc_addr_;
        case GEN_FLC_BASE + GEN_FLC_DATA0: return flc_data_[0];
        case GEN_FLC_BASE + GEN_FLC_DATA1: return flc_data_[1];
        case GEN_FLC_BASE + GEN_FLC_STS: return flc_sts_;
        case GEN_WDT_BASE + GEN_WDT_LOAD: return wdt_load_;
        case GEN_WDT_BASE + GEN_WDT_CTRL: return wdt_en_ ? GEN_WDT_CTRL_EN : 0u;
        case GEN_WDT_BASE + GEN_WDT_STS: return wdt_exp_ ? GEN_WDT_STS_EXP : 0u;
        default: return 0;   // CMD, unmapped offsets
        }
    }

    void reg_write(uint32_t a, uint32_t v)
    {
        switch (a) {
        case GEN_PWM_BASE + GEN_PWM_CTRL: pwm_ctrl_ = v & (GEN_PWM_CTRL_RUN | GEN_PWM_CTRL_OE); break;
        case GEN_PWM_BASE + GEN_PWM_PRD: prd_ = v; break;
        case GEN_PWM_BASE + GEN_PWM_DT: dt_ = v; break;
        case GEN_PWM_BASE + GEN_PWM_CMP(0): cmp_[0] = v; break;
        case GEN_PWM_BASE + GEN_PWM_CMP(1): cmp_[1] = v; break;
        case GEN_PWM_BASE + GEN_PWM_CMP(2): cmp_[2] = v; break;
        case GEN_ADC_BASE + GEN_ADC_CTRL: adc_ctrl_ = v & (GEN_ADC_CTRL_EN | GEN_ADC_CTRL_IE); break;
        case GEN_ADC_BASE + GEN_ADC_STS: adc_sts_ &= ~(v & (GEN_ADC_STS_EOC | GEN_ADC_STS_OVR)); break;
        case GEN_ADC_BASE + GEN_ADC_CHMAP: chmap_ = v; break;
        case GEN_QEP_BASE + GEN_QEP_MAX: qep_max_ = v; break;
        case GEN_FLC_BASE + GEN_FLC_ADDR: flc_addr_ = v; break;
        case GEN_FLC_BASE + GEN_FLC_DATA0: flc_data_[0] = v; break;
        case GEN_FLC_BASE + GEN_FLC_DATA1: flc_data_[1] = v; break;
        case GEN_FLC_BASE + GEN_FLC_CMD: flc_command(v); break;
        case GEN_FLC_BASE + GEN_FLC_STS: flc_sts_ &= ~(v & 2u); break;
        case GEN_WDT_BASE + GEN_WDT_LOAD:
        case GEN_WDT_BASE + GEN_WDT_CTRL:
        case GEN_WDT_BASE + GEN_WDT_KICK: wdt_write(a - GEN_WDT_BASE, v); break;
        default: break;   // read-only (RES, POS, STS, IDX, US) and unmapped offsets
        }
    }

    // ---- watchdog
    void wdt_write(uint32_t off, uint32_t v)
    {
        if (off == GEN_WDT_LOAD && !wdt_en_) wdt_load_ = v;
        if (off == GEN_WDT_CTRL && (v & GEN_WDT_CTRL_EN) && !wdt_en_) {
            wdt_en_ = true;
            wdt_left_ = wdt_load_;
        }
        if (off == GEN_WDT_KICK && v == GEN_WDT_KICK_KEY && !wdt_exp_) wdt_left_ = wdt_load_;
    }
    void wdt_advance(uint32_t dt_us)
    {
        if (!wdt_en_ || wdt_exp_) return;
        if (dt_us < wdt_left_) {
            wdt_left_ -= dt_us;
            return;
        }
        wdt_left_ = 0;
        wdt_exp_ = true;
        pwm_ctrl_ = 0;   // expiry: the PWM's outputs off and its counter stopped, in hardware
    }

    void flc_command(uint32_t cmd)
    {
        const uint64_t nvm_end = static_cast<uint64_t>(GEN_NVM_BASE) + GEN_NVM_BLOCKS * GEN_NVM_BLOCK;
        const bool inside = flc_addr_ >= GEN_NVM_BASE && flc_addr_ < nvm_end;
        if (cmd == GEN_FLC_CMD_PROGRAM) {
            if (!inside || flc_addr_ % GEN_NVM_UNIT != 0 || flc_addr_ + GEN_NVM_UNIT > nvm_end || !write_) {
                flc_sts_ |= 2u;
                return;
            }
            uint8_t unit[GEN_NVM_UNIT];
            read_(flc_addr_, unit, sizeof unit);
            for (unsigned j = 0; j < GEN_NVM_UNIT; ++j)
                unit[j] = static_cast<uint8_t>(unit[j] & (flc_data_[j / 4] >> (8u * (j % 4))));   // bits only clear
            write_(flc_addr_, unit, sizeof unit);
        } else if (cmd == GEN_FLC_CMD_ERASE) {
            if (!inside || !write_) {
                flc_sts_ |= 2u;
                return;
            }
            const uint32_t blk = GEN_NVM_BASE + (flc_addr_ - GEN_NVM_BASE) / GEN_NVM_BLOCK * GEN_NVM_BLOCK;
            std::vector<uint8_t> ff(GEN_NVM_BLOCK, 0xFF);
            write_(blk, ff.data(), ff.size());
        } else {
            flc_sts_ |= 2u;   // unknown command
        }
    }

    MemWrite write_;
    MemRead read_;
    uint32_t pwm_ctrl_ = 0, prd_ = 0, dt_ = 0;
    uint32_t cmp_[3] = {0, 0, 0}, cmp_active_[3] = {0, 0, 0};
    uint32_t adc_ctrl_ = 0, adc_sts_ = 0, chmap_ = 0x03020100u, res_[4] = {0, 0, 0, 0};
    uint32_t qep_count_ = 0, qep_max_ = 0, qep_index_count_ = 0;
    bool qep_index_seen_ = false;
    uint32_t time_us_ = 0;
    uint32_t flc_addr_ = 0, flc_data_[2] = {0, 0}, flc_sts_ = 0;
    uint32_t wdt_load_ = 0, wdt_left_ = 0;
    bool wdt_en_ = false, wdt_exp_ = false;
};

}  // namespace

std::unique_ptr<Peripherals> make_generic_peripherals()
{
    return std::make_unique<GenericPeripherals>();
}

}  // namespace mcsim::pil
