/* CANopen device: NMT slave, heartbeat producer, the SDO server, the step that runs the PDOs and
 * the CiA 402 layer (mc/co.h; CiA 301 §7.2). */
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

/* The 402 block's configuration from the drive's parameters in force. The default ramps give 5 %
 * of the rated torque's acceleration on the inertia (1090 rpm/s on the thesis motor: the demo's
 * ramps), so that a sensorless start at light load follows them with little torque. */
static void ds_cfg(const mc_co_t *co, mc_402_cfg_t *c)
{
    const mc_params_t *p = mc_drive_params(co->drive);
    const float accel = 0.05f * p->motor_torque_rated_nm / p->motor_inertia_kgm2 * (60.0f / 6.2831853f);   /* [rpm/s] */
    *c = (mc_402_cfg_t){.dt = co->cfg.step_s, .pole_pairs = p->motor_pole_pairs, .rated_torque = p->motor_torque_rated_nm,
                        .rated_current = p->motor_i_rated_a, .psi_pm = p->motor_psi_pm_wb, .ld = p->motor_ld_h, .lq = p->motor_lq_h,
                        .vdc_on = p->control_vdc_min_v, .max_speed_rpm = 0.95f * p->protection_overspeed_rpm,
                        .accel_rpm_s = accel > 1.0f ? accel : 1.0f};
}

/* Communication reset (§7.2.8.3.2): the communication objects to their defaults, boot-up, then
 * pre-operational. */
static void reset_comm(mc_co_t *co)
{
    co->heartbeat_ms = co->cfg.heartbeat_ms;
    co->cob_sync = 0x080u;
    co->sdo.active = false;
    mc_co_pdo_defaults(co);
    co->nmt = MC_NMT_INITIALISING;
    co->boot_pending = true;
}

/* Application reset: also the 402 objects and state, and (with defaults given) the drive's
 * parameters to their power-on values once its outputs are off (reload_step). */
static void reset_app(mc_co_t *co)
{
    co->reload_pending = co->defaults != NULL;
    mc_402_cfg_t c;
    ds_cfg(co, &c);
    mc_402_init(&co->ds, &c);
    co->scope_cfg = (mc_scope_cfg_t){.decimation = 1u};
    co->scope_ctrl = 0u;
    if (co->scope != NULL) {
        mc_scope_stop(co->scope);
    }
    reset_comm(co);
}

bool mc_co_init(mc_co_t *co, const mc_co_cfg_t *cfg, hal_can_t *can, mc_drive_t *drive, hal_nvm_t *nvm,
                mc_scope_t *scope, mc_pstore_status_t cfg_source)
{
    if (cfg == NULL || cfg->node_id < 1u || cfg->node_id > 127u || can == NULL || drive == NULL ||
        !(cfg->step_s > 0.0f && cfg->step_s < 1.0f)) {
        return false;
    }
    memset(co, 0, sizeof *co);
    co->cfg = *cfg;
    co->can = can;
    co->drive = drive;
    co->nvm = nvm;
    co->scope = scope;
    co->ds_on = true;
    co->cfg_source = (uint8_t)cfg_source;
    (void)mc_drive_telemetry_read(drive, &co->tm);
    reset_app(co);
    return true;
}

void mc_co_set_defaults(mc_co_t *co, const mc_params_t *defaults)
{
    co->defaults = defaults;
}

void mc_co_set_boot_report(mc_co_t *co, const mc_store_report_t *rep)
{
    co->boot_params = *rep;
}

/* The power-on parameter set after a reset node: the stored one, else the defaults; taken when
 * the outputs are off (the 402 reset disables them), retried while the drive's hand-over is busy.
 * A set the drive refuses (an INIT parameter that differs, a cross-check) keeps the parameters
 * in force and sends EMCY 0x6320 with the parameter's id. */
static void reload_step(mc_co_t *co)
{
    const mc_state_t st = mc_drive_state(co->drive);
    if (!co->reload_pending || (st != MC_STATE_IDLE && st != MC_STATE_FAULT)) {
        return;
    }
    mc_drive_cfg_t cfg = {.p = *co->defaults, .est = co->drive->est};
    if (co->nvm != NULL) {
        uint8_t work[MC_CO_STORE_WORK];
        mc_drive_cfg_t stored = cfg;
        const mc_pstore_status_t ls = mc_pstore_load(co->nvm, &stored, NULL, work, sizeof work, NULL);
        if (ls == MC_PSTORE_OK || ls == MC_PSTORE_FELL_BACK || ls == MC_PSTORE_PARTIAL) {
            cfg.p = stored.p;
        }
    }
    mc_param_err_t err;
    if (mc_drive_params_write(co->drive, &cfg.p, &err)) {
        co->reload_pending = false;
    } else if (err.kind != MC_PERR_BUSY) {
        co->reload_pending = false;
        const uint8_t info[5] = {(uint8_t)err.kind, (uint8_t)err.param, (uint8_t)((uint32_t)err.param >> 8), 0u, 0u};
        mc_co_emcy_send(co, 0x6320u, 0x01u, info);   /* parameter error */
    }
}

