/* CANopen device: NMT slave, heartbeat producer and the SDO server (mc/co.h; CiA 301 §7.2). */
#include <string.h>
#include "mc/co.h"

static void send(mc_co_t *co, uint32_t id, const uint8_t *data, uint8_t dlc)
{
    hal_can_frame_t f = {.id = id, .ext = false, .rtr = false, .dlc = dlc};
    memcpy(f.data, data, dlc);
    if (!hal_can_send(co->can, &f)) {
        co->tx_dropped++;
    }
}

static void sdo_send(mc_co_t *co, const uint8_t d[8])
{
    send(co, 0x580u + co->cfg.node_id, d, 8u);
}

static void sdo_abort(mc_co_t *co, uint16_t index, uint8_t sub, uint32_t code)
{
    const uint8_t d[8] = {0x80u, (uint8_t)index, (uint8_t)(index >> 8), sub,
                          (uint8_t)code, (uint8_t)(code >> 8), (uint8_t)(code >> 16), (uint8_t)(code >> 24)};
    sdo_send(co, d);
    co->sdo.active = false;
}

static void reset_comm(mc_co_t *co)
{
    co->heartbeat_ms = co->cfg.heartbeat_ms;
    co->sdo.active = false;
    co->nmt = MC_NMT_INITIALISING;
    co->boot_pending = true;   /* §7.2.8.3.2: boot-up, then pre-operational */
}

bool mc_co_init(mc_co_t *co, const mc_co_cfg_t *cfg, hal_can_t *can, mc_drive_t *drive)
{
    if (cfg == NULL || cfg->node_id < 1u || cfg->node_id > 127u || can == NULL || drive == NULL) {
        return false;
    }
    memset(co, 0, sizeof *co);
    co->cfg = *cfg;
    co->can = can;
    co->drive = drive;
    reset_comm(co);
    return true;
}

/* Initiate upload (§7.2.4.3.5): expedited up to 4 bytes, else segmented with the size. */
static void sdo_upload(mc_co_t *co, uint16_t index, uint8_t sub)
{
    uint32_t len = 0u;
    const uint32_t a = mc_co_od_read(co, index, sub, co->sdo.buf, sizeof co->sdo.buf, &len);
    if (a != 0u) {
        sdo_abort(co, index, sub, a);
        return;
    }
    uint8_t d[8] = {0u, (uint8_t)index, (uint8_t)(index >> 8), sub, 0u, 0u, 0u, 0u};
    if (len <= 4u) {
        d[0] = (uint8_t)(0x43u | ((4u - len) << 2));   /* scs 2, n, e, s */
        memcpy(d + 4, co->sdo.buf, len);
        sdo_send(co, d);
        return;
    }
    d[0] = 0x41u;   /* scs 2, s: size in d[4..7] */
    d[4] = (uint8_t)len;
    d[5] = (uint8_t)(len >> 8);
    sdo_send(co, d);
    co->sdo = (mc_co_sdo_t){.active = true, .upload = true, .index = index, .sub = sub, .toggle = 0u,
                                .len = len, .pos = 0u, .t0_ms = co->now_ms};
    (void)mc_co_od_read(co, index, sub, co->sdo.buf, sizeof co->sdo.buf, &co->sdo.len);
}

/* Upload segment (§7.2.4.3.6). */
static void sdo_upload_segment(mc_co_t *co, uint8_t cmd)
{
    if (!co->sdo.active || !co->sdo.upload) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_CS);
        return;
    }
    const uint8_t t = (uint8_t)((cmd >> 4) & 1u);
    if (t != co->sdo.toggle) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_TOGGLE);
        return;
    }
    uint32_t n = co->sdo.len - co->sdo.pos;
    if (n > 7u) {
        n = 7u;
    }
    const bool last = co->sdo.pos + n >= co->sdo.len;
    uint8_t d[8] = {(uint8_t)((t << 4) | ((7u - n) << 1) | (last ? 1u : 0u)), 0u, 0u, 0u, 0u, 0u, 0u, 0u};
    memcpy(d + 1, co->sdo.buf + co->sdo.pos, n);
    sdo_send(co, d);
    co->sdo.pos += n;
    co->sdo.toggle ^= 1u;
    co->sdo.t0_ms = co->now_ms;
    if (last) {
        co->sdo.active = false;
    }
}

/* Initiate download (§7.2.4.3.3): expedited written at once, else a segmented transfer. */
static void sdo_download(mc_co_t *co, const uint8_t *r, uint16_t index, uint8_t sub)
{
    const uint8_t cmd = r[0];
    const bool e = (cmd & 0x02u) != 0u, s = (cmd & 0x01u) != 0u;
    uint8_t d[8] = {0x60u, (uint8_t)index, (uint8_t)(index >> 8), sub, 0u, 0u, 0u, 0u};
    if (e) {
        const uint32_t n = s ? 4u - ((cmd >> 2) & 3u) : 4u;
        const uint32_t a = mc_co_od_write(co, index, sub, r + 4, n);
        if (a != 0u) {
            sdo_abort(co, index, sub, a);
            return;
        }
        sdo_send(co, d);
        return;
    }
    const uint32_t size = s ? (uint32_t)r[4] | ((uint32_t)r[5] << 8) | ((uint32_t)r[6] << 16) | ((uint32_t)r[7] << 24)
                            : 0u;
    if (size > MC_CO_SDO_BUF) {
        sdo_abort(co, index, sub, MC_SDO_ABORT_LENGTH_HIGH);
        return;
    }
    /* the object must exist before the segments come (its own checks run at the end) */
    uint8_t tmp[MC_CO_SDO_BUF];
    uint32_t n;
    const uint32_t a = mc_co_od_read(co, index, sub, tmp, sizeof tmp, &n);
    if (a == MC_SDO_ABORT_NO_OBJECT || a == MC_SDO_ABORT_NO_SUB) {
        sdo_abort(co, index, sub, a);
        return;
    }
    sdo_send(co, d);
    co->sdo = (mc_co_sdo_t){.active = true, .upload = false, .index = index, .sub = sub, .toggle = 0u,
                                .len = 0u, .size = size, .t0_ms = co->now_ms};
}

