/* Hand-over primitives (mc/handover.h) with the ISR run between every two steps of the
 * background side. This test builds handover.c with MC_HANDOVER_TESTING: every background-side
 * call passes test points (after every byte it copies, around every publishing store) where the
 * hook below may run the ISR-side call, as an interrupt would; the tests' own in-place fills
 * pass the same hook after every byte / word. Payloads carry their generation in every field
 * plus a checksum, so a copy mixing two writes shows. */
#include "core_test.h"
#include "mc/handover.h"
#include <stdbool.h>
#include <string.h>

/* ---- interleaving harness ------------------------------------------------------------------ */

typedef enum { FIRE_NEVER, FIRE_EVERY, FIRE_AT, FIRE_RANDOM } fire_mode_t;

static struct {
    fire_mode_t mode;
    long n;                            /* test points passed since arm()                   */
    long at[2];                        /* FIRE_AT: fire at these points (-1: unused)       */
    uint32_t rng, one_in;              /* FIRE_RANDOM: fire with probability 1 / one_in    */
    void (*track)(mc_handover_tp_t p); /* bookkeeping at every point, before any firing    */
    void (*isr)(mc_handover_tp_t p);   /* the ISR-side call                                */
    long fired;
    int depth;
} H;

static uint32_t lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static void hook(mc_handover_tp_t p)
{
    assert_int_equal(H.depth, 0);   /* ISR-side calls never reach a test point */
    if (H.track != NULL) {
        H.track(p);
    }
    bool fire = false;
    switch (H.mode) {
    case FIRE_NEVER:
        break;
    case FIRE_EVERY:
        fire = true;
        break;
    case FIRE_AT:
        fire = (H.n == H.at[0]) || (H.n == H.at[1]);
        break;
    case FIRE_RANDOM:
        fire = (lcg(&H.rng) % H.one_in) == 0u;
        break;
    }
    H.n++;
    if (fire && H.isr != NULL) {
        H.fired++;
        H.depth++;
        H.isr(p);
        H.depth--;
    }
}

static void arm(fire_mode_t mode, long at0, long at1, void (*track)(mc_handover_tp_t),
                void (*isr)(mc_handover_tp_t))
{
    H.mode = mode;
    H.n = 0;
    H.at[0] = at0;
    H.at[1] = at1;
    H.track = track;
    H.isr = isr;
    H.fired = 0;
    H.depth = 0;
    mc_handover_test_hook = hook;
}

static void disarm(void)
{
    mc_handover_test_hook = NULL;
}

/* a background step of the test's own (in-place fill): a point like the library's */
static void step(void)
{
    if (mc_handover_test_hook != NULL) {
        mc_handover_test_hook(MC_HTP_COPY_BYTE);
    }
}

static void fill_bytes(void *dst, const void *src, size_t n)
{
    unsigned char *d = dst;
    const unsigned char *s = src;
    for (size_t i = 0; i < n; ++i) {
        d[i] = s[i];
        step();
    }
}

static uint32_t fnv1a(const void *p, size_t n)
{
    const unsigned char *b = p;
    uint32_t h = 2166136261u;
    for (size_t i = 0; i < n; ++i) {
        h = (h ^ b[i]) * 16777619u;
    }
    return h;
}

/* ---- 1. commands ------------------------------------------------------------------------- */

typedef struct {
    uint32_t gen;
    float x[8];
    uint32_t check;   /* fnv1a of the bytes before it */
} tcmd_t;             /* 40 bytes, like mc_drive_cmd_t */

MC_CMDBUF_TYPED(tcmdbuf, tcmd_t)

enum { REASON_TORN = 1, REASON_NOT_FINITE = 7, REASON_BAD_GEN = 9 };

static tcmd_t cmd_make(uint32_t gen)
{
    tcmd_t c;
    memset(&c, 0, sizeof c);
    c.gen = gen;
    for (int i = 0; i < 8; ++i) {
        c.x[i] = (float)(gen * 16u + (uint32_t)i) + 0.25f;
    }
    c.check = fnv1a(&c, offsetof(tcmd_t, check));
    return c;
}

