#include "mc/sequencer.h"

/* A timeout in periods; 0 (none) for a non-positive or NaN time. Converting a float beyond
 * uint32_t is undefined behaviour: anything above ~4e9 periods (or a non-positive ts) becomes the
 * longest representable timeout instead. */
static uint32_t periods(const mc_seq_t *s, float seconds)
{
    if (!(seconds > 0.0f)) {
        return 0u;
    }
    const float n = seconds / s->cfg.ts + 0.5f;
    return (s->cfg.ts > 0.0f && n < 4.0e9f) ? (uint32_t)n : 4000000000u;
}

static void enter(mc_seq_t *s, mc_state_t st, mc_init_step_t step, float timeout)
{
    s->state = st;
    s->step = step;
    s->ticks = 0u;
    s->limit = periods(s, timeout);
}

void mc_seq_init(mc_seq_t *s, const mc_seq_cfg_t *cfg)
{
    s->cfg = *cfg;
    s->faults = 0u;
    s->enabled = false;
    enter(s, MC_STATE_IDLE, MC_INIT_NONE, 0.0f);
}

bool mc_seq_enable(mc_seq_t *s, bool on)
{
    const bool rising = on && !s->enabled;
    if (rising) {
        s->faults = 0u;
        enter(s, MC_STATE_OFFSET_CAL, MC_INIT_NONE, s->cfg.timeout_cal);
    } else if (!on && s->enabled) {
        enter(s, MC_STATE_IDLE, MC_INIT_NONE, 0.0f);
    }
    s->enabled = on;
    return rising;
}

void mc_seq_event(mc_seq_t *s, mc_seq_event_t ev)
{
    if (s->state == MC_STATE_OFFSET_CAL && ev == MC_SEQ_CAL_DONE) {
        if (s->cfg.catch_first) {
            enter(s, MC_STATE_INIT_POS, MC_INIT_CATCH, s->cfg.timeout_catch);
        } else if (s->cfg.init_pos) {
            enter(s, MC_STATE_INIT_POS, MC_INIT_STEP1, s->cfg.timeout_step12);
        } else {
            enter(s, MC_STATE_RUN, MC_INIT_NONE, 0.0f);
        }
    } else if (s->state == MC_STATE_FAULT_REACTION && ev == MC_SEQ_REACTION_DONE) {
        enter(s, MC_STATE_FAULT, MC_INIT_NONE, 0.0f);
    } else if (s->state == MC_STATE_RUN && ev == MC_SEQ_RECOVER) {
        enter(s, MC_STATE_INIT_POS, MC_INIT_CATCH, s->cfg.timeout_catch);
    } else if (s->state == MC_STATE_INIT_POS && s->step == MC_INIT_CATCH) {
        if (ev == MC_SEQ_CAUGHT || (ev == MC_SEQ_STEP_DONE && !s->cfg.init_pos)) {
            enter(s, MC_STATE_RUN, MC_INIT_NONE, 0.0f);
        } else if (ev == MC_SEQ_STEP_DONE) {
            enter(s, MC_STATE_INIT_POS, MC_INIT_STEP1, s->cfg.timeout_step12);
        }
    } else if (s->state == MC_STATE_INIT_POS && ev == MC_SEQ_STEP_DONE) {
        if (s->step == MC_INIT_STEP1) {
            /* Step I and II share one budget: keep the tick count running */
            const uint32_t t = s->ticks;
            enter(s, MC_STATE_INIT_POS, MC_INIT_STEP2, s->cfg.timeout_step12);
            s->ticks = t;
        } else if (s->step == MC_INIT_STEP2) {
            enter(s, MC_STATE_INIT_POS, MC_INIT_STEP3, s->cfg.timeout_step3);
        } else {
            enter(s, MC_STATE_RUN, MC_INIT_NONE, 0.0f);
        }
    }
    /* anything else (an event that does not belong to the state) is ignored */
}

void mc_seq_fault(mc_seq_t *s, uint32_t reason)
{
    s->faults |= reason;
    enter(s, MC_STATE_FAULT, MC_INIT_NONE, 0.0f);
}

void mc_seq_fault_reaction(mc_seq_t *s, uint32_t reason)
{
    if (s->state != MC_STATE_RUN) {
        mc_seq_fault(s, reason);
        return;
    }
    s->faults |= reason;
    enter(s, MC_STATE_FAULT_REACTION, MC_INIT_NONE, s->cfg.timeout_reaction);
}

void mc_seq_tick(mc_seq_t *s)
{
    /* saturates, never wraps: RUN has no limit, and code that acts on its first ticks (the I/f
     * entry, the protection's running flag) must not see them again after 2^32 periods (5 days
     * at 10 kHz) */
    if (s->ticks < UINT32_MAX) {
        s->ticks++;
    }
    if (s->limit != 0u && s->ticks > s->limit) {
        mc_seq_fault(s, MC_FAULT_TIMEOUT);
    }
}
