/* The generic memory-mapped port (hal_generic/regs.h): the HAL contract on a minimal register
 * block, for the Cortex-M4F budget reference and its processor-in-the-loop run. Register bases
 * are held in the port's structs so that a unit test can point them at RAM. */
#include <math.h>
#include "hal/board.h"
#include "hal/stage.h"
#include "hal_generic/regs.h"

struct hal_pwm { uintptr_t base; float period_s, dead_time_s; uint32_t prd; uint32_t nonfinite; };
struct hal_adc { uintptr_t base; };
struct hal_qep { uintptr_t base; uint32_t counts_per_rev; };
struct hal_time { uintptr_t base; };
struct hal_can { hal_can_state_t state; };
struct hal_nvm { uintptr_t flc; uint32_t base; };
struct hal_wdg {
    uintptr_t base;
    volatile uint32_t isr_runs;   /* control-ISR entries, counted by hal_generic_adc_irq */
    uint32_t seen;                /* isr_runs at the last hal_wdg_service kick            */
};

#define REG(b, off) (*(volatile uint32_t *)((b) + (off)))

/* The name the PIL picks this port's peripheral model by. */
__attribute__((used, section(".rodata.hal_port_name"))) const char hal_port_name[] = "generic";
/* Stage marker (hal/stage.h): the PIL watches stores to it. */
volatile uint32_t hal_stage_reg;

static hal_pwm_t pwm0 = {GEN_PWM_BASE, 0, 0, 0, 0};
static hal_adc_t adc0 = {GEN_ADC_BASE};
static hal_qep_t qep0 = {GEN_QEP_BASE, 0};
static hal_time_t tim0 = {GEN_TIM_BASE};
static hal_can_t can0 = {HAL_CAN_BUS_OFF};
static hal_nvm_t nvm0 = {GEN_FLC_BASE, GEN_NVM_BASE};
static hal_wdg_t wdg0 = {GEN_WDT_BASE, 0u, 0u};
/* The control interrupt's target: the one piece of state the vector needs. */
static hal_isr_fn_t isr_fn;
static void *isr_ctx;

void hal_stage_mark(hal_stage_t stage)
{
    hal_stage_reg = (uint32_t)stage;
}

bool hal_board_init(const hal_board_cfg_t *cfg, hal_board_t *out)
{
    /* up-down counter: period = 2 PRD clock counts */
    const float prd = (float)GEN_PWM_CLK_HZ / (2.0f * cfg->f_pwm_hz);
    const float dt = cfg->dead_time_s * (float)GEN_PWM_CLK_HZ;
    if (!(prd >= 100.0f && prd <= 65535.0f) || !(dt >= (float)GEN_PWM_DT_MIN && dt < 0.25f * prd) || cfg->qep_counts_per_rev < 4u) {
        REG(GEN_PWM_BASE, GEN_PWM_CTRL) = 0u;
        return false;
    }
    pwm0.prd = (uint32_t)lroundf(prd);
    pwm0.period_s = 2.0f * (float)pwm0.prd / (float)GEN_PWM_CLK_HZ;
    pwm0.dead_time_s = (float)(uint32_t)lroundf(dt) / (float)GEN_PWM_CLK_HZ;
    REG(pwm0.base, GEN_PWM_CTRL) = 0u;   /* stopped, outputs off */
    REG(pwm0.base, GEN_PWM_PRD) = pwm0.prd;
    REG(pwm0.base, GEN_PWM_DT) = (uint32_t)lroundf(dt);
    for (uint32_t k = 0u; k < 3u; ++k) {
        REG(pwm0.base, GEN_PWM_CMP(k)) = pwm0.prd / 2u;
    }
    REG(adc0.base, GEN_ADC_CTRL) = 0u;
    REG(adc0.base, GEN_ADC_CHMAP) = (uint32_t)cfg->adc_ch_i[0] | ((uint32_t)cfg->adc_ch_i[1] << 8) |
                                    ((uint32_t)cfg->adc_ch_i[2] << 16) | ((uint32_t)cfg->adc_ch_vdc << 24);
    REG(adc0.base, GEN_ADC_STS) = GEN_ADC_STS_EOC | GEN_ADC_STS_OVR;
    qep0.counts_per_rev = cfg->qep_counts_per_rev;
    REG(qep0.base, GEN_QEP_MAX) = cfg->qep_counts_per_rev - 1u;
    out->adc = &adc0;
    out->pwm = &pwm0;
    out->qep = &qep0;
    out->can = &can0;
    out->nvm = &nvm0;
    out->time = &tim0;
    out->wdg = &wdg0;
    return true;
}

void hal_board_attach_isr(hal_isr_fn_t fn, void *ctx)
{
    isr_ctx = ctx;
    isr_fn = fn;
}

