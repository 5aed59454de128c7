/* The scope: chosen telemetry channels (mc/telem_channels.h) captured at the control-ISR rate into
 * a caller-owned RAM buffer around a trigger, for upload over CANopen (0x2300-0x2308, docs/can.md).
 *
 * Arm with a configuration (channels, trigger channel, level and edge, decimation, pre-trigger
 * samples, length). While armed, samples go into a ring (the pre-trigger history); the trigger is
 * evaluated on every ISR call (more precise than on the decimated samples) and the sample of the
 * trigger call is recorded; then length - (pre-trigger samples kept) more follow and the record is
 * DONE: exactly `length` samples per channel, the trigger at mc_scope_trigger_index (less than
 * `pre` when the trigger came before the history was that long). An edge needs a previous value:
 * rising = prev < level <= now, falling = prev > level >= now; a NaN never triggers (it is stored,
 * it is data). Trigger channel 0 triggers on the first call.
 *
 * Concurrency on a target: mc_scope_sample runs in the ISR and preempts the background's calls.
 * The background writes the configuration and the indices while the ISR does not use them (IDLE or
 * DONE) and publishes the state last; force and stop are requests the ISR acts on (stop is also
 * immediate: the ISR ignores a scope that is not ARMED / TRIGGERED); the background reads the
 * record only when DONE, when the ISR no longer writes it. No heap, no globals, O(channels) per
 * ISR call, O(n) per read. */
#ifndef MC_SCOPE_H
#define MC_SCOPE_H
#include <stdbool.h>
#include <stdint.h>
#include "mc/drive.h"

#define MC_SCOPE_MAX_CH 8

typedef enum { MC_SCOPE_IDLE = 0, MC_SCOPE_ARMED = 1, MC_SCOPE_TRIGGERED = 2, MC_SCOPE_DONE = 3 } mc_scope_state_t;
typedef enum { MC_SCOPE_EDGE_RISING = 0, MC_SCOPE_EDGE_FALLING = 1, MC_SCOPE_EDGE_EITHER = 2 } mc_scope_edge_t;

typedef struct {
    uint8_t ch[MC_SCOPE_MAX_CH];   /* channel ids, 0 = unused; the used ones are packed in order */
    uint8_t trig_ch;               /* 0: trigger at once when armed */
    float trig_level;
    uint8_t edge;                  /* mc_scope_edge_t */
    uint16_t decimation;           /* >= 1: one sample every N ISR calls */
    uint32_t pre;                  /* samples kept before the trigger */
    uint32_t length;               /* samples per channel; 0 = as many as fit */
} mc_scope_cfg_t;

typedef enum {
    MC_SCOPE_OK = 0,
    MC_SCOPE_ERR_CHANNEL,          /* a channel id beyond the table */
    MC_SCOPE_ERR_NO_CHANNEL,       /* no channel chosen */
    MC_SCOPE_ERR_TRIGGER,          /* the trigger channel beyond the table */
    MC_SCOPE_ERR_EDGE,
    MC_SCOPE_ERR_LEVEL,            /* not finite */
    MC_SCOPE_ERR_DECIMATION,       /* 0 */
    MC_SCOPE_ERR_LENGTH,           /* length x channels beyond the buffer (or no buffer) */
    MC_SCOPE_ERR_PRE,              /* pre >= length */
    MC_SCOPE_ERR_BUSY              /* armed or triggered: stop first */
} mc_scope_err_t;

typedef struct {
    float *buf;
    uint32_t cap;                  /* floats */
    float ts;                      /* ISR period [s] */
    mc_scope_cfg_t cfg;            /* as armed */
    uint8_t ch[MC_SCOPE_MAX_CH];   /* the used channels, packed */
    uint32_t n_ch, len;            /* channels, samples per channel in the record */
    uint32_t head;                 /* ring index the next sample goes to */
    uint32_t count;                /* samples in the ring (at most len) */
    uint32_t post;                 /* samples still to take after the trigger */
    uint32_t pre_kept;             /* samples before the trigger in the record */
    uint32_t decim;                /* ISR calls until the next sample */
    float prev;                    /* the trigger channel's last value */
    bool have_prev;
    volatile uint32_t state;       /* mc_scope_state_t, published last */
    volatile uint32_t force_req;   /* set by mc_scope_force, taken by the ISR */
} mc_scope_t;

void mc_scope_init(mc_scope_t *s, float *buf, uint32_t cap_floats, float ts_s);
/* Validate and arm (from IDLE or DONE: the old record is dropped). */
mc_scope_err_t mc_scope_arm(mc_scope_t *s, const mc_scope_cfg_t *cfg);
void mc_scope_force(mc_scope_t *s);    /* ARMED: trigger at the next ISR call */
void mc_scope_stop(mc_scope_t *s);     /* -> IDLE, the record discarded */
void mc_scope_sample(mc_scope_t *s, const mc_drive_telem_t *t);   /* the ISR */
mc_scope_state_t mc_scope_state(const mc_scope_t *s);
uint32_t mc_scope_channels(const mc_scope_t *s);      /* used channels of the record */
uint32_t mc_scope_samples(const mc_scope_t *s);       /* samples per channel (DONE), else 0 */
uint32_t mc_scope_trigger_index(const mc_scope_t *s); /* the trigger sample's index (DONE), else 0 */
float mc_scope_sample_period(const mc_scope_t *s);    /* ts x decimation [s] */
uint32_t mc_scope_capacity(const mc_scope_t *s);      /* floats */
uint32_t mc_scope_data_size(const mc_scope_t *s);     /* bytes of the record (DONE), else 0 */
/* Bytes [offset, offset + n) of the record: time order from the oldest sample, sample-major
 * (s0 ch1 .. ch n, s1 ch1 ..), each a little-endian IEEE float32. Returns the bytes copied (0
 * past the end or when not DONE). */
uint32_t mc_scope_read(const mc_scope_t *s, uint32_t offset, uint8_t *dst, uint32_t n);
const char *mc_scope_err_name(mc_scope_err_t e);

#endif
