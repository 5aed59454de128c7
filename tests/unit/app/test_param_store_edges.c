/* The configuration store (mc/param_store.h) at its edges, for the survivors of the mutation run
 * (issue 30) that test_param_store.c cannot see on its two standard maps:
 *   - the slot size at the exact rounding limit: a block as large as the largest copy is one
 *     block a slot, not two;
 *   - the largest map geometry() reports on devices just large enough for the set: it is the
 *     largest map a save keeps, 0 when not even a 2 x 2 map fits;
 *   - a save refused by its setup (work buffer too small, device too small) touches nothing;
 *   - the write unit's limits (16 to 4096 bytes accepted, 8192 refused; a refused device reports
 *     no layout); a header CRC with any bit flipped; a model record of another version and a
 *     version 1 parameter record with a position past its table, every CRC valid: refused;
 *   - a read that fails while a save looks for the copy a load returns: nothing written;
 *   - an NVM call that fails in the middle of a save (a payload write whose status is lost, a
 *     write that fails, a unit that does not program): the save is an error at once, never a
 *     success, and the set committed before still loads;
 *   - a marker byte that does not program, a header read back wrong once, an unreadable record
 *     CRC word: the save (or load) is an NVM error, nothing is marked or overwritten;
 *   - a newest copy whose records contradict its header is refused from its first words, before
 *     an unreadable rest: the older copy loads;
 *   - write units below 8 (the layout of 8), blocks of any size (odd too) with byte writes, a
 *     write unit or block size of 0 (refused).
 * The host NVM model (hal_host) is the device; the faults are put in between the store and it by
 * the linker (--wrap of hal_nvm_read / write / erase / write_unit / block_size, CMakeLists.txt):
 * the firmware calls the wrappers below, which count the calls and inject the faults, then call
 * the model. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/bits.h"
#include "mc/param_store.h"
#include "pstore_same.h"

/* ---- the NVM between the store and the host model ----------------------------------------- */

bool __real_hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len);
bool __real_hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len);
bool __real_hal_nvm_erase(hal_nvm_t *nvm, uint32_t block);
bool __wrap_hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len);
bool __wrap_hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len);
bool __wrap_hal_nvm_erase(hal_nvm_t *nvm, uint32_t block);
uint32_t __real_hal_nvm_write_unit(const hal_nvm_t *nvm);
uint32_t __wrap_hal_nvm_write_unit(const hal_nvm_t *nvm);

typedef struct {
    uint32_t calls;            /* read, write and erase calls since fault_arm()              */
    uint32_t writes;           /* write calls since fault_arm()                               */
    uint32_t fail_write;       /* this write call (1: the first) reports a failure; 0: none    */
    bool carried_out;          /* ... and is carried out all the same (its status was lost)    */
    uint32_t failed_at;        /* calls at the failure, 0: none yet                           */
    uint32_t stuck_at;         /* a device byte (nvm.mem index) that never programs: it reads
                                  0xFF whatever is written; UINT32_MAX: none                   */
    uint32_t reads;            /* read calls since fault_arm()                                */
    uint32_t fail_read;        /* this read call (1: the first) fails, nothing read; 0: none   */
    uint32_t bad_at, bad_len;  /* device bytes [bad_at, bad_at + bad_len) cannot be read: a
                                  read call that touches one fails (a page ECC cannot correct) */
    uint32_t flip_block;       /* with flip_nth: a read at offset 0 of this block ...          */
    uint32_t flip_nth;         /* ... the n-th such after the first write call (1: the first)
                                  returns its bit flip_bit flipped (a marginal cell, once)      */
    uint32_t flip_bit;
    uint32_t failed_off;       /* the device address of the read that failed                  */
} fault_t;
static fault_t fault = {.stuck_at = UINT32_MAX};   /* no fault */
/* The write unit the device reports, 0: the host model's (8). A larger one (a multiple of 8) is
 * enforced here as a device with that unit would: a write at another offset or length fails; a
 * smaller one (1, 2, 4) is programmed by small_unit_write(). */
static uint32_t unit;
/* The block size the device reports: the host model's unless block_zero (a device description
 * that lost its erase size). */
static bool block_zero;
static bool unit_zero;   /* the write unit reported as 0 */
uint32_t __real_hal_nvm_block_size(const hal_nvm_t *nvm);
uint32_t __wrap_hal_nvm_block_size(const hal_nvm_t *nvm);

uint32_t __wrap_hal_nvm_block_size(const hal_nvm_t *nvm)
{
    return block_zero ? 0u : __real_hal_nvm_block_size(nvm);
}

uint32_t __wrap_hal_nvm_write_unit(const hal_nvm_t *nvm)
{
    return unit_zero ? 0u : unit != 0u ? unit : __real_hal_nvm_write_unit(nvm);
}

static void fault_arm(uint32_t fail_write, bool carried_out, uint32_t stuck_at)
{
    fault = (fault_t){.fail_write = fail_write, .carried_out = carried_out, .stuck_at = stuck_at};
}

/* no fault but the n-th read call from now failing */
static void fault_read(uint32_t n)
{
    fault_arm(0u, false, UINT32_MAX);
    fault.fail_read = n;
}

static void count_call(void)
{
    fault.calls++;
}

bool __wrap_hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len)
{
    count_call();
    const uint32_t at = block * nvm->block_size + offset;
    if (++fault.reads == fault.fail_read ||
        (fault.bad_len != 0u && at < fault.bad_at + fault.bad_len && fault.bad_at < at + len)) {
        fault.failed_at = fault.calls;
        fault.failed_off = at;
        return false;
    }
    const bool ok = __real_hal_nvm_read(nvm, block, offset, data, len);
    if (ok && fault.flip_nth != 0u && block == fault.flip_block && offset == 0u && fault.writes > 0u &&
        --fault.flip_nth == 0u && fault.flip_bit / 8u < len) {
        ((uint8_t *)data)[fault.flip_bit / 8u] ^= (uint8_t)(1u << (fault.flip_bit % 8u));
    }
    return ok;
}

/* A device whose unit is 1, 2 or 4 bytes, programmed here as it would be (the host model takes
 * whole 8-byte units only): a write only clears bits, within the block. */