static bool cmd_ok(const tcmd_t *c)
{
    const tcmd_t ref = cmd_make(c->gen);
    return memcmp(&ref, c, sizeof ref) == 0;
}

static tcmdbuf_t CB;
static tcmd_t CUR;                 /* the ISR's command in force                           */
static uint32_t W_GEN;             /* generation the background is writing                 */
static uint32_t W_PUB;             /* generation whose publishing store has executed       */
static const void *W_SLOT;         /* slot the background is writing (NULL: none)          */
static uint32_t CMD_TAKES;

static const tcmd_t *cmd_spare(void)
{
    return &CB.slot[(atomic_load(&CB.base.seq) + 1u) & 1u];
}

/* validator of the interleaving tests: runs on the published slot, in the ISR */
static uint32_t check_in_place(const void *cmd, void *ctx)
{
    (void)ctx;
    assert_ptr_not_equal(cmd, W_SLOT);   /* never the slot being written */
    return cmd_ok(cmd) ? 0u : (uint32_t)REASON_TORN;
}

static void cmd_track(mc_handover_tp_t p)
{
    if (p == MC_HTP_CMD_PUBLISHED) {   /* the publishing store has executed */
        W_PUB = W_GEN;
        W_SLOT = NULL;
    }
}

static void cmd_isr(mc_handover_tp_t p)
{
    (void)p;
    const uint32_t before = CUR.gen;
    const mc_cmdbuf_status_t st = tcmdbuf_take(&CB, &CUR);
    assert_int_not_equal(st, MC_CMDBUF_REFUSED);
    assert_true(cmd_ok(&CUR));              /* never torn                                */
    assert_int_equal(CUR.gen, W_PUB);       /* the newest published: old before the store,
                                               new from the store on, nothing in between  */
    assert_int_equal(st == MC_CMDBUF_TAKEN, CUR.gen != before);
    CMD_TAKES++;
}

static void cmd_reset(void)
{
    disarm();
    const tcmd_t c1 = cmd_make(1u);
    tcmdbuf_init(&CB, &c1, check_in_place, NULL);
    memset(&CUR, 0, sizeof CUR);
    W_GEN = 1u;
    W_PUB = 1u;
    W_SLOT = NULL;
    CMD_TAKES = 0u;
    assert_int_equal(tcmdbuf_take(&CB, &CUR), MC_CMDBUF_TAKEN);   /* the initial command */
    assert_int_equal(CUR.gen, 1u);
}

/* The background writes generations 2 .. n+1 back to back, alternately in place (begin, which
 * copies the newest command into the spare slot, then a byte-by-byte overwrite, then publish)
 * and by mc_cmdbuf_write (byte-by-byte copy in the test build). */
static void cmd_writes(uint32_t n)
{
    for (uint32_t g = 2u; g < n + 2u; ++g) {
        const tcmd_t c = cmd_make(g);
        W_GEN = g;
        W_SLOT = cmd_spare();
        if (g % 2u == 0u) {
            tcmd_t *s = tcmdbuf_begin(&CB);
            assert_ptr_equal(s, W_SLOT);
            assert_true(cmd_ok(s) && s->gen == g - 1u);   /* starts from the newest */
            fill_bytes(s, &c, sizeof c);
            tcmdbuf_publish(&CB);
        } else {
            tcmdbuf_write(&CB, &c);
        }
        assert_int_equal(W_PUB, g);
        assert_null(W_SLOT);
    }
}

static void cmd_final_take(uint32_t last)
{
    disarm();
    (void)tcmdbuf_take(&CB, &CUR);
    assert_int_equal(CUR.gen, last);   /* the final command is never missed */
    assert_true(cmd_ok(&CUR));
    assert_int_equal(mc_cmdbuf_refused(&CB.base), 0u);
}

