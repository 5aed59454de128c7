/* PDO rules of CiA 301 (co_pdo.c) one by one, on the PDO block's own interface
 * (mc_co_pdo_read/write/rx/sync/tx, the clock set by hand): the object sizes a mapping takes for
 * every mappable data type, the 64-bit limit at its edge, the order the mapping is checked in,
 * the transmission types 0 / 1..240 / 254 / 255 and the refused ones, the SYNC counter, the event
 * timer and the inhibit time at their edges, the COB-ID and its RTR bit, SYNC start, the frame a
 * TPDO carries and how an RPDO's bytes land in the objects. */
#include "rig.h"

#define INVALID 0x80000000u
#define NO_RTR  0x40000000u
#define TPDO1   0x185u
#define TPDO2   0x285u
#define RPDO3   0x405u

/* A fresh device in OPERATIONAL, nothing in the CAN queue, the clock at 0. */
static void operational(void)
{
    rig_init();
    rig.co.ds_on = false;
    nmt(0x01);
    drain();
    assert_int_equal(rig.co.nmt, MC_NMT_OPERATIONAL);
}

static uint32_t pw(uint16_t index, uint8_t sub, uint32_t v)
{
    return mc_co_pdo_write(&rig.co, index, sub, v);
}

static uint32_t pr(uint16_t index, uint8_t sub)
{
    uint32_t v = 0xDEADBEEFu;
    assert_int_equal(mc_co_pdo_read(&rig.co, index, sub, &v), 0u);
    return v;
}

/* Frames with this id in the queue (all taken). */
static uint32_t count_id(uint32_t id)
{
    hal_can_frame_t f;
    uint32_t n = 0u;
    while (take_any(&f)) {
        n += f.id == id;
    }
    return n;
}

/* mc_co_pdo_tx at t ms; the number of frames of TPDO id it sent. */
static uint32_t tx_at(uint32_t t, uint32_t id)
{
    rig.co.now_ms = t;
    mc_co_pdo_tx(&rig.co);
    return count_id(id);
}

static uint32_t sync_count(uint32_t id)
{
    mc_co_pdo_sync(&rig.co);
    return count_id(id);
}

/* The mapping of one PDO (map index), made invalid first through its comm index with cob. */
static void remap(uint16_t comm, uint16_t map, uint32_t cob, const uint32_t *e, uint32_t n)
{
    assert_int_equal(pw(comm, 1u, INVALID | cob), 0u);
    assert_int_equal(pw(map, 0u, 0u), 0u);
    for (uint32_t k = 0u; k < n; ++k) {
        assert_int_equal(pw(map, (uint8_t)(k + 1u), e[k]), 0u);
    }
    assert_int_equal(pw(map, 0u, n), 0u);
    assert_int_equal(pw(comm, 1u, cob), 0u);
}

/* Every mappable data type goes in with its own size only: U8, I8 8 bits; U16, I16 16; U32,
 * I32, REAL32 32 (§7.4.7: a mapping names the object's length). A TPDO takes the read objects,
 * an RPDO the written ones, each at the exact size. */
static void test_mapping_sizes_every_type(void **state)
{
    (void)state;
    rig_init();
    static const struct {
        uint16_t index;
        uint32_t bits;
        bool tx;
    } obj[] = {
        {0x1001u, 8u, true},    /* U8 error register */
        {0x6061u, 8u, true},    /* I8 modes display */
        {0x6041u, 16u, true},   /* U16 statusword */
        {0x6077u, 16u, true},   /* I16 torque actual */
        {0x606Cu, 32u, true},   /* I32 velocity actual */
        {0x6079u, 32u, true},   /* U32 DC link */
        {0x2207u, 32u, true},   /* REAL32 estimated angle */
        {0x6060u, 8u, false},   /* I8 modes of operation */
        {0x6040u, 16u, false},  /* U16 controlword */
        {0x6071u, 16u, false},  /* I16 target torque */
        {0x60FFu, 32u, false},  /* I32 target velocity */
        {0x6080u, 32u, false},  /* U32 max motor speed */
    };
    assert_int_equal(pw(0x1803u, 1u, INVALID | 0x485u), 0u);
    assert_int_equal(pw(0x1403u, 1u, INVALID | 0x505u), 0u);
    assert_int_equal(pw(0x1A03u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1603u, 0u, 0u), 0u);
    /* a sub-index the object does not have (every mappable object is sub 0): NO_SUB */
    static const uint32_t subs[] = {0x01u, 0x02u, 0x40u, 0x80u, 0xFFu};
    for (size_t k = 0; k < sizeof subs / sizeof subs[0]; ++k) {
        assert_int_equal(pw(0x1A03u, 1u, 0x60410010u | subs[k] << 8), MC_SDO_ABORT_NO_SUB);
        assert_int_equal(pw(0x1603u, 1u, 0x60FF0020u | subs[k] << 8), MC_SDO_ABORT_NO_SUB);
    }
    static const uint32_t sizes[] = {8u, 16u, 32u, 24u, 64u, 0u};
    for (size_t k = 0; k < sizeof obj / sizeof obj[0]; ++k) {
        const uint16_t map = obj[k].tx ? 0x1A03u : 0x1603u;
        for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; ++s) {
            const uint32_t e = (uint32_t)obj[k].index << 16 | sizes[s];
            const uint32_t want = sizes[s] == obj[k].bits ? 0u : MC_SDO_ABORT_NOT_MAPPABLE;
            if (pw(map, 1u, e) != want) {
                fail_msg("0x%04X mapped at %u bits: abort 0x%08X, want 0x%08X", obj[k].index, sizes[s],
                         pw(map, 1u, e), want);
            }
        }
        /* and the mapping of that one object is taken, its length in the frame */
        const uint32_t e = (uint32_t)obj[k].index << 16 | obj[k].bits;
        assert_int_equal(pw(map, 1u, e), 0u);
        assert_int_equal(pw(map, 0u, 1u), 0u);
        assert_int_equal(pr(map, 0u), 1u);
        assert_int_equal(pr(map, 1u), e);
        assert_int_equal(pw(map, 0u, 0u), 0u);
    }
}

