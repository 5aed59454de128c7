/* Hand-over of data between the background loop and the control ISR, on one core.
 *
 * Three primitives on caller-owned state (no heap; the slot storage is the caller's, its size
 * fixed at init):
 *
 *   mc_cmdbuf_t    commands       background -> ISR   two slots + publish counter; the ISR takes
 *                                                     the newest one through a validator
 *   mc_snapshot_t  telemetry      ISR -> background   two slots + publish counter ("latch");
 *                                                     the reader retries a bounded number of times
 *   mc_cfgswap_t   configuration  background -> ISR   two slots; request / acknowledge; the
 *                                                     background reuses a slot only after the ack
 *
 * EXECUTION MODEL (everything below rests on it)
 *   One core, two contexts: the background loop "B" and the control ISR "I". I preempts B at any
 *   instruction; B never preempts I. So every I-side call is one indivisible step as seen from B,
 *   while a B-side call may be cut by any number of complete I-side calls anywhere.
 *   Every shared word has exactly one writer (B or I), so nothing needs a read-modify-write
 *   (no LDREX/STREX, no interrupt masking); the shared words are C11 _Atomic uint32_t accessed
 *   relaxed, i.e. one aligned LDR / STR each on ARM, no libatomic.
 *   Exactly one background context may use the B-side calls of an object (if, say, a CAN
 *   interrupt and the main loop both produce commands, serialise them), and one ISR the I-side
 *   calls. Initialise an object before the ISR is enabled; do not copy it afterwards (it points
 *   into its slot storage).
 *   NOT for two cores or a DMA master as the other party: the proofs below use the fact that the
 *   ISR cannot be observed half-way (see mc_snapshot_read for the one place where it matters).
 *
 * BARRIERS: WHICH ONE IS NEEDED AND WHY
 *   Needed: a compiler barrier at each publication point, so that the compiler does not sink a
 *   payload store below the store that publishes it (B side), nor move payload loads across the
 *   loads that check the counter (telemetry reader). C11 names exactly this case: an ISR on the
 *   same core is what atomic_signal_fence() orders against ("a signal handler executed in the same
 *   thread"); it emits no instruction.
 *   Not needed: a hardware barrier (DMB). A Cortex-M4 or Cortex-R5 core observes its own loads
 *   and stores in program order (its write buffer / store buffer forwards to its own later loads,
 *   and exception entry does not change that), so the ISR sees what the interrupted code stored
 *   in program order, and vice versa. A DMB only orders accesses for ANOTHER observer: a second
 *   core, a DMA master, a debugger reading RAM.
 *   Used: MC_HANDOVER_FENCE(), by default MC_DMB(), at the B-side points only (command publish,
 *   configuration commit and the busy check before a slot is reused, the two counter loads of
 *   the telemetry reader). There it costs a few cycles of
 *   background time (M4: ~1-4, R5: drains the store buffer) and keeps a published slot valid for
 *   such another observer too (a debugger's live watch, a DMA copy of the config). The I side
 *   uses MC_COMPILER_BARRIER() only: 0 instructions. Define MC_HANDOVER_FENCE to
 *   MC_COMPILER_BARRIER (e.g. -DMC_HANDOVER_FENCE=MC_COMPILER_BARRIER) to drop the DMBs.
 *
 * COST IN THE ISR (I-side calls; Cortex-M4, size-independent unless stated)
 *   mc_cmdbuf_take     nothing new: 2 loads + compare. New: + validator call + memcpy(size)
 *                      (+ 2 loads / 2 stores when refused).
 *   mc_snapshot_begin  1 load + address computation; fill the slot in place (no extra copy).
 *   mc_snapshot_publish 1 load + 1 store.
 *   mc_cfgswap_take    2 loads + compare (+ 1 store on a swap); returns a pointer, no copy.
 *
 * Test builds (MC_HANDOVER_TESTING) copy byte by byte on the B side and call a hook at every step
 * (mc_handover_test_hook) so that a test can run the ISR side between any two steps. */
#ifndef MC_HANDOVER_H
#define MC_HANDOVER_H
#ifdef __cplusplus
/* A C++ host (the simulator) only allocates these structs for the C firmware, never touches the
 * shared words: plain uint32_t has the size and alignment of _Atomic uint32_t (checked in
 * handover.c), and C++17 has no _Atomic. */
