/* The drive's firmware image: boot, configuration, the control ISR and the background loop, on
 * whatever port the image is linked with (hal/generic, hal/am263x). The one instance of the drive
 * and its mailbox live here, as statics of the image (the library has no globals).
 *
 * Boot: the board with the default timing (so the outputs are held off), the configuration from
 * the image's configuration area (mc/store.h; the defaults where it is erased or refused, with
 * the reason in the monitor), over it the set stored by CANopen 0x1010 in the NVM (mc/co.h; its
 * map stays in the NVM: the area's map is used), the board again with the configured PWM
 * frequency and dead time, the drive, the CANopen device, then the ISR. The ISR runs the drive
 * and the scope. The background loop sleeps until an interrupt; after each control ISR it runs
 * the drive's background work and the CANopen device every 10th period, publishes the telemetry
 * to the monitor block (mc/monitor.h) and hands the drive a command written there. It services the
 * watchdog (hal/watchdog.h: a kick only if the port counted an ISR since the last one), as the NVM
 * driver does while a store waits on the flash: a stalled ISR or a hung loop trips.
 * Two commanders: the monitor (a debugger, the PIL) and CiA 402 over CAN. The last one heard
 * wins: a monitor command takes the drive from CANopen, a controlword gives it to CANopen. */
#include <math.h>
#include "hal/board.h"
#include "mc/co.h"
#include "mc/drive.h"
#include "mc/monitor.h"
#include "mc/scope.h"
#include "mc/store.h"

#define SCOPE_VALUES 1536u   /* 6 KB: e.g. 4 channels x 384 samples */

/* The configuration area: erased records in the image, written by a tool before flashing; the
 * estimator uses the map where it lies (mc_store_model_view), so no RAM holds a copy. */
__attribute__((section(".mc_config"), used, aligned(8)))
const mc_config_area_t mc_config_area = {.records = {[0 ... MC_CONFIG_RECORDS_SIZE - 1] = 0xFFu}};

/* Read and written by a debugger (or the PIL) while the drive runs. */
volatile mc_monitor_t mc_monitor;

static mc_drive_t drive;
static mc_drive_link_t drive_link;
static mc_co_t co;
static mc_scope_t scope;
static float scope_buf[SCOPE_VALUES];
static hal_time_t *clock;
static hal_wdg_t *wdg;

static void control_isr(void *ctx)
{
    mc_drive_t *d = (mc_drive_t *)ctx;
    mc_drive_isr(d);
    mc_scope_sample(&scope, mc_drive_telemetry(d));
    mc_monitor.isr_count = mc_monitor.isr_count + 1u;
}

static void board_cfg_from(const mc_params_t *p, hal_board_cfg_t *b)
{
    b->f_pwm_hz = 1.0f / p->control_ts_s;
    b->dead_time_s = p->hw_dead_time_s;
    b->adc_ch_i[0] = 0u;
    b->adc_ch_i[1] = 1u;
    b->adc_ch_i[2] = 2u;
    b->adc_ch_vdc = 3u;
    b->qep_counts_per_rev = 4u * (uint32_t)p->hw_encoder_lines;
    b->can_bitrate = 500000u;
}

static void load_config(mc_drive_cfg_t *cfg)
{
    const mc_store_status_t sp = mc_store_params_decode(mc_config_area.records, MC_CONFIG_MODEL_OFFSET, &cfg->p, NULL);
    const mc_store_status_t sm =
        mc_store_model_view(mc_config_area.records + MC_CONFIG_MODEL_OFFSET,
                            MC_CONFIG_RECORDS_SIZE - MC_CONFIG_MODEL_OFFSET, &cfg->est, &mc_config_area.map);
    mc_monitor.store_params = (uint32_t)sp;
    mc_monitor.store_model = (uint32_t)sm;
}