/* The ISR runs at every step of six back-to-back writes. */
static void test_cmd_isr_at_every_step(void **st)
{
    (void)st;
    cmd_reset();
    arm(FIRE_EVERY, -1, -1, cmd_track, cmd_isr);
    cmd_writes(6u);
    /* 3 x (40 begin + 40 fill + 2) + 3 x (40 + 2) points */
    assert_int_equal(H.fired, 3 * 82 + 3 * 42);
    assert_int_equal(CMD_TAKES, (uint32_t)H.fired);
    cmd_final_take(7u);
}

/* The ISR runs once, at each single point in turn, of two quick writes (so also between the
 * two publishes), then once more after them; and at each pair of points. */
static void test_cmd_isr_at_each_point_and_pair(void **st)
{
    (void)st;
    cmd_reset();
    arm(FIRE_NEVER, -1, -1, cmd_track, cmd_isr);
    cmd_writes(2u);
    const long n = H.n;
    assert_int_equal(n, 82 + 42);
    for (long k = 0; k < n; ++k) {
        cmd_reset();
        arm(FIRE_AT, k, -1, cmd_track, cmd_isr);
        cmd_writes(2u);
        assert_int_equal(H.fired, 1);
        cmd_final_take(3u);
    }
    for (long k1 = 0; k1 < n; ++k1) {
        for (long k2 = k1 + 1; k2 < n; ++k2) {
            cmd_reset();
            arm(FIRE_AT, k1, k2, cmd_track, cmd_isr);
            cmd_writes(2u);
            assert_int_equal(H.fired, 2);
            cmd_final_take(3u);
        }
    }
}

/* The ISR at random points of many writes, at several rates. */
static void test_cmd_isr_random(void **st)
{
    (void)st;
    const uint32_t rates[] = {2u, 7u, 40u, 300u};
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; ++r) {
        cmd_reset();
        arm(FIRE_RANDOM, -1, -1, cmd_track, cmd_isr);
        H.rng = 12345u + (uint32_t)r;
        H.one_in = rates[r];
        cmd_writes(400u);
        assert_true(H.fired > 0);
        cmd_final_take(401u);
    }
}

/* toy validator: refuses non-finite numbers and generation 0; counts its calls */
static uint32_t check_finite(const void *cmd, void *ctx)
{
    const tcmd_t *c = cmd;
    int *calls = ctx;
    ++*calls;
    for (int i = 0; i < 8; ++i) {
        if (!isfinite(c->x[i])) {
            return REASON_NOT_FINITE;
        }
    }
    return c->gen == 0u ? (uint32_t)REASON_BAD_GEN : 0u;
}