#define NVIC_ISER0 (*(volatile uint32_t *)0xE000E100u)

void hal_board_start(void)
{
    REG(adc0.base, GEN_ADC_CTRL) = GEN_ADC_CTRL_EN | GEN_ADC_CTRL_IE;
    NVIC_ISER0 = 1u << GEN_ADC_IRQ;
    REG(pwm0.base, GEN_PWM_CTRL) = GEN_PWM_CTRL_RUN;   /* running, outputs still off */
    REG(wdg0.base, GEN_WDT_LOAD) = GEN_WDT_TIMEOUT_US;
    REG(wdg0.base, GEN_WDT_CTRL) = GEN_WDT_CTRL_EN;     /* from here the loop must progress */
}

void hal_wdg_kick(hal_wdg_t *wdg)
{
    REG(wdg->base, GEN_WDT_KICK) = GEN_WDT_KICK_KEY;
}

void hal_wdg_service(hal_wdg_t *wdg)
{
    const uint32_t n = wdg->isr_runs;
    if (n != wdg->seen) {
        wdg->seen = n;
        hal_wdg_kick(wdg);
    }
}

float hal_board_min_dead_time_s(void)
{
    return (float)GEN_PWM_DT_MIN / (float)GEN_PWM_CLK_HZ;
}

void hal_board_idle(void)
{
    __asm volatile("wfi");
}

/* The ADC end-of-conversion interrupt (vector 16 + GEN_ADC_IRQ). */
void hal_generic_adc_irq(void);
void hal_generic_adc_irq(void)
{
    wdg0.isr_runs = wdg0.isr_runs + 1u;   /* the progress hal_wdg_service looks for */
    if (isr_fn != NULL) {
        isr_fn(isr_ctx);
    }
    REG(adc0.base, GEN_ADC_STS) = GEN_ADC_STS_EOC;   /* acknowledged: an EOC before this is an overrun */
}

/* ---- PWM */
static uint32_t duty_counts(hal_pwm_t *pwm, float d)
{
    if (!(d >= 0.0f && d <= 1.0f)) {
        if (d != d || d == INFINITY || d == -INFINITY) {
            pwm->nonfinite++;
            d = 0.5f;
        } else {
            d = d < 0.0f ? 0.0f : 1.0f;
        }
    }
    return (uint32_t)lroundf(d * (float)pwm->prd);
}

void hal_pwm_set_duties(hal_pwm_t *pwm, float da, float db, float dc)
{
    REG(pwm->base, GEN_PWM_CMP(0)) = duty_counts(pwm, da);
    REG(pwm->base, GEN_PWM_CMP(1)) = duty_counts(pwm, db);
    REG(pwm->base, GEN_PWM_CMP(2)) = duty_counts(pwm, dc);
}

void hal_pwm_enable(hal_pwm_t *pwm, bool on)
{
    const uint32_t c = REG(pwm->base, GEN_PWM_CTRL);
    REG(pwm->base, GEN_PWM_CTRL) = on ? (c | GEN_PWM_CTRL_OE) : (c & ~GEN_PWM_CTRL_OE);
}

bool hal_pwm_enabled(const hal_pwm_t *pwm)
{
    return (REG(pwm->base, GEN_PWM_CTRL) & GEN_PWM_CTRL_OE) != 0u;
}

float hal_pwm_period_s(const hal_pwm_t *pwm)
{
    return pwm->period_s;
}

float hal_pwm_dead_time_s(const hal_pwm_t *pwm)
{
    return pwm->dead_time_s;
}

/* ---- ADC, encoder, time */
void hal_adc_read(hal_adc_t *adc, hal_adc_sample_t *out)
{
    for (uint32_t k = 0u; k < 3u; ++k) {
        out->i[k] = (uint16_t)REG(adc->base, GEN_ADC_RES(k));
    }
    out->vdc = (uint16_t)REG(adc->base, GEN_ADC_RES(3));
    const uint32_t sts = REG(adc->base, GEN_ADC_STS);
    out->overrun = (sts & GEN_ADC_STS_OVR) != 0u;
    if (out->overrun) {
        REG(adc->base, GEN_ADC_STS) = GEN_ADC_STS_OVR;
    }
}

void hal_qep_read(hal_qep_t *qep, hal_qep_sample_t *out)
{
    out->count = REG(qep->base, GEN_QEP_POS);
    out->index_seen = (REG(qep->base, GEN_QEP_STS) & 1u) != 0u;
    out->index_count = REG(qep->base, GEN_QEP_IDX);
}

uint32_t hal_qep_counts_per_rev(const hal_qep_t *qep)
{
    return qep->counts_per_rev;
}

uint32_t hal_time_us(const hal_time_t *t)
{
    return REG(t->base, GEN_TIM_US);
}

