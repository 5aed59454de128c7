/* The host port of hal/can.h and hal/nvm.h: what the CANopen stack and the parameter store will
 * rely on. CAN: frames checked, FIFO order, full rings refused and counted, bus-off refuses and
 * recovers. NVM: erased to 0xFF, writes only clear bits, alignment and range checked, and a
 * power cut leaves only the step it hit undefined, every call failing until power returns. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>
#include <cmocka.h>

#include "hal_host/host.h"

static hal_can_frame_t frame(uint32_t id, uint8_t dlc, uint8_t first)
{
    hal_can_frame_t f = {.id = id, .dlc = dlc};
    for (uint8_t k = 0; k < 8u; ++k) {
        f.data[k] = (uint8_t)(first + k);
    }
    return f;
}

static void test_can_queues_and_checks(void **st)
{
    (void)st;
    static hal_can_t can;
    hal_host_can_init(&can);
    hal_can_frame_t f = frame(0x181, 8, 1), g;
    assert_true(hal_can_send(&can, &f));
    f = frame(0x281, 2, 9);
    assert_true(hal_can_send(&can, &f));
    assert_true(hal_host_can_take(&can, &g));
    assert_int_equal(g.id, 0x181);
    assert_int_equal(g.data[7], 8);
    assert_true(hal_host_can_take(&can, &g));
    assert_int_equal(g.id, 0x281);
    assert_false(hal_host_can_take(&can, &g));
    /* not valid: dlc 9, an 11-bit id beyond 0x7FF; a 29-bit one is fine with ext */
    f = frame(0x100, 9, 0);
    assert_false(hal_can_send(&can, &f));
    f = frame(0x800, 1, 0);
    assert_false(hal_can_send(&can, &f));
    f.ext = true;
    assert_true(hal_can_send(&can, &f));
    f.id = 0x20000000u;
    assert_false(hal_can_send(&can, &f));
    assert_false(hal_host_can_deliver(&can, &f));
    /* full: refused and counted */
    hal_host_can_init(&can);
    for (uint32_t k = 0; k < HAL_HOST_CAN_QUEUE; ++k) {
        f = frame(0x700 + (k & 0x7Fu), 1, (uint8_t)k);
        assert_true(hal_can_send(&can, &f));
        assert_true(hal_host_can_deliver(&can, &f));
    }
    assert_false(hal_can_send(&can, &f));
    assert_false(hal_host_can_deliver(&can, &f));
    assert_int_equal(can.tx_dropped, 1);
    assert_int_equal(can.rx_dropped, 1);
    for (uint32_t k = 0; k < HAL_HOST_CAN_QUEUE; ++k) {
        assert_true(hal_can_receive(&can, &g));
        assert_int_equal(g.data[0], (uint8_t)k);   /* oldest first */
    }
    assert_false(hal_can_receive(&can, &g));
    /* bus-off: nothing sent until recovered */
    hal_host_can_init(&can);
    hal_host_can_set_state(&can, HAL_CAN_BUS_OFF);
    f = frame(0x701, 1, 0);
    assert_false(hal_can_send(&can, &f));
    assert_int_equal(hal_can_state(&can), HAL_CAN_BUS_OFF);
    hal_can_recover(&can);
    assert_int_equal(hal_can_state(&can), HAL_CAN_ERROR_ACTIVE);
    assert_int_equal(can.recoveries, 1);
    assert_true(hal_can_send(&can, &f));
}