static void service(uint32_t *seen_isr, uint32_t *seen_cmd, uint32_t *seen_cw)
{
    const uint32_t n = mc_monitor.isr_count;
    if (n != *seen_isr) {
        *seen_isr = n;
        hal_wdg_service(wdg);   /* progress: the ISR ran since the last kick and so did this loop */
        if ((n - 1u) % 10u == 0u) {
            mc_drive_background(&drive);
            mc_co_step(&co, hal_time_us(clock) / 1000u);
            if (co.cw_count != *seen_cw) {
                *seen_cw = co.cw_count;
                co.ds_on = true;   /* a controlword: CANopen commands the drive */
            }
        }
        mc_drive_telem_t tm;
        if (mc_drive_telemetry_read(&drive, &tm)) {
            uint32_t w[MC_MONITOR_TM_WORDS];
            mc_monitor_pack_telem(&tm, w);
            for (unsigned k = 0u; k < MC_MONITOR_TM_WORDS; ++k) {
                mc_monitor.tm[k] = w[k];
            }
            mc_monitor.tm_seq = mc_monitor.tm_seq + 1u;
        }
    }
    const uint32_t s = mc_monitor.cmd_seq;
    if (s != *seen_cmd) {
        *seen_cmd = s;
        uint32_t w[MC_MONITOR_CMD_WORDS];
        for (unsigned k = 0u; k < MC_MONITOR_CMD_WORDS; ++k) {
            w[k] = mc_monitor.cmd[k];
        }
        mc_drive_cmd_t cmd;
        mc_monitor_unpack_cmd(w, &cmd);
        co.ds_on = false;   /* the monitor commands the drive */
        mc_drive_command(&drive, &cmd);
    }
}

int main(void)
{
    mc_monitor.magic = MC_MONITOR_MAGIC;
    mc_monitor.version = MC_MONITOR_VERSION;
    mc_monitor.boot = 0u;

    static mc_drive_cfg_t cfg;
    mc_drive_cfg_default(&cfg);
    hal_board_cfg_t bcfg;
    board_cfg_from(&cfg.p, &bcfg);
    hal_board_t board;
    if (!hal_board_init(&bcfg, &board)) {
        mc_monitor.boot = 2u;
        for (;;) {
            hal_board_idle();
        }
    }
    static mc_drive_cfg_t base;
    base = cfg;
    load_config(&base);
    mc_store_report_t rep;
    mc_pstore_status_t src = mc_co_boot_config(board.nvm, &base, &cfg, NULL, &rep);
    mc_monitor.store_nvm = (uint32_t)src;
    board_cfg_from(&cfg.p, &bcfg);
    bool board_ok = hal_board_init(&bcfg, &board);
    bool drive_ok = board_ok && mc_drive_init(&drive, &drive_link, &cfg, board.adc, board.pwm, board.qep);
    if (board_ok && !drive_ok && (src == MC_PSTORE_OK || src == MC_PSTORE_FELL_BACK || src == MC_PSTORE_PARTIAL)) {
        /* the stored set does not start this drive: the configuration area's, and say so */
        src = MC_PSTORE_CORRUPT;
        mc_monitor.store_nvm = (uint32_t)src;
        cfg = base;
        board_cfg_from(&cfg.p, &bcfg);
        board_ok = hal_board_init(&bcfg, &board);
        drive_ok = board_ok && mc_drive_init(&drive, &drive_link, &cfg, board.adc, board.pwm, board.qep);
    }
    if (!drive_ok) {
        const mc_param_err_t *e = mc_drive_config_error(&drive);
        /* the board refused: a dead time below the port's floor is named (0 is shoot-through) */
        const bool dt = !board_ok && !(bcfg.dead_time_s >= hal_board_min_dead_time_s());
        mc_monitor.cfg_err_kind = board_ok ? (uint32_t)e->kind : dt ? (uint32_t)MC_PERR_RANGE : 0xFFFFFFFFu;
        mc_monitor.cfg_err_param = board_ok ? (uint32_t)e->param : dt ? (uint32_t)MC_PARAM_hw_dead_time_s : 0xFFFFFFFFu;
        mc_monitor.boot = 2u;
        for (;;) {
            hal_board_idle();   /* outputs off: the board came up with them off */
        }
    }
    clock = board.time;
    wdg = board.wdg;
    mc_scope_init(&scope, scope_buf, SCOPE_VALUES, cfg.p.control_ts_s);
    const mc_co_cfg_t cc = {.node_id = 1u, .heartbeat_ms = 1000u, .step_s = 10.0f * cfg.p.control_ts_s, .vendor_id = 0u,
                            .product_code = 1u, .revision = 0x00020000u, .serial = 0u};
    (void)mc_co_init(&co, &cc, board.can, &drive, board.nvm, &scope, src);
    mc_co_set_defaults(&co, &base.p);   /* a reset node: the stored set, else the area's */
    mc_co_set_boot_report(&co, &rep);
    co.ds_on = false;   /* until a controlword comes */
    hal_board_attach_isr(control_isr, &drive);
    mc_monitor.boot = 1u;
    hal_board_start();

    uint32_t seen_isr = 0u, seen_cmd = 0u, seen_cw = 0u;
    for (;;) {
        hal_board_idle();
        service(&seen_isr, &seen_cmd, &seen_cw);
    }
}
