/* AM263x NVM driver (QSPI NOR through TI's QSPI controller) against a register fake: the driver is
 * built with AM263X_MMIO_HOOKS, so that every register access comes here; the QSPI0 registers are
 * emulated (configuration-port words assembled into frames, a serial NOR behind them: WREN/WEL,
 * RDSR with WIP for a set number of polls, page program = AND, and the S25FL128S's erases: P4E
 * erases a 4 KiB parameter sector (0x000000-0x01FFFF) and nothing elsewhere, SE a 64 KiB sector
 * above them), the flash window is a RAM array. Checked: the exact command sequence of an erase
 * and of a write (bytes on the wire, the address most significant byte first), flash semantics,
 * the configuration port only used between the switches, argument checks, write protection, a
 * device that never finishes, bits that do not program, the blocks placed from the map, and an
 * erase the part did not carry out (wrong command for the region, or none) refused. */
#include "../mc_test.h"
#include <stdlib.h>
#include <string.h>

#include "am263x/port.h"
#include "am263x/regs_qspi.h"
#include "am263x/regs_soc.h"

#define FLASH_SIZE AM263X_FLASH_WIN_SIZE
#define MAX_FRAMES 256

static uint8_t qspi_ram[0x100] __attribute__((aligned(8)));
static uint8_t *flash;

typedef struct {
    uint8_t b[16];
    uint32_t n;
} frame_t;

static struct {
    uint32_t sw, data, busy_left;
    uint32_t flen, words;
    frame_t cur;
    frame_t log[MAX_FRAMES];
    uint32_t nlog, errors;
    int wel;
    uint32_t wip_left, program_busy, erase_busy;
    int write_protect, stuck, ignore_erase;
} q;

static void run_frame(void)
{
    const frame_t *f = &q.cur;
    if (q.nlog < MAX_FRAMES) {
        q.log[q.nlog++] = *f;
    }
    const uint32_t a = f->n >= 4u ? ((uint32_t)f->b[1] << 16) | ((uint32_t)f->b[2] << 8) | f->b[3] : 0u;
    switch (f->b[0]) {
    case NOR_CMD_WREN:
        if (!q.write_protect) {
            q.wel = 1;
        }
        break;
    case NOR_CMD_PP:
        if (q.wel && !q.stuck) {
            for (uint32_t k = 4u; k < f->n; ++k) {
                flash[(a & ~0xFFu) | ((a + k - 4u) & 0xFFu)] &= f->b[k];
            }
        }
        if (q.wel) {
            q.wip_left = q.program_busy;
        }
        q.wel = 0;
        break;
    case NOR_CMD_P4E:   /* only the parameter sectors: elsewhere the part erases nothing */
    case NOR_CMD_SE:    /* 64 KiB sectors above them (an SE into them is not used, not modelled) */
        if (q.wel) {
            const int p4e = f->b[0] == NOR_CMD_P4E;
            if (!q.ignore_erase && (p4e ? a < 0x20000u : a >= 0x20000u)) {
                const uint32_t n = p4e ? 0x1000u : 0x10000u;
                memset(flash + (a & ~(n - 1u)), 0xFF, n);
            }
            q.wip_left = q.erase_busy;
        }
        q.wel = 0;
        break;
    default:
        break;
    }
}

static uint32_t qspi_read(uint32_t off)
{
    switch (off) {
    case QSPI_SPI_STATUS:
        if (q.busy_left > 0u) {
            q.busy_left--;
            return QSPI_STATUS_BUSY;
        }
        return QSPI_STATUS_WC | QSPI_STATUS_FC;
    case QSPI_SPI_DATA:
        return q.data;
    case QSPI_SPI_SWITCH:
        return q.sw;
    default:
        return 0u;
    }
}

static void qspi_write(uint32_t off, uint32_t v)
{
    if (off == QSPI_SPI_SWITCH) {
        q.sw = v;
    } else if (off == QSPI_SPI_DATA) {
        q.data = v;
    } else if (off == QSPI_SPI_CMD) {
        if ((q.sw & QSPI_SWITCH_MMPT_S) != 0u) {
            q.errors++;   /* a command while the memory-mapped port is selected */
            return;
        }
        const uint32_t flen = (v & 0xFFFu) + 1u, cmd = (v >> 16) & 7u, wlen = ((v >> 19) & 0x7Fu) + 1u;
        if (wlen != 8u || ((v >> 28) & 3u) != 0u) {
            q.errors++;
        }
        if (q.words == 0u) {
            q.flen = flen;
            q.cur.n = 0u;
        } else if (flen != q.flen) {
            q.errors++;
        }
        uint8_t b;
        if (cmd == QSPI_CMD_WRITE_SINGLE) {
            b = (uint8_t)q.data;
        } else if (cmd == QSPI_CMD_READ_SINGLE) {
            b = 0xFFu;
            if (q.cur.n > 0u && q.cur.b[0] == NOR_CMD_RDSR) {
                b = (uint8_t)((q.wip_left > 0u ? NOR_SR_WIP : 0u) | (q.wel ? NOR_SR_WEL : 0u));
                if (q.wip_left > 0u && q.wip_left != 0xFFFFFFFFu) {
                    q.wip_left--;
                }
            }
            q.data = b;
        } else {
            q.errors++;
            return;
        }
        if (q.cur.n < sizeof q.cur.b) {
            q.cur.b[q.cur.n++] = b;
        }
        q.busy_left = 1u;   /* one BUSY read per word: the driver must poll */
        if (++q.words == q.flen) {
            run_frame();
            q.words = 0u;
        }
    }
}

