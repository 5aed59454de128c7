/* Hand-over between the background loop and the control ISR: protocols and invariants are in
 * mc/handover.h. B-side calls are marked with test points; I-side calls have none (the ISR is
 * indivisible as seen from the background, which is what the tests run at the test points). */
#include "mc/handover.h"

_Static_assert(sizeof(MC_ATOMIC_U32) == sizeof(uint32_t) && _Alignof(MC_ATOMIC_U32) == _Alignof(uint32_t),
               "the C++ view of the shared words (plain uint32_t) must match");
#include <string.h>

#if defined(MC_HANDOVER_TESTING)
void (*mc_handover_test_hook)(mc_handover_tp_t point);
#define MC_HANDOVER_TEST_POINT(p)                                                            \
    do {                                                                                     \
        if (mc_handover_test_hook != NULL) {                                                 \
            mc_handover_test_hook(p);                                                        \
        }                                                                                    \
    } while (0)
#else
#define MC_HANDOVER_TEST_POINT(p) ((void)0)
#endif

/* The shared words: relaxed single-copy-atomic accesses, one LDR / STR on ARM (macros: gcc -Os
 * would otherwise keep them as calls). The ordering comes from the fences at the call sites. */
#define load(a)     atomic_load_explicit((a), memory_order_relaxed)
#define store(a, v) atomic_store_explicit((a), (v), memory_order_relaxed)

/* slot i & 1 of a two-slot storage */
static inline unsigned char *slot_at(unsigned char *slots, size_t size, uint32_t i)
{
    return slots + (size_t)(i & 1u) * size;
}

/* B-side copy. Test builds go byte by byte with a test point after each byte, so that a test can
 * run the ISR between any two bytes; the result is the same as memcpy's. */
static void b_copy(void *dst, const void *src, size_t n)
{
#if defined(MC_HANDOVER_TESTING)
    unsigned char *d = dst;
    const unsigned char *s = src;
    for (size_t i = 0; i < n; ++i) {
        d[i] = s[i];
        MC_HANDOVER_TEST_POINT(MC_HTP_COPY_BYTE);
    }
#else
    memcpy(dst, src, n);
#endif
}

static void fill_slots(unsigned char *slots, size_t size, const void *initial)
{
    if (initial != NULL) {
        memcpy(slots, initial, size);
        memcpy(slots + size, initial, size);
    } else {
        memset(slots, 0, 2u * size);
    }
}

/* ---- 1. command double buffer ----------------------------------------------------------- */

void mc_cmdbuf_init(mc_cmdbuf_t *b, void *slots, size_t size, const void *initial,
                    mc_cmdbuf_check_fn check, void *check_ctx)
{
    b->slots = slots;
    b->size = size;
    b->check = check;
    b->check_ctx = check_ctx;
    fill_slots(b->slots, size, initial);
    atomic_init(&b->seq, 0u);
    atomic_init(&b->refused, 0u);
    atomic_init(&b->last_reason, 0u);
    b->seen = UINT32_MAX;   /* != seq: the first take delivers the initial command */
}

void *mc_cmdbuf_begin(mc_cmdbuf_t *b)
{
    const uint32_t s = load(&b->seq);   /* B's own word: no concurrent change */
    unsigned char *spare = slot_at(b->slots, b->size, s + 1u);
    /* slot[s & 1] is only read by the ISR, and written by B alone: a stable source */
    b_copy(spare, slot_at(b->slots, b->size, s), b->size);
    return spare;
}

void mc_cmdbuf_publish(mc_cmdbuf_t *b)
{
    const uint32_t s = load(&b->seq);
    MC_HANDOVER_TEST_POINT(MC_HTP_CMD_PUBLISH);
    MC_HANDOVER_FENCE();                 /* every payload store before the publishing store */
    store(&b->seq, s + 1u);
    MC_HANDOVER_TEST_POINT(MC_HTP_CMD_PUBLISHED);
}

bool mc_cmdbuf_write(mc_cmdbuf_t *b, const void *cmd, size_t size)
{
    if (size != b->size) {
        return false;
    }
    const uint32_t s = load(&b->seq);
    b_copy(slot_at(b->slots, b->size, s + 1u), cmd, size);
    mc_cmdbuf_publish(b);
    return true;
}

const void *mc_cmdbuf_latest(const mc_cmdbuf_t *b)
{
    return slot_at(b->slots, b->size, load(&b->seq));
}

uint32_t mc_cmdbuf_refused(const mc_cmdbuf_t *b)
{
    return load(&b->refused);
}

uint32_t mc_cmdbuf_last_reason(const mc_cmdbuf_t *b)
{
    return load(&b->last_reason);
}

mc_cmdbuf_status_t mc_cmdbuf_take(mc_cmdbuf_t *b, void *cur)
{
    const uint32_t s = load(&b->seq);
    if (s == b->seen) {
        return MC_CMDBUF_SAME;
    }
    b->seen = s;   /* judged once per publish, whatever the verdict */
    /* B writes only slot[(s + 1) & 1] and cannot run before this ISR returns: stable */
    const unsigned char *p = slot_at(b->slots, b->size, s);
    if (b->check != NULL) {
        const uint32_t why = b->check(p, b->check_ctx);
        if (why != 0u) {
            store(&b->refused, load(&b->refused) + 1u);   /* I is the only writer */
            store(&b->last_reason, why);
            return MC_CMDBUF_REFUSED;
        }
    }
    memcpy(cur, p, b->size);
    return MC_CMDBUF_TAKEN;
}