static void test_cmd_validator_refuses_nan(void **st)
{
    (void)st;
    disarm();
    int calls = 0;
    tcmdbuf_t b;
    tcmd_t cur;
    memset(&cur, 0, sizeof cur);
    const tcmd_t c1 = cmd_make(1u);
    tcmdbuf_init(&b, &c1, check_finite, &calls);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_TAKEN);
    assert_int_equal(cur.gen, 1u);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_SAME);   /* nothing new: no call */
    assert_int_equal(calls, 1);

    tcmd_t bad = cmd_make(2u);
    bad.x[3] = NAN;
    tcmdbuf_write(&b, &bad);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_REFUSED);
    assert_int_equal(cur.gen, 1u);                               /* the previous one stays */
    assert_true(cmd_ok(&cur));
    assert_int_equal(mc_cmdbuf_refused(&b.base), 1u);
    assert_int_equal(mc_cmdbuf_last_reason(&b.base), REASON_NOT_FINITE);
    /* judged once per publish, not once per period */
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_SAME);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_SAME);
    assert_int_equal(mc_cmdbuf_refused(&b.base), 1u);
    assert_int_equal(calls, 2);

    bad = cmd_make(3u);
    bad.x[0] = -INFINITY;
    tcmdbuf_write(&b, &bad);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_REFUSED);
    bad = cmd_make(0u);   /* another reason */
    tcmdbuf_write(&b, &bad);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_REFUSED);
    assert_int_equal(mc_cmdbuf_refused(&b.base), 3u);
    assert_int_equal(mc_cmdbuf_last_reason(&b.base), REASON_BAD_GEN);
    assert_int_equal(cur.gen, 1u);

    const tcmd_t c5 = cmd_make(5u);
    tcmdbuf_write(&b, &c5);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_TAKEN);
    assert_int_equal(cur.gen, 5u);
    assert_int_equal(mc_cmdbuf_refused(&b.base), 3u);
    assert_int_equal(mc_cmdbuf_last_reason(&b.base), REASON_BAD_GEN);

    /* latest wins: a valid command overtaken by a refused one before the ISR came never runs */
    const tcmd_t c6 = cmd_make(6u);
    tcmdbuf_write(&b, &c6);
    bad = cmd_make(7u);
    bad.x[7] = NAN;
    tcmdbuf_write(&b, &bad);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_REFUSED);
    assert_int_equal(cur.gen, 5u);
    assert_int_equal(mc_cmdbuf_refused(&b.base), 4u);

    /* in place: begin starts from the newest published command (here the refused one) */
    tcmd_t *s = tcmdbuf_begin(&b);
    assert_memory_equal(s, tcmdbuf_latest(&b), sizeof *s);
    assert_true(isnan(s->x[7]));
    s->x[7] = cmd_make(7u).x[7];
    tcmdbuf_publish(&b);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_TAKEN);
    assert_int_equal(cur.gen, 7u);
    assert_true(cmd_ok(&cur));

    /* a refused initial command: the ISR's own command is not touched */
    bad = cmd_make(1u);
    bad.x[1] = NAN;
    tcmdbuf_init(&b, &bad, check_finite, &calls);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_REFUSED);
    assert_int_equal(cur.gen, 7u);
    assert_int_equal(mc_cmdbuf_refused(&b.base), 1u);

    /* the byte-blob API checks the size */
    assert_false(mc_cmdbuf_write(&b.base, &c5, sizeof c5 - 1u));
    assert_true(mc_cmdbuf_write(&b.base, &c5, sizeof c5));
    /* no validator: everything is taken */
    tcmdbuf_init(&b, NULL, NULL, NULL);
    assert_int_equal(tcmdbuf_take(&b, &cur), MC_CMDBUF_TAKEN);
    assert_int_equal(cur.gen, 0u);
}

/* ---- 2. telemetry ------------------------------------------------------------------------ */

typedef struct {
    uint32_t gen;
    float v[14];
    uint32_t check;
} tsnap_t;            /* 64 bytes */

MC_SNAPSHOT_TYPED(tsnapbuf, tsnap_t)

enum { MAX_TRIES = 8, SNAP_POINTS = 64 + 3 };   /* points per try: TRY, COPY, 64 bytes, CHECK */

static tsnap_t snap_make(uint32_t gen)
{
    tsnap_t t;
    memset(&t, 0, sizeof t);
    t.gen = gen;
    for (int i = 0; i < 14; ++i) {
        t.v[i] = (float)(gen * 32u + (uint32_t)i) - 0.5f;
    }
    t.check = fnv1a(&t, offsetof(tsnap_t, check));
    return t;
}

static bool snap_ok(const tsnap_t *t)
{
    const tsnap_t ref = snap_make(t->gen);
    return memcmp(&ref, t, sizeof ref) == 0;
}

static tsnapbuf_t SB;
static uint32_t ISR_GEN;                /* generation the ISR published last                  */
static int TRY;                         /* index of the reader's current try                  */
static int INTERF[MAX_TRIES];           /* ISR publishes between the try's two counter loads  */
static uint32_t GEN_AT_S1[MAX_TRIES];   /* newest generation when the try loaded s1          */

/* one control period: publish the next generation, alternately in place and by copy */
static void snap_isr(mc_handover_tp_t p)
{
    ++ISR_GEN;
    const tsnap_t t = snap_make(ISR_GEN);
    if (ISR_GEN % 2u == 0u) {
        tsnap_t *s = tsnapbuf_begin(&SB);
        *s = t;
        tsnapbuf_publish(&SB);
    } else {
        tsnapbuf_write(&SB, &t);
    }
    if (p != MC_HTP_SNAP_TRY && TRY >= 0) {   /* at TRY the ISR runs before s1 is loaded */
        INTERF[TRY]++;
    }
}