uint32_t am263x_mmio_read(uintptr_t a, unsigned size)
{
    if (a >= (uintptr_t)qspi_ram && a < (uintptr_t)qspi_ram + sizeof qspi_ram) {
        return qspi_read((uint32_t)(a - (uintptr_t)qspi_ram));
    }
    uint32_t v = 0u;
    memcpy(&v, (const void *)a, size);
    return v;
}

void am263x_mmio_write(uintptr_t a, unsigned size, uint32_t v)
{
    if (a >= (uintptr_t)qspi_ram && a < (uintptr_t)qspi_ram + sizeof qspi_ram) {
        qspi_write((uint32_t)(a - (uintptr_t)qspi_ram), v);
        return;
    }
    memcpy((void *)a, &v, size);
}

static hal_nvm_t nvm;

static int setup(void **st)
{
    (void)st;
    memset(&q, 0, sizeof q);
    memset(flash, 0x5A, FLASH_SIZE);
    am263x_nvm_init(&nvm, (uintptr_t)qspi_ram, (uintptr_t)flash, &am263x_s25fl128s, AM263X_NVM_FLASH_OFF,
                    AM263X_NVM_BYTES);
    return 0;
}

static void expect_frame(uint32_t k, const uint8_t *bytes, uint32_t n)
{
    assert_true(k < q.nlog);
    assert_int_equal(q.log[k].n, n);
    assert_memory_equal(q.log[k].b, bytes, n);
}

static void test_geometry(void **st)
{
    (void)st;
    assert_int_equal(hal_nvm_blocks(&nvm), 2);
    assert_int_equal(hal_nvm_block_size(&nvm), 65536);
    assert_int_equal(hal_nvm_write_unit(&nvm), 8);
    assert_int_equal(q.sw, QSPI_SWITCH_MMPT_S);   /* init: memory-mapped port */
    assert_int_equal(AM263X_NVM_FLASH_OFF + 2u * 65536u, 0x00800000u);   /* the end of the first 8 MiB */
    /* the map: 32 x 4 KiB + 254 x 64 KiB = 16 MiB, contiguous */
    const hal_nvm_geometry_t *g = hal_nvm_geometry(&nvm);
    assert_ptr_equal(g, &am263x_s25fl128s);
    assert_int_equal(g->n_regions, 2);
    assert_int_equal(g->region[0].start + g->region[0].sector_size * g->region[0].count, g->region[1].start);
    assert_int_equal(g->region[1].start + g->region[1].sector_size * g->region[1].count, g->size);
    assert_int_equal(g->size, 16u << 20);
    assert_int_equal(g->page_size, 256);
    assert_int_equal(g->region[0].sector_size, 4096);   /* the same facts as hal_host_nvm_s25fl128s */
    assert_int_equal(g->region[0].count, 32);
    assert_int_equal(g->region[0].erase_cmd, 0x20);
    assert_int_equal(g->region[1].sector_size, 65536);
    assert_int_equal(g->region[1].erase_cmd, 0xD8);
    /* ranges that are not whole sectors of one region: no blocks, every call refused */
    const uint32_t bad[][2] = {{0x7F8000u, 0x8000u}, {0x10000u, 0x20000u}, {0x7E0000u, 0x11000u}, {0x7E0000u, 0u}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        hal_nvm_t n;
        am263x_nvm_init(&n, (uintptr_t)qspi_ram, (uintptr_t)flash, &am263x_s25fl128s, bad[k][0], bad[k][1]);
        assert_int_equal(hal_nvm_blocks(&n), 0);
        assert_int_equal(hal_nvm_block_size(&n), 0);
        assert_false(hal_nvm_erase(&n, 0u));
    }
    assert_int_equal(q.nlog, 0);
}