#define MC_ATOMIC_U32 uint32_t
#else
#include <stdatomic.h>
#define MC_ATOMIC_U32 _Atomic uint32_t
#endif
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* ---- barriers --------------------------------------------------------------------------- */

#ifndef __cplusplus
/* Hardware data memory barrier (plus compiler barrier). */
#if defined(__ARM_ARCH)
#define MC_DMB() __asm__ volatile("dmb" ::: "memory")
#else
#define MC_DMB() atomic_thread_fence(memory_order_seq_cst)
#endif
/* Compiler-only barrier: orders against an ISR on the same core; no instruction. */
#define MC_COMPILER_BARRIER() atomic_signal_fence(memory_order_seq_cst)
/* The barrier at the background-side publication points (see above). */
#ifndef MC_HANDOVER_FENCE
#define MC_HANDOVER_FENCE() MC_DMB()
#endif
#endif

/* ---- 1. command double buffer: background writes, ISR takes --------------------------------
 *
 * State: slot[2] (caller's storage, `size` bytes each) and seq, the number of publishes. The
 * newest published command is slot[seq & 1]; the spare slot is slot[(seq + 1) & 1].
 *   B, write:  fill slot[(seq+1) & 1] (in place after mc_cmdbuf_begin, or by mc_cmdbuf_write);
 *              MC_HANDOVER_FENCE(); seq = seq + 1 (one 32-bit store: the publication).
 *   I, take:   s = seq; if s == seen: nothing new. Else seen = s; check(slot[s & 1]); if accepted,
 *              copy slot[s & 1] into the caller's current command, else keep it and count.
 * Invariant: B writes only slot[(seq+1) & 1], I reads only slot[seq & 1], and seq changes only by
 * B's single store after B finished writing. Hence the slot I reads is never the one B is
 * writing, at any instant - also when B publishes twice in a row: after publishing A into slot 1
 * (seq 1) B writes B into slot 0 while I reads slot 1; once B is published (seq 2) B's next write
 * goes to slot 1 while I reads slot 0. Two slots suffice because I's read (validate + copy) runs
 * whole inside the ISR, which B cannot interrupt; I copies out, so B may overwrite the slot
 * right after.
 * Latest wins: if B publishes several commands between two takes, I sees only the last one (a
 * mailbox, not a queue). After the final publish, the next take delivers it.
 * Validation: the validator runs in the ISR on the published slot (stable while the ISR runs).
 * It returns 0 to accept, else a caller-defined reason code: the command is not taken, the
 * caller's current command stays as it was, `refused` is incremented and `last_reason` set,
 * once per published command (not once per period). Keep the validator short (it is ISR time).
 * A refused command is not retried; the next publish replaces it. */

/* 0 = accept; anything else = refuse with this reason code. Called in the ISR. */
typedef uint32_t (*mc_cmdbuf_check_fn)(const void *cmd, void *ctx);

typedef enum {
    MC_CMDBUF_SAME = 0,   /* nothing new published since the last take: `cur` unchanged   */
    MC_CMDBUF_TAKEN,      /* a new command was accepted and copied into `cur`              */
    MC_CMDBUF_REFUSED     /* a new command was refused by the validator: `cur` unchanged   */
} mc_cmdbuf_status_t;

typedef struct {
    MC_ATOMIC_U32 seq;             /* B writes: publishes so far; newest in slot seq & 1      */
    MC_ATOMIC_U32 refused;      /* I writes: commands refused by the validator             */
    MC_ATOMIC_U32 last_reason;  /* I writes: reason code of the last refusal (0: none yet) */
    uint32_t seen;                 /* I private: seq at the last take                         */
    unsigned char *slots;          /* 2 * size bytes, caller's                                */
    size_t size;
    mc_cmdbuf_check_fn check;      /* may be NULL: everything accepted                        */
    void *check_ctx;
} mc_cmdbuf_t;

/* Setup, before the ISR runs. `slots`: storage for two commands (e.g. `T slots[2]`), `size` =
 * sizeof(T). Both slots get `initial` (zeros if NULL); the first take after init delivers it
 * (through the validator) as a new command. */
void mc_cmdbuf_init(mc_cmdbuf_t *b, void *slots, size_t size, const void *initial,
                    mc_cmdbuf_check_fn check, void *check_ctx);
/* B: the spare slot, pre-filled with the newest published command, to edit in place and then
 * publish with mc_cmdbuf_publish. Nothing is visible to the ISR before the publish. */