void mc_co_emcy_send(mc_co_t *co, uint16_t code, uint8_t reg, const uint8_t info[5])
{
    const hal_can_frame_t f = {.id = 0x080u + co->cfg.node_id, .dlc = 8u,
                               .data = {(uint8_t)code, (uint8_t)(code >> 8), reg, info[0], info[1], info[2], info[3],
                                        info[4]}};
    if (!hal_can_send(co->can, &f)) {
        co->tx_dropped++;
    }
}

mc_pstore_status_t mc_co_boot_config(const hal_nvm_t *nvm, const mc_drive_cfg_t *base, mc_drive_cfg_t *out,
                                     mc_flux_map_t *map_out, mc_store_report_t *rep)
{
    *out = *base;
    mc_pstore_info_t info;
    mc_store_report_clear(&info.params);
    mc_pstore_status_t st = MC_PSTORE_EMPTY;
    if (nvm != NULL) {
        uint8_t work[MC_CO_STORE_WORK];
        mc_drive_cfg_t stored = *base;
        st = mc_pstore_load(nvm, &stored, map_out, work, sizeof work, &info);
        if (st == MC_PSTORE_OK || st == MC_PSTORE_FELL_BACK || st == MC_PSTORE_PARTIAL) {
            if (stored.est.map == NULL) {
                /* saved without it (too large for the slot), or not loaded (map_out NULL): the
                 * integrator's map of the same machine */
                stored.est.map = base->est.map;
            }
            *out = stored;
        }
    }
    if (rep != NULL) {
        *rep = info.params;
    }
    return st;
}

/* Initiate upload (§7.2.4.3.5): expedited up to 4 bytes, else segmented with the size. A DOMAIN
 * is streamed from the object as the segments go; anything else is copied now. */
static void sdo_upload(mc_co_t *co, uint16_t index, uint8_t sub)
{
    mc_co_entry_t e;
    bool miss;
    uint32_t len = 0u;
    const bool domain = mc_co_od_lookup(index, sub, &e, &miss) && e.type == MC_CO_DOMAIN;
    if (domain) {
        len = mc_co_od_domain_size(co, index, sub);
        if (len == 0u) {
            sdo_abort(co, index, sub, co->scope == NULL ? MC_SDO_ABORT_NO_OBJECT : MC_SDO_ABORT_NO_DATA);
            return;
        }
    } else {
        const uint32_t a = mc_co_od_read(co, index, sub, co->sdo.buf, sizeof co->sdo.buf, &len);
        if (a != 0u) {
            sdo_abort(co, index, sub, a);
            return;
        }
    }
    uint8_t d[8] = {0u, (uint8_t)index, (uint8_t)(index >> 8), sub, 0u, 0u, 0u, 0u};
    if (!domain && len <= 4u) {
        d[0] = (uint8_t)(0x43u | ((4u - len) << 2));   /* scs 2, n, e, s */
        memcpy(d + 4, co->sdo.buf, len);
        sdo_send(co, d);
        return;
    }
    d[0] = 0x41u;   /* scs 2, s: size in d[4..7] */
    d[4] = (uint8_t)len;
    d[5] = (uint8_t)(len >> 8);
    d[6] = (uint8_t)(len >> 16);
    d[7] = (uint8_t)(len >> 24);
    sdo_send(co, d);
    co->sdo.active = true;
    co->sdo.upload = true;
    co->sdo.domain = domain;
    co->sdo.index = index;
    co->sdo.sub = sub;
    co->sdo.toggle = 0u;
    co->sdo.len = len;
    co->sdo.pos = 0u;
    co->sdo.t0_ms = co->now_ms;
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
    uint8_t d[8] = {0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u};
    if (co->sdo.domain) {
        if (mc_co_od_domain_read(co, co->sdo.index, co->sdo.sub, co->sdo.pos, d + 1, n) != n) {
            sdo_abort(co, co->sdo.index, co->sdo.sub, MC_SDO_ABORT_NO_DATA);   /* re-armed meanwhile */
            return;
        }
    } else {
        memcpy(d + 1, co->sdo.buf + co->sdo.pos, n);
    }
    const bool last = co->sdo.pos + n >= co->sdo.len;
    d[0] = (uint8_t)((t << 4) | ((7u - n) << 1) | (last ? 1u : 0u));
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
        if (index == 0x6040u) {
            co->cw_written = true;
            co->cw_count++;
        }
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
    /* the object must exist and be writable before the segments come (the rest is checked at the end) */
    mc_co_entry_t ent;
    bool miss;
    if (!mc_co_od_lookup(index, sub, &ent, &miss)) {
        sdo_abort(co, index, sub, miss ? MC_SDO_ABORT_NO_SUB : MC_SDO_ABORT_NO_OBJECT);
        return;
    }
    if (ent.access == MC_CO_RO || ent.access == MC_CO_CONST) {
        sdo_abort(co, index, sub, MC_SDO_ABORT_READ_ONLY);
        return;
    }
    sdo_send(co, d);
    co->sdo.active = true;
    co->sdo.upload = false;
    co->sdo.domain = false;
    co->sdo.index = index;
    co->sdo.sub = sub;
    co->sdo.toggle = 0u;
    co->sdo.len = 0u;
    co->sdo.size = size;
    co->sdo.t0_ms = co->now_ms;
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
    if (co->sdo.index == 0x6040u) {
        co->cw_written = true;
            co->cw_count++;
    }
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
    case 0x81u: reset_app(co); break;
    case 0x82u: reset_comm(co); break;
    default: break;
    }
}