static void snap_track(mc_handover_tp_t p)
{
    if (p == MC_HTP_SNAP_TRY) {
        ++TRY;
        assert_true(TRY < MAX_TRIES);
        INTERF[TRY] = 0;
    } else if (p == MC_HTP_SNAP_COPY) {   /* s1 has just been loaded */
        GEN_AT_S1[TRY] = ISR_GEN;
    }
}

static void snap_reset(void)
{
    disarm();
    const tsnap_t t0 = snap_make(0u);
    tsnapbuf_init(&SB, &t0);
    ISR_GEN = 0u;
    TRY = -1;
}

/* one read; returns whether it succeeded, after checking everything it may and may not do */
static bool snap_read_checked(unsigned tries)
{
    tsnap_t d;
    uint32_t seq = 0xdeadbeefu;
    TRY = -1;
    const bool ok = tsnapbuf_read(&SB, &d, tries, &seq);
    const int used = TRY + 1;
    assert_true(used >= 1 && used <= (int)tries);
    for (int k = 0; k + 1 < used; ++k) {
        assert_true(INTERF[k] >= 2);   /* a retry only after two publishes during the copy */
    }
    if (ok) {
        assert_true(snap_ok(&d));                    /* never torn                          */
        assert_int_equal(d.gen, GEN_AT_S1[TRY]);      /* the newest at the start of the try  */
        assert_int_equal(seq, d.gen);                 /* seq = publishes = generation here   */
        assert_true(INTERF[TRY] <= 1);
    } else {
        assert_int_equal(used, (int)tries);           /* false only after every try ...     */
        assert_true(INTERF[TRY] >= 2);                /* ... was interfered with            */
    }
    TRY = -1;
    return ok;
}

static void test_snapshot_single_interference_anywhere(void **st)
{
    (void)st;
    /* any one publish during a read: the first try succeeds (it went to the other slot) */
    for (long k = 0; k < SNAP_POINTS; ++k) {
        snap_reset();
        snap_isr(MC_HTP_SNAP_TRY);   /* a few periods before the read */
        snap_isr(MC_HTP_SNAP_TRY);
        arm(FIRE_AT, k, -1, snap_track, snap_isr);
        assert_true(snap_read_checked(3u));
        assert_int_equal(H.n, SNAP_POINTS);
        assert_int_equal(H.fired, 1);
        disarm();
    }
}

static void test_snapshot_two_interferences_each_pair(void **st)
{
    (void)st;
    /* two publishes at any two points of the first try (the second try is left alone) */
    long retried = 0;
    for (long k1 = 0; k1 < SNAP_POINTS; ++k1) {
        for (long k2 = k1 + 1; k2 < SNAP_POINTS; ++k2) {
            snap_reset();
            arm(FIRE_AT, k1, k2, snap_track, snap_isr);
            assert_true(snap_read_checked(2u));
            retried += (H.n > SNAP_POINTS);
            /* a retry exactly when both publishes fell between the loads of s1 and s2 */
            assert_int_equal(H.n > SNAP_POINTS, k1 >= 1);
            disarm();
            /* with a single try, that case is a failure, and only that case */
            snap_reset();
            arm(FIRE_AT, k1, k2, snap_track, snap_isr);
            assert_int_equal(snap_read_checked(1u), k1 == 0);
            disarm();
        }
    }
    assert_true(retried > 0);
}

static void test_snapshot_isr_at_every_step(void **st)
{
    (void)st;
    snap_reset();
    arm(FIRE_EVERY, -1, -1, snap_track, snap_isr);
    assert_false(snap_read_checked(5u));   /* interfered with on every try: gives up */
    assert_int_equal(H.n, 5 * SNAP_POINTS);
    disarm();
    tsnap_t d;
    assert_true(tsnapbuf_read(&SB, &d, 1u, NULL));   /* quiet: succeeds at once */
    assert_true(snap_ok(&d));
    assert_int_equal(d.gen, ISR_GEN);
    assert_false(mc_snapshot_read(&SB.base, &d, sizeof d - 4u, 3u, NULL));   /* size check */
}