void *mc_cmdbuf_begin(mc_cmdbuf_t *b);
/* B: publish the spare slot (after mc_cmdbuf_begin). */
void mc_cmdbuf_publish(mc_cmdbuf_t *b);
/* B: copy `cmd` into the spare slot and publish it. false (nothing done) if size != b->size. */
bool mc_cmdbuf_write(mc_cmdbuf_t *b, const void *cmd, size_t size);
/* B: the newest published command; valid until the next begin / write. */
const void *mc_cmdbuf_latest(const mc_cmdbuf_t *b);
/* B or I: refusals so far, and the reason of the last one (two separate reads). */
uint32_t mc_cmdbuf_refused(const mc_cmdbuf_t *b);
uint32_t mc_cmdbuf_last_reason(const mc_cmdbuf_t *b);
/* I, at the start of a period: if a new command was published, validate it and, if accepted,
 * copy it into `cur` (the ISR's own command in force, size bytes). */
mc_cmdbuf_status_t mc_cmdbuf_take(mc_cmdbuf_t *b, void *cur);

/* ---- 2. telemetry snapshot: ISR writes once per period, background reads ------------------
 *
 * A seqlock over two slots (a "latch"): seq = number of publishes, newest in slot[seq & 1].
 *   I, publish: fill slot[(seq+1) & 1]; seq = seq + 1.
 *   B, read:    s1 = seq; fence; copy slot[s1 & 1]; fence; s2 = seq;
 *               consistent iff s2 - s1 <= 1, else retry (at most `tries` times, then false).
 * Why s2 - s1 <= 1: the first publish after s1 writes the OTHER slot; only a second one writes
 * slot[s1 & 1] again. An ISR publish is indivisible as seen from B, so a slot is never caught
 * half-written without the counter showing it. (With a concurrent writer on another core this
 * would not hold: there the condition would have to be s2 == s1.)
 * Why this and not a one-slot seqlock or a plain double buffer: same ISR cost (the ISR writes the
 * payload into a slot and stores the counter once; no odd "writing" state is needed because B
 * can never observe the ISR half-way), but a read fails only when the ISR published TWICE during
 * one copy, i.e. when B was held off for a full period in the middle of a copy of ~100 bytes -
 * not merely when one period boundary fell into it. A plain double buffer the ISR flips cannot
 * detect that case at all. The reader may still return false, after `tries` interfered copies;
 * then `dst` is garbage and must be ignored.
 * The returned snapshot is the newest one at the start of the successful try (at most one
 * period old when the call returns). The torn copies that are discarded are, formally, a data
 * race in the C11 model, as in every seqlock; their bytes are never used. */

typedef struct {
    MC_ATOMIC_U32 seq;             /* I writes: publishes so far; newest in slot seq & 1      */
    unsigned char *slots;          /* 2 * size bytes, caller's                                */
    size_t size;
} mc_snapshot_t;

/* Setup, before the ISR runs. Both slots get `initial` (zeros if NULL). */
void mc_snapshot_init(mc_snapshot_t *s, void *slots, size_t size, const void *initial);
/* I: the slot to fill this period, in place. It holds the snapshot of two publishes ago:
 * write every field. */
void *mc_snapshot_begin(mc_snapshot_t *s);
/* I: publish the slot filled after mc_snapshot_begin. */
void mc_snapshot_publish(mc_snapshot_t *s);
/* I: copy `src` into the spare slot and publish it. false if size != s->size. */
bool mc_snapshot_write(mc_snapshot_t *s, const void *src, size_t size);
/* B: copy a consistent snapshot into dst (size bytes). Tries at most `tries` times (0 counts as
 * 1); false if each try was interfered with (two publishes during the copy) or on a size
 * mismatch. `seq_out` (may be NULL) gets the snapshot's publish count (a period counter). */
bool mc_snapshot_read(const mc_snapshot_t *s, void *dst, size_t size, unsigned tries,
                      uint32_t *seq_out);

