/* Emergency messages (CiA 301 §7.2.7) and the pre-defined error field 0x1003 (§7.5.2.3) for the
 * drive's latched faults. The codes and error-register bits are the fault table's (mc/faults.h,
 * CiA 301 Table 21 and CiA 402's drive error codes); the manufacturer bytes carry the fault bit
 * number and the whole fault word, so that a tool names the drive's own reason. */
#include "mc/co.h"

/* By bit: the EMCY code (0: no fault has this bit) and the error-register bits besides generic.
 * A bit given twice fails the build (-Woverride-init), one >= 32 too (beyond the array). */
static const struct {
    uint16_t code;
    uint8_t reg;
} by_bit[32] = {
#define MC_FAULT_EMCY_(NAME, bit, name, emcy, reg_, reaction, rec, doc) [bit] = {emcy, MC_ERR_REG_##reg_},
    MC_FAULTS(MC_FAULT_EMCY_)
#undef MC_FAULT_EMCY_
};

uint16_t mc_co_emcy_code(uint32_t bit)
{
    return bit < 32u && by_bit[bit].code != 0u ? by_bit[bit].code : 0x1000u;   /* else generic */
}

uint8_t mc_co_error_register(uint32_t faults)
{
    if (faults == 0u) {
        return 0u;
    }
    uint8_t r = MC_ERR_REG_GENERIC;
    for (uint32_t b = 0u; b < 32u; ++b) {
        if ((faults & (1u << b)) != 0u) {
            r |= by_bit[b].reg;
        }
    }
    return r;
}

/* A drive fault's EMCY: the manufacturer bytes carry the fault bit number and the low 32 bits
 * of the fault word less its top byte (a tool names the reason from the bit). */
static void emcy(mc_co_t *co, uint16_t code, uint8_t reg, uint8_t bit, uint32_t faults)
{
    const uint8_t info[5] = {bit, (uint8_t)faults, (uint8_t)(faults >> 8), (uint8_t)(faults >> 16),
                             (uint8_t)(faults >> 24)};
    mc_co_emcy_send(co, code, reg, info);
}

void mc_co_emcy_step(mc_co_t *co)
{
    const uint32_t faults = mc_drive_faults(co->drive);
    const uint32_t fresh = faults & ~co->faults_seen;
    if (co->nmt != MC_NMT_STOPPED) {   /* §7.3.2: no EMCY in STOPPED; reported when it leaves */
        for (uint32_t b = 0u; b < 32u; ++b) {
            if ((fresh & (1u << b)) == 0u) {
                continue;
            }
            const uint16_t code = mc_co_emcy_code(b);
            for (uint32_t k = 7u; k > 0u; --k) {
                co->err_hist[k] = co->err_hist[k - 1u];
            }
            co->err_hist[0] = (uint32_t)code | (b << 16);
            if (co->err_count < 8u) {
                co->err_count++;
            }
            emcy(co, code, mc_co_error_register(faults), (uint8_t)b, faults);
        }
        if (faults == 0u && co->faults_seen != 0u) {
            emcy(co, 0x0000u, 0u, 0u, 0u);   /* error reset / no error */
        }
        co->faults_seen = faults;
    }
}