static void test_snapshot_random(void **st)
{
    (void)st;
    const uint32_t rates[] = {1u, 2u, 5u, 20u, 100u};
    int outcomes[2] = {0, 0};
    long retries = 0;
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; ++r) {
        snap_reset();
        arm(FIRE_RANDOM, -1, -1, snap_track, snap_isr);
        H.rng = 777u + (uint32_t)r;
        H.one_in = rates[r];
        for (int n = 0; n < 4000; ++n) {
            const long before = H.n;
            outcomes[snap_read_checked(4u)]++;
            retries += (H.n - before > SNAP_POINTS);
        }
        disarm();
    }
    assert_true(outcomes[0] > 0 && outcomes[1] > 0 && retries > 0);   /* all paths taken */
}

/* ---- 3. configuration ---------------------------------------------------------------------- */

typedef struct {
    uint32_t gen;
    uint32_t w[254];
    uint32_t check;
} tcfg_t;             /* 1 KB */

MC_CFGSWAP_TYPED(tcfgsw, tcfg_t)

static uint32_t cfg_word(uint32_t gen, uint32_t i)
{
    return gen * 2654435761u + i * 40503u;
}

static bool cfg_ok(const tcfg_t *c)
{
    for (uint32_t i = 0; i < 254u; ++i) {
        if (c->w[i] != cfg_word(c->gen, i)) {
            return false;
        }
    }
    return c->check == fnv1a(c, offsetof(tcfg_t, check));
}

static tcfg_t CFG_TMP;
static const tcfg_t *cfg_make(uint32_t gen)
{
    CFG_TMP.gen = gen;
    for (uint32_t i = 0; i < 254u; ++i) {
        CFG_TMP.w[i] = cfg_word(gen, i);
    }
    CFG_TMP.check = fnv1a(&CFG_TMP, offsetof(tcfg_t, check));
    return &CFG_TMP;
}

static tcfgsw_t CS;
static const tcfg_t *ISR_CFG;      /* the configuration the ISR used last              */
static uint32_t ISR_SWITCHES;
static const void *B_BUILD;        /* slot the background is writing (NULL: none)     */
static uint32_t B_GEN;             /* generation the background is building            */
static uint32_t B_COMMITTED;       /* generation whose committing store has executed   */

static void cfg_isr(mc_handover_tp_t p)
{
    (void)p;
    bool changed = true;
    const tcfg_t *c = tcfgsw_take(&CS, &changed);
    assert_ptr_not_equal(c, B_BUILD);              /* never the slot being built      */
    assert_true(cfg_ok(c));                        /* never half-built                */
    assert_int_equal(c->gen, B_COMMITTED);         /* switches at the first period after
                                                      the commit, not before          */
    assert_int_equal(changed, c != ISR_CFG);
    assert_ptr_equal(mc_cfgswap_active(&CS.base), c);
    ISR_SWITCHES += changed;
    ISR_CFG = c;
}

static void cfg_track(mc_handover_tp_t p)
{
    if (p == MC_HTP_CFG_BEGUN) {
        /* the background is about to write the spare slot: the ISR must be done with it */
        B_BUILD = &CS.slot[(atomic_load(&CS.base.req) + 1u) & 1u];
        assert_ptr_not_equal(B_BUILD, ISR_CFG);
        assert_false(mc_cfgswap_pending(&CS.base));
    } else if (p == MC_HTP_CFG_COMMITTED) {
        B_COMMITTED = B_GEN;
        B_BUILD = NULL;
    }
}

static void cfg_reset(void)
{
    disarm();
    tcfgsw_init(&CS, cfg_make(1u));
    ISR_CFG = mc_cfgswap_active(&CS.base);
    B_BUILD = NULL;
    B_GEN = 1u;
    B_COMMITTED = 1u;
    cfg_isr(MC_HTP_COPY_BYTE);   /* first period */
    ISR_SWITCHES = 0u;
}