/* Sub 0 checks the whole mapping against 64 bits: exactly 64 (2 x 32, 32 + 16 + 16, 8 x 8) is
 * taken, 72 is PDO_LENGTH; only entries 1..n are checked, in order, the first bad one's abort
 * is the answer, and a refused sub 0 leaves the PDO without mapping. */
static void test_mapping_length_and_order(void **state)
{
    (void)state;
    rig_init();
    assert_int_equal(pw(0x1801u, 1u, INVALID | TPDO2), 0u);
    assert_int_equal(pw(0x1A01u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1A01u, 1u, 0x606C0020u), 0u);
    assert_int_equal(pw(0x1A01u, 2u, 0x60790020u), 0u);
    assert_int_equal(pw(0x1A01u, 0u, 2u), 0u);   /* 64 */
    assert_int_equal(pw(0x1A01u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1A01u, 2u, 0x60770010u), 0u);
    assert_int_equal(pw(0x1A01u, 3u, 0x60410010u), 0u);
    assert_int_equal(pw(0x1A01u, 0u, 3u), 0u);   /* 32 + 16 + 16 */
    assert_int_equal(pw(0x1A01u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1A01u, 4u, 0x60610008u), 0u);
    assert_int_equal(pw(0x1A01u, 0u, 4u), MC_SDO_ABORT_PDO_LENGTH);   /* 72 */
    assert_int_equal(pr(0x1A01u, 0u), 0u);
    for (uint8_t s = 1u; s <= 8u; ++s) {
        assert_int_equal(pw(0x1A01u, s, 0x60610008u), 0u);
    }
    assert_int_equal(pw(0x1A01u, 0u, 8u), 0u);   /* 8 x 8 */
    assert_int_equal(pw(0x1A01u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1A01u, 0u, 9u), MC_SDO_ABORT_VALUE_HIGH);
    /* RPDO4 has no default mapping: its entries are 0 (no object) */
    assert_int_equal(pw(0x1403u, 1u, INVALID | 0x505u), 0u);
    assert_int_equal(pr(0x1603u, 0u), 0u);
    assert_int_equal(pw(0x1603u, 1u, 0x60400010u), 0u);
    assert_int_equal(pw(0x1603u, 0u, 2u), MC_SDO_ABORT_NO_OBJECT);   /* entry 2 is 0 */
    assert_int_equal(pw(0x1603u, 0u, 1u), 0u);                       /* entry 2 is not looked at */
    assert_int_equal(pr(0x1603u, 0u), 1u);
    assert_int_equal(pw(0x1603u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1603u, 2u, 0x60710010u), 0u);
    assert_int_equal(pw(0x1603u, 1u, 0u), MC_SDO_ABORT_NO_OBJECT);   /* an entry is checked as written */
    assert_int_equal(pr(0x1603u, 1u), 0x60400010u);
    assert_int_equal(pw(0x1603u, 0u, 2u), 0u);
    assert_int_equal(pr(0x1603u, 2u), 0x60710010u);
}

/* Transmission types: 0..240, 254 and 255 are taken and read back; 241..253 and anything above
 * 255 (which a byte would wrap into a valid one) are VALUE and change nothing. */
static void test_transmission_types(void **state)
{
    (void)state;
    rig_init();
    for (uint32_t t = 0u; t <= 300u; ++t) {
        const bool ok = t <= 240u || t == 254u || t == 255u;
        for (int g = 0; g < 2; ++g) {
            const uint16_t index = g == 0 ? 0x1801u : 0x1401u;
            const uint32_t before = pr(index, 2u);
            const uint32_t a = pw(index, 2u, t);
            if (a != (ok ? 0u : MC_SDO_ABORT_VALUE)) {
                fail_msg("type %u on 0x%04X: abort 0x%08X", t, index, a);
            }
            assert_int_equal(pr(index, 2u), ok ? t : before);
        }
    }
    assert_int_equal(pw(0x1801u, 2u, 0x101u), MC_SDO_ABORT_VALUE);
    assert_int_equal(pw(0x1801u, 2u, 0xFFFFFFFFu), MC_SDO_ABORT_VALUE);
}

/* Type 0 (synchronous, acyclic): at a SYNC only if the mapped data changed since the last one
 * sent; the first SYNC after OPERATIONAL sends; nothing between SYNCs. */