static bool small_unit_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    const uint32_t bs = nvm->block_size;
    if (nvm->dead || block >= nvm->blocks || offset > bs || len > bs - offset) {
        return false;
    }
    for (uint32_t k = 0u; k < len; ++k) {
        nvm->mem[block * bs + offset + k] &= ((const uint8_t *)data)[k];
    }
    return true;
}

bool __wrap_hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    count_call();
    fault.writes++;
    if (unit != 0u && (offset % unit != 0u || len % unit != 0u)) {
        return false;
    }
    const bool fail = fault.writes == fault.fail_write;
    bool ok = false;
    if (!fail || fault.carried_out) {
        ok = unit != 0u && unit < 8u ? small_unit_write(nvm, block, offset, data, len)
                                     : __real_hal_nvm_write(nvm, block, offset, data, len);
        const uint32_t at = block * nvm->block_size + offset;
        if (ok && fault.stuck_at != UINT32_MAX && fault.stuck_at >= at && fault.stuck_at - at < len) {
            nvm->mem[fault.stuck_at] = 0xFFu;
        }
    }
    if (fail) {
        fault.failed_at = fault.calls;
        return false;
    }
    return ok;
}

bool __wrap_hal_nvm_erase(hal_nvm_t *nvm, uint32_t block)
{
    count_call();
    return __real_hal_nvm_erase(nvm, block);
}

/* ---- sets (as test_param_store.c makes them) ------------------------------------------------ */

static hal_nvm_t nvm, snap;
static uint8_t work[MC_PSTORE_WORK_MIN];   /* the smallest work buffer */
static uint8_t big[16384];                 /* larger than any payload (13.5 KB at most) */
enum { NSETS = 4 };
static mc_flux_map_t maps[NSETS];
static mc_drive_cfg_t sets[NSETS];
static mc_flux_map_t got_map;

/* set k: a few parameters moved, the model's scalars, an nd x nq map (0: none) */
static const mc_drive_cfg_t *make_cfg(int k, int nd, int nq)
{
    return pstore_make_cfg(&sets[k], &maps[k], k, nd, nq);
}

static bool same_cfg(const mc_drive_cfg_t *got, const mc_drive_cfg_t *want, bool dropped)
{
    return same_cfg_in(got, want, dropped, &got_map);
}

static mc_pstore_status_t load_with(uint8_t *w, size_t w_len, mc_drive_cfg_t *got, mc_pstore_info_t *info)
{
    memset(got, 0, sizeof *got);
    mc_params_default(&got->p);
    return mc_pstore_load(&nvm, got, &got_map, w, w_len, info);
}

static mc_pstore_status_t load(mc_drive_cfg_t *got, mc_pstore_info_t *info)
{
    return load_with(work, sizeof work, got, info);
}

/* ---- devices of any block size ------------------------------------------------------------ */

/* The copy's layout on the host model (write unit 8, mc/param_store.h): header 32 bytes, marker
 * 8, then the records padded to 8. */
#define PAYLOAD_AT 40u
static uint32_t round8(uint32_t x)
{
    return (x + 7u) / 8u * 8u;
}

/* the bytes a slot needs for records of these lengths */
static uint32_t copy_bytes(uint32_t records)
{
    return PAYLOAD_AT + round8(records);
}

static hal_nvm_region_t region[1];
static const hal_nvm_geometry_t device = {0u, 256u, 1u, region};

/* n blocks of bs bytes, all erased */
static void nvm_blocks(uint32_t bs, uint32_t n)
{
    region[0] = (hal_nvm_region_t){0u, bs, n, 0u};
    assert_true(hal_host_nvm_init_geom(&nvm, &device, 0u, n));
    assert_int_equal(hal_nvm_block_size(&nvm), bs);
}

/* A slot takes as many blocks as the largest copy needs, rounded up, not one more: on a device
 * whose blocks are exactly the largest copy's size a slot is one block (the largest map fits,
 * the second slot starts at block 2 of 4); 8 bytes less and it takes two. (param_store.c:99, the
 * rounding of the blocks a copy needs.) */
static void test_slot_blocks_at_the_rounding_limit(void **state)
{
    (void)state;
    const uint32_t largest = copy_bytes(MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX);
    const uint32_t all = (uint32_t)MC_FLUX_MAP_MAX * (uint32_t)MC_FLUX_MAP_MAX;
    mc_pstore_geom_t g;

    nvm_blocks(largest, 4u);
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_OK);
    assert_int_equal(g.slot_first[0], 0u);
    assert_int_equal(g.slot_first[1], 2u);
    assert_int_equal(g.slot_blocks, 1u);
    assert_int_equal(g.payload_max, largest - PAYLOAD_AT);
    assert_int_equal(g.map_cells_max, all);
    /* the largest set fills the block to its last byte and comes back whole */
    const mc_drive_cfg_t *a = make_cfg(0, MC_FLUX_MAP_MAX, MC_FLUX_MAP_MAX);
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_OK);
    assert_false(info.map_dropped);
    mc_drive_cfg_t got;
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, a, false));
    /* on flash: the model record, map and all, ends 4 padding bytes before the block's end */
    const size_t ml = mc_store_model_encode(&a->est, big, sizeof big);
    assert_int_equal(ml, MC_STORE_MODEL_MAX);
    assert_int_equal(PAYLOAD_AT + MC_STORE_PARAMS_MAX + ml, largest - (round8(MC_STORE_PARAMS_MAX + ml) -
                                                                      (MC_STORE_PARAMS_MAX + ml)));
    assert_memory_equal(nvm.mem + PAYLOAD_AT + MC_STORE_PARAMS_MAX, big, ml);

    /* one write unit less a block: two blocks a slot */
    nvm_blocks(largest - 8u, 4u);
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_OK);
    assert_int_equal(g.slot_first[1], 2u);
    assert_int_equal(g.slot_blocks, 2u);
    assert_int_equal(g.payload_max, 2u * (largest - 8u) - PAYLOAD_AT);
    /* one write unit more: one block */
    nvm_blocks(largest + 8u, 4u);
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_OK);
    assert_int_equal(g.slot_blocks, 1u);
    assert_int_equal(g.payload_max, largest + 8u - PAYLOAD_AT);
}

