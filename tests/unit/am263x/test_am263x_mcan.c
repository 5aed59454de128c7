/* AM263x MCAN driver against RAM register fakes: nominal bit timing at the 80 MHz functional
 * clock, the message RAM element words of a standard and an extended frame (T0/T1 and data) and
 * the decoding of received elements (R0/R1), the initialisation's layout registers, sending into
 * the TX FIFO at its put index, receiving from RX FIFO 0 at its get index, bus state and
 * recovery. */
#include "../mc_test.h"
#include <string.h>

#include "am263x/port.h"
#include "am263x/regs_mcan.h"
#include "am263x/regs_soc.h"

static uint8_t cfg_ram[0x1000] __attribute__((aligned(8)));
static uint8_t msg_ram[0x8000] __attribute__((aligned(8)));

static uint32_t core(uint32_t off)
{
    uint32_t v;
    memcpy(&v, cfg_ram + MCAN_CORE_OFFSET + off, 4);
    return v;
}
static void set_core(uint32_t off, uint32_t v)
{
    memcpy(cfg_ram + MCAN_CORE_OFFSET + off, &v, 4);
}
static uint32_t ram(uint32_t off)
{
    uint32_t v;
    memcpy(&v, msg_ram + off, 4);
    return v;
}
static void set_ram(uint32_t off, uint32_t v)
{
    memcpy(msg_ram + off, &v, 4);
}

static void test_bit_timing(void **st)
{
    (void)st;
    am263x_can_timing_t t;
    /* 500 kbit/s at 80 MHz: 10 x 16 quanta, sample point 14/16 = 87.5 % */
    assert_true(am263x_can_bit_timing(500000u, 80000000u, &t));
    assert_int_equal(t.brp, 10);
    assert_int_equal(t.tseg1, 13);
    assert_int_equal(t.tseg2, 2);
    assert_int_equal(t.sjw, 2);
    assert_int_equal(am263x_can_nbtp(&t), 0x02090C01u);   /* NSJW 1, NBRP 9, NTSEG1 12, NTSEG2 1 */
    assert_true(am263x_can_bit_timing(1000000u, 80000000u, &t));
    assert_int_equal(am263x_can_nbtp(&t), 0x02040C01u);
    assert_true(am263x_can_bit_timing(125000u, 80000000u, &t));
    assert_int_equal(t.brp, 40);
    assert_int_equal(1 + t.tseg1 + t.tseg2, 16);
    assert_true(am263x_can_bit_timing(250000u, 80000000u, &t));
    assert_int_equal((uint32_t)t.brp * (1u + t.tseg1 + t.tseg2) * 250000u, 80000000u);
    /* no exact divisor: refused */
    assert_false(am263x_can_bit_timing(333333u, 80000000u, &t));
    assert_false(am263x_can_bit_timing(0u, 80000000u, &t));
}

static void test_element_encoding(void **st)
{
    (void)st;
    uint32_t w[MCAN_ELEM_WORDS];
    hal_can_frame_t f = {.id = 0x123u, .ext = false, .rtr = false, .dlc = 3u, .data = {0x11, 0x22, 0x33}};
    am263x_can_encode(&f, w);
    assert_int_equal(w[0], 0x048C0000u);   /* 0x123 << 18: ID[28:18], XTD 0, RTR 0 */
    assert_int_equal(w[1], 0x00030000u);   /* DLC 3, FDF/BRS/EFC 0 */
    assert_int_equal(w[2], 0x00332211u);   /* byte 0 in bits 7:0 */
    assert_int_equal(w[3], 0u);
    hal_can_frame_t x = {.id = 0x12345678u, .ext = true, .dlc = 8u,
                         .data = {0x01, 0x02, 0x03, 0x04, 0xA5, 0xB6, 0xC7, 0xD8}};
    am263x_can_encode(&x, w);
    assert_int_equal(w[0], 0x52345678u);   /* XTD (bit 30) | 29-bit ID */
    assert_int_equal(w[1], 0x00080000u);
    assert_int_equal(w[2], 0x04030201u);
    assert_int_equal(w[3], 0xD8C7B6A5u);
    x.rtr = true;
    x.id = 0x1FFFFFFFu;
    x.dlc = 2u;
    am263x_can_encode(&x, w);
    assert_int_equal(w[0], 0x7FFFFFFFu);   /* XTD | RTR | ID */
    assert_int_equal(w[1], 0x00020000u);
    f.rtr = true;
    f.id = 0x7FFu;
    am263x_can_encode(&f, w);
    assert_int_equal(w[0], 0x3FFC0000u);   /* RTR | 0x7FF << 18 */
}