static void test_erase_sequence(void **st)
{
    (void)st;
    const uint32_t b2 = AM263X_NVM_FLASH_OFF;   /* block 0: 0x7E0000 */
    memset(flash + b2, 0x00, 65536);
    q.erase_busy = 3u;
    assert_true(hal_nvm_erase(&nvm, 0u));
    const uint8_t wren[] = {0x06}, rdsr_wel[] = {0x05, 0x02}, se[] = {0xD8, 0x7E, 0x00, 0x00};
    const uint8_t busy[] = {0x05, 0x01}, ready[] = {0x05, 0x00};
    assert_int_equal(q.nlog, 7);
    expect_frame(0, wren, 1);
    expect_frame(1, rdsr_wel, 2);
    expect_frame(2, se, 4);
    expect_frame(3, busy, 2);
    expect_frame(4, busy, 2);
    expect_frame(5, busy, 2);
    expect_frame(6, ready, 2);
    for (uint32_t k = 0; k < 65536u; ++k) {
        assert_int_equal(flash[b2 + k], 0xFF);
    }
    assert_int_equal(flash[b2 - 1u], 0x5A);       /* the neighbours kept */
    assert_int_equal(flash[b2 + 65536u], 0x5A);
    assert_int_equal(q.sw, QSPI_SWITCH_MMPT_S);   /* back to memory-mapped */
    assert_int_equal(q.errors, 0);
}

static void test_write_sequence_and_and(void **st)
{
    (void)st;
    const uint32_t b1 = AM263X_NVM_FLASH_OFF + 65536u;   /* 0x7F0000 */
    memset(flash + b1, 0xF0, 65536);
    uint8_t d[16];
    for (uint32_t k = 0; k < 16u; ++k) {
        d[k] = (uint8_t)(0x3Cu + 17u * k);
    }
    q.program_busy = 1u;
    assert_true(hal_nvm_write(&nvm, 1u, 16u, d, 16u));
    assert_int_equal(q.nlog, 10);
    const uint8_t wren[] = {0x06}, rdsr_wel[] = {0x05, 0x02}, busy[] = {0x05, 0x01}, ready[] = {0x05, 0x00};
    uint8_t pp[12] = {0x02, 0x7F, 0x00, 0x10};
    memcpy(pp + 4, d, 8);
    expect_frame(0, wren, 1);
    expect_frame(1, rdsr_wel, 2);
    expect_frame(2, pp, 12);
    expect_frame(3, busy, 2);
    expect_frame(4, ready, 2);
    pp[3] = 0x18;
    memcpy(pp + 4, d + 8, 8);
    expect_frame(5, wren, 1);
    expect_frame(7, pp, 12);
    for (uint32_t k = 0; k < 16u; ++k) {
        assert_int_equal(flash[b1 + 16u + k], 0xF0 & d[k]);   /* old AND new */
    }
    assert_int_equal(flash[b1 + 15u], 0xF0);
    assert_int_equal(flash[b1 + 32u], 0xF0);
    uint8_t back[16];
    assert_true(hal_nvm_read(&nvm, 1u, 16u, back, 16u));
    for (uint32_t k = 0; k < 16u; ++k) {
        assert_int_equal(back[k], 0xF0 & d[k]);
    }
    assert_int_equal(q.sw, QSPI_SWITCH_MMPT_S);
    assert_int_equal(q.errors, 0);
}

static void test_argument_checks(void **st)
{
    (void)st;
    uint8_t d[16] = {0};
    assert_false(hal_nvm_erase(&nvm, 2u));
    assert_false(hal_nvm_write(&nvm, 0u, 4u, d, 8u));       /* offset not a unit multiple */
    assert_false(hal_nvm_write(&nvm, 0u, 0u, d, 12u));      /* length not a unit multiple */
    assert_false(hal_nvm_write(&nvm, 0u, 65536u, d, 8u));   /* beyond the block */
    assert_false(hal_nvm_write(&nvm, 2u, 0u, d, 8u));
    assert_false(hal_nvm_read(&nvm, 0u, 65530u, d, 8u));
    assert_false(hal_nvm_read(&nvm, 2u, 0u, d, 1u));
    assert_int_equal(q.nlog, 0);                            /* nothing sent */
    assert_true(hal_nvm_read(&nvm, 1u, 65528u, d, 8u));
    assert_int_equal(d[0], 0x5A);
}