/* ---- 3. configuration swap: background builds, ISR switches at a period boundary ----------
 *
 * State: slot[2] (caller's storage), req (B: commits so far), ack (I: commits taken). The ISR
 * uses slot[ack & 1]; a commit is pending while req != ack (then req == ack + 1 and the pending
 * configuration is slot[req & 1]).
 *   B, begin:  if req != ack: busy, NULL. Else the spare slot[(ack+1) & 1] is free: copy the
 *              active configuration into it and return it; B builds / derives in place, as
 *              slowly as it likes (the ISR never looks at it).
 *   B, commit: MC_HANDOVER_FENCE(); req = req + 1 (one store): the slot is pending.
 *   I, take:   at the start of each period: r = req; if r != ack: ack = r (the switch and its
 *              acknowledgement in one store). Returns slot[ack & 1].
 * Invariants: (1) the ISR only ever points at a slot B has finished: it switches to slot[req & 1]
 * only after the store of req, which follows the whole build. (2) B writes a slot only when
 * req == ack, i.e. only the slot that is neither active nor pending; the ISR stopped using it
 * when it stored ack - RULE for the ISR: get the pointer from mc_cfgswap_take (or _active) every
 * period and do not keep it across periods. As B runs only between ISR runs, every ISR run after
 * the acknowledging one already uses the new slot, so when B sees ack == req the old slot is
 * free.
 * Busy: a second commit before the ISR took the first is REFUSED (begin returns NULL, request
 * returns false; retry on a later pass of the background loop, at most one period later).
 * Replacing the pending configuration instead would need B to withdraw it atomically against
 * a concurrent take, i.e. a read-modify-write on a word the ISR also writes (LDREX/STREX, whose
 * exclusive monitor an ARMv7-R ISR does not clear by itself, or masking interrupts); refusing
 * keeps every shared word single-writer. The configuration is never derived in the ISR. */

typedef struct {
    MC_ATOMIC_U32 req;          /* B writes: commits so far; newest in slot req & 1        */
    MC_ATOMIC_U32 ack;          /* I writes: commits taken; active slot ack & 1            */
    unsigned char *slots;          /* 2 * size bytes, caller's                                */
    size_t size;
} mc_cfgswap_t;

/* Setup, before the ISR runs. Slot 0 becomes the active configuration: a copy of `initial`, or,
 * if `initial` is NULL, whatever the caller already built in slot 0. */
void mc_cfgswap_init(mc_cfgswap_t *c, void *slots, size_t size, const void *initial);
/* B: the spare slot, pre-filled with the newest configuration, to build into; NULL while a
 * commit is pending (busy). Nothing is visible to the ISR before mc_cfgswap_commit. */
void *mc_cfgswap_begin(mc_cfgswap_t *c);
/* B: make the slot of the last successful begin pending; the ISR switches to it at its next
 * take. false (nothing done) while a commit is pending. */
bool mc_cfgswap_commit(mc_cfgswap_t *c);
/* B: begin + copy `cfg` + commit. false if busy or size != c->size. */
bool mc_cfgswap_request(mc_cfgswap_t *c, const void *cfg, size_t size);
/* B: a commit is waiting for the ISR. */
bool mc_cfgswap_pending(const mc_cfgswap_t *c);
/* B: the newest committed configuration (pending or active); valid until the next begin. */
const void *mc_cfgswap_latest(const mc_cfgswap_t *c);
/* I, at the start of each period: switch to a pending configuration (and acknowledge it);
 * returns the active one, valid for this period. `changed` (may be NULL): switched just now. */
const void *mc_cfgswap_take(mc_cfgswap_t *c, bool *changed);
/* I: the active configuration without switching. */
const void *mc_cfgswap_active(const mc_cfgswap_t *c);

/* ---- typed wrappers ------------------------------------------------------------------------
 * MC_CMDBUF_TYPED(name, T) declares name_t (the buffer with its two slots of T) and name_init,
 * name_begin, name_publish, name_write, name_latest, name_take with T in their signatures; the
 * same for MC_SNAPSHOT_TYPED and MC_CFGSWAP_TYPED. Use at file scope, e.g.
 *     MC_CMDBUF_TYPED(mc_drive_cmdbuf, mc_drive_cmd_t)
 */