static void test_type0_on_change_at_sync(void **state)
{
    (void)state;
    operational();
    rig.co.ds.od.velocity_actual = 1200;
    rig.co.ds.od.torque_actual = -50;
    assert_int_equal(pw(0x1801u, 2u, 0u), 0u);
    assert_int_equal(tx_at(500u, TPDO2), 0u);   /* not on its timer */
    assert_int_equal(sync_count(TPDO2), 1u);
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 0u);
    rig.co.ds.od.torque_actual = -51;   /* a change in the last mapped byte pair */
    assert_int_equal(tx_at(501u, TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 1u);
    assert_int_equal(sync_count(TPDO2), 0u);
    rig.co.ds.od.velocity_actual = 1200 + 0x1000000;   /* in its highest byte */
    assert_int_equal(sync_count(TPDO2), 1u);
    /* made valid again: goes at the first SYNC with the same data */
    remap(0x1801u, 0x1A01u, TPDO2, (const uint32_t[]){0x606C0020u}, 1u);
    assert_int_equal(sync_count(TPDO2), 1u);
    assert_int_equal(sync_count(TPDO2), 0u);
}

/* Types 1..240: every n-th SYNC, counted from the type's write; 1 every SYNC; 240 the 240th. */
static void test_cyclic_sync_counter(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pw(0x1801u, 2u, 1u), 0u);
    for (int k = 0; k < 5; ++k) {
        assert_int_equal(sync_count(TPDO2), 1u);
    }
    assert_int_equal(pw(0x1801u, 2u, 3u), 0u);
    uint32_t seen[9];
    for (int k = 0; k < 9; ++k) {
        seen[k] = sync_count(TPDO2);
    }
    static const uint32_t want[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    assert_memory_equal(seen, want, sizeof seen);
    /* two SYNCs in, the type written again: three more to the next one */
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(pw(0x1801u, 2u, 3u), 0u);
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 1u);
    assert_int_equal(pw(0x1801u, 2u, 240u), 0u);
    uint32_t n = 0u, first = 0u;
    for (uint32_t k = 1u; k <= 480u; ++k) {
        const uint32_t c = sync_count(TPDO2);
        n += c;
        if (c != 0u && first == 0u) {
            first = k;
        }
    }
    assert_int_equal(n, 2u);
    assert_int_equal(first, 240u);
    /* a SYNC outside OPERATIONAL counts nothing */
    assert_int_equal(pw(0x1801u, 2u, 2u), 0u);
    rig.co.nmt = MC_NMT_PRE_OPERATIONAL;
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 0u);
    rig.co.nmt = MC_NMT_OPERATIONAL;
    assert_int_equal(sync_count(TPDO2), 0u);
    assert_int_equal(sync_count(TPDO2), 1u);
}

/* Type 254: the event timer alone, at its period exactly counted from the last transmission;
 * a change does not send; event timer 0 is off. */
static void test_event_timer(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pr(0x1801u, 5u), 10u);
    assert_int_equal(tx_at(9u, TPDO2), 0u);
    assert_int_equal(tx_at(10u, TPDO2), 1u);
    rig.co.ds.od.velocity_actual = 77;
    assert_int_equal(tx_at(19u, TPDO2), 0u);
    assert_int_equal(tx_at(20u, TPDO2), 1u);
    assert_int_equal(pw(0x1801u, 5u, 3u), 0u);   /* while valid */
    assert_int_equal(pr(0x1801u, 5u), 3u);
    assert_int_equal(tx_at(22u, TPDO2), 0u);
    assert_int_equal(tx_at(23u, TPDO2), 1u);
    assert_int_equal(pw(0x1801u, 5u, 0u), 0u);
    for (uint32_t t = 24u; t < 2000u; t += 97u) {
        rig.co.ds.od.velocity_actual = (int32_t)t;
        assert_int_equal(tx_at(t, TPDO2), 0u);
    }
    /* the timer of a type 255 PDO counts from its last frame, also one sent on a change */
    assert_int_equal(pw(0x1801u, 2u, 255u), 0u);
    assert_int_equal(pw(0x1801u, 5u, 50u), 0u);
    rig.co.ds.od.velocity_actual = 5;
    assert_int_equal(tx_at(3000u, TPDO2), 1u);   /* changed */
    assert_int_equal(tx_at(3049u, TPDO2), 0u);
    assert_int_equal(tx_at(3050u, TPDO2), 1u);   /* unchanged: its timer */
}

/* Type 255: on a change, but not sooner than the inhibit time [100 us] after the last frame;
 * the change stays due and goes when the inhibit time is over. */