/* On devices just large enough for the set (one block a slot, from the set without a map up to
 * a few map points more), map_cells_max is the largest number of map points whose model record
 * fits beside the parameter record, counted here from the records' lengths (mc/store.h), and 0
 * where not even a 2 x 2 map fits; a save keeps a map of that many points and drops one of more.
 * (param_store.c:149, the threshold for any map at all.) */
static void test_map_cells_on_small_devices(void **state)
{
    (void)state;
    const uint32_t pl = MC_STORE_PARAMS_MAX;
    unsigned none = 0u, some = 0u;
    for (uint32_t cap = round8(pl + 32u); cap <= round8(pl + 32u) + 96u; cap += 8u) {
        nvm_blocks(PAYLOAD_AT + cap, 2u);
        mc_pstore_geom_t g;
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
        assert_int_equal(g.slot_first[1], 1u);
        assert_int_equal(g.slot_blocks, 1u);
        assert_int_equal(g.payload_max, cap);
        uint32_t want = 0u;   /* the largest map (at least 2 x 2) whose records fit */
        for (uint32_t c = 4u; round8(pl + 4u * (14u + 2u * c)) <= cap; ++c) {
            want = c;
        }
        assert_int_equal(g.map_cells_max, want);

        mc_drive_cfg_t got;
        mc_pstore_info_t info;
        if (want == 0u) {
            /* no map fits: the smallest one is dropped, the set saved without it */
            ++none;
            const mc_drive_cfg_t *a = make_cfg(1, 2, 2);
            assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_MAP_DROPPED);
            assert_int_equal(load(&got, &info), MC_PSTORE_OK);
            assert_true(info.map_dropped);
            assert_true(same_cfg(&got, a, true));
            continue;
        }
        /* 2 x (want / 2) points fit and load back; one column more is dropped */
        ++some;
        const int nq = (int)(want / 2u);
        const mc_drive_cfg_t *a = make_cfg(1, 2, nq), *b = make_cfg(2, 2, nq + 1);
        assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_OK);
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_true(same_cfg(&got, a, false));
        assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, &info), MC_PSTORE_MAP_DROPPED);
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_true(info.map_dropped);
        assert_true(same_cfg(&got, b, true));
    }
    /* both sides of the limit were tried */
    assert_true(none >= 5u && some >= 3u);
}

/* A save its setup refuses writes nothing: a work buffer one byte short of the minimum (the
 * buffer itself large, its length says otherwise) leaves the committed set and every byte of the
 * device as they were; on a device too small for the set, save and erase are TOO_LARGE with no
 * NVM step. (param_store.c:704, the save's check of its setup's status.) */
static void test_refused_setup_touches_nothing(void **state)
{
    (void)state;
    hal_host_nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(0, 4, 3), *b = make_cfg(1, 5, 5);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    snap = nvm;
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_save(&nvm, b, big, MC_PSTORE_WORK_MIN - 1u, &info), MC_PSTORE_BAD_ARGS);
    assert_int_equal(info.slot, -1);
    assert_int_equal(nvm.steps, snap.steps);
    assert_memory_equal(nvm.mem, snap.mem, sizeof nvm.mem);
    mc_drive_cfg_t got;
    assert_int_equal(load(&got, NULL), MC_PSTORE_OK);
    assert_true(same_cfg(&got, a, false));

    /* one write unit short of the set without a map */
    nvm_blocks(PAYLOAD_AT + round8(MC_STORE_PARAMS_MAX + 32u) - 8u, 2u);
    mc_pstore_geom_t g;
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_TOO_LARGE);
    const mc_drive_cfg_t *c = make_cfg(2, 0, 0);
    assert_int_equal(mc_pstore_save(&nvm, c, big, sizeof big, &info), MC_PSTORE_TOO_LARGE);
    assert_int_equal(info.slot, -1);
    assert_int_equal(mc_pstore_erase(&nvm, big, sizeof big), MC_PSTORE_TOO_LARGE);
    assert_int_equal(nvm.steps, 0u);
    for (uint32_t k = 0u; k < hal_host_nvm_bytes(&nvm); ++k) {
        assert_int_equal(nvm.mem[k], 0xFF);
    }
}

/* A device whose write unit U is larger than 8 (16 or 32 bytes: a flash with ECC words; 64): the
 * marker is max(U, 8) bytes at round_up(32, U) (mc/param_store.h), the payload after it, every
 * write whole units (the wrapper refuses any other, as such a device does), the record space
 * whole units, and sets come back whole from both slots. (param_store.c:94, the alignment.) */
