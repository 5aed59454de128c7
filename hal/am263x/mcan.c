/* MCAN driver of the AM263x port, classic CAN only: bit timing, message RAM layout (filters
 * reserved and disabled, RX FIFO 0, TX FIFO; am263x/regs_mcan.h), polled send and receive, bus
 * state and bus-off recovery. Register facts: am263x/regs_mcan.h (TRM: MCAN Message RAM, MCAN
 * Registers; the Bosch M_CAN element layout). */
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_mcan.h"

#define INIT_POLLS 100000u   /* reads of STAT / CCCR before a state change counts as failed */

bool am263x_can_bit_timing(uint32_t bitrate, uint32_t fclk_hz, am263x_can_timing_t *t)
{
    bool found = false;
    uint32_t best_err = 0xFFFFFFFFu;
    if (bitrate == 0u) {
        return false;
    }
    for (uint32_t n = 25u; n >= 8u; --n) {   /* time quanta per bit, more first */
        const uint64_t q = (uint64_t)bitrate * n;
        if (fclk_hz % q != 0u) {
            continue;
        }
        const uint32_t brp = (uint32_t)(fclk_hz / q);
        if (brp < 1u || brp > 512u) {
            continue;
        }
        /* sample point at (1 + tseg1) / n, nearest 87.5 % (in 1/1000 of a bit) */
        uint32_t tseg2 = (n + 4u) / 8u;
        if (tseg2 < 1u) {
            tseg2 = 1u;
        }
        const uint32_t tseg1 = n - 1u - tseg2;
        const uint32_t sp = 1000u * (1u + tseg1) / n;
        const uint32_t err = sp > 875u ? sp - 875u : 875u - sp;
        if (err < best_err) {
            best_err = err;
            t->brp = (uint16_t)brp;
            t->tseg1 = (uint8_t)tseg1;
            t->tseg2 = (uint8_t)tseg2;
            t->sjw = (uint8_t)(tseg2 < 4u ? tseg2 : 4u);
            found = true;
        }
    }
    return found;
}

uint32_t am263x_can_nbtp(const am263x_can_timing_t *t)
{
    /* every field holds "value - 1" */
    return ((uint32_t)(t->sjw - 1u) << MCAN_NBTP_NSJW_SHIFT) | ((uint32_t)(t->brp - 1u) << MCAN_NBTP_NBRP_SHIFT) |
           ((uint32_t)(t->tseg1 - 1u) << MCAN_NBTP_NTSEG1_SHIFT) | ((uint32_t)(t->tseg2 - 1u) << MCAN_NBTP_NTSEG2_SHIFT);
}

void am263x_can_encode(const hal_can_frame_t *f, uint32_t w[MCAN_ELEM_WORDS])
{
    uint32_t w0 = f->ext ? (f->id & 0x1FFFFFFFu) | MCAN_ELEM_XTD : (f->id & 0x7FFu) << MCAN_ELEM_STD_ID_SHIFT;
    if (f->rtr) {
        w0 |= MCAN_ELEM_RTR;
    }
    w[0] = w0;
    w[1] = (uint32_t)(f->dlc & 0xFu) << MCAN_ELEM_DLC_SHIFT;   /* FDF, BRS, EFC, MM = 0 */
    w[2] = (uint32_t)f->data[0] | ((uint32_t)f->data[1] << 8) | ((uint32_t)f->data[2] << 16) |
           ((uint32_t)f->data[3] << 24);
    w[3] = (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) | ((uint32_t)f->data[6] << 16) |
           ((uint32_t)f->data[7] << 24);
}