static void test_nvm_flash_semantics(void **st)
{
    (void)st;
    static hal_nvm_t nvm;
    hal_host_nvm_init(&nvm);
    assert_int_equal(hal_nvm_blocks(&nvm), 4);
    assert_int_equal(hal_nvm_block_size(&nvm), 4096);
    assert_int_equal(hal_nvm_write_unit(&nvm), 8);
    uint8_t buf[16], out[16];
    assert_true(hal_nvm_read(&nvm, 3, 4088, out, 8));
    for (int k = 0; k < 8; ++k) assert_int_equal(out[k], 0xFF);
    for (int k = 0; k < 16; ++k) buf[k] = (uint8_t)(0xF0 | k);
    assert_true(hal_nvm_write(&nvm, 1, 64, buf, 16));
    assert_true(hal_nvm_read(&nvm, 1, 64, out, 16));
    assert_memory_equal(out, buf, 16);
    /* a write only clears bits: 0x0F over 0xF3 gives 0x03 */
    uint8_t ones[8];
    memset(ones, 0x0F, sizeof ones);
    assert_true(hal_nvm_write(&nvm, 1, 64, ones, 8));
    assert_true(hal_nvm_read(&nvm, 1, 64, out, 8));
    assert_int_equal(out[3], 0x03);
    assert_true(hal_nvm_erase(&nvm, 1));
    assert_true(hal_nvm_read(&nvm, 1, 64, out, 8));
    assert_int_equal(out[3], 0xFF);
    /* alignment, range, block */
    assert_false(hal_nvm_write(&nvm, 1, 4, buf, 8));
    assert_false(hal_nvm_write(&nvm, 1, 8, buf, 6));
    assert_false(hal_nvm_write(&nvm, 1, 4096, buf, 8));
    assert_false(hal_nvm_write(&nvm, 4, 0, buf, 8));
    assert_false(hal_nvm_read(&nvm, 0, 4090, out, 8));
    assert_false(hal_nvm_erase(&nvm, 4));
    assert_false(hal_nvm_write(&nvm, 0, 0, NULL, 8));
}

/* A power cut at every step of "erase block 2, write 64 bytes into it": the block written may be
 * anything, the others keep their content, every call fails until power returns. */
static void test_nvm_power_cut_every_step(void **st)
{
    (void)st;
    static hal_nvm_t nvm;
    uint8_t data[64], keep[64], out[64];
    for (int k = 0; k < 64; ++k) {
        data[k] = (uint8_t)(k * 7);
        keep[k] = (uint8_t)(0x55 ^ k);
    }
    for (uint32_t cut = 1; cut <= 9; ++cut) {   /* 1 erase + 8 write units */
        hal_host_nvm_init(&nvm);
        assert_true(hal_nvm_write(&nvm, 0, 0, keep, 64));
        assert_true(hal_nvm_write(&nvm, 2, 0, keep, 64));
        const uint32_t base = nvm.steps;
        hal_host_nvm_cut_at(&nvm, base + cut);
        const bool ok = hal_nvm_erase(&nvm, 2) && hal_nvm_write(&nvm, 2, 0, data, 64);
        assert_false(ok);
        assert_true(nvm.dead);
        assert_false(hal_nvm_read(&nvm, 0, 0, out, 64));   /* dead until power returns */
        hal_host_nvm_power_on(&nvm);
        assert_true(hal_nvm_read(&nvm, 0, 0, out, 64));
        assert_memory_equal(out, keep, 64);                 /* the other block intact */
        assert_true(hal_nvm_read(&nvm, 2, 0, out, 64));
        /* the units the cut did not reach: erased (0xFF) after an erase, untouched before */
        if (cut >= 2u) {
            for (uint32_t u = cut - 1u; u < 8u; ++u) {
                for (int k = 0; k < 8; ++k) assert_int_equal(out[8u * u + (uint32_t)k], 0xFF);
            }
        }
    }
}

/* The model with the S25FL128S's map: blocks are the sectors of the region at base (4 KiB in the
 * parameter sectors, 64 KiB above), an erase of another size is not carried out and is refused by
 * the verify, a cut in an erase scrambles that sector only. */