static void test_write_units_above_8(void **state)
{
    (void)state;
    const uint32_t units[] = {16u, 32u, 64u};
    for (size_t i = 0; i < sizeof units / sizeof units[0]; ++i) {
        const uint32_t u = units[i];
        nvm_blocks(4096u, 4u);
        unit = u;
        assert_int_equal(hal_nvm_write_unit(&nvm), u);
        const uint32_t head = (32u + u - 1u) / u * u, pay_at = head + u;
        mc_pstore_geom_t g;
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
        assert_int_equal(g.slot_first[1], 2u);
        assert_int_equal(g.slot_blocks, 2u);
        assert_int_equal(g.payload_max, (8192u - pay_at) / u * u);
        uint32_t want = 0u;   /* the largest map whose records, padded to U, fit */
        for (uint32_t c = 4u; (MC_STORE_PARAMS_MAX + 4u * (14u + 2u * c) + u - 1u) / u * u <= g.payload_max; ++c) {
            want = c;
        }
        assert_int_equal(g.map_cells_max, want);

        const mc_drive_cfg_t *a = make_cfg(0, 6, 6), *b = make_cfg(1, 0, 0);
        mc_pstore_info_t info;
        mc_drive_cfg_t got;
        /* the work buffer: MC_PSTORE_WORK_MIN bytes and 2 write units (header and marker in one
         * read); one byte less is refused before any NVM step */
        const size_t wl = 2u * u > MC_PSTORE_WORK_MIN ? 2u * u : MC_PSTORE_WORK_MIN;
        assert_int_equal(mc_pstore_save(&nvm, a, big, wl - 1u, NULL), MC_PSTORE_BAD_ARGS);
        assert_int_equal(load_with(big, wl - 1u, &got, NULL), MC_PSTORE_BAD_ARGS);
        assert_int_equal(nvm.steps, 0u);
        assert_int_equal(mc_pstore_save(&nvm, a, big, wl, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, 0);
        assert_int_equal(load_with(big, wl, &got, &info), MC_PSTORE_OK);
        assert_true(same_cfg(&got, a, false));
        /* on flash: the header padded to U, the marker over one unit, then the records */
        for (uint32_t k = 32u; k < head; ++k) {
            assert_int_equal(nvm.mem[k], 0xFF);
        }
        for (uint32_t k = 0u; k < u; ++k) {
            assert_int_equal(nvm.mem[head + k], (k & 1u) != 0u ? 0xA5 : 0x5A);
        }
        static uint8_t rec[MC_STORE_PARAMS_MAX];
        const size_t pl = mc_store_params_encode(&a->p, rec, sizeof rec);
        assert_int_equal(pl, MC_STORE_PARAMS_MAX);
        assert_memory_equal(nvm.mem + pay_at, rec, pl);
        assert_int_equal(mc_pstore_save(&nvm, b, big, wl, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, 1);
        assert_int_equal(load_with(big, wl, &got, &info), MC_PSTORE_OK);
        assert_true(same_cfg(&got, b, false));
        assert_int_equal(mc_store_params_encode(&b->p, rec, sizeof rec), pl);
        assert_memory_equal(nvm.mem + 2u * 4096u + pay_at, rec, pl);
        assert_int_equal(mc_pstore_erase(&nvm, big, wl), MC_PSTORE_OK);
        assert_int_equal(load_with(big, wl, &got, &info), MC_PSTORE_EMPTY);
        assert_true(info.defaults);
    }
}

/* The write unit's limits: a power of two up to 4096 bytes. At 4096 (header, marker and the
 * records' padding each a whole unit: 8 KiB before the records) the largest set is stored and
 * comes back; 8192, a unit not a power of two (24) and a block that is not whole units are
 * refused (BAD_ARGS) by geometry, save, load and erase before any NVM step. A refused geometry
 * reports no layout (every field 0), even right after a valid one. (param_store.c:90, the
 * upper limit; :138, the layout of a refused device.) */
static void test_write_unit_limits(void **state)
{
    (void)state;
    nvm_blocks(4096u, 16u);
    unit = 4096u;
    mc_pstore_geom_t g;
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_OK);
    const uint32_t need = (2u * 4096u + (MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX + 4095u) / 4096u * 4096u) / 4096u;
    assert_int_equal(g.slot_first[1], 8u);
    assert_int_equal(g.slot_blocks, need);
    assert_int_equal(g.payload_max, (need - 2u) * 4096u);
    assert_int_equal(g.map_cells_max, MC_FLUX_MAP_MAX * MC_FLUX_MAP_MAX);
    const mc_drive_cfg_t *a = make_cfg(0, MC_FLUX_MAP_MAX, MC_FLUX_MAP_MAX);
    mc_pstore_info_t info;
    mc_drive_cfg_t got;
    assert_int_equal(mc_pstore_save(&nvm, a, big, 8192u, &info), MC_PSTORE_OK);
    assert_int_equal(load_with(big, 8192u, &got, &info), MC_PSTORE_OK);
    assert_true(same_cfg(&got, a, false));
    for (uint32_t k = 0u; k < 4096u; ++k) {
        assert_int_equal(nvm.mem[4096u + k], (k & 1u) != 0u ? 0xA5 : 0x5A);   /* the marker */
    }

    const struct {
        uint32_t block, unit;
    } bad[] = {{8192u, 8192u}, {4096u, 24u}, {4100u, 8u}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        nvm_blocks(4096u, 4u);
        unit = 0u;
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);   /* a valid layout first */
        assert_int_not_equal(g.slot_first[1], 0u);
        nvm_blocks(bad[i].block, 8u);
        unit = bad[i].unit;
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_BAD_ARGS);
        assert_int_equal(g.slot_first[0], 0u);
        assert_int_equal(g.slot_first[1], 0u);
        assert_int_equal(g.slot_blocks, 0u);
        assert_int_equal(g.payload_max, 0u);
        assert_int_equal(g.map_cells_max, 0u);
        const mc_drive_cfg_t *b = make_cfg(1, 3, 3);
        assert_int_equal(mc_pstore_save(&nvm, b, big, sizeof big, &info), MC_PSTORE_BAD_ARGS);
        assert_int_equal(load_with(big, sizeof big, &got, &info), MC_PSTORE_BAD_ARGS);
        assert_int_equal(mc_pstore_erase(&nvm, big, sizeof big), MC_PSTORE_BAD_ARGS);
        assert_int_equal(nvm.steps, 0u);
    }
}

/* ---- copies that check in part: a and b committed, b the newest ---------------------------- */

static const mc_drive_cfg_t *ca, *cb;
static uint8_t *slot1;   /* b's copy on flash */