bool am263x_can_decode(const uint32_t w[MCAN_ELEM_WORDS], hal_can_frame_t *f)
{
    if ((w[1] & MCAN_ELEM_FDF) != 0u) {
        return false;
    }
    f->ext = (w[0] & MCAN_ELEM_XTD) != 0u;
    f->rtr = (w[0] & MCAN_ELEM_RTR) != 0u;
    f->id = f->ext ? (w[0] & 0x1FFFFFFFu) : (w[0] >> MCAN_ELEM_STD_ID_SHIFT) & 0x7FFu;
    uint32_t dlc = (w[1] >> MCAN_ELEM_DLC_SHIFT) & 0xFu;
    f->dlc = (uint8_t)(dlc > 8u ? 8u : dlc);   /* classic CAN: a DLC of 9..15 means 8 bytes */
    for (uint32_t k = 0u; k < 8u; ++k) {
        f->data[k] = (uint8_t)(w[2u + k / 4u] >> (8u * (k % 4u)));
    }
    return true;
}

static bool wait_bits(uintptr_t reg, uint32_t mask, uint32_t want)
{
    for (uint32_t k = 0u; k < INIT_POLLS; ++k) {
        if ((am263x_rd32(reg) & mask) == want) {
            return true;
        }
    }
    return false;
}

bool am263x_can_init(hal_can_t *can, uint32_t bitrate, uint32_t fclk_hz)
{
    am263x_can_timing_t t;
    can->up = false;
    can->tx_dropped = 0u;
    can->rx_lost = 0u;
    can->rx_bad = 0u;
    if (!am263x_can_bit_timing(bitrate, fclk_hz, &t)) {
        return false;
    }
    const uintptr_t c = can->core;
    /* message RAM initialised by the wrapper after reset */
    if (!wait_bits(can->ss + MCANSS_STAT, MCANSS_STAT_MEM_INIT_DONE, MCANSS_STAT_MEM_INIT_DONE)) {
        return false;
    }
    /* initialisation mode, then configuration change enable */
    am263x_wr32(c + MCAN_CCCR, MCAN_CCCR_INIT);
    if (!wait_bits(c + MCAN_CCCR, MCAN_CCCR_INIT, MCAN_CCCR_INIT)) {
        return false;
    }
    am263x_wr32(c + MCAN_CCCR, MCAN_CCCR_INIT | MCAN_CCCR_CCE);   /* classic CAN: FDOE = BRSE = 0 */
    am263x_wr32(c + MCAN_NBTP, am263x_can_nbtp(&t));
    am263x_wr32(c + MCAN_GFC, 0u);   /* non-matching std/ext frames and remote frames -> FIFO 0 */
    for (uint32_t k = 0u; k < AM263X_CAN_SID_NUM; ++k) {
        am263x_wr32(can->ram + AM263X_CAN_SID_OFF + 4u * k, 0u);   /* SFEC 0: disabled */
    }
    for (uint32_t k = 0u; k < 2u * AM263X_CAN_XID_NUM; ++k) {
        am263x_wr32(can->ram + AM263X_CAN_XID_OFF + 4u * k, 0u);   /* EFEC 0: disabled */
    }
    am263x_wr32(c + MCAN_SIDFC, AM263X_CAN_SID_OFF | (AM263X_CAN_SID_NUM << MCAN_LIST_SIZE_SHIFT));
    am263x_wr32(c + MCAN_XIDFC, AM263X_CAN_XID_OFF | (AM263X_CAN_XID_NUM << MCAN_LIST_SIZE_SHIFT));
    am263x_wr32(c + MCAN_RXF0C, AM263X_CAN_RX0_OFF | (AM263X_CAN_RX0_NUM << MCAN_LIST_SIZE_SHIFT));
    am263x_wr32(c + MCAN_RXESC, 0u);   /* 8-byte data fields */
    am263x_wr32(c + MCAN_TXESC, 0u);
    am263x_wr32(c + MCAN_TXBC, AM263X_CAN_TX_OFF | (AM263X_CAN_TX_NUM << MCAN_TXBC_TFQS_SHIFT));
    am263x_wr32(c + MCAN_TXEFC, 0u);
    am263x_wr32(c + MCAN_IE, 0u);      /* polled */
    am263x_wr32(c + MCAN_ILE, 0u);
    am263x_wr32(c + MCAN_IR, 0xFFFFFFFFu);
    /* leave initialisation: the controller joins the bus after 11 recessive bits */
    am263x_wr32(c + MCAN_CCCR, 0u);
    if (!wait_bits(c + MCAN_CCCR, MCAN_CCCR_INIT, 0u)) {
        return false;
    }
    can->up = true;
    return true;
}

