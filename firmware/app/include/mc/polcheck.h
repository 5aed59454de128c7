/* The running polarity re-check (protection.polarity_check; docs/protection.md, detector (e)):
 * the principle of Step II (thesis 5.3) on the running drive, with a d-current bias of +-I_b
 * under the HF injection (6.4). Its sequence, verdict and settledness test are described in
 * polcheck.c. The block owns its state (the running check and its counters) and reads its
 * configuration, built in the background (mc_drive_build). Units SI, rad/s electrical. */
#ifndef MC_POLCHECK_H
#define MC_POLCHECK_H
#include <stdbool.h>
#include <stdint.h>

typedef struct {
    bool enable;                 /* protection.polarity_check != off: started on a lock doubt  */
    bool at_start;               /* = at_start: also a settling time into RUN                  */
    bool inject;                 /* the angle source injects (6.4): the check needs it         */
    bool three_step;             /* Step II ran before RUN: no at_start check                  */
    float omega_n1;              /* the injection's fade speed N1: checks below half of it [rad/s el] */
    float bias;                  /* I_b [A]                                                     */
    float log_ratio;             /* ln (l_dd(-I_b) / l_dd(+I_b))^2 from the map (0: unknown)     */
    uint32_t settle_n, measure_n;   /* [periods]                                               */
    uint32_t start_n;            /* at_start: this long into RUN (the estimate settled first)   */
    float w_scale;               /* 10 deg / speed tolerance: a speed drift in "angle" units    */
    float avg_k;                 /* the 20 Hz first-order low-pass coefficient of its average   */
} mc_polcheck_cfg_t;

typedef struct {
    int phase;
    uint32_t n, cnt[2];
    float acc[2];                /* sums of the squared HF d current, +I_b and -I_b             */
    float moved;                 /* largest unsettledness during the check                     */
    float w0;                    /* speed estimate (20 Hz average) at its start [rad/s el]      */
    float innov;                 /* |raw angle - PLL angle|, 20 Hz average [rad]                */
    uint32_t starts;             /* at_start: checks begun since the enable (at most 3)         */
    bool unsure;                 /* this RUN entry follows a 'standing' verdict of the catch's
                                    probe that the device drop makes unsure: checked as at_start */
    uint32_t checks, flips;      /* checks begun and estimates turned since the enable          */
    int last;                    /* last verdict: +1 reversed, -1 right, 0 inconclusive         */
} mc_polcheck_t;

/* One period's inputs. */
typedef struct {
    float i_d, i_d_filtered;     /* the d current, raw and through the injection's notch [A]    */
    float theta, theta_raw;      /* the angle source's estimate and its raw angle [rad]          */
    float w_avg;                 /* the speed estimate's 20 Hz average (protection's) [rad/s el] */
} mc_polcheck_in_t;

void mc_polcheck_reset(mc_polcheck_t *s);     /* no check running (the estimate was set)     */
void mc_polcheck_restart(mc_polcheck_t *s);   /* an enable: counters and verdicts cleared too */
bool mc_polcheck_active(const mc_polcheck_t *s);
/* Begin a check (false: not now: off, no injection, one running, not in RUN (running false) or
 * at or above half of N1). */
bool mc_polcheck_start(mc_polcheck_t *s, const mc_polcheck_cfg_t *c, float omega, bool running);
/* The at_start trigger, every period: ticks periods into RUN. */
void mc_polcheck_schedule(mc_polcheck_t *s, const mc_polcheck_cfg_t *c, float omega, bool running, uint32_t ticks);
/* The d-reference bias while a check runs [A] (0 otherwise). */
float mc_polcheck_bias(const mc_polcheck_t *s, const mc_polcheck_cfg_t *c);
/* One measuring period; true: the estimate is reversed, the caller turns it by pi (and its speed
 * changes sign: the mirrored solution is (theta + pi, -omega)) and restarts its current loop. */
bool mc_polcheck_step(mc_polcheck_t *s, const mc_polcheck_cfg_t *c, const mc_polcheck_in_t *in);

#endif
