/* Startup sequencer: IDLE -> OFFSET_CAL -> INIT_POS (Step I, II, III) -> RUN, and FAULT with a
 * reason. A pure state machine (no HAL, no estimator): the drive reports events and calls
 * mc_seq_tick() once per period; every state that waits for something has a timeout. */
#ifndef MC_SEQUENCER_H
#define MC_SEQUENCER_H
#include "mc/faults.h"
#include "mc/types.h"

typedef enum {
    MC_STATE_IDLE = 0,      /* outputs off, waiting for enable                                */
    MC_STATE_OFFSET_CAL,    /* outputs off, averaging the current-channel offsets              */
    MC_STATE_RUN,           /* closed-loop control                                             */
    MC_STATE_FAULT,         /* outputs off until disable + enable                              */
    MC_STATE_INIT_POS,      /* initial position: Step I, II (pulses), III (continuous injection) */
    MC_STATE_FAULT_REACTION /* a fault is latched, the outputs stay on for its reaction (CiA 402
                               "fault reaction active"): over-speed above the uncontrolled-
                               generation speed keeps field weakening up with zero torque until
                               the speed is safe; then FAULT */
} mc_state_t;

/* CATCH (the flying-start catch, mc/catch.h) runs first when configured: a turning rotor goes
 * from it straight to RUN, a standing one on to Step I (or RUN with the given angle). */
typedef enum { MC_INIT_NONE = 0, MC_INIT_STEP1, MC_INIT_STEP2, MC_INIT_STEP3, MC_INIT_CATCH } mc_init_step_t;

/* Fault reasons: the MC_FAULT_* bit masks of mc/faults.h (latched until the next enable). */

typedef struct {
    float ts;               /* [s] */
    bool  init_pos;         /* run Steps I-III after the calibration (else straight to RUN)  */
    bool  catch_first;      /* the catch before them (INIT_POS with step CATCH)              */
    float timeout_catch;    /* [s] the catch                                                 */
    float timeout_reaction; /* [s] FAULT_REACTION                                            */
    float timeout_cal;      /* [s] OFFSET_CAL                                                */
    float timeout_step12;   /* [s] Step I + Step II together                                 */
    float timeout_step3;    /* [s] Step III until the convergence test holds                 */
} mc_seq_cfg_t;

typedef struct {
    mc_seq_cfg_t cfg;
    mc_state_t state;
    mc_init_step_t step;
    uint32_t faults;
    uint32_t ticks;         /* periods in the current state / step                           */
    uint32_t limit;         /* timeout of the current state / step in periods (0: none)      */
    bool enabled;
} mc_seq_t;

typedef enum {
    MC_SEQ_CAL_DONE = 0,
    MC_SEQ_STEP_DONE,       /* Step I or II finished; Step III: the convergence test holds;
                               the catch found the rotor standing                           */
    MC_SEQ_CAUGHT,          /* the catch has the angle and speed of a turning rotor: RUN     */
    MC_SEQ_RECOVER,         /* RUN lost the angle: the catch (protection.lock_action)        */
    MC_SEQ_REACTION_DONE,   /* FAULT_REACTION reached its safe point: FAULT                  */
} mc_seq_event_t;

void mc_seq_init(mc_seq_t *s, const mc_seq_cfg_t *cfg);
/* Enable (rising edge: clean start at OFFSET_CAL, faults cleared) or disable (IDLE). Returns
 * true on a rising edge, so the caller resets its blocks. */
bool mc_seq_enable(mc_seq_t *s, bool on);
void mc_seq_event(mc_seq_t *s, mc_seq_event_t ev);
/* Latch a fault reason: FAULT until disable + enable. */
void mc_seq_fault(mc_seq_t *s, uint32_t reason);
/* Latch a fault reason with its reaction first (RUN only; elsewhere the same as mc_seq_fault):
 * FAULT_REACTION, then FAULT on MC_SEQ_REACTION_DONE, another fault or the timeout. */
void mc_seq_fault_reaction(mc_seq_t *s, uint32_t reason);
/* Once per period, after the events: counts and applies the timeouts. */
void mc_seq_tick(mc_seq_t *s);

#endif
