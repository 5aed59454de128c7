/* The scope (mc/scope.h). */
#include "mc/bits.h"
#include "mc/scope.h"
#include "mc/telem_channels.h"

#define BARRIER() __asm__ volatile("" ::: "memory")

void mc_scope_init(mc_scope_t *s, float *buf, uint32_t cap_floats, float ts_s)
{
    *s = (mc_scope_t){.buf = buf, .cap = buf != 0 ? cap_floats : 0u, .ts = ts_s};
    s->cfg.decimation = 1u;
    s->state = MC_SCOPE_IDLE;
}

mc_scope_err_t mc_scope_arm(mc_scope_t *s, const mc_scope_cfg_t *cfg)
{
    const uint32_t st = s->state;
    if (st == MC_SCOPE_ARMED || st == MC_SCOPE_TRIGGERED) {
        return MC_SCOPE_ERR_BUSY;
    }
    uint32_t n = 0u;
    uint8_t ch[MC_SCOPE_MAX_CH] = {0};
    for (uint32_t k = 0u; k < MC_SCOPE_MAX_CH; ++k) {
        if (cfg->ch[k] > MC_TELEM_CHANNEL_COUNT) {
            return MC_SCOPE_ERR_CHANNEL;
        }
        if (cfg->ch[k] != 0u) {
            ch[n++] = cfg->ch[k];
        }
    }
    if (n == 0u) {
        return MC_SCOPE_ERR_NO_CHANNEL;
    }
    if (cfg->trig_ch > MC_TELEM_CHANNEL_COUNT) {
        return MC_SCOPE_ERR_TRIGGER;
    }
    if (cfg->edge > (uint8_t)MC_SCOPE_EDGE_EITHER) {
        return MC_SCOPE_ERR_EDGE;
    }
    if (cfg->trig_ch != 0u && (mc_f32_bits(cfg->trig_level) & 0x7F800000u) == 0x7F800000u) {
        return MC_SCOPE_ERR_LEVEL;
    }
    if (cfg->decimation == 0u) {
        return MC_SCOPE_ERR_DECIMATION;
    }
    const uint32_t fit = s->cap / n;
    const uint32_t len = cfg->length != 0u ? cfg->length : fit;
    if (len == 0u || len > fit) {
        return MC_SCOPE_ERR_LENGTH;
    }
    if (cfg->pre >= len) {
        return MC_SCOPE_ERR_PRE;
    }
    s->state = MC_SCOPE_IDLE;   /* the ISR leaves it alone while the indices change */
    BARRIER();
    s->cfg = *cfg;
    for (uint32_t k = 0u; k < MC_SCOPE_MAX_CH; ++k) {
        s->ch[k] = ch[k];
    }
    s->n_ch = n;
    s->len = len;
    s->head = 0u;
    s->count = 0u;
    s->post = 0u;
    s->pre_kept = 0u;
    s->decim = 0u;
    s->have_prev = false;
    s->force_req = 0u;
    BARRIER();
    s->state = MC_SCOPE_ARMED;
    return MC_SCOPE_OK;
}

void mc_scope_force(mc_scope_t *s)
{
    s->force_req = 1u;
}

void mc_scope_stop(mc_scope_t *s)
{
    s->state = MC_SCOPE_IDLE;
}

static bool crossed(const mc_scope_t *s, float v)
{
    const float lv = s->cfg.trig_level, p = s->prev;
    if (!s->have_prev || !(v == v) || !(p == p)) {
        return false;
    }
    const bool up = p < lv && v >= lv, down = p > lv && v <= lv;
    switch (s->cfg.edge) {
    case MC_SCOPE_EDGE_RISING: return up;
    case MC_SCOPE_EDGE_FALLING: return down;
    default: return up || down;
    }
}