static void test_element_decoding(void **st)
{
    (void)st;
    hal_can_frame_t f;
    /* R0: std 0x123; R1: RXTS 0x1234, DLC 8, FIDX 5, ANMF 1 */
    const uint32_t a[4] = {0x048C0000u, 0x85081234u, 0x44332211u, 0x88776655u};
    assert_true(am263x_can_decode(a, &f));
    assert_false(f.ext);
    assert_false(f.rtr);
    assert_int_equal(f.id, 0x123);
    assert_int_equal(f.dlc, 8);
    assert_int_equal(f.data[0], 0x11);
    assert_int_equal(f.data[3], 0x44);
    assert_int_equal(f.data[4], 0x55);
    assert_int_equal(f.data[7], 0x88);
    /* extended remote frame, DLC 2 */
    const uint32_t b[4] = {0x60000ABCu, 0x00020000u, 0u, 0u};
    assert_true(am263x_can_decode(b, &f));
    assert_true(f.ext);
    assert_true(f.rtr);
    assert_int_equal(f.id, 0xABC);
    assert_int_equal(f.dlc, 2);
    /* a classic frame with DLC 12 carries 8 bytes */
    const uint32_t c[4] = {0x00040000u, 0x000C0000u, 0u, 0u};
    assert_true(am263x_can_decode(c, &f));
    assert_int_equal(f.id, 0x001);
    assert_int_equal(f.dlc, 8);
    /* an FD element (FDF, bit 21) is refused */
    const uint32_t d[4] = {0x048C0000u, 0x00280000u, 0u, 0u};
    assert_false(am263x_can_decode(d, &f));
    /* round trip of a frame through both */
    hal_can_frame_t g = {.id = 0x1ABCDEFu, .ext = true, .dlc = 5u, .data = {9, 8, 7, 6, 5}}, h;
    uint32_t w[4];
    am263x_can_encode(&g, w);
    assert_true(am263x_can_decode(w, &h));
    assert_int_equal(h.id, g.id);
    assert_true(h.ext);
    assert_int_equal(h.dlc, 5);
    assert_memory_equal(h.data, g.data, 5);
}

static hal_can_t can_on_fakes(void)
{
    memset(cfg_ram, 0, sizeof cfg_ram);
    memset(msg_ram, 0xCC, sizeof msg_ram);
    const uint32_t done = MCANSS_STAT_MEM_INIT_DONE;
    memcpy(cfg_ram + MCANSS_STAT, &done, 4);
    hal_can_t can = {.ss = (uintptr_t)cfg_ram, .core = (uintptr_t)cfg_ram + MCAN_CORE_OFFSET, .ram = (uintptr_t)msg_ram};
    return can;
}

static void test_init_layout(void **st)
{
    (void)st;
    hal_can_t can = can_on_fakes();
    assert_true(am263x_can_init(&can, 500000u, AM263X_MCAN_FCLK_HZ));
    assert_true(can.up);
    assert_int_equal(core(MCAN_NBTP), 0x02090C01u);
    assert_int_equal(core(MCAN_SIDFC), 0x00080000u);   /* 8 std filters at 0x000 */
    assert_int_equal(core(MCAN_XIDFC), 0x00040020u);   /* 4 ext filters at 0x020 */
    assert_int_equal(core(MCAN_RXF0C), 0x00100040u);   /* 16 elements at 0x040, blocking */
    assert_int_equal(core(MCAN_TXBC), 0x08000140u);    /* TX FIFO of 8 at 0x140, no buffers */
    assert_int_equal(core(MCAN_RXESC), 0u);
    assert_int_equal(core(MCAN_TXESC), 0u);
    assert_int_equal(core(MCAN_GFC), 0u);              /* non-matching -> FIFO 0 */
    assert_int_equal(core(MCAN_CCCR), 0u);             /* running, classic CAN */
    for (uint32_t k = 0; k < 8u; ++k) {
        assert_int_equal(ram(4u * k), 0u);             /* filters disabled */
    }
    for (uint32_t k = 0; k < 8u; ++k) {
        assert_int_equal(ram(0x20u + 4u * k), 0u);
    }
    assert_int_equal(ram(0x40u), 0xCCCCCCCCu);         /* RX FIFO not touched */
    /* a message RAM that never finishes its initialisation: refused */
    can = can_on_fakes();
    memset(cfg_ram, 0, 16);
    assert_false(am263x_can_init(&can, 500000u, AM263X_MCAN_FCLK_HZ));
    assert_false(can.up);
    hal_can_frame_t f = {.id = 1u, .dlc = 0u};
    assert_false(hal_can_send(&can, &f));
    assert_int_equal(hal_can_state(&can), HAL_CAN_BUS_OFF);
}