static void test_inhibit_time(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pr(0x1800u, 3u), 10u);   /* 1 ms */
    assert_int_equal(tx_at(1u, TPDO1), 1u);   /* the first: its data is new */
    rig.co.ds.od.statusword ^= 0x0200u;
    assert_int_equal(tx_at(1u, TPDO1), 0u);   /* 0 ms after */
    assert_int_equal(tx_at(2u, TPDO1), 1u);   /* 1 ms: 10 x 100 us */
    assert_int_equal(tx_at(3u, TPDO1), 0u);   /* nothing new */
    /* 2.5 ms: a change 2 ms after the last frame waits for the 3rd */
    assert_int_equal(pw(0x1800u, 3u, 25u), MC_SDO_ABORT_STATE);   /* only while invalid */
    assert_int_equal(pw(0x1800u, 1u, INVALID | TPDO1), 0u);
    assert_int_equal(pw(0x1800u, 3u, 25u), 0u);
    assert_int_equal(pr(0x1800u, 3u), 25u);
    assert_int_equal(pw(0x1800u, 1u, TPDO1), 0u);
    assert_int_equal(tx_at(10u, TPDO1), 1u);   /* valid again: goes at the first event */
    rig.co.ds.od.statusword ^= 0x0200u;
    assert_int_equal(tx_at(11u, TPDO1), 0u);
    assert_int_equal(tx_at(12u, TPDO1), 0u);
    assert_int_equal(tx_at(13u, TPDO1), 1u);
    /* 2 ms exactly */
    assert_int_equal(pw(0x1800u, 1u, INVALID | TPDO1), 0u);
    assert_int_equal(pw(0x1800u, 3u, 20u), 0u);
    assert_int_equal(pw(0x1800u, 1u, TPDO1), 0u);
    assert_int_equal(tx_at(20u, TPDO1), 1u);
    rig.co.ds.od.statusword ^= 0x0200u;
    assert_int_equal(tx_at(21u, TPDO1), 0u);
    assert_int_equal(tx_at(22u, TPDO1), 1u);
    /* inhibit 0: every change at once */
    assert_int_equal(pw(0x1800u, 1u, INVALID | TPDO1), 0u);
    assert_int_equal(pw(0x1800u, 3u, 0u), 0u);
    assert_int_equal(pw(0x1800u, 1u, TPDO1), 0u);
    assert_int_equal(tx_at(22u, TPDO1), 1u);
    rig.co.ds.od.statusword ^= 0x0200u;
    assert_int_equal(tx_at(22u, TPDO1), 1u);
    assert_int_equal(tx_at(22u, TPDO1), 0u);
}

/* COB-ID (sub 1): bits 11..29 are refused (no 29-bit ids), a valid PDO keeps its CAN-ID, an
 * invalid one takes a new one; a TPDO always reads "no RTR" (bit 30), an RPDO keeps bit 30 as
 * written. SYNC start (sub 6) and the inhibit time only while invalid, SYNC start at most 240. */
static void test_cob_id_and_sync_start(void **state)
{
    (void)state;
    rig_init();
    for (uint32_t b = 11u; b <= 29u; ++b) {
        assert_int_equal(pw(0x1803u, 1u, INVALID | (1u << b) | 0x485u), MC_SDO_ABORT_VALUE);
        assert_int_equal(pw(0x1403u, 1u, INVALID | (1u << b) | 0x505u), MC_SDO_ABORT_VALUE);
    }
    assert_int_equal(pr(0x1803u, 1u), NO_RTR | 0x485u);
    assert_int_equal(pr(0x1403u, 1u), INVALID | 0x505u);
    assert_int_equal(pw(0x1803u, 1u, 0x485u), 0u);   /* the same id: taken */
    assert_int_equal(pw(0x1803u, 1u, 0x486u), MC_SDO_ABORT_VALUE);
    assert_int_equal(pw(0x1803u, 1u, 0x484u), MC_SDO_ABORT_VALUE);   /* lower or higher alike */
    assert_int_equal(pw(0x1803u, 1u, NO_RTR | 0x485u), 0u);          /* the same id with bit 30 */
    assert_int_equal(pw(0x1803u, 1u, INVALID | 0x486u), 0u);   /* invalid: any id */
    assert_int_equal(pr(0x1803u, 1u), INVALID | NO_RTR | 0x486u);
    assert_int_equal(pw(0x1803u, 1u, 0x487u), 0u);   /* from invalid to valid with a new id */
    assert_int_equal(pr(0x1803u, 1u), NO_RTR | 0x487u);
    assert_int_equal(pw(0x1403u, 1u, INVALID | NO_RTR | 0x506u), 0u);
    assert_int_equal(pr(0x1403u, 1u), INVALID | NO_RTR | 0x506u);
    assert_int_equal(pw(0x1403u, 1u, 0x507u), 0u);
    assert_int_equal(pr(0x1403u, 1u), 0x507u);
    /* SYNC start */
    assert_int_equal(pr(0x1801u, 6u), 0u);
    assert_int_equal(pw(0x1801u, 6u, 5u), MC_SDO_ABORT_STATE);
    assert_int_equal(pw(0x1801u, 1u, INVALID | TPDO2), 0u);
    assert_int_equal(pw(0x1801u, 6u, 241u), MC_SDO_ABORT_VALUE_HIGH);
    assert_int_equal(pw(0x1801u, 6u, 240u), 0u);
    assert_int_equal(pr(0x1801u, 6u), 240u);
    assert_int_equal(pw(0x1801u, 6u, 1u), 0u);
    assert_int_equal(pr(0x1801u, 6u), 1u);
    /* the subs a comm parameter has: TPDO 0,1,2,3,5,6; 4 is reserved, 7 none */
    assert_int_equal(pr(0x1801u, 0u), 6u);
    assert_int_equal(pr(0x1401u, 0u), 2u);
    uint32_t v;
    assert_int_equal(mc_co_pdo_read(&rig.co, 0x1801u, 4u, &v), MC_SDO_ABORT_NO_SUB);
    assert_int_equal(mc_co_pdo_read(&rig.co, 0x1801u, 7u, &v), MC_SDO_ABORT_NO_SUB);
    assert_int_equal(pw(0x1801u, 4u, 0u), MC_SDO_ABORT_NO_SUB);
    assert_int_equal(pw(0x1801u, 0u, 6u), MC_SDO_ABORT_NO_SUB);
}