static void two_copies(void)
{
    hal_host_nvm_init(&nvm);
    ca = make_cfg(0, 4, 5);
    cb = make_cfg(1, 6, 3);
    assert_int_equal(mc_pstore_save(&nvm, ca, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 0 */
    assert_int_equal(mc_pstore_save(&nvm, cb, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 1 */
    mc_pstore_geom_t g;
    (void)mc_pstore_geometry(&nvm, &g);
    slot1 = nvm.mem + g.slot_first[1] * nvm.block_size;
    snap = nvm;
}

/* load gives a (the newest copy refused) or b (taken) */
static void loads(const mc_drive_cfg_t *want)
{
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(load(&got, &info), want == ca ? MC_PSTORE_FELL_BACK : MC_PSTORE_OK);
    assert_int_equal(info.slot, want == ca ? 0 : 1);
    assert_true(same_cfg(&got, want, false));
}

static void put32(uint8_t *b, uint32_t w)
{
    for (int k = 0; k < 4; ++k) {
        b[k] = (uint8_t)(w >> (8 * k));
    }
}

/* b's copy rewritten with these records under a header of this format, every CRC valid: the
 * copy a writer of such records would have committed (format 1: the records' CRC words in the
 * payload CRC, 2: not). */
static void forge_b(const uint8_t *pr, uint32_t pl, const uint8_t *mr, uint32_t ml, uint32_t format)
{
    static uint8_t crc_in[MC_STORE_PARAMS_MAX + MC_STORE_MODEL_MAX];
    memset(slot1 + PAYLOAD_AT, 0xFF, round8(pl + ml));
    memcpy(slot1 + PAYLOAD_AT, pr, pl);
    memcpy(slot1 + PAYLOAD_AT + pl, mr, ml);
    const uint32_t cut = format == 1u ? 0u : 4u;
    memcpy(crc_in, pr, pl - cut);
    memcpy(crc_in + pl - cut, mr, ml - cut);
    put32(slot1 + 4, format);
    put32(slot1 + 16, pl);
    put32(slot1 + 20, ml);
    put32(slot1 + 24, mc_crc32(crc_in, pl + ml - 2u * cut));
    put32(slot1 + 28, mc_crc32(slot1, 28u));
}

static void close_record(uint8_t *r, uint32_t len)
{
    put32(r + len - 4u, mc_crc32(r, len - 4u));
}

/* Any bit of the newest copy's header CRC flipped (above or below the right value): the header
 * does not check, the older copy is returned. (param_store.c:535, the header CRC compare.) */
static void test_header_crc_any_bit(void **state)
{
    (void)state;
    two_copies();
    loads(cb);
    for (int bit = 0; bit < 32; ++bit) {
        nvm = snap;
        slot1[28 + bit / 8] ^= (uint8_t)(1u << (bit % 8));
        loads(ca);
    }
}

/* The model record's version: a copy whose model record is of another version (0, 2), with every
 * CRC of the copy valid, is refused like mc_store_model_decode refuses the record; the same
 * forging with version 1 loads (format 1 and 2 headers). (param_store.c:437.) */
static void test_model_record_other_version(void **state)
{
    (void)state;
    two_copies();
    static uint8_t pr[MC_STORE_PARAMS_MAX], mr[MC_STORE_MODEL_MAX];
    const uint32_t pl = (uint32_t)mc_store_params_encode(&cb->p, pr, sizeof pr);
    const uint32_t ml = (uint32_t)mc_store_model_encode(&cb->est, mr, sizeof mr);
    for (uint32_t format = 1u; format <= 2u; ++format) {
        nvm = snap;
        forge_b(pr, pl, mr, ml, format);
        loads(cb);
    }
    const uint32_t versions[] = {0u, MC_STORE_VERSION + 1u};
    for (size_t i = 0; i < 2u; ++i) {
        put32(mr + 4, versions[i]);
        close_record(mr, ml);
        mc_est_model_t m;
        assert_int_not_equal(mc_store_model_decode(mr, ml, &m, &got_map), MC_STORE_OK);
        nvm = snap;
        forge_b(pr, pl, mr, ml, MC_PSTORE_FORMAT);
        loads(ca);
    }
}

/* A version 1 parameter record (as main at 5265cfe wrote it: positions in the frozen table of
 * MC_STORE_V1_COUNT) holding a position past that table is damaged: the copy is refused; the same
 * record with the table's last position loads. (param_store.c:418.) */
static void test_v1_record_position_past_the_table(void **state)
{
    (void)state;
    two_copies();
    static uint8_t mr[MC_STORE_MODEL_MAX];
    const uint32_t ml = (uint32_t)mc_store_model_encode(&cb->est, mr, sizeof mr);
    const uint32_t last[] = {MC_STORE_V1_COUNT - 1u, MC_STORE_V1_COUNT, 0x7FFFFFFFu};
    for (size_t i = 0; i < 3u; ++i) {
        /* two derived entries (their values unused): position 0 and last[i] */
        uint8_t pr[4u * (5u + 2u * 2u)];
        const uint32_t w[] = {MC_STORE_MAGIC_PARAMS, 1u, MC_STORE_V1_TABLE, 2u,
                              0u | MC_STORE_V1_AUTO, 0u, last[i] | MC_STORE_V1_AUTO, 0u};
        for (int k = 0; k < 8; ++k) {
            put32(pr + 4 * k, w[k]);
        }
        close_record(pr, sizeof pr);
        nvm = snap;
        forge_b(pr, sizeof pr, mr, ml, 1u);
        mc_drive_cfg_t got;
        mc_pstore_info_t info;
        const mc_pstore_status_t st = load(&got, &info);
        if (last[i] < MC_STORE_V1_COUNT) {
            assert_int_equal(st, MC_PSTORE_OK);
            assert_int_equal(info.slot, 1);
            assert_true(info.params.other_table);
            assert_int_equal(info.params.dropped, 0u);
            assert_int_equal(info.params.kept + info.params.unknown, 2u);
        } else {
            assert_int_equal(st, MC_PSTORE_FELL_BACK);
            assert_int_equal(info.slot, 0);
            assert_true(same_cfg(&got, ca, false));
        }
    }
}

/* A read that fails while a save or an erase looks for the copy a load returns (a header, or a
 * copy's records): it is an error at once, before any erase or write, so that the copy a load
 * returns is never overwritten on a guess; a load is an error and leaves cfg as it was.
 * (param_store.c:721, the save's check of that search.) */
static void test_read_failure_before_a_save(void **state)
{
    (void)state;
    /* only a committed (slot 0): a save over a would lose the only set */
    hal_host_nvm_init(&nvm);
    const mc_drive_cfg_t *a = make_cfg(0, 4, 5), *b = make_cfg(1, 6, 3);
    assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, NULL), MC_PSTORE_OK);
    snap = nvm;
    for (uint32_t n = 1u; n <= 4u; ++n) {   /* slot 0's header, slot 1's, a's first records */
        nvm = snap;
        fault_read(n);
        assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, NULL), MC_PSTORE_NVM_ERROR);
        assert_int_equal(fault.calls, fault.failed_at);
        nvm = snap;
        fault_read(n);
        assert_int_equal(mc_pstore_erase(&nvm, work, sizeof work), MC_PSTORE_NVM_ERROR);
        assert_int_equal(fault.calls, fault.failed_at);
        nvm = snap;
        fault_read(n);
        mc_drive_cfg_t got = *b;
        assert_int_equal(mc_pstore_load(&nvm, &got, &got_map, work, sizeof work, NULL), MC_PSTORE_NVM_ERROR);
        assert_memory_equal(&got, b, sizeof got);
        assert_int_equal(nvm.steps, snap.steps);
        assert_memory_equal(nvm.mem, snap.mem, sizeof nvm.mem);
        fault_arm(0u, false, UINT32_MAX);
        mc_drive_cfg_t now;
        assert_int_equal(load(&now, NULL), MC_PSTORE_OK);
        assert_true(same_cfg(&now, a, false));
    }
}