#define MC_CMDBUF_TYPED(name, T)                                                             \
    typedef struct {                                                                         \
        mc_cmdbuf_t base;                                                                    \
        T slot[2];                                                                           \
    } name##_t;                                                                              \
    static inline void name##_init(name##_t *x, const T *initial, mc_cmdbuf_check_fn check,  \
                                   void *ctx)                                                \
    {                                                                                        \
        mc_cmdbuf_init(&x->base, x->slot, sizeof(T), initial, check, ctx);                   \
    }                                                                                        \
    static inline T *name##_begin(name##_t *x) { return (T *)mc_cmdbuf_begin(&x->base); }    \
    static inline void name##_publish(name##_t *x) { mc_cmdbuf_publish(&x->base); }          \
    static inline void name##_write(name##_t *x, const T *cmd)                               \
    {                                                                                        \
        (void)mc_cmdbuf_write(&x->base, cmd, sizeof(T));                                     \
    }                                                                                        \
    static inline const T *name##_latest(const name##_t *x)                                  \
    {                                                                                        \
        return (const T *)mc_cmdbuf_latest(&x->base);                                        \
    }                                                                                        \
    static inline mc_cmdbuf_status_t name##_take(name##_t *x, T *cur)                        \
    {                                                                                        \
        return mc_cmdbuf_take(&x->base, cur);                                                \
    }

#define MC_SNAPSHOT_TYPED(name, T)                                                           \
    typedef struct {                                                                         \
        mc_snapshot_t base;                                                                  \
        T slot[2];                                                                           \
    } name##_t;                                                                              \
    static inline void name##_init(name##_t *x, const T *initial)                            \
    {                                                                                        \
        mc_snapshot_init(&x->base, x->slot, sizeof(T), initial);                             \
    }                                                                                        \
    static inline T *name##_begin(name##_t *x) { return (T *)mc_snapshot_begin(&x->base); }  \
    static inline void name##_publish(name##_t *x) { mc_snapshot_publish(&x->base); }        \
    static inline void name##_write(name##_t *x, const T *src)                               \
    {                                                                                        \
        (void)mc_snapshot_write(&x->base, src, sizeof(T));                                   \
    }                                                                                        \
    static inline bool name##_read(const name##_t *x, T *dst, unsigned tries, uint32_t *seq) \
    {                                                                                        \
        return mc_snapshot_read(&x->base, dst, sizeof(T), tries, seq);                       \
    }

#define MC_CFGSWAP_TYPED(name, T)                                                            \
    typedef struct {                                                                         \
        mc_cfgswap_t base;                                                                   \
        T slot[2];                                                                           \
    } name##_t;                                                                              \
    static inline void name##_init(name##_t *x, const T *initial)                            \
    {                                                                                        \
        mc_cfgswap_init(&x->base, x->slot, sizeof(T), initial);                              \
    }                                                                                        \
    static inline T *name##_begin(name##_t *x) { return (T *)mc_cfgswap_begin(&x->base); }   \
    static inline bool name##_commit(name##_t *x) { return mc_cfgswap_commit(&x->base); }    \
    static inline bool name##_request(name##_t *x, const T *cfg)                             \
    {                                                                                        \
        return mc_cfgswap_request(&x->base, cfg, sizeof(T));                                 \
    }                                                                                        \
    static inline const T *name##_latest(const name##_t *x)                                  \
    {                                                                                        \
        return (const T *)mc_cfgswap_latest(&x->base);                                       \
    }                                                                                        \
    static inline const T *name##_take(name##_t *x, bool *changed)                           \
    {                                                                                        \
        return (const T *)mc_cfgswap_take(&x->base, changed);                                \
    }

/* ---- test hook (test builds only) ---------------------------------------------------------- */
#if defined(MC_HANDOVER_TESTING)
typedef enum {
    MC_HTP_COPY_BYTE = 0,      /* after each byte of a B-side copy                          */
    MC_HTP_CMD_PUBLISH,        /* B: payload written, before the fence and the publishing store */
    MC_HTP_CMD_PUBLISHED,      /* B: after the publishing store                             */
    MC_HTP_SNAP_TRY,           /* B: start of a read try, before s1 is loaded               */
    MC_HTP_SNAP_COPY,          /* B: s1 loaded, before the copy                             */
    MC_HTP_SNAP_CHECK,         /* B: copy done, before s2 is loaded                         */
    MC_HTP_CFG_CHECK,          /* B: begin/commit, req loaded, before ack is loaded         */
    MC_HTP_CFG_BEGUN,          /* B: begin, busy check passed, before the copy              */
    MC_HTP_CFG_COMMIT,         /* B: commit, before the fence and the committing store      */
    MC_HTP_CFG_COMMITTED       /* B: after the committing store                             */
} mc_handover_tp_t;
/* Called at every test point of the B-side calls; NULL: nothing. Never called by I-side calls. */
extern void (*mc_handover_test_hook)(mc_handover_tp_t point);
#endif

#endif