/* The defaults (CiA 402 predefined connection set): RPDO1/2 valid at 0x200/0x300 + node, 3/4
 * invalid, all asynchronous (255); TPDO1 statusword on change (1 ms inhibit) and every 100 ms,
 * TPDO2..4 every 10 ms (254), inhibit 0, SYNC start 0. */
static void test_default_comm_parameters(void **state)
{
    (void)state;
    rig_init();
    for (uint16_t k = 0u; k < 4u; ++k) {
        assert_int_equal(pr((uint16_t)(0x1400u + k), 1u), (0x200u + 0x100u * k + NODE) | (k >= 2u ? INVALID : 0u));
        assert_int_equal(pr((uint16_t)(0x1400u + k), 2u), 255u);
        assert_int_equal(pr((uint16_t)(0x1800u + k), 1u), NO_RTR | (0x180u + 0x100u * k + NODE));
        assert_int_equal(pr((uint16_t)(0x1800u + k), 2u), k == 0u ? 255u : 254u);
        assert_int_equal(pr((uint16_t)(0x1800u + k), 3u), k == 0u ? 10u : 0u);
        assert_int_equal(pr((uint16_t)(0x1800u + k), 5u), k == 0u ? 100u : 10u);
        assert_int_equal(pr((uint16_t)(0x1800u + k), 6u), 0u);
        assert_int_equal(pr((uint16_t)(0x1A00u + k), 0u), 2u);
        assert_int_equal(pr((uint16_t)(0x1600u + k), 0u), k < 2u ? 2u : 0u);
    }
    assert_int_equal(pr(0x1A00u, 1u), 0x60410010u);
    assert_int_equal(pr(0x1A00u, 2u), 0x60610008u);
    assert_int_equal(pr(0x1A02u, 1u), 0x22070020u);
    assert_int_equal(pr(0x1A02u, 2u), 0x22080020u);
    assert_int_equal(pr(0x1A03u, 2u), 0x60790020u);
    assert_int_equal(pr(0x1601u, 2u), 0x60710010u);
}

/* The predefined connection set's COB-IDs for any node id (CiA 301 §7.3.5): base + node id,
 * RPDO3/4 invalid, TPDOs without RTR; here for the even, the lowest and the highest ids too. */
static void test_default_cob_ids_every_node(void **state)
{
    (void)state;
    static const uint8_t nodes[] = {1u, 2u, 64u, 100u, 127u};
    for (size_t n = 0; n < sizeof nodes / sizeof nodes[0]; ++n) {
        rig_init();
        const mc_co_cfg_t c = {.node_id = nodes[n], .step_s = 1e-3f};
        assert_true(mc_co_init(&rig.co, &c, &rig.can, &rig.d, &rig.nvm, &rig.scope, MC_PSTORE_EMPTY));
        for (uint16_t k = 0u; k < 4u; ++k) {
            const uint32_t r = pr((uint16_t)(0x1400u + k), 1u), t = pr((uint16_t)(0x1800u + k), 1u);
            if (r != ((0x200u + 0x100u * k + nodes[n]) | (k >= 2u ? INVALID : 0u)) ||
                t != (NO_RTR | (0x180u + 0x100u * k + nodes[n]))) {
                fail_msg("node %u PDO %u: RPDO 0x%08X TPDO 0x%08X", nodes[n], k + 1u, r, t);
            }
        }
    }
}

/* A TPDO's frame: the mapped objects little-endian one after the other, its DLC their bytes. */
static void test_tpdo_frame_layout(void **state)
{
    (void)state;
    operational();
    remap(0x1801u, 0x1A01u, TPDO2,
          (const uint32_t[]){0x60610008u, 0x60770010u, 0x606C0020u}, 3u);
    rig.co.ds.od.mode_display = -3;
    rig.co.ds.od.torque_actual = -2;
    rig.co.ds.od.velocity_actual = 0x01020304;
    rig.co.now_ms = 1000u;
    mc_co_pdo_tx(&rig.co);
    hal_can_frame_t f;
    assert_true(take_id(TPDO2, &f));
    assert_int_equal(f.dlc, 7u);
    static const uint8_t want[7] = {0xFD, 0xFE, 0xFF, 0x04, 0x03, 0x02, 0x01};
    assert_memory_equal(f.data, want, 7u);
    /* an empty mapping: a frame without data */
    remap(0x1801u, 0x1A01u, TPDO2, NULL, 0u);
    rig.co.now_ms = 2000u;
    mc_co_pdo_tx(&rig.co);
    assert_true(take_id(TPDO2, &f));
    assert_int_equal(f.dlc, 0u);
}