/* ---- a failing call in the middle of a save ------------------------------------------------ */

static const mc_drive_cfg_t *fa, *fb;   /* fa committed in slot 0; fb saved over slot 1 */

static void committed_a(void)
{
    hal_host_nvm_init(&nvm);
    fa = make_cfg(0, 6, 6);
    fb = make_cfg(1, 7, 5);
    fault_arm(0u, false, UINT32_MAX);
    assert_int_equal(mc_pstore_save(&nvm, fa, work, sizeof work, NULL), MC_PSTORE_OK);   /* slot 0 */
    snap = nvm;
}

/* after fb's save failed: fa is what a load returns (nothing of fb committed) */
static void a_still_loads(void)
{
    fault_arm(0u, false, UINT32_MAX);
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(load(&got, &info), MC_PSTORE_OK);
    assert_int_equal(info.slot, 0);
    assert_int_equal(info.seq, 1u);
    assert_true(same_cfg(&got, fa, false));
}

static void save_b_fails(void)
{
    mc_pstore_info_t info;
    assert_int_equal(mc_pstore_save(&nvm, fb, work, sizeof work, &info), MC_PSTORE_NVM_ERROR);
    assert_int_equal(info.slot, -1);
}

/* A payload write the device carried out but whose status came back as a failure (a lost or
 * timed-out status): the call failed, so the save fails, and it is not taken back by the data
 * reading right afterwards. (param_store.c:238: without the else, the sink compared the chunk
 * after the failed write, found it written and reported the save as a success.) */
static void test_failed_payload_write_is_not_a_success(void **state)
{
    (void)state;
    committed_a();
    /* the writes of a clean save of fb: the payload chunks (one a work buffer), header, marker */
    fault_arm(0u, false, UINT32_MAX);
    assert_int_equal(mc_pstore_save(&nvm, fb, work, sizeof work, NULL), MC_PSTORE_OK);
    const uint32_t writes = fault.writes;
    assert_true(writes >= 6u);
    /* the status of each write but the marker's (the last) lost in turn, the data written */
    for (uint32_t w = 1u; w < writes; ++w) {
        nvm = snap;
        fault_arm(w, true, UINT32_MAX);
        save_b_fails();
        a_still_loads();
    }
}

/* A payload write that fails: the save ends with it (no further NVM call, no retry), NVM_ERROR.
 * (param_store.c:238: without the else, every later chunk was read back after the failure.) */
static void test_failed_payload_write_ends_the_save(void **state)
{
    (void)state;
    committed_a();
    for (uint32_t w = 1u; w <= 3u; ++w) {
        nvm = snap;
        fault_arm(w, false, UINT32_MAX);
        save_b_fails();
        assert_int_not_equal(fault.failed_at, 0u);
        assert_int_equal(fault.calls, fault.failed_at);   /* the failed write was the last call */
        a_still_loads();
    }
}

/* A payload byte that does not program (it reads erased whatever is written, the write call
 * succeeding) in the first work buffer of the copy: the read-back differs, and that is the save's
 * status (NVM_ERROR: "a read-back differed"; the set itself is fine: not BAD_ARGS, which the
 * load checks after the read-back would give), and the set committed before still loads. */
static void test_unprogrammed_byte_fails_the_read_back(void **state)
{
    (void)state;
    committed_a();
    /* the byte of fb's parameter record at payload offset k, the first one not 0xFF */
    static uint8_t rec[MC_STORE_PARAMS_MAX];
    assert_int_equal(mc_store_params_encode(&fb->p, rec, sizeof rec), MC_STORE_PARAMS_MAX);
    uint32_t k = 0u;
    while (rec[k] == 0xFFu) {
        ++k;
    }
    assert_true(k < MC_PSTORE_WORK_MIN);
    mc_pstore_geom_t g;
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
    nvm = snap;
    fault_arm(0u, false, g.slot_first[1] * nvm.block_size + PAYLOAD_AT + k);
    save_b_fails();
    assert_int_equal(nvm.mem[g.slot_first[1] * nvm.block_size + PAYLOAD_AT + k], 0xFF);   /* the fault was hit */
    a_still_loads();
}

/* A marker byte that does not program (it reads erased, the write call succeeding): the copy is
 * not committed, the save says so (NVM_ERROR: the marker's read-back differed) and the set
 * committed before still loads. (param_store.c:658, the marker's write and its read-back.) */
static void test_unprogrammed_marker_fails_the_save(void **state)
{
    (void)state;
    committed_a();
    mc_pstore_geom_t g;
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
    for (uint32_t k = 0u; k < 8u; ++k) {
        nvm = snap;
        const uint32_t at = g.slot_first[1] * nvm.block_size + 32u + k;   /* the marker's byte k */
        fault_arm(0u, false, at);
        save_b_fails();
        assert_int_equal(nvm.mem[at], 0xFF);   /* the fault was hit */
        a_still_loads();
    }
}

/* The header read back wrong once after it was written (a marginal cell, a bus glitch: the
 * flash holds it right): by the bit-exact compare (the first read at the slot's start after the
 * writes) or by the load's header check (the second), any of its 256 bits: the save fails, the
 * copy is not marked, the set committed before loads. (param_store.c:643: a read-back header
 * that does not check ends the save.) */
static void test_header_read_back_wrong_once(void **state)
{
    (void)state;
    committed_a();
    mc_pstore_geom_t g;
    assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
    for (uint32_t nth = 1u; nth <= 2u; ++nth) {
        for (uint32_t bit = 0u; bit < 256u; ++bit) {
            nvm = snap;
            fault_arm(0u, false, UINT32_MAX);
            fault.flip_block = g.slot_first[1];
            fault.flip_nth = nth;
            fault.flip_bit = bit;
            save_b_fails();
            assert_int_equal(fault.flip_nth, 0u);   /* the flip was made */
            a_still_loads();
        }
    }
}