/* ---- 2. telemetry snapshot ---------------------------------------------------------------- */

void mc_snapshot_init(mc_snapshot_t *s, void *slots, size_t size, const void *initial)
{
    s->slots = slots;
    s->size = size;
    fill_slots(s->slots, size, initial);
    atomic_init(&s->seq, 0u);
}

void *mc_snapshot_begin(mc_snapshot_t *s)
{
    return slot_at(s->slots, s->size, load(&s->seq) + 1u);
}

void mc_snapshot_publish(mc_snapshot_t *s)
{
    const uint32_t q = load(&s->seq);
    MC_COMPILER_BARRIER();   /* the ISR is indivisible for the reader: no DMB needed */
    store(&s->seq, q + 1u);
}

bool mc_snapshot_write(mc_snapshot_t *s, const void *src, size_t size)
{
    if (size != s->size) {
        return false;
    }
    memcpy(mc_snapshot_begin(s), src, size);
    mc_snapshot_publish(s);
    return true;
}

bool mc_snapshot_read(const mc_snapshot_t *s, void *dst, size_t size, unsigned tries,
                      uint32_t *seq_out)
{
    if (size != s->size) {
        return false;
    }
    if (tries == 0u) {
        tries = 1u;
    }
    for (unsigned k = 0; k < tries; ++k) {
        MC_HANDOVER_TEST_POINT(MC_HTP_SNAP_TRY);
        const uint32_t s1 = load(&s->seq);
        MC_HANDOVER_FENCE();             /* the copy after the load of s1 */
        MC_HANDOVER_TEST_POINT(MC_HTP_SNAP_COPY);
        b_copy(dst, slot_at(s->slots, s->size, s1), size);
        MC_HANDOVER_FENCE();             /* the copy before the load of s2 */
        MC_HANDOVER_TEST_POINT(MC_HTP_SNAP_CHECK);
        const uint32_t s2 = load(&s->seq);
        if (s2 - s1 <= 1u) {             /* at most one publish: it went to the other slot */
            if (seq_out != NULL) {
                *seq_out = s1;
            }
            return true;
        }
    }
    return false;
}

/* ---- 3. configuration swap ---------------------------------------------------------------- */

void mc_cfgswap_init(mc_cfgswap_t *c, void *slots, size_t size, const void *initial)
{
    c->slots = slots;
    c->size = size;
    if (initial != NULL) {
        memcpy(c->slots, initial, size);
    }
    atomic_init(&c->req, 0u);
    atomic_init(&c->ack, 0u);
}

/* B: req == ack, i.e. nothing pending (req is B's own word, ack the ISR's) */
static bool cfg_idle(const mc_cfgswap_t *c, uint32_t *req)
{
    *req = load(&c->req);
    MC_HANDOVER_TEST_POINT(MC_HTP_CFG_CHECK);
    return load(&c->ack) == *req;
}

void *mc_cfgswap_begin(mc_cfgswap_t *c)
{
    uint32_t r;
    if (!cfg_idle(c, &r)) {
        return NULL;   /* busy: the ISR may switch to slot[r & 1] at any instant */
    }
    MC_HANDOVER_FENCE();   /* no access to the old slot before the ack has been seen */
    MC_HANDOVER_TEST_POINT(MC_HTP_CFG_BEGUN);
    /* idle: the ISR uses slot[r & 1] and switches only after B's next commit */
    unsigned char *spare = slot_at(c->slots, c->size, r + 1u);
    b_copy(spare, slot_at(c->slots, c->size, r), c->size);
    return spare;
}

bool mc_cfgswap_commit(mc_cfgswap_t *c)
{
    uint32_t r;
    if (!cfg_idle(c, &r)) {
        return false;   /* a commit now would make the ACTIVE slot pending */
    }
    MC_HANDOVER_TEST_POINT(MC_HTP_CFG_COMMIT);
    MC_HANDOVER_FENCE();   /* the whole build before the committing store */
    store(&c->req, r + 1u);
    MC_HANDOVER_TEST_POINT(MC_HTP_CFG_COMMITTED);
    return true;
}

bool mc_cfgswap_request(mc_cfgswap_t *c, const void *cfg, size_t size)
{
    if (size != c->size) {
        return false;
    }
    uint32_t r;
    if (!cfg_idle(c, &r)) {
        return false;
    }
    MC_HANDOVER_FENCE();
    MC_HANDOVER_TEST_POINT(MC_HTP_CFG_BEGUN);
    b_copy(slot_at(c->slots, c->size, r + 1u), cfg, size);
    return mc_cfgswap_commit(c);   /* cannot be busy: only B's commit makes it so */
}

bool mc_cfgswap_pending(const mc_cfgswap_t *c)
{
    return load(&c->req) != load(&c->ack);
}

const void *mc_cfgswap_latest(const mc_cfgswap_t *c)
{
    return slot_at(c->slots, c->size, load(&c->req));
}

const void *mc_cfgswap_take(mc_cfgswap_t *c, bool *changed)
{
    const uint32_t r = load(&c->req);
    uint32_t a = load(&c->ack);   /* the ISR's own word */
    const bool sw = (r != a);
    if (sw) {
        a = r;
        store(&c->ack, a);        /* switch + acknowledge: B may now reuse the old slot */
    }
    if (changed != NULL) {
        *changed = sw;
    }
    return slot_at(c->slots, c->size, a);
}

const void *mc_cfgswap_active(const mc_cfgswap_t *c)
{
    return slot_at(c->slots, c->size, load(&c->ack));
}