/* A TPDO the CAN driver refuses counts as dropped; the others go on. */
static void test_tpdo_dropped(void **state)
{
    (void)state;
    operational();
    const hal_can_frame_t filler = {.id = 0x7FFu, .dlc = 0u};
    uint32_t queued = 0u;
    while (hal_can_send(&rig.can, &filler)) {
        ++queued;
    }
    assert_true(queued > 0u);
    const uint32_t d0 = rig.co.tx_dropped;
    rig.co.now_ms = 10u;
    mc_co_pdo_tx(&rig.co);   /* TPDO1 (new data) and TPDO2..4 (timers) */
    assert_int_equal(rig.co.tx_dropped, d0 + 4u);
    drain();
    assert_int_equal(tx_at(20u, TPDO2), 1u);
}

/* RPDO: longer frames are taken (the mapped bytes applied), shorter ones refused with an EMCY
 * naming the PDO, the DLC and the length wanted; bytes go little-endian into the objects in
 * mapping order; a frame outside OPERATIONAL is consumed and applied nowhere; a frame for no
 * RPDO is not the PDO block's. */
static void test_rpdo_layout_and_length(void **state)
{
    (void)state;
    operational();
    remap(0x1403u, 0x1603u, 0x505u, (const uint32_t[]){0x60600008u, 0x60710010u, 0x60FF0020u}, 3u);
    const hal_can_frame_t f = {.id = 0x505u, .dlc = 8u, .data = {0x0A, 0xF6, 0xFF, 0x18, 0xFC, 0xFF, 0xFF, 0x99}};
    const uint32_t rx0 = rig.co.rpdo_rx;
    assert_true(mc_co_pdo_rx(&rig.co, &f));
    assert_int_equal(rig.co.rpdo_rx, rx0 + 1u);
    assert_int_equal(rig.co.ds.od.mode, 10);
    assert_int_equal(rig.co.ds.od.target_torque, -10);
    assert_int_equal(rig.co.ds.od.target_velocity, -1000);
    /* 6 bytes for 7 */
    const hal_can_frame_t s = {.id = 0x505u, .dlc = 6u, .data = {0x09, 0x01, 0x00, 0x01, 0x00, 0x00}};
    const uint32_t bad0 = rig.co.rpdo_bad;
    assert_true(mc_co_pdo_rx(&rig.co, &s));
    assert_int_equal(rig.co.rpdo_bad, bad0 + 1u);
    assert_int_equal(rig.co.rpdo_rx, rx0 + 1u);
    assert_int_equal(rig.co.ds.od.mode, 10);
    assert_int_equal(rig.co.ds.od.target_velocity, -1000);
    hal_can_frame_t e;
    assert_true(take_id(0x080u + NODE, &e));
    assert_int_equal(e.dlc, 8u);
    assert_int_equal(e.data[0] | (e.data[1] << 8), MC_EMCY_PDO_LENGTH);
    assert_int_equal(e.data[2], 0x10u);   /* error register: communication */
    assert_int_equal(e.data[3], 3u);   /* RPDO4 */
    assert_int_equal(e.data[4], 6u);   /* its DLC */
    assert_int_equal(e.data[5], 7u);   /* the mapping's bytes */
    assert_int_equal(e.data[6], 0u);   /* the rest of the manufacturer field: 0 */
    assert_int_equal(e.data[7], 0u);
    /* the exact length */
    const hal_can_frame_t x = {.id = 0x505u, .dlc = 7u, .data = {0x09, 0x05, 0x00, 0xE8, 0x03, 0x00, 0x00}};
    assert_true(mc_co_pdo_rx(&rig.co, &x));
    assert_int_equal(rig.co.ds.od.mode, 9);
    assert_int_equal(rig.co.ds.od.target_torque, 5);
    assert_int_equal(rig.co.ds.od.target_velocity, 1000);
    /* pre-operational: consumed, nothing applied, nothing counted */
    rig.co.nmt = MC_NMT_PRE_OPERATIONAL;
    const hal_can_frame_t y = {.id = 0x505u, .dlc = 7u, .data = {0x0A, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00}};
    assert_true(mc_co_pdo_rx(&rig.co, &y));
    assert_int_equal(rig.co.ds.od.mode, 9);
    assert_int_equal(rig.co.ds.od.target_torque, 5);
    assert_int_equal(rig.co.rpdo_rx, rx0 + 2u);
    rig.co.nmt = MC_NMT_OPERATIONAL;
    /* an invalid RPDO's id, an unknown id: not a PDO */
    const hal_can_frame_t z = {.id = 0x405u, .dlc = 8u};
    assert_false(mc_co_pdo_rx(&rig.co, &z));
    const hal_can_frame_t u = {.id = 0x506u, .dlc = 8u};
    assert_false(mc_co_pdo_rx(&rig.co, &u));
    assert_int_equal(rig.co.rpdo_rx, rx0 + 2u);
}

/* A synchronous RPDO (0..240) holds its last frame until the SYNC and applies it once; a frame
 * held when the PDO is made invalid, or its COB-ID rewritten, is dropped; the SYNC's COB-ID is
 * what 0x1005 says. */