static void test_protected_stuck_and_timeout(void **st)
{
    (void)st;
    const uint32_t b0 = AM263X_NVM_FLASH_OFF;
    uint8_t d[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    /* write-protected: WEL never set, nothing erased or programmed */
    q.write_protect = 1;
    assert_false(hal_nvm_erase(&nvm, 0u));
    assert_int_equal(q.nlog, 2);   /* WREN, RDSR */
    assert_int_equal(flash[b0], 0x5A);
    assert_false(hal_nvm_write(&nvm, 0u, 0u, d, 8u));
    assert_int_equal(flash[b0 + 1u], 0x5A);
    assert_int_equal(q.sw, QSPI_SWITCH_MMPT_S);
    /* bits that do not program: the read-back refuses the write */
    setup(NULL);
    q.stuck = 1;
    assert_false(hal_nvm_write(&nvm, 0u, 0u, d, 8u));
    /* writing only 1s over the erased state cannot fail the read-back */
    setup(NULL);
    memset(flash + b0, 0xFF, 8);
    q.stuck = 1;
    const uint8_t ones[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    assert_true(hal_nvm_write(&nvm, 0u, 0u, ones, 8u));
    /* a device that never finishes: bounded, false, memory-mapped port back */
    setup(NULL);
    q.erase_busy = 0xFFFFFFFFu;
    nvm.erase_polls = 10u;
    assert_false(hal_nvm_erase(&nvm, 1u));
    assert_int_equal(q.nlog, 3u + 10u);
    assert_int_equal(q.sw, QSPI_SWITCH_MMPT_S);
    assert_int_equal(q.errors, 0);
}

/* The erase must hit the sector the part has: with the map read as uniform 4 KiB sectors (TI's
 * SDK config lists a 4 KiB "sector" with 0x20), the driver sends P4E into a 64 KiB sector, the
 * part erases nothing, and the verify refuses it; an erase the part skipped (WIP, no erase) is
 * refused the same way. The parameter sectors themselves take P4E, one 4 KiB sector at a time. */
static void test_erase_not_done_is_refused(void **st)
{
    (void)st;
    static const hal_nvm_region_t uniform[1] = {{0u, 0x1000u, 4096u, NOR_CMD_P4E}};
    static const hal_nvm_geometry_t wrong = {0x1000000u, 256u, 1u, uniform};
    hal_nvm_t n;
    am263x_nvm_init(&n, (uintptr_t)qspi_ram, (uintptr_t)flash, &wrong, AM263X_NVM_FLASH_OFF, 0x8000u);
    assert_int_equal(hal_nvm_block_size(&n), 4096);
    assert_false(hal_nvm_erase(&n, 0u));
    const uint8_t p4e[] = {0x20, 0x7E, 0x00, 0x00};
    expect_frame(2, p4e, 4);
    assert_int_equal(flash[AM263X_NVM_FLASH_OFF], 0x5A);   /* the part did nothing */
    /* the right map, a part that does not erase */
    q.ignore_erase = 1;
    assert_false(hal_nvm_erase(&nvm, 0u));
    assert_int_equal(flash[AM263X_NVM_FLASH_OFF + 65535u], 0x5A);
    /* a verify that sees one byte left: still refused */
    q.ignore_erase = 0;
    assert_true(hal_nvm_erase(&nvm, 0u));
    flash[AM263X_NVM_FLASH_OFF + 65535u] = 0xFE;
    q.ignore_erase = 1;
    assert_false(hal_nvm_erase(&nvm, 0u));
    /* the parameter sectors: P4E, 4 KiB each */
    q.ignore_erase = 0;
    q.nlog = 0u;
    am263x_nvm_init(&n, (uintptr_t)qspi_ram, (uintptr_t)flash, &am263x_s25fl128s, 0x1000u, 0x2000u);
    assert_int_equal(hal_nvm_blocks(&n), 2);
    assert_int_equal(hal_nvm_block_size(&n), 4096);
    assert_true(hal_nvm_erase(&n, 1u));
    const uint8_t p4e2[] = {0x20, 0x00, 0x20, 0x00};
    expect_frame(2, p4e2, 4);
    assert_int_equal(flash[0x1FFFu], 0x5A);
    assert_int_equal(flash[0x2000u], 0xFF);
    assert_int_equal(flash[0x2FFFu], 0xFF);
    assert_int_equal(flash[0x3000u], 0x5A);
    assert_int_equal(q.errors, 0);
}

int main(void)
{
    flash = malloc(FLASH_SIZE);
    if (flash == NULL) {
        return 1;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_geometry, setup),
        cmocka_unit_test_setup(test_erase_sequence, setup),
        cmocka_unit_test_setup(test_write_sequence_and_and, setup),
        cmocka_unit_test_setup(test_argument_checks, setup),
        cmocka_unit_test_setup(test_protected_stuck_and_timeout, setup),
        cmocka_unit_test_setup(test_erase_not_done_is_refused, setup),
    };
    const int r = cmocka_run_group_tests(tests, NULL, NULL);
    free(flash);
    return r;
}