/* The background derives generations 2 .. n+1, alternately in place (begin: byte-by-byte copy
 * of the newest; then poison, then a word-by-word build; commit) and by request (byte-by-byte
 * copy). While busy, it waits for a period, as a background loop would. */
static void cfg_builds(uint32_t n)
{
    for (uint32_t g = 2u; g < n + 2u; ++g) {
        B_GEN = g;
        if (g % 2u == 0u) {
            tcfg_t *s;
            while ((s = tcfgsw_begin(&CS)) == NULL) {
                assert_true(mc_cfgswap_pending(&CS.base));
                cfg_isr(MC_HTP_COPY_BYTE);   /* a period passes */
            }
            assert_ptr_equal(s, B_BUILD);
            assert_true(cfg_ok(s) && s->gen == g - 1u);   /* starts from the newest */
            for (size_t i = 0; i < sizeof *s; i += 16u) {  /* scribble: the old slot is free */
                memset((unsigned char *)s + i, 0xA5, 16u);
                step();
            }
            s->gen = g;
            step();
            for (uint32_t i = 0; i < 254u; ++i) {
                s->w[i] = cfg_word(g, i);
                step();
            }
            s->check = fnv1a(s, offsetof(tcfg_t, check));
            step();
            assert_true(tcfgsw_commit(&CS));
        } else {
            while (!tcfgsw_request(&CS, cfg_make(g))) {
                cfg_isr(MC_HTP_COPY_BYTE);
            }
        }
        assert_int_equal(B_COMMITTED, g);
        assert_null(B_BUILD);
        assert_int_equal(tcfgsw_latest(&CS)->gen, g);
    }
}

static void cfg_final_take(uint32_t last)
{
    disarm();
    cfg_isr(MC_HTP_COPY_BYTE);
    assert_int_equal(ISR_CFG->gen, last);
    assert_false(mc_cfgswap_pending(&CS.base));
}

static void test_cfg_isr_at_every_step(void **st)
{
    (void)st;
    cfg_reset();
    arm(FIRE_EVERY, -1, -1, cfg_track, cfg_isr);
    cfg_builds(4u);
    assert_int_equal(ISR_SWITCHES, 4u);
    assert_true(H.fired > 4 * 1024);
    cfg_final_take(5u);
}

static void test_cfg_isr_at_each_point(void **st)
{
    (void)st;
    cfg_reset();
    arm(FIRE_NEVER, -1, -1, cfg_track, cfg_isr);
    cfg_builds(2u);   /* (without any ISR the second build waits for one period) */
    const long n = H.n;
    assert_true(n > 2 * 1024);
    for (long k = 0; k < n; ++k) {
        cfg_reset();
        arm(FIRE_AT, k, -1, cfg_track, cfg_isr);
        cfg_builds(2u);
        cfg_final_take(3u);
    }
}

static void test_cfg_isr_random(void **st)
{
    (void)st;
    const uint32_t rates[] = {3u, 50u, 2000u};
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; ++r) {
        cfg_reset();
        arm(FIRE_RANDOM, -1, -1, cfg_track, cfg_isr);
        H.rng = 4242u + (uint32_t)r;
        H.one_in = rates[r];
        cfg_builds(30u);
        cfg_final_take(31u);
    }
}