static void test_rpdo_synchronous(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pw(0x1401u, 2u, 10u), 0u);
    const hal_can_frame_t a = {.id = 0x305u, .dlc = 6u, .data = {0xE8, 0x03, 0x00, 0x00, 0x05, 0x00}};
    const hal_can_frame_t b = {.id = 0x305u, .dlc = 6u, .data = {0xD0, 0x07, 0x00, 0x00, 0x06, 0x00}};
    assert_true(mc_co_pdo_rx(&rig.co, &a));
    assert_true(mc_co_pdo_rx(&rig.co, &b));   /* the last one counts */
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    const hal_can_frame_t sync = {.id = 0x080u, .dlc = 0u};
    assert_true(mc_co_pdo_rx(&rig.co, &sync));
    assert_int_equal(rig.co.ds.od.target_velocity, 2000);
    assert_int_equal(rig.co.ds.od.target_torque, 6);
    const uint32_t rx = rig.co.rpdo_rx;
    rig.co.ds.od.target_velocity = 0;
    mc_co_pdo_sync(&rig.co);   /* applied once */
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    assert_int_equal(rig.co.rpdo_rx, rx);
    /* held, then the PDO made invalid: dropped, also once valid again */
    assert_true(mc_co_pdo_rx(&rig.co, &a));
    assert_int_equal(pw(0x1401u, 1u, INVALID | 0x305u), 0u);
    mc_co_pdo_sync(&rig.co);
    assert_int_equal(pw(0x1401u, 1u, 0x305u), 0u);
    mc_co_pdo_sync(&rig.co);
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    /* held, then the same COB-ID written again: dropped */
    assert_true(mc_co_pdo_rx(&rig.co, &a));
    assert_int_equal(pw(0x1401u, 1u, 0x305u), 0u);
    mc_co_pdo_sync(&rig.co);
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    /* held while invalid cannot happen: an invalid RPDO takes no frame */
    assert_int_equal(pw(0x1401u, 1u, INVALID | 0x305u), 0u);
    assert_false(mc_co_pdo_rx(&rig.co, &a));
    assert_int_equal(pw(0x1401u, 1u, 0x305u), 0u);
    mc_co_pdo_sync(&rig.co);
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    /* held, a SYNC outside OPERATIONAL applies nothing */
    assert_true(mc_co_pdo_rx(&rig.co, &a));
    rig.co.nmt = MC_NMT_PRE_OPERATIONAL;
    mc_co_pdo_sync(&rig.co);
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    rig.co.nmt = MC_NMT_OPERATIONAL;
    /* another SYNC id */
    rig.co.cob_sync = 0x081u;
    assert_false(mc_co_pdo_rx(&rig.co, &sync));
    const hal_can_frame_t sync2 = {.id = 0x081u, .dlc = 0u};
    assert_true(mc_co_pdo_rx(&rig.co, &sync2));
}

/* The RPDO's transmission type decides when a frame is applied: 0..240 at the next SYNC (240
 * and 0 alike), 254 and 255 at once. */
static void test_rpdo_type_edges(void **state)
{
    (void)state;
    static const struct {
        uint32_t type;
        bool held;
    } c[] = {{0u, true}, {1u, true}, {240u, true}, {254u, false}, {255u, false}};
    for (size_t k = 0; k < sizeof c / sizeof c[0]; ++k) {
        operational();
        assert_int_equal(pw(0x1401u, 2u, c[k].type), 0u);
        const hal_can_frame_t a = {.id = 0x305u, .dlc = 6u, .data = {0xE8, 0x03, 0x00, 0x00, 0x05, 0x00}};
        assert_true(mc_co_pdo_rx(&rig.co, &a));
        if (rig.co.ds.od.target_velocity != (c[k].held ? 0 : 1000)) {
            fail_msg("type %u: applied %s", c[k].type, c[k].held ? "before the SYNC" : "only at the SYNC");
        }
        mc_co_pdo_sync(&rig.co);
        assert_int_equal(rig.co.ds.od.target_velocity, 1000);
    }
}

/* STOPPED (CiA 301 §7.3.2): no PDO at all, neither on a timer, nor on a change, nor at a SYNC,
 * and received RPDOs are not applied; OPERATIONAL again, the timers go on. */
static void test_stopped_no_pdo(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pw(0x1802u, 2u, 1u), 0u);
    nmt(0x02);
    assert_int_equal(rig.co.nmt, MC_NMT_STOPPED);
    drain();
    rig.co.ds.od.statusword ^= 0x0200u;
    for (uint32_t t = 1u; t < 300u; t += 7u) {
        rig.co.ds.od.velocity_actual = (int32_t)t;
        rig.co.now_ms = t;
        mc_co_pdo_tx(&rig.co);
        mc_co_pdo_sync(&rig.co);
    }
    hal_can_frame_t f;
    assert_false(take_any(&f));
    const hal_can_frame_t a = {.id = 0x305u, .dlc = 6u, .data = {0xE8, 0x03, 0x00, 0x00, 0x05, 0x00}};
    assert_true(mc_co_pdo_rx(&rig.co, &a));
    assert_int_equal(rig.co.ds.od.target_velocity, 0);
    rig.co.nmt = MC_NMT_OPERATIONAL;
    assert_int_equal(tx_at(400u, TPDO2), 1u);
}

/* Mapping edges the run found: a valid PDO without mapping still refuses entry writes (§7.5.2.36:
 * the PDO must be invalid); a mapping cut to fewer entries counts only those (an RPDO of their
 * length is taken); asynchronous TPDOs (254, 255) never go out on SYNCs. */