/* A read that fails on a record's CRC word, on the model record's second word or on its map
 * header (the work buffer's length puts that word at the start of a read): the copy's state is
 * unknown, so a load is an error and so is a save, which then writes nothing: taken for
 * "damaged", the older copy would load and a save would overwrite the newest, which may be good.
 * (param_store.c:383, :434, :451: a failed read is COPY_IO.) */
static void test_unreadable_record_crc(void **state)
{
    (void)state;
    two_copies();   /* cb's map 6 x 3: parameter record 780 bytes, model record 200 */
    const uint32_t pl = MC_STORE_PARAMS_MAX, ml = 4u * (14u + 2u * 18u);
    assert_int_equal(pl % 8u, 4u);   /* the chunk lengths below: multiples of 8 */
    const struct {
        uint32_t crc_at, work_len;   /* the word's payload offset; a length it is a multiple of */
    } cases[] = {{pl - 4u, pl - 4u}, {pl + ml - 4u, pl + ml - 4u}, {pl + 4u, pl + 4u}, {pl + 28u, pl + 28u}};
    const uint32_t pay = (uint32_t)(slot1 - nvm.mem) + PAYLOAD_AT;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        assert_int_equal(cases[i].crc_at % cases[i].work_len, 0u);
        assert_int_equal(cases[i].work_len % 8u, 0u);
        nvm = snap;
        fault_arm(0u, false, UINT32_MAX);
        fault.bad_at = pay + cases[i].crc_at;
        fault.bad_len = 4u;
        mc_drive_cfg_t got = *ca;
        assert_int_equal(mc_pstore_load(&nvm, &got, &got_map, big, cases[i].work_len, NULL), MC_PSTORE_NVM_ERROR);
        assert_int_equal(fault.failed_off, pay + cases[i].crc_at);   /* the read of that word */
        assert_memory_equal(&got, ca, sizeof got);
        const mc_drive_cfg_t *c = make_cfg(2, 3, 3);
        assert_int_equal(mc_pstore_save(&nvm, c, big, cases[i].work_len, NULL), MC_PSTORE_NVM_ERROR);
        assert_int_equal(mc_pstore_erase(&nvm, big, cases[i].work_len), MC_PSTORE_NVM_ERROR);
        assert_int_equal(nvm.steps, snap.steps);
        assert_memory_equal(nvm.mem, snap.mem, sizeof nvm.mem);
        fault_arm(0u, false, UINT32_MAX);
        loads(cb);
    }
}

/* A newest copy whose records do not match its header's lengths, and whose rest cannot be read
 * (a page the ECC cannot correct): it is refused as soon as its first words show the mismatch,
 * without reading on, so the older copy loads (FELL_BACK, not an NVM error):
 *   - a model record without a map, 32 bytes, under a header claiming 40 (param_store.c:446);
 *   - a parameter record claiming 2^29 - 2 values in a 4-byte record, the count whose length
 *     4 (5 + 2 n) wraps to 4 in 32 bits (param_store.c:402, the count bounded by the length
 *     first). */
static void test_mismatch_refused_before_an_unreadable_rest(void **state)
{
    (void)state;
    two_copies();
    const uint32_t pay = (uint32_t)(slot1 - nvm.mem) + PAYLOAD_AT;
    static uint8_t pr[MC_STORE_PARAMS_MAX], mr[MC_STORE_MODEL_MAX];
    const uint32_t pl = (uint32_t)mc_store_params_encode(&cb->p, pr, sizeof pr);
    const mc_est_model_t nomap = {cb->est.rs, cb->est.ld, cb->est.lq, cb->est.psi_pm, NULL};
    assert_int_equal(mc_store_model_encode(&nomap, mr, sizeof mr), 32u);
    memset(mr + 32, 0, 8u);
    /* the model record 8 bytes short of its header's length; reads of 808 bytes: the first ends
     * right before the model record's CRC word, the unreadable rest from there */
    nvm = snap;
    forge_b(pr, pl, mr, 40u, MC_PSTORE_FORMAT);
    fault_arm(0u, false, UINT32_MAX);
    fault.bad_at = pay + pl + 28u;
    fault.bad_len = 12u;
    mc_drive_cfg_t got;
    mc_pstore_info_t info;
    assert_int_equal(load_with(big, pl + 28u, &got, &info), MC_PSTORE_FELL_BACK);
    assert_int_equal(info.slot, 0);
    assert_true(same_cfg(&got, ca, false));
    assert_int_equal(fault.failed_at, 0u);   /* nothing unreadable was read */

    /* the count: 4 (5 + 2 (2^29 - 2)) = 2^32 + 4 */
    static uint8_t p4[1000];
    memset(p4, 0xAB, sizeof p4);
    const uint32_t w[] = {MC_STORE_MAGIC_PARAMS, MC_STORE_PARAMS_VERSION, mc_params_table_hash(), 0x1FFFFFFEu};
    for (int k = 0; k < 4; ++k) {
        put32(p4 + 4 * k, w[k]);
    }
    assert_int_equal((uint32_t)(4u * (5u + 2u * w[3])), 4u);
    nvm = snap;
    forge_b(p4, 4u, p4 + 4, sizeof p4 - 4u, MC_PSTORE_FORMAT);
    fault_arm(0u, false, UINT32_MAX);
    fault.bad_at = pay + 64u;
    fault.bad_len = sizeof p4 - 64u;
    assert_int_equal(load(&got, &info), MC_PSTORE_FELL_BACK);
    assert_int_equal(info.slot, 0);
    assert_true(same_cfg(&got, ca, false));
    assert_int_equal(fault.failed_at, 0u);
}

/* Write units below 8 (1, 2, 4 bytes: a NOR flash, an EEPROM) use the layout of 8: header at 0,
 * an 8-byte marker at 32 (a marker shorter than 8 bytes would be a weaker commit), records at
 * 40; a unit of 0 is refused before any NVM step. (param_store.c:94, the alignment of at least 8;
 * :90, 0 refused and 1 a power of two.) */