static void test_nvm_s25fl128s_map(void **st)
{
    (void)st;
    static hal_nvm_t nvm;
    uint8_t d[8] = {0, 1, 2, 3, 4, 5, 6, 7}, out[8];
    assert_true(hal_host_nvm_init_geom(&nvm, &hal_host_nvm_s25fl128s, 0x1000u, 3u));
    assert_int_equal(hal_nvm_block_size(&nvm), 4096);
    assert_int_equal(hal_nvm_blocks(&nvm), 3);
    assert_true(hal_nvm_write(&nvm, 1, 0, d, 8));
    assert_true(hal_nvm_write(&nvm, 2, 0, d, 8));
    assert_true(hal_nvm_erase(&nvm, 1));
    assert_true(hal_nvm_read(&nvm, 2, 0, out, 8));
    assert_memory_equal(out, d, 8);                 /* the next 4 KiB sector kept */
    assert_true(hal_host_nvm_init_geom(&nvm, &hal_host_nvm_s25fl128s, 0x7E0000u, 2u));
    assert_int_equal(hal_nvm_block_size(&nvm), 65536);
    assert_true(hal_nvm_write(&nvm, 0, 65528, d, 8));
    assert_true(hal_nvm_write(&nvm, 1, 0, d, 8));
    nvm.erase_size = 4096u;                          /* P4E into a 64 KiB sector: nothing */
    assert_false(hal_nvm_erase(&nvm, 0));
    assert_true(hal_nvm_read(&nvm, 0, 65528, out, 8));
    assert_memory_equal(out, d, 8);
    nvm.erase_size = 65536u;
    assert_true(hal_nvm_erase(&nvm, 0));
    assert_true(hal_nvm_read(&nvm, 0, 65528, out, 8));
    for (int k = 0; k < 8; ++k) assert_int_equal(out[k], 0xFF);
    assert_true(hal_nvm_read(&nvm, 1, 0, out, 8));
    assert_memory_equal(out, d, 8);                 /* the other sector kept */
    /* a cut in the erase: that sector scrambled, the other intact */
    assert_true(hal_nvm_write(&nvm, 0, 0, d, 8));
    hal_host_nvm_cut_at(&nvm, nvm.steps + 1u);
    assert_false(hal_nvm_erase(&nvm, 0));
    hal_host_nvm_power_on(&nvm);
    assert_true(hal_nvm_read(&nvm, 1, 0, out, 8));
    assert_memory_equal(out, d, 8);
}

/* The host watchdog: kicks reload it, the simulated time expires it, the expiry turns the bound
 * PWM's outputs off and sticks (a kick after it revives nothing). */
static void test_watchdog_expiry_turns_outputs_off(void **st)
{
    (void)st;
    hal_pwm_t pwm;
    hal_host_pwm_init(&pwm, 1e-4f, 0.0f);
    hal_pwm_enable(&pwm, true);
    hal_wdg_t w;
    hal_host_wdg_start(&w, 1000u, &pwm);
    for (int k = 0; k < 50; ++k) {
        assert_false(hal_host_wdg_elapse(&w, 100u));
        hal_wdg_kick(&w);
    }
    assert_int_equal(w.kicks, 50);
    assert_true(hal_pwm_enabled(&pwm));
    assert_false(hal_host_wdg_elapse(&w, 999u));
    assert_true(hal_host_wdg_elapse(&w, 1u));
    assert_false(hal_pwm_enabled(&pwm));
    hal_wdg_kick(&w);
    hal_pwm_enable(&pwm, true);
    assert_true(hal_host_wdg_elapse(&w, 0u));
    assert_true(w.expired);
}

/* hal_wdg_service kicks only when an ISR run was counted since its last kick: called in a
 * loop without ISR progress it lets the watchdog expire. */
static void test_watchdog_service_needs_isr_progress(void **st)
{
    (void)st;
    hal_wdg_t w;
    hal_host_wdg_start(&w, 1000u, NULL);
    for (int k = 0; k < 50; ++k) {
        assert_false(hal_host_wdg_elapse(&w, 100u));
        w.isr_runs++;
        hal_wdg_service(&w);
        hal_wdg_service(&w);   /* no new run: no kick */
    }
    assert_int_equal(w.kicks, 50);
    for (int k = 0; k < 9; ++k) {
        assert_false(hal_host_wdg_elapse(&w, 100u));
        hal_wdg_service(&w);
    }
    assert_int_equal(w.kicks, 50);
    assert_true(hal_host_wdg_elapse(&w, 100u));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_can_queues_and_checks),
        cmocka_unit_test(test_nvm_flash_semantics),
        cmocka_unit_test(test_nvm_power_cut_every_step),
        cmocka_unit_test(test_nvm_s25fl128s_map),
        cmocka_unit_test(test_watchdog_expiry_turns_outputs_off),
        cmocka_unit_test(test_watchdog_service_needs_isr_progress),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