static void test_mapping_cut_and_async_at_sync(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pw(0x1403u, 1u, INVALID | 0x505u), 0u);
    assert_int_equal(pw(0x1603u, 0u, 0u), 0u);
    assert_int_equal(pw(0x1403u, 1u, 0x505u), 0u);   /* valid, no mapping */
    assert_int_equal(pw(0x1603u, 1u, 0x60400010u), MC_SDO_ABORT_STATE);
    assert_int_equal(pr(0x1603u, 1u), 0u);
    /* three entries, then cut to two: a 3-byte frame (controlword + mode) is the whole RPDO */
    remap(0x1403u, 0x1603u, 0x505u, (const uint32_t[]){0x60400010u, 0x60600008u, 0x60FF0020u}, 3u);
    assert_int_equal(pw(0x1403u, 1u, INVALID | 0x505u), 0u);
    assert_int_equal(pw(0x1603u, 0u, 2u), 0u);
    assert_int_equal(pw(0x1403u, 1u, 0x505u), 0u);
    const uint32_t bad0 = rig.co.rpdo_bad;
    const hal_can_frame_t f = {.id = 0x505u, .dlc = 3u, .data = {0x06, 0x00, 0x09}};
    assert_true(mc_co_pdo_rx(&rig.co, &f));
    assert_int_equal(rig.co.rpdo_bad, bad0);
    assert_int_equal(rig.co.ds.od.mode, 9);
    /* TPDO1 (255) and TPDO2 (254) over 600 SYNCs: nothing */
    drain();
    for (int k = 0; k < 600; ++k) {
        mc_co_pdo_sync(&rig.co);
    }
    hal_can_frame_t g;
    assert_false(take_id(TPDO1, &g));
    drain();
    for (int k = 0; k < 600; ++k) {
        mc_co_pdo_sync(&rig.co);
    }
    assert_false(take_id(TPDO2, &g));
}

/* The SYNC serves every PDO, the first ones too: RPDO1 synchronous, TPDO1 every SYNC. */
static void test_sync_serves_pdo1(void **state)
{
    (void)state;
    operational();
    assert_int_equal(pw(0x1400u, 2u, 0u), 0u);
    assert_int_equal(pw(0x1800u, 2u, 1u), 0u);
    const hal_can_frame_t f = {.id = 0x205u, .dlc = 3u, .data = {0x06, 0x00, 0x0A}};   /* shutdown, cst */
    assert_true(mc_co_pdo_rx(&rig.co, &f));
    assert_int_equal(rig.co.ds.od.mode, MC_402_MODE_PV);
    for (int k = 0; k < 3; ++k) {
        assert_int_equal(sync_count(TPDO1), 1u);
    }
    assert_int_equal(rig.co.ds.od.controlword, 0x06u);
    assert_int_equal(rig.co.ds.od.mode, 10);
}

/* An invalid TPDO sends nothing: not on its timer, not on a change, not at a SYNC; nor does any
 * TPDO outside OPERATIONAL. */
static void test_invalid_tpdo_silent(void **state)
{
    (void)state;
    operational();
    for (uint16_t k = 0u; k < 4u; ++k) {
        assert_int_equal(pw((uint16_t)(0x1800u + k), 1u, INVALID | (0x180u + 0x100u * k + NODE)), 0u);
    }
    rig.co.ds.od.statusword ^= 0x0200u;
    for (uint32_t t = 1u; t < 300u; t += 7u) {
        rig.co.ds.od.velocity_actual = (int32_t)t;
        rig.co.now_ms = t;
        mc_co_pdo_tx(&rig.co);
    }
    assert_int_equal(pw(0x1801u, 2u, 1u), 0u);
    assert_int_equal(pw(0x1802u, 2u, 0u), 0u);
    for (int k = 0; k < 3; ++k) {
        mc_co_pdo_sync(&rig.co);
    }
    hal_can_frame_t f;
    assert_false(take_any(&f));
    /* valid again, but pre-operational */
    operational();
    rig.co.nmt = MC_NMT_PRE_OPERATIONAL;
    assert_int_equal(pw(0x1801u, 2u, 1u), 0u);
    for (uint32_t t = 1u; t < 300u; t += 7u) {
        rig.co.now_ms = t;
        mc_co_pdo_tx(&rig.co);
        mc_co_pdo_sync(&rig.co);
    }
    assert_false(take_any(&f));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mapping_sizes_every_type),
        cmocka_unit_test(test_mapping_length_and_order),
        cmocka_unit_test(test_transmission_types),
        cmocka_unit_test(test_type0_on_change_at_sync),
        cmocka_unit_test(test_cyclic_sync_counter),
        cmocka_unit_test(test_event_timer),
        cmocka_unit_test(test_inhibit_time),
        cmocka_unit_test(test_cob_id_and_sync_start),
        cmocka_unit_test(test_default_comm_parameters),
        cmocka_unit_test(test_default_cob_ids_every_node),
        cmocka_unit_test(test_tpdo_frame_layout),
        cmocka_unit_test(test_tpdo_dropped),
        cmocka_unit_test(test_rpdo_layout_and_length),
        cmocka_unit_test(test_rpdo_synchronous),
        cmocka_unit_test(test_rpdo_type_edges),
        cmocka_unit_test(test_invalid_tpdo_silent),
        cmocka_unit_test(test_sync_serves_pdo1),
        cmocka_unit_test(test_stopped_no_pdo),
        cmocka_unit_test(test_mapping_cut_and_async_at_sync),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