void mc_scope_sample(mc_scope_t *s, const mc_drive_telem_t *t)
{
    uint32_t st = s->state;
    if (st != MC_SCOPE_ARMED && st != MC_SCOPE_TRIGGERED) {
        return;
    }
    if (st == MC_SCOPE_ARMED) {
        bool fire = s->cfg.trig_ch == 0u || s->force_req != 0u;
        if (s->cfg.trig_ch != 0u) {
            const float v = mc_telem_channel(t, s->cfg.trig_ch);
            fire = fire || crossed(s, v);
            s->prev = v;
            s->have_prev = true;
        }
        if (fire) {
            st = MC_SCOPE_TRIGGERED;
            s->pre_kept = s->count < s->cfg.pre ? s->count : s->cfg.pre;
            s->post = s->len - s->pre_kept;
            s->decim = 0u;   /* the trigger call's sample is recorded */
        }
    }
    if (s->decim == 0u) {
        float *row = s->buf + s->head * s->n_ch;
        for (uint32_t k = 0u; k < s->n_ch; ++k) {
            row[k] = mc_telem_channel(t, s->ch[k]);
        }
        s->head = s->head + 1u == s->len ? 0u : s->head + 1u;
        if (s->count < s->len) {
            s->count++;
        }
        if (st == MC_SCOPE_TRIGGERED && --s->post == 0u) {
            st = MC_SCOPE_DONE;   /* the ring holds exactly the record; the oldest is at head */
        }
    }
    s->decim = s->decim + 1u >= s->cfg.decimation ? 0u : s->decim + 1u;
    if (s->state != MC_SCOPE_IDLE) {   /* a stop in between wins */
        s->state = st;
    }
}

mc_scope_state_t mc_scope_state(const mc_scope_t *s)
{
    return (mc_scope_state_t)s->state;
}

uint32_t mc_scope_channels(const mc_scope_t *s)
{
    return s->n_ch;
}

uint32_t mc_scope_samples(const mc_scope_t *s)
{
    return s->state == MC_SCOPE_DONE ? s->len : 0u;
}

uint32_t mc_scope_trigger_index(const mc_scope_t *s)
{
    return s->state == MC_SCOPE_DONE ? s->pre_kept : 0u;
}

float mc_scope_sample_period(const mc_scope_t *s)
{
    return s->ts * (float)(s->cfg.decimation != 0u ? s->cfg.decimation : 1u);
}

uint32_t mc_scope_capacity(const mc_scope_t *s)
{
    return s->cap;
}

uint32_t mc_scope_data_size(const mc_scope_t *s)
{
    return s->state == MC_SCOPE_DONE ? 4u * s->len * s->n_ch : 0u;
}

uint32_t mc_scope_read(const mc_scope_t *s, uint32_t offset, uint8_t *dst, uint32_t n)
{
    const uint32_t size = mc_scope_data_size(s);
    if (offset >= size) {
        return 0u;
    }
    if (n > size - offset) {
        n = size - offset;
    }
    for (uint32_t k = 0u; k < n; ++k) {
        const uint32_t byte = offset + k, value = byte / 4u;
        const uint32_t sample = value / s->n_ch, ch = value % s->n_ch;
        const uint32_t ring = (s->head + sample) % s->len;
        const uint32_t w = mc_f32_bits(s->buf[ring * s->n_ch + ch]);
        dst[k] = (uint8_t)(w >> (8u * (byte % 4u)));
    }
    return n;
}

const char *mc_scope_err_name(mc_scope_err_t e)
{
    switch (e) {
    case MC_SCOPE_OK: return "ok";
    case MC_SCOPE_ERR_CHANNEL: return "a channel id beyond the telemetry table";
    case MC_SCOPE_ERR_NO_CHANNEL: return "no channel chosen";
    case MC_SCOPE_ERR_TRIGGER: return "the trigger channel beyond the telemetry table";
    case MC_SCOPE_ERR_EDGE: return "edge not 0 (rising), 1 (falling) or 2 (either)";
    case MC_SCOPE_ERR_LEVEL: return "trigger level not finite";
    case MC_SCOPE_ERR_DECIMATION: return "decimation 0";
    case MC_SCOPE_ERR_LENGTH: return "length x channels beyond the buffer";
    case MC_SCOPE_ERR_PRE: return "pre-trigger not below the length";
    case MC_SCOPE_ERR_BUSY: return "armed: stop first";
    default: return "?";
    }
}