/* Download segment (§7.2.4.3.4). */
static void sdo_download_segment(mc_co_t *co, const uint8_t *r)
{
    if (!co->sdo.active || co->sdo.upload) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_CS);
        return;
    }
    const uint8_t t = (uint8_t)((r[0] >> 4) & 1u);
    if (t != co->sdo.toggle) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_TOGGLE);
        return;
    }
    const uint32_t n = 7u - ((r[0] >> 1) & 7u);
    if (co->sdo.len + n > MC_CO_SDO_BUF) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_LENGTH_HIGH);
        return;
    }
    memcpy(co->sdo.buf + co->sdo.len, r + 1, n);
    co->sdo.len += n;
    co->sdo.toggle ^= 1u;
    co->sdo.t0_ms = co->now_ms;
    const uint8_t d[8] = {(uint8_t)(0x20u | (t << 4)), 0u, 0u, 0u, 0u, 0u, 0u, 0u};
    if ((r[0] & 1u) == 0u) {
        sdo_send(co, d);
        return;
    }
    co->sdo.active = false;
    if (co->sdo.size != 0u && co->sdo.size != co->sdo.len) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_LENGTH);
        return;
    }
    const uint32_t a = mc_co_od_write(co, co->sdo.index, co->sdo.sub, co->sdo.buf, co->sdo.len);
    if (a != 0u) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, a);
        return;
    }
    sdo_send(co, d);
}

static void sdo_request(mc_co_t *co, const hal_can_frame_t *f)
{
    if (f->dlc != 8u) {
        return;   /* §7.2.4.3: an SDO frame has 8 bytes; a short one is not answered */
    }
    const uint8_t *r = f->data;
    const uint16_t index = (uint16_t)(r[1] | (r[2] << 8));
    const uint8_t sub = r[3];
    switch (r[0] >> 5) {   /* client command specifier */
    case 1u:
        co->sdo.active = false;   /* a new request ends an unfinished one */
        sdo_download(co, r, index, sub);
        break;
    case 2u:
        co->sdo.active = false;
        sdo_upload(co, index, sub);
        break;
    case 0u:
        sdo_download_segment(co, r);
        break;
    case 3u:
        sdo_upload_segment(co, r[0]);
        break;
    case 4u:
        co->sdo.active = false;   /* the client aborted: no answer */
        break;
    default:
        sdo_abort(co, index, sub, MC_SDO_ABORT_CS);
        break;
    }
}

static void nmt_command(mc_co_t *co, const hal_can_frame_t *f)
{
    if (f->dlc != 2u || (f->data[1] != 0u && f->data[1] != co->cfg.node_id)) {
        return;
    }
    switch (f->data[0]) {
    case 0x01u: co->nmt = MC_NMT_OPERATIONAL; break;
    case 0x02u: co->nmt = MC_NMT_STOPPED; co->sdo.active = false; break;
    case 0x80u: co->nmt = MC_NMT_PRE_OPERATIONAL; break;
    case 0x81u:   /* reset node: the application's parameters are the drive's, kept; comm restarts */
    case 0x82u: reset_comm(co); break;
    default: break;
    }
}

void mc_co_step(mc_co_t *co, uint32_t now_ms)
{
    co->now_ms = now_ms;
    if (co->boot_pending) {
        const uint8_t b = 0u;
        send(co, 0x700u + co->cfg.node_id, &b, 1u);
        co->boot_pending = false;
        co->nmt = MC_NMT_PRE_OPERATIONAL;
        co->hb_last_ms = now_ms;
    }
    hal_can_frame_t f;
    for (uint32_t k = 0u; k < MC_CO_RX_PER_STEP && hal_can_receive(co->can, &f); ++k) {
        if (f.ext || f.rtr) {
            continue;
        }
        if (f.id == 0x000u) {
            nmt_command(co, &f);
        } else if (f.id == 0x600u + co->cfg.node_id && co->nmt != MC_NMT_STOPPED) {
            sdo_request(co, &f);
        }
        if (co->boot_pending) {   /* a reset communication in this batch */
            return;
        }
    }
    mc_co_emcy_step(co);
    if (co->sdo.active && now_ms - co->sdo.t0_ms > MC_CO_SDO_TIMEOUT_MS) {
        sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_TIMEOUT);
    }
    if (co->heartbeat_ms != 0u && now_ms - co->hb_last_ms >= co->heartbeat_ms) {
        const uint8_t st = (uint8_t)co->nmt;
        send(co, 0x700u + co->cfg.node_id, &st, 1u);
        co->hb_last_ms = now_ms;
    }
}
