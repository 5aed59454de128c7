/* Emergency messages (CiA 301 §7.2.7) and the pre-defined error field 0x1003 (§7.5.2.3) for the
 * drive's latched faults (mc/sequencer.h). Codes from CiA 301 Table 21 and CiA 402's drive
 * error codes; the manufacturer bytes carry the fault bit number and the whole fault word, so
 * that a tool names the drive's own reason (docs/protection.md). */
#include "mc/co.h"

uint16_t mc_co_emcy_code(uint32_t bit)
{
    switch (1u << bit) {
    case MC_FAULT_OVERCURRENT: return 0x2310u;      /* continuous over-current, device output */
    case MC_FAULT_OVERVOLTAGE: return 0x3210u;      /* DC link over-voltage */
    case MC_FAULT_UNDERVOLTAGE: return 0x3220u;     /* DC link under-voltage */
    case MC_FAULT_OFFSET_CAL:
    case MC_FAULT_CURRENT_SENSOR: return 0x5210u;   /* measurement circuit */
    case MC_FAULT_CONFIG: return 0x6320u;           /* parameter error */
    case MC_FAULT_TIMEOUT:
    case MC_FAULT_NUMERIC:
    case MC_FAULT_OVERRUN: return 0x6100u;          /* internal software */
    case MC_FAULT_INIT_POS:
    case MC_FAULT_LOSS_OF_LOCK:
    case MC_FAULT_VOLTAGE_MODEL: return 0x7300u;    /* sensor (the sensorless angle's plausibility) */
    case MC_FAULT_STALL: return 0x7121u;            /* motor blocked */
    case MC_FAULT_OVERSPEED: return 0x8400u;        /* velocity / speed monitoring */
    case MC_FAULT_TRACKING:
    case MC_FAULT_TORQUE: return 0x8300u;           /* torque control */
    default: return 0x1000u;                        /* generic error */
    }
}

uint8_t mc_co_error_register(uint32_t faults)
{
    if (faults == 0u) {
        return 0u;
    }
    uint8_t r = 0x01u;   /* generic */
    if ((faults & (MC_FAULT_OVERCURRENT | MC_FAULT_OFFSET_CAL | MC_FAULT_CURRENT_SENSOR | MC_FAULT_TRACKING)) != 0u) {
        r |= 0x02u;      /* current */
    }
    if ((faults & (MC_FAULT_OVERVOLTAGE | MC_FAULT_UNDERVOLTAGE)) != 0u) {
        r |= 0x04u;      /* voltage */
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