static void test_send_receive_state(void **st)
{
    (void)st;
    hal_can_t can = can_on_fakes();
    assert_true(am263x_can_init(&can, 500000u, AM263X_MCAN_FCLK_HZ));
    /* TX FIFO put index 3 */
    set_core(MCAN_TXFQS, (3u << 16) | 5u);
    hal_can_frame_t f = {.id = 0x181u, .dlc = 2u, .data = {0xAB, 0xCD}};
    assert_true(hal_can_send(&can, &f));
    assert_int_equal(ram(0x140u + 3u * 16u), 0x181u << 18);
    assert_int_equal(ram(0x140u + 3u * 16u + 4u), 0x00020000u);
    assert_int_equal(ram(0x140u + 3u * 16u + 8u) & 0xFFFFu, 0xCDABu);
    assert_int_equal(core(MCAN_TXBAR), 1u << 3);
    /* full: refused and counted */
    set_core(MCAN_TXFQS, MCAN_TXFQS_TFQF | (4u << 16));
    assert_false(hal_can_send(&can, &f));
    assert_int_equal(can.tx_dropped, 1);
    set_core(MCAN_TXFQS, 0u);
    f.dlc = 9u;
    assert_false(hal_can_send(&can, &f));   /* not a valid frame */
    f.dlc = 1u;
    set_core(MCAN_PSR, MCAN_PSR_BO);
    assert_false(hal_can_send(&can, &f));   /* bus-off */
    assert_int_equal(hal_can_state(&can), HAL_CAN_BUS_OFF);
    set_core(MCAN_PSR, MCAN_PSR_EP);
    assert_int_equal(hal_can_state(&can), HAL_CAN_ERROR_PASSIVE);
    set_core(MCAN_PSR, 0u);
    assert_int_equal(hal_can_state(&can), HAL_CAN_ERROR_ACTIVE);

    /* RX FIFO 0: fill level 1, get index 5 */
    hal_can_frame_t r;
    set_core(MCAN_IR, 0u);
    set_core(MCAN_RXF0S, 0u);
    assert_false(hal_can_receive(&can, &r));
    const uint32_t e = 0x40u + 5u * 16u;
    set_ram(e, 0x40000765u);   /* ext 0x765 */
    set_ram(e + 4u, 0x00040000u);
    set_ram(e + 8u, 0x04030201u);
    set_ram(e + 12u, 0u);
    set_core(MCAN_RXF0S, (5u << 8) | 1u);
    set_core(MCAN_RXF0A, 0xFFu);
    assert_true(hal_can_receive(&can, &r));
    assert_true(r.ext);
    assert_int_equal(r.id, 0x765);
    assert_int_equal(r.dlc, 4);
    assert_int_equal(r.data[2], 3);
    assert_int_equal(core(MCAN_RXF0A), 5u);   /* acknowledged */
    assert_int_equal(can.rx_lost, 0);
    set_core(MCAN_IR, MCAN_IR_RF0L);          /* the controller lost one: counted, cleared */
    set_core(MCAN_RXF0S, 0u);
    assert_false(hal_can_receive(&can, &r));
    assert_int_equal(can.rx_lost, 1);

    /* bus-off recovery: INIT set by the controller is cleared */
    set_core(MCAN_CCCR, MCAN_CCCR_INIT);
    hal_can_recover(&can);
    assert_int_equal(core(MCAN_CCCR) & MCAN_CCCR_INIT, 0u);
    set_core(MCAN_CCCR, 0x100u);   /* not in INIT: left alone */
    hal_can_recover(&can);
    assert_int_equal(core(MCAN_CCCR), 0x100u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bit_timing),
        cmocka_unit_test(test_element_encoding),
        cmocka_unit_test(test_element_decoding),
        cmocka_unit_test(test_init_layout),
        cmocka_unit_test(test_send_receive_state),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