static void test_write_units_below_8(void **state)
{
    (void)state;
    const uint32_t units[] = {1u, 2u, 4u};
    for (size_t i = 0; i < sizeof units / sizeof units[0]; ++i) {
        nvm_blocks(4096u, 4u);
        unit = units[i];
        mc_pstore_geom_t g;
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_MAP_DROPPED);
        assert_int_equal(g.slot_first[1], 2u);
        assert_int_equal(g.slot_blocks, 2u);
        assert_int_equal(g.payload_max, 8192u - PAYLOAD_AT);
        const mc_drive_cfg_t *a = make_cfg(0, 5, 4);
        mc_pstore_info_t info;
        mc_drive_cfg_t got;
        assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_OK);
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_true(same_cfg(&got, a, false));
        for (uint32_t k = 0u; k < 8u; ++k) {
            assert_int_equal(nvm.mem[32u + k], (k & 1u) != 0u ? 0xA5 : 0x5A);
        }
        static uint8_t rec[MC_STORE_PARAMS_MAX];
        assert_int_equal(mc_store_params_encode(&a->p, rec, sizeof rec), MC_STORE_PARAMS_MAX);
        assert_memory_equal(nvm.mem + PAYLOAD_AT, rec, MC_STORE_PARAMS_MAX);
    }
}

/* A write unit of 1 (an EEPROM, a NOR flash written by bytes) allows a block of any size, odd
 * too: a write that crosses a block's end is split there, and each part written whole, down to a
 * last part of a single byte. Block sizes 3937 to 3951 bytes with the smallest work buffer: one
 * of the payload's 64-byte writes crosses each of them with 1 to 15 bytes left (3943: 1 byte);
 * both slots' sets come back bit-exact. (param_store.c:177, slot_write's loop to the last byte.) */
static void test_any_block_size_with_byte_writes(void **state)
{
    (void)state;
    for (uint32_t bs = 3937u; bs <= 3951u; ++bs) {
        nvm_blocks(bs, 4u);
        unit = 1u;
        const mc_drive_cfg_t *a = make_cfg(0, 20, 20), *b = make_cfg(1, 21, 19);
        assert_true(MC_STORE_PARAMS_MAX + 4u * (14u + 2u * 400u) > 3944u - PAYLOAD_AT);   /* it crosses */
        mc_pstore_info_t info;
        mc_drive_cfg_t got;
        assert_int_equal(mc_pstore_save(&nvm, a, work, sizeof work, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, 0);
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_true(same_cfg(&got, a, false));
        assert_int_equal(mc_pstore_save(&nvm, b, work, sizeof work, &info), MC_PSTORE_OK);
        assert_int_equal(info.slot, 1);
        assert_int_equal(load(&got, &info), MC_PSTORE_OK);
        assert_true(same_cfg(&got, b, false));
    }
}

/* A device that reports a write unit of 0 or a block size of 0 (a description that lost them) is
 * refused (BAD_ARGS) by geometry, save, load and erase before any NVM step, with no layout.
 * (param_store.c:90.) */
static void test_zero_sizes_refused(void **state)
{
    (void)state;
    for (int k = 0; k < 2; ++k) {
        nvm_blocks(4096u, 4u);
        unit_zero = k == 0;
        block_zero = k == 1;
        assert_int_equal(hal_nvm_write_unit(&nvm), k == 0 ? 0u : 8u);
        assert_int_equal(hal_nvm_block_size(&nvm), k == 1 ? 0u : 4096u);
        mc_pstore_geom_t g;
        memset(&g, 0xA5, sizeof g);
        assert_int_equal(mc_pstore_geometry(&nvm, &g), MC_PSTORE_BAD_ARGS);
        assert_int_equal(g.slot_blocks, 0u);
        assert_int_equal(g.payload_max, 0u);
        const mc_drive_cfg_t *a = make_cfg(0, 3, 3);
        mc_drive_cfg_t got;
        assert_int_equal(mc_pstore_save(&nvm, a, big, sizeof big, NULL), MC_PSTORE_BAD_ARGS);
        assert_int_equal(load_with(big, sizeof big, &got, NULL), MC_PSTORE_BAD_ARGS);
        assert_int_equal(mc_pstore_erase(&nvm, big, sizeof big), MC_PSTORE_BAD_ARGS);
        assert_int_equal(nvm.steps, 0u);
    }
}

/* every test starts with the host model's write unit and no fault */
static int no_fault(void **state)
{
    (void)state;
    unit = 0u;
    unit_zero = false;
    block_zero = false;
    fault_arm(0u, false, UINT32_MAX);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_slot_blocks_at_the_rounding_limit, no_fault),
        cmocka_unit_test_setup(test_map_cells_on_small_devices, no_fault),
        cmocka_unit_test_setup(test_refused_setup_touches_nothing, no_fault),
        cmocka_unit_test_setup(test_write_units_above_8, no_fault),
        cmocka_unit_test_setup(test_write_unit_limits, no_fault),
        cmocka_unit_test_setup(test_header_crc_any_bit, no_fault),
        cmocka_unit_test_setup(test_model_record_other_version, no_fault),
        cmocka_unit_test_setup(test_v1_record_position_past_the_table, no_fault),
        cmocka_unit_test_setup(test_read_failure_before_a_save, no_fault),
        cmocka_unit_test_setup(test_failed_payload_write_is_not_a_success, no_fault),
        cmocka_unit_test_setup(test_failed_payload_write_ends_the_save, no_fault),
        cmocka_unit_test_setup(test_unprogrammed_byte_fails_the_read_back, no_fault),
        cmocka_unit_test_setup(test_unprogrammed_marker_fails_the_save, no_fault),
        cmocka_unit_test_setup(test_header_read_back_wrong_once, no_fault),
        cmocka_unit_test_setup(test_unreadable_record_crc, no_fault),
        cmocka_unit_test_setup(test_mismatch_refused_before_an_unreadable_rest, no_fault),
        cmocka_unit_test_setup(test_write_units_below_8, no_fault),
        cmocka_unit_test_setup(test_any_block_size_with_byte_writes, no_fault),
        cmocka_unit_test_setup(test_zero_sizes_refused, no_fault),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
