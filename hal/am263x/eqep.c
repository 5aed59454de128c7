/* eQEP driver of the AM263x port: quadrature count mode over one revolution, index latch, unit
 * timer (speed from the position change per unit period, high speeds) and capture unit (speed
 * from the period between unit position events, low speeds). Register facts: am263x/regs_eqep.h
 * (TRM: eQEP Quadrature Decoder Unit, Position Counter and Control Unit, Edge Capture Unit, Unit
 * Timer Base). */
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_eqep.h"
#include "am263x/regs_soc.h"

bool am263x_qep_init(hal_qep_t *qep, uint32_t counts_per_rev, uint32_t unit_clk)
{
    if (counts_per_rev < 4u || unit_clk == 0u) {
        return false;
    }
    const uintptr_t b = qep->eqep;
    am263x_wr16(b + EQEP_QEPCTL, 0u);            /* counter, unit timer, latches off */
    am263x_wr16(b + EQEP_QCAPCTL, 0u);           /* prescalers change only with CEN = 0 */
    am263x_wr16(b + EQEP_QDECCTL, EQEP_QDECCTL_QUADRATURE);
    am263x_wr32(b + EQEP_QPOSINIT, 0u);
    am263x_wr32(b + EQEP_QPOSMAX, counts_per_rev - 1u);
    am263x_wr32(b + EQEP_QPOSCNT, 0u);
    am263x_wr32(b + EQEP_QUTMR, 0u);
    am263x_wr32(b + EQEP_QUPRD, unit_clk);
    am263x_wr16(b + EQEP_QCAPCTL, (uint16_t)((AM263X_QEP_CCPS << EQEP_QCAPCTL_CCPS_SHIFT) |
                                             (AM263X_QEP_UPPS << EQEP_QCAPCTL_UPPS_SHIFT)));
    am263x_wr16(b + EQEP_QCAPCTL, (uint16_t)(EQEP_QCAPCTL_CEN | (AM263X_QEP_CCPS << EQEP_QCAPCTL_CCPS_SHIFT) |
                                             (AM263X_QEP_UPPS << EQEP_QCAPCTL_UPPS_SHIFT)));
    am263x_wr16(b + EQEP_QEINT, 0u);
    am263x_wr16(b + EQEP_QCLR, 0xFFFFu);
    am263x_wr16(b + EQEP_QEPSTS, (uint16_t)(EQEP_QEPSTS_FIMF | EQEP_QEPSTS_CDEF | EQEP_QEPSTS_COEF |
                                            EQEP_QEPSTS_UPEVNT));
    am263x_wr16(b + EQEP_QEPCTL, (uint16_t)(EQEP_QEPCTL_FREE_RUN | EQEP_QEPCTL_PCRM_MAX | EQEP_QEPCTL_IEL_RISING |
                                            EQEP_QEPCTL_QPEN | EQEP_QEPCTL_QCLM | EQEP_QEPCTL_UTE));
    qep->counts_per_rev = counts_per_rev;
    qep->unit_clk = unit_clk;
    qep->last_lat = 0u;
    qep->have_last = false;
    return true;
}

int32_t am263x_qep_delta(uint32_t prev, uint32_t cur, uint32_t cpr, bool up)
{
    const uint32_t fwd = (cur + cpr - prev) % cpr;   /* counts moved forward, 0..cpr-1 */
    const uint32_t back = (cpr - fwd) % cpr;        /* counts moved backward */
    if (fwd < back || (fwd == back && up)) {
        return (int32_t)fwd;
    }
    return -(int32_t)back;
}

float am263x_qep_unit_speed(int32_t delta, uint32_t unit_clk, uint32_t clk_hz)
{
    return (float)delta * ((float)clk_hz / (float)unit_clk);
}

float am263x_qep_capture_speed(uint16_t qcprd, uint32_t upps, uint32_t ccps, uint32_t clk_hz, bool up)
{
    if (qcprd == 0u) {
        return 0.0f;
    }
    /* 2^upps counts in qcprd ticks of clk_hz / 2^ccps */
    const float counts = (float)(1u << upps);
    const float t = (float)qcprd * (float)(1u << ccps) / (float)clk_hz;
    const float v = counts / t;
    return up ? v : -v;
}

bool am263x_qep_poll_speed(hal_qep_t *qep, am263x_qep_speed_t *out)
{
    const uintptr_t b = qep->eqep;
    if ((am263x_rd16(b + EQEP_QFLG) & EQEP_QFLG_UTO) == 0u) {
        return false;
    }
    /* latched together at the time-out (QCLM = 1) */
    const uint32_t lat = am263x_rd32(b + EQEP_QPOSLAT);
    const uint16_t cprd = am263x_rd16(b + EQEP_QCPRDLAT);
    const uint16_t sts = am263x_rd16(b + EQEP_QEPSTS);
    const bool up = (sts & EQEP_QEPSTS_QDF) != 0u;
    int32_t delta = 0;
    if (qep->have_last) {
        delta = am263x_qep_delta(qep->last_lat, lat, qep->counts_per_rev, up);
    }
    qep->last_lat = lat;
    qep->have_last = true;
    out->unit_cps = am263x_qep_unit_speed(delta, qep->unit_clk, AM263X_SYSCLK_HZ);
    out->capture_valid = (sts & (EQEP_QEPSTS_COEF | EQEP_QEPSTS_CDEF)) == 0u;
    out->capture_cps = out->capture_valid
                           ? am263x_qep_capture_speed(cprd, AM263X_QEP_UPPS, AM263X_QEP_CCPS, AM263X_SYSCLK_HZ, up)
                           : 0.0f;
    am263x_wr16(b + EQEP_QEPSTS, (uint16_t)(sts & (EQEP_QEPSTS_COEF | EQEP_QEPSTS_CDEF)));
    am263x_wr16(b + EQEP_QCLR, (uint16_t)(EQEP_QFLG_UTO | EQEP_QFLG_INT));
    return true;
}

/* ---- hal/qep.h */
void hal_qep_read(hal_qep_t *qep, hal_qep_sample_t *out)
{
    const uintptr_t b = qep->eqep;
    out->count = am263x_rd32(b + EQEP_QPOSCNT);
    out->index_seen = (am263x_rd16(b + EQEP_QEPSTS) & EQEP_QEPSTS_FIMF) != 0u;
    out->index_count = am263x_rd32(b + EQEP_QPOSILAT);
}

uint32_t hal_qep_counts_per_rev(const hal_qep_t *qep)
{
    return qep->counts_per_rev;
}