/* The 402 layer: its step on the telemetry, its command to the drive. */
/* The 402 layer: its step on the telemetry (advance: a period; else only the new controlword's
 * transition), its command to the drive. */
static void ds_step(mc_co_t *co, bool advance)
{
    /* the 402 configuration from the parameters in force, every step: a write over SDO (or a
     * reload) reaches them only when the control ISR takes the new set, and rules derive values
     * from other parameters, so a flag set at the write would read the old set */
    mc_402_cfg_t c;
    ds_cfg(co, &c);
    mc_402_configure(&co->ds, &c);
    mc_drive_cmd_t cmd;
    if (advance) {
        mc_402_step(&co->ds, &co->tm, &cmd);
    } else {
        mc_402_controlword(&co->ds, &co->tm, &cmd);
    }
    if (co->ds_on) {
        mc_drive_command(co->drive, &cmd);
    }
}

/* The stored set came from another table version and some of its values keep their defaults
 * (mc/store.h): the EMCY "parameters lost" with the count, the first such parameter and why
 * (mc_store_drop_t), and an entry in the error history 0x1003 that outlives the EMCY. */
static void boot_partial(mc_co_t *co)
{
    const mc_store_report_t *r = &co->boot_params;
    const uint16_t id = (uint16_t)r->first;
    const uint8_t info[5] = {co->cfg_source, (uint8_t)(r->dropped > 255u ? 255u : r->dropped), (uint8_t)id,
                             (uint8_t)(id >> 8), r->reason};
    for (uint32_t k = 7u; k > 0u; --k) {
        co->err_hist[k] = co->err_hist[k - 1u];
    }
    co->err_hist[0] = MC_EMCY_PARAMS_LOST | ((uint32_t)id << 16);
    if (co->err_count < 8u) {
        co->err_count++;
    }
    mc_co_emcy_send(co, MC_EMCY_PARAMS_LOST, 0x01u, info);
}

void mc_co_step(mc_co_t *co, uint32_t now_ms)
{
    co->now_ms = now_ms;
    (void)mc_drive_telemetry_read(co->drive, &co->tm);   /* on failure: the last one */
    if (co->boot_pending) {
        const uint8_t b = 0u;
        send(co, 0x700u + co->cfg.node_id, &b, 1u);
        co->boot_pending = false;
        co->nmt = MC_NMT_PRE_OPERATIONAL;
        co->hb_last_ms = now_ms;
        if (co->cfg_source == (uint8_t)MC_PSTORE_CORRUPT || co->cfg_source == (uint8_t)MC_PSTORE_NVM_ERROR) {
            const uint8_t info[5] = {co->cfg_source, 0u, 0u, 0u, 0u};
            mc_co_emcy_send(co, MC_EMCY_PARAMS_LOST, 0x01u, info);   /* defaults in force */
        } else if (co->cfg_source == (uint8_t)MC_PSTORE_PARTIAL) {
            boot_partial(co);
        }
    }
    hal_can_frame_t f;
    for (uint32_t k = 0u; k < MC_CO_RX_PER_STEP && hal_can_receive(co->can, &f); ++k) {
        if (f.ext || f.rtr) {
            continue;
        }
        if (f.id == 0x000u) {
            nmt_command(co, &f);
        } else if (f.id == 0x600u + co->cfg.node_id) {
            if (co->nmt != MC_NMT_STOPPED) {
                sdo_request(co, &f);
            }
        } else {
            (void)mc_co_pdo_rx(co, &f);
        }
        if (co->boot_pending) {   /* a reset in this batch */
            return;
        }
        if (co->cw_written) {
            /* every controlword takes its transition, also two in one batch (CiA 402 §6.3) */
            co->cw_written = false;
            ds_step(co, false);
        }
    }
    reload_step(co);
    ds_step(co, true);
    mc_co_pdo_tx(co);
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