/* ---- CAN: this port has no controller (the budget reference); every send is refused. */
bool hal_can_send(hal_can_t *can, const hal_can_frame_t *f)
{
    (void)can;
    (void)f;
    return false;
}

bool hal_can_receive(hal_can_t *can, hal_can_frame_t *f)
{
    (void)can;
    (void)f;
    return false;
}

hal_can_state_t hal_can_state(const hal_can_t *can)
{
    return can->state;
}

void hal_can_recover(hal_can_t *can)
{
    (void)can;
}

/* ---- NVM through the flash controller; reads are memory-mapped. The part's map: its whole
 * flash in 16 KiB blocks, each erased by the controller's erase command, programmed in 8-byte units. */
static const hal_nvm_region_t gen_flash_regions[1] = {
    {0u, GEN_NVM_BLOCK, GEN_FLASH_SIZE / GEN_NVM_BLOCK, (uint8_t)GEN_FLC_CMD_ERASE}};
static const hal_nvm_geometry_t gen_flash_map = {GEN_FLASH_SIZE, GEN_NVM_UNIT, 1u, gen_flash_regions};

const hal_nvm_geometry_t *hal_nvm_geometry(const hal_nvm_t *nvm)
{
    (void)nvm;
    return &gen_flash_map;
}

uint32_t hal_nvm_blocks(const hal_nvm_t *nvm)
{
    (void)nvm;
    return GEN_NVM_BLOCKS;
}

uint32_t hal_nvm_block_size(const hal_nvm_t *nvm)
{
    (void)nvm;
    return GEN_NVM_BLOCK;
}

uint32_t hal_nvm_write_unit(const hal_nvm_t *nvm)
{
    (void)nvm;
    return GEN_NVM_UNIT;
}

static bool nvm_range(uint32_t block, uint32_t offset, uint32_t len)
{
    return block < GEN_NVM_BLOCKS && offset <= GEN_NVM_BLOCK && len <= GEN_NVM_BLOCK - offset;
}

static bool flc_done(const hal_nvm_t *nvm)
{
    while ((REG(nvm->flc, GEN_FLC_STS) & 1u) != 0u) {
    }
    const bool err = (REG(nvm->flc, GEN_FLC_STS) & 2u) != 0u;
    REG(nvm->flc, GEN_FLC_STS) = 2u;
    return !err;
}

bool hal_nvm_erase(hal_nvm_t *nvm, uint32_t block)
{
    if (block >= GEN_NVM_BLOCKS) {
        return false;
    }
    const uint32_t a = nvm->base + block * GEN_NVM_BLOCK;
    REG(nvm->flc, GEN_FLC_ADDR) = a;
    REG(nvm->flc, GEN_FLC_CMD) = GEN_FLC_CMD_ERASE;
    bool ok = flc_done(nvm);
    /* erased is all 0xFF (hal/nvm.h): an erase that did not happen is an error, not a success */
    for (uint32_t k = 0u; ok && k < GEN_NVM_BLOCK; k += 4u) {
        ok = *(const volatile uint32_t *)(uintptr_t)(a + k) == 0xFFFFFFFFu;
    }
    return ok;
}

bool hal_nvm_write(hal_nvm_t *nvm, uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (!nvm_range(block, offset, len) || offset % GEN_NVM_UNIT != 0u || len % GEN_NVM_UNIT != 0u) {
        return false;
    }
    const uint8_t *p = (const uint8_t *)data;
    for (uint32_t k = 0u; k < len; k += GEN_NVM_UNIT) {
        uint32_t w[2] = {0u, 0u};
        for (uint32_t j = 0u; j < 8u; ++j) {
            w[j / 4u] |= (uint32_t)p[k + j] << (8u * (j % 4u));
        }
        REG(nvm->flc, GEN_FLC_ADDR) = nvm->base + block * GEN_NVM_BLOCK + offset + k;
        REG(nvm->flc, GEN_FLC_DATA0) = w[0];
        REG(nvm->flc, GEN_FLC_DATA1) = w[1];
        REG(nvm->flc, GEN_FLC_CMD) = GEN_FLC_CMD_PROGRAM;
        if (!flc_done(nvm)) {
            return false;
        }
    }
    return true;
}

bool hal_nvm_read(const hal_nvm_t *nvm, uint32_t block, uint32_t offset, void *data, uint32_t len)
{
    if (!nvm_range(block, offset, len)) {
        return false;
    }
    const volatile uint8_t *src = (const volatile uint8_t *)(uintptr_t)(nvm->base + block * GEN_NVM_BLOCK + offset);
    uint8_t *dst = (uint8_t *)data;
    for (uint32_t k = 0u; k < len; ++k) {
        dst[k] = src[k];
    }
    return true;
}