/* ---- hal/can.h */
bool hal_can_send(hal_can_t *can, const hal_can_frame_t *f)
{
    if (!can->up || !hal_can_frame_valid(f)) {
        return false;
    }
    const uintptr_t c = can->core;
    if ((am263x_rd32(c + MCAN_PSR) & MCAN_PSR_BO) != 0u) {
        return false;
    }
    const uint32_t fqs = am263x_rd32(c + MCAN_TXFQS);
    if ((fqs & MCAN_TXFQS_TFQF) != 0u) {
        can->tx_dropped++;
        return false;
    }
    const uint32_t put = (fqs >> MCAN_TXFQS_TFQPI_SHIFT) & MCAN_TXFQS_TFQPI_MASK;
    uint32_t w[MCAN_ELEM_WORDS];
    am263x_can_encode(f, w);
    const uintptr_t e = can->ram + AM263X_CAN_TX_OFF + AM263X_CAN_ELEM_BYTES * put;
    for (uint32_t k = 0u; k < MCAN_ELEM_WORDS; ++k) {
        am263x_wr32(e + 4u * k, w[k]);
    }
    am263x_wr32(c + MCAN_TXBAR, 1u << put);   /* add request: the element is queued */
    return true;
}

bool hal_can_receive(hal_can_t *can, hal_can_frame_t *f)
{
    if (!can->up) {
        return false;
    }
    const uintptr_t c = can->core;
    for (uint32_t n = 0u; n < AM263X_CAN_RX0_NUM; ++n) {   /* each pass takes one element */
        const uint32_t s = am263x_rd32(c + MCAN_RXF0S);
        if ((am263x_rd32(c + MCAN_IR) & MCAN_IR_RF0L) != 0u) {
            can->rx_lost++;
            am263x_wr32(c + MCAN_IR, MCAN_IR_RF0L);
        }
        if ((s & MCAN_RXF0S_F0FL_MASK) == 0u) {
            return false;
        }
        const uint32_t gi = (s >> MCAN_RXF0S_F0GI_SHIFT) & MCAN_RXF0S_F0GI_MASK;
        const uintptr_t e = can->ram + AM263X_CAN_RX0_OFF + AM263X_CAN_ELEM_BYTES * gi;
        uint32_t w[MCAN_ELEM_WORDS];
        for (uint32_t k = 0u; k < MCAN_ELEM_WORDS; ++k) {
            w[k] = am263x_rd32(e + 4u * k);
        }
        am263x_wr32(c + MCAN_RXF0A, gi);   /* acknowledge: the element is free again */
        if (am263x_can_decode(w, f)) {
            return true;
        }
        can->rx_bad++;
    }
    return false;
}

hal_can_state_t hal_can_state(const hal_can_t *can)
{
    if (!can->up) {
        return HAL_CAN_BUS_OFF;
    }
    const uint32_t psr = am263x_rd32(can->core + MCAN_PSR);
    if ((psr & MCAN_PSR_BO) != 0u) {
        return HAL_CAN_BUS_OFF;
    }
    return (psr & MCAN_PSR_EP) != 0u ? HAL_CAN_ERROR_PASSIVE : HAL_CAN_ERROR_ACTIVE;
}

void hal_can_recover(hal_can_t *can)
{
    if (!can->up) {
        return;
    }
    /* at bus-off the controller sets CCCR.INIT; clearing it starts the recovery sequence
     * (129 x 11 recessive bits, ISO 11898-1), after which the controller is error active */
    const uint32_t cccr = am263x_rd32(can->core + MCAN_CCCR);
    if ((cccr & MCAN_CCCR_INIT) != 0u) {
        am263x_wr32(can->core + MCAN_CCCR, cccr & ~(MCAN_CCCR_INIT | MCAN_CCCR_CCE));
    }
}