/* A second request before the ISR took the first is refused; the pending one stays intact. */
static void test_cfg_busy_refused(void **st)
{
    (void)st;
    disarm();
    tcfgsw_t c;
    tcfgsw_init(&c, cfg_make(1u));
    bool changed = true;
    const tcfg_t *a1 = tcfgsw_take(&c, &changed);
    assert_false(changed);
    assert_int_equal(a1->gen, 1u);

    assert_true(tcfgsw_request(&c, cfg_make(2u)));
    assert_true(mc_cfgswap_pending(&c.base));
    assert_int_equal(tcfgsw_latest(&c)->gen, 2u);
    assert_ptr_not_equal(tcfgsw_latest(&c), a1);
    /* busy: every way of writing is refused, nothing changes */
    assert_false(tcfgsw_request(&c, cfg_make(3u)));
    assert_null(tcfgsw_begin(&c));
    assert_false(tcfgsw_commit(&c));   /* would make the active slot pending */
    assert_int_equal(tcfgsw_latest(&c)->gen, 2u);
    assert_true(cfg_ok(tcfgsw_latest(&c)));
    assert_ptr_equal(mc_cfgswap_active(&c.base), a1);   /* the ISR has not switched yet */
    assert_int_equal(a1->gen, 1u);

    const tcfg_t *a2 = tcfgsw_take(&c, &changed);   /* next period: switch + acknowledge */
    assert_true(changed);
    assert_int_equal(a2->gen, 2u);
    assert_false(mc_cfgswap_pending(&c.base));
    assert_ptr_equal(tcfgsw_take(&c, &changed), a2);
    assert_false(changed);
    assert_ptr_equal(tcfgsw_take(&c, NULL), a2);

    /* now the old slot is free again, and it is the one reused */
    tcfg_t *s = tcfgsw_begin(&c);
    assert_ptr_equal(s, a1);
    assert_memory_equal(s, a2, sizeof *s);   /* pre-filled with the newest */
    s->w[0] ^= 1u;                           /* a half-built one ...                        */
    assert_ptr_equal(tcfgsw_take(&c, &changed), a2);   /* ... is invisible to the ISR      */
    assert_false(changed);
    assert_true(tcfgsw_request(&c, cfg_make(3u)));     /* request overwrites the same slot */
    assert_int_equal(tcfgsw_take(&c, &changed)->gen, 3u);
    assert_true(changed);
    assert_false(mc_cfgswap_request(&c.base, cfg_make(4u), sizeof(tcfg_t) - 1u));   /* size */

    /* init with NULL: slot 0 was built in place by the caller */
    tcfgsw_t d;
    memcpy(&d.slot[0], cfg_make(9u), sizeof(tcfg_t));
    mc_cfgswap_init(&d.base, d.slot, sizeof(tcfg_t), NULL);
    assert_int_equal(tcfgsw_take(&d, NULL)->gen, 9u);
}

/* the typed and byte-blob interfaces sit on the same state */
static void test_typed_wrappers_and_barriers(void **st)
{
    (void)st;
    disarm();
    MC_DMB();
    MC_COMPILER_BARRIER();
    MC_HANDOVER_FENCE();
    tsnapbuf_t s;
    tsnapbuf_init(&s, NULL);
    tsnap_t d;
    uint32_t seq = 99u;
    assert_true(tsnapbuf_read(&s, &d, 0u, &seq));   /* 0 tries counts as 1 */
    assert_int_equal(seq, 0u);
    assert_int_equal(d.gen, 0u);
    const tsnap_t t = snap_make(4u);
    assert_true(mc_snapshot_write(&s.base, &t, sizeof t));
    assert_false(mc_snapshot_write(&s.base, &t, sizeof t + 1u));
    assert_true(mc_snapshot_read(&s.base, &d, sizeof d, 1u, &seq));
    assert_int_equal(seq, 1u);
    assert_memory_equal(&d, &t, sizeof t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cmd_isr_at_every_step),
        cmocka_unit_test(test_cmd_isr_at_each_point_and_pair),
        cmocka_unit_test(test_cmd_isr_random),
        cmocka_unit_test(test_cmd_validator_refuses_nan),
        cmocka_unit_test(test_snapshot_single_interference_anywhere),
        cmocka_unit_test(test_snapshot_two_interferences_each_pair),
        cmocka_unit_test(test_snapshot_isr_at_every_step),
        cmocka_unit_test(test_snapshot_random),
        cmocka_unit_test(test_cfg_isr_at_every_step),
        cmocka_unit_test(test_cfg_isr_at_each_point),
        cmocka_unit_test(test_cfg_isr_random),
        cmocka_unit_test(test_cfg_busy_refused),
        cmocka_unit_test(test_typed_wrappers_and_barriers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
